//! What a bulge instance hands on: its `result.json` ([`BulgeReport`], also what `hdi bulge
//! --json` prints) with the fitted TFC bulge (`tfc`): the geometry a `[simulate]` instance with
//! `geometry = { bulge = "NAME" }` uses, and the efficiency that turns heater power into
//! actuation (docs/bulge.md).

use crate::error::Result;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// TFC bulge per scan and the efficiency over heater power (docs/bulge.md); SI units named in
/// the keys. Schema version 1 (docs/json.md): existing keys keep their name, unit and type;
/// renaming or removing one makes version 2.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BulgeReport {
    /// One object per file, in command-line order.
    pub scans: Vec<BulgeScan>,
    /// Bulge growth per heater power, m/W; null with fewer than two scans at known, different
    /// powers. `null` when not defined for this input (docs/json.md).
    #[serde(rename = "efficiency_m_per_W")]
    pub efficiency_m_per_w: Option<f64>,
    /// Its standard error, m/W. `null` when not defined for this input (docs/json.md).
    #[serde(rename = "efficiency_se_m_per_W")]
    pub efficiency_se_m_per_w: Option<f64>,
    /// Unpowered bulge height (fit intercept), m. `null` when not defined for this input
    /// (docs/json.md).
    pub intercept_m: Option<f64>,
    /// Its standard error, m. `null` when not defined for this input (docs/json.md).
    pub intercept_se_m: Option<f64>,
    /// The geometry handed to the slider stages (result.json `tfc`).
    pub tfc: FittedBulge,
}

/// One profilometer scan's fit (docs/bulge.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BulgeScan {
    /// File name of the scan.
    pub file: String,
    /// Heater power, mW (from --power or the file name); null: unknown. `null` when not
    /// defined for this input (docs/json.md).
    #[serde(rename = "heater_power_mW")]
    pub heater_power_mw: Option<f64>,
    /// Bulge height, m. `null` when not defined for this input (docs/json.md).
    pub height_m: Option<f64>,
    /// Its standard error, m. `null` when not defined for this input (docs/json.md).
    pub height_se_m: Option<f64>,
    /// Half-length along the slider a, m. `null` when not defined for this input
    /// (docs/json.md).
    pub a_tfc_m: Option<f64>,
    /// Its standard error, m. `null` when not defined for this input (docs/json.md).
    pub a_tfc_se_m: Option<f64>,
    /// Full width across the slider w, m. `null` when not defined for this input
    /// (docs/json.md).
    pub w_tfc_m: Option<f64>,
    /// Its standard error, m. `null` when not defined for this input (docs/json.md).
    pub w_tfc_se_m: Option<f64>,
    /// Bulge centre distance from the trailing edge x_TFC, m; null: no edge detected. `null`
    /// when not defined for this input (docs/json.md).
    pub x_tfc_m: Option<f64>,
    /// Its standard error, m; null: no edge detected. `null` when not defined for this input
    /// (docs/json.md).
    pub x_tfc_se_m: Option<f64>,
    /// Bulge centre along the scan, m. `null` when not defined for this input (docs/json.md).
    pub x_c_m: Option<f64>,
    /// Bulge centre across the scans, m. `null` when not defined for this input
    /// (docs/json.md).
    pub y_c_m: Option<f64>,
    /// Standard error of y_c, m. `null` when not defined for this input (docs/json.md).
    pub y_c_se_m: Option<f64>,
    /// Detected trailing-edge position, m; null: none detected (or --no-auto-te). `null` when
    /// not defined for this input (docs/json.md).
    pub trailing_edge_x_m: Option<f64>,
    /// RMS residual of the fit, m. `null` when not defined for this input (docs/json.md).
    pub residual_rms_m: Option<f64>,
    /// Pixels fitted.
    pub n_pixels: usize,
}

/// The fitted bulge as written (SI units, unit suffixes in the keys).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct FittedBulge {
    /// Inverse-variance mean half-length, m.
    pub a_tfc_m: f64,
    /// Inverse-variance mean width, m.
    pub w_tfc_m: f64,
    /// Inverse-variance mean distance from the trailing edge, m. `null` when not defined for
    /// this input (docs/json.md).
    pub x_tfc_m: Option<f64>,
    /// As above, m/W. `null` when not defined for this input (docs/json.md).
    #[serde(rename = "efficiency_m_per_W")]
    pub efficiency_m_per_w: Option<f64>,
    /// As above, m. `null` when not defined for this input (docs/json.md).
    pub intercept_m: Option<f64>,
}

/// The fitted bulge of the bulge instance `name` from the upstream results.
pub fn upstream_bulge(upstream: &BTreeMap<String, Value>, name: &str) -> Result<FittedBulge> {
    let report: BulgeReport = super::upstream_result(upstream, "bulge", name)?;
    Ok(report.tfc)
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
        let report = BulgeReport {
            scans: Vec::new(),
            efficiency_m_per_w: Some(3e-7),
            efficiency_se_m_per_w: None,
            intercept_m: Some(3e-9),
            intercept_se_m: None,
            tfc: b,
        };
        let written = serde_json::to_value(&report).unwrap();
        assert!(written["tfc"]["efficiency_m_per_W"].is_number());
        assert!(written["efficiency_se_m_per_W"].is_null());
        let up = BTreeMap::from([("tfc".to_string(), written)]);
        assert_eq!(upstream_bulge(&up, "tfc").unwrap(), b);
        assert!(upstream_bulge(&up, "other").is_err());
        let bad = BTreeMap::from([("tfc".to_string(), json!({}))]);
        assert!(upstream_bulge(&bad, "tfc").is_err());
    }
}
