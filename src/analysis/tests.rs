//! Acceptance tests of the analysis numerics (docs/analysis.md).

use super::classify::{classify, Class, ClassifyOptions};
use super::cwt::{
    cwt_complex_padded, cwt_morlet, cwt_morlet_complex, reconstruction_integrals, ridge,
    CwtOptions, FrequencyGrid, Normalization, Wavelet,
};
use super::poincare::{phase_space, poincare_section, velocity};
use super::series::{detrend, spectrum, time_window, welch_psd, Detrend};
use super::AnalysisError;
use crate::signal::spectrum::{PeakOptions, Window};
use std::f64::consts::PI;

const FS: f64 = 4e6;

fn tone(n: usize, fs: f64, f: f64, a: f64, phase: f64) -> Vec<f64> {
    (0..n)
        .map(|i| a * (2.0 * PI * f * i as f64 / fs + phase).cos())
        .collect()
}

/// Linear chirp from f0 to f1 over the record; instantaneous frequency f0 + (f1 − f0)·t/T.
fn chirp(n: usize, fs: f64, f0: f64, f1: f64, a: f64) -> Vec<f64> {
    let t_total = n as f64 / fs;
    (0..n)
        .map(|i| {
            let t = i as f64 / fs;
            a * (2.0 * PI * (f0 * t + 0.5 * (f1 - f0) / t_total * t * t)).cos()
        })
        .collect()
}

/// Deterministic uniform noise in [−1, 1) (64-bit LCG, top bits).
fn noise(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
        .collect()
}

// ---------------------------------------------------------------- FFT, PSD, windows

#[test]
fn fft_peak_of_a_tone_reads_its_amplitude_at_its_frequency() {
    let (n, a) = (8192, 2.5e-9);
    let df = FS / n as f64;
    // On a bin: exact amplitude at exactly that bin.
    let s = spectrum(&tone(n, FS, 300.0 * df, a, 0.3), FS, Window::Hann).unwrap();
    let p = s.peaks(&PeakOptions::default())[0];
    assert_eq!(p.bin, 300);
    assert!((p.amplitude - a).abs() < 1e-12 * a, "{}", p.amplitude / a);
    assert!((p.frequency - 300.0 * df).abs() < 1e-6);
    // Off-bin tones 10 kHz–500 kHz: the raw peak is the nearest bin (bin-limited) and the
    // refined amplitude is A.
    for f in [10.7e3, 110e3, 275e3, 500e3] {
        let s = spectrum(&tone(n, FS, f, a, 1.1), FS, Window::Hann).unwrap();
        let p = s.peaks(&PeakOptions::default())[0];
        assert!((p.bin as f64 * df - f).abs() <= 0.5 * df, "{f}");
        assert!((p.frequency - f).abs() < 0.05 * df, "{f}: {}", p.frequency);
        assert!(
            (p.amplitude - a).abs() < 1e-3 * a,
            "{f}: {}",
            p.amplitude / a
        );
    }
}

#[test]
fn parseval_holds_for_the_one_sided_amplitude_spectrum() {
    // Rectangular window: Σ(x − x̄)²/N = A_0² + Σ_{0<k<N/2} A_k²/2 + A_{N/2}².
    for n in [4096usize, 4095] {
        let x: Vec<f64> = noise(n, 7)
            .iter()
            .zip(tone(n, FS, 123e3, 0.7, 0.0))
            .map(|(a, b)| a + b)
            .collect();
        let xd = detrend(&x, Detrend::Mean);
        let time: f64 = xd.iter().map(|v| v * v).sum::<f64>() / n as f64;
        let s = spectrum(&x, FS, Window::None).unwrap();
        let half = n / 2;
        let freq: f64 = s
            .amplitude
            .iter()
            .enumerate()
            .map(|(k, a)| {
                if k == 0 || (n.is_multiple_of(2) && k == half) {
                    a * a
                } else {
                    a * a / 2.0
                }
            })
            .sum();
        assert!((freq / time - 1.0).abs() < 1e-12, "{n}: {}", freq / time);
    }
}

