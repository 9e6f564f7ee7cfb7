//! Deterministic synthetic surfaces (sample data and tests).
//!
//! The random numbers come from a self-contained xoshiro256** generator seeded through
//! SplitMix64 and turned into normal deviates with Marsaglia's polar method, so a seed gives the
//! same field on every platform and every version of the dependencies. (The canonical reference
//! surface of the spec was made with numpy's PCG64, so these fields are statistically, not
//! numerically, equivalent to it.)
use super::{HeightMap, SourceInfo};
use crate::numerics::fft2::{angular_wavenumbers, fft2_real, ifft2_real};
use crate::numerics::rng::Rng;
use ndarray::Array2;
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// Periodic Gaussian random surface with Gaussian ACF σ² exp(−r²/ℓ²) on an n × n grid of
/// physical size `size` (m), rescaled so its RMS is exactly `sigma`; same seed → same field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussianSurfaceSpec {
    pub n: usize,
    pub size: f64,
    pub sigma: f64,
    pub correlation_length: f64,
    pub seed: u64,
}

fn synthetic_map(
    z: Array2<f64>,
    dx: f64,
    periodic: bool,
    header: BTreeMap<String, String>,
) -> HeightMap {
    HeightMap {
        z,
        dx,
        dy: dx,
        x0: 0.0,
        y0: 0.0,
        channel: "synthetic height".into(),
        valid: None,
        periodic,
        source: SourceInfo {
            format: "synthetic".into(),
            header,
        },
        history: Vec::new(),
    }
}

/// White Gaussian noise filtered in Fourier space by √PSD, where the PSD of the ACF
/// σ² exp(−r²/ℓ²) is ∝ exp(−k²ℓ²/4) (angular k); then the mean is removed and the field is
/// scaled to RMS σ exactly. Degenerate specs (n = 0, non-positive size) give an all-zero map.
pub fn gaussian_acf_surface(spec: &GaussianSurfaceSpec) -> HeightMap {
    let n = spec.n;
    let dx = if n > 0 {
        spec.size / n as f64
    } else {
        spec.size
    };
    let mut rng = Rng::new(spec.seed);
    let noise = Array2::from_shape_fn((n, n), |_| rng.normal());
    let mut spectrum = fft2_real(&noise);
    let k = angular_wavenumbers(n, dx);
    let l2 = spec.correlation_length * spec.correlation_length;
    // √PSD = exp(−k²ℓ²/8), separable in kx and ky.
    let amplitude: Vec<f64> = k.iter().map(|kk| (-kk * kk * l2 / 8.0).exp()).collect();
    for ((q, p), c) in spectrum.indexed_iter_mut() {
        *c *= amplitude[q] * amplitude[p];
    }
    let mut z = ifft2_real(&spectrum);
    let count = z.len().max(1) as f64;
    let mean = z.sum() / count;
    z.mapv_inplace(|v| v - mean);
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / count).sqrt();
    if rms > 0.0 && rms.is_finite() {
        z.mapv_inplace(|v| v * (spec.sigma / rms));
    }

    let mut header = BTreeMap::new();
    header.insert("generator".into(), "gaussian_acf_surface".into());
    header.insert(
        "rng".into(),
        "xoshiro256** seeded by SplitMix64, Marsaglia polar normals".into(),
    );
    header.insert("acf".into(), "sigma^2 exp(-r^2/l^2)".into());
    header.insert("n".into(), n.to_string());
    header.insert("size_m".into(), format!("{:e}", spec.size));
    header.insert("sigma_m".into(), format!("{:e}", spec.sigma));
    header.insert(
        "correlation_length_m".into(),
        format!("{:e}", spec.correlation_length),
    );
    header.insert("seed".into(), spec.seed.to_string());
    synthetic_map(z, dx, true, header)
}

