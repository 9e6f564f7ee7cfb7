//! The library's error type: domain errors from each module, with user-facing messages.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Config(#[from] crate::core::config::ConfigError),
    #[error(transparent)]
    Surface(#[from] crate::surface::SurfaceError),
    #[error(transparent)]
    Dmw(#[from] crate::dmw::DmwError),
    #[error(transparent)]
    Contact(#[from] crate::contact::ContactError),
    #[error(transparent)]
    Signal(#[from] crate::signal::SignalError),
    #[error(transparent)]
    Dynamics(#[from] crate::dynamics::DynamicsError),
    /// Drawing or writing a figure failed (same text as an output or I/O error).
    #[error(transparent)]
    Figure(#[from] crate::figures::FigureError),
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Writing an output (HDF5, table, plot) failed.
    #[error("writing {}: {message}", path.display())]
    Output { path: PathBuf, message: String },
    /// `hdi synth` could not write the sample data.
    #[error(transparent)]
    Samples(#[from] crate::samples::SampleError),
    /// Storing a computed case in the cache failed.
    #[error(transparent)]
    CaseStore(#[from] crate::core::cases::CaseError),
    /// One slider case of a sweep failed.
    #[error("case h_TFC = {:.3} nm", .actuation * 1e9)]
    Case {
        /// The case's actuation (m).
        actuation: f64,
        #[source]
        source: Box<Error>,
    },
    /// A stage could not run for a reason that is not one of the above.
    #[error("{0}")]
    Stage(String),
}

impl Error {
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
    pub fn output(path: impl Into<PathBuf>, message: impl std::fmt::Display) -> Self {
        Error::Output {
            path: path.into(),
            message: message.to_string(),
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;

/// The error and all its sources on one line, `outer: inner: …` (as the binary prints errors).
pub use crate::core::chain;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::FigureError;

    #[test]
    fn figure_errors_read_as_output_and_io_errors() {
        let draw = FigureError::Draw {
            path: PathBuf::from("out/a.png"),
            message: "plot: empty map".into(),
        };
        let as_output = Error::output("out/a.png", "plot: empty map");
        assert_eq!(Error::from(draw).to_string(), as_output.to_string());
        let io = || std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        let fig = Error::from(FigureError::Io {
            path: PathBuf::from("out/a.png"),
            source: io(),
        });
        assert_eq!(chain(&fig), chain(&Error::io("out/a.png", io())));
    }
}
