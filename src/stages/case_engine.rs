//! The case capability of the stage contract (issue 31): a stage kind whose work splits into
//! independent cases (2-DOF sweeps, DOE designs, 3-DOF interfaces, calibration rounds) lists
//! them as typed recipes, prepares what they share once, and computes one. A local run and a
//! Slurm worker go through the same [`CaseEngine::prepare_cases`] and
//! [`PreparedCases::compute`], so the bytes of a case do not depend on where it ran; the
//! engine drives any kind through these traits and names none (docs/architecture.md).

use crate::core::cache::Store;
use crate::error::{Error, Result};
use crate::slider::case::MODEL_VERSION as SWEEP_CASE_MODEL_VERSION;
use crate::slider::sweep::{PreparedSweep, SweepCase};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The upstream entries an instance's cases read, by instance name: their results
/// (`result.json`), entry directories and cache keys (case keys include the keys).
#[derive(Debug, Clone, Default)]
pub struct UpstreamEntries {
    pub results: BTreeMap<String, Value>,
    pub dirs: BTreeMap<String, PathBuf>,
    pub keys: BTreeMap<String, String>,
}

impl UpstreamEntries {
    /// The cache key of upstream instance `name` (empty when it is not upstream).
    pub fn key_of(&self, name: &str) -> String {
        self.keys.get(name).cloned().unwrap_or_default()
    }

    /// The entries as a recipe carries them: directories relative to `processed`, so a worker
    /// on another node with the same shared `processed/` reads exactly these entries.
    pub fn refs(&self, processed: &Path) -> Vec<UpstreamRef> {
        self.dirs
            .iter()
            .map(|(name, dir)| UpstreamRef {
                name: name.clone(),
                key: self.key_of(name),
                dir: dir
                    .strip_prefix(processed)
                    .unwrap_or(dir)
                    .display()
                    .to_string(),
            })
            .collect()
    }

    /// The entries `refs` names, read from `store` (by directory and key, not by what the
    /// pipeline file would plan now: the case-key check then proves both sides hashed the
    /// same inputs).
    pub fn read(store: &Store, refs: &[UpstreamRef]) -> Result<Self> {
        let mut entries = UpstreamEntries::default();
        for r in refs {
            let dir = store.processed().join(&r.dir);
            entries.results.insert(r.name.clone(), read_result(&dir)?);
            entries.dirs.insert(r.name.clone(), dir);
            entries.keys.insert(r.name.clone(), r.key.clone());
        }
        Ok(entries)
    }
}

/// A stage entry's `result.json`.
pub fn read_result(dir: &Path) -> Result<Value> {
    let p = dir.join("result.json");
    let bytes = std::fs::read(&p).map_err(|e| Error::io(&p, e))?;
    serde_json::from_slice(&bytes).map_err(|source| Error::ResultJson { path: p, source })
}

/// One upstream entry a recipe names.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct UpstreamRef {
    /// Upstream instance.
    pub name: String,
    /// Its cache key (part of the case key).
    #[schemars(regex(pattern = r"^[0-9a-f]{64}$"))]
    pub key: String,
    /// Its store entry directory, relative to processed/.
    pub dir: String,
}

/// What a worker needs besides params to recompute the case: it rebuilds the instance alone
/// from the pipeline file, prepares it from exactly the upstream entries named here, and
/// refuses to compute when the parameters it derives give another key (the file or an
/// upstream entry changed). `recipe` of a case manifest entry (docs/schemas/case-manifest.json).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CaseRecipe {
    /// Absolute path of the pipeline file (the batch runner sets it on submission).
    #[serde(default)]
    pub config: String,
    /// The instance whose case this is (its section follows from the case kind).
    pub instance: String,
    /// The upstream entries the submitter's preparation read.
    pub upstream: Vec<UpstreamRef>,
    /// The case in its kind's own type, serialised (a sweep case's `{actuation_m, design_m,
    /// static_start}`, a 3-DOF interface label, …).
    pub case: Value,
    /// The case key again: the worker re-derives the parameters and refuses to compute when
    /// they give another key.
    #[schemars(regex(pattern = r"^[0-9a-f]{64}$"))]
    pub key: String,
}

