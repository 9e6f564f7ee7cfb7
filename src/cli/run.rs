//! `hdi run`, `status`, `gc` and `exec-cases`: the pipeline commands.

use anyhow::{bail, Context, Result};
use schemars::JsonSchema;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

use super::progress::StageBars;
use super::{jobs_or_cores, load};
use hdi::core::cache::{StaleReason, Store};
use hdi::engine::{self, Outcome, RunOptions, State};

/// Exit status for "something is stale" in `hdi status`.
pub struct Stale;
impl std::fmt::Debug for Stale {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "stale")
    }
}
impl std::fmt::Display for Stale {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "some stage instances are stale")
    }
}
impl std::error::Error for Stale {}

pub(super) fn cmd_run(
    config: &Path,
    only: Vec<String>,
    force: bool,
    dry_run: bool,
    jobs: Option<usize>,
    batch: Option<std::sync::Arc<dyn hdi::core::executor::batch::BatchRunner>>,
) -> Result<()> {
    let started = Instant::now();
    let (file, stages) = load(config)?;
    let processed = file.processed_dir();
    let store =
        Store::open(&processed).with_context(|| format!("opening {}", processed.display()))?;
    let opts = RunOptions {
        only,
        force,
        dry_run,
        jobs: jobs_or_cores(jobs),
        batch,
    };
    let report = engine::run(stages, &store, &opts, &StageBars::new("stages"))?;
    if dry_run {
        for (name, o) in &report.outcomes {
            match o {
                Outcome::WouldRun(why) => {
                    println!("would run  {name}: {}", StaleReason::join(why))
                }
                _ => println!("fresh      {name}"),
            }
        }
        return Ok(());
    }
    let ran = report.count(|o| matches!(o, Outcome::Ran { .. }));
    let cached = report.count(|o| matches!(o, Outcome::Cached));
    let n_failed = report.count(|o| matches!(o, Outcome::Failed(_)));
    let mut first_failure = None;
    for (name, o) in &report.outcomes {
        match o {
            Outcome::Ran { seconds } => eprintln!("ran     {name} ({seconds:.2} s)"),
            Outcome::Failed(e) => {
                // The first failure becomes the error line; list the others here.
                if first_failure.is_none() {
                    first_failure = Some(format!("stage `{name}` failed: {e}"));
                } else {
                    eprintln!("FAILED  {name}: {e}");
                }
            }
            Outcome::Skipped(e) => eprintln!("skipped {name}: {e}"),
            _ => {}
        }
    }
    if let Err(e) = engine::write_summary_tables(&store, &report) {
        // A full disk fails the tables too: the failed instance is the error to report.
        if first_failure.is_none() {
            return Err(e.into());
        }
        eprintln!(
            "warning: summary tables not written: {}",
            hdi::error::chain(&e)
        );
    }
    let failed = report.failed();
    let total = report.outcomes.len();
    if ran == 0 && failed == 0 {
        eprintln!(
            "nothing to do: all {total} stage instances fresh ({:.2} s)",
            started.elapsed().as_secs_f64()
        );
    } else {
        eprintln!(
            "ran {ran}, cached {cached}, failed {n_failed}, skipped {} of {total} ({:.2} s); \
             outputs in {}",
            failed - n_failed,
            started.elapsed().as_secs_f64(),
            processed.display()
        );
    }
    // The HTML report (docs/report.md); a no-op run keeps the last run's record, so its
    // report stays as it is.
    let record =
        hdi::report::RunRecord::from_report(&report, started.elapsed().as_secs_f64(), opts.jobs);
    if record.changed_something() {
        if let Err(e) = record.save(&processed) {
            eprintln!("warning: {}", hdi::error::chain(&e));
        }
    }
    super::report::after_run(config);
    if let Some(first) = first_failure {
        if n_failed > 1 {
            bail!("{first} (and {} more failed)", n_failed - 1);
        }
        bail!("{first}");
    }
    if failed > 0 {
        bail!("{failed} stage instance(s) did not run");
    }
    Ok(())
}

pub(super) fn cmd_exec_cases(manifest: &Path, task: usize) -> Result<()> {
    use hdi::core::executor::{exec_task, TaskIdentity};
    // Manifests live in `processed/.hdi/slurm/manifests/`: the store is four levels up.
    let processed = manifest
        .ancestors()
        .nth(4)
        .filter(|p| p.join(".hdi").is_dir())
        .with_context(|| {
            format!(
                "{}: not a manifest under processed/.hdi/slurm/manifests/",
                manifest.display()
            )
        })?
        .to_path_buf();
    let store = Store::open(&processed)?;
    let report = exec_task(
        &store,
        manifest,
        task,
        &hdi::engine::distributed::registry(),
        &TaskIdentity::from_env(&processed),
    )?;
    eprintln!(
        "task {task}: {} computed, {} cached, {} failed",
        report.computed, report.cached, report.failed
    );
    if report.failed > 0 {
        bail!("{} case(s) of task {task} failed", report.failed);
    }
    Ok(())
}

