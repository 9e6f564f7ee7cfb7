//! Velocity → displacement (docs/dmw.md).
//!
//! `cumulative_trapezoid` works on any record; its response relative to the ideal integrator
//! `1/(jω)` is `(πf/fs)·cot(πf/fs)` (0.98440 at 275 kHz, 4 MS/s), which `trapezoid_gain`
//! reports. `integrate_periodic` is exact for records that are one period of a periodic
//! signal (angle-domain revolutions) and wrong (wrap-around) for anything else.

use super::SignalError;
use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;

/// `D[0] = 0`, `D[n] = D[n−1] + (v[n] + v[n−1])/(2 fs)` (scipy `cumulative_trapezoid(initial=0)`).
pub fn cumulative_trapezoid(v: &[f64], fs: f64) -> Vec<f64> {
    let half_dt = 0.5 / fs;
    let mut out = Vec::with_capacity(v.len());
    let mut acc = 0.0;
    let mut prev = match v.first() {
        Some(&x) => x,
        None => return out,
    };
    out.push(0.0);
    for &x in &v[1..] {
        acc += (x + prev) * half_dt;
        prev = x;
        out.push(acc);
    }
    out
}

/// Trapezoid amplitude relative to the ideal integrator at frequency `f`: `(πf/fs)·cot(πf/fs)`.
pub fn trapezoid_gain(f: f64, fs: f64) -> f64 {
    let x = std::f64::consts::PI * f / fs;
    if x == 0.0 {
        1.0
    } else {
        x / x.tan()
    }
}

/// How to remove the integration constant and drift from a displacement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Detrend {
    None,
    /// Subtract the mean.
    Mean,
    /// Subtract the least-squares line (mean included). A velocity offset integrates to a
    /// ramp; the line's slope is reported as QA.
    Line,
}

impl std::str::FromStr for Detrend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "none" => Ok(Detrend::None),
            "mean" => Ok(Detrend::Mean),
            "line" | "linear" => Ok(Detrend::Line),
            _ => Err(format!(
                "unknown detrend `{s}` (expected \"line\", \"mean\" or \"none\")"
            )),
        }
    }
}

impl std::fmt::Display for Detrend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Detrend::None => "none",
            Detrend::Mean => "mean",
            Detrend::Line => "line",
        })
    }
}

/// Least-squares line `a + b·n` through `y` against the sample index; returns `(a, b)`.
pub fn fit_line(y: &[f64]) -> (f64, f64) {
    let n = y.len();
    if n == 0 {
        return (0.0, 0.0);
    }
    if n == 1 {
        return (y[0], 0.0);
    }
    // Centred index: the normal equations decouple and stay well conditioned for 10^7 samples.
    let c = (n as f64 - 1.0) / 2.0;
    let (mut sy, mut sxy, mut sxx) = (0.0, 0.0, 0.0);
    for (i, &v) in y.iter().enumerate() {
        let x = i as f64 - c;
        sy += v;
        sxy += x * v;
        sxx += x * x;
    }
    let b = sxy / sxx;
    let mean = sy / n as f64;
    (mean - b * c, b)
}

/// Remove the trend in place; returns the removed slope per sample (0 unless `Line`).
pub fn detrend(y: &mut [f64], how: Detrend) -> f64 {
    match how {
        Detrend::None => 0.0,
        Detrend::Mean => {
            let m = mean(y);
            y.iter_mut().for_each(|v| *v -= m);
            0.0
        }
        Detrend::Line => {
            let (a, b) = fit_line(y);
            for (i, v) in y.iter_mut().enumerate() {
                *v -= a + b * i as f64;
            }
            b
        }
    }
}

pub fn mean(y: &[f64]) -> f64 {
    if y.is_empty() {
        0.0
    } else {
        y.iter().sum::<f64>() / y.len() as f64
    }
}

