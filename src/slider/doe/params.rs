//! The `[doe]` stage's settings (dissertation §2.3; docs/doe.md): the table as written, its
//! checks against the base `[simulate]` instance, and the validated parameters (SI) whose
//! canonical JSON keys the stage.

use crate::numerics::annealing::AnnealingOptions;
use crate::numerics::regression::coded;
use crate::slider::doe_design;
use crate::slider::params::SimulateParams;
use crate::units::Length;
use serde::Deserialize;
use serde_json::{json, Value};

pub(crate) const UM: f64 = 1e-6;
/// Highest actuation a DOE case may use [m] (see `check`).
const DOE_MAX_ACTUATION: f64 = 20e-9;
pub(crate) const NM: f64 = 1e-9;
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
    pub(crate) fn canonical(&self) -> Value {
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
    pub(crate) fn design_points(&self) -> Vec<[f64; 3]> {
        doe_design::design_points(&self.levels)
    }

    /// Physical design `[a, w, x]` of a coded point.
    pub(crate) fn decode(&self, c: &[f64]) -> [f64; 3] {
        doe_design::decode(&self.levels, c)
    }

    pub(crate) fn encode(&self, x: &[f64; 3]) -> [f64; 3] {
        std::array::from_fn(|f| coded(x[f], self.levels[f][0], self.levels[f][2]))
    }
}

fn bad<T>(
    key: &str,
    m: impl Into<String>,
) -> std::result::Result<T, crate::core::config::KeyError> {
    Err(crate::core::config::KeyError::new(key, m))
}

type KeyResult<T> = std::result::Result<T, crate::core::config::KeyError>;

/// Check `[doe]` keys against the base instance; failures name the key.
pub fn check(cfg: &DoeConfig, base: SimulateParams, base_name: &str) -> KeyResult<DoeParams> {
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
    let levels = checked_levels(cfg)?;
    // The 2-DOF range is 0–15 nm [seed §2.1.1], but §2.3's fully contacting level is 16 nm:
    // DOE cases may run up to 20 nm, extrapolating the rear-stiffening law (docs/doe.md).
    let max_h = base.model.max_actuation.max(DOE_MAX_ACTUATION);
    let actuations = checked_actuations(cfg, max_h)?;
    let fixed = fixed_factors(cfg, &actuations)?;
    let (sa_objective, sa_actuation, sa_start) =
        checked_annealing(cfg, &levels, &actuations, max_h)?;
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

/// The −1/0/+1 levels of each factor: positive, increasing, the middle one the midpoint, and
/// no bulge overhanging the trailing edge.
fn checked_levels(cfg: &DoeConfig) -> KeyResult<[[f64; 3]; 3]> {
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
    Ok(levels)
}

/// Whether an actuation lies within the DOE's range 0–`max_h`.
fn in_actuation_range(h: f64, max_h: f64) -> bool {
    h.is_finite() && (0.0..=max_h).contains(&h)
}

/// The DOE's actuation levels: at least one, within 0–`max_h`, increasing.
fn checked_actuations(cfg: &DoeConfig, max_h: f64) -> KeyResult<Vec<f64>> {
    if cfg.actuations.is_empty()
        || !cfg
            .actuations
            .iter()
            .all(|h| in_actuation_range(h.0, max_h))
    {
        return bad(
            "actuations",
            format!("one or more actuations within 0–{:.1} nm", max_h / NM),
        );
    }
    let actuations: Vec<f64> = cfg.actuations.iter().map(|h| h.0).collect();
    if actuations.windows(2).any(|w| w[1] <= w[0]) {
        return bad("actuations", "increasing, without repeats");
    }
    Ok(actuations)
}

/// The factor held fixed at each actuation level (Table 2.7), as written or §2.3.2's default.
fn fixed_factors(cfg: &DoeConfig, actuations: &[f64]) -> KeyResult<Vec<usize>> {
    Ok(match &cfg.fixed_factors {
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
    })
}

/// The simulated-annealing settings: its objective, the actuation it optimises at, its start
/// within the design box, and its budget, temperature and re-annealing interval.
fn checked_annealing(
    cfg: &DoeConfig,
    levels: &[[f64; 3]; 3],
    actuations: &[f64],
    max_h: f64,
) -> KeyResult<(SaObjective, f64, [f64; 3])> {
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
    if !in_actuation_range(sa_actuation, max_h) {
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
    Ok((sa_objective, sa_actuation, sa_start))
}

#[cfg(test)]
mod tests {
    use super::*;

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
