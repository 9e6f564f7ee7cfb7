//! `hdi diff A B`: what differs between two processed directories or two pipeline files
//! (or one of each) — stage instances (by cache key), their parameters, and the metrics of
//! the summary tables and `result.json` (docs/diff.md).
//!
//! Loading turns either side into a [`Snapshot`] (per instance: fingerprint, key, metrics);
//! [`compare`] is pure and knows nothing about where a snapshot came from.

use crate::core::cache::{Fingerprint, Manifest, StaleReason, Store};
use crate::engine::State;
use schemars::JsonSchema;
use serde::Serialize;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum DiffError {
    #[error("{}: no such file or directory", .0.display())]
    NotFound(PathBuf),
    #[error(
        "{}: not a processed directory (no .hdi/refs/ inside; run `hdi run` first) and not a pipeline file{}",
        .0.display(), .1
    )]
    NotProcessed(PathBuf, String),
    #[error("{}: {message}", path.display())]
    Unreadable { path: PathBuf, message: String },
    #[error("{}", path.display())]
    Pipeline {
        path: PathBuf,
        #[source]
        source: Box<crate::error::Error>,
    },
    #[error("--rtol must be a finite number ≥ 0, got {0}")]
    BadRtol(f64),
}

/// Where a snapshot came from: `processed`, a processed directory (its last runs);
/// `pipeline`, a pipeline file (keys planned, nothing run).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SourceKind {
    /// A `processed/` directory: the last successful run of every instance (`.hdi/refs/`).
    Processed,
    /// A pipeline file: keys planned without running (what `hdi status` computes).
    Pipeline,
}

/// One stage instance as one side knows it.
#[derive(Debug, Clone)]
pub struct Instance {
    pub kind: String,
    pub key: String,
    pub fingerprint: Fingerprint,
    /// (source, metric) → scalar value; source is a table file name or `result.json`.
    /// Empty when the side has no result for this instance.
    pub metrics: BTreeMap<(String, String), Value>,
}

/// One side of a diff: every stage instance by name.
#[derive(Debug, Clone)]
pub struct Snapshot {
    pub path: PathBuf,
    pub source: SourceKind,
    pub instances: BTreeMap<String, Instance>,
}

/// A directory is read as a processed directory, a file as a pipeline file.
pub fn load(path: &Path) -> Result<Snapshot, DiffError> {
    let meta = std::fs::metadata(path).map_err(|_| DiffError::NotFound(path.to_path_buf()))?;
    if meta.is_dir() {
        load_processed(path)
    } else {
        load_pipeline(path)
    }
}

