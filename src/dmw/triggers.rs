//! Once-per-revolution trigger detection (docs/dmw.md) and segmentation from
//! the spindle speed when there is no index channel.

use super::DmwError;

/// Trigger detection settings.
#[derive(Debug, Clone, Copy)]
pub struct TriggerOptions {
    /// Threshold in the index channel's unit; `None` = midpoint of its 0.1 % and 99.9 %
    /// quantiles.
    pub level: Option<f64>,
    /// Crossings closer than this fraction of the nominal period to the previous one are
    /// dropped (bounce on a slow TTL edge, noise around the threshold).
    pub debounce_fraction: f64,
}

impl Default for TriggerOptions {
    fn default() -> Self {
        TriggerOptions {
            level: None,
            debounce_fraction: 0.5,
        }
    }
}

/// Detected revolutions.
#[derive(Debug, Clone)]
pub struct Triggers {
    /// Sub-sample trigger times, seconds from sample 0.
    pub times: Vec<f64>,
    /// The threshold used.
    pub level: f64,
    /// Crossings dropped by the debounce.
    pub n_debounced: usize,
}

impl Triggers {
    /// Revolution periods `T_{k+1} − T_k`.
    pub fn periods(&self) -> Vec<f64> {
        self.times.windows(2).map(|w| w[1] - w[0]).collect()
    }
}

/// Quantile by linear interpolation between order statistics (numpy's default), on a strided
/// subsample of at most ~2^17 values: a trigger level needs the channel's two plateaus, not
/// every sample, and selection (O(n)) replaces a sort.
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

/// Rising crossings of `level` with linear sub-sample interpolation:
/// `t = (i + (L − x_i)/(x_{i+1} − x_i))/fs`, debounced against `nominal_period`.
pub fn detect_triggers(
    index: &[f64],
    fs: f64,
    nominal_period: Option<f64>,
    opts: &TriggerOptions,
) -> Result<Triggers, DmwError> {
    let level = match opts.level {
        Some(l) => l,
        None => {
            let lo = quantile(index, 0.001);
            let hi = quantile(index, 0.999);
            if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
                return Err(DmwError::Processing(format!(
                    "the index channel is flat ({lo} … {hi}): no once-per-revolution pulses; \
                     set `trigger_level` or give the spindle speed `rpm` and no index channel"
                )));
            }
            0.5 * (lo + hi)
        }
    };
    let mut times = Vec::new();
    let mut n_debounced = 0;
    // Before any reliable period is known, debounce against the nominal one (if given) or the
    // first full gap.
    let min_gap = nominal_period.map(|p| opts.debounce_fraction * p);
    let mut last: Option<f64> = None;
    for i in 0..index.len().saturating_sub(1) {
        let (a, b) = (index[i], index[i + 1]);
        if a < level && b >= level {
            let frac = if b != a { (level - a) / (b - a) } else { 0.0 };
            let t = (i as f64 + frac) / fs;
            if let (Some(prev), Some(gap)) = (last, min_gap) {
                if t - prev < gap {
                    n_debounced += 1;
                    continue;
                }
            }
            times.push(t);
            last = Some(t);
        }
    }
    if min_gap.is_none() && times.len() >= 3 {
        // No nominal period: debounce against the upper-quartile gap, which is a true
        // revolution even when every edge bounces (then half the gaps are glitches).
        let mut gaps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        gaps.sort_by(f64::total_cmp);
        let typical = gaps[(3 * gaps.len()) / 4];
        let mut kept: Vec<f64> = Vec::with_capacity(times.len());
        for t in times {
            match kept.last() {
                Some(&p) if t - p < opts.debounce_fraction * typical => n_debounced += 1,
                _ => kept.push(t),
            }
        }
        times = kept;
    }
    Ok(Triggers {
        times,
        level,
        n_debounced,
    })
}

/// Segment starts from the spindle speed alone (no index channel): `t_k = k·60/rpm`.
/// Averaging then only works if the record's speed is exactly `rpm`; the QA says so.
pub fn triggers_from_speed(n_samples: usize, fs: f64, rpm: f64) -> Triggers {
    let period = 60.0 / rpm;
    let duration = n_samples as f64 / fs;
    let n = (duration / period).floor() as usize + 1;
    Triggers {
        times: (0..n)
            .map(|k| k as f64 * period)
            .filter(|&t| t < duration)
            .collect(),
        level: f64::NAN,
        n_debounced: 0,
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
    fn flat_index_channel_is_an_error() {
        let x = vec![1.0; 1000];
        let e = detect_triggers(&x, 1e3, None, &TriggerOptions::default()).unwrap_err();
        assert!(e.to_string().contains("flat"), "{e}");
    }

    #[test]
    fn speed_segmentation_covers_the_record() {
        let tr = triggers_from_speed(4_000_000, 4e6, 5425.0);
        assert_eq!(tr.times.len(), 91); // 1 s at 90.42 rev/s
        assert!((tr.times[1] - 60.0 / 5425.0).abs() < 1e-15);
    }
}
