//! Time-dependent inputs of the 3-DOF scenarios (§4.1; docs/three-dof.md): the TFC actuation as a
//! piecewise-linear profile (S3 constant, S5/S6 variable) and the impulse shock of S4. Pure; SI.
//!
//! Both know their non-smooth instants (profile breakpoints, pulse start and end): the
//! integrator stops there (§10 item 3, "known discontinuity times go in as mandatory step
//! stops"), so no step straddles a kink of the input.

use super::super::{DynamicsError, Result, NM};

/// TFC actuation `h_TFC(t)`: piecewise linear through `(t_k, h_k)`, held constant before the
/// first and after the last point.
#[derive(Debug, Clone, PartialEq)]
pub struct ActuationProfile {
    points: Vec<(f64, f64)>,
}

impl ActuationProfile {
    /// A constant actuation (S3, S4).
    pub fn constant(actuation: f64) -> Result<Self> {
        Self::table(vec![(0.0, actuation)])
    }

    /// A table of `(time [s], actuation [m])`: times ≥ 0 and strictly increasing, actuations
    /// finite and in `[0, 30 nm]`.
    pub fn table(points: Vec<(f64, f64)>) -> Result<Self> {
        if points.is_empty() {
            return Err(DynamicsError::parameter(
                "actuation profile",
                0.0,
                "needs at least one (time, actuation) point",
            ));
        }
        for (k, &(t, h)) in points.iter().enumerate() {
            if !(t.is_finite() && t >= 0.0) {
                return Err(DynamicsError::parameter(
                    format!("actuation profile time #{}", k + 1),
                    t,
                    "must be finite and >= 0",
                ));
            }
            if k > 0 && t <= points[k - 1].0 {
                return Err(DynamicsError::parameter(
                    format!("actuation profile time #{}", k + 1),
                    t,
                    "must be later than the previous point",
                ));
            }
            if !(h.is_finite() && (0.0..=30.0 * NM).contains(&h)) {
                return Err(DynamicsError::parameter(
                    format!("actuation profile actuation #{}", k + 1),
                    h,
                    "must lie in [0, 30 nm]",
                ));
            }
        }
        Ok(ActuationProfile { points })
    }

    /// S5 (Fig. 4.13) [assumption, docs/three-dof.md]: 5 nm to 0.2 ms, ramp to 18 nm at 0.6 ms,
    /// plateau to 1.4 ms, ramp back to 5 nm at 1.8 ms, hold to 2 ms.
    pub fn variable_default() -> Self {
        ActuationProfile {
            points: vec![
                (0.0, 5.0 * NM),
                (0.2e-3, 5.0 * NM),
                (0.6e-3, 18.0 * NM),
                (1.4e-3, 18.0 * NM),
                (1.8e-3, 5.0 * NM),
                (2.0e-3, 5.0 * NM),
            ],
        }
    }

    pub fn points(&self) -> &[(f64, f64)] {
        &self.points
    }

    /// True when every point has the same actuation.
    pub fn is_constant(&self) -> bool {
        self.points.iter().all(|p| p.1 == self.points[0].1)
    }

    /// `(h_TFC, dh_TFC/dt)` at `t`. The rate at a breakpoint is the right-hand one.
    #[inline]
    pub fn at(&self, t: f64) -> (f64, f64) {
        let p = &self.points;
        if t < p[0].0 || p.len() == 1 {
            return (p[0].1, 0.0);
        }
        // Few points: a linear scan beats a binary search here.
        let k = p.iter().rposition(|q| q.0 <= t).unwrap_or(0);
        if k + 1 >= p.len() {
            return (p[p.len() - 1].1, 0.0);
        }
        let ((t0, h0), (t1, h1)) = (p[k], p[k + 1]);
        let rate = (h1 - h0) / (t1 - t0);
        (h0 + rate * (t - t0), rate)
    }

