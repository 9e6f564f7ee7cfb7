//! `hdi synth profilometer`, `hdi bulge` and the `[bulge.NAME]` stage on synthetic scans of a
//! known bulge (truth: the generator's parameters in `truth.json`, docs/bulge.md).

use crate::common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn synth(dir: &Path) -> (Vec<PathBuf>, Value) {
    let o = hdi()
        .args(["synth", "profilometer", "--out-dir"])
        .arg(dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "gsf"))
        .collect();
    files.sort();
    let truth =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    (files, truth)
}

fn bulge_json(files: &[PathBuf], extra: &[&str]) -> Value {
    let o = hdi()
        .arg("bulge")
        .args(files)
        .args(extra)
        .arg("--json")
        .output()
        .unwrap();
    assert!(o.status.success(), "hdi bulge failed: {}", stderr(&o));
    serde_json::from_str(&stdout(&o)).expect("one JSON object on stdout")
}

fn f(v: &Value, k: &str) -> f64 {
    v[k].as_f64()
        .unwrap_or_else(|| panic!("{k} missing in {v}"))
}

fn check_against_truth(j: &Value, truth: &Value) {
    let scans = j["scans"].as_array().unwrap();
    let want = truth["scans"].as_array().unwrap();
    assert_eq!(scans.len(), want.len());
    for (s, t) in scans.iter().zip(want) {
        assert_eq!(s["file"], t["file"]);
        assert_eq!(f(s, "heater_power_mW"), f(t, "heater_power_mW"));
        // Acceptance of docs/bulge.md: a, w within 5 %, x within 0.5 µm, height within 0.3 nm.
        assert!(
            (f(s, "a_tfc_m") / f(t, "a_tfc_m") - 1.0).abs() < 0.05,
            "{s}"
        );
        assert!(
            (f(s, "w_tfc_m") / f(t, "w_tfc_m") - 1.0).abs() < 0.05,
            "{s}"
        );
        assert!((f(s, "x_tfc_m") - f(t, "x_tfc_m")).abs() < 0.5e-6, "{s}");
        assert!((f(s, "height_m") - f(t, "height_m")).abs() < 0.3e-9, "{s}");
        // The residual is the generator's white noise (nothing systematic left).
        assert!((f(s, "residual_rms_m") / f(t, "noise_rms_m") - 1.0).abs() < 0.1);
        for k in ["height_se_m", "a_tfc_se_m", "w_tfc_se_m", "x_tfc_se_m"] {
            assert!(f(s, k) > 0.0, "{k}");
        }
    }
    let e = f(j, "efficiency_m_per_W");
    assert!(
        (e / f(truth, "efficiency_m_per_W") - 1.0).abs() < 0.05,
        "{e}"
    );
    assert!((f(j, "intercept_m") - f(truth, "intercept_m")).abs() < 0.3e-9);
    assert!(f(j, "efficiency_se_m_per_W") >= 0.0);
}

#[test]
fn bulge_recovers_the_synthetic_scans() {
    let dir = tempfile::tempdir().unwrap();
    let (files, truth) = synth(dir.path());
    assert_eq!(files.len(), 4);
    // Powers from the file names (tfc_30mW.gsf)…
    let j = bulge_json(&files, &[]);
    check_against_truth(&j, &truth);
    // …or given explicitly (here deliberately doubled: the efficiency halves).
    let j2 = bulge_json(
        &files,
        &[
            "--power", "0 mW", "--power", "60 mW", "--power", "0.12 W", "--power", "180 mW",
        ],
    );
    let e1 = f(&j, "efficiency_m_per_W");
    let e2 = f(&j2, "efficiency_m_per_W");
    assert!((e2 / e1 - 0.5).abs() < 1e-9, "{e1} {e2}");
    // The human table names the efficiency in nm/mW.
    let o = hdi().arg("bulge").args(&files).output().unwrap();
    assert!(o.status.success());
    assert!(stdout(&o).contains("nm/mW"), "{}", stdout(&o));
}

