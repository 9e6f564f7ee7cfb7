//! 2-DOF case tests: equilibrium, tracking of slow disk motion, energy, the published flying
//! clearance, and bad input.

use super::*;
use crate::contact::isbl::{IsblModel, IsblParams};
use crate::dynamics::params::improved_2dof;
use std::f64::consts::PI;

fn lookup() -> IsblLookup {
    IsblLookup::build_standard(IsblModel::new(IsblParams::improved_2dof()).unwrap()).unwrap()
}

fn short(duration: f64) -> SimOptions {
    SimOptions {
        duration,
        output_step: 0.25e-6,
        ..SimOptions::default()
    }
}

/// Energy of the linear heave–pitch system with both AB springs and the suspension:
/// `½ q̇ᵀ M q̇ + ½ qᵀ K q + ½ k_r z_r²` (the rear spring is on the right-hand side).
fn energy(case: &TwoDofCase, y: &[f64; 4]) -> f64 {
    let q = Vector2::new(y[0], y[1]);
    let v = Vector2::new(y[2], y[3]);
    let m = case.inverse_mass.try_inverse().unwrap();
    let d = case.air_bearing.half_length;
    let z_r = y[0] - d * y[1];
    0.5 * v.dot(&(m * v))
        + 0.5 * q.dot(&(case.stiffness * q))
        + 0.5 * case.air_bearing.rear_stiffness(case.actuation) * z_r * z_r
}

#[test]
fn nominal_state_stays_put_without_dmw_or_interfacial_forces() {
    // h_TFC = 0: no nominal area, so no contact or adhesion; no DMW (docs/simulation.md:
    // drift < 1e-15 m over 2 ms).
    let isbl = lookup();
    let case = TwoDofCase::new(&improved_2dof(), 0.0, &isbl, None, short(2e-3)).unwrap();
    assert_eq!(case.nominal_area(), 0.0);
    let h = case.run().unwrap();
    let drift = h.heave.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(drift < 1e-15, "drift {drift:e} m");
    // With no bulge the POC is the TE-side rim of the (flat) ellipsoid, x_TFC − a = 5 µm from
    // the TE: s = 11.75 nm + 5 µm · θ0.
    assert!(
        (h.spacing[0] - (11.75e-9 + 5e-6 * 100e-6)).abs() < 1e-13,
        "{}",
        h.spacing[0]
    );
}

#[test]
fn settles_to_the_static_equilibrium_with_adhesion() {
    // 8.5 nm actuation, no DMW: adhesion pulls the slider down a little; after the transient
    // the state is at rest and the static force balance holds.
    let isbl = lookup();
    let case = TwoDofCase::new(&improved_2dof(), 8.5e-9, &isbl, None, short(2e-3)).unwrap();
    let h = case.run().unwrap();
    let n = h.len();
    let y = [h.heave[n - 1], h.pitch_offset[n - 1], 0.0, 0.0];
    let mut dy = [0.0; 4];
    case.rhs(2e-3, &y, &mut dy).unwrap();
    // Residual acceleration of the final position (at rest) vs the adhesion acceleration.
    let i = case.interface(2e-3, &y).unwrap();
    let scale = i.adhesion / case.model.slider.mass;
    assert!(dy[2].abs() < 1e-4 * scale, "{} vs {}", dy[2], scale);
    let spread = h.heave[n - 400..]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    assert!(
        spread.1 - spread.0 < 1e-15,
        "still moving: {:e}",
        spread.1 - spread.0
    );
    // The static solver finds the same rest state directly (§5.4 init = "static").
    let q = case.static_equilibrium().unwrap();
    assert!(
        (q[0] - h.heave[n - 1]).abs() < 1e-15,
        "{:e} vs {:e}",
        q[0],
        h.heave[n - 1]
    );
    assert!((q[1] - h.pitch_offset[n - 1]).abs() < 1e-12);
    // Published flying clearance at 8.5 nm: 2.54 nm (class K ±0.05 nm, §12 row 18); the
    // independent reference gets 2.525 nm with F_s(s).
    let c = h.clearance[n - 1];
    assert!((c - 2.54e-9).abs() < 0.05e-9, "clearance {:.4} nm", c * 1e9);
    assert_eq!(h.contact_force[n - 1], 0.0);
}

