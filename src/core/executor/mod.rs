//! Where independent cases run: the groundwork for `hdi run --executor slurm` (issue 9,
//! docs/slurm.md). Nothing here is wired into the engine or the stages yet.
//!
//! The unit of work is a [`CaseSpec`]: a case's cache key and canonical parameters (what
//! `core::cases` hashes) plus a *recipe* (what a worker process needs to recompute it). The
//! submitting process writes the stale cases to a [`CaseManifest`]; each Slurm array task runs
//! a contiguous range of them through [`exec_task`], which computes through
//! `cases::get_or_compute` (the same code path and atomic store rules as a local run, hence
//! the same bytes) and reports each case in its own outcome file. Workers never rewrite the
//! shared manifest: concurrent tasks on different nodes would lose each other's updates, so
//! the submitter folds the outcome files back in ([`CaseManifest::merge_outcomes`]).

pub mod batch;
pub mod plan;
pub mod slurm;

use crate::core::cache::{write_atomic, Store, Verification};
use crate::core::cases::{self, CASE_KIND};
use crate::core::hash::hash_json;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use std::path::{Path, PathBuf};

pub use plan::{plan_arrays, task_cases, ArraySubmission};

/// Version of the layout of the case manifest, outcome and submission-record JSON files
/// (`docs/schemas/case-manifest.json`), bumped when it changes so a file of another layout is
/// refused with both versions named rather than misread. Version 1 is the layout of issue 9
/// (outcomes and submission records had no version field then: a missing one reads as 1);
/// version 2 (issue 21) versions all three files and adds `three_dof` cases; version 3 (issue 31)
/// gives every kind one recipe envelope (`stages::case_engine::CaseRecipe`).
pub const MANIFEST_SCHEMA_VERSION: u32 = 3;

#[derive(Debug, thiserror::Error)]
pub enum ExecutorError {
    #[error("unknown executor `{0}` (expected `local` or `slurm`)")]
    UnknownExecutor(String),
    #[error("invalid array plan: {0}")]
    InvalidPlan(String),
    #[error(
        "`{tool}` not found (searched {searched}); is Slurm installed and on PATH on this node?"
    )]
    ToolMissing { tool: String, searched: String },
    #[error("`{tool}` could not be started")]
    ToolSpawn {
        tool: String,
        #[source]
        source: std::io::Error,
    },
    #[error("`{command}` failed ({status}): {stderr}")]
    ToolFailed {
        command: String,
        status: String,
        stderr: String,
    },
    #[error("cannot parse {what} output line {line:?}")]
    Parse { what: &'static str, line: String },
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("case manifest {}: {message}", path.display())]
    Manifest { path: PathBuf, message: String },
    #[error(
        "{}: schema version {found}, but this hdi (v{hdi}) reads schema version {expected} of \
         case manifests, outcomes and submission records (written by another hdi version; \
         `hdi run --executor slurm` with this one writes a new manifest)",
        path.display(),
        hdi = env!("CARGO_PKG_VERSION")
    )]
    SchemaVersion {
        path: PathBuf,
        found: u64,
        expected: u32,
    },
    #[error(
        "unsafe value for #SBATCH {directive}: {value:?} (no whitespace or control characters)"
    )]
    UnsafeDirective { directive: String, value: String },
    #[error("task {task} is outside the manifest ({tasks} tasks of {cases_per_task} cases)")]
    TaskOutOfRange {
        task: usize,
        tasks: usize,
        cases_per_task: usize,
    },
    #[error("case kind `{kind}` has no worker registered (registered: {registered})")]
    UnknownCaseKind { kind: String, registered: String },
}

impl ExecutorError {
    fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        ExecutorError::Io {
            path: path.into(),
            source,
        }
    }
}

pub type ExecResult<T> = std::result::Result<T, ExecutorError>;

/// Which executor runs a stage's independent cases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ExecutorKind {
    /// The rayon pool of this process (the behaviour before issue 9).
    #[default]
    Local,
    /// One `sbatch --array` job per ≤ `max_array` tasks.
    Slurm,
}

impl std::str::FromStr for ExecutorKind {
    type Err = ExecutorError;
    fn from_str(s: &str) -> ExecResult<Self> {
        match s {
            "local" => Ok(ExecutorKind::Local),
            "slurm" => Ok(ExecutorKind::Slurm),
            other => Err(ExecutorError::UnknownExecutor(other.to_string())),
        }
    }
}

