//! The DOE's tables (docs/doe.md): the design, the annealing, Table 2.7's predictive
//! equations, the surfaces' coefficients and ANOVA, and Table 2.8's comparison, as rows.

use super::cases::DesignCase;
use super::params::{DoeParams, FACTORS, NM, UM};
use super::surface::{model_selection, LevelFit};
use crate::dynamics::metrics::Regime;
use crate::error::{Error, Result};
use crate::numerics::annealing::AnnealingRecord;
use crate::numerics::regression::{decoded, Polynomial, ResponseSurface};
use crate::slider::case::SweepCaseResult;
use crate::slider::params::SimulateParams;
use crate::slider::sweep::{sweep_analysis, CaseOutcome};
use serde_json::{json, Map, Value};

/// A table value: seven significant digits, null when not finite.
pub(crate) fn table_value(v: f64) -> Value {
    if v.is_finite() {
        json!(crate::core::store::round_significant(v, 7))
    } else {
        Value::Null
    }
}

/// The design table: one row per case, level by level.
pub(crate) fn design_rows(
    coded_points: &[Vec<f64>],
    per_level: usize,
    cases: &[DesignCase],
) -> Vec<Map<String, Value>> {
    let mut rows = Vec::new();
    for (i, c) in cases.iter().enumerate() {
        let coded_point = &coded_points[i % per_level];
        let mut row = Map::new();
        row.insert("run".into(), json!(i + 1));
        for f in 0..3 {
            row.insert(format!("{}_coded", FACTORS[f]), json!(coded_point[f]));
        }
        row.insert("a_um".into(), table_value(c.design[0] / UM));
        row.insert("w_um".into(), table_value(c.design[1] / UM));
        row.insert("x_um".into(), table_value(c.design[2] / UM));
        row.insert("actuation_nm".into(), table_value(c.actuation / NM));
        let m = &c.result;
        // A non-finite value is null in the case's result.json: null here too.
        let finite = |v: f64| Some(v).filter(|v| v.is_finite());
        row.insert(
            "clearance_nm".into(),
            finite(m.clearance_m.mean).map_or(Value::Null, |v| table_value(v / NM)),
        );
        row.insert(
            "fhm_or_bv_percent".into(),
            finite(m.vibration_percent).map_or(Value::Null, table_value),
        );
        row.insert(
            "regime".into(),
            crate::slider::sweep::regime_label(&json!(m.regime)),
        );
        row.insert("xi".into(), table_value(c.xi));
        row.insert("case_key".into(), json!(c.entry.key));
        rows.push(row);
    }
    rows
}

/// The annealing table: one row per evaluation, with its ξ.
pub(crate) fn annealing_rows(
    p: &DoeParams,
    history: &[AnnealingRecord],
    xis: &[f64],
) -> Vec<Map<String, Value>> {
    let mut rows = Vec::new();
    for (r, xi) in history.iter().zip(xis) {
        let d = p.decode(&r.candidate);
        let mut m = Map::new();
        m.insert("iteration".into(), json!(r.iteration));
        m.insert("temperature".into(), table_value(r.temperature));
        m.insert("a_um".into(), table_value(d[0] / UM));
        m.insert("w_um".into(), table_value(d[1] / UM));
        m.insert("x_um".into(), table_value(d[2] / UM));
        m.insert("xi".into(), table_value(*xi));
        m.insert("candidate_j".into(), table_value(r.candidate_j));
        m.insert("accepted".into(), json!(r.accepted));
        m.insert("current_j".into(), table_value(r.current_j));
        m.insert("best_j".into(), table_value(r.best_j));
        rows.push(m);
    }
    rows
}

/// Table 2.7 coefficient names of a two-factor reduced polynomial, in output order.
const PREDICTIVE_TERMS: [&str; 9] = [
    "b0", "b1", "b2", "b11", "b22", "b12", "b112", "b122", "b1122",
];

pub(crate) fn predictive_rows(p: &DoeParams, fits: &[LevelFit]) -> Result<Vec<Map<String, Value>>> {
    let mut rows = Vec::new();
    for lf in fits {
        let poly: Polynomial = lf.quartic.polynomial();
        for level in [-1.0, 0.0, 1.0] {
            let reduced = poly
                .fix_factor(lf.fixed, level)
                .map_err(Error::PredictiveEquation)?;
            let free: Vec<&str> = (0..3)
                .filter(|f| *f != lf.fixed)
                .map(|f| FACTORS[f])
                .collect();
            let mut row = Map::new();
            row.insert("actuation_nm".into(), table_value(lf.actuation / NM));
            row.insert("fixed_factor".into(), json!(FACTORS[lf.fixed]));
            row.insert("fixed_coded".into(), json!(level));
            row.insert(
                "fixed_value_um".into(),
                table_value(decoded(level, p.levels[lf.fixed][0], p.levels[lf.fixed][2]) / UM),
            );
            row.insert("x1".into(), json!(free[0]));
            row.insert("x2".into(), json!(free[1]));
            for name in PREDICTIVE_TERMS {
                row.insert(
                    name.into(),
                    table_value(reduced.coefficient(name).unwrap_or(0.0)),
                );
            }
            row.insert(
                "residual_error".into(),
                table_value(lf.quartic.residual_ss_at(lf.fixed, level, 1e-9)),
            );
            rows.push(row);
        }
    }
    Ok(rows)
}

