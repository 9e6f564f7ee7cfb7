//! Post-processing metrics of the slider dynamics (docs/dynamics-metrics.md): pure functions on
//! uniformly sampled time series of one case (steady window, mean/std, FHM/BV, % solid contact,
//! contact severity, HMS) and on the per-case results of an actuation sweep (regime, touchdown,
//! slopes A–D and critical point, optimum operating point).
//!
//! Self-contained: std + `thiserror` only. SI units throughout (m, s, N, Pa, m²); percentages
//! are in % (0–100). Field names carry the unit suffix (`_m`, `_s`, `_n`, `_pa`, `_m2`) or
//! are dimensionless (slopes in m/m = nm/nm, ratios). Choices the spec leaves open are stated in
//! the doc comment of the item that makes them and collected in `docs/dynamics-metrics.md`.
use std::ops::Range;

/// Errors of the metrics: bad input, never a numerical failure.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricsError {
    #[error("{what}: empty series")]
    Empty { what: &'static str },
    #[error("{what}: {got} samples, expected {expected}")]
    LengthMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("{what}: non-finite sample at index {index}")]
    NonFinite { what: &'static str, index: usize },
    #[error("{name} = {value}: {reason}")]
    InvalidParameter {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    #[error("steady window [{start_s:e}, {end_s:e}] s holds no sample of {n} samples from {t0_s:e} s every {dt_s:e} s")]
    EmptyWindow {
        start_s: f64,
        end_s: f64,
        t0_s: f64,
        dt_s: f64,
        n: usize,
    },
    #[error("{what}: needs at least {needed} samples, got {got}")]
    TooShort {
        what: &'static str,
        needed: usize,
        got: usize,
    },
    #[error("actuations must be finite and strictly increasing (index {index})")]
    NotIncreasing { index: usize },
}

pub type Result<T> = std::result::Result<T, MetricsError>;

fn check_finite(what: &'static str, x: &[f64]) -> Result<()> {
    if x.is_empty() {
        return Err(MetricsError::Empty { what });
    }
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(MetricsError::NonFinite { what, index }),
        None => Ok(()),
    }
}

fn check_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(MetricsError::InvalidParameter {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}

// ------------------------------------------------------------------------------------------
// Steady-state window
// ------------------------------------------------------------------------------------------

/// The steady-state window `[start_s, end_s]` (both ends inclusive) [§7: 0.5–2.0 ms for the 2-DOF
/// cases and S3].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SteadyWindow {
    pub start_s: f64,
    pub end_s: f64,
}

impl SteadyWindow {
    /// 0.5–2.0 ms (docs/dynamics-metrics.md).
    pub const DEFAULT: SteadyWindow = SteadyWindow {
        start_s: 0.5e-3,
        end_s: 2.0e-3,
    };

    /// Indices of the samples `t_k = t0_s + k·dt_s`, `k < n`, with `start_s ≤ t_k ≤ end_s`.
    /// Sample times within 1e-9·dt of an end count as inside (the ends are usually on the grid
    /// but are not exactly representable). An end past the record is clipped to it; a window
    /// holding no sample is an error.
    pub fn indices(&self, t0_s: f64, dt_s: f64, n: usize) -> Result<Range<usize>> {
        check_positive("dt_s", dt_s)?;
        let empty = MetricsError::EmptyWindow {
            start_s: self.start_s,
            end_s: self.end_s,
            t0_s,
            dt_s,
            n,
        };
        if !(self.start_s.is_finite() && self.end_s.is_finite() && t0_s.is_finite())
            || self.end_s < self.start_s
            || n == 0
        {
            return Err(empty);
        }
        let first = ((self.start_s - t0_s) / dt_s - 1e-9).ceil().max(0.0);
        let last = ((self.end_s - t0_s) / dt_s + 1e-9).floor();
        if last < 0.0 || first > last || first >= n as f64 {
            return Err(empty);
        }
        let last = (last as usize).min(n - 1);
        Ok(first as usize..last + 1)
    }

    /// The sub-slice of `series` inside the window.
    pub fn slice<'a>(&self, series: &'a [f64], t0_s: f64, dt_s: f64) -> Result<&'a [f64]> {
        Ok(&series[self.indices(t0_s, dt_s, series.len())?])
    }
}

// ------------------------------------------------------------------------------------------
// Per-series statistics
// ------------------------------------------------------------------------------------------

/// Mean, standard deviation and range of a series (same unit as the series).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SeriesStats {
    pub mean: f64,
    /// Population standard deviation (divide by n): the RMS fluctuation about the mean over the
    /// window, as for a time-series RMS [choice: the spec does not say; for the thousands of
    /// samples of a window the n−1 form differs by < 0.01 %].
    pub std: f64,
    pub min: f64,
    pub max: f64,
    pub n: usize,
}

/// Mean, population standard deviation, min and max (two-pass, so the std of a 1e-9 m signal
/// with a 1e-8 m offset keeps its digits).
pub fn series_stats(x: &[f64]) -> Result<SeriesStats> {
    check_finite("series", x)?;
    let n = x.len();
    let mean = x.iter().sum::<f64>() / n as f64;
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n as f64;
    let (min, max) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    Ok(SeriesStats {
        mean,
        std: var.sqrt(),
        min,
        max,
        n,
    })
}

// ------------------------------------------------------------------------------------------
// FHM / BV (eq. 2.1)
// ------------------------------------------------------------------------------------------

/// Number of largest/smallest samples averaged by eq. 2.1 [seed §2.3.2].
pub const EXTREME_COUNT: usize = 5;

/// Flying-height modulation or bouncing vibration of one series (eq. 2.1):
/// `percent = 100·(fh_max_m − fh_min_m)/FH_nom`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Modulation {
    pub percent: f64,
    /// Mean of the largest values used [m].
    pub fh_max_m: f64,
    /// Mean of the smallest values used [m].
    pub fh_min_m: f64,
    /// How many values entered each mean (the extrema variant may have fewer than asked).
    pub count_max: usize,
    pub count_min: usize,
}

/// What eq. 2.1 is called for a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum VibrationKind {
    /// Flying-height modulation: the case is flying.
    Fhm,
    /// Bouncing vibration: the case contacts.
    Bv,
}

impl VibrationKind {
    /// BV when any steady-window sample is in solid contact (`c < 0`), FHM otherwise [choice:
    /// §8 says "FHM when the case is flying, BV when it contacts"; "contacts" is read as the
    /// touchdown criterion of §8, so every case at or beyond touchdown reports BV]. Only the
    /// label depends on this; the number is the same formula.
    pub fn for_case(percent_solid_contact: f64) -> Self {
        if percent_solid_contact > 0.0 {
            VibrationKind::Bv
        } else {
            VibrationKind::Fhm
        }
    }
}

