//! Universal File Format dataset 58 (function at a nodal DOF) as vibrometer and DAQ software
//! exports time records: ASCII (`58`) and the UC-SDRL binary variant (`58b`), following the
//! dataset description that pyuff ships (docs/dmw.md). Each dataset is framed by `    -1`
//! lines; its 11 header records are
//!
//! 1–5 ID lines (ID line 1 names the channel), 6 function type, response node and direction,
//! 7 ordinate data type (2 real single, 4 real double, 5/6 complex), number of points,
//! even (1) / uneven (0) abscissa, abscissa start and increment, 8–11 axis characteristics
//! (data type, unit exponents, axis label, units label) of abscissa, ordinate numerator,
//! ordinate denominator and z axis.
//!
//! ASCII data follow as Fortran E fields (6 × E13.5 single, 4 × E20.12 double; uneven
//! abscissa interleaves x and y). In `58b` the dataset line also gives the byte order (1 little,
//! 2 big endian), the float format (2 IEEE 754) and the byte count of the binary block that
//! follows the 11th header line (y values, or x, y pairs for uneven abscissa, in the ordinate
//! precision). Every dataset 58 is one channel; other datasets (151, 164, …) are skipped.

use super::columns::{self, Column, Num, Seg, Table};
use super::names::{parse_unit, Meta, Unit};
use super::{read_err, record_err, ReadOptions};
use crate::dmw::{DmwError, LdvRecord};
use std::path::Path;

/// Whether `head` starts like a universal file: blank lines, then a `-1` delimiter line,
/// then a dataset number.
pub(super) fn is_uff(head: &[u8]) -> bool {
    let mut lines = head
        .split(|&b| b == b'\n')
        .map(|l| l.trim_ascii())
        .skip_while(|l| l.is_empty());
    lines.next() == Some(&b"-1"[..])
        && lines.next().is_some_and(|l| {
            !l.is_empty() && l.iter().take_while(|b| b.is_ascii_digit()).count() > 0
        })
}

/// A cursor over the lines of the file (1-based line numbers for messages).
struct Lines<'a> {
    b: &'a [u8],
    pos: usize,
    line: usize,
    /// Bytes before this offset have been handed back to the kernel (see `release`).
    released: usize,
}

/// ASCII data is parsed once, front to back: every 32 MiB the pages already parsed leave the
/// resident set, so a large ASCII file costs its parsed values, not its text as well
/// (docs/performance.md, "LDV reader throughput").
const RELEASE_STEP: usize = 32 << 20;

impl<'a> Lines<'a> {
    /// Drops the mapped pages before the cursor from the resident set. The map is a shared,
    /// read-only file mapping, so a page touched again is simply read back from the file.
    fn release(&mut self) {
        if self.pos - self.released < RELEASE_STEP {
            return;
        }
        let page = 1usize << 12;
        let base = self.b.as_ptr() as usize;
        let start = (base + self.released).next_multiple_of(page);
        let end = (base + self.pos) & !(page - 1);
        if end > start {
            // SAFETY: [start, end) lies inside the mapping (base is page-aligned by mmap);
            // MADV_DONTNEED on a shared file mapping only drops cached pages.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_DONTNEED);
            }
        }
        self.released = self.pos;
    }

    fn next(&mut self) -> Option<&'a [u8]> {
        if self.pos >= self.b.len() {
            return None;
        }
        let rest = &self.b[self.pos..];
        let end = rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
        self.pos += (end + 1).min(rest.len());
        self.line += 1;
        let l = &rest[..end];
        Some(l.strip_suffix(b"\r").unwrap_or(l))
    }
}

/// One dataset 58 as read: its channel data, either in the file (binary) or parsed (ASCII).
struct Function<'a> {
    name: String,
    alias: String,
    n: usize,
    even: bool,
    x0: f64,
    dx: f64,
    x_unit: String,
    y_unit: Option<String>,
    spec_type: i64,
    data: Data<'a>,
    line: usize,
}

enum Data<'a> {
    Binary {
        bytes: &'a [u8],
        num: Num,
        big_endian: bool,
    },
    Ascii {
        x: Vec<f64>,
        y: Vec<f64>,
    },
}

