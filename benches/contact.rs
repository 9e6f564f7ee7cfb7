//! criterion benches of the contact force tables: build time and ns per lookup (the dynamics'
//! inner loop). Not run in CI.
use criterion::{black_box, criterion_group, criterion_main, Criterion};
use hdi::contact::table::{ForceTable, Interp, Sample};

/// A GW-like positive tail and its exact derivative (the table's cost does not depend on what
/// the physics is, only on the channel count and the grid).
fn tail(x: f64) -> Result<Sample, hdi::contact::ContactError> {
    let y = (-0.5 * x * x).exp() * (1.0 + 0.3 * x * x);
    let dy = (-0.5 * x * x).exp() * (0.6 * x - x * (1.0 + 0.3 * x * x));
    Ok(Sample {
        value: vec![y; 6],
        derivative: vec![dy; 6],
    })
}

fn contact(c: &mut Criterion) {
    let channels: Vec<(&str, Interp)> = ["p", "kc", "ar", "q", "fs", "nc"]
        .iter()
        .map(|n| (*n, Interp::Log))
        .collect();
    let table = ForceTable::build(&channels, -4.0, 14.0, 0.05, tail).unwrap();
    let mut g = c.benchmark_group("force_table");
    g.bench_function("lookup_one_channel", |b| {
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
}

criterion_group!(benches, contact);
criterion_main!(benches);
