//! Design-of-experiments stage (dissertation §2.3; docs/doe.md): a 3³ full factorial in the
//! bulge geometry (`a_TFC`, `w_TFC`, `x_TFC`) crossed with actuation levels, every point a cached
//! improved-2-DOF case (the `[simulate]` stage's own case cache, so a killed run loses no
//! finished case); polynomial response surfaces of the flyability parameter ξ with ANOVA and
//! residual diagnostics per level; Table 2.7's predictive equations; simulated annealing on ξ
//! with a sensitivity check; and Table 2.8, the 2-DOF sweep on the initial and optimised designs.

use super::case_engine::{CaseEngine, Listing, PreparedCases, SweepCases, UpstreamEntries};
use super::{FromConfig, StageContext, StageKind, StageOutput};
use crate::contact::isbl::IsblModel;
use crate::contact::lookup::IsblLookup;
use crate::core::cache::Store;
use crate::core::cases::CaseEntry;
use crate::core::config::{ConfigError, PipelineFile};
use crate::dynamics::metrics::{flyability, Regime};
use crate::error::{Error, Result};
use crate::numerics::annealing::{
    sensitivity_points, Annealer, AnnealingOptions, AnnealingRecord, StopReason,
};
use crate::numerics::regression::{
    coded, decoded, full_factorial, FitOptions, Polynomial, PolynomialBasis, ResponseSurface,
};
use crate::slider::calibration::base_inputs;
use crate::slider::case::SweepCaseResult;
use crate::slider::doe_design::{self, design_cases, design_params};
use crate::slider::params::{uncalibrated_base, SimulateParams};
use crate::slider::sweep::{sweep_analysis, CaseOutcome, PreparedSweep, SweepCase};
use crate::units::Length;
use rayon::prelude::*;
use serde::Deserialize;
use serde_json::{json, Map, Value};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// Bump when the numbers the stage derives from its cases change (the cases themselves carry
/// the simulate stage's model version).
/// doe-3: annealing settings and objective as plain JSON in the key (same numbers).
pub const MODEL_VERSION: &str = "doe-3";

const UM: f64 = 1e-6;
/// Highest actuation a DOE case may use [m] (see `check`).
const DOE_MAX_ACTUATION: f64 = 20e-9;
const NM: f64 = 1e-9;
/// Factor names, in the coded order `x1 = a_TFC`, `x2 = w_TFC`, `x3 = x_TFC` (so `b_1122`
/// multiplies `a² w²`, as the dissertation numbers them).
pub const FACTORS: [&str; 3] = ["a_tfc", "w_tfc", "x_tfc"];

fn um3(a: f64, b: f64, c: f64) -> [Length; 3] {
    [Length(a * UM), Length(b * UM), Length(c * UM)]
}
fn default_a() -> [Length; 3] {
    um3(1.0, 3.0, 5.0)
}
fn default_w() -> [Length; 3] {
    um3(10.0, 50.0, 90.0)
}
fn default_x() -> [Length; 3] {
    um3(5.0, 8.0, 11.0)
}
fn default_actuations() -> Vec<Length> {
    [5.0, 9.0, 12.0, 15.0].map(|h| Length(h * NM)).to_vec()
}
fn default_true() -> bool {
    true
}
fn default_sa_actuation() -> Length {
    Length(9.7 * NM)
}
fn default_sa_start() -> [Length; 3] {
    um3(3.0, 10.0, 5.0)
}
fn default_objective() -> String {
    "simulation".into()
}
fn default_seed() -> u64 {
    1
}
fn default_sa_evaluations() -> usize {
    400
}
fn default_temperature() -> f64 {
    100.0
}
fn default_reanneal() -> usize {
    100
}
fn default_sensitivity_step() -> Length {
    Length(50.0 * NM)
}
fn default_sensitivity_steps() -> u16 {
    3
}
fn default_compare_step() -> Length {
    Length(0.2 * NM)
}

/// `[doe.NAME]` as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DoeConfig {
    /// The `[simulate.*]` instance whose model, contact set, DMW and case options every design
    /// point uses (its actuation list and geometry are replaced).
    pub simulate: String,
    /// Levels −1, 0, +1 of each factor.
    #[serde(default = "default_a")]
    pub a_tfc: [Length; 3],
    #[serde(default = "default_w")]
    pub w_tfc: [Length; 3],
    #[serde(default = "default_x")]
    pub x_tfc: [Length; 3],
    /// Actuation levels crossed with the design (5, 9, 12, 15 nm: §2.3's 16 nm top level lies
    /// beyond the 2-DOF model's 0–15 nm, where designs with x_TFC = 5 µm lose the air bearing).
    #[serde(default = "default_actuations")]
    pub actuations: Vec<Length>,
    /// Per actuation level, the factor held at −1/0/+1 in Table 2.7's predictive equations
    /// (default: `a_tfc` at the flying and the contacting level, `x_tfc` at 9 and 12 nm, as
    /// the dissertation chose).
    #[serde(default)]
    pub fixed_factors: Option<Vec<String>>,
    /// Run the simulated annealing, the sensitivity check and the Table 2.8 comparison.
    #[serde(default = "default_true")]
    pub optimise: bool,
    #[serde(default = "default_sa_actuation")]
    pub sa_actuation: Length,
    #[serde(default = "default_sa_start")]
    pub sa_start: [Length; 3],
    /// `simulation` (every evaluation a cached 2-DOF case) or `surrogate` (the response
    /// surfaces, linear in h_TFC between the levels around `sa_actuation`).
    #[serde(default = "default_objective")]
    pub sa_objective: String,
    #[serde(default = "default_seed")]
    pub sa_seed: u64,
    #[serde(default = "default_sa_evaluations")]
    pub sa_max_evaluations: usize,
    #[serde(default = "default_temperature")]
    pub sa_initial_temperature: f64,
    #[serde(default = "default_reanneal")]
    pub sa_reanneal_interval: usize,
    /// Iterations without improvement before stopping (default 500 × 3).
    #[serde(default)]
    pub sa_stall_iterations: Option<usize>,
    #[serde(default = "default_sensitivity_step")]
    pub sensitivity_step: Length,
    #[serde(default = "default_sensitivity_steps")]
    pub sensitivity_steps: u16,
    /// Table 2.8: sweep both designs over 0–15 nm.
    #[serde(default = "default_true")]
    pub compare: bool,
    #[serde(default = "default_compare_step")]
    pub compare_step: Length,
    /// `{ bulge = "NAME" }`: the `[bulge.NAME]` fit is the measured design — Table 2.8's
    /// "initial" design compared with the optimum (docs/doe.md). Default: the base
    /// `[simulate]` instance's geometry.
    #[serde(default)]
    pub geometry: Option<crate::slider::params::GeometryConfig>,
}

/// Where the annealing's ξ comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SaObjective {
    Simulation,
    Surrogate,
}

/// Validated settings (SI).
#[derive(Debug, Clone, PartialEq)]
pub struct DoeParams {
    pub base_name: String,
    pub base: SimulateParams,
    /// `levels[f]` = the −1/0/+1 values of factor f [m].
    pub levels: [[f64; 3]; 3],
    pub actuations: Vec<f64>,
    /// Factor index held fixed in Table 2.7, per actuation level.
    pub fixed: Vec<usize>,
    pub optimise: bool,
    pub sa_actuation: f64,
    pub sa_start: [f64; 3],
    pub sa_objective: SaObjective,
    pub sa: AnnealingOptions,
    pub sensitivity_step: f64,
    pub sensitivity_steps: u16,
    pub compare: bool,
    pub compare_actuations: Vec<f64>,
    /// The `[bulge.*]` instance whose fit replaces the base's bulge at run time (this
    /// instance's `geometry`, else the base's own).
    pub bulge: Option<String>,
}

