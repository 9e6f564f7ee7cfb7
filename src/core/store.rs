//! Output writers: HDF5 files following docs/hdf5.md (units and long_name on
//! every numeric dataset, NXdata groups, shuffle+gzip for large data, no plugins), and tidy
//! tables through polars (Parquet + CSV) and arrow-rs (Arrow IPC, through
//! `core::arrow_bridge`). polars lives here, in the bridge and in the LDV readers
//! (`dmw::io::{text, parquet}`) only: its Rust API churns between minor versions, so an
//! upgrade touches those files. docs/tables.md says which table format is for what.

use hdf5::types::VarLenUnicode;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Why an output could not be written. `Io`: the filesystem refused (create, rename);
/// `Write`: the HDF5 or table library failed on the named file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("writing {}: {message}", path.display())]
    Write { path: PathBuf, message: String },
    /// The table library or the filesystem failed writing the summary table `path`.
    #[error("writing {}", path.display())]
    Table {
        path: PathBuf,
        #[source]
        source: TableWriteError,
    },
}

/// Why a summary table (Parquet, CSV, Arrow IPC) could not be written.
#[derive(Debug, thiserror::Error)]
pub enum TableWriteError {
    #[error(transparent)]
    Polars(#[from] polars_core::error::PolarsError),
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// Shown as its own text only, not as a source: arrow's I/O and external errors already
    /// repeat their source in it.
    #[error("{0}")]
    Arrow(arrow_schema::ArrowError),
}

impl From<arrow_schema::ArrowError> for TableWriteError {
    fn from(e: arrow_schema::ArrowError) -> Self {
        TableWriteError::Arrow(e)
    }
}

impl OutputError {
    fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        OutputError::Io {
            path: path.into(),
            source,
        }
    }
    fn output(path: impl Into<PathBuf>, message: impl std::fmt::Display) -> Self {
        OutputError::Write {
            path: path.into(),
            message: message.to_string(),
        }
    }
}

type Result<T> = std::result::Result<T, OutputError>;

fn vlu(s: &str) -> VarLenUnicode {
    // Only NUL bytes can make this fail; strip them rather than fail an output.
    s.replace('\0', "").parse().unwrap_or_default()
}

/// An HDF5 file being written to `<path>.tmp-<pid>`; `finish` renames it into place, so a
/// crash never leaves a half-written file under the final name.
pub struct H5Out {
    file: Option<hdf5::File>,
    tmp: PathBuf,
    path: PathBuf,
}

/// Datasets smaller than this stay contiguous (§5).
const COMPRESS_MIN_BYTES: usize = 64 * 1024;

impl H5Out {
    pub fn create(path: &Path) -> Result<Self> {
        let tmp = path.with_extension(format!("h5.tmp-{}", std::process::id()));
        let file = hdf5::File::create(&tmp).map_err(|e| OutputError::output(path, e))?;
        Ok(Self {
            file: Some(file),
            tmp,
            path: path.to_path_buf(),
        })
    }

    fn file(&self) -> Result<&hdf5::File> {
        self.file
            .as_ref()
            .ok_or_else(|| self.err("file already closed"))
    }

    fn err(&self, e: impl std::fmt::Display) -> OutputError {
        OutputError::output(&self.path, e)
    }

    /// Root attributes every hdi file carries (§5).
    pub fn root_attributes(
        &self,
        stage: &str,
        cache_key: &str,
        parameters: &Value,
        inputs: &Value,
        default_entry: &str,
    ) -> Result<()> {
        let root: &hdf5::Group = self.file()?;
        self.attr_str(root, "hdi_version", env!("CARGO_PKG_VERSION"))?;
        self.attr_str(root, "stage", stage)?;
        self.attr_str(root, "cache_key", cache_key)?;
        self.attr_str(root, "parameters", &parameters.to_string())?;
        self.attr_str(root, "inputs", &inputs.to_string())?;
        // No creation time: identical inputs give byte-identical files; when a result was made
        // is in its manifest.
        self.attr_str(root, "NX_class", "NXroot")?;
        self.attr_str(root, "default", default_entry)?;
        Ok(())
    }

