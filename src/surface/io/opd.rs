//! Wyko / Veeco / Bruker Vision `.opd` (white-light interferometers; docs/surfaces.md). The
//! layout, as Gwyddion's `opdfile.c` and SurfaceTopography's `IO/OPD.py` read it: two bytes, then
//! a directory of 24-byte block descriptors (name, 16 bytes NUL-padded; type, i16; length, i32;
//! attributes, u16; little-endian), whose first entry is the directory itself (`Directory`,
//! its length = 24 × the number of blocks). The blocks' contents follow in directory order.
//! An array block (`RAW DATA`, `RAW_DATA`, `OPD`, `Raw`) starts with nx, ny, element size
//! (u16 each), then nx·ny elements, x outer and y inner, y counted from the bottom of the
//! image (SurfaceTopography flips it so; hdi's row 0 is the top). Scalars: `Wavelength` (f32,
//! nm), `Mult` (u16), `Aspect` (f32, dy/dx), `Pixel_size` (f32, mm).
//!
//! Heights: z = value · Wavelength / Mult (nm); int16 values ≥ 32766 and float32 values
//! ≥ 1e38 (or non-finite) mark pixels without data. Spacing: dx = Pixel_size, dy = Pixel_size ·
//! Aspect. 8-bit arrays are refused as unsupported (no sample to test them on).
use super::le::{le_f32, le_i32, le_u16};
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// Bytes per directory entry.
const ENTRY: usize = 24;
/// Where the directory starts (after two bytes the readers skip).
const DIRECTORY_AT: usize = 2;
/// Array block names.
const ARRAY_BLOCKS: [&str; 4] = ["RAW DATA", "RAW_DATA", "OPD", "Raw"];

/// Whether the file starts like an OPD file: the directory's own entry, named `Directory`.
pub(crate) fn looks_like(head: &[u8]) -> bool {
    head.get(DIRECTORY_AT..DIRECTORY_AT + 16)
        .is_some_and(|name| name.starts_with(b"Directory\0"))
}

/// One directory entry.
struct Block {
    name: String,
    length: usize,
}

/// An array block: where its elements start and how they are laid out.
struct ArrayBlock {
    name: String,
    nx: usize,
    ny: usize,
    element_size: usize,
    data_at: usize,
}