fn field(line: &[u8], from: usize, to: usize) -> String {
    let s = String::from_utf8_lossy(
        line.get(from.min(line.len())..to.min(line.len()))
            .unwrap_or(&[]),
    );
    s.trim().to_string()
}

/// A Fortran real: `1.5E+00`, also with a `D` exponent.
fn fortran_real(tok: &str) -> Option<f64> {
    tok.parse::<f64>()
        .ok()
        .or_else(|| tok.replace(['D', 'd'], "E").parse::<f64>().ok())
}

fn label(s: String) -> Option<String> {
    (!s.is_empty() && !s.eq_ignore_ascii_case("none")).then_some(s)
}

pub(super) fn read(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let file = std::fs::File::open(path).map_err(|e| read_err(path, e))?;
    // SAFETY: read-only map; hdi does not modify the file while reading it.
    let mmap = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| read_err(path, e))?;
    let functions = parse(path, &mmap)?;
    if functions.is_empty() {
        return Err(record_err(
            path,
            "no dataset 58 (function) in the universal file",
        ));
    }
    let first = &functions[0];
    let mut meta = Meta::default();
    let x_scale = match parse_unit(&first.x_unit) {
        _ if label(first.x_unit.clone()).is_none() => 1.0,
        Some(Unit::Second(f)) => f,
        _ => {
            return Err(record_err(
                path,
                format!(
                    "the abscissa of '{}' is in '{}', not time; an LDV record is a time record",
                    first.name, first.x_unit
                ),
            ))
        }
    };
    for f in &functions {
        if f.even != first.even
            || (f.even && (f.dx != first.dx || f.x0 != first.x0))
            || f.x_unit != first.x_unit
        {
            return Err(record_err(
                path,
                format!(
                    "functions '{}' and '{}' have different abscissas (start, increment or \
                     unit); a record's channels share one time axis",
                    first.name, f.name
                ),
            ));
        }
    }
    if first.even {
        if !(first.dx.is_finite() && first.dx > 0.0) {
            return Err(record_err(
                path,
                format!(
                    "function '{}' (line {}) has abscissa increment {}; it must be positive",
                    first.name, first.line, first.dx
                ),
            ));
        }
        meta.sample_rate = Some(1.0 / (first.dx * x_scale));
        meta.t0 = Some(first.x0 * x_scale);
    }
    let mut columns = Vec::new();
    for f in &functions {
        let mut col = match &f.data {
            Data::Ascii { y, .. } => Column::new(f.name.clone(), vec![Seg::F64(y)]),
            Data::Binary {
                bytes,
                num,
                big_endian,
            } => {
                let (offset, stride) = if f.even {
                    (0, num.size())
                } else {
                    (num.size(), 2 * num.size())
                };
                let seg = Seg::Bytes {
                    bytes,
                    offset,
                    stride,
                    len: f.n,
                    num: *num,
                    big_endian: *big_endian,
                    valid: None,
                };
                Column::new(f.name.clone(), vec![seg])
            }
        };
        col.alias = Some(f.alias.clone());
        // Data type 11 is velocity (the units label, when present, says which unit).
        col.unit = f
            .y_unit
            .clone()
            .or((f.spec_type == 11).then(|| "m/s".to_string()));
        columns.push(col);
    }
    // Uneven abscissa: the first function's x values are the time column.
    if !first.even {
        let seg = match &first.data {
            Data::Ascii { x, .. } => Seg::F64(x),
            Data::Binary {
                bytes,
                num,
                big_endian,
            } => Seg::Bytes {
                bytes,
                offset: 0,
                stride: 2 * num.size(),
                len: first.n,
                num: *num,
                big_endian: *big_endian,
                valid: None,
            },
        };
        let unit = if x_scale == 1e-3 {
            "ms"
        } else if x_scale == 1e-6 {
            "us"
        } else {
            "s"
        };
        columns.push(Column::new(format!("time_{unit}"), vec![seg]));
    }
    let provenance = vec![(
        "uff".to_string(),
        functions
            .iter()
            .map(|f| format!("{} (node:dir {}, line {})", f.name, f.alias, f.line))
            .collect::<Vec<_>>()
            .join("; "),
    )];
    let table = Table {
        format: "uff58",
        columns,
        meta,
        meta_hint: "an even abscissa (record 7 start and increment)",
        what: "function",
        positional: true,
        provenance,
    };
    columns::read(path, table, opts)
}

