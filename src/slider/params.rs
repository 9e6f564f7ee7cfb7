//! `[simulate]` settings: the raw `pipeline.toml` table (`SimulateConfig`, every key also a
//! `hdi simulate` option), its check into `SimulateParams`, and the canonical parameters that
//! key the instance and each of its cases. `[calibrate]`, `[doe]`, `[analysis]` and the Slurm
//! executor resolve a `[simulate]` instance through here, not through the simulate stage.

use crate::core::config::{ConfigError, KeyError, PipelineFile};
use crate::dynamics::air_bearing::RearStiffening;
use crate::dynamics::metrics::{CaseParams, SteadyWindow};
use crate::dynamics::params::{improved_2dof, initial_2dof, optimised_bulge, Model2Dof};
use crate::dynamics::two_dof::{ContactForceForm, Integrator, LubricantForce, SimOptions};
use crate::units::{Length, Power, TimeSpan};
use serde::Deserialize;
use serde_json::{json, Value};

fn default_model() -> String {
    "improved_2dof".into()
}
fn default_none() -> String {
    "none".into()
}
fn nm(v: f64) -> Length {
    Length(v * 1e-9)
}
fn default_start() -> Length {
    nm(0.0)
}
fn default_stop() -> Length {
    nm(15.0)
}
fn default_step() -> Length {
    nm(0.2)
}
fn default_duration() -> TimeSpan {
    TimeSpan(2e-3)
}
fn default_steady() -> TimeSpan {
    TimeSpan(0.5e-3)
}
fn default_output_step() -> TimeSpan {
    TimeSpan(0.25e-6)
}
fn default_contact_force() -> String {
    "interference_tangent".into()
}
fn default_integrator() -> String {
    "dopri5".into()
}
fn default_rtol() -> f64 {
    1e-8
}
fn default_contact_max_step() -> TimeSpan {
    TimeSpan(1e-8)
}
fn default_max_step() -> TimeSpan {
    TimeSpan(1e-6)
}
fn default_fixed_step() -> TimeSpan {
    TimeSpan(1e-9)
}
fn default_true() -> bool {
    true
}
fn default_geometry() -> GeometryConfig {
    GeometryConfig::Named("dissertation".into())
}

/// `geometry = "dissertation" | "optimised"`, or `geometry = { bulge = "NAME" }`: a, w and
/// x_TFC from a `[bulge.NAME]` fit (docs/bulge.md).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum GeometryConfig {
    Named(String),
    Bulge { bulge: String },
}

