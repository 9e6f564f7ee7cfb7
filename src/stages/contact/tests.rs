use super::*;

#[test]
fn force_table_matches_direct_evaluation_across_the_regime_boundaries() {
    // Acceptance: ≤ 1e-4 relative everywhere the curves matter, no NaN or jump at 3σ,
    // 3σ + t and the table's ends (measured: ≤ 1.1e-8, F_s the worst).
    let cfg = ContactConfig::defaults();
    let c = check(&cfg).unwrap();
    let a = analyse(&c.params, &c, None).unwrap();
    for e in a.table_error() {
        assert!(e.max_rel < 1e-4, "{e:?}");
    }
    let sigma = c.params.sigma;
    let t = c.params.lubricant_thickness / sigma;
    for x in [3.0, 3.0 + t, 0.0, -3.5, 10.0] {
        for ch in 0..5 {
            let below = a.table().eval(ch, x - 1e-7).unwrap();
            let above = a.table().eval(ch, x + 1e-7).unwrap();
            assert!(below.is_finite() && above.is_finite());
            assert!(((below - above) / below).abs() < 1e-5, "{ch} at {x}");
        }
    }
    // P, A_r, Q fall and F_s falls with separation.
    for ch in [0, 2, 3, 4] {
        let mut prev = f64::INFINITY;
        for k in 0..2000 {
            let y = a.table().eval(ch, -3.9 + k as f64 * 0.0087).unwrap();
            assert!(y <= prev, "channel {ch} at step {k}");
            prev = y;
        }
    }
}

#[test]
fn isbl_params_round_trip_through_the_result_json() {
    for p in [IsblParams::improved_2dof(), IsblParams::mtl_table_3_2()] {
        let c = ContactParams {
            params: p,
            ..check(&ContactConfig::defaults()).unwrap()
        };
        let report = report_json(&analyse(&p, &c, None).unwrap(), &c);
        let result = serde_json::to_value(&report).unwrap();
        let back: crate::artefacts::contact::ContactResult =
            serde_json::from_value(result).unwrap();
        assert_eq!(back.inputs.params().unwrap(), p);
    }
}

/// The default distribution, spelt either way, keeps the key the contact instance had
/// before the switch existed; the others name themselves in it.
#[test]
fn summit_distribution_keys_and_the_default_key() {
    let with = |d: Option<&str>, o: Option<&str>| ContactConfig {
        summit_distribution: d.map(str::to_string),
        summit_offset: o.map(str::to_string),
        ..ContactConfig::defaults()
    };
    let base = check(&ContactConfig::defaults()).unwrap();
    let key = base.canonical();
    assert!(key.get("summit_distribution").is_none());
    assert_eq!(key["inputs"]["summit_offset"], "none");
    assert!(key["inputs"].get("summit_ratios").is_none());
    for (d, o) in [
        (Some("surface"), None),
        (None, Some("none")),
        (Some("surface"), Some("none")),
    ] {
        assert_eq!(check(&with(d, o)).unwrap().canonical(), key, "{d:?} {o:?}");
    }
    let mccool = check(&with(Some("mccool"), None)).unwrap();
    assert_eq!(
        mccool.canonical(),
        check(&with(None, Some("mccool"))).unwrap().canonical()
    );
    assert_eq!(mccool.params.summits, SummitDistribution::McCool);
    let fig = check(&ContactConfig {
        fig_2_11_nominal_area: Some(Area(62e-12)),
        ..with(Some("fig_2_11"), None)
    })
    .unwrap();
    assert_eq!(
        fig.summits,
        SummitSpec::Fig211 {
            nominal_area: 62e-12
        }
    );
    let k = fig.canonical();
    assert_eq!(k["inputs"]["summit_offset"], "fig_2_11");
    assert_eq!(k["summit_distribution"]["nominal_area_m2"], 62e-12);
    // The fit replaces the distribution when the curves are computed.
    let a = analyse(&fig.params, &fig, None).unwrap();
    let (s, y) = a.summit_origin.as_ref().unwrap().ratios();
    assert!(s > 0.3 && s < 0.4 && y > 2.1 && y < 2.3, "{s} {y}");
    let p3 = a.model.at(3.0 * fig.params.sigma).unwrap().contact_pressure;
    assert!((p3 * 62e-12 / 7.30e-6 - 1.0).abs() < 1e-9);
    assert_eq!(report_json(&a, &fig).inputs.summit_offset, "given");
    // Conflicts and misplaced keys name themselves; measured without a pipeline is an error.
    let key_of = |c: &ContactConfig| check(c).unwrap_err().key;
    assert_eq!(
        key_of(&with(Some("fig_2_11"), Some("mccool"))),
        "summit_offset"
    );
    assert_eq!(
        key_of(&with(Some("lognormal"), None)),
        "summit_distribution"
    );
    assert_eq!(key_of(&with(None, Some("surface"))), "summit_offset");
    assert_eq!(key_of(&with(Some("measured"), None)), "summit_distribution");
    let misplaced = ContactConfig {
        fig_2_11_nominal_area: Some(Area(62e-12)),
        ..with(Some("mccool"), None)
    };
    assert_eq!(key_of(&misplaced), "fig_2_11_nominal_area");
    let source = ContactConfig {
        summit_source: Some("disk".into()),
        ..ContactConfig::defaults()
    };
    assert_eq!(key_of(&source), "summit_source");
    let measured = check(&ContactConfig {
        summit_source: Some("disk".into()),
        ..with(Some("measured"), None)
    })
    .unwrap();
    assert!(analyse(&measured.params, &measured, None).is_err());
}

#[test]
fn bad_keys_name_themselves() {
    let mut cfg = ContactConfig::defaults();
    cfg.parameter_set = "nope".into();
    assert_eq!(check(&cfg).unwrap_err().key, "parameter_set");
    let mut cfg = ContactConfig::defaults();
    cfg.hardness = Some(Pressure(-1.0));
    assert_eq!(check(&cfg).unwrap_err().key, "hardness");
    let mut cfg = ContactConfig::defaults();
    cfg.step = 0.0;
    assert_eq!(check(&cfg).unwrap_err().key, "step");
    let mut cfg = ContactConfig::defaults();
    cfg.surface_energy = Some(SurfaceEnergyConfig::Text("lots".into()));
    assert_eq!(check(&cfg).unwrap_err().key, "surface_energy");
}
