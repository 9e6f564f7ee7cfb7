//! Explicit embedded Runge–Kutta integrator for the slider dynamics (docs/integrator.md):
//! Dormand–Prince 5(4) with FSAL, mixed absolute/relative error control per component, a PI
//! step-size controller, `max_step`/`min_step`, mandatory stop times, a fixed-step
//! "reproduction" mode and the order-4 continuous extension (dense output), so that samples land
//! on exact uniform output times independent of the internal steps.
//!
//! Generic over the state size with `const N: usize` (`[f64; N]` states, no heap allocation per
//! step). The right-hand side is `FnMut(t, &y, &mut dy) -> Result<(), E>`; an `Err` aborts the
//! integration cleanly with [`OdeError::Rhs`]. The integrator never returns a non-finite state:
//! a NaN/∞ ends the run with [`OdeError::NonFinite`].
//!
//! Tableau and continuous extension: J. R. Dormand & P. J. Prince, "A family of embedded
//! Runge–Kutta formulae", J. Comput. Appl. Math. 6(1):19–26, 1980; dense-output coefficients and
//! the PI controller as in Hairer, Nørsett & Wanner, *Solving ODEs I* (2nd ed.), §II.4–II.6 and
//! their code DOPRI5. See `docs/integrator.md`.

/// Errors of [`integrate`]. `E` is the right-hand side's own error type.
#[derive(Debug, thiserror::Error)]
pub enum OdeError<E> {
    /// The controller asked for a step below `min_step` (or below the floating-point resolution
    /// of `t`): the problem is too stiff or singular near `t`.
    #[error("step size underflow at t = {t:e} s (h = {h:e} s)")]
    StepUnderflow { t: f64, h: f64 },
    /// A state component (or a derivative) became NaN or infinite in a step starting at `t`.
    #[error("non-finite value in state component {component} at t = {t:e} s")]
    NonFinite { t: f64, component: usize },
    /// `max_steps` steps (accepted + rejected) were taken before reaching the end.
    #[error("maximum number of steps ({steps}) exceeded at t = {t:e} s")]
    MaxStepsExceeded { t: f64, steps: u64 },
    /// The right-hand side reported an error at `t`.
    #[error("right-hand side failed at t = {t:e} s: {source}")]
    Rhs {
        t: f64,
        #[source]
        source: E,
    },
    /// Options or arguments out of range (negative tolerance, `t_end < t0`, ...).
    #[error("invalid integrator input: {0}")]
    InvalidInput(String),
}

/// Step-size mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepMode {
    /// Error-controlled steps (`rtol`, `atol`, PI controller, `max_step`, `min_step`).
    Adaptive,
    /// Fixed step `h` on the grid `t0 + k·h` (the dissertation's "5th-order RK at a small fixed
    /// step"); no error estimate is computed. Stop times and `t_end` shorten the step that
    /// crosses them.
    Fixed(f64),
}

/// Integrator options. SI units (seconds for all step sizes).
#[derive(Debug, Clone, PartialEq)]
pub struct OdeOptions<const N: usize> {
    pub mode: StepMode,
    /// Relative tolerance (all components).
    pub rtol: f64,
    /// Absolute tolerance per component (same unit as the component).
    pub atol: [f64; N],
    /// Initial step; `None` = automatic (Hairer's starting-step heuristic).
    pub h_init: Option<f64>,
    /// Largest step [s] (`f64::INFINITY` = no cap). Resolves contact switching.
    pub max_step: f64,
    /// Smallest step [s] the controller may ask for before giving up with
    /// [`OdeError::StepUnderflow`] (steps shortened to land on a stop time or `t_end` are exempt).
    pub min_step: f64,
    /// Maximum number of steps (accepted + rejected).
    pub max_steps: u64,
    /// Safety factor of the controller.
    pub safety: f64,
    /// Bounds of the step-size ratio `h_new/h`.
    pub min_factor: f64,
    pub max_factor: f64,
    /// PI controller: `h_new = h·safety·err^(−α)·err_prev^(β)`, `α = 1/5 − 0.75 β`.
    pub beta: f64,
    /// Times where a step must end exactly (known discontinuities: pulse start/end, actuation
    /// breakpoints). The derivative is re-evaluated there (FSAL is not carried across).
    /// Need not be sorted; times outside `(t0, t_end)` are ignored.
    pub stop_times: Vec<f64>,
}

impl<const N: usize> OdeOptions<N> {
    /// Adaptive mode with `rtol` and the same `atol` for every component; no step cap.
    pub fn adaptive(rtol: f64, atol: f64) -> Self {
        Self::adaptive_per_component(rtol, [atol; N])
    }

    /// Adaptive mode with per-component absolute tolerances.
    pub fn adaptive_per_component(rtol: f64, atol: [f64; N]) -> Self {
        OdeOptions {
            mode: StepMode::Adaptive,
            rtol,
            atol,
            h_init: None,
            max_step: f64::INFINITY,
            min_step: 0.0,
            max_steps: 100_000_000,
            safety: 0.9,
            min_factor: 0.2,
            max_factor: 10.0,
            beta: 0.04,
            stop_times: Vec::new(),
        }
    }

    /// Fixed-step mode with step `h` [s].
    pub fn fixed(h: f64) -> Self {
        OdeOptions {
            mode: StepMode::Fixed(h),
            ..Self::adaptive(0.0, 0.0)
        }
    }

    /// Builder: cap the step size.
    pub fn with_max_step(mut self, max_step: f64) -> Self {
        self.max_step = max_step;
        self
    }

    /// Builder: smallest acceptable controller step.
    pub fn with_min_step(mut self, min_step: f64) -> Self {
        self.min_step = min_step;
        self
    }

    /// Builder: mandatory stop times.
    pub fn with_stop_times(mut self, stop_times: Vec<f64>) -> Self {
        self.stop_times = stop_times;
        self
    }

