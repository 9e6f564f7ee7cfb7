//! `hdi run --executor slurm`: the batch runner the `[calibrate]` instances send their rounds
//! of cases to during the local pipeline run (docs/slurm.md, "Calibration on Slurm").

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use super::args::SlurmArgs;
use super::load;
use hdi::core::executor::batch::SlurmBatchRunner;
use hdi::core::executor::slurm::{ScriptOptions, SlurmClient};

/// The Slurm runner of the rounds (the same job-script options as the sweep's arrays; the
/// `squeue` period is `HDI_SLURM_POLL_MS`, default 5 s; outcome files are checked every 50 ms).
pub(super) fn calibration_runner(config: &Path, args: &SlurmArgs) -> Result<Arc<SlurmBatchRunner>> {
    let (file, _) = load(config)?;
    let processed = file.processed_dir();
    std::fs::create_dir_all(&processed)
        .with_context(|| format!("creating {}", processed.display()))?;
    let config_abs =
        std::fs::canonicalize(config).with_context(|| format!("resolving {}", config.display()))?;
    let workdir = config_abs
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let script = ScriptOptions {
        hdi: std::env::current_exe().context("locating the hdi binary")?,
        workdir,
        processed: std::fs::canonicalize(&processed)?,
        job_name: "hdi-calibration".into(),
        partition: args.partition.clone(),
        max_running: None,
        extra_directives: Vec::new(),
    };
    let poll = std::env::var("HDI_SLURM_POLL_MS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5_000u64);
    Ok(Arc::new(SlurmBatchRunner::new(
        SlurmClient::from_path(),
        script,
        config_abs,
        args.cases_per_task,
        args.max_array,
        Duration::from_millis(poll),
    )))
}

/// One line on what the rounds did (nothing if no stage asked for one).
pub(super) fn report(runner: &SlurmBatchRunner) {
    let s = runner.stats();
    if s.rounds > 0 {
        eprintln!(
            "slurm: calibration rounds: {} ({} submitted, {:.1} s waiting), cases: {} ({} submitted)",
            s.rounds, s.submitted_rounds, s.seconds, s.cases, s.submitted_cases
        );
    }
}
