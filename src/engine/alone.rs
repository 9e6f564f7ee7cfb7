//! One stage instance run alone: the one-off commands (`hdi surface`, `contact`, `dmw`,
//! `bulge`) build a one-instance pipeline in memory and run it here, against a store of their
//! own, so they compute, write and commit exactly as `hdi run` does (docs/architecture.md).

use super::{run, Outcome, RunOptions};
use crate::core::cache::Store;
use crate::core::progress::RunObserver;
use crate::error::{Error, Result};
use crate::stages::Stage;
use serde_json::Value;
use std::path::PathBuf;

/// The committed entry of an instance run alone.
#[derive(Debug)]
pub struct Entry {
    /// Its `result.json`.
    pub result: Value,
    /// Its store directory (the kind's files beside `result.json` and `manifest.json`).
    pub dir: PathBuf,
}

/// Run `stage` (no upstream) against `store`, or take its entry from there when it is
/// fresh; a failure is the engine's message as an error.
pub fn run_alone(
    stage: Box<dyn Stage>,
    store: &Store,
    observer: &dyn RunObserver,
) -> Result<Entry> {
    let name = stage.name().to_string();
    let opts = RunOptions {
        jobs: 1,
        ..RunOptions::default()
    };
    let report = run(vec![stage], store, &opts, observer)?;
    let failed = |message: String| Error::InstanceFailed {
        name: name.clone(),
        message,
    };
    match report.outcomes.iter().find(|(n, _)| *n == name) {
        Some((_, Outcome::Ran { .. } | Outcome::Cached)) => {}
        Some((_, Outcome::Failed(m) | Outcome::Skipped(m))) => return Err(failed(m.clone())),
        _ => return Err(failed("did not run".into())),
    }
    let (_, kind, key) = report
        .current
        .iter()
        .find(|(n, _, _)| *n == name)
        .ok_or_else(|| failed("has no entry".into()))?;
    let dir = store.entry_dir(kind, key);
    let result = super::read_result(&dir)?;
    Ok(Entry { result, dir })
}
