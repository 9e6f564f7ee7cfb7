//! Which spectral and wavelet features are real (docs/analysis.md, "Significance"): the
//! red-noise (AR(1)) background of Torrence & Compo (1998, "T&C") and the χ² confidence
//! levels of the local wavelet power, the global wavelet spectrum, the scale-averaged power
//! and the FFT amplitude spectrum.
//!
//! - Background: the lag-1 autocorrelation `α = r₁` of the analysed (mean-removed) window,
//!   `r₁ = Σ (x_n − x̄)(x_{n+1} − x̄) / Σ (x_n − x̄)²` (the biased sample ACF at lag 1), and
//!   the AR(1) spectrum normalised to unit mean over the band, T&C eq. 16:
//!   `P(f) = (1 − α²)/(1 + α² − 2α cos(2π f δt))`; white noise is `α = 0`.
//! - The wavelet power of the background at scale `s` is `σ²·P(f_F)·K(s)`, `f_F` the
//!   wavelet's Fourier frequency (T&C Table 1: `(ω_c + √(ω_c² + 2σ_w²))/(4πs)`, `1/(1.033 s)`
//!   for ω0 = 6) and `K(s)` the white-noise power of the transform's normalisation (1 for
//!   T&C's L2; `2σ_w/(√π s fs)` for the L1 transform hdi reports).
//! - Levels: local `χ²₂(p)/2` (T&C eq. 18); global spectrum `χ²_ν(p)/ν` with
//!   `ν = 2√(1 + (n_a δt/(γ s))²)`, γ = 2.32 (eq. 23); scale-averaged power eqs. 25–28 with
//!   δj0 = 0.60. γ and δj0 are T&C's Table 2 values for the Morlet wavelet with ω0 = 6: the
//!   global and scale-averaged levels are refused for other wavelets.
//!
//! Pure functions on the scalogram and the series; no I/O.

use super::cwt::{Normalization, Scalogram, Wavelet};
use super::{check_series, AnalysisError};
use crate::signal::spectrum::{AmplitudeSpectrum, Window};
use rayon::prelude::*;
use std::f64::consts::PI;

/// T&C Table 2, Morlet ω0 = 6: decorrelation factor of the time-averaged power.
pub const MORLET_GAMMA: f64 = 2.32;
/// T&C Table 2, Morlet ω0 = 6: scale-decorrelation length (octaves).
pub const MORLET_DJ0: f64 = 0.60;

/// The red-noise background of a series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RedNoise {
    /// Lag-1 autocorrelation α (0: white noise).
    pub alpha: f64,
    /// Variance σ² of the series (signal units²).
    pub variance: f64,
}

/// Lag-1 autocorrelation `r₁` of `x` (mean removed; the biased sample ACF at lag 1).
pub fn lag1_autocorrelation(x: &[f64]) -> Result<f64, AnalysisError> {
    check_series(x, 3, "lag-1 autocorrelation")?;
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let c0: f64 = x.iter().map(|v| (v - mean).powi(2)).sum();
    if c0 <= 0.0 {
        return Err(AnalysisError::parameter(
            "series",
            "constant",
            "a constant series has no autocorrelation (nothing to test)",
        ));
    }
    let c1: f64 = x.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)).sum();
    Ok(c1 / c0)
}

impl RedNoise {
    /// The AR(1) background of `x`: its lag-1 autocorrelation and variance (ddof 0).
    pub fn estimate(x: &[f64]) -> Result<RedNoise, AnalysisError> {
        let alpha = lag1_autocorrelation(x)?;
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let variance = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        RedNoise::new(alpha, variance)
    }

    /// A background with a stated α (|α| < 1) and variance (> 0).
    pub fn new(alpha: f64, variance: f64) -> Result<RedNoise, AnalysisError> {
        if !(alpha.is_finite() && alpha.abs() < 1.0) {
            return Err(AnalysisError::parameter(
                "lag-1 autocorrelation",
                alpha,
                "an AR(1) background needs |α| < 1",
            ));
        }
        if !(variance.is_finite() && variance > 0.0) {
            return Err(AnalysisError::parameter(
                "variance",
                variance,
                "must be finite and > 0",
            ));
        }
        Ok(RedNoise { alpha, variance })
    }

