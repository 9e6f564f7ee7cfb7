//! LDV record writers (`hdi synth`, round-trip tests): the record files the `[dmw]` stage
//! reads. The HDF5 layout documented in `dmw::io`, written through the pipeline's HDF5 writer
//! [`H5Out`] (temp file + rename, `units`/`long_name` on every dataset, shuffle + deflate for
//! large data) — which is why it sits here above the physics, not in `dmw::io` — and the text
//! and Parquet writers of `dmw::io` behind one function.

use crate::core::store::H5Out;
use crate::dmw::io::{
    check_writable, layout_name, sample_time, write_err, write_ldv_parquet, write_ldv_text,
    LdvFormat,
};
use crate::dmw::{DmwError, Layout, LdvRecord, VelocityUnit};
use std::path::Path;

/// Above this many samples the explicit `time` dataset is left out (§5).
const TIME_MAX: usize = 10_000_000;

/// Write a record (for the synthetic generator and round-trip tests), atomically (temporary
/// file in the same directory, then rename). CSV: `# key = value` metadata lines, then
/// `time_s,velocity_V|velocity_m_s[,index_V]` with shortest round-trip floats; Parquet: the
/// same Float64 columns plus key-value metadata; HDF5: the layout in the `dmw::io` docs.
/// Text and Parquet hold one time axis, so `Layout::Segments` needs HDF5.
pub fn write_ldv(rec: &LdvRecord, path: &Path, format: LdvFormat) -> Result<(), DmwError> {
    match format {
        LdvFormat::Csv => write_ldv_text(rec, path),
        LdvFormat::Parquet => write_ldv_parquet(rec, path),
        LdvFormat::Hdf5 => {
            check_writable(rec)?;
            write_hdf5(rec, path, None)
        }
        other => Err(DmwError::Processing(format!(
            "hdi writes LDV records as CSV, Parquet or HDF5; {} is read only",
            other.name()
        ))),
    }
}

/// HDF5 variant that stores channels as int16 ADC counts with `scale`/`offset` attributes
/// (`y = scale·count + offset`), shuffle + deflate: a compact file for the shipped sample.
/// `velocity_lsb`/`index_lsb` are the quantisation steps (in the channel's unit); the error is
/// at most half a step. No `time` dataset: `sampling_rate` and `t0` give the axis.
pub fn write_ldv_hdf5_counts(
    rec: &LdvRecord,
    path: &Path,
    velocity_lsb: f64,
    index_lsb: f64,
) -> Result<(), DmwError> {
    check_writable(rec)?;
    write_hdf5(rec, path, Some((velocity_lsb, index_lsb)))
}

/// int16 counts of `y` with step `lsb` around the mid-range; `None` if `lsb` is unusable.
fn quantise(path: &Path, y: &[f64], lsb: f64, what: &str) -> Result<(Vec<i16>, f64), DmwError> {
    let err = |m: String| DmwError::Processing(format!("writing {}: {m}", path.display()));
    if !(lsb.is_finite() && lsb > 0.0) {
        return Err(err(format!(
            "{what} LSB = {lsb}: must be a positive number"
        )));
    }
    let (lo, hi) = y
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        });
    if !(lo.is_finite() && hi.is_finite()) || y.iter().any(|x| !x.is_finite()) {
        return Err(err(format!("{what} has NaN/inf values")));
    }
    let offset = 0.5 * (lo + hi);
    if (hi - offset) / lsb > 32767.0 {
        return Err(err(format!(
            "{what} spans {lo}..{hi}, more than 65535 steps of {lsb}; choose a larger LSB"
        )));
    }
    let counts = y
        .iter()
        .map(|&x| ((x - offset) / lsb).round().clamp(-32767.0, 32767.0) as i16)
        .collect();
    Ok((counts, offset))
}

