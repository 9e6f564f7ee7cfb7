//! The streamed band transform against the in-memory `cwt_morlet` (same definition, one FFT
//! of the whole series), the L1 reading of a tone, determinism and the errors.

use super::*;
use crate::analysis::cwt::{cwt_morlet, CwtOptions};
use std::convert::Infallible;
use std::f64::consts::PI;

const FS: f64 = 1e6;
const N: usize = 1 << 16;

/// 50 kHz (amplitude 1) in the first half, 120 kHz (0.5) throughout, white noise (σ 0.1)
/// from a fixed xorshift, on an offset of 2 (so the mean removal matters).
fn signal() -> Vec<f64> {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..N)
        .map(|i| {
            let t = i as f64 / FS;
            let first = if i < N / 2 {
                (2.0 * PI * 50e3 * t).cos()
            } else {
                0.0
            };
            // Sum of 12 uniforms − 6: unit-variance, near-Gaussian noise.
            let noise = (0..12).map(|_| uniform()).sum::<f64>() - 6.0;
            2.0 + first + 0.5 * (2.0 * PI * 120e3 * t + 0.4).sin() + 0.1 * noise
        })
        .collect()
}

fn reader(x: &[f64]) -> impl FnMut(usize, &mut [f64]) -> Result<(), Infallible> + '_ {
    let mut next_min = 0;
    move |start, buf| {
        // The documented contract: inside the record, starts never go back.
        assert!(start + buf.len() <= x.len() && start >= next_min);
        next_min = start;
        buf.copy_from_slice(&x[start..start + buf.len()]);
        Ok(())
    }
}

fn stream(x: &[f64], opts: &BandOptions) -> BandScalogram {
    let plan = BandPlan::new(x.len(), FS, opts).unwrap();
    let mean = series_mean(x.len(), 5000, reader(x)).unwrap();
    band_cwt(&plan, mean, reader(x)).unwrap()
}

