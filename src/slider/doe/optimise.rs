//! The DOE's optimisation (dissertation §2.3.3): simulated annealing of ξ in coded units,
//! the sensitivity check around the optimum, and Table 2.8's sweeps of the initial and the
//! optimised design. The stage writes what they return.

use super::cases::{refined_touchdown, CaseRunner, DesignCase};
use super::params::{DoeParams, SaObjective, FACTORS, NM, UM};
use super::surface::{surrogate_xi, LevelFit};
use super::tables::{comparison_rows, table_value};
use crate::artefacts::doe::ComparisonRow;
use crate::core::progress::Progress;
use crate::error::{Error, Result};
use crate::numerics::annealing::{sensitivity_points, Annealer, AnnealingRecord, StopReason};
use crate::slider::sweep::CaseOutcome;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The annealing's box, in coded units.
const CODED_LOWER: [f64; 3] = [-1.0; 3];
const CODED_UPPER: [f64; 3] = [1.0; 3];

/// The annealing objective of §9: ξ when positive, else `1 + |ξ|` (never preferred).
fn annealing_objective(xi: f64) -> f64 {
    if xi > 0.0 {
        xi
    } else {
        1.0 + xi.abs()
    }
}

/// ξ at a coded point for the annealing and the sensitivity check (dissertation §2.3): a cached
/// simulation case at `sa_actuation`, or the level surfaces interpolated to it.
pub(crate) struct Objective<'a> {
    pub(crate) p: &'a DoeParams,
    pub(crate) runner: &'a CaseRunner<'a>,
    pub(crate) fits: &'a [LevelFit],
}

/// One objective evaluation: ξ and, for a simulation, the case it used.
struct Evaluation {
    xi: f64,
    case_key: Option<String>,
}

impl Objective<'_> {
    fn evaluate(&self, c: &[f64]) -> Result<Evaluation> {
        let p = self.p;
        match p.sa_objective {
            SaObjective::Simulation => {
                let r = self.runner.run(p.decode(c), p.sa_actuation)?;
                Ok(Evaluation {
                    xi: r.xi,
                    case_key: Some(r.entry.key),
                })
            }
            SaObjective::Surrogate => Ok(Evaluation {
                xi: surrogate_xi(self.fits, p.sa_actuation, c),
                case_key: None,
            }),
        }
    }
}

/// The annealing's optimum and what it cost.
pub(crate) struct Annealing {
    /// The optimum in coded units, and decoded [m].
    pub(crate) coded: Vec<f64>,
    pub(crate) best: [f64; 3],
    pub(crate) best_xi: f64,
    pub(crate) evaluations: usize,
    pub(crate) reanneals: usize,
    pub(crate) stop: StopReason,
    pub(crate) case_keys: Vec<String>,
    /// Every evaluation (for the annealing table and Fig. 2.30), with its ξ.
    pub(crate) history: Vec<AnnealingRecord>,
    pub(crate) xis: Vec<f64>,
}

/// Simulated annealing on ξ at `sa_actuation`, in coded units.
pub(crate) fn anneal(
    p: &DoeParams,
    progress: &dyn Progress,
    objective: &Objective,
) -> Result<Annealing> {
    progress.set_message("simulated annealing");
    let start = p.encode(&p.sa_start);
    let mut annealer =
        Annealer::new(&CODED_LOWER, &CODED_UPPER, &start, &p.sa).map_err(Error::Annealing)?;
    let mut case_keys = Vec::new();
    let mut xis = Vec::new();
    while let Some(c) = annealer.ask() {
        let e = objective.evaluate(&c)?;
        case_keys.extend(e.case_key);
        xis.push(e.xi);
        annealer.tell(annealing_objective(e.xi));
        progress.set_message(format!(
            "simulated annealing: {} evaluations, best J {:.4e}",
            annealer.evaluations(),
            annealer.best().1
        ));
    }
    let stop = annealer.stop_reason();
    let res = annealer.into_result();
    let best = p.decode(&res.x);
    // The optimum is an evaluated point: a simulation finds its case cached, already listed.
    let best_xi = objective.evaluate(&res.x)?.xi;
    Ok(Annealing {
        best,
        best_xi,
        evaluations: res.evaluations,
        reanneals: res.reanneals,
        stop: stop.unwrap_or(res.stop),
        case_keys,
        history: res.history,
        xis,
        coded: res.x,
    })
}

/// The one-step ξ spread per factor around the optimum.
pub(crate) struct Sensitivity {
    pub(crate) spread: [f64; 3],
    pub(crate) most_sensitive: Option<&'static str>,
    pub(crate) case_keys: Vec<String>,
    /// The sensitivity table.
    pub(crate) rows: Vec<SensitivityRow>,
}

