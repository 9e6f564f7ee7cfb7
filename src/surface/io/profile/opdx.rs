//! Bruker Vision64 `.opdx` (Dektak XT stylus profilometers): after the magic, a tree of named,
//! typed items (containers hold items up to a terminator). A line profile is
//! `/1D_Data/<channel>` (channel names in `/MetaData/1D_Channels/Height`) with `NumPoints`,
//! `Extent` (first-to-last point distance, a unit item), `DataScale` (height per raw unit) and
//! `Array` (5 bytes of prefix, then little-endian float64 raw heights). Item layout and type
//! ids as SurfaceTopography 1.27.1's `IO/OPDx.py` and Gwyddion's `dektakvca.c` describe them.

use super::{format_error, unit_factor, RawProfile};
use crate::surface::Result;
use std::collections::BTreeMap;
use std::path::Path;

pub(crate) const MAGIC: &[u8] = b"VCA DATA\x01\x00\x00\x55";

const CONTAINER: u8 = 0x7D;
const RAW_DATA: u8 = 0x46;
const RAW_DATA_2D: u8 = 0x47;
const POS_RAW_DATA: u8 = 0x7C;
const TERMINATOR: u8 = 0x7F;
/// Bytes of the double array's prefix before the values.
const DOUBLE_ARRAY_EXTRA: usize = 5;
/// Bytes after a unit's value.
const UNIT_EXTRA: usize = 12;
/// Containers nested deeper than this are refused (real files nest a handful of levels).
const MAX_DEPTH: usize = 64;

#[derive(Debug, Clone)]
enum Item {
    Int(i128),
    Float(f64),
    Text(String),
    /// A value with a unit (unit and quantity items).
    Unit {
        symbol: String,
        value: f64,
    },
    /// Start and length of a byte block in the file.
    Block {
        start: usize,
        len: usize,
    },
    List(Vec<String>),
    Other,
}

struct Cursor<'a> {
    path: &'a Path,
    b: &'a [u8],
    pos: usize,
}

impl Cursor<'_> {
    fn err(&self, what: &str) -> crate::surface::SurfaceError {
        format_error(self.path, format!("at byte {}: {what}", self.pos))
    }
    fn take(&mut self, n: usize) -> Result<&[u8]> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|e| *e <= self.b.len())
            .ok_or_else(|| {
                self.err(&format!(
                    "{n} bytes needed, the file ends first (truncated?)"
                ))
            })?;
        let s = &self.b[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8> {
        Ok(self.take(1)?[0])
    }
    fn uint(&mut self, n: usize) -> Result<u64> {
        let s = self.take(n)?;
        Ok(s.iter().rev().fold(0u64, |a, &v| (a << 8) | v as u64))
    }
    fn f64(&mut self) -> Result<f64> {
        let s = self.take(8)?;
        Ok(f64::from_le_bytes(s.try_into().unwrap_or([0; 8])))
    }
    fn name(&mut self) -> Result<String> {
        let n = self.uint(4)? as usize;
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }
    /// A length stored in 1, 2 or 4 bytes after a byte saying which.
    fn varlen(&mut self) -> Result<usize> {
        match self.u8()? {
            k @ (1 | 2 | 4) => Ok(self.uint(k as usize)? as usize),
            k => Err(self.err(&format!("length field of {k} bytes (1, 2 or 4 expected)"))),
        }
    }
    /// Skip a block of `len` bytes, checked against the file length.
    fn block(&mut self, len: usize) -> Result<Item> {
        let start = self.pos;
        self.take(len)?;
        Ok(Item::Block { start, len })
    }
    fn seek_to(&mut self, end: usize, what: &str) -> Result<()> {
        if end > self.b.len() || end < self.pos {
            return Err(self.err(&format!("{what} ends at byte {end}, outside the item")));
        }
        self.pos = end;
        Ok(())
    }
    fn unit_data(&mut self) -> Result<Item> {
        self.name()?;
        let symbol = self.name()?;
        let value = self.f64()?;
        self.take(UNIT_EXTRA)?;
        Ok(Item::Unit { symbol, value })
    }
}

