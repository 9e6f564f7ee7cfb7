//! The thermal-flying-control (TFC) bulge from stylus-profilometer scans (dissertation App. C.2,
//! docs/bulge.md): level with a plane fitted outside the bulge (user exclusion rectangles plus an
//! automatically detected trailing-edge drop and its "pull-up" artifact), fit the ellipsoidal cap
//! `z = h·√(1 − ((x−x_c)/a)² − ((y−y_c)/(w/2))²)` of docs/dynamics-geometry.md by
//! Levenberg–Marquardt, and fit bulge height against heater power (the efficiency, nm/mW).
//!
//! Conventions as in the rest of `surface`: `z[[j, i]]`, column `i` = x (the scan direction,
//! along the slider), row `j` = y (between scan lines); dx ≠ dy is normal here (0.5 µm along
//! the scan, 1 µm between lines in App. C.2).

use super::io::profile::LineProfile;
use super::{HeightMap, Result, SourceInfo, SurfaceError};
use crate::numerics::rng::Rng;
use nalgebra::{DMatrix, DVector};
use ndarray::Array2;

/// A rectangle excluded from levelling and fitting, metres from the first pixel (x = i·dx
/// along a scan line, y = j·dy down from the top row, as `crop` in docs/surfaces.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub x0: f64,
    pub y0: f64,
    pub width: f64,
    pub height: f64,
}

impl Rect {
    fn contains(&self, x: f64, y: f64) -> bool {
        x >= self.x0 && x <= self.x0 + self.width && y >= self.y0 && y <= self.y0 + self.height
    }
}

/// Options of the bulge fit.
#[derive(Debug, Clone)]
pub struct BulgeOptions {
    /// Rectangles left out of levelling and fitting.
    pub exclude: Vec<Rect>,
    /// Detect the trailing-edge drop and mask it (with the pull-up before it) to the map edge.
    pub auto_te: bool,
    /// How far before the detected edge the mask starts (covers the pull-up), metres.
    pub te_margin: f64,
}

impl Default for BulgeOptions {
    fn default() -> Self {
        Self {
            exclude: Vec::new(),
            auto_te: true,
            te_margin: 2.0e-6,
        }
    }
}

/// Where the trailing edge was found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrailingEdge {
    /// x of the drop (between the two columns of the steepest step), metres from the first
    /// pixel.
    pub x: f64,
    /// `true` if the slider lies at smaller x than the edge (the surface falls going +x).
    pub slider_below: bool,
}

/// One fitted scan. Lengths and heights in metres; `*_se` are standard errors from
/// σ²(JᵀJ)⁻¹ at the optimum.
#[derive(Debug, Clone)]
pub struct BulgeFit {
    pub height: f64,
    pub height_se: f64,
    /// Half-length along the slider (x).
    pub a: f64,
    pub a_se: f64,
    /// Full width across the slider (y).
    pub w: f64,
    pub w_se: f64,
    /// Centre, metres from the first pixel.
    pub xc: f64,
    pub xc_se: f64,
    pub yc: f64,
    pub yc_se: f64,
    /// Constant offset of the levelled map under the cap.
    pub offset: f64,
    /// Distance of the centre from the trailing edge (x_TFC), if an edge was found.
    pub x_tfc: Option<f64>,
    pub trailing_edge: Option<TrailingEdge>,
    pub residual_rms: f64,
    /// Pixels used by the fit.
    pub n_pixels: usize,
    pub iterations: usize,
    /// The levelled map (plane fitted outside the bulge removed), invalid pixels marked;
    /// `None` for a fit of line scans.
    pub levelled: Option<HeightMap>,
    /// The levelled line scans of a line-scan fit (empty for a map).
    pub lines: Vec<LevelledLine>,
}

/// One line scan at a stated lateral offset from the bulge centre (docs/bulge.md "Line
/// scans"): x along the slider as the profile gives it, heights in metres.
#[derive(Debug, Clone)]
pub struct OffsetLine {
    pub profile: LineProfile,
    /// Distance of the line from the bulge centre across the slider, metres.
    pub offset: f64,
}

/// A line scan after levelling: its own straight line fitted outside the bulge removed;
/// points left out of the fit (invalid, masked, excluded) are NaN.
#[derive(Debug, Clone)]
pub struct LevelledLine {
    pub offset: f64,
    pub x: Vec<f64>,
    pub z: Vec<f64>,
}

/// Plane `c0 + cx·x + cy·y` by least squares over the `use_px` pixels.
fn fit_plane(map: &HeightMap, use_px: &Array2<bool>) -> Option<[f64; 3]> {
    let mut ata = nalgebra::Matrix3::<f64>::zeros();
    let mut atb = nalgebra::Vector3::<f64>::zeros();
    for ((j, i), &ok) in use_px.indexed_iter() {
        if !ok {
            continue;
        }
        let r = nalgebra::Vector3::new(1.0, i as f64 * map.dx, j as f64 * map.dy);
        ata += r * r.transpose();
        atb += r * map.z[[j, i]];
    }
    let c = ata.lu().solve(&atb)?;
    c.iter().all(|v| v.is_finite()).then(|| [c[0], c[1], c[2]])
}