/// One independent case as a worker process sees it.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct CaseSpec {
    /// Case kind: the registered worker that recomputes it (simulate, doe, three_dof,
    /// calibration).
    #[schemars(regex(pattern = r"^[a-z][a-z0-9_]*$"))]
    pub kind: String,
    /// Cache key of the case's store entry (BLAKE3 of model_version and params, hex):
    /// `cases::case_fingerprint(model_version, params).key()`. The worker checks it, so a
    /// binary that hashes differently fails loudly instead of filling the cache under keys the
    /// submitter never looks up.
    #[schemars(regex(pattern = r"^[0-9a-f]{64}$"))]
    pub key: String,
    /// Model version of the case kind, hashed into the key (e.g. three-dof-3).
    pub model_version: String,
    /// Canonical case parameters exactly as hashed into the key (the stage's key parameters).
    #[schemars(with = "serde_json::Map<String, Value>")]
    pub params: Value,
    /// What the worker needs besides `params` to recompute the case (the stage's case recipe:
    /// `stages::case_engine::CaseRecipe`): key parameters can be lossy (`model_parameters` is
    /// a Debug string), so they cannot double as the recipe.
    pub recipe: Value,
}

impl CaseSpec {
    /// A spec whose key is computed here, the same way `cases::get_or_compute` does.
    pub fn new(kind: &str, model_version: &str, params: Value, recipe: Value) -> Self {
        let key = cases::case_fingerprint(model_version, &params).key();
        Self {
            kind: kind.to_string(),
            key,
            model_version: model_version.to_string(),
            params,
            recipe,
        }
    }
}

/// Where the case stands; failed carries the error chain and where it ran.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(tag = "state", rename_all = "snake_case")]
pub enum CaseStatus {
    /// Not computed yet.
    Pending,
    /// In the cache.
    Done,
    /// Its worker failed.
    Failed {
        /// The error and its sources.
        error: String,
        /// Slurm array job id (null outside Slurm).
        job_id: Option<u64>,
        /// Slurm array task id (null outside Slurm).
        task_id: Option<u32>,
        /// The task's log file, for `hdi status`.
        log: Option<PathBuf>,
    },
}

/// One case of the manifest: its spec and its status.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct ManifestEntry {
    #[serde(flatten)]
    pub spec: CaseSpec,
    /// Where the case stands.
    pub status: CaseStatus,
}

/// One `sbatch` submission made for a manifest; kept in a small file of its own beside the
/// manifest ([`submissions_path`]) so recording a job id does not rewrite megabytes of cases.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SubmissionRecord {
    pub job_id: u64,
    /// Global index of the array's task 0 (`--offset`).
    pub offset: usize,
    pub tasks: usize,
    pub submitted: String,
}

/// processed/.hdi/slurm/manifests/<created>-<hash12>.json, written by `hdi run --executor
/// slurm` and read by `hdi exec-cases` on the nodes and by `hdi status` (docs/slurm.md). The
/// stale cases of one submission, each with its cache key, the canonical parameters hashed
/// into that key, the recipe a worker recomputes it from, and its status. Schema version 3
/// (issue 31: every kind's recipe is one envelope naming the instance, the upstream entries
/// its preparation read, the kind's own case and the key); a reader refuses any other version
/// naming the file and both versions.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct CaseManifest {
    /// Layout version of manifests, outcome files and submission records
    /// (MANIFEST_SCHEMA_VERSION).
    #[schemars(extend("const" = 3))]
    pub schema_version: u32,
    /// Version of the hdi that wrote the manifest.
    pub hdi_version: String,
    /// Creation time, ISO 8601 UTC (also the start of the file name).
    #[schemars(regex(pattern = r"^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}"))]
    pub created: String,
    /// Fixed when the manifest is written: global array task t runs cases
    /// t*cases_per_task .. (t+1)*cases_per_task (clipped to the case count).
    #[schemars(range(min = 1))]
    pub cases_per_task: usize,
    /// The cases in task order; no two share a key.
    pub cases: Vec<ManifestEntry>,
}

/// What a worker writes for one case: `outcomes/<case index>.json` beside the manifest.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CaseOutcome {
    /// [`MANIFEST_SCHEMA_VERSION`].
    pub schema_version: u32,
    pub index: usize,
    pub key: String,
    pub status: CaseStatus,
}

/// The Slurm identity of a running worker (from `SLURM_ARRAY_JOB_ID`/`SLURM_ARRAY_TASK_ID`),
/// passed in rather than read here so the worker stays testable.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TaskIdentity {
    pub job_id: Option<u64>,
    pub task_id: Option<u32>,
    pub log: Option<PathBuf>,
}

