//! Once-per-revolution trigger detection (docs/dmw.md, "Segment") and segmentation from
//! the spindle speed when there is no index channel.
//!
//! Real tachometers give narrow pulses (10 µs at 5 425 rpm is a 0.09 % duty cycle), either
//! polarity, bouncing contacts, and the occasional missing or extra pulse. The detector:
//! 1. takes the channel's two levels from its robust extremes (the 3rd smallest and 3rd
//!    largest sample: a pulse of one sample per revolution still counts, a glitch of one or
//!    two samples does not), and the threshold at their midpoint;
//! 2. decides the polarity from the time spent on either side (the pulse is the rare state);
//! 3. fires on a Schmitt trigger (two levels, ±20 % of the range around the threshold) and
//!    locates the edge at the threshold between samples;
//! 4. drops re-fires within a tenth of a pulse period (contact bounce);
//! 5. places the pulses on the grid of the median pulse period: a gap of ~m periods means
//!    m − 1 missing pulses (the revolutions that span it are dropped), a pulse off the grid
//!    is an extra one (reported and ignored);
//! 6. groups `pulses_per_revolution` pulses into a revolution.

use super::DmwError;

/// Which edge of the index channel starts a revolution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Polarity {
    /// Active-high pulse: its rising edge.
    Rising,
    /// Active-low pulse: its falling edge.
    Falling,
    /// The pulse is the state the channel spends less time in.
    Auto,
}

impl std::str::FromStr for Polarity {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "rising" => Ok(Polarity::Rising),
            "falling" => Ok(Polarity::Falling),
            "auto" => Ok(Polarity::Auto),
            _ => Err(format!(
                "unknown trigger polarity `{s}` (expected \"rising\", \"falling\" or \"auto\")"
            )),
        }
    }
}

impl std::fmt::Display for Polarity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Polarity::Rising => "rising",
            Polarity::Falling => "falling",
            Polarity::Auto => "auto",
        })
    }
}

/// Trigger detection settings.
#[derive(Debug, Clone, Copy)]
pub struct TriggerOptions {
    /// Threshold in the index channel's unit; `None` = midpoint of its robust extremes.
    pub level: Option<f64>,
    pub polarity: Polarity,
    /// Edges closer than this fraction of the pulse period to the previous one are
    /// contact bounce and dropped.
    pub debounce_fraction: f64,
    /// Index pulses per revolution (evenly spaced); a revolution starts at every
    /// `pulses_per_revolution`-th pulse from the first one found.
    pub pulses_per_revolution: usize,
}

impl Default for TriggerOptions {
    fn default() -> Self {
        TriggerOptions {
            level: None,
            polarity: Polarity::Auto,
            debounce_fraction: 0.1,
            pulses_per_revolution: 1,
        }
    }
}

/// A pulse that should have been there (from the period grid) but was not.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MissingPulse {
    /// Expected time of the missing pulse, s.
    pub time: f64,
    /// Length of the gap it sits in, in pulse periods.
    pub gap_periods: f64,
}

/// Detected revolutions.
#[derive(Debug, Clone)]
pub struct Triggers {
    /// Start times of the usable revolutions (sub-sample, seconds from sample 0).
    pub times: Vec<f64>,
    /// Each usable revolution's period (`None`: its end lies beyond the record).
    pub revolution_periods: Vec<Option<f64>>,
    /// All accepted pulses (after debounce and extra-pulse removal), s.
    pub pulses: Vec<f64>,
    /// The threshold used (NaN for speed segmentation).
    pub level: f64,
    /// The edge used (`Rising` or `Falling`; `Auto` for speed segmentation).
    pub polarity: Polarity,
    /// Fraction of the time the channel spends in the pulse state.
    pub duty_cycle: f64,
    /// Edges dropped by the debounce.
    pub n_debounced: usize,
    /// Pulses the period grid expected but the channel did not show.
    pub missing: Vec<MissingPulse>,
    /// Pulses off the period grid (ignored), s.
    pub extra: Vec<f64>,
    /// Revolutions dropped because a missing pulse falls inside them (or at their start).
    pub n_gap_dropped: usize,
}

