//! criterion benches of the contact model: one direct ISBL evaluation, building the force
//! table of an interface, and ns per table lookup (the dynamics' inner loop). Not run in CI.
use criterion::{criterion_group, criterion_main, Criterion};
use hdi::contact::isbl::{IsblModel, IsblParams};
use hdi::contact::lookup::IsblLookup;
use hdi::contact::mtl::rough::RoughMtl;
use hdi::stages::contact::{analyse, check, ContactConfig};
use std::hint::black_box;
use std::sync::Arc;

fn contact(c: &mut Criterion) {
    let cfg = ContactConfig::defaults();
    let params = check(&cfg).unwrap();
    let model = IsblModel::new(IsblParams::improved_2dof()).unwrap();
    let table = analyse(&params.params, &params, None)
        .unwrap()
        .table()
        .clone();
    let mut g = c.benchmark_group("contact");
    g.sample_size(10);
    g.bench_function("isbl_direct_evaluation_h_3sigma", |b| {
        b.iter(|| model.at(black_box(1.5e-9)).unwrap())
    });
    g.bench_function("build_curves_and_verified_table_improved_set", |b| {
        b.iter(|| analyse(&params.params, &params, None).unwrap())
    });
    g.finish();
    let mut g = c.benchmark_group("force_table");
    g.bench_function("lookup_value", |b| {
        let mut x = -3.9;
        b.iter(|| {
            x += 0.000_37;
            if x > 13.9 {
                x = -3.9;
            }
            black_box(table.eval(0, black_box(x)))
        })
    });
    g.bench_function("lookup_value_and_slope", |b| {
        let mut x = -3.9;
        b.iter(|| {
            x += 0.000_37;
            if x > 13.9 {
                x = -3.9;
            }
            black_box(table.eval_with_slope(1, black_box(x)))
        })
    });
    g.finish();
    // What the dynamics call per feature and step: all ISBL quantities at one separation, and
    // the MTL lubricant + solid interface on the tabulated solid (closed-form lubricant law).
    let mut g = c.benchmark_group("lookup");
    let isbl = Arc::new(
        IsblLookup::build_standard(IsblModel::new(IsblParams::mtl_table_3_2()).unwrap()).unwrap(),
    );
    g.bench_function("isbl_all_channels", |b| {
        let mut h = 0.0;
        b.iter(|| {
            h += 0.000_37e-9;
            if h > 8e-9 {
                h = 0.0;
            }
            black_box(isbl.at(black_box(h)).unwrap())
        })
    });
    let mtl = RoughMtl::reference().with_solid(isbl.as_solid(2500e-12));
    g.bench_function("mtl_interface_on_tabulated_solid", |b| {
        let mut h = 1.5e-9;
        b.iter(|| {
            h += 0.000_37e-9;
            if h > 4.5e-9 {
                h = 1.5e-9;
            }
            black_box(mtl.evaluate(black_box(h)))
        })
    });
    g.finish();
}

criterion_group!(benches, contact);
criterion_main!(benches);
