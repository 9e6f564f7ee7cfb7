//! Special functions for the response-surface statistics (§2.3; docs/doe.md): log-gamma, the
//! regularised incomplete beta function, F and Student-t tail probabilities, and the
//! standard-normal quantile for normal-probability plots of residuals.
//!
//! Pure `f64` functions; arguments outside a function's domain give `NaN` (as `libm` does)
//! rather than an error, because they only ever come from a fit's own degrees of freedom.
//!
//! - `ln_gamma`: Lanczos approximation, g = 7, 9 coefficients (P. Godfrey's set), with the
//!   reflection formula below ½; about 15 significant digits for x > 0.
//! - `reg_inc_beta`: continued fraction of Abramowitz & Stegun 26.5.8 evaluated with the
//!   modified Lentz method (the algorithm of Numerical Recipes §6.4), on whichever side
//!   (`x` or `1 − x`) converges fast, so both tails keep their relative accuracy.
//! - `normal_quantile`: M. J. Wichura, "Algorithm AS 241: The percentage points of the normal
//!   distribution", Applied Statistics 37(3):477–484, 1988 (PPND16, about 16 digits).

use std::f64::consts::PI;

/// `ln |Γ(x)|`. `+∞` at the poles (0, −1, −2, …), `NaN` for `NaN`.
// The published coefficients keep their published digits.
#[allow(clippy::excessive_precision)]
pub fn ln_gamma(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x == f64::INFINITY {
        return f64::INFINITY;
    }
    if x <= 0.0 && x == x.floor() {
        return f64::INFINITY;
    }
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1 − x) = π / sin(πx); the series below is accurate only for x ≥ ½.
        return (PI / (PI * x).sin().abs()).ln() - ln_gamma(1.0 - x);
    }
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_93,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_13,
        -176.615_029_162_140_59,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_571_6e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let z = x - 1.0;
    let mut series = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        series += c / (z + i as f64);
    }
    let t = z + G + 0.5;
    0.5 * (2.0 * PI).ln() + (z + 0.5) * t.ln() - t + series.ln()
}

/// `ln B(a, b) = ln Γ(a) + ln Γ(b) − ln Γ(a + b)`.
pub fn ln_beta(a: f64, b: f64) -> f64 {
    ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b)
}