/// One point of the sensitivity check: the factor moved, by how many steps, the design and
/// its ξ.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub(crate) struct SensitivityRow {
    pub factor: &'static str,
    pub offset_steps: i32,
    pub offset_nm: Option<f64>,
    pub a_um: Option<f64>,
    pub w_um: Option<f64>,
    pub x_um: Option<f64>,
    pub xi: Option<f64>,
}

/// ± steps of `sensitivity_step` per factor around the optimum.
pub(crate) fn check_sensitivity(
    p: &DoeParams,
    progress: &dyn Progress,
    objective: &Objective,
    annealing: &Annealing,
) -> Result<Sensitivity> {
    progress.set_message("sensitivity check");
    let step: Vec<f64> = (0..3)
        .map(|f| p.sensitivity_step / (0.5 * (p.levels[f][2] - p.levels[f][0])))
        .collect();
    let pts = sensitivity_points(
        &annealing.coded,
        &step,
        p.sensitivity_steps,
        &CODED_LOWER,
        &CODED_UPPER,
    )
    .map_err(Error::Sensitivity)?;
    let values: Vec<Result<Evaluation>> =
        pts.par_iter().map(|s| objective.evaluate(&s.x)).collect();
    let mut case_keys = Vec::new();
    let mut sens_rows = Vec::new();
    let mut spread = [0.0f64; 3];
    for (s, v) in pts.iter().zip(values) {
        let e = v?;
        let xi = e.xi;
        case_keys.extend(e.case_key);
        let d = p.decode(&s.x);
        if s.offset.abs() == 1 {
            spread[s.coordinate] = spread[s.coordinate].max((xi - annealing.best_xi).abs());
        }
        sens_rows.push(SensitivityRow {
            factor: FACTORS[s.coordinate],
            offset_steps: s.offset,
            offset_nm: table_value(f64::from(s.offset) * p.sensitivity_step / NM),
            a_um: table_value(d[0] / UM),
            w_um: table_value(d[1] / UM),
            x_um: table_value(d[2] / UM),
            xi: table_value(xi),
        });
    }
    let most_sensitive = (0..3)
        .max_by(|a, b| spread[*a].total_cmp(&spread[*b]))
        .map(|f| FACTORS[f]);
    Ok(Sensitivity {
        spread,
        most_sensitive,
        case_keys,
        rows: sens_rows,
    })
}

/// One design's 2-DOF sweep of Table 2.8.
pub(crate) struct DesignSweep {
    pub(crate) label: &'static str,
    pub(crate) outcomes: Vec<CaseOutcome>,
}

/// Table 2.8's rows and the cases they used.
pub(crate) struct Comparison {
    pub(crate) rows: Vec<ComparisonRow>,
    pub(crate) case_keys: Vec<String>,
    /// Both designs' sweeps, for the comparison plot.
    pub(crate) sweeps: Vec<DesignSweep>,
}

/// Table 2.8: the 2-DOF sweep on the initial and the optimised design.
pub(crate) fn compare_designs(
    p: &DoeParams,
    progress: &dyn Progress,
    runner: &CaseRunner,
    best: [f64; 3],
) -> Result<Comparison> {
    let initial = {
        let b = p.base.model.bulge;
        [b.semi_width_x, b.full_width_y, b.offset_from_te]
    };
    let n = p.compare_actuations.len();
    let total = 2 * n;
    let done = AtomicUsize::new(0);
    let runs: Vec<Result<DesignCase>> = (0..total)
        .into_par_iter()
        .map(|i| {
            let design = if i < n { initial } else { best };
            let r = runner.run(design, p.compare_actuations[i % n]);
            let k = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress.set_message(format!("Table 2.8 sweeps: {k}/{total} cases"));
            r
        })
        .collect();
    let mut all = Vec::with_capacity(total);
    for r in runs {
        all.push(r?);
    }
    let case_keys = all.iter().map(|c| c.entry.key.clone()).collect();
    let mut rows = Vec::new();
    let mut sweeps = Vec::new();
    for (label, chunk) in [("initial", &all[..n]), ("optimised", &all[n..])] {
        let design = chunk[0].design;
        let sp = runner.params_for(&design)?;
        let outcomes: Vec<CaseOutcome> = chunk
            .iter()
            .map(|c| CaseOutcome {
                actuation: c.actuation,
                metrics: c.result.clone(),
                entry: c.entry.clone(),
            })
            .collect();
        let td = refined_touchdown(runner, design, &outcomes)?;
        rows.extend(comparison_rows(label, &design, &sp, &outcomes, td)?);
        sweeps.push(DesignSweep { label, outcomes });
    }
    Ok(Comparison {
        rows,
        case_keys,
        sweeps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objective_never_prefers_contact() {
        assert_eq!(annealing_objective(0.02), 0.02);
        // Negative ξ (solid contact) is worse than any positive ξ below 1.
        assert_eq!(annealing_objective(-0.3), 1.3);
        assert!(annealing_objective(-1e-9) > annealing_objective(0.9));
    }
}
