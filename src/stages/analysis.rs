//! Analysis stage (Appendix B; docs/analysis.md): any time series of an upstream
//! stage's HDF5 (a slider case's heave, a DMW or excitation track, …) within a time window →
//! amplitude spectrum and peaks, CWT scalogram with ridge and cone of influence, Poincaré
//! section with a periodicity class, phase space. `hdi analyze FILE` runs the same on any file.

use super::{FromConfig, Output, StageContext, StageKind};
use crate::analysis::coherence::MonteCarlo;
use crate::analysis::report::{
    analyze, coherence_against, AnalysisReport, AnalyzeOptions, CoherenceReport, GridRequest,
    Significance, SignificanceOptions,
};
pub use crate::artefacts::analysis::amplitude_key;
use crate::artefacts::analysis::{
    display_unit, Amplitudes, AnalysedSeries, AnalysisResult, AnalysisRow, AnalysisSummary,
    BandCoherence, BandSignificance, CoherenceSummary, Evidence, FrequencyGridUsed, PeakColumns,
    PeriodicityClass, SectionStatistics, SignificanceSummary, SpectralLine, SpectralLines,
    SpectralPeak, FILE as ANALYSIS_FILE,
};
use crate::artefacts::cases as case_files;
use crate::artefacts::dmw_tracks;
use crate::artefacts::finite;
pub use crate::artefacts::series::{read_any_series, read_series, Series, DEFAULT_SERIES};
use crate::core::config::{ConfigError, PipelineFile};
use crate::core::store::H5Out;
use crate::error::{Error, Result};
use crate::slider::params::{SimulateConfig, SimulateParams};
use crate::slider::three_dof_params::{ThreeDofConfig, ThreeDofParams};
use crate::units::{Frequency, Length, TimeSpan};
use serde::Deserialize;
use serde_json::{json, Value};
use std::path::Path;

/// 2: periodicity from the spectral lines too (issue 19), JSON evidence instead of a debug
/// string, any HDF5 time axis. 3: real-input FFTs and the scalogram's inverse transforms in f32
/// (issue 20): |W| and spectra change in their last digits. 4: red-noise significance, the
/// grid from the record, coherence against a second series (issue 34).
pub const MODEL_VERSION: &str = "analysis-4";

fn default_peaks() -> usize {
    5
}

/// `[analysis.NAME]` as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AnalysisConfig {
    /// The stage instance whose output holds the series.
    pub source: String,
    /// File inside the source's outputs (default: `dmw.h5` for DMW/excitation sources, the
    /// case at `actuation` for simulate sources).
    #[serde(default)]
    pub file: Option<String>,
    /// Simulate sources: the case to analyse (default: the only one).
    #[serde(default)]
    pub actuation: Option<Length>,
    /// Dataset path (default: `case/history/heave` or `dmw/tracks/D1`).
    #[serde(default)]
    pub dataset: Option<String>,
    /// Velocity dataset for the Poincaré section and phase space (default: the model's or the
    /// LDV's own velocity; `"none"`: central differences).
    #[serde(default)]
    pub velocity: Option<String>,
    /// `[start, end]` on the series' time axis (default: the whole record).
    #[serde(default)]
    pub window: Option<[TimeSpan; 2]>,
    /// CWT range (default: from the record, `analysis::report::choose_grid`).
    #[serde(default)]
    pub f_min: Option<Frequency>,
    #[serde(default)]
    pub f_max: Option<Frequency>,
    /// Log-spaced CWT frequencies between f_min and f_max (default: from the range).
    #[serde(default)]
    pub frequencies: Option<usize>,
    /// Spectral peaks reported.
    #[serde(default = "default_peaks")]
    pub peaks: usize,
    /// Ignore spectral peaks below this frequency (e.g. a sweep's slow settling).
    #[serde(default)]
    pub min_peak_frequency: Option<Frequency>,
    /// A second series for wavelet coherence: the instance that holds it (e.g. the DMW the
    /// slider flew over), on the same time axis.
    #[serde(default)]
    pub against: Option<String>,
    /// Its file and dataset (default for a DMW/excitation instance: dmw.h5, dmw/tracks/D1).
    #[serde(default)]
    pub against_file: Option<String>,
    #[serde(default)]
    pub against_dataset: Option<String>,
    /// AR(1) surrogate pairs of the coherence Monte Carlo (default 300).
    #[serde(default)]
    pub surrogates: Option<usize>,
    /// Their seed (default 1).
    #[serde(default)]
    pub seed: Option<u64>,
}

/// The second series of a coherence analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct AgainstSpec {
    pub source: String,
    pub file: String,
    pub dataset: String,
    pub surrogates: usize,
    pub seed: u64,
}

/// Where the series is and how to analyse it.
#[derive(Debug, Clone, PartialEq)]
pub struct SeriesSpec {
    pub file: String,
    pub dataset: String,
    /// `None`: central differences.
    pub velocity: Option<String>,
}

/// The settings that are plain numbers (shared with `hdi analyze`).
#[derive(Debug, Clone, PartialEq)]
pub struct AnalysisSettings {
    pub window: (Option<f64>, Option<f64>),
    pub f_min: Option<f64>,
    pub f_max: Option<f64>,
    pub frequencies: Option<usize>,
    pub peaks: usize,
    pub min_peak_frequency: f64,
}

