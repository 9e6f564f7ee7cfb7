//! The DOE's tables (docs/doe.md): the design, the annealing, Table 2.7's predictive
//! equations, the surfaces' coefficients and ANOVA, and Table 2.8's comparison, as rows.

use super::cases::DesignCase;
use super::params::{DoeParams, FACTORS, NM, UM};
use super::surface::{model_selection, LevelFit};
use crate::artefacts::doe::{ComparisonRow, DegreeTest, LevelFitSummary, SurfaceFitSummary};
use crate::dynamics::metrics::Regime;
use crate::error::{Error, Result};
use crate::numerics::annealing::AnnealingRecord;
use crate::numerics::regression::{decoded, Polynomial, ResponseSurface};
use crate::slider::case::SweepCaseResult;
use crate::slider::params::SimulateParams;
use crate::slider::sweep::{sweep_analysis, CaseOutcome};
use serde::Serialize;
use serde_json::Value;

/// A table value: seven significant digits, null when not finite.
pub(crate) fn table_value(v: f64) -> Option<f64> {
    v.is_finite()
        .then(|| crate::core::store::round_significant(v, 7))
}

/// A table value of a quantity a case's result.json may hold as null (non-finite).
fn finite_value(v: f64, scale: f64) -> Option<f64> {
    Some(v)
        .filter(|v| v.is_finite())
        .and_then(|v| table_value(v / scale))
}

/// One row of the design table: a case, its coded point and bulge, and its response.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct DesignRow {
    pub run: usize,
    pub a_tfc_coded: f64,
    pub w_tfc_coded: f64,
    pub x_tfc_coded: f64,
    pub a_um: Option<f64>,
    pub w_um: Option<f64>,
    pub x_um: Option<f64>,
    pub actuation_nm: Option<f64>,
    pub clearance_nm: Option<f64>,
    pub fhm_or_bv_percent: Option<f64>,
    pub regime: String,
    pub xi: Option<f64>,
    pub case_key: String,
}

/// The design table: one row per case, level by level.
pub(crate) fn design_rows(
    coded_points: &[Vec<f64>],
    per_level: usize,
    cases: &[DesignCase],
) -> Vec<DesignRow> {
    cases
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let coded_point = &coded_points[i % per_level];
            let m = &c.result;
            DesignRow {
                run: i + 1,
                a_tfc_coded: coded_point[0],
                w_tfc_coded: coded_point[1],
                x_tfc_coded: coded_point[2],
                a_um: table_value(c.design[0] / UM),
                w_um: table_value(c.design[1] / UM),
                x_um: table_value(c.design[2] / UM),
                actuation_nm: table_value(c.actuation / NM),
                // A non-finite value is null in the case's result.json: null here too.
                clearance_nm: finite_value(m.clearance_m.mean, NM),
                fhm_or_bv_percent: finite_value(m.vibration_percent, 1.0),
                regime: regime_label_of(&m.regime),
                xi: table_value(c.xi),
                case_key: c.entry.key.clone(),
            }
        })
        .collect()
}

/// A case result's regime as the tables name it (`regime_label`).
fn regime_label_of(regime: &str) -> String {
    match crate::slider::sweep::regime_label(&Value::from(regime)) {
        Value::String(s) => s,
        _ => regime.to_string(),
    }
}

/// One evaluation of the annealing, with its ξ.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct AnnealingRow {
    pub iteration: usize,
    pub temperature: Option<f64>,
    pub a_um: Option<f64>,
    pub w_um: Option<f64>,
    pub x_um: Option<f64>,
    pub xi: Option<f64>,
    pub candidate_j: Option<f64>,
    pub accepted: bool,
    pub current_j: Option<f64>,
    pub best_j: Option<f64>,
}