impl DoeParams {
    fn canonical(&self) -> Value {
        let mut v = json!({
            "base": self.base.canonical(),
            "levels_m": self.levels,
            "actuations_m": self.actuations,
            "fixed": self.fixed,
            "optimise": self.optimise,
            "sa_actuation_m": self.sa_actuation,
            "sa_start_m": self.sa_start,
            "sa_objective": self.sa_objective,
            "sa": self.sa,
            "sensitivity_step_m": self.sensitivity_step,
            "sensitivity_steps": self.sensitivity_steps,
            "compare": self.compare,
            "compare_actuations_m": self.compare_actuations,
        });
        // Only a bulge of the DOE's own adds a key (the base's is in `base` already): the
        // other instances keep their keys.
        if let (Some(b), Some(obj)) = (&self.bulge, v.as_object_mut()) {
            if self.base.bulge.as_ref() != Some(b) {
                obj.insert("bulge".into(), json!(b));
            }
        }
        v
    }

    /// The 27 designs `[a, w, x]` [m] of the 3³ factorial, in `full_factorial` order.
    fn design_points(&self) -> Vec<[f64; 3]> {
        doe_design::design_points(&self.levels)
    }

    /// Physical design `[a, w, x]` of a coded point.
    fn decode(&self, c: &[f64]) -> [f64; 3] {
        doe_design::decode(&self.levels, c)
    }

    fn encode(&self, x: &[f64; 3]) -> [f64; 3] {
        std::array::from_fn(|f| coded(x[f], self.levels[f][0], self.levels[f][2]))
    }
}

fn bad<T>(
    key: &str,
    m: impl Into<String>,
) -> std::result::Result<T, crate::core::config::KeyError> {
    Err(crate::core::config::KeyError::new(key, m))
}

/// Check `[doe]` keys against the base instance; failures name the key.
pub fn check(
    cfg: &DoeConfig,
    base: SimulateParams,
    base_name: &str,
) -> std::result::Result<DoeParams, crate::core::config::KeyError> {
    let bulge = match &cfg.geometry {
        None => base.bulge.clone(),
        Some(crate::slider::params::GeometryConfig::Bulge { bulge }) => Some(bulge.clone()),
        Some(crate::slider::params::GeometryConfig::Named(n)) => {
            return bad(
                "geometry",
                format!(
                    "`{n}`: only {{ bulge = \"NAME\" }} (a named geometry comes from the [simulate] base)"
                ),
            )
        }
    };
    let levels = [cfg.a_tfc, cfg.w_tfc, cfg.x_tfc].map(|l| l.map(|v| v.0));
    for (f, l) in levels.iter().enumerate() {
        if !(l.iter().all(|v| v.is_finite() && *v > 0.0) && l[0] < l[1] && l[1] < l[2]) {
            return bad(FACTORS[f], "three positive, increasing levels (−1, 0, +1)");
        }
        // The DOE codes the middle level as 0: it must be the midpoint.
        let mid = 0.5 * (l[0] + l[2]);
        if (l[1] - mid).abs() > 1e-9 * mid {
            return bad(
                FACTORS[f],
                format!(
                    "the middle level must be the midpoint ({:.4} um) for coded levels −1, 0, +1",
                    mid / UM
                ),
            );
        }
    }
    if levels[0][2] > levels[2][0] {
        return bad(
            "a_tfc",
            "the largest a_tfc exceeds the smallest x_tfc: that bulge would overhang the trailing edge",
        );
    }
    // The 2-DOF range is 0–15 nm [seed §2.1.1], but §2.3's fully contacting level is 16 nm:
    // DOE cases may run up to 20 nm, extrapolating the rear-stiffening law (docs/doe.md).
    let max_h = base.model.max_actuation.max(DOE_MAX_ACTUATION);
    let in_range = |h: f64| h.is_finite() && (0.0..=max_h).contains(&h);
    if cfg.actuations.is_empty() || !cfg.actuations.iter().all(|h| in_range(h.0)) {
        return bad(
            "actuations",
            format!("one or more actuations within 0–{:.1} nm", max_h / NM),
        );
    }
    let actuations: Vec<f64> = cfg.actuations.iter().map(|h| h.0).collect();
    if actuations.windows(2).any(|w| w[1] <= w[0]) {
        return bad("actuations", "increasing, without repeats");
    }
    let fixed = match &cfg.fixed_factors {
        Some(list) => {
            if list.len() != actuations.len() {
                return bad(
                    "fixed_factors",
                    format!("one factor per actuation level ({})", actuations.len()),
                );
            }
            list.iter()
                .map(|n| {
                    FACTORS.iter().position(|f| f == n).ok_or_else(|| {
                        crate::core::config::KeyError::new(
                            "fixed_factors",
                            format!("unknown factor `{n}` ({})", FACTORS.join(", ")),
                        )
                    })
                })
                .collect::<std::result::Result<Vec<_>, _>>()?
        }
        // §2.3.2: a_TFC fixed at the flying (5) and contacting (16 nm) levels, x_TFC in between.
        None => actuations
            .iter()
            .map(|h| {
                if (7.0 * NM..14.0 * NM).contains(h) {
                    2
                } else {
                    0
                }
            })
            .collect(),
    };
    let sa_objective = match cfg.sa_objective.as_str() {
        "simulation" => SaObjective::Simulation,
        "surrogate" => SaObjective::Surrogate,
        o => {
            return bad(
                "sa_objective",
                format!("unknown `{o}` (simulation, surrogate)"),
            )
        }
    };
    let sa_actuation = cfg.sa_actuation.0;
    if !in_range(sa_actuation) {
        return bad("sa_actuation", format!("within 0–{:.1} nm", max_h / NM));
    }
    if sa_objective == SaObjective::Surrogate
        && !(actuations[0] <= sa_actuation && sa_actuation <= actuations[actuations.len() - 1])
    {
        return bad(
            "sa_actuation",
            "the surrogate interpolates between the DOE's actuation levels: stay within them",
        );
    }
    let sa_start = cfg.sa_start.map(|v| v.0);
    for f in 0..3 {
        if !(levels[f][0] <= sa_start[f] && sa_start[f] <= levels[f][2]) {
            return bad(
                "sa_start",
                format!("{} must lie within the design box", FACTORS[f]),
            );
        }
    }
    if cfg.sa_max_evaluations == 0 || cfg.sa_max_evaluations > 1_000_000 {
        return bad("sa_max_evaluations", "1 to 1 000 000");
    }
    if !(cfg.sa_initial_temperature.is_finite() && cfg.sa_initial_temperature > 0.0) {
        return bad("sa_initial_temperature", "positive");
    }
    if cfg.sa_reanneal_interval == 0 {
        return bad("sa_reanneal_interval", "at least 1");
    }
    let sensitivity_step = cfg.sensitivity_step.0;
    if !(sensitivity_step.is_finite() && sensitivity_step > 0.0) {
        return bad("sensitivity_step", "positive");
    }
    if cfg.sensitivity_steps > 20 {
        return bad("sensitivity_steps", "at most 20");
    }
    let step = cfg.compare_step.0;
    if !(0.01 * NM..=5.0 * NM).contains(&step) {
        return bad("compare_step", "0.01–5 nm");
    }
    // The `[simulate]` grid formula (picometre-rounded), so the initial design's sweep is the
    // base instance's own cached cases when the steps agree.
    let sweep_max = base.model.max_actuation;
    let n = (sweep_max / step + 1e-9).floor() as usize;
    let compare_actuations = (0..=n)
        .map(|k| ((k as f64 * step) * 1e12).round() / 1e12)
        .collect();
    Ok(DoeParams {
        base_name: base_name.to_string(),
        base,
        levels,
        actuations,
        fixed,
        optimise: cfg.optimise,
        sa_actuation,
        sa_start,
        sa_objective,
        sa: AnnealingOptions {
            initial_temperature: cfg.sa_initial_temperature,
            reanneal_interval: cfg.sa_reanneal_interval,
            stall_iterations: cfg.sa_stall_iterations,
            max_evaluations: Some(cfg.sa_max_evaluations),
            seed: cfg.sa_seed,
            ..AnnealingOptions::default()
        },
        sensitivity_step,
        sensitivity_steps: cfg.sensitivity_steps,
        compare: cfg.compare,
        compare_actuations,
        bulge,
    })
}

