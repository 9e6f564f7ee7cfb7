//! Deterministic synthetic surfaces (sample data and tests). CONTRACT STUB.
use super::HeightMap;

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

pub fn gaussian_acf_surface(_spec: &GaussianSurfaceSpec) -> HeightMap {
    unimplemented!()
}

/// z = A·cos(2πx/λ)·cos(2πy/λ) on an n × n grid of spacing `dx` (periodic if n·dx is a
/// multiple of λ).
pub fn egg_crate(_n: usize, _dx: f64, _amplitude: f64, _wavelength: f64) -> HeightMap {
    unimplemented!()
}