/// A processed directory: instances from `.hdi/refs/` (the manifest of each name's last
/// successful run, fingerprint and params included), metrics from `tables/*.csv` and each
/// entry's `result.json`.
pub fn load_processed(dir: &Path) -> Result<Snapshot, DiffError> {
    let refs = dir.join(".hdi").join("refs");
    if !refs.is_dir() {
        // A project directory given for its processed/ or its pipeline file: say which.
        let hint = if dir.join("processed").join(".hdi").join("refs").is_dir() {
            format!(" (did you mean {}?)", dir.join("processed").display())
        } else if dir.join("pipeline.toml").is_file() {
            format!(" (did you mean {}?)", dir.join("pipeline.toml").display())
        } else {
            String::new()
        };
        return Err(DiffError::NotProcessed(dir.to_path_buf(), hint));
    }
    let unreadable = |path: &Path, message: String| DiffError::Unreadable {
        path: path.to_path_buf(),
        message,
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(&refs)
        .map_err(|e| unreadable(&refs, e.to_string()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    let store = Store::open_existing(dir);
    let mut instances = BTreeMap::new();
    for f in files {
        let bytes = std::fs::read(&f).map_err(|e| unreadable(&f, e.to_string()))?;
        let m: Manifest = serde_json::from_slice(&bytes)
            .map_err(|e| unreadable(&f, format!("not an hdi manifest: {e}")))?;
        let entry = store.entry_dir(&m.fingerprint.kind, &m.key);
        let metrics = result_metrics(&entry)?;
        instances.insert(
            m.name.clone(),
            Instance {
                kind: m.fingerprint.kind.clone(),
                key: m.key,
                fingerprint: m.fingerprint,
                metrics,
            },
        );
    }
    let tables = dir.join("tables");
    // Each table's CSV; its Parquet twin only where the CSV is missing (both hold the same
    // rows, docs/architecture.md "Tables").
    let mut files: Vec<PathBuf> = std::fs::read_dir(&tables)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| match p.extension().and_then(|x| x.to_str()) {
            Some("csv") => true,
            Some("parquet") => !p.with_extension("csv").exists(),
            _ => false,
        })
        .collect();
    files.sort();
    for table in files {
        let source = table
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let rows = if source.ends_with(".csv") {
            let text =
                std::fs::read_to_string(&table).map_err(|e| unreadable(&table, e.to_string()))?;
            table_rows(&text)
        } else {
            parquet_rows(&table)
        }
        .map_err(|m| unreadable(&table, m))?;
        for row in rows {
            // Rows of instances without a ref (removed from the pipeline, ref gone) have no
            // fingerprint to compare: they are left out.
            let Some(Value::String(stage)) = row.get("stage") else {
                continue;
            };
            if let Some(inst) = instances.get_mut(stage) {
                for (col, v) in &row {
                    if col != "stage" {
                        inst.metrics
                            .insert((source.clone(), col.clone()), v.clone());
                    }
                }
            }
        }
    }
    Ok(Snapshot {
        path: dir.to_path_buf(),
        source: SourceKind::Processed,
        instances,
    })
}

/// A pipeline file: every instance's fingerprint and key as `hdi status` plans them (input
/// files hashed, upstream keys chained), without running anything. Metrics come from the
/// store's `result.json` of the instances whose planned entry is already there.
pub fn load_pipeline(path: &Path) -> Result<Snapshot, DiffError> {
    let wrap = |e: crate::error::Error| DiffError::Pipeline {
        path: path.to_path_buf(),
        source: Box::new(e),
    };
    let file = crate::stages::load(path).map_err(|e| wrap(e.into()))?;
    let stages = crate::stages::build(&file).map_err(|e| wrap(e.into()))?;
    let store = Store::open_existing(&file.processed_dir());
    let plan = super::plan_read_only(stages, &store).map_err(wrap)?;
    let mut instances = BTreeMap::new();
    for p in plan.planned {
        let metrics = if p.state == State::Fresh {
            result_metrics(&store.entry_dir(&p.kind, &p.key))?
        } else {
            BTreeMap::new()
        };
        instances.insert(
            p.name,
            Instance {
                kind: p.kind,
                key: p.key,
                fingerprint: p.fingerprint,
                metrics,
            },
        );
    }
    Ok(Snapshot {
        path: path.to_path_buf(),
        source: SourceKind::Pipeline,
        instances,
    })
}

/// The scalars of an entry's `result.json` (nested objects flattened to dotted keys; arrays
/// and the `summary_row`, which the tables hold, left out); empty when there is no result.
fn result_metrics(entry: &Path) -> Result<BTreeMap<(String, String), Value>, DiffError> {
    let p = entry.join("result.json");
    let mut out = BTreeMap::new();
    let Ok(bytes) = std::fs::read(&p) else {
        return Ok(out);
    };
    let v: Value = serde_json::from_slice(&bytes).map_err(|e| DiffError::Unreadable {
        path: p.clone(),
        message: format!("not JSON: {e}"),
    })?;
    let mut flat = BTreeMap::new();
    if let Value::Object(m) = &v {
        for (k, x) in m {
            if k != "summary_row" {
                flatten(k, x, false, &mut flat);
            }
        }
    }
    for (k, x) in flat {
        out.insert(("result.json".to_string(), k), x);
    }
    Ok(out)
}

/// Dotted keys → leaf values. With `keep_arrays` an array is one leaf (parameters such as a
/// levelling list); without, arrays are dropped (per-case vectors are not summary scalars).
fn flatten(prefix: &str, v: &Value, keep_arrays: bool, out: &mut BTreeMap<String, Value>) {
    match v {
        Value::Object(m) => {
            if m.is_empty() && keep_arrays {
                out.insert(prefix.to_string(), v.clone());
            }
            for (k, x) in m {
                let p = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&p, x, keep_arrays, out);
            }
        }
        Value::Array(_) if !keep_arrays => {}
        _ => {
            out.insert(prefix.to_string(), v.clone());
        }
    }
}

/// The rows of a summary-table CSV as column → value: integers and finite numbers as JSON
/// numbers, `true`/`false` as booleans, an empty cell as null, anything else as text.
/// Quoted fields (`"a, b"`, `""` for a quote) are understood.
pub fn table_rows(text: &str) -> Result<Vec<BTreeMap<String, Value>>, String> {
    let records = csv_records(text)?;
    let mut it = records.into_iter();
    let Some(head) = it.next() else {
        return Ok(Vec::new());
    };
    let mut rows = Vec::new();
    for (i, r) in it.enumerate() {
        if r.len() == 1 && r[0].is_empty() {
            continue;
        }
        if r.len() != head.len() {
            return Err(format!(
                "row {} has {} fields, the header {}",
                i + 2,
                r.len(),
                head.len()
            ));
        }
        rows.push(
            head.iter()
                .cloned()
                .zip(r.into_iter().map(|c| cell_value(&c)))
                .collect(),
        );
    }
    Ok(rows)
}

/// The rows of a summary-table Parquet file, typed as [`table_rows`] types CSV cells.
fn parquet_rows(path: &Path) -> Result<Vec<BTreeMap<String, Value>>, String> {
    use polars_core::prelude::*;
    use polars_io::prelude::*;
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let df = ParquetReader::new(file)
        .finish()
        .map_err(|e| format!("not a readable Parquet file: {e}"))?;
    let mut rows = vec![BTreeMap::new(); df.height()];
    for col in df.columns() {
        let name = col.name().to_string();
        for (i, row) in rows.iter_mut().enumerate() {
            let v = match col.get(i).map_err(|e| e.to_string())? {
                AnyValue::Null => Value::Null,
                AnyValue::Boolean(b) => Value::Bool(b),
                AnyValue::Int64(x) => Value::from(x),
                AnyValue::Int32(x) => Value::from(x),
                AnyValue::UInt64(x) => Value::from(x),
                AnyValue::UInt32(x) => Value::from(x),
                AnyValue::Float64(x) if x.is_finite() => Value::from(x),
                AnyValue::Float32(x) if x.is_finite() => Value::from(x as f64),
                AnyValue::String(s) => Value::String(s.to_string()),
                AnyValue::StringOwned(s) => Value::String(s.to_string()),
                other => Value::String(other.to_string()),
            };
            row.insert(name.clone(), v);
        }
    }
    Ok(rows)
}

fn cell_value(c: &str) -> Value {
    if c.is_empty() {
        return Value::Null;
    }
    if let Ok(i) = c.parse::<i64>() {
        return Value::from(i);
    }
    match c {
        "true" => return Value::Bool(true),
        "false" => return Value::Bool(false),
        _ => {}
    }
    match c.parse::<f64>() {
        // JSON has no NaN/∞: those stay text, compared as text.
        Ok(x) if x.is_finite() => Value::from(x),
        _ => Value::String(c.to_string()),
    }
}

/// RFC 4180 records (a quoted field may hold commas, quotes as `""` and line breaks).
fn csv_records(text: &str) -> Result<Vec<Vec<String>>, String> {
    let mut records = Vec::new();
    let mut record = Vec::new();
    let mut field = String::new();
    let mut chars = text.chars().peekable();
    let mut quoted = false;
    let mut line = 1;
    while let Some(c) = chars.next() {
        if quoted {
            match c {
                '"' if chars.peek() == Some(&'"') => {
                    chars.next();
                    field.push('"');
                }
                '"' => quoted = false,
                '\n' => {
                    line += 1;
                    field.push(c);
                }
                _ => field.push(c),
            }
            continue;
        }
        match c {
            '"' if field.is_empty() => quoted = true,
            ',' => record.push(std::mem::take(&mut field)),
            '\r' if chars.peek() == Some(&'\n') => {}
            '\n' => {
                line += 1;
                record.push(std::mem::take(&mut field));
                records.push(std::mem::take(&mut record));
            }
            _ => field.push(c),
        }
    }
    if quoted {
        return Err(format!("unterminated quoted field (line {line})"));
    }
    if !field.is_empty() || !record.is_empty() {
        record.push(field);
        records.push(record);
    }
    Ok(records)
}

/// What `hdi diff` shows.
#[derive(Debug, Clone, Copy, Default)]
pub struct Options {
    /// Numbers within `rtol · max(|old|, |new|)` count as equal (0: exact).
    pub rtol: f64,
    /// List unchanged instances and metrics too.
    pub all: bool,
}

impl Options {
    /// A finite, non-negative tolerance.
    pub fn check(&self) -> Result<(), DiffError> {
        if self.rtol.is_finite() && self.rtol >= 0.0 {
            Ok(())
        } else {
            Err(DiffError::BadRtol(self.rtol))
        }
    }
}

/// How an instance differs between A and B.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Added,
    Removed,
    Changed,
    Unchanged,
}

