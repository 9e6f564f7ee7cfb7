//! Talking to Slurm through its command-line tools: the array job script, `sbatch --parsable`,
//! and polling with `squeue` (live tasks) and `sacct` (how finished tasks ended).
//!
//! `squeue` is the progress source because `sacct` needs accounting storage, which small or
//! single-node installations often leave off (`AccountingStorageType=accounting_storage/none`,
//! docs/slurm.md); `sacct` only adds *why* a task failed when it is available. Whether a
//! case succeeded is decided by the store and the workers' outcome files, never by Slurm.

use super::plan::{plan_arrays, ArraySubmission};
use super::{
    read_submissions, slurm_dir, write_submissions, CaseManifest, ExecResult, ExecutorError,
    SubmissionRecord,
};
use crate::core::cache::{now_iso8601, write_atomic};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// A task's log file as the script's `--output=%A_%a.log` pattern names it.
pub fn log_path(processed: &Path, job_id: u64, task_id: u32) -> PathBuf {
    slurm_dir(processed).join(format!("{job_id}_{task_id}.log"))
}

/// What the job script needs besides the manifest and the array.
#[derive(Debug, Clone, PartialEq)]
pub struct ScriptOptions {
    /// The `hdi` binary the tasks run (the submitting binary, so both hash alike).
    pub hdi: PathBuf,
    /// Project directory the tasks start in (`--chdir`), so relative paths resolve alike.
    pub workdir: PathBuf,
    /// `processed/`: task logs go to `processed/.hdi/slurm/%A_%a.log`.
    pub processed: PathBuf,
    pub job_name: String,
    pub partition: Option<String>,
    /// At most this many tasks running at once (`--array=…%N`).
    pub max_running: Option<usize>,
    /// Further `#SBATCH` directives, e.g. `--time=00:30:00`, `--cpus-per-task=2`.
    pub extra_directives: Vec<String>,
}

/// The batch script of one array: `#SBATCH` header, then one `hdi exec-cases` line whose
/// `--offset` turns the array-local task id into the manifest's global task index.
pub fn sbatch_script(
    opts: &ScriptOptions,
    manifest: &Path,
    array: &ArraySubmission,
) -> ExecResult<String> {
    if array.tasks == 0 {
        return Err(ExecutorError::InvalidPlan(
            "an array needs at least one task".into(),
        ));
    }
    let mut array_spec = format!("0-{}", array.tasks - 1);
    if let Some(n) = opts.max_running {
        array_spec.push_str(&format!("%{n}"));
    }
    let log = slurm_dir(&opts.processed).join("%A_%a.log");
    let mut directives = vec![
        ("job-name".to_string(), opts.job_name.clone()),
        ("array".to_string(), array_spec),
        ("output".to_string(), log.display().to_string()),
        ("chdir".to_string(), opts.workdir.display().to_string()),
    ];
    if let Some(p) = &opts.partition {
        directives.push(("partition".to_string(), p.clone()));
    }
    let mut script = String::from("#!/bin/sh\n");
    // `#SBATCH` lines are not shell-parsed: a space would silently cut the value short.
    for (name, value) in &directives {
        check_directive(name, value)?;
        script.push_str(&format!("#SBATCH --{name}={value}\n"));
    }
    for extra in &opts.extra_directives {
        check_directive("(extra)", extra)?;
        script.push_str(&format!("#SBATCH {extra}\n"));
    }
    script.push_str("set -eu\n");
    script.push_str(&format!(
        "exec {} exec-cases {} --task \"$SLURM_ARRAY_TASK_ID\" --offset {}\n",
        shell_quote(&opts.hdi.display().to_string()),
        shell_quote(&manifest.display().to_string()),
        array.offset
    ));
    Ok(script)
}

fn check_directive(name: &str, value: &str) -> ExecResult<()> {
    if value.is_empty() || value.chars().any(|c| c.is_whitespace() || c.is_control()) {
        return Err(ExecutorError::UnsafeDirective {
            directive: name.to_string(),
            value: value.to_string(),
        });
    }
    Ok(())
}

