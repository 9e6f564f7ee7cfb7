//! Lookup tests: table vs direct evaluation, behaviour at every regime boundary and outside
//! the table, and seeded property tests of the monotonicity physics requires.

use super::*;
use crate::contact::isbl::{IsblParams, SurfaceEnergy};
use crate::contact::mtl::rough::{LubricantCase, RoughFilm, RoughMtl, SolidResponse};
use crate::contact::mtl::FwmExperiment;

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

fn isbl(params: IsblParams) -> IsblLookup {
    IsblLookup::build_standard(IsblModel::new(params).unwrap()).unwrap()
}

/// Table 3.2 interface with the variable surface energy, `A_n` = 2500 µm².
const NOMINAL_AREA: f64 = 2500e-12;

/// Small deterministic generator for the property tests (xorshift64*).
struct Rng(u64);
impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let u = (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }
}

#[test]
fn isbl_lookup_matches_direct_evaluation_at_random_separations() {
    // Acceptance: ≤ 1e-4 relative (spec target 1e-6) wherever the value is above 1e-12 of
    // its maximum, for both surface-energy models.
    // The `ke_static` friction law tabulates a different Q and k_fr (docs/contact.md).
    let ke_static = |p: IsblParams| IsblParams {
        friction_law: crate::contact::isbl::FrictionLaw::KeStatic,
        ..p
    };
    for params in [
        IsblParams::improved_2dof(),
        IsblParams::mtl_table_3_2(),
        ke_static(IsblParams::improved_2dof()),
        ke_static(IsblParams::mtl_table_3_2()),
    ] {
        let l = isbl(params);
        for e in l.verified_error() {
            assert!(e.max_rel < 1e-6, "{e:?}");
        }
        let mut rng = Rng(0x5eed);
        let sigma = params.sigma;
        for _ in 0..400 {
            let h = rng.uniform(-3.9, 14.0) * sigma;
            let got = l.at(h).unwrap();
            let want = l.model().at(h).unwrap();
            assert_eq!(got.range, LookupRange::Table);
            for (g, w) in [
                (got.pressure, want.contact_pressure),
                (got.stiffness, want.contact_stiffness),
                (got.real_area_fraction, want.real_area_fraction),
                (got.friction, want.friction_stress),
                (got.friction_stiffness, want.friction_stiffness),
                (got.adhesion, want.adhesion),
                (got.adhesion_gradient, want.adhesion_gradient),
            ] {
                if w.abs() > 1e-9 * want.contact_pressure.max(want.adhesion) {
                    assert!(rel(g, w) < 1e-5, "h* = {}: {g} vs {w}", h / sigma);
                }
            }
        }
    }
}

#[test]
fn isbl_lookup_is_continuous_at_regime_boundaries() {
    // 3σ (solid onset), 3σ + t (lubricant surface), ε (equilibrium spacing: where the
    // variable surface energy saturates), 3σ + t − ε, h = 0.
    let params = IsblParams::mtl_table_3_2();
    let l = isbl(params);
    let (s, t, eps) = (params.sigma, params.lubricant_thickness, params.lj_spacing);
    for h in [3.0 * s, 3.0 * s + t, eps, 3.0 * s + t - eps, 0.0] {
        let a = l.at(h - 1e-21).unwrap();
        let b = l.at(h + 1e-21).unwrap();
        for (x, y) in [
            (a.pressure, b.pressure),
            (a.stiffness, b.stiffness),
            (a.friction, b.friction),
            (a.adhesion, b.adhesion),
        ] {
            assert!(x.is_finite() && y.is_finite());
            assert!(rel(x, y) < 1e-6, "at h* = {}: {x} vs {y}", h / s);
        }
    }
}

