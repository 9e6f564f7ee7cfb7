//! Delimited text (CSV, TSV, semicolon): the preamble and header are sniffed here, the data
//! are parsed part by part by polars' eager (multi-threaded) CSV reader with only the needed
//! columns projected. Cells polars cannot parse become nulls; the first one is then looked up
//! in the file to name the line and the cell (a slow path taken only on error).

use super::names::{self, Meta};
use super::scan::{self, I, T, V};
use super::stream::{BadRun, Channel, Stream};
use super::{
    finish, flat_layout, meta_pairs, read_err, record_err, run_message, velocity_unit,
    write_atomic, Raw, ReadOptions, F,
};
use crate::dmw::{DmwError, LdvRecord, VelocityUnit};
use polars_core::prelude::*;
use polars_io::prelude::*;
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom, Write};
use std::path::Path;

/// How far the preamble (comments + header) may reach.
const PREAMBLE_MAX: u64 = 1 << 20;
/// Bytes of text parsed per call of polars' eager CSV reader (cut at a line end). Tiny in the
/// unit tests so that their records (multi_chunk_csv, the bad-input files) cross part
/// boundaries.
const PART: usize = if cfg!(test) { 4 << 10 } else { 64 << 20 };
/// Bytes read from the end of the file to check the last line.
const TAIL_BYTES: u64 = 64 * 1024;

/// What the first lines of the file say.
struct Sniff {
    /// Lines before the header (comments, blank lines).
    header_index: usize,
    names: Vec<String>,
    sep: u8,
    decimal_comma: bool,
    meta: Meta,
    /// Length of the first data line in bytes (with its newline), for a row-count estimate.
    first_row_bytes: usize,
}

impl Sniff {
    /// 1-based line number of data row `row`.
    fn line_of(&self, row: usize) -> usize {
        self.header_index + 2 + row
    }
}

/// UTF-8 if valid, else latin-1 (instrument software writes `µ` as 0xB5).
fn decode(bytes: &[u8]) -> String {
    match std::str::from_utf8(bytes) {
        Ok(t) => t.to_string(),
        Err(_) => bytes.iter().map(|&b| b as char).collect(),
    }
}

fn sniff(path: &Path) -> Result<Sniff, DmwError> {
    let file = File::open(path).map_err(|e| read_err(path, e))?;
    let mut reader = BufReader::new(file.take(PREAMBLE_MAX));
    let mut buf = Vec::new();
    let mut meta = Meta::default();
    let mut lineno = 0usize;
    let mut header: Option<(usize, String)> = None;
    let mut first_data: Option<String> = None;
    loop {
        buf.clear();
        let n = reader
            .read_until(b'\n', &mut buf)
            .map_err(|e| read_err(path, e))?;
        if n == 0 {
            break;
        }
        lineno += 1;
        let bytes = if lineno == 1 {
            buf.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&buf)
        } else {
            &buf
        };
        let line = decode(bytes);
        let line = line.trim();
        if header.is_some() {
            if !line.is_empty() {
                first_data = Some(line.to_string());
                break;
            }
            continue;
        }
        if line.is_empty() {
            continue;
        }
        if let Some(comment) = line.strip_prefix('#') {
            let split = comment.find(['=', ':']);
            if let Some(k) = split {
                let (key, value) = (&comment[..k], &comment[k + 1..]);
                meta.set(key, value)
                    .map_err(|m| record_err(path, format!("line {lineno}: {m}")))?;
            }
            continue;
        }
        header = Some((lineno - 1, line.to_string()));
    }
    let Some((header_index, header)) = header else {
        let what = if lineno == 0 {
            "empty file".to_string()
        } else {
            format!(
                "no header line in the first {} lines; the first non-comment line must name \
                 the columns, e.g. time_s,velocity_V,index_V",
                lineno
            )
        };
        return Err(record_err(path, what));
    };
    let count = |c: char| header.matches(c).count();
    let sep = [('\t', b'\t'), (';', b';'), (',', b',')]
        .into_iter()
        .max_by_key(|(c, _)| count(*c))
        .filter(|(c, _)| count(*c) > 0)
        .map_or(b',', |(_, b)| b);
    let names: Vec<String> = header
        .split(sep as char)
        .map(|s| names::clean(s).to_string())
        .collect();
    if names.iter().all(|n| n.parse::<f64>().is_ok()) {
        return Err(record_err(
            path,
            format!(
                "line {}: no header line (it holds numbers); the first non-comment line must \
                 name the columns, e.g. time_s,velocity_V,index_V",
                header_index + 1
            ),
        ));
    }
    let mut decimal_comma = false;
    if let Some(data) = &first_data {
        if names.len() == 1 && data.split_whitespace().count() > 1 {
            return Err(record_err(
                path,
                format!(
                    "line {}: columns separated by spaces are not supported; use commas, tabs \
                     or semicolons",
                    header_index + 2
                ),
            ));
        }
        // A comma inside the fields of a tab- or semicolon-separated row is a decimal comma.
        decimal_comma = sep != b',' && data.contains(',') && !data.contains('.');
    }
    Ok(Sniff {
        header_index,
        names,
        sep,
        decimal_comma,
        meta,
        first_row_bytes: first_data.as_ref().map_or(0, |d| d.len() + 1),
    })
}

