//! FRT MicroProf `.frt` (FRT / FormFactor chromatic and white-light profilometers;
//! docs/surfaces.md). The layout, as Gwyddion's `microprof.c` and SurfaceTopography's
//! `IO/FRT.py` read it (little-endian): the magic `FRTM_GLIDERV`, the version (`1.00` or
//! `1.01`), a u16 block count, then blocks of a u16 tag, a size (u32 in 1.00, u64 in 1.01) and
//! that many bytes. The blocks read here:
//!
//! - `0x0066`: nx, ny, bits per pixel (u32; 16 = uint16, 32 = int32);
//! - `0x0067`: size x, size y, offset x, offset y (f64, metres), y/x factor (f64), scan direction;
//! - `0x006c`: measuring range (u32), height scale (f64, metres per count);
//! - `0x000b`: the topography, ny rows of nx values, the first row at the bottom of the image;
//! - `0x007d`: four u16 buffer ids, then images, each a data type (u32 flags: 0x4 topography,
//!   0x2 intensity, 0x80 thickness, 0x800 sample thickness, 0x1000 AFM; 0x10000000 bottom
//!   sensor; bits 24–27 the buffer counter), nx, ny, bits per pixel (u32) and its values;
//! - `0x0070`: the first and last valid value (u32); `0x0072`: start and end of the
//!   measurement (u32, Unix time); `0x0077`: name of the parameter set; `0x008e`: the sensor's
//!   serial number (u32 length, text).
//!
//! Heights: value × height scale; value 1 marks a pixel without data (both readers), and so do
//! 16-bit values outside block `0x0070`'s valid range (a departure from both readers, whose
//! code notes the range as unused: in `frt-1.frt` the one line the aborted measurement did not
//! scan is all 0, below its first valid value 5). Rows are flipped so that row 0 is the top, as
//! both readers show it.
//!
//! Channels: the images of block `0x007d`, named as Gwyddion names them (`Topography (top
//! sensor) 1`, `Intensity (top sensor) 1`, …; heights for the height types, counts otherwise),
//! or, without that block, `Topography (top sensor) 1` from block `0x000b`. The default is the
//! first height image.
use super::le::{le_f64, le_u16, le_u32};
use super::units::nul_terminated;
use super::{find_channel, format_error, unsupported, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

/// The start of every binary FRT file.
pub(crate) const MAGIC: &[u8] = b"FRTM_GLIDERV";
/// Image types whose values are heights (scaled by the height scale).
const HEIGHT_TYPES: u32 = 0x0004 | 0x0080 | 0x0800 | 0x1000;
const TYPE_MASK: u32 = 0x0000_ffdf;
const BOTTOM_SENSOR: u32 = 0x1000_0000;
const BUFFER_COUNTER: u32 = 0x0f00_0000;

/// One image: its name, type and where its values are.
struct Image {
    name: String,
    kind: u32,
    nx: usize,
    ny: usize,
    bits: u32,
    at: usize,
}

impl Image {
    fn is_height(&self) -> bool {
        self.kind & TYPE_MASK & HEIGHT_TYPES != 0
    }
}

/// Gwyddion's title of an image of data type `kind`.
fn image_name(kind: u32) -> String {
    let what = match kind & TYPE_MASK {
        0x0001 => "Piezo",
        0x0002 => "Intensity",
        0x0004 => "Topography",
        0x0008 => "Real part",
        0x0010 => "Imaginary part",
        0x0040 => "Camera",
        0x0080 => "Thickness",
        0x0100 => "DIB from file",
        0x0200 => "Absolute value",
        0x0400 => "Phase",
        0x0800 => "Sample thickness",
        0x1000 => "AFM",
        0x2000 => "Quality",
        0x4001 => "Fit",
        _ => "Unknown",
    };
    let sensor = if kind & BOTTOM_SENSOR != 0 {
        "bottom"
    } else {
        "top"
    };
    let counter = ((kind & BUFFER_COUNTER) >> 24) + 1;
    format!("{what} ({sensor} sensor) {counter}")
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    if bytes.len() < 18 || !bytes.starts_with(MAGIC) {
        return Err(fail(
            "not an FRT MicroProf file, or its header is truncated".into(),
        ));
    }
    let size_bytes = match &bytes[12..16] {
        b"1.00" => 4,
        b"1.01" => 8,
        v => {
            return Err(unsupported(
                path,
                format!(
                    "FRT version `{}` (only 1.00 and 1.01 are read)",
                    String::from_utf8_lossy(v)
                ),
            ))
        }
    };
    let n_blocks = usize::from(le_u16(bytes, 16));
    // Tag → (start, length) of each block's content.
    let mut blocks: BTreeMap<u16, (usize, usize)> = BTreeMap::new();
    let mut at = 18;
    for k in 0..n_blocks {
        if at + 2 + size_bytes > bytes.len() {
            return Err(fail(format!(
                "truncated FRT file: block {k} of {n_blocks} starts past the end ({} bytes)",
                bytes.len()
            )));
        }
        let tag = le_u16(bytes, at);
        let size = if size_bytes == 4 {
            u64::from(le_u32(bytes, at + 2))
        } else {
            u64::from_le_bytes(bytes[at + 2..at + 10].try_into().expect("8 bytes"))
        };
        let start = at + 2 + size_bytes;
        let end = usize::try_from(size)
            .ok()
            .and_then(|s| start.checked_add(s))
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                fail(format!(
                    "truncated FRT file: block 0x{tag:04x} of {size} bytes at {start} runs past \
                     the end ({} bytes)",
                    bytes.len()
                ))
            })?;
        blocks.entry(tag).or_insert((start, end - start));
        at = end;
    }
    // A block's content if it has at least `min` bytes.
    let block = |tag: u16, min: usize| {
        blocks
            .get(&tag)
            .filter(|(_, len)| *len >= min)
            .map(|&(start, _)| start)
    };
    let need = |tag: u16, min: usize, what: &str| {
        block(tag, min).ok_or_else(|| fail(format!("FRT file has no {what} (block 0x{tag:04x})")))
    };

    let mut images = Vec::new();
    if let Some(&(start, len)) = blocks.get(&0x007d) {
        let end = start + len;
        let mut p = start + 8;
        while p + 16 <= end {
            let kind = le_u32(bytes, p);
            let (nx, ny, bits) = (
                le_u32(bytes, p + 4) as usize,
                le_u32(bytes, p + 8) as usize,
                le_u32(bytes, p + 12),
            );
            let data = p + 16;
            let size = image_bytes(nx, ny, bits)
                .filter(|&n| data.checked_add(n).is_some_and(|e| e <= end))
                .ok_or_else(|| {
                    fail(format!(
                        "FRT image {} of {nx} × {ny} × {bits} bits does not fit its block",
                        images.len()
                    ))
                })?;
            images.push(Image {
                name: image_name(kind),
                kind,
                nx,
                ny,
                bits,
                at: data,
            });
            p = data + size;
        }
    }
    if images.is_empty() {
        let grid = need(0x0066, 12, "image size")?;
        let (nx, ny, bits) = (
            le_u32(bytes, grid) as usize,
            le_u32(bytes, grid + 4) as usize,
            le_u32(bytes, grid + 8),
        );
        let &(start, len) = blocks
            .get(&0x000b)
            .ok_or_else(|| fail("FRT file has no topography (block 0x000b or 0x007d)".into()))?;
        if image_bytes(nx, ny, bits).is_none_or(|n| n > len) {
            return Err(fail(format!(
                "FRT topography of {nx} × {ny} × {bits} bits does not fit its block of {len} bytes"
            )));
        }
        images.push(Image {
            name: image_name(0x0004),
            kind: 0x0004,
            nx,
            ny,
            bits,
            at: start,
        });
    }

    let names: Vec<Vec<String>> = images.iter().map(|i| vec![i.name.clone()]).collect();
    let listing = names
        .iter()
        .map(|n| n[0].as_str())
        .collect::<Vec<_>>()
        .join(", ");
    let chosen = match &opts.channel {
        None => images
            .iter()
            .position(Image::is_height)
            .ok_or_else(|| fail(format!("FRT file has no height image; channels: {listing}")))?,
        Some(wanted) => find_channel(wanted, &names)
            .ok_or_else(|| fail(format!("no channel `{wanted}`; channels: {listing}")))?,
    };
    let image = &images[chosen];

    let scan = need(0x0067, 32, "scan size")?;
    let (size_x, size_y) = (le_f64(bytes, scan).abs(), le_f64(bytes, scan + 8).abs());
    for (name, v) in [("x", size_x), ("y", size_y)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(fail(format!(
                "FRT scan size {name} = {v} m is not a positive length"
            )));
        }
    }
    let scale = if image.is_height() {
        let sensor = need(0x006c, 12, "height scale")?;
        let s = le_f64(bytes, sensor + 4);
        if !(s.is_finite() && s != 0.0) {
            return Err(fail(format!("FRT height scale {s} is not a usable number")));
        }
        s
    } else {
        1.0
    };
    let valid_range = block(0x0070, 8)
        .filter(|_| image.bits == 16)
        .map(|b| (le_u32(bytes, b), le_u32(bytes, b + 4)));
    let (nx, ny) = (image.nx, image.ny);
    let z = Array2::from_shape_fn((ny, nx), |(r, i)| {
        // Row r is stored row ny − 1 − r (stored bottom first).
        let k = (ny - 1 - r) * nx + i;
        let v = if image.bits == 16 {
            let v = u32::from(le_u16(bytes, image.at + 2 * k));
            if valid_range.is_some_and(|(lo, hi)| v < lo || v > hi) {
                return f64::NAN;
            }
            i64::from(v)
        } else {
            i64::from(le_u32(bytes, image.at + 4 * k) as i32)
        };
        if v == 1 {
            f64::NAN
        } else {
            v as f64 * scale
        }
    });

    let mut header = BTreeMap::new();
    header.insert("channels".to_string(), listing);
    header.insert(
        "version".to_string(),
        String::from_utf8_lossy(&bytes[12..16]).into_owned(),
    );
    if !image.is_height() {
        header.insert("z_unit".to_string(), "counts".to_string());
    }
    header.insert("height_scale_m".to_string(), scale.to_string());
    if let Some((lo, hi)) = valid_range {
        header.insert("valid_range".to_string(), format!("{lo}..={hi}"));
    }
    if let Some(b) = block(0x0072, 12) {
        let (start, end) = (le_u32(bytes, b), le_u32(bytes, b + 4));
        for (key, t) in [("measurement_started", start), ("measurement_ended", end)] {
            if t != 0 && t != u32::MAX {
                header.insert(key.to_string(), format!("{t} (Unix time)"));
            }
        }
    }
    for (key, tag) in [("description", 0x0065u16), ("parameter_set", 0x0077)] {
        if let Some(&(start, len)) = blocks.get(&tag) {
            let text = nul_terminated(&bytes[start..start + len]);
            if !text.is_empty() {
                header.insert(key.to_string(), text);
            }
        }
    }
    if let Some(&(start, len)) = blocks.get(&0x008e) {
        if len >= 4 {
            let n = (le_u32(bytes, start) as usize).min(len - 4);
            let serial = nul_terminated(&bytes[start + 4..start + 4 + n]);
            if !serial.is_empty() {
                header.insert("serial_number".to_string(), serial);
            }
        }
    }
    Ok(RawMap {
        z,
        dx: size_x / nx as f64,
        dy: size_y / ny as f64,
        x0: 0.0,
        y0: 0.0,
        channel: image.name.clone(),
        format: "frt",
        header,
    })
}

