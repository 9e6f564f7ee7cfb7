//! Deterministic synthetic excitation tracks for the slider dynamics (§2.1.2, App. B, and
//! the excitation studies of App. B): a synthetic DMW, a pure sinusoid, zero excitation,
//! band-limited random excitation and a quadratic chirp. Each returns the displacement `D`
//! (m) and velocity `V = dD/dt` (m/s) sampled at `fs`, plus the closed-form [`Model`] they
//! were sampled from, so the excitation can also be evaluated exactly between samples.
//!
//! Conventions (choices where the spec is silent):
//! - Samples sit at `t_n = n/fs`, `n = 0 … N−1`, with `N − 1 = ⌈duration·fs⌉` (an integer
//!   product is taken as such): the record covers `[0, duration]` inclusive, so a 2 ms record
//!   at 4 MS/s has 8001 samples and `duration()` 2 ms, what a Hermite track over it needs.
//! - Velocities are the analytic derivatives of the tone sums / chirp, never differences.
//! - "RMS" is of the samples as returned. The random tracks (synthetic DMW, band-limited
//!   random) have their sample mean removed, then are scaled so the sample RMS — which is
//!   then the standard deviation — is exactly the target. The sinusoid is a pure sine
//!   `A·sin(2πft)` (starting at D = 0) whose amplitude is set so the sample RMS is exactly the
//!   target (A = √2·rms to within 1/(2π·cycles)). The chirp takes a peak amplitude.
//! - Every frequency must lie strictly below Nyquist (`fs/2`); the chirp's `f0`, `f1` too.
//! - Randomness comes from a SplitMix64 generator private to this file, so a seed's tracks
//!   do not change when other generators in the crate do.

use super::DmwError;
use rayon::prelude::*;
use std::f64::consts::TAU;

/// The dominant DMW line (App. B), Hz.
pub const DMW_LINE_HZ: f64 = 10.7e3;

/// Most samples a generator will allocate (2²⁸, 2 GiB per channel); more is an error.
pub const MAX_SAMPLES: usize = 1 << 28;

/// One sinusoid: `D = amplitude·sin(2π·frequency·t + phase)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tone {
    /// Hz.
    pub frequency: f64,
    /// m.
    pub amplitude: f64,
    /// rad.
    pub phase: f64,
}

/// The closed form a track was sampled from.
#[derive(Debug, Clone, PartialEq)]
pub enum Model {
    /// `D = V = 0`.
    Zero,
    /// `D = offset + Σ a·sin(2πft + φ)`. For [`synthetic_dmw`] the first
    /// [`SyntheticDmwSpec::line_tones`] tones are the 10.7 kHz line, the rest the broadband part.
    Tones { tones: Vec<Tone>, offset: f64 },
    /// `D = amplitude·sin(2π(f0·t + (f1 − f0)·t³/(3T²)))`, instantaneous frequency
    /// `f0 + (f1 − f0)(t/T)²` with `T = sweep_time`.
    Chirp {
        f0: f64,
        f1: f64,
        sweep_time: f64,
        amplitude: f64,
    },
}

impl Model {
    /// Displacement at time `t` (s), m.
    pub fn displacement_at(&self, t: f64) -> f64 {
        match self {
            Model::Zero => 0.0,
            Model::Tones { tones, offset } => {
                offset
                    + tones
                        .iter()
                        .map(|k| k.amplitude * (TAU * k.frequency * t + k.phase).sin())
                        .sum::<f64>()
            }
            Model::Chirp { amplitude, .. } => amplitude * self.chirp_phase(t).sin(),
        }
    }

    /// Velocity (the exact derivative of [`displacement_at`](Self::displacement_at)), m/s.
    pub fn velocity_at(&self, t: f64) -> f64 {
        match self {
            Model::Zero => 0.0,
            Model::Tones { tones, .. } => tones
                .iter()
                .map(|k| {
                    let w = TAU * k.frequency;
                    k.amplitude * w * (w * t + k.phase).cos()
                })
                .sum(),
            Model::Chirp { amplitude, .. } => {
                let f = self.instantaneous_frequency(t).unwrap_or(0.0);
                amplitude * TAU * f * self.chirp_phase(t).cos()
            }
        }
    }

    /// Instantaneous frequency (Hz) of a chirp or a single tone; `None` for anything else.
    pub fn instantaneous_frequency(&self, t: f64) -> Option<f64> {
        match self {
            Model::Chirp {
                f0, f1, sweep_time, ..
            } => {
                let r = t / sweep_time;
                Some(f0 + (f1 - f0) * r * r)
            }
            Model::Tones { tones, .. } if tones.len() == 1 => Some(tones[0].frequency),
            _ => None,
        }
    }

    fn chirp_phase(&self, t: f64) -> f64 {
        match self {
            Model::Chirp {
                f0, f1, sweep_time, ..
            } => TAU * (f0 * t + (f1 - f0) * t * t * t / (3.0 * sweep_time * sweep_time)),
            _ => 0.0,
        }
    }
}

/// A sampled excitation track.
#[derive(Debug, Clone, PartialEq)]
pub struct Excitation {
    /// Samples per second.
    pub fs: f64,
    /// `D(n/fs)`, m.
    pub displacement: Vec<f64>,
    /// `V(n/fs) = D'(n/fs)`, m/s.
    pub velocity: Vec<f64>,
    pub model: Model,
}

