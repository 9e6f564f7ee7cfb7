//! `hdi validate --json` (docs/schemas/validate.json): the rows of [`super::Row`] as written,
//! typed, so that the schema is generated from what is printed. The views borrow the rows;
//! non-finite numbers are written as null.

use super::{class_counts, Basis, Calibrated, Class, Ledger, Ordering, Origin, Row, Tally};
use crate::artefacts::finite;
use crate::dynamics::calibration::TargetSet;
use schemars::JsonSchema;
use serde::Serialize;

/// The published targets hdi is checked against, one typed row each, grouped by area
/// (docs/validation.md). Schema version 1 (docs/json.md): existing keys keep their name, unit
/// and type; renaming or removing one makes version 2.
#[derive(Debug, Serialize, JsonSchema)]
pub struct ValidateDocument<'a> {
    /// Rows per area (only the areas computed: `--only`, and the pipeline areas only with a
    /// pipeline file).
    pub areas: AreaRows<'a>,
    /// Rows listed.
    pub rows: usize,
    /// Per class present: rows and passes.
    pub classes: ByClass<ClassCount>,
    /// Gated rows that failed (the exit status is 1 when > 0).
    pub failed: usize,
    /// Their ids.
    pub failed_ids: Vec<&'a str>,
    /// The ledger's summary over the rows listed (docs/validation.md).
    pub ledger: LedgerJson,
}

impl<'a> ValidateDocument<'a> {
    /// The document of `areas` (area name → its listed rows, in [`super::AREAS`] order) whose
    /// gated failures are `failed`.
    pub fn new(areas: &[(&'static str, Vec<&'a Row>)], failed: &[&'a Row]) -> Self {
        let all: Vec<&Row> = areas.iter().flat_map(|(_, r)| r.iter().copied()).collect();
        let classes = class_counts(all.iter().copied())
            .into_iter()
            .map(|(c, rows, pass)| (c, ClassCount { rows, pass }))
            .collect();
        ValidateDocument {
            areas: AreaRows(
                areas
                    .iter()
                    .map(|(a, rows)| (*a, rows.iter().map(|r| RowJson::new(r)).collect()))
                    .collect(),
            ),
            rows: all.len(),
            classes,
            failed: failed.len(),
            failed_ids: failed.iter().map(|r| r.id.as_str()).collect(),
            ledger: LedgerJson::new(&super::ledger(all.iter().copied())),
        }
    }
}

/// Area name → its rows, in [`super::AREAS`] order; written as one object.
#[derive(Debug)]
pub struct AreaRows<'a>(pub Vec<(&'static str, Vec<RowJson<'a>>)>);

impl Serialize for AreaRows<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

impl JsonSchema for AreaRows<'_> {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "AreaRows".into()
    }
    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let names: Vec<&str> = super::AREAS.iter().map(|a| a.name).collect();
        let mut rows = generator.subschema_for::<Vec<RowJson>>();
        rows.insert("description".into(), "The area's rows.".into());
        schemars::json_schema!({
            "type": "object",
            "propertyNames": { "enum": names },
            "additionalProperties": rows,
        })
    }
}

/// One value per class present, in [`Class::ALL`] order (classes without rows left out).
#[derive(Debug, Serialize, JsonSchema)]
pub struct ByClass<T> {
    /// Geometry or closed form.
    #[serde(rename = "G", skip_serializing_if = "Option::is_none")]
    pub g: Option<T>,
    /// Kinematic.
    #[serde(rename = "K", skip_serializing_if = "Option::is_none")]
    pub k: Option<T>,
    /// Depends on dropped inputs.
    #[serde(rename = "D", skip_serializing_if = "Option::is_none")]
    pub d: Option<T>,
    /// Qualitative ordering.
    #[serde(rename = "Q", skip_serializing_if = "Option::is_none")]
    pub q: Option<T>,
    /// Consistency check.
    #[serde(rename = "C", skip_serializing_if = "Option::is_none")]
    pub c: Option<T>,
}

