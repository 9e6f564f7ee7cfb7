//! The surfaces stage and the signal and roughness kernels.

use super::main_job::ScratchDir;
use super::{time_best, BenchError, Details, Figure, Figures, Group, Result, Unit, FS};
use crate::surface::io::encode_gwy;
use crate::surface::synth::{gaussian_acf_surface, GaussianSurfaceSpec};
use crate::surface::HeightMap;
use serde_json::json;

/// The synthetic Gaussian-ACF map (σ 0.5 nm, correlation length 40 nm over 4 µm).
fn synthetic_spec(size: usize) -> GaussianSurfaceSpec {
    GaussianSurfaceSpec {
        n: size,
        size: 4e-6,
        sigma: 0.5e-9,
        correlation_length: 40e-9,
        seed: 7,
    }
}

/// The synthetic 1024² (`--size`) map of the surfaces figures, treated as non-periodic like a
/// measured map.
pub(super) fn synthetic_map(size: usize) -> HeightMap {
    let mut map = gaussian_acf_surface(&synthetic_spec(size));
    map.periodic = false;
    map
}

/// The shared benchmark signal (`crate::samples::chirp_with_line`, also `benches/analysis.rs`).
pub(super) fn series(n: usize) -> Vec<f64> {
    crate::samples::chirp_with_line(n, FS)
}