impl Excitation {
    pub fn len(&self) -> usize {
        self.displacement.len()
    }

    pub fn is_empty(&self) -> bool {
        self.displacement.is_empty()
    }

    /// Time of the last sample, s.
    pub fn duration(&self) -> f64 {
        self.len().saturating_sub(1) as f64 / self.fs
    }

    /// Root mean square of the displacement samples, m.
    pub fn rms(&self) -> f64 {
        rms(&self.displacement)
    }
}

/// The synthetic DMW of §2.1.2 and App. B. Defaults ([`SyntheticDmwSpec::new`]): σ total, 80 %
/// of the variance in a quasi-periodic line at 10.7 kHz, 20 % in 64 log-spaced broadband tones
/// 10–500 kHz with amplitude ∝ f⁻².
///
/// The line is a carrier at `line_hz` plus `line_tones − 1` weaker side tones (relative
/// amplitude 0.3–0.7) at random frequencies within `±line_spread·line_hz`, random phases: a
/// line whose envelope and phase wander on the beat time scale (≳ 1/(2·spread·f) ≈ 2.3 ms by
/// default) — quasi-periodic, but still one spectral line at the dissertation's resolution.
/// The broadband tones sit on a jittered logarithmic grid over `hf_band` (the band cut into
/// `hf_tones` cells of equal width in ln f, one tone at a log-uniformly random position in
/// each: incommensurate with probability 1), amplitude ∝ f^(−hf_exponent), random phases. Each part is scaled so its sample variance is
/// its share of σ²; the sum then has its mean removed and is rescaled to σ exactly (the
/// shares hold to within the parts' sample cross-correlation: a few % of σ², since the
/// lowest broadband cells, which carry most of the f⁻⁴ variance, lie beside the line).
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticDmwSpec {
    /// Total standard deviation σ_DMW, m (spec: 1.0 nm).
    pub sigma_m: f64,
    /// Share of the variance in the broadband part, 0…1 (spec: 0.2). The calibration knob
    /// for the flying FHM target (docs/calibration.md); the line gets `1 − hf_share`.
    pub hf_share: f64,
    /// Line carrier frequency, Hz.
    pub line_hz: f64,
    /// Tones making up the line (carrier included), ≥ 1.
    pub line_tones: usize,
    /// Relative half-width of the line's side tones, 0 ≤ spread < 0.5.
    pub line_spread: f64,
    /// Broadband frequency range, Hz.
    pub hf_band: (f64, f64),
    /// Broadband tone count (spec: ≥ 50).
    pub hf_tones: usize,
    /// Broadband amplitude ∝ f^(−hf_exponent) (spec: 2); a second calibration knob that moves
    /// broadband variance toward the 100–300 kHz content that sets FHM when lowered.
    pub hf_exponent: f64,
    pub seed: u64,
}

impl SyntheticDmwSpec {
    /// The spec's synthetic DMW with total σ `sigma_m` and random seed `seed`.
    pub fn new(sigma_m: f64, seed: u64) -> Self {
        SyntheticDmwSpec {
            sigma_m,
            hf_share: 0.2,
            line_hz: DMW_LINE_HZ,
            line_tones: 5,
            line_spread: 0.02,
            hf_band: (10e3, 500e3),
            hf_tones: 64,
            hf_exponent: 2.0,
            seed,
        }
    }
}

impl Default for SyntheticDmwSpec {
    /// σ = 1.0 nm, seed 1.
    fn default() -> Self {
        SyntheticDmwSpec::new(1e-9, 1)
    }
}

/// [`synthetic_dmw_with`] with the spec's defaults ([`SyntheticDmwSpec::new`]).
pub fn synthetic_dmw(
    duration_s: f64,
    fs: f64,
    sigma_m: f64,
    seed: u64,
) -> Result<Excitation, DmwError> {
    synthetic_dmw_with(duration_s, fs, &SyntheticDmwSpec::new(sigma_m, seed))
}

