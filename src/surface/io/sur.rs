//! Digital Surf `.sur` (MountainsMap, many profilometers and optical profilers).
//!
//! Each object is a 512-byte little-endian header (signature `DIGITAL SURF`, object type, point
//! size 16/32 bit, zmin/zmax, point counts, spacings with 16-byte unit strings, z offset,
//! comment and private-zone sizes), the comment, the private zone, then `nx·ny` signed
//! integers, x varying fastest (one profile per row, first profile = row 0 as in the file).
//! Height = raw · dz + z offset, in the dz unit. With the "non-measured points" flag set, the
//! value `zmin − 2` marks an invalid pixel (both SurfaceTopography samples use exactly that).
//! Several objects may follow each other; hdi reads the first surface, or the one whose object
//! name matches `ReadOptions::channel`. Compressed files (`DSCOMPRESSED`) are refused.
use super::le::{le_f32, le_i32, le_u16};
use super::units::{decode_text, length_factor};
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

pub(crate) const MAGIC: &[u8] = b"DIGITAL SURF";
pub(crate) const MAGIC_COMPRESSED: &[u8] = b"DSCOMPRESSED";
const HEADER: usize = 512;

/// Object types of the header (2 = surface; 1 = profile, 3 = binary image, 4/5 = series).
const SURFACE: u16 = 2;

fn text(b: &[u8], at: usize, len: usize) -> String {
    let s = &b[at..at + len];
    let end = s.iter().position(|&c| c == 0).unwrap_or(len);
    decode_text(&s[..end]).trim().to_string()
}

/// One object's header fields (offsets from the Digital Surf format description as used by
/// Gwyddion's and SurfaceTopography's readers).
struct Object {
    start: usize,
    name: String,
    kind: u16,
    special_points: bool,
    point_bits: u16,
    zmin: i32,
    nx: usize,
    ny: usize,
    dx: f64,
    dy: f64,
    dz: f64,
    units: [String; 3],
    offsets: [f64; 3],
    data_start: usize,
    data_len: usize,
}

