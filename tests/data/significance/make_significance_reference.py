#!/usr/bin/env python3
"""Independent reference values for hdi's significance tests (issue 34).

Writes `reference.json` and the AR(1) input `ar1_alpha072_n4096.npy` beside this script. Every
number comes from scipy/numpy/statsmodels/pycwt or from the published formulas evaluated here
in numpy -- never from hdi. Formulas: Torrence & Compo (1998), "A practical guide to wavelet
analysis", BAMS 79, 61-78 ("T&C"); Grinsted, Moore & Jevrejeva (2004), Nonlin. Processes
Geophys. 11, 561-566; Torrence & Webster (1999), J. Climate 12, 2679-2690.

Run once (versions pinned in requirements.txt):
    python3 -m venv /tmp/sigenv && /tmp/sigenv/bin/pip install -r requirements.txt
    nice /tmp/sigenv/bin/python make_significance_reference.py
The pycwt coherence timings (block `pycwt_notes`) run one at a time in child processes, each
capped at 600 s (about 8 minutes in all here);
`--skip-wct-timing` leaves it out (the JSON then says so).
"""

import hashlib
import json
import os
import platform
import subprocess
import sys
import time

import numpy as np
import scipy
import scipy.signal
import scipy.stats

import pycwt
from pycwt.mothers import Morlet

try:
    import statsmodels
    from statsmodels.tsa.stattools import acf as sm_acf
except ImportError:  # optional, as the brief allows
    statsmodels = None

HERE = os.path.dirname(os.path.abspath(__file__))
SEED = 3404  # numpy default_rng seed of the committed AR(1) series
MC_SEED = 3405  # seed of the FFT-level Monte Carlo
WCT_SEED = 3406  # numpy legacy seed (pycwt.rednoise uses numpy.random.randn)
SA_MC_SEED = 3407  # seed of the scale-averaged power Monte Carlo

OMEGA0 = 6.0
# T&C Table 1: Fourier wavelength of the Morlet at scale s is lambda = FLAMBDA * s.
FLAMBDA = 4.0 * np.pi / (OMEGA0 + np.sqrt(2.0 + OMEGA0**2))
# T&C Table 2 (Morlet, omega0 = 6).
C_DELTA, GAMMA, DJ0, DOFMIN = 0.776, 2.32, 0.60, 2.0

ALPHA_TRUE = 0.72
N = 4096
FS = 1.0e6
DT = 1.0 / FS
P95 = 0.95


def f64(a):
    """JSON-ready float list (repr round-trips float64 exactly)."""
    return [float(v) for v in np.atleast_1d(a)]


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))


def lag1_biased(x):
    """hdi's estimator: biased sample ACF at lag 1 (= statsmodels acf(x)[1])."""
    d = x - x.mean()
    return float(np.dot(d[:-1], d[1:]) / np.dot(d, d))


def ar1_spectrum(f, alpha, dt):
    """T&C eq. 16 with k/N = f*dt: normalised (unit-variance) AR(1) Fourier spectrum."""
    return (1 - alpha**2) / (1 + alpha**2 - 2 * alpha * np.cos(2 * np.pi * f * dt))


def chi2_ppf(p, nu):
    return float(scipy.stats.chi2.ppf(p, nu))


def make_series():
    """AR(1), alpha = 0.72, unit innovations, started from the stationary distribution."""
    rng = np.random.default_rng(SEED)
    e = rng.standard_normal(N)
    x = np.empty(N)
    x[0] = e[0] / np.sqrt(1 - ALPHA_TRUE**2)
    for n in range(1, N):
        x[n] = ALPHA_TRUE * x[n - 1] + e[n]
    return x


def block_chi2():
    ps = [0.5, 0.9, 0.95, 0.99]
    nus = [1, 2, 2.7, 5.3, 10, 33.3, 100, 1000, 12345.6]
    table = [[chi2_ppf(p, nu) for nu in nus] for p in ps]
    return {
        "what": "chi-square quantiles chi2_nu(p): table[i][j] = scipy.stats.chi2.ppf(p[i], nu[j])",
        "library": f"scipy {scipy.__version__}",
        "p": ps,
        "nu": nus,
        "table": table,
    }


