//! One numeric series from a table file, for `hdi analyze` (docs/analysis.md): delimited text
//! (CSV, TSV, semicolon- or space-separated), Parquet, Arrow IPC file/stream (memory-mapped,
//! through [`super::arrow::table`]) and `.npy` (memory-mapped, through
//! [`super::npy::npy_table`]). HDF5 files are read by the analysis stage, which knows hdi's
//! layouts; the name, unit and time-axis rules below are shared with it.
//!
//! - The series: `column` if given (exact name, or case-insensitive), else the one numeric
//!   column that is not a time or sample-number column; otherwise an error listing them.
//! - Its unit from the Arrow field's `units`/`unit` metadata or the name (`heave_nm`,
//!   `displacement (µm)`, `velocity [mm/s]`, see [`si_unit`]); values are converted to SI.
//! - The sample rate from a time column (`time`, `t`, `time_s`, `time_ms`, `t [us]`, …;
//!   steps checked for uniformity), else from `--sample-rate`, else from metadata
//!   (`# sample_rate = 500 kHz` lines, Parquet key-value or Arrow schema metadata:
//!   `sample_rate`, `sampling_rate`, `fs`, or `dt` in s). When a time column and a stated rate
//!   both exist they must agree within [`RATE_RTOL`]; the time column's start is `t0`.

use super::names::{self, Meta, Role, Unit};
use super::{arrow, detect_format, no_panic, npy, read_err, record_err, LdvFormat};
use crate::dmw::DmwError;
use std::path::Path;

/// Agreement required between a time column and a stated sample rate (relative).
pub const RATE_RTOL: f64 = 1e-6;
/// Largest deviation of one time step from the mean step, relative to the mean step.
pub const UNIFORM_RTOL: f64 = 1e-3;
/// The formats, for messages.
const SERIES_FORMATS: &str = "use CSV/TSV, Parquet, Arrow IPC, .npy or HDF5";
/// Fewest samples a series may have.
pub const MIN_SAMPLES: usize = 16;

/// What to read.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SeriesRequest {
    /// The series' column; default: the only numeric non-time column.
    pub column: Option<String>,
    /// Sample rate, Hz (checked against a time column if there is one).
    pub sample_rate: Option<f64>,
}

/// A string attribute of an HDF5 object in any encoding h5py and other writers use (the LDV
/// reader's rule), for the analysis stage's HDF5 series.
pub fn hdf5_attr_string(loc: &hdf5::Location, name: &str) -> Option<String> {
    super::h5::attr_string(loc, name)
}

/// A numeric HDF5 attribute, scalar or one-element array.
pub fn hdf5_attr_number(loc: &hdf5::Location, name: &str) -> Option<f64> {
    super::h5::attr_number(loc, name)
}

/// A series in SI units with its time axis.
#[derive(Debug, Clone, PartialEq)]
pub struct TableSeries {
    pub values: Vec<f64>,
    /// The column as named in the file.
    pub column: String,
    /// SI unit of `values` ("1" when the file does not say).
    pub unit: String,
    pub sample_rate: f64,
    /// Time of the first sample, s.
    pub t0: f64,
    /// Where the sample rate came from, e.g. "time column `time_s`".
    pub rate_source: String,
    /// "csv", "parquet", "arrow-file", "arrow-stream", "npy".
    pub format: &'static str,
}

/// A unit spelling → (SI unit, factor to SI). Case matters for the prefixes (`ms` is
/// milliseconds, `Ms` is not accepted), `u`, `µ` and `μ` are micro.
pub fn si_unit(text: &str) -> Option<(&'static str, f64)> {
    let t: String = text
        .trim()
        .chars()
        .filter(|c| !c.is_whitespace())
        .map(|c| if c == 'µ' || c == 'μ' { 'u' } else { c })
        .collect();
    let t = t.replace("_per_", "/");
    let (base, rest) = match t.find(['/', '_']) {
        Some(k) => (&t[..k], Some(&t[k + 1..])),
        None => (t.as_str(), None),
    };
    let length = |b: &str| match b {
        "m" => Some(1.0),
        "mm" => Some(1e-3),
        "um" => Some(1e-6),
        "nm" => Some(1e-9),
        "pm" => Some(1e-12),
        "A" | "angstrom" => Some(1e-10),
        _ => None,
    };
    if let Some(rest) = rest {
        // Speeds: m/s, mm/s, um_s, nm_s.
        return match (length(base), rest) {
            (Some(f), "s") => Some(("m/s", f)),
            _ => None,
        };
    }
    if let Some(f) = length(base) {
        return Some(("m", f));
    }
    Some(match base {
        "mps" => ("m/s", 1.0),
        "s" => ("s", 1.0),
        "ms" => ("s", 1e-3),
        "us" => ("s", 1e-6),
        "ns" => ("s", 1e-9),
        "V" => ("V", 1.0),
        "mV" => ("V", 1e-3),
        "uV" => ("V", 1e-6),
        "N" => ("N", 1.0),
        "mN" => ("N", 1e-3),
        "uN" => ("N", 1e-6),
        "nN" => ("N", 1e-9),
        "Pa" => ("Pa", 1.0),
        "kPa" => ("Pa", 1e3),
        "MPa" => ("Pa", 1e6),
        "GPa" => ("Pa", 1e9),
        "rad" => ("rad", 1.0),
        "mrad" => ("rad", 1e-3),
        "urad" => ("rad", 1e-6),
        "Hz" => ("Hz", 1.0),
        "kHz" => ("Hz", 1e3),
        "1" => ("1", 1.0),
        _ => return None,
    })
}

