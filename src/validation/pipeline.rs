//! The pipeline results `hdi validate` reads (calibrated sweeps, 3-DOF stage outputs, spectra):
//! only current ones — a stage whose cache entry matches its fingerprint now — each with the
//! [`Origin`] that names the instance and its cache key.

use super::Origin;
use crate::core::cache::Store;
use crate::engine::{plan, read_result, Plan, State};
use crate::error::Result;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A planned pipeline and its store.
pub struct Cache {
    store: Store,
    plan: Plan,
}

/// One current stage result.
pub struct Stored {
    pub result: Value,
    pub dir: PathBuf,
    pub origin: Origin,
}

impl Cache {
    /// Plan the pipeline in `config` against its store (nothing is run).
    pub fn open(config: &Path) -> Result<Cache> {
        let file = crate::stages::load(config)?;
        let stages = crate::stages::build(&file)?;
        let store = Store::open_existing(&file.processed_dir());
        let plan = plan(stages, &store, &Default::default())?;
        Ok(Cache { store, plan })
    }

    /// The pipeline's store (its case store holds `hdi validate`'s computed 2-DOF cases).
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// The current result of the instance `name`, `None` if it has not run (or is stale).
    pub fn current(&self, name: &str) -> Option<Stored> {
        let p = self
            .plan
            .planned
            .iter()
            .find(|p| p.name == name && p.state == State::Fresh)?;
        let dir = self.store.entry_dir(&p.kind, &p.key);
        let result = read_result(&dir).ok()?;
        Some(Stored {
            result,
            dir,
            origin: Origin::Cache {
                instance: format!("{}.{}", p.kind, p.name),
                key: p.key.clone(),
            },
        })
    }
}

/// The cache of `config`, if it exists and plans.
pub fn open(config: Option<&Path>) -> Option<Cache> {
    config.and_then(|c| Cache::open(c).ok())
}
