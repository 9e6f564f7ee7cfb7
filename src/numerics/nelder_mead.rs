//! Derivative-free minimisation in the unit box `[0, 1]^d` (Nelder–Mead with box projection).
//!
//! Used by the class-D calibration, whose objective is a handful of simulations per
//! evaluation: no gradients, mild noise from contact switching, a few dimensions. Standard
//! coefficients (reflection 1, expansion 2, contraction ½, shrink ½; Lagarias et al. 1998);
//! every trial point is projected onto the box, so physical bounds are never left. The start
//! simplex is the start point plus `initial_step` along each axis (minus where that would leave
//! the box), which makes the run deterministic for a given start.

/// Stopping rules and the start simplex.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
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
    /// The objective value, or a lower bound of it when `exact` is false (an early-rejected
    /// trial point, see [`minimize_unit_box_with_cutoff`]).
    pub f: f64,
    pub exact: bool,
}

/// What the search needs to know of a trial point's value: only whether it reaches `value`
/// (`inclusive`: `f ≥ value`; otherwise `f > value`). Once a lower bound of the objective
/// reaches it, the objective may stop and answer [`Trial::AtLeast`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cutoff {
    pub value: f64,
    pub inclusive: bool,
}

impl Cutoff {
    /// Whether a lower bound `lb` of the objective already decides the comparison.
    pub fn rejects(&self, lb: f64) -> bool {
        if self.inclusive {
            lb >= self.value
        } else {
            lb > self.value
        }
    }
}

/// An objective value: exact, or (only when a [`Cutoff`] was offered and rejects it) a lower
/// bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Trial {
    Exact(f64),
    AtLeast(f64),
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
    minimize_unit_box_with_cutoff(|x, _| f(x).map(Trial::Exact), x0, opts)
}

