//! DMW stage: one LDV record → revolution average → high-passed velocity and displacement →
//! the three tracks, as HDF5 + PNG + a summary row. The same function serves the pipeline and
//! `hdi dmw FILE`.

use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::dmw_tracks;
use crate::artefacts::finite;
use crate::core::config::{ConfigError, PipelineFile};
use crate::dmw::average::AverageMode;
use crate::dmw::chain::{
    process, Butterworth, ChainOrder, ChainParams, DmwResult, FilterMode, Padlen,
};
use crate::dmw::io::{read_ldv, ReadOptions};
use crate::dmw::triggers::Polarity;
use crate::dmw::{LdvRecord, VelocityUnit};
use crate::error::Result;
use crate::signal::integrate::Detrend;
use crate::units::{Frequency, Sensitivity, TimeSpan};
use serde::Deserialize;
use serde_json::{json, Value};
use std::path::PathBuf;

pub use crate::artefacts::ldv::{write_ldv, write_ldv_hdf5_counts};

mod output;
pub use output::{
    write_outputs, DmwReport, DmwRow, DmwStageResult, SpectralLine, TrackStd, TRACKS_NOTE,
};

/// Bump when the numbers this stage produces change.
pub const MODEL_VERSION: &str = "dmw-2";

fn default_sensitivity() -> Sensitivity {
    Sensitivity(0.025)
}
fn default_segment() -> TimeSpan {
    TimeSpan(2.5e-3)
}
fn default_averaging() -> String {
    "angular".into()
}
fn default_filter() -> String {
    "zero_phase".into()
}
fn default_highpass() -> Frequency {
    Frequency(10e3)
}
fn default_order() -> usize {
    4
}
fn default_padlen() -> PadlenConfig {
    PadlenConfig::Text("auto".into())
}
fn default_chain_order() -> String {
    "filter_then_integrate".into()
}
fn default_detrend() -> String {
    "line".into()
}
fn default_true() -> bool {
    true
}
fn default_polarity() -> String {
    "auto".into()
}
fn default_ppr() -> usize {
    1
}
fn default_peaks() -> usize {
    8
}

/// `padlen = "auto" | "scipy" | <samples>`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum PadlenConfig {
    Samples(i64),
    Text(String),
}

/// `[dmw.NAME]` as written in `pipeline.toml` (every key is also a `hdi dmw` option).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DmwConfig {
    /// LDV record (CSV, Parquet or HDF5; detected from content).
    pub file: PathBuf,
    /// Sample rate, when the file has no time column and does not state it.
    #[serde(default)]
    pub sample_rate: Option<Frequency>,
    /// Velocity-decoder sensitivity (used when the velocity channel is in volts).
    #[serde(default = "default_sensitivity")]
    pub sensitivity: Sensitivity,
    /// Spindle speed, rpm: checks the index channel's period, or segments a record that has
    /// no index channel.
    #[serde(default)]
    pub rpm: Option<f64>,
    #[serde(default)]
    pub velocity_column: Option<String>,
    #[serde(default)]
    pub index_column: Option<String>,
    #[serde(default)]
    pub time_column: Option<String>,
    /// "V" or "m/s", overriding what the file says.
    #[serde(default)]
    pub velocity_unit: Option<String>,
    /// Trigger threshold in the index channel's unit (default: mid-level of its range).
    #[serde(default)]
    pub trigger_level: Option<f64>,
    /// "auto" (the pulse is the rarer state), "rising" (active-high) or "falling"
    /// (active-low).
    #[serde(default = "default_polarity")]
    pub trigger_polarity: String,
    /// Index pulses per revolution (evenly spaced).
    #[serde(default = "default_ppr")]
    pub pulses_per_revolution: usize,
    /// Length of the averaged segment after each trigger.
    #[serde(default = "default_segment")]
    pub segment: TimeSpan,
    #[serde(default)]
    pub max_revolutions: Option<usize>,
    /// "angular" (order tracking), "subsample" or "integer".
    #[serde(default = "default_averaging")]
    pub averaging: String,
    /// "zero_phase" (forward–backward), "causal" (one pass) or "none".
    #[serde(default = "default_filter")]
    pub filter: String,
    #[serde(default = "default_highpass")]
    pub highpass_hz: Frequency,
    #[serde(default = "default_order")]
    pub highpass_order: usize,
    #[serde(default)]
    pub lowpass_hz: Option<Frequency>,
    #[serde(default = "default_order")]
    pub lowpass_order: usize,
    #[serde(default = "default_padlen")]
    pub padlen: PadlenConfig,
    /// "filter_then_integrate" (recommended) or "integrate_then_filter" (reference order).
    #[serde(default = "default_chain_order")]
    pub chain_order: String,
    /// "line", "mean" or "none" after integration.
    #[serde(default = "default_detrend")]
    pub detrend: String,
    /// Subtract the averaged velocity's mean before integration (a decoder offset is not
    /// motion); `false` reproduces the reference scripts.
    #[serde(default = "default_true")]
    pub remove_offset: bool,
    /// Output sample rate (band-limited resampling); default: the record's.
    #[serde(default)]
    pub resample_hz: Option<Frequency>,
    /// Number of spectral peaks reported.
    #[serde(default = "default_peaks")]
    pub peaks: usize,
}

