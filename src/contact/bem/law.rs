//! The BEM force–separation curve of a measured interface as the dynamics' contact law
//! (`[simulate] contact_law = "bem"`; docs/model-form.md, "Contact law").
//!
//! Between the curve's separations, `ln P` and `ln A_r` are monotone cubic Hermite
//! interpolants (Fritsch–Carlson slopes) of the solved points, so P, its slope and A_r are
//! continuous and positive. Above the largest separation the last interval's exponential
//! continues (the measured map's highest summits still touch: a decaying tail). Below the
//! smallest the law is an **extrapolation** — a mean gap cannot close below zero in the
//! half-space model, while the slider's kinematic separation can (ISBL calls it interference),
//! flagged by [`ContactCurve::measured_range`]: P continues along its tangent there (the
//! stiffness stops growing where the data stop), so the law stays finite however deep a
//! transient or an equilibrium search probes. (An exponential continuation instead stiffens
//! without bound and makes the DMW-driven cases diverge; docs/model-form.md.)

use crate::contact::ContactError;
use crate::signal::resample::hermite_segment;

/// `ln P(h)` and `ln A_r(h)` on the solved separations.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactCurve {
    h: Vec<f64>,
    log_p: Log,
    log_a: Log,
}

#[derive(Debug, Clone, PartialEq)]
struct Log {
    y: Vec<f64>,
    slope: Vec<f64>,
}

impl Log {
    fn new(h: &[f64], y: Vec<f64>) -> Self {
        let n = h.len();
        let secant: Vec<f64> = (0..n - 1)
            .map(|i| (y[i + 1] - y[i]) / (h[i + 1] - h[i]))
            .collect();
        let mut slope = vec![0.0; n];
        slope[0] = secant[0];
        slope[n - 1] = secant[n - 2];
        for i in 1..n - 1 {
            let (a, b) = (secant[i - 1], secant[i]);
            // Fritsch–Carlson: zero at a local extremum, else the weighted harmonic mean.
            slope[i] = if a * b <= 0.0 {
                0.0
            } else {
                let (w1, w2) = (
                    2.0 * (h[i + 1] - h[i]) + (h[i] - h[i - 1]),
                    (h[i + 1] - h[i]) + 2.0 * (h[i] - h[i - 1]),
                );
                (w1 + w2) / (w1 / a + w2 / b)
            };
        }
        Log { y, slope }
    }

    /// Value and h-derivative at `x`.
    fn at(&self, h: &[f64], x: f64) -> (f64, f64) {
        let n = h.len();
        if x <= h[0] {
            let s = (self.y[1] - self.y[0]) / (h[1] - h[0]);
            return (self.y[0] + s * (x - h[0]), s);
        }
        if x >= h[n - 1] {
            let s = (self.y[n - 1] - self.y[n - 2]) / (h[n - 1] - h[n - 2]);
            return (self.y[n - 1] + s * (x - h[n - 1]), s);
        }
        let i = h.partition_point(|&v| v <= x) - 1;
        let w = h[i + 1] - h[i];
        let (value, slope) = hermite_segment(
            self.y[i],
            self.y[i + 1],
            self.slope[i] * w,
            self.slope[i + 1] * w,
            (x - h[i]) / w,
        );
        (value, slope / w)
    }
}

/// Contact pressure and real area at one separation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawPoint {
    /// Mean contact pressure [Pa] and its slope dP/dh [Pa/m] (negative).
    pub pressure: f64,
    pub pressure_slope: f64,
    /// A_r/A_0 and its slope [1/m].
    pub real_area_fraction: f64,
    pub real_area_slope: f64,
}

