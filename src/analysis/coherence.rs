//! Cross-wavelet transform and wavelet coherence of two series, with Monte Carlo significance
//! from AR(1) surrogates (Grinsted, Moore & Jevrejeva 2004; Torrence & Webster 1999;
//! docs/analysis.md, "Coherence").
//!
//! With the L1 transform `W` of [`super::cwt`] (`s^{-1}|W_L2|² ∝ |W_L1|²`), the coherence is
//! `R² = |S(W_x W_y*)|² / (S(|W_x|²)·S(|W_y|²))`, the smoothing `S` a Gaussian in time of
//! standard deviation `s` (the scale, in seconds; applied in the Fourier domain) followed by a
//! boxcar of width δj0 = 0.6 octaves in scale. The phase is `arg S(W_x W_y*)`: `−2πfτ` when x
//! lags y by τ.
//!
//! The Monte Carlo draws pairs of independent AR(1) series with the two series' lag-1
//! autocorrelations, computes their coherence, and takes per scale the quantile of R² over
//! the samples outside the cone of influence (a 2000-bin histogram, interpolated within its
//! bin). It needs R² only at samples a few per period apart, so each row is evaluated at
//! every D-th sample, D the largest power of two for which the row's band and its smoothed
//! products stay un-aliased (`fs/D > (ω_c + 8.5σ + 8.5)/(2πs)`): exact, and most rows are
//! cheap. Surrogate i draws from its own seeded stream and histograms add as integers, so
//! the levels do not depend on the thread count.

use super::cwt::{
    normalization_terms, padded_spectrum, prepare, CwtOptions, Normalization, Prepared, ScaleFilter,
};
use super::significance::{RedNoise, MORLET_DJ0};
use super::{check_series, AnalysisError};
use crate::numerics::rng::Rng;
use crate::signal::rfft::RealFft;
use rayon::prelude::*;
use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::sync::Arc;

/// Histogram bins of R² ∈ [0, 1] per scale in the Monte Carlo.
const BINS: usize = 2000;
/// Cut-off of the Gaussians (e^{−36}), as in the transform.
const CUTOFF: f64 = 8.5;
/// Largest coherence field held in memory (rows × samples).
const MAX_CELLS: usize = 1 << 28;

/// Cross-wavelet power, phase and coherence of x against y.
#[derive(Debug, Clone)]
pub struct WaveletCoherence {
    pub frequencies_hz: Vec<f64>,
    pub scales_s: Vec<f64>,
    pub sample_rate_hz: f64,
    pub n_time: usize,
    pub coi_hz: Vec<f64>,
    /// `|W_x W_y*|`, row-major `[n_freq][n_time]` (x units × y units, L1).
    pub cross_magnitude: Vec<f32>,
    /// `arg S(W_x W_y*)`, rad.
    pub phase: Vec<f32>,
    /// Squared coherence R² ∈ [0, 1].
    pub coherence: Vec<f32>,
}

impl WaveletCoherence {
    pub fn row(&self, field: &[f32], j: usize) -> std::ops::Range<usize> {
        debug_assert_eq!(field.len(), self.frequencies_hz.len() * self.n_time);
        j * self.n_time..(j + 1) * self.n_time
    }
}

/// The smoothing and decimation plan shared by the data and all surrogates.
struct Engine {
    template: Prepared,
    coi: Vec<f64>,
    /// Output decimation per row (1 for the data).
    d_out: Vec<usize>,
    /// Decimation at which row j is transformed and time-smoothed: that of the highest row
    /// its scale boxcar reaches, so that every output row can read it by subsampling.
    d_comp: Vec<usize>,
    boxcar: Vec<f64>,
    /// (forward, inverse) f32 plans by length.
    plans: BTreeMap<usize, PlanPair>,
    /// Per row: the first signed bin of the wavelet's band and its gains there (the same
    /// filter as the transform's, evaluated once for all surrogates).
    filters: Vec<(i64, Vec<f64>)>,
    /// Per row: the time-smoothing Gaussian on its decimated FFT grid, with the inverse's 1/m.
    smoothers: Vec<Vec<f32>>,
}

type PlanPair = (Arc<dyn Fft<f32>>, Arc<dyn Fft<f32>>);

/// One row of a pair, time-smoothed: (smoothed W_x W_y*, smoothed |W_x|² + i|W_y|², the raw
/// W_x W_y* on the record's samples).
type SmoothedRow = (Vec<Complex32>, Vec<Complex32>, Vec<Complex32>);

