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
use crate::signal::spectrum::{AmplitudeSpectrum, PeakOptions};
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
    /// Spectral-line test: lines are local maxima of the Hann amplitude spectrum at least this
    /// fraction of the largest (5 %), at most `max_lines` (16) of them.
    pub line_threshold: f64,
    pub max_lines: usize,
    /// The lines must carry at least this fraction of the variance (0.9) to call the signal a
    /// sum of tones.
    pub min_line_power: f64,
    /// Largest harmonic number q of the lowest line over the common fundamental (16, as
    /// `max_period`).
    pub max_denominator: usize,
    /// The fundamental period must fit this many times into the record (3).
    pub min_periods: f64,
    /// Frequency uncertainty of one refined line, in bins of the spectrum (0.02).
    pub line_tolerance_bins: f64,
    /// Largest recurrence residual rms(x(t+P) − x(t))/(√2·rms x) of a periodic signal (0.25).
    pub max_recurrence: f64,
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
            line_threshold: 0.05,
            max_lines: 16,
            min_line_power: 0.9,
            max_denominator: 16,
            min_periods: 3.0,
            line_tolerance_bins: 0.02,
            max_recurrence: 0.25,
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
    /// Which test decided: "decay", "section recurrence", "spectral lines", "return-map
    /// ring" or "none" (irregular).
    pub decided_by: &'static str,
    /// Period of a periodic verdict, s (the section's mean time per k maxima, or 1/fundamental).
    pub period_s: Option<f64>,
    /// The spectral-line test's evidence (`None` from [`classify`], which sees the section only).
    pub lines: Option<LineEvidence>,
}

/// One spectral line and its place in the harmonic series of the common fundamental.
#[derive(Debug, Clone, PartialEq)]
pub struct LineFit {
    /// Refined frequency, Hz, and amplitude, signal units.
    pub frequency_hz: f64,
    pub amplitude: f64,
    /// Frequency over the lowest line's.
    pub ratio: f64,
    /// The rational approximation p/q of `ratio` with q ≤ max_denominator that fits best
    /// (the one of the accepted fundamental if the lines are commensurate).
    pub numerator: u64,
    pub denominator: u64,
    /// |f − n·f0|, Hz, for the harmonic number n of this line, and the tolerance it was held to.
    pub mismatch_hz: f64,
    pub tolerance_hz: f64,
}

/// The spectral-line test (docs/analysis.md).
#[derive(Debug, Clone, PartialEq)]
pub struct LineEvidence {
    /// Lines, lowest frequency first.
    pub lines: Vec<LineFit>,
    /// Σ A²/2 over the lines / variance of the series.
    pub line_power_fraction: f64,
    /// The common fundamental, Hz, if the lines are integer multiples of one.
    pub fundamental_hz: Option<f64>,
    /// Harmonic number of the lowest line over that fundamental.
    pub lowest_harmonic: Option<u64>,
    /// Largest denominator tried (max_denominator, lowered so that the period fits
    /// min_periods times into the record).
    pub max_denominator: u64,
    /// rms(x(t+P) − x(t))/(√2·rms x) at the fundamental period P (0: exact recurrence, ≈1:
    /// unrelated).
    pub recurrence_residual: Option<f64>,
    /// Frequency resolution fs/N of the spectrum, Hz.
    pub resolution_hz: f64,
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
        d.decided_by = "decay";
        return verdict(Class::FixedPoint, d);
    }
    d.spread = scale.spread;

    // 1. Convergence.
    let decay = swing_decay(section);
    d.final_to_initial = decay.final_to_initial;
    d.decreasing_fraction = decay.decreasing_fraction;
    d.decay_ratio = decay.decay_ratio;
    if decay.converges(opts) {
        d.decided_by = "decay";
        return verdict(Class::FixedPoint, d);
    }

    // 2. Periodicity of maxima and minima.
    let fit = period_search(section, scale.amplitude, opts);
    d.best_period = fit.best_period;
    d.period_residual = fit.residual;
    if fit.passed {
        d.decided_by = "section recurrence";
        d.period_s = section_period(section, fit.best_period);
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
        d.decided_by = "return-map ring";
        Class::QuasiPeriodic
    } else {
        d.decided_by = "none";
        Class::Irregular
    };
    verdict(class, d)
}

