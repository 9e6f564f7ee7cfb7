//! Continuous wavelet transform with a complex Morlet wavelet, computed in the Fourier domain
//! (docs/analysis.md).
//!
//! The signal (mean removed by default) is zero-padded and transformed once; for every scale
//! `s` the spectrum is multiplied by the wavelet's Fourier transform `Ψ̂(sω)` and inverse
//! transformed (one plan, shared by all scales; scales run in parallel with rayon):
//!
//! `W(s, t_n) = IFFT( X(ω_k) · Ψ̂(s ω_k) )[n]`, `ω_k = 2π k fs / N_pad` (signed).
//!
//! Both wavelets are Gaussians in frequency, `G(sω) = exp(−(sω − ω_c)²/(2σ²))`:
//! - [`Wavelet::Morlet`] `{ω0}`: ω_c = ω0, σ = 1 (Torrence & Compo's Morlet; ω0 = 6 default);
//! - [`Wavelet::Cmor`] `{B, C}`: PyWavelets' `cmorB-C`, `ψ(t) = (πB)^{-1/2} e^{−t²/B} e^{i2πCt}`,
//!   whose transform is `exp(−π²B(f − C)²)`, i.e. ω_c = 2πC, σ = √(2/B).
//!
//! Scale ↔ frequency (peak mapping): `f = ω_c/(2π s)` — `f = ω0/(2πs)` for Morlet, `f = C/s`
//! for cmor, so PyWavelets' scale in samples is `a = s·fs = C·fs/f`.
//!
//! Normalisations ([`Normalization`]):
//! - `Amplitude` (L1, default, MATLAB's convention): `Ψ̂ = 2·G·H(ω)` (analytic: positive
//!   frequencies only). A tone `A cos(2πft)` gives `|W| = A` on the ridge at exactly `f`.
//! - `Energy` (L2, Torrence & Compo): `Ψ̂ = √(s·fs)·P·G·H(ω)` with `P` the peak of the
//!   unit-energy mother wavelet's transform (`π^{-1/4}√(2π)` for Morlet, `(2πB)^{1/4}` for
//!   cmor). Magnitudes of equal tones grow as √s; the ridge moves to the T&C Fourier period.
//! - `Pywt`: PyWavelets' `cwt(x, a, 'cmorB-C', method='fft')`. It convolves x with the
//!   *integrated* wavelet sampled at the scale and differences the result (`np.diff`), times
//!   `−√a`, i.e. `W(a, n) = a^{-1/2} Σ_m x[m] ∫_{m−½}^{m+½} ψ*((u − n)/a) du`, `a = s·fs` in
//!   samples. In the Fourier domain: `Ψ̂ = √(s·fs)·M(sω)·sinc(ω/2fs)` with `M` the mother
//!   wavelet's own transform (peak 1 for cmor, `π^{-1/4}√(2π)` for Morlet), *no* Heaviside
//!   (cmor is not exactly analytic) and the one-sample box of the difference as the sinc.
//!   PyWavelets' integer wavelet length and `floor/ceil` trimming also shift its output by
//!   `δ = ⌊(L−2)/2⌋ − L + 3/2 + 8a` samples (|δ| ≤ ½; `L` the length of its sampled integrated
//!   wavelet, which depends on its `precision`); `Pywt { precision: Some(p) }` applies that shift,
//!   `None` keeps the transform centred. With PyWavelets at `precision=18` the two agree to
//!   2·10⁻⁴ (test); at its default 12 its coarse wavelet table alone costs up to ~5 % in |W|.
//!   Conversion to L1 for a component near the scale's frequency f:
//!   `W_pywt ≈ √(s·fs)·P_pywt/2 · sinc(πf/fs) · W_L1`.
//!
//! Padding: zero padding only has to keep the circular convolution from wrapping, so the FFT
//! length is the smallest 2^a or 3·2^a ≥ N + 8.5·s_max·fs/σ (where the wavelet envelope has
//! fallen below e^{−36}); the spec's reference (next power of two ≥ 2N) gives the same values
//! to 6·10⁻¹³ of the largest |W| (test). Bins where `G < e^{−36}` are skipped.
//!
//! Cone of influence: the e-folding time of the wavelet power, `√2·s/σ` (T&C's `√2 s` for
//! Morlet), reaching the nearest record edge: `f_coi(t) = ω_c√2/(2πσ·t_edge)`
//! (`1.350/t_edge` for ω0 = 6); stored per sample and clamped to Nyquist at the edges.

use super::{check_rate, check_series, AnalysisError};
use crate::signal::rfft::RealFft;
use rayon::prelude::*;
use rustfft::num_complex::{Complex, Complex64};
use rustfft::num_traits::Float;
use rustfft::{Fft, FftNum, FftPlanner};
use std::f64::consts::{PI, SQRT_2};

/// Where `G(sω)` is treated as zero: `|sω − ω_c| > CUTOFF·σ` (e^{−36} ≈ 2·10⁻¹⁶).
pub(crate) const CUTOFF: f64 = 8.5;