/// Reads one item into `manifest`; `false` at a terminator or the end of the file.
fn read_item(
    c: &mut Cursor,
    manifest: &mut BTreeMap<String, Item>,
    prefix: &str,
    depth: usize,
) -> Result<bool> {
    if c.pos >= c.b.len() {
        return Ok(false);
    }
    let path = format!("{prefix}/{}", c.name()?);
    let item = match c.u8()? {
        TERMINATOR => return Ok(false),
        CONTAINER | RAW_DATA | RAW_DATA_2D => {
            if depth >= MAX_DEPTH {
                return Err(c.err("containers nested too deep"));
            }
            let len = c.varlen()?;
            let end = c.pos.saturating_add(len);
            if end > c.b.len() {
                return Err(c.err(&format!(
                    "container of {len} bytes past the end of the file"
                )));
            }
            while c.pos < end && read_item(c, manifest, &path, depth + 1)? {}
            c.take(2)?;
            if c.pos != end {
                return Err(c.err(&format!("container `{path}` should end at byte {end}")));
            }
            return Ok(true);
        }
        POS_RAW_DATA => {
            c.name()?;
            let len = c.varlen()?;
            c.block(len)?;
            Item::Other
        }
        0x01 => Item::Int(c.u8()? as i128),
        0x04 => Item::Int(c.uint(2)? as u16 as i16 as i128),
        0x05 => Item::Int(c.uint(2)? as i128),
        0x06 => Item::Int(c.uint(4)? as u32 as i32 as i128),
        0x07 => Item::Int(c.uint(4)? as i128),
        0x0A => Item::Int(c.uint(8)? as i64 as i128),
        0x0B => Item::Int(c.uint(8)? as i128),
        0x0C => Item::Float(f32::from_bits(c.uint(4)? as u32) as f64),
        0x0D => Item::Float(c.f64()?),
        0x0E | 0x40 => {
            c.name()?;
            let len = c.varlen()?;
            c.block(len)?
        }
        0x12 => {
            let len = c.varlen()?;
            Item::Text(String::from_utf8_lossy(c.take(len)?).into_owned())
        }
        0x13 => {
            let len = c.varlen()?;
            let end = c.pos.saturating_add(len);
            let value = c.f64()?;
            c.name()?;
            let symbol = c.name()?;
            c.seek_to(end, "quantity")?;
            Item::Unit { symbol, value }
        }
        0x15 => {
            c.take(9)?;
            Item::Other
        }
        0x18 => {
            let len = c.varlen()?;
            let end = c.pos.saturating_add(len);
            let u = c.unit_data()?;
            if c.pos != end {
                return Err(c.err("unit item of unexpected length"));
            }
            u
        }
        0x42 => {
            c.name()?;
            let len = c.varlen()?;
            let end = c.pos.saturating_add(len);
            let mut list = Vec::new();
            while c.pos < end {
                list.push(c.name()?);
            }
            if c.pos != end {
                return Err(c.err("string list of unexpected length"));
            }
            Item::List(list)
        }
        0x00 => {
            c.name()?;
            c.uint(4)?;
            c.name()?;
            let len = c.varlen()?;
            c.block(len)?;
            Item::Other
        }
        0x45 => {
            c.name()?;
            let len = c.varlen()?;
            c.block(len)?;
            Item::Other
        }
        t => return Err(c.err(&format!("unknown item type 0x{t:02x} in `{path}`"))),
    };
    manifest.insert(path, item);
    Ok(true)
}

pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<RawProfile> {
    let mut c = Cursor {
        path,
        b: bytes,
        pos: MAGIC.len(),
    };
    let mut manifest = BTreeMap::new();
    while read_item(&mut c, &mut manifest, "", 0)? {}
    let get = |k: &str| {
        manifest
            .get(k)
            .ok_or_else(|| format_error(path, format!("no `{k}` item")))
    };
    let channel = match manifest.get("/MetaData/1D_Channels/Height") {
        Some(Item::List(l)) if !l.is_empty() => l[0].clone(),
        _ if manifest.keys().any(|k| k.starts_with("/2D_Data/")) => {
            return Err(format_error(
                path,
                "an OPDx height map (2-D); hdi reads OPDx line profiles only",
            ))
        }
        _ => {
            return Err(format_error(
                path,
                "no 1-D height channel (`/MetaData/1D_Channels/Height`)",
            ))
        }
    };
    let prefix = format!("/1D_Data/{channel}");
    let n = match get(&format!("{prefix}/NumPoints"))? {
        Item::Int(n) if *n >= 2 => *n as u128 as usize,
        other => {
            return Err(format_error(
                path,
                format!("`{prefix}/NumPoints` is {other:?}"),
            ))
        }
    };
    let unit = |k: &str| -> Result<(f64, f64)> {
        match get(&format!("{prefix}/{k}"))? {
            Item::Unit { symbol, value } => {
                let f = unit_factor(symbol).ok_or_else(|| {
                    format_error(
                        path,
                        format!("`{prefix}/{k}`: `{symbol}` is not a length unit"),
                    )
                })?;
                Ok((*value, f))
            }
            _ => Err(format_error(
                path,
                format!("`{prefix}/{k}` is not a value with a unit"),
            )),
        }
    };
    let (extent, fx) = unit("Extent")?;
    let (scale, fz) = unit("DataScale")?;
    let Item::Block { start, len } = get(&format!("{prefix}/Array"))? else {
        return Err(format_error(
            path,
            format!("`{prefix}/Array` is not a data array"),
        ));
    };
    if n.checked_mul(8)
        .and_then(|b| b.checked_add(DOUBLE_ARRAY_EXTRA))
        != Some(*len)
    {
        return Err(format_error(
            path,
            format!("`{prefix}/Array` holds {len} bytes, not {n} float64 values"),
        ));
    }
    let data = &bytes[start + DOUBLE_ARRAY_EXTRA..start + len];
    let dx = extent * fx / (n - 1) as f64;
    let x = (0..n).map(|k| k as f64 * dx).collect();
    let z = data
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])) * scale * fz)
        .collect();
    let mut header = BTreeMap::new();
    for (k, v) in &manifest {
        if let Some(key) = k.strip_prefix("/MetaData/") {
            let text = match v {
                Item::Int(i) => i.to_string(),
                Item::Float(f) => f.to_string(),
                Item::Text(s) => s.clone(),
                Item::Unit { symbol, value } => format!("{value} {symbol}"),
                Item::List(l) => l.join(", "),
                Item::Block { .. } | Item::Other => continue,
            };
            header.insert(key.to_string(), text);
        }
    }
    header.insert("channel".into(), channel);
    Ok(RawProfile { x, z, header })
}