/// The unit a column name carries: `name (unit)`, `name [unit]`, or the shortest `_unit`
/// suffix that is one (`velocity_m_s` → m/s, `heave_nm` → nm). `None`: no unit in the name.
pub fn unit_of_name(name: &str) -> Option<(&'static str, f64)> {
    let n = names::clean(name);
    for (open, close) in [('(', ')'), ('[', ']')] {
        if let Some(stripped) = n.strip_suffix(close) {
            if let Some(k) = stripped.rfind(open) {
                return si_unit(&stripped[k + 1..]);
            }
        }
    }
    // Try the longest suffix first so that `_m_s` wins over `_s`.
    n.match_indices('_')
        .map(|(k, _)| &n[k + 1..])
        .find_map(si_unit)
}

/// How a column's name marks it: a time axis (with its factor to s), a sample number, or data.
fn time_role(name: &str) -> Option<Option<f64>> {
    let p = names::classify(name);
    match (p.role, p.unit) {
        (Some(Role::Time), Some(Unit::Second(f))) => Some(Some(f)),
        (Some(Role::Time), _) => Some(Some(1.0)),
        (Some(Role::Sample), _) => Some(None),
        _ => None,
    }
}

/// A column read whole: values, or why it is not numeric.
struct RawColumn {
    name: String,
    values: Result<Vec<f64>, String>,
    /// The unit the file states for it (Arrow field metadata).
    unit: Option<String>,
}

/// Reads the series (rules in the module docs). Every error names the file and the column.
pub fn read_table_series(path: &Path, req: &SeriesRequest) -> Result<TableSeries, DmwError> {
    if let Some(fs) = req.sample_rate {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(record_err(
                path,
                format!("sample rate {fs} Hz: must be a positive number"),
            ));
        }
    }
    let format = detect_format(path)?;
    let (columns, meta, fmt) = match format {
        LdvFormat::Csv => {
            let (c, m) = read_text(path)?;
            (c, m, "csv")
        }
        LdvFormat::Parquet => {
            let (c, m) = no_panic(path, "the Parquet reader", || read_parquet(path))?;
            (c, m, "parquet")
        }
        LdvFormat::Arrow => {
            let dec = arrow::decode(path)?;
            let table = arrow::table(path, &dec, &super::ReadOptions::default())?;
            let mut cols = Vec::new();
            for c in &table.columns {
                cols.push(RawColumn {
                    name: c.name.clone(),
                    values: Ok(c.values(path)?),
                    unit: c.unit.clone(),
                });
            }
            let kind = dec.kind;
            (cols, table.meta, kind)
        }
        LdvFormat::Npy => {
            let mmap = npy::map_file(path)?;
            let header =
                crate::formats::npy::parse(&mmap, mmap.len()).map_err(|e| read_err(path, e))?;
            let structured = matches!(header.dtype, crate::formats::npy::Dtype::Structured { .. });
            let table = npy::npy_table(path, &mmap)?;
            let k = table.columns.len();
            let mut cols = Vec::new();
            for (j, c) in table.columns.iter().enumerate() {
                // Plain arrays have no names: one column is the series, two are (time s,
                // series), more are numbered from 0.
                let name = match (structured, k, j) {
                    (true, _, _) => c.name.clone(),
                    (false, 1, _) => "values".to_string(),
                    (false, 2, 0) => "time_s".to_string(),
                    (false, 2, _) => "values".to_string(),
                    (false, _, j) => j.to_string(),
                };
                cols.push(RawColumn {
                    name,
                    values: Ok(c.values(path)?),
                    unit: None,
                });
            }
            (cols, Meta::default(), "npy")
        }
        other => {
            let msg = format!(
                "{} is not read by `hdi analyze`; {SERIES_FORMATS}",
                other.name()
            );
            return Err(read_err(path, msg));
        }
    };
    choose(path, columns, &meta, fmt, req)
}

