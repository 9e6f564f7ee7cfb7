//! The `[calibrate.*]` stage: the fitted numbers agree with an independent evaluation through
//! the calibrated sweep, the in-band counts follow from the table, knobs stay in the models'
//! ranges, `hdi validate` rows, clean errors. (The fit itself — recovering known knob values,
//! the held-out set never reaching the objective — is tested in `dynamics::calibration`.)
use crate::common::*;

fn read_json(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

/// The test pipeline with `[simulate.improved_calibrated]` run at 8.5 nm only, the actuation of
/// the test calibration's two targets.
fn calibrated_sweep_at_8_5nm(p: &Project) {
    let cfg = p.config();
    let at = cfg.find("[simulate.improved_calibrated]").unwrap();
    let end = at + cfg[at..].find("\n\n").unwrap();
    let section = cfg[at..end]
        .replace(
            "actuation_start = \"0 nm\"\nactuation_stop = \"15 nm\"\nactuation_step = \"5 nm\"",
            "actuations = [\"8.5 nm\"]",
        )
        .lines()
        .filter(|l| !l.starts_with("histories"))
        .collect::<Vec<_>>()
        .join("\n");
    assert!(section.contains("actuations = [\"8.5 nm\"]"), "{section}");
    p.set_config(&format!("{}{}{}", &cfg[..at], section, &cfg[end..]));
}

#[test]
fn calibrated_numbers_match_an_independent_sweep_and_the_counts_match_the_table() {
    let p = Project::shipped();
    calibrated_sweep_at_8_5nm(&p);
    let o = p.run(&["run", "--only", "improved_calibrated"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = p.processed().join("improved_calibration");
    for f in [
        "calibration.parquet",
        "calibration.csv",
        "knobs.csv",
        "convergence.png",
        "residuals.png",
        "calibration.log",
    ] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    let r = read_json(&dir.join("result.json"));
    // The test pipeline fits dmw_scale to FHM and clearance at 8.5 nm (tests/common.rs).
    let fitted = r["fitted"].as_array().unwrap();
    assert_eq!(fitted.len(), 1);
    assert_eq!(fitted[0]["knob"], "dmw_scale");
    let scale = fitted[0]["value"].as_f64().unwrap();
    // Three evaluations cannot meet the simplex tolerance: the result must say so.
    assert_eq!(r["converged"], false);
    assert_eq!(r["convergence"]["reason"], "budget");

    // Independent evaluation: the calibrated sweep applies the fitted knobs through
    // `[simulate] calibration = …` (its own cases, cache keys and DMW scaling) and must give
    // the numbers the fit reported for the same actuation.
    let value = |id: &str| {
        r["calibrated"]["targets"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["id"] == id)
            .and_then(|t| t["value"].as_f64())
            .unwrap()
    };
    // One actuation, both continuation branches (docs/conventions.md): the fit's cases start
    // from the static equilibrium as the up-branch does.
    let sweep = csv_rows(&p.processed().join("improved_calibrated").join("sweep.csv"));
    assert_eq!(sweep.len(), 2);
    let up = sweep
        .iter()
        .find(|r| r["branch"] == "up")
        .expect("an up-branch row");
    let num = |k: &str| up[k].parse::<f64>().unwrap();
    assert_eq!(num("actuation_nm"), 8.5);
    let (c_fit, c_sweep) = (value("clearance_8.5nm") * 1e9, num("clearance_mean_nm"));
    assert!((c_fit - c_sweep).abs() < 1e-6, "{c_fit} vs {c_sweep}");
    let (f_fit, f_sweep) = (value("fhm_8.5nm"), num("vibration_percent"));
    assert!(
        (f_fit - f_sweep).abs() < 1e-6 * f_fit,
        "{f_fit} vs {f_sweep}"
    );
    // …and the DMW scale is not a no-op: the uncalibrated FHM at 8.5 nm differs unless the
    // fit stayed at 1.
    let f0 = r["defaults"]["targets"][1]["value"].as_f64().unwrap();
    if (scale - 1.0).abs() > 0.05 {
        assert!((f0 - f_fit).abs() > 0.01 * f0, "{f0} vs {f_fit}");
    }

    // In-band counts from the table: |after − published| ≤ tolerance, per set.
    let table = csv_rows(&dir.join("calibration.csv"));
    let ids: Vec<&str> = table.iter().map(|t| t["target"].as_str()).collect();
    assert_eq!(
        ids,
        [
            "clearance_8.5nm",
            "fhm_8.5nm",
            "regime_solid_start",
            "full_contact_onset",
            "touchdown_clearance"
        ]
    );
    let count = |set: &str, column: &str| {
        table
            .iter()
            .filter(|t| t["set"] == set)
            .filter(|t| {
                let (v, p, tol) = (&t[column], &t["published"], &t["tolerance"]);
                !v.is_empty()
                    && (v.parse::<f64>().unwrap() - p.parse::<f64>().unwrap()).abs()
                        <= tol.parse::<f64>().unwrap() * (1.0 + 1e-12)
            })
            .count() as u64
    };
    // The held-out targets are the selection set (the dissertation geometry) and the final
    // set (the optimised design); `held_out` counts both.
    assert!(table
        .iter()
        .all(|t| ["fitted", "selection", "final"].contains(&t["set"].as_str())));
    for key in ["targets", "defaults", "calibrated"] {
        assert_eq!(
            r["in_band"]["held_out"][key].as_u64().unwrap(),
            r["in_band"]["selection"][key].as_u64().unwrap()
                + r["in_band"]["final"][key].as_u64().unwrap(),
            "{key}"
        );
    }
    for (set, key) in [
        ("fitted", "fitted"),
        ("selection", "selection"),
        ("final", "final"),
    ] {
        let n = table.iter().filter(|t| t["set"] == set).count() as u64;
        assert_eq!(r["in_band"][key]["targets"], n, "{set}");
        assert_eq!(
            r["in_band"][key]["defaults"],
            count(set, "spec_defaults"),
            "{set}"
        );
        assert_eq!(
            r["in_band"][key]["calibrated"],
            count(set, "calibrated"),
            "{set}"
        );
    }
    // The held-out rows come from the sweep grid (0, 5, 10, 15 nm in the test pipeline):
    // full solid contact first at a grid point, the solid boundary halfway between two.
    let onset = table
        .iter()
        .find(|t| t["target"] == "full_contact_onset")
        .unwrap();
    if let Ok(v) = onset["spec_defaults"].parse::<f64>() {
        assert!(
            [0.0, 5.0, 10.0, 15.0].iter().any(|g| (g - v).abs() < 1e-9),
            "{v}"
        );
    }
    let solid = table
        .iter()
        .find(|t| t["target"] == "regime_solid_start")
        .unwrap();
    if let Ok(v) = solid["spec_defaults"].parse::<f64>() {
        assert!([2.5, 7.5, 12.5].iter().any(|g| (g - v).abs() < 1e-9), "{v}");
    }

    // `hdi validate` re-evaluates the fit now, one row per fitted target.
    let v = p.run(&["validate", "--only", "calibration", "--json"]);
    assert!(v.status.success(), "{}", stderr(&v));
    let j: serde_json::Value = serde_json::from_str(&stdout(&v)).unwrap();
    let rows = j["areas"]["calibration"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert!(rows[0]["variant"].as_str().unwrap().contains("dmw_scale"));
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
            // A held-out target cannot be fitted: it is not in the fitted catalogue.
            "targets = [\"clearance_8.5nm\", \"fhm_8.5nm\"]",
            "targets = [\"optimised_touchdown\"]",
            "unknown target `optimised_touchdown`",
        ),
        (
            "held_out = [\"regime_solid_start\"",
            "held_out = [\"fhm_8.5nm\"",
            "unknown held-out target `fhm_8.5nm`",
        ),
        (
            "knobs = [\"dmw_scale\"]",
            "knobs = [\"kr_stiffening_beta\"]\nbounds = { kr_stiffening_beta = [0.0, 5.0] }",
            "kr_stiffening_beta = 5e0 is outside the model's range",
        ),
        (
            "max_evaluations = 3\n",
            "max_evaluations = 3\nstart = { dmw_scale = 1.5 }\nstart_fitted_for = \"fit of 2024\"\n",
            "calibrate.improved_calibration.start_fitted_for",
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

/// The guard on the warm start (docs/calibration.md, "Warm start"): a `start` fitted for other
/// inputs is ignored — the run is the one without it, evaluation for evaluation — and one
/// fitted for these inputs is where the search starts.
#[test]
fn a_warm_start_is_used_only_for_the_inputs_it_was_fitted_for() {
    let p = Project::shipped();
    let base = p.config();
    let result = |p: &Project| {
        let o = p.run(&["run", "--only", "improved_calibration"]);
        assert!(o.status.success(), "{}", stderr(&o));
        read_json(
            &p.processed()
                .join("improved_calibration")
                .join("result.json"),
        )
    };
    let plain = result(&p);
    let fp = plain["convergence"]["fit_inputs"]
        .as_str()
        .unwrap()
        .to_string();
    assert_eq!(fp.len(), 16);
    assert_eq!(plain["convergence"]["warm_start"], "none");
    assert_eq!(plain["fitted"][0]["knob"], "dmw_scale");
    let f0 = plain["fitted"][0]["value"].as_f64().unwrap();
    let with_start = |fitted_for: &str| {
        base.replacen(
            "max_evaluations = 3\n",
            &format!(
                "max_evaluations = 3\nstart = {{ dmw_scale = {f0:?} }}\ninitial_step = 1e-3\n\
                 start_fitted_for = \"{fitted_for}\"\n"
            ),
            1,
        )
    };
    // Fitted for other inputs: ignored, recorded, and the fit is the plain one.
    let other = if fp.starts_with('0') { "1" } else { "0" }.repeat(16);
    p.set_config(&with_start(&other));
    let ignored = result(&p);
    let c = &ignored["convergence"];
    assert_eq!(c["warm_start"], "ignored");
    let why = c["start_ignored"].as_str().unwrap();
    assert!(why.contains(&fp) && why.contains(&other), "{why}");
    assert_eq!(
        c["fit_inputs"],
        fp.as_str(),
        "start keys are not fit inputs"
    );
    assert_eq!(c["start"], serde_json::json!([]));
    assert_eq!(c["initial_step"], 0.2);
    for k in ["fitted", "calibrated", "history", "evaluations", "cases"] {
        assert_eq!(ignored[k], plain[k], "{k}");
    }
    let log = std::fs::read_to_string(
        p.processed()
            .join("improved_calibration")
            .join("calibration.log"),
    )
    .unwrap();
    assert!(log.starts_with("WARNING: start_fitted_for"), "{log}");
    // Fitted for these inputs: the search starts there, so its first point is the plain
    // run's optimum (same objective) rather than the spec defaults.
    p.set_config(&with_start(&fp));
    let matched = result(&p);
    let c = &matched["convergence"];
    assert_eq!(c["warm_start"], "matched");
    assert!(c["start_ignored"].is_null());
    assert_eq!(c["start"][0]["value"].as_f64(), Some(f0));
    assert_eq!(c["initial_step"], 1e-3);
    assert_eq!(matched["history"][0][1], plain["calibrated"]["objective"]);
    assert_ne!(matched["history"][0][1], plain["history"][0][1]);
    assert!(
        matched["calibrated"]["objective"].as_f64() <= plain["calibrated"]["objective"].as_f64()
    );
    // Run to convergence: from the full fit's own optimum the search re-checks it in fewer
    // evaluations and ends no worse (within the f tolerance).
    p.set_config(&base.replacen("max_evaluations = 3\n", "max_evaluations = 60\n", 1));
    let full = result(&p);
    assert_eq!(full["converged"], true);
    assert_eq!(full["convergence"]["fit_inputs"], fp.as_str());
    let opt = full["fitted"][0]["value"].as_f64().unwrap();
    p.set_config(&base.replacen(
        "max_evaluations = 3\n",
        &format!(
            "max_evaluations = 60\nstart = {{ dmw_scale = {opt:?} }}\ninitial_step = 1e-3\n\
             start_fitted_for = \"{fp}\"\n"
        ),
        1,
    ));
    let warm = result(&p);
    assert_eq!(warm["convergence"]["warm_start"], "matched");
    assert_eq!(warm["converged"], true);
    let n = |r: &serde_json::Value| r["evaluations"].as_u64().unwrap();
    assert!(n(&warm) < n(&full), "{} vs {}", n(&warm), n(&full));
    let f = |r: &serde_json::Value| r["calibrated"]["objective"].as_f64().unwrap();
    assert!(f(&warm) <= f(&full) + 1e-3, "{} vs {}", f(&warm), f(&full));
}
