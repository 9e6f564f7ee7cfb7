//! 3-DOF air bearing: the §3.3 stiffness table, interpolation, damping, forces, the modal round
//! trip and the ΔF_AB calibration against the spec's derived numbers.

use super::*;

fn default_ab() -> ThreeDofAirBearing {
    ThreeDofAirBearing::new(&ThreeDofAbParams::default()).unwrap()
}

/// The spec's reference numbers (§3.3) were derived with the linear spring law of eqs.
/// 4.11–4.14; these tests pin them with that law.
fn linear_params() -> ThreeDofAbParams {
    ThreeDofAbParams {
        spring_law: SpringLaw::Linear,
        ..ThreeDofAbParams::default()
    }
}

fn linear_ab() -> ThreeDofAirBearing {
    ThreeDofAirBearing::new(&linear_params()).unwrap()
}

/// `x` rounded to 4 significant digits equals the quoted value.
fn four_digits(x: f64, quoted: f64) -> bool {
    let e = quoted.abs().log10().floor();
    let unit = 10f64.powf(e - 3.0);
    ((x / unit).round() - (quoted / unit).round()).abs() < 0.5
}

#[test]
fn slider_inertias_match_table_4_1() {
    let p = ThreeDofAbParams::default();
    assert!(four_digits(p.slider.mass, 1.098e-6), "{}", p.slider.mass);
    assert!(four_digits(p.slider.pitch_inertia, 1.466e-13));
    assert!(four_digits(p.roll_inertia, 5.306e-14), "{}", p.roll_inertia);
}

#[test]
fn stiffness_table_matches_spec_3_3() {
    let ab = default_ab();
    let rows = ab.stiffness_table().points();
    let kf = [1.780e5, 1.797e5, 1.851e5, 1.864e5, 1.927e5, 2.031e5];
    let kr = [1.130e7, 3.248e6, 1.107e6, 9.701e5, 6.472e5, 4.566e5];
    assert_eq!(rows.len(), 6);
    for (i, r) in rows.iter().enumerate() {
        assert!((r.pole_tip - DEFAULT_POLE_TIP_GRID_NM[i] * NM).abs() < 1e-20);
        assert!(four_digits(r.front, kf[i]), "k_f[{i}] = {:e}", r.front);
        assert!(four_digits(r.rear, kr[i]), "k_r[{i}] = {:e}", r.rear);
        assert!(four_digits(r.roll, 2.090e-2), "k_l = {:e}", r.roll);
    }
    assert!(four_digits(ab.roll_stiffness(), 2.090e-2));
    let (f, r) = ab.nominal_stiffness();
    assert!(four_digits(f, 1.864e5) && four_digits(r, 9.701e5));
}

#[test]
fn stiffness_interpolates_log_log_and_clamps() {
    let ab = default_ab();
    let rows = ab.stiffness_table().points();
    // Exact at the nodes.
    for r in &rows {
        let (f, k) = ab.stiffness_at(r.pole_tip);
        assert!((f / r.front - 1.0).abs() < 1e-12 && (k / r.rear - 1.0).abs() < 1e-12);
    }
    // Geometric mean at the log-midpoint of 5 and 10 nm.
    let (f, k) = ab.stiffness_at((5.0f64 * 10.0).sqrt() * NM);
    assert!((f / (rows[1].front * rows[2].front).sqrt() - 1.0).abs() < 1e-12);
    assert!((k / (rows[1].rear * rows[2].rear).sqrt() - 1.0).abs() < 1e-12);
    // Clamped outside [2.5, 20] nm, including PT ≤ 0 and NaN.
    for pt in [1.0 * NM, 0.0, -3.0 * NM, f64::NAN] {
        assert_eq!(ab.stiffness_at(pt), ab.stiffness_at(2.5 * NM));
    }
    assert_eq!(ab.stiffness_at(40.0 * NM), ab.stiffness_at(20.0 * NM));
    // Monotone: k_r grows as the pole tip approaches the disk.
    let mut last = f64::INFINITY;
    for i in 0..=100 {
        let (_, k) = ab.stiffness_at((2.5 + 0.175 * i as f64) * NM);
        assert!(k <= last);
        last = k;
    }
}