    /// Smallest and largest actuation of the profile.
    pub fn range(&self) -> (f64, f64) {
        self.points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.1), hi.max(p.1))
            })
    }

    /// Times where the rate jumps (interior kinks; a constant profile has none).
    pub fn breakpoints(&self) -> Vec<f64> {
        let p = &self.points;
        (0..p.len())
            .filter(|&k| {
                let before = if k == 0 {
                    0.0
                } else {
                    (p[k].1 - p[k - 1].1) / (p[k].0 - p[k - 1].0)
                };
                let after = if k + 1 == p.len() {
                    0.0
                } else {
                    (p[k + 1].1 - p[k].1) / (p[k + 1].0 - p[k].0)
                };
                before != after
            })
            .map(|k| p[k].0)
            .collect()
    }

    /// The plateau at the profile's maximum: `(start, end)` of the first maximal segment held
    /// for a positive time, if any (the steady-contact window of Table 4.4).
    pub fn plateau(&self) -> Option<(f64, f64)> {
        let (_, hi) = self.range();
        self.points
            .windows(2)
            .find(|w| w[0].1 == hi && w[1].1 == hi)
            .map(|w| (w[0].0, w[1].0))
    }
}

/// S4 impulse shock toward the disk at the COM: a haversine
/// `F(t) = (F_pk/2)(1 − cos(2π(t − t0)/T))` on `[t0, t0 + T]` [derived, docs/three-dof.md: only
/// a haversine or triangle carries 0.25 µN·s with a 100 mN peak over 5 µs].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShockPulse {
    /// `t0` [s].
    pub start: f64,
    /// `T` [s].
    pub duration: f64,
    /// `F_pk` [N], positive toward the disk.
    pub peak: f64,
}

impl ShockPulse {
    /// The pulse carrying `impulse` [N·s] over `duration` (`F_pk = 2 I / T`).
    pub fn from_impulse(start: f64, duration: f64, impulse: f64) -> Result<Self> {
        if !(start.is_finite() && start >= 0.0) {
            return Err(DynamicsError::parameter(
                "shock start (s)",
                start,
                "must be finite and >= 0",
            ));
        }
        if !(duration.is_finite() && duration > 0.0 && duration <= 1e-3) {
            return Err(DynamicsError::parameter(
                "shock duration (s)",
                duration,
                "must lie in (0, 1 ms]",
            ));
        }
        if !(0.0..=1e-3).contains(&impulse) {
            return Err(DynamicsError::parameter(
                "shock impulse (N s)",
                impulse,
                "must lie in [0, 1e-3] N s",
            ));
        }
        Ok(ShockPulse {
            start,
            duration,
            peak: 2.0 * impulse / duration,
        })
    }

    /// The dissertation's shock (§4.1.7): 0.25 µN·s over 5 µs from 0.6 ms (peak 100 mN).
    pub fn dissertation() -> Self {
        ShockPulse {
            start: 0.6e-3,
            duration: 5e-6,
            peak: 0.1,
        }
    }

    /// Force toward the disk [N] at `t`.
    #[inline]
    pub fn force(&self, t: f64) -> f64 {
        let s = t - self.start;
        if s <= 0.0 || s >= self.duration {
            0.0
        } else {
            0.5 * self.peak * (1.0 - (std::f64::consts::TAU * s / self.duration).cos())
        }
    }

    /// `∫F dt` = `F_pk T/2` [N·s].
    pub fn impulse(&self) -> f64 {
        0.5 * self.peak * self.duration
    }

    /// Start and end: mandatory step stops.
    pub fn breakpoints(&self) -> [f64; 2] {
        [self.start, self.start + self.duration]
    }
}

/// Table 4.4 windows of a variable-actuation case [assumption, docs/dynamics-metrics.md]: flying
/// from 0.1 ms to the first entry of any feature into lubricant contact; jump-to-contact from that
/// entry to 0.1 ms after the plateau starts; steady contact the rest of the plateau.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegimeWindows {
    /// `[start, end)` in seconds; `None` when the case never enters lubricant contact before
    /// the plateau ends (then the jump-to-contact window does not exist).
    pub flying: (f64, f64),
    pub jump_to_contact: Option<(f64, f64)>,
    pub steady_contact: Option<(f64, f64)>,
}