fn modulation_from(
    maxima: &mut [f64],
    minima: &mut [f64],
    count: usize,
    fh_nom_m: f64,
) -> Modulation {
    maxima.sort_unstable_by(|a, b| b.total_cmp(a));
    minima.sort_unstable_by(f64::total_cmp);
    let nmax = count.min(maxima.len());
    let nmin = count.min(minima.len());
    let fh_max_m = maxima[..nmax].iter().sum::<f64>() / nmax as f64;
    let fh_min_m = minima[..nmin].iter().sum::<f64>() / nmin as f64;
    Modulation {
        percent: 100.0 * (fh_max_m - fh_min_m) / fh_nom_m,
        fh_max_m,
        fh_min_m,
        count_max: nmax,
        count_min: nmin,
    }
}

/// Eq. 2.1 on the raw samples (the faithful definition): `FH_max` = mean of the `count` largest
/// samples, `FH_min` = mean of the `count` smallest, `100·(FH_max − FH_min)/fh_nom_m` %.
/// `count` is [`EXTREME_COUNT`] in the dissertation; the series needs at least `count` samples.
pub fn modulation(fh_m: &[f64], fh_nom_m: f64, count: usize) -> Result<Modulation> {
    check_finite("fh", fh_m)?;
    check_positive("fh_nom_m", fh_nom_m)?;
    if count == 0 || fh_m.len() < count {
        return Err(MetricsError::TooShort {
            what: "fh (modulation)",
            needed: count.max(1),
            got: fh_m.len(),
        });
    }
    let mut a = fh_m.to_vec();
    let mut b = fh_m.to_vec();
    Ok(modulation_from(&mut a, &mut b, count, fh_nom_m))
}

/// Local maxima and minima of a series: interior runs of equal values bounded by smaller
/// (maximum) or larger (minimum) neighbours on both sides; each plateau counts once; the two
/// ends of the window are not extrema (the window cuts the signal there).
pub fn local_extrema(x: &[f64]) -> (Vec<f64>, Vec<f64>) {
    // Run-length compress equal neighbours.
    let mut runs: Vec<f64> = Vec::with_capacity(x.len());
    for &v in x {
        if runs.last() != Some(&v) {
            runs.push(v);
        }
    }
    let (mut maxima, mut minima) = (Vec::new(), Vec::new());
    for w in runs.windows(3) {
        if w[1] > w[0] && w[1] > w[2] {
            maxima.push(w[1]);
        } else if w[1] < w[0] && w[1] < w[2] {
            minima.push(w[1]);
        }
    }
    (maxima, minima)
}

/// Robustness variant of eq. 2.1 on the local extrema: mean of the `count` largest local maxima
/// minus mean of the `count` smallest local minima. With fewer extrema than `count` all of them
/// are used (see `count_max`/`count_min`); `None` when the window has no interior maximum or
/// no interior minimum (monotone signal).
pub fn modulation_extrema(fh_m: &[f64], fh_nom_m: f64, count: usize) -> Result<Option<Modulation>> {
    check_finite("fh", fh_m)?;
    check_positive("fh_nom_m", fh_nom_m)?;
    if count == 0 {
        return Err(MetricsError::TooShort {
            what: "modulation count",
            needed: 1,
            got: 0,
        });
    }
    let (mut maxima, mut minima) = local_extrema(fh_m);
    if maxima.is_empty() || minima.is_empty() {
        return Ok(None);
    }
    Ok(Some(modulation_from(
        &mut maxima,
        &mut minima,
        count,
        fh_nom_m,
    )))
}

// ------------------------------------------------------------------------------------------
// Solid contact, spacings
// ------------------------------------------------------------------------------------------

/// % of samples in solid contact, clearance `c < 0` (§8).
pub fn percent_solid_contact(clearance_m: &[f64]) -> Result<f64> {
    check_finite("clearance", clearance_m)?;
    let n = clearance_m.iter().filter(|&&c| c < 0.0).count();
    Ok(100.0 * n as f64 / clearance_m.len() as f64)
}

/// 3-DOF form: % of samples in which *any* feature is in solid contact. `solid_margin_m[i][k]`
/// is feature i's `s_i − 3σ` at sample k (negative = solid contact); all features need the same
/// length.
pub fn percent_solid_contact_any(solid_margin_m: &[&[f64]]) -> Result<f64> {
    let first = solid_margin_m
        .first()
        .ok_or(MetricsError::Empty { what: "features" })?;
    let n = first.len();
    for f in solid_margin_m {
        check_finite("feature margin", f)?;
        if f.len() != n {
            return Err(MetricsError::LengthMismatch {
                what: "feature margin",
                expected: n,
                got: f.len(),
            });
        }
    }
    let hits = (0..n)
        .filter(|&k| solid_margin_m.iter().any(|f| f[k] < 0.0))
        .count();
    Ok(100.0 * hits as f64 / n as f64)
}

/// Clearance from the chapter-2 flying height: `c = FH + T0 − 3σ` (§1.2).
pub fn clearance_from_fh(fh_m: f64, t0_m: f64, sigma_m: f64) -> f64 {
    fh_m + t0_m - 3.0 * sigma_m
}

/// Head–media spacing `HMS = c − 2T0` (§1.2; negative = inside the lubricant).
pub fn head_media_spacing(clearance_m: f64, t0_m: f64) -> f64 {
    clearance_m - 2.0 * t0_m
}

/// Magnetic spacing `HMS + t + t_DLC,disk + 3σ` (§1.2; slider DLC assumed burnished).
pub fn magnetic_spacing(hms_m: f64, lube_total_m: f64, dlc_disk_m: f64, sigma_m: f64) -> f64 {
    hms_m + lube_total_m + dlc_disk_m + 3.0 * sigma_m
}

/// Plasticity index `ψ = (E*/H)·sqrt(σ/R)` [seed §2.1.3].
pub fn plasticity_index(e_star_pa: f64, hardness_pa: f64, sigma_m: f64, radius_m: f64) -> f64 {
    (e_star_pa / hardness_pa) * (sigma_m / radius_m).sqrt()
}

/// Flyability parameter `ξ = (c̄/FH_nom)·(V/100)` (§2.3; an assumption, docs/doe.md).
pub fn flyability(mean_clearance_m: f64, fh_nom_m: f64, vibration_percent: f64) -> f64 {
    (mean_clearance_m / fh_nom_m) * (vibration_percent / 100.0)
}

// ------------------------------------------------------------------------------------------
// Contact severity
// ------------------------------------------------------------------------------------------

/// `μ`, `P_m` and `τ` are defined only where the contact force exceeds this (1 µN, §8).
pub const FORCE_THRESHOLD_N: f64 = 1e-6;

/// Steady-window interfacial series of one case (same length each).
#[derive(Debug, Clone, Copy)]
pub struct ContactSeries<'a> {
    /// Contact force `F_c ≥ 0` [N].
    pub contact_force_n: &'a [f64],
    /// Friction magnitude `Q ≥ 0` [N].
    pub friction_n: &'a [f64],
    /// Real contact area `A_r` [m²].
    pub real_area_m2: &'a [f64],
    /// Adhesion force `F_s` [N] (positive = pulling the slider toward the disk), if recorded.
    pub adhesion_n: Option<&'a [f64]>,
}