#[test]
fn welch_psd_integrates_to_the_power() {
    let n = 1 << 16;
    let a = 0.8;
    let psd = welch_psd(&tone(n, FS, 200e3, a, 0.4), FS, 4096).unwrap();
    let df = psd.frequency_hz[1];
    let power: f64 = psd.density.iter().sum::<f64>() * df;
    assert_eq!(psd.segments, 31);
    assert!((power / (a * a / 2.0) - 1.0).abs() < 1e-3, "{power}");
    // White noise: flat at σ²/(fs/2).
    let x = noise(n, 3);
    let var = detrend(&x, Detrend::Mean)
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        / n as f64;
    let psd = welch_psd(&x, FS, 1024).unwrap();
    let total: f64 = psd.density.iter().sum::<f64>() * psd.frequency_hz[1];
    assert!((total / var - 1.0).abs() < 0.02, "{}", total / var);
}

#[test]
fn welch_psd_equals_scipy_welch() {
    // scipy.signal.welch(x, 4e6, 'hann', nperseg=1000, detrend='constant', scaling='density')
    // of 0.8 cos(2π·123.4 kHz·t + 0.4) + 0.1 cos(2π·700 kHz·t) + a ramp 0…0.01, 20 000 samples.
    let n = 20_000;
    let x: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 / FS;
            0.8 * (2.0 * PI * 123.4e3 * t + 0.4).cos()
                + 0.1 * (2.0 * PI * 700e3 * t).cos()
                + 0.01 * i as f64 / n as f64
        })
        .collect();
    let psd = welch_psd(&x, FS, 1000).unwrap();
    assert_eq!(psd.frequency_hz.len(), 501);
    let scipy = [
        (0, 1.1516073276437111e-09),
        (1, 5.733690832523187e-10),
        (30, 2.001836954819226e-05),
        (31, 5.180556950654473e-05),
        (175, 8.333333433334437e-07),
    ];
    for (k, p) in scipy {
        assert!(
            (psd.density[k] / p - 1.0).abs() < 1e-9,
            "bin {k}: {}",
            psd.density[k] / p
        );
    }
}

#[test]
fn time_window_and_detrend() {
    // App. B's 0.7–1.3 ms window of a record starting at t0 = 0.
    let r = time_window(8000, FS, 0.0, Some(0.7e-3), Some(1.3e-3)).unwrap();
    assert_eq!(r, 2800..5200);
    assert_eq!(time_window(100, FS, 1.0, None, None).unwrap(), 0..100);
    assert!(time_window(100, FS, 0.0, Some(1.0), Some(2.0)).is_err());
    let line: Vec<f64> = (0..101).map(|i| 3.0 + 0.25 * i as f64).collect();
    assert!(detrend(&line, Detrend::Linear)
        .iter()
        .all(|v| v.abs() < 1e-12));
    let m = detrend(&line, Detrend::Mean);
    assert!(m.iter().sum::<f64>().abs() < 1e-9);
}

// ---------------------------------------------------------------- CWT

#[test]
fn cwt_ridge_of_pure_tones_sits_on_the_tone_with_amplitude_a() {
    // §4.2 reference case: A = 2 nm tones, 8 000 samples at 4 MS/s, default grid (10 kHz–1 MHz,
    // 10 voices per octave); ridge within ±0.5 % and |W|/A within ±0.5 % at mid-record, and
    // within one grid step wherever the cone of influence trusts it.
    let (n, a) = (8000, 2e-9);
    let step = 2f64.powf(0.1);
    for f in [10.7e3, 25e3, 60e3, 110e3, 275e3, 500e3] {
        let s = cwt_morlet(&tone(n, FS, f, a, 0.3), FS, &CwtOptions::default()).unwrap();
        assert_eq!(s.frequencies_hz.len(), 67);
        let r = ridge(&s);
        let mid = n / 2;
        eprintln!(
            "tone {f} Hz: ridge {:.2} Hz, |W|/A {:.5}",
            r.frequency_hz[mid],
            r.magnitude[mid] / a
        );
        assert!(
            (r.frequency_hz[mid] / f - 1.0).abs() < 5e-3,
            "{f}: ridge {}",
            r.frequency_hz[mid]
        );
        assert!(
            (r.magnitude[mid] / a - 1.0).abs() < 5e-3,
            "{f}: |W|/A {}",
            r.magnitude[mid] / a
        );
        // The spec's reference values (log-parabolic interpolation), to their printed digits.
        let reference = [
            (10.7e3, 10.726e3, 0.5, 0.99996),
            (110e3, 110.14e3, 5.0, 0.9981),
            (275e3, 275.61e3, 5.0, 0.9990),
        ];
        if let Some(&(_, fr, tol, wr)) = reference.iter().find(|r| r.0 == f) {
            assert!((r.frequency_hz[mid] - fr).abs() <= tol, "{f}");
            assert!((r.magnitude[mid] / a - wr).abs() <= 5e-5, "{f}");
        }
        let mut trusted = 0;
        for i in 0..n {
            if r.trusted[i] && s.coi_hz[i] < f / step {
                trusted += 1;
                let ratio = r.frequency_hz[i] / f;
                assert!(ratio < step && ratio > 1.0 / step, "{f} at {i}: {ratio}");
            }
        }
        assert!(trusted > n / 2, "{f}: only {trusted} trusted samples");
    }
}

