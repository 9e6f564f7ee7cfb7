//! LDV record readers and writers (docs/dmw.md).
//!
//! The format is detected from the content, never from the extension: `PAR1` → Parquet,
//! `\x89HDF\r\n\x1a\n` (at offset 0 or a power-of-two user-block offset) → HDF5, `ARROW1` or
//! the `FF FF FF FF` continuation marker → Arrow IPC file (Feather v2) or stream
//! ([`arrow`]), `\x93NUMPY` → `.npy`, `PK\x03\x04` → `.npz`, `RIFF…WAVE` → WAV, a `-1`
//! delimiter line followed by a dataset number → universal file (UFF 58/58b), anything else
//! that is text → delimited text (CSV, TSV or semicolon-separated).
//!
//! # Binary channel formats (Arrow IPC, UFF 58, `.npy`, `.npz`, WAV)
//!
//! These share `columns`: each file's channels are described as typed (possibly strided or
//! big-endian) byte ranges over a memory map, or parsed values (UFF ASCII), then chosen by the
//! name rules below and decoded in chunks of 2^16 samples into the shared stream checks.
//! Channel names: Arrow field names; UFF ID line 1 (also `node:direction` of record 6);
//! `.npz` member names; structured `.npy` field names; plain `.npy` columns and WAV channels
//! by position (velocity, index; a 3-column array is time, velocity, index). In UFF, `.npy`
//! and WAV the column options also take a channel number (from 0). Units: Arrow field
//! `units` metadata, UFF record 9 units label; WAV integer PCM is a fraction of full scale
//! (±1 V). Sample rate: Arrow schema metadata, UFF abscissa increment (uneven abscissa →
//! time column), `.npz` 0-d `sample_rate` member, WAV `fmt ` chunk; `.npy` needs a time
//! column or the option. docs/dmw.md has the table.
//!
//! # Columns (text and Parquet) and datasets (HDF5)
//!
//! Names are matched case-insensitively; a unit may follow as `name_unit`, `name (unit)` or
//! `name [unit]`.
//! - time: `time`, `t` in s (`time_s`, `t_s`), ms (`time_ms`) or µs (`time_us`); or a sample
//!   number `sample`, `n`, `sample_index` (then the sample rate comes from the options or the
//!   file's metadata, and `t = n / fs`).
//! - velocity: `velocity`, `voltage`, `U`, `v` — volts unless the unit says m/s
//!   (`velocity_m_s`, `velocity_mps`, `v_m_s`, `velocity (m/s)`); `mV`, `mm/s`, `µm/s` are
//!   scaled to V and m/s. Missing or ambiguous → error listing the columns
//!   (`ReadOptions::velocity_column` chooses).
//! - index (once-per-revolution trigger): `index`, `trigger`, `tacho`, `once_per_rev`, any of
//!   them with `_V`; absent → `None`.
//!
//! Text metadata: `#` lines before the header, `# key = value` or `# key: value`, with keys
//! `sample_rate` (Hz; `fs`, `sampling_rate`; `kHz`, `MHz`, `MS/s` accepted), `sensitivity`
//! (m/s/V; `mm/s/V` accepted), `rpm`, `t0` (s), `layout` (`continuous` or `averaged`) and
//! `velocity_unit`. Parquet carries the same keys as file key-value metadata.
//!
//! # HDF5 layout (written by `artefacts::ldv::write_ldv` and `write_ldv_hdf5_counts`)
//!
//! ```text
//! / (NX_class = NXroot, default = "ldv")
//! /ldv (NX_class = NXdata, signal = "velocity", axes, auxiliary_signals = ["index"])
//!   @sampling_rate  Hz           @t0  s          @layout  "continuous" | "segments" | "averaged"
//!   @sensitivity    m/s per V (optional)         @rpm     (optional)
//!   velocity  float64[n] or [n_segments, n_samples]; @units "V" | "m/s", @long_name
//!   index     float64, same shape (optional); @units "V"
//!   time      float64[n_samples] s (omitted above 10^7 samples and in the counts variant)
//! ```
//! The counts variant stores `velocity`/`index` as int16 with `@scale`, `@offset`
//! (`y = scale·count + offset`), chunked with shuffle + deflate.
//!
//! Reading is more lenient: the datasets may sit in the root group when `/ldv` is missing, may
//! be any integer or float type with optional `scale`/`offset` (or CF `scale_factor`/
//! `add_offset`) attributes, the names follow the column rules above, and `sampling_rate`
//! (or `sample_rate`, `fs`) and `t0` may sit on the velocity dataset or the group. A 2-D
//! velocity dataset is `Layout::Segments`; `@layout = "averaged"` marks an averaged record.
//!
//! # Checks
//!
//! Each is a `DmwError::Record` naming the file and the line (text), row (Parquet) or sample
//! (HDF5): no data or a single sample; a non-numeric cell; a run of empty/NaN/inf values in any
//! used channel (first row and run length); a short last line (a cut file; text only — a
//! cut that leaves every field in place cannot be seen); a time column that does not
//! increase; a step deviating from the mean step (last − first)/(n − 1) by more than 0.1 %
//! (the mean, not the median, so that the time column need not be kept); sample rates from
//! the time column, the file and the option that disagree by more than 1e-6. Truncated or
//! corrupt Parquet/HDF5 is a `DmwError::Read` with the library's message on one line (Parquet
//! pages carry no checksums, so garbled uncompressed data can go unnoticed).
//!
//! # Memory
//!
//! Arrow IPC files, `.npy`, stored `.npz` members, UFF 58b and WAV are memory-mapped and
//! decoded in place (compressed Arrow buffers and deflated members are decompressed first;
//! UFF ASCII is parsed into one vector per channel).
//! Text and Parquet are read part by part (64 MiB of text, or whole row groups of at least
//! 2^22 rows) by polars' eager readers with projection (only the chosen columns are parsed)
//! and consumed batch by batch; HDF5 is read in hyperslabs of 2^20
//! samples. Only the velocity and index channels are materialised (as `Vec<f64>`); the time
//! column is reduced on the fly (first, last, count, extreme steps).

