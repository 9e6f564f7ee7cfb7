//! `hdi bench`: the timing figures of docs/performance.md, each printed with its unit, the
//! number of timed repeats and the statistic (best of N after one untimed warm-up, with the
//! median beside it): the surfaces stage, the 2-DOF slider per accepted step, the 76-case
//! sweep, one 3-DOF case, the CWT and Hann spectrum kernels, roughness, the no-op cached rerun
//! and (with `--main-job`) the shipped pipeline run cold in a temp dir. `--json` prints the
//! same figures as one document (docs/schemas/bench.json); `--only` selects groups and
//! `--input FILE.npy` times a kernel on a given array, which is how `bench/compare.sh` gives
//! hdi and the Python anchors identical data (bench/README.md).

use anyhow::{bail, Context, Result};
use hdi::surface::io::encode_gwy;
use hdi::surface::synth::{gaussian_acf_surface, GaussianSurfaceSpec};
use hdi::surface::HeightMap;
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Sample rate the signal kernels assume (also for `--input`): the LDV records' 4 MS/s.
const FS: f64 = 4e6;

/// The figure groups, in the order they run; `--only` takes these names.
const GROUPS: [&str; 9] = [
    "surfaces",
    "two-dof",
    "sweep",
    "three-dof",
    "cwt",
    "fft",
    "roughness",
    "noop",
    "main-job",
];

/// What `hdi bench` was asked for (see `Command::Bench` in args.rs).
pub(super) struct BenchOptions {
    pub config: PathBuf,
    pub size: usize,
    pub json: bool,
    pub only: Vec<String>,
    pub main_job: bool,
    pub input: Option<PathBuf>,
    pub repeat: Option<usize>,
}

/// One printed figure.
struct Figure {
    group: &'static str,
    name: String,
    label: String,
    value: f64,
    unit: &'static str,
    /// "best" (of `repeats`, after a warm-up) or "single" (one cold run).
    statistic: &'static str,
    repeats: usize,
    median: Option<f64>,
    details: Map<String, Value>,
}

struct Out {
    json: bool,
    figures: Vec<Figure>,
}

impl Out {
    fn push(&mut self, f: Figure) {
        if !self.json {
            let stat = match (f.statistic, f.median) {
                ("best", Some(m)) => format!("best of {} (median {})", f.repeats, fmt(m)),
                ("best", None) => format!("best of {}", f.repeats),
                _ => "single run".to_string(),
            };
            // The counts behind the figure (steps, RHS evaluations, ms per case, …).
            let counts: Vec<String> = f
                .details
                .iter()
                .filter_map(|(k, v)| match v {
                    Value::Number(x) if x.is_f64() => Some(format!("{k} {}", fmt(x.as_f64()?))),
                    Value::Number(x) => Some(format!("{k} {x}")),
                    _ => None,
                })
                .collect();
            let counts = if counts.is_empty() {
                String::new()
            } else {
                format!("; {}", counts.join(", "))
            };
            println!(
                "{:<62} {:>10} {:<8} {stat}{counts}",
                f.label,
                fmt(f.value),
                f.unit
            );
        }
        self.figures.push(f);
    }
}

/// Four significant digits, enough for noisy timings.
fn fmt(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:.digits$}")
}

/// Timings of `repeats` runs of `f` after one untimed warm-up (caches, page faults, the rayon
/// pool): (best, median) seconds and the last result.
fn time_best<T>(repeats: usize, mut f: impl FnMut() -> Result<T>) -> Result<(f64, f64, T)> {
    let mut last = f()?;
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        last = f()?;
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let median = if times.len() % 2 == 1 {
        times[times.len() / 2]
    } else {
        0.5 * (times[times.len() / 2 - 1] + times[times.len() / 2])
    };
    Ok((times[0], median, last))
}

fn details(pairs: &[(&str, Value)]) -> Map<String, Value> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect()
}

