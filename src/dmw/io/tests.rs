//! Reader/writer tests: detection rules, and every bad input giving an error (never a panic)
//! whose message names the line/row/sample or key. Round trips through every format (the HDF5
//! writer sits with the DMW stage) are in `stages::dmw`'s LDV writer tests, with the helpers
//! here.

use super::*;
use crate::dmw::{DmwError, Layout, LdvRecord, VelocityUnit};
use std::path::{Path, PathBuf};

pub(crate) fn record(n: usize, fs: f64, index: bool, unit: VelocityUnit) -> LdvRecord {
    let velocity = (0..n)
        .map(|i| {
            let x = i as f64;
            0.3 * (0.0137 * x).sin() + 0.01 * (1.7 * x).cos() - 1e-7 * x
        })
        .collect();
    LdvRecord {
        source: PathBuf::from("synthetic"),
        format: "synthetic",
        sample_rate: fs,
        t0: 0.125,
        velocity,
        velocity_unit: unit,
        index: index.then(|| {
            (0..n)
                .map(|i| {
                    if i % 97 < 5 {
                        4.9 + 1e-3 * (i % 7) as f64
                    } else {
                        0.02
                    }
                })
                .collect()
        }),
        layout: Layout::Continuous,
        sensitivity: Some(0.025),
        rpm: Some(5425.0),
        provenance: vec![],
    }
}

fn temp(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    (dir, path)
}

pub(crate) fn prov<'a>(rec: &'a LdvRecord, key: &str) -> &'a str {
    rec.provenance
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
        .unwrap_or_else(|| panic!("no provenance key {key}: {:?}", rec.provenance))
}

pub(crate) fn read(path: &Path) -> Result<LdvRecord, DmwError> {
    read_ldv(path, &ReadOptions::default())
}

fn read_text(text: &str) -> Result<LdvRecord, DmwError> {
    let (_d, p) = temp("rec.csv", text.as_bytes());
    read(&p)
}