/// Largest padded length accepted (2³³ complex samples would be 128 GiB).
pub(crate) const MAX_LEN: usize = 1 << 33;

/// The mother wavelet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Wavelet {
    /// Complex Morlet `π^{-1/4} e^{iω0 t} e^{−t²/2}` (ω0 = 6 is the usual choice).
    Morlet { omega0: f64 },
    /// PyWavelets' `cmorB-C`: bandwidth B, centre frequency C (cycles per unit scale).
    Cmor { bandwidth: f64, center: f64 },
}

impl Default for Wavelet {
    fn default() -> Self {
        Wavelet::Morlet { omega0: 6.0 }
    }
}

impl Wavelet {
    /// Centre angular frequency ω_c (rad per unit scale) and spectral width σ of `G`.
    pub(crate) fn gaussian(&self) -> (f64, f64) {
        match *self {
            Wavelet::Morlet { omega0 } => (omega0, 1.0),
            Wavelet::Cmor { bandwidth, center } => (2.0 * PI * center, (2.0 / bandwidth).sqrt()),
        }
    }

    /// Peak of the Fourier transform of the mother wavelet as PyWavelets defines it.
    fn pywt_peak(&self) -> f64 {
        match *self {
            Wavelet::Morlet { .. } => PI.powf(-0.25) * (2.0 * PI).sqrt(),
            Wavelet::Cmor { .. } => 1.0,
        }
    }

    /// Peak of the Fourier transform of the unit-energy mother wavelet.
    pub(crate) fn energy_peak(&self) -> f64 {
        match *self {
            Wavelet::Morlet { .. } => PI.powf(-0.25) * (2.0 * PI).sqrt(),
            Wavelet::Cmor { bandwidth, .. } => (2.0 * PI * bandwidth).powf(0.25),
        }
    }

    /// Frequency (Hz) that scale `s` (s) is tuned to: `ω_c/(2πs)`.
    pub fn frequency_of_scale(&self, s: f64) -> f64 {
        self.gaussian().0 / (2.0 * PI * s)
    }

    /// Scale (s) tuned to frequency `f` (Hz).
    pub fn scale_of_frequency(&self, f: f64) -> f64 {
        self.gaussian().0 / (2.0 * PI * f)
    }

    /// e-folding time (s) of the wavelet power at scale `s`: `√2·s/σ`.
    pub fn e_folding_time(&self, s: f64) -> f64 {
        SQRT_2 * s / self.gaussian().1
    }

    /// Lowest trusted frequency (Hz) at `t_edge` seconds from the nearest record edge.
    pub fn coi_frequency(&self, t_edge: f64) -> f64 {
        let (wc, sigma) = self.gaussian();
        wc * SQRT_2 / (2.0 * PI * sigma * t_edge)
    }

    /// One-sided time support (samples at `fs`) of the wavelet at scale `s`: its envelope
    /// `exp(−σ²t²/(2s²))` falls below e^{−36} beyond `CUTOFF·s·fs/σ` (the time-domain twin of
    /// the frequency cut-off). The zero padding and the streaming overlap are this long.
    pub(crate) fn support_samples(&self, s: f64, fs: f64) -> f64 {
        CUTOFF * s * fs / self.gaussian().1
    }

    pub(crate) fn validate(&self) -> Result<(), AnalysisError> {
        let bad = |x: f64| x.is_nan() || x.is_infinite() || x <= 0.0;
        match *self {
            Wavelet::Morlet { omega0 } if bad(omega0) => Err(AnalysisError::parameter(
                "Morlet omega0",
                omega0,
                "must be finite and > 0 (6 is usual)",
            )),
            Wavelet::Cmor { bandwidth, .. } if bad(bandwidth) => Err(AnalysisError::parameter(
                "cmor bandwidth B",
                bandwidth,
                "must be finite and > 0",
            )),
            Wavelet::Cmor { center, .. } if bad(center) => Err(AnalysisError::parameter(
                "cmor centre frequency C",
                center,
                "must be finite and > 0",
            )),
            _ => Ok(()),
        }
    }
}

impl std::str::FromStr for Wavelet {
    type Err = String;
    /// `"morlet"` (ω0 = 6), `"morlet<ω0>"` or PyWavelets' `"cmorB-C"`, e.g. `"cmor1.5-1.0"`.
    fn from_str(s: &str) -> Result<Self, String> {
        let err = || {
            format!("unknown wavelet `{s}` (expected \"morlet\", \"morlet6\" or \"cmorB-C\" like \"cmor1.5-1.0\")")
        };
        if s == "morlet" {
            return Ok(Wavelet::default());
        }
        if let Some(w0) = s.strip_prefix("morlet") {
            let omega0 = w0.parse().map_err(|_| err())?;
            return Ok(Wavelet::Morlet { omega0 });
        }
        let bc = s.strip_prefix("cmor").ok_or_else(err)?;
        let (b, c) = bc.split_once('-').ok_or_else(err)?;
        Ok(Wavelet::Cmor {
            bandwidth: b.parse().map_err(|_| err())?,
            center: c.parse().map_err(|_| err())?,
        })
    }
}

