//! The DMW stage's outputs: `dmw.h5` (layout in docs/hdf5.md; its tracks as
//! `artefacts::dmw_tracks` reads them) and the PNGs.

use super::DmwParams;
use crate::artefacts::dmw_tracks;
use crate::core::store::H5Out;
use crate::dmw::chain::DmwResult;
use crate::dmw::{LdvRecord, VelocityUnit};
use crate::error::Result;
use crate::figures;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use std::path::Path;

/// QA and statistics of one LDV record's disk-waviness (DMW) tracks (docs/dmw.md); SI units
/// named in the keys; null where the record does not define a value (no index channel, too
/// few revolutions). Schema version 1 (docs/json.md): existing keys keep their name, unit and
/// type; renaming or removing one makes version 2.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct DmwReport {
    /// The record as given.
    pub file: String,
    /// Detected format (e.g. `hdf5`, `csv`, `parquet`, `arrow`, `uff58`, `npy`, `wav`).
    pub format: String,
    /// Record layout (docs/dmw.md).
    #[schemars(extend("enum" = ["continuous", "segments", "averaged"]))]
    pub layout: String,
    /// How revolutions were found: `index channel`, `spindle speed`, `pre-segmented` or
    /// `pre-averaged`.
    pub segmentation: String,
    /// Sample rate of the output tracks, Hz.
    pub sample_rate_Hz: f64,
    /// Sample rate of the record, Hz.
    pub record_sample_rate_Hz: f64,
    /// Samples per output track.
    pub n_samples: usize,
    /// Track duration, s.
    pub duration_s: f64,
    /// Unit of the velocity channel in the record.
    #[schemars(extend("enum" = ["V", "m/s"]))]
    pub velocity_unit: String,
    /// Decoder sensitivity, m/s per V (used for a channel in V).
    pub sensitivity_m_per_s_per_V: f64,
    /// Index triggers found.
    pub n_triggers: usize,
    /// Revolutions averaged.
    pub n_avg: usize,
    /// Revolutions not averaged (incomplete).
    pub n_dropped: usize,
    /// Index trigger level, V; null without an index channel. `null` when not defined for
    /// this input (docs/json.md).
    pub trigger_level_V: Option<f64>,
    /// Index edge used; empty without an index channel.
    #[schemars(extend("enum" = ["rising", "falling", ""]))]
    pub trigger_polarity: String,
    /// Fraction of time the index channel is in the pulse state, 0–1. `null` when not defined
    /// for this input (docs/json.md).
    pub duty_cycle: Option<f64>,
    /// Index edges merged by debouncing.
    pub n_debounced: usize,
    /// Expected times of index pulses the channel did not show, s.
    pub missing_pulse_times_s: Vec<Option<f64>>,
    /// Times of index pulses off the period grid (ignored), s.
    pub extra_pulse_times_s: Vec<Option<f64>>,
    /// Revolutions dropped because a missing pulse falls in them.
    pub n_dropped_missing_pulse: usize,
    /// Mean revolution period, s. `null` when not defined for this input (docs/json.md).
    pub period_mean_s: Option<f64>,
    /// Relative standard deviation of the period, dimensionless. `null` when not defined for
    /// this input (docs/json.md).
    pub period_relstd: Option<f64>,
    /// Spindle speed from the mean period, revolutions per minute. `null` when not defined for
    /// this input (docs/json.md).
    pub rpm_measured: Option<f64>,
    /// Phase error of a 275 kHz line at the segment end from the period wander, rad. `null`
    /// when not defined for this input (docs/json.md).
    pub phase_wander_275kHz_rad: Option<f64>,
    /// Non-repeating velocity left in the average, m/s. `null` when not defined for this
    /// input (docs/json.md).
    pub noise_floor_m_per_s: Option<f64>,
    /// Non-repeating velocity per revolution, m/s. `null` when not defined for this input
    /// (docs/json.md).
    pub residual_std_m_per_s: Option<f64>,
    /// Velocity offset removed before integration, m/s. `null` when not defined for this
    /// input (docs/json.md).
    pub velocity_offset_m_per_s: Option<f64>,
    /// Slope of the displacement line removed after integration, m/s. `null` when not defined
    /// for this input (docs/json.md).
    pub drift_m_per_s: Option<f64>,
    /// Trapezoid integration gain at 275 kHz relative to ideal, dimensionless. `null` when not
    /// defined for this input (docs/json.md).
    pub integration_gain_275kHz: Option<f64>,
    /// Samples at each end inside the filter transients (excluded from the statistics).
    pub edge_samples: usize,
    /// DMW standard deviation, m. `null` when not defined for this input (docs/json.md).
    pub dmw_std_m: Option<f64>,
    /// DMW peak-to-peak, m. `null` when not defined for this input (docs/json.md).
    pub dmw_peak_to_peak_m: Option<f64>,
    /// Standard deviation of the averaged velocity, m/s. `null` when not defined for this
    /// input (docs/json.md).
    pub velocity_std_m_per_s: Option<f64>,
    /// Frequency of the largest spectral line, Hz; null without lines. `null` when not
    /// defined for this input (docs/json.md).
    pub dominant_frequency_Hz: Option<f64>,
    /// Largest spectral lines of D1 (Hann window, interpolated), largest first.
    pub peaks: Vec<SpectralLine>,
    /// Per-track statistics.
    pub tracks: TrackStd,
    /// Processing order.
    #[schemars(extend("enum" = ["filter_then_integrate", "integrate_then_filter"]))]
    pub chain_order: String,
    /// Revolution averaging.
    #[schemars(extend("enum" = ["angular", "subsample", "integer"]))]
    pub averaging: String,
    /// Warnings in words.
    pub warnings: Vec<String>,
}