impl ContactCurve {
    /// From `(separation [m], mean pressure [Pa], A_r/A_0)` points (any order); points with
    /// no contact are left out. Needs three points with contact.
    pub fn new(points: &[(f64, f64, f64)]) -> Result<Self, ContactError> {
        let mut p: Vec<(f64, f64, f64)> = points
            .iter()
            .copied()
            .filter(|(h, pr, a)| h.is_finite() && *pr > 0.0 && *a > 0.0 && pr.is_finite())
            .collect();
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        p.dedup_by(|a, b| a.0 == b.0);
        if p.len() < 3 {
            return Err(ContactError::parameter(
                "BEM curve",
                p.len(),
                "needs at least three separations with contact",
            ));
        }
        let h: Vec<f64> = p.iter().map(|v| v.0).collect();
        let log_p = Log::new(&h, p.iter().map(|v| v.1.ln()).collect());
        let log_a = Log::new(&h, p.iter().map(|v| v.2.ln()).collect());
        Ok(ContactCurve { h, log_p, log_a })
    }

    /// The separations solved [m]: outside them the law is extrapolated.
    pub fn measured_range(&self) -> (f64, f64) {
        (self.h[0], self.h[self.h.len() - 1])
    }

    pub fn at(&self, h: f64) -> LawPoint {
        let floor = self.h[0];
        if h < floor {
            let edge = self.at(floor);
            return LawPoint {
                pressure: edge.pressure + edge.pressure_slope * (h - floor),
                real_area_slope: 0.0,
                ..edge
            };
        }
        let (lp, dlp) = self.log_p.at(&self.h, h);
        let (la, dla) = self.log_a.at(&self.h, h);
        let (p, a) = (lp.exp(), la.exp().min(1.0));
        LawPoint {
            pressure: p,
            pressure_slope: p * dlp,
            real_area_fraction: a,
            real_area_slope: if a < 1.0 { a * dla } else { 0.0 },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponential_curves_are_reproduced_and_extended() {
        // P = 1e6·exp(−h/0.2 nm): Hermite in ln P is exact on a straight line (inside the
        // solved range and above it).
        let pts: Vec<(f64, f64, f64)> = (0..10)
            .map(|k| {
                let h = 0.1e-9 * k as f64;
                (h, 1e6 * (-h / 0.2e-9).exp(), 0.1 * (-h / 0.4e-9).exp())
            })
            .collect();
        let c = ContactCurve::new(&pts).unwrap();
        for h in [0.0, 0.05e-9, 0.33e-9, 0.85e-9, 1.5e-9] {
            let q = c.at(h);
            let want = 1e6 * (-h / 0.2e-9).exp();
            assert!((q.pressure / want - 1.0).abs() < 1e-12, "{h}");
            assert!(
                (q.pressure_slope / (-want / 0.2e-9) - 1.0).abs() < 1e-9,
                "{h}"
            );
        }
        assert_eq!(c.measured_range(), (0.0, 0.9e-9));
        // Below the smallest separation P follows its tangent there.
        let edge = c.at(0.0);
        let deep = c.at(-5e-9);
        let want = edge.pressure + edge.pressure_slope * -5e-9;
        assert!((deep.pressure / want - 1.0).abs() < 1e-12 && deep.pressure.is_finite());
        assert_eq!(deep.pressure_slope, edge.pressure_slope);
    }

    #[test]
    fn a_monotone_curve_stays_monotone_and_too_few_points_are_refused() {
        let pts = [
            (1.0, 1.0, 0.01),
            (2.0, 0.5, 0.005),
            (3.0, 0.49, 0.004),
            (4.0, 0.1, 0.001),
        ];
        let c = ContactCurve::new(&pts).unwrap();
        let mut last = f64::INFINITY;
        for k in 0..=300 {
            let q = c.at(1.0 + 3.0 * k as f64 / 300.0);
            assert!(q.pressure <= last && q.pressure_slope <= 0.0);
            last = q.pressure;
        }
        assert!(ContactCurve::new(&pts[..2]).is_err());
        assert!(ContactCurve::new(&[(1.0, 0.0, 0.0), (2.0, 0.0, 0.0), (3.0, 1.0, 0.1)]).is_err());
    }
}