/// Picks the series and the time axis from the columns (module docs).
fn choose(
    path: &Path,
    columns: Vec<RawColumn>,
    meta: &Meta,
    format: &'static str,
    req: &SeriesRequest,
) -> Result<TableSeries, DmwError> {
    if columns.is_empty() {
        return Err(record_err(path, "no columns"));
    }
    let described: Vec<String> = columns
        .iter()
        .map(|c| match &c.values {
            Ok(_) => c.name.clone(),
            Err(_) => format!("{} (not numeric)", c.name),
        })
        .collect();
    let list = described.join(", ");
    let time_idx = columns
        .iter()
        .position(|c| matches!(time_role(&c.name), Some(Some(_))) && c.values.is_ok());
    let k = match &req.column {
        Some(want) => {
            let w = names::clean(want);
            columns
                .iter()
                .position(|c| c.name == w)
                .or_else(|| {
                    columns
                        .iter()
                        .position(|c| names::clean(&c.name).eq_ignore_ascii_case(w))
                })
                .ok_or_else(|| record_err(path, format!("no column `{want}` (columns: {list})")))?
        }
        None => {
            // Prefer the one numeric data column; a lone non-numeric one is reported as such.
            let data: Vec<usize> = (0..columns.len())
                .filter(|&k| time_role(&columns[k].name).is_none())
                .collect();
            let numeric: Vec<usize> = data
                .iter()
                .copied()
                .filter(|&k| columns[k].values.is_ok())
                .collect();
            match (numeric.as_slice(), data.as_slice()) {
                ([one], _) | ([], [one]) => *one,
                ([], _) => {
                    return Err(record_err(
                        path,
                        format!("no numeric data column besides time (columns: {list})"),
                    ))
                }
                _ => {
                    return Err(record_err(
                        path,
                        format!("several data columns; choose one with --column (columns: {list})"),
                    ))
                }
            }
        }
    };
    let col = &columns[k];
    let raw = match &col.values {
        Ok(v) => v,
        Err(why) => {
            return Err(record_err(
                path,
                format!("column `{}` is not numeric: {why}", col.name),
            ))
        }
    };
    check_values(path, &col.name, raw)?;
    let (unit, factor) = match &col.unit {
        Some(u) => si_unit(u).ok_or_else(|| {
            record_err(
                path,
                format!("column `{}`: unit `{u}` is not one hdi knows", col.name),
            )
        })?,
        None => unit_of_name(&col.name).unwrap_or(("1", 1.0)),
    };
    let values: Vec<f64> = raw.iter().map(|v| v * factor).collect();
    let stated = match req.sample_rate {
        Some(fs) => Some((fs, "--sample-rate".to_string())),
        None => meta_rate(path, meta)?,
    };
    // time_idx points at a numeric column only.
    let time = time_idx.filter(|&t| t != k).and_then(|t| {
        let tv = columns[t].values.as_ref().ok()?;
        let scale = time_role(&columns[t].name).flatten().unwrap_or(1.0);
        let secs: Vec<f64> = tv.iter().map(|v| v * scale).collect();
        Some((columns[t].name.clone(), secs))
    });
    let (sample_rate, t0, rate_source) = match (time, stated) {
        (Some((name, t)), stated) => {
            let (fs, t0) = rate_from_time(path, &name, &t)?;
            if let Some((s, from)) = stated {
                if ((s - fs) / fs).abs() > RATE_RTOL {
                    return Err(record_err(
                        path,
                        format!(
                            "time column `{name}` gives {fs} Hz but {from} says {s} Hz; \
                             drop one or make them agree"
                        ),
                    ));
                }
            }
            (fs, t0, format!("time column `{name}`"))
        }
        (None, Some((fs, from))) => (fs, meta.t0.unwrap_or(0.0), from),
        (None, None) => {
            return Err(record_err(
                path,
                format!(
                    "no time column and no sample rate: add a `time_s` column, a \
                     `sample_rate` metadata entry, or pass --sample-rate (columns: {list})"
                ),
            ))
        }
    };
    Ok(TableSeries {
        values,
        column: col.name.clone(),
        unit: unit.to_string(),
        sample_rate,
        t0,
        rate_source,
        format,
    })
}