impl AnalysisSettings {
    pub fn check(&self) -> std::result::Result<(), crate::core::config::KeyError> {
        let bad = |k: &str, m: String| Err(crate::core::config::KeyError::new(k, m));
        for (key, f) in [("f_min", self.f_min), ("f_max", self.f_max)] {
            if let Some(f) = f {
                if !(f.is_finite() && f > 0.0) {
                    return bad(key, format!("need a finite frequency > 0 (got {f} Hz)"));
                }
            }
        }
        if let (Some(lo), Some(hi)) = (self.f_min, self.f_max) {
            if hi <= lo {
                return bad("f_min", format!("need f_min < f_max (got {lo} … {hi} Hz)"));
            }
        }
        if let Some(n) = self.frequencies {
            if !(2..=2000).contains(&n) {
                return bad("frequencies", format!("{n} is out of range: 2 … 2000"));
            }
        }
        if !(1..=100).contains(&self.peaks) {
            return bad("peaks", format!("{} is out of range: 1 … 100", self.peaks));
        }
        if let (Some(a), Some(b)) = self.window {
            if !(a.is_finite() && b.is_finite() && b > a && a >= 0.0) {
                return bad("window", format!("need 0 ≤ start < end (got {a} … {b} s)"));
            }
        }
        Ok(())
    }

    pub fn options(&self) -> AnalyzeOptions {
        let mut o = AnalyzeOptions {
            window: self.window,
            ..AnalyzeOptions::default()
        };
        o.grid = Some(GridRequest {
            f_min_hz: self.f_min,
            f_max_hz: self.f_max,
            count: self.frequencies,
        });
        o.peaks.max_peaks = self.peaks;
        o.peaks.min_frequency = self.min_peak_frequency;
        o
    }
}

/// Six significant digits for the summary table; the HDF5 keeps full precision.
fn sig6(x: f64) -> f64 {
    crate::core::store::round_significant(x, 6)
}

/// The periodicity class of a report, as `summary.class` states it (the period is a separate
/// key).
pub fn class_name(r: &AnalysisReport) -> PeriodicityClass {
    use crate::analysis::classify::Class;
    match &r.classification {
        Ok(c) => match c.class {
            Class::FixedPoint => PeriodicityClass::FixedPoint,
            Class::Periodic { .. } => PeriodicityClass::Periodic,
            Class::QuasiPeriodic => PeriodicityClass::QuasiPeriodic,
            Class::Irregular => PeriodicityClass::Irregular,
        },
        Err(_) => PeriodicityClass::Unclassified,
    }
}

/// The evidence behind the class (docs/analysis.md; `docs/schemas/analyze.json`).
fn evidence(c: &crate::analysis::classify::Classification, unit: &str) -> Evidence {
    let d = &c.diagnostics;
    let section = SectionStatistics {
        amplitude: Amplitudes::new(unit, d.amplitude),
        maxima: d.n_maxima,
        spread: finite(d.spread),
        final_to_initial: finite(d.final_to_initial),
        decay_ratio: finite(d.decay_ratio),
        decreasing_fraction: finite(d.decreasing_fraction),
        best_period_sections: d.best_period,
        period_residual: finite(d.period_residual),
        distinct_values: d.distinct_values,
        distinct_fraction: finite(d.distinct_fraction),
        ring_coverage: finite(d.coverage),
        ring_hole: finite(d.hole),
        neighbour_cosine: finite(d.neighbour_cosine),
    };
    let spectral_lines = d.lines.as_ref().map(|e| SpectralLines {
        line_power_fraction: finite(e.line_power_fraction),
        fundamental_hz: e.fundamental_hz,
        lowest_harmonic: e.lowest_harmonic,
        max_denominator: e.max_denominator,
        recurrence_residual: e.recurrence_residual,
        resolution_hz: e.resolution_hz,
        lines: e
            .lines
            .iter()
            .map(|l| SpectralLine {
                amplitude: Amplitudes::new(unit, l.amplitude),
                frequency_hz: l.frequency_hz,
                ratio: l.ratio,
                numerator: l.numerator,
                denominator: l.denominator,
                mismatch_hz: l.mismatch_hz,
                tolerance_hz: l.tolerance_hz,
            })
            .collect(),
    });
    Evidence {
        decided_by: d.decided_by.to_string(),
        section,
        spectral_lines,
    }
}

/// The summary of a report (`--json`, `result.json`); keys carry their units
/// (docs/schemas/analyze.json).
pub fn summary(r: &AnalysisReport, unit: &str) -> AnalysisSummary {
    use crate::analysis::classify::Class;
    let c = r.classification.as_ref().ok();
    let period_sections = c.and_then(|c| match c.class {
        Class::Periodic { period } => Some(period),
        _ => None,
    });
    let sig = r.significance.as_ref().ok();
    AnalysisSummary {
        window_s: [r.t0_s, r.t0_s + r.samples as f64 / r.sample_rate_hz],
        samples: r.samples,
        sample_rate_hz: r.sample_rate_hz,
        unit: unit.to_string(),
        peaks: r
            .peaks
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let ratio = sig.map(|s| p.amplitude / s.peak_levels[i]);
                SpectralPeak {
                    amplitude: Amplitudes::new(unit, p.amplitude),
                    frequency_hz: p.frequency,
                    significant: ratio.map(|q| q > 1.0),
                    amplitude_to_level: ratio.map(sig6),
                }
            })
            .collect(),
        ridge_median_hz: r.median_trusted_ridge_hz(),
        class: class_name(r),
        period_sections,
        period_s: c.and_then(|c| c.diagnostics.period_s),
        unclassified_reason: r.classification.as_ref().err().map(|e| e.to_string()),
        poincare_maxima: r.section.maxima.len(),
        evidence: c.map(|c| evidence(c, unit)),
        ridge_significant_fraction: r.ridge_significant_fraction().map(sig6),
        frequency_grid: Some(FrequencyGridUsed {
            f_min_hz: r.grid.f_min_hz,
            f_max_hz: r.grid.f_max_hz,
            count: r.grid.count,
            reason: r.grid.reason.clone(),
        }),
        significance: sig.map(|s| significance_summary(r, s)),
        significance_unavailable: r.significance.as_ref().err().map(|e| e.to_string()),
        coherence: None,
    }
}