/// Runs one 2-DOF case of a given bulge through the 2-DOF case cache (`slider::case`).
struct CaseRunner<'a> {
    base: &'a SimulateParams,
    /// The base sweep prepared once (`DoeStage::prepare`): it computes every design case, as
    /// a Slurm worker's does.
    sweep: &'a PreparedSweep,
    store: &'a Store,
}

/// One finished case of a design: its metrics and ξ.
#[derive(Debug, Clone)]
struct DesignCase {
    design: [f64; 3],
    actuation: f64,
    entry: CaseEntry,
    result: SweepCaseResult,
    xi: f64,
}

impl CaseRunner<'_> {
    fn params_for(&self, design: &[f64; 3]) -> Result<SimulateParams> {
        design_params(self.base, design, 0.0)
    }

    fn run(&self, design: [f64; 3], actuation: f64) -> Result<DesignCase> {
        let p = design_params(self.base, &design, actuation)?;
        let case = SweepCase {
            actuation_m: actuation,
            design_m: Some(design),
            static_start: None,
        };
        let entry = self
            .sweep
            .cached(self.store, &case)
            .map_err(|e| Error::DoeCase {
                design,
                actuation,
                source: Box::new(e),
            })?;
        let result = SweepCaseResult::from_json(&entry.result)?;
        let xi = xi_of(&result, p.model.nominal_flying_height);
        Ok(DesignCase {
            design,
            actuation,
            entry,
            result,
            xi,
        })
    }
}

/// ξ of a case result (§9): steady mean clearance over FH_nom times FHM/BV in units of 100 %.
fn xi_of(result: &SweepCaseResult, fh_nom: f64) -> f64 {
    flyability(result.clearance_m.mean, fh_nom, result.vibration_percent)
}

/// The annealing objective of §9: ξ when positive, else `1 + |ξ|` (never preferred).
fn annealing_objective(xi: f64) -> f64 {
    if xi > 0.0 {
        xi
    } else {
        1.0 + xi.abs()
    }
}

/// The response surfaces of one actuation level: the spec's degree-4 model and the degree-5
/// model kept for the residual comparison.
struct LevelFit {
    actuation: f64,
    fixed: usize,
    quartic: ResponseSurface,
    quintic: Option<ResponseSurface>,
}

fn fit_level(actuation: f64, fixed: usize, points: &[Vec<f64>], xi: &[f64]) -> Result<LevelFit> {
    let opts = FitOptions::default();
    let fit = |degree: u32| {
        ResponseSurface::fit(&PolynomialBasis::bounded(3, 2, degree), points, xi, &opts)
    };
    let quartic = fit(4).map_err(|source| Error::ResponseSurface { actuation, source })?;
    Ok(LevelFit {
        actuation,
        fixed,
        quartic,
        // A 3³ design leaves one residual df to the 26-term model; keep it if it fits.
        quintic: fit(5).ok(),
    })
}

/// The surrogate ξ at any actuation: the level fits, linear in h between neighbours.
fn surrogate_xi(fits: &[LevelFit], h: f64, coded_point: &[f64]) -> f64 {
    let k = fits
        .windows(2)
        .position(|w| w[0].actuation <= h && h <= w[1].actuation);
    match k {
        Some(k) => {
            let (lo, hi) = (&fits[k], &fits[k + 1]);
            let t = (h - lo.actuation) / (hi.actuation - lo.actuation);
            (1.0 - t) * lo.quartic.predict(coded_point) + t * hi.quartic.predict(coded_point)
        }
        None => fits
            .iter()
            .min_by(|a, b| (a.actuation - h).abs().total_cmp(&(b.actuation - h).abs()))
            .map_or(f64::NAN, |f| f.quartic.predict(coded_point)),
    }
}

/// A table value: seven significant digits, null when not finite.
fn table_value(v: f64) -> Value {
    if v.is_finite() {
        json!(crate::core::store::round_significant(v, 7))
    } else {
        Value::Null
    }
}

/// The design table: one row per case, level by level.
fn design_rows(
    coded_points: &[Vec<f64>],
    per_level: usize,
    cases: &[DesignCase],
) -> Vec<Map<String, Value>> {
    let mut rows = Vec::new();
    for (i, c) in cases.iter().enumerate() {
        let coded_point = &coded_points[i % per_level];
        let mut row = Map::new();
        row.insert("run".into(), json!(i + 1));
        for f in 0..3 {
            row.insert(format!("{}_coded", FACTORS[f]), json!(coded_point[f]));
        }
        row.insert("a_um".into(), table_value(c.design[0] / UM));
        row.insert("w_um".into(), table_value(c.design[1] / UM));
        row.insert("x_um".into(), table_value(c.design[2] / UM));
        row.insert("actuation_nm".into(), table_value(c.actuation / NM));
        let m = &c.entry.result;
        row.insert(
            "clearance_nm".into(),
            m["clearance_m"]["mean"]
                .as_f64()
                .map_or(Value::Null, |v| table_value(v / NM)),
        );
        row.insert(
            "fhm_or_bv_percent".into(),
            m["vibration_percent"]
                .as_f64()
                .map_or(Value::Null, table_value),
        );
        row.insert(
            "regime".into(),
            crate::slider::sweep::regime_label(&m["regime"]),
        );
        row.insert("xi".into(), table_value(c.xi));
        row.insert("case_key".into(), json!(c.entry.key));
        rows.push(row);
    }
    rows
}

/// The annealing table: one row per evaluation, with its ξ.
fn annealing_rows(
    p: &DoeParams,
    history: &[AnnealingRecord],
    xis: &[f64],
) -> Vec<Map<String, Value>> {
    let mut rows = Vec::new();
    for (r, xi) in history.iter().zip(xis) {
        let d = p.decode(&r.candidate);
        let mut m = Map::new();
        m.insert("iteration".into(), json!(r.iteration));
        m.insert("temperature".into(), table_value(r.temperature));
        m.insert("a_um".into(), table_value(d[0] / UM));
        m.insert("w_um".into(), table_value(d[1] / UM));
        m.insert("x_um".into(), table_value(d[2] / UM));
        m.insert("xi".into(), table_value(*xi));
        m.insert("candidate_j".into(), table_value(r.candidate_j));
        m.insert("accepted".into(), json!(r.accepted));
        m.insert("current_j".into(), table_value(r.current_j));
        m.insert("best_j".into(), table_value(r.best_j));
        rows.push(m);
    }
    rows
}

/// Table 2.7 coefficient names of a two-factor reduced polynomial, in output order.
const PREDICTIVE_TERMS: [&str; 9] = [
    "b0", "b1", "b2", "b11", "b22", "b12", "b112", "b122", "b1122",
];

fn predictive_rows(p: &DoeParams, fits: &[LevelFit]) -> Result<Vec<Map<String, Value>>> {
    let mut rows = Vec::new();
    for lf in fits {
        let poly: Polynomial = lf.quartic.polynomial();
        for level in [-1.0, 0.0, 1.0] {
            let reduced = poly
                .fix_factor(lf.fixed, level)
                .map_err(Error::PredictiveEquation)?;
            let free: Vec<&str> = (0..3)
                .filter(|f| *f != lf.fixed)
                .map(|f| FACTORS[f])
                .collect();
            let mut row = Map::new();
            row.insert("actuation_nm".into(), table_value(lf.actuation / NM));
            row.insert("fixed_factor".into(), json!(FACTORS[lf.fixed]));
            row.insert("fixed_coded".into(), json!(level));
            row.insert(
                "fixed_value_um".into(),
                table_value(decoded(level, p.levels[lf.fixed][0], p.levels[lf.fixed][2]) / UM),
            );
            row.insert("x1".into(), json!(free[0]));
            row.insert("x2".into(), json!(free[1]));
            for name in PREDICTIVE_TERMS {
                row.insert(
                    name.into(),
                    table_value(reduced.coefficient(name).unwrap_or(0.0)),
                );
            }
            row.insert(
                "residual_error".into(),
                table_value(lf.quartic.residual_ss_at(lf.fixed, level, 1e-9)),
            );
            rows.push(row);
        }
    }
    Ok(rows)
}

