//! `hdi report`: one static HTML page of the whole pipeline (docs/report.md) — what ran and
//! what was cached and how long it took, each stage instance's key numbers, figures and files,
//! the `hdi validate` table, the provenance (cache keys, input hashes, versions) and the
//! `hdi status` view.
//!
//! The report is a *view*, like the run log: it shows wall times and dates, so it is not a
//! result and is left out of the byte-identical-rerun guarantee (docs/architecture.md). It
//! sits above the engine and the validation harness: it reads the plan, the store's manifests
//! and `result.json`s, and the validation rows; nothing below imports it.

mod html;

use crate::core::cache::{Manifest, StaleReason, Store};
use crate::core::hash::{canonical_json, hash_file};
use crate::engine::{self, Outcome, RunReport, State};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Bump when the page's layout or the key's recipe changes: an old report is then rebuilt.
const REPORT_SCHEMA: u32 = 1;

/// The key file inside the report directory: the report is rebuilt only when it differs.
pub const KEY_FILE: &str = "report-key.txt";

/// The last `hdi run` that changed something (ran or failed an instance), kept in
/// `processed/.hdi/last-run.json` for `hdi report` to show.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RunRecord {
    /// UTC, ISO 8601.
    pub finished: String,
    pub hdi_version: String,
    pub wall_time_s: f64,
    pub jobs: usize,
    pub instances: Vec<RunInstance>,
}

/// One instance's outcome in a [`RunRecord`].
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct RunInstance {
    pub name: String,
    /// `ran`, `cached`, `failed` or `skipped`.
    pub outcome: String,
    /// Seconds it ran (`ran` only).
    pub wall_time_s: Option<f64>,
    /// Why it failed or was skipped.
    pub message: String,
}

impl RunRecord {
    /// The record of a finished run.
    pub fn from_report(report: &RunReport, wall_time_s: f64, jobs: usize) -> RunRecord {
        let instances = report
            .outcomes
            .iter()
            .map(|(name, o)| {
                let (outcome, secs, message) = match o {
                    Outcome::Cached => ("cached", None, String::new()),
                    Outcome::Ran { seconds } => ("ran", Some(*seconds), String::new()),
                    Outcome::Failed(e) => ("failed", None, e.clone()),
                    Outcome::Skipped(e) => ("skipped", None, e.clone()),
                    Outcome::WouldRun(why) => ("would run", None, StaleReason::join(why)),
                };
                RunInstance {
                    name: name.clone(),
                    outcome: outcome.into(),
                    wall_time_s: secs,
                    message,
                }
            })
            .collect();
        RunRecord {
            finished: crate::core::cache::now_iso8601(),
            hdi_version: env!("CARGO_PKG_VERSION").into(),
            wall_time_s,
            jobs,
            instances,
        }
    }

    /// Whether the run changed anything: a no-op run (everything cached) keeps the previous
    /// record, so the report of the run that produced the results stays as it was.
    pub fn changed_something(&self) -> bool {
        self.instances.iter().any(|i| i.outcome != "cached")
    }

    fn path(processed: &Path) -> PathBuf {
        processed.join(".hdi").join("last-run.json")
    }

    /// Save as `processed/.hdi/last-run.json` (atomically).
    pub fn save(&self, processed: &Path) -> Result<()> {
        let path = Self::path(processed);
        let bytes = serde_json::to_vec_pretty(self).map_err(|e| Error::Output {
            path: path.clone(),
            message: e.to_string(),
        })?;
        crate::core::cache::write_atomic(&path, &bytes).map_err(|e| Error::io(&path, e))
    }

    /// The saved record, if there is a readable one.
    pub fn load(processed: &Path) -> Option<RunRecord> {
        let bytes = std::fs::read(Self::path(processed)).ok()?;
        serde_json::from_slice(&bytes).ok()
    }
}

