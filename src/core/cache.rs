//! The content-addressed store under `processed/`: fingerprints, manifests, atomic commits,
//! verification, per-name refs, the input-hash accelerator and the workspace lock.
//!
//! Layout:
//! ```text
//! processed/
//!   <name> -> .hdi/store/<kind>/<key>     human-friendly symlink per stage instance
//!   tables/<kind>.parquet|csv|arrow       tidy summary tables (docs/tables.md)
//!   .hdi/store/<kind>/<key>/              one entry: outputs + manifest.json (written last)
//!   .hdi/refs/<name>.json                 fingerprint of the last run of that name (for `status`)
//!   .hdi/tmp/                             work dirs; renamed into the store on success
//!   .hdi/input-hashes.json                (path, size, mtime, ctime, inode) → blake3 accelerator
//!   .hdi/lock                             workspace lock (flock), holder's PID inside
//! ```

use crate::core::hash::{hash_file, hash_json};
use crate::core::progress::RunObserver;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use std::fs;
use std::io::{self, Write};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// Bumped when the manifest/fingerprint layout changes.
pub const SCHEMA_VERSION: u32 = 1;

/// Everything a stage instance's cache key is made of (docs/architecture.md, "The cache, precisely").
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Fingerprint {
    pub kind: String,
    pub model_version: String,
    /// Canonical parameters: defaults filled in, SI units.
    pub params: Value,
    /// Input files by role, with content hashes. Paths are informative only: not in the key.
    pub inputs: Vec<InputRecord>,
    /// Keys of the consumed stages, by name.
    pub upstream: Vec<UpstreamRecord>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct InputRecord {
    pub role: String,
    pub path: String,
    pub blake3: String,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct UpstreamRecord {
    pub name: String,
    pub key: String,
}

impl Fingerprint {
    /// The cache key: blake3 of the canonical JSON of everything but input paths.
    pub fn key(&self) -> String {
        let inputs: Vec<Value> = self
            .inputs
            .iter()
            .map(|i| serde_json::json!({"role": i.role, "blake3": i.blake3}))
            .collect();
        let upstream: Vec<Value> = self
            .upstream
            .iter()
            .map(|u| serde_json::json!({"name": u.name, "key": u.key}))
            .collect();
        hash_json(&serde_json::json!({
            "schema": SCHEMA_VERSION,
            "kind": self.kind,
            "model_version": self.model_version,
            "params": self.params,
            "inputs": inputs,
            "upstream": upstream,
        }))
    }

    /// The differences from an older fingerprint: why a stage is stale.
    pub fn explain_changes(&self, old: &Fingerprint) -> Vec<StaleReason> {
        let mut why = Vec::new();
        if self.kind != old.kind {
            why.push(StaleReason::Kind {
                old: old.kind.clone(),
                new: self.kind.clone(),
            });
        }
        if self.model_version != old.model_version {
            why.push(StaleReason::ModelVersion {
                old: old.model_version.clone(),
                new: self.model_version.clone(),
            });
        }
        diff_values("", &old.params, &self.params, &mut why);
        for new in &self.inputs {
            match old.inputs.iter().find(|o| o.role == new.role) {
                None => why.push(StaleReason::NewInput {
                    role: new.role.clone(),
                    path: new.path.clone(),
                }),
                Some(o) if o.blake3 != new.blake3 => why.push(StaleReason::InputChanged {
                    role: new.role.clone(),
                    path: new.path.clone(),
                }),
                _ => {}
            }
        }
        for o in &old.inputs {
            if !self.inputs.iter().any(|n| n.role == o.role) {
                why.push(StaleReason::InputRemoved {
                    role: o.role.clone(),
                });
            }
        }
        for new in &self.upstream {
            match old.upstream.iter().find(|o| o.name == new.name) {
                None => why.push(StaleReason::NewUpstream {
                    name: new.name.clone(),
                }),
                Some(o) if o.key != new.key => why.push(StaleReason::UpstreamChanged {
                    name: new.name.clone(),
                }),
                _ => {}
            }
        }
        why
    }
}

/// Why a stage instance must run (`hdi run --dry-run`, `hdi status`, the report, `hdi diff`);
/// displayed as one short phrase each.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StaleReason {
    /// `--force` named it.
    Forced,
    /// Its entry exists but does not match its manifest.
    Damaged(String),
    /// No entry and no earlier record of the instance.
    NeverRun,
    /// The same fingerprint ran before, but its entry is gone.
    OutputMissing,
    Kind {
        old: String,
        new: String,
    },
    ModelVersion {
        old: String,
        new: String,
    },
    /// A parameter at `path` (dotted) changed; `None` is unset. Values are shortened JSON.
    Param {
        path: String,
        old: Option<String>,
        new: Option<String>,
    },
    NewInput {
        role: String,
        path: String,
    },
    InputChanged {
        role: String,
        path: String,
    },
    InputRemoved {
        role: String,
    },
    NewUpstream {
        name: String,
    },
    UpstreamChanged {
        name: String,
    },
}

/// Written as its phrase (the report's key and `hdi diff --json` hold the phrases).
impl Serialize for StaleReason {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl StaleReason {
    /// The reasons as one line, `; ` between them.
    pub fn join(why: &[StaleReason]) -> String {
        why.iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join("; ")
    }

    /// The reasons as phrases.
    pub fn phrases(why: &[StaleReason]) -> Vec<String> {
        why.iter().map(ToString::to_string).collect()
    }
}

impl std::fmt::Display for StaleReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unset = |v: &Option<String>| v.clone().unwrap_or_else(|| "(unset)".into());
        match self {
            StaleReason::Forced => write!(f, "forced"),
            StaleReason::Damaged(why) => write!(f, "cached output damaged: {why}"),
            StaleReason::NeverRun => write!(f, "never run"),
            StaleReason::OutputMissing => write!(f, "cached output missing"),
            StaleReason::Kind { old, new } => write!(f, "kind {old} → {new}"),
            StaleReason::ModelVersion { old, new } => write!(f, "model version {old} → {new}"),
            StaleReason::Param { path, old, new } => {
                write!(f, "{path}: {} → {}", unset(old), unset(new))
            }
            StaleReason::NewInput { role, path } => write!(f, "new input {role} ({path})"),
            StaleReason::InputChanged { role, path } => write!(f, "input {role} changed ({path})"),
            StaleReason::InputRemoved { role } => write!(f, "input {role} removed"),
            StaleReason::NewUpstream { name } => write!(f, "now depends on {name}"),
            StaleReason::UpstreamChanged { name } => write!(f, "upstream {name} changed"),
        }
    }
}