impl TaskIdentity {
    /// From the environment of a Slurm array task; log path as [`slurm::log_path`] names it.
    pub fn from_env(processed: &Path) -> Self {
        let num = |v: &str| {
            std::env::var(v)
                .ok()
                .and_then(|s| s.trim().parse::<u64>().ok())
        };
        let job_id = num("SLURM_ARRAY_JOB_ID");
        let task_id = num("SLURM_ARRAY_TASK_ID").and_then(|t| u32::try_from(t).ok());
        let log = match (job_id, task_id) {
            (Some(j), Some(t)) => Some(slurm::log_path(processed, j, t)),
            _ => None,
        };
        Self {
            job_id,
            task_id,
            log,
        }
    }
}

impl CaseManifest {
    /// A manifest of `specs`, all pending; duplicate keys are dropped (two tasks must never
    /// race to commit the same store entry).
    pub fn new(specs: Vec<CaseSpec>, cases_per_task: usize) -> ExecResult<Self> {
        if cases_per_task == 0 {
            return Err(ExecutorError::InvalidPlan(
                "cases per task must be at least 1".into(),
            ));
        }
        let mut seen = BTreeSet::new();
        let cases = specs
            .into_iter()
            .filter(|s| seen.insert(s.key.clone()))
            .map(|spec| ManifestEntry {
                spec,
                status: CaseStatus::Pending,
            })
            .collect();
        Ok(Self {
            schema_version: MANIFEST_SCHEMA_VERSION,
            hdi_version: env!("CARGO_PKG_VERSION").to_string(),
            created: crate::core::cache::now_iso8601(),
            cases_per_task,
            cases,
        })
    }

    /// Number of array tasks covering all cases.
    pub fn task_count(&self) -> usize {
        self.cases.len().div_ceil(self.cases_per_task)
    }

    /// The cases global task `task` runs.
    pub fn task_range(&self, task: usize) -> ExecResult<Range<usize>> {
        let tasks = self.task_count();
        if task >= tasks {
            return Err(ExecutorError::TaskOutOfRange {
                task,
                tasks,
                cases_per_task: self.cases_per_task,
            });
        }
        Ok(task_cases(self.cases.len(), self.cases_per_task, task))
    }

    /// A name unique to this set of cases and creation time, for [`manifest_path`].
    pub fn id(&self) -> String {
        let keys: Vec<&str> = self.cases.iter().map(|c| c.spec.key.as_str()).collect();
        let digest = hash_json(&serde_json::json!({"created": self.created, "keys": keys}));
        let stamp: String = self
            .created
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .collect();
        format!("{stamp}-{}", &digest[..12])
    }