#[test]
fn cwt_ridge_follows_a_linear_chirp() {
    let (n, f0, f1) = (8000, 20e3, 400e3);
    let opts = CwtOptions {
        frequencies: FrequencyGrid::VoicesPerOctave {
            f_min_hz: 10e3,
            f_max_hz: 1e6,
            voices: 16,
        },
        ..Default::default()
    };
    let s = cwt_morlet(&chirp(n, FS, f0, f1, 1.0), FS, &opts).unwrap();
    let r = ridge(&s);
    let step = 2f64.powf(1.0 / 16.0);
    let mut errors = Vec::new();
    for i in (0..n).step_by(10) {
        let f_inst = f0 + (f1 - f0) * i as f64 / n as f64;
        // Trusted by the cone of influence, with a margin for the sweep itself.
        if s.coi_hz[i] < 0.5 * f_inst {
            let ratio = r.frequency_hz[i] / f_inst;
            assert!(ratio < step && ratio > 1.0 / step, "at {i}: {ratio}");
            errors.push((ratio - 1.0).abs());
        }
    }
    assert!(errors.len() > 600);
    errors.sort_by(f64::total_cmp);
    assert!(
        errors[errors.len() / 2] < 5e-3,
        "median {}",
        errors[errors.len() / 2]
    );
}

#[derive(serde::Deserialize)]
struct PywtReference {
    signal: PywtSignal,
    frequencies_hz: Vec<f64>,
    scales_samples: Vec<f64>,
    precision: u32,
    time_index: Vec<usize>,
    re: Vec<Vec<f64>>,
    im: Vec<Vec<f64>>,
}

#[derive(serde::Deserialize)]
struct PywtSignal {
    fs_hz: f64,
    n: usize,
    f0_hz: f64,
    f1_hz: f64,
    amplitude: f64,
}

/// Max relative error of |W| (where |W_pywt| ≥ 10 % of its row maximum) and max complex
/// error relative to the row maximum, against bench/pywt_reference.py's output.
fn pywt_errors() -> (f64, f64) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/cwt_linear_chirp_pywt.json"
    );
    let r: PywtReference = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let sig = &r.signal;
    let x = chirp(sig.n, sig.fs_hz, sig.f0_hz, sig.f1_hz, sig.amplitude);
    let opts = CwtOptions {
        wavelet: Wavelet::Cmor {
            bandwidth: 1.5,
            center: 1.0,
        },
        normalization: Normalization::Pywt {
            precision: Some(r.precision),
        },
        frequencies: FrequencyGrid::Explicit(r.frequencies_hz.clone()),
        keep_mean: false,
    };
    let w = cwt_morlet_complex(&x, sig.fs_hz, &opts).unwrap();
    let (mut mag_err, mut cplx_err) = (0.0f64, 0.0f64);
    for j in 0..r.frequencies_hz.len() {
        assert!((w.scales_s[j] * sig.fs_hz / r.scales_samples[j] - 1.0).abs() < 1e-12);
        let row = w.row(j);
        let refs: Vec<(usize, f64, f64)> = r
            .time_index
            .iter()
            .zip(r.re[j].iter().zip(&r.im[j]))
            .map(|(&i, (&re, &im))| (i, re, im))
            .collect();
        let row_max = refs
            .iter()
            .map(|&(_, re, im)| re.hypot(im))
            .fold(0.0, f64::max);
        for (i, re, im) in refs {
            let m_ref = re.hypot(im);
            let c = row[i];
            cplx_err = cplx_err.max((c.re - re).hypot(c.im - im) / row_max);
            if m_ref >= 0.1 * row_max {
                mag_err = mag_err.max((c.norm() / m_ref - 1.0).abs());
            }
        }
    }
    (mag_err, cplx_err)
}

