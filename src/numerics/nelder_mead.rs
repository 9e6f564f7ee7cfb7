//! Derivative-free minimisation in the unit box `[0, 1]^d` (Nelder–Mead with box projection).
//!
//! Used by the class-D calibration, whose objective is a handful of simulations per
//! evaluation: no gradients, mild noise from contact switching, a few dimensions. Standard
//! coefficients (reflection 1, expansion 2, contraction ½, shrink ½; Lagarias et al. 1998);
//! every trial point is projected onto the box, so physical bounds are never left. The start
//! simplex is the start point plus `initial_step` along each axis (minus where that would leave
//! the box), which makes the run deterministic for a given start.

/// Stopping rules and the start simplex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NelderMeadOptions {
    /// Edge of the start simplex in unit-box coordinates.
    pub initial_step: f64,
    /// Objective evaluations allowed (the start simplex counts).
    pub max_evaluations: usize,
    /// Stop when best and worst vertex values differ by less than this …
    pub f_tolerance: f64,
    /// … and the simplex fits in a cube of this edge.
    pub x_tolerance: f64,
}

impl Default for NelderMeadOptions {
    fn default() -> Self {
        NelderMeadOptions {
            initial_step: 0.15,
            max_evaluations: 200,
            f_tolerance: 1e-4,
            x_tolerance: 1e-3,
        }
    }
}

/// One objective evaluation, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    pub x: Vec<f64>,
    pub f: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct NelderMeadResult {
    pub x: Vec<f64>,
    pub f: f64,
    /// Every evaluation (the convergence history).
    pub evaluations: Vec<Evaluation>,
    /// Whether the tolerances stopped the run (otherwise the evaluation budget did).
    pub converged: bool,
    /// What ended the run.
    pub stop: StopReason,
    /// Objective spread (worst − best vertex) of the final simplex.
    pub f_spread: f64,
    /// Edge of the smallest axis-aligned cube holding the final simplex (unit-box units).
    pub x_spread: f64,
}

/// Why the search stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// Both tolerances met: `f_spread ≤ f_tolerance` and `x_spread ≤ x_tolerance`.
    Tolerance,
    /// The evaluation budget ran out first.
    Budget,
}

impl StopReason {
    pub fn name(self) -> &'static str {
        match self {
            StopReason::Tolerance => "tolerance",
            StopReason::Budget => "budget",
        }
    }
}

/// `(worst − best, largest coordinate range)` of a simplex.
fn spreads(simplex: &[(Vec<f64>, f64)]) -> (f64, f64) {
    let d = simplex.first().map_or(0, |v| v.0.len());
    let (best, worst) = simplex
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |a, v| {
            (a.0.min(v.1), a.1.max(v.1))
        });
    let x = (0..d)
        .map(|k| {
            let (lo, hi) = simplex
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |a, v| {
                    (a.0.min(v.0[k]), a.1.max(v.0[k]))
                });
            hi - lo
        })
        .fold(0.0, f64::max);
    let f = if worst == best { 0.0 } else { worst - best };
    (f, x)
}

fn project(x: &mut [f64]) {
    for v in x {
        *v = v.clamp(0.0, 1.0);
    }
}

