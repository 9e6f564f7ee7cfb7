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

use serde::Serialize;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Sample rate the signal kernels assume (also for `--input`): the LDV records' 4 MS/s.
const FS: f64 = 4e6;

/// The figure groups, in the order they run; `--only` takes these names.
pub const GROUPS: [&str; 9] = [
    "surfaces",
    "two-dof",
    "sweep",
    "three-dof",
    "cwt",
    "fft",
    "roughness",
    "noop",
    "main-job",
];

/// Why a measurement could not be taken; the messages name the option or file at fault.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error("--only: unknown group `{group}` (groups: {})", GROUPS.join(", "))]
    UnknownGroup { group: String },
    #[error(
        "--input {}: give exactly one of --only cwt, --only fft, --only roughness \
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
#[derive(Debug, Clone, Serialize)]
pub struct Figure {
    pub group: &'static str,
    pub name: String,
    pub label: String,
    pub value: f64,
    pub unit: &'static str,
    /// "best" (of `repeats`, after a warm-up) or "single" (one cold run).
    pub statistic: &'static str,
    pub repeats: usize,
    pub median: Option<f64>,
    /// The counts behind the figure (steps, RHS evaluations, ms per case, …).
    pub details: Map<String, Value>,
}

impl Figure {
    /// A best-of-`repeats` figure with its median.
    fn best(
        group: &'static str,
        name: impl Into<String>,
        label: impl Into<String>,
        (value, median): (f64, f64),
        unit: &'static str,
        repeats: usize,
        details: Map<String, Value>,
    ) -> Self {
        Figure {
            group,
            name: name.into(),
            label: label.into(),
            value,
            unit,
            statistic: "best",
            repeats,
            median: Some(median),
            details,
        }
    }

    /// The printed line: label, value, unit, statistic and the numeric details.
    pub fn table_line(&self) -> String {
        let stat = match (self.statistic, self.median) {
            ("best", Some(m)) => format!("best of {} (median {})", self.repeats, fmt(m)),
            ("best", None) => format!("best of {}", self.repeats),
            _ => "single run".to_string(),
        };
        let counts: Vec<String> = self
            .details
            .iter()
            .filter_map(|(k, v)| match v {
                Value::Number(x) if x.is_f64() => Some(format!("{k} {}", fmt(x.as_f64()?))),
                Value::Number(x) => Some(format!("{k} {x}")),
                _ => None,
            })
            .collect();
        let counts = if counts.is_empty() {
            String::new()
        } else {
            format!("; {}", counts.join(", "))
        };
        format!(
            "{:<62} {:>10} {:<8} {stat}{counts}",
            self.label,
            fmt(self.value),
            self.unit
        )
    }
}

/// `hdi bench --json` (docs/schemas/bench.json).
#[derive(Debug, Serialize)]
pub struct BenchDocument {
    pub hdi_version: &'static str,
    pub threads: usize,
    pub input: Option<String>,
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
        if !(o.only.len() == 1 && ["cwt", "fft", "roughness"].contains(&o.only[0].as_str())) {
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
            g != "main-job" || o.main_job
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

fn details(pairs: &[(&str, Value)]) -> Map<String, Value> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect()
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
