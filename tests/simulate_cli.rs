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
    assert_eq!(first["cases"].as_array().unwrap().len(), 4);
    assert_eq!(first["cases_cached"], 0);
    for f in [
        "sweep.parquet",
        "sweep.csv",
        "clearance_sweep.png",
        "vibration_sweep.png",
        "solid_contact_sweep.png",
        "cases/h_010.00nm.h5",
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
    assert_eq!(second["cases"].as_array().unwrap().len(), 3);
    assert_eq!(second["cases_cached"], 2, "{second}");
    // gc keeps the cases the current sweep lists.
    let o = p.run(&["gc"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = p.run(&["run", "--only", "improved_sweep", "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(read(&p)["cases_cached"], 3);
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
