//! The DMW stage's outputs: `dmw.h5` (layout in docs/hdf5.md; its tracks as
//! `artefacts::dmw_tracks` reads them) and the PNGs.

use super::DmwParams;
use crate::artefacts::dmw_tracks;
use crate::core::store::H5Out;
use crate::dmw::chain::DmwResult;
use crate::dmw::{LdvRecord, VelocityUnit};
use crate::error::Result;
use crate::figures;
use serde_json::{json, Map, Value};
use std::path::Path;

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
        .map(|(k, v)| (k.clone(), json!(v)))
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