/// The DMW stage's `result.json`: the report and where the tracks are.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DmwStageResult {
    #[serde(flatten)]
    pub report: DmwReport,
    /// Where the simulations find the tracks (`dmw.h5` in the entry).
    pub h5: String,
}

/// One spectral line of D1.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SpectralLine {
    /// Line frequency, Hz. `null` when not defined for this input (docs/json.md).
    pub frequency_Hz: Option<f64>,
    /// Line amplitude (displacement), m. `null` when not defined for this input
    /// (docs/json.md).
    pub amplitude_m: Option<f64>,
}

/// How D2 and D3 relate to D1 (`tracks.note`).
pub const TRACKS_NOTE: &str =
    "D2 and D3 are time-flipped copies of D1: same std and amplitude spectrum";

/// Per-track statistics.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TrackStd {
    /// Std of track D1, m. `null` when not defined for this input (docs/json.md).
    pub D1_std_m: Option<f64>,
    /// Std of track D2, m. `null` when not defined for this input (docs/json.md).
    pub D2_std_m: Option<f64>,
    /// Std of track D3, m. `null` when not defined for this input (docs/json.md).
    pub D3_std_m: Option<f64>,
    /// How D2 and D3 relate to D1.
    pub note: String,
}

/// One row of the tidy DMW table (unit suffixes in the names).
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DmwRow {
    pub file: String,
    pub format: &'static str,
    pub n_avg: i64,
    pub n_missing_pulses: i64,
    pub n_extra_pulses: i64,
    pub period_mean_ms: f64,
    pub period_relstd: f64,
    pub noise_floor_um_s: f64,
    pub dmw_std_nm: f64,
    pub dmw_peak_to_peak_nm: f64,
    pub velocity_std_mm_s: f64,
    pub dominant_frequency_kHz: Option<f64>,
    pub dominant_amplitude_nm: Option<f64>,
    pub highpass_kHz: Option<f64>,
    pub averaging: String,
    pub chain_order: String,
    pub n_samples: i64,
    pub sample_rate_MHz: f64,
}