    fn validate<E>(&self, t0: f64, t_end: f64) -> Result<(), OdeError<E>> {
        let bad = |m: String| Err(OdeError::InvalidInput(m));
        if !t0.is_finite() || !t_end.is_finite() || t_end < t0 {
            return bad(format!("need finite t0 <= t_end, got {t0} .. {t_end}"));
        }
        match self.mode {
            StepMode::Fixed(h) => {
                if !(h.is_finite() && h > 0.0) {
                    return bad(format!("fixed step must be finite and > 0, got {h}"));
                }
            }
            StepMode::Adaptive => {
                if !(self.rtol.is_finite() && self.rtol >= 0.0) {
                    return bad(format!("rtol must be finite and >= 0, got {}", self.rtol));
                }
                if let Some(i) = self.atol.iter().position(|a| !(a.is_finite() && *a >= 0.0)) {
                    return bad(format!("atol[{i}] must be finite and >= 0"));
                }
                if let Some(i) = (0..N).find(|&i| self.atol[i] == 0.0 && self.rtol == 0.0) {
                    return bad(format!("component {i} has rtol = atol = 0"));
                }
                let steps_ok =
                    self.max_step > 0.0 && self.min_step >= 0.0 && self.min_step <= self.max_step;
                if !steps_ok {
                    return bad(format!(
                        "need 0 <= min_step <= max_step, max_step > 0 (got {} .. {})",
                        self.min_step, self.max_step
                    ));
                }
                if let Some(h) = self.h_init {
                    if !(h.is_finite() && h > 0.0) {
                        return bad(format!("h_init must be finite and > 0, got {h}"));
                    }
                }
                let controller_ok = self.safety > 0.0
                    && self.safety <= 1.0
                    && self.min_factor > 0.0
                    && self.min_factor < 1.0
                    && self.max_factor > 1.0
                    && (0.0..=0.2).contains(&self.beta);
                if !controller_ok {
                    return bad("controller constants out of range".into());
                }
            }
        }
        if let Some(s) = self.stop_times.iter().find(|s| !s.is_finite()) {
            return bad(format!("stop time {s} is not finite"));
        }
        Ok(())
    }
}

/// Where the observer is called.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sampling {
    /// At `t0 + k·dt` for every `k ≥ 0` with `t0 + k·dt ≤ t_end` (dense output between steps;
    /// a sample that coincides with a step end uses the step's own state).
    Uniform { dt: f64 },
    /// At `t0` and at the end of every accepted step.
    Steps,
    /// Never.
    None,
}

/// Counters of one integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OdeStats {
    pub accepted_steps: u64,
    pub rejected_steps: u64,
    pub rhs_evaluations: u64,
    /// Observer calls.
    pub samples: u64,
}

impl OdeStats {
    /// Wall time per accepted step [µs] for a run that took `wall_seconds` (the figure of
    /// `hdi bench` and `cargo bench --bench simulate`; docs/performance.md). NaN without steps.
    pub fn micros_per_accepted_step(&self, wall_seconds: f64) -> f64 {
        if self.accepted_steps == 0 {
            return f64::NAN;
        }
        wall_seconds * 1e6 / self.accepted_steps as f64
    }

    /// Right-hand-side evaluations per accepted step (6 for DP5 with FSAL and no rejections,
    /// plus the rejected steps' and the start's). NaN without steps.
    pub fn rhs_per_accepted_step(&self) -> f64 {
        if self.accepted_steps == 0 {
            return f64::NAN;
        }
        self.rhs_evaluations as f64 / self.accepted_steps as f64
    }
}

/// Result of a successful integration: the state at `t_end` and the counters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdeSolution<const N: usize> {
    pub t: f64,
    pub y: [f64; N],
    pub stats: OdeStats,
}

// ---- Dormand–Prince 5(4) tableau (Dormand & Prince 1980, Table 2 "RK5(4)7M") ----
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
// 5th-order weights (= row 7: FSAL).
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
// Error weights b − b̂ (5th minus embedded 4th order).
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Order-4 continuous extension (Hairer–Wanner DOPRI5 `dense` coefficients).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Dense output of one accepted step `[t, t + h]`: `y(t + θh) = r1 + θ(r2 + (1−θ)(r3 + θ(r4 +
/// (1−θ) r5)))`.
struct Dense<const N: usize> {
    t: f64,
    h: f64,
    r: [[f64; N]; 5],
}

impl<const N: usize> Dense<N> {
    fn eval(&self, t: f64, out: &mut [f64; N]) {
        let th = (t - self.t) / self.h;
        let th1 = 1.0 - th;
        let [r1, r2, r3, r4, r5] = &self.r;
        for i in 0..N {
            out[i] = r1[i] + th * (r2[i] + th1 * (r3[i] + th * (r4[i] + th1 * r5[i])));
        }
    }
}

fn first_non_finite<const N: usize>(v: &[f64; N]) -> Option<usize> {
    v.iter().position(|x| !x.is_finite())
}

/// Sorted, deduplicated stop times strictly inside `(t0, t_end)`.
fn sorted_stops(stops: &[f64], t0: f64, t_end: f64) -> Vec<f64> {
    let mut s: Vec<f64> = stops
        .iter()
        .copied()
        .filter(|&s| s > t0 && s < t_end)
        .collect();
    s.sort_by(f64::total_cmp);
    s.dedup();
    s
}

/// Integrate `y' = f(t, y)` from `(t0, y0)` to `t_end`.
///
/// `rhs(t, y, dy)` writes the derivative into `dy`; returning `Err(e)` aborts with
/// [`OdeError::Rhs`]. `observer(t, y)` is called at the times chosen by `sampling`, in
/// increasing order (including `t0`; including `t_end` when it lies on the sampling grid or
/// with [`Sampling::Steps`]). All buffers are on the stack; the only allocation is the sorted copy
/// of `opts.stop_times`, once per call.
pub fn integrate<const N: usize, E, F, O>(
    rhs: F,
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    opts: &OdeOptions<N>,
    sampling: Sampling,
    observer: O,
) -> Result<OdeSolution<N>, OdeError<E>>
where
    F: FnMut(f64, &[f64; N], &mut [f64; N]) -> Result<(), E>,
    O: FnMut(f64, &[f64; N]),
{
    integrate_capped(
        rhs,
        |_, _| f64::INFINITY,
        t0,
        y0,
        t_end,
        opts,
        sampling,
        observer,
    )
}

