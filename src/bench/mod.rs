//! `hdi bench`'s measurements: the timing figures of docs/performance.md, each with its unit,
//! the number of timed repeats and the statistic (best of N after one untimed warm-up, with
//! the median beside it): the surfaces stage, the 2-DOF slider per accepted step, the 76-case
//! sweep, one 3-DOF case, the CWT and Hann spectrum kernels, roughness, the no-op cached rerun
//! and (on request) the shipped pipeline run cold in a temp dir. [`run`] measures, a
//! [`BenchHost`] (the command line) prints each figure as it comes and runs the pipeline as a
//! child process; [`BenchDocument`] is the `--json` document (docs/schemas/bench.json) and
//! [`Figure::table_line`] the printed line. `readers` times the file readers
//! (docs/performance.md, "Reader throughput"); bench/README.md says how `bench/compare.sh`
//! feeds hdi and the Python anchors the same arrays (`npy`).

mod kernels;
mod main_job;
mod npy;
pub mod readers;
mod slider;

use schemars::JsonSchema;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Sample rate the signal kernels assume (also for `--input`): the LDV records' 4 MS/s.
const FS: f64 = 4e6;

/// Length of the streaming CWT's generated record (docs/performance.md, "Streaming band CWT").
const STREAM_SAMPLES: usize = 100_000_000;

/// The figure groups, in the order they run; `--only` takes these names.
pub const GROUPS: [&str; 12] = [
    "surfaces",
    "two-dof",
    "sweep",
    "three-dof",
    "cwt",
    "fft",
    "roughness",
    "bem",
    "stream",
    "significance",
    "noop",
    "main-job",
];

