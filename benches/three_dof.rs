//! criterion benches of the 3-DOF slider (issue 7): one 2 ms case at constant 12 nm (ISBL) and
//! the 2 ms variable-actuation scenario (S5 profile, MTL reference lubricant), both on the
//! spec's synthetic DMW as tracks D1–D3, plus the shock case. Not run in CI.
use criterion::{criterion_group, criterion_main, Criterion};
use hdi::contact::isbl::{IsblModel, IsblParams, SurfaceEnergy};
use hdi::contact::lookup::IsblLookup;
use hdi::contact::mtl::{FwmExperiment, LubricantCase, RoughFilm, RoughMtl};
use hdi::dmw::excitation_tracks::synthetic_dmw;
use hdi::dynamics::three_dof::air_bearing::PushbackCurve;
use hdi::dynamics::three_dof::case::{Model3Dof, Options3Dof, ThreeDofCase};
use hdi::dynamics::three_dof::inputs::{ActuationProfile, ShockPulse};
use hdi::dynamics::three_dof::interface::{FeatureInterface, InterfaceLaw};
use hdi::dynamics::two_dof::{ContactForceForm, DmwInput};
use std::hint::black_box;

fn three_dof(c: &mut Criterion) {
    let lookup = |variable: bool| {
        let mut p = IsblParams::three_dof();
        if variable {
            p.surface_energy = SurfaceEnergy::seed_variable();
        }
        IsblLookup::build_standard(IsblModel::new(p).unwrap()).unwrap()
    };
    let (isbl, isbl_mtl) = (lookup(false), lookup(true));
    let d = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1).unwrap();
    let flip = |x: &[f64], s: f64| x.iter().rev().map(|v| s * v).collect::<Vec<_>>();
    let (d2, v2, d3, v3) = (
        flip(&d.displacement, 1.0),
        flip(&d.velocity, -1.0),
        flip(&d.displacement, -1.0),
        flip(&d.velocity, 1.0),
    );
    let tracks = || {
        Some([
            DmwInput {
                displacement: &d.displacement,
                velocity: &d.velocity,
                sample_rate: d.fs,
            },
            DmwInput {
                displacement: &d2,
                velocity: &v2,
                sample_rate: d.fs,
            },
            DmwInput {
                displacement: &d3,
                velocity: &v3,
                sample_rate: d.fs,
            },
        ])
    };
    let model = Model3Dof::dissertation();
    let mass = model.air_bearing.slider.mass;
    let isbl_interface = || {
        FeatureInterface::new(
            &isbl,
            InterfaceLaw::Isbl,
            ContactForceForm::InterferenceTangent,
            0.05,
            mass,
        )
        .unwrap()
    };
    let film = RoughFilm::new(0.5e-9, 0.3e-9, 1.5e-9, model.disk_speed).unwrap();
    let exp = FwmExperiment::fukuzawa_z03()
        .with_limiting_viscosity(LubricantCase::Reference.limiting_viscosity())
        .unwrap();
    let mtl = RoughMtl::from_experiment(film, &exp).unwrap();
    let mut g = c.benchmark_group("three_dof");
    g.sample_size(10);
    g.bench_function("one_2ms_case_12nm_isbl", |b| {
        b.iter(|| {
            let case = ThreeDofCase::new(
                &model,
                isbl_interface(),
                ActuationProfile::constant(12e-9).unwrap(),
                None,
                tracks(),
                Options3Dof::default(),
            )
            .unwrap();
            black_box(case.run().unwrap())
        })
    });
    let mut flattened = model.clone();
    flattened.pushback = PushbackCurve::flattened();
    g.bench_function("variable_actuation_2ms_mtl", |b| {
        b.iter(|| {
            let interface = FeatureInterface::new(
                &isbl_mtl,
                InterfaceLaw::Mtl(mtl),
                ContactForceForm::InterferenceTangent,
                0.05,
                mass,
            )
            .unwrap();
            let case = ThreeDofCase::new(
                &flattened,
                interface,
                ActuationProfile::variable_default(),
                None,
                tracks(),
                Options3Dof::default(),
            )
            .unwrap();
            black_box(case.run().unwrap())
        })
    });
    g.bench_function("shock_1_5ms_isbl", |b| {
        b.iter(|| {
            let case = ThreeDofCase::new(
                &model,
                isbl_interface(),
                ActuationProfile::constant(5e-9).unwrap(),
                Some(ShockPulse::dissertation()),
                tracks(),
                Options3Dof {
                    duration: 1.5e-3,
                    ..Options3Dof::default()
                },
            )
            .unwrap();
            black_box(case.run().unwrap())
        })
    });
    g.finish();
}

criterion_group!(benches, three_dof);
criterion_main!(benches);
