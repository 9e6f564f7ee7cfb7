//! Digital Surf Mountains documents (`.mnt`; docs/surfaces.md), as SurfaceTopography 1.27.1's
//! `IO/MNT.py` describes and reads them. Nothing is shared with the `.sur` reader: a `.mnt` is a
//! Microsoft compound file (`crate::formats::cfb`) whose `ScopedContents` stream holds the
//! document as nested TLV entries (tag u16, size u64, value; little-endian) after a u64 length.
//! Text values are the byte 0x04 then UTF-16LE. The main entry (tag 1) holds the software
//! version (0xC8), its serial number (0xCB) and the document (0x2BD → 2 → 1), a list of
//! objects each preceded by an extra u64 size. An object is its class (1 → 1, u32), its body
//! (2) and a GUID (3). Only measured surfaces (class 9012) carry heights; derived layers are
//! recomputed by Mountains and not stored. A surface's body: header (0xFFFF → title at 4) and
//! its measurement object (1, class 9062), whose body's 0xFFFF entry holds the grid (0xFFFF:
//! description name at 0xFFFF → 0xFFFF → 1; x axis 1, y axis 2, each 0xFFFF → scale and point
//! count at 1; mask at 3), the heights (1, class 9049) and the height axis (2: scale, minimum
//! and maximum count). A scale: step (1, f64) in unit (2), display unit (3), origin (5, in the
//! display unit). Arrays: element count (1), then (2) the total byte size (u64) and zlib blocks
//! (element offset u64, element count u32, compressed size u32, zlib stream), in any order.
//! Heights: int32 (or int16) counts, x fastest, first row at the top (as SurfaceTopography and
//! the same measurement's BCRF export, bcrf-1.bcrf, store it): z = count · step + origin.
//! The optional mask is (nx + 2) × (ny + 2) bytes with a one-pixel border; 9 marks a measured
//! point, anything else a point without data.
use super::units::length_factor;
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::formats::cfb::{Cfb, CfbError};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// The compound-file signature every `.mnt` starts with.
pub(crate) use crate::formats::cfb::SIGNATURE as MAGIC;

const CLASS_SURFACE: u32 = 9012;
const CLASS_MEASUREMENT: u32 = 9062;
const CLASS_MASK: u32 = 9056;
const CLASS_MASK_ARRAY: u32 = 9048;
const CLASS_HEIGHTS: u32 = 9049;
const MASK_MEASURED: u8 = 9;
/// Deflate cannot expand input by more than this factor (RFC 1951).
const MAX_DEFLATE_RATIO: usize = 1032;

/// The entries of a TLV container, in order; a truncated last entry ends the list (as
/// SurfaceTopography reads it). With `prefixed`, every entry has an extra u64 before it.
fn entries(data: &[u8], prefixed: bool) -> Vec<(u16, &[u8])> {
    let mut out = Vec::new();
    let mut at = if prefixed { 8 } else { 0 };
    while let Some(head) = data.get(at..at + 10) {
        let tag = u16::from_le_bytes([head[0], head[1]]);
        let size = u64::from_le_bytes(head[2..10].try_into().unwrap_or([0; 8]));
        let start = at + 10;
        let Some(value) = usize::try_from(size)
            .ok()
            .and_then(|s| start.checked_add(s))
            .and_then(|end| data.get(start..end))
        else {
            break;
        };
        out.push((tag, value));
        at = start + value.len() + if prefixed { 8 } else { 0 };
    }
    out
}

/// The value at a path of tags (the first entry with each tag).
fn at<'a>(data: &'a [u8], path: &[u16]) -> Option<&'a [u8]> {
    path.iter().try_fold(data, |d, &tag| {
        entries(d, false)
            .into_iter()
            .find(|(t, _)| *t == tag)
            .map(|(_, v)| v)
    })
}

