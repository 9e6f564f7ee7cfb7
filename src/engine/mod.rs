//! The pipeline engine: the stage instances' dependency graph, plan (fresh/stale and why), run
//! with a thread pool (reporting to a `RunObserver`), status, gc. Above the stages: it drives
//! them through the [`Stage`] contract they define.
pub mod alone;
pub mod diff;
pub mod distributed;
pub mod verify;

use crate::core::cache::{
    Fingerprint, InputRecord, Manifest, StaleReason, Store, UpstreamRecord, Verification,
};
use crate::core::executor::batch::BatchRunner;
use crate::core::progress::{Progress, RunObserver};
use crate::error::{Error, Result};
use crate::stages::{Stage, StageContext};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::time::Instant;

/// Per-instance state in a plan.
#[derive(Debug, Clone, PartialEq)]
pub enum State {
    /// Cached and verified.
    Fresh,
    /// Must run; the reasons say why.
    Stale(Vec<StaleReason>),
}

pub struct Planned {
    pub index: usize,
    pub name: String,
    pub kind: String,
    pub fingerprint: Fingerprint,
    pub key: String,
    pub state: State,
    pub manifest: Option<Manifest>,
}

/// A pipeline with its fingerprints computed and checked against the store.
pub struct Plan {
    pub stages: Vec<Box<dyn Stage>>,
    /// In topological order.
    pub planned: Vec<Planned>,
}

/// Topological order of the stages (upstream first); errors on unknown names and cycles.
pub fn topo_order(stages: &[Box<dyn Stage>]) -> Result<Vec<usize>> {
    let index: BTreeMap<&str, usize> = stages
        .iter()
        .enumerate()
        .map(|(i, s)| (s.name(), i))
        .collect();
    let mut order = Vec::new();
    let mut mark = vec![0u8; stages.len()]; // 0 new, 1 visiting, 2 done
    fn visit(
        i: usize,
        stages: &[Box<dyn Stage>],
        index: &BTreeMap<&str, usize>,
        mark: &mut [u8],
        order: &mut Vec<usize>,
    ) -> Result<()> {
        match mark[i] {
            2 => return Ok(()),
            1 => return Err(Error::DependencyCycle(stages[i].name().to_string())),
            _ => {}
        }
        mark[i] = 1;
        for up in stages[i].upstream() {
            let j = *index
                .get(up.as_str())
                .ok_or_else(|| Error::UndeclaredUpstream {
                    stage: stages[i].name().to_string(),
                    upstream: up.clone(),
                })?;
            visit(j, stages, index, mark, order)?;
        }
        mark[i] = 2;
        order.push(i);
        Ok(())
    }
    for i in 0..stages.len() {
        visit(i, stages, &index, &mut mark, &mut order)?;
    }
    Ok(order)
}

/// Compute every stage's fingerprint (hashing input files through the stat accelerator) and
/// check the store; instances named in `force` are stale even when cached.
pub fn plan(stages: Vec<Box<dyn Stage>>, store: &Store, force: &BTreeSet<String>) -> Result<Plan> {
    plan_inner(stages, store, force, true)
}

/// [`plan`] without saving the input-hash accelerator: writes nothing (for `hdi diff`, which
/// only reads the directories it compares).
pub fn plan_read_only(stages: Vec<Box<dyn Stage>>, store: &Store) -> Result<Plan> {
    plan_inner(stages, store, &BTreeSet::new(), false)
}

