//! Arrow IPC: the file format (Feather v2, magic `ARROW1`) decoded zero-copy from a memory
//! map with arrow-rs' `FileDecoder`, and the stream format (no footer) through its
//! `StreamReader`. Columns follow the Parquet name rules; schema key-value metadata carries
//! `sample_rate`, `sensitivity`, `t0`, …, and a field's `units`/`unit` metadata its unit.
//! LZ4- and ZSTD-compressed buffers (pyarrow's Feather default is LZ4) are decompressed into
//! memory; uncompressed aligned buffers stay in the map. Kept in one module so that summary
//! tables can reuse [`decode`].

use super::columns::{self, Column, Num, Seg, Table};
use super::names::{meta_key, Meta};
use super::{no_panic, read_err, record_err, ReadOptions};
use crate::dmw::{DmwError, LdvRecord};
use arrow_array::RecordBatch;
use arrow_buffer::Buffer;
use arrow_ipc::reader::{read_footer_length, FileDecoder, StreamReader};
use arrow_schema::{DataType, SchemaRef};
use std::path::Path;
use std::ptr::NonNull;
use std::sync::Arc;

/// `ARROW1` plus two bytes of padding opens an Arrow IPC file.
pub(super) const FILE_MAGIC: &[u8] = b"ARROW1";
/// Every message of the stream format starts with this continuation marker.
pub(super) const STREAM_MAGIC: &[u8] = &[0xff, 0xff, 0xff, 0xff];

/// The schema and record batches of an Arrow IPC file or stream.
pub struct Decoded {
    pub schema: SchemaRef,
    pub batches: Vec<RecordBatch>,
    /// "arrow-file" or "arrow-stream".
    pub kind: &'static str,
}

/// Decodes an Arrow IPC file (memory-mapped, zero-copy where the buffers are aligned and
/// uncompressed) or stream. Errors are one line naming the file.
pub fn decode(path: &Path) -> Result<Decoded, DmwError> {
    no_panic(path, "the Arrow IPC reader", || {
        use std::io::{Read, Seek, SeekFrom};
        let mut file = std::fs::File::open(path).map_err(|e| read_err(path, e))?;
        let mut head = [0u8; 8];
        let n = file.read(&mut head).map_err(|e| read_err(path, e))?;
        if head[..n].starts_with(FILE_MAGIC) {
            decode_file(path, &file)
        } else {
            file.seek(SeekFrom::Start(0))
                .map_err(|e| read_err(path, e))?;
            decode_stream(path, file)
        }
    })
}

