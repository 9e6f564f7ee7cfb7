//! Calibration stage (docs/calibration.md): fit the dropped `[assumption]` knobs of a `[simulate]`
//! instance to the dissertation's class-D landmarks. Cached like every stage: the fit reruns
//! only when the base model, its contact set, its DMW record or the calibration settings change.
//! A `[simulate]` instance with `calibration = "NAME"` then runs with the fitted knobs.

use super::case_engine::{
    case_value, typed_case, CaseEngine, CaseRecipe, ListedCase, PreparedCases, UpstreamEntries,
    UpstreamRef,
};
use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::calibration::{
    fitted_list, CalibrateResult, ConvergenceRecord, FailureRecord, HeldOutRecord, InBandCount,
    InBandRecord, KnobAtBound, TouchdownSearchRecord,
};
use crate::artefacts::finite;
use crate::artefacts::ordered::OrderedMap;
use crate::contact::isbl::IsblParams;
use crate::core::config::{ConfigError, PipelineFile};
use crate::core::executor::batch::BatchRunner;
use crate::core::executor::CaseSpec;
use crate::core::store::rows_of;
use crate::dynamics::calibration::{
    calibrate, round_case, CalibrationResult, CalibrationSettings, CaseRound, CaseRounds,
    TargetGeometry, DEFAULT_MAX_EVALUATIONS,
};
use crate::dynamics::metrics::CaseMetrics;
use crate::dynamics::DynamicsError;
use crate::error::Result;
pub use crate::slider::calibration::report::describe_knobs;
use crate::slider::calibration::report::{
    evaluation_record, knob_rows, residuals_png, summary_text, table_rows, InBandCounts,
};
pub use crate::slider::calibration::WarmStart;
use crate::slider::calibration::{base_inputs, base_of};
use crate::slider::params::{uncalibrated_base, SimulateParams};
use crate::units::Length;
pub use case::{case_params, case_result, knobs_json, CalibrationCase, CalibrationCaseResult};
use serde::Deserialize;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::sync::Arc;

mod config;
use config::{chosen_targets, knob_ranges, start_fitted_for, warm_start};

// calibrate-6: the held-out set split into selection and final (outputs only; the fit is
// calibrate-5's, FIT_VERSION).
pub const MODEL_VERSION: &str = "calibrate-6";
/// What the fit computes (objective, search, cases): the fit-inputs fingerprint and the case
/// keys carry it, so an output-only change of the stage keeps its fits and warm start.
// calibrate-5: key params as plain JSON (settings, base model), not Rust Debug strings.
const FIT_VERSION: &str = "calibrate-5";

/// Hex digits of the fit-inputs fingerprint written to `result.json` (64 bits of blake3).
pub const FIT_INPUTS_DIGITS: usize = 16;

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
    /// The fit-inputs fingerprint `start` was fitted for (`convergence.fit_inputs` of that
    /// run's `result.json`): when the current inputs' fingerprint differs, `start` and
    /// `initial_step` are ignored and the fit runs from the spec defaults (docs/calibration.md,
    /// "Warm start").
    #[serde(default)]
    pub start_fitted_for: Option<String>,
}

/// Validated settings.
pub struct CalibrateStage {
    pub name: String,
    pub base_name: String,
    pub base: SimulateParams,
    pub settings: CalibrationSettings,
    /// `start_fitted_for`, lower case.
    pub start_fitted_for: Option<String>,
}

