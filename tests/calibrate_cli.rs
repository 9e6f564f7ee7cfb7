//! The `[calibrate.*]` stage: a fit that never ends worse than the spec defaults, knobs that
//! stay in their bounds, a calibrated sweep that uses them, `hdi validate` rows, clean errors.
use crate::common::*;

fn read_json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

#[test]
fn calibration_fits_within_bounds_and_feeds_the_calibrated_sweeps() {
    let p = Project::shipped();
    let o = p.run(&["run", "--only", "improved_calibrated"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = p.processed().join("improved_calibration");
    for f in [
        "calibration.parquet",
        "calibration.csv",
        "knobs.csv",
        "convergence.png",
        "residuals.png",
    ] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    let r = read_json(&dir.join("result.json"));
    // The test pipeline fits dmw_scale to FHM and clearance at 8.5 nm (tests/common.rs).
    let fitted = r["fitted"].as_array().unwrap();
    assert_eq!(fitted.len(), 1);
    assert_eq!(fitted[0]["knob"], "dmw_scale");
    let scale = fitted[0]["value"].as_f64().unwrap();
    assert!((0.25..=4.0).contains(&scale), "{scale}");
    // Nelder–Mead keeps the start point in its simplex: never worse than the defaults.
    let (before, after) = (
        r["defaults"]["objective"].as_f64().unwrap(),
        r["calibrated"]["objective"].as_f64().unwrap(),
    );
    assert!(after <= before, "{after} > {before}");
    // The defaults row is the uncalibrated model: FHM at 8.5 nm with the shipped DMW.
    let fhm0 = r["defaults"]["targets"][1]["value"].as_f64().unwrap();
    assert!(fhm0 > 1.0 && fhm0 < 20.0, "{fhm0}");

    // The calibrated sweep ran with the fitted knobs…
    let s = read_json(
        &p.processed()
            .join("improved_calibrated")
            .join("result.json"),
    );
    assert_eq!(s["calibration"], "improved_calibration");
    assert_eq!(s["calibrated_knobs"][0]["knob"], "dmw_scale");
    assert_eq!(s["calibrated_knobs"][0]["value"].as_f64().unwrap(), scale);

    // …and `hdi validate` re-evaluates the fit now, one row per target.
    let v = p.run(&["validate", "--only", "calibration", "--json"]);
    assert!(v.status.success(), "{}", stderr(&v));
    let j: serde_json::Value = serde_json::from_str(&stdout(&v)).unwrap();
    let rows = j["areas"]["calibration"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert!(rows[0]["variant"].as_str().unwrap().contains("dmw_scale"));
    let fhm = rows[1]["value"].as_f64().unwrap();
    let stored = r["calibrated"]["targets"][1]["value"].as_f64().unwrap();
    assert!(
        (fhm - stored).abs() < 1e-9 * stored.abs().max(1.0),
        "{fhm} vs {stored}"
    );
}

#[test]
fn validate_says_when_a_calibration_has_not_run() {
    let p = Project::shipped();
    let v = p.run(&["validate", "--only", "calibration"]);
    assert!(v.status.success(), "{}", stderr(&v));
    assert!(
        stdout(&v).contains("hdi run --only improved_calibration"),
        "{}",
        stdout(&v)
    );
}

#[test]
fn bad_calibration_settings_name_the_key() {
    let p = Project::shipped();
    let base = p.config();
    for (from, to, needle) in [
        (
            "max_evaluations = 3\n",
            "max_evaluations = 3\nbounds = { lj_spacing = [1e-9, 1e-10] }\n",
            "calibrate.improved_calibration.bounds",
        ),
        (
            "knobs = [\"dmw_scale\"]",
            "knobs = [\"dmw_scal\"]",
            "unknown knob `dmw_scal`",
        ),
        (
            "targets = [\"clearance_8.5nm\", \"fhm_8.5nm\"]",
            "targets = [\"touchdown_9nm\"]",
            "unknown target `touchdown_9nm`",
        ),
        (
            "calibration = \"improved_calibration\"\nmodel = \"improved_2dof\"\ncontact",
            "calibration = \"nope\"\nmodel = \"improved_2dof\"\ncontact",
            "no [calibrate.nope]",
        ),
    ] {
        let cfg = base.replacen(from, to, 1);
        assert_ne!(cfg, base, "{from}");
        p.set_config(&cfg);
        let o = p.run(&["run"]);
        assert_clean_failure(&o, needle);
        assert!(stderr(&o).contains("pipeline.toml"), "{}", stderr(&o));
    }
}
