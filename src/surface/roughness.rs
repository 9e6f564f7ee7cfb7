//! Roughness parameters (signals-and-surfaces.md §2.6). CONTRACT STUB.
use super::{HeightMap, Result};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SummitScheme {
    FivePoint,
    NinePoint,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RadiusDefinition {
    /// R = 1/mean(κ) (McCool; default)
    InverseMeanCurvature,
    /// mean(1/κ) over κ > 0
    MeanOfInverse,
    /// median(1/κ) over κ > 0
    MedianOfInverse,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MomentsMethod {
    FiniteDifference,
    Spectral,
}

#[derive(Debug, Clone, PartialEq)]
pub struct RoughnessOptions {
    pub summits: SummitScheme,
    pub radius: RadiusDefinition,
    pub birmingham: bool,
    pub moments: MomentsMethod,
    pub histogram_bins: usize,
}

impl Default for RoughnessOptions {
    fn default() -> Self {
        Self {
            summits: SummitScheme::NinePoint,
            radius: RadiusDefinition::InverseMeanCurvature,
            birmingham: false,
            moments: MomentsMethod::FiniteDifference,
            histogram_bins: 64,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Summit {
    pub x: f64,
    pub y: f64,
    pub height: f64,
    pub curvature: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    /// Bin edges (n+1), metres.
    pub edges: Vec<f64>,
    pub counts: Vec<u64>,
    /// Probability density per bin (1/m).
    pub density: Vec<f64>,
    /// Gaussian density with the same mean and σ at the bin centres (1/m).
    pub gaussian: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct NayakEstimate {
    pub eta: f64,
    pub r: f64,
    pub beta: f64,
    pub sigma_s: f64,
    pub mean_summit_height: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct RoughnessReport {
    pub sigma: f64,
    pub sa: f64,
    pub ssk: f64,
    pub sku: f64,
    pub m2: f64,
    pub m4: f64,
    pub alpha: f64,
    pub moments_method: MomentsMethod,
    pub eta: f64,
    pub r: f64,
    pub r_definition: RadiusDefinition,
    pub r_mean_of_inverse: f64,
    pub r_median_of_inverse: f64,
    pub beta: f64,
    pub sigma_s: f64,
    pub mean_summit_height: f64,
    pub n_summits: usize,
    pub summit_scheme: SummitScheme,
    /// Area of the region where summits can be found (m²).
    pub candidate_area: f64,
    pub sampling_interval: f64,
    pub nayak: NayakEstimate,
    pub summits: Vec<Summit>,
    pub height_histogram: Histogram,
    pub summit_histogram: Histogram,
    pub warnings: Vec<String>,
}

pub fn roughness(_map: &HeightMap, _opts: &RoughnessOptions) -> Result<RoughnessReport> {
    unimplemented!()
}

/// One row of the scale-dependence sweep (sub-sampling 1, 2, 4; S-filter 2, 4, 8, 16 px).
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRow {
    /// "subsample" or "s_filter"
    pub kind: String,
    /// sub-sampling factor or S-filter cutoff in pixels
    pub value: f64,
    pub sampling_interval: f64,
    pub sigma: f64,
    pub eta: f64,
    pub r: f64,
    pub beta: f64,
}

pub fn scale_sweep(_map: &HeightMap, _opts: &RoughnessOptions) -> Result<Vec<SweepRow>> {
    unimplemented!()
}