/// [`integrate`] with a state-dependent step limit (adaptive mode): before each step attempt
/// `step_cap(t, y)` bounds the step from the current accepted state. The slider dynamics use
/// it to shorten steps only while a contact is near or active (a fixed `max_step` everywhere
/// would cost 100× more steps in free flight, docs/integrator.md). Ignored in fixed mode.
#[allow(clippy::too_many_arguments)]
pub fn integrate_capped<const N: usize, E, F, C, O>(
    mut rhs: F,
    mut step_cap: C,
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    opts: &OdeOptions<N>,
    sampling: Sampling,
    mut observer: O,
) -> Result<OdeSolution<N>, OdeError<E>>
where
    F: FnMut(f64, &[f64; N], &mut [f64; N]) -> Result<(), E>,
    C: FnMut(f64, &[f64; N]) -> f64,
    O: FnMut(f64, &[f64; N]),
{
    check_inputs(opts, t0, &y0, t_end, sampling)?;
    let stops = sorted_stops(&opts.stop_times, t0, t_end);
    let mut next_stop = 0usize;
    let mut stats = OdeStats::default();
    let mut samples = Samples::new(sampling, t0, t_end);
    samples.first(t0, &y0, &mut observer, &mut stats);

    let mut t = t0;
    let mut y = y0;
    let mut st = Stages::new();
    if t_end == t0 {
        return Ok(OdeSolution { t, y, stats });
    }
    evaluate(&mut rhs, &mut stats, t, &y, &mut st.k1)?;

    let (fixed_h, max_step) = match opts.mode {
        StepMode::Fixed(h) => (Some(h), f64::INFINITY),
        StepMode::Adaptive => (None, opts.max_step),
    };
    let mut h = match (fixed_h, opts.h_init) {
        (Some(h), _) => h,
        (None, Some(h)) => h.min(max_step),
        (None, None) => starting_step(&mut rhs, &mut stats, opts, t, t_end, &y, &st.k1, max_step)?,
    };
    let mut control = Controller::new(opts);
    let mut pending_non_finite: Option<usize> = None;
    let mut k_grid: u64 = 0; // fixed mode: index of the current grid point

    while t < t_end {
        if stats.accepted_steps + stats.rejected_steps >= opts.max_steps {
            return Err(OdeError::MaxStepsExceeded {
                t,
                steps: opts.max_steps,
            });
        }
        // Target of this step: the controller's h, clipped to the next stop / t_end / grid.
        let target_limit = stops.get(next_stop).copied().unwrap_or(t_end);
        let t_new = match fixed_h {
            Some(hf) => fixed_step_end(t0, hf, t, target_limit, &mut k_grid),
            None => {
                let cap = step_cap(t, &y);
                adaptive_step_end(&mut h, cap, max_step, opts.min_step, t, target_limit).map_err(
                    |underflow| match pending_non_finite {
                        Some(component) => OdeError::NonFinite { t, component },
                        None => underflow,
                    },
                )?
            }
        };
        let hs = t_new - t;
        // A step ending on a stop time sees the left limit of the right-hand side there: its
        // c = 1 stages are evaluated at the float just below the stop.
        let t_right = if next_stop < stops.len() && t_new == stops[next_stop] {
            t_new.next_down()
        } else {
            t_new
        };

        // In adaptive mode a non-finite stage or result rejects the step (it may just be too
        // long); the error is reported only if the controller cannot shrink further.
        let adaptive = fixed_h.is_none();
        if let Some(component) = st.attempt(&mut rhs, &mut stats, t, &y, hs, t_right, adaptive)? {
            pending_non_finite = Some(component);
            h = hs * opts.min_factor;
            control.last_rejected = true;
            stats.rejected_steps += 1;
            continue;
        }
        pending_non_finite = None;

        if adaptive {
            let err = st.error_norm(opts, &y, hs);
            if !err.is_finite() {
                // Finite states and stages with a non-finite error norm: the terms overflowed.
                return Err(OdeError::NonFinite { t, component: 0 });
            }
            let at_limit = t_new == target_limit;
            match control.judge(err, h, hs, max_step, at_limit) {
                Verdict::Accept { h: next } => h = next,
                Verdict::Reject { h: retry } => {
                    h = retry;
                    stats.rejected_steps += 1;
                    continue;
                }
            }
        }

        stats.accepted_steps += 1;
        samples.after_step(&st, t, &y, hs, t_new, &mut observer, &mut stats);
        t = t_new;
        y = st.y_new;
        if next_stop < stops.len() && t >= stops[next_stop] {
            next_stop += 1;
            // Discontinuity: the derivative after the stop is re-evaluated, not carried over.
            evaluate(&mut rhs, &mut stats, t, &y, &mut st.k1)?;
        } else {
            st.k1 = st.k7;
        }
    }
    Ok(OdeSolution { t, y, stats })
}

/// The options, the output step and the initial state, checked before any evaluation.
fn check_inputs<const N: usize, E>(
    opts: &OdeOptions<N>,
    t0: f64,
    y0: &[f64; N],
    t_end: f64,
    sampling: Sampling,
) -> Result<(), OdeError<E>> {
    opts.validate::<E>(t0, t_end)?;
    if let Sampling::Uniform { dt } = sampling {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(OdeError::InvalidInput(format!(
                "output step must be finite and > 0, got {dt}"
            )));
        }
    }
    match first_non_finite(y0) {
        Some(i) => Err(OdeError::NonFinite {
            t: t0,
            component: i,
        }),
        None => Ok(()),
    }
}