/// z = A·cos(2πx/λ)·cos(2πy/λ) on an n × n grid of spacing `dx` (periodic if n·dx is a
/// multiple of λ).
pub fn egg_crate(n: usize, dx: f64, amplitude: f64, wavelength: f64) -> HeightMap {
    let k = 2.0 * PI / wavelength;
    let profile: Vec<f64> = (0..n).map(|i| (k * i as f64 * dx).cos()).collect();
    let z = Array2::from_shape_fn((n, n), |(j, i)| amplitude * profile[i] * profile[j]);
    let periods = n as f64 * dx / wavelength;
    let periodic =
        periods.is_finite() && periods.round() >= 1.0 && (periods - periods.round()).abs() < 1e-9;
    let mut header = BTreeMap::new();
    header.insert("generator".into(), "egg_crate".into());
    header.insert("n".into(), n.to_string());
    header.insert("dx_m".into(), format!("{dx:e}"));
    header.insert("amplitude_m".into(), format!("{amplitude:e}"));
    header.insert("wavelength_m".into(), format!("{wavelength:e}"));
    synthetic_map(z, dx, periodic, header)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(seed: u64) -> GaussianSurfaceSpec {
        GaussianSurfaceSpec {
            n: 128,
            size: 0.5e-6,
            sigma: 0.5e-9,
            correlation_length: 20e-9,
            seed,
        }
    }

    #[test]
    fn rng_is_reproducible_and_roughly_normal() {
        let mut a = Rng::new(7);
        let mut b = Rng::new(7);
        let xs: Vec<f64> = (0..200_000).map(|_| a.normal()).collect();
        let ys: Vec<f64> = (0..200_000).map(|_| b.normal()).collect();
        assert_eq!(xs, ys);
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        let kurt = xs.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / n / (var * var);
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.01, "{var}");
        assert!((kurt - 3.0).abs() < 0.05, "{kurt}");
    }

    #[test]
    fn gaussian_surface_is_deterministic_and_exactly_scaled() {
        let a = gaussian_acf_surface(&spec(1));
        let b = gaussian_acf_surface(&spec(1));
        let c = gaussian_acf_surface(&spec(2));
        assert_eq!(a.z, b.z);
        assert_ne!(a.z, c.z);
        let n = a.z.len() as f64;
        let mean = a.z.sum() / n;
        let rms = (a.z.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
        assert!(mean.abs() < 1e-12 * 0.5e-9);
        assert!((rms / 0.5e-9 - 1.0).abs() < 1e-12);
        assert!(a.periodic);
        assert_eq!(a.channel, "synthetic height");
        assert_eq!(a.source.format, "synthetic");
        assert_eq!(a.source.header["seed"], "1");
        assert_eq!((a.nx(), a.ny()), (128, 128));
        assert!((a.dx - 0.5e-6 / 128.0).abs() < 1e-24);
    }

    #[test]
    fn gaussian_surface_has_the_requested_correlation_length() {
        // Ensemble-free check on one large field: ACF at lag r ≈ σ² exp(−r²/ℓ²).
        let s = GaussianSurfaceSpec {
            n: 256,
            size: 2e-6,
            sigma: 1.0,
            correlation_length: 40e-9,
            seed: 99,
        };
        let map = gaussian_acf_surface(&s);
        let n = 256;
        let lag = 5; // 5 px = 39 nm ≈ ℓ
        let mut acc = 0.0;
        for j in 0..n {
            for i in 0..n {
                acc += map.z[[j, i]] * (map.z[[j, (i + lag) % n]] + map.z[[(j + lag) % n, i]]);
            }
        }
        let acf = acc / (2 * n * n) as f64;
        let r = lag as f64 * map.dx;
        let expected = (-(r * r) / (40e-9f64).powi(2)).exp();
        assert!((acf - expected).abs() < 0.08, "{acf} vs {expected}");
    }

    #[test]
    fn egg_crate_values_and_periodicity() {
        let dx = 1e-6 / 256.0;
        let map = egg_crate(256, dx, 1e-9, 64.0 * dx);
        assert!(map.periodic);
        assert!((map.z[[0, 0]] - 1e-9).abs() < 1e-24);
        assert!((map.z[[32, 32]] - 1e-9).abs() < 1e-22);
        assert!((map.z[[0, 32]] + 1e-9).abs() < 1e-22);
        assert!(!egg_crate(100, dx, 1e-9, 64.0 * dx).periodic);
        assert!(!egg_crate(16, dx, 1e-9, 64.0 * dx).periodic);
    }
}
