//! The bulge stage's fitted TFC bulge (`tfc` in its `result.json`): the geometry a `[simulate]`
//! instance with `geometry = { bulge = "NAME" }` uses, and the efficiency that turns heater
//! power into actuation (docs/bulge.md).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// The fitted bulge as written (SI units, unit suffixes in the keys).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FittedBulge {
    /// Half-length along the slider, m.
    pub a_tfc_m: f64,
    /// Full width across the slider, m.
    pub w_tfc_m: f64,
    /// Centre distance from the trailing edge, m (`None` when no edge was detected).
    pub x_tfc_m: Option<f64>,
    /// Bulge growth per heater power, m/W (`None` without two or more scans with powers).
    #[serde(rename = "efficiency_m_per_W")]
    pub efficiency_m_per_w: Option<f64>,
    /// Bulge height at zero heater power, m.
    pub intercept_m: Option<f64>,
}

impl FittedBulge {
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self).unwrap_or(Value::Null)
    }
}

/// The fitted bulge of the bulge instance `name` from the upstream results.
pub fn upstream_bulge(upstream: &BTreeMap<String, Value>, name: &str) -> Result<FittedBulge> {
    let result = upstream.get(name).ok_or_else(|| Error::MissingUpstream {
        kind: "bulge",
        name: name.to_string(),
    })?;
    FittedBulge::deserialize(&result["tfc"]).map_err(|_| Error::UpstreamField {
        kind: "bulge",
        name: name.to_string(),
        what: "usable `tfc`".into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn round_trip_and_missing() {
        let b = FittedBulge {
            a_tfc_m: 4.86e-6,
            w_tfc_m: 50e-6,
            x_tfc_m: Some(6.35e-6),
            efficiency_m_per_w: Some(3e-7),
            intercept_m: Some(3e-9),
        };
        let up = BTreeMap::from([("tfc".to_string(), json!({"tfc": b.to_json()}))]);
        assert_eq!(upstream_bulge(&up, "tfc").unwrap(), b);
        assert!(b.to_json()["efficiency_m_per_W"].is_number());
        assert!(upstream_bulge(&up, "other").is_err());
        let bad = BTreeMap::from([("tfc".to_string(), json!({}))]);
        assert!(upstream_bulge(&bad, "tfc").is_err());
    }
}
