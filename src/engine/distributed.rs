//! The `[simulate]`, `[doe]` and `[three_dof]` cases handed to an executor other than the
//! local thread pool (issues 9 and 21, `docs/slurm.md`): which cases of the instances a run
//! selects are stale, and the workers that compute one on a Slurm node through the same case
//! cache (so the bytes are a local run's).

use crate::core::cache::{Store, Verification};
use crate::core::cases::{case_fingerprint, CASE_KIND};
use crate::core::config::PipelineFile;
use crate::core::executor::{CaseComputer, CaseFailure, CaseRegistry, CaseSpec};
use crate::engine::{plan, read_result, selection, Plan, State};
use crate::error::{Error, Result};
use crate::slider::case::{simulate_case, MODEL_VERSION};
use crate::slider::doe_design::{design_cases, design_params};
use crate::slider::params::{SimulateConfig, SimulateParams};
use crate::slider::sweep::{continuation_starts, with_start, PreparedSweep};
use crate::stages::doe::{DoeConfig, DoeStage};
use crate::stages::three_dof::{
    PreparedThreeDof, ThreeDofConfig, ThreeDofSolver, ThreeDofStage,
    MODEL_VERSION as THREE_DOF_MODEL_VERSION,
};
use crate::stages::FromConfig;
use serde_json::{json, Value};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Case kind of a 2-DOF sweep point.
pub const SIMULATE_CASE: &str = "simulate";
/// Case kind of a DOE design point (a 2-DOF case of the base sweep with another bulge).
pub const DOE_CASE: &str = "doe";
/// Case kind of a `[three_dof]` case (one interface of the instance's scenario).
pub const THREE_DOF_CASE: &str = "three_dof";

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

/// Results (`result.json`), entry directories and cache keys of upstream instances, by name.
type Upstream = (
    BTreeMap<String, Value>,
    BTreeMap<String, std::path::PathBuf>,
    BTreeMap<String, String>,
);

/// The [`Upstream`] of `consumer`'s upstream instances `names` from the store's current
/// entries (they must be fresh: the submitting run computes them first).
fn upstream_entries(
    store: &Store,
    planned: &Plan,
    consumer: &str,
    names: &[String],
) -> Result<Upstream> {
    let (mut results, mut dirs, mut keys) = (BTreeMap::new(), BTreeMap::new(), BTreeMap::new());
    for u in names {
        let p = planned
            .planned
            .iter()
            .find(|p| &p.name == u)
            .ok_or_else(|| Error::UpstreamNotReady {
                upstream: u.clone(),
                consumer: consumer.to_string(),
                planned: false,
            })?;
        if p.state != State::Fresh {
            return Err(Error::UpstreamNotReady {
                upstream: u.clone(),
                consumer: consumer.to_string(),
                planned: true,
            });
        }
        let dir = store.entry_dir(&p.kind, &p.key);
        results.insert(u.clone(), read_result(&dir)?);
        dirs.insert(u.clone(), dir);
        keys.insert(u.clone(), p.key.clone());
    }
    Ok((results, dirs, keys))
}

/// The prepared sweep of a `[simulate]` or `[doe]` instance from the store's current upstream
/// entries.
fn prepared(
    file: &PipelineFile,
    store: &Store,
    planned: &Plan,
    kind: &str,
    instance: &str,
) -> Result<PreparedSweep> {
    let params = sweep_params(file, kind, instance)?;
    let (results, dirs, keys) = upstream_entries(store, planned, instance, &params.upstream())?;
    PreparedSweep::prepare(&params, &results, &dirs, |n| {
        keys.get(n).cloned().unwrap_or_default()
    })
}

/// The `[three_dof.NAME]` instance, checked.
fn three_dof_stage(file: &PipelineFile, instance: &str) -> Result<ThreeDofStage> {
    let cfg = file
        .instance::<ThreeDofConfig>("three_dof", instance)?
        .ok_or_else(|| Error::MissingInstance {
            kind: "three_dof",
            name: instance.to_string(),
        })?;
    Ok(ThreeDofStage::from_config(file, instance, &cfg)?)
}

/// The upstream instances a case kind's instance consumes.
fn instance_upstream(file: &PipelineFile, kind: &str, instance: &str) -> Result<Vec<String>> {
    if kind == THREE_DOF_CASE {
        use crate::stages::StageKind;
        return Ok(three_dof_stage(file, instance)?.upstream());
    }
    Ok(sweep_params(file, kind, instance)?.upstream())
}