/// Single-quoted for `sh`: `'` becomes `'\''`.
fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The job id from `sbatch --parsable`: `123` or `123;cluster`.
pub fn parse_sbatch_parsable(out: &str) -> ExecResult<u64> {
    let line = out
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("");
    line.split(';')
        .next()
        .and_then(|id| id.trim().parse().ok())
        .ok_or_else(|| ExecutorError::Parse {
            what: "sbatch --parsable",
            line: out.trim().to_string(),
        })
}

/// Slurm job states (`squeue %T`, `sacct State`), the ones that matter here by name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum JobState {
    Pending,
    Running,
    Completing,
    Completed,
    Failed,
    Cancelled,
    Timeout,
    OutOfMemory,
    NodeFail,
    Preempted,
    Other(String),
}

impl JobState {
    pub fn parse(s: &str) -> Self {
        // sacct prints `CANCELLED by 1000`; the first word is the state.
        match s.split_whitespace().next().unwrap_or("") {
            "PENDING" | "PD" => JobState::Pending,
            "RUNNING" | "R" | "CONFIGURING" | "CF" | "SUSPENDED" | "S" | "REQUEUED" => {
                JobState::Running
            }
            "COMPLETING" | "CG" => JobState::Completing,
            "COMPLETED" | "CD" => JobState::Completed,
            "FAILED" | "F" => JobState::Failed,
            "CANCELLED" | "CA" => JobState::Cancelled,
            "TIMEOUT" | "TO" => JobState::Timeout,
            "OUT_OF_MEMORY" | "OOM" => JobState::OutOfMemory,
            "NODE_FAIL" | "NF" => JobState::NodeFail,
            "PREEMPTED" | "PR" => JobState::Preempted,
            other => JobState::Other(other.to_string()),
        }
    }

    /// Finished without success.
    pub fn is_failure(&self) -> bool {
        matches!(
            self,
            JobState::Failed
                | JobState::Cancelled
                | JobState::Timeout
                | JobState::OutOfMemory
                | JobState::NodeFail
                | JobState::Preempted
        )
    }
}

impl std::fmt::Display for JobState {
    /// Slurm's own name, as `sacct` prints it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = match self {
            JobState::Pending => "PENDING",
            JobState::Running => "RUNNING",
            JobState::Completing => "COMPLETING",
            JobState::Completed => "COMPLETED",
            JobState::Failed => "FAILED",
            JobState::Cancelled => "CANCELLED",
            JobState::Timeout => "TIMEOUT",
            JobState::OutOfMemory => "OUT_OF_MEMORY",
            JobState::NodeFail => "NODE_FAIL",
            JobState::Preempted => "PREEMPTED",
            JobState::Other(s) => s,
        };
        f.write_str(name)
    }
}

/// Which tasks of an array a line speaks for: `123` (the whole job), `123_4`, `123_[5-9]`,
/// `123_[1,3,5-7%2]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ArrayTasks {
    pub job_id: u64,
    /// Inclusive task-id ranges; `None` for a line about the job as a whole.
    pub tasks: Option<Vec<(u32, u32)>>,
}

impl ArrayTasks {
    pub fn parse(id: &str) -> Option<Self> {
        let id = id.trim();
        let Some((job, tasks)) = id.split_once('_') else {
            return Some(Self {
                job_id: id.parse().ok()?,
                tasks: None,
            });
        };
        let job_id = job.parse().ok()?;
        let list = match tasks.strip_prefix('[') {
            Some(rest) => rest.strip_suffix(']')?,
            None => tasks,
        };
        // `%N` is the concurrency limit of a pending array, not a task.
        let list = list.split('%').next().unwrap_or("");
        let mut ranges = Vec::new();
        for part in list.split(',') {
            let range = match part.split_once('-') {
                Some((a, b)) => (a.trim().parse().ok()?, b.trim().parse().ok()?),
                None => {
                    let t = part.trim().parse().ok()?;
                    (t, t)
                }
            };
            if range.0 > range.1 {
                return None;
            }
            ranges.push(range);
        }
        Some(Self {
            job_id,
            tasks: Some(ranges),
        })
    }

    /// How many tasks, given the array's size for whole-job lines.
    pub fn count(&self, array_tasks: usize) -> usize {
        match &self.tasks {
            None => array_tasks,
            Some(r) => r.iter().map(|(a, b)| (b - a) as usize + 1).sum(),
        }
    }