#[test]
fn damping_from_nominal_stiffness() {
    let ab = default_ab();
    let p = ab.params().clone();
    let m = p.slider.mass;
    let (kf, kr) = ab.nominal_stiffness();
    let d = ab.damping();
    let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-12;
    assert!(close(d.front, 2.0 * 0.03 * (kf * m).sqrt()));
    assert!(close(d.rear, 2.0 * 0.03 * (kr * m).sqrt()));
    assert!(close(
        d.roll,
        2.0 * 0.03 * (ab.roll_stiffness() * p.roll_inertia).sqrt()
    ));
    assert!(close(d.heave, 2.0 * 0.02 * (10.0 * m).sqrt()));
    assert!(close(
        d.pitch,
        2.0 * 0.02 * (5e-5 * p.slider.pitch_inertia).sqrt()
    ));
    assert!(close(
        d.suspension_roll,
        2.0 * 0.02 * (5e-5 * p.roll_inertia).sqrt()
    ));
    // §11.1 quotes c_f, c_r (same slider) 2.715e-2 / 6.186e-2 for 9.683e5; ours uses 9.701e5.
    assert!(four_digits(d.front, 2.714e-2), "{}", d.front);
    assert!(four_digits(d.rear, 6.192e-2), "{}", d.rear);
    // Damping sits in C only through the roll spring and the suspension.
    let c = ab.eom_matrices().damping;
    assert!(close(c[(2, 2)], d.roll + d.suspension_roll));
    assert!(close(c[(0, 0)], d.heave) && close(c[(1, 1)], d.pitch));
}

#[test]
fn modal_round_trip_at_every_table_row() {
    // §3.3 / §10 item 7: the assembled linear AB (springs at ±l/2, suspension, roll spring)
    // has the table's frequencies. At 11 nm the fit gives 300.269 kHz ("300" in the spec).
    let ab = default_ab();
    let f = ab.modal_frequencies(11.0 * NM).unwrap();
    let expected = [100e3, 110e3, default_normal_frequency_hz(11.0 * NM)];
    for i in 0..3 {
        assert!((f[i] / expected[i] - 1.0).abs() < 1e-9, "{f:?}");
    }
    assert!((f[2] / 300e3 - 1.0).abs() < 1e-3);
    for row in ab.params().frequencies.points() {
        let f = ab.modal_frequencies(row.pole_tip).unwrap();
        assert!((f[0] / row.roll_hz - 1.0).abs() < 1e-9);
        assert!((f[1] / row.first_pitch_hz - 1.0).abs() < 1e-9);
        assert!((f[2] / row.normal_hz - 1.0).abs() < 1e-9);
    }
}

#[test]
fn exact_frequencies_with_a_user_table() {
    // 110 / 300 / 100 kHz exactly at 11 nm (user table): round trip to 1e-6, and the
    // 2-DOF springs of §3.2 (same slider, same suspension) come back.
    let row = |pt: f64, fn_khz: f64| AbFrequencyPoint {
        pole_tip: pt * NM,
        first_pitch_hz: 110e3,
        normal_hz: fn_khz * 1e3,
        roll_hz: 100e3,
    };
    let table =
        AbFrequencyTable::new(vec![row(5.0, 500.0), row(11.0, 300.0), row(20.0, 220.0)]).unwrap();
    let ab = ThreeDofAirBearing::new(&ThreeDofAbParams {
        frequencies: table,
        ..Default::default()
    })
    .unwrap();
    let f = ab.modal_frequencies(11.0 * NM).unwrap();
    for (got, want) in f.iter().zip([100e3, 110e3, 300e3]) {
        assert!((got / want - 1.0).abs() < 1e-6, "{f:?}");
    }
    let (kf, kr) = ab.nominal_stiffness();
    assert!(
        four_digits(kf, 1.865e5) && four_digits(kr, 9.683e5),
        "{kf:e} {kr:e}"
    );
}