/// The error of reading `text` must be a `Record` error whose message has all `parts`.
fn record_error(text: &str, opts: &ReadOptions, parts: &[&str]) {
    let (_d, p) = temp("bad.csv", text.as_bytes());
    let err = match std::panic::catch_unwind(|| read_ldv(&p, opts)).expect("reader panicked") {
        Ok(rec) => panic!("{text:?}: no error, {} samples", rec.velocity.len()),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert!(matches!(err, DmwError::Record { .. }), "{err:?}");
    assert!(!msg.contains('\n'), "multi-line message: {msg}");
    assert!(msg.contains("bad.csv"), "{msg}");
    for part in parts {
        assert!(msg.contains(part), "missing '{part}' in: {msg}");
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

pub(crate) fn same_record(got: &LdvRecord, want: &LdvRecord) {
    assert_eq!(got.velocity, want.velocity);
    assert_eq!(got.index, want.index);
    assert_eq!(got.velocity_unit, want.velocity_unit);
    assert_eq!(got.layout, want.layout);
    assert_eq!(got.sensitivity, want.sensitivity);
    assert_eq!(got.rpm, want.rpm);
    assert!(
        rel(got.sample_rate, want.sample_rate) < 1e-12,
        "{}",
        got.sample_rate
    );
    assert!((got.t0 - want.t0).abs() < 1e-15, "{}", got.t0);
}

#[test]
fn hdf5_foreign_layouts() {
    use hdf5::types::{FixedAscii, VarLenUnicode};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scope.h5");
    {
        let f = hdf5::File::create(&path).unwrap();
        let counts: Vec<i32> = (0..1000).map(|i| (i % 50) - 25).collect();
        let ds = f
            .new_dataset_builder()
            .with_data(&counts)
            .create("U")
            .unwrap();
        ds.new_attr::<f64>()
            .create("scale_factor")
            .unwrap()
            .write_scalar(&0.5)
            .unwrap();
        ds.new_attr::<f64>()
            .create("add_offset")
            .unwrap()
            .write_scalar(&1.0)
            .unwrap();
        let unit: FixedAscii<8> = FixedAscii::from_ascii(b"mV").unwrap();
        ds.new_attr::<FixedAscii<8>>()
            .create("units")
            .unwrap()
            .write_scalar(&unit)
            .unwrap();
        ds.new_attr::<f64>()
            .create("fs")
            .unwrap()
            .write_scalar(&1e6)
            .unwrap();
        let n: Vec<u32> = (100..1100).collect();
        f.new_dataset_builder()
            .with_data(&n)
            .create("sample")
            .unwrap();
        let s: VarLenUnicode = "5425".parse().unwrap();
        f.new_attr::<VarLenUnicode>()
            .create("rpm")
            .unwrap()
            .write_scalar(&s)
            .unwrap();
    }
    let got = read(&path).unwrap();
    assert_eq!(got.velocity.len(), 1000);
    assert_eq!(got.velocity[3], (0.5 * -22.0 + 1.0) * 1e-3);
    assert_eq!(got.velocity_unit, VelocityUnit::Volt);
    assert_eq!(got.sample_rate, 1e6);
    assert_eq!(got.t0, 100.0 / 1e6);
    assert_eq!(got.rpm, Some(5425.0));
    assert_eq!(prov(&got, "group"), "/");
    assert_eq!(prov(&got, "velocity_unit_source"), "units attribute");
    assert_eq!(prov(&got, "sample_rate_source"), "file metadata");
    // The option must agree with the file.
    let opts = ReadOptions {
        sample_rate: Some(1.1e6),
        ..Default::default()
    };
    let err = read_ldv(&path, &opts).unwrap_err();
    assert!(
        err.to_string().contains("1100000") && err.to_string().contains("1000000"),
        "{err}"
    );

    // NaN run in an HDF5 velocity dataset; no rate at all.
    let path = dir.path().join("nan.h5");
    {
        let f = hdf5::File::create(&path).unwrap();
        let g = f.create_group("ldv").unwrap();
        let mut v = vec![0.25f32; 100];
        v[40..43].fill(f32::NAN);
        g.new_dataset_builder()
            .with_data(&v)
            .create("velocity")
            .unwrap();
    }
    let err = read(&path).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, DmwError::Record { .. }));
    assert!(
        msg.contains("sample 40") && msg.contains("run of 3"),
        "{msg}"
    );
    let path2 = dir.path().join("norate.h5");
    {
        let f = hdf5::File::create(&path2).unwrap();
        f.new_dataset_builder()
            .with_data(&[0.1f64, 0.2, 0.3])
            .create("velocity_m_s")
            .unwrap();
    }
    let err = read(&path2).unwrap_err();
    assert!(err.to_string().contains("sampling_rate"), "{err}");
    let opts = ReadOptions {
        sample_rate: Some(1e5),
        ..Default::default()
    };
    let got = read_ldv(&path2, &opts).unwrap();
    assert_eq!(got.velocity_unit, VelocityUnit::MetrePerSecond);
    assert_eq!(prov(&got, "sample_rate_source"), "option");
}

/// A Parquet file from another writer: f32 velocity, integer sample numbers, a null.
#[test]
fn parquet_foreign_columns() {
    use polars_core::prelude::*;
    use polars_io::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, v: Vec<Option<f32>>| {
        let n = v.len();
        let samples: Vec<i64> = (0..n as i64).collect();
        let mut df = DataFrame::new(
            n,
            vec![
                Column::new("n".into(), samples),
                Column::new("U (mV)".into(), v),
            ],
        )
        .unwrap();
        let path = dir.path().join(name);
        let f = std::fs::File::create(&path).unwrap();
        ParquetWriter::new(f).finish(&mut df).unwrap();
        path
    };
    let good = write("good.parquet", vec![Some(1.5), Some(-2.0), Some(0.25)]);
    let opts = ReadOptions {
        sample_rate: Some(1e6),
        ..Default::default()
    };
    let rec = read_ldv(&good, &opts).unwrap();
    assert_eq!(rec.velocity, vec![1.5e-3, -2e-3, 0.25e-3]);
    assert_eq!(rec.velocity_unit, VelocityUnit::Volt);
    assert_eq!(prov(&rec, "time"), "n (sample number)");
    let bad = write("bad.parquet", vec![Some(1.0), None, None, Some(2.0)]);
    let err = read_ldv(&bad, &opts).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, DmwError::Record { .. }), "{msg}");
    assert!(
        msg.contains("row 1") && msg.contains("run of 2") && msg.contains("missing"),
        "{msg}"
    );
}

