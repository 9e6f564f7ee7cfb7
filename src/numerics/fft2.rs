//! 2-D FFT helpers on ndarray fields (rows then columns, via rustfft).
//!
//! Conventions are numpy's: the forward transform is unnormalised,
//! `Ẑ[q, p] = Σ z[j, i]·exp(−2πi(p·i/nx + q·j/ny))`, and the inverse divides by `nx·ny`, so
//! `ifft2(fft2(z)) = z` and Parseval reads `Σ|Ẑ|² = N·Σ|z|²`.
use ndarray::Array2;
use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftDirection, FftPlanner};
use std::f64::consts::PI;
use std::sync::Arc;

/// Forward 2-D FFT of a complex field (unnormalised).
pub fn fft2(field: &Array2<Complex64>) -> Array2<Complex64> {
    let mut out = field.as_standard_layout().into_owned();
    transform_in_place(&mut out, FftDirection::Forward);
    out
}

/// Inverse 2-D FFT (normalised by `1/(nx·ny)`).
pub fn ifft2(spectrum: &Array2<Complex64>) -> Array2<Complex64> {
    let mut out = spectrum.as_standard_layout().into_owned();
    transform_in_place(&mut out, FftDirection::Inverse);
    let scale = 1.0 / out.len().max(1) as f64;
    out.mapv_inplace(|c| c * scale);
    out
}

/// Forward 2-D FFT of a real field.
pub fn fft2_real(field: &Array2<f64>) -> Array2<Complex64> {
    let mut out = field.mapv(|v| Complex64::new(v, 0.0));
    transform_in_place(&mut out, FftDirection::Forward);
    out
}

/// Inverse 2-D FFT keeping the real part (for spectra of real fields that were only multiplied
/// by real, even transfer functions, where the imaginary part is rounding noise).
pub fn ifft2_real(spectrum: &Array2<Complex64>) -> Array2<f64> {
    ifft2(spectrum).mapv(|c| c.re)
}

/// Angular wavenumbers `2π·fftfreq(n, d)` of an n-point axis with spacing `d`, in FFT order:
/// `0, 1, …, ⌈n/2⌉−1, −⌊n/2⌋, …, −1` times `2π/(n·d)` (the Nyquist bin of an even n is negative,
/// as in numpy).
pub fn angular_wavenumbers(n: usize, d: f64) -> Vec<f64> {
    let step = 2.0 * PI / (n as f64 * d);
    (0..n)
        .map(|k| {
            let signed = if k < n.div_ceil(2) {
                k as f64
            } else {
                k as f64 - n as f64
            };
            signed * step
        })
        .collect()
}

/// Rows then columns, in place; `field` must be in standard (row-major) layout.
fn transform_in_place(field: &mut Array2<Complex64>, direction: FftDirection) {
    let (ny, nx) = field.dim();
    if nx == 0 || ny == 0 {
        return;
    }
    let mut planner = FftPlanner::<f64>::new();
    let row_fft: Arc<dyn Fft<f64>> = planner.plan_fft(nx, direction);
    let col_fft: Arc<dyn Fft<f64>> = planner.plan_fft(ny, direction);
    let scratch_len = row_fft
        .get_inplace_scratch_len()
        .max(col_fft.get_inplace_scratch_len());
    let mut scratch = vec![Complex64::new(0.0, 0.0); scratch_len];

    let data = field
        .as_slice_mut()
        .expect("transform_in_place needs a standard-layout array");
    // rustfft processes consecutive chunks of the transform length: all rows in one call.
    row_fft.process_with_scratch(data, &mut scratch[..row_fft.get_inplace_scratch_len()]);

    // Columns: transpose into a contiguous buffer so every column is a contiguous chunk.
    let mut columns = vec![Complex64::new(0.0, 0.0); nx * ny];
    for j in 0..ny {
        for i in 0..nx {
            columns[i * ny + j] = data[j * nx + i];
        }
    }
    col_fft.process_with_scratch(
        &mut columns,
        &mut scratch[..col_fft.get_inplace_scratch_len()],
    );
    for i in 0..nx {
        for j in 0..ny {
            data[j * nx + i] = columns[i * ny + j];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test_field(ny: usize, nx: usize) -> Array2<f64> {
        Array2::from_shape_fn((ny, nx), |(j, i)| {
            ((j * 31 + i * 17) % 23) as f64 / 7.0 - 1.3 + (0.3 * i as f64).sin()
        })
    }

    #[test]
    fn round_trip_recovers_the_field() {
        for &(ny, nx) in &[(8, 8), (6, 10), (7, 5), (1, 9), (12, 1)] {
            let z = test_field(ny, nx);
            let back = ifft2_real(&fft2_real(&z));
            for (a, b) in z.iter().zip(back.iter()) {
                assert!((a - b).abs() < 1e-12, "{ny}x{nx}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn parseval_holds() {
        let z = test_field(12, 18);
        let spec = fft2_real(&z);
        let energy: f64 = z.iter().map(|v| v * v).sum();
        let spec_energy: f64 = spec.iter().map(|c| c.norm_sqr()).sum::<f64>() / z.len() as f64;
        assert!((energy - spec_energy).abs() < 1e-12 * energy);
    }

    #[test]
    fn single_mode_lands_in_its_bin() {
        let (ny, nx) = (8, 16);
        let z = Array2::from_shape_fn((ny, nx), |(j, i)| {
            (2.0 * PI * (3.0 * i as f64 / nx as f64 + 2.0 * j as f64 / ny as f64)).cos()
        });
        let spec = fft2_real(&z);
        let n = (nx * ny) as f64;
        assert!((spec[[2, 3]].re - n / 2.0).abs() < 1e-9);
        assert!((spec[[ny - 2, nx - 3]].re - n / 2.0).abs() < 1e-9);
        let rest: f64 = spec.iter().map(|c| c.norm()).sum::<f64>() - n;
        assert!(rest.abs() < 1e-9);
    }

    #[test]
    fn wavenumbers_follow_numpy_fftfreq() {
        let k = angular_wavenumbers(4, 0.5);
        let step = 2.0 * PI / 2.0;
        assert_eq!(k, vec![0.0, step, -2.0 * step, -step]);
        let k = angular_wavenumbers(5, 1.0);
        let step = 2.0 * PI / 5.0;
        assert_eq!(k, vec![0.0, step, 2.0 * step, -2.0 * step, -step]);
    }
}