fn parse<'a>(path: &Path, b: &'a [u8]) -> Result<Vec<Function<'a>>, DmwError> {
    let mut lines = Lines {
        b,
        pos: 0,
        line: 0,
        released: 0,
    };
    let mut out = Vec::new();
    loop {
        let Some(id) = open_dataset(path, &mut lines)? else {
            return Ok(out);
        };
        let id_line = lines.line;
        let id_text = String::from_utf8_lossy(id).to_string();
        let mut words = id_text.split_whitespace();
        let number = words.next().unwrap_or("");
        let (number, binary) = match number.strip_suffix(['b', 'B']) {
            Some(n) => (n, true),
            None => (number, false),
        };
        if number != "58" {
            // Another dataset: skip to its closing delimiter (binary datasets other than 58b
            // are not expected in time-record exports).
            if !skip_dataset(&mut lines) {
                return Ok(out);
            }
            continue;
        }
        let rec = header_records(path, &mut lines, id_line)?;
        let h = parse_header(path, &rec, id_line)?;
        let data = if binary {
            read_binary_block(path, &mut lines, &id_text, id_line, &h)?
        } else {
            read_ascii_values(path, &mut lines, &h)?
        };
        out.push(Function {
            name: h.name,
            alias: h.alias,
            n: h.n,
            even: h.even,
            x0: h.x0,
            dx: h.dx,
            x_unit: h.x_unit,
            y_unit: h.y_unit,
            spec_type: h.spec_type,
            data,
            line: id_line,
        });
    }
}

fn line_err(path: &Path, line: usize, what: String) -> DmwError {
    record_err(path, format!("line {line}: {what}"))
}

/// The dataset number line after an opening `-1` delimiter (blank lines between datasets
/// are tolerated); `None` at the end of the file.
fn open_dataset<'a>(path: &Path, lines: &mut Lines<'a>) -> Result<Option<&'a [u8]>, DmwError> {
    let open = loop {
        match lines.next() {
            None => return Ok(None),
            Some(l) if l.trim_ascii().is_empty() => continue,
            Some(l) => break l,
        }
    };
    if open.trim_ascii() != b"-1" {
        return Err(record_err(
            path,
            format!(
                "line {}: expected the '    -1' dataset delimiter, found '{}'",
                lines.line,
                String::from_utf8_lossy(&open[..open.len().min(40)]).trim()
            ),
        ));
    }
    let Some(id) = lines.next().filter(|l| !l.trim_ascii().is_empty()) else {
        return Err(record_err(
            path,
            format!(
                "line {}: the file ends after a '    -1' delimiter; is it cut?",
                lines.line
            ),
        ));
    };
    Ok(Some(id))
}

/// Moves past the closing delimiter of a dataset; false if the file ends first.
fn skip_dataset(lines: &mut Lines<'_>) -> bool {
    loop {
        match lines.next() {
            None => return false,
            Some(l) if l.trim_ascii() == b"-1" => return true,
            Some(_) => {}
        }
    }
}

/// The 11 header records of the dataset 58 whose number line is `id_line`.
fn header_records<'a>(
    path: &Path,
    lines: &mut Lines<'a>,
    id_line: usize,
) -> Result<Vec<&'a [u8]>, DmwError> {
    let mut rec: Vec<&[u8]> = Vec::with_capacity(11);
    for _ in 0..11 {
        match lines.next() {
            Some(l) => rec.push(l),
            None => {
                return Err(line_err(
                    path,
                    lines.line,
                    format!(
                        "dataset 58 from line {id_line} ends inside its 11 header records; \
                         is the file cut?"
                    ),
                ))
            }
        }
    }
    Ok(rec)
}