/// A rate stated in the metadata: `sample_rate` (and spellings) or `dt` in s.
fn meta_rate(path: &Path, meta: &Meta) -> Result<Option<(f64, String)>, DmwError> {
    if let Some(fs) = meta.sample_rate {
        return Ok(Some((fs, "metadata `sample_rate`".into())));
    }
    if let Some((_, v)) = meta.other.iter().find(|(k, _)| k == "dt") {
        let dt: f64 = v
            .split_whitespace()
            .next()
            .and_then(|x| x.parse().ok())
            .ok_or_else(|| record_err(path, format!("metadata `dt = {v}` is not a number (s)")))?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(record_err(
                path,
                format!("metadata `dt = {v}` must be > 0 s"),
            ));
        }
        return Ok(Some((1.0 / dt, "metadata `dt`".into())));
    }
    Ok(None)
}

/// At least [`MIN_SAMPLES`] values, all finite; the error names the column and the row.
pub fn check_values(path: &Path, name: &str, v: &[f64]) -> Result<(), DmwError> {
    if v.len() < MIN_SAMPLES {
        return Err(record_err(
            path,
            format!(
                "`{name}`: {} samples are too few (need at least {MIN_SAMPLES})",
                v.len()
            ),
        ));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(record_err(
            path,
            format!(
                "`{name}`: non-finite value {} at sample {i} (an empty cell reads NaN); the \
                 series must be finite",
                v[i]
            ),
        ));
    }
    Ok(())
}

/// Sample rate and start time from a time axis in s: increasing, each step within
/// [`UNIFORM_RTOL`] of the mean step; the error names the worst step and where it is.
pub fn rate_from_time(path: &Path, name: &str, t: &[f64]) -> Result<(f64, f64), DmwError> {
    if t.len() < 2 {
        return Err(record_err(
            path,
            format!("time `{name}`: fewer than 2 values"),
        ));
    }
    if let Some(i) = t.iter().position(|x| !x.is_finite()) {
        return Err(record_err(
            path,
            format!("time `{name}`: non-finite value at sample {i}"),
        ));
    }
    let n = t.len();
    let mean = (t[n - 1] - t[0]) / (n - 1) as f64;
    if mean.is_nan() || mean <= 0.0 {
        return Err(record_err(
            path,
            format!(
                "time `{name}` does not increase ({} … {} s)",
                t[0],
                t[n - 1]
            ),
        ));
    }
    let (worst, at) = t
        .windows(2)
        .enumerate()
        .map(|(i, w)| (((w[1] - w[0]) - mean).abs() / mean, i))
        .fold((0.0f64, 0usize), |a, b| if b.0 > a.0 { b } else { a });
    if worst > UNIFORM_RTOL {
        return Err(record_err(
            path,
            format!(
                "time `{name}` is not uniformly sampled: the step from sample {at} to {} \
                 ({} s → {} s) deviates {:.3} % from the mean step {mean:e} s (limit {} %)",
                at + 1,
                t[at],
                t[at + 1],
                worst * 100.0,
                UNIFORM_RTOL * 100.0
            ),
        ));
    }
    Ok((1.0 / mean, t[0]))
}

/// Delimited text: `#` metadata lines (`# key = value`), a header line, rows of numbers.
/// The delimiter is the header's: tab, comma, semicolon, else runs of spaces.
fn read_text(path: &Path) -> Result<(Vec<RawColumn>, Meta), DmwError> {
    let text = std::fs::read_to_string(path).map_err(|e| read_err(path, e))?;
    let mut meta = Meta::default();
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (header_line, header) = loop {
        let Some((i, l)) = lines.next() else {
            return Err(record_err(path, "no header line"));
        };
        if let Some(c) = l.trim_start().strip_prefix('#') {
            if let Some((k, v)) = c.split_once('=').or_else(|| c.split_once(':')) {
                meta.set(k, v)
                    .map_err(|m| record_err(path, format!("line {}: {m}", i + 1)))?;
            }
            continue;
        }
        break (i, l);
    };
    let delim: Option<char> = ['\t', ',', ';'].into_iter().find(|d| header.contains(*d));
    let split = |l: &str| -> Vec<String> {
        match delim {
            Some(d) => l.split(d).map(|s| s.trim().to_string()).collect(),
            None => l.split_whitespace().map(str::to_string).collect(),
        }
    };
    let names: Vec<String> = split(header)
        .into_iter()
        .map(|n| names::clean(&n).to_string())
        .collect();
    let mut values: Vec<Result<Vec<f64>, String>> = vec![Ok(Vec::new()); names.len()];
    for (i, l) in lines {
        if l.trim_start().starts_with('#') {
            continue;
        }
        let fields = split(l);
        if fields.len() != names.len() {
            return Err(record_err(
                path,
                format!(
                    "line {}: {} fields, the header (line {}) has {}; is the file cut?",
                    i + 1,
                    fields.len(),
                    header_line + 1,
                    names.len()
                ),
            ));
        }
        for (col, f) in values.iter_mut().zip(&fields) {
            if let Ok(v) = col {
                if f.is_empty() {
                    v.push(f64::NAN);
                } else {
                    match f.parse::<f64>() {
                        Ok(x) => v.push(x),
                        Err(_) => *col = Err(format!("`{f}` on line {}", i + 1)),
                    }
                }
            }
        }
    }
    Ok((
        names
            .into_iter()
            .zip(values)
            .map(|(name, values)| RawColumn {
                name,
                values,
                unit: None,
            })
            .collect(),
        meta,
    ))
}

