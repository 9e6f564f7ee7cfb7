//! Mean, spread and percentile-bootstrap confidence interval of a small sample (several scan
//! areas of one surface, dissertation App. C.1: "σ = 1.247 ± 0.153 nm"; docs/surfaces.md).

use super::rng::Rng;

/// Resamples drawn by [`summarise`] (the percentile interval's 2.5 % and 97.5 % points are then
/// the 50th and 1951st order statistics).
pub const RESAMPLES: usize = 2000;
/// Fixed seed: the same areas give the same interval on every run.
pub const SEED: u64 = 0x005E_EDC1;

/// Mean, sample standard deviation and 95 % percentile-bootstrap interval of the mean.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    pub n: usize,
    pub mean: f64,
    /// Sample standard deviation (n − 1 denominator); NaN for n < 2.
    pub std: f64,
    pub ci_low: f64,
    pub ci_high: f64,
}

/// Percentile of sorted values by linear interpolation between order statistics (numpy's
/// default `linear` method).
fn percentile_sorted(sorted: &[f64], q: f64) -> f64 {
    let pos = q * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}

/// Percentile bootstrap of the mean: `resamples` means of `n` values drawn with replacement
/// (index = ⌊u·n⌋ from `Rng::new(seed)`), the interval between their `(1 − level)/2` and
/// `(1 + level)/2` percentiles. Non-finite values are left out; an empty sample gives NaNs.
pub fn bootstrap_mean(x: &[f64], resamples: usize, level: f64, seed: u64) -> Summary {
    let v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    let n = v.len();
    if n == 0 {
        return Summary {
            n,
            mean: f64::NAN,
            std: f64::NAN,
            ci_low: f64::NAN,
            ci_high: f64::NAN,
        };
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    let std = if n >= 2 {
        (v.iter().map(|a| (a - mean) * (a - mean)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        f64::NAN
    };
    let mut rng = Rng::new(seed);
    let mut means: Vec<f64> = (0..resamples.max(1))
        .map(|_| {
            (0..n)
                .map(|_| v[((rng.uniform() * n as f64) as usize).min(n - 1)])
                .sum::<f64>()
                / n as f64
        })
        .collect();
    means.sort_by(f64::total_cmp);
    let a = 0.5 * (1.0 - level);
    Summary {
        n,
        mean,
        std,
        ci_low: percentile_sorted(&means, a),
        ci_high: percentile_sorted(&means, 1.0 - a),
    }
}

/// [`bootstrap_mean`] with the defaults: 2000 resamples, 95 %, the fixed seed.
pub fn summarise(x: &[f64]) -> Summary {
    bootstrap_mean(x, RESAMPLES, 0.95, SEED)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_std_are_the_direct_ones() {
        let x = [1.0, 2.0, 4.0, 7.0];
        let s = summarise(&x);
        assert_eq!(s.n, 4);
        assert_eq!(s.mean, 3.5);
        // Sample variance (1 − 3.5)² + … = 6.25 + 2.25 + 0.25 + 12.25 = 21 → 21/3 = 7.
        assert!((s.std - 7f64.sqrt()).abs() < 1e-15);
        assert!(s.ci_low >= 1.0 && s.ci_high <= 7.0 && s.ci_low < s.mean && s.mean < s.ci_high);
        assert_eq!(summarise(&x), s, "deterministic");
        let one = summarise(&[2.5]);
        assert_eq!((one.mean, one.ci_low, one.ci_high), (2.5, 2.5, 2.5));
        assert!(one.std.is_nan());
        assert!(summarise(&[]).mean.is_nan());
    }

    #[test]
    fn large_sample_interval_matches_normal_theory() {
        // For n = 400 normal values the percentile-bootstrap interval of the mean approaches
        // the normal-theory one, mean ± 1.95996·s·√((n−1)/n)/√n (the bootstrap uses the
        // plug-in variance). Its endpoints scatter by ~3 % of the half-width with 2000
        // resamples (Monte-Carlo error of the 2.5 % quantile), hence 8 %.
        let mut rng = Rng::new(11);
        let n = 400;
        let x: Vec<f64> = (0..n).map(|_| 3.0 + 0.5 * rng.normal()).collect();
        let s = summarise(&x);
        let half =
            1.959_963_984_540_054 * s.std * ((n - 1) as f64 / n as f64).sqrt() / (n as f64).sqrt();
        for (got, want) in [(s.ci_low, s.mean - half), (s.ci_high, s.mean + half)] {
            assert!(
                (got - want).abs() < 0.08 * half,
                "{got} vs {want} (half {half})"
            );
        }
    }

    #[test]
    fn coverage_is_close_to_nominal() {
        // 400 samples of n = 30 from N(0, 1): the 95 % interval should contain the true mean
        // ~94 % of the time (the percentile bootstrap under-covers slightly at small n:
        // 1 − α − O(1/n)). Binomial sd of the rate over 400 trials: 1.2 %; accept 90–97 %.
        let mut rng = Rng::new(5);
        let trials = 400;
        let hits = (0..trials)
            .filter(|&k| {
                let x: Vec<f64> = (0..30).map(|_| rng.normal()).collect();
                let s = bootstrap_mean(&x, 1000, 0.95, 100 + k as u64);
                s.ci_low <= 0.0 && 0.0 <= s.ci_high
            })
            .count();
        let rate = hits as f64 / trials as f64;
        assert!((0.90..=0.97).contains(&rate), "{rate}");
    }
}
