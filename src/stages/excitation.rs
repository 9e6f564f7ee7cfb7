//! Excitation stage (Appendix B; docs/analysis.md): a synthetic disk-motion track — pure
//! sinusoid, zero, band-limited random, quadratic chirp or the spec's synthetic DMW — written in
//! the DMW stage's track layout (`dmw.h5`, `dmw/tracks/D1…V3`), so any `[simulate]` instance
//! takes it as its `dmw`. The record runs `margin` beyond `duration` so the leading edge's
//! transit delay (~62 µs) stays inside it.

use super::{FromConfig, Output, StageContext, StageKind};
use crate::artefacts::dmw_tracks;
use crate::core::config::{ConfigError, KeyError, PipelineFile};
use crate::core::store::H5Out;
use crate::dmw::excitation_tracks::{
    band_limited_random, quadratic_chirp, sinusoid, synthetic_dmw, zero, Excitation, DMW_LINE_HZ,
};
use crate::error::Result;
use crate::units::{Frequency, Length, TimeSpan};
use serde::Deserialize;
use serde::Serialize;
use serde_json::{json, Value};
use std::path::Path;

// excitation-2: the key holds the excitation as plain JSON, not a Debug string (same numbers).
// excitation-3: so do the outputs (result.json `params`, the HDF5 root's `parameters`).
pub const MODEL_VERSION: &str = "excitation-3";

fn default_duration() -> TimeSpan {
    TimeSpan(2e-3)
}
fn default_margin() -> TimeSpan {
    TimeSpan(0.1e-3)
}
fn default_rate() -> Frequency {
    Frequency(4e6)
}
fn default_seed() -> u64 {
    1
}

/// `[excitation.NAME]` as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ExcitationConfig {
    /// `sinusoid`, `zero`, `band_limited_random`, `quadratic_chirp` or `synthetic_dmw`.
    pub kind: String,
    /// Signal length (the chirp's sweep time T); the record is `duration + margin`.
    #[serde(default = "default_duration")]
    pub duration: TimeSpan,
    #[serde(default = "default_margin")]
    pub margin: TimeSpan,
    #[serde(default = "default_rate")]
    pub sample_rate: Frequency,
    /// Sinusoid frequency (default 10.7 kHz, the DMW line).
    #[serde(default)]
    pub frequency: Option<Frequency>,
    /// RMS of the sinusoid / random band, σ of the synthetic DMW (default 1 nm).
    #[serde(default)]
    pub rms: Option<Length>,
    /// Band of the random excitation, e.g. `["10 kHz", "50 kHz"]`.
    #[serde(default)]
    pub band: Option<[Frequency; 2]>,
    /// Chirp start and end frequencies (default 40 → 500 kHz) and peak amplitude (1 nm).
    #[serde(default)]
    pub f0: Option<Frequency>,
    #[serde(default)]
    pub f1: Option<Frequency>,
    #[serde(default)]
    pub amplitude: Option<Length>,
    #[serde(default = "default_seed")]
    pub seed: u64,
}

/// What to generate, validated.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExcitationKind {
    Sinusoid {
        frequency: f64,
        rms: f64,
    },
    Zero,
    BandLimitedRandom {
        f_lo: f64,
        f_hi: f64,
        rms: f64,
        seed: u64,
    },
    QuadraticChirp {
        f0: f64,
        f1: f64,
        amplitude: f64,
    },
    SyntheticDmw {
        sigma: f64,
        seed: u64,
    },
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExcitationParams {
    pub kind: ExcitationKind,
    pub duration: f64,
    pub margin: f64,
    pub sample_rate: f64,
}

impl ExcitationParams {
    fn label(&self) -> &'static str {
        match self.kind {
            ExcitationKind::Sinusoid { .. } => "sinusoid",
            ExcitationKind::Zero => "zero",
            ExcitationKind::BandLimitedRandom { .. } => "band_limited_random",
            ExcitationKind::QuadraticChirp { .. } => "quadratic_chirp",
            ExcitationKind::SyntheticDmw { .. } => "synthetic_dmw",
        }
    }
}