    /// T&C eq. 16 at `f_hz` for sampling rate `fs`: the background's power relative to white
    /// noise of the same variance (mean 1 over 0…fs/2).
    pub fn normalized_spectrum(&self, f_hz: f64, fs: f64) -> f64 {
        let a = self.alpha;
        (1.0 - a * a) / (1.0 + a * a - 2.0 * a * (2.0 * PI * f_hz / fs).cos())
    }
}

/// T&C's Fourier frequency of scale `s` (s): the frequency of the cosine whose L2 wavelet power
/// peaks at `s`, `(ω_c + √(ω_c² + 2σ_w²))/(4πs)` (`1/(1.033 s)` for Morlet ω0 = 6).
pub fn fourier_frequency(wavelet: &Wavelet, s: f64) -> f64 {
    let (wc, sigma) = wavelet.gaussian();
    (wc + (wc * wc + 2.0 * sigma * sigma).sqrt()) / (4.0 * PI * s)
}

/// Expected `|W|²` of unit-variance white noise at scale `s` (s) for `fs` (Hz):
/// `(1/fs)·∫|Ψ̂|² df` — 1 for T&C's L2 normalisation, `2σ_w/(√π s fs)` for L1.
pub fn white_noise_power(
    wavelet: &Wavelet,
    normalization: Normalization,
    s: f64,
    fs: f64,
) -> Result<f64, AnalysisError> {
    let (_, sigma) = wavelet.gaussian();
    // ∫₀^∞ G(sω)² dω/(2π) = √π σ_w/(2π s) for the Gaussian G of width σ_w.
    let gauss = PI.sqrt() * sigma / (2.0 * PI * s);
    match normalization {
        Normalization::Amplitude => Ok(4.0 * gauss / fs),
        Normalization::Energy => Ok(wavelet.energy_peak().powi(2) * s * gauss),
        Normalization::Pywt { .. } => Err(AnalysisError::parameter(
            "normalization",
            normalization,
            "significance levels are for the L1 or L2 transform",
        )),
    }
}