fn u32_value(v: Option<&[u8]>) -> Option<u32> {
    Some(u32::from_le_bytes(v?.try_into().ok()?))
}
fn i32_value(v: Option<&[u8]>) -> Option<i32> {
    Some(i32::from_le_bytes(v?.try_into().ok()?))
}
fn f64_value(v: Option<&[u8]>) -> Option<f64> {
    Some(f64::from_le_bytes(v?.try_into().ok()?)).filter(|x| x.is_finite())
}
/// A text value: 0x04, then UTF-16LE.
fn text_value(v: Option<&[u8]>) -> Option<String> {
    let v = v?;
    if v.first() != Some(&0x04) || (v.len() - 1) % 2 != 0 {
        return None;
    }
    let units: Vec<u16> = v[1..]
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    String::from_utf16(&units)
        .ok()
        .map(|s| s.trim_end_matches('\0').to_string())
}

/// An object's class number.
fn class(object: &[u8]) -> Option<u32> {
    u32_value(at(object, &[1, 1]))
}

/// An axis scale: step in `unit`, origin in `display_unit`.
struct Scale {
    step: f64,
    unit: String,
    display_unit: String,
    origin: f64,
}

fn scale(data: &[u8]) -> Option<Scale> {
    let unit = text_value(at(data, &[2])).filter(|u| !u.is_empty())?;
    Some(Scale {
        step: f64_value(at(data, &[1]))?,
        display_unit: text_value(at(data, &[3]))
            .filter(|u| !u.is_empty())
            .unwrap_or_else(|| unit.clone()),
        unit,
        origin: f64_value(at(data, &[5])).unwrap_or(0.0),
    })
}

/// An array object's element count and data (class checked by the caller).
fn array(object: &[u8]) -> Option<(usize, &[u8])> {
    let a = at(object, &[2])?;
    Some((u32_value(at(a, &[1]))? as usize, at(a, &[2])?))
}

/// One measured surface of the document.
struct Surface<'a> {
    name: String,
    nx: usize,
    ny: usize,
    x: Scale,
    y: Scale,
    z: Scale,
    min_count: Option<i32>,
    max_count: Option<i32>,
    heights: (usize, &'a [u8]),
    mask: Option<(usize, &'a [u8])>,
}

/// A surface object's contents; `Err` for an inconsistent one, `Ok(None)` for a surface that is
/// not a height map (no measurement, or heights not in a length unit).
fn surface(body: &[u8]) -> std::result::Result<Option<Surface<'_>>, String> {
    let title = text_value(at(body, &[0xFFFF, 4]));
    let Some(measurement_object) = at(body, &[1]).filter(|o| class(o) == Some(CLASS_MEASUREMENT))
    else {
        return Ok(None);
    };
    let m = at(measurement_object, &[2, 0xFFFF]).ok_or("MNT measurement has no body")?;
    let grid = at(m, &[0xFFFF]).ok_or("MNT measurement has no grid")?;
    let lateral = |tag: u16| -> std::result::Result<(usize, Scale), String> {
        let axis = at(grid, &[tag, 0xFFFF]).ok_or("MNT grid lacks an axis")?;
        let n = u32_value(at(axis, &[1])).ok_or("MNT axis has no point count")? as usize;
        let s = at(axis, &[0xFFFF])
            .and_then(scale)
            .ok_or("MNT axis has an incomplete scale")?;
        Ok((n, s))
    };
    let (nx, x) = lateral(1)?;
    let (ny, y) = lateral(2)?;
    let Some(heights) = at(m, &[1]).filter(|o| class(o) == Some(CLASS_HEIGHTS)) else {
        return Ok(None);
    };
    let z_axis = at(m, &[2]).ok_or("MNT measurement has no height axis")?;
    let z = at(z_axis, &[0xFFFF])
        .and_then(scale)
        .ok_or("MNT height axis has an incomplete scale")?;
    if length_factor(&z.display_unit).is_none() {
        return Ok(None);
    }
    let heights = array(heights).ok_or("MNT heights have no array")?;
    if Some(heights.0) != nx.checked_mul(ny) {
        return Err(format!(
            "MNT has {} heights for a grid of {nx} × {ny}",
            heights.0
        ));
    }
    let mask = match at(grid, &[3]).filter(|o| class(o) == Some(CLASS_MASK)) {
        None => None,
        Some(mask) => {
            let body = at(mask, &[2]).ok_or("MNT mask has no body")?;
            let size = (
                u32_value(at(body, &[1])).map(|w| w as usize),
                u32_value(at(body, &[2])).map(|h| h as usize),
            );
            let object = at(body, &[5]).filter(|o| class(o) == Some(CLASS_MASK_ARRAY));
            match (object.and_then(array), size) {
                (Some(a), (Some(w), Some(h))) if (w, h) == (nx, ny) => Some(a),
                _ => return Err("inconsistent MNT mask".into()),
            }
        }
    };
    let name = text_value(at(grid, &[0xFFFF, 0xFFFF, 1]))
        .filter(|n| !n.is_empty())
        .or(title.filter(|t| !t.is_empty()))
        .unwrap_or_else(|| "Default".into());
    Ok(Some(Surface {
        name,
        nx,
        ny,
        x,
        y,
        z,
        min_count: i32_value(at(z_axis, &[1])),
        max_count: i32_value(at(z_axis, &[2])),
        heights,
        mask,
    }))
}