fn coefficient_rows(fits: &[LevelFit]) -> Vec<Map<String, Value>> {
    let mut rows = Vec::new();
    for lf in fits {
        for (model, s) in [
            ("degree 4", Some(&lf.quartic)),
            ("degree 5", lf.quintic.as_ref()),
        ] {
            let Some(s) = s else { continue };
            for (j, name) in s.basis.names().iter().enumerate() {
                let mut row = Map::new();
                row.insert("actuation_nm".into(), table_value(lf.actuation / NM));
                row.insert("model".into(), json!(model));
                row.insert("term".into(), json!(name));
                row.insert("coefficient".into(), table_value(s.fit.coefficients[j]));
                row.insert("std_error".into(), table_value(s.fit.standard_errors[j]));
                row.insert("t".into(), table_value(s.fit.t_values[j]));
                row.insert("p".into(), table_value(s.fit.p_values[j]));
                rows.push(row);
            }
        }
    }
    rows
}

fn anova_rows(fits: &[LevelFit]) -> Vec<Map<String, Value>> {
    let mut rows = Vec::new();
    for lf in fits {
        let t = lf.quartic.anova();
        let all = t.terms.iter().chain([&t.model, &t.residual, &t.total]);
        for r in all {
            let mut row = Map::new();
            row.insert("actuation_nm".into(), table_value(lf.actuation / NM));
            row.insert("source".into(), json!(r.source));
            row.insert("df".into(), json!(r.df));
            row.insert("sum_sq".into(), table_value(r.sum_sq));
            row.insert("mean_sq".into(), table_value(r.mean_sq));
            row.insert("F".into(), r.f.map_or(Value::Null, table_value));
            row.insert("p".into(), r.p.map_or(Value::Null, table_value));
            rows.push(row);
        }
    }
    rows
}

fn fit_summary(lf: &LevelFit) -> Value {
    let one = |s: &ResponseSurface| {
        json!({
            "terms": s.basis.len(),
            "residual_df": s.fit.residual_df,
            "rss": s.fit.rss,
            "r_squared": s.fit.r_squared,
            "adj_r_squared": s.fit.adj_r_squared,
            "sigma": s.fit.sigma,
        })
    };
    let (f, p, selected) = model_selection(lf);
    json!({
        "actuation_m": lf.actuation,
        "fixed_factor": FACTORS[lf.fixed],
        "degree_4": one(&lf.quartic),
        "degree_5": lf.quintic.as_ref().map(one),
        "degree_5_vs_4": {"F": f, "p": p},
        "selected_degree": selected,
    })
}

/// Does the degree-5 model explain significantly more than the degree-4 one? The
/// extra-sum-of-squares F test of the nested models (3 added terms against the larger model's
/// residual), at 5 %: the dissertation kept degree 4 where the added terms were not needed.
fn model_selection(lf: &LevelFit) -> (Option<f64>, Option<f64>, u32) {
    let Some(q) = &lf.quintic else {
        return (None, None, 4);
    };
    let (r4, r5) = (&lf.quartic.fit, &q.fit);
    let added = r5.parameters.saturating_sub(r4.parameters);
    if added == 0 || r5.residual_df == 0 || r5.rss <= 0.0 {
        return (None, None, 4);
    }
    let f = ((r4.rss - r5.rss) / added as f64) / (r5.rss / r5.residual_df as f64);
    let p = crate::numerics::special::f_sf(f, added as f64, r5.residual_df as f64);
    (Some(f), Some(p), if p < 0.05 { 5 } else { 4 })
}

/// Touchdown of a design's Table 2.8 sweep by the convention (docs/conventions.md,
/// `dynamics::touchdown`): the sweep's grid is the scan, the first crossing refined to 0.02 nm
/// with extra cached cases (not with `refine_touchdown = false` on the base sweep).
fn refined_touchdown(
    runner: &CaseRunner,
    design: [f64; 3],
    cases: &[CaseOutcome],
) -> Result<Option<f64>> {
    use crate::dynamics::touchdown::{find_touchdown, TouchdownSearch};
    let known: Vec<(f64, bool)> = cases
        .iter()
        .map(|c| (c.actuation, c.metrics.touches()))
        .collect();
    let (Some(first), Some(last)) = (cases.first(), cases.last()) else {
        return Ok(None);
    };
    let step = cases
        .windows(2)
        .map(|w| w[1].actuation - w[0].actuation)
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !step.is_finite() || !runner.base.refine_touchdown {
        // One case, or no refinement asked: the grid's first touching case.
        return Ok(known.iter().find(|k| k.1).map(|k| k.0));
    }
    let search = TouchdownSearch {
        start: first.actuation,
        ..TouchdownSearch::convention(last.actuation, step, 3)
    };
    let td = find_touchdown(&search, &known, |acts: &[f64]| -> Result<Vec<bool>> {
        let runs: Vec<Result<DesignCase>> =
            acts.par_iter().map(|&a| runner.run(design, a)).collect();
        runs.into_iter()
            .map(|r| r.map(|c| c.result.touches()))
            .collect()
    })?;
    Ok(td.actuation)
}

/// One condition of Table 2.8 for a design; `touchdown_refined` (the convention's) goes into
/// the touchdown row beside the grid case it describes.
fn comparison_rows(
    label: &str,
    design: &[f64; 3],
    sp: &SimulateParams,
    cases: &[CaseOutcome],
    touchdown_refined: Option<f64>,
) -> Result<Vec<Map<String, Value>>> {
    let sweep = sweep_analysis(sp, cases)?;
    let nearest = |h: f64| {
        cases
            .iter()
            .enumerate()
            .min_by(|a, b| {
                (a.1.actuation - h)
                    .abs()
                    .total_cmp(&(b.1.actuation - h).abs())
            })
            .map(|(i, _)| i)
    };
    let critical = sweep
        .slopes
        .critical_point
        .as_ref()
        .and_then(|c| nearest(c.actuation_m));
    let steady = sweep
        .touchdown_index
        .and_then(|td| (td..cases.len()).find(|&i| sweep.regimes[i] == Regime::SolidContact));
    let mut rows = Vec::new();
    for (condition, idx) in [
        ("critical actuation", critical),
        ("optimum actuation", sweep.optimum_index),
        ("touchdown", sweep.touchdown_index),
        ("steady contact", steady),
    ] {
        let mut row = Map::new();
        row.insert("design".into(), json!(label));
        row.insert("a_um".into(), table_value(design[0] / UM));
        row.insert("w_um".into(), table_value(design[1] / UM));
        row.insert("x_um".into(), table_value(design[2] / UM));
        row.insert("condition".into(), json!(condition));
        row.insert(
            "touchdown_refined_nm".into(),
            match (condition, touchdown_refined) {
                ("touchdown", Some(t)) => table_value(t / NM),
                _ => Value::Null,
            },
        );
        let m = idx.map(|i| (&cases[i].metrics, cases[i].actuation));
        // As the case's result.json has it: a non-finite value is null there.
        let get = |of: fn(&SweepCaseResult) -> f64| {
            m.and_then(|(m, _)| Some(of(m)).filter(|v| v.is_finite()))
        };
        row.insert(
            "h_tfc_nm".into(),
            m.map_or(Value::Null, |(_, h)| table_value(h / NM)),
        );
        row.insert(
            "clearance_nm".into(),
            get(|m| m.clearance_m.mean).map_or(Value::Null, |v| table_value(v / NM)),
        );
        row.insert(
            "hms_nm".into(),
            get(|m| m.hms_mean_m).map_or(Value::Null, |v| table_value(v / NM)),
        );
        row.insert(
            "fhm_or_bv_percent".into(),
            get(|m| m.vibration_percent).map_or(Value::Null, table_value),
        );
        rows.push(row);
    }
    Ok(rows)
}

