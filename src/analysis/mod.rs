//! Analysis-stage numerics (App. B; docs/analysis.md): amplitude spectra and Welch PSD of a
//! time window, the continuous complex-Morlet wavelet transform, Poincaré sections and phase
//! space, and a periodicity classification of the section points.
//!
//! Everything here is a pure function on slices in SI units (s, Hz, signal units); no I/O.
//! Inputs are checked: a series that is too short, holds NaN/∞ or comes with an impossible
//! frequency range returns an [`AnalysisError`], never a panic.
//!
//! - [`series`]: time window, mean/linear detrend, amplitude spectrum (reusing
//!   [`crate::signal::spectrum`]) and Welch PSD.
//! - [`cwt`]: FFT-based CWT (analytic Morlet ω0 = 6 by default, or PyWavelets' `cmorB-C`),
//!   L1 / L2 / PyWavelets normalisations, cone of influence and ridge.
//! - [`poincare`]: the section {v = 0} (one extremum per half period, parabola-refined), the
//!   return map (x_n, x_{n+1}) of the maxima, and the decimated phase-space trajectory.
//! - [`streaming`]: the same CWT for a band of frequencies over a record read block by block
//!   (overlap-save), reduced to decimated bins in bounded memory.
//! - [`classify`]: fixed point / periodic (period k) / quasi-periodic / irregular from the
//!   section, with the thresholds and the diagnostics behind the verdict.

pub mod classify;
pub mod coherence;
pub mod cwt;
pub mod poincare;
pub mod report;
pub mod series;
pub mod significance;
pub mod streaming;

#[cfg(test)]
mod tests;

use crate::signal::SignalError;

/// Errors of the analysis numerics: always a property of the input or of the options.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AnalysisError {
    /// Too few samples (or too few section points) for the operation.
    #[error("{what}: {len} {unit} are too few (need at least {min})")]
    TooShort {
        what: &'static str,
        len: usize,
        min: usize,
        /// What is counted: "samples", "section maxima".
        unit: &'static str,
    },
    /// NaN or infinity in an input series.
    #[error("{what}: non-finite value {value} at sample {index}")]
    NonFinite {
        what: &'static str,
        index: usize,
        value: f64,
    },
    /// A frequency band that is empty, non-positive or beyond Nyquist.
    #[error("frequency range {low_hz} Hz to {high_hz} Hz: {reason}")]
    FrequencyRange {
        low_hz: f64,
        high_hz: f64,
        reason: String,
    },
    /// Two series that must be sample-aligned have different lengths.
    #[error("{what}: lengths differ ({left} vs {right} samples)")]
    LengthMismatch {
        what: &'static str,
        left: usize,
        right: usize,
    },
    /// Any other option outside its valid range.
    #[error("{name} = {value}: {reason}")]
    Parameter {
        name: &'static str,
        value: String,
        reason: String,
    },
    /// An error of the shared signal numerics (spectrum).
    #[error(transparent)]
    Signal(#[from] SignalError),
}

impl AnalysisError {
    pub(crate) fn parameter(
        name: &'static str,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        AnalysisError::Parameter {
            name,
            value: value.to_string(),
            reason: reason.into(),
        }
    }
}

/// Checks a series: at least `min` samples, all finite.
pub(crate) fn check_series(x: &[f64], min: usize, what: &'static str) -> Result<(), AnalysisError> {
    if x.len() < min {
        return Err(AnalysisError::TooShort {
            what,
            len: x.len(),
            min,
            unit: "samples",
        });
    }
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(AnalysisError::NonFinite {
            what,
            index,
            value: x[index],
        }),
        None => Ok(()),
    }
}

/// Checks a sample rate: finite and > 0.
pub(crate) fn check_rate(fs: f64) -> Result<(), AnalysisError> {
    if fs.is_nan() || fs.is_infinite() || fs <= 0.0 {
        return Err(AnalysisError::parameter(
            "sample rate",
            fs,
            "must be finite and > 0 Hz",
        ));
    }
    Ok(())
}
