//! ISO 16610-61 areal Gaussian filter (docs/surfaces.md).
//!
//! The analytic transfer function `H(λ) = exp(−π(αλc/λ)²)`, `α = √(ln2/π)`, is applied in the
//! frequency domain, so the transmission of every Fourier mode is exact (no kernel truncation).
//! Periodic fields are transformed as they are; non-periodic fields are mirror-extended to
//! 2ny × 2nx first (even reflection), which is periodic without wrap-around steps.
use super::level::check_mask_shape;
use super::{HeightMap, Result, SurfaceError};
use crate::numerics::fft2::angular_wavenumbers;
use ndarray::Array2;
use std::f64::consts::PI;

/// `α = √(ln2/π)`: makes the transmission exactly 50 % at the cutoff.
pub fn iso_alpha() -> f64 {
    (std::f64::consts::LN_2 / PI).sqrt()
}

/// Low-pass amplitude transmission of a mode of wavelength `wavelength` for cutoff `cutoff`.
pub fn lowpass_transmission(wavelength: f64, cutoff: f64) -> f64 {
    let ratio = iso_alpha() * cutoff / wavelength;
    (-PI * ratio * ratio).exp()
}

/// Gaussian low-pass with cutoff wavelength `cutoff` (m): transmission 0.5^((λc/λ)²).
///
/// Pure function of the heights: NaNs propagate (use [`apply_filters`] for maps with invalid
/// pixels) and the cutoff is not validated here (`apply_filters` does).
pub fn gaussian_lowpass(
    z: &Array2<f64>,
    dx: f64,
    dy: f64,
    cutoff: f64,
    periodic: bool,
) -> Array2<f64> {
    let (ny, nx) = z.dim();
    if nx == 0 || ny == 0 {
        return z.clone();
    }
    // |k|²/(2π)² = 1/λ², so H = exp(−π α²λc² |k|²/(4π²)). The Gaussian factorises,
    // H(kx, ky) = H(kx)·H(ky), and so does the even mirror extension: filtering every row,
    // then every column, equals the 2-D transform of the 2ny × 2nx extended field, at a
    // quarter of the work.
    let mut out = z.as_standard_layout().into_owned();
    gaussian_lowpass_in_place(&mut out, dx, dy, cutoff, periodic);
    out
}

/// Columns gathered per batch by [`gaussian_lowpass_in_place`]: even, so the columns pair up
/// for the two-lines-per-FFT trick exactly as a whole transposed copy would (same numbers), while
/// the transposed buffer stays small (ny·128·8 bytes instead of a second full map).
const COLUMN_BATCH: usize = 128;

/// [`gaussian_lowpass`] overwriting `z` (one map in memory plus a column batch).
pub fn gaussian_lowpass_in_place(
    z: &mut Array2<f64>,
    dx: f64,
    dy: f64,
    cutoff: f64,
    periodic: bool,
) {
    let (ny, nx) = z.dim();
    if nx == 0 || ny == 0 {
        return;
    }
    // |k|²/(2π)² = 1/λ², so H = exp(−π α²λc² |k|²/(4π²)). The Gaussian factorises,
    // H(kx, ky) = H(kx)·H(ky), and so does the even mirror extension: filtering every row,
    // then every column, equals the 2-D transform of the 2ny × 2nx extended field, at a
    // quarter of the work.
    let factor = -PI * (iso_alpha() * cutoff).powi(2) / (4.0 * PI * PI);
    if !z.is_standard_layout() {
        *z = z.as_standard_layout().into_owned();
    }
    let Some(data) = z.as_slice_mut() else {
        return;
    };
    filter_lines(data, nx, dx, factor, periodic);
    let mut batch = vec![0.0; ny * COLUMN_BATCH.min(nx)];
    for c0 in (0..nx).step_by(COLUMN_BATCH) {
        let width = COLUMN_BATCH.min(nx - c0);
        let cols = &mut batch[..width * ny];
        for j in 0..ny {
            let row = &data[j * nx + c0..j * nx + c0 + width];
            for (c, &v) in row.iter().enumerate() {
                cols[c * ny + j] = v;
            }
        }
        filter_lines(cols, ny, dy, factor, periodic);
        for j in 0..ny {
            let row = &mut data[j * nx + c0..j * nx + c0 + width];
            for (c, v) in row.iter_mut().enumerate() {
                *v = cols[c * ny + j];
            }
        }
    }
}