/// HDF5 (layout in docs/hdf5.md) and PNGs into `plot_dir`.
pub fn write_outputs(
    rec: &LdvRecord,
    r: &DmwResult,
    p: &DmwParams,
    h5_path: &Path,
    plot_dir: Option<&Path>,
    cache_key: &str,
    inputs: &Value,
) -> Result<()> {
    let out = H5Out::create(h5_path)?;
    out.root_attributes("dmw", cache_key, &p.canonical(), inputs, "dmw")?;
    let entry = out.group("dmw", Some("NXentry"))?;
    out.attr_str(&entry, "default", "tracks")?;
    write_tracks(&out, r)?;
    write_average(&out, rec, r)?;
    write_spectrum(&out, r)?;
    if !r.trigger_times.is_empty() {
        let g = out.group("dmw/triggers", None)?;
        out.write_1d(
            &g,
            "time",
            &r.trigger_times,
            "s",
            "once-per-revolution trigger times",
        )?;
        out.write_1d(&g, "period", &r.periods, "s", "revolution periods")?;
    }
    write_qa(&out, r)?;
    write_process(&out, rec, r, p)?;
    out.finish()?;

    if let Some(dir) = plot_dir {
        write_plots(r, dir)?;
    }
    Ok(())
}

/// `dmw/tracks`: time, the three displacement tracks D1–D3 and velocities V1–V3, and the
/// filter-transient flags.
pub(super) fn write_tracks(out: &H5Out, r: &DmwResult) -> Result<()> {
    let n = r.tracks.d[0].len();
    let fs = r.sample_rate;
    let time: Vec<f64> = (0..n).map(|i| i as f64 / fs).collect();

    let g = out.group(dmw_tracks::GROUP, Some("NXdata"))?;
    out.attr_str(&g, "signal", "D1")?;
    out.attr_str_list(&g, "auxiliary_signals", &["D2", "D3"])?;
    out.attr_str_list(&g, "axes", &["time"])?;
    let t = out.write_1d(&g, "time", &time, "s", "time from the segment start")?;
    out.attr_f64(&t, "sampling_rate", fs)?;
    out.attr_f64(&t, "t0", 0.0)?;
    let names = [
        ("D1", "V1", "original track (TFC bulge, centre line)"),
        ("D2", "V2", "time-flipped track (features at +y)"),
        ("D3", "V3", "negated time-flipped track (features at -y)"),
    ];
    for (k, (dn, vn, what)) in names.iter().enumerate() {
        out.write_1d(
            &g,
            dn,
            &r.tracks.d[k],
            "m",
            &format!("DMW displacement, {what}"),
        )?;
        out.write_1d(
            &g,
            vn,
            &r.tracks.v[k],
            "m/s",
            &format!("DMW velocity, {what}"),
        )?;
    }
    let edge: Vec<u8> = r.edge_transient.iter().map(|&b| u8::from(b)).collect();
    out.write_array(
        &g,
        "edge_transient",
        ndarray::ArrayView1::from(&edge[..]),
        "1",
        "1 = inside the filter's start/end transient (excluded from statistics)",
    )?;
    Ok(())
}

/// `dmw/average`: the revolution-averaged record as recorded and as velocity.
pub(super) fn write_average(out: &H5Out, rec: &LdvRecord, r: &DmwResult) -> Result<()> {
    let g = out.group("dmw/average", Some("NXdata"))?;
    out.attr_str(&g, "signal", "velocity")?;
    out.attr_str_list(&g, "axes", &["time"])?;
    let avg_time: Vec<f64> = (0..r.averaged_raw.len())
        .map(|i| i as f64 / rec.sample_rate)
        .collect();
    out.write_1d(&g, "time", &avg_time, "s", "time from the trigger")?;
    match r.averaged_raw_unit {
        VelocityUnit::Volt => out.write_1d(
            &g,
            "voltage",
            &r.averaged_raw,
            "V",
            "revolution-averaged decoder output",
        )?,
        VelocityUnit::MetrePerSecond => out.write_1d(
            &g,
            "velocity_raw",
            &r.averaged_raw,
            "m/s",
            "revolution-averaged velocity as recorded",
        )?,
    };
    out.write_1d(
        &g,
        "velocity",
        &r.averaged_velocity,
        "m/s",
        "revolution-averaged velocity, offset removed, unfiltered",
    )?;
    Ok(())
}

