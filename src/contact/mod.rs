//! Contact physics of the head-disk interface (App. A; docs/contact.md): the ISBL
//! rough-surface model (Greenwood–Williamson statistics, Kogut–Etsion asperities, friction,
//! adhesion, real area), the molecularly-thin-lubricant model, and fast force tables for the
//! dynamics. Pure functions; no I/O.

pub mod bem;
pub mod isbl;
pub mod lookup;
pub mod mtl;
pub mod table;

/// Effective (reduced) modulus of two elastic bodies, `E* = [(1−ν1²)/E1 + (1−ν2²)/E2]⁻¹`
/// (seed eq. A.5): the one formula both the ISBL and the MTL models use.
pub fn reduced_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2)
}

/// Errors of the contact models: always a parameter outside its physical range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactError {
    #[error("{name} = {value}: {reason}")]
    Parameter {
        name: &'static str,
        value: String,
        reason: String,
    },
    /// A numerical procedure did not reach its tolerance.
    #[error("{0}")]
    Numerical(String),
}

impl ContactError {
    pub fn parameter(
        name: &'static str,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        ContactError::Parameter {
            name,
            value: value.to_string(),
            reason: reason.into(),
        }
    }
}
