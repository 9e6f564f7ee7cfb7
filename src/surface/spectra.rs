//! Surface analyses (docs/surfaces.md, "Surface analyses"): power spectral density, the
//! height-difference autocorrelation function, the scale-dependent RMS slope and curvature, and
//! the scanning-probe tip-radius reliability cutoff.
//!
//! The definitions, windows, normalisations and log bins are SurfaceTopography's (Jacobs, Junge
//! & Pastewka, Surf. Topogr. Metrol. Prop. 5, 013001 (2017); Sanner et al., Appl. Surf. Sci.
//! Adv. 7, 100190 (2022)), so that the numbers agree with SurfaceTopography 1.27.1 on the same
//! map (the tests compare to 1e-9 relative). Axes: SurfaceTopography's x is hdi's column axis,
//! so "profile" analyses run along the rows (fast-scan axis x) and are averaged over the rows.
//! Lengths in metres, wavevectors in rad/m.
use super::{HeightMap, Result, SurfaceError};
use ndarray::Array2;
use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;
use std::f64::consts::PI;

/// A sampled function: abscissae (wavevector, distance or scale) and values. Log bins without
/// data are left out (SurfaceTopography masks them).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Curve {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
}

/// Log bins per decade of the PSDs and the profile ACF (SurfaceTopography's default).
pub const BINS_PER_DECADE: usize = 10;
/// Log bins per decade of the radially averaged ACF (SurfaceTopography's default).
pub const AREA_ACF_BINS_PER_DECADE: usize = 5;
/// The tip must resolve curvatures down to −`TIP_SAFETY_FACTOR`/R (Sanner et al. 2022).
pub const TIP_SAFETY_FACTOR: f64 = 0.5;

/// All curves of one map (docs/surfaces.md, "Surface analyses").
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceAnalyses {
    /// 1-D PSD along x averaged over the rows: q (rad/m), C¹ᴰ (m³).
    pub psd_profile: Curve,
    /// Radially averaged 2-D PSD: q (rad/m), C²ᴰ (m⁴).
    pub psd_area: Curve,
    /// Height-difference ACF along x averaged over the rows: r (m), A (m²).
    pub acf_profile: Curve,
    /// Radially averaged 2-D height-difference ACF: r (m), A (m²).
    pub acf_area: Curve,
    /// RMS slope √(2A(λ))/λ along x at every grid distance λ: λ (m), slope (1).
    pub slope_profile: Curve,
    /// RMS curvature 4√(8A(λ/2) − 2A(λ))/λ² along x: stencil length λ (m), curvature (1/m).
    pub curvature_profile: Curve,
    /// RMS slope from the radially averaged ACF: λ (m), slope (1).
    pub slope_area: Curve,
    /// RMS curvature from the radially averaged ACF: λ (m), curvature (1/m).
    pub curvature_area: Curve,
}

/// The heights of a map in SurfaceTopography's terms: physical sizes `sx = nx·dx`,
/// `sy = ny·dy`, pixel sizes `sx/nx`, `sy/ny`.
struct Grid<'a> {
    z: std::borrow::Cow<'a, [f64]>,
    nx: usize,
    ny: usize,
    sx: f64,
    sy: f64,
    periodic: bool,
}

impl<'a> Grid<'a> {
    fn new(map: &'a HeightMap) -> Result<Self> {
        let (ny, nx) = map.z.dim();
        if nx < 2 || ny < 2 {
            return Err(SurfaceError::InvalidData(format!(
                "surface analyses need at least 2 × 2 pixels (the map has {nx} × {ny})"
            )));
        }
        if !(map.dx.is_finite() && map.dx > 0.0 && map.dy.is_finite() && map.dy > 0.0) {
            return Err(SurfaceError::InvalidData(format!(
                "surface analyses: pixel spacing must be positive (dx = {:e} m, dy = {:e} m)",
                map.dx, map.dy
            )));
        }
        let z: std::borrow::Cow<'a, [f64]> = match map.z.as_slice() {
            Some(slice) => std::borrow::Cow::Borrowed(slice),
            None => std::borrow::Cow::Owned(map.z.iter().copied().collect()),
        };
        let invalid = match &map.valid {
            Some(v) => z
                .iter()
                .zip(v.iter())
                .filter(|(h, ok)| !(**ok && h.is_finite()))
                .count(),
            None => z.iter().filter(|h| !h.is_finite()).count(),
        };
        if invalid > 0 {
            return Err(SurfaceError::InvalidData(format!(
                "surface analyses need a map without invalid pixels ({invalid} invalid); \
                 SurfaceTopography's PSD refuses such maps too"
            )));
        }
        Ok(Self {
            z,
            nx,
            ny,
            sx: nx as f64 * map.dx,
            sy: ny as f64 * map.dy,
            periodic: map.periodic,
        })
    }
    fn px(&self) -> f64 {
        self.sx / self.nx as f64
    }
    fn py(&self) -> f64 {
        self.sy / self.ny as f64
    }
    fn row(&self, j: usize) -> &[f64] {
        &self.z[j * self.nx..(j + 1) * self.nx]
    }
}

