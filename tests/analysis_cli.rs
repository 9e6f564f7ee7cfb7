//! The Appendix-B study: excitations → slider cases → analyses, as pipeline stages and as
//! `hdi analyze`, and its clean errors.
use crate::common::*;

fn json_of(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_str(&stdout(o)).expect("one JSON object on stdout")
}

#[test]
fn a_sine_driven_slider_answers_at_the_sine_and_is_periodic() {
    let p = Project::shipped();
    let o = p.run(&["run", "--only", "sine_response"]);
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
    assert_eq!(s["class"], "periodic (period 1)", "{s}");
    let ridge = s["ridge_median_Hz"].as_f64().unwrap();
    assert!((ridge - 10.7e3).abs() < 0.05 * 10.7e3, "{ridge}");

    // The same case through `hdi analyze`: the same numbers.
    let case = p
        .processed()
        .join("sine_flight")
        .join("cases")
        .join("h_005.00nm.h5");
    let j = json_of(
        &hdi()
            .arg("analyze")
            .arg(&case)
            .args(["--window", "0.5 ms", "2 ms", "--json"])
            .output()
            .unwrap(),
    );
    assert_eq!(j["peaks"][0]["frequency_Hz"], s["peaks"][0]["frequency_Hz"]);
    assert_eq!(j["class"], s["class"]);

    // 10.7 kHz is far below the AB modes: the bulge tracks the disk, so the clearance barely
    // moves — 0.049 nm, 3 % of the 1.414 nm disk motion (the quasi-static (10.7/110)² ≈ 1 %
    // plus the pitch the transit delay imposes).
    let c = json_of(
        &hdi()
            .arg("analyze")
            .arg(&case)
            .args(["--dataset", "case/history/clearance", "--velocity", "none"])
            .args(["--window", "0.5 ms", "2 ms", "--json"])
            .output()
            .unwrap(),
    );
    let line = c["peaks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| (p["frequency_Hz"].as_f64().unwrap() - 10.7e3).abs() < 200.0)
        .map_or(0.0, |p| p["amplitude_nm"].as_f64().unwrap());
    assert!(
        line > 0.0 && line < 0.1,
        "clearance modulation at 10.7 kHz {line} nm"
    );
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
    let f = j["peaks"][0]["frequency_Hz"].as_f64().unwrap();
    assert!((f - 1e4).abs() < 200.0, "{f}");
}

#[test]
fn bad_analysis_and_excitation_keys_name_the_key() {
    let p = Project::shipped();
    let base = p.config();
    for (from, to, needle) in [
        (
            "[analysis.sine_response]\nsource = \"sine_flight\"",
            "[analysis.sine_response]\nsource = \"sine_flite\"",
            "analysis.sine_response.source",
        ),
        (
            "[analysis.dmw_response]\nsource = \"dmw_flight\"",
            "[analysis.dmw_response]\nsource = \"dmw_flight\"\nactuation = \"7 nm\"",
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