/// `[simulate.NAME]` as written in `pipeline.toml` (every key is also a `hdi simulate` option).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SimulateConfig {
    /// `improved_2dof` (§2.2, default) or `initial_2dof` (§2.1).
    #[serde(default = "default_model")]
    pub model: String,
    /// The `[contact.*]` instance whose interface (ISBL table) the cases use.
    pub contact: String,
    /// A `[dmw.*]` instance (track 1 under every point) or `none`.
    #[serde(default = "default_none")]
    pub dmw: String,
    /// Explicit actuations; otherwise `actuation_start … actuation_stop` by `actuation_step`.
    #[serde(default)]
    pub actuations: Option<Vec<Length>>,
    #[serde(default = "default_start")]
    pub actuation_start: Length,
    #[serde(default = "default_stop")]
    pub actuation_stop: Length,
    #[serde(default = "default_step")]
    pub actuation_step: Length,
    #[serde(default = "default_duration")]
    pub duration: TimeSpan,
    /// Start of the steady-state window (it ends at `duration`).
    #[serde(default = "default_steady")]
    pub steady_start: TimeSpan,
    #[serde(default = "default_output_step")]
    pub output_step: TimeSpan,
    /// `interference_tangent` (default, eq. 2.16 as written), `static_curve` or
    /// `integrated_stiffness` (docs/model-form.md).
    #[serde(default = "default_contact_force")]
    pub contact_force: String,
    /// `isbl` (default) or `bem`: the contact pressure, real area and junction-shear friction
    /// from the `[contact_bem.*]` curve named by `contact_bem` (docs/model-form.md, "Contact
    /// law"); adhesion stays the `contact` instance's.
    #[serde(default)]
    pub contact_law: Option<String>,
    #[serde(default)]
    pub contact_bem: Option<String>,
    /// `none` (default, Chapter 2: the lubricant offers no resistance) or `mtl` (Chapter 3's
    /// lubricant force inside the film; improved model only; docs/model-form.md).
    #[serde(default = "default_none")]
    pub lubricant: String,
    /// `dopri5` (adaptive, default) or `rk5_fixed` (the dissertation's fixed small step).
    #[serde(default = "default_integrator")]
    pub integrator: String,
    #[serde(default = "default_rtol")]
    pub rtol: f64,
    /// Step cap while the bulge is in contact (dopri5).
    #[serde(default = "default_contact_max_step")]
    pub contact_max_step: TimeSpan,
    /// Step cap everywhere (dopri5).
    #[serde(default = "default_max_step")]
    pub max_step: TimeSpan,
    /// Step of `rk5_fixed`.
    #[serde(default = "default_fixed_step")]
    pub fixed_step: TimeSpan,
    /// DMW under the LE/TE delayed by the disk transit (§6).
    #[serde(default = "default_true")]
    pub transit_delay: bool,
    /// Repeat a DMW record shorter than the run.
    #[serde(default)]
    pub dmw_wrap: bool,
    /// Improved model's rear-spring stiffening amplitude β (§3.2, default 1).
    #[serde(default)]
    pub kr_stiffening_beta: Option<f64>,
    /// `dissertation` (Tables 2.1: a = 3 µm, x = 8 µm) or `optimised` (§2.3: a = 4.86 µm,
    /// x = 6.35 µm).
    #[serde(default = "default_geometry")]
    pub geometry: GeometryConfig,
    /// Heater powers instead of actuations (needs `geometry = { bulge = "NAME" }` with an
    /// efficiency): actuation = efficiency × power (docs/bulge.md).
    #[serde(default)]
    pub powers: Option<Vec<Power>>,
    /// Power range `power_start … power_stop` by `power_step` (start default 0 W).
    #[serde(default)]
    pub power_start: Option<Power>,
    #[serde(default)]
    pub power_stop: Option<Power>,
    #[serde(default)]
    pub power_step: Option<Power>,
    /// Full bulge width w_TFC of the optimised design (dropped in the text; default 50 µm).
    #[serde(default)]
    pub bulge_width: Option<Length>,
    /// Actuations whose time histories are plotted (nearest case).
    #[serde(default)]
    pub histories: Vec<Length>,
    /// `nominal` (§5.4 default: start from the nominal state) or `static` (start from the
    /// static equilibrium at the case's actuation, recommended for sweeps).
    #[serde(default = "default_init")]
    pub init: String,
    /// With `init = "static"`: `both` (default), `up` or `down` — the continuation branches
    /// the sweep tracks (docs/conventions.md). Not allowed with `init = "nominal"`.
    #[serde(default)]
    pub branches: Option<String>,
    /// Refine the sweep's touchdown to 0.02 nm by running the extra cases (default true;
    /// docs/conventions.md). `false` reports the grid touchdown only (quick test sweeps).
    #[serde(default = "default_true")]
    pub refine_touchdown: bool,
    /// A `[calibrate.*]` instance whose fitted knobs (DMW scale, β, Δγ, ε, ζ_c, …) replace
    /// the spec defaults of this instance.
    #[serde(default)]
    pub calibration: Option<String>,
    /// Heave offset of the start state (from the nominal or static state), e.g. `"1 nm"`: a
    /// kick whose free decay shows the AB modes (Appendix B's zero excitation).
    #[serde(default)]
    pub initial_heave: Option<Length>,
}

fn default_init() -> String {
    "nominal".into()
}

/// Validated settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulateParams {
    pub model_name: String,
    pub model: Model2Dof,
    pub contact: String,
    /// `contact_law = "bem"`: the `[contact_bem.*]` instance whose curve is the contact law.
    pub contact_bem: Option<String>,
    pub dmw: Option<String>,
    pub actuations: Vec<f64>,
    pub options: SimOptions,
    pub steady_start: f64,
    pub histories: Vec<f64>,
    pub geometry: String,
    pub calibration: Option<String>,
    /// The fitted knob values applied at run time (empty without calibration).
    pub calibrated_knobs: Vec<(String, f64)>,
    /// The `[bulge.*]` instance whose fitted a, w, x_TFC replace the geometry at run time.
    pub bulge: Option<String>,
    /// Heater powers (W) of a power sweep: the actuations follow at run time from the bulge
    /// efficiency.
    pub powers: Option<Vec<f64>>,
    /// The efficiency (m/W) the actuations were computed with (set when prepared).
    pub efficiency: Option<f64>,
    /// Branch-tracking (continuation) sweeps of `init = "static"`; empty with `init =
    /// "nominal"` (one sweep from the nominal state).
    pub branches: Vec<Branch>,
    /// Refine the touchdown to 0.02 nm (the convention) with extra cases.
    pub refine_touchdown: bool,
}

