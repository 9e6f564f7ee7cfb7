//! polars → arrow-rs: the one place where hdi's two Arrow implementations meet.
//!
//! polars (0.55, built on its own fork `polars-arrow`) assembles the summary tables; arrow-rs
//! writes them as Arrow IPC and reads Arrow IPC inputs (`dmw::io::arrow`). The columns cross
//! over through the Arrow C Data Interface (<https://arrow.apache.org/docs/format/CDataInterface.html>),
//! the ABI every Arrow implementation exports and imports: polars-arrow's `export_field_to_c`
//! / `export_array_to_c` fill the C structs, arrow-rs' `ffi::from_ffi` adopts them. No value is
//! copied except strings (below); arrow-rs' buffers keep polars' allocations alive through the
//! C release callbacks and free them when the last arrow-rs array drops.
//!
//! Audit points (re-check on every polars or arrow-rs upgrade):
//! 1. ABI. polars-arrow's `ffi::ArrowSchema`/`ffi::ArrowArray` and arrow-rs'
//!    `FFI_ArrowSchema`/`FFI_ArrowArray` are both `#[repr(C)]` transcriptions of the same C
//!    structs; the crossing casts a pointer from one to the other. The compile-time asserts
//!    below check size and alignment; field order is fixed by the C specification, which both
//!    crates copy (polars-arrow's by bindgen from `abi.h`).
//! 2. Ownership. `FFI_*::from_raw` *moves* the struct out and leaves an empty one (null
//!    `release`) behind, so polars' `Drop` on the husk is a no-op and the release callback runs
//!    exactly once, from arrow-rs.
//! 3. Strings. polars keeps strings as `Utf8View` (its newest compat level). They are exported
//!    at `CompatLevel::oldest()`, which converts them (one copy) to `LargeUtf8`: every Arrow
//!    reader (pyarrow, R arrow, Arrow.jl, DuckDB) supports it, whereas view types (which
//!    polars records in its Parquet schema) are recent. Numeric and boolean columns are
//!    unaffected by the compat level.
//! 4. Chunks. Each column is rechunked to one contiguous array first (a no-op for the
//!    freshly built tables `core::store::write_table` passes), so a table is one record batch.
//! 5. Types. hdi's tables hold Int64, Float64, Boolean and String columns with nulls;
//!    `to_record_batch` accepts only those, so a new polars dtype is a clear error rather than
//!    an unaudited conversion.
//! 6. Validation. arrow-rs validates the imported `ArrayData` (lengths, offsets, UTF-8) and
//!    realigns under-aligned buffers; a bad export is an error, not undefined behaviour later.

use arrow_array::ffi::{from_ffi, FFI_ArrowArray, FFI_ArrowSchema};
use arrow_array::{make_array, RecordBatch, RecordBatchOptions};
use arrow_schema::{Field, Schema};
use polars_core::prelude::{CompatLevel, DataFrame, DataType as PlType};
use std::sync::Arc;

// Audit point 1: the C structs have the same size and alignment on both sides.
const _: () = {
    use polars_arrow::ffi::{ArrowArray, ArrowSchema};
    use std::mem::{align_of, size_of};
    assert!(size_of::<ArrowSchema>() == size_of::<FFI_ArrowSchema>());
    assert!(align_of::<ArrowSchema>() == align_of::<FFI_ArrowSchema>());
    assert!(size_of::<ArrowArray>() == size_of::<FFI_ArrowArray>());
    assert!(align_of::<ArrowArray>() == align_of::<FFI_ArrowArray>());
};

/// Why a polars frame could not cross into arrow-rs.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    #[error("column `{column}`: polars type {dtype} is not one hdi writes (Int64, Float64, Boolean, String)")]
    Unsupported { column: String, dtype: String },
    #[error("column `{column}`: arrow-rs refused the C Data Interface import: {message}")]
    Import { column: String, message: String },
    #[error("record batch: {0}")]
    Batch(String),
}