fn decode_file(path: &Path, file: &std::fs::File) -> Result<Decoded, DmwError> {
    let bad = |what: String| read_err(path, format!("Arrow IPC file: {what}"));
    // SAFETY: the map is read-only; hdi does not write the file while reading it (another
    // process truncating it could fault, as with any mmap reader).
    let mmap = unsafe { memmap2::Mmap::map(file) }.map_err(|e| read_err(path, e))?;
    let len = mmap.len();
    if len < 8 + 10 {
        return Err(bad(format!(
            "{len} bytes, too short for the header and footer"
        )));
    }
    let tail: [u8; 10] = mmap[len - 10..]
        .try_into()
        .map_err(|_| bad("no footer".into()))?;
    let footer_len = read_footer_length(tail)
        .map_err(|_| bad("no ARROW1 footer at the end; is the file cut?".into()))?;
    if footer_len > len - 10 - 8 {
        return Err(bad(format!(
            "footer length {footer_len} exceeds the file ({len} bytes); is the file cut?"
        )));
    }
    let ptr = NonNull::new(mmap.as_ptr() as *mut u8).ok_or_else(|| bad("empty map".into()))?;
    // SAFETY: `ptr` is valid for `len` bytes for as long as the Mmap lives, and the Buffer
    // owns it through the Arc.
    let buffer = unsafe { Buffer::from_custom_allocation(ptr, len, Arc::new(mmap)) };
    let footer_bytes = &buffer.as_slice()[len - 10 - footer_len..len - 10];
    let footer = arrow_ipc::root_as_footer(footer_bytes)
        .map_err(|e| bad(format!("corrupt footer ({e})")))?;
    let fb_schema = footer
        .schema()
        .ok_or_else(|| bad("the footer has no schema".into()))?;
    let schema =
        Arc::new(arrow_ipc::convert::try_fb_to_schema(fb_schema).map_err(|e| bad(e.to_string()))?);
    let mut decoder = FileDecoder::new(schema.clone(), footer.version());
    let block_bytes = |b: &arrow_ipc::Block| -> Result<Buffer, DmwError> {
        let start = usize::try_from(b.offset()).ok();
        let size = usize::try_from(b.metaDataLength())
            .ok()
            .zip(usize::try_from(b.bodyLength()).ok())
            .and_then(|(m, body)| m.checked_add(body));
        match (start, size) {
            (Some(s), Some(k)) if s.checked_add(k).is_some_and(|e| e <= len) => {
                Ok(buffer.slice_with_length(s, k))
            }
            _ => Err(bad(format!(
                "a block at offset {} of {} + {} bytes lies outside the file ({len} bytes); \
                 is the file cut?",
                b.offset(),
                b.metaDataLength(),
                b.bodyLength()
            ))),
        }
    };
    for block in footer.dictionaries().iter().flat_map(|v| v.iter()) {
        let data = block_bytes(block)?;
        decoder
            .read_dictionary(block, &data)
            .map_err(|e| bad(e.to_string()))?;
    }
    let mut batches = Vec::new();
    for block in footer.recordBatches().iter().flat_map(|v| v.iter()) {
        let data = block_bytes(block)?;
        check_block_lengths(block, &data).map_err(bad)?;
        if let Some(batch) = decoder
            .read_record_batch(block, &data)
            .map_err(|e| bad(e.to_string()))?
        {
            batches.push(batch);
        }
    }
    Ok(Decoded {
        schema,
        batches,
        kind: "arrow-file",
    })
}

/// Rejects a record batch whose compressed buffers declare a decompressed length out of
/// proportion to the batch: arrow-ipc allocates the declared length before decompressing, and a
/// failed allocation aborts the process (no panic to catch). Found by the `ldv` fuzz target
/// (docs/reliability.md, "Coverage-guided fuzzing"): an LZ4 buffer declaring 2.4·10¹⁸ bytes.
/// Bound: 1 KiB per row, and 2¹⁶ × the compressed size (LZ4 expands at most ~255×, zstd at most
/// ~32 768× with RLE blocks), whichever is smaller, plus 1 MiB.
fn check_block_lengths(block: &arrow_ipc::Block, data: &Buffer) -> Result<(), String> {
    let bytes = data.as_slice();
    match usize::try_from(block.metaDataLength()) {
        Ok(meta_len) if meta_len <= bytes.len() => {
            check_compressed_lengths(&bytes[..meta_len], &bytes[meta_len..])
        }
        _ => Ok(()),
    }
}

/// [`check_block_lengths`] for a message: `meta` is its framed metadata (marker, length,
/// flatbuffer), `body` its body.
fn check_compressed_lengths(meta: &[u8], body: &[u8]) -> Result<(), String> {
    // The message: an optional 0xFFFFFFFF continuation marker, its length, the flatbuffer.
    let fb = if meta.starts_with(&[0xff; 4]) {
        meta.get(8..)
    } else {
        meta.get(4..)
    };
    // Anything unreadable here is left to arrow-ipc's decoder, which reports it.
    let Some(message) = fb.and_then(|fb| arrow_ipc::root_as_message(fb).ok()) else {
        return Ok(());
    };
    let Some(batch) = message.header_as_record_batch() else {
        return Ok(());
    };
    if batch.compression().is_none() {
        return Ok(());
    }
    let rows = u64::try_from(batch.length()).unwrap_or(u64::MAX);
    for b in batch.buffers().iter().flat_map(|v| v.iter()) {
        let (Ok(off), Ok(len)) = (usize::try_from(b.offset()), usize::try_from(b.length())) else {
            continue;
        };
        let Some(buf) = off.checked_add(len).and_then(|end| body.get(off..end)) else {
            continue;
        };
        let Some(prefix) = buf.get(..8) else {
            continue;
        };
        let mut le = [0u8; 8];
        le.copy_from_slice(prefix);
        // −1: the buffer is stored uncompressed.
        let Ok(declared) = u64::try_from(i64::from_le_bytes(le)) else {
            continue;
        };
        let bound = rows
            .saturating_mul(1024)
            .min((len as u64).saturating_mul(1 << 16))
            .saturating_add(1 << 20);
        if declared > bound {
            return Err(format!(
                "a compressed buffer of {len} bytes declares {declared} bytes decompressed \
                 ({rows} rows); is the file corrupt?"
            ));
        }
    }
    Ok(())
}