/// Quantile of the χ² distribution with `nu` (> 0, not necessarily integer) degrees of freedom
/// at probability `p` (0 < p < 1): the root of `P(ν/2, x/2) = p` (regularised lower incomplete
/// gamma function), to ~1e-12 relative.
pub fn chi2_quantile(p: f64, nu: f64) -> Result<f64, AnalysisError> {
    if !(p > 0.0 && p < 1.0) {
        return Err(AnalysisError::parameter(
            "significance level",
            p,
            "must lie strictly between 0 and 1",
        ));
    }
    if !(nu.is_finite() && nu > 0.0) {
        return Err(AnalysisError::parameter(
            "degrees of freedom",
            nu,
            "must be finite and > 0",
        ));
    }
    let a = nu / 2.0;
    let cdf = |x: f64| gamma_p(a, x / 2.0);
    // Bracket, then bisect in ln x (robust for tiny and huge ν) to 1e-14 relative.
    let (mut lo, mut hi) = (1e-300_f64, nu.max(1.0));
    while cdf(hi) < p {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = (lo.ln() + hi.ln()).mul_add(0.5, 0.0).exp();
        if cdf(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi / lo - 1.0 < 1e-14 {
            break;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// `ln Γ(x)`, x > 0 (Lanczos, g = 7, n = 9: ~1e-15 relative).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection.
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised lower incomplete gamma `P(a, x)`: series for x < a + 1, Lentz's continued
/// fraction for the complement otherwise (Numerical Recipes §6.2).
fn gamma_p(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let log_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..100_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (sum * log_prefactor.exp()).min(1.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (1.0 - log_prefactor.exp() * h).max(0.0)
    }
}

/// Significance of a scalogram's local power and of its global spectrum.
#[derive(Debug, Clone)]
pub struct WaveletSignificance {
    /// Confidence level, e.g. 0.95.
    pub level: f64,
    pub background: RedNoise,
    /// T&C Fourier frequency of each row's scale, Hz.
    pub fourier_frequency_hz: Vec<f64>,
    /// Expected `|W|²` of the background per row (signal units², the transform's normalisation).
    pub background_power: Vec<f64>,
    /// Local level: `|W|²` above it is significant (T&C eq. 18).
    pub local_level: Vec<f64>,
    /// `[row][time]`, row-major like the scalogram: `|W|²` above the local level.
    pub mask: Vec<bool>,
    /// Global wavelet spectrum: mean `|W|²` over the samples outside the cone of influence
    /// (`None` where the cone covers the whole record).
    pub global_power: Vec<Option<f64>>,
    /// Samples averaged per row (outside the cone of influence).
    pub global_samples: Vec<usize>,
    /// Degrees of freedom of the global spectrum per row (T&C eq. 23).
    pub global_dof: Vec<f64>,
    /// The global spectrum's level per row (`None` where it was not formed).
    pub global_level: Vec<Option<f64>>,
    /// Fraction of the time–frequency cells outside the cone of influence that are significant.
    pub significant_fraction: f64,
}

impl WaveletSignificance {
    /// Whether row `j` at sample `n` is significant.
    pub fn significant(&self, j: usize, n: usize, n_time: usize) -> bool {
        self.mask[j * n_time + n]
    }
}

/// Checks the confidence level and that γ, δj0 are known for the wavelet.
fn check_level(level: f64) -> Result<(), AnalysisError> {
    if !(level > 0.0 && level < 1.0) {
        return Err(AnalysisError::parameter(
            "significance level",
            level,
            "must lie strictly between 0 and 1 (e.g. 0.95)",
        ));
    }
    Ok(())
}

fn check_morlet6(wavelet: &Wavelet, what: &'static str) -> Result<(), AnalysisError> {
    match *wavelet {
        Wavelet::Morlet { omega0 } if (omega0 - 6.0).abs() < 1e-12 => Ok(()),
        w => Err(AnalysisError::parameter(
            what,
            w,
            "T&C's decorrelation factors (γ = 2.32, δj0 = 0.60) are for the Morlet with ω0 = 6",
        )),
    }
}

/// Local and global significance of `sc` against `background` at confidence `level`.
pub fn wavelet_significance(
    sc: &Scalogram,
    background: &RedNoise,
    level: f64,
) -> Result<WaveletSignificance, AnalysisError> {
    check_level(level)?;
    check_morlet6(&sc.wavelet, "wavelet")?;
    let (nf, nt, fs) = (sc.frequencies_hz.len(), sc.n_time, sc.sample_rate_hz);
    let local_factor = chi2_quantile(level, 2.0)? / 2.0;
    let mut fourier = Vec::with_capacity(nf);
    let mut bg = Vec::with_capacity(nf);
    for &s in &sc.scales_s {
        let f_f = fourier_frequency(&sc.wavelet, s);
        fourier.push(f_f);
        bg.push(
            background.variance
                * background.normalized_spectrum(f_f, fs)
                * white_noise_power(&sc.wavelet, sc.normalization, s, fs)?,
        );
    }
    let local: Vec<f64> = bg.iter().map(|b| b * local_factor).collect();
    let mut mask = vec![false; nf * nt];
    // Rows in parallel; each row's sums in sample order, so the result does not depend on the
    // thread count.
    let per_row: Vec<(f64, usize, usize)> = mask
        .par_chunks_mut(nt.max(1))
        .enumerate()
        .map(|(j, mask_row)| {
            let (f, row) = (sc.frequencies_hz[j], sc.row(j));
            let (mut sum, mut count, mut hits) = (0.0, 0usize, 0usize);
            for ((m, sig), coi) in row.iter().zip(mask_row.iter_mut()).zip(&sc.coi_hz) {
                let p = f64::from(*m) * f64::from(*m);
                *sig = p > local[j];
                if f >= *coi {
                    sum += p;
                    count += 1;
                    hits += usize::from(*sig);
                }
            }
            (sum, count, hits)
        })
        .collect();
    let (mut global, mut samples, mut dof, mut glevel) = (
        Vec::with_capacity(nf),
        Vec::with_capacity(nf),
        Vec::with_capacity(nf),
        Vec::with_capacity(nf),
    );
    let (mut outside, mut significant) = (0usize, 0usize);
    for (j, &(sum, count, hits)) in per_row.iter().enumerate() {
        outside += count;
        significant += hits;
        // T&C eq. 23 with n_a the samples averaged.
        let nu = 2.0 * (1.0 + (count as f64 / fs / (MORLET_GAMMA * sc.scales_s[j])).powi(2)).sqrt();
        let nu = nu.max(2.0);
        dof.push(nu);
        samples.push(count);
        if count > 0 {
            global.push(Some(sum / count as f64));
            glevel.push(Some(bg[j] * chi2_quantile(level, nu)? / nu));
        } else {
            global.push(None);
            glevel.push(None);
        }
    }
    Ok(WaveletSignificance {
        level,
        background: *background,
        fourier_frequency_hz: fourier,
        background_power: bg,
        local_level: local,
        mask,
        global_power: global,
        global_samples: samples,
        global_dof: dof,
        global_level: glevel,
        significant_fraction: if outside > 0 {
            significant as f64 / outside as f64
        } else {
            0.0
        },
    })
}

/// The scale-averaged power of a band (T&C eq. 24): the band's variance over time.
#[derive(Debug, Clone)]
pub struct ScaleAverage {
    pub name: String,
    /// The band asked for, Hz.
    pub band_hz: (f64, f64),
    /// The grid rows inside it (inclusive).
    pub rows: (usize, usize),
    /// Band power per sample (signal units²): the variance the band carries.
    pub power: Vec<f64>,
    /// Its level (T&C eqs. 25–28).
    pub level_power: f64,
    pub dof: f64,
    /// Mean band power over the samples where every row of the band is outside the cone.
    pub mean_power: Option<f64>,
    /// Fraction of those samples above the level.
    pub significant_fraction: Option<f64>,
}

/// Scale-averaged power of the rows of `sc` inside `band` (Hz) with its significance level.
///
/// With the L1 transform, T&C's `(δj δt/C_δ) Σ |W_L2|²/s_j` is `(δj ln2/(2 I_E)) Σ |W_L1|²`
/// with the exact energy constant of the wavelet (`I_E = ∫ G²/u du`; T&C's empirical
/// C_δ = 0.776 corresponds to 0.766 for this Morlet), so that summing over all scales gives
/// the variance ([`super::cwt::ComplexScalogram::variance`]). The level's ν follows eq. 28
/// with `n_a` the number of scales averaged.
pub fn scale_average(
    sc: &Scalogram,
    background: &RedNoise,
    name: &str,
    band: (f64, f64),
    level: f64,
) -> Result<ScaleAverage, AnalysisError> {
    check_level(level)?;
    check_morlet6(&sc.wavelet, "wavelet")?;
    if sc.normalization != Normalization::Amplitude {
        return Err(AnalysisError::parameter(
            "normalization",
            sc.normalization,
            "the scale-averaged power is formed from the L1 transform",
        ));
    }
    let f = &sc.frequencies_hz;
    let range = |reason: &str| AnalysisError::FrequencyRange {
        low_hz: band.0,
        high_hz: band.1,
        reason: reason.to_string(),
    };
    if !(band.0 > 0.0 && band.1 > band.0) {
        return Err(range("need 0 < low < high"));
    }
    let rows: Vec<usize> = (0..f.len())
        .filter(|&j| f[j] >= band.0 && f[j] <= band.1)
        .collect();
    let (j1, j2) = match (rows.first(), rows.last()) {
        (Some(&a), Some(&b)) => (a, b),
        _ => return Err(range("no analysed frequency lies in the band")),
    };
    let dj = if f.len() >= 2 {
        (f[1] / f[0]).log2()
    } else {
        return Err(range(
            "a scale average needs a grid of at least 2 frequencies",
        ));
    };
    if f.windows(2)
        .any(|w| ((w[1] / w[0]).log2() / dj - 1.0).abs() > 1e-6)
    {
        return Err(AnalysisError::parameter(
            "frequencies",
            "non-uniform",
            "a scale average needs a log-uniform grid",
        ));
    }
    let (nt, fs) = (sc.n_time, sc.sample_rate_hz);
    let i_e = super::cwt::reconstruction_integrals(&sc.wavelet).0;
    let c = dj * std::f64::consts::LN_2 / (2.0 * i_e);
    let mut power = vec![0.0; nt];
    for j in j1..=j2 {
        for (p, m) in power.iter_mut().zip(sc.row(j)) {
            *p += c * f64::from(*m).powi(2);
        }
    }
    // T&C eqs. 25–28 in L2 terms: background of the band P̄ = S_avg Σ P_j/s_j, level
    // (δj δt σ²/(C_δ S_avg))·P̄·χ²_ν/ν; the same C_δ as the power itself (here the energy
    // constant in L1 form), so that the mask does not depend on it.
    let scales = &sc.scales_s[j1..=j2];
    let s_avg = 1.0 / scales.iter().map(|s| 1.0 / s).sum::<f64>();
    let s_mid = sc.scales_s[j1] * 2f64.powf(-((j2 - j1) as f64) * dj / 2.0);
    let p_bar = s_avg
        * (j1..=j2)
            .map(|j| {
                background.normalized_spectrum(fourier_frequency(&sc.wavelet, sc.scales_s[j]), fs)
                    / sc.scales_s[j]
            })
            .sum::<f64>();
    // n_a of eq. 28 is the number of scales averaged.
    let n_a = (j2 - j1 + 1) as f64;
    let nu = (2.0 * n_a * s_avg / s_mid) * (1.0 + (n_a * dj / MORLET_DJ0).powi(2)).sqrt();
    let nu = nu.max(2.0);
    // (δj δt/(C_δ S_avg)) in L2 is, with L1's white-noise power 2/(√π s fs) per row,
    // c·Σ_j K_j·… : the expected band power of the background is c·Σ_j E|W_L1,j|².
    // With E|W_L1,j|² = σ² P_j 2/(√π s_j fs), c·Σ = σ²·(2c/(√π fs))·Σ P_j/s_j = σ²·(2c/(√π fs))·P̄/S_avg.
    let expected = background.variance * 2.0 * c / (PI.sqrt() * fs) * p_bar / s_avg;
    let level_power = expected * chi2_quantile(level, nu)? / nu;
    // Samples where the band's lowest frequency is outside the cone.
    let trusted: Vec<usize> = (0..nt).filter(|&n| f[j1] >= sc.coi_hz[n]).collect();
    let (mean_power, significant_fraction) = if trusted.is_empty() {
        (None, None)
    } else {
        let m = trusted.iter().map(|&n| power[n]).sum::<f64>() / trusted.len() as f64;
        let above = trusted.iter().filter(|&&n| power[n] > level_power).count();
        (Some(m), Some(above as f64 / trusted.len() as f64))
    };
    Ok(ScaleAverage {
        name: name.to_string(),
        band_hz: band,
        rows: (j1, j2),
        power,
        level_power,
        dof: nu,
        mean_power,
        significant_fraction,
    })
}

/// The level a spectral amplitude must exceed at `f_hz` to be significant against
/// `background` at confidence `level`: a noise bin's `A²` is `E[A²]·χ²₂/2` with
/// `E[A²] = 4σ² P(f) Σw²/(Σw)²` for the amplitude scaling `A = 2|X|/Σw`.
pub fn spectrum_level(
    spectrum: &AmplitudeSpectrum,
    samples: usize,
    background: &RedNoise,
    f_hz: f64,
    level: f64,
) -> Result<f64, AnalysisError> {
    Ok(spectrum_levels(spectrum, samples, background, &[f_hz], level)?[0])
}

/// [`spectrum_level`] at many frequencies (the χ² quantile computed once).
pub fn spectrum_levels(
    spectrum: &AmplitudeSpectrum,
    samples: usize,
    background: &RedNoise,
    f_hz: &[f64],
    level: f64,
) -> Result<Vec<f64>, AnalysisError> {
    check_level(level)?;
    let n = samples as f64;
    // Periodic Hann: Σw = N/2, Σw² = 3N/8 (exact for N ≥ 3); rectangular: N, N.
    let (sum_w, sum_w2) = match spectrum.window {
        Window::Hann => (n / 2.0, 3.0 * n / 8.0),
        Window::None => (n, n),
    };
    let fs = spectrum.resolution * n;
    let factor =
        4.0 * background.variance * sum_w2 / (sum_w * sum_w) * chi2_quantile(level, 2.0)? / 2.0;
    Ok(f_hz
        .iter()
        .map(|&f| (factor * background.normalized_spectrum(f, fs)).sqrt())
        .collect())
}

#[cfg(test)]
mod golden;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_quantiles_of_integer_dof_match_closed_forms() {
        // ν = 2: exponential, x = −2 ln(1 − p).
        for p in [0.5, 0.9, 0.95, 0.99] {
            let x = chi2_quantile(p, 2.0).unwrap();
            assert!((x - (-2.0 * (1.0 - p).ln())).abs() < 1e-10 * x, "{p}: {x}");
        }
        assert!(chi2_quantile(1.0, 2.0).is_err());
        assert!(chi2_quantile(0.95, 0.0).is_err());
    }

    #[test]
    fn ar1_spectrum_has_unit_mean_and_white_noise_is_flat() {
        let r = RedNoise::new(0.72, 1.0).unwrap();
        let n = 20_000;
        let mean: f64 = (0..n)
            .map(|k| r.normalized_spectrum((k as f64 + 0.5) / n as f64 * 0.5, 1.0))
            .sum::<f64>()
            / n as f64;
        assert!((mean - 1.0).abs() < 1e-6, "{mean}");
        let w = RedNoise::new(0.0, 1.0).unwrap();
        assert_eq!(w.normalized_spectrum(0.1, 1.0), 1.0);
        assert!(RedNoise::new(1.0, 1.0).is_err());
        assert!(RedNoise::new(0.5, 0.0).is_err());
    }

    #[test]
    fn white_noise_power_of_l2_is_one_and_l1_converts() {
        let w = Wavelet::default();
        let (s, fs) = (1e-5, 1e6);
        let l2 = white_noise_power(&w, Normalization::Energy, s, fs).unwrap();
        assert!((l2 - 1.0).abs() < 1e-12, "{l2}");
        let l1 = white_noise_power(&w, Normalization::Amplitude, s, fs).unwrap();
        assert!((l1 - 2.0 / (PI.sqrt() * s * fs)).abs() < 1e-12 * l1);
        let f = fourier_frequency(&w, s);
        assert!((1.0 / (f * s) - 1.033).abs() < 1e-3, "{}", 1.0 / (f * s));
    }
}

#[cfg(test)]
mod behaviour {
    //! The Monte Carlo checks: AR(1) noise is flagged on ~5 % of the cells, a sine in
    //! red noise at its scale and nowhere else.
    use super::*;
    use crate::analysis::cwt::{cwt_morlet, CwtOptions, FrequencyGrid};
    use crate::analysis::series::spectrum;
    use crate::numerics::rng::Rng;

    fn ar1(rng: &mut Rng, alpha: f64, n: usize) -> Vec<f64> {
        let mut v = rng.normal() / (1.0 - alpha * alpha).sqrt();
        (0..n)
            .map(|i| {
                if i > 0 {
                    v = alpha * v + rng.normal();
                }
                v
            })
            .collect()
    }

    fn grid() -> CwtOptions {
        CwtOptions {
            frequencies: FrequencyGrid::Log {
                f_min_hz: 2e3,
                f_max_hz: 2e5,
                count: 60,
            },
            ..Default::default()
        }
    }

    #[test]
    fn ar1_noise_is_significant_on_five_percent_of_the_cells() {
        let (fs, n) = (1e6, 4096);
        let mut rng = Rng::new(2024);
        let (mut cells, mut flagged, mut band_samples, mut band_flagged) = (0.0, 0.0, 0.0, 0.0);
        let (mut bins, mut bins_flagged) = (0.0f64, 0.0f64);
        for _ in 0..40 {
            let x = ar1(&mut rng, 0.72, n);
            let bg = RedNoise::estimate(&x).unwrap();
            let sc = cwt_morlet(&x, fs, &grid()).unwrap();
            let sig = wavelet_significance(&sc, &bg, 0.95).unwrap();
            let outside = sig.global_samples.iter().sum::<usize>() as f64;
            cells += outside;
            flagged += sig.significant_fraction * outside;
            let avg = scale_average(&sc, &bg, "band", (9e4, 1.2e5), 0.95).unwrap();
            let trusted = sig.global_samples[avg.rows.0] as f64;
            band_samples += trusted;
            band_flagged += avg.significant_fraction.unwrap() * trusted;
            let sp = spectrum(&x, fs, crate::signal::spectrum::Window::Hann).unwrap();
            for (f, a) in sp.frequency.iter().zip(&sp.amplitude) {
                if *f >= 0.01 * fs && *f <= 0.45 * fs {
                    bins += 1.0;
                    if *a > spectrum_level(&sp, n, &bg, *f, 0.95).unwrap() {
                        bins_flagged += 1.0;
                    }
                }
            }
        }
        let area = flagged / cells;
        assert!((area - 0.05).abs() <= 0.01, "mask covers {area}");
        let band = band_flagged / band_samples;
        assert!(
            (0.03..=0.08).contains(&band),
            "scale-averaged power above its level {band}"
        );
        let fft = bins_flagged / bins;
        assert!((fft - 0.05).abs() <= 0.01, "FFT bins above the level {fft}");
    }

    #[test]
    fn a_sine_in_red_noise_is_found_at_its_scale_and_nowhere_else() {
        let (fs, n, f0) = (1e6, 8192, 5e4);
        let mut rng = Rng::new(99);
        let noise = ar1(&mut rng, 0.72, n);
        let x: Vec<f64> = noise
            .iter()
            .enumerate()
            .map(|(i, v)| v + 2.5 * (2.0 * PI * f0 * i as f64 / fs).sin())
            .collect();
        let bg = RedNoise::estimate(&x).unwrap();
        let sc = cwt_morlet(&x, fs, &grid()).unwrap();
        let sig = wavelet_significance(&sc, &bg, 0.95).unwrap();
        let nt = sc.n_time;
        let fraction = |j: usize| {
            let f = sc.frequencies_hz[j];
            let inside: Vec<usize> = (0..nt).filter(|&t| f >= sc.coi_hz[t]).collect();
            inside.iter().filter(|&&t| sig.mask[j * nt + t]).count() as f64 / inside.len() as f64
        };
        let j0 = (0..sc.frequencies_hz.len())
            .min_by(|&a, &b| {
                (sc.frequencies_hz[a] / f0)
                    .ln()
                    .abs()
                    .total_cmp(&(sc.frequencies_hz[b] / f0).ln().abs())
            })
            .unwrap();
        assert!(fraction(j0) > 0.95, "at the sine's scale {}", fraction(j0));
        // More than half an octave away the sine's wavelet power has fallen by e^{-(ω0 ln√2)²}…
        for j in 0..sc.frequencies_hz.len() {
            if (sc.frequencies_hz[j] / f0).log2().abs() > 0.5 {
                assert!(
                    fraction(j) < 0.12,
                    "{} Hz: {}",
                    sc.frequencies_hz[j],
                    fraction(j)
                );
            }
        }
        assert!(sig.global_power[j0].unwrap() > sig.global_level[j0].unwrap());
        let sp = spectrum(&x, fs, crate::signal::spectrum::Window::Hann).unwrap();
        let peak = sp.peaks(&Default::default())[0];
        assert!((peak.frequency - f0).abs() < 200.0);
        assert!(peak.amplitude > spectrum_level(&sp, n, &bg, peak.frequency, 0.95).unwrap());
    }
}