/// One right-hand-side evaluation as the integrator counts and checks it: a non-finite
/// derivative is an error.
#[inline(always)]
fn evaluate<const N: usize, E, F>(
    rhs: &mut F,
    stats: &mut OdeStats,
    t: f64,
    y: &[f64; N],
    dy: &mut [f64; N],
) -> Result<(), OdeError<E>>
where
    F: FnMut(f64, &[f64; N], &mut [f64; N]) -> Result<(), E>,
{
    stats.rhs_evaluations += 1;
    rhs(t, y, dy).map_err(|source| OdeError::Rhs { t, source })?;
    match first_non_finite(dy) {
        Some(i) => Err(OdeError::NonFinite { t, component: i }),
        None => Ok(()),
    }
}

/// The error scale of component `i` between two states: `atol_i + rtol·max(|y0_i|, |y1_i|)`.
#[inline(always)]
fn error_scale<const N: usize>(
    opts: &OdeOptions<N>,
    y0: &[f64; N],
    y1: &[f64; N],
    i: usize,
) -> f64 {
    opts.atol[i] + opts.rtol * y0[i].abs().max(y1[i].abs())
}

/// Hairer's starting step: h0 = 0.01·‖y‖/‖f‖, one Euler probe, h1 from the second-derivative
/// estimate; h = min(100 h0, h1), within `max_step`.
#[allow(clippy::too_many_arguments)]
fn starting_step<const N: usize, E, F>(
    rhs: &mut F,
    stats: &mut OdeStats,
    opts: &OdeOptions<N>,
    t: f64,
    t_end: f64,
    y: &[f64; N],
    k1: &[f64; N],
    max_step: f64,
) -> Result<f64, OdeError<E>>
where
    F: FnMut(f64, &[f64; N], &mut [f64; N]) -> Result<(), E>,
{
    let mut d0 = 0.0;
    let mut d1 = 0.0;
    for i in 0..N {
        let sc = error_scale(opts, y, y, i);
        d0 += (y[i] / sc).powi(2);
        d1 += (k1[i] / sc).powi(2);
    }
    let (d0, d1) = ((d0 / N as f64).sqrt(), (d1 / N as f64).sqrt());
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(max_step).min(t_end - t);
    let mut y1 = [0.0; N];
    for i in 0..N {
        y1[i] = y[i] + h0 * k1[i];
    }
    let mut f1 = [0.0; N];
    evaluate(rhs, stats, t + h0, &y1, &mut f1)?;
    let mut d2 = 0.0;
    for i in 0..N {
        d2 += ((f1[i] - k1[i]) / error_scale(opts, y, y, i)).powi(2);
    }
    let d2 = (d2 / N as f64).sqrt() / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(0.2)
    };
    Ok((100.0 * h0).min(h1).min(max_step))
}

/// Fixed mode: the next grid point strictly after `t`, clipped to the limit (a grid point
/// within rounding of the limit is moved onto it rather than leave a sliver step).
#[inline(always)]
fn fixed_step_end(t0: f64, hf: f64, t: f64, target_limit: f64, k_grid: &mut u64) -> f64 {
    let mut g = t0 + (*k_grid + 1) as f64 * hf;
    while g <= t {
        *k_grid += 1;
        g = t0 + (*k_grid + 1) as f64 * hf;
    }
    let t_new = g.min(target_limit);
    if target_limit - t_new < 1e-9 * hf {
        target_limit
    } else {
        t_new
    }
}

/// Adaptive mode: the controller's step `h` bounded by the caller's cap (a non-positive or
/// NaN cap means "no extra limit") and `max_step`, and stretched by ≤ 1 % (never beyond the
/// cap) rather than leave a sliver step before the limit. A step below `min_step` or the
/// resolution of `t` is [`OdeError::StepUnderflow`].
#[inline(always)]
fn adaptive_step_end<E>(
    h: &mut f64,
    cap: f64,
    max_step: f64,
    min_step: f64,
    t: f64,
    target_limit: f64,
) -> Result<f64, OdeError<E>> {
    let cap = if cap > 0.0 {
        cap.min(max_step)
    } else {
        max_step
    };
    *h = h.min(cap);
    if *h < min_step || *h <= 8.0 * f64::EPSILON * t.abs().max(f64::MIN_POSITIVE) {
        return Err(OdeError::StepUnderflow { t, h: *h });
    }
    let t_new = t + *h;
    if t_new >= target_limit || (target_limit - t_new < 0.01 * *h && target_limit - t <= cap) {
        Ok(target_limit)
    } else {
        Ok(t_new)
    }
}

/// The stage derivatives of one Dormand–Prince step (k1 carried over by FSAL) and its result.
struct Stages<const N: usize> {
    k1: [f64; N],
    k2: [f64; N],
    k3: [f64; N],
    k4: [f64; N],
    k5: [f64; N],
    k6: [f64; N],
    k7: [f64; N],
    ys: [f64; N],
    y_new: [f64; N],
}

impl<const N: usize> Stages<N> {
    fn new() -> Self {
        Stages {
            k1: [0.0; N],
            k2: [0.0; N],
            k3: [0.0; N],
            k4: [0.0; N],
            k5: [0.0; N],
            k6: [0.0; N],
            k7: [0.0; N],
            ys: [0.0; N],
            y_new: [0.0; N],
        }
    }