impl Triggers {
    /// Periods of the usable revolutions that have one.
    pub fn periods(&self) -> Vec<f64> {
        self.revolution_periods.iter().flatten().copied().collect()
    }
}

/// Quantile by linear interpolation between order statistics (numpy's default), on a strided
/// subsample of at most ~2^17 values (selection, O(n)).
pub fn quantile(x: &[f64], q: f64) -> f64 {
    let stride = (x.len() >> 17).max(1);
    let mut v: Vec<f64> = x.iter().step_by(stride).copied().collect();
    if v.is_empty() {
        return f64::NAN;
    }
    let pos = q.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let (_, &mut a, upper) = v.select_nth_unstable_by(lo, f64::total_cmp);
    // The next order statistic is the smallest of the upper part.
    let b = if pos > lo as f64 {
        upper.iter().copied().fold(f64::INFINITY, f64::min)
    } else {
        a
    };
    a + (b - a) * (pos - lo as f64)
}

/// Order of the extreme used as a level: the `ROBUST_K`-th smallest and largest finite sample.
/// A pulse one sample wide recurs every revolution, so it passes once the record holds three
/// pulses; an isolated glitch of one or two samples does not move the level.
const ROBUST_K: usize = 3;
/// Half-width of the Schmitt trigger's hysteresis band, as a fraction of the level range.
const HYSTERESIS: f64 = 0.2;
/// A gap within this many pulse periods of an integer multiple is on the grid.
const GRID_TOLERANCE: f64 = 0.15;