/// What to build.
#[derive(Debug, Clone)]
pub struct Options {
    /// The report directory (default `processed/report/`).
    pub out: Option<PathBuf>,
    /// Include the `hdi validate` table.
    pub validation: bool,
    /// Rebuild even when the key file says the report is current.
    pub force: bool,
}

/// What [`build`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum Built {
    Written(PathBuf),
    /// The report for the same cache keys, pipeline file and run exists already.
    UpToDate(PathBuf),
}

impl Built {
    pub fn dir(&self) -> &Path {
        match self {
            Built::Written(d) | Built::UpToDate(d) => d,
        }
    }
}

/// One stage instance as the report shows it.
#[derive(Debug, Clone)]
pub(crate) struct Instance {
    pub name: String,
    pub kind: String,
    pub key: String,
    pub model_version: String,
    /// `fresh`, `stale` or `missing` (as `hdi status` says), and why.
    pub state: String,
    pub why: Vec<String>,
    /// The last run's outcome for it, if that run included it.
    pub last_run: Option<RunInstance>,
    pub manifest: Option<Manifest>,
    /// Summary-table row (column → value), in the stage's column order.
    pub numbers: Vec<(String, Value)>,
    /// Output files relative to the report directory (URL-ready, `/`-separated) with their
    /// names in the entry: figures (PNG) and the other files.
    pub figures: Vec<(String, String)>,
    pub files: Vec<(String, String, u64)>,
    pub inputs: Vec<(String, String, String)>,
    pub upstream: Vec<(String, String)>,
}

/// Validation, as the report shows it: per area its rows, or why they could not be computed.
pub(crate) struct Validation {
    pub areas: Vec<(
        String,
        std::result::Result<Vec<crate::validation::Row>, String>,
    )>,
}

/// Everything the page shows.
pub(crate) struct Page {
    pub project: String,
    pub config_name: String,
    pub config_blake3: String,
    pub hdi_version: String,
    pub generated: String,
    pub run: Option<RunRecord>,
    pub instances: Vec<Instance>,
    /// `processed/tables/*` relative to the report dir, and their names.
    pub tables: Vec<(String, String)>,
    pub validation: Option<Validation>,
    pub key: String,
}

/// Build the report of the pipeline in `config` (unless the one in the report directory is
/// already of the same cache keys, pipeline file and last run).
pub fn build(config: &Path, opts: &Options) -> Result<Built> {
    let file = crate::stages::load(config)?;
    let stages = crate::stages::build(&file)?;
    let processed = file.processed_dir();
    let store = Store::open_existing(&processed);
    let plan = engine::plan(stages, &store, &Default::default())?;
    let out = opts.out.clone().unwrap_or_else(|| processed.join("report"));
    let run = RunRecord::load(&processed);
    let config_blake3 = hash_file(config).map_err(|e| Error::io(config, e))?;

    let key = report_key(&plan, run.as_ref(), &config_blake3, opts, &processed);
    let key_path = out.join(KEY_FILE);
    if !opts.force
        && out.join("index.html").is_file()
        && std::fs::read_to_string(&key_path).is_ok_and(|k| k.trim() == key)
    {
        return Ok(Built::UpToDate(out));
    }

    std::fs::create_dir_all(out.parent().unwrap_or(Path::new(".")))
        .map_err(|e| Error::io(&out, e))?;
    // Links are relative to the report directory, so the page works from file:// and when
    // processed/ (with the report inside) is moved or copied as a whole.
    let rel = relative_prefix(&out, &processed);

    let mut instances = Vec::new();
    for p in &plan.planned {
        let model_version = plan.stages[p.index].model_version().to_string();
        instances.push(instance(
            p,
            model_version,
            run.as_ref(),
            &store,
            &processed,
            &rel,
        ));
    }

    let tables = list_dir(&processed.join("tables"))
        .into_iter()
        .map(|n| {
            (
                format!("{rel}{}", url_path(&["tables".to_string(), n.clone()])),
                n,
            )
        })
        .collect();

    let validation = opts.validation.then(|| Validation {
        areas: crate::validation::AREAS
            .iter()
            .map(|a| {
                (
                    a.name.to_string(),
                    a.rows(config).map_err(|e| crate::error::chain(&e)),
                )
            })
            .collect(),
    });

    let page = Page {
        project: file.project.name.clone(),
        config_name: config
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default(),
        config_blake3,
        hdi_version: env!("CARGO_PKG_VERSION").into(),
        generated: crate::core::cache::now_iso8601(),
        run,
        instances,
        tables,
        validation,
        key: key.clone(),
    };
    let text = html::render(&page);
    write_dir(
        &out,
        &[("index.html", text.as_bytes()), (KEY_FILE, key.as_bytes())],
    )?;
    Ok(Built::Written(out))
}

