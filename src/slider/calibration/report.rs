//! What a calibration reports (docs/calibration.md): every target before and after the fit as
//! rows, the knobs with their bounds, the log, the residual plot, and the evaluations as
//! `result.json` values. The `[calibrate]` stage writes them.

use super::WarmStart;
use crate::artefacts::calibration::{EvaluationRecord, KnobValue, TargetRecord};
use crate::artefacts::finite;
use crate::dynamics::calibration::{
    in_band, CalibrationResult, CalibrationSettings, Evaluation, Knob, KnobRange, TargetOutcome,
    TargetSet,
};
use crate::error::Result;
use serde::Serialize;

/// One evaluation (knobs, objective, every target) for `result.json`.
pub(crate) fn evaluation_record(e: &Evaluation) -> EvaluationRecord {
    let (inside, total) = in_band(e);
    EvaluationRecord {
        objective: finite(e.objective),
        cases: e.cases,
        in_band: inside,
        targets_total: total,
        knobs: e
            .knobs
            .iter()
            .map(|(k, v)| KnobValue {
                knob: k.name().to_string(),
                value: *v,
            })
            .collect(),
        targets: e
            .outcomes
            .iter()
            .map(|o| TargetRecord {
                id: o.target.id.to_string(),
                set: o.target.set.name().to_string(),
                class: o.target.class.to_string(),
                value: o.value.and_then(finite),
                published: o.target.published,
                tolerance: o.target.tolerance,
                weight: o.target.weight,
                normalised_residual: finite(o.normalised_residual),
                within_tolerance: o.within_tolerance(),
            })
            .collect(),
    }
}

