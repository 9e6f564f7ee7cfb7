//! The binary formats whose channels are whole numeric columns (Arrow IPC, UFF58, `.npy`,
//! `.npz`, WAV) share this path: each reader describes its channels as typed, possibly strided
//! byte ranges (over a memory map where the format allows) or parsed `f64` vectors, and this
//! module picks the channels by name or number, decodes them in chunks into the shared
//! [`Stream`] (which checks them) and hands the result to [`finish`].

use super::names::{self, Meta, Unit};
use super::stream::{Col, Stream};
use super::{finish, flat_layout, record_err, velocity_unit, Raw, ReadOptions};
use crate::dmw::{DmwError, LdvRecord};
use std::path::Path;

/// Element type of a binary column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Num {
    F64,
    F32,
    I8,
    U8,
    I16,
    U16,
    /// 24-bit two's complement (WAV PCM).
    I24,
    I32,
    U32,
    I64,
    U64,
}

impl Num {
    pub fn size(self) -> usize {
        match self {
            Num::I8 | Num::U8 => 1,
            Num::I16 | Num::U16 => 2,
            Num::I24 => 3,
            Num::F32 | Num::I32 | Num::U32 => 4,
            Num::F64 | Num::I64 | Num::U64 => 8,
        }
    }
}

/// A run of consecutive samples of one column.
pub(super) enum Seg<'a> {
    /// `len` elements of type `num`, element `i` at `bytes[offset + i·stride..]`.
    Bytes {
        bytes: &'a [u8],
        offset: usize,
        stride: usize,
        len: usize,
        num: Num,
        big_endian: bool,
        /// Arrow validity bitmap (LSB first) and the bit of element 0; a clear bit is missing.
        valid: Option<(&'a [u8], usize)>,
    },
    /// Values parsed from text (UFF ASCII) or decoded already.
    F64(&'a [f64]),
}

impl Seg<'_> {
    fn len(&self) -> usize {
        match self {
            Seg::Bytes { len, .. } => *len,
            Seg::F64(v) => v.len(),
        }
    }

    /// Whether every element lies inside `bytes` (checked once, so decoding cannot panic).
    fn in_bounds(&self) -> bool {
        match self {
            Seg::Bytes {
                bytes,
                offset,
                stride,
                len,
                num,
                valid,
                ..
            } => {
                let end = match len {
                    0 => Some(0),
                    n => (n - 1)
                        .checked_mul(*stride)
                        .and_then(|x| x.checked_add(*offset))
                        .and_then(|x| x.checked_add(num.size())),
                };
                let bits_ok = valid.is_none_or(|(b, off)| {
                    off.checked_add(*len)
                        .is_some_and(|bits| bits.div_ceil(8) <= b.len())
                });
                end.is_some_and(|e| e <= bytes.len()) && bits_ok
            }
            Seg::F64(_) => true,
        }
    }

    /// Appends elements `from..from + n` (scaled) to `out` and their missing flags to `nulls`.
    fn decode(
        &self,
        from: usize,
        n: usize,
        scale: f64,
        offset_y: f64,
        out: &mut Vec<f64>,
        nulls: &mut Vec<bool>,
    ) {
        match self {
            Seg::F64(v) => {
                out.extend(v[from..from + n].iter().map(|x| x * scale + offset_y));
                nulls.extend(std::iter::repeat_n(false, n));
            }
            Seg::Bytes {
                bytes,
                offset,
                stride,
                num,
                big_endian,
                valid,
                ..
            } => {
                let (be, stride) = (*big_endian, *stride);
                let base = offset + from * stride;
                macro_rules! each {
                    ($w:expr, $conv:expr) => {{
                        out.extend((0..n).map(|i| {
                            let p = base + i * stride;
                            let a: [u8; $w] = bytes[p..p + $w].try_into().unwrap_or([0; $w]);
                            let x: f64 = $conv(a);
                            x * scale + offset_y
                        }))
                    }};
                }
                macro_rules! int {
                    ($t:ty, $w:expr) => {
                        each!($w, |a| if be {
                            <$t>::from_be_bytes(a) as f64
                        } else {
                            <$t>::from_le_bytes(a) as f64
                        })
                    };
                }
                match num {
                    Num::F64 => int!(f64, 8),
                    Num::F32 => int!(f32, 4),
                    Num::I8 => int!(i8, 1),
                    Num::U8 => int!(u8, 1),
                    Num::I16 => int!(i16, 2),
                    Num::U16 => int!(u16, 2),
                    Num::I32 => int!(i32, 4),
                    Num::U32 => int!(u32, 4),
                    Num::I64 => int!(i64, 8),
                    Num::U64 => int!(u64, 8),
                    Num::I24 => each!(3, |a: [u8; 3]| {
                        let b = if be {
                            [a[0], a[1], a[2], 0]
                        } else {
                            [a[2], a[1], a[0], 0]
                        };
                        // Sign-extend through the top byte of an i32.
                        (i32::from_be_bytes(b) >> 8) as f64
                    }),
                }
                match valid {
                    None => nulls.extend(std::iter::repeat_n(false, n)),
                    Some((bits, off)) => nulls.extend((0..n).map(|i| {
                        let b = off + from + i;
                        bits[b / 8] & (1 << (b % 8)) == 0
                    })),
                }
            }
        }
    }
}

