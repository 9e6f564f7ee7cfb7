//! The binary/foreign formats against the CSV version of the same record, all written by
//! independent writers (pyuff, pyarrow, numpy, Python's wave, scipy; tests/data/ldv/ and its
//! generator `make_ldv_formats.py`). The record's values are multiples of 2^-10 V, so every
//! double-precision rendering (UFF ASCII: 12 significant digits) holds them exactly.

use super::*;
use crate::dmw::chain::Butterworth;
use crate::dmw::chain::{process, ChainParams};
use crate::dmw::{DmwError, LdvRecord};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/ldv")).join(name)
}

fn read_opts(name: &str, opts: &ReadOptions) -> LdvRecord {
    read_ldv(&data(name), opts).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn read(name: &str) -> LdvRecord {
    read_opts(name, &ReadOptions::default())
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Chain parameters for the test record: 4 revolutions of 1000 samples at 100 kHz.
fn params() -> ChainParams {
    ChainParams {
        rpm: Some(6000.0),
        segment: 9e-3,
        highpass: Some(Butterworth {
            order: 4,
            cutoff: 1e3,
        }),
        ..ChainParams::default()
    }
}

/// `got` holds the reference's samples within `tol_v` (velocity) and `tol_i` (index, in the
/// reference's unit after multiplying by `index_gain`), the same rate and start.
fn same_samples(name: &str, got: &LdvRecord, want: &LdvRecord, tol_v: f64, tol_i: f64, gain: f64) {
    assert_eq!(got.velocity.len(), want.velocity.len(), "{name}");
    let dv = max_diff(&got.velocity, &want.velocity);
    assert!(dv <= tol_v, "{name}: velocity differs by {dv}");
    let gi: Vec<f64> = got
        .index
        .as_ref()
        .expect(name)
        .iter()
        .map(|x| x * gain)
        .collect();
    let di = max_diff(&gi, want.index.as_ref().unwrap());
    assert!(di <= tol_i, "{name}: index differs by {di}");
    assert!(
        (got.sample_rate / want.sample_rate - 1.0).abs() < 1e-12,
        "{name}: {} Hz",
        got.sample_rate
    );
    // WAV and a bare .npy store no start time.
    if !matches!(got.format, "wav" | "npy") || got.t0 != 0.0 {
        assert!((got.t0 - want.t0).abs() < 1e-12, "{name}: t0 {}", got.t0);
    }
    assert_eq!(got.velocity_unit, want.velocity_unit, "{name}");
}

/// The DMW tracks of `got` and `want` agree to `rtol` of the largest |D1|.
fn same_tracks(name: &str, got: &LdvRecord, want: &LdvRecord, rtol: f64) {
    let p = params();
    let a = process(got, &p).unwrap_or_else(|e| panic!("{name}: {e}"));
    let b = process(want, &p).unwrap();
    assert_eq!(a.qa.n_avg, 4, "{name}");
    let scale = b.tracks.d[0].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(scale > 0.0);
    for k in 0..3 {
        let d = max_diff(&a.tracks.d[k], &b.tracks.d[k]);
        assert!(
            d <= rtol * scale,
            "{name}: track {k} differs by {d} (scale {scale})"
        );
    }
}

#[test]
fn double_precision_formats_give_the_csv_record_and_tracks() {
    let csv = read("record.csv");
    assert_eq!(csv.velocity.len(), 4200);
    for (name, format) in [
        ("record_plain.arrow", "arrow"),
        ("record_lz4.feather", "arrow"),
        ("record_zstd.feather", "arrow"),
        ("record_stream.arrows", "arrow"),
        ("record_ascii.uff", "uff58"),
        ("record_binary.uff", "uff58"),
        ("record_ascii_uneven.uff", "uff58"),
        ("record_binary_noname.uff", "uff58"),
        ("record_c.npy", "npy"),
        ("record_fortran.npy", "npy"),
        ("record_be.npy", "npy"),
        ("record.npz", "npz"),
        ("record_deflate.npz", "npz"),
        ("record_f64.wav", "wav"),
    ] {
        let rec = read(name);
        assert_eq!(rec.format, format, "{name}");
        assert_eq!(detect_format(&data(name)).unwrap().name(), format);
        same_samples(name, &rec, &csv, 0.0, 0.0, 1.0);
        same_tracks(name, &rec, &csv, 1e-12);
    }
    // Metadata: Arrow schema metadata, .npz 0-d members.
    let arrow = read("record_lz4.feather");
    assert_eq!((arrow.sensitivity, arrow.rpm), (Some(0.025), Some(6000.0)));
    assert_eq!(tests::prov(&arrow, "sample_rate_source"), "time column");
    let npz = read("record_deflate.npz");
    assert_eq!(tests::prov(&npz, "sample_rate_source"), "file metadata");
    let uff = read("record_binary.uff");
    assert_eq!(tests::prov(&uff, "velocity_unit_source"), "file unit label");
    assert_eq!(tests::prov(&uff, "velocity"), "velocity");
}

#[test]
fn single_precision_and_integer_formats_within_their_quantisation() {
    let csv = read("record.csv");
    // Multiples of 2^-10 below 8 are exact in f32.
    for name in [
        "record_f32.feather",
        "record_structured.npy",
        "record_f32.wav",
    ] {
        let rec = read(name);
        same_samples(name, &rec, &csv, 0.0, 0.0, 1.0);
        same_tracks(name, &rec, &csv, 1e-12);
    }
    // UFF ASCII single precision: E13.5, six significant digits.
    let rec = read("record_ascii_single.uff");
    same_samples("single", &rec, &csv, 5e-6 * 0.3, 5e-6 * 4.9, 1.0);
    same_tracks("single", &rec, &csv, 1e-4);
    // PCM: half a code step of full scale 1 V; the index was written as index/5.
    for (name, bits) in [
        ("record_int16.wav", 16),
        ("record_int24.wav", 24),
        ("record_int32.wav", 32),
    ] {
        let step = 1.0 / f64::powi(2.0, bits - 1);
        let rec = read(name);
        same_samples(
            name,
            &rec,
            &csv,
            0.5 * step + 1e-15,
            2.5 * step + 1e-15,
            5.0,
        );
        // Quantisation noise of a half step on a ~0.2 V signal.
        let rtol = if bits == 16 { 1e-3 } else { 1e-6 };
        let mut scaled = rec.clone();
        scaled.index = rec
            .index
            .as_ref()
            .map(|i| i.iter().map(|x| x * 5.0).collect());
        same_tracks(name, &scaled, &csv, rtol);
    }
}

#[test]
fn channels_by_name_number_and_node() {
    let csv = read("record.csv");
    // 1-D .npy: only the velocity, the rate from the option.
    let err = read_ldv(&data("record_velocity.npy"), &ReadOptions::default()).unwrap_err();
    assert!(err.to_string().contains("sample_rate option"), "{err}");
    let opts = ReadOptions {
        sample_rate: Some(1e5),
        ..Default::default()
    };
    let v = read_opts("record_velocity.npy", &opts);
    assert_eq!(v.velocity, csv.velocity);
    assert!(v.index.is_none());
    // UFF: by node:direction and by number; WAV and .npy columns by number.
    for (name, vel, idx) in [
        ("record_binary.uff", "2:3", "1:3"),
        ("record_binary_noname.uff", "1", "0"),
        ("record_f64.wav", "1", "0"),
        ("record_c.npy", "2", "1"),
    ] {
        let opts = ReadOptions {
            velocity_column: Some(vel.into()),
            index_column: Some(idx.into()),
            ..Default::default()
        };
        let rec = read_opts(name, &opts);
        assert_eq!(&rec.velocity, csv.index.as_ref().unwrap(), "{name}");
        assert_eq!(rec.index.as_ref().unwrap(), &csv.velocity, "{name}");
    }
    let opts = ReadOptions {
        velocity_column: Some("7".into()),
        ..Default::default()
    };
    let err = read_ldv(&data("record_f64.wav"), &opts).unwrap_err();
    assert!(err.to_string().contains("channel number 7"), "{err}");
}

/// Every cut and a few corruptions of every file: an error naming the file, on one line,
/// never a panic.
#[test]
fn truncated_and_corrupt_files_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let names = [
        "record_plain.arrow",
        "record_lz4.feather",
        "record_stream.arrows",
        "record_ascii.uff",
        "record_binary.uff",
        "record_ascii_uneven.uff",
        "record_c.npy",
        "record_structured.npy",
        "record.npz",
        "record_deflate.npz",
        "record_int24.wav",
        "record_f32.wav",
    ];
    for name in names {
        let bytes = std::fs::read(data(name)).unwrap();
        let n = bytes.len();
        let mut variants: Vec<(String, Vec<u8>)> = [7, 64, 300, n / 3, n / 2 + 17, n - 9, n - 3]
            .iter()
            .filter(|&&k| k < n)
            .map(|&k| (format!("cut{k}"), bytes[..k].to_vec()))
            .collect();
        // Overwrite 16 bytes with 0xff at a few places (headers, sizes, data).
        for at in [8, 40, 100, n / 2, n - 40] {
            let mut b = bytes.clone();
            for x in b.iter_mut().skip(at).take(16) {
                *x = 0xff;
            }
            variants.push((format!("garbled{at}"), b));
        }
        for (what, b) in variants {
            let p = dir.path().join(format!("bad-{what}-{name}"));
            std::fs::write(&p, &b).unwrap();
            let r = std::panic::catch_unwind(|| read_ldv(&p, &ReadOptions::default()));
            let r = r.unwrap_or_else(|_| panic!("{name} {what}: panic"));
            match r {
                // Garbling sample values can leave a valid record (NaN → error, others not).
                Ok(rec) => assert!(what.starts_with("garbled"), "{name} {what}: read {rec:?}"),
                Err(e) => {
                    let msg = e.to_string();
                    assert!(
                        matches!(e, DmwError::Read { .. } | DmwError::Record { .. }),
                        "{name} {what}: {e:?}"
                    );
                    assert!(msg.contains(&format!("bad-{what}-{name}")), "{msg}");
                    assert!(!msg.contains('\n'), "{name} {what}: {msg}");
                }
            }
        }
    }
}
