//! Iso-lines of a surface sampled on a rectangular grid: marching squares with the
//! asymptotic decider, nice contour levels, and bilinear interpolation/refinement of the grid
//! (so that iso-lines and a banded fill agree). No drawing here; the DOE contour panels
//! (Figs 2.26–2.28) draw with it.

use super::usable;
use ndarray::ArrayView2;
use std::collections::HashMap;

/// An iso-line in data coordinates; a closed one repeats its first point at the end.
pub type Polyline = Vec<(f64, f64)>;

/// About this many contour levels over the whole value range (before the negative range is
/// doubled).
const TARGET_LEVELS: f64 = 10.0;

/// One of the four edges of a grid cell: `H(j, i)` joins nodes (j, i)–(j, i+1), `V(j, i)`
/// joins (j, i)–(j+1, i). Segments that cross the same edge meet at the same point, which is
/// how they are chained into polylines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Edge {
    H(usize, usize),
    V(usize, usize),
}

/// Iso-lines `z = level` of a gridded surface by marching squares, chained into polylines
/// (closed ones end on their first point). `z` has shape `(y.len(), x.len())`, `z[[j, i]]` at
/// `(x[i], y[j])`; a node counts as inside when `z ≥ level`. Cells with a non-finite corner
/// are skipped, so lines end at holes. The ambiguous saddle cells (diagonal corners on the
/// same side) are resolved with the asymptotic decider — the value of the bilinear
/// interpolant at its saddle point — which gives the topology of the bilinear surface rather
/// than an arbitrary choice. A shape mismatch, a grid smaller than 2 × 2 or a non-finite
/// level gives no lines.
pub fn marching_squares(x: &[f64], y: &[f64], z: ArrayView2<f64>, level: f64) -> Vec<Polyline> {
    let (ny, nx) = z.dim();
    if nx < 2 || ny < 2 || x.len() != nx || y.len() != ny || !usable(level) {
        return Vec::new();
    }
    let node = |j: usize, i: usize| z[[j, i]];
    let point = |e: Edge| -> (f64, f64) {
        let ((ja, ia), (jb, ib)) = match e {
            Edge::H(j, i) => ((j, i), (j, i + 1)),
            Edge::V(j, i) => ((j, i), (j + 1, i)),
        };
        let (za, zb) = (node(ja, ia), node(jb, ib));
        // One end is ≥ level and the other < level, so za ≠ zb.
        let t = ((level - za) / (zb - za)).clamp(0.0, 1.0);
        (x[ia] + t * (x[ib] - x[ia]), y[ja] + t * (y[jb] - y[ja]))
    };
    let mut segments: Vec<(Edge, Edge)> = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            // Corners counter-clockwise from bottom-left; edge k joins corners k and k+1.
            let c = [
                node(j, i),
                node(j, i + 1),
                node(j + 1, i + 1),
                node(j + 1, i),
            ];
            if !c.iter().all(|&v| usable(v)) {
                continue;
            }
            let inside = c.map(|v| v >= level);
            let edges = [
                Edge::H(j, i),
                Edge::V(j, i + 1),
                Edge::H(j + 1, i),
                Edge::V(j, i),
            ];
            let cut: Vec<Edge> = (0..4)
                .filter(|&k| inside[k] != inside[(k + 1) % 4])
                .map(|k| edges[k])
                .collect();
            match cut.len() {
                2 => segments.push((cut[0], cut[1])),
                4 => {
                    // Saddle: the corners on the other side from the centre are cut off one
                    // by one (corner k lies between edges k−1 and k).
                    let den = c[0] + c[2] - c[1] - c[3];
                    let saddle = if den != 0.0 {
                        (c[0] * c[2] - c[1] * c[3]) / den
                    } else {
                        0.25 * c.iter().sum::<f64>()
                    };
                    let centre_inside = saddle >= level;
                    for k in 0..4 {
                        if inside[k] != centre_inside {
                            segments.push((edges[(k + 3) % 4], edges[k]));
                        }
                    }
                }
                _ => {}
            }
        }
    }
    chain_segments(&segments)
        .into_iter()
        .map(|chain| chain.into_iter().map(point).collect())
        .collect()
}

