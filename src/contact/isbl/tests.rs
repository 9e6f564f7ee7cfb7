//! Tests of the ISBL curves against the reference CSVs (independent numpy/scipy
//! implementation, tests/data/isbl), closed forms and the landmarks of docs/contact.md.

use super::asperity::KeRegime;
use super::*;

const DATA_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/isbl/");
const COLUMNS: [&str; 7] = [
    "P_Pa",
    "kc_Pa_per_m",
    "Ar_frac",
    "Q_Pa",
    "Fs_const_Pa",
    "Fs_var_Pa",
    "n_contacts_per_m2",
];

/// Rows of a reference CSV: `h_m` and the seven value columns in `COLUMNS` order.
fn read_reference(name: &str) -> Vec<(f64, [f64; 7])> {
    let path = format!("{DATA_DIR}{name}.csv");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let index = |col: &str| header.iter().position(|h| *h == col).unwrap();
    let h_index = index("h_m");
    let value_index: Vec<usize> = COLUMNS.iter().map(|c| index(c)).collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|x| x.trim().parse().unwrap()).collect();
            (f[h_index], std::array::from_fn(|k| f[value_index[k]]))
        })
        .collect()
}

fn with_energy(params: IsblParams, surface_energy: SurfaceEnergy) -> IsblModel {
    IsblModel::new(IsblParams {
        surface_energy,
        ..params
    })
    .unwrap()
}

/// Compares every column of one reference CSV (acceptance: ≤ 1e-6 relative wherever the
/// reference exceeds 1e-12 of its column's maximum); returns the worst errors.
fn check_reference(name: &str, params: IsblParams) -> [f64; 7] {
    let rows = read_reference(name);
    // The CSVs hold both surface-energy variants: constant Δγ = 0.06 N/m and the seed's
    // variable law (docs/contact.md).
    let constant = with_energy(params, SurfaceEnergy::Constant { delta_gamma: 0.06 });
    let variable = with_energy(params, SurfaceEnergy::seed_variable());
    let column_max: [f64; 7] =
        std::array::from_fn(|k| rows.iter().map(|r| r.1[k].abs()).fold(0.0, f64::max));
    let mut worst = [0.0f64; 7];
    for (h, want) in &rows {
        let c = constant.at(*h).unwrap();
        let v = variable.at(*h).unwrap();
        let got = [
            c.contact_pressure,
            c.contact_stiffness,
            c.real_area_fraction,
            c.friction_stress,
            c.adhesion,
            v.adhesion,
            c.contacts_per_area,
        ];
        for k in 0..7 {
            if want[k].abs() > 1e-12 * column_max[k] {
                let rel = (got[k] / want[k] - 1.0).abs();
                assert!(
                    rel <= 1e-6,
                    "{name} {} at h = {h:e}: got {:e}, want {:e} (rel {rel:e})",
                    COLUMNS[k],
                    got[k],
                    want[k]
                );
                worst[k] = worst[k].max(rel);
            }
        }
    }
    for k in 0..7 {
        eprintln!(
            "{name} {:>18}: worst relative error {:.2e}",
            COLUMNS[k], worst[k]
        );
    }
    worst
}

#[test]
fn reference_csv_initial_2dof() {
    check_reference("initial_2dof", IsblParams::initial_2dof());
}

#[test]
fn reference_csv_improved_2dof() {
    check_reference("improved_2dof", IsblParams::improved_2dof());
}

#[test]
fn reference_csv_three_dof() {
    check_reference("three_dof", IsblParams::three_dof());
}

#[test]
fn reference_csv_mtl_table_3_2() {
    check_reference("mtl_table_3_2", IsblParams::mtl_table_3_2());
}

// ---------------------------------------------------------------------------------------
// Closed forms and derived constants
// ---------------------------------------------------------------------------------------

/// DLC sphere on DLC of Ch. 3.1 (Table 3.2; docs/contact.md): E = 180 GPa, ν = 0.24, H = 18 GPa,
/// R = 102 μm.
fn dlc_sphere_ch3_1() -> IsblModel {
    IsblModel::new(IsblParams {
        summit_radius: 102e-6,
        slider_modulus: 180e9,
        disk_modulus: 180e9,
        slider_poisson: 0.24,
        disk_poisson: 0.24,
        yielding_poisson: 0.24,
        hardness: 18e9,
        ..IsblParams::initial_2dof()
    })
    .unwrap()
}

#[test]
fn composite_modulus_matches_spec() {
    // Table 3.2: E* = 95.5 GPa for the Ch. 3.1 DLC pair; Tables 2.2/2.4/4.2: 149.3 GPa (overcoats).
    let e = dlc_sphere_ch3_1().derived().composite_modulus;
    assert!((e / 95.5e9 - 1.0).abs() < 5e-4, "{e}");
    let e = IsblParams::initial_2dof().composite_modulus();
    assert!((e / 149.3e9 - 1.0).abs() < 5e-4, "{e}");
}