/// The frame as one arrow-rs record batch: same column names and order, same values and
/// nulls; Int64 → Int64, Float64 → Float64, Boolean → Boolean, String → LargeUtf8. Fields
/// carry no metadata (the caller adds it).
pub fn to_record_batch(df: &DataFrame) -> Result<RecordBatch, BridgeError> {
    let mut fields = Vec::with_capacity(df.width());
    let mut arrays = Vec::with_capacity(df.width());
    for col in df.columns() {
        let name = col.name().to_string();
        match col.dtype() {
            PlType::Int64 | PlType::Float64 | PlType::Boolean | PlType::String | PlType::Null => {}
            other => {
                return Err(BridgeError::Unsupported {
                    column: name,
                    dtype: other.to_string(),
                })
            }
        }
        let pl_field = col.field().to_arrow(CompatLevel::oldest());
        let pl_array = col.clone().rechunk_to_arrow(CompatLevel::oldest());
        let mut c_schema = polars_arrow::ffi::export_field_to_c(&pl_field);
        let mut c_array = polars_arrow::ffi::export_array_to_c(pl_array);
        // SAFETY (audit points 1 and 2): both values are valid, exported C Data Interface
        // structs of identical layout; `from_raw` moves each out and leaves an empty struct
        // whose polars `Drop` does nothing.
        let (ffi_schema, ffi_array) = unsafe {
            (
                FFI_ArrowSchema::from_raw(
                    (&mut c_schema as *mut polars_arrow::ffi::ArrowSchema).cast(),
                ),
                FFI_ArrowArray::from_raw(
                    (&mut c_array as *mut polars_arrow::ffi::ArrowArray).cast(),
                ),
            )
        };
        let import_err = |e: arrow_schema::ArrowError| BridgeError::Import {
            column: name.clone(),
            message: e.to_string(),
        };
        let field = Field::try_from(&ffi_schema).map_err(import_err)?;
        // SAFETY: the struct was produced by polars-arrow's exporter for this very schema.
        let data = unsafe { from_ffi(ffi_array, &ffi_schema) }.map_err(import_err)?;
        fields.push(field);
        arrays.push(make_array(data));
    }
    RecordBatch::try_new_with_options(
        Arc::new(Schema::new(fields)),
        arrays,
        &RecordBatchOptions::new().with_row_count(Some(df.height())),
    )
    .map_err(|e| BridgeError::Batch(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use arrow_array::{Array, BooleanArray, Float64Array, Int64Array, LargeStringArray};
    use arrow_schema::DataType;
    use polars_core::prelude::{Column, NamedFrom, Series};

    fn frame() -> DataFrame {
        let cols = vec![
            Column::new("n".into(), [Some(1i64), None, Some(-7), Some(i64::MAX)]),
            Column::new(
                "x_nm".into(),
                [Some(0.1f64), Some(f64::NAN), None, Some(-1e-300)],
            ),
            Column::new("ok".into(), [Some(true), Some(false), None, Some(true)]),
            Column::new(
                "name".into(),
                [
                    Some("a"),
                    None,
                    Some(""),
                    Some("µm — a longer string than 12 bytes"),
                ],
            ),
        ];
        DataFrame::new(4, cols).expect("frame")
    }

    #[test]
    fn columns_values_and_nulls_cross_unchanged() {
        let df = frame();
        let b = to_record_batch(&df).expect("bridge");
        assert_eq!(b.num_rows(), 4);
        let names: Vec<&str> = b
            .schema_ref()
            .fields()
            .iter()
            .map(|f| f.name().as_str())
            .collect();
        assert_eq!(names, ["n", "x_nm", "ok", "name"]);
        let types: Vec<&DataType> = b
            .schema_ref()
            .fields()
            .iter()
            .map(|f| f.data_type())
            .collect();
        assert_eq!(
            types,
            [
                &DataType::Int64,
                &DataType::Float64,
                &DataType::Boolean,
                &DataType::LargeUtf8
            ]
        );

        // Each arrow-rs value against the polars value of the same cell.
        let n = b
            .column(0)
            .as_any()
            .downcast_ref::<Int64Array>()
            .expect("i64");
        let pn = df.column("n").expect("n").i64().expect("i64");
        for i in 0..4 {
            assert_eq!(n.is_null(i), pn.get(i).is_none());
            if let Some(v) = pn.get(i) {
                assert_eq!(n.value(i), v);
            }
        }
        let x = b
            .column(1)
            .as_any()
            .downcast_ref::<Float64Array>()
            .expect("f64");
        let px = df.column("x_nm").expect("x").f64().expect("f64");
        for i in 0..4 {
            assert_eq!(x.is_null(i), px.get(i).is_none());
            if let Some(v) = px.get(i) {
                assert_eq!(x.value(i).to_bits(), v.to_bits());
            }
        }
        let ok = b
            .column(2)
            .as_any()
            .downcast_ref::<BooleanArray>()
            .expect("bool");
        let pok = df.column("ok").expect("ok").bool().expect("bool");
        for i in 0..4 {
            assert_eq!(ok.is_null(i), pok.get(i).is_none());
            if let Some(v) = pok.get(i) {
                assert_eq!(ok.value(i), v);
            }
        }
        let s = b
            .column(3)
            .as_any()
            .downcast_ref::<LargeStringArray>()
            .expect("utf8");
        let ps = df.column("name").expect("name").str().expect("str");
        for i in 0..4 {
            assert_eq!(s.is_null(i), ps.get(i).is_none());
            if let Some(v) = ps.get(i) {
                assert_eq!(s.value(i), v);
            }
        }
        assert_eq!(
            n.null_count() + x.null_count() + ok.null_count() + s.null_count(),
            4
        );
    }

    #[test]
    fn sliced_multi_chunk_and_empty_frames_cross() {
        // Two chunks, then a slice with a non-byte-aligned offset: the bridge rechunks and
        // the C export carries the offset.
        let mut a = Series::new("b".into(), [true, false, true, true, false]);
        a.append(&Series::new("b".into(), [false, true, true]))
            .expect("append");
        let df = DataFrame::new(8, vec![a.into()]).expect("df").slice(3, 4);
        let b = to_record_batch(&df).expect("bridge");
        let got = b
            .column(0)
            .as_any()
            .downcast_ref::<BooleanArray>()
            .expect("bool");
        let pb = df.column("b").expect("b").bool().expect("b");
        let want: Vec<Option<bool>> = (0..pb.len()).map(|i| pb.get(i)).collect();
        assert_eq!(got.iter().collect::<Vec<_>>(), want);
        assert_eq!(want, [Some(true), Some(false), Some(false), Some(true)]);

        let empty = to_record_batch(&DataFrame::empty()).expect("empty");
        assert_eq!((empty.num_rows(), empty.num_columns()), (0, 0));
    }

    #[test]
    fn an_unaudited_type_is_an_error() {
        let df = DataFrame::new(2, vec![Column::new("f".into(), [1.0f32, 2.0])]).expect("df");
        let e = to_record_batch(&df).expect_err("f32 is not an hdi table type");
        assert!(e.to_string().contains("`f`"), "{e}");
    }
}
