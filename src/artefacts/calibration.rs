//! The calibration stage's fitted knobs (`fitted` in its `result.json`): what a calibrated
//! `[simulate]` instance applies to its model, interface and DMW scale.

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
pub fn fitted_json(knobs: &[(Knob, f64)]) -> Value {
    let list: Vec<FittedKnob> = knobs.iter().map(|(k, v)| FittedKnob::new(*k, *v)).collect();
    serde_json::to_value(list).unwrap_or(Value::Null)
}

/// Fitted knob values from a calibrate result (`result["fitted"]`); `None` if it is missing,
/// malformed or names an unknown knob.
pub fn fitted_knobs(result: &Value) -> Option<Vec<(Knob, f64)>> {
    let list = Vec::<FittedKnob>::deserialize(&result["fitted"]).ok()?;
    list.iter()
        .map(|k| Some((Knob::from_name(&k.knob)?, k.value)))
        .collect()
}

/// The fitted knobs of the calibrate instance `calibration` from the upstream results.
pub fn upstream_fitted_knobs(
    upstream: &BTreeMap<String, Value>,
    calibration: &str,
) -> Result<Vec<(Knob, f64)>> {
    let result = upstream
        .get(calibration)
        .ok_or_else(|| Error::MissingUpstream {
            kind: "calibrate",
            name: calibration.to_string(),
        })?;
    fitted_knobs(result).ok_or_else(|| Error::UpstreamField {
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
        let written = fitted_json(&knobs);
        assert_eq!(written.to_string(), before.to_string());
        let back = fitted_knobs(&json!({"fitted": written})).unwrap();
        assert_eq!(back, knobs.to_vec());
    }

    #[test]
    fn unknown_or_missing_knobs_are_unusable() {
        assert!(fitted_knobs(&json!({})).is_none());
        assert!(fitted_knobs(&json!({"fitted": [{"knob": "nope", "value": 1.0}]})).is_none());
        assert!(fitted_knobs(&json!({"fitted": [{"knob": "dmw_scale"}]})).is_none());
        // The unit is informative: a list without it still reads.
        assert_eq!(
            fitted_knobs(&json!({"fitted": [{"knob": "dmw_scale", "value": 2.0}]})),
            Some(vec![(Knob::DmwScale, 2.0)])
        );
        let e = upstream_fitted_knobs(&BTreeMap::new(), "cal").unwrap_err();
        assert!(
            e.to_string().contains("no result from calibrate `cal`"),
            "{e}"
        );
    }
}
