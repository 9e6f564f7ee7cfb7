//! One series → everything the analysis stage reports (docs/analysis.md): the time
//! window, the amplitude spectrum and its peaks, the CWT scalogram with its ridge and cone of
//! influence, the Poincaré section with its classification, and the decimated phase space.
//! Pure: the stage and `hdi analyze` do the reading and writing.

use super::classify::{classify_signal, Classification, ClassifyOptions};
use super::cwt::{cwt_morlet, ridge, CwtOptions, FrequencyGrid, Ridge, Scalogram};
use super::poincare::{phase_space, poincare_section, PhaseSpace, PoincareSection};
use super::series::{detrend, spectrum, time_window, Detrend};
use super::significance::{
    scale_average, spectrum_levels, wavelet_significance, RedNoise, ScaleAverage,
    WaveletSignificance,
};
use super::AnalysisError;
use crate::signal::spectrum::{AmplitudeSpectrum, Peak, PeakOptions, Window};

/// Settings of one analysis.
#[derive(Debug, Clone)]
pub struct AnalyzeOptions {
    /// Window `[start, end)` in s on the series' own time axis (`None`: the record's ends).
    pub window: (Option<f64>, Option<f64>),
    pub detrend: Detrend,
    pub spectrum_window: Window,
    pub peaks: PeakOptions,
    pub cwt: CwtOptions,
    /// Phase-space points kept for the output (all points enter the section).
    pub phase_space_points: usize,
    pub classify: ClassifyOptions,
    pub significance: SignificanceOptions,
    /// The CWT grid from the record (replaces `cwt.frequencies`); `None`: `cwt.frequencies`.
    pub grid: Option<GridRequest>,
}

/// The CWT frequency range as asked: unset bounds and count follow the record.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GridRequest {
    pub f_min_hz: Option<f64>,
    pub f_max_hz: Option<f64>,
    pub count: Option<usize>,
}

/// The grid used and why.
#[derive(Debug, Clone, PartialEq)]
pub struct GridChoice {
    pub f_min_hz: f64,
    pub f_max_hz: f64,
    pub count: usize,
    pub reason: String,
}

/// The HDI band of the dissertation's wavelet figures (Fig. 4.12, App. B): 5 kHz–1 MHz at 100
/// log-spaced frequencies.
const HDI_BAND: (f64, f64, usize) = (5e3, 1e6, 100);

/// The grid for `n` samples at `fs`: the HDI band where the record resolves it, else
///
/// - top `min(1 MHz, fs/3)`: at fs/3 the Morlet's band (ω0 ± 3σ) ends at Nyquist;
/// - bottom `max(f_coi, min(5 kHz, f_max/200))`, `f_coi` the cone of influence at mid-record
///   (below it no sample is trusted), 200 the HDI band's span;
/// - count: the HDI band's density, 100 per log2(200) octaves (13.1 per octave), at least 16.
///
/// Bounds that are given are kept (and checked later against Nyquist).
pub fn choose_grid(
    fs: f64,
    n: usize,
    req: GridRequest,
    wavelet: &super::cwt::Wavelet,
) -> GridChoice {
    let mut why = Vec::new();
    let f_max = req.f_max_hz.unwrap_or_else(|| {
        if fs / 3.0 < HDI_BAND.1 {
            why.push(format!(
                "top fs/3 = {:.6} Hz (the Morlet band stays below Nyquist)",
                fs / 3.0
            ));
            fs / 3.0
        } else {
            HDI_BAND.1
        }
    });
    let f_min = req.f_min_hz.unwrap_or_else(|| {
        let coi = wavelet.coi_frequency((n as f64 / 2.0) / fs);
        let span = HDI_BAND.0.min(f_max * HDI_BAND.0 / HDI_BAND.1);
        if coi > span {
            why.push(format!(
                "bottom {coi:.6} Hz: the cone of influence at mid-record ({n} samples)"
            ));
            coi
        } else {
            if span < HDI_BAND.0 {
                why.push("bottom f_max/200 (the HDI band's span)".to_string());
            }
            span
        }
    });
    let count = req.count.unwrap_or_else(|| {
        let octaves = (f_max / f_min).log2().max(0.0);
        let per_octave = HDI_BAND.2 as f64 / (HDI_BAND.1 / HDI_BAND.0).log2();
        (octaves * per_octave).round().max(16.0) as usize
    });
    let given = [
        req.f_min_hz.is_some(),
        req.f_max_hz.is_some(),
        req.count.is_some(),
    ];
    let reason = if given == [true, true, true] {
        "given".to_string()
    } else if why.is_empty() {
        let g: Vec<&str> = ["f_min", "f_max", "count"]
            .iter()
            .zip(given)
            .filter(|(_, g)| *g)
            .map(|(k, _)| *k)
            .collect();
        if g.is_empty() {
            "default: the HDI band 5 kHz–1 MHz, 100 frequencies (the record resolves it)"
                .to_string()
        } else {
            format!("{} given; the rest the HDI band's", g.join(", "))
        }
    } else {
        format!("from the record: {}", why.join("; "))
    };
    GridChoice {
        f_min_hz: f_min,
        f_max_hz: f_max,
        count,
        reason,
    }
}

