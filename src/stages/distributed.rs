//! The `[simulate]` cases handed to an executor other than the local thread pool (issue 9,
//! `docs/slurm.md`): which cases of the pipeline are stale, and the worker that computes one
//! on a Slurm node through the same case cache (so the bytes are a local run's).

use super::simulate::{PreparedSweep, SimulateStage, MODEL_VERSION};
use crate::core::cache::{Store, Verification};
use crate::core::cases::{case_fingerprint, CASE_KIND};
use crate::core::config::PipelineFile;
use crate::core::engine::{plan, read_result, Stage, State};
use crate::core::executor::{CaseComputer, CaseRegistry, CaseSpec};
use crate::error::{Error, Result};
use serde_json::{json, Value};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Case kind of a 2-DOF sweep point.
pub const SIMULATE_CASE: &str = "simulate";

/// The prepared sweep of `[simulate.<instance>]` from the store's current upstream entries
/// (they must be fresh: the submitting run computes them first).
fn prepared(file: &PipelineFile, store: &Store, instance: &str) -> Result<PreparedSweep> {
    let cfg = file
        .raw
        .simulate
        .get(instance)
        .ok_or_else(|| Error::Stage(format!("no [simulate.{instance}] in the pipeline")))?;
    let stage = SimulateStage::from_config(file, instance, cfg)?;
    let planned = plan(super::build(file)?, store, &Default::default())?;
    let (mut results, mut dirs, mut keys) = (BTreeMap::new(), BTreeMap::new(), BTreeMap::new());
    for u in stage.upstream() {
        let p = planned
            .planned
            .iter()
            .find(|p| p.name == u)
            .ok_or_else(|| Error::Stage(format!("upstream `{u}` of `{instance}` is unknown")))?;
        if p.state != State::Fresh {
            return Err(Error::Stage(format!(
                "upstream `{u}` of `{instance}` has no current result (run it first)"
            )));
        }
        let dir = store.entry_dir(&p.kind, &p.key);
        results.insert(u.clone(), read_result(&dir)?);
        dirs.insert(u.clone(), dir);
        keys.insert(u.clone(), p.key.clone());
    }
    stage.prepare(&results, &dirs, |n| {
        keys.get(n).cloned().unwrap_or_default()
    })
}

/// The upstream instances of every stale `[simulate]` instance: what must be current before
/// its cases can be listed.
pub fn simulate_upstream(file: &PipelineFile, store: &Store) -> Result<Vec<String>> {
    let planned = plan(super::build(file)?, store, &Default::default())?;
    let mut names = Vec::new();
    for (name, cfg) in &file.raw.simulate {
        let stale = planned
            .planned
            .iter()
            .any(|p| &p.name == name && p.state != State::Fresh);
        if stale {
            for u in SimulateStage::from_config(file, name, cfg)?.upstream() {
                if !names.contains(&u) {
                    names.push(u);
                }
            }
        }
    }
    Ok(names)
}

/// Every case of the stale `[simulate]` instances without a verified store entry, with the
/// recipe a worker needs (`config` must be the absolute path of the pipeline file).
pub fn stale_cases(file: &PipelineFile, config: &Path, store: &Store) -> Result<Vec<CaseSpec>> {
    let planned = plan(super::build(file)?, store, &Default::default())?;
    let mut specs = Vec::new();
    for name in file.raw.simulate.keys() {
        let fresh = planned
            .planned
            .iter()
            .any(|p| &p.name == name && p.state == State::Fresh);
        if fresh {
            continue;
        }
        let sweep = prepared(file, store, name)?;
        for &a in &sweep.params.actuations {
            let params = sweep.case_params(a);
            let key = case_fingerprint(MODEL_VERSION, &params).key();
            if matches!(store.verify(CASE_KIND, &key), Verification::Fresh(_)) {
                continue;
            }
            let recipe = json!({
                "config": config.display().to_string(),
                "instance": name,
                "actuation_m": a,
            });
            specs.push(CaseSpec::new(SIMULATE_CASE, MODEL_VERSION, params, recipe));
        }
    }
    Ok(specs)
}

/// Computes `simulate` cases; prepares each sweep once per process (a task runs a range of
/// cases of usually one sweep, in parallel).
#[derive(Default)]
struct SimulateWorker {
    sweeps: Mutex<HashMap<(String, String), Arc<PreparedSweep>>>,
}

impl CaseComputer for SimulateWorker {
    fn compute(&self, recipe: &Value, store: &Store, dir: &Path) -> Result<Value> {
        let field = |k: &str| {
            recipe[k]
                .as_str()
                .map(str::to_string)
                .ok_or_else(|| Error::Stage(format!("simulate recipe without `{k}`")))
        };
        let (config, instance) = (field("config")?, field("instance")?);
        let actuation = recipe["actuation_m"]
            .as_f64()
            .ok_or_else(|| Error::Stage("simulate recipe without `actuation_m`".into()))?;
        let sweep = {
            let mut sweeps = self
                .sweeps
                .lock()
                .map_err(|_| Error::Stage("a worker thread panicked".into()))?;
            let k = (config.clone(), instance.clone());
            match sweeps.get(&k) {
                Some(s) => Arc::clone(s),
                None => {
                    let file = PipelineFile::load(Path::new(&config))?;
                    let s = Arc::new(prepared(&file, store, &instance)?);
                    sweeps.insert(k, Arc::clone(&s));
                    s
                }
            }
        };
        sweep.compute_case(actuation, dir)
    }
}

/// The workers `hdi exec-cases` dispatches to.
pub fn registry() -> CaseRegistry {
    let mut r = CaseRegistry::new();
    r.register(SIMULATE_CASE, SimulateWorker::default());
    r
}