#[test]
fn bad_tables_and_parameters_are_errors() {
    let row = |pt: f64| AbFrequencyPoint {
        pole_tip: pt,
        first_pitch_hz: 110e3,
        normal_hz: 300e3,
        roll_hz: 100e3,
    };
    assert!(AbFrequencyTable::new(vec![row(5e-9)]).is_err());
    assert!(AbFrequencyTable::new(vec![row(5e-9), row(5e-9)]).is_err());
    assert!(AbFrequencyTable::new(vec![row(-1e-9), row(5e-9)]).is_err());
    let mut bad = row(6e-9);
    bad.normal_hz = 100e3;
    assert!(AbFrequencyTable::new(vec![row(5e-9), bad]).is_err());
    // Too small a frequency ratio: no real spring pair.
    let mut close = row(6e-9);
    close.normal_hz = 150e3;
    let t = AbFrequencyTable::new(vec![row(5e-9), close]).unwrap();
    let p = ThreeDofAbParams {
        frequencies: t,
        ..Default::default()
    };
    assert!(ThreeDofAirBearing::new(&p).is_err());
    for p in [
        ThreeDofAbParams {
            roll_inertia: 0.0,
            ..Default::default()
        },
        ThreeDofAbParams {
            limit_flying_height: 10e-9,
            ..Default::default()
        },
        ThreeDofAbParams {
            read_offset: 6e-6,
            ..Default::default()
        },
        ThreeDofAbParams {
            front_damping_ratio: f64::NAN,
            ..Default::default()
        },
    ] {
        assert!(ThreeDofAirBearing::new(&p).is_err());
    }
    assert!(PushbackCurve::from_points(&[(0.0, 0.0)]).is_err());
    assert!(PushbackCurve::from_points(&[(1e-9, 0.0), (1e-9, 1e-9)]).is_err());
    let ab = default_ab();
    assert!(DeltaFabTable::calibrate(&ab, &PushbackCurve::default(), 5e-9, 0.0).is_err());
    assert!(ab
        .solve_static(f64::NAN, StaticCondition::GivenForce(0.0), None, false)
        .is_err());
}

#[test]
fn nominal_forces_and_weights_for_both_switches() {
    let ab = default_ab();
    let [ff, fr] = ab.nominal_forces();
    // Balanced at θ0: R p lever arms differ by (l_t/2) sinθ0 from ±l/2: F/2 to 3e-5 relative.
    assert!((ff + fr - 14.7e-3).abs() < 1e-15);
    assert!((ff / 7.35e-3 - 1.0).abs() < 3e-5 && (fr / 7.35e-3 - 1.0).abs() < 3e-5);
    let [wf, wr] = ab.weights();
    assert!((wf + wr - 1.0).abs() < 1e-15);
    assert!((wr - (1.23e-3 - 15e-6) / 1.23e-3).abs() < 1e-15);
    assert!((wr - 0.988).abs() < 5e-4);

    let faithful = ThreeDofAirBearing::new(&ThreeDofAbParams {
        nominal_force: NominalForce::AsPrinted,
        stiffening_point: StiffeningPoint::Com,
        ..Default::default()
    })
    .unwrap();
    let [ff, fr] = faithful.nominal_forces();
    // §3.3: 12.7 mN in total, split 2.05 / 10.67 mN.
    assert!((ff + fr - 12.72e-3).abs() < 0.01e-3, "{}", ff + fr);
    assert!((ff - 2.05e-3).abs() < 0.005e-3 && (fr - 10.67e-3).abs() < 0.005e-3);
    assert_eq!(faithful.weights(), [0.5, 0.5]);
}

#[test]
fn forces_at_the_nominal_state_balance_the_preload() {
    let ab = default_ab();
    let att = Attitude::pitch_only(100e-6);
    let [sf, sr] = ab.nominal_spring_spacings();
    assert!((sr - 11e-9).abs() < 1e-20);
    assert!((sf - (11e-9 + 1.23e-3 * (100e-6f64).sin())).abs() < 1e-20);
    let sp = SpringSpacings {
        front: sf,
        rear: sr,
        ..Default::default()
    };
    // PT does not matter at the nominal spacings (the spring deflection is zero).
    for pt in [3e-9, 11e-9, 13.8e-9] {
        let f = ab.forces(&sp, pt, 0.0, &att);
        assert!(!f.ab_lost());
        assert!(f.generalised.x.abs() < 1e-17, "{:e}", f.generalised.x);
        assert!(f.generalised.y.abs() < 1e-19, "{:e}", f.generalised.y);
        assert_eq!(f.generalised.z, 0.0);
    }
}