/// The first element of `seg` (a 0-d metadata array), if it lies inside its bytes.
pub(super) fn first_value(seg: &Seg) -> Option<f64> {
    if seg.len() == 0 || !seg.in_bounds() {
        return None;
    }
    let (mut v, mut m) = (Vec::new(), Vec::new());
    seg.decode(0, 1, 1.0, 0.0, &mut v, &mut m);
    v.first().copied()
}

/// One channel of a file.
pub(super) struct Column<'a> {
    pub name: String,
    pub segs: Vec<Seg<'a>>,
    /// `y = scale·x + offset` (WAV full scale, UFF is 1).
    pub scale: f64,
    pub offset: f64,
    /// Unit the file states for this channel (UFF axis label, Arrow field metadata).
    pub unit: Option<String>,
    /// Another name the options may use (UFF `node:direction`).
    pub alias: Option<String>,
}

impl<'a> Column<'a> {
    pub fn new(name: impl Into<String>, segs: Vec<Seg<'a>>) -> Self {
        Column {
            name: name.into(),
            segs,
            scale: 1.0,
            offset: 0.0,
            unit: None,
            alias: None,
        }
    }

    fn len(&self) -> usize {
        self.segs.iter().map(Seg::len).sum()
    }

    /// Appends rows `from..from + n` to `out`/`nulls` (cleared first).
    fn fill(&self, from: usize, n: usize, out: &mut Vec<f64>, nulls: &mut Vec<bool>) {
        out.clear();
        nulls.clear();
        let (mut start, mut left, mut pos) = (0usize, n, from);
        for seg in &self.segs {
            let len = seg.len();
            if left > 0 && pos < start + len {
                let k = (start + len - pos).min(left);
                seg.decode(pos - start, k, self.scale, self.offset, out, nulls);
                pos += k;
                left -= k;
            }
            start += len;
        }
    }
}

impl Column<'_> {
    /// Every value of the column (scaled; missing values as NaN), after checking that its
    /// segments lie inside the data: for readers that need a whole column (`super::series`).
    pub(super) fn values(&self, path: &Path) -> Result<Vec<f64>, DmwError> {
        if !self.segs.iter().all(Seg::in_bounds) {
            return Err(record_err(
                path,
                format!(
                    "column '{}' extends past the end of the data; is the file cut?",
                    self.name
                ),
            ));
        }
        let (mut out, mut nulls) = (Vec::new(), Vec::new());
        self.fill(0, self.len(), &mut out, &mut nulls);
        for (v, null) in out.iter_mut().zip(&nulls) {
            if *null {
                *v = f64::NAN;
            }
        }
        Ok(out)
    }
}

/// A file's channels and what it says about them.
pub(super) struct Table<'a> {
    pub format: &'static str,
    pub columns: Vec<Column<'a>>,
    pub meta: Meta,
    pub meta_hint: &'static str,
    /// "column", "channel", "function", "member": in messages.
    pub what: &'static str,
    /// Without recognisable names, channel 0 is the velocity and channel 1 the index.
    pub positional: bool,
    pub provenance: Vec<(String, String)>,
}

/// Rows decoded per step: small enough to stay in cache, large enough to amortise the calls.
const CHUNK: usize = 1 << 16;

/// A number given as a column option (`--velocity-column 1`) names the channel at that
/// position (from 0) unless a channel has that name.
fn by_number(
    path: &Path,
    names: &[String],
    aliases: &[Option<String>],
    wanted: &Option<String>,
    what: &str,
) -> Result<Option<String>, DmwError> {
    let Some(w) = wanted else { return Ok(None) };
    if names
        .iter()
        .any(|n| names::clean(n).eq_ignore_ascii_case(names::clean(w)))
    {
        return Ok(Some(w.clone()));
    }
    if let Some(k) = aliases.iter().position(|a| a.as_deref() == Some(w.trim())) {
        return Ok(Some(names[k].clone()));
    }
    match w.trim().parse::<usize>() {
        Ok(k) if k < names.len() => Ok(Some(names[k].clone())),
        Ok(k) => Err(record_err(
            path,
            format!(
                "{what} number {k} does not exist: the file has {} {what}s (numbered from 0)",
                names.len()
            ),
        )),
        Err(_) => Ok(Some(w.clone())),
    }
}