/// The synthetic DMW of `spec` (see [`SyntheticDmwSpec`]).
///
/// Errors: non-positive or non-finite `duration_s`/`fs`, too many samples, a negative σ,
/// `hf_share` outside 0…1, an empty or inverted band, a frequency at or above Nyquist, no
/// tones for a part with a nonzero share.
pub fn synthetic_dmw_with(
    duration_s: f64,
    fs: f64,
    spec: &SyntheticDmwSpec,
) -> Result<Excitation, DmwError> {
    let n = sample_count(duration_s, fs)?;
    non_negative("sigma_m", spec.sigma_m)?;
    if !(0.0..=1.0).contains(&spec.hf_share) {
        return Err(bad("hf_share", spec.hf_share, "must lie in 0…1"));
    }
    below_nyquist("line_hz", spec.line_hz, fs)?;
    if !(0.0..0.5).contains(&spec.line_spread) {
        return Err(bad("line_spread", spec.line_spread, "must lie in [0, 0.5)"));
    }
    below_nyquist(
        "line frequency",
        spec.line_hz * (1.0 + spec.line_spread),
        fs,
    )?;
    band("hf_band", spec.hf_band.0, spec.hf_band.1, fs)?;
    if !spec.hf_exponent.is_finite() {
        return Err(bad("hf_exponent", spec.hf_exponent, "must be finite"));
    }
    let line_share = 1.0 - spec.hf_share;
    if line_share > 0.0 && spec.line_tones == 0 {
        return Err(bad(
            "line_tones",
            0,
            "must be ≥ 1 when the line has variance",
        ));
    }
    if spec.hf_share > 0.0 && spec.hf_tones == 0 {
        return Err(bad("hf_tones", 0, "must be ≥ 1 when hf_share > 0"));
    }

    let mut rng = SplitMix64::new(spec.seed);
    let mut line: Vec<Tone> = (0..spec.line_tones)
        .map(|k| {
            let (frequency, amplitude) = if k == 0 {
                (spec.line_hz, 1.0)
            } else {
                let f = spec.line_hz * (1.0 + spec.line_spread * (2.0 * rng.uniform() - 1.0));
                (f, 0.3 + 0.4 * rng.uniform())
            };
            Tone {
                frequency,
                amplitude,
                phase: TAU * rng.uniform(),
            }
        })
        .collect();
    let (lo, hi) = spec.hf_band;
    // Log-spaced (docs/conventions.md): equal cells in ln f, one tone log-uniform inside
    // each. A linear grid puts most tones (and so ~3.5× the spec's variance) above 100 kHz.
    let cell = (hi / lo).ln() / spec.hf_tones.max(1) as f64;
    let mut broad: Vec<Tone> = (0..spec.hf_tones)
        .map(|k| {
            let f = (lo * ((k as f64 + rng.uniform()) * cell).exp()).min(hi);
            Tone {
                frequency: f,
                amplitude: (f / lo).powf(-spec.hf_exponent),
                phase: TAU * rng.uniform(),
            }
        })
        .collect();

    let var = spec.sigma_m * spec.sigma_m;
    let (d_line, v_line) = eval_tones(&line, fs, n);
    let (d_broad, v_broad) = eval_tones(&broad, fs, n);
    let part_scale = |share: f64, d: &[f64], what: &str| -> Result<f64, DmwError> {
        if share == 0.0 || var == 0.0 {
            return Ok(0.0);
        }
        let (_, v) = mean_var(d);
        if v > 0.0 && v.is_finite() {
            Ok((share * var / v).sqrt())
        } else {
            Err(DmwError::Processing(format!(
                "synthetic DMW: the {what} has no variance over {n} samples (record too short)"
            )))
        }
    };
    let s_line = part_scale(line_share, &d_line, "line")?;
    let s_broad = part_scale(spec.hf_share, &d_broad, "broadband part")?;
    let mut d: Vec<f64> = d_line
        .iter()
        .zip(&d_broad)
        .map(|(a, b)| s_line * a + s_broad * b)
        .collect();
    let mut v: Vec<f64> = v_line
        .iter()
        .zip(&v_broad)
        .map(|(a, b)| s_line * a + s_broad * b)
        .collect();
    for t in &mut line {
        t.amplitude *= s_line;
    }
    for t in &mut broad {
        t.amplitude *= s_broad;
    }
    line.append(&mut broad);
    let offset = normalise(&mut line, &mut d, &mut v, spec.sigma_m, true)?;
    Ok(Excitation {
        fs,
        displacement: d,
        velocity: v,
        model: Model::Tones {
            tones: line,
            offset,
        },
    })
}

/// S7b: `A·sin(2π·freq·t)` with the sample RMS exactly `rms` (m).
pub fn sinusoid(duration_s: f64, fs: f64, freq_hz: f64, rms: f64) -> Result<Excitation, DmwError> {
    let n = sample_count(duration_s, fs)?;
    below_nyquist("freq_hz", freq_hz, fs)?;
    non_negative("rms", rms)?;
    let mut tones = vec![Tone {
        frequency: freq_hz,
        amplitude: 1.0,
        phase: 0.0,
    }];
    let (mut d, mut v) = eval_tones(&tones, fs, n);
    let offset = normalise(&mut tones, &mut d, &mut v, rms, false)?;
    Ok(Excitation {
        fs,
        displacement: d,
        velocity: v,
        model: Model::Tones { tones, offset },
    })
}

/// S7c: no excitation, on the same time grid as the others.
pub fn zero(duration_s: f64, fs: f64) -> Result<Excitation, DmwError> {
    let n = sample_count(duration_s, fs)?;
    Ok(Excitation {
        fs,
        displacement: vec![0.0; n],
        velocity: vec![0.0; n],
        model: Model::Zero,
    })
}

