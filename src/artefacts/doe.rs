//! The DOE stage's `result.json` (`[doe.NAME]`; docs/doe.md): how many cases, the response
//! surface fits of every actuation level, the tables, and when it optimised the annealing's
//! optimum and Table 2.8. Field order is the file's key order.

use serde::{Deserialize, Serialize};

/// The result of one `[doe]` instance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DoeResult {
    /// Design cases run (every coded point at every actuation level).
    pub cases: usize,
    pub fits: Vec<LevelFitSummary>,
    /// The table names the stage may write.
    pub tables: Vec<String>,
    /// The fitted (measured) bulge, Table 2.8's initial design, m; only with a fitted bulge.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_design_m: Option<DesignM>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimum: Option<DoeOptimum>,
    /// Table 2.8's rows; only when the designs were compared.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub comparison: Option<Vec<ComparisonRow>>,
    /// Every case this instance used (design, annealing, sensitivity, comparison), sorted.
    pub case_keys: Vec<String>,
}

/// A bulge design, m.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DesignM {
    pub a_tfc: f64,
    pub w_tfc: f64,
    pub x_tfc: f64,
}

/// The response surfaces of one actuation level and the degree selected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LevelFitSummary {
    pub actuation_m: f64,
    pub fixed_factor: String,
    pub degree_4: SurfaceFitSummary,
    pub degree_5: Option<SurfaceFitSummary>,
    pub degree_5_vs_4: DegreeTest,
    pub selected_degree: u32,
}

/// Goodness of one polynomial fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurfaceFitSummary {
    pub terms: usize,
    pub residual_df: usize,
    pub rss: f64,
    pub r_squared: f64,
    pub adj_r_squared: f64,
    pub sigma: f64,
}

/// The F test of degree 5 against degree 4 (null when not defined).
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DegreeTest {
    pub F: Option<f64>,
    pub p: Option<f64>,
}

/// The annealing's optimum and the sensitivity around it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DoeOptimum {
    pub a_m: f64,
    pub w_m: f64,
    pub x_m: f64,
    pub xi: f64,
    /// `simulation` or `surrogate`.
    pub objective: String,
    pub evaluations: usize,
    pub reanneals: usize,
    /// `converged (stalled)` or `evaluation budget`.
    pub stop: String,
    /// Largest |Δξ| one sensitivity step from the optimum, per factor.
    pub sensitivity_one_step: DesignSpread,
    pub most_sensitive: Option<String>,
}

/// A value per design factor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DesignSpread {
    pub a_tfc: f64,
    pub w_tfc: f64,
    pub x_tfc: f64,
}

/// One condition of Table 2.8 for one design (table values: seven significant digits, null
/// when not finite or not reached).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ComparisonRow {
    /// `initial` or `optimised`.
    pub design: String,
    pub a_um: Option<f64>,
    pub w_um: Option<f64>,
    pub x_um: Option<f64>,
    /// `critical actuation`, `optimum actuation`, `touchdown` or `steady contact`.
    pub condition: String,
    /// The convention's touchdown, on the touchdown row only.
    pub touchdown_refined_nm: Option<f64>,
    pub h_tfc_nm: Option<f64>,
    pub clearance_nm: Option<f64>,
    pub hms_nm: Option<f64>,
    pub fhm_or_bv_percent: Option<f64>,
}