impl DmwConfig {
    /// The defaults for a file (what `hdi dmw FILE` starts from).
    pub fn for_file(file: PathBuf) -> Self {
        DmwConfig {
            file,
            sample_rate: None,
            sensitivity: default_sensitivity(),
            rpm: None,
            velocity_column: None,
            index_column: None,
            time_column: None,
            velocity_unit: None,
            trigger_level: None,
            trigger_polarity: default_polarity(),
            pulses_per_revolution: default_ppr(),
            segment: default_segment(),
            max_revolutions: None,
            averaging: default_averaging(),
            filter: default_filter(),
            highpass_hz: default_highpass(),
            highpass_order: default_order(),
            lowpass_hz: None,
            lowpass_order: default_order(),
            padlen: default_padlen(),
            chain_order: default_chain_order(),
            detrend: default_detrend(),
            remove_offset: true,
            resample_hz: None,
            peaks: default_peaks(),
        }
    }
}

/// Validated parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct DmwParams {
    pub file: PathBuf,
    pub read: ReadOptions,
    pub chain: ChainParams,
}

fn positive(
    key: &str,
    v: f64,
    what: &str,
) -> std::result::Result<(), crate::core::config::KeyError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(crate::core::config::KeyError::new(
            key,
            format!("{v} is out of range: {what} must be > 0"),
        ))
    }
}

/// The acquisition keys: sample rate, sensitivity, spindle, segments and the trigger.
fn check_acquisition(
    cfg: &DmwConfig,
) -> std::result::Result<Polarity, crate::core::config::KeyError> {
    let bad = |k: &str, m: String| Err(crate::core::config::KeyError::new(k, m));
    if let Some(f) = cfg.sample_rate {
        positive("sample_rate", f.0, "a sample rate")?;
    }
    positive("sensitivity", cfg.sensitivity.0, "the decoder sensitivity")?;
    if let Some(r) = cfg.rpm {
        if !(r.is_finite() && r > 0.0 && r <= 100_000.0) {
            return bad(
                "rpm",
                format!("{r} is out of range: spindle speed must be in (0, 100000] rpm"),
            );
        }
    }
    positive("segment", cfg.segment.0, "the segment length")?;
    if cfg.max_revolutions == Some(0) {
        return bad(
            "max_revolutions",
            "0 is out of range: average at least 1 revolution".into(),
        );
    }
    let trigger_polarity: Polarity = match cfg.trigger_polarity.parse() {
        Ok(p) => p,
        Err(e) => return bad("trigger_polarity", e),
    };
    if !(1..=360).contains(&cfg.pulses_per_revolution) {
        return bad(
            "pulses_per_revolution",
            format!(
                "{} is out of range: must be 1…360",
                cfg.pulses_per_revolution
            ),
        );
    }
    Ok(trigger_polarity)
}