impl<T> FromIterator<(Class, T)> for ByClass<T> {
    fn from_iter<I: IntoIterator<Item = (Class, T)>>(iter: I) -> Self {
        let mut out = ByClass {
            g: None,
            k: None,
            d: None,
            q: None,
            c: None,
        };
        for (class, t) in iter {
            let slot = match class {
                Class::G => &mut out.g,
                Class::K => &mut out.k,
                Class::D => &mut out.d,
                Class::Q => &mut out.q,
                Class::C => &mut out.c,
            };
            *slot = Some(t);
        }
        out
    }
}

/// A class's rows and passes.
#[derive(Debug, Serialize, JsonSchema)]
pub struct ClassCount {
    /// Rows of the class.
    pub rows: usize,
    /// Of which pass.
    pub pass: usize,
}

/// One validation target as written.
#[derive(Debug, Serialize, JsonSchema)]
pub struct RowJson<'a> {
    /// Stable row id (e.g. `dyn-12`, `dmw-1`).
    #[schemars(length(min = 1))]
    pub id: &'a str,
    /// G geometry, K kinematic, D depends on dropped inputs, Q ordering, C consistency check
    /// (docs/validation.md).
    pub class: Class,
    /// Where the target is published.
    pub reference: &'a str,
    /// What is compared.
    pub quantity: &'a str,
    /// Unit of `target`, `value` and the tolerance of this row (`1`: dimensionless). The row
    /// table is the one place where the unit is a field rather than a key suffix: rows of
    /// different quantities share one shape.
    pub unit: &'a str,
    /// Published value, in `unit`; null when not defined for this input (docs/json.md).
    pub target: Option<f64>,
    /// hdi's value, in `unit`; null when it could not be computed or is not defined for this
    /// input (docs/json.md).
    pub value: Option<f64>,
    /// How close `value` must be to `target`.
    pub tolerance: ToleranceJson,
    /// Class-Q rows: the ordering asserted; null for other rows.
    pub ordering: Option<OrderingJson<'a>>,
    /// Q rows: the ordering holds; others: `value` is within the tolerance of `target`.
    pub pass: bool,
    /// `not_run`: the row reads a pipeline result that is not computed yet (`needs` names
    /// it); such a row neither passes nor gates. Otherwise `pass` or `fail` as `pass` says.
    pub status: RowStatus,
    /// What a `not_run` row needs (a pipeline result); null otherwise.
    pub needs: Option<&'a str>,
    /// D rows with a calibrated value: the calibration's set of the target — `fitted` (in the
    /// fit's objective: the calibrated value is a fit, not a reproduction), `selection` (held
    /// out; model-form switches are chosen on it), `final` (held out from the fit and from
    /// every choice); null otherwise.
    pub calibration_set: Option<TargetSet>,
    /// D rows of the 2-DOF sweeps: the value on the pipeline's DMW record without calibration
    /// (every file of the shipped raw/ is synthetic: the text table's and report's column
    /// says "synthetic record"); null otherwise.
    pub uncalibrated_record: Option<AlternativeJson<'a>>,
    /// A class-D row's value after calibration; null otherwise.
    pub calibrated: Option<AlternativeJson<'a>>,
    /// Model variant the value is computed with.
    pub variant: &'a str,
    /// Inputs of the value in words.
    pub inputs: &'a str,
    /// Where the number comes from.
    pub origin: &'a Origin,
    /// Remark.
    pub note: &'a str,
    /// What the target is (the ledger, docs/validation.md).
    pub basis: BasisJson<'a>,
    /// The row's value under other model variants (named switches, docs/model-form.md), so
    /// the ledger shows which reading produced which number.
    pub variants: Vec<VariantJson<'a>>,
}

