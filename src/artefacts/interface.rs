//! The combined roughness an interface instance hands the contact stage (its `result.json`):
//! σ, R, η of the equivalent rough surface against a flat, with β, the spectral moments and
//! the Nayak bandwidth α.

use crate::error::{Error, Result};
use crate::surface::combine::InterfaceStats;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// The interface result as written (SI, unit suffixes in the keys; the field order is the
/// key order).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InterfaceRoughness {
    /// `sum_surface`, `harmonic_r` or `explicit`.
    pub rule: String,
    #[serde(rename = "sigma_m")]
    pub sigma: f64,
    #[serde(rename = "R_m")]
    pub r: f64,
    #[serde(rename = "eta_per_m2")]
    pub eta: f64,
    pub beta: f64,
    pub m2: f64,
    #[serde(rename = "m4_per_m2")]
    pub m4: f64,
    pub alpha: f64,
}

impl InterfaceRoughness {
    pub fn new(st: &InterfaceStats, rule: &str) -> Self {
        InterfaceRoughness {
            rule: rule.to_string(),
            sigma: st.sigma,
            r: st.r,
            eta: st.eta,
            beta: st.beta,
            m2: st.m2,
            m4: st.m4,
            alpha: st.alpha,
        }
    }

    /// The JSON the interface stage writes as its result.
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self).unwrap_or(Value::Null)
    }
}

/// σ, R, η [m, m, 1/m²] of the upstream interface instance `name`; a missing value is an
/// error naming its key.
pub fn upstream_summits(upstream: &BTreeMap<String, Value>, name: &str) -> Result<[f64; 3]> {
    let r = upstream.get(name).ok_or_else(|| Error::MissingUpstream {
        kind: "interface",
        name: name.to_string(),
    })?;
    let get = |k: &str| {
        r[k].as_f64().ok_or_else(|| Error::UpstreamField {
            kind: "interface",
            name: name.to_string(),
            what: format!("`{k}`"),
        })
    };
    Ok([get("sigma_m")?, get("R_m")?, get("eta_per_m2")?])
}

/// What an `[interface.NAME]` table says about its surfaces, read leniently (the interface
/// stage checks the table itself): its combination rule and the `[surface.*]` instances.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct InterfaceSurfaces {
    #[serde(default = "default_rule")]
    pub rule: String,
    #[serde(default)]
    pub surfaces: Vec<String>,
}

fn default_rule() -> String {
    "sum_surface".into()
}

impl InterfaceSurfaces {
    /// The table of `[interface.name]` in `file`, `None` if the file has no such instance.
    pub fn of(
        file: &crate::core::config::PipelineFile,
        name: &str,
    ) -> std::result::Result<Option<Self>, crate::core::config::ConfigError> {
        file.instance::<Self>("interface", name)
    }

    /// Two measured surfaces (not `explicit` numbers).
    pub fn has_two_surfaces(&self) -> bool {
        self.rule != "explicit" && self.surfaces.len() == 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn written_json_is_unchanged_and_reads_back() {
        let w = InterfaceRoughness {
            rule: "sum_surface".into(),
            sigma: 0.5e-9,
            r: 0.43e-6,
            eta: 124e12,
            beta: 0.0267,
            m2: 1.5e-3,
            m4: f64::NAN,
            alpha: 2.0,
        };
        // As the interface stage wrote it before the struct existed.
        let before = json!({
            "rule": w.rule,
            "sigma_m": w.sigma, "R_m": w.r, "eta_per_m2": w.eta, "beta": w.beta,
            "m2": w.m2, "m4_per_m2": w.m4, "alpha": w.alpha,
        });
        assert_eq!(w.to_json().to_string(), before.to_string());
        let up = BTreeMap::from([("i".to_string(), w.to_json())]);
        assert_eq!(upstream_summits(&up, "i").unwrap(), [w.sigma, w.r, w.eta]);
        let up = BTreeMap::from([("i".to_string(), json!({"sigma_m": 1.0}))]);
        let e = upstream_summits(&up, "i").unwrap_err().to_string();
        assert_eq!(e, "interface `i` result has no `R_m`");
    }
}
