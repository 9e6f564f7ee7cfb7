//! The `[doe]` stage through the binary: the shipped design runs, is fully cached, survives a
//! kill mid-run without losing a finished case, and bad keys name the key.
use crate::common::*;
use std::path::Path;
use std::time::{Duration, Instant};

fn stored_cases(processed: &Path) -> usize {
    std::fs::read_dir(processed.join(".hdi/store/case"))
        .map(|d| {
            d.filter_map(|e| e.ok())
                .filter(|e| e.path().is_dir())
                .count()
        })
        .unwrap_or(0)
}

#[test]
fn doe_runs_resumes_after_a_kill_and_is_fully_cached() {
    let p = Project::shipped();
    // Upstream first, so the kill below lands inside the DOE's own cases.
    let o = p.run(&["run", "--only", "improved", "disk_md"]);
    assert_ok(&o);
    let before = stored_cases(&p.processed());
    let mut child = hdi()
        .current_dir(p.path())
        .args(["run", "--only", "bulge_design"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("spawn hdi");
    let started = Instant::now();
    while stored_cases(&p.processed()) < before + 12 && started.elapsed() < Duration::from_secs(600)
    {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.kill().ok();
    child.wait().unwrap();
    let finished = stored_cases(&p.processed()) - before;
    assert!(finished >= 12, "only {finished} cases before the kill");

    let o = p.run(&["run", "--only", "bulge_design"]);
    assert_ok(&o);
    let out = p.processed().join("bulge_design");
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("result.json")).unwrap()).unwrap();
    assert_eq!(result["cases"], 108);
    // Every case finished before the kill was reused (the run had not reached the annealing).
    let cached = result["cases_cached"].as_u64().unwrap() as usize;
    assert!(
        cached >= finished.min(108),
        "{cached} cached of {finished} finished"
    );
    for f in [
        "design.csv",
        "coefficients.parquet",
        "anova.csv",
        "predictive_equations.csv",
        "annealing.csv",
        "sensitivity.csv",
        "comparison.csv",
        "contours_9p0nm.png",
        "residuals_12p0nm.png",
        "annealing.png",
        "comparison.png",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let design = csv_rows(&out.join("design.csv"));
    assert_eq!(design.len(), 108);
    // The 23-term quartic on 27 points leaves 4 residual df at every level.
    let anova = csv_rows(&out.join("anova.csv"));
    let residual: Vec<_> = anova.iter().filter(|r| r["source"] == "residual").collect();
    assert_eq!(residual.len(), 4);
    assert!(residual.iter().all(|r| r["df"] == "4"), "{residual:?}");
    // Table 2.7: three fixed-factor equations per level, a_tfc at 5 and 16 nm.
    let pred = csv_rows(&out.join("predictive_equations.csv"));
    assert_eq!(pred.len(), 12);
    assert_eq!(pred[0]["fixed_factor"], "a_tfc");
    assert_eq!(pred[3]["fixed_factor"], "x_tfc");
    // The optimum stays in the box and is reported beside the dissertation's.
    let a = result["optimum"]["a_m"].as_f64().unwrap() * 1e6;
    assert!((1.0..=5.0).contains(&a), "a = {a}");
    let v = p.run(&["validate", "--only", "optimisation"]);
    let text = stdout(&v);
    assert!(
        text.contains("optimised a_TFC") && text.contains("4.86"),
        "{text}"
    );

    // Fully cached: a rerun recomputes nothing.
    let again = p.run(&["run", "--only", "bulge_design"]);
    assert_ok(&again);
    assert!(
        stderr(&again).contains("nothing to do"),
        "{}",
        stderr(&again)
    );
}

#[test]
fn bad_doe_keys_name_the_key() {
    let p = Project::shipped();
    let base = p.config();
    for (from, to, needle) in [
        (
            "a_tfc = [\"1 um\", \"3 um\", \"5 um\"]",
            "a_tfc = [\"5 um\", \"3 um\", \"1 um\"]",
            "doe.bulge_design.a_tfc",
        ),
        (
            "x_tfc = [\"5 um\", \"8 um\", \"11 um\"]",
            "x_tfc = [\"4 um\", \"7 um\", \"10 um\"]",
            "overhang",
        ),
        (
            "sa_objective = \"simulation\"",
            "sa_objective = \"guess\"",
            "doe.bulge_design.sa_objective",
        ),
        (
            "sa_start = [\"3 um\", \"10 um\", \"5 um\"]",
            "sa_start = [\"3 um\", \"100 um\", \"5 um\"]",
            "design box",
        ),
        (
            "actuations = [\"5 nm\", \"9 nm\", \"12 nm\", \"15 nm\"]",
            "actuations = [\"5 nm\", \"9 nm\", \"12 nm\", \"160 nm\"]",
            "doe.bulge_design.actuations",
        ),
    ] {
        let cfg = base.replacen(from, to, 1);
        assert_ne!(cfg, base, "{from}");
        p.set_config(&cfg);
        let o = p.run(&["run", "--only", "bulge_design"]);
        assert_clean_failure(&o, needle);
    }
}