/// The surfaces stage on a synthetic map written as `.gwy` (read + level + roughness + scale
/// sweep, then with the HDF5 and PNG outputs).
pub(super) fn surfaces(out: &mut Figures, size: usize, repeats: usize) -> Result<()> {
    use crate::stages::surfaces::{analyse, check, write_outputs, SurfaceConfig};
    let tmp = ScratchDir::new("surfaces")?;
    let file = tmp.path().join("bench.gwy");
    std::fs::write(
        &file,
        encode_gwy(&gaussian_acf_surface(&synthetic_spec(size))),
    )
    .map_err(BenchError::io("writing", &file))?;
    let cfg: SurfaceConfig = toml::from_str(&format!("file = {:?}", file.to_string_lossy()))?;
    let params = check(&cfg, file.clone())?;
    let pixels = || Details {
        pixels: Some(size * size),
        ..Details::default()
    };
    let (times, _) = time_best(repeats, || Ok(analyse(&params)?))?;
    out.push(Figure::best(
        Group::Surfaces,
        "surfaces_stage_analyse",
        format!("surfaces stage, {size}² map (read+level+roughness+scale sweep)"),
        times,
        Unit::Seconds,
        repeats,
        pixels(),
    ));
    let (times, _) = time_best(repeats, || {
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
    out.push(Figure::best(
        Group::Surfaces,
        "surfaces_stage_with_outputs",
        format!("surfaces stage, {size}² map incl. HDF5 + PNG outputs"),
        times,
        Unit::Seconds,
        repeats,
        pixels(),
    ));
    Ok(())
}

/// CWT magnitude (analytic Morlet ω0 = 6, f32 output) at 100 log-spaced frequencies
/// 5 kHz–1 MHz, fs = 4 MHz.
pub(super) fn cwt(out: &mut Figures, x: &[f64], repeats: usize) -> Result<()> {
    use crate::analysis::cwt::{cwt_morlet, CwtOptions, FrequencyGrid};
    let opts = CwtOptions {
        frequencies: FrequencyGrid::Log {
            f_min_hz: 5e3,
            f_max_hz: 1e6,
            count: 100,
        },
        ..Default::default()
    };
    let (times, rows) = time_best(repeats, || {
        Ok(cwt_morlet(x, FS, &opts)?.frequencies_hz.len())
    })?;
    out.push(Figure::best(
        Group::Cwt,
        "cwt_morlet_100_frequencies",
        format!(
            "CWT, {} samples × {rows} frequencies (5 kHz–1 MHz, f32)",
            x.len()
        ),
        times,
        Unit::Seconds,
        repeats,
        Details {
            samples: Some(x.len()),
            frequencies: Some(rows),
            ..Details::default()
        },
    ));
    Ok(())
}

/// The whole `hdi analyze` of a series (spectrum, CWT, red-noise significance, Poincaré
/// section, class) beside its bare CWT, and the coherence Monte Carlo of a 10⁴-sample pair
/// with 300 AR(1) surrogates (docs/performance.md, "Significance").
pub(super) fn significance(out: &mut Figures, x: &[f64], repeats: usize) -> Result<()> {
    use crate::analysis::coherence::{coherence_levels, MonteCarlo};
    use crate::analysis::cwt::{cwt_morlet, CwtOptions, FrequencyGrid};
    use crate::analysis::report::{analyze, AnalyzeOptions};
    let opts = CwtOptions {
        frequencies: FrequencyGrid::Log {
            f_min_hz: 5e3,
            f_max_hz: 1e6,
            count: 100,
        },
        ..Default::default()
    };
    let (bare, _) = time_best(repeats, || Ok(cwt_morlet(x, FS, &opts)?.n_time))?;
    let (whole, r) = time_best(repeats, || {
        Ok(analyze(x, None, FS, 0.0, &AnalyzeOptions::default())?)
    })?;
    let details = Details {
        samples: Some(x.len()),
        frequencies: Some(r.scalogram.frequencies_hz.len()),
        ..Details::default()
    };
    out.push(Figure::best(
        Group::Significance,
        "bare_cwt_100_frequencies",
        format!("CWT alone, {} samples × 100 frequencies", x.len()),
        bare,
        Unit::Seconds,
        repeats,
        details.clone(),
    ));
    out.push(Figure::best(
        Group::Significance,
        "analyze_with_significance",
        format!(
            "the whole analysis (spectrum, CWT, AR(1) significance, Poincaré, class), {} samples",
            x.len()
        ),
        whole,
        Unit::Seconds,
        repeats,
        details,
    ));
    let n = 10_000;
    let mc = MonteCarlo::default();
    let grid = CwtOptions {
        frequencies: FrequencyGrid::Log {
            f_min_hz: 5e3,
            f_max_hz: 1e6,
            count: 100,
        },
        ..Default::default()
    };
    let (times, levels) = time_best(repeats, || {
        Ok(coherence_levels(n, FS, &grid, 0.9, 0.5, &mc)?)
    })?;
    out.push(Figure::best(
        Group::Significance,
        "coherence_monte_carlo_300",
        format!(
            "coherence levels: {} AR(1) surrogate pairs of {n} samples × {} frequencies",
            mc.surrogates,
            levels.len()
        ),
        times,
        Unit::Seconds,
        repeats,
        Details {
            samples: Some(n),
            frequencies: Some(levels.len()),
            ..Details::default()
        },
    ));
    Ok(())
}

/// One-sided Hann amplitude spectrum (mean removed, window, transform, scaling).
pub(super) fn fft(out: &mut Figures, x: &[f64], repeats: usize) -> Result<()> {
    use crate::analysis::series::spectrum;
    use crate::signal::spectrum::Window;
    let (times, _) = time_best(repeats, || Ok(spectrum(x, FS, Window::Hann)?))?;
    out.push(Figure::best(
        Group::Fft,
        "hann_amplitude_spectrum",
        format!("Hann amplitude spectrum, {} samples", x.len()),
        times,
        Unit::Seconds,
        repeats,
        Details {
            samples: Some(x.len()),
            ..Details::default()
        },
    ));
    Ok(())
}

/// What `hdi surface` computes on an already-read map: a `plane` levelling, then the whole
/// roughness evaluation (heights, 9-point summits, derivative moments, Nayak, histograms) with
/// default options — the calls bench/roughness_surfacetopography.py times on its side.
pub(super) fn roughness(out: &mut Figures, map: &HeightMap, repeats: usize) -> Result<()> {
    use crate::surface::level::{level, LevelOp};
    use crate::surface::roughness::{roughness, RoughnessOptions};
    let plane = [LevelOp::Plane];
    let (times, _) = time_best(repeats, || {
        let mut m = map.clone();
        level(&mut m, &plane)?;
        Ok(roughness(&m, &RoughnessOptions::default())?)
    })?;
    out.push(Figure::best(
        Group::Roughness,
        "roughness_default",
        format!(
            "roughness, {}×{} map (plane level + default evaluation)",
            map.ny(),
            map.nx()
        ),
        times,
        Unit::Seconds,
        repeats,
        Details {
            pixels: Some(map.ny() * map.nx()),
            ..Details::default()
        },
    ));
    Ok(())
}

/// The BEM's reduced load on a bench map: `p̄ = 0.05·E*·h′_rms` (A_r/A_0 ≈ 10 %, κ ≈ 2), with
/// `h′_rms² = mean((Δ_x h/dx)² + (Δ_y h/dy)²)` by periodic forward differences — the load
/// bench/compare.py gives tamaas.
pub(super) const BEM_LOAD: f64 = 0.05;
/// Tolerance of the timed solves, the same number bench/compare.py gives tamaas.
pub(super) const BEM_TOLERANCE: f64 = 1e-10;

/// One pressure-controlled load step of the map with `E*` = 1 Pa, periodic, cold-started
/// (`bem_periodic_load_step`), and non-periodic on the 2n × 2n padded grid
/// (`bem_non_periodic_load_step`); iterations and memory in the details.
pub(super) fn bem(out: &mut Figures, map: &HeightMap, repeats: usize) -> Result<()> {
    use crate::contact::bem::{BemSolver, Boundary, SolverSettings, Target};
    let (ny, nx) = (map.ny(), map.nx());
    let h: Vec<f64> = map.z.iter().copied().collect();
    let (dx, dy) = (map.dx, map.dy);
    let mut slope2 = 0.0;
    for j in 0..ny {
        for i in 0..nx {
            let here = h[j * nx + i];
            let gx = (h[j * nx + (i + 1) % nx] - here) / dx;
            let gy = (h[((j + 1) % ny) * nx + i] - here) / dy;
            slope2 += gx * gx + gy * gy;
        }
    }
    let load = BEM_LOAD * (slope2 / (nx * ny) as f64).sqrt();
    let settings = SolverSettings {
        tolerance: BEM_TOLERANCE,
        max_iterations: 10_000,
    };
    for (boundary, name, what) in [
        (Boundary::Periodic, "bem_periodic_load_step", "periodic"),
        (
            Boundary::NonPeriodic,
            "bem_non_periodic_load_step",
            "non-periodic, padded 2n × 2n",
        ),
    ] {
        let solver = BemSolver::new(&h, nx, ny, (dx, dy), 1.0, boundary)?;
        let (times, s) = time_best(repeats, || {
            Ok(solver.solve(Target::MeanPressure(load), &settings, None)?)
        })?;
        out.push(Figure::best(
            Group::Bem,
            name,
            format!(
                "BEM load step, {ny}×{nx} map, {what}, p̄ = 0.05 E* h′_rms, tolerance {:e} \
                 (A_r/A_0 = {:.4})",
                BEM_TOLERANCE, s.contact_fraction
            ),
            times,
            Unit::Seconds,
            repeats,
            Details {
                pixels: Some(nx * ny),
                iterations: Some(s.iterations),
                memory_bytes: Some(solver.memory_bytes()),
                ..Details::default()
            },
        ));
    }
    Ok(())
}

/// The streaming band CWT (`analysis::streaming`, what `hdi analyze --stream` runs) on a
/// generated record of `samples` samples at 4 MS/s — a 100 kHz tone of amplitude 1 plus
/// uniform noise of amplitude 0.5, computed inside the reader so that no record is held —
/// at 10 log-spaced frequencies 90–120 kHz, decimate 1000: both passes (mean, transform).
pub(super) fn stream(out: &mut Figures, samples: usize, repeats: usize) -> Result<()> {
    use crate::analysis::cwt::{FrequencyGrid, Wavelet};
    use crate::analysis::streaming::{band_cwt, series_mean, BandOptions, BandPlan, StreamError};
    use std::convert::Infallible;
    let opts = BandOptions {
        wavelet: Wavelet::default(),
        frequencies: FrequencyGrid::Log {
            f_min_hz: 90e3,
            f_max_hz: 120e3,
            count: 10,
        },
        decimate: 1000,
        block: None,
    };
    let plan = BandPlan::new(samples, FS, &opts)?;
    let read = |start: usize, buf: &mut [f64]| -> std::result::Result<(), Infallible> {
        for (i, v) in buf.iter_mut().enumerate() {
            let k = (start + i) as u64;
            // splitmix64 of the index: noise that any block reproduces on its own.
            let mut z = k.wrapping_add(1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            let u = (z ^ (z >> 31)) as f64 / u64::MAX as f64 - 0.5;
            let t = k as f64 / FS;
            *v = (2.0 * std::f64::consts::PI * 100e3 * t).cos() + u;
        }
        Ok(())
    };
    let unwrap = |e: StreamError<Infallible>| match e {
        StreamError::Analysis(a) => BenchError::Analysis(a),
        StreamError::Read { error, .. } => match error {},
    };
    let (times, r) = time_best(repeats, || {
        let mean = series_mean(samples, plan.fft_len, read).map_err(unwrap)?;
        band_cwt(&plan, mean, read).map_err(unwrap)
    })?;
    out.push(Figure::best(
        Group::Stream,
        "stream_band_cwt_10_frequencies",
        format!(
            "streaming band CWT, {samples} samples × {} frequencies (90–120 kHz, decimate {})",
            plan.frequencies_hz.len(),
            plan.decimate
        ),
        times,
        Unit::Seconds,
        repeats,
        Details {
            samples: Some(samples),
            frequencies: Some(plan.frequencies_hz.len()),
            memory_bytes: Some(r.working_bytes),
            peak_rss_bytes: super::readers::peak_rss_bytes(),
            ..Details::default()
        },
    ));
    Ok(())
}
