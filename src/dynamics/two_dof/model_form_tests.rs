//! The model-form switches of the 2-DOF interface (docs/model-form.md), each against an
//! independent derivation: the integrated-stiffness reading against a quadrature of the ISBL
//! stiffness, the MTL lubricant force against the closed-form hydrodynamic law written out
//! from the FWM fit (eqs. 3.40, A.9) and its limits outside the film and in solid contact.

use super::*;
use crate::contact::isbl::{IsblModel, IsblParams};
use crate::contact::mtl::FwmExperiment;
use crate::dynamics::params::{improved_2dof, initial_2dof};

fn lookup() -> IsblLookup {
    IsblLookup::build_standard(IsblModel::new(IsblParams::improved_2dof()).unwrap()).unwrap()
}

fn options(contact_force: ContactForceForm, lubricant: LubricantForce) -> SimOptions {
    SimOptions {
        contact_force,
        lubricant,
        ..SimOptions::default()
    }
}

/// The interface of `case` at rest with the bulge POC at solid spacing `s` (pitch nominal,
/// t = 0, no DMW): the spacing is the heave plus a constant at fixed pitch.
fn at_spacing(case: &TwoDofCase, s: f64) -> InterfaceState {
    let s0 = case.poc_kinematics(0.0, &[0.0; 4]).unwrap().spacing;
    let i = case.interface(0.0, &[s - s0, 0.0, 0.0, 0.0]).unwrap();
    assert!((i.spacing - s).abs() < 1e-18, "{} vs {s}", i.spacing);
    i
}

#[test]
fn integrated_stiffness_is_the_quadrature_of_the_contact_stiffness() {
    let isbl = lookup();
    let h = 12e-9;
    let case = TwoDofCase::new(
        &improved_2dof(),
        h,
        &isbl,
        None,
        options(ContactForceForm::IntegratedStiffness, LubricantForce::None),
    )
    .unwrap();
    let a = case.nominal_area();
    let threshold = 3.0 * 0.5e-9;
    for s in [1.4e-9, 1.1e-9, 0.8e-9] {
        let i = at_spacing(&case, s);
        // A_n ∫_s^{3σ} k_c(h) dh by Simpson's rule on the table's stiffness (its own GW
        // integral, not the pressure column the switch reads).
        let n = 400;
        let dh = (threshold - s) / n as f64;
        let k = |j: usize| isbl.at(s + j as f64 * dh).unwrap().stiffness;
        let simpson: f64 = (0..=n)
            .map(|j| {
                let w = if j == 0 || j == n {
                    1.0
                } else if j % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * k(j)
            })
            .sum::<f64>()
            * dh
            / 3.0;
        let expected = a * simpson;
        assert!(
            (i.contact_force / expected - 1.0).abs() < 2e-3,
            "s = {s}: F_c {} vs A_n∫k_c {}",
            i.contact_force,
            expected
        );
        // Softer than the tangent reading wherever k_c grows into the interface (convex P).
        let tangent = a * isbl.at(s).unwrap().stiffness * (threshold - s);
        assert!(i.contact_force < tangent);
    }
    // Continuous at the threshold: by the mean-value theorem 0 < F_c(3σ − δ) ≤ A_n k_c(3σ − δ)·δ
    // (k_c grows into the interface).
    let delta = 1e-12;
    let just = at_spacing(&case, threshold - delta);
    let bound = a * isbl.at(threshold - delta).unwrap().stiffness * delta;
    assert!(
        just.contact_force > 0.0 && just.contact_force <= bound * (1.0 + 1e-6),
        "{} vs {bound}",
        just.contact_force
    );
}

