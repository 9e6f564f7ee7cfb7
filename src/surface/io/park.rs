//! Park Systems TIFF (XE/NX-series AFMs, SmartScan; docs/surfaces.md), as Gwyddion's `psia.c`
//! and SurfaceTopography's `IO/PS.py` read it. A classic TIFF whose first IFD carries four
//! private tags: 50432 the magic LONG `0x0E031301`, 50433 the version (`0x01000001` or
//! `0x01000002`), 50434 the heights (BYTE blob), 50435 the header (a little-endian block; its
//! layout is in [`Header`]). The TIFF image itself is only an 8-bit colour preview.
//!
//! The heights are `ny` lines of `nx` little-endian values (version 1: int16; version 2: int16,
//! int32 or float32 by the header's data type), the first line at the bottom of the image, so
//! hdi's row r is line ny − 1 − r (Gwyddion flips it so; SurfaceTopography 1.27.1 too). A value
//! v is `data_gain · (data_scale_factor · v + data_offset)` in `data_unit` (a scale factor of 0
//! means 1, an empty unit µm); lengths are `physical_size_x/y` in µm over the `nx` × `ny`
//! pixels. Line profiles (image type 1) and channels whose unit is not a length are refused.
use super::le::{le_f32, le_f64, le_i32, le_u32};
use super::tiff::{first_ifd_scalar, Tiff};
use super::units::length_factor;
use super::{format_error, unsupported, RawMap};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

const TAG_MAGIC: u16 = 50432;
const TAG_VERSION: u16 = 50433;
const TAG_DATA: u16 = 50434;
const TAG_HEADER: u16 = 50435;
const MAGIC: u32 = 0x0E03_1301;
const VERSION_1: u64 = 0x0100_0001;
const VERSION_2: u64 = 0x0100_0002;
/// Header bytes of version 1 and of version 2 (which appends servo, voltage-mode, data-type
/// and cantilever fields).
const HEADER_V1: usize = 284;
const HEADER_V2: usize = 408;

/// Whether the first IFD of a TIFF carries Park's magic tag.
pub(crate) fn looks_like(head: &[u8]) -> bool {
    first_ifd_scalar(head, TAG_MAGIC) == Some(MAGIC)
}

