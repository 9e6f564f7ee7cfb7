//! `hdi::signal::rfft` against numpy's `np.fft.rfft` / `np.fft.irfft` (an independent
//! implementation, pocketfft): even lengths (the packed N/2 transform), odd lengths (the complex
//! fallback) and a length with large prime factors.

use crate::common::python;
use hdi::signal::rfft::RealFft;
use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;
use std::io::Write;
use std::process::{Command, Stdio};

/// A deterministic broadband series (tones, a ramp and an offset).
fn series(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            let t = i as f64;
            (0.37 * t).sin() + 0.5 * (1.91 * t + 0.3).cos() + 2e-4 * t - 0.25
                + 0.1 * ((i * 7919) % 1009) as f64 / 1009.0
        })
        .collect()
}

/// numpy's rfft of `x` as (re, im) pairs, read back from Python float `repr` text (round-trip
/// exact; numpy 2 scalars would print as `np.float64(…)`).
fn numpy_rfft(x: &[f64]) -> Vec<Complex64> {
    let script = "import sys, numpy as np\n\
        x = np.array([float(v) for v in sys.stdin.read().split()])\n\
        X = np.fft.rfft(x)\n\
        print('\\n'.join(f'{float(c.real)!r} {float(c.imag)!r}' for c in X))\n";
    let mut child = Command::new(python())
        .args(["-c", script])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("start python");
    let text: String = x.iter().map(|v| format!("{v:?}\n")).collect();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(text.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            let mut it = l.split_whitespace().map(|v| v.parse::<f64>().unwrap());
            Complex64::new(it.next().unwrap(), it.next().unwrap())
        })
        .collect()
}

#[test]
fn real_fft_matches_numpy_rfft_and_inverts() {
    let mut planner = FftPlanner::<f64>::new();
    // Even (radix-2, mixed, N/2 odd), odd, prime and a large-prime-factor length.
    for n in [
        2usize,
        6,
        64,
        1000,
        4097,
        6002,
        7919,
        2 * 3 * 5 * 7 * 11 * 13,
    ] {
        let x = series(n);
        let reference = numpy_rfft(&x);
        let r = RealFft::new(&mut planner, n);
        assert_eq!(reference.len(), r.spectrum_len(), "n {n}");
        let mut ours = vec![Complex64::default(); r.spectrum_len()];
        r.forward(&x, &mut ours);
        let scale = reference.iter().map(|c| c.norm()).fold(0.0, f64::max);
        let err = ours
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        // Both are O(ε log N) accurate: 1e-12 of the largest bin is far above either's error.
        assert!(err <= 1e-12 * scale, "n {n}: {err:e} of {scale:e}");
        let mut back = vec![0.0; n];
        r.inverse(&mut ours, &mut back);
        let err = back
            .iter()
            .zip(&x)
            .map(|(a, b)| (a / n as f64 - b).abs())
            .fold(0.0, f64::max);
        assert!(err <= 1e-12, "n {n}: inverse {err:e}");
    }
}