#[test]
fn mtl_lubricant_force_follows_the_hydrodynamic_law_and_its_limits() {
    let isbl = lookup();
    let model = improved_2dof();
    let case = TwoDofCase::new(
        &model,
        9.5e-9,
        &isbl,
        None,
        options(ContactForceForm::InterferenceTangent, LubricantForce::Mtl),
    )
    .unwrap();
    let (sigma, t, kappa): (f64, f64, f64) = (0.5e-9, 1.5e-9, 0.3e-9);
    // Closed form (eqs. 3.40, A.9): P_lub = C_P (d0^−m − (t − κ)^−m), C_P = P0 (U/γ̇0)^m,
    // d0 = s − 3σ − κ, written out from the FWM fit's three numbers.
    let fit = FwmExperiment::fukuzawa_z03().high_shear_fit();
    let m = fit.normal_exponent;
    let c_p = fit.p0 * (model.disk_speed / fit.critical_shear_rate).powf(m);
    for s in [2.95e-9, 2.6e-9, 2.2e-9] {
        let d0 = s - 3.0 * sigma - kappa;
        let expected = c_p * (d0.powf(-m) - (t - kappa).powf(-m));
        let i = at_spacing(&case, s);
        assert!(
            (i.lubricant_force / expected - 1.0).abs() < 1e-9,
            "s = {s}: P_lub {} vs {}",
            i.lubricant_force,
            expected
        );
        assert_eq!(i.contact_force, 0.0, "no solid contact above 3σ");
    }
    // Outside the film (s ≥ 3σ + t): nothing; in solid contact (s < 3σ): the force at 3σ held.
    assert_eq!(at_spacing(&case, 3.0e-9 + 1e-12).lubricant_force, 0.0);
    let held = at_spacing(&case, 1.5e-9 - 1e-13).lubricant_force;
    let deeper = at_spacing(&case, 1.0e-9);
    assert!((deeper.lubricant_force / held - 1.0).abs() < 1e-9);
    assert!(deeper.contact_force > 0.0);
    // The held force exceeds the end of the hydrodynamic range (the transition adds to it).
    let end = c_p * (kappa.powf(-m) - (t - kappa).powf(-m));
    assert!(held > end, "{held} vs {end}");
    // Without the switch the same state carries no lubricant force.
    let plain = TwoDofCase::new(&model, 9.5e-9, &isbl, None, SimOptions::default()).unwrap();
    assert_eq!(at_spacing(&plain, 2.6e-9).lubricant_force, 0.0);
}

#[test]
fn mtl_lubricant_enters_the_force_balance_at_rest() {
    // The static equilibrium (Newton on the rest accelerations, which include P_lub) of the
    // 12 nm case: the bulge rides on the lubricant inside the film, above solid contact, the
    // bearing force exceeding the adhesion (the Chapter 4 finding that the lubricant carries
    // steady contact, §4.1.7).
    let isbl = lookup();
    let h = 12e-9;
    let o = SimOptions {
        static_init: true,
        ..options(ContactForceForm::InterferenceTangent, LubricantForce::Mtl)
    };
    let case = TwoDofCase::new(&improved_2dof(), h, &isbl, None, o).unwrap();
    let q = case.static_equilibrium().unwrap();
    let i = case.interface(0.0, &[q[0], q[1], 0.0, 0.0]).unwrap();
    assert!(
        i.clearance > 0.0 && i.clearance < 2.0 * 0.75e-9,
        "{}",
        i.clearance
    );
    assert!(i.lubricant_force > i.adhesion && i.contact_force == 0.0);
    // Rest accelerations vanish with the lubricant term included.
    let mut dy = [0.0; 4];
    case.rhs(0.0, &[q[0], q[1], 0.0, 0.0], &mut dy).unwrap();
    assert!(dy[2].abs() < 1e-3 && dy[3].abs() < 1e3, "{dy:?}");
}

#[test]
fn mtl_needs_the_three_sigma_criterion() {
    let isbl =
        IsblLookup::build_standard(IsblModel::new(IsblParams::initial_2dof()).unwrap()).unwrap();
    let e = TwoDofCase::new(
        &initial_2dof(),
        5e-9,
        &isbl,
        None,
        options(ContactForceForm::InterferenceTangent, LubricantForce::Mtl),
    )
    .err()
    .expect("refused");
    assert!(e.to_string().contains("3σ"), "{e}");
}