fn short(v: &Value) -> String {
    let s = v.to_string();
    if s.len() > 60 {
        format!("{}…", &s[..57])
    } else {
        s
    }
}

fn diff_values(path: &str, old: &Value, new: &Value, out: &mut Vec<StaleReason>) {
    match (old, new) {
        (Value::Object(a), Value::Object(b)) => {
            let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
            for k in keys {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                match (a.get(k), b.get(k)) {
                    (Some(x), Some(y)) => diff_values(&p, x, y, out),
                    (None, Some(y)) => out.push(StaleReason::Param {
                        path: p,
                        old: None,
                        new: Some(short(y)),
                    }),
                    (Some(x), None) => out.push(StaleReason::Param {
                        path: p,
                        old: Some(short(x)),
                        new: None,
                    }),
                    (None, None) => {}
                }
            }
        }
        (a, b) if a != b => out.push(StaleReason::Param {
            path: path.to_string(),
            old: Some(short(a)),
            new: Some(short(b)),
        }),
        _ => {}
    }
}

/// One store entry's record, written last into the entry directory.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Manifest {
    pub schema_version: u32,
    pub key: String,
    pub name: String,
    pub fingerprint: Fingerprint,
    pub outputs: Vec<OutputRecord>,
    pub hdi_version: String,
    pub created: String,
    pub wall_time_s: f64,
    /// Facts about the run that made the entry (e.g. `cases_cached`), which depend on the
    /// store's state and timing and so are kept out of the results.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub run_log: BTreeMap<String, serde_json::Value>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct OutputRecord {
    /// Path relative to the entry directory.
    pub path: String,
    pub bytes: u64,
    pub blake3: String,
}

/// Result of checking a store entry against its manifest.
#[derive(Debug)]
pub enum Verification {
    Fresh(Box<Manifest>),
    Missing,
    Damaged(String),
}