pub(crate) fn coefficient_rows(fits: &[LevelFit]) -> Vec<Map<String, Value>> {
    let mut rows = Vec::new();
    for lf in fits {
        for (model, s) in [
            ("degree 4", Some(&lf.quartic)),
            ("degree 5", lf.quintic.as_ref()),
        ] {
            let Some(s) = s else { continue };
            for (j, name) in s.basis.names().iter().enumerate() {
                let mut row = Map::new();
                row.insert("actuation_nm".into(), table_value(lf.actuation / NM));
                row.insert("model".into(), json!(model));
                row.insert("term".into(), json!(name));
                row.insert("coefficient".into(), table_value(s.fit.coefficients[j]));
                row.insert("std_error".into(), table_value(s.fit.standard_errors[j]));
                row.insert("t".into(), table_value(s.fit.t_values[j]));
                row.insert("p".into(), table_value(s.fit.p_values[j]));
                rows.push(row);
            }
        }
    }
    rows
}

pub(crate) fn anova_rows(fits: &[LevelFit]) -> Vec<Map<String, Value>> {
    let mut rows = Vec::new();
    for lf in fits {
        let t = lf.quartic.anova();
        let all = t.terms.iter().chain([&t.model, &t.residual, &t.total]);
        for r in all {
            let mut row = Map::new();
            row.insert("actuation_nm".into(), table_value(lf.actuation / NM));
            row.insert("source".into(), json!(r.source));
            row.insert("df".into(), json!(r.df));
            row.insert("sum_sq".into(), table_value(r.sum_sq));
            row.insert("mean_sq".into(), table_value(r.mean_sq));
            row.insert("F".into(), r.f.map_or(Value::Null, table_value));
            row.insert("p".into(), r.p.map_or(Value::Null, table_value));
            rows.push(row);
        }
    }
    rows
}

pub(crate) fn fit_summary(lf: &LevelFit) -> Value {
    let one = |s: &ResponseSurface| {
        json!({
            "terms": s.basis.len(),
            "residual_df": s.fit.residual_df,
            "rss": s.fit.rss,
            "r_squared": s.fit.r_squared,
            "adj_r_squared": s.fit.adj_r_squared,
            "sigma": s.fit.sigma,
        })
    };
    let (f, p, selected) = model_selection(lf);
    json!({
        "actuation_m": lf.actuation,
        "fixed_factor": FACTORS[lf.fixed],
        "degree_4": one(&lf.quartic),
        "degree_5": lf.quintic.as_ref().map(one),
        "degree_5_vs_4": {"F": f, "p": p},
        "selected_degree": selected,
    })
}

/// One condition of Table 2.8 for a design; `touchdown_refined` (the convention's) goes into
/// the touchdown row beside the grid case it describes.
pub(crate) fn comparison_rows(
    label: &str,
    design: &[f64; 3],
    sp: &SimulateParams,
    cases: &[CaseOutcome],
    touchdown_refined: Option<f64>,
) -> Result<Vec<Map<String, Value>>> {
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
        let mut row = Map::new();
        row.insert("design".into(), json!(label));
        row.insert("a_um".into(), table_value(design[0] / UM));
        row.insert("w_um".into(), table_value(design[1] / UM));
        row.insert("x_um".into(), table_value(design[2] / UM));
        row.insert("condition".into(), json!(condition));
        row.insert(
            "touchdown_refined_nm".into(),
            match (condition, touchdown_refined) {
                ("touchdown", Some(t)) => table_value(t / NM),
                _ => Value::Null,
            },
        );
        let m = idx.map(|i| (&cases[i].metrics, cases[i].actuation));
        // As the case's result.json has it: a non-finite value is null there.
        let get = |of: fn(&SweepCaseResult) -> f64| {
            m.and_then(|(m, _)| Some(of(m)).filter(|v| v.is_finite()))
        };
        row.insert(
            "h_tfc_nm".into(),
            m.map_or(Value::Null, |(_, h)| table_value(h / NM)),
        );
        row.insert(
            "clearance_nm".into(),
            get(|m| m.clearance_m.mean).map_or(Value::Null, |v| table_value(v / NM)),
        );
        row.insert(
            "hms_nm".into(),
            get(|m| m.hms_mean_m).map_or(Value::Null, |v| table_value(v / NM)),
        );
        row.insert(
            "fhm_or_bv_percent".into(),
            get(|m| m.vibration_percent).map_or(Value::Null, table_value),
        );
        rows.push(row);
    }
    Ok(rows)
}
