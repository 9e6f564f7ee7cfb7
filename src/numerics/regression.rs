//! Polynomial response surfaces in coded factors, least squares and sequential ANOVA
//! (§2.3, docs/doe.md: the 3³ DOE, the 23- and 26-term models, Table 2.7's predictive equations).
//!
//! - A model is a [`PolynomialBasis`]: an ordered list of [`Monomial`]s. The order matters: it
//!   is the order of the sequential (type I) sums of squares. [`PolynomialBasis::bounded`]
//!   builds "every monomial with each power ≤ p_max and total degree ≤ d_max", ordered by total
//!   degree and then by the name's digits (`b0, b1, b2, b3, b11, b12, …, b1122`).
//! - Least squares goes through a Householder QR of the column-equilibrated design matrix,
//!   never the normal equations (whose condition number is the square of the design's).
//! - Rank: column `j` counts as dependent when the part of it orthogonal to the kept earlier
//!   columns is below `rank_tolerance` times its norm. A rank-deficient design is an error
//!   ([`RegressionError::RankDeficient`]) naming the aliased terms, in basis order, rather than
//!   a silent minimum-norm solution whose coefficients would not mean what their names say;
//!   [`PolynomialBasis::without_terms`] drops them.
//! - The ANOVA's sequential sums of squares are the squared components of `Qᵀy`: term `j`'s is
//!   the reduction in residual sum of squares from adding it after terms `0..j`.

use nalgebra::{DMatrix, DVector};

use super::special::{f_sf, normal_quantile, t_two_sided_p};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegressionError {
    #[error("{observations} observations for {parameters} terms: need at least as many observations as terms")]
    TooFewObservations {
        observations: usize,
        parameters: usize,
    },
    #[error("{what}: expected length {expected}, got {got}")]
    LengthMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("non-finite value in the {what} at index {index}")]
    NonFinite { what: &'static str, index: usize },
    #[error(
        "rank-deficient design (rank {rank} < {parameters} terms): {} {} of earlier terms on \
         these points; drop them (PolynomialBasis::without_terms) or add points",
        names.join(", "),
        if names.len() == 1 { "is a linear combination" } else { "are linear combinations" }
    )]
    RankDeficient {
        rank: usize,
        parameters: usize,
        /// Indices of the dependent columns/terms, ascending.
        dependent: Vec<usize>,
        names: Vec<String>,
    },
    #[error("invalid polynomial basis: {0}")]
    InvalidBasis(String),
    #[error("factor index {factor} out of range for {factors} factors")]
    InvalidFactor { factor: usize, factors: usize },
}

/// `x_1^p_1 · x_2^p_2 · …`; `powers[i]` belongs to factor `i` (0-based here, 1-based in names).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Monomial {
    pub powers: Vec<u8>,
}

impl Monomial {
    pub fn constant(factors: usize) -> Self {
        Monomial {
            powers: vec![0; factors],
        }
    }

    pub fn degree(&self) -> u32 {
        self.powers.iter().map(|&p| u32::from(p)).sum()
    }

    pub fn is_constant(&self) -> bool {
        self.powers.iter().all(|&p| p == 0)
    }

    /// Factor indices (1-based) repeated per power: `x1² x2` → `[1, 1, 2]`.
    fn index_digits(&self) -> Vec<usize> {
        self.powers
            .iter()
            .enumerate()
            .flat_map(|(i, &p)| std::iter::repeat_n(i + 1, usize::from(p)))
            .collect()
    }

    /// The dissertation's coefficient name: `b0`, `b1`, `b12`, `b1122`. With more than nine
    /// factors the indices are joined by `_` (`b3_10`) so names stay unambiguous.
    pub fn name(&self) -> String {
        let digits = self.index_digits();
        if digits.is_empty() {
            return "b0".to_string();
        }
        let sep = if self.powers.len() > 9 { "_" } else { "" };
        let parts: Vec<String> = digits.iter().map(|d| d.to_string()).collect();
        format!("b{}", parts.join(sep))
    }

    /// Value at `x` (`x.len()` must equal the number of factors).
    pub fn eval(&self, x: &[f64]) -> f64 {
        self.powers
            .iter()
            .zip(x)
            .map(|(&p, &v)| v.powi(i32::from(p)))
            .product()
    }

    /// Standard order: total degree, then the name's index sequence.
    fn order_key(&self) -> (u32, Vec<usize>) {
        (self.degree(), self.index_digits())
    }
}

/// An ordered list of monomials in `factors` variables: the columns of a design matrix.
#[derive(Debug, Clone, PartialEq)]
pub struct PolynomialBasis {
    factors: usize,
    terms: Vec<Monomial>,
}

impl PolynomialBasis {
    /// Every monomial with each power ≤ `max_power` and total degree ≤ `max_degree`, in
    /// standard order. `bounded(3, 2, 4)` is the spec's 23-term model, `bounded(3, 2, 5)` the
    /// 26-term one; `bounded(1, d, d)` is an ordinary degree-d polynomial `1, x, …, x^d`.
    pub fn bounded(factors: usize, max_power: u8, max_degree: u32) -> Self {
        let mut terms = Vec::new();
        let mut powers = vec![0u8; factors];
        // Odometer over [0, max_power]^factors.
        loop {
            let m = Monomial {
                powers: powers.clone(),
            };
            if m.degree() <= max_degree {
                terms.push(m);
            }
            let mut i = 0;
            while i < factors && powers[i] == max_power {
                powers[i] = 0;
                i += 1;
            }
            if i == factors {
                break;
            }
            powers[i] += 1;
        }
        terms.sort_by_key(Monomial::order_key);
        PolynomialBasis { factors, terms }
    }

    /// A basis in the given order (which is the order of the sequential sums of squares).
    pub fn from_terms(factors: usize, terms: Vec<Monomial>) -> Result<Self, RegressionError> {
        for (i, t) in terms.iter().enumerate() {
            if t.powers.len() != factors {
                return Err(RegressionError::InvalidBasis(format!(
                    "term {i} has {} powers for {factors} factors",
                    t.powers.len()
                )));
            }
            if terms[..i].contains(t) {
                return Err(RegressionError::InvalidBasis(format!(
                    "term {} appears twice",
                    t.name()
                )));
            }
        }
        Ok(PolynomialBasis { factors, terms })
    }