/// Describe the knob values compactly in display units (`dmw_scale 2.1, Δγ 52 mN/m, …`).
pub fn describe_knobs(values: &[(Knob, f64)]) -> String {
    values
        .iter()
        .map(|(k, v)| match k {
            Knob::SurfaceEnergy => format!("Δγ {:.3} mN/m", v * 1e3),
            Knob::LjSpacing => format!("ε {:.3} nm", v * 1e9),
            Knob::AsperityDensity => format!("η {:.1} µm⁻²", v * 1e-12),
            Knob::KrStiffeningBeta => format!("β {v:.3}"),
            Knob::ContactDamping => format!("ζ_c {v:.4}"),
            Knob::DmwScale => format!("dmw_scale {v:.3}"),
            Knob::TruncationN => format!("n {v:.3}"),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// One row of the calibration table (`calibration.parquet`): a target of either set in
/// display units, before (spec defaults) and after (fitted knobs) the fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct TargetRow {
    pub(crate) target: &'static str,
    pub(crate) set: &'static str,
    pub(crate) class: &'static str,
    /// `dissertation` / `optimised`.
    pub(crate) geometry: &'static str,
    /// The id of `hdi validate` (docs/validation.md), e.g. dyn-16.
    pub(crate) spec_row: String,
    pub(crate) unit: &'static str,
    pub(crate) published: f64,
    pub(crate) tolerance: f64,
    pub(crate) weight: f64,
    pub(crate) spec_defaults: Option<f64>,
    pub(crate) calibrated: Option<f64>,
    pub(crate) residual_defaults: Option<f64>,
    pub(crate) residual_calibrated: Option<f64>,
    pub(crate) in_band_defaults: bool,
    pub(crate) in_band_calibrated: bool,
    pub(crate) within_tolerance: bool,
}

/// One row per target of both sets: published, tolerance, value before (spec defaults) and
/// after (fitted knobs), in band before and after.
pub(crate) fn table_rows(r: &CalibrationResult) -> Vec<TargetRow> {
    let pairs = |before: &Evaluation, after: &Evaluation| -> Vec<(TargetOutcome, TargetOutcome)> {
        before
            .outcomes
            .iter()
            .cloned()
            .zip(after.outcomes.iter().cloned())
            .collect()
    };
    let mut all = pairs(&r.initial, &r.best);
    if let (Some(b), Some(a)) = (&r.held_out_initial, &r.held_out_best) {
        all.extend(pairs(b, a));
    }
    all.iter()
        .map(|(i, b)| {
            let t = &b.target;
            let s = |v: Option<f64>| v.map(|v| v * t.display_scale).and_then(finite);
            TargetRow {
                target: t.id,
                set: t.set.name(),
                class: t.class,
                geometry: match t.geometry {
                    crate::dynamics::calibration::TargetGeometry::Base => "dissertation",
                    crate::dynamics::calibration::TargetGeometry::Optimised => "optimised",
                },
                spec_row: format!("dyn-{}", t.source.trim_start_matches('#')),
                unit: t.unit,
                published: t.published * t.display_scale,
                tolerance: t.tolerance * t.display_scale,
                weight: t.weight,
                spec_defaults: s(i.value),
                calibrated: s(b.value),
                residual_defaults: finite(i.normalised_residual),
                residual_calibrated: finite(b.normalised_residual),
                in_band_defaults: i.within_tolerance(),
                in_band_calibrated: b.within_tolerance(),
                within_tolerance: b.within_tolerance(),
            }
        })
        .collect()
}

/// One row of the knob table (`knobs.parquet`): its bounds, the fitted value and the bound it
/// ended on (`null` for none).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct KnobRow {
    pub(crate) knob: &'static str,
    pub(crate) unit: &'static str,
    pub(crate) lower_bound: f64,
    pub(crate) upper_bound: f64,
    pub(crate) fitted: f64,
    pub(crate) at_bound: Option<&'static str>,
}

/// One row per knob: its bounds, the fitted value and the bound it ended on.
pub(crate) fn knob_rows(knobs: &[KnobRange], r: &CalibrationResult) -> Vec<KnobRow> {
    knobs
        .iter()
        .zip(&r.best.knobs)
        .map(|(range, (k, v))| KnobRow {
            knob: k.name(),
            unit: k.unit(),
            lower_bound: range.lo,
            upper_bound: range.hi,
            fitted: *v,
            at_bound: r
                .at_bound
                .iter()
                .find(|(kb, _)| kb == k)
                .map(|(_, b)| b.name()),
        })
        .collect()
}

/// In-band counts `(spec defaults, calibrated)` of the fitted and the held-out sets, and of the
/// held-out set's selection and final parts.
pub(crate) struct InBandCounts {
    pub(crate) fitted: (usize, usize),
    pub(crate) fitted_total: usize,
    pub(crate) held_out: (usize, usize),
    pub(crate) held_out_total: usize,
    pub(crate) selection: (usize, usize),
    pub(crate) selection_total: usize,
    pub(crate) final_set: (usize, usize),
    pub(crate) final_total: usize,
}

impl InBandCounts {
    pub(crate) fn of(r: &CalibrationResult) -> Self {
        let (f0, ft) = in_band(&r.initial);
        let (f1, _) = in_band(&r.best);
        let (h0, ht) = r.held_out_initial.as_ref().map_or((0, 0), in_band);
        let (h1, _) = r.held_out_best.as_ref().map_or((0, 0), in_band);
        // In band / total of the held-out targets of one set.
        let part = |e: &Option<Evaluation>, set: TargetSet| {
            e.as_ref().map_or((0, 0), |e| {
                let of: Vec<_> = e.outcomes.iter().filter(|o| o.target.set == set).collect();
                (of.iter().filter(|o| o.within_tolerance()).count(), of.len())
            })
        };
        let (s0, st) = part(&r.held_out_initial, TargetSet::Selection);
        let (s1, _) = part(&r.held_out_best, TargetSet::Selection);
        let (x0, xt) = part(&r.held_out_initial, TargetSet::Final);
        let (x1, _) = part(&r.held_out_best, TargetSet::Final);
        InBandCounts {
            fitted: (f0, f1),
            fitted_total: ft,
            held_out: (h0, h1),
            held_out_total: ht,
            selection: (s0, s1),
            selection_total: st,
            final_set: (x0, x1),
            final_total: xt,
        }
    }
}

/// The stage's log: counts, convergence, knobs (with bounds reached), every target.
pub(crate) fn summary_text(
    name: &str,
    settings: &CalibrationSettings,
    fit_inputs: &str,
    warm: &WarmStart,
    r: &CalibrationResult,
    c: &InBandCounts,
) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    if let WarmStart::Ignored(reason) = warm {
        let _ = writeln!(s, "WARNING: {reason}");
    }
    let _ = writeln!(
        s,
        "{}: fitted set {}/{} → {}/{} in band, held-out set {}/{} → {}/{} (selection {}/{} → {}/{}, final {}/{} → {}/{}); objective {:.3} → {:.3}; {} after {} evaluations ({} cases)",
        name,
        c.fitted.0,
        c.fitted_total,
        c.fitted.1,
        c.fitted_total,
        c.held_out.0,
        c.held_out_total,
        c.held_out.1,
        c.held_out_total,
        c.selection.0,
        c.selection_total,
        c.selection.1,
        c.selection_total,
        c.final_set.0,
        c.final_total,
        c.final_set.1,
        c.final_total,
        r.initial.objective,
        r.best.objective,
        if r.converged {
            "converged (simplex tolerance)"
        } else {
            "NOT converged (evaluation budget)"
        },
        r.evaluations,
        r.cases
    );
    let _ = writeln!(
        s,
        "simplex: f spread {:.3e} (tolerance {:.1e}), unit-box edge {:.3e} (tolerance {:.1e})",
        r.final_f_spread,
        settings.search.f_tolerance,
        r.final_x_spread,
        settings.search.x_tolerance
    );
    let _ = writeln!(
        s,
        "fit inputs: {fit_inputs}; warm start: {}",
        match warm {
            WarmStart::None => "none".to_string(),
            WarmStart::Unguarded => "used as written, unguarded (no start_fitted_for: \
                 it is not checked against the fit's inputs)"
                .to_string(),
            WarmStart::Matched => "used (start_fitted_for matches)".to_string(),
            WarmStart::Ignored(_) => "ignored (see the warning above)".to_string(),
        }
    );
    let _ = writeln!(
        s,
        "search: start simplex edge {} (unit box) at {}; {} trial points rejected early (touchdown search skipped)",
        settings.search.initial_step,
        if settings.start.is_empty() {
            "the spec defaults".to_string()
        } else {
            describe_knobs(&settings.start)
        },
        r.rejected
    );
    let _ = writeln!(s, "knobs: {}", describe_knobs(&r.best.knobs));
    for (k, b) in &r.at_bound {
        let _ = writeln!(s, "knob {} ended on its {} bound", k.name(), b.name());
    }
    let _ = writeln!(
        s,
        "set\ttarget\tpublished\ttolerance\tdefaults\tcalibrated\tin band before/after"
    );
    for row in table_rows(r) {
        let f = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.4}"));
        let _ = writeln!(
            s,
            "{}\t{}\t{} {}\t±{}\t{}\t{}\t{}/{}",
            row.set,
            row.target,
            f(finite(row.published)),
            row.unit,
            f(finite(row.tolerance)),
            f(row.spec_defaults),
            f(row.calibrated),
            row.in_band_defaults,
            row.in_band_calibrated,
        );
    }
    s
}

/// Normalised residual per target, spec defaults against calibrated, with the ±1 band.
pub(crate) fn residuals_png(
    path: &std::path::Path,
    base: &str,
    r: &CalibrationResult,
) -> Result<()> {
    let values = |e: &Evaluation| -> Vec<f64> {
        e.outcomes
            .iter()
            .map(|o| o.normalised_residual.clamp(-10.0, 10.0))
            .collect()
    };
    let categories: Vec<String> = r
        .best
        .outcomes
        .iter()
        .map(|o| {
            if o.target.weight == 0.0 {
                format!("{} (reported)", o.target.id)
            } else {
                o.target.id.to_string()
            }
        })
        .collect();
    crate::figures::category_dots_png(
        path,
        &format!("Calibration of {base}: residual / tolerance (band ±1)"),
        "(value − published) / tolerance (clamped to ±10)",
        &categories,
        &[
            ("spec defaults", values(&r.initial)),
            ("calibrated", values(&r.best)),
        ],
        1.0,
    )?;
    Ok(())
}
