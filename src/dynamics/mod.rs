//! Slider dynamics building blocks (Ch. 2, 4; docs/dynamics-geometry.md): TFC-bulge geometry, the
//! linear air bearing of the 2-DOF models and their parameter sets. Pure physics, no I/O; SI units
//! inside (m, kg, s, N, rad).
//!
//! * [`geometry`] — attitude and body→world rotation (§1.1), the TFC bulge as a lower
//!   half-ellipsoid, its lowest point (POC) in closed form (§2.2), lever arms and generalised
//!   forces (§1.1, §2.3), the nominal contact area by truncation with the initial (`nσ`) and the
//!   improved (`6σ − 3σ`) rules (§2.4), chord radii ("protrusion curvatures") and the 2-DOF
//!   slider geometry with its altitude anchor (§5.1, check C2).
//! * [`air_bearing`] — front/rear spring stiffness from the two AB natural frequencies by modal
//!   inversion (§3.1, closed form, suspension included), a nalgebra eigen-solve of the 2×2
//!   heave–pitch system, damping from damping ratios (§3.4), the improved model's rear-spring
//!   stiffening (§3.2) and the AB forces / matrices of the 2-DOF equations of motion (§5.1).
//! * [`params`] — the initial and improved 2-DOF parameter sets (§11.1, §11.2) with provenance,
//!   the optimised bulge of §2.3 and `validate()`.
//!
//! * [`three_dof`] — the 3-DOF slider (chapter 4): feature geometry, spacings, truncated areas.
//!
//! The equations of motion are not here; this module gives them every geometric and AB term.

pub mod air_bearing;
pub mod calibration;
pub mod contact_force;
pub mod geometry;
pub mod metrics;
pub mod params;
pub mod three_dof;
pub mod touchdown;
pub mod two_dof;

#[cfg(test)]
mod tests;

/// Errors of the dynamics building blocks.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// A parameter outside its physical range; `why` states the allowed range.
    #[error("parameter {name} = {value:e}: {why}")]
    Parameter {
        name: String,
        value: f64,
        why: String,
    },
    /// A numerical procedure has no (real) solution or did not converge.
    #[error("{0}")]
    Numerical(String),
}

impl DynamicsError {
    pub fn parameter(name: impl Into<String>, value: f64, why: impl Into<String>) -> Self {
        DynamicsError::Parameter {
            name: name.into(),
            value,
            why: why.into(),
        }
    }
}

pub type Result<T> = std::result::Result<T, DynamicsError>;

/// One nanometre in metres (for readable literals).
pub const NM: f64 = 1e-9;
/// One micrometre in metres.
pub const UM: f64 = 1e-6;

/// `value` must be finite and `> 0`.
pub(crate) fn require_positive(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(DynamicsError::parameter(
            name,
            value,
            "must be finite and > 0",
        ))
    }
}

/// `value` must be finite and `>= 0`.
pub(crate) fn require_non_negative(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(DynamicsError::parameter(
            name,
            value,
            "must be finite and >= 0",
        ))
    }
}

/// `value` must be finite and inside `[lo, hi]`; `unit` only decorates the message.
/// Inlined with the error path out of line: the 2-DOF POC checks the pitch once per
/// right-hand side (docs/performance.md).
#[inline]
pub(crate) fn require_in(name: &str, value: f64, lo: f64, hi: f64, unit: &str) -> Result<f64> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(out_of_range(name, value, lo, hi, unit))
    }
}

#[cold]
#[inline(never)]
fn out_of_range(name: &str, value: f64, lo: f64, hi: f64, unit: &str) -> DynamicsError {
    DynamicsError::parameter(name, value, format!("must lie in [{lo:e}, {hi:e}] {unit}"))
}

/// `value` must be finite (any sign).
pub(crate) fn require_finite(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(DynamicsError::parameter(name, value, "must be finite"))
    }
}