/// The JSON view of a coherence analysis: per stated band the mean R², the fraction above the
/// Monte Carlo level and the circular-mean phase, outside the cone of influence.
pub fn coherence_summary(c: &CoherenceReport, against: &str) -> CoherenceSummary {
    let wc = &c.coherence;
    let n = wc.n_time;
    let bands = SignificanceOptions::default()
        .bands
        .iter()
        .filter_map(|(name, lo, hi)| {
            let rows: Vec<usize> = (0..wc.frequencies_hz.len())
                .filter(|&j| wc.frequencies_hz[j] >= *lo && wc.frequencies_hz[j] <= *hi)
                .collect();
            if rows.is_empty() {
                return None;
            }
            let (mut sum, mut count, mut above, mut re, mut im) = (0.0, 0usize, 0usize, 0.0, 0.0);
            for &j in &rows {
                let f = wc.frequencies_hz[j];
                for t in 0..n {
                    if f >= wc.coi_hz[t] {
                        let r2 = f64::from(wc.coherence[j * n + t]);
                        sum += r2;
                        count += 1;
                        above += usize::from(c.levels[j].is_some_and(|l| r2 > l));
                        let ph = f64::from(wc.phase[j * n + t]);
                        re += ph.cos();
                        im += ph.sin();
                    }
                }
            }
            let some = count > 0;
            Some(BandCoherence {
                name: name.clone(),
                band_hz: [*lo, *hi],
                mean_coherence: some.then(|| sig6(sum / count as f64)),
                significant_fraction: some.then(|| sig6(above as f64 / count as f64)),
                phase_rad: some.then(|| sig6(im.atan2(re))),
            })
        })
        .collect();
    CoherenceSummary {
        against: against.to_string(),
        surrogates: c.monte_carlo.surrogates,
        seed: c.monte_carlo.seed,
        level: c.monte_carlo.level,
        lag1_autocorrelation: [sig6(c.alpha.0), sig6(c.alpha.1)],
        bands,
    }
}

/// `analysis/coherence` (R², phase, cross-wavelet power, the Monte Carlo level per row) and
/// `coherence.png` (R² with the significant region outlined, the mean R² beside it).
fn write_coherence(
    out: &H5Out,
    dir: &Path,
    label: &str,
    r: &AnalysisReport,
    c: &CoherenceReport,
    against: &str,
) -> Result<()> {
    let wc = &c.coherence;
    let (nf, n) = (wc.frequencies_hz.len(), wc.n_time);
    let g = out.group("analysis/coherence", Some("NXdata"))?;
    out.attr_str(&g, "signal", "coherence")?;
    out.attr_str_list(&g, "axes", &["frequency", "time"])?;
    out.attr_str(&g, "against", against)?;
    out.attr_f64(&g, "level", c.monte_carlo.level)?;
    out.attr_f64(&g, "surrogates", c.monte_carlo.surrogates as f64)?;
    out.attr_f64(&g, "seed", c.monte_carlo.seed as f64)?;
    let shape = |what: &'static str, v: &[f32]| {
        ndarray::ArrayView2::from_shape((nf, n), v)
            .map(|a| a.to_owned())
            .map_err(|source| Error::Shape { what, source })
    };
    out.write_array(
        &g,
        "coherence",
        shape("coherence", &wc.coherence)?.view(),
        "1",
        "squared wavelet coherence R^2 (Grinsted et al. 2004)",
    )?;
    out.write_array(
        &g,
        "phase",
        shape("phase", &wc.phase)?.view(),
        "rad",
        "arg S(W_x W_y*): negative when the series lags the against-series",
    )?;
    out.write_array(
        &g,
        "cross_magnitude",
        shape("cross", &wc.cross_magnitude)?.view(),
        "1",
        "|W_x W_y*| (L1, product of the two series' units)",
    )?;
    let levels: Vec<f64> = c.levels.iter().map(|l| l.unwrap_or(f64::NAN)).collect();
    out.write_1d(
        &g,
        "level",
        &levels,
        "1",
        "Monte Carlo level of R^2 (AR(1) surrogates)",
    )?;
    out.write_1d(&g, "frequency", &wc.frequencies_hz, "Hz", "frequency")?;
    out.write_1d(&g, "time", &shifted(r, &r.scalogram.time_s()), "s", "time")?;
    let mask: Vec<bool> = (0..nf * n)
        .map(|i| c.levels[i / n].is_some_and(|l| f64::from(wc.coherence[i]) > l))
        .collect();
    crate::figures::scalogram_significance_png(
        &dir.join("coherence.png"),
        &format!("Wavelet coherence — {label} vs {against}"),
        &shifted(r, &r.scalogram.time_s()),
        &wc.frequencies_hz,
        &wc.coherence,
        &wc.coi_hz,
        None,
        "R²",
        &crate::figures::SignificanceOverlay {
            mask: &mask,
            global: &c.mean_coherence,
            global_level: &levels,
            power_unit: "R²",
            level: c.monte_carlo.level,
        },
    )?;
    Ok(())
}

