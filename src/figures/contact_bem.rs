//! The deterministic-contact stage's figures (docs/contact.md, "Deterministic contact"): BEM
//! and ISBL pressure and real area against h/σ, their ratio, the pressure map at one
//! separation and the gap histogram there.

use super::basic::{field_png, histogram_png, semilogy_png, ColourScale};
use super::Result;
use crate::contact::bem::GapHistogram;

/// One separation of the overlay: BEM pressure [Pa] and A_r/A_0, and ISBL's when overlaid.
#[derive(Debug, Clone, Copy)]
pub struct OverlayPoint {
    pub h_star: f64,
    pub bem: (f64, f64),
    pub isbl: Option<(f64, f64)>,
}
use ndarray::ArrayView2;
use std::path::Path;

/// Every figure of one instance into `dir`.
pub fn write_all(
    dir: &Path,
    curve: &[OverlayPoint],
    pressure: &[f64],
    ((nx, ny), (dx, dy)): ((usize, usize), (f64, f64)),
    histogram: &GapHistogram,
    map_at: f64,
) -> Result<()> {
    let series = |f: &dyn Fn(&OverlayPoint) -> Option<f64>| {
        curve
            .iter()
            .filter_map(|p| f(p).map(|v| (p.h_star, v)))
            .collect::<Vec<_>>()
    };
    let mut pressures = vec![("BEM (measured map)", series(&|p| Some(p.bem.0 * 1e-6)))];
    let mut areas = vec![("BEM (measured map)", series(&|p| Some(p.bem.1)))];
    if curve.iter().any(|p| p.isbl.is_some()) {
        pressures.push(("ISBL", series(&|p| p.isbl.map(|v| v.0 * 1e-6))));
        areas.push(("ISBL", series(&|p| p.isbl.map(|v| v.1))));
        let ratio = series(&|p| p.isbl.filter(|v| v.0 > 0.0).map(|v| p.bem.0 / v.0));
        semilogy_png(
            &dir.join("bem_isbl_ratio.png"),
            "BEM / ISBL contact pressure",
            "h/σ",
            "P_BEM / P_ISBL",
            &[("P_BEM / P_ISBL", ratio)],
            &[],
        )?;
    }
    semilogy_png(
        &dir.join("bem_pressure.png"),
        "Contact pressure vs separation",
        "h/σ",
        "mean contact pressure (MPa)",
        &pressures,
        &[],
    )?;
    semilogy_png(
        &dir.join("bem_real_area.png"),
        "Real contact area vs separation",
        "h/σ",
        "A_r / A_0",
        &areas,
        &[],
    )?;
    let field = ArrayView2::from_shape((ny, nx), pressure)
        .map_err(|e| super::kit::perr(&dir.join("bem_pressure_map.png"), format!("field: {e}")))?;
    field_png(
        &dir.join("bem_pressure_map.png"),
        field,
        (dx, dy),
        &format!("Contact pressure at h/σ = {map_at}"),
        ColourScale {
            factor: 1e-6,
            label: "pressure (MPa)",
        },
    )?;
    let total: u64 = histogram.counts.iter().sum::<u64>() + histogram.in_contact;
    let width = histogram.edges[1] - histogram.edges[0];
    let density: Vec<f64> = histogram
        .counts
        .iter()
        .map(|&c| c as f64 / (total.max(1) as f64 * width))
        .collect();
    histogram_png(
        &dir.join("bem_gap_histogram.png"),
        &histogram.edges,
        &density,
        &[],
        1.0,
        &format!(
            "Gaps at h/σ = {map_at} ({:.2} % of the area in contact)",
            100.0 * histogram.in_contact as f64 / total.max(1) as f64
        ),
        "gap / σ",
        "",
    )
}