// ---------------------------------------------------------------------------------------------
// Log bins (SurfaceTopography's `make_grid('log')` and `bin_average`).

/// Bin edges `10^linspace(log10 min − 0.01, log10 max + 0.01, n)`, `n = ⌈(log10(max/min) + 1)·k⌉`
/// with `k` points per decade, and the collocation points at the geometric bin centres.
fn log_bin_edges(min: f64, max: f64, per_decade: usize) -> Result<Vec<f64>> {
    if !(min > 0.0 && min < max && max.is_finite()) {
        return Err(SurfaceError::InvalidData(format!(
            "surface analyses: empty range [{min:e}, {max:e}] for log bins"
        )));
    }
    const DECADE_TOLERANCE: f64 = 0.01;
    let n = ((max.log10() - min.log10() + 1.0) * per_decade as f64).ceil() as usize;
    let start = min.log10() - DECADE_TOLERANCE;
    let stop = max.log10() + DECADE_TOLERANCE;
    // numpy's linspace: start + i·step, the last point exactly `stop`.
    let step = (stop - start) / (n.max(2) - 1) as f64;
    Ok((0..n)
        .map(|i| {
            let e = if i + 1 == n {
                stop
            } else {
                i as f64 * step + start
            };
            10f64.powf(e)
        })
        .collect())
}