#[test]
fn derived_constants_match_spec_table_10() {
    // Eq. A.4 with Tables 2.2/2.4/3.2: K = 0.5565, ω_c = 2.49 nm (ω_c/σ = 2.86, 4.98), 30.0 nm
    // (36.6) for T3.2, β = 0.0464 / 0.0267 / 0.050, ψ = 0.517 / 0.392 / 0.145,
    // ψ_KE = 0.591 / 0.448 / 0.165. Tolerances: half a unit in the last printed digit.
    let close = |got: f64, want: f64, rel: f64| {
        assert!((got / want - 1.0).abs() < rel, "got {got}, want {want}")
    };
    let digits = |got: f64, want: f64, half_unit: f64| {
        assert!((got - want).abs() <= half_unit, "got {got}, want {want}")
    };
    let cases = [
        (
            IsblParams::initial_2dof(),
            2.49e-9,
            2.86,
            0.0464,
            0.517,
            0.591,
        ),
        (
            IsblParams::improved_2dof(),
            2.49e-9,
            4.98,
            0.0267,
            0.392,
            0.448,
        ),
        (IsblParams::three_dof(), 2.49e-9, 4.98, 0.0267, 0.392, 0.448),
        (
            IsblParams::mtl_table_3_2(),
            30.0e-9,
            36.6,
            0.050,
            0.145,
            0.165,
        ),
    ];
    for (p, wc, wc_star, beta, psi, psi_ke) in cases {
        let m = IsblModel::new(p).unwrap();
        let dv = m.derived();
        close(dv.k_factor, 0.5565, 1e-9);
        close(dv.critical_interference, wc, 3e-3);
        close(dv.critical_interference / p.sigma, wc_star, 3e-3);
        close(dv.beta, beta, 2e-2);
        digits(dv.plasticity_index, psi, 5e-4);
        digits(dv.plasticity_index_ke, psi_ke, 5e-4);
        assert!(!dv.elastic_plastic_adhesion_assumed);
        // L_c = (4/3)E*R^½ω_c^{3/2} = (2/3)πKHRω_c (eq. A.4: two forms of the same number).
        let hertz_lc = 4.0 / 3.0
            * dv.composite_modulus
            * p.summit_radius.sqrt()
            * dv.critical_interference.powf(1.5);
        close(dv.critical_load, hertz_lc, 1e-12);
    }
}

#[test]
fn hertz_limit_below_critical_interference() {
    // Hertz: P = (4/3)E*√R ω^{3/2}, A = πRω for ω ≤ ω_c (closed form). docs/contact.md: 1.29 and
    // 40.7 μN at ω = 0.1 and 1 nm; junction-shear Q = 118.9 and 1189 μN.
    let m = dlc_sphere_ch3_1();
    let dv = *m.derived();
    for omega in [
        1e-12,
        1e-10,
        1e-9,
        0.5 * dv.critical_interference,
        dv.critical_interference,
    ] {
        let c = m.asperity_at(omega).unwrap();
        let hertz = 4.0 / 3.0 * dv.composite_modulus * 102e-6f64.sqrt() * omega.powf(1.5);
        assert!((c.load / hertz - 1.0).abs() < 1e-12);
        assert!((c.area / (PI * 102e-6 * omega) - 1.0).abs() < 1e-12);
    }
    let c01 = m.asperity_at(0.1e-9).unwrap();
    let c1 = m.asperity_at(1e-9).unwrap();
    assert!((c01.load / 1.29e-6 - 1.0).abs() < 4e-3, "{}", c01.load);
    assert!((c1.load / 40.7e-6 - 1.0).abs() < 2e-3, "{}", c1.load);
    assert!(
        (c01.friction / 118.9e-6 - 1.0).abs() < 1e-3,
        "{}",
        c01.friction
    );
    assert!(
        (c1.friction / 1189e-6 - 1.0).abs() < 1e-3,
        "{}",
        c1.friction
    );
    // Seed power law reproduces the seed's 120 / 1120 μN (eq. A.6, fitted to 4 digits).
    let seed = IsblModel::new(IsblParams {
        friction_law: FrictionLaw::SeedPowerElastic,
        ..*m.params()
    })
    .unwrap();
    let q01 = seed.asperity_at(0.1e-9).unwrap().friction;
    let q1 = seed.asperity_at(1e-9).unwrap().friction;
    assert!((q01 / 120e-6 - 1.0).abs() < 5e-3, "{q01}");
    assert!((q1 / 1120e-6 - 1.0).abs() < 5e-3, "{q1}");
    // No contact at ω ≤ 0.
    assert_eq!(m.asperity_at(-1e-9).unwrap().load, 0.0);
    assert!(m.asperity_at(f64::NAN).is_err());
}

// ---------------------------------------------------------------------------------------
// Independent quadrature and derivatives
// ---------------------------------------------------------------------------------------

/// Composite Simpson rule with `n` (even) intervals: independent of the adaptive
/// Gauss–Kronrod code under test.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for i in 1..n {
        s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