/// Check an `[excitation]` table key by key.
pub fn check(cfg: &ExcitationConfig) -> std::result::Result<ExcitationParams, KeyError> {
    let bad = |k: &str, m: String| Err(KeyError::new(k, m));
    let fs = cfg.sample_rate.0;
    if !(fs.is_finite() && (1e4..=1e9).contains(&fs)) {
        return bad(
            "sample_rate",
            format!("{fs} Hz is out of range: 10 kHz … 1 GHz"),
        );
    }
    let (t, margin) = (cfg.duration.0, cfg.margin.0);
    if !(t.is_finite() && t > 0.0 && t <= 1.0) {
        return bad("duration", format!("{t} s is out of range: 0 < T ≤ 1 s"));
    }
    if !(margin.is_finite() && (0.0..=1.0).contains(&margin)) {
        return bad("margin", format!("{margin} s is out of range: 0 … 1 s"));
    }
    let rms = cfg.rms.map_or(1e-9, |l| l.0);
    let unused = |keys: &[(&str, bool)]| -> std::result::Result<(), KeyError> {
        match keys.iter().find(|(_, set)| *set) {
            Some((k, _)) => Err(KeyError::new(
                *k,
                format!("not used by kind = \"{}\"", cfg.kind),
            )),
            None => Ok(()),
        }
    };
    let kind = match cfg.kind.as_str() {
        "sinusoid" => {
            unused(&[("band", cfg.band.is_some()), ("f0", cfg.f0.is_some()), ("f1", cfg.f1.is_some()), ("amplitude", cfg.amplitude.is_some())])?;
            ExcitationKind::Sinusoid {
                frequency: cfg.frequency.map_or(DMW_LINE_HZ, |f| f.0),
                rms,
            }
        }
        "zero" => {
            unused(&[("frequency", cfg.frequency.is_some()), ("rms", cfg.rms.is_some()), ("band", cfg.band.is_some()), ("f0", cfg.f0.is_some()), ("f1", cfg.f1.is_some()), ("amplitude", cfg.amplitude.is_some())])?;
            ExcitationKind::Zero
        }
        "band_limited_random" => {
            unused(&[("frequency", cfg.frequency.is_some()), ("f0", cfg.f0.is_some()), ("f1", cfg.f1.is_some()), ("amplitude", cfg.amplitude.is_some())])?;
            let Some([lo, hi]) = cfg.band else {
                return bad("band", "band_limited_random needs band = [\"f_lo\", \"f_hi\"]".into());
            };
            ExcitationKind::BandLimitedRandom {
                f_lo: lo.0,
                f_hi: hi.0,
                rms,
                seed: cfg.seed,
            }
        }
        "quadratic_chirp" => {
            unused(&[("frequency", cfg.frequency.is_some()), ("rms", cfg.rms.is_some()), ("band", cfg.band.is_some())])?;
            ExcitationKind::QuadraticChirp {
                f0: cfg.f0.map_or(40e3, |f| f.0),
                f1: cfg.f1.map_or(500e3, |f| f.0),
                amplitude: cfg.amplitude.map_or(1e-9, |l| l.0),
            }
        }
        "synthetic_dmw" => {
            unused(&[("frequency", cfg.frequency.is_some()), ("band", cfg.band.is_some()), ("f0", cfg.f0.is_some()), ("f1", cfg.f1.is_some()), ("amplitude", cfg.amplitude.is_some())])?;
            ExcitationKind::SyntheticDmw {
                sigma: rms,
                seed: cfg.seed,
            }
        }
        o => {
            return bad(
                "kind",
                format!("unknown kind `{o}` (sinusoid, zero, band_limited_random, quadratic_chirp, synthetic_dmw)"),
            )
        }
    };
    let p = ExcitationParams {
        kind,
        duration: t,
        margin,
        sample_rate: fs,
    };
    // The generators check frequencies against Nyquist, bands, amplitudes: a short trial run
    // turns their errors into key errors now rather than at run time.
    let trial = ExcitationParams {
        duration: (64.0 / fs).min(t),
        margin: 0.0,
        ..p.clone()
    };
    if let Err(e) = generate(&trial) {
        let e = e.to_string();
        let key = match &p.kind {
            ExcitationKind::Sinusoid { .. } if e.contains("freq") => "frequency",
            ExcitationKind::BandLimitedRandom { .. } if e.contains("band") => "band",
            ExcitationKind::QuadraticChirp { .. } if e.contains("f0") => "f0",
            ExcitationKind::QuadraticChirp { .. } if e.contains("f1") => "f1",
            ExcitationKind::QuadraticChirp { .. } => "amplitude",
            _ => "rms",
        };
        return bad(key, e);
    }
    Ok(p)
}

