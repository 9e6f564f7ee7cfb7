//! `hdi bench` (docs/performance.md, bench/README.md): its `--json` output against
//! docs/schemas/bench.json (Python jsonschema), the counts it reports against the inputs it was
//! given (arrays written by numpy, an independent writer), the arithmetic of the per-step
//! figure, and clean errors on bad options and inputs. Nothing here asserts a timing: the
//! values are wall times of a loaded machine and a debug build.

use crate::common::*;
use serde_json::Value;
use std::path::Path;

/// Write `.npy` arrays with numpy: `sig.npy` (f8, 4096 samples), `map.npy` (f8, 64 × 48),
/// `map_f.npy` (f4, Fortran order, 40 × 24), `ints.npy` (i8) and `bad.npy` (a NaN).
fn write_arrays(dir: &Path) {
    let script = r#"
import numpy as np, sys, os
d = sys.argv[1]
rng = np.random.default_rng(3)
np.save(os.path.join(d, "sig.npy"), rng.standard_normal(4096))
np.save(os.path.join(d, "map.npy"), 1e-9 * rng.standard_normal((64, 48)))
np.save(os.path.join(d, "map_f.npy"), np.asfortranarray(1e-9 * rng.standard_normal((40, 24)).astype(np.float32)))
np.save(os.path.join(d, "ints.npy"), np.arange(100, dtype=np.int64))
x = rng.standard_normal(100); x[7] = np.nan
np.save(os.path.join(d, "bad.npy"), x)
"#;
    let o = std::process::Command::new(python())
        .arg("-c")
        .arg(script)
        .arg(dir)
        .output()
        .expect("python");
    assert_ok(&o);
}

/// `hdi bench ARGS --json` in `dir`: the validated document.
fn bench_json(dir: &Path, args: &[&str]) -> Value {
    let o = hdi()
        .current_dir(dir)
        .arg("bench")
        .args(args)
        .arg("--json")
        .output()
        .expect("run hdi bench");
    assert_ok(&o);
    let text = stdout(&o);
    assert_matches_schema("bench", &text);
    serde_json::from_str(&text).expect("one JSON document")
}

fn only_figure(v: &Value) -> &Value {
    let figs = v["figures"].as_array().unwrap();
    assert_eq!(figs.len(), 1, "{v}");
    &figs[0]
}

#[test]
fn bench_kernels_on_given_npy_inputs_report_their_sizes() {
    let dir = tempfile::tempdir().unwrap();
    write_arrays(dir.path());
    let p = |f: &str| dir.path().join(f).to_string_lossy().into_owned();

    let v = bench_json(
        dir.path(),
        &["--only", "fft", "--input", &p("sig.npy"), "--repeat", "2"],
    );
    assert_eq!(v["input"], p("sig.npy"));
    let f = only_figure(&v);
    assert_eq!(f["group"], "fft");
    assert_eq!(f["details"]["samples"], 4096);
    assert_eq!(f["unit"], "s");
    assert_eq!(
        (f["statistic"].as_str(), f["repeats"].as_u64()),
        (Some("best"), Some(2))
    );
    // best ≤ median by definition of both.
    assert!(f["value"].as_f64().unwrap() <= f["median"].as_f64().unwrap());

    let v = bench_json(
        dir.path(),
        &["--only", "cwt", "--input", &p("sig.npy"), "--repeat", "1"],
    );
    let f = only_figure(&v);
    assert_eq!(f["group"], "cwt");
    assert_eq!(f["details"]["samples"], 4096);
    assert_eq!(f["details"]["frequencies"], 100);

    let v = bench_json(
        dir.path(),
        &[
            "--only",
            "roughness",
            "--input",
            &p("map.npy"),
            "--repeat",
            "1",
        ],
    );
    let f = only_figure(&v);
    assert_eq!(f["details"]["pixels"], 64 * 48);
    assert!(f["label"].as_str().unwrap().contains("64×48"), "{f}");
    // A float32 Fortran-order array keeps numpy's (rows, columns) shape.
    let v = bench_json(
        dir.path(),
        &[
            "--only",
            "roughness",
            "--input",
            &p("map_f.npy"),
            "--repeat",
            "1",
        ],
    );
    let f = only_figure(&v);
    assert!(f["label"].as_str().unwrap().contains("40×24"), "{f}");
}

