//! One-dimensional signal numerics shared by the DMW and analysis stages: Butterworth design,
//! zero-phase second-order-section filtering, integration, band-limited resampling, Hermite
//! evaluation and amplitude spectra. Pure functions on slices; no I/O.

pub mod butterworth;
pub mod fft_convolution;
pub mod integrate;
pub mod resample;
pub mod rfft;
pub mod sosfilt;
pub mod spectrum;

/// Errors of the signal numerics: always a bad argument (the functions do no I/O).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SignalError {
    /// A parameter outside its valid range, e.g. a cutoff at or above Nyquist.
    #[error("{name} = {value}: {reason}")]
    Parameter {
        name: &'static str,
        value: String,
        reason: String,
    },
    /// The signal is too short for the operation (e.g. shorter than the filter padding).
    #[error("signal of {len} samples is too short: {reason}")]
    TooShort { len: usize, reason: String },
    /// NaN or infinity in the input.
    #[error("non-finite value at sample {index}")]
    NonFinite { index: usize },
}

impl SignalError {
    pub fn parameter(
        name: &'static str,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        SignalError::Parameter {
            name,
            value: value.to_string(),
            reason: reason.into(),
        }
    }
}
