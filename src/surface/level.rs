//! Levelling (docs/surfaces.md).
//!
//! Every fit is least squares over the valid pixels (`map.valid`); the fitted background is
//! subtracted from every pixel, valid or not. Polynomial fits use Householder QR (nalgebra) on
//! centred, scaled coordinates, accumulated block by block (TSQR) so a 1024² map with a
//! degree-5 background never needs the full design matrix in memory.
use super::{HeightMap, Result, SurfaceError};
use nalgebra::DMatrix;

/// One levelling operation; parses from / prints to the config strings
/// "plane", "poly(n)", "rows:mean", "rows:poly(n)", "rows:median", "rows:median_diff", "mean".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LevelOp {
    Plane,
    Poly(usize),
    RowsMean,
    RowsPoly(usize),
    RowsMedian,
    RowsMedianDiff,
    Mean,
}

/// Highest polynomial degree accepted by `poly(n)` and `rows:poly(n)`.
/// The default levelling of a surface (`[surface] level`): the rows' medians, a plane, the
/// mean.
pub const DEFAULT_RECIPE: [LevelOp; 3] = [LevelOp::RowsMedian, LevelOp::Plane, LevelOp::Mean];

pub const MAX_POLY_DEGREE: usize = 5;

/// Maps with every pixel valid and at least this many pixels along each side cannot fail any
/// levelling op (see [`level`]); well above the MAX_POLY_DEGREE + 1 points a fit needs.
const ROLLBACK_FREE_SIDE: usize = 16;

const VALID_OPS: &str = "\"plane\", \"poly(n)\", \"rows:mean\", \"rows:poly(n)\", \
\"rows:median\", \"rows:median_diff\", \"mean\" (1 ≤ n ≤ 5)";

impl std::str::FromStr for LevelOp {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let text = s.trim();
        let parse_degree = |inner: &str| -> std::result::Result<usize, String> {
            match inner.trim().parse::<usize>() {
                Ok(n) if (1..=MAX_POLY_DEGREE).contains(&n) => Ok(n),
                _ => Err(format!(
                    "levelling op `{s}`: polynomial degree must be an integer 1..={MAX_POLY_DEGREE}; valid ops are {VALID_OPS}"
                )),
            }
        };
        match text {
            "plane" => Ok(LevelOp::Plane),
            "rows:mean" => Ok(LevelOp::RowsMean),
            "rows:median" => Ok(LevelOp::RowsMedian),
            "rows:median_diff" => Ok(LevelOp::RowsMedianDiff),
            "mean" => Ok(LevelOp::Mean),
            _ => {
                if let Some(inner) = text
                    .strip_prefix("rows:poly(")
                    .and_then(|r| r.strip_suffix(')'))
                {
                    parse_degree(inner).map(LevelOp::RowsPoly)
                } else if let Some(inner) =
                    text.strip_prefix("poly(").and_then(|r| r.strip_suffix(')'))
                {
                    parse_degree(inner).map(LevelOp::Poly)
                } else {
                    Err(format!(
                        "unknown levelling op `{s}`; valid ops are {VALID_OPS}"
                    ))
                }
            }
        }
    }
}

impl std::fmt::Display for LevelOp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LevelOp::Plane => write!(f, "plane"),
            LevelOp::Poly(n) => write!(f, "poly({n})"),
            LevelOp::RowsMean => write!(f, "rows:mean"),
            LevelOp::RowsPoly(n) => write!(f, "rows:poly({n})"),
            LevelOp::RowsMedian => write!(f, "rows:median"),
            LevelOp::RowsMedianDiff => write!(f, "rows:median_diff"),
            LevelOp::Mean => write!(f, "mean"),
        }
    }
}