/// Boxcar weights over scale rows: width δj0/δj rows, each row weighted by the overlap of
/// `[i − ½, i + ½]` with `[−w/2, w/2]` (Torrence & Webster 1999's 0.6-octave boxcar).
fn scale_boxcar(dj: f64) -> Vec<f64> {
    let w = MORLET_DJ0 / dj;
    let h = (w / 2.0 - 0.5).ceil().max(0.0) as i64;
    let weights: Vec<f64> = (-h..=h)
        .map(|i| {
            let (a, b) = (i as f64 - 0.5, i as f64 + 0.5);
            (b.min(w / 2.0) - a.max(-w / 2.0)).max(0.0)
        })
        .collect();
    let sum: f64 = weights.iter().sum();
    weights.iter().map(|v| v / sum).collect()
}

impl Engine {
    fn new(template: Prepared, decimate: bool) -> Result<Engine, AnalysisError> {
        if template.normalization != Normalization::Amplitude {
            return Err(AnalysisError::parameter(
                "normalization",
                template.normalization,
                "coherence is formed from the L1 transform",
            ));
        }
        let f = &template.frequencies;
        let nf = f.len();
        let dj = if nf >= 2 { (f[1] / f[0]).log2() } else { 1.0 };
        if nf >= 2
            && f.windows(2)
                .any(|w| ((w[1] / w[0]).log2() / dj - 1.0).abs() > 1e-6)
        {
            return Err(AnalysisError::parameter(
                "frequencies",
                "non-uniform",
                "the scale smoothing needs a log-uniform grid",
            ));
        }
        let boxcar = scale_boxcar(dj);
        let h = boxcar.len() / 2;
        let (wc, sigma) = template.wavelet.gaussian();
        let n_pad = template.n_pad;
        let d_out: Vec<usize> = template
            .scales
            .iter()
            .map(|&s| {
                if !decimate {
                    return 1;
                }
                let rate = (wc + CUTOFF * sigma + CUTOFF) / (2.0 * PI * s);
                let mut d = 1;
                while n_pad.is_multiple_of(2 * d) && template.fs / (2 * d) as f64 > rate {
                    d *= 2;
                }
                d
            })
            .collect();
        // Frequencies increase with j, so d_out does not increase: the highest row a boxcar
        // reaches has the finest decimation of its neighbourhood.
        let d_comp: Vec<usize> = (0..nf).map(|j| d_out[(j + h).min(nf - 1)]).collect();
        let mut planner = FftPlanner::<f32>::new();
        let mut plans = BTreeMap::new();
        for &d in &d_comp {
            let m = n_pad / d;
            plans
                .entry(m)
                .or_insert_with(|| (planner.plan_fft_forward(m), planner.plan_fft_inverse(m)));
        }
        let filters = template
            .scales
            .iter()
            .map(|&s| {
                let (peak, analytic, _) =
                    normalization_terms(template.normalization, &template.wavelet, s, template.fs);
                let f = ScaleFilter::new(&template.wavelet, s, template.fs, n_pad, peak, analytic);
                (f.k_lo, (f.k_lo..=f.k_hi).map(|k| f.gain(k)).collect())
            })
            .collect();
        let dw = 2.0 * PI * template.fs / n_pad as f64;
        let smoothers = (0..nf)
            .map(|j| {
                let (m, s) = (n_pad / d_comp[j], template.scales[j]);
                (0..m)
                    .map(|k| {
                        let signed = if k <= m / 2 {
                            k as f64
                        } else {
                            k as f64 - m as f64
                        };
                        let w = signed * dw * s;
                        ((-0.5 * w * w).exp() / m as f64) as f32
                    })
                    .collect()
            })
            .collect();
        Ok(Engine {
            coi: template.coi(),
            template,
            d_out,
            d_comp,
            boxcar,
            plans,
            filters,
            smoothers,
        })
    }

