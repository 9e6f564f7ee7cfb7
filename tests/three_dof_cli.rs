//! The `[three_dof]` stage through the binary: the shipped scenarios run, cache per case, write
//! their files, and bad keys name the key.
use crate::common::*;

fn assert_ok(o: &std::process::Output) {
    assert!(o.status.success(), "{}", stderr(o));
}

fn csv_rows(path: &std::path::Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

#[test]
fn shipped_three_dof_scenarios_run_and_cache_per_case() {
    let p = Project::shipped();
    let o = p.run(&["run", "--only", "constant_12nm", "shock"]);
    assert_ok(&o);
    let out = p.processed();
    for f in [
        "constant_12nm/cases.parquet",
        "constant_12nm/cases/isbl.h5",
        "constant_12nm/cases/mtl_reference.png",
        "shock/cases/isbl.h5",
        "tables/three_dof.csv",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    // 12 nm: the pole tip holds the push-back state (dissertation 7.5 ± 1.0 nm).
    let rows = csv_rows(&out.join("constant_12nm/cases.csv"));
    let pt: f64 = rows[0]["pole_tip_mean_nm"].parse().unwrap();
    assert!((pt - 7.5).abs() < 1.0, "PT {pt}");
    // The shock: the pads touch and the bulge comes back.
    let shock = csv_rows(&out.join("shock/cases.csv"));
    let touched = &shock[0]["features_in_solid_contact"];
    assert!(touched.contains("Pad"), "{touched}");
    // A rerun recomputes nothing; another lubricant list reuses the cached ISBL case.
    let again = p.run(&["run", "--only", "constant_12nm"]);
    assert_ok(&again);
    assert!(
        stderr(&again).contains("nothing to do"),
        "{}",
        stderr(&again)
    );
    let cfg = p.config().replacen(
        "interfaces = [\"isbl\", \"mtl\"]             # MTL with",
        "interfaces = [\"isbl\"]             # MTL with",
        1,
    );
    p.set_config(&cfg);
    let o = p.run(&["run", "--only", "constant_12nm"]);
    assert_ok(&o);
    let rows = csv_rows(&out.join("constant_12nm/cases.csv"));
    assert_eq!(rows.len(), 1);
}

#[test]
fn bad_three_dof_keys_name_the_key() {
    let p = Project::shipped();
    let base = p.config();
    for (from, to, needle) in [
        (
            "scenario = \"shock\"",
            "scenario = \"crash\"",
            "three_dof.shock.scenario",
        ),
        (
            "lubricants = [\"reference\", \"humidity_temperature\"",
            "lubricants = [\"reference\", \"wet\"",
            "unknown `wet`",
        ),
        (
            "actuation = \"12 nm\"",
            "actuation = \"2 nm\"",
            "bulge height",
        ),
        (
            "[three_dof.shock]                        # S4: 0.25 µN·s over 5 µs at 0.6 ms, 5 nm actuation\ncontact = \"slider3\"",
            "[three_dof.shock]\ncontact = \"slider4\"",
            "three_dof.shock.contact",
        ),
    ] {
        let cfg = base.replacen(from, to, 1);
        assert_ne!(cfg, base, "{from}");
        p.set_config(&cfg);
        let o = p.run(&["run", "--only", "shock", "constant_12nm", "lubricant_cases"]);
        assert_clean_failure(&o, needle);
    }
}