pub(super) fn read(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let sn = sniff(path)?;
    let chosen = names::choose(&sn.names, opts, "column").map_err(|m| record_err(path, m))?;
    let unit = velocity_unit(
        path,
        opts,
        chosen.velocity_unit,
        chosen.velocity_unknown_unit.as_deref(),
        sn.meta.velocity_unit,
        "header",
    )?;
    let layout = flat_layout(path, &sn.meta)?;

    let plan = CsvPlan::new(&sn, &chosen);
    // The data are parsed in parts of about PART bytes cut at line ends, each by polars'
    // multi-threaded eager reader: only one part's text and columns are in memory beside the
    // output channels, and the time column is reduced, never kept.
    let mut parts = Parts::after_header(path, sn.header_index)?;
    let next = || -> Result<Option<DataFrame>, DmwError> {
        match parts.next(path)? {
            Some(buf) => plan.parse(path, buf).map(Some),
            None => Ok(None),
        }
    };
    // Room for the rows the file size suggests (with 25 % slack for shorter rows): the big
    // channel buffers are then allocated once, on huge pages (numerics::buffer).
    let size = std::fs::metadata(path)
        .map(|m| m.len() as usize)
        .unwrap_or(0);
    let rows_guess = match sn.first_row_bytes {
        0 => 0,
        b => size / b + size / b / 4,
    };
    let stream = Stream::new(
        unit.scale,
        chosen.index.is_some(),
        chosen.time.is_some(),
        rows_guess,
    );
    let mut stream = scan::feed(path, next, stream, "CSV reader")?;

    let (trailing_blank, last_fields) = tail(path, sn.sep)?;
    let provenance = text_provenance(&sn);
    // Blank lines at the end of the file are rows of nulls to polars, not a gap.
    if let Some(run) = &stream.run {
        if !run.ended && run.all_missing && run.len == trailing_blank {
            stream.run = None;
        }
    }
    let raw = Raw {
        format: "csv",
        stream,
        velocity_name: sn.names[chosen.velocity].clone(),
        index_name: chosen.index.map(|k| sn.names[k].clone()),
        time: chosen.time.map(|(k, kind)| (sn.names[k].clone(), kind)),
        unit,
        layout,
        meta: sn.meta.clone(),
        meta_hint: "a '# sample_rate = …' line before the header",
        provenance,
    };
    let locate = |row: usize| format!("line {} (sample {row})", sn.line_of(row));
    if let Some(run) = &raw.stream.run {
        return Err(record_err(
            path,
            explain_run(path, &sn, &raw, run, &chosen)?,
        ));
    }
    let n = raw.stream.velocity.len();
    if raw.stream.time.as_ref().is_none_or(|t| t.fault.is_none()) && n > 0 {
        if let Some(k) = last_fields.filter(|k| *k < sn.names.len()) {
            return Err(record_err(
                path,
                format!(
                    "the last line (line {}) has {k} of {} fields: the file looks truncated; \
                     delete that line or restore the file",
                    sn.line_of(n - 1),
                    sn.names.len()
                ),
            ));
        }
    }
    finish(path, raw, opts, &locate)
}

/// Polars' name for column `k` (the file's own header is not used).
fn column_name(k: usize) -> String {
    format!("c{k}")
}