/// Everything [`Store::check_entry`] found in one entry.
#[derive(Debug, Default)]
pub struct EntryCheck {
    /// The parsed manifest (`None` when it is missing or does not parse).
    pub manifest: Option<Box<Manifest>>,
    /// Files checked (listed in the manifest, or found when there is no manifest).
    pub files: usize,
    /// Bytes re-hashed.
    pub bytes: u64,
    /// Empty when the entry is intact.
    pub problems: Vec<FileProblem>,
}

/// One file of an entry that does not match its manifest.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FileProblem {
    /// File relative to the entry directory (`manifest.json` for the manifest itself, `.` for
    /// the whole entry directory).
    pub file: String,
    /// `changed`: size or blake3 differs from the manifest; `missing`: listed in the manifest
    /// (or the entry, or the manifest itself) but absent; `extra`: present but not listed;
    /// `unreadable`: cannot be read, or the manifest does not parse.
    pub problem: ProblemKind,
    /// The same in words (sizes when they differ).
    pub detail: String,
}

impl FileProblem {
    fn new(file: &str, problem: ProblemKind, detail: impl Into<String>) -> Self {
        Self {
            file: file.to_string(),
            problem,
            detail: detail.into(),
        }
    }
}

/// What is wrong with one file of an entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ProblemKind {
    /// Present, but its size or blake3 differs from the manifest's.
    Changed,
    /// Listed in the manifest (or the manifest itself), not on disk.
    Missing,
    /// On disk, not listed in the manifest.
    Extra,
    /// Cannot be read (permissions, I/O error) or, for the manifest, does not parse.
    Unreadable,
}

/// Files under `dir`, relative to `root`, in sorted order (unreadable directories are skipped:
/// their listed files then show up as unreadable or missing).
fn list_files(root: &Path, dir: &Path, out: &mut Vec<String>) {
    let Ok(rd) = fs::read_dir(dir) else { return };
    let mut v: Vec<_> = rd.flatten().collect();
    v.sort_by_key(|e| e.file_name());
    for e in v {
        let p = e.path();
        if e.file_type().is_ok_and(|t| t.is_dir()) {
            list_files(root, &p, out);
        } else if let Ok(rel) = p.strip_prefix(root) {
            out.push(rel.to_string_lossy().to_string());
        }
    }
}

pub struct Store {
    processed: PathBuf,
    meta: PathBuf,
}

impl Store {
    /// Open (creating if needed) the store under `processed`.
    pub fn open(processed: &Path) -> io::Result<Self> {
        let meta = processed.join(".hdi");
        for d in ["store", "refs", "tmp"] {
            fs::create_dir_all(meta.join(d))?;
        }
        Ok(Self {
            processed: processed.to_path_buf(),
            meta,
        })
    }

    /// Open read-only: does not create anything (for `status`).
    pub fn open_existing(processed: &Path) -> Self {
        Self {
            processed: processed.to_path_buf(),
            meta: processed.join(".hdi"),
        }
    }

    pub fn processed(&self) -> &Path {
        &self.processed
    }

    pub fn entry_dir(&self, kind: &str, key: &str) -> PathBuf {
        self.meta.join("store").join(kind).join(key)
    }

