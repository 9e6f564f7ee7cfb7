//! Force tables: contact curves tabulated once per interface and interpolated in O(1) inside
//! the dynamics' inner loop (docs/contact.md).
//!
//! The grid is uniform in the abscissa (e.g. h* = h/σ), so a lookup is one multiply, one
//! floor and a cubic. Each channel stores its values and *exact* derivatives at the nodes
//! (the physics supplies both: derivatives come from differentiating the Gaussian density, not
//! from finite differences) and is interpolated with cubic Hermite — in `ln y` for positive,
//! exponentially decaying curves (P, A_r, k_c, …), where the error at Δh* = 0.05 is ~1e-9,
//! or in `y` for curves that may change sign. The result is C¹ in h, which the adaptive ODE
//! solver's error control needs; linear interpolation would make the stiffness jump at nodes.

use super::ContactError;
use crate::signal::resample::{hermite_segment, hermite_weights};
use rayon::prelude::*;

/// How a channel is interpolated between nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interp {
    /// Cubic Hermite in `ln y` with `d ln y/dx = y'/y`: for strictly positive curves.
    Log,
    /// Cubic Hermite in `y`.
    Linear,
}

/// One tabulated quantity.
#[derive(Debug, Clone)]
struct Channel {
    name: String,
    interp: Interp,
    /// Per node: `y` or `ln y`, and its derivative with respect to x times the grid step (so
    /// the Hermite basis needs no extra multiply). Interleaved: a lookup reads its cell's two
    /// nodes from one contiguous 32-byte span.
    nodes: Vec<[f64; 2]>,
    /// Where the node values decrease strictly: the bracket index of `invert_decreasing`.
    index: Option<DecreasingIndex>,
}

/// A coarse value → node index over a channel whose node values decrease strictly, so
/// [`ForceTable::invert_decreasing`] bisects from a bracket of a node or two instead of the
/// whole table (nine unpredictable comparisons per `P⁻¹`, on the 2-DOF right-hand side's
/// critical path). The answer does not depend on the bracket: on strictly decreasing values
/// every bracket `(lo, hi)` with `v[lo] ≥ y` and `hi = n − 1` or `v[hi] < y` bisects to the
/// largest `i ≤ n − 2` with `v[i] ≥ y`, and so does the whole table `(0, n − 1)`.
#[derive(Debug, Clone)]
struct DecreasingIndex {
    /// The first node's value and buckets per unit value.
    top: f64,
    per_value: f64,
    /// `start[b]`: the largest node `i ≤ n − 2` with `v[i] ≥ top − b/per_value`.
    start: Vec<usize>,
}

impl DecreasingIndex {
    /// Four buckets per node; `None` unless the values decrease strictly.
    fn new(nodes: &[[f64; 2]]) -> Option<Self> {
        let n = nodes.len();
        if n < 2 || !nodes.windows(2).all(|w| w[0][0] > w[1][0]) {
            return None;
        }
        let top = nodes[0][0];
        let buckets = 4 * n;
        let per_value = buckets as f64 / (top - nodes[n - 1][0]);
        if !per_value.is_finite() {
            return None;
        }
        let mut start = Vec::with_capacity(buckets + 2);
        let mut i = 0;
        for b in 0..=buckets + 1 {
            let bound = top - b as f64 / per_value;
            while i + 2 < n && nodes[i + 1][0] >= bound {
                i += 1;
            }
            start.push(i);
        }
        Some(DecreasingIndex {
            top,
            per_value,
            start,
        })
    }

    /// A bracket for `y` (`v[n−1] ≤ y ≤ v[0]`), checked against the nodes; `None` where the
    /// bucket's rounding missed (the caller searches the whole table).
    #[inline]
    fn bracket(&self, nodes: &[[f64; 2]], y: f64) -> Option<(usize, usize)> {
        let last = nodes.len() - 1;
        // Saturating cast: 0 at the top; past the end of `start` only by rounding at the
        // bottom (→ None).
        let b = ((self.top - y) * self.per_value) as usize;
        let lo = *self.start.get(b)?;
        let hi = (*self.start.get(b + 1)? + 1).min(last);
        let valid = lo < hi && nodes[lo][0] >= y && (hi == last || nodes[hi][0] < y);
        valid.then_some((lo, hi))
    }
}