/// How each part is parsed: used columns as numbers, the others as strings (never
/// projected), and the velocity, index and time columns renamed to the stream's aliases.
struct CsvPlan {
    schema: Arc<Schema>,
    projection: Arc<[PlSmallStr]>,
    /// (column, alias) of velocity, index and time, in that order.
    select: Vec<(usize, &'static str)>,
    sep: u8,
    decimal_comma: bool,
}

impl CsvPlan {
    fn new(sn: &Sniff, chosen: &names::Chosen) -> Self {
        let mut schema = Schema::default();
        let used = chosen.used();
        for k in 0..sn.names.len() {
            let dtype = if used.contains(&k) {
                DataType::Float64
            } else {
                DataType::String
            };
            schema.insert(column_name(k).into(), dtype);
        }
        let mut select = vec![(chosen.velocity, V)];
        if let Some(k) = chosen.index {
            select.push((k, I));
        }
        if let Some((k, _)) = chosen.time {
            select.push((k, T));
        }
        let projection: Arc<[PlSmallStr]> = used.iter().map(|&k| column_name(k).into()).collect();
        CsvPlan {
            schema: Arc::new(schema),
            projection,
            select,
            sep: sn.sep,
            decimal_comma: sn.decimal_comma,
        }
    }

    /// One part of text (whole lines) as a frame of the selected columns.
    fn parse(&self, path: &Path, buf: Vec<u8>) -> Result<DataFrame, DmwError> {
        let read = CsvReadOptions::default()
            .with_has_header(false)
            .with_schema(Some(self.schema.clone()))
            .with_columns(Some(self.projection.clone()))
            .with_ignore_errors(true)
            .with_raise_if_empty(false)
            .map_parse_options(|o| {
                o.with_separator(self.sep)
                    .with_decimal_comma(self.decimal_comma)
            })
            .into_reader_with_file_handle(std::io::Cursor::new(buf))
            .finish()
            .map_err(|e| read_err(path, format!("CSV reader: {e}")))?;
        let columns = self
            .select
            .iter()
            .map(|(k, alias)| {
                read.column(column_name(*k).as_str())
                    .map(|col| col.clone().with_name((*alias).into()))
            })
            .collect::<PolarsResult<Vec<Column>>>()
            .map_err(|e| read_err(path, format!("CSV reader: {e}")))?;
        DataFrame::new(read.height(), columns)
            .map_err(|e| read_err(path, format!("CSV reader: {e}")))
    }
}

/// The data text after the header, in parts of about [`PART`] bytes cut at line ends.
struct Parts {
    file: File,
    /// What was read past the last line end (the start of the next part).
    carry: Vec<u8>,
    at_end: bool,
}

impl Parts {
    fn after_header(path: &Path, header_index: usize) -> Result<Self, DmwError> {
        let mut reader = BufReader::new(File::open(path).map_err(|e| read_err(path, e))?);
        let mut line = Vec::new();
        for _ in 0..=header_index {
            line.clear();
            reader
                .read_until(b'\n', &mut line)
                .map_err(|e| read_err(path, e))?;
        }
        let carry = reader.buffer().to_vec();
        Ok(Parts {
            file: reader.into_inner(),
            carry,
            at_end: false,
        })
    }