fn entry(bytes: &[u8], at: usize) -> Block {
    let raw = &bytes[at..at + 16];
    let end = raw.iter().position(|&b| b == 0).unwrap_or(16);
    // Names are ASCII; latin-1 keeps any other byte readable.
    let name = raw[..end].iter().map(|&b| b as char).collect();
    let length = le_i32(bytes, at + 18);
    Block {
        name,
        length: usize::try_from(length).unwrap_or(0),
    }
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    if bytes.len() < DIRECTORY_AT + ENTRY || !looks_like(bytes) {
        return Err(fail("not a Wyko OPD file (no `Directory` block)".into()));
    }
    let directory = entry(bytes, DIRECTORY_AT);
    if directory.length == 0 || !directory.length.is_multiple_of(ENTRY) {
        return Err(fail(format!(
            "OPD directory length {} is not a positive multiple of {ENTRY}",
            directory.length
        )));
    }
    let n_blocks = directory.length / ENTRY;
    let mut at = DIRECTORY_AT + directory.length;
    if at > bytes.len() {
        return Err(fail(format!(
            "truncated OPD file: its directory of {n_blocks} blocks needs {at} bytes, the file has {}",
            bytes.len()
        )));
    }
    let blocks: Vec<Block> = (1..n_blocks)
        .map(|k| entry(bytes, DIRECTORY_AT + k * ENTRY))
        .collect();
    let mut arrays = Vec::new();
    let mut header = BTreeMap::new();
    let (mut wavelength, mut mult, mut aspect, mut pixel) = (None, 1.0, 1.0, None);
    for b in &blocks {
        if b.length == 0 {
            continue;
        }
        let end = at
            .checked_add(b.length)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                fail(format!(
                    "truncated OPD file: block `{}` ({} bytes at {at}) runs past the end ({} bytes)",
                    b.name,
                    b.length,
                    bytes.len()
                ))
            })?;
        let scalar_f32 = || (b.length >= 4).then(|| le_f32(bytes, at));
        match b.name.as_str() {
            n if ARRAY_BLOCKS.contains(&n) => arrays.push(array_block(path, bytes, at, b)?),
            "Wavelength" => wavelength = scalar_f32(),
            "Mult" if b.length >= 2 => mult = f64::from(le_u16(bytes, at)),
            "Aspect" => aspect = scalar_f32().unwrap_or(f64::NAN),
            "Pixel_size" => pixel = scalar_f32(),
            _ => {}
        }
        if !ARRAY_BLOCKS.contains(&b.name.as_str()) && b.length <= 4 {
            if let Some(v) = scalar_f32() {
                header.insert(b.name.clone(), format!("{v}"));
            }
        }
        at = end;
    }
    let wavelength = wavelength.ok_or_else(|| fail("OPD file has no `Wavelength` block".into()))?;
    let pixel = pixel.ok_or_else(|| fail("OPD file has no `Pixel_size` block".into()))?;
    for (name, v) in [
        ("Wavelength", wavelength),
        ("Mult", mult),
        ("Pixel_size", pixel),
        ("Aspect", aspect),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(fail(format!("OPD `{name}` = {v} is not a positive number")));
        }
    }
    let names: Vec<Vec<String>> = arrays.iter().map(|a| vec![a.name.clone()]).collect();
    let k = match &opts.channel {
        None => 0,
        Some(c) => find_channel(c, &names).ok_or_else(|| {
            let have: Vec<&str> = arrays.iter().map(|a| a.name.as_str()).collect();
            fail(format!("no channel `{c}`; the file has {have:?}"))
        })?,
    };
    let a = arrays
        .get(k)
        .ok_or_else(|| fail("OPD file has no data array".into()))?;
    let arrays_named: Vec<&str> = arrays.iter().map(|a| a.name.as_str()).collect();
    header.insert("channels".into(), arrays_named.join(", "));
    header.insert("blocks".into(), {
        let names: Vec<&str> = blocks.iter().map(|b| b.name.as_str()).collect();
        names.join(", ")
    });
    let scale = wavelength / mult * 1e-9;
    let value = |i: usize| -> f64 {
        let at = a.data_at + i * a.element_size;
        if a.element_size == 2 {
            let v = i16::from_le_bytes([bytes[at], bytes[at + 1]]);
            if v >= 32766 {
                f64::NAN
            } else {
                f64::from(v) * scale
            }
        } else {
            // Compared in float32, as SurfaceTopography's numpy comparison does.
            let v = f32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
            if v.is_finite() && v < 1e38f32 {
                f64::from(v) * scale
            } else {
                f64::NAN
            }
        }
    };
    // Element (x, y) is at x·ny + y with y from the bottom: hdi's row r is y = ny − 1 − r.
    let z = Array2::from_shape_fn((a.ny, a.nx), |(r, x)| value(x * a.ny + (a.ny - 1 - r)));
    Ok(RawMap {
        z,
        dx: pixel * 1e-3,
        dy: pixel * aspect * 1e-3,
        x0: 0.0,
        y0: 0.0,
        channel: a.name.clone(),
        format: "opd",
        header,
    })
}

