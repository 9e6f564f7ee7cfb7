//! The 2-DOF sweep stage's `result.json` (`[simulate.NAME]`; docs/simulation.md): the sweep
//! analysis of its first branch, every case with its metrics and HDF5 file, the case keys,
//! and with two continuation branches each branch and their hysteresis. Field order is the
//! file's key order.

use super::cases::SweepCaseResult;
use super::ordered::OrderedMap;
use serde::{Deserialize, Serialize};

/// The result of one `[simulate]` instance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimulateResult {
    /// The first (or only) branch's sweep.
    pub sweep: SimulateSweep,
    /// Every grid case of every branch, branch by branch.
    pub cases: Vec<SimulateCase>,
    /// Case-cache keys of the grid cases, in the order they ran.
    pub case_keys: Vec<String>,
    /// The `[calibrate]` instance whose knobs the model carries.
    pub calibration: Option<String>,
    pub calibrated_knobs: Vec<CalibratedKnob>,
    /// The sweep table's file name.
    pub table: String,
    /// Each branch by name (`up`, `down`), in the order they ran; only with branches.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branches: Option<Branches>,
    /// Where the up and down branches differ; only with two branches.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hysteresis: Option<HysteresisResult>,
}

/// Sweep metrics of one branch's grid cases (§8): touchdown, critical point, slopes A–D,
/// optimum and the regime of every case.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepSummary {
    /// First grid case in solid contact, m.
    pub touchdown_m: Option<f64>,
    pub critical_point: Option<CriticalPoint>,
    pub slope_A: Option<SlopeFit>,
    pub slope_B: Option<SlopeFit>,
    pub slope_C: Option<SlopeFit>,
    pub slope_D: Option<SlopeFit>,
    /// Optimum operating actuation, m.
    pub optimum_m: Option<f64>,
    pub regimes: Vec<CaseRegime>,
}

/// The first branch's sweep as `sweep` holds it: its metrics, its name, its touchdown by the
/// convention and, for a sweep stated in heater power (docs/bulge.md), the efficiency and the
/// touchdown power.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimulateSweep {
    #[serde(flatten)]
    pub metrics: SweepSummary,
    /// `up`, `down`, or `nominal`.
    pub branch: String,
    pub touchdown_convention: TouchdownConvention,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub efficiency_m_per_W: Option<f64>,
    /// Present (possibly null) exactly when the efficiency is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub touchdown_power_W: Option<Option<f64>>,
}

/// One branch under `branches`: its metrics and its touchdown by the convention.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BranchSweep {
    #[serde(flatten)]
    pub metrics: SweepSummary,
    pub touchdown_convention: TouchdownConvention,
}

/// The branches by name (`up`, `down`), in run order.
pub type Branches = OrderedMap<BranchSweep>;

/// Intersection of slopes A and B (§8).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CriticalPoint {
    pub actuation_m: f64,
    pub clearance_m: f64,
}

/// Least-squares line c̄ = slope·h_TFC + intercept of one segment and the actuations it fits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SlopeFit {
    /// dc̄/dh_TFC, m/m.
    pub slope: f64,
    pub intercept_m: f64,
    pub rms_residual_m: f64,
    pub actuations_m: Vec<f64>,
}

/// A grid case's operating regime (`regime_name`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseRegime {
    pub actuation_m: f64,
    pub regime: String,
}

/// The convention's touchdown of one branch (docs/conventions.md) and the cases it added.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TouchdownConvention {
    /// First actuation known to touch, m.
    pub actuation_m: Option<f64>,
    /// Largest actuation known to fly below it, m.
    pub last_flying_m: Option<f64>,
    pub resolution_m: f64,
    /// The grid's touchdown, m.
    pub grid_touchdown_m: Option<f64>,
    pub extra_cases: Vec<ExtraCase>,
}

/// A case the touchdown refinement ran beyond the grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExtraCase {
    pub actuation_m: f64,
    pub solid_contact_percent: f64,
    pub clearance_mean_m: f64,
    pub case_key: String,
}

/// One grid case: its actuation, branch, HDF5 file (inside the instance's outputs) and
/// metrics (the case's `result.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimulateCase {
    pub actuation_m: f64,
    pub branch: String,
    pub h5: String,
    pub metrics: SweepCaseResult,
}

/// A knob the calibration fitted, as the model applies it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibratedKnob {
    pub knob: String,
    pub value: f64,
}

/// Where the up and down branches' steady clearances differ, and whether their touchdowns
/// and critical points coincide.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HysteresisResult {
    pub tolerance_m: f64,
    pub from_m: Option<f64>,
    pub to_m: Option<f64>,
    pub max_difference_m: f64,
    pub max_difference_at_m: Option<f64>,
    pub differing_actuations_m: Vec<f64>,
    pub touchdown_coincides: bool,
    pub critical_point_coincides: bool,
}
