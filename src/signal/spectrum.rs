//! One-sided amplitude spectrum and peak picking (docs/analysis.md).
//!
//! Scaling: a sinusoid of amplitude A centred on a bin reads A (`A_k = 2|X_k|/Σw`), the same
//! as `sqrt(2·P)` of scipy `periodogram(window='hann', scaling='spectrum')`. Peaks between
//! bins are refined with the exact two-bin estimator for the Hann window, so a tone reads its
//! true amplitude and frequency wherever it falls.

use super::rfft::RealFft;
use super::SignalError;
use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Window {
    /// Periodic (DFT-even) Hann, scipy `get_window('hann', N)`.
    Hann,
    /// Rectangular.
    None,
}

impl std::str::FromStr for Window {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "hann" => Ok(Window::Hann),
            "none" | "rectangular" | "boxcar" => Ok(Window::None),
            _ => Err(format!(
                "unknown window `{s}` (expected \"hann\" or \"none\")"
            )),
        }
    }
}

impl std::fmt::Display for Window {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Window::Hann => "hann",
            Window::None => "none",
        })
    }
}

/// A one-sided amplitude spectrum, with the complex bins kept for peak refinement.
#[derive(Debug, Clone)]
pub struct AmplitudeSpectrum {
    /// Bin frequencies, Hz (`k·fs/N`, k = 0…N/2).
    pub frequency: Vec<f64>,
    /// Amplitude in signal units.
    pub amplitude: Vec<f64>,
    pub window: Window,
    /// Bin spacing fs/N, Hz.
    pub resolution: f64,
    /// |X_k| (unscaled), for the interpolating peak estimator.
    magnitude: Vec<f64>,
    window_sum: f64,
}

/// One spectral line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    pub frequency: f64,
    pub amplitude: f64,
    /// Bin index of the local maximum.
    pub bin: usize,
}

/// Peak-picking settings.
#[derive(Debug, Clone, Copy)]
pub struct PeakOptions {
    /// Keep peaks above this fraction of the largest amplitude.
    pub rel_threshold: f64,
    /// And above this absolute level (signal units).
    pub floor: f64,
    /// Minimum distance between reported peaks, in bins.
    pub min_separation_bins: usize,
    /// Top-N by amplitude.
    pub max_peaks: usize,
    /// Ignore peaks below this frequency (e.g. the DC leakage of a high-passed record).
    pub min_frequency: f64,
}

impl Default for PeakOptions {
    fn default() -> Self {
        PeakOptions {
            rel_threshold: 0.01,
            floor: 0.0,
            min_separation_bins: 3,
            max_peaks: 8,
            min_frequency: 0.0,
        }
    }
}