#[test]
fn slow_disk_motion_is_tracked() {
    // A 1 kHz, 1 nm DMW (far below the 110/300 kHz AB modes): the slider follows the disk, the
    // spacing hardly changes (transfer ≈ 1).
    let isbl = lookup();
    let fs = 4e6;
    let n = (2.2e-3 * fs) as usize;
    let w = 2.0 * PI * 1e3;
    let d: Vec<f64> = (0..n).map(|k| 1e-9 * (w * k as f64 / fs).sin()).collect();
    let v: Vec<f64> = (0..n)
        .map(|k| 1e-9 * w * (w * k as f64 / fs).cos())
        .collect();
    let dmw = DmwInput {
        displacement: &d,
        velocity: &v,
        sample_rate: fs,
    };
    let std = |x: &[f64]| {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
    };
    // Every point sees the same disk motion: the slider moves with it (heave transfer 1).
    let mut same = short(2e-3);
    same.transit_delay = false;
    let h = TwoDofCase::new(&improved_2dof(), 0.0, &isbl, Some(dmw), same)
        .unwrap()
        .run()
        .unwrap();
    let half = h.len() / 2;
    let disk = std(&h.disk_displacement[half..]);
    let transfer = std(&h.heave[half..]) / disk;
    assert!((transfer - 1.0).abs() < 1e-3, "transfer {transfer}");
    assert!(std(&h.spacing[half..]) < 1e-3 * disk);
    // One track passing under the slider (the LE sees it 62 µs early): heave and pitch share
    // the motion, and the bulge still tracks it to ~1 %.
    let h = TwoDofCase::new(&improved_2dof(), 0.0, &isbl, Some(dmw), short(2e-3))
        .unwrap()
        .run()
        .unwrap();
    let spacing = std(&h.spacing[half..]);
    assert!(
        spacing < 0.02 * disk,
        "spacing std {spacing:e} vs disk {disk:e}"
    );
}

#[test]
fn undamped_free_vibration_creates_no_energy() {
    let isbl = lookup();
    let mut model = improved_2dof();
    model.air_bearing.front_damping_ratio = 0.0;
    model.air_bearing.rear_damping_ratio = 0.0;
    model.suspension.heave_damping_ratio = 0.0;
    model.suspension.pitch_damping_ratio = 0.0;
    // Adaptive at the spec's tolerances (atol 1e-14 m ≈ 1e-5 of the 1 nm amplitude): the
    // scheme may only dissipate, by no more than its tolerance allows; at a fixed 1 ns step
    // the energy is conserved to 1e-8.
    for (integrator, loss) in [
        (Integrator::recommended(), 1e-2),
        (Integrator::Rk5Fixed { step: 1e-9 }, 1e-8),
    ] {
        let mut options = short(0.5e-3);
        options.initial_state = [1e-9, 2e-6, 0.0, 0.0];
        options.integrator = integrator;
        let case = TwoDofCase::new(&model, 0.0, &isbl, None, options).unwrap();
        let h = case.run().unwrap();
        let e0 = energy(&case, &options.initial_state);
        let n = h.len();
        let e1 = energy(
            &case,
            &[
                h.heave[n - 1],
                h.pitch_offset[n - 1],
                h.heave_rate[n - 1],
                h.pitch_rate[n - 1],
            ],
        );
        assert!(
            e1 <= e0 * (1.0 + 1e-9),
            "{integrator:?}: energy grew: {e0:e} → {e1:e}"
        );
        assert!(
            e1 >= e0 * (1.0 - loss),
            "{integrator:?}: energy lost: {e0:e} → {e1:e}"
        );
    }
}

#[test]
fn contact_at_high_actuation_and_air_bearing_loss() {
    let isbl = lookup();
    // 12 nm without DMW: steady solid contact (negative clearance), friction and real area.
    let case = TwoDofCase::new(&improved_2dof(), 12e-9, &isbl, None, short(1e-3)).unwrap();
    let h = case.run().unwrap();
    let n = h.len();
    assert!(h.clearance[n - 1] < 0.0);
    assert!(h.contact_force[n - 1] > 0.0 && h.friction[n - 1] > 0.0 && h.real_area[n - 1] > 0.0);
    // 15 nm from the nominal state starts 3.9 nm deep in the disk: the contact throws the
    // slider off the air bearing. From the static equilibrium it settles into steady contact.
    let e = TwoDofCase::new(&improved_2dof(), 15e-9, &isbl, None, short(0.2e-3))
        .unwrap()
        .run()
        .unwrap_err()
        .to_string();
    assert!(e.contains("air bearing lost"), "{e}");
    let mut options = short(0.2e-3);
    options.static_init = true;
    let h = TwoDofCase::new(&improved_2dof(), 15e-9, &isbl, None, options)
        .unwrap()
        .run()
        .unwrap();
    let spread = h
        .clearance
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    assert!(spread.1 < 0.0 && spread.1 - spread.0 < 1e-12, "{spread:?}");
    // Lifted 5 nm: the TE flies above 15 nm → stopped and reported, not continued.
    let mut options = short(0.2e-3);
    options.initial_state = [5e-9, 0.0, 0.0, 0.0];
    let case = TwoDofCase::new(&improved_2dof(), 0.0, &isbl, None, options).unwrap();
    let e = case.run().unwrap_err().to_string();
    assert!(e.contains("air bearing lost"), "{e}");
}