/// Mean time spanned by `k` successive maxima, s.
fn section_period(section: &PoincareSection, k: usize) -> Option<f64> {
    let t = &section.maxima_time_s;
    let n = t.len();
    (n > k && k > 0).then(|| (t[n - 1] - t[0]) / (n - 1) as f64 * k as f64)
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

/// Classifies a series from its Poincaré section and its amplitude spectrum (docs/analysis.md):
/// the section tests of [`classify`] (decay → fixed point, recurrence of ≤ `max_period`
/// section points → periodic) first, then the spectral-line test, then the return-map ring.
///
/// Spectral-line test: the lines (local maxima ≥ `line_threshold` of the largest, Hann-refined)
/// must carry ≥ `min_line_power` of the variance. They are commensurate when, for some
/// q ≤ `max_denominator` (and q/f_low ≤ T/`min_periods`), every line sits within
/// `line_tolerance_bins`·Δf·(1 + n/q) of a multiple n of f0 = f_low/q (the lowest line's error
/// carried to harmonic n). Then the series is periodic with P = 1/f0 if it also recurs:
/// rms(x(t+P) − x(t)) ≤ `max_recurrence`·√2·rms x. Two or more lines that are not commensurate
/// are quasi-periodic (a torus). The period in section points is the mean number of maxima per P.
///
/// `x` is the (detrended) series the spectrum was computed from, sampled at `fs`.
pub fn classify_signal(
    x: &[f64],
    fs: f64,
    section: &PoincareSection,
    spectrum: &AmplitudeSpectrum,
    opts: &ClassifyOptions,
) -> Result<Classification, AnalysisError> {
    let mut c = classify(section, opts)?;
    let evidence = line_evidence(x, fs, spectrum, opts);
    let decided = matches!(c.class, Class::FixedPoint | Class::Periodic { .. });
    if !decided && evidence.line_power_fraction >= opts.min_line_power {
        match (evidence.fundamental_hz, evidence.recurrence_residual) {
            (Some(f0), Some(r)) if r <= opts.max_recurrence => {
                let period = 1.0 / f0;
                c.class = Class::Periodic {
                    period: maxima_per(section, period),
                };
                c.diagnostics.period_s = Some(period);
                c.diagnostics.decided_by = "spectral lines";
            }
            _ if evidence.lines.len() >= 2 => {
                c.class = Class::QuasiPeriodic;
                c.diagnostics.decided_by = "spectral lines";
            }
            _ => {}
        }
    }
    // A section-decided period is the mean spacing of k maxima; the fundamental, when it
    // agrees within 1 %, is the sharper estimate of the same period.
    if let (Class::Periodic { .. }, Some(p), Some(f0)) =
        (c.class, c.diagnostics.period_s, evidence.fundamental_hz)
    {
        if (p * f0 - 1.0).abs() < 0.01 {
            c.diagnostics.period_s = Some(1.0 / f0);
        }
    }
    c.diagnostics.lines = Some(evidence);
    Ok(c)
}

/// Mean number of section maxima in `period` seconds (at least 1).
fn maxima_per(section: &PoincareSection, period: f64) -> usize {
    let t = &section.maxima_time_s;
    let n = t.len();
    if n < 2 || t[n - 1] <= t[0] {
        return 1;
    }
    let rate = (n - 1) as f64 / (t[n - 1] - t[0]);
    ((rate * period).round() as usize).max(1)
}

/// The spectral-line test's evidence.
fn line_evidence(
    x: &[f64],
    fs: f64,
    spectrum: &AmplitudeSpectrum,
    opts: &ClassifyOptions,
) -> LineEvidence {
    let n = x.len().max(1) as f64;
    let mean = x.iter().sum::<f64>() / n;
    let variance = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    let mut peaks = spectrum.peaks(&PeakOptions {
        rel_threshold: opts.line_threshold,
        max_peaks: opts.max_lines.max(1),
        ..PeakOptions::default()
    });
    peaks.retain(|p| p.frequency > 0.0 && p.amplitude.is_finite());
    peaks.sort_by(|a, b| a.frequency.total_cmp(&b.frequency));
    let line_power: f64 = peaks.iter().map(|p| 0.5 * p.amplitude * p.amplitude).sum();
    let resolution = spectrum.resolution;
    let record = n / fs;
    let delta = opts.line_tolerance_bins * resolution;
    let mut ev = LineEvidence {
        lines: Vec::new(),
        line_power_fraction: if variance > 0.0 {
            line_power / variance
        } else {
            0.0
        },
        fundamental_hz: None,
        lowest_harmonic: None,
        max_denominator: 0,
        recurrence_residual: None,
        resolution_hz: resolution,
    };
    let Some(low) = peaks.first().map(|p| p.frequency) else {
        return ev;
    };
    // A record of exactly `min_periods` periods (e.g. 3 × 0.5 ms) sits on an integer: the
    // relative 1e-9 keeps the last bit of the refined line frequency (which depends on the FFT
    // algorithm's rounding) from deciding the denominator.
    let q_max = (opts.max_denominator as f64)
        .min((low * record / opts.min_periods * (1.0 + 1e-9)).floor())
        .max(0.0) as u64;
    ev.max_denominator = q_max;
    // Each line against f0 = low/q: harmonic number, mismatch and its tolerance.
    let fit = |q: u64, f: f64| {
        let f0 = low / q as f64;
        let h = (f / f0).round().max(1.0);
        ((f - h * f0).abs(), delta * (1.0 + h / q as f64), h as u64)
    };
    let accepted = (1..=q_max).find(|&q| {
        peaks.iter().all(|p| {
            let (m, tol, _) = fit(q, p.frequency);
            m <= tol
        })
    });
    ev.lines = peaks
        .iter()
        .map(|p| {
            // The accepted q, or the q ≤ q_max that brings this line closest (in tolerances).
            let q = accepted.unwrap_or_else(|| {
                (1..=q_max.max(1))
                    .min_by(|&a, &b| {
                        let (ma, ta, _) = fit(a, p.frequency);
                        let (mb, tb, _) = fit(b, p.frequency);
                        (ma / ta).total_cmp(&(mb / tb))
                    })
                    .unwrap_or(1)
            });
            let (mismatch, tol, h) = fit(q, p.frequency);
            let g = gcd(h, q);
            LineFit {
                frequency_hz: p.frequency,
                amplitude: p.amplitude,
                ratio: p.frequency / low,
                numerator: h / g,
                denominator: q / g,
                mismatch_hz: mismatch,
                tolerance_hz: tol,
            }
        })
        .collect();
    if let Some(q) = accepted {
        // The fundamental by least squares over all lines, f0 = Σ n f / Σ n².
        let (mut nf, mut nn) = (0.0, 0.0);
        for p in &peaks {
            let (_, _, h) = fit(q, p.frequency);
            nf += h as f64 * p.frequency;
            nn += (h * h) as f64;
        }
        let f0 = nf / nn;
        ev.fundamental_hz = Some(f0);
        ev.lowest_harmonic = Some(q);
        ev.recurrence_residual = Some(recurrence(x, fs, 1.0 / f0, variance));
    }
    ev
}

/// rms(x(t+P) − x(t)) / (√2·rms(x − mean)), x(t+P) linearly interpolated between samples.
fn recurrence(x: &[f64], fs: f64, period: f64, variance: f64) -> f64 {
    let lag = period * fs;
    let whole = lag.floor() as usize;
    let frac = lag - whole as f64;
    if whole + 1 >= x.len() || variance <= 0.0 {
        return f64::INFINITY;
    }
    let count = x.len() - whole - 1;
    let sum: f64 = (0..count)
        .map(|i| {
            let later = x[i + whole] * (1.0 - frac) + x[i + whole + 1] * frac;
            (later - x[i]).powi(2)
        })
        .sum();
    (sum / count as f64 / (2.0 * variance)).sqrt()
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a.max(1)
    } else {
        gcd(b, a % b)
    }
}