def block_series(x, fname):
    r1 = lag1_biased(x)
    g, a, mu2 = pycwt.ar1(x)
    d = x - x.mean()
    # The "unbiased-covariance" ratio c1/(N-1) over c0/N that pycwt.ar1 starts from.
    c_ratio = float((np.dot(d[:-1], d[1:]) / (N - 1)) / (np.dot(d, d) / N))
    out = {
        "what": "committed AR(1) series x_n = alpha x_{n-1} + e_n, e ~ N(0,1) (unit innovations), "
        "x_0 = e_0/sqrt(1-alpha^2) (stationary start); float64 little-endian .npy",
        "file": fname,
        "generator": f"numpy.random.default_rng({SEED}).standard_normal({N}) then the recursion",
        "alpha_true": ALPHA_TRUE,
        "n": N,
        "process_variance_true": 1 / (1 - ALPHA_TRUE**2),
        "mean": float(x.mean()),
        "variance_ddof0": float(x.var()),
        "r1_biased_acf": r1,
        "r1_formula": "sum_{n=0}^{N-2}(x_n-xbar)(x_{n+1}-xbar) / sum_{n=0}^{N-1}(x_n-xbar)^2 (numpy)",
        "c1_over_c0_unbiased_lag_cov": c_ratio,
        "c1_over_c0_formula": "[sum (x_n-xbar)(x_{n+1}-xbar)/(N-1)] / [sum (x_n-xbar)^2/N]; "
        "= r1*N/(N-1), the ratio pycwt.ar1 starts from",
        "pycwt_ar1": {
            "g": float(g),
            "a": float(a),
            "mu2": float(mu2),
            "call": "pycwt.ar1(x) -> (g, a, mu2)",
            "estimator": "Allen & Smith (1996) bias correction: solves the quadratic that makes the "
            "expected sample lag-1 covariance ratio (with the mean-removal bias mu2 of a finite "
            "AR(1) segment) equal the observed c1/c0, c1 = sum/(N-1), c0 = sum/N; g is larger "
            "than the biased r1 (here by g - r1 shown below)",
            "g_minus_r1": float(g) - r1,
        },
    }
    if statsmodels is not None:
        out["statsmodels_acf_lag1"] = float(sm_acf(x, nlags=1, fft=False)[1])
        out["statsmodels_version"] = statsmodels.__version__
        out["statsmodels_minus_r1"] = out["statsmodels_acf_lag1"] - r1
    return out


def grid():
    j = np.arange(60)
    f = 2.0e3 * (200.0e3 / 2.0e3) ** (j / 59)
    s = OMEGA0 / (2 * np.pi * f)  # hdi's scale: the scale tuned to f = omega0/(2 pi s)
    dj = np.log2(200.0e3 / 2.0e3) / 59  # octaves per grid step (scales descend with j)
    return f, s, dj


def direct_levels(s, alpha, n_a_list):
    f_fourier = 1.0 / (FLAMBDA * s)
    p = ar1_spectrum(f_fourier, alpha, DT)
    out = {
        "fourier_frequency_hz": f64(f_fourier),
        "P": f64(p),
        "local_level_factor": f64(p * chi2_ppf(P95, 2) / 2),
    }
    for n_a in n_a_list:
        nu = DOFMIN * np.sqrt(1 + (n_a * DT / (GAMMA * s)) ** 2)  # T&C eq. 23
        fac = np.array([chi2_ppf(P95, v) / v for v in nu])
        out[f"global_n_a_{n_a}"] = {"nu": f64(nu), "level_factor": f64(p * fac)}
    return out


def block_levels(x, r1):
    f, s, dj = grid()
    n_a_list = [N, 1000]
    d = direct_levels(s, r1, n_a_list)
    mor = Morlet(6)
    # pycwt with a SCALAR variance 1.0: its pk(freq, alpha, n0) uses n0 = 1, i.e. eq. 16 proper.
    sig0, theor0 = pycwt.significance(1.0, DT, s, 0, alpha=r1, significance_level=P95, wavelet=mor)
    compare = {
        "flambda_pycwt": float(mor.flambda()),
        "flambda_formula": float(FLAMBDA),
        "flambda_rel_diff": rel(mor.flambda(), FLAMBDA),
        "sigtest0_P_max_rel_diff": rel(theor0, d["P"]),
        "sigtest0_level_max_rel_diff": rel(sig0, d["local_level_factor"]),
    }
    pycwt_vals = {"sigtest0_level": f64(sig0), "sigtest0_fft_theor": f64(theor0)}
    for n_a in n_a_list:
        # pycwt needs dof as a float array of len(scales): a scalar fails at len(dof) and a
        # length-1 array at numpy.zeros(1, J + 1) (dtype argument).
        dof = np.full(len(s), float(n_a))
        sig1, theor1 = pycwt.significance(
            1.0, DT, s, 1, alpha=r1, significance_level=P95, dof=dof, wavelet=mor
        )
        compare[f"sigtest1_n_a_{n_a}_level_max_rel_diff"] = rel(
            sig1, d[f"global_n_a_{n_a}"]["level_factor"]
        )
        # signif = fft_theor aliases the array, so sigtest 1 returns the level as fft_theor too.
        compare[f"sigtest1_n_a_{n_a}_fft_theor_is_the_level"] = bool(np.array_equal(theor1, sig1))
        pycwt_vals[f"sigtest1_n_a_{n_a}_level"] = f64(sig1)
    for bad, label in ((float(N), "scalar"), (np.array([float(N)]), "length1_array")):
        try:
            pycwt.significance(1.0, DT, s, 1, alpha=r1, dof=bad, wavelet=mor)
            compare[f"sigtest1_dof_{label}"] = "accepted"
        except Exception as err:  # record the failure mode, it is a pycwt defect
            compare[f"sigtest1_dof_{label}"] = f"fails: {type(err).__name__}: {err}"
    return {
        "what": "T&C red-noise significance levels per scale for the committed series, "
        "normalised to unit variance (multiply by the series variance for the level of |W|^2 in "
        "T&C's L2 normalisation); p = 0.95",
        "inputs": {
            "series": "ar1_series",
            "alpha": "ar1_series.r1_biased_acf",
            "alpha_value": r1,
            "fs_hz": FS,
            "dt_s": DT,
            "omega0": OMEGA0,
            "frequencies": "f_j = 2e3*(200e3/2e3)^(j/59), j = 0..59 (ascending)",
            "scales": "s_j = omega0/(2 pi f_j) in seconds (descending)",
            "dj_octaves": float(dj),
            "gamma": GAMMA,
            "n_a": n_a_list,
        },
        "formulas": {
            "fourier_frequency": "f_F = 1/lambda, lambda = 4 pi s/(omega0 + sqrt(2 + omega0^2)) (T&C Table 1)",
            "P": "(1 - alpha^2)/(1 + alpha^2 - 2 alpha cos(2 pi f_F dt)) (T&C eq. 16)",
            "local_level_factor": "P * chi2.ppf(0.95, 2)/2 (T&C eq. 18)",
            "global nu": "2 sqrt(1 + (n_a dt/(gamma s))^2) (T&C eq. 23)",
            "global level_factor": "P * chi2.ppf(0.95, nu)/nu (T&C eq. 22-23)",
        },
        "frequency_hz": f64(f),
        "scale_s": f64(s),
        "direct": d,
        "pycwt": {
            "calls": "pycwt.significance(1.0, dt, scales, 0, alpha=r1) and "
            "pycwt.significance(1.0, dt, scales, 1, alpha=r1, dof=numpy.full(60, n_a))",
            "values": pycwt_vals,
            "agreement": compare,
        },
    }