/// Contact severity of one case (§8). Means of `F_c`, `Q`, `A_r`, `F_s` are over every window
/// sample (zero out of contact), i.e. time averages. The instantaneous ratios `μ = Q/F_c`,
/// `P_m = F_c/A_r`, `τ = Q/A_r` are averaged over the *loaded* samples only (`F_c >` threshold,
/// and `A_r > 0` for `P_m` and `τ`); the ratio-of-means forms divide the time averages. Both are
/// reported, as §8 asks; `None` when no sample is loaded.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactSeverity {
    pub contact_force_n: SeriesStats,
    pub friction_n: SeriesStats,
    pub real_area_m2: SeriesStats,
    pub adhesion_n: Option<SeriesStats>,
    /// Samples with `F_c >` threshold.
    pub loaded_samples: usize,
    /// Instantaneous `μ` over the loaded samples (dimensionless).
    pub friction_coefficient: Option<SeriesStats>,
    /// `mean(Q)/mean(F_c)`.
    pub friction_coefficient_ratio_of_means: Option<f64>,
    /// Instantaneous mean real pressure `P_m = F_c/A_r` [Pa].
    pub mean_pressure_pa: Option<SeriesStats>,
    /// `mean(F_c)/mean(A_r)` [Pa].
    pub mean_pressure_pa_ratio_of_means: Option<f64>,
    /// Instantaneous shear traction `τ = Q/A_r` [Pa].
    pub shear_traction_pa: Option<SeriesStats>,
    /// `mean(Q)/mean(A_r)` [Pa].
    pub shear_traction_pa_ratio_of_means: Option<f64>,
    /// Hertz maximum pressure `P_0 = 1.5·P_m` [Pa] (from the ratio of means).
    pub hertz_max_pressure_pa: Option<f64>,
}

/// Contact severity of one case from its steady-window series (see [`ContactSeverity`]).
pub fn contact_severity(s: &ContactSeries, force_threshold_n: f64) -> Result<ContactSeverity> {
    if !(force_threshold_n.is_finite() && force_threshold_n >= 0.0) {
        return Err(MetricsError::InvalidParameter {
            name: "force_threshold_n",
            value: force_threshold_n,
            reason: "must be finite and >= 0",
        });
    }
    let n = s.contact_force_n.len();
    let fc = series_stats(s.contact_force_n)?;
    for (what, x) in [
        ("friction", s.friction_n),
        ("real area", s.real_area_m2),
        ("adhesion", s.adhesion_n.unwrap_or(s.contact_force_n)),
    ] {
        if x.len() != n {
            return Err(MetricsError::LengthMismatch {
                what,
                expected: n,
                got: x.len(),
            });
        }
    }
    let q = series_stats(s.friction_n)?;
    let ar = series_stats(s.real_area_m2)?;
    let adhesion_n = s.adhesion_n.map(series_stats).transpose()?;
    let (mut mu, mut pm, mut tau) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..n {
        let (f, qk, a) = (s.contact_force_n[k], s.friction_n[k], s.real_area_m2[k]);
        if f > force_threshold_n {
            mu.push(qk / f);
            if a > 0.0 {
                pm.push(f / a);
                tau.push(qk / a);
            }
        }
    }
    let stats_opt = |v: &[f64]| {
        if v.is_empty() {
            Ok(None)
        } else {
            series_stats(v).map(Some)
        }
    };
    let loaded = mu.len();
    let ratio = |num: f64, den: f64| (loaded > 0 && den > 0.0).then(|| num / den);
    let pm_rom = ratio(fc.mean, ar.mean);
    Ok(ContactSeverity {
        contact_force_n: fc,
        friction_n: q,
        real_area_m2: ar,
        adhesion_n,
        loaded_samples: loaded,
        friction_coefficient: stats_opt(&mu)?,
        friction_coefficient_ratio_of_means: ratio(q.mean, fc.mean),
        mean_pressure_pa: stats_opt(&pm)?,
        mean_pressure_pa_ratio_of_means: pm_rom,
        shear_traction_pa: stats_opt(&tau)?,
        shear_traction_pa_ratio_of_means: ratio(q.mean, ar.mean),
        hertz_max_pressure_pa: pm_rom.map(|p| 1.5 * p),
    })
}

// ------------------------------------------------------------------------------------------
// One case
// ------------------------------------------------------------------------------------------

/// Parameters of the per-case metrics.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CaseParams {
    pub window: SteadyWindow,
    /// Nominal FH of eq. 2.1 [m] (11 nm).
    pub fh_nom_m: f64,
    /// Bonded (= mobile) lubricant thickness T0 [m]; total lubricant `t = 2T0`.
    pub t0_m: f64,
    /// Number of extremes averaged by eq. 2.1.
    pub extreme_count: usize,
    /// Force below which `μ`, `P_m`, `τ` are undefined [N].
    pub force_threshold_n: f64,
}

impl CaseParams {
    /// Improved 2-DOF defaults: window 0.5–2 ms, FH_nom = 11 nm, T0 = 0.75 nm, 5 extremes, 1 µN.
    pub fn improved_2dof() -> Self {
        CaseParams {
            window: SteadyWindow::DEFAULT,
            fh_nom_m: 11e-9,
            t0_m: 0.75e-9,
            extreme_count: EXTREME_COUNT,
            force_threshold_n: FORCE_THRESHOLD_N,
        }
    }
}

/// Full-record series of one case, sampled at `t0_s + k·dt_s`.
#[derive(Debug, Clone, Copy)]
pub struct CaseSeries<'a> {
    pub t0_s: f64,
    pub dt_s: f64,
    /// FH series of §8 (bulge POC; 2-DOF `s − T0`, initial model `h`, 3-DOF `s`) [m].
    pub fh_m: &'a [f64],
    /// Clearance `c` of the same point [m] (initial model: `h − nσ`).
    pub clearance_m: &'a [f64],
    /// Interfacial series over the full record, if the case has them.
    pub contact: Option<ContactSeries<'a>>,
}

/// Metrics of one case on its steady window.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaseMetrics {
    /// Sample indices of the steady window.
    pub window: Range<usize>,
    pub fh_m: SeriesStats,
    pub clearance_m: SeriesStats,
    /// HMS of the mean clearance, `c̄ − 2T0` [m].
    pub hms_mean_m: f64,
    /// Eq. 2.1 on the raw samples (faithful).
    pub vibration: Modulation,
    /// Eq. 2.1 on the local extrema (robustness column).
    pub vibration_extrema: Option<Modulation>,
    pub vibration_kind: VibrationKind,
    pub percent_solid_contact: f64,
    pub regime: Regime,
    pub contact: Option<ContactSeverity>,
}