#[test]
fn outside_the_table() {
    let params = IsblParams::improved_2dof();
    let l = isbl(params);
    let sigma = params.sigma;
    let (lo, hi) = l.table().range();
    // Above: contact terms vanish, adhesion continues with the far-tail formula, continuous
    // at the last node and within 0.5 % of the full model three σ further out.
    let at_edge = l.at(hi * sigma * (1.0 - 1e-12)).unwrap();
    let just_above = l.at(hi * sigma * (1.0 + 1e-12)).unwrap();
    assert_eq!(just_above.range, LookupRange::AboveTable);
    assert_eq!(just_above.pressure, 0.0);
    assert!(rel(just_above.adhesion, at_edge.adhesion) < 1e-9);
    assert!(rel(just_above.adhesion_gradient, at_edge.adhesion_gradient) < 1e-2);
    let far = (hi + 3.0) * sigma;
    let direct = l.model().at(far).unwrap();
    let tail = l.at(far).unwrap();
    assert!(
        rel(tail.adhesion, direct.adhesion) < 5e-3,
        "{} vs {}",
        tail.adhesion,
        direct.adhesion
    );
    assert!(tail.adhesion_gradient < 0.0);
    // Below: direct evaluation, flagged.
    let deep = l.at((lo - 0.5) * sigma).unwrap();
    assert_eq!(deep.range, LookupRange::BelowTable);
    let direct = l.model().at((lo - 0.5) * sigma).unwrap();
    assert_eq!(deep.pressure, direct.contact_pressure);
    assert!(l.at(f64::NAN).is_err());
}

#[test]
fn isbl_monotonicity_property_over_random_interfaces() {
    // P, A_r, Q, F_s fall with separation and k_c > 0, for any physical interface.
    let mut rng = Rng(42);
    for case in 0..12 {
        let params = IsblParams {
            sigma: rng.uniform(0.3, 1.5) * 1e-9,
            summit_radius: rng.uniform(0.2, 5.0) * 1e-6,
            summit_density: rng.uniform(5.0, 300.0) * 1e12,
            hardness: rng.uniform(8.0, 25.0) * 1e9,
            lubricant_thickness: rng.uniform(0.8, 2.5) * 1e-9,
            surface_energy: if case % 2 == 0 {
                SurfaceEnergy::seed_variable()
            } else {
                SurfaceEnergy::Constant {
                    delta_gamma: rng.uniform(0.02, 0.08),
                }
            },
            ..IsblParams::improved_2dof()
        };
        let l = isbl(params);
        let mut prev = l.at(-3.5 * params.sigma).unwrap();
        for k in 1..=600 {
            let h = (-3.5 + k as f64 * 0.025) * params.sigma;
            let f = l.at(h).unwrap();
            assert!(f.stiffness >= 0.0 && f.friction_stiffness >= 0.0);
            assert!(f.adhesion_gradient <= 0.0, "case {case} k {k}");
            assert!(f.pressure <= prev.pressure, "case {case} P at k {k}");
            assert!(f.real_area_fraction <= prev.real_area_fraction);
            assert!(f.friction <= prev.friction);
            assert!(f.adhesion <= prev.adhesion, "case {case} F_s at k {k}");
            prev = f;
        }
    }
}

/// The ISBL model itself (direct quadrature) as the MTL solid, scaled to `A_n`.
fn direct_solid(model: IsblModel) -> impl Fn(f64) -> SolidResponse + Sync {
    move |h| {
        let p = model.at(h).unwrap();
        SolidResponse {
            normal: p.contact_pressure * NOMINAL_AREA,
            friction: p.friction_stress * NOMINAL_AREA,
            normal_stiffness: p.contact_stiffness * NOMINAL_AREA,
            friction_stiffness: p.friction_stiffness * NOMINAL_AREA,
        }
    }
}

