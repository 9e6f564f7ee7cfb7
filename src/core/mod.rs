//! The services every stage uses: pipeline-file parsing, the content-addressed cache and the
//! per-case cache, HDF5 and table writers (and the polars → arrow-rs bridge they use), progress observers, the Slurm executor. It names no
//! stage and no physics: the engine and the stages sit above it.
pub mod arrow_bridge;
pub mod cache;
pub mod cases;
pub mod config;
pub mod executor;
pub mod hash;
pub mod progress;
pub mod store;

/// The error and all its sources on one line, `outer: inner: …` (as the binary prints errors).
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}