#[test]
fn bad_input_is_refused() {
    let isbl = lookup();
    let mut model = improved_2dof();
    model.slider.mass = -1.0;
    let e = TwoDofCase::new(&model, 5e-9, &isbl, None, short(1e-4))
        .err()
        .unwrap();
    assert!(e.to_string().contains("mass"), "{e}");
    let e = TwoDofCase::new(&improved_2dof(), 20e-9, &isbl, None, short(1e-4))
        .err()
        .unwrap();
    assert!(e.to_string().contains("actuation"), "{e}");
    let d = vec![0.0; 100];
    let dmw = DmwInput {
        displacement: &d,
        velocity: &d,
        sample_rate: 4e6,
    };
    let e = TwoDofCase::new(&improved_2dof(), 5e-9, &isbl, Some(dmw), short(1e-3))
        .err()
        .unwrap();
    assert!(e.to_string().contains("DMW record"), "{e}");
    let mut o = short(1e-3);
    o.integrator = Integrator::Rk5Fixed { step: -1.0 };
    assert!(TwoDofCase::new(&improved_2dof(), 5e-9, &isbl, None, o).is_err());
}

#[test]
fn agrees_with_the_independent_scipy_implementation() {
    // bench/two_dof_scipy.py (written from the spec by another author, scipy RK45, PCHIP on
    // the shared ISBL table; bench/README.md): 12 nm steady contact c̄ = −0.7982 nm,
    // F_c = 1.1664 mN, Q = 1.5372 mN, μ = 1.318; 8.5 nm flying c̄ = 2.52505 nm. Steady contact
    // and the static flying state hardly depend on the DMW realisation (std 0.007 / 0.04 nm),
    // so the no-DMW cases are compared.
    let isbl = lookup();
    let params = crate::dynamics::metrics::CaseParams::improved_2dof();
    let run = |h: f64| {
        let o = SimOptions {
            static_init: true,
            ..SimOptions::default()
        };
        let case = TwoDofCase::new(&improved_2dof(), h, &isbl, None, o).unwrap();
        case.run().unwrap().metrics(&params).unwrap()
    };
    let m = run(12e-9);
    let c = m.contact.unwrap();
    assert!(
        (m.clearance_m.mean + 0.7982e-9).abs() < 0.002e-9,
        "{}",
        m.clearance_m.mean
    );
    assert!((c.contact_force_n.mean / 1.1664e-3 - 1.0).abs() < 5e-3);
    assert!((c.friction_n.mean / 1.5372e-3 - 1.0).abs() < 5e-3);
    let m = run(8.5e-9);
    assert!(
        (m.clearance_m.mean - 2.52505e-9).abs() < 0.0005e-9,
        "{}",
        m.clearance_m.mean
    );
}

/// Strong adhesion folds the rest forces near the jump to contact: Newton from the nominal
/// state stalls on the fold, and the static equilibrium must be found from another start (the
/// contact side). Every actuation across the jump has one, with zero residual force.
#[test]
fn static_equilibrium_is_found_across_the_jump_to_contact() {
    for delta_gamma in [0.118, 0.15, 0.2] {
        let isbl = IsblLookup::build_standard(
            IsblModel::new(IsblParams {
                surface_energy: crate::contact::isbl::SurfaceEnergy::Constant { delta_gamma },
                ..IsblParams::improved_2dof()
            })
            .unwrap(),
        )
        .unwrap();
        for h in [9.3, 9.5, 9.7, 9.9] {
            let case =
                TwoDofCase::new(&improved_2dof(), h * 1e-9, &isbl, None, short(1e-4)).unwrap();
            let q = case
                .static_equilibrium()
                .unwrap_or_else(|e| panic!("Δγ {delta_gamma}, {h} nm: {e}"));
            let a = case
                .rest_acceleration(q[0], q[1], case.contact_damping)
                .unwrap();
            assert!(
                a[0].abs() * case.model.slider.mass < 1e-9 * case.model.suspension.preload,
                "Δγ {delta_gamma}, {h} nm: {a:?}"
            );
        }
    }
}