/// The filter keys: mode, Butterworth orders and cutoffs (below Nyquist when the rate is
/// given); `(mode, filtered)`.
fn check_filters(
    cfg: &DmwConfig,
) -> std::result::Result<(FilterMode, bool), crate::core::config::KeyError> {
    let bad = |k: &str, m: String| Err(crate::core::config::KeyError::new(k, m));
    let (filter_mode, filtered) = match cfg.filter.as_str() {
        "none" => (FilterMode::ZeroPhase, false),
        other => match other.parse::<FilterMode>() {
            Ok(m) => (m, true),
            Err(e) => return bad("filter", format!("{e} or \"none\"")),
        },
    };
    positive("highpass_hz", cfg.highpass_hz.0, "the high-pass cutoff")?;
    for (k, o) in [
        ("highpass_order", cfg.highpass_order),
        ("lowpass_order", cfg.lowpass_order),
    ] {
        if !(1..=12).contains(&o) {
            return bad(
                k,
                format!("{o} is out of range: Butterworth order must be 1…12"),
            );
        }
    }
    if let Some(lp) = cfg.lowpass_hz {
        positive("lowpass_hz", lp.0, "the low-pass cutoff")?;
        if filtered && lp.0 <= cfg.highpass_hz.0 {
            return bad(
                "lowpass_hz",
                format!(
                    "{} Hz must be above the high-pass cutoff {} Hz",
                    lp.0, cfg.highpass_hz.0
                ),
            );
        }
    }
    if let Some(fs) = cfg.sample_rate {
        let nyquist = fs.0 / 2.0;
        for (k, f) in [
            ("highpass_hz", Some(cfg.highpass_hz.0)),
            ("lowpass_hz", cfg.lowpass_hz.map(|f| f.0)),
        ] {
            if let Some(f) = f {
                if filtered && f >= nyquist {
                    return bad(
                        k,
                        format!("{f} Hz is out of range: must be below Nyquist ({nyquist} Hz)"),
                    );
                }
            }
        }
    }
    Ok((filter_mode, filtered))
}

/// `padlen`: samples, `auto` or `scipy`.
fn padlen_of(padlen: &PadlenConfig) -> std::result::Result<Padlen, crate::core::config::KeyError> {
    let bad = |k: &str, m: String| Err(crate::core::config::KeyError::new(k, m));
    let padlen = match padlen {
        PadlenConfig::Samples(n) if *n >= 0 => Padlen::Samples(*n as usize),
        PadlenConfig::Samples(n) => {
            return bad("padlen", format!("{n} is out of range: must be ≥ 0"))
        }
        PadlenConfig::Text(t) if t == "auto" => Padlen::Auto,
        PadlenConfig::Text(t) if t == "scipy" => Padlen::Scipy,
        PadlenConfig::Text(t) => {
            return bad(
                "padlen",
                format!("`{t}`: expected \"auto\", \"scipy\" or a number of samples"),
            )
        }
    };
    Ok(padlen)
}

/// Check a `[dmw]` table (or `hdi dmw`'s options) key by key.
pub fn check(
    cfg: &DmwConfig,
    file: PathBuf,
) -> std::result::Result<DmwParams, crate::core::config::KeyError> {
    let bad = |k: &str, m: String| Err(crate::core::config::KeyError::new(k, m));
    let trigger_polarity = check_acquisition(cfg)?;
    let averaging: AverageMode = match cfg.averaging.parse() {
        Ok(m) => m,
        Err(e) => return bad("averaging", e),
    };
    let (filter_mode, filtered) = check_filters(cfg)?;
    let padlen = padlen_of(&cfg.padlen)?;
    let order: ChainOrder = match cfg.chain_order.parse() {
        Ok(o) => o,
        Err(e) => return bad("chain_order", e),
    };
    let detrend: Detrend = match cfg.detrend.parse() {
        Ok(d) => d,
        Err(e) => return bad("detrend", e),
    };
    if let Some(r) = cfg.resample_hz {
        positive("resample_hz", r.0, "the output sample rate")?;
    }
    if cfg.peaks > 100 {
        return bad(
            "peaks",
            format!("{} is out of range: at most 100 peaks", cfg.peaks),
        );
    }
    let velocity_unit = match cfg.velocity_unit.as_deref() {
        None => None,
        Some("V") => Some(VelocityUnit::Volt),
        Some("m/s") => Some(VelocityUnit::MetrePerSecond),
        Some(u) => return bad("velocity_unit", format!("`{u}`: expected \"V\" or \"m/s\"")),
    };
    Ok(DmwParams {
        file,
        read: ReadOptions {
            velocity_column: cfg.velocity_column.clone(),
            index_column: cfg.index_column.clone(),
            time_column: cfg.time_column.clone(),
            sample_rate: cfg.sample_rate.map(|f| f.0),
            velocity_unit,
        },
        chain: ChainParams {
            sensitivity: cfg.sensitivity.0,
            rpm: cfg.rpm,
            trigger_level: cfg.trigger_level,
            trigger_polarity,
            pulses_per_revolution: cfg.pulses_per_revolution,
            segment: cfg.segment.0,
            max_revolutions: cfg.max_revolutions,
            averaging,
            highpass: filtered.then_some(Butterworth {
                order: cfg.highpass_order,
                cutoff: cfg.highpass_hz.0,
            }),
            lowpass: cfg.lowpass_hz.filter(|_| filtered).map(|f| Butterworth {
                order: cfg.lowpass_order,
                cutoff: f.0,
            }),
            filter_mode,
            padlen,
            order,
            detrend,
            remove_offset: cfg.remove_offset,
            resample_rate: cfg.resample_hz.map(|f| f.0),
            n_peaks: cfg.peaks,
        },
    })
}