/// What the header records of one dataset 58 say about its data.
struct Header58 {
    name: String,
    alias: String,
    /// Ordinate in single (4-byte) rather than double precision.
    single: bool,
    n: usize,
    even: bool,
    x0: f64,
    dx: f64,
    x_unit: String,
    y_unit: Option<String>,
    spec_type: i64,
}

impl Header58 {
    /// Values per point: y alone on an even abscissa, x and y otherwise.
    fn per(&self) -> usize {
        if self.even {
            1
        } else {
            2
        }
    }
}

/// Records 1 (name), 6 (node and direction), 7 (data type, points, abscissa) and 8–9 (units).
fn parse_header(path: &Path, rec: &[&[u8]], id_line: usize) -> Result<Header58, DmwError> {
    let name = String::from_utf8_lossy(rec[0]).trim().to_string();
    let r6 = rec[5];
    let node = field(r6, 41, 51);
    let dir = field(r6, 51, 55);
    let alias = format!("{node}:{dir}");
    let name = label(name).unwrap_or_else(|| alias.clone());
    let r7 = String::from_utf8_lossy(rec[6]).to_string();
    let r7_line = id_line + 7;
    let bad = |what: String| line_err(path, r7_line, what);
    let t: Vec<&str> = r7.split_whitespace().collect();
    if t.len() < 5 {
        return Err(bad(format!(
            "record 7 of '{name}' has {} fields, expected 6",
            t.len()
        )));
    }
    let int = |s: &str, what: &str| {
        s.parse::<i64>()
            .map_err(|_| bad(format!("record 7 {what} '{s}' is not an integer")))
    };
    let real = |s: &str, what: &str| {
        s.replace(['D', 'd'], "E")
            .parse::<f64>()
            .map_err(|_| bad(format!("record 7 {what} '{s}' is not a number")))
    };
    let ord = int(t[0], "ordinate data type")?;
    let n = int(t[1], "number of points")?;
    let even = int(t[2], "abscissa spacing")? == 1;
    let x0 = real(t[3], "abscissa start")?;
    let dx = real(t[4], "abscissa increment")?;
    let single = match ord {
        2 => true,
        4 => false,
        5 | 6 => {
            return Err(bad(format!(
                "'{name}' holds complex data (ordinate type {ord}); an LDV record is a \
                 real time signal"
            )))
        }
        _ => {
            return Err(bad(format!(
                "'{name}': unknown ordinate data type {ord} (2, 4, 5 or 6)"
            )))
        }
    };
    let n = usize::try_from(n).map_err(|_| bad(format!("'{name}' has {n} points")))?;
    Ok(Header58 {
        name,
        alias,
        single,
        n,
        even,
        x0,
        dx,
        x_unit: field(rec[7], 47, 67),
        y_unit: label(field(rec[8], 47, 67)),
        spec_type: field(rec[8], 0, 10).parse::<i64>().unwrap_or(0),
    })
}

