//! Molecularly-thin-lubricant (MTL) contact model (Vakis 2011, Ch. 3 and
//! App. A.2).
//!
//! Three layers, each pure and closed-form (no quadrature at run time):
//! - [`sphere_on_flat`] (§3.1): a rigid sphere sliding over a flat through a lubricant
//!   film — apparent viscosity, wall slip, Kapitza pressure and load, shear force for the
//!   partially and fully submerged sphere, transitional forces.
//! - [`extrapolation`] (eqs. 3.36–3.47): the fibre-wobbling (FWM) measurement carried to HDI
//!   shear rates — `P0`, `Q0`, `m`, `n`, and the lubricant stiffnesses versus liquid gap.
//! - [`rough`] (eqs. 3.55–3.60): lubricant stiffness and force between rough surfaces versus
//!   mean-plane separation, composed with a caller-supplied solid contribution
//!   ([`rough::SolidContact`]) so the ISBL model can be plugged in without this module
//!   depending on it.
//!
//! SI units throughout (m, s, Pa, N, N/m). Stiffnesses are `k = −dF/dh`, positive when the
//! force grows as the gap closes; forces are magnitudes (normal force repulsive, friction
//! opposing sliding).

pub mod extrapolation;
pub mod rough;
pub mod sphere_on_flat;

#[cfg(test)]
mod tests;

pub use extrapolation::{FwmExperiment, HighShearFit};
pub use rough::{
    ForceStiffness, InterfaceResponse, LubricantCase, MtlInterface, NoSolid, RoughFilm, RoughMtl,
    RoughRegime, SolidContact, SolidResponse,
};
pub use sphere_on_flat::{
    ContactForces, ShearModel, SlipModel, SphereOnFlat, SphereRegime, TrueViscosity, ViscosityLaw,
    ViscosityModel,
};

use super::ContactError;

/// `x > 0`, false for NaN (clearer than a negated comparison).
pub(crate) fn is_positive(x: f64) -> bool {
    x > 0.0
}

/// `value` must be finite and strictly positive (lengths, viscosities, radii).
pub(crate) fn require_positive(name: &'static str, value: f64) -> Result<f64, ContactError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ContactError::parameter(
            name,
            value,
            "must be finite and > 0",
        ))
    }
}

/// `value` must be finite and non-negative (speeds, roughness, slip length).
pub(crate) fn require_non_negative(name: &'static str, value: f64) -> Result<f64, ContactError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(ContactError::parameter(
            name,
            value,
            "must be finite and >= 0",
        ))
    }
}

/// Effective (reduced) elastic modulus of two bodies, `E* = [(1−ν1²)/E1 + (1−ν2²)/E2]⁻¹`.
///
/// Kept here only because the sphere-on-flat validation numbers of docs/contact.md (V1, V14, V15)
/// are quoted with it; the solid model proper lives in `contact::isbl`.
pub fn effective_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> Result<f64, ContactError> {
    require_positive("E1", e1)?;
    require_positive("E2", e2)?;
    for (name, nu) in [("nu1", nu1), ("nu2", nu2)] {
        if !(nu.is_finite() && (-1.0..0.5).contains(&nu)) {
            return Err(ContactError::parameter(name, nu, "must be in [-1, 0.5)"));
        }
    }
    Ok(super::reduced_modulus(e1, nu1, e2, nu2))
}

/// Hertz load of a sphere of radius `radius` pressed by `interference` into a flat,
/// `P = (4/3)·E*·√R·ω^{3/2}`; 0 for `ω ≤ 0`.
///
/// The spec's best reproduction of the dissertation's `P_solid,min` (1.5 µN at 1 Å, 40 µN at
/// 1 nm; the dissertation's model [72] is unidentified). A convenient single-asperity solid
/// for [`SphereOnFlat::forces`] until the ISBL model is wired in.
pub fn hertz_normal_force(e_star: f64, radius: f64, interference: f64) -> f64 {
    if !is_positive(interference) || !is_positive(e_star) || !is_positive(radius) {
        return 0.0;
    }
    4.0 / 3.0 * e_star * radius.sqrt() * interference.powf(1.5)
}