#[test]
fn spring_force_law_limits_and_damper() {
    let ab = linear_ab();
    let att = Attitude::pitch_only(100e-6);
    let [sf, sr] = ab.nominal_spring_spacings();
    let pt = 7e-9;
    let (kf, kr) = ab.stiffness_at(pt);
    let [f0, r0] = ab.nominal_forces();
    let [wf, wr] = ab.weights();
    let c = ab.damping();
    let sp = SpringSpacings {
        front: sf - 2e-9,
        rear: sr + 3e-9,
        front_rate: 1e-4,
        rear_rate: -2e-4,
    };
    let df = 5e-3;
    let f = ab.forces(&sp, pt, df, &att);
    let ef = f0 + kf * 2e-9 + wf * df - c.front * 1e-4;
    let er = r0 - kr * 3e-9 + wr * df + c.rear * 2e-4;
    assert!((f.front - ef).abs() < 1e-15 && (f.rear - er).abs() < 1e-15);
    assert_eq!((f.front_stiffness, f.rear_stiffness), (kf, kr));
    // eq. 4.17 with r = R p.
    let rf = att.world_offset(&ab.spring_points()[0]);
    let rr = att.world_offset(&ab.spring_points()[1]);
    assert!((f.generalised.x - (ef + er - 14.7e-3)).abs() < 1e-15);
    assert!((f.generalised.y - (rf.x * ef + rr.x * er)).abs() < 1e-18);
    // Never pulls: F ≥ 0.
    let far = SpringSpacings {
        rear: sr + 10e-9,
        rear_rate: 0.0,
        ..sp
    };
    let f = ab.forces(&far, 11e-9, 0.0, &att);
    assert_eq!(f.rear, 0.0);
    assert!(!f.rear_lost);
    // AB lost at ŝ ≥ FH_lim = 22 nm: zero force and the flag.
    let lost = SpringSpacings {
        front: sf + 11e-9,
        ..sp
    };
    let f = ab.forces(&lost, 11e-9, 50e-3, &att);
    assert!(f.front_lost && f.ab_lost() && f.front == 0.0);
    // Roll moment of centre-line springs: cosθ r_y F with r_y = sinφ l_t/2.
    let rolled = Attitude::new(100e-6, -10e-6);
    let f = ab.forces(&sp, pt, 0.0, &rolled);
    let ry = (-10e-6f64).sin() * 0.15e-3;
    assert!((f.generalised.z - (100e-6f64).cos() * ry * (f.front + f.rear)).abs() < 1e-22);
}

#[test]
fn spacing_increment_is_exact() {
    let ab = default_ab();
    let p = Vector3::new(0.4e-3, -0.2e-3, -0.15e-3);
    let att = Attitude::new(103e-6, -7e-6);
    let n0 = Attitude::pitch_only(100e-6);
    let direct = 2e-9 + att.altitude_offset(&p) - n0.altitude_offset(&p);
    assert!((ab.spacing_increment(&p, 2e-9, &att) - direct).abs() < 1e-18);
    assert_eq!(ab.spacing_increment(&p, 0.0, &n0), 0.0);
}

#[test]
fn eom_matrices_match_eqs_4_1_to_4_3() {
    let ab = ThreeDofAirBearing::new(&ThreeDofAbParams {
        preload_offset: 20e-6,
        ..Default::default()
    })
    .unwrap();
    let m = ab.eom_matrices();
    let p = ab.params();
    assert_eq!(m.mass[(0, 0)], p.slider.mass);
    assert_eq!(m.mass[(1, 1)], p.slider.pitch_inertia);
    assert_eq!(m.mass[(2, 2)], p.roll_inertia);
    let e = 20e-6;
    assert!((m.stiffness[(0, 1)] - e * 10.0).abs() < 1e-18);
    assert!((m.stiffness[(1, 1)] - (e * e * 10.0 + 5e-5)).abs() < 1e-18);
    assert!((m.stiffness[(2, 2)] - (5e-5 + ab.roll_stiffness())).abs() < 1e-15);
    assert_eq!(m.stiffness[(0, 2)], 0.0);
    assert_eq!(m.damping[(1, 2)], 0.0);
    // Balanced nominal forces with e ≠ 0 still balance the preload moment.
    let [ff, fr] = ab.nominal_forces();
    let att = Attitude::pitch_only(100e-6);
    let rf = att.world_offset(&ab.spring_points()[0]).x;
    let rr = att.world_offset(&ab.spring_points()[1]).x;
    assert!((rf * ff + rr * fr - e * att.pitch.cos() * 14.7e-3).abs() < 1e-20);
}

