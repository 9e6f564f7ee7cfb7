//! Calibration stage (docs/calibration.md): fit the dropped `[assumption]` knobs of a `[simulate]`
//! instance to the dissertation's class-D landmarks. Cached like every stage: the fit reruns
//! only when the base model, its contact set, its DMW record or the calibration settings change.
//! A `[simulate]` instance with `calibration = "NAME"` then runs with the fitted knobs.

use super::{FromConfig, StageContext, StageKind, StageOutput};
use crate::artefacts::calibration::fitted_json;
use crate::contact::isbl::IsblParams;
use crate::core::config::{ConfigError, PipelineFile};
use crate::dynamics::calibration::{
    apply_knobs, calibrate, default_knobs, held_out_for, in_band, targets_for, CalibrationResult,
    CalibrationSettings, Evaluation, Knob, KnobRange, TargetOutcome, DEFAULT_MAX_EVALUATIONS,
};
use crate::error::Result;
use crate::slider::calibration::{base_inputs, base_of};
use crate::slider::params::{uncalibrated_base, SimulateParams};
use crate::units::Length;
use serde::Deserialize;
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;

pub const MODEL_VERSION: &str = "calibrate-3";

fn default_evaluations() -> usize {
    DEFAULT_MAX_EVALUATIONS
}

/// `[calibrate.NAME]` as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CalibrateConfig {
    /// The `[simulate.*]` instance whose model, contact set, DMW and case options are
    /// calibrated (its actuation list is not used).
    pub simulate: String,
    /// Knobs to fit (default: the model's set, see `docs/calibration.md`).
    #[serde(default)]
    pub knobs: Option<Vec<String>>,
    /// Target ids to fit (default: the model's fitted set, docs/calibration.md).
    #[serde(default)]
    pub targets: Option<Vec<String>>,
    /// Held-out target ids, judged before and after the fit on the base instance's sweep grid
    /// and never seen by it (default: the model's whole held-out set; `[]` for none).
    #[serde(default)]
    pub held_out: Option<Vec<String>>,
    /// Search range per knob in SI units, e.g. `bounds = { lj_spacing = [0.2e-9, 0.8e-9] }`.
    #[serde(default)]
    pub bounds: BTreeMap<String, [f64; 2]>,
    /// Weight per target id (default 1; 10 for the class-K anchor, 0 for the targets reported
    /// but not fitted), e.g. `weights = { clearance_12nm = 1.0 }`.
    #[serde(default)]
    pub weights: BTreeMap<String, f64>,
    /// Objective evaluations of the Nelder–Mead search.
    #[serde(default = "default_evaluations")]
    pub max_evaluations: usize,
    /// Width of the touchdown bracket (0.02 nm, the convention).
    #[serde(default)]
    pub touchdown_resolution: Option<Length>,
    /// Scan step of the fitted set's touchdown search from 0 nm (0.5 nm).
    #[serde(default)]
    pub touchdown_step: Option<Length>,
    /// Start point of the search per knob in SI units (default: the spec defaults), e.g. a
    /// previous fit's optimum (docs/calibration.md, "Warm start").
    #[serde(default)]
    pub start: BTreeMap<String, f64>,
    /// Edge of the start simplex in unit-box coordinates (default 0.2).
    #[serde(default)]
    pub initial_step: Option<f64>,
}

/// Validated settings.
pub struct CalibrateStage {
    pub name: String,
    pub base_name: String,
    pub base: SimulateParams,
    pub settings: CalibrationSettings,
}

