//! The cases of the instances a run selects, handed to an executor other than the local
//! thread pool (issues 9, 21 and 31, `docs/slurm.md`): which are stale, and the one worker
//! that computes any kind of case on a Slurm node through the same case cache. The engine
//! names no stage kind: a stage with cases offers them through the stage contract's case
//! capability (`stages::case_engine`), whose preparation and computation its own local run
//! uses too, so a case's bytes do not depend on where it ran.

use crate::core::cache::{Store, Verification};
use crate::core::cases::{case_fingerprint, CASE_KIND};
use crate::core::config::PipelineFile;
use crate::core::executor::{CaseComputer, CaseFailure, CaseRegistry, CaseSpec};
use crate::engine::{plan, read_result, selection, Plan, State};
use crate::error::{Error, Result};
use crate::stages::case_engine::{CaseRecipe, PreparedCases, UpstreamEntries};
use crate::stages::Stage;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// The pipeline planned against the store (fingerprints hash every input file: done once).
fn plan_of(file: &PipelineFile, store: &Store) -> Result<Plan> {
    plan(crate::stages::build(file)?, store, &Default::default())
}

/// The stale instances `only` selects (the engine's own `--only` selection: the named
/// instances and what they consume; all when empty) whose cases an executor lists up front,
/// as indices into `planned.stages`.
fn stale_case_instances(planned: &Plan, only: &[String]) -> Result<Vec<usize>> {
    let selected: BTreeSet<String> = selection(planned, only)?;
    Ok(planned
        .planned
        .iter()
        .filter(|p| p.state != State::Fresh && selected.contains(&p.name))
        .map(|p| p.index)
        .filter(|&i| {
            planned.stages[i]
                .cases()
                .is_some_and(|(_, engine)| engine.listed_up_front())
        })
        .collect())
}

/// The current entries of `consumer`'s upstream instances (they must be fresh: the
/// submitting run computes them first).
fn upstream_entries(
    store: &Store,
    planned: &Plan,
    consumer: &dyn Stage,
) -> Result<UpstreamEntries> {
    let mut entries = UpstreamEntries::default();
    for u in consumer.upstream() {
        let p = planned
            .planned
            .iter()
            .find(|p| p.name == u)
            .ok_or_else(|| Error::UpstreamNotReady {
                upstream: u.clone(),
                consumer: consumer.name().to_string(),
                planned: false,
            })?;
        if p.state != State::Fresh {
            return Err(Error::UpstreamNotReady {
                upstream: u.clone(),
                consumer: consumer.name().to_string(),
                planned: true,
            });
        }
        let dir = store.entry_dir(&p.kind, &p.key);
        entries.results.insert(u.clone(), read_result(&dir)?);
        entries.dirs.insert(u.clone(), dir);
        entries.keys.insert(u, p.key.clone());
    }
    Ok(entries)
}

/// The upstream instances of every stale case-carrying instance `only` selects: what must be
/// current before their cases can be listed.
pub fn case_upstream(file: &PipelineFile, store: &Store, only: &[String]) -> Result<Vec<String>> {
    let planned = plan_of(file, store)?;
    let mut names = Vec::new();
    for i in stale_case_instances(&planned, only)? {
        for u in planned.stages[i].upstream() {
            if !names.contains(&u) {
                names.push(u);
            }
        }
    }
    Ok(names)
}

/// Of the instances `only` selects (all when empty): every case the stale case-carrying
/// instances compute up front that has no verified store entry, with the recipe a worker
/// needs (`config` must be the absolute path of the pipeline file). Cases a stage adds while
/// it runs (a DOE's annealing, touchdown refinement) run locally when the stage runs.
pub fn stale_cases(
    file: &PipelineFile,
    config: &Path,
    store: &Store,
    only: &[String],
) -> Result<Vec<CaseSpec>> {
    let mut specs = Vec::new();
    let planned = plan_of(file, store)?;
    for i in stale_case_instances(&planned, only)? {
        let stage = planned.stages[i].as_ref();
        let Some((kind, engine)) = stage.cases() else {
            continue;
        };
        let upstream = upstream_entries(store, &planned, stage)?;
        let prepared = engine.prepare_cases(&upstream)?;
        let refs = upstream.refs(store.processed());
        let mut listed = HashSet::new();
        for case in prepared.cases()? {
            let key = case_fingerprint(prepared.model_version(), &case.params).key();
            // Computed already, or listed once (branches sharing an equilibrium share a case).
            let fresh = matches!(store.verify(CASE_KIND, &key), Verification::Fresh(_));
            if fresh || !listed.insert(key.clone()) {
                continue;
            }
            // The key travels in the recipe: the worker re-derives the case's parameters and
            // refuses to file a case whose key differs (the file edited since submission).
            let recipe = CaseRecipe {
                config: config.display().to_string(),
                instance: stage.name().to_string(),
                upstream: refs.clone(),
                case: case.case,
                key,
            };
            let recipe = serde_json::to_value(&recipe).map_err(|source| Error::Recipe {
                kind: kind.to_string(),
                source,
            })?;
            specs.push(CaseSpec::new(
                kind,
                prepared.model_version(),
                case.params,
                recipe,
            ));
        }
    }
    Ok(specs)
}