/// The JSON view of the red-noise tests.
fn significance_summary(r: &AnalysisReport, s: &Significance) -> SignificanceSummary {
    let w = &s.wavelet;
    let f = &r.scalogram.frequencies_hz;
    let excess: Vec<Option<f64>> = w
        .global_power
        .iter()
        .zip(&w.global_level)
        .map(|(p, l)| Some((*p)? / (*l)?))
        .collect();
    let global_significant_peaks_hz = (0..f.len())
        .filter(|&j| {
            let e = |k: usize| excess[k].unwrap_or(0.0);
            excess[j].is_some_and(|x| x > 1.0)
                && (j == 0 || e(j) >= e(j - 1))
                && (j + 1 == f.len() || e(j) >= e(j + 1))
        })
        .map(|j| sig6(f[j]))
        .collect();
    SignificanceSummary {
        level: w.level,
        background: "AR(1)".into(),
        lag1_autocorrelation: sig6(s.background.alpha),
        significant_area_fraction: sig6(w.significant_fraction),
        global_significant_peaks_hz,
        bands: s
            .bands
            .iter()
            .map(|b| BandSignificance {
                name: b.name.clone(),
                band_hz: [b.band_hz.0, b.band_hz.1],
                frequencies: b.rows.1 - b.rows.0 + 1,
                mean_power_to_level: b.mean_power.map(|m| sig6(m / b.level_power)),
                significant_fraction: b.significant_fraction.map(sig6),
                dof: sig6(b.dof),
            })
            .collect(),
    }
}

/// The instance's summary-table row: six significant digits, the three strongest lines.
fn summary_row(source: &str, dataset: &str, r: &AnalysisReport, unit: &str) -> AnalysisRow {
    let (du, k) = display_unit(unit);
    AnalysisRow {
        source: source.to_string(),
        dataset: dataset.to_string(),
        window_start_ms: sig6(r.t0_s * 1e3),
        window_end_ms: sig6((r.t0_s + r.samples as f64 / r.sample_rate_hz) * 1e3),
        peaks: PeakColumns {
            unit: du.to_string(),
            peaks: r
                .peaks
                .iter()
                .take(3)
                .map(|p| (sig6(p.frequency / 1e3), sig6(p.amplitude * k)))
                .collect(),
        },
        ridge_median_khz: r.median_trusted_ridge_hz().map(|f| sig6(f / 1e3)),
        class: r.class_label(),
        poincare_maxima: r.section.maxima.len(),
    }
}

/// Write `analysis.h5` and the four PNGs into `dir`; `label` titles the plots.
pub fn write_outputs(
    dir: &Path,
    key: &str,
    label: &str,
    source: &Value,
    r: &AnalysisReport,
    s: &Series,
    coherence: Option<(&CoherenceReport, &str)>,
) -> Result<()> {
    let out = H5Out::create(&dir.join(ANALYSIS_FILE))?;
    out.root_attributes(
        "analysis",
        key,
        source,
        &Value::Object(Default::default()),
        "analysis",
    )?;
    let entry = out.group("analysis", Some("NXentry"))?;
    out.attr_str(&entry, "default", "spectrum")?;
    out.attr_str(&entry, "class", &r.class_label())?;
    write_spectrum(&out, r, s)?;
    write_scalogram(&out, r, s)?;
    if let Ok(sig) = &r.significance {
        write_significance(&out, r, sig, s)?;
    }
    write_poincare(&out, r, s)?;
    write_phase_space(&out, r, s)?;
    if let Some((c, against)) = coherence {
        write_coherence(&out, dir, label, r, c, against)?;
    }
    out.finish()?;
    write_figures(dir, label, r, s)
}

/// Stored time values shifted to the window start (the report's times start at 0).
fn shifted(r: &AnalysisReport, t: &[f64]) -> Vec<f64> {
    t.iter().map(|t| t + r.t0_s).collect()
}

/// `analysis/spectrum`: amplitude spectrum and refined peaks.
fn write_spectrum(out: &H5Out, r: &AnalysisReport, s: &Series) -> Result<()> {
    let g = out.group("analysis/spectrum", Some("NXdata"))?;
    out.attr_str(&g, "signal", "amplitude")?;
    out.attr_str_list(&g, "axes", &["frequency"])?;
    out.write_1d(&g, "frequency", &r.spectrum.frequency, "Hz", "frequency")?;
    out.write_1d(
        &g,
        "amplitude",
        &r.spectrum.amplitude,
        &s.unit,
        "one-sided amplitude (Hann; a tone of amplitude A reads A)",
    )?;
    let pf: Vec<f64> = r.peaks.iter().map(|p| p.frequency).collect();
    let pa: Vec<f64> = r.peaks.iter().map(|p| p.amplitude).collect();
    out.write_1d(&g, "peak_frequency", &pf, "Hz", "refined peak frequency")?;
    out.write_1d(&g, "peak_amplitude", &pa, &s.unit, "refined peak amplitude")?;
    Ok(())
}