    /// Create a group (and its parents); `nx_class` sets the NeXus class attribute.
    pub fn group(&self, path: &str, nx_class: Option<&str>) -> Result<hdf5::Group> {
        let mut g: hdf5::Group = self.file()?.as_group().map_err(|e| self.err(e))?;
        for part in path.split('/').filter(|p| !p.is_empty()) {
            g = match g.group(part) {
                Ok(existing) => existing,
                Err(_) => g.create_group(part).map_err(|e| self.err(e))?,
            };
        }
        if let Some(c) = nx_class {
            self.attr_str(&g, "NX_class", c)?;
        }
        Ok(g)
    }

    pub fn attr_str(&self, loc: &hdf5::Location, name: &str, value: &str) -> Result<()> {
        loc.new_attr::<VarLenUnicode>()
            .create(name)
            .and_then(|a| a.write_scalar(&vlu(value)))
            .map_err(|e| self.err(format!("attribute {name}: {e}")))
    }

    pub fn attr_str_list(&self, loc: &hdf5::Location, name: &str, values: &[&str]) -> Result<()> {
        let v: Vec<VarLenUnicode> = values.iter().map(|s| vlu(s)).collect();
        loc.new_attr_builder()
            .with_data(v.as_slice())
            .create(name)
            .map(|_| ())
            .map_err(|e| self.err(format!("attribute {name}: {e}")))
    }

    /// An NXdata group of time histories: `signal` as the default plot, a `time` axis of `n`
    /// samples `dt` apart with its `sampling_rate` attribute (the layout `hdi analyze` reads).
    pub fn history_group(
        &self,
        path: &str,
        signal: &str,
        dt: f64,
        n: usize,
    ) -> Result<hdf5::Group> {
        let g = self.group(path, Some("NXdata"))?;
        self.attr_str(&g, "signal", signal)?;
        self.attr_str_list(&g, "axes", &["time"])?;
        let time: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
        let t = self.write_1d(&g, "time", &time, "s", "time")?;
        self.attr_f64(&t, "sampling_rate", 1.0 / dt)?;
        Ok(g)
    }

    pub fn attr_f64(&self, loc: &hdf5::Location, name: &str, value: f64) -> Result<()> {
        loc.new_attr::<f64>()
            .create(name)
            .and_then(|a| a.write_scalar(&value))
            .map_err(|e| self.err(format!("attribute {name}: {e}")))
    }

    fn describe(&self, ds: &hdf5::Dataset, units: &str, long_name: &str) -> Result<()> {
        self.attr_str(ds, "units", units)?;
        self.attr_str(ds, "long_name", long_name)
    }

    /// An n-D dataset with units: contiguous when small, else chunked (1-D: up to 65 536
    /// elements; n-D: up to 256 per axis) with shuffle + gzip(4), which every HDF5 reads.
    pub fn write_array<T: hdf5::H5Type + Clone, D: ndarray::Dimension>(
        &self,
        g: &hdf5::Group,
        name: &str,
        data: ndarray::ArrayView<T, D>,
        units: &str,
        long_name: &str,
    ) -> Result<hdf5::Dataset> {
        // HDF5 writes row-major memory; views from slicing may not be.
        let data = data.as_standard_layout();
        let b = g.new_dataset_builder().with_data(data.view());
        let ds = if data.len() * std::mem::size_of::<T>() >= COMPRESS_MIN_BYTES {
            let cap = if data.ndim() == 1 { 65_536 } else { 256 };
            let chunk: Vec<usize> = data.shape().iter().map(|&n| n.min(cap)).collect();
            b.chunk(chunk).shuffle().deflate(4).create(name)
        } else {
            b.create(name)
        }
        .map_err(|e| self.err(format!("dataset {name}: {e}")))?;
        self.describe(&ds, units, long_name)?;
        Ok(ds)
    }

