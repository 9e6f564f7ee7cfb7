//! A time series for `[analysis]` and `hdi analyze` (docs/analysis.md): from hdi's own HDF5
//! artefacts (a slider case's heave history, a DMW track) or any HDF5 file, with its units and
//! sample rate, or from a table (CSV/TSV, Parquet, Arrow IPC, `.npy`) through
//! `dmw::io::series`.

use crate::dmw::DmwError;
use crate::error::{Error, Result};
use std::path::Path;

/// A series read from a file, in SI units.
pub struct Series {
    pub x: Vec<f64>,
    pub v: Option<Vec<f64>>,
    pub sample_rate: f64,
    /// Time of the first sample kept, s.
    pub t0: f64,
    pub unit: String,
    pub velocity_unit: String,
    /// The column or dataset read.
    pub name: String,
    /// "hdf5", "csv", "parquet", "arrow-file", "arrow-stream", "npy".
    pub format: String,
    /// Where the sample rate came from ("time column `time_s`", "--sample-rate", …).
    pub rate_source: String,
}

/// A failure reading `what` of the HDF5 series file `path` (the reader runs in a child
/// process, so only text comes back: the error is the series reader's text, as the table
/// readers' are).
fn h5err(path: &Path, what: &str, e: impl std::fmt::Display) -> DmwError {
    DmwError::Read {
        path: path.to_path_buf(),
        message: format!("{what}: {e}"),
    }
}

/// A string attribute (`units`, `unit`, `CLASS`) in any encoding.
fn attr_string(loc: &hdf5::Location, name: &str) -> Option<String> {
    crate::dmw::io::series::hdf5_attr_string(loc, name)
}

fn read_units(ds: &hdf5::Dataset) -> String {
    attr_string(ds, "units")
        .or_else(|| attr_string(ds, "unit"))
        .unwrap_or_else(|| "1".into())
}

/// A numeric attribute, if present and readable as a number.
fn attr_f64(loc: &hdf5::Location, name: &str) -> Option<f64> {
    crate::dmw::io::series::hdf5_attr_number(loc, name)
}

/// Attributes that state a sample rate (Hz), or `dt` (s).
const RATE_ATTRS: &[&str] = &["sampling_rate", "sample_rate", "fs", "sampling_frequency"];

/// A sample rate stated on `loc`: (Hz, "attribute `name` of `where`").
fn stated_rate(loc: &hdf5::Location, place: &str) -> Option<(f64, String)> {
    RATE_ATTRS
        .iter()
        .find_map(|a| attr_f64(loc, a).map(|f| (f, format!("attribute `{a}` of `{place}`"))))
        .or_else(|| {
            attr_f64(loc, "dt").map(|dt| (1.0 / dt, format!("attribute `dt` of `{place}`")))
        })
}

/// Time-axis names beside a series (the series itself is never one of them).
const TIME_NAMES: &[&str] = &["time", "t", "time_s"];

/// 1-D numeric datasets of a file (for the error that lists what could have been meant).
fn list_series(file: &hdf5::File) -> Vec<String> {
    fn walk(g: &hdf5::Group, prefix: &str, out: &mut Vec<String>) {
        for name in g.member_names().unwrap_or_default() {
            let path = format!("{prefix}{name}");
            if let Ok(ds) = g.dataset(&name) {
                let numeric = ds.dtype().is_ok_and(|t| {
                    matches!(
                        t.to_descriptor(),
                        Ok(hdf5::types::TypeDescriptor::Float(_)
                            | hdf5::types::TypeDescriptor::Integer(_)
                            | hdf5::types::TypeDescriptor::Unsigned(_))
                    )
                });
                if ds.ndim() == 1 && numeric {
                    out.push(path);
                }
            } else if let Ok(sub) = g.group(&name) {
                walk(&sub, &format!("{path}/"), out);
            }
        }
    }
    let mut out = Vec::new();
    walk(file, "", &mut out);
    out
}

/// The default series of a file: a slider case's heave or a DMW track.
pub const DEFAULT_SERIES: &[(&str, &str)] = &[
    ("case/history/heave", "case/history/heave_rate"),
    ("dmw/tracks/D1", "dmw/tracks/V1"),
];