impl std::fmt::Display for Wavelet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Wavelet::Morlet { omega0 } => write!(f, "morlet{omega0}"),
            Wavelet::Cmor { bandwidth, center } => write!(f, "cmor{bandwidth}-{center}"),
        }
    }
}

/// How the wavelet at each scale is scaled (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Normalization {
    /// L1: a tone of amplitude A reads |W| = A on its ridge.
    #[default]
    Amplitude,
    /// L2 (Torrence & Compo 1998), energy-preserving, time unit = one sample.
    Energy,
    /// PyWavelets' `cwt` (√a-scaled, no Heaviside, one-sample box); with `precision` (its
    /// argument, default there 12) also its sub-sample time offset.
    Pywt { precision: Option<u32> },
}

impl std::fmt::Display for Normalization {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Normalization::Amplitude => "L1",
            Normalization::Energy => "L2",
            Normalization::Pywt { .. } => "pywt",
        })
    }
}

/// The frequencies to analyse.
#[derive(Debug, Clone, PartialEq)]
pub enum FrequencyGrid {
    /// `f_j = f_min·2^{j/voices}` for all `f_j ≤ f_max` (the spec's grid: 10 kHz–1 MHz at 10
    /// voices per octave = 67 frequencies).
    VoicesPerOctave {
        f_min_hz: f64,
        f_max_hz: f64,
        voices: usize,
    },
    /// `count` log-spaced frequencies from `f_min` to `f_max` inclusive.
    Log {
        f_min_hz: f64,
        f_max_hz: f64,
        count: usize,
    },
    /// These frequencies (Hz), strictly increasing.
    Explicit(Vec<f64>),
}

impl Default for FrequencyGrid {
    fn default() -> Self {
        FrequencyGrid::VoicesPerOctave {
            f_min_hz: 10e3,
            f_max_hz: 1e6,
            voices: 10,
        }
    }
}

impl FrequencyGrid {
    /// The frequencies (Hz, increasing), checked against Nyquist `fs/2`.
    pub fn frequencies(&self, fs: f64) -> Result<Vec<f64>, AnalysisError> {
        let range = |lo: f64, hi: f64, reason: &str| AnalysisError::FrequencyRange {
            low_hz: lo,
            high_hz: hi,
            reason: reason.to_string(),
        };
        let check_band = |lo: f64, hi: f64| {
            if !(lo.is_finite() && hi.is_finite()) || lo <= 0.0 {
                Err(range(lo, hi, "bounds must be finite and > 0"))
            } else if lo > hi {
                Err(range(lo, hi, "lower bound above upper bound"))
            } else if hi > fs / 2.0 {
                Err(range(
                    lo,
                    hi,
                    &format!("above the Nyquist frequency {} Hz", fs / 2.0),
                ))
            } else {
                Ok(())
            }
        };
        let f = match self {
            &FrequencyGrid::VoicesPerOctave {
                f_min_hz,
                f_max_hz,
                voices,
            } => {
                check_band(f_min_hz, f_max_hz)?;
                if voices == 0 {
                    return Err(AnalysisError::parameter(
                        "voices per octave",
                        0,
                        "must be ≥ 1",
                    ));
                }
                // Tolerance so that an f_max sitting on the grid is included despite rounding.
                let n = ((f_max_hz / f_min_hz).log2() * voices as f64 + 1e-9).floor() as usize + 1;
                (0..n)
                    .map(|j| f_min_hz * 2f64.powf(j as f64 / voices as f64))
                    .collect()
            }
            &FrequencyGrid::Log {
                f_min_hz,
                f_max_hz,
                count,
            } => {
                check_band(f_min_hz, f_max_hz)?;
                match count {
                    0 => {
                        return Err(AnalysisError::parameter(
                            "frequency count",
                            0,
                            "must be ≥ 1",
                        ))
                    }
                    1 => vec![f_min_hz],
                    _ => {
                        if f_min_hz == f_max_hz {
                            return Err(range(
                                f_min_hz,
                                f_max_hz,
                                "empty band for several frequencies",
                            ));
                        }
                        let r = (f_max_hz / f_min_hz).ln() / (count - 1) as f64;
                        (0..count)
                            .map(|j| f_min_hz * (r * j as f64).exp())
                            .collect()
                    }
                }
            }
            FrequencyGrid::Explicit(f) => {
                let (lo, hi) = (
                    f.first().copied().unwrap_or(f64::NAN),
                    f.last().copied().unwrap_or(f64::NAN),
                );
                if f.is_empty() {
                    return Err(range(lo, hi, "no frequencies given"));
                }
                check_band(lo, hi)?;
                if f.windows(2).any(|w| w[1].is_nan() || w[1] <= w[0]) {
                    return Err(range(
                        lo,
                        hi,
                        "explicit frequencies must be finite and strictly increasing",
                    ));
                }
                f.clone()
            }
        };
        Ok(f)
    }
}