    /// A fresh work directory for one stage run.
    pub fn new_work_dir(&self, name: &str, key: &str) -> io::Result<PathBuf> {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0);
        let dir = self.meta.join("tmp").join(format!(
            "{name}-{}-{}-{nanos}",
            &key[..12.min(key.len())],
            std::process::id()
        ));
        fs::create_dir_all(&dir)?;
        Ok(dir)
    }

    /// Check an entry: manifest present and parseable, every output present with its checksum.
    pub fn verify(&self, kind: &str, key: &str) -> Verification {
        let dir = self.entry_dir(kind, key);
        let manifest_path = dir.join("manifest.json");
        if !dir.exists() {
            return Verification::Missing;
        }
        let manifest: Manifest = match fs::read(&manifest_path)
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
        {
            Some(m) => m,
            None => return Verification::Damaged("manifest missing or unreadable".into()),
        };
        if manifest.key != key {
            return Verification::Damaged("manifest belongs to another key".into());
        }
        for out in &manifest.outputs {
            let p = dir.join(&out.path);
            match hash_file(&p) {
                Ok(h) if h == out.blake3 => {}
                Ok(_) => {
                    return Verification::Damaged(format!("{} changed since written", out.path))
                }
                Err(_) => return Verification::Damaged(format!("{} missing", out.path)),
            }
        }
        Verification::Fresh(Box::new(manifest))
    }

    /// Every problem of one entry, not just the first (for `hdi verify`): each output the
    /// manifest lists is re-hashed (size and blake3), and files in the entry that the manifest
    /// does not list are reported as extra. `None` when the entry directory does not exist.
    pub fn check_entry(&self, kind: &str, key: &str) -> Option<EntryCheck> {
        let dir = self.entry_dir(kind, key);
        if !dir.is_dir() {
            return None;
        }
        let mut check = EntryCheck::default();
        let manifest: Option<Manifest> = match fs::read(dir.join("manifest.json")) {
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                check.problems.push(FileProblem::new(
                    "manifest.json",
                    ProblemKind::Missing,
                    "manifest missing",
                ));
                None
            }
            Err(e) => {
                check.problems.push(FileProblem::new(
                    "manifest.json",
                    ProblemKind::Unreadable,
                    format!("manifest unreadable: {e}"),
                ));
                None
            }
            Ok(bytes) => match serde_json::from_slice::<Manifest>(&bytes) {
                Ok(m) => Some(m),
                Err(e) => {
                    check.problems.push(FileProblem::new(
                        "manifest.json",
                        ProblemKind::Unreadable,
                        format!("manifest does not parse: {e}"),
                    ));
                    None
                }
            },
        };
        let mut on_disk = Vec::new();
        list_files(&dir, &dir, &mut on_disk);
        let Some(manifest) = manifest else {
            check.files = on_disk.len();
            return Some(check);
        };
        if manifest.key != key {
            check.problems.push(FileProblem::new(
                "manifest.json",
                ProblemKind::Changed,
                format!("manifest belongs to key {}", manifest.key),
            ));
        }
        let listed: std::collections::BTreeSet<&str> =
            manifest.outputs.iter().map(|o| o.path.as_str()).collect();
        for out in &manifest.outputs {
            let p = dir.join(&out.path);
            check.files += 1;
            match fs::metadata(&p) {
                Err(e) if e.kind() == io::ErrorKind::NotFound => check
                    .problems
                    .push(FileProblem::new(&out.path, ProblemKind::Missing, "missing")),
                Err(e) => check.problems.push(FileProblem::new(
                    &out.path,
                    ProblemKind::Unreadable,
                    format!("unreadable: {e}"),
                )),
                Ok(meta) => {
                    check.bytes += meta.len();
                    match hash_file(&p) {
                        Ok(h) if h == out.blake3 && meta.len() == out.bytes => {}
                        Ok(_) => check.problems.push(FileProblem::new(
                            &out.path,
                            ProblemKind::Changed,
                            format!(
                                "changed since written ({} bytes, manifest says {}; blake3 differs)",
                                meta.len(),
                                out.bytes
                            ),
                        )),
                        Err(e) => check.problems.push(FileProblem::new(
                            &out.path,
                            ProblemKind::Unreadable,
                            format!("unreadable: {e}"),
                        )),
                    }
                }
            }
        }
        for rel in on_disk {
            if rel != "manifest.json" && !listed.contains(rel.as_str()) {
                check.problems.push(FileProblem::new(
                    &rel,
                    ProblemKind::Extra,
                    "not in the manifest",
                ));
            }
        }
        check.manifest = Some(Box::new(manifest));
        Some(check)
    }

    /// Move an entry out of the store into `.hdi/tmp/` (never trusted; `hdi gc` removes it),
    /// so the next run recomputes it. Returns where it went, `None` if there was no entry.
    pub fn quarantine(&self, kind: &str, key: &str) -> io::Result<Option<PathBuf>> {
        let dir = self.entry_dir(kind, key);
        if !dir.exists() {
            return Ok(None);
        }
        let aside = self.new_work_dir(&format!("quarantine-{kind}"), key)?;
        fs::remove_dir(&aside)?;
        fs::rename(&dir, &aside)?;
        if let Some(parent) = dir.parent() {
            sync_dir(parent);
        }
        Ok(Some(aside))
    }

    /// Checksum the work dir's files, write the manifest last, fsync, and rename the whole
    /// directory into the store: a crash before the rename leaves only a tmp dir.
    pub fn commit(
        &self,
        work_dir: &Path,
        name: &str,
        fingerprint: &Fingerprint,
        wall_time_s: f64,
        run_log: BTreeMap<String, serde_json::Value>,
    ) -> io::Result<Manifest> {
        let key = fingerprint.key();
        let mut outputs = Vec::new();
        collect_outputs(work_dir, work_dir, &mut outputs)?;
        outputs.sort_by(|a, b| a.path.cmp(&b.path));
        let manifest = Manifest {
            schema_version: SCHEMA_VERSION,
            key: key.clone(),
            name: name.to_string(),
            fingerprint: fingerprint.clone(),
            outputs,
            hdi_version: env!("CARGO_PKG_VERSION").to_string(),
            created: now_iso8601(),
            wall_time_s,
            run_log,
        };
        let bytes = serde_json::to_vec_pretty(&manifest).map_err(io::Error::other)?;
        write_synced(&work_dir.join("manifest.json"), &bytes)?;
        sync_dir(work_dir);
        let dest = self.entry_dir(&fingerprint.kind, &key);
        if let Some(parent) = dest.parent() {
            fs::create_dir_all(parent)?;
        }
        if dest.exists() {
            // A damaged or forced entry: move it aside first so the rename can succeed.
            let aside = self.new_work_dir(&format!("{name}-old"), &key)?;
            fs::remove_dir(&aside)?;
            fs::rename(&dest, &aside)?;
            let _ = fs::remove_dir_all(&aside);
        }
        if let Err(e) = fs::rename(work_dir, &dest) {
            // Another process committed the same key between the check above and this rename
            // (two Slurm tasks, or a task and a local run): same key, same inputs, so a
            // verified entry there is as good as ours.
            if let Verification::Fresh(theirs) = self.verify(&fingerprint.kind, &key) {
                let _ = fs::remove_dir_all(work_dir);
                return Ok(*theirs);
            }
            // The kind stays (a full disk, a read-only store); the message names the entry.
            return Err(io::Error::new(e.kind(), format!("{}: {e}", dest.display())));
        }
        if let Some(parent) = dest.parent() {
            sync_dir(parent);
        }
        Ok(manifest)
    }

    pub fn read_ref(&self, name: &str) -> Option<Manifest> {
        let bytes = fs::read(self.meta.join("refs").join(format!("{name}.json"))).ok()?;
        serde_json::from_slice(&bytes).ok()
    }

    /// Record that `name` now means this entry, and point `processed/<name>` at it. Nothing is
    /// written when both already say so: a no-op run leaves `processed/` untouched.
    pub fn write_ref(&self, manifest: &Manifest) -> io::Result<()> {
        let name = &manifest.name;
        let unchanged = self
            .read_ref(name)
            .is_some_and(|old| old.key == manifest.key && old.created == manifest.created);
        if !unchanged {
            let bytes = serde_json::to_vec_pretty(manifest).map_err(io::Error::other)?;
            write_atomic(&self.meta.join("refs").join(format!("{name}.json")), &bytes)?;
        }
        let target = PathBuf::from(".hdi")
            .join("store")
            .join(&manifest.fingerprint.kind)
            .join(&manifest.key);
        let link = self.processed.join(name);
        let current = fs::read_link(&link).ok();
        if current.as_deref() != Some(target.as_path()) {
            let tmp = self
                .processed
                .join(format!(".{name}.link-{}", std::process::id()));
            let _ = fs::remove_file(&tmp);
            std::os::unix::fs::symlink(&target, &tmp)?;
            if link.exists() && fs::symlink_metadata(&link)?.is_dir() {
                let _ = fs::remove_file(&tmp);
                return Err(io::Error::other(format!(
                    "{} is a real directory, not hdi's link; move it away",
                    link.display()
                )));
            }
            fs::rename(&tmp, &link)?;
        }
        Ok(())
    }

    /// All names with refs.
    pub fn ref_names(&self) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(self.meta.join("refs"))
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| {
                e.file_name()
                    .to_str()
                    .and_then(|n| n.strip_suffix(".json"))
                    .map(str::to_string)
            })
            .collect();
        names.sort();
        names
    }

    pub fn remove_ref(&self, name: &str) -> io::Result<()> {
        let _ = fs::remove_file(self.meta.join("refs").join(format!("{name}.json")));
        let link = self.processed.join(name);
        if fs::symlink_metadata(&link).is_ok_and(|m| m.file_type().is_symlink()) {
            fs::remove_file(link)?;
        }
        Ok(())
    }

    /// Every (kind, key) entry in the store.
    pub fn entries(&self) -> Vec<(String, String, PathBuf)> {
        let mut out = Vec::new();
        for kind in fs::read_dir(self.meta.join("store"))
            .into_iter()
            .flatten()
            .flatten()
        {
            let kname = kind.file_name().to_string_lossy().to_string();
            for e in fs::read_dir(kind.path()).into_iter().flatten().flatten() {
                out.push((
                    kname.clone(),
                    e.file_name().to_string_lossy().to_string(),
                    e.path(),
                ));
            }
        }
        out.sort();
        out
    }

    /// Leftover work dirs (crashed or interrupted runs).
    pub fn tmp_dirs(&self) -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = fs::read_dir(self.meta.join("tmp"))
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.path())
            .collect();
        v.sort();
        v
    }

    /// Take the workspace lock, waiting while another run holds it (`observer` hears that it
    /// waits, and for whom).
    pub fn lock(&self, observer: &dyn RunObserver) -> io::Result<WorkspaceLock> {
        let path = self.meta.join("lock");
        let mut file = fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .read(true)
            .write(true)
            .open(&path)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(fs::TryLockError::WouldBlock) => {
                let holder = fs::read_to_string(&path).unwrap_or_default();
                observer.waiting_for_lock(holder.trim(), &path);
                file.lock()?;
            }
            Err(fs::TryLockError::Error(e)) => return Err(e),
        }
        file.set_len(0)?;
        write!(file, "{}", std::process::id())?;
        Ok(WorkspaceLock { _file: file })
    }

    /// Input hash with a stat-keyed accelerator (size, mtime, ctime, inode, device): any field
    /// differing forces a rehash, so the accelerator can never make a changed file look fresh
    /// unless all five agree.
    pub fn hash_input(&self, cache: &mut InputHashCache, path: &Path) -> io::Result<String> {
        let meta = fs::metadata(path)?;
        let stat = StatKey {
            size: meta.len(),
            mtime_ns: meta.mtime() as i128 * 1_000_000_000 + meta.mtime_nsec() as i128,
            ctime_ns: meta.ctime() as i128 * 1_000_000_000 + meta.ctime_nsec() as i128,
            inode: meta.ino(),
            dev: meta.dev(),
        };
        let abs = fs::canonicalize(path)?.to_string_lossy().to_string();
        if let Some((s, h)) = cache.entries.get(&abs) {
            if *s == stat {
                return Ok(h.clone());
            }
        }
        let h = hash_file(path)?;
        cache.entries.insert(abs, (stat, h.clone()));
        cache.dirty = true;
        Ok(h)
    }

    pub fn load_input_cache(&self) -> InputHashCache {
        let entries = fs::read(self.meta.join("input-hashes.json"))
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
            .unwrap_or_default();
        InputHashCache {
            entries,
            dirty: false,
        }
    }

    pub fn save_input_cache(&self, cache: &InputHashCache) -> io::Result<()> {
        if !cache.dirty {
            return Ok(());
        }
        let bytes = serde_json::to_vec(&cache.entries).map_err(io::Error::other)?;
        write_atomic(&self.meta.join("input-hashes.json"), &bytes)
    }
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
pub struct StatKey {
    size: u64,
    mtime_ns: i128,
    ctime_ns: i128,
    inode: u64,
    dev: u64,
}