/// Read a series from any file `hdi analyze` takes: HDF5 through [`read_series`], tables
/// (CSV/TSV, Parquet, Arrow IPC, `.npy`) through `dmw::io::series` (docs/analysis.md).
/// `name` is the column or dataset; `velocity` applies to HDF5 only.
pub fn read_any_series(
    path: &Path,
    name: Option<&str>,
    velocity: Option<&str>,
    sample_rate: Option<f64>,
) -> Result<Series> {
    use crate::dmw::io::{detect_format, series, LdvFormat};
    let fmt = detect_format(path)?;
    if fmt == LdvFormat::Hdf5 {
        return read_series(path, name, velocity, sample_rate);
    }
    if velocity.is_some_and(|v| v != "none") {
        return Err(Error::VelocityOfTable {
            path: path.to_path_buf(),
        });
    }
    let s = series::read_table_series(
        path,
        &series::SeriesRequest {
            column: name.map(str::to_string),
            sample_rate,
        },
    )?;
    Ok(Series {
        velocity_unit: format!("{}/s", s.unit),
        x: s.values,
        v: None,
        sample_rate: s.sample_rate,
        t0: s.t0,
        unit: s.unit,
        name: s.column,
        format: s.format.to_string(),
        rate_source: s.rate_source,
    })
}

/// Read `dataset` (and `velocity`) of an HDF5 file, converted to SI by its `units`/`unit`
/// attribute. The sample rate comes from a `time` dataset beside it (its `sampling_rate`
/// attribute, else its values, checked for uniform steps), else from `sample_rate`, else from
/// a `sampling_rate`/`sample_rate`/`fs`/`dt` attribute of the dataset or its group; stated
/// rates must agree with a time axis. Samples flagged in an `edge_transient` dataset beside it
/// are dropped from both ends. Without `dataset`: hdi's default series, else the only 1-D
/// numeric dataset that is not a time axis.
///
/// Reads in a child process (`formats::isolated`): libhdf5 1.10 crashes or spins on some
/// corrupt files, and that must be an error naming the file, not the end of hdi.
pub fn read_series(
    path: &Path,
    dataset: Option<&str>,
    velocity: Option<&str>,
    sample_rate: Option<f64>,
) -> Result<Series> {
    use crate::formats::isolated::{self, Reader, Writer};
    fn send(reply: std::result::Result<Series, DmwError>, w: &mut Writer) -> std::io::Result<()> {
        let s = match reply {
            Ok(s) => s,
            Err(e) => {
                w.bool(false)?;
                return w.str(&crate::core::chain(&e));
            }
        };
        w.bool(true)?;
        w.f64s(&s.x)?;
        w.bool(s.v.is_some())?;
        w.f64s(s.v.as_deref().unwrap_or_default())?;
        w.f64(s.sample_rate)?;
        w.f64(s.t0)?;
        for text in [
            &s.unit,
            &s.velocity_unit,
            &s.name,
            &s.format,
            &s.rate_source,
        ] {
            w.str(text)?;
        }
        Ok(())
    }
    fn receive(r: &mut Reader) -> std::io::Result<std::result::Result<Series, DmwError>> {
        if !r.bool()? {
            return Ok(Err(DmwError::Isolated(r.str()?)));
        }
        let x = r.f64s()?;
        let has_v = r.bool()?;
        let v = r.f64s()?;
        Ok(Ok(Series {
            x,
            v: has_v.then_some(v),
            sample_rate: r.f64()?,
            t0: r.f64()?,
            unit: r.str()?,
            velocity_unit: r.str()?,
            name: r.str()?,
            format: r.str()?,
            rate_source: r.str()?,
        }))
    }
    let reply = isolated::read_hdf5(
        path,
        || {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                read_series_in_process(path, dataset, velocity, sample_rate)
            }))
            .unwrap_or_else(|_| Err(h5err(path, "cannot read", "the HDF5 reader failed")))
        },
        send,
        receive,
    );
    let series = reply.unwrap_or_else(|failure| {
        Err(h5err(
            path,
            "cannot read",
            format!("{failure}; is the file corrupt?"),
        ))
    })?;
    Ok(series)
}