/// `analysis/scalogram`: CWT magnitude, cone of influence and ridge.
fn write_scalogram(out: &H5Out, r: &AnalysisReport, s: &Series) -> Result<()> {
    let sc = &r.scalogram;
    let g = out.group("analysis/scalogram", Some("NXdata"))?;
    out.attr_str(&g, "signal", "magnitude")?;
    out.attr_str_list(&g, "axes", &["frequency", "time"])?;
    out.attr_str(&g, "wavelet", &sc.wavelet.to_string())?;
    out.attr_str(&g, "normalization", &sc.normalization.to_string())?;
    let nf = sc.frequencies_hz.len();
    let mag =
        ndarray::ArrayView2::from_shape((nf, sc.n_time), &sc.magnitude).map_err(|source| {
            Error::Shape {
                what: "scalogram",
                source,
            }
        })?;
    out.write_array(
        &g,
        "magnitude",
        mag,
        &s.unit,
        "|W| (L1: a tone of amplitude A reads A)",
    )?;
    out.write_1d(&g, "frequency", &sc.frequencies_hz, "Hz", "frequency")?;
    out.write_1d(&g, "time", &shifted(r, &sc.time_s()), "s", "time")?;
    out.write_1d(
        &g,
        "coi_frequency",
        &sc.coi_hz,
        "Hz",
        "cone of influence: lowest trusted frequency",
    )?;
    out.write_1d(
        &g,
        "ridge_frequency",
        &r.ridge.frequency_hz,
        "Hz",
        "ridge (dominant frequency)",
    )?;
    Ok(())
}

/// `analysis/significance`: the AR(1) background, the local and global levels, the mask and
/// the scale-averaged power of the bands; `analysis/spectrum/significance_level` beside the
/// spectrum.
fn write_significance(
    out: &H5Out,
    r: &AnalysisReport,
    sig: &Significance,
    s: &Series,
) -> Result<()> {
    let spec = out.group("analysis/spectrum", None)?;
    out.write_1d(
        &spec,
        "significance_level",
        &sig.spectrum_level,
        &s.unit,
        "red-noise amplitude level at the confidence `level` of analysis/significance",
    )?;
    let w = &sig.wavelet;
    let g = out.group("analysis/significance", Some("NXdata"))?;
    out.attr_str(&g, "signal", "mask")?;
    out.attr_str_list(&g, "axes", &["frequency", "time"])?;
    out.attr_f64(&g, "level", w.level)?;
    out.attr_str(&g, "background", "AR(1), Torrence & Compo (1998) eq. 16")?;
    out.attr_f64(&g, "lag1_autocorrelation", sig.background.alpha)?;
    out.attr_f64(&g, "variance", sig.background.variance)?;
    let power_unit = if s.unit == "1" {
        "1".to_string()
    } else {
        format!("({})^2", s.unit)
    };
    let sc = &r.scalogram;
    let nf = sc.frequencies_hz.len();
    let mask: Vec<u8> = w.mask.iter().map(|m| u8::from(*m)).collect();
    let mask =
        ndarray::ArrayView2::from_shape((nf, sc.n_time), &mask).map_err(|source| Error::Shape {
            what: "significance mask",
            source,
        })?;
    out.write_array(
        &g,
        "mask",
        mask,
        "1",
        "1 where |W|^2 exceeds the local level (T&C eq. 18)",
    )?;
    out.write_1d(&g, "frequency", &sc.frequencies_hz, "Hz", "frequency")?;
    out.write_1d(&g, "time", &shifted(r, &sc.time_s()), "s", "time")?;
    out.write_1d(
        &g,
        "fourier_frequency",
        &w.fourier_frequency_hz,
        "Hz",
        "T&C Fourier frequency of each scale",
    )?;
    out.write_1d(
        &g,
        "background_power",
        &w.background_power,
        &power_unit,
        "expected |W|^2 of the AR(1) background (L1)",
    )?;
    out.write_1d(
        &g,
        "local_level",
        &w.local_level,
        &power_unit,
        "local level of |W|^2",
    )?;
    let nan = |v: &[Option<f64>]| -> Vec<f64> { v.iter().map(|x| x.unwrap_or(f64::NAN)).collect() };
    out.write_1d(
        &g,
        "global_power",
        &nan(&w.global_power),
        &power_unit,
        "global wavelet spectrum: mean |W|^2 outside the cone of influence (NaN: none)",
    )?;
    out.write_1d(
        &g,
        "global_level",
        &nan(&w.global_level),
        &power_unit,
        "level of the global spectrum (T&C eq. 23)",
    )?;
    out.write_1d(&g, "global_dof", &w.global_dof, "1", "degrees of freedom")?;
    for b in &sig.bands {
        let d = out.write_1d(
            &g,
            &format!("band_{}", b.name),
            &b.power,
            &power_unit,
            "scale-averaged power (the band's variance; T&C eq. 24)",
        )?;
        out.attr_f64(&d, "level", b.level_power)?;
        out.attr_f64(&d, "dof", b.dof)?;
        out.attr_f64(&d, "band_low_Hz", b.band_hz.0)?;
        out.attr_f64(&d, "band_high_Hz", b.band_hz.1)?;
    }
    Ok(())
}