/// Why a measurement could not be taken; the messages name the option or file at fault.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error("--only: unknown group `{group}` (groups: {})", GROUPS.join(", "))]
    UnknownGroup { group: String },
    #[error(
        "--input {}: give exactly one of --only cwt, --only fft, --only roughness, --only bem \
         (the kernel that times this array)",
        .0.display()
    )]
    InputWithoutKernel(PathBuf),
    #[error("--size {0}: the map needs at least 8 × 8 pixels")]
    MapTooSmall(usize),
    #[error(
        "--main-job: {} not found (run it where the shipped pipeline.toml and raw/ are, or \
         give --config)",
        .0.display()
    )]
    NoPipeline(PathBuf),
    #[error("{what} {}", path.display())]
    Io {
        /// "reading", "writing", "copying", "creating", …
        what: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}", path.display())]
    Npy {
        path: PathBuf,
        #[source]
        source: crate::formats::npy::NpyError,
    },
    /// An `--input` array that is not what the kernel times.
    #[error("{}: {message}", path.display())]
    Input { path: PathBuf, message: String },
    #[error("running hdi run")]
    Spawn(#[source] std::io::Error),
    #[error("hdi run --config {} failed: {last_line}", config.display())]
    PipelineFailed { config: PathBuf, last_line: String },
    #[error("{0}")]
    Settings(#[from] crate::core::config::KeyError),
    #[error(transparent)]
    Toml(#[from] toml::de::Error),
    #[error(transparent)]
    Hdi(#[from] crate::Error),
    #[error(transparent)]
    Analysis(#[from] crate::analysis::AnalysisError),
    #[error(transparent)]
    Surface(#[from] crate::surface::SurfaceError),
    #[error(transparent)]
    Dmw(#[from] crate::dmw::DmwError),
    #[error(transparent)]
    Contact(#[from] crate::contact::ContactError),
    #[error(transparent)]
    Dynamics(#[from] crate::dynamics::DynamicsError),
}

pub type Result<T> = std::result::Result<T, BenchError>;

impl BenchError {
    fn io<'a>(what: &'static str, path: &'a Path) -> impl FnOnce(std::io::Error) -> Self + 'a {
        move |source| BenchError::Io {
            what,
            path: path.to_path_buf(),
            source,
        }
    }
}

/// What to measure (`hdi bench`'s options).
pub struct BenchOptions {
    /// The pipeline of the `noop` and `main-job` groups.
    pub config: PathBuf,
    /// Side of the synthetic height map (pixels).
    pub size: usize,
    /// Groups to run (empty: all but `main-job`).
    pub only: Vec<String>,
    /// Run the main job too.
    pub main_job: bool,
    /// A `.npy` array the one selected kernel times instead of its synthetic input.
    pub input: Option<PathBuf>,
    /// Timed repeats of every figure (default: each group's own).
    pub repeat: Option<usize>,
}

/// What the caller does while the figures are measured.
pub trait BenchHost {
    /// A figure was measured (the command line prints it at once).
    fn figure(&mut self, figure: &Figure);
    /// The main job is about to run cold in a temp dir (minutes).
    fn main_job_starting(&mut self, config: &Path);
    /// Run the pipeline `config` to completion as `hdi run` does (a child process, so that a
    /// no-op rerun's figure includes start-up); its log (`ran NAME (S s)` lines).
    fn run_pipeline(&mut self, config: &Path) -> Result<String>;
}

/// One measured figure.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Figure {
    /// The `--only` group that produced the figure.
    pub group: Group,
    /// Stable identifier of the figure (e.g. `two_dof_8.5nm_us_per_step`,
    /// `main_job_stage_NAME`).
    #[schemars(length(min = 1))]
    pub name: String,
    /// What was timed, as printed in the text table.
    #[schemars(length(min = 1))]
    pub label: String,
    /// The figure, in `unit`: the best of `repeats` timed runs after one untimed warm-up
    /// (`statistic` best), or one cold run (`statistic` single).
    #[schemars(range(min = 0))]
    pub value: f64,
    /// Unit of `value` and `median`.
    pub unit: Unit,
    /// best: minimum over `repeats` timed runs after a warm-up; single: one run (the cold
    /// main job).
    pub statistic: Statistic,
    /// Number of timed runs behind `value` (`--repeat`).
    #[schemars(range(min = 1))]
    pub repeats: usize,
    /// Median of the timed runs, in `unit`; null for a single run.
    #[schemars(range(min = 0))]
    pub median: Option<f64>,
    /// Counts behind the figure (keys with unit suffixes where they have units).
    pub details: Details,
}

/// A figure group ([`GROUPS`], in the same words).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Group {
    Surfaces,
    TwoDof,
    Sweep,
    ThreeDof,
    Cwt,
    Fft,
    Roughness,
    Bem,
    Stream,
    Significance,
    Noop,
    MainJob,
}

/// The unit of a figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
pub enum Unit {
    #[serde(rename = "s")]
    Seconds,
    #[serde(rename = "ms")]
    Milliseconds,
    #[serde(rename = "µs/step")]
    MicrosecondsPerStep,
}

impl Unit {
    fn as_str(self) -> &'static str {
        match self {
            Unit::Seconds => "s",
            Unit::Milliseconds => "ms",
            Unit::MicrosecondsPerStep => "µs/step",
        }
    }
}

/// How `value` was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Statistic {
    Best,
    Single,
}

/// The counts behind a figure; each figure writes its own few, in this order.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct Details {
    /// Map pixels (surfaces, roughness).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(range(min = 1))]
    pub pixels: Option<usize>,
    /// Signal samples (cwt, fft).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(range(min = 1))]
    pub samples: Option<usize>,
    /// CWT rows.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(range(min = 1))]
    pub frequencies: Option<usize>,
    /// Slider cases of the sweep.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(range(min = 1))]
    pub cases: Option<usize>,
    /// Accepted integrator steps (one case; the sweep: all cases).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accepted_steps: Option<u64>,
    /// Threads the sweep ran on.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(range(min = 1))]
    pub threads: Option<usize>,
    /// Rejected integrator steps of the case.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rejected_steps: Option<u64>,
    /// Right-hand-side evaluations of the case.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rhs_evaluations: Option<u64>,
    /// Wall time of one case (the best run), ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(range(min = 0))]
    pub case_ms: Option<f64>,
    /// Best case wall time per right-hand-side evaluation, µs.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(range(min = 0))]
    pub us_per_rhs_evaluation: Option<f64>,
    /// Best case wall time per accepted step, µs.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(range(min = 0))]
    pub us_per_step: Option<f64>,
    /// BEM solves: conjugate-gradient iterations of the timed solve, and the memory the
    /// solver held, bytes (the streaming CWT: the transform's allocations at their peak).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub memory_bytes: Option<usize>,
    /// Peak resident set of the bench process after the figure (Linux VmHWM), bytes: it
    /// includes every group run before.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_rss_bytes: Option<u64>,
    /// Stage instances the cold main job ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stages_ran: Option<usize>,
    /// Wall time of every stage instance the cold run ran, s, as `hdi run` logs it (`ran NAME
    /// (S s)`); stages run concurrently, so they need not sum to `value`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stage_wall_s: Option<StageWalls>,
}

impl Details {
    /// The numeric details as `name value` (integers as they are, floats to four digits).
    fn counts(&self) -> Vec<String> {
        let n = |v: Option<usize>| v.map(|v| v as u64);
        let ints = [
            ("pixels", n(self.pixels)),
            ("samples", n(self.samples)),
            ("frequencies", n(self.frequencies)),
            ("cases", n(self.cases)),
            ("accepted_steps", self.accepted_steps),
            ("threads", n(self.threads)),
            ("rejected_steps", self.rejected_steps),
            ("rhs_evaluations", self.rhs_evaluations),
            ("memory_bytes", n(self.memory_bytes)),
            ("peak_rss_bytes", self.peak_rss_bytes),
        ];
        let floats = [
            ("case_ms", self.case_ms),
            ("us_per_rhs_evaluation", self.us_per_rhs_evaluation),
            ("us_per_step", self.us_per_step),
        ];
        let mut out: Vec<String> = ints
            .iter()
            .filter_map(|(k, v)| v.map(|v| format!("{k} {v}")))
            .collect();
        out.extend(
            floats
                .iter()
                .filter_map(|(k, v)| v.map(|v| format!("{k} {}", fmt(v)))),
        );
        if let Some(n) = self.stages_ran {
            out.push(format!("stages_ran {n}"));
        }
        out
    }
}

/// Stage name → wall time (s), in log order; written as one object.
#[derive(Debug, Clone, Default)]
pub struct StageWalls(pub Vec<(String, f64)>);

impl Serialize for StageWalls {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

impl JsonSchema for StageWalls {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "StageWalls".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "type": "object",
            "additionalProperties": { "type": "number", "minimum": 0 }
        })
    }
}

impl Figure {
    /// A best-of-`repeats` figure with its median.
    fn best(
        group: Group,
        name: impl Into<String>,
        label: impl Into<String>,
        (value, median): (f64, f64),
        unit: Unit,
        repeats: usize,
        details: Details,
    ) -> Self {
        Figure {
            group,
            name: name.into(),
            label: label.into(),
            value,
            unit,
            statistic: Statistic::Best,
            repeats,
            median: Some(median),
            details,
        }
    }

    /// The printed line: label, value, unit, statistic and the numeric details.
    pub fn table_line(&self) -> String {
        let stat = match (self.statistic, self.median) {
            (Statistic::Best, Some(m)) => {
                format!("best of {} (median {})", self.repeats, fmt(m))
            }
            (Statistic::Best, None) => format!("best of {}", self.repeats),
            _ => "single run".to_string(),
        };
        let counts = self.details.counts();
        let counts = if counts.is_empty() {
            String::new()
        } else {
            format!("; {}", counts.join(", "))
        };
        format!(
            "{:<62} {:>10} {:<8} {stat}{counts}",
            self.label,
            fmt(self.value),
            self.unit.as_str()
        )
    }
}

/// Timing figures of `hdi bench` (docs/performance.md, bench/README.md): one object per
/// figure, in the order they ran. Wall times of this machine and moment: not a result file,
/// not deterministic. Schema version 1 (docs/json.md): existing keys keep their name, unit and
/// type; renaming or removing one makes version 2.
#[derive(Debug, Serialize, JsonSchema)]
pub struct BenchDocument {
    /// Version of the hdi binary that timed the figures.
    #[schemars(length(min = 1))]
    pub hdi_version: &'static str,
    /// Threads of the rayon pool (what the parallel figures, e.g. the sweep, ran on).
    #[schemars(range(min = 1))]
    pub threads: usize,
    /// The `--input FILE.npy` the one selected kernel was timed on; null when the built-in
    /// inputs were used.
    pub input: Option<String>,
    /// The figures, in the order they ran.
    pub figures: Vec<Figure>,
}

impl BenchDocument {
    pub fn new(input: Option<&Path>, figures: Vec<Figure>) -> Self {
        BenchDocument {
            hdi_version: env!("CARGO_PKG_VERSION"),
            threads: rayon::current_num_threads(),
            input: input.map(|p| p.to_string_lossy().into_owned()),
            figures,
        }
    }
}

/// The first printed line: version and thread count.
pub fn header_line() -> String {
    format!(
        "hdi {} bench, {} threads; every timing after one untimed warm-up",
        env!("CARGO_PKG_VERSION"),
        rayon::current_num_threads()
    )
}

/// Checks the options: known groups, a kernel for `--input`, a large enough map.
pub fn check(o: &BenchOptions) -> Result<()> {
    if let Some(g) = o.only.iter().find(|g| !GROUPS.contains(&g.as_str())) {
        return Err(BenchError::UnknownGroup { group: g.clone() });
    }
    if let Some(input) = &o.input {
        if !(o.only.len() == 1 && ["cwt", "fft", "roughness", "bem"].contains(&o.only[0].as_str()))
        {
            return Err(BenchError::InputWithoutKernel(input.clone()));
        }
    }
    if o.size < 8 {
        return Err(BenchError::MapTooSmall(o.size));
    }
    Ok(())
}

/// Measure the selected groups in [`GROUPS`] order, handing each figure to `host`; all figures.
pub fn run(o: &BenchOptions, host: &mut dyn BenchHost) -> Result<Vec<Figure>> {
    check(o)?;
    let wanted = |g: &str| -> bool {
        if o.only.is_empty() {
            // The BEM solves and the 10⁸-sample streaming CWT take tens of seconds: only when
            // asked (bench/compare.py).
            g != "bem" && g != "stream" && g != "significance" && (g != "main-job" || o.main_job)
        } else {
            o.only.iter().any(|x| x == g) || (g == "main-job" && o.main_job)
        }
    };
    let n = |default: usize| o.repeat.unwrap_or(default).max(1);
    let mut out = Figures {
        host,
        figures: Vec::new(),
    };
    if wanted("surfaces") {
        kernels::surfaces(&mut out, o.size, n(3))?;
    }
    if wanted("two-dof") || wanted("sweep") {
        slider::two_dof(&mut out, wanted("two-dof"), wanted("sweep"), n(5), n(3))?;
    }
    if wanted("three-dof") {
        slider::three_dof(&mut out, n(3))?;
    }
    if wanted("cwt") {
        let x = match &o.input {
            Some(p) => npy::read_signal(p)?,
            None => kernels::series(1_000_000),
        };
        kernels::cwt(&mut out, &x, n(3))?;
    }
    if wanted("fft") {
        let x = match &o.input {
            Some(p) => npy::read_signal(p)?,
            None => kernels::series(10_000_000),
        };
        kernels::fft(&mut out, &x, n(5))?;
    }
    if wanted("roughness") {
        let map = match &o.input {
            Some(p) => npy::read_map(p, 4e-6)?,
            None => kernels::synthetic_map(o.size),
        };
        kernels::roughness(&mut out, &map, n(5))?;
    }
    if wanted("bem") {
        let map = match &o.input {
            Some(p) => npy::read_map(p, 4e-6)?,
            None => kernels::synthetic_map(o.size),
        };
        kernels::bem(&mut out, &map, n(3))?;
    }
    if wanted("significance") {
        let x = match &o.input {
            Some(p) => npy::read_signal(p)?,
            None => kernels::series(1_000_000),
        };
        kernels::significance(&mut out, &x, n(3))?;
    }
    if wanted("stream") {
        kernels::stream(&mut out, STREAM_SAMPLES, n(1))?;
    }
    if wanted("noop") && o.config.is_file() {
        main_job::noop(&mut out, &o.config, n(4))?;
    }
    if wanted("main-job") {
        main_job::cold(&mut out, &o.config, n(4))?;
    }
    Ok(out.figures)
}

/// The figures so far, each handed to the host as it is measured.
struct Figures<'a> {
    host: &'a mut dyn BenchHost,
    figures: Vec<Figure>,
}