impl DmwParams {
    /// Canonical parameters for the cache key and the HDF5 root attribute (SI units).
    pub fn canonical(&self) -> Value {
        let c = &self.chain;
        let r = &self.read;
        let bw =
            |b: Option<Butterworth>| b.map(|b| json!({"order": b.order, "cutoff_Hz": b.cutoff}));
        json!({
            "read": {
                "velocity_column": r.velocity_column,
                "index_column": r.index_column,
                "time_column": r.time_column,
                "sample_rate_Hz": r.sample_rate,
                "velocity_unit": r.velocity_unit.map(|u| u.symbol()),
            },
            "sensitivity_m_s_per_V": c.sensitivity,
            "rpm": c.rpm,
            "trigger_level": c.trigger_level,
            "trigger_polarity": c.trigger_polarity.to_string(),
            "pulses_per_revolution": c.pulses_per_revolution,
            "segment_s": c.segment,
            "max_revolutions": c.max_revolutions,
            "averaging": c.averaging.to_string(),
            "highpass": bw(c.highpass),
            "lowpass": bw(c.lowpass),
            "filter_mode": c.filter_mode.to_string(),
            "padlen": match c.padlen {
                Padlen::Auto => json!("auto"),
                Padlen::Scipy => json!("scipy"),
                Padlen::Samples(n) => json!(n),
            },
            "chain_order": c.order.to_string(),
            "detrend": c.detrend.to_string(),
            "remove_offset": c.remove_offset,
            "resample_Hz": c.resample_rate,
            "peaks": c.n_peaks,
        })
    }
}

/// Read and process.
pub fn analyse(p: &DmwParams) -> Result<(LdvRecord, DmwResult)> {
    let rec = read_ldv(&p.file, &p.read)?;
    let mut chain = p.chain.clone();
    if chain.rpm.is_none() {
        chain.rpm = rec.rpm;
    }
    let res = process(&rec, &chain).map_err(|e| match e {
        crate::dmw::DmwError::Processing(m) => crate::dmw::DmwError::Record {
            path: p.file.clone(),
            message: m,
        },
        other => other,
    })?;
    Ok((rec, res))
}