#[test]
fn gaussian_integrals_match_independent_simpson_quadrature() {
    // P, k_c, A_r, n_c and the three adhesion parts by brute-force Simpson (elastic piece
    // in u = √(ω/ω_c), other pieces in ω; 20 σ_s beyond the Gaussian centre), to 1e-6.
    for p in [IsblParams::initial_2dof(), IsblParams::mtl_table_3_2()] {
        let m = IsblModel::new(p).unwrap();
        let dv = *m.derived();
        let (wc, s, eta, eps, t) = (
            dv.critical_interference,
            p.sigma,
            p.summit_density,
            p.lj_spacing,
            p.lubricant_thickness,
        );
        let phi = |z: f64| (-0.5 * (z / s).powi(2)).exp() / (s * (2.0 * PI).sqrt());
        for h_star in [-3.0, -0.5, 0.0, 1.7, 3.0, 5.0] {
            let d = h_star * s;
            let top = (-d).max(0.0) + 20.0 * s;
            // The regime is fixed per piece (not re-derived from ω*, which rounding can put on
            // the wrong side of a boundary at the Simpson end points).
            use asperity::KeRegime::*;
            let contact = |weight: &dyn Fn(f64) -> f64, law: &dyn Fn(KeRegime, f64) -> f64| {
                let elastic_end = (top / wc).min(1.0).sqrt();
                let mut sum = simpson(
                    |u| law(Elastic, u * u) * weight(d + wc * u * u) * 2.0 * wc * u,
                    0.0,
                    elastic_end,
                    4000,
                );
                for (regime, lo, hi) in [
                    (ElasticPlasticI, 1.0, 6.0),
                    (ElasticPlasticII, 6.0, 110.0),
                    (FullyPlastic, 110.0, 1e9),
                ] {
                    let (a, b) = (lo * wc, (hi * wc).min(top));
                    if b > a {
                        sum += simpson(|w| law(regime, w / wc) * weight(d + w), a, b, 4000);
                    }
                }
                sum
            };
            let k = dv.k_factor;
            let phi_slope = |z: f64| z / (s * s) * phi(z);
            let pt = m.at(d).unwrap();
            let checks = [
                (
                    eta * dv.critical_load
                        * contact(&phi, &|r, w| asperity::ke_load_ratio_in(r, w, k)),
                    pt.contact_pressure,
                ),
                (
                    eta * dv.critical_load
                        * contact(&phi_slope, &|r, w| asperity::ke_load_ratio_in(r, w, k)),
                    pt.contact_stiffness,
                ),
                (
                    eta * dv.critical_area * contact(&phi, &asperity::ke_area_ratio_in),
                    pt.real_area_fraction,
                ),
                (eta * contact(&phi, &|_, _| 1.0), pt.contacts_per_area),
                (
                    2.0 * PI
                        * p.summit_radius
                        * eta
                        * dv.delta_gamma_max
                        * contact(&phi, &|_, w| {
                            asperity::adhesion_factor_elastic(w * wc / eps).unwrap()
                        }),
                    pt.adhesion_solid,
                ),
                (
                    2.0 * PI
                        * p.summit_radius
                        * eta
                        * simpson(
                            |x| surface_energy_at(&p, x) * phi(d - x),
                            0.0,
                            eps.min(t),
                            2000,
                        )
                        + 2.0
                            * PI
                            * p.summit_radius
                            * eta
                            * simpson(
                                |x| surface_energy_at(&p, x) * phi(d - x),
                                eps.min(t),
                                t,
                                2000,
                            ),
                    pt.adhesion_lubricant,
                ),
                (
                    2.0 * PI
                        * p.summit_radius
                        * eta
                        * dv.delta_gamma_min
                        * simpson(
                            |x| {
                                let r = eps / (x + eps);
                                4.0 / 3.0 * (r.powi(2) - 0.25 * r.powi(8)) * phi(d - t - x)
                            },
                            0.0,
                            (d - t).max(0.0) + 20.0 * s,
                            40000,
                        ),
                    pt.adhesion_non_contacting,
                ),
            ];
            for (k, (want, got)) in checks.iter().enumerate() {
                assert!(
                    (got / want - 1.0).abs() < 1e-6,
                    "quantity {k} at h* = {h_star}: {got:e} vs Simpson {want:e}"
                );
            }
        }
    }
}