/// `analysis/poincare`: the maxima and minima section.
fn write_poincare(out: &H5Out, r: &AnalysisReport, s: &Series) -> Result<()> {
    let g = out.group("analysis/poincare", Some("NXdata"))?;
    out.attr_str(&g, "signal", "maxima")?;
    out.attr_str_list(&g, "axes", &["maxima_time"])?;
    let shift = |t: &[f64]| shifted(r, t);
    out.write_1d(
        &g,
        "maxima_time",
        &shift(&r.section.maxima_time_s),
        "s",
        "time of the maxima",
    )?;
    out.write_1d(
        &g,
        "maxima",
        &r.section.maxima,
        &s.unit,
        "maxima (v = 0, parabola-refined)",
    )?;
    out.write_1d(
        &g,
        "minima_time",
        &shift(&r.section.minima_time_s),
        "s",
        "time of the minima",
    )?;
    out.write_1d(&g, "minima", &r.section.minima, &s.unit, "minima")?;
    Ok(())
}

/// `analysis/phase_space`: displacement against velocity.
fn write_phase_space(out: &H5Out, r: &AnalysisReport, s: &Series) -> Result<()> {
    let ps = &r.phase_space;
    let g = out.group("analysis/phase_space", Some("NXdata"))?;
    out.attr_str(&g, "signal", "velocity")?;
    out.attr_str_list(&g, "axes", &["displacement"])?;
    out.write_1d(&g, "time", &shifted(r, &ps.time_s), "s", "time")?;
    out.write_1d(&g, "displacement", &ps.x, &s.unit, "series (detrended)")?;
    out.write_1d(&g, "velocity", &ps.v, &s.velocity_unit, "velocity")?;
    Ok(())
}

/// Spectrum, scalogram, Poincaré map and phase portrait PNGs, in display units.
fn write_figures(dir: &Path, label: &str, r: &AnalysisReport, s: &Series) -> Result<()> {
    let (du, k) = display_unit(&s.unit);
    let (vu, kv) = display_unit(&s.velocity_unit);
    use crate::figures;
    let peaks: Vec<(f64, f64)> = r
        .peaks
        .iter()
        .map(|p| (p.frequency, p.amplitude * k))
        .collect();
    let amp: Vec<f64> = r.spectrum.amplitude.iter().map(|a| a * k).collect();
    figures::spectrum_png(
        &dir.join("spectrum.png"),
        &format!("Amplitude spectrum — {label}"),
        &r.spectrum.frequency,
        &amp,
        &peaks,
        du,
        None,
    )?;
    let sc = &r.scalogram;
    let time = shifted(r, &sc.time_s());
    let mag: Vec<f32> = sc
        .magnitude
        .iter()
        .map(|m| (*m as f64 * k) as f32)
        .collect();
    match &r.significance {
        Ok(sig) => {
            let k2 = k * k;
            let scaled = |v: &[Option<f64>]| -> Vec<f64> {
                v.iter().map(|x| x.map_or(f64::NAN, |x| x * k2)).collect()
            };
            let power_unit = if du.is_empty() || du == "1" {
                String::new()
            } else {
                format!("{du}²")
            };
            figures::scalogram_significance_png(
                &dir.join("scalogram.png"),
                &format!("Wavelet scalogram — {label}"),
                &time,
                &sc.frequencies_hz,
                &mag,
                &sc.coi_hz,
                Some(&r.ridge.frequency_hz),
                du,
                &figures::SignificanceOverlay {
                    mask: &sig.wavelet.mask,
                    global: &scaled(&sig.wavelet.global_power),
                    global_level: &scaled(&sig.wavelet.global_level),
                    power_unit: &power_unit,
                    level: sig.wavelet.level,
                },
            )?;
        }
        Err(_) => figures::scalogram_png(
            &dir.join("scalogram.png"),
            &format!("Wavelet scalogram — {label}"),
            &time,
            &sc.frequencies_hz,
            &mag,
            &sc.coi_hz,
            Some(&r.ridge.frequency_hz),
            du,
        )?,
    }
    let rm: Vec<(f64, f64)> = r
        .section
        .return_map()
        .iter()
        .map(|p| (p[0] * k, p[1] * k))
        .collect();
    if !rm.is_empty() {
        figures::poincare_png(
            &dir.join("poincare.png"),
            &format!("Poincaré map of the maxima — {label}"),
            &rm,
            du,
            &r.class_label(),
        )?;
    }
    let ps = &r.phase_space;
    let x: Vec<f64> = ps.x.iter().map(|x| x * k).collect();
    let v: Vec<f64> = ps.v.iter().map(|v| v * kv).collect();
    figures::phase_portrait_png(
        &dir.join("phase_portrait.png"),
        &format!("Phase portrait — {label}"),
        &x,
        &v,
        du,
        vu,
    )?;
    Ok(())
}

/// The stage.
pub struct AnalysisStage {
    pub name: String,
    pub source: String,
    pub series: SeriesSpec,
    pub settings: AnalysisSettings,
    pub against: Option<AgainstSpec>,
}

