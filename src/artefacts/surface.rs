//! What a surface instance hands on: its `result.json` ([`SurfaceResult`]: the `hdi surface
//! --json` report, the summit statistics the interface stage combines, and the spread over
//! areas when there are several), read downstream through the same types.

use crate::error::{Error, Result};
use crate::surface::combine::{SummitHeights, SurfaceStats};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// Roughness parameters of one height map (docs/surfaces.md), SI units named in the keys;
/// dimensionless quantities have no suffix. Schema version 1 (docs/json.md): existing keys
/// keep their name, unit and type; renaming or removing one makes version 2.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SurfaceReport {
    /// The height map as given on the command line.
    pub file: String,
    /// Detected file format (e.g. `gwy`, `spm`, `gsf`).
    pub format: String,
    /// Channel read.
    pub channel: String,
    /// Columns analysed (after cropping).
    #[schemars(range(min = 1))]
    pub nx: usize,
    /// Rows analysed (after cropping).
    #[schemars(range(min = 1))]
    pub ny: usize,
    /// Pixel size along x, m.
    pub dx_m: f64,
    /// Pixel size along y, m.
    pub dy_m: f64,
    /// RMS roughness σ (Sq), m.
    pub sigma_m: f64,
    /// Arithmetic mean height Sa, m.
    #[serde(rename = "Sa_m")]
    pub sa_m: f64,
    /// Skewness, dimensionless. `null` when not defined for this input (docs/json.md).
    #[serde(rename = "Ssk")]
    pub ssk: Option<f64>,
    /// Kurtosis, dimensionless. `null` when not defined for this input (docs/json.md).
    #[serde(rename = "Sku")]
    pub sku: Option<f64>,
    /// Second spectral moment (mean square slope), dimensionless. `null` when not defined for
    /// this input (docs/json.md).
    pub m2: Option<f64>,
    /// Fourth spectral moment (mean square curvature), 1/m². `null` when not defined for this
    /// input (docs/json.md).
    pub m4_per_m2: Option<f64>,
    /// Nayak's bandwidth parameter α = m0·m4/m2², dimensionless. `null` when not defined for
    /// this input (docs/json.md).
    pub alpha: Option<f64>,
    /// How m2 and m4 are estimated.
    #[schemars(extend("enum" = ["finite_difference", "spectral"]))]
    pub moments_method: String,
    /// Summit density η, 1/m². `null` when not defined for this input (docs/json.md).
    pub eta_per_m2: Option<f64>,
    /// Mean summit radius R (per `R_definition`), m. `null` when not defined for this input
    /// (docs/json.md).
    #[serde(rename = "R_m")]
    pub r_m: Option<f64>,
    /// Which summit-radius average `R_m` is (e.g. `inverse_mean_curvature`).
    #[serde(rename = "R_definition")]
    pub r_definition: String,
    /// 1 / mean summit curvature, m. `null` when not defined for this input (docs/json.md).
    #[serde(rename = "R_mean_of_inverse_m")]
    pub r_mean_of_inverse_m: Option<f64>,
    /// 1 / median summit curvature, m. `null` when not defined for this input (docs/json.md).
    #[serde(rename = "R_median_of_inverse_m")]
    pub r_median_of_inverse_m: Option<f64>,
    /// β = σ·R·η, dimensionless. `null` when not defined for this input (docs/json.md).
    pub beta: Option<f64>,
    /// Standard deviation of the summit heights, m. `null` when not defined for this input
    /// (docs/json.md).
    pub sigma_s_m: Option<f64>,
    /// Mean summit height above the mean plane, m. `null` when not defined for this input
    /// (docs/json.md).
    pub mean_summit_height_m: Option<f64>,
    /// Summits found.
    pub n_summits: usize,
    /// Summit definition: `9-point`, `5-point`, optionally with Birmingham thresholds.
    pub summit_scheme: String,
    /// Sampling interval used for the derivatives, m.
    pub sampling_interval_m: f64,
    /// Nayak's random-process estimates (docs/surfaces.md).
    pub nayak: NayakReport,
    /// Levelling steps applied, in order (e.g. `rows:median`, `plane`, `mean`).
    pub levelling: Vec<String>,
    /// Analysed rectangle [x0, y0, width, height], m (y down from the top row); null: the
    /// whole map.
    pub crop_m: Option<[f64; 4]>,
    /// S-filter (Gaussian low-pass) cutoff, m; null: no S-filter.
    pub filter_s_m: Option<f64>,
    /// L-filter (Gaussian high-pass) cutoff, m; null: no L-filter.
    pub filter_l_m: Option<f64>,
    /// Fraction of pixels masked (invalid), 0–1.
    pub masked_fraction: f64,
    /// Warnings in words (also why a value is null).
    pub warnings: Vec<String>,
    /// The scanning-probe tip-radius reliability cutoff and σ, R, η, β above it
    /// (docs/surfaces.md, "Surface analyses"); present only when a tip radius is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip_reliability: Option<TipReliabilityReport>,
}