/// What the red-noise test reports (docs/analysis.md, "Significance").
#[derive(Debug, Clone, PartialEq)]
pub struct SignificanceOptions {
    /// Confidence level, e.g. 0.95.
    pub level: f64,
    /// Named bands (Hz) whose scale-averaged power is tested; a band with no analysed
    /// frequency is left out.
    pub bands: Vec<(String, f64, f64)>,
}

impl Default for SignificanceOptions {
    /// 95 %; the bands of the slider's response (docs/analysis.md, the validation bands): the
    /// DMW lines 3–20 kHz, the pitch/roll modes 90–120 kHz, the normal mode 200–1000 kHz.
    fn default() -> Self {
        SignificanceOptions {
            level: 0.95,
            bands: vec![
                ("dmw".into(), 3e3, 20e3),
                ("pitch_roll".into(), 90e3, 120e3),
                ("normal".into(), 200e3, 1000e3),
            ],
        }
    }
}

/// The significance of everything reported, against the window's AR(1) background.
#[derive(Debug, Clone)]
pub struct Significance {
    pub background: RedNoise,
    pub wavelet: WaveletSignificance,
    pub bands: Vec<ScaleAverage>,
    /// The amplitude level at each spectrum bin.
    pub spectrum_level: Vec<f64>,
    /// The level at each reported peak's frequency.
    pub peak_levels: Vec<f64>,
}

impl Default for AnalyzeOptions {
    /// Hann spectrum, 5 peaks above 1 % of the largest; CWT 5 kHz–1 MHz at 100 log-spaced
    /// frequencies (the default band); 20 000 phase-space points.
    fn default() -> Self {
        AnalyzeOptions {
            window: (None, None),
            detrend: Detrend::Mean,
            spectrum_window: Window::Hann,
            peaks: PeakOptions {
                max_peaks: 5,
                ..PeakOptions::default()
            },
            cwt: CwtOptions {
                frequencies: FrequencyGrid::Log {
                    f_min_hz: 5e3,
                    f_max_hz: 1e6,
                    count: 100,
                },
                ..CwtOptions::default()
            },
            phase_space_points: 20_000,
            classify: ClassifyOptions::default(),
            significance: SignificanceOptions::default(),
            grid: Some(GridRequest::default()),
        }
    }
}

/// Everything computed for one series.
#[derive(Debug, Clone)]
pub struct AnalysisReport {
    /// Time of the window's first sample on the series' axis, s.
    pub t0_s: f64,
    pub sample_rate_hz: f64,
    pub samples: usize,
    pub spectrum: AmplitudeSpectrum,
    pub peaks: Vec<Peak>,
    pub scalogram: Scalogram,
    pub ridge: Ridge,
    pub section: PoincareSection,
    /// `Err` when the section has too few maxima to judge (a short or nearly static record):
    /// the reason is reported instead of a class.
    pub classification: Result<Classification, AnalysisError>,
    pub phase_space: PhaseSpace,
    /// `Err` when the window has no background to test against (a constant series).
    pub significance: Result<Significance, AnalysisError>,
    /// The CWT grid used and why.
    pub grid: GridChoice,
}