    /// The next part, `None` when the text is used up.
    fn next(&mut self, path: &Path) -> Result<Option<Vec<u8>>, DmwError> {
        let mut buf = std::mem::take(&mut self.carry);
        while !self.at_end {
            let got = Read::by_ref(&mut self.file)
                .take(PART as u64)
                .read_to_end(&mut buf)
                .map_err(|e| read_err(path, e))?;
            if got == 0 {
                self.at_end = true;
            } else if let Some(k) = buf.iter().rposition(|&b| b == b'\n') {
                // The unfinished last line goes to the next part.
                self.carry = buf.split_off(k + 1);
                break;
            }
        }
        Ok((!buf.is_empty()).then_some(buf))
    }
}

fn text_provenance(sn: &Sniff) -> Vec<(String, String)> {
    let mut provenance = vec![(
        "delimiter".to_string(),
        match sn.sep {
            b'\t' => "tab",
            b';' => "semicolon",
            _ => "comma",
        }
        .to_string(),
    )];
    if sn.decimal_comma {
        provenance.push(("decimal_comma".to_string(), "true".to_string()));
    }
    provenance
}

/// Message for the first bad run: names the offending cell when it is not a number or the row
/// is short, else the run of empty/NaN values.
fn explain_run(
    path: &Path,
    sn: &Sniff,
    raw: &Raw,
    run: &BadRun,
    chosen: &names::Chosen,
) -> Result<String, DmwError> {
    let locate = |row: usize| format!("line {} (sample {row})", sn.line_of(row));
    let generic = run_message(raw, run, &locate);
    if !run.missing {
        return Ok(generic);
    }
    let lineno = sn.line_of(run.start);
    let Some(line) = nth_line(path, lineno)? else {
        return Ok(generic);
    };
    let fields: Vec<&str> = line.split(sn.sep as char).collect();
    if line.trim().is_empty() {
        return Ok(format!(
            "line {lineno} (sample {}) is empty ({} missing sample{} from there); delete the \
             empty lines",
            run.start,
            run.len,
            if run.len == 1 { "" } else { "s" }
        ));
    }
    if fields.len() < sn.names.len() {
        return Ok(format!(
            "line {lineno} (sample {}) has {} of {} fields: a truncated or malformed row; fix \
             or delete it",
            run.start,
            fields.len(),
            sn.names.len()
        ));
    }
    for chan in &run.channels {
        let k = match chan {
            Channel::Velocity => chosen.velocity,
            Channel::Index => chosen.index.unwrap_or(usize::MAX),
            Channel::Time => chosen.time.map_or(usize::MAX, |t| t.0),
        };
        let Some(cell) = fields.get(k) else { continue };
        let cell = cell.trim_end_matches('\r');
        let value = if sn.decimal_comma {
            cell.trim().replace(',', ".")
        } else {
            cell.trim().to_string()
        };
        if value.is_empty() || value.trim_matches('"').is_empty() {
            continue;
        }
        let hint = if cell != cell.trim() && value.parse::<f64>().is_ok() {
            " (spaces around the delimiter are not supported)"
        } else {
            ""
        };
        return Ok(format!(
            "line {lineno} (sample {}): '{}' in column '{}' is not a number{hint}; fix or \
             delete that row",
            run.start,
            cell.chars().take(40).collect::<String>(),
            sn.names[k]
        ));
    }
    Ok(generic.replace("missing values", "empty cells"))
}

/// Line `lineno` (1-based) without its line end, read by streaming through the file.
fn nth_line(path: &Path, lineno: usize) -> Result<Option<String>, DmwError> {
    let mut reader = BufReader::new(File::open(path).map_err(|e| read_err(path, e))?);
    let mut buf = Vec::new();
    for _ in 1..lineno {
        buf.clear();
        if reader
            .read_until(b'\n', &mut buf)
            .map_err(|e| read_err(path, e))?
            == 0
        {
            return Ok(None);
        }
    }
    buf.clear();
    if reader
        .read_until(b'\n', &mut buf)
        .map_err(|e| read_err(path, e))?
        == 0
    {
        return Ok(None);
    }
    let line = decode(&buf);
    Ok(Some(line.trim_end_matches(['\n', '\r']).to_string()))
}

/// Blank lines at the end of the file and the number of fields of the last non-blank line.
fn tail(path: &Path, sep: u8) -> Result<(usize, Option<usize>), DmwError> {
    let mut f = File::open(path).map_err(|e| read_err(path, e))?;
    let len = f.metadata().map_err(|e| read_err(path, e))?.len();
    let start = len.saturating_sub(TAIL_BYTES);
    let mut bytes = Vec::new();
    f.seek(SeekFrom::Start(start))
        .and_then(|_| f.read_to_end(&mut bytes))
        .map_err(|e| read_err(path, e))?;
    let text = decode(&bytes);
    let mut lines: Vec<&str> = text.split('\n').collect();
    if text.ends_with('\n') {
        lines.pop();
    }
    let blank = lines
        .iter()
        .rev()
        .take_while(|l| l.trim().is_empty())
        .count();
    let last = lines[..lines.len() - blank].last();
    // A last line that starts before the tail window cannot be judged.
    let judged = start == 0 || lines.len() - blank > 1;
    let fields = last
        .filter(|_| judged)
        .map(|l| l.split(sep as char).count());
    Ok((blank, fields))
}

pub(super) fn write(rec: &LdvRecord, path: &Path) -> Result<(), DmwError> {
    super::check_flat(rec)?;
    write_atomic(path, |file| {
        let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
        let io = |e: std::io::Error| e.to_string();
        for (k, v) in meta_pairs(rec) {
            writeln!(w, "# {k} = {v}").map_err(io)?;
        }
        let vname = match rec.velocity_unit {
            VelocityUnit::Volt => "velocity_V",
            VelocityUnit::MetrePerSecond => "velocity_m_s",
        };
        let idx = rec.index.as_deref();
        write!(w, "time_s,{vname}").map_err(io)?;
        if idx.is_some() {
            write!(w, ",index_V").map_err(io)?;
        }
        writeln!(w).map_err(io)?;
        for (i, v) in rec.velocity.iter().enumerate() {
            write!(w, "{},{}", F(super::sample_time(rec, i)), F(*v)).map_err(io)?;
            if let Some(idx) = idx {
                write!(w, ",{}", F(idx[i])).map_err(io)?;
            }
            writeln!(w).map_err(io)?;
        }
        w.flush().map_err(io)
    })
}
