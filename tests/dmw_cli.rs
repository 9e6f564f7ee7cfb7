//! `hdi dmw FILE` and the DMW stage in the pipeline: formats, JSON contract, bad input,
//! caching.

use crate::common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn synth(dir: &Path, format: &str, revolutions: usize, extra: &[&str]) -> PathBuf {
    let o = hdi()
        .args(["synth", "ldv", "--format", format, "--revolutions"])
        .arg(revolutions.to_string())
        .arg("--out-dir")
        .arg(dir)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "synth failed: {}", stderr(&o));
    PathBuf::from(stdout(&o).lines().next().unwrap().trim())
}

fn dmw_json(file: &Path, extra: &[&str]) -> Value {
    let o = hdi()
        .arg("dmw")
        .arg(file)
        .args(extra)
        .arg("--json")
        .output()
        .unwrap();
    assert!(o.status.success(), "hdi dmw failed: {}", stderr(&o));
    serde_json::from_str(&stdout(&o)).expect("one JSON object on stdout")
}

#[test]
fn every_format_gives_the_same_tracks_in_si_units() {
    let dir = tempfile::tempdir().unwrap();
    let mut results = Vec::new();
    for format in ["csv", "parquet", "h5-f64", "h5"] {
        let sub = dir.path().join(format);
        let f = synth(&sub, format, 4, &[]);
        let j = dmw_json(&f, &["--rpm", "5425"]);
        assert_eq!(j["n_avg"], 4, "{format}: {j}");
        assert_eq!(j["sample_rate_Hz"], 4e6);
        assert_eq!(j["n_samples"], 10_000);
        assert_eq!(j["segmentation"], "index channel");
        let std = j["dmw_std_m"].as_f64().unwrap();
        // Metres: the synthetic disk's high-passed DMW is about 0.73 nm; 4 revolutions leave
        // more noise than 100 do.
        assert!(std > 0.5e-9 && std < 1.2e-9, "{format}: {std}");
        let f0 = j["dominant_frequency_Hz"].as_f64().unwrap();
        // Harmonic 118 of 90.42 Hz: 10.67 kHz.
        assert!((f0 - 10_669.0).abs() < 60.0, "{format}: {f0}");
        let period = j["period_mean_s"].as_f64().unwrap();
        assert!((period * 5425.0 / 60.0 - 1.0).abs() < 1e-3, "{period}");
        results.push(std);
    }
    // Text, Parquet and f64 HDF5 hold the same numbers; int16 counts differ by quantisation.
    assert!(
        (results[0] - results[1]).abs() < 1e-6 * results[0],
        "{results:?}"
    );
    assert!(
        (results[0] - results[2]).abs() < 1e-6 * results[0],
        "{results:?}"
    );
    assert!(
        (results[0] - results[3]).abs() < 2e-2 * results[0],
        "{results:?}"
    );
}

#[test]
fn out_writes_hdf5_that_h5py_reads_with_flipped_tracks() {
    let dir = tempfile::tempdir().unwrap();
    let f = synth(dir.path(), "h5", 3, &[]);
    let out = dir.path().join("res").join("dmw.h5");
    let o = hdi()
        .arg("dmw")
        .arg(&f)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("DMW") && text.contains("kHz"), "{text}");
    for png in ["tracks.png", "spectrum.png"] {
        assert!(dir.path().join("res").join(png).is_file(), "{png}");
    }
    let script = r#"
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], 'r') as h:
    g = h['dmw/tracks']
    assert g.attrs['signal'] == 'D1'
    d1, d2, d3 = g['D1'][()], g['D2'][()], g['D3'][()]
    v1, v2, v3 = g['V1'][()], g['V2'][()], g['V3'][()]
    assert np.array_equal(d2, d1[::-1]) and np.array_equal(d3, -d2)
    assert np.array_equal(v2, -v1[::-1]) and np.array_equal(v3, -v2)
    assert g['D1'].attrs['units'] == 'm' and g['V1'].attrs['units'] == 'm/s'
    assert g['time'].attrs['units'] == 's'
    assert h['dmw/average/voltage'].attrs['units'] == 'V'
    assert h['dmw/spectrum/frequency'].attrs['units'] == 'Hz'
    assert h['dmw/qa/n_avg'][()] == 3
    assert 0.3e-9 < h['dmw/qa/dmw_std'][()] < 1.5e-9
    edge = g['edge_transient'][()]
    assert edge[0] == 1 and edge[5000] == 0 and edge.sum() == 2400
print('ok')
"#;
    let py = std::process::Command::new(python())
        .args(["-c", script])
        .arg(&out)
        .output()
        .unwrap();
    assert!(py.status.success(), "python: {}", stderr(&py));
}

#[test]
fn no_index_needs_the_spindle_speed() {
    let dir = tempfile::tempdir().unwrap();
    let f = synth(dir.path(), "csv", 3, &["--no-index"]);
    // The generator states the spindle speed in a comment line; a bare record does not.
    let text = std::fs::read_to_string(&f).unwrap();
    let bare: Vec<&str> = text.lines().filter(|l| !l.starts_with("# rpm")).collect();
    std::fs::write(&f, bare.join("\n")).unwrap();
    let o = hdi().arg("dmw").arg(&f).arg("--json").output().unwrap();
    assert_clean_failure(&o, "no index");
    let j = dmw_json(&f, &["--rpm", "5425"]);
    assert_eq!(j["segmentation"], "spindle speed");
    assert!(j["warnings"].to_string().contains("spindle speed"));
}