#[derive(Debug, Default)]
pub struct InputHashCache {
    entries: BTreeMap<String, (StatKey, String)>,
    dirty: bool,
}

/// Held for the duration of a run; the OS releases it if the process dies.
pub struct WorkspaceLock {
    _file: fs::File,
}

fn collect_outputs(root: &Path, dir: &Path, out: &mut Vec<OutputRecord>) -> io::Result<()> {
    for e in fs::read_dir(dir)? {
        let e = e?;
        let p = e.path();
        if e.file_type()?.is_dir() {
            collect_outputs(root, &p, out)?;
        } else {
            let rel = p
                .strip_prefix(root)
                .map_err(io::Error::other)?
                .to_string_lossy()
                .to_string();
            if rel == "manifest.json" {
                continue;
            }
            // fsync each output before the rename publishes it.
            fs::File::open(&p)?.sync_all()?;
            out.push(OutputRecord {
                path: rel,
                bytes: e.metadata()?.len(),
                blake3: hash_file(&p)?,
            });
        }
    }
    Ok(())
}

fn write_synced(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut f = fs::File::create(path)?;
    f.write_all(bytes)?;
    f.sync_all()
}

fn sync_dir(dir: &Path) {
    if let Ok(d) = fs::File::open(dir) {
        let _ = d.sync_all();
    }
}