// ---- Figures: these helpers only assemble data for `crate::figures` ----

/// Contour panels of one level: ξ over the two free factors at the fixed one's three levels.
fn contour_png(path: &Path, p: &DoeParams, lf: &LevelFit, points: &[[f64; 3]]) -> Result<()> {
    use crate::figures::{contour_panels_png, ContourPanel};
    const N: usize = 41;
    let free: Vec<usize> = (0..3).filter(|f| *f != lf.fixed).collect();
    let (fx, fy) = (free[0], free[1]);
    let grid = |f: usize| -> Vec<f64> {
        (0..N)
            .map(|i| {
                decoded(
                    -1.0 + 2.0 * i as f64 / (N - 1) as f64,
                    p.levels[f][0],
                    p.levels[f][2],
                ) / UM
            })
            .collect()
    };
    let poly = lf.quartic.polynomial();
    let desc = |f: usize| format!("{} (µm)", FACTORS[f].replace("_tfc", "_TFC"));
    let (xd, yd) = (desc(fx), desc(fy));
    let titles: Vec<String> = [-1.0, 0.0, 1.0]
        .iter()
        .map(|&level| {
            format!(
                "{} = {:.3} µm",
                FACTORS[lf.fixed].replace("_tfc", "_TFC"),
                decoded(level, p.levels[lf.fixed][0], p.levels[lf.fixed][2]) / UM
            )
        })
        .collect();
    let panels: Vec<ContourPanel> = [-1.0, 0.0, 1.0]
        .iter()
        .zip(&titles)
        .map(|(&level, title)| {
            let z = ndarray::Array2::from_shape_fn((N, N), |(iy, ix)| {
                let mut c = [0.0; 3];
                c[lf.fixed] = level;
                c[fx] = -1.0 + 2.0 * ix as f64 / (N - 1) as f64;
                c[fy] = -1.0 + 2.0 * iy as f64 / (N - 1) as f64;
                poly.eval(&c)
            });
            let fixed_value = decoded(level, p.levels[lf.fixed][0], p.levels[lf.fixed][2]);
            ContourPanel {
                title,
                x_desc: &xd,
                y_desc: &yd,
                x: grid(fx),
                y: grid(fy),
                z,
                points: points
                    .iter()
                    .filter(|d| (d[lf.fixed] - fixed_value).abs() < 1e-12)
                    .map(|d| (d[fx] / UM, d[fy] / UM))
                    .collect(),
                marker: None,
            }
        })
        .collect();
    contour_panels_png(
        path,
        &format!(
            "Flyability ξ (degree-4 response surface), h_TFC = {:.1} nm (Figs 2.26–2.29)",
            lf.actuation / NM
        ),
        "ξ",
        &panels,
    )?;
    Ok(())
}

/// Residual diagnostics of one level's degree-4 surface.
fn residuals_png(path: &Path, lf: &LevelFit) -> Result<()> {
    let diag = lf.quartic.fit.residual_diagnostics();
    crate::figures::residual_panels_png(
        path,
        &format!(
            "Residuals of the degree-4 ξ surface, h_TFC = {:.1} nm",
            lf.actuation / NM
        ),
        &diag.fitted_residual,
        &diag.normal_probability,
    )?;
    Ok(())
}

/// The annealing's convergence: current and best J per iteration, with the temperature.
fn annealing_convergence_png(
    path: &Path,
    p: &DoeParams,
    history: &[AnnealingRecord],
) -> Result<()> {
    let curve: Vec<(f64, f64, f64)> = history
        .iter()
        .map(|r| (r.iteration as f64, r.current_j, r.best_j))
        .collect();
    let temps: Vec<f64> = history.iter().map(|r| r.temperature).collect();
    crate::figures::annealing_png(
        path,
        &format!(
            "Simulated annealing of ξ at h_TFC = {:.1} nm (Fig. 2.30)",
            p.sa_actuation / NM
        ),
        &curve,
        Some(&temps),
    )?;
    Ok(())
}

/// Steady clearance over actuation of the initial and the optimised design (Table 2.8).
fn comparison_png(path: &Path, p: &DoeParams, sweeps: &[DesignSweep]) -> Result<()> {
    let t0 = 0.5 * p.base.model.interface.lubricant_thickness / NM;
    let sweep_series: Vec<crate::figures::SweepSeries> = sweeps
        .iter()
        .map(|s| crate::figures::SweepSeries {
            label: s.label,
            points: s
                .outcomes
                .iter()
                .map(|c| {
                    (
                        c.actuation / NM,
                        c.metrics.clearance_m.mean / NM,
                        c.metrics.clearance_m.std / NM,
                    )
                })
                .collect(),
        })
        .collect();
    crate::figures::clearance_sweep_png(
        path,
        "Initial vs optimised design: steady clearance (Table 2.8)",
        "TFC actuation (nm)",
        "clearance (nm)",
        &sweep_series,
        &[],
        &[(0.0, "solid contact"), (t0, "T0"), (2.0 * t0, "2T0")],
    )?;
    Ok(())
}

/// Validated stage instance.
pub struct DoeStage {
    pub name: String,
    pub params: DoeParams,
}

impl FromConfig for DoeStage {
    type Config = DoeConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &DoeConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let err = |k: &str, m: String| file.error("doe", name, k, m);
        let base = uncalibrated_base(file, "doe", name, &cfg.simulate)?;
        let params = check(cfg, base, &cfg.simulate).map_err(|e| err(&e.key, e.message))?;
        if let Some(b) = &params.bulge {
            if !file.has_instance("bulge", b) {
                return Err(err("geometry", format!("no [bulge.{b}] in this file")));
            }
        }
        Ok(DoeStage {
            name: name.to_string(),
            params,
        })
    }
}

impl StageKind for DoeStage {
    const KIND: &'static str = "doe";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    const CASE_KIND: Option<&'static str> = Some(DOE_CASE);
    fn case_engine(&self) -> Option<&dyn CaseEngine> {
        Some(self)
    }

    fn params(&self) -> Value {
        self.params.canonical()
    }
    fn upstream(&self) -> Vec<String> {
        // The base is uncalibrated: its contact and DMW instances (and its bulge).
        let mut u = self.params.base.upstream();
        if let Some(b) = &self.params.bulge {
            if !u.contains(b) {
                u.push(b.clone());
            }
        }
        u
    }
    fn run(&self, ctx: &StageContext) -> Result<StageOutput> {
        ctx.progress.set_message("interface table");
        let (p, sweep) = self.prepare(&ctx.upstream_entries())?;
        let p = &p;
        let runner = CaseRunner {
            base: &p.base,
            sweep: &sweep,
            store: ctx.store,
        };
        // Annealing on simulations needs neither the design nor its fits, and is sequential
        // (each step a slider case): it runs beside the design's parallel cases instead of
        // after them, where it held one core of a 2-core cold run for ~3 s (docs/doe.md).
        // The same cases in the same order: the outputs are those of the sequential order.
        let early = p.optimise && p.sa_objective == SaObjective::Simulation;
        let (design_and_fits, early_annealing) = rayon::join(
            || -> Result<_> {
                let design = run_design(p, ctx, &runner)?;
                let surfaces = fit_surfaces(p, ctx, &design)?;
                draw_fit_figures(p, ctx, &surfaces.fits, &design.designs)?;
                Ok((design, surfaces))
            },
            || {
                early.then(|| {
                    let objective = Objective {
                        p,
                        runner: &runner,
                        fits: &[],
                    };
                    anneal(p, ctx, &objective)
                })
            },
        );
        let (design, surfaces) = design_and_fits?;
        let optimum = if p.optimise {
            let objective = Objective {
                p,
                runner: &runner,
                fits: &surfaces.fits,
            };
            let annealing = match early_annealing {
                Some(a) => a?,
                None => anneal(p, ctx, &objective)?,
            };
            let sensitivity = check_sensitivity(p, ctx, &objective, &annealing)?;
            let comparison = if p.compare {
                Some(compare_designs(p, ctx, &runner, annealing.best)?)
            } else {
                None
            };
            Some(Optimum {
                annealing,
                sensitivity,
                comparison,
            })
        } else {
            None
        };
        // A fact of this run, not a result (it depends on what the store held): manifest only.
        ctx.log_run(
            "cases_cached",
            json!(design.cases.iter().filter(|c| c.entry.cached).count()),
        );
        Ok(assemble_output(p, &design, &surfaces, optimum))
    }
}