/// The `k`-th smallest and `k`-th largest finite values (one pass; `k` ≥ 1), or the extremes
/// of a shorter record.
fn robust_extremes(x: &[f64], k: usize) -> Option<(f64, f64)> {
    let mut low: Vec<f64> = Vec::with_capacity(k + 1);
    let mut high: Vec<f64> = Vec::with_capacity(k + 1);
    for &v in x.iter().filter(|v| v.is_finite()) {
        if low.len() < k || v < low[low.len() - 1] {
            let at = low.partition_point(|&a| a <= v);
            low.insert(at, v);
            low.truncate(k);
        }
        if high.len() < k || v > high[high.len() - 1] {
            let at = high.partition_point(|&a| a >= v);
            high.insert(at, v);
            high.truncate(k);
        }
    }
    Some((*low.last()?, *high.last()?))
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// What the channel looked like, for the error when no trigger is found.
fn no_trigger_error(
    lo: f64,
    hi: f64,
    level: f64,
    n_edges: usize,
    duty: f64,
    why: &str,
) -> DmwError {
    DmwError::Processing(format!(
        "{why}: the index channel's levels are {lo:.6} … {hi:.6} (robust min … max), \
         {n_edges} edge(s) through the threshold {level:.6}, pulse state {:.4} % of the time; \
         set `trigger_level` (a value between the two levels), `trigger_polarity` \
         (\"rising\" for an active-high pulse, \"falling\" for an active-low one), or give the \
         spindle speed `rpm` and no index channel",
        100.0 * duty
    ))
}

/// Triggers from the index channel `index` sampled at `fs`. `nominal_period` is the
/// revolution period from `rpm`, if known (it sets the debounce before any period is
/// measured).
pub fn detect_triggers(
    index: &[f64],
    fs: f64,
    nominal_period: Option<f64>,
    opts: &TriggerOptions,
) -> Result<Triggers, DmwError> {
    let ppr = opts.pulses_per_revolution.max(1);
    let Some((lo, hi)) = robust_extremes(index, ROBUST_K) else {
        return Err(DmwError::Processing(
            "the index channel has no finite sample".into(),
        ));
    };
    let level = match opts.level {
        Some(l) => l,
        None => {
            if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
                return Err(no_trigger_error(
                    lo,
                    hi,
                    0.5 * (lo + hi),
                    0,
                    0.0,
                    "the index channel is flat: no once-per-revolution pulses",
                ));
            }
            0.5 * (lo + hi)
        }
    };
    let n_finite = index.iter().filter(|v| v.is_finite()).count().max(1);
    let above = index.iter().filter(|&&v| v > level).count() as f64 / n_finite as f64;
    let polarity = match opts.polarity {
        Polarity::Auto if above > 0.5 => Polarity::Falling,
        Polarity::Auto => Polarity::Rising,
        p => p,
    };
    let duty = if polarity == Polarity::Rising {
        above
    } else {
        1.0 - above
    };
    // Work on the pulse-up view of the channel: a falling edge of x is a rising edge of −x.
    let sign = if polarity == Polarity::Rising {
        1.0
    } else {
        -1.0
    };
    let (l, b, t) = (sign * level, sign * lo, sign * hi);
    let (base, top) = (b.min(t), b.max(t));
    let band = HYSTERESIS * (top - base);
    let upper = (l + band).min(l + 0.5 * (top - l).max(0.0));
    let lower = (l - band).max(l - 0.5 * (l - base).max(0.0));
    let y = |i: usize| sign * index[i];

    // Schmitt trigger: armed below `lower`, fires at `upper`; the edge is located where it
    // crosses the threshold, between the last sample below and the next one.
    let mut edges: Vec<f64> = Vec::new();
    let mut armed_at: Option<usize> = None;
    for i in 0..index.len() {
        let v = y(i);
        if !v.is_finite() {
            continue;
        }
        match armed_at {
            None => {
                if v < lower || (i == 0 && v < l) {
                    armed_at = Some(i);
                }
            }
            Some(a) => {
                if v >= upper && v >= l {
                    let mut j = i - 1;
                    while j > a && y(j).partial_cmp(&l) != Some(std::cmp::Ordering::Less) {
                        j -= 1;
                    }
                    let (ya, yb) = (y(j), y(j + 1));
                    let frac = if yb != ya { (l - ya) / (yb - ya) } else { 0.0 };
                    edges.push((j as f64 + frac.clamp(0.0, 1.0)) / fs);
                    armed_at = None;
                }
            }
        }
    }
    let n_edges = edges.len();
    if edges.is_empty() {
        return Err(no_trigger_error(
            lo,
            hi,
            level,
            0,
            duty,
            "no once-per-revolution pulse found",
        ));
    }

    // Debounce against the nominal pulse period, or without one against the upper-quartile
    // gap, which is a true pulse period even when every edge bounces (then half the gaps are
    // bounces).
    let typical = nominal_period.map(|p| p / ppr as f64).or_else(|| {
        (edges.len() >= 3).then(|| {
            let mut gaps: Vec<f64> = edges.windows(2).map(|w| w[1] - w[0]).collect();
            gaps.sort_by(f64::total_cmp);
            gaps[(3 * gaps.len()) / 4]
        })
    });
    let mut n_debounced = 0;
    let mut pulses: Vec<f64> = Vec::with_capacity(edges.len());
    for t in edges {
        match (pulses.last(), typical) {
            (Some(&p), Some(g)) if t - p < opts.debounce_fraction * g => n_debounced += 1,
            _ => pulses.push(t),
        }
    }

    let (grid, extra) = place_on_grid(&pulses);
    let missing = missing_pulses(&grid);
    let accepted: Vec<(f64, i64)> = grid;
    let (times, revolution_periods, n_gap_dropped) = group_revolutions(&accepted, ppr);
    if times.is_empty() {
        return Err(no_trigger_error(
            lo,
            hi,
            level,
            n_edges,
            duty,
            "no complete revolution between the index pulses found",
        ));
    }
    Ok(Triggers {
        times,
        revolution_periods,
        pulses: accepted.iter().map(|&(t, _)| t).collect(),
        level,
        polarity,
        duty_cycle: duty,
        n_debounced,
        missing,
        extra,
        n_gap_dropped,
    })
}