#[cfg(test)]
mod signal_tests {
    //! Textbook cases for [`classify_signal`], built from analytic signals.
    use super::*;
    use crate::analysis::poincare::poincare_section;
    use crate::analysis::series::{detrend, spectrum, Detrend};
    use crate::signal::spectrum::Window;
    use std::f64::consts::TAU;

    /// Uniform noise in [−1, 1) from a 64-bit LCG (Knuth's MMIX constants): reproducible.
    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed
            .wrapping_mul(2862933555777941757)
            .wrapping_add(3037000493);
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            })
            .collect()
    }

    /// Sum of tones (frequency Hz, amplitude, phase) at `fs` for `t` seconds.
    fn tones(fs: f64, t: f64, parts: &[(f64, f64, f64)]) -> Vec<f64> {
        let n = (fs * t).round() as usize;
        (0..n)
            .map(|i| {
                let t = i as f64 / fs;
                parts
                    .iter()
                    .map(|(f, a, p)| a * (TAU * f * t + p).sin())
                    .sum()
            })
            .collect()
    }

    fn run(x: &[f64], fs: f64) -> Classification {
        let xw = detrend(x, Detrend::Mean);
        let s = spectrum(&xw, fs, Window::Hann).unwrap();
        let section = poincare_section(&xw, None, fs).unwrap();
        classify_signal(&xw, fs, &section, &s, &ClassifyOptions::default()).unwrap()
    }

    fn add_noise(x: &mut [f64], level: f64, seed: u64) {
        let e = noise(x.len(), seed);
        for (v, e) in x.iter_mut().zip(e) {
            *v += level * e;
        }
    }

    #[test]
    fn the_12_and_110_khz_two_tone_is_periodic_with_a_half_millisecond_period() {
        // 110/12 = 55/6: f0 = 2 kHz, P = 0.5 ms. On-bin (2 MHz, 5 ms), off-bin at the
        // analysis stage's rate (4 MHz, 1.5 ms window: exactly 3 periods) and an odd rate/length.
        for (fs, t) in [(2e6, 5e-3), (4e6, 1.5e-3), (3.3e6, 3.7e-3), (1e6, 20e-3)] {
            let x = tones(fs, t, &[(12e3, 1.0, 0.3), (110e3, 0.3, 1.1)]);
            let c = run(&x, fs);
            let d = &c.diagnostics;
            assert!(matches!(c.class, Class::Periodic { .. }), "{fs} {t}: {d:?}");
            assert_eq!(d.decided_by, "spectral lines");
            let p = d.period_s.unwrap();
            assert!((p - 0.5e-3).abs() < 1e-6 * 0.5e-3, "{p}");
            let ev = d.lines.as_ref().unwrap();
            assert_eq!(ev.lowest_harmonic, Some(6));
            assert!((ev.fundamental_hz.unwrap() - 2e3).abs() < 1e-3, "{ev:?}");
            let hi = ev.lines.last().unwrap();
            assert_eq!((hi.numerator, hi.denominator), (55, 6));
            assert!(ev.recurrence_residual.unwrap() < 0.02, "{ev:?}");
            // About 2·55 extrema per period (the 110 kHz slope 0.3·110 exceeds 12): ~55 maxima.
            let Class::Periodic { period } = c.class else {
                unreachable!()
            };
            assert!((50..=60).contains(&period), "{period}");
        }
    }

    #[test]
    fn commensurate_tones_stay_periodic_under_noise() {
        // 5 % of the larger amplitude, uniform: the section test fails (1 % tolerance), the
        // lines still carry > 99 % of the variance.
        let fs = 4e6;
        for (parts, period) in [
            (vec![(12e3, 1.0, 0.3), (110e3, 0.3, 1.1)], 0.5e-3),
            (vec![(30e3, 1.0, 0.0), (50e3, 0.5, 0.7)], 0.1e-3),
            (vec![(10.7e3, 1.0, 0.0)], 1.0 / 10.7e3),
        ] {
            let mut x = tones(fs, 4e-3, &parts);
            add_noise(&mut x, 0.05, 7);
            let c = run(&x, fs);
            let d = &c.diagnostics;
            assert!(
                matches!(c.class, Class::Periodic { .. }),
                "{parts:?}: {d:?}"
            );
            let p = d.period_s.unwrap();
            assert!((p - period).abs() < 1e-4 * period, "{parts:?}: {p}");
        }
    }

    #[test]
    fn a_harmonic_rich_wave_is_periodic() {
        // Square-wave partial sum (odd harmonics 1/k up to 9) at 20 kHz: period 50 µs.
        let parts: Vec<(f64, f64, f64)> = [1.0, 3.0, 5.0, 7.0, 9.0]
            .iter()
            .map(|k| (20e3 * k, 1.0 / k, 0.0))
            .collect();
        let c = run(&tones(4e6, 2e-3, &parts), 4e6);
        assert!(
            matches!(c.class, Class::Periodic { .. }),
            "{:?}",
            c.diagnostics
        );
        assert!((c.diagnostics.period_s.unwrap() - 50e-6).abs() < 1e-5 * 50e-6);
    }

    #[test]
    fn a_period_three_orbit_shows_three_section_points() {
        // A 1/3 subharmonic: the maxima repeat every third.
        let fs = 4e6;
        let x = tones(fs, 4e-3, &[(30e3, 1.0, 0.0), (10e3, 0.4, 0.3)]);
        let c = run(&x, fs);
        assert_eq!(
            c.class,
            Class::Periodic { period: 3 },
            "{:?}",
            c.diagnostics
        );
        assert!((c.diagnostics.period_s.unwrap() - 1e-4).abs() < 1e-5 * 1e-4);
    }

    #[test]
    fn golden_ratio_tones_are_quasi_periodic_at_any_length_and_with_noise() {
        // 1 : φ: the best p/q with q ≤ 16 is 21/13, 0.26 % off — far beyond the line
        // tolerance (0.02 bin) at every record length; shorter records lower q further.
        let golden = (1.0 + 5f64.sqrt()) / 2.0;
        for (fs, t, level) in [(4e6, 2e-3, 0.0), (4e6, 20e-3, 0.0), (1e6, 50e-3, 0.05)] {
            let mut x = tones(fs, t, &[(10.7e3, 1.0, 0.0), (10.7e3 * golden, 0.3, 0.5)]);
            add_noise(&mut x, level, 3);
            let c = run(&x, fs);
            let d = &c.diagnostics;
            assert_eq!(c.class, Class::QuasiPeriodic, "{t} {level}: {d:?}");
            let ev = d.lines.as_ref().unwrap();
            assert!(ev.fundamental_hz.is_none());
            assert!((ev.lines[1].ratio - golden).abs() < 1e-4, "{ev:?}");
            assert!(ev.lines[1].mismatch_hz > ev.lines[1].tolerance_hz);
        }
    }

    #[test]
    fn a_decaying_oscillation_is_a_fixed_point() {
        // ζ = 0.02 at 110 kHz (the pitch mode's free decay), 2 ms at 4 MHz.
        let (fs, f, zeta) = (4e6, 110e3, 0.02);
        let x: Vec<f64> = (0..8000)
            .map(|i| {
                let t = i as f64 / fs;
                (-zeta * TAU * f * t).exp() * (TAU * f * t).cos()
            })
            .collect();
        let c = run(&x, fs);
        assert_eq!(c.class, Class::FixedPoint, "{:?}", c.diagnostics);
        assert_eq!(c.diagnostics.decided_by, "decay");
    }

    #[test]
    fn the_logistic_map_and_white_noise_are_irregular() {
        // x_{n+1} = 4 x_n (1 − x_n): fully chaotic, flat spectrum.
        let mut x = vec![0.3141592];
        for i in 1..20_000 {
            let p: f64 = x[i - 1];
            x.push(4.0 * p * (1.0 - p));
        }
        let c = run(&x, 1e6);
        assert_eq!(c.class, Class::Irregular, "{:?}", c.diagnostics);
        let ev = c.diagnostics.lines.as_ref().unwrap();
        assert!(ev.line_power_fraction < 0.5, "{ev:?}");
        // White noise, and white noise smoothed over 5 samples (resolved extrema).
        let raw = noise(40_000, 11);
        let smooth: Vec<f64> = raw.windows(5).map(|w| w.iter().sum()).collect();
        for x in [raw, smooth] {
            let c = run(&x, 4e6);
            assert_eq!(c.class, Class::Irregular, "{:?}", c.diagnostics);
        }
    }
}