/// All per-case metrics of §8 on the steady window.
pub fn case_metrics(s: &CaseSeries, p: &CaseParams) -> Result<CaseMetrics> {
    check_positive("fh_nom_m", p.fh_nom_m)?;
    check_positive("t0_m", p.t0_m)?;
    let n = s.fh_m.len();
    if s.clearance_m.len() != n {
        return Err(MetricsError::LengthMismatch {
            what: "clearance",
            expected: n,
            got: s.clearance_m.len(),
        });
    }
    let w = p.window.indices(s.t0_s, s.dt_s, n)?;
    let fh = &s.fh_m[w.clone()];
    let c = &s.clearance_m[w.clone()];
    let clearance_m = series_stats(c)?;
    let percent = percent_solid_contact(c)?;
    let contact = match &s.contact {
        Some(cs) => {
            for (what, len) in [
                ("contact force", cs.contact_force_n.len()),
                ("friction", cs.friction_n.len()),
                ("real area", cs.real_area_m2.len()),
                ("adhesion", cs.adhesion_n.map_or(n, <[f64]>::len)),
            ] {
                if len != n {
                    return Err(MetricsError::LengthMismatch {
                        what,
                        expected: n,
                        got: len,
                    });
                }
            }
            let win = ContactSeries {
                contact_force_n: &cs.contact_force_n[w.clone()],
                friction_n: &cs.friction_n[w.clone()],
                real_area_m2: &cs.real_area_m2[w.clone()],
                adhesion_n: cs.adhesion_n.map(|a| &a[w.clone()]),
            };
            Some(contact_severity(&win, p.force_threshold_n)?)
        }
        None => None,
    };
    Ok(CaseMetrics {
        fh_m: series_stats(fh)?,
        hms_mean_m: head_media_spacing(clearance_m.mean, p.t0_m),
        vibration: modulation(fh, p.fh_nom_m, p.extreme_count)?,
        vibration_extrema: modulation_extrema(fh, p.fh_nom_m, p.extreme_count)?,
        vibration_kind: VibrationKind::for_case(percent),
        percent_solid_contact: percent,
        regime: Regime::classify(clearance_m.mean, p.t0_m)?,
        clearance_m,
        contact,
        window: w,
    })
}

// ------------------------------------------------------------------------------------------
// Sweeps
// ------------------------------------------------------------------------------------------

/// Operating regime from the steady mean clearance `c̄` (§1.2).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Regime {
    /// `c̄ > 2T0`.
    Flying,
    /// `T0 < c̄ ≤ 2T0`.
    MobileLubricantContact,
    /// `0 ≤ c̄ ≤ T0`.
    BondedLubricantContact,
    /// `c̄ < 0`.
    SolidContact,
}

impl Regime {
    /// Classify a steady mean clearance (§1.2); the boundaries belong to the contact side
    /// (`c̄ = 2T0` is mobile-lubricant contact, `c̄ = T0` and `c̄ = 0` bonded) as the spec writes.
    pub fn classify(mean_clearance_m: f64, t0_m: f64) -> Result<Regime> {
        check_positive("t0_m", t0_m)?;
        if !mean_clearance_m.is_finite() {
            return Err(MetricsError::NonFinite {
                what: "mean clearance",
                index: 0,
            });
        }
        let c = mean_clearance_m;
        Ok(if c > 2.0 * t0_m {
            Regime::Flying
        } else if c > t0_m {
            Regime::MobileLubricantContact
        } else if c >= 0.0 {
            Regime::BondedLubricantContact
        } else {
            Regime::SolidContact
        })
    }

    /// Mobile or bonded lubricant contact (`0 ≤ c̄ ≤ 2T0`).
    pub fn is_lubricant_contact(self) -> bool {
        matches!(
            self,
            Regime::MobileLubricantContact | Regime::BondedLubricantContact
        )
    }
}

/// One case of an actuation sweep, as the sweep metrics need it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepPoint {
    /// TFC actuation `h_TFC` [m].
    pub actuation_m: f64,
    /// Steady mean clearance `c̄` [m].
    pub mean_clearance_m: f64,
    /// Any steady-window sample with `c < 0` (3-DOF: any feature).
    pub any_solid_contact: bool,
    /// FHM/BV of the case [%].
    pub vibration_percent: f64,
}

impl SweepPoint {
    /// From a case's metrics.
    pub fn from_case(actuation_m: f64, m: &CaseMetrics) -> Self {
        SweepPoint {
            actuation_m,
            mean_clearance_m: m.clearance_m.mean,
            any_solid_contact: m.percent_solid_contact > 0.0,
            vibration_percent: m.vibration.percent,
        }
    }
}

fn check_sweep(points: &[SweepPoint]) -> Result<()> {
    if points.is_empty() {
        return Err(MetricsError::Empty { what: "sweep" });
    }
    for (i, p) in points.iter().enumerate() {
        if !p.actuation_m.is_finite() || (i > 0 && p.actuation_m <= points[i - 1].actuation_m) {
            return Err(MetricsError::NotIncreasing { index: i });
        }
        if !p.mean_clearance_m.is_finite() || !p.vibration_percent.is_finite() {
            return Err(MetricsError::NonFinite {
                what: "sweep point",
                index: i,
            });
        }
    }
    Ok(())
}

/// Touchdown (§8): index of the smallest actuation whose steady window contains any sample in
/// solid contact; `None` if no case contacts. Points must be sorted by strictly increasing
/// actuation.
pub fn touchdown(points: &[SweepPoint]) -> Result<Option<usize>> {
    check_sweep(points)?;
    Ok(points.iter().position(|p| p.any_solid_contact))
}

/// Least-squares line `c = slope·h + intercept_m` through a set of sweep points.
#[derive(Debug, Clone, PartialEq)]
pub struct LineFit {
    /// dc̄/dh_TFC (m/m = nm/nm).
    pub slope: f64,
    pub intercept_m: f64,
    /// Sweep indices used (increasing).
    pub indices: Vec<usize>,
    /// RMS residual [m].
    pub rms_residual_m: f64,
}

impl LineFit {
    /// Ordinary least squares (centred, so the 1e-9 m scale keeps its digits); `None` with
    /// fewer than two points.
    pub fn fit(points: &[SweepPoint], indices: Vec<usize>) -> Option<LineFit> {
        if indices.len() < 2 {
            return None;
        }
        let n = indices.len() as f64;
        let hm = indices.iter().map(|&i| points[i].actuation_m).sum::<f64>() / n;
        let cm = indices
            .iter()
            .map(|&i| points[i].mean_clearance_m)
            .sum::<f64>()
            / n;
        let (mut sxx, mut sxy) = (0.0, 0.0);
        for &i in &indices {
            let dx = points[i].actuation_m - hm;
            sxx += dx * dx;
            sxy += dx * (points[i].mean_clearance_m - cm);
        }
        let slope = sxy / sxx;
        let intercept_m = cm - slope * hm;
        let ss = indices
            .iter()
            .map(|&i| {
                (points[i].mean_clearance_m - slope * points[i].actuation_m - intercept_m).powi(2)
            })
            .sum::<f64>();
        Some(LineFit {
            slope,
            intercept_m,
            rms_residual_m: (ss / n).sqrt(),
            indices,
        })
    }