/// Max |streamed − in-memory| of the bin maxima and of the bin RMS |W|, relative to the
/// largest |W|, and the same restricted to bins within 2 samples of a block boundary.
fn compare(x: &[f64], opts: &BandOptions) -> (f64, f64, f64) {
    let s = stream(x, opts);
    let p = &s.plan;
    let mem = cwt_morlet(
        x,
        FS,
        &CwtOptions {
            wavelet: opts.wavelet,
            frequencies: opts.frequencies.clone(),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(mem.frequencies_hz, p.frequencies_hz);
    let largest = mem.magnitude.iter().fold(0f32, |a, &b| a.max(b)) as f64;
    let (mut e_max, mut e_rms, mut e_edge) = (0f64, 0f64, 0f64);
    for j in 0..p.frequencies_hz.len() {
        let row = mem.row(j);
        for b in 0..p.bins {
            let (lo, hi) = p.bin_range(b);
            let bin = &row[lo..hi];
            let max = bin.iter().fold(0f32, |a, &v| a.max(v)) as f64;
            let power = bin.iter().map(|&v| (v as f64).powi(2)).sum::<f64>() / bin.len() as f64;
            let d_max = (s.max_magnitude_row(j)[b] as f64 - max).abs() / largest;
            let d_rms = ((s.mean_power_row(j)[b] as f64).sqrt() - power.sqrt()).abs() / largest;
            e_max = e_max.max(d_max);
            e_rms = e_rms.max(d_rms);
            let near = (lo..hi).any(|i| {
                let r = i % p.block;
                r < 2 || r + 2 >= p.block
            });
            if near {
                e_edge = e_edge.max(d_max).max(d_rms);
            }
        }
    }
    // Cone of influence: the highest per-sample value of the bin; time: the bin's mean time.
    for b in 0..p.bins {
        let (lo, hi) = p.bin_range(b);
        let coi = mem.coi_hz[lo..hi].iter().cloned().fold(0.0, f64::max);
        assert_eq!(s.coi_hz[b], coi, "bin {b}");
        let t = (lo..hi).map(|i| i as f64 / FS).sum::<f64>() / (hi - lo) as f64;
        assert!(
            (s.time_s[b] - t).abs() < 1e-12,
            "bin {b}: {} vs {t}",
            s.time_s[b]
        );
    }
    (e_max, e_rms, e_edge)
}

fn log_band(lo: f64, hi: f64, count: usize) -> FrequencyGrid {
    FrequencyGrid::Log {
        f_min_hz: lo,
        f_max_hz: hi,
        count,
    }
}

#[test]
fn streamed_band_equals_the_in_memory_transform_decimated() {
    let x = signal();
    // (band, block, decimate): per-sample outputs, bins straddling blocks, long bins, and a
    // low band whose overlap (8117 samples at 1 kHz) is twice the block.
    let cases = [
        (log_band(30e3, 200e3, 12), 4096, 1),
        (log_band(30e3, 200e3, 12), 4096, 7),
        (log_band(30e3, 200e3, 12), 4096, 1000),
        (log_band(1e3, 5e3, 4), 4096, 10),
        (log_band(30e3, 200e3, 3), 3000, 64),
    ];
    for (band, block, decimate) in cases {
        let opts = BandOptions {
            wavelet: Wavelet::default(),
            frequencies: band.clone(),
            decimate,
            block: Some(block),
        };
        let plan = BandPlan::new(N, FS, &opts).unwrap();
        assert!(plan.blocks() >= 16, "{plan:?}");
        let (e_max, e_rms, e_edge) = compare(&x, &opts);
        eprintln!(
            "{band:?} block {block} decimate {decimate}: {e_max:.2e} {e_rms:.2e} {e_edge:.2e}"
        );
        assert!(
            e_max <= 1e-5 && e_rms <= 1e-5,
            "{band:?} block {block} decimate {decimate}: max {e_max:.2e}, rms {e_rms:.2e}"
        );
        assert!(e_edge <= 1e-5, "{band:?} at block boundaries: {e_edge:.2e}");
    }
    // PyWavelets' cmor wavelet (another Gaussian width) through the same code.
    let opts = BandOptions {
        wavelet: Wavelet::Cmor {
            bandwidth: 1.5,
            center: 1.0,
        },
        frequencies: log_band(30e3, 200e3, 6),
        decimate: 5,
        block: Some(4096),
    };
    let (e_max, e_rms, _) = compare(&x, &opts);
    assert!(
        e_max <= 1e-5 && e_rms <= 1e-5,
        "cmor: {e_max:.2e} {e_rms:.2e}"
    );
}

#[test]
fn a_tone_reads_its_amplitude_and_the_ridge_follows_it() {
    let x = signal();
    let opts = BandOptions {
        wavelet: Wavelet::default(),
        frequencies: FrequencyGrid::Explicit(vec![
            30e3, 40e3, 45e3, 50e3, 55e3, 65e3, 85e3, 110e3, 120e3, 130e3, 160e3,
        ]),
        decimate: 512,
        block: None,
    };
    let s = stream(&x, &opts);
    let half = N / 2;
    let mut checked = 0;
    for b in 0..s.plan.bins {
        let (lo, hi) = s.plan.bin_range(b);
        // Inside the cone of influence at 30 kHz, and 2000 samples clear of the switch.
        if !(s.coi_hz[b] < 30e3 && (hi + 2000 <= half || lo >= half + 2000)) {
            continue;
        }
        checked += 1;
        // L1: a tone of amplitude A reads |W| = A at its frequency (the noise: ±0.5 % per bin).
        let at = |j: usize| (s.mean_power_row(j)[b] as f64).sqrt();
        // Rows 3 and 8: 50 and 120 kHz; the grid is fine enough there (±10 %) for the
        // parabola to place the ridge within 1 %.
        if hi <= half {
            assert!((at(3) - 1.0).abs() < 0.02, "bin {b}: {}", at(3));
            assert!(
                (s.ridge.frequency_hz[b] / 50e3 - 1.0).abs() < 0.01,
                "bin {b}"
            );
        } else {
            assert!(at(3) < 0.1, "bin {b}: {}", at(3));
            assert!(
                (s.ridge.frequency_hz[b] / 120e3 - 1.0).abs() < 0.01,
                "bin {b}"
            );
        }
        assert!((at(8) - 0.5).abs() < 0.02, "bin {b}: {}", at(8));
        assert!(s.ridge.trusted[b]);
    }
    assert!(checked > 100, "{checked}");
    // Over the record: 1²/2 (half the time) + 0.5² at 120 kHz.
    assert!(
        (s.global_power[3] - 0.5).abs() < 0.02,
        "{:?}",
        s.global_power
    );
    assert!(
        (s.global_power[8] - 0.25).abs() < 0.02,
        "{:?}",
        s.global_power
    );
    let median = s.median_trusted_ridge_hz().unwrap();
    assert!(median > 45e3 && median < 130e3, "{median}");
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let x = signal();
    let opts = BandOptions {
        wavelet: Wavelet::default(),
        frequencies: log_band(30e3, 200e3, 7),
        decimate: 33,
        block: Some(4096),
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| stream(&x, &opts))
    };
    let (one, three) = (run(1), run(3));
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&one.mean_power), bits(&three.mean_power));
    assert_eq!(bits(&one.max_magnitude), bits(&three.max_magnitude));
    assert_eq!(one.ridge.frequency_hz, three.ridge.frequency_hz);
}