/// The key of a `[calibrate]` table a calibrated instance checks (the table itself is
/// validated by its own kind).
#[derive(serde::Deserialize)]
struct CalibrateTarget {
    simulate: String,
}

/// The uncalibrated `[simulate.<base>]` another stage builds on (`[calibrate]`, `[doe]`),
/// validated; failures are reported against that stage's `simulate` key.
pub fn uncalibrated_base(
    file: &PipelineFile,
    section: &str,
    name: &str,
    base: &str,
) -> std::result::Result<SimulateParams, ConfigError> {
    let err = |m: String| file.error(section, name, "simulate", m);
    let Some(cfg) = file.instance::<SimulateConfig>("simulate", base)? else {
        return Err(err(format!("no [simulate.{base}] in this file")));
    };
    if cfg.calibration.is_some() {
        return Err(err(format!(
            "[simulate.{base}] is itself calibrated; [{section}] starts from an uncalibrated \
             instance"
        )));
    }
    if cfg.contact_law.as_deref() == Some("bem") {
        return Err(err(format!(
            "[simulate.{base}] has contact_law = \"bem\"; [{section}] builds ISBL tables \
             (docs/model-form.md, \"Contact law\"): use an ISBL instance"
        )));
    }
    SimulateParams::check(&cfg).map_err(|e| err(format!("[simulate.{base}] is invalid ({e})")))
}

/// A failed `[simulate]` check at `key`.
fn bad<T>(key: &str, message: impl Into<String>) -> std::result::Result<T, KeyError> {
    Err(KeyError::new(key, message))
}

/// `model`, `geometry` and `kr_stiffening_beta`: the 2-DOF model, checked as a whole.
fn check_model(cfg: &SimulateConfig) -> std::result::Result<Model2Dof, KeyError> {
    let mut model = match cfg.model.as_str() {
        "improved_2dof" => improved_2dof(),
        "initial_2dof" => initial_2dof(),
        o => {
            return bad(
                "model",
                format!("unknown model `{o}` (improved_2dof, initial_2dof)"),
            )
        }
    };
    let named = match &cfg.geometry {
        GeometryConfig::Named(n) => n.as_str(),
        GeometryConfig::Bulge { .. } => {
            if cfg.bulge_width.is_some() {
                return bad(
                    "bulge_width",
                    "not used with geometry = { bulge = … } (the fit gives w)",
                );
            }
            "dissertation"
        }
    };
    match named {
        "dissertation" => {
            if cfg.bulge_width.is_some() {
                return bad("bulge_width", "only used with geometry = \"optimised\"");
            }
        }
        "optimised" => {
            let w = cfg.bulge_width.map_or(50e-6, |l| l.0);
            match optimised_bulge(w) {
                Ok(b) => model = model.with_bulge(b),
                Err(e) => return bad("bulge_width", e.to_string()),
            }
        }
        o => {
            return bad(
                "geometry",
                format!("unknown geometry `{o}` (dissertation, optimised)"),
            )
        }
    }
    if let Some(beta) = cfg.kr_stiffening_beta {
        if !(beta.is_finite() && (0.0..=10.0).contains(&beta)) {
            return bad(
                "kr_stiffening_beta",
                format!("{beta} is out of range: 0 ≤ β ≤ 10"),
            );
        }
        model.air_bearing.stiffening = if beta == 0.0 {
            RearStiffening::Constant
        } else {
            RearStiffening::Quadratic { beta }
        };
    }
    if let Err(e) = model.validate() {
        return bad("model", e.to_string());
    }
    Ok(model)
}