/// The tip-radius reliability cutoff (SurfaceTopography's `scanning_probe_reliability_cutoff`)
/// and the roughness above it: the analysed map S-filtered (ISO 16610-61 Gaussian) at
/// λs = the cutoff.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TipReliabilityReport {
    /// Tip radius given, m.
    pub tip_radius_m: f64,
    /// Safety factor f of the criterion min h''(λ) = −f/R, dimensionless.
    pub safety_factor: f64,
    /// `cutoff`: data below `cutoff_m` are unreliable; `no_artefacts`: the curvature criterion
    /// holds down to the pixel scale (the values above the cutoff are the raw ones);
    /// `no_reliable_data`: it fails even at the largest scale; `not_computed`: the map has
    /// invalid pixels (see `warnings`).
    #[schemars(extend("enum" = ["cutoff", "no_artefacts", "no_reliable_data", "not_computed"]))]
    pub status: String,
    /// Stencil length λc below which the curvature exceeds what the tip can follow, m; for
    /// `no_reliable_data` the mean physical size. `null` for `no_artefacts` and `not_computed`.
    pub cutoff_m: Option<f64>,
    /// σ above the cutoff, m. `null` when not defined (docs/json.md).
    pub sigma_m: Option<f64>,
    /// Summit density above the cutoff, 1/m². `null` when not defined (docs/json.md).
    pub eta_per_m2: Option<f64>,
    /// Mean summit radius above the cutoff (same definition as `R_m`), m. `null` when not
    /// defined (docs/json.md).
    #[serde(rename = "R_m")]
    pub r_m: Option<f64>,
    /// β = σ·R·η above the cutoff, dimensionless. `null` when not defined (docs/json.md).
    pub beta: Option<f64>,
    /// Summits found above the cutoff.
    pub n_summits: Option<usize>,
}

/// Nayak's random-process estimates (docs/surfaces.md).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct NayakReport {
    /// Summit density from the spectral moments (Nayak), 1/m². `null` when not defined for
    /// this input (docs/json.md).
    pub eta_per_m2: Option<f64>,
    /// Mean summit radius from the spectral moments, m. `null` when not defined for this
    /// input (docs/json.md).
    #[serde(rename = "R_m")]
    pub r_m: Option<f64>,
    /// σ·R·η from the Nayak values, dimensionless. `null` when not defined for this input
    /// (docs/json.md).
    pub beta: Option<f64>,
    /// Summit-height standard deviation from the spectral moments, m. `null` when not defined
    /// for this input (docs/json.md).
    pub sigma_s_m: Option<f64>,
}

/// A surface instance's `result.json`: the report of its (first) area, the statistics the
/// interface combines and, over several areas, their spread.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurfaceResult {
    #[serde(flatten)]
    pub report: SurfaceReport,
    /// What the interface stage combines (the means over areas when there are several).
    pub stats: SummitStats,
    /// Several areas: the spread of each quantity over them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub areas: Option<AreasSummary>,
}

/// `areas` of a result over several (file × crop) areas (docs/surfaces.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AreasSummary {
    /// Areas analysed.
    pub n: usize,
    /// Mean, std and bootstrap interval of each quantity over the areas.
    pub summary: AreaQuantities,
    pub bootstrap: BootstrapSettings,
    /// The per-area table beside the result.
    pub table: String,
}

/// The quantities summarised over areas, in table order.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AreaQuantities {
    pub sigma: Spread,
    #[serde(rename = "R")]
    pub r: Spread,
    pub eta: Spread,
    pub beta: Spread,
    pub m2: Spread,
    pub m4: Spread,
}

/// One quantity over the areas (SI); `None` where it is not finite (e.g. the std of one area).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    pub mean: Option<f64>,
    pub std: Option<f64>,
    /// 95 % percentile-bootstrap interval of the mean, [low, high].
    pub ci95: [Option<f64>; 2],
    pub n: usize,
}

/// How the intervals were drawn (`numerics::bootstrap`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BootstrapSettings {
    pub resamples: usize,
    pub level: f64,
    pub seed: u64,
}

/// `stats` as written: SI values; one that is not finite is written as `null` (`None`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SummitStats {
    pub sigma: Option<f64>,
    pub r: Option<f64>,
    pub eta: Option<f64>,
    pub m2: Option<f64>,
    pub m4: Option<f64>,
}