/// CWT settings.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CwtOptions {
    pub wavelet: Wavelet,
    pub normalization: Normalization,
    pub frequencies: FrequencyGrid,
    /// Keep the mean (PyWavelets does not remove it); by default it is removed.
    pub keep_mean: bool,
}

/// Magnitude scalogram `|W|` (signal units with [`Normalization::Amplitude`]).
#[derive(Debug, Clone)]
pub struct Scalogram {
    /// Analysed frequencies, Hz, increasing (row index).
    pub frequencies_hz: Vec<f64>,
    /// Wavelet scale of each row, s (`f = ω_c/(2πs)`; PyWavelets' scale is `s·fs`).
    pub scales_s: Vec<f64>,
    pub sample_rate_hz: f64,
    pub n_time: usize,
    /// `|W|`, row-major `[n_freq][n_time]`, f32 (the stored precision, halves the memory).
    pub magnitude: Vec<f32>,
    /// Cone of influence per sample, Hz: below it edge effects matter.
    pub coi_hz: Vec<f64>,
    pub wavelet: Wavelet,
    pub normalization: Normalization,
}

impl Scalogram {
    /// The row of frequency index `j`.
    pub fn row(&self, j: usize) -> &[f32] {
        &self.magnitude[j * self.n_time..(j + 1) * self.n_time]
    }
    /// Sample times, s, from 0.
    pub fn time_s(&self) -> Vec<f64> {
        (0..self.n_time)
            .map(|n| n as f64 / self.sample_rate_hz)
            .collect()
    }
}

/// Complex coefficients `W`, row-major `[n_freq][n_time]`, f64.
#[derive(Debug, Clone)]
pub struct ComplexScalogram {
    pub frequencies_hz: Vec<f64>,
    pub scales_s: Vec<f64>,
    pub sample_rate_hz: f64,
    pub n_time: usize,
    pub coefficients: Vec<Complex64>,
    pub coi_hz: Vec<f64>,
    pub wavelet: Wavelet,
    pub normalization: Normalization,
}

impl ComplexScalogram {
    pub fn row(&self, j: usize) -> &[Complex64] {
        &self.coefficients[j * self.n_time..(j + 1) * self.n_time]
    }

    /// Scale step δj in octaves of an L1 transform on a uniform log grid (the energy and
    /// reconstruction sums need both).
    fn octave_step(&self) -> Result<f64, AnalysisError> {
        if self.normalization != Normalization::Amplitude {
            return Err(AnalysisError::parameter(
                "normalization",
                self.normalization,
                "variance and reconstruction sums are for the L1 (amplitude) transform",
            ));
        }
        let f = &self.frequencies_hz;
        if f.len() < 2 {
            return Err(AnalysisError::parameter(
                "frequencies",
                f.len(),
                "need at least 2",
            ));
        }
        let dj = (f[1] / f[0]).log2();
        if f.windows(2)
            .any(|w| ((w[1] / w[0]).log2() / dj - 1.0).abs() > 1e-6)
        {
            return Err(AnalysisError::parameter(
                "frequencies",
                "non-uniform",
                "need a log-uniform grid (VoicesPerOctave or Log)",
            ));
        }
        Ok(dj)
    }

    /// Variance of the signal estimated from the scalogram (§4.2):
    /// `(ln2/(2 I_E))·(δj/N)·Σ_n Σ_j |W|²`, `I_E = ∫₀^∞ G(u)²/u du` (0.299696 for ω0 = 6).
    /// Captures the variance inside the analysed band only.
    pub fn variance(&self) -> Result<f64, AnalysisError> {
        let dj = self.octave_step()?;
        let (i_e, _) = reconstruction_integrals(&self.wavelet);
        let sum: f64 = self.coefficients.iter().map(|c| c.norm_sqr()).sum();
        Ok(std::f64::consts::LN_2 / (2.0 * i_e) * dj / self.n_time as f64 * sum)
    }

    /// Inverse transform by the single-integral formula (§4.2):
    /// `x(t_n) ≈ (δj·ln2/I_R)·Σ_j Re W(s_j, t_n)`, `I_R = ∫₀^∞ G(u)/u du` (0.430514 for ω0 = 6).
    pub fn reconstruct(&self) -> Result<Vec<f64>, AnalysisError> {
        let dj = self.octave_step()?;
        let (_, i_r) = reconstruction_integrals(&self.wavelet);
        let c = dj * std::f64::consts::LN_2 / i_r;
        let mut x = vec![0.0; self.n_time];
        for j in 0..self.frequencies_hz.len() {
            for (xi, w) in x.iter_mut().zip(self.row(j)) {
                *xi += c * w.re;
            }
        }
        Ok(x)
    }
}

