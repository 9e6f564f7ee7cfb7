//! The `[simulate]` cases handed to an executor other than the local thread pool (issue 9,
//! `docs/slurm.md`): which cases of the pipeline are stale, and the worker that computes one
//! on a Slurm node through the same case cache (so the bytes are a local run's).

use crate::core::cache::{Store, Verification};
use crate::core::cases::{case_fingerprint, CASE_KIND};
use crate::core::config::PipelineFile;
use crate::core::executor::{CaseComputer, CaseFailure, CaseRegistry, CaseSpec};
use crate::engine::{plan, read_result, Plan, State};
use crate::error::{Error, Result};
use crate::slider::case::{simulate_case, MODEL_VERSION};
use crate::slider::doe_design::{design_cases, design_params};
use crate::slider::params::{SimulateConfig, SimulateParams};
use crate::slider::sweep::{continuation_starts, with_start, PreparedSweep};
use crate::stages::doe::{DoeConfig, DoeStage};
use crate::stages::FromConfig;
use serde_json::{json, Value};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Case kind of a 2-DOF sweep point.
pub const SIMULATE_CASE: &str = "simulate";
/// Case kind of a DOE design point (a 2-DOF case of the base sweep with another bulge).
pub const DOE_CASE: &str = "doe";

/// The sweep whose cases are prepared: a `[simulate]` instance's, or the base sweep of a
/// `[doe]` instance (uncalibrated by construction).
fn sweep_params(file: &PipelineFile, kind: &str, instance: &str) -> Result<SimulateParams> {
    match kind {
        SIMULATE_CASE => {
            let cfg = file
                .instance::<SimulateConfig>("simulate", instance)?
                .ok_or_else(|| Error::MissingInstance {
                    kind: "simulate",
                    name: instance.to_string(),
                })?;
            Ok(SimulateParams::from_config(file, instance, &cfg)?)
        }
        _ => Ok(doe_stage(file, instance)?.params.base),
    }
}

/// The `[doe.NAME]` instance, checked.
fn doe_stage(file: &PipelineFile, instance: &str) -> Result<DoeStage> {
    let cfg = file
        .instance::<DoeConfig>("doe", instance)?
        .ok_or_else(|| Error::MissingInstance {
            kind: "doe",
            name: instance.to_string(),
        })?;
    Ok(DoeStage::from_config(file, instance, &cfg)?)
}

/// The prepared sweep of a `[simulate]` or `[doe]` instance from the store's current upstream
/// entries (they must be fresh: the submitting run computes them first).
fn prepared(
    file: &PipelineFile,
    store: &Store,
    planned: &Plan,
    kind: &str,
    instance: &str,
) -> Result<PreparedSweep> {
    let params = sweep_params(file, kind, instance)?;
    let (mut results, mut dirs, mut keys) = (BTreeMap::new(), BTreeMap::new(), BTreeMap::new());
    for u in params.upstream() {
        let p = planned
            .planned
            .iter()
            .find(|p| p.name == u)
            .ok_or_else(|| Error::UpstreamNotReady {
                upstream: u.clone(),
                consumer: instance.to_string(),
                planned: false,
            })?;
        if p.state != State::Fresh {
            return Err(Error::UpstreamNotReady {
                upstream: u.clone(),
                consumer: instance.to_string(),
                planned: true,
            });
        }
        let dir = store.entry_dir(&p.kind, &p.key);
        results.insert(u.clone(), read_result(&dir)?);
        dirs.insert(u.clone(), dir);
        keys.insert(u.clone(), p.key.clone());
    }
    PreparedSweep::prepare(&params, &results, &dirs, |n| {
        keys.get(n).cloned().unwrap_or_default()
    })
}

/// The stale `[simulate]` and `[doe]` instances, as (case kind, name).
fn stale_instances(file: &PipelineFile, planned: &Plan) -> Vec<(&'static str, String)> {
    let stale = |name: &str| {
        planned
            .planned
            .iter()
            .any(|p| p.name == name && p.state != State::Fresh)
    };
    let sims = file
        .instance_names("simulate")
        .into_iter()
        .map(|n| (SIMULATE_CASE, n.to_string()));
    let does = file
        .instance_names("doe")
        .into_iter()
        .map(|n| (DOE_CASE, n.to_string()));
    sims.chain(does).filter(|(_, n)| stale(n)).collect()
}

/// The pipeline planned against the store (fingerprints hash every input file: done once).
fn plan_of(file: &PipelineFile, store: &Store) -> Result<Plan> {
    plan(crate::stages::build(file)?, store, &Default::default())
}

/// The upstream instances of every stale `[simulate]` and `[doe]` instance: what must be
/// current before their cases can be listed.
pub fn case_upstream(file: &PipelineFile, store: &Store) -> Result<Vec<String>> {
    let mut names = Vec::new();
    for (kind, name) in stale_instances(file, &plan_of(file, store)?) {
        for u in sweep_params(file, kind, &name)?.upstream() {
            if !names.contains(&u) {
                names.push(u);
            }
        }
    }
    Ok(names)
}

