//! Periodicity classification from a Poincaré section (docs/analysis.md has the same rule).
//!
//! Scale: the amplitude `A = (max maxima − min minima)/2` of the section. Swings are the
//! half-cycle excursions `h_i = |e_{i+1} − e_i|` between successive extrema. In this order:
//!
//! 1. **Fixed point** — the oscillation dies out: the largest swing in the last quarter of the
//!    record is below `convergence_ratio` (1 %) of the largest in the first quarter; or it
//!    decays steadily: ≥ 95 % of the per-period swing ratios `h_{i+2}/h_i` are < 1 and the
//!    last/first ratio is < 0.5. (The median per-period ratio is reported: for a damped
//!    oscillator it is `exp(−2πζ/√(1−ζ²))`.)
//! 2. **Periodic, period k** — the smallest `k ≤ max_period` (16) with
//!    `|x_{n+k} − x_n| ≤ tolerance·A` (1 %) for every maximum and every minimum: the section
//!    shows k points.
//! 3. **Quasi-periodic** — the return map `(x_n, x_{n+1})` fills a closed curve: ≥ 90 % of the
//!    maxima distinct at 10⁻⁴ A (or at least 200 distinct values, so that long records, whose
//!    maxima crowd closer than 10⁻⁴ A, still pass); around the centroid the points cover ≥ 90 % of 36 angular
//!    sectors and leave a hole (`r_min/r_max ≥ 0.05`, a ring, not a blob); and the map is
//!    locally one-dimensional: for the median point the two nearest neighbours lie on opposite
//!    sides (cosine of the angle between them ≤ −0.8; on ≤ 500 points, evenly subsampled).
//! 4. **Irregular** — anything else (chaos, noise, or a transient the rules do not fit).
//!
//! At least `min_points` (16) maxima are required. The rule is deliberately simple: it does not
//! estimate Lyapunov exponents or a correlation dimension, and measurement noise above the
//! tolerance turns a periodic orbit into "irregular" — raise `tolerance` for noisy data; the
//! diagnostics say how close each test came.

use super::poincare::PoincareSection;
use super::AnalysisError;
use std::f64::consts::PI;

/// The verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    FixedPoint,
    Periodic { period: usize },
    QuasiPeriodic,
    Irregular,
}

impl std::fmt::Display for Class {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Class::FixedPoint => f.write_str("fixed point"),
            Class::Periodic { period } => write!(f, "periodic (period {period})"),
            Class::QuasiPeriodic => f.write_str("quasi-periodic"),
            Class::Irregular => f.write_str("irregular"),
        }
    }
}

/// Thresholds of the rule (defaults in the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClassifyOptions {
    pub min_points: usize,
    pub convergence_ratio: f64,
    pub tolerance: f64,
    pub max_period: usize,
    pub distinct_tolerance: f64,
    pub min_distinct_fraction: f64,
    /// This many distinct values suffice whatever the fraction.
    pub distinct_cap: usize,
    pub sectors: usize,
    pub min_coverage: f64,
    pub min_hole: f64,
    pub max_neighbour_cosine: f64,
}

impl Default for ClassifyOptions {
    fn default() -> Self {
        ClassifyOptions {
            min_points: 16,
            convergence_ratio: 0.01,
            tolerance: 0.01,
            max_period: 16,
            distinct_tolerance: 1e-4,
            min_distinct_fraction: 0.9,
            distinct_cap: 200,
            sectors: 36,
            min_coverage: 0.9,
            min_hole: 0.05,
            max_neighbour_cosine: -0.8,
        }
    }
}