#[test]
fn bench_slider_figures_are_per_accepted_step() {
    let dir = tempfile::tempdir().unwrap();
    let v = bench_json(
        dir.path(),
        &["--only", "two-dof,three-dof", "--repeat", "1"],
    );
    assert!(v["input"].is_null());
    let figs = v["figures"].as_array().unwrap();
    let names: Vec<&str> = figs.iter().map(|f| f["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "two_dof_8.5nm_us_per_step",
            "two_dof_12nm_us_per_step",
            "three_dof_12nm_case"
        ]
    );
    for f in &figs[..2] {
        assert_eq!(f["unit"], "µs/step");
        let d = &f["details"];
        let steps = d["accepted_steps"].as_f64().unwrap();
        let rhs = d["rhs_evaluations"].as_f64().unwrap();
        assert!(steps > 100.0 && rhs > steps, "{f}");
        // µs per step × steps is the case time in ms × 1000, and per RHS evaluation likewise.
        let case_us = d["case_ms"].as_f64().unwrap() * 1e3;
        let per_step = f["value"].as_f64().unwrap();
        assert!((per_step * steps - case_us).abs() <= 1e-9 * case_us, "{f}");
        let per_rhs = d["us_per_rhs_evaluation"].as_f64().unwrap();
        assert!((per_rhs * rhs - case_us).abs() <= 1e-9 * case_us, "{f}");
    }
    let f = &figs[2];
    assert_eq!(f["unit"], "ms");
    let d = &f["details"];
    let case_us = f["value"].as_f64().unwrap() * 1e3;
    let steps = d["accepted_steps"].as_f64().unwrap();
    assert!((d["us_per_step"].as_f64().unwrap() * steps - case_us).abs() <= 1e-9 * case_us);
}

#[test]
fn bench_main_job_runs_the_pipeline_cold_and_logs_every_stage() {
    let p = Project::shipped();
    let v = bench_json(p.path(), &["--only", "main-job", "--repeat", "1"]);
    // The user's project is left alone: the cold run happened in a temp dir.
    assert!(!p.processed().exists());
    let figs = v["figures"].as_array().unwrap();
    let cold = &figs[0];
    assert_eq!(cold["name"], "main_job_cold");
    assert_eq!(
        (cold["statistic"].as_str(), cold["repeats"].as_u64()),
        (Some("single"), Some(1))
    );
    assert!(cold["median"].is_null());
    // Every stage instance `hdi status` lists ran once, and has its wall time.
    let st = p.run(&["status", "--json"]);
    let status: Value = serde_json::from_str(&stdout(&st)).unwrap();
    let mut want: Vec<String> = status
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap().to_string())
        .collect();
    let walls = cold["details"]["stage_wall_s"].as_object().unwrap();
    let mut got: Vec<String> = walls.keys().cloned().collect();
    want.sort();
    got.sort();
    assert_eq!(got, want);
    assert_eq!(cold["details"]["stages_ran"], want.len());
    // No stage took longer than the whole run.
    let total = cold["value"].as_f64().unwrap();
    assert!(
        walls.values().all(|t| t.as_f64().unwrap() <= total),
        "{cold}"
    );
    assert_eq!(figs.last().unwrap()["name"], "main_job_noop_rerun");
}

#[test]
fn bench_bad_options_and_inputs_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    write_arrays(dir.path());
    let p = |f: &str| dir.path().join(f).to_string_lossy().into_owned();
    let run = |args: &[&str]| {
        hdi()
            .current_dir(dir.path())
            .arg("bench")
            .args(args)
            .output()
            .unwrap()
    };
    assert_clean_failure(&run(&["--only", "fft,warp"]), "unknown group `warp`");
    assert_clean_failure(
        &run(&["--only", "fft,cwt", "--input", &p("sig.npy")]),
        "exactly one of",
    );
    assert_clean_failure(
        &run(&["--only", "fft", "--input", &p("nope.npy")]),
        "nope.npy",
    );
    assert_clean_failure(
        &run(&["--only", "fft", "--input", &p("ints.npy")]),
        "float64 or float32",
    );
    assert_clean_failure(
        &run(&["--only", "fft", "--input", &p("bad.npy")]),
        "value 7 is not finite",
    );
    assert_clean_failure(
        &run(&["--only", "fft", "--input", &p("map.npy")]),
        "1-D signal",
    );
    assert_clean_failure(
        &run(&["--only", "roughness", "--input", &p("sig.npy")]),
        "2-D map",
    );
    assert_clean_failure(
        &run(&["--only", "main-job", "--config", "absent.toml"]),
        "absent.toml",
    );
}