use super::{DmwError, Layout, LdvRecord, VelocityUnit};
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

pub mod arrow;
mod columns;
#[cfg(test)]
mod format_tests;
mod h5;
mod names;
mod npy;
mod parquet;
mod scan;
pub mod series;
mod stream;
#[cfg(test)]
pub(crate) mod tests;
mod text;
mod uff;
mod wav;

use names::{Meta, TimeKind, Unit};
use stream::{BadRun, Channel, Stream, TimeFault, TimeStats};

/// How to read a record; everything defaults to detection from the file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadOptions {
    /// Column/dataset holding the velocity channel; default: detected by name.
    pub velocity_column: Option<String>,
    /// Column/dataset holding the once-per-revolution index; default: detected (absent → none).
    pub index_column: Option<String>,
    /// Time or sample-number column/dataset; default: detected.
    pub time_column: Option<String>,
    /// Sample rate (Hz). Needed when there is no time column and the file does not state it;
    /// when the file has one too, both must agree within 1e-6 relative.
    pub sample_rate: Option<f64>,
    /// Unit of the velocity channel, overriding the header (no scaling is applied then).
    pub velocity_unit: Option<VelocityUnit>,
}

/// The formats an LDV record is written in (and [`read_ldv`] reads).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LdvFormat {
    Csv,
    Parquet,
    Hdf5,
    /// Arrow IPC file (Feather v2) or stream; read only.
    Arrow,
    /// Universal File Format dataset 58 (ASCII) or 58b (binary); read only.
    Uff58,
    /// NumPy `.npy` array; read only.
    Npy,
    /// NumPy `.npz` archive of `.npy` members; read only.
    Npz,
    /// RIFF/WAVE audio (PCM or IEEE float); read only.
    Wav,
}

impl LdvFormat {
    pub fn name(self) -> &'static str {
        match self {
            LdvFormat::Csv => "csv",
            LdvFormat::Parquet => "parquet",
            LdvFormat::Hdf5 => "hdf5",
            LdvFormat::Arrow => "arrow",
            LdvFormat::Uff58 => "uff58",
            LdvFormat::Npy => "npy",
            LdvFormat::Npz => "npz",
            LdvFormat::Wav => "wav",
        }
    }
}

/// Agreement required between two statements of the sample rate.
const RATE_RTOL: f64 = 1e-6;
/// Largest allowed deviation of one time step from the mean step, relative.
const UNIFORM_RTOL: f64 = 1e-3;

