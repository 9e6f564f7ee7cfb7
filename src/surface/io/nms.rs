//! NanoFocus `.nms` (µsurf confocal microscopes; docs/surfaces.md). No public description of
//! the format exists; the layout is SurfaceTopography's `IO/NMS.py` (1.27.1), checked against
//! the two public samples (little-endian): a fixed 3468-byte header holding, at 8, the raw range
//! (u32 min, max: 0, 65535), at 16 the height range zmin, zmax (f64, µm), at 32 a version text
//! (`OM_MS_2.0`), at 52 the title (`Confocal Height Image`), at 1076 the date
//! (`2022-02-09T13:25`), at 1368 nx, ny (u32) and dx, dy (f64); then ny rows of nx uint16
//! heights, the first row at the top (SurfaceTopography's y = 0; no instrument software was at
//! hand to check), then, in the samples, an nx × ny 8-bit intensity image.
//!
//! hdi departs from SurfaceTopography 1.27.1 twice, both in hdi's favour on the evidence of the
//! samples (tests/data/README.md): heights are zmin + (v − raw min)/(raw max − raw min) ·
//! (zmax − zmin), the header's raw range [0, 65535] mapped onto [zmin, zmax] (each sample
//! holds exactly one 0 and one 65535, at zmin and zmax; SurfaceTopography divides by 65534,
//! putting the highest pixel above zmax); and dx, dy are in nanometres (312.5 nm × 512 pixels
//! = a 160 µm field, that of the µsurf's 100× objective; SurfaceTopography reads millimetres,
//! a 160 m field).
//!
//! Channels: `height` and, when the file holds it, `intensity` (counts 0–255, not lengths).
use super::le::{le_f64, le_u16, le_u32};
use super::units::nul_terminated;
use super::{find_channel, format_error, RawMap, ReadOptions};
use crate::surface::Result;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::path::Path;

const HEADER: usize = 3468;
const VERSION_AT: usize = 32;
const GRID_AT: usize = 1368;
/// The version text the samples carry (the only check of the format short of its sizes).
const VERSION_PREFIX: &[u8] = b"OM_MS_";
/// Largest plausible side (SurfaceTopography's check).
const MAX_SIDE: u32 = 100_000;

/// Whether a file starts like a NanoFocus NMS file: the version text `OM_MS_…` at byte 32 and a
/// plausible grid (1–100 000 pixels a side, positive spacings) at byte 1368.
pub(crate) fn looks_like(head: &[u8]) -> bool {
    if head.len() < GRID_AT + 24 || !head[VERSION_AT..].starts_with(VERSION_PREFIX) {
        return false;
    }
    let (nx, ny) = (le_u32(head, GRID_AT), le_u32(head, GRID_AT + 4));
    let (dx, dy) = (le_f64(head, GRID_AT + 8), le_f64(head, GRID_AT + 16));
    (1..=MAX_SIDE).contains(&nx)
        && (1..=MAX_SIDE).contains(&ny)
        && dx.is_finite()
        && dx > 0.0
        && dy.is_finite()
        && dy > 0.0
}

