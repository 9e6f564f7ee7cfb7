//! Poincaré sections and phase space (docs/analysis.md).
//!
//! The section is the dissertation's "displacement values for zero velocity within the
//! half-period": Σ = {v = 0}. Between consecutive samples where the velocity changes sign
//! (exact zeros are skipped over, so a touch of zero without a sign change is no crossing), the
//! sample with the smaller |v| is refined with the 3-point parabola through x:
//! `x_e = x_j − (x_{j+1} − x_{j−1})²/(8(x_{j+1} − 2x_j + x_{j−1}))`. `v: + → −` is a maximum,
//! `− → +` a minimum: one extremum per half period, maxima and minima alternating. The return
//! map is `(x_n, x_{n+1})` of the maxima.
//!
//! The velocity should be the model's own state or the measured one (DMW); without it a
//! central difference of x is used (adequate for the smooth, well-sampled series here, noisy
//! for measured displacement).

use super::{check_rate, check_series, AnalysisError};

/// Extrema of a series at the section v = 0.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoincareSection {
    /// Times of the maxima, s from the first sample.
    pub maxima_time_s: Vec<f64>,
    /// Refined maxima, signal units.
    pub maxima: Vec<f64>,
    pub minima_time_s: Vec<f64>,
    pub minima: Vec<f64>,
}

impl PoincareSection {
    /// The Poincaré plot: successive maxima `(x_n, x_{n+1})`.
    pub fn return_map(&self) -> Vec<[f64; 2]> {
        pairs(&self.maxima)
    }
    /// The same for the minima.
    pub fn return_map_minima(&self) -> Vec<[f64; 2]> {
        pairs(&self.minima)
    }
    /// All extrema in time order as (time s, value, is_maximum).
    pub fn extrema(&self) -> Vec<(f64, f64, bool)> {
        let mut all: Vec<(f64, f64, bool)> = self
            .maxima_time_s
            .iter()
            .zip(&self.maxima)
            .map(|(&t, &x)| (t, x, true))
            .chain(
                self.minima_time_s
                    .iter()
                    .zip(&self.minima)
                    .map(|(&t, &x)| (t, x, false)),
            )
            .collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        all
    }
}

fn pairs(x: &[f64]) -> Vec<[f64; 2]> {
    x.windows(2).map(|w| [w[0], w[1]]).collect()
}

/// Velocity by central differences (one-sided at the ends), signal units per second.
pub fn velocity(x: &[f64], fs: f64) -> Vec<f64> {
    let n = x.len();
    if n < 2 {
        return vec![0.0; n];
    }
    let mut v = Vec::with_capacity(n);
    v.push((x[1] - x[0]) * fs);
    for i in 1..n - 1 {
        v.push((x[i + 1] - x[i - 1]) * 0.5 * fs);
    }
    v.push((x[n - 1] - x[n - 2]) * fs);
    v
}

fn checked_velocity<'a>(
    x: &[f64],
    v: Option<&'a [f64]>,
    fs: f64,
    what: &'static str,
) -> Result<std::borrow::Cow<'a, [f64]>, AnalysisError> {
    check_rate(fs)?;
    check_series(x, 3, what)?;
    match v {
        Some(v) => {
            if v.len() != x.len() {
                return Err(AnalysisError::LengthMismatch {
                    what,
                    left: x.len(),
                    right: v.len(),
                });
            }
            check_series(v, 3, what)?;
            Ok(std::borrow::Cow::Borrowed(v))
        }
        None => Ok(std::borrow::Cow::Owned(velocity(x, fs))),
    }
}

/// The section {v = 0} of displacement `x` sampled at `fs`, velocity `v` if known (same
/// length), otherwise central differences of `x`.
pub fn poincare_section(
    x: &[f64],
    v: Option<&[f64]>,
    fs: f64,
) -> Result<PoincareSection, AnalysisError> {
    let v = checked_velocity(x, v, fs, "Poincaré section")?;
    let n = x.len();
    let mut out = PoincareSection::default();
    let sign = |a: f64| {
        if a > 0.0 {
            1
        } else if a < 0.0 {
            -1
        } else {
            0
        }
    };
    let mut last: Option<usize> = None; // last sample with non-zero velocity
    for i in 0..n {
        let si = sign(v[i]);
        if si == 0 {
            continue;
        }
        if let Some(p) = last {
            let sp = sign(v[p]);
            if sp != si {
                // The crossing lies in p..=i; take the sample nearest to v = 0.
                let j = (p..=i)
                    .min_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))
                    .unwrap_or(i);
                let (t, xe) = refine(x, j, fs);
                if sp > 0 {
                    out.maxima_time_s.push(t);
                    out.maxima.push(xe);
                } else {
                    out.minima_time_s.push(t);
                    out.minima.push(xe);
                }
            }
        }
        last = Some(i);
    }
    Ok(out)
}

/// Vertex of the parabola through x at j−1, j, j+1 (time s, value); the raw sample at the
/// record's ends or when the vertex is not within one sample (x has no extremum there).
fn refine(x: &[f64], j: usize, fs: f64) -> (f64, f64) {
    let raw = (j as f64 / fs, x[j]);
    if j == 0 || j + 1 >= x.len() {
        return raw;
    }
    let (a, b, c) = (x[j - 1], x[j], x[j + 1]);
    let den = c - 2.0 * b + a;
    if den == 0.0 {
        return raw;
    }
    let delta = (a - c) / (2.0 * den);
    if delta.abs() > 1.0 {
        return raw;
    }
    ((j as f64 + delta) / fs, b - (c - a) * (c - a) / (8.0 * den))
}

/// A phase-space trajectory (x, v), decimated for plotting.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PhaseSpace {
    pub time_s: Vec<f64>,
    pub x: Vec<f64>,
    /// Velocity, signal units per second.
    pub v: Vec<f64>,
    /// Every `stride`-th sample was kept.
    pub stride: usize,
}

/// The trajectory (x, v) with at most `max_points` points (every `⌈N/max_points⌉`-th sample;
/// `max_points = 0` keeps all). Velocity from `v` or central differences.
pub fn phase_space(
    x: &[f64],
    v: Option<&[f64]>,
    fs: f64,
    max_points: usize,
) -> Result<PhaseSpace, AnalysisError> {
    let v = checked_velocity(x, v, fs, "phase space")?;
    let stride = if max_points == 0 {
        1
    } else {
        x.len().div_ceil(max_points).max(1)
    };
    let keep = (0..x.len()).step_by(stride);
    Ok(PhaseSpace {
        time_s: keep.clone().map(|i| i as f64 / fs).collect(),
        x: keep.clone().map(|i| x[i]).collect(),
        v: keep.map(|i| v[i]).collect(),
        stride,
    })
}
