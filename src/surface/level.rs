//! Levelling (signals-and-surfaces.md §2.3). CONTRACT STUB.
use super::{HeightMap, Result};

/// One levelling operation; parses from / prints to the config strings
/// "plane", "poly(n)", "rows:mean", "rows:poly(n)", "rows:median", "rows:median_diff", "mean".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LevelOp {
    Plane,
    Poly(usize),
    RowsMean,
    RowsPoly(usize),
    RowsMedian,
    RowsMedianDiff,
    Mean,
}

impl std::str::FromStr for LevelOp {
    type Err = String;
    fn from_str(_s: &str) -> std::result::Result<Self, String> {
        unimplemented!()
    }
}

impl std::fmt::Display for LevelOp {
    fn fmt(&self, _f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        unimplemented!()
    }
}

/// Apply a recipe in order; each op is recorded in `map.history`.
pub fn level(_map: &mut HeightMap, _recipe: &[LevelOp]) -> Result<()> {
    unimplemented!()
}