/// Detects the format of `path` from its first bytes (see the module docs).
pub fn detect_format(path: &Path) -> Result<LdvFormat, DmwError> {
    let mut f = std::fs::File::open(path).map_err(|e| read_err(path, e))?;
    let len = f.metadata().map_err(|e| read_err(path, e))?.len();
    if len == 0 {
        return Err(record_err(path, "empty file"));
    }
    let mut head = vec![0u8; 4096.min(len as usize)];
    f.read_exact(&mut head).map_err(|e| read_err(path, e))?;
    if head.starts_with(b"PAR1") {
        return Ok(LdvFormat::Parquet);
    }
    if head.starts_with(arrow::FILE_MAGIC) || head.starts_with(arrow::STREAM_MAGIC) {
        return Ok(LdvFormat::Arrow);
    }
    if head.starts_with(crate::formats::npy::MAGIC) {
        return Ok(LdvFormat::Npy);
    }
    if crate::formats::zip::is_zip(&head) {
        return Ok(LdvFormat::Npz);
    }
    if head.len() >= 12 && &head[..4] == b"RIFF" && &head[8..12] == b"WAVE" {
        return Ok(LdvFormat::Wav);
    }
    if head.starts_with(b"FEA1") {
        return Err(read_err(
            path,
            "Feather v1 is not read; write Feather v2 (pyarrow.feather.write_feather, \
             version=2, the default)",
        ));
    }
    if uff::is_uff(&head) {
        return Ok(LdvFormat::Uff58);
    }
    const HDF5_MAGIC: &[u8; 8] = b"\x89HDF\r\n\x1a\n";
    // The HDF5 superblock sits at 0 or after a user block of 512·2^k bytes.
    let mut offset = 0u64;
    while offset + 8 <= len && offset <= 1 << 20 {
        let mut magic = [0u8; 8];
        f.seek(SeekFrom::Start(offset))
            .and_then(|_| f.read_exact(&mut magic))
            .map_err(|e| read_err(path, e))?;
        if &magic == HDF5_MAGIC {
            return Ok(LdvFormat::Hdf5);
        }
        offset = if offset == 0 { 512 } else { offset * 2 };
    }
    if head.contains(&0) {
        return Err(read_err(
            path,
            format!("binary content of no known format; {FORMATS}"),
        ));
    }
    Ok(LdvFormat::Csv)
}

/// The formats, for messages.
pub const FORMATS: &str = "LDV records are read from CSV/TSV text, Parquet, HDF5, Arrow IPC \
     (Feather v2), UFF dataset 58/58b, NumPy .npy/.npz and WAV";

/// Read an LDV record, detecting the format from the content (magic bytes, see the module
/// docs), never from the extension.
pub fn read_ldv(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    if let Some(fs) = opts.sample_rate {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(DmwError::Processing(format!(
                "sample_rate = {fs} Hz: must be a positive number"
            )));
        }
    }
    match detect_format(path)? {
        LdvFormat::Csv => text::read(path, opts),
        LdvFormat::Parquet => parquet::read(path, opts),
        LdvFormat::Hdf5 => h5::read(path, opts),
        LdvFormat::Arrow => arrow::read(path, opts),
        LdvFormat::Uff58 => uff::read(path, opts),
        LdvFormat::Npy => npy::read_npy(path, opts),
        LdvFormat::Npz => npy::read_npz(path, opts),
        LdvFormat::Wav => wav::read(path, opts),
    }
}

/// Write a record as delimited text (for the synthetic generator and round-trip tests),
/// atomically (temporary file in the same directory, then rename): `# key = value` metadata
/// lines, then `time_s,velocity_V|velocity_m_s[,index_V]` with shortest round-trip floats.
/// Text holds one time axis, so `Layout::Segments` needs HDF5. (The HDF5 writer of the
/// layout above lives with the DMW stage, beside the pipeline's other HDF5 outputs.)
pub fn write_ldv_text(rec: &LdvRecord, path: &Path) -> Result<(), DmwError> {
    check_writable(rec)?;
    text::write(rec, path)
}

/// Write a record as Parquet: the Float64 columns of [`write_ldv_text`] plus key-value
/// metadata, atomically. `Layout::Segments` needs HDF5.
pub fn write_ldv_parquet(rec: &LdvRecord, path: &Path) -> Result<(), DmwError> {
    check_writable(rec)?;
    parquet::write(rec, path)
}