/// Averages of `(x, value)` pairs within the bins (a value on an edge belongs to the bin
/// below it, as numpy's `searchsorted`); points outside the edges are dropped, as are bins
/// without data. Returns the mean abscissa and the mean value of each bin.
fn bin_average(edges: &[f64], points: impl Iterator<Item = (f64, f64)>) -> Curve {
    let bins = edges.len().saturating_sub(1);
    let mut count = vec![0usize; bins];
    let mut sum_x = vec![0.0; bins];
    let mut sum_y = vec![0.0; bins];
    for (x, y) in points {
        let index = edges.partition_point(|e| *e < x);
        if index >= 1 && index <= bins {
            count[index - 1] += 1;
            sum_x[index - 1] += x;
            sum_y[index - 1] += y;
        }
    }
    let mut out = Curve::default();
    for ((n, sx), sy) in count.iter().zip(&sum_x).zip(&sum_y) {
        if *n > 0 {
            out.x.push(sx / *n as f64);
            out.y.push(sy / *n as f64);
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Windows.

/// scipy's periodic Hann window `0.5 − 0.5·cos(2πn/N)`, scaled to a mean square of one.
fn hann_profile_window(n: usize) -> Vec<f64> {
    let mut w: Vec<f64> = (0..n)
        .map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / n as f64).cos())
        .collect();
    let norm = (n as f64 / w.iter().map(|v| v * v).sum::<f64>()).sqrt();
    w.iter_mut().for_each(|v| *v *= norm);
    w
}

/// SurfaceTopography's rotationally symmetric Hann window about pixel (nx/2, ny/2):
/// `[1 + cos(πr/r_max)]/2` for r ≤ r_max = min(Lx, Ly)/2, zero outside; mean square one.
/// Row-major `[j·nx + i]`.
fn hann_radial_window(g: &Grid) -> Vec<f64> {
    let (nx, ny) = (g.nx, g.ny);
    let max_r = g.sx.min(g.sy) / 2.0;
    let mut w = vec![0.0; nx * ny];
    for j in 0..ny {
        let y = g.sy * (j as f64 - (ny / 2) as f64) / ny as f64;
        for i in 0..nx {
            let x = g.sx * (i as f64 - (nx / 2) as f64) / nx as f64;
            let r = (x * x + y * y).sqrt();
            w[j * nx + i] = if r > max_r {
                0.0
            } else {
                0.5 + 0.5 * (PI * r / max_r).cos()
            };
        }
    }
    let norm = ((nx * ny) as f64 / w.iter().map(|v| v * v).sum::<f64>()).sqrt();
    w.iter_mut().for_each(|v| *v *= norm);
    w
}

// ---------------------------------------------------------------------------------------------
// Power spectral density.

/// 1-D PSD along x averaged over the rows, `C¹ᴰ(q) = |Δx Σ hᵢ e^{−iqxᵢ}|²/L`, the ±q branches
/// averaged, log-binned from 2π/L to π/Δx. Non-periodic maps get the Hann window first.
pub fn psd_profile(map: &HeightMap) -> Result<Curve> {
    let g = Grid::new(map)?;
    let (nx, sx) = (g.nx, g.sx);
    let window = (!g.periodic).then(|| hann_profile_window(nx));
    let fft = FftPlanner::<f64>::new().plan_fft_forward(nx);
    let half = nx / 2;
    let norm = sx / nx as f64;
    let mut sum = vec![0.0; half];
    let mut buf = vec![Complex64::new(0.0, 0.0); nx];
    for j in 0..g.ny {
        for (i, (b, h)) in buf.iter_mut().zip(g.row(j)).enumerate() {
            let w = window.as_ref().map_or(1.0, |w| w[i]);
            *b = Complex64::new(h * w, 0.0);
        }
        fft.process(&mut buf);
        let power = |k: usize| (buf[k] * norm).norm_sqr() / sx;
        sum[0] += power(0);
        for (k, s) in sum.iter_mut().enumerate().skip(1) {
            *s += (power(k) + power(nx - k)) / 2.0;
        }
    }
    let dq = 2.0 * PI / sx;
    let edges = log_bin_edges(dq, PI * nx as f64 / sx, BINS_PER_DECADE)?;
    let ny = g.ny as f64;
    Ok(bin_average(
        &edges,
        (1..half).map(|k| (dq * k as f64, sum[k] / ny)),
    ))
}

/// Radially averaged 2-D PSD, `C²ᴰ(q) = |ΔxΔy Σ h e^{−iq·x}|²/(LxLy)`, log-binned up to
/// π·min(1/Δx, 1/Δy). Non-periodic maps get the radial Hann window first.
pub fn psd_area(map: &HeightMap) -> Result<Curve> {
    let g = Grid::new(map)?;
    let (nx, ny, sx, sy) = (g.nx, g.ny, g.sx, g.sy);
    let window = (!g.periodic).then(|| hann_radial_window(&g));
    let field = Array2::from_shape_fn((ny, nx), |(j, i)| {
        let w = window.as_ref().map_or(1.0, |w| w[j * nx + i]);
        g.z[j * nx + i] * w
    });
    let spectrum = crate::numerics::fft2::fft2_real(&field);
    let area_per_pixel = g.px() * g.py();
    let qx_step = 2.0 * PI * nx as f64 / sx / nx as f64;
    let qy_step = 2.0 * PI * ny as f64 / sy / ny as f64;
    let q_max = PI * (nx as f64 / sx).min(ny as f64 / sy);
    let edges = log_bin_edges(qx_step.min(qy_step), q_max, BINS_PER_DECADE)?;
    let folded = |k: usize, n: usize| if k > n / 2 { n - k } else { k } as f64;
    let points = (0..ny).flat_map(|j| {
        let spectrum = &spectrum;
        let qy = qy_step * folded(j, ny);
        (0..nx).map(move |i| {
            let qx = qx_step * folded(i, nx);
            let c = (spectrum[[j, i]] * area_per_pixel).norm_sqr() / (sx * sy);
            ((qx * qx + qy * qy).sqrt(), c)
        })
    });
    Ok(bin_average(&edges, points))
}

// ---------------------------------------------------------------------------------------------
// Height-difference autocorrelation A(r) = ½⟨[h(x + r) − h(x)]²⟩.

/// Circular correlation `c[k] = Σᵢ aᵢ·a_{i+k}` of a zero-padded line, via the FFT.
fn autocorrelate(fft_len: usize, planner: &mut FftPlanner<f64>) -> impl FnMut(&[f64]) -> Vec<f64> {
    let forward = planner.plan_fft_forward(fft_len);
    let inverse = planner.plan_fft_inverse(fft_len);
    let mut buf = vec![Complex64::new(0.0, 0.0); fft_len];
    move |line: &[f64]| {
        buf.iter_mut().for_each(|b| *b = Complex64::new(0.0, 0.0));
        for (b, h) in buf.iter_mut().zip(line) {
            b.re = *h;
        }
        forward.process(&mut buf);
        buf.iter_mut()
            .for_each(|b| *b = Complex64::new(b.norm_sqr(), 0.0));
        inverse.process(&mut buf);
        buf.iter().map(|b| b.re / fft_len as f64).collect()
    }
}

/// The profile ACF on the grid distances `r_k = kL/N`: `0 ≤ k < N/2` (periodic, the values at
/// r and L − r averaged) or `0 ≤ k < N` (non-periodic, averaged over the N − k pairs in the
/// scan), averaged over the rows.
fn acf_profile_grid(g: &Grid) -> (Vec<f64>, Vec<f64>) {
    let nx = g.nx;
    let mut planner = FftPlanner::<f64>::new();
    let (fft_len, len) = if g.periodic {
        (nx, nx / 2)
    } else {
        // Zero padding to ≥ 2N − 1 separates the images; a power of two is fastest.
        ((2 * nx - 1).next_power_of_two(), nx)
    };
    let mut correlate = autocorrelate(fft_len, &mut planner);
    let mut sum = vec![0.0; len];
    for j in 0..g.ny {
        let row = g.row(j);
        let c = correlate(row);
        if g.periodic {
            let a = |k: usize| (c[0] - c[k]) / nx as f64;
            sum[0] += a(0);
            for (k, s) in sum.iter_mut().enumerate().skip(1) {
                *s += (a(k) + a(nx - k)) / 2.0;
            }
        } else {
            // ½ Σ_{i<N−k} (hᵢ² + h_{i+k}²) from the cumulative sums of h².
            let mut head = vec![0.0; nx + 1];
            for (i, h) in row.iter().enumerate() {
                head[i + 1] = head[i] + h * h;
            }
            let total = head[nx];
            for (k, s) in sum.iter_mut().enumerate() {
                let a0 = (head[nx - k] + (total - head[k])) / 2.0;
                *s += (a0 - c[k]) / (nx - k) as f64;
            }
        }
    }
    let ny = g.ny as f64;
    let r = (0..len).map(|k| g.sx * k as f64 / nx as f64).collect();
    (r, sum.into_iter().map(|s| s / ny).collect())
}

/// 1-D height-difference ACF along x averaged over the rows, log-binned from Δx to L
/// (non-periodic) or L/2 (periodic).
pub fn acf_profile(map: &HeightMap) -> Result<Curve> {
    let g = Grid::new(map)?;
    let (r, a) = acf_profile_grid(&g);
    let max = if g.periodic { g.sx / 2.0 } else { g.sx };
    let edges = log_bin_edges(2.0 * g.sx / g.nx as f64 / 2.0, max, BINS_PER_DECADE)?;
    Ok(bin_average(
        &edges,
        r.into_iter().zip(a).skip(1), // r = 0 has no place on a log scale
    ))
}

/// The 2-D ACF map `A[l][k]` at distance (k·Δx, l·Δy), row-major `[l·nx + k]`: circular with
/// all lags for periodic maps; non-negative lags only for non-periodic ones, each averaged over
/// the (Nx − k)(Ny − l) pairs inside the map.
fn acf_area_map(g: &Grid) -> Vec<f64> {
    let (nx, ny) = (g.nx, g.ny);
    let (fx, fy) = if g.periodic {
        (nx, ny)
    } else {
        (
            (2 * nx - 1).next_power_of_two(),
            (2 * ny - 1).next_power_of_two(),
        )
    };
    let mut padded = Array2::<f64>::zeros((fy, fx));
    for j in 0..ny {
        for i in 0..nx {
            padded[[j, i]] = g.z[j * nx + i];
        }
    }
    let spectrum = crate::numerics::fft2::fft2_real(&padded);
    drop(padded);
    let power = spectrum.mapv(|c| Complex64::new(c.norm_sqr(), 0.0));
    drop(spectrum);
    let c = crate::numerics::fft2::ifft2_real(&power);
    drop(power);
    if g.periodic {
        let n = (nx * ny) as f64;
        let c0 = c[[0, 0]] / n;
        return c.iter().map(|v| c0 - v / n).collect();
    }
    // ½ Σ over the overlapping pairs of (h² + h'²): rectangle sums of h² from a summed-area
    // table, `s[(j, i)] = Σ_{j'<j, i'<i} h²`.
    let mut table = vec![0.0; (nx + 1) * (ny + 1)];
    for j in 0..ny {
        let mut row_sum = 0.0;
        for i in 0..nx {
            let h = g.z[j * nx + i];
            row_sum += h * h;
            table[(j + 1) * (nx + 1) + i + 1] = table[j * (nx + 1) + i + 1] + row_sum;
        }
    }
    let s = |j: usize, i: usize| table[j * (nx + 1) + i];
    let total = s(ny, nx);
    let mut out = vec![0.0; nx * ny];
    for l in 0..ny {
        for k in 0..nx {
            let low = s(ny - l, nx - k);
            let high = total - s(l, nx) - s(ny, k) + s(l, k);
            let a0 = (low + high) / 2.0;
            out[l * nx + k] = (a0 - c[[l, k]]) / ((nx - k) * (ny - l)) as f64;
        }
    }
    out
}

/// Radially averaged 2-D height-difference ACF, log-binned (5 per decade) from the mean pixel
/// size to (Lx + Ly)/2 (non-periodic) or (Lx + Ly)/4 (periodic).
pub fn acf_area(map: &HeightMap) -> Result<Curve> {
    let g = Grid::new(map)?;
    acf_area_of(&g)
}

fn acf_area_of(g: &Grid) -> Result<Curve> {
    let (nx, ny, sx, sy) = (g.nx, g.ny, g.sx, g.sy);
    let a = acf_area_map(g);
    let short_cutoff = 2.0 * ((g.px() + g.py()) / 2.0);
    let min = (sx / nx as f64).min(sy / ny as f64).max(short_cutoff / 2.0);
    let max = if g.periodic {
        (sx + sy) / 4.0
    } else {
        (sx + sy) / 2.0
    };
    let edges = log_bin_edges(min, max, AREA_ACF_BINS_PER_DECADE)?;
    let lag = |k: usize, n: usize| {
        if g.periodic && k > n / 2 {
            n - k
        } else {
            k
        }
    };
    let (rx, ry) = (sx / nx as f64, sy / ny as f64);
    let points = (0..ny).flat_map(|l| {
        let a = &a;
        let y = ry * lag(l, ny) as f64;
        (0..nx).map(move |k| {
            let x = rx * lag(k, nx) as f64;
            ((x * x + y * y).sqrt(), a[l * nx + k])
        })
    });
    Ok(bin_average(&edges, points))
}

// ---------------------------------------------------------------------------------------------
// Scale-dependent slope and curvature (Sanner et al. 2022), from the ACF.

/// `√(2A(λ))/λ`, the RMS of the two-point difference [h(x + λ) − h(x)]/λ, for λ > 0.
fn slope_from_acf(r: &[f64], a: &[f64]) -> Curve {
    let mut out = Curve::default();
    for (&r, &a) in r.iter().zip(a) {
        if r != 0.0 {
            out.x.push(r);
            out.y.push((2.0 * a).sqrt() / r);
        }
    }
    out
}

/// numpy's `interp` on increasing `xp` (inside the range; clamped outside).
fn interp(x: f64, xp: &[f64], fp: &[f64]) -> f64 {
    let n = xp.len();
    if x <= xp[0] {
        return fp[0];
    }
    if x >= xp[n - 1] {
        return fp[n - 1];
    }
    let j = xp.partition_point(|v| *v <= x) - 1;
    let slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]);
    slope * (x - xp[j]) + fp[j]
}