/// S7d: band-limited random displacement, flat (white) in `f_lo…f_hi`, sample RMS exactly
/// `rms` about a zero mean. A random-phase multisine: equal-amplitude tones, one at a
/// uniformly random position in each of `M` equal cells of the band (an incommensurate,
/// finer-than-resolution grid), `M = ⌈(f_hi − f_lo)·duration⌉` clamped to 64…4096 — about one
/// tone per frequency-resolution bin, so the record looks Gaussian.
pub fn band_limited_random(
    duration_s: f64,
    fs: f64,
    f_lo: f64,
    f_hi: f64,
    rms: f64,
    seed: u64,
) -> Result<Excitation, DmwError> {
    let n = sample_count(duration_s, fs)?;
    band("band", f_lo, f_hi, fs)?;
    non_negative("rms", rms)?;
    let m = ((f_hi - f_lo) * duration_s).ceil().clamp(64.0, 4096.0) as usize;
    let cell = (f_hi - f_lo) / m as f64;
    let mut rng = SplitMix64::new(seed);
    let mut tones: Vec<Tone> = (0..m)
        .map(|k| Tone {
            frequency: f_lo + (k as f64 + rng.uniform()) * cell,
            amplitude: 1.0,
            phase: TAU * rng.uniform(),
        })
        .collect();
    let (mut d, mut v) = eval_tones(&tones, fs, n);
    let offset = normalise(&mut tones, &mut d, &mut v, rms, true)?;
    Ok(Excitation {
        fs,
        displacement: d,
        velocity: v,
        model: Model::Tones { tones, offset },
    })
}

/// S7e: `D = amplitude·sin(φ(t))`, `f(t) = f0 + (f1 − f0)(t/T)²` with `T = duration_s`,
/// `φ = 2π∫f = 2π(f0·t + (f1 − f0)t³/(3T²))`; `amplitude` is the peak displacement (m).
/// A down-sweep (f1 < f0) is allowed.
pub fn quadratic_chirp(
    duration_s: f64,
    fs: f64,
    f0: f64,
    f1: f64,
    amplitude: f64,
) -> Result<Excitation, DmwError> {
    let n = sample_count(duration_s, fs)?;
    for (name, f) in [("f0", f0), ("f1", f1)] {
        if f == 0.0 {
            continue;
        }
        below_nyquist(name, f, fs)?;
    }
    if !amplitude.is_finite() {
        return Err(bad("amplitude", amplitude, "must be finite"));
    }
    let model = Model::Chirp {
        f0,
        f1,
        sweep_time: duration_s,
        amplitude,
    };
    let (displacement, velocity): (Vec<f64>, Vec<f64>) = (0..n)
        .into_par_iter()
        .map(|i| {
            let t = i as f64 / fs;
            (model.displacement_at(t), model.velocity_at(t))
        })
        .unzip();
    Ok(Excitation {
        fs,
        displacement,
        velocity,
        model,
    })
}

// ---------------------------------------------------------------------------------------
// Helpers

fn bad(name: &str, value: impl std::fmt::Display, why: &str) -> DmwError {
    DmwError::Processing(format!("synthetic excitation: {name} = {value} {why}"))
}

fn non_negative(name: &str, v: f64) -> Result<(), DmwError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(bad(name, v, "must be finite and ≥ 0"))
    }
}

fn below_nyquist(name: &str, f: f64, fs: f64) -> Result<(), DmwError> {
    if !(f.is_finite() && f > 0.0) {
        return Err(bad(name, f, "Hz must be finite and > 0"));
    }
    if f >= 0.5 * fs {
        return Err(bad(
            name,
            f,
            &format!(
                "Hz must lie below Nyquist ({} Hz at fs = {fs} S/s)",
                0.5 * fs
            ),
        ));
    }
    Ok(())
}

fn band(name: &str, lo: f64, hi: f64, fs: f64) -> Result<(), DmwError> {
    below_nyquist(&format!("{name} lower edge"), lo, fs)?;
    below_nyquist(&format!("{name} upper edge"), hi, fs)?;
    if hi <= lo {
        return Err(bad(
            name,
            format!("{lo}…{hi} Hz"),
            "must have its upper edge above its lower edge",
        ));
    }
    Ok(())
}

/// Samples covering `[0, duration_s]`: `⌈duration·fs⌉ + 1` (see the module doc).
fn sample_count(duration_s: f64, fs: f64) -> Result<usize, DmwError> {
    if !(fs.is_finite() && fs > 0.0) {
        return Err(bad("fs", fs, "S/s must be finite and > 0"));
    }
    if !(duration_s.is_finite() && duration_s > 0.0) {
        return Err(bad("duration", duration_s, "s must be finite and > 0"));
    }
    let m = duration_s * fs;
    let intervals = if (m - m.round()).abs() <= 1e-9 * m.max(1.0) {
        m.round()
    } else {
        m.ceil()
    }
    .max(1.0);
    // duration and fs are finite and positive: the product is finite or +∞, never NaN.
    if intervals >= MAX_SAMPLES as f64 {
        return Err(bad(
            "duration·fs",
            m,
            &format!("samples exceed the limit of {MAX_SAMPLES}"),
        ));
    }
    Ok(intervals as usize + 1)
}

/// Samples per chunk between exact re-evaluations of each tone's phasor.
const CHUNK: usize = 512;

/// `Σ a·sin(ωt + φ)` and its derivative at `t = n/fs`. Within a chunk each tone's phasor is
/// advanced by an exact rotation (rounding grows ~`CHUNK`·ε, < 10⁻¹³ relative); at each chunk
/// start it is evaluated afresh, so long records do not drift. Chunks run in parallel.
fn eval_tones(tones: &[Tone], fs: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut d = vec![0.0; n];
    let mut v = vec![0.0; n];
    d.par_chunks_mut(CHUNK)
        .zip(v.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(c, (dc, vc))| {
            let t0 = (c * CHUNK) as f64 / fs;
            for tone in tones {
                let w = TAU * tone.frequency;
                let (mut s, mut co) = (w * t0 + tone.phase).sin_cos();
                let (sr, cr) = (w / fs).sin_cos();
                let (a, av) = (tone.amplitude, tone.amplitude * w);
                for (dj, vj) in dc.iter_mut().zip(vc.iter_mut()) {
                    *dj += a * s;
                    *vj += av * co;
                    let s_next = s * cr + co * sr;
                    co = co * cr - s * sr;
                    s = s_next;
                }
            }
        });
    (d, v)
}