/// Amplitude spectrum of `x` sampled at `fs` after removing its mean. No zero padding.
pub fn amplitude_spectrum(
    x: &[f64],
    fs: f64,
    window: Window,
) -> Result<AmplitudeSpectrum, SignalError> {
    let n = x.len();
    if n < 4 {
        return Err(SignalError::TooShort {
            len: n,
            reason: "a spectrum needs at least 4 samples".into(),
        });
    }
    if !(fs.is_finite() && fs > 0.0) {
        return Err(SignalError::parameter("sample rate", fs, "must be > 0"));
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(SignalError::NonFinite { index: i });
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    // A real-input FFT (signal::rfft: N/2 + 1 bins from an N/2-point complex transform) that
    // reads the windowed, mean-removed samples on the fly — no window or input copy.
    let rfft = RealFft::new(&mut FftPlanner::<f64>::new(), n);
    let mut bins = vec![Complex64::default(); rfft.spectrum_len()];
    let mut window_sum = 0.0;
    match window {
        Window::Hann => rfft.forward_from_fn(
            |i| {
                let wi = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos();
                window_sum += wi;
                (x[i] - mean) * wi
            },
            &mut bins,
            &mut rfft.make_scratch(),
        ),
        Window::None => {
            window_sum = n as f64;
            rfft.forward_from_fn(|i| x[i] - mean, &mut bins, &mut rfft.make_scratch())
        }
    }
    let half = n / 2;
    // √(re² + im²) is vectorisable where hypot is a libm call; hypot only where the square
    // would overflow or lose precision to underflow.
    let magnitude: Vec<f64> = bins
        .iter()
        .map(|c| {
            let sq = c.norm_sqr();
            if sq.is_finite() && sq >= f64::MIN_POSITIVE {
                sq.sqrt()
            } else {
                c.norm()
            }
        })
        .collect();
    drop(bins);
    let amplitude = magnitude
        .iter()
        .enumerate()
        .map(|(k, &m)| {
            let one_sided = if k == 0 || (n.is_multiple_of(2) && k == half) {
                1.0
            } else {
                2.0
            };
            one_sided * m / window_sum
        })
        .collect();
    let resolution = fs / n as f64;
    Ok(AmplitudeSpectrum {
        frequency: (0..=half).map(|k| k as f64 * resolution).collect(),
        amplitude,
        window,
        resolution,
        magnitude,
        window_sum,
    })
}

/// Hann main-lobe shape relative to its peak at offset δ bins: `sinc(δ)/(1 − δ²)`.
fn hann_lobe(delta: f64) -> f64 {
    if delta.abs() < 1e-12 {
        return 1.0;
    }
    if (delta.abs() - 1.0).abs() < 1e-12 {
        return 0.5;
    }
    let x = std::f64::consts::PI * delta;
    (x.sin() / x) / (1.0 - delta * delta)
}

impl AmplitudeSpectrum {
    /// Amplitude and frequency of the line whose local maximum is bin `k`.
    pub fn refine(&self, k: usize) -> Peak {
        let m = &self.magnitude;
        let raw = Peak {
            frequency: k as f64 * self.resolution,
            amplitude: self.amplitude[k],
            bin: k,
        };
        if self.window != Window::Hann || k == 0 || k + 1 >= m.len() || m[k] == 0.0 {
            return raw;
        }
        // Exact for a single tone under a Hann window: the two larger neighbours' ratio gives
        // the offset, the lobe shape at that offset gives the amplitude.
        let (a, sign) = if m[k + 1] >= m[k - 1] {
            (m[k + 1] / m[k], 1.0)
        } else {
            (m[k - 1] / m[k], -1.0)
        };
        let delta = sign * (2.0 * a - 1.0) / (a + 1.0);
        Peak {
            frequency: (k as f64 + delta) * self.resolution,
            amplitude: 2.0 * m[k] / self.window_sum / hann_lobe(delta),
            bin: k,
        }
    }

    /// Local maxima above the thresholds, at least `min_separation_bins` apart, largest first.
    pub fn peaks(&self, opts: &PeakOptions) -> Vec<Peak> {
        let a = &self.amplitude;
        let n = a.len();
        if n < 3 {
            return Vec::new();
        }
        let first = ((opts.min_frequency / self.resolution).ceil() as usize).max(1);
        let max = a[first.min(n - 1)..].iter().cloned().fold(0.0, f64::max);
        let level = (opts.rel_threshold * max).max(opts.floor);
        let mut candidates: Vec<usize> = (first.max(1)..n - 1)
            .filter(|&k| a[k] > a[k - 1] && a[k] >= a[k + 1] && a[k] > level)
            .collect();
        candidates.sort_by(|&i, &j| a[j].total_cmp(&a[i]));
        let mut chosen: Vec<usize> = Vec::new();
        for k in candidates {
            if chosen.len() >= opts.max_peaks {
                break;
            }
            if chosen
                .iter()
                .all(|&c| c.abs_diff(k) >= opts.min_separation_bins)
            {
                chosen.push(k);
            }
        }
        chosen.into_iter().map(|k| self.refine(k)).collect()
    }
}

/// The strongest line of a stored one-sided Hann amplitude spectrum (`frequency`, `amplitude`,
/// as `AmplitudeSpectrum` writes them) inside `[lo, hi]` Hz: the largest local maximum whose
/// bin lies in the band, refined by the exact two-bin Hann estimator (amplitudes of interior
/// bins are proportional to |X_k|, so their ratio is the one [`AmplitudeSpectrum::refine`]
/// uses). The band is chosen by the caller on physical grounds; no line outside it is looked
/// at. `None` without a local maximum in the band or for malformed input.
pub fn strongest_line(frequency: &[f64], amplitude: &[f64], lo: f64, hi: f64) -> Option<Peak> {
    let n = amplitude.len();
    if n < 3 || frequency.len() != n || hi.is_nan() || lo.is_nan() || hi < lo {
        return None;
    }
    let df = frequency[1] - frequency[0];
    if df.is_nan() || df <= 0.0 {
        return None;
    }
    let a = amplitude;
    let k = (1..n - 1)
        .filter(|&k| frequency[k] >= lo && frequency[k] <= hi)
        .filter(|&k| a[k] > a[k - 1] && a[k] >= a[k + 1])
        .max_by(|&i, &j| a[i].total_cmp(&a[j]))?;
    let (r, sign) = if a[k + 1] >= a[k - 1] {
        (a[k + 1] / a[k], 1.0)
    } else {
        (a[k - 1] / a[k], -1.0)
    };
    let delta = sign * (2.0 * r - 1.0) / (r + 1.0);
    Some(Peak {
        frequency: frequency[k] + delta * df,
        amplitude: a[k] / hann_lobe(delta),
        bin: k,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn tone(n: usize, fs: f64, f: f64, a: f64, phase: f64) -> Vec<f64> {
        (0..n)
            .map(|i| a * (2.0 * PI * f * i as f64 / fs + phase).cos())
            .collect()
    }

    #[test]
    fn a_tone_on_a_bin_reads_its_amplitude() {
        let (n, fs) = (8192, 4e6);
        let df = fs / n as f64;
        assert!((df - 488.28125).abs() < 1e-9);
        let s = amplitude_spectrum(&tone(n, fs, 100.0 * df, 1.5, 0.2), fs, Window::Hann).unwrap();
        assert!((s.amplitude[100] - 1.5).abs() < 1e-12);
        let r = amplitude_spectrum(&tone(n, fs, 100.0 * df, 1.5, 0.2), fs, Window::None).unwrap();
        assert!((r.amplitude[100] - 1.5).abs() < 1e-12);
    }

    #[test]
    fn half_bin_tone_shows_hann_scalloping_and_the_estimator_undoes_it() {
        // §4.1: a half-bin tone of 1.5 reads 1.27324 raw; offsets 0, 1/4, 1/2 refine to 1.5.
        let (n, fs) = (8192, 4e6);
        let df = fs / n as f64;
        for offset in [0.0, 0.25, 0.5] {
            let f = (1000.0 + offset) * df;
            let s = amplitude_spectrum(&tone(n, fs, f, 1.5, 0.7), fs, Window::Hann).unwrap();
            let peaks = s.peaks(&PeakOptions::default());
            let p = peaks[0];
            assert!(
                (p.amplitude - 1.5).abs() < 1e-6,
                "{offset}: {}",
                p.amplitude
            );
            assert!(
                (p.frequency - f).abs() < 1e-3,
                "{offset}: {} vs {f}",
                p.frequency
            );
            if offset == 0.5 {
                assert!((s.amplitude[p.bin] - 1.27324).abs() < 2e-5);
            }
        }
    }

    #[test]
    fn strongest_line_looks_only_inside_its_band_and_refines_like_the_peaks() {
        // A 2.0 tone at 50 kHz outside the band, a 0.3 tone at 104.3 kHz and a 0.1 tone at
        // 112.7 kHz inside it: the band's strongest line is the 0.3 tone, refined exactly.
        let (n, fs) = (6000, 4e6);
        let x: Vec<f64> = tone(n, fs, 50e3, 2.0, 0.1)
            .iter()
            .zip(tone(n, fs, 104.3e3, 0.3, 0.4))
            .zip(tone(n, fs, 112.7e3, 0.1, 1.1))
            .map(|((a, b), c)| a + b + c)
            .collect();
        let s = amplitude_spectrum(&x, fs, Window::Hann).unwrap();
        let p = strongest_line(&s.frequency, &s.amplitude, 90e3, 120e3).unwrap();
        assert!((p.frequency - 104.3e3).abs() < 5.0, "{}", p.frequency);
        assert!((p.amplitude - 0.3).abs() < 3e-3, "{}", p.amplitude);
        // The same as the peak picker's refinement of that bin.
        let r = s.refine(p.bin);
        assert!(
            (r.frequency - p.frequency).abs() < 1e-6 && (r.amplitude - p.amplitude).abs() < 1e-12
        );
        // The whole spectrum's strongest line is the 50 kHz tone.
        let top = strongest_line(&s.frequency, &s.amplitude, 0.0, 2e6).unwrap();
        assert!((top.frequency - 50e3).abs() < 5.0);
        // Nothing in an empty band; malformed input refused.
        assert!(strongest_line(&s.frequency, &s.amplitude, 600e3, 601e3).is_none());
        assert!(strongest_line(&s.frequency, &s.amplitude[1..], 90e3, 120e3).is_none());
        assert!(strongest_line(&s.frequency, &s.amplitude, 120e3, 90e3).is_none());
    }

    #[test]
    fn peaks_are_sorted_separated_and_thresholded() {
        let (n, fs) = (10_000, 4e6);
        let mut x = tone(n, fs, 10.7e3, 1.0, 0.0);
        for (f, a) in [(50e3, 0.3), (120e3, 0.1), (275e3, 0.004)] {
            for (v, t) in x.iter_mut().zip(tone(n, fs, f, a, 1.0)) {
                *v += t;
            }
        }
        let s = amplitude_spectrum(&x, fs, Window::Hann).unwrap();
        let p = s.peaks(&PeakOptions::default());
        assert_eq!(p.len(), 3, "{p:?}"); // 275 kHz is below 1 % of the largest
        let f: Vec<f64> = p.iter().map(|p| p.frequency).collect();
        assert!((f[0] - 10.7e3).abs() < 5.0 && (f[1] - 50e3).abs() < 5.0);
        assert!((p[0].amplitude - 1.0).abs() < 2e-3 && (p[2].amplitude - 0.1).abs() < 1e-3);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(amplitude_spectrum(&[1.0, 2.0], 1.0, Window::Hann).is_err());
        assert!(amplitude_spectrum(&[1.0, f64::NAN, 0.0, 1.0], 1.0, Window::Hann).is_err());
        assert!(amplitude_spectrum(&[1.0; 8], 0.0, Window::Hann).is_err());
    }
}
