//! criterion benches of the surfaces kernels on a 1024 × 1024 map and of the binary readers
//! (not run in CI).
use criterion::{criterion_group, criterion_main, Criterion};
use hdi::surface::filter::gaussian_lowpass;
use hdi::surface::io::{read_height_map, ReadOptions};
use hdi::surface::level::{level, LevelOp};
use hdi::surface::roughness::{roughness, scale_sweep_with, RoughnessOptions};
use hdi::surface::spectra;
use hdi::surface::synth::{gaussian_acf_surface, GaussianSurfaceSpec};

fn surfaces(c: &mut Criterion) {
    let spec = GaussianSurfaceSpec {
        n: 1024,
        size: 4e-6,
        sigma: 0.5e-9,
        correlation_length: 40e-9,
        seed: 7,
    };
    let mut map = gaussian_acf_surface(&spec);
    map.periodic = false;
    let recipe: Vec<LevelOp> = ["rows:median", "plane", "mean"]
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    let mut g = c.benchmark_group("surfaces_1024");
    g.sample_size(10);
    g.bench_function("level_default_recipe", |b| {
        b.iter(|| {
            let mut m = map.clone();
            level(&mut m, &recipe).unwrap();
            m
        })
    });
    g.bench_function("roughness_9pt", |b| {
        b.iter(|| roughness(&map, &RoughnessOptions::default()).unwrap())
    });
    // The stage's sweep: it reuses the full-resolution report, as `stages::surfaces::analyse`.
    let full = roughness(&map, &RoughnessOptions::default()).unwrap();
    g.bench_function("scale_sweep_reusing_full_report", |b| {
        b.iter(|| scale_sweep_with(&map, &RoughnessOptions::default(), Some(&full)).unwrap())
    });
    g.bench_function("gaussian_filter_mirror", |b| {
        b.iter(|| gaussian_lowpass(&map.z, map.dx, map.dy, 16.0 * map.dx, false))
    });
    // Surface analyses (docs/surfaces.md, "Surface analyses"): each curve, all of them as the
    // stage computes them, and the tip cutoff for a radius that puts it inside the bandwidth.
    g.bench_function("psd_profile", |b| {
        b.iter(|| spectra::psd_profile(&map).unwrap())
    });
    g.bench_function("psd_area", |b| b.iter(|| spectra::psd_area(&map).unwrap()));
    g.bench_function("acf_profile", |b| {
        b.iter(|| spectra::acf_profile(&map).unwrap())
    });
    g.bench_function("acf_area", |b| b.iter(|| spectra::acf_area(&map).unwrap()));
    g.bench_function("surface_analyses_all_curves", |b| {
        b.iter(|| spectra::surface_analyses(&map).unwrap())
    });
    let tip_radius = 1e-6;
    eprintln!(
        "tip cutoff for R = {tip_radius:e} m: {:?}",
        spectra::tip_reliability_cutoff(&map, tip_radius).unwrap()
    );
    g.bench_function("tip_reliability_cutoff", |b| {
        b.iter(|| spectra::tip_reliability_cutoff(&map, tip_radius).unwrap())
    });
    g.bench_function("synth_gaussian_acf", |b| {
        b.iter(|| gaussian_acf_surface(&spec))
    });
    g.finish();

    // Reader throughput on the largest real samples (tests/data/surfaces, tests/data/README.md):
    // bytes per second = file size / time per read.
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/surfaces");
    let mut g = c.benchmark_group("readers");
    g.sample_size(10);
    for name in ["spot_1-1000nm.ibw", "sur-2.sur", "sur-3.sur"] {
        let path = data.join(name);
        let len = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        g.throughput(criterion::Throughput::Bytes(len));
        g.bench_function(name, |b| {
            b.iter(|| read_height_map(&path, &ReadOptions::default()).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, surfaces);
criterion_main!(benches);
