//! criterion benches of the 2-DOF slider: one 2 ms case (flying and in steady contact) with the
//! spec's synthetic DMW, and the shipped 76-case sweep on all cores. Not run in CI.
//! Before criterion, prints µs per accepted step and RHS evaluations per step of each case
//! (best of 5; the issue-20 goal is ≤ 1.5 µs per step, docs/performance.md).
use criterion::{criterion_group, criterion_main, Criterion};
use hdi::contact::isbl::{IsblModel, IsblParams};
use hdi::contact::lookup::IsblLookup;
use hdi::dmw::excitation_tracks::synthetic_dmw;
use hdi::dynamics::params::improved_2dof;
use hdi::dynamics::two_dof::{DmwInput, SimOptions, TwoDofCase};
use rayon::prelude::*;
use std::hint::black_box;

fn simulate(c: &mut Criterion) {
    let isbl =
        IsblLookup::build_standard(IsblModel::new(IsblParams::improved_2dof()).unwrap()).unwrap();
    let track = synthetic_dmw(2.2e-3, 4e6, 1e-9, 1).unwrap();
    let dmw = || {
        Some(DmwInput {
            displacement: &track.displacement,
            velocity: &track.velocity,
            sample_rate: track.fs,
        })
    };
    let model = improved_2dof();
    let options = SimOptions {
        static_init: true,
        ..SimOptions::default()
    };
    for h in [8.5, 10.4, 12.0] {
        let (mut best, mut stats) = (f64::INFINITY, Default::default());
        for _ in 0..5 {
            let t = std::time::Instant::now();
            let case = TwoDofCase::new(&model, h * 1e-9, &isbl, dmw(), options).unwrap();
            let r = case.run().unwrap();
            best = best.min(t.elapsed().as_secs_f64());
            stats = r.stats;
        }
        let s: hdi::numerics::ode::OdeStats = stats;
        eprintln!(
            "two_dof {h} nm: {} accepted + {} rejected steps, {:.2} RHS/step, best {:.2} ms = \
             {:.3} µs per accepted step",
            s.accepted_steps,
            s.rejected_steps,
            s.rhs_per_accepted_step(),
            best * 1e3,
            s.micros_per_accepted_step(best)
        );
    }
    let mut g = c.benchmark_group("two_dof");
    g.sample_size(10);
    for h in [8.5, 10.4, 12.0] {
        g.bench_function(format!("one_2ms_case_{h}nm"), |b| {
            b.iter(|| {
                let case = TwoDofCase::new(&model, h * 1e-9, &isbl, dmw(), options).unwrap();
                black_box(case.run().unwrap())
            })
        });
    }
    g.bench_function("sweep_76_cases_0_to_15nm", |b| {
        b.iter(|| {
            let r: Vec<_> = (0..76)
                .into_par_iter()
                .map(|i| {
                    let h = i as f64 * 0.2e-9;
                    let case = TwoDofCase::new(&model, h, &isbl, dmw(), options).unwrap();
                    case.run()
                        .unwrap()
                        .metrics(&hdi::dynamics::metrics::CaseParams::improved_2dof())
                })
                .collect();
            black_box(r)
        })
    });
    g.finish();
}

criterion_group!(benches, simulate);
criterion_main!(benches);
