//! HDF5 records (layout in the module docs of `io`): read in hyperslabs of [`CHUNK`] samples
//! converted to f64 as they come. (Writing them is the DMW stage's, through the pipeline's
//! HDF5 writer.)

use super::names::{self, parse_unit, Meta, TimeKind, Unit};
use super::stream::{Col, Stream, TimeAcc};
use super::{finish, no_panic, read_err, record_err, velocity_unit, Raw, ReadOptions, VelUnit, F};
use crate::dmw::{DmwError, Layout, LdvRecord, VelocityUnit};
use crate::formats::isolated;
use hdf5::types::{FixedAscii, FixedUnicode, TypeDescriptor, VarLenAscii, VarLenUnicode};
use ndarray::s;
use std::path::Path;

/// Samples per hyperslab read: peak memory is the output plus one chunk per channel.
const CHUNK: usize = 1 << 20;

fn h5err(path: &Path, e: hdf5::Error) -> DmwError {
    read_err(path, format!("HDF5: {e}"))
}

/// A string attribute in any of the encodings h5py and other writers use.
pub(super) fn attr_string(loc: &hdf5::Location, name: &str) -> Option<String> {
    let a = loc.attr(name).ok()?;
    if let Ok(s) = a.read_scalar::<VarLenUnicode>() {
        return Some(s.as_str().to_string());
    }
    if let Ok(s) = a.read_scalar::<VarLenAscii>() {
        return Some(s.as_str().to_string());
    }
    if let Ok(s) = a.read_scalar::<FixedAscii<256>>() {
        return Some(s.as_str().to_string());
    }
    if let Ok(s) = a.read_scalar::<FixedUnicode<256>>() {
        return Some(s.as_str().to_string());
    }
    None
}

/// A numeric attribute, scalar or a one-element array.
pub(super) fn attr_number(loc: &hdf5::Location, name: &str) -> Option<f64> {
    let a = loc.attr(name).ok()?;
    if let Ok(x) = a.read_scalar::<f64>() {
        return Some(x);
    }
    // A corrupt dataspace may declare millions of elements: `read_raw` would allocate them
    // all before the length check below could refuse them.
    if a.size() != 1 {
        return None;
    }
    match a.read_raw::<f64>() {
        Ok(v) if v.len() == 1 => Some(v[0]),
        _ => None,
    }
}

/// Attribute as text (numbers in round-trip form), for `Meta::set`.
fn attr_text(loc: &hdf5::Location, name: &str) -> Option<String> {
    if !loc.attr_names().ok()?.iter().any(|n| n == name) {
        return None;
    }
    attr_number(loc, name)
        .map(|x| F(x).to_string())
        .or_else(|| attr_string(loc, name))
}

/// `y = scale·stored + offset` (also CF `scale_factor`/`add_offset`).
fn scale_offset(ds: &hdf5::Dataset) -> (f64, f64) {
    let get = |a: &str, b: &str| attr_number(ds, a).or_else(|| attr_number(ds, b));
    (
        get("scale", "scale_factor").unwrap_or(1.0),
        get("offset", "add_offset").unwrap_or(0.0),
    )
}

fn numeric(path: &Path, ds: &hdf5::Dataset, name: &str) -> Result<(), DmwError> {
    let td = ds
        .dtype()
        .and_then(|t| t.to_descriptor())
        .map_err(|e| h5err(path, e))?;
    match td {
        TypeDescriptor::Integer(_)
        | TypeDescriptor::Unsigned(_)
        | TypeDescriptor::Float(_)
        | TypeDescriptor::Boolean => Ok(()),
        other => Err(record_err(
            path,
            format!("dataset '{name}' holds {other:?}, not numbers"),
        )),
    }
}

/// Reads `ds[a..b]` (1-D) or rows `a..b` (2-D) as f64 with scale and offset applied into
/// `out` (cleared first). The caller reuses `out` across slices: a fresh 8 MB vector per
/// slice cost a third of the read time in page faults.
fn read_part(
    path: &Path,
    ds: &hdf5::Dataset,
    so: (f64, f64),
    a: usize,
    b: usize,
    out: &mut Vec<f64>,
) -> Result<(), DmwError> {
    out.clear();
    let (scale, offset) = so;
    // int16 ADC counts (the common digitiser format, and the shipped sample): read them as
    // stored and convert here; HDF5's soft conversion to double is slower.
    let is_i16 = matches!(
        ds.dtype().and_then(|t| t.to_descriptor()),
        Ok(TypeDescriptor::Integer(hdf5::types::IntSize::U2))
    );
    if is_i16 && ds.ndim() == 1 {
        let raw = ds
            .read_slice_1d::<i16, _>(s![a..b])
            .map_err(|e| h5err(path, e))?;
        out.extend(raw.iter().map(|&c| scale * f64::from(c) + offset));
        return Ok(());
    }
    if ds.ndim() == 1 {
        let x = ds
            .read_slice_1d::<f64, _>(s![a..b])
            .map_err(|e| h5err(path, e))?;
        out.extend(x.iter());
    } else {
        let x = ds
            .read_slice_2d::<f64, _>(s![a..b, ..])
            .map_err(|e| h5err(path, e))?;
        out.extend(x.iter());
    }
    if so != (1.0, 0.0) {
        for x in out.iter_mut() {
            *x = scale * *x + offset;
        }
    }
    Ok(())
}