impl FromConfig for CalibrateStage {
    type Config = CalibrateConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &CalibrateConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let err = |k: &str, m: String| file.error("calibrate", name, k, m);
        let base = uncalibrated_base(file, "calibrate", name, &cfg.simulate)?;
        if base.geometry != "dissertation" {
            return Err(err(
                "simulate",
                format!(
                    "[simulate.{}] uses geometry = \"{}\"; the targets are the dissertation \
                     geometry's (the optimised design's are held out as `optimised_*` targets)",
                    cfg.simulate, base.geometry
                ),
            ));
        }
        let variant = base.model.variant;
        let knobs: Vec<Knob> = match &cfg.knobs {
            None => default_knobs(variant),
            Some(names) => names
                .iter()
                .map(|n| {
                    Knob::from_name(n).ok_or_else(|| {
                        err(
                            "knobs",
                            format!(
                                "unknown knob `{n}` (known: {})",
                                Knob::ALL.map(|k| k.name()).join(", ")
                            ),
                        )
                    })
                })
                .collect::<std::result::Result<_, _>>()?,
        };
        let mut ranges = Vec::new();
        let isbl_probe = IsblParams::improved_2dof();
        for k in &knobs {
            if ranges.iter().any(|r: &KnobRange| r.knob == *k) {
                return Err(err("knobs", format!("knob `{}` listed twice", k.name())));
            }
            // The knob must exist in the base model (e.g. no β on the initial model).
            if !matches!(k, Knob::SurfaceEnergy) {
                k.base_value(&base.model, &isbl_probe)
                    .map_err(|e| err("knobs", e.to_string()))?;
            }
            if *k == Knob::DmwScale && base.dmw.is_none() {
                return Err(err(
                    "knobs",
                    format!(
                        "dmw_scale needs a DMW input, but [simulate.{}] has dmw = \"none\"",
                        cfg.simulate
                    ),
                ));
            }
            let mut r = KnobRange::new(*k);
            if let Some([lo, hi]) = cfg.bounds.get(k.name()) {
                (r.lo, r.hi) = (*lo, *hi);
                // A box wider than the model accepts would hand the fit points the model
                // rejects: refuse it here, naming the model's limit.
                for v in [*lo, *hi] {
                    let (mut m, mut i) = (base.model, isbl_probe);
                    apply_knobs(&[(*k, v)], &mut m, &mut i).map_err(|e| {
                        err(
                            "bounds",
                            format!("{} = {v:e} is outside the model's range: {e}", k.name()),
                        )
                    })?;
                }
            }
            ranges.push(r);
        }
        for b in cfg.bounds.keys() {
            if !knobs.iter().any(|k| k.name() == b) {
                return Err(err(
                    "bounds",
                    format!("`{b}` is not one of the calibrated knobs"),
                ));
            }
        }
        let catalogue = targets_for(variant);
        let mut targets: Vec<_> = match &cfg.targets {
            None => catalogue,
            Some(ids) => ids
                .iter()
                .map(|id| {
                    catalogue
                        .iter()
                        .find(|t| t.id == id)
                        .cloned()
                        .ok_or_else(|| {
                            err(
                                "targets",
                                format!(
                                    "unknown target `{id}` for {} (known: {})",
                                    base.model_name,
                                    catalogue
                                        .iter()
                                        .map(|t| t.id)
                                        .collect::<Vec<_>>()
                                        .join(", ")
                                ),
                            )
                        })
                })
                .collect::<std::result::Result<_, _>>()?,
        };
        let held_catalogue = held_out_for(variant);
        let held_out: Vec<_> = match &cfg.held_out {
            None => held_catalogue,
            Some(ids) => ids
                .iter()
                .map(|id| {
                    held_catalogue
                        .iter()
                        .find(|t| t.id == id)
                        .cloned()
                        .ok_or_else(|| {
                            err(
                                "held_out",
                                format!(
                                    "unknown held-out target `{id}` for {} (known: {})",
                                    base.model_name,
                                    held_catalogue
                                        .iter()
                                        .map(|t| t.id)
                                        .collect::<Vec<_>>()
                                        .join(", ")
                                ),
                            )
                        })
                })
                .collect::<std::result::Result<_, _>>()?,
        };
        for (id, w) in &cfg.weights {
            let Some(t) = targets.iter_mut().find(|t| t.id == id) else {
                return Err(err(
                    "weights",
                    format!("`{id}` is not one of the calibration's fitted targets"),
                ));
            };
            if !(w.is_finite() && *w >= 0.0) {
                return Err(err("weights", format!("{id} = {w}: must be ≥ 0")));
            }
            t.weight = *w;
        }
        if !targets.iter().any(|t| t.weight > 0.0) {
            return Err(err("targets", "no target with a weight > 0 to fit".into()));
        }
        if !(1..=10_000).contains(&cfg.max_evaluations) {
            return Err(err(
                "max_evaluations",
                format!("{} is out of range: 1 … 10000", cfg.max_evaluations),
            ));
        }
        let mut settings = CalibrationSettings::new(ranges, targets);
        settings.held_out = held_out;
        settings.sweep_grid = base.actuations.clone();
        settings.sweep_grid.sort_by(f64::total_cmp);
        settings.search.max_evaluations = cfg.max_evaluations;
        if let Some(r) = cfg.touchdown_resolution {
            if !(r.0 > 0.0 && r.0 <= 1e-9) {
                return Err(err(
                    "touchdown_resolution",
                    format!("{} m is out of range: 0 < r ≤ 1 nm", r.0),
                ));
            }
            settings.touchdown.resolution = r.0;
        }
        if let Some(s) = cfg.touchdown_step {
            if !(s.0 >= settings.touchdown.resolution && s.0 <= 5e-9) {
                return Err(err(
                    "touchdown_step",
                    format!(
                        "{} m is out of range: touchdown_resolution ≤ step ≤ 5 nm",
                        s.0
                    ),
                ));
            }
            settings.touchdown.step = s.0;
        }
        for r in &settings.knobs {
            r.check().map_err(|e| err("bounds", e.to_string()))?;
        }
        for (name, v) in &cfg.start {
            let Some(r) = settings.knobs.iter().find(|r| r.knob.name() == name) else {
                return Err(err(
                    "start",
                    format!("`{name}` is not one of the calibrated knobs"),
                ));
            };
            if !(v.is_finite() && *v >= r.lo && *v <= r.hi) {
                return Err(err(
                    "start",
                    format!("{name} = {v:e} is outside its box [{:e}, {:e}]", r.lo, r.hi),
                ));
            }
            settings.start.push((r.knob, *v));
        }
        // The knobs' order, not the file's: the settings (and the cache key) stay canonical.
        settings.start.sort_by_key(|(k, _)| {
            settings
                .knobs
                .iter()
                .position(|r| r.knob == *k)
                .unwrap_or(usize::MAX)
        });
        if let Some(step) = cfg.initial_step {
            if !(step > 0.0 && step <= 0.5) {
                return Err(err(
                    "initial_step",
                    format!("{step} is out of range: 0 < step ≤ 0.5 (unit box)"),
                ));
            }
            settings.search.initial_step = step;
        }
        Ok(CalibrateStage {
            name: name.to_string(),
            base_name: cfg.simulate.clone(),
            base,
            settings,
        })
    }
}