/// `hdi bench`: figures for docs/performance.md.
pub(super) fn cmd_bench(o: BenchOptions) -> Result<()> {
    for g in &o.only {
        if !GROUPS.contains(&g.as_str()) {
            bail!(
                "--only: unknown group `{g}` (groups: {})",
                GROUPS.join(", ")
            );
        }
    }
    let wanted = |g: &str| -> bool {
        if o.only.is_empty() {
            g != "main-job" || o.main_job
        } else {
            o.only.iter().any(|x| x == g) || (g == "main-job" && o.main_job)
        }
    };
    if let Some(input) = &o.input {
        let kernels: Vec<&String> = o.only.iter().collect();
        if !(kernels.len() == 1 && ["cwt", "fft", "roughness"].contains(&kernels[0].as_str())) {
            bail!(
                "--input {}: give exactly one of --only cwt, --only fft, --only roughness \
                 (the kernel that times this array)",
                input.display()
            );
        }
    }
    if o.size < 8 {
        bail!("--size {}: the map needs at least 8 × 8 pixels", o.size);
    }
    let n = |default: usize| o.repeat.unwrap_or(default).max(1);
    let mut out = Out {
        json: o.json,
        figures: Vec::new(),
    };
    if !o.json {
        println!(
            "hdi {} bench, {} threads; every timing after one untimed warm-up",
            env!("CARGO_PKG_VERSION"),
            rayon::current_num_threads()
        );
    }
    if wanted("surfaces") {
        bench_surfaces(&mut out, o.size, n(3))?;
    }
    if wanted("two-dof") || wanted("sweep") {
        bench_two_dof(&mut out, wanted("two-dof"), wanted("sweep"), n(5), n(3))?;
    }
    if wanted("three-dof") {
        bench_three_dof(&mut out, n(3))?;
    }
    if wanted("cwt") {
        let x = match &o.input {
            Some(p) => read_npy_1d(p)?,
            None => series(1_000_000),
        };
        bench_cwt(&mut out, &x, n(3))?;
    }
    if wanted("fft") {
        let x = match &o.input {
            Some(p) => read_npy_1d(p)?,
            None => series(10_000_000),
        };
        bench_fft(&mut out, &x, n(5))?;
    }
    if wanted("roughness") {
        let map = match &o.input {
            Some(p) => read_npy_map(p, 4e-6)?,
            None => synthetic_map(o.size),
        };
        bench_roughness(&mut out, &map, n(5))?;
    }
    if wanted("noop") && o.config.is_file() {
        bench_noop(&mut out, &o.config, n(4))?;
    }
    if wanted("main-job") {
        bench_main_job(&mut out, &o.config, n(4))?;
    } else if !o.json && o.only.is_empty() {
        // Not estimated: a figure of the main job is a measured cold run or nothing.
        println!(
            "main job cold: not run (add --main-job: it runs {} cold in a temp dir, minutes)",
            o.config.display()
        );
    }
    if o.json {
        let figures: Vec<Value> = out
            .figures
            .iter()
            .map(|f| {
                json!({
                    "group": f.group,
                    "name": f.name,
                    "label": f.label,
                    "value": f.value,
                    "unit": f.unit,
                    "statistic": f.statistic,
                    "repeats": f.repeats,
                    "median": f.median,
                    "details": f.details,
                })
            })
            .collect();
        let doc = json!({
            "hdi_version": env!("CARGO_PKG_VERSION"),
            "threads": rayon::current_num_threads(),
            "input": o.input.as_ref().map(|p| p.to_string_lossy().into_owned()),
            "figures": figures,
        });
        println!("{}", serde_json::to_string_pretty(&doc)?);
    }
    Ok(())
}

/// The synthetic 1024² (`--size`) Gaussian-ACF map of the surfaces figures (σ 0.5 nm,
/// correlation length 40 nm over 4 µm), treated as non-periodic like a measured map.
fn synthetic_map(size: usize) -> HeightMap {
    let mut map = gaussian_acf_surface(&GaussianSurfaceSpec {
        n: size,
        size: 4e-6,
        sigma: 0.5e-9,
        correlation_length: 40e-9,
        seed: 7,
    });
    map.periodic = false;
    map
}