#[test]
fn read_element_and_pole_tip_geometry() {
    let ab = default_ab();
    // Table 4.3: 1.000 nm above the bulge bottom.
    assert!((ab.read_height_above_bulge_bottom() - 1e-9).abs() < 1e-21);
    // Nominal attitude: ABS under the reader at 11 + 18 µm·θ0 = 12.8 nm; h = 12 → PT 1.8 nm.
    let pt = ab.static_pole_tip(0.0, &Attitude::pitch_only(100e-6), 12e-9);
    assert!((pt - 1.8e-9).abs() < 1e-15, "{pt:e}");
}

#[test]
fn pushback_curves() {
    let lin = PushbackCurve::default();
    let flat = PushbackCurve::flattened();
    for h in [0.0, 5.0, 12.0, 18.0, 30.0] {
        assert!((lin.rise_at(h * NM) - 0.5 * h * NM).abs() < 1e-20);
    }
    assert!((flat.rise_at(10.0 * NM) - 5.0 * NM).abs() < 1e-20);
    assert!((flat.rise_at(18.0 * NM) - 7.5 * NM).abs() < 1e-20);
    assert!((flat.rise_at(25.0 * NM) - 9.25 * NM).abs() < 1e-20);
}

fn at(table: &DeltaFabTable, h_nm: f64) -> StaticState {
    *table
        .points()
        .iter()
        .find(|s| (s.actuation - h_nm * NM).abs() < 1e-15)
        .unwrap()
}

#[test]
fn delta_fab_calibration_reproduces_spec_reference() {
    // §3.3: TFC-centre application, balanced F_j,0, default tables, ΔFH = 0.5 h:
    // ΔF_AB = 2.40 / 10.0 / 32.4 mN and PT = 11.29 / 7.79 / 4.78 nm at h = 5 / 12 / 18 nm.
    // Tolerance: half a unit of the last quoted digit.
    let ab = linear_ab();
    let t = DeltaFabTable::calibrate_default(&ab, &PushbackCurve::default()).unwrap();
    let cases = [
        (5.0, 2.40e-3, 0.005e-3, 11.29e-9),
        (12.0, 10.0e-3, 0.05e-3, 7.79e-9),
        (18.0, 32.4e-3, 0.05e-3, 4.78e-9),
    ];
    for (h, df, tol, pt) in cases {
        let s = at(&t, h);
        assert!(
            (s.delta_force - df).abs() <= tol,
            "h {h}: ΔF {:e}",
            s.delta_force
        );
        assert!(
            (s.pole_tip - pt).abs() <= 0.005e-9,
            "h {h}: PT {:e}",
            s.pole_tip
        );
        assert!((s.tfc_rise - 0.5 * h * NM).abs() < 1e-16);
        assert!(!s.ab_lost);
        // Interpolation hits the grid values.
        assert!((t.delta_force_at(h * NM) - s.delta_force).abs() < 1e-15);
    }
    // §3.3 "applied at the TFC it is ~10 mN, raises the TE ~6 nm, trims the pitch −4 µrad".
    let s = at(&t, 12.0);
    assert!((s.te_rise - 6.07e-9).abs() < 0.01e-9, "{:e}", s.te_rise);
    assert!(((s.pitch - 100e-6) - (-4.39e-6)).abs() < 0.01e-6);
    // h = 0 is the nominal state.
    let s0 = at(&t, 0.0);
    assert!(s0.delta_force.abs() < 1e-12 && s0.heave.abs() < 1e-18);
    // Linear push-back lifts the TE spring to FH_lim just below 22 nm: the table stops there.
    assert_eq!(t.ab_lost_at(), Some(22.0 * NM));
    assert!((t.max_actuation() - 21.5 * NM).abs() < 1e-18);
    assert_eq!(t.delta_force_at(25.0 * NM), at(&t, 21.5).delta_force);
    // Linear interpolation between grid points.
    let mid = 0.5 * (at(&t, 12.0).delta_force + at(&t, 12.5).delta_force);
    assert!((t.delta_force_at(12.25 * NM) - mid).abs() < 1e-15);
}

