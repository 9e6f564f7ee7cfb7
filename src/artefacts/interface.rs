//! The combined roughness an interface instance hands the contact stage (its `result.json`):
//! σ, R, η of the equivalent rough surface against a flat, with β, the spectral moments and
//! the Nayak bandwidth α.

use super::finite;
use crate::error::{Error, Result};
use crate::surface::combine::InterfaceStats;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// The interface result as written (SI, unit suffixes in the keys; the field order is the
/// key order); a value that is not finite (the moments of explicit values) is `null`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InterfaceRoughness {
    /// `sum_surface`, `harmonic_r` or `explicit`.
    pub rule: String,
    #[serde(rename = "sigma_m")]
    pub sigma: Option<f64>,
    #[serde(rename = "R_m")]
    pub r: Option<f64>,
    #[serde(rename = "eta_per_m2")]
    pub eta: Option<f64>,
    pub beta: Option<f64>,
    pub m2: Option<f64>,
    #[serde(rename = "m4_per_m2")]
    pub m4: Option<f64>,
    pub alpha: Option<f64>,
}

impl InterfaceRoughness {
    pub fn new(st: &InterfaceStats, rule: &str) -> Self {
        InterfaceRoughness {
            rule: rule.to_string(),
            sigma: finite(st.sigma),
            r: finite(st.r),
            eta: finite(st.eta),
            beta: finite(st.beta),
            m2: finite(st.m2),
            m4: finite(st.m4),
            alpha: finite(st.alpha),
        }
    }
}

/// σ, R, η [m, m, 1/m²] of the upstream interface instance `name`; a missing value is an
/// error naming its key.
pub fn upstream_summits(upstream: &BTreeMap<String, Value>, name: &str) -> Result<[f64; 3]> {
    let r: InterfaceRoughness = super::upstream_result(upstream, "interface", name)?;
    let get = |v: Option<f64>, k: &str| {
        v.ok_or_else(|| Error::UpstreamField {
            kind: "interface",
            name: name.to_string(),
            what: format!("`{k}`"),
        })
    };
    Ok([
        get(r.sigma, "sigma_m")?,
        get(r.r, "R_m")?,
        get(r.eta, "eta_per_m2")?,
    ])
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
        let (sigma, r, eta, beta, m2, m4, alpha) =
            (0.5e-9, 0.43e-6, 124e12, 0.0267, 1.5e-3, f64::NAN, 2.0);
        let mut w = InterfaceRoughness {
            rule: "sum_surface".into(),
            sigma: finite(sigma),
            r: finite(r),
            eta: finite(eta),
            beta: finite(beta),
            m2: finite(m2),
            m4: finite(m4),
            alpha: finite(alpha),
        };
        // As the interface stage wrote it before the struct existed.
        let before = json!({
            "rule": w.rule,
            "sigma_m": sigma, "R_m": r, "eta_per_m2": eta, "beta": beta,
            "m2": m2, "m4_per_m2": m4, "alpha": alpha,
        });
        let written = serde_json::to_value(&w).unwrap();
        assert_eq!(written.to_string(), before.to_string());
        let up = BTreeMap::from([("i".to_string(), written)]);
        assert_eq!(upstream_summits(&up, "i").unwrap(), [sigma, r, eta]);
        w.r = None;
        let up = BTreeMap::from([("i".to_string(), serde_json::to_value(&w).unwrap())]);
        let e = upstream_summits(&up, "i").unwrap_err().to_string();
        assert_eq!(e, "interface `i` result has no `R_m`");
        let e = upstream_summits(&BTreeMap::new(), "i").unwrap_err();
        assert_eq!(e.to_string(), "no result from interface `i`");
    }
}