/// Filter every contiguous line of length `n` in `data` with the transfer function
/// `exp(factor·k²)`: on the line itself when periodic, else on its even mirror extension
/// (length 2n, edge samples repeated, continuous across the wrap-around). Two real lines share
/// one complex FFT (the filter is real and even, so real and imaginary parts stay apart);
/// line pairs run in parallel.
fn filter_lines(data: &mut [f64], n: usize, d: f64, factor: f64, periodic: bool) {
    use rayon::prelude::*;
    use rustfft::num_complex::Complex64;
    let m = if periodic { n } else { 2 * n };
    let gain: Vec<f64> = angular_wavenumbers(m, d)
        .iter()
        .map(|k| (factor * k * k).exp() / m as f64)
        .collect();
    let mut planner = rustfft::FftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(m);
    let inverse = planner.plan_fft_inverse(m);
    let scratch_len = forward
        .get_inplace_scratch_len()
        .max(inverse.get_inplace_scratch_len());
    let source = |i: usize| if i < n { i } else { 2 * n - 1 - i };
    data.par_chunks_mut(2 * n).for_each_init(
        || {
            (
                vec![Complex64::default(); m],
                vec![Complex64::default(); scratch_len],
            )
        },
        |(buf, scratch), pair| {
            let (a, mut b) = if pair.len() == 2 * n {
                let (a, b) = pair.split_at_mut(n);
                (a, Some(b))
            } else {
                (pair, None)
            };
            for (i, c) in buf.iter_mut().enumerate() {
                let j = source(i);
                *c = Complex64::new(a[j], b.as_ref().map_or(0.0, |b| b[j]));
            }
            forward.process_with_scratch(buf, scratch);
            for (c, g) in buf.iter_mut().zip(&gain) {
                *c *= g;
            }
            inverse.process_with_scratch(buf, scratch);
            for (i, v) in a.iter_mut().enumerate() {
                *v = buf[i].re;
            }
            if let Some(b) = b.as_mut() {
                for (i, v) in b.iter_mut().enumerate() {
                    *v = buf[i].im;
                }
            }
        },
    );
}

/// Validates a cutoff wavelength: finite, positive and at least two pixels (Nyquist).
fn check_cutoff(name: &str, cutoff: f64, map: &HeightMap) -> Result<()> {
    let nyquist = 2.0 * map.dx.max(map.dy);
    if !cutoff.is_finite() || cutoff <= 0.0 || cutoff < nyquist {
        return Err(SurfaceError::Parameter {
            name: name.into(),
            value: format!("{cutoff:e} m"),
            expected: format!(
                "a finite cutoff wavelength ≥ 2·max(dx, dy) = {nyquist:e} m (Nyquist)"
            ),
        });
    }
    Ok(())
}

/// The filters of [`apply_filters`] on a map with invalid pixels: those are filled with the mean
/// of the valid pixels first and get their original values back afterwards.
fn filter_with_fill(
    map: &mut HeightMap,
    s_cutoff: Option<f64>,
    l_cutoff: Option<f64>,
) -> Result<()> {
    let original = map.z.clone();
    let usable = |j: usize, i: usize, v: f64| map.is_valid(j, i) && v.is_finite();
    let (mut sum, mut count) = (0.0, 0usize);
    for ((j, i), &v) in original.indexed_iter() {
        if usable(j, i, v) {
            sum += v;
            count += 1;
        }
    }
    if count == 0 {
        return Err(SurfaceError::InvalidData(
            "filtering: the map has no valid pixels".into(),
        ));
    }
    let fill = sum / count as f64;
    let mut z = Array2::from_shape_fn(original.dim(), |(j, i)| {
        let v = original[[j, i]];
        if usable(j, i, v) {
            v
        } else {
            fill
        }
    });
    if let Some(cutoff) = s_cutoff {
        gaussian_lowpass_in_place(&mut z, map.dx, map.dy, cutoff, map.periodic);
    }
    if let Some(cutoff) = l_cutoff {
        let waviness = gaussian_lowpass(&z, map.dx, map.dy, cutoff, map.periodic);
        z -= &waviness;
    }
    for ((j, i), v) in z.indexed_iter_mut() {
        let raw = original[[j, i]];
        if !(map.is_valid(j, i) && raw.is_finite()) {
            *v = raw;
        }
    }
    map.z = z;
    Ok(())
}

