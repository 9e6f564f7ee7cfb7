//! hdi — head-disk interface pipeline.
pub mod numerics;
pub mod surface;
