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
