//! `hdi verify`: re-hash the store entries the pipeline references (or, with `all`, every
//! entry) against the per-file blake3 and sizes their manifests record, report damaged and
//! orphaned entries, and move damaged entries aside so a run recomputes them
//! (docs/reliability.md, "`hdi verify`").
//!
//! "Referenced" is exactly what `hdi gc` keeps ([`references`] is its keep set): each
//! instance's current entry, the entry its ref (`processed/<name>`) points at, the case entries
//! those entries list under `case_keys`, and the cases of Slurm case manifests.

use crate::core::cache::{FileProblem, ProblemKind, Store};
use crate::core::cases::CASE_KIND;
use crate::engine::Plan;
use schemars::JsonSchema;
use serde::Serialize;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

/// A store entry: (kind, key).
pub type EntryId = (String, String);

/// Why an entry is referenced.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub enum By {
    /// The instance's current key.
    Instance(String),
    /// The instance's last successful run (`processed/<name>`), when its key has changed since.
    LastRun(String),
    /// Listed under `case_keys` by this instance's entry.
    CaseOf(String),
    /// Listed by a Slurm case manifest (file name).
    SlurmManifest(String),
}

impl By {
    pub fn label(&self) -> String {
        match self {
            By::Instance(n) => n.clone(),
            By::LastRun(n) => format!("{n} (last run)"),
            By::CaseOf(n) => format!("case of {n}"),
            By::SlurmManifest(f) => format!("Slurm manifest {f}"),
        }
    }
    /// The pipeline instance whose run recomputes the entry, if any.
    fn instance(&self) -> Option<&str> {
        match self {
            By::Instance(n) | By::LastRun(n) | By::CaseOf(n) => Some(n),
            By::SlurmManifest(_) => None,
        }
    }
}

/// Every store entry the pipeline references, `(kind, key)` → who references it. Entries that
/// do not exist (never run) are included: the caller decides whether that is damage.
pub fn references(plan: &Plan, store: &Store) -> BTreeMap<EntryId, BTreeSet<By>> {
    let mut refs: BTreeMap<EntryId, BTreeSet<By>> = BTreeMap::new();
    for p in &plan.planned {
        refs.entry((p.kind.clone(), p.key.clone()))
            .or_default()
            .insert(By::Instance(p.name.clone()));
        if let Some(m) = store.read_ref(&p.name) {
            if m.key != p.key || m.fingerprint.kind != p.kind {
                refs.entry((m.fingerprint.kind.clone(), m.key.clone()))
                    .or_default()
                    .insert(By::LastRun(p.name.clone()));
            }
        }
    }
    // Case entries (core::cases) live as long as a referenced stage entry lists them.
    let stage_entries: Vec<(EntryId, Vec<String>)> = refs
        .iter()
        .map(|(k, by)| {
            let names = by
                .iter()
                .filter_map(|b| b.instance().map(str::to_string))
                .collect();
            (k.clone(), names)
        })
        .collect();
    for ((kind, key), names) in stage_entries {
        let result = store.entry_dir(&kind, &key).join("result.json");
        let Some(v) = std::fs::read(&result)
            .ok()
            .and_then(|b| serde_json::from_slice::<Value>(&b).ok())
        else {
            continue;
        };
        for k in v["case_keys"].as_array().into_iter().flatten() {
            if let Some(k) = k.as_str() {
                let by = refs
                    .entry((CASE_KIND.to_string(), k.to_string()))
                    .or_default();
                by.extend(names.iter().map(|n| By::CaseOf(n.clone())));
            }
        }
    }
    // …and as long as a Slurm case manifest lists them: cases finished by a `--no-wait`
    // array before their stage ran are listed nowhere else yet.
    for path in crate::core::executor::list_manifests(store.processed()).unwrap_or_default() {
        if let Ok(m) = crate::core::executor::CaseManifest::read(&path) {
            let file = path
                .file_name()
                .map(|f| f.to_string_lossy().to_string())
                .unwrap_or_default();
            for e in &m.cases {
                refs.entry((CASE_KIND.to_string(), e.spec.key.clone()))
                    .or_default()
                    .insert(By::SlurmManifest(file.clone()));
            }
        }
    }
    refs
}

