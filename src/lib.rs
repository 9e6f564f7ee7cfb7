//! hdi — head-disk interface pipeline.
//!
//! `core` is the small spine every stage uses (config, cache, store, the progress observers);
//! `figures` draws every plot with one plotting kit; the physics modules are pure functions
//! with no I/O besides readers; `stages` wires physics into the pipeline. The command line is
//! the binary target (`src/main.rs`, `src/cli/`, feature `cli`), outside this library.
pub mod analysis;
pub mod contact;
pub mod core;
pub mod dmw;
pub mod dynamics;
pub mod error;
pub mod figures;
pub mod numerics;
pub mod samples;
pub mod signal;
pub mod stages;
pub mod surface;
pub mod validation;

pub use error::{Error, Result};