/// The windows of Table 4.4 from the first lubricant-contact entry time and the plateau.
pub fn regime_windows(
    first_lubricant_contact: Option<f64>,
    plateau: (f64, f64),
    duration: f64,
) -> RegimeWindows {
    const SETTLE: f64 = 0.1e-3;
    let (p0, p1) = plateau;
    match first_lubricant_contact {
        Some(entry) if entry < p1 => {
            let jtc_end = (p0 + SETTLE).max(entry).min(p1);
            RegimeWindows {
                flying: (SETTLE.min(entry), entry),
                jump_to_contact: (jtc_end > entry).then_some((entry, jtc_end)),
                steady_contact: (p1 > jtc_end).then_some((jtc_end, p1)),
            }
        }
        _ => RegimeWindows {
            flying: (SETTLE, p1.min(duration)),
            jump_to_contact: None,
            steady_contact: None,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_interpolates_holds_and_reports_its_kinks() {
        let p = ActuationProfile::variable_default();
        let close = |a: f64, b: f64| (a - b).abs() < 1e-20;
        assert!(close(p.at(0.1e-3).0, 5.0 * NM));
        let (h, rate) = p.at(0.4e-3);
        assert!(close(h, 11.5 * NM), "{h}");
        assert!((rate - 13.0 * NM / 0.4e-3).abs() < 1e-12);
        assert!(close(p.at(1.0e-3).0, 18.0 * NM));
        assert!(close(p.at(1.6e-3).0, 11.5 * NM));
        assert!(close(p.at(5e-3).0, 5.0 * NM) && p.at(5e-3).1 == 0.0);
        assert_eq!(p.breakpoints(), vec![0.2e-3, 0.6e-3, 1.4e-3, 1.8e-3]);
        assert_eq!(p.plateau(), Some((0.6e-3, 1.4e-3)));
        assert_eq!(p.range(), (5.0 * NM, 18.0 * NM));
        let c = ActuationProfile::constant(12.0 * NM).unwrap();
        assert!(c.is_constant() && c.breakpoints().is_empty());
        assert_eq!(c.at(1e-3), (12.0 * NM, 0.0));
    }

    #[test]
    fn bad_profiles_are_errors() {
        assert!(ActuationProfile::table(vec![]).is_err());
        assert!(ActuationProfile::table(vec![(0.0, 5e-9), (0.0, 6e-9)]).is_err());
        assert!(ActuationProfile::table(vec![(0.0, -1e-9)]).is_err());
        assert!(ActuationProfile::table(vec![(0.0, f64::NAN)]).is_err());
        assert!(ActuationProfile::table(vec![(-1e-3, 5e-9)]).is_err());
        assert!(ActuationProfile::table(vec![(0.0, 40e-9)]).is_err());
    }

    #[test]
    fn dissertation_shock_carries_its_impulse() {
        let s = ShockPulse::from_impulse(0.6e-3, 5e-6, 0.25e-6).unwrap();
        assert!((s.peak - 0.1).abs() < 1e-15, "peak {}", s.peak);
        let d = ShockPulse::dissertation();
        assert!(d.start == s.start && d.duration == s.duration && (d.peak - s.peak).abs() < 1e-15);
        // Simpson over the pulse: the impulse integral to 1e-6 (docs/three-dof.md).
        let n = 2000;
        let h = s.duration / n as f64;
        let mut sum = s.force(s.start) + s.force(s.start + s.duration);
        for k in 1..n {
            let w = if k % 2 == 1 { 4.0 } else { 2.0 };
            sum += w * s.force(s.start + k as f64 * h);
        }
        let integral = sum * h / 3.0;
        assert!((integral / 0.25e-6 - 1.0).abs() < 1e-6, "{integral}");
        assert!((s.impulse() - 0.25e-6).abs() < 1e-18);
        assert_eq!(s.force(0.5e-3), 0.0);
        assert!((s.force(0.6e-3 + 2.5e-6) - 0.1).abs() < 1e-15);
        assert!(ShockPulse::from_impulse(0.0, 0.0, 1e-7).is_err());
        assert!(ShockPulse::from_impulse(0.0, 5e-6, -1e-7).is_err());
    }

    #[test]
    fn table_4_4_windows() {
        let w = regime_windows(Some(0.45e-3), (0.6e-3, 1.4e-3), 2e-3);
        assert_eq!(w.flying, (0.1e-3, 0.45e-3));
        assert_eq!(w.jump_to_contact, Some((0.45e-3, 0.7e-3)));
        assert_eq!(w.steady_contact, Some((0.7e-3, 1.4e-3)));
        // Entry on the plateau itself, after its settling time.
        let w = regime_windows(Some(0.9e-3), (0.6e-3, 1.4e-3), 2e-3);
        assert_eq!(w.jump_to_contact, None);
        assert_eq!(w.steady_contact, Some((0.9e-3, 1.4e-3)));
        // Never in lubricant contact: flying only.
        let w = regime_windows(None, (0.6e-3, 1.4e-3), 2e-3);
        assert_eq!(w.flying, (0.1e-3, 1.4e-3));
        assert!(w.jump_to_contact.is_none() && w.steady_contact.is_none());
    }
}
