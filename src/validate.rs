//! `hdi validate`: every reproducible number of the specs and the dissertation, computed by
//! hdi's own code now (nothing here is a stored result), against its target and tolerance.
//!
//! Each physics area contributes rows; a row says which model variant produced the number,
//! whether the target is reproducible (class of the spec's validation tables) and, when it is
//! not, why hdi's number differs.

use serde_json::{json, Value};

/// How close `ours` must be to `target`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance {
    /// |ours − target| ≤ tol·|target|.
    Relative(f64),
    /// |ours − target| ≤ tol.
    Absolute(f64),
}

/// One validation target.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Where the target comes from (spec file and section or table row).
    pub source: String,
    pub quantity: String,
    pub unit: String,
    pub target: f64,
    pub ours: f64,
    pub tolerance: Tolerance,
    /// Reproducible targets must pass; others are reported with the reason in `note`.
    pub reproducible: bool,
    /// Which model variant produced `ours` (e.g. "zero_phase order 4").
    pub variant: String,
    pub note: String,
}

impl Row {
    /// A reproducible row (the usual case); set `reproducible: false` with struct update for
    /// the others.
    #[allow(clippy::too_many_arguments)] // a table row: positional reads like the table
    pub fn reproducible(
        source: &str,
        quantity: &str,
        unit: &str,
        target: f64,
        ours: f64,
        tolerance: Tolerance,
        variant: &str,
        note: &str,
    ) -> Row {
        Row {
            source: source.into(),
            quantity: quantity.into(),
            unit: unit.into(),
            target,
            ours,
            tolerance,
            reproducible: true,
            variant: variant.into(),
            note: note.into(),
        }
    }

    pub fn pass(&self) -> bool {
        if !(self.ours.is_finite() && self.target.is_finite()) {
            return false;
        }
        let d = (self.ours - self.target).abs();
        match self.tolerance {
            Tolerance::Relative(t) => d <= t * self.target.abs(),
            Tolerance::Absolute(t) => d <= t,
        }
    }

    pub fn to_json(&self) -> Value {
        let (kind, tol) = match self.tolerance {
            Tolerance::Relative(t) => ("relative", t),
            Tolerance::Absolute(t) => ("absolute", t),
        };
        json!({
            "source": self.source,
            "quantity": self.quantity,
            "unit": self.unit,
            "target": self.target,
            "ours": if self.ours.is_finite() { json!(self.ours) } else { Value::Null },
            "tolerance": {"kind": kind, "value": tol},
            "reproducible": self.reproducible,
            "pass": self.pass(),
            "variant": self.variant,
            "note": self.note,
        })
    }
}

/// The areas computed from the code alone, with the function that computes each one's rows.
/// (`hdi validate` adds the area `calibration` from the fits of a pipeline.)
/// Computes one area's rows.
pub type AreaRows = fn() -> Vec<Row>;

pub const AREAS: &[(&str, AreaRows)] = &[
    ("dmw", crate::dmw::validation::rows),
    ("contact", crate::contact::validation::isbl_rows),
    ("mtl", crate::contact::validation::mtl_rows),
    ("dynamics", crate::dynamics::validation::rows),
    ("three_dof", crate::dynamics::three_dof::validation::rows),
];

/// Every row of [`AREAS`], area by area.
pub fn all_rows() -> Vec<(&'static str, Vec<Row>)> {
    AREAS.iter().map(|(a, rows)| (*a, rows())).collect()
}

/// Rows whose target is reproducible but which fail.
pub fn failures(areas: &[(&'static str, Vec<Row>)]) -> usize {
    areas
        .iter()
        .flat_map(|(_, rows)| rows)
        .filter(|r| r.reproducible && !r.pass())
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(target: f64, ours: f64, tol: Tolerance) -> Row {
        Row {
            source: "s".into(),
            quantity: "q".into(),
            unit: "1".into(),
            target,
            ours,
            tolerance: tol,
            reproducible: true,
            variant: "v".into(),
            note: String::new(),
        }
    }

    #[test]
    fn tolerances() {
        assert!(row(1.0, 1.009, Tolerance::Relative(0.01)).pass());
        assert!(!row(1.0, 1.011, Tolerance::Relative(0.01)).pass());
        assert!(row(-2.0, -2.05, Tolerance::Absolute(0.1)).pass());
        assert!(!row(1.0, f64::NAN, Tolerance::Absolute(1.0)).pass());
    }
}