impl CalibrateStage {
    /// Fingerprint of everything the fit's trajectory and optimum depend on, hex
    /// ([`FIT_INPUTS_DIGITS`] digits): the stage's model version and the simulate cases'
    /// (`slider::case`), the base instance's parameters, the cache keys of its upstream
    /// entries (contact set, DMW record: their parameters and raw-file hashes), knobs with
    /// bounds, fitted targets with weights, the touchdown search and the Nelder–Mead
    /// tolerances. Left out: `start`, `initial_step` and `max_evaluations` (how the search is
    /// run, not what it fits), and the held-out set with the base's actuation grid and
    /// history actuations, which are evaluated only before and after the fit and never seen
    /// by it (test `held_out_targets_do_not_influence_the_fit`). Canonical JSON of ordered
    /// values only: no paths, no map iteration order.
    pub fn fit_inputs(&self, upstream_key: impl Fn(&str) -> String) -> String {
        let mut s = self.settings.clone();
        s.start.clear();
        s.search.initial_step = 0.0;
        s.search.max_evaluations = 0;
        s.held_out.clear();
        s.sweep_grid.clear();
        let mut base = self.base.canonical();
        if let Some(o) = base.as_object_mut() {
            o.remove("actuations_m");
            o.remove("histories_m");
        }
        let upstream: Vec<Value> = self
            .base
            .upstream()
            .iter()
            .map(|n| json!({"name": n, "key": upstream_key(n)}))
            .collect();
        let mut h = crate::core::hash::hash_json(&json!({
            "fingerprint": "calibrate-fit-inputs-1",
            "model_version": FIT_VERSION,
            "case_model_version": crate::slider::case::MODEL_VERSION,
            "base_parameters": base,
            "upstream": upstream,
            "settings": s,
        }));
        h.truncate(FIT_INPUTS_DIGITS);
        h
    }

    /// The settings the run uses given the current fit inputs' fingerprint: a guarded start
    /// whose fingerprint differs is dropped with `initial_step` (back to the default simplex).
    pub fn effective_settings(&self, fit_inputs: &str) -> (CalibrationSettings, WarmStart) {
        let mut s = self.settings.clone();
        if s.start.is_empty() {
            return (s, WarmStart::None);
        }
        let Some(given) = &self.start_fitted_for else {
            return (s, WarmStart::Unguarded);
        };
        // A prefix of the full hash is accepted, so either length matches (≥ 16 digits).
        if fit_inputs.starts_with(given.as_str()) || given.starts_with(fit_inputs) {
            return (s, WarmStart::Matched);
        }
        s.start.clear();
        s.search.initial_step = CalibrationSettings::new(Vec::new(), Vec::new())
            .search
            .initial_step;
        let reason = format!(
            "start_fitted_for = {given} but the fit's inputs now have fingerprint {fit_inputs}: \
             `start` and `initial_step` were fitted for other inputs and are ignored; the fit \
             runs from the spec defaults (update or delete `start`, `initial_step` and \
             `start_fitted_for`)"
        );
        (s, WarmStart::Ignored(reason))
    }
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
        let ranges = knob_ranges(cfg, &base, &err)?;
        let (targets, held_out) = chosen_targets(cfg, &base, &err)?;
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
        warm_start(cfg, &mut settings, &err)?;
        let start_fitted_for = start_fitted_for(cfg, &err)?;
        Ok(CalibrateStage {
            name: name.to_string(),
            base_name: cfg.simulate.clone(),
            base,
            settings,
            start_fitted_for,
        })
    }
}

impl StageKind for CalibrateStage {
    const KIND: &'static str = "calibrate";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = CalibrateResult;
    type Row = CalibrateRow;
    const CASE_KIND: Option<&'static str> = Some(CALIBRATION_CASE);
    fn case_engine(&self) -> Option<&dyn CaseEngine> {
        Some(self)
    }