    /// Clearance of the line at actuation `h` [m].
    pub fn at(&self, actuation_m: f64) -> f64 {
        self.slope * actuation_m + self.intercept_m
    }
}

/// Critical point: intersection of lines A and B.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CriticalPoint {
    /// `h_TFC,cr` [m].
    pub actuation_m: f64,
    /// `c_cr` [m].
    pub clearance_m: f64,
}

/// Parameters of the slope analysis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlopeParams {
    /// T0 [m] (regime boundaries).
    pub t0_m: f64,
    /// A point is "on the A-line" within this distance [m] (§8: 0.05 nm).
    pub on_line_tol_m: f64,
    /// Points that seed the A-line before it is extended (≥ 2).
    pub min_a_points: usize,
    /// The A-line starts at the first flying point at or above this actuation [m] (2 nm):
    /// below ~1 nm the bulge is flatter than the pitch tilts the ABS, its lowest point sits on
    /// the TE-side rim, and c̄(h) bends away from the approach line for geometric reasons. If
    /// fewer than two flying points lie above it, A starts at the lowest actuation.
    pub a_start_m: f64,
}

impl SlopeParams {
    pub fn new(t0_m: f64) -> Self {
        SlopeParams {
            t0_m,
            on_line_tol_m: 0.05e-9,
            min_a_points: 3,
            a_start_m: 2e-9,
        }
    }
}

/// Slopes A–D, the critical point and the segment boundaries used (§8).
#[derive(Debug, Clone, PartialEq)]
pub struct SlopeAnalysis {
    /// A: approach (flying, before adhesion matters).
    pub a: Option<LineFit>,
    /// B: jump to contact.
    pub b: Option<LineFit>,
    /// C: lubricant contact (`0 ≤ c̄ ≤ 2T0`).
    pub c: Option<LineFit>,
    /// D: solid contact (`c̄ < 0`).
    pub d: Option<LineFit>,
    /// Intersection of A and B.
    pub critical_point: Option<CriticalPoint>,
    /// Last flying point on the A-line within the tolerance (start of B).
    pub last_on_a_index: Option<usize>,
    /// First point after it that is not flying (end of B).
    pub first_contact_index: Option<usize>,
}

/// Slopes A–D and the critical point of the curve `c̄(h_TFC)` (§8). Points sorted by strictly
/// increasing actuation. Operational choices (the spec fixes the criteria, not the algorithm):
///
/// * **A**: start from the initial run of flying points (from the lowest actuation up to the
///   first non-flying point); seed the line with its first `min_a_points` points, then extend
///   one point at a time while the next point lies within `on_line_tol_m` of the line fitted to
///   the points so far (adhesion pulls the points below the line as the critical point nears,
///   which ends the segment); A is the least-squares line of the final set.
/// * **B**: from the last flying point lying on the final A-line within `on_line_tol_m` to the
///   first following point that is not flying (the first point inside the lubricant regime; if
///   the curve jumps straight to solid contact, that point), both included; least squares
///   (the secant when there are two).
/// * **C**: all points with `0 ≤ c̄ ≤ 2T0`; **D**: all points with `c̄ < 0`. Each slope needs two
///   points, otherwise `None`.
/// * **CP**: intersection of A and B; `None` if either is missing or they are parallel.
pub fn slopes(points: &[SweepPoint], p: &SlopeParams) -> Result<SlopeAnalysis> {
    check_sweep(points)?;
    check_positive("t0_m", p.t0_m)?;
    if !(p.on_line_tol_m.is_finite() && p.on_line_tol_m >= 0.0) {
        return Err(MetricsError::InvalidParameter {
            name: "on_line_tol_m",
            value: p.on_line_tol_m,
            reason: "must be finite and >= 0",
        });
    }
    let regimes = points
        .iter()
        .map(|q| Regime::classify(q.mean_clearance_m, p.t0_m))
        .collect::<Result<Vec<_>>>()?;
    let run = regimes
        .iter()
        .position(|&r| r != Regime::Flying)
        .unwrap_or(points.len());

    // A.
    let mut a = None;
    let start = points[..run]
        .iter()
        .position(|q| q.actuation_m >= p.a_start_m)
        .filter(|&i| run - i >= 2)
        .unwrap_or(0);
    if run - start >= 2 {
        let seed = start + p.min_a_points.max(2).min(run - start);
        let Some(mut fit) = LineFit::fit(points, (start..seed).collect()) else {
            return Err(MetricsError::NonFinite {
                what: "approach line",
                index: start,
            });
        };
        for j in seed..run {
            let q = &points[j];
            if (q.mean_clearance_m - fit.at(q.actuation_m)).abs() > p.on_line_tol_m {
                break;
            }
            let mut idx = fit.indices.clone();
            idx.push(j);
            match LineFit::fit(points, idx) {
                Some(f) => fit = f,
                None => break,
            }
        }
        a = Some(fit);
    }

    // B.
    let first_contact = (run < points.len()).then_some(run);
    let last_on_a = a.as_ref().and_then(|fa| {
        (start..run).rev().find(|&i| {
            (points[i].mean_clearance_m - fa.at(points[i].actuation_m)).abs() <= p.on_line_tol_m
        })
    });
    let b = match (last_on_a, first_contact) {
        (Some(i0), Some(i1)) => LineFit::fit(points, (i0..=i1).collect()),
        _ => None,
    };
    let critical_point = match (&a, &b) {
        (Some(fa), Some(fb)) if fa.slope != fb.slope => {
            let h = (fb.intercept_m - fa.intercept_m) / (fa.slope - fb.slope);
            Some(CriticalPoint {
                actuation_m: h,
                clearance_m: fa.at(h),
            })
        }
        _ => None,
    };

    let c_idx = (0..points.len())
        .filter(|&i| regimes[i].is_lubricant_contact())
        .collect();
    let d_idx = (0..points.len())
        .filter(|&i| regimes[i] == Regime::SolidContact)
        .collect();
    Ok(SlopeAnalysis {
        a,
        b,
        c: LineFit::fit(points, c_idx),
        d: LineFit::fit(points, d_idx),
        critical_point,
        last_on_a_index: last_on_a,
        first_contact_index: first_contact,
    })
}