    /// The task ids, given the array's size for whole-job lines.
    pub fn ids(&self, array_tasks: usize) -> Vec<u32> {
        match &self.tasks {
            None => (0..array_tasks as u32).collect(),
            Some(r) => r.iter().flat_map(|&(a, b)| a..=b).collect(),
        }
    }
}

/// One line of `squeue -h -j ID -o '%i %T'`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct QueueLine {
    pub tasks: ArrayTasks,
    pub state: JobState,
}

pub fn parse_squeue(out: &str) -> ExecResult<Vec<QueueLine>> {
    let mut lines = Vec::new();
    for line in out.lines().map(str::trim).filter(|l| !l.is_empty()) {
        let bad = || ExecutorError::Parse {
            what: "squeue",
            line: line.to_string(),
        };
        let (id, state) = line.split_once(char::is_whitespace).ok_or_else(bad)?;
        lines.push(QueueLine {
            tasks: ArrayTasks::parse(id).ok_or_else(bad)?,
            state: JobState::parse(state.trim()),
        });
    }
    Ok(lines)
}

/// One line of `sacct -n -P -j ID -o JobID,State,ExitCode` (job steps such as `123_4.batch`
/// are skipped: the task line carries the outcome).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AccountingLine {
    pub tasks: ArrayTasks,
    pub state: JobState,
    /// `exit:signal`, e.g. `1:0`.
    pub exit_code: String,
}

pub fn parse_sacct(out: &str) -> ExecResult<Vec<AccountingLine>> {
    let mut lines = Vec::new();
    for line in out.lines().map(str::trim).filter(|l| !l.is_empty()) {
        let bad = || ExecutorError::Parse {
            what: "sacct",
            line: line.to_string(),
        };
        let fields: Vec<&str> = line.split('|').collect();
        let [id, state, exit_code] = fields[..] else {
            return Err(bad());
        };
        if id.contains('.') {
            continue;
        }
        lines.push(AccountingLine {
            tasks: ArrayTasks::parse(id).ok_or_else(bad)?,
            state: JobState::parse(state),
            exit_code: exit_code.trim().to_string(),
        });
    }
    Ok(lines)
}

/// A task that finished badly, as `sacct` reports it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FailedTask {
    pub task_id: u32,
    pub state: JobState,
    pub exit_code: String,
}

/// One poll of an array job.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ArrayStatus {
    pub job_id: u64,
    pub tasks: usize,
    pub pending: usize,
    pub running: usize,
    /// Tasks no longer in the queue.
    pub finished: usize,
    /// Filled once the array has finished, if `sacct` works on this cluster.
    pub failed: Vec<FailedTask>,
    /// `false` when `sacct` was unavailable (accounting off): `failed` is then unknown and
    /// the outcome files are the only record.
    pub accounting: bool,
}

impl ArrayStatus {
    /// From `squeue` lines: whatever is not queued has finished. Lines of other jobs are
    /// ignored; pending ranges count as many tasks as they span.
    pub fn from_queue(job_id: u64, tasks: usize, queue: &[QueueLine]) -> Self {
        let (mut pending, mut running) = (0, 0);
        for line in queue.iter().filter(|l| l.tasks.job_id == job_id) {
            let n = line.tasks.count(tasks);
            match line.state {
                JobState::Pending => pending += n,
                _ => running += n,
            }
        }
        // Clamped: a line about the whole job would otherwise double-count its tasks.
        let pending = pending.min(tasks);
        let running = running.min(tasks - pending);
        Self {
            job_id,
            tasks,
            pending,
            running,
            finished: tasks - pending - running,
            failed: Vec::new(),
            accounting: false,
        }
    }

    pub fn is_finished(&self) -> bool {
        self.finished >= self.tasks
    }
}

/// Failed tasks of `job_id` from `sacct` lines.
pub fn failed_tasks(job_id: u64, tasks: usize, acct: &[AccountingLine]) -> Vec<FailedTask> {
    let mut failed: Vec<FailedTask> = acct
        .iter()
        .filter(|l| l.tasks.job_id == job_id && l.state.is_failure())
        .flat_map(|l| {
            l.tasks.ids(tasks).into_iter().map(|task_id| FailedTask {
                task_id,
                state: l.state.clone(),
                exit_code: l.exit_code.clone(),
            })
        })
        .collect();
    failed.sort_by_key(|f| f.task_id);
    failed.dedup_by_key(|f| f.task_id);
    failed
}