#[test]
fn flattened_pushback_calibrates_to_25_nm() {
    // Validation variant: ΔFH(18) = 7.5 nm, bulge bottom 12.5 + 7.5 − 18 = 2.0 nm (lubricant
    // contact band 1.5–3 nm without solid contact, §3.3).
    let ab = linear_ab();
    let t = DeltaFabTable::calibrate_default(&ab, &PushbackCurve::flattened()).unwrap();
    assert_eq!(t.ab_lost_at(), None);
    assert!((t.max_actuation() - 25.0 * NM).abs() < 1e-18);
    let s = at(&t, 18.0);
    let bottom = s.pole_tip - ab.read_height_above_bulge_bottom();
    // PT sits x_R·θ above the bottom: ≈ 0.3 nm.
    assert!((bottom - 2.29e-9).abs() < 0.01e-9, "{bottom:e}");
    assert!((s.tfc_rise - 7.5e-9).abs() < 1e-16);
    // Same as the linear curve up to 12 nm.
    let lin = DeltaFabTable::calibrate(&ab, &PushbackCurve::default(), 12e-9, 0.5e-9).unwrap();
    assert!((at(&t, 12.0).delta_force - at(&lin, 12.0).delta_force).abs() < 1e-12);
    // Values the docs quote.
    // (PT 3.3 nm puts k_r near 6.4e6 N/m, so ΔF_AB is larger than with the linear curve.)
    assert!(
        (s.delta_force - 52.67e-3).abs() < 0.01e-3,
        "{:e}",
        s.delta_force
    );
    assert!((s.pole_tip - 3.29e-9).abs() < 0.01e-9, "{:e}", s.pole_tip);
}

#[test]
fn com_application_lifts_the_leading_edge() {
    // §3.3: COM-applied, ΔF_AB ≈ 17.5 mN at 12 nm, LE up ~48 nm, pitch +34 µrad, driving the
    // front spring past FH_lim (solved with the cut-off off to see that state).
    let ab = ThreeDofAirBearing::new(&ThreeDofAbParams {
        stiffening_point: StiffeningPoint::Com,
        ..linear_params()
    })
    .unwrap();
    let s = ab
        .solve_static(12e-9, StaticCondition::TfcRise(6e-9), None, true)
        .unwrap();
    assert!(
        (s.delta_force - 17.5e-3).abs() < 0.05e-3,
        "{:e}",
        s.delta_force
    );
    assert!((s.le_rise - 48e-9).abs() < 0.5e-9, "{:e}", s.le_rise);
    assert!(((s.pitch - 100e-6) - 34e-6).abs() < 0.5e-6, "{:e}", s.pitch);
    assert!(s.ab_lost);
    // With the FH_lim guard the COM variant has no equilibrium there, and the calibrated table
    // ends early (the LE spring passes 22 nm by h ≈ 5 nm).
    assert!(ab
        .solve_static(12e-9, StaticCondition::TfcRise(6e-9), None, false)
        .is_err());
    let t = DeltaFabTable::calibrate_default(&ab, &PushbackCurve::default()).unwrap();
    let lost = t.ab_lost_at().unwrap();
    assert!(lost > 1e-9 && lost <= 6e-9, "{lost:e}");
}

#[test]
fn faithful_nominal_forces_retrim_before_actuation() {
    // §3.3 claims ~26 µrad nose-down and the TE up ~3.4 nm with zero actuation. That holds
    // with the stiffnesses frozen at k_nom (PT = 11 nm); with k(PT) the unactuated reader sits
    // at PT ≈ 13.8 nm + the TE rise, k_r is softer and the TE rises ~7.3 nm (−27 µrad).
    let nominal_row = |pt: f64| AbFrequencyPoint {
        pole_tip: pt,
        first_pitch_hz: 110e3,
        normal_hz: default_normal_frequency_hz(11e-9),
        roll_hz: 100e3,
    };
    let frozen = AbFrequencyTable::new(vec![nominal_row(2.5e-9), nominal_row(20e-9)]).unwrap();
    let frozen = ThreeDofAirBearing::new(&ThreeDofAbParams {
        nominal_force: NominalForce::AsPrinted,
        frequencies: frozen,
        ..linear_params()
    })
    .unwrap();
    let s = frozen
        .solve_static(0.0, StaticCondition::GivenForce(0.0), None, false)
        .unwrap();
    assert!(
        ((s.pitch - 100e-6) - (-25.9e-6)).abs() < 0.1e-6,
        "{:e}",
        s.pitch
    );
    assert!((s.te_rise - 3.42e-9).abs() < 0.01e-9, "{:e}", s.te_rise);

    let ab = ThreeDofAirBearing::new(&ThreeDofAbParams {
        nominal_force: NominalForce::AsPrinted,
        ..linear_params()
    })
    .unwrap();
    let s = ab
        .solve_static(0.0, StaticCondition::GivenForce(0.0), None, false)
        .unwrap();
    assert!(
        ((s.pitch - 100e-6) - (-27.1e-6)).abs() < 0.1e-6,
        "{:e}",
        s.pitch
    );
    assert!((s.te_rise - 7.27e-9).abs() < 0.01e-9, "{:e}", s.te_rise);
    // Equilibrium: the springs carry the preload and balance the moment.
    assert!((s.front_force + s.rear_force - 14.7e-3 - 10.0 * s.heave).abs() < 1e-12);
    // Calibration under faithful forces is relative to this re-trimmed state.
    let t = DeltaFabTable::calibrate(&ab, &PushbackCurve::default(), 5e-9, 0.5e-9).unwrap();
    assert!(at(&t, 0.0).delta_force.abs() < 1e-12);
    assert!((at(&t, 5.0).tfc_rise - at(&t, 0.0).tfc_rise - 2.5e-9).abs() < 1e-16);
}