    /// 1-D f64 dataset with units.
    pub fn write_1d(
        &self,
        g: &hdf5::Group,
        name: &str,
        data: &[f64],
        units: &str,
        long_name: &str,
    ) -> Result<hdf5::Dataset> {
        self.write_array(g, name, ndarray::ArrayView1::from(data), units, long_name)
    }

    /// Scalar f64 dataset (so `f[path][()]` is a float).
    pub fn write_scalar(
        &self,
        g: &hdf5::Group,
        name: &str,
        value: f64,
        units: &str,
        long_name: &str,
    ) -> Result<()> {
        let ds = g
            .new_dataset::<f64>()
            .create(name)
            .and_then(|d| d.write_scalar(&value).map(|_| d))
            .map_err(|e| self.err(format!("dataset {name}: {e}")))?;
        self.describe(&ds, units, long_name)
    }

    /// Scalar integer count.
    pub fn write_count(
        &self,
        g: &hdf5::Group,
        name: &str,
        value: u64,
        long_name: &str,
    ) -> Result<()> {
        let ds = g
            .new_dataset::<u64>()
            .create(name)
            .and_then(|d| d.write_scalar(&value).map(|_| d))
            .map_err(|e| self.err(format!("dataset {name}: {e}")))?;
        self.describe(&ds, "1", long_name)
    }

    /// Scalar UTF-8 string dataset.
    pub fn write_string(&self, g: &hdf5::Group, name: &str, value: &str) -> Result<()> {
        g.new_dataset::<VarLenUnicode>()
            .create(name)
            .and_then(|d| d.write_scalar(&vlu(value)))
            .map_err(|e| self.err(format!("dataset {name}: {e}")))
    }

    /// Close and move into place.
    pub fn finish(mut self) -> Result<()> {
        if let Some(file) = self.file.take() {
            file.close()
                .map_err(|e| OutputError::output(&self.path, e))?;
        }
        std::fs::rename(&self.tmp, &self.path).map_err(|e| OutputError::io(&self.path, e))
    }
}

