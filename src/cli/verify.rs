//! `hdi verify [--all] [--repair] [--json]`: the store against its manifests
//! (`engine::verify`, docs/reliability.md).

use anyhow::{Context, Result};
use schemars::JsonSchema;
use serde::Serialize;
use std::path::Path;

use hdi::core::cache::Store;
use hdi::engine::{self, verify};

/// Exit status 1 for "the store holds damaged entries".
pub struct Damaged;
impl std::fmt::Debug for Damaged {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "damaged")
    }
}
impl std::fmt::Display for Damaged {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "damaged store entries")
    }
}
impl std::error::Error for Damaged {}

fn check(config: &Path, all: bool) -> Result<verify::VerifyReport> {
    let (file, stages) = super::load(config)?;
    let store = Store::open_existing(&file.processed_dir());
    // Read-only planning: verify writes nothing (not even the input-hash accelerator).
    let plan = engine::plan_read_only(stages, &store)?;
    Ok(verify::verify(&plan, &store, all))
}

pub(super) fn cmd_verify(
    config: &Path,
    all: bool,
    repair: bool,
    json: bool,
    jobs: Option<usize>,
) -> Result<()> {
    let first = check(config, all)?;
    let mut repaired = None;
    let report = if repair && !first.clean() {
        let (file, _) = super::load(config)?;
        let processed = file.processed_dir();
        let store = Store::open_existing(&processed);
        let q = verify::quarantine_damaged(&store, &first, &super::progress::LockNotice)
            .with_context(|| format!("moving damaged entries aside in {}", processed.display()))?;
        for m in &q.moved {
            eprintln!("moved aside {m}");
        }
        if !q.rerun.is_empty() {
            eprintln!("re-running {}", q.rerun.join(", "));
            super::run::cmd_run(config, q.rerun.clone(), true, false, jobs, None)
                .context("re-running the instances of the damaged entries")?;
        }
        let after = check(config, all)?;
        repaired = Some((first, q));
        after
    } else {
        first
    };
    if json {
        let doc = VerifyDocument {
            clean: report.clean(),
            report: &report,
            repair: repaired.as_ref().map(|(before, q)| Repair {
                damaged_before: &before.damaged,
                moved: &q.moved,
                rerun: &q.rerun,
            }),
        };
        println!("{}", serde_json::to_string_pretty(&doc)?);
    } else {
        print_text(&report, repaired.as_ref().map(|(b, _)| b));
    }
    if report.clean() {
        Ok(())
    } else {
        Err(Damaged.into())
    }
}

/// The store under processed/.hdi/store/ checked against the per-file blake3 hashes and sizes
/// its manifests record (docs/reliability.md, `hdi verify`). With --repair, the state after
/// the repair, and what was repaired under `repair`. Exit status 0 when `clean`, 1 when
/// damaged entries remain, 2 on error. Schema version 1 (docs/json.md): existing keys keep
/// their name, unit and type; renaming or removing one makes version 2.
#[derive(Serialize, JsonSchema)]
pub(super) struct VerifyDocument<'a> {
    #[serde(flatten)]
    report: &'a verify::VerifyReport,
    /// No damaged entry (after the repair, with --repair).
    clean: bool,
    /// null without --repair or when nothing was damaged; otherwise what the repair did.
    repair: Option<Repair<'a>>,
}

/// What `--repair` did.
#[derive(Serialize, JsonSchema)]
struct Repair<'a> {
    /// The damaged entries found before the repair.
    damaged_before: &'a [verify::DamagedEntry],
    /// Where each damaged entry was moved (relative to processed/, under .hdi/tmp/: never
    /// trusted, removed by `hdi gc`).
    moved: &'a [String],
    /// The instances re-run (forced) so the engine recomputed what was moved.
    rerun: &'a [String],
}

fn print_text(r: &verify::VerifyReport, before: Option<&verify::VerifyReport>) {
    if let Some(b) = before {
        println!(
            "repaired {}:",
            count(b.damaged.len(), "damaged entry", "damaged entries")
        );
        for d in &b.damaged {
            println!("  {} ({})", d.path, d.referenced_by.join(", "));
        }
    }
    for d in &r.damaged {
        let by = if d.referenced_by.is_empty() {
            "orphan".to_string()
        } else {
            d.referenced_by.join(", ")
        };
        println!("damaged  {} ({by})", d.path);
        for p in &d.problems {
            println!("           {}: {}", p.file, p.detail);
        }
    }
    // Orphans are harmless: the first few by path, then a count per kind (`--json` lists all).
    const SHOWN: usize = 10;
    for o in r.orphans.iter().take(SHOWN) {
        println!(
            "orphan   {} (not referenced by the pipeline; `hdi gc` removes it)",
            o.path
        );
    }
    if r.orphans.len() > SHOWN {
        let mut by_kind = std::collections::BTreeMap::<&str, usize>::new();
        for o in &r.orphans[SHOWN..] {
            *by_kind.entry(o.kind.as_str()).or_default() += 1;
        }
        let kinds: Vec<String> = by_kind.iter().map(|(k, n)| format!("{n} {k}")).collect();
        println!(
            "orphan   … and {} more ({}; `--json` lists them)",
            r.orphans.len() - SHOWN,
            kinds.join(", ")
        );
    }
    if !r.not_run.is_empty() {
        println!("not run  {} (`hdi status` says why)", r.not_run.join(", "));
    }
    if r.leftover_work_dirs > 0 {
        println!(
            "leftover {} in .hdi/tmp/ (interrupted runs, quarantined entries: never trusted; `hdi gc` removes them)",
            count(r.leftover_work_dirs, "work dir", "work dirs")
        );
    }
    eprintln!(
        "verified {}, {}, {:.1} MB ({}): {} damaged, {} orphaned",
        count(r.entries_checked, "entry", "entries"),
        count(r.files_checked, "file", "files"),
        r.bytes_checked as f64 / 1e6,
        if r.scope == verify::Scope::All {
            "every entry"
        } else {
            "entries the pipeline references"
        },
        r.damaged.len(),
        r.orphans.len()
    );
}

fn count(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}
