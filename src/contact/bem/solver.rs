//! The Polonsky–Keer (1999) constrained conjugate gradient for frictionless, non-adhesive
//! elastic contact against a rigid flat (docs/contact.md, "Deterministic contact").
//!
//! Unknown: the element pressures `p ≥ 0`. Gap `g = d − h + u(p)` with `h` the heights about
//! their mean plane, `u = K p` the half-space's displacement ([`super::kernel`]) and `d` the
//! flat's separation from that plane. Solution: `p ≥ 0`, `g ≥ 0`, `p·g = 0` elementwise.
//!
//! - **Mean pressure given**: `d` is unknown; each iteration removes the mean gap over the
//!   contact set (its Lagrange multiplier), and rescales `p` to the target mean (PK's step 6).
//! - **Separation given**: the gap is known up to `K p`; the same iteration without the mean
//!   removal and the rescaling (Rey, Anciaux & Molinari 2017 solve the same problem).
//!
//! **Convergence**: with `Ic` the elements carrying pressure,
//! `ε = Σ_Ic p·|g| / (Σ p · σ)` (the pressure-weighted gap left on the contact set, in units of
//! the heights' RMS σ) and `π = max over the free elements of (−g)/σ` (penetration left
//! outside it). Converged when both are ≤ the tolerance; reaching the iteration limit first is
//! an error, never a silent stop. The vector operations run in one thread in a fixed order, so
//! a solve is bit-for-bit reproducible; the FFTs run in parallel, row by row.

use super::kernel;
use crate::contact::ContactError;
use crate::signal::fft_convolution::{ConvolutionWork, FftConvolver};
use std::sync::Mutex;

/// The domain's boundary condition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Boundary {
    /// The map repeats: the natural model of a patch of a larger surface.
    Periodic,
    /// An isolated body on an infinite half-space (zero-padded, Hockney): a sphere, a punch.
    NonPeriodic,
}

/// What is imposed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// Mean pressure over the nominal area [Pa].
    MeanPressure(f64),
    /// Separation of the flat from the mean plane of the heights [m].
    Separation(f64),
}

/// Convergence settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Bound on both `ε` and `π` (module docs).
    pub tolerance: f64,
    pub max_iterations: usize,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            tolerance: 1e-10,
            max_iterations: 10_000,
        }
    }
}

/// A converged contact state.
#[derive(Debug, Clone, PartialEq)]
pub struct BemSolution {
    /// Element pressures [Pa], row-major like the heights.
    pub pressure: Vec<f64>,
    /// Element gaps [m].
    pub gap: Vec<f64>,
    pub mean_pressure: f64,
    pub mean_gap: f64,
    /// The flat's separation from the mean plane of the undeformed heights [m].
    pub separation: f64,
    /// Fraction of elements carrying pressure.
    pub contact_fraction: f64,
    pub iterations: usize,
    /// Final `ε` and `π` (module docs).
    pub error: f64,
    pub penetration: f64,
}

/// A surface on a grid, ready to solve.
pub struct BemSolver {
    nx: usize,
    ny: usize,
    /// Heights about their mean plane [m].
    heights: Vec<f64>,
    sigma: f64,
    max_height: f64,
    /// Displacement of an element under unit pressure on itself [m/Pa].
    self_compliance: f64,
    compliance: FftConvolver,
    boundary: Boundary,
    work: Mutex<ConvolutionWork>,
}