/// Apply a recipe in order; each op is recorded in `map.history`. On error the map is left
/// as it was before the call.
pub fn level(map: &mut HeightMap, recipe: &[LevelOp]) -> Result<()> {
    check_mask_shape(map)?;
    // A failed op leaves the map as it was before the recipe. That needs a snapshot of the
    // heights (a second full copy: 512 MB for an 8192² map) only when an op can fail at all:
    // on a map without invalid pixels, at least ROLLBACK_FREE_SIDE pixels a side, every fit of
    // degree ≤ MAX_POLY_DEGREE is determined and no op returns an error.
    let all_usable = map.valid.as_ref().is_none_or(|v| v.iter().all(|ok| *ok))
        && map.z.iter().all(|v| v.is_finite());
    let cannot_fail = all_usable
        && map.nx() >= ROLLBACK_FREE_SIDE
        && map.ny() >= ROLLBACK_FREE_SIDE
        && recipe.iter().all(|op| check_degree(*op).is_ok());
    let snapshot = (!cannot_fail).then(|| map.z.clone());
    let history_len = map.history.len();
    for &op in recipe {
        if let Err(e) = apply_op(map, op) {
            if let Some(z) = snapshot {
                map.z = z;
            }
            map.history.truncate(history_len);
            return Err(e);
        }
        map.push_step("level", &[("op", op.to_string())]);
    }
    Ok(())
}

/// A validity mask must have the shape of the heights (indexing it would otherwise fail).
pub(crate) fn check_mask_shape(map: &HeightMap) -> Result<()> {
    match &map.valid {
        Some(v) if v.dim() != map.z.dim() => Err(SurfaceError::InvalidData(format!(
            "validity mask is {}×{} but the height map is {}×{}",
            v.ncols(),
            v.nrows(),
            map.nx(),
            map.ny()
        ))),
        _ => Ok(()),
    }
}

fn apply_op(map: &mut HeightMap, op: LevelOp) -> Result<()> {
    check_degree(op)?;
    match op {
        LevelOp::Plane => subtract_polynomial_2d(map, 1),
        LevelOp::Poly(n) => subtract_polynomial_2d(map, n),
        LevelOp::RowsMean => rows_poly(map, 0),
        LevelOp::RowsPoly(n) => rows_poly(map, n),
        LevelOp::RowsMedian => rows_median(map),
        LevelOp::RowsMedianDiff => rows_median_diff(map),
        LevelOp::Mean => subtract_mean(map),
    }
}

fn check_degree(op: LevelOp) -> Result<()> {
    let degree = match op {
        LevelOp::Poly(n) | LevelOp::RowsPoly(n) => n,
        _ => return Ok(()),
    };
    if (1..=MAX_POLY_DEGREE).contains(&degree) {
        Ok(())
    } else {
        Err(SurfaceError::Parameter {
            name: "level".into(),
            value: op.to_string(),
            expected: format!("polynomial degree 1..={MAX_POLY_DEGREE}"),
        })
    }
}

fn subtract_mean(map: &mut HeightMap) -> Result<()> {
    let (mut sum, mut count) = (0.0, 0usize);
    for ((j, i), &v) in map.z.indexed_iter() {
        if map.is_valid(j, i) && v.is_finite() {
            sum += v;
            count += 1;
        }
    }
    if count == 0 {
        return Err(SurfaceError::InvalidData(
            "levelling `mean`: the map has no valid pixels".into(),
        ));
    }
    let mean = sum / count as f64;
    map.z.mapv_inplace(|v| v - mean);
    Ok(())
}

/// Monomials x^p·y^q with p + q ≤ degree, in a fixed order (constant first).
fn monomial_exponents(degree: usize) -> Vec<(usize, usize)> {
    let mut exps = Vec::new();
    for total in 0..=degree {
        for q in 0..=total {
            exps.push((total - q, q));
        }
    }
    exps
}

/// Coordinate of index `k` on an `n`-point axis mapped onto [−1, 1] (centred and scaled so the
/// design matrix stays well conditioned up to degree 5).
fn unit_coordinate(k: usize, n: usize) -> f64 {
    if n <= 1 {
        0.0
    } else {
        let half = (n - 1) as f64 / 2.0;
        (k as f64 - half) / half
    }
}

/// Least-squares solver fed row by row: keeps only the triangular factor of the augmented
/// matrix `[A | b]` (tall-skinny QR), so memory is O(block · terms).
struct StreamingLeastSquares {
    n_terms: usize,
    /// Upper-triangular factor of the rows seen so far (`n_terms + 1` columns incl. rhs).
    r: Option<DMatrix<f64>>,
    block: Vec<f64>,
    block_rows: usize,
    total_rows: usize,
}

const LSQ_BLOCK_ROWS: usize = 2048;

impl StreamingLeastSquares {
    fn new(n_terms: usize) -> Self {
        Self {
            n_terms,
            r: None,
            block: Vec::with_capacity(LSQ_BLOCK_ROWS * (n_terms + 1)),
            block_rows: 0,
            total_rows: 0,
        }
    }

