//! Combining two surfaces into the equivalent rough surface (signals-and-surfaces.md §2.7).
//! CONTRACT STUB.
use super::Result;

/// What the contact model needs of one surface; `m2`/`m4` when measured, else inverted from
/// (σ, R, η) through Nayak's relations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceStats {
    pub sigma: f64,
    pub r: f64,
    pub eta: f64,
    pub m2: Option<f64>,
    pub m4: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CombineRule {
    SumSurface,
    HarmonicR,
    Explicit { sigma: f64, r: f64, eta: f64 },
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceStats {
    pub sigma: f64,
    pub r: f64,
    pub eta: f64,
    pub beta: f64,
    pub m2: f64,
    pub m4: f64,
    pub alpha: f64,
    pub rule: CombineRule,
}

pub fn combine(_a: &SurfaceStats, _b: &SurfaceStats, _rule: CombineRule) -> Result<InterfaceStats> {
    unimplemented!()
}