/// `powers`, or the `power_start … power_stop` range by `power_step` (W, sorted); `None` when
/// the sweep is stated in actuation. Needs `geometry = { bulge = … }`.
fn check_powers(cfg: &SimulateConfig) -> std::result::Result<Option<Vec<f64>>, KeyError> {
    let range = cfg.power_start.is_some() || cfg.power_stop.is_some() || cfg.power_step.is_some();
    let list: Vec<f64> = match (&cfg.powers, range) {
        (None, false) => return Ok(None),
        (Some(_), true) => return bad("powers", "give powers or power_start/stop/step, not both"),
        (Some(l), false) => {
            let mut v: Vec<f64> = l.iter().map(|p| p.0).collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        }
        (None, true) => {
            let a = cfg.power_start.map_or(0.0, |p| p.0);
            let (Some(b), Some(st)) = (cfg.power_stop, cfg.power_step) else {
                return bad(
                    "power_stop",
                    "a power range needs power_stop and power_step",
                );
            };
            let (b, st) = (b.0, st.0);
            if !(st > 0.0 && b >= a) {
                return bad(
                    "power_step",
                    format!("need power_step > 0 and power_stop ≥ power_start (got {a} … {b} by {st} W)"),
                );
            }
            let n = ((b - a) / st + 1e-9).floor() as usize;
            if n > 10_000 {
                return bad("power_step", format!("{n} cases is too many (≤ 10 000)"));
            }
            // Rounded to the nanowatt so 2.5 mW steps give 7.5 mW exactly.
            (0..=n)
                .map(|i| ((a + i as f64 * st) * 1e9).round() / 1e9)
                .collect()
        }
    };
    if !matches!(cfg.geometry, GeometryConfig::Bulge { .. }) {
        return bad(
            if cfg.powers.is_some() {
                "powers"
            } else {
                "power_stop"
            },
            "a sweep in heater power needs geometry = { bulge = \"NAME\" } (its efficiency)",
        );
    }
    if cfg.actuations.is_some() {
        return bad("actuations", "give actuations or heater powers, not both");
    }
    if list.is_empty() || list.iter().any(|p| !(p.is_finite() && *p >= 0.0)) {
        return bad("powers", "need one or more powers ≥ 0");
    }
    Ok(Some(list))
}

/// `actuations`, or the `actuation_start … actuation_stop` range by `actuation_step`, each
/// within the model's range `0 … max`.
fn check_actuations(cfg: &SimulateConfig, max: f64) -> std::result::Result<Vec<f64>, KeyError> {
    let actuations: Vec<f64> = match &cfg.actuations {
        Some(list) => {
            let mut v: Vec<f64> = list.iter().map(|l| l.0).collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        }
        None => {
            let (a, b, s) = (
                cfg.actuation_start.0,
                cfg.actuation_stop.0,
                cfg.actuation_step.0,
            );
            if !(s > 0.0 && b >= a) {
                return bad(
                    "actuation_step",
                    format!("need actuation_step > 0 and actuation_stop ≥ actuation_start (got {a:e} … {b:e} by {s:e} m)"),
                );
            }
            let n = ((b - a) / s + 1e-9).floor() as usize;
            if n > 10_000 {
                return bad(
                    "actuation_step",
                    format!("{n} cases is too many (≤ 10 000)"),
                );
            }
            // Rounded to the picometre so 0.2 nm steps give 8.6 nm, not 8.600000000000001.
            (0..=n)
                .map(|i| ((a + i as f64 * s) * 1e12).round() / 1e12)
                .collect()
        }
    };
    if actuations.is_empty() {
        return bad("actuations", "no actuation to simulate");
    }
    if let Some(a) = actuations.iter().find(|a| !(**a >= 0.0 && **a <= max)) {
        let key = if cfg.actuations.is_some() {
            "actuations"
        } else if *a < 0.0 {
            "actuation_start"
        } else {
            "actuation_stop"
        };
        return bad(
            key,
            format!(
                "{} nm is outside the model's range 0 … {} nm",
                a * 1e9,
                max * 1e9
            ),
        );
    }
    Ok(actuations)
}

/// `contact_force`, `integrator` and `init`: the choices among named forms.
fn check_forms(
    cfg: &SimulateConfig,
) -> std::result::Result<(ContactForceForm, Integrator, bool), KeyError> {
    let contact_force = match cfg.contact_force.as_str() {
        "interference_tangent" => ContactForceForm::InterferenceTangent,
        "static_curve" => ContactForceForm::StaticCurve,
        "integrated_stiffness" => ContactForceForm::IntegratedStiffness,
        o => {
            return bad(
                "contact_force",
                format!("unknown `{o}` (interference_tangent, static_curve, integrated_stiffness)"),
            )
        }
    };
    let integrator = match cfg.integrator.as_str() {
        "dopri5" => Integrator::Dopri5 {
            rtol: cfg.rtol,
            contact_max_step: cfg.contact_max_step.0,
            max_step: cfg.max_step.0,
        },
        "rk5_fixed" => Integrator::Rk5Fixed {
            step: cfg.fixed_step.0,
        },
        o => return bad("integrator", format!("unknown `{o}` (dopri5, rk5_fixed)")),
    };
    let static_init = match cfg.init.as_str() {
        "nominal" => false,
        "static" => true,
        o => return bad("init", format!("unknown `{o}` (nominal, static)")),
    };
    Ok((contact_force, integrator, static_init))
}