/// The shared benchmark signal (`hdi::samples::chirp_with_line`, also `benches/analysis.rs`).
fn series(n: usize) -> Vec<f64> {
    hdi::samples::chirp_with_line(n, FS)
}

/// A float `.npy` array (f8 or f4, either byte order, C or Fortran order): its shape and
/// values in C order.
fn read_npy(path: &Path) -> Result<(Vec<usize>, Vec<f64>)> {
    use hdi::formats::npy::{parse, Dtype};
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let h = parse(&bytes, bytes.len()).with_context(|| format!("{}", path.display()))?;
    let s = match h.dtype {
        Dtype::Scalar(s) if s.kind == 'f' && (s.size == 8 || s.size == 4) => s,
        _ => bail!(
            "{}: the array must hold float64 or float32 values",
            path.display()
        ),
    };
    let data = bytes
        .get(h.data_offset..h.data_offset + h.data_len())
        .with_context(|| {
            format!(
                "{}: the data is shorter than its header says",
                path.display()
            )
        })?;
    let values: Vec<f64> = data
        .chunks_exact(s.size)
        .map(|c| match (s.size, s.big_endian) {
            (8, false) => f64::from_le_bytes(c.try_into().unwrap_or([0; 8])),
            (8, true) => f64::from_be_bytes(c.try_into().unwrap_or([0; 8])),
            (_, false) => f32::from_le_bytes(c.try_into().unwrap_or([0; 4])) as f64,
            (_, true) => f32::from_be_bytes(c.try_into().unwrap_or([0; 4])) as f64,
        })
        .collect();
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        bail!("{}: value {i} is not finite", path.display());
    }
    let values = if h.fortran_order && h.shape.len() == 2 {
        let (a, b) = (h.shape[0], h.shape[1]);
        let mut c = vec![0.0; values.len()];
        for i in 0..a {
            for j in 0..b {
                c[i * b + j] = values[i + j * a];
            }
        }
        c
    } else {
        values
    };
    Ok((h.shape, values))
}

fn read_npy_1d(path: &Path) -> Result<Vec<f64>> {
    let (shape, values) = read_npy(path)?;
    if shape.len() != 1 || shape[0] < 16 {
        bail!(
            "{}: a 1-D signal of at least 16 samples is needed, the array has shape {shape:?}",
            path.display()
        );
    }
    Ok(values)
}

/// A 2-D `.npy` array as a height map in metres over `size_m` along x (square pixels).
fn read_npy_map(path: &Path, size_m: f64) -> Result<HeightMap> {
    let (shape, values) = read_npy(path)?;
    if shape.len() != 2 || shape[0] < 8 || shape[1] < 8 {
        bail!(
            "{}: a 2-D map of at least 8 × 8 pixels is needed, the array has shape {shape:?}",
            path.display()
        );
    }
    let z = ndarray::Array2::from_shape_vec((shape[0], shape[1]), values)
        .with_context(|| format!("{}: shape", path.display()))?;
    let dx = size_m / shape[1] as f64;
    Ok(HeightMap {
        z,
        dx,
        dy: dx,
        x0: 0.0,
        y0: 0.0,
        channel: "height".into(),
        valid: None,
        periodic: false,
        source: hdi::surface::SourceInfo {
            format: "npy".into(),
            header: Default::default(),
        },
        history: Vec::new(),
    })
}

