//! Calibration stage (docs/calibration.md): fit the dropped `[assumption]` knobs of a `[simulate]`
//! instance to the dissertation's class-D landmarks. Cached like every stage: the fit reruns
//! only when the base model, its contact set, its DMW record or the calibration settings change.
//! A `[simulate]` instance with `calibration = "NAME"` then runs with the fitted knobs.

use super::{FromConfig, StageContext, StageKind, StageOutput};
use crate::artefacts::calibration::fitted_json;
use crate::contact::isbl::IsblParams;
use crate::core::config::{ConfigError, PipelineFile};
use crate::dynamics::calibration::{
    calibrate, default_knobs, targets_for, CalibrationResult, CalibrationSettings, Evaluation,
    Knob, KnobRange,
};
use crate::error::Result;
use crate::slider::calibration::{base_inputs, base_of};
use crate::slider::params::{uncalibrated_base, SimulateParams};
use crate::units::Length;
use serde::Deserialize;
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;

pub const MODEL_VERSION: &str = "calibrate-1";

fn default_evaluations() -> usize {
    120
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
    /// Target ids to fit (default: the model's class-D catalogue).
    #[serde(default)]
    pub targets: Option<Vec<String>>,
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
    /// Width of the touchdown bracket.
    #[serde(default)]
    pub touchdown_resolution: Option<Length>,
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
                     geometry's (the optimised design's are included as `optimised_*` targets)",
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
        for (id, w) in &cfg.weights {
            let Some(t) = targets.iter_mut().find(|t| t.id == id) else {
                return Err(err(
                    "weights",
                    format!("`{id}` is not one of the calibration's targets"),
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
        settings.search.max_evaluations = cfg.max_evaluations;
        if let Some(r) = cfg.touchdown_resolution {
            if !(r.0 > 0.0 && r.0 <= 1e-9) {
                return Err(err(
                    "touchdown_resolution",
                    format!("{} m is out of range: 0 < r ≤ 1 nm", r.0),
                ));
            }
            settings.touchdown_resolution = r.0;
        }
        for r in &settings.knobs {
            r.check().map_err(|e| err("bounds", e.to_string()))?;
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
    json!({
        "objective": e.objective,
        "cases": e.cases,
        "knobs": e.knobs.iter().map(|(k, v)| json!({"knob": k.name(), "value": v})).collect::<Vec<_>>(),
        "targets": e.outcomes.iter().map(|o| json!({
            "id": o.target.id,
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

fn table_rows(r: &CalibrationResult) -> Vec<Map<String, Value>> {
    r.best
        .outcomes
        .iter()
        .zip(&r.initial.outcomes)
        .map(|(b, i)| {
            let t = &b.target;
            let s = |v: Option<f64>| json!(v.map(|v| v * t.display_scale));
            let mut m = Map::new();
            m.insert("target".into(), json!(t.id));
            m.insert(
                "spec_row".into(),
                json!(format!("dynamics.md §12.2 {}", t.source)),
            );
            m.insert("unit".into(), json!(t.unit));
            m.insert("published".into(), json!(t.published * t.display_scale));
            m.insert("tolerance".into(), json!(t.tolerance * t.display_scale));
            m.insert("weight".into(), json!(t.weight));
            m.insert("spec_defaults".into(), s(i.value));
            m.insert("calibrated".into(), s(b.value));
            m.insert("residual_defaults".into(), json!(i.normalised_residual));
            m.insert("residual_calibrated".into(), json!(b.normalised_residual));
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
                json!(
                    (*v - range.lo).abs() <= 1e-6 * (range.hi - range.lo)
                        || (*v - range.hi).abs() <= 1e-6 * (range.hi - range.lo)
                ),
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
            .map(|(i, f, _)| (*i as f64 + 1.0, *f))
            .collect();
        let best: Vec<(f64, f64)> = result
            .history
            .iter()
            .map(|(i, _, b)| (*i as f64 + 1.0, *b))
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
        let within = result
            .best
            .outcomes
            .iter()
            .filter(|o| o.within_tolerance())
            .count();
        let mut row = Map::new();
        row.insert("base".into(), json!(self.base_name));
        row.insert("objective_defaults".into(), json!(result.initial.objective));
        row.insert("objective_calibrated".into(), json!(result.best.objective));
        row.insert("targets".into(), json!(result.best.outcomes.len()));
        row.insert("within_tolerance".into(), json!(within));
        row.insert("evaluations".into(), json!(result.evaluations));
        row.insert("cases".into(), json!(result.cases));
        for (k, v) in &result.best.knobs {
            row.insert(k.name().into(), json!(v));
        }
        Ok(StageOutput {
            result: json!({
                "base": self.base_name,
                "model": self.base.model_name,
                "fitted": fitted_json(&result.best.knobs),
                "fitted_description": describe_knobs(&result.best.knobs),
                "defaults": evaluation_json(&result.initial),
                "calibrated": evaluation_json(&result.best),
                "converged": result.converged,
                "evaluations": result.evaluations,
                "cases": result.cases,
                "failures": result.failures.iter().map(|(k, e)| json!({
                    "knobs": describe_knobs(k), "error": e,
                })).collect::<Vec<_>>(),
                "history": result.history.iter().map(|(i, f, b)| json!([i, f, b])).collect::<Vec<_>>(),
                "table": "calibration.parquet",
            }),
            summary_row: Some(row),
        })
    }
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