/// Optimum operating point of a sweep [choice: §8 does not define it; the published optima —
/// 9 nm with FHM 9 % before the 9.8 nm touchdown (initial model), 9.3 nm with 9.19 % inside the
/// ≈ 10 % band between CP (8.6) and TD (9.9) (optimised design) — are the cases of least
/// vibration between the critical point and touchdown]: among cases with actuation strictly
/// above the critical point's (all cases if there is no CP) and strictly below touchdown (all
/// remaining cases if there is no TD) that have no solid contact, the one with the smallest
/// FHM; ties (within 1e-9 %) go to the larger actuation (smaller spacing, which is what TFC is
/// for). `None` when no case qualifies.
pub fn optimum_operating_point(
    points: &[SweepPoint],
    critical_point: Option<&CriticalPoint>,
    touchdown_index: Option<usize>,
) -> Result<Option<usize>> {
    check_sweep(points)?;
    let end = touchdown_index.unwrap_or(points.len()).min(points.len());
    let mut best: Option<usize> = None;
    for i in 0..end {
        let q = &points[i];
        if q.any_solid_contact || critical_point.is_some_and(|cp| q.actuation_m <= cp.actuation_m) {
            continue;
        }
        best = match best {
            Some(b) if points[b].vibration_percent < q.vibration_percent - 1e-9 => Some(b),
            _ => Some(i),
        };
    }
    Ok(best)
}

/// Sweep-level metrics.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepMetrics {
    pub regimes: Vec<Regime>,
    pub touchdown_index: Option<usize>,
    /// Touchdown actuation [m].
    pub touchdown_actuation_m: Option<f64>,
    pub slopes: SlopeAnalysis,
    pub optimum_index: Option<usize>,
    /// `ξ` of every case (§9).
    pub flyability: Vec<f64>,
}

