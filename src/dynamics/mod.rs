//! TEMPORARY (branch `ode` only): the real `dynamics/mod.rs` comes from another branch. When
//! merging, keep only the `pub mod metrics;` line below in that file.
pub mod metrics;
