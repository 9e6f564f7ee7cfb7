//! Rounds of independent cases computed elsewhere and awaited: the seam a stage whose driver
//! is sequential (the calibration's Nelder–Mead search and touchdown scan) uses to send the
//! cases of one step to Slurm while the driver stays in the submitting process
//! (docs/slurm.md, "Calibration on Slurm").
//!
//! A round is a list of [`CaseSpec`]s. [`SlurmBatchRunner`] lists those without a verified
//! store entry in a case manifest of their own, submits it as array jobs (the same manifest,
//! worker and outcome files as `hdi run --executor slurm`), waits, and returns every case's
//! `result.json` from the store. A stage without a runner computes its cases in-process.

use super::slurm::{submit_manifest, ScriptOptions, SlurmClient};
use super::{manifest_path, outcome_dir, CaseManifest, CaseSpec, CaseStatus, ExecutorError};
use crate::core::cache::{Store, Verification};
use crate::core::cases::CASE_KIND;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Why a round did not come back: the scheduler, the store, or a case that failed on a node
/// (its error as the worker recorded it). Never a property of the model: a stage treats it
/// as fatal, not as an infeasible point.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    #[error(transparent)]
    Executor(#[from] ExecutorError),
    #[error(
        "case {key} ({kind}) failed on Slurm{at}: {error} (`hdi status` lists it; manifest {})",
        manifest.display()
    )]
    CaseFailed {
        kind: String,
        key: String,
        error: String,
        at: String,
        manifest: PathBuf,
    },
    #[error("case {key}: no verified store entry after its round (manifest {})", manifest.display())]
    Missing { key: String, manifest: PathBuf },
    #[error("case {key}: cannot read its result {}: {message}", path.display())]
    Result {
        key: String,
        path: PathBuf,
        message: String,
    },
}

/// Computes rounds of cases elsewhere (a stage gets one through `StageContext::batch`).
pub trait BatchRunner: Send + Sync + std::fmt::Debug {
    /// Each case of `specs` computed through `cases::get_or_compute` under its key (cases
    /// already in `store` are not recomputed); their results (`result.json` of each entry),
    /// in the order of `specs`.
    fn run_batch(&self, store: &Store, specs: &[CaseSpec]) -> Result<Vec<Value>, BatchError>;
}

/// What a runner did, for the run's log and the timings of docs/slurm.md.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BatchStats {
    /// Rounds asked for, and those that needed a submission (the others were all cached).
    pub rounds: usize,
    pub submitted_rounds: usize,
    /// Cases asked for, and those submitted.
    pub cases: usize,
    pub submitted_cases: usize,
    /// Wall seconds from writing a round's manifest to having its results, summed.
    pub seconds: f64,
}

/// One manifest and one set of arrays per round. It waits on the round's outcome files
/// (checked every 50 ms) and asks `squeue` every `poll` for tasks that ended without
/// reporting: a round of a few flying cases takes about a second, so a detection delay of
/// the poll period (5 s by default) would dominate it (docs/slurm.md).
#[derive(Debug)]
pub struct SlurmBatchRunner {
    pub client: SlurmClient,
    pub script: ScriptOptions,
    /// Absolute path of the pipeline file, added to every recipe as `config` (the workers
    /// rebuild the stage's inputs from it).
    pub config: PathBuf,
    pub cases_per_task: usize,
    pub max_array: usize,
    pub poll: Duration,
    stats: Mutex<BatchStats>,
}

impl SlurmBatchRunner {
    pub fn new(
        client: SlurmClient,
        script: ScriptOptions,
        config: PathBuf,
        cases_per_task: usize,
        max_array: usize,
        poll: Duration,
    ) -> Self {
        SlurmBatchRunner {
            client,
            script,
            config,
            cases_per_task: cases_per_task.max(1),
            max_array: max_array.max(1),
            poll,
            stats: Mutex::new(BatchStats::default()),
        }
    }

    pub fn stats(&self) -> BatchStats {
        self.stats.lock().map(|s| *s).unwrap_or_default()
    }

    fn record(&self, f: impl FnOnce(&mut BatchStats)) {
        if let Ok(mut s) = self.stats.lock() {
            f(&mut s);
        }
    }