/// The same check over a stream's messages, walked by their framing before arrow-ipc's
/// `StreamReader` decodes them (it has no hook between reading a message and allocating its
/// buffers). Anything the walk cannot frame is left to the reader, which reports it.
fn check_stream_lengths(bytes: &[u8]) -> Result<(), String> {
    let word = |at: usize| {
        let w = bytes.get(at..at.checked_add(4)?)?;
        Some(i32::from_le_bytes([w[0], w[1], w[2], w[3]]))
    };
    let mut at = 0usize;
    while let Some(first) = word(at) {
        // A continuation marker (−1) and the length, or (before format 0.15) the length alone.
        let (prefix, len) = match first {
            -1 => match word(at + 4) {
                Some(len) => (8, len),
                None => return Ok(()),
            },
            len => (4, len),
        };
        let Ok(len) = usize::try_from(len) else {
            return Ok(());
        };
        if len == 0 {
            return Ok(()); // end of stream
        }
        let Some(meta_end) = at.checked_add(prefix + len) else {
            return Ok(());
        };
        let Some(meta) = bytes.get(at..meta_end) else {
            return Ok(());
        };
        let Ok(message) = arrow_ipc::root_as_message(&meta[prefix..]) else {
            return Ok(());
        };
        let body_end = usize::try_from(message.bodyLength())
            .ok()
            .and_then(|n| meta_end.checked_add(n));
        let Some(body) = body_end.and_then(|end| bytes.get(meta_end..end)) else {
            return Ok(());
        };
        check_compressed_lengths(meta, body)?;
        at = meta_end + body.len();
    }
    Ok(())
}

fn decode_stream(path: &Path, file: std::fs::File) -> Result<Decoded, DmwError> {
    let bad = |e: arrow_schema::ArrowError| read_err(path, format!("Arrow IPC stream: {e}"));
    // SAFETY: read-only map, as in `decode_file`.
    let mmap = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| read_err(path, e))?;
    check_stream_lengths(&mmap)
        .map_err(|what| read_err(path, format!("Arrow IPC stream: {what}")))?;
    let reader = StreamReader::try_new(std::io::Cursor::new(&mmap[..]), None).map_err(bad)?;
    let schema = reader.schema();
    let batches = reader.collect::<Result<Vec<_>, _>>().map_err(bad)?;
    Ok(Decoded {
        schema,
        batches,
        kind: "arrow-stream",
    })
}

fn num_of(t: &DataType) -> Option<Num> {
    Some(match t {
        DataType::Float64 => Num::F64,
        DataType::Float32 => Num::F32,
        DataType::Int8 => Num::I8,
        DataType::UInt8 => Num::U8,
        DataType::Int16 => Num::I16,
        DataType::UInt16 => Num::U16,
        DataType::Int32 => Num::I32,
        DataType::UInt32 => Num::U32,
        DataType::Int64 => Num::I64,
        DataType::UInt64 => Num::U64,
        _ => return None,
    })
}

pub(super) fn read(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let dec = decode(path)?;
    let table = table(path, &dec, opts)?;
    columns::read(path, table, opts)
}