/// The QA block and statistics, as printed by `hdi dmw --json` (and the stage's `result.json`):
/// SI units named in the keys, `null` for what the record does not define (no index channel,
/// too few revolutions), documented in `docs/json.md` and `docs/schemas/dmw.json`.
pub fn report_json(rec: &LdvRecord, r: &DmwResult, p: &DmwParams) -> DmwReport {
    let q = &r.qa;
    let s = &r.stats;
    DmwReport {
        file: p.file.display().to_string(),
        format: rec.format.into(),
        layout: q.layout.into(),
        segmentation: q.segmentation.into(),
        sample_rate_Hz: r.sample_rate,
        record_sample_rate_Hz: rec.sample_rate,
        n_samples: r.tracks.d[0].len(),
        duration_s: r.tracks.d[0].len() as f64 / r.sample_rate,
        velocity_unit: rec.velocity_unit.symbol().into(),
        sensitivity_m_per_s_per_V: p.chain.sensitivity,
        n_triggers: q.n_triggers,
        n_avg: q.n_avg,
        n_dropped: q.n_dropped,
        trigger_level_V: finite(q.trigger_level),
        trigger_polarity: q.trigger_polarity.into(),
        duty_cycle: finite(q.duty_cycle),
        n_debounced: q.n_debounced,
        missing_pulse_times_s: q.missing_pulses.iter().map(|m| finite(m.time)).collect(),
        extra_pulse_times_s: q.extra_pulses.iter().map(|&t| finite(t)).collect(),
        n_dropped_missing_pulse: q.n_gap_dropped,
        period_mean_s: finite(q.period_mean),
        period_relstd: finite(q.period_relstd),
        rpm_measured: finite(60.0 / q.period_mean),
        phase_wander_275kHz_rad: finite(q.phase_wander_275khz),
        noise_floor_m_per_s: finite(q.noise_floor),
        residual_std_m_per_s: finite(q.residual_std),
        velocity_offset_m_per_s: finite(q.velocity_offset),
        drift_m_per_s: finite(q.drift),
        integration_gain_275kHz: finite(q.integration_gain_275khz),
        edge_samples: q.edge_samples,
        dmw_std_m: finite(s.std),
        dmw_peak_to_peak_m: finite(s.peak_to_peak),
        velocity_std_m_per_s: finite(s.velocity_std),
        dominant_frequency_Hz: s.peaks.first().and_then(|p| finite(p.frequency)),
        peaks: s
            .peaks
            .iter()
            .map(|pk| SpectralLine {
                frequency_Hz: finite(pk.frequency),
                amplitude_m: finite(pk.amplitude),
            })
            .collect(),
        tracks: TrackStd {
            D1_std_m: finite(s.std),
            D2_std_m: finite(s.std),
            D3_std_m: finite(s.std),
            note: TRACKS_NOTE.into(),
        },
        chain_order: p.chain.order.to_string(),
        averaging: p.chain.averaging.to_string(),
        warnings: q.warnings.clone(),
    }
}

/// One row of the tidy DMW table (unit suffixes in the names).
pub fn summary_row(rec: &LdvRecord, r: &DmwResult, p: &DmwParams) -> DmwRow {
    let q = &r.qa;
    let s = &r.stats;
    DmwRow {
        file: p.file.display().to_string(),
        format: rec.format,
        n_avg: q.n_avg as i64,
        n_missing_pulses: q.missing_pulses.len() as i64,
        n_extra_pulses: q.extra_pulses.len() as i64,
        period_mean_ms: q.period_mean * 1e3,
        period_relstd: q.period_relstd,
        noise_floor_um_s: q.noise_floor * 1e6,
        dmw_std_nm: s.std * 1e9,
        dmw_peak_to_peak_nm: s.peak_to_peak * 1e9,
        velocity_std_mm_s: s.velocity_std * 1e3,
        dominant_frequency_kHz: s.peaks.first().map(|p| p.frequency / 1e3),
        dominant_amplitude_nm: s.peaks.first().map(|p| p.amplitude * 1e9),
        highpass_kHz: p.chain.highpass.map(|b| b.cutoff / 1e3),
        averaging: p.chain.averaging.to_string(),
        chain_order: p.chain.order.to_string(),
        n_samples: r.tracks.d[0].len() as i64,
        sample_rate_MHz: r.sample_rate / 1e6,
    }
}

/// A `[dmw.NAME]` instance.
pub struct DmwStage {
    pub name: String,
    pub params: DmwParams,
}

impl FromConfig for DmwStage {
    type Config = DmwConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &DmwConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let path = file.input_file("dmw", name, "file", &cfg.file, "LDV record")?;
        let params = check(cfg, path).map_err(|e| e.locate(file, "dmw", name))?;
        Ok(Self {
            name: name.to_string(),
            params,
        })
    }
}

impl StageKind for DmwStage {
    const KIND: &'static str = "dmw";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = DmwStageResult;
    type Row = DmwRow;