    fn params(&self) -> Value {
        json!({
            "base": self.base_name,
            "base_parameters": self.base.canonical(),
            "settings": self.settings,
            "start_fitted_for": self.start_fitted_for,
        })
    }
    fn upstream(&self) -> Vec<String> {
        // The base is uncalibrated: its contact and DMW instances.
        self.base.upstream()
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<CalibrateResult, CalibrateRow>> {
        let (isbl, dmw) = base_inputs(&self.base, &ctx.upstream, &ctx.upstream_dirs)?;
        // Under a batch runner (`hdi run --executor slurm`) the rounds of cases go to it; the
        // search stays here (docs/slurm.md, "Calibration on Slurm").
        let rounds = ctx.batch.map(|batch| StoreRounds::new(self, ctx, batch));
        let mut base = base_of(&self.base, isbl, dmw.as_ref());
        base.rounds = rounds.as_ref().map(|r| r as &dyn CaseRounds);
        // Every knob must have a value in the base (e.g. a constant Δγ for `surface_energy`).
        for r in &self.settings.knobs {
            r.knob.base_value(&base.model, &base.isbl)?;
        }
        let fit_inputs = self.fit_inputs(|n| ctx.upstream_key(n));
        let (settings, warm) = self.effective_settings(&fit_inputs);
        if let WarmStart::Ignored(reason) = &warm {
            ctx.progress
                .set_message(format!("warning: {}: {reason}", self.name));
            // …and in the entry's manifest, beside result.json's `convergence.start_ignored`.
            ctx.log_run("warm_start_ignored", json!(reason));
        }
        let budget = settings.search.max_evaluations;
        ctx.progress
            .set_message(format!("fit inputs {fit_inputs}; 0/{budget} evaluations"));
        let result = calibrate(&base, &settings, |n, best| {
            ctx.progress
                .set_message(format!("{n}/{budget} evaluations, objective {best:.3}"));
        });
        if let Some(r) = &rounds {
            // A round that did not come back (scheduler, store) must not pass for an
            // infeasible point: the fit is void.
            r.finish(ctx)?;
        }
        let result = result?;
        let rows = rows_of(&table_rows(&result));
        crate::core::store::write_table(&rows, &ctx.out_dir.join("calibration"))?;
        crate::core::store::write_table(
            &rows_of(&knob_rows(&self.settings.knobs, &result)),
            &ctx.out_dir.join("knobs"),
        )?;
        self.convergence_png(ctx, &result)?;
        residuals_png(&ctx.out_dir.join("residuals.png"), &self.base_name, &result)?;
        let counts = InBandCounts::of(&result);
        let log = summary_text(&self.name, &settings, &fit_inputs, &warm, &result, &counts);
        let log_path = ctx.out_dir.join("calibration.log");
        std::fs::write(&log_path, &log).map_err(|e| crate::error::Error::io(&log_path, e))?;
        ctx.progress
            .set_message(log.lines().next().unwrap_or_default());
        Ok(Output {
            result: self.result(&settings, &fit_inputs, &warm, &result, &counts),
            summary_row: Some(self.summary_row(&result, &counts)),
        })
    }
}

/// The instance's row of the run's summary table: the objective and the in-band counts
/// (fitted, held-out and its selection and final sets) at the defaults and calibrated, the
/// convergence, and each fitted knob under its `pipeline.toml` name (SI units).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CalibrateRow {
    pub base: String,
    pub objective_defaults: f64,
    pub objective_calibrated: f64,
    pub targets: usize,
    pub within_tolerance: usize,
    pub fitted_in_band_defaults: usize,
    pub fitted_in_band_calibrated: usize,
    pub held_out_targets: usize,
    pub held_out_in_band_defaults: usize,
    pub held_out_in_band_calibrated: usize,
    pub selection_targets: usize,
    pub selection_in_band_defaults: usize,
    pub selection_in_band_calibrated: usize,
    pub final_targets: usize,
    pub final_in_band_defaults: usize,
    pub final_in_band_calibrated: usize,
    pub converged: bool,
    pub evaluations: usize,
    pub cases: usize,
    #[serde(flatten)]
    pub knobs: OrderedMap<f64>,
}

impl CalibrateStage {
    /// The objective of every evaluation and the best so far (`convergence.png`).
    fn convergence_png(&self, ctx: &StageContext, result: &CalibrationResult) -> Result<()> {
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
        Ok(())
    }