// ---- The phases of `DoeStage::run`, in order ----

/// The annealing's box, in coded units.
const CODED_LOWER: [f64; 3] = [-1.0; 3];
const CODED_UPPER: [f64; 3] = [1.0; 3];

impl DoeStage {
    /// The parameters with a fitted bulge applied (docs/doe.md: the measured design replaces
    /// the base's bulge, so it is Table 2.8's initial design; the factorial levels stay as
    /// configured) and the base sweep every case shares (interface table, DMW track, the keys
    /// of the instances they come from): the one preparation of a local run and a Slurm
    /// worker.
    pub fn prepare(&self, upstream: &UpstreamEntries) -> Result<(DoeParams, PreparedSweep)> {
        let mut p = self.params.clone();
        if let Some(b) = &p.bulge {
            let fitted = crate::artefacts::bulge::upstream_bulge(&upstream.results, b)?;
            p.base.powers = None;
            p.base.apply_bulge(&fitted, b)?;
        }
        let (isbl_params, dmw_track) = base_inputs(&p.base, &upstream.results, &upstream.dirs)?;
        let isbl = IsblLookup::build_standard_unverified(IsblModel::new(isbl_params)?)?;
        let sweep = PreparedSweep {
            contact_key: upstream.key_of(&p.base.contact),
            dmw: match (&p.base.dmw, dmw_track) {
                (Some(d), Some(t)) => Some((t, upstream.key_of(d))),
                _ => None,
            },
            params: p.base.clone(),
            isbl,
        };
        Ok((p, sweep))
    }
}

/// Case kind of a DOE design point (a 2-DOF case of the base sweep with another bulge).
pub const DOE_CASE: &str = "doe";

impl CaseEngine for DoeStage {
    /// The design cases, level by level; the annealing is sequential and runs locally.
    fn prepare_cases(&self, upstream: &UpstreamEntries) -> Result<Arc<dyn PreparedCases>> {
        let (p, sweep) = self.prepare(upstream)?;
        let cases = design_cases(&p.levels, &p.actuations)
            .into_iter()
            .map(|(d, a)| SweepCase {
                actuation_m: a,
                design_m: Some(d),
                static_start: None,
            })
            .collect();
        Ok(Arc::new(SweepCases {
            kind: DOE_CASE,
            sweep,
            listing: Listing::Cases(cases),
        }))
    }
}

/// The finished design: the coded points, their bulges [m], and every case, level by level.
struct DesignRun {
    coded_points: Vec<Vec<f64>>,
    designs: Vec<[f64; 3]>,
    cases: Vec<DesignCase>,
}

/// The 27 coded points × the actuation levels, in parallel through the case cache; writes the
/// design table. The same list the Slurm executor submits (`design_cases`), level by level.
fn run_design(p: &DoeParams, ctx: &StageContext, runner: &CaseRunner) -> Result<DesignRun> {
    let coded_points = full_factorial(&[3, 3, 3]);
    let designs = p.design_points();
    let jobs = design_cases(&p.levels, &p.actuations);
    let total = jobs.len();
    let finished = AtomicUsize::new(0);
    ctx.progress.set_message(format!("0/{total} DOE cases"));
    let outcomes: Vec<Result<DesignCase>> = jobs
        .par_iter()
        .map(|&(design, actuation)| {
            let r = runner.run(design, actuation);
            let n = finished.fetch_add(1, Ordering::Relaxed) + 1;
            ctx.progress.set_message(format!("{n}/{total} DOE cases"));
            r
        })
        .collect();
    let mut cases = Vec::with_capacity(total);
    for o in outcomes {
        cases.push(o?);
    }
    crate::core::store::write_table(
        &design_rows(&coded_points, designs.len(), &cases),
        &ctx.out_dir.join("design"),
    )?;
    Ok(DesignRun {
        coded_points,
        designs,
        cases,
    })
}

/// The response surfaces of every actuation level and the degree each selects.
struct SurfaceFits {
    fits: Vec<LevelFit>,
    selected_degrees: Vec<String>,
}

/// Fits the surfaces per level; writes the coefficient, ANOVA and predictive-equation tables.
fn fit_surfaces(p: &DoeParams, ctx: &StageContext, design: &DesignRun) -> Result<SurfaceFits> {
    ctx.progress.set_message("response surfaces");
    let per_level = design.designs.len();
    let mut fits = Vec::new();
    for (k, &h) in p.actuations.iter().enumerate() {
        let xi: Vec<f64> = design.cases[k * per_level..(k + 1) * per_level]
            .iter()
            .map(|c| c.xi)
            .collect();
        if let Some(i) = xi.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFiniteXi {
                design: design.designs[i],
                actuation: h,
            });
        }
        fits.push(fit_level(h, p.fixed[k], &design.coded_points, &xi)?);
    }
    let selected_degrees: Vec<String> = fits
        .iter()
        .map(|f| model_selection(f).2.to_string())
        .collect();
    crate::core::store::write_table(&coefficient_rows(&fits), &ctx.out_dir.join("coefficients"))?;
    crate::core::store::write_table(&anova_rows(&fits), &ctx.out_dir.join("anova"))?;
    crate::core::store::write_table(
        &predictive_rows(p, &fits)?,
        &ctx.out_dir.join("predictive_equations"),
    )?;
    Ok(SurfaceFits {
        fits,
        selected_degrees,
    })
}

/// Contour and residual plots of every level (Figs 2.26–2.29).
fn draw_fit_figures(
    p: &DoeParams,
    ctx: &StageContext,
    fits: &[LevelFit],
    designs: &[[f64; 3]],
) -> Result<()> {
    ctx.progress.set_message("contour and residual plots");
    for lf in fits {
        let tag = format!("{:.1}nm", lf.actuation / NM).replace('.', "p");
        contour_png(
            &ctx.out_dir.join(format!("contours_{tag}.png")),
            p,
            lf,
            designs,
        )?;
        residuals_png(&ctx.out_dir.join(format!("residuals_{tag}.png")), lf)?;
    }
    Ok(())
}

/// ξ at a coded point for the annealing and the sensitivity check (dissertation §2.3): a cached
/// simulation case at `sa_actuation`, or the level surfaces interpolated to it.
struct Objective<'a> {
    p: &'a DoeParams,
    runner: &'a CaseRunner<'a>,
    fits: &'a [LevelFit],
}

/// One objective evaluation: ξ and, for a simulation, the case it used.
struct Evaluation {
    xi: f64,
    case_key: Option<String>,
}

impl Objective<'_> {
    fn evaluate(&self, c: &[f64]) -> Result<Evaluation> {
        let p = self.p;
        match p.sa_objective {
            SaObjective::Simulation => {
                let r = self.runner.run(p.decode(c), p.sa_actuation)?;
                Ok(Evaluation {
                    xi: r.xi,
                    case_key: Some(r.entry.key),
                })
            }
            SaObjective::Surrogate => Ok(Evaluation {
                xi: surrogate_xi(self.fits, p.sa_actuation, c),
                case_key: None,
            }),
        }
    }
}