/// `lubricant`: the lubricant layer's force (docs/model-form.md). The MTL law puts solid
/// contact at 3σ, so it needs the improved model's criterion.
fn check_lubricant(cfg: &SimulateConfig) -> std::result::Result<LubricantForce, KeyError> {
    match cfg.lubricant.as_str() {
        "none" => Ok(LubricantForce::None),
        "mtl" if cfg.model == "initial_2dof" => bad(
            "lubricant",
            "`mtl` needs model = \"improved_2dof\" (the MTL law puts solid contact at 3σ)",
        ),
        "mtl" => Ok(LubricantForce::Mtl),
        o => bad("lubricant", format!("unknown `{o}` (none, mtl)")),
    }
}

/// The integrator options: the named forms, `initial_heave`, `duration`, `steady_start`, then
/// the remaining numbers (rtol, steps, output step), which the case checks with their ranges.
fn check_options(cfg: &SimulateConfig) -> std::result::Result<SimOptions, KeyError> {
    let (contact_force, integrator, static_init) = check_forms(cfg)?;
    let lubricant = check_lubricant(cfg)?;
    let z0 = cfg.initial_heave.map_or(0.0, |l| l.0);
    if !(z0.is_finite() && z0.abs() <= 5e-9) {
        return bad(
            "initial_heave",
            format!("{z0} m is out of range: |z0| ≤ 5 nm"),
        );
    }
    let options = SimOptions {
        static_init,
        duration: cfg.duration.0,
        output_step: cfg.output_step.0,
        contact_force,
        lubricant,
        integrator,
        transit_delay: cfg.transit_delay,
        wrap_dmw: cfg.dmw_wrap,
        initial_state: [z0, 0.0, 0.0, 0.0],
        static_start: None,
    };
    if !(cfg.duration.0 > 0.0 && cfg.duration.0 <= 0.1) {
        return bad(
            "duration",
            format!("{} s is out of range: 0 < T ≤ 100 ms", cfg.duration.0),
        );
    }
    if !(cfg.steady_start.0 >= 0.0 && cfg.steady_start.0 < 0.9 * cfg.duration.0) {
        return bad(
            "steady_start",
            "must lie in [0, 0.9·duration): the steady window needs samples",
        );
    }
    if let Err(e) = options.validate().map_err(|e| e.to_string()) {
        let key = if e.contains("rtol") {
            "rtol"
        } else if e.contains("contact_max_step") {
            "contact_max_step"
        } else if e.contains("max_step") {
            "max_step"
        } else if e.contains("fixed step") {
            "fixed_step"
        } else {
            "output_step"
        };
        return bad(key, e);
    }
    Ok(options)
}

impl SimulateParams {
    /// Check a `[simulate]` table key by key (no cross-references to other instances): the
    /// model, its actuations, then the integrator options.
    pub fn check(cfg: &SimulateConfig) -> std::result::Result<SimulateParams, KeyError> {
        let model = check_model(cfg)?;
        let powers = check_powers(cfg)?;
        let actuations = if powers.is_some() {
            Vec::new()
        } else {
            check_actuations(cfg, model.max_actuation)?
        };
        let options = check_options(cfg)?;
        let branches = Branch::parse(cfg.branches.as_deref(), options.static_init)
            .map_err(|m| KeyError::new("branches", m))?;
        let (geometry, bulge) = match &cfg.geometry {
            GeometryConfig::Named(n) => (n.clone(), None),
            GeometryConfig::Bulge { bulge } => (format!("bulge:{bulge}"), Some(bulge.clone())),
        };
        let dmw = (cfg.dmw != "none").then(|| cfg.dmw.clone());
        let contact_bem = match (
            cfg.contact_law.as_deref().unwrap_or("isbl"),
            &cfg.contact_bem,
        ) {
            ("isbl", None) => None,
            ("bem", Some(b)) => Some(b.clone()),
            ("bem", None) => {
                return Err(KeyError::new(
                    "contact_bem",
                    "contact_law = \"bem\" needs contact_bem = the [contact_bem.*] instance",
                ))
            }
            ("isbl", Some(_)) => {
                return Err(KeyError::new(
                    "contact_bem",
                    "is read only with contact_law = \"bem\"",
                ))
            }
            (other, _) => {
                return Err(KeyError::new(
                    "contact_law",
                    format!("`{other}`: use isbl or bem"),
                ))
            }
        };
        Ok(SimulateParams {
            model_name: cfg.model.clone(),
            model,
            contact: cfg.contact.clone(),
            contact_bem,
            dmw,
            actuations,
            options,
            steady_start: cfg.steady_start.0,
            histories: cfg.histories.iter().map(|l| l.0).collect(),
            geometry,
            calibration: cfg.calibration.clone(),
            calibrated_knobs: Vec::new(),
            bulge,
            powers,
            efficiency: None,
            branches,
            refine_touchdown: cfg.refine_touchdown,
        })
    }
    /// Canonical parameters of the whole stage instance (its cache key).
    pub fn canonical(&self) -> Value {
        let mut v = json!({
            "model": self.model_name,
            "geometry": self.geometry,
            "model_parameters": self.model,
            "contact": self.contact,
            "dmw": self.dmw,
            "actuations_m": self.actuations,
            "options": self.options,
            "steady_start_s": self.steady_start,
            "histories_m": self.histories,
            "calibration": self.calibration,
        });
        if let (false, Some(obj)) = (self.branches.is_empty(), v.as_object_mut()) {
            obj.insert("branches".into(), json!(self.branches));
        }
        if let (false, Some(obj)) = (self.refine_touchdown, v.as_object_mut()) {
            obj.insert("refine_touchdown".into(), json!(false));
        }
        // Only instances with the BEM law carry it: the others keep their keys.
        if let (Some(b), Some(obj)) = (&self.contact_bem, v.as_object_mut()) {
            obj.insert("contact_bem".into(), json!(b));
        }
        // Only instances with a fitted bulge carry these keys: the others keep their keys.
        if let (Some(b), Some(obj)) = (&self.bulge, v.as_object_mut()) {
            obj.insert("bulge".into(), json!(b));
            obj.insert("powers_W".into(), json!(self.powers));
        }
        v
    }