fn plan_inner(
    stages: Vec<Box<dyn Stage>>,
    store: &Store,
    force: &BTreeSet<String>,
    save_accelerator: bool,
) -> Result<Plan> {
    let order = topo_order(&stages)?;
    let mut input_cache = store.load_input_cache();
    let mut keys: BTreeMap<String, String> = BTreeMap::new();
    let mut planned = Vec::new();
    for i in order {
        let s = &stages[i];
        let mut inputs = Vec::new();
        for (role, path) in s.inputs() {
            let blake3 = store
                .hash_input(&mut input_cache, &path)
                .map_err(|source| Error::Input {
                    path: path.clone(),
                    source,
                })?;
            inputs.push(InputRecord {
                role,
                path: path.to_string_lossy().to_string(),
                blake3,
            });
        }
        let upstream = s
            .upstream()
            .into_iter()
            .map(|name| UpstreamRecord {
                key: keys.get(&name).cloned().unwrap_or_default(),
                name,
            })
            .collect();
        let fingerprint = Fingerprint {
            kind: s.kind().to_string(),
            model_version: s.model_version().to_string(),
            params: s.params(),
            inputs,
            upstream,
        };
        let key = fingerprint.key();
        keys.insert(s.name().to_string(), key.clone());
        let (state, manifest) = match store.verify(s.kind(), &key) {
            Verification::Fresh(m) if !force.contains(s.name()) => (State::Fresh, Some(*m)),
            Verification::Fresh(m) => (State::Stale(vec![StaleReason::Forced]), Some(*m)),
            Verification::Damaged(why) => (State::Stale(vec![StaleReason::Damaged(why)]), None),
            Verification::Missing => {
                let why = match store.read_ref(s.name()) {
                    None => vec![StaleReason::NeverRun],
                    Some(old) => {
                        let w = fingerprint.explain_changes(&old.fingerprint);
                        if w.is_empty() {
                            vec![StaleReason::OutputMissing]
                        } else {
                            w
                        }
                    }
                };
                (State::Stale(why), None)
            }
        };
        planned.push(Planned {
            index: i,
            name: s.name().to_string(),
            kind: s.kind().to_string(),
            fingerprint,
            key,
            state,
            manifest,
        });
    }
    // The accelerator is an optimisation: failing to save it only costs a rehash next time.
    if save_accelerator {
        let _ = store.save_input_cache(&input_cache);
    }
    Ok(Plan { stages, planned })
}

/// Options of `hdi run`.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    pub only: Vec<String>,
    pub force: bool,
    pub dry_run: bool,
    pub jobs: usize,
    /// Given to every stage as `StageContext::batch` (the calibration's rounds on Slurm).
    pub batch: Option<std::sync::Arc<dyn crate::core::executor::batch::BatchRunner>>,
}

/// What happened to each instance.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    Cached,
    Ran { seconds: f64 },
    Failed(String),
    Skipped(String),
    WouldRun(Vec<StaleReason>),
}

pub struct RunReport {
    pub outcomes: Vec<(String, Outcome)>,
    /// (name, kind, key) of every instance whose entry is now current (ran, or cached whether
    /// selected by `--only` or not): what the summary tables are built from.
    pub current: Vec<(String, String, String)>,
}

impl RunReport {
    pub fn count(&self, f: impl Fn(&Outcome) -> bool) -> usize {
        self.outcomes.iter().filter(|(_, o)| f(o)).count()
    }
    pub fn failed(&self) -> usize {
        self.count(|o| matches!(o, Outcome::Failed(_) | Outcome::Skipped(_)))
    }
}

/// The stages named in `only` plus everything they consume (transitively); all when `only`
/// is empty. `hdi run --only` runs this set, and the Slurm executor submits the cases of
/// this set (`engine::distributed`).
pub fn selection(plan: &Plan, only: &[String]) -> Result<BTreeSet<String>> {
    let all: BTreeSet<String> = plan.planned.iter().map(|p| p.name.clone()).collect();
    if only.is_empty() {
        return Ok(all);
    }
    let by_name: BTreeMap<&str, &Box<dyn Stage>> =
        plan.stages.iter().map(|s| (s.name(), s)).collect();
    let mut sel = BTreeSet::new();
    let mut todo: Vec<String> = only.to_vec();
    while let Some(n) = todo.pop() {
        let stage = by_name.get(n.as_str()).ok_or_else(|| {
            let names: Vec<&str> = by_name.keys().copied().collect();
            let hint = crate::core::config::nearest(&n, &names)
                .map(|c| format!(" (did you mean `{c}`?)"))
                .unwrap_or_default();
            Error::UnknownStage {
                name: n.clone(),
                hint,
            }
        })?;
        if sel.insert(n.clone()) {
            todo.extend(stage.upstream());
        }
    }
    Ok(sel)
}