/// What a writer needs to be able to write something the readers accept again.
pub fn check_writable(rec: &LdvRecord) -> Result<(), DmwError> {
    let n = rec.velocity.len();
    let bad = |what: String| Err(DmwError::Processing(format!("cannot write record: {what}")));
    if !(rec.sample_rate.is_finite() && rec.sample_rate > 0.0) {
        return bad(format!("sample_rate = {} Hz", rec.sample_rate));
    }
    if !rec.t0.is_finite() {
        return bad(format!("t0 = {}", rec.t0));
    }
    if n < 2 {
        return bad(format!("{n} samples (at least 2 are needed)"));
    }
    if let Some(idx) = &rec.index {
        if idx.len() != n {
            return bad(format!("index has {} samples, velocity {n}", idx.len()));
        }
    }
    if let Layout::Segments {
        n_segments,
        segment_len,
    } = rec.layout
    {
        if n_segments.checked_mul(segment_len) != Some(n) {
            return bad(format!(
                "{n_segments} segments × {segment_len} samples ≠ {n} samples"
            ));
        }
    }
    Ok(())
}

// ---- errors ----

fn read_err(path: &Path, e: impl std::fmt::Display) -> DmwError {
    DmwError::Read {
        path: path.to_path_buf(),
        message: one_line(&e.to_string()),
    }
}

fn record_err(path: &Path, message: impl Into<String>) -> DmwError {
    DmwError::Record {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Writers have no error variant of their own; `Processing` carries the path in the text.
pub fn write_err(path: &Path, e: impl std::fmt::Display) -> DmwError {
    DmwError::Processing(format!(
        "writing {}: {}",
        path.display(),
        one_line(&e.to_string())
    ))
}

/// First non-empty line of a library message, at most ~300 characters: polars and HDF5 append
/// multi-line hints that would break the one-line error contract.
fn one_line(message: &str) -> String {
    let line = message
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("unknown error");
    let mut out: String = line.chars().take(300).collect();
    if out.len() < line.len() {
        out.push('…');
    }
    out
}

/// Runs a library call that might panic on corrupt input and turns the panic into an error.
fn no_panic<T>(
    path: &Path,
    what: &str,
    f: impl FnOnce() -> Result<T, DmwError>,
) -> Result<T, DmwError> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| payload.downcast_ref::<&str>().copied())
                .unwrap_or("internal error");
            Err(read_err(
                path,
                format!(
                    "{what} failed on this file ({}); is it corrupt?",
                    one_line(msg)
                ),
            ))
        }
    }
}

/// Atomic write: `<name>.tmp-<pid>` in the same directory, then rename.
fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> Result<(), String>,
) -> Result<(), DmwError> {
    let tmp = temp_path(path);
    let result = std::fs::File::create(&tmp)
        .map_err(|e| e.to_string())
        .and_then(|mut f| {
            write(&mut f)?;
            f.sync_all().map_err(|e| e.to_string())
        })
        .and_then(|_| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(write_err(path, e));
    }
    Ok(())
}

fn temp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(format!(".tmp-{}", std::process::id()));
    path.with_file_name(name)
}

// ---- what the readers share after streaming ----

/// Unit of the velocity channel, the factor applied while reading, and where it came from.
struct VelUnit {
    pub unit: VelocityUnit,
    pub scale: f64,
    pub source: &'static str,
}

/// Option > name/`units` attribute > metadata key > volts (the decoder output, §3.1).
fn velocity_unit(
    path: &Path,
    opts: &ReadOptions,
    from_name: Option<Unit>,
    unknown: Option<&str>,
    from_meta: Option<Unit>,
    name_source: &'static str,
) -> Result<VelUnit, DmwError> {
    if let Some(unit) = opts.velocity_unit {
        return Ok(VelUnit {
            unit,
            scale: 1.0,
            source: "option",
        });
    }
    if let Some(u) = unknown {
        return Err(record_err(
            path,
            format!(
                "velocity unit '{u}' is not V, mV, m/s, mm/s or µm/s; set the velocity_unit \
                 option"
            ),
        ));
    }
    let (unit, source) = match (from_name, from_meta) {
        (Some(u), _) => (u, name_source),
        (None, Some(u)) => (u, "file metadata"),
        (None, None) => (Unit::Volt(1.0), "default (no unit given)"),
    };
    Ok(match unit {
        Unit::MetrePerSecond(f) => VelUnit {
            unit: VelocityUnit::MetrePerSecond,
            scale: f,
            source,
        },
        Unit::Volt(f) => VelUnit {
            unit: VelocityUnit::Volt,
            scale: f,
            source,
        },
        other => {
            return Err(record_err(
                path,
                format!(
                    "velocity unit {} is not a voltage or velocity; set the velocity_unit option",
                    other.describe()
                ),
            ))
        }
    })
}

