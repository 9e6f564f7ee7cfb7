//! A calibration case as a recipe carries it, its key parameters and its stored result.

use super::{geometry_from_name, geometry_name, CALIBRATION_CASE};
use crate::dynamics::calibration::{Knob, TargetGeometry};
use crate::dynamics::metrics::CaseMetrics;
use crate::error::Result;
use serde_json::{json, Value};

/// `[[name, value], …]` (JSON numbers round-trip f64 exactly: serde_json `float_roundtrip`).
pub fn knobs_json(knobs: &[(Knob, f64)]) -> Value {
    json!(knobs
        .iter()
        .map(|(k, v)| json!([k.name(), v]))
        .collect::<Vec<_>>())
}

/// Canonical parameters of one case (its store key).
pub fn case_params(
    base_params: &Value,
    knobs: &[(Knob, f64)],
    geometry: TargetGeometry,
    actuation: f64,
) -> Value {
    json!({
        "calibration_base": base_params,
        "knobs": knobs_json(knobs),
        "geometry": geometry_name(geometry),
        "actuation_m": actuation,
    })
}

/// A case's result as stored: `{"metrics": …}`, or `{"error": …}` for a case that fails (a
/// failing case is deterministic, and the fit counts its point infeasible with this text).
pub fn case_result(outcome: &crate::dynamics::Result<CaseMetrics>) -> CalibrationCaseResult {
    match outcome {
        Ok(m) => CalibrationCaseResult::Metrics(Box::new(m.clone())),
        Err(e) => CalibrationCaseResult::Error(e.to_string()),
    }
}

/// A calibration case's stored result (`{"metrics": …}` or `{"error": "…"}`): written by the
/// worker, read back by the fit's round through this type.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CalibrationCaseResult {
    /// The case's metrics.
    Metrics(Box<CaseMetrics>),
    /// The error that ended the case (the round reports the first in order).
    Error(String),
}

/// One case of a calibration round, as a recipe carries it (docs/schemas/case-manifest.json).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CalibrationCase {
    /// The round's knob values, [name, value] pairs (JSON numbers round-trip f64 exactly:
    /// serde_json `float_roundtrip`).
    pub knobs: Vec<(String, f64)>,
    /// Target geometry: base or optimised.
    #[schemars(extend("enum" = ["base", "optimised"]))]
    pub geometry: String,
    /// TFC actuation of the case, m.
    pub actuation_m: f64,
}

impl CalibrationCase {
    pub(super) fn new(knobs: &[(Knob, f64)], geometry: TargetGeometry, actuation_m: f64) -> Self {
        CalibrationCase {
            knobs: knobs
                .iter()
                .map(|(k, v)| (k.name().to_string(), *v))
                .collect(),
            geometry: geometry_name(geometry).to_string(),
            actuation_m,
        }
    }

    /// The knobs and geometry as the fit names them.
    pub(super) fn resolve(&self) -> Result<(Vec<(Knob, f64)>, TargetGeometry)> {
        let bad = |what: &str| {
            let source = <serde_json::Error as serde::de::Error>::custom(what);
            crate::error::Error::RecipeCase {
                kind: CALIBRATION_CASE,
                source,
            }
        };
        let knobs = self
            .knobs
            .iter()
            .map(|(k, v)| Knob::from_name(k).map(|k| (k, *v)))
            .collect::<Option<Vec<_>>>()
            .ok_or_else(|| bad("unknown knob"))?;
        let geometry = geometry_from_name(&self.geometry).ok_or_else(|| bad("unknown geometry"))?;
        Ok((knobs, geometry))
    }
}