/// The annealing's optimum and what it cost.
struct Annealing {
    /// The optimum in coded units, and decoded [m].
    coded: Vec<f64>,
    best: [f64; 3],
    best_xi: f64,
    evaluations: usize,
    reanneals: usize,
    stop: StopReason,
    case_keys: Vec<String>,
}

/// Simulated annealing on ξ at `sa_actuation`, in coded units; writes the annealing table and
/// its convergence plot (Fig. 2.30).
fn anneal(p: &DoeParams, ctx: &StageContext, objective: &Objective) -> Result<Annealing> {
    ctx.progress.set_message("simulated annealing");
    let start = p.encode(&p.sa_start);
    let mut annealer =
        Annealer::new(&CODED_LOWER, &CODED_UPPER, &start, &p.sa).map_err(Error::Annealing)?;
    let mut case_keys = Vec::new();
    let mut xis = Vec::new();
    while let Some(c) = annealer.ask() {
        let e = objective.evaluate(&c)?;
        case_keys.extend(e.case_key);
        xis.push(e.xi);
        annealer.tell(annealing_objective(e.xi));
        ctx.progress.set_message(format!(
            "simulated annealing: {} evaluations, best J {:.4e}",
            annealer.evaluations(),
            annealer.best().1
        ));
    }
    let stop = annealer.stop_reason();
    let res = annealer.into_result();
    let best = p.decode(&res.x);
    crate::core::store::write_table(
        &annealing_rows(p, &res.history, &xis),
        &ctx.out_dir.join("annealing"),
    )?;
    annealing_convergence_png(&ctx.out_dir.join("annealing.png"), p, &res.history)?;
    // The optimum is an evaluated point: a simulation finds its case cached, already listed.
    let best_xi = objective.evaluate(&res.x)?.xi;
    Ok(Annealing {
        best,
        best_xi,
        evaluations: res.evaluations,
        reanneals: res.reanneals,
        stop: stop.unwrap_or(res.stop),
        case_keys,
        coded: res.x,
    })
}

/// The one-step ξ spread per factor around the optimum.
struct Sensitivity {
    spread: [f64; 3],
    most_sensitive: Option<&'static str>,
    case_keys: Vec<String>,
}

/// ± steps of `sensitivity_step` per factor around the optimum; writes the sensitivity table.
fn check_sensitivity(
    p: &DoeParams,
    ctx: &StageContext,
    objective: &Objective,
    annealing: &Annealing,
) -> Result<Sensitivity> {
    ctx.progress.set_message("sensitivity check");
    let step: Vec<f64> = (0..3)
        .map(|f| p.sensitivity_step / (0.5 * (p.levels[f][2] - p.levels[f][0])))
        .collect();
    let pts = sensitivity_points(
        &annealing.coded,
        &step,
        p.sensitivity_steps,
        &CODED_LOWER,
        &CODED_UPPER,
    )
    .map_err(Error::Sensitivity)?;
    let values: Vec<Result<Evaluation>> =
        pts.par_iter().map(|s| objective.evaluate(&s.x)).collect();
    let mut case_keys = Vec::new();
    let mut sens_rows = Vec::new();
    let mut spread = [0.0f64; 3];
    for (s, v) in pts.iter().zip(values) {
        let e = v?;
        let xi = e.xi;
        case_keys.extend(e.case_key);
        let d = p.decode(&s.x);
        if s.offset.abs() == 1 {
            spread[s.coordinate] = spread[s.coordinate].max((xi - annealing.best_xi).abs());
        }
        let mut m = Map::new();
        m.insert("factor".into(), json!(FACTORS[s.coordinate]));
        m.insert("offset_steps".into(), json!(s.offset));
        m.insert(
            "offset_nm".into(),
            table_value(f64::from(s.offset) * p.sensitivity_step / NM),
        );
        m.insert("a_um".into(), table_value(d[0] / UM));
        m.insert("w_um".into(), table_value(d[1] / UM));
        m.insert("x_um".into(), table_value(d[2] / UM));
        m.insert("xi".into(), table_value(xi));
        sens_rows.push(m);
    }
    crate::core::store::write_table(&sens_rows, &ctx.out_dir.join("sensitivity"))?;
    let most_sensitive = (0..3)
        .max_by(|a, b| spread[*a].total_cmp(&spread[*b]))
        .map(|f| FACTORS[f]);
    Ok(Sensitivity {
        spread,
        most_sensitive,
        case_keys,
    })
}

/// One design's 2-DOF sweep of Table 2.8.
struct DesignSweep {
    label: &'static str,
    outcomes: Vec<CaseOutcome>,
}

/// Table 2.8's rows and the cases they used.
struct Comparison {
    rows: Vec<Map<String, Value>>,
    case_keys: Vec<String>,
}

/// Table 2.8: the 2-DOF sweep on the initial and the optimised design; writes the comparison
/// table and plot.
fn compare_designs(
    p: &DoeParams,
    ctx: &StageContext,
    runner: &CaseRunner,
    best: [f64; 3],
) -> Result<Comparison> {
    let initial = {
        let b = p.base.model.bulge;
        [b.semi_width_x, b.full_width_y, b.offset_from_te]
    };
    let n = p.compare_actuations.len();
    let total = 2 * n;
    let done = AtomicUsize::new(0);
    let runs: Vec<Result<DesignCase>> = (0..total)
        .into_par_iter()
        .map(|i| {
            let design = if i < n { initial } else { best };
            let r = runner.run(design, p.compare_actuations[i % n]);
            let k = done.fetch_add(1, Ordering::Relaxed) + 1;
            ctx.progress
                .set_message(format!("Table 2.8 sweeps: {k}/{total} cases"));
            r
        })
        .collect();
    let mut all = Vec::with_capacity(total);
    for r in runs {
        all.push(r?);
    }
    let case_keys = all.iter().map(|c| c.entry.key.clone()).collect();
    let mut rows = Vec::new();
    let mut sweeps = Vec::new();
    for (label, chunk) in [("initial", &all[..n]), ("optimised", &all[n..])] {
        let design = chunk[0].design;
        let sp = runner.params_for(&design)?;
        let outcomes: Vec<CaseOutcome> = chunk
            .iter()
            .map(|c| CaseOutcome {
                actuation: c.actuation,
                metrics: c.result.clone(),
                entry: c.entry.clone(),
            })
            .collect();
        let td = refined_touchdown(runner, design, &outcomes)?;
        rows.extend(comparison_rows(label, &design, &sp, &outcomes, td)?);
        sweeps.push(DesignSweep { label, outcomes });
    }
    crate::core::store::write_table(&rows, &ctx.out_dir.join("comparison"))?;
    comparison_png(&ctx.out_dir.join("comparison.png"), p, &sweeps)?;
    Ok(Comparison { rows, case_keys })
}

/// What the optimisation found, when it ran.
struct Optimum {
    annealing: Annealing,
    sensitivity: Sensitivity,
    comparison: Option<Comparison>,
}