pub(crate) fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<RawMap> {
    let fail = |reason: String| format_error(path, reason);
    if !looks_like(bytes) {
        return Err(fail(format!(
            "not a NanoFocus NMS file (no `OM_MS_` version text and plausible grid in its header \
             of {} bytes)",
            bytes.len()
        )));
    }
    let (nx, ny) = (
        le_u32(bytes, GRID_AT) as usize,
        le_u32(bytes, GRID_AT + 4) as usize,
    );
    let (dx_nm, dy_nm) = (le_f64(bytes, GRID_AT + 8), le_f64(bytes, GRID_AT + 16));
    let pixels = nx * ny;
    let heights_end = HEADER + 2 * pixels;
    if bytes.len() < heights_end {
        return Err(fail(format!(
            "truncated NMS file: {nx} × {ny} uint16 heights need {heights_end} bytes, the file \
             has {}",
            bytes.len()
        )));
    }
    let has_intensity = bytes.len() >= heights_end + pixels;
    let mut names = vec![vec!["height".to_string()]];
    if has_intensity {
        names.push(vec!["intensity".to_string()]);
    }
    let listing = names
        .iter()
        .map(|n| n[0].as_str())
        .collect::<Vec<_>>()
        .join(", ");
    let chosen = match &opts.channel {
        None => 0,
        Some(wanted) => find_channel(wanted, &names)
            .ok_or_else(|| fail(format!("no channel `{wanted}`; channels: {listing}")))?,
    };
    let (raw_min, raw_max) = (le_u32(bytes, 8), le_u32(bytes, 12));
    let (z_min, z_max) = (le_f64(bytes, 16), le_f64(bytes, 24));
    let z = if chosen == 0 {
        if raw_max <= raw_min || !(z_min.is_finite() && z_max.is_finite() && z_max >= z_min) {
            return Err(fail(format!(
                "NMS height range: raw {raw_min}..{raw_max} onto {z_min}..{z_max} µm is not a \
                 usable scale"
            )));
        }
        let per_count = (z_max - z_min) / f64::from(raw_max - raw_min) * 1e-6;
        let (offset, raw_min) = (z_min * 1e-6, f64::from(raw_min));
        Array2::from_shape_fn((ny, nx), |(j, i)| {
            let v = f64::from(le_u16(bytes, HEADER + 2 * (j * nx + i)));
            offset + (v - raw_min) * per_count
        })
    } else {
        Array2::from_shape_fn((ny, nx), |(j, i)| {
            f64::from(bytes[heights_end + j * nx + i])
        })
    };
    let mut header = BTreeMap::new();
    header.insert("channels".to_string(), listing);
    for (key, at, len) in [
        ("version", VERSION_AT, 20),
        ("title", 52, 100),
        ("date", 1076, 20),
    ] {
        let text = nul_terminated(&bytes[at..at + len]);
        if !text.is_empty() {
            header.insert(key.to_string(), text);
        }
    }
    header.insert("z_range_um".to_string(), format!("{z_min}..{z_max}"));
    if chosen == 1 {
        header.insert("z_unit".to_string(), "counts".to_string());
    }
    Ok(RawMap {
        z,
        dx: dx_nm * 1e-9,
        dy: dy_nm * 1e-9,
        x0: 0.0,
        y0: 0.0,
        channel: names[chosen][0].clone(),
        format: "nms",
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::{read_height_map, ReadOptions};

    /// nms-1.nms: the one raw 0 and the one raw 65535 are exactly zmin and zmax of the header
    /// (2.689124584197998 and 6.007402420043945 µm, as SurfaceTopography reads them), the
    /// header's text fields, and the intensity image after the heights.
    #[test]
    fn height_range_header_and_intensity_of_nms_1() {
        let path = surface_sample("nms-1.nms");
        let map = read_height_map(&path, &ReadOptions::default()).unwrap();
        let lo = map.z.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = map.z.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        assert!(close(lo, 2.689124584197998e-6, 1e-15), "{lo}");
        assert!(close(hi, 6.007402420043945e-6, 1e-15), "{hi}");
        let h = &map.source.header;
        assert_eq!(h["version"], "OM_MS_2.0");
        assert_eq!(h["title"], "Confocal Height Image");
        assert_eq!(h["date"], "2022-02-09T13:25");
        assert_eq!(h["channels"], "height, intensity");
        let opts = ReadOptions {
            channel: Some("intensity".into()),
            ..ReadOptions::default()
        };
        let intensity = read_height_map(&path, &opts).unwrap();
        assert_eq!((intensity.nx(), intensity.ny()), (512, 512));
        assert_eq!(intensity.source.header["z_unit"], "counts");
    }

    /// Without the `OM_MS_` text the file is not recognised; a raw range that is empty is an
    /// error naming the file.
    #[test]
    fn detection_and_bad_range() {
        let bytes = std::fs::read(surface_sample("nms-2.nms")).unwrap();
        let mut other = bytes.clone();
        other[32] = b'X';
        let e = read_bytes("a.nms", &other).unwrap_err().to_string();
        assert!(e.contains("a.nms") && e.contains("unrecognised"), "{e}");
        let mut empty_range = bytes.clone();
        empty_range[12..16].copy_from_slice(&0u32.to_le_bytes());
        let e = read_bytes("b.nms", &empty_range).unwrap_err().to_string();
        assert!(
            e.contains("b.nms") && e.contains("not a usable scale"),
            "{e}"
        );
    }
}
