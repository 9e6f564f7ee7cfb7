//! criterion benches of the DMW chain on a 10^7-sample record (4 MS/s, 2.5 s, 227
//! revolutions): the benchmark size. Not run in CI. `scripts/bench_dmw.py` times
//! the same steps end to end against numpy/scipy.
use criterion::{criterion_group, criterion_main, Criterion};
use hdi::dmw::average::{synchronous_average, AverageMode};
use hdi::dmw::chain::{process, ChainParams};
use hdi::dmw::synthetic_ldv::{generate, LdvSynthSpec};
use hdi::dmw::triggers::{detect_triggers, TriggerOptions};
use hdi::signal::butterworth::{butterworth_sos, FilterKind};
use hdi::signal::sosfilt::{sosfiltfilt, PadType};

fn dmw(c: &mut Criterion) {
    let spec = LdvSynthSpec {
        n_revolutions: 227,
        ..Default::default()
    };
    let (rec, _) = generate(&spec);
    assert!(rec.velocity.len() >= 10_000_000);
    let index = rec.index.clone().unwrap();
    let fs = spec.sample_rate;
    let hp = butterworth_sos(4, 10e3, fs, FilterKind::HighPass).unwrap();
    let params = ChainParams {
        rpm: Some(spec.rpm),
        ..Default::default()
    };
    let triggers = detect_triggers(
        &index,
        fs,
        Some(60.0 / spec.rpm),
        &TriggerOptions::default(),
    )
    .unwrap()
    .times;

    let mut g = c.benchmark_group("dmw_1e7");
    g.sample_size(10);
    g.bench_function("chain_angular_in_memory", |b| {
        b.iter(|| process(&rec, &params).unwrap())
    });
    g.bench_function("trigger_detection", |b| {
        b.iter(|| {
            detect_triggers(
                &index,
                fs,
                Some(60.0 / spec.rpm),
                &TriggerOptions::default(),
            )
            .unwrap()
        })
    });
    for mode in [
        AverageMode::Integer,
        AverageMode::Subsample,
        AverageMode::Angular,
    ] {
        g.bench_function(format!("average_{mode}"), |b| {
            b.iter(|| synchronous_average(&rec.velocity, fs, &triggers, 10_000, mode).unwrap())
        });
    }
    g.bench_function("sosfiltfilt_whole_record", |b| {
        b.iter(|| sosfiltfilt(&hp, &rec.velocity, PadType::Odd, Some(1200)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, dmw);
criterion_main!(benches);