/// The numbers behind the verdict.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Diagnostics {
    pub n_maxima: usize,
    /// A, signal units.
    pub amplitude: f64,
    /// (max − min) of the maxima / A.
    pub spread: f64,
    /// Largest swing of the last quarter / largest of the first quarter.
    pub final_to_initial: f64,
    /// Median per-period swing ratio h_{i+2}/h_i.
    pub decay_ratio: f64,
    /// Fraction of per-period swing ratios below 1.
    pub decreasing_fraction: f64,
    /// Smallest k ≤ max_period and its max |x_{n+k} − x_n|/A (the best k if none passes).
    pub best_period: usize,
    pub period_residual: f64,
    /// Number and fraction of maxima distinct at distinct_tolerance·A.
    pub distinct_values: usize,
    pub distinct_fraction: f64,
    /// Occupied fraction of the angular sectors around the return map's centroid.
    pub coverage: f64,
    /// r_min/r_max of the return map around its centroid.
    pub hole: f64,
    /// Median cosine of the angle between a point's two nearest neighbours (−1: on a curve).
    pub neighbour_cosine: f64,
}

/// Classification with its diagnostics.
#[derive(Debug, Clone, PartialEq)]
pub struct Classification {
    pub class: Class,
    pub diagnostics: Diagnostics,
}

/// Classifies the motion behind a Poincaré section (rule in the module docs): each test
/// gathers its evidence into the diagnostics, then its threshold decides or passes on.
pub fn classify(
    section: &PoincareSection,
    opts: &ClassifyOptions,
) -> Result<Classification, AnalysisError> {
    check_section(section, opts)?;
    let scale = Scale::of(section);
    let mut d = Diagnostics {
        n_maxima: section.maxima.len(),
        amplitude: scale.amplitude,
        ..Default::default()
    };
    let verdict = |class, diagnostics| Ok(Classification { class, diagnostics });
    if scale.amplitude.is_nan() || scale.amplitude <= 0.0 {
        return verdict(Class::FixedPoint, d);
    }
    d.spread = scale.spread;

    // 1. Convergence.
    let decay = swing_decay(section);
    d.final_to_initial = decay.final_to_initial;
    d.decreasing_fraction = decay.decreasing_fraction;
    d.decay_ratio = decay.decay_ratio;
    if decay.converges(opts) {
        return verdict(Class::FixedPoint, d);
    }

    // 2. Periodicity of maxima and minima.
    let fit = period_search(section, scale.amplitude, opts);
    d.best_period = fit.best_period;
    d.period_residual = fit.residual;
    if fit.passed {
        return verdict(
            Class::Periodic {
                period: fit.best_period,
            },
            d,
        );
    }

    // 3. A closed one-dimensional curve in the return map.
    let curve = return_map_shape(section, scale.amplitude, opts);
    d.distinct_values = curve.distinct_values;
    d.distinct_fraction = curve.distinct_fraction;
    d.coverage = curve.coverage;
    d.hole = curve.hole;
    d.neighbour_cosine = curve.neighbour_cosine;
    let class = if curve.is_closed_curve(opts) {
        Class::QuasiPeriodic
    } else {
        Class::Irregular
    };
    verdict(class, d)
}

/// At least `min_points` (and 4) maxima, 2 minima, all finite.
fn check_section(section: &PoincareSection, opts: &ClassifyOptions) -> Result<(), AnalysisError> {
    let m = &section.maxima;
    let need = opts.min_points.max(4);
    if m.len() < need || section.minima.len() < 2 {
        return Err(AnalysisError::TooShort {
            what: "classification (record too short or not oscillating)",
            len: m.len(),
            min: need,
            unit: "Poincaré maxima",
        });
    }
    if let Some(i) = m.iter().chain(&section.minima).position(|v| !v.is_finite()) {
        return Err(AnalysisError::NonFinite {
            what: "classification: section point",
            index: i,
            value: m
                .iter()
                .chain(&section.minima)
                .nth(i)
                .copied()
                .unwrap_or(f64::NAN),
        });
    }
    Ok(())
}

/// The section's scale.
struct Scale {
    /// `A = (max maxima − min minima)/2`.
    amplitude: f64,
    /// (max − min) of the maxima / A.
    spread: f64,
}

impl Scale {
    /// From the largest maximum, the smallest maximum and the smallest minimum.
    fn of(section: &PoincareSection) -> Scale {
        let m = &section.maxima;
        let max = m.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let min_max = m.iter().cloned().fold(f64::INFINITY, f64::min);
        let min = section.minima.iter().cloned().fold(f64::INFINITY, f64::min);
        let amplitude = 0.5 * (max - min);
        Scale {
            amplitude,
            spread: (max - min_max) / amplitude,
        }
    }
}

