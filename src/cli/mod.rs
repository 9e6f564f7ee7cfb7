//! The thin command-line layer: parse arguments, call the library, print. clap, indicatif and
//! anyhow live only here (feature `cli`).

mod analyze;
mod analyze_stream;
mod args;
mod bench;
mod bulge;
mod contact;
mod diff;
mod dmw;
mod one_off;
mod progress;
mod report;
mod run;
mod schema;
mod simulate;
mod slurm;
mod slurm_batch;
mod surface;
mod synth;
mod validate;
mod verify;

use anyhow::{Context, Result};
use clap::Parser;
use std::path::Path;

use args::{Cli, Command};
use hdi::core::executor::ExecutorKind;

pub use diff::Differs;
pub use run::Stale;
pub use verify::Damaged;

pub fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Run {
            config,
            only,
            force,
            dry_run,
            jobs,
            slurm,
        } => {
            if slurm.executor.parse::<ExecutorKind>()? == ExecutorKind::Slurm && !dry_run {
                // The calibration's rounds go to Slurm during the local runs (docs/slurm.md).
                let runner = slurm_batch::calibration_runner(&config, &slurm)?;
                let submitted =
                    slurm::run_cases_on_slurm(&config, &only, &slurm, jobs, Some(runner.clone()));
                if !matches!(submitted, Ok(true)) {
                    slurm_batch::report(&runner);
                    return submitted.map(|_| ());
                }
                let ran = run::cmd_run(&config, only, force, dry_run, jobs, Some(runner.clone()));
                slurm_batch::report(&runner);
                return ran;
            }
            run::cmd_run(&config, only, force, dry_run, jobs, None)
        }
        Command::ExecCases {
            manifest,
            task,
            offset,
        } => run::cmd_exec_cases(&manifest, task + offset),
        Command::Status { config, json } => run::cmd_status(&config, json),
        Command::Gc { config, dry_run } => run::cmd_gc(&config, dry_run),
        Command::Surface(args) => surface::cmd_surface(*args),
        Command::Bulge(args) => bulge::cmd_bulge(*args),
        Command::Dmw(args) => dmw::cmd_dmw(*args),
        Command::Contact(args) => contact::cmd_contact(*args),
        Command::Simulate(args) => simulate::cmd_simulate(*args),
        Command::Analyze(args) => analyze::cmd_analyze(*args),
        Command::Validate {
            json,
            only,
            class,
            config,
        } => validate::cmd_validate(json, &only, &class, &config),
        Command::Synth {
            what,
            out_dir,
            format,
            revolutions,
            seed,
            no_index,
        } => synth::cmd_synth(&what, out_dir, &format, revolutions, seed, no_index),
        Command::Bench {
            config,
            size,
            json,
            only,
            main_job,
            input,
            repeat,
            readers,
            read_one,
        } => match (read_one, readers.is_empty()) {
            (Some(file), _) => bench::read_one(&file),
            (None, false) => bench::bench_readers(&readers),
            (None, true) => bench::cmd_bench(
                hdi::bench::BenchOptions {
                    config,
                    size,
                    only,
                    main_job,
                    input,
                    repeat,
                },
                json,
            ),
        },
        Command::Report {
            config,
            out,
            no_validation,
            validation,
            force,
        } => report::cmd_report(&config, out, no_validation, validation, force),
        Command::Diff(args) => diff::cmd_diff(*args),
        Command::Schema { name, write, check } => {
            schema::cmd_schema(name, write.as_deref(), check.as_deref())
        }
        Command::Verify {
            config,
            all,
            repair,
            json,
            jobs,
        } => verify::cmd_verify(&config, all, repair, json, jobs),
    }
}

/// The directory an `--out FILE` goes into (created; `.` for a bare file name).
fn out_parent(out: &Path) -> Result<&Path> {
    let dir = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    Ok(dir)
}

/// `--{key}` for a config key (`h_star_min` → `--h-star-min`).
fn flag(key: &str) -> String {
    format!("--{}", key.replace('_', "-"))
}

/// The pipeline file and its validated stage instances (the commands that read a pipeline).
pub(crate) fn load(
    config: &Path,
) -> Result<(
    hdi::core::config::PipelineFile,
    Vec<Box<dyn hdi::stages::Stage>>,
)> {
    let file = hdi::stages::load(config)?;
    let stages = hdi::stages::build(&file)?;
    Ok((file, stages))
}

/// `--jobs`, or one per core.
pub(crate) fn jobs_or_cores(jobs: Option<usize>) -> usize {
    jobs.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    })
}
