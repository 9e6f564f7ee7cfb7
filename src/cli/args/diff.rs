//! `hdi diff`'s options.

use clap::Args;
use std::path::PathBuf;

/// `hdi diff`.
#[derive(Args, Debug)]
pub struct DiffArgs {
    /// The old side: a processed directory (with `.hdi/`) or a pipeline file.
    pub a: PathBuf,
    /// The new side: a processed directory or a pipeline file.
    pub b: PathBuf,
    /// Machine-readable output (docs/schemas/diff.json).
    #[arg(long)]
    pub json: bool,
    /// Also list unchanged instances and metrics.
    #[arg(long)]
    pub all: bool,
    /// Numbers within rtol·max(|old|, |new|) count as equal (default: exact; results are
    /// byte-deterministic).
    #[arg(long, default_value_t = 0.0)]
    pub rtol: f64,
}
