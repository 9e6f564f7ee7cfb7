//! NumPy records: a memory-mapped `.npy` array (1-D velocity, 2-D with one channel per column,
//! or a structured array with named fields), or a `.npz` archive whose `.npy` members are the
//! channels, named by the member (`time.npy`, `velocity.npy`, `index.npy`), with 0-d members
//! (`sample_rate.npy`, `sensitivity.npy`, …) as metadata. Header parsing: `formats::npy`.

use super::columns::{self, Column, Num, Seg, Table};
use super::names::Meta;
use super::{read_err, record_err, ReadOptions};
use crate::dmw::{DmwError, LdvRecord};
use crate::formats::npy::{self, Dtype, Header, Scalar};
use crate::formats::zip::ZipArchive;
use std::path::Path;

fn num(path: &Path, s: Scalar, what: &str) -> Result<Num, DmwError> {
    Ok(match (s.kind, s.size) {
        ('f', 8) => Num::F64,
        ('f', 4) => Num::F32,
        ('i', 1) => Num::I8,
        ('u', 1) | ('b', 1) => Num::U8,
        ('i', 2) => Num::I16,
        ('u', 2) => Num::U16,
        ('i', 4) => Num::I32,
        ('u', 4) => Num::U32,
        ('i', 8) => Num::I64,
        ('u', 8) => Num::U64,
        _ => {
            return Err(record_err(
                path,
                format!("{what} has element type {}{}, not a number", s.kind, s.size),
            ))
        }
    })
}

fn map(path: &Path) -> Result<memmap2::Mmap, DmwError> {
    let file = std::fs::File::open(path).map_err(|e| read_err(path, e))?;
    // SAFETY: read-only map; hdi does not modify the file while reading it.
    unsafe { memmap2::Mmap::map(&file) }.map_err(|e| read_err(path, e))
}

fn scalar_seg(bytes: &[u8], offset: usize, stride: usize, len: usize, n: Num, be: bool) -> Seg<'_> {
    Seg::Bytes {
        bytes,
        offset,
        stride,
        len,
        num: n,
        big_endian: be,
        valid: None,
    }
}

/// The channels of one array: names by position for plain arrays (1 column: velocity; 2:
/// velocity, index; 3: time, velocity, index; more: channel0, channel1, … chosen by number),
/// field names for structured arrays. A 2-D array whose first axis is the short one
/// (`np.vstack([v, idx])`, shape (2, n)) holds one channel per row.
fn array_columns<'a>(
    path: &Path,
    h: &Header,
    bytes: &'a [u8],
) -> Result<(Vec<Column<'a>>, bool), DmwError> {
    let off = h.data_offset;
    match &h.dtype {
        Dtype::Structured { fields, itemsize } => {
            if h.shape.len() != 1 {
                return Err(record_err(
                    path,
                    format!("structured array of shape {:?}; a record is 1-D", h.shape),
                ));
            }
            let mut cols = Vec::new();
            for f in fields.iter().filter(|f| f.scalar.kind != 'V') {
                let n = num(path, f.scalar, &format!("field '{}'", f.name))?;
                let seg = scalar_seg(
                    bytes,
                    off + f.offset,
                    *itemsize,
                    h.shape[0],
                    n,
                    f.scalar.big_endian,
                );
                cols.push(Column::new(f.name.clone(), vec![seg]));
            }
            Ok((cols, false))
        }
        Dtype::Scalar(s) => {
            let n = num(path, *s, "the array")?;
            let size = s.size;
            let (rows, k, channel_rows) = match h.shape.as_slice() {
                [n] => (*n, 1, false),
                [a, b] if *a <= 3 && *b > 3 => (*b, *a, true),
                [a, b] => (*a, *b, false),
                other => {
                    return Err(record_err(
                        path,
                        format!("array of shape {other:?}; a record is 1-D or 2-D"),
                    ))
                }
            };
            let names: Vec<String> = match k {
                1 => vec!["velocity".into()],
                2 => vec!["velocity".into(), "index".into()],
                3 => vec!["time".into(), "velocity".into(), "index".into()],
                _ => (0..k).map(|j| format!("channel{j}")).collect(),
            };
            // Element (r, c) of an (R, C) array: C order at r·C + c, Fortran at c·R + r.
            // A channel per row is the transpose.
            let contiguous = h.fortran_order != channel_rows;
            let mut cols = Vec::new();
            for (j, name) in names.into_iter().enumerate() {
                let (start, stride) = if h.shape.len() == 1 {
                    (off, size)
                } else if contiguous {
                    (off + j * rows * size, size)
                } else {
                    (off + j * size, k * size)
                };
                cols.push(Column::new(
                    name,
                    vec![scalar_seg(bytes, start, stride, rows, n, s.big_endian)],
                ));
            }
            Ok((cols, k > 3))
        }
    }
}