impl Channel {
    /// Nodes `i` and `i + 1` (one bounds check).
    #[inline]
    fn cell_nodes(&self, i: usize) -> [[f64; 2]; 2] {
        let pair = &self.nodes[i..i + 2];
        [pair[0], pair[1]]
    }
}

/// A uniform-grid table of several smooth curves of one abscissa.
#[derive(Debug, Clone)]
pub struct ForceTable {
    x0: f64,
    dx: f64,
    inv_dx: f64,
    n: usize,
    /// `n − 1` as f64 (the last node's position).
    last: f64,
    channels: Vec<Channel>,
}

/// Where an abscissa falls in a table ([`ForceTable::locate`]): the cell and the Hermite
/// value weights at its fraction, computed once and shared by every channel read there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TablePoint {
    i: usize,
    w: [f64; 4],
}

/// Value and derivative of every channel at one abscissa, as the physics computes them.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    pub value: Vec<f64>,
    pub derivative: Vec<f64>,
}

/// Worst interpolation error of a channel against direct evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelError {
    pub name: String,
    /// Max |table − direct| / |direct| over the checked points where |direct| exceeds
    /// `floor` × the channel's largest node value.
    pub max_rel: f64,
    /// Abscissa of the worst point.
    pub at: f64,
}

impl ForceTable {
    /// Tabulate `f` on `x0, x0 + dx, …` up to at least `x1` (nodes evaluated in parallel).
    /// `channels` names each output of `f` and says how to interpolate it.
    pub fn build<F>(
        channels: &[(&str, Interp)],
        x0: f64,
        x1: f64,
        dx: f64,
        f: F,
    ) -> Result<Self, ContactError>
    where
        F: Fn(f64) -> Result<Sample, ContactError> + Sync,
    {
        if !(x0.is_finite() && x1.is_finite() && x1 > x0) {
            return Err(ContactError::parameter(
                "table range",
                format!("[{x0}, {x1}]"),
                "must be finite with x1 > x0",
            ));
        }
        if !(dx.is_finite() && dx > 0.0) || (x1 - x0) / dx > 1e7 {
            return Err(ContactError::parameter(
                "table step",
                dx,
                "must be > 0 and give at most 10^7 nodes",
            ));
        }
        let n = ((x1 - x0) / dx).ceil() as usize + 1;
        Self::from_nodes(channels, x0, dx, n, |i| f(x0 + i as f64 * dx))
    }

    /// Tabulate `f` on `intervals` equal steps from exactly `x0` to exactly `x1`, for a piece
    /// of a curve whose derivative jumps at `x0` or `x1` (a regime boundary): the end nodes
    /// are evaluated a hair (10⁻⁹ of the step) inside, so they carry the one-sided
    /// derivatives of this piece.
    pub fn build_between<F>(
        channels: &[(&str, Interp)],
        x0: f64,
        x1: f64,
        intervals: usize,
        f: F,
    ) -> Result<Self, ContactError>
    where
        F: Fn(f64) -> Result<Sample, ContactError> + Sync,
    {
        if !(x0.is_finite() && x1.is_finite() && x1 > x0 && (1..=10_000_000).contains(&intervals)) {
            return Err(ContactError::parameter(
                "table range",
                format!("[{x0}, {x1}] in {intervals} steps"),
                "must be finite with x1 > x0 and 1 to 10^7 steps",
            ));
        }
        let dx = (x1 - x0) / intervals as f64;
        let inset = 1e-9 * dx;
        let n = intervals + 1;
        Self::from_nodes(channels, x0, dx, n, |i| {
            let x = if i == n - 1 { x1 } else { x0 + i as f64 * dx };
            f(x.clamp(x0 + inset, x1 - inset))
        })
    }