/// Test 1's evidence: how the half-cycle swings shrink.
struct Decay {
    /// Largest swing of the last quarter / largest of the first quarter.
    final_to_initial: f64,
    /// Fraction of per-period swing ratios `h_{i+2}/h_i` below 1.
    decreasing_fraction: f64,
    /// Their median.
    decay_ratio: f64,
}

impl Decay {
    /// Dies out, or decays steadily.
    fn converges(&self, opts: &ClassifyOptions) -> bool {
        self.final_to_initial < opts.convergence_ratio
            || (self.decreasing_fraction >= 0.95 && self.final_to_initial < 0.5)
    }
}

/// Swings `h_i = |e_{i+1} − e_i|` between successive extrema and their decay.
fn swing_decay(section: &PoincareSection) -> Decay {
    let ext = section.extrema();
    let swings: Vec<f64> = ext.windows(2).map(|w| (w[1].1 - w[0].1).abs()).collect();
    let q = (swings.len() / 4).max(1);
    let largest = |s: &[f64]| s.iter().cloned().fold(0.0, f64::max);
    let first = largest(&swings[..q]);
    let last = largest(&swings[swings.len() - q..]);
    let mut ratios: Vec<f64> = swings
        .windows(3)
        .filter(|w| w[0] > 0.0)
        .map(|w| w[2] / w[0])
        .collect();
    let decreasing_fraction = if ratios.is_empty() {
        0.0
    } else {
        ratios.iter().filter(|&&r| r < 1.0).count() as f64 / ratios.len() as f64
    };
    Decay {
        final_to_initial: if first > 0.0 { last / first } else { 0.0 },
        decreasing_fraction,
        decay_ratio: median(&mut ratios),
    }
}

/// Test 2's evidence.
struct PeriodFit {
    /// The passing k if `passed`, else the k with the smallest residual.
    best_period: usize,
    /// max |x_{n+k} − x_n| / A at `best_period`.
    residual: f64,
    passed: bool,
}

/// The smallest `k ≤ max_period` whose maxima and minima repeat within `tolerance·A`.
fn period_search(section: &PoincareSection, amplitude: f64, opts: &ClassifyOptions) -> PeriodFit {
    let m = &section.maxima;
    let residual = |k: usize| -> f64 {
        [m, &section.minima]
            .iter()
            .flat_map(|s| s.windows(k + 1).map(move |w| (w[k] - w[0]).abs()))
            .fold(0.0, f64::max)
            / amplitude
    };
    let kmax = opts.max_period.min(m.len() / 2).max(1);
    let mut fit = PeriodFit {
        best_period: 0,
        residual: f64::INFINITY,
        passed: false,
    };
    for k in 1..=kmax {
        let r = residual(k);
        if r < fit.residual {
            fit.best_period = k;
            fit.residual = r;
        }
        if r <= opts.tolerance {
            fit.best_period = k;
            fit.residual = r;
            fit.passed = true;
            break;
        }
    }
    fit
}

/// Test 3's evidence: is the return map a closed one-dimensional curve?
struct CurveShape {
    /// Number and fraction of maxima distinct at `distinct_tolerance·A`.
    distinct_values: usize,
    distinct_fraction: f64,
    /// Occupied fraction of the angular sectors around the centroid.
    coverage: f64,
    /// r_min/r_max around the centroid.
    hole: f64,
    /// Median cosine of the angle between a point's two nearest neighbours.
    neighbour_cosine: f64,
}

impl CurveShape {
    /// Enough distinct values, all around the centroid, a ring not a blob, locally a curve.
    fn is_closed_curve(&self, opts: &ClassifyOptions) -> bool {
        let enough_distinct = self.distinct_fraction >= opts.min_distinct_fraction
            || self.distinct_values >= opts.distinct_cap;
        enough_distinct
            && self.coverage >= opts.min_coverage
            && self.hole >= opts.min_hole
            && self.neighbour_cosine <= opts.max_neighbour_cosine
    }
}