/// Where the damper-free rest state lies just inside the contact threshold and the frozen DMW
/// closes the gap, the contact damper's force jumps across zero at the threshold and no rest
/// state with it exists: the case starts from the damper-free one (such cases failed with
/// "Newton did not converge" before; docs/model-form.md, "Summit heights").
#[test]
fn static_start_falls_back_to_the_damper_free_rest_state_at_the_threshold_jump() {
    use crate::contact::isbl::{SummitDistribution, SurfaceEnergy};
    use crate::dynamics::air_bearing::RearStiffening;
    let isbl = IsblLookup::build_standard_unverified(
        IsblModel::new(IsblParams {
            summits: SummitDistribution::McCool,
            surface_energy: SurfaceEnergy::Constant { delta_gamma: 0.057 },
            lj_spacing: 0.186e-9,
            ..IsblParams::improved_2dof()
        })
        .unwrap(),
    )
    .unwrap();
    let mut model = improved_2dof();
    model.air_bearing.stiffening = RearStiffening::Quadratic { beta: 0.376 };
    model.interface.surface_energy = 0.057;
    model.interface.equilibrium_spacing = 0.186e-9;
    model.interface.contact_damping_ratio = 0.33;
    // The disk rising at 82 µm/s (the synthetic DMW's rate at t = 0 in the failing cases).
    let (fs, v0) = (4e6, 8.19e-5);
    let displacement: Vec<f64> = (0..8800).map(|i| v0 * (i as f64 / fs - 1e-4)).collect();
    let velocity = vec![v0; displacement.len()];
    let options = SimOptions {
        static_init: true,
        ..short(1e-4)
    };
    let mut fell_back = 0;
    for k in 0..=40 {
        let h = (9.7 + 0.01 * k as f64) * 1e-9;
        let input = DmwInput {
            displacement: &displacement,
            velocity: &velocity,
            sample_rate: fs,
        };
        let case = TwoDofCase::new(&model, h, &isbl, Some(input), options).unwrap();
        let q = case
            .static_equilibrium()
            .unwrap_or_else(|e| panic!("{h:e}: {e}"));
        let damped_fails = [0.0, -0.5, 0.5, -1.0, 1.0, -2.0, 2.0, -4.0, 4.0]
            .iter()
            .all(|dz| {
                case.static_equilibrium_from([dz * 1e-9, 0.0], case.contact_damping)
                    .is_err()
            });
        if !damped_fails {
            continue;
        }
        fell_back += 1;
        let scale = case.model.slider.mass / (1e-9 * case.model.suspension.preload);
        let undamped = case.rest_acceleration(q[0], q[1], 0.0).unwrap();
        let damped = case
            .rest_acceleration(q[0], q[1], case.contact_damping)
            .unwrap();
        // Balanced without the damper; the damper's jump (c_c|ṡ|) is what is left with it.
        assert!(undamped[0].abs() * scale < 1.0, "{h:e}: {undamped:?}");
        assert!(damped[0].abs() * scale > 1e3, "{h:e}: {damped:?}");
        let clearance = case.clearance_at_rest(q).unwrap();
        assert!(clearance < 0.0 && clearance > -0.2e-9, "{h:e}: {clearance}");
    }
    assert!(fell_back > 0, "no actuation needed the damper-free start");
}

