//! The DOE's figures (Figs 2.26–2.30, Table 2.8): these helpers only assemble data for
//! `crate::figures`.

use super::optimise::DesignSweep;
use super::params::{DoeParams, FACTORS, NM, UM};
use super::surface::LevelFit;
use crate::error::Result;
use crate::numerics::annealing::AnnealingRecord;
use crate::numerics::regression::decoded;
use std::path::Path;

/// Contour panels of one level: ξ over the two free factors at the fixed one's three levels.
pub(crate) fn contour_png(
    path: &Path,
    p: &DoeParams,
    lf: &LevelFit,
    points: &[[f64; 3]],
) -> Result<()> {
    use crate::figures::{contour_panels_png, ContourPanel};
    const N: usize = 41;
    let free: Vec<usize> = (0..3).filter(|f| *f != lf.fixed).collect();
    let (fx, fy) = (free[0], free[1]);
    let grid = |f: usize| -> Vec<f64> {
        (0..N)
            .map(|i| {
                decoded(
                    -1.0 + 2.0 * i as f64 / (N - 1) as f64,
                    p.levels[f][0],
                    p.levels[f][2],
                ) / UM
            })
            .collect()
    };
    let poly = lf.quartic.polynomial();
    let desc = |f: usize| format!("{} (µm)", FACTORS[f].replace("_tfc", "_TFC"));
    let (xd, yd) = (desc(fx), desc(fy));
    let titles: Vec<String> = [-1.0, 0.0, 1.0]
        .iter()
        .map(|&level| {
            format!(
                "{} = {:.3} µm",
                FACTORS[lf.fixed].replace("_tfc", "_TFC"),
                decoded(level, p.levels[lf.fixed][0], p.levels[lf.fixed][2]) / UM
            )
        })
        .collect();
    let panels: Vec<ContourPanel> = [-1.0, 0.0, 1.0]
        .iter()
        .zip(&titles)
        .map(|(&level, title)| {
            let z = ndarray::Array2::from_shape_fn((N, N), |(iy, ix)| {
                let mut c = [0.0; 3];
                c[lf.fixed] = level;
                c[fx] = -1.0 + 2.0 * ix as f64 / (N - 1) as f64;
                c[fy] = -1.0 + 2.0 * iy as f64 / (N - 1) as f64;
                poly.eval(&c)
            });
            let fixed_value = decoded(level, p.levels[lf.fixed][0], p.levels[lf.fixed][2]);
            ContourPanel {
                title,
                x_desc: &xd,
                y_desc: &yd,
                x: grid(fx),
                y: grid(fy),
                z,
                points: points
                    .iter()
                    .filter(|d| (d[lf.fixed] - fixed_value).abs() < 1e-12)
                    .map(|d| (d[fx] / UM, d[fy] / UM))
                    .collect(),
                marker: None,
            }
        })
        .collect();
    contour_panels_png(
        path,
        &format!(
            "Flyability ξ (degree-4 response surface), h_TFC = {:.1} nm (Figs 2.26–2.29)",
            lf.actuation / NM
        ),
        "ξ",
        &panels,
    )?;
    Ok(())
}

/// Residual diagnostics of one level's degree-4 surface.
pub(crate) fn residuals_png(path: &Path, lf: &LevelFit) -> Result<()> {
    let diag = lf.quartic.fit.residual_diagnostics();
    crate::figures::residual_panels_png(
        path,
        &format!(
            "Residuals of the degree-4 ξ surface, h_TFC = {:.1} nm",
            lf.actuation / NM
        ),
        &diag.fitted_residual,
        &diag.normal_probability,
    )?;
    Ok(())
}

/// The annealing's convergence: current and best J per iteration, with the temperature.
pub(crate) fn annealing_convergence_png(
    path: &Path,
    p: &DoeParams,
    history: &[AnnealingRecord],
) -> Result<()> {
    let curve: Vec<(f64, f64, f64)> = history
        .iter()
        .map(|r| (r.iteration as f64, r.current_j, r.best_j))
        .collect();
    let temps: Vec<f64> = history.iter().map(|r| r.temperature).collect();
    crate::figures::annealing_png(
        path,
        &format!(
            "Simulated annealing of ξ at h_TFC = {:.1} nm (Fig. 2.30)",
            p.sa_actuation / NM
        ),
        &curve,
        Some(&temps),
    )?;
    Ok(())
}

/// Steady clearance over actuation of the initial and the optimised design (Table 2.8).
pub(crate) fn comparison_png(path: &Path, p: &DoeParams, sweeps: &[DesignSweep]) -> Result<()> {
    let t0 = 0.5 * p.base.model.interface.lubricant_thickness / NM;
    let sweep_series: Vec<crate::figures::SweepSeries> = sweeps
        .iter()
        .map(|s| crate::figures::SweepSeries {
            label: s.label,
            points: s
                .outcomes
                .iter()
                .map(|c| {
                    (
                        c.actuation / NM,
                        c.metrics.clearance_m.mean / NM,
                        c.metrics.clearance_m.std / NM,
                    )
                })
                .collect(),
        })
        .collect();
    crate::figures::clearance_sweep_png(
        path,
        "Initial vs optimised design: steady clearance (Table 2.8)",
        "TFC actuation (nm)",
        "clearance (nm)",
        &sweep_series,
        &[],
        &[(0.0, "solid contact"), (t0, "T0"), (2.0 * t0, "2T0")],
    )?;
    Ok(())
}