impl Figures<'_> {
    fn push(&mut self, f: Figure) {
        self.host.figure(&f);
        self.figures.push(f);
    }
}

/// Four significant digits, enough for noisy timings.
fn fmt(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:.digits$}")
}

/// Timings of `repeats` runs of `f` after one untimed warm-up (caches, page faults, the rayon
/// pool): (best, median) seconds and the last result.
fn time_best<T>(repeats: usize, mut f: impl FnMut() -> Result<T>) -> Result<((f64, f64), T)> {
    let mut last = f()?;
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        last = f()?;
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let median = if times.len() % 2 == 1 {
        times[times.len() / 2]
    } else {
        0.5 * (times[times.len() / 2 - 1] + times[times.len() / 2])
    };
    Ok(((times[0], median), last))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_significant_digits() {
        assert_eq!(fmt(0.0), "0");
        assert_eq!(fmt(1234.5678), "1235");
        assert_eq!(fmt(1.234567), "1.235");
        assert_eq!(fmt(0.00123456), "0.001235");
    }

    #[test]
    fn best_and_median_of_the_timed_repeats() {
        let mut calls = 0;
        let ((best, median), last) = time_best(4, || {
            calls += 1;
            Ok(calls)
        })
        .unwrap();
        assert_eq!((calls, last), (5, 5));
        assert!(best <= median);
    }
}
