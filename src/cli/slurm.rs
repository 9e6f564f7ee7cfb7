//! `hdi run --executor slurm`: the stale cases of the `[simulate]`/`[doe]`/`[three_dof]`
//! instances the run selects as Slurm array jobs (docs/slurm.md).

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

use super::args::SlurmArgs;
use super::progress::{task_bar, StageBars};
use super::{jobs_or_cores, load};
use hdi::core::cache::Store;
use hdi::core::executor::CaseManifest;
use hdi::engine::{self, RunOptions};

/// Bring the upstream of the case-carrying instances `only` selects (all when empty) up to
/// date, list their stale cases into a manifest, submit it as array jobs and wait for them. Returns `false` for `--no-wait`
/// (submitted; nothing more to do now), `true` when the local run should follow (every case
/// is then cached).
pub(super) fn run_cases_on_slurm(
    config: &Path,
    only: &[String],
    args: &SlurmArgs,
    jobs: Option<usize>,
    batch: Option<std::sync::Arc<dyn hdi::core::executor::batch::BatchRunner>>,
) -> Result<bool> {
    use hdi::core::executor::manifest_path;
    use hdi::core::executor::slurm::{submit_manifest, ScriptOptions, SlurmClient};
    use hdi::engine::distributed;
    let (file, _) = load(config)?;
    let processed = file.processed_dir();
    let store =
        Store::open(&processed).with_context(|| format!("opening {}", processed.display()))?;
    let upstream = distributed::case_upstream(&file, &store, only)?;
    if !upstream.is_empty() {
        let report = engine::run(
            hdi::stages::build(&file)?,
            &store,
            &RunOptions {
                only: upstream,
                force: false,
                dry_run: false,
                jobs: jobs_or_cores(jobs),
                // A calibration upstream of a calibrated sweep sends its rounds to Slurm too.
                batch,
            },
            &StageBars::new("stages"),
        )?;
        if report.failed() > 0 {
            bail!(
                "the upstream of the instances whose cases go to Slurm failed: run `hdi run` to see why"
            );
        }
    }
    let config_abs =
        std::fs::canonicalize(config).with_context(|| format!("resolving {}", config.display()))?;
    let specs = distributed::stale_cases(&file, &config_abs, &store, only)?;
    if specs.is_empty() {
        eprintln!("slurm: no stale [simulate], [doe] or [three_dof] case to submit");
        return Ok(true);
    }
    let manifest = CaseManifest::new(specs, args.cases_per_task)?;
    let path = manifest_path(&processed, &manifest.id());
    manifest.write(&path)?;
    let client = SlurmClient::from_path();
    let workdir = config_abs
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let opts = ScriptOptions {
        hdi: std::env::current_exe().context("locating the hdi binary")?,
        workdir,
        processed: std::fs::canonicalize(&processed)?,
        job_name: "hdi-cases".into(),
        partition: args.partition.clone(),
        max_running: None,
        extra_directives: Vec::new(),
    };
    let records = submit_manifest(&client, &opts, &path, &manifest, args.max_array)?;
    let ids: Vec<String> = records.iter().map(|r| r.job_id.to_string()).collect();
    eprintln!(
        "slurm: {} cases in {} tasks submitted as job(s) {} (manifest {})",
        manifest.cases.len(),
        manifest.task_count(),
        ids.join(", "),
        path.display()
    );
    if args.no_wait {
        eprintln!("slurm: --no-wait: `hdi run --executor slurm` later collects the results");
        return Ok(false);
    }
    let poll = std::env::var("HDI_SLURM_POLL_MS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5_000u64);
    let bar = task_bar(manifest.task_count());
    let statuses = loop {
        let (total, each) = client.status_all(&records)?;
        bar.set_position(total.finished as u64);
        bar.set_message(format!(
            "{} running, {} pending",
            total.running, total.pending
        ));
        if total.is_finished() {
            break each;
        }
        std::thread::sleep(std::time::Duration::from_millis(poll));
    };
    bar.finish_and_clear();
    let mut done = CaseManifest::read(&path)?;
    done.merge_outcomes(&path)?;
    for (record, status) in records.iter().zip(&statuses) {
        done.mark_unreported(&processed, record, &status.failed);
    }
    done.write(&path)?;
    let failed = report_failed_cases(&done);
    if failed > 0 {
        bail!(
            "{failed} case(s) failed on Slurm (listed above; `hdi status` lists them too); \
             `hdi run --executor slurm` resubmits only what is missing"
        );
    }
    Ok(true)
}

/// Print the failed cases of a manifest (key, error, job/task, log); returns how many.
pub(super) fn report_failed_cases(m: &CaseManifest) -> usize {
    use hdi::core::executor::CaseStatus;
    let mut n = 0;
    for (i, e) in m.failed() {
        if let CaseStatus::Failed {
            error,
            job_id,
            task_id,
            log,
        } = &e.status
        {
            n += 1;
            let at = match (job_id, task_id) {
                (Some(j), Some(t)) => format!(" (job {j}, task {t})"),
                _ => String::new(),
            };
            let log = log
                .as_ref()
                .map_or(String::new(), |l| format!(", log {}", l.display()));
            eprintln!(
                "FAILED  case {i} {} {}{at}{log}: {error}",
                e.spec.kind, e.spec.key
            );
        }
    }
    n
}
