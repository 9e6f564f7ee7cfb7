//! criterion bench of the ODE integrator (`numerics::ode`): a damped, coupled 2-DOF oscillator
//! with the slider's air-bearing frequencies (110 kHz pitch, 275 kHz heave, ζ = 0.02) driven by
//! a DMW-like 1 nm, 10.7 kHz line plus a small 200 kHz component, integrated for 2 ms of
//! simulated time with rtol 1e-8 (docs/integrator.md tolerances) and sampled at 0.25 µs by dense
//! output. Prints the step and RHS counts once, so ns/step = time / accepted steps.
//! Not run in CI.
use criterion::{criterion_group, criterion_main, Criterion};
use hdi::numerics::ode::{integrate, OdeOptions, OdeSolution, Sampling};
use std::convert::Infallible;
use std::f64::consts::PI;
use std::hint::black_box;

const T_END: f64 = 2e-3;
const DT_OUT: f64 = 0.25e-6;

struct TwoDof {
    k: [[f64; 2]; 2],
    c: [[f64; 2]; 2],
    /// Scale of the forcing (0 = free vibration: measures the integrator's own cost per step).
    forcing: f64,
}

impl TwoDof {
    fn slider_like() -> Self {
        let (w1, w2) = (2.0 * PI * 110e3, 2.0 * PI * 275e3);
        let zeta = 0.02;
        let (s, co) = (PI / 6.0).sin_cos(); // modes rotated by 30°: coupled coordinates
        let r = [[co, -s], [s, co]];
        let mut k = [[0.0; 2]; 2];
        let mut c = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                k[i][j] = r[i][0] * w1 * w1 * r[j][0] + r[i][1] * w2 * w2 * r[j][1];
                c[i][j] = 2.0 * zeta * (r[i][0] * w1 * r[j][0] + r[i][1] * w2 * r[j][1]);
            }
        }
        TwoDof { k, c, forcing: 1.0 }
    }

    fn rhs(&self, t: f64, y: &[f64; 4], dy: &mut [f64; 4]) -> Result<(), Infallible> {
        let w_dmw = 2.0 * PI * 10.7e3;
        let f = if self.forcing == 0.0 {
            0.0
        } else {
            self.forcing
                * (1e-9 * self.k[0][0] * (w_dmw * t).sin()
                    + 0.05e-9 * self.k[1][1] * (2.0 * PI * 200e3 * t).sin())
        };
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = f
            - self.k[0][0] * y[0]
            - self.k[0][1] * y[1]
            - self.c[0][0] * y[2]
            - self.c[0][1] * y[3];
        dy[3] =
            -self.k[1][0] * y[0] - self.k[1][1] * y[1] - self.c[1][0] * y[2] - self.c[1][1] * y[3];
        Ok(())
    }
}

fn options(max_step: Option<f64>) -> OdeOptions<4> {
    let vel = 1e-14 * 2.0 * PI * 1e6;
    let o = OdeOptions::adaptive_per_component(1e-8, [1e-14, 1e-14, vel, vel]);
    match max_step {
        Some(h) => o.with_max_step(h),
        None => o,
    }
}

fn run(sys: &TwoDof, opts: &OdeOptions<4>, out: &mut Vec<f64>) -> OdeSolution<4> {
    out.clear();
    integrate(
        |t, y: &[f64; 4], dy: &mut [f64; 4]| sys.rhs(t, y, dy),
        0.0,
        [1e-9, 0.0, 0.0, 0.0],
        T_END,
        opts,
        Sampling::Uniform { dt: DT_OUT },
        |_, y| out.push(y[0]),
    )
    .unwrap()
}

fn ode(c: &mut Criterion) {
    let forced = TwoDof::slider_like();
    let free = TwoDof {
        forcing: 0.0,
        ..TwoDof::slider_like()
    };
    let cases = [
        ("dopri5_rtol1e-8_2ms", &forced, options(None)),
        ("dopri5_rtol1e-8_hmax1e-8_2ms", &forced, options(Some(1e-8))),
        ("dopri5_fixed_h1e-9_2ms", &forced, OdeOptions::fixed(1e-9)),
        (
            "dopri5_rtol1e-8_hmax1e-8_2ms_free",
            &free,
            options(Some(1e-8)),
        ),
    ];
    let mut out = Vec::with_capacity((T_END / DT_OUT) as usize + 2);
    for (name, sys, o) in &cases {
        let s = run(sys, o, &mut out).stats;
        eprintln!(
            "{name}: {} accepted, {} rejected, {} RHS evaluations, {} samples",
            s.accepted_steps, s.rejected_steps, s.rhs_evaluations, s.samples
        );
    }
    let mut g = c.benchmark_group("ode");
    g.sample_size(10);
    for (name, sys, o) in &cases {
        g.bench_function(*name, |b| b.iter(|| run(black_box(sys), o, &mut out)));
    }
    g.finish();
}

criterion_group!(benches, ode);
criterion_main!(benches);