fn read_series_in_process(
    path: &Path,
    dataset: Option<&str>,
    velocity: Option<&str>,
    sample_rate: Option<f64>,
) -> std::result::Result<Series, DmwError> {
    use crate::dmw::io::series::{check_values, si_unit};
    let file = hdf5::File::open(path).map_err(|e| h5err(path, "cannot open as HDF5", e))?;
    let (dataset, velocity) = choose_dataset(path, &file, dataset, velocity)?;
    let velocity = velocity.filter(|v| v != "none");
    let ds = file.dataset(&dataset).map_err(|_| DmwError::Record {
        path: path.to_path_buf(),
        message: format!(
            "no dataset `{dataset}` (1-D series in this file: {})",
            list_series(&file).join(", ")
        ),
    })?;
    if ds.ndim() != 1 {
        return Err(h5err(
            path,
            &dataset,
            format!("is {}-D, not a time series", ds.ndim()),
        ));
    }
    let raw: Vec<f64> = ds.read_raw().map_err(|e| h5err(path, &dataset, e))?;
    check_values(path, &dataset, &raw)?;
    let stored_unit = read_units(&ds);
    let (unit, factor) = match si_unit(&stored_unit) {
        Some((u, f)) => (u.to_string(), f),
        None => (stored_unit, 1.0),
    };
    let x: Vec<f64> = raw.iter().map(|v| v * factor).collect();
    let parent = dataset.rsplit_once('/').map_or("", |(p, _)| p);
    let group_name = if parent.is_empty() { "/" } else { parent };
    let stated = match sample_rate {
        Some(fs) => Some((fs, "--sample-rate".to_string())),
        None => stated_rate(&ds, &dataset).or_else(|| {
            file.group(group_name)
                .ok()
                .and_then(|g| stated_rate(&g, group_name))
        }),
    };
    if let Some((fs, from)) = &stated {
        if !(fs.is_finite() && *fs > 0.0) {
            return Err(h5err(
                path,
                from,
                format!("sample rate {fs} Hz must be > 0"),
            ));
        }
    }
    let (fs, t0, rate_source) = match find_time_axis(&file, &dataset, parent, x.len()) {
        Some(time) => rate_from_time_axis(path, &dataset, time, x.len(), &stated)?,
        None => match stated {
            Some((fs, from)) => (fs, 0.0, from),
            None => {
                return Err(DmwError::Record {
                    path: path.to_path_buf(),
                    message: format!(
                        "`{dataset}` has no time axis (no `{}` dataset or dimension scale \
                         beside it and no sampling_rate/sample_rate/fs/dt attribute); pass \
                         --sample-rate",
                        sibling(parent, "time")
                    ),
                })
            }
        },
    };
    let (v, velocity_unit) = match &velocity {
        Some(vp) => {
            let (v, unit) = read_velocity(path, &file, vp, x.len())?;
            (Some(v), unit)
        }
        None => (None, format!("{unit}/s")),
    };
    let (a, b) = edge_window(&file, parent, x.len());
    Ok(Series {
        x: x[a..b].to_vec(),
        v: v.map(|v| v[a..b].to_vec()),
        sample_rate: fs,
        t0: t0 + a as f64 / fs,
        unit,
        velocity_unit,
        name: dataset,
        format: "hdf5".into(),
        rate_source,
    })
}

/// The dataset `name` beside the series (in its group `parent`, "" for the root).
fn sibling(parent: &str, name: &str) -> String {
    if parent.is_empty() {
        name.to_string()
    } else {
        format!("{parent}/{name}")
    }
}

/// The series and velocity dataset paths: as given, else hdi's own layouts
/// (`DEFAULT_SERIES`), else the file's only 1-D data dataset (time axes, edge masks and
/// dimension scales are not data).
fn choose_dataset(
    path: &Path,
    file: &hdf5::File,
    dataset: Option<&str>,
    velocity: Option<&str>,
) -> std::result::Result<(String, Option<String>), DmwError> {
    Ok(match dataset {
        Some(d) => (d.to_string(), velocity.map(str::to_string)),
        None => match DEFAULT_SERIES.iter().find(|(d, _)| file.dataset(d).is_ok()) {
            Some((d, v)) => (
                d.to_string(),
                velocity.map_or(Some(v.to_string()), |v| Some(v.to_string())),
            ),
            None => {
                let all = list_series(file);
                let data: Vec<&String> = all
                    .iter()
                    .filter(|d| {
                        let leaf = d.rsplit('/').next().unwrap_or(d).to_lowercase();
                        let scale = file
                            .dataset(d)
                            .ok()
                            .and_then(|ds| attr_string(&ds, "CLASS"));
                        !TIME_NAMES.contains(&leaf.as_str())
                            && leaf != "edge_transient"
                            && scale.as_deref() != Some("DIMENSION_SCALE")
                    })
                    .collect();
                match data.as_slice() {
                    [one] => (one.to_string(), velocity.map(str::to_string)),
                    _ => {
                        return Err(DmwError::Record {
                            path: path.to_path_buf(),
                            message: format!(
                                "{} 1-D datasets; choose one with --dataset ({})",
                                if data.is_empty() { "no" } else { "several" },
                                all.join(", ")
                            ),
                        })
                    }
                }
            }
        },
    })
}

