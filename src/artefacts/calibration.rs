//! The calibration stage's `result.json` ([`CalibrateResult`]) and its fitted knobs (`fitted`):
//! what a calibrated `[simulate]` instance applies to its model, interface and DMW scale, and
//! what `hdi validate` re-evaluates.

use crate::dynamics::calibration::Knob;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// One fitted knob as written: its `pipeline.toml` name, SI unit and value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FittedKnob {
    pub knob: String,
    /// Informative only (the knob's name fixes its unit).
    #[serde(default)]
    pub unit: String,
    pub value: f64,
}

impl FittedKnob {
    pub fn new(knob: Knob, value: f64) -> Self {
        FittedKnob {
            knob: knob.name().to_string(),
            unit: knob.unit().to_string(),
            value,
        }
    }
}

/// The `fitted` list the calibration stage writes.
pub fn fitted_list(knobs: &[(Knob, f64)]) -> Vec<FittedKnob> {
    knobs.iter().map(|(k, v)| FittedKnob::new(*k, *v)).collect()
}

/// The calibration stage's `result.json`: the fitted knobs, the evaluations at the defaults
/// and at the fit, the in-band counts, the convergence and the search's history
/// (docs/calibration.md). Values a fit may leave undefined (an infeasible objective) are
/// `null`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrateResult {
    /// The `[simulate]` instance calibrated.
    pub base: String,
    pub model: String,
    pub fitted: Vec<FittedKnob>,
    pub fitted_description: String,
    /// The fitted set at the spec defaults.
    pub defaults: EvaluationRecord,
    /// The fitted set at the fitted knobs.
    pub calibrated: EvaluationRecord,
    pub held_out: HeldOutRecord,
    pub in_band: InBandRecord,
    pub converged: bool,
    pub convergence: ConvergenceRecord,
    pub at_bound: Vec<KnobAtBound>,
    pub touchdown_search: TouchdownSearchRecord,
    pub evaluations: usize,
    pub cases: usize,
    pub failures: Vec<FailureRecord>,
    /// `[evaluation, objective, best so far, exact]` per evaluation.
    pub history: Vec<(usize, Option<f64>, Option<f64>, bool)>,
    pub rejected_early: usize,
    /// File name of the target table.
    pub table: String,
    /// File name of the log.
    pub log: String,
}

/// One evaluation: its knobs, objective and every target.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvaluationRecord {
    pub objective: Option<f64>,
    pub cases: usize,
    pub in_band: usize,
    pub targets_total: usize,
    pub knobs: Vec<KnobValue>,
    pub targets: Vec<TargetRecord>,
}

/// A knob's value in an evaluation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KnobValue {
    pub knob: String,
    pub value: f64,
}

/// One target of an evaluation (SI units; `value` is `null` where the case gave none).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TargetRecord {
    pub id: String,
    /// `fitted`, `selection` or `final`.
    pub set: String,
    pub class: String,
    pub value: Option<f64>,
    pub published: f64,
    pub tolerance: f64,
    pub weight: f64,
    pub normalised_residual: Option<f64>,
    pub within_tolerance: bool,
}

/// The held-out set before and after the fit (`null` when there is none) and its sweep grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOutRecord {
    pub defaults: Option<EvaluationRecord>,
    pub calibrated: Option<EvaluationRecord>,
    pub sweep_grid_nm: Vec<f64>,
}

/// In-band counts of the fitted and held-out sets and the held-out set's two parts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InBandRecord {
    pub fitted: InBandCount,
    pub held_out: InBandCount,
    pub selection: InBandCount,
    #[serde(rename = "final")]
    pub final_set: InBandCount,
}

/// Targets of a set and how many are in band at the defaults and calibrated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InBandCount {
    pub targets: usize,
    pub defaults: usize,
    pub calibrated: usize,
}

/// How the search ended and how it started (docs/calibration.md, "Warm start").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConvergenceRecord {
    pub converged: bool,
    pub reason: String,
    pub f_tolerance: f64,
    pub x_tolerance: f64,
    pub final_f_spread: Option<f64>,
    pub final_x_spread: Option<f64>,
    pub max_evaluations: usize,
    pub initial_step: f64,
    pub start: Vec<FittedKnob>,
    /// The fit-inputs fingerprint (hex).
    pub fit_inputs: String,
    pub start_fitted_for: Option<String>,
    pub warm_start: String,
    pub start_ignored: Option<String>,
}

/// A knob that ended on a bound (`lower` / `upper`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KnobAtBound {
    pub knob: String,
    pub bound: String,
}

/// The touchdown search of the fitted set (nm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TouchdownSearchRecord {
    pub start_nm: f64,
    pub stop_nm: f64,
    pub step_nm: f64,
    pub resolution_nm: f64,
    pub batch: usize,
}

/// A trial point whose cases failed: its knobs (described) and the error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailureRecord {
    pub knobs: String,
    pub error: String,
}

/// Fitted knob values of a calibrate result; `None` if one names an unknown knob.
pub fn fitted_knobs(result: &CalibrateResult) -> Option<Vec<(Knob, f64)>> {
    result
        .fitted
        .iter()
        .map(|k| Some((Knob::from_name(&k.knob)?, k.value)))
        .collect()
}

/// The fitted knobs of the calibrate instance `calibration` from the upstream results.
pub fn upstream_fitted_knobs(
    upstream: &BTreeMap<String, Value>,
    calibration: &str,
) -> Result<Vec<(Knob, f64)>> {
    let result: CalibrateResult =
        crate::artefacts::upstream_result(upstream, "calibrate", calibration)?;
    fitted_knobs(&result).ok_or_else(|| Error::UpstreamField {
        kind: "calibrate",
        name: calibration.to_string(),
        what: "usable `fitted`".into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn written_json_is_unchanged_and_reads_back() {
        let knobs = [
            (Knob::DmwScale, 2.125),
            (Knob::SurfaceEnergy, 0.052),
            (Knob::LjSpacing, 0.31e-9),
        ];
        // As the calibration stage wrote it before the struct existed.
        let before = json!(knobs
            .iter()
            .map(|(k, v)| json!({"knob": k.name(), "unit": k.unit(), "value": v}))
            .collect::<Vec<_>>());
        let written = serde_json::to_value(fitted_list(&knobs)).unwrap();
        assert_eq!(written.to_string(), before.to_string());
        let back = Vec::<FittedKnob>::deserialize(&written).unwrap();
        assert_eq!(back, fitted_list(&knobs));
    }

    #[test]
    fn unknown_or_missing_knobs_are_unusable() {
        assert!(Vec::<FittedKnob>::deserialize(&json!([{"knob": "dmw_scale"}])).is_err());
        // The unit is informative: a list without it still reads.
        let k = Vec::<FittedKnob>::deserialize(&json!([{"knob": "dmw_scale", "value": 2.0}]));
        assert_eq!(k.unwrap()[0].value, 2.0);
        let e = upstream_fitted_knobs(&BTreeMap::new(), "cal").unwrap_err();
        assert!(
            e.to_string().contains("no result from calibrate `cal`"),
            "{e}"
        );
        let partial = BTreeMap::from([("cal".to_string(), json!({"fitted": []}))]);
        assert!(upstream_fitted_knobs(&partial, "cal").is_err());
    }
}
