//! Runs a polars lazy scan on the streaming engine and feeds its batches to a [`Stream`]:
//! the scan parses only the projected columns and never holds the whole file, and the time
//! column is reduced batch by batch instead of being collected.
//!
//! The query must produce Float64 columns named `v` (velocity) and optionally `i` (index) and
//! `t` (time).

use super::stream::{Col, Stream};
use super::{no_panic, read_err};
use crate::dmw::DmwError;
use polars::prelude::*;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Column names the scans alias their projections to.
pub(super) const T: &str = "t";
pub(super) const V: &str = "v";
pub(super) const I: &str = "i";

/// polars needs a UTF-8 path; an absolute one so that nothing is resolved differently.
pub(super) fn pl_path(path: &Path) -> Result<PlRefPath, DmwError> {
    let abs = std::path::absolute(path).map_err(|e| read_err(path, e))?;
    let text = abs
        .to_str()
        .ok_or_else(|| read_err(path, "the path is not valid UTF-8, which polars needs"))?;
    Ok(PlRefPath::new(text))
}

pub(super) fn run(
    path: &Path,
    lf: LazyFrame,
    stream: Stream,
    what: &str,
) -> Result<Stream, DmwError> {
    let state = Arc::new(Mutex::new(stream));
    let shared = state.clone();
    let callback: Arc<dyn Fn(DataFrame) -> PolarsResult<bool> + Send + Sync> =
        Arc::new(move |df: DataFrame| {
            let mut s = shared.lock().unwrap_or_else(|e| e.into_inner());
            push_batch(&mut s, &df)
        });
    no_panic(path, what, || {
        lf.sink_batches(PlanCallback::Rust(SpecialEq::new(callback)), true, None)
            .and_then(|lf| lf.collect_with_engine(Engine::Streaming))
            .map(|_| ())
            .map_err(|e| read_err(path, format!("{what}: {e}")))
    })?;
    let mut guard = state.lock().unwrap_or_else(|e| e.into_inner());
    Ok(std::mem::replace(
        &mut *guard,
        Stream::new(1.0, false, false, 0),
    ))
}

/// A batch column as one contiguous f64 array plus its null mask.
struct Owned {
    ca: Float64Chunked,
    nulls: Option<Vec<bool>>,
}

impl Owned {
    fn get(df: &DataFrame, name: &str) -> PolarsResult<Option<Owned>> {
        if df.schema().get(name).is_none() {
            return Ok(None);
        }
        let ca = df.column(name)?.f64()?.rechunk().into_owned();
        let nulls = if ca.null_count() > 0 {
            Some(ca.iter().map(|x| x.is_none()).collect())
        } else {
            None
        };
        Ok(Some(Owned { ca, nulls }))
    }

    fn col(&self) -> Col<'_> {
        let values = self
            .ca
            .downcast_iter()
            .next()
            .map_or(&[][..], |a| a.values().as_slice());
        Col {
            values,
            nulls: self.nulls.as_deref(),
        }
    }
}

fn push_batch(s: &mut Stream, df: &DataFrame) -> PolarsResult<bool> {
    if df.height() == 0 {
        return Ok(s.done());
    }
    let v = Owned::get(df, V)?.ok_or_else(|| polars_err!(ColumnNotFound: "v"))?;
    let i = Owned::get(df, I)?;
    let t = Owned::get(df, T)?;
    Ok(s.push(
        t.as_ref().map(Owned::col),
        v.col(),
        i.as_ref().map(Owned::col),
    ))
}