    /// The same basis without the terms at `indices` (e.g. a rank error's `dependent`).
    pub fn without_terms(&self, indices: &[usize]) -> Self {
        PolynomialBasis {
            factors: self.factors,
            terms: self
                .terms
                .iter()
                .enumerate()
                .filter(|(i, _)| !indices.contains(i))
                .map(|(_, t)| t.clone())
                .collect(),
        }
    }

    pub fn factors(&self) -> usize {
        self.factors
    }

    pub fn terms(&self) -> &[Monomial] {
        &self.terms
    }

    pub fn len(&self) -> usize {
        self.terms.len()
    }

    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    pub fn names(&self) -> Vec<String> {
        self.terms.iter().map(Monomial::name).collect()
    }

    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.terms.iter().position(|t| t.name() == name)
    }

    /// Whether the first term is the constant (then sums of squares are about the mean).
    pub fn has_intercept_first(&self) -> bool {
        self.terms.first().is_some_and(Monomial::is_constant)
    }

    /// One design-matrix row: every term evaluated at `x`.
    pub fn row(&self, x: &[f64]) -> Vec<f64> {
        self.terms.iter().map(|t| t.eval(x)).collect()
    }

    /// The design matrix, one row per point.
    pub fn design_matrix(&self, points: &[Vec<f64>]) -> Result<DMatrix<f64>, RegressionError> {
        for p in points {
            if p.len() != self.factors {
                return Err(RegressionError::LengthMismatch {
                    what: "design point",
                    expected: self.factors,
                    got: p.len(),
                });
            }
        }
        Ok(DMatrix::from_fn(points.len(), self.len(), |i, j| {
            self.terms[j].eval(&points[i])
        }))
    }
}

/// A polynomial: a basis and one coefficient per term.
#[derive(Debug, Clone, PartialEq)]
pub struct Polynomial {
    pub basis: PolynomialBasis,
    pub coefficients: Vec<f64>,
}

impl Polynomial {
    pub fn eval(&self, x: &[f64]) -> f64 {
        self.basis
            .terms
            .iter()
            .zip(&self.coefficients)
            .map(|(t, c)| c * t.eval(x))
            .sum()
    }

    pub fn coefficient(&self, name: &str) -> Option<f64> {
        self.basis.index_of(name).map(|i| self.coefficients[i])
    }

    /// Substitute `x_factor = value` (0-based factor index) and collect the result as a
    /// polynomial in the remaining factors, renumbered in order (Table 2.7's predictive
    /// equations: fixing `a_TFC` in the 23-term model leaves the nine coefficients `b0, b1, b2,
    /// b11, b12, b22, b112, b122, b1122` of the other two). Terms in standard order.
    pub fn fix_factor(&self, factor: usize, value: f64) -> Result<Polynomial, RegressionError> {
        let factors = self.basis.factors;
        if factor >= factors {
            return Err(RegressionError::InvalidFactor { factor, factors });
        }
        let mut collected: Vec<(Monomial, f64)> = Vec::new();
        for (t, &c) in self.basis.terms.iter().zip(&self.coefficients) {
            let mut powers = t.powers.clone();
            let p = powers.remove(factor);
            let reduced = Monomial { powers };
            let contribution = c * value.powi(i32::from(p));
            match collected.iter_mut().find(|(m, _)| *m == reduced) {
                Some((_, acc)) => *acc += contribution,
                None => collected.push((reduced, contribution)),
            }
        }
        collected.sort_by_key(|(m, _)| m.order_key());
        let (terms, coefficients) = collected.into_iter().unzip();
        Ok(Polynomial {
            basis: PolynomialBasis {
                factors: factors - 1,
                terms,
            },
            coefficients,
        })
    }
}

/// Coded level of `value` on `[low, high]`: −1 at `low`, +1 at `high`.
pub fn coded(value: f64, low: f64, high: f64) -> f64 {
    (value - 0.5 * (low + high)) / (0.5 * (high - low))
}

/// Inverse of [`coded`].
pub fn decoded(coded_value: f64, low: f64, high: f64) -> f64 {
    0.5 * (low + high) + coded_value * 0.5 * (high - low)
}

/// Full factorial in coded units: factor `i` takes `levels_per_factor[i]` equally spaced
/// levels on `[−1, 1]` (a single level is 0). Standard (Yates) order: the first factor varies
/// fastest. A factor with zero levels gives no points.
pub fn full_factorial(levels_per_factor: &[usize]) -> Vec<Vec<f64>> {
    let total: usize = levels_per_factor.iter().product();
    let level = |l: usize, j: usize| {
        if l == 1 {
            0.0
        } else {
            -1.0 + 2.0 * j as f64 / (l - 1) as f64
        }
    };
    (0..total)
        .map(|mut k| {
            levels_per_factor
                .iter()
                .map(|&l| {
                    let j = k % l;
                    k /= l;
                    level(l, j)
                })
                .collect()
        })
        .collect()
}

/// Fit options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// A column is dependent when its part orthogonal to the kept earlier columns is below
    /// this fraction of its norm (exact aliases, like `x³ = x` on three levels, give ~1e-16).
    pub rank_tolerance: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            rank_tolerance: 1e-9,
        }
    }
}

/// Ordinary least squares `y ≈ Xβ` and its usual statistics. Quantities that need a residual
/// variance (standard errors, t, p, σ̂, adjusted R²) are `NaN` when `residual_df == 0`.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearFit {
    pub coefficients: Vec<f64>,
    /// `σ̂ · sqrt(diag((RᵀR)⁻¹))`.
    pub standard_errors: Vec<f64>,
    pub t_values: Vec<f64>,
    /// Two-sided, Student t with `residual_df`.
    pub p_values: Vec<f64>,
    pub fitted: Vec<f64>,
    pub residuals: Vec<f64>,
    /// Hat-matrix diagonal `h_ii` (row norms² of the thin Q).
    pub leverage: Vec<f64>,
    /// Sequential (type I) sum of squares of each column in order: `(Qᵀy)_j²`.
    pub sequential_ss: Vec<f64>,
    pub observations: usize,
    pub parameters: usize,
    pub residual_df: usize,
    /// Residual sum of squares.
    pub rss: f64,
    /// Total sum of squares: about the mean with an intercept, about zero without.
    pub tss: f64,
    /// Residual standard deviation `sqrt(rss / residual_df)`.
    pub sigma: f64,
    /// `1 − rss/tss` (`NaN` for a constant response with an intercept).
    pub r_squared: f64,
    pub adj_r_squared: f64,
    /// Column 0 is the intercept (sums of squares are corrected for the mean).
    pub intercept: bool,
}