/// One object per stage instance of the pipeline, in pipeline order: whether its cached
/// result is current. Exit status 1 when any is stale or missing. Schema version 1
/// (docs/json.md): existing keys keep their name, unit and type; renaming or removing one
/// makes version 2.
#[derive(Debug, Serialize, JsonSchema)]
pub(super) struct InstanceStatus {
    /// Instance name: the NAME of its `[kind.NAME]` table in pipeline.toml (e.g. `disk`).
    #[schemars(length(min = 1))]
    name: String,
    /// Stage kind: the `kind` of `[kind.NAME]` (e.g. `surface`, `dmw`, `simulate`).
    #[schemars(regex(pattern = r"^[a-z][a-z0-9_]*$"))]
    kind: String,
    /// `fresh`: the cache holds the current result; `stale`: inputs, parameters or upstream
    /// changed (see `why`); `missing`: never run.
    state: Freshness,
    /// Reasons it is stale or missing (e.g. `filter_l_m: null → 2.5e-7`, `upstream disk
    /// changed`, `never run`); empty when fresh.
    why: Vec<String>,
    /// Cache key the instance has now: blake3 hex of its fingerprint (docs/architecture.md).
    #[schemars(regex(pattern = r"^[0-9a-f]{16,64}$"))]
    key: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub(super) enum Freshness {
    Fresh,
    Stale,
    Missing,
}

impl Freshness {
    fn word(self) -> &'static str {
        match self {
            Freshness::Fresh => "fresh",
            Freshness::Stale => "stale",
            Freshness::Missing => "missing",
        }
    }
}

pub(super) fn cmd_status(config: &Path, as_json: bool) -> Result<()> {
    let (file, stages) = load(config)?;
    let store = Store::open_existing(&file.processed_dir());
    let plan = engine::plan(stages, &store, &Default::default())?;
    let mut stale = 0;
    let mut rows = Vec::new();
    for p in &plan.planned {
        let (state, why) = match &p.state {
            State::Fresh => (Freshness::Fresh, Vec::new()),
            State::Stale(why) if why.contains(&StaleReason::NeverRun) => {
                (Freshness::Missing, StaleReason::phrases(why))
            }
            State::Stale(why) => (Freshness::Stale, StaleReason::phrases(why)),
        };
        if state != Freshness::Fresh {
            stale += 1;
        }
        if !as_json {
            if why.is_empty() {
                println!("{:<8} {}", state.word(), p.name);
            } else {
                println!("{:<8} {}: {}", state.word(), p.name, why.join("; "));
            }
        }
        rows.push(InstanceStatus {
            name: p.name.clone(),
            kind: p.kind.to_string(),
            state,
            why,
            key: p.key.clone(),
        });
    }
    if as_json {
        println!("{}", serde_json::to_string(&rows)?);
    } else {
        // Cases that failed on Slurm and are still missing from the cache.
        use hdi::core::executor::{list_manifests, CaseManifest};
        for path in list_manifests(&file.processed_dir()).unwrap_or_default() {
            let Ok(mut m) = CaseManifest::read(&path) else {
                continue;
            };
            let _ = m.merge_outcomes(&path);
            let missing: std::collections::BTreeSet<String> =
                m.still_missing(&store).into_iter().map(|s| s.key).collect();
            let total = m.cases.len();
            m.cases.retain(|e| missing.contains(&e.spec.key));
            if m.failed().next().is_some() {
                println!("failed cases in {}:", path.display());
                super::slurm::report_failed_cases(&m);
            }
            // Submitted cases no task has stored or failed yet (queued, running, or lost
            // with a task Slurm no longer knows): the next `hdi run --executor slurm` waits
            // for or resubmits them.
            let (pending, _, _) = m.counts();
            let submitted =
                hdi::core::executor::read_submissions(&path).is_ok_and(|s| !s.is_empty());
            if pending > 0 && submitted {
                let kinds: std::collections::BTreeSet<&str> =
                    m.cases.iter().map(|e| e.spec.kind.as_str()).collect();
                let kinds: Vec<&str> = kinds.into_iter().collect();
                println!(
                    "slurm: {pending} of {total} submitted cases ({}) missing from the store (queued, running or lost): {}",
                    kinds.join(", "),
                    path.display()
                );
            }
        }
    }
    if stale > 0 {
        return Err(Stale.into());
    }
    Ok(())
}

pub(super) fn cmd_gc(config: &Path, dry_run: bool) -> Result<()> {
    let (file, stages) = load(config)?;
    let store = Store::open(&file.processed_dir())?;
    let plan = engine::plan(stages, &store, &Default::default())?;
    let removed = engine::gc(&plan, &store, dry_run, &super::progress::LockNotice)?;
    let verb = if dry_run { "would remove" } else { "removed" };
    for r in &removed {
        println!("{verb} {}", r.display());
    }
    eprintln!("{verb} {} item(s)", removed.len());
    Ok(())
}
