//! `hdi validate`: the published numbers hdi can be checked against, one typed row each
//! (docs/validation.md). Every row carries an `id`, a class ([`Class`]: G, K, D, Q, or C for a
//! consistency check), its target and tolerance (or, for Q rows, the ordering it asserts), hdi's
//! value, the model variant and inputs that produced it, and its [`Origin`]: computed now by
//! the library, or read from the pipeline's cache (a stage instance and its cache key) — the
//! calibrated values of class-D rows, the DOE optimum and the 3-DOF stage outputs come from the
//! cache when the pipeline has run.
//!
//! The harness sits above the physics it exercises: one file per area ([`AREAS`]), each calling
//! the physics modules (and, for the pipeline areas, the pipeline's current results); no
//! physics module imports this one.

use crate::dynamics::calibration::TargetSet;
use crate::error::{Error, Result};
use schemars::JsonSchema;
use serde::Serialize;
use std::path::Path;

/// What kind of target a row checks (dissertation Chapter 2–4 numbers; docs/validation.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, JsonSchema)]
pub enum Class {
    /// Geometry or closed form: only the dissertation's rounding can differ. Must pass.
    G,
    /// Kinematic results insensitive to the inputs the dissertation dropped. Must pass.
    K,
    /// Depends on dropped inputs (adhesion parameters, damping, DMW spectrum, stiffening):
    /// reported before and after calibration, never fails the command.
    D,
    /// Qualitative: an ordering or trend, carried as data ([`Ordering`]).
    Q,
    /// Consistency check: hdi's own inputs re-derived (e.g. a value back-solved from a target
    /// and checked against the same target). Not a reproduction; must hold.
    C,
}

impl Class {
    pub const ALL: [Class; 5] = [Class::G, Class::K, Class::D, Class::Q, Class::C];

    pub fn label(self) -> &'static str {
        match self {
            Class::G => "G",
            Class::K => "K",
            Class::D => "D",
            Class::Q => "Q",
            Class::C => "C",
        }
    }

    /// `G`, `k`, … (case-insensitive).
    pub fn parse(s: &str) -> Option<Class> {
        Class::ALL
            .into_iter()
            .find(|c| c.label().eq_ignore_ascii_case(s.trim()))
    }

    /// Whether a failing row of this class fails the command when its class is selected only
    /// implicitly (no `--class`): G, K and C. Q rows gate only when `--class` names Q; D rows
    /// never gate.
    pub fn gates_by_default(self) -> bool {
        matches!(self, Class::G | Class::K | Class::C)
    }
}

/// How close `value` must be to `target`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance {
    /// |value − target| ≤ tol·|target|.
    Relative(f64),
    /// |value − target| ≤ tol.
    Absolute(f64),
    /// lo ≤ value ≤ hi (the target is the published value, shown for reference).
    Range { lo: f64, hi: f64 },
}

impl Tolerance {
    pub fn holds(&self, target: f64, value: f64) -> bool {
        if !value.is_finite() {
            return false;
        }
        match *self {
            Tolerance::Relative(t) => {
                target.is_finite() && (value - target).abs() <= t * target.abs()
            }
            Tolerance::Absolute(t) => target.is_finite() && (value - target).abs() <= t,
            Tolerance::Range { lo, hi } => value >= lo && value <= hi,
        }
    }

    /// Short text form: `±1%`, `±0.2`, `[1, 1.6]`, `≥ 20`.
    pub fn short(&self) -> String {
        let s = |x: f64| {
            if x != 0.0 && x.abs() < 1e-3 {
                format!("{x:.0e}")
            } else {
                format!("{}", (x * 1e4).round() / 1e4)
            }
        };
        match *self {
            Tolerance::Relative(t) => format!("±{}%", s(t * 100.0)),
            Tolerance::Absolute(t) => format!("±{}", s(t)),
            Tolerance::Range { lo, hi } if !hi.is_finite() => format!("≥ {}", s(lo)),
            Tolerance::Range { lo, hi } if !lo.is_finite() => format!("≤ {}", s(hi)),
            Tolerance::Range { lo, hi } => format!("[{}, {}]", s(lo), s(hi)),
        }
    }
}

/// The relation a Q row asserts between its listed values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Relation {
    /// Strictly increasing in the listed order (`a < b < c`).
    Ascending,
    /// Every one of the first `split` values is at least `factor` times every other one
    /// ("cases 1 and 3 ≫ cases 0 and 2").
    Dominates {
        /// The first `split` items…
        split: usize,
        /// …are at least this factor above every other one.
        factor: f64,
    },
    /// All values within `tol` of each other (max − min ≤ tol).
    Close {
        /// All items within this of each other, in the row's `unit`.
        tol: f64,
    },
    /// Every value is a true fact (1 = true, 0 = false).
    AllTrue,
}