/// The report's cache key: everything the page shows except the dates and the validation
/// numbers' code (the hdi version stands for that).
fn report_key(
    plan: &engine::Plan,
    run: Option<&RunRecord>,
    config_blake3: &str,
    opts: &Options,
    processed: &Path,
) -> String {
    let key_doc = json!({
        "schema": REPORT_SCHEMA,
        "hdi_version": env!("CARGO_PKG_VERSION"),
        "pipeline_blake3": config_blake3,
        "validation": opts.validation,
        "instances": plan.planned.iter().map(|p| json!({
            "name": p.name,
            "key": p.key,
            "state": match &p.state { State::Fresh => Value::Null, State::Stale(w) => json!(w) },
        })).collect::<Vec<_>>(),
        "run": run.map(|r| serde_json::to_value(r).unwrap_or(Value::Null)),
        "tables": list_dir(&processed.join("tables")),
    });
    blake3::hash(canonical_json(&key_doc).as_bytes())
        .to_hex()
        .to_string()
}

/// One instance of the page: its state and why, its last run, its summary numbers, its
/// figures and files (linked relative to the report directory), inputs and upstream.
fn instance(
    p: &engine::Planned,
    model_version: String,
    run: Option<&RunRecord>,
    store: &Store,
    processed: &Path,
    rel: &str,
) -> Instance {
    let (state, why) = match &p.state {
        State::Fresh => ("fresh".to_string(), Vec::new()),
        State::Stale(w) if w.contains(&StaleReason::NeverRun) => {
            ("missing".into(), StaleReason::phrases(w))
        }
        State::Stale(w) => ("stale".into(), StaleReason::phrases(w)),
    };
    let last_run = run.and_then(|r| r.instances.iter().find(|i| i.name == p.name).cloned());
    let mut inst = Instance {
        name: p.name.clone(),
        kind: p.kind.clone(),
        key: p.key.clone(),
        model_version,
        state,
        why,
        last_run,
        manifest: p.manifest.clone(),
        numbers: Vec::new(),
        figures: Vec::new(),
        files: Vec::new(),
        inputs: p
            .fingerprint
            .inputs
            .iter()
            .map(|i| (i.role.clone(), i.path.clone(), i.blake3.clone()))
            .collect(),
        upstream: p
            .fingerprint
            .upstream
            .iter()
            .map(|u| (u.name.clone(), u.key.clone()))
            .collect(),
    };
    if let Some(m) = &p.manifest {
        let entry = store.entry_dir(&p.kind, &p.key);
        if let Ok(Value::Object(mut r)) = engine::read_result(&entry) {
            if let Some(Value::Object(row)) = r.remove("summary_row") {
                inst.numbers = row.into_iter().collect();
            }
        }
        // Through the human-friendly link when it points at this entry, else the entry.
        let link_target = PathBuf::from(".hdi")
            .join("store")
            .join(&p.kind)
            .join(&p.key);
        let base = if std::fs::read_link(processed.join(&p.name)).ok() == Some(link_target) {
            vec![p.name.clone()]
        } else {
            vec![".hdi".into(), "store".into(), p.kind.clone(), p.key.clone()]
        };
        let mut outputs: Vec<_> = m.outputs.iter().collect();
        outputs.sort_by(|a, b| a.path.cmp(&b.path));
        for o in outputs {
            let mut segs = base.clone();
            segs.extend(o.path.split('/').map(str::to_string));
            let href = format!("{rel}{}", url_path(&segs));
            if o.path.to_ascii_lowercase().ends_with(".png") {
                inst.figures.push((href.clone(), o.path.clone()));
            }
            inst.files.push((href, o.path.clone(), o.bytes));
        }
    }
    inst
}