#[test]
fn cwt_matches_pywavelets_cmor_on_a_linear_chirp() {
    let (mag, cplx) = pywt_errors();
    eprintln!(
        "PyWavelets parity: max |W| rel. error {mag:.3e}, max complex error / row max {cplx:.3e}"
    );
    assert!(mag < 0.01, "{mag}");
    assert!(cplx < 0.01, "{cplx}");
}

#[test]
fn pywt_normalisation_reads_half_a_root_scale_on_a_tone() {
    // §4.2 documented form: |W_pywt| = (A/2)·√a at the tone's scale a = C·fs/f (within 3 %).
    let (n, a) = (8000, 2e-9);
    for f in [10.7e3, 110e3, 275e3] {
        let opts = CwtOptions {
            wavelet: "cmor1.5-1.0".parse().unwrap(),
            normalization: Normalization::Pywt { precision: None },
            frequencies: FrequencyGrid::Explicit(vec![f]),
            keep_mean: false,
        };
        let s = cwt_morlet(&tone(n, FS, f, a, 0.0), FS, &opts).unwrap();
        let scale_samples = s.scales_s[0] * FS;
        assert!((scale_samples - FS / f).abs() < 1e-9);
        let expected = 0.5 * a * scale_samples.sqrt();
        let got = s.row(0)[n / 2] as f64;
        assert!(
            (got / expected - 1.0).abs() < 0.03,
            "{f}: {}",
            got / expected
        );
    }
}

#[test]
fn l2_and_l1_normalisations_differ_by_the_documented_factor() {
    let x = chirp(3000, FS, 30e3, 300e3, 1.0);
    let grid = FrequencyGrid::Log {
        f_min_hz: 20e3,
        f_max_hz: 500e3,
        count: 9,
    };
    let l1 = cwt_morlet_complex(
        &x,
        FS,
        &CwtOptions {
            frequencies: grid.clone(),
            ..Default::default()
        },
    )
    .unwrap();
    let l2 = cwt_morlet_complex(
        &x,
        FS,
        &CwtOptions {
            frequencies: grid,
            normalization: Normalization::Energy,
            ..Default::default()
        },
    )
    .unwrap();
    let p = PI.powf(-0.25) * (2.0 * PI).sqrt();
    for j in 0..9 {
        let factor = (l1.scales_s[j] * FS).sqrt() * p / 2.0;
        for (a, b) in l1.row(j).iter().zip(l2.row(j)) {
            assert!((a * factor - b).norm() <= 1e-12 * (1.0 + b.norm()));
        }
    }
}

#[test]
fn cone_of_influence_follows_the_e_folding_time() {
    // f_coi = ω0√2/(2π t_edge) = 1.350/t_edge; 10 kHz needs 135 µs from each edge.
    let n = 4000;
    let s = cwt_morlet(&tone(n, FS, 100e3, 1.0, 0.0), FS, &CwtOptions::default()).unwrap();
    let c = 6.0 * 2f64.sqrt() / (2.0 * PI);
    assert!((c - 1.3505).abs() < 1e-4);
    for i in [1usize, 17, 540, 1999, 2000, 3998] {
        let t_edge = i.min(n - 1 - i) as f64 / FS;
        let expected = (c / t_edge).min(FS / 2.0);
        assert!((s.coi_hz[i] / expected - 1.0).abs() < 1e-12, "{i}");
    }
    assert_eq!(s.coi_hz[0], FS / 2.0);
    let w = Wavelet::default();
    assert!((w.coi_frequency(135e-6) / 10e3 - 1.0).abs() < 1e-3);
    assert!((w.e_folding_time(w.scale_of_frequency(10e3)) - 135.05e-6).abs() < 0.01e-6);
}