/// The ordering of a Q row: labelled values and the relation between them.
#[derive(Debug, Clone, PartialEq)]
pub struct Ordering {
    pub items: Vec<(String, f64)>,
    pub relation: Relation,
}

impl Ordering {
    pub fn new(relation: Relation, items: &[(&str, f64)]) -> Ordering {
        Ordering {
            items: items.iter().map(|(l, v)| (l.to_string(), *v)).collect(),
            relation,
        }
    }

    /// Whether the relation holds (false with fewer than two values, except `AllTrue`, or any
    /// non-finite value).
    pub fn holds(&self) -> bool {
        let v: Vec<f64> = self.items.iter().map(|(_, v)| *v).collect();
        if v.is_empty() || v.iter().any(|x| !x.is_finite()) {
            return false;
        }
        match self.relation {
            Relation::Ascending => v.len() >= 2 && v.windows(2).all(|w| w[0] < w[1]),
            Relation::Dominates { split, factor } => {
                if split == 0 || split >= v.len() {
                    return false;
                }
                let low = v[..split].iter().cloned().fold(f64::INFINITY, f64::min);
                let high = v[split..].iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                low >= factor * high
            }
            Relation::Close { tol } => {
                let lo = v.iter().cloned().fold(f64::INFINITY, f64::min);
                let hi = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                v.len() >= 2 && hi - lo <= tol
            }
            Relation::AllTrue => v.iter().all(|x| *x != 0.0),
        }
    }

    /// `case 2 1.59 < case 0 1.77 < …`
    pub fn describe(&self) -> String {
        let item = |(l, v): &(String, f64)| format!("{l} {}", sig(*v));
        match self.relation {
            Relation::Ascending => self.items.iter().map(item).collect::<Vec<_>>().join(" < "),
            Relation::Dominates { split, factor } => format!(
                "{} ≥ {factor}× {}",
                self.items[..split.min(self.items.len())]
                    .iter()
                    .map(item)
                    .collect::<Vec<_>>()
                    .join(", "),
                self.items[split.min(self.items.len())..]
                    .iter()
                    .map(item)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            Relation::Close { tol } => format!(
                "within {tol}: {}",
                self.items.iter().map(item).collect::<Vec<_>>().join(", ")
            ),
            Relation::AllTrue => self
                .items
                .iter()
                .map(|(l, v)| format!("{l}: {}", if *v != 0.0 { "yes" } else { "no" }))
                .collect::<Vec<_>>()
                .join("; "),
        }
    }
}

/// Four significant digits for the text forms.
pub(crate) fn sig(x: f64) -> String {
    if !x.is_finite() {
        return "–".into();
    }
    let a = x.abs();
    if x != 0.0 && !(1e-3..1e6).contains(&a) {
        format!("{x:.3e}")
    } else {
        let digits = (3 - a.log10().floor().max(-3.0) as i32).clamp(0, 6) as usize;
        format!("{x:.digits$}")
    }
}

/// Where a row's number comes from.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Origin {
    /// Computed now by the library.
    Computed,
    /// Read from the pipeline's cache: the stage instance (`kind.name`) and its cache key.
    Cache {
        /// Stage instance (`kind.name`).
        instance: String,
        /// Its cache key.
        key: String,
    },
    /// Computed now from values read from the cache (e.g. a fit's knobs).
    Recomputed {
        /// Stage instance (`kind.name`).
        instance: String,
        /// Its cache key.
        key: String,
    },
}

impl Origin {
    pub fn short(&self) -> String {
        match self {
            Origin::Computed => "computed".into(),
            Origin::Cache { instance, .. } => format!("cache {instance}"),
            Origin::Recomputed { instance, .. } => format!("recomputed from {instance}"),
        }
    }
}

/// A class-D row's value under other inputs than the row's own: after calibration, or
/// uncalibrated on the pipeline's shipped DMW record (the inputs the calibration starts from).
#[derive(Debug, Clone, PartialEq)]
pub struct Calibrated {
    pub value: f64,
    /// The calibration (`[calibrate.NAME]`) whose knobs produced it, and the inputs.
    pub inputs: String,
    pub origin: Origin,
}

/// What a row's target is (the ledger of docs/validation.md): a number the dissertation
/// prints, a number computed from printed ones, or an input hdi was built from.
#[derive(Debug, Clone, PartialEq)]
pub enum Basis {
    /// Printed in the dissertation; `at` says where (section, table, figure).
    Published { at: String },
    /// Computed from published numbers (or by an independent implementation of the printed
    /// equations with the printed parameters); `how` says how.
    Derived { how: String },
    /// Recovers an input hdi was built from (`what`): a consistency check, class C, never a
    /// reproduction.
    ByConstruction { what: String },
    /// Not stated by the row's builder: shown as such, and refused by the ledger's tests.
    Unstated,
}