    fn params(&self) -> Value {
        self.params.canonical()
    }
    fn inputs(&self) -> Vec<(String, PathBuf)> {
        vec![("file".into(), self.params.file.clone())]
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<DmwStageResult, DmwRow>> {
        ctx.progress.set_message("reading, averaging, filtering");
        let (rec, res) = analyse(&self.params)?;
        ctx.progress.set_message("writing HDF5 and plots");
        let inputs = serde_json::to_value(&ctx.fingerprint.inputs).unwrap_or(Value::Null);
        write_outputs(
            &rec,
            &res,
            &self.params,
            &ctx.out_dir.join(dmw_tracks::FILE),
            Some(ctx.out_dir),
            ctx.key,
            &inputs,
        )?;
        Ok(Output {
            result: DmwStageResult {
                report: report_json(&rec, &res, &self.params),
                h5: dmw_tracks::FILE.into(),
            },
            summary_row: Some(summary_row(&rec, &res, &self.params)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(name: &str) -> PathBuf {
        PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/dmw/")).join(name)
    }

    /// The reference DMW std of `tests/data/dmw/reference.json` (numpy/scipy chain over whole
    /// revolutions at the known pulse times, tests/data/README.md).
    fn reference_std() -> f64 {
        let text = std::fs::read_to_string(data("reference.json")).unwrap();
        let v: Value = serde_json::from_str(&text).unwrap();
        v["dmw_std_m"].as_f64().unwrap()
    }

    fn run(name: &str) -> (LdvRecord, DmwResult) {
        let mut cfg = DmwConfig::for_file(data(name));
        cfg.sensitivity = Sensitivity(0.025);
        let p = check(&cfg, data(name)).unwrap();
        analyse(&p).unwrap()
    }

    #[test]
    fn narrow_index_pulse_gives_the_scipy_whole_revolution_dmw_std() {
        // 10 µs pulse at 5 425 rpm (duty cycle 0.09 %), only `sensitivity` set.
        let (_, r) = run("narrow_pulse.h5");
        let want = reference_std();
        assert_eq!(r.qa.trigger_polarity, "rising");
        assert_eq!(r.qa.n_avg, 8);
        assert!(r.qa.missing_pulses.is_empty() && r.qa.extra_pulses.is_empty());
        assert!(
            (r.qa.period_mean * 1e6 - 11060.0).abs() < 1e-6,
            "{}",
            r.qa.period_mean
        );
        let rel = r.stats.std / want - 1.0;
        eprintln!("DMW std {} m vs scipy {want} m: {rel:+.2e}", r.stats.std);
        assert!(rel.abs() < 0.03, "{} vs {want} ({rel})", r.stats.std);
    }

    #[test]
    fn inverted_bouncing_index_pulse_gives_the_same_dmw_std() {
        let (_, r) = run("inverted_bounce.h5");
        let want = reference_std();
        assert_eq!(r.qa.trigger_polarity, "falling");
        assert_eq!(r.qa.n_avg, 8);
        // Each of the 9 pulses bounces on both edges.
        assert_eq!(r.qa.n_debounced, 18);
        assert!(r.qa.missing_pulses.is_empty() && r.qa.extra_pulses.is_empty());
        let rel = r.stats.std / want - 1.0;
        eprintln!("DMW std {} m vs scipy {want} m: {rel:+.2e}", r.stats.std);
        assert!(rel.abs() < 0.03, "{} vs {want} ({rel})", r.stats.std);
    }

    #[test]
    fn trigger_keys_are_checked() {
        let mut cfg = DmwConfig::for_file(data("narrow_pulse.h5"));
        cfg.trigger_polarity = "up".into();
        let e = check(&cfg, data("x")).unwrap_err();
        assert!(e.to_string().contains("trigger_polarity"), "{e}");
        cfg.trigger_polarity = "falling".into();
        cfg.pulses_per_revolution = 0;
        let e = check(&cfg, data("x")).unwrap_err();
        assert!(e.to_string().contains("pulses_per_revolution"), "{e}");
        cfg.pulses_per_revolution = 2;
        let p = check(&cfg, data("x")).unwrap();
        assert_eq!(p.chain.trigger_polarity, Polarity::Falling);
        assert_eq!(p.chain.pulses_per_revolution, 2);
    }
}
