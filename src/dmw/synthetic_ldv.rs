//! Synthetic LDV records (docs/dmw.md): the shipped `raw/ldv/` sample
//! and the test fixtures. No registry package ships an LDV record with a once-per-revolution
//! index, so the sample is generated from a documented disk model, deterministically.
//!
//! Model: the disk's out-of-plane displacement is a sum of repeatable harmonics of the
//! rotation (a function of disk angle), plus non-repeatable tones (a function of time, e.g.
//! spindle NRRO). The spindle period wanders from revolution to revolution. The LDV measures
//! velocity; the decoder outputs `U = v/sensitivity` volts plus white noise. The index channel
//! is a TTL pulse whose rising edge crosses mid-level exactly at the start of each revolution.

use super::{Layout, LdvRecord, VelocityUnit};
use crate::numerics::rng::Rng;
use crate::signal::butterworth::{sos_response, Sos};
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::path::PathBuf;

/// One repeatable line: `amplitude·sin(order·θ + phase)`, θ the disk angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Harmonic {
    /// Cycles per revolution.
    pub order: u32,
    /// Displacement amplitude, m.
    pub amplitude: f64,
}

/// Everything that defines a synthetic record (written next to the shipped sample).
#[derive(Debug, Clone, PartialEq)]
pub struct LdvSynthSpec {
    pub sample_rate: f64,
    pub rpm: f64,
    pub n_revolutions: usize,
    /// Time before the first index pulse, s.
    pub lead_in: f64,
    pub harmonics: Vec<Harmonic>,
    /// Non-repeatable tones (frequency Hz, displacement amplitude m).
    pub nrro: Vec<(f64, f64)>,
    /// Decoder sensitivity, m/s per V.
    pub sensitivity: f64,
    /// White noise on the decoder output, V (std).
    pub noise_v: f64,
    /// Relative std of the revolution period.
    pub speed_wander: f64,
    /// Index pulse: high level (V), width (s), 10–90 % rise time (s).
    pub pulse_high: f64,
    pub pulse_width: f64,
    pub pulse_rise: f64,
    pub seed: u64,
}

impl Default for LdvSynthSpec {
    /// The dissertation's conditions (4 MS/s, 5 425 rpm, 25 mm/s/V) and the reference chain
    /// of §3.3: five repeatable harmonics, a 33.3 kHz NRRO tone, 5 mV decoder noise, 2·10⁻⁴
    /// speed wander, 100 revolutions.
    fn default() -> Self {
        LdvSynthSpec {
            sample_rate: 4e6,
            rpm: 5425.0,
            n_revolutions: 100,
            lead_in: 100e-6,
            harmonics: vec![
                Harmonic {
                    order: 11,
                    amplitude: 20e-9,
                },
                Harmonic {
                    order: 118,
                    amplitude: 1.5e-9,
                },
                Harmonic {
                    order: 553,
                    amplitude: 0.4e-9,
                },
                Harmonic {
                    order: 1327,
                    amplitude: 0.15e-9,
                },
                Harmonic {
                    order: 3041,
                    amplitude: 0.05e-9,
                },
            ],
            nrro: vec![(33.3e3, 0.5e-9)],
            sensitivity: 0.025,
            noise_v: 5e-3,
            speed_wander: 2e-4,
            pulse_high: 5.0,
            pulse_width: 20e-6,
            pulse_rise: 0.5e-6,
            seed: 20_111_223,
        }
    }
}

/// What the generator knows and a processing chain should recover.
#[derive(Debug, Clone)]
pub struct SynthTruth {
    /// Index edge mid-level crossings, s: the start of each revolution and the end of the
    /// last (`n_revolutions + 1` edges).
    pub trigger_times: Vec<f64>,
    /// Revolution periods, s.
    pub periods: Vec<f64>,
    /// Phase of each harmonic, rad.
    pub harmonic_phases: Vec<f64>,
}

impl LdvSynthSpec {
    pub fn nominal_period(&self) -> f64 {
        60.0 / self.rpm
    }

    /// The parameters as JSON (written beside generated files).
    pub fn to_json(&self) -> Value {
        json!({
            "sample_rate_Hz": self.sample_rate,
            "rpm": self.rpm,
            "n_revolutions": self.n_revolutions,
            "lead_in_s": self.lead_in,
            "harmonics": self.harmonics.iter().map(|h| json!({
                "order": h.order,
                "frequency_Hz": h.order as f64 * self.rpm / 60.0,
                "amplitude_m": h.amplitude,
            })).collect::<Vec<_>>(),
            "nrro": self.nrro.iter().map(|(f, a)| json!({"frequency_Hz": f, "amplitude_m": a})).collect::<Vec<_>>(),
            "sensitivity_m_s_per_V": self.sensitivity,
            "noise_V": self.noise_v,
            "speed_wander": self.speed_wander,
            "index_pulse": {"high_V": self.pulse_high, "width_s": self.pulse_width, "rise_s": self.pulse_rise},
            "seed": self.seed,
        })
    }
}