#[test]
fn shipped_scans_are_what_the_generator_writes() {
    let dir = tempfile::tempdir().unwrap();
    synth(dir.path());
    for name in [
        "tfc_00mW.gsf",
        "tfc_30mW.gsf",
        "tfc_60mW.gsf",
        "tfc_90mW.gsf",
        "truth.json",
    ] {
        let shipped = std::fs::read(repo_root().join("raw/bulge").join(name)).unwrap();
        let fresh = std::fs::read(dir.path().join(name)).unwrap();
        assert!(
            shipped == fresh,
            "raw/bulge/{name} differs from `hdi synth profilometer`"
        );
    }
}

#[test]
fn bulge_bad_input_is_one_clean_error() {
    let dir = tempfile::tempdir().unwrap();
    let (files, _) = synth(dir.path());
    let o = hdi()
        .arg("bulge")
        .args(&files)
        .args(["--power", "10 mW"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "--power");
    let cut = dir.path().join("cut_30mW.gsf");
    let bytes = std::fs::read(&files[1]).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let o = hdi().arg("bulge").arg(&cut).output().unwrap();
    assert_clean_failure(&o, "cut_30mW.gsf");
}

#[test]
fn bulge_stage_in_a_pipeline() {
    let dir = tempfile::tempdir().unwrap();
    let raw = dir.path().join("raw");
    let (_, truth) = synth(&raw);
    std::fs::write(
        dir.path().join("pipeline.toml"),
        r#"[project]
name = "bulge test"

[report]
validation = false

[bulge.tfc]
files = ["raw/tfc_00mW.gsf", "raw/tfc_30mW.gsf", "raw/tfc_60mW.gsf", "raw/tfc_90mW.gsf"]
powers = ["0 mW", "30 mW", "60 mW", "90 mW"]
"#,
    )
    .unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["run", "-j", "1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let store = dir.path().join("processed/.hdi/store/bulge");
    let entry = std::fs::read_dir(&store)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.join("result.json").is_file())
        .expect("a bulge store entry");
    for out in [
        "bulge.h5",
        "scans.csv",
        "scans.parquet",
        "height_vs_power.png",
    ] {
        assert!(
            entry.join(out).is_file(),
            "{out} missing in {}",
            entry.display()
        );
    }
    let result: Value =
        serde_json::from_str(&std::fs::read_to_string(entry.join("result.json")).unwrap()).unwrap();
    check_against_truth(&result, &truth);
    let tfc = &result["tfc"];
    assert!((f(tfc, "a_tfc_m") / 4.86e-6 - 1.0).abs() < 0.05);
    assert!((f(tfc, "x_tfc_m") - 6.35e-6).abs() < 0.5e-6);
    let csv = std::fs::read_to_string(entry.join("scans.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("heater_power_mW"));
    assert_eq!(csv.lines().count(), 5);
}

#[test]
fn simulate_sweep_in_heater_power_from_a_fitted_bulge() {
    let dir = tempfile::tempdir().unwrap();
    synth(&dir.path().join("raw"));
    // The shipped [bulge.tfc] and [simulate.power_sweep] tables, on a short coarse sweep.
    let shipped = std::fs::read_to_string(repo_root().join("pipeline.toml")).unwrap();
    let table = |head: &str| -> String {
        let start = shipped
            .find(head)
            .unwrap_or_else(|| panic!("{head} in pipeline.toml"));
        let rest = &shipped[start..];
        let end = rest[1..].find("\n[").map_or(rest.len(), |e| e + 1);
        rest[..end].to_string()
    };
    let text = format!(
        "[project]\nname = \"t\"\n\n[report]\nvalidation = false\n\n{}\n[contact.improved]\nparameter_set = \"improved_2dof\"\n\n{}",
        table("[bulge.tfc]").replace("raw/bulge/", "raw/"),
        table("[simulate.power_sweep]")
            .replace("dmw = \"disk_md\"", "dmw = \"none\"")
            // One branch, grid touchdown: the rows are the four powers (docs/conventions.md).
            .replace("power_step = \"2 mW\"", "power_step = \"16 mW\"\nduration = \"0.5 ms\"\nsteady_start = \"0.2 ms\"\nbranches = \"up\"\nrefine_touchdown = false"),
    );
    std::fs::write(dir.path().join("pipeline.toml"), &text).unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["run", "-j", "1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}\n{text}", stderr(&o));
    let csv = std::fs::read_to_string(dir.path().join("processed/power_sweep/sweep.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (ia, ip) = (col("actuation_nm"), col("heater_power_mW"));
    let rows: Vec<(f64, f64)> = lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            (v[ia].parse().unwrap(), v[ip].parse().unwrap())
        })
        .collect();
    assert_eq!(
        rows.iter().map(|r| r.1).collect::<Vec<_>>(),
        [0.0, 16.0, 32.0, 48.0]
    );
    // actuation = efficiency × power with the fitted efficiency ≈ 0.3 nm/mW (within 5 %).
    for (a, p) in &rows[1..] {
        assert!((a / p / 0.3 - 1.0).abs() < 0.05, "{a} nm at {p} mW");
    }
    let result: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("processed/power_sweep/result.json")).unwrap(),
    )
    .unwrap();
    let sweep = &result["sweep"];
    let eff = f(sweep, "efficiency_m_per_W");
    if let Some(td) = sweep["touchdown_m"].as_f64() {
        assert!((f(sweep, "touchdown_power_W") - td / eff).abs() < 1e-12);
    }
    let table = std::fs::read_to_string(dir.path().join("processed/tables/simulates.csv")).unwrap();
    assert!(table.lines().next().unwrap().contains("touchdown_power_mW"));
    // A power sweep without a fitted bulge is a clean configuration error.
    let bad = text.replace("geometry = { bulge = \"tfc\" }", "geometry = \"optimised\"");
    std::fs::write(dir.path().join("pipeline.toml"), bad).unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["run", "-j", "1"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "bulge");
}

/// Run `text` as the pipeline in a fresh project with the synthetic scans under `raw/`, and
/// return the project directory and the fitted `tfc` of `[bulge.tfc]`.
fn run_with_fitted_bulge(text: &str) -> (tempfile::TempDir, Value) {
    let dir = tempfile::tempdir().unwrap();
    synth(&dir.path().join("raw"));
    let text = format!(
        "[project]\nname = \"t\"\n\n[report]\nvalidation = false\n\n[bulge.tfc]\nfiles = [\"raw/tfc_00mW.gsf\", \"raw/tfc_30mW.gsf\", \"raw/tfc_60mW.gsf\", \"raw/tfc_90mW.gsf\"]\n\n{text}"
    );
    std::fs::write(dir.path().join("pipeline.toml"), &text).unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["run", "-j", "1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}\n{text}", stderr(&o));
    let bulge: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("processed/tfc/result.json")).unwrap(),
    )
    .unwrap();
    let tfc = bulge["tfc"].clone();
    // The fit recovers the generator's design (truth.json: §2.3's optimised bulge).
    assert!((f(&tfc, "a_tfc_m") / 4.86e-6 - 1.0).abs() < 0.01, "{tfc}");
    (dir, tfc)
}