    /// The instance's row of the run's summary table: objective and in-band counts before and
    /// after the fit, its convergence and the fitted knobs.
    fn summary_row(&self, result: &CalibrationResult, counts: &InBandCounts) -> CalibrateRow {
        CalibrateRow {
            base: self.base_name.clone(),
            objective_defaults: result.initial.objective,
            objective_calibrated: result.best.objective,
            targets: result.best.outcomes.len(),
            within_tolerance: counts.fitted.1,
            fitted_in_band_defaults: counts.fitted.0,
            fitted_in_band_calibrated: counts.fitted.1,
            held_out_targets: counts.held_out_total,
            held_out_in_band_defaults: counts.held_out.0,
            held_out_in_band_calibrated: counts.held_out.1,
            selection_targets: counts.selection_total,
            selection_in_band_defaults: counts.selection.0,
            selection_in_band_calibrated: counts.selection.1,
            final_targets: counts.final_total,
            final_in_band_defaults: counts.final_set.0,
            final_in_band_calibrated: counts.final_set.1,
            converged: result.converged,
            evaluations: result.evaluations,
            cases: result.cases,
            knobs: OrderedMap(
                result
                    .best
                    .knobs
                    .iter()
                    .map(|(k, v)| (k.name().to_string(), *v))
                    .collect(),
            ),
        }
    }

    /// The stage's `result.json`: the fitted knobs, the evaluations at the defaults and at the
    /// fit, the in-band counts, the convergence and the search's history.
    fn result(
        &self,
        settings: &CalibrationSettings,
        fit_inputs: &str,
        warm: &WarmStart,
        result: &CalibrationResult,
        counts: &InBandCounts,
    ) -> CalibrateResult {
        let search = &settings.search;
        let td = &settings.touchdown;
        let count = |targets: usize, (defaults, calibrated): (usize, usize)| InBandCount {
            targets,
            defaults,
            calibrated,
        };
        CalibrateResult {
            base: self.base_name.clone(),
            model: self.base.model_name.clone(),
            fitted: fitted_list(&result.best.knobs),
            fitted_description: describe_knobs(&result.best.knobs),
            defaults: evaluation_record(&result.initial),
            calibrated: evaluation_record(&result.best),
            held_out: HeldOutRecord {
                defaults: result.held_out_initial.as_ref().map(evaluation_record),
                calibrated: result.held_out_best.as_ref().map(evaluation_record),
                sweep_grid_nm: self.settings.sweep_grid.iter().map(|a| a * 1e9).collect(),
            },
            in_band: InBandRecord {
                fitted: count(counts.fitted_total, counts.fitted),
                held_out: count(counts.held_out_total, counts.held_out),
                selection: count(counts.selection_total, counts.selection),
                final_set: count(counts.final_total, counts.final_set),
            },
            converged: result.converged,
            convergence: ConvergenceRecord {
                converged: result.converged,
                reason: result.stop.name().to_string(),
                f_tolerance: search.f_tolerance,
                x_tolerance: search.x_tolerance,
                final_f_spread: finite(result.final_f_spread),
                final_x_spread: finite(result.final_x_spread),
                max_evaluations: search.max_evaluations,
                initial_step: search.initial_step,
                start: fitted_list(&settings.start),
                fit_inputs: fit_inputs.to_string(),
                start_fitted_for: self.start_fitted_for.clone(),
                warm_start: warm.name().to_string(),
                start_ignored: match warm {
                    WarmStart::Ignored(reason) => Some(reason.clone()),
                    _ => None,
                },
            },
            at_bound: result
                .at_bound
                .iter()
                .map(|(k, b)| KnobAtBound {
                    knob: k.name().to_string(),
                    bound: b.name().to_string(),
                })
                .collect(),
            touchdown_search: TouchdownSearchRecord {
                start_nm: td.start * 1e9,
                stop_nm: td.stop * 1e9,
                step_nm: td.step * 1e9,
                resolution_nm: td.resolution * 1e9,
                batch: td.batch,
            },
            evaluations: result.evaluations,
            cases: result.cases,
            failures: result
                .failures
                .iter()
                .map(|(k, e)| FailureRecord {
                    knobs: describe_knobs(k),
                    error: e.clone(),
                })
                .collect(),
            history: result
                .history
                .iter()
                .map(|(i, f, b, exact)| (*i, finite(*f), finite(*b), *exact))
                .collect(),
            rejected_early: result.rejected,
            table: "calibration.parquet".into(),
            log: "calibration.log".into(),
        }
    }
}

// ------------------------------------------------------------------------------------------
// The fit's cases as store entries, for a batch runner (docs/slurm.md, "Calibration on Slurm")
// ------------------------------------------------------------------------------------------

