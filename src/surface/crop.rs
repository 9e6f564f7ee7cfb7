//! Crops (docs/surfaces.md): the dissertation analysed 1 × 1 µm sub-areas of larger
//! scans, chosen to exclude artefacts.

use super::{HeightMap, Result, SurfaceError};
use ndarray::s;

/// A rectangle in metres, relative to the map's first pixel: x along a scan line, y down the
/// image from the top row (as the instrument software displays it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CropRect {
    pub x0: f64,
    pub y0: f64,
    pub width: f64,
    pub height: f64,
}

/// Pixel range `[first, last)` covering `[start, start + len)` on an axis of `n` pixels of
/// size `d` (a pixel belongs when its centre lies inside).
fn pixel_range(start: f64, len: f64, d: f64, n: usize, axis: &str) -> Result<(usize, usize)> {
    let bad = |why: String| SurfaceError::Parameter {
        name: format!("crop {axis}"),
        value: format!("start {start:e} m, length {len:e} m"),
        expected: why,
    };
    if !(start.is_finite() && len.is_finite()) || start < 0.0 || len <= 0.0 {
        return Err(bad("a start ≥ 0 and a length > 0".into()));
    }
    let first = (start / d - 0.5).ceil().max(0.0) as usize;
    let last = (((start + len) / d - 0.5).ceil().max(0.0) as usize).min(n);
    if start + len > n as f64 * d * (1.0 + 1e-9) {
        return Err(bad(format!(
            "inside the map, which is {:e} m long",
            n as f64 * d
        )));
    }
    if last < first + 3 {
        return Err(bad("at least 3 pixels".into()));
    }
    Ok((first, last))
}

/// The sub-map inside `rect`; records a `crop` step.
pub fn crop(map: &HeightMap, rect: &CropRect) -> Result<HeightMap> {
    let (i0, i1) = pixel_range(rect.x0, rect.width, map.dx, map.nx(), "x")?;
    let (j0, j1) = pixel_range(rect.y0, rect.height, map.dy, map.ny(), "y")?;
    let mut out = map.clone();
    out.z = map.z.slice(s![j0..j1, i0..i1]).to_owned();
    out.valid = map
        .valid
        .as_ref()
        .map(|v| v.slice(s![j0..j1, i0..i1]).to_owned());
    out.x0 = map.x0 + i0 as f64 * map.dx;
    out.y0 = map.y0 + j0 as f64 * map.dy;
    // A cut-out of a periodic field is no longer periodic.
    out.periodic = false;
    out.push_step(
        "crop",
        &[
            ("columns", format!("{i0}..{i1}")),
            ("rows", format!("{j0}..{j1}")),
        ],
    );
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::synth::egg_crate;

    #[test]
    fn crop_selects_the_pixels_whose_centres_are_inside() {
        let map = egg_crate(64, 10e-9, 1e-9, 160e-9);
        let rect = CropRect {
            x0: 100e-9,
            y0: 200e-9,
            width: 250e-9,
            height: 100e-9,
        };
        let c = crop(&map, &rect).unwrap();
        assert_eq!(c.z.dim(), (10, 25));
        assert_eq!(c.z[[0, 0]], map.z[[20, 10]]);
        assert!((c.x0 - 100e-9).abs() < 1e-18 && (c.y0 - 200e-9).abs() < 1e-18);
        assert!(!c.periodic);
        assert_eq!(c.history.last().unwrap().name, "crop");
    }

    #[test]
    fn crops_outside_the_map_or_too_small_are_parameter_errors() {
        let map = egg_crate(64, 10e-9, 1e-9, 160e-9);
        for rect in [
            CropRect {
                x0: 0.0,
                y0: 0.0,
                width: 1e-6,
                height: 1e-7,
            },
            CropRect {
                x0: -1e-9,
                y0: 0.0,
                width: 1e-7,
                height: 1e-7,
            },
            CropRect {
                x0: 0.0,
                y0: 0.0,
                width: 1e-8,
                height: 1e-7,
            },
            CropRect {
                x0: 0.0,
                y0: 0.0,
                width: f64::NAN,
                height: 1e-7,
            },
        ] {
            assert!(
                matches!(crop(&map, &rect), Err(SurfaceError::Parameter { .. })),
                "{rect:?}"
            );
        }
    }
}