    /// Add one observation: basis values `row` (length n_terms) and value `rhs`.
    fn push(&mut self, row: &[f64], rhs: f64) {
        self.block.extend_from_slice(row);
        self.block.push(rhs);
        self.block_rows += 1;
        self.total_rows += 1;
        if self.block_rows == LSQ_BLOCK_ROWS {
            self.flush();
        }
    }

    fn flush(&mut self) {
        if self.block_rows == 0 {
            return;
        }
        let cols = self.n_terms + 1;
        let prev_rows = self.r.as_ref().map_or(0, |r| r.nrows());
        let mut stacked = DMatrix::<f64>::zeros(prev_rows + self.block_rows, cols);
        if let Some(r) = &self.r {
            stacked.view_mut((0, 0), (prev_rows, cols)).copy_from(r);
        }
        for b in 0..self.block_rows {
            for c in 0..cols {
                stacked[(prev_rows + b, c)] = self.block[b * cols + c];
            }
        }
        self.r = Some(stacked.qr().unpack_r());
        self.block.clear();
        self.block_rows = 0;
    }

    /// Coefficients, or `None` when the system is underdetermined or rank deficient.
    fn solve(mut self) -> Option<Vec<f64>> {
        self.flush();
        let n = self.n_terms;
        let r = self.r?;
        if self.total_rows < n || r.nrows() < n {
            return None;
        }
        let max_diag = (0..n).map(|i| r[(i, i)].abs()).fold(0.0, f64::max);
        if max_diag == 0.0 || (0..n).any(|i| r[(i, i)].abs() <= 1e-12 * max_diag) {
            return None;
        }
        // Back substitution of R·c = (Qᵀb)[..n].
        let mut coef = vec![0.0; n];
        for i in (0..n).rev() {
            let mut acc = r[(i, n)];
            for k in i + 1..n {
                acc -= r[(i, k)] * coef[k];
            }
            coef[i] = acc / r[(i, i)];
        }
        Some(coef)
    }
}

fn powers(base: f64, degree: usize, out: &mut [f64]) {
    let mut p = 1.0;
    for slot in out.iter_mut().take(degree + 1) {
        *slot = p;
        p *= base;
    }
}

fn subtract_polynomial_2d(map: &mut HeightMap, degree: usize) -> Result<()> {
    let (ny, nx) = map.z.dim();
    let exps = monomial_exponents(degree);
    let n_terms = exps.len();
    let mut lsq = StreamingLeastSquares::new(n_terms);
    let mut basis = vec![0.0; n_terms];
    let mut xp = vec![0.0; degree + 1];
    let mut yp = vec![0.0; degree + 1];
    for j in 0..ny {
        powers(unit_coordinate(j, ny), degree, &mut yp);
        for i in 0..nx {
            let v = map.z[[j, i]];
            if !map.is_valid(j, i) || !v.is_finite() {
                continue;
            }
            powers(unit_coordinate(i, nx), degree, &mut xp);
            for (slot, &(p, q)) in basis.iter_mut().zip(&exps) {
                *slot = xp[p] * yp[q];
            }
            lsq.push(&basis, v);
        }
    }
    let n_valid = lsq.total_rows;
    let coef = lsq.solve().ok_or_else(|| {
        SurfaceError::InvalidData(format!(
            "levelling `{}`: the fit of {n_terms} terms is underdetermined ({n_valid} valid \
             pixels, or they do not span the plane)",
            if degree == 1 {
                "plane".to_string()
            } else {
                format!("poly({degree})")
            }
        ))
    })?;
    for j in 0..ny {
        powers(unit_coordinate(j, ny), degree, &mut yp);
        for i in 0..nx {
            powers(unit_coordinate(i, nx), degree, &mut xp);
            let background: f64 = exps
                .iter()
                .zip(&coef)
                .map(|(&(p, q), c)| c * xp[p] * yp[q])
                .sum();
            map.z[[j, i]] -= background;
        }
    }
    Ok(())
}