def block_issue26(x, r1):
    f, s, _ = grid()
    var = float(x.var())
    mor = Morlet(6)
    sig_scalar, _ = pycwt.significance(1.0, DT, s, 0, alpha=r1, wavelet=mor)
    sig_series, theor_series = pycwt.significance(x, DT, s, 0, alpha=r1, wavelet=mor)
    f_fourier = 1.0 / (FLAMBDA * s)
    idx = [0, 15, 30, 45, 59]
    rows = []
    for j in idx:
        p_right = ar1_spectrum(f_fourier[j], r1, DT)
        p_wrong = ar1_spectrum(f_fourier[j] / N, r1, DT)  # pycwt's pk(k, a, N) with k = f_F dt
        rows.append(
            {
                "j": j,
                "frequency_hz": float(f[j]),
                "fourier_frequency_hz": float(f_fourier[j]),
                "pycwt_scalar_level_over_1": float(sig_scalar[j]),
                "pycwt_series_level_over_variance": float(sig_series[j] / var),
                "ratio_series_over_scalar": float(sig_series[j] / var / sig_scalar[j]),
                "P_eq16": float(p_right),
                "P_pycwt_series_call": float(theor_series[j] / var),
                "P_at_f_F_over_N": float(p_wrong),
            }
        )
    return {
        "what": "pycwt issue #26 (regeirk/pycwt): significance() given the SERIES evaluates eq. 16 "
        "as cos(2 pi (f_F dt)/N) with N = len(series) instead of cos(2 pi f_F dt); given a scalar "
        "variance N = 1 and eq. 16 is right. The series call therefore puts the background at "
        "~ P(0) = (1 + alpha)/(1 - alpha) at every scale.",
        "calls": "pycwt.significance(x, dt, scales, 0, alpha=r1) vs pycwt.significance(1.0, dt, "
        "scales, 0, alpha=r1); series call divided by x.var() (ddof 0, pycwt's variance)",
        "alpha": r1,
        "series_variance_ddof0": var,
        "P_at_zero_frequency": (1 + r1) / (1 - r1),
        "max_rel_diff_series_call_vs_P_at_f_F_over_N": rel(
            theor_series / var, ar1_spectrum(f_fourier / N, r1, DT)
        ),
        "rows": rows,
    }


