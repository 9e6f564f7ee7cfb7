//! The small core every stage uses: configuration, cache/store, engine, outputs.
pub mod cache;
pub mod cases;
pub mod config;
pub mod engine;
pub mod executor;
pub mod hash;
pub mod progress;
pub mod store;
pub mod units;