fn npy_err(path: &Path, e: npy::NpyError) -> DmwError {
    read_err(path, e)
}

pub(super) fn read_npy(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let mmap = map(path)?;
    let table = npy_table(path, &mmap)?;
    columns::read(path, table, opts)
}

/// The memory-mapped file (for [`npy_table`]).
pub(super) fn map_file(path: &Path) -> Result<memmap2::Mmap, DmwError> {
    map(path)
}

/// The channels of a `.npy` file's bytes; shared by the LDV reader and `super::series`.
pub(super) fn npy_table<'a>(path: &Path, mmap: &'a [u8]) -> Result<Table<'a>, DmwError> {
    let h = npy::parse(mmap, mmap.len()).map_err(|e| npy_err(path, e))?;
    let (columns, positional) = array_columns(path, &h, mmap)?;
    Ok(Table {
        format: "npy",
        columns,
        meta: Meta::default(),
        meta_hint: "nothing (.npy has no metadata; use .npz with a sample_rate member)",
        what: "column",
        positional,
        provenance: vec![(
            "npy_version".into(),
            format!("{}.{}", h.version.0, h.version.1),
        )],
    })
}

/// Members are decompressed one at a time; none may exceed this (1 TiB: a cap against a lying
/// size field, the ZIP reader also bounds it by deflate's ratio).
const MAX_MEMBER: u64 = 1 << 40;

pub(super) fn read_npz(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let mmap = map(path)?;
    let zip = ZipArchive::parse(&mmap).map_err(|e| read_err(path, e))?;
    // Stored members are read in place; deflated ones are inflated into `owned` first.
    let mut owned: Vec<(String, Vec<u8>)> = Vec::new();
    let mut borrowed: Vec<(String, &[u8])> = Vec::new();
    for e in zip.entries() {
        let Some(stem) = e.name.strip_suffix(".npy") else {
            continue;
        };
        match zip.stored_slice(e).map_err(|err| read_err(path, err))? {
            Some(b) => borrowed.push((stem.to_string(), b)),
            None => owned.push((
                stem.to_string(),
                zip.read(e, MAX_MEMBER).map_err(|err| read_err(path, err))?,
            )),
        }
    }
    let members = borrowed
        .into_iter()
        .chain(owned.iter().map(|(n, b)| (n.clone(), b.as_slice())));
    let mut meta = Meta::default();
    let mut columns = Vec::new();
    for (name, bytes) in members {
        let h = npy::parse(bytes, bytes.len())
            .map_err(|e| read_err(path, format!("member {name}.npy: {e}")))?;
        if h.shape.is_empty() {
            // A 0-d member is a metadata value (np.savez(..., sample_rate=4e6)).
            let one = Header {
                shape: vec![1],
                ..h.clone()
            };
            let (cols, _) = array_columns(path, &one, bytes)?;
            let v = cols
                .first()
                .and_then(|c| c.segs.first())
                .and_then(columns::first_value);
            if let Some(x) = v {
                meta.set(&name, &x.to_string())
                    .map_err(|m| record_err(path, format!("member {name}.npy: {m}")))?;
            }
            continue;
        }
        if h.shape.len() != 1 {
            return Err(record_err(
                path,
                format!(
                    "member {name}.npy has shape {:?}; .npz channels are 1-D arrays",
                    h.shape
                ),
            ));
        }
        let (mut cols, _) = array_columns(path, &h, bytes)?;
        if let Dtype::Scalar(_) = h.dtype {
            if let Some(mut c) = cols.pop() {
                c.name = name.clone();
                columns.push(c);
            }
        } else {
            columns.extend(cols);
        }
    }
    let table = Table {
        format: "npz",
        columns,
        meta,
        meta_hint: "a 0-d 'sample_rate' member (np.savez(..., sample_rate=fs))",
        what: "member",
        positional: false,
        provenance: vec![],
    };
    columns::read(path, table, opts)
}