impl FromConfig for AnalysisStage {
    type Config = AnalysisConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &AnalysisConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let err = |k: &str, m: String| file.error("analysis", name, k, m);
        let has = |kind: &str| file.has_instance(kind, &cfg.source);
        let (default_file, dataset, velocity) = if let Some(sim) =
            &file.instance::<SimulateConfig>("simulate", &cfg.source)?
        {
            let p = SimulateParams::check(sim).map_err(|e| {
                err(
                    "source",
                    format!("[simulate.{}] is invalid ({e})", cfg.source),
                )
            })?;
            let a = match (cfg.actuation, p.actuations.as_slice()) {
                (Some(a), list) => {
                    if !list.iter().any(|x| (x - a.0).abs() < 1e-13) {
                        return Err(err(
                            "actuation",
                            format!("[simulate.{}] has no case at {} nm", cfg.source, a.0 * 1e9),
                        ));
                    }
                    a.0
                }
                (None, [one]) => *one,
                (None, _) => {
                    return Err(err(
                        "actuation",
                        format!(
                            "[simulate.{}] has several cases: say which (actuation = \"5 nm\")",
                            cfg.source
                        ),
                    ))
                }
            };
            (
                Some(case_files::sweep_case_file(a)),
                DEFAULT_SERIES[0].0,
                DEFAULT_SERIES[0].1,
            )
        } else if let Some(three) = &file.instance::<ThreeDofConfig>("three_dof", &cfg.source)? {
            if cfg.actuation.is_some() {
                return Err(err("actuation", "only for a [simulate] source".into()));
            }
            let p = ThreeDofParams::check(three).map_err(|e| {
                err(
                    "source",
                    format!("[three_dof.{}] is invalid ({e})", cfg.source),
                )
            })?;
            // One case: its file by default; several: `file` says which.
            let only = match p.cases.as_slice() {
                [one] => Some(case_files::three_dof_case_file(&one.label())),
                _ if cfg.file.is_some() => None,
                several => {
                    let names: Vec<String> = several
                        .iter()
                        .map(|c| case_files::three_dof_case_file(&c.label()))
                        .collect();
                    return Err(err(
                        "file",
                        format!(
                            "[three_dof.{}] has several cases: say which file, one of {}",
                            cfg.source,
                            names.join(", ")
                        ),
                    ));
                }
            };
            (only, DEFAULT_SERIES[0].0, DEFAULT_SERIES[0].1)
        } else if has("dmw") || has("excitation") {
            if cfg.actuation.is_some() {
                return Err(err("actuation", "only for a [simulate] source".into()));
            }
            (
                Some(dmw_tracks::FILE.to_string()),
                DEFAULT_SERIES[1].0,
                DEFAULT_SERIES[1].1,
            )
        } else {
            let known = has("surface")
                || has("interface")
                || has("contact")
                || has("calibrate")
                || has("analysis");
            if !known {
                return Err(err(
                    "source",
                    format!("no stage instance `{}` in this file", cfg.source),
                ));
            }
            (None, "", "")
        };
        let file_name = match (&cfg.file, default_file) {
            (Some(f), _) => f.clone(),
            (None, Some(f)) => f,
            (None, None) => {
                return Err(err(
                    "file",
                    format!("say which file of `{}` holds the series", cfg.source),
                ))
            }
        };
        if file_name.starts_with('/') || file_name.split('/').any(|c| c == "..") {
            return Err(err(
                "file",
                format!("`{file_name}` must be a path inside the source's outputs"),
            ));
        }
        let dataset = match (&cfg.dataset, dataset) {
            (Some(d), _) => d.clone(),
            (None, "") => return Err(err("dataset", "say which dataset holds the series".into())),
            (None, d) => d.to_string(),
        };
        let velocity = match (&cfg.velocity, cfg.dataset.is_some()) {
            (Some(v), _) if v == "none" => None,
            (Some(v), _) => Some(v.clone()),
            (None, false) if !velocity.is_empty() => Some(velocity.to_string()),
            (None, _) => None,
        };
        let settings = AnalysisSettings {
            window: cfg
                .window
                .map_or((None, None), |[a, b]| (Some(a.0), Some(b.0))),
            f_min: cfg.f_min.map(|f| f.0),
            f_max: cfg.f_max.map(|f| f.0),
            frequencies: cfg.frequencies,
            peaks: cfg.peaks,
            min_peak_frequency: cfg.min_peak_frequency.map_or(0.0, |f| f.0),
        };
        settings.check().map_err(|e| err(&e.key, e.message))?;
        let against = match &cfg.against {
            None => {
                for (k, given) in [
                    ("against_file", cfg.against_file.is_some()),
                    ("against_dataset", cfg.against_dataset.is_some()),
                    ("surrogates", cfg.surrogates.is_some()),
                    ("seed", cfg.seed.is_some()),
                ] {
                    if given {
                        return Err(err(k, "only with `against`".into()));
                    }
                }
                None
            }
            Some(a) => {
                let dmw_like = file.has_instance("dmw", a) || file.has_instance("excitation", a);
                if !dmw_like && !file.has_any_instance(a) {
                    return Err(err(
                        "against",
                        format!("no stage instance `{a}` in this file"),
                    ));
                }
                let (f, d) = match (&cfg.against_file, &cfg.against_dataset, dmw_like) {
                    (Some(f), Some(d), _) => (f.clone(), d.clone()),
                    (f, d, true) => (
                        f.clone().unwrap_or_else(|| dmw_tracks::FILE.to_string()),
                        d.clone().unwrap_or_else(|| DEFAULT_SERIES[1].0.to_string()),
                    ),
                    _ => {
                        return Err(err(
                            "against_file",
                            format!("say which file and dataset of `{a}` hold the series"),
                        ))
                    }
                };
                if f.starts_with('/') || f.split('/').any(|c| c == "..") {
                    return Err(err(
                        "against_file",
                        format!("`{f}` must be a path inside the instance's outputs"),
                    ));
                }
                let surrogates = cfg.surrogates.unwrap_or(300);
                if !(20..=100_000).contains(&surrogates) {
                    return Err(err(
                        "surrogates",
                        format!("{surrogates} is out of range: 20 … 100000"),
                    ));
                }
                Some(AgainstSpec {
                    source: a.clone(),
                    file: f,
                    dataset: d,
                    surrogates,
                    seed: cfg.seed.unwrap_or(1),
                })
            }
        };
        Ok(AnalysisStage {
            name: name.to_string(),
            source: cfg.source.clone(),
            series: SeriesSpec {
                file: file_name,
                dataset,
                velocity,
            },
            settings,
            against,
        })
    }
}