/// Writes the HDF5 layout of `dmw::io`; `counts` = (velocity LSB, index LSB) for int16.
fn write_hdf5(rec: &LdvRecord, path: &Path, counts: Option<(f64, f64)>) -> Result<(), DmwError> {
    let werr = |e: crate::core::store::OutputError| DmwError::Processing(crate::error::chain(&e));
    let herr = |e: hdf5::Error| write_err(path, e);
    let (rows, len) = match rec.layout {
        Layout::Segments {
            n_segments,
            segment_len,
        } => (n_segments, segment_len),
        _ => (1, rec.velocity.len()),
    };
    let shape: Vec<usize> = match rec.layout {
        Layout::Segments { .. } => vec![rows, len],
        _ => vec![len],
    };
    let out = H5Out::create(path).map_err(werr)?;
    let root = out.group("", None).map_err(werr)?;
    out.attr_str(&root, "NX_class", "NXroot").map_err(werr)?;
    out.attr_str(&root, "default", "ldv").map_err(werr)?;
    out.attr_str(&root, "hdi_version", env!("CARGO_PKG_VERSION"))
        .map_err(werr)?;
    let g = out.group("ldv", Some("NXdata")).map_err(werr)?;
    let with_time = counts.is_none() && len <= TIME_MAX;
    out.attr_str(&g, "signal", "velocity").map_err(werr)?;
    let axes: Vec<&str> = match (shape.len(), with_time) {
        (1, true) => vec!["time"],
        (1, false) => vec!["."],
        (_, true) => vec![".", "time"],
        (_, false) => vec![".", "."],
    };
    out.attr_str_list(&g, "axes", &axes).map_err(werr)?;
    if with_time {
        let dim = shape.len() as i64 - 1;
        g.new_attr::<i64>()
            .create("time_indices")
            .and_then(|a| a.write_scalar(&dim))
            .map_err(herr)?;
    }
    if rec.index.is_some() {
        out.attr_str_list(&g, "auxiliary_signals", &["index"])
            .map_err(werr)?;
    }
    out.attr_f64(&g, "sampling_rate", rec.sample_rate)
        .map_err(werr)?;
    out.attr_f64(&g, "t0", rec.t0).map_err(werr)?;
    if let Some(s) = rec.sensitivity {
        out.attr_f64(&g, "sensitivity", s).map_err(werr)?;
    }
    if let Some(r) = rec.rpm {
        out.attr_f64(&g, "rpm", r).map_err(werr)?;
    }
    out.attr_str(&g, "layout", layout_name(&rec.layout))
        .map_err(werr)?;

    let (vunit, vlong) = match rec.velocity_unit {
        VelocityUnit::Volt => ("V", "LDV decoder output voltage"),
        VelocityUnit::MetrePerSecond => ("m/s", "LDV surface velocity"),
    };
    let channels = [
        Some((
            "velocity",
            rec.velocity.as_slice(),
            vunit,
            vlong,
            counts.map(|c| c.0),
        )),
        rec.index.as_deref().map(|idx| {
            (
                "index",
                idx,
                "V",
                "once-per-revolution index",
                counts.map(|c| c.1),
            )
        }),
    ];
    for (name, data, unit, long, lsb) in channels.into_iter().flatten() {
        let shape_err = |e: ndarray::ShapeError| write_err(path, e);
        match lsb {
            None => {
                let view =
                    ndarray::ArrayViewD::from_shape(shape.as_slice(), data).map_err(shape_err)?;
                out.write_array(&g, name, view, unit, long).map_err(werr)?;
            }
            Some(lsb) => {
                let (q, offset) = quantise(path, data, lsb, name)?;
                let view =
                    ndarray::ArrayViewD::from_shape(shape.as_slice(), &q).map_err(shape_err)?;
                let ds = out.write_array(&g, name, view, unit, long).map_err(werr)?;
                out.attr_f64(&ds, "scale", lsb).map_err(werr)?;
                out.attr_f64(&ds, "offset", offset).map_err(werr)?;
            }
        }
    }
    if with_time {
        let t: Vec<f64> = (0..len).map(|i| sample_time(rec, i)).collect();
        let ds = out.write_1d(&g, "time", &t, "s", "time").map_err(werr)?;
        out.attr_f64(&ds, "sampling_rate", rec.sample_rate)
            .map_err(werr)?;
        out.attr_f64(&ds, "t0", rec.t0).map_err(werr)?;
    }
    out.finish().map_err(werr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dmw::io::tests::{prov, read, record, same_record};
    use crate::dmw::io::{detect_format, LdvFormat};

    #[test]
    fn round_trips() {
        let dir = tempfile::tempdir().unwrap();
        for (k, unit) in [VelocityUnit::Volt, VelocityUnit::MetrePerSecond]
            .into_iter()
            .enumerate()
        {
            let rec = record(5000, 4e6, k == 0, unit);
            // Extensions that lie: detection is by content.
            for (format, name, fmt) in [
                (LdvFormat::Csv, "a.h5", "csv"),
                (LdvFormat::Parquet, "b.csv", "parquet"),
                (LdvFormat::Hdf5, "c.parquet", "hdf5"),
            ] {
                let path = dir.path().join(name);
                write_ldv(&rec, &path, format).unwrap();
                assert_eq!(detect_format(&path).unwrap(), format);
                let got = read(&path).unwrap();
                same_record(&got, &rec);
                assert_eq!(got.format, fmt);
                assert_eq!(prov(&got, "format"), fmt);
                assert_eq!(prov(&got, "sample_rate_source"), "time column");
                let index = match (k, format) {
                    (1, _) => "none",
                    (_, LdvFormat::Hdf5) => "index",
                    _ => "index_V",
                };
                assert_eq!(prov(&got, "index"), index);
            }
        }
        // No temporary files left behind.
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 3);
    }

    #[test]
    fn hdf5_layouts_and_counts() {
        let dir = tempfile::tempdir().unwrap();
        let mut rec = record(6000, 2e6, true, VelocityUnit::Volt);
        rec.layout = Layout::Segments {
            n_segments: 3,
            segment_len: 2000,
        };
        let path = dir.path().join("seg.h5");
        write_ldv(&rec, &path, LdvFormat::Hdf5).unwrap();
        let got = read(&path).unwrap();
        same_record(&got, &rec);
        // Text cannot hold a segment stack.
        let err = write_ldv(&rec, &dir.path().join("seg.csv"), LdvFormat::Csv).unwrap_err();
        assert!(err.to_string().contains("needs HDF5"), "{err}");

        rec.layout = Layout::Averaged;
        write_ldv(&rec, &path, LdvFormat::Hdf5).unwrap();
        assert_eq!(read(&path).unwrap().layout, Layout::Averaged);
        let csv = dir.path().join("avg.csv");
        write_ldv(&rec, &csv, LdvFormat::Csv).unwrap();
        assert_eq!(read(&csv).unwrap().layout, Layout::Averaged);

        // int16 counts: within half an LSB, no time dataset, rate from the attribute.
        let rec = record(200_000, 4e6, true, VelocityUnit::Volt);
        let (vl, il) = (1e-5, 2e-4);
        let f64_path = dir.path().join("f64.h5");
        let cnt_path = dir.path().join("counts.h5");
        write_ldv(&rec, &f64_path, LdvFormat::Hdf5).unwrap();
        write_ldv_hdf5_counts(&rec, &cnt_path, vl, il).unwrap();
        let got = read(&cnt_path).unwrap();
        let worst = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        };
        assert!(worst(&got.velocity, &rec.velocity) <= 0.5 * vl * (1.0 + 1e-9));
        let (gi, ri) = (got.index.as_ref().unwrap(), rec.index.as_ref().unwrap());
        assert!(worst(gi, ri) <= 0.5 * il * (1.0 + 1e-9));
        assert_eq!(got.sample_rate, 4e6);
        assert_eq!(got.t0, rec.t0);
        assert_eq!(prov(&got, "sample_rate_source"), "file metadata");
        assert_eq!(prov(&got, "time"), "none");
        let size = |p: &Path| std::fs::metadata(p).unwrap().len();
        assert!(
            size(&cnt_path) * 4 < size(&f64_path),
            "{} {}",
            size(&cnt_path),
            size(&f64_path)
        );
        // An LSB too fine for 16 bits.
        let err = write_ldv_hdf5_counts(&rec, &cnt_path, 1e-8, il).unwrap_err();
        assert!(err.to_string().contains("larger LSB"), "{err}");
    }

    /// Files laid out by other writers: datasets in the root, int32 with CF scale attributes,
    /// fixed-length string units, the rate on the dataset, sample-number time.

    #[test]
    fn truncated_and_corrupt_binary_files() {
        let dir = tempfile::tempdir().unwrap();
        let rec = record(300_000, 4e6, true, VelocityUnit::Volt);
        for (format, name) in [(LdvFormat::Parquet, "r.parquet"), (LdvFormat::Hdf5, "r.h5")] {
            let path = dir.path().join(name);
            write_ldv(&rec, &path, format).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            // Cut to half; garble the middle; cut to just the magic.
            let mut garbled = bytes.clone();
            let mid = garbled.len() / 2;
            for b in &mut garbled[mid - 2000..mid + 2000] {
                *b ^= 0x5a;
            }
            for (k, variant) in [
                bytes[..bytes.len() / 2].to_vec(),
                garbled,
                bytes[..8].to_vec(),
            ]
            .into_iter()
            .enumerate()
            {
                let bad = dir.path().join(format!("bad{k}-{name}"));
                std::fs::write(&bad, &variant).unwrap();
                let outcome = std::panic::catch_unwind(|| read(&bad));
                let err = match outcome.unwrap_or_else(|_| panic!("{name} variant {k} panicked")) {
                    Err(e) => e,
                    // Parquet pages carry no checksum: garbled plain data can go unnoticed.
                    Ok(_) if k == 1 && format == LdvFormat::Parquet => continue,
                    Ok(_) => panic!("{name} variant {k} read without error"),
                };
                let msg = err.to_string();
                assert!(!msg.contains('\n'), "{msg}");
                assert!(msg.contains(&format!("bad{k}-{name}")), "{msg}");
                if k != 1 {
                    assert!(matches!(err, DmwError::Read { .. }), "{name} {k}: {err:?}");
                }
            }
        }
    }
}