impl Status {
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Added => "added",
            Status::Removed => "removed",
            Status::Changed => "changed",
            Status::Unchanged => "unchanged",
        }
    }
}

/// One stage instance added, removed, changed (or, with --all, unchanged).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct InstanceDiff {
    /// Instance name.
    pub name: String,
    /// Stage kind (surface, simulate, …).
    pub kind: String,
    /// `added`: only in B; `removed`: only in A; `changed`: the cache key differs;
    /// `unchanged`: the same key.
    pub status: Status,
    /// Cache key in A (null: not in A).
    pub key_a: Option<String>,
    /// Cache key in B (null: not in B).
    pub key_b: Option<String>,
    /// For a changed instance: what in its fingerprint differs (parameter, input file,
    /// upstream key, model version), as `hdi status` words it.
    pub why: Vec<String>,
}

/// One parameter that differs, of an instance present in both A and B.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ParamDiff {
    /// Instance name.
    pub instance: String,
    /// `<kind>.<name>.<parameter>` (dotted for nested tables): the validated parameter in SI
    /// units with defaults filled in, as the cache key uses it (e.g.
    /// `simulate.improved_sweep.actuation_step_m`).
    pub key: String,
    /// Value in A (null: not set).
    #[schemars(with = "AnyValue")]
    pub old: Value,
    /// Value in B (null: not set).
    #[schemars(with = "AnyValue")]
    pub new: Value,
}