/// File names in `dir`, sorted (none when it does not exist).
fn list_dir(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .filter(|e| e.path().is_file())
                .map(|e| e.file_name().to_string_lossy().to_string())
                .filter(|n| !n.starts_with('.'))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

/// The URL prefix from the report directory `out` to `processed` (`../` for the default
/// `processed/report/`), ending in `/` unless empty.
fn relative_prefix(out: &Path, processed: &Path) -> String {
    let abs = |p: &Path| -> PathBuf {
        let p = if p.is_absolute() {
            p.to_path_buf()
        } else {
            std::env::current_dir().unwrap_or_default().join(p)
        };
        // Resolve what exists (the processed dir, the report's parent), keep the rest.
        let mut existing = p.clone();
        let mut tail = Vec::new();
        while !existing.exists() {
            match (existing.file_name(), existing.parent()) {
                (Some(n), Some(parent)) => {
                    tail.push(n.to_os_string());
                    existing = parent.to_path_buf();
                }
                _ => break,
            }
        }
        let mut r = existing.canonicalize().unwrap_or(existing);
        for t in tail.into_iter().rev() {
            r.push(t);
        }
        r
    };
    let (out, processed) = (abs(out), abs(processed));
    let a: Vec<_> = out.components().collect();
    let b: Vec<_> = processed.components().collect();
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut segs: Vec<String> = vec!["..".into(); a.len() - common];
    segs.extend(
        b[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().to_string()),
    );
    if segs.is_empty() {
        String::new()
    } else {
        format!("{}/", url_path(&segs))
    }
}

/// Path segments percent-encoded for a relative URL (RFC 3986 unreserved characters kept).
pub(crate) fn url_path(segs: &[String]) -> String {
    segs.iter()
        .map(|s| {
            let mut o = String::new();
            for b in s.bytes() {
                if b.is_ascii_alphanumeric() || matches!(b, b'-' | b'.' | b'_' | b'~') {
                    o.push(b as char);
                } else {
                    o.push_str(&format!("%{b:02X}"));
                }
            }
            o
        })
        .collect::<Vec<_>>()
        .join("/")
}

/// Replace the directory `out` with one holding `files`: written into a sibling temp dir,
/// then swapped in by renames, so a reader sees the old report or the new one.
fn write_dir(out: &Path, files: &[(&str, &[u8])]) -> Result<()> {
    let parent = out.parent().unwrap_or(Path::new("."));
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_else(|| "report".into());
    let pid = std::process::id();
    let tmp = parent.join(format!(".{name}.tmp-{pid}"));
    let old = parent.join(format!(".{name}.old-{pid}"));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).map_err(|e| Error::io(&tmp, e))?;
    for (f, bytes) in files {
        let p = tmp.join(f);
        if let Err(e) = std::fs::write(&p, bytes) {
            // A full disk: leave no half-written report dir behind (docs/reliability.md).
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(Error::io(&p, e));
        }
    }
    if out.exists() {
        let _ = std::fs::remove_dir_all(&old);
        std::fs::rename(out, &old).map_err(|e| Error::io(out, e))?;
    }
    std::fs::rename(&tmp, out).map_err(|e| Error::io(out, e))?;
    let _ = std::fs::remove_dir_all(&old);
    Ok(())
}

#[cfg(test)]
mod tests;