/// Bytes of an `nx` × `ny` image of `bits` per value (16 or 32), if that is a valid image.
fn image_bytes(nx: usize, ny: usize, bits: u32) -> Option<usize> {
    let bytes_per = match bits {
        16 => 2,
        32 => 4,
        _ => return None,
    };
    nx.checked_mul(ny)
        .filter(|&n| n > 0)
        .and_then(|n| n.checked_mul(bytes_per))
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};

    /// frt-1.frt: the channels of its image block, the header SurfaceTopography 1.27.1 also
    /// reads (serial number SN_1036, start time 1678463840 = 2023-03-10 15:57:20 UTC, no end
    /// time: the measurement was aborted), and the unscanned top line (all raw 0, below the
    /// file's first valid value 5) masked on top of the 76 456 pixels of value 1.
    #[test]
    fn channels_header_and_valid_range_of_frt_1() {
        let path = surface_sample("frt-1.frt");
        let map = read_height_map(&path, &ReadOptions::default()).unwrap();
        let h = &map.source.header;
        assert_eq!(map.channel, "Topography (top sensor) 1");
        assert_eq!(
            h["channels"],
            "Topography (top sensor) 1, Intensity (top sensor) 1"
        );
        assert_eq!(h["serial_number"], "SN_1036");
        assert_eq!(h["measurement_started"], "1678463840 (Unix time)");
        assert!(!h.contains_key("measurement_ended"));
        assert_eq!(h["valid_range"], "5..=65529");
        let valid = map.valid.as_ref().unwrap();
        assert!(valid.row(0).iter().all(|v| !v));
        assert_eq!(valid.iter().filter(|v| !**v).count(), 76_456 + 500);
        let opts = ReadOptions {
            channel: Some("intensity".into()),
            ..ReadOptions::default()
        };
        let intensity = read_height_map(&path, &opts).unwrap();
        assert_eq!(intensity.source.header["z_unit"], "counts");
        assert_eq!((intensity.nx(), intensity.ny()), (500, 500));
    }

    /// frt-2.frt is 150 × 300 on 30 × 60 mm (SurfaceTopography's sizes) with its parameter set
    /// name; other versions are refused as unsupported.
    #[test]
    fn frt_2_and_other_versions() {
        let bytes = std::fs::read(surface_sample("frt-2.frt")).unwrap();
        let map = read_bytes("frt-2.frt", &bytes).unwrap();
        assert_eq!((map.nx(), map.ny()), (150, 300));
        assert!(close(map.dx, 0.03 / 150.0, 1e-15) && close(map.dy, 0.06 / 300.0, 1e-15));
        assert_eq!(map.source.header["parameter_set"], "TexSimEx_Pin_New");
        let mut v2 = bytes.clone();
        v2[12..16].copy_from_slice(b"2.00");
        let e = read_bytes("v2.frt", &v2).unwrap_err().to_string();
        assert!(e.contains("v2.frt") && e.contains("`2.00`"), "{e}");
    }
}
