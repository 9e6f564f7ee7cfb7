//! Preparing a series for analysis (a time window, mean or linear detrend) and its spectra:
//! the amplitude spectrum of §4.1 (thin checked wrapper over [`crate::signal::spectrum`]) and
//! a Welch power spectral density for noisy records.

use super::{check_rate, check_series, AnalysisError};
use crate::signal::rfft::RealFft;
use crate::signal::spectrum::{amplitude_spectrum, AmplitudeSpectrum, Window};
use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;
use std::ops::Range;

/// What to subtract before analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Detrend {
    /// Nothing.
    None,
    /// The mean (the spec's default).
    #[default]
    Mean,
    /// The least-squares straight line.
    Linear,
}

/// Sample range of the window `[t_start, t_end)` (s) of a series of `len` samples at `fs`
/// whose first sample is at `t0`. `None` bounds mean the record's start/end.
pub fn time_window(
    len: usize,
    fs: f64,
    t0: f64,
    t_start: Option<f64>,
    t_end: Option<f64>,
) -> Result<Range<usize>, AnalysisError> {
    check_rate(fs)?;
    let index = |t: f64, name: &'static str| -> Result<usize, AnalysisError> {
        if !t.is_finite() {
            return Err(AnalysisError::parameter(name, t, "must be finite"));
        }
        // Round so that a bound on a sample time includes that sample despite float error.
        let i = ((t - t0) * fs).round();
        Ok(i.clamp(0.0, len as f64) as usize)
    };
    let a = t_start.map_or(Ok(0), |t| index(t, "window start"))?;
    let b = t_end.map_or(Ok(len), |t| index(t, "window end"))?;
    if a >= b {
        return Err(AnalysisError::parameter(
            "time window",
            format!("{t_start:?}..{t_end:?} s"),
            format!(
                "selects no samples of a record from {t0} s to {} s",
                t0 + len as f64 / fs
            ),
        ));
    }
    Ok(a..b)
}

/// `x` with its mean or least-squares line removed.
pub fn detrend(x: &[f64], how: Detrend) -> Vec<f64> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    match how {
        Detrend::None => x.to_vec(),
        Detrend::Mean => x.iter().map(|v| v - mean).collect(),
        Detrend::Linear => {
            // Centred abscissa: slope = Σ(i−c)(x−mean)/Σ(i−c)², no cancellation.
            let c = (n as f64 - 1.0) / 2.0;
            let (mut sxy, mut sxx) = (0.0, 0.0);
            for (i, v) in x.iter().enumerate() {
                let d = i as f64 - c;
                sxy += d * (v - mean);
                sxx += d * d;
            }
            let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
            x.iter()
                .enumerate()
                .map(|(i, v)| v - mean - slope * (i as f64 - c))
                .collect()
        }
    }
}

/// One-sided amplitude spectrum (§4.1) of a checked series: a tone of amplitude A on a bin
/// reads A. The mean is removed inside; pass a [`detrend`]ed series for a linear trend.
pub fn spectrum(x: &[f64], fs: f64, window: Window) -> Result<AmplitudeSpectrum, AnalysisError> {
    check_rate(fs)?;
    check_series(x, 4, "spectrum")?;
    Ok(amplitude_spectrum(x, fs, window)?)
}

/// A one-sided power spectral density.
#[derive(Debug, Clone)]
pub struct Psd {
    /// Bin frequencies, Hz.
    pub frequency_hz: Vec<f64>,
    /// Density in signal units²/Hz.
    pub density: Vec<f64>,
    /// Number of averaged segments.
    pub segments: usize,
}

/// Welch PSD with a periodic Hann window, `segment` samples per segment and 50 % overlap,
/// each segment mean-removed — scipy `welch(x, fs, 'hann', nperseg=segment, detrend='constant',
/// scaling='density')` (mean over segments). The integral Σ density·Δf equals the variance.
pub fn welch_psd(x: &[f64], fs: f64, segment: usize) -> Result<Psd, AnalysisError> {
    check_rate(fs)?;
    if segment < 4 {
        return Err(AnalysisError::parameter(
            "Welch segment",
            segment,
            "must be at least 4 samples",
        ));
    }
    check_series(x, segment, "Welch PSD")?;
    let step = segment - segment / 2;
    let w: Vec<f64> = (0..segment)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / segment as f64).cos())
        .collect();
    let w2: f64 = w.iter().map(|v| v * v).sum();
    // Real-input FFT (signal::rfft); plan, buffers and scratch reused across segments.
    let fft = RealFft::new(&mut FftPlanner::<f64>::new(), segment);
    let mut scratch = fft.make_scratch();
    let half = segment / 2;
    let mut acc = vec![0.0; half + 1];
    let mut seg_w = vec![0.0; segment];
    let mut bins = vec![Complex64::default(); fft.spectrum_len()];
    let mut segments = 0;
    let mut start = 0;
    while start + segment <= x.len() {
        let seg = &x[start..start + segment];
        let mean = seg.iter().sum::<f64>() / segment as f64;
        for ((b, v), wi) in seg_w.iter_mut().zip(seg).zip(&w) {
            *b = (v - mean) * wi;
        }
        fft.forward_with_scratch(&seg_w, &mut bins, &mut scratch);
        for (a, b) in acc.iter_mut().zip(&bins) {
            *a += b.norm_sqr();
        }
        segments += 1;
        start += step;
    }
    let density = acc
        .iter()
        .enumerate()
        .map(|(k, a)| {
            // One-sided: double everything but DC and (even N) Nyquist.
            let one_sided = if k == 0 || (segment.is_multiple_of(2) && k == half) {
                1.0
            } else {
                2.0
            };
            one_sided * a / (segments as f64 * fs * w2)
        })
        .collect();
    Ok(Psd {
        frequency_hz: (0..=half).map(|k| k as f64 * fs / segment as f64).collect(),
        density,
        segments,
    })
}