impl Drop for H5Out {
    fn drop(&mut self) {
        // Reached without `finish` only on error paths: do not leave the temp file behind.
        drop(self.file.take());
        if self.tmp.exists() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// `x` rounded to `digits` significant digits, for summary tables (1.92325, not
/// 1.9232500000000001); zero and non-finite values pass through. HDF5 keeps full precision.
pub fn round_significant(x: f64, digits: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(digits - 1 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

/// Write rows (JSON objects with the same keys) as `<stem>.parquet`, `<stem>.csv` and
/// `<stem>.arrow` (Arrow IPC file = Feather v2, uncompressed so that readers can memory-map
/// it; every field with a unit suffix carries `unit` metadata, [`unit_of_column`]; the
/// Parquet file has them all in its file-level key `units`).
/// Integers become Int64 columns, other numbers Float64, strings Utf8 (LargeUtf8 in Arrow),
/// booleans Boolean; a missing key or JSON null is a null. (An all-null column is Float64.)
/// Typed rows as table rows: each serialised to a JSON object (field order is column order).
pub fn rows_of<T: serde::Serialize>(rows: &[T]) -> Vec<serde_json::Map<String, Value>> {
    rows.iter()
        .map(|r| match serde_json::to_value(r) {
            Ok(Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        })
        .collect()
}

pub fn write_table(rows: &[serde_json::Map<String, Value>], stem: &Path) -> Result<()> {
    use polars_core::prelude::*;
    use polars_io::prelude::*;
    let mut names: Vec<String> = Vec::new();
    for r in rows {
        for k in r.keys() {
            if !names.contains(k) {
                names.push(k.clone());
            }
        }
    }
    let mut columns: Vec<Column> = Vec::new();
    for name in &names {
        // JSON null and a missing key are both a missing value.
        let values: Vec<Option<&Value>> = rows
            .iter()
            .map(|r| r.get(name).filter(|v| !v.is_null()))
            .collect();
        let present = || values.iter().flatten();
        let col = if present().next().is_some() && present().all(|v| v.is_i64()) {
            let v: Vec<Option<i64>> = values.iter().map(|v| v.and_then(Value::as_i64)).collect();
            Column::new(name.as_str().into(), v)
        } else if present().all(|v| v.is_number()) {
            let v: Vec<Option<f64>> = values.iter().map(|v| v.and_then(Value::as_f64)).collect();
            Column::new(name.as_str().into(), v)
        } else if present().all(|v| v.is_boolean()) {
            let v: Vec<Option<bool>> = values.iter().map(|v| v.and_then(Value::as_bool)).collect();
            Column::new(name.as_str().into(), v)
        } else {
            let v: Vec<Option<String>> = values
                .iter()
                .map(|v| {
                    v.map(|x| match x {
                        Value::String(s) => s.clone(),
                        other => other.to_string(),
                    })
                })
                .collect();
            Column::new(name.as_str().into(), v)
        };
        columns.push(col);
    }
    let mut df = DataFrame::new(rows.len(), columns).map_err(|e| OutputError::output(stem, e))?;

    // Parquet has no per-column metadata of its own: the units go into one file-level key,
    // `units` = {"column": "unit", …} in column order (docs/tables.md). One key in a Vec:
    // deterministic.
    let units: serde_json::Map<String, Value> = names
        .iter()
        .filter_map(|n| unit_of_column(n).map(|u| (n.clone(), Value::from(u))))
        .collect();
    let units_kv = (!units.is_empty()).then(|| {
        KeyValueMetadata::from_static(vec![("units".into(), Value::Object(units).to_string())])
    });
    let parquet = stem.with_extension("parquet");
    write_via_temp(&parquet, |f| {
        ParquetWriter::new(f)
            .with_compression(ParquetCompression::Zstd(None))
            .with_key_value_metadata(units_kv)
            .finish(&mut df)?;
        Ok(())
    })?;
    let csv = stem.with_extension("csv");
    write_via_temp(&csv, |f| {
        CsvWriter::new(f).include_header(true).finish(&mut df)?;
        Ok(())
    })?;
    let arrow = stem.with_extension("arrow");
    let batch =
        super::arrow_bridge::to_record_batch(&df).map_err(|e| OutputError::output(&arrow, e))?;
    write_via_temp(&arrow, |f| write_arrow_ipc(f, &batch))
}

/// One record batch as an Arrow IPC file, unit metadata added. Deterministic: the only
/// metadata maps (arrow-rs keeps them in `HashMap`s) have a single key, the schema and footer
/// have none, and the writer zero-fills its padding.
fn write_arrow_ipc(
    f: &mut std::fs::File,
    batch: &arrow_array::RecordBatch,
) -> std::result::Result<(), TableWriteError> {
    use arrow_schema::{Field, Schema};
    use std::collections::HashMap;
    use std::sync::Arc;
    let fields: Vec<Field> = batch
        .schema_ref()
        .fields()
        .iter()
        .map(|field| {
            let meta: HashMap<String, String> = unit_of_column(field.name())
                .map(|u| HashMap::from([("unit".to_string(), u.to_string())]))
                .unwrap_or_default();
            field.as_ref().clone().with_metadata(meta)
        })
        .collect();
    let schema = Arc::new(Schema::new(fields));
    let batch = batch.clone().with_schema(schema.clone())?;
    // Default options: format V5, 64-byte alignment, no compression (memory-mappable).
    let mut w = arrow_ipc::writer::FileWriter::try_new(std::io::BufWriter::new(f), &schema)?;
    w.write(&batch)?;
    w.finish()?;
    let mut out = w.into_inner()?;
    std::io::Write::flush(&mut out)?;
    Ok(())
}

/// The unit a column name's suffix states (docs/tables.md, "Units"), as written into the
/// Arrow field metadata `unit`: the longest matching suffix of `_`-separated tokens in
/// [`UNIT_SUFFIXES`] wins (`k_P_max_N_per_m` → `N/m`, not `m`). A name whose suffix is not
/// in the table (`Sku`, `slope_A`, `case`) has no unit: dimensionless, coded or text.
pub fn unit_of_column(name: &str) -> Option<&'static str> {
    UNIT_SUFFIXES
        .iter()
        .filter(|(suffix, _)| {
            name.len() > suffix.len() + 1
                && name.ends_with(suffix)
                && name.as_bytes()[name.len() - suffix.len() - 1] == b'_'
        })
        .max_by_key(|(suffix, _)| suffix.len())
        .map(|&(_, unit)| unit)
}

/// Column-name suffix → unit, for the suffixes hdi's tables use (ASCII `u` for micro, as
/// UDUNITS parses it).
pub const UNIT_SUFFIXES: &[(&str, &str)] = &[
    // length
    ("m", "m"),
    ("mm", "mm"),
    ("um", "um"),
    ("nm", "nm"),
    // area, density
    ("um2", "um^2"),
    ("per_um2", "1/um^2"),
    // time
    ("s", "s"),
    ("ms", "ms"),
    ("us", "us"),
    // frequency
    ("Hz", "Hz"),
    ("kHz", "kHz"),
    ("MHz", "MHz"),
    // force
    ("N", "N"),
    ("mN", "mN"),
    ("uN", "uN"),
    // pressure, modulus
    ("Pa", "Pa"),
    ("MPa", "MPa"),
    ("GPa", "GPa"),
    // power
    ("W", "W"),
    ("mW", "mW"),
    // angle
    ("rad", "rad"),
    ("urad", "urad"),
    // stiffness, velocity, efficiency
    ("N_per_m", "N/m"),
    ("mm_s", "mm/s"),
    ("um_s", "um/s"),
    ("nm_per_mW", "nm/mW"),
    // fractions
    ("percent", "%"),
    ("pct", "%"),
];

fn write_via_temp(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::result::Result<(), TableWriteError>,
) -> Result<()> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| OutputError::io(parent, e))?;
    }
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    let mut f = std::fs::File::create(&tmp).map_err(|e| OutputError::io(&tmp, e))?;
    let r = write(&mut f).and_then(|_| Ok(f.sync_all()?));
    if let Err(source) = r {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError::Table {
            path: path.to_path_buf(),
            source,
        });
    }
    std::fs::rename(&tmp, path).map_err(|e| OutputError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn unit_suffixes_of_the_pipeline_columns() {
        // Column names as the shipped pipeline writes them (processed/tables and stage tables).
        for (name, unit) in [
            ("clearance_nm", Some("nm")),
            ("a_tfc_m", Some("m")),
            ("R_um", Some("um")),
            ("nominal_area_um2", Some("um^2")),
            ("eta_per_um2", Some("1/um^2")),
            ("nayak_eta_per_um2", Some("1/um^2")),
            ("wall_time_s", Some("s")),
            ("duration_ms", Some("ms")),
            ("dominant_frequency_kHz", Some("kHz")),
            ("sample_rate_MHz", Some("MHz")),
            ("peak_contact_force_mN", Some("mN")),
            ("Q_lub_transition_end_uN", Some("uN")),
            ("P_at_3sigma_Pa", Some("Pa")),
            ("E_star_GPa", Some("GPa")),
            ("heater_power_mW", Some("mW")),
            ("roll_std_urad", Some("urad")),
            ("k_P_max_N_per_m", Some("N/m")),
            ("velocity_std_mm_s", Some("mm/s")),
            ("noise_floor_um_s", Some("um/s")),
            ("efficiency_nm_per_mW", Some("nm/mW")),
            ("bulge_vibration_percent", Some("%")),
            ("masked_pct", Some("%")),
            // No unit suffix: dimensionless, coded, counts, text.
            ("Sku", None),
            ("slope_A", None),
            ("a_tfc_coded", None),
            ("n_samples", None),
            ("period_relstd", None),
            ("case", None),
            ("t", None),
            // A bare unit is a name, not a suffix.
            ("nm", None),
            ("_nm", None),
        ] {
            assert_eq!(unit_of_column(name), unit, "{name}");
        }
    }

    fn read_ipc(path: &Path) -> (arrow_schema::SchemaRef, Vec<arrow_array::RecordBatch>) {
        let f = std::fs::File::open(path).expect("open");
        let r = arrow_ipc::reader::FileReader::try_new(f, None).expect("Arrow IPC file");
        let schema = r.schema();
        let batches = r
            .collect::<std::result::Result<Vec<_>, _>>()
            .expect("batches");
        (schema, batches)
    }

    #[test]
    fn write_table_writes_an_arrow_ipc_file_with_units_that_arrow_ipc_reads_back() {
        use arrow_array::{Array, BooleanArray, Float64Array, Int64Array, LargeStringArray};
        let rows: Vec<serde_json::Map<String, Value>> = [
            json!({"case": "a", "n_steps": 3, "clearance_nm": 1.25, "k_N_per_m": 2e5, "ok": true}),
            json!({"case": "b", "n_steps": null, "clearance_nm": -0.5, "ok": false}),
            json!({"case": null, "n_steps": 7, "clearance_nm": 1e-300, "k_N_per_m": 3, "ok": null}),
        ]
        .into_iter()
        .map(|v| v.as_object().cloned().expect("object"))
        .collect();
        let dir = tempfile::tempdir().expect("tempdir");
        let stem = dir.path().join("t");
        write_table(&rows, &stem).expect("write");
        let arrow = stem.with_extension("arrow");
        let (schema, batches) = read_ipc(&arrow);
        assert_eq!(batches.len(), 1);
        let b = &batches[0];
        assert_eq!(b.num_rows(), 3);
        let names: Vec<&str> = schema.fields().iter().map(|f| f.name().as_str()).collect();
        assert_eq!(
            names,
            ["case", "n_steps", "clearance_nm", "k_N_per_m", "ok"]
        );
        let unit = |i: usize| schema.field(i).metadata().get("unit").cloned();
        assert_eq!(
            (0..5).map(unit).collect::<Vec<_>>(),
            [None, None, Some("nm".into()), Some("N/m".into()), None]
        );
        let case = b
            .column(0)
            .as_any()
            .downcast_ref::<LargeStringArray>()
            .expect("str");
        assert_eq!(
            case.iter().collect::<Vec<_>>(),
            [Some("a"), Some("b"), None]
        );
        let n = b
            .column(1)
            .as_any()
            .downcast_ref::<Int64Array>()
            .expect("i64");
        assert_eq!(n.iter().collect::<Vec<_>>(), [Some(3), None, Some(7)]);
        let c = b
            .column(2)
            .as_any()
            .downcast_ref::<Float64Array>()
            .expect("f64");
        assert_eq!(
            c.iter().collect::<Vec<_>>(),
            [Some(1.25), Some(-0.5), Some(1e-300)]
        );
        // 2e5 and 3 mixed: a Float64 column; the missing key is a null.
        let k = b
            .column(3)
            .as_any()
            .downcast_ref::<Float64Array>()
            .expect("f64");
        assert_eq!(k.iter().collect::<Vec<_>>(), [Some(2e5), None, Some(3.0)]);
        let ok = b
            .column(4)
            .as_any()
            .downcast_ref::<BooleanArray>()
            .expect("bool");
        assert_eq!(
            ok.iter().collect::<Vec<_>>(),
            [Some(true), Some(false), None]
        );
        assert_eq!(ok.null_count(), 1);

        // Byte-identical on a rewrite (determinism), and no temp file left behind.
        let first = std::fs::read(&arrow).expect("read");
        write_table(&rows, &stem).expect("rewrite");
        assert_eq!(first, std::fs::read(&arrow).expect("read"));
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .expect("dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["t.arrow", "t.csv", "t.parquet"]);
    }

    #[test]
    fn an_empty_table_is_a_valid_arrow_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let stem = dir.path().join("e");
        write_table(&[], &stem).expect("write");
        let (schema, batches) = read_ipc(&stem.with_extension("arrow"));
        assert_eq!(schema.fields().len(), 0);
        assert_eq!(batches.iter().map(|b| b.num_rows()).sum::<usize>(), 0);
    }
}