#[test]
fn column_detection() {
    // (text, velocity unit, sample rate, t0, index present)
    let cases: &[(&str, VelocityUnit, f64, f64, bool)] = &[
        (
            "t,U,trigger\n0,1,0\n0.5,2,5\n1,3,0\n",
            VelocityUnit::Volt,
            2.0,
            0.0,
            true,
        ),
        (
            "# comment\n#fs: 2 kHz\nTime (ms);Velocity (m/s);Tacho\n1;0.1;0\n1.5;0.2;1\n2;0.3;0\n",
            VelocityUnit::MetrePerSecond,
            2000.0,
            1e-3,
            true,
        ),
        (
            "Time [s]\tVelocity [V]\n0\t1\n0.25\t2\n",
            VelocityUnit::Volt,
            4.0,
            0.0,
            false,
        ),
        (
            "time_us,voltage_V,once_per_rev_V\n10,1,0\n12,2,0\n14,3,1\n",
            VelocityUnit::Volt,
            5e5,
            1e-5,
            true,
        ),
        (
            "\u{feff}\"t_s\",\"v_m_s\",\"index\"\r\n0,1,0\r\n1,2,0\r\n",
            VelocityUnit::MetrePerSecond,
            1.0,
            0.0,
            true,
        ),
        (
            "# sample_rate = 4e6\nvelocity_mps\n1\n2\n3\n",
            VelocityUnit::MetrePerSecond,
            4e6,
            0.0,
            false,
        ),
    ];
    for (text, unit, fs, t0, has_index) in cases {
        let rec = read_text(text).unwrap_or_else(|e| panic!("{text:?}: {e}"));
        assert_eq!(rec.velocity_unit, *unit, "{text:?}");
        assert!(
            rel(rec.sample_rate, *fs) < 1e-12,
            "{text:?}: {}",
            rec.sample_rate
        );
        assert!((rec.t0 - t0).abs() < 1e-15, "{text:?}: {}", rec.t0);
        assert_eq!(rec.index.is_some(), *has_index, "{text:?}");
    }

    // Scaled units: mV → V, mm/s → m/s; the option overrides without scaling.
    let rec = read_text("time_s,velocity (mV)\n0,250\n1,500\n").unwrap();
    assert_eq!(rec.velocity, vec![0.25, 0.5]);
    let rec = read_text("time_s,velocity [mm/s]\n0,250\n1,500\n").unwrap();
    assert_eq!(
        (rec.velocity_unit, rec.velocity.clone()),
        (VelocityUnit::MetrePerSecond, vec![0.25, 0.5])
    );
    let (_d, p) = temp("o.csv", b"time_s,velocity_V\n0,250\n1,500\n");
    let opts = ReadOptions {
        velocity_unit: Some(VelocityUnit::MetrePerSecond),
        ..Default::default()
    };
    let rec = read_ldv(&p, &opts).unwrap();
    assert_eq!(rec.velocity_unit, VelocityUnit::MetrePerSecond);
    assert_eq!(prov(&rec, "velocity_unit_source"), "option");

    // Decimal comma with semicolons; metadata with units.
    let rec =
        read_text("# sensitivity = 25 mm/s/V\n# rpm: 5425\ntime_s;velocity_V\n0,0;1,5\n0,5;2,5\n")
            .unwrap();
    assert_eq!(rec.velocity, vec![1.5, 2.5]);
    assert_eq!(rec.sensitivity, Some(0.025));
    assert_eq!(rec.rpm, Some(5425.0));

    // Ambiguous and missing velocity; explicit choice.
    let text = "time_s,voltage_V,velocity_m_s\n0,1,2\n1,1,2\n";
    record_error(
        text,
        &ReadOptions::default(),
        &["voltage_V", "velocity_m_s", "velocity_column"],
    );
    let (_d, p) = temp("c.csv", text.as_bytes());
    let opts = ReadOptions {
        velocity_column: Some("VELOCITY_M_S".into()),
        ..Default::default()
    };
    let rec = read_ldv(&p, &opts).unwrap();
    assert_eq!(rec.velocity, vec![2.0, 2.0]);
    assert_eq!(rec.velocity_unit, VelocityUnit::MetrePerSecond);
    record_error(
        "time_s,foo,bar\n0,1,2\n1,1,2\n",
        &ReadOptions::default(),
        &["no velocity column", "foo", "bar", "velocity_column"],
    );
    let opts = ReadOptions {
        index_column: Some("nope".into()),
        ..Default::default()
    };
    record_error(
        "time_s,velocity_V\n0,1\n1,1\n",
        &opts,
        &["no column 'nope'", "index_column"],
    );
    // A velocity unit we do not know asks for the option.
    record_error(
        "time_s,velocity (in/s)\n0,1\n1,2\n",
        &ReadOptions::default(),
        &["'in/s'", "velocity_unit"],
    );
    // An explicitly chosen, unknown-named time column is in seconds.
    let (_d, p) = temp("z.csv", b"Zeit,U_V\n0,1\n0.5,1\n");
    let opts = ReadOptions {
        time_column: Some("zeit".into()),
        ..Default::default()
    };
    assert_eq!(read_ldv(&p, &opts).unwrap().sample_rate, 2.0);
}