    /// One step of length `hs` from `(t, y)`: k2…k7 and `y_new`. In adaptive mode a
    /// non-finite stage or result is `Ok(Some(component))` (the step is rejected), otherwise
    /// an error.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn attempt<E, F>(
        &mut self,
        rhs: &mut F,
        stats: &mut OdeStats,
        t: f64,
        y: &[f64; N],
        hs: f64,
        t_right: f64,
        adaptive: bool,
    ) -> Result<Option<usize>, OdeError<E>>
    where
        F: FnMut(f64, &[f64; N], &mut [f64; N]) -> Result<(), E>,
    {
        macro_rules! stage {
            ($e:expr) => {
                match $e {
                    Ok(()) => {}
                    Err(OdeError::NonFinite { component, .. }) if adaptive => {
                        return Ok(Some(component))
                    }
                    Err(e) => return Err(e),
                }
            };
        }
        let Stages {
            k1,
            k2,
            k3,
            k4,
            k5,
            k6,
            k7,
            ys,
            y_new,
        } = self;
        for i in 0..N {
            ys[i] = y[i] + hs * A21 * k1[i];
        }
        stage!(evaluate(rhs, stats, t + C2 * hs, ys, k2));
        for i in 0..N {
            ys[i] = y[i] + hs * (A31 * k1[i] + A32 * k2[i]);
        }
        stage!(evaluate(rhs, stats, t + C3 * hs, ys, k3));
        for i in 0..N {
            ys[i] = y[i] + hs * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
        }
        stage!(evaluate(rhs, stats, t + C4 * hs, ys, k4));
        for i in 0..N {
            ys[i] = y[i] + hs * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
        }
        stage!(evaluate(rhs, stats, t + C5 * hs, ys, k5));
        for i in 0..N {
            ys[i] =
                y[i] + hs * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
        }
        stage!(evaluate(rhs, stats, t_right, ys, k6));
        for i in 0..N {
            y_new[i] = y[i] + hs * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i]);
        }
        if let Some(i) = first_non_finite(y_new) {
            stage!(Err(OdeError::NonFinite { t, component: i }));
        }
        stage!(evaluate(rhs, stats, t_right, y_new, k7));
        Ok(None)
    }

    /// The RMS of the embedded error estimate in units of the error scale.
    #[inline(always)]
    fn error_norm(&self, opts: &OdeOptions<N>, y: &[f64; N], hs: f64) -> f64 {
        let mut err = 0.0;
        for i in 0..N {
            let e = hs
                * (E1 * self.k1[i]
                    + E3 * self.k3[i]
                    + E4 * self.k4[i]
                    + E5 * self.k5[i]
                    + E6 * self.k6[i]
                    + E7 * self.k7[i]);
            err += (e / error_scale(opts, y, &self.y_new, i)).powi(2);
        }
        (err / N as f64).sqrt()
    }

    /// The order-4 continuous extension of the step `[t, t + hs]` just taken from `y`.
    fn dense(&self, t: f64, y: &[f64; N], hs: f64) -> Dense<N> {
        let mut dense = Dense {
            t,
            h: hs,
            r: [[0.0; N]; 5],
        };
        let (k1, k3, k4, k5, k6, k7) = (&self.k1, &self.k3, &self.k4, &self.k5, &self.k6, &self.k7);
        for i in 0..N {
            let ydiff = self.y_new[i] - y[i];
            let bspl = hs * k1[i] - ydiff;
            dense.r[0][i] = y[i];
            dense.r[1][i] = ydiff;
            dense.r[2][i] = bspl;
            dense.r[3][i] = ydiff - hs * k7[i] - bspl;
            dense.r[4][i] =
                hs * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
        }
        dense
    }
}

/// What the PI controller decides about a step.
enum Verdict {
    /// Keep the step; the controller's next step.
    Accept { h: f64 },
    /// Retry from the same state with this step.
    Reject { h: f64 },
}

/// The PI step-size controller (Hairer, Nørsett & Wanner §II.4; docs/integrator.md).
struct Controller {
    alpha: f64,
    beta: f64,
    safety: f64,
    min_factor: f64,
    max_factor: f64,
    /// Below this error the PI factor is ≤ 1 whatever err_prev (≥ 1e-4) is: the step cannot
    /// shrink, so at the max_step cap the controller has nothing to decide.
    err_cap: f64,
    err_prev: f64,
    last_rejected: bool,
}

impl Controller {
    fn new<const N: usize>(opts: &OdeOptions<N>) -> Self {
        let alpha = 0.2 - 0.75 * opts.beta;
        Controller {
            alpha,
            beta: opts.beta,
            safety: opts.safety,
            min_factor: opts.min_factor,
            max_factor: opts.max_factor,
            err_cap: (opts.safety * 1e-4f64.powf(opts.beta)).powf(1.0 / alpha),
            err_prev: 1e-4,
            last_rejected: false,
        }
    }

    /// The verdict on a step of length `hs` (the controller had asked for `h`) with error
    /// norm `err`; `at_limit`: the step was shortened to end on a stop time or `t_end`.
    #[inline(always)]
    fn judge(&mut self, err: f64, h: f64, hs: f64, max_step: f64, at_limit: bool) -> Verdict {
        if err <= self.err_cap && h >= max_step {
            // Capped by max_step and the controller would not shrink: skip the two powf
            // (exact: the new step would be clamped to max_step anyway).
            self.err_prev = err.max(1e-4);
            self.last_rejected = false;
            Verdict::Accept { h }
        } else if err <= 1.0 {
            let fac_i = err.powf(self.alpha);
            let mut fac = fac_i / self.err_prev.powf(self.beta) / self.safety;
            fac = fac.clamp(1.0 / self.max_factor, 1.0 / self.min_factor);
            let mut h_next = hs / fac;
            if self.last_rejected {
                h_next = h_next.min(hs);
            }
            // A step shortened to hit a limit does not shrink the controller's step.
            if at_limit && hs < h {
                h_next = h_next.max(h);
            }
            self.err_prev = err.max(1e-4);
            self.last_rejected = false;
            Verdict::Accept { h: h_next }
        } else {
            let fac = (err.powf(self.alpha) / self.safety).min(1.0 / self.min_factor);
            self.last_rejected = true;
            Verdict::Reject { h: hs / fac }
        }
    }
}

/// Where the observer is called, and how many calls are left of a uniform grid.
struct Samples {
    sampling: Sampling,
    t0: f64,
    t_end: f64,
    /// Last index of the uniform grid.
    n_out: u64,
    /// Index of the next uniform sample.
    next_out: u64,
}

impl Samples {
    fn new(sampling: Sampling, t0: f64, t_end: f64) -> Self {
        let n_out = match sampling {
            Sampling::Uniform { dt } => {
                ((t_end - t0) / dt * (1.0 + 4.0 * f64::EPSILON)).floor() as u64
            }
            _ => 0,
        };
        Samples {
            sampling,
            t0,
            t_end,
            n_out,
            next_out: 0,
        }
    }