/// The surfaces stage on a synthetic map written as `.gwy` (read + level + roughness + scale
/// sweep, then with the HDF5 and PNG outputs).
fn bench_surfaces(out: &mut Out, size: usize, repeats: usize) -> Result<()> {
    use hdi::stages::surfaces::{analyse, check, write_outputs, SurfaceConfig};
    let tmp = TempDir::new("surfaces")?;
    let spec = GaussianSurfaceSpec {
        n: size,
        size: 4e-6,
        sigma: 0.5e-9,
        correlation_length: 40e-9,
        seed: 7,
    };
    let file = tmp.path().join("bench.gwy");
    std::fs::write(&file, encode_gwy(&gaussian_acf_surface(&spec)))?;
    let cfg: SurfaceConfig = toml::from_str(&format!("file = {:?}", file.to_string_lossy()))?;
    let params = check(&cfg, file.clone()).map_err(|e| anyhow::anyhow!("{e}"))?;
    let (best, median, _) = time_best(repeats, || Ok(analyse(&params)?))?;
    out.push(Figure {
        group: "surfaces",
        name: "surfaces_stage_analyse".into(),
        label: format!("surfaces stage, {size}² map (read+level+roughness+scale sweep)"),
        value: best,
        unit: "s",
        statistic: "best",
        repeats,
        median: Some(median),
        details: details(&[("pixels", json!(size * size))]),
    });
    let (best, median, _) = time_best(repeats, || {
        let a = analyse(&params)?;
        write_outputs(
            &a,
            &params,
            &tmp.path().join("out.h5"),
            Some(tmp.path()),
            "bench",
            &json!([]),
        )?;
        Ok(())
    })?;
    out.push(Figure {
        group: "surfaces",
        name: "surfaces_stage_with_outputs".into(),
        label: format!("surfaces stage, {size}² map incl. HDF5 + PNG outputs"),
        value: best,
        unit: "s",
        statistic: "best",
        repeats,
        median: Some(median),
        details: details(&[("pixels", json!(size * size))]),
    });
    Ok(())
}

/// The 2-DOF slider figures: one 2 ms case at 8.5 and 12 nm (µs per accepted step) and the
/// 76-case sweep 0–15 nm on all threads; improved model, spec defaults, the spec's synthetic
/// DMW (σ 1 nm), static initialisation (what the sweep stage runs).
fn bench_two_dof(
    out: &mut Out,
    cases: bool,
    sweep: bool,
    repeats: usize,
    sweep_repeats: usize,
) -> Result<()> {
    use hdi::contact::isbl::{IsblModel, IsblParams};
    use hdi::contact::lookup::IsblLookup;
    use hdi::dmw::excitation_tracks::synthetic_dmw;
    use hdi::dynamics::params::improved_2dof;
    use hdi::dynamics::two_dof::{DmwInput, SimOptions, TwoDofCase};
    use hdi::numerics::ode::OdeStats;
    use rayon::prelude::*;
    let isbl = IsblLookup::build_standard(IsblModel::new(IsblParams::improved_2dof())?)?;
    let track = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1)?;
    let dmw = || {
        Some(DmwInput {
            displacement: &track.displacement,
            velocity: &track.velocity,
            sample_rate: track.fs,
        })
    };
    let model = improved_2dof();
    let options = SimOptions {
        static_init: true,
        ..SimOptions::default()
    };
    let run = |h: f64| -> Result<OdeStats> {
        let case = TwoDofCase::new(&model, h, &isbl, dmw(), options)?;
        Ok(case.run()?.stats)
    };
    if cases {
        for h in [8.5e-9, 12e-9] {
            let (best, median, stats) = time_best(repeats, || run(h))?;
            let steps = stats.accepted_steps.max(1) as f64;
            out.push(Figure {
                group: "two-dof",
                name: format!("two_dof_{}nm_us_per_step", fmt_nm(h)),
                label: format!(
                    "2-DOF, one 2 ms case at {} nm: time per accepted step",
                    fmt_nm(h)
                ),
                value: best / steps * 1e6,
                unit: "µs/step",
                statistic: "best",
                repeats,
                median: Some(median / steps * 1e6),
                details: details(&[
                    ("accepted_steps", json!(stats.accepted_steps)),
                    ("rejected_steps", json!(stats.rejected_steps)),
                    ("rhs_evaluations", json!(stats.rhs_evaluations)),
                    ("case_ms", json!(best * 1e3)),
                    (
                        "us_per_rhs_evaluation",
                        json!(best / stats.rhs_evaluations.max(1) as f64 * 1e6),
                    ),
                ]),
            });
        }
    }
    if sweep {
        let (best, median, steps) = time_best(sweep_repeats, || {
            let stats: Vec<Result<OdeStats>> = (0..76)
                .into_par_iter()
                .map(|i| run(i as f64 * 0.2e-9))
                .collect();
            let mut steps = 0;
            for s in stats {
                steps += s?.accepted_steps;
            }
            Ok(steps)
        })?;
        out.push(Figure {
            group: "sweep",
            name: "two_dof_sweep_76_cases".into(),
            label: format!(
                "2-DOF, 76-case sweep 0–15 nm on {} threads",
                rayon::current_num_threads()
            ),
            value: best,
            unit: "s",
            statistic: "best",
            repeats: sweep_repeats,
            median: Some(median),
            details: details(&[
                ("cases", json!(76)),
                ("accepted_steps", json!(steps)),
                ("threads", json!(rayon::current_num_threads())),
            ]),
        });
    }
    Ok(())
}