/// Reads in a child process (`formats::isolated`): libhdf5 1.10 crashes or spins on some
/// corrupt files, and that must be an error naming the file, not the end of hdi.
pub(super) fn read(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let reply = isolated::read_hdf5(
        path,
        || no_panic(path, "the HDF5 reader", || read_inner(path, opts)),
        send,
        |r| receive(path, r),
    );
    reply.unwrap_or_else(|failure| {
        Err(read_err(
            path,
            format!("{failure} on this HDF5 file; is it corrupt?"),
        ))
    })
}

/// The child's reply: tag 0 and the record, or an error's kind and text (the path is the
/// parent's own).
fn send(reply: Result<LdvRecord, DmwError>, w: &mut isolated::Writer) -> std::io::Result<()> {
    let rec = match reply {
        Ok(rec) => rec,
        Err(e) => {
            let (tag, text) = match e {
                DmwError::Read { message, .. } => (1, message),
                DmwError::Record { message, .. } => (2, message),
                DmwError::Processing(m) => (3, m),
                other => (3, other.to_string()),
            };
            w.u64(tag)?;
            return w.str(&text);
        }
    };
    let LdvRecord {
        velocity, index, ..
    } = rec;
    w.u64(0)?;
    w.f64(rec.sample_rate)?;
    w.f64(rec.t0)?;
    // Each channel is freed once sent (the child's memory falls as the parent's grows).
    w.f64s(&velocity)?;
    drop(velocity);
    w.bool(rec.velocity_unit == VelocityUnit::Volt)?;
    w.bool(index.is_some())?;
    w.f64s(index.as_deref().unwrap_or_default())?;
    drop(index);
    let (kind, n, len) = match rec.layout {
        Layout::Continuous => (0, 0, 0),
        Layout::Segments {
            n_segments,
            segment_len,
        } => (1, n_segments, segment_len),
        Layout::Averaged => (2, 0, 0),
    };
    for x in [kind, n, len] {
        w.u64(x as u64)?;
    }
    w.opt_f64(rec.sensitivity)?;
    w.opt_f64(rec.rpm)?;
    w.u64(rec.provenance.len() as u64)?;
    for (k, v) in &rec.provenance {
        w.str(k)?;
        w.str(v)?;
    }
    Ok(())
}

fn receive(path: &Path, r: &mut isolated::Reader) -> std::io::Result<Result<LdvRecord, DmwError>> {
    let bad = || std::io::Error::from(std::io::ErrorKind::InvalidData);
    match r.u64()? {
        0 => {}
        1 => return Ok(Err(read_err(path, r.str()?))),
        2 => return Ok(Err(record_err(path, r.str()?))),
        3 => return Ok(Err(DmwError::Processing(r.str()?))),
        _ => return Err(bad()),
    }
    let sample_rate = r.f64()?;
    let t0 = r.f64()?;
    let velocity = r.f64s()?;
    let velocity_unit = if r.bool()? {
        VelocityUnit::Volt
    } else {
        VelocityUnit::MetrePerSecond
    };
    let has_index = r.bool()?;
    let index = r.f64s()?;
    let layout = match (r.u64()?, r.usize()?, r.usize()?) {
        (0, _, _) => Layout::Continuous,
        (1, n_segments, segment_len) => Layout::Segments {
            n_segments,
            segment_len,
        },
        (2, _, _) => Layout::Averaged,
        _ => return Err(bad()),
    };
    let sensitivity = r.opt_f64()?;
    let rpm = r.opt_f64()?;
    let mut provenance = Vec::new();
    for _ in 0..r.u64()? {
        let k = r.str()?;
        provenance.push((k, r.str()?));
    }
    Ok(Ok(LdvRecord {
        source: path.to_path_buf(),
        format: "hdf5",
        sample_rate,
        t0,
        velocity,
        velocity_unit,
        index: has_index.then_some(index),
        layout,
        sensitivity,
        rpm,
        provenance,
    }))
}