/// The numeric columns of a decoded file (borrowing its buffers), their units and the schema
/// metadata; shared by the LDV reader and the generic series reader (`super::series`).
pub(super) fn table<'a>(
    path: &Path,
    dec: &'a Decoded,
    opts: &ReadOptions,
) -> Result<Table<'a>, DmwError> {
    let mut meta = Meta::default();
    for (k, v) in dec.schema.metadata() {
        // pandas and Arrow store JSON blobs under their own keys.
        if k.starts_with("ARROW:") || k == "pandas" {
            continue;
        }
        meta.set(k, v)
            .map_err(|m| record_err(path, format!("schema {m}")))?;
    }
    let fields = dec.schema.fields();
    let mut columns = Vec::new();
    let mut skipped = Vec::new();
    for (k, field) in fields.iter().enumerate() {
        let Some(num) = num_of(field.data_type()) else {
            skipped.push(format!("{} ({})", field.name(), field.data_type()));
            for opt in [&opts.velocity_column, &opts.index_column, &opts.time_column] {
                if opt
                    .as_deref()
                    .is_some_and(|o| o.trim().eq_ignore_ascii_case(field.name()))
                {
                    return Err(record_err(
                        path,
                        format!(
                            "column '{}' has type {}, not a number",
                            field.name(),
                            field.data_type()
                        ),
                    ));
                }
            }
            continue;
        };
        let mut col = Column::new(field.name().clone(), Vec::new());
        for batch in &dec.batches {
            if let Some(arr) = batch.columns().get(k) {
                col.segs.push(segment(arr.as_ref(), num));
            }
        }
        for (key, value) in field.metadata() {
            match meta_key(key).as_str() {
                "units" | "unit" => col.unit = Some(value.clone()),
                _ => meta
                    .set(key, value)
                    .map_err(|m| record_err(path, format!("field '{}' {m}", field.name())))?,
            }
        }
        columns.push(col);
    }
    let mut provenance = vec![("arrow_ipc".to_string(), dec.kind.to_string())];
    if !skipped.is_empty() {
        provenance.push(("skipped_columns".to_string(), skipped.join(", ")));
    }
    Ok(Table {
        format: "arrow",
        columns,
        meta,
        meta_hint: "a 'sample_rate' schema metadata entry",
        what: "column",
        positional: false,
        provenance,
    })
}

/// The values (and validity) of one primitive array, borrowed from its buffers.
fn segment(arr: &dyn arrow_array::Array, num: Num) -> Seg<'_> {
    let size = num.size();
    let values: &[u8] = primitive_values(arr);
    let valid = arr
        .nulls()
        .filter(|n| n.null_count() > 0)
        .map(|n| (n.buffer().as_slice(), n.offset()));
    Seg::Bytes {
        bytes: values,
        offset: 0,
        stride: size,
        len: arr.len(),
        num,
        big_endian: false,
        valid,
    }
}

/// The value bytes of a primitive array, `len()` elements.
fn primitive_values(arr: &dyn arrow_array::Array) -> &[u8] {
    use arrow_array::cast::AsArray;
    use arrow_array::types::*;
    macro_rules! buf {
        ($t:ty) => {{
            let a = arr.as_primitive::<$t>();
            // `values()` is already sliced to the array's own elements.
            a.values().inner().as_slice()
        }};
    }
    match arr.data_type() {
        DataType::Float64 => buf!(Float64Type),
        DataType::Float32 => buf!(Float32Type),
        DataType::Int8 => buf!(Int8Type),
        DataType::UInt8 => buf!(UInt8Type),
        DataType::Int16 => buf!(Int16Type),
        DataType::UInt16 => buf!(UInt16Type),
        DataType::Int32 => buf!(Int32Type),
        DataType::UInt32 => buf!(UInt32Type),
        DataType::Int64 => buf!(Int64Type),
        DataType::UInt64 => buf!(UInt64Type),
        _ => &[],
    }
}