    /// Evaluate node `i` = 0..n with `node(i)` (in parallel) and store the channels.
    fn from_nodes<F>(
        channels: &[(&str, Interp)],
        x0: f64,
        dx: f64,
        n: usize,
        node: F,
    ) -> Result<Self, ContactError>
    where
        F: Fn(usize) -> Result<Sample, ContactError> + Sync,
    {
        let samples: Vec<Result<Sample, ContactError>> =
            (0..n).into_par_iter().map(&node).collect();
        let mut out: Vec<Channel> = channels
            .iter()
            .map(|(name, interp)| Channel {
                name: name.to_string(),
                interp: *interp,
                nodes: Vec::with_capacity(n),
                index: None,
            })
            .collect();
        for (i, s) in samples.into_iter().enumerate() {
            let s = s?;
            let x = x0 + i as f64 * dx;
            if s.value.len() != channels.len() || s.derivative.len() != channels.len() {
                return Err(ContactError::Numerical(format!(
                    "table function returned {} values and {} derivatives for {} channels",
                    s.value.len(),
                    s.derivative.len(),
                    channels.len()
                )));
            }
            for (c, ch) in out.iter_mut().enumerate() {
                let (y, dy) = (s.value[c], s.derivative[c]);
                if !(y.is_finite() && dy.is_finite()) {
                    return Err(ContactError::Numerical(format!(
                        "{} is not finite at x = {x} ({y}, slope {dy})",
                        ch.name
                    )));
                }
                match ch.interp {
                    Interp::Log => {
                        if y <= 0.0 {
                            return Err(ContactError::Numerical(format!(
                                "{} = {y} at x = {x}: a log-interpolated channel must stay > 0 \
                                 (shorten the table or interpolate it linearly)",
                                ch.name
                            )));
                        }
                        ch.nodes.push([y.ln(), dy / y * dx]);
                    }
                    Interp::Linear => {
                        ch.nodes.push([y, dy * dx]);
                    }
                }
            }
        }
        for ch in &mut out {
            ch.index = DecreasingIndex::new(&ch.nodes);
        }
        Ok(ForceTable {
            x0,
            dx,
            inv_dx: 1.0 / dx,
            n,
            last: (n - 1) as f64,
            channels: out,
        })
    }

    /// First and last node abscissa.
    pub fn range(&self) -> (f64, f64) {
        (self.x0, self.x0 + self.last * self.dx)
    }

    pub fn step(&self) -> f64 {
        self.dx
    }

    pub fn n_nodes(&self) -> usize {
        self.n
    }

    pub fn channel_names(&self) -> Vec<&str> {
        self.channels.iter().map(|c| c.name.as_str()).collect()
    }

    /// Index of a channel by name.
    pub fn channel(&self, name: &str) -> Option<usize> {
        self.channels.iter().position(|c| c.name == name)
    }

    /// Value and x-derivative of channel `c` at `x`; `None` outside the table (the caller
    /// decides what the physics does there) or for an unknown channel.
    #[inline]
    pub fn eval_with_slope(&self, c: usize, x: f64) -> Option<(f64, f64)> {
        let ch = self.channels.get(c)?;
        let (i, t) = self.cell(x)?;
        let [[p0, m0], [p1, m1]] = ch.cell_nodes(i);
        let (v, dv) = hermite_segment(p0, p1, m0, m1, t);
        let dv = dv * self.inv_dx;
        Some(match ch.interp {
            Interp::Linear => (v, dv),
            Interp::Log => {
                let y = v.exp();
                (y, y * dv)
            }
        })
    }

    /// The cell `i` (0..=n−2) holding `x` and the fraction `t ∈ [0, 1]` in it; `None` outside
    /// the table (or NaN).
    #[inline]
    fn cell(&self, x: f64) -> Option<(usize, f64)> {
        let u = (x - self.x0) * self.inv_dx;
        if !(u >= 0.0 && u <= self.last) {
            return None;
        }
        // Through i64: one instruction each way, where usize ↔ f64 takes a dozen on baseline
        // x86-64 (exact either way: 0 ≤ u ≤ n − 1 < 2⁵³).
        let i = (u as i64).min(self.n as i64 - 2);
        Some((i as usize, u - i as f64))
    }

    /// Where `x` falls in the table, for reading several channels there with
    /// [`ForceTable::value_at`]; `None` exactly where [`ForceTable::eval_with_slope`] is.
    #[inline]
    pub fn locate(&self, x: f64) -> Option<TablePoint> {
        let (i, t) = self.cell(x)?;
        Some(TablePoint {
            i,
            w: hermite_weights(t),
        })
    }

