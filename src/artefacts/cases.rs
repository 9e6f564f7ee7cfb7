//! The case files a `[simulate]` or `[three_dof]` instance exposes in its outputs (hard links
//! to its cached cases), by the names a downstream stage (`[analysis]`) addresses them with;
//! and a 2-DOF case's `result.json` ([`SweepCaseResult`]).

use serde::{Deserialize, Serialize};

/// Directory of the case files inside the instance's outputs.
pub const DIR: &str = "cases";

/// File name (inside `DIR`) of the 2-DOF sweep case at `actuation` [m]: `h_008.60nm.h5`.
pub fn sweep_case_name(actuation: f64) -> String {
    format!("h_{:06.2}nm.h5", actuation * 1e9)
}

/// Path of the 2-DOF sweep case at `actuation` [m] inside the instance's outputs.
pub fn sweep_case_file(actuation: f64) -> String {
    format!("{DIR}/{}", sweep_case_name(actuation))
}

/// Path of the 3-DOF case with interface label `label` (`isbl`, `mtl_reference`, …).
pub fn three_dof_case_file(label: &str) -> String {
    format!("{DIR}/{label}.h5")
}

/// Mean, standard deviation and extremes of one steady-window series, SI units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    #[serde(deserialize_with = "f64_or_nan")]
    pub mean: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub std: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub min: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub max: f64,
}

/// A non-finite number is written as JSON `null`; it reads back as NaN.
pub(crate) fn f64_or_nan<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// One 2-DOF case's result (`result.json` of its case-cache entry; docs/json.md), written and
/// read through this type: field names carry the SI unit; `None`/`null` where the case has
/// no contact or the quantity is undefined. The field order is the file's.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepCaseResult {
    pub actuation_m: f64,
    pub nominal_area_m2: f64,
    pub contact_damping_N_s_per_m: f64,
    pub clearance_m: Stats,
    pub fh_m: Stats,
    #[serde(deserialize_with = "f64_or_nan")]
    pub hms_mean_m: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub vibration_percent: f64,
    pub vibration_extrema_percent: Option<f64>,
    /// `FHM` or `BV` (explicit names, not Rust debug forms; docs/json.md).
    pub vibration_kind: String,
    #[serde(deserialize_with = "f64_or_nan")]
    pub percent_solid_contact: f64,
    pub regime: String,
    pub contact_force_N: Option<Stats>,
    pub friction_N: Option<Stats>,
    pub real_area_m2: Option<Stats>,
    pub adhesion_N: Option<Stats>,
    /// Headline ratio of means, the mean of the instantaneous ratio beside it
    /// (docs/conventions.md); `_ratio_of_means` is kept as an alias of the headline.
    pub friction_coefficient: Option<f64>,
    pub friction_coefficient_ratio_of_means: Option<f64>,
    pub friction_coefficient_mean_inst: Option<f64>,
    pub mean_pressure_Pa: Option<f64>,
    pub mean_pressure_Pa_mean_inst: Option<f64>,
    pub shear_traction_Pa: Option<f64>,
    pub shear_traction_Pa_mean_inst: Option<f64>,
    pub clipped_samples: u64,
    pub steps: u64,
    pub rejected_steps: u64,
    pub rhs_evaluations: u64,
    // No wall time: results are byte-identical for identical inputs; timings are in the store
    // entry's manifest.json and the run log (docs/architecture.md).
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_the_published_ones() {
        assert_eq!(sweep_case_file(8.6e-9), "cases/h_008.60nm.h5");
        assert_eq!(sweep_case_file(12e-9), "cases/h_012.00nm.h5");
        assert_eq!(three_dof_case_file("isbl"), "cases/isbl.h5");
    }
}