impl<'a> RowJson<'a> {
    pub fn new(r: &'a Row) -> Self {
        let alternative = |c: &'a Calibrated| AlternativeJson {
            value: finite(c.value),
            pass: r.tolerance.holds(r.target, c.value),
            inputs: &c.inputs,
            origin: &c.origin,
        };
        RowJson {
            id: &r.id,
            class: r.class,
            reference: &r.reference,
            quantity: &r.quantity,
            unit: &r.unit,
            target: finite(r.target),
            value: finite(r.value),
            tolerance: ToleranceJson::new(&r.tolerance),
            ordering: r.ordering.as_ref().map(OrderingJson::new),
            pass: r.pass(),
            status: RowStatus::of(r),
            needs: r.needs.as_deref(),
            calibration_set: r.calibration_set,
            uncalibrated_record: r.record.as_ref().map(alternative),
            calibrated: r.calibrated.as_ref().map(alternative),
            variant: &r.variant,
            inputs: &r.inputs,
            origin: &r.origin,
            note: &r.note,
            basis: BasisJson::new(&r.basis),
            variants: r
                .variants
                .iter()
                .map(|v| VariantJson {
                    variant: &v.variant,
                    value: finite(v.value),
                    ordering: v.ordering.as_ref().map(OrderingJson::new),
                    pass: v.pass(r),
                    inputs: &v.inputs,
                    origin: &v.origin,
                })
                .collect(),
        }
    }
}

/// A row's status ([`Row::status`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RowStatus {
    Pass,
    Fail,
    NotRun,
}

impl RowStatus {
    fn of(r: &Row) -> Self {
        match (r.needs.is_some(), r.pass()) {
            (true, _) => RowStatus::NotRun,
            (false, true) => RowStatus::Pass,
            (false, false) => RowStatus::Fail,
        }
    }
}

/// How close `value` must be to `target`: `relative`: |value − target| ≤ value·|target|;
/// `absolute`: |value − target| ≤ value (in the row's `unit`); `range`: lo ≤ value ≤ hi.
#[derive(Debug, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ToleranceJson {
    /// |value − target| ≤ tolerance·|target|.
    Relative {
        /// The tolerance.
        value: f64,
    },
    /// |value − target| ≤ tolerance, in the row's `unit`.
    Absolute {
        /// The tolerance.
        value: f64,
    },
    /// lo ≤ value ≤ hi (the target is the published value, shown for reference).
    Range {
        /// Lower bound in the row's `unit`; null: none.
        lo: Option<f64>,
        /// Upper bound; null: none.
        hi: Option<f64>,
    },
}

impl ToleranceJson {
    fn new(t: &super::Tolerance) -> Self {
        match *t {
            super::Tolerance::Relative(value) => ToleranceJson::Relative { value },
            super::Tolerance::Absolute(value) => ToleranceJson::Absolute { value },
            super::Tolerance::Range { lo, hi } => ToleranceJson::Range {
                lo: finite(lo),
                hi: finite(hi),
            },
        }
    }
}

/// The ordering of a Q row: the relation, the values, whether it holds.
#[derive(Debug, Serialize, JsonSchema)]
pub struct OrderingJson<'a> {
    /// The relation a Q row asserts.
    pub relation: super::Relation,
    /// The values compared, in order.
    pub items: Vec<OrderingItem<'a>>,
    /// The relation holds.
    pub holds: bool,
}

impl<'a> OrderingJson<'a> {
    fn new(o: &'a Ordering) -> Self {
        OrderingJson {
            relation: o.relation,
            items: o
                .items
                .iter()
                .map(|(label, v)| OrderingItem {
                    label,
                    value: finite(*v),
                })
                .collect(),
            holds: o.holds(),
        }
    }
}

/// One labelled value of an ordering.
#[derive(Debug, Serialize, JsonSchema)]
pub struct OrderingItem<'a> {
    /// What the value is.
    pub label: &'a str,
    /// The value, in the row's `unit`; null when not defined for this input (docs/json.md).
    pub value: Option<f64>,
}

/// A class-D row's value under other inputs (calibrated, or uncalibrated on the shipped
/// record).
#[derive(Debug, Serialize, JsonSchema)]
pub struct AlternativeJson<'a> {
    /// The value under these inputs, in the row's `unit`; null when not defined for this
    /// input (docs/json.md).
    pub value: Option<f64>,
    /// Within the row's tolerance.
    pub pass: bool,
    /// The inputs it was computed with.
    pub inputs: &'a str,
    /// Where the number comes from.
    pub origin: &'a Origin,
}