/// Run the pipeline: stale instances in dependency order, independent ones in parallel;
/// `observer` hears which instances start and end.
pub fn run(
    stages: Vec<Box<dyn Stage>>,
    store: &Store,
    opts: &RunOptions,
    observer: &dyn RunObserver,
) -> Result<RunReport> {
    let _lock = if opts.dry_run {
        None
    } else {
        Some(store.lock(observer).map_err(|e| {
            // A read-only or forbidden processed/ is refused here, before anything runs.
            let lock = store.processed().join(".hdi").join("lock");
            let msg = format!("{}: {e}", lock.display());
            match crate::core::cache::filesystem_cause(store.processed(), &msg) {
                Some(cause) => Error::LockRefused {
                    cause,
                    lock,
                    error: e,
                },
                None => Error::io(lock, e),
            }
        })?)
    };
    let force = forced(&stages, opts);
    let plan = plan(stages, store, &force)?;
    let selected = selection(&plan, &opts.only)?;

    if opts.dry_run {
        return Ok(dry_run_report(&plan, &selected));
    }

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.jobs.max(1))
        .build()
        .map_err(|error| Error::WorkerThreads { error })?;

    let to_run: Vec<usize> = (0..plan.planned.len())
        .filter(|&i| {
            selected.contains(&plan.planned[i].name)
                && matches!(plan.planned[i].state, State::Stale(_))
        })
        .collect();
    observer.run_started(to_run.len());

    let mut settled = read_fresh(&plan, &selected, store);
    let batch = opts.batch.as_deref();
    run_waves(&plan, store, &pool, observer, to_run, &mut settled, batch);
    observer.run_finished();

    report(&plan, store, settled)
}

/// The instances `--force` re-runs: those named by `--only`, else all.
fn forced(stages: &[Box<dyn Stage>], opts: &RunOptions) -> BTreeSet<String> {
    let names: Vec<String> = stages.iter().map(|s| s.name().to_string()).collect();
    if opts.force {
        if opts.only.is_empty() {
            names.iter().cloned().collect()
        } else {
            opts.only.iter().cloned().collect()
        }
    } else {
        BTreeSet::new()
    }
}

/// What `--dry-run` reports: the selected instances, cached or why they would run.
fn dry_run_report(plan: &Plan, selected: &BTreeSet<String>) -> RunReport {
    let outcomes = plan
        .planned
        .iter()
        .filter(|p| selected.contains(&p.name))
        .map(|p| {
            let o = match &p.state {
                State::Fresh => Outcome::Cached,
                State::Stale(why) => Outcome::WouldRun(why.clone()),
            };
            (p.name.clone(), o)
        })
        .collect();
    RunReport {
        outcomes,
        current: Vec::new(),
    }
}

/// The instances settled so far, by name.
#[derive(Default)]
struct Settled {
    /// `result.json`, or why there is none.
    results: BTreeMap<String, std::result::Result<Value, String>>,
    manifests: BTreeMap<String, Manifest>,
    outcomes: BTreeMap<String, Outcome>,
}

impl Settled {
    /// Records one executed instance; "skipped: …" errors are skips, not failures.
    fn record(&mut self, name: String, r: Executed) {
        match r {
            Ok((value, manifest, secs)) => {
                self.results.insert(name.clone(), Ok(value));
                self.manifests.insert(name.clone(), manifest);
                self.outcomes.insert(name, Outcome::Ran { seconds: secs });
            }
            Err(e) => {
                let o = if e.starts_with("skipped:") {
                    Outcome::Skipped(e.trim_start_matches("skipped: ").to_string())
                } else {
                    Outcome::Failed(e.clone())
                };
                self.results.insert(name.clone(), Err(e));
                self.outcomes.insert(name, o);
            }
        }
    }
}