    /// Submit the missing cases and wait until every one has reported or its task has left
    /// the queue.
    fn submit_and_wait(&self, store: &Store, missing: Vec<CaseSpec>) -> Result<(), BatchError> {
        let processed = store.processed();
        let specs = missing
            .into_iter()
            .map(|mut s| {
                if let Value::Object(o) = &mut s.recipe {
                    o.insert(
                        "config".into(),
                        Value::String(self.config.display().to_string()),
                    );
                }
                s
            })
            .collect();
        let manifest = CaseManifest::new(specs, self.cases_per_task)?;
        let path = manifest_path(processed, &manifest.id());
        manifest.write(&path)?;
        let records =
            submit_manifest(&self.client, &self.script, &path, &manifest, self.max_array)?;
        // Every case reported (its entry is committed before its outcome is written): done,
        // without waiting for Slurm to notice the tasks ended. The outcome files are checked
        // every 50 ms (a few `stat`s); `squeue`, which only has to catch tasks that end
        // without reporting, every `poll`.
        let tick = Duration::from_millis(50).min(self.poll);
        let mut last_queue = Instant::now();
        let statuses = loop {
            std::thread::sleep(tick);
            if all_reported(&path, manifest.cases.len()) {
                break Vec::new();
            }
            if last_queue.elapsed() >= self.poll {
                last_queue = Instant::now();
                let (total, each) = self.client.status_all(&records)?;
                if total.is_finished() {
                    break each;
                }
            }
        };
        let mut done = CaseManifest::read(&path)?;
        done.merge_outcomes(&path)?;
        for (record, status) in records.iter().zip(&statuses) {
            done.mark_unreported(processed, record, &status.failed);
        }
        done.write(&path)?;
        if let Some((_, e)) = done.failed().next() {
            if let CaseStatus::Failed {
                error,
                job_id,
                task_id,
                log,
            } = &e.status
            {
                let mut at = match (job_id, task_id) {
                    (Some(j), Some(t)) => format!(" (job {j}, task {t}"),
                    _ => String::new(),
                };
                if let Some(l) = log {
                    at.push_str(&format!(
                        "{}log {}",
                        if at.is_empty() { " (" } else { ", " },
                        l.display()
                    ));
                }
                if !at.is_empty() {
                    at.push(')');
                }
                return Err(BatchError::CaseFailed {
                    kind: e.spec.kind.clone(),
                    key: e.spec.key.clone(),
                    error: error.clone(),
                    at,
                    manifest: path,
                });
            }
        }
        Ok(())
    }
}

/// Whether every case of the manifest at `path` has an outcome file.
fn all_reported(path: &Path, n: usize) -> bool {
    let dir = outcome_dir(path);
    (0..n).all(|i| dir.join(format!("{i}.json")).is_file())
}

impl BatchRunner for SlurmBatchRunner {
    fn run_batch(&self, store: &Store, specs: &[CaseSpec]) -> Result<Vec<Value>, BatchError> {
        let started = Instant::now();
        let fresh = |key: &str| matches!(store.verify(CASE_KIND, key), Verification::Fresh(_));
        let missing: Vec<CaseSpec> = specs.iter().filter(|s| !fresh(&s.key)).cloned().collect();
        let submitted = missing.len();
        let mut manifest_dir = PathBuf::new();
        if !missing.is_empty() {
            manifest_dir = super::slurm_dir(store.processed()).join("manifests");
            self.submit_and_wait(store, missing)?;
        }
        let results = specs
            .iter()
            .map(|s| read_case_result(store, s, &manifest_dir))
            .collect::<Result<Vec<_>, _>>()?;
        let seconds = started.elapsed().as_secs_f64();
        self.record(|st| {
            st.rounds += 1;
            st.cases += specs.len();
            if submitted > 0 {
                st.submitted_rounds += 1;
                st.submitted_cases += submitted;
                st.seconds += seconds;
            }
        });
        Ok(results)
    }
}

/// The `result.json` of a case's verified store entry.
pub fn read_case_result(
    store: &Store,
    spec: &CaseSpec,
    manifests: &Path,
) -> Result<Value, BatchError> {
    if !matches!(store.verify(CASE_KIND, &spec.key), Verification::Fresh(_)) {
        return Err(BatchError::Missing {
            key: spec.key.clone(),
            manifest: manifests.to_path_buf(),
        });
    }
    let path = store.entry_dir(CASE_KIND, &spec.key).join("result.json");
    let err = |message: String| BatchError::Result {
        key: spec.key.clone(),
        path: path.clone(),
        message,
    };
    let bytes = std::fs::read(&path).map_err(|e| err(e.to_string()))?;
    serde_json::from_slice(&bytes).map_err(|e| err(e.to_string()))
}
