use super::reference::{hertz, kappa, westergaard};
use super::*;

fn settings() -> SolverSettings {
    SolverSettings {
        tolerance: 1e-10,
        max_iterations: 2000,
    }
}

#[test]
fn hertz_contact_radius_and_peak_pressure() {
    // 128² with the contact over 2/3 of the side: radius 43 elements.
    let h = hertz(128, 1.5, &settings()).unwrap();
    assert!((h.radius / h.radius_exact - 1.0).abs() < 0.01, "{h:?}");
    assert!((h.peak / h.peak_exact - 1.0).abs() < 0.01, "{h:?}");
}

#[test]
fn westergaard_contact_fraction_follows_the_load() {
    for c in westergaard(2048, &[0.05, 0.3, 0.7], &settings()).unwrap() {
        assert!((c.fraction / c.fraction_exact - 1.0).abs() < 0.005, "{c:?}");
    }
}

#[test]
fn pressure_and_separation_targets_agree() {
    let (heights, _) = reference::self_affine(64, 0.8, 2.0, 16.0, 7);
    let solver = BemSolver::new(
        &heights,
        64,
        64,
        (1.0 / 64.0, 1.0 / 64.0),
        1.0,
        Boundary::Periodic,
    )
    .unwrap();
    let by_p = solver
        .solve(Target::MeanPressure(0.5), &settings(), None)
        .unwrap();
    let by_d = solver
        .solve(Target::Separation(by_p.separation), &settings(), None)
        .unwrap();
    assert!((by_d.mean_pressure / by_p.mean_pressure - 1.0).abs() < 1e-6);
    assert_eq!(by_d.contact_fraction, by_p.contact_fraction);
    // Periodic: the separation is the mean gap.
    assert!((by_p.mean_gap - by_p.separation).abs() < 1e-9);
    // Complementarity holds to the tolerance on every element.
    for (p, g) in by_p.pressure.iter().zip(&by_p.gap) {
        assert!(*p >= 0.0 && *g >= -1e-9);
        assert!(*p == 0.0 || g.abs() < 1e-6);
    }
    // A warm start converges to the same state in fewer iterations.
    let warm = solver
        .solve(
            Target::MeanPressure(0.55),
            &settings(),
            Some(&by_p.pressure),
        )
        .unwrap();
    let cold = solver
        .solve(Target::MeanPressure(0.55), &settings(), None)
        .unwrap();
    assert!(
        warm.iterations < cold.iterations,
        "{} vs {}",
        warm.iterations,
        cold.iterations
    );
    assert!((warm.separation - cold.separation).abs() < 1e-8);
}

#[test]
fn separations_above_the_highest_point_carry_no_load() {
    let (heights, _) = reference::self_affine(32, 0.8, 2.0, 8.0, 3);
    let solver = BemSolver::new(&heights, 32, 32, (1.0, 1.0), 1.0, Boundary::Periodic).unwrap();
    let curve =
        force_separation(&solver, &[solver.max_height() + 0.1, 1.0, 0.5], &settings()).unwrap();
    assert_eq!(curve[0].mean_pressure, 0.0);
    assert!(curve[2].mean_pressure > curve[1].mean_pressure && curve[1].mean_pressure > 0.0);
}

#[test]
fn the_iteration_limit_is_an_error() {
    let (heights, _) = reference::self_affine(32, 0.8, 2.0, 8.0, 3);
    let solver = BemSolver::new(&heights, 32, 32, (1.0, 1.0), 1.0, Boundary::Periodic).unwrap();
    let tight = SolverSettings {
        tolerance: 1e-14,
        max_iterations: 2,
    };
    let e = solver
        .solve(Target::MeanPressure(0.1), &tight, None)
        .unwrap_err();
    assert!(
        e.to_string().contains("did not converge in 2 iterations"),
        "{e}"
    );
}

#[test]
fn bad_input_is_refused() {
    let nan = [0.0, f64::NAN, 1.0, 2.0];
    assert!(BemSolver::new(&nan, 2, 2, (1.0, 1.0), 1.0, Boundary::Periodic).is_err());
    let flat = [1.0; 4];
    assert!(BemSolver::new(&flat, 2, 2, (1.0, 1.0), 1.0, Boundary::Periodic).is_err());
    let ok = [0.0, 1.0, 2.0, 3.0];
    assert!(BemSolver::new(&ok, 2, 2, (1.0, 1.0), -1.0, Boundary::Periodic).is_err());
}

#[test]
fn kappa_lies_between_persson_and_bgt() {
    let k = kappa(128, (0.8, 2.0, 16.0, 1), &[0.005, 0.01], &settings()).unwrap();
    assert!(k.kappa > 1.5 && k.kappa < 3.0, "{k:?}");
}