/// Each pulse's position on the grid of the median pulse period `(time, grid index)`, and the
/// pulses off the grid (extra). The grid follows a slowly wandering speed: the local period is
/// the median of the last gaps per period. Anchored at the first pulse whose next gap is one
/// period, and walked both ways from there, so an extra pulse before the first true one does
/// not shift the grid.
fn place_on_grid(pulses: &[f64]) -> (Vec<(f64, i64)>, Vec<f64>) {
    if pulses.len() < 3 {
        return (
            pulses
                .iter()
                .enumerate()
                .map(|(k, &t)| (t, k as i64))
                .collect(),
            Vec::new(),
        );
    }
    let gaps: Vec<f64> = pulses.windows(2).map(|w| w[1] - w[0]).collect();
    let p0 = median(&gaps);
    let on_grid = |g: f64, p: f64| -> Option<i64> {
        let m = (g / p).round();
        (m >= 1.0 && (g - m * p).abs() <= GRID_TOLERANCE * p).then_some(m as i64)
    };
    let anchor = gaps
        .iter()
        .position(|&g| on_grid(g, p0) == Some(1))
        .unwrap_or(0);
    let mut accepted = vec![(pulses[anchor], 0i64)];
    let mut extra = Vec::new();
    let walk = |range: &mut dyn Iterator<Item = usize>,
                dir: f64,
                accepted: &mut Vec<(f64, i64)>,
                extra: &mut Vec<f64>| {
        let mut recent: Vec<f64> = vec![p0];
        let (mut last_t, mut last_k) = (pulses[anchor], 0i64);
        for j in range {
            let t = pulses[j];
            let p = median(&recent);
            match on_grid(dir * (t - last_t), p) {
                Some(m) => {
                    last_k += dir as i64 * m;
                    recent.push(dir * (t - last_t) / m as f64);
                    if recent.len() > 9 {
                        recent.remove(0);
                    }
                    last_t = t;
                    accepted.push((t, last_k));
                }
                None => extra.push(t),
            }
        }
    };
    walk(
        &mut (anchor + 1..pulses.len()),
        1.0,
        &mut accepted,
        &mut extra,
    );
    walk(&mut (0..anchor).rev(), -1.0, &mut accepted, &mut extra);
    accepted.sort_by_key(|a| a.1);
    extra.sort_by(f64::total_cmp);
    (accepted, extra)
}

/// Where the grid has holes between accepted pulses: one entry per missing pulse, at its
/// expected time (linear between the neighbours).
fn missing_pulses(grid: &[(f64, i64)]) -> Vec<MissingPulse> {
    let mut out = Vec::new();
    for w in grid.windows(2) {
        let ((ta, ka), (tb, kb)) = (w[0], w[1]);
        let m = kb - ka;
        for j in 1..m {
            out.push(MissingPulse {
                time: ta + (tb - ta) * j as f64 / m as f64,
                gap_periods: m as f64,
            });
        }
    }
    out
}

/// Revolution starts from pulses on the grid: revolution r runs from grid index `r·ppr` to
/// `(r+1)·ppr`; it is usable if all its pulses are there (the last one may lie beyond the
/// record: period `None`). Returns starts, periods and the number of revolutions lost to
/// missing pulses.
fn group_revolutions(grid: &[(f64, i64)], ppr: usize) -> (Vec<f64>, Vec<Option<f64>>, usize) {
    let Some((&(_, k0), &(_, k_last))) = grid.first().zip(grid.last()) else {
        return (Vec::new(), Vec::new(), 0);
    };
    let ppr = ppr as i64;
    let at = |k: i64| -> Option<f64> {
        grid.binary_search_by(|&(_, kk)| kk.cmp(&k))
            .ok()
            .map(|i| grid[i].0)
    };
    let (mut starts, mut periods, mut lost) = (Vec::new(), Vec::new(), 0);
    let mut r0 = k0;
    while r0 <= k_last {
        let r1 = r0 + ppr;
        let complete = (r0..=r1.min(k_last)).all(|k| at(k).is_some());
        match (complete, at(r0)) {
            (true, Some(t0)) => {
                starts.push(t0);
                periods.push(at(r1).map(|t1| t1 - t0));
            }
            _ => lost += 1,
        }
        r0 = r1;
    }
    (starts, periods, lost)
}