fn fmt_nm(h: f64) -> String {
    let nm = h * 1e9;
    if (nm - nm.round()).abs() < 1e-9 {
        format!("{}", nm.round() as i64)
    } else {
        format!("{nm:.1}")
    }
}

/// One 2 ms 3-DOF case at constant 12 nm with the ISBL interface on the spec's synthetic DMW
/// (tracks D1–D3 as in benches/three_dof.rs).
fn bench_three_dof(out: &mut Out, repeats: usize) -> Result<()> {
    use hdi::contact::isbl::{IsblModel, IsblParams};
    use hdi::contact::lookup::IsblLookup;
    use hdi::dmw::excitation_tracks::synthetic_dmw;
    use hdi::dynamics::three_dof::case::{Model3Dof, Options3Dof, ThreeDofCase};
    use hdi::dynamics::three_dof::inputs::ActuationProfile;
    use hdi::dynamics::three_dof::interface::{FeatureInterface, InterfaceLaw};
    use hdi::dynamics::two_dof::{ContactForceForm, DmwInput};
    let isbl = IsblLookup::build_standard(IsblModel::new(IsblParams::three_dof())?)?;
    let d = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1)?;
    let flip = |x: &[f64], s: f64| x.iter().rev().map(|v| s * v).collect::<Vec<_>>();
    let (d2, v2, d3, v3) = (
        flip(&d.displacement, 1.0),
        flip(&d.velocity, -1.0),
        flip(&d.displacement, -1.0),
        flip(&d.velocity, 1.0),
    );
    fn track<'a>(x: &'a [f64], v: &'a [f64], fs: f64) -> DmwInput<'a> {
        DmwInput {
            displacement: x,
            velocity: v,
            sample_rate: fs,
        }
    }
    let model = Model3Dof::dissertation();
    let mass = model.air_bearing.slider.mass;
    let (best, median, stats) = time_best(repeats, || {
        let interface = FeatureInterface::new(
            &isbl,
            InterfaceLaw::Isbl,
            ContactForceForm::InterferenceTangent,
            0.05,
            mass,
        )?;
        let case = ThreeDofCase::new(
            &model,
            interface,
            ActuationProfile::constant(12e-9)?,
            None,
            Some([
                track(&d.displacement, &d.velocity, d.fs),
                track(&d2, &v2, d.fs),
                track(&d3, &v3, d.fs),
            ]),
            Options3Dof::default(),
        )?;
        Ok(case.run()?.stats)
    })?;
    let steps = stats.accepted_steps.max(1) as f64;
    out.push(Figure {
        group: "three-dof",
        name: "three_dof_12nm_case".into(),
        label: "3-DOF, one 2 ms case at 12 nm (ISBL, synthetic DMW)".into(),
        value: best * 1e3,
        unit: "ms",
        statistic: "best",
        repeats,
        median: Some(median * 1e3),
        details: details(&[
            ("accepted_steps", json!(stats.accepted_steps)),
            ("rejected_steps", json!(stats.rejected_steps)),
            ("rhs_evaluations", json!(stats.rhs_evaluations)),
            ("us_per_step", json!(best / steps * 1e6)),
        ]),
    });
    Ok(())
}