impl AnalysisReport {
    /// Fraction of the trusted ridge samples where the scalogram is significant.
    pub fn ridge_significant_fraction(&self) -> Option<f64> {
        let sig = self.significance.as_ref().ok()?;
        let nt = self.scalogram.n_time;
        let (mut trusted, mut hit) = (0usize, 0usize);
        for n in 0..nt {
            if self.ridge.trusted[n] {
                trusted += 1;
                hit += usize::from(sig.wavelet.significant(self.ridge.index[n], n, nt));
            }
        }
        (trusted > 0).then(|| hit as f64 / trusted as f64)
    }

    /// Median ridge frequency over the samples the cone of influence trusts (Hz).
    pub fn median_trusted_ridge_hz(&self) -> Option<f64> {
        super::cwt::median_trusted(&self.ridge.frequency_hz, &self.ridge.trusted)
    }

    /// The class as text (or why there is none).
    pub fn class_label(&self) -> String {
        match &self.classification {
            Ok(c) => c.class.to_string(),
            Err(e) => format!("unclassified ({e})"),
        }
    }
}

/// Analyse `x` (and its velocity `v`, if known) sampled at `fs` with the first sample at `t0`.
pub fn analyze(
    x: &[f64],
    v: Option<&[f64]>,
    fs: f64,
    t0: f64,
    opts: &AnalyzeOptions,
) -> Result<AnalysisReport, AnalysisError> {
    if let Some(v) = v {
        if v.len() != x.len() {
            return Err(AnalysisError::LengthMismatch {
                what: "series and velocity",
                left: x.len(),
                right: v.len(),
            });
        }
    }
    let w = time_window(x.len(), fs, t0, opts.window.0, opts.window.1)?;
    // Checked before the detrend, which would spread one NaN over the whole window.
    // Sample indices in errors count from the record's start, not the window's.
    super::check_series(&x[w.clone()], 16, "analysis window").map_err(|e| match e {
        AnalysisError::NonFinite { what, index, value } => AnalysisError::NonFinite {
            what,
            index: index + w.start,
            value,
        },
        e => e,
    })?;
    let xw = detrend(&x[w.clone()], opts.detrend);
    let vw = v.map(|v| &v[w.clone()]);
    let spectrum = spectrum(&xw, fs, opts.spectrum_window)?;
    let peaks = spectrum.peaks(&opts.peaks);
    let (cwt, grid) = match opts.grid {
        Some(req) => {
            let g = choose_grid(fs, xw.len(), req, &opts.cwt.wavelet);
            let cwt = super::cwt::CwtOptions {
                frequencies: FrequencyGrid::Log {
                    f_min_hz: g.f_min_hz,
                    f_max_hz: g.f_max_hz,
                    count: g.count,
                },
                ..opts.cwt.clone()
            };
            (cwt, g)
        }
        None => {
            let f = opts.cwt.frequencies.frequencies(fs)?;
            let g = GridChoice {
                f_min_hz: f[0],
                f_max_hz: f[f.len() - 1],
                count: f.len(),
                reason: "given".into(),
            };
            (opts.cwt.clone(), g)
        }
    };
    let scalogram = cwt_morlet(&xw, fs, &cwt)?;
    let ridge = ridge(&scalogram);
    let section = poincare_section(&xw, vw, fs)?;
    let classification = classify_signal(&xw, fs, &section, &spectrum, &opts.classify);
    let phase_space = phase_space(&xw, vw, fs, opts.phase_space_points)?;
    let significance = test_significance(&xw, &spectrum, &peaks, &scalogram, &opts.significance);
    Ok(AnalysisReport {
        t0_s: t0 + w.start as f64 / fs,
        sample_rate_hz: fs,
        samples: xw.len(),
        spectrum,
        peaks,
        scalogram,
        ridge,
        section,
        classification,
        phase_space,
        significance,
        grid,
    })
}