#[test]
fn cwt_grids_wavelet_names_and_bad_options() {
    assert_eq!(FrequencyGrid::default().frequencies(FS).unwrap().len(), 67);
    let f = FrequencyGrid::Log {
        f_min_hz: 5e3,
        f_max_hz: 1e6,
        count: 100,
    }
    .frequencies(FS)
    .unwrap();
    assert_eq!(f.len(), 100);
    assert!((f[99] - 1e6).abs() < 1e-6);
    assert_eq!(
        "morlet".parse::<Wavelet>().unwrap(),
        Wavelet::Morlet { omega0: 6.0 }
    );
    assert_eq!(
        "cmor1.5-1.0".parse::<Wavelet>().unwrap(),
        Wavelet::Cmor {
            bandwidth: 1.5,
            center: 1.0
        }
    );
    assert!("mexh".parse::<Wavelet>().is_err());
    let x = tone(1000, FS, 100e3, 1.0, 0.0);
    let with = |frequencies| CwtOptions {
        frequencies,
        ..Default::default()
    };
    for bad in [
        FrequencyGrid::Log {
            f_min_hz: 1e6,
            f_max_hz: 1e5,
            count: 10,
        },
        FrequencyGrid::Log {
            f_min_hz: 0.0,
            f_max_hz: 1e5,
            count: 10,
        },
        FrequencyGrid::Log {
            f_min_hz: 1e4,
            f_max_hz: 3e6,
            count: 10,
        },
        FrequencyGrid::Explicit(vec![]),
        FrequencyGrid::Explicit(vec![2e4, 1e4]),
    ] {
        let e = cwt_morlet(&x, FS, &with(bad.clone())).unwrap_err();
        assert!(
            matches!(e, AnalysisError::FrequencyRange { .. }),
            "{bad:?}: {e}"
        );
    }
    let e = cwt_morlet(
        &x,
        FS,
        &CwtOptions {
            wavelet: Wavelet::Morlet { omega0: f64::NAN },
            ..Default::default()
        },
    );
    assert!(matches!(e, Err(AnalysisError::Parameter { .. })));
    assert!(cwt_morlet(&x, 0.0, &CwtOptions::default()).is_err());
    let e = cwt_morlet(&x, FS, &with(FrequencyGrid::Explicit(vec![1e-9, 1e3]))).unwrap_err();
    assert!(matches!(e, AnalysisError::FrequencyRange { .. }), "{e}");
}