/// Find the trailing-edge drop: the column step whose median (over lines) height difference is
/// largest and stands far above the typical step (App. C.2: the edge is a drop of tens of nm or
/// more within a pixel or two, much steeper than the bulge flanks).
pub fn detect_trailing_edge(map: &HeightMap) -> Option<TrailingEdge> {
    let (ny, nx) = map.z.dim();
    if nx < 4 || ny == 0 {
        return None;
    }
    let mut med = Vec::with_capacity(nx - 1);
    for i in 0..nx - 1 {
        let mut d: Vec<f64> = (0..ny)
            .filter(|&j| map.is_valid(j, i) && map.is_valid(j, i + 1))
            .map(|j| map.z[[j, i + 1]] - map.z[[j, i]])
            .filter(|v| v.is_finite())
            .collect();
        if d.is_empty() {
            med.push(0.0);
            continue;
        }
        d.sort_by(f64::total_cmp);
        med.push(d[d.len() / 2]);
    }
    let (imax, step) = med
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map(|(i, v)| (i, *v))?;
    let mut abs: Vec<f64> = med.iter().map(|v| v.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let typical = abs[abs.len() / 2];
    // A drop is at least 20 typical steps and 5 nm: noise and the bulge flanks are not.
    if step.abs() < (20.0 * typical).max(5e-9) {
        return None;
    }
    Some(TrailingEdge {
        x: (imax as f64 + 0.5) * map.dx,
        slider_below: step < 0.0,
    })
}

/// Pixels usable for levelling and fitting: valid, finite, outside the exclusion rectangles
/// and on the slider side of the trailing edge (minus the margin).
fn usable_pixels(map: &HeightMap, opts: &BulgeOptions, te: Option<TrailingEdge>) -> Array2<bool> {
    let (ny, nx) = map.z.dim();
    Array2::from_shape_fn((ny, nx), |(j, i)| {
        let x = i as f64 * map.dx;
        let y = j as f64 * map.dy;
        let te_ok = match te {
            None => true,
            Some(t) if t.slider_below => x < t.x - opts.te_margin,
            Some(t) => x > t.x + opts.te_margin,
        };
        te_ok
            && map.is_valid(j, i)
            && map.z[[j, i]].is_finite()
            && !opts.exclude.iter().any(|r| r.contains(x, y))
    })
}

/// The cap model and its Jacobian row at one pixel. Parameters
/// `p = [h, a, w, x_c, y_c, offset]` (x, y relative to the map origin).
fn cap(p: &[f64; 6], x: f64, y: f64) -> (f64, [f64; 6]) {
    let [h, a, w, xc, yc, _] = *p;
    let u = (x - xc) / a;
    let v = 2.0 * (y - yc) / w;
    let q = 1.0 - u * u - v * v;
    if q <= 0.0 {
        return (p[5], [0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    }
    let s = q.sqrt();
    // The flank slope diverges at the rim; cap 1/s (at s = 0.05, 0.1 % of the area) so the
    // rim pixels do not dominate JᵀJ.
    let inv = 1.0 / s.max(0.05);
    (
        p[5] + h * s,
        [
            s,
            h * u * u / a * inv,
            h * v * v / w * inv,
            h * u / a * inv,
            h * 2.0 * v / w * inv,
            1.0,
        ],
    )
}

struct LmResult {
    p: [f64; 6],
    cov_unscaled: DMatrix<f64>,
    sse: f64,
    iterations: usize,
}

/// Levenberg–Marquardt (Marquardt's diagonal scaling) on the cap model over `pts` = (x, y, z).
/// Parameters with `free[k] == false` stay at `p0[k]` (their rows and columns of JᵀJ are
/// the identity, their gradient zero).
fn levenberg_marquardt(pts: &[(f64, f64, f64)], p0: [f64; 6], free: [bool; 6]) -> Option<LmResult> {
    let sse_of = |p: &[f64; 6]| -> f64 {
        pts.iter()
            .map(|&(x, y, z)| {
                let r = z - cap(p, x, y).0;
                r * r
            })
            .sum()
    };
    let normal = |p: &[f64; 6]| -> (DMatrix<f64>, DVector<f64>) {
        let mut jtj = DMatrix::<f64>::zeros(6, 6);
        let mut jtr = DVector::<f64>::zeros(6);
        for &(x, y, z) in pts {
            let (m, g) = cap(p, x, y);
            let r = z - m;
            for k in 0..6 {
                jtr[k] += g[k] * r;
                for l in 0..6 {
                    jtj[(k, l)] += g[k] * g[l];
                }
            }
        }
        for k in (0..6).filter(|&k| !free[k]) {
            jtr[k] = 0.0;
            for l in 0..6 {
                jtj[(k, l)] = 0.0;
                jtj[(l, k)] = 0.0;
            }
            jtj[(k, k)] = 1.0;
        }
        (jtj, jtr)
    };
    let mut p = p0;
    let mut sse = sse_of(&p);
    let mut lambda = 1e-3;
    let mut iterations = 0;
    for it in 0..200 {
        iterations = it + 1;
        let (jtj, jtr) = normal(&p);
        let mut improved = false;
        for _ in 0..30 {
            let mut m = jtj.clone();
            for k in 0..6 {
                m[(k, k)] += lambda * jtj[(k, k)].max(1e-300);
            }
            let Some(step) = m.lu().solve(&jtr) else {
                lambda *= 10.0;
                continue;
            };
            let mut trial = p;
            for k in 0..6 {
                trial[k] += step[k];
            }
            if trial[1] <= 0.0 || trial[2] <= 0.0 {
                lambda *= 10.0;
                continue;
            }
            let s = sse_of(&trial);
            if s.is_finite() && s < sse {
                let rel = (sse - s) / sse.max(1e-300);
                p = trial;
                sse = s;
                lambda = (lambda / 10.0).max(1e-12);
                improved = rel > 1e-12;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let (jtj, _) = normal(&p);
    let cov_unscaled = jtj.try_inverse()?;
    Some(LmResult {
        p,
        cov_unscaled,
        sse,
        iterations,
    })
}

/// Half-extent of the part of `profile` above half of `peak`, walking out from `k0`.
fn half_max_extent(profile: &[f64], k0: usize, peak: f64) -> usize {
    let mut lo = k0;
    while lo > 0 && profile[lo - 1] > peak / 2.0 {
        lo -= 1;
    }
    let mut hi = k0;
    while hi + 1 < profile.len() && profile[hi + 1] > peak / 2.0 {
        hi += 1;
    }
    (hi - lo + 1).div_ceil(2).max(1)
}

/// Level `map` (plane over `use_px`) and return the levelled copy.
fn levelled_copy(map: &HeightMap, use_px: &Array2<bool>, plane: [f64; 3]) -> HeightMap {
    let mut out = map.clone();
    for ((j, i), z) in out.z.indexed_iter_mut() {
        *z -= plane[0] + plane[1] * i as f64 * map.dx + plane[2] * j as f64 * map.dy;
    }
    out.valid = Some(use_px.clone());
    out
}

/// Fit the bulge of one profilometer map (the full procedure of docs/bulge.md).
pub fn fit_bulge(map: &HeightMap, opts: &BulgeOptions) -> Result<BulgeFit> {
    let (ny, nx) = map.z.dim();
    if nx < 8 || ny < 3 {
        return Err(SurfaceError::InvalidData(format!(
            "bulge fit needs at least 8 × 3 pixels, the map has {nx} × {ny}"
        )));
    }
    if !(map.dx > 0.0 && map.dy > 0.0) {
        return Err(SurfaceError::InvalidData(
            "bulge fit needs positive pixel spacings".into(),
        ));
    }
    let te = if opts.auto_te {
        detect_trailing_edge(map)
    } else {
        None
    };
    let usable = usable_pixels(map, opts, te);
    let n_usable = usable.iter().filter(|v| **v).count();
    if n_usable < 50 {
        return Err(SurfaceError::InvalidData(format!(
            "only {n_usable} usable pixels left after masking (exclusions and trailing edge)"
        )));
    }
    // Pass 1: plane through everything usable, then clip what sticks up (the bulge) and refit.
    let no_plane = || SurfaceError::InvalidData("levelling plane is singular".into());
    let mut outside = usable.clone();
    let mut plane = fit_plane(map, &outside).ok_or_else(no_plane)?;
    let mut sigma = 0.0;
    for _ in 0..5 {
        let lev = levelled_copy(map, &usable, plane);
        let vals: Vec<f64> = outside
            .indexed_iter()
            .filter(|(_, ok)| **ok)
            .map(|(ji, _)| lev.z[ji])
            .collect();
        let mut sorted: Vec<f64> = vals.iter().map(|v| v.abs()).collect();
        sorted.sort_by(f64::total_cmp);
        let mad = sorted[sorted.len() / 2].max(1e-15);
        sigma = 1.4826 * mad;
        let mut next = usable.clone();
        for (ji, ok) in next.indexed_iter_mut() {
            if *ok && lev.z[ji] > 3.0 * 1.4826 * mad {
                *ok = false;
            }
        }
        if next.iter().filter(|v| **v).count() < 20 {
            break;
        }
        outside = next;
        plane = fit_plane(map, &outside).ok_or_else(no_plane)?;
    }
    let mut lev = levelled_copy(map, &usable, plane);
    let mut fit = None;
    // Pass 2 and 3: locate/fit, then relevel outside the fitted ellipse (enlarged by 25 %) and
    // refit, so the plane is not pulled by the bulge flanks.
    for pass in 0..2 {
        let p0 = match &fit {
            Some(r) => {
                let r: &LmResult = r;
                r.p
            }
            None => initial_guess(&lev, &usable, 5.0 * sigma)?,
        };
        let pts: Vec<(f64, f64, f64)> = usable
            .indexed_iter()
            .filter(|(_, ok)| **ok)
            .map(|((j, i), _)| (i as f64 * map.dx, j as f64 * map.dy, lev.z[[j, i]]))
            .collect();
        let r = levenberg_marquardt(&pts, p0, [true; 6]).ok_or_else(|| {
            SurfaceError::InvalidData("bulge fit did not converge (singular Jacobian)".into())
        })?;
        if pass == 0 {
            let [_, a, w, xc, yc, _] = r.p;
            let mut out2 = usable.clone();
            for ((j, i), ok) in out2.indexed_iter_mut() {
                let u = (i as f64 * map.dx - xc) / (1.25 * a);
                let v = 2.0 * (j as f64 * map.dy - yc) / (1.25 * w);
                if u * u + v * v < 1.0 {
                    *ok = false;
                }
            }
            if out2.iter().filter(|v| **v).count() >= 20 {
                plane = fit_plane(map, &out2).ok_or_else(no_plane)?;
                lev = levelled_copy(map, &usable, plane);
            }
        }
        fit = Some(r);
    }
    let Some(r) = fit else {
        return Err(SurfaceError::InvalidData("bulge fit failed".into()));
    };
    let n = n_usable;
    let dof = n.saturating_sub(6).max(1) as f64;
    let s2 = r.sse / dof;
    let se = |k: usize| (s2 * r.cov_unscaled[(k, k)]).max(0.0).sqrt();
    let [h, a, w, xc, yc, offset] = r.p;
    if !(h > 0.0 && a > 0.0 && w > 0.0) {
        return Err(SurfaceError::InvalidData(format!(
            "no bulge found: fitted height {:.3} nm",
            h * 1e9
        )));
    }
    Ok(BulgeFit {
        height: h,
        height_se: se(0),
        a,
        a_se: se(1),
        w,
        w_se: se(2),
        xc,
        xc_se: se(3),
        yc,
        yc_se: se(4),
        offset,
        x_tfc: te.map(|t| (t.x - xc).abs()),
        trailing_edge: te,
        residual_rms: (r.sse / n as f64).sqrt(),
        n_pixels: n,
        iterations: r.iterations,
        levelled: Some(lev),
        lines: Vec::new(),
    })
}

/// Start values (a peak below `min_peak` is no bulge): the maximum of the 5 × 3-pixel box-smoothed levelled map, its height, and the
/// half-maximum extents through it (for the cap, z = h/2 at u = √3/2).
fn initial_guess(lev: &HeightMap, usable: &Array2<bool>, min_peak: f64) -> Result<[f64; 6]> {
    let (ny, nx) = lev.z.dim();
    let mut sm = Array2::<f64>::from_elem((ny, nx), f64::NEG_INFINITY);
    for j in 0..ny {
        for i in 0..nx {
            if !usable[[j, i]] {
                continue;
            }
            let (mut s, mut c) = (0.0, 0);
            for jj in j.saturating_sub(1)..(j + 2).min(ny) {
                for ii in i.saturating_sub(2)..(i + 3).min(nx) {
                    if usable[[jj, ii]] {
                        s += lev.z[[jj, ii]];
                        c += 1;
                    }
                }
            }
            sm[[j, i]] = s / c as f64;
        }
    }
    let ((jm, im), &peak) = sm
        .indexed_iter()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .ok_or_else(|| SurfaceError::InvalidData("empty map".into()))?;
    if !(peak.is_finite() && peak > min_peak) {
        return Err(SurfaceError::InvalidData(
            "no bulge found: nothing stands above the levelled plane".into(),
        ));
    }
    let row: Vec<f64> = (0..nx).map(|i| sm[[jm, i]]).collect();
    let col: Vec<f64> = (0..ny).map(|j| sm[[j, im]]).collect();
    let hx = half_max_extent(&row, im, peak) as f64 * lev.dx;
    let hy = half_max_extent(&col, jm, peak) as f64 * lev.dy;
    let k = 3f64.sqrt() / 2.0;
    Ok([
        peak,
        (hx / k).max(2.0 * lev.dx),
        (2.0 * hy / k).max(4.0 * lev.dy),
        im as f64 * lev.dx,
        jm as f64 * lev.dy,
        0.0,
    ])
}

/// The trailing edge of one line scan: the largest height step between neighbouring points in
/// `ok`, if it is at least 20 typical steps and 5 nm (the map's criterion, docs/bulge.md).
fn line_trailing_edge(x: &[f64], z: &[f64], ok: &[bool]) -> Option<TrailingEdge> {
    let idx: Vec<usize> = (0..x.len()).filter(|&k| ok[k]).collect();
    if idx.len() < 4 {
        return None;
    }
    // (midpoint, height step, position step) along the line.
    let steps: Vec<(f64, f64, f64)> = idx
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            ((x[a] + x[b]) / 2.0, z[b] - z[a], x[b] - x[a])
        })
        .collect();
    let (xe, step, run) = steps
        .iter()
        .copied()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))?;
    let mut abs: Vec<f64> = steps.iter().map(|s| s.1.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let typical = abs[abs.len() / 2];
    if step.abs() < (20.0 * typical).max(5e-9) {
        return None;
    }
    Some(TrailingEdge {
        x: xe,
        // The surface falls going +x off the slider.
        slider_below: step * run.signum() < 0.0,
    })
}

/// Straight line `c0 + c1·x` by least squares over the points in `use_pt`.
fn fit_line(x: &[f64], z: &[f64], use_pt: &[bool]) -> Option<[f64; 2]> {
    let (mut n, mut sx, mut sz, mut sxx, mut sxz) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for k in (0..x.len()).filter(|&k| use_pt[k]) {
        n += 1.0;
        sx += x[k];
        sz += z[k];
        sxx += x[k] * x[k];
        sxz += x[k] * z[k];
    }
    let det = n * sxx - sx * sx;
    if n < 2.0 || det.is_nan() || det.abs() <= 1e-30 * sxx.max(1e-300) * n {
        return None;
    }
    let c1 = (n * sxz - sx * sz) / det;
    let c0 = (sz - c1 * sx) / n;
    (c0.is_finite() && c1.is_finite()).then_some([c0, c1])
}

/// Fit the bulge cap to line scans at stated offsets from the bulge centre (docs/bulge.md
/// "Line scans"): the map procedure per line — trailing edge (median over the lines that show
/// one; the lines share the x axis), exclusions (`y` = the line's offset), a straight line
/// fitted outside the bulge removed from each line — then the same cap model evaluated along
/// each line at its offset (y_c = 0 by definition of the offsets). w is fitted when a line lies
/// off the centre; a centre line alone gives h, a and x_c, and w is NaN.
pub fn fit_bulge_lines(lines: &[OffsetLine], opts: &BulgeOptions) -> Result<BulgeFit> {
    if lines.is_empty() {
        return Err(SurfaceError::InvalidData("no line scans given".into()));
    }
    if let Some(l) = lines.iter().find(|l| !l.offset.is_finite()) {
        return Err(SurfaceError::InvalidData(format!(
            "line offset {} is not a finite length",
            l.offset
        )));
    }
    let fit_w = lines.iter().any(|l| l.offset != 0.0);
    // Valid and outside the exclusions, per line.
    let base: Vec<Vec<bool>> = lines
        .iter()
        .map(|l| {
            let p = &l.profile;
            (0..p.len())
                .map(|k| {
                    p.valid[k]
                        && p.z[k].is_finite()
                        && !opts.exclude.iter().any(|r| r.contains(p.x[k], l.offset))
                })
                .collect()
        })
        .collect();
    let te = if opts.auto_te {
        let found: Vec<TrailingEdge> = lines
            .iter()
            .zip(&base)
            .filter_map(|(l, ok)| line_trailing_edge(&l.profile.x, &l.profile.z, ok))
            .collect();
        (!found.is_empty()).then(|| {
            let mut xs: Vec<f64> = found.iter().map(|t| t.x).collect();
            xs.sort_by(f64::total_cmp);
            let below = found.iter().filter(|t| t.slider_below).count();
            TrailingEdge {
                x: xs[xs.len() / 2],
                slider_below: 2 * below >= found.len(),
            }
        })
    } else {
        None
    };
    let usable: Vec<Vec<bool>> = lines
        .iter()
        .zip(&base)
        .map(|(l, ok)| {
            l.profile
                .x
                .iter()
                .zip(ok)
                .map(|(&x, &ok)| {
                    ok && match te {
                        None => true,
                        Some(t) if t.slider_below => x < t.x - opts.te_margin,
                        Some(t) => x > t.x + opts.te_margin,
                    }
                })
                .collect()
        })
        .collect();
    let n_usable: usize = usable
        .iter()
        .map(|u| u.iter().filter(|v| **v).count())
        .sum();
    let n_free = if fit_w { 5 } else { 4 };
    if n_usable < 10 * n_free {
        return Err(SurfaceError::InvalidData(format!(
            "only {n_usable} usable points left on the line scans after masking (exclusions and \
             trailing edge)"
        )));
    }
    let no_line = || {
        SurfaceError::InvalidData(
            "levelling a line scan: fewer than two usable points outside the bulge".into(),
        )
    };
    let level = |planes: &[[f64; 2]]| -> Vec<Vec<f64>> {
        lines
            .iter()
            .zip(planes)
            .map(|(l, c)| {
                let p = &l.profile;
                p.x.iter()
                    .zip(&p.z)
                    .map(|(x, z)| z - c[0] - c[1] * x)
                    .collect()
            })
            .collect()
    };
    // The noise from neighbouring differences (robust, and blind to the smooth bulge, which
    // covers a large share of a line through it: the MAD about the line would not be).
    let mut diffs: Vec<f64> = lines
        .iter()
        .zip(&usable)
        .flat_map(|(l, u)| {
            (1..u.len())
                .filter(|&k| u[k] && u[k - 1])
                .map(|k| (l.profile.z[k] - l.profile.z[k - 1]).abs())
                .collect::<Vec<_>>()
        })
        .collect();
    if diffs.is_empty() {
        return Err(no_line());
    }
    diffs.sort_by(f64::total_cmp);
    let sigma = (1.4826 * diffs[diffs.len() / 2] / 2f64.sqrt()).max(1e-15);
    // Levelling: a line through everything usable on each scan line, then drop what sticks up
    // more than 3 σ (the bulge) and refit, until nothing changes (at most 20 rounds).
    let mut outside = usable.clone();
    let mut planes = lines
        .iter()
        .zip(&outside)
        .map(|(l, o)| fit_line(&l.profile.x, &l.profile.z, o).ok_or_else(no_line))
        .collect::<Result<Vec<_>>>()?;
    for _ in 0..20 {
        let lev = level(&planes);
        let next: Vec<Vec<bool>> = usable
            .iter()
            .zip(&lev)
            .map(|(u, z)| {
                u.iter()
                    .zip(z)
                    .map(|(u, z)| *u && *z <= 3.0 * sigma)
                    .collect()
            })
            .collect();
        if next == outside {
            break;
        }
        let refit: Option<Vec<[f64; 2]>> = lines
            .iter()
            .zip(&next)
            .map(|(l, o)| fit_line(&l.profile.x, &l.profile.z, o))
            .collect();
        let Some(refit) = refit else { break };
        outside = next;
        planes = refit;
    }
    let mut lev = level(&planes);
    let points = |lev: &[Vec<f64>]| -> Vec<(f64, f64, f64)> {
        let mut pts = Vec::with_capacity(n_usable);
        for ((l, u), z) in lines.iter().zip(&usable).zip(lev) {
            for k in (0..u.len()).filter(|&k| u[k]) {
                pts.push((l.profile.x[k], l.offset, z[k]));
            }
        }
        pts
    };
    let free = [true, true, fit_w, true, false, true];
    let mut fit: Option<LmResult> = None;
    for pass in 0..2 {
        let p0 = match &fit {
            Some(r) => r.p,
            None => line_initial_guess(lines, &usable, &lev, 5.0 * sigma, fit_w)?,
        };
        let r = levenberg_marquardt(&points(&lev), p0, free).ok_or_else(|| {
            SurfaceError::InvalidData("bulge fit did not converge (singular Jacobian)".into())
        })?;
        if pass == 0 {
            // Relevel outside the fitted cap enlarged by 25 %, as for maps.
            let [_, a, w, xc, _, _] = r.p;
            let out2: Vec<Vec<bool>> = lines
                .iter()
                .zip(&usable)
                .map(|(l, u)| {
                    let v = if fit_w {
                        2.0 * l.offset / (1.25 * w)
                    } else {
                        0.0
                    };
                    l.profile
                        .x
                        .iter()
                        .zip(u)
                        .map(|(x, u)| {
                            let q = (x - xc) / (1.25 * a);
                            *u && q * q + v * v >= 1.0
                        })
                        .collect()
                })
                .collect();
            let refit: Option<Vec<[f64; 2]>> = lines
                .iter()
                .zip(&out2)
                .map(|(l, o)| fit_line(&l.profile.x, &l.profile.z, o))
                .collect();
            if let Some(refit) = refit {
                planes = refit;
                lev = level(&planes);
            }
        }
        fit = Some(r);
    }
    let Some(r) = fit else {
        return Err(SurfaceError::InvalidData("bulge fit failed".into()));
    };
    let dof = n_usable.saturating_sub(n_free).max(1) as f64;
    let s2 = r.sse / dof;
    let se = |k: usize| {
        if free[k] {
            (s2 * r.cov_unscaled[(k, k)]).max(0.0).sqrt()
        } else {
            f64::NAN
        }
    };
    let [h, a, w, xc, _, offset] = r.p;
    if !(h > 0.0 && a > 0.0 && w > 0.0) {
        return Err(SurfaceError::InvalidData(format!(
            "no bulge found: fitted height {:.3} nm",
            h * 1e9
        )));
    }
    let levelled_lines = lines
        .iter()
        .zip(&usable)
        .zip(&lev)
        .map(|((l, u), z)| LevelledLine {
            offset: l.offset,
            x: l.profile.x.clone(),
            z: z.iter()
                .zip(u)
                .map(|(z, u)| if *u { *z } else { f64::NAN })
                .collect(),
        })
        .collect();
    Ok(BulgeFit {
        height: h,
        height_se: se(0),
        a,
        a_se: se(1),
        w: if fit_w { w } else { f64::NAN },
        w_se: se(2),
        xc,
        xc_se: se(3),
        yc: 0.0,
        yc_se: f64::NAN,
        offset,
        x_tfc: te.map(|t| (t.x - xc).abs()),
        trailing_edge: te,
        residual_rms: (r.sse / n_usable as f64).sqrt(),
        n_pixels: n_usable,
        iterations: r.iterations,
        levelled: None,
        lines: levelled_lines,
    })
}

/// Start values on levelled lines (a peak below `min_peak` is no bulge): the maximum of the
/// 5-point box-smoothed lines, its height, a from the half-maximum extent along its line (the
/// cap is at half height at u = √3/2), and w from how much lower the off-centre lines peak
/// (h_line = h·√(1 − (2·offset/w)²)); w = 1 (unused) when it is not fitted.
fn line_initial_guess(
    lines: &[OffsetLine],
    usable: &[Vec<bool>],
    lev: &[Vec<f64>],
    min_peak: f64,
    fit_w: bool,
) -> Result<[f64; 6]> {
    let smooth: Vec<Vec<f64>> = usable
        .iter()
        .zip(lev)
        .map(|(u, z)| {
            (0..u.len())
                .map(|k| {
                    if !u[k] {
                        return f64::NEG_INFINITY;
                    }
                    let r = k.saturating_sub(2)..(k + 3).min(u.len());
                    let (s, c) = r
                        .filter(|&m| u[m])
                        .fold((0.0, 0.0), |(s, c), m| (s + z[m], c + 1.0));
                    s / c
                })
                .collect()
        })
        .collect();
    let peak_of = |s: &Vec<f64>| {
        s.iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(k, v)| (k, *v))
    };
    let (line, (k, peak)) = smooth
        .iter()
        .enumerate()
        .filter_map(|(j, s)| peak_of(s).map(|p| (j, p)))
        .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .ok_or_else(|| SurfaceError::InvalidData("no usable points".into()))?;
    if !(peak.is_finite() && peak > min_peak) {
        return Err(SurfaceError::InvalidData(
            "no bulge found: nothing stands above the levelled lines".into(),
        ));
    }
    let s = &smooth[line];
    let x = &lines[line].profile.x;
    let (mut lo, mut hi) = (k, k);
    while lo > 0 && s[lo - 1] > peak / 2.0 {
        lo -= 1;
    }
    while hi + 1 < s.len() && s[hi + 1] > peak / 2.0 {
        hi += 1;
    }
    let spacing = (x[x.len() - 1] - x[0]).abs() / (x.len() - 1).max(1) as f64;
    let half = ((x[hi] - x[lo]).abs() + spacing) / 2.0;
    let a0 = (half / (3f64.sqrt() / 2.0)).max(2.0 * spacing);
    let max_off = lines.iter().map(|l| l.offset.abs()).fold(0.0, f64::max);
    let w0 = if fit_w {
        let mut est: Vec<f64> = lines
            .iter()
            .zip(&smooth)
            .filter(|(l, _)| l.offset != 0.0)
            .filter_map(|(l, s)| {
                let r = peak_of(s)?.1 / peak;
                (r > 0.05 && r < 0.98).then(|| 2.0 * l.offset.abs() / (1.0 - r * r).sqrt())
            })
            .collect();
        est.sort_by(f64::total_cmp);
        est.get(est.len() / 2).copied().unwrap_or(4.0 * max_off)
    } else {
        1.0
    };
    Ok([peak, a0, w0, x[k], 0.0, 0.0])
}

/// Heater power from a file name such as `tfc_30mW.gsf` or `scan-7.5mW`: the number right
/// before the last `mW`, in W.
pub fn power_from_name(name: &str) -> Option<f64> {
    let end = name.rfind("mW")?;
    let head = &name[..end];
    let start = head
        .char_indices()
        .rev()
        .take_while(|(_, c)| c.is_ascii_digit() || *c == '.')
        .last()
        .map(|(i, _)| i)?;
    head[start..].parse::<f64>().ok().map(|v| v / 1e3)
}

/// Straight line height = intercept + efficiency·power over several scans.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EfficiencyFit {
    /// Bulge growth per heater power, m/W.
    pub efficiency: f64,
    pub efficiency_se: f64,
    /// Height at zero power (the unpowered bulge), m.
    pub intercept: f64,
    pub intercept_se: f64,
    pub n: usize,
}

/// Ordinary least squares of height against power; standard errors from the residuals
/// (NaN with only two scans, where the line passes through both).
pub fn fit_efficiency(powers: &[f64], heights: &[f64]) -> Result<EfficiencyFit> {
    let n = powers.len();
    if n != heights.len() || n < 2 {
        return Err(SurfaceError::InvalidData(format!(
            "efficiency fit needs at least two scans with powers ({n} given)"
        )));
    }
    let nf = n as f64;
    let pm = powers.iter().sum::<f64>() / nf;
    let hm = heights.iter().sum::<f64>() / nf;
    let sxx: f64 = powers.iter().map(|p| (p - pm).powi(2)).sum();
    if sxx <= 0.0 {
        return Err(SurfaceError::InvalidData(
            "efficiency fit needs at least two different heater powers".into(),
        ));
    }
    let sxy: f64 = powers
        .iter()
        .zip(heights)
        .map(|(p, h)| (p - pm) * (h - hm))
        .sum();
    let slope = sxy / sxx;
    let intercept = hm - slope * pm;
    let (slope_se, int_se) = if n > 2 {
        let sse: f64 = powers
            .iter()
            .zip(heights)
            .map(|(p, h)| (h - intercept - slope * p).powi(2))
            .sum();
        let s2 = sse / (nf - 2.0);
        ((s2 / sxx).sqrt(), (s2 * (1.0 / nf + pm * pm / sxx)).sqrt())
    } else {
        (f64::NAN, f64::NAN)
    };
    Ok(EfficiencyFit {
        efficiency: slope,
        efficiency_se: slope_se,
        intercept,
        intercept_se: int_se,
        n,
    })
}

/// A synthetic profilometer scan of a known bulge (for `hdi synth profilometer` and tests).
#[derive(Debug, Clone)]
pub struct ScanSpec {
    /// Pixels along x (scan direction) and y.
    pub nx: usize,
    pub ny: usize,
    pub dx: f64,
    pub dy: f64,
    /// x of the trailing edge (the slider is at x < x_te), metres from the map origin.
    pub x_te: f64,
    pub height: f64,
    pub a: f64,
    pub w: f64,
    /// Centre distance from the trailing edge.
    pub x_tfc: f64,
    pub yc: f64,
    /// Height of the pull-up just before the edge and its decay length.
    pub pullup: f64,
    pub pullup_length: f64,
    /// Depth of the surface beyond the edge (the stylus falls off the slider).
    pub drop: f64,
    pub tilt_x: f64,
    pub tilt_y: f64,
    pub offset: f64,
    pub noise: f64,
    pub seed: u64,
}

/// The height map of `spec` (z in metres, dx ≠ dy allowed).
pub fn synth_scan(spec: &ScanSpec) -> HeightMap {
    let mut rng = Rng::new(spec.seed);
    let xc = spec.x_te - spec.x_tfc;
    let z = Array2::from_shape_fn((spec.ny, spec.nx), |(j, i)| {
        let x = i as f64 * spec.dx;
        let y = j as f64 * spec.dy;
        let mut z = spec.offset + spec.tilt_x * x + spec.tilt_y * y;
        if x < spec.x_te {
            let u = (x - xc) / spec.a;
            let v = 2.0 * (y - spec.yc) / spec.w;
            z += spec.height * (1.0 - u * u - v * v).max(0.0).sqrt();
            z += spec.pullup * (-(spec.x_te - x) / spec.pullup_length).exp();
        } else {
            z -= spec.drop;
        }
        z
    });
    let mut z = z;
    // Noise drawn in raster order after the field so the stream does not depend on the model.
    for v in z.iter_mut() {
        *v += spec.noise * rng.normal();
    }
    HeightMap {
        z,
        dx: spec.dx,
        dy: spec.dy,
        x0: 0.0,
        y0: 0.0,
        channel: "Profile".into(),
        valid: None,
        periodic: false,
        source: SourceInfo {
            format: "synthetic".into(),
            header: Default::default(),
        },
        history: Vec::new(),
    }
}

impl ScanSpec {
    /// The scan of the shipped set (docs/bulge.md): 50 µm × 80 µm at dx = 0.5 µm, dy = 1 µm,
    /// the trailing edge midway between two columns (so the sampled edge is unambiguous),
    /// the optimised bulge geometry (a = 4.86 µm, w = 50 µm, x_TFC = 6.35 µm,
    /// src/slider/params.rs) of the given height, a 6 nm pull-up decaying over 0.4 µm before
    /// the edge, a 150 nm drop beyond it, a tilt of a few nm over the scan and 0.2 nm noise.
    pub fn shipped(height: f64, seed: u64) -> Self {
        Self {
            nx: 100,
            ny: 80,
            dx: 0.5e-6,
            dy: 1.0e-6,
            x_te: 40.25e-6,
            height,
            a: 4.86e-6,
            w: 50e-6,
            x_tfc: 6.35e-6,
            yc: 40.0e-6,
            pullup: 6e-9,
            pullup_length: 0.4e-6,
            drop: 150e-9,
            tilt_x: 1.2e-4,
            tilt_y: -0.5e-4,
            offset: 20e-9,
            noise: 0.2e-9,
            seed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_fit(fit: &BulgeFit, spec: &ScanSpec) {
        assert!(
            (fit.a / spec.a - 1.0).abs() < 0.05,
            "a {} vs {}",
            fit.a,
            spec.a
        );
        assert!(
            (fit.w / spec.w - 1.0).abs() < 0.05,
            "w {} vs {}",
            fit.w,
            spec.w
        );
        let x = fit.x_tfc.expect("trailing edge found");
        assert!((x - spec.x_tfc).abs() < 0.5e-6, "x {x} vs {}", spec.x_tfc);
        assert!(
            (fit.height - spec.height).abs() < 0.3e-9,
            "h {} vs {}",
            fit.height,
            spec.height
        );
    }

    #[test]
    fn recovers_known_bulge_with_artifact_noise_and_tilt() {
        for (k, h) in [3e-9, 12e-9, 21e-9, 30e-9].into_iter().enumerate() {
            let spec = ScanSpec::shipped(h, 100 + k as u64);
            let map = synth_scan(&spec);
            let fit = fit_bulge(&map, &BulgeOptions::default()).unwrap();
            let te = fit.trailing_edge.unwrap();
            assert!(te.slider_below);
            // The edge lies between the last slider column and the first dropped one.
            assert!((te.x - spec.x_te).abs() <= spec.dx, "{}", te.x);
            check_fit(&fit, &spec);
            // Residual ≈ the noise: levelling and the artifact mask leave nothing systematic.
            assert!(
                (fit.residual_rms / spec.noise - 1.0).abs() < 0.1,
                "rms {}",
                fit.residual_rms
            );
        }
    }

    /// Rows of a synthetic scan as line scans at their offsets from y_c.
    fn rows_as_lines(map: &HeightMap, spec: &ScanSpec, offsets_um: &[f64]) -> Vec<OffsetLine> {
        offsets_um
            .iter()
            .map(|o| {
                let j = ((spec.yc + o * 1e-6) / spec.dy).round() as usize;
                let x: Vec<f64> = (0..spec.nx).map(|i| i as f64 * spec.dx).collect();
                OffsetLine {
                    profile: LineProfile {
                        z: (0..spec.nx).map(|i| map.z[[j, i]]).collect(),
                        valid: vec![true; x.len()],
                        x,
                        format: "xz",
                        header: Default::default(),
                    },
                    offset: o * 1e-6,
                }
            })
            .collect()
    }

    #[test]
    fn line_scans_recover_the_bulge() {
        for (k, h) in [3e-9, 12e-9, 21e-9, 30e-9].into_iter().enumerate() {
            let spec = ScanSpec::shipped(h, 300 + k as u64);
            let map = synth_scan(&spec);
            let lines = rows_as_lines(&map, &spec, &[-20.0, -10.0, 0.0, 10.0, 20.0]);
            let fit = fit_bulge_lines(&lines, &BulgeOptions::default()).unwrap();
            assert!(fit.levelled.is_none() && fit.lines.len() == 5);
            check_fit(&fit, &spec);
            assert!(fit.w_se > 0.0 && fit.a_se > 0.0 && fit.xc_se > 0.0);
            assert!(
                (fit.residual_rms / spec.noise - 1.0).abs() < 0.2,
                "{}",
                fit.residual_rms
            );
        }
        // The centre line alone: h, a and x_TFC, no width.
        let spec = ScanSpec::shipped(21e-9, 9);
        let lines = rows_as_lines(&synth_scan(&spec), &spec, &[0.0]);
        let fit = fit_bulge_lines(&lines, &BulgeOptions::default()).unwrap();
        assert!(fit.w.is_nan() && fit.w_se.is_nan());
        assert!((fit.a / spec.a - 1.0).abs() < 0.05, "{}", fit.a);
        assert!((fit.height - spec.height).abs() < 0.3e-9, "{}", fit.height);
        assert!((fit.x_tfc.unwrap() - spec.x_tfc).abs() < 0.5e-6);
        // A flat line is "no bulge", not a panic.
        let mut flat = spec.clone();
        flat.height = 0.0;
        flat.pullup = 0.0;
        let lines = rows_as_lines(&synth_scan(&flat), &flat, &[0.0, 10.0]);
        assert!(fit_bulge_lines(&lines, &BulgeOptions::default()).is_err());
        assert!(fit_bulge_lines(&[], &BulgeOptions::default()).is_err());
    }

    #[test]
    fn without_the_trailing_edge_mask_the_pullup_biases_or_breaks_the_fit() {
        // The artifact matters: fitting with auto_te off (and the drop in the data) must not
        // give the right answer, or the mask would be untested.
        let spec = ScanSpec::shipped(12e-9, 7);
        let map = synth_scan(&spec);
        let opts = BulgeOptions {
            auto_te: false,
            ..Default::default()
        };
        if let Ok(fit) = fit_bulge(&map, &opts) {
            let bad = (fit.a / spec.a - 1.0).abs() > 0.05
                || (fit.height - spec.height).abs() > 0.3e-9
                || fit.x_tfc.is_none();
            assert!(bad);
        }
    }

    #[test]
    fn exclusion_rectangle_removes_a_defect() {
        let spec = ScanSpec::shipped(21e-9, 11);
        let mut map = synth_scan(&spec);
        // A 40 nm particle far from the bulge.
        for j in 5..10 {
            for i in 10..16 {
                map.z[[j, i]] += 40e-9;
            }
        }
        let opts = BulgeOptions {
            exclude: vec![Rect {
                x0: 4e-6,
                y0: 4e-6,
                width: 5e-6,
                height: 7e-6,
            }],
            ..Default::default()
        };
        let fit = fit_bulge(&map, &opts).unwrap();
        check_fit(&fit, &spec);
    }

    #[test]
    fn standard_errors_match_monte_carlo_spread() {
        // 40 noise realisations of one bulge: the sample standard deviation of each estimate
        // should match the mean reported standard error within a factor 1.5.
        let n = 40;
        let mut est = vec![Vec::new(); 4];
        let mut ses = [0.0; 4];
        for s in 0..n {
            let mut spec = ScanSpec::shipped(12e-9, 5000 + s);
            spec.noise = 0.5e-9;
            let fit = fit_bulge(&synth_scan(&spec), &BulgeOptions::default()).unwrap();
            for (k, (v, se)) in [
                (fit.height, fit.height_se),
                (fit.a, fit.a_se),
                (fit.w, fit.w_se),
                (fit.xc, fit.xc_se),
            ]
            .into_iter()
            .enumerate()
            {
                est[k].push(v);
                ses[k] += se / n as f64;
            }
        }
        for k in 0..4 {
            let m = est[k].iter().sum::<f64>() / n as f64;
            let sd =
                (est[k].iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n as f64 - 1.0)).sqrt();
            let ratio = sd / ses[k];
            assert!(
                (1.0 / 1.5..1.5).contains(&ratio),
                "parameter {k}: spread {sd:e} vs SE {:e}",
                ses[k]
            );
        }
    }

    #[test]
    fn efficiency_line_through_exact_points() {
        // h = 3 nm + 0.3 nm/mW·P exactly: slope 3e-7 m/W, intercept 3 nm, zero SE.
        let p = [0.0, 0.03, 0.06, 0.09];
        let h: Vec<f64> = p.iter().map(|p| 3e-9 + 0.3e-6 * p).collect();
        let e = fit_efficiency(&p, &h).unwrap();
        assert!((e.efficiency - 3e-7).abs() < 1e-15);
        assert!((e.intercept - 3e-9).abs() < 1e-18);
        assert!(e.efficiency_se < 1e-15);
        // Hand-computed: heights 0,1,0,1 at P = 0,1,2,3 → slope 0.2, intercept 0.2;
        // residuals −0.2, 0.6, −0.6, 0.2 → s² = 0.8/2, SE(slope) = √(0.4/5).
        let e = fit_efficiency(&[0.0, 1.0, 2.0, 3.0], &[0.0, 1.0, 0.0, 1.0]).unwrap();
        assert!((e.efficiency - 0.2).abs() < 1e-12);
        assert!((e.intercept - 0.2).abs() < 1e-12);
        assert!((e.efficiency_se - (0.4f64 / 5.0).sqrt()).abs() < 1e-12);
        assert!(fit_efficiency(&[1.0, 1.0], &[0.0, 1.0]).is_err());
    }

    #[test]
    fn power_in_file_names() {
        assert_eq!(power_from_name("tfc_30mW.gsf"), Some(30e-3));
        assert_eq!(power_from_name("tfc_00mW.gsf"), Some(0.0));
        assert_eq!(power_from_name("scan-7.5mW"), Some(7.5e-3));
        assert_eq!(power_from_name("scan.gsf"), None);
        assert_eq!(power_from_name("mW.gsf"), None);
    }

    #[test]
    fn flat_or_tiny_maps_are_errors_not_panics() {
        let mut spec = ScanSpec::shipped(0.0, 3);
        spec.pullup = 0.0;
        spec.noise = 0.0;
        let map = synth_scan(&spec);
        assert!(fit_bulge(&map, &BulgeOptions::default()).is_err());
        let mut small = map.clone();
        small.z = Array2::zeros((2, 2));
        assert!(fit_bulge(&small, &BulgeOptions::default()).is_err());
    }
}