#[test]
fn bad_records_fail_cleanly_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let csv = synth(&dir.path().join("c"), "csv", 2, &[]);
    let text = std::fs::read_to_string(&csv).unwrap();

    // Truncated mid-row: a row cut inside its velocity field (time present, index missing).
    let cut = dir.path().join("truncated.csv");
    let line_start = text[text.len() / 2..].find('\n').unwrap() + text.len() / 2 + 1;
    let comma = text[line_start..].find(',').unwrap() + line_start;
    std::fs::write(&cut, &text[..comma + 3]).unwrap();
    let o = hdi().arg("dmw").arg(&cut).output().unwrap();
    assert_clean_failure(&o, "truncated.csv");

    // Time going backwards.
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header_rows = lines
        .iter()
        .take_while(|l| !l.starts_with(|c: char| c.is_ascii_digit() || c == '-'))
        .count();
    lines.swap(header_rows + 1000, header_rows + 1001);
    let back = dir.path().join("backwards.csv");
    std::fs::write(&back, lines.join("\n")).unwrap();
    let o = hdi().arg("dmw").arg(&back).output().unwrap();
    assert_clean_failure(&o, "backwards.csv");
    assert!(stderr(&o).contains("does not increase"), "{}", stderr(&o));

    // A run of NaNs in the velocity channel.
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    for l in lines.iter_mut().skip(header_rows + 500).take(20) {
        let mut cols: Vec<&str> = l.split(',').collect();
        cols[1] = "NaN";
        *l = cols.join(",");
    }
    let nan = dir.path().join("nan.csv");
    std::fs::write(&nan, lines.join("\n")).unwrap();
    let o = hdi().arg("dmw").arg(&nan).output().unwrap();
    assert_clean_failure(&o, "nan.csv");

    // Truncated binary formats.
    for format in ["parquet", "h5"] {
        let f = synth(&dir.path().join(format), format, 2, &[]);
        let bytes = std::fs::read(&f).unwrap();
        let cut = dir.path().join(format!("cut.{format}"));
        std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
        let o = hdi().arg("dmw").arg(&cut).output().unwrap();
        assert_clean_failure(&o, &format!("cut.{format}"));
    }

    // Missing file, empty file, out-of-range options.
    let o = hdi().args(["dmw", "no/such/record.csv"]).output().unwrap();
    assert_clean_failure(&o, "no/such/record.csv");
    let empty = dir.path().join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    let o = hdi().arg("dmw").arg(&empty).output().unwrap();
    assert_clean_failure(&o, "empty.csv");
    let o = hdi()
        .arg("dmw")
        .arg(&csv)
        .args(["--highpass-hz=-5 kHz"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "--highpass-hz");
    let o = hdi()
        .arg("dmw")
        .arg(&csv)
        .args(["--sample-rate", "3 MHz"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "sample rate");
}

#[test]
fn pipeline_caches_dmw_and_a_cutoff_change_reruns_only_dmw() {
    let p = Project::shipped();
    let o = p.run(&["run", "--only", "disk_md"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let proc = p.processed();
    for f in [
        "disk_md/dmw.h5",
        "disk_md/tracks.png",
        "disk_md/spectrum.png",
        "tables/dmw.parquet",
        "tables/dmw.csv",
    ] {
        assert!(proc.join(f).is_file(), "missing {f}");
    }
    let o = p.run(&["run", "--only", "disk_md"]);
    assert!(stderr(&o).contains("nothing to do"), "{}", stderr(&o));

    let cfg = p
        .config()
        .replace("# highpass_hz = \"10 kHz\"", "highpass_hz = \"20 kHz\"");
    assert_ne!(cfg, p.config());
    p.set_config(&cfg);
    let st = p.run(&["status"]);
    let s = stdout(&st);
    assert!(s.contains("stale    disk_md"), "{s}");
    let o = p.run(&["run", "--only", "disk_md"]);
    let e = stderr(&o);
    assert!(o.status.success() && e.contains("ran     disk_md"), "{e}");
    // The surfaces were never part of it and stay untouched.
    assert!(!e.contains("ran     disk\n"), "{e}");
}

#[test]
fn a_misspelt_dmw_key_names_file_line_and_the_nearest_key() {
    let p = Project::shipped();
    let cfg = p.config().replace("rpm = 5425 ", "rmp = 5425 ");
    assert_ne!(cfg, p.config());
    p.set_config(&cfg);
    let o = p.run(&["run"]);
    assert_clean_failure(&o, "pipeline.toml:");
    let e = stderr(&o);
    assert!(e.contains("rmp") && e.contains("did you mean `rpm`"), "{e}");
}

#[test]
fn validate_reports_every_dmw_row_as_passing() {
    let o = hdi()
        .args(["validate", "--only", "dmw", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let j: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(j["failed"], 0);
    let rows = j["areas"]["dmw"].as_array().unwrap();
    assert!(rows.len() >= 20);
    for r in rows {
        assert_eq!(r["pass"], true, "{r}");
        assert!(r["variant"].is_string() && r["reference"].is_string() && r["class"] == "G");
    }
    let o = hdi()
        .args(["validate", "--only", "nonsense"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "unknown area");
}
