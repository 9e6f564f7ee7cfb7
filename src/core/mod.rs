//! The small core every stage uses: configuration, cache/store, engine, outputs, plots.
pub mod cache;
pub mod cases;
pub mod config;
pub mod engine;
pub mod executor;
pub mod hash;
pub mod plot;
pub mod plot_analysis;
pub mod plot_doe;
pub mod plot_sweep;
pub mod progress;
pub mod store;
pub mod units;