/// Parquet through polars: every column, numeric ones cast to Float64 (nulls → NaN), plus the
/// file's key-value metadata.
fn read_parquet(path: &Path) -> Result<(Vec<RawColumn>, Meta), DmwError> {
    use polars_core::prelude::*;
    use polars_io::prelude::*;
    let file = std::fs::File::open(path).map_err(|e| read_err(path, e))?;
    let mut reader = ParquetReader::new(file);
    let md = reader
        .get_metadata()
        .map_err(|e| read_err(path, format!("Parquet footer: {e}")))?;
    let mut meta = Meta::default();
    for kv in md.key_value_metadata().iter().flatten() {
        let (k, Some(v)) = (&kv.key, &kv.value) else {
            continue;
        };
        if k == "ARROW:schema" || k == "pandas" || k.starts_with("polars") {
            continue;
        }
        meta.set(k, v)
            .map_err(|m| record_err(path, format!("key-value {m}")))?;
    }
    let df = reader
        .finish()
        .map_err(|e| read_err(path, format!("Parquet: {e}")))?;
    let mut out = Vec::new();
    for c in df.columns() {
        let s = c.as_materialized_series();
        let values = if s.dtype().is_primitive_numeric() {
            s.cast(&DataType::Float64)
                .and_then(|s| {
                    s.f64()
                        .map(|ca| ca.iter().map(|v| v.unwrap_or(f64::NAN)).collect())
                })
                .map_err(|e| e.to_string())
        } else {
            Err(format!("type {}", s.dtype()))
        };
        out.push(RawColumn {
            name: s.name().to_string(),
            values,
            unit: None,
        });
    }
    Ok((out, meta))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_from_names() {
        assert_eq!(unit_of_name("displacement_m"), Some(("m", 1.0)));
        assert_eq!(unit_of_name("heave_nm"), Some(("m", 1e-9)));
        assert_eq!(unit_of_name("velocity_m_s"), Some(("m/s", 1.0)));
        assert_eq!(unit_of_name("velocity_mm_s"), Some(("m/s", 1e-3)));
        assert_eq!(unit_of_name("displacement (µm)"), Some(("m", 1e-6)));
        assert_eq!(unit_of_name("force [mN]"), Some(("N", 1e-3)));
        assert_eq!(unit_of_name("heave_rate"), None);
        assert_eq!(unit_of_name("x"), None);
        assert_eq!(time_role("time_s"), Some(Some(1.0)));
        assert_eq!(time_role("time_ms"), Some(Some(1e-3)));
        assert_eq!(time_role("t"), Some(Some(1.0)));
        assert_eq!(time_role("sample"), Some(None));
        assert_eq!(time_role("displacement_m"), None);
    }

    #[test]
    fn a_time_axis_gives_the_rate_or_names_the_worst_step() {
        let p = Path::new("x.csv");
        let t: Vec<f64> = (0..100).map(|i| 1e-3 + i as f64 * 2e-6).collect();
        let (fs, t0) = rate_from_time(p, "time_s", &t).unwrap();
        assert!((fs - 5e5).abs() < 1e-6 * 5e5 && (t0 - 1e-3).abs() < 1e-15);
        let mut bad = t.clone();
        bad[40] += 1e-7; // 5 % of a step
        let e = rate_from_time(p, "time_s", &bad).unwrap_err().to_string();
        assert!(
            e.contains("x.csv") && e.contains("sample 39") && e.contains("not uniformly"),
            "{e}"
        );
    }
}