/// The selected fresh instances, settled from their cached `result.json`.
fn read_fresh(plan: &Plan, selected: &BTreeSet<String>, store: &Store) -> Settled {
    let mut s = Settled::default();
    for p in &plan.planned {
        if let (State::Fresh, Some(m)) = (&p.state, &p.manifest) {
            if selected.contains(&p.name) {
                let dir = store.entry_dir(&p.kind, &p.key);
                match read_result(&dir) {
                    Ok(v) => {
                        s.results.insert(p.name.clone(), Ok(v));
                        s.manifests.insert(p.name.clone(), m.clone());
                        s.outcomes.insert(p.name.clone(), Outcome::Cached);
                    }
                    Err(e) => {
                        let e = crate::error::chain(&e);
                        s.results.insert(p.name.clone(), Err(e.clone()));
                        s.outcomes.insert(p.name.clone(), Outcome::Failed(e));
                    }
                }
            }
        }
    }
    s
}

/// Waves: every stale instance whose upstream is settled runs in the current wave.
fn run_waves(
    plan: &Plan,
    store: &Store,
    pool: &rayon::ThreadPool,
    observer: &dyn RunObserver,
    to_run: Vec<usize>,
    settled: &mut Settled,
    batch: Option<&dyn BatchRunner>,
) {
    let mut remaining: Vec<usize> = to_run;
    while !remaining.is_empty() {
        let (ready, blocked): (Vec<usize>, Vec<usize>) = remaining.iter().partition(|&&i| {
            plan.stages[plan.planned[i].index]
                .upstream()
                .iter()
                .all(|u| settled.results.contains_key(u))
        });
        if ready.is_empty() {
            // Cannot happen with a valid topological order; guard against an infinite loop.
            for i in blocked {
                settled.outcomes.insert(
                    plan.planned[i].name.clone(),
                    Outcome::Skipped("upstream never settled".into()),
                );
            }
            break;
        }
        let results = &settled.results;
        let wave: Vec<(usize, Executed)> = pool.install(|| {
            use rayon::prelude::*;
            ready
                .par_iter()
                .map(|&i| (i, run_instance(plan, i, store, results, observer, batch)))
                .collect()
        });
        for (i, r) in wave {
            settled.record(plan.planned[i].name.clone(), r);
        }
        remaining = blocked;
    }
}

/// Runs planned instance `i` on its upstream results (skipped if one of them failed).
fn run_instance(
    plan: &Plan,
    i: usize,
    store: &Store,
    results: &BTreeMap<String, std::result::Result<Value, String>>,
    observer: &dyn RunObserver,
    batch: Option<&dyn BatchRunner>,
) -> Executed {
    let p = &plan.planned[i];
    let stage = &plan.stages[p.index];
    let mut upstream = BTreeMap::new();
    let mut upstream_dirs = BTreeMap::new();
    for u in stage.upstream() {
        match results.get(&u) {
            Some(Ok(v)) => {
                upstream.insert(u.clone(), v.clone());
            }
            _ => return Err(format!("skipped: upstream `{u}` failed")),
        }
        if let Some(up) = plan.planned.iter().find(|q| q.name == u) {
            upstream_dirs.insert(u, store.entry_dir(&up.kind, &up.key));
        }
    }
    let progress = observer.stage_started(&p.name);
    let r = execute(
        stage.as_ref(),
        p,
        store,
        upstream,
        upstream_dirs,
        progress.as_ref(),
        batch,
    );
    observer.stage_finished(&p.name, r.is_ok());
    r
}