    pub fn case_params(&self, actuation: f64, contact_key: &str, dmw_key: Option<&str>) -> Value {
        // `model_parameters` carries the calibrated model; the DMW scale and the calibrated
        // interface enter through `calibrated_knobs`.
        json!({
            "calibrated_knobs": self.calibrated_knobs,
            "model_parameters": self.model,
            "actuation_m": actuation,
            "options": self.options,
            "steady_start_s": self.steady_start,
            "contact_key": contact_key,
            "dmw_key": dmw_key,
        })
    }

    pub fn case_metric_params(&self) -> CaseParams {
        CaseParams {
            window: SteadyWindow {
                start_s: self.steady_start,
                end_s: self.options.duration,
            },
            fh_nom_m: self.model.nominal_flying_height,
            t0_m: 0.5 * self.model.interface.lubricant_thickness,
            ..CaseParams::improved_2dof()
        }
    }

    /// A `[simulate.NAME]` table checked, and its references to other instances (contact,
    /// calibration, DMW) resolved against the file; errors name the instance's key.
    pub fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &SimulateConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let params = SimulateParams::check(cfg).map_err(|e| e.locate(file, "simulate", name))?;
        if !file.has_instance("contact", &cfg.contact) {
            return Err(file.error(
                "simulate",
                name,
                "contact",
                format!("no [contact.{}] in this file", cfg.contact),
            ));
        }
        if let Some(b) = &params.contact_bem {
            if !file.has_instance("contact_bem", b) {
                return Err(file.error(
                    "simulate",
                    name,
                    "contact_bem",
                    format!("no [contact_bem.{b}] in this file"),
                ));
            }
        }
        if let Some(c) = &params.calibration {
            let Some(cal) = file.instance::<CalibrateTarget>("calibrate", c)? else {
                return Err(file.error(
                    "simulate",
                    name,
                    "calibration",
                    format!("no [calibrate.{c}] in this file"),
                ));
            };
            if cal.simulate == name {
                return Err(file.error(
                    "simulate",
                    name,
                    "calibration",
                    format!("[calibrate.{c}] calibrates this instance; run the calibrated sweep as a second [simulate] instance"),
                ));
            }
        }
        if let Some(b) = &params.bulge {
            if !file.has_instance("bulge", b) {
                return Err(file.error(
                    "simulate",
                    name,
                    "geometry",
                    format!("no [bulge.{b}] in this file"),
                ));
            }
        }
        if let Some(d) = &params.dmw {
            if !file.has_instance("dmw", d) && !file.has_instance("excitation", d) {
                return Err(file.error(
                    "simulate",
                    name,
                    "dmw",
                    format!("no [dmw.{d}] or [excitation.{d}] in this file (or \"none\")"),
                ));
            }
        }
        Ok(params)
    }

    /// The instances whose results the cases need: contact, DMW, calibration.
    pub fn upstream(&self) -> Vec<String> {
        let mut u = vec![self.contact.clone()];
        u.extend(self.contact_bem.iter().cloned());
        u.extend(self.dmw.iter().cloned());
        u.extend(self.calibration.iter().cloned());
        u.extend(self.bulge.iter().cloned());
        u
    }

    /// Apply a fitted bulge (docs/bulge.md): its a, w, x_TFC replace the geometry, and a
    /// power sweep gets its actuations = efficiency × power. The unpowered bulge (the
    /// intercept) does not add: the 2-DOF actuation is the height the heater adds above the
    /// slider as it flies unpowered, whose nominal flying height already includes it.
    pub fn apply_bulge(
        &mut self,
        fitted: &crate::artefacts::bulge::FittedBulge,
        name: &str,
    ) -> crate::error::Result<()> {
        use crate::error::Error;
        let missing = |what: &str| Error::UpstreamField {
            kind: "bulge",
            name: name.to_string(),
            what: what.to_string(),
        };
        let x = fitted
            .x_tfc_m
            .ok_or_else(|| missing("x_TFC (no trailing edge detected)"))?;
        let design = crate::dynamics::geometry::BulgeDesign {
            semi_width_x: fitted.a_tfc_m,
            full_width_y: fitted.w_tfc_m,
            offset_from_te: x,
        };
        design.validate()?;
        self.model = self.model.with_bulge(design);
        if let Some(powers) = &self.powers {
            let eff = fitted
                .efficiency_m_per_w
                .filter(|e| *e > 0.0 && e.is_finite())
                .ok_or_else(|| missing("positive efficiency (scans at two or more powers)"))?;
            let max = self.model.max_actuation;
            let mut acts = Vec::with_capacity(powers.len());
            for p in powers {
                // Picometre-rounded, as the actuation ranges are.
                let a = (eff * p * 1e12).round() / 1e12;
                if !(0.0..=max).contains(&a) {
                    return Err(missing(&format!(
                        "actuation within the model's range at {:.1} mW ({:.2} nm > {:.2} nm)",
                        p * 1e3,
                        a * 1e9,
                        max * 1e9
                    )));
                }
                acts.push(a);
            }
            self.actuations = acts;
            self.efficiency = Some(eff);
        }
        Ok(())
    }

    /// The heater power (W) of the case at `actuation` in a power sweep.
    pub fn power_of(&self, actuation: f64) -> Option<f64> {
        let powers = self.powers.as_ref()?;
        let k = self.actuations.iter().position(|a| *a == actuation)?;
        powers.get(k).copied()
    }
}