/// The result JSON and the summary row.
fn assemble_output(
    p: &DoeParams,
    design: &DesignRun,
    surfaces: &SurfaceFits,
    optimum: Option<Optimum>,
) -> StageOutput {
    let total = design.cases.len();
    // Every case this instance used, so `hdi gc` keeps them with it.
    let mut case_keys: Vec<String> = design.cases.iter().map(|c| c.entry.key.clone()).collect();
    let mut result = json!({
        "cases": total,
        "fits": surfaces.fits.iter().map(fit_summary).collect::<Vec<_>>(),
        "tables": ["design", "coefficients", "anova", "predictive_equations"],
    });
    if p.bulge.is_some() {
        // The fitted (measured) bulge: Table 2.8's initial design.
        let b = p.base.model.bulge;
        result["initial_design_m"] = json!({
            "a_tfc": b.semi_width_x, "w_tfc": b.full_width_y, "x_tfc": b.offset_from_te,
        });
    }
    let mut row = Map::new();
    row.insert("simulate".into(), json!(p.base_name));
    row.insert("cases".into(), json!(total));
    row.insert(
        "selected_degrees".into(),
        json!(surfaces.selected_degrees.join(" ")),
    );
    if let Some(Optimum {
        annealing: a,
        sensitivity: s,
        comparison,
    }) = optimum
    {
        case_keys.extend(a.case_keys);
        case_keys.extend(s.case_keys);
        let best = a.best;
        let spread = s.spread;
        let optimum = json!({
            "a_m": best[0], "w_m": best[1], "x_m": best[2],
            "xi": a.best_xi,
            "objective": format!("{:?}", p.sa_objective).to_lowercase(),
            "evaluations": a.evaluations,
            "reanneals": a.reanneals,
            "stop": match a.stop {
                StopReason::Stalled => "converged (stalled)",
                StopReason::MaxEvaluations => "evaluation budget",
            },
            "sensitivity_one_step": {"a_tfc": spread[0], "w_tfc": spread[1], "x_tfc": spread[2]},
            "most_sensitive": s.most_sensitive,
        });
        row.insert("optimum_a_um".into(), table_value(best[0] / UM));
        row.insert("optimum_w_um".into(), table_value(best[1] / UM));
        row.insert("optimum_x_um".into(), table_value(best[2] / UM));
        row.insert("optimum_xi".into(), table_value(a.best_xi));
        row.insert("sa_evaluations".into(), json!(a.evaluations));
        row.insert("most_sensitive".into(), json!(s.most_sensitive));
        result["optimum"] = optimum;
        if let Some(c) = comparison {
            case_keys.extend(c.case_keys);
            result["comparison"] = json!(c.rows);
        }
    }
    case_keys.sort();
    case_keys.dedup();
    result["case_keys"] = json!(case_keys);
    result["tables"] = json!([
        "design",
        "coefficients",
        "anova",
        "predictive_equations",
        "annealing",
        "sensitivity",
        "comparison"
    ]);
    StageOutput {
        result,
        summary_row: Some(row),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objective_never_prefers_contact() {
        assert_eq!(annealing_objective(0.02), 0.02);
        // Negative ξ (solid contact) is worse than any positive ξ below 1.
        assert_eq!(annealing_objective(-0.3), 1.3);
        assert!(annealing_objective(-1e-9) > annealing_objective(0.9));
    }

    #[test]
    fn surrogate_interpolates_linearly_between_levels() {
        let points = full_factorial(&[3, 3, 3]);
        let basis = PolynomialBasis::bounded(3, 2, 4);
        // ξ = 1 + x1 at 9 nm and 3 + x1 at 12 nm: exact on the quartic basis.
        let fit_of = |h: f64, c: f64| {
            let xi: Vec<f64> = points.iter().map(|p| c + p[0]).collect();
            LevelFit {
                actuation: h,
                fixed: 0,
                quartic: ResponseSurface::fit(&basis, &points, &xi, &FitOptions::default())
                    .unwrap(),
                quintic: None,
            }
        };
        let fits = [fit_of(9e-9, 1.0), fit_of(12e-9, 3.0)];
        let at = |h: f64| surrogate_xi(&fits, h, &[0.5, 0.0, 0.0]);
        assert!((at(9e-9) - 1.5).abs() < 1e-10);
        assert!((at(12e-9) - 3.5).abs() < 1e-10);
        // 9.75 nm is a quarter of the way: 1.5 + 0.25 · 2.
        assert!((at(9.75e-9) - 2.0).abs() < 1e-10);
        // Outside: the nearest level.
        assert!((at(20e-9) - 3.5).abs() < 1e-10);
    }

    #[test]
    fn degree_five_is_selected_only_when_its_terms_are_needed() {
        let points = full_factorial(&[3, 3, 3]);
        let mut rng = crate::numerics::rng::Rng::new(5);
        let noise: Vec<f64> = points.iter().map(|_| 1e-3 * rng.normal()).collect();
        let level = |y: Vec<f64>| {
            let opts = FitOptions::default();
            let fit =
                |d| ResponseSurface::fit(&PolynomialBasis::bounded(3, 2, d), &points, &y, &opts);
            LevelFit {
                actuation: 9e-9,
                fixed: 2,
                quartic: fit(4).unwrap(),
                quintic: fit(5).ok(),
            }
        };
        // A quartic surface plus noise: the added terms explain noise only.
        let quartic: Vec<f64> = points
            .iter()
            .zip(&noise)
            .map(|(x, e)| 1.0 + x[0] - 0.5 * x[1] * x[1] * x[2] * x[2] + e)
            .collect();
        assert_eq!(model_selection(&level(quartic)).2, 4);
        // A strong degree-5 term (x1² x2² x3) the quartic cannot represent.
        let quintic: Vec<f64> = points
            .iter()
            .zip(&noise)
            .map(|(x, e)| 1.0 + x[0] * x[0] * x[1] * x[1] * x[2] + e)
            .collect();
        let (f, p, d) = model_selection(&level(quintic));
        assert_eq!(d, 5, "F {f:?}, p {p:?}");
    }

    #[test]
    fn coded_levels_decode_to_the_levels_exactly() {
        let cfg: DoeConfig = toml::from_str("simulate = \"s\"").unwrap();
        let base = SimulateParams::check(&toml::from_str("contact = \"c\"").unwrap()).unwrap();
        let p = check(&cfg, base, "s").unwrap();
        // a_TFC's top level and x_TFC's bottom level are both 5 µm: equal, not an ulp apart.
        let d = p.decode(&[1.0, 0.0, -1.0]);
        assert_eq!(d[0], d[2]);
        assert_eq!(d, [5.0 * UM, 50.0 * UM, 5.0 * UM]);
        let back = p.encode(&d);
        assert!(back
            .iter()
            .zip([1.0, 0.0, -1.0])
            .all(|(a, b)| (a - b).abs() < 1e-12));
        // §2.3.2's rule: a_TFC held at 5 and 15 nm, x_TFC at 9 and 12 nm.
        assert_eq!(p.fixed, vec![0, 2, 2, 0]);
    }

    #[test]
    fn bulge_geometry_keys_and_checks() {
        let base = || SimulateParams::check(&toml::from_str("contact = \"c\"").unwrap()).unwrap();
        let plain: DoeConfig = toml::from_str("simulate = \"s\"").unwrap();
        let p = check(&plain, base(), "s").unwrap();
        // Without a geometry the canonical parameters are the ones keyed before it existed.
        let keys: Vec<String> = p.canonical().as_object().unwrap().keys().cloned().collect();
        let before = vec![
            "base",
            "levels_m",
            "actuations_m",
            "fixed",
            "optimise",
            "sa_actuation_m",
            "sa_start_m",
            "sa_objective",
            "sa",
            "sensitivity_step_m",
            "sensitivity_steps",
            "compare",
            "compare_actuations_m",
        ];
        assert_eq!(keys, before);
        assert!(p.bulge.is_none());
        let fitted: DoeConfig =
            toml::from_str("simulate = \"s\"\ngeometry = { bulge = \"tfc\" }").unwrap();
        let q = check(&fitted, base(), "s").unwrap();
        assert_eq!(q.bulge.as_deref(), Some("tfc"));
        assert_eq!(q.canonical()["bulge"], "tfc");
        // A base that already has the fitted bulge keys it through `base` alone.
        let fitted_base = SimulateParams::check(
            &toml::from_str("contact = \"c\"\ngeometry = { bulge = \"tfc\" }").unwrap(),
        )
        .unwrap();
        let r = check(&plain, fitted_base, "s").unwrap();
        assert_eq!(r.bulge.as_deref(), Some("tfc"));
        assert!(r.canonical().get("bulge").is_none());
        let named: DoeConfig =
            toml::from_str("simulate = \"s\"\ngeometry = \"optimised\"").unwrap();
        assert_eq!(check(&named, base(), "s").unwrap_err().key, "geometry");
    }
}