fn evaluation_json(e: &Evaluation) -> Value {
    let (inside, total) = in_band(e);
    json!({
        "objective": e.objective,
        "cases": e.cases,
        "in_band": inside,
        "targets_total": total,
        "knobs": e.knobs.iter().map(|(k, v)| json!({"knob": k.name(), "value": v})).collect::<Vec<_>>(),
        "targets": e.outcomes.iter().map(|o| json!({
            "id": o.target.id,
            "set": o.target.set.name(),
            "class": o.target.class,
            "value": o.value,
            "published": o.target.published,
            "tolerance": o.target.tolerance,
            "weight": o.target.weight,
            "normalised_residual": o.normalised_residual,
            "within_tolerance": o.within_tolerance(),
        })).collect::<Vec<_>>(),
    })
}

/// Describe the knob values compactly in display units (`dmw_scale 2.1, Δγ 52 mN/m, …`).
pub fn describe_knobs(values: &[(Knob, f64)]) -> String {
    values
        .iter()
        .map(|(k, v)| match k {
            Knob::SurfaceEnergy => format!("Δγ {:.3} mN/m", v * 1e3),
            Knob::LjSpacing => format!("ε {:.3} nm", v * 1e9),
            Knob::AsperityDensity => format!("η {:.1} µm⁻²", v * 1e-12),
            Knob::KrStiffeningBeta => format!("β {v:.3}"),
            Knob::ContactDamping => format!("ζ_c {v:.4}"),
            Knob::DmwScale => format!("dmw_scale {v:.3}"),
            Knob::TruncationN => format!("n {v:.3}"),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// One row per target of both sets: published, tolerance, value before (spec defaults) and
/// after (fitted knobs), in band before and after.
fn table_rows(r: &CalibrationResult) -> Vec<Map<String, Value>> {
    let pairs = |before: &Evaluation, after: &Evaluation| -> Vec<(TargetOutcome, TargetOutcome)> {
        before
            .outcomes
            .iter()
            .cloned()
            .zip(after.outcomes.iter().cloned())
            .collect()
    };
    let mut all = pairs(&r.initial, &r.best);
    if let (Some(b), Some(a)) = (&r.held_out_initial, &r.held_out_best) {
        all.extend(pairs(b, a));
    }
    all.iter()
        .map(|(i, b)| {
            let t = &b.target;
            let s = |v: Option<f64>| json!(v.map(|v| v * t.display_scale));
            let mut m = Map::new();
            m.insert("target".into(), json!(t.id));
            m.insert("set".into(), json!(t.set.name()));
            m.insert("class".into(), json!(t.class));
            m.insert(
                "geometry".into(),
                json!(match t.geometry {
                    crate::dynamics::calibration::TargetGeometry::Base => "dissertation",
                    crate::dynamics::calibration::TargetGeometry::Optimised => "optimised",
                }),
            );
            m.insert(
                "spec_row".into(),
                // The id of `hdi validate` (docs/validation.md), e.g. dyn-16.
                json!(format!("dyn-{}", t.source.trim_start_matches('#'))),
            );
            m.insert("unit".into(), json!(t.unit));
            m.insert("published".into(), json!(t.published * t.display_scale));
            m.insert("tolerance".into(), json!(t.tolerance * t.display_scale));
            m.insert("weight".into(), json!(t.weight));
            m.insert("spec_defaults".into(), s(i.value));
            m.insert("calibrated".into(), s(b.value));
            m.insert("residual_defaults".into(), json!(i.normalised_residual));
            m.insert("residual_calibrated".into(), json!(b.normalised_residual));
            m.insert("in_band_defaults".into(), json!(i.within_tolerance()));
            m.insert("in_band_calibrated".into(), json!(b.within_tolerance()));
            m.insert("within_tolerance".into(), json!(b.within_tolerance()));
            m
        })
        .collect()
}

fn knob_rows(stage: &CalibrateStage, r: &CalibrationResult) -> Vec<Map<String, Value>> {
    stage
        .settings
        .knobs
        .iter()
        .zip(&r.best.knobs)
        .map(|(range, (k, v))| {
            let mut m = Map::new();
            m.insert("knob".into(), json!(k.name()));
            m.insert("unit".into(), json!(k.unit()));
            m.insert("lower_bound".into(), json!(range.lo));
            m.insert("upper_bound".into(), json!(range.hi));
            m.insert("fitted".into(), json!(v));
            m.insert(
                "at_bound".into(),
                json!(r
                    .at_bound
                    .iter()
                    .find(|(kb, _)| kb == k)
                    .map(|(_, b)| b.name())),
            );
            m
        })
        .collect()
}

impl StageKind for CalibrateStage {
    const KIND: &'static str = "calibrate";
    const MODEL_VERSION: &'static str = MODEL_VERSION;

    fn params(&self) -> Value {
        json!({
            "base": self.base_name,
            "base_parameters": self.base.canonical(),
            "settings": format!("{:?}", self.settings),
        })
    }
    fn upstream(&self) -> Vec<String> {
        // The base is uncalibrated: its contact and DMW instances.
        self.base.upstream()
    }
    fn run(&self, ctx: &StageContext) -> Result<StageOutput> {
        let (isbl, dmw) = base_inputs(&self.base, &ctx.upstream, &ctx.upstream_dirs)?;
        let base = base_of(&self.base, isbl, dmw.as_ref());
        // Every knob must have a value in the base (e.g. a constant Δγ for `surface_energy`).
        for r in &self.settings.knobs {
            r.knob.base_value(&base.model, &base.isbl)?;
        }
        let budget = self.settings.search.max_evaluations;
        ctx.progress.set_message(format!("0/{budget} evaluations"));
        let result = calibrate(&base, &self.settings, |n, best| {
            ctx.progress
                .set_message(format!("{n}/{budget} evaluations, objective {best:.3}"));
        })?;
        let rows = table_rows(&result);
        crate::core::store::write_table(&rows, &ctx.out_dir.join("calibration"))?;
        crate::core::store::write_table(&knob_rows(self, &result), &ctx.out_dir.join("knobs"))?;
        let current: Vec<(f64, f64)> = result
            .history
            .iter()
            .map(|(i, f, _, _)| (*i as f64 + 1.0, *f))
            .collect();
        let best: Vec<(f64, f64)> = result
            .history
            .iter()
            .map(|(i, _, b, _)| (*i as f64 + 1.0, *b))
            .collect();
        crate::figures::semilogy_png(
            &ctx.out_dir.join("convergence.png"),
            &format!(
                "Calibration of {} — objective Σ weight·(residual/tolerance)²",
                self.base_name
            ),
            "objective evaluation",
            "objective",
            &[("evaluated", current), ("best so far", best)],
            &[],
        )?;
        residuals_png(&ctx.out_dir.join("residuals.png"), &self.base_name, &result)?;
        let counts = InBandCounts::of(&result);
        let log = summary_text(self, &result, &counts);
        let log_path = ctx.out_dir.join("calibration.log");
        std::fs::write(&log_path, &log).map_err(|e| crate::error::Error::io(&log_path, e))?;
        ctx.progress
            .set_message(log.lines().next().unwrap_or_default());
        let mut row = Map::new();
        row.insert("base".into(), json!(self.base_name));
        row.insert("objective_defaults".into(), json!(result.initial.objective));
        row.insert("objective_calibrated".into(), json!(result.best.objective));
        row.insert("targets".into(), json!(result.best.outcomes.len()));
        row.insert("within_tolerance".into(), json!(counts.fitted.1));
        row.insert("fitted_in_band_defaults".into(), json!(counts.fitted.0));
        row.insert("fitted_in_band_calibrated".into(), json!(counts.fitted.1));
        row.insert("held_out_targets".into(), json!(counts.held_out_total));
        row.insert("held_out_in_band_defaults".into(), json!(counts.held_out.0));
        row.insert(
            "held_out_in_band_calibrated".into(),
            json!(counts.held_out.1),
        );
        row.insert("converged".into(), json!(result.converged));
        row.insert("evaluations".into(), json!(result.evaluations));
        row.insert("cases".into(), json!(result.cases));
        for (k, v) in &result.best.knobs {
            row.insert(k.name().into(), json!(v));
        }
        let search = &self.settings.search;
        let td = &self.settings.touchdown;
        Ok(StageOutput {
            result: json!({
                "base": self.base_name,
                "model": self.base.model_name,
                "fitted": fitted_json(&result.best.knobs),
                "fitted_description": describe_knobs(&result.best.knobs),
                "defaults": evaluation_json(&result.initial),
                "calibrated": evaluation_json(&result.best),
                "held_out": {
                    "defaults": result.held_out_initial.as_ref().map(evaluation_json),
                    "calibrated": result.held_out_best.as_ref().map(evaluation_json),
                    "sweep_grid_nm": self.settings.sweep_grid.iter().map(|a| a * 1e9).collect::<Vec<_>>(),
                },
                "in_band": {
                    "fitted": {"targets": counts.fitted_total, "defaults": counts.fitted.0, "calibrated": counts.fitted.1},
                    "held_out": {"targets": counts.held_out_total, "defaults": counts.held_out.0, "calibrated": counts.held_out.1},
                },
                "converged": result.converged,
                "convergence": {
                    "converged": result.converged,
                    "reason": result.stop.name(),
                    "f_tolerance": search.f_tolerance,
                    "x_tolerance": search.x_tolerance,
                    "final_f_spread": result.final_f_spread,
                    "final_x_spread": result.final_x_spread,
                    "max_evaluations": search.max_evaluations,
                    "initial_step": search.initial_step,
                    "start": fitted_json(&self.settings.start),
                },
                "at_bound": result.at_bound.iter().map(|(k, b)| json!({
                    "knob": k.name(), "bound": b.name(),
                })).collect::<Vec<_>>(),
                "touchdown_search": {
                    "start_nm": td.start * 1e9, "stop_nm": td.stop * 1e9, "step_nm": td.step * 1e9,
                    "resolution_nm": td.resolution * 1e9, "batch": td.batch,
                },
                "evaluations": result.evaluations,
                "cases": result.cases,
                "failures": result.failures.iter().map(|(k, e)| json!({
                    "knobs": describe_knobs(k), "error": e,
                })).collect::<Vec<_>>(),
                "history": result.history.iter().map(|(i, f, b, exact)| json!([i, f, b, exact])).collect::<Vec<_>>(),
                "rejected_early": result.rejected,
                "table": "calibration.parquet",
                "log": "calibration.log",
            }),
            summary_row: Some(row),
        })
    }
}

/// In-band counts `(spec defaults, calibrated)` of the fitted and the held-out sets.
struct InBandCounts {
    fitted: (usize, usize),
    fitted_total: usize,
    held_out: (usize, usize),
    held_out_total: usize,
}

impl InBandCounts {
    fn of(r: &CalibrationResult) -> Self {
        let (f0, ft) = in_band(&r.initial);
        let (f1, _) = in_band(&r.best);
        let (h0, ht) = r.held_out_initial.as_ref().map_or((0, 0), in_band);
        let (h1, _) = r.held_out_best.as_ref().map_or((0, 0), in_band);
        InBandCounts {
            fitted: (f0, f1),
            fitted_total: ft,
            held_out: (h0, h1),
            held_out_total: ht,
        }
    }
}

/// The stage's log: counts, convergence, knobs (with bounds reached), every target.
fn summary_text(stage: &CalibrateStage, r: &CalibrationResult, c: &InBandCounts) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: fitted set {}/{} → {}/{} in band, held-out set {}/{} → {}/{}; objective {:.3} → {:.3}; {} after {} evaluations ({} cases)",
        stage.name,
        c.fitted.0,
        c.fitted_total,
        c.fitted.1,
        c.fitted_total,
        c.held_out.0,
        c.held_out_total,
        c.held_out.1,
        c.held_out_total,
        r.initial.objective,
        r.best.objective,
        if r.converged {
            "converged (simplex tolerance)"
        } else {
            "NOT converged (evaluation budget)"
        },
        r.evaluations,
        r.cases
    );
    let _ = writeln!(
        s,
        "simplex: f spread {:.3e} (tolerance {:.1e}), unit-box edge {:.3e} (tolerance {:.1e})",
        r.final_f_spread,
        stage.settings.search.f_tolerance,
        r.final_x_spread,
        stage.settings.search.x_tolerance
    );
    let _ = writeln!(
        s,
        "search: start simplex edge {} (unit box) at {}; {} trial points rejected early (touchdown search skipped)",
        stage.settings.search.initial_step,
        if stage.settings.start.is_empty() {
            "the spec defaults".to_string()
        } else {
            describe_knobs(&stage.settings.start)
        },
        r.rejected
    );
    let _ = writeln!(s, "knobs: {}", describe_knobs(&r.best.knobs));
    for (k, b) in &r.at_bound {
        let _ = writeln!(s, "knob {} ended on its {} bound", k.name(), b.name());
    }
    let _ = writeln!(
        s,
        "set\ttarget\tpublished\ttolerance\tdefaults\tcalibrated\tin band before/after"
    );
    for row in table_rows(r) {
        let f = |k: &str| {
            row[k]
                .as_f64()
                .map_or("–".to_string(), |v| format!("{v:.4}"))
        };
        let _ = writeln!(
            s,
            "{}\t{}\t{} {}\t±{}\t{}\t{}\t{}/{}",
            row["set"].as_str().unwrap_or_default(),
            row["target"].as_str().unwrap_or_default(),
            f("published"),
            row["unit"].as_str().unwrap_or_default(),
            f("tolerance"),
            f("spec_defaults"),
            f("calibrated"),
            row["in_band_defaults"],
            row["in_band_calibrated"],
        );
    }
    s
}

/// Normalised residual per target, spec defaults against calibrated, with the ±1 band.
fn residuals_png(path: &std::path::Path, base: &str, r: &CalibrationResult) -> Result<()> {
    let values = |e: &Evaluation| -> Vec<f64> {
        e.outcomes
            .iter()
            .map(|o| o.normalised_residual.clamp(-10.0, 10.0))
            .collect()
    };
    let categories: Vec<String> = r
        .best
        .outcomes
        .iter()
        .map(|o| {
            if o.target.weight == 0.0 {
                format!("{} (reported)", o.target.id)
            } else {
                o.target.id.to_string()
            }
        })
        .collect();
    crate::figures::category_dots_png(
        path,
        &format!("Calibration of {base}: residual / tolerance (band ±1)"),
        "(value − published) / tolerance (clamped to ±10)",
        &categories,
        &[
            ("spec defaults", values(&r.initial)),
            ("calibrated", values(&r.best)),
        ],
        1.0,
    )?;
    Ok(())
}