/// Every case of the stale `[simulate]` instances and the design cases of the stale `[doe]`
/// instances without a verified store entry, with the recipe a worker needs (`config` must be
/// the absolute path of the pipeline file). A DOE's annealing is sequential: it runs locally.
pub fn stale_cases(file: &PipelineFile, config: &Path, store: &Store) -> Result<Vec<CaseSpec>> {
    let mut specs = Vec::new();
    let missing = |key: &str| !matches!(store.verify(CASE_KIND, key), Verification::Fresh(_));
    let planned = plan_of(file, store)?;
    for (kind, name) in stale_instances(file, &planned) {
        let sweep = prepared(file, store, &planned, kind, &name)?;
        let dmw_key = sweep.dmw.as_ref().map(|d| d.1.as_str());
        // A branch-tracking sweep's cases start at their continuation equilibria
        // (docs/conventions.md): solved here, sequentially, as the stage does; the start is
        // part of each case's key and of its recipe.
        type Point = (Option<[f64; 3]>, f64, Option<[f64; 2]>);
        let points: Vec<Point> = if kind == SIMULATE_CASE && !sweep.params.branches.is_empty() {
            let mut grid = sweep.params.actuations.clone();
            grid.sort_by(|a, b| a.total_cmp(b));
            grid.dedup();
            let mut v = Vec::new();
            for &b in &sweep.params.branches {
                let track = sweep.dmw.as_ref().map(|d| &d.0);
                let starts = continuation_starts(&sweep.params, &grid, &sweep.isbl, track, b)?;
                v.extend(grid.iter().zip(starts).map(|(&a, s)| (None, a, Some(s))));
            }
            v
        } else if kind == SIMULATE_CASE {
            sweep
                .params
                .actuations
                .iter()
                .map(|&a| (None, a, None))
                .collect()
        } else {
            let doe = doe_stage(file, &name)?;
            design_cases(&doe.params.levels, &doe.params.actuations)
                .into_iter()
                .map(|(d, a)| (Some(d), a, None))
                .collect()
        };
        let mut listed = std::collections::HashSet::new();
        for (design, a, start) in points {
            let params = match (design, start) {
                (None, None) => sweep.case_params(a),
                (None, Some(s)) => {
                    with_start(&sweep.params, Some(s)).case_params(a, &sweep.contact_key, dmw_key)
                }
                (Some(d), _) => {
                    design_params(&sweep.params, &d, a)?.case_params(a, &sweep.contact_key, dmw_key)
                }
            };
            let key = case_fingerprint(MODEL_VERSION, &params).key();
            // Branches sharing an equilibrium share the case: list it once.
            if !missing(&key) || !listed.insert(key) {
                continue;
            }
            let recipe = json!({
                "config": config.display().to_string(),
                "instance": name,
                "actuation_m": a,
                "design_m": design,
                "static_start": start,
            });
            specs.push(CaseSpec::new(kind, MODEL_VERSION, params, recipe));
        }
    }
    Ok(specs)
}

/// Computes `simulate` and DOE cases; prepares each sweep once per process (a task runs a
/// range of cases of usually one sweep, in parallel).
struct SweepWorker {
    kind: &'static str,
    sweeps: Mutex<HashMap<(String, String), Arc<PreparedSweep>>>,
}

impl SweepWorker {
    fn new(kind: &'static str) -> Self {
        SweepWorker {
            kind,
            sweeps: Mutex::new(HashMap::new()),
        }
    }
}

impl CaseComputer for SweepWorker {
    fn compute(
        &self,
        recipe: &Value,
        store: &Store,
        dir: &Path,
    ) -> std::result::Result<Value, CaseFailure> {
        Ok(self.compute_recipe(recipe, store, dir)?)
    }
}

impl SweepWorker {
    fn compute_recipe(&self, recipe: &Value, store: &Store, dir: &Path) -> Result<Value> {
        let field = |k: &str| {
            recipe[k]
                .as_str()
                .map(str::to_string)
                .ok_or_else(|| Error::RecipeField {
                    kind: self.kind,
                    field: k.to_string(),
                })
        };
        let (config, instance) = (field("config")?, field("instance")?);
        let actuation = recipe["actuation_m"]
            .as_f64()
            .ok_or_else(|| Error::RecipeField {
                kind: self.kind,
                field: "actuation_m".into(),
            })?;
        let sweep = {
            let mut sweeps = self
                .sweeps
                .lock()
                .map_err(|_| Error::Stage("a worker thread panicked".into()))?;
            let k = (config.clone(), instance.clone());
            match sweeps.get(&k) {
                Some(s) => Arc::clone(s),
                None => {
                    let file = crate::stages::load(Path::new(&config))?;
                    let planned = plan_of(&file, store)?;
                    let s = Arc::new(prepared(&file, store, &planned, self.kind, &instance)?);
                    sweeps.insert(k, Arc::clone(&s));
                    s
                }
            }
        };
        let start = serde_json::from_value::<Option<[f64; 2]>>(recipe["static_start"].clone())
            .map_err(|_| Error::RecipeField {
                kind: self.kind,
                field: "static_start".into(),
            })?;
        match serde_json::from_value::<Option<[f64; 3]>>(recipe["design_m"].clone()) {
            Ok(None) if start.is_some() => simulate_case(
                &with_start(&sweep.params, start),
                actuation,
                &sweep.isbl,
                sweep.dmw.as_ref().map(|d| &d.0),
                dir,
            ),
            Ok(None) => sweep.compute_case(actuation, dir),
            Ok(Some(design)) => {
                let p = design_params(&sweep.params, &design, actuation)?;
                simulate_case(
                    &p,
                    actuation,
                    &sweep.isbl,
                    sweep.dmw.as_ref().map(|d| &d.0),
                    dir,
                )
            }
            Err(source) => Err(Error::RecipeDesign {
                kind: self.kind,
                source,
            }),
        }
    }
}

/// The workers `hdi exec-cases` dispatches to.
pub fn registry() -> CaseRegistry {
    let mut r = CaseRegistry::new();
    r.register(SIMULATE_CASE, SweepWorker::new(SIMULATE_CASE));
    r.register(DOE_CASE, SweepWorker::new(DOE_CASE));
    r.register(
        crate::stages::calibrate::CALIBRATION_CASE,
        super::distributed_calibration::CalibrationWorker::default(),
    );
    r
}