/// `(I_E, I_R) = (∫₀^∞ G(u)²/u du, ∫₀^∞ G(u)/u du)` for the wavelet's Gaussian `G`, by
/// Simpson's rule in ln u from 10⁻³·ω_c to ω_c + 12σ. (Both integrals diverge
/// logarithmically at u → 0 as `G(0)·ln(1/u)`; `G(0) = e^{−18}` for ω0 = 6, so the cut-off
/// changes them by ~10⁻⁷ — in practice the lowest analysed scale cuts them anyway.)
pub fn reconstruction_integrals(wavelet: &Wavelet) -> (f64, f64) {
    let (wc, sigma) = wavelet.gaussian();
    let (a, b) = ((1e-3 * wc).ln(), (wc + 12.0 * sigma).ln());
    let m = 20_000; // even
    let h = (b - a) / m as f64;
    let (mut i_e, mut i_r) = (0.0, 0.0);
    for i in 0..=m {
        let u = (a + i as f64 * h).exp();
        let g = (-(u - wc).powi(2) / (2.0 * sigma * sigma)).exp();
        let w = if i == 0 || i == m {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        i_e += w * g * g;
        i_r += w * g;
    }
    (i_e * h / 3.0, i_r * h / 3.0)
}

/// The normalisation's peak gain of `Ψ̂` at scale `s` (module docs), whether the wavelet is
/// analytic (positive frequencies only), and PyWavelets' sub-sample shift when it applies.
pub(crate) fn normalization_terms(
    normalization: Normalization,
    wavelet: &Wavelet,
    s: f64,
    fs: f64,
) -> (f64, bool, Option<f64>) {
    let root = (s * fs).sqrt();
    match normalization {
        Normalization::Amplitude => (2.0, true, None),
        Normalization::Energy => (root * wavelet.energy_peak(), true, None),
        Normalization::Pywt { precision } => (
            root * wavelet.pywt_peak(),
            false,
            Some(precision.map_or(0.0, |p| pywt_time_offset(s * fs, p))),
        ),
    }
}

/// The Gaussian filter of scale `s` on the `n_pad`-point FFT grid at `fs`: the signed bins
/// `k_lo…k_hi` where `G(sω_k)` is not negligible (bin `n_pad/2` counts as positive; analytic:
/// `k ≥ 1`) and the gain `peak·G(sω_k)/n_pad` there (the `1/n_pad` of the inverse FFT folded in).
pub(crate) struct ScaleFilter {
    pub(crate) k_lo: i64,
    pub(crate) k_hi: i64,
    s: f64,
    wc: f64,
    dw: f64,
    scale: f64,
    inv_two_var: f64,
}

impl ScaleFilter {
    pub(crate) fn new(
        wavelet: &Wavelet,
        s: f64,
        fs: f64,
        n_pad: usize,
        peak: f64,
        analytic: bool,
    ) -> Self {
        let (wc, sigma) = wavelet.gaussian();
        let dw = 2.0 * PI * fs / n_pad as f64;
        let half = (n_pad / 2) as i64;
        let k_lo = (((wc - CUTOFF * sigma) / s) / dw).ceil() as i64;
        let k_hi = ((((wc + CUTOFF * sigma) / s) / dw).floor() as i64).min(half);
        ScaleFilter {
            k_lo: k_lo.max(if analytic { 1 } else { 1 - half }),
            k_hi,
            s,
            wc,
            dw,
            scale: peak / n_pad as f64,
            inv_two_var: 0.5 / (sigma * sigma),
        }
    }

    /// `peak·G(s ω_k)/n_pad` at signed bin `k`.
    pub(crate) fn gain(&self, k: i64) -> f64 {
        let d = self.s * k as f64 * self.dw - self.wc;
        self.scale * (-d * d * self.inv_two_var).exp()
    }
}

/// Everything shared by all scales: the padded series' one-sided spectrum (bins 0…N_pad/2 of
/// a real-input FFT; negative bins are their conjugates).
pub(crate) struct Prepared {
    pub(crate) spectrum: Vec<Complex64>,
    pub(crate) n: usize,
    pub(crate) n_pad: usize,
    pub(crate) fs: f64,
    pub(crate) frequencies: Vec<f64>,
    pub(crate) scales: Vec<f64>,
    pub(crate) wavelet: Wavelet,
    pub(crate) normalization: Normalization,
}

/// Smallest 2^a or 3·2^a ≥ n (fast rustfft lengths).
pub(crate) fn fast_len(n: usize) -> usize {
    let p2 = n.next_power_of_two();
    let p3 = 3 * n.div_ceil(3).next_power_of_two();
    p2.min(p3)
}

/// `min_pad`: a longer FFT than needed (tests compare against the spec's ≥ 2N padding).
pub(crate) fn prepare(
    signal: &[f64],
    fs: f64,
    opts: &CwtOptions,
    min_pad: usize,
) -> Result<Prepared, AnalysisError> {
    check_rate(fs)?;
    check_series(signal, 4, "CWT")?;
    opts.wavelet.validate()?;
    let frequencies = opts.frequencies.frequencies(fs)?;
    let scales: Vec<f64> = frequencies
        .iter()
        .map(|&f| opts.wavelet.scale_of_frequency(f))
        .collect();
    let n = signal.len();
    let s_max = scales.iter().cloned().fold(0.0, f64::max);
    let support = opts.wavelet.support_samples(s_max, fs).ceil();
    // Absurdly low frequencies (a wavelet of billions of samples) would overflow the FFT size.
    if support > MAX_LEN as f64 || n + min_pad > MAX_LEN {
        return Err(AnalysisError::FrequencyRange {
            low_hz: frequencies[0],
            high_hz: frequencies[frequencies.len() - 1],
            reason: format!(
                "the lowest frequency needs a wavelet of {support:.3e} samples (limit {MAX_LEN})"
            ),
        });
    }
    let n_pad = fast_len((n + support as usize).max(min_pad));
    let rfft = RealFft::new(&mut FftPlanner::<f64>::new(), n_pad);
    let spectrum = padded_spectrum(signal, opts.keep_mean, &rfft);
    Ok(Prepared {
        spectrum,
        n,
        n_pad,
        fs,
        frequencies,
        scales,
        wavelet: opts.wavelet,
        normalization: opts.normalization,
    })
}

/// One-sided spectrum of the (mean-removed unless `keep_mean`) series zero-padded to the
/// plan's length.
pub(crate) fn padded_spectrum(
    signal: &[f64],
    keep_mean: bool,
    rfft: &RealFft<f64>,
) -> Vec<Complex64> {
    let mean = if keep_mean {
        0.0
    } else {
        signal.iter().sum::<f64>() / signal.len() as f64
    };
    // The series is real: one real-input FFT (half the work and memory of a complex one).
    let mut padded = vec![0.0; rfft.len()];
    for (b, v) in padded.iter_mut().zip(signal) {
        *b = v - mean;
    }
    let mut spectrum = vec![Complex64::default(); rfft.spectrum_len()];
    rfft.forward(&padded, &mut spectrum);
    spectrum
}

impl Prepared {
    /// The same grid and padding with no spectrum (for another series of the same length).
    pub(crate) fn same_grid(&self) -> Prepared {
        Prepared {
            spectrum: Vec::new(),
            n: self.n,
            n_pad: self.n_pad,
            fs: self.fs,
            frequencies: self.frequencies.clone(),
            scales: self.scales.clone(),
            wavelet: self.wavelet,
            normalization: self.normalization,
        }
    }

    /// n_freq × n_time, refused beyond MAX_LEN values rather than overflowing.
    fn output_len(&self) -> Result<usize, AnalysisError> {
        match self.n.checked_mul(self.frequencies.len()) {
            Some(len) if len <= MAX_LEN => Ok(len),
            _ => Err(AnalysisError::parameter(
                "scalogram size",
                format!(
                    "{} frequencies × {} samples",
                    self.frequencies.len(),
                    self.n
                ),
                format!(
                    "more than {MAX_LEN} values; analyse a shorter window or fewer frequencies"
                ),
            )),
        }
    }

    /// Fills `buf` with `X·Ψ̂(s_j ω)/N_pad` (computed in f64, stored in `T`) and inverse
    /// transforms it in place with `ifft` (length N_pad, precision `T`).
    fn row<T: FftNum + Float>(
        &self,
        j: usize,
        ifft: &dyn Fft<T>,
        buf: &mut [Complex<T>],
        scratch: &mut [Complex<T>],
    ) {
        let s = self.scales[j];
        let (peak, analytic, pywt) =
            normalization_terms(self.normalization, &self.wavelet, s, self.fs);
        let filter = ScaleFilter::new(&self.wavelet, s, self.fs, self.n_pad, peak, analytic);
        buf.fill(Complex::new(T::zero(), T::zero()));
        let cast = |v: f64| T::from_f64(v).unwrap_or_else(T::zero);
        for k in filter.k_lo..=filter.k_hi {
            let i = k.rem_euclid(self.n_pad as i64) as usize;
            let g = filter.gain(k);
            // X_{−k} = conj X_k for the real series.
            let x = if k >= 0 {
                self.spectrum[k as usize]
            } else {
                self.spectrum[(-k) as usize].conj()
            };
            let c = x * match pywt {
                None => Complex64::new(g, 0.0),
                Some(shift) => {
                    // Cycles per sample; sinc = the difference's one-sample box.
                    let fc = k as f64 / self.n_pad as f64;
                    let box_ = if k == 0 {
                        1.0
                    } else {
                        (PI * fc).sin() / (PI * fc)
                    };
                    Complex64::from_polar(g * box_, 2.0 * PI * fc * shift)
                }
            };
            buf[i] = Complex::new(cast(c.re), cast(c.im));
        }
        ifft.process_with_scratch(buf, scratch);
    }

    /// Runs all scales in parallel with the inverse transform in precision `T`, mapping each
    /// coefficient through `f` into `out`.
    ///
    /// Memory: besides `out` and the one-sided spectrum (N_pad/2 + 1 complex f64), each running
    /// block holds one N_pad-point buffer and the FFT scratch in `T` — O(threads × N_pad).
    fn run<T: FftNum + Float, O: Send>(&self, out: &mut [O], f: impl Fn(Complex<T>) -> O + Sync) {
        let ifft = FftPlanner::<T>::new().plan_fft_inverse(self.n_pad);
        let scratch_len = ifft.get_inplace_scratch_len();
        let zero = Complex::new(T::zero(), T::zero());
        let n_freq = self.frequencies.len();
        // A few blocks of rows per thread: each block allocates its N_pad-sized buffers once
        // (not once per rayon split), and several blocks still let work stealing even out a
        // core that is busy with something else.
        let blocks = 4 * rayon::current_num_threads().max(1);
        let rows_per_block = n_freq.div_ceil(blocks).max(1);
        out.par_chunks_mut(self.n * rows_per_block)
            .enumerate()
            .for_each(|(b, block)| {
                let mut buf = vec![zero; self.n_pad];
                let mut scratch = vec![zero; scratch_len];
                for (i, row) in block.chunks_mut(self.n).enumerate() {
                    self.row(b * rows_per_block + i, &*ifft, &mut buf, &mut scratch);
                    for (o, c) in row.iter_mut().zip(&buf[..self.n]) {
                        *o = f(*c);
                    }
                }
            });
    }

    pub(crate) fn coi(&self) -> Vec<f64> {
        (0..self.n)
            .map(|i| coi_at_edge(&self.wavelet, i.min(self.n - 1 - i), self.fs))
            .collect()
    }
}

/// The cone of influence `edge` samples from the nearest record edge, clamped to Nyquist
/// (and Nyquist on the edge itself).
pub(crate) fn coi_at_edge(wavelet: &Wavelet, edge: usize, fs: f64) -> f64 {
    let nyquist = fs / 2.0;
    let t_edge = edge as f64 / fs;
    if t_edge > 0.0 {
        wavelet.coi_frequency(t_edge).min(nyquist)
    } else {
        nyquist
    }
}

/// PyWavelets' output offset in samples at scale `a` (samples) for its `precision`: its
/// integrated wavelet is tabulated on `2^precision` points over [−8, 8] and sampled at
/// `⌊i/(a·step)⌋`, `i < ⌈16a + 1⌉` (entries past the table dropped), giving `L` taps; after
/// `np.diff` and the `floor`/`ceil` trim, output `i` is centred on `i + ⌊(L−2)/2⌋ − L + 3/2 + 8a`.
/// (Only PyWavelets' support of [−8, 8] is used, as for its complex Morlet.)
pub fn pywt_time_offset(a: f64, precision: u32) -> f64 {
    let size = 2f64.powi(precision.min(40) as i32);
    let step = 16.0 / (size - 1.0);
    let count = (16.0 * a + 1.0).ceil() as i64;
    let mut taps = count;
    while taps > 0 && ((taps - 1) as f64 / (a * step)).floor() >= size {
        taps -= 1;
    }
    let l = taps as f64;
    ((l - 2.0) / 2.0).floor() - l + 1.5 + 8.0 * a
}

/// Magnitude scalogram of `signal` sampled at `fs` (Hz). See the module docs for the
/// definition; with default options: analytic Morlet ω0 = 6, L1, 10 kHz–1 MHz, 10 voices per
/// octave, mean removed.
pub fn cwt_morlet(signal: &[f64], fs: f64, opts: &CwtOptions) -> Result<Scalogram, AnalysisError> {
    let p = prepare(signal, fs, opts, 0)?;
    let mut magnitude = vec![0f32; p.output_len()?];
    // Inverse transforms in f32: the output is f32 anyway, and the single-precision FFT
    // (twice the SIMD width, half the memory traffic) stays within ~1e-6 of the largest |W|
    // (test `f32_scalogram_matches_the_f64_transform`).
    // |W| from the f32 parts in f64: no overflow or underflow, and vectorisable (unlike hypot).
    p.run::<f32, _>(&mut magnitude, |c| {
        (f64::from(c.re).powi(2) + f64::from(c.im).powi(2)).sqrt() as f32
    });
    Ok(Scalogram {
        coi_hz: p.coi(),
        n_time: p.n,
        sample_rate_hz: fs,
        magnitude,
        wavelet: p.wavelet,
        normalization: p.normalization,
        frequencies_hz: p.frequencies,
        scales_s: p.scales,
    })
}

/// Complex coefficients (f64) of the same transform as [`cwt_morlet`]; 16 bytes per value,
/// so meant for short records, phase work and reference comparisons.
pub fn cwt_morlet_complex(
    signal: &[f64],
    fs: f64,
    opts: &CwtOptions,
) -> Result<ComplexScalogram, AnalysisError> {
    cwt_complex_padded(signal, fs, opts, 0)
}

pub(crate) fn cwt_complex_padded(
    signal: &[f64],
    fs: f64,
    opts: &CwtOptions,
    min_pad: usize,
) -> Result<ComplexScalogram, AnalysisError> {
    let p = prepare(signal, fs, opts, min_pad)?;
    let mut coefficients = vec![Complex64::default(); p.output_len()?];
    p.run::<f64, _>(&mut coefficients, |c| c);
    Ok(ComplexScalogram {
        coi_hz: p.coi(),
        n_time: p.n,
        sample_rate_hz: fs,
        coefficients,
        wavelet: p.wavelet,
        normalization: p.normalization,
        frequencies_hz: p.frequencies,
        scales_s: p.scales,
    })
}

/// Median of the ridge frequencies the cone of influence trusts (Hz; `None`: none trusted).
pub fn median_trusted(frequency_hz: &[f64], trusted: &[bool]) -> Option<f64> {
    let mut f: Vec<f64> = frequency_hz
        .iter()
        .zip(trusted)
        .filter(|(_, t)| **t)
        .map(|(f, _)| *f)
        .collect();
    if f.is_empty() {
        return None;
    }
    f.sort_by(f64::total_cmp);
    Some(f[f.len() / 2])
}

/// The dominant frequency at every sample.
#[derive(Debug, Clone)]
pub struct Ridge {
    /// Ridge frequency, Hz, refined by a parabola through ln|W| against ln f.
    pub frequency_hz: Vec<f64>,
    /// |W| at the refined ridge (the parabola's vertex value).
    pub magnitude: Vec<f64>,
    /// Grid row of the raw maximum.
    pub index: Vec<usize>,
    /// Ridge frequency at or above the cone of influence (free of edge effects).
    pub trusted: Vec<bool>,
}

/// Ridge of a scalogram: per sample the row of largest |W|, refined by the parabola through
/// ln|W| of it and its two neighbours against ln f (the spec's reference interpolation; for the
/// Gaussian wavelet ln|W| is nearly quadratic there). No refinement at the grid's ends, with a
/// zero neighbour or with one frequency; a column of zeros gives the lowest frequency and 0.
pub fn ridge(s: &Scalogram) -> Ridge {
    let (nf, nt) = (s.frequencies_hz.len(), s.n_time);
    let logf: Vec<f64> = s.frequencies_hz.iter().map(|f| f.ln()).collect();
    let mut out = Ridge {
        frequency_hz: Vec::with_capacity(nt),
        magnitude: Vec::with_capacity(nt),
        index: Vec::with_capacity(nt),
        trusted: Vec::with_capacity(nt),
    };
    // The raw maximum per sample, row by row (contiguous reads; the first maximum wins, as a
    // scan up the column would give), in parallel over blocks of samples.
    let mut best_row = vec![0usize; nt];
    best_row
        .par_chunks_mut(8192)
        .enumerate()
        .for_each(|(b, rows)| {
            let start = b * 8192;
            let mut best: Vec<f32> = s.magnitude[start..start + rows.len()].to_vec();
            for i in 1..nf {
                let row = &s.magnitude[i * nt + start..i * nt + start + rows.len()];
                for ((r, m), v) in rows.iter_mut().zip(best.iter_mut()).zip(row) {
                    if *v > *m {
                        *m = *v;
                        *r = i;
                    }
                }
            }
        });
    for (n, &j) in best_row.iter().enumerate() {
        let at = |j: usize| s.magnitude[j * nt + n] as f64;
        let (mut u, mut y) = (logf[j], at(j));
        if j > 0 && j + 1 < nf && at(j - 1) > 0.0 && at(j + 1) > 0.0 {
            let (u0, u1, u2) = (logf[j - 1], logf[j], logf[j + 1]);
            let (y0, y1, y2) = (at(j - 1).ln(), at(j).ln(), at(j + 1).ln());
            // Vertex of the parabola through three (u, y) points, general spacing.
            let num = (u1 - u0).powi(2) * (y1 - y2) - (u1 - u2).powi(2) * (y1 - y0);
            let den = (u1 - u0) * (y1 - y2) - (u1 - u2) * (y1 - y0);
            if den != 0.0 {
                let uv = (u1 - 0.5 * num / den).clamp(u0, u2);
                // Lagrange form evaluated at the vertex.
                let l0 = (uv - u1) * (uv - u2) / ((u0 - u1) * (u0 - u2));
                let l1 = (uv - u0) * (uv - u2) / ((u1 - u0) * (u1 - u2));
                let l2 = (uv - u0) * (uv - u1) / ((u2 - u0) * (u2 - u1));
                u = uv;
                y = (y0 * l0 + y1 * l1 + y2 * l2).exp();
            }
        }
        let f = u.exp();
        out.frequency_hz.push(f);
        out.magnitude.push(y);
        out.index.push(j);
        out.trusted.push(f >= s.coi_hz[n]);
    }
    out
}
