//! Problems with known answers for the BEM solver (docs/contact.md, "Deterministic contact";
//! the G rows of `hdi validate`): Hertz's sphere, Westergaard's periodic sinusoid, and the
//! small-load area–pressure proportionality of a self-affine surface.

use super::{at_pressures, BemSolver, Boundary, SolverSettings};
use crate::contact::ContactError;
use crate::numerics::fft2::{angular_wavenumbers, fft2_real, ifft2};
use crate::numerics::rng::Rng;
use ndarray::Array2;
use rustfft::num_complex::Complex64;
use std::f64::consts::PI;

/// Hertz's paraboloid against a flat, solved non-periodically.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzCheck {
    /// Contact radius: Hertz `(3FR/4E*)^{1/3}` and the BEM's `√(A/π)` [m].
    pub radius_exact: f64,
    pub radius: f64,
    /// Peak pressure: Hertz `3F/(2πa²)` and the BEM's largest element pressure [Pa].
    pub peak_exact: f64,
    pub peak: f64,
    pub iterations: usize,
}

/// A paraboloid of radius `R` = 1 m against a flat, `E*` = 1 Pa, on an `n × n` grid whose side
/// is `side_ratio` contact diameters (the contact radius spans `n/(2·side_ratio)` elements;
/// the non-periodic domain only has to hold the contact, so `side_ratio` ≥ 1.2 suffices).
pub fn hertz(
    n: usize,
    side_ratio: f64,
    settings: &SolverSettings,
) -> Result<HertzCheck, ContactError> {
    let (r_sphere, e_star, side) = (1.0, 1.0, 1.0);
    let dx = side / n as f64;
    let a = side / (2.0 * side_ratio);
    let force = 4.0 * e_star * a.powi(3) / (3.0 * r_sphere);
    let centre = (n / 2) as f64 * dx;
    let heights: Vec<f64> = (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as f64 * dx - centre, (k / n) as f64 * dx - centre);
            -(x * x + y * y) / (2.0 * r_sphere)
        })
        .collect();
    let solver = BemSolver::new(&heights, n, n, (dx, dx), e_star, Boundary::NonPeriodic)?;
    let s = &at_pressures(&solver, &[force / (side * side)], settings)?[0];
    let area = s.contact_fraction * side * side;
    let peak = s.pressure.iter().cloned().fold(0.0, f64::max);
    Ok(HertzCheck {
        radius_exact: a,
        radius: (area / PI).sqrt(),
        peak_exact: 3.0 * force / (2.0 * PI * a * a),
        peak,
        iterations: s.iterations,
    })
}

/// Westergaard's periodic sinusoid at one mean pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WestergaardCheck {
    /// `p̄/p*`, `p* = π E* Δ/λ` the pressure of full contact.
    pub load: f64,
    /// Contact fraction `2a/λ`: Westergaard's `(2/π)·asin(√(p̄/p*))` and the BEM's.
    pub fraction_exact: f64,
    pub fraction: f64,
    pub iterations: usize,
}

/// `h = Δ cos(2πx/λ)` on `n` elements per wavelength (one row, periodic), at each of `loads`
/// (`p̄/p*`, in (0, 1)).
pub fn westergaard(
    n: usize,
    loads: &[f64],
    settings: &SolverSettings,
) -> Result<Vec<WestergaardCheck>, ContactError> {
    let (lambda, amplitude, e_star) = (1.0, 1e-3, 1.0);
    let dx = lambda / n as f64;
    let heights: Vec<f64> = (0..n)
        .map(|i| amplitude * (2.0 * PI * i as f64 / n as f64).cos())
        .collect();
    let solver = BemSolver::new(&heights, n, 1, (dx, dx), e_star, Boundary::Periodic)?;
    let p_star = PI * e_star * amplitude / lambda;
    let pressures: Vec<f64> = loads.iter().map(|l| l * p_star).collect();
    let solutions = at_pressures(&solver, &pressures, settings)?;
    Ok(loads
        .iter()
        .zip(solutions)
        .map(|(&load, s)| WestergaardCheck {
            load,
            fraction_exact: 2.0 / PI * load.sqrt().asin(),
            fraction: s.contact_fraction,
            iterations: s.iterations,
        })
        .collect())
}

/// A periodic, isotropic, Gaussian self-affine surface (`n × n` on a unit square): PSD
/// `C(q) ∝ q^{−2(1+H)}` between the roll-off `k_r` and the cutoff `k_s` (wavenumbers in units
/// of 2π/L), flat below `k_r`, zero above `k_s`; random phases from `seed`. Scaled to RMS
/// height 1; returns the heights and the RMS slope `h′_rms` from the spectrum.
pub fn self_affine(n: usize, hurst: f64, k_r: f64, k_s: f64, seed: u64) -> (Vec<f64>, f64) {
    let q = angular_wavenumbers(n, 1.0 / n as f64);
    let unit = 2.0 * PI;
    let mut rng = Rng::new(seed);
    let mut spectrum = Array2::<Complex64>::zeros((n, n));
    for ((j, i), c) in spectrum.indexed_iter_mut() {
        let k = q[i].hypot(q[j]) / unit;
        if k == 0.0 || k > k_s {
            continue;
        }
        let amplitude = k.max(k_r).powf(-(1.0 + hurst));
        let (a, b) = rng.normal_pair();
        *c = Complex64::new(a, b) * amplitude;
    }
    let field = ifft2(&spectrum).mapv(|c| c.re);
    let n2 = (n * n) as f64;
    let mean = field.sum() / n2;
    let rms = (field.mapv(|v| (v - mean).powi(2)).sum() / n2).sqrt();
    let heights: Vec<f64> = field.iter().map(|v| (v - mean) / rms).collect();
    let h = Array2::from_shape_vec((n, n), heights.clone()).expect("n × n heights");
    let spec = fft2_real(&h);
    let slope2: f64 = spec
        .indexed_iter()
        .map(|((j, i), c)| (q[i] * q[i] + q[j] * q[j]) * c.norm_sqr())
        .sum::<f64>()
        / (n2 * n2);
    (heights, slope2.sqrt())
}

/// The small-load proportionality `A_r/A_0 = κ·p̄/(E* h′_rms)`.
#[derive(Debug, Clone, PartialEq)]
pub struct KappaCheck {
    /// `(p̄/(E* h′_rms), A_r/A_0, κ)` at each load.
    pub points: Vec<(f64, f64, f64)>,
    /// Mean κ over the loads.
    pub kappa: f64,
}

/// κ of [`self_affine`]`(n, hurst, k_r, k_s, seed)` at the reduced pressures `loads`.
pub fn kappa(
    n: usize,
    (hurst, k_r, k_s, seed): (f64, f64, f64, u64),
    loads: &[f64],
    settings: &SolverSettings,
) -> Result<KappaCheck, ContactError> {
    let (heights, slope) = self_affine(n, hurst, k_r, k_s, seed);
    let dx = 1.0 / n as f64;
    let solver = BemSolver::new(&heights, n, n, (dx, dx), 1.0, Boundary::Periodic)?;
    let pressures: Vec<f64> = loads.iter().map(|l| l * slope).collect();
    let points: Vec<(f64, f64, f64)> = at_pressures(&solver, &pressures, settings)?
        .iter()
        .zip(loads)
        .map(|(s, &l)| (l, s.contact_fraction, s.contact_fraction / l))
        .collect();
    let kappa = points.iter().map(|p| p.2).sum::<f64>() / points.len().max(1) as f64;
    Ok(KappaCheck { points, kappa })
}