def scale_average_mc(sb, s_all, dj, n_real=1000):
    """Fraction of time points whose T&C scale-averaged power (eq. 24) of AR(1) noise exceeds the
    eq. 26 level, with nu from eq. 28 read both ways. pycwt.cwt (T&C's L2 normalisation) at the
    band's grid scales; each realisation's own variance; alpha = 0.72 known; samples within the
    COI (sqrt(2) s_max of either end) left out."""
    rng = np.random.default_rng(SA_MC_SEED)
    mor = Morlet(6)
    s_avg = 1.0 / np.sum(1.0 / sb)
    s_mid = np.sqrt(sb.min() * sb.max())
    n_sc = len(sb)
    root = np.sqrt(1 + (n_sc * dj / DJ0) ** 2)
    p_norm = ar1_spectrum(1.0 / (FLAMBDA * sb), ALPHA_TRUE, DT)
    edge = int(np.ceil(np.sqrt(2) * sb.max() / DT))
    counts = {"scales": 0, "time_points": 0}
    total = 0
    s_asc = s_all[::-1].copy()
    for _ in range(n_real):
        e = rng.standard_normal(N)
        e[0] /= np.sqrt(1 - ALPHA_TRUE**2)
        x = scipy.signal.lfilter([1.0], [1.0, -ALPHA_TRUE], e)
        x = x - x.mean()
        var = x.var()
        w, sj, _, _, _, _ = pycwt.cwt(x, DT, freqs=1.0 / (FLAMBDA * sb), wavelet=mor)
        power = (dj * DT / C_DELTA) * np.sum(np.abs(w) ** 2 / sj[:, None], axis=0)  # eq. 24
        inner = power[edge : N - edge]
        p_bar = s_avg * np.sum(var * p_norm / sb)
        for key, n_a in (("scales", n_sc), ("time_points", N)):
            nu = 2 * n_a * s_avg / s_mid * root
            lvl = dj * DT / (C_DELTA * s_avg) * p_bar * chi2_ppf(P95, nu) / nu
            counts[key] += int(np.sum(inner > lvl))
        total += inner.size
    # the same level from pycwt for the last realisation, to show the formula is pycwt's
    sig, _ = pycwt.significance(var, DT, s_asc, 2, alpha=ALPHA_TRUE, dof=[sb.min(), sb.max()], wavelet=mor)
    nu = 2 * n_sc * s_avg / s_mid * root
    mine = dj * DT / (C_DELTA * s_avg) * p_bar * chi2_ppf(P95, nu) / nu
    return {
        "what": "Monte Carlo check of eq. 28's n_a: fraction of time points (outside the COI) whose "
        "scale-averaged power of AR(1) noise exceeds the 95 % level; it should be near 0.05",
        "how": f"{n_real} AR(1) realisations (alpha = 0.72, N = {N}, unit innovations, stationary "
        f"start, numpy default_rng({SA_MC_SEED}), scipy lfilter), mean removed; pycwt.cwt(x, dt, "
        "freqs = 1/(lambda_factor s_j)) at the band's grid scales (T&C L2 normalisation); power "
        "(dj dt/C_delta) sum_j |W_j|^2/s_j (eq. 24); level eq. 26 with the realisation's "
        "variance, alpha = 0.72; samples within sqrt(2) s_max of either end left out",
        "fraction_nu_with_n_a_scales": counts["scales"] / total,
        "fraction_nu_with_n_a_time_points": counts["time_points"] / total,
        "time_points_counted": total,
        "level_rel_diff_vs_pycwt_last_realisation": rel(sig, mine),
    }