    fn out_time(&self, k: u64) -> f64 {
        match self.sampling {
            Sampling::Uniform { dt } => (self.t0 + k as f64 * dt).min(self.t_end),
            _ => f64::NAN,
        }
    }

    /// The sample at `t0` (every mode but [`Sampling::None`]).
    fn first<const N: usize, O: FnMut(f64, &[f64; N])>(
        &mut self,
        t0: f64,
        y0: &[f64; N],
        observer: &mut O,
        stats: &mut OdeStats,
    ) {
        if !matches!(self.sampling, Sampling::None) {
            observer(t0, y0);
            stats.samples += 1;
            self.next_out = 1;
        }
    }

    /// The samples in `(t, t + hs]` of the accepted step `st` from `y`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn after_step<const N: usize, O: FnMut(f64, &[f64; N])>(
        &mut self,
        st: &Stages<N>,
        t: f64,
        y: &[f64; N],
        hs: f64,
        t_new: f64,
        observer: &mut O,
        stats: &mut OdeStats,
    ) {
        match self.sampling {
            Sampling::Uniform { .. } => {
                if self.next_out <= self.n_out && self.out_time(self.next_out) <= t_new {
                    let dense = st.dense(t, y, hs);
                    let mut buf = [0.0; N];
                    while self.next_out <= self.n_out {
                        let to = self.out_time(self.next_out);
                        if to > t_new {
                            break;
                        }
                        if to == t_new {
                            observer(to, &st.y_new);
                        } else {
                            dense.eval(to, &mut buf);
                            observer(to, &buf);
                        }
                        stats.samples += 1;
                        self.next_out += 1;
                    }
                }
            }
            Sampling::Steps => {
                observer(t_new, &st.y_new);
                stats.samples += 1;
            }
            Sampling::None => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;
    use std::f64::consts::PI;

    type R = Result<(), Infallible>;

    fn oscillator(w: f64) -> impl FnMut(f64, &[f64; 2], &mut [f64; 2]) -> R {
        move |_t, y, dy| {
            dy[0] = y[1];
            dy[1] = -w * w * y[0];
            Ok(())
        }
    }

    #[test]
    fn exponential_decay_matches_closed_form() {
        let lam = 3.0;
        let opts = OdeOptions::<1>::adaptive(1e-10, 1e-14);
        let mut worst: f64 = 0.0;
        let sol = integrate(
            |_t, y: &[f64; 1], dy: &mut [f64; 1]| -> R {
                dy[0] = -lam * y[0];
                Ok(())
            },
            0.0,
            [2.0],
            4.0,
            &opts,
            Sampling::Uniform { dt: 0.01 },
            |t, y| {
                let exact = 2.0 * (-lam * t).exp();
                worst = worst.max((y[0] - exact).abs() / exact);
            },
        )
        .unwrap();
        assert_eq!(sol.t, 4.0);
        assert_eq!(sol.stats.samples, 401);
        assert!(worst < 1e-8, "worst relative error {worst:e}");
        assert_eq!(
            sol.stats.rhs_evaluations,
            1 + 1 + 6 * (sol.stats.accepted_steps + sol.stats.rejected_steps)
        );
    }

    #[test]
    fn harmonic_oscillator_matches_closed_form() {
        let w = 2.0 * PI * 3.0;
        let opts = OdeOptions::<2>::adaptive_per_component(1e-10, [1e-13, 1e-13 * w]);
        let mut worst: f64 = 0.0;
        integrate(
            oscillator(w),
            0.0,
            [1.0, 0.0],
            2.0,
            &opts,
            Sampling::Steps,
            |t, y| {
                worst = worst
                    .max((y[0] - (w * t).cos()).abs())
                    .max((y[1] / w + (w * t).sin()).abs());
            },
        )
        .unwrap();
        assert!(worst < 1e-8, "worst error {worst:e}");
    }

    fn fixed_error(h: f64) -> f64 {
        let w = 1.0;
        let t_end = 2.0 * PI;
        let sol = integrate(
            oscillator(w),
            0.0,
            [1.0, 0.0],
            t_end,
            &OdeOptions::fixed(h),
            Sampling::None,
            |_, _| {},
        )
        .unwrap();
        (sol.y[0] - t_end.cos()).hypot(sol.y[1] + t_end.sin())
    }

    #[test]
    fn fixed_step_convergence_order_is_five() {
        let h = 2.0 * PI / 40.0;
        let (e1, e2, e3) = (fixed_error(h), fixed_error(h / 2.0), fixed_error(h / 4.0));
        let p1 = (e1 / e2).log2();
        let p2 = (e2 / e3).log2();
        eprintln!("fixed-step errors {e1:e} {e2:e} {e3:e}; order {p1:.3} {p2:.3}");
        for p in [p1, p2] {
            assert!((4.7..=5.3).contains(&p), "measured order {p}");
        }
    }

    #[test]
    fn fixed_step_counts_and_lands_on_t_end() {
        let sol = integrate(
            oscillator(1.0),
            0.0,
            [1.0, 0.0],
            1.05,
            &OdeOptions::fixed(0.1),
            Sampling::None,
            |_, _| {},
        )
        .unwrap();
        assert_eq!(sol.t, 1.05);
        assert_eq!(sol.stats.accepted_steps, 11);
        assert_eq!(sol.stats.rejected_steps, 0);
        assert_eq!(sol.stats.rhs_evaluations, 1 + 6 * 11);
        // FSAL: 6 new evaluations per step, plus the start's.
        assert_eq!(sol.stats.rhs_per_accepted_step(), 67.0 / 11.0);
        assert_eq!(sol.stats.micros_per_accepted_step(0.022), 2000.0);
        assert!(OdeStats::default().micros_per_accepted_step(1.0).is_nan());
    }

    #[test]
    fn adaptive_error_decreases_with_tolerance() {
        let w = 2.0 * PI;
        let mut prev = f64::INFINITY;
        let mut prev_steps = 0;
        for k in [4, 6, 8, 10, 12] {
            let rtol = 10f64.powi(-k);
            let opts =
                OdeOptions::<2>::adaptive_per_component(rtol, [rtol * 1e-3, rtol * 1e-3 * w]);
            let sol = integrate(
                oscillator(w),
                0.0,
                [1.0, 0.0],
                5.0,
                &opts,
                Sampling::None,
                |_, _| {},
            )
            .unwrap();
            let err = (sol.y[0] - (w * 5.0).cos()).abs();
            eprintln!(
                "rtol {rtol:e}: error {err:e}, steps {}",
                sol.stats.accepted_steps
            );
            assert!(err < prev, "error {err:e} did not decrease (prev {prev:e})");
            assert!(err < 1e3 * rtol, "error {err:e} far above rtol {rtol:e}");
            assert!(sol.stats.accepted_steps > prev_steps);
            prev = err;
            prev_steps = sol.stats.accepted_steps;
        }
    }

    /// A mass falling under gravity onto a one-sided linear spring (contact switching on/off):
    /// the elastic bounce is periodic; apex height and time are known in closed form.
    #[test]
    fn discontinuous_contact_spring_with_max_step() {
        let (g, height, w): (f64, f64, f64) = (1.0, 1.0, 100.0);
        let k = w * w;
        let v0 = (2.0 * g * height).sqrt();
        let phi = (v0 / w).atan2(g / k);
        let t_contact = (2.0 * PI - 2.0 * phi) / w;
        let period = 2.0 * (2.0 * height / g).sqrt() + t_contact;
        let rhs = |_t: f64, y: &[f64; 2], dy: &mut [f64; 2]| -> R {
            dy[0] = y[1];
            dy[1] = -g - if y[0] < 0.0 { k * y[0] } else { 0.0 };
            Ok(())
        };
        let n_bounces = 5.0;
        let opts = OdeOptions::<2>::adaptive(1e-10, 1e-12).with_max_step(t_contact / 50.0);
        let sol = integrate(
            rhs,
            0.0,
            [height, 0.0],
            n_bounces * period,
            &opts,
            Sampling::None,
            |_, _| {},
        )
        .unwrap();
        let (dx, dv) = (sol.y[0] - height, sol.y[1]);
        eprintln!(
            "bounce: apex error {dx:e}, velocity {dv:e}, steps {} (+{} rejected)",
            sol.stats.accepted_steps, sol.stats.rejected_steps
        );
        assert!(dx.abs() < 1e-6 && dv.abs() < 1e-5, "{dx:e} {dv:e}");
    }

    /// The same bounce with the step limited only near and in contact (a state-dependent
    /// cap): as accurate as the global cap with fewer steps.
    #[test]
    fn state_dependent_cap_resolves_contact_with_fewer_steps() {
        let (g, height, w): (f64, f64, f64) = (1.0, 1.0, 100.0);
        let k = w * w;
        let v0 = (2.0 * g * height).sqrt();
        let phi = (v0 / w).atan2(g / k);
        let t_contact = (2.0 * PI - 2.0 * phi) / w;
        let period = 2.0 * (2.0 * height / g).sqrt() + t_contact;
        let rhs = |_t: f64, y: &[f64; 2], dy: &mut [f64; 2]| -> R {
            dy[0] = y[1];
            dy[1] = -g - if y[0] < 0.0 { k * y[0] } else { 0.0 };
            Ok(())
        };
        let h_contact = t_contact / 50.0;
        // In contact: h_contact. Approaching: at most half the time to reach the surface.
        let cap = |_t: f64, y: &[f64; 2]| {
            if y[0] <= 0.0 {
                h_contact
            } else if y[1] < 0.0 {
                (0.5 * y[0] / -y[1]).max(h_contact)
            } else {
                f64::INFINITY
            }
        };
        let opts = OdeOptions::<2>::adaptive(1e-10, 1e-12);
        let run = |capped: bool| {
            let c = move |t: f64, y: &[f64; 2]| if capped { cap(t, y) } else { h_contact };
            integrate_capped(
                rhs,
                c,
                0.0,
                [height, 0.0],
                5.0 * period,
                &opts,
                Sampling::None,
                |_, _| {},
            )
            .unwrap()
        };
        let (local, global) = (run(true), run(false));
        let dx = local.y[0] - height;
        assert!(dx.abs() < 1e-6 && local.y[1].abs() < 1e-5, "{dx:e}");
        assert!(
            local.stats.accepted_steps * 3 < global.stats.accepted_steps,
            "{} vs {}",
            local.stats.accepted_steps,
            global.stats.accepted_steps
        );
    }

    #[test]
    fn stop_times_resolve_a_known_discontinuity() {
        // y' = 1 for t < 0.3, 0 after: y(1) = 0.3 exactly when a step ends at 0.3.
        let opts = OdeOptions::<1>::adaptive(1e-12, 1e-14).with_stop_times(vec![0.3, 7.0]);
        let sol = integrate(
            |t: f64, _y: &[f64; 1], dy: &mut [f64; 1]| -> R {
                dy[0] = if t < 0.3 { 1.0 } else { 0.0 };
                Ok(())
            },
            0.0,
            [0.0],
            1.0,
            &opts,
            Sampling::None,
            |_, _| {},
        )
        .unwrap();
        assert!((sol.y[0] - 0.3).abs() < 1e-14, "{:e}", sol.y[0] - 0.3);
    }

    #[test]
    fn undamped_oscillator_creates_no_energy() {
        let w = 2.0 * PI * 200e3; // slider-like frequency
        let periods = 1000.0;
        let rtol = 1e-9;
        let opts = OdeOptions::<2>::adaptive_per_component(rtol, [1e-20, 1e-20 * w]);
        let energy = |y: &[f64; 2]| 0.5 * (y[1] * y[1] + w * w * y[0] * y[0]);
        let y0 = [1e-9, 0.0];
        let e0 = energy(&y0);
        let mut worst_gain: f64 = 0.0;
        let sol = integrate(
            oscillator(w),
            0.0,
            y0,
            periods * 2.0 * PI / w,
            &opts,
            Sampling::Steps,
            |_, y| worst_gain = worst_gain.max(energy(y) / e0 - 1.0),
        )
        .unwrap();
        let drift = energy(&sol.y) / e0 - 1.0;
        eprintln!("energy: worst gain {worst_gain:e}, final drift {drift:e}");
        assert!(worst_gain < 10.0 * rtol, "energy created: {worst_gain:e}");
        assert!(drift.abs() < 1e-5, "energy drift {drift:e}");
    }

    #[test]
    fn dense_output_matches_closed_form_between_steps() {
        let w = 1.0;
        let opts = OdeOptions::<2>::adaptive(1e-9, 1e-12);
        let mut worst: f64 = 0.0;
        let mut times = Vec::new();
        let sol = integrate(
            oscillator(w),
            0.0,
            [1.0, 0.0],
            10.0,
            &opts,
            Sampling::Uniform { dt: 0.01 },
            |t, y| {
                times.push(t);
                worst = worst.max((y[0] - (w * t).cos()).abs());
            },
        )
        .unwrap();
        assert_eq!(times.len(), 1001);
        assert!(
            sol.stats.accepted_steps * 2 < 1001,
            "samples must be interpolated"
        );
        for (k, t) in times.iter().enumerate() {
            assert_eq!(*t, (k as f64 * 0.01).min(10.0));
        }
        eprintln!(
            "dense output worst error {worst:e}, {} steps",
            sol.stats.accepted_steps
        );
        assert!(worst < 1e-7, "dense output error {worst:e}");
    }

    #[derive(Debug, thiserror::Error, PartialEq)]
    #[error("model left its table")]
    struct ModelError;

    #[test]
    fn error_cases() {
        let blowup = |_t: f64, y: &[f64; 1], dy: &mut [f64; 1]| -> R {
            dy[0] = y[0] * y[0];
            Ok(())
        };
        // y' = y², y(0) = 1 blows up at t = 1.
        let opts = OdeOptions::<1>::adaptive(1e-8, 1e-8).with_min_step(1e-10);
        match integrate(blowup, 0.0, [1.0], 2.0, &opts, Sampling::None, |_, _| {}) {
            Err(OdeError::StepUnderflow { t, .. }) => assert!((t - 1.0).abs() < 1e-3, "t = {t}"),
            other => panic!("expected underflow, got {other:?}"),
        }
        // Fixed step straight through the singularity: overflow → NonFinite, never a NaN result.
        match integrate(
            blowup,
            0.0,
            [1.0],
            2.0,
            &OdeOptions::fixed(0.05),
            Sampling::None,
            |_, _| {},
        ) {
            Err(OdeError::NonFinite { t, component }) => {
                assert_eq!(component, 0);
                assert!(t > 0.9 && t < 2.0, "t = {t}");
            }
            other => panic!("expected non-finite, got {other:?}"),
        }
        // A NaN derivative in the second component.
        let nan = |t: f64, _y: &[f64; 2], dy: &mut [f64; 2]| -> R {
            dy[0] = 1.0;
            dy[1] = if t > 0.5 { f64::NAN } else { 0.0 };
            Ok(())
        };
        match integrate(
            nan,
            0.0,
            [0.0; 2],
            1.0,
            &OdeOptions::fixed(0.1),
            Sampling::None,
            |_, _| {},
        ) {
            Err(OdeError::NonFinite { component: 1, t }) => assert!(t > 0.4 && t <= 0.6),
            other => panic!("expected non-finite, got {other:?}"),
        }
        // Max steps.
        let mut opts = OdeOptions::<2>::adaptive(1e-10, 1e-10);
        opts.max_steps = 10;
        match integrate(
            oscillator(1.0),
            0.0,
            [1.0, 0.0],
            100.0,
            &opts,
            Sampling::None,
            |_, _| {},
        ) {
            Err(OdeError::MaxStepsExceeded { steps: 10, t }) => assert!(t > 0.0 && t < 100.0),
            other => panic!("expected max steps, got {other:?}"),
        }
        // The right-hand side's own error aborts cleanly with its time.
        let failing = |t: f64, y: &[f64; 1], dy: &mut [f64; 1]| -> Result<(), ModelError> {
            if t > 0.25 {
                return Err(ModelError);
            }
            dy[0] = -y[0];
            Ok(())
        };
        let opts = OdeOptions::<1>::adaptive(1e-8, 1e-10);
        match integrate(failing, 0.0, [1.0], 1.0, &opts, Sampling::None, |_, _| {}) {
            Err(OdeError::Rhs { t, source }) => {
                assert!(t > 0.25 && t < 1.0);
                assert_eq!(source, ModelError);
            }
            other => panic!("expected rhs error, got {other:?}"),
        }
        // Invalid input.
        for opts in [
            OdeOptions::<1>::adaptive(-1.0, 1e-8),
            OdeOptions::<1>::adaptive(0.0, 0.0),
            OdeOptions::<1>::fixed(0.0),
            OdeOptions::<1>::adaptive(1e-6, 1e-6).with_max_step(0.0),
        ] {
            let r = integrate(
                |_t, _y: &[f64; 1], dy: &mut [f64; 1]| -> R {
                    dy[0] = 0.0;
                    Ok(())
                },
                0.0,
                [0.0],
                1.0,
                &opts,
                Sampling::None,
                |_, _| {},
            );
            assert!(matches!(r, Err(OdeError::InvalidInput(_))), "{r:?}");
        }
        let r = integrate(
            oscillator(1.0),
            0.0,
            [f64::NAN, 0.0],
            1.0,
            &OdeOptions::adaptive(1e-6, 1e-6),
            Sampling::None,
            |_, _| {},
        );
        assert!(matches!(r, Err(OdeError::NonFinite { component: 0, .. })));
    }
}