/// Points the human-friendly names at the current entries and assembles the report in plan
/// order.
fn report(plan: &Plan, store: &Store, settled: Settled) -> Result<RunReport> {
    let Settled {
        manifests,
        mut outcomes,
        ..
    } = settled;
    for (name, m) in &manifests {
        store.write_ref(m).map_err(|e| {
            let path = store.processed().join(name);
            let msg = format!(
                "`{name}` ran, but pointing {} at its result failed: {e}",
                path.display()
            );
            match crate::core::cache::filesystem_cause(store.processed(), &msg) {
                Some(cause) => Error::RefNotWritten {
                    cause,
                    name: name.clone(),
                    path,
                    error: e,
                },
                None => Error::io(path, e),
            }
        })?;
    }
    let current = plan
        .planned
        .iter()
        .filter(|p| manifests.contains_key(&p.name) || p.state == State::Fresh)
        .map(|p| (p.name.clone(), p.kind.clone(), p.key.clone()))
        .collect();
    let outcomes = plan
        .planned
        .iter()
        .filter_map(|p| outcomes.remove(&p.name).map(|o| (p.name.clone(), o)))
        .collect();
    Ok(RunReport { outcomes, current })
}

/// A store entry's `result.json`.
pub use crate::stages::case_engine::read_result;

/// A finished stage: its result, its manifest and the seconds it took; or why it did not run.
type Executed = std::result::Result<(Value, Manifest, f64), String>;

/// Run one stage into a work dir, then commit it to the store.
fn execute(
    stage: &dyn Stage,
    p: &Planned,
    store: &Store,
    upstream: BTreeMap<String, Value>,
    upstream_dirs: BTreeMap<String, PathBuf>,
    progress: &dyn Progress,
    batch: Option<&dyn BatchRunner>,
) -> Executed {
    let started = Instant::now();
    // A full, read-only or forbidden processed/ says so first (docs/reliability.md), checked
    // before the work dir is removed (which frees the space again).
    let explain = |msg: String| {
        // One line: HDF5's error text carries a newline (after its timestamp).
        let msg = msg.replace('\n', " ");
        match crate::core::cache::filesystem_cause(store.processed(), &msg) {
            Some(cause) => format!("{cause}: {msg}"),
            None => msg,
        }
    };
    let work = store.new_work_dir(&p.name, &p.key).map_err(|e| {
        explain(format!(
            "cannot create a work dir in {}: {e}",
            store.processed().join(".hdi/tmp").display()
        ))
    })?;
    let ctx = StageContext {
        name: &p.name,
        key: &p.key,
        fingerprint: &p.fingerprint,
        out_dir: &work,
        upstream,
        upstream_dirs,
        store,
        progress,
        run_log: Default::default(),
        batch,
    };
    // A bug must not take the other stages down with it, nor leave a trusted output.
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| stage.run(&ctx)));
    let out = match outcome {
        Ok(Ok(out)) => out,
        Ok(Err(e)) => {
            let msg = explain(crate::error::chain(&e));
            let _ = std::fs::remove_dir_all(&work);
            return Err(msg);
        }
        Err(panic) => {
            let msg = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            let msg = explain(format!("internal error (please report): {msg}"));
            let _ = std::fs::remove_dir_all(&work);
            return Err(msg);
        }
    };
    // Inputs that changed while the stage ran would make the recorded hashes lie.
    for (role, path) in stage.inputs() {
        let now =
            crate::core::hash::hash_file(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        if p.fingerprint
            .inputs
            .iter()
            .any(|i| i.role == role && i.blake3 != now)
        {
            let _ = std::fs::remove_dir_all(&work);
            return Err(format!(
                "input {} changed while the stage ran; not recorded, run again",
                path.display()
            ));
        }
    }
    let mut result = out.result;
    if let (Some(row), Value::Object(map)) = (out.summary_row, &mut result) {
        map.insert("summary_row".into(), Value::Object(row));
    }
    let bytes = serde_json::to_vec_pretty(&result).map_err(|e| e.to_string())?;
    let result_path = work.join("result.json");
    if let Err(e) = std::fs::write(&result_path, bytes) {
        let msg = explain(format!("{}: {e}", result_path.display()));
        let _ = std::fs::remove_dir_all(&work);
        return Err(msg);
    }
    let secs = started.elapsed().as_secs_f64();
    let run_log = ctx.run_log.into_inner().unwrap_or_default();
    let manifest = store
        .commit(&work, &p.name, &p.fingerprint, secs, run_log)
        .map_err(|e| {
            let msg = explain(format!("cannot record the output in the store: {e}"));
            let _ = std::fs::remove_dir_all(&work);
            msg
        })?;
    Ok((result, manifest, secs))
}