#[test]
fn stiffnesses_match_central_differences() {
    // docs/contact.md: analytic derivatives agree with central differences (step 1e-4σ,
    // truncation error ~1e-8·y'''/y').
    for p in [
        IsblParams::improved_2dof(),
        IsblParams::mtl_table_3_2(),
        IsblParams {
            friction_law: FrictionLaw::SeedPowerElastic,
            ..IsblParams::initial_2dof()
        },
    ] {
        let m = IsblModel::new(p).unwrap();
        let step = 1e-4 * p.sigma;
        for h_star in [-2.0, 0.0, 1.0, 3.0, 4.5] {
            let h = h_star * p.sigma;
            let (lo, mid, hi) = (
                m.at(h - step).unwrap(),
                m.at(h).unwrap(),
                m.at(h + step).unwrap(),
            );
            let fd = |f: fn(&IsblPoint) -> f64| (f(&hi) - f(&lo)) / (2.0 * step);
            let pairs = [
                (-fd(|q| q.contact_pressure), mid.contact_stiffness),
                (-fd(|q| q.real_area_fraction), mid.real_area_gradient),
                (-fd(|q| q.friction_stress), mid.friction_stiffness),
                (fd(|q| q.adhesion), mid.adhesion_gradient),
            ];
            for (k, (fd_value, analytic)) in pairs.iter().enumerate() {
                assert!(
                    (analytic / fd_value - 1.0).abs() < 1e-6,
                    "derivative {k} at h* = {h_star}: {analytic:e} vs FD {fd_value:e}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Physics: monotonicity, smoothness at regime and class boundaries, robustness
// ---------------------------------------------------------------------------------------

#[test]
fn curves_are_monotone_finite_and_continuous_at_boundaries() {
    for p in [
        IsblParams::initial_2dof(),
        IsblParams::improved_2dof(),
        IsblParams::mtl_table_3_2(),
        IsblParams {
            surface_energy: SurfaceEnergy::Constant { delta_gamma: 0.06 },
            ..IsblParams::mtl_table_3_2()
        },
    ] {
        let m = IsblModel::new(p).unwrap();
        let s = p.sigma;
        let wc = m.derived().critical_interference;
        let mut hs: Vec<f64> = (0..=80).map(|i| (-6.0 + 0.25 * i as f64) * s).collect();
        // Boundaries named by the spec: contact onset 3σ, lubricant top 3σ + t, MTL 3σ + 2κ
        // (κ = 0.3 nm), the non-contact class edge d = t (x-split), d = 0, d = ±ε, and the h
        // where the KE regime limits ω_c, 6ω_c, 110ω_c meet the integration cut-off.
        let mut boundaries = vec![
            0.0,
            3.0 * s,
            3.0 * s + p.lubricant_thickness,
            3.0 * s + 0.6e-9,
            p.lubricant_thickness,
            p.lubricant_thickness + p.lj_spacing,
            p.lj_spacing,
            -p.lj_spacing,
        ];
        for k in [1.0, 6.0, 110.0] {
            boundaries.push(14.0 * s - k * wc);
        }
        for b in boundaries {
            let below = m.at(b * (1.0 - 1e-13) - 1e-25).unwrap();
            let above = m.at(b * (1.0 + 1e-13) + 1e-25).unwrap();
            let pairs = [
                (below.contact_pressure, above.contact_pressure),
                (below.contact_stiffness, above.contact_stiffness),
                (below.real_area_fraction, above.real_area_fraction),
                (below.adhesion, above.adhesion),
                (below.adhesion_gradient, above.adhesion_gradient),
                (below.contacts_per_area, above.contacts_per_area),
            ];
            for (k, (a, c)) in pairs.iter().enumerate() {
                assert!(a.is_finite() && c.is_finite());
                assert!(
                    (a - c).abs() <= 1e-8 * a.abs().max(c.abs()),
                    "quantity {k} jumps at h = {b:e}: {a:e} vs {c:e}"
                );
            }
            hs.push(b);
        }
        hs.sort_by(f64::total_cmp);
        let points: Vec<IsblPoint> = hs.iter().map(|h| m.at(*h).unwrap()).collect();
        for pt in &points {
            for v in [
                pt.contact_pressure,
                pt.contact_stiffness,
                pt.real_area_fraction,
                pt.real_area_gradient,
                pt.friction_stress,
                pt.friction_stiffness,
                pt.adhesion_non_contacting,
                pt.adhesion_lubricant,
                pt.adhesion_solid,
                pt.contacts_per_area,
            ] {
                assert!(v.is_finite() && v >= 0.0, "{pt:?}");
            }
            assert!(
                pt.adhesion_gradient < 0.0,
                "dF_s/dh must be negative: {pt:?}"
            );
        }
        for w in points.windows(2) {
            // n_c and A_r saturate for deep interference; allow quadrature noise (1e-10).
            let not_above = |next: f64, prev: f64| next <= prev * (1.0 + 1e-10);
            if w[1].separation > w[0].separation {
                assert!(not_above(w[1].contact_pressure, w[0].contact_pressure));
                assert!(not_above(w[1].real_area_fraction, w[0].real_area_fraction));
                assert!(not_above(w[1].contacts_per_area, w[0].contacts_per_area));
                assert!(w[1].adhesion < w[0].adhesion, "F_s must fall with h");
            }
        }
    }
}

#[test]
fn far_tail_of_adhesion_matches_asymptote() {
    // docs/contact.md: improved set at h* = 12, reference 1.083e5 Pa; tail formula
    // 2πRNΔγ(4/3)(ε/D)²[1 + 3σ²/D²], D = d − t + ε, gives 1.081e5 Pa.
    let p = IsblParams::improved_2dof();
    let m = IsblModel::new(p).unwrap();
    let h = 12.0 * p.sigma;
    let fs = m.at(h).unwrap().adhesion;
    assert!((fs / 1.083e5 - 1.0).abs() < 5e-4, "{fs}");
    let dd = h - p.lubricant_thickness + p.lj_spacing;
    let tail = 2.0 * PI * p.summit_radius * p.summit_density * 0.06 * 4.0 / 3.0
        * (p.lj_spacing / dd).powi(2)
        * (1.0 + 3.0 * p.sigma.powi(2) / dd.powi(2));
    assert!((tail / 1.081e5 - 1.0).abs() < 5e-4, "{tail}");
}

#[test]
fn invalid_inputs_are_errors_not_panics() {
    let good = IsblParams::initial_2dof();
    let bad = [
        IsblParams { sigma: 0.0, ..good },
        IsblParams {
            sigma: f64::NAN,
            ..good
        },
        IsblParams {
            summit_radius: -1.0,
            ..good
        },
        IsblParams {
            summit_density: f64::INFINITY,
            ..good
        },
        IsblParams {
            disk_poisson: 0.5,
            ..good
        },
        IsblParams {
            yielding_poisson: -1.0,
            ..good
        },
        IsblParams {
            hardness: 0.0,
            ..good
        },
        IsblParams {
            lj_spacing: 0.0,
            ..good
        },
        IsblParams {
            lubricant_thickness: -1e-9,
            ..good
        },
        IsblParams {
            surface_energy: SurfaceEnergy::Constant { delta_gamma: -0.1 },
            ..good
        },
        IsblParams {
            surface_energy: SurfaceEnergy::Variable {
                c1: 0.1,
                c2: f64::NAN,
                c3: 0.0,
            },
            ..good
        },
        // β = 0.0145 < 0.0193: McCool's σ_s relation is invalid.
        IsblParams {
            summits: SummitDistribution::McCool,
            summit_density: 38.8e12,
            ..good
        },
    ];
    for p in bad {
        assert!(
            matches!(IsblModel::new(p), Err(ContactError::Parameter { .. })),
            "{p:?}"
        );
        assert!(isbl_at(&p, 0.0).is_err());
    }
    let m = IsblModel::new(good).unwrap();
    assert!(m.at(f64::NAN).is_err());
    assert!(m.at(f64::INFINITY).is_err());
    // Extreme but finite separations (up to the accepted ±1e4σ): no NaN, F_s still falls,
    // contact curves vanish far away; beyond ±1e4σ a parameter error.
    for h_star in [-1e4, -50.0, -5.0, 40.0, 1e3, 1e4] {
        let h = h_star * good.sigma;
        let pt = m.at(h).unwrap_or_else(|e| panic!("h* = {h_star}: {e}"));
        assert!(
            pt.contact_pressure.is_finite() && pt.adhesion.is_finite(),
            "{pt:?}"
        );
        assert!(pt.adhesion_gradient < 0.0, "{pt:?}");
        assert_eq!(pt.deep_interference, h_star < -4.0);
    }
    assert_eq!(m.at(40.0 * good.sigma).unwrap().contact_pressure, 0.0);
    for h in [1.0, -1.0, 1.01e4 * good.sigma] {
        assert!(matches!(m.at(h), Err(ContactError::Parameter { .. })));
    }
}

#[test]
fn mccool_offset_and_summit_sigma_match_spec_section_2() {
    // App. A.1: y_s = 0.99σ for β = 0.046 (initial set), y_s = 1.72σ and σ_s = 0.69σ for
    // β = 0.027 (improved); docs/contact.md: McCool offset gives 81 μN on 62 μm² at h* = 3.
    let initial = IsblModel::new(IsblParams {
        summits: SummitDistribution::McCool,
        ..IsblParams::initial_2dof()
    })
    .unwrap();
    let s = 0.87e-9;
    assert!((initial.derived().summit_offset / s - 0.99).abs() < 0.005);
    let p3 = initial.at(3.0 * s).unwrap().contact_pressure * 62e-12;
    assert!((p3 / 81e-6 - 1.0).abs() < 0.007, "{p3}");
    let improved = IsblModel::new(IsblParams {
        summits: SummitDistribution::McCool,
        ..IsblParams::improved_2dof()
    })
    .unwrap();
    assert!((improved.derived().summit_offset / 0.5e-9 - 1.72).abs() < 0.005);
    assert!((improved.derived().summit_sigma / 0.5e-9 - 0.69).abs() < 0.005);
}

// ---------------------------------------------------------------------------------------
// Validation table of docs/contact.md (numbers quoted there come from the reference implementation;
// tolerances are half a unit in the last quoted digit unless stated)
// ---------------------------------------------------------------------------------------

/// `h` where the decreasing function `f` crosses `target`, by bisection on `[lo, hi]`.
fn solve_decreasing(f: impl Fn(f64) -> f64, target: f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

fn assert_digits(what: &str, got: f64, want: f64, half_unit: f64) {
    assert!(
        (got - want).abs() <= half_unit,
        "{what}: got {got}, spec {want} ± {half_unit}"
    );
}

#[test]
fn section9_row3_plasticity_index() {
    // ψ = (E*/H)√(σ/R) = 0.5167 with ν = 0.25, 0.514 with 0.24, 0.532 with 0.30; ψ_KE = 0.591.
    let psi = |nu: f64| {
        let p = IsblParams {
            slider_poisson: nu,
            disk_poisson: nu,
            yielding_poisson: nu,
            ..IsblParams::initial_2dof()
        };
        *IsblModel::new(p).unwrap().derived()
    };
    assert_digits("psi(0.25)", psi(0.25).plasticity_index, 0.5167, 5e-5);
    assert_digits("psi(0.24)", psi(0.24).plasticity_index, 0.514, 5e-4);
    assert_digits("psi(0.30)", psi(0.30).plasticity_index, 0.532, 5e-4);
    assert_digits("psi_KE", psi(0.25).plasticity_index_ke, 0.591, 5e-4);
}

#[test]
fn section9_row1_contact_force_at_three_sigma() {
    let initial = IsblModel::new(IsblParams::initial_2dof()).unwrap();
    let s = 0.87e-9;
    let p = |h_star: f64| initial.at(h_star * s).unwrap().contact_pressure;
    // #1a: 1.097e5 Pa; 6.80 μN on 62 μm², 7.46 on 68, 7.30 on 66.6 (the seed's 7.30 μN).
    assert_digits("P(3)", p(3.0), 1.097e5, 0.0005e5);
    assert_digits("P(3)·62 μm² [μN]", p(3.0) * 62e-12 * 1e6, 6.80, 0.005);
    assert_digits("P(3)·68 μm² [μN]", p(3.0) * 68e-12 * 1e6, 7.46, 0.005);
    assert_digits("P(3)·66.6 μm² [μN]", p(3.0) * 66.6e-12 * 1e6, 7.30, 0.005);
    let improved = IsblModel::new(IsblParams::improved_2dof()).unwrap();
    let p_improved = improved.at(1.5e-9).unwrap().contact_pressure;
    assert_digits(
        "improved P(3)·62 μm² [μN]",
        p_improved * 62e-12 * 1e6,
        2.96,
        0.005,
    );
    // #1b, known deviation (spec: "not reproduced; likely a misread axis in the seed"): the
    // seed says 7.30 μN is ~3 % of P(2.5); the model gives P(3)/P(2.5) = 0.180,
    // P(3)/P(2) = 0.040, and 3 % at h* = 1.90. Pinned so a change of model is noticed.
    assert_digits("P(3)/P(2.5)", p(3.0) / p(2.5), 0.180, 5e-4);
    assert_digits("P(3)/P(2)", p(3.0) / p(2.0), 0.040, 5e-4);
    let h3 = solve_decreasing(p, p(3.0) / 0.03, 0.0, 3.0);
    assert_digits("h* where P(3)/P = 3 %", h3, 1.90, 0.005);
}

#[test]
fn section9_row1c_adhesion_negligible_beyond_six_sigma() {
    // F_s(6)/F_s(0) = 0.8 % (σ = 0.87 nm), 4.8 % (σ = 0.5 nm), ε = 0.3 nm.
    for (p, want) in [
        (IsblParams::initial_2dof(), 0.008),
        (IsblParams::improved_2dof(), 0.048),
    ] {
        let m = IsblModel::new(p).unwrap();
        let ratio = m.at(6.0 * p.sigma).unwrap().adhesion / m.at(0.0).unwrap().adhesion;
        assert_digits("F_s(6)/F_s(0)", ratio, want, 5e-4);
    }
}

#[test]
fn section9_row2_improved_interface_at_12nm() {
    // Improved set, A_n = 55 μm² (§9 #5). Known deviations #2a/#2b (static reading of the
    // seed's dynamic F_c; spec: "−14 % on μ", "not reproducible as a static relation") are
    // pinned at the spec's model values; #2c is reproduced.
    let area = 55e-12;
    let p = IsblParams::improved_2dof();
    let m = IsblModel::new(p).unwrap();
    let seed_law = IsblModel::new(IsblParams {
        friction_law: FrictionLaw::SeedPowerElastic,
        ..p
    })
    .unwrap();
    let s = p.sigma;
    let force = |h: f64| m.at(h).unwrap().contact_pressure * area;
    // #2a: P = F_c = 1.63 mN at h* = 0.60; Q = 2.08 mN, μ = 1.28; seed law 1.64 mN, 1.01.
    let h = solve_decreasing(force, 1.63e-3, -2.0 * s, 3.0 * s);
    let pt = m.at(h).unwrap();
    assert_digits("h* at P = F_c", h / s, 0.60, 0.005);
    assert_digits("Q [mN]", pt.friction_stress * area * 1e3, 2.08, 0.005);
    assert_digits("mu", pt.friction_stress / pt.contact_pressure, 1.28, 0.005);
    let seed_pt = seed_law.at(h).unwrap();
    assert_digits(
        "Q seed law [mN]",
        seed_pt.friction_stress * area * 1e3,
        1.64,
        0.005,
    );
    assert_digits(
        "mu seed law",
        seed_pt.friction_stress / seed_pt.contact_pressure,
        1.01,
        0.005,
    );
    // #2b: A_r = 0.78 μm² there; 0.36 μm² occurs at h* = 1.03 where P = 0.70 mN.
    assert_digits(
        "A_r [μm²]",
        pt.real_area_fraction * area * 1e12,
        0.78,
        0.005,
    );
    let h036 = solve_decreasing(
        |h| m.at(h).unwrap().real_area_fraction * area,
        0.36e-12,
        -2.0 * s,
        3.0 * s,
    );
    assert_digits("h* at A_r = 0.36 μm²", h036 / s, 1.03, 0.005);
    assert_digits("P there [mN]", force(h036) * 1e3, 0.70, 0.005);
    // At the reported mean clearance h = 3σ − 0.34 nm (h* = 2.32): μ = 1.65,
    // A_r = 0.016 μm², P = 26 μN.
    let mean = m.at(3.0 * s - 0.34e-9).unwrap();
    assert_digits(
        "mu at h* = 2.32",
        mean.friction_stress / mean.contact_pressure,
        1.65,
        0.005,
    );
    assert_digits(
        "A_r at h* = 2.32 [μm²]",
        mean.real_area_fraction * area * 1e12,
        0.016,
        5e-4,
    );
    assert_digits(
        "P at h* = 2.32 [μN]",
        mean.contact_pressure * area * 1e6,
        26.0,
        0.5,
    );
    // #2c: adhesion 0.961 mN at h_c = 1.16 nm (non-contact 0.13, lubricant 0.82, solid
    // 0.012 mN) with Δγ = 0.06 N/m; Δγ = 0.0612 N/m gives the seed's 0.98 mN (F_s ∝ Δγ).
    let a = m.at(1.16e-9).unwrap();
    assert_digits("F_s [mN]", a.adhesion * area * 1e3, 0.961, 5e-4);
    assert_digits(
        "F_nc [mN]",
        a.adhesion_non_contacting * area * 1e3,
        0.13,
        0.005,
    );
    assert_digits("F_lc [mN]", a.adhesion_lubricant * area * 1e3, 0.82, 0.005);
    assert_digits("F_sc [mN]", a.adhesion_solid * area * 1e3, 0.012, 5e-4);
    assert_digits(
        "F_s with 0.0612 N/m [mN]",
        a.adhesion * area * 1e3 * 0.0612 / 0.06,
        0.98,
        0.005,
    );
}

#[test]
fn section9_row2d_initial_interface_at_11nm() {
    // Initial set, A_n = 62 μm², P = 1 mN: h* = 1.31, A_r = 0.405 μm², Q = 1.09 mN,
    // μ = 1.09 (junction shear) / 0.85 (seed law); A_r = 2.72 μm² at h* = 0.21, P = 8.1 mN.
    // Known deviation (A_r ×6.7 below the seed's 2.7 μm²: dynamic vs static, spec #2d).
    let area = 62e-12;
    let p = IsblParams::initial_2dof();
    let s = p.sigma;
    let m = IsblModel::new(p).unwrap();
    let h = solve_decreasing(
        |h| m.at(h).unwrap().contact_pressure * area,
        1e-3,
        -2.0 * s,
        3.0 * s,
    );
    let pt = m.at(h).unwrap();
    assert_digits("h*", h / s, 1.31, 0.005);
    assert_digits(
        "A_r [μm²]",
        pt.real_area_fraction * area * 1e12,
        0.405,
        5e-4,
    );
    assert_digits("Q [mN]", pt.friction_stress * area * 1e3, 1.09, 0.005);
    assert_digits("mu", pt.friction_stress / pt.contact_pressure, 1.09, 0.005);
    let seed = IsblModel::new(IsblParams {
        friction_law: FrictionLaw::SeedPowerElastic,
        ..p
    })
    .unwrap()
    .at(h)
    .unwrap();
    assert_digits(
        "mu seed law",
        seed.friction_stress / seed.contact_pressure,
        0.85,
        0.005,
    );
    let h272 = solve_decreasing(
        |h| m.at(h).unwrap().real_area_fraction * area,
        2.72e-12,
        -2.0 * s,
        3.0 * s,
    );
    assert_digits("h* at A_r = 2.72 μm²", h272 / s, 0.21, 0.005);
    let p272 = m.at(h272).unwrap().contact_pressure * area;
    assert_digits("P there [mN]", p272 * 1e3, 8.1, 0.05);
}

#[test]
fn adhesion_far_apart_keeps_the_whole_gaussian() {
    // At h* = 200 every summit is far below the flat: F_s → 2πRηΔγ(4/3)(ε/D)²[1 + 3σ²/D²]
    // (docs/contact.md tail formula, D = h − t + ε ≫ σ; the next term is O(σ⁴/D⁴) ≈ 1e-9).
    let p = IsblParams::improved_2dof();
    let m = IsblModel::new(p).unwrap();
    let h = 200.0 * p.sigma;
    let dd = h - p.lubricant_thickness + p.lj_spacing;
    let tail = 2.0 * PI * p.summit_radius * p.summit_density * 0.06 * 4.0 / 3.0
        * (p.lj_spacing / dd).powi(2)
        * (1.0 + 3.0 * p.sigma.powi(2) / dd.powi(2));
    let fs = m.at(h).unwrap().adhesion;
    assert!((fs / tail - 1.0).abs() < 1e-6, "{fs} vs {tail}");
}

#[test]
fn every_configuration_evaluates_across_the_accepted_range() {
    // No error and no NaN from −1e4σ to 1e4σ for all parameter sets (Tables 2.2, 2.4, 3.2) and the
    // non-default switches.
    let mut configs = vec![
        IsblParams::initial_2dof(),
        IsblParams::improved_2dof(),
        IsblParams::mtl_table_3_2(),
    ];
    configs.push(IsblParams {
        summits: SummitDistribution::McCool,
        friction_law: FrictionLaw::SeedPowerElastic,
        surface_energy: SurfaceEnergy::seed_variable(),
        ..IsblParams::initial_2dof()
    });
    // A plastic interface (ψ_KE > 1, all KE regimes populated) and a zero lubricant.
    configs.push(IsblParams {
        hardness: 2e9,
        lubricant_thickness: 0.0,
        ..IsblParams::initial_2dof()
    });
    let mut h_stars: Vec<f64> = (0..=300).map(|i| -100.0 + 0.667 * i as f64).collect();
    h_stars.extend([-1e4, -3e3, -1e3, 1e3, 3e3, 1e4]);
    for p in configs {
        let m = IsblModel::new(p).unwrap();
        for &h_star in &h_stars {
            let pt = m
                .at(h_star * p.sigma)
                .unwrap_or_else(|e| panic!("{p:?} at h* = {h_star}: {e}"));
            let values = [
                pt.contact_pressure,
                pt.contact_stiffness,
                pt.real_area_fraction,
                pt.friction_stress,
                pt.friction_stiffness,
                pt.adhesion,
                pt.adhesion_gradient,
                pt.contacts_per_area,
            ];
            assert!(values.iter().all(|v| v.is_finite()), "{pt:?}");
        }
    }
    let plastic = IsblModel::new(IsblParams {
        hardness: 2e9,
        ..IsblParams::initial_2dof()
    })
    .unwrap();
    assert!(plastic.derived().elastic_plastic_adhesion_assumed);
}

// ---------------------------------------------------------------------------------------
// The `ke_static` friction law (docs/contact.md, "Friction")
// ---------------------------------------------------------------------------------------

const KE_STATIC_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/isbl/ke_static/");

/// Data rows of a CSV beside `make_ke_static.py`: the first column as text, the rest as numbers.
fn read_ke_static(name: &str) -> Vec<(String, Vec<f64>)> {
    let path = format!("{KE_STATIC_DIR}{name}");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let mut f = l.split(',');
            let first = f.next().unwrap().to_string();
            (first, f.map(|x| x.trim().parse().unwrap()).collect())
        })
        .collect()
}

fn ke_static(params: IsblParams) -> IsblModel {
    IsblModel::new(IsblParams {
        friction_law: FrictionLaw::KeStatic,
        ..params
    })
    .unwrap()
}

#[test]
fn ke_static_matches_the_independent_scipy_reference() {
    // tests/data/isbl/ke_static/ke_static.csv: scipy quadrature of the law (its own f_el,
    // KE loads and Gaussian), and k_fr as a five-point difference of that Q, against the
    // model's Q and analytic k_fr (density derivative under the integral). Both to 1e-6.
    let mut worst = [0.0f64; 2];
    let rows = read_ke_static("ke_static.csv");
    assert_eq!(rows.len(), 24);
    for (set, v) in rows {
        let params = match set.as_str() {
            "initial_2dof" => IsblParams::initial_2dof(),
            "improved_2dof" => IsblParams::improved_2dof(),
            "mtl_table_3_2" => IsblParams::mtl_table_3_2(),
            other => panic!("unknown set {other}"),
        };
        let (h, q, kfr) = (v[1], v[2], v[3]);
        let p = ke_static(params).at(h).unwrap();
        for (k, (got, want)) in [(p.friction_stress, q), (p.friction_stiffness, kfr)]
            .into_iter()
            .enumerate()
        {
            let rel = (got / want - 1.0).abs();
            assert!(rel < 1e-6, "{set} h = {h:e}: {got:e} vs {want:e}");
            worst[k] = worst[k].max(rel);
        }
    }
    eprintln!(
        "ke_static: worst relative error Q {:.1e}, k_fr {:.1e}",
        worst[0], worst[1]
    );
}

#[test]
fn ke_static_single_sphere_matches_the_reference_and_ch3_1_without_adhesion() {
    // The Ch. 3.1 DLC sphere (R = 102 µm), Δγ = 0.06 N/m and Δγ = 0: load, adhesion force
    // and Q_max from ke_static_sphere.csv (independent scipy f_el).
    for (omega, v) in read_ke_static("ke_static_sphere.csv") {
        let omega: f64 = omega.parse().unwrap();
        let (dgamma, load, q) = (v[0], v[1], v[3]);
        let m = IsblModel::new(IsblParams {
            friction_law: FrictionLaw::KeStatic,
            surface_energy: SurfaceEnergy::Constant {
                delta_gamma: dgamma,
            },
            ..*dlc_sphere_ch3_1().params()
        })
        .unwrap();
        let a = m.asperity_at(omega).unwrap();
        assert!((a.load / load - 1.0).abs() < 1e-12, "{} vs {load}", a.load);
        assert!((a.friction / q - 1.0).abs() < 1e-9, "{} vs {q}", a.friction);
    }
    // Without adhesion the law is the Ch. 3.1 power law through 120 and 1120 µN: the
    // dissertation's numbers to 0.1 % (its back-solve, not a reproduction).
    let m = IsblModel::new(IsblParams {
        friction_law: FrictionLaw::KeStatic,
        surface_energy: SurfaceEnergy::Constant { delta_gamma: 0.0 },
        ..*dlc_sphere_ch3_1().params()
    })
    .unwrap();
    for (omega, want) in [(0.1e-9, 120e-6), (1e-9, 1120e-6)] {
        let q = m.asperity_at(omega).unwrap().friction;
        assert!((q / want - 1.0).abs() < 1e-3, "ω = {omega:e}: {q:e}");
    }
}

#[test]
fn ke_static_without_adhesion_is_the_seed_power_law_on_elastic_summits() {
    // 0.4155·(ω*^1.5)^(0.970/1.5) = 0.4155·ω*^0.970 for ω* ≤ 1; beyond, ke_static keeps
    // the elastic-plastic summits (KE 2002 loads) up to ω* = 110 and drops the fully
    // plastic ones, where the seed power law is zero from ω* = 1.
    let base = IsblParams {
        surface_energy: SurfaceEnergy::Constant { delta_gamma: 0.0 },
        ..IsblParams::improved_2dof()
    };
    let ke = ke_static(base);
    let seed = IsblModel::new(IsblParams {
        friction_law: FrictionLaw::SeedPowerElastic,
        ..base
    })
    .unwrap();
    let wc = ke.derived().critical_interference;
    let k = ke.derived().k_factor;
    let lc = ke.derived().critical_load;
    for ws in [1e-6, 1e-3, 0.1, 0.5, 1.0] {
        let a = ke.asperity_at(ws * wc).unwrap().friction;
        let b = seed.asperity_at(ws * wc).unwrap().friction;
        assert!((a / b - 1.0).abs() < 1e-12, "ω* = {ws}: {a} vs {b}");
    }
    for ws in [1.5, 6.0, 50.0, 110.0] {
        let a = ke.asperity_at(ws * wc).unwrap().friction / lc;
        let want = 0.4155 * asperity::ke_load_ratio(ws, k).powf(0.970 / 1.5);
        assert!((a / want - 1.0).abs() < 1e-12, "ω* = {ws}: {a} vs {want}");
        assert_eq!(seed.asperity_at(ws * wc).unwrap().friction, 0.0);
    }
    assert_eq!(ke.asperity_at(110.5 * wc).unwrap().friction, 0.0);
    assert_eq!(ke.asperity_at(0.0).unwrap().friction, 0.0);
    assert_eq!(ke.asperity_at(-1e-9).unwrap().friction, 0.0);
}

#[test]
fn ke_static_leaves_the_other_curves_and_laws_as_they_were() {
    // Only Q and k_fr change with the law; P, k_c, A_r, F_s, n_c agree to the quadrature's
    // tolerance (the adaptive partition differs), and the default law's Q is τ_s·A_r.
    for params in [IsblParams::initial_2dof(), IsblParams::improved_2dof()] {
        let js = IsblModel::new(params).unwrap();
        let ke = ke_static(params);
        for x in [-1.0, 0.0, 1.0, 3.0] {
            let (a, b) = (
                js.at(x * params.sigma).unwrap(),
                ke.at(x * params.sigma).unwrap(),
            );
            for (u, v) in [
                (a.contact_pressure, b.contact_pressure),
                (a.contact_stiffness, b.contact_stiffness),
                (a.real_area_fraction, b.real_area_fraction),
                (a.adhesion, b.adhesion),
                (a.contacts_per_area, b.contacts_per_area),
            ] {
                assert!((u / v - 1.0).abs() < 1e-9, "h* = {x}: {u} vs {v}");
            }
            let tau = js.derived().junction_shear_strength;
            assert!((a.friction_stress / (tau * a.real_area_fraction) - 1.0).abs() < 1e-15);
            assert!(b.friction_stress > 0.0 && b.friction_stiffness > 0.0);
        }
    }
}