/// A continuation branch of a static-start sweep (docs/conventions.md): `Up` steps the
/// static equilibrium along increasing actuation from the nominal state at the lowest one,
/// `Down` along decreasing actuation from the highest; near the adhesion fold, where there
/// are several equilibria, the two can differ (hysteresis).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Branch {
    Up,
    Down,
}

impl Branch {
    pub fn name(self) -> &'static str {
        match self {
            Branch::Up => "up",
            Branch::Down => "down",
        }
    }

    /// The `branches` key: `both` (default with static init), `up`, `down`; with the nominal
    /// start (`static_init` false) there are no branches and the key is an error.
    pub fn parse(
        value: Option<&str>,
        static_init: bool,
    ) -> std::result::Result<Vec<Branch>, String> {
        match (value, static_init) {
            (None, false) => Ok(Vec::new()),
            (Some(_), false) => Err("only with init = \"static\" (continuation sweeps); \
                                     init = \"nominal\" is one sweep"
                .into()),
            (None | Some("both"), true) => Ok(vec![Branch::Up, Branch::Down]),
            (Some("up"), true) => Ok(vec![Branch::Up]),
            (Some("down"), true) => Ok(vec![Branch::Down]),
            (Some(o), true) => Err(format!("unknown `{o}` (both, up, down)")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(toml_text: &str) -> SimulateParams {
        let cfg: SimulateConfig = toml::from_str(toml_text).unwrap();
        SimulateParams::check(&cfg).unwrap()
    }

    #[test]
    fn named_geometries_keep_their_canonical_keys() {
        // The keys the instance's cache key was built from before the bulge geometry existed:
        // a named geometry must not gain any (its cached outputs stay valid).
        let before = [
            "model",
            "geometry",
            "model_parameters",
            "contact",
            "dmw",
            "actuations_m",
            "options",
            "steady_start_s",
            "histories_m",
            "calibration",
        ];
        for g in ["dissertation", "optimised"] {
            let p = params(&format!("contact = \"c\"\ngeometry = \"{g}\""));
            let c = p.canonical();
            let keys: Vec<&str> = c.as_object().unwrap().keys().map(|k| k.as_str()).collect();
            assert_eq!(keys, before);
            assert_eq!(c["geometry"], g);
            assert!(p.bulge.is_none() && p.powers.is_none());
        }
    }

    #[test]
    fn bulge_geometry_and_power_sweep() {
        let p = params(
            "contact = \"c\"\ngeometry = { bulge = \"tfc\" }\npower_stop = \"30 mW\"\npower_step = \"7.5 mW\"",
        );
        assert_eq!(p.bulge.as_deref(), Some("tfc"));
        assert_eq!(p.powers, Some(vec![0.0, 0.0075, 0.015, 0.0225, 0.03]));
        assert!(p.actuations.is_empty());
        let mut q = p.clone();
        // A fit that found exactly the optimised design (§2.3) must give that model.
        let opt = params("contact = \"c\"\ngeometry = \"optimised\"");
        let b = opt.model.bulge;
        let fitted = crate::artefacts::bulge::FittedBulge {
            a_tfc_m: b.semi_width_x,
            w_tfc_m: b.full_width_y,
            x_tfc_m: Some(b.offset_from_te),
            efficiency_m_per_w: Some(0.3e-6),
            intercept_m: Some(3e-9),
        };
        q.apply_bulge(&fitted, "tfc").unwrap();
        // 0.3 nm/mW × 7.5 mW steps = 2.25 nm steps; no intercept added.
        assert_eq!(q.actuations, vec![0.0, 2.25e-9, 4.5e-9, 6.75e-9, 9e-9]);
        assert_eq!(q.power_of(4.5e-9), Some(0.015));
        assert_eq!(q.model, opt.model);
        let bad = |t: &str| SimulateParams::check(&toml::from_str(t).unwrap()).is_err();
        // contact_law: bem needs its instance, isbl refuses one, other values are refused.
        let law = params("contact = \"c\"\ncontact_law = \"bem\"\ncontact_bem = \"b\"");
        assert_eq!(law.contact_bem.as_deref(), Some("b"));
        assert_eq!(law.canonical()["contact_bem"], "b");
        assert!(params("contact = \"c\"")
            .canonical()
            .get("contact_bem")
            .is_none());
        assert!(bad("contact = \"c\"\ncontact_law = \"bem\""));
        assert!(bad("contact = \"c\"\ncontact_bem = \"b\""));
        assert!(bad("contact = \"c\"\ncontact_law = \"gw\""));
        // Powers need a bulge; both lists at once are an error.
        assert!(bad("contact = \"c\"\npowers = [\"10 mW\"]"));
        assert!(bad(
            "contact = \"c\"\ngeometry = { bulge = \"t\" }\npowers = [\"10 mW\"]\nactuations = [\"1 nm\"]"
        ));
        assert!(bad(
            "contact = \"c\"\ngeometry = { bulge = \"t\" }\nbulge_width = \"40 um\""
        ));
        // A power beyond the model's actuation range is an error at run time.
        let mut far = params("contact = \"c\"\ngeometry = { bulge = \"t\" }\npowers = [\"10 W\"]");
        assert!(far.apply_bulge(&fitted, "t").is_err());
    }

    #[test]
    fn model_form_switches_parse_and_refuse_unknown_values() {
        let base = "contact = \"c\"\n";
        let p = params(&format!(
            "{base}lubricant = \"mtl\"\ncontact_force = \"integrated_stiffness\""
        ));
        assert_eq!(p.options.lubricant, LubricantForce::Mtl);
        assert_eq!(
            p.options.contact_force,
            ContactForceForm::IntegratedStiffness
        );
        assert_eq!(params(base).options.lubricant, LubricantForce::None);
        let err = |text: &str| {
            let cfg: SimulateConfig = toml::from_str(text).unwrap();
            SimulateParams::check(&cfg).unwrap_err()
        };
        let e = err(&format!("{base}lubricant = \"grease\""));
        assert_eq!(e.key, "lubricant");
        assert!(e.message.contains("grease") && e.message.contains("mtl"));
        let e = err(&format!(
            "{base}model = \"initial_2dof\"\nlubricant = \"mtl\""
        ));
        assert_eq!(e.key, "lubricant");
        let e = err(&format!("{base}contact_force = \"secant\""));
        assert_eq!(e.key, "contact_force");
        assert!(e.message.contains("integrated_stiffness"));
    }
}