/// Any JSON value (a parameter: number, text, list, table or null). Schema only.
struct AnyValue;

impl JsonSchema for AnyValue {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "AnyValue".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::Schema::default()
    }
}

/// A table cell or result.json scalar (number, text, boolean) or null. Schema only.
struct Scalar;

impl JsonSchema for Scalar {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Scalar".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({ "type": ["number", "string", "boolean", "null"] })
    }
}

/// One metric compared, of an instance present in both A and B.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct MetricDiff {
    /// Instance name.
    pub instance: String,
    /// The summary table the value comes from (`surfaces.csv`, …) or `result.json`.
    pub source: String,
    /// Column name (unit suffix kept, e.g. `sigma_nm`) or dotted result.json key.
    pub metric: String,
    /// The value in A: a table cell or result.json scalar; null when missing in A.
    #[schemars(with = "Scalar")]
    pub old: Value,
    /// The value in B: a table cell or result.json scalar; null when missing in B.
    #[schemars(with = "Scalar")]
    pub new: Value,
    /// new − old in the metric's unit; null unless both are numbers.
    pub delta: Option<f64>,
    /// (new − old) / |old|; null unless both are numbers and old ≠ 0.
    pub rel_delta: Option<f64>,
    /// Differs beyond `rtol` (text and booleans: differs at all).
    pub changed: bool,
}

/// The counts of the comparison.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct Summary {
    /// Instances only in B.
    pub added: usize,
    /// Instances only in A.
    pub removed: usize,
    /// Instances in both whose cache key differs.
    pub changed: usize,
    /// Instances in both with the same cache key.
    pub unchanged: usize,
    /// Entries in `params`.
    pub params_changed: usize,
    /// Metrics that differ (beyond rtol).
    pub metrics_changed: usize,
    /// Metrics compared over the instances in both A and B.
    pub metrics_compared: usize,
}

/// One side of the comparison.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Side {
    /// The path as given on the command line.
    pub path: String,
    /// processed: a processed directory (its last runs); pipeline: a pipeline file (keys
    /// planned, nothing run).
    pub source: SourceKind,
    /// Stage instances on this side.
    pub instances: usize,
}

/// What differs between two processed directories or pipeline files (docs/diff.md). A is the
/// old side, B the new one. Schema version 1 (docs/json.md): existing keys keep their name,
/// unit and type; renaming or removing one makes version 2.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Diff {
    /// The old side.
    pub a: Side,
    /// The new side.
    pub b: Side,
    /// No instance added, removed or changed and no metric differs (exit status 0);
    /// otherwise exit status 1.
    pub identical: bool,
    /// Relative tolerance for numeric metrics (0: exact comparison).
    #[schemars(range(min = 0))]
    pub rtol: f64,
    /// The counts.
    pub summary: Summary,
    /// Added, removed and changed instances by name (with --all also the unchanged ones).
    pub instances: Vec<InstanceDiff>,
    /// Parameters that differ, per instance present in both A and B.
    pub params: Vec<ParamDiff>,
    /// Metrics that differ (with --all every compared metric), per instance present in both
    /// A and B.
    pub metrics: Vec<MetricDiff>,
}