/// Summary rows of the given instances grouped by kind, from their cached `result.json`.
pub fn summary_rows(
    store: &Store,
    plan: &[(String, String, String)],
) -> BTreeMap<String, Vec<serde_json::Map<String, Value>>> {
    let mut by_kind: BTreeMap<String, Vec<serde_json::Map<String, Value>>> = BTreeMap::new();
    for (name, kind, key) in plan {
        if let Ok(Value::Object(mut v)) = read_result(&store.entry_dir(kind, key)) {
            if let Some(Value::Object(row)) = v.remove("summary_row") {
                let mut r = serde_json::Map::new();
                r.insert("stage".into(), Value::String(name.clone()));
                r.extend(row);
                by_kind.entry(kind.clone()).or_default().push(r);
            }
        }
    }
    by_kind
}

/// `hdi gc`: remove store entries and refs not referenced by the current pipeline, and
/// leftover work dirs. Returns what was (or, with `dry_run`, would be) removed.
pub fn gc(
    plan: &Plan,
    store: &Store,
    dry_run: bool,
    observer: &dyn RunObserver,
) -> Result<Vec<PathBuf>> {
    let _lock = if dry_run {
        None
    } else {
        Some(
            store
                .lock(observer)
                .map_err(|e| Error::io(store.processed(), e))?,
        )
    };
    let current: BTreeSet<&str> = plan.planned.iter().map(|p| p.name.as_str()).collect();
    // What `hdi verify` calls referenced: current and last-run entries, the cases they list
    // and the cases of Slurm case manifests.
    let keep: BTreeSet<(String, String)> = verify::references(plan, store).into_keys().collect();
    let mut removed = Vec::new();
    for (kind, key, path) in store.entries() {
        if !keep.contains(&(kind, key)) {
            if !dry_run {
                std::fs::remove_dir_all(&path).map_err(|e| Error::io(&path, e))?;
            }
            removed.push(path);
        }
    }
    // Work dirs of Slurm tasks that may be running now live in tmp/ too: while a submitted
    // case manifest still has cases missing from the store, leave tmp/ alone.
    let slurm_pending = crate::core::executor::list_manifests(store.processed())
        .unwrap_or_default()
        .iter()
        .any(|path| {
            let submitted =
                crate::core::executor::read_submissions(path).is_ok_and(|s| !s.is_empty());
            submitted
                && crate::core::executor::CaseManifest::read(path)
                    .is_ok_and(|m| !m.still_missing(store).is_empty())
        });
    for t in store.tmp_dirs() {
        if slurm_pending {
            break;
        }
        if !dry_run {
            let _ = std::fs::remove_dir_all(&t);
        }
        removed.push(t);
    }
    for name in store.ref_names() {
        if !current.contains(name.as_str()) {
            if !dry_run {
                store
                    .remove_ref(&name)
                    .map_err(|e| Error::io(store.processed().join(&name), e))?;
            }
            removed.push(store.processed().join(&name));
        }
    }
    Ok(removed)
}

/// After `hdi run`: the summary tables from the current entries, one per kind. A table is
/// rewritten when something ran and nothing failed (a failed instance keeps its earlier row),
/// or when it is missing.
pub fn write_summary_tables(
    store: &crate::core::cache::Store,
    report: &RunReport,
) -> crate::error::Result<()> {
    let tables_dir = store.processed().join("tables");
    let ran = report.count(|o| matches!(o, Outcome::Ran { .. }));
    let failed = report.failed();
    for (kind, rows) in summary_rows(store, &report.current) {
        let stem = tables_dir.join(crate::stages::summary_table_name(&kind));
        if (ran > 0 && failed == 0)
            || ["parquet", "csv", "arrow"]
                .iter()
                .any(|ext| !stem.with_extension(ext).exists())
        {
            crate::core::store::write_table(&rows, &stem)?;
        }
    }
    Ok(())
}