/// `dmw/spectrum` and its peaks.
pub(super) fn write_spectrum(out: &H5Out, r: &DmwResult) -> Result<()> {
    let g = out.group("dmw/spectrum", Some("NXdata"))?;
    out.attr_str(&g, "signal", "amplitude")?;
    out.attr_str_list(&g, "auxiliary_signals", &["velocity_amplitude"])?;
    out.attr_str_list(&g, "axes", &["frequency"])?;
    out.write_1d(&g, "frequency", &r.spectrum_frequency, "Hz", "frequency")?;
    out.write_1d(
        &g,
        "amplitude",
        &r.spectrum_displacement,
        "m",
        "one-sided amplitude of D1 (Hann)",
    )?;
    out.write_1d(
        &g,
        "velocity_amplitude",
        &r.spectrum_velocity,
        "m/s",
        "one-sided amplitude of V1 (Hann)",
    )?;
    let g = out.group("dmw/spectrum/peaks", None)?;
    let pf: Vec<f64> = r.stats.peaks.iter().map(|p| p.frequency).collect();
    let pa: Vec<f64> = r.stats.peaks.iter().map(|p| p.amplitude).collect();
    out.write_1d(
        &g,
        "frequency",
        &pf,
        "Hz",
        "spectral peak frequency (Hann-interpolated)",
    )?;
    out.write_1d(&g, "amplitude", &pa, "m", "spectral peak amplitude")?;
    Ok(())
}

/// `dmw/qa`: trigger and averaging quality, integration corrections, DMW statistics.
pub(super) fn write_qa(out: &H5Out, r: &DmwResult) -> Result<()> {
    let q = &r.qa;
    let g = out.group("dmw/qa", None)?;
    out.write_count(&g, "n_avg", q.n_avg as u64, "revolutions averaged")?;
    out.write_count(&g, "n_triggers", q.n_triggers as u64, "triggers found")?;
    out.write_count(
        &g,
        "n_debounced",
        q.n_debounced as u64,
        "index edges dropped as contact bounce",
    )?;
    out.write_count(
        &g,
        "n_dropped_missing_pulse",
        q.n_gap_dropped as u64,
        "revolutions not averaged because an index pulse is missing",
    )?;
    let missing: Vec<f64> = q.missing_pulses.iter().map(|m| m.time).collect();
    for (name, times, what) in [
        (
            "missing_pulse_time",
            &missing,
            "expected times of index pulses the channel did not show",
        ),
        (
            "extra_pulse_time",
            &q.extra_pulses,
            "index pulses off the period grid (ignored)",
        ),
    ] {
        // Written only when there are events (no empty datasets).
        if !times.is_empty() {
            out.write_1d(&g, name, times, "s", what)?;
        }
    }
    out.write_string(&g, "trigger_polarity", q.trigger_polarity)?;
    for (name, v, u, ln) in [
        ("period_mean", q.period_mean, "s", "mean revolution period"),
        (
            "period_relstd",
            q.period_relstd,
            "1",
            "relative std of the revolution period",
        ),
        (
            "phase_wander",
            q.phase_wander_275khz,
            "rad",
            "phase error of a 275 kHz line at the segment end",
        ),
        (
            "noise_floor",
            q.noise_floor,
            "m/s",
            "non-repeating velocity left in the average",
        ),
        (
            "residual_std",
            q.residual_std,
            "m/s",
            "non-repeating velocity per revolution",
        ),
        (
            "velocity_offset",
            q.velocity_offset,
            "m/s",
            "velocity offset removed before integration",
        ),
        (
            "drift",
            q.drift,
            "m/s",
            "slope of the displacement line removed after integration",
        ),
        (
            "integration_gain_275kHz",
            q.integration_gain_275khz,
            "1",
            "trapezoid gain at 275 kHz relative to ideal",
        ),
        (
            "dmw_std",
            r.stats.std,
            "m",
            "DMW standard deviation (edges excluded)",
        ),
        (
            "dmw_peak_to_peak",
            r.stats.peak_to_peak,
            "m",
            "DMW peak-to-peak (edges excluded)",
        ),
    ] {
        out.write_scalar(&g, name, v, u, ln)?;
    }
    out.write_string(&g, "warnings", &q.warnings.join("\n"))?;
    Ok(())
}