/// Segment starts from the spindle speed alone (no index channel): `t_k = k·60/rpm`.
/// Averaging then only works if the record's speed is exactly `rpm`; the QA says so.
pub fn triggers_from_speed(n_samples: usize, fs: f64, rpm: f64) -> Triggers {
    let period = 60.0 / rpm;
    let duration = n_samples as f64 / fs;
    let n = (duration / period).floor() as usize + 1;
    let times: Vec<f64> = (0..n)
        .map(|k| k as f64 * period)
        .filter(|&t| t < duration)
        .collect();
    let revolution_periods = (0..times.len())
        .map(|k| (k + 1 < times.len()).then_some(period))
        .collect();
    Triggers {
        pulses: times.clone(),
        times,
        revolution_periods,
        level: f64::NAN,
        polarity: Polarity::Auto,
        duty_cycle: f64::NAN,
        n_debounced: 0,
        missing: Vec::new(),
        extra: Vec::new(),
        n_gap_dropped: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pulse_train(fs: f64, period: f64, n_rev: usize, width: f64, offset: f64) -> Vec<f64> {
        let n = (((n_rev as f64 - 0.5) * period + offset) * fs) as usize;
        (0..n)
            .map(|i| {
                let t = i as f64 / fs - offset;
                if t < 0.0 {
                    return 0.0;
                }
                let ph = t.rem_euclid(period);
                if ph < width {
                    5.0
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Samples `[s, s + width)` of each pulse in `starts` (sample numbers) at `high`.
    fn pulses_at(n: usize, starts: &[usize], width: usize, base: f64, high: f64) -> Vec<f64> {
        let mut x = vec![base; n];
        for &s in starts {
            for v in x.iter_mut().skip(s).take(width) {
                *v = high;
            }
        }
        x
    }

    #[test]
    fn ttl_pulses_give_one_trigger_per_revolution_within_half_a_sample() {
        let fs = 4e6;
        let period = 60.0 / 5425.0;
        let offset = 1.234e-5;
        let x = pulse_train(fs, period, 20, 20e-6, offset);
        let tr = detect_triggers(&x, fs, Some(period), &TriggerOptions::default()).unwrap();
        assert_eq!(tr.times.len(), 20);
        for (k, t) in tr.times.iter().enumerate() {
            let truth = offset + k as f64 * period;
            assert!((t - truth).abs() <= 0.5 / fs + 1e-12, "{k}: {t} vs {truth}");
        }
        assert_eq!(tr.level, 2.5);
        assert_eq!(tr.polarity, Polarity::Rising);
        assert!(tr.missing.is_empty() && tr.extra.is_empty());
    }

    #[test]
    fn one_sample_pulses_at_a_tiny_duty_cycle_are_found() {
        // 10 µs at 5 425 rpm sampled at 100 kS/s: one sample per 1 106-sample revolution
        // (0.09 %), which the old 0.1 %/99.9 % quantile level saw as a flat channel.
        let p = 1106;
        let starts: Vec<usize> = (0..12).map(|k| 500 + k * p).collect();
        let x = pulses_at(500 + 12 * p, &starts, 1, 0.0, 5.0);
        assert_eq!(quantile(&x, 0.999), 0.0);
        let tr = detect_triggers(&x, 1e5, None, &TriggerOptions::default()).unwrap();
        assert_eq!(tr.times.len(), 12);
        for (t, s) in tr.times.iter().zip(&starts) {
            // The edge is between the last low sample and the pulse sample.
            assert!((t * 1e5 - (*s as f64 - 0.5)).abs() < 1e-9, "{t} vs {s}");
        }
        assert!((tr.duty_cycle - 12.0 / x.len() as f64).abs() < 1e-12);
        assert_eq!(tr.n_debounced, 0);
    }

    #[test]
    fn a_single_glitch_does_not_set_the_level() {
        let p = 1000;
        let starts: Vec<usize> = (0..8).map(|k| 100 + k * p).collect();
        let mut x = pulses_at(100 + 8 * p, &starts, 20, 0.0, 5.0);
        x[4321] = 80.0; // one spike far above the TTL level
        let tr = detect_triggers(&x, 1.0, None, &TriggerOptions::default()).unwrap();
        assert_eq!(tr.level, 2.5);
        assert_eq!(tr.times.len(), 8);
        // The spike itself is an extra pulse off the grid, reported at its edge: 2.5 V is
        // crossed 2.5/80 of the way from sample 4320 to the spike.
        assert_eq!(tr.extra, vec![4320.0 + 2.5 / 80.0]);
    }

    #[test]
    fn active_low_pulses_trigger_on_their_falling_edge() {
        let p = 2000;
        let starts: Vec<usize> = (0..6).map(|k| 300 + k * p).collect();
        let x = pulses_at(300 + 6 * p, &starts, 15, 5.0, 0.0);
        let auto = detect_triggers(&x, 1.0, None, &TriggerOptions::default()).unwrap();
        assert_eq!(auto.polarity, Polarity::Falling);
        assert_eq!(auto.times.len(), 6);
        for (t, s) in auto.times.iter().zip(&starts) {
            assert!((t - (*s as f64 - 0.5)).abs() < 1e-12);
        }
        assert!((auto.duty_cycle - 90.0 / x.len() as f64).abs() < 1e-12);
        // Forcing "rising" uses the end of each low pulse instead.
        let rising = detect_triggers(
            &x,
            1.0,
            None,
            &TriggerOptions {
                polarity: Polarity::Rising,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(rising.polarity, Polarity::Rising);
        for (t, s) in rising.times.iter().zip(&starts) {
            assert!((t - (*s as f64 + 14.5)).abs() < 1e-12);
        }
        assert_eq!(
            "falling".parse::<Polarity>().unwrap(),
            Polarity::Falling,
            "key spelling"
        );
        assert!("up".parse::<Polarity>().is_err());
    }

    #[test]
    fn noise_on_a_slow_edge_fires_once_per_pulse() {
        // 60-sample linear edges with noise of 0.1 V: without hysteresis the threshold is
        // crossed several times per edge.
        let mut rng = crate::numerics::rng::Rng::new(3);
        let p = 3000;
        let n = 10 * p;
        let x: Vec<f64> = (0..n)
            .map(|i| {
                let ph = (i % p) as f64;
                let clean = if ph < 60.0 {
                    5.0 * ph / 60.0
                } else if ph < 300.0 {
                    5.0
                } else if ph < 360.0 {
                    5.0 * (360.0 - ph) / 60.0
                } else {
                    0.0
                };
                clean + 0.1 * rng.normal()
            })
            .collect();
        let plain_crossings = x.windows(2).filter(|w| w[0] < 2.5 && w[1] >= 2.5).count();
        assert!(plain_crossings > 10, "{plain_crossings}");
        let tr = detect_triggers(&x, 1.0, None, &TriggerOptions::default()).unwrap();
        assert_eq!(tr.n_debounced, 0);
        assert_eq!(tr.pulses.len(), 10);
        for (k, t) in tr.pulses.iter().enumerate() {
            // Crossing of 2.5 V at 30 samples into the edge, give or take the noise
            // (0.1 V on a 5/60 V-per-sample slope: ~1.2 samples σ).
            let truth = (k * p) as f64 + 30.0;
            assert!((t - truth).abs() < 6.0, "{k}: {t}");
        }
    }

    #[test]
    fn sloped_edge_is_located_between_samples() {
        // Linear edge from 0 to 1 across samples 10..12: crossing at 0.5 → sample 11.
        let mut x = vec![0.0; 30];
        x[11] = 0.5;
        for v in x.iter_mut().skip(12).take(5) {
            *v = 1.0;
        }
        let tr = detect_triggers(
            &x,
            1.0,
            None,
            &TriggerOptions {
                level: Some(0.25),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(tr.times, vec![10.5]);
    }

    #[test]
    fn bouncing_edges_are_debounced() {
        let fs = 1e5;
        let period = 0.01;
        let mut x = pulse_train(fs, period, 5, 1e-3, 1e-3);
        // A glitch 30 samples after each edge.
        for k in 0..5 {
            let i = ((k as f64 * period + 1e-3) * fs) as usize + 30;
            x[i] = 0.0;
        }
        let tr = detect_triggers(&x, fs, None, &TriggerOptions::default()).unwrap();
        assert_eq!(tr.times.len(), 5);
        assert_eq!(tr.n_debounced, 5);
        assert!(tr.extra.is_empty());
    }

    #[test]
    fn a_missing_pulse_is_reported_and_its_revolutions_dropped() {
        let p = 1000usize;
        // Pulse 5 of 0..12 is missing.
        let starts: Vec<usize> = (0..12).filter(|&k| k != 5).map(|k| 200 + k * p).collect();
        let x = pulses_at(200 + 12 * p, &starts, 10, 0.0, 5.0);
        let fs = 1e4;
        let tr = detect_triggers(&x, fs, None, &TriggerOptions::default()).unwrap();
        assert_eq!(tr.missing.len(), 1);
        let expected = (200.0 + 5.0 * p as f64 - 0.5) / fs;
        assert!(
            (tr.missing[0].time - expected).abs() < 1e-12,
            "{:?}",
            tr.missing
        );
        assert_eq!(tr.missing[0].gap_periods, 2.0);
        // Revolution 4 (whose end is missing) and 5 (no start) are gone; 10 remain, and no
        // remaining period spans the gap.
        assert_eq!(tr.n_gap_dropped, 2);
        assert_eq!(tr.times.len(), 10);
        assert!(!tr
            .times
            .iter()
            .any(|&t| (t - (200.0 + 4000.0 - 0.5) / fs).abs() < 1e-9));
        for per in tr.periods() {
            assert!((per * fs - p as f64).abs() < 1e-9, "{per}");
        }
        assert_eq!(
            tr.revolution_periods.iter().filter(|p| p.is_none()).count(),
            1
        );
        // With rpm given, the debounce uses it and the result is the same.
        let tr2 = detect_triggers(&x, fs, Some(0.1), &TriggerOptions::default()).unwrap();
        assert_eq!(tr2.times, tr.times);
    }

    #[test]
    fn an_extra_pulse_is_reported_and_ignored() {
        let p = 1000usize;
        let mut starts: Vec<usize> = (0..10).map(|k| 200 + k * p).collect();
        let truth: Vec<f64> = starts.iter().map(|&s| s as f64 - 0.5).collect();
        starts.push(200 + 3 * p + 600); // 0.6 revolution after pulse 3
        starts.push(50); // and one before the first true pulse
        let x = pulses_at(200 + 10 * p, &starts, 10, 0.0, 5.0);
        let tr = detect_triggers(&x, 1.0, None, &TriggerOptions::default()).unwrap();
        assert_eq!(tr.extra, vec![49.5, (200 + 3 * p + 600) as f64 - 0.5]);
        assert_eq!(tr.times, truth);
        assert!(tr.missing.is_empty());
        assert_eq!(tr.n_gap_dropped, 0);
    }

    #[test]
    fn several_pulses_per_revolution_are_grouped() {
        let p = 4000usize;
        let fs = 1.0;
        // 4 pulses per revolution, 6 revolutions (+ the 7th start).
        let starts: Vec<usize> = (0..=24).map(|k| 100 + k * p / 4).collect();
        let x = pulses_at(100 + 6 * p + 500, &starts, 5, 0.0, 5.0);
        let opts = TriggerOptions {
            pulses_per_revolution: 4,
            ..Default::default()
        };
        let tr = detect_triggers(&x, fs, None, &opts).unwrap();
        assert_eq!(tr.pulses.len(), 25);
        assert_eq!(tr.times.len(), 7);
        for (k, t) in tr.times.iter().enumerate() {
            assert_eq!(*t, (100 + k * p) as f64 - 0.5);
        }
        assert_eq!(tr.periods(), vec![p as f64; 6]);
        // 2 per revolution with rpm known.
        let opts2 = TriggerOptions {
            pulses_per_revolution: 2,
            ..Default::default()
        };
        let tr2 = detect_triggers(&x, fs, Some(p as f64 / 2.0), &opts2).unwrap();
        assert_eq!(tr2.periods(), vec![p as f64 / 2.0; 12]);
        // A pulse missing inside revolution 2 drops that revolution only.
        let mut holes = starts.clone();
        holes.remove(10); // pulse 2 of revolution 2
        let x = pulses_at(100 + 6 * p + 500, &holes, 5, 0.0, 5.0);
        let tr = detect_triggers(&x, fs, None, &opts).unwrap();
        assert_eq!(tr.missing.len(), 1);
        assert_eq!(tr.missing[0].time, (100 + 10 * p / 4) as f64 - 0.5);
        assert_eq!(tr.n_gap_dropped, 1);
        assert_eq!(tr.times.len(), 6);
        assert!(!tr.times.contains(&((100 + 2 * p) as f64 - 0.5)));
        assert_eq!(tr.periods(), vec![p as f64; 5]);
    }

    #[test]
    fn quantile_interpolates_like_numpy() {
        let x: Vec<f64> = (0..11).rev().map(|i| i as f64).collect();
        assert_eq!(quantile(&x, 0.5), 5.0);
        assert_eq!(quantile(&x, 0.25), 2.5);
        assert!((quantile(&x, 0.001) - 0.01).abs() < 1e-12);
        assert_eq!(quantile(&x, 1.0), 10.0);
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn flat_index_channel_error_says_what_was_seen_and_what_to_set() {
        let x = vec![1.0; 1000];
        let e = detect_triggers(&x, 1e3, None, &TriggerOptions::default())
            .unwrap_err()
            .to_string();
        for want in ["flat", "1.000000 … 1.000000", "0 edge(s)", "trigger_level"] {
            assert!(e.contains(want), "{want}: {e}");
        }
        assert!(e.contains("trigger_polarity") && e.contains("`rpm`"), "{e}");
        // A level above the pulses: no edge, and the duty cycle seen is reported.
        let x = pulses_at(5000, &[100, 1100, 2100], 10, 0.0, 5.0);
        let e = detect_triggers(
            &x,
            1.0,
            None,
            &TriggerOptions {
                level: Some(7.0),
                ..Default::default()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("0.0000 … 5.000000") || e.contains("0.000000 … 5.000000"),
            "{e}"
        );
        assert!(e.contains("0 edge(s)"), "{e}");
    }

    #[test]
    fn speed_segmentation_covers_the_record() {
        let tr = triggers_from_speed(4_000_000, 4e6, 5425.0);
        assert_eq!(tr.times.len(), 91); // 1 s at 90.42 rev/s
        assert!((tr.times[1] - 60.0 / 5425.0).abs() < 1e-15);
        assert_eq!(tr.periods().len(), 90);
    }
}