#[test]
fn default_blocks_keep_the_overlap_small() {
    for (f_min, n) in [(90e3, 100_000_000), (100.0, 100_000_000), (90e3, 1000)] {
        let opts = BandOptions {
            wavelet: Wavelet::default(),
            frequencies: log_band(f_min, 120e3, 10),
            decimate: 1000,
            block: None,
        };
        let p = BandPlan::new(n, 4e6, &opts).unwrap();
        assert!(p.fft_len >= p.block + 2 * p.overlap, "{p:?}");
        if n > p.fft_len {
            assert!(
                16 * p.overlap <= p.fft_len && p.fft_len >= MIN_FFT_LEN,
                "{p:?}"
            );
        } else {
            assert_eq!(p.block, n);
        }
    }
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let x = signal();
    let good = BandOptions {
        wavelet: Wavelet::default(),
        frequencies: log_band(30e3, 200e3, 4),
        decimate: 10,
        block: Some(4096),
    };
    let plan_err = |o: BandOptions, n: usize| BandPlan::new(n, FS, &o).unwrap_err();
    assert!(matches!(
        plan_err(
            BandOptions {
                decimate: 0,
                ..good.clone()
            },
            N
        ),
        AnalysisError::Parameter {
            name: "decimate",
            ..
        }
    ));
    assert!(matches!(
        plan_err(
            BandOptions {
                block: Some(0),
                ..good.clone()
            },
            N
        ),
        AnalysisError::Parameter { name: "block", .. }
    ));
    let above = plan_err(
        BandOptions {
            frequencies: log_band(30e3, 600e3, 4),
            ..good.clone()
        },
        N,
    );
    assert!(above.to_string().contains("Nyquist"), "{above}");
    assert!(matches!(
        plan_err(good.clone(), 3),
        AnalysisError::TooShort { len: 3, .. }
    ));
    // A wavelet longer than any FFT: refused, not an overflow.
    let low = plan_err(
        BandOptions {
            frequencies: log_band(1e-6, 1e3, 2),
            ..good.clone()
        },
        N,
    );
    assert!(matches!(low, AnalysisError::FrequencyRange { .. }), "{low}");
    assert!(BandPlan::new(N, f64::NAN, &good).is_err());

    // A NaN in a block: its index in the whole record, from either pass.
    let mut bad = x.clone();
    bad[40_000] = f64::NAN;
    let plan = BandPlan::new(N, FS, &good).unwrap();
    let nan_at = |e: StreamError<Infallible>| match e {
        StreamError::Analysis(AnalysisError::NonFinite { index, .. }) => index,
        other => panic!("{other}"),
    };
    assert_eq!(
        nan_at(series_mean(N, 4096, reader(&bad)).unwrap_err()),
        40_000
    );
    assert_eq!(
        nan_at(band_cwt(&plan, 0.0, reader(&bad)).unwrap_err()),
        40_000
    );
    let e = band_cwt(&plan, 0.0, reader(&bad)).unwrap_err().to_string();
    assert!(e.contains("at sample 40000"), "{e}");
    assert!(band_cwt(&plan, f64::NAN, reader(&x)).is_err());
    assert!(series_mean(N, 0, reader(&x)).is_err());
    assert!(series_mean(0, 10, reader(&x)).is_err());

    // The reader's own error comes back with the range it was reading.
    let failing = |start: usize, _: &mut [f64]| {
        if start > 20_000 {
            Err(std::io::Error::other("disk gone"))
        } else {
            Ok(())
        }
    };
    match band_cwt(&plan, 0.0, failing).unwrap_err() {
        StreamError::Read { start, error, .. } => {
            assert!(start > 20_000 && start < 20_000 + 4096 + 2 * plan.overlap);
            assert_eq!(error.to_string(), "disk gone");
        }
        other => panic!("{other}"),
    }
}