/// Everything a format reader hands to [`finish`].
struct Raw {
    pub format: &'static str,
    pub stream: Stream,
    pub velocity_name: String,
    pub index_name: Option<String>,
    pub time: Option<(String, TimeKind)>,
    pub unit: VelUnit,
    pub layout: Layout,
    pub meta: Meta,
    /// How the file states metadata, for messages ("a '# sample_rate = …' line").
    pub meta_hint: &'static str,
    pub provenance: Vec<(String, String)>,
}

/// Message for the first run of missing/non-finite samples.
fn run_message(raw: &Raw, run: &BadRun, locate: &dyn Fn(usize) -> String) -> String {
    let names: Vec<&str> = run
        .channels
        .iter()
        .map(|c| match c {
            Channel::Velocity => raw.velocity_name.as_str(),
            Channel::Index => raw.index_name.as_deref().unwrap_or("index"),
            Channel::Time => raw.time.as_ref().map_or("time", |t| t.0.as_str()),
        })
        .collect();
    let what = if run.missing {
        "missing values"
    } else {
        "NaN/inf values"
    };
    let tail = if run.ended {
        ""
    } else {
        ", up to the end of the record"
    };
    format!(
        "{} has {what} from {} on, a run of {} sample{}{tail}; the record must be gap-free: \
         cut the record before the gap or repair it",
        names.join(" and "),
        locate(run.start),
        run.len,
        if run.len == 1 { "" } else { "s" }
    )
}

fn time_fault_message(name: &str, fault: TimeFault, locate: &dyn Fn(usize) -> String) -> String {
    match fault {
        TimeFault::NonMonotonic { row, prev, cur } => format!(
            "time column '{name}' does not increase at {}: {cur} follows {prev}; sort the \
             record or fix the time column",
            locate(row)
        ),
        TimeFault::NonFinite { row } => format!(
            "time column '{name}' has a NaN/inf value at {}; fix the time column",
            locate(row)
        ),
    }
}

fn agree(a: f64, b: f64) -> bool {
    (a - b).abs() <= RATE_RTOL * a.abs().max(b.abs())
}

fn positive(path: &Path, key: &str, v: Option<f64>) -> Result<Option<f64>, DmwError> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(record_err(
            path,
            format!("{key} = {x} in the file: must be a positive number"),
        )),
        other => Ok(other),
    }
}

/// Checks the stream's outcome (bad runs, time faults, length, uniform sampling), resolves
/// the sample rate and assembles the record. Bad runs are reported by the caller when it can
/// say more (the text reader names the cell); otherwise here.
fn finish(
    path: &Path,
    mut raw: Raw,
    opts: &ReadOptions,
    locate: &dyn Fn(usize) -> String,
) -> Result<LdvRecord, DmwError> {
    check_stream(path, &raw, locate)?;
    let meta = &raw.meta;
    let stated = positive(path, "sample_rate", meta.sample_rate)?;
    let sensitivity = positive(path, "sensitivity", meta.sensitivity)?;
    let rpm = positive(path, "rpm", meta.rpm)?;
    if let Some(t0) = meta.t0.filter(|t| !t.is_finite()) {
        return Err(record_err(path, format!("t0 = {t0} in the file")));
    }
    let (sample_rate, t0, rate_source) = resolve_rate(path, &raw, opts, stated, locate)?;
    let provenance = record_provenance(&mut raw, rate_source);
    Ok(LdvRecord {
        source: path.to_path_buf(),
        format: raw.format,
        sample_rate,
        t0,
        velocity: raw.stream.velocity,
        velocity_unit: raw.unit.unit,
        index: raw.stream.index,
        layout: raw.layout,
        sensitivity,
        rpm,
        provenance,
    })
}

