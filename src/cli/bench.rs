//! `hdi bench`: the timing figures of docs/performance.md, measured by `hdi::bench` and printed
//! here one line each as they come (or, with `--json`, as one document, docs/schemas/bench.json).
//! `--readers DIR…` times the file readers, each file in a child `hdi bench --read-one FILE`.

use anyhow::{bail, Context, Result};
use hdi::bench::readers::{self, ReadTiming};
use hdi::bench::{self, BenchDocument, BenchError, BenchHost, BenchOptions, Figure};
use std::path::{Path, PathBuf};

/// Prints each figure (unless `--json`) and runs `hdi run` as a child process.
struct Printer {
    json: bool,
}

impl BenchHost for Printer {
    fn figure(&mut self, figure: &Figure) {
        if !self.json {
            println!("{}", figure.table_line());
        }
    }

    fn main_job_starting(&mut self, config: &Path) {
        if !self.json {
            eprintln!("main job: running {} cold in a temp dir…", config.display());
        }
    }

    /// `hdi run --config CONFIG` as a child process; its stderr.
    fn run_pipeline(&mut self, config: &Path) -> bench::Result<String> {
        let o = std::process::Command::new(std::env::current_exe().map_err(BenchError::Spawn)?)
            .args(["run", "--config"])
            .arg(config)
            .output()
            .map_err(BenchError::Spawn)?;
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        if !o.status.success() {
            return Err(BenchError::PipelineFailed {
                config: config.to_path_buf(),
                last_line: err.lines().last().unwrap_or("").to_string(),
            });
        }
        Ok(err)
    }
}

/// `hdi bench`: figures for docs/performance.md.
pub(super) fn cmd_bench(o: BenchOptions, json: bool) -> Result<()> {
    bench::check(&o)?;
    if !json {
        println!("{}", bench::header_line());
    }
    let figures = bench::run(&o, &mut Printer { json })?;
    if !json && o.only.is_empty() && !o.main_job {
        // Not estimated: a figure of the main job is a measured cold run or nothing.
        println!(
            "main job cold: not run (add --main-job: it runs {} cold in a temp dir, minutes)",
            o.config.display()
        );
    }
    if json {
        let doc = BenchDocument::new(o.input.as_deref(), figures);
        println!("{}", serde_json::to_string_pretty(&doc)?);
    }
    Ok(())
}

/// The child of `--readers`: read `file` three times, print `seconds peak_rss_bytes format
/// values`.
pub(super) fn read_one(file: &Path) -> Result<()> {
    println!("{}", readers::read_one(file)?.child_line());
    Ok(())
}

/// `--readers DIR…`: one line per readable file.
pub(super) fn bench_readers(dirs: &[PathBuf]) -> Result<()> {
    let files = readers::readable_files(dirs)?;
    let exe = std::env::current_exe()?;
    println!("{}", readers::table_header());
    for file in &files {
        let out = std::process::Command::new(&exe)
            .args(["bench", "--read-one"])
            .arg(file)
            .output()
            .context("running hdi bench --read-one")?;
        if !out.status.success() {
            // A deliberately corrupt test file: not a throughput figure.
            continue;
        }
        let text = String::from_utf8_lossy(&out.stdout);
        let Some(timing) = ReadTiming::parse_child_line(&text) else {
            bail!("unexpected child output `{text}`");
        };
        println!("{}", readers::table_row(file, &timing)?);
    }
    Ok(())
}
