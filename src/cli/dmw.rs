//! `hdi dmw FILE`: one LDV record's DMW tracks and their statistics, as a one-instance
//! pipeline through the engine.

use anyhow::Result;

use super::args::DmwArgs;
use super::{flag, one_off, out_parent};
use hdi::stages::dmw::{self, DmwConfig, DmwStage, DmwStageResult};
use hdi::stages::Instance;

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
    let stage = Instance {
        name: one_off::NAME.into(),
        stage: DmwStage {
            name: one_off::NAME.into(),
            params,
        },
    };
    let ran = one_off::run::<DmwStageResult>("dmw", Box::new(stage))?;
    if let Some(out) = &a.out {
        one_off::deliver(&ran.dir, out_parent(out)?, &ran.result.h5, Some(out))?;
    }
    let r = &ran.result.report;
    if a.json {
        println!("{}", serde_json::to_string(r)?);
        return Ok(());
    }
    // Non-finite values are `None` in the result; they print as NaN.
    let nan = |v: Option<f64>| v.unwrap_or(f64::NAN);
    println!(
        "{} ({}, {}), recorded at {} MS/s",
        a.file.display(),
        r.format,
        r.layout,
        r.record_sample_rate_Hz / 1e6
    );
    println!(
        "  revolutions  {} averaged of {} triggers ({}; {} averaging)",
        r.n_avg, r.n_triggers, r.segmentation, r.averaging
    );
    if let Some(period) = r.period_mean_s {
        println!(
            "  period       {:.6} ms ({:.1} rpm), relative std {:.2e}",
            period * 1e3,
            nan(r.rpm_measured),
            nan(r.period_relstd)
        );
    }
    println!(
        "  noise floor  {:.3} µm/s in the average (residual {:.3} µm/s per revolution)",
        nan(r.noise_floor_m_per_s) * 1e6,
        nan(r.residual_std_m_per_s) * 1e6
    );
    println!(
        "  DMW          std {:.4} nm, peak-to-peak {:.4} nm ({} samples at {} MS/s, {} edge samples excluded each end)",
        nan(r.dmw_std_m) * 1e9,
        nan(r.dmw_peak_to_peak_m) * 1e9,
        r.n_samples,
        r.sample_rate_Hz / 1e6,
        r.edge_samples
    );
    for p in r.peaks.iter().take(5) {
        println!(
            "  line         {:9.3} kHz  {:.4} nm",
            nan(p.frequency_Hz) / 1e3,
            nan(p.amplitude_m) * 1e9
        );
    }
    for w in &r.warnings {
        println!("  warning: {w}");
    }
    Ok(())
}