fn check_finite(
    values: impl IntoIterator<Item = f64>,
    what: &'static str,
) -> Result<(), RegressionError> {
    match values.into_iter().position(|v| !v.is_finite()) {
        Some(index) => Err(RegressionError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Least squares through a Householder QR of the column-equilibrated design. `intercept`
/// says column 0 is the constant term (R² and the ANOVA total are then about the mean).
pub fn least_squares(
    design: &DMatrix<f64>,
    y: &[f64],
    intercept: bool,
    opts: &FitOptions,
) -> Result<LinearFit, RegressionError> {
    let (n, p) = design.shape();
    if y.len() != n {
        return Err(RegressionError::LengthMismatch {
            what: "response",
            expected: n,
            got: y.len(),
        });
    }
    if n < p || p == 0 {
        return Err(RegressionError::TooFewObservations {
            observations: n,
            parameters: p,
        });
    }
    check_finite(design.iter().copied(), "design matrix")?;
    check_finite(y.iter().copied(), "response")?;

    // Unit-norm columns: the rank test becomes a sine of an angle, and QR accuracy no longer
    // depends on the columns' scales (Pontius's x² reaches 9e12).
    let norms: Vec<f64> = design.column_iter().map(|c| c.norm()).collect();
    let scaled = DMatrix::from_fn(n, p, |i, j| {
        if norms[j] > 0.0 {
            design[(i, j)] / norms[j]
        } else {
            0.0
        }
    });
    let dependent = dependent_columns(&scaled, opts.rank_tolerance);
    if !dependent.is_empty() {
        return Err(RegressionError::RankDeficient {
            rank: p - dependent.len(),
            parameters: p,
            names: dependent.iter().map(|j| format!("column {j}")).collect(),
            dependent,
        });
    }

    let qr = scaled.qr();
    let r = qr.r();
    let mut qty = DVector::from_column_slice(y);
    qr.q_tr_mul(&mut qty);
    let sequential_ss: Vec<f64> = (0..p).map(|j| qty[j] * qty[j]).collect();
    let beta_scaled = r
        .solve_upper_triangular(&qty.rows(0, p).into_owned())
        .expect("full rank checked above");
    let coefficients: Vec<f64> = (0..p).map(|j| beta_scaled[j] / norms[j]).collect();

    let fitted: Vec<f64> = (0..n)
        .map(|i| (0..p).map(|j| design[(i, j)] * coefficients[j]).sum())
        .collect();
    let residuals: Vec<f64> = y.iter().zip(&fitted).map(|(a, b)| a - b).collect();
    let q = qr.q();
    let leverage: Vec<f64> = (0..n).map(|i| q.row(i).norm_squared()).collect();

    let residual_df = n - p;
    let rss: f64 = residuals.iter().map(|e| e * e).sum();
    let mean = if intercept {
        y.iter().sum::<f64>() / n as f64
    } else {
        0.0
    };
    let tss: f64 = y.iter().map(|v| (v - mean) * (v - mean)).sum();
    let sigma = if residual_df > 0 {
        (rss / residual_df as f64).sqrt()
    } else {
        f64::NAN
    };
    let r_squared = 1.0 - rss / tss;
    let n_for_adj = if intercept { n - 1 } else { n } as f64;
    let adj_r_squared = if residual_df > 0 {
        1.0 - (1.0 - r_squared) * n_for_adj / residual_df as f64
    } else {
        f64::NAN
    };

    // diag((RᵀR)⁻¹) = row norms² of R⁻¹; unscale by the column norms.
    let r_inv = r
        .solve_upper_triangular(&DMatrix::identity(p, p))
        .expect("full rank checked above");
    let standard_errors: Vec<f64> = (0..p)
        .map(|j| sigma * r_inv.row(j).norm() / norms[j])
        .collect();
    let t_values: Vec<f64> = coefficients
        .iter()
        .zip(&standard_errors)
        .map(|(b, s)| b / s)
        .collect();
    let p_values: Vec<f64> = t_values
        .iter()
        .map(|&t| {
            if residual_df > 0 {
                t_two_sided_p(t, residual_df as f64)
            } else {
                f64::NAN
            }
        })
        .collect();

    Ok(LinearFit {
        coefficients,
        standard_errors,
        t_values,
        p_values,
        fitted,
        residuals,
        leverage,
        sequential_ss,
        observations: n,
        parameters: p,
        residual_df,
        rss,
        tss,
        sigma,
        r_squared,
        adj_r_squared,
        intercept,
    })
}

/// Columns (ascending) that are, within `tol`, combinations of the kept earlier columns of a
/// unit-column matrix. Refactors after each find: a Householder step built on a near-zero
/// column would otherwise rotate in an arbitrary direction and spoil later diagonals.
fn dependent_columns(scaled: &DMatrix<f64>, tol: f64) -> Vec<usize> {
    let p = scaled.ncols();
    let mut kept: Vec<usize> = (0..p).collect();
    let mut dependent = Vec::new();
    'refactor: loop {
        let sub = DMatrix::from_fn(scaled.nrows(), kept.len(), |i, j| scaled[(i, kept[j])]);
        let r = sub.qr().r();
        for (k, &col) in kept.iter().enumerate() {
            // A zero column (norm 0 before scaling) is dependent by definition.
            if r[(k, k)].abs() <= tol || scaled.column(col).norm() == 0.0 {
                dependent.push(col);
                kept.remove(k);
                continue 'refactor;
            }
        }
        break;
    }
    dependent.sort_unstable();
    dependent
}

/// One ANOVA row. `f` and `p` are `None` for the residual and total rows, and everywhere when
/// there are no residual degrees of freedom.
#[derive(Debug, Clone, PartialEq)]
pub struct AnovaRow {
    pub source: String,
    pub df: usize,
    pub sum_sq: f64,
    pub mean_sq: f64,
    pub f: Option<f64>,
    pub p: Option<f64>,
}

/// Sequential (type I) ANOVA: one row per term in basis order (the intercept is not a row when
/// the fit has one), the whole model, the residual and the total.
#[derive(Debug, Clone, PartialEq)]
pub struct AnovaTable {
    pub terms: Vec<AnovaRow>,
    pub model: AnovaRow,
    pub residual: AnovaRow,
    pub total: AnovaRow,
}

/// Residual plots: residuals against fitted values, and a normal-probability plot.
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualDiagnostics {
    /// `(fitted, residual)` in observation order.
    pub fitted_residual: Vec<(f64, f64)>,
    /// `e_i / σ̂` (Montgomery's standardized residuals).
    pub standardized: Vec<f64>,
    /// Internally studentized `e_i / (σ̂ sqrt(1 − h_ii))`; `NaN` where `h_ii ≈ 1`.
    pub studentized: Vec<f64>,
    /// `(theoretical normal quantile, standardized residual)`, residuals ascending; the
    /// quantiles are at Blom's positions `(i − 3/8)/(n + 1/4)`, i = 1…n.
    pub normal_probability: Vec<(f64, f64)>,
}

impl LinearFit {
    /// The ANOVA table; `names[j]` labels column `j` (`names.len()` = parameters).
    pub fn anova(&self, names: &[String]) -> AnovaTable {
        let ms_res = if self.residual_df > 0 {
            self.rss / self.residual_df as f64
        } else {
            f64::NAN
        };
        let test = |ss: f64, df: usize| -> (Option<f64>, Option<f64>) {
            if self.residual_df == 0 || df == 0 {
                return (None, None);
            }
            let f = (ss / df as f64) / ms_res;
            (Some(f), Some(f_sf(f, df as f64, self.residual_df as f64)))
        };
        let first = usize::from(self.intercept);
        let terms: Vec<AnovaRow> = (first..self.parameters)
            .map(|j| {
                let ss = self.sequential_ss[j];
                let (f, p) = test(ss, 1);
                AnovaRow {
                    source: names
                        .get(j)
                        .cloned()
                        .unwrap_or_else(|| format!("column {j}")),
                    df: 1,
                    sum_sq: ss,
                    mean_sq: ss,
                    f,
                    p,
                }
            })
            .collect();
        let model_df = self.parameters - first;
        let model_ss: f64 = terms.iter().map(|r| r.sum_sq).sum();
        let (f, p) = test(model_ss, model_df);
        let model = AnovaRow {
            source: "model".to_string(),
            df: model_df,
            sum_sq: model_ss,
            mean_sq: if model_df > 0 {
                model_ss / model_df as f64
            } else {
                f64::NAN
            },
            f,
            p,
        };
        let residual = AnovaRow {
            source: "residual".to_string(),
            df: self.residual_df,
            sum_sq: self.rss,
            mean_sq: ms_res,
            f: None,
            p: None,
        };
        let total_df = self.observations - first;
        let total = AnovaRow {
            source: "total".to_string(),
            df: total_df,
            sum_sq: self.tss,
            mean_sq: if total_df > 0 {
                self.tss / total_df as f64
            } else {
                f64::NAN
            },
            f: None,
            p: None,
        };
        AnovaTable {
            terms,
            model,
            residual,
            total,
        }
    }

    pub fn residual_diagnostics(&self) -> ResidualDiagnostics {
        let n = self.observations;
        let standardized: Vec<f64> = self.residuals.iter().map(|e| e / self.sigma).collect();
        let studentized: Vec<f64> = self
            .residuals
            .iter()
            .zip(&self.leverage)
            .map(|(e, h)| {
                let room = 1.0 - h;
                // h = 1 up to rounding: the point is fitted exactly whatever its response.
                if room <= 1e-12 {
                    f64::NAN
                } else {
                    e / (self.sigma * room.sqrt())
                }
            })
            .collect();
        let mut sorted = standardized.clone();
        sorted.sort_by(f64::total_cmp);
        let normal_probability = sorted
            .into_iter()
            .enumerate()
            .map(|(i, r)| {
                let position = (i as f64 + 1.0 - 0.375) / (n as f64 + 0.25);
                (normal_quantile(position), r)
            })
            .collect();
        ResidualDiagnostics {
            fitted_residual: self
                .fitted
                .iter()
                .copied()
                .zip(self.residuals.iter().copied())
                .collect(),
            standardized,
            studentized,
            normal_probability,
        }
    }
}

/// A polynomial response surface fitted to design points (coded factors).
#[derive(Debug, Clone, PartialEq)]
pub struct ResponseSurface {
    pub basis: PolynomialBasis,
    pub points: Vec<Vec<f64>>,
    pub fit: LinearFit,
}

impl ResponseSurface {
    /// Least-squares fit of `y` on `basis` at `points`. A rank error names the aliased terms.
    pub fn fit(
        basis: &PolynomialBasis,
        points: &[Vec<f64>],
        y: &[f64],
        opts: &FitOptions,
    ) -> Result<Self, RegressionError> {
        let design = basis.design_matrix(points)?;
        let fit =
            least_squares(&design, y, basis.has_intercept_first(), opts).map_err(|e| match e {
                RegressionError::RankDeficient {
                    rank,
                    parameters,
                    dependent,
                    ..
                } => RegressionError::RankDeficient {
                    rank,
                    parameters,
                    names: dependent.iter().map(|&j| basis.terms[j].name()).collect(),
                    dependent,
                },
                other => other,
            })?;
        Ok(ResponseSurface {
            basis: basis.clone(),
            points: points.to_vec(),
            fit,
        })
    }

    pub fn polynomial(&self) -> Polynomial {
        Polynomial {
            basis: self.basis.clone(),
            coefficients: self.fit.coefficients.clone(),
        }
    }

    /// The fitted surface at `x` (coded factors).
    pub fn predict(&self, x: &[f64]) -> f64 {
        self.basis
            .terms
            .iter()
            .zip(&self.fit.coefficients)
            .map(|(t, c)| c * t.eval(x))
            .sum()
    }

    pub fn anova(&self) -> AnovaTable {
        self.fit.anova(&self.basis.names())
    }

    /// Sum of squared residuals over the design points whose factor `factor` is within `tol`
    /// of `level` (Table 2.7's "residual error" of one fixed-factor equation).
    pub fn residual_ss_at(&self, factor: usize, level: f64, tol: f64) -> f64 {
        self.points
            .iter()
            .zip(&self.fit.residuals)
            .filter(|(p, _)| (p[factor] - level).abs() <= tol)
            .map(|(_, e)| e * e)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(got: f64, want: f64, rel: f64) {
        let err = ((got - want) / want).abs();
        assert!(
            err <= rel,
            "got {got:e}, want {want:e}, relative error {err:e}"
        );
    }

    /// SplitMix64 and Box–Muller: seeded noise for the tests.
    struct Noise(u64);
    impl Noise {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn gaussian(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
        }
    }

    #[test]
    fn bounded_basis_sizes_order_and_names() {
        let m23 = PolynomialBasis::bounded(3, 2, 4);
        assert_eq!(
            m23.names(),
            [
                "b0", "b1", "b2", "b3", "b11", "b12", "b13", "b22", "b23", "b33", "b112", "b113",
                "b122", "b123", "b133", "b223", "b233", "b1122", "b1123", "b1133", "b1223",
                "b1233", "b2233"
            ]
        );
        let m26 = PolynomialBasis::bounded(3, 2, 5);
        assert_eq!(m26.len(), 26);
        assert_eq!(&m26.names()[23..], ["b11223", "b11233", "b12233"]);
        assert_eq!(PolynomialBasis::bounded(3, 2, 6).len(), 27);
        assert_eq!(
            PolynomialBasis::bounded(2, 2, 4).names(),
            ["b0", "b1", "b2", "b11", "b12", "b22", "b112", "b122", "b1122"]
        );
        assert!(m23.has_intercept_first());
        let b1122 = &m23.terms()[m23.index_of("b1122").unwrap()];
        assert_eq!(b1122.powers, [2, 2, 0]);
        assert_eq!(b1122.eval(&[2.0, 3.0, 5.0]), 36.0);
        assert_eq!(
            Monomial {
                powers: vec![0, 0, 1, 0, 0, 0, 0, 0, 0, 2]
            }
            .name(),
            "b3_10_10"
        );
        assert!(
            PolynomialBasis::from_terms(2, vec![Monomial::constant(2), Monomial::constant(2)])
                .is_err()
        );
        assert!(PolynomialBasis::from_terms(2, vec![Monomial::constant(3)]).is_err());
    }

    #[test]
    fn coded_levels_and_full_factorial() {
        // §2.3 (docs/doe.md): w_TFC = 10, 50, 90 µm are coded −1, 0, +1.
        assert_eq!(coded(10.0, 10.0, 90.0), -1.0);
        assert_eq!(coded(50.0, 10.0, 90.0), 0.0);
        assert_eq!(coded(90.0, 10.0, 90.0), 1.0);
        assert!((coded(70.0, 10.0, 90.0) - 0.5).abs() < 1e-15);
        assert!((decoded(coded(4.86, 1.0, 5.0), 1.0, 5.0) - 4.86).abs() < 1e-14);
        let d = full_factorial(&[3, 3, 3]);
        assert_eq!(d.len(), 27);
        assert_eq!(d[0], [-1.0, -1.0, -1.0]);
        assert_eq!(d[1], [0.0, -1.0, -1.0]); // first factor fastest
        assert_eq!(d[3], [-1.0, 0.0, -1.0]);
        assert_eq!(d[26], [1.0, 1.0, 1.0]);
        assert_eq!(full_factorial(&[2, 1]), [[-1.0, 0.0], [1.0, 0.0]]);
        assert_eq!(full_factorial(&[5])[1], [-0.5]);
        assert!(full_factorial(&[3, 0]).is_empty());
    }

    /// NIST/ITL StRD linear least squares, dataset "Norris" (lower difficulty; J. Norris,
    /// "Calibration of ozone monitors"), data and certified values from
    /// https://www.itl.nist.gov/div898/strd/lls/data/LINKS/DATA/Norris.dat
    const NORRIS: [(f64, f64); 36] = [
        (0.1, 0.2),
        (338.8, 337.4),
        (118.1, 118.2),
        (888.0, 884.6),
        (9.2, 10.1),
        (228.1, 226.5),
        (668.5, 666.3),
        (998.5, 996.3),
        (449.1, 448.6),
        (778.9, 777.0),
        (559.2, 558.2),
        (0.3, 0.4),
        (0.1, 0.6),
        (778.1, 775.5),
        (668.8, 666.9),
        (339.3, 338.0),
        (448.9, 447.5),
        (10.8, 11.6),
        (557.7, 556.0),
        (228.3, 228.1),
        (998.0, 995.8),
        (888.8, 887.6),
        (119.6, 120.2),
        (0.3, 0.3),
        (0.6, 0.3),
        (557.6, 556.8),
        (339.3, 339.1),
        (888.0, 887.2),
        (998.5, 999.0),
        (778.9, 779.0),
        (10.2, 11.1),
        (117.6, 118.3),
        (228.9, 229.2),
        (668.4, 669.1),
        (449.2, 448.9),
        (0.2, 0.5),
    ];

    #[test]
    fn nist_norris_certified_values() {
        let points: Vec<Vec<f64>> = NORRIS.iter().map(|&(_, x)| vec![x]).collect();
        let y: Vec<f64> = NORRIS.iter().map(|&(y, _)| y).collect();
        let s = ResponseSurface::fit(
            &PolynomialBasis::bounded(1, 1, 1),
            &points,
            &y,
            &FitOptions::default(),
        )
        .unwrap();
        let f = &s.fit;
        close(f.coefficients[0], -0.262323073774029, 1e-11);
        close(f.coefficients[1], 1.00211681802045, 1e-13);
        close(f.standard_errors[0], 0.232818234301152, 1e-11);
        close(f.standard_errors[1], 0.429796848199937E-03, 1e-11);
        close(f.sigma, 0.884796396144373, 1e-11);
        close(f.r_squared, 0.999993745883712, 1e-14);
        assert_eq!(f.residual_df, 34);
        let a = s.anova();
        assert_eq!((a.model.df, a.residual.df), (1, 34));
        close(a.model.sum_sq, 4255954.13232369, 1e-12);
        close(a.model.mean_sq, 4255954.13232369, 1e-12);
        close(a.residual.sum_sq, 26.6173985294224, 1e-11);
        close(a.residual.mean_sq, 0.782864662630069, 1e-11);
        close(a.model.f.unwrap(), 5436385.54079785, 1e-10);
        // One term: its sequential row is the model row.
        assert_eq!(a.terms.len(), 1);
        assert_eq!(a.terms[0].source, "b1");
        close(a.terms[0].f.unwrap(), 5436385.54079785, 1e-10);
        close(a.total.sum_sq, 4255954.13232369 + 26.6173985294224, 1e-12);
    }

    /// NIST/ITL StRD linear least squares, dataset "Pontius" (lower difficulty; P. Pontius,
    /// "Load cell calibration"), quadratic model y = B0 + B1 x + B2 x², data and certified
    /// values from https://www.itl.nist.gov/div898/strd/lls/data/LINKS/DATA/Pontius.dat
    #[test]
    fn nist_pontius_certified_values() {
        let y = [
            0.11019, 0.21956, 0.32949, 0.43899, 0.54803, 0.65694, 0.76562, 0.87487, 0.98292,
            1.09146, 1.20001, 1.30822, 1.41599, 1.52399, 1.63194, 1.73947, 1.84646, 1.95392,
            2.06128, 2.16844, 0.11052, 0.22018, 0.32939, 0.43886, 0.54798, 0.65739, 0.76596,
            0.87474, 0.98300, 1.09150, 1.20004, 1.30818, 1.41613, 1.52408, 1.63159, 1.73965,
            1.84696, 1.95445, 2.06177, 2.16829,
        ];
        // x = 150000, 300000, …, 3000000, twice.
        let points: Vec<Vec<f64>> = (0..40)
            .map(|i| vec![150000.0 * ((i % 20) + 1) as f64])
            .collect();
        let s = ResponseSurface::fit(
            &PolynomialBasis::bounded(1, 2, 2),
            &points,
            &y,
            &FitOptions::default(),
        )
        .unwrap();
        let f = &s.fit;
        close(f.coefficients[0], 0.673565789473684E-03, 1e-9);
        close(f.coefficients[1], 0.732059160401003E-06, 1e-11);
        close(f.coefficients[2], -0.316081871345029E-14, 1e-9);
        close(f.standard_errors[0], 0.107938612033077E-03, 1e-9);
        close(f.standard_errors[1], 0.157817399981659E-09, 1e-9);
        close(f.standard_errors[2], 0.486652849992036E-16, 1e-9);
        close(f.sigma, 0.205177424076185E-03, 1e-9);
        close(f.r_squared, 0.999999900178537, 1e-14);
        let a = s.anova();
        assert_eq!((a.model.df, a.residual.df), (2, 37));
        close(a.model.sum_sq, 15.6040343244198, 1e-12);
        close(a.model.mean_sq, 7.80201716220991, 1e-12);
        close(a.residual.sum_sq, 0.155761768796992E-05, 1e-9);
        close(a.residual.mean_sq, 0.420977753505385E-07, 1e-9);
        close(a.model.f.unwrap(), 185330865.995752, 1e-9);
    }

    /// NIST/ITL StRD "Wampler1" (higher difficulty; R. H. Wampler, JASA 65:549–565, 1970):
    /// y = 1 + x + x² + x³ + x⁴ + x⁵ exactly at x = 0…20; certified B0…B5 = 1, residual SD 0.
    #[test]
    fn nist_wampler1_exact_quintic() {
        let points: Vec<Vec<f64>> = (0..=20).map(|x| vec![x as f64]).collect();
        let y: Vec<f64> = (0..=20)
            .map(|x| (0..=5).map(|k| (x as f64).powi(k)).sum())
            .collect();
        let s = ResponseSurface::fit(
            &PolynomialBasis::bounded(1, 5, 5),
            &points,
            &y,
            &FitOptions::default(),
        )
        .unwrap();
        for b in &s.fit.coefficients {
            assert!((b - 1.0).abs() < 1e-8, "{:?}", s.fit.coefficients);
        }
        assert!(s.fit.sigma < 1e-8 * 3368421.0);
    }

    #[test]
    fn recovers_a_known_cubic_quartic_surface_from_noisy_samples() {
        let basis = PolynomialBasis::bounded(3, 2, 4);
        let truth: Vec<f64> = (0..basis.len())
            .map(|j| 0.5 + 0.25 * ((j * 7) % 11) as f64)
            .collect();
        let poly = Polynomial {
            basis: basis.clone(),
            coefficients: truth.clone(),
        };
        // 5³ grid, twice: plenty of residual df for a meaningful σ̂.
        let mut points = full_factorial(&[5, 5, 5]);
        points.extend(full_factorial(&[5, 5, 5]));
        let mut noise = Noise(20240611);
        let sd = 0.05;
        let y: Vec<f64> = points
            .iter()
            .map(|x| poly.eval(x) + sd * noise.gaussian())
            .collect();
        let s = ResponseSurface::fit(&basis, &points, &y, &FitOptions::default()).unwrap();
        assert_eq!(s.fit.residual_df, 250 - 23);
        assert!((s.fit.sigma / sd - 1.0).abs() < 0.15, "σ̂ = {}", s.fit.sigma);
        for (j, name) in basis.names().iter().enumerate() {
            let (b, se) = (s.fit.coefficients[j], s.fit.standard_errors[j]);
            assert!(
                (b - truth[j]).abs() < 3.0 * se,
                "{name}: {b} vs {} (se {se})",
                truth[j]
            );
        }
        let x = [0.3, -0.2, 0.9];
        assert!((s.predict(&x) - s.polynomial().eval(&x)).abs() < 1e-12);
        assert!((s.predict(&points[17]) - s.fit.fitted[17]).abs() < 1e-12);
        // Every true term is large against its noise: all significant.
        assert!(s.fit.p_values.iter().all(|&p| p < 1e-6));
        assert!(s.fit.r_squared > 0.99);
    }

    #[test]
    fn spec_models_on_the_three_level_design_leave_4_and_1_residual_df() {
        let points = full_factorial(&[3, 3, 3]);
        let mut noise = Noise(7);
        let y: Vec<f64> = points
            .iter()
            .map(|x| 0.3 + x[0] - 0.5 * x[1] * x[1] + 0.2 * x[0] * x[2] + 0.1 * noise.gaussian())
            .collect();
        for (degree, terms, df) in [(4, 23, 4), (5, 26, 1)] {
            let s = ResponseSurface::fit(
                &PolynomialBasis::bounded(3, 2, degree),
                &points,
                &y,
                &FitOptions::default(),
            )
            .unwrap();
            assert_eq!((s.fit.parameters, s.fit.residual_df), (terms, df));
            let a = s.anova();
            assert_eq!(a.terms.len(), terms - 1);
            assert_eq!((a.model.df, a.residual.df, a.total.df), (terms - 1, df, 26));
            let ss: f64 = a.terms.iter().map(|r| r.sum_sq).sum::<f64>() + a.residual.sum_sq;
            close(ss, a.total.sum_sq, 1e-12);
        }
        // The full quadratic tensor (27 terms) is saturated: no residual df, no F tests.
        let s = ResponseSurface::fit(
            &PolynomialBasis::bounded(3, 2, 6),
            &points,
            &y,
            &FitOptions::default(),
        )
        .unwrap();
        assert_eq!(s.fit.residual_df, 0);
        assert!(s.fit.residuals.iter().all(|e| e.abs() < 1e-12));
        assert!(s.anova().model.f.is_none() && s.fit.standard_errors[0].is_nan());
    }

    #[test]
    fn aliased_terms_are_a_clear_error() {
        // On three levels x³ = x: the cubes are aliased with the linear terms.
        let points = full_factorial(&[3, 3, 3]);
        let y: Vec<f64> = points.iter().map(|x| x[0] + x[1] * x[2]).collect();
        let basis = PolynomialBasis::bounded(3, 3, 3);
        let e = ResponseSurface::fit(&basis, &points, &y, &FitOptions::default()).unwrap_err();
        match &e {
            RegressionError::RankDeficient {
                rank,
                parameters,
                dependent,
                names,
            } => {
                assert_eq!((*rank, *parameters), (17, 20));
                assert_eq!(names, &["b111", "b222", "b333"]);
                let reduced = basis.without_terms(dependent);
                let s =
                    ResponseSurface::fit(&reduced, &points, &y, &FitOptions::default()).unwrap();
                assert!((s.polynomial().coefficient("b23").unwrap() - 1.0).abs() < 1e-12);
            }
            other => panic!("{other:?}"),
        }
        assert!(e
            .to_string()
            .contains("b111, b222, b333 are linear combinations"));
        // A duplicated column and too few points.
        let x = DMatrix::from_row_slice(3, 2, &[1.0, 1.0, 1.0, 1.0, 1.0, 1.0]);
        let e = least_squares(&x, &[1.0, 2.0, 3.0], true, &FitOptions::default()).unwrap_err();
        assert!(
            matches!(&e, RegressionError::RankDeficient { dependent, .. } if dependent == &[1])
        );
        assert!(e
            .to_string()
            .contains("column 1 is a linear combination of earlier terms"));
        let few = full_factorial(&[2, 2]);
        assert!(matches!(
            ResponseSurface::fit(
                &PolynomialBasis::bounded(2, 2, 4),
                &few,
                &[0.0; 4],
                &FitOptions::default()
            ),
            Err(RegressionError::TooFewObservations {
                observations: 4,
                parameters: 9
            })
        ));
        assert!(matches!(
            least_squares(&x, &[1.0, f64::NAN, 3.0], true, &FitOptions::default()),
            Err(RegressionError::NonFinite {
                what: "response",
                index: 1
            })
        ));
    }

    #[test]
    fn sequential_anova_t_and_p_match_statsmodels() {
        // Reference: statsmodels 0.15.0, with the data below as y and x1, x2 columns,
        //   m = smf.ols("y ~ x1 + x2 + I(x1**2) + I(x1*x2) + I(x2**2)", df).fit()
        //   sm.stats.anova_lm(m, typ=1); m.params; m.bse; m.tvalues; m.pvalues
        // (the formula's term order is this basis's order: b1, b2, b11, b12, b22).
        let points = full_factorial(&[3, 3]);
        let mut points2 = points.clone();
        points2.extend(points.iter().cloned());
        let y = [
            3.1, 4.0, 6.2, 2.2, 3.5, 5.1, 2.9, 3.0, 5.9, 3.4, 4.1, 5.8, 2.5, 3.1, 5.4, 2.6, 3.3,
            6.1,
        ];
        let s = ResponseSurface::fit(
            &PolynomialBasis::bounded(2, 2, 2),
            &points2,
            &y,
            &FitOptions::default(),
        )
        .unwrap();
        let a = s.anova();
        let names: Vec<&str> = a.terms.iter().map(|r| r.source.as_str()).collect();
        assert_eq!(names, ["b1", "b2", "b11", "b12", "b22"]);
        let want_ss = [
            26.403333333333333,
            0.6533333333333327,
            2.351111111111111,
            0.125,
            1.284444444444441,
        ];
        let want_f = [
            376.9411764705886,
            9.327164573694647,
            33.565102445472604,
            1.7845340383344248,
            18.337078651685363,
        ];
        let want_p = [
            1.9720517180323197e-10,
            0.010009275160508353,
            8.559293932693826e-05,
            0.20637646056213546,
            0.0010648957856725417,
        ];
        for (k, row) in a.terms.iter().enumerate() {
            close(row.sum_sq, want_ss[k], 1e-10);
            close(row.f.unwrap(), want_f[k], 1e-10);
            close(row.p.unwrap(), want_p[k], 1e-9);
        }
        close(a.residual.sum_sq, 0.8405555555555546, 1e-10);
        let params = [
            3.122222222222223,
            1.483333333333333,
            -0.23333333333333295,
            0.7666666666666674,
            0.12499999999999967,
            0.566666666666666,
        ];
        let bse = [
            0.13948944234869157,
            0.07640151410819475,
            0.07640151410819479,
            0.13233130421058373,
            0.09357236257056371,
            0.13233130421058373,
        ];
        let t = [
            22.383215314728872,
            19.414972996905988,
            -3.054040696142509,
            5.793539716397279,
            1.3358645284363329,
            4.282181529511024,
        ];
        let pt = [
            3.732952133937618e-11,
            1.972051718032314e-10,
            0.010009275160508438,
            8.559293932693751e-05,
            0.20637646056213524,
            0.0010648957856725402,
        ];
        for j in 0..6 {
            close(s.fit.coefficients[j], params[j], 1e-10);
            close(s.fit.standard_errors[j], bse[j], 1e-10);
            close(s.fit.t_values[j], t[j], 1e-10);
            close(s.fit.p_values[j], pt[j], 1e-9);
        }
        close(s.fit.r_squared, 0.9734486873508353, 1e-12);
        close(s.fit.adj_r_squared, 0.9623856404136834, 1e-12);
        close(a.model.f.unwrap(), 87.99101123595517, 1e-10);
        close(a.model.p.unwrap(), 4.96302206430449e-09, 1e-9);
        // Sequential SS depend on the order: the last term's equals its partial (type III) SS,
        // the first one's does not in general — here b1 is orthogonal to everything (balanced
        // design), so moving it last leaves its SS unchanged.
        let reordered = PolynomialBasis::from_terms(
            2,
            [0, 2, 3, 4, 5, 1]
                .iter()
                .map(|&j| s.basis.terms()[j].clone())
                .collect(),
        )
        .unwrap();
        let s2 = ResponseSurface::fit(&reordered, &points2, &y, &FitOptions::default()).unwrap();
        close(s2.fit.sequential_ss[5], s.fit.sequential_ss[1], 1e-10);
    }

    #[test]
    fn residual_diagnostics_use_blom_positions() {
        let points = full_factorial(&[3, 3]);
        let y = [3.1, 4.0, 6.2, 2.2, 3.5, 5.1, 2.9, 3.0, 5.9];
        let s = ResponseSurface::fit(
            &PolynomialBasis::bounded(2, 1, 2),
            &points,
            &y,
            &FitOptions::default(),
        )
        .unwrap();
        let d = s.fit.residual_diagnostics();
        let n = 9.0;
        assert_eq!(d.fitted_residual.len(), 9);
        for (i, &(q, r)) in d.normal_probability.iter().enumerate() {
            let pos = (i as f64 + 1.0 - 0.375) / (n + 0.25);
            assert_eq!(q, normal_quantile(pos));
            if i > 0 {
                assert!(r >= d.normal_probability[i - 1].1);
            }
        }
        // Symmetric positions give symmetric quantiles; the middle one is 0.
        assert!((d.normal_probability[0].0 + d.normal_probability[8].0).abs() < 1e-15);
        assert_eq!(d.normal_probability[4].0, 0.0);
        for (i, &yi) in y.iter().enumerate() {
            let (fit, e) = d.fitted_residual[i];
            assert!((fit + e - yi).abs() < 1e-12);
            assert!((d.standardized[i] - e / s.fit.sigma).abs() < 1e-12);
            let h = s.fit.leverage[i];
            assert!((d.studentized[i] - e / (s.fit.sigma * (1.0 - h).sqrt())).abs() < 1e-12);
        }
        // Leverages sum to the number of parameters.
        close(s.fit.leverage.iter().sum::<f64>(), 4.0, 1e-12);
    }

    #[test]
    fn fixing_a_factor_collects_the_remaining_polynomial() {
        let basis = PolynomialBasis::bounded(3, 2, 4);
        let coefficients: Vec<f64> = (0..basis.len()).map(|j| 1.0 + 0.1 * j as f64).collect();
        let poly = Polynomial {
            basis,
            coefficients,
        };
        for level in [-1.0, 0.0, 1.0, 0.37] {
            // Fix factor 1 (a_TFC): nine coefficients in (x2, x3), renumbered (x1, x2).
            let fixed = poly.fix_factor(0, level).unwrap();
            assert_eq!(
                fixed.basis.names(),
                ["b0", "b1", "b2", "b11", "b12", "b22", "b112", "b122", "b1122"]
            );
            for x in full_factorial(&[4, 4]) {
                let full = poly.eval(&[level, x[0], x[1]]);
                assert!((fixed.eval(&x) - full).abs() < 1e-12);
            }
            // b0 collects b0 + b1·a + b11·a².
            let c = |n: &str| poly.coefficient(n).unwrap();
            let want_b0 = c("b0") + c("b1") * level + c("b11") * level * level;
            assert!((fixed.coefficient("b0").unwrap() - want_b0).abs() < 1e-12);
            // x2²x3² can only come from b2233 (a⁰): unchanged by the level.
            assert_eq!(fixed.coefficient("b1122"), Some(c("b2233")));
        }
        // Fixing the last factor keeps the first two's numbering; x1·x2 collects b12·x3⁰,
        // b123·x3 and b1233·x3² at x3 = 1.
        let fixed = poly.fix_factor(2, 1.0).unwrap();
        let c = |n: &str| poly.coefficient(n).unwrap();
        assert!(
            (fixed.coefficient("b12").unwrap() - (c("b12") + c("b123") + c("b1233"))).abs() < 1e-12
        );
        assert!(matches!(
            poly.fix_factor(3, 0.0),
            Err(RegressionError::InvalidFactor {
                factor: 3,
                factors: 3
            })
        ));
    }

    #[test]
    fn residual_error_of_one_level() {
        let points = full_factorial(&[3, 3, 3]);
        let mut noise = Noise(11);
        let y: Vec<f64> = points.iter().map(|x| x[0] + noise.gaussian()).collect();
        let s = ResponseSurface::fit(
            &PolynomialBasis::bounded(3, 2, 4),
            &points,
            &y,
            &FitOptions::default(),
        )
        .unwrap();
        let by_level: f64 = [-1.0, 0.0, 1.0]
            .iter()
            .map(|&l| s.residual_ss_at(0, l, 1e-9))
            .sum();
        close(by_level, s.fit.rss, 1e-12);
    }
}
