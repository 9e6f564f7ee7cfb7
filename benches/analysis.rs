//! criterion bench of the analysis numerics (docs/analysis.md): the CWT of a
//! 10⁶-sample series (4 MS/s, 0.25 s) at 100 log-spaced frequencies from 5 kHz to 1 MHz
//! (analytic Morlet ω0 = 6, L1, magnitude as f32), and the Hann amplitude spectrum of 10⁷
//! samples (real-input FFT, `signal::rfft`), and that bare real FFT of 10⁷ samples.
//! `bench/analysis_numpy.py` times numpy / PyWavelets on the same cases.
//! Not run in CI.
use criterion::{criterion_group, criterion_main, Criterion};
use hdi::analysis::cwt::{cwt_morlet, CwtOptions, FrequencyGrid};
use hdi::analysis::series::spectrum;
use hdi::signal::rfft::RealFft;
use hdi::signal::spectrum::Window;
use rustfft::num_complex::Complex64;
use std::hint::black_box;

const FS: f64 = 4e6;

/// The shared benchmark signal (also `hdi bench` and `bench/compare.py`).
fn series(n: usize) -> Vec<f64> {
    hdi::samples::chirp_with_line(n, FS)
}

fn analysis(c: &mut Criterion) {
    let x6 = series(1_000_000);
    let opts = CwtOptions {
        frequencies: FrequencyGrid::Log {
            f_min_hz: 5e3,
            f_max_hz: 1e6,
            count: 100,
        },
        ..Default::default()
    };
    let x7 = series(10_000_000);
    let mut g = c.benchmark_group("analysis");
    g.sample_size(10);
    g.bench_function("cwt_morlet_1e6_samples_100_freqs", |b| {
        b.iter(|| cwt_morlet(black_box(&x6), FS, &opts).unwrap())
    });
    g.bench_function("amplitude_spectrum_hann_1e7_samples", |b| {
        b.iter(|| spectrum(black_box(&x7), FS, Window::Hann).unwrap())
    });
    let rfft = RealFft::new(&mut rustfft::FftPlanner::new(), x7.len());
    let mut bins = vec![Complex64::default(); rfft.spectrum_len()];
    let mut scratch = rfft.make_scratch();
    g.bench_function("real_fft_1e7_samples", |b| {
        b.iter(|| rfft.forward_with_scratch(black_box(&x7), &mut bins, &mut scratch))
    });
    g.finish();
}

criterion_group!(benches, analysis);
criterion_main!(benches);