    /// Row j of x and y at decimation `d_comp[j]`, multiplied and time-smoothed: (smoothed
    /// cross products, smoothed |W_x|² in re and |W_y|² in im, the raw cross products).
    fn smoothed_row(&self, x: &Prepared, y: &Prepared, j: usize) -> SmoothedRow {
        let d = self.d_comp[j];
        let m = self.template.n_pad / d;
        let nv = self.template.n.div_ceil(d);
        let (fwd, inv) = &self.plans[&m];
        let zero = Complex32::new(0.0, 0.0);
        let mut scratch = vec![
            zero;
            inv.get_inplace_scratch_len()
                .max(fwd.get_inplace_scratch_len())
        ];
        let mut wx = vec![zero; m];
        let mut wy = vec![zero; m];
        // X·Ψ̂ folded onto the m-point grid (exact: the band spans fewer than m bins), for both
        // series at once.
        let (k_lo, gains) = &self.filters[j];
        for (i, g) in gains.iter().enumerate() {
            let k = k_lo + i as i64;
            let slot = k.rem_euclid(m as i64) as usize;
            let at = |spec: &[rustfft::num_complex::Complex64]| {
                let v = if k >= 0 {
                    spec[k as usize]
                } else {
                    spec[(-k) as usize].conj()
                } * *g;
                Complex32::new(v.re as f32, v.im as f32)
            };
            wx[slot] = at(&x.spectrum);
            wy[slot] = at(&y.spectrum);
        }
        inv.process_with_scratch(&mut wx, &mut scratch);
        inv.process_with_scratch(&mut wy, &mut scratch);
        let mut cross = vec![zero; m];
        let mut powers = vec![zero; m];
        // Over the whole padded span, not only the record: the products stay band-limited, so
        // the decimated smoothing is exact (cutting them at the record's ends would alias the
        // edge). Beyond the ends W is the transform of the zero padding; it reaches into the
        // record only inside the cone of influence.
        for i in 0..m {
            cross[i] = wx[i] * wy[i].conj();
            powers[i] = Complex32::new(wx[i].norm_sqr(), wy[i].norm_sqr());
        }
        let raw = cross[..nv].to_vec();
        fwd.process_with_scratch(&mut cross, &mut scratch);
        fwd.process_with_scratch(&mut powers, &mut scratch);
        // Gaussian of standard deviation s in time: exp(−ω²s²/2) in frequency.
        for ((c, p), g) in cross
            .iter_mut()
            .zip(powers.iter_mut())
            .zip(&self.smoothers[j])
        {
            *c *= *g;
            *p *= *g;
        }
        inv.process_with_scratch(&mut cross, &mut scratch);
        inv.process_with_scratch(&mut powers, &mut scratch);
        cross.truncate(nv);
        powers.truncate(nv);
        (cross, powers, raw)
    }

    /// Every row of x and y time-smoothed, in parallel.
    fn smoothed_rows(&self, x: &Prepared, y: &Prepared, parallel: bool) -> Vec<SmoothedRow> {
        let nf = self.template.frequencies.len();
        if parallel {
            (0..nf)
                .into_par_iter()
                .map(|j| self.smoothed_row(x, y, j))
                .collect()
        } else {
            (0..nf).map(|j| self.smoothed_row(x, y, j)).collect()
        }
    }

    /// Scale-smoothes output row j at its decimation: calls `emit(n, cross, sx, sy)` for each
    /// output sample n (a multiple of `d_out[j]`).
    fn output_row(
        &self,
        rows: &[SmoothedRow],
        j: usize,
        mut emit: impl FnMut(usize, Complex32, f32, f32),
    ) {
        let nf = rows.len();
        let h = self.boxcar.len() / 2;
        let d = self.d_out[j];
        for t in (0..self.template.n).step_by(d) {
            let (mut c, mut sx, mut sy) = (Complex32::new(0.0, 0.0), 0f32, 0f32);
            for (i, w) in self.boxcar.iter().enumerate() {
                let r = j as i64 + i as i64 - h as i64;
                if r < 0 || r >= nf as i64 {
                    continue;
                }
                let r = r as usize;
                let idx = t / self.d_comp[r];
                let w = *w as f32;
                c += rows[r].0[idx] * w;
                sx += rows[r].1[idx].re * w;
                sy += rows[r].1[idx].im * w;
            }
            emit(t, c, sx, sy);
        }
    }
}