fn parse_object(path: &Path, bytes: &[u8], start: usize) -> Result<Object> {
    let h = bytes
        .get(start..)
        .filter(|h| h.len() >= HEADER)
        .ok_or_else(|| {
            format_error(
                path,
                format!(
                    "truncated Digital Surf file: object header at {start} needs {HEADER} \
                     bytes, file has {}",
                    bytes.len()
                ),
            )
        })?;
    if h.starts_with(MAGIC_COMPRESSED) {
        return Err(unsupported(
            path,
            "compressed Digital Surf (DSCOMPRESSED) is not read; save uncompressed",
        ));
    }
    if !h.starts_with(MAGIC) {
        return Err(format_error(
            path,
            format!("no DIGITAL SURF signature at object offset {start}"),
        ));
    }
    let format = le_u16(h, 12);
    if format != 0 {
        return Err(unsupported(
            path,
            format!("Digital Surf byte-order code {format}: only PC (0) files are read"),
        ));
    }
    let point_bits = le_u16(h, 98);
    if !matches!(point_bits, 16 | 32) {
        return Err(format_error(
            path,
            format!("Digital Surf point size {point_bits} bits (16 or 32 expected)"),
        ));
    }
    let count = |at: usize, what: &str| -> Result<usize> {
        let v = le_i32(h, at);
        usize::try_from(v)
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format_error(path, format!("Digital Surf {what} = {v} is not positive")))
    };
    let nx = count(108, "number of points per profile")?;
    let ny = count(112, "number of profiles")?;
    let comment = le_u16(h, 334) as usize;
    let private = le_u16(h, 336) as usize;
    let data_start = start + HEADER + comment + private;
    let data_len = nx
        .checked_mul(ny)
        .and_then(|n| n.checked_mul(point_bits as usize / 8))
        .filter(|&n| {
            data_start
                .checked_add(n)
                .is_some_and(|end| end <= bytes.len())
        })
        .ok_or_else(|| {
            format_error(
                path,
                format!(
                    "truncated Digital Surf file: {nx}×{ny} points of {point_bits} bits at \
                     offset {data_start} do not fit in {} bytes",
                    bytes.len()
                ),
            )
        })?;
    Ok(Object {
        start,
        name: text(h, 20, 30),
        kind: le_u16(h, 18),
        special_points: le_u16(h, 86) != 0,
        point_bits,
        zmin: le_i32(h, 100),
        nx,
        ny,
        dx: le_f32(h, 120),
        dy: le_f32(h, 124),
        dz: le_f32(h, 128),
        units: [text(h, 180, 16), text(h, 196, 16), text(h, 212, 16)],
        offsets: [le_f32(h, 466), le_f32(h, 470), le_f32(h, 474)],
        data_start,
        data_len,
    })
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let first = parse_object(path, bytes, 0)?;
    let n_objects = (le_u16(bytes, 14) as usize).max(1);
    let mut objects = vec![first];
    while objects.len() < n_objects {
        let last = &objects[objects.len() - 1];
        let next = last.data_start + last.data_len;
        if next >= bytes.len() {
            break;
        }
        // A damaged later object must not hide the first one: stop listing there.
        match parse_object(path, bytes, next) {
            Ok(o) => objects.push(o),
            Err(_) => break,
        }
    }
    let label = |k: usize, o: &Object| {
        if o.name.is_empty() {
            format!("object {k}")
        } else {
            o.name.clone()
        }
    };
    let names: Vec<String> = objects
        .iter()
        .enumerate()
        .map(|(k, o)| label(k, o))
        .collect();
    let index = match &opts.channel {
        Some(wanted) => {
            let options: Vec<Vec<String>> = names.iter().map(|n| vec![n.clone()]).collect();
            find_channel(wanted, &options).ok_or_else(|| {
                format_error(
                    path,
                    format!("no object `{wanted}`; objects: {}", names.join(", ")),
                )
            })?
        }
        None => objects.iter().position(|o| o.kind == SURFACE).unwrap_or(0),
    };
    let o = &objects[index];
    if o.kind != SURFACE {
        return Err(unsupported(
            path,
            format!(
                "Digital Surf object `{}` has type {} (only surfaces, type 2, are height maps)",
                names[index], o.kind
            ),
        ));
    }
    let factor = |k: usize| {
        let unit = &o.units[k];
        length_factor(unit).ok_or_else(|| {
            format_error(
                path,
                format!(
                    "Digital Surf {} unit `{unit}` is not a length",
                    ["x", "y", "z"][k]
                ),
            )
        })
    };
    let (fx, fy, fz) = (factor(0)?, factor(1)?, factor(2)?);
    let dz = o.dz * fz;
    let z0 = o.offsets[2] * fz;
    let invalid = o.zmin.checked_sub(2).filter(|_| o.special_points);
    let data = &bytes[o.data_start..o.data_start + o.data_len];
    let convert = |raw: i32| {
        if Some(raw) == invalid {
            f64::NAN
        } else {
            raw as f64 * dz + z0
        }
    };
    let values: Vec<f64> = if o.point_bits == 16 {
        data.chunks_exact(2)
            .map(|c| convert(i16::from_le_bytes([c[0], c[1]]) as i32))
            .collect()
    } else {
        data.chunks_exact(4)
            .map(|c| convert(i32::from_le_bytes([c[0], c[1], c[2], c[3]])))
            .collect()
    };
    let z = Array2::from_shape_vec((o.ny, o.nx), values)
        .map_err(|e| format_error(path, format!("Digital Surf data shape: {e}")))?;

    let h = &bytes[o.start..o.start + HEADER];
    let mut header = BTreeMap::new();
    header.insert("channels".into(), names.join(", "));
    header.insert("version".into(), le_u16(h, 16).to_string());
    header.insert("operator".into(), text(h, 50, 30));
    header.insert("point_bits".into(), o.point_bits.to_string());
    header.insert("zmin".into(), o.zmin.to_string());
    header.insert("zmax".into(), le_i32(h, 104).to_string());
    header.insert("non_measured_points".into(), o.special_points.to_string());
    // Recorded, not applied: the flip conventions of this field are not documented publicly.
    header.insert("inversion".into(), le_u16(h, 290).to_string());
    header.insert("x_unit".into(), o.units[0].clone());
    header.insert("y_unit".into(), o.units[1].clone());
    header.insert("z_unit".into(), o.units[2].clone());
    let (year, month, day) = (le_u16(h, 316), le_u16(h, 314), le_u16(h, 312));
    if year > 0 {
        let (hour, minute, second) = (le_u16(h, 310), le_u16(h, 308), le_u16(h, 306));
        header.insert(
            "date".into(),
            format!("{year:04}-{month:02}-{day:02} {hour:02}:{minute:02}:{second:02}"),
        );
    }
    let comment_len = le_u16(h, 334) as usize;
    if comment_len > 0 {
        let at = o.start + HEADER;
        header.insert(
            "comment".into(),
            decode_text(&bytes[at..at + comment_len]).trim().to_string(),
        );
    }
    Ok(RawMap {
        z,
        dx: o.dx.abs() * fx,
        dy: o.dy.abs() * fy,
        x0: o.offsets[0] * fx,
        y0: o.offsets[1] * fy,
        channel: names[index].clone(),
        format: "sur",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};
    use std::path::PathBuf;

    fn sample(name: &str) -> PathBuf {
        surface_sample(name)
    }

    /// SurfaceTopography's `test_sur3_metadata`: 512 × 512, 0.151319552 m square, unit m,
    /// rms_height_from_area = 0.0019200491394179297 m. SurfaceTopography ignores the
    /// non-measured points (raw zmin − 2 = −2), so its rms includes them at −2·dz; hdi marks
    /// them invalid. Putting them back reproduces SurfaceTopography's number.
    #[test]
    fn sur3_matches_surface_topography() {
        let map = read_height_map(&sample("sur-3.sur"), &ReadOptions::default()).unwrap();
        assert_eq!(map.source.format, "sur");
        assert_eq!(map.z.dim(), (512, 512));
        let (w, h) = map.size();
        assert!(
            close(w, 0.151319552, 1e-6) && close(h, 0.151319552, 1e-6),
            "{w}×{h}"
        );
        let valid = map.valid.as_ref().expect("sur-3 has non-measured points");
        let n_invalid = valid.iter().filter(|v| !**v).count();
        // Counted independently with numpy (raw value −2 = zmin − 2).
        assert_eq!(n_invalid, 233009);
        let dz = 9.99999971718069e-10; // the header's f32 dz, in m
        let z0 = -0.0034143300727009773; // the header's z offset, m
        let full: Vec<f64> = map
            .z
            .iter()
            .zip(valid.iter())
            .map(|(&z, &ok)| if ok { z } else { -2.0 * dz + z0 })
            .collect();
        let mean = full.iter().sum::<f64>() / full.len() as f64;
        let rms = (full.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / full.len() as f64).sqrt();
        assert!(close(rms, 0.0019200491394179297, 1e-6), "{rms}");
        assert_eq!(map.source.header["date"], "2023-06-22 10:08:53");
    }

    /// sur-2 (mm units, 563 × 484, 117 non-measured points): sizes from the header and
    /// σ of the valid pixels, both computed with numpy from the raw file.
    #[test]
    fn sur2_mm_units_non_square() {
        let map = read_height_map(&sample("sur-2.sur"), &ReadOptions::default()).unwrap();
        assert_eq!(map.z.dim(), (484, 563));
        let dx = 3.48400021903217e-06;
        assert!(close(map.dx, dx, 1e-12) && close(map.dy, dx, 1e-12));
        let valid = map.valid.as_ref().unwrap();
        assert_eq!(valid.iter().filter(|v| !**v).count(), 117);
        let vals: Vec<f64> = map
            .z
            .iter()
            .zip(valid.iter())
            .filter(|(_, &ok)| ok)
            .map(|(&z, _)| z)
            .collect();
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        let sd = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / vals.len() as f64).sqrt();
        assert!(close(sd, 1.75178812435882e-05 * 1e-3, 1e-6), "{sd}");
    }

    #[test]
    fn truncated_and_hostile_files_are_errors() {
        let bytes = std::fs::read(sample("sur-2.sur")).unwrap();
        for cut in [12, 100, 511, 512, 600_000, bytes.len() - 1] {
            let msg = read_bytes("t.sur", &bytes[..cut]).unwrap_err().to_string();
            assert!(
                msg.contains("t.sur") && msg.contains("truncated"),
                "{cut}: {msg}"
            );
        }
        let mut huge = bytes.clone();
        huge[108..112].copy_from_slice(&i32::MAX.to_le_bytes());
        huge[112..116].copy_from_slice(&i32::MAX.to_le_bytes());
        let msg = read_bytes("h.sur", &huge).unwrap_err().to_string();
        assert!(msg.contains("do not fit"), "{msg}");
        let mut negative = bytes.clone();
        negative[108..112].copy_from_slice(&(-3i32).to_le_bytes());
        assert!(read_bytes("n.sur", &negative).is_err());
        let mut compressed = bytes[..2048].to_vec();
        compressed[..12].copy_from_slice(b"DSCOMPRESSED");
        let msg = read_bytes("c.sur", &compressed).unwrap_err().to_string();
        assert!(msg.contains("compressed"), "{msg}");
        // The fuzzing on a cut-down copy keeps the test fast: 8 profiles of sur-2.
        let mut small = bytes[..512 + 563 * 8 * 4].to_vec();
        small[112..116].copy_from_slice(&8i32.to_le_bytes());
        assert!(read_bytes("s.sur", &small).is_ok());
        assert!(fuzz_reader("f.sur", &small) > 0);
    }
}
