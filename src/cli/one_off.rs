//! The one-off commands' road through the engine: one stage instance, run alone against a
//! scratch store of its own (removed afterwards), its result read through the kind's type and
//! its files delivered where `--out` says (docs/architecture.md).

use anyhow::{Context, Result};
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

use super::progress::StageBars;
use hdi::core::cache::{write_atomic, Store};
use hdi::stages::Stage;

/// The instance name one-off commands give their stage (it names the store's ref only).
pub(super) const NAME: &str = "cli";

/// A scratch directory, removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// An instance's committed entry in a scratch store that is removed when this is dropped.
pub(super) struct Ran<R> {
    /// Its `result.json`, read through the kind's result type.
    pub result: R,
    /// Its store directory.
    pub dir: PathBuf,
    _scratch: Scratch,
}

/// Run `stage` through the engine against a fresh scratch store under the system's temporary
/// directory (`command` names it).
pub(super) fn run<R: DeserializeOwned>(
    command: &'static str,
    stage: Box<dyn Stage>,
) -> Result<Ran<R>> {
    let scratch = Scratch(std::env::temp_dir().join(format!(
        "hdi-{command}-{}-{}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos())
    )));
    let store = Store::open(&scratch.0)
        .with_context(|| format!("opening a scratch store at {}", scratch.0.display()))?;
    let entry = hdi::engine::alone::run_alone(stage, &store, &StageBars::new(command))?;
    let result = serde_json::from_value(entry.result)
        .context("the stage's result.json does not read as its type")?;
    Ok(Ran {
        result,
        dir: entry.dir,
        _scratch: scratch,
    })
}

/// One file of the entry, written to `to` through a temporary file and a rename.
pub(super) fn deliver_file(entry: &Path, name: &str, to: &Path) -> Result<()> {
    let from = entry.join(name);
    let bytes = std::fs::read(&from).with_context(|| format!("reading {}", from.display()))?;
    write_atomic(to, &bytes).with_context(|| format!("writing {}", to.display()))
}

/// The entry's files (not the store's `result.json`, `manifest.json`): each written to
/// `dir` through a temporary file and a rename, `main` renamed to `main_as` when given.
pub(super) fn deliver(entry: &Path, dir: &Path, main: &str, main_as: Option<&Path>) -> Result<()> {
    let mut names: Vec<String> = std::fs::read_dir(entry)
        .with_context(|| format!("reading {}", entry.display()))?
        .filter_map(|e| e.ok())
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "result.json" && n != "manifest.json")
        .collect();
    names.sort();
    for name in names {
        let to = match main_as {
            Some(path) if name == main => path.to_path_buf(),
            _ => dir.join(&name),
        };
        deliver_file(entry, &name, &to)?;
    }
    Ok(())
}