/// Exact integration of one period of a periodic signal in the frequency domain:
/// `D̂_k = V̂_k/(j2πf_k)`, `D̂_0 = 0`, Nyquist bin zeroed. Drift-free; the result has zero mean.
pub fn integrate_periodic(v: &[f64], fs: f64) -> Result<Vec<f64>, SignalError> {
    let n = v.len();
    if n < 2 {
        return Err(SignalError::TooShort {
            len: n,
            reason: "periodic integration needs at least 2 samples".into(),
        });
    }
    let fft = FftPlanner::<f64>::new().plan_fft_forward(n);
    let ifft = FftPlanner::<f64>::new().plan_fft_inverse(n);
    let mut buf: Vec<Complex64> = v.iter().map(|&x| Complex64::new(x, 0.0)).collect();
    fft.process(&mut buf);
    for (k, c) in buf.iter_mut().enumerate() {
        // Signed frequency index: bins above n/2 are negative frequencies.
        let kk = if k <= n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        };
        if k == 0 || (n.is_multiple_of(2) && k == n / 2) {
            *c = Complex64::new(0.0, 0.0);
        } else {
            let w = 2.0 * std::f64::consts::PI * kk * fs / n as f64;
            *c /= Complex64::new(0.0, w);
        }
    }
    ifft.process(&mut buf);
    Ok(buf.iter().map(|c| c.re / n as f64).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn amplitude_at(y: &[f64], f: f64, fs: f64) -> f64 {
        // Least-squares amplitude of a tone at f (integer cycles: exact projection).
        let n = y.len() as f64;
        let (mut c, mut s) = (0.0, 0.0);
        for (i, &v) in y.iter().enumerate() {
            let ph = 2.0 * PI * f * i as f64 / fs;
            c += v * ph.cos();
            s += v * ph.sin();
        }
        2.0 * (c * c + s * s).sqrt() / n
    }

    #[test]
    fn periodic_integration_of_a_tone_is_exact() {
        let (fs, n, f, amp) = (4e6, 4000, 10e3 * 11.0, 0.025);
        let v: Vec<f64> = (0..n)
            .map(|i| amp * (2.0 * PI * f * i as f64 / fs).cos())
            .collect();
        let d = integrate_periodic(&v, fs).unwrap();
        for (i, &x) in d.iter().enumerate() {
            let exact = amp / (2.0 * PI * f) * (2.0 * PI * f * i as f64 / fs).sin();
            assert!((x - exact).abs() <= 1e-10 * amp / (2.0 * PI * f), "{i}");
        }
    }

    #[test]
    fn trapezoid_amplitude_follows_its_frequency_response() {
        // Integer cycles, then remove the mean: what remains is the tone at the trapezoid's gain.
        let fs = 4e6;
        let n = 40_000;
        for f in [10.7e3_f64, 100e3, 275e3, 500e3] {
            let f = (f * n as f64 / fs).round() * fs / n as f64;
            let v: Vec<f64> = (0..n)
                .map(|i| (2.0 * PI * f * i as f64 / fs).cos())
                .collect();
            let mut d = cumulative_trapezoid(&v, fs);
            detrend(&mut d, Detrend::Mean);
            let ratio = amplitude_at(&d, f, fs) * 2.0 * PI * f;
            let theory = trapezoid_gain(f, fs);
            assert!(
                (ratio / theory - 1.0).abs() < 1e-5,
                "{f}: {ratio} vs {theory}"
            );
        }
        assert!((trapezoid_gain(275e3, 4e6) - 0.98440).abs() < 5e-6);
        assert!((trapezoid_gain(500e3, 4e6) - 0.94806).abs() < 5e-6);
    }

    #[test]
    fn velocity_sinusoid_integrates_to_v_over_two_pi_f() {
        // Acceptance: amplitude V/(2πf) within 0.5 % (trapezoid, non-integer number of cycles,
        // linear detrend): 1 V at 10.7 kHz through a 25 mm/s/V decoder gives 3.719e-7 m.
        let fs = 4e6;
        let v_amp = 0.025;
        for f in [10.7e3, 50e3, 137e3] {
            let v: Vec<f64> = (0..10_000)
                .map(|i| v_amp * (2.0 * PI * f * i as f64 / fs + 0.3).cos())
                .collect();
            let mut d = cumulative_trapezoid(&v, fs);
            detrend(&mut d, Detrend::Line);
            // Amplitude by least squares on sin/cos at f (not integer cycles: solve 2x2).
            let (mut scc, mut sss, mut ssc, mut syc, mut sys) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for (i, &y) in d.iter().enumerate() {
                let ph = 2.0 * PI * f * i as f64 / fs;
                let (s, c) = ph.sin_cos();
                scc += c * c;
                sss += s * s;
                ssc += s * c;
                syc += y * c;
                sys += y * s;
            }
            let det = scc * sss - ssc * ssc;
            let a = (syc * sss - sys * ssc) / det;
            let b = (sys * scc - syc * ssc) / det;
            let amp = a.hypot(b);
            let want = v_amp / (2.0 * PI * f);
            assert!((amp / want - 1.0).abs() < 0.005, "{f}: {amp} vs {want}");
        }
        assert!((0.025 / (2.0 * PI * 10_700.0) - 3.719e-7).abs() < 1e-10);
    }

    #[test]
    fn line_detrend_removes_an_offset_ramp_and_reports_its_slope() {
        let mut y: Vec<f64> = (0..1001).map(|i| 2.0 + 0.5 * i as f64).collect();
        let slope = detrend(&mut y, Detrend::Line);
        assert!((slope - 0.5).abs() < 1e-12);
        assert!(y.iter().all(|v| v.abs() < 1e-9));
    }

    #[test]
    fn trapezoid_matches_scipy_convention() {
        let d = cumulative_trapezoid(&[1.0, 3.0, 5.0], 2.0);
        assert_eq!(d, vec![0.0, 1.0, 3.0]);
        assert!(cumulative_trapezoid(&[], 1.0).is_empty());
        assert!(integrate_periodic(&[1.0], 1.0).is_err());
    }
}