/// Generate the record (velocity in volts, index in volts) and its truth.
pub fn generate(spec: &LdvSynthSpec) -> (LdvRecord, SynthTruth) {
    let mut rng = Rng::new(spec.seed);
    let p0 = spec.nominal_period();
    let harmonic_phases: Vec<f64> = spec
        .harmonics
        .iter()
        .map(|_| 2.0 * PI * rng.uniform())
        .collect();
    let nrro_phases: Vec<f64> = spec.nrro.iter().map(|_| 2.0 * PI * rng.uniform()).collect();
    let periods: Vec<f64> = (0..spec.n_revolutions)
        .map(|_| p0 * (1.0 + spec.speed_wander * rng.normal()))
        .collect();
    let mut trigger_times = Vec::with_capacity(periods.len());
    let mut t = spec.lead_in;
    for p in &periods {
        trigger_times.push(t);
        t += p;
    }
    // The edge that closes the last revolution, so every revolution has a measured period.
    trigger_times.push(t);
    let end = t + spec.lead_in.max(50e-6);
    let fs = spec.sample_rate;
    let n = (end * fs).ceil() as usize;
    let mut velocity = Vec::with_capacity(n);
    let mut index = Vec::with_capacity(n);
    // Revolution −1 (the lead-in) turns at the nominal speed.
    let mut rev = 0usize;
    for i in 0..n {
        let t = i as f64 / fs;
        while rev < trigger_times.len() && t >= trigger_times[rev] {
            rev += 1;
        }
        // `rev` revolutions have started; the current one began at trigger rev−1.
        let (start, period) = if rev == 0 {
            (trigger_times.first().copied().unwrap_or(0.0) - p0, p0)
        } else {
            let k = rev - 1;
            (trigger_times[k], periods.get(k).copied().unwrap_or(p0))
        };
        let angle = 2.0 * PI * (t - start) / period;
        let omega = 2.0 * PI / period;
        let mut v = 0.0;
        for (h, ph) in spec.harmonics.iter().zip(&harmonic_phases) {
            let m = h.order as f64;
            v += h.amplitude * m * omega * (m * angle + ph).cos();
        }
        for ((f, a), ph) in spec.nrro.iter().zip(&nrro_phases) {
            v += a * 2.0 * PI * f * (2.0 * PI * f * t + ph).cos();
        }
        velocity.push(v / spec.sensitivity + spec.noise_v * rng.normal());
        index.push(index_level(spec, &trigger_times, t));
    }
    let record = LdvRecord {
        source: PathBuf::from("synthetic"),
        format: "synthetic",
        sample_rate: fs,
        t0: 0.0,
        velocity,
        velocity_unit: VelocityUnit::Volt,
        index: Some(index),
        layout: Layout::Continuous,
        sensitivity: Some(spec.sensitivity),
        rpm: Some(spec.rpm),
        provenance: vec![("generator".into(), spec.to_json().to_string())],
    };
    (
        record,
        SynthTruth {
            trigger_times,
            periods,
            harmonic_phases,
        },
    )
}

/// TTL index: a linear edge of `pulse_rise` centred on each trigger time, `pulse_width` high.
fn index_level(spec: &LdvSynthSpec, triggers: &[f64], t: f64) -> f64 {
    // The last trigger at or before t + rise/2.
    let k = triggers.partition_point(|&tk| tk <= t + 0.5 * spec.pulse_rise);
    if k == 0 {
        return 0.0;
    }
    let tk = triggers[k - 1];
    let rise = spec.pulse_rise.max(1e-15);
    let up = ((t - tk) / rise + 0.5).clamp(0.0, 1.0);
    let down = ((tk + spec.pulse_width - t) / rise + 0.5).clamp(0.0, 1.0);
    spec.pulse_high * up.min(down)
}

/// The repeatable displacement at mean speed, `t` seconds after a trigger, with each line
/// scaled by the zero-phase gain |H(f)|² of `highpass` (if given): what an ideal chain
/// (perfect average, exact integration, steady-state filter) returns.
pub fn truth_displacement(
    spec: &LdvSynthSpec,
    truth: &SynthTruth,
    mean_period: f64,
    times: &[f64],
    highpass: Option<&[Sos]>,
) -> Vec<f64> {
    let gains: Vec<f64> = spec
        .harmonics
        .iter()
        .map(|h| match highpass {
            Some(sos) => {
                let f = h.order as f64 / mean_period;
                sos_response(sos, f, spec.sample_rate).norm_sqr()
            }
            None => 1.0,
        })
        .collect();
    times
        .iter()
        .map(|&t| {
            spec.harmonics
                .iter()
                .zip(&truth.harmonic_phases)
                .zip(&gains)
                .map(|((h, ph), g)| {
                    g * h.amplitude * (h.order as f64 * 2.0 * PI * t / mean_period + ph).sin()
                })
                .sum()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_edges_cross_mid_level_at_the_trigger_times() {
        let spec = LdvSynthSpec {
            n_revolutions: 3,
            ..Default::default()
        };
        let (rec, truth) = generate(&spec);
        let idx = rec.index.as_ref().unwrap();
        assert_eq!(idx.len(), rec.velocity.len());
        for &tk in &truth.trigger_times {
            let i = (tk * spec.sample_rate).floor() as usize;
            assert!(idx[i] <= 2.5 && idx[i + 1] >= 2.5, "{tk}");
            assert_eq!(idx[i + 40], 5.0);
            assert_eq!(idx[i + 200], 0.0);
        }
        let p = &truth.periods;
        assert!(p
            .iter()
            .all(|p| (p / spec.nominal_period() - 1.0).abs() < 1e-3));
    }

    #[test]
    fn generator_is_deterministic() {
        let spec = LdvSynthSpec {
            n_revolutions: 2,
            ..Default::default()
        };
        let (a, _) = generate(&spec);
        let (b, _) = generate(&spec);
        assert_eq!(a.velocity, b.velocity);
        let other = LdvSynthSpec {
            seed: 1,
            ..spec.clone()
        };
        assert_ne!(generate(&other).0.velocity, a.velocity);
    }
}