#[test]
fn stiffness_integral_is_the_antiderivative_of_the_interpolated_stiffness() {
    let ab = default_ab();
    let t = ab.stiffness_table();
    // Central differences of ∫k dPT reproduce k(PT) inside, below and above the table.
    for pt in [
        1.0e-9, 2.6e-9, 3.7e-9, 7.79e-9, 11.0e-9, 14.2e-9, 19.9e-9, 30e-9,
    ] {
        let d = 1e-13;
        let (a, b) = (
            t.stiffness_integral_at(pt - d),
            t.stiffness_integral_at(pt + d),
        );
        let (kf, kr) = t.stiffness_at(pt);
        assert!(
            ((b.0 - a.0) / (2.0 * d) / kf - 1.0).abs() < 1e-6,
            "front at {pt:e}"
        );
        assert!(
            ((b.1 - a.1) / (2.0 * d) / kr - 1.0).abs() < 1e-6,
            "rear at {pt:e}"
        );
    }
    // Against an independent trapezoid quadrature of stiffness_at over 2.5 → 20 nm.
    let n = 200_000;
    let (lo, hi) = (2.5e-9, 20e-9);
    let h = (hi - lo) / n as f64;
    let mut q = 0.5 * (t.stiffness_at(lo).1 + t.stiffness_at(hi).1);
    for k in 1..n {
        q += t.stiffness_at(lo + k as f64 * h).1;
    }
    q *= h;
    let exact = t.stiffness_integral_at(hi).1 - t.stiffness_integral_at(lo).1;
    assert!((exact / q - 1.0).abs() < 1e-6, "{exact} vs {q}");
}

#[test]
fn integrated_law_agrees_to_first_order_and_keeps_the_pushback_states_stable() {
    let (lin, int) = (linear_ab(), default_ab());
    let att = Attitude::new(100e-6, 0.0);
    let [s_f, s_r] = int.nominal_spring_spacings();
    // A 0.01 nm deflection: the two laws agree to O(deflection²).
    let sp = SpringSpacings {
        front: s_f - 1e-11,
        rear: s_r - 1e-11,
        ..SpringSpacings::default()
    };
    let (a, b) = (
        lin.forces(&sp, 11e-9, 0.0, &att),
        int.forces(&sp, 11e-9, 0.0, &att),
    );
    assert!((a.rear - b.rear).abs() < 1e-3 * (a.rear - int.nominal_forces()[1]).abs());
    // The calibrated push-back state at 12 nm: heave stiffness (−∂F/∂z of the spring sum with
    // PT moving with the slider) positive for the integrated law, negative for the linear one.
    let heave_stiffness = |ab: &ThreeDofAirBearing| {
        let table = DeltaFabTable::calibrate_default(ab, &PushbackCurve::default()).unwrap();
        let dfab = table.delta_force_at(12e-9);
        let s = ab
            .solve_static(12e-9, StaticCondition::TfcRise(6e-9), None, false)
            .unwrap();
        let att = Attitude::new(s.pitch, 0.0);
        let force = |dz: f64| {
            let [pf, pr] = ab.spring_points();
            let sp = SpringSpacings {
                front: ab.nominal_spacing(&pf) + ab.spacing_increment(&pf, s.heave + dz, &att),
                rear: ab.nominal_spacing(&pr) + ab.spacing_increment(&pr, s.heave + dz, &att),
                ..SpringSpacings::default()
            };
            let f = ab.forces(&sp, s.pole_tip + dz, dfab, &att);
            f.front + f.rear
        };
        -(force(1e-11) - force(-1e-11)) / 2e-11
    };
    let (k_lin, k_int) = (heave_stiffness(&lin), heave_stiffness(&int));
    let table = DeltaFabTable::calibrate_default(&int, &PushbackCurve::default()).unwrap();
    for h in [5e-9, 12e-9, 18e-9] {
        let s = int
            .solve_static(h, StaticCondition::TfcRise(0.5 * h), None, false)
            .unwrap();
        eprintln!(
            "integrated law: h {:.0} nm ΔF_AB {:.3} mN PT {:.3} nm (table {:.3} mN)",
            h * 1e9,
            s.delta_force * 1e3,
            s.pole_tip * 1e9,
            table.delta_force_at(h) * 1e3
        );
    }
    eprintln!("heave stiffness at 12 nm: linear {k_lin:.4e}, integrated {k_int:.4e} N/m");
    assert!(k_int > 1e5, "integrated law: heave stiffness {k_int:e} N/m");
    assert!(k_lin < 0.0, "linear law: heave stiffness {k_lin:e} N/m");
}