impl Basis {
    /// `published`, `derived`, `by_construction` or `unstated`.
    pub fn kind(&self) -> &'static str {
        match self {
            Basis::Published { .. } => "published",
            Basis::Derived { .. } => "derived",
            Basis::ByConstruction { .. } => "by_construction",
            Basis::Unstated => "unstated",
        }
    }

    /// Where, how, or what: the basis's text.
    pub fn detail(&self) -> &str {
        match self {
            Basis::Published { at } => at,
            Basis::Derived { how } => how,
            Basis::ByConstruction { what } => what,
            Basis::Unstated => "",
        }
    }
}

/// A row's value under another model variant than the row's own (a named switch), so the
/// ledger shows which reading produced which number (docs/model-form.md).
#[derive(Debug, Clone, PartialEq)]
pub struct VariantValue {
    /// The switches, as `key = value` (`friction_law = ke_static`).
    pub variant: String,
    /// The value in the row's unit (NaN for an ordering row or when undefined).
    pub value: f64,
    /// Q rows: the ordering under this variant.
    pub ordering: Option<Ordering>,
    pub inputs: String,
    pub origin: Origin,
}

impl VariantValue {
    fn pass(&self, row: &Row) -> bool {
        match &self.ordering {
            Some(o) => o.holds(),
            None => row.tolerance.holds(row.target, self.value),
        }
    }
}

/// One validation target.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Stable identifier: `dyn-16` (target #16 of the Chapter 2–4 table, sub-quantities
    /// `dyn-16.solid`), `isbl-…`, `mtl-V13`, `dmw-…`, `cal-…`, `doe-…`.
    pub id: String,
    pub class: Class,
    /// Where the published number is (dissertation section, table, figure), or which
    /// independent reference it is.
    pub reference: String,
    pub quantity: String,
    pub unit: String,
    pub target: f64,
    /// hdi's value (class D: with the spec-default, uncalibrated inputs).
    pub value: f64,
    pub tolerance: Tolerance,
    /// Q rows: the ordering asserted (pass = it holds).
    pub ordering: Option<Ordering>,
    /// D rows: the value after calibration, when the pipeline's calibration has run.
    pub calibrated: Option<Calibrated>,
    /// D rows: the uncalibrated value on the shipped DMW record (the pipeline's uncalibrated
    /// sweep), so that `value` → `record` → `calibrated` changes one input at a time.
    pub record: Option<Calibrated>,
    /// Which model variant / switches produced the value.
    pub variant: String,
    /// Which DMW, start state and calibration.
    pub inputs: String,
    pub origin: Origin,
    pub note: String,
    /// What the target is: published, derived or by construction ([`Basis`]).
    pub basis: Basis,
    /// The value under other switches than the row's own variant.
    pub variants: Vec<VariantValue>,
    /// Set when the row's input has not been computed yet (a pipeline result it reads): what
    /// it needs. Such a row is `not run`: neither a pass nor a failure, and never gates.
    pub needs: Option<String>,
    /// D rows with a `calibrated` value: the calibration's set the target belongs to —
    /// `Fitted` (in the fit's objective: the calibrated value is a fit, not a reproduction),
    /// `Selection` (held out; model-form switches are chosen on it) or `Final` (held out from
    /// the fit and from every choice; docs/calibration.md).
    pub calibration_set: Option<TargetSet>,
}

/// A row as the cells of a table ([`Row::cells`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RowCells {
    /// `None` for a dimensionless quantity.
    pub unit: Option<String>,
    /// Empty for an ordering row (its relation is the tolerance cell).
    pub target: String,
    pub value: String,
    /// The calibrated value, `✓` when within tolerance; empty without one.
    pub calibrated: String,
    /// The uncalibrated value on the synthetic DMW record of `raw/`, `✓` when within
    /// tolerance; empty without one.
    pub record: String,
    /// `published`, `derived`, `by construction` (or `unstated`).
    pub basis: String,
    pub tolerance: String,
    /// Origin, variant and note, joined by ` — `.
    pub notes: String,
}

impl Row {
    /// A row with a numeric target; reference, variant, inputs and note are set with the
    /// builder methods.
    pub fn new(
        id: &str,
        class: Class,
        quantity: &str,
        unit: &str,
        target: f64,
        value: f64,
        tolerance: Tolerance,
    ) -> Row {
        Row {
            id: id.into(),
            class,
            reference: String::new(),
            quantity: quantity.into(),
            unit: unit.into(),
            target,
            value,
            tolerance,
            ordering: None,
            calibrated: None,
            record: None,
            variant: String::new(),
            inputs: String::new(),
            origin: Origin::Computed,
            note: String::new(),
            basis: Basis::Unstated,
            variants: Vec::new(),
            needs: None,
            calibration_set: None,
        }
    }