fn read_inner(path: &Path, opts: &ReadOptions) -> Result<LdvRecord, DmwError> {
    let file = hdf5::File::open(path).map_err(|e| h5err(path, e))?;
    let root = file.as_group().map_err(|e| h5err(path, e))?;
    let (group, gname) = record_group(path, &root)?;
    let names: Vec<String> = group
        .member_names()
        .map_err(|e| h5err(path, e))?
        .into_iter()
        .filter(|n| group.dataset(n).is_ok())
        .collect();
    let chosen = names::choose(&names, opts, "dataset")
        .map_err(|m| record_err(path, format!("{m} (in {gname})")))?;
    let open = |k: usize| -> Result<hdf5::Dataset, DmwError> {
        let ds = group.dataset(&names[k]).map_err(|e| h5err(path, e))?;
        numeric(path, &ds, &names[k])?;
        Ok(ds)
    };
    let vds = open(chosen.velocity)?;
    let ids = chosen.index.map(open).transpose()?;
    let tds = chosen.time.map(|(k, _)| open(k)).transpose()?;

    let meta = read_meta(path, &root, &group, gname, &vds)?;
    let unit = resolve_unit(path, opts, &vds, &chosen, &meta)?;

    let shape = vds.shape();
    let vname = names[chosen.velocity].clone();
    let averaged = meta.layout.as_deref() == Some("averaged");
    let (layout, n_rows, row_len) = velocity_layout(path, &shape, averaged, &vname)?;
    let samples_per_axis = if shape.len() == 1 { n_rows } else { row_len };
    if let (Some(ids), Some(k)) = (&ids, chosen.index) {
        if ids.shape() != shape {
            return Err(record_err(
                path,
                format!(
                    "index dataset '{}' has shape {:?}, velocity {shape:?}",
                    names[k],
                    ids.shape()
                ),
            ));
        }
    }
    let time = chosen.time.map(|(k, kind)| (names[k].clone(), kind));
    let time = time_axis(path, tds.as_ref(), time, samples_per_axis)?;

    let vso = scale_offset(&vds);
    let rows = RowShape {
        n_rows,
        row_len,
        segmented: shape.len() == 2,
    };
    let stream = stream_datasets(
        path,
        (&vds, vso),
        ids.as_ref(),
        tds.as_ref(),
        unit.scale,
        rows,
    )?;
    let mut provenance = vec![("group".to_string(), gname.to_string())];
    if vso != (1.0, 0.0) {
        provenance.push((
            "velocity_scale_offset".to_string(),
            format!("{} {}", vso.0, vso.1),
        ));
    }
    let raw = Raw {
        format: "hdf5",
        stream,
        velocity_name: vname,
        index_name: chosen.index.map(|k| names[k].clone()),
        time,
        unit,
        layout,
        meta,
        meta_hint: "a 'sampling_rate' attribute",
        provenance,
    };
    let segmented = rows.segmented;
    let locate = move |row: usize| {
        if segmented {
            format!("segment {}, sample {}", row / row_len, row % row_len)
        } else {
            format!("sample {row}")
        }
    };
    finish(path, raw, opts, &locate)
}

/// The group holding the record: `/ldv` if the file has one, else the root.
fn record_group(path: &Path, root: &hdf5::Group) -> Result<(hdf5::Group, &'static str), DmwError> {
    if root.link_exists("ldv") {
        let g = root.group("ldv").map_err(|_| {
            record_err(
                path,
                "'/ldv' is not a group; expected the layout of the docs",
            )
        })?;
        Ok((g, "/ldv"))
    } else {
        Ok((root.clone(), "/"))
    }
}

/// Metadata attributes: root, then group, then the velocity dataset (the most specific wins).
fn read_meta(
    path: &Path,
    root: &hdf5::Group,
    group: &hdf5::Group,
    gname: &str,
    vds: &hdf5::Dataset,
) -> Result<Meta, DmwError> {
    let mut meta = Meta::default();
    let mut sources: Vec<&hdf5::Location> = vec![];
    if gname != "/" {
        sources.push(root);
    }
    sources.push(group);
    sources.push(vds);
    for loc in sources {
        for key in [
            "sampling_rate",
            "sample_rate",
            "fs",
            "t0",
            "sensitivity",
            "rpm",
            "layout",
        ] {
            if let Some(v) = attr_text(loc, key) {
                meta.set(key, &v)
                    .map_err(|m| record_err(path, format!("attribute {m}")))?;
            }
        }
    }
    Ok(meta)
}