/// Regimes, touchdown, slopes/CP and optimum of a sweep (points sorted by actuation).
pub fn sweep_metrics(
    points: &[SweepPoint],
    p: &SlopeParams,
    fh_nom_m: f64,
) -> Result<SweepMetrics> {
    check_positive("fh_nom_m", fh_nom_m)?;
    let slopes = slopes(points, p)?;
    let td = touchdown(points)?;
    let optimum_index = optimum_operating_point(points, slopes.critical_point.as_ref(), td)?;
    Ok(SweepMetrics {
        regimes: points
            .iter()
            .map(|q| Regime::classify(q.mean_clearance_m, p.t0_m))
            .collect::<Result<_>>()?,
        touchdown_index: td,
        touchdown_actuation_m: td.map(|i| points[i].actuation_m),
        slopes,
        optimum_index,
        flyability: points
            .iter()
            .map(|q| flyability(q.mean_clearance_m, fh_nom_m, q.vibration_percent))
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const NM: f64 = 1e-9;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1e-300)
    }

    #[test]
    fn window_selection() {
        // 2 ms at 0.25 µs: 8001 samples; 0.5–2 ms → indices 2000..=8000.
        let w = SteadyWindow::DEFAULT.indices(0.0, 0.25e-6, 8001).unwrap();
        assert_eq!(w, 2000..8001);
        // Record shorter than the window end: clipped.
        assert_eq!(
            SteadyWindow::DEFAULT.indices(0.0, 0.25e-6, 5000).unwrap(),
            2000..5000
        );
        // Off-grid ends: inclusive of the grid points inside.
        let w = SteadyWindow {
            start_s: 0.3,
            end_s: 0.7,
        }
        .indices(0.05, 0.1, 100)
        .unwrap();
        assert_eq!(w, 3..7); // t = 0.35 .. 0.65
        assert!(SteadyWindow::DEFAULT.indices(0.0, 0.25e-6, 1000).is_err());
        assert!(SteadyWindow::DEFAULT.indices(0.0, 0.0, 1000).is_err());
        let x: Vec<f64> = (0..10).map(|k| k as f64).collect();
        let s = SteadyWindow {
            start_s: 2.0,
            end_s: 4.0,
        }
        .slice(&x, 0.0, 1.0)
        .unwrap();
        assert_eq!(s, &[2.0, 3.0, 4.0]);
    }

    /// `FH = 11 nm + 1 nm·sin(2πk/40)` sampled 40 times per period.
    fn sinusoid(periods: usize) -> Vec<f64> {
        (0..40 * periods)
            .map(|k| 11.0 * NM + 1.0 * NM * (2.0 * PI * k as f64 / 40.0).sin())
            .collect()
    }

    #[test]
    fn stats_and_modulation_of_a_sinusoid() {
        let fh = sinusoid(10);
        let st = series_stats(&fh).unwrap();
        assert!(close(st.mean, 11.0 * NM, 1e-12));
        // Population std of a sinusoid over whole periods: A/√2.
        assert!(close(st.std, NM / 2f64.sqrt(), 1e-10), "{}", st.std);
        // 10 periods: 10 samples exactly at each peak → FHM = 100·2A/FH_nom = 18.18… %.
        let m = modulation(&fh, 11.0 * NM, 5).unwrap();
        assert!(close(m.percent, 200.0 / 11.0, 1e-10), "{}", m.percent);
        assert!(close(m.fh_max_m, 12.0 * NM, 1e-12));
        let e = modulation_extrema(&fh, 11.0 * NM, 5).unwrap().unwrap();
        assert!(close(e.percent, 200.0 / 11.0, 1e-10));
        assert_eq!((e.count_max, e.count_min), (5, 5));
        // One period: the five largest samples are k = 8..12, sin 72°, 81°, 90°, 81°, 72°.
        let one = sinusoid(1);
        let m = modulation(&one, 11.0 * NM, 5).unwrap();
        let top = (1.0 + 2.0 * (0.45 * PI).sin() + 2.0 * (0.4 * PI).sin()) / 5.0; // 0.975498
        assert!(close(top, 0.975_498, 1e-6));
        assert!(
            close(m.percent, 100.0 * 2.0 * top / 11.0, 1e-10),
            "{}",
            m.percent
        );
        // …whereas the extrema variant sees one maximum and one minimum: the full 2A.
        let e = modulation_extrema(&one, 11.0 * NM, 5).unwrap().unwrap();
        assert_eq!((e.count_max, e.count_min), (1, 1));
        assert!(close(e.percent, 200.0 / 11.0, 1e-10));
        // Monotone: no extrema; too short for the raw form.
        let ramp: Vec<f64> = (0..10).map(|k| k as f64 * NM).collect();
        assert_eq!(modulation_extrema(&ramp, 11.0 * NM, 5).unwrap(), None);
        assert!(modulation(&ramp[..4], 11.0 * NM, 5).is_err());
        assert!(modulation(&[f64::NAN; 6], 11.0 * NM, 5).is_err());
    }

    #[test]
    fn extrema_count_plateaus_once() {
        let (mx, mn) = local_extrema(&[0.0, 1.0, 1.0, 0.0, -1.0, -1.0, -1.0, 2.0, 2.0]);
        assert_eq!(mx, vec![1.0]);
        assert_eq!(mn, vec![-1.0]);
    }

    #[test]
    fn solid_contact_percent_and_spacings() {
        let c = [1.0, -0.5, 0.0, -1e-12, 2.0].map(|v| v * NM);
        assert!(close(percent_solid_contact(&c).unwrap(), 40.0, 1e-15));
        let f1 = [1.0, -1.0, 1.0, 1.0];
        let f2 = [1.0, 1.0, -1.0, -1.0];
        assert!(close(
            percent_solid_contact_any(&[&f1, &f2]).unwrap(),
            75.0,
            1e-15
        ));
        assert!(percent_solid_contact_any(&[&f1, &f2[..3]]).is_err());
        // §1.2 / C3: c = 2.54 nm, T0 = 0.75 → HMS 1.04 nm; magnetic spacing 1 + 1.5 + 2 + 1.5 = 6.
        assert!(close(
            head_media_spacing(2.54 * NM, 0.75 * NM),
            1.04 * NM,
            1e-12
        ));
        assert!(close(
            magnetic_spacing(1.0 * NM, 1.5 * NM, 2.0 * NM, 0.5 * NM),
            6.0 * NM,
            1e-12
        ));
        assert!(close(
            clearance_from_fh(11.0 * NM, 0.75 * NM, 0.5 * NM),
            10.25 * NM,
            1e-12
        ));
        assert!(close(plasticity_index(4.0, 2.0, 1.0, 16.0), 0.5, 1e-15));
        assert!(close(flyability(1.1 * NM, 11.0 * NM, 10.0), 0.01, 1e-12));
    }

    #[test]
    fn contact_severity_hand_numbers() {
        // Four samples: out of contact, two loaded, one below the 1 µN threshold.
        let fc = [0.0, 1e-3, 3e-3, 0.5e-6];
        let q = [0.0, 1.5e-3, 3e-3, 1e-6];
        let ar = [0.0, 0.5e-12, 1e-12, 1e-15];
        let fs = [1e-3, 1e-3, 2e-3, 0.0];
        let s = ContactSeries {
            contact_force_n: &fc,
            friction_n: &q,
            real_area_m2: &ar,
            adhesion_n: Some(&fs),
        };
        let r = contact_severity(&s, FORCE_THRESHOLD_N).unwrap();
        assert_eq!(r.loaded_samples, 2);
        assert!(close(r.contact_force_n.mean, 4.0005e-3 / 4.0, 1e-12));
        // μ: instantaneous 1.5 and 1.0 → mean 1.25, std 0.25; ratio of means 4.501e-3/4.0005e-3.
        let mu = r.friction_coefficient.unwrap();
        assert!(close(mu.mean, 1.25, 1e-12) && close(mu.std, 0.25, 1e-12));
        assert!(close(
            r.friction_coefficient_ratio_of_means.unwrap(),
            4.501e-3 / 4.0005e-3,
            1e-12
        ));
        // P_m: 2 GPa and 3 GPa → 2.5 GPa; τ: 3 and 3 GPa.
        assert!(close(r.mean_pressure_pa.unwrap().mean, 2.5e9, 1e-12));
        assert!(close(r.shear_traction_pa.unwrap().mean, 3.0e9, 1e-12));
        let pm = 4.0005e-3 / 1.501e-12;
        assert!(close(r.mean_pressure_pa_ratio_of_means.unwrap(), pm, 1e-12));
        assert!(close(r.hertz_max_pressure_pa.unwrap(), 1.5 * pm, 1e-12));
        assert!(close(r.adhesion_n.unwrap().mean, 1e-3, 1e-12));
        // C4 of the spec: 1.63 mN on 0.3647 µm² = 4.47 GPa, μ = 2.43/1.63 = 1.49.
        let s = ContactSeries {
            contact_force_n: &[1.63e-3; 3],
            friction_n: &[2.43e-3; 3],
            real_area_m2: &[0.3647e-12; 3],
            adhesion_n: None,
        };
        let r = contact_severity(&s, FORCE_THRESHOLD_N).unwrap();
        assert!((r.mean_pressure_pa_ratio_of_means.unwrap() / 1e9 - 4.47).abs() < 0.005);
        assert!((r.friction_coefficient.unwrap().mean - 1.49).abs() < 0.005);
        // Never loaded: ratios undefined.
        let z = [0.0; 3];
        let s = ContactSeries {
            contact_force_n: &z,
            friction_n: &z,
            real_area_m2: &z,
            adhesion_n: None,
        };
        let r = contact_severity(&s, FORCE_THRESHOLD_N).unwrap();
        assert_eq!(r.friction_coefficient, None);
        assert_eq!(r.mean_pressure_pa_ratio_of_means, None);
        let s = ContactSeries {
            contact_force_n: &z,
            friction_n: &z[..2],
            real_area_m2: &z,
            adhesion_n: None,
        };
        assert!(contact_severity(&s, FORCE_THRESHOLD_N).is_err());
    }

    #[test]
    fn regime_boundaries() {
        let t0 = 0.75 * NM;
        let r = |c: f64| Regime::classify(c, t0).unwrap();
        assert_eq!(r(1.6 * NM), Regime::Flying);
        assert_eq!(r(1.5 * NM), Regime::MobileLubricantContact);
        assert_eq!(r(0.76 * NM), Regime::MobileLubricantContact);
        assert_eq!(r(0.75 * NM), Regime::BondedLubricantContact);
        assert_eq!(r(0.0), Regime::BondedLubricantContact);
        assert_eq!(r(-1e-12), Regime::SolidContact);
        assert!(Regime::classify(f64::NAN, t0).is_err());
    }

    #[test]
    fn case_metrics_on_a_synthetic_record() {
        // 2 ms at 0.25 µs; FH = 11 + sin(2π·100 kHz·t) nm (40 samples per period), T0 = 0.75,
        // σ = 0.5 → c = FH − 0.75 nm, never negative.
        let dt = 0.25e-6;
        let n = 8001;
        let fh: Vec<f64> = (0..n)
            .map(|k| 11.0 * NM + NM * (2.0 * PI * 100e3 * k as f64 * dt).sin())
            .collect();
        let c: Vec<f64> = fh
            .iter()
            .map(|&f| clearance_from_fh(f, 0.75 * NM, 0.5 * NM))
            .collect();
        let s = CaseSeries {
            t0_s: 0.0,
            dt_s: dt,
            fh_m: &fh,
            clearance_m: &c,
            contact: None,
        };
        let m = case_metrics(&s, &CaseParams::improved_2dof()).unwrap();
        assert_eq!(m.window, 2000..8001);
        assert!(close(m.clearance_m.mean, 10.25 * NM, 1e-6));
        assert!(close(m.vibration.percent, 200.0 / 11.0, 1e-9));
        assert_eq!(m.vibration_kind, VibrationKind::Fhm);
        assert_eq!(m.regime, Regime::Flying);
        assert_eq!(m.percent_solid_contact, 0.0);
        assert!(close(m.hms_mean_m, 8.75 * NM, 1e-6));
        // Shift the clearance down by 10 nm: the troughs go solid.
        let c2: Vec<f64> = c.iter().map(|v| v - 10.0 * NM).collect();
        let s2 = CaseSeries {
            clearance_m: &c2,
            ..s
        };
        let m2 = case_metrics(&s2, &CaseParams::improved_2dof()).unwrap();
        assert_eq!(m2.vibration_kind, VibrationKind::Bv);
        assert_eq!(m2.regime, Regime::BondedLubricantContact);
        // c < 0 where sin(9°·k) < −0.25, i.e. 194.5° < 9°·k < 345.5°: k = 22..=38, 17 of every
        // 40 samples; the window holds 150 whole periods plus one k ≡ 0 sample (not in contact).
        let expected = 100.0 * (150.0 * 17.0) / 6001.0;
        assert!(
            close(m2.percent_solid_contact, expected, 1e-12),
            "{}",
            m2.percent_solid_contact
        );
    }

    /// Piecewise-linear `c̄(h)` on a 0.1 nm grid, T0 = 0.75 nm:
    /// A: c = 11.05 − h up to 8.6 nm; B: slope −5 to 8.8 nm (1.45 nm, lubricant);
    /// C: slope −1 down to 0.05 nm at 10.2 nm; D: c = −0.01 − 0.2(h − 10.3) from 10.3 nm.
    fn synthetic_sweep() -> Vec<SweepPoint> {
        (50..=130)
            .map(|k| {
                let h = k as f64 / 10.0;
                let c = if k <= 86 {
                    11.05 - h
                } else if k <= 88 {
                    2.45 - 5.0 * (h - 8.6)
                } else if k <= 102 {
                    1.45 - (h - 8.8)
                } else {
                    -0.01 - 0.2 * (h - 10.3)
                };
                // Vibration: 8 % flying, 14 % spike at CP, dip to 9.2 % at 9.3 nm, then rising.
                let v = match k {
                    ..=85 => 8.0,
                    86 => 14.0,
                    87..=93 => 9.2 + 0.1 * (93 - k) as f64,
                    _ => 9.2 + 0.5 * (k - 93) as f64,
                };
                SweepPoint {
                    actuation_m: h * NM,
                    mean_clearance_m: c * NM,
                    any_solid_contact: c < 0.3, // fluctuations reach c < 0 from c̄ = 0.25 nm
                    vibration_percent: v,
                }
            })
            .collect()
    }

    #[test]
    fn sweep_touchdown_slopes_and_optimum() {
        let pts = synthetic_sweep();
        let idx = |h: f64| ((h - 5.0) * 10.0).round() as usize;
        let m = sweep_metrics(&pts, &SlopeParams::new(0.75 * NM), 11.0 * NM).unwrap();
        // TD: first c̄ < 0.3 nm is 1.45 − (h − 8.8) < 0.3 → h = 10.0 nm (c̄ = 0.25).
        assert_eq!(m.touchdown_index, Some(idx(10.0)));
        assert!(close(m.touchdown_actuation_m.unwrap(), 10.0 * NM, 1e-12));
        let s = &m.slopes;
        let a = s.a.as_ref().unwrap();
        assert!(close(a.slope, -1.0, 1e-9), "A = {}", a.slope);
        assert!(close(a.intercept_m, 11.05 * NM, 1e-9));
        assert_eq!(a.indices, (0..=idx(8.6)).collect::<Vec<_>>());
        assert_eq!(s.last_on_a_index, Some(idx(8.6)));
        assert_eq!(s.first_contact_index, Some(idx(8.8)));
        let b = s.b.as_ref().unwrap();
        assert!(close(b.slope, -5.0, 1e-9), "B = {}", b.slope);
        let cp = s.critical_point.unwrap();
        assert!(close(cp.actuation_m, 8.6 * NM, 1e-9), "{}", cp.actuation_m);
        assert!(close(cp.clearance_m, 2.45 * NM, 1e-9));
        let c = s.c.as_ref().unwrap();
        assert!(close(c.slope, -1.0, 1e-9));
        assert_eq!(c.indices, (idx(8.8)..=idx(10.2)).collect::<Vec<_>>());
        let d = s.d.as_ref().unwrap();
        assert!(close(d.slope, -0.2, 1e-9), "D = {}", d.slope);
        assert_eq!(d.indices.len(), idx(13.0) - idx(10.3) + 1);
        // Regimes: flying to 8.7 (1.95 nm), mobile 8.8 … 9.5 (0.75 → bonded at 9.5), solid 10.3.
        assert_eq!(m.regimes[idx(8.7)], Regime::Flying);
        assert_eq!(m.regimes[idx(8.8)], Regime::MobileLubricantContact);
        assert_eq!(m.regimes[idx(9.6)], Regime::BondedLubricantContact);
        assert_eq!(m.regimes[idx(10.3)], Regime::SolidContact);
        // Optimum: least vibration strictly between CP (8.6) and TD (10.0): 9.3 nm.
        assert_eq!(m.optimum_index, Some(idx(9.3)));
        assert!(close(m.flyability[0], (6.05 / 11.0) * 0.08, 1e-9));
        // Ties go to the larger actuation.
        let mut flat = pts.clone();
        for q in &mut flat {
            q.vibration_percent = 5.0;
        }
        let o = optimum_operating_point(&flat, Some(&cp), m.touchdown_index).unwrap();
        assert_eq!(o, Some(idx(9.9)));
    }

    #[test]
    fn approach_line_skips_the_small_actuation_bend() {
        // A sweep from 0 nm whose first points bend away from the approach line (below ~1 nm
        // the bulge's rim is the lowest point): A still has slope −1 and the same CP.
        let mut pts: Vec<SweepPoint> = (0..50)
            .map(|k| {
                let h = k as f64 / 10.0;
                let c = 11.05 - h - 0.3 * (-h / 0.3).exp();
                SweepPoint {
                    actuation_m: h * NM,
                    mean_clearance_m: c * NM,
                    any_solid_contact: false,
                    vibration_percent: 8.0,
                }
            })
            .collect();
        pts.extend(synthetic_sweep());
        let s = slopes(&pts, &SlopeParams::new(0.75 * NM)).unwrap();
        let a = s.a.as_ref().unwrap();
        assert!(close(a.slope, -1.0, 1e-4), "A = {}", a.slope);
        assert!(pts[a.indices[0]].actuation_m >= 2.0 * NM);
        let cp = s.critical_point.unwrap();
        assert!(close(cp.actuation_m, 8.6 * NM, 1e-3), "{}", cp.actuation_m);
    }

    #[test]
    fn sweep_input_errors_and_degenerate_curves() {
        let mut pts = synthetic_sweep();
        pts.swap(3, 4);
        assert_eq!(
            touchdown(&pts),
            Err(MetricsError::NotIncreasing { index: 4 })
        );
        assert!(touchdown(&[]).is_err());
        // All flying: no B, no CP, no TD; the optimum is then the least-vibration case overall.
        let flying: Vec<SweepPoint> = synthetic_sweep().into_iter().take(30).collect();
        let s = slopes(&flying, &SlopeParams::new(0.75 * NM)).unwrap();
        assert!(s.a.is_some() && s.b.is_none() && s.critical_point.is_none());
        assert!(s.c.is_none() && s.d.is_none());
        assert_eq!(touchdown(&flying).unwrap(), None);
    }
}