def block_scale_average(x, r1):
    f, s, dj = grid()
    mor = Morlet(6)
    p_all = ar1_spectrum(1.0 / (FLAMBDA * s), r1, DT)
    sigma2 = 1.0
    bands = []
    for lo, hi in ((90e3, 120e3), (10e3, 20e3)):
        sel = np.nonzero((f >= lo) & (f <= hi))[0]
        j1, j2 = int(sel[0]), int(sel[-1])
        sb = s[sel]
        n_sc = len(sel)
        s_avg = 1.0 / np.sum(1.0 / sb)  # T&C eq. 25
        # T&C: S_mid = s0 2^{0.5 (j1 + j2) dj} on an ascending scale index, i.e. the geometric
        # mean of the band's smallest and largest scale (hdi's index ascends in frequency).
        s_mid = float(np.sqrt(sb.min() * sb.max()))
        root = np.sqrt(1 + (n_sc * dj / DJ0) ** 2)
        nu = 2 * n_sc * s_avg / s_mid * root  # T&C eq. 28, n_a = number of scales averaged
        nu_brief = 2 * N * s_avg / s_mid * root  # the brief's reading, n_a = time points
        p_bar = s_avg * np.sum(p_all[sel] / sb)  # T&C eq. 27
        bare = p_bar * chi2_ppf(P95, nu) / nu
        full = dj * DT * sigma2 / (C_DELTA * s_avg) * bare  # T&C eq. 26
        bare_brief = p_bar * chi2_ppf(P95, nu_brief) / nu_brief
        # pycwt wants dof = [s1, s2] in the units of `scales`; it averages scales with
        # s1 <= s <= s2, takes S_mid = sqrt(s1 s2) from the two numbers given, and dj =
        # log2(scales[1]/scales[0]) -- so the scales must ascend (hdi's descend: dj < 0 and a
        # negative level).
        s_asc = s[::-1].copy()
        sig2, theor2 = pycwt.significance(
            1.0, DT, s_asc, 2, alpha=r1, significance_level=P95, dof=[sb.min(), sb.max()],
            wavelet=mor,
        )
        sig2_desc, _ = pycwt.significance(
            1.0, DT, s.copy(), 2, alpha=r1, significance_level=P95, dof=[sb.min(), sb.max()],
            wavelet=mor,
        )
        s_edges = [OMEGA0 / (2 * np.pi * hi), OMEGA0 / (2 * np.pi * lo)]
        sig2_edges, _ = pycwt.significance(
            1.0, DT, s_asc, 2, alpha=r1, significance_level=P95, dof=s_edges, wavelet=mor
        )
        bands.append(
            {
                "band_hz": [lo, hi],
                "j1": j1,
                "j2": j2,
                "n_scales": n_sc,
                "frequencies_hz": f64(f[sel]),
                "S_avg": float(s_avg),
                "S_mid": s_mid,
                "nu": float(nu),
                "P_bar": float(p_bar),
                "chi2_95_over_nu": chi2_ppf(P95, nu) / nu,
                "bare_level_P_bar_chi2_over_nu": float(bare),
                "full_level_variance_1": float(full),
                "brief_reading_na_equals_N": {
                    "note": "NOT T&C: eq. 28's n_a is the number of scales averaged (T&C's own "
                    "wave_signif: navg = number of scales); with n_a = N time points nu is huge",
                    "nu": float(nu_brief),
                    "bare_level": float(bare_brief),
                    "full_level_variance_1": float(dj * DT * sigma2 / (C_DELTA * s_avg) * bare_brief),
                },
                "pycwt": {
                    "call": "pycwt.significance(1.0, dt, scales_ascending, 2, alpha=r1, "
                    "dof=[s_min_in_band, s_max_in_band]) -> (signif, fft_theor), both scalars: "
                    "signif = (dj dt/(C_delta S_avg)) P_bar chi2_nu/nu, fft_theor = P_bar "
                    "(variance included)",
                    "signif": float(sig2),
                    "fft_theor": float(theor2),
                    "signif_rel_diff_vs_full_level": rel(sig2, full),
                    "fft_theor_rel_diff_vs_P_bar": rel(theor2, p_bar),
                    "signif_with_descending_scales": float(sig2_desc),
                    "signif_with_band_edge_scales_as_dof": float(sig2_edges),
                    "band_edge_note": "dof = [s(hi), s(lo)] (band edges, not grid scales) selects "
                    "the same scales but S_mid = sqrt(s(hi) s(lo)) changes nu",
                },
                "monte_carlo": scale_average_mc(sb, s, dj),
            }
        )
    return {
        "what": "T&C scale-averaged power significance (eqs. 24-28) on the grid of `levels`, "
        "alpha = r1, variance 1, p = 0.95",
        "inputs": {
            "grid": "levels",
            "dj_octaves": float(dj),
            "dt_s": DT,
            "C_delta": C_DELTA,
            "delta_j0": DJ0,
            "n_time_points": N,
            "alpha": r1,
        },
        "formulas": {
            "S_avg": "1/sum_j(1/s_j) over the band's grid scales (eq. 25)",
            "S_mid": "sqrt(s_min s_max) of the band's grid scales (= s_{j1} 2^{0.5 (j2-j1) dj} "
            "with j ascending in scale)",
            "nu": "(2 n_a S_avg/S_mid) sqrt(1 + (n_a dj/delta_j0)^2), n_a = j2 - j1 + 1 scales (eq. 28)",
            "P_bar": "S_avg sum_j P_j/s_j (eq. 27)",
            "full_level": "(dj dt sigma^2/(C_delta S_avg)) P_bar chi2_nu(0.95)/nu (eq. 26), sigma^2 = 1",
        },
        "bands": bands,
    }