/// The binary block of a `58b` dataset, left in the file: its byte count must match the
/// points and fit in the file, and a `-1` must follow it.
fn read_binary_block<'a>(
    path: &Path,
    lines: &mut Lines<'a>,
    id_text: &str,
    id_line: usize,
    h: &Header58,
) -> Result<Data<'a>, DmwError> {
    let (name, n, even, single) = (&h.name, h.n, h.even, h.single);
    let w: Vec<&str> = id_text.split_whitespace().collect();
    let order = w.get(1).and_then(|s| s.parse::<i64>().ok()).unwrap_or(1);
    let n_bytes = w
        .get(4)
        .and_then(|s| s.parse::<u64>().ok())
        .ok_or_else(|| {
            line_err(
                path,
                id_line,
                "the 58b line has no byte count (field 6)".to_string(),
            )
        })?;
    let size = if single { 4 } else { 8 };
    // The byte count must match the points (checked against the file below before
    // anything is read).
    let need = (n as u64).checked_mul((h.per() * size) as u64);
    if need != Some(n_bytes) {
        return Err(line_err(
            path,
            id_line,
            format!(
                "'{name}': the 58b block has {n_bytes} bytes but {n} points of \
                 {size}-byte values{} need {}",
                if even { "" } else { " with abscissa" },
                need.map_or("more".to_string(), |x| x.to_string())
            ),
        ));
    }
    let b = lines.b;
    let start = lines.pos;
    let end = usize::try_from(n_bytes)
        .ok()
        .and_then(|k| start.checked_add(k))
        .filter(|&e| e <= b.len())
        .ok_or_else(|| {
            line_err(
                path,
                lines.line,
                format!(
                    "'{name}': the 58b block of {n_bytes} bytes runs past the end of the \
                     file; is it cut?"
                ),
            )
        })?;
    lines.pos = end;
    let close = lines.next().unwrap_or(b"");
    let close = if close.trim_ascii().is_empty() {
        lines.next().unwrap_or(b"")
    } else {
        close
    };
    if close.trim_ascii() != b"-1" {
        return Err(line_err(
            path,
            lines.line,
            format!("'{name}': no '    -1' after the 58b block; is the file corrupt?"),
        ));
    }
    Ok(Data::Binary {
        bytes: &b[start..end],
        num: if single { Num::F32 } else { Num::F64 },
        big_endian: order == 2,
    })
}

/// Parses the ASCII values of a dataset up to its closing `-1`: y values, or interleaved
/// x, y pairs on an uneven abscissa.
fn read_ascii_values<'a>(
    path: &Path,
    lines: &mut Lines<'a>,
    h: &Header58,
) -> Result<Data<'a>, DmwError> {
    let (name, n, even, per) = (&h.name, h.n, h.even, h.per());
    let bad = |line: usize, what: String| line_err(path, line, what);
    let width: &[usize] = match (h.single, even) {
        (true, _) => &[13],
        (false, true) => &[20],
        (false, false) => &[13, 20],
    };
    // Capacity from the header only up to what the rest of the file can hold
    // (a value takes at least 2 bytes).
    let b = lines.b;
    let cap = n.min((b.len() - lines.pos.min(b.len())) / 2);
    let mut x = Vec::with_capacity(if even { 0 } else { cap });
    let mut y = crate::numerics::buffer::sample_buffer(cap);
    let mut k = 0usize;
    let mut vals: Vec<f64> = Vec::with_capacity(8);
    loop {
        let Some(l) = lines.next() else {
            return Err(bad(
                lines.line,
                format!(
                    "'{name}' ends without its '    -1' delimiter after {} of {n} \
                     values; is the file cut?",
                    k / per
                ),
            ));
        };
        if l.trim_ascii() == b"-1" {
            break;
        }
        lines.release();
        let text = std::str::from_utf8(l)
            .map_err(|_| bad(lines.line, format!("'{name}': data is not text")))?;
        // Whitespace-separated fields first; touching fixed-width fields (a 3-digit
        // exponent fills E13.5) are re-read by width.
        vals.clear();
        let spaced = text.split_whitespace().all(|tok| match fortran_real(tok) {
            Some(v) => {
                vals.push(v);
                true
            }
            None => false,
        });
        if !spaced {
            vals.clear();
            let mut at = 0;
            let mut j = 0;
            while at < text.len() {
                let w = width[j % width.len()];
                let cell = text.get(at..(at + w).min(text.len())).unwrap_or("");
                let v = fortran_real(cell.trim()).ok_or_else(|| {
                    bad(
                        lines.line,
                        format!("'{name}': '{}' is not a number", cell.trim()),
                    )
                })?;
                vals.push(v);
                at += w;
                j += 1;
            }
        }
        for &v in &vals {
            if k / per < n {
                if !even && k.is_multiple_of(2) {
                    x.push(v);
                } else {
                    y.push(v);
                }
            }
            k += 1;
        }
    }
    if k != n * per {
        return Err(bad(
            lines.line,
            format!(
                "'{name}' declares {n} points but has {} values{}; is the file cut or \
                 corrupt?",
                k,
                if even { "" } else { " (x, y pairs)" }
            ),
        ));
    }
    Ok(Data::Ascii { x, y })
}