/// Joins segments that share an edge into maximal chains. Every edge is crossed by at most
/// two segments (one per adjacent cell), so the chains are unambiguous.
fn chain_segments(segments: &[(Edge, Edge)]) -> Vec<Vec<Edge>> {
    let mut at: HashMap<Edge, Vec<usize>> = HashMap::new();
    for (k, &(a, b)) in segments.iter().enumerate() {
        at.entry(a).or_default().push(k);
        at.entry(b).or_default().push(k);
    }
    let mut used = vec![false; segments.len()];
    // Follow unused segments from edge `e`, returning the edges reached in order.
    let walk = |mut e: Edge, used: &mut Vec<bool>| {
        let mut out = Vec::new();
        while let Some(k) = at[&e].iter().copied().find(|&k| !used[k]) {
            used[k] = true;
            let (p, q) = segments[k];
            e = if p == e { q } else { p };
            out.push(e);
        }
        out
    };
    let mut chains = Vec::new();
    for start in 0..segments.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let (a, b) = segments[start];
        let forward = walk(b, &mut used);
        // A closed loop has come back to `a`, which then has no unused segment left.
        let backward = walk(a, &mut used);
        let mut chain: Vec<Edge> = backward.into_iter().rev().collect();
        chain.push(a);
        chain.push(b);
        chain.extend(forward);
        chains.push(chain);
    }
    chains
}

/// A "nice" step (1, 2, 2.5 or 5 × 10ⁿ) that divides `span` into the count closest to
/// `target`.
fn nice_step(span: f64, target: f64) -> f64 {
    let e = (span / target).log10().floor();
    let mut best = (f64::INFINITY, span / target);
    for de in [-1.0, 0.0, 1.0] {
        for m in [1.0, 2.0, 2.5, 5.0] {
            let step = m * 10f64.powf(e + de);
            let miss = ((span / step).floor() - target).abs();
            if miss < best.0 {
                best = (miss, step);
            }
        }
    }
    best.1
}

/// Contour levels strictly inside `(lo, hi)`: multiples of a nice step chosen for about ten
/// levels over the range, at half that step below zero — the dissertation draws the ξ < 0
/// region (where the design works) with denser contours. Zero, when inside, is a level.
/// A constant (or numerically constant) range has no levels.
pub(crate) fn contour_levels(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    let scale = lo.abs().max(hi.abs());
    if !(usable(lo) && usable(hi) && span.is_finite()) || span <= 0.0 || span <= scale * 1e-9 {
        return Vec::new();
    }
    let half = 0.5 * nice_step(span, TARGET_LEVELS);
    let (k0, k1) = ((lo / half).floor() as i64, (hi / half).ceil() as i64);
    (k0..=k1)
        .map(|k| (k, k as f64 * half))
        .filter(|&(k, v)| v > lo && v < hi && (v < 0.0 || k % 2 == 0))
        .map(|(_, v)| v)
        .collect()
}

/// Cell of a sorted grid holding `v`: `(i0, i1, t)` with `v ≈ g[i0] + t·(g[i1] − g[i0])`,
/// `t` clamped to [0, 1] (values outside the grid take the edge value). A single node is its
/// own cell.
pub(crate) fn locate(g: &[f64], v: f64) -> (usize, usize, f64) {
    let n = g.len();
    if n < 2 {
        return (0, 0, 0.0);
    }
    let i = g.partition_point(|&a| a <= v).clamp(1, n - 1) - 1;
    let t = ((v - g[i]) / (g[i + 1] - g[i])).clamp(0.0, 1.0);
    (i, i + 1, t)
}

/// Bilinear interpolation in a located cell. Only corners with a positive weight count: a
/// point on a cell edge needs only that edge's nodes, a point inside a cell with a NaN
/// corner has no value (so the fill and the iso-lines leave the same holes).
pub(crate) fn bilinear(
    z: &ArrayView2<f64>,
    (i0, i1, t): (usize, usize, f64),
    (j0, j1, u): (usize, usize, f64),
) -> f64 {
    let corners = [
        ((j0, i0), (1.0 - t) * (1.0 - u)),
        ((j0, i1), t * (1.0 - u)),
        ((j1, i0), (1.0 - t) * u),
        ((j1, i1), t * u),
    ];
    let mut acc = 0.0;
    for (idx, w) in corners {
        if w > 0.0 {
            let v = z[idx];
            if !usable(v) {
                return f64::NAN;
            }
            acc += w * v;
        }
    }
    acc
}