impl BemSolver {
    /// `heights` row-major (`y·nx + x`), spacing `dx × dy` [m], reduced modulus `e_star`.
    pub fn new(
        heights: &[f64],
        nx: usize,
        ny: usize,
        (dx, dy): (f64, f64),
        e_star: f64,
        boundary: Boundary,
    ) -> Result<Self, ContactError> {
        let bad = |name, value: f64, why: &str| Err(ContactError::parameter(name, value, why));
        if nx < 2 || ny < 1 || heights.len() != nx * ny {
            return Err(ContactError::parameter(
                "grid",
                format!("{nx} × {ny} for {} heights", heights.len()),
                "needs at least 2 × 1 elements, one height each",
            ));
        }
        if !(dx > 0.0 && dy > 0.0 && dx.is_finite() && dy.is_finite()) {
            return bad("spacing", dx.min(dy), "must be finite and > 0");
        }
        if !(e_star > 0.0 && e_star.is_finite()) {
            return bad("E*", e_star, "must be finite and > 0");
        }
        if let Some(i) = heights.iter().position(|h| !h.is_finite()) {
            return Err(ContactError::parameter(
                "heights",
                format!("element {i}"),
                "is not finite (fill or crop invalid pixels first)",
            ));
        }
        let n = heights.len() as f64;
        let mean = heights.iter().sum::<f64>() / n;
        let heights: Vec<f64> = heights.iter().map(|h| h - mean).collect();
        let sigma = (heights.iter().map(|h| h * h).sum::<f64>() / n).sqrt();
        if sigma <= 0.0 {
            return bad(
                "heights",
                sigma,
                "have zero RMS: a flat surface has no rough contact",
            );
        }
        let max_height = heights.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let compliance = match boundary {
            Boundary::Periodic => kernel::periodic(nx, ny, dx, dy, e_star),
            Boundary::NonPeriodic => kernel::non_periodic(nx, ny, dx, dy, e_star),
        };
        let mut work = compliance.work();
        let mut unit = vec![0.0; nx * ny];
        unit[0] = 1.0;
        let mut u = vec![0.0; nx * ny];
        compliance.apply(&unit, &mut u, &mut work);
        Ok(BemSolver {
            nx,
            ny,
            heights,
            sigma,
            max_height,
            self_compliance: u[0],
            compliance,
            boundary,
            work: Mutex::new(work),
        })
    }

    /// RMS of the heights about their mean plane [m].
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Highest height above the mean plane [m]: no contact at larger separations.
    pub fn max_height(&self) -> f64 {
        self.max_height
    }

