//! `hdi report`, and the report `hdi run` writes at its end (docs/report.md).

use anyhow::{Context, Result};
use hdi::report::{self, Built, Options};
use std::path::{Path, PathBuf};

pub(super) fn cmd_report(
    config: &Path,
    out: Option<PathBuf>,
    no_validation: bool,
    validation: bool,
    force: bool,
) -> Result<()> {
    let file = hdi::stages::load(config)?;
    let opts = Options {
        out,
        validation: validation || (file.report.validation && !no_validation),
        force,
    };
    let built = report::build(config, &opts).context("writing the report")?;
    print_built(&built);
    Ok(())
}

/// After `hdi run`: the report, unless `[report] enabled = false`. A report that cannot be
/// written is a warning: the run's results are in place either way.
pub(super) fn after_run(config: &Path) {
    let Ok(file) = hdi::stages::load(config) else {
        return;
    };
    if !file.report.enabled {
        return;
    }
    let opts = Options {
        out: None,
        validation: file.report.validation,
        force: false,
    };
    match report::build(config, &opts) {
        Ok(built) => print_built(&built),
        Err(e) => eprintln!("warning: report not written: {}", hdi::error::chain(&e)),
    }
}

fn print_built(built: &Built) {
    let index = built.dir().join("index.html");
    match built {
        Built::Written(_) => eprintln!("report: {}", index.display()),
        Built::UpToDate(_) => eprintln!("report up to date: {}", index.display()),
    }
}
