//! The `[three_dof]` stage through the binary: the shipped scenarios run, cache per case, write
//! their files, and bad keys name the key.
use crate::common::*;

#[test]
fn shipped_three_dof_scenarios_run_and_cache_per_case() {
    let p = Project::shipped();
    let o = p.run(&[
        "run",
        "--only",
        "constant_12nm",
        "shock_response",
        "lubricant_cases",
    ]);
    assert_ok(&o);
    let out = p.processed();
    for f in [
        "constant_12nm/cases.parquet",
        "constant_12nm/cases/isbl.h5",
        "constant_12nm/cases/mtl_reference.png",
        "shock/cases/isbl.h5",
        "tables/three_dof.csv",
        "shock_response/scalogram.png",
        "lubricant_cases/cases/mtl_reference_regimes.png",
        "lubricant_cases/cases/isbl_forces.png",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    // Table 4.4 on the shipped DMW: stiffer lubricant → smaller steady-contact BV
    // (case 2 < case 0 < case 1), the softer one vibrates most into contact.
    let lub = csv_rows(&out.join("lubricant_cases/cases.csv"));
    let bv = |case: &str, key: &str| -> f64 {
        let row = lub.iter().find(|r| r["case"] == case).expect(case);
        row[key]
            .parse()
            .unwrap_or_else(|_| panic!("{case} {key}: {row:?}"))
    };
    let steady = |c: &str| bv(c, "steady_contact_bv_percent");
    assert!(
        steady("mtl_more_bonding") < steady("mtl_reference")
            && steady("mtl_reference") < steady("mtl_humidity_temperature"),
        "{lub:?}"
    );
    let jtc = |c: &str| bv(c, "jump_to_contact_bv_percent");
    assert!(
        jtc("mtl_humidity_temperature") > jtc("mtl_reference")
            && jtc("mtl_humidity_temperature") > jtc("mtl_more_bonding"),
        "{lub:?}"
    );
    // 12 nm: the pole tip holds the push-back state (dissertation 7.5 ± 1.0 nm).
    let rows = csv_rows(&out.join("constant_12nm/cases.csv"));
    let pt: f64 = rows[0]["pole_tip_mean_nm"].parse().unwrap();
    assert!((pt - 7.5).abs() < 1.0, "PT {pt}");
    // The shock: the pads touch and the bulge comes back.
    let shock = csv_rows(&out.join("shock/cases.csv"));
    let touched = &shock[0]["features_in_solid_contact"];
    assert!(touched.contains("Pad"), "{touched}");
    // Fig. 4.12: the shock excites the AB modes (≈ 100 kHz) above the DMW's 10.7 kHz.
    let tables = csv_rows(&out.join("tables/analyses.csv"));
    let shock_row = tables
        .iter()
        .find(|r| r["stage"] == "shock_response")
        .expect("shock_response row");
    let khz = |k: &str| -> f64 { shock_row[k].parse().unwrap() };
    // Pitch/roll modes at 100–110 kHz (§4.1.7, App. B); the ridge follows the DMW most of the time.
    assert!((80.0..130.0).contains(&khz("peak1_kHz")), "{shock_row:?}");
    assert!(
        (9.5..12.0).contains(&khz("ridge_median_kHz")),
        "{shock_row:?}"
    );
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
            "scenario = \"shock\"",
            "scenario = \"shock\"\nair_bearing = \"printed\"",
            "three_dof.shock.air_bearing",
        ),
        (
            "scenario = \"shock\"",
            "scenario = \"shock\"\nab_roll_spring = \"relative\"",
            "unknown `relative` (disk_relative, absolute)",
        ),
        (
            "[three_dof.shock]                        # S4: 0.25 µN·s over 5 µs at 0.6 ms, 5 nm actuation\ncontact = \"slider3\"",
            "[three_dof.shock]\ncontact = \"slider4\"",
            "three_dof.shock.contact",
        ),
        (
            "source = \"shock\"",
            "source = \"lubricant_cases\"",
            "has several cases: say which file, one of cases/isbl.h5",
        ),
    ] {
        let cfg = base.replacen(from, to, 1);
        assert_ne!(cfg, base, "{from}");
        p.set_config(&cfg);
        let o = p.run(&["run", "--only", "shock", "constant_12nm", "lubricant_cases"]);
        assert_clean_failure(&o, needle);
    }
}