/// The row's value under another model variant.
#[derive(Debug, Serialize, JsonSchema)]
pub struct VariantJson<'a> {
    /// The switches, `key = value`.
    pub variant: &'a str,
    /// The value under the variant, in the row's `unit`; null for an ordering row or when
    /// undefined.
    pub value: Option<f64>,
    /// Q rows: the ordering under the variant.
    pub ordering: Option<OrderingJson<'a>>,
    /// Within the row's tolerance (Q rows: the ordering holds).
    pub pass: bool,
    /// The inputs it was computed with.
    pub inputs: &'a str,
    /// Where the number comes from.
    pub origin: &'a Origin,
}

/// What the target is (the ledger, docs/validation.md).
#[derive(Debug, Serialize, JsonSchema)]
pub struct BasisJson<'a> {
    /// `published`: a number printed in the dissertation (`detail` says where); `derived`:
    /// computed from published numbers (`detail` says how); `by_construction`: recovers an
    /// input hdi was built from (a class-C consistency check, never counted as a
    /// reproduction); `unstated`: the row's builder did not say (a defect).
    pub kind: BasisKind,
    /// Where, how, or which input.
    pub detail: &'a str,
}

/// The kind of a [`Basis`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BasisKind {
    Published,
    Derived,
    ByConstruction,
    Unstated,
}

impl<'a> BasisJson<'a> {
    fn new(b: &'a Basis) -> Self {
        let kind = match b {
            Basis::Published { .. } => BasisKind::Published,
            Basis::Derived { .. } => BasisKind::Derived,
            Basis::ByConstruction { .. } => BasisKind::ByConstruction,
            Basis::Unstated => BasisKind::Unstated,
        };
        BasisJson {
            kind,
            detail: b.detail(),
        }
    }
}

/// The ledger's summary over the rows listed (docs/validation.md).
#[derive(Debug, Serialize, JsonSchema)]
pub struct LedgerJson {
    /// Numbers printed in the dissertation (basis `published`, numeric target): reproduced =
    /// in tolerance with the row's own inputs.
    pub published: Tally,
    /// The same per class.
    pub published_by_class: ByClass<Tally>,
    /// Targets computed from published numbers.
    pub derived: Tally,
    /// Consistency checks that recover an input hdi was built from (class C).
    pub by_construction: Tally,
    /// Class-D rows in tolerance.
    pub d_in_band: DInBand,
    /// Q orderings that hold.
    pub q_orderings: Tally,
    /// Rows whose builder stated no basis (a defect).
    pub unstated: usize,
}

/// Class-D rows in tolerance.
#[derive(Debug, Serialize, JsonSchema)]
pub struct DInBand {
    /// With the row's own inputs (default inputs, the validation's synthetic DMW).
    pub default_inputs: Tally,
    /// On the synthetic DMW record shipped in raw/, uncalibrated.
    pub synthetic_record: Tally,
    /// After calibration, the selection set's targets (held out from the fit; switches are
    /// chosen on them).
    pub calibrated_selection: Tally,
    /// After calibration, the final set's targets (held out from the fit and from every
    /// choice).
    pub calibrated_final: Tally,
    /// After calibration, targets in the fit's objective (fits, not reproductions).
    pub calibrated_fitted: Tally,
}

impl LedgerJson {
    pub fn new(l: &Ledger) -> Self {
        LedgerJson {
            published: l.published,
            published_by_class: l.published_by_class.iter().copied().collect(),
            derived: l.derived,
            by_construction: l.by_construction,
            d_in_band: DInBand {
                default_inputs: l.d_default,
                synthetic_record: l.d_record,
                calibrated_selection: l.d_calibrated_selection,
                calibrated_final: l.d_calibrated_final,
                calibrated_fitted: l.d_calibrated_fitted,
            },
            q_orderings: l.q,
            unstated: l.unstated,
        }
    }
}