impl SummitStats {
    /// The statistics of surface instance `name`; a missing σ, R or η is an error naming
    /// it, a missing moment is `None`.
    pub fn stats(&self, name: &str) -> Result<SurfaceStats> {
        let get = |v: Option<f64>, k: &str| {
            v.ok_or_else(|| Error::UpstreamField {
                kind: "surface",
                name: name.to_string(),
                what: format!("`{k}`"),
            })
        };
        Ok(SurfaceStats {
            sigma: get(self.sigma, "sigma")?,
            r: get(self.r, "r")?,
            eta: get(self.eta, "eta")?,
            m2: self.m2,
            m4: self.m4,
        })
    }
}

/// The result of the upstream surface instance `name`.
fn upstream(upstream: &BTreeMap<String, Value>, name: &str) -> Result<SurfaceResult> {
    super::upstream_result(upstream, "surface", name)
}

/// The summit statistics of the upstream surface instance `name`.
pub fn upstream_surface_stats(
    upstream_results: &BTreeMap<String, Value>,
    name: &str,
) -> Result<SurfaceStats> {
    upstream(upstream_results, name)?.stats.stats(name)
}

/// The height map a surface instance analysed last (its `surface.h5`: the filtered map when a
/// filter ran, else the levelled one, as the group's `default` attribute says), in metres,
/// `[ny, nx]`, with its spacing. A surface of several areas is refused (its file holds one
/// map per area).
pub struct FinalMap {
    pub z: ndarray::Array2<f64>,
    pub dx: f64,
    pub dy: f64,
}

/// The [`FinalMap`] of the upstream surface instance `name` (from its store directory).
pub fn upstream_final_map(
    upstream_dirs: &BTreeMap<String, std::path::PathBuf>,
    name: &str,
) -> Result<FinalMap> {
    let dir = upstream_dirs
        .get(name)
        .ok_or_else(|| Error::MissingUpstreamFiles {
            kind: "surface",
            name: name.to_string(),
        })?;
    let path = dir.join("surface.h5");
    let read_err = |what: String| {
        let path = path.clone();
        move |source| Error::Hdf5Read { path, what, source }
    };
    let file = hdf5::File::open(&path).map_err(|source| Error::Hdf5Open {
        path: path.clone(),
        source,
    })?;
    let entry = file.group("surface").map_err(|_| Error::UpstreamField {
        kind: "surface",
        name: name.to_string(),
        what: "single map (several areas: give the BEM one area)".into(),
    })?;
    let default = entry
        .attr("default")
        .and_then(|a| a.read_scalar::<hdf5::types::VarLenUnicode>())
        .map_err(read_err("surface `default` attribute".into()))?
        .to_string();
    let group = format!("surface/{default}");
    let z = file
        .dataset(&format!("{group}/height"))
        .and_then(|d| d.read_2d::<f64>())
        .map_err(read_err(format!("{group}/height")))?;
    let axis = |a: &str| -> Result<f64> {
        let v = file
            .dataset(&format!("{group}/{a}"))
            .and_then(|d| d.read_raw::<f64>())
            .map_err(read_err(format!("{group}/{a}")))?;
        Ok(if v.len() >= 2 { v[1] - v[0] } else { f64::NAN })
    };
    let (dx, dy) = (axis("x")?, axis("y")?);
    if !(dx > 0.0 && dy > 0.0) {
        return Err(Error::UpstreamField {
            kind: "surface",
            name: name.to_string(),
            what: format!("usable pixel spacing in {group} (dx = {dx}, dy = {dy})"),
        });
    }
    Ok(FinalMap { z, dx, dy })
}