/// The script file of the array starting at global task `offset` of a manifest.
pub fn script_path(manifest_path: &Path, offset: usize) -> PathBuf {
    let stem = manifest_path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    manifest_path.with_file_name(format!("{stem}.task{offset}.sh"))
}

/// Submit the arrays of a manifest (planned with its `cases_per_task` and `max_array`): one
/// script per array beside the manifest, `sbatch`, and the job id appended to the manifest's
/// submission records after every submission, so a refusal half-way (a per-user job limit)
/// still leaves a record of what is queued. Arrays already recorded (same offset and size)
/// are not submitted again. Returns the records of this call's submissions.
pub fn submit_manifest(
    client: &SlurmClient,
    opts: &ScriptOptions,
    manifest_path: &Path,
    manifest: &CaseManifest,
    max_array: usize,
) -> ExecResult<Vec<SubmissionRecord>> {
    let arrays = plan_arrays(manifest.cases.len(), manifest.cases_per_task, max_array)?;
    let mut records = read_submissions(manifest_path)?;
    // Slurm does not create the `--output` directory: a missing one fails every task unlogged.
    let logs = slurm_dir(&opts.processed);
    std::fs::create_dir_all(&logs).map_err(|e| ExecutorError::io(&logs, e))?;
    let mut submitted = Vec::new();
    for array in &arrays {
        let already = records
            .iter()
            .any(|s| s.offset == array.offset && s.tasks == array.tasks);
        if already {
            continue;
        }
        let script = sbatch_script(opts, manifest_path, array)?;
        let path = script_path(manifest_path, array.offset);
        write_atomic(&path, script.as_bytes()).map_err(|e| ExecutorError::io(&path, e))?;
        let job_id = client.submit(&path)?;
        let record = SubmissionRecord {
            job_id,
            offset: array.offset,
            tasks: array.tasks,
            submitted: now_iso8601(),
        };
        records.push(record.clone());
        write_submissions(manifest_path, &records)?;
        submitted.push(record);
    }
    Ok(submitted)
}

/// Runs `sbatch`, `squeue` and `sacct`: from PATH, or from one directory (tests, or a site
/// where Slurm lives off PATH).
#[derive(Debug, Clone, Default)]
pub struct SlurmClient {
    bin_dir: Option<PathBuf>,
}

impl SlurmClient {
    /// Tools looked up on PATH.
    pub fn from_path() -> Self {
        Self { bin_dir: None }
    }

    /// Tools looked up in `dir` only.
    pub fn with_bin_dir(dir: impl Into<PathBuf>) -> Self {
        Self {
            bin_dir: Some(dir.into()),
        }
    }

    /// The executable for `tool`, or an error saying where it was looked for.
    pub fn locate(&self, tool: &str) -> ExecResult<PathBuf> {
        let dirs: Vec<PathBuf> = match &self.bin_dir {
            Some(d) => vec![d.clone()],
            None => std::env::var_os("PATH")
                .map(|p| std::env::split_paths(&p).collect())
                .unwrap_or_default(),
        };
        dirs.iter()
            .map(|d| d.join(tool))
            .find(|p| is_executable(p))
            .ok_or_else(|| ExecutorError::ToolMissing {
                tool: tool.to_string(),
                searched: match &self.bin_dir {
                    Some(d) => d.display().to_string(),
                    None => "PATH".to_string(),
                },
            })
    }

    /// Submit a script file: the job id.
    pub fn submit(&self, script: &Path) -> ExecResult<u64> {
        let out = self.run("sbatch", &["--parsable".as_ref(), script.as_os_str()])?;
        parse_sbatch_parsable(&out)
    }

    /// Queued and running tasks of `job_id`. A job already purged from the controller makes
    /// `squeue` fail with "Invalid job id": that means nothing is queued.
    pub fn queue(&self, job_id: u64) -> ExecResult<Vec<QueueLine>> {
        let id = job_id.to_string();
        match self.run(
            "squeue",
            &["-h", "-j", &id, "-o", "%i %T"].map(std::ffi::OsStr::new),
        ) {
            Ok(out) => parse_squeue(&out),
            Err(ExecutorError::ToolFailed { stderr, .. })
                if stderr.to_ascii_lowercase().contains("invalid job id") =>
            {
                Ok(Vec::new())
            }
            Err(e) => Err(e),
        }
    }

