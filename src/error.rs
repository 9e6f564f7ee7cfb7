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
    /// An input file could not be read to fingerprint it.
    #[error("cannot read {}", path.display())]
    Input {
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
    /// A stage's typed output could not be written as JSON (a map key that is not a string).
    #[error("{kind} {what}: {message}")]
    Encode {
        kind: &'static str,
        what: String,
        message: String,
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
    /// An instance run alone (a one-off command through the engine) failed; the engine's
    /// message, which names the cause.
    #[error("{message}")]
    InstanceFailed { name: String, message: String },
    /// The stages' upstream links form a cycle.
    #[error("dependency cycle through stage `{0}`")]
    DependencyCycle(String),
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
    /// A 2-DOF case entry's `result.json` is not a case result of this hdi.
    #[error("2-DOF case result: unreadable")]
    CaseResult {
        #[source]
        source: serde_json::Error,
    },
    /// A worker thread panicked while holding a shared preparation.
    #[error("a worker thread panicked")]
    WorkerPanicked,
    /// `hdi validate` names no known area.
    #[error("unknown validation area `{0}`")]
    UnknownArea(String),
    /// The analysis of a series failed.
    #[error(transparent)]
    Analysis(#[from] crate::analysis::AnalysisError),
    /// The analysis of an upstream's series `file` `dataset` failed.
    #[error("{file} `{dataset}`")]
    AnalysisOf {
        file: String,
        dataset: String,
        #[source]
        source: crate::analysis::AnalysisError,
    },
    /// A regression (response surface, predictive equation) failed.
    #[error(transparent)]
    Regression(#[from] crate::numerics::regression::RegressionError),
    /// The DOE's response surface at one actuation could not be fitted.
    #[error("response surface at {:.1} nm", .actuation / 1e-9)]
    ResponseSurface {
        /// The actuation (m).
        actuation: f64,
        #[source]
        source: crate::numerics::regression::RegressionError,
    },
    /// A predictive equation (the response surface with one factor fixed) could not be formed.
    #[error("predictive equation")]
    PredictiveEquation(#[source] crate::numerics::regression::RegressionError),
    /// Simulated annealing (or its sensitivity points) refused its input.
    #[error("annealing")]
    Annealing(#[from] crate::numerics::annealing::AnnealingError),
    /// The sensitivity points around the annealing optimum could not be laid out.
    #[error("sensitivity")]
    Sensitivity(#[source] crate::numerics::annealing::AnnealingError),
    /// An ODE integration failed; the right-hand side's error is the dynamics one.
    #[error(transparent)]
    Ode(#[from] crate::numerics::ode::OdeError<crate::dynamics::DynamicsError>),
    /// One DOE case (a design at an actuation) failed.
    #[error(
        "case a = {:.3} um, w = {:.3} um, x = {:.3} um, h_TFC = {:.3} nm",
        .design[0] / 1e-6, .design[1] / 1e-6, .design[2] / 1e-6, .actuation / 1e-9
    )]
    DoeCase {
        /// The design (a, w, x) in m.
        design: [f64; 3],
        /// The actuation (m).
        actuation: f64,
        #[source]
        source: Box<Error>,
    },
    /// The DOE's objective ξ is not finite for a design of the 3³ grid.
    #[error(
        "ξ is not finite for design {:?} µm at {:.1} nm (a case without a steady clearance or \
         vibration)",
        .design.map(|v| v / 1e-6), .actuation / 1e-9
    )]
    NonFiniteXi {
        /// The design (a, w, x) in m.
        design: [f64; 3],
        /// The actuation (m).
        actuation: f64,
    },
    /// One 3-DOF case (an interface model) failed.
    #[error("case {case}")]
    ThreeDofCase {
        /// The case's label (`isbl`, `mtl_…`).
        case: String,
        #[source]
        source: Box<Error>,
    },
    /// A round of calibration cases failed as a whole (`message` is the round's error chain).
    #[error("{instance}: a round of calibration cases did not come back: {message}")]
    CalibrationRoundLost { instance: String, message: String },
    /// Opening an HDF5 file that hdi wrote failed.
    #[error("{}", path.display())]
    Hdf5Open {
        path: PathBuf,
        #[source]
        source: hdf5::Error,
    },
    /// Reading a dataset or attribute (`what`) of an HDF5 file that hdi wrote failed.
    #[error("{}: {what}", path.display())]
    Hdf5Read {
        path: PathBuf,
        what: String,
        #[source]
        source: hdf5::Error,
    },
    /// `--velocity` was given for a table, whose velocity is always derived.
    #[error(
        "{}: --velocity names an HDF5 dataset; a table's velocity is computed by central \
         differences",
        path.display()
    )]
    VelocityOfTable { path: PathBuf },
    /// The upstream `stage` handed no files to the stage that reads them.
    #[error("no files from `{stage}`")]
    NoUpstreamFiles { stage: String },
    /// The upstream `stage` has no output file `file`.
    #[error("`{stage}` has no output `{file}`")]
    MissingOutput { stage: String, file: String },
    /// An array did not have the shape its dimensions say (`what` names it).
    #[error("{what} shape")]
    Shape {
        what: &'static str,
        #[source]
        source: ndarray::ShapeError,
    },
    /// Measured summits come from one surface or an interface's two.
    #[error("measured summits of `{stage}`: need one or two surfaces, got {count}")]
    SummitSurfaces { stage: String, count: usize },
    /// Measured summits need the surface stage `surface` of a pipeline.
    #[error(
        "summit_distribution = \"measured\" needs the summits of `{surface}` from a pipeline \
         (`hdi run`); `hdi contact` has none"
    )]
    MeasuredSummitsOutsidePipeline { surface: String },
    /// `--only` names no stage of the pipeline; `hint` is " (did you mean `x`?)" or empty.
    #[error("--only: no stage named `{name}`{hint}")]
    UnknownStage { name: String, hint: String },
    /// The workspace lock could not be taken because of the filesystem (`cause`).
    #[error(
        "{cause}: cannot take the workspace lock ({}: {error}); `hdi status` and `hdi verify` \
         only read",
        lock.display()
    )]
    LockRefused {
        cause: String,
        lock: PathBuf,
        /// Shown inline: the text names the filesystem cause first.
        error: std::io::Error,
    },
    /// The rayon pool for the pipeline's waves could not start.
    #[error("cannot start worker threads: {error}")]
    WorkerThreads {
        /// Shown inline, not as a source: rayon's error displays as its own source, so the
        /// chain would print it twice.
        error: rayon::ThreadPoolBuildError,
    },
    /// An instance ran, but its human-friendly ref could not be written (`cause` names the
    /// filesystem's reason).
    #[error(
        "{cause}: `{name}` ran, but pointing {} at its result failed: {error}",
        path.display()
    )]
    RefNotWritten {
        cause: String,
        name: String,
        path: PathBuf,
        error: std::io::Error,
    },
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
        // The variants that replaced `Stage(String)`: the old `format!` beside each.
        let (design, h) = ([3e-6, 40e-6, 1.5e-6], 2.5e-9);
        let (um, nm) = (1e-6, 1e-9);
        assert_eq!(
            s(Error::NonFiniteXi {
                design,
                actuation: h
            }),
            format!(
                "ξ is not finite for design {:?} µm at {:.1} nm (a case without a steady \
                 clearance or vibration)",
                design.map(|v| v / um),
                h / nm
            )
        );
        assert_eq!(
            s(Error::DoeCase {
                design,
                actuation: h,
                source: Box::new(Error::UnknownArea(name()))
            }),
            format!(
                "case a = {:.3} um, w = {:.3} um, x = {:.3} um, h_TFC = {:.3} nm: {}",
                design[0] / um,
                design[1] / um,
                design[2] / um,
                h / nm,
                "unknown validation area `a`"
            )
        );
        let lock = std::path::Path::new("p/.hdi/lock");
        assert_eq!(
            s(Error::LockRefused {
                cause: "p is on a read-only filesystem".into(),
                lock: lock.into(),
                error: std::io::Error::other("ro"),
            }),
            format!(
                "p is on a read-only filesystem: cannot take the workspace lock ({}: ro); \
                 `hdi status` and `hdi verify` only read",
                lock.display()
            )
        );
        assert_eq!(
            s(Error::CaseKeyMismatch {
                kind: "doe".into(),
                case: "x".into(),
                derived: "k1".into(),
                submitted: "k0".into(),
            }),
            "doe case x: the pipeline file now gives key k1, the manifest has k0 (the file or \
             its upstream changed since submission; resubmit with `hdi run --executor slurm`)"
        );
        assert_eq!(
            s(Error::MeasuredSummitsOutsidePipeline { surface: name() }),
            "summit_distribution = \"measured\" needs the summits of `a` from a pipeline (`hdi \
             run`); `hdi contact` has none"
        );
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
