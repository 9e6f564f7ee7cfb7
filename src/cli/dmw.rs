//! `hdi dmw FILE`: one LDV record's DMW tracks and their statistics.

use anyhow::Result;
use serde_json::json;

use super::args::DmwArgs;
use super::{flag, out_parent};
use hdi::stages::dmw::{self, DmwConfig};

pub(super) fn cmd_dmw(a: DmwArgs) -> Result<()> {
    let mut cfg = DmwConfig::for_file(a.file.clone());
    cfg.sample_rate = a.sample_rate;
    if let Some(s) = a.sensitivity {
        cfg.sensitivity = s;
    }
    cfg.rpm = a.rpm;
    cfg.velocity_column = a.velocity_column;
    cfg.index_column = a.index_column;
    cfg.time_column = a.time_column;
    cfg.velocity_unit = a.velocity_unit;
    cfg.trigger_level = a.trigger_level;
    if let Some(v) = a.trigger_polarity {
        cfg.trigger_polarity = v;
    }
    if let Some(v) = a.pulses_per_revolution {
        cfg.pulses_per_revolution = v;
    }
    if let Some(s) = a.segment {
        cfg.segment = s;
    }
    cfg.max_revolutions = a.max_revolutions;
    if let Some(v) = a.averaging {
        cfg.averaging = v;
    }
    if let Some(v) = a.filter {
        cfg.filter = v;
    }
    if let Some(v) = a.highpass_hz {
        cfg.highpass_hz = v;
    }
    if let Some(v) = a.highpass_order {
        cfg.highpass_order = v;
    }
    cfg.lowpass_hz = a.lowpass_hz;
    if let Some(v) = a.lowpass_order {
        cfg.lowpass_order = v;
    }
    if let Some(v) = a.padlen {
        cfg.padlen = match v.parse::<i64>() {
            Ok(n) => dmw::PadlenConfig::Samples(n),
            Err(_) => dmw::PadlenConfig::Text(v),
        };
    }
    if let Some(v) = a.chain_order {
        cfg.chain_order = v;
    }
    if let Some(v) = a.detrend {
        cfg.detrend = v;
    }
    if let Some(v) = a.remove_offset {
        cfg.remove_offset = v;
    }
    cfg.resample_hz = a.resample_hz;
    if let Some(v) = a.peaks {
        cfg.peaks = v;
    }
    let params = dmw::check(&cfg, a.file.clone())
        .map_err(|e| anyhow::anyhow!("{}: {}", flag(&e.key), e.message))?;
    let (rec, res) = dmw::analyse(&params)?;
    if let Some(out) = &a.out {
        let dir = out_parent(out)?;
        dmw::write_outputs(
            &rec,
            &res,
            &params,
            out,
            Some(dir),
            "",
            &json!([a.file.to_string_lossy()]),
        )?;
    }
    let report = dmw::report_json(&rec, &res, &params);
    if a.json {
        println!("{}", serde_json::to_string(&report)?);
        return Ok(());
    }
    let q = &res.qa;
    let s = &res.stats;
    println!(
        "{} ({}, {}), {} samples at {} MS/s",
        a.file.display(),
        rec.format,
        q.layout,
        rec.velocity.len(),
        rec.sample_rate / 1e6
    );
    println!(
        "  revolutions  {} averaged of {} triggers ({}; {} averaging)",
        q.n_avg, q.n_triggers, q.segmentation, params.chain.averaging
    );
    if q.period_mean.is_finite() {
        println!(
            "  period       {:.6} ms ({:.1} rpm), relative std {:.2e}",
            q.period_mean * 1e3,
            60.0 / q.period_mean,
            q.period_relstd
        );
    }
    println!(
        "  noise floor  {:.3} µm/s in the average (residual {:.3} µm/s per revolution)",
        q.noise_floor * 1e6,
        q.residual_std * 1e6
    );
    println!(
        "  DMW          std {:.4} nm, peak-to-peak {:.4} nm ({} samples at {} MS/s, {} edge samples excluded each end)",
        s.std * 1e9,
        s.peak_to_peak * 1e9,
        res.tracks.d[0].len(),
        res.sample_rate / 1e6,
        q.edge_samples
    );
    for p in s.peaks.iter().take(5) {
        println!(
            "  line         {:9.3} kHz  {:.4} nm",
            p.frequency / 1e3,
            p.amplitude * 1e9
        );
    }
    for w in &q.warnings {
        println!("  warning: {w}");
    }
    Ok(())
}