/// The annealing table: one row per evaluation, with its ξ.
pub(crate) fn annealing_rows(
    p: &DoeParams,
    history: &[AnnealingRecord],
    xis: &[f64],
) -> Vec<AnnealingRow> {
    history
        .iter()
        .zip(xis)
        .map(|(r, xi)| {
            let d = p.decode(&r.candidate);
            AnnealingRow {
                iteration: r.iteration,
                temperature: table_value(r.temperature),
                a_um: table_value(d[0] / UM),
                w_um: table_value(d[1] / UM),
                x_um: table_value(d[2] / UM),
                xi: table_value(*xi),
                candidate_j: table_value(r.candidate_j),
                accepted: r.accepted,
                current_j: table_value(r.current_j),
                best_j: table_value(r.best_j),
            }
        })
        .collect()
}

/// One of Table 2.7's predictive equations: a level's quartic with one factor fixed at a
/// coded level, its coefficients in [`PREDICTIVE_TERMS`] order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct PredictiveRow {
    pub actuation_nm: Option<f64>,
    pub fixed_factor: &'static str,
    pub fixed_coded: f64,
    pub fixed_value_um: Option<f64>,
    pub x1: &'static str,
    pub x2: &'static str,
    pub b0: Option<f64>,
    pub b1: Option<f64>,
    pub b2: Option<f64>,
    pub b11: Option<f64>,
    pub b22: Option<f64>,
    pub b12: Option<f64>,
    pub b112: Option<f64>,
    pub b122: Option<f64>,
    pub b1122: Option<f64>,
    pub residual_error: Option<f64>,
}

pub(crate) fn predictive_rows(p: &DoeParams, fits: &[LevelFit]) -> Result<Vec<PredictiveRow>> {
    let mut rows = Vec::new();
    for lf in fits {
        let poly: Polynomial = lf.quartic.polynomial();
        for level in [-1.0, 0.0, 1.0] {
            let reduced = poly
                .fix_factor(lf.fixed, level)
                .map_err(Error::PredictiveEquation)?;
            let free: Vec<&'static str> = (0..3)
                .filter(|f| *f != lf.fixed)
                .map(|f| FACTORS[f])
                .collect();
            let b = |name: &str| table_value(reduced.coefficient(name).unwrap_or(0.0));
            rows.push(PredictiveRow {
                actuation_nm: table_value(lf.actuation / NM),
                fixed_factor: FACTORS[lf.fixed],
                fixed_coded: level,
                fixed_value_um: table_value(
                    decoded(level, p.levels[lf.fixed][0], p.levels[lf.fixed][2]) / UM,
                ),
                x1: free[0],
                x2: free[1],
                b0: b("b0"),
                b1: b("b1"),
                b2: b("b2"),
                b11: b("b11"),
                b22: b("b22"),
                b12: b("b12"),
                b112: b("b112"),
                b122: b("b122"),
                b1122: b("b1122"),
                residual_error: table_value(lf.quartic.residual_ss_at(lf.fixed, level, 1e-9)),
            });
        }
    }
    Ok(rows)
}

/// One coefficient of a level's degree-4 or degree-5 surface.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct CoefficientRow {
    pub actuation_nm: Option<f64>,
    /// `degree 4` or `degree 5`.
    pub model: &'static str,
    pub term: String,
    pub coefficient: Option<f64>,
    pub std_error: Option<f64>,
    pub t: Option<f64>,
    pub p: Option<f64>,
}

pub(crate) fn coefficient_rows(fits: &[LevelFit]) -> Vec<CoefficientRow> {
    let mut rows = Vec::new();
    for lf in fits {
        for (model, s) in [
            ("degree 4", Some(&lf.quartic)),
            ("degree 5", lf.quintic.as_ref()),
        ] {
            let Some(s) = s else { continue };
            for (j, name) in s.basis.names().into_iter().enumerate() {
                rows.push(CoefficientRow {
                    actuation_nm: table_value(lf.actuation / NM),
                    model,
                    term: name,
                    coefficient: table_value(s.fit.coefficients[j]),
                    std_error: table_value(s.fit.standard_errors[j]),
                    t: table_value(s.fit.t_values[j]),
                    p: table_value(s.fit.p_values[j]),
                });
            }
        }
    }
    rows
}