/// CWT magnitude (analytic Morlet ω0 = 6, f32 output) at 100 log-spaced frequencies
/// 5 kHz–1 MHz, fs = 4 MHz.
fn bench_cwt(out: &mut Out, x: &[f64], repeats: usize) -> Result<()> {
    use hdi::analysis::cwt::{cwt_morlet, CwtOptions, FrequencyGrid};
    let opts = CwtOptions {
        frequencies: FrequencyGrid::Log {
            f_min_hz: 5e3,
            f_max_hz: 1e6,
            count: 100,
        },
        ..Default::default()
    };
    let (best, median, rows) = time_best(repeats, || {
        Ok(cwt_morlet(x, FS, &opts)?.frequencies_hz.len())
    })?;
    out.push(Figure {
        group: "cwt",
        name: "cwt_morlet_100_frequencies".into(),
        label: format!(
            "CWT, {} samples × {rows} frequencies (5 kHz–1 MHz, f32)",
            x.len()
        ),
        value: best,
        unit: "s",
        statistic: "best",
        repeats,
        median: Some(median),
        details: details(&[("samples", json!(x.len())), ("frequencies", json!(rows))]),
    });
    Ok(())
}

/// One-sided Hann amplitude spectrum (mean removed, window, transform, scaling).
fn bench_fft(out: &mut Out, x: &[f64], repeats: usize) -> Result<()> {
    use hdi::analysis::series::spectrum;
    use hdi::signal::spectrum::Window;
    let (best, median, _) = time_best(repeats, || Ok(spectrum(x, FS, Window::Hann)?))?;
    out.push(Figure {
        group: "fft",
        name: "hann_amplitude_spectrum".into(),
        label: format!("Hann amplitude spectrum, {} samples", x.len()),
        value: best,
        unit: "s",
        statistic: "best",
        repeats,
        median: Some(median),
        details: details(&[("samples", json!(x.len()))]),
    });
    Ok(())
}

/// What `hdi surface` computes on an already-read map: a `plane` levelling, then the whole
/// roughness evaluation (heights, 9-point summits, derivative moments, Nayak, histograms) with
/// default options — the calls bench/roughness_surfacetopography.py times on its side.
fn bench_roughness(out: &mut Out, map: &HeightMap, repeats: usize) -> Result<()> {
    use hdi::surface::level::{level, LevelOp};
    use hdi::surface::roughness::{roughness, RoughnessOptions};
    let plane: LevelOp = "plane"
        .parse()
        .map_err(|e| anyhow::anyhow!("level op: {e}"))?;
    let (best, median, _) = time_best(repeats, || {
        let mut m = map.clone();
        level(&mut m, std::slice::from_ref(&plane))?;
        Ok(roughness(&m, &RoughnessOptions::default())?)
    })?;
    out.push(Figure {
        group: "roughness",
        name: "roughness_default".into(),
        label: format!(
            "roughness, {}×{} map (plane level + default evaluation)",
            map.ny(),
            map.nx()
        ),
        value: best,
        unit: "s",
        statistic: "best",
        repeats,
        median: Some(median),
        details: details(&[("pixels", json!(map.ny() * map.nx()))]),
    });
    Ok(())
}

/// `hdi run --config CONFIG` as a child process; its wall time and stderr.
fn run_pipeline(config: &Path) -> Result<(f64, String)> {
    let exe = std::env::current_exe()?;
    let t = Instant::now();
    let o = std::process::Command::new(&exe)
        .args(["run", "--config"])
        .arg(config)
        .output()
        .context("running hdi run")?;
    let secs = t.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    if !o.status.success() {
        bail!(
            "hdi run --config {} failed: {}",
            config.display(),
            err.lines().last().unwrap_or("")
        );
    }
    Ok((secs, err))
}