    /// Write atomically (temp file, fsync, rename): a reader sees the old or the new manifest.
    pub fn write(&self, path: &Path) -> ExecResult<()> {
        let bytes = serde_json::to_vec(self).map_err(|e| ExecutorError::Manifest {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        write_atomic(path, &bytes).map_err(|e| ExecutorError::io(path, e))
    }

    pub fn read(path: &Path) -> ExecResult<Self> {
        let bytes = std::fs::read(path).map_err(|e| ExecutorError::io(path, e))?;
        Self::from_json_slice(&bytes, path)
    }

    /// Parse a manifest from its JSON bytes; `path` only names the file in errors. The one
    /// parser of manifests (what [`Self::read`], `hdi exec-cases` and `hdi status` use, and
    /// what the fuzz target exercises): the schema version is checked first, so a manifest
    /// of another layout is refused naming both versions rather than failing on a field, and
    /// a manifest whose `cases_per_task` is 0 is refused (it would divide by zero).
    pub fn from_json_slice(bytes: &[u8], path: &Path) -> ExecResult<Self> {
        check_schema_version(bytes, path)?;
        let manifest: Self =
            serde_json::from_slice(bytes).map_err(|e| ExecutorError::Manifest {
                path: path.to_path_buf(),
                message: e.to_string(),
            })?;
        if manifest.cases_per_task == 0 {
            return Err(ExecutorError::Manifest {
                path: path.to_path_buf(),
                message: "cases_per_task is 0".into(),
            });
        }
        Ok(manifest)
    }

    /// Fold the workers' outcome files into the entries' statuses. Returns how many changed.
    /// Outcomes whose key does not match the entry at that index are ignored (stale files).
    pub fn merge_outcomes(&mut self, manifest_path: &Path) -> ExecResult<usize> {
        let dir = outcome_dir(manifest_path);
        let listing = match std::fs::read_dir(&dir) {
            Ok(l) => l,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(0),
            Err(e) => return Err(ExecutorError::io(&dir, e)),
        };
        let mut changed = 0;
        for item in listing {
            let path = item.map_err(|e| ExecutorError::io(&dir, e))?.path();
            if path.extension().and_then(|e| e.to_str()) != Some("json") {
                continue; // half-written temp files start with a dot and end in .tmp-PID
            }
            let bytes = std::fs::read(&path).map_err(|e| ExecutorError::io(&path, e))?;
            check_schema_version(&bytes, &path)?;
            let outcome: CaseOutcome =
                serde_json::from_slice(&bytes).map_err(|e| ExecutorError::Manifest {
                    path: path.clone(),
                    message: e.to_string(),
                })?;
            if let Some(entry) = self.cases.get_mut(outcome.index) {
                if entry.spec.key == outcome.key && entry.status != outcome.status {
                    entry.status = outcome.status;
                    changed += 1;
                }
            }
        }
        Ok(changed)
    }

    /// Cases of tasks that Slurm reports as failed but that never wrote an outcome (killed
    /// by TIMEOUT, OOM, NODE_FAIL before reporting): still `Pending`, they become `Failed`
    /// with the Slurm state, so `hdi status` can point at the log. Call after
    /// [`Self::merge_outcomes`]. Returns how many changed.
    pub fn mark_unreported(
        &mut self,
        processed: &Path,
        submission: &SubmissionRecord,
        failed: &[slurm::FailedTask],
    ) -> usize {
        let mut changed = 0;
        for f in failed {
            let global = submission.offset + f.task_id as usize;
            if f.task_id as usize >= submission.tasks || global >= self.task_count() {
                continue;
            }
            for index in task_cases(self.cases.len(), self.cases_per_task, global) {
                let entry = &mut self.cases[index];
                if entry.status == CaseStatus::Pending {
                    entry.status = CaseStatus::Failed {
                        error: format!(
                            "task ended {} (exit {}) without reporting this case",
                            f.state, f.exit_code
                        ),
                        job_id: Some(submission.job_id),
                        task_id: Some(f.task_id),
                        log: Some(slurm::log_path(processed, submission.job_id, f.task_id)),
                    };
                    changed += 1;
                }
            }
        }
        changed
    }

    /// Entries that failed, with their index.
    pub fn failed(&self) -> impl Iterator<Item = (usize, &ManifestEntry)> {
        self.cases
            .iter()
            .enumerate()
            .filter(|(_, e)| matches!(e.status, CaseStatus::Failed { .. }))
    }

    /// Counts of (pending, done, failed).
    pub fn counts(&self) -> (usize, usize, usize) {
        let mut c = (0, 0, 0);
        for e in &self.cases {
            match e.status {
                CaseStatus::Pending => c.0 += 1,
                CaseStatus::Done => c.1 += 1,
                CaseStatus::Failed { .. } => c.2 += 1,
            }
        }
        c
    }

    /// Cases without a verified store entry: what a resubmission must run (failed ones and
    /// those a killed task never reached). The store, not the status, is the truth here.
    pub fn still_missing(&self, store: &Store) -> Vec<CaseSpec> {
        self.cases
            .iter()
            .filter(|e| !matches!(store.verify(CASE_KIND, &e.spec.key), Verification::Fresh(_)))
            .map(|e| e.spec.clone())
            .collect()
    }
}

/// `processed/.hdi/slurm/`: manifests, their outcome files, sbatch scripts and task logs.
pub fn slurm_dir(processed: &Path) -> PathBuf {
    processed.join(".hdi").join("slurm")
}

/// Where a manifest with this id lives.
pub fn manifest_path(processed: &Path, id: &str) -> PathBuf {
    slurm_dir(processed)
        .join("manifests")
        .join(format!("{id}.json"))
}

/// The submission records of a manifest: `<manifest stem>.jobs.json` beside it.
pub fn submissions_path(manifest_path: &Path) -> PathBuf {
    let stem = manifest_path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    manifest_path.with_file_name(format!("{stem}.jobs.json"))
}

/// The `.jobs.json` file: the submission records with their schema version.
#[derive(Serialize, Deserialize)]
struct SubmissionLog {
    schema_version: u32,
    submissions: Vec<SubmissionRecord>,
}

/// The arrays submitted for a manifest so far (none if the file does not exist).
pub fn read_submissions(manifest_path: &Path) -> ExecResult<Vec<SubmissionRecord>> {
    let path = submissions_path(manifest_path);
    match std::fs::read(&path) {
        Ok(bytes) => {
            check_schema_version(&bytes, &path)?;
            serde_json::from_slice::<SubmissionLog>(&bytes)
                .map(|log| log.submissions)
                .map_err(|e| ExecutorError::Manifest {
                    path,
                    message: e.to_string(),
                })
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(ExecutorError::io(path, e)),
    }
}

/// Refuse a manifest, outcome or submission-record file of another schema version, before
/// its fields are read. A file without `schema_version` (or a bare array: the submission
/// records of version 1) is version 1.
fn check_schema_version(bytes: &[u8], path: &Path) -> ExecResult<()> {
    #[derive(Deserialize)]
    struct Versioned {
        schema_version: Option<serde_json::Number>,
    }
    let first = bytes.iter().find(|b| !b.is_ascii_whitespace());
    let found = if first == Some(&b'[') {
        Some(1)
    } else {
        match serde_json::from_slice::<Versioned>(bytes) {
            // Not an object, or not JSON: the full parse names what is wrong.
            Err(_) => None,
            Ok(Versioned {
                schema_version: None,
            }) => Some(1),
            // Anything but the expected integer (2.5, -1, 2^70) is "another version" too.
            Ok(Versioned {
                schema_version: Some(n),
            }) => match n.as_u64() {
                Some(v) if v == u64::from(MANIFEST_SCHEMA_VERSION) => None,
                Some(v) => Some(v),
                None => {
                    return Err(ExecutorError::Manifest {
                        path: path.to_path_buf(),
                        message: format!(
                            "schema_version {n} is not a version number (this hdi reads \
                             schema version {MANIFEST_SCHEMA_VERSION})"
                        ),
                    })
                }
            },
        }
    };
    match found {
        Some(found) => Err(ExecutorError::SchemaVersion {
            path: path.to_path_buf(),
            found,
            expected: MANIFEST_SCHEMA_VERSION,
        }),
        None => Ok(()),
    }
}

fn write_submissions(manifest_path: &Path, records: &[SubmissionRecord]) -> ExecResult<()> {
    let path = submissions_path(manifest_path);
    let log = SubmissionLog {
        schema_version: MANIFEST_SCHEMA_VERSION,
        submissions: records.to_vec(),
    };
    let bytes = serde_json::to_vec_pretty(&log).map_err(|e| ExecutorError::Manifest {
        path: path.clone(),
        message: e.to_string(),
    })?;
    write_atomic(&path, &bytes).map_err(|e| ExecutorError::io(path, e))
}

/// All case manifests, oldest first (their names start with the creation time): what
/// `hdi status` lists failed cases from.
pub fn list_manifests(processed: &Path) -> ExecResult<Vec<PathBuf>> {
    let dir = slurm_dir(processed).join("manifests");
    let listing = match std::fs::read_dir(&dir) {
        Ok(l) => l,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(ExecutorError::io(&dir, e)),
    };
    let mut paths = Vec::new();
    for item in listing {
        let path = item.map_err(|e| ExecutorError::io(&dir, e))?.path();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let is_manifest = path.is_file()
            && name.ends_with(".json")
            && !name.ends_with(".jobs.json")
            && !name.starts_with('.');
        if is_manifest {
            paths.push(path);
        }
    }
    paths.sort();
    Ok(paths)
}

/// The outcome files of a manifest: `<manifest stem>.outcomes/` beside it.
pub fn outcome_dir(manifest_path: &Path) -> PathBuf {
    let stem = manifest_path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    manifest_path.with_file_name(format!("{stem}.outcomes"))
}

/// Recomputes one kind of case in a worker process from its recipe, writing its files into
/// `dir` and returning its result (as the stage's own closure does under `get_or_compute`).
pub trait CaseComputer: Send + Sync {
    fn compute(&self, recipe: &Value, store: &Store, dir: &Path) -> Result<Value, CaseFailure>;
}

/// Why a worker could not compute a case: any error of the layer that registered it (the core
/// names no stage, so not the crate's error type); recorded in the outcome with its sources.
pub type CaseFailure = Box<dyn std::error::Error + Send + Sync>;

impl<F, E> CaseComputer for F
where
    F: Fn(&Value, &Store, &Path) -> Result<Value, E> + Send + Sync,
    E: Into<CaseFailure>,
{
    fn compute(&self, recipe: &Value, store: &Store, dir: &Path) -> Result<Value, CaseFailure> {
        self(recipe, store, dir).map_err(Into::into)
    }
}

/// Case kind → worker. `hdi exec-cases` dispatches on [`CaseSpec::kind`] through this; the
/// stages fill it (the core names no case kind).
#[derive(Default)]
pub struct CaseRegistry {
    computers: BTreeMap<String, Box<dyn CaseComputer>>,
}

impl CaseRegistry {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn register(&mut self, kind: &str, computer: impl CaseComputer + 'static) {
        self.computers.insert(kind.to_string(), Box::new(computer));
    }

    pub fn kinds(&self) -> Vec<&str> {
        self.computers.keys().map(String::as_str).collect()
    }

    /// Compute one case of `kind`; a kind without a worker is an error naming what is missing.
    pub fn compute_case(
        &self,
        kind: &str,
        recipe: &Value,
        store: &Store,
        dir: &Path,
    ) -> Result<Value, CaseFailure> {
        match self.computers.get(kind) {
            Some(c) => c.compute(recipe, store, dir),
            None => Err(self.unknown(kind).into()),
        }
    }

    fn unknown(&self, kind: &str) -> ExecutorError {
        let registered = self.kinds();
        ExecutorError::UnknownCaseKind {
            kind: kind.to_string(),
            registered: if registered.is_empty() {
                "none".to_string()
            } else {
                registered.join(", ")
            },
        }
    }
}

/// What one worker task did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TaskReport {
    pub computed: usize,
    pub cached: usize,
    pub failed: usize,
}

/// The body of `hdi exec-cases MANIFEST --task T --offset X`: run global task `task` (the
/// array task id plus the array's offset) — each case through `cases::get_or_compute`, in
/// parallel on this process's rayon pool — and write one outcome file per case. A failing
/// case is recorded, not fatal, so its siblings still finish; the caller exits non-zero when
/// `failed > 0` so `sacct` shows the task FAILED.
pub fn exec_task(
    store: &Store,
    manifest_path: &Path,
    task: usize,
    registry: &CaseRegistry,
    identity: &TaskIdentity,
) -> ExecResult<TaskReport> {
    use rayon::prelude::*;
    let manifest = CaseManifest::read(manifest_path)?;
    let range = manifest.task_range(task)?;
    let out_dir = outcome_dir(manifest_path);
    std::fs::create_dir_all(&out_dir).map_err(|e| ExecutorError::io(&out_dir, e))?;
    let results: Vec<ExecResult<Option<bool>>> = range
        .into_par_iter()
        .map(|index| {
            let spec = &manifest.cases[index].spec;
            let computed = cases::get_or_compute(store, &spec.model_version, &spec.params, |d| {
                registry.compute_case(&spec.kind, &spec.recipe, store, d)
            });
            let (status, cached) = match computed {
                Ok(entry) if entry.key == spec.key => (CaseStatus::Done, Some(entry.cached)),
                Ok(entry) => (
                    failed_status(
                        format!(
                            "key mismatch: manifest says {}, this hdi computes {} \
                             (different hdi version on the nodes?)",
                            spec.key, entry.key
                        ),
                        identity,
                    ),
                    None,
                ),
                Err(e) => (failed_status(crate::core::chain(&*e), identity), None),
            };
            let outcome = CaseOutcome {
                schema_version: MANIFEST_SCHEMA_VERSION,
                index,
                key: spec.key.clone(),
                status,
            };
            let path = out_dir.join(format!("{index}.json"));
            let bytes = serde_json::to_vec(&outcome).map_err(|e| ExecutorError::Manifest {
                path: path.clone(),
                message: e.to_string(),
            })?;
            write_atomic(&path, &bytes).map_err(|e| ExecutorError::io(&path, e))?;
            Ok(cached)
        })
        .collect();
    let mut report = TaskReport::default();
    for r in results {
        match r? {
            Some(true) => report.cached += 1,
            Some(false) => report.computed += 1,
            None => report.failed += 1,
        }
    }
    Ok(report)
}

fn failed_status(error: String, identity: &TaskIdentity) -> CaseStatus {
    CaseStatus::Failed {
        error,
        job_id: identity.job_id,
        task_id: identity.task_id,
        log: identity.log.clone(),
    }
}

#[cfg(test)]
mod tests;