/// `4√(8A(λ/2) − 2A(λ))/λ²` at stencil lengths λ = 2r, the RMS of the three-point second
/// difference with spacing λ/2; A(2r) by linear interpolation, so only up to half the largest
/// distance, and cut at the first negative radicand.
fn curvature_from_acf(r: &[f64], a: &[f64]) -> Curve {
    let (r, a): (Vec<f64>, Vec<f64>) = r
        .iter()
        .zip(a)
        .filter(|(r, a)| r.is_finite() && a.is_finite())
        .map(|(r, a)| (*r, *a))
        .unzip();
    let mut out = Curve::default();
    let Some(&last) = r.last() else {
        return out;
    };
    for &rm in r.iter().filter(|&&rm| rm > 0.0 && 2.0 * rm <= last) {
        let b = 8.0 * interp(rm, &r, &a) - 2.0 * interp(2.0 * rm, &r, &a);
        if b < 0.0 {
            break;
        }
        out.x.push(2.0 * rm);
        out.y.push(b.sqrt() / (rm * rm));
    }
    out
}

/// All curves of [`SurfaceAnalyses`] for one map; it must have no invalid pixels.
pub fn surface_analyses(map: &HeightMap) -> Result<SurfaceAnalyses> {
    let g = Grid::new(map)?;
    let (r, a) = acf_profile_grid(&g);
    let acf_area = acf_area_of(&g)?;
    Ok(SurfaceAnalyses {
        psd_profile: psd_profile(map)?,
        psd_area: psd_area(map)?,
        acf_profile: acf_profile(map)?,
        slope_profile: slope_from_acf(&r, &a),
        curvature_profile: curvature_from_acf(&r, &a),
        slope_area: slope_from_acf(&acf_area.x, &acf_area.y),
        curvature_area: curvature_from_acf(&acf_area.x, &acf_area.y),
        acf_area,
    })
}