/// The velocity unit: the dataset's `units` attribute, else its name, then the options and
/// metadata as `velocity_unit` ranks them.
fn resolve_unit(
    path: &Path,
    opts: &ReadOptions,
    vds: &hdf5::Dataset,
    chosen: &names::Chosen,
    meta: &Meta,
) -> Result<VelUnit, DmwError> {
    let units = attr_string(vds, "units");
    let (name_unit, unknown) = match &units {
        Some(u) => match parse_unit(u) {
            Some(unit) => (Some(unit), None),
            None => (None, Some(u.clone())),
        },
        None => (chosen.velocity_unit, chosen.velocity_unknown_unit.clone()),
    };
    let unit_source = if units.is_some() {
        "units attribute"
    } else {
        "dataset name"
    };
    velocity_unit(
        path,
        opts,
        name_unit,
        unknown.as_deref(),
        meta.velocity_unit,
        unit_source,
    )
}

/// (layout, rows, samples per row) of a velocity dataset of shape [n] or [segments, n].
fn velocity_layout(
    path: &Path,
    shape: &[usize],
    averaged: bool,
    vname: &str,
) -> Result<(Layout, usize, usize), DmwError> {
    Ok(match shape {
        [n] => (
            if averaged {
                Layout::Averaged
            } else {
                Layout::Continuous
            },
            *n,
            1,
        ),
        [1, n] if averaged => (Layout::Averaged, 1, *n),
        [s, n] => (
            Layout::Segments {
                n_segments: *s,
                segment_len: *n,
            },
            *s,
            *n,
        ),
        _ => {
            return Err(record_err(
                path,
                format!("dataset '{vname}' has shape {shape:?}; expected [n] or [segments, n]"),
            ))
        }
    })
}

/// Checks the time dataset's length and takes its kind from its `units` attribute.
fn time_axis(
    path: &Path,
    tds: Option<&hdf5::Dataset>,
    mut time: Option<(String, TimeKind)>,
    samples_per_axis: usize,
) -> Result<Option<(String, TimeKind)>, DmwError> {
    if let (Some(tds), Some((tname, kind))) = (tds, &mut time) {
        if tds.shape() != [samples_per_axis] {
            return Err(record_err(
                path,
                format!(
                    "time dataset '{tname}' has shape {:?}; expected [{samples_per_axis}]",
                    tds.shape()
                ),
            ));
        }
        match attr_string(tds, "units").as_deref().map(parse_unit) {
            Some(Some(Unit::Second(f))) => *kind = TimeKind::Seconds(f),
            Some(Some(Unit::Count)) => *kind = TimeKind::Samples,
            _ => {}
        }
    }
    Ok(time)
}

/// Rows of the velocity dataset (1-D: samples; 2-D: segments) and their length.
#[derive(Clone, Copy)]
struct RowShape {
    n_rows: usize,
    row_len: usize,
    segmented: bool,
}

/// Streams velocity, index and (1-D) time in hyperslabs of about [`CHUNK`] samples; a
/// segmented record's time axis is shared by all segments and read once.
fn stream_datasets(
    path: &Path,
    (vds, vso): (&hdf5::Dataset, (f64, f64)),
    ids: Option<&hdf5::Dataset>,
    tds: Option<&hdf5::Dataset>,
    vel_scale: f64,
    rows: RowShape,
) -> Result<Stream, DmwError> {
    let RowShape {
        n_rows,
        row_len,
        segmented,
    } = rows;
    let iso = ids.map(scale_offset).unwrap_or((1.0, 0.0));
    let tso = tds.map(scale_offset).unwrap_or((1.0, 0.0));
    let total = n_rows * row_len;
    let mut stream = Stream::new(vel_scale, ids.is_some(), tds.is_some() && !segmented, total);
    // Rows (1-D: samples; 2-D: segments) per hyperslab.
    let step = (CHUNK / row_len.max(1)).max(1);
    let mut a = 0;
    let (mut v, mut i, mut t) = (Vec::new(), Vec::new(), Vec::new());
    while a < n_rows && !stream.done() {
        let b = (a + step).min(n_rows);
        read_part(path, vds, vso, a, b, &mut v)?;
        if let Some(d) = ids {
            read_part(path, d, iso, a, b, &mut i)?;
        }
        let has_t = match tds {
            Some(d) if !segmented => {
                read_part(path, d, tso, a, b, &mut t)?;
                true
            }
            _ => false,
        };
        stream.push(
            has_t.then(|| Col::new(&t)),
            Col::new(&v),
            ids.map(|_| Col::new(&i)),
        );
        a = b;
    }
    if let (true, Some(d)) = (segmented, tds) {
        // One time axis shared by all segments.
        let mut acc = TimeAcc::default();
        let mut a = 0;
        let mut buf = Vec::new();
        while a < row_len && acc.fault.is_none() {
            let b = (a + CHUNK).min(row_len);
            read_part(path, d, tso, a, b, &mut buf)?;
            acc.push_slice(a, &buf);
            a = b;
        }
        stream.time = Some(acc);
    }
    Ok(stream)
}