/// The measured summit heights of the upstream surface instance `name` (its discrete summits:
/// `mean_summit_height_m`, `sigma_s_m`, with `sigma_m` and `eta_per_m2`). A surface of several
/// areas is refused: its result carries these for the first area only.
pub fn upstream_summit_heights(
    upstream_results: &BTreeMap<String, Value>,
    name: &str,
) -> Result<SummitHeights> {
    let result = upstream(upstream_results, name)?;
    let field = |what: String| Error::UpstreamField {
        kind: "surface",
        name: name.to_string(),
        what,
    };
    if result.areas.is_some() {
        return Err(field(
            "summit heights over its areas (several areas: the result holds the first \
             area's only; measure the summits on one area)"
                .into(),
        ));
    }
    let r = &result.report;
    let get = |v: Option<f64>, k: &str| v.ok_or_else(|| field(format!("`{k}`")));
    Ok(SummitHeights {
        sigma: get(Some(r.sigma_m), "sigma_m")?,
        eta: get(r.eta_per_m2, "eta_per_m2")?,
        mean: get(r.mean_summit_height_m, "mean_summit_height_m")?,
        std: get(r.sigma_s_m, "sigma_s_m")?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artefacts::finite;
    use serde_json::json;

    fn report() -> SurfaceReport {
        SurfaceReport {
            file: "s.gwy".into(),
            format: "gwy".into(),
            channel: "Height".into(),
            nx: 4,
            ny: 4,
            dx_m: 1e-9,
            dy_m: 1e-9,
            sigma_m: 0.4e-9,
            sa_m: 0.3e-9,
            ssk: Some(0.1),
            sku: Some(3.0),
            m2: Some(1e-3),
            m4_per_m2: Some(4e12),
            alpha: Some(5.0),
            moments_method: "finite_difference".into(),
            eta_per_m2: Some(3e14),
            r_m: Some(0.36e-6),
            r_definition: "inverse_mean_curvature".into(),
            r_mean_of_inverse_m: Some(0.42e-6),
            r_median_of_inverse_m: Some(0.37e-6),
            beta: Some(0.04),
            sigma_s_m: Some(0.33e-9),
            mean_summit_height_m: Some(0.45e-9),
            n_summits: 3,
            summit_scheme: "9-point".into(),
            sampling_interval_m: 1e-9,
            nayak: NayakReport {
                eta_per_m2: Some(4e14),
                r_m: Some(0.33e-6),
                beta: Some(0.045),
                sigma_s_m: None,
            },
            levelling: vec!["plane".into()],
            crop_m: None,
            filter_s_m: None,
            filter_l_m: Some(2.5e-7),
            masked_fraction: 0.0,
            warnings: Vec::new(),
            tip_reliability: None,
        }
    }

    fn upstream_of(result: &SurfaceResult) -> BTreeMap<String, Value> {
        BTreeMap::from([("s".to_string(), serde_json::to_value(result).unwrap())])
    }

    #[test]
    fn written_json_is_unchanged_and_reads_back() {
        let (sigma, r, eta, m2, m4) = (0.5e-9, 0.43e-6, 124e12, 1.5e-3, f64::NAN);
        let s = SummitStats {
            sigma: Some(sigma),
            r: Some(r),
            eta: Some(eta),
            m2: finite(m2),
            m4: finite(m4),
        };
        // As the surface stage wrote it before the struct existed.
        let before = json!({"sigma": sigma, "r": r, "eta": eta, "m2": m2, "m4": m4});
        assert_eq!(serde_json::to_string(&s).unwrap(), before.to_string());
        let mut result = SurfaceResult {
            report: report(),
            stats: s,
            areas: None,
        };
        // The report's keys first (flattened), then `stats`; no `areas` for one area.
        let v = serde_json::to_value(&result).unwrap();
        let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
        assert_eq!(keys.first().map(|k| k.as_str()), Some("file"));
        assert_eq!(keys.last().map(|k| k.as_str()), Some("stats"));
        let back = upstream_surface_stats(&upstream_of(&result), "s").unwrap();
        assert_eq!((back.sigma, back.r, back.eta), (sigma, r, eta));
        assert_eq!((back.m2, back.m4), (Some(m2), None));
        result.stats.r = None;
        let e = upstream_surface_stats(&upstream_of(&result), "s")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "surface `s` result has no `r`");
        let e = upstream_surface_stats(&BTreeMap::new(), "s").unwrap_err();
        assert_eq!(e.to_string(), "no result from surface `s`");
    }

    #[test]
    fn summit_heights_read_from_a_single_area_result_only() {
        let stats = SummitStats {
            sigma: Some(0.4e-9),
            r: Some(0.36e-6),
            eta: Some(3e14),
            m2: None,
            m4: None,
        };
        let mut result = SurfaceResult {
            report: report(),
            stats,
            areas: None,
        };
        let h = upstream_summit_heights(&upstream_of(&result), "s").unwrap();
        assert_eq!(
            (h.sigma, h.eta, h.mean, h.std),
            (0.4e-9, 3e14, 0.45e-9, 0.33e-9)
        );
        let spread = Spread {
            mean: Some(1.0),
            std: None,
            ci95: [Some(1.0), Some(1.0)],
            n: 2,
        };
        let mut areas = result.clone();
        areas.areas = Some(AreasSummary {
            n: 2,
            summary: AreaQuantities {
                sigma: spread,
                r: spread,
                eta: spread,
                beta: spread,
                m2: spread,
                m4: spread,
            },
            bootstrap: BootstrapSettings {
                resamples: 2000,
                level: 0.95,
                seed: 1,
            },
            table: "areas.csv".into(),
        });
        assert!(upstream_summit_heights(&upstream_of(&areas), "s").is_err());
        // No summits found: σ_s is not a number (null), an error naming it.
        result.report.sigma_s_m = finite(f64::NAN);
        let up = upstream_of(&result);
        assert!(up["s"]["sigma_s_m"].is_null());
        let e = upstream_summit_heights(&up, "s").unwrap_err().to_string();
        assert!(e.contains("sigma_s_m"), "{e}");
    }
}
