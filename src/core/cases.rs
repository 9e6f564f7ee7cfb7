//! Sub-results cached by content hash inside a stage: one store entry per case (a sweep point,
//! a DOE run), so extending a sweep or re-running after a crash recomputes only the missing
//! cases. The same rules as stage entries: written into a work dir, checksummed, manifest last,
//! renamed into the store; a damaged entry is recomputed.

use crate::core::cache::{Fingerprint, Store, Verification};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Store kind of case entries (kept by `hdi gc` while a current stage lists their keys under
/// `case_keys` in its result).
pub const CASE_KIND: &str = "case";

/// A case's entry: where its files are, its result, and whether it came from the cache.
#[derive(Debug, Clone)]
pub struct CaseEntry {
    pub key: String,
    pub dir: PathBuf,
    pub result: Value,
    pub cached: bool,
}

/// Storing a computed case failed (the computing closure's own errors pass through as they
/// are).
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}

impl CaseError {
    fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        CaseError::Io {
            path: path.into(),
            source,
        }
    }
}

/// The cache key of a case: the case's canonical parameters and the model version.
pub fn case_fingerprint(model_version: &str, params: &Value) -> Fingerprint {
    Fingerprint {
        kind: CASE_KIND.to_string(),
        model_version: model_version.to_string(),
        params: params.clone(),
        inputs: Vec::new(),
        upstream: Vec::new(),
    }
}

/// The cached case for `params`, or compute it: `compute(dir)` writes the case's files into
/// `dir` and returns its result (stored as `result.json`).
pub fn get_or_compute<F, E>(
    store: &Store,
    model_version: &str,
    params: &Value,
    compute: F,
) -> Result<CaseEntry, E>
where
    F: FnOnce(&Path) -> Result<Value, E>,
    E: From<CaseError>,
{
    let fp = case_fingerprint(model_version, params);
    let key = fp.key();
    if let Verification::Fresh(_) = store.verify(CASE_KIND, &key) {
        let dir = store.entry_dir(CASE_KIND, &key);
        let path = dir.join("result.json");
        let read = std::fs::read(&path)
            .ok()
            .and_then(|b| serde_json::from_slice::<Value>(&b).ok());
        if let Some(result) = read {
            return Ok(CaseEntry {
                key,
                dir,
                result,
                cached: true,
            });
        }
    }
    let started = Instant::now();
    let work = store
        .new_work_dir("case", &key)
        .map_err(|e| CaseError::io(store.processed(), e))?;
    let result = match compute(&work) {
        Ok(r) => r,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&work);
            return Err(e);
        }
    };
    let bytes = serde_json::to_vec_pretty(&result).map_err(CaseError::from)?;
    let path = work.join("result.json");
    if let Err(e) = std::fs::write(&path, bytes) {
        let _ = std::fs::remove_dir_all(&work);
        return Err(CaseError::io(path, e).into());
    }
    if let Err(e) = store.commit(
        &work,
        "case",
        &fp,
        started.elapsed().as_secs_f64(),
        Default::default(),
    ) {
        // (A full disk fails the manifest's write: free what the case wrote.)
        let _ = std::fs::remove_dir_all(&work);
        return Err(CaseError::io(store.entry_dir(CASE_KIND, &key), e).into());
    }
    Ok(CaseEntry {
        dir: store.entry_dir(CASE_KIND, &key),
        key,
        result,
        cached: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn computes_once_then_reads_back_and_recovers_from_damage() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let params = json!({"actuation_m": 8.5e-9});
        let mut runs = 0;
        let mut run = |store: &Store| {
            get_or_compute(store, "test-1", &params, |d| -> Result<Value, CaseError> {
                runs += 1;
                std::fs::write(d.join("data.txt"), b"42").unwrap();
                Ok(json!({"value": 42}))
            })
            .unwrap()
        };
        let a = run(&store);
        assert!(!a.cached && a.result["value"] == 42);
        let b = run(&store);
        assert!(b.cached && b.key == a.key);
        // A damaged output file: the entry no longer verifies and is recomputed.
        std::fs::write(b.dir.join("data.txt"), b"43").unwrap();
        let c = run(&store);
        assert!(!c.cached);
        assert_eq!(std::fs::read(c.dir.join("data.txt")).unwrap(), b"42");
        assert_eq!(runs, 2);
        // A failing case leaves nothing behind.
        let e = get_or_compute(&store, "test-1", &json!({"x": 1}), |_| {
            Err::<Value, Box<dyn std::error::Error + Send + Sync>>("boom".into())
        });
        assert!(e.is_err());
        assert!(store.tmp_dirs().is_empty());
    }
}