/// The stream's own faults, in the order they are reported: a bad run, a time fault, fewer
/// than 2 samples.
fn check_stream(path: &Path, raw: &Raw, locate: &dyn Fn(usize) -> String) -> Result<(), DmwError> {
    if let Some(run) = &raw.stream.run {
        return Err(record_err(path, run_message(raw, run, locate)));
    }
    let time_name = raw.time.as_ref().map(|t| t.0.clone()).unwrap_or_default();
    if let Some(fault) = raw.stream.time.as_ref().and_then(|t| t.fault) {
        return Err(record_err(
            path,
            time_fault_message(&time_name, fault, locate),
        ));
    }
    let n = raw.stream.velocity.len();
    if n == 0 {
        return Err(record_err(path, "no data rows"));
    }
    if n < 2 {
        return Err(record_err(path, "only 1 sample; a record needs at least 2"));
    }
    Ok(())
}

/// The rate the option or the file states, which must agree when both exist.
fn stated_rate(
    path: &Path,
    opts: &ReadOptions,
    stated: Option<f64>,
) -> Result<Option<(f64, &'static str)>, DmwError> {
    match (opts.sample_rate, stated) {
        (Some(o), Some(s)) if !agree(o, s) => Err(record_err(
            path,
            format!(
                "the sample_rate option ({o} Hz) and the file's sample rate ({s} Hz) \
                 disagree; drop the option or fix the file"
            ),
        )),
        (Some(o), _) => Ok(Some((o, "option"))),
        (None, Some(s)) => Ok(Some((s, "file metadata"))),
        (None, None) => Ok(None),
    }
}

/// (sample rate, t0, source of the rate): from the time column when there is one, else the
/// rate the option or the file states.
fn resolve_rate(
    path: &Path,
    raw: &Raw,
    opts: &ReadOptions,
    stated: Option<f64>,
    locate: &dyn Fn(usize) -> String,
) -> Result<(f64, f64, &'static str), DmwError> {
    let time_stats = raw.stream.time.as_ref().and_then(|t| t.stats());
    match (&raw.time, time_stats) {
        (Some((name, kind)), Some(st)) => {
            rate_from_time_column(path, raw, (name, *kind), &st, opts, stated, locate)
        }
        _ => {
            let Some((fs, source)) = stated_rate(path, opts, stated)? else {
                return Err(record_err(
                    path,
                    format!(
                        "no time column and no sample rate: set the sample_rate option (Hz) or \
                         add {}",
                        raw.meta_hint
                    ),
                ));
            };
            Ok((fs, raw.meta.t0.unwrap_or(0.0), source))
        }
    }
}

/// The rate and t0 a time column gives: it must be uniformly sampled; in seconds it must
/// agree with any stated rate, as sample numbers it needs one.
fn rate_from_time_column(
    path: &Path,
    raw: &Raw,
    (name, kind): (&str, TimeKind),
    st: &TimeStats,
    opts: &ReadOptions,
    stated: Option<f64>,
    locate: &dyn Fn(usize) -> String,
) -> Result<(f64, f64, &'static str), DmwError> {
    // Steps are reported in the column's own unit.
    let unit = match &kind {
        TimeKind::Seconds(f) if *f == 1e-3 => "ms",
        TimeKind::Seconds(f) if *f == 1e-6 => "µs",
        TimeKind::Seconds(f) if *f == 1e-9 => "ns",
        TimeKind::Seconds(_) => "s",
        TimeKind::Samples => "samples",
    };
    let (row, dt) = st.worst;
    if (dt - st.mean_dt).abs() > UNIFORM_RTOL * st.mean_dt {
        return Err(record_err(
            path,
            format!(
                "time column '{name}' is not uniformly sampled: the step to {} is {dt} \
                 {unit}, the mean step {} {unit} (tolerance 0.1 %); resample the record \
                 to a uniform rate",
                locate(row),
                st.mean_dt
            ),
        ));
    }
    match kind {
        TimeKind::Seconds(f) => {
            let fs = 1.0 / (st.mean_dt * f);
            for (other, what) in [
                (opts.sample_rate, "the sample_rate option"),
                (stated, "the file's sample rate"),
            ] {
                if let Some(o) = other.filter(|o| !agree(*o, fs)) {
                    return Err(record_err(
                        path,
                        format!(
                            "sample rate from time column '{name}' ({fs} Hz) and \
                             {what} ({o} Hz) disagree; fix one of them"
                        ),
                    ));
                }
            }
            Ok((fs, st.first * f, "time column"))
        }
        TimeKind::Samples => {
            let Some((fs_count, source)) = stated_rate(path, opts, stated)? else {
                return Err(record_err(
                    path,
                    format!(
                        "'{name}' counts samples but no sample rate is given: set the \
                         sample_rate option (Hz) or add {}",
                        raw.meta_hint
                    ),
                ));
            };
            Ok((fs_count / st.mean_dt, st.first / fs_count, source))
        }
    }
}