/// [`minimize_unit_box`] with early rejection: each trial point whose value only matters
/// through one comparison is offered that comparison as a [`Cutoff`], and `f` may answer a
/// lower bound ([`Trial::AtLeast`]) as soon as the bound decides it (e.g. a sum of
/// non-negative terms whose first terms already exceed the cutoff). The decisions, and so the
/// simplex trajectory and the result, are those of the exact search:
///
/// * reflection `x_r`: cutoff `f_worst` (inclusive). `f_r ≥ f_worst` means an inside
///   contraction whatever `f_r` is, and `f_r` is not used again;
/// * expansion `x_e`: cutoff `f_r` (inclusive): `f_e ≥ f_r` keeps `x_r`;
/// * outside contraction: cutoff `f_r` (exclusive): `f_c > f_r` means shrink;
/// * inside contraction: cutoff `f_worst` (inclusive): `f_c ≥ f_worst` means shrink;
/// * start simplex and shrink points enter the simplex unconditionally: no cutoff.
///
/// A rejected point never enters the simplex, so only exact values are ever compared again;
/// its lower bound is what the evaluation log records (`exact = false`).
pub fn minimize_unit_box_with_cutoff<E>(
    mut f: impl FnMut(&[f64], Option<Cutoff>) -> Result<Trial, E>,
    x0: &[f64],
    opts: &NelderMeadOptions,
) -> Result<NelderMeadResult, E> {
    let d = x0.len();
    let mut evaluations: Vec<Evaluation> = Vec::new();
    let mut eval_cut =
        |x: &[f64], cut: Option<Cutoff>, log: &mut Vec<Evaluation>| -> Result<f64, E> {
            let (v, exact) = match f(x, cut)? {
                Trial::Exact(v) => (v, true),
                Trial::AtLeast(lb) if cut.is_some_and(|c| c.rejects(lb)) => (lb, false),
                // A bound that decides nothing breaks `f`'s contract; the search can only
                // take it at face value.
                Trial::AtLeast(lb) => {
                    debug_assert!(
                        cut.is_some_and(|c| c.rejects(lb)),
                        "lower bound {lb} offered for cutoff {cut:?}"
                    );
                    (lb, true)
                }
            };
            let v = if v.is_finite() { v } else { f64::INFINITY };
            log.push(Evaluation {
                x: x.to_vec(),
                f: v,
                exact,
            });
            Ok(v)
        };
    let mut start = x0.to_vec();
    project(&mut start);
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(d + 1);
    let f0 = eval_cut(&start, None, &mut evaluations)?;
    simplex.push((start.clone(), f0));
    for i in 0..d {
        let mut v = start.clone();
        v[i] = if v[i] + opts.initial_step <= 1.0 {
            v[i] + opts.initial_step
        } else {
            v[i] - opts.initial_step
        };
        project(&mut v);
        let fv = eval_cut(&v, None, &mut evaluations)?;
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
        let worst = Cutoff {
            value: simplex[d].1,
            inclusive: true,
        };
        let fr = eval_cut(&xr, Some(worst), &mut evaluations)?;
        if fr < simplex[0].1 {
            let xe = along(-2.0);
            let cut = Cutoff {
                value: fr,
                inclusive: true,
            };
            let fe = eval_cut(&xe, Some(cut), &mut evaluations)?;
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
            let cut = Cutoff {
                value: fr,
                inclusive: false,
            };
            let fc = eval_cut(&xc, Some(cut), &mut evaluations)?;
            (xc, fc, fc <= fr)
        } else {
            let xc = along(0.5);
            let fc = eval_cut(&xc, Some(worst), &mut evaluations)?;
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
            let fp = eval_cut(&p, None, &mut evaluations)?;
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

    /// A sum of non-negative terms evaluated term by term, stopping once the partial sum
    /// decides the offered cutoff — the calibration's early rejection in miniature.
    fn terms(x: &[f64]) -> Vec<f64> {
        let c = [0.31, 0.62, 0.47];
        let mut t: Vec<f64> = x
            .iter()
            .zip(c)
            .enumerate()
            .map(|(i, (a, b))| (i as f64 + 1.0) * (a - b).powi(2))
            .collect();
        // A coupled, non-smooth term, like the touchdown's refined bracket.
        t.push(((x[0] + x[1] - 0.9) * 20.0).floor().abs() * 0.01);
        t
    }

    #[test]
    fn early_rejection_leaves_the_trajectory_unchanged() {
        for (x0, step) in [([0.5, 0.5, 0.5], 0.15), ([0.05, 0.9, 0.2], 0.3)] {
            let opts = NelderMeadOptions {
                initial_step: step,
                f_tolerance: 1e-10,
                x_tolerance: 1e-6,
                max_evaluations: 600,
            };
            let exact = minimize_unit_box(
                |x| -> Result<f64, Infallible> { Ok(terms(x).iter().sum()) },
                &x0,
                &opts,
            )
            .unwrap();
            let mut terms_summed = (0, 0);
            let cut = minimize_unit_box_with_cutoff(
                |x, cut| -> Result<Trial, Infallible> {
                    let t = terms(x);
                    terms_summed.1 += t.len();
                    let mut partial = 0.0;
                    for (k, v) in t.iter().enumerate() {
                        terms_summed.0 += 1;
                        // Later terms first, as the calibration leaves its costly term last.
                        partial += v;
                        if k + 1 < t.len() && cut.is_some_and(|c| c.rejects(partial)) {
                            return Ok(Trial::AtLeast(partial));
                        }
                    }
                    // The exact value summed in the same order as the reference.
                    Ok(Trial::Exact(t.iter().sum()))
                },
                &x0,
                &opts,
            )
            .unwrap();
            // The same points in the same order; exact values bit for bit; bounds below.
            assert_eq!(exact.evaluations.len(), cut.evaluations.len());
            for (a, b) in exact.evaluations.iter().zip(&cut.evaluations) {
                assert_eq!(a.x, b.x);
                if b.exact {
                    assert_eq!(a.f.to_bits(), b.f.to_bits());
                } else {
                    assert!(b.f <= a.f, "{} > {}", b.f, a.f);
                }
            }
            assert_eq!(exact.x, cut.x);
            assert_eq!(exact.f.to_bits(), cut.f.to_bits());
            assert_eq!(exact.stop, cut.stop);
            let rejected = cut.evaluations.iter().filter(|e| !e.exact).count();
            assert!(rejected > 0, "no point was rejected early");
            assert!(terms_summed.0 < terms_summed.1);
        }
    }
}