    pub fn grid(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    pub fn boundary(&self) -> Boundary {
        self.boundary
    }

    /// Bytes the solver holds (heights, kernel, FFT buffers) plus one solve's fields.
    pub fn memory_bytes(&self) -> usize {
        self.compliance.memory_bytes() + 8 * self.heights.len() * 6
    }

    /// `u = K p`.
    pub fn displacement(&self, p: &[f64], u: &mut [f64]) {
        let mut work = self.work.lock().unwrap_or_else(|e| e.into_inner());
        self.compliance.apply(p, u, &mut work);
    }

    /// Solve for `target`, starting from `warm` (a previous pressure field) when given.
    pub fn solve(
        &self,
        target: Target,
        settings: &SolverSettings,
        warm: Option<&[f64]>,
    ) -> Result<BemSolution, ContactError> {
        let n = self.heights.len();
        let tol = settings.tolerance;
        if !(tol > 0.0 && tol.is_finite()) {
            return Err(ContactError::parameter("tolerance", tol, "must be > 0"));
        }
        if warm.is_some_and(|w| w.len() != n) {
            return Err(ContactError::parameter(
                "warm start",
                warm.map_or(0, <[f64]>::len),
                format!("needs {n} pressures"),
            ));
        }
        let (p_target, d) = match target {
            Target::MeanPressure(p) if p > 0.0 && p.is_finite() => (Some(p), 0.0),
            Target::MeanPressure(p) => {
                return Err(ContactError::parameter("mean pressure", p, "must be > 0"))
            }
            Target::Separation(d) if d.is_finite() => (None, d),
            Target::Separation(d) => {
                return Err(ContactError::parameter("separation", d, "must be finite"))
            }
        };
        if p_target.is_none() && d >= self.max_height {
            return Ok(self.no_contact(d));
        }
        let h = &self.heights;
        let mut p = self.initial_pressure(p_target, d, warm);
        let mut u = vec![0.0; n];
        let mut g = vec![0.0; n];
        let mut t = vec![0.0; n];
        let mut r = vec![0.0; n];
        self.displacement(&p, &mut u);
        let (mut g_old, mut conjugate) = (1.0, false);
        for iteration in 0..=settings.max_iterations {
            // The gap, up to the constant a pressure target removes below.
            for i in 0..n {
                g[i] = d - h[i] + u[i];
            }
            let (mut on, mut sum_g) = (0usize, 0.0);
            for i in 0..n {
                if p[i] > 0.0 {
                    on += 1;
                    sum_g += g[i];
                }
            }
            let shift = match p_target {
                Some(_) if on > 0 => sum_g / on as f64,
                _ => 0.0,
            };
            if shift != 0.0 {
                g.iter_mut().for_each(|v| *v -= shift);
            }
            let (error, penetration) = self.residuals(&p, &g);
            if error <= tol && penetration <= tol {
                return Ok(self.solution(p, g, d - shift, iteration, error, penetration));
            }
            if iteration == settings.max_iterations {
                return Err(ContactError::Numerical(format!(
                    "BEM contact did not converge in {} iterations (error {error:.3e}, \
                     penetration {penetration:.3e}, tolerance {tol:.1e}): raise \
                     max_iterations or the tolerance",
                    settings.max_iterations
                )));
            }
            // Conjugate direction on the contact set.
            let big_g: f64 = (0..n).filter(|&i| p[i] > 0.0).map(|i| g[i] * g[i]).sum();
            let beta = if conjugate { big_g / g_old } else { 0.0 };
            for i in 0..n {
                t[i] = if p[i] > 0.0 { g[i] + beta * t[i] } else { 0.0 };
            }
            g_old = big_g;
            self.displacement(&t, &mut r);
            if p_target.is_some() && on > 0 {
                let mean_r = (0..n).filter(|&i| p[i] > 0.0).map(|i| r[i]).sum::<f64>() / on as f64;
                r.iter_mut().for_each(|v| *v -= mean_r);
            }
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..n {
                if p[i] > 0.0 {
                    num += g[i] * t[i];
                    den += r[i] * t[i];
                }
            }
            let tau = if den > 0.0 { num / den } else { 0.0 };
            for i in 0..n {
                if p[i] > 0.0 {
                    p[i] = (p[i] - tau * t[i]).max(0.0);
                }
            }
            // Elements that penetrate without pressure enter the contact set.
            let step = if tau > 0.0 {
                tau
            } else {
                1.0 / self.self_compliance
            };
            let mut entered = false;
            for i in 0..n {
                if p[i] == 0.0 && g[i] < 0.0 {
                    p[i] = -step * g[i];
                    entered = true;
                }
            }
            conjugate = !entered;
            if let Some(target) = p_target {
                let mean = p.iter().sum::<f64>() / n as f64;
                if mean <= 0.0 {
                    return Err(ContactError::Numerical(
                        "BEM contact lost every contact element".into(),
                    ));
                }
                let scale = target / mean;
                p.iter_mut().for_each(|v| *v *= scale);
            }
            self.displacement(&p, &mut u);
        }
        unreachable!("the loop returns at its last iteration")
    }

    /// The first pressure field: the warm start (rescaled to a pressure target), else uniform
    /// pressure (pressure target) or each overlapping element's pressure alone (separation).
    fn initial_pressure(&self, p_target: Option<f64>, d: f64, warm: Option<&[f64]>) -> Vec<f64> {
        let n = self.heights.len();
        if let Some(w) = warm.filter(|w| w.iter().any(|&v| v > 0.0)) {
            let mut p: Vec<f64> = w.iter().map(|&v| v.max(0.0)).collect();
            if let Some(target) = p_target {
                let scale = target * n as f64 / p.iter().sum::<f64>();
                p.iter_mut().for_each(|v| *v *= scale);
            }
            return p;
        }
        match p_target {
            Some(target) => vec![target; n],
            None => self
                .heights
                .iter()
                .map(|&h| ((h - d) / self.self_compliance).max(0.0))
                .collect(),
        }
    }

    /// `(ε, π)` of the module docs.
    fn residuals(&self, p: &[f64], g: &[f64]) -> (f64, f64) {
        let (mut weighted, mut total, mut worst) = (0.0, 0.0, 0.0f64);
        for (&pi, &gi) in p.iter().zip(g) {
            if pi > 0.0 {
                weighted += pi * gi.abs();
                total += pi;
            } else {
                worst = worst.max(-gi);
            }
        }
        let error = if total > 0.0 {
            weighted / (total * self.sigma)
        } else {
            0.0
        };
        (error, worst / self.sigma)
    }

    fn solution(
        &self,
        pressure: Vec<f64>,
        gap: Vec<f64>,
        separation: f64,
        iterations: usize,
        error: f64,
        penetration: f64,
    ) -> BemSolution {
        let n = pressure.len() as f64;
        let on = pressure.iter().filter(|&&v| v > 0.0).count();
        BemSolution {
            mean_pressure: pressure.iter().sum::<f64>() / n,
            mean_gap: gap.iter().sum::<f64>() / n,
            separation,
            contact_fraction: on as f64 / n,
            iterations,
            error,
            penetration,
            pressure,
            gap,
        }
    }

    fn no_contact(&self, d: f64) -> BemSolution {
        let gap: Vec<f64> = self.heights.iter().map(|h| d - h).collect();
        self.solution(vec![0.0; gap.len()], gap, d, 0, 0.0, 0.0)
    }
}