fn side(s: &Snapshot) -> Side {
    Side {
        path: s.path.to_string_lossy().to_string(),
        source: s.source,
        instances: s.instances.len(),
    }
}

/// Compare two snapshots (A old, B new). Pure.
pub fn compare(a: &Snapshot, b: &Snapshot, opts: &Options) -> Result<Diff, DiffError> {
    opts.check()?;
    let names: BTreeSet<&String> = a.instances.keys().chain(b.instances.keys()).collect();
    let mut summary = Summary::default();
    let mut instances = Vec::new();
    let mut params = Vec::new();
    let mut metrics = Vec::new();
    for name in names {
        let (old, new) = (a.instances.get(name), b.instances.get(name));
        let (status, why) = match (old, new) {
            (None, Some(_)) => (Status::Added, Vec::new()),
            (Some(_), None) => (Status::Removed, Vec::new()),
            (Some(o), Some(n)) if o.key != n.key => (
                Status::Changed,
                StaleReason::phrases(&n.fingerprint.explain_changes(&o.fingerprint)),
            ),
            _ => (Status::Unchanged, Vec::new()),
        };
        match status {
            Status::Added => summary.added += 1,
            Status::Removed => summary.removed += 1,
            Status::Changed => summary.changed += 1,
            Status::Unchanged => summary.unchanged += 1,
        }
        let any = new.or(old).map(|i| i.kind.clone()).unwrap_or_default();
        if status != Status::Unchanged || opts.all {
            instances.push(InstanceDiff {
                name: name.clone(),
                kind: any.clone(),
                status,
                key_a: old.map(|i| i.key.clone()),
                key_b: new.map(|i| i.key.clone()),
                why,
            });
        }
        let (Some(o), Some(n)) = (old, new) else {
            continue;
        };
        let prefix = format!("{}.{}", n.kind, name);
        let mut po = BTreeMap::new();
        let mut pn = BTreeMap::new();
        flatten(&prefix, &o.fingerprint.params, true, &mut po);
        flatten(&prefix, &n.fingerprint.params, true, &mut pn);
        let pkeys: BTreeSet<&String> = po.keys().chain(pn.keys()).collect();
        for k in pkeys {
            let (x, y) = (
                po.get(k).cloned().unwrap_or(Value::Null),
                pn.get(k).cloned().unwrap_or(Value::Null),
            );
            if x != y {
                summary.params_changed += 1;
                params.push(ParamDiff {
                    instance: name.clone(),
                    key: k.clone(),
                    old: x,
                    new: y,
                });
            }
        }
        // A source (table or result.json) only one side has — a pipeline file's side has no
        // tables — is not compared; within a shared source a missing cell is null.
        let sources = |i: &Instance| -> BTreeSet<String> {
            i.metrics.keys().map(|(s, _)| s.clone()).collect()
        };
        let shared: BTreeSet<String> = sources(o).intersection(&sources(n)).cloned().collect();
        let mkeys: BTreeSet<&(String, String)> = o
            .metrics
            .keys()
            .chain(n.metrics.keys())
            .filter(|(s, _)| shared.contains(s))
            .collect();
        for k in mkeys {
            let x = o.metrics.get(k).cloned().unwrap_or(Value::Null);
            let y = n.metrics.get(k).cloned().unwrap_or(Value::Null);
            let m = metric_diff(name, k, x, y, opts.rtol);
            summary.metrics_compared += 1;
            if m.changed {
                summary.metrics_changed += 1;
            }
            if m.changed || opts.all {
                metrics.push(m);
            }
        }
    }
    let identical =
        summary.added + summary.removed + summary.changed + summary.metrics_changed == 0;
    Ok(Diff {
        a: side(a),
        b: side(b),
        identical,
        rtol: opts.rtol,
        summary,
        instances,
        params,
        metrics,
    })
}