/// Subtract each row's least-squares polynomial of `degree` in x centred on the row
/// (degree 0 = row mean). Rows without any valid pixel are left as they are (nothing to fit,
/// and they do not enter any statistic); a row with some but too few valid pixels is an error.
fn rows_poly(map: &mut HeightMap, degree: usize) -> Result<()> {
    let (ny, nx) = map.z.dim();
    let n_terms = degree + 1;
    let mut xp = vec![0.0; n_terms];
    for j in 0..ny {
        if degree == 0 {
            let (mut sum, mut count) = (0.0, 0usize);
            for i in 0..nx {
                let v = map.z[[j, i]];
                if map.is_valid(j, i) && v.is_finite() {
                    sum += v;
                    count += 1;
                }
            }
            if count > 0 {
                let mean = sum / count as f64;
                map.z.row_mut(j).mapv_inplace(|v| v - mean);
            }
            continue;
        }
        let mut lsq = StreamingLeastSquares::new(n_terms);
        for i in 0..nx {
            let v = map.z[[j, i]];
            if map.is_valid(j, i) && v.is_finite() {
                powers(unit_coordinate(i, nx), degree, &mut xp);
                lsq.push(&xp, v);
            }
        }
        let n_valid = lsq.total_rows;
        if n_valid == 0 {
            continue;
        }
        let coef = lsq.solve().ok_or_else(|| {
            SurfaceError::InvalidData(format!(
                "levelling `rows:poly({degree})`: row {j} has only {n_valid} valid pixels, \
                 too few for a degree-{degree} fit"
            ))
        })?;
        for i in 0..nx {
            powers(unit_coordinate(i, nx), degree, &mut xp);
            let background: f64 = coef.iter().zip(&xp).map(|(c, p)| c * p).sum();
            map.z[[j, i]] -= background;
        }
    }
    Ok(())
}

/// Median of a non-empty slice (mean of the two middle values for an even count); reorders it.
pub(crate) fn median_in_place(values: &mut [f64]) -> f64 {
    let n = values.len();
    let mid = n / 2;
    let (_, &mut upper, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    if n % 2 == 1 {
        upper
    } else {
        let lower = values[..mid]
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lower + upper)
    }
}

/// Subtract each row's median over its valid pixels (no global offset added back, as
/// Gwyddion's *Align rows → Median*). Rows without valid pixels are left as they are.
fn rows_median(map: &mut HeightMap) -> Result<()> {
    let (ny, nx) = map.z.dim();
    let mut buf = Vec::with_capacity(nx);
    for j in 0..ny {
        buf.clear();
        for i in 0..nx {
            let v = map.z[[j, i]];
            if map.is_valid(j, i) && v.is_finite() {
                buf.push(v);
            }
        }
        if buf.is_empty() {
            continue;
        }
        let median = median_in_place(&mut buf);
        map.z.row_mut(j).mapv_inplace(|v| v - median);
    }
    Ok(())
}