/// The layout of the array block at `at`, its elements checked against the block and file.
fn array_block(path: &Path, bytes: &[u8], at: usize, b: &Block) -> Result<ArrayBlock> {
    let fail = |reason: String| format_error(path, reason);
    if b.length < 6 {
        return Err(fail(format!(
            "OPD array block `{}` has {} bytes, fewer than its 6-byte size header",
            b.name, b.length
        )));
    }
    let (nx, ny, element_size) = (
        usize::from(le_u16(bytes, at)),
        usize::from(le_u16(bytes, at + 2)),
        usize::from(le_u16(bytes, at + 4)),
    );
    match element_size {
        2 | 4 => {}
        1 => return Err(unsupported(path, "8-bit OPD arrays are not supported")),
        e => {
            return Err(fail(format!(
                "OPD element size {e} (expected 2 or 4 bytes)"
            )))
        }
    }
    let need = nx * ny * element_size + 6;
    if nx == 0 || ny == 0 || need > b.length {
        return Err(fail(format!(
            "OPD array `{}` of {nx} × {ny} × {element_size} bytes does not fit its block of {} bytes",
            b.name, b.length
        )));
    }
    Ok(ArrayBlock {
        name: b.name.clone(),
        nx,
        ny,
        element_size,
        data_at: at + 6,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::ReadOptions;

    /// An OPD file as the layout above describes it: the directory, then `blocks` in order
    /// (name, type, content).
    fn opd(blocks: &[(&str, i16, Vec<u8>)]) -> Vec<u8> {
        let entry = |name: &str, kind: i16, len: usize| {
            let mut e = vec![0u8; 24];
            e[..name.len()].copy_from_slice(name.as_bytes());
            e[16..18].copy_from_slice(&kind.to_le_bytes());
            e[18..22].copy_from_slice(&(len as i32).to_le_bytes());
            e
        };
        let mut out = vec![1u8, 0];
        out.extend(entry("Directory", 1, 24 * (blocks.len() + 1)));
        for (name, kind, content) in blocks {
            out.extend(entry(name, *kind, content.len()));
        }
        for (_, _, content) in blocks {
            out.extend(content);
        }
        out
    }

    /// A 4 × 3 int16 array: element (x, y) = 10·x + y, one invalid (32767).
    fn int16_array() -> Vec<u8> {
        let (nx, ny) = (4u16, 3u16);
        let mut a = Vec::new();
        for v in [nx, ny, 2] {
            a.extend(v.to_le_bytes());
        }
        for x in 0..nx as i16 {
            for y in 0..ny as i16 {
                let v: i16 = if (x, y) == (2, 1) { 32767 } else { 10 * x + y };
                a.extend(v.to_le_bytes());
            }
        }
        a
    }

    fn scalars(mult: u16, aspect: f32) -> Vec<(&'static str, i16, Vec<u8>)> {
        vec![
            ("Wavelength", 7, 600.0f32.to_le_bytes().to_vec()),
            ("Mult", 6, mult.to_le_bytes().to_vec()),
            ("Aspect", 7, aspect.to_le_bytes().to_vec()),
            ("Pixel_size", 7, 0.002f32.to_le_bytes().to_vec()),
            ("Title", 5, b"a title\0".to_vec()),
        ]
    }

    #[test]
    fn int16_heights_orientation_spacing_and_invalid_pixels() {
        let mut blocks = vec![("RAW DATA", 3, int16_array())];
        blocks.extend(scalars(2, 1.5));
        let map = read_bytes("a.opd", &opd(&blocks)).unwrap();
        assert_eq!((map.nx(), map.ny()), (4, 3));
        assert_eq!(map.source.format, "opd");
        let pixel = 0.002f32 as f64 * 1e-3;
        assert!(close(map.dx, pixel, 1e-15) && close(map.dy, 1.5 * pixel, 1e-6));
        // z = value · 600 nm / 2; element (x, y) is hdi's row ny − 1 − y.
        let scale = 600.0 / 2.0 * 1e-9;
        for x in 0..4 {
            for y in 0..3 {
                let (row, ok) = (2 - y, map.valid.as_ref().unwrap()[[2 - y, x]]);
                if (x, y) == (2, 1) {
                    assert!(!ok);
                } else {
                    assert!(ok && close(map.z[[row, x]], (10 * x + y) as f64 * scale, 1e-12));
                }
            }
        }
        assert_eq!(map.source.header["Wavelength"], "600");
    }

    #[test]
    fn float32_arrays_channels_and_bad_files() {
        let mut f32_array = Vec::new();
        for v in [3u16, 3, 4] {
            f32_array.extend(v.to_le_bytes());
        }
        for k in 0..9 {
            let v = if k == 4 { 1e38f32 } else { k as f32 * 0.25 };
            f32_array.extend(v.to_le_bytes());
        }
        let mut blocks = vec![("OPD", 3, f32_array), ("Raw", 3, int16_array())];
        blocks.extend(scalars(1, 1.0));
        let map = read_bytes("b.opd", &opd(&blocks)).unwrap();
        assert_eq!((map.nx(), map.ny(), map.channel.as_str()), (3, 3, "OPD"));
        assert!(!map.valid.as_ref().unwrap()[[1, 1]]);
        let (dir, path) = write_temp("b.opd", &opd(&blocks));
        let opts = ReadOptions {
            channel: Some("raw".into()),
            ..ReadOptions::default()
        };
        let raw = super::super::read_height_map(&path, &opts).unwrap();
        assert_eq!((raw.nx(), raw.channel.as_str()), (4, "Raw"));
        drop(dir);
        // No wavelength, an 8-bit array, an array larger than its block.
        let no_wavelength = opd(&[("RAW DATA", 3, int16_array())]);
        let e = read_bytes("c.opd", &no_wavelength).unwrap_err().to_string();
        assert!(e.contains("c.opd") && e.contains("Wavelength"), "{e}");
        let mut bytes8 = int16_array();
        bytes8[4] = 1;
        let mut blocks = vec![("RAW DATA", 3, bytes8)];
        blocks.extend(scalars(1, 1.0));
        let e = read_bytes("d.opd", &opd(&blocks)).unwrap_err().to_string();
        assert!(e.contains("8-bit"), "{e}");
        let mut short = int16_array();
        short[0] = 200;
        let mut blocks = vec![("RAW DATA", 3, short)];
        blocks.extend(scalars(1, 1.0));
        let e = read_bytes("e.opd", &opd(&blocks)).unwrap_err().to_string();
        assert!(e.contains("does not fit"), "{e}");
        assert!(fuzz_reader("f.opd", &opd(&blocks)) > 0);
    }
}
