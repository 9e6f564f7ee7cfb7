//! The shipped synthetic sample data (`hdi synth afm`, `hdi synth ldv`). Deterministic:
//! fixed seeds, so the files are byte-identical on every run.

use crate::numerics::rng::Rng;
use crate::surface::io::{encode_gwy, encode_nanoscope};
use crate::surface::synth::{gaussian_acf_surface, GaussianSurfaceSpec};
use crate::surface::HeightMap;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Why sample data could not be written.
#[derive(Debug, thiserror::Error)]
pub enum SampleError {
    #[error("--revolutions must be at least 1")]
    NoRevolutions,
    #[error("unknown --format `{0}` (h5, h5-f64, csv, parquet)")]
    UnknownFormat(String),
    #[error("creating {}", path.display())]
    Create {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("writing {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Io(#[from] std::io::Error),
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A failure of the library code the generator uses (readers, writers, filters).
    #[error(transparent)]
    Hdi(#[from] crate::Error),
    #[error(transparent)]
    Dmw(#[from] crate::dmw::DmwError),
    #[error(transparent)]
    Signal(#[from] crate::signal::SignalError),
}

type Result<T> = std::result::Result<T, SampleError>;

/// Instrument-like defects on top of a clean field: a tilt, per-line offsets (a random walk,
/// as AFM line jumps look) and white measurement noise. Levelling is expected to remove the
/// first two; the noise stays.
pub struct Defects {
    pub tilt_x: f64,
    pub tilt_y: f64,
    pub line_offset_step: f64,
    pub noise: f64,
    pub seed: u64,
}

pub fn add_defects(map: &mut HeightMap, d: &Defects) {
    let mut rng = Rng::new(d.seed);
    let mut offset = 0.0;
    let (ny, nx) = map.z.dim();
    for j in 0..ny {
        offset += d.line_offset_step * rng.normal();
        for i in 0..nx {
            let x = i as f64 / nx as f64;
            let y = j as f64 / ny as f64;
            map.z[[j, i]] += d.tilt_x * x + d.tilt_y * y + offset + d.noise * rng.normal();
        }
    }
}

/// Revolutions in the shipped LDV sample: enough to show the √N noise reduction and the
/// speed wander, small enough to keep the file about a megabyte.
pub const SHIPPED_LDV_REVOLUTIONS: usize = 32;
/// ADC step of the shipped sample's velocity channel (0.5 mV: a 16-bit digitiser on ±16 V
/// would be coarser; 12-bit on ±1 V is this).
pub const SHIPPED_LDV_LSB: f64 = 0.5e-3;

/// The synthetic LDV record of `raw/ldv/` (or a variant for tests) and `samples.json` beside it
/// with the generator's parameters and the truth a processing chain should recover.
pub fn write_ldv_sample(
    dir: &Path,
    format: &str,
    revolutions: Option<usize>,
    seed: Option<u64>,
    with_index: bool,
) -> Result<Vec<PathBuf>> {
    use crate::artefacts::ldv::{write_ldv, write_ldv_hdf5_counts};
    use crate::dmw::io::LdvFormat;
    use crate::dmw::synthetic_ldv::{generate, truth_displacement, LdvSynthSpec};
    use crate::signal::butterworth::{butterworth_sos, FilterKind};
    let defaults = LdvSynthSpec::default();
    let spec = LdvSynthSpec {
        n_revolutions: revolutions.unwrap_or(SHIPPED_LDV_REVOLUTIONS),
        seed: seed.unwrap_or(defaults.seed),
        ..defaults
    };
    if spec.n_revolutions == 0 {
        return Err(SampleError::NoRevolutions);
    }
    std::fs::create_dir_all(dir).map_err(|source| SampleError::Create {
        path: dir.to_path_buf(),
        source,
    })?;
    let (mut rec, truth) = generate(&spec);
    if !with_index {
        rec.index = None;
    }
    let stem = format!("disk_md_{}rpm", spec.rpm);
    let path = match format {
        "h5" | "hdf5" => {
            let p = dir.join(format!("{stem}.h5"));
            write_ldv_hdf5_counts(&rec, &p, SHIPPED_LDV_LSB, 0.01)?;
            p
        }
        "h5-f64" => {
            let p = dir.join(format!("{stem}_f64.h5"));
            write_ldv(&rec, &p, LdvFormat::Hdf5)?;
            p
        }
        "csv" => {
            let p = dir.join(format!("{stem}.csv"));
            write_ldv(&rec, &p, LdvFormat::Csv)?;
            p
        }
        "parquet" => {
            let p = dir.join(format!("{stem}.parquet"));
            write_ldv(&rec, &p, LdvFormat::Parquet)?;
            p
        }
        other => return Err(SampleError::UnknownFormat(other.to_string())),
    };
    // What an ideal chain returns: the repeatable lines at mean speed through the default
    // zero-phase 10 kHz high-pass, over a 2.5 ms segment without its 0.3 ms edges.
    let n_p = truth.periods.len() as f64;
    let mean_period = truth.periods.iter().sum::<f64>() / n_p;
    let relstd = (truth
        .periods
        .iter()
        .map(|p| (p - mean_period).powi(2))
        .sum::<f64>()
        / n_p)
        .sqrt()
        / mean_period;
    let hp = butterworth_sos(4, 10e3, spec.sample_rate, FilterKind::HighPass)?;
    let times: Vec<f64> = (1200..8800).map(|i| i as f64 / spec.sample_rate).collect();
    let d = truth_displacement(&spec, &truth, mean_period, &times, Some(&hp));
    let m = d.iter().sum::<f64>() / d.len() as f64;
    let truth_std = (d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / d.len() as f64).sqrt();
    let info = json!({
        "file": path.file_name().map(|n| n.to_string_lossy().to_string()),
        "generator": "hdi synth ldv (src/dmw/synthetic_ldv.rs); model in docs/dmw.md",
        "parameters": spec.to_json(),
        "index_channel": with_index,
        "velocity_lsb_V": if format.starts_with("h5") && format != "h5-f64" { json!(SHIPPED_LDV_LSB) } else { json!(null) },
        "n_samples": rec.velocity.len(),
        "truth": {
            "n_trigger_edges": truth.trigger_times.len(),
            "first_trigger_s": truth.trigger_times.first(),
            "period_mean_s": mean_period,
            "period_relstd": relstd,
            "harmonic_phases_rad": truth.harmonic_phases,
            "dmw_std_m (zero-phase 10 kHz order-4 HP, mean speed, samples 1200..8800)": truth_std,
        },
    });
    let json_path = dir.join("samples.json");
    let text = serde_json::to_string_pretty(&info).map_err(SampleError::Json)?;
    crate::core::cache::write_atomic(&json_path, text.as_bytes()).map_err(|source| {
        SampleError::Write {
            path: json_path.clone(),
            source,
        }
    })?;
    Ok(vec![path, json_path])
}

/// The two sample height maps of `raw/afm/` and a JSON file with how they were made.
pub fn write_afm_samples(dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(SampleError::Io)?;
    // Disk-like: σ 0.34 nm; ℓ chosen so Nayak's R ≈ 0.43 µm (Table 2.2): for a Gaussian ACF
    // R = 0.375·√π·ℓ²/(√12·σ) ⇒ ℓ = 27.6 nm, and then η = 1/(π√3 ℓ²) ≈ 241 µm⁻².
    let disk_spec = GaussianSurfaceSpec {
        n: 256,
        size: 1e-6,
        sigma: 0.34e-9,
        correlation_length: 27.6e-9,
        seed: 2011_0001,
    };
    let disk_defects = Defects {
        tilt_x: 1.5e-9,
        tilt_y: -0.8e-9,
        line_offset_step: 0.02e-9,
        noise: 0.0,
        seed: 2011_0002,
    };
    // Slider-like: σ 0.38 nm (App. C.1 NanoScope value), ℓ = 40 nm, with line jumps and noise
    // as real AFM scans of a slider have.
    let slider_spec = GaussianSurfaceSpec {
        n: 256,
        size: 1e-6,
        sigma: 0.38e-9,
        correlation_length: 40e-9,
        seed: 2011_0003,
    };
    let slider_defects = Defects {
        tilt_x: -2.0e-9,
        tilt_y: 3.0e-9,
        line_offset_step: 0.05e-9,
        noise: 0.03e-9,
        seed: 2011_0004,
    };
    let mut disk = gaussian_acf_surface(&disk_spec);
    disk.periodic = false;
    disk.channel = "Height".into();
    add_defects(&mut disk, &disk_defects);
    let mut slider = gaussian_acf_surface(&slider_spec);
    slider.periodic = false;
    slider.channel = "Height Sensor".into();
    add_defects(&mut slider, &slider_defects);

    let disk_path = dir.join("disk_dlc_1um.gwy");
    let slider_path = dir.join("slider_tfc_1um.spm");
    crate::core::cache::write_atomic(&disk_path, &encode_gwy(&disk)).map_err(SampleError::Io)?;
    crate::core::cache::write_atomic(&slider_path, &encode_nanoscope(&slider, 2))
        .map_err(SampleError::Io)?;

    let describe = |spec: &GaussianSurfaceSpec, d: &Defects, file: &str, format: &str| {
        json!({
            "file": file, "format": format,
            "generator": "hdi synth afm (src/samples.rs): periodic Gaussian random field with Gaussian ACF σ²·exp(−r²/ℓ²), rescaled to σ exactly, then defects added",
            "nx": spec.n, "ny": spec.n, "size_m": spec.size,
            "sigma_m": spec.sigma, "correlation_length_m": spec.correlation_length, "seed": spec.seed,
            "nayak_continuum": {
                "R_m": 0.375 * std::f64::consts::PI.sqrt() * spec.correlation_length.powi(2) / (12f64.sqrt() * spec.sigma),
                "eta_per_m2": 1.0 / (std::f64::consts::PI * 3f64.sqrt() * spec.correlation_length.powi(2)),
            },
            "defects": {"tilt_x_m": d.tilt_x, "tilt_y_m": d.tilt_y,
                        "line_offset_random_walk_step_m": d.line_offset_step,
                        "white_noise_m": d.noise, "seed": d.seed},
        })
    };
    let meta = json!({
        "samples": [
            describe(&disk_spec, &disk_defects, "disk_dlc_1um.gwy", "Gwyddion native .gwy (f64, metres)"),
            describe(&slider_spec, &slider_defects, "slider_tfc_1um.spm", "Bruker NanoScope v9.2 (int16, ZSensor channel)"),
        ]
    });
    let meta_path = dir.join("samples.json");
    let text = serde_json::to_string_pretty(&meta).map_err(SampleError::Json)?;
    crate::core::cache::write_atomic(&meta_path, text.as_bytes()).map_err(SampleError::Io)?;
    Ok(vec![disk_path, slider_path, meta_path])
}

/// Heater powers of the shipped profilometer set (App. C.2 measured 0–90 mW).
pub const PROFILOMETER_POWERS_MW: [f64; 4] = [0.0, 30.0, 60.0, 90.0];
/// Bulge height without heater power (App. C.2: 2–5 nm even at 0 mW) and growth per power
/// (App. C.2: 0.3 nm/mW) of the shipped set.
pub const PROFILOMETER_H0: f64 = 3e-9;
pub const PROFILOMETER_EFFICIENCY: f64 = 0.3e-9 / 1e-3;

/// The synthetic profilometer scans of `raw/bulge/` (`hdi synth profilometer`, docs/bulge.md):
/// one Gwyddion `.gsf` per heater power (dx = 0.5 µm, dy = 1 µm) and `truth.json` with the
/// parameters a fit should recover.
pub fn write_profilometer_samples(dir: &Path) -> Result<Vec<PathBuf>> {
    use crate::surface::bulge::{synth_scan, ScanSpec};
    use crate::surface::io::encode_gsf;
    std::fs::create_dir_all(dir).map_err(|source| SampleError::Create {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut files = Vec::new();
    let mut scans = Vec::new();
    for (k, p_mw) in PROFILOMETER_POWERS_MW.into_iter().enumerate() {
        let height = PROFILOMETER_H0 + PROFILOMETER_EFFICIENCY * p_mw * 1e-3;
        let spec = ScanSpec::shipped(height, 2011_0100 + k as u64);
        let map = synth_scan(&spec);
        let name = format!("tfc_{p_mw:02.0}mW.gsf");
        let path = dir.join(&name);
        crate::core::cache::write_atomic(&path, &encode_gsf(&map)).map_err(SampleError::Io)?;
        files.push(path);
        scans.push(json!({
            "file": name, "heater_power_mW": p_mw, "height_m": height,
            "a_tfc_m": spec.a, "w_tfc_m": spec.w, "x_tfc_m": spec.x_tfc,
            "x_te_m": spec.x_te, "y_c_m": spec.yc,
            "nx": spec.nx, "ny": spec.ny, "dx_m": spec.dx, "dy_m": spec.dy,
            "pullup_m": spec.pullup, "pullup_length_m": spec.pullup_length,
            "te_drop_m": spec.drop, "tilt_x": spec.tilt_x, "tilt_y": spec.tilt_y,
            "offset_m": spec.offset, "noise_rms_m": spec.noise, "seed": spec.seed,
        }));
    }
    let meta = json!({
        "generator": "hdi synth profilometer (src/samples.rs, src/surface/bulge.rs synth_scan): ellipsoidal cap z = h·√(1 − ((x−x_c)/a)² − ((y−y_c)/(w/2))²) on a tilted plane, exponential pull-up before the trailing edge, drop beyond it, white noise; slider at x < x_te",
        "efficiency_m_per_W": PROFILOMETER_EFFICIENCY,
        "intercept_m": PROFILOMETER_H0,
        "scans": scans,
    });
    let meta_path = dir.join("truth.json");
    let text = serde_json::to_string_pretty(&meta).map_err(SampleError::Json)?;
    crate::core::cache::write_atomic(&meta_path, text.as_bytes()).map_err(SampleError::Io)?;
    files.push(meta_path);
    Ok(files)
}

/// The benchmarks' test signal (`hdi bench`, `benches/analysis.rs`, `bench/compare.py`): a
/// chirp 10 kHz → 500 kHz plus a 275 kHz line of amplitude 0.3, sampled at `fs`, so every CWT
/// scale of 5 kHz–1 MHz has something to see.
pub fn chirp_with_line(n: usize, fs: f64) -> Vec<f64> {
    use std::f64::consts::PI;
    let t_total = n as f64 / fs;
    (0..n)
        .map(|i| {
            let t = i as f64 / fs;
            (2.0 * PI * (10e3 * t + 0.5 * 490e3 / t_total * t * t)).cos()
                + 0.3 * (2.0 * PI * 275e3 * t).sin()
        })
        .collect()
}