fn result_of(dir: &Path, name: &str) -> Value {
    serde_json::from_str(
        &std::fs::read_to_string(dir.join("processed").join(name).join("result.json")).unwrap(),
    )
    .unwrap()
}

#[test]
fn three_dof_runs_on_the_fitted_bulge() {
    let (dir, tfc) = run_with_fitted_bulge(
        "[contact.slider3]\nparameter_set = \"three_dof\"\n\n[three_dof.fit]\ncontact = \"slider3\"\nactuation = \"12 nm\"\ninterfaces = [\"isbl\"]\nduration = \"0.3 ms\"\nsteady_start = \"0.1 ms\"\ngeometry = { bulge = \"tfc\" }\n",
    );
    let r = result_of(dir.path(), "fit");
    let used = &r["fitted_bulge"];
    for k in ["a_tfc_m", "w_tfc_m", "x_tfc_m"] {
        assert_eq!(used[k], tfc[k], "{k}: {used} vs {tfc}");
    }
    assert_eq!(r["cases"].as_array().map(|c| c.len()), Some(1), "{r}");
    // A geometry naming no bulge instance is a clean configuration error.
    let p = dir.path().join("pipeline.toml");
    let text = std::fs::read_to_string(&p).unwrap();
    std::fs::write(&p, text.replace("bulge = \"tfc\" }", "bulge = \"nope\" }")).unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["run", "-j", "1"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "nope");
}

