//! ISO 16610-61 areal Gaussian filter (signals-and-surfaces.md §2.4). CONTRACT STUB.
use super::{HeightMap, Result};
use ndarray::Array2;

/// Gaussian low-pass with cutoff wavelength `cutoff` (m): transmission 0.5^((λc/λ)²).
pub fn gaussian_lowpass(_z: &Array2<f64>, _dx: f64, _dy: f64, _cutoff: f64, _periodic: bool) -> Array2<f64> {
    unimplemented!()
}

/// S-filter (low-pass at `s_cutoff`, removes noise) and L-filter (high-pass at `l_cutoff`,
/// removes waviness), both optional; recorded in history.
pub fn apply_filters(_map: &mut HeightMap, _s_cutoff: Option<f64>, _l_cutoff: Option<f64>) -> Result<()> {
    unimplemented!()
}