// ---------------------------------------------------------------------------------------------
// Tip-radius reliability cutoff (SurfaceTopography's `scanning_probe_reliability_cutoff`).

/// Where the tip-radius criterion puts the reliability cutoff.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TipCutoff {
    /// The curvature stays above −f/R down to the smallest scale: no tip artefacts.
    NoArtefacts,
    /// Below this stencil length (m) the curvature exceeds what the tip can follow.
    At(f64),
    /// Even the largest scale violates the criterion: no reliable data; the value is the upper
    /// bound of the bandwidth (mean physical size), as SurfaceTopography returns it.
    NoReliableData(f64),
}

impl TipCutoff {
    /// The length below which data are unreliable, if any.
    pub fn length(self) -> Option<f64> {
        match self {
            TipCutoff::NoArtefacts => None,
            TipCutoff::At(l) | TipCutoff::NoReliableData(l) => Some(l),
        }
    }
}

/// Minimum over the map of the x second derivative with a three-point stencil of total length
/// `distance` (spacing distance/2, heights between pixels by SurfaceTopography's triangle-wise
/// linear interpolation), without the border where the stencil leaves a non-periodic map.
/// `None` where no pixel is left.
fn min_second_derivative_x(g: &Grid, distance: f64) -> Option<f64> {
    let (nx, ny) = (g.nx, g.ny);
    let (px, py) = (g.px(), g.py());
    let (s_x, s_y) = (distance / (2.0 * px), distance / (2.0 * py));
    let step = s_x * px;
    let (i_range, j_range) = if g.periodic {
        (0..nx, 0..ny)
    } else {
        // `trim_nonperiodic` of the 3 × 3 operator: ⌈s⌉ pixels from both ends, along both
        // axes (SurfaceTopography trims y too).
        let trim = |s: f64, n: usize| {
            let cut = s.ceil();
            if 2.0 * cut >= n as f64 {
                return 0..0;
            }
            (cut as usize)..(n - cut as usize)
        };
        (trim(s_x, nx), trim(s_y, ny))
    };
    if i_range.is_empty() || j_range.is_empty() {
        return None;
    }
    let h = |i: usize, j: usize| g.z[j * nx + i];
    let wrap = |k: f64, n: usize| (k as i64).rem_euclid(n as i64) as usize;
    let value = |x: f64, y: f64| -> f64 {
        let (scaled_x, scaled_y) = (x / px, y / py);
        let (fx, fy) = (scaled_x.floor(), scaled_y.floor());
        let (frac_x, frac_y) = (scaled_x - fx, scaled_y - fy);
        let (ix, iy) = (wrap(fx, nx), wrap(fy, ny));
        let (ix1, iy1) = ((ix + 1) % nx, (iy + 1) % ny);
        if frac_x + frac_y > 1.0 {
            (frac_x + frac_y - 1.0) * h(ix1, iy1)
                + (1.0 - frac_x) * h(ix, iy1)
                + (1.0 - frac_y) * h(ix1, iy)
        } else {
            (1.0 - frac_x - frac_y) * h(ix, iy) + frac_x * h(ix1, iy) + frac_y * h(ix, iy1)
        }
    };
    let norm = step * step;
    let mut min = f64::INFINITY;
    for j in j_range {
        let y = j as f64 * g.sy / ny as f64;
        for i in i_range.clone() {
            let x = i as f64 * g.sx / nx as f64;
            let d = value(x - step, y) - 2.0 * value(x, y) + value(x + step, y);
            min = min.min(d / norm);
        }
    }
    Some(min)
}