/// The filesystem reason a write under `processed` failed, in words, when the failure is the
/// disk's rather than hdi's: a full disk or quota, a read-only filesystem, a permission denied.
/// `message` is the failure's whole chain. HDF5's own write errors do not always carry the
/// errno, so a filesystem with (almost) no space left is also taken as the cause.
/// (docs/reliability.md, "Fault campaigns".)
pub fn filesystem_cause(processed: &Path, message: &str) -> Option<String> {
    let m = message.to_ascii_lowercase();
    let at = processed.display();
    if m.contains("no space left") || m.contains("os error 28") {
        return Some(format!("no space left on device (writing to {at})"));
    }
    if m.contains("quota exceeded") || m.contains("os error 122") {
        return Some(format!(
            "no space left: disk quota exceeded (writing to {at})"
        ));
    }
    let mentions_store = message.contains(&processed.to_string_lossy().to_string());
    if mentions_store && (m.contains("read-only file system") || m.contains("os error 30")) {
        return Some(format!("{at} is on a read-only filesystem"));
    }
    if mentions_store && (m.contains("permission denied") || m.contains("os error 13")) {
        return Some(format!("permission denied writing to {at}"));
    }
    match free_bytes(processed) {
        Some(free) if free < 64 * 1024 => Some(format!(
            "no space left on device (writing to {at}: {free} bytes free)"
        )),
        _ => None,
    }
}

