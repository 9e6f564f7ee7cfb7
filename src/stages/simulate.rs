//! Simulation stage: 2-DOF slider cases (dynamics.md §5.1, §7 S1/S2/S2o) over an actuation
//! sweep, each case cached by content hash (`core::cases`), run in parallel with a progress
//! bar; per-case HDF5 time histories, the sweep table, the flyability metrics of §8 and the
//! dissertation's plots (Figs 2.13–2.14, 2.16–2.19, 2.22).

use super::{FromConfig, StageContext, StageKind, StageOutput};
use crate::contact::isbl::IsblModel;
use crate::contact::lookup::IsblLookup;
use crate::core::cases::{self, CaseEntry};
use crate::core::config::{ConfigError, PipelineFile};
use crate::core::store::H5Out;
use crate::core::units::{Length, TimeSpan};
use crate::dynamics::air_bearing::RearStiffening;
use crate::dynamics::metrics::{
    sweep_metrics, CaseMetrics, CaseParams, Regime, SlopeParams, SteadyWindow, SweepMetrics,
    SweepPoint,
};
use crate::dynamics::params::{improved_2dof, initial_2dof, optimised_bulge, Model2Dof};
use crate::dynamics::two_dof::{
    CaseHistory, ContactForceForm, DmwInput, Integrator, SimOptions, TwoDofCase,
};
use crate::error::{Error, Result};
use serde::Deserialize;
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};

/// Bump when the numbers a case produces change.
pub const MODEL_VERSION: &str = "simulate-2";

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
fn default_geometry() -> String {
    "dissertation".into()
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
    /// `interference_tangent` (default, eq. 2.16 as written) or `static_curve`.
    #[serde(default = "default_contact_force")]
    pub contact_force: String,
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
    pub geometry: String,
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
    pub dmw: Option<String>,
    pub actuations: Vec<f64>,
    pub options: SimOptions,
    pub steady_start: f64,
    pub histories: Vec<f64>,
    pub geometry: String,
    pub calibration: Option<String>,
    /// The fitted knob values applied at run time (empty without calibration).
    pub calibrated_knobs: Vec<(String, f64)>,
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
    let Some(cfg) = &file.instance::<SimulateConfig>("simulate", base)? else {
        return Err(err(format!("no [simulate.{base}] in this file")));
    };
    if cfg.calibration.is_some() {
        return Err(err(format!(
            "[simulate.{base}] is itself calibrated; [{section}] starts from an uncalibrated \
             instance"
        )));
    }
    validate(cfg).map_err(|(k, m)| err(format!("[simulate.{base}] is invalid ({k}: {m})")))
}