fn metric_diff(
    instance: &str,
    (source, metric): &(String, String),
    old: Value,
    new: Value,
    rtol: f64,
) -> MetricDiff {
    let (delta, rel_delta, changed) = match (old.as_f64(), new.as_f64()) {
        (Some(x), Some(y)) if old.is_number() && new.is_number() => {
            let d = y - x;
            let changed = if rtol == 0.0 {
                x != y
            } else {
                d.abs() > rtol * x.abs().max(y.abs())
            };
            let rel = (x != 0.0).then(|| d / x.abs());
            (Some(d), rel, changed)
        }
        _ => (None, None, old != new),
    };
    MetricDiff {
        instance: instance.to_string(),
        source: source.clone(),
        metric: metric.clone(),
        old,
        new,
        delta,
        rel_delta,
        changed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn inst(
        kind: &str,
        params: Value,
        upstream: &[(&str, &str)],
        metrics: &[(&str, Value)],
    ) -> Instance {
        let fingerprint = Fingerprint {
            kind: kind.into(),
            model_version: format!("{kind}-1"),
            params,
            inputs: Vec::new(),
            upstream: upstream
                .iter()
                .map(|(n, k)| crate::core::cache::UpstreamRecord {
                    name: n.to_string(),
                    key: k.to_string(),
                })
                .collect(),
        };
        Instance {
            kind: kind.into(),
            key: fingerprint.key(),
            fingerprint,
            metrics: metrics
                .iter()
                .map(|(m, v)| (("t.csv".to_string(), m.to_string()), v.clone()))
                .collect(),
        }
    }

    fn snap(items: Vec<(&str, Instance)>) -> Snapshot {
        Snapshot {
            path: PathBuf::from("x"),
            source: SourceKind::Processed,
            instances: items.into_iter().map(|(n, i)| (n.to_string(), i)).collect(),
        }
    }

    #[test]
    fn identical_snapshots_are_identical_and_list_nothing() {
        let a = snap(vec![(
            "disk",
            inst(
                "surface",
                json!({"filter_s_m": 1.6e-8}),
                &[],
                &[("sigma_nm", json!(0.5))],
            ),
        )]);
        let d = compare(&a, &a.clone(), &Options::default()).unwrap();
        assert!(d.identical);
        assert!(d.instances.is_empty() && d.params.is_empty() && d.metrics.is_empty());
        assert_eq!(d.summary.unchanged, 1);
        assert_eq!(d.summary.metrics_compared, 1);
        let all = compare(
            &a,
            &a.clone(),
            &Options {
                rtol: 0.0,
                all: true,
            },
        )
        .unwrap();
        assert!(all.identical);
        assert_eq!(all.instances.len(), 1);
        assert_eq!(all.metrics.len(), 1);
        assert!(!all.metrics[0].changed);
        assert_eq!(all.metrics[0].delta, Some(0.0));
    }

    #[test]
    fn a_changed_parameter_lists_the_instance_its_param_and_the_metric_deltas() {
        let a = snap(vec![
            (
                "disk",
                inst(
                    "surface",
                    json!({"filter_s_m": 1.6e-8, "level": ["plane"], "inner": {"x": 1}}),
                    &[],
                    &[
                        ("sigma_nm", json!(0.5)),
                        ("n", json!(10)),
                        ("format", json!("gwy")),
                    ],
                ),
            ),
            ("gone", inst("surface", json!({}), &[], &[])),
        ]);
        let b = snap(vec![
            (
                "disk",
                inst(
                    "surface",
                    json!({"filter_s_m": 3.2e-8, "level": ["plane", "mean"], "inner": {"x": 1}}),
                    &[],
                    &[
                        ("sigma_nm", json!(0.4)),
                        ("n", json!(10)),
                        ("format", json!("spm")),
                    ],
                ),
            ),
            ("new", inst("surface", json!({}), &[], &[])),
        ]);
        let d = compare(&a, &b, &Options::default()).unwrap();
        assert!(!d.identical);
        let st: Vec<(&str, Status)> = d
            .instances
            .iter()
            .map(|i| (i.name.as_str(), i.status))
            .collect();
        assert_eq!(
            st,
            vec![
                ("disk", Status::Changed),
                ("gone", Status::Removed),
                ("new", Status::Added)
            ]
        );
        assert!(d.instances[0].why.iter().any(|w| w.contains("filter_s_m")));
        let keys: Vec<&str> = d.params.iter().map(|p| p.key.as_str()).collect();
        assert_eq!(keys, vec!["surface.disk.filter_s_m", "surface.disk.level"]);
        assert_eq!(d.params[0].old, json!(1.6e-8));
        assert_eq!(d.params[0].new, json!(3.2e-8));
        // Metrics: sigma −0.1 (−20 %), format text change; n unchanged and not listed.
        assert_eq!(d.metrics.len(), 2);
        let fmt = &d.metrics[0];
        assert_eq!((fmt.metric.as_str(), fmt.delta), ("format", None));
        let s = &d.metrics[1];
        assert_eq!(s.metric, "sigma_nm");
        assert_eq!(s.delta, Some(0.4 - 0.5));
        assert_eq!(s.rel_delta, Some((0.4 - 0.5) / 0.5));
        assert_eq!(d.summary.metrics_changed, 2);
        assert_eq!(d.summary.metrics_compared, 3);
    }

    #[test]
    fn rtol_hides_small_numeric_changes_only() {
        let a = snap(vec![(
            "s",
            inst(
                "surface",
                json!({}),
                &[],
                &[("x", json!(1.0)), ("y", json!(1.0))],
            ),
        )]);
        let b = snap(vec![(
            "s",
            inst(
                "surface",
                json!({}),
                &[],
                &[("x", json!(1.0 + 1e-9)), ("y", json!(1.1))],
            ),
        )]);
        let exact = compare(&a, &b, &Options::default()).unwrap();
        assert_eq!(exact.summary.metrics_changed, 2);
        let tol = compare(
            &a,
            &b,
            &Options {
                rtol: 1e-6,
                all: false,
            },
        )
        .unwrap();
        assert_eq!(tol.summary.metrics_changed, 1);
        assert_eq!(tol.metrics[0].metric, "y");
        assert!(compare(
            &a,
            &b,
            &Options {
                rtol: -1.0,
                all: false
            }
        )
        .is_err());
        assert!(compare(
            &a,
            &b,
            &Options {
                rtol: f64::NAN,
                all: false
            }
        )
        .is_err());
    }

    #[test]
    fn a_source_only_one_side_has_is_not_compared() {
        let a = snap(vec![(
            "s",
            inst("surface", json!({}), &[], &[("x", json!(1.0))]),
        )]);
        let mut b = a.clone();
        let i = b.instances.get_mut("s").unwrap();
        i.metrics
            .insert(("result.json".into(), "y".into()), json!(2.0));
        let d = compare(&a, &b, &Options::default()).unwrap();
        assert!(d.identical);
        assert_eq!(d.summary.metrics_compared, 1);
        // …but a column only one side's table has is a change (null → value).
        let i = b.instances.get_mut("s").unwrap();
        i.metrics.insert(("t.csv".into(), "z".into()), json!(3.0));
        let d = compare(&a, &b, &Options::default()).unwrap();
        assert_eq!(d.summary.metrics_changed, 1);
        assert_eq!(d.metrics[0].old, Value::Null);
    }

    #[test]
    fn integer_and_float_forms_of_one_number_are_equal() {
        let a = snap(vec![(
            "s",
            inst("surface", json!({}), &[], &[("x", json!(2))]),
        )]);
        let b = snap(vec![(
            "s",
            inst("surface", json!({}), &[], &[("x", json!(2.0))]),
        )]);
        assert!(compare(&a, &b, &Options::default()).unwrap().identical);
    }

    #[test]
    fn csv_cells_are_typed_and_quotes_understood() {
        let rows = table_rows(
            "stage,n,x_nm,ok,note\r\ndisk,3,0.25,true,\"a, \"\"b\"\"\"\nslider,,NaN,false,plain\n",
        )
        .unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0]["n"], json!(3));
        assert_eq!(rows[0]["x_nm"], json!(0.25));
        assert_eq!(rows[0]["ok"], json!(true));
        assert_eq!(rows[0]["note"], json!("a, \"b\""));
        assert_eq!(rows[1]["n"], Value::Null);
        assert_eq!(rows[1]["x_nm"], json!("NaN"));
        assert!(table_rows("a,b\n1\n").unwrap_err().contains("row 2"));
        assert!(table_rows("a\n\"open\n").is_err());
    }

    #[test]
    fn result_scalars_flatten_without_arrays() {
        let mut out = BTreeMap::new();
        flatten(
            "",
            &json!({"a": 1, "b": {"c": "x", "d": [1, 2]}}),
            false,
            &mut out,
        );
        assert_eq!(out.keys().collect::<Vec<_>>(), vec!["a", "b.c"]);
    }
}