#[test]
fn tabulated_mtl_interface_matches_direct_and_is_continuous() {
    // The fast path (closed-form MTL law on the tabulated solid) against the same law on the
    // direct ISBL quadrature, for every lubricant case, across 3σ, 3σ + 2κ, 3σ + t and ε.
    let l = Arc::new(isbl(IsblParams::mtl_table_3_2()));
    let mut worst: f64 = 0.0;
    for case in LubricantCase::ALL {
        let mtl = case.model().unwrap();
        let fast = mtl.with_solid(l.as_solid(NOMINAL_AREA));
        let slow = mtl.with_solid(direct_solid(*l.model()));
        let (onset, end, surface) = (
            mtl.solid_onset(),
            mtl.transition_end(),
            mtl.lubricant_surface(),
        );
        let eps = l.model().params().lj_spacing;
        let mut rng = Rng(11);
        let mut hs: Vec<f64> = (0..300).map(|_| rng.uniform(-1e-9, 6e-9)).collect();
        hs.extend([onset, end, surface, eps, surface - eps]);
        for h in hs {
            let (a, b) = (fast.evaluate(h), slow.evaluate(h));
            for (x, y, what) in [
                (a.total.normal, b.total.normal, "P"),
                (a.total.friction, b.total.friction, "Q"),
                (a.lubricant.normal, b.lubricant.normal, "P_lub"),
                (a.lubricant.friction, b.lubricant.friction, "Q_lub"),
                (a.total.normal_stiffness, b.total.normal_stiffness, "k"),
            ] {
                assert!(x.is_finite(), "{what} at {h}");
                if y.abs() > 1e-12 * mtl.max_normal_stiffness() * 1e-9 {
                    let r = rel(x, y);
                    worst = worst.max(r);
                    assert!(r < 1e-4, "{case:?} {what} at h = {h}: {x} vs {y}");
                }
            }
        }
        // Forces are continuous at every boundary; stiffness jumps only at 3σ + 2κ and 3σ + t.
        // A jump would show as a difference beyond what the stiffness explains over 2δ.
        let delta = 1e-21;
        for h in [onset, end, surface, eps] {
            let (a, b) = (fast.evaluate(h - delta), fast.evaluate(h + delta));
            let (ta, tb) = (a.total, b.total);
            let slope = ta.normal_stiffness.abs() + tb.normal_stiffness.abs();
            assert!(
                (ta.normal - tb.normal).abs() <= 2.0 * delta * slope + 1e-12 * ta.normal,
                "{case:?} P jumps at {h}: {} vs {}",
                ta.normal,
                tb.normal
            );
            let slope = ta.friction_stiffness.abs() + tb.friction_stiffness.abs();
            assert!(
                (ta.friction - tb.friction).abs() <= 2.0 * delta * slope + 1e-12 * ta.friction,
                "{case:?} Q jumps at {h}"
            );
        }
        let (a, b) = (
            fast.evaluate(onset * (1.0 - 1e-12)),
            fast.evaluate(onset * (1.0 + 1e-12)),
        );
        assert!(rel(a.total.normal_stiffness, b.total.normal_stiffness) < 1e-6);
    }
    eprintln!("tabulated vs direct MTL interface: worst relative difference {worst:.2e}");
}

#[test]
fn mtl_total_force_monotone_for_random_lubricants() {
    // Property: with the ISBL solid, the total normal force never increases with separation
    // and the total stiffness is never negative, for random films and lubricants.
    let l = Arc::new(isbl(IsblParams::mtl_table_3_2()));
    let mut rng = Rng(2024);
    for case in 0..40 {
        let kappa = rng.uniform(0.15, 0.6) * 1e-9;
        let t = rng.uniform(2.2, 6.0) * kappa;
        let film = RoughFilm::new(0.82e-9, kappa, t, rng.uniform(1.0, 40.0)).unwrap();
        let fwm = FwmExperiment::fukuzawa_z03()
            .with_limiting_viscosity(rng.uniform(0.1, 0.6))
            .unwrap();
        let iface = RoughMtl::from_experiment(film, &fwm)
            .unwrap()
            .with_solid(l.as_solid(NOMINAL_AREA));
        let mut prev = iface.evaluate(0.0).total;
        for k in 1..=800 {
            let h = k as f64 * 0.01e-9;
            let f = iface.evaluate(h).total;
            assert!(f.normal_stiffness >= 0.0 && f.friction_stiffness >= 0.0);
            assert!(f.normal <= prev.normal, "case {case} at h = {h}");
            assert!(f.friction <= prev.friction, "case {case} at h = {h}");
            prev = f;
        }
    }
}