/// A time axis beside the series: by name, else the one dimension scale (h5py `make_scale`:
/// attribute CLASS = "DIMENSION_SCALE") of the series' length `len` in its group.
fn find_time_axis(
    file: &hdf5::File,
    dataset: &str,
    parent: &str,
    len: usize,
) -> Option<(String, hdf5::Dataset)> {
    let group_name = if parent.is_empty() { "/" } else { parent };
    TIME_NAMES
        .iter()
        .find_map(|n| {
            file.dataset(&sibling(parent, n))
                .ok()
                .map(|d| (sibling(parent, n), d))
        })
        .or_else(|| {
            let g = file.group(group_name).ok()?;
            let scales: Vec<(String, hdf5::Dataset)> = g
                .member_names()
                .unwrap_or_default()
                .into_iter()
                .filter_map(|n| g.dataset(&n).ok().map(|d| (sibling(parent, &n), d)))
                .filter(|(n, d)| {
                    *n != dataset
                        && d.ndim() == 1
                        && d.size() == len
                        && attr_string(d, "CLASS").as_deref() == Some("DIMENSION_SCALE")
                })
                .collect();
            match <[_; 1]>::try_from(scales) {
                Ok([one]) => Some(one),
                Err(_) => None,
            }
        })
}

/// (sample rate, t0, source) from the time axis `tname` of a series of `len` samples; a rate
/// stated elsewhere must agree with it.
fn rate_from_time_axis(
    path: &Path,
    dataset: &str,
    (tname, time): (String, hdf5::Dataset),
    len: usize,
    stated: &Option<(f64, String)>,
) -> std::result::Result<(f64, f64, String), DmwError> {
    use crate::dmw::io::series::{rate_from_time, si_unit, RATE_RTOL};
    let t: Vec<f64> = time.read_raw().map_err(|e| h5err(path, &tname, e))?;
    if t.len() != len {
        return Err(h5err(
            path,
            dataset,
            format!(
                "{} samples but its time axis `{tname}` has {}",
                len,
                t.len()
            ),
        ));
    }
    let scale = si_unit(&read_units(&time))
        .filter(|(u, _)| *u == "s")
        .map_or(1.0, |(_, f)| f);
    let t: Vec<f64> = t.iter().map(|v| v * scale).collect();
    // hdi's own files state the exact rate on the time axis; others are measured.
    let (fs, t0, from) = match attr_f64(&time, "sampling_rate") {
        Some(fs) if fs.is_finite() && fs > 0.0 => (
            fs,
            t.first().copied().unwrap_or(0.0),
            format!("attribute `sampling_rate` of `{tname}`"),
        ),
        _ => {
            let (fs, t0) = rate_from_time(path, &tname, &t)?;
            let kind = if attr_string(&time, "CLASS").as_deref() == Some("DIMENSION_SCALE") {
                "dimension scale"
            } else {
                "time dataset"
            };
            (fs, t0, format!("{kind} `{tname}`"))
        }
    };
    if let Some((s, sfrom)) = stated {
        if ((s - fs) / fs).abs() > RATE_RTOL {
            return Err(h5err(
                path,
                dataset,
                format!(
                    "{from} gives {fs} Hz but {sfrom} says {s} Hz; drop one or make \
                     them agree"
                ),
            ));
        }
    }
    Ok((fs, t0, from))
}

/// The velocity dataset `vp` in SI units (when its unit is known) and its unit; it must have
/// the series' `len` samples.
fn read_velocity(
    path: &Path,
    file: &hdf5::File,
    vp: &str,
    len: usize,
) -> std::result::Result<(Vec<f64>, String), DmwError> {
    use crate::dmw::io::series::si_unit;
    let vd = file.dataset(vp).map_err(|_| DmwError::Record {
        path: path.to_path_buf(),
        message: format!("no velocity dataset `{vp}`"),
    })?;
    let v: Vec<f64> = vd.read_raw().map_err(|e| h5err(path, vp, e))?;
    if v.len() != len {
        return Err(h5err(
            path,
            vp,
            format!("{} samples, the series has {}", v.len(), len),
        ));
    }
    let stored = read_units(&vd);
    Ok(match si_unit(&stored) {
        Some((u, f)) => (v.iter().map(|x| x * f).collect(), u.to_string()),
        None => (v, stored),
    })
}

/// The samples kept, `a..b`: those outside the `edge_transient` mask beside the series (the
/// first to the last unmasked sample), or all when there is no usable mask.
fn edge_window(file: &hdf5::File, parent: &str, len: usize) -> (usize, usize) {
    let edge: Vec<u8> = file
        .dataset(&sibling(parent, "edge_transient"))
        .and_then(|d| d.read_raw::<u8>())
        .unwrap_or_default();
    if edge.len() == len {
        let a = edge.iter().position(|&e| e == 0).unwrap_or(0);
        let b = edge.iter().rposition(|&e| e == 0).map_or(len, |i| i + 1);
        if b > a + 1 {
            (a, b)
        } else {
            (0, len)
        }
    } else {
        (0, len)
    }
}