    /// Accounting lines of `job_id`.
    pub fn accounting(&self, job_id: u64) -> ExecResult<Vec<AccountingLine>> {
        let id = job_id.to_string();
        let args = ["-n", "-P", "-j", &id, "-o", "JobID,State,ExitCode"];
        let out = self.run("sacct", &args.map(std::ffi::OsStr::new))?;
        parse_sacct(&out)
    }

    /// One poll: counts from `squeue`; once nothing is queued, failures from `sacct` if it
    /// works here (a missing or failing `sacct` leaves `accounting: false`).
    pub fn status(&self, job_id: u64, tasks: usize) -> ExecResult<ArrayStatus> {
        let mut status = ArrayStatus::from_queue(job_id, tasks, &self.queue(job_id)?);
        if status.is_finished() {
            if let Ok(acct) = self.accounting(job_id) {
                status.failed = failed_tasks(job_id, tasks, &acct);
                status.accounting = true;
            }
        }
        Ok(status)
    }

    /// One poll of every submitted array of a manifest, summed into one status for the
    /// progress bar (job id of the first array; `failed` left empty because task ids are
    /// per array: see each array's own status, returned alongside).
    pub fn status_all(
        &self,
        submissions: &[SubmissionRecord],
    ) -> ExecResult<(ArrayStatus, Vec<ArrayStatus>)> {
        let each = submissions
            .iter()
            .map(|s| self.status(s.job_id, s.tasks))
            .collect::<ExecResult<Vec<_>>>()?;
        let mut total = ArrayStatus {
            job_id: submissions.first().map_or(0, |s| s.job_id),
            tasks: 0,
            pending: 0,
            running: 0,
            finished: 0,
            failed: Vec::new(),
            accounting: !each.is_empty() && each.iter().all(|s| s.accounting),
        };
        for s in &each {
            total.tasks += s.tasks;
            total.pending += s.pending;
            total.running += s.running;
            total.finished += s.finished;
        }
        Ok((total, each))
    }

    /// Poll every `interval` until the array has left the queue; `on_poll` sees each poll
    /// (the progress bar).
    pub fn wait(
        &self,
        job_id: u64,
        tasks: usize,
        interval: Duration,
        mut on_poll: impl FnMut(&ArrayStatus),
    ) -> ExecResult<ArrayStatus> {
        loop {
            let status = self.status(job_id, tasks)?;
            on_poll(&status);
            if status.is_finished() {
                return Ok(status);
            }
            std::thread::sleep(interval);
        }
    }

    fn run(&self, tool: &str, args: &[&std::ffi::OsStr]) -> ExecResult<String> {
        let exe = self.locate(tool)?;
        let output = spawn_retrying(|| Command::new(&exe).args(args).output()).map_err(|e| {
            ExecutorError::ToolSpawn {
                tool: tool.to_string(),
                source: e,
            }
        })?;
        let stdout = String::from_utf8_lossy(&output.stdout).to_string();
        if !output.status.success() {
            let shown: Vec<String> = args
                .iter()
                .map(|a| a.to_string_lossy().to_string())
                .collect();
            return Err(ExecutorError::ToolFailed {
                command: format!("{tool} {}", shown.join(" ")),
                status: output.status.to_string(),
                stderr: String::from_utf8_lossy(&output.stderr).trim().to_string(),
            });
        }
        Ok(stdout)
    }
}

/// Spawning a script another thread has just written can fail with ETXTBSY while a forked
/// child still holds its write handle; it clears within milliseconds.
fn spawn_retrying<T>(mut spawn: impl FnMut() -> std::io::Result<T>) -> std::io::Result<T> {
    let mut attempt = 0;
    loop {
        match spawn() {
            Err(e) if e.raw_os_error() == Some(libc::ETXTBSY) && attempt < 20 => {
                attempt += 1;
                std::thread::sleep(Duration::from_millis(10));
            }
            other => return other,
        }
    }
}

fn is_executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    std::fs::metadata(p)
        .map(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
        .unwrap_or(false)
}

#[cfg(test)]
mod tests;