def block_fft_level():
    w = scipy.signal.get_window("hann", N)  # periodic (DFT-even) Hann, as src/signal/spectrum.rs
    sw, sw2 = float(w.sum()), float(np.sum(w * w))
    chi = chi2_ppf(P95, 2) / 2
    ffs = [0.01, 0.05, 0.1, 0.2, 0.25, 0.3, 0.4, 0.45]
    levels = {}
    for alpha in (0.0, ALPHA_TRUE):
        p = ar1_spectrum(np.array(ffs), alpha, 1.0)
        ea2 = 4 * 1.0 * p * sw2 / sw**2
        levels[f"alpha_{alpha}"] = {
            "P": f64(p),
            "expected_A2": f64(ea2),
            "level_A_95": f64(np.sqrt(ea2 * chi)),
        }

    # Monte Carlo: AR(1), alpha = 0.72, unit innovations (sigma^2 = 1/(1 - alpha^2)), stationary
    # start; the spectrum as hdi computes it (mean removed, periodic Hann, A_k = 2|X_k|/sum w).
    rng = np.random.default_rng(MC_SEED)
    n_real, batch = 10_000, 500
    k = np.arange(N // 2 + 1)
    band = (k / N >= 0.01) & (k / N <= 0.45)
    sigma2 = 1 / (1 - ALPHA_TRUE**2)
    p_bins = ar1_spectrum(k[band] / N, ALPHA_TRUE, 1.0)
    lvl_known = np.sqrt(4 * sigma2 * p_bins * sw2 / sw**2 * chi)
    thirds = np.array_split(np.nonzero(band)[0], 3)
    exceed_known, exceed_est, total = 0, 0, 0
    exceed_third = np.zeros(3)
    count_third = np.zeros(3)
    for _ in range(n_real // batch):
        e = rng.standard_normal((batch, N))
        e[:, 0] /= np.sqrt(1 - ALPHA_TRUE**2)
        xs = scipy.signal.lfilter([1.0], [1.0, -ALPHA_TRUE], e, axis=1)
        d = xs - xs.mean(axis=1, keepdims=True)
        a = 2 * np.abs(np.fft.rfft(d * w, axis=1)) / sw
        ab = a[:, band]
        exceed_known += int(np.sum(ab > lvl_known))
        total += ab.size
        for t, idx in enumerate(thirds):
            lvl = np.sqrt(4 * sigma2 * ar1_spectrum(idx / N, ALPHA_TRUE, 1.0) * sw2 / sw**2 * chi)
            exceed_third[t] += np.sum(a[:, idx] > lvl)
            count_third[t] += a[:, idx].size
        # the same with alpha and sigma^2 estimated from each realisation (hdi's practice)
        r1 = np.sum(d[:, :-1] * d[:, 1:], axis=1) / np.sum(d * d, axis=1)
        var = np.mean(d * d, axis=1)
        pe = (1 - r1[:, None] ** 2) / (1 + r1[:, None] ** 2 - 2 * r1[:, None] * np.cos(2 * np.pi * k[band] / N))
        lvl_est = np.sqrt(4 * var[:, None] * pe * sw2 / sw**2 * chi)
        exceed_est += int(np.sum(ab > lvl_est))
    return {
        "what": "95 % level of a one-sided Hann amplitude spectrum A_k = 2|sum w_n x_n e^{-2 pi i k n/N}|/sum w "
        "of noise with variance sigma^2 and normalised AR(1) spectrum P: E[A^2] = 4 sigma^2 P(f) "
        "sum w^2/(sum w)^2, level = sqrt(E[A^2] chi2_2(0.95)/2)",
        "window": "scipy.signal.get_window('hann', N): periodic (DFT-even) Hann, the one "
        "src/signal/spectrum.rs uses (w_n = 0.5 - 0.5 cos(2 pi n/N)); hdi removes the mean first, "
        "which changes no bin k >= 2 (the periodic Hann's DFT is zero there)",
        "n": N,
        "sum_w": sw,
        "sum_w2": sw2,
        "sigma2": 1.0,
        "f_over_fs": ffs,
        "levels": levels,
        "monte_carlo": {
            "what": "fraction of bins 0.01 <= k/N <= 0.45 whose A exceeds the 95 % level, over "
            "10^4 AR(1) realisations (alpha = 0.72, unit innovations, N = 4096, stationary start), "
            f"numpy default_rng({MC_SEED}), scipy.signal.lfilter",
            "realisations": n_real,
            "bins_per_realisation": int(band.sum()),
            "fraction_known_alpha_sigma2": exceed_known / total,
            "fraction_known_by_thirds_of_band": f64(exceed_third / count_third),
            "fraction_estimated_r1_and_variance": exceed_est / total,
            "note": "known: alpha = 0.72, sigma^2 = 1/(1 - alpha^2); estimated: each "
            "realisation's biased r1 and ddof-0 variance",
        },
    }


def grinsted_kernel(dj):
    """Grinsted et al. 2004 scale smoothing (their toolbox's smoothwavelet): a boxcar of total
    width delta_j0 = 0.6 octaves, in steps 2*(0.6/(2 dj)) with fractional end weights."""
    half = DJ0 / (2 * dj)
    frac = half % 1
    k = np.concatenate(([frac], np.ones(int(2 * round(half) - 1)), [frac]))
    return k / k.sum()


def pycwt_kernel(dj):
    from pycwt.helpers import rect

    return rect(int(np.round(DJ0 / dj * 2)), normalize=True)


def width_octaves(kernel, dj):
    # width of a boxcar with the same sum and the same (1-normalised) height, in octaves
    return float(1.0 / kernel.max() * dj)


WCT_CHILD = r"""
import json, sys, time, numpy, pycwt
a = json.loads(sys.argv[1])
numpy.random.seed(a["seed"])
dt, dj, s0, J, mc = a["dt"], a["dj"], a["s0"], a["J"], a["mc_count"]
if a["what"] == "wct_significance":
    # wct_significance needs a wavelet instance: the string default fails at wavelet.smooth
    t0 = time.perf_counter()
    sig = pycwt.wct_significance(0.5, 0.5, dt=dt, dj=dj, s0=s0, J=J, significance_level=0.95,
                                 wavelet=pycwt.Morlet(6), mc_count=mc, progress=False,
                                 cache=False)
    t1 = time.perf_counter()
    out = {"seconds": t1 - t0, "sig95_first3": [float(v) for v in sig[:3]],
           "sig95_nan_count": int(numpy.isnan(sig).sum())}
else:
    y1 = pycwt.helpers.rednoise(10000, 0.5, 1)
    y2 = pycwt.helpers.rednoise(10000, 0.5, 1)
    t0 = time.perf_counter()
    pycwt.wct(y1, y2, dt, dj=dj, s0=s0, J=J, sig=True, mc_count=mc, progress=False, cache=False)
    out = {"seconds": time.perf_counter() - t0}
print(json.dumps(out))
"""


def _run_wct_child(args):
    cmd = ["nice", sys.executable, "-c", WCT_CHILD, json.dumps(args)]
    try:
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    except subprocess.TimeoutExpired:
        return {"stopped_after_s": 600, "note": "exceeded 10 minutes and was stopped"}
    if res.returncode != 0:
        return {"error": res.stderr[-2000:]}
    return json.loads(res.stdout.strip().splitlines()[-1])


def block_pycwt_notes(skip_timing):
    dj_grid = grid()[2]
    kern = {}
    for name, dj in (("dj_1_12", 1 / 12), ("dj_hdi_grid", dj_grid)):
        kp, kg = pycwt_kernel(dj), grinsted_kernel(dj)
        kern[name] = {
            "dj": float(dj),
            "pycwt_kernel": f64(kp),
            "pycwt_width_octaves": width_octaves(kp, dj),
            "grinsted_kernel": f64(kg),
            "grinsted_width_octaves": width_octaves(kg, dj),
        }
    # pycwt's cache key: round(arctanh(al*4)) is NaN for |al| > 0.25, so every such pair of
    # alphas maps to the same cache file name.
    with np.errstate(invalid="ignore"):
        aa = np.round(np.arctanh(np.array([0.5, 0.9]) * 4))
    out = {
        "pycwt_version": {"pip": _pip_version("pycwt"), "module": getattr(pycwt, "__version__", "?")},
        "smoothing_scale": {
            "pycwt": "Morlet.smooth: time smoothing by a Gaussian exp(-t^2/(2 s^2)) (FFT, zero-padded "
            "to the next power of two); scale smoothing by helpers.rect(round(wsize)) with wsize "
            "= deltaj0/dj*2 = 1.2/dj steps, i.e. [0.5, 1, ..., 1, 0.5]/sum: a boxcar about 1.2 "
            "octaves wide (13 steps = 1.08 octaves at dj = 1/12), applied with scipy "
            "convolve2d(mode='same') (zero beyond the first and last scale)",
            "grinsted_2004": "Grinsted et al. 2004 (after Torrence & Webster 1999): scale smoothing "
            "by a boxcar Pi(0.6 s), 0.6 = the Morlet's scale-decorrelation length delta_j0 of "
            "T&C Table 2; their toolbox uses half-width 0.6/(2 dj) steps, total width 0.6 "
            "octaves (8.2 steps = 0.68 octaves with end weights at dj = 1/12)",
            "difference": "pycwt smooths over about twice Grinsted's scale width (wsize is 2 delta_j0/dj "
            "where Grinsted's full width is delta_j0/dj); its coherence is therefore smoother in "
            "scale and its Monte Carlo levels differ from Grinsted's",
            "kernels": kern,
        },
        "wct_significance": {
            "how": "Monte Carlo: surrogate length N_mc = ceil(6 s_max/dt) (not the series length); "
            "for each of mc_count draws two red-noise series (helpers.rednoise: lfilter AR(1) with "
            "burn-in tau = ceil(-2/ln|g|), numpy.random.randn), their CWTs, the smoothed coherence "
            "R^2 = |S(W12/s)|^2/(S(|W1|^2/s) S(|W2|^2/s)); for every scale below the largest with "
            "any point outside the COI (period <= coi), a 1000-bin histogram of R^2 over all time "
            "points outside the COI, accumulated over the draws (a pure-Python loop over points); "
            "the level per scale is the 95th percentile of that histogram: cumulative counts "
            "(P - 0.5)/P_total interpolated at 0.95 onto the bin centres",
            "quirks": [
                "`for s in range(maxscale)` leaves the largest scale with points outside the COI at "
                "NaN, and scales with none outside the COI at 0 (not NaN)",
                "white noise (al = 0) fails: helpers.rednoise calls numpy.randn, which does not exist",
                "cache=True (default) names the cache file after round(arctanh(al*4)): NaN for "
                "|al| > 0.25, so all such alpha pairs share one cached result for the same dj, s0/dt, J",
                "the levels are per scale only (one number per scale, pooled over time outside the COI)",
                "wct_significance does not convert a wavelet name: its default wavelet='morlet' "
                "fails at wavelet.smooth (AttributeError); pass pycwt.Morlet(6) (wct() converts "
                "before calling it)",
            ],
            "cache_key_check": {"alphas": [0.5, 0.9], "round_arctanh_4alpha": [str(v) for v in aa]},
        },
        "cwt_padding": "pycwt.cwt: without pyfftw (the case here), scipy.fftpack with n = next power "
        "of two >= N: the series is zero-padded to 2^ceil(log2 N) (T&C's pad = 1); with pyfftw "
        "installed fft_kwargs sets n = len(signal), i.e. NO padding (circular transform). No mean "
        "removal inside cwt (wct/xwt normalise (y - mean)/std first). psi_ft normalised by "
        "sqrt(2 pi s/dt) (T&C eq. 6, L2 energy), so |W|^2 is in units of variance; scales with an "
        "all-NaN row are dropped",
        "significance_defects": [
            "issue #26: pk(k, a, N) uses N = len(signal) for a series (see pycwt_issue_26)",
            "sigtest 1: a scalar dof fails at len(dof), a length-1 array at numpy.zeros(1, J+1); "
            "only a full-length array works, and `dof[sel] = 1` modifies it in place",
            "sigtest 1: signif = fft_theor aliases the array, so the returned fft_theor is the level",
            "sigtest 2: dj = log2(scales[1]/scales[0]) is negative for descending scales, giving a "
            "negative level; S_mid is taken from the dof pair, not from the scales selected",
        ],
    }
    if skip_timing:
        out["timing"] = {"skipped": True}
        return out
    base = {"seed": WCT_SEED, "dt": DT, "dj": 1 / 12, "s0": 2 * DT}
    runs = [
        ("wct_significance_85_scales_mc300", dict(base, what="wct_significance", J=84, mc_count=300)),
        ("wct_pair_1e4_85_scales_mc300", dict(base, what="wct", J=84, mc_count=300)),
        ("wct_significance_117_scales_mc30", dict(base, what="wct_significance", J=116, mc_count=30)),
    ]
    timing = {}
    for name, args in runs:
        load_before = os.getloadavg()[0]
        r = _run_wct_child(args)
        # the machine is shared: the 1-minute load average says how contended the run was
        r["load_average_1min_before_after"] = [load_before, os.getloadavg()[0]]
        s_max = args["s0"] * 2 ** (args["J"] * args["dj"])
        r.update(
            {
                "n_scales": args["J"] + 1,
                "mc_count": args["mc_count"],
                "surrogate_length": int(np.ceil(s_max / DT * 6)),
            }
        )
        if "seconds" in r:
            r["seconds_per_draw"] = r["seconds"] / args["mc_count"]
        timing[name] = r
    timing.update(
        {
            "calls": {
                "wct_significance_85_scales_mc300": "pycwt.wct_significance(0.5, 0.5, dt=1e-6, "
                "dj=1/12, s0=2 dt, J=84, wavelet=pycwt.Morlet(6), mc_count=300, progress=False, "
                "cache=False)",
                "wct_pair_1e4_85_scales_mc300": "pycwt.wct(y1, y2, 1e-6, dj=1/12, s0=2 dt, J=84, "
                "sig=True, mc_count=300, progress=False, cache=False) on two 10^4-sample AR(1) "
                "(0.5) series from pycwt.helpers.rednoise: the pair's coherence + the same Monte "
                "Carlo (pycwt's own AR(1) estimates of the pair as alphas)",
                "wct_significance_117_scales_mc30": "as the first with J=116 (s_max ~ 1625 dt, "
                "surrogates ~ 10^4 samples) and only 30 draws: the cost per draw when the "
                "surrogates are as long as a 10^4-sample series",
            },
            "surrogate_note": "wct_significance has no series-length argument: the surrogates are "
            "ceil(6 s_max/dt) samples long (1536 for 85 scales from 2 dt at dj = 1/12), whatever "
            "the series length",
            "machine": f"{platform.machine()}, {os.cpu_count()} cores shared with other work, "
            f"{_cpu_model()}, Python {platform.python_version()}, numpy {np.__version__}, "
            f"scipy {scipy.__version__}, no pyfftw; each run a single niced process, one at a time",
        }
    )
    out["timing"] = timing
    return out


def _cpu_model():
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "?"


def _pip_version(name):
    from importlib.metadata import version

    return version(name)


def main():
    skip = "--skip-wct-timing" in sys.argv
    x = make_series()
    fname = "ar1_alpha072_n4096.npy"
    path = os.path.join(HERE, fname)
    np.save(path, x.astype("<f8"))
    with open(path, "rb") as fh:
        sha = hashlib.sha256(fh.read()).hexdigest()
    r1 = lag1_biased(x)
    ref = {
        "what": "Independent reference values for hdi's significance testing (issue 34): "
        "Torrence & Compo 1998 red-noise levels, global and scale-averaged spectra, the FFT "
        "amplitude level, and pycwt's behaviour. Values from scipy/numpy/pycwt or from the "
        "formulas evaluated in numpy here; none from hdi.",
        "generator": "tests/data/significance/make_significance_reference.py",
        "versions": {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "pycwt": _pip_version("pycwt"),
            "statsmodels": statsmodels.__version__ if statsmodels is not None else None,
        },
        "conventions": "Morlet omega0 = 6, dt = 1/fs, p = 0.95 unless stated; levels normalised "
        "to unit variance; T&C = Torrence & Compo 1998",
        "chi2_ppf": block_chi2(),
        "ar1_series": dict(block_series(x, fname), sha256=sha),
        "levels": block_levels(x, r1),
        "pycwt_issue_26": block_issue26(x, r1),
        "scale_average": block_scale_average(x, r1),
        "fft_level": block_fft_level(),
        "pycwt_notes": block_pycwt_notes(skip),
    }
    with open(os.path.join(HERE, "reference.json"), "w") as fh:
        json.dump(ref, fh, indent=1)
        fh.write("\n")


if __name__ == "__main__":
    main()