/// The fields of the header block hdi uses, at their byte offsets (Gwyddion's `psia.c`;
/// strings are UTF-16LE, NUL-padded).
struct Header {
    image_type: u32,
    source_name: String,
    image_mode: String,
    nx: usize,
    ny: usize,
    size_x_um: f64,
    size_y_um: f64,
    x_offset_um: f64,
    y_offset_um: f64,
    data_gain: f64,
    data_scale_factor: f64,
    data_offset: f64,
    data_unit: String,
    data_type: u32,
    extra: Vec<(&'static str, String)>,
}

fn utf16(b: &[u8], at: usize, chars: usize) -> String {
    let units: Vec<u16> = (0..chars)
        .map(|k| u16::from_le_bytes([b[at + 2 * k], b[at + 2 * k + 1]]))
        .take_while(|&u| u != 0)
        .collect();
    String::from_utf16_lossy(&units).trim().to_string()
}

fn header(b: &[u8], version: u64) -> Header {
    let v2 = version == VERSION_2;
    let mut extra = vec![
        ("lpf_strength", le_f64(b, 84).to_string()),
        ("angle", le_f64(b, 108).to_string()),
        ("overscan_rate", le_f64(b, 120).to_string()),
        ("forward", le_u32(b, 128).to_string()),
        ("scan_up", le_u32(b, 132).to_string()),
        ("swap_xy", le_u32(b, 136).to_string()),
        ("scan_rate", le_f64(b, 172).to_string()),
        ("set_point", le_f64(b, 180).to_string()),
        ("set_point_unit", utf16(b, 188, 8)),
        ("tip_bias", le_f64(b, 204).to_string()),
        ("sample_bias", le_f64(b, 212).to_string()),
    ];
    if v2 {
        extra.push(("cantilever_name", utf16(b, 376, 16)));
        extra.push(("ncm_amplitude", le_f64(b, 360).to_string()));
        extra.push(("ncm_frequency", le_f64(b, 368).to_string()));
    }
    Header {
        image_type: le_u32(b, 0),
        source_name: utf16(b, 4, 32),
        image_mode: utf16(b, 68, 8),
        nx: le_u32(b, 100) as usize,
        ny: le_u32(b, 104) as usize,
        size_x_um: le_f64(b, 140),
        size_y_um: le_f64(b, 148),
        x_offset_um: le_f64(b, 156),
        y_offset_um: le_f64(b, 164),
        data_gain: le_f64(b, 220),
        data_scale_factor: le_f64(b, 228),
        data_offset: le_f64(b, 236),
        data_unit: utf16(b, 244, 8),
        // Version 1 always stores int16.
        data_type: if v2 { le_u32(b, 348) } else { 0 },
        extra,
    }
}

pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    let tiff = Tiff::parse(bytes).map_err(fail)?;
    if tiff.uint(0, TAG_MAGIC) != Some(u64::from(MAGIC)) {
        return Err(fail("not a Park Systems TIFF (no magic tag 50432)".into()));
    }
    let version = tiff
        .uint(0, TAG_VERSION)
        .ok_or_else(|| fail("Park Systems TIFF has no version tag 50433".into()))?;
    let header_len = match version {
        VERSION_1 => HEADER_V1,
        VERSION_2 => HEADER_V2,
        v => {
            return Err(unsupported(
                path,
                format!("Park Systems TIFF version {v:#x} (only 0x1000001 and 0x1000002 are read)"),
            ))
        }
    };
    let block = |tag: u16, what: &str| {
        tiff.find(0, tag)
            .map(|e| tiff.data(e))
            .ok_or_else(|| fail(format!("Park Systems TIFF has no {what} tag {tag}")))
    };
    let head_bytes = block(TAG_HEADER, "header")?;
    if head_bytes.len() < header_len {
        return Err(fail(format!(
            "Park Systems header tag 50435 has {} bytes; version {version:#x} needs {header_len}",
            head_bytes.len()
        )));
    }
    let h = header(head_bytes, version);
    match h.image_type {
        0 | 2 => {}
        1 => {
            return Err(unsupported(
                path,
                "Park Systems line profiles (image type 1) are not height maps",
            ))
        }
        t => return Err(fail(format!("Park Systems image type {t} is unknown"))),
    }
    let size = match h.data_type {
        0 => 2,
        1 | 2 => 4,
        t => return Err(fail(format!("Park Systems data type {t} is unknown"))),
    };
    let data = block(TAG_DATA, "data")?;
    let need = h.nx.checked_mul(h.ny).and_then(|n| n.checked_mul(size));
    if h.nx == 0 || h.ny == 0 || need.is_none_or(|n| n > data.len()) {
        return Err(fail(format!(
            "Park Systems grid {} × {} of {size}-byte values does not fit its data tag ({} bytes)",
            h.nx,
            h.ny,
            data.len()
        )));
    }
    for (name, v) in [
        ("physical_size_x", h.size_x_um),
        ("physical_size_y", h.size_y_um),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(fail(format!(
                "Park Systems {name} = {v} µm is not a positive length"
            )));
        }
    }
    let unit = if h.data_unit.is_empty() {
        "um"
    } else {
        h.data_unit.as_str()
    };
    let unit_factor = length_factor(unit).ok_or_else(|| {
        unsupported(
            path,
            format!(
                "channel `{}` is in `{unit}`, not a length; only height channels are read",
                h.source_name
            ),
        )
    })?;
    let scale = if h.data_scale_factor == 0.0 {
        1.0
    } else {
        h.data_scale_factor
    };
    let (gain, offset) = (h.data_gain * unit_factor, h.data_offset);
    let value = |k: usize| -> f64 {
        let raw = match h.data_type {
            0 => f64::from(i16::from_le_bytes([data[2 * k], data[2 * k + 1]])),
            1 => f64::from(le_i32(data, 4 * k)),
            _ => le_f32(data, 4 * k),
        };
        gain * (scale * raw + offset)
    };
    let (nx, ny) = (h.nx, h.ny);
    let z = Array2::from_shape_fn((ny, nx), |(r, i)| value((ny - 1 - r) * nx + i));
    let mut header = BTreeMap::new();
    header.insert("version".into(), format!("{version:#x}"));
    header.insert("source_name".into(), h.source_name.clone());
    header.insert("image_mode".into(), h.image_mode.clone());
    header.insert("data_unit".into(), unit.to_string());
    header.insert("data_gain".into(), h.data_gain.to_string());
    header.insert("data_scale_factor".into(), h.data_scale_factor.to_string());
    header.insert("data_offset".into(), h.data_offset.to_string());
    for (k, v) in h.extra {
        header.insert(k.into(), v);
    }
    let um = 1e-6;
    Ok(RawMap {
        z,
        dx: h.size_x_um * um / nx as f64,
        dy: h.size_y_um * um / ny as f64,
        x0: h.x_offset_um * um,
        y0: h.y_offset_um * um,
        channel: h.source_name,
        format: "park",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::tiff::tests::tiff;
    use super::super::tiff::{Order, BYTE, LONG, UNDEFINED};
    use super::*;

    fn put_f64(b: &mut [u8], at: usize, v: f64) {
        b[at..at + 8].copy_from_slice(&v.to_le_bytes());
    }
    fn put_u32(b: &mut [u8], at: usize, v: u32) {
        b[at..at + 4].copy_from_slice(&v.to_le_bytes());
    }
    fn put_utf16(b: &mut [u8], at: usize, s: &str) {
        for (k, u) in s.encode_utf16().enumerate() {
            b[at + 2 * k..at + 2 * k + 2].copy_from_slice(&u.to_le_bytes());
        }
    }

    /// A version-2 Park TIFF (in TIFF byte order `order`) of 4 × 3 values `data_type`
    /// (0 int16, 1 int32, 2 float32), line k holding 10·k + i, with gain 2, scale 0.5,
    /// offset 1 in `unit`, 8 × 6 µm.
    fn park(order: Order, data_type: u32, unit: &str) -> Vec<u8> {
        let (nx, ny) = (4u32, 3u32);
        let mut h = vec![0u8; HEADER_V2];
        put_utf16(&mut h, 4, "Z Height");
        put_u32(&mut h, 100, nx);
        put_u32(&mut h, 104, ny);
        put_f64(&mut h, 140, 8.0);
        put_f64(&mut h, 148, 6.0);
        put_f64(&mut h, 220, 2.0);
        put_f64(&mut h, 228, 0.5);
        put_f64(&mut h, 236, 1.0);
        put_utf16(&mut h, 244, unit);
        put_u32(&mut h, 348, data_type);
        let mut data = Vec::new();
        for k in 0..ny {
            for i in 0..nx {
                let v = (10 * k + i) as i16;
                match data_type {
                    0 => data.extend(v.to_le_bytes()),
                    1 => data.extend(i32::from(v).to_le_bytes()),
                    _ => data.extend(f32::from(v).to_le_bytes()),
                }
            }
        }
        let long = |v: u32| match order {
            Order::Little => v.to_le_bytes().to_vec(),
            Order::Big => v.to_be_bytes().to_vec(),
        };
        tiff(
            order,
            &[
                (TAG_MAGIC, LONG, 1, long(MAGIC)),
                (TAG_VERSION, LONG, 1, long(VERSION_2 as u32)),
                (TAG_DATA, BYTE, data.len() as u32, data),
                (TAG_HEADER, UNDEFINED, h.len() as u32, h),
            ],
        )
    }

    #[test]
    fn heights_orientation_and_scales_in_both_byte_orders_and_types() {
        for order in [Order::Little, Order::Big] {
            for data_type in 0..3 {
                let bytes = park(order, data_type, "nm");
                assert!(looks_like(&bytes));
                let map = read_bytes("a.tiff", &bytes).unwrap();
                assert_eq!(
                    (map.nx(), map.ny(), map.source.format.as_str()),
                    (4, 3, "park")
                );
                assert_eq!(map.channel, "Z Height");
                assert!(close(map.dx, 2e-6, 1e-15) && close(map.dy, 2e-6, 1e-15));
                // Row r is stored line 2 − r: z = 2 · (0.5 · (10·(2 − r) + i) + 1) nm.
                for r in 0..3 {
                    for i in 0..4 {
                        let want = 2.0 * (0.5 * (10 * (2 - r) + i) as f64 + 1.0) * 1e-9;
                        assert!(close(map.z[[r, i]], want, 1e-12), "{r} {i}");
                    }
                }
            }
        }
    }

    #[test]
    fn non_length_units_line_profiles_and_short_data_are_errors() {
        let e = read_bytes("b.tiff", &park(Order::Little, 2, "deg"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.tiff") && e.contains("not a length"), "{e}");
        let mut bytes = park(Order::Little, 0, "um");
        // The header is the last value the test writer appends.
        let header_at = bytes.len() - HEADER_V2;
        let mut line = bytes.clone();
        line[header_at] = 1;
        let e = read_bytes("c.tiff", &line).unwrap_err().to_string();
        assert!(e.contains("line profiles"), "{e}");
        // 1000 × 3 int16 values do not fit 24 bytes of data.
        bytes[header_at + 100..header_at + 104].copy_from_slice(&1000u32.to_le_bytes());
        let e = read_bytes("d.tiff", &bytes).unwrap_err().to_string();
        assert!(e.contains("d.tiff") && e.contains("does not fit"), "{e}");
    }
}