/// An array stored in zlib blocks: its bytes and element size (the total byte size is checked
/// against the compressed data before anything is allocated).
fn block_array(data: &[u8], count: usize) -> std::result::Result<(Vec<u8>, usize), String> {
    let total = data
        .get(..8)
        .map(|b| u64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
        .ok_or("truncated MNT data array")?;
    let total = usize::try_from(total)
        .ok()
        .filter(|&t| count > 0 && t % count == 0 && t <= data.len() * MAX_DEFLATE_RATIO)
        .ok_or_else(|| {
            format!(
                "MNT data array of {total} bytes for {count} elements in {} bytes",
                data.len()
            )
        })?;
    let element = total / count;
    let mut out = vec![0u8; total];
    let (mut at, mut filled) = (8, 0);
    while at < data.len() {
        let head = data
            .get(at..at + 16)
            .ok_or("truncated block header in an MNT data array")?;
        let offset = u64::from_le_bytes(head[..8].try_into().unwrap_or([0; 8]));
        let n = u32::from_le_bytes(head[8..12].try_into().unwrap_or([0; 4])) as usize;
        let compressed = u32::from_le_bytes(head[12..16].try_into().unwrap_or([0; 4])) as usize;
        let stream = data
            .get(at + 16..at + 16 + compressed)
            .ok_or("an MNT data block runs past its array")?;
        let len = n
            .checked_mul(element)
            .filter(|&l| l <= total)
            .ok_or("MNT block too large")?;
        let block = miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(stream, len)
            .map_err(|e| format!("MNT data block does not inflate: {:?}", e.status))?;
        let start = usize::try_from(offset)
            .ok()
            .and_then(|o| o.checked_mul(element))
            .filter(|&s| block.len() == len && s.checked_add(len).is_some_and(|e| e <= total))
            .ok_or("inconsistent block in an MNT data array")?;
        out[start..start + len].copy_from_slice(&block);
        filled += len;
        at += 16 + compressed;
    }
    if filled != total {
        return Err(format!(
            "MNT data array has {filled} bytes, {total} expected"
        ));
    }
    Ok((out, element))
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    let cfb = Cfb::parse(bytes).map_err(|e| fail(e.to_string()))?;
    let contents = cfb.stream("ScopedContents").map_err(|e| match e {
        CfbError::Missing(_) => unsupported(
            path,
            "compound file without a `ScopedContents` stream: not a Mountains document",
        ),
        e => fail(e.to_string()),
    })?;
    let main = contents
        .get(8..)
        .and_then(|c| at(c, &[1]))
        .ok_or_else(|| fail("MNT `ScopedContents` has no main entry".into()))?;
    let objects = at(main, &[0x2BD, 2, 1])
        .map(|list| entries(list, true))
        .unwrap_or_default();
    let mut surfaces = Vec::new();
    for (tag, object) in objects {
        if tag != 1 || class(object) != Some(CLASS_SURFACE) {
            continue;
        }
        if let Some(body) = at(object, &[2]) {
            if let Some(s) = surface(body).map_err(fail)? {
                surfaces.push(s);
            }
        }
    }
    if surfaces.is_empty() {
        return Err(fail("MNT document holds no measured height map".into()));
    }
    let names: Vec<&str> = surfaces.iter().map(|s| s.name.as_str()).collect();
    let k = match &opts.channel {
        None => 0,
        Some(wanted) => {
            let options: Vec<Vec<String>> = names.iter().map(|n| vec![n.to_string()]).collect();
            find_channel(wanted, &options).ok_or_else(|| {
                fail(format!(
                    "no surface `{wanted}`; surfaces: {}",
                    names.join(", ")
                ))
            })?
        }
    };
    let s = &surfaces[k];
    let factor = |unit: &str, axis: &str| {
        length_factor(unit).ok_or_else(|| fail(format!("MNT {axis} unit `{unit}` is not a length")))
    };
    let (fx, fy) = (factor(&s.x.unit, "x")?, factor(&s.y.unit, "y")?);
    let step = s.z.step * factor(&s.z.unit, "z")?;
    let origin = s.z.origin * factor(&s.z.display_unit, "z display")?;
    let (counts, element) = block_array(s.heights.1, s.heights.0).map_err(fail)?;
    if !matches!(element, 2 | 4) {
        return Err(fail(format!(
            "MNT heights of {element} bytes (2 or 4 expected)"
        )));
    }
    let mask = match s.mask {
        None => None,
        Some((count, data)) => {
            let (m, _) = block_array(data, count).map_err(fail)?;
            if m.len() != (s.nx + 2) * (s.ny + 2) {
                return Err(fail(format!(
                    "MNT mask of {} bytes for a grid of {} × {}",
                    m.len(),
                    s.nx,
                    s.ny
                )));
            }
            Some(m)
        }
    };
    let z = Array2::from_shape_fn((s.ny, s.nx), |(r, c)| {
        let i = (r * s.nx + c) * element;
        let count = if element == 4 {
            f64::from(i32::from_le_bytes([
                counts[i],
                counts[i + 1],
                counts[i + 2],
                counts[i + 3],
            ]))
        } else {
            f64::from(i16::from_le_bytes([counts[i], counts[i + 1]]))
        };
        let measured = mask
            .as_ref()
            .is_none_or(|m| m[(r + 1) * (s.nx + 2) + c + 1] == MASK_MEASURED);
        if measured {
            count * step + origin
        } else {
            f64::NAN
        }
    });
    let mut header = BTreeMap::new();
    header.insert("surfaces".into(), names.join(", "));
    for (axis, sc) in [("x", &s.x), ("y", &s.y), ("z", &s.z)] {
        header.insert(format!("{axis}_step"), format!("{}", sc.step));
        header.insert(format!("{axis}_unit"), sc.unit.clone());
        header.insert(format!("{axis}_display_unit"), sc.display_unit.clone());
        header.insert(format!("{axis}_origin"), format!("{}", sc.origin));
    }
    if let (Some(lo), Some(hi)) = (s.min_count, s.max_count) {
        header.insert("z_min_count".into(), lo.to_string());
        header.insert("z_max_count".into(), hi.to_string());
    }
    let version: Option<Vec<String>> = (1..=4)
        .map(|t| u32_value(at(main, &[0xC8, t])).map(|v| v.to_string()))
        .collect();
    if let Some(v) = version {
        header.insert("software_version".into(), v.join("."));
    }
    if let Some(serial) = text_value(at(main, &[0xCB])).filter(|t| !t.is_empty()) {
        header.insert("software_serial_number".into(), serial);
    }
    header.insert("streams".into(), cfb.stream_names().join(", "));
    let offset = |sc: &Scale| length_factor(&sc.display_unit).map_or(0.0, |d| sc.origin * d);
    Ok(RawMap {
        z,
        dx: s.x.step * fx,
        dy: s.y.step * fy,
        x0: offset(&s.x),
        y0: offset(&s.y),
        channel: s.name.clone(),
        format: "mnt",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::surface_sample;
    use super::super::{read_height_map, ReadOptions};
    use super::*;

    /// mnt-1.mnt and bcrf-1.bcrf are the same measurement (960 × 600) saved by Mountains and
    /// exported as BCRF: two formats, two readers, the same heights to the float32 precision of
    /// the BCRF copy (50 µm · 2⁻²⁴ ≈ 3 pm). The BCRF `xlength` is (nx − 1) · dx of the MNT.
    #[test]
    fn the_mnt_and_its_bcrf_export_give_the_same_heights() {
        let read = |name: &str| read_height_map(&surface_sample(name), &ReadOptions::default());
        let (mnt, bcrf) = (read("mnt-1.mnt").unwrap(), read("bcrf-1.bcrf").unwrap());
        assert_eq!(mnt.z.dim(), bcrf.z.dim());
        let worst = (&mnt.z - &bcrf.z).iter().fold(0f64, |w, d| w.max(d.abs()));
        assert!(worst < 1e-11, "{worst}");
        assert!((mnt.dx * 959.0 / 960.0 - bcrf.dx).abs() < 1e-6 * bcrf.dx);
        assert_eq!(mnt.channel, "A48_10x_P1");
        assert_eq!(mnt.source.header["z_display_unit"], "µm");
    }

    /// The compound-file layer on the real samples: the streams and sizes Python's
    /// independent `olefile` 0.47 lists for mnt-1.mnt.
    #[test]
    fn the_compound_file_streams_are_olefiles() {
        let bytes = std::fs::read(surface_sample("mnt-1.mnt")).unwrap();
        let cfb = Cfb::parse(&bytes).unwrap();
        for (name, size) in [
            ("ImagePreview", 84724),
            ("ScopedContents", 1851132),
            ("ScopedResults", 37025),
            // Below the 4096-byte cutoff: read from the mini stream.
            ("XmlHeader", 4018),
        ] {
            assert_eq!(cfb.stream(name).unwrap().len(), size, "{name}");
        }
        assert!(cfb
            .stream("XmlHeader")
            .unwrap()
            .starts_with(b"\xff\xfe\xff"));
        assert_eq!(
            cfb.stream("Nothing"),
            Err(CfbError::Missing("Nothing".into()))
        );
        assert_eq!(
            Cfb::parse(&bytes[..400]).err(),
            Some(CfbError::Corrupt("shorter than its 512-byte header".into()))
        );
    }

    #[test]
    fn tlv_entries_stop_at_a_truncated_entry() {
        let mut d = Vec::new();
        for (tag, value) in [(1u16, &b"abcd"[..]), (2, b"xy")] {
            d.extend(tag.to_le_bytes());
            d.extend((value.len() as u64).to_le_bytes());
            d.extend(value);
        }
        assert_eq!(entries(&d, false), vec![(1, &b"abcd"[..]), (2, &b"xy"[..])]);
        assert_eq!(entries(&d[..d.len() - 1], false).len(), 1);
        assert_eq!(u32_value(at(&d, &[1])), Some(u32::from_le_bytes(*b"abcd")));
    }

    #[test]
    fn block_arrays_refuse_inconsistent_sizes() {
        let values: Vec<u8> = (0..16u8).collect();
        let z = miniz_oxide::deflate::compress_to_vec_zlib(&values, 6);
        let mut a = 16u64.to_le_bytes().to_vec();
        a.extend(0u64.to_le_bytes());
        a.extend(4u32.to_le_bytes());
        a.extend((z.len() as u32).to_le_bytes());
        a.extend(&z);
        assert_eq!(block_array(&a, 4).unwrap(), (values, 4));
        assert!(block_array(&a, 3).is_err());
        let mut huge = a.clone();
        huge[..8].copy_from_slice(&(1u64 << 40).to_le_bytes());
        assert!(block_array(&huge, 4).unwrap_err().contains("bytes"));
    }
}