/// Branch-tracking sweeps (docs/conventions.md): continuation from the neighbouring
/// actuation's equilibrium must land on the same equilibrium as the nominal start wherever
/// there is only one (the flying range below the adhesion fold), and the dynamic case started
/// there must settle where the nominal-start case settles.
#[test]
fn up_branch_continuation_matches_the_nominal_start_where_the_equilibrium_is_unique() {
    let isbl = lookup();
    let nm = 1e-9;
    let grid = [0.0, 2.0, 4.0, 6.0, 7.0, 7.6, 8.0, 8.3, 8.5];
    let mut prev: Option<[f64; 2]> = None;
    let mut roots = Vec::new();
    for &h in &grid {
        let case = TwoDofCase::new(&improved_2dof(), h * nm, &isbl, None, short(1e-4)).unwrap();
        let q = match prev {
            None => case.static_equilibrium().unwrap(),
            Some(q0) => case.static_equilibrium_near(q0).unwrap(),
        };
        let nominal = case.static_equilibrium().unwrap();
        let arm = 0.5 * improved_2dof().slider.length;
        assert!(
            (q[0] - nominal[0]).abs() < 1e-14 && ((q[1] - nominal[1]) * arm).abs() < 1e-14,
            "{h} nm: continuation {q:?} vs nominal start {nominal:?}"
        );
        roots.push(q);
        prev = Some(q);
    }
    // Dynamic: 8.5 nm from the continuation root vs from the nominal state (no DMW): the
    // steady mean clearances agree (the published 2.525 nm; scipy reference 2.52505 nm).
    let params = crate::dynamics::metrics::CaseParams::improved_2dof();
    let run = |static_init: bool, static_start: Option<[f64; 2]>| {
        let o = SimOptions {
            static_init,
            static_start,
            ..SimOptions::default()
        };
        let case = TwoDofCase::new(&improved_2dof(), 8.5 * nm, &isbl, None, o).unwrap();
        case.run()
            .unwrap()
            .metrics(&params)
            .unwrap()
            .clearance_m
            .mean
    };
    let branch = run(true, roots.last().copied());
    let nominal = run(false, None);
    assert!((branch - 2.52505e-9).abs() < 0.0005e-9, "{branch}");
    assert!((branch - nominal).abs() < 0.005e-9, "{branch} vs {nominal}");
}

/// Across the adhesion fold the continuation follows its branch: stepping down from deep
/// contact it may stay in contact where stepping up still flies, never the reverse, and
/// every root it returns is an equilibrium (zero rest force, checked by Newton's residual).
/// At the shipped Δγ the two coincide; with strong adhesion (Δγ = 0.2 N/m) the rest force
/// folds and there are two stable equilibria over part of the range: the down branch must
/// then be in solid contact where the up branch still flies (docs/simulation.md measures
/// the same hysteresis dynamically, 7.8–9.4 nm).
#[test]
fn continuation_branches_across_the_fold() {
    let strong = IsblLookup::build_standard(
        IsblModel::new(IsblParams {
            surface_energy: crate::contact::isbl::SurfaceEnergy::Constant { delta_gamma: 0.2 },
            ..IsblParams::improved_2dof()
        })
        .unwrap(),
    )
    .unwrap();
    let (up, down) = branches_over_the_fold(&strong);
    assert!(
        up.iter().zip(&down).any(|(u, d)| *u > 1e-9 && *d < 0.0),
        "no hysteresis at Δγ = 0.2 N/m: up {up:?}, down {down:?}"
    );
    let (up, down) = branches_over_the_fold(&lookup());
    for (u, d) in up.iter().zip(&down) {
        assert!((u - d).abs() < 1e-13, "shipped Δγ: up {u} vs down {d}");
    }
}

/// Static clearances of the up and down continuation over 7–10.6 nm (no DMW), checking
/// that the down branch never lies above the up branch and that both ends agree.
fn branches_over_the_fold(isbl: &IsblLookup) -> (Vec<f64>, Vec<f64>) {
    let nm = 1e-9;
    let grid: Vec<f64> = (0..=18).map(|i| (7.0 + 0.2 * i as f64) * nm).collect();
    let sweep = |order: Vec<usize>| {
        let mut prev: Option<[f64; 2]> = None;
        let mut c = vec![0.0; grid.len()];
        for i in order {
            let case = TwoDofCase::new(&improved_2dof(), grid[i], isbl, None, short(1e-4)).unwrap();
            let q = match prev {
                None => case.static_equilibrium().unwrap(),
                Some(q0) => case.static_equilibrium_near(q0).unwrap(),
            };
            c[i] = case.clearance_at_rest(q).unwrap();
            prev = Some(q);
        }
        c
    };
    let up = sweep((0..grid.len()).collect());
    let down = sweep((0..grid.len()).rev().collect());
    for (i, (u, d)) in up.iter().zip(&down).enumerate() {
        println!(
            "{:.1} nm: up {:.4} nm, down {:.4} nm",
            grid[i] / nm,
            u / nm,
            d / nm
        );
        assert!(
            *d <= u + 1e-12,
            "{:.1} nm: down {d} above up {u}",
            grid[i] / nm
        );
    }
    // Both ends agree (one equilibrium far from the fold).
    assert!((up[0] - down[0]).abs() < 1e-13);
    assert!((up[18] - down[18]).abs() < 1e-13);
    (up, down)
}
