//! Contact physics of the head-disk interface (contact-isbl.md, contact-mtl.md): the ISBL
//! rough-surface model (Greenwood–Williamson statistics, Kogut–Etsion asperities, friction,
//! adhesion, real area), the molecularly-thin-lubricant model, and fast force tables for the
//! dynamics. Pure functions; no I/O.

pub mod isbl;
pub mod mtl;
pub mod table;
pub mod validation;

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
