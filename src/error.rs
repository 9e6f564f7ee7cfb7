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
    /// Writing an HDF5 file or a table failed.
    #[error(transparent)]
    Store(#[from] crate::core::store::OutputError),
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
    /// An upstream instance's result was not handed to the stage that consumes it.
    #[error("no result from {kind} `{name}`")]
    MissingUpstream { kind: &'static str, name: String },
    /// An upstream instance's store entry was not handed to the stage that reads its files.
    #[error("no files from {kind} `{name}`")]
    MissingUpstreamFiles { kind: &'static str, name: String },
    /// An upstream result lacks a value its consumer needs; `what` names it (e.g. "`sigma`").
    #[error("{kind} `{name}` result has no {what}")]
    UpstreamField {
        kind: &'static str,
        name: String,
        what: String,
    },
    /// A store entry's `result.json` does not parse.
    #[error("{}", path.display())]
    ResultJson {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    /// The sweep metrics of a finished sweep could not be computed.
    #[error("sweep metrics")]
    SweepMetrics(#[source] crate::dynamics::metrics::MetricsError),
    /// A distributed case's upstream is not in the plan, or has no current store entry.
    #[error("upstream `{upstream}` of `{consumer}` {}", if *.planned { "has no current result (run it first)" } else { "is unknown" })]
    UpstreamNotReady {
        upstream: String,
        consumer: String,
        /// Whether the upstream is in the plan (then it is only stale).
        planned: bool,
    },
    /// A stage names an upstream that the pipeline does not declare.
    #[error("stage `{stage}` consumes `{upstream}`, which is not declared")]
    UndeclaredUpstream { stage: String, upstream: String },
    /// The stages' upstream links form a cycle.
    #[error("dependency cycle through stage `{0}`")]
    DependencyCycle(String),
    /// The pipeline has no `[kind.name]` instance.
    #[error("no [{kind}.{name}] in the pipeline")]
    MissingInstance { kind: &'static str, name: String },
    /// A distributed case's recipe is not a recipe of this hdi (`stages::case_engine`).
    #[error("{kind} recipe: unreadable")]
    Recipe {
        kind: String,
        #[source]
        source: serde_json::Error,
    },
    /// A distributed case's recipe holds a case that is not one of its kind.
    #[error("{kind} recipe: bad case")]
    RecipeCase {
        kind: &'static str,
        #[source]
        source: serde_json::Error,
    },
    /// A case re-derived on a worker does not arrive at the key the submitter derived: the
    /// pipeline file or an upstream entry changed since submission.
    #[error(
        "{kind} case {case}: the pipeline file now gives key {derived}, the manifest has \
         {submitted} (the file or its upstream changed since submission; resubmit with \
         `hdi run --executor slurm`)"
    )]
    CaseKeyMismatch {
        kind: String,
        case: String,
        derived: String,
        submitted: String,
    },
    /// A recipe names an instance that is not (or no longer) a stage with cases of its kind.
    #[error("{kind} recipe: [{section}.{instance}] in {config} {why}")]
    CaseInstance {
        kind: String,
        section: String,
        instance: String,
        config: String,
        why: &'static str,
    },
    /// A recipe names a case its instance does not have (the file changed since submission).
    #[error(
        "{kind} recipe: the instance has no case `{case}` (the file changed since submission?)"
    )]
    UnknownCase { kind: &'static str, case: String },
    /// A calibration case's metrics do not come back from JSON bit for bit.
    #[error("calibration case: its metrics do not survive JSON exactly")]
    CaseMetricsJson,
    /// A worker thread panicked while holding a shared preparation.
    #[error("a worker thread panicked")]
    WorkerPoisoned,
    /// `hdi validate` names no known area.
    #[error("unknown validation area `{0}`")]
    UnknownArea(String),
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

    /// The typed variants print exactly what their `Stage(format!(…))` predecessors printed.
    #[test]
    fn typed_variants_keep_the_stage_texts() {
        let s = |e: Error| chain(&e);
        let name = || "a".to_string();
        assert_eq!(
            s(Error::MissingUpstream {
                kind: "surface",
                name: name()
            }),
            "no result from surface `a`"
        );
        assert_eq!(
            s(Error::MissingUpstreamFiles {
                kind: "dmw",
                name: name()
            }),
            "no files from dmw `a`"
        );
        assert_eq!(
            s(Error::UpstreamField {
                kind: "interface",
                name: name(),
                what: "`R_m`".into()
            }),
            "interface `a` result has no `R_m`"
        );
        assert_eq!(
            s(Error::UpstreamField {
                kind: "contact",
                name: name(),
                what: "usable `inputs`".into()
            }),
            "contact `a` result has no usable `inputs`"
        );
        let json = || serde_json::from_slice::<serde_json::Value>(b"{").unwrap_err();
        assert_eq!(
            s(Error::ResultJson {
                path: "d/result.json".into(),
                source: json()
            }),
            format!("d/result.json: {}", json())
        );
        let metrics = || crate::dynamics::metrics::MetricsError::NotIncreasing { index: 2 };
        assert_eq!(
            s(Error::SweepMetrics(metrics())),
            format!("sweep metrics: {}", metrics())
        );
        assert_eq!(
            s(Error::UndeclaredUpstream {
                stage: "b".into(),
                upstream: name()
            }),
            "stage `b` consumes `a`, which is not declared"
        );
        let ready = |planned| Error::UpstreamNotReady {
            upstream: name(),
            consumer: "b".into(),
            planned,
        };
        assert_eq!(s(ready(false)), "upstream `a` of `b` is unknown");
        assert_eq!(
            s(ready(true)),
            "upstream `a` of `b` has no current result (run it first)"
        );
        assert_eq!(
            s(Error::DependencyCycle(name())),
            "dependency cycle through stage `a`"
        );
        assert_eq!(
            s(Error::MissingInstance {
                kind: "doe",
                name: name()
            }),
            "no [doe.a] in the pipeline"
        );
        let bad =
            || serde_json::from_value::<Option<[f64; 3]>>(serde_json::json!("x")).unwrap_err();
        assert_eq!(
            s(Error::RecipeCase {
                kind: "doe",
                source: bad()
            }),
            format!("doe recipe: bad case: {}", bad())
        );
        assert_eq!(s(Error::UnknownArea(name())), "unknown validation area `a`");
        let case = crate::core::cases::CaseError::Io {
            path: "p".into(),
            source: std::io::Error::other("gone"),
        };
        assert_eq!(
            s(Error::from(case)),
            chain(&Error::io("p", std::io::Error::other("gone")))
        );
    }
}