/// `at_lazy` answers each channel with exactly the value of the matching `at` field, inside
/// the table, above it (far tail) and below it (direct evaluation).
#[test]
fn lazy_lookup_is_bit_identical_to_the_full_lookup() {
    for params in [IsblParams::improved_2dof(), IsblParams::initial_2dof()] {
        let lookup = isbl(params);
        let sigma = lookup.model().params().sigma;
        let (lo, hi) = lookup.table().range();
        let mut x = lo - 1.0;
        while x < hi + 3.0 {
            for h in [x * sigma, lo * sigma, hi * sigma] {
                let full = lookup.at(h).unwrap();
                let lazy = lookup.at_lazy(h).unwrap();
                for (a, b) in [
                    (lazy.pressure(), full.pressure),
                    (lazy.stiffness(), full.stiffness),
                    (lazy.real_area_fraction(), full.real_area_fraction),
                    (lazy.friction(), full.friction),
                    (lazy.adhesion(), full.adhesion),
                ] {
                    assert_eq!(a.to_bits(), b.to_bits(), "h* = {x}");
                }
            }
            x += 0.0137;
        }
        assert!(lookup.at_lazy(f64::NAN).is_err());
    }
}

#[test]
fn the_unverified_table_is_the_verified_one_bit_for_bit() {
    for params in [IsblParams::improved_2dof(), IsblParams::mtl_table_3_2()] {
        let verified = isbl(params);
        let plain = IsblLookup::build_standard_unverified(IsblModel::new(params).unwrap()).unwrap();
        assert!(!verified.verified_error().is_empty());
        assert!(plain.verified_error().is_empty());
        let sigma = params.sigma;
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        // Below, inside and above the table (h* from −6 to 25).
        for _ in 0..2000 {
            let h = rng.uniform(-6.0, 25.0) * sigma;
            let (a, b) = (verified.at(h).unwrap(), plain.at(h).unwrap());
            for (x, y) in [
                (a.pressure, b.pressure),
                (a.stiffness, b.stiffness),
                (a.real_area_fraction, b.real_area_fraction),
                (a.friction, b.friction),
                (a.adhesion, b.adhesion),
                (a.adhesion_gradient, b.adhesion_gradient),
            ] {
                assert_eq!(x.to_bits(), y.to_bits(), "h = {h:e}");
            }
        }
    }
}

/// `contact_law = "bem"`: the contact channels follow the measured law (inside the table and
/// below it), friction is τ·A_r on its area, adhesion stays ISBL's.
#[test]
fn a_contact_law_replaces_the_contact_channels_only() {
    use crate::contact::bem::law::ContactCurve;
    let model = IsblModel::new(IsblParams::improved_2dof()).unwrap();
    let points: Vec<(f64, f64, f64)> = (1..=20)
        .map(|k| {
            let h = 0.1e-9 * k as f64;
            (h, 2e9 * (-h / 0.3e-9).exp(), 0.3 * (-h / 0.5e-9).exp())
        })
        .collect();
    let law = std::sync::Arc::new(ContactCurve::new(&points).unwrap());
    let isbl = IsblLookup::build_standard(model).unwrap();
    let bem = IsblLookup::build_with_contact_law(model, law.clone()).unwrap();
    let tau = model.derived().junction_shear_strength;
    for h in [0.15e-9, 0.72e-9, 1.33e-9, -0.5e-9, -3e-9] {
        let (a, b, q) = (isbl.at(h).unwrap(), bem.at(h).unwrap(), law.at(h));
        assert!(
            (b.pressure / q.pressure - 1.0).abs() < 1e-6,
            "{h}: {b:?} {q:?}"
        );
        assert!((b.stiffness / -q.pressure_slope - 1.0).abs() < 1e-4, "{h}");
        assert!(
            (b.real_area_fraction / q.real_area_fraction - 1.0).abs() < 1e-6,
            "{h}"
        );
        assert!(
            (b.friction / (tau * q.real_area_fraction) - 1.0).abs() < 1e-6,
            "{h}"
        );
        assert!((b.adhesion / a.adhesion - 1.0).abs() < 1e-9, "{h}");
    }
}
