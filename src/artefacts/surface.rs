//! The summit statistics a surface instance hands the interface stage (`stats` in its
//! `result.json`): σ, R, η and the spectral moments the combination rules need.

use crate::error::{Error, Result};
use crate::surface::combine::{SummitHeights, SurfaceStats};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// `stats` as written: SI values; a moment that is not finite is written as `null`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SummitStats {
    pub sigma: f64,
    pub r: f64,
    pub eta: f64,
    pub m2: Option<f64>,
    pub m4: Option<f64>,
}

impl SummitStats {
    /// The JSON the surface stage writes (`stats`).
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self).unwrap_or(Value::Null)
    }

    /// `stats` of the result of surface instance `name`; a missing σ, R or η is an error
    /// naming it, a missing moment is `None`.
    pub fn from_result(result: &Value, name: &str) -> Result<Self> {
        let s = &result["stats"];
        let get = |k: &str| {
            s[k].as_f64().ok_or_else(|| Error::UpstreamField {
                kind: "surface",
                name: name.to_string(),
                what: format!("`{k}`"),
            })
        };
        Ok(SummitStats {
            sigma: get("sigma")?,
            r: get("r")?,
            eta: get("eta")?,
            m2: s["m2"].as_f64(),
            m4: s["m4"].as_f64(),
        })
    }

    pub fn stats(&self) -> SurfaceStats {
        SurfaceStats {
            sigma: self.sigma,
            r: self.r,
            eta: self.eta,
            m2: self.m2,
            m4: self.m4,
        }
    }
}

/// The summit statistics of the upstream surface instance `name`.
pub fn upstream_surface_stats(
    upstream: &BTreeMap<String, Value>,
    name: &str,
) -> Result<SurfaceStats> {
    let result = upstream.get(name).ok_or_else(|| Error::MissingUpstream {
        kind: "surface",
        name: name.to_string(),
    })?;
    Ok(SummitStats::from_result(result, name)?.stats())
}

/// The measured summit heights of the upstream surface instance `name` (its discrete summits:
/// `mean_summit_height_m`, `sigma_s_m`, with `sigma_m` and `eta_per_m2`). A surface of several
/// areas is refused: its result carries these for the first area only.
pub fn upstream_summit_heights(
    upstream: &BTreeMap<String, Value>,
    name: &str,
) -> Result<SummitHeights> {
    let result = upstream.get(name).ok_or_else(|| Error::MissingUpstream {
        kind: "surface",
        name: name.to_string(),
    })?;
    let field = |what: String| Error::UpstreamField {
        kind: "surface",
        name: name.to_string(),
        what,
    };
    if result.get("areas").is_some() {
        return Err(field(
            "summit heights over its areas (several areas: the result holds the first \
             area's only; measure the summits on one area)"
                .into(),
        ));
    }
    let get = |k: &str| result[k].as_f64().ok_or_else(|| field(format!("`{k}`")));
    Ok(SummitHeights {
        sigma: get("sigma_m")?,
        eta: get("eta_per_m2")?,
        mean: get("mean_summit_height_m")?,
        std: get("sigma_s_m")?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn written_json_is_unchanged_and_reads_back() {
        let (sigma, r, eta, m2, m4) = (0.5e-9, 0.43e-6, 124e12, 1.5e-3, f64::NAN);
        let s = SummitStats {
            sigma,
            r,
            eta,
            m2: Some(m2),
            m4: Some(m4),
        };
        // As the surface stage wrote it before the struct existed.
        let before = json!({"sigma": sigma, "r": r, "eta": eta, "m2": m2, "m4": m4});
        assert_eq!(s.to_json().to_string(), before.to_string());
        let up = BTreeMap::from([("s".to_string(), json!({"stats": s.to_json()}))]);
        let back = upstream_surface_stats(&up, "s").unwrap();
        assert_eq!((back.sigma, back.r, back.eta), (sigma, r, eta));
        assert_eq!((back.m2, back.m4), (Some(m2), None));
        let up = BTreeMap::from([("s".to_string(), json!({"stats": {"sigma": 1.0}}))]);
        let e = upstream_surface_stats(&up, "s").unwrap_err().to_string();
        assert_eq!(e, "surface `s` result has no `r`");
    }

    #[test]
    fn summit_heights_read_from_a_single_area_result_only() {
        let r = json!({"sigma_m": 0.4e-9, "eta_per_m2": 3e14, "mean_summit_height_m": 0.45e-9,
                       "sigma_s_m": 0.33e-9});
        let up = BTreeMap::from([("s".to_string(), r.clone())]);
        let h = upstream_summit_heights(&up, "s").unwrap();
        assert_eq!(
            (h.sigma, h.eta, h.mean, h.std),
            (0.4e-9, 3e14, 0.45e-9, 0.33e-9)
        );
        let mut areas = r.clone();
        areas["areas"] = json!({"n": 2});
        let up = BTreeMap::from([("s".to_string(), areas)]);
        assert!(upstream_summit_heights(&up, "s").is_err());
        // No summits found: σ_s is not a number (null), an error naming it.
        let mut none = r;
        none["sigma_s_m"] = Value::Null;
        let up = BTreeMap::from([("s".to_string(), none)]);
        let e = upstream_summit_heights(&up, "s").unwrap_err().to_string();
        assert!(e.contains("sigma_s_m"), "{e}");
    }
}