/// Case kind of one calibration case sent to a batch runner (`hdi exec-cases` dispatches on
/// it to [`CaseEngine`] below).
pub const CALIBRATION_CASE: &str = "calibration";

/// Model version of a calibration case's store entry: its result is the case metrics of
/// `dynamics::calibration::round_case` as JSON (or the error of a case that fails).
pub const CASE_MODEL_VERSION: &str = "calibration-case-1";

impl CalibrateStage {
    /// What every case of this fit depends on besides its knobs, geometry and actuation: the
    /// stage's and the simulation cases' model versions, the base instance's parameters
    /// (without its actuation grid and history points) and the keys of its upstream entries.
    pub fn case_base_params(&self, upstream_key: impl Fn(&str) -> String) -> Value {
        let mut base = self.base.canonical();
        if let Some(o) = base.as_object_mut() {
            o.remove("actuations_m");
            o.remove("histories_m");
        }
        let upstream: Vec<Value> = self
            .base
            .upstream()
            .iter()
            .map(|n| json!({"name": n, "key": upstream_key(n)}))
            .collect();
        json!({
            "model_version": FIT_VERSION,
            "case_model_version": crate::slider::case::MODEL_VERSION,
            "base_parameters": base,
            "upstream": upstream,
        })
    }
}

/// `base` / `optimised`.
pub fn geometry_name(g: TargetGeometry) -> &'static str {
    match g {
        TargetGeometry::Base => "base",
        TargetGeometry::Optimised => "optimised",
    }
}

pub fn geometry_from_name(s: &str) -> Option<TargetGeometry> {
    match s {
        "base" => Some(TargetGeometry::Base),
        "optimised" => Some(TargetGeometry::Optimised),
        _ => None,
    }
}

/// The fit's rounds as store entries computed by a batch runner. A round that does not come
/// back (scheduler, store, unreadable result) is recorded as fatal: the fit then fails fast
/// and the stage reports it, instead of counting the point infeasible.
struct StoreRounds<'c> {
    batch: &'c dyn BatchRunner,
    store: &'c crate::core::cache::Store,
    instance: String,
    base_params: Value,
    /// Where a worker reads the base's contact and DMW entries.
    upstream: Vec<UpstreamRef>,
    fatal: std::sync::Mutex<Option<String>>,
    counts: std::sync::Mutex<(usize, usize)>,
}

impl<'c> StoreRounds<'c> {
    fn new(stage: &CalibrateStage, ctx: &StageContext<'c>, batch: &'c dyn BatchRunner) -> Self {
        StoreRounds {
            batch,
            store: ctx.store,
            instance: ctx.name.to_string(),
            base_params: stage.case_base_params(|n| ctx.upstream_key(n)),
            upstream: ctx.upstream_entries().refs(ctx.store.processed()),
            fatal: Default::default(),
            counts: Default::default(),
        }
    }

    fn fail(&self, message: String) -> DynamicsError {
        if let Ok(mut f) = self.fatal.lock() {
            f.get_or_insert(message.clone());
        }
        DynamicsError::Numerical(message)
    }

    /// The fatal error of a round, if one happened; the rounds and cases in the run's log.
    fn finish(&self, ctx: &StageContext) -> Result<()> {
        let (rounds, cases) = self.counts.lock().map(|c| *c).unwrap_or_default();
        ctx.log_run("batch_rounds", json!({"rounds": rounds, "cases": cases}));
        match self.fatal.lock().ok().and_then(|f| f.clone()) {
            Some(message) => Err(crate::error::Error::CalibrationRoundLost {
                instance: self.instance.to_string(),
                message,
            }),
            None => Ok(()),
        }
    }
}

