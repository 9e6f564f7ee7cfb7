//! DMW stage physics and I/O: LDV velocity records → revolution-averaged velocity →
//! displacement → the three dynamic-microwaviness tracks (App. B; docs/dmw.md).
//!
//! Everything in here is pure except `io` (readers, text and Parquet writers); the `dmw` stage wires it
//! into the pipeline. SI inside: seconds, metres, m/s; the raw decoder output is in volts.

pub mod average;
pub mod chain;
pub mod excitation_tracks;
pub mod io;
pub mod synthetic_ldv;
pub mod tracks;
pub mod triggers;

use std::path::PathBuf;

/// Unit of the velocity channel as recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VelocityUnit {
    /// Decoder output voltage; multiply by the decoder sensitivity (m/s per V).
    Volt,
    /// Already a velocity.
    MetrePerSecond,
}

impl VelocityUnit {
    pub fn symbol(self) -> &'static str {
        match self {
            VelocityUnit::Volt => "V",
            VelocityUnit::MetrePerSecond => "m/s",
        }
    }
}

/// How the samples of a record are arranged (docs/dmw.md).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Layout {
    /// One long record, optionally with a once-per-revolution index channel.
    Continuous,
    /// A stack of triggered segments `[n_segments, segment_len]`, row-major in `velocity`.
    Segments {
        n_segments: usize,
        segment_len: usize,
    },
    /// An already averaged record (one segment).
    Averaged,
}

/// One LDV record as read from a file, before any processing.
#[derive(Debug, Clone)]
pub struct LdvRecord {
    pub source: PathBuf,
    /// "csv", "parquet" or "hdf5".
    pub format: &'static str,
    /// Samples per second.
    pub sample_rate: f64,
    /// Time of sample 0, seconds.
    pub t0: f64,
    /// Velocity channel in `velocity_unit`.
    pub velocity: Vec<f64>,
    pub velocity_unit: VelocityUnit,
    /// Once-per-revolution index (trigger) channel, any unit (volts for a TTL).
    pub index: Option<Vec<f64>>,
    pub layout: Layout,
    /// Decoder sensitivity (m/s per V) if the file states it.
    pub sensitivity: Option<f64>,
    /// Spindle speed (rpm) if the file states it.
    pub rpm: Option<f64>,
    /// What was read, for provenance: (key, value) pairs such as column names.
    pub provenance: Vec<(String, String)>,
}

/// Errors of reading and processing LDV records. Messages name the file or the parameter.
#[derive(Debug, thiserror::Error)]
pub enum DmwError {
    /// The file could not be read or parsed.
    #[error("{}: {message}", path.display())]
    Read { path: PathBuf, message: String },
    /// The record's content is unusable (non-monotonic time, NaN run, missing channel...).
    #[error("{}: {message}", path.display())]
    Record { path: PathBuf, message: String },
    /// A processing step cannot run on this record with these parameters.
    #[error("{0}")]
    Processing(String),
    #[error(transparent)]
    Signal(#[from] crate::signal::SignalError),
    /// A reader run in a child process (`formats::isolated`) failed: only its error's text
    /// crosses the process boundary.
    #[error("{0}")]
    Isolated(String),
}