    /// A class-Q row asserting `ordering`.
    pub fn ordering(id: &str, quantity: &str, ordering: Ordering) -> Row {
        Row {
            ordering: Some(ordering),
            ..Row::new(
                id,
                Class::Q,
                quantity,
                "1",
                f64::NAN,
                f64::NAN,
                Tolerance::Absolute(0.0),
            )
        }
    }

    /// A closed-form / reference check (class G, basis `derived`: `reference` says how) without
    /// an id yet: the area assigns one ([`assign_ids`]).
    #[allow(clippy::too_many_arguments)] // a table row: positional reads like the table
    pub fn check(
        reference: &str,
        quantity: &str,
        unit: &str,
        target: f64,
        value: f64,
        tolerance: Tolerance,
        variant: &str,
        note: &str,
    ) -> Row {
        Row::new("", Class::G, quantity, unit, target, value, tolerance)
            .reference(reference)
            .derived(reference)
            .variant(variant)
            .note(note)
    }

    pub fn reference(mut self, s: &str) -> Row {
        self.reference = s.into();
        self
    }
    /// The target is printed in the dissertation at `at` (also the row's reference).
    pub fn published(mut self, at: &str) -> Row {
        self.reference = at.into();
        self.basis = Basis::Published { at: at.into() };
        self
    }
    /// The target is computed from published numbers, `how`.
    pub fn derived(mut self, how: &str) -> Row {
        self.basis = Basis::Derived { how: how.into() };
        self
    }
    /// The target recovers an input hdi was built from: a consistency check (class C).
    pub fn by_construction(mut self, what: &str) -> Row {
        self.basis = Basis::ByConstruction { what: what.into() };
        self.class = Class::C;
        self
    }
    /// The row's input is not computed yet: `what` names it (a pipeline result). The row is
    /// `not run`, not a failure.
    pub fn not_run(mut self, what: &str) -> Row {
        self.needs = Some(what.into());
        self.value = f64::NAN;
        self.note = format!("not run: needs {what} (run `hdi run` first)");
        self
    }
    /// D rows: the calibration set of the target behind the calibrated value.
    pub fn calibration_set(mut self, set: Option<TargetSet>) -> Row {
        self.calibration_set = set;
        self
    }
    /// The row's value under another variant (`variant`: the switches as `key = value`).
    pub fn with_variant(mut self, variant: &str, value: f64, inputs: &str, origin: Origin) -> Row {
        self.variants.push(VariantValue {
            variant: variant.into(),
            value,
            ordering: None,
            inputs: inputs.into(),
            origin,
        });
        self
    }
    /// A Q row's ordering under another variant.
    pub fn with_variant_ordering(
        mut self,
        variant: &str,
        ordering: Ordering,
        inputs: &str,
        origin: Origin,
    ) -> Row {
        self.variants.push(VariantValue {
            variant: variant.into(),
            value: f64::NAN,
            ordering: Some(ordering),
            inputs: inputs.into(),
            origin,
        });
        self
    }
    pub fn variant(mut self, s: &str) -> Row {
        self.variant = s.into();
        self
    }
    pub fn inputs(mut self, s: &str) -> Row {
        self.inputs = s.into();
        self
    }
    pub fn note(mut self, s: &str) -> Row {
        self.note = s.into();
        self
    }
    pub fn origin(mut self, o: Origin) -> Row {
        self.origin = o;
        self
    }
    pub fn class(mut self, c: Class) -> Row {
        self.class = c;
        self
    }
    pub fn calibrated(mut self, c: Option<Calibrated>) -> Row {
        self.calibrated = c;
        self
    }
    pub fn record(mut self, c: Option<Calibrated>) -> Row {
        self.record = c;
        self
    }

    /// Q rows: the ordering holds; others: the value is within the tolerance of the target.
    /// A row that has not run does not pass (and does not fail: [`Row::status`]).
    pub fn pass(&self) -> bool {
        if self.needs.is_some() {
            return false;
        }
        match &self.ordering {
            Some(o) => o.holds(),
            None => self.tolerance.holds(self.target, self.value),
        }
    }