impl CaseRounds for StoreRounds<'_> {
    fn run_round(&self, round: &CaseRound) -> crate::dynamics::Result<Vec<CaseMetrics>> {
        if let Some(m) = self.fatal.lock().ok().and_then(|f| f.clone()) {
            return Err(DynamicsError::Numerical(m));
        }
        if let Ok(mut c) = self.counts.lock() {
            c.0 += 1;
            c.1 += round.actuations.len();
        }
        let specs: Vec<CaseSpec> = round
            .actuations
            .iter()
            .map(|&a| {
                let params = case_params(&self.base_params, round.knobs, round.geometry, a);
                let key = crate::core::cases::case_fingerprint(CASE_MODEL_VERSION, &params).key();
                let recipe = CaseRecipe {
                    // The batch runner names the pipeline file.
                    config: String::new(),
                    instance: self.instance.clone(),
                    upstream: self.upstream.clone(),
                    case: case_value(&CalibrationCase::new(round.knobs, round.geometry, a)),
                    key,
                };
                CaseSpec::new(
                    CALIBRATION_CASE,
                    CASE_MODEL_VERSION,
                    params,
                    case_value(&recipe),
                )
            })
            .collect();
        let results = self
            .batch
            .run_batch(self.store, &specs)
            .map_err(|e| self.fail(crate::core::chain(&e)))?;
        let mut metrics = Vec::with_capacity(results.len());
        for (spec, r) in specs.iter().zip(results) {
            match serde_json::from_value::<CalibrationCaseResult>(r) {
                // As the in-process round: the case's own error (the first in order).
                Ok(CalibrationCaseResult::Error(e)) => return Err(DynamicsError::Numerical(e)),
                Ok(CalibrationCaseResult::Metrics(m)) => metrics.push(*m),
                Err(e) => {
                    return Err(self.fail(format!("case {}: unreadable metrics: {e}", spec.key)))
                }
            }
        }
        Ok(metrics)
    }
}

impl CaseEngine for CalibrateStage {
    /// The base's interface parameters, DMW track and case base parameters, rebuilt from the
    /// entries the submitting fit read.
    fn prepare_cases(&self, upstream: &UpstreamEntries) -> Result<Arc<dyn PreparedCases>> {
        let (isbl, dmw) = base_inputs(&self.base, &upstream.results, &upstream.dirs)?;
        Ok(Arc::new(CalibrationCases {
            base: self.base.clone(),
            isbl,
            dmw,
            base_params: self.case_base_params(|n| upstream.key_of(n)),
        }))
    }
    /// The fit submits its rounds itself while it runs.
    fn listed_up_front(&self) -> bool {
        false
    }
}

/// What every case of one fit shares.
struct CalibrationCases {
    base: SimulateParams,
    isbl: IsblParams,
    dmw: Option<crate::artefacts::dmw_tracks::DmwTrack>,
    base_params: Value,
}

impl PreparedCases for CalibrationCases {
    fn model_version(&self) -> &'static str {
        CASE_MODEL_VERSION
    }
    fn cases(&self) -> Result<Vec<ListedCase>> {
        Ok(Vec::new())
    }
    fn case_params(&self, case: &Value) -> Result<Value> {
        let c: CalibrationCase = typed_case(CALIBRATION_CASE, case)?;
        let (knobs, geometry) = c.resolve()?;
        Ok(case_params(
            &self.base_params,
            &knobs,
            geometry,
            c.actuation_m,
        ))
    }
    /// The case through [`round_case`], the function the fit's own rounds run.
    fn compute(&self, case: &Value, _dir: &std::path::Path) -> Result<Value> {
        let c: CalibrationCase = typed_case(CALIBRATION_CASE, case)?;
        let (knobs, geometry) = c.resolve()?;
        let base = base_of(&self.base, self.isbl, self.dmw.as_ref());
        let outcome = round_case(&base, &knobs, geometry, c.actuation_m);
        let result = case_result(&outcome);
        let written =
            serde_json::to_value(&result).map_err(|_| crate::error::Error::CaseMetricsJson)?;
        // The fit compares these numbers: they must come back bit for bit (a non-finite value
        // would not survive JSON).
        if outcome.is_ok() {
            let back = serde_json::from_value::<CalibrationCaseResult>(written.clone()).ok();
            if back.as_ref() != Some(&result) {
                return Err(crate::error::Error::CaseMetricsJson);
            }
        }
        Ok(written)
    }
}

mod case;
#[cfg(test)]
mod tests;