/// Test 3's evidence from the maxima and their return map `(x_n, x_{n+1})`.
fn return_map_shape(
    section: &PoincareSection,
    amplitude: f64,
    opts: &ClassifyOptions,
) -> CurveShape {
    let m = &section.maxima;
    let distinct = distinct_values(m, opts.distinct_tolerance * amplitude);
    let pts = section.return_map();
    let ring = ring_around_centroid(&pts, opts.sectors.max(1));
    CurveShape {
        distinct_values: distinct,
        distinct_fraction: distinct as f64 / m.len() as f64,
        coverage: ring.coverage,
        hole: ring.hole,
        neighbour_cosine: neighbour_cosine(&pts),
    }
}

/// Values distinct at `tol`: greedy bins of width `tol` anchored at their first value
/// (chaining gaps would merge a dense set into one cluster).
fn distinct_values(values: &[f64], tol: f64) -> usize {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mut distinct = 0;
    let mut anchor = f64::NEG_INFINITY;
    for &v in &sorted {
        if v - anchor > tol {
            distinct += 1;
            anchor = v;
        }
    }
    distinct
}

/// How the return map surrounds its centroid.
struct Ring {
    /// Occupied fraction of the angular sectors.
    coverage: f64,
    /// r_min/r_max (0 if all points sit on the centroid).
    hole: f64,
}

/// Angular coverage and hole of `pts` around their centroid, in `sectors` sectors.
fn ring_around_centroid(pts: &[[f64; 2]], sectors: usize) -> Ring {
    let (cx, cy) = {
        let n = pts.len() as f64;
        (
            pts.iter().map(|p| p[0]).sum::<f64>() / n,
            pts.iter().map(|p| p[1]).sum::<f64>() / n,
        )
    };
    let mut occupied = vec![false; sectors];
    let (mut rmin, mut rmax) = (f64::INFINITY, 0.0f64);
    for p in pts {
        let (dx, dy) = (p[0] - cx, p[1] - cy);
        let r = dx.hypot(dy);
        rmin = rmin.min(r);
        rmax = rmax.max(r);
        let a = dy.atan2(dx) + PI; // 0..=2π
        occupied[((a / (2.0 * PI) * sectors as f64) as usize).min(sectors - 1)] = true;
    }
    Ring {
        coverage: occupied.iter().filter(|&&o| o).count() as f64 / sectors as f64,
        hole: if rmax > 0.0 { rmin / rmax } else { 0.0 },
    }
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Median over points of the cosine of the angle at a point between its two nearest
/// neighbours. On at most 500 points (evenly subsampled in time): denser sets would put the
/// neighbours closer than the sub-sample scatter of the parabola-refined extrema of coarsely
/// sampled records (≈ 15–20 samples per period), which is not the curve's structure.
fn neighbour_cosine(pts: &[[f64; 2]]) -> f64 {
    let step = pts.len().div_ceil(500).max(1);
    let p: Vec<[f64; 2]> = pts.iter().step_by(step).copied().collect();
    if p.len() < 3 {
        return f64::NAN;
    }
    let mut cosines: Vec<f64> = Vec::with_capacity(p.len());
    for (i, a) in p.iter().enumerate() {
        let (mut b1, mut b2) = ((f64::INFINITY, 0), (f64::INFINITY, 0));
        for (j, b) in p.iter().enumerate() {
            if i == j {
                continue;
            }
            let d2 = (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2);
            if d2 < b1.0 {
                b2 = b1;
                b1 = (d2, j);
            } else if d2 < b2.0 {
                b2 = (d2, j);
            }
        }
        let (u, w) = (p[b1.1], p[b2.1]);
        let (ux, uy, wx, wy) = (u[0] - a[0], u[1] - a[1], w[0] - a[0], w[1] - a[1]);
        let norm = ux.hypot(uy) * wx.hypot(wy);
        if norm > 0.0 {
            cosines.push((ux * wx + uy * wy) / norm);
        }
    }
    median(&mut cosines)
}