fn coherence_of(c: Complex32, sx: f32, sy: f32) -> f32 {
    let den = sx * sy;
    if den > 0.0 {
        (c.norm_sqr() / den).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

fn check_pair(x: &[f64], y: &[f64]) -> Result<(), AnalysisError> {
    check_series(x, 16, "coherence: series")?;
    check_series(y, 16, "coherence: against-series")?;
    if x.len() != y.len() {
        return Err(AnalysisError::LengthMismatch {
            what: "coherence: series and against-series",
            left: x.len(),
            right: y.len(),
        });
    }
    Ok(())
}

/// Cross-wavelet transform, phase and coherence of `x` against `y` (same length and rate).
pub fn wavelet_coherence(
    x: &[f64],
    y: &[f64],
    fs: f64,
    opts: &CwtOptions,
) -> Result<WaveletCoherence, AnalysisError> {
    check_pair(x, y)?;
    let px = prepare(x, fs, opts, 0)?;
    let cells = px.frequencies.len().saturating_mul(px.n);
    if cells > MAX_CELLS {
        return Err(AnalysisError::parameter(
            "coherence size",
            format!("{} frequencies × {} samples", px.frequencies.len(), px.n),
            format!("more than {MAX_CELLS} values; use a shorter window or fewer frequencies"),
        ));
    }
    let rfft = RealFft::new(&mut FftPlanner::<f64>::new(), px.n_pad);
    let py = Prepared {
        spectrum: padded_spectrum(y, opts.keep_mean, &rfft),
        ..px.same_grid()
    };
    let engine = Engine::new(px.same_grid(), false)?;
    let rows = engine.smoothed_rows(&px, &py, true);
    let (nf, n) = (rows.len(), px.n);
    let mut out = WaveletCoherence {
        frequencies_hz: px.frequencies.clone(),
        scales_s: px.scales.clone(),
        sample_rate_hz: fs,
        n_time: n,
        coi_hz: engine.coi.clone(),
        cross_magnitude: vec![0.0; nf * n],
        phase: vec![0.0; nf * n],
        coherence: vec![0.0; nf * n],
    };
    for j in 0..nf {
        for (t, c) in rows[j].2.iter().enumerate() {
            out.cross_magnitude[j * n + t] = c.norm();
        }
        let (phase, coherence) = (&mut out.phase, &mut out.coherence);
        engine.output_row(&rows, j, |t, c, sx, sy| {
            phase[j * n + t] = c.im.atan2(c.re);
            coherence[j * n + t] = coherence_of(c, sx, sy);
        });
    }
    Ok(out)
}

/// Monte Carlo settings of the coherence significance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MonteCarlo {
    pub surrogates: usize,
    pub seed: u64,
    /// Confidence level, e.g. 0.95.
    pub level: f64,
}

impl Default for MonteCarlo {
    fn default() -> Self {
        MonteCarlo {
            surrogates: 300,
            seed: 1,
            level: 0.95,
        }
    }
}

/// An AR(1) series of unit innovations started in its stationary distribution.
fn ar1_series(rng: &mut Rng, alpha: f64, n: usize) -> Vec<f64> {
    let mut x = Vec::with_capacity(n);
    let mut v = rng.normal() / (1.0 - alpha * alpha).sqrt();
    x.push(v);
    for _ in 1..n {
        v = alpha * v + rng.normal();
        x.push(v);
    }
    x
}

/// Per-row coherence level (R² quantile at `mc.level`) of independent AR(1) pairs with lag-1
/// autocorrelations `alpha_x`, `alpha_y`, `n` samples at `fs`, on the grid of `opts`; `None`
/// for a row the cone of influence covers entirely.
pub fn coherence_levels(
    n: usize,
    fs: f64,
    opts: &CwtOptions,
    alpha_x: f64,
    alpha_y: f64,
    mc: &MonteCarlo,
) -> Result<Vec<Option<f64>>, AnalysisError> {
    RedNoise::new(alpha_x, 1.0)?;
    RedNoise::new(alpha_y, 1.0)?;
    if mc.surrogates < 20 {
        return Err(AnalysisError::parameter(
            "surrogates",
            mc.surrogates,
            "need at least 20 for a quantile",
        ));
    }
    if !(mc.level > 0.0 && mc.level < 1.0) {
        return Err(AnalysisError::parameter(
            "significance level",
            mc.level,
            "must lie strictly between 0 and 1",
        ));
    }
    if n < 16 {
        return Err(AnalysisError::TooShort {
            what: "coherence surrogates",
            len: n,
            min: 16,
            unit: "samples",
        });
    }
    let template = prepare(&vec![0.0; n], fs, opts, 0)?.same_grid();
    let rfft = RealFft::new(&mut FftPlanner::<f64>::new(), template.n_pad);
    let engine = Engine::new(template, true)?;
    let nf = engine.template.frequencies.len();
    let histogram = (0..mc.surrogates)
        .into_par_iter()
        .fold(
            || vec![0u64; nf * BINS],
            |mut hist, i| {
                let mut rng =
                    Rng::new(mc.seed ^ (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
                let xs = ar1_series(&mut rng, alpha_x, n);
                let ys = ar1_series(&mut rng, alpha_y, n);
                let px = Prepared {
                    spectrum: padded_spectrum(&xs, false, &rfft),
                    ..engine.template.same_grid()
                };
                let py = Prepared {
                    spectrum: padded_spectrum(&ys, false, &rfft),
                    ..engine.template.same_grid()
                };
                let rows = engine.smoothed_rows(&px, &py, false);
                for j in 0..nf {
                    let f = engine.template.frequencies[j];
                    let h = &mut hist[j * BINS..(j + 1) * BINS];
                    engine.output_row(&rows, j, |t, c, sx, sy| {
                        if f >= engine.coi[t] {
                            let r2 = coherence_of(c, sx, sy);
                            h[((r2 * BINS as f32) as usize).min(BINS - 1)] += 1;
                        }
                    });
                }
                hist
            },
        )
        .reduce(
            || vec![0u64; nf * BINS],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    *x += y;
                }
                a
            },
        );
    Ok((0..nf)
        .map(|j| quantile(&histogram[j * BINS..(j + 1) * BINS], mc.level))
        .collect())
}

/// The `p` quantile of a histogram over [0, 1], linear within the bin.
fn quantile(h: &[u64], p: f64) -> Option<f64> {
    let total: u64 = h.iter().sum();
    if total == 0 {
        return None;
    }
    let target = p * total as f64;
    let mut cum = 0.0;
    for (b, &c) in h.iter().enumerate() {
        let next = cum + c as f64;
        if next >= target && c > 0 {
            let frac = (target - cum) / c as f64;
            return Some((b as f64 + frac) / h.len() as f64);
        }
        cum = next;
    }
    Some(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::cwt::FrequencyGrid;

    #[test]
    fn the_boxcar_spans_point_six_octaves() {
        let w = scale_boxcar(1.0 / 12.0);
        let width = MORLET_DJ0 * 12.0;
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // Full rows carry 1/width each; the two edge rows the remainder.
        assert_eq!(w.len(), 9);
        assert!((w[4] - 1.0 / width).abs() < 1e-12);
        assert_eq!(scale_boxcar(1.0), vec![1.0]);
    }

    #[test]
    fn quantiles_interpolate_within_the_bin() {
        let mut h = vec![0u64; 10];
        h[3] = 50;
        h[7] = 50;
        assert!((quantile(&h, 0.25).unwrap() - 0.35).abs() < 1e-12);
        assert!((quantile(&h, 0.95).unwrap() - 0.79).abs() < 1e-12);
        assert_eq!(quantile(&[0, 0], 0.5), None);
    }

    pub(super) fn opts(f_min: f64, f_max: f64, count: usize) -> CwtOptions {
        CwtOptions {
            frequencies: FrequencyGrid::Log {
                f_min_hz: f_min,
                f_max_hz: f_max,
                count,
            },
            ..Default::default()
        }
    }

    #[test]
    fn decimated_rows_equal_the_full_rate_rows() {
        // The Monte Carlo's decimated evaluation is exact: compare its R² with the data path.
        let (fs, n) = (1e6, 4096);
        let mut rng = Rng::new(7);
        let x = ar1_series(&mut rng, 0.6, n);
        let y = ar1_series(&mut rng, 0.3, n);
        let o = opts(2e3, 2e5, 40);
        let full = wavelet_coherence(&x, &y, fs, &o).unwrap();
        let px = prepare(&x, fs, &o, 0).unwrap();
        let rfft = RealFft::new(&mut FftPlanner::<f64>::new(), px.n_pad);
        let py = Prepared {
            spectrum: padded_spectrum(&y, false, &rfft),
            ..px.same_grid()
        };
        let engine = Engine::new(px.same_grid(), true).unwrap();
        assert!(engine.d_out[0] > 1, "{:?}", engine.d_out);
        let rows = engine.smoothed_rows(&px, &py, false);
        let mut worst = 0f32;
        for j in 0..rows.len() {
            engine.output_row(&rows, j, |t, c, sx, sy| {
                let r = coherence_of(c, sx, sy);
                worst = worst.max((r - full.coherence[j * n + t]).abs());
            });
        }
        assert!(worst < 1e-5, "{worst}");
    }
}

#[cfg(test)]
mod behaviour {
    //! The checks that can fail: a lagged copy is coherent with the lag's phase,
    //! independent noises stay below the Monte Carlo level.
    use super::tests::opts as grid;
    use super::*;

    #[test]
    fn a_lagged_copy_is_coherent_with_the_phase_of_its_lag() {
        let (fs, n, lag) = (1e6, 8192, 2usize);
        let mut rng = Rng::new(3);
        // White: the scale boxcar then weights its rows nearly evenly (a red spectrum would pull
        // the smoothed phase towards the lower rows' smaller lag phase).
        let base = ar1_series(&mut rng, 0.0, n + lag);
        let x = &base[..n]; // x(t) = base(t)
        let y = &base[lag..]; // y(t) = base(t + lag): y leads, x lags by `lag` samples
        let c = wavelet_coherence(x, y, fs, &grid(5e3, 3e4, 24)).unwrap();
        let tau = lag as f64 / fs;
        let h = scale_boxcar((c.frequencies_hz[1] / c.frequencies_hz[0]).log2()).len() / 2;
        let (mut checked, mut sum, mut ratio, mut ratios) = (0, 0.0, 0.0, 0);
        for j in 0..c.frequencies_hz.len() {
            let f = c.frequencies_hz[j];
            for t in (0..n).step_by(97) {
                // The time smoothing (σ = s) reaches past the cone's e-folding time √2·s:
                // two e-folding times from the edges the copies' differing ends do not show.
                if f < 2.0 * c.coi_hz[t] {
                    continue;
                }
                let r2 = c.coherence[j * n + t];
                // 1 − O((τ/s)²): the lag turns the band's spread of frequencies into a spread of
                // phases inside the smoothing window.
                assert!(r2 > 0.99, "R² {r2} at {f} Hz, sample {t}");
                sum += f64::from(r2);
                // x lags y by τ: arg(W_x W_y*) = −2πfτ (wrapped). The scale boxcar averages
                // the phase over ±0.3 octave, weighted by the rows' power (∝ f for white noise
                // in L1: +2.2 %); the outer 0.3 octave of the grid sees a one-sided boxcar, so
                // it is left out.
                if j < h || j + h >= c.frequencies_hz.len() {
                    continue;
                }
                // One realisation's local power-weighted frequency wanders around the row's by
                // several per cent; the mean over the record is checked tighter below.
                let want = -2.0 * PI * f * tau;
                let got = f64::from(c.phase[j * n + t]);
                let d = (got - want + PI).rem_euclid(2.0 * PI) - PI;
                assert!(
                    d.abs() < 0.005 + 0.3 * want.abs(),
                    "phase {got} vs {want} at {f} Hz"
                );
                if want.abs() < 2.5 {
                    ratio += (want + d) / want;
                    ratios += 1;
                }
                checked += 1;
            }
        }
        assert!(checked > 300, "{checked}");
        let ratio = ratio / ratios as f64;
        assert!(
            (0.99..1.06).contains(&ratio),
            "mean phase / −2πfτ = {ratio}"
        );
        assert!(sum / checked as f64 > 0.998, "{}", sum / checked as f64);
    }

    #[test]
    fn independent_noises_stay_below_the_level() {
        let (fs, n) = (1e6, 4096);
        let o = grid(5e3, 2e5, 24);
        let mut rng = Rng::new(11);
        let x = ar1_series(&mut rng, 0.7, n);
        let y = ar1_series(&mut rng, 0.2, n);
        let (ax, ay) = (
            super::super::significance::lag1_autocorrelation(&x).unwrap(),
            super::super::significance::lag1_autocorrelation(&y).unwrap(),
        );
        let mc = MonteCarlo {
            surrogates: 60,
            ..MonteCarlo::default()
        };
        let levels = coherence_levels(n, fs, &o, ax, ay, &mc).unwrap();
        let c = wavelet_coherence(&x, &y, fs, &o).unwrap();
        let (mut above, mut outside) = (0usize, 0usize);
        for (j, level) in levels.iter().enumerate() {
            let level = level.expect("rows outside the cone") as f32;
            assert!(level > 0.3 && level < 1.0, "{level}");
            for t in 0..n {
                if c.frequencies_hz[j] >= c.coi_hz[t] {
                    outside += 1;
                    above += usize::from(c.coherence[j * n + t] > level);
                }
            }
        }
        // At the 95 % level about 5 % of the cells of one realisation exceed it; neighbours are
        // correlated, so allow for it — but not for a coherent pair.
        let fraction = above as f64 / outside as f64;
        assert!(fraction < 0.15, "{fraction}");
        // Determinism: the same seed gives the same levels on any thread count.
        let again = coherence_levels(n, fs, &o, ax, ay, &mc).unwrap();
        assert_eq!(levels, again);
    }
}