/// One case as its stage lists it: the kind's case (serialised) and its key parameters.
#[derive(Debug, Clone)]
pub struct ListedCase {
    pub case: Value,
    pub params: Value,
}

/// The case capability of a stage kind ([`super::StageKind::case_engine`]).
pub trait CaseEngine: Send + Sync {
    /// What every case of the instance shares (interface tables, DMW tracks, the calibrated
    /// parameters), built once from the upstream entries: by the stage's own run, and once
    /// per worker process and instance on a Slurm node.
    fn prepare_cases(&self, upstream: &UpstreamEntries) -> Result<Arc<dyn PreparedCases>>;
    /// Whether an executor lists this kind's cases up front (`false`: a sequential driver
    /// submits its own rounds of cases while the stage runs, as the calibration's fit does).
    fn listed_up_front(&self) -> bool {
        true
    }
}

/// The shared preparation of one instance's cases.
pub trait PreparedCases: Send + Sync {
    /// Model version of the kind's case entries (hashed into each case key).
    fn model_version(&self) -> &'static str;
    /// The cases the stage's run computes up front, in its order (not the cases a driver adds
    /// while it runs: touchdown refinement, annealing, calibration rounds).
    fn cases(&self) -> Result<Vec<ListedCase>>;
    /// The key parameters of `case` (the kind's case, serialised).
    fn case_params(&self, case: &Value) -> Result<Value>;
    /// Compute `case` into `dir`; returns its result (what the case cache stores).
    fn compute(&self, case: &Value, dir: &Path) -> Result<Value>;
}

/// `case` as the kind's type `T`, or the error naming the case kind.
pub fn typed_case<T: serde::de::DeserializeOwned>(kind: &'static str, case: &Value) -> Result<T> {
    serde_json::from_value(case.clone()).map_err(|source| Error::RecipeCase { kind, source })
}

/// `case` serialised (a case type of plain numbers and strings always serialises).
pub fn case_value<T: Serialize>(case: &T) -> Value {
    serde_json::to_value(case).unwrap_or(Value::Null)
}

// ------------------------------------------------------------------------------------------
// The 2-DOF sweep's cases, shared by the `[simulate]` and `[doe]` kinds
// ------------------------------------------------------------------------------------------

/// Which cases a prepared sweep lists up front.
pub enum Listing {
    /// The sweep's plan: grid × branches from their continuation starts.
    Plan,
    /// A DOE's design cases.
    Cases(Vec<SweepCase>),
}

/// A prepared 2-DOF sweep (or a DOE's base sweep) as [`PreparedCases`].
pub struct SweepCases {
    pub kind: &'static str,
    pub sweep: PreparedSweep,
    pub listing: Listing,
}

impl PreparedCases for SweepCases {
    fn model_version(&self) -> &'static str {
        SWEEP_CASE_MODEL_VERSION
    }
    fn cases(&self) -> Result<Vec<ListedCase>> {
        let cases = match &self.listing {
            Listing::Plan => self.sweep.plan()?.cases(),
            Listing::Cases(c) => c.clone(),
        };
        cases
            .iter()
            .map(|c| {
                Ok(ListedCase {
                    case: case_value(c),
                    params: self.sweep.case_params(c)?,
                })
            })
            .collect()
    }
    fn case_params(&self, case: &Value) -> Result<Value> {
        self.sweep
            .case_params(&typed_case::<SweepCase>(self.kind, case)?)
    }
    fn compute(&self, case: &Value, dir: &Path) -> Result<Value> {
        self.sweep
            .compute(&typed_case::<SweepCase>(self.kind, case)?, dir)
    }
}