#[test]
fn doe_compares_the_fitted_bulge_with_the_optimum() {
    let (dir, tfc) = run_with_fitted_bulge(
        "[contact.improved]\nparameter_set = \"improved_2dof\"\n\n[simulate.base]\ncontact = \"improved\"\nactuations = [\"5 nm\"]\nduration = \"0.5 ms\"\nsteady_start = \"0.2 ms\"\n\n[doe.d]\nsimulate = \"base\"\ngeometry = { bulge = \"tfc\" }\nactuations = [\"9 nm\", \"12 nm\"]\nsa_actuation = \"10 nm\"\nsa_objective = \"surrogate\"\nsa_max_evaluations = 200\nsensitivity_steps = 1\ncompare_step = \"4 nm\"\n",
    );
    let r = result_of(dir.path(), "d");
    let init = &r["initial_design_m"];
    for (k, t) in [
        ("a_tfc", "a_tfc_m"),
        ("w_tfc", "w_tfc_m"),
        ("x_tfc", "x_tfc_m"),
    ] {
        assert_eq!(init[k], tfc[t], "{k}: {init} vs {tfc}");
    }
    assert!(r["comparison"].is_array(), "{r}");
}

/// The line scans of the shipped bulge (tests/data/bulge_lines/, written from raw/bulge/ by
/// numpy: make_bulge_lines.py), as `FILE@OFFSET` arguments, in lines.json's order.
fn shipped_lines() -> (Vec<String>, Value) {
    let dir = repo_root().join("tests/data/bulge_lines");
    let list: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("lines.json")).unwrap()).unwrap();
    let args = list["lines"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| {
            format!(
                "{}@{}um",
                dir.join(l["file"].as_str().unwrap()).display(),
                l["offset_um"].as_i64().unwrap()
            )
        })
        .collect();
    let truth = serde_json::from_str(
        &std::fs::read_to_string(repo_root().join("raw/bulge/truth.json")).unwrap(),
    )
    .unwrap();
    (args, truth)
}

