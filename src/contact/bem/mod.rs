//! Deterministic elastic contact of a measured rough surface against a rigid flat: an FFT
//! boundary-element method (docs/contact.md, "Deterministic contact"). Pure: no I/O.
//!
//! The rough surface is the composite of the pair (the sum of the two maps, as the ISBL
//! interface is the sum of their statistics), pressed by a rigid flat; `E*` is the pair's
//! reduced modulus. The surface is discretised in uniformly loaded elements; the elastic
//! half-space turns pressure into displacement by an FFT convolution ([`kernel`]), periodic or
//! non-periodic. The frictionless, non-adhesive contact problem — pressure ≥ 0, gap ≥ 0, one
//! of the two zero at every element — is solved by the Polonsky–Keer (1999) constrained
//! conjugate gradient ([`solver`]) at a given mean pressure or at a given separation of the
//! flat from the mean plane of the heights (the mean gap, in a periodic domain).

pub mod kernel;
pub mod law;
pub mod reference;
pub mod solver;

pub use solver::{BemSolution, BemSolver, Boundary, SolverSettings, Target};

use super::ContactError;

/// One point of a force–separation curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// Separation of the flat from the mean plane of the undeformed heights [m] (periodic: the
    /// mean gap).
    pub separation: f64,
    /// Mean contact pressure over the nominal area [Pa].
    pub mean_pressure: f64,
    /// Fraction of elements in contact, `A_r/A_0`.
    pub contact_fraction: f64,
    /// Mean gap over the nominal area [m].
    pub mean_gap: f64,
    /// Iterations the solve took, and its final error (see [`SolverSettings::tolerance`]).
    pub iterations: usize,
    pub error: f64,
}

impl CurvePoint {
    fn of(s: &BemSolution) -> Self {
        CurvePoint {
            separation: s.separation,
            mean_pressure: s.mean_pressure,
            contact_fraction: s.contact_fraction,
            mean_gap: s.mean_gap,
            iterations: s.iterations,
            error: s.error,
        }
    }
}

/// The force–separation curve at `separations` (any order; solved from the largest down, each
/// step warm-started from the previous pressure field), returned in the order given.
pub fn force_separation(
    solver: &BemSolver,
    separations: &[f64],
    settings: &SolverSettings,
) -> Result<Vec<CurvePoint>, ContactError> {
    let targets: Vec<Target> = separations.iter().map(|&d| Target::Separation(d)).collect();
    let solutions = solve_warm(
        solver,
        &targets,
        |a, b| separations[b].total_cmp(&separations[a]),
        settings,
    )?;
    Ok(solutions.iter().map(CurvePoint::of).collect())
}

/// The pressure-controlled solutions at `pressures` (solved from the lightest up, each
/// warm-started from the previous), in the order given.
pub fn at_pressures(
    solver: &BemSolver,
    pressures: &[f64],
    settings: &SolverSettings,
) -> Result<Vec<BemSolution>, ContactError> {
    let targets: Vec<Target> = pressures.iter().map(|&p| Target::MeanPressure(p)).collect();
    solve_warm(
        solver,
        &targets,
        |a, b| pressures[a].total_cmp(&pressures[b]),
        settings,
    )
}

/// Each target, solved in the order `solve_first` sorts their indices, warm-started from the
/// previous solution; returned in the order given.
fn solve_warm(
    solver: &BemSolver,
    targets: &[Target],
    solve_first: impl Fn(usize, usize) -> std::cmp::Ordering,
    settings: &SolverSettings,
) -> Result<Vec<BemSolution>, ContactError> {
    let mut order: Vec<usize> = (0..targets.len()).collect();
    order.sort_by(|&a, &b| solve_first(a, b));
    let mut out: Vec<Option<BemSolution>> = vec![None; targets.len()];
    let mut warm: Option<Vec<f64>> = None;
    for i in order {
        let s = solver.solve(targets[i], settings, warm.as_deref())?;
        warm = Some(s.pressure.clone());
        out[i] = Some(s);
    }
    Ok(out.into_iter().flatten().collect())
}

/// The gap distribution at one separation: counts of the elements out of contact in bins of
/// h/σ, and how many are in contact.
pub struct GapHistogram {
    /// Bin edges in units of σ.
    pub edges: Vec<f64>,
    pub counts: Vec<u64>,
    pub in_contact: u64,
}

impl GapHistogram {
    const BINS: usize = 60;

    /// The histogram of solution `s`, gaps in units of `sigma`.
    pub fn of(s: &BemSolution, sigma: f64) -> Self {
        let free: Vec<f64> = s
            .pressure
            .iter()
            .zip(&s.gap)
            .filter(|(p, _)| **p == 0.0)
            .map(|(_, g)| g.max(0.0) / sigma)
            .collect();
        let top = free.iter().cloned().fold(0.0, f64::max).max(1e-12);
        let width = top / Self::BINS as f64;
        let mut counts = vec![0u64; Self::BINS];
        for g in &free {
            counts[((g / width) as usize).min(Self::BINS - 1)] += 1;
        }
        GapHistogram {
            edges: (0..=Self::BINS).map(|k| k as f64 * width).collect(),
            counts,
            in_contact: (s.pressure.len() - free.len()) as u64,
        }
    }
}

#[cfg(test)]
mod tests;
