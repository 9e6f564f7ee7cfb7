//! One series → everything the analysis stage reports (docs/analysis.md): the time
//! window, the amplitude spectrum and its peaks, the CWT scalogram with its ridge and cone of
//! influence, the Poincaré section with its classification, and the decimated phase space.
//! Pure: the stage and `hdi analyze` do the reading and writing.

use super::classify::{classify_signal, Classification, ClassifyOptions};
use super::cwt::{cwt_morlet, ridge, CwtOptions, FrequencyGrid, Ridge, Scalogram};
use super::poincare::{phase_space, poincare_section, PhaseSpace, PoincareSection};
use super::series::{detrend, spectrum, time_window, Detrend};
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
}

impl AnalysisReport {
    /// Median ridge frequency over the samples the cone of influence trusts (Hz).
    pub fn median_trusted_ridge_hz(&self) -> Option<f64> {
        let mut f: Vec<f64> = self
            .ridge
            .frequency_hz
            .iter()
            .zip(&self.ridge.trusted)
            .filter(|(_, t)| **t)
            .map(|(f, _)| *f)
            .collect();
        if f.is_empty() {
            return None;
        }
        f.sort_by(f64::total_cmp);
        Some(f[f.len() / 2])
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
    let scalogram = cwt_morlet(&xw, fs, &opts.cwt)?;
    let ridge = ridge(&scalogram);
    let section = poincare_section(&xw, vw, fs)?;
    let classification = classify_signal(&xw, fs, &section, &spectrum, &opts.classify);
    let phase_space = phase_space(&xw, vw, fs, opts.phase_space_points)?;
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
