//! hdi — head-disk interface pipeline.
//!
//! `core` is the small spine every stage uses (config, cache, store, plots);
//! `surface` (and later physics modules) are pure functions with no I/O besides readers;
//! `stages` wires physics into the pipeline (and registers the stage kinds); `engine` plans
//! and runs the stage instances; `cli` is the thin command-line layer.
pub mod analysis;
pub mod cli;
pub mod contact;
pub mod core;
pub mod dmw;
pub mod dynamics;
pub mod engine;
pub mod error;
pub mod numerics;
pub mod samples;
pub mod signal;
pub mod stages;
pub mod surface;
pub mod validate;

pub use error::{Error, Result};