/// S-filter (low-pass at `s_cutoff`, removes noise) and L-filter (high-pass at `l_cutoff`,
/// removes waviness), both optional; recorded in history.
///
/// Invalid (or non-finite) pixels are filled with the mean of the valid pixels before
/// filtering (0 after levelling with `mean`) and keep their original values afterwards, so they
/// stay excluded from statistics without leaking NaNs into their neighbours.
pub fn apply_filters(
    map: &mut HeightMap,
    s_cutoff: Option<f64>,
    l_cutoff: Option<f64>,
) -> Result<()> {
    check_mask_shape(map)?;
    if let Some(c) = s_cutoff {
        check_cutoff("filter_s", c, map)?;
    }
    if let Some(c) = l_cutoff {
        check_cutoff("filter_l", c, map)?;
    }
    if let (Some(s), Some(l)) = (s_cutoff, l_cutoff) {
        if s >= l {
            return Err(SurfaceError::Parameter {
                name: "filter_s".into(),
                value: format!("{s:e} m"),
                expected: format!("below the L-filter cutoff {l:e} m"),
            });
        }
    }
    if s_cutoff.is_none() && l_cutoff.is_none() {
        return Ok(());
    }

    let edges = if map.periodic { "periodic" } else { "mirror" };
    let all_usable = map.valid.as_ref().is_none_or(|v| v.iter().all(|ok| *ok))
        && map.z.iter().all(|v| v.is_finite());
    if all_usable {
        // Nothing to fill or restore: filter the heights where they are (no copy of the map
        // for the S-filter; the L-filter needs its waviness beside them).
        if let Some(cutoff) = s_cutoff {
            gaussian_lowpass_in_place(&mut map.z, map.dx, map.dy, cutoff, map.periodic);
        }
        if let Some(cutoff) = l_cutoff {
            let waviness = gaussian_lowpass(&map.z, map.dx, map.dy, cutoff, map.periodic);
            map.z -= &waviness;
        }
    } else {
        filter_with_fill(map, s_cutoff, l_cutoff)?;
    }

    if let Some(cutoff) = s_cutoff {
        map.push_step(
            "filter_s",
            &[
                ("kind", "gaussian ISO 16610-61 low-pass".into()),
                ("cutoff_m", format!("{cutoff:e}")),
                ("edges", edges.into()),
                ("invalid_fill", "valid mean".into()),
            ],
        );
    }
    if let Some(cutoff) = l_cutoff {
        map.push_step(
            "filter_l",
            &[
                ("kind", "gaussian ISO 16610-61 high-pass".into()),
                ("cutoff_m", format!("{cutoff:e}")),
                ("edges", edges.into()),
                ("invalid_fill", "valid mean".into()),
            ],
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::SourceInfo;

    fn sinusoid(ny: usize, nx: usize, wavelength_px: f64, phase: f64) -> Array2<f64> {
        Array2::from_shape_fn((ny, nx), |(_, i)| {
            (2.0 * PI * i as f64 / wavelength_px + phase).cos()
        })
    }

    #[test]
    fn transmission_constants_match_iso() {
        assert!((iso_alpha() - 0.469719).abs() < 1e-6);
        assert!((lowpass_transmission(2.0, 1.0) - 0.840896).abs() < 1e-6);
        assert!((lowpass_transmission(4.0, 1.0) - 0.957603).abs() < 1e-6);
    }

    #[test]
    fn periodic_sinusoid_transmission_is_exact() {
        let dx = 1e-9;
        let z = sinusoid(16, 128, 32.0, 0.3);
        for (cutoff_px, expected) in [(16.0, 0.840896), (32.0, 0.5), (64.0, 0.0625)] {
            let low = gaussian_lowpass(&z, dx, dx, cutoff_px * dx, true);
            let exact = 0.5f64.powf((cutoff_px / 32.0f64).powi(2));
            assert!((exact - expected).abs() < 1e-6);
            for (a, b) in low.iter().zip(z.iter()) {
                assert!(
                    (a - exact * b).abs() < 1e-12,
                    "λc = {cutoff_px}: {a} vs {}",
                    exact * b
                );
            }
        }
    }

    /// Columns are filtered in batches of COLUMN_BATCH: a map wider than two batches with an
    /// odd width (a lone last column) must still get the analytic transmission 0.5^((λc/λ)²)
    /// of each mode: z = cos(2πj/16)·(1 + ½cos(2π·3i/nx)), λc = 8 px, periodic.
    #[test]
    fn column_batches_filter_every_column_exactly() {
        let (ny, nx) = (64, 2 * COLUMN_BATCH + 45);
        let x_mode = |i: usize| (2.0 * PI * 3.0 * i as f64 / nx as f64).cos();
        let y_mode = |j: usize| (2.0 * PI * j as f64 / 16.0).cos();
        let z = Array2::from_shape_fn((ny, nx), |(j, i)| y_mode(j) * (1.0 + 0.5 * x_mode(i)));
        let dx = 1e-9;
        let t = |wavelength_px: f64| 0.5f64.powf((8.0 / wavelength_px).powi(2));
        let (t_y, t_x) = (t(16.0), t(nx as f64 / 3.0));
        let mut low = z.clone();
        gaussian_lowpass_in_place(&mut low, dx, dx, 8.0 * dx, true);
        for ((j, i), a) in low.indexed_iter() {
            let expected = t_y * y_mode(j) * (1.0 + 0.5 * t_x * x_mode(i));
            assert!(
                (a - expected).abs() < 1e-12,
                "({j}, {i}): {a} vs {expected}"
            );
        }
    }

    #[test]
    fn sinusoid_along_y_and_rectangular_pixels() {
        let (dx, dy) = (1e-9, 2e-9);
        let z = Array2::from_shape_fn((64, 8), |(j, _)| (2.0 * PI * j as f64 / 16.0).sin());
        // λ = 16 px · dy = 32 nm; λc = 32 nm ⇒ 0.5.
        let low = gaussian_lowpass(&z, dx, dy, 32e-9, true);
        for (a, b) in low.iter().zip(z.iter()) {
            assert!((a - 0.5 * b).abs() < 1e-12);
        }
    }

    #[test]
    fn non_periodic_interior_transmission() {
        let dx = 1e-9;
        // 300 px is not a multiple of 32 px, so the field is not periodic.
        let z = sinusoid(40, 300, 32.0, 0.7);
        for cutoff_px in [16.0, 32.0, 64.0] {
            let h = lowpass_transmission(32.0, cutoff_px);
            let low = gaussian_lowpass(&z, dx, dx, cutoff_px * dx, false);
            for j in 0..40 {
                for i in 100..200 {
                    let expected = h * z[[j, i]];
                    assert!(
                        (low[[j, i]] - expected).abs() < 1e-3,
                        "λc = {cutoff_px} at ({j},{i}): {} vs {expected}",
                        low[[j, i]]
                    );
                }
            }
        }
    }

    fn test_map(z: Array2<f64>) -> HeightMap {
        HeightMap {
            z,
            dx: 1e-9,
            dy: 1e-9,
            x0: 0.0,
            y0: 0.0,
            channel: "test".into(),
            valid: None,
            periodic: true,
            source: SourceInfo::default(),
            history: Vec::new(),
        }
    }

    #[test]
    fn high_pass_is_the_complement_and_steps_are_recorded() {
        let z = Array2::from_shape_fn((64, 64), |(j, i)| {
            (2.0 * PI * i as f64 / 8.0).cos() + 2.0 * (2.0 * PI * j as f64 / 64.0).sin()
        });
        let mut map = test_map(z.clone());
        apply_filters(&mut map, Some(2e-9), Some(32e-9)).unwrap();
        let hs = lowpass_transmission(8.0, 2.0);
        let hl_short = lowpass_transmission(8.0, 32.0);
        let hl_long = lowpass_transmission(64.0, 32.0);
        for ((j, i), v) in map.z.indexed_iter() {
            let expected = hs * (1.0 - hl_short) * (2.0 * PI * i as f64 / 8.0).cos()
                + lowpass_transmission(64.0, 2.0)
                    * (1.0 - hl_long)
                    * 2.0
                    * (2.0 * PI * j as f64 / 64.0).sin();
            assert!((v - expected).abs() < 1e-12);
        }
        let names: Vec<&str> = map.history.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["filter_s", "filter_l"]);
    }

    #[test]
    fn bad_cutoffs_are_parameter_errors() {
        let mut map = test_map(Array2::zeros((8, 8)));
        for bad in [0.0, -1e-9, f64::NAN, f64::INFINITY, 1.5e-9] {
            assert!(matches!(
                apply_filters(&mut map, Some(bad), None),
                Err(SurfaceError::Parameter { .. })
            ));
            assert!(apply_filters(&mut map, None, Some(bad)).is_err());
        }
        assert!(apply_filters(&mut map, Some(8e-9), Some(4e-9)).is_err());
        assert!(map.history.is_empty());
    }

    #[test]
    fn invalid_pixels_do_not_leak() {
        let mut z = Array2::from_shape_fn((32, 32), |(j, i)| ((i * 7 + j * 3) % 5) as f64);
        z[[5, 5]] = f64::NAN;
        let mut valid = Array2::from_elem((32, 32), true);
        valid[[5, 5]] = false;
        let mut map = test_map(z);
        map.periodic = false;
        map.valid = Some(valid);
        apply_filters(&mut map, Some(4e-9), None).unwrap();
        assert!(map.z[[5, 5]].is_nan());
        assert_eq!(map.z.iter().filter(|v| v.is_finite()).count(), 32 * 32 - 1);
    }
}