fn mean_var(x: &[f64]) -> (f64, f64) {
    let n = x.len().max(1) as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    (mean, var)
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// Optionally remove the sample mean of `d`, then scale `d`, `v` and the tone amplitudes so
/// the sample RMS of `d` is `target`. Returns the model's constant offset.
fn normalise(
    tones: &mut [Tone],
    d: &mut [f64],
    v: &mut [f64],
    target: f64,
    remove_mean: bool,
) -> Result<f64, DmwError> {
    let mean = if remove_mean { mean_var(d).0 } else { 0.0 };
    d.iter_mut().for_each(|x| *x -= mean);
    let r = rms(d);
    let g = if target == 0.0 {
        0.0
    } else if r > 0.0 && r.is_finite() {
        target / r
    } else {
        return Err(DmwError::Processing(format!(
            "synthetic excitation: the record of {} samples has no variation to scale to RMS {target}",
            d.len()
        )));
    };
    d.iter_mut().for_each(|x| *x *= g);
    v.iter_mut().for_each(|x| *x *= g);
    tones.iter_mut().for_each(|t| t.amplitude *= g);
    Ok(-mean * g)
}

/// SplitMix64 (Steele, Lea & Flood 2014): tiny, fast, and every seed (0 included) is good.
struct SplitMix64(u64);

impl SplitMix64 {
    fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 53 random bits.
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::spectrum::{amplitude_spectrum, Window};

    const FS: f64 = 4e6;
    const T: f64 = 2e-3;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// Fraction of the Hann-windowed power of `x` in `lo…hi` Hz.
    fn band_fraction(x: &[f64], fs: f64, lo: f64, hi: f64) -> f64 {
        let s = amplitude_spectrum(x, fs, Window::Hann).unwrap();
        let (mut inside, mut total) = (0.0, 0.0);
        for (f, a) in s.frequency.iter().zip(&s.amplitude) {
            total += a * a;
            if (lo..=hi).contains(f) {
                inside += a * a;
            }
        }
        inside / total
    }

    /// Every excitation of the module with its name.
    fn all(seed: u64) -> Vec<(&'static str, Excitation)> {
        vec![
            ("dmw", synthetic_dmw(T, FS, 1e-9, seed).unwrap()),
            ("sine", sinusoid(T, FS, DMW_LINE_HZ, 1e-9).unwrap()),
            ("zero", zero(T, FS).unwrap()),
            (
                "random-low",
                band_limited_random(T, FS, 10e3, 50e3, 1e-9, seed).unwrap(),
            ),
            (
                "random-ab",
                band_limited_random(T, FS, 10e3, 500e3, 1e-9, seed).unwrap(),
            ),
            (
                "random-high",
                band_limited_random(T, FS, 10e3, 1000e3, 1e-9, seed).unwrap(),
            ),
            (
                "chirp",
                quadratic_chirp(1.923e-3, FS, 40e3, 500e3, 1e-9).unwrap(),
            ),
        ]
    }

    #[test]
    fn sample_grid_covers_the_duration() {
        let z = zero(T, FS).unwrap();
        assert_eq!(z.len(), 8001);
        assert!(rel(z.duration(), T) < 1e-12);
        assert!(z.displacement.iter().chain(&z.velocity).all(|&v| v == 0.0));
        // A non-integer product rounds up: the record still reaches the duration.
        let c = sinusoid(1.0001e-3, 1e6, 1e3, 1.0).unwrap();
        assert_eq!(c.len(), 1002);
        assert!(c.duration() >= 1.0001e-3);
    }

    #[test]
    fn rms_is_exact() {
        for (name, x) in all(11) {
            match name {
                "zero" => assert_eq!(x.rms(), 0.0),
                "chirp" => {
                    // Peak amplitude 1 nm: RMS ≈ A/√2.
                    assert!(rel(x.rms(), 1e-9 / 2f64.sqrt()) < 1e-2, "{}", x.rms());
                }
                _ => {
                    assert!(rel(x.rms(), 1e-9) < 1e-3, "{name}: {}", x.rms());
                    assert!(rel(x.rms(), 1e-9) < 1e-12, "{name}: {}", x.rms());
                }
            }
        }
        for name in ["dmw", "random-ab"] {
            let x = all(3).into_iter().find(|e| e.0 == name).unwrap().1;
            let mean = x.displacement.iter().sum::<f64>() / x.len() as f64;
            assert!(mean.abs() < 1e-12 * 1e-9, "{name}: mean {mean}");
        }
        // Other σ, and a zero target, scale.
        let x = synthetic_dmw(T, FS, 0.37e-9, 5).unwrap();
        assert!(rel(x.rms(), 0.37e-9) < 1e-12);
        let x = synthetic_dmw(T, FS, 0.0, 5).unwrap();
        assert!(x.displacement.iter().chain(&x.velocity).all(|&v| v == 0.0));
        // Pure sine: amplitude near √2·rms, no offset.
        let s = sinusoid(T, FS, DMW_LINE_HZ, 1e-9).unwrap();
        let Model::Tones { tones, offset } = &s.model else {
            panic!()
        };
        assert_eq!((tones.len(), *offset), (1, 0.0));
        assert!(rel(tones[0].amplitude, 2f64.sqrt() * 1e-9) < 1e-2);
    }

    #[test]
    fn dmw_variance_split() {
        for (seed, hf_share) in [(1, 0.2), (2, 0.2), (3, 0.5), (4, 0.05)] {
            let spec = SyntheticDmwSpec {
                hf_share,
                ..SyntheticDmwSpec::new(1e-9, seed)
            };
            let x = synthetic_dmw_with(20e-3, FS, &spec).unwrap();
            let Model::Tones { tones, .. } = &x.model else {
                panic!("tones expected")
            };
            assert_eq!(tones.len(), spec.line_tones + spec.hf_tones);
            assert!(spec.hf_tones >= 50);
            let (line, broad) = tones.split_at(spec.line_tones);
            // By construction: the line part alone carries 1 − hf_share of σ².
            let part = |ts: &[Tone]| {
                let d = eval_tones(ts, FS, x.len()).0;
                (mean_var(&d).1, d)
            };
            let (var_line, d_line) = part(line);
            let (var_broad, _) = part(broad);
            // The parts' variances split exactly; the total also holds their cross term,
            // which is no longer negligible now that the log-spaced broadband tones crowd
            // 10–12 kHz beside the line (documented on `SyntheticDmwSpec`; 0.5–6 % of σ² over
            // 20 ms for these seeds).
            let split = var_line / (var_line + var_broad);
            assert!((split - (1.0 - hf_share)).abs() < 1e-9, "{split}");
            let cross = 1.0 - (var_line + var_broad) / 1e-18;
            assert!(cross.abs() < 0.1, "seed {seed}: cross term {cross}");
            // Spectrally: the line sits in 9–12 kHz, the broadband tones in 10–500 kHz with
            // amplitude ∝ f⁻².
            assert!(band_fraction(&d_line, FS, 9e3, 12e3) > 0.99);
            let total_in_band = band_fraction(&x.displacement, FS, 9e3, 12e3);
            // Hann-weighted, so only to a few % (the line's envelope beats; see below).
            assert!(total_in_band > 1.0 - hf_share - 0.05, "{total_in_band}");
            assert!(broad.iter().all(|t| (10e3..=500e3).contains(&t.frequency)));
            let k = broad[0].amplitude * broad[0].frequency.powi(2);
            assert!(broad
                .iter()
                .all(|t| rel(t.amplitude * t.frequency.powi(2), k) < 1e-9));
            // Incommensurate: no two broadband frequencies share a rational ratio with a
            // small denominator (all distinct, none a harmonic of the line).
            for (i, a) in broad.iter().enumerate() {
                for b in &broad[i + 1..] {
                    assert!((a.frequency - b.frequency).abs() > 1e-3);
                }
                let r = a.frequency / DMW_LINE_HZ;
                assert!((r - r.round()).abs() > 1e-9);
            }
        }
        // A 2 ms record: the line still dominates 9–12 kHz, only roughly 80 % under a Hann
        // window, which weights the record's middle while the line's envelope beats on a
        // ~2 ms scale (the sample variance, uniformly weighted, is the exact 80 %).
        for seed in 1..4 {
            let x = synthetic_dmw(T, FS, 1e-9, seed).unwrap();
            let f = band_fraction(&x.displacement, FS, 9e3, 12e3);
            assert!(f > 0.75, "seed {seed}: {f}");
        }
    }

    /// The 100–300 kHz share of the broadband variance against the spec's definition worked
    /// out independently (docs/conventions.md): one tone per equal-ln f cell of 10–500 kHz,
    /// log-uniform in its cell, variance a²/2 ∝ f⁻⁴. Then E[Σ f⁻⁴·1{f ∈ band}] =
    /// N/ln(R)·∫_band f⁻⁵ df exactly (the cell densities sum to N/(f·ln R)), so the expected
    /// share is (a⁻⁴ − b⁻⁴)/(lo⁻⁴ − hi⁻⁴); each seed's share must also lie between the bounds
    /// the cell edges allow (the jitter tolerance).
    #[test]
    fn broadband_band_share_follows_the_log_uniform_integral() {
        let (lo, hi, a, b) = (10e3f64, 500e3f64, 100e3f64, 300e3f64);
        let expected = (a.powi(-4) - b.powi(-4)) / (lo.powi(-4) - hi.powi(-4));
        let spec0 = SyntheticDmwSpec::new(1e-9, 0);
        let n = spec0.hf_tones;
        let w = (hi / lo).ln() / n as f64;
        let edge = |k: usize| lo * (k as f64 * w).exp();
        // Jitter bounds from the cell edges alone.
        let (mut in_min, mut in_max, mut out_min, mut out_max) = (0.0, 0.0, 0.0, 0.0);
        for k in 0..n {
            let (e0, e1) = (edge(k), edge(k + 1));
            let (small, large) = (e1.powi(-4), e0.powi(-4));
            if e0 >= a && e1 <= b {
                in_min += small;
                in_max += large;
            } else if e1 <= a || e0 >= b {
                out_min += small;
                out_max += large;
            } else {
                in_max += large; // may fall either side of the band edge
                out_max += large;
            }
        }
        let (share_min, share_max) = (in_min / (in_min + out_max), in_max / (in_max + out_min));
        let (mut sum_in, mut sum_all) = (0.0, 0.0);
        for seed in 1..=400u64 {
            let x = synthetic_dmw_with(0.1e-3, FS, &SyntheticDmwSpec::new(1e-9, seed)).unwrap();
            let Model::Tones { tones, .. } = &x.model else {
                panic!("tones expected")
            };
            let broad = &tones[spec0.line_tones..];
            assert_eq!(broad.len(), n);
            for (k, t) in broad.iter().enumerate() {
                // One tone per log cell.
                assert!(
                    t.frequency >= edge(k) * (1.0 - 1e-12)
                        && t.frequency <= edge(k + 1) * (1.0 + 1e-12)
                );
            }
            let var = |ts: &mut dyn Iterator<Item = &Tone>| {
                ts.map(|t| 0.5 * t.amplitude * t.amplitude).sum::<f64>()
            };
            let v_in = var(&mut broad.iter().filter(|t| (a..=b).contains(&t.frequency)));
            let v_all = var(&mut broad.iter());
            let share = v_in / v_all;
            assert!(
                share >= share_min && share <= share_max,
                "seed {seed}: {share}"
            );
            // Scale-free ratio of the per-seed sums against the f⁻⁴ weights.
            let v0 = broad[0].amplitude.powi(2) * broad[0].frequency.powi(4);
            sum_in += v_in / v0;
            sum_all += v_all / v0;
        }
        let mean_share = sum_in / sum_all;
        assert!(
            rel(mean_share, expected) < 0.03,
            "{mean_share} vs {expected}"
        );
    }

    #[test]
    fn band_limited_random_stays_in_band() {
        for (lo, hi) in [(10e3, 50e3), (10e3, 500e3), (10e3, 1000e3)] {
            let x = band_limited_random(5e-3, FS, lo, hi, 1e-9, 9).unwrap();
            let Model::Tones { tones, .. } = &x.model else {
                panic!()
            };
            assert!(tones.len() >= 64);
            assert!(tones.iter().all(|t| (lo..hi).contains(&t.frequency)));
            // Hann leakage spreads each tone over ±2 bins (±400 Hz at 5 ms).
            assert!(band_fraction(&x.displacement, FS, lo - 1e3, hi + 1e3) > 0.999);
        }
    }

    #[test]
    fn velocity_is_the_derivative() {
        let h = 1e-10;
        for (name, x) in all(21) {
            let vmax = x.velocity.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let dmax = x.displacement.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if name == "zero" {
                assert_eq!(vmax, 0.0);
                continue;
            }
            let mut worst_v: f64 = 0.0;
            let mut worst_d: f64 = 0.0;
            for i in (0..x.len()).step_by(7) {
                let t = i as f64 / x.fs;
                let cd =
                    (x.model.displacement_at(t + h) - x.model.displacement_at(t - h)) / (2.0 * h);
                worst_v = worst_v.max((x.velocity[i] - cd).abs());
                worst_d = worst_d.max((x.displacement[i] - x.model.displacement_at(t)).abs());
                assert!((x.velocity[i] - x.model.velocity_at(t)).abs() <= 1e-9 * vmax);
            }
            assert!(worst_v <= 1e-6 * vmax, "{name}: {worst_v} vs {vmax}");
            assert!(worst_d <= 1e-9 * dmax, "{name}: samples vs model {worst_d}");
        }
        // On the sample grid: a slow tone's central difference agrees to O((ωh)²).
        let x = sinusoid(T, 400e6, 10.7e3, 1.0).unwrap();
        let vmax = x.velocity.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 1..x.len() - 1 {
            let cd = (x.displacement[i + 1] - x.displacement[i - 1]) * x.fs / 2.0;
            assert!((x.velocity[i] - cd).abs() <= 1e-6 * vmax);
        }
    }

    #[test]
    fn seeds_are_deterministic() {
        let a = all(42);
        let b = all(42);
        let c = all(43);
        for ((name, x), ((_, y), (_, z))) in a.iter().zip(b.iter().zip(&c)) {
            assert_eq!(x, y, "{name}");
            let seeded = matches!(*name, "dmw" | "random-low" | "random-ab" | "random-high");
            if seeded {
                assert_ne!(x.displacement, z.displacement, "{name}");
            }
        }
        let mut r = SplitMix64::new(0);
        let u: Vec<f64> = (0..1000).map(|_| r.uniform()).collect();
        assert!(u.iter().all(|v| (0.0..1.0).contains(v)));
        let mean = u.iter().sum::<f64>() / 1000.0;
        assert!((mean - 0.5).abs() < 0.05);
    }

    #[test]
    fn chirp_crosses_the_pitch_mode_at_0_75_ms() {
        let (t_sweep, f0, f1, a) = (1.923e-3, 40e3, 500e3, 1e-9);
        let x = quadratic_chirp(t_sweep, FS, f0, f1, a).unwrap();
        let t_cross = t_sweep * ((110e3 - f0) / (f1 - f0)).sqrt();
        assert!((t_cross - 0.75e-3).abs() < 1e-6, "{t_cross}");
        let f = x.model.instantaneous_frequency(t_cross).unwrap();
        assert!(rel(f, 110e3) < 1e-12);
        // The published landmarks (App. B).
        for (f, t) in [(90e3, 0.634e-3), (120e3, 0.802e-3), (240e3, 1.268e-3)] {
            let tc = t_sweep * ((f - f0) / (f1 - f0)).sqrt();
            assert!((tc - t).abs() < 1e-6, "{f}: {tc}");
        }
        // From the samples: for a unit-envelope tone, f = |V| / (2π·sqrt(A² − D²)).
        let (mut sum, mut count) = (0.0, 0);
        for i in 0..x.len() {
            let t = i as f64 / FS;
            let d = x.displacement[i];
            if (t - t_cross).abs() < 5e-6 && d.abs() < 0.7 * a {
                sum += x.velocity[i].abs() / (TAU * (a * a - d * d).sqrt());
                count += 1;
            }
        }
        assert!(count > 10);
        assert!(
            rel(sum / count as f64, 110e3) < 5e-3,
            "{}",
            sum / count as f64
        );
        // Starts at f0, ends at f1, D(0) = 0.
        assert_eq!(x.displacement[0], 0.0);
        assert!(rel(x.model.instantaneous_frequency(0.0).unwrap(), f0) < 1e-12);
        assert!(rel(x.model.instantaneous_frequency(t_sweep).unwrap(), f1) < 1e-12);
        // A down-sweep and a sweep from 0 Hz are fine.
        assert!(quadratic_chirp(1e-3, FS, 500e3, 40e3, a).is_ok());
        assert!(quadratic_chirp(1e-3, FS, 0.0, 40e3, a).is_ok());
    }

    #[test]
    fn invalid_input_is_an_error() {
        let nan = f64::NAN;
        let errs: Vec<Result<Excitation, DmwError>> = vec![
            zero(0.0, FS),
            zero(-1.0, FS),
            zero(T, 0.0),
            zero(T, -FS),
            zero(nan, FS),
            zero(T, f64::INFINITY),
            zero(1e9, 4e6),
            synthetic_dmw(T, FS, -1e-9, 1),
            synthetic_dmw(T, FS, nan, 1),
            synthetic_dmw(T, 0.0, 1e-9, 1),
            // Nyquist 500 kHz: the 500 kHz top of the broadband part is not below it.
            synthetic_dmw(T, 1e6, 1e-9, 1),
            synthetic_dmw_with(
                T,
                FS,
                &SyntheticDmwSpec {
                    hf_share: 1.5,
                    ..SyntheticDmwSpec::default()
                },
            ),
            synthetic_dmw_with(
                T,
                FS,
                &SyntheticDmwSpec {
                    hf_tones: 0,
                    ..SyntheticDmwSpec::default()
                },
            ),
            synthetic_dmw_with(
                T,
                FS,
                &SyntheticDmwSpec {
                    hf_band: (500e3, 10e3),
                    ..SyntheticDmwSpec::default()
                },
            ),
            sinusoid(T, FS, 2e6, 1e-9),
            sinusoid(T, FS, 3e6, 1e-9),
            sinusoid(T, FS, 0.0, 1e-9),
            sinusoid(T, FS, 10e3, -1.0),
            sinusoid(-T, FS, 10e3, 1.0),
            band_limited_random(T, FS, 50e3, 10e3, 1e-9, 1),
            band_limited_random(T, FS, 50e3, 50e3, 1e-9, 1),
            band_limited_random(T, FS, 10e3, 2.5e6, 1e-9, 1),
            band_limited_random(T, FS, -10e3, 50e3, 1e-9, 1),
            band_limited_random(T, FS, 10e3, 50e3, nan, 1),
            band_limited_random(T, 0.0, 10e3, 50e3, 1e-9, 1),
            quadratic_chirp(T, FS, 40e3, 2e6, 1e-9),
            quadratic_chirp(T, FS, 3e6, 40e3, 1e-9),
            quadratic_chirp(T, FS, -1.0, 40e3, 1e-9),
            quadratic_chirp(T, FS, 40e3, 500e3, nan),
            quadratic_chirp(0.0, FS, 40e3, 500e3, 1e-9),
        ];
        for (k, e) in errs.into_iter().enumerate() {
            match e {
                Err(DmwError::Processing(msg)) => assert!(!msg.is_empty()),
                other => panic!(
                    "case {k}: expected an error, got {:?}",
                    other.map(|x| x.len())
                ),
            }
        }
        // A two-sample record: either a finite track or an error, never a panic or a NaN.
        for x in [
            band_limited_random(0.25e-6, FS, 10e3, 50e3, 1e-9, 1),
            synthetic_dmw(0.25e-6, FS, 1e-9, 1),
            sinusoid(0.25e-6, FS, 10e3, 1e-9),
        ]
        .into_iter()
        .flatten()
        {
            assert_eq!(x.len(), 2);
            assert!(x
                .displacement
                .iter()
                .chain(&x.velocity)
                .all(|v| v.is_finite()));
        }
    }
}