pub(super) fn read(path: &Path, table: Table, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let what = table.what;
    for c in &table.columns {
        if !c.segs.iter().all(Seg::in_bounds) {
            return Err(record_err(
                path,
                format!(
                    "{what} '{}' extends past the end of the data; is the file cut?",
                    c.name
                ),
            ));
        }
    }
    let names: Vec<String> = table.columns.iter().map(|c| c.name.clone()).collect();
    if names.is_empty() {
        return Err(record_err(path, format!("no {what}s in the file")));
    }
    let aliases: Vec<Option<String>> = table.columns.iter().map(|c| c.alias.clone()).collect();
    let mut o = opts.clone();
    o.velocity_column = by_number(path, &names, &aliases, &opts.velocity_column, what)?;
    o.index_column = by_number(path, &names, &aliases, &opts.index_column, what)?;
    o.time_column = by_number(path, &names, &aliases, &opts.time_column, what)?;
    let chosen = match names::choose(&names, &o, what) {
        Ok(c) => c,
        // Files without channel names (WAV, plain arrays, UFF with free-text IDs): by position.
        Err(m) if table.positional && o.velocity_column.is_none() => {
            let roles: Vec<_> = names.iter().map(|n| names::classify(n).role).collect();
            if roles.iter().any(Option::is_some) {
                return Err(record_err(path, m));
            }
            let index = o
                .index_column
                .as_ref()
                .and_then(|w| names.iter().position(|n| n == w))
                .or((names.len() > 1).then_some(1));
            names::Chosen {
                velocity: if index == Some(0) {
                    1.min(names.len() - 1)
                } else {
                    0
                },
                velocity_unit: None,
                velocity_unknown_unit: None,
                index,
                time: None,
            }
        }
        Err(m) => return Err(record_err(path, m)),
    };
    let vcol = &table.columns[chosen.velocity];
    // The unit the name carries wins over the one the file states beside it.
    let (from_name, unknown) = match (&chosen.velocity_unit, &vcol.unit) {
        (Some(u), _) => (Some(*u), None),
        (None, Some(text)) => match names::parse_unit(text) {
            Some(u) => (Some(u), None),
            None if text.trim().is_empty() => (None, None),
            None => (None, Some(text.clone())),
        },
        (None, None) => (None, chosen.velocity_unknown_unit.clone()),
    };
    let source = if chosen.velocity_unit.is_some() {
        "column name"
    } else {
        "file unit label"
    };
    let unit = velocity_unit(
        path,
        opts,
        from_name,
        unknown.as_deref(),
        table.meta.velocity_unit,
        source,
    )?;
    if let Some(u @ (Unit::Second(_) | Unit::Count)) = from_name {
        return Err(record_err(
            path,
            format!("velocity {what} '{}' has unit {}", vcol.name, u.describe()),
        ));
    }
    let layout = flat_layout(path, &table.meta)?;
    let n = vcol.len();
    let picked = chosen.used();
    for &k in &picked {
        let len = table.columns[k].len();
        if len != n {
            return Err(record_err(
                path,
                format!(
                    "{what} '{}' has {len} samples, '{}' {n}; the channels must be equally long",
                    table.columns[k].name, vcol.name
                ),
            ));
        }
    }
    let mut stream = Stream::new(unit.scale, chosen.index.is_some(), chosen.time.is_some(), n);
    let mut bufs: Vec<(Vec<f64>, Vec<bool>)> = (0..3)
        .map(|_| (Vec::with_capacity(CHUNK), Vec::with_capacity(CHUNK)))
        .collect();
    let mut from = 0;
    while from < n {
        let k = CHUNK.min(n - from);
        let cols = chosen.slots();
        for (slot, c) in cols.iter().enumerate() {
            if let Some(c) = c {
                let (v, m) = &mut bufs[slot];
                table.columns[*c].fill(from, k, v, m);
            }
        }
        let col = |slot: usize| {
            let (v, m) = &bufs[slot];
            Col {
                values: v,
                nulls: m.iter().any(|x| *x).then_some(m.as_slice()),
            }
        };
        let done = stream.push(
            chosen.time.map(|_| col(2)),
            col(0),
            chosen.index.map(|_| col(1)),
        );
        if done {
            break;
        }
        from += k;
    }
    let raw = Raw {
        format: table.format,
        stream,
        velocity_name: names[chosen.velocity].clone(),
        index_name: chosen.index.map(|k| names[k].clone()),
        time: chosen.time.map(|(k, kind)| (names[k].clone(), kind)),
        unit,
        layout,
        meta: table.meta,
        meta_hint: table.meta_hint,
        provenance: table.provenance,
    };
    finish(path, raw, opts, &|row| format!("sample {row}"))
}