/// One source of a level's degree-4 ANOVA.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct AnovaTableRow {
    pub actuation_nm: Option<f64>,
    pub source: String,
    pub df: usize,
    pub sum_sq: Option<f64>,
    pub mean_sq: Option<f64>,
    pub F: Option<f64>,
    pub p: Option<f64>,
}

pub(crate) fn anova_rows(fits: &[LevelFit]) -> Vec<AnovaTableRow> {
    let mut rows = Vec::new();
    for lf in fits {
        let t = lf.quartic.anova();
        let all = t.terms.iter().chain([&t.model, &t.residual, &t.total]);
        for r in all {
            rows.push(AnovaTableRow {
                actuation_nm: table_value(lf.actuation / NM),
                source: r.source.clone(),
                df: r.df,
                sum_sq: table_value(r.sum_sq),
                mean_sq: table_value(r.mean_sq),
                F: r.f.and_then(table_value),
                p: r.p.and_then(table_value),
            });
        }
    }
    rows
}

pub(crate) fn fit_summary(lf: &LevelFit) -> LevelFitSummary {
    let one = |s: &ResponseSurface| SurfaceFitSummary {
        terms: s.basis.len(),
        residual_df: s.fit.residual_df,
        rss: s.fit.rss,
        r_squared: s.fit.r_squared,
        adj_r_squared: s.fit.adj_r_squared,
        sigma: s.fit.sigma,
    };
    let (f, p, selected) = model_selection(lf);
    LevelFitSummary {
        actuation_m: lf.actuation,
        fixed_factor: FACTORS[lf.fixed].to_string(),
        degree_4: one(&lf.quartic),
        degree_5: lf.quintic.as_ref().map(one),
        degree_5_vs_4: DegreeTest { F: f, p },
        selected_degree: selected,
    }
}

/// One condition of Table 2.8 for a design; `touchdown_refined` (the convention's) goes into
/// the touchdown row beside the grid case it describes.
pub(crate) fn comparison_rows(
    label: &str,
    design: &[f64; 3],
    sp: &SimulateParams,
    cases: &[CaseOutcome],
    touchdown_refined: Option<f64>,
) -> Result<Vec<ComparisonRow>> {
    let sweep = sweep_analysis(sp, cases)?;
    let nearest = |h: f64| {
        cases
            .iter()
            .enumerate()
            .min_by(|a, b| {
                (a.1.actuation - h)
                    .abs()
                    .total_cmp(&(b.1.actuation - h).abs())
            })
            .map(|(i, _)| i)
    };
    let critical = sweep
        .slopes
        .critical_point
        .as_ref()
        .and_then(|c| nearest(c.actuation_m));
    let steady = sweep
        .touchdown_index
        .and_then(|td| (td..cases.len()).find(|&i| sweep.regimes[i] == Regime::SolidContact));
    let mut rows = Vec::new();
    for (condition, idx) in [
        ("critical actuation", critical),
        ("optimum actuation", sweep.optimum_index),
        ("touchdown", sweep.touchdown_index),
        ("steady contact", steady),
    ] {
        let m = idx.map(|i| (&cases[i].metrics, cases[i].actuation));
        // As the case's result.json has it: a non-finite value is null there.
        let get = |of: fn(&SweepCaseResult) -> f64, scale: f64| {
            m.and_then(|(m, _)| finite_value(of(m), scale))
        };
        rows.push(ComparisonRow {
            design: label.to_string(),
            a_um: table_value(design[0] / UM),
            w_um: table_value(design[1] / UM),
            x_um: table_value(design[2] / UM),
            condition: condition.to_string(),
            touchdown_refined_nm: match (condition, touchdown_refined) {
                ("touchdown", Some(t)) => table_value(t / NM),
                _ => None,
            },
            h_tfc_nm: m.and_then(|(_, h)| table_value(h / NM)),
            clearance_nm: get(|m| m.clearance_m.mean, NM),
            hms_nm: get(|m| m.hms_mean_m, NM),
            fhm_or_bv_percent: get(|m| m.vibration_percent, 1.0),
        });
    }
    Ok(rows)
}