/// Acceptance (issue 32): five line scans per power (centre, ±10 µm as x–z text, ±20 µm as
/// Dektak CSV) recover a, w, x_TFC, the heights and the efficiency of the shipped bulge to the
/// map fit's tolerances (`check_against_truth`: a, w 5 %, x_TFC 0.5 µm, h 0.3 nm, efficiency
/// 5 %, intercept 0.3 nm).
#[test]
fn bulge_from_line_scans_recovers_the_shipped_bulge() {
    let (lines, truth) = shipped_lines();
    assert_eq!(lines.len(), 20);
    let mut args = vec!["bulge".to_string()];
    for l in &lines {
        args.push("--line".into());
        args.push(l.clone());
    }
    args.push("--json".into());
    let o = hdi().args(&args).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let j: Value = serde_json::from_str(&stdout(&o)).unwrap();
    let scans = j["scans"].as_array().unwrap();
    assert_eq!(scans.len(), 4);
    let want = truth["scans"].as_array().unwrap();
    for (s, t) in scans.iter().zip(want) {
        assert_eq!(f(s, "heater_power_mW"), f(t, "heater_power_mW"));
        assert!(
            (f(s, "a_tfc_m") / f(t, "a_tfc_m") - 1.0).abs() < 0.05,
            "{s}"
        );
        assert!(
            (f(s, "w_tfc_m") / f(t, "w_tfc_m") - 1.0).abs() < 0.05,
            "{s}"
        );
        assert!((f(s, "x_tfc_m") - f(t, "x_tfc_m")).abs() < 0.5e-6, "{s}");
        assert!((f(s, "height_m") - f(t, "height_m")).abs() < 0.3e-9, "{s}");
        for k in ["height_se_m", "a_tfc_se_m", "w_tfc_se_m", "x_tfc_se_m"] {
            assert!(f(s, k) > 0.0, "{k}");
        }
        assert!(s["y_c_m"].is_null());
    }
    let e = f(&j, "efficiency_m_per_W");
    assert!(
        (e / f(&truth, "efficiency_m_per_W") - 1.0).abs() < 0.05,
        "{e}"
    );
    assert!((f(&j, "intercept_m") - f(&truth, "intercept_m")).abs() < 0.3e-9);
    let tfc = &j["tfc"];
    assert!((f(tfc, "w_tfc_m") / 50e-6 - 1.0).abs() < 0.05, "{tfc}");
    // The centre lines alone give h, a, x_TFC but no width: a clean error naming w.
    let centre: Vec<String> = lines
        .iter()
        .filter(|l| l.ends_with("@0um"))
        .cloned()
        .collect();
    assert_eq!(centre.len(), 4);
    let mut args = vec!["bulge".to_string()];
    for l in &centre {
        args.push("--line".into());
        args.push(l.clone());
    }
    let o = hdi().args(&args).output().unwrap();
    assert_clean_failure(&o, "width w");
}

#[test]
fn bulge_stage_takes_line_scans_and_refuses_unknown_keys() {
    let dir = tempfile::tempdir().unwrap();
    let src = repo_root().join("tests/data/bulge_lines");
    let list: Value =
        serde_json::from_str(&std::fs::read_to_string(src.join("lines.json")).unwrap()).unwrap();
    std::fs::create_dir_all(dir.path().join("raw")).unwrap();
    let mut entries = Vec::new();
    for l in list["lines"].as_array().unwrap() {
        let name = l["file"].as_str().unwrap();
        std::fs::copy(src.join(name), dir.path().join("raw").join(name)).unwrap();
        entries.push(format!(
            "  {{ file = \"raw/{name}\", offset = \"{} um\" }},",
            l["offset_um"].as_i64().unwrap()
        ));
    }
    let text = format!(
        "[project]\nname = \"lines\"\n\n[report]\nvalidation = false\n\n[bulge.tfc]\nlines = [\n{}\n]\n",
        entries.join("\n")
    );
    std::fs::write(dir.path().join("pipeline.toml"), &text).unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["run", "-j", "1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}\n{text}", stderr(&o));
    let r = result_of(dir.path(), "tfc");
    assert_eq!(r["scans"].as_array().map(|s| s.len()), Some(4), "{r}");
    assert!(
        (f(&r["tfc"], "a_tfc_m") / 4.86e-6 - 1.0).abs() < 0.05,
        "{r}"
    );
    assert!((f(&r["tfc"], "x_tfc_m") - 6.35e-6).abs() < 0.5e-6, "{r}");
    let store = dir.path().join("processed/.hdi/store/bulge");
    let entry = std::fs::read_dir(&store)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.join("result.json").is_file())
        .unwrap();
    for out in [
        "bulge.h5",
        "scans.csv",
        "scan_0_lines.png",
        "height_vs_power.png",
    ] {
        assert!(entry.join(out).is_file(), "{out}");
    }
    // A misspelt key inside a line is refused, naming the key, the file and the line.
    let bad = text.replacen("offset = ", "ofset = ", 1);
    std::fs::write(dir.path().join("pipeline.toml"), &bad).unwrap();
    let o = hdi()
        .current_dir(dir.path())
        .args(["run", "-j", "1"])
        .output()
        .unwrap();
    assert_clean_failure(&o, "ofset");
    let err = stderr(&o);
    assert!(err.contains("pipeline.toml:9"), "{err}");
}