/// Local, global and band significance of the scalogram and the spectrum's levels.
fn test_significance(
    x: &[f64],
    spectrum: &AmplitudeSpectrum,
    peaks: &[Peak],
    scalogram: &Scalogram,
    opts: &SignificanceOptions,
) -> Result<Significance, AnalysisError> {
    let background = RedNoise::estimate(x)?;
    let wavelet = wavelet_significance(scalogram, &background, opts.level)?;
    let f = &scalogram.frequencies_hz;
    let bands = opts
        .bands
        .iter()
        .filter(|(_, lo, hi)| f.iter().any(|f| f >= lo && f <= hi))
        .map(|(name, lo, hi)| scale_average(scalogram, &background, name, (*lo, *hi), opts.level))
        .collect::<Result<Vec<_>, _>>()?;
    let levels = |f: &[f64]| spectrum_levels(spectrum, x.len(), &background, f, opts.level);
    let peak_frequencies: Vec<f64> = peaks.iter().map(|p| p.frequency).collect();
    Ok(Significance {
        spectrum_level: levels(&spectrum.frequency)?,
        peak_levels: levels(&peak_frequencies)?,
        background,
        wavelet,
        bands,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::classify::Class;
    use std::f64::consts::TAU;

    #[test]
    fn a_tone_in_a_window_reads_its_line_ridge_and_class() {
        let (fs, f, a) = (4e6, 10.7e3, 1.5e-9);
        let x: Vec<f64> = (0..8000)
            .map(|i| a * (TAU * f * i as f64 / fs).sin())
            .collect();
        let v: Vec<f64> = (0..8000)
            .map(|i| a * TAU * f * (TAU * f * i as f64 / fs).cos())
            .collect();
        let r = analyze(
            &x,
            Some(&v),
            fs,
            0.0,
            &AnalyzeOptions {
                window: (Some(0.2e-3), Some(1.8e-3)),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(r.samples, 6400);
        assert!((r.t0_s - 0.2e-3).abs() < 1e-12);
        let p = &r.peaks[0];
        assert!((p.frequency - f).abs() < 0.01 * f, "{p:?}");
        assert!((p.amplitude - a).abs() < 1e-3 * a, "{p:?}");
        let ridge = r.median_trusted_ridge_hz().unwrap();
        assert!((ridge - f).abs() < 0.03 * f, "{ridge}");
        assert_eq!(
            r.classification.as_ref().unwrap().class,
            Class::Periodic { period: 1 }
        );
        assert!(r.phase_space.x.len() <= 20_000);
    }

    #[test]
    fn bad_series_are_errors() {
        let fs = 4e6;
        let mut x: Vec<f64> = (0..4000).map(|i| (i as f64 * 0.01).sin()).collect();
        let o = AnalyzeOptions::default();
        assert!(matches!(
            analyze(&x[..8], None, fs, 0.0, &o),
            Err(AnalysisError::TooShort { .. })
        ));
        x[100] = f64::NAN;
        assert!(matches!(
            analyze(&x, None, fs, 0.0, &o),
            Err(AnalysisError::NonFinite { index: 100, .. })
        ));
        let ok: Vec<f64> = (0..4000).map(|i| (i as f64 * 0.01).sin()).collect();
        assert!(matches!(
            analyze(&ok, Some(&ok[..10]), fs, 0.0, &o),
            Err(AnalysisError::LengthMismatch { .. })
        ));
        let late = AnalyzeOptions {
            window: (Some(5e-3), None),
            ..Default::default()
        };
        assert!(analyze(&ok, None, fs, 0.0, &late).is_err());
    }
}

/// The coherence of the analysed window with a second series on the same time axis.
#[derive(Debug, Clone)]
pub struct CoherenceReport {
    pub coherence: super::coherence::WaveletCoherence,
    /// Monte Carlo level of R² per row (`None`: the cone covers the row).
    pub levels: Vec<Option<f64>>,
    pub monte_carlo: super::coherence::MonteCarlo,
    /// Lag-1 autocorrelations of the series and of the against-series.
    pub alpha: (f64, f64),
    /// Per row: mean R² over the samples outside the cone (NaN: none).
    pub mean_coherence: Vec<f64>,
    /// Per row: fraction of those samples above the level.
    pub significant_fraction: Vec<f64>,
}

/// Aligns `y` (sampled at `fs_y` from `t0_y`) with the window of `r` (the report of `x`, whose
/// first sample is at `t0_x`) and computes the coherence of the window against it on the
/// report's grid, with Monte Carlo levels.
pub fn coherence_against(
    x: &[f64],
    t0_x: f64,
    r: &AnalysisReport,
    y: &[f64],
    fs_y: f64,
    t0_y: f64,
    mc: &super::coherence::MonteCarlo,
) -> Result<CoherenceReport, AnalysisError> {
    use super::coherence::{coherence_levels, wavelet_coherence};
    let fs = r.sample_rate_hz;
    if ((fs_y - fs) / fs).abs() > 1e-9 {
        return Err(AnalysisError::parameter(
            "against-series sample rate",
            format!("{fs_y} Hz"),
            format!("must equal the series' {fs} Hz (resample one of them)"),
        ));
    }
    // The window's first sample on y's axis; the grids must coincide.
    let offset = (r.t0_s - t0_y) * fs;
    let start = offset.round();
    if (offset - start).abs() > 1e-6 || start < 0.0 || start as usize + r.samples > y.len() {
        return Err(AnalysisError::parameter(
            "against-series time axis",
            format!("{} samples from {t0_y} s", y.len()),
            format!(
                "must cover the window {} s … {} s on the same sample grid",
                r.t0_s,
                r.t0_s + r.samples as f64 / fs
            ),
        ));
    }
    let start = start as usize;
    let yw = detrend(&y[start..start + r.samples], Detrend::Mean);
    let sx = ((r.t0_s - t0_x) * fs).round().max(0.0) as usize;
    let xw = &detrend(&x[sx..(sx + r.samples).min(x.len())], Detrend::Mean)[..];
    let grid = &r.scalogram.frequencies_hz;
    let opts = super::cwt::CwtOptions {
        frequencies: FrequencyGrid::Log {
            f_min_hz: grid[0],
            f_max_hz: grid[grid.len() - 1],
            count: grid.len(),
        },
        ..Default::default()
    };
    let coherence = wavelet_coherence(xw, &yw, fs, &opts)?;
    let alpha = (
        super::significance::lag1_autocorrelation(xw)?,
        super::significance::lag1_autocorrelation(&yw)?,
    );
    let levels = coherence_levels(r.samples, fs, &opts, alpha.0, alpha.1, mc)?;
    let n = r.samples;
    let (mut mean_coherence, mut significant_fraction) = (Vec::new(), Vec::new());
    for (j, level) in levels.iter().enumerate() {
        let f = coherence.frequencies_hz[j];
        let (mut sum, mut count, mut above) = (0.0, 0usize, 0usize);
        for t in 0..n {
            if f >= coherence.coi_hz[t] {
                let c = f64::from(coherence.coherence[j * n + t]);
                sum += c;
                count += 1;
                above += usize::from(level.is_some_and(|l| c > l));
            }
        }
        mean_coherence.push(if count > 0 {
            sum / count as f64
        } else {
            f64::NAN
        });
        significant_fraction.push(if count > 0 {
            above as f64 / count as f64
        } else {
            f64::NAN
        });
    }
    Ok(CoherenceReport {
        coherence,
        levels,
        monte_carlo: *mc,
        alpha,
        mean_coherence,
        significant_fraction,
    })
}