/// A `[three_dof]` instance prepared from the store's current upstream entries.
fn prepared_three_dof(
    file: &PipelineFile,
    store: &Store,
    planned: &Plan,
    instance: &str,
) -> Result<PreparedThreeDof> {
    let stage = three_dof_stage(file, instance)?;
    let upstream = instance_upstream(file, THREE_DOF_CASE, instance)?;
    let (results, dirs, keys) = upstream_entries(store, planned, instance, &upstream)?;
    PreparedThreeDof::prepare(&stage.params, &results, &dirs, |n| {
        keys.get(n).cloned().unwrap_or_default()
    })
}

/// The stale `[simulate]`, `[doe]` and `[three_dof]` instances among those `only` selects
/// (the engine's own `--only` selection: the named instances and what they consume; all when
/// empty), as (case kind, name).
fn stale_instances(
    file: &PipelineFile,
    planned: &Plan,
    only: &[String],
) -> Result<Vec<(&'static str, String)>> {
    let selected: BTreeSet<String> = selection(planned, only)?;
    let stale = |name: &str| {
        selected.contains(name)
            && planned
                .planned
                .iter()
                .any(|p| p.name == name && p.state != State::Fresh)
    };
    let of = |section: &str, kind: &'static str| {
        file.instance_names(section)
            .into_iter()
            .map(move |n| (kind, n.to_string()))
    };
    Ok(of("simulate", SIMULATE_CASE)
        .chain(of("doe", DOE_CASE))
        .chain(of("three_dof", THREE_DOF_CASE))
        .filter(|(_, n)| stale(n))
        .collect())
}

/// The pipeline planned against the store (fingerprints hash every input file: done once).
fn plan_of(file: &PipelineFile, store: &Store) -> Result<Plan> {
    plan(crate::stages::build(file)?, store, &Default::default())
}

/// The upstream instances of every stale case-carrying instance `only` selects: what must be
/// current before their cases can be listed.
pub fn case_upstream(file: &PipelineFile, store: &Store, only: &[String]) -> Result<Vec<String>> {
    let mut names = Vec::new();
    for (kind, name) in stale_instances(file, &plan_of(file, store)?, only)? {
        for u in instance_upstream(file, kind, &name)? {
            if !names.contains(&u) {
                names.push(u);
            }
        }
    }
    Ok(names)
}

/// Of the instances `only` selects (all when empty): every case of the stale `[simulate]` and
/// `[three_dof]` instances and the design cases of the stale `[doe]` instances without a
/// verified store entry, with the recipe a worker needs (`config` must be the absolute path
/// of the pipeline file). A DOE's annealing is sequential: it runs locally.
pub fn stale_cases(
    file: &PipelineFile,
    config: &Path,
    store: &Store,
    only: &[String],
) -> Result<Vec<CaseSpec>> {
    let mut specs = Vec::new();
    let missing = |key: &str| !matches!(store.verify(CASE_KIND, key), Verification::Fresh(_));
    let planned = plan_of(file, store)?;
    for (kind, name) in stale_instances(file, &planned, only)? {
        if kind == THREE_DOF_CASE {
            let prepared = prepared_three_dof(file, store, &planned, &name)?;
            for &which in &prepared.params.cases {
                let params = prepared.case_params(which);
                let key = case_fingerprint(THREE_DOF_MODEL_VERSION, &params).key();
                if !missing(&key) {
                    continue;
                }
                // The key travels in the recipe: the worker re-derives the case's parameters
                // from the pipeline file and refuses to file a case whose key differs (the
                // file edited between submission and the task).
                let recipe = json!({
                    "config": config.display().to_string(),
                    "instance": name,
                    "case": which.label(),
                    "key": key,
                });
                specs.push(CaseSpec::new(kind, THREE_DOF_MODEL_VERSION, params, recipe));
            }
            continue;
        }
        let sweep = prepared(file, store, &planned, kind, &name)?;
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
            let params = sweep_case_params(&sweep, design, a, start)?;
            let key = case_fingerprint(MODEL_VERSION, &params).key();
            // Branches sharing an equilibrium share the case: list it once.
            if !missing(&key) || !listed.insert(key.clone()) {
                continue;
            }
            let recipe = json!({
                "config": config.display().to_string(),
                "instance": name,
                "actuation_m": a,
                "design_m": design,
                "static_start": start,
                // The worker re-derives the key from the pipeline file and refuses to file
                // the case under this one if they differ (file edited since submission).
                "key": key,
            });
            specs.push(CaseSpec::new(kind, MODEL_VERSION, params, recipe));
        }
    }
    Ok(specs)
}

/// The key parameters of one sweep or DOE case, as the stages key it.
fn sweep_case_params(
    sweep: &PreparedSweep,
    design: Option<[f64; 3]>,
    actuation: f64,
    start: Option<[f64; 2]>,
) -> Result<Value> {
    let dmw_key = sweep.dmw.as_ref().map(|d| d.1.as_str());
    Ok(match (design, start) {
        (None, None) => sweep.case_params(actuation),
        (None, Some(s)) => {
            with_start(&sweep.params, Some(s)).case_params(actuation, &sweep.contact_key, dmw_key)
        }
        (Some(d), _) => design_params(&sweep.params, &d, actuation)?.case_params(
            actuation,
            &sweep.contact_key,
            dmw_key,
        ),
    })
}