#[test]
fn sample_rate_sources() {
    let text = "sample,velocity_V,index_V\n10,1,0\n11,2,0\n12,3,5\n";
    let (_d, p) = temp("s.csv", text.as_bytes());
    let err = read(&p).unwrap_err();
    assert!(
        err.to_string().contains("sample_rate") && err.to_string().contains("'sample'"),
        "{err}"
    );
    let opts = ReadOptions {
        sample_rate: Some(4e6),
        ..Default::default()
    };
    let rec = read_ldv(&p, &opts).unwrap();
    assert_eq!(rec.sample_rate, 4e6);
    assert_eq!(rec.t0, 10.0 / 4e6);
    assert_eq!(prov(&rec, "sample_rate_source"), "option");
    assert_eq!(prov(&rec, "time"), "sample (sample number)");

    // No time column at all.
    record_error(
        "velocity_V\n1\n2\n",
        &ReadOptions::default(),
        &["no time column", "sample_rate"],
    );
    // Time column against option and against metadata.
    let text = "time_s,velocity_V\n0,1\n0.25,2\n0.5,3\n";
    let opts = ReadOptions {
        sample_rate: Some(4.1),
        ..Default::default()
    };
    record_error(text, &opts, &["4.1 Hz", "(4 Hz)", "disagree"]);
    let close = ReadOptions {
        sample_rate: Some(4.0 * (1.0 + 1e-7)),
        ..Default::default()
    };
    let (_d, p) = temp("ok.csv", text.as_bytes());
    assert!(read_ldv(&p, &close).is_ok());
    record_error(
        &format!("# sample_rate = 5\n{text}"),
        &ReadOptions::default(),
        &["5 Hz", "4 Hz", "disagree"],
    );
    // Metadata against option without a time column.
    record_error(
        "# sample_rate = 5\nvelocity_V\n1\n2\n",
        &opts,
        &["4.1 Hz", "5 Hz"],
    );
    let bad = ReadOptions {
        sample_rate: Some(-1.0),
        ..Default::default()
    };
    let (_d, p) = temp("neg.csv", b"velocity_V\n1\n2\n");
    assert!(read_ldv(&p, &bad).is_err());
    record_error(
        "# sample_rate = fast\nvelocity_V\n1\n2\n",
        &ReadOptions::default(),
        &["line 1", "sample_rate"],
    );
    record_error(
        "# rpm = -5\ntime_s,velocity_V\n0,1\n1,2\n",
        &ReadOptions::default(),
        &["rpm"],
    );
}