/// `g` with every interval split evenly so that it has at least about `target` nodes; the
/// original nodes are kept exactly.
pub(crate) fn refine(g: &[f64], target: usize) -> Vec<f64> {
    let n = g.len();
    if n < 2 || n >= target {
        return g.to_vec();
    }
    let r = (target - 1).div_ceil(n - 1);
    let mut out = Vec::with_capacity((n - 1) * r + 1);
    for w in g.windows(2) {
        out.extend((0..r).map(|s| w[0] + (w[1] - w[0]) * s as f64 / r as f64));
    }
    out.push(g[n - 1]);
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use ndarray::Array2;

    pub(crate) fn grid(lo: f64, hi: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| lo + (hi - lo) * k as f64 / (n - 1) as f64)
            .collect()
    }

    pub(crate) fn surface(x: &[f64], y: &[f64], f: impl Fn(f64, f64) -> f64) -> Array2<f64> {
        Array2::from_shape_fn((y.len(), x.len()), |(j, i)| f(x[i], y[j]))
    }

    fn is_closed(l: &Polyline) -> bool {
        l.len() > 3 && l.first() == l.last()
    }

    #[test]
    fn cone_gives_closed_circles() {
        let g = grid(-2.0, 2.0, 41);
        let h = 0.1;
        let z = surface(&g, &g, |x, y| x * x + y * y);
        for level in [0.25, 1.0, 3.0] {
            let lines = marching_squares(&g, &g, z.view(), level);
            assert_eq!(lines.len(), 1, "level {level}");
            let l = &lines[0];
            assert!(is_closed(l), "level {level}: not closed");
            // Linear interpolation of r² along an edge is off by at most h²/4 in z.
            let r = level.sqrt();
            for &(x, y) in l {
                let d = ((x * x + y * y).sqrt() - r).abs();
                assert!(
                    d < h * h / (4.0 * r) + 1e-12,
                    "level {level}: |r − √level| = {d}"
                );
            }
            // The whole circle is there: its polygon area is close to πr².
            let area: f64 = 0.5
                * l.windows(2)
                    .map(|w| w[0].0 * w[1].1 - w[1].0 * w[0].1)
                    .sum::<f64>()
                    .abs();
            let exact = std::f64::consts::PI * level;
            assert!(
                (area - exact).abs() < 0.02 * exact,
                "level {level}: {area} vs {exact}"
            );
        }
        // A circle that leaves the grid: four open arcs, ending on the boundary.
        let lines = marching_squares(&g, &g, z.view(), 5.0);
        assert_eq!(lines.len(), 4);
        for l in &lines {
            assert!(!is_closed(l));
            for &(x, y) in [l[0], l[l.len() - 1]].iter() {
                assert!((x.abs() - 2.0).abs() < 1e-12 || (y.abs() - 2.0).abs() < 1e-12);
            }
        }
        // Outside the range: nothing.
        assert!(marching_squares(&g, &g, z.view(), 9.0).is_empty());
        assert!(marching_squares(&g, &g, z.view(), -1.0).is_empty());
    }

    #[test]
    fn saddle_cell_follows_the_bilinear_surface() {
        // z = xy on one cell: diagonal corners equal, the saddle value at the centre is 0.
        let g = [-1.0, 1.0];
        let z = surface(&g, &g, |x, y| x * y);
        let ends = |l: &Polyline| {
            let mut e = [l[0], l[l.len() - 1]];
            e.sort_by(|a, b| a.partial_cmp(b).unwrap());
            e
        };
        let close =
            |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12;
        // Level 0.2: the hyperbola branches in quadrants III and I (the corners at z = 1 are
        // cut off); level −0.2: quadrants II and IV.
        let expected = [
            (
                0.2,
                [[(-1.0, -0.2), (-0.2, -1.0)], [(0.2, 1.0), (1.0, 0.2)]],
            ),
            (
                -0.2,
                [[(-1.0, 0.2), (-0.2, 1.0)], [(0.2, -1.0), (1.0, -0.2)]],
            ),
        ];
        for (level, want) in expected {
            let mut got: Vec<_> = marching_squares(&g, &g, z.view(), level)
                .iter()
                .map(ends)
                .collect();
            got.sort_by(|a, b| a.partial_cmp(b).unwrap());
            assert_eq!(got.len(), 2, "level {level}");
            for (e, w) in got.iter().zip(&want) {
                assert!(
                    close(e[0], w[0]) && close(e[1], w[1]),
                    "level {level}: {got:?}"
                );
            }
        }

        // z = x² − y² on a grid with the saddle inside: hyperbola points, no branch crossing.
        let g = grid(-1.0, 1.0, 20);
        let z = surface(&g, &g, |x, y| x * x - y * y);
        for level in [0.3, -0.3] {
            let lines = marching_squares(&g, &g, z.view(), level);
            assert_eq!(lines.len(), 2, "level {level}");
            for l in &lines {
                assert!(!is_closed(l));
                let side = if level > 0.0 {
                    l[0].0.signum()
                } else {
                    l[0].1.signum()
                };
                for &(x, y) in l {
                    assert!((x * x - y * y - level).abs() < 0.02, "({x}, {y})");
                    let s = if level > 0.0 { x.signum() } else { y.signum() };
                    assert_eq!(s, side, "a branch crosses the saddle");
                }
            }
        }
    }

    #[test]
    fn marching_squares_skips_holes_and_bad_input() {
        let g = grid(-2.0, 2.0, 41);
        let mut z = surface(&g, &g, |x, y| x * x + y * y);
        // A NaN node on the unit circle's path breaks the loop into one open line.
        z[[20, 30]] = f64::NAN;
        let lines = marching_squares(&g, &g, z.view(), 1.0);
        assert_eq!(lines.len(), 1);
        assert!(!is_closed(&lines[0]));
        assert!(lines[0]
            .iter()
            .all(|&(x, y)| (x - 1.0).abs() > 0.05 || y.abs() > 0.05));
        // Shape mismatch, too small a grid, non-finite level: no lines, no panic.
        assert!(marching_squares(&g[..40], &g, z.view(), 1.0).is_empty());
        let one = Array2::from_elem((1, 3), 1.0);
        assert!(marching_squares(&[0.0, 1.0, 2.0], &[0.0], one.view(), 1.0).is_empty());
        assert!(marching_squares(&g, &g, z.view(), f64::NAN).is_empty());
    }

    #[test]
    fn levels_are_nice_and_denser_below_zero() {
        let l = contour_levels(-1.0, 1.0);
        let neg = l.iter().filter(|&&v| v < 0.0).count();
        let pos = l.iter().filter(|&&v| v > 0.0).count();
        assert!(l.contains(&0.0));
        assert!(neg >= 2 * pos - 1 && pos >= 3, "{l:?}");
        assert!(l.windows(2).all(|w| w[1] > w[0]));
        let l = contour_levels(3.0, 17.0);
        assert!((7..=13).contains(&l.len()), "{l:?}");
        assert!(l.iter().all(|&v| v > 3.0 && v < 17.0));
        assert!(contour_levels(2.0, 2.0).is_empty());
        assert!(contour_levels(0.0, 0.0).is_empty());
        assert!(contour_levels(f64::NAN, 1.0).is_empty());
        // All negative: the whole range at the dense spacing.
        let l = contour_levels(-2.0, -1.0);
        assert!(l.len() >= 15, "{l:?}");
    }

    #[test]
    fn refine_and_bilinear_keep_nodes_and_holes() {
        let g = [0.0, 1.0, 3.0];
        assert_eq!(refine(&g, 5), vec![0.0, 0.5, 1.0, 2.0, 3.0]);
        assert_eq!(refine(&g, 7).len(), 7);
        assert_eq!(refine(&g, 3), g.to_vec());
        let mut z = Array2::from_shape_fn((2, 3), |(j, i)| (i + 10 * j) as f64);
        z[[1, 2]] = f64::NAN;
        let v = z.view();
        let at = |x: f64, y: f64| bilinear(&v, locate(&g, x), locate(&[0.0, 1.0], y));
        assert_eq!(at(0.5, 0.5), 5.5);
        assert_eq!(at(1.0, 1.0), 11.0);
        // On the shared edge x = 1 the NaN corner has no weight; inside its cell it has.
        assert_eq!(at(1.0, 0.5), 6.0);
        assert!(at(2.0, 0.5).is_nan());
        assert_eq!(at(2.0, 0.0), 1.5);
    }
}