/// Minimise `f` over `[0, 1]^d` from `x0`. A non-finite objective value counts as +∞ (the
/// point is rejected); an error from `f` aborts the run.
pub fn minimize_unit_box<E>(
    mut f: impl FnMut(&[f64]) -> Result<f64, E>,
    x0: &[f64],
    opts: &NelderMeadOptions,
) -> Result<NelderMeadResult, E> {
    let d = x0.len();
    let mut evaluations: Vec<Evaluation> = Vec::new();
    let mut eval = |x: &[f64], log: &mut Vec<Evaluation>| -> Result<f64, E> {
        let v = f(x)?;
        let v = if v.is_finite() { v } else { f64::INFINITY };
        log.push(Evaluation {
            x: x.to_vec(),
            f: v,
        });
        Ok(v)
    };
    let mut start = x0.to_vec();
    project(&mut start);
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(d + 1);
    let f0 = eval(&start, &mut evaluations)?;
    simplex.push((start.clone(), f0));
    for i in 0..d {
        let mut v = start.clone();
        v[i] = if v[i] + opts.initial_step <= 1.0 {
            v[i] + opts.initial_step
        } else {
            v[i] - opts.initial_step
        };
        project(&mut v);
        let fv = eval(&v, &mut evaluations)?;
        simplex.push((v, fv));
    }
    let mut converged = false;
    while evaluations.len() < opts.max_evaluations {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (f_spread, spread) = spreads(&simplex);
        if f_spread <= opts.f_tolerance && spread <= opts.x_tolerance {
            converged = true;
            break;
        }
        if d == 0 {
            converged = true;
            break;
        }
        let centroid: Vec<f64> = (0..d)
            .map(|k| simplex[..d].iter().map(|v| v.0[k]).sum::<f64>() / d as f64)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            let mut p: Vec<f64> = (0..d)
                .map(|k| centroid[k] + t * (simplex[d].0[k] - centroid[k]))
                .collect();
            project(&mut p);
            p
        };
        let xr = along(-1.0);
        let fr = eval(&xr, &mut evaluations)?;
        if fr < simplex[0].1 {
            let xe = along(-2.0);
            let fe = eval(&xe, &mut evaluations)?;
            simplex[d] = if fe < fr { (xe, fe) } else { (xr, fr) };
            continue;
        }
        if fr < simplex[d - 1].1 {
            simplex[d] = (xr, fr);
            continue;
        }
        // Contract outside (toward the reflected point) or inside (toward the worst).
        let (xc, fc, accept) = if fr < simplex[d].1 {
            let xc = along(-0.5);
            let fc = eval(&xc, &mut evaluations)?;
            (xc, fc, fc <= fr)
        } else {
            let xc = along(0.5);
            let fc = eval(&xc, &mut evaluations)?;
            (xc, fc, fc < simplex[d].1)
        };
        if accept {
            simplex[d] = (xc, fc);
            continue;
        }
        // Shrink toward the best vertex.
        let best_x = simplex[0].0.clone();
        for v in simplex.iter_mut().skip(1) {
            if evaluations.len() >= opts.max_evaluations {
                break;
            }
            let mut p: Vec<f64> = (0..d)
                .map(|k| best_x[k] + 0.5 * (v.0[k] - best_x[k]))
                .collect();
            project(&mut p);
            let fp = eval(&p, &mut evaluations)?;
            *v = (p, fp);
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (f_spread, x_spread) = spreads(&simplex);
    // The budget can run out exactly as the last step meets the tolerances.
    converged |= f_spread <= opts.f_tolerance && x_spread <= opts.x_tolerance;
    let (x, f) = simplex.swap_remove(0);
    Ok(NelderMeadResult {
        x,
        f,
        evaluations,
        converged,
        stop: if converged {
            StopReason::Tolerance
        } else {
            StopReason::Budget
        },
        f_spread,
        x_spread,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    #[test]
    fn finds_the_minimum_of_a_shifted_quadratic() {
        let target = [0.3, 0.7, 0.55];
        let r = minimize_unit_box(
            |x| -> Result<f64, Infallible> {
                Ok(x.iter()
                    .zip(target)
                    .enumerate()
                    .map(|(i, (a, b))| (i as f64 + 1.0) * (a - b).powi(2))
                    .sum())
            },
            &[0.5, 0.5, 0.5],
            &NelderMeadOptions {
                f_tolerance: 1e-12,
                x_tolerance: 1e-6,
                max_evaluations: 2000,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(r.converged);
        assert_eq!(r.stop, StopReason::Tolerance);
        assert!(
            r.f_spread <= 1e-12 && r.x_spread <= 1e-6,
            "{} {}",
            r.f_spread,
            r.x_spread
        );
        for (a, b) in r.x.iter().zip(target) {
            assert!((a - b).abs() < 1e-4, "{:?}", r.x);
        }
    }

    #[test]
    fn rosenbrock_in_the_box() {
        // Minimum at (1, 1) in physical coordinates [−2, 2]² → (0.75, 0.75) in the unit box.
        let r = minimize_unit_box(
            |u| -> Result<f64, Infallible> {
                let (x, y) = (4.0 * u[0] - 2.0, 4.0 * u[1] - 2.0);
                Ok((1.0 - x).powi(2) + 100.0 * (y - x * x).powi(2))
            },
            &[0.2, 0.6],
            &NelderMeadOptions {
                f_tolerance: 1e-14,
                x_tolerance: 1e-8,
                max_evaluations: 5000,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(
            (r.x[0] - 0.75).abs() < 1e-3 && (r.x[1] - 0.75).abs() < 1e-3,
            "{:?}",
            r.x
        );
    }

    #[test]
    fn respects_the_box_and_the_budget() {
        // The unconstrained minimum (x = 1.5) lies outside: the answer is the face x = 1.
        let r = minimize_unit_box(
            |x| -> Result<f64, Infallible> { Ok((x[0] - 1.5).powi(2) + (x[1] - 0.2).powi(2)) },
            &[0.1, 0.9],
            &NelderMeadOptions {
                max_evaluations: 300,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(r
            .evaluations
            .iter()
            .all(|e| e.x.iter().all(|v| (0.0..=1.0).contains(v))));
        assert!((r.x[0] - 1.0).abs() < 1e-3, "{:?}", r.x);
        let capped = minimize_unit_box(
            |x| -> Result<f64, Infallible> { Ok(x[0] * x[0]) },
            &[0.9],
            &NelderMeadOptions {
                max_evaluations: 5,
                f_tolerance: 0.0,
                x_tolerance: 0.0,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(!capped.converged);
        assert_eq!(capped.stop, StopReason::Budget);
        assert!(capped.evaluations.len() <= 6);
    }

    #[test]
    fn non_finite_values_are_rejected_and_errors_propagate() {
        let r = minimize_unit_box(
            |x| -> Result<f64, Infallible> {
                Ok(if x[0] > 0.8 {
                    f64::NAN
                } else {
                    (x[0] - 0.4).powi(2)
                })
            },
            &[0.7],
            &NelderMeadOptions::default(),
        )
        .unwrap();
        assert!((r.x[0] - 0.4).abs() < 1e-2);
        let e = minimize_unit_box(
            |_| -> Result<f64, &str> { Err("boom") },
            &[0.5],
            &Default::default(),
        );
        assert_eq!(e.unwrap_err(), "boom");
    }
}