/// One damaged entry: its files do not match its manifest, or something points at it and it
/// is gone.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct DamagedEntry {
    /// Store kind: a stage kind (`surface`, `simulate`, …) or `case` (one slider case, DOE run
    /// or 3-DOF case).
    #[schemars(regex(pattern = r"^[a-z][a-z0-9_]*$"))]
    pub kind: String,
    /// Cache key of the entry (blake3 hex of its fingerprint).
    #[schemars(regex(pattern = r"^[0-9a-f]{16,64}$"))]
    pub key: String,
    /// The entry directory relative to processed/: `.hdi/store/<kind>/<key>`.
    pub path: String,
    /// Who references the entry: an instance name (its current key), `NAME (last run)` (what
    /// processed/NAME points at), `case of NAME` (listed under case_keys of NAME's entry),
    /// `Slurm manifest FILE`. Empty for an unreferenced entry checked with --all.
    pub referenced_by: Vec<String>,
    /// What is wrong, file by file.
    #[schemars(length(min = 1))]
    pub problems: Vec<FileProblem>,
    /// The instances whose run recomputes it (empty: nothing in the pipeline does).
    #[serde(skip)]
    pub instances: Vec<String>,
}

/// An entry the pipeline does not reference (what `hdi gc` would remove).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct OrphanEntry {
    /// Store kind.
    #[schemars(regex(pattern = r"^[a-z][a-z0-9_]*$"))]
    pub kind: String,
    /// Cache key.
    #[schemars(regex(pattern = r"^[0-9a-f]{16,64}$"))]
    pub key: String,
    /// Relative to processed/.
    pub path: String,
}

/// Which entries [`verify`] re-hashes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Scope {
    // Plain comments: variant doc comments would make the schema a `oneOf`, not an `enum`.
    // The entries the pipeline references.
    Pipeline,
    // Every entry in the store (`--all`).
    All,
}

/// What [`verify`] found.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct VerifyReport {
    /// `pipeline`: the entries the pipeline references were re-hashed; `all` (--all): every
    /// entry in the store.
    pub scope: Scope,
    /// Entries whose files were re-hashed.
    pub entries_checked: usize,
    /// Files re-hashed (the manifests' outputs).
    pub files_checked: usize,
    /// Bytes re-hashed.
    pub bytes_checked: u64,
    /// Entries whose files do not match their manifest, or that something points at and that
    /// are gone.
    pub damaged: Vec<DamagedEntry>,
    /// Entries in the store the pipeline does not reference (what `hdi gc` removes). Only
    /// reported; hashed only with --all.
    pub orphans: Vec<OrphanEntry>,
    /// Instances whose current key has no entry yet (never run, or stale: `hdi status` says
    /// why). Not damage.
    pub not_run: Vec<String>,
    /// Directories under processed/.hdi/tmp/: work directories of interrupted runs and entries
    /// quarantined by --repair (never trusted; `hdi gc` removes them).
    pub leftover_work_dirs: usize,
}

impl VerifyReport {
    pub fn clean(&self) -> bool {
        self.damaged.is_empty()
    }
}

fn rel_path(kind: &str, key: &str) -> String {
    format!(".hdi/store/{kind}/{key}")
}