/// Refuse to compute a case whose key, re-derived on the node from the pipeline file, is not
/// the manifest's: the file (or its upstream) changed since submission, and computing would
/// file another case's results under the manifest's key.
fn check_recipe_key(kind: &str, recipe: &Value, params: &Value, what: &str) -> Result<()> {
    let key = case_fingerprint(
        if kind == THREE_DOF_CASE {
            THREE_DOF_MODEL_VERSION
        } else {
            MODEL_VERSION
        },
        params,
    )
    .key();
    match recipe["key"].as_str() {
        Some(k) if k == key => Ok(()),
        other => Err(Error::Stage(format!(
            "{kind} case {what}: the pipeline file now gives key {key}, the manifest has {} \
             (the file or its upstream changed since submission; resubmit with \
             `hdi run --executor slurm`)",
            other.unwrap_or("none")
        ))),
    }
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

/// The string field `k` of a case recipe, or the error naming the case kind and the field.
pub(crate) fn recipe_field(recipe: &Value, kind: &'static str, k: &str) -> Result<String> {
    recipe[k]
        .as_str()
        .map(str::to_string)
        .ok_or_else(|| Error::RecipeField {
            kind,
            field: k.to_string(),
        })
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
        let field = |k: &str| recipe_field(recipe, self.kind, k);
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
        let design = serde_json::from_value::<Option<[f64; 3]>>(recipe["design_m"].clone());
        if let Ok(d) = &design {
            let params = sweep_case_params(&sweep, *d, actuation, start)?;
            let what = format!("{instance} at {:.4} nm", actuation * 1e9);
            check_recipe_key(self.kind, recipe, &params, &what)?;
        }
        match design {
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

/// Computes `[three_dof]` cases; prepares each instance (its lookup tables and DMW tracks)
/// once per process.
#[derive(Default)]
struct ThreeDofWorker {
    #[allow(clippy::type_complexity)]
    instances: Mutex<HashMap<(String, String), Arc<(PreparedThreeDof, ThreeDofSolver)>>>,
}

impl CaseComputer for ThreeDofWorker {
    fn compute(
        &self,
        recipe: &Value,
        store: &Store,
        dir: &Path,
    ) -> std::result::Result<Value, CaseFailure> {
        Ok(self.compute_recipe(recipe, store, dir)?)
    }
}

impl ThreeDofWorker {
    fn compute_recipe(&self, recipe: &Value, store: &Store, dir: &Path) -> Result<Value> {
        let field = |k: &str| recipe_field(recipe, THREE_DOF_CASE, k);
        let (config, instance, label) = (field("config")?, field("instance")?, field("case")?);
        let prepared = {
            let mut instances = self
                .instances
                .lock()
                .map_err(|_| Error::Stage("a worker thread panicked".into()))?;
            let k = (config.clone(), instance.clone());
            match instances.get(&k) {
                Some(s) => Arc::clone(s),
                None => {
                    let file = crate::stages::load(Path::new(&config))?;
                    let planned = plan_of(&file, store)?;
                    let p = prepared_three_dof(&file, store, &planned, &instance)?;
                    let solver = p.solver()?;
                    let s = Arc::new((p, solver));
                    instances.insert(k, Arc::clone(&s));
                    s
                }
            }
        };
        let (p, solver) = (&prepared.0, &prepared.1);
        let which = p
            .params
            .cases
            .iter()
            .copied()
            .find(|c| c.label() == label)
            .ok_or_else(|| {
                Error::Stage(format!(
                    "three_dof recipe: [three_dof.{instance}] in {config} has no case `{label}` \
                     (the file changed since submission?)"
                ))
            })?;
        check_recipe_key(
            THREE_DOF_CASE,
            recipe,
            &p.case_params(which),
            &format!("{instance}/{label}"),
        )?;
        solver.compute_case(p, which, dir)
    }
}

/// The workers `hdi exec-cases` dispatches to.
pub fn registry() -> CaseRegistry {
    let mut r = CaseRegistry::new();
    r.register(SIMULATE_CASE, SweepWorker::new(SIMULATE_CASE));
    r.register(DOE_CASE, SweepWorker::new(DOE_CASE));
    r.register(THREE_DOF_CASE, ThreeDofWorker::default());
    r.register(
        crate::stages::calibrate::CALIBRATION_CASE,
        super::distributed_calibration::CalibrationWorker::default(),
    );
    r
}