#[test]
fn tangent_stiffness_shows_the_linear_law_diverging_where_the_integrated_law_holds() {
    // The 12 nm push-back state of each law (docs/dynamics-3dof-air-bearing.md: heave
    // stiffness of the two springs +1.81e6 N/m integrated, −1.58e5 N/m linear).
    for (law, expected) in [
        (SpringLaw::Integrated, 1.815e6),
        (SpringLaw::Linear, -1.582e5),
    ] {
        let ab = ThreeDofAirBearing::new(&ThreeDofAbParams {
            spring_law: law,
            ..ThreeDofAbParams::default()
        })
        .unwrap();
        let t = DeltaFabTable::calibrate_default(&ab, &PushbackCurve::default()).unwrap();
        let s = at(&t, 12.0);
        let k = ab.tangent_stiffness(&s);
        let suspension = ab.params().suspension.heave_stiffness;
        // Independently, in heave every spacing and PT move together (∂PT/∂z = 1):
        // integrated −∂F/∂ŝ = k(PT); linear k − (FH_nom − ŝ)·dk/dPT.
        let (kf, kr) = ab.stiffness_at(s.pole_tip);
        let d = 1e-13;
        let (kf1, kr1) = ab.stiffness_at(s.pole_tip + d);
        let (kf0, kr0) = ab.stiffness_at(s.pole_tip - d);
        let fh = ab.params().nominal_flying_height;
        let att = crate::dynamics::geometry::Attitude::pitch_only(s.pitch);
        let [pf, pr] = ab.spring_points();
        let s_hat = |p: &Vector3<f64>| fh + ab.spacing_increment(p, s.heave, &att);
        let analytic = match law {
            SpringLaw::Integrated => kf + kr,
            SpringLaw::Linear => {
                kf - (fh - s_hat(&pf)) * (kf1 - kf0) / (2.0 * d) + kr
                    - (fh - s_hat(&pr)) * (kr1 - kr0) / (2.0 * d)
            }
        };
        let kzz = k[(0, 0)] - suspension;
        assert!(
            (kzz / analytic - 1.0).abs() < 1e-4,
            "{law:?}: {kzz:e} vs {analytic:e}"
        );
        assert!(
            (kzz / expected - 1.0).abs() < 1e-3,
            "{law:?}: {kzz:e} vs {expected:e}"
        );
        let eig = ab.heave_pitch_eigenvalues(&s);
        match law {
            SpringLaw::Integrated => {
                assert!(eig[0].re > 0.0 && eig[0].im == 0.0, "{eig:?}");
                let f = eig.map(|l| l.re.sqrt() / std::f64::consts::TAU / 1e3);
                // The 1st pitch mode stays near its 110 kHz.
                assert!((f[0] - 108.0).abs() < 2.0, "{f:?} kHz");
            }
            SpringLaw::Linear => {
                assert!(eig[0].re < 0.0, "a divergence: {eig:?}");
                // Growth time 1/√−λ ≈ 1 µs: far inside one DMW period.
                let tau = 1.0 / (-eig[0].re).sqrt();
                assert!(tau > 0.5e-6 && tau < 2e-6, "{tau:e} s");
            }
        }
    }
}
