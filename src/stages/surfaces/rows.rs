//! The surface stage's summary-table rows (unit suffixes in the column names): one per
//! instance in the kind's table, one per area in `areas.{csv,parquet}`.

use super::{SurfaceAnalysis, SurfaceParams};
use crate::numerics::bootstrap::Summary;
use serde::Serialize;

/// One analysed map as a table row (table units: nm, µm, µm⁻², per cent).
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceRow {
    pub file: String,
    pub format: String,
    pub channel: String,
    pub nx: usize,
    pub ny: usize,
    pub dx_nm: f64,
    pub dy_nm: f64,
    pub sigma_nm: f64,
    #[serde(rename = "Sa_nm")]
    pub sa_nm: f64,
    #[serde(rename = "Ssk")]
    pub ssk: f64,
    #[serde(rename = "Sku")]
    pub sku: f64,
    #[serde(rename = "R_um")]
    pub r_um: f64,
    pub eta_per_um2: f64,
    pub beta: f64,
    pub sigma_s_nm: f64,
    pub n_summits: usize,
    pub alpha: f64,
    #[serde(rename = "nayak_R_um")]
    pub nayak_r_um: f64,
    pub nayak_eta_per_um2: f64,
    pub nayak_beta: f64,
    pub summit_scheme: String,
    #[serde(rename = "R_definition")]
    pub r_definition: String,
    /// The levelling steps, space-separated.
    pub levelling: String,
    /// `x0 y0 width height` in µm; `None`: the whole map.
    pub crop_um: Option<String>,
    pub filter_s_um: Option<f64>,
    pub filter_l_um: Option<f64>,
    pub masked_pct: f64,
    /// The warnings, `; `-separated.
    pub warnings: String,
}

impl SurfaceRow {
    pub fn new(a: &SurfaceAnalysis, p: &SurfaceParams) -> Self {
        let r = &a.report;
        let m = a.final_map();
        SurfaceRow {
            file: p
                .file
                .file_name()
                .map(|f| f.to_string_lossy().to_string())
                .unwrap_or_default(),
            format: a.raw.source.format.clone(),
            channel: a.raw.channel.clone(),
            nx: m.nx(),
            ny: m.ny(),
            dx_nm: m.dx * 1e9,
            dy_nm: m.dy * 1e9,
            sigma_nm: r.sigma * 1e9,
            sa_nm: r.sa * 1e9,
            ssk: r.ssk,
            sku: r.sku,
            r_um: r.r * 1e6,
            eta_per_um2: r.eta * 1e-12,
            beta: r.beta,
            sigma_s_nm: r.sigma_s * 1e9,
            n_summits: r.n_summits,
            alpha: r.alpha,
            nayak_r_um: r.nayak.r * 1e6,
            nayak_eta_per_um2: r.nayak.eta * 1e-12,
            nayak_beta: r.nayak.beta,
            summit_scheme: r.summit_scheme.to_string(),
            r_definition: r.r_definition.to_string(),
            levelling: p
                .level
                .iter()
                .map(|l| l.to_string())
                .collect::<Vec<_>>()
                .join(" "),
            crop_um: p.crop.map(|c| {
                format!(
                    "{} {} {} {}",
                    c.x0 * 1e6,
                    c.y0 * 1e6,
                    c.width * 1e6,
                    c.height * 1e6
                )
            }),
            filter_s_um: p.filter_s.map(|v| v * 1e6),
            filter_l_um: p.filter_l.map(|v| v * 1e6),
            masked_pct: m.masked_fraction() * 100.0,
            warnings: r.warnings.join("; "),
        }
    }
}

/// One row of `areas.{csv,parquet}`: the area's index, then its row.
#[derive(Debug, Clone, Serialize)]
pub struct AreaRow {
    pub area: i64,
    #[serde(flatten)]
    pub row: SurfaceRow,
}

/// The instance's row in the surface table: the first area's row and, over several areas,
/// the spread columns after it.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceSummaryRow {
    #[serde(flatten)]
    pub row: SurfaceRow,
    #[serde(flatten)]
    pub areas: Option<AreaColumns>,
}

/// Mean, std and 95 % bootstrap interval over the areas of σ, R, η and β, in the row's units.
#[derive(Debug, Clone, Serialize)]
pub struct AreaColumns {
    pub n_areas: i64,
    pub sigma_nm_mean: f64,
    pub sigma_nm_std: f64,
    pub sigma_nm_ci95_low: f64,
    pub sigma_nm_ci95_high: f64,
    #[serde(rename = "R_um_mean")]
    pub r_um_mean: f64,
    #[serde(rename = "R_um_std")]
    pub r_um_std: f64,
    #[serde(rename = "R_um_ci95_low")]
    pub r_um_ci95_low: f64,
    #[serde(rename = "R_um_ci95_high")]
    pub r_um_ci95_high: f64,
    pub eta_per_um2_mean: f64,
    pub eta_per_um2_std: f64,
    pub eta_per_um2_ci95_low: f64,
    pub eta_per_um2_ci95_high: f64,
    pub beta_mean: f64,
    pub beta_std: f64,
    pub beta_ci95_low: f64,
    pub beta_ci95_high: f64,
}

impl AreaColumns {
    /// From the summaries of σ, R, η and β (SI) and their table-unit factors.
    pub fn new(n_areas: usize, [sigma, r, eta, beta]: [(Summary, f64); 4]) -> Self {
        let s = |(x, k): (Summary, f64)| [x.mean * k, x.std * k, x.ci_low * k, x.ci_high * k];
        let [sigma_nm_mean, sigma_nm_std, sigma_nm_ci95_low, sigma_nm_ci95_high] = s(sigma);
        let [r_um_mean, r_um_std, r_um_ci95_low, r_um_ci95_high] = s(r);
        let [eta_per_um2_mean, eta_per_um2_std, eta_per_um2_ci95_low, eta_per_um2_ci95_high] =
            s(eta);
        let [beta_mean, beta_std, beta_ci95_low, beta_ci95_high] = s(beta);
        AreaColumns {
            n_areas: n_areas as i64,
            sigma_nm_mean,
            sigma_nm_std,
            sigma_nm_ci95_low,
            sigma_nm_ci95_high,
            r_um_mean,
            r_um_std,
            r_um_ci95_low,
            r_um_ci95_high,
            eta_per_um2_mean,
            eta_per_um2_std,
            eta_per_um2_ci95_low,
            eta_per_um2_ci95_high,
            beta_mean,
            beta_std,
            beta_ci95_low,
            beta_ci95_high,
        }
    }
}