#[test]
fn nan_and_too_short_series_are_errors_not_panics() {
    let mut x = tone(1000, FS, 100e3, 1.0, 0.0);
    x[321] = f64::NAN;
    let e = cwt_morlet(&x, FS, &CwtOptions::default()).unwrap_err();
    assert!(
        matches!(e, AnalysisError::NonFinite { index: 321, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("321"), "{e}");
    let e = poincare_section(&x, None, FS).unwrap_err();
    assert!(matches!(e, AnalysisError::NonFinite { index: 321, .. }));
    x[321] = f64::INFINITY;
    assert!(matches!(
        spectrum(&x, FS, Window::Hann).unwrap_err(),
        AnalysisError::NonFinite { index: 321, .. }
    ));
    assert!(matches!(
        welch_psd(&x, FS, 256).unwrap_err(),
        AnalysisError::NonFinite { index: 321, .. }
    ));
    assert!(matches!(
        phase_space(&x, None, FS, 100).unwrap_err(),
        AnalysisError::NonFinite { index: 321, .. }
    ));
    let short = [1.0, 2.0];
    for e in [
        cwt_morlet(&short, FS, &CwtOptions::default()).unwrap_err(),
        poincare_section(&short, None, FS).unwrap_err(),
        spectrum(&short, FS, Window::Hann).unwrap_err(),
        welch_psd(&short, FS, 256).unwrap_err(),
    ] {
        assert!(matches!(e, AnalysisError::TooShort { len: 2, .. }), "{e}");
    }
    let y = tone(1000, FS, 100e3, 1.0, 0.0);
    assert!(matches!(
        poincare_section(&y, Some(&y[..999]), FS).unwrap_err(),
        AnalysisError::LengthMismatch { .. }
    ));
    // A few cycles are too few to classify.
    let few = poincare_section(&y, None, FS).unwrap();
    assert_eq!(few.maxima.len(), 24);
    let e = classify(
        &few,
        &ClassifyOptions {
            min_points: 30,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            AnalysisError::TooShort {
                len: 24,
                min: 30,
                ..
            }
        ),
        "{e}"
    );
    assert!(poincare_section(&[0.0; 10], None, FS)
        .unwrap()
        .maxima
        .is_empty());
}

// ---------------------------------------------------------------- Poincaré, classification

/// §4.3 reference setting: 20 ms at 4 MS/s, 10.7 kHz.
const N_POINCARE: usize = 80_000;
const F_POINCARE: f64 = 10.7e3;

#[test]
fn poincare_of_a_sine_collapses_to_one_point() {
    let a = 1e-9;
    let w = 2.0 * PI * F_POINCARE;
    let x: Vec<f64> = (0..N_POINCARE)
        .map(|i| a * (w * i as f64 / FS).sin())
        .collect();
    let v: Vec<f64> = (0..N_POINCARE)
        .map(|i| a * w * (w * i as f64 / FS).cos())
        .collect();
    for vel in [Some(&v[..]), None] {
        let s = poincare_section(&x, vel, FS).unwrap();
        assert_eq!(s.maxima.len(), 214);
        let spread = s.maxima.iter().map(|m| (m - a).abs()).fold(0.0, f64::max);
        assert!(spread < 1e-6 * a, "{}", spread / a);
        assert!(s.minima.iter().all(|m| (m + a).abs() < 1e-6 * a));
        // Maxima a period apart.
        for t in s.maxima_time_s.windows(2) {
            assert!(((t[1] - t[0]) * F_POINCARE - 1.0).abs() < 1e-6);
        }
        let c = classify(&s, &ClassifyOptions::default()).unwrap();
        assert_eq!(
            c.class,
            Class::Periodic { period: 1 },
            "{:?}",
            c.diagnostics
        );
    }
    // Phase space with the exact velocity: the ellipse (x/A)² + (v/(Aω))² = 1.
    let ps = phase_space(&x, Some(&v), FS, 1000).unwrap();
    assert_eq!(ps.x.len(), 1000);
    assert_eq!(ps.stride, 80);
    for (xi, vi) in ps.x.iter().zip(&ps.v) {
        assert!(((xi / a).powi(2) + (vi / (a * w)).powi(2) - 1.0).abs() < 1e-14);
    }
    // Central differences: v·sinc error (ωΔt)²/6 ≈ 4.7e-5.
    let vc = velocity(&x, FS);
    for i in 1..N_POINCARE - 1 {
        assert!((vc[i] - v[i]).abs() < 1e-4 * a * w);
    }
}

#[test]
fn poincare_of_two_incommensurate_tones_fills_a_closed_curve() {
    let golden = (1.0 + 5f64.sqrt()) / 2.0;
    let w1 = 2.0 * PI * F_POINCARE;
    let w2 = golden * w1;
    let x: Vec<f64> = (0..N_POINCARE)
        .map(|i| {
            let t = i as f64 / FS;
            (w1 * t).sin() + 0.3 * (w2 * t + 0.5).sin()
        })
        .collect();
    let s = poincare_section(&x, None, FS).unwrap();
    let c = classify(&s, &ClassifyOptions::default()).unwrap();
    let d = &c.diagnostics;
    eprintln!("two tones: {d:?}");
    assert!(d.distinct_fraction >= 0.9);
    assert!(d.coverage >= 0.9);
    assert!(d.hole > 0.05);
    assert_eq!(c.class, Class::QuasiPeriodic);
    // A long record: ~20 000 maxima crowd closer than 10⁻⁴ A; still quasi-periodic.
    let f1 = 200e3;
    let x: Vec<f64> = (0..400_000)
        .map(|i| {
            let t = i as f64 / FS;
            (2.0 * PI * f1 * t).sin() + 0.3 * (2.0 * PI * golden * f1 * t + 0.5).sin()
        })
        .collect();
    let s = poincare_section(&x, None, FS).unwrap();
    let c = classify(&s, &ClassifyOptions::default()).unwrap();
    eprintln!("two tones, long: {:?}", c.diagnostics);
    assert!(c.diagnostics.n_maxima > 19_000);
    assert_eq!(c.class, Class::QuasiPeriodic);
}

#[test]
fn poincare_of_a_decaying_oscillation_converges_to_a_fixed_point() {
    let zeta: f64 = 0.02;
    let wn = 2.0 * PI * F_POINCARE;
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    // Free response from x0 = 1 nm, v0 = 0.
    let x: Vec<f64> = (0..N_POINCARE)
        .map(|i| {
            let t = i as f64 / FS;
            1e-9 * (-zeta * wn * t).exp()
                * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin())
        })
        .collect();
    let s = poincare_section(&x, None, FS).unwrap();
    let c = classify(&s, &ClassifyOptions::default()).unwrap();
    let expected = (-2.0 * PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
    assert!((expected - 0.881889).abs() < 1e-6);
    let d = &c.diagnostics;
    assert!((d.decay_ratio - expected).abs() < 1e-4, "{}", d.decay_ratio);
    // Successive maxima decay geometrically with the same ratio.
    for m in s.maxima.windows(2).take(150) {
        assert!((m[1] / m[0] - expected).abs() < 1e-4);
    }
    assert!(s.maxima.last().unwrap() / s.maxima[0] < 1e-10);
    assert_eq!(c.class, Class::FixedPoint, "{d:?}");
}

#[test]
fn a_period_two_orbit_shows_two_points_and_noise_is_irregular() {
    let w = 2.0 * PI * F_POINCARE;
    let x: Vec<f64> = (0..N_POINCARE)
        .map(|i| {
            let t = i as f64 / FS;
            (w * t).sin() + 0.4 * (0.5 * w * t + 0.3).sin()
        })
        .collect();
    let s = poincare_section(&x, None, FS).unwrap();
    let c = classify(&s, &ClassifyOptions::default()).unwrap();
    assert_eq!(
        c.class,
        Class::Periodic { period: 2 },
        "{:?}",
        c.diagnostics
    );
    // White noise (band-limited by a 5-point moving average so extrema are resolved).
    let raw = noise(N_POINCARE, 11);
    let x: Vec<f64> = raw.windows(5).map(|w| w.iter().sum::<f64>()).collect();
    let s = poincare_section(&x, None, FS).unwrap();
    let c = classify(&s, &ClassifyOptions::default()).unwrap();
    eprintln!("noise: {:?}", c.diagnostics);
    assert_eq!(c.class, Class::Irregular, "{:?}", c.diagnostics);
}

#[test]
fn padding_to_the_spec_length_gives_the_same_coefficients() {
    // Our pad (N + wavelet support) vs the spec's reference (next power of two ≥ 2N).
    let n = 5000;
    let x: Vec<f64> = chirp(n, FS, 15e3, 600e3, 1.0)
        .iter()
        .zip(noise(n, 5))
        .map(|(a, b)| a + 0.2 * b)
        .collect();
    let opts = CwtOptions::default();
    let ours = cwt_morlet_complex(&x, FS, &opts).unwrap();
    let spec = cwt_complex_padded(&x, FS, &opts, (2 * n).next_power_of_two()).unwrap();
    let max = spec
        .coefficients
        .iter()
        .map(|c| c.norm())
        .fold(0.0, f64::max);
    let err = ours
        .coefficients
        .iter()
        .zip(&spec.coefficients)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    eprintln!("padding: max difference {:.1e} of max |W|", err / max);
    assert!(err < 5e-12 * max, "{}", err / max);
}

#[test]
fn f32_scalogram_matches_the_f64_transform() {
    // The magnitude scalogram inverse-transforms in f32; the complex one in f64. Budget:
    // 1e-5 of max |W| (docs/analysis.md), for the analytic L1 and the PyWavelets normalisation,
    // on a chirp plus noise long enough for a 2^16-point transform.
    let n = 60_000;
    let x: Vec<f64> = chirp(n, FS, 8e3, 900e3, 1.0)
        .iter()
        .zip(noise(n, 11))
        .map(|(a, b)| a + 0.3 * b)
        .collect();
    for opts in [
        CwtOptions::default(),
        CwtOptions {
            wavelet: "cmor1.5-1.0".parse().unwrap(),
            normalization: Normalization::Pywt {
                precision: Some(12),
            },
            ..Default::default()
        },
    ] {
        let single = cwt_morlet(&x, FS, &opts).unwrap();
        let double = cwt_morlet_complex(&x, FS, &opts).unwrap();
        let max = double
            .coefficients
            .iter()
            .map(|c| c.norm())
            .fold(0.0, f64::max);
        let err = single
            .magnitude
            .iter()
            .zip(&double.coefficients)
            .map(|(&a, b)| (a as f64 - b.norm()).abs())
            .fold(0.0, f64::max);
        eprintln!("f32 vs f64: max difference {:.1e} of max |W|", err / max);
        assert!(err <= 1e-5 * max, "{}", err / max);
    }
}

/// Noise band-limited to [f_lo, f_hi] by zeroing its spectrum outside the band.
fn band_limited_noise(n: usize, f_lo: f64, f_hi: f64, seed: u64) -> Vec<f64> {
    use rustfft::num_complex::Complex64;
    let mut buf: Vec<Complex64> = noise(n, seed)
        .iter()
        .map(|&v| Complex64::new(v, 0.0))
        .collect();
    let mut planner = rustfft::FftPlanner::<f64>::new();
    planner.plan_fft_forward(n).process(&mut buf);
    for (k, b) in buf.iter_mut().enumerate() {
        let f = k.min(n - k) as f64 * FS / n as f64;
        if f < f_lo || f > f_hi {
            *b = Complex64::default();
        }
    }
    planner.plan_fft_inverse(n).process(&mut buf);
    buf.iter().map(|c| c.re / n as f64).collect()
}

#[test]
fn cwt_energy_and_reconstruction_on_band_limited_noise() {
    // §4.2: I_E = 0.299696, I_R = 0.430514 for ω0 = 6; noise in fs/512…fs/16 analysed at
    // 8 voices per octave: variance ratio 0.99 ± 0.01, reconstruction error < 1 % (middle 75 %).
    let (i_e, i_r) = reconstruction_integrals(&Wavelet::default());
    assert!((i_e - 0.299696).abs() < 2e-6, "{i_e}");
    assert!((i_r - 0.430514).abs() < 2e-6, "{i_r}");
    let n = 1 << 15;
    let x = band_limited_noise(n, FS / 512.0, FS / 16.0, 17);
    let opts = CwtOptions {
        frequencies: FrequencyGrid::VoicesPerOctave {
            f_min_hz: FS / 8192.0,
            f_max_hz: FS / 2.0,
            voices: 8,
        },
        ..Default::default()
    };
    let w = cwt_morlet_complex(&x, FS, &opts).unwrap();
    let var = x.iter().map(|v| v * v).sum::<f64>() / n as f64;
    let ratio = w.variance().unwrap() / var;
    let y = w.reconstruct().unwrap();
    let (a, b) = (n / 8, n - n / 8);
    let err = (x[a..b]
        .iter()
        .zip(&y[a..b])
        .map(|(p, q)| (p - q).powi(2))
        .sum::<f64>()
        / x[a..b].iter().map(|p| p * p).sum::<f64>())
    .sqrt();
    eprintln!("variance ratio {ratio:.4}, reconstruction rel. RMS error {err:.4}");
    assert!((ratio - 0.99).abs() <= 0.01, "{ratio}");
    assert!(err < 0.01, "{err}");
    // Only for the L1 transform on a log-uniform grid.
    let l2 = cwt_morlet_complex(
        &x[..1000],
        FS,
        &CwtOptions {
            normalization: Normalization::Energy,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(matches!(
        l2.variance(),
        Err(AnalysisError::Parameter { .. })
    ));
}
