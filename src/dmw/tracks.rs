//! The three DMW tracks of the 3-DOF model (§4.1.7; docs/dmw.md):
//! original under the TFC bulge, time-flipped for features at +y, negated time-flipped for
//! features at −y. Velocities transform with the time reversal (`d/dt` flips sign).

/// Displacement (m) and velocity (m/s) of the three tracks, all of one length.
#[derive(Debug, Clone, PartialEq)]
pub struct Tracks {
    pub d: [Vec<f64>; 3],
    pub v: [Vec<f64>; 3],
}

/// `D1 = D`, `V1 = V`; `D2[n] = D[N−1−n]`, `V2[n] = −V[N−1−n]`; `D3 = −D2`, `V3 = −V2`.
pub fn three_tracks(d: &[f64], v: &[f64]) -> Tracks {
    let d2: Vec<f64> = d.iter().rev().copied().collect();
    let v2: Vec<f64> = v.iter().rev().map(|x| -x).collect();
    let d3: Vec<f64> = d2.iter().map(|x| -x).collect();
    let v3: Vec<f64> = v2.iter().map(|x| -x).collect();
    Tracks {
        d: [d.to_vec(), d2, d3],
        v: [v.to_vec(), v2, v3],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::spectrum::{amplitude_spectrum, Window};

    fn sample() -> (Vec<f64>, Vec<f64>, f64) {
        let fs = 4e6;
        let mut rng = crate::numerics::rng::Rng::new(3);
        let phases: Vec<f64> = (0..6)
            .map(|_| rng.uniform() * std::f64::consts::TAU)
            .collect();
        let freqs = [10.7e3, 33e3, 51e3, 120e3, 275e3, 410e3];
        let d = |t: f64| -> f64 {
            freqs
                .iter()
                .zip(&phases)
                .map(|(f, p)| {
                    1e-9 / (1.0 + f / 1e5) * (2.0 * std::f64::consts::PI * f * t + p).sin()
                })
                .sum()
        };
        let n: usize = 10_000;
        let dd: Vec<f64> = (0..n).map(|i| d(i as f64 / fs)).collect();
        // Velocity as the central difference of D (the identity below is exact for it).
        let vv: Vec<f64> = (0..n)
            .map(|i| {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
                (dd[b] - dd[a]) * fs / (b - a) as f64
            })
            .collect();
        (dd, vv, fs)
    }

    #[test]
    fn flipped_tracks_keep_spectrum_and_std_and_negate_exactly() {
        let (d, v, fs) = sample();
        let t = three_tracks(&d, &v);
        let std = |x: &[f64]| {
            let m = x.iter().sum::<f64>() / x.len() as f64;
            (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / x.len() as f64).sqrt()
        };
        let s1 = std(&t.d[0]);
        assert!((std(&t.d[1]) - s1).abs() <= 1e-15 * s1 * 10.0);
        assert!((std(&t.d[2]) - s1).abs() <= 1e-15 * s1 * 10.0);
        let a1 = amplitude_spectrum(&t.d[0], fs, Window::None)
            .unwrap()
            .amplitude;
        let a2 = amplitude_spectrum(&t.d[1], fs, Window::None)
            .unwrap()
            .amplitude;
        let a3 = amplitude_spectrum(&t.d[2], fs, Window::None)
            .unwrap()
            .amplitude;
        let top = a1.iter().cloned().fold(0.0, f64::max);
        for k in 0..a1.len() {
            assert!((a1[k] - a2[k]).abs() <= 1e-12 * top, "{k}");
            assert_eq!(a2[k], a3[k]);
        }
        for n in 0..d.len() {
            assert_eq!(t.d[2][n], -t.d[1][n]);
            assert_eq!(t.v[2][n], -t.v[1][n]);
        }
        // Flipping D2 again returns D1.
        let back: Vec<f64> = t.d[1].iter().rev().copied().collect();
        assert_eq!(back, t.d[0]);
    }

    #[test]
    fn flipped_velocities_are_the_derivatives_of_flipped_displacements() {
        let (d, v, fs) = sample();
        let t = three_tracks(&d, &v);
        let n = d.len();
        for k in 1..3 {
            for i in 1..n - 1 {
                let deriv = (t.d[k][i + 1] - t.d[k][i - 1]) * fs / 2.0;
                assert!(
                    (deriv - t.v[k][i]).abs()
                        <= 1e-15 * v.iter().fold(0.0f64, |m, x| m.max(x.abs())) * 4.0,
                    "track {k}, sample {i}"
                );
            }
        }
    }
}