/// A preparation's identity: pipeline file, instance and the upstream entries' keys.
type PreparationId = (String, String, Vec<String>);

/// Computes any kind of case from its recipe; prepares each instance once per process and
/// set of upstream entries (a task runs a range of cases of usually one instance, in
/// parallel).
struct CaseWorker {
    kind: &'static str,
    /// The `pipeline.toml` section whose instances have cases of this kind.
    section: &'static str,
    prepared: Mutex<HashMap<PreparationId, Arc<dyn PreparedCases>>>,
}

impl CaseWorker {
    fn new(kind: &'static str, section: &'static str) -> Self {
        CaseWorker {
            kind,
            section,
            prepared: Mutex::new(HashMap::new()),
        }
    }

    /// The instance's prepared cases: from the pipeline file (that instance alone) and the
    /// upstream entries the recipe names.
    fn prepared(&self, recipe: &CaseRecipe, store: &Store) -> Result<Arc<dyn PreparedCases>> {
        let id = (
            recipe.config.clone(),
            recipe.instance.clone(),
            recipe.upstream.iter().map(|u| u.key.clone()).collect(),
        );
        let mut cache = self.prepared.lock().map_err(|_| Error::WorkerPanicked)?;
        if let Some(p) = cache.get(&id) {
            return Ok(Arc::clone(p));
        }
        let not = |why| Error::CaseInstance {
            kind: self.kind.to_string(),
            section: self.section.to_string(),
            instance: recipe.instance.clone(),
            config: recipe.config.clone(),
            why,
        };
        let file = crate::stages::load(Path::new(&recipe.config))?;
        let stage = crate::stages::build_instance(&file, self.section, &recipe.instance)?
            .ok_or_else(|| not("does not exist (the file changed since submission?)"))?;
        let (kind, engine) = stage.cases().ok_or_else(|| not("has no cases"))?;
        if kind != self.kind {
            return Err(not("has cases of another kind"));
        }
        let upstream = UpstreamEntries::read(store, &recipe.upstream)?;
        let prepared = engine.prepare_cases(&upstream)?;
        cache.insert(id, Arc::clone(&prepared));
        Ok(prepared)
    }

    fn compute_recipe(&self, recipe: &Value, store: &Store, dir: &Path) -> Result<Value> {
        let recipe: CaseRecipe =
            serde_json::from_value(recipe.clone()).map_err(|source| Error::Recipe {
                kind: self.kind.to_string(),
                source,
            })?;
        let prepared = self.prepared(&recipe, store)?;
        let params = prepared.case_params(&recipe.case)?;
        let derived = case_fingerprint(prepared.model_version(), &params).key();
        if derived != recipe.key {
            return Err(Error::CaseKeyMismatch {
                kind: self.kind.to_string(),
                case: format!("{}/{}", recipe.instance, recipe.case),
                derived,
                submitted: recipe.key,
            });
        }
        prepared.compute(&recipe.case, dir)
    }
}

impl CaseComputer for CaseWorker {
    fn compute(
        &self,
        recipe: &Value,
        store: &Store,
        dir: &Path,
    ) -> std::result::Result<Value, CaseFailure> {
        Ok(self.compute_recipe(recipe, store, dir)?)
    }
}

/// The workers `hdi exec-cases` dispatches to: one per case kind of the stage registry.
pub fn registry() -> CaseRegistry {
    let mut r = CaseRegistry::new();
    let kinds: BTreeMap<&'static str, &'static str> =
        crate::stages::case_kinds().into_iter().collect();
    for (kind, section) in kinds {
        r.register(kind, CaseWorker::new(kind, section));
    }
    r
}