#[test]
fn bad_text_inputs() {
    let d = ReadOptions::default();
    record_error("", &d, &["empty file"]);
    record_error("# only a comment\n\n", &d, &["no header"]);
    record_error("time_s,velocity_V,index_V\n", &d, &["no data rows"]);
    record_error("1,2,3\n4,5,6\n", &d, &["line 1", "no header"]);
    record_error("time_s,velocity_V\n0,1\n", &d, &["only 1 sample"]);
    record_error("time velocity\n0 1\n1 2\n", &d, &["spaces"]);
    // Non-numeric cell: line 5 is sample 2.
    record_error(
        "# x\ntime_s,velocity_V,index_V\n0,1,0\n1,2,0\n2,abc,0\n3,4,0\n",
        &d,
        &["line 5", "sample 2", "'abc'", "velocity_V", "not a number"],
    );
    // polars skips leading spaces but not trailing ones.
    assert_eq!(
        read_text("time_s,velocity_V\n0, 1\n1, 2\n")
            .unwrap()
            .velocity,
        vec![1.0, 2.0]
    );
    record_error(
        "time_s,velocity_V\n0,1\n1 ,2\n2,3\n",
        &d,
        &["line 3", "'1 '", "spaces around"],
    );
    // NaN run of 3 in the index channel.
    record_error(
        "time_s,velocity_V,index_V\n0,1,0\n1,2,NaN\n2,3,nan\n3,4,inf\n4,5,0\n",
        &d,
        &["index_V", "NaN/inf", "line 3", "sample 1", "run of 3"],
    );
    // Empty cells up to the end.
    record_error(
        "time_s,velocity_V\n0,1\n1,2\n2,\n3,\n",
        &d,
        &[
            "velocity_V",
            "empty cells",
            "line 4",
            "run of 2",
            "end of the record",
        ],
    );
    // A blank line in the middle.
    record_error(
        "time_s,velocity_V\n0,1\n\n1,2\n",
        &d,
        &["line 3", "is empty"],
    );
    // Non-monotonic and non-uniform time.
    record_error(
        "time_s,velocity_V\n0,1\n1,2\n2,3\n2,4\n",
        &d,
        &["does not increase", "line 5", "sample 3"],
    );
    record_error(
        "time_s,velocity_V\n0,1\n1,2\n2,3\n3.01,4\n4,5\n",
        &d,
        &["not uniformly sampled", "line 5", "sample 3"],
    );
    // Truncated last line: missing a used field, missing an unused field.
    record_error(
        "time_s,velocity_V,index_V\n0,1,0\n1,2,0\n2,3",
        &d,
        &["line 4", "2 of 3 fields"],
    );
    record_error(
        "time_s,velocity_V,extra\n0,1,a\n1,2,b\n2,3",
        &d,
        &["last line (line 4)", "2 of 3 fields", "truncated"],
    );
    // Trailing blank lines are not a gap.
    let rec = read_text("time_s,velocity_V\n0,1\n1,2\n\n\n").unwrap();
    assert_eq!(rec.velocity, vec![1.0, 2.0]);
    // Binary junk.
    let (_d, p) = temp("junk.csv", b"\x7fELF\x02\x01\x01\0\0\0");
    let err = read(&p).unwrap_err();
    assert!(matches!(err, DmwError::Read { .. }), "{err}");
    // A missing file.
    assert!(matches!(
        read(Path::new("/nonexistent/x.csv")).unwrap_err(),
        DmwError::Read { .. }
    ));
}

/// A CSV record over several decode chunks (2^16 samples) with a partial last one. (It was a
/// million rows; 300 001 cross the same boundaries at a third of the test's time.)
#[test]
fn multi_chunk_csv() {
    let rec = record(300_001, 4e6, true, VelocityUnit::Volt);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.csv");
    write_ldv_text(&rec, &path).unwrap();
    let got = read(&path).unwrap();
    same_record(&got, &rec);
}
