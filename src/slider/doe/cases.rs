//! One DOE case: a design `[a, w, x]` at one actuation, run through the 2-DOF case cache, its
//! flyability ξ, and the refined touchdown of a design's sweep (Table 2.8).

use crate::core::cache::Store;
use crate::core::cases::CaseEntry;
use crate::dynamics::metrics::flyability;
use crate::error::{Error, Result};
use crate::slider::case::SweepCaseResult;
use crate::slider::doe_design::design_params;
use crate::slider::params::SimulateParams;
use crate::slider::sweep::{CaseOutcome, PreparedSweep, SweepCase};
use rayon::prelude::*;

/// Runs one 2-DOF case of a given bulge through the 2-DOF case cache (`slider::case`).
pub(crate) struct CaseRunner<'a> {
    pub(crate) base: &'a SimulateParams,
    /// The base sweep prepared once (`DoeStage::prepare`): it computes every design case, as
    /// a Slurm worker's does.
    pub(crate) sweep: &'a PreparedSweep,
    pub(crate) store: &'a Store,
}

/// One finished case of a design: its metrics and ξ.
#[derive(Debug, Clone)]
pub(crate) struct DesignCase {
    pub(crate) design: [f64; 3],
    pub(crate) actuation: f64,
    pub(crate) entry: CaseEntry,
    pub(crate) result: SweepCaseResult,
    pub(crate) xi: f64,
}

impl CaseRunner<'_> {
    pub(crate) fn params_for(&self, design: &[f64; 3]) -> Result<SimulateParams> {
        design_params(self.base, design, 0.0)
    }

    pub(crate) fn run(&self, design: [f64; 3], actuation: f64) -> Result<DesignCase> {
        let p = design_params(self.base, &design, actuation)?;
        let case = SweepCase {
            actuation_m: actuation,
            design_m: Some(design),
            static_start: None,
        };
        let entry = self
            .sweep
            .cached(self.store, &case)
            .map_err(|e| Error::DoeCase {
                design,
                actuation,
                source: Box::new(e),
            })?;
        let result = SweepCaseResult::from_json(&entry.result)?;
        let xi = xi_of(&result, p.model.nominal_flying_height);
        Ok(DesignCase {
            design,
            actuation,
            entry,
            result,
            xi,
        })
    }
}

/// ξ of a case result (§9): steady mean clearance over FH_nom times FHM/BV in units of 100 %.
fn xi_of(result: &SweepCaseResult, fh_nom: f64) -> f64 {
    flyability(result.clearance_m.mean, fh_nom, result.vibration_percent)
}

/// Touchdown of a design's Table 2.8 sweep by the convention (docs/conventions.md,
/// `dynamics::touchdown`): the sweep's grid is the scan, the first crossing refined to 0.02 nm
/// with extra cached cases (not with `refine_touchdown = false` on the base sweep).
pub(crate) fn refined_touchdown(
    runner: &CaseRunner,
    design: [f64; 3],
    cases: &[CaseOutcome],
) -> Result<Option<f64>> {
    use crate::dynamics::touchdown::{find_touchdown, TouchdownSearch};
    let known: Vec<(f64, bool)> = cases
        .iter()
        .map(|c| (c.actuation, c.metrics.touches()))
        .collect();
    let (Some(first), Some(last)) = (cases.first(), cases.last()) else {
        return Ok(None);
    };
    let step = cases
        .windows(2)
        .map(|w| w[1].actuation - w[0].actuation)
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !step.is_finite() || !runner.base.refine_touchdown {
        // One case, or no refinement asked: the grid's first touching case.
        return Ok(known.iter().find(|k| k.1).map(|k| k.0));
    }
    let search = TouchdownSearch {
        start: first.actuation,
        ..TouchdownSearch::convention(last.actuation, step, 3)
    };
    let td = find_touchdown(&search, &known, |acts: &[f64]| -> Result<Vec<bool>> {
        let runs: Vec<Result<DesignCase>> =
            acts.par_iter().map(|&a| runner.run(design, a)).collect();
        runs.into_iter()
            .map(|r| r.map(|c| c.result.touches()))
            .collect()
    })?;
    Ok(td.actuation)
}
