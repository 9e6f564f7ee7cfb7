//! hdi — head-disk interface pipeline.
//!
//! `core` is the small spine every stage uses (config, cache, store, the progress observers);
//! `figures` draws every plot with one plotting kit; the physics modules are pure functions
//! with no I/O besides readers; `stages` wires physics into the pipeline; `slider` is the case
//! machinery the slider stages share and `artefacts` what one stage hands another; `engine`
//! plans and runs the pipeline; `validation` is `hdi validate`'s harness; `report` the HTML
//! page of a whole run (`hdi report`). The command line is
//! the binary target (`src/main.rs`, `src/cli/`, feature `cli`), outside this library.
pub mod analysis;
pub mod artefacts;
pub mod bench;
pub mod contact;
pub mod core;
pub mod dmw;
pub mod dynamics;
pub mod engine;
pub mod error;
pub mod figures;
pub mod formats;
pub mod numerics;
pub mod report;
pub mod samples;
pub mod signal;
pub mod slider;
pub mod stages;
pub mod surface;
pub mod units;
pub mod validation;

pub use error::{Error, Result};