/// Generate the track (`duration + margin` long).
pub fn generate(p: &ExcitationParams) -> std::result::Result<Excitation, crate::dmw::DmwError> {
    let (fs, record) = (p.sample_rate, p.duration + p.margin);
    match p.kind {
        ExcitationKind::Sinusoid { frequency, rms } => sinusoid(record, fs, frequency, rms),
        ExcitationKind::Zero => zero(record, fs),
        ExcitationKind::BandLimitedRandom {
            f_lo,
            f_hi,
            rms,
            seed,
        } => band_limited_random(record, fs, f_lo, f_hi, rms, seed),
        ExcitationKind::SyntheticDmw { sigma, seed } => synthetic_dmw(record, fs, sigma, seed),
        ExcitationKind::QuadraticChirp { f0, f1, amplitude } => {
            // The sweep time is `duration`; the margin continues the same phase law.
            let mut x = quadratic_chirp(p.duration, fs, f0, f1, amplitude)?;
            let n = (record * fs * (1.0 + 4.0 * f64::EPSILON)).floor() as usize + 1;
            for i in x.displacement.len()..n {
                let t = i as f64 / fs;
                x.displacement.push(x.model.displacement_at(t));
                x.velocity.push(x.model.velocity_at(t));
            }
            Ok(x)
        }
    }
}

/// The excitation stage's `result.json`.
#[allow(non_snake_case)]
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExcitationResult {
    /// The generator (`sinusoid`, `zero`, …).
    pub kind: &'static str,
    /// Its parameters (SI).
    pub params: ExcitationKind,
    pub sample_rate_Hz: f64,
    pub samples: usize,
    /// RMS of the displacement track, m.
    pub rms_m: f64,
    /// The tracks file in the entry (`dmw.h5`).
    pub file: &'static str,
}

/// One row of the tidy excitation table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExcitationRow {
    pub kind: &'static str,
    pub duration_ms: f64,
    pub samples: usize,
    pub rms_nm: f64,
}

pub struct ExcitationStage {
    pub name: String,
    pub params: ExcitationParams,
}

impl FromConfig for ExcitationStage {
    type Config = ExcitationConfig;

    fn from_config(
        file: &PipelineFile,
        name: &str,
        cfg: &ExcitationConfig,
    ) -> std::result::Result<Self, ConfigError> {
        let params = check(cfg).map_err(|e| e.locate(file, "excitation", name))?;
        Ok(Self {
            name: name.to_string(),
            params,
        })
    }
}

