//! Parquet through polars: the footer gives the schema and the key-value metadata, then the
//! eager reader decodes only the chosen columns (cast to Float64).

use super::names::{self, Meta};
use super::scan::{self, I, T, V};
use super::stream::Stream;
use super::{
    check_flat, finish, flat_layout, meta_pairs, no_panic, read_err, record_err, sample_time,
    velocity_unit, write_atomic, Raw, ReadOptions,
};
use crate::dmw::{DmwError, LdvRecord, VelocityUnit};
use polars_core::prelude::*;
use polars_io::prelude::*;
use std::path::Path;

/// Rows read per call of the eager reader (whole row groups are added until this is reached).
const PART: usize = 1 << 22;

pub(super) fn read(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let file = std::fs::File::open(path).map_err(|e| read_err(path, e))?;
    let (md, schema, kv) = no_panic(path, "the Parquet reader", || {
        let mut reader = ParquetReader::new(file);
        let md = reader
            .get_metadata()
            .map_err(|e| read_err(path, format!("Parquet footer: {e}")))?;
        let kv: Vec<(String, String)> = md
            .key_value_metadata()
            .iter()
            .flatten()
            .filter_map(|kv| kv.value.clone().map(|v| (kv.key.clone(), v)))
            .collect();
        let md = md.clone();
        let schema: Vec<(String, DataType)> = reader
            .schema()
            .map_err(|e| read_err(path, format!("Parquet schema: {e}")))?
            .iter_values()
            .map(|f| (f.name.to_string(), DataType::from_arrow_field(f)))
            .collect();
        Ok((md, schema, kv))
    })?;
    let mut meta = Meta::default();
    for (k, v) in &kv {
        // Writers (pandas, pyarrow) add large JSON blobs under their own keys; skip them.
        if k == "ARROW:schema" || k == "pandas" || k.starts_with("polars") {
            continue;
        }
        meta.set(k, v)
            .map_err(|m| record_err(path, format!("key-value {m}")))?;
    }
    let names: Vec<String> = schema.iter().map(|(n, _)| n.clone()).collect();
    let chosen = names::choose(&names, opts, "column").map_err(|m| record_err(path, m))?;
    let unit = velocity_unit(
        path,
        opts,
        chosen.velocity_unit,
        chosen.velocity_unknown_unit.as_deref(),
        meta.velocity_unit,
        "column name",
    )?;
    let layout = flat_layout(path, &meta)?;
    let mut select: Vec<(usize, &str)> = Vec::new();
    for (k, alias) in [
        (Some(chosen.velocity), V),
        (chosen.index, I),
        (chosen.time.map(|t| t.0), T),
    ] {
        let Some(k) = k else { continue };
        let dtype = schema[k].1.clone();
        if !(dtype.is_primitive_numeric() || dtype == DataType::Boolean) {
            return Err(record_err(
                path,
                format!("column '{}' has type {dtype}, not a number", names[k]),
            ));
        }
        select.push((k, alias));
    }
    let mut wanted: Vec<usize> = select.iter().map(|(k, _)| *k).collect();
    wanted.sort_unstable();
    wanted.dedup();
    // The footer's row count sizes the channel buffers once (on huge pages, numerics::buffer).
    let stream = Stream::new(
        unit.scale,
        chosen.index.is_some(),
        chosen.time.is_some(),
        md.num_rows,
    );
    // Whole row groups, at least PART rows at a time: only one part's columns are in memory
    // beside the output channels (the time column is reduced, never kept).
    let mut parts = Vec::new();
    let (mut start, mut len) = (0, 0);
    for rg in &md.row_groups {
        len += rg.num_rows();
        if len >= PART {
            parts.push((start, len));
            (start, len) = (start + len, 0);
        }
    }
    if len > 0 || parts.is_empty() {
        parts.push((start, len));
    }
    let mut parts = parts.into_iter();
    let next = || -> Result<Option<DataFrame>, DmwError> {
        let Some((offset, len)) = parts.next() else {
            return Ok(None);
        };
        let file = std::fs::File::open(path).map_err(|e| read_err(path, e))?;
        let mut reader = ParquetReader::new(file);
        reader.set_metadata(md.clone());
        let read = reader
            .with_projection(Some(wanted.clone()))
            .with_slice(Some((offset, len)))
            .finish()
            .map_err(|e| read_err(path, format!("Parquet reader: {e}")))?;
        let columns = select
            .iter()
            .map(|(k, alias)| {
                read.column(names[*k].as_str())
                    .and_then(|c| c.cast(&DataType::Float64))
                    .map(|c| c.with_name((*alias).into()))
            })
            .collect::<PolarsResult<Vec<Column>>>()
            .map_err(|e| read_err(path, format!("Parquet reader: {e}")))?;
        DataFrame::new(read.height(), columns)
            .map(Some)
            .map_err(|e| read_err(path, format!("Parquet reader: {e}")))
    };
    let stream = scan::feed(path, next, stream, "Parquet reader")?;
    let raw = Raw {
        format: "parquet",
        stream,
        velocity_name: names[chosen.velocity].clone(),
        index_name: chosen.index.map(|k| names[k].clone()),
        time: chosen.time.map(|(k, kind)| (names[k].clone(), kind)),
        unit,
        layout,
        meta,
        meta_hint: "a 'sample_rate' key-value metadata entry",
        provenance: vec![],
    };
    finish(path, raw, opts, &|row| format!("row {row}"))
}

pub(super) fn write(rec: &LdvRecord, path: &Path) -> Result<(), DmwError> {
    check_flat(rec)?;
    let n = rec.velocity.len();
    let time: Vec<f64> = (0..n).map(|i| sample_time(rec, i)).collect();
    let vname = match rec.velocity_unit {
        VelocityUnit::Volt => "velocity_V",
        VelocityUnit::MetrePerSecond => "velocity_m_s",
    };
    let mut columns = vec![
        Column::new("time_s".into(), time),
        Column::new(vname.into(), rec.velocity.as_slice()),
    ];
    if let Some(idx) = &rec.index {
        columns.push(Column::new("index_V".into(), idx.as_slice()));
    }
    let mut df = DataFrame::new(n, columns).map_err(|e| super::write_err(path, e))?;
    let kv = KeyValueMetadata::from_static(meta_pairs(rec));
    write_atomic(path, |f| {
        ParquetWriter::new(f)
            .with_compression(ParquetCompression::Zstd(None))
            .with_key_value_metadata(Some(kv))
            .finish(&mut df)
            .map(|_| ())
            .map_err(|e| e.to_string())
    })
}