/// The no-op cached rerun of `config` (the first run may do real work and is the warm-up).
fn bench_noop(out: &mut Out, config: &Path, repeats: usize) -> Result<()> {
    let (best, median, _) = time_best(repeats, || run_pipeline(config).map(|_| ()))?;
    out.push(Figure {
        group: "noop",
        name: "noop_cached_rerun".into(),
        label: format!("no-op cached rerun of {}", config.display()),
        value: best,
        unit: "s",
        statistic: "best",
        repeats,
        median: Some(median),
        details: Map::new(),
    });
    Ok(())
}

/// The main job measured, not estimated: `CONFIG` and the `raw/` beside it copied into a temp
/// dir, `hdi run` there from scratch (one cold run; the per-stage wall times are the ones
/// `hdi run` logs as `ran NAME (S s)`), then its no-op rerun.
fn bench_main_job(out: &mut Out, config: &Path, repeats: usize) -> Result<()> {
    if !config.is_file() {
        bail!(
            "--main-job: {} not found (run it where the shipped pipeline.toml and raw/ are, or \
             give --config)",
            config.display()
        );
    }
    let from = config.parent().unwrap_or(Path::new("."));
    let from = if from.as_os_str().is_empty() {
        Path::new(".")
    } else {
        from
    };
    let tmp = TempDir::new("main-job")?;
    let raw = from.join("raw");
    if raw.is_dir() {
        copy_dir(&raw, &tmp.path().join("raw"))?;
    }
    let cfg = tmp.path().join("pipeline.toml");
    std::fs::copy(config, &cfg).with_context(|| format!("copying {}", config.display()))?;
    if !out.json {
        eprintln!("main job: running {} cold in a temp dir…", config.display());
    }
    let (secs, log) = run_pipeline(&cfg)?;
    let stages: Vec<(String, f64)> = log
        .lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("ran     ")?;
            let (name, t) = rest.rsplit_once(" (")?;
            let t = t.strip_suffix(" s)")?.parse::<f64>().ok()?;
            Some((name.to_string(), t))
        })
        .collect();
    let stage_details: Map<String, Value> =
        stages.iter().map(|(n, t)| (n.clone(), json!(t))).collect();
    out.push(Figure {
        group: "main-job",
        name: "main_job_cold".into(),
        label: format!("main job cold ({}, fresh temp dir)", config.display()),
        value: secs,
        unit: "s",
        statistic: "single",
        repeats: 1,
        median: None,
        details: details(&[
            ("stages_ran", json!(stages.len())),
            ("stage_wall_s", Value::Object(stage_details)),
        ]),
    });
    let mut sorted = stages.clone();
    sorted.sort_by(|a, b| b.1.total_cmp(&a.1));
    for (name, t) in sorted {
        out.push(Figure {
            group: "main-job",
            name: format!("main_job_stage_{name}"),
            label: format!("  stage {name}"),
            value: t,
            unit: "s",
            statistic: "single",
            repeats: 1,
            median: None,
            details: Map::new(),
        });
    }
    let (best, median, _) = time_best(repeats, || run_pipeline(&cfg).map(|_| ()))?;
    out.push(Figure {
        group: "main-job",
        name: "main_job_noop_rerun".into(),
        label: "main job, no-op cached rerun".into(),
        value: best,
        unit: "s",
        statistic: "best",
        repeats,
        median: Some(median),
        details: Map::new(),
    });
    Ok(())
}

fn copy_dir(from: &Path, to: &Path) -> Result<()> {
    std::fs::create_dir_all(to)?;
    for e in std::fs::read_dir(from)? {
        let e = e?;
        let p = e.path();
        if e.file_type()?.is_dir() {
            copy_dir(&p, &to.join(e.file_name()))?;
        } else {
            std::fs::copy(&p, to.join(e.file_name()))
                .with_context(|| format!("copying {}", p.display()))?;
        }
    }
    Ok(())
}

/// A scratch directory under the system temp dir, removed when dropped (`tempfile` is a
/// dev-dependency only).
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> Result<Self> {
        let p = std::env::temp_dir().join(format!("hdi-bench-{}-{tag}", std::process::id()));
        std::fs::create_dir_all(&p).with_context(|| format!("creating {}", p.display()))?;
        Ok(Self(p))
    }
    fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