/// Write the track in the DMW stage's layout: D1 = the track, D2/D3 its flipped and
/// negated-flipped copies (§4.1.7; docs/dmw.md), velocities alike.
fn write_tracks(path: &Path, key: &str, p: &ExcitationParams, x: &Excitation) -> Result<()> {
    let out = H5Out::create(path)?;
    out.root_attributes(
        "excitation",
        key,
        &json!({ "excitation": p }),
        &json!({}),
        "dmw",
    )?;
    let entry = out.group("dmw", Some("NXentry"))?;
    out.attr_str(&entry, "default", "tracks")?;
    let g = out.group(dmw_tracks::GROUP, Some("NXdata"))?;
    out.attr_str(&g, "signal", "D1")?;
    out.attr_str_list(&g, "axes", &["time"])?;
    let n = x.displacement.len();
    let time: Vec<f64> = (0..n).map(|i| i as f64 / x.fs).collect();
    let t = out.write_1d(&g, "time", &time, "s", "time")?;
    out.attr_f64(&t, "sampling_rate", x.fs)?;
    let flipped = |v: &[f64], sign: f64| v.iter().rev().map(|y| sign * y).collect::<Vec<f64>>();
    out.write_1d(&g, "D1", &x.displacement, "m", "excitation displacement")?;
    out.write_1d(&g, "V1", &x.velocity, "m/s", "excitation velocity")?;
    out.write_1d(
        &g,
        "D2",
        &flipped(&x.displacement, 1.0),
        "m",
        "time-flipped displacement",
    )?;
    out.write_1d(
        &g,
        "V2",
        &flipped(&x.velocity, -1.0),
        "m/s",
        "time-flipped velocity",
    )?;
    out.write_1d(
        &g,
        "D3",
        &flipped(&x.displacement, -1.0),
        "m",
        "negated flipped displacement",
    )?;
    out.write_1d(
        &g,
        "V3",
        &flipped(&x.velocity, 1.0),
        "m/s",
        "negated flipped velocity",
    )?;
    // No filter here: no edge transient to mask.
    out.write_array(
        &g,
        "edge_transient",
        ndarray::ArrayView1::from(&vec![0u8; n][..]),
        "1",
        "1 where the filter's edge transient affects the track",
    )?;
    Ok(out.finish()?)
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

impl StageKind for ExcitationStage {
    const KIND: &'static str = "excitation";
    const MODEL_VERSION: &'static str = MODEL_VERSION;
    type Result = ExcitationResult;
    type Row = ExcitationRow;

    fn params(&self) -> Value {
        json!({ "excitation": self.params })
    }
    fn run(&self, ctx: &StageContext) -> Result<Output<ExcitationResult, ExcitationRow>> {
        let p = &self.params;
        let x = generate(p)?;
        write_tracks(&ctx.out_dir.join(dmw_tracks::FILE), ctx.key, p, &x)?;
        let ms: Vec<(f64, f64)> = x
            .displacement
            .iter()
            .enumerate()
            .step_by((x.displacement.len() / 4000).max(1))
            .map(|(i, d)| (i as f64 / x.fs * 1e3, d * 1e9))
            .collect();
        crate::figures::lines_png(
            &ctx.out_dir.join("track.png"),
            &format!("Excitation `{}` ({})", self.name, p.label()),
            "time (ms)",
            "disk displacement (nm)",
            &[("D1", ms)],
        )?;
        let sigma = rms(&x.displacement);
        Ok(Output {
            result: ExcitationResult {
                kind: p.label(),
                params: p.kind.clone(),
                sample_rate_Hz: x.fs,
                samples: x.displacement.len(),
                rms_m: sigma,
                file: dmw_tracks::FILE,
            },
            summary_row: Some(ExcitationRow {
                kind: p.label(),
                duration_ms: p.duration * 1e3,
                samples: x.displacement.len(),
                rms_nm: sigma * 1e9,
            }),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artefacts::dmw_tracks::{read_dmw_track, read_dmw_tracks};

    #[test]
    fn written_tracks_read_back_through_the_artefact_reader() {
        let cfg: ExcitationConfig = toml::from_str("kind = \"sinusoid\"").unwrap();
        let p = check(&cfg).unwrap();
        let x = generate(&p).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(dmw_tracks::FILE);
        write_tracks(&path, "key", &p, &x).unwrap();
        let [t1, t2, t3] = read_dmw_tracks(&path).unwrap();
        // No filter: no edge transient, every sample kept.
        assert_eq!(t1.displacement, x.displacement);
        assert_eq!(t1.velocity, x.velocity);
        assert_eq!(t1.sample_rate, x.fs);
        let n = x.displacement.len();
        assert_eq!(t2.displacement[0], x.displacement[n - 1]);
        assert_eq!(t3.displacement[0], -x.displacement[n - 1]);
        assert_eq!(t3.velocity[0], x.velocity[n - 1]);
        assert_eq!(read_dmw_track(&path).unwrap().displacement, t1.displacement);
    }
}