/// `dmw/process`: program, parameters, source provenance and the filter sections.
pub(super) fn write_process(
    out: &H5Out,
    rec: &LdvRecord,
    r: &DmwResult,
    p: &DmwParams,
) -> Result<()> {
    let g = out.group("dmw/process", Some("NXprocess"))?;
    out.write_string(&g, "program", "hdi")?;
    out.write_string(&g, "version", env!("CARGO_PKG_VERSION"))?;
    out.write_string(&g, "parameters", &p.canonical().to_string())?;
    let prov: Map<String, Value> = rec
        .provenance
        .iter()
        .map(|(k, v)| (k.clone(), Value::from(v.as_str())))
        .collect();
    out.write_string(&g, "source", &Value::Object(prov).to_string())?;
    let sos = |s: &[[f64; 6]]| -> ndarray::Array2<f64> {
        ndarray::Array2::from_shape_fn((s.len(), 6), |(i, j)| s[i][j])
    };
    if !r.highpass_sos.is_empty() {
        out.write_array(
            &g,
            "highpass_sos",
            sos(&r.highpass_sos).view(),
            "1",
            "high-pass second-order sections [b0 b1 b2 a0 a1 a2]",
        )?;
    }
    if !r.lowpass_sos.is_empty() {
        out.write_array(
            &g,
            "lowpass_sos",
            sos(&r.lowpass_sos).view(),
            "1",
            "low-pass second-order sections [b0 b1 b2 a0 a1 a2]",
        )?;
    }
    Ok(())
}

pub(super) fn write_plots(r: &DmwResult, dir: &Path) -> Result<()> {
    let fs = r.sample_rate;
    // At most ~4000 points per series: enough for the eye, small PNGs.
    let stride = (r.tracks.d[0].len() / 4000).max(1);
    let series = |k: usize| -> Vec<(f64, f64)> {
        r.tracks.d[k]
            .iter()
            .enumerate()
            .step_by(stride)
            .map(|(i, d)| (i as f64 / fs * 1e3, d * 1e9))
            .collect()
    };
    let n = r.tracks.d[0].len();
    let edge = r.qa.edge_samples as f64 / fs * 1e3;
    let end = n as f64 / fs * 1e3;
    let shade = if edge > 0.0 {
        vec![(0.0, edge), (end - edge, end)]
    } else {
        Vec::new()
    };
    figures::stacked_png(
        &dir.join("tracks.png"),
        &format!(
            "DMW tracks: std {:.3} nm (grey: filter transients, excluded)",
            r.stats.std * 1e9
        ),
        "time (ms)",
        &[
            ("D1 original, bulge (nm)", series(0)),
            ("D2 time-flipped, +y (nm)", series(1)),
            ("D3 negated flipped, −y (nm)", series(2)),
        ],
        &shade,
    )?;
    let spec: Vec<(f64, f64)> = r
        .spectrum_frequency
        .iter()
        .zip(&r.spectrum_displacement)
        .filter(|(f, a)| **f > 0.0 && **a > 0.0)
        .map(|(f, a)| (f / 1e3, a * 1e9))
        .collect();
    if !spec.is_empty() {
        let peaks: Vec<(f64, f64)> = r
            .stats
            .peaks
            .iter()
            .map(|p| (p.frequency / 1e3, p.amplitude * 1e9))
            .collect();
        figures::loglog_png(
            &dir.join("spectrum.png"),
            "DMW amplitude spectrum (D1, Hann)",
            "frequency (kHz)",
            "amplitude (nm)",
            &[("D1", spec)],
            &peaks,
        )?;
    }
    Ok(())
}