/// Bytes an unprivileged user may still write on the filesystem holding `dir`.
pub fn free_bytes(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    // SAFETY: `c` is a valid NUL-terminated path and `s` a properly sized, writable statvfs.
    let mut s: libc::statvfs = unsafe { std::mem::zeroed() };
    let r = unsafe { libc::statvfs(c.as_ptr(), &mut s) };
    (r == 0).then(|| s.f_bavail as u64 * s.f_frsize as u64)
}

/// Write to a sibling temp file, fsync, rename: readers see the old or the new file, never half.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let parent = path.parent().unwrap_or_else(|| Path::new("."));
    fs::create_dir_all(parent)?;
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = parent.join(format!(".{file_name}.tmp-{}", std::process::id()));
    // A full disk fails the write half-way: remove the partial temp file, not only a failed
    // rename's.
    write_synced(&tmp, bytes)
        .and_then(|()| fs::rename(&tmp, path))
        .inspect_err(|_| {
            let _ = fs::remove_file(&tmp);
        })
}

/// Current UTC time as ISO 8601 (no external time crate needed for this).
pub fn now_iso8601() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let days = secs.div_euclid(86_400);
    let rem = secs.rem_euclid(86_400);
    // Civil-from-days (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn fp(cutoff: f64, input_hash: &str) -> Fingerprint {
        Fingerprint {
            kind: "surface".into(),
            model_version: "1".into(),
            params: json!({"filter_l": cutoff, "level": ["plane"]}),
            inputs: vec![InputRecord {
                role: "file".into(),
                path: "raw/a.gwy".into(),
                blake3: input_hash.into(),
            }],
            upstream: vec![],
        }
    }

    #[test]
    fn key_ignores_input_paths_but_not_contents() {
        let a = fp(5e-6, "aa");
        let mut moved = a.clone();
        moved.inputs[0].path = "elsewhere/a.gwy".into();
        assert_eq!(a.key(), moved.key());
        assert_ne!(a.key(), fp(5e-6, "ab").key());
        assert_ne!(a.key(), fp(2.5e-6, "aa").key());
    }

    #[test]
    fn changes_are_explained() {
        let why = fp(2.5e-6, "bb").explain_changes(&fp(5e-6, "aa"));
        assert_eq!(why.len(), 2, "{why:?}");
        assert!(
            why[0].to_string().starts_with("filter_l: 5e-6 → 2.5e-6"),
            "{why:?}"
        );
        assert!(
            matches!(&why[1], StaleReason::InputChanged { role, .. } if role == "file"),
            "{why:?}"
        );
        assert!(why[1].to_string().contains("input file changed"), "{why:?}");
    }

    #[test]
    fn fingerprints_survive_a_json_round_trip_exactly() {
        // Floats that a fast, non-round-trip parser gets wrong by one ulp.
        let mut a = fp(2.5e-7, "aa");
        a.params = json!({"x": 0.1 + 0.2, "y": 1.0 / 3.0, "z": 5.6e-310, "w": 6.02214076e23});
        let back: Fingerprint = serde_json::from_str(&serde_json::to_string(&a).unwrap()).unwrap();
        assert_eq!(a, back);
        assert!(a.explain_changes(&back).is_empty());
        assert_eq!(a.key(), back.key());
    }

    #[test]
    fn check_entry_names_every_changed_missing_and_extra_file() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let f = fp(5e-6, "aa");
        let work = store.new_work_dir("disk", &f.key()).unwrap();
        fs::write(work.join("a.txt"), b"alpha").unwrap();
        fs::create_dir_all(work.join("sub")).unwrap();
        fs::write(work.join("sub/b.txt"), b"beta").unwrap();
        let m = store
            .commit(&work, "disk", &f, 0.0, Default::default())
            .unwrap();
        let entry = store.entry_dir("surface", &m.key);
        let clean = store.check_entry("surface", &m.key).unwrap();
        assert!(clean.problems.is_empty(), "{:?}", clean.problems);
        assert_eq!((clean.files, clean.bytes), (2, 9));
        // Same size, one byte different: only the hash can tell.
        fs::write(entry.join("a.txt"), b"alphA").unwrap();
        fs::remove_file(entry.join("sub/b.txt")).unwrap();
        fs::write(entry.join("c.txt"), b"").unwrap();
        let got: Vec<(String, ProblemKind)> = store
            .check_entry("surface", &m.key)
            .unwrap()
            .problems
            .into_iter()
            .map(|p| (p.file, p.problem))
            .collect();
        assert_eq!(
            got,
            [
                ("a.txt".to_string(), ProblemKind::Changed),
                ("sub/b.txt".to_string(), ProblemKind::Missing),
                ("c.txt".to_string(), ProblemKind::Extra),
            ]
        );
        // A damaged manifest; a missing entry.
        fs::write(entry.join("manifest.json"), b"{").unwrap();
        let p = &store.check_entry("surface", &m.key).unwrap().problems;
        assert_eq!(
            (p[0].file.as_str(), p[0].problem),
            ("manifest.json", ProblemKind::Unreadable)
        );
        assert!(store.check_entry("surface", "0000").is_none());
        // Quarantine moves it into tmp/, where nothing is trusted.
        let aside = store.quarantine("surface", &m.key).unwrap().unwrap();
        assert!(aside.starts_with(dir.path().join(".hdi/tmp")) && aside.join("a.txt").is_file());
        assert!(matches!(
            store.verify("surface", &m.key),
            Verification::Missing
        ));
    }

    #[test]
    fn filesystem_causes_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        let at = p.display().to_string();
        let full = filesystem_cause(p, "x.h5: No space left on device (os error 28)").unwrap();
        assert!(
            full.starts_with("no space left on device") && full.contains(&at),
            "{full}"
        );
        let ro = filesystem_cause(
            p,
            &format!("{at}/.hdi/lock: Read-only file system (os error 30)"),
        );
        assert_eq!(ro.unwrap(), format!("{at} is on a read-only filesystem"));
        // Permission denied on a file outside processed/ (an input) is not the store's fault.
        assert_eq!(
            filesystem_cause(p, "raw/a.gwy: Permission denied (os error 13)"),
            None
        );
        assert_eq!(filesystem_cause(p, "case h_TFC = 1 nm: diverged"), None);
        assert!(free_bytes(p).is_some_and(|b| b > 0));
    }

    #[test]
    fn iso_dates_are_civil() {
        let s = now_iso8601();
        assert_eq!(s.len(), 20);
        assert!(s.starts_with("20"));
    }
}
