//! `hdi simulate` ad hoc and the `[simulate.*]` stage: published flying clearance, contact at
//! high actuation, one cached case per actuation, and clean errors.
use crate::common::*;

fn json_of(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_str(&stdout(o)).expect("one JSON object on stdout")
}

#[test]
fn ad_hoc_cases_land_on_the_published_clearance_and_contact() {
    let o = hdi()
        .args([
            "simulate",
            "--actuation",
            "8.5 nm",
            "12 nm",
            "--duration",
            "1 ms",
            "--json",
        ])
        .output()
        .unwrap();
    let j = json_of(&o);
    let cases = j["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 2);
    // docs/validation.md (class K): c = 2.54 nm at 8.5 nm, ±0.05 nm; no DMW here.
    let c85 = cases[0]["clearance_mean_nm"].as_f64().unwrap();
    assert!((c85 - 2.54).abs() < 0.05, "{c85}");
    assert_eq!(cases[0]["regime"], "flying");
    // 12 nm: steady solid contact with friction above the contact force (μ > 1).
    assert_eq!(cases[1]["regime"], "solid contact");
    assert!(cases[1]["friction_coefficient"].as_f64().unwrap() > 1.0);
}

#[test]
fn interface_overrides_reach_the_cases() {
    // Δγ → 0 removes the adhesion; the 12 nm contact then sits less deep (0.63 vs 0.80 nm).
    let run = |extra: &[&str]| {
        let o = hdi()
            .args(["simulate", "--init", "static", "--duration", "0.6 ms"])
            .args(["--steady-start", "0.3 ms", "--actuation", "12 nm", "--json"])
            .args(extra)
            .output()
            .unwrap();
        json_of(&o)["cases"][0].clone()
    };
    let default = run(&[]);
    let no_adhesion = run(&["--surface-energy", "0.1 mN/m"]);
    assert!(no_adhesion["adhesion_mean_mN"].as_f64().unwrap() < 0.01);
    let (c0, c1) = (
        default["clearance_mean_nm"].as_f64().unwrap(),
        no_adhesion["clearance_mean_nm"].as_f64().unwrap(),
    );
    assert!(c1 > c0 + 0.1, "{c0} {c1}");
}

#[test]
fn bad_simulation_input_is_a_clean_error() {
    let run = |args: &[&str]| hdi().arg("simulate").args(args).output().unwrap();
    assert_clean_failure(&run(&["--actuation", "20 nm"]), "--actuation:");
    assert_clean_failure(&run(&["--integrator", "euler"]), "--integrator");
    assert_clean_failure(&run(&["--dmw", "no/such/dmw.h5"]), "no/such/dmw.h5");
    assert_clean_failure(&run(&["--rtol", "-1"]), "--rtol");
    assert_clean_failure(&run(&["--model", "5dof"]), "--model");
    assert_clean_failure(&run(&["--contact-set", "nope"]), "--contact-set");
    assert_clean_failure(&run(&["--surface-energy", "lots"]), "--surface-energy");
}

#[test]
fn pipeline_sweep_caches_each_case() {
    let p = Project::shipped();
    let o = p.run(&["run", "--only", "improved_sweep"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let read = |p: &Project| -> serde_json::Value {
        let r = std::fs::read(p.processed().join("improved_sweep").join("result.json")).unwrap();
        serde_json::from_slice(&r).unwrap()
    };
    let first = read(&p);
    // init = "static": an up and a down branch of 4 cases each (docs/conventions.md).
    assert_eq!(first["cases"].as_array().unwrap().len(), 8);
    // Cold store: nothing cached, except that a case both branches share (same key) may be
    // found by the second of two parallel jobs once the first stored it.
    let shared = |r: &serde_json::Value| {
        let keys = r["case_keys"].as_array().unwrap();
        let unique: std::collections::BTreeSet<&str> =
            keys.iter().map(|k| k.as_str().unwrap()).collect();
        (keys.len() - unique.len()) as u64
    };
    assert!(cases_cached(&p.processed().join("improved_sweep")) <= shared(&first));
    assert!(
        first.get("cases_cached").is_none(),
        "a run fact in the results"
    );
    let branches: Vec<&str> = first["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["branch"].as_str().unwrap())
        .collect();
    assert_eq!(
        branches,
        ["up", "up", "up", "up", "down", "down", "down", "down"]
    );
    assert!(first["hysteresis"]["tolerance_m"].as_f64().unwrap() > 0.0);
    for f in [
        "sweep.parquet",
        "sweep.csv",
        "clearance_sweep.png",
        "vibration_sweep.png",
        "solid_contact_sweep.png",
        "cases/h_010.00nm.h5",
        "cases/down/h_010.00nm.h5",
    ] {
        assert!(p.processed().join("improved_sweep").join(f).exists(), "{f}");
    }
    // Another sweep sharing two actuations: only the new cases run.
    let text = p.config().replace(
        "actuation_step = \"5 nm\"",
        "actuations = [\"5 nm\", \"10 nm\", \"12 nm\"]",
    );
    p.set_config(&text);
    let o = p.run(&["run", "--only", "improved_sweep"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let second = read(&p);
    assert_eq!(second["cases"].as_array().unwrap().len(), 6);
    // 5 and 10 nm of both branches: each branch reaches them along the same path (up from
    // below, down from deep contact), so their continuation starts and case keys are the same.
    let cached = cases_cached(&p.processed().join("improved_sweep"));
    assert!(
        (4..=4 + shared(&second)).contains(&cached),
        "{cached} cached: {second}"
    );
    // gc keeps the cases the current sweep lists.
    let o = p.run(&["gc"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = p.run(&["run", "--only", "improved_sweep", "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(cases_cached(&p.processed().join("improved_sweep")), 6);
}

#[test]
fn bad_simulate_keys_name_the_key_and_line() {
    let p = Project::shipped();
    let before = snapshot(&p.processed());
    for (from, to, needle) in [
        (
            "contact = \"improved\"",
            "contact = \"nope\"",
            "simulate.improved_sweep.contact",
        ),
        (
            "actuation_stop = \"15 nm\"",
            "actuation_stop = \"25 nm\"",
            "simulate.improved_sweep.actuation_stop",
        ),
        (
            "init = \"static\"",
            "init = \"static\"\nintegrater = \"dopri5\"",
            "integrater",
        ),
        (
            "init = \"static\"",
            "init = \"static\"\nbranches = \"sideways\"",
            "simulate.improved_sweep.branches",
        ),
        (
            "init = \"static\"",
            "init = \"nominal\"\nbranches = \"up\"",
            "simulate.improved_sweep.branches",
        ),
        (
            "init = \"static\"",
            "init = \"static\"\nlubricant = \"grease\"",
            "simulate.improved_sweep.lubricant",
        ),
    ] {
        let text = p.config();
        assert!(text.contains(from), "{from}");
        p.set_config(&text.replacen(from, to, 1));
        let o = p.run(&["run"]);
        assert_clean_failure(&o, needle);
        assert!(stderr(&o).contains("pipeline.toml"), "{}", stderr(&o));
        p.set_config(&text);
    }
    assert_eq!(snapshot(&p.processed()), before);
}

/// Touchdown by the convention (docs/conventions.md): the sweep's grid is the scan, the first
/// crossing is refined to 0.02 nm with extra cases, each of which is recorded; the refined
/// bracket must be consistent with those cases (the touching end touches, the flying end
/// flies) and lie inside the grid bracket.
#[test]
fn sweep_touchdown_is_refined_to_the_convention() {
    let p = Project::shipped();
    let text = p.config().replacen(
        "actuation_start = \"0 nm\"\nactuation_stop = \"15 nm\"\nactuation_step = \"5 nm\"\nrefine_touchdown = false",
        "actuation_start = \"9 nm\"\nactuation_stop = \"11 nm\"\nactuation_step = \"0.5 nm\"\nbranches = \"up\"",
        1,
    );
    assert!(text.contains("branches = \"up\""));
    p.set_config(&text);
    let o = p.run(&["run", "--only", "improved_sweep"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(
        &std::fs::read(p.processed().join("improved_sweep").join("result.json")).unwrap(),
    )
    .unwrap();
    let td = &r["sweep"]["touchdown_convention"];
    let grid_td = r["sweep"]["touchdown_m"]
        .as_f64()
        .expect("the sweep touches");
    let (a, lo) = (
        td["actuation_m"].as_f64().unwrap(),
        td["last_flying_m"].as_f64().unwrap(),
    );
    assert!(a - lo <= 0.02e-9 * (1.0 + 1e-9) && a > lo, "{td}");
    assert!(
        a <= grid_td + 1e-15 && a > grid_td - 0.5e-9 - 1e-15,
        "{a} vs grid {grid_td}"
    );
    let extra = td["extra_cases"].as_array().unwrap();
    assert!(!extra.is_empty() && extra.len() <= 9, "{extra:?}");
    let touches_at = |x: f64| -> Option<bool> {
        extra
            .iter()
            .find(|c| (c["actuation_m"].as_f64().unwrap() - x).abs() < 1e-15)
            .map(|c| c["solid_contact_percent"].as_f64().unwrap() > 0.0)
    };
    // Both ends are extra cases unless an end is a grid point.
    if let Some(t) = touches_at(a) {
        assert!(t, "{a}");
    }
    if let Some(t) = touches_at(lo) {
        assert!(!t, "{lo}");
    }
    assert_eq!(r["sweep"]["branch"], "up");
}