impl StageKind for AnalysisStage {
    const KIND: &'static str = "analysis";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = AnalysisResult;
    type Row = AnalysisRow;

    fn params(&self) -> Value {
        let st = &self.settings;
        json!({
            "source": self.source,
            "series": {
                "file": self.series.file,
                "dataset": self.series.dataset,
                "velocity": self.series.velocity,
            },
            "settings": {
                "window_s": [st.window.0, st.window.1],
                "f_min_Hz": st.f_min,
                "f_max_Hz": st.f_max,
                "frequencies": st.frequencies,
                "peaks": st.peaks,
                "min_peak_frequency_Hz": st.min_peak_frequency,
            },
            "against": self.against.as_ref().map(|a| json!({
                "source": a.source,
                "file": a.file,
                "dataset": a.dataset,
                "surrogates": a.surrogates,
                "seed": a.seed,
            })),
        })
    }
    fn upstream(&self) -> Vec<String> {
        let mut u = vec![self.source.clone()];
        if let Some(a) = &self.against {
            if a.source != self.source {
                u.push(a.source.clone());
            }
        }
        u
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<AnalysisResult, AnalysisRow>> {
        let dir = ctx
            .upstream_dirs
            .get(&self.source)
            .ok_or_else(|| Error::NoUpstreamFiles {
                stage: self.source.clone(),
            })?;
        let path = dir.join(&self.series.file);
        if !path.is_file() {
            return Err(Error::MissingOutput {
                stage: self.source.clone(),
                file: self.series.file.clone(),
            });
        }
        ctx.progress.set_message("reading the series");
        let s = read_series(
            &path,
            Some(&self.series.dataset),
            Some(self.series.velocity.as_deref().unwrap_or("none")),
            None,
        )?;
        ctx.progress
            .set_message("spectrum, wavelet transform, Poincaré section");
        let r = analyze(
            &s.x,
            s.v.as_deref(),
            s.sample_rate,
            s.t0,
            &self.settings.options(),
        )
        .map_err(|source| Error::AnalysisOf {
            file: self.series.file.clone(),
            dataset: self.series.dataset.clone(),
            source,
        })?;
        let label = format!(
            "{} {}",
            self.source,
            self.series.dataset.rsplit('/').next().unwrap_or("")
        );
        let series = AnalysedSeries {
            source: self.source.clone(),
            file: self.series.file.clone(),
            dataset: self.series.dataset.clone(),
            velocity: self.series.velocity.clone(),
        };
        let source = serde_json::to_value(&series).map_err(|e| Error::Encode {
            kind: Self::KIND,
            what: "series".into(),
            message: e.to_string(),
        })?;
        let coherence = match &self.against {
            None => None,
            Some(a) => {
                ctx.progress
                    .set_message("wavelet coherence and its Monte Carlo levels");
                let adir =
                    ctx.upstream_dirs
                        .get(&a.source)
                        .ok_or_else(|| Error::NoUpstreamFiles {
                            stage: a.source.clone(),
                        })?;
                let apath = adir.join(&a.file);
                if !apath.is_file() {
                    return Err(Error::MissingOutput {
                        stage: a.source.clone(),
                        file: a.file.clone(),
                    });
                }
                let y = read_series(&apath, Some(&a.dataset), Some("none"), None)?;
                let mc = MonteCarlo {
                    surrogates: a.surrogates,
                    seed: a.seed,
                    ..MonteCarlo::default()
                };
                let c = coherence_against(&s.x, s.t0, &r, &y.x, y.sample_rate, y.t0, &mc).map_err(
                    |source| Error::AnalysisOf {
                        file: a.file.clone(),
                        dataset: a.dataset.clone(),
                        source,
                    },
                )?;
                Some((c, format!("{} {}", a.source, a.dataset)))
            }
        };
        ctx.progress.set_message("HDF5 and plots");
        write_outputs(
            ctx.out_dir,
            ctx.key,
            &label,
            &source,
            &r,
            &s,
            coherence.as_ref().map(|(c, l)| (c, l.as_str())),
        )?;
        let summary_row = summary_row(&self.source, &self.series.dataset, &r, &s.unit);
        let mut summary = summary(&r, &s.unit);
        summary.coherence = coherence.as_ref().map(|(c, l)| coherence_summary(c, l));
        Ok(Output {
            result: AnalysisResult {
                series,
                summary,
                file: ANALYSIS_FILE.to_string(),
            },
            summary_row: Some(summary_row),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::sig6;

    #[test]
    fn summary_values_keep_six_significant_digits() {
        assert_eq!(sig6(1.923_250_000_000_000_1), 1.92325);
        assert_eq!(sig6(110.491_866_891_587), 110.492);
        assert_eq!(sig6(1.177_594_661e-4), 1.17759e-4);
        assert_eq!(sig6(-0.340_004_2), -0.340004);
        assert_eq!(sig6(0.0), 0.0);
        assert!(sig6(f64::NAN).is_nan());
    }
}