/// Gwyddion's *Median difference*: `s_0 = 0`, `s_j = s_{j−1} + median(row_j − row_{j−1})` over
/// the pixels valid in both rows, then subtract `s_j` from row j. Where two consecutive rows
/// share no valid pixel the step is taken as 0 (nothing to compare).
fn rows_median_diff(map: &mut HeightMap) -> Result<()> {
    let (ny, nx) = map.z.dim();
    let mut offsets = vec![0.0; ny];
    let mut buf = Vec::with_capacity(nx);
    for j in 1..ny {
        buf.clear();
        for i in 0..nx {
            let (a, b) = (map.z[[j, i]], map.z[[j - 1, i]]);
            if map.is_valid(j, i) && map.is_valid(j - 1, i) && a.is_finite() && b.is_finite() {
                buf.push(a - b);
            }
        }
        let step = if buf.is_empty() {
            0.0
        } else {
            median_in_place(&mut buf)
        };
        offsets[j] = offsets[j - 1] + step;
    }
    for (j, &s) in offsets.iter().enumerate() {
        map.z.row_mut(j).mapv_inplace(|v| v - s);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::SourceInfo;
    use ndarray::Array2;

    fn map_from(z: Array2<f64>) -> HeightMap {
        HeightMap {
            z,
            dx: 2e-9,
            dy: 3e-9,
            x0: 0.0,
            y0: 0.0,
            channel: "test".into(),
            valid: None,
            periodic: false,
            source: SourceInfo::default(),
            history: Vec::new(),
        }
    }

    /// Deterministic pseudo-random values in [−1, 1).
    fn noise(k: usize) -> f64 {
        let mut x = (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
        x ^= x >> 31;
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 29;
        (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    /// Roughness that every row fit of degree ≤ 1 and every plane fit leave untouched: each row
    /// is mirror-symmetric about its centre (orthogonal to centred x) and has zero mean.
    fn orthogonal_roughness(ny: usize, nx: usize) -> Array2<f64> {
        let mut r = Array2::zeros((ny, nx));
        for j in 0..ny {
            for i in 0..nx.div_ceil(2) {
                let v = 1e-9 * noise(j * nx + i);
                r[[j, i]] = v;
                r[[j, nx - 1 - i]] = v;
            }
            let mean = r.row(j).sum() / nx as f64;
            r.row_mut(j).mapv_inplace(|v| v - mean);
        }
        r
    }

    fn max_abs_diff(a: &Array2<f64>, b: &Array2<f64>) -> f64 {
        a.iter()
            .zip(b.iter())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn parse_and_print_round_trip() {
        for s in [
            "plane",
            "poly(1)",
            "poly(5)",
            "rows:mean",
            "rows:poly(3)",
            "rows:median",
            "rows:median_diff",
            "mean",
        ] {
            let op: LevelOp = s.parse().unwrap();
            assert_eq!(op.to_string(), s);
        }
        for bad in [
            "poly(0)",
            "poly(6)",
            "rows:poly(x)",
            "median",
            "Plane",
            "poly(2",
        ] {
            let err = bad.parse::<LevelOp>().unwrap_err();
            assert!(err.contains("valid ops are"), "{err}");
        }
    }

    #[test]
    fn plane_and_row_offsets_leave_the_roughness() {
        let (ny, nx) = (40, 57);
        let r = orthogonal_roughness(ny, nx);
        let z = Array2::from_shape_fn((ny, nx), |(j, i)| {
            1e-8 + 2e-10 * i as f64 - 3e-10 * j as f64 + 4e-9 * noise(10_000 + j) + r[[j, i]]
        });
        let scale = 1e-9;
        for recipe in [
            vec![LevelOp::RowsMean, LevelOp::Plane, LevelOp::Mean],
            vec![LevelOp::Plane, LevelOp::RowsMean],
            vec![LevelOp::RowsPoly(1)],
        ] {
            let mut map = map_from(z.clone());
            level(&mut map, &recipe).unwrap();
            let err = max_abs_diff(&map.z, &r);
            assert!(err < 1e-12 * scale, "{recipe:?}: {err}");
            assert_eq!(map.history.len(), recipe.len());
            assert_eq!(map.history[0].params["op"], recipe[0].to_string());
        }
    }

    #[test]
    fn rows_median_and_median_diff_remove_offsets() {
        let (ny, nx) = (20, 31);
        // Each row: same odd-count set of values with median exactly 0.
        let base: Vec<f64> = (0..nx).map(|i| 1e-9 * noise(i)).collect();
        let mut sorted = base.clone();
        let med = median_in_place(&mut sorted);
        let r = Array2::from_shape_fn((ny, nx), |(_, i)| base[i] - med);
        let offsets: Vec<f64> = (0..ny).map(|j| 5e-8 * noise(500 + j)).collect();
        let z = Array2::from_shape_fn((ny, nx), |(j, i)| r[[j, i]] + offsets[j]);

        let mut map = map_from(z.clone());
        level(&mut map, &[LevelOp::RowsMedian]).unwrap();
        assert!(max_abs_diff(&map.z, &r) < 1e-21);

        let mut map = map_from(z);
        level(&mut map, &[LevelOp::RowsMedianDiff]).unwrap();
        let expected = r.mapv(|v| v + offsets[0]);
        assert!(max_abs_diff(&map.z, &expected) < 1e-21);
    }

    #[test]
    fn poly2_removes_a_paraboloid_bow() {
        let (ny, nx) = (33, 48);
        let z = Array2::from_shape_fn((ny, nx), |(j, i)| {
            let (x, y) = (i as f64 * 2e-9 - 30e-9, j as f64 * 3e-9 - 40e-9);
            1e-7 + 0.3 * x - 0.1 * y + 2e5 * (x * x + 0.7 * y * y) - 1e5 * x * y
        });
        let scale = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut map = map_from(z);
        level(&mut map, &[LevelOp::Poly(2)]).unwrap();
        let worst = map.z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(worst < 1e-12 * scale, "{worst} vs {scale}");
    }

    #[test]
    fn poly5_is_well_conditioned_and_respects_the_mask() {
        let (ny, nx) = (64, 64);
        let z = Array2::from_shape_fn((ny, nx), |(j, i)| {
            let (x, y) = (unit_coordinate(i, nx), unit_coordinate(j, ny));
            1e-8 * (x.powi(5) - 2.0 * x.powi(3) * y.powi(2) + y.powi(4) + 0.5 * x * y)
        });
        let mut masked = z.clone();
        let mut valid = Array2::from_elem((ny, nx), true);
        for j in 10..20 {
            for i in 5..30 {
                masked[[j, i]] = f64::NAN;
                valid[[j, i]] = false;
            }
        }
        let mut map = map_from(masked);
        map.valid = Some(valid.clone());
        level(&mut map, &[LevelOp::Poly(5)]).unwrap();
        for ((j, i), v) in map.z.indexed_iter() {
            if valid[[j, i]] {
                assert!(v.abs() < 1e-20, "{j},{i}: {v}");
            } else {
                assert!(v.is_nan());
            }
        }
    }

    #[test]
    fn underdetermined_fits_are_errors() {
        let mut map = map_from(Array2::from_elem((1, 2), 1.0));
        assert!(matches!(
            level(&mut map, &[LevelOp::Plane]),
            Err(SurfaceError::InvalidData(_))
        ));
        let mut map = map_from(Array2::from_elem((4, 4), 1.0));
        let mut valid = Array2::from_elem((4, 4), false);
        valid[[1, 1]] = true;
        valid[[1, 2]] = true;
        map.valid = Some(valid.clone());
        assert!(level(&mut map, &[LevelOp::Plane]).is_err());
        let mut map = map_from(Array2::from_elem((4, 4), 1.0));
        map.valid = Some(valid);
        assert!(level(&mut map, &[LevelOp::RowsPoly(2)]).is_err());
        let mut map = map_from(Array2::from_elem((4, 4), 1.0));
        map.valid = Some(Array2::from_elem((4, 4), false));
        assert!(level(&mut map, &[LevelOp::Mean]).is_err());
        // A failing op leaves the map as it was, including earlier ops of the recipe.
        let z = Array2::from_shape_fn((4, 4), |(j, i)| (i + 3 * j) as f64);
        let mut valid = Array2::from_elem((4, 4), false);
        valid[[2, 0]] = true;
        valid[[2, 3]] = true;
        let mut map = map_from(z.clone());
        map.valid = Some(valid);
        assert!(level(&mut map, &[LevelOp::RowsMean, LevelOp::Plane]).is_err());
        assert_eq!(map.z, z);
        assert!(map.history.is_empty());
        // A mask of the wrong shape is reported, not indexed.
        let mut map = map_from(z);
        map.valid = Some(Array2::from_elem((3, 4), true));
        assert!(matches!(
            level(&mut map, &[LevelOp::Mean]),
            Err(SurfaceError::InvalidData(_))
        ));
    }

    /// `level` skips its undo snapshot on maps with every pixel valid and ≥ ROLLBACK_FREE_SIDE
    /// pixels a side because no op can fail there: every op at the highest degree succeeds on
    /// the smallest such map. With an invalid pixel the snapshot is back and a failing recipe
    /// still leaves a large map untouched.
    #[test]
    fn undo_snapshot_is_skipped_only_where_no_op_can_fail() {
        let n = ROLLBACK_FREE_SIDE;
        let z = Array2::from_shape_fn((n, n), |(j, i)| noise(j * n + i) + 0.1 * i as f64);
        let mut map = map_from(z.clone());
        let every_op = [
            LevelOp::RowsMedian,
            LevelOp::RowsMedianDiff,
            LevelOp::RowsPoly(MAX_POLY_DEGREE),
            LevelOp::Poly(MAX_POLY_DEGREE),
            LevelOp::Plane,
            LevelOp::RowsMean,
            LevelOp::Mean,
        ];
        level(&mut map, &every_op).unwrap();
        assert_eq!(map.history.len(), every_op.len());

        let mut valid = Array2::from_elem((n, n), false);
        valid[[3, 0]] = true;
        valid[[3, n - 1]] = true;
        let mut map = map_from(z.clone());
        map.valid = Some(valid);
        assert!(level(&mut map, &[LevelOp::RowsMean, LevelOp::Plane]).is_err());
        assert_eq!(map.z, z);
        assert!(map.history.is_empty());
    }
}