    /// Value of channel `c` at a located point: bit for bit the value of
    /// [`ForceTable::eval_with_slope`] at the same abscissa, without its slope; `None` for an
    /// unknown channel.
    #[inline]
    pub fn value_at(&self, c: usize, p: &TablePoint) -> Option<f64> {
        let ch = self.channels.get(c)?;
        let [[p0, m0], [p1, m1]] = ch.cell_nodes(p.i);
        let [w0, w1, w2, w3] = p.w;
        // hermite_segment's value, term for term.
        let v = w0 * p0 + w1 * m0 + w2 * p1 + w3 * m1;
        Some(match ch.interp {
            Interp::Linear => v,
            Interp::Log => v.exp(),
        })
    }

    /// Value of channel `c` at `x` (see [`ForceTable::eval_with_slope`]).
    #[inline]
    pub fn eval(&self, c: usize, x: f64) -> Option<f64> {
        self.eval_with_slope(c, x).map(|(v, _)| v)
    }

    /// The abscissa where a channel that decreases strictly over the table takes the value
    /// `y`: binary search over the nodes, then Newton on the cell's cubic, safeguarded by
    /// bisection. `None` for an unknown channel or a `y` outside the tabulated values (the
    /// caller clamps). Used for `P⁻¹` (friction from a dynamic contact force, eq. 2.16).
    pub fn invert_decreasing(&self, c: usize, y: f64) -> Option<f64> {
        let ch = self.channels.get(c)?;
        let target = match ch.interp {
            Interp::Log if y > 0.0 => y.ln(),
            Interp::Log => return None,
            Interp::Linear => y,
        };
        let nodes = &ch.nodes;
        if !(target <= nodes[0][0] && target >= nodes[self.n - 1][0]) {
            return None;
        }
        // Largest i with v[i] ≥ target (v decreasing), from the index's bracket where the
        // values decrease strictly (the same i, see DecreasingIndex), else the whole table.
        let (mut lo, mut hi) = ch
            .index
            .as_ref()
            .and_then(|index| index.bracket(nodes, target))
            .unwrap_or((0, self.n - 1));
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if nodes[mid][0] >= target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let i = lo;
        // The cell's nodes loaded once, outside the Newton loop.
        let [[p0, m0], [p1, m1]] = ch.cell_nodes(i);
        let cell = |s: f64| hermite_segment(p0, p1, m0, m1, s);
        let (mut a, mut b) = (0.0f64, 1.0f64);
        let span = p0 - p1;
        let mut s = if span > 0.0 {
            ((p0 - target) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        for _ in 0..40 {
            let (f, df) = cell(s);
            let r = f - target;
            if r.abs() <= 1e-14 * target.abs().max(1e-300) {
                break;
            }
            // Keep the bracket: the cell's cubic decreases from v[i] to v[i+1].
            if r > 0.0 {
                a = s;
            } else {
                b = s;
            }
            let newton = if df < 0.0 { s - r / df } else { f64::NAN };
            s = if newton > a && newton < b {
                newton
            } else {
                0.5 * (a + b)
            };
            if b - a < 1e-15 {
                break;
            }
        }
        Some(self.x0 + (i as f64 + s) * self.dx)
    }

    /// Largest node value of a channel (for relative floors).
    fn peak(&self, c: usize) -> f64 {
        let ch = &self.channels[c];
        ch.nodes
            .iter()
            .map(|&[v, _]| match ch.interp {
                Interp::Log => v.exp(),
                Interp::Linear => v.abs(),
            })
            .fold(0.0, f64::max)
    }

    /// Interpolation error against direct evaluation at the midpoints between nodes (where
    /// cubic Hermite is worst) and at `extra` points per interval, ignoring values below
    /// `floor` × the channel's peak.
    pub fn verify<F>(
        &self,
        f: F,
        extra: usize,
        floor: f64,
    ) -> Result<Vec<ChannelError>, ContactError>
    where
        F: Fn(f64) -> Result<Sample, ContactError> + Sync,
    {
        let per = extra + 1;
        let points: Vec<f64> = (0..self.n - 1)
            .flat_map(|i| {
                (0..per).map(move |k| {
                    // Midpoint first, then evenly spread interior points.
                    let frac = if k == 0 {
                        0.5
                    } else {
                        k as f64 / (per + 1) as f64
                    };
                    self.x0 + (i as f64 + frac) * self.dx
                })
            })
            .collect();
        let direct: Vec<Result<Sample, ContactError>> = points.par_iter().map(|&x| f(x)).collect();
        let mut worst: Vec<ChannelError> = self
            .channels
            .iter()
            .map(|c| ChannelError {
                name: c.name.clone(),
                max_rel: 0.0,
                at: f64::NAN,
            })
            .collect();
        let peaks: Vec<f64> = (0..self.channels.len()).map(|c| self.peak(c)).collect();
        for (&x, d) in points.iter().zip(direct) {
            let d = d?;
            for (c, w) in worst.iter_mut().enumerate() {
                let want = d.value[c];
                if want.abs() <= floor * peaks[c] {
                    continue;
                }
                let got = self.eval(c, x).unwrap_or(f64::NAN);
                let rel = ((got - want) / want).abs();
                // NaN (a lookup outside the table) must register as the worst.
                if rel.is_nan() || rel > w.max_rel {
                    w.max_rel = rel;
                    w.at = x;
                }
            }
        }
        Ok(worst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Gaussian-tail-like positive curve and a sign-changing one, with exact derivatives.
    fn curves(x: f64) -> Result<Sample, ContactError> {
        let tail = (-0.5 * x * x).exp() * (1.0 + 0.3 * x * x);
        let dtail = (-0.5 * x * x).exp() * (0.6 * x - x * (1.0 + 0.3 * x * x));
        let wave = (2.0 * x).sin() * x;
        let dwave = 2.0 * (2.0 * x).cos() * x + (2.0 * x).sin();
        Ok(Sample {
            value: vec![tail, wave],
            derivative: vec![dtail, dwave],
        })
    }

    fn table(dx: f64) -> ForceTable {
        ForceTable::build(
            &[("tail", Interp::Log), ("wave", Interp::Linear)],
            -4.0,
            10.0,
            dx,
            curves,
        )
        .unwrap()
    }

    #[test]
    fn nodes_are_exact_and_midpoints_converge_at_fourth_order() {
        let t = table(0.05);
        assert_eq!(t.range(), (-4.0, 10.0));
        for i in 0..t.n_nodes() {
            let x = -4.0 + i as f64 * 0.05;
            let d = curves(x).unwrap();
            let (v, s) = t.eval_with_slope(0, x).unwrap();
            assert!((v / d.value[0] - 1.0).abs() < 1e-12, "{x}");
            assert!(
                (s - d.derivative[0]).abs() <= 1e-9 * d.derivative[0].abs().max(1e-300),
                "{x}"
            );
        }
        // Floor: relative errors next to the wave's zero crossings say nothing about order.
        let e1 = t.verify(curves, 3, 1e-2).unwrap();
        let e2 = table(0.025).verify(curves, 3, 1e-2).unwrap();
        // Hermite error ∝ dx⁴: halving the step divides it by ~16.
        for c in 0..2 {
            let ratio = e1[c].max_rel / e2[c].max_rel;
            assert!(ratio > 10.0 && ratio < 20.0, "{}: {ratio}", e1[c].name);
        }
        assert!(e1[0].max_rel < 1e-6, "{:?}", e1[0]);
    }

    #[test]
    fn interpolant_is_c1_across_nodes() {
        let t = table(0.1);
        for i in 1..t.n_nodes() - 1 {
            let x = -4.0 + i as f64 * 0.1;
            for c in 0..2 {
                let (a, sa) = t.eval_with_slope(c, x - 1e-9).unwrap();
                let (b, sb) = t.eval_with_slope(c, x + 1e-9).unwrap();
                assert!((a - b).abs() <= 1e-7, "{c} {x}");
                // Values are O(1): 2e-9 apart, the slopes may differ by y''·2e-9 only.
                assert!((sa - sb).abs() <= 1e-7, "{c} {x}: {sa} {sb}");
            }
        }
    }

    #[test]
    fn monotone_data_stays_monotone() {
        // A decreasing positive curve (like P or A_r above h* = 0) on a coarse grid.
        let f = |x: f64| -> Result<Sample, ContactError> {
            let y = (-x).exp() / (1.0 + x * x);
            let dy = -y - y * 2.0 * x / (1.0 + x * x);
            Ok(Sample {
                value: vec![y],
                derivative: vec![dy],
            })
        };
        let t = ForceTable::build(&[("p", Interp::Log)], 0.0, 10.0, 0.2, f).unwrap();
        let mut prev = f64::INFINITY;
        for k in 0..=10_000 {
            let y = t.eval(0, k as f64 * 1e-3).unwrap();
            assert!(y < prev, "{k}");
            prev = y;
        }
    }

    #[test]
    fn inverse_of_a_decreasing_channel() {
        let f = |x: f64| -> Result<Sample, ContactError> {
            let y = (-x).exp() / (1.0 + x * x);
            let dy = -y - y * 2.0 * x / (1.0 + x * x);
            Ok(Sample {
                value: vec![y, -x],
                derivative: vec![dy, -1.0],
            })
        };
        let t = ForceTable::build(
            &[("p", Interp::Log), ("q", Interp::Linear)],
            0.0,
            10.0,
            0.05,
            f,
        )
        .unwrap();
        for k in 0..=400 {
            let x = k as f64 * 0.025;
            for c in 0..2 {
                let y = t.eval(c, x).unwrap();
                let back = t.invert_decreasing(c, y).unwrap();
                assert!((back - x).abs() < 1e-10, "{c}: {x} → {y} → {back}");
            }
        }
        assert!(t.invert_decreasing(0, 2.0).is_none());
        assert!(t.invert_decreasing(0, -1.0).is_none());
        assert!(t.invert_decreasing(0, f64::NAN).is_none());
        assert!(t.invert_decreasing(5, 0.5).is_none());
    }

    /// The bracket index changes where the search starts, never its answer: every inversion
    /// equals the whole-table bisection's, bit for bit, on a channel steep in places and flat
    /// in others (uneven nodes per bucket).
    #[test]
    fn indexed_inversion_equals_the_whole_table_search() {
        let f = |x: f64| -> Result<Sample, ContactError> {
            let steep = (-x * x * x - x).exp();
            let flat = 1e-3 * (-x).exp();
            Ok(Sample {
                value: vec![steep + flat],
                derivative: vec![-(3.0 * x * x + 1.0) * steep - flat],
            })
        };
        let t = ForceTable::build(&[("p", Interp::Log)], -2.0, 3.0, 0.05, f).unwrap();
        assert!(t.channels[0].index.is_some());
        let mut plain = t.clone();
        plain.channels[0].index = None;
        let (y_top, y_bottom) = (t.eval(0, -2.0).unwrap(), t.eval(0, 3.0).unwrap());
        let steps = 20_000;
        for k in 0..=steps {
            // Log-uniform over the whole tabulated range, ends included.
            let y = y_top * (y_bottom / y_top).powf(k as f64 / steps as f64);
            let (a, b) = (t.invert_decreasing(0, y), plain.invert_decreasing(0, y));
            assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "{y}");
        }
        for node in &t.channels[0].nodes {
            let y = node[0].exp();
            assert_eq!(
                t.invert_decreasing(0, y).map(f64::to_bits),
                plain.invert_decreasing(0, y).map(f64::to_bits)
            );
        }
    }

    #[test]
    fn outside_the_table_and_bad_input() {
        let t = table(0.5);
        assert!(t.eval(0, -4.1).is_none() && t.eval(0, 10.1).is_none());
        assert!(t.eval(0, f64::NAN).is_none());
        assert!(t.eval(7, 0.0).is_none());
        assert_eq!(t.channel("wave"), Some(1));
        assert!(ForceTable::build(&[("a", Interp::Log)], 1.0, 0.0, 0.1, curves).is_err());
        assert!(ForceTable::build(&[("a", Interp::Log)], 0.0, 1.0, 0.0, curves).is_err());
        // The wave changes sign: log interpolation must refuse it.
        let e = ForceTable::build(
            &[("x", Interp::Log), ("y", Interp::Log)],
            -4.0,
            4.0,
            0.1,
            curves,
        )
        .unwrap_err();
        assert!(e.to_string().contains("must stay > 0"), "{e}");
        let nan = |_x: f64| -> Result<Sample, ContactError> {
            Ok(Sample {
                value: vec![f64::NAN],
                derivative: vec![0.0],
            })
        };
        assert!(ForceTable::build(&[("n", Interp::Linear)], 0.0, 1.0, 0.1, nan).is_err());
    }
}