    /// The row's status word: `pass`, `differs` (a class-D miss), `no` (a Q ordering that does
    /// not hold) or `FAIL`.
    pub fn verdict(&self) -> &'static str {
        if self.needs.is_some() {
            return "not run";
        }
        match (self.pass(), self.class) {
            (true, _) => "pass",
            (false, Class::D) => "differs",
            (false, Class::Q) => "no",
            (false, _) => "FAIL",
        }
    }

    /// `pass`, `fail` or `not_run` (the JSON `status`).
    pub fn status(&self) -> &'static str {
        match (self.needs.is_some(), self.pass()) {
            (true, _) => "not_run",
            (false, true) => "pass",
            (false, false) => "fail",
        }
    }

    /// The row as table cells, numbers written by `num` (shared by `hdi validate`'s table and
    /// the HTML report, so both read the same).
    pub fn cells(&self, num: impl Fn(f64) -> String) -> RowCells {
        let (target, value, tolerance) = match &self.ordering {
            Some(o) => (String::new(), String::new(), o.describe()),
            None => (num(self.target), num(self.value), self.tolerance.short()),
        };
        let alternative = |c: &Option<Calibrated>, suffix: &str| {
            c.as_ref().map_or(String::new(), |c| {
                let mark = if self.tolerance.holds(self.target, c.value) {
                    " ✓"
                } else {
                    ""
                };
                format!("{}{mark}{suffix}", num(c.value))
            })
        };
        let fitted = self.calibration_set == Some(TargetSet::Fitted);
        let calibrated = alternative(&self.calibrated, if fitted { " (fit)" } else { "" });
        let record = alternative(&self.record, "");
        let mut notes = vec![self.origin.short()];
        if !self.variant.is_empty() {
            notes.push(self.variant.clone());
        }
        if !self.note.is_empty() {
            notes.push(self.note.clone());
        }
        RowCells {
            unit: (self.unit != "1" && !self.unit.is_empty()).then(|| self.unit.clone()),
            target,
            value,
            calibrated,
            record,
            basis: self.basis.kind().replace('_', " "),
            tolerance,
            notes: notes.join(" — "),
        }
    }

    /// The calibrated value within the tolerance (D rows), `None` without one.
    pub fn calibrated_pass(&self) -> Option<bool> {
        self.calibrated
            .as_ref()
            .map(|c| self.tolerance.holds(self.target, c.value))
    }

    /// The row as `hdi validate --json` writes it ([`document::RowJson`]).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(document::RowJson::new(self)).unwrap_or_default()
    }
}

/// Give every row without an id `prefix-1`, `prefix-2`, … in order, and make ids unique
/// within `rows` by suffixing repeats (`isbl-2a`, `isbl-2a.2`).
pub fn assign_ids(prefix: &str, rows: &mut [Row]) {
    let mut k = 0;
    for r in rows.iter_mut() {
        if r.id.is_empty() {
            k += 1;
            r.id = format!("{prefix}-{k}");
        }
    }
    let mut seen: std::collections::HashMap<String, usize> = Default::default();
    for r in rows.iter_mut() {
        let n = seen.entry(r.id.clone()).or_insert(0);
        *n += 1;
        if *n > 1 {
            r.id = format!("{}.{}", r.id, n);
        }
    }
}

pub mod bem;
pub mod calibration;
pub mod contact;
pub mod dmw;
pub mod document;
pub mod dynamics;
pub mod mtl;
pub mod optimisation;
pub mod pipeline;
pub mod spectral;
pub mod three_dof;

/// Where an area's rows come from.
#[derive(Debug, Clone, Copy)]
pub enum Source {
    /// Computed from the code alone.
    Code(fn() -> Vec<Row>),
    /// Computed from the code, with values read from the pipeline in `pipeline.toml` where it
    /// has run (calibrated values, 3-DOF stage outputs); the computed rows do not need it.
    CodeAndCache(fn(Option<&Path>) -> Vec<Row>),
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

    const fn mixed(name: &'static str, rows: fn(Option<&Path>) -> Vec<Row>) -> Area {
        Area {
            name,
            source: Source::CodeAndCache(rows),
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
            Source::CodeAndCache(rows) => Ok(rows(config.exists().then_some(config))),
            Source::Pipeline(rows) => rows(config),
        }
    }
}

/// Every area in report order: the physics areas, then the fits of a pipeline.
#[rustfmt::skip]
pub const AREAS: &[Area] = &[
    Area::code("dmw", dmw::rows),
    Area::mixed("contact", contact::rows),
    Area::code("mtl", mtl::rows),
    Area::code("bem", bem::rows),
    Area::mixed("dynamics", dynamics::rows),
    Area::mixed("three_dof", three_dof::rows),
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

/// The ids of the 38 targets of the Chapter 2–4 table (dissertation §2.1–§2.3, §4, App. B)
/// that area `dynamics` and `three_dof` answer: `dyn-1` … `dyn-38`.
pub fn target_ids() -> Vec<String> {
    (1..=38).map(|n| format!("dyn-{n}")).collect()
}

/// Whether `id` answers target `base` (`dyn-16` is answered by `dyn-16` and `dyn-16.solid`).
pub fn answers(id: &str, base: &str) -> bool {
    id == base
        || id
            .strip_prefix(base)
            .is_some_and(|rest| rest.starts_with('.'))
}

/// The rows that fail the command: a failing row of a gating class. `selected` is the
/// `--class` list (empty: none given). G, K and C always gate; Q gates only when `selected`
/// names it; D never gates.
pub fn gate<'a>(rows: impl IntoIterator<Item = &'a Row>, selected: &[Class]) -> Vec<&'a Row> {
    rows.into_iter()
        .filter(|r| match r.class {
            Class::D => false,
            Class::Q => selected.contains(&Class::Q),
            c => c.gates_by_default(),
        })
        .filter(|r| r.needs.is_none() && !r.pass())
        .collect()
}