/// scipy's `brentq` (Brent's method as in scipy/optimize/Zeros/brentq.c), so the root lands
/// on the same iterate as SurfaceTopography's.
fn brentq(f: impl Fn(f64) -> f64, xa: f64, xb: f64, xtol: f64, rtol: f64) -> f64 {
    let (mut xpre, mut xcur) = (xa, xb);
    let (mut xblk, mut fblk, mut spre, mut scur) = (0.0, 0.0, 0.0, 0.0);
    let mut fpre = f(xpre);
    let mut fcur = f(xcur);
    if fpre == 0.0 {
        return xpre;
    }
    if fcur == 0.0 {
        return xcur;
    }
    for _ in 0..100 {
        if fpre != 0.0 && fcur != 0.0 && (fpre.is_sign_negative() != fcur.is_sign_negative()) {
            xblk = xpre;
            fblk = fpre;
            spre = xcur - xpre;
            scur = spre;
        }
        if fblk.abs() < fcur.abs() {
            xpre = xcur;
            xcur = xblk;
            xblk = xpre;
            fpre = fcur;
            fcur = fblk;
            fblk = fpre;
        }
        let delta = (xtol + rtol * xcur.abs()) / 2.0;
        let sbis = (xblk - xcur) / 2.0;
        if fcur == 0.0 || sbis.abs() < delta {
            return xcur;
        }
        if spre.abs() > delta && fcur.abs() < fpre.abs() {
            let stry = if xpre == xblk {
                -fcur * (xcur - xpre) / (fcur - fpre)
            } else {
                let dpre = (fpre - fcur) / (xpre - xcur);
                let dblk = (fblk - fcur) / (xblk - xcur);
                -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            };
            if 2.0 * stry.abs() < spre.abs().min(3.0 * sbis.abs() - delta) {
                spre = scur;
                scur = stry;
            } else {
                spre = sbis;
                scur = sbis;
            }
        } else {
            spre = sbis;
            scur = sbis;
        }
        xpre = xcur;
        fpre = fcur;
        if scur.abs() > delta {
            xcur += scur;
        } else {
            xcur += if sbis > 0.0 { delta } else { -delta };
        }
        fcur = f(xcur);
    }
    xcur
}

