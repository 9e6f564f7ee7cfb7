//! `hdi validate`: every reproducible number of the specs and the dissertation, computed by
//! hdi's own code now (nothing here is a stored result), against its target and tolerance.
//!
//! Each physics area contributes rows; a row says which model variant produced the number,
//! whether the target is reproducible (class of the spec's validation tables) and, when it is
//! not, why hdi's number differs.
//!
//! The harness sits above the physics it exercises: one file per area ([`AREAS`]), each calling
//! the physics modules (and, for `calibration` and `optimisation`, the pipeline's current
//! results); no physics module imports this one.

use crate::error::{Error, Result};
use serde_json::{json, Value};
use std::path::Path;

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

pub mod calibration;
pub mod contact;
pub mod dmw;
pub mod dynamics;
pub mod mtl;
pub mod optimisation;
pub mod three_dof;

/// Where an area's rows come from.
#[derive(Debug, Clone, Copy)]
pub enum Source {
    /// Computed from the code alone.
    Code(fn() -> Vec<Row>),
    /// Read from the current results of the pipeline in `pipeline.toml` (re-evaluated now).
    Pipeline(fn(&Path) -> Result<Vec<Row>>),
}

/// One area of `hdi validate`.
#[derive(Debug, Clone, Copy)]
pub struct Area {
    pub name: &'static str,
    pub source: Source,
}

impl Area {
    const fn code(name: &'static str, rows: fn() -> Vec<Row>) -> Area {
        Area {
            name,
            source: Source::Code(rows),
        }
    }

    const fn pipeline(name: &'static str, rows: fn(&Path) -> Result<Vec<Row>>) -> Area {
        Area {
            name,
            source: Source::Pipeline(rows),
        }
    }

    /// Whether the rows need a pipeline (its file and cache), not only the code.
    pub fn needs_pipeline(&self) -> bool {
        matches!(self.source, Source::Pipeline(_))
    }

    /// This area's rows; `config` is the pipeline file the pipeline areas read.
    pub fn rows(&self, config: &Path) -> Result<Vec<Row>> {
        match self.source {
            Source::Code(rows) => Ok(rows()),
            Source::Pipeline(rows) => rows(config),
        }
    }
}

/// Every area in report order: the physics areas, then the fits of a pipeline.
#[rustfmt::skip]
pub const AREAS: &[Area] = &[
    Area::code("dmw", dmw::rows),
    Area::code("contact", contact::rows),
    Area::code("mtl", mtl::rows),
    Area::code("dynamics", dynamics::rows),
    Area::code("three_dof", three_dof::rows),
    Area::pipeline("calibration", calibration::rows),
    Area::pipeline("optimisation", optimisation::rows),
];

/// The area called `name`.
pub fn area(name: &str) -> Option<&'static Area> {
    AREAS.iter().find(|a| a.name == name)
}

/// The rows of the area called `name` (`config`: the pipeline file the pipeline areas read).
pub fn rows(name: &str, config: &Path) -> Result<Vec<Row>> {
    match area(name) {
        Some(a) => a.rows(config),
        None => Err(Error::UnknownArea(name.to_string())),
    }
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