/// Passes out of rows; rows that have not run are counted apart (in `rows`, not in `pass`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, JsonSchema)]
pub struct Tally {
    /// Rows counted.
    pub rows: usize,
    /// Of which in tolerance (Q: the ordering holds).
    pub pass: usize,
    /// Of which not run (neither pass nor fail).
    pub not_run: usize,
}

impl Tally {
    fn add(&mut self, row: &Row, pass: bool) {
        self.rows += 1;
        if row.needs.is_some() {
            self.not_run += 1;
        } else if pass {
            self.pass += 1;
        }
    }

    /// `12/30` (`, 2 not run`).
    pub fn short(&self) -> String {
        if self.not_run > 0 {
            format!("{}/{} ({} not run)", self.pass, self.rows, self.not_run)
        } else {
            format!("{}/{}", self.pass, self.rows)
        }
    }
}

/// The ledger's summary (docs/validation.md): what is reproduced, what only derived or
/// consistent by construction.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Ledger {
    /// Numbers printed in the dissertation (basis `published`, a numeric target), reproduced
    /// (in tolerance) with each row's own inputs, and per class.
    pub published: Tally,
    pub published_by_class: Vec<(Class, Tally)>,
    /// Targets computed from published numbers (basis `derived`).
    pub derived: Tally,
    /// Rows that recover an input hdi was built from (class C): they must hold.
    pub by_construction: Tally,
    /// Class-D rows in tolerance with the row's own inputs (default inputs, synthetic DMW).
    pub d_default: Tally,
    /// The same D rows on the synthetic DMW record shipped in `raw/`, uncalibrated.
    pub d_record: Tally,
    /// D rows after calibration whose target the fit did not see: the selection set (switches
    /// are chosen on it) and the final set (never tuned on).
    pub d_calibrated_selection: Tally,
    pub d_calibrated_final: Tally,
    /// D rows after calibration whose target was in the fit's objective (fits, not
    /// reproductions).
    pub d_calibrated_fitted: Tally,
    /// Q orderings that hold.
    pub q: Tally,
    /// Rows whose builder stated no basis (a defect the tests refuse).
    pub unstated: usize,
}

/// The ledger of `rows` ([`Ledger`]).
pub fn ledger<'a>(rows: impl IntoIterator<Item = &'a Row>) -> Ledger {
    let mut l = Ledger::default();
    let mut by_class: Vec<(Class, Tally)> = Vec::new();
    for r in rows {
        let pass = r.pass();
        match &r.basis {
            Basis::Published { .. } if r.ordering.is_none() => {
                l.published.add(r, pass);
                match by_class.iter_mut().find(|(c, _)| *c == r.class) {
                    Some((_, t)) => t.add(r, pass),
                    None => {
                        let mut t = Tally::default();
                        t.add(r, pass);
                        by_class.push((r.class, t));
                    }
                }
            }
            Basis::Derived { .. } if r.ordering.is_none() => l.derived.add(r, pass),
            Basis::ByConstruction { .. } => l.by_construction.add(r, pass),
            Basis::Unstated => l.unstated += 1,
            _ => {}
        }
        if r.class == Class::D {
            l.d_default.add(r, pass);
            if let Some(c) = &r.record {
                l.d_record.add(r, r.tolerance.holds(r.target, c.value));
            }
            if let (Some(c), Some(set)) = (&r.calibrated, r.calibration_set) {
                let t = match set {
                    TargetSet::Fitted => &mut l.d_calibrated_fitted,
                    TargetSet::Selection => &mut l.d_calibrated_selection,
                    TargetSet::Final => &mut l.d_calibrated_final,
                };
                t.add(r, r.tolerance.holds(r.target, c.value));
            }
        }
        if r.class == Class::Q {
            l.q.add(r, pass);
        }
    }
    by_class.sort_by_key(|(c, _)| *c);
    l.published_by_class = by_class;
    l
}

