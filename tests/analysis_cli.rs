//! The Appendix-B study: excitations → slider cases → analyses, as pipeline stages and as
//! `hdi analyze`, and its clean errors.
use crate::common::*;

fn json_of(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_str(&stdout(o)).expect("one JSON object on stdout")
}

#[test]
fn a_sine_driven_slider_answers_at_the_sine_and_is_periodic() {
    // App. B on the 3-DOF slider (12 nm, S3) and the 2-DOF variant (5 nm).
    let p = Project::shipped();
    let o = p.run(&["run", "--only", "sine_response", "sine_response_2dof"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = p.processed().join("sine_response");
    for f in [
        "analysis.h5",
        "spectrum.png",
        "scalogram.png",
        "poincare.png",
        "phase_portrait.png",
    ] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("result.json")).unwrap()).unwrap();
    let s = &r["summary"];
    // One line at the excitation, one Poincaré point. The heave answers with less than the
    // disk's 1.414 nm: with the transit delay LE and TE see the disk 243° apart, so the
    // slider follows by pitching as well as heaving.
    let f = s["peaks"][0]["frequency_Hz"].as_f64().unwrap();
    let a = s["peaks"][0]["amplitude_nm"].as_f64().unwrap();
    assert!((f - 10.7e3).abs() < 0.01 * 10.7e3, "{f}");
    assert!(a > 0.3 && a < 1.414, "{a}");
    assert_eq!(s["class"], "periodic", "{s}");
    assert_eq!(s["period_sections"], 1, "{s}");
    let period = s["period_s"].as_f64().unwrap();
    assert!((period * 10.7e3 - 1.0).abs() < 0.01, "{period}");
    assert_matches_schema("analysis-result", &serde_json::to_string(&r).unwrap());
    let ridge = s["ridge_median_Hz"].as_f64().unwrap();
    assert!((ridge - 10.7e3).abs() < 0.05 * 10.7e3, "{ridge}");

    // The excitation's result states its parameters as data, SI (not a Rust Debug string):
    // 10.7 kHz and 1 nm RMS.
    let x: serde_json::Value = serde_json::from_slice(
        &std::fs::read(p.processed().join("sine").join("result.json")).unwrap(),
    )
    .unwrap();
    let sine = &x["params"]["sinusoid"];
    assert_eq!(sine["frequency"], serde_json::json!(10.7e3), "{x}");
    let rms = sine["rms"].as_f64().unwrap_or(f64::NAN);
    assert!((rms - 1e-9).abs() < 1e-21, "{x}");

    // The same case through `hdi analyze`: the same numbers.
    let case = p
        .processed()
        .join("sine_flight")
        .join("cases")
        .join("isbl.h5");
    let j = json_of(
        &hdi()
            .arg("analyze")
            .arg(&case)
            .args(["--window", "0.5 ms", "2 ms", "--json"])
            .output()
            .unwrap(),
    );
    assert_eq!(
        j["summary"]["peaks"][0]["frequency_Hz"],
        s["peaks"][0]["frequency_Hz"]
    );
    assert_eq!(j["summary"]["class"], s["class"]);
    assert_eq!(j["input"]["series"], "case/history/heave");

    // 10.7 kHz is far below the AB modes: the bulge tracks the disk, so its spacing moves far
    // less than the disk. 3-DOF bulge spacing: 0.26 nm, 18 % of the 1.414 nm disk motion;
    // 2-DOF clearance: 0.049 nm, 3 % (the quasi-static (10.7/110)² ≈ 1 % plus the pitch the
    // transit delay imposes).
    let line_at_sine = |case: &std::path::Path, dataset: &str| {
        let c = json_of(
            &hdi()
                .arg("analyze")
                .arg(case)
                .args(["--dataset", dataset, "--velocity", "none"])
                .args(["--window", "0.5 ms", "2 ms", "--json"])
                .output()
                .unwrap(),
        );
        c["summary"]["peaks"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| (p["frequency_Hz"].as_f64().unwrap() - 10.7e3).abs() < 200.0)
            .map_or(0.0, |p| p["amplitude_nm"].as_f64().unwrap())
    };
    let bulge = line_at_sine(&case, "case/history/bulge_spacing");
    assert!(
        bulge > 0.0 && bulge < 0.35,
        "3-DOF bulge-spacing modulation at 10.7 kHz {bulge} nm"
    );
    let case2 = p
        .processed()
        .join("sine_flight_2dof")
        .join("cases")
        .join("h_005.00nm.h5");
    let clearance = line_at_sine(&case2, "case/history/clearance");
    assert!(
        clearance > 0.0 && clearance < 0.1,
        "2-DOF clearance modulation at 10.7 kHz {clearance} nm"
    );
    let r2: serde_json::Value = serde_json::from_slice(
        &std::fs::read(p.processed().join("sine_response_2dof").join("result.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(r2["summary"]["class"], "periodic", "{r2}");
}

#[test]
fn analyze_errors_are_clear() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("series.h5");
    {
        // No HDF5 file lock: hdf5 opens without O_CLOEXEC, so an `hdi` child that another test
        // thread forks meanwhile inherits the descriptor, and with it the lock, until it exits.
        let f = hdf5::File::with_options()
            .with_fapl(|p| p.file_locking(false))
            .create(&path)
            .unwrap();
        let g = f.create_group("g").unwrap();
        let n = 4000;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / 4e6).collect();
        let mut x: Vec<f64> = t.iter().map(|t| (6.28e4 * t).sin()).collect();
        x[1234] = f64::NAN;
        let time = g
            .new_dataset_builder()
            .with_data(&t)
            .create("time")
            .unwrap();
        time.new_attr::<f64>()
            .create("sampling_rate")
            .unwrap()
            .write_scalar(&4e6)
            .unwrap();
        g.new_dataset_builder().with_data(&x).create("x").unwrap();
        let ok: Vec<f64> = t.iter().map(|t| (6.28e4 * t).sin()).collect();
        g.new_dataset_builder().with_data(&ok).create("ok").unwrap();
        drop((time, g));
        f.close().unwrap();
    }
    let run = |args: &[&str]| hdi().arg("analyze").arg(&path).args(args).output().unwrap();
    // No default series: the error lists what the file holds.
    assert_clean_failure(&run(&[]), "g/ok");
    assert_clean_failure(&run(&["--dataset", "g/nope"]), "no dataset `g/nope`");
    assert_clean_failure(
        &run(&["--dataset", "g/x"]),
        "non-finite value NaN at sample 1234",
    );
    assert_clean_failure(
        &run(&["--dataset", "g/ok", "--window", "0.1 ms", "0.101 ms"]),
        "too few",
    );
    assert_clean_failure(&run(&["--dataset", "g/ok", "--f-min", "2 MHz"]), "--f-min");
    let missing = hdi().args(["analyze", "nowhere.h5"]).output().unwrap();
    assert_clean_failure(&missing, "nowhere.h5: no such file");
    let o = run(&["--dataset", "g/ok", "--json"]);
    let j = json_of(&o);
    let f = j["summary"]["peaks"][0]["frequency_Hz"].as_f64().unwrap();
    assert!((f - 1e4).abs() < 200.0, "{f}");
    assert_matches_schema("analyze", &stdout(&o));
}

#[test]
fn bad_analysis_and_excitation_keys_name_the_key() {
    let p = Project::shipped();
    let base = p.config();
    for (from, to, needle) in [
        (
            "[analysis.sine_response_2dof]\nsource = \"sine_flight_2dof\"",
            "[analysis.sine_response_2dof]\nsource = \"sine_flite\"",
            "analysis.sine_response_2dof.source",
        ),
        (
            "[analysis.dmw_response_2dof]\nsource = \"dmw_flight_2dof\"",
            "[analysis.dmw_response_2dof]\nsource = \"dmw_flight_2dof\"\nactuation = \"7 nm\"",
            "has no case at 7 nm",
        ),
        (
            "kind = \"quadratic_chirp\"",
            "kind = \"quadratic_chirp\"\nband = [\"1 kHz\", \"2 kHz\"]",
            "not used by kind",
        ),
        (
            "frequency = \"10.7 kHz\"",
            "frequency = \"3 MHz\"",
            "excitation.sine.frequency",
        ),
    ] {
        let cfg = base.replacen(from, to, 1);
        assert_ne!(cfg, base, "{from}");
        p.set_config(&cfg);
        let o = p.run(&["run"]);
        assert_clean_failure(&o, needle);
    }
}

/// Issue 19's acceptance: the 12 kHz + 110 kHz two-tone (1.0 nm and 0.3 nm; 110/12 = 55/6,
/// period 0.5 ms) written by independent writers — Python's csv module, pyarrow (Arrow IPC
/// file, Feather v2 with LZ4, Parquet), numpy (.npy, structured and plain) and h5py (a `time`
/// dataset with no attribute, the series in nm; and a dimension scale in ms, the series in µm)
/// — is read by `hdi analyze` with both lines
/// within 1 % in amplitude, classified periodic with the 0.5 ms period, and its `--json`
/// validates against docs/schemas/analyze.json.
#[test]
fn a_two_tone_series_from_any_writer_is_periodic_with_both_lines() {
    let dir = tempfile::tempdir().unwrap();
    // 2 MHz for 5 ms: both tones on bins (200 Hz), so the Hann amplitudes are exact to
    // rounding; 10 periods of 0.5 ms.
    let script = r#"
import csv, sys, os
import numpy as np, pyarrow as pa, pyarrow.feather as feather, pyarrow.parquet as pq, h5py
d = sys.argv[1]
fs, n = 2e6, 10000
t = np.arange(n) / fs
x = 1.0e-9 * np.sin(2 * np.pi * 12e3 * t + 0.3) + 0.3e-9 * np.sin(2 * np.pi * 110e3 * t + 1.1)
with open(os.path.join(d, "two_tone.csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["time_s", "displacement_m"])
    for a, b in zip(t, x):
        w.writerow([repr(float(a)), repr(float(b))])
table = pa.table({"time_s": t, "displacement_m": x})
with pa.OSFile(os.path.join(d, "two_tone.arrow"), "wb") as sink:
    with pa.ipc.new_file(sink, table.schema) as writer:
        writer.write_table(table, max_chunksize=3000)
feather.write_feather(table, os.path.join(d, "two_tone.feather"))
pq.write_table(table, os.path.join(d, "two_tone.parquet"))
rec = np.zeros(n, dtype=[("time_s", "<f8"), ("displacement_m", "<f8")])
rec["time_s"], rec["displacement_m"] = t, x
np.save(os.path.join(d, "two_tone_structured.npy"), rec)
np.save(os.path.join(d, "two_tone_plain.npy"), (x * 1e9).astype("<f4"))
with h5py.File(os.path.join(d, "two_tone.h5"), "w") as f:
    g = f.create_group("measurement")
    g.create_dataset("time", data=t)
    g.create_dataset("displacement", data=x * 1e9).attrs["units"] = "nm"
with h5py.File(os.path.join(d, "two_tone_scale.h5"), "w") as f:
    s = f.create_dataset("seconds", data=t * 1e3)
    s.attrs["units"] = "ms"
    s.make_scale("time")
    x_ds = f.create_dataset("heave", data=x * 1e6)
    x_ds.attrs["unit"] = np.bytes_("um")
    x_ds.dims[0].attach_scale(s)
"#;
    let o = std::process::Command::new(python())
        .arg("-c")
        .arg(script)
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // (file, extra args, amplitude key, its unit per nm)
    let cases: &[(&str, &[&str], &str, f64)] = &[
        ("two_tone.csv", &[], "amplitude_nm", 1.0),
        ("two_tone.arrow", &[], "amplitude_nm", 1.0),
        ("two_tone.feather", &[], "amplitude_nm", 1.0),
        ("two_tone.parquet", &[], "amplitude_nm", 1.0),
        ("two_tone_structured.npy", &[], "amplitude_nm", 1.0),
        // No unit, no time axis: the values are nm as written; the rate is given.
        (
            "two_tone_plain.npy",
            &["--sample-rate", "2 MHz"],
            "amplitude",
            1.0,
        ),
        ("two_tone.h5", &[], "amplitude_nm", 1.0),
        // The time axis as a dimension scale in ms, the unit a fixed-length string.
        ("two_tone_scale.h5", &[], "amplitude_nm", 1.0),
    ];
    for (file, args, key, per_nm) in cases {
        let o = hdi()
            .arg("analyze")
            .arg(dir.path().join(file))
            .args(*args)
            .arg("--json")
            .output()
            .unwrap();
        let text = stdout(&o);
        let j = json_of(&o);
        assert_matches_schema("analyze", &text);
        let s = &j["summary"];
        assert!(
            (s["sample_rate_Hz"].as_f64().unwrap() - 2e6).abs() < 1e-6 * 2e6,
            "{file}: {s}"
        );
        for (f, a) in [(12e3, 1.0), (110e3, 0.3)] {
            let p = s["peaks"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| (p["frequency_Hz"].as_f64().unwrap() - f).abs() < 1e-3 * f)
                .unwrap_or_else(|| panic!("{file}: no line at {f} Hz: {s}"));
            let got = p[*key].as_f64().unwrap() / per_nm;
            assert!((got - a).abs() < 0.01 * a, "{file}: {f} Hz reads {got} nm");
        }
        assert_eq!(s["class"], "periodic", "{file}: {s}");
        let period = s["period_s"].as_f64().unwrap();
        assert!((period - 0.5e-3).abs() < 1e-6 * 0.5e-3, "{file}: {period}");
        let lines = &s["evidence"]["spectral_lines"];
        assert!(
            (lines["fundamental_Hz"].as_f64().unwrap() - 2e3).abs() < 0.01,
            "{file}: {lines}"
        );
        assert_eq!(lines["lowest_harmonic"], 6, "{file}");
    }
    // The text output names the series, the rate's origin and the class.
    let o = hdi()
        .arg("analyze")
        .arg(dir.path().join("two_tone.csv"))
        .output()
        .unwrap();
    assert_ok(&o);
    let text = stdout(&o);
    assert!(
        text.contains("displacement_m") && text.contains("time column `time_s`"),
        "{text}"
    );
    assert!(
        text.contains("periodic") && text.contains("0.500000 ms"),
        "{text}"
    );
}
