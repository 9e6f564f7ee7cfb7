//! `hdi simulate --json`: the printed document as types (docs/schemas/simulate.json is
//! generated from them).

use anyhow::Result;
use hdi::artefacts::finite;
use hdi::slider::sweep::SweepRow;
use schemars::JsonSchema;
use serde::Serialize;

/// 2-DOF slider cases (docs/simulation.md): one case, or a sweep (two or more actuations)
/// with its touchdown, critical point and slopes. Schema version 1 (docs/json.md): existing
/// keys keep their name, unit and type; renaming or removing one makes version 2.
#[derive(Debug, Serialize, JsonSchema)]
pub(crate) struct SimulateOutput {
    /// One row per actuation, in increasing actuation (the one case of a single actuation).
    #[schemars(length(min = 1))]
    cases: Vec<SweepRow>,
    /// Wall time of the cases, s (the only timing; it is printed, never written to a result
    /// file).
    wall_time_s: f64,
    /// Sweep analysis of c̄(h_TFC); only for a sweep (two or more actuations).
    #[serde(skip_serializing_if = "Option::is_none")]
    sweep: Option<SweepAnalysis>,
}

/// Sweep analysis of c̄(h_TFC).
#[derive(Debug, Serialize, JsonSchema)]
struct SweepAnalysis {
    /// Touchdown actuation (first case in solid contact), m; null: none reached. `null` when
    /// not defined for this input (docs/json.md).
    touchdown_actuation_m: Option<f64>,
    /// Intersection of slopes A and B (§8); null when either is missing.
    critical_point: Option<CriticalPoint>,
    /// Slopes A (approach), B (jump to contact), C (lubricant contact), D (solid contact) of
    /// §8.
    slopes: Slopes,
}

/// Intersection of slopes A and B (§8).
#[derive(Debug, Serialize, JsonSchema)]
struct CriticalPoint {
    /// h_TFC,cr, m. `null` when not defined for this input (docs/json.md).
    actuation_m: Option<f64>,
    /// c_cr, m. `null` when not defined for this input (docs/json.md).
    clearance_m: Option<f64>,
}

/// Slopes A (approach), B (jump to contact), C (lubricant contact), D (solid contact) of §8.
#[allow(non_snake_case)]
#[derive(Debug, Serialize, JsonSchema)]
struct Slopes {
    /// Least-squares line of the approach; null when the sweep does not reach it.
    A: Option<Slope>,
    /// Least-squares line of the jump to contact; null when the sweep does not reach it.
    B: Option<Slope>,
    /// Least-squares line of the lubricant contact; null when the sweep does not reach it.
    C: Option<Slope>,
    /// Least-squares line of the solid contact; null when the sweep does not reach it.
    D: Option<Slope>,
}

/// Least-squares line of one segment.
#[derive(Debug, Serialize, JsonSchema)]
struct Slope {
    /// dc̄/dh_TFC, m/m (= nm/nm). `null` when not defined for this input (docs/json.md).
    slope: Option<f64>,
    /// Intercept of the line c̄ = slope·h_TFC + intercept, m. `null` when not defined for this
    /// input (docs/json.md).
    intercept_m: Option<f64>,
    /// RMS residual of the fit, m. `null` when not defined for this input (docs/json.md).
    rms_residual_m: Option<f64>,
    /// Sweep points fitted.
    n_points: usize,
}

/// `--json` (docs/schemas/simulate.json): one case, or a sweep with its touchdown, critical
/// point and slopes A–D (dc̄/dh_TFC, m/m) beside the cases.
pub(super) fn print_json(
    cases: &[hdi::slider::sweep::CaseOutcome],
    sweep: &hdi::dynamics::metrics::SweepMetrics,
    rows: Vec<SweepRow>,
    wall: f64,
) -> Result<()> {
    let fit = |l: &Option<hdi::dynamics::metrics::LineFit>| {
        l.as_ref().map(|l| Slope {
            slope: finite(l.slope),
            intercept_m: finite(l.intercept_m),
            rms_residual_m: finite(l.rms_residual_m),
            n_points: l.indices.len(),
        })
    };
    let s = &sweep.slopes;
    let out = SimulateOutput {
        cases: rows,
        wall_time_s: wall,
        sweep: (cases.len() > 1).then(|| SweepAnalysis {
            touchdown_actuation_m: sweep.touchdown_actuation_m.and_then(finite),
            critical_point: s.critical_point.as_ref().map(|c| CriticalPoint {
                actuation_m: finite(c.actuation_m),
                clearance_m: finite(c.clearance_m),
            }),
            slopes: Slopes {
                A: fit(&s.a),
                B: fit(&s.b),
                C: fit(&s.c),
                D: fit(&s.d),
            },
        }),
    };
    println!("{}", serde_json::to_string(&out)?);
    Ok(())
}