impl Ledger {
    /// The summary lines, leading with the published numbers reproduced.
    pub fn lines(&self) -> Vec<String> {
        let per_class = self
            .published_by_class
            .iter()
            .map(|(c, t)| format!("{} {}", c.label(), t.short()))
            .collect::<Vec<_>>()
            .join(", ");
        let mut out = vec![format!(
            "published numbers: {} reproduced of {}{} ({per_class})",
            self.published.pass,
            self.published.rows,
            if self.published.not_run > 0 {
                format!(", {} not run", self.published.not_run)
            } else {
                String::new()
            }
        )];
        let mut d = format!("D in band: {} with default inputs", self.d_default.short());
        if self.d_record.rows > 0 {
            d.push_str(&format!(
                "; {} on the synthetic DMW record, uncalibrated",
                self.d_record.short()
            ));
        }
        let calibrated = [
            ("selection set", &self.d_calibrated_selection),
            ("final set", &self.d_calibrated_final),
            (
                "fitted (fits, not reproductions)",
                &self.d_calibrated_fitted,
            ),
        ];
        if calibrated.iter().any(|(_, t)| t.rows > 0) {
            d.push_str(&format!(
                "; calibrated: {}",
                calibrated
                    .iter()
                    .map(|(name, t)| format!("{} {name}", t.short()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        out.push(d);
        out.push(format!("Q orderings: {} hold", self.q.short()));
        out.push(format!(
            "derived targets: {} in tolerance; consistency checks (by construction): {} hold",
            self.derived.short(),
            self.by_construction.short()
        ));
        if self.unstated > 0 {
            out.push(format!("{} row(s) state no basis", self.unstated));
        }
        out
    }
}

/// Rows and passes per class, in [`Class::ALL`] order (classes without rows left out).
pub fn class_counts<'a>(rows: impl IntoIterator<Item = &'a Row>) -> Vec<(Class, usize, usize)> {
    let rows: Vec<&Row> = rows.into_iter().collect();
    Class::ALL
        .into_iter()
        .map(|c| {
            let of: Vec<&&Row> = rows.iter().filter(|r| r.class == c).collect();
            (c, of.len(), of.iter().filter(|r| r.pass()).count())
        })
        .filter(|(_, n, _)| *n > 0)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(target: f64, value: f64, tol: Tolerance) -> Row {
        Row::new("x-1", Class::G, "q", "1", target, value, tol)
    }

    #[test]
    fn tolerances() {
        assert!(row(1.0, 1.009, Tolerance::Relative(0.01)).pass());
        assert!(!row(1.0, 1.011, Tolerance::Relative(0.01)).pass());
        assert!(row(-2.0, -2.05, Tolerance::Absolute(0.1)).pass());
        assert!(!row(1.0, f64::NAN, Tolerance::Absolute(1.0)).pass());
        let r = Tolerance::Range { lo: 1.0, hi: 1.6 };
        assert!(row(1.2, 1.6, r).pass() && !row(1.2, 1.61, r).pass() && !row(1.2, 0.99, r).pass());
        let above = Tolerance::Range {
            lo: 20.0,
            hi: f64::INFINITY,
        };
        assert!(row(f64::NAN, 1e6, above).pass() && !row(f64::NAN, 19.9, above).pass());
    }

    #[test]
    fn orderings() {
        // Table 4.4's steady-contact order 2 < 0 < 1 < 3 with the published BVs holds…
        let table = |v: [f64; 4]| {
            Ordering::new(
                Relation::Ascending,
                &[
                    ("case 2", v[2]),
                    ("case 0", v[0]),
                    ("case 1", v[1]),
                    ("case 3", v[3]),
                ],
            )
        };
        assert!(table([5.7, 19.4, 1.7, 23.6]).holds());
        // …and fails when one pair is swapped, or on a tie, or on a missing value.
        assert!(!table([5.7, 19.4, 6.0, 23.6]).holds());
        assert!(!table([5.7, 23.6, 1.7, 23.6]).holds());
        assert!(!table([5.7, f64::NAN, 1.7, 23.6]).holds());
        // "cases 1 and 3 ≫ cases 0 and 2" with a factor 3: 623.9, 900 vs 61.7, 61.8.
        let dom = |v: [f64; 4]| {
            Ordering::new(
                Relation::Dominates {
                    split: 2,
                    factor: 3.0,
                },
                &[
                    ("case 1", v[1]),
                    ("case 3", v[3]),
                    ("case 0", v[0]),
                    ("case 2", v[2]),
                ],
            )
        };
        assert!(dom([61.7, 623.9, 61.8, 900.0]).holds());
        assert!(!dom([7.5, 8.6, 6.7, 6.2]).holds());
        assert!(!Ordering::new(
            Relation::Dominates {
                split: 0,
                factor: 1.0
            },
            &[("a", 1.0)]
        )
        .holds());
        let close = Ordering::new(
            Relation::Close { tol: 0.1 },
            &[("isbl", 7.79), ("mtl", 7.85)],
        );
        assert!(close.holds());
        assert!(!Ordering::new(Relation::Close { tol: 0.05 }, &[("a", 7.79), ("b", 7.85)]).holds());
        assert!(Ordering::new(Relation::AllTrue, &[("a", 1.0), ("b", 1.0)]).holds());
        assert!(!Ordering::new(Relation::AllTrue, &[("a", 1.0), ("b", 0.0)]).holds());
        // A Q row passes exactly when its ordering holds.
        assert!(!Row::ordering("dyn-35", "q", table([5.7, 19.4, 6.0, 23.6])).pass());
        assert!(Row::ordering("dyn-35", "q", table([5.7, 19.4, 1.7, 23.6])).pass());
    }

    #[test]
    fn the_gate_fails_on_g_k_c_and_selected_q_only() {
        let bad = |c: Class| {
            let mut r = row(1.0, 2.0, Tolerance::Absolute(0.1)).class(c);
            r.id = format!("bad-{}", c.label());
            r
        };
        let good = row(1.0, 1.0, Tolerance::Absolute(0.1));
        // A failing G row fails the gate (with or without --class)…
        assert_eq!(
            gate([&bad(Class::G), &good], &[Class::G, Class::K]).len(),
            1
        );
        assert_eq!(gate([&bad(Class::K)], &[]).len(), 1);
        assert_eq!(gate([&bad(Class::C)], &[]).len(), 1);
        // …a failing D row never does…
        assert!(gate([&bad(Class::D)], &[Class::D]).is_empty());
        // …and a failing Q row only when Q is selected.
        let q = Row::ordering(
            "q-1",
            "q",
            Ordering::new(Relation::Ascending, &[("a", 2.0), ("b", 1.0)]),
        );
        assert!(gate([&q], &[]).is_empty());
        assert_eq!(gate([&q], &[Class::Q]).len(), 1);
        assert!(gate([&good], &[]).is_empty());
    }

    /// Static registry check (the full run takes ~20 s in release, too slow for a debug test;
    /// docs/validation.md records its per-class counts): every target `dyn-1` … `dyn-38` has a
    /// row builder in the 2-DOF or 3-DOF area, by id or as `dyn-N.sub`.
    #[test]
    fn every_target_has_a_row_builder() {
        let src = [include_str!("dynamics.rs"), include_str!("three_dof.rs")].concat();
        for id in target_ids() {
            assert!(
                src.contains(&format!("\"{id}\"")) || src.contains(&format!("\"{id}.")),
                "no row for {id}"
            );
        }
    }

    #[test]
    fn the_ledger_counts_published_numbers_apart_from_derived_and_built_ones() {
        let published = |v: f64| row(1.0, v, Tolerance::Absolute(0.1)).published("dissertation §1");
        let rows = vec![
            published(1.0),
            published(2.0).class(Class::D).record(Some(Calibrated {
                value: 1.05,
                inputs: String::new(),
                origin: Origin::Computed,
            })),
            published(1.0).class(Class::K).not_run("a result"),
            row(1.0, 1.0, Tolerance::Absolute(0.1)).derived("closed form"),
            row(1.0, 1.0, Tolerance::Absolute(0.1)).by_construction("an input"),
            row(1.0, 1.0, Tolerance::Absolute(0.1)),
        ];
        let l = ledger(&rows);
        assert_eq!(
            (l.published.rows, l.published.pass, l.published.not_run),
            (3, 1, 1)
        );
        assert_eq!((l.derived.rows, l.derived.pass), (1, 1));
        assert_eq!((l.by_construction.rows, l.by_construction.pass), (1, 1));
        assert_eq!(rows[4].class, Class::C);
        assert_eq!((l.d_default.pass, l.d_record.pass), (0, 1));
        assert_eq!(l.unstated, 1);
        assert!(l.lines()[0].starts_with("published numbers: 1 reproduced of 3, 1 not run"));
        // A row that has not run neither passes nor gates, even in a gating class.
        assert_eq!(rows[2].status(), "not_run");
        assert_eq!(rows[2].verdict(), "not run");
        assert!(gate(&rows, &[Class::K]).is_empty());
        let j = rows[2].to_json();
        assert_eq!(j["status"], "not_run");
        assert_eq!(j["basis"]["kind"], "published");
    }

    #[test]
    fn ids_and_counts() {
        let mut rows = vec![
            row(1.0, 1.0, Tolerance::Absolute(0.1)),
            row(1.0, 3.0, Tolerance::Absolute(0.1)).class(Class::D),
            row(1.0, 1.0, Tolerance::Absolute(0.1)),
        ];
        rows[0].id = String::new();
        rows[1].id = "isbl-2a".into();
        rows[2].id = "isbl-2a".into();
        assign_ids("dmw", &mut rows);
        assert_eq!(rows[0].id, "dmw-1");
        assert_eq!(rows[2].id, "isbl-2a.2");
        assert_eq!(
            class_counts(&rows),
            vec![(Class::G, 2, 2), (Class::D, 1, 0)]
        );
        assert!(answers("dyn-16.solid", "dyn-16") && answers("dyn-16", "dyn-16"));
        assert!(!answers("dyn-160", "dyn-16") && !answers("dyn-1", "dyn-16"));
        assert_eq!(Class::parse(" k"), Some(Class::K));
        assert_eq!(Class::parse("X"), None);
        assert_eq!(target_ids().len(), 38);
    }
}