/// The record's provenance: how it was read, then the reader's own entries, then the file's
/// other metadata.
fn record_provenance(raw: &mut Raw, rate_source: &str) -> Vec<(String, String)> {
    let mut provenance = vec![
        ("format".to_string(), raw.format.to_string()),
        ("velocity".to_string(), raw.velocity_name.clone()),
        (
            "velocity_unit".to_string(),
            raw.unit.unit.symbol().to_string(),
        ),
        (
            "velocity_unit_source".to_string(),
            raw.unit.source.to_string(),
        ),
    ];
    if raw.unit.scale != 1.0 {
        provenance.push(("velocity_scale".to_string(), raw.unit.scale.to_string()));
    }
    provenance.push((
        "index".to_string(),
        raw.index_name.clone().unwrap_or_else(|| "none".to_string()),
    ));
    provenance.push((
        "time".to_string(),
        match &raw.time {
            Some((name, TimeKind::Seconds(f))) if *f != 1.0 => format!("{name} (×{f} s)"),
            Some((name, TimeKind::Seconds(_))) => format!("{name} (s)"),
            Some((name, TimeKind::Samples)) => format!("{name} (sample number)"),
            None => "none".to_string(),
        },
    ));
    provenance.push(("sample_rate_source".to_string(), rate_source.to_string()));
    provenance.append(&mut raw.provenance);
    for (k, v) in &raw.meta.other {
        provenance.push((format!("meta.{k}"), v.clone()));
    }
    provenance
}

/// `layout` metadata of the single-axis formats.
fn flat_layout(path: &Path, meta: &Meta) -> Result<Layout, DmwError> {
    match meta.layout.as_deref() {
        None | Some("continuous") => Ok(Layout::Continuous),
        Some("averaged") => Ok(Layout::Averaged),
        Some(other) => Err(record_err(
            path,
            format!(
                "layout = '{other}': a text or Parquet record is 'continuous' or 'averaged' \
                 (segment stacks need HDF5 with a 2-D velocity dataset)"
            ),
        )),
    }
}

/// The metadata the writers store, as (key, value) text.
fn meta_pairs(rec: &LdvRecord) -> Vec<(String, String)> {
    let mut kv = vec![
        ("sample_rate".to_string(), fmt_f64(rec.sample_rate)),
        ("t0".to_string(), fmt_f64(rec.t0)),
    ];
    if let Some(s) = rec.sensitivity {
        kv.push(("sensitivity".to_string(), fmt_f64(s)));
    }
    if let Some(r) = rec.rpm {
        kv.push(("rpm".to_string(), fmt_f64(r)));
    }
    kv.push(("layout".to_string(), layout_name(&rec.layout).to_string()));
    kv
}

/// The `layout` metadata value of a layout.
pub fn layout_name(layout: &Layout) -> &'static str {
    match layout {
        Layout::Continuous => "continuous",
        Layout::Segments { .. } => "segments",
        Layout::Averaged => "averaged",
    }
}

/// Shortest text that parses back to the same f64, in exponent form outside 1e-4..1e15 so
/// that tiny values do not expand to hundreds of digits. Formats without allocating.
struct F(pub f64);

impl std::fmt::Display for F {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let a = self.0.abs();
        if self.0 == 0.0 || (1e-4..1e15).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

fn fmt_f64(x: f64) -> String {
    F(x).to_string()
}

/// Text and Parquet hold one time axis: a stack of segments needs HDF5.
fn check_flat(rec: &LdvRecord) -> Result<(), DmwError> {
    if let Layout::Segments { .. } = rec.layout {
        return Err(DmwError::Processing(format!(
            "cannot write {} as text or Parquet: a segment stack needs HDF5",
            rec.source.display()
        )));
    }
    Ok(())
}

/// Time of sample `i` as the writers store it.
pub fn sample_time(rec: &LdvRecord, i: usize) -> f64 {
    rec.t0 + i as f64 / rec.sample_rate
}