/// Validation failures: (key, message).
pub fn validate(cfg: &SimulateConfig) -> std::result::Result<SimulateParams, (String, String)> {
    let bad = |k: &str, m: String| Err((k.to_string(), m));
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
    match cfg.geometry.as_str() {
        "dissertation" => {
            if cfg.bulge_width.is_some() {
                return bad(
                    "bulge_width",
                    "only used with geometry = \"optimised\"".into(),
                );
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
    let max = model.max_actuation;
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
        return bad("actuations", "no actuation to simulate".into());
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
    let contact_force = match cfg.contact_force.as_str() {
        "interference_tangent" => ContactForceForm::InterferenceTangent,
        "static_curve" => ContactForceForm::StaticCurve,
        o => {
            return bad(
                "contact_force",
                format!("unknown `{o}` (interference_tangent, static_curve)"),
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
        integrator,
        transit_delay: cfg.transit_delay,
        wrap_dmw: cfg.dmw_wrap,
        initial_state: [z0, 0.0, 0.0, 0.0],
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
            "must lie in [0, 0.9·duration): the steady window needs samples".into(),
        );
    }
    // The case checks the remaining numbers (rtol, steps, output step) with their ranges.
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
    let dmw = (cfg.dmw != "none").then(|| cfg.dmw.clone());
    Ok(SimulateParams {
        model_name: cfg.model.clone(),
        model,
        contact: cfg.contact.clone(),
        dmw,
        actuations,
        options,
        steady_start: cfg.steady_start.0,
        histories: cfg.histories.iter().map(|l| l.0).collect(),
        geometry: cfg.geometry.clone(),
        calibration: cfg.calibration.clone(),
        calibrated_knobs: Vec::new(),
    })
}

impl SimulateParams {
    /// Canonical parameters of the whole stage instance (its cache key).
    pub fn canonical(&self) -> Value {
        json!({
            "model": self.model_name,
            "geometry": self.geometry,
            "model_parameters": format!("{:?}", self.model),
            "contact": self.contact,
            "dmw": self.dmw,
            "actuations_m": self.actuations,
            "options": format!("{:?}", self.options),
            "steady_start_s": self.steady_start,
            "histories_m": self.histories,
            "calibration": self.calibration,
        })
    }

    pub fn case_params(&self, actuation: f64, contact_key: &str, dmw_key: Option<&str>) -> Value {
        // `model_parameters` carries the calibrated model; the DMW scale and the calibrated
        // interface enter through `calibrated_knobs`.
        json!({
            "calibrated_knobs": self.calibrated_knobs,
            "model_parameters": format!("{:?}", self.model),
            "actuation_m": actuation,
            "options": format!("{:?}", self.options),
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
}

/// A DMW track as the simulations use it: the transient-free part of track 1.
pub struct DmwTrack {
    pub displacement: Vec<f64>,
    pub velocity: Vec<f64>,
    pub sample_rate: f64,
}

/// Read track 1 of a DMW stage's `dmw.h5`, without the filter's edge transients.
pub fn read_dmw_track(path: &Path) -> Result<DmwTrack> {
    read_dmw_track_named(path, 1)
}

/// Tracks 1–3 (original, flipped, negated flipped) of a `dmw.h5`, edge transients dropped.
pub fn read_dmw_tracks(path: &Path) -> Result<[DmwTrack; 3]> {
    Ok([
        read_dmw_track_named(path, 1)?,
        read_dmw_track_named(path, 2)?,
        read_dmw_track_named(path, 3)?,
    ])
}

/// Track `k` (1–3) of a `dmw.h5`: `D{k}`, `V{k}`, without the filter's edge transients.
fn read_dmw_track_named(path: &Path, k: usize) -> Result<DmwTrack> {
    let e = |m: String| Error::Stage(format!("{}: {m}", path.display()));
    let file = hdf5::File::open(path).map_err(|x| e(x.to_string()))?;
    let read = |name: &str| -> Result<Vec<f64>> {
        file.dataset(&format!("dmw/tracks/{name}"))
            .and_then(|d| d.read_raw::<f64>())
            .map_err(|x| e(format!("dmw/tracks/{name}: {x}")))
    };
    let (d, v) = (read(&format!("D{k}"))?, read(&format!("V{k}"))?);
    let edge: Vec<u8> = file
        .dataset("dmw/tracks/edge_transient")
        .and_then(|d| d.read_raw::<u8>())
        .unwrap_or_default();
    let time = file
        .dataset("dmw/tracks/time")
        .map_err(|x| e(format!("dmw/tracks/time: {x}")))?;
    let fs = time
        .attr("sampling_rate")
        .and_then(|a| a.read_scalar::<f64>())
        .map_err(|x| e(format!("sampling_rate attribute: {x}")))?;
    if d.len() != v.len() || d.len() < 2 || fs.is_nan() || fs <= 0.0 {
        return Err(e("inconsistent track datasets".into()));
    }
    // Keep the samples outside the marked edge transients.
    let first = edge.iter().position(|&b| b == 0).unwrap_or(0);
    let last = edge
        .iter()
        .rposition(|&b| b == 0)
        .map_or(d.len(), |i| i + 1);
    let (first, last) = if edge.len() == d.len() && last > first + 1 {
        (first, last)
    } else {
        (0, d.len())
    };
    Ok(DmwTrack {
        displacement: d[first..last].to_vec(),
        velocity: v[first..last].to_vec(),
        sample_rate: fs,
    })
}

/// One finished case: its actuation, metrics, and where its files are.
pub struct CaseOutcome {
    pub actuation: f64,
    pub metrics: Value,
    pub entry: CaseEntry,
}

/// Simulate one case and write its HDF5 (time histories) into `dir`; returns its result.
pub fn simulate_case(
    p: &SimulateParams,
    actuation: f64,
    isbl: &IsblLookup,
    dmw: Option<&DmwTrack>,
    dir: &Path,
) -> Result<Value> {
    let input = dmw.map(|t| DmwInput {
        displacement: &t.displacement,
        velocity: &t.velocity,
        sample_rate: t.sample_rate,
    });
    let case = TwoDofCase::new(&p.model, actuation, isbl, input, p.options)?;
    let started = std::time::Instant::now();
    let h = case.run()?;
    let seconds = started.elapsed().as_secs_f64();
    let m = h.metrics(&p.case_metric_params())?;
    write_case_h5(&dir.join("case.h5"), &h, actuation, &m)?;
    Ok(case_json(
        actuation,
        &h,
        &m,
        seconds,
        case.contact_damping(),
    ))
}

fn stats_json(s: &crate::dynamics::metrics::SeriesStats) -> Value {
    json!({"mean": s.mean, "std": s.std, "min": s.min, "max": s.max})
}

fn case_json(actuation: f64, h: &CaseHistory, m: &CaseMetrics, seconds: f64, c_c: f64) -> Value {
    let c = m.contact.as_ref();
    let opt = |v: Option<f64>| v.filter(|x| x.is_finite());
    json!({
        "actuation_m": actuation,
        "nominal_area_m2": h.nominal_area,
        "contact_damping_N_s_per_m": c_c,
        "clearance_m": stats_json(&m.clearance_m),
        "fh_m": stats_json(&m.fh_m),
        "hms_mean_m": m.hms_mean_m,
        "vibration_percent": m.vibration.percent,
        "vibration_extrema_percent": m.vibration_extrema.as_ref().map(|v| v.percent),
        "vibration_kind": format!("{:?}", m.vibration_kind),
        "percent_solid_contact": m.percent_solid_contact,
        "regime": format!("{:?}", m.regime),
        "contact_force_N": c.map(|c| stats_json(&c.contact_force_n)),
        "friction_N": c.map(|c| stats_json(&c.friction_n)),
        "real_area_m2": c.map(|c| stats_json(&c.real_area_m2)),
        "adhesion_N": c.and_then(|c| c.adhesion_n.as_ref().map(stats_json)),
        "friction_coefficient": c.and_then(|c| c.friction_coefficient.as_ref().map(|s| s.mean)),
        "friction_coefficient_ratio_of_means": c.and_then(|c| opt(c.friction_coefficient_ratio_of_means)),
        "mean_pressure_Pa": c.and_then(|c| c.mean_pressure_pa.as_ref().map(|s| s.mean)),
        "shear_traction_Pa": c.and_then(|c| c.shear_traction_pa.as_ref().map(|s| s.mean)),
        "clipped_samples": h.clipped_samples,
        "steps": h.stats.accepted_steps,
        "rejected_steps": h.stats.rejected_steps,
        "rhs_evaluations": h.stats.rhs_evaluations,
        "wall_time_s": seconds,
    })
}

fn write_case_h5(path: &Path, h: &CaseHistory, actuation: f64, m: &CaseMetrics) -> Result<()> {
    let out = H5Out::create(path)?;
    let entry = out.group("case", Some("NXentry"))?;
    out.attr_str(&entry, "default", "history")?;
    out.write_scalar(&entry, "actuation", actuation, "m", "TFC actuation h_TFC")?;
    out.write_scalar(
        &entry,
        "nominal_area",
        h.nominal_area,
        "m^2",
        "bulge nominal contact area",
    )?;
    out.write_scalar(
        &entry,
        "clearance_mean",
        m.clearance_m.mean,
        "m",
        "steady mean clearance",
    )?;
    out.write_scalar(
        &entry,
        "vibration",
        m.vibration.percent,
        "%",
        "FHM/BV (eq. 2.1) over the steady window",
    )?;
    let g = out.history_group("case/history", "clearance", h.dt, h.len())?;
    for (name, data, unit, what) in [
        ("heave", &h.heave, "m", "COM heave from the nominal state"),
        ("pitch_offset", &h.pitch_offset, "rad", "pitch θ − θ0"),
        ("heave_rate", &h.heave_rate, "m/s", "dz/dt"),
        ("pitch_rate", &h.pitch_rate, "rad/s", "dθ/dt"),
        (
            "spacing",
            &h.spacing,
            "m",
            "solid spacing s of the bulge POC",
        ),
        (
            "clearance",
            &h.clearance,
            "m",
            "clearance (negative: solid contact)",
        ),
        (
            "flying_height",
            &h.flying_height,
            "m",
            "flying height of the POC",
        ),
        (
            "contact_force",
            &h.contact_force,
            "N",
            "dynamic contact force F_c",
        ),
        ("friction", &h.friction, "N", "friction Q"),
        ("adhesion", &h.adhesion, "N", "adhesion F_s"),
        ("real_area", &h.real_area, "m^2", "real contact area A_r"),
        (
            "disk_displacement",
            &h.disk_displacement,
            "m",
            "DMW under the POC",
        ),
        (
            "trailing_edge_spacing",
            &h.trailing_edge_spacing,
            "m",
            "solid spacing of the TE",
        ),
    ] {
        out.write_1d(&g, name, data, unit, what)?;
    }
    out.finish()
}

/// Named series of a case file.
pub type NamedSeries = Vec<(String, Vec<f64>)>;

/// Read a case's histories back (for plots of chosen actuations): time and named series.
pub fn read_case_history(path: &Path) -> Result<(Vec<f64>, NamedSeries)> {
    let e = |m: String| Error::Stage(format!("{}: {m}", path.display()));
    let file = hdf5::File::open(path).map_err(|x| e(x.to_string()))?;
    let read = |name: &str| -> Result<Vec<f64>> {
        file.dataset(&format!("case/history/{name}"))
            .and_then(|d| d.read_raw::<f64>())
            .map_err(|x| e(format!("{name}: {x}")))
    };
    let time = read("time")?;
    let mut out = Vec::new();
    for n in [
        "clearance",
        "contact_force",
        "friction",
        "adhesion",
        "real_area",
    ] {
        out.push((n.to_string(), read(n)?));
    }
    Ok((time, out))
}

/// The sweep-level analysis of finished cases (sorted by actuation).
pub fn sweep_analysis(p: &SimulateParams, cases: &[CaseOutcome]) -> Result<SweepMetrics> {
    let points: Vec<SweepPoint> = cases
        .iter()
        .map(|c| SweepPoint {
            actuation_m: c.actuation,
            mean_clearance_m: c.metrics["clearance_m"]["mean"]
                .as_f64()
                .unwrap_or(f64::NAN),
            any_solid_contact: c.metrics["percent_solid_contact"].as_f64().unwrap_or(0.0) > 0.0,
            vibration_percent: c.metrics["vibration_percent"].as_f64().unwrap_or(f64::NAN),
        })
        .collect();
    let t0 = 0.5 * p.model.interface.lubricant_thickness;
    sweep_metrics(
        &points,
        &SlopeParams::new(t0),
        p.model.nominal_flying_height,
    )
    .map_err(|e| Error::Stage(format!("sweep metrics: {e}")))
}

fn regime_name(r: Regime) -> &'static str {
    match r {
        Regime::Flying => "flying",
        Regime::MobileLubricantContact => "mobile lubricant",
        Regime::BondedLubricantContact => "bonded lubricant",
        Regime::SolidContact => "solid contact",
    }
}

/// One table row per case (unit suffixes in the names).
pub fn case_rows(cases: &[CaseOutcome], sweep: &SweepMetrics) -> Vec<Map<String, Value>> {
    cases
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let m = &c.metrics;
            let f = |v: &Value, scale: f64| v.as_f64().map(|x| x * scale);
            let mut r = Map::new();
            // Rounded to the femtometre: 8.8 nm, not 8.799999999999999.
            r.insert(
                "actuation_nm".into(),
                json!((c.actuation * 1e15).round() / 1e6),
            );
            r.insert(
                "clearance_mean_nm".into(),
                json!(f(&m["clearance_m"]["mean"], 1e9)),
            );
            r.insert(
                "clearance_std_nm".into(),
                json!(f(&m["clearance_m"]["std"], 1e9)),
            );
            r.insert("fh_mean_nm".into(), json!(f(&m["fh_m"]["mean"], 1e9)));
            r.insert("hms_mean_nm".into(), json!(f(&m["hms_mean_m"], 1e9)));
            r.insert("vibration_percent".into(), m["vibration_percent"].clone());
            r.insert(
                "vibration_extrema_percent".into(),
                m["vibration_extrema_percent"].clone(),
            );
            r.insert("vibration_kind".into(), m["vibration_kind"].clone());
            r.insert(
                "solid_contact_percent".into(),
                m["percent_solid_contact"].clone(),
            );
            r.insert(
                "regime".into(),
                json!(sweep.regimes.get(i).map(|r| regime_name(*r))),
            );
            r.insert(
                "contact_force_mean_mN".into(),
                json!(f(&m["contact_force_N"]["mean"], 1e3)),
            );
            r.insert(
                "friction_mean_mN".into(),
                json!(f(&m["friction_N"]["mean"], 1e3)),
            );
            r.insert(
                "adhesion_mean_mN".into(),
                json!(f(&m["adhesion_N"]["mean"], 1e3)),
            );
            r.insert(
                "real_area_mean_um2".into(),
                json!(f(&m["real_area_m2"]["mean"], 1e12)),
            );
            r.insert(
                "friction_coefficient".into(),
                m["friction_coefficient"].clone(),
            );
            r.insert(
                "mean_pressure_GPa".into(),
                json!(f(&m["mean_pressure_Pa"], 1e-9)),
            );
            r.insert(
                "shear_traction_GPa".into(),
                json!(f(&m["shear_traction_Pa"], 1e-9)),
            );
            r.insert(
                "nominal_area_um2".into(),
                json!(f(&m["nominal_area_m2"], 1e12)),
            );
            r.insert("flyability".into(), json!(sweep.flyability.get(i)));
            r.insert("steps".into(), m["steps"].clone());
            r.insert("case_key".into(), json!(c.entry.key));
            r
        })
        .collect()
}

fn sweep_json(cases: &[CaseOutcome], s: &SweepMetrics) -> Value {
    let line = |l: &Option<crate::dynamics::metrics::LineFit>| {
        l.as_ref().map(|l| {
            json!({
                "slope": l.slope, "intercept_m": l.intercept_m, "rms_residual_m": l.rms_residual_m,
                "actuations_m": l.indices.iter().map(|&i| cases[i].actuation).collect::<Vec<_>>(),
            })
        })
    };
    json!({
        "touchdown_m": s.touchdown_actuation_m,
        "critical_point": s.slopes.critical_point.as_ref().map(|c| json!({
            "actuation_m": c.actuation_m, "clearance_m": c.clearance_m,
        })),
        "slope_A": line(&s.slopes.a),
        "slope_B": line(&s.slopes.b),
        "slope_C": line(&s.slopes.c),
        "slope_D": line(&s.slopes.d),
        "optimum_m": s.optimum_index.map(|i| cases[i].actuation),
        "regimes": cases.iter().zip(&s.regimes).map(|(c, r)| json!({
            "actuation_m": c.actuation, "regime": regime_name(*r),
        })).collect::<Vec<_>>(),
    })
}

/// Contiguous runs of the same regime as (x0, x1, regime) bands, x in nm, edges halfway
/// between neighbouring cases.
fn regime_bands(cases: &[CaseOutcome], s: &SweepMetrics) -> Vec<(f64, f64, Regime)> {
    let x: Vec<f64> = cases.iter().map(|c| c.actuation * 1e9).collect();
    let mut bands = Vec::new();
    let mut start = 0;
    for i in 1..=x.len() {
        if i == x.len() || s.regimes[i] != s.regimes[start] {
            let lo = if start == 0 {
                x[0]
            } else {
                0.5 * (x[start - 1] + x[start])
            };
            let hi = if i == x.len() {
                x[i - 1]
            } else {
                0.5 * (x[i - 1] + x[i])
            };
            bands.push((lo, hi, s.regimes[start]));
            start = i;
        }
    }
    bands
}

/// Figs 2.16/2.18 (clearance ± std with regimes), 2.19 (FHM/BV), 2.22 (% solid contact) and
/// time histories at the chosen actuations (Figs 2.13–2.14, 2.17).
pub fn plots(
    dir: &Path,
    p: &SimulateParams,
    cases: &[CaseOutcome],
    s: &SweepMetrics,
    title: &str,
) -> Result<()> {
    use crate::core::plot_sweep::{
        clearance_sweep_png, metric_sweep_png, time_histories_png, Panel, RegimeBand, SweepSeries,
    };
    let nm_of = |v: &Value| v.as_f64().unwrap_or(f64::NAN) * 1e9;
    let clearance: Vec<(f64, f64, f64)> = cases
        .iter()
        .map(|c| {
            (
                c.actuation * 1e9,
                nm_of(&c.metrics["clearance_m"]["mean"]),
                nm_of(&c.metrics["clearance_m"]["std"]),
            )
        })
        .collect();
    let bands = regime_bands(cases, s);
    let bands: Vec<RegimeBand> = bands
        .iter()
        .map(|(x0, x1, r)| RegimeBand {
            x0: *x0,
            x1: *x1,
            label: regime_name(*r),
        })
        .collect();
    let t0 = 0.5 * p.model.interface.lubricant_thickness * 1e9;
    clearance_sweep_png(
        &dir.join("clearance_sweep.png"),
        &format!("Steady clearance vs TFC actuation — {title}"),
        "TFC actuation (nm)",
        "clearance (nm)",
        &[SweepSeries {
            label: "mean ± 1 std",
            points: clearance,
        }],
        &bands,
        &[(0.0, "solid contact"), (t0, "T0"), (2.0 * t0, "2T0")],
    )?;
    let mut marks: Vec<(f64, &str)> = Vec::new();
    if let Some(td) = s.touchdown_actuation_m {
        marks.push((td * 1e9, "touchdown"));
    }
    if let Some(cp) = &s.slopes.critical_point {
        marks.push((cp.actuation_m * 1e9, "critical point"));
    }
    let series = |key: &str| -> Vec<(f64, f64)> {
        cases
            .iter()
            .map(|c| {
                (
                    c.actuation * 1e9,
                    c.metrics[key].as_f64().unwrap_or(f64::NAN),
                )
            })
            .collect()
    };
    metric_sweep_png(
        &dir.join("vibration_sweep.png"),
        &format!("FHM (flying) / BV (contact) vs actuation — {title}"),
        "TFC actuation (nm)",
        "FHM / BV (%)",
        &[
            (
                "eq. 2.1, 5 largest/smallest samples",
                series("vibration_percent"),
            ),
            (
                "5 largest/smallest local extrema",
                series("vibration_extrema_percent"),
            ),
        ],
        &marks,
    )?;
    metric_sweep_png(
        &dir.join("solid_contact_sweep.png"),
        &format!("Time in solid contact vs actuation — {title}"),
        "TFC actuation (nm)",
        "solid contact (% of the steady window)",
        &[("solid contact", series("percent_solid_contact"))],
        &marks,
    )?;
    for &want in &p.histories {
        let Some(c) = cases.iter().min_by(|a, b| {
            (a.actuation - want)
                .abs()
                .total_cmp(&(b.actuation - want).abs())
        }) else {
            continue;
        };
        let (time, series) = read_case_history(&c.entry.dir.join("case.h5"))?;
        let ms: Vec<f64> = time.iter().map(|t| t * 1e3).collect();
        let get = |n: &str| {
            series
                .iter()
                .find(|(k, _)| k == n)
                .map(|(_, v)| v.as_slice())
                .unwrap_or(&[])
        };
        let pair = |v: &[f64], scale: f64| -> Vec<(f64, f64)> {
            ms.iter().zip(v).map(|(t, y)| (*t, y * scale)).collect()
        };
        let fc = get("contact_force");
        let q = get("friction");
        let ar = get("real_area");
        // μ, P_m and τ only where F_c > 1 µN, as the metrics define them (dynamics.md §8).
        let loaded = |num: &[f64], den: &[f64], scale: f64| -> Vec<(f64, f64)> {
            ms.iter()
                .zip(fc)
                .zip(num.iter().zip(den))
                .filter(|((_, f), _)| **f > 1e-6)
                .map(|((t, _), (n, d))| (*t, n / d * scale))
                .collect()
        };
        let mu = loaded(q, fc, 1.0);
        let pm = loaded(fc, ar, 1e-9);
        let tau = loaded(q, ar, 1e-9);
        let name = format!("history_{:.2}nm.png", c.actuation * 1e9);
        time_histories_png(
            &dir.join(name),
            &format!(
                "{title}: h_TFC = {:.2} nm (Figs 2.13–2.14, 2.17)",
                c.actuation * 1e9
            ),
            &[
                Panel {
                    y_desc: "clearance (nm)",
                    series: vec![("clearance", pair(get("clearance"), 1e9))],
                },
                Panel {
                    y_desc: "force (mN)",
                    series: vec![
                        ("contact F_c", pair(fc, 1e3)),
                        ("friction Q", pair(q, 1e3)),
                        ("adhesion F_s", pair(get("adhesion"), 1e3)),
                    ],
                },
                Panel {
                    y_desc: "μ = Q/F_c",
                    series: vec![("μ", mu)],
                },
                Panel {
                    y_desc: "GPa",
                    series: vec![("P_m = F_c/A_r", pm), ("τ = Q/A_r", tau)],
                },
            ],
        )?;
    }
    Ok(())
}

/// A `[simulate.NAME]` instance.
pub struct SimulateStage {
    pub name: String,
    pub params: SimulateParams,
}

/// What every case of one sweep shares: the (calibrated) parameters, the interface table, the
/// DMW track with its instance key, and the contact instance's key (both enter the case keys).
pub struct PreparedSweep {
    pub params: SimulateParams,
    pub isbl: IsblLookup,
    pub dmw: Option<(DmwTrack, String)>,
    pub contact_key: String,
}

impl PreparedSweep {
    /// The canonical parameters (cache key input) of the case at `actuation`.
    pub fn case_params(&self, actuation: f64) -> Value {
        self.params.case_params(
            actuation,
            &self.contact_key,
            self.dmw.as_ref().map(|d| d.1.as_str()),
        )
    }

    /// Simulate the case at `actuation` into `dir` (what the case cache calls, locally or on
    /// a Slurm worker).
    pub fn compute_case(&self, actuation: f64, dir: &Path) -> Result<Value> {
        simulate_case(
            &self.params,
            actuation,
            &self.isbl,
            self.dmw.as_ref().map(|d| &d.0),
            dir,
        )
    }
}

/// The key of a `[calibrate]` table a calibrated instance checks (the table itself is
/// validated by its own kind).
#[derive(Deserialize)]
struct CalibrateTarget {
    simulate: String,
}

impl FromConfig for SimulateStage {
    type Config = SimulateConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &SimulateConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let params = validate(cfg).map_err(|(k, m)| file.error("simulate", name, &k, m))?;
        if !file.has_instance("contact", &cfg.contact) {
            return Err(file.error(
                "simulate",
                name,
                "contact",
                format!("no [contact.{}] in this file", cfg.contact),
            ));
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
        Ok(Self {
            name: name.to_string(),
            params,
        })
    }
}

/// Run every case (cached, parallel, with progress) and return them sorted by actuation.
pub fn run_cases(
    p: &SimulateParams,
    store: &crate::core::cache::Store,
    isbl: &IsblLookup,
    contact_key: &str,
    dmw: Option<(&DmwTrack, &str)>,
    progress: &indicatif::ProgressBar,
) -> Result<Vec<CaseOutcome>> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let total = p.actuations.len();
    let finished = AtomicUsize::new(0);
    progress.set_message(format!("0/{total} cases"));
    let outcomes: Vec<Result<CaseOutcome>> = p
        .actuations
        .par_iter()
        .map(|&a| {
            let params = p.case_params(a, contact_key, dmw.map(|d| d.1));
            let entry = cases::get_or_compute(store, MODEL_VERSION, &params, |dir| {
                simulate_case(p, a, isbl, dmw.map(|d| d.0), dir)
            })
            .map_err(|e| Error::Stage(format!("case h_TFC = {:.3} nm: {e}", a * 1e9)));
            let k = finished.fetch_add(1, Ordering::Relaxed) + 1;
            progress.set_message(format!("{k}/{total} cases"));
            let entry = entry?;
            Ok(CaseOutcome {
                actuation: a,
                metrics: entry.result.clone(),
                entry,
            })
        })
        .collect();
    let mut done = Vec::with_capacity(outcomes.len());
    for o in outcomes {
        done.push(o?);
    }
    done.sort_by(|a, b| a.actuation.total_cmp(&b.actuation));
    Ok(done)
}

/// Hard-link (or copy) each case's HDF5 into `out/cases/`.
fn link_cases(out: &Path, cases: &[CaseOutcome]) -> Result<Vec<String>> {
    let dir = out.join("cases");
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut names = Vec::new();
    for c in cases {
        let name = format!("h_{:06.2}nm.h5", c.actuation * 1e9);
        let (from, to) = (c.entry.dir.join("case.h5"), dir.join(&name));
        if std::fs::hard_link(&from, &to).is_err() {
            std::fs::copy(&from, &to).map_err(|e| Error::io(&to, e))?;
        }
        names.push(format!("cases/{name}"));
    }
    Ok(names)
}

impl SimulateStage {
    /// Resolve the upstream results (contact inputs, DMW track, calibration knobs) into the
    /// shared inputs of the cases; `key_of` gives an upstream instance's cache key.
    pub fn prepare(
        &self,
        upstream: &std::collections::BTreeMap<String, Value>,
        upstream_dirs: &std::collections::BTreeMap<String, PathBuf>,
        key_of: impl Fn(&str) -> String,
    ) -> Result<PreparedSweep> {
        let (mut isbl_params, mut dmw_track) =
            super::calibrate::base_inputs(&self.params, upstream, upstream_dirs)?;
        let mut calibrated = self.params.clone();
        if let Some(cal) = &self.params.calibration {
            let result = upstream
                .get(cal)
                .ok_or_else(|| Error::Stage(format!("no result from calibrate `{cal}`")))?;
            let fitted = super::calibrate::fitted_knobs(result).ok_or_else(|| {
                Error::Stage(format!("calibrate `{cal}` result has no usable `fitted`"))
            })?;
            let scale = crate::dynamics::calibration::apply_knobs(
                &fitted,
                &mut calibrated.model,
                &mut isbl_params,
            )?;
            if let Some(t) = dmw_track.as_mut() {
                t.displacement.iter_mut().for_each(|x| *x *= scale);
                t.velocity.iter_mut().for_each(|x| *x *= scale);
            }
            calibrated.calibrated_knobs = fitted
                .iter()
                .map(|(k, v)| (k.name().to_string(), *v))
                .collect();
        }
        let isbl = IsblLookup::build_standard(IsblModel::new(isbl_params)?)?;
        let dmw = match (&calibrated.dmw, dmw_track) {
            (Some(d), Some(t)) => Some((t, key_of(d))),
            _ => None,
        };
        Ok(PreparedSweep {
            contact_key: key_of(&calibrated.contact),
            params: calibrated,
            isbl,
            dmw,
        })
    }
}

impl StageKind for SimulateStage {
    const KIND: &'static str = "simulate";
    const MODEL_VERSION: &'static str = MODEL_VERSION;

    fn params(&self) -> Value {
        self.params.canonical()
    }
    fn upstream(&self) -> Vec<String> {
        let mut u = vec![self.params.contact.clone()];
        u.extend(self.params.dmw.iter().cloned());
        u.extend(self.params.calibration.iter().cloned());
        u
    }
    fn run(&self, ctx: &StageContext) -> Result<StageOutput> {
        let key_of = |name: &str| {
            ctx.fingerprint
                .upstream
                .iter()
                .find(|u| u.name == name)
                .map(|u| u.key.clone())
                .unwrap_or_default()
        };
        ctx.progress.set_message("interface table");
        let prepared = self.prepare(&ctx.upstream, &ctx.upstream_dirs, key_of)?;
        let p = &prepared.params;
        let isbl = &prepared.isbl;
        let dmw = prepared.dmw.as_ref();
        ctx.progress
            .set_message(format!("{} cases", p.actuations.len()));
        let cases = run_cases(
            p,
            ctx.store,
            isbl,
            &prepared.contact_key,
            dmw.map(|(t, k)| (t, k.as_str())),
            ctx.progress,
        )?;
        ctx.progress.set_message("sweep metrics, tables, plots");
        let sweep = sweep_analysis(p, &cases)?;
        let files = link_cases(ctx.out_dir, &cases)?;
        let rows = case_rows(&cases, &sweep);
        crate::core::store::write_table(&rows, &ctx.out_dir.join("sweep"))?;
        plots(ctx.out_dir, p, &cases, &sweep, &self.name)?;
        let summary = sweep_json(&cases, &sweep);
        // Femtometre-rounded nm: 10.2, not 10.200000000000001.
        let nm = |x: f64| (x * 1e15).round() / 1e6;
        let mut row = Map::new();
        row.insert("model".into(), json!(p.model_name));
        row.insert("geometry".into(), json!(p.geometry));
        row.insert("calibration".into(), json!(p.calibration));
        row.insert("cases".into(), json!(cases.len()));
        row.insert(
            "touchdown_nm".into(),
            json!(sweep.touchdown_actuation_m.map(nm)),
        );
        if let Some(cp) = &sweep.slopes.critical_point {
            row.insert("critical_point_nm".into(), json!(cp.actuation_m * 1e9));
            row.insert("critical_clearance_nm".into(), json!(cp.clearance_m * 1e9));
        }
        for (k, l) in [
            ("slope_A", &sweep.slopes.a),
            ("slope_B", &sweep.slopes.b),
            ("slope_C", &sweep.slopes.c),
            ("slope_D", &sweep.slopes.d),
        ] {
            row.insert(k.into(), json!(l.as_ref().map(|l| l.slope)));
        }
        row.insert(
            "optimum_nm".into(),
            json!(sweep.optimum_index.map(|i| nm(cases[i].actuation))),
        );
        let cached = cases.iter().filter(|c| c.entry.cached).count();
        Ok(StageOutput {
            result: json!({
                "sweep": summary,
                "cases": cases.iter().zip(&files).map(|(c, f)| json!({
                    "actuation_m": c.actuation, "h5": f, "metrics": c.metrics,
                })).collect::<Vec<_>>(),
                "case_keys": cases.iter().map(|c| c.entry.key.clone()).collect::<Vec<_>>(),
                "cases_cached": cached,
                "calibration": p.calibration,
                "calibrated_knobs": p.calibrated_knobs.iter().map(|(k, v)| json!({"knob": k, "value": v})).collect::<Vec<_>>(),
                "table": "sweep.parquet",
            }),
            summary_row: Some(row),
        })
    }
}