/// The stencil length λc below which a spherical tip of radius `tip_radius` (m) distorts the
/// map: the root of min h''(λ) = −f/R (f = [`TIP_SAFETY_FACTOR`], h'' along x with a
/// three-point stencil of total length λ), bracketed in [2Δ, L/2] (Δ, L: mean pixel and
/// physical size) and found with Brent's method on λ/√(ΔL) to SurfaceTopography's tolerances.
pub fn tip_reliability_cutoff(map: &HeightMap, tip_radius: f64) -> Result<TipCutoff> {
    if !(tip_radius.is_finite() && tip_radius > 0.0) {
        return Err(SurfaceError::Parameter {
            name: "tip_radius".into(),
            value: format!("{tip_radius:e} m"),
            expected: "a positive length".into(),
        });
    }
    let g = Grid::new(map)?;
    let lower = (g.px() + g.py()) / 2.0;
    let upper = (g.sx + g.sy) / 2.0;
    let fac = ((lower.ln() + upper.ln()) / 2.0).exp();
    let target = fac * TIP_SAFETY_FACTOR / tip_radius;
    let objective = |d: f64| match min_second_derivative_x(&g, fac * d) {
        Some(min) => target + fac * min,
        None => target,
    };
    let (a, b) = (2.0 * lower / fac, upper / (2.0 * fac));
    if objective(a) > 0.0 {
        Ok(TipCutoff::NoArtefacts)
    } else if objective(b) < 0.0 {
        Ok(TipCutoff::NoReliableData(upper))
    } else {
        Ok(TipCutoff::At(fac * brentq(objective, a, b, 2e-12, 1e-8)))
    }
}

#[cfg(test)]
mod tests;