/// Re-hash the referenced entries (every entry with `all`) against their manifests.
/// Reads only: nothing in `processed/` is written.
pub fn verify(plan: &Plan, store: &Store, all: bool) -> VerifyReport {
    let refs = references(plan, store);
    let in_store: BTreeSet<(String, String)> = store
        .entries()
        .into_iter()
        .map(|(kind, key, _)| (kind, key))
        .collect();
    let mut report = VerifyReport {
        scope: if all { Scope::All } else { Scope::Pipeline },
        entries_checked: 0,
        files_checked: 0,
        bytes_checked: 0,
        damaged: Vec::new(),
        orphans: Vec::new(),
        not_run: Vec::new(),
        leftover_work_dirs: store.tmp_dirs().len(),
    };
    let mut to_check: Vec<(EntryId, Option<&BTreeSet<By>>)> = Vec::new();
    for (k, by) in &refs {
        to_check.push((k.clone(), Some(by)));
    }
    for k in &in_store {
        if !refs.contains_key(k) {
            report.orphans.push(OrphanEntry {
                kind: k.0.clone(),
                key: k.1.clone(),
                path: rel_path(&k.0, &k.1),
            });
            if all {
                to_check.push((k.clone(), None));
            }
        }
    }
    to_check.sort_by(|a, b| a.0.cmp(&b.0));
    for ((kind, key), by) in to_check {
        let labels: Vec<String> = by
            .into_iter()
            .flatten()
            .map(By::label)
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        let instances: Vec<String> = by
            .into_iter()
            .flatten()
            .filter_map(|b| b.instance().map(str::to_string))
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        let problems = match store.check_entry(&kind, &key) {
            Some(check) => {
                report.entries_checked += 1;
                report.files_checked += check.files;
                report.bytes_checked += check.bytes;
                check.problems
            }
            None => {
                let by = by.cloned().unwrap_or_default();
                // Never run (or stale) is not damage; an entry that something points at and
                // that is gone is.
                let pointed_at = by
                    .iter()
                    .any(|b| matches!(b, By::LastRun(_) | By::CaseOf(_)))
                    || by.iter().any(|b| match b {
                        By::Instance(n) => store.read_ref(n).is_some_and(|m| m.key == key),
                        _ => false,
                    });
                if !pointed_at {
                    for b in &by {
                        if let By::Instance(n) = b {
                            report.not_run.push(n.clone());
                        }
                    }
                    continue;
                }
                vec![FileProblem {
                    file: ".".into(),
                    problem: ProblemKind::Missing,
                    detail: "entry directory missing".into(),
                }]
            }
        };
        if !problems.is_empty() {
            report.damaged.push(DamagedEntry {
                path: rel_path(&kind, &key),
                kind,
                key,
                referenced_by: labels,
                problems,
                instances,
            });
        }
    }
    report.not_run.sort();
    report.not_run.dedup();
    report
}

/// What [`quarantine_damaged`] did.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Quarantined {
    /// Where each damaged entry went (relative to `processed/`).
    pub moved: Vec<String>,
    /// The instances to run (forced) so the engine recomputes what was moved: those whose
    /// entry, last run or case was damaged.
    pub rerun: Vec<String>,
}

/// Move every damaged entry of `report` out of the store (into `.hdi/tmp/`, which is never
/// trusted and which `hdi gc` empties) and list the instances to re-run. Takes the workspace
/// lock while it moves, so no run is reading the entries meanwhile (`observer` hears if it
/// waits for it).
pub fn quarantine_damaged(
    store: &Store,
    report: &VerifyReport,
    observer: &dyn crate::core::progress::RunObserver,
) -> std::io::Result<Quarantined> {
    let _lock = store.lock(observer)?;
    let mut q = Quarantined::default();
    let mut rerun = BTreeSet::new();
    for d in &report.damaged {
        if let Some(to) = store.quarantine(&d.kind, &d.key)? {
            let rel = to
                .strip_prefix(store.processed())
                .map(PathBuf::from)
                .unwrap_or(to);
            q.moved.push(rel.to_string_lossy().to_string());
        }
        rerun.extend(d.instances.iter().cloned());
    }
    q.rerun = rerun.into_iter().collect();
    Ok(q)
}
