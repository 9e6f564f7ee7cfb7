//! The small core every stage uses: configuration, cache/store, outputs, plots. It names no
//! stage: the engine and the stages sit above it.
pub mod cache;
pub mod cases;
pub mod config;
pub mod executor;
pub mod hash;
pub mod progress;
pub mod store;
// Transitional path while branches merge; removed once every `core::units` path is rewritten.
pub use crate::units;