/// Continued fraction for `I_x(a, b)` (A&S 26.5.8), modified Lentz. Converges quickly for
/// `x < (a + 1)/(a + b + 2)`.
fn beta_continued_fraction(a: f64, b: f64, x: f64) -> f64 {
    const MAX_ITERATIONS: usize = 10_000;
    const EPS: f64 = 1e-16;
    // Stand-in for zero denominators (Lentz): small, but not so small its reciprocal overflows.
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..=MAX_ITERATIONS {
        let m = m as f64;
        let m2 = 2.0 * m;
        // Even step d_{2m}.
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        h *= d * c;
        // Odd step d_{2m+1}.
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

/// `(I_x(a, b), 1 − I_x(a, b))`, each computed directly where it is the small one, so a tail
/// probability of 1e-80 keeps its digits instead of being `1 − (1 − 1e-80)`.
fn inc_beta_pair(a: f64, b: f64, x: f64) -> (f64, f64) {
    if x.is_nan() || a.is_nan() || b.is_nan() || a <= 0.0 || b <= 0.0 || !(0.0..=1.0).contains(&x) {
        return (f64::NAN, f64::NAN);
    }
    if x == 0.0 {
        return (0.0, 1.0);
    }
    if x == 1.0 {
        return (1.0, 0.0);
    }
    // x^a (1 − x)^b / B(a, b), in logs; ln_1p keeps (1 − x) accurate for small x.
    let front = (a * x.ln() + b * (-x).ln_1p() - ln_beta(a, b)).exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        let i = front * beta_continued_fraction(a, b, x) / a;
        (i, 1.0 - i)
    } else {
        let j = front * beta_continued_fraction(b, a, 1.0 - x) / b;
        (1.0 - j, j)
    }
}

/// Regularised incomplete beta function `I_x(a, b)` for `a, b > 0`, `0 ≤ x ≤ 1`.
pub fn reg_inc_beta(a: f64, b: f64, x: f64) -> f64 {
    inc_beta_pair(a, b, x).0
}

/// Survival function of the F distribution, `P(F(d1, d2) > f)`: the p-value of an F test.
/// `f ≤ 0` gives 1, `f = +∞` gives 0; non-positive degrees of freedom give `NaN`.
pub fn f_sf(f: f64, d1: f64, d2: f64) -> f64 {
    if f.is_nan() || d1.is_nan() || d2.is_nan() || d1 <= 0.0 || d2 <= 0.0 {
        return f64::NAN;
    }
    if f <= 0.0 {
        return 1.0;
    }
    if f == f64::INFINITY {
        return 0.0;
    }
    // P(F > f) = I_{d2/(d2 + d1 f)}(d2/2, d1/2) (A&S 26.6.2).
    let x = d2 / (d2 + d1 * f);
    inc_beta_pair(d2 / 2.0, d1 / 2.0, x).0
}

/// Two-sided p-value of a Student-t statistic, `P(|T(df)| > |t|)`.
pub fn t_two_sided_p(t: f64, df: f64) -> f64 {
    if t.is_nan() || df.is_nan() || df <= 0.0 {
        return f64::NAN;
    }
    if t.is_infinite() {
        return 0.0;
    }
    // P(|T| > t) = I_{df/(df + t²)}(df/2, ½) (A&S 26.7.1).
    let x = df / (df + t * t);
    inc_beta_pair(df / 2.0, 0.5, x).0
}

/// Standard-normal quantile `Φ⁻¹(p)` (Wichura's AS 241). `±∞` at 0 and 1, `NaN` outside.
// The published coefficients keep their published digits.
#[allow(clippy::excessive_precision)]
pub fn normal_quantile(p: f64) -> f64 {
    if p.is_nan() || !(0.0..=1.0).contains(&p) {
        return f64::NAN;
    }
    if p == 0.0 {
        return f64::NEG_INFINITY;
    }
    if p == 1.0 {
        return f64::INFINITY;
    }
    const A: [f64; 8] = [
        3.387_132_872_796_366_608,
        1.331_416_678_917_843_774_5e2,
        1.971_590_950_306_551_442_7e3,
        1.373_169_376_550_946_112_5e4,
        4.592_195_393_154_987_145_7e4,
        6.726_577_092_700_870_085_3e4,
        3.343_057_558_358_812_810_5e4,
        2.509_080_928_730_122_672_7e3,
    ];
    const B: [f64; 8] = [
        1.0,
        4.231_333_070_160_091_125_2e1,
        6.871_870_074_920_579_083e2,
        5.394_196_021_424_751_107_7e3,
        2.121_379_430_158_659_586_7e4,
        3.930_789_580_009_271_061e4,
        2.872_908_573_572_194_267_4e4,
        5.226_495_278_852_854_561e3,
    ];
    const C: [f64; 8] = [
        1.423_437_110_749_683_577_34,
        4.630_337_846_156_545_295_9,
        5.769_497_221_460_691_405_5,
        3.647_848_324_763_204_605_04,
        1.270_458_252_452_368_382_58,
        2.417_807_251_774_506_117_7e-1,
        2.272_384_498_926_918_458_33e-2,
        7.745_450_142_783_414_076_4e-4,
    ];
    const D: [f64; 8] = [
        1.0,
        2.053_191_626_637_758_821_87,
        1.676_384_830_183_803_849_4,
        6.897_673_349_851_000_045_5e-1,
        1.481_039_764_274_800_745_9e-1,
        1.519_866_656_361_645_719_66e-2,
        5.475_938_084_995_344_946e-4,
        1.050_750_071_644_416_843_24e-9,
    ];
    const E: [f64; 8] = [
        6.657_904_643_501_103_777_2,
        5.463_784_911_164_114_369_9,
        1.784_826_539_917_291_335_8,
        2.965_605_718_285_048_912_3e-1,
        2.653_218_952_657_612_309_3e-2,
        1.242_660_947_388_078_438_6e-3,
        2.711_555_568_743_487_578_15e-5,
        2.010_334_399_292_288_132_65e-7,
    ];
    const F: [f64; 8] = [
        1.0,
        5.998_322_065_558_879_376_9e-1,
        1.369_298_809_227_358_053_1e-1,
        1.487_536_129_085_061_485_25e-2,
        7.868_691_311_456_132_591e-4,
        1.846_318_317_510_054_681_8e-5,
        1.421_511_758_316_445_888_7e-7,
        2.044_263_103_389_939_785_64e-15,
    ];
    fn horner(c: &[f64; 8], x: f64) -> f64 {
        c.iter().rev().fold(0.0, |acc, &k| acc * x + k)
    }
    let q = p - 0.5;
    if q.abs() <= 0.425 {
        let r = 0.180_625 - q * q;
        return q * horner(&A, r) / horner(&B, r);
    }
    let tail = if q < 0.0 { p } else { 1.0 - p };
    let r = (-tail.ln()).sqrt();
    let z = if r <= 5.0 {
        let r = r - 1.6;
        horner(&C, r) / horner(&D, r)
    } else {
        let r = r - 5.0;
        horner(&E, r) / horner(&F, r)
    };
    if q < 0.0 {
        -z
    } else {
        z
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

    #[test]
    fn ln_gamma_matches_scipy() {
        // scipy.special.gammaln(x) (SciPy 1.17.1) for x in the list.
        let cases: [(f64, f64); 10] = [
            (0.1, 2.252_712_651_734_206),
            (0.5, 0.572_364_942_924_7),
            (1.0, 0.0),
            (1.5, -0.120_782_237_635_245_26),
            (2.0, 0.0),
            (3.7, 1.428_072_326_665_388),
            (17.0, 30.671_860_106_080_675),
            (123.456, 469.605_547_129_929_5),
            (1e4, 82_099.717_496_442_38),
            (-2.5, -0.056_243_716_497_674_01),
        ];
        for (x, want) in cases {
            // Absolute error near the zeros of ln Γ (x = 1, 2, and −2.5 where the reflection
            // formula subtracts two numbers near 1.2), relative elsewhere.
            let got = ln_gamma(x);
            let tol = 2e-14 * want.abs().max(1.0);
            assert!(
                (got - want).abs() <= tol,
                "ln_gamma({x}) = {got:e}, want {want:e}"
            );
        }
        assert_eq!(ln_gamma(0.0), f64::INFINITY);
        assert_eq!(ln_gamma(-3.0), f64::INFINITY);
        assert!(ln_gamma(f64::NAN).is_nan());
    }

    #[test]
    fn incomplete_beta_matches_scipy() {
        // scipy.special.betainc(a, b, x) (SciPy 1.17.1) for (a, b, x) in the list.
        let cases = [
            (0.5, 0.5, 0.3, 0.369_010_119_565_545_36),
            (2.0, 3.0, 0.4, 0.524_799_999_999_999_9),
            (17.0, 0.5, 0.9, 0.060_252_071_502_404_844),
            (10.0, 20.0, 0.05, 8.109_121_873_645_938e-7),
            (200.0, 150.0, 0.6, 0.860_190_660_480_152_8),
            (1.5, 40.0, 0.2, 0.999_551_801_977_843_3),
            (1.5, 40.0, 0.999, 1.0),
        ];
        for (a, b, x, want) in cases {
            close(reg_inc_beta(a, b, x), want, 1e-13);
        }
        assert_eq!(reg_inc_beta(2.0, 3.0, 0.0), 0.0);
        assert_eq!(reg_inc_beta(2.0, 3.0, 1.0), 1.0);
        assert!(reg_inc_beta(-1.0, 3.0, 0.5).is_nan());
        assert!(reg_inc_beta(1.0, 3.0, 1.5).is_nan());
        // Symmetry I_x(a, b) = 1 − I_{1−x}(b, a).
        let (a, b, x) = (3.3, 7.1, 0.27);
        close(
            reg_inc_beta(a, b, x),
            1.0 - reg_inc_beta(b, a, 1.0 - x),
            1e-14,
        );
    }

    #[test]
    fn f_survival_matches_scipy() {
        // scipy.stats.f.sf(f, d1, d2) (SciPy 1.17.1) for (f, d1, d2) in the list. The last two
        // are the NIST StRD Norris and Pontius model F statistics (deep tail).
        let cases = [
            (1.0, 1.0, 4.0, 0.373_900_966_300_058_87),
            (3.5, 2.0, 10.0, 0.070_429_627_772_374_27),
            (0.2, 5.0, 3.0, 0.942_331_114_377_562_8),
            (12.3, 1.0, 4.0, 0.024_735_897_868_028_316),
            (2.7, 22.0, 4.0, 0.172_850_366_642_175_2),
            (5_436_385.540_797_85, 1.0, 34.0, 4.654_040_852_472_337e-90),
            (185_330_865.995_752, 2.0, 37.0, 3.059_445_382_857_971_2e-130),
        ];
        for (f, d1, d2, want) in cases {
            close(f_sf(f, d1, d2), want, 1e-12);
        }
        assert_eq!(f_sf(0.0, 3.0, 4.0), 1.0);
        assert_eq!(f_sf(f64::INFINITY, 3.0, 4.0), 0.0);
        assert!(f_sf(1.0, 0.0, 4.0).is_nan());
    }

    #[test]
    fn student_t_two_sided_matches_scipy() {
        // 2 * scipy.stats.t.sf(abs(t), df) (SciPy 1.17.1) for (t, df) in the list.
        let cases = [
            (2.0, 4.0, 0.116_116_523_516_815_56),
            (-2.0, 4.0, 0.116_116_523_516_815_56),
            (0.5, 1.0, 0.704_832_764_699_133_5),
            (3.1, 25.0, 0.004_742_531_447_984_517),
            (10.0, 34.0, 1.166_556_120_654_683_7e-11),
            (1e-3, 4.0, 0.999_250_000_156_25),
        ];
        for (t, df, want) in cases {
            close(t_two_sided_p(t, df), want, 1e-12);
        }
        assert_eq!(t_two_sided_p(0.0, 7.0), 1.0);
        assert_eq!(t_two_sided_p(f64::INFINITY, 7.0), 0.0);
    }

    #[test]
    fn normal_quantile_matches_scipy() {
        // scipy.stats.norm.ppf(p) (SciPy 1.17.1) for p in the list: all three AS 241 branches.
        let cases = [
            (0.5, 0.0),
            (0.975, 1.959_963_984_540_054),
            (0.025, -1.959_963_984_540_054_5),
            (0.1, -1.281_551_565_544_600_4),
            (0.6, 0.253_347_103_135_799_7),
            (1e-3, -3.090_232_306_167_813),
            (0.999_9, 3.719_016_485_455_709),
            (1e-10, -6.361_340_902_404_056),
            (1e-300, -37.047_096_299_361_2),
        ];
        for (p, want) in cases {
            let got = normal_quantile(p);
            if want == 0.0 {
                assert_eq!(got, 0.0);
            } else {
                close(got, want, 1e-14);
            }
        }
        assert_eq!(normal_quantile(0.0), f64::NEG_INFINITY);
        assert_eq!(normal_quantile(1.0), f64::INFINITY);
        assert!(normal_quantile(1.5).is_nan());
    }
}
