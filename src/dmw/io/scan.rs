//! Feeds the columns an eager polars reader returned to a [`Stream`] in batches of
//! [`BATCH`] rows: the stream's checks (gaps, time steps) then see the same batches whatever
//! the reader, and stop at the first fault.
//!
//! polars' eager readers (no `lazy`, so no streaming engine and none of the cloud/HTTP stack it
//! pulls in, docs/performance.md "Build times") parse only the projected columns, in parallel;
//! the frame must hold Float64 columns named `v` (velocity) and optionally `i` (index) and `t`
//! (time).

use super::stream::{Col, Stream};
use super::{no_panic, read_err};
use crate::dmw::DmwError;
use polars_core::prelude::*;
use std::path::Path;

/// Column names the readers rename their projections to.
pub(super) const T: &str = "t";
pub(super) const V: &str = "v";
pub(super) const I: &str = "i";

/// Rows per batch: large enough that the per-batch overhead vanishes, small enough that a
/// batch's copy stays in cache.
const BATCH: usize = 1 << 16;

/// Calls `next` for frames until it returns `None` or the stream has seen enough (a gap, a
/// bad time step), and pushes each frame in batches of [`BATCH`] rows.
pub(super) fn feed(
    path: &Path,
    mut next: impl FnMut() -> Result<Option<DataFrame>, DmwError>,
    mut stream: Stream,
    what: &str,
) -> Result<Stream, DmwError> {
    no_panic(path, what, || {
        while let Some(df) = next()? {
            let n = df.height();
            let mut offset = 0;
            while offset < n {
                let len = BATCH.min(n - offset);
                let batch = df.slice(offset as i64, len);
                let stop = push_batch(&mut stream, &batch)
                    .map_err(|e| read_err(path, format!("{what}: {e}")))?;
                if stop {
                    return Ok(());
                }
                offset += len;
            }
        }
        Ok(())
    })?;
    Ok(stream)
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
