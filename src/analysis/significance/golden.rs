//! Golden tests: hdi's significance numerics against the independent values in
//! `tests/data/significance/reference.json` (scipy, numpy and pycwt, written by
//! `make_significance_reference.py` beside it; tests/data/README.md, "significance/").
//! Formulas: Torrence & Compo 1998 ("T&C"). The reference's wavelet levels are "normalised
//! level factors": T&C's L2 levels divided by the series variance. hdi's CWT is L1, whose
//! white-noise power at scale `s` is `K(s)` ([`white_noise_power`]), so an hdi level divided by
//! `σ²·K(s)` is the reference's factor.

use super::*;
use crate::analysis::cwt::{cwt_morlet, reconstruction_integrals, CwtOptions, FrequencyGrid};
use crate::analysis::series::spectrum;
use crate::formats::npy::{parse, Dtype};
use serde_json::Value;

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/significance/");
/// The reference's confidence level (its `conventions`: p = 0.95 unless stated).
const LEVEL: f64 = 0.95;

fn reference() -> Value {
    let text = std::fs::read_to_string(format!("{DIR}reference.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("not an array: {v}"))
        .iter()
        .map(num)
        .collect()
}

#[track_caller]
fn assert_rel(what: &str, got: f64, want: f64, tol: f64) {
    let rel = (got - want).abs() / want.abs();
    assert!(
        rel <= tol,
        "{what}: hdi {got:e}, reference {want:e}, relative difference {rel:e} > {tol:e}"
    );
}

/// The committed AR(1) series (`ar1_series.file`: little-endian float64, 1-d).
fn series(r: &Value) -> Vec<f64> {
    let name = r["ar1_series"]["file"].as_str().unwrap();
    let bytes = std::fs::read(format!("{DIR}{name}")).unwrap();
    let h = parse(&bytes, bytes.len()).unwrap();
    match h.dtype {
        Dtype::Scalar(s) if s.kind == 'f' && s.size == 8 && !s.big_endian => {}
        d => panic!("{name}: expected <f8, found {d:?}"),
    }
    assert_eq!(h.shape.len(), 1, "{name}: a 1-d array");
    let x: Vec<f64> = bytes[h.data_offset..h.data_offset + h.data_len()]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(x.len() as u64, r["ar1_series"]["n"].as_u64().unwrap());
    x
}

/// hdi's L1 scalogram of the series on the grid of the `levels` block (log-spaced, ascending),
/// checked to be that grid: the same frequencies and scales `s = ω0/(2πf)`.
fn scalogram(r: &Value, x: &[f64]) -> Scalogram {
    let lv = &r["levels"];
    let f_ref = floats(&lv["frequency_hz"]);
    let fs = num(&lv["inputs"]["fs_hz"]);
    let opts = CwtOptions {
        frequencies: FrequencyGrid::Log {
            f_min_hz: f_ref[0],
            f_max_hz: f_ref[f_ref.len() - 1],
            count: f_ref.len(),
        },
        ..Default::default()
    };
    let sc = cwt_morlet(x, fs, &opts).unwrap();
    assert_eq!(sc.wavelet, Wavelet::Morlet { omega0: 6.0 });
    assert_eq!(sc.normalization, Normalization::Amplitude);
    for (j, (f, s)) in f_ref.iter().zip(floats(&lv["scale_s"])).enumerate() {
        assert_rel(
            &format!("grid frequency {j}"),
            sc.frequencies_hz[j],
            *f,
            1e-12,
        );
        assert_rel(&format!("grid scale {j}"), sc.scales_s[j], s, 1e-12);
    }
    sc
}

#[test]
fn chi2_quantiles_match_scipy() {
    let r = reference();
    let c = &r["chi2_ppf"];
    let nus = floats(&c["nu"]);
    for (p, row) in floats(&c["p"]).iter().zip(c["table"].as_array().unwrap()) {
        for (nu, want) in nus.iter().zip(floats(row)) {
            let got = chi2_quantile(*p, *nu).unwrap();
            assert_rel(&format!("chi2_quantile({p}, {nu})"), got, want, 1e-9);
        }
    }
}

#[test]
fn ar1_background_of_the_committed_series_matches_numpy() {
    let r = reference();
    let a = &r["ar1_series"];
    let x = series(&r);
    // The file is the one the JSON describes (its mean, to summation rounding).
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    assert_rel("series mean", mean, num(&a["mean"]), 1e-12);
    let r1 = num(&a["r1_biased_acf"]);
    assert_rel(
        "lag-1 autocorrelation",
        lag1_autocorrelation(&x).unwrap(),
        r1,
        1e-12,
    );
    let bg = RedNoise::estimate(&x).unwrap();
    assert_rel("RedNoise alpha", bg.alpha, r1, 1e-12);
    assert_rel(
        "RedNoise variance (ddof 0)",
        bg.variance,
        num(&a["variance_ddof0"]),
        1e-12,
    );
    // hdi's estimator is the biased sample ACF (statsmodels' acf, to the last bit), not pycwt's
    // Allen & Smith (1996) bias-corrected g, which the reference gives 5.9e-4 higher.
    assert_rel(
        "statsmodels acf",
        bg.alpha,
        num(&a["statsmodels_acf_lag1"]),
        1e-12,
    );
    let g = num(&a["pycwt_ar1"]["g"]);
    assert!(
        (bg.alpha - g).abs() > 1e-4,
        "hdi's r1 {} vs pycwt g {g}",
        bg.alpha
    );
}

#[test]
fn local_levels_match_tc_eqs_16_and_18() {
    let r = reference();
    let lv = &r["levels"];
    let d = &lv["direct"];
    let x = series(&r);
    let sc = scalogram(&r, &x);
    let fs = sc.sample_rate_hz;
    // α = the series' r1, as the reference's `inputs.alpha` says.
    let bg = RedNoise::estimate(&x).unwrap();
    assert_rel("alpha", bg.alpha, num(&lv["inputs"]["alpha_value"]), 1e-12);
    let sig = wavelet_significance(&sc, &bg, LEVEL).unwrap();
    let (f_f, p, local) = (
        floats(&d["fourier_frequency_hz"]),
        floats(&d["P"]),
        floats(&d["local_level_factor"]),
    );
    for (j, &s) in sc.scales_s.iter().enumerate() {
        let k = white_noise_power(&sc.wavelet, sc.normalization, s, fs).unwrap();
        let at = |what: &str| format!("{what}, row {j} ({:.0} Hz)", sc.frequencies_hz[j]);
        // T&C Table 1.
        assert_rel(
            &at("Fourier frequency"),
            fourier_frequency(&sc.wavelet, s),
            f_f[j],
            1e-9,
        );
        assert_rel(
            &at("significance's Fourier frequency"),
            sig.fourier_frequency_hz[j],
            f_f[j],
            1e-9,
        );
        // T&C eq. 16 at the Fourier frequency.
        assert_rel(&at("P"), bg.normalized_spectrum(f_f[j], fs), p[j], 1e-9);
        assert_rel(
            &at("background power / σ²K"),
            sig.background_power[j] / bg.variance / k,
            p[j],
            1e-9,
        );
        // T&C eq. 18: P·χ²₂(0.95)/2.
        assert_rel(
            &at("local level / σ²K"),
            sig.local_level[j] / bg.variance / k,
            local[j],
            1e-9,
        );
    }
}

/// hdi averages the global spectrum over the samples outside its cone of influence, so its `n_a`
/// of T&C eq. 23 ("the number of points averaged") is `global_samples[j]`, which varies by row
/// and never equals the reference's n_a = N (the record's edge samples are always inside the
/// cone) or 1000. The level depends on the scalogram only through that count: with the cone
/// replaced so that exactly n_a samples lie outside it in every row, hdi's definition and the
/// reference's coincide and `wavelet_significance`'s own ν and level can be compared.
#[test]
fn global_levels_match_tc_eqs_22_and_23() {
    let r = reference();
    let lv = &r["levels"];
    let x = series(&r);
    let mut sc = scalogram(&r, &x);
    let fs = sc.sample_rate_hz;
    let bg = RedNoise::estimate(&x).unwrap();
    let n_as: Vec<u64> = lv["inputs"]["n_a"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(n_as.len(), 2);
    for n_a in n_as {
        let block = &lv["direct"][format!("global_n_a_{n_a}")];
        let (nu, factor) = (floats(&block["nu"]), floats(&block["level_factor"]));
        let n_a = n_a as usize;
        assert!(n_a <= sc.n_time);
        // A row is averaged where f ≥ coi: 0 Hz admits every row, ∞ none.
        sc.coi_hz = (0..sc.n_time)
            .map(|n| if n < n_a { 0.0 } else { f64::INFINITY })
            .collect();
        let sig = wavelet_significance(&sc, &bg, LEVEL).unwrap();
        for (j, &s) in sc.scales_s.iter().enumerate() {
            let at = |what: &str| format!("{what}, n_a = {n_a}, row {j}");
            assert_eq!(sig.global_samples[j], n_a, "{}", at("samples averaged"));
            assert_rel(&at("ν"), sig.global_dof[j], nu[j], 1e-9);
            let k = white_noise_power(&sc.wavelet, sc.normalization, s, fs).unwrap();
            let level = sig.global_level[j].unwrap() / bg.variance / k;
            assert_rel(&at("global level / σ²K"), level, factor[j], 1e-9);
        }
    }
}

/// T&C eqs. 25–28, ν with n_a = the number of scales averaged (as hdi and the reference both
/// read eq. 28). hdi forms the band power from the L1 transform with its exact energy constant
/// instead of T&C's empirical C_δ = 0.776 (and its level with the same constant, so that the
/// mask does not depend on it); the reference's full level uses 0.776. The C_δ-free part,
/// `P̄·χ²_ν/ν`, is compared: hdi's `level_power = σ²·(2c/(√π fs))·(P̄/S_avg)·χ²_ν/ν` with
/// `c = δj ln2/(2 I_E)` (see `scale_average`), divided by that factor.
#[test]
fn scale_averaged_levels_match_tc_eqs_25_to_28() {
    let r = reference();
    let sa = &r["scale_average"];
    let x = series(&r);
    let sc = scalogram(&r, &x);
    let fs = sc.sample_rate_hz;
    let bg = RedNoise::estimate(&x).unwrap();
    assert_rel("alpha", bg.alpha, num(&sa["inputs"]["alpha"]), 1e-12);
    let dj = (sc.frequencies_hz[1] / sc.frequencies_hz[0]).log2();
    assert_rel("δj", dj, num(&sa["inputs"]["dj_octaves"]), 1e-12);
    let c = dj * std::f64::consts::LN_2 / (2.0 * reconstruction_integrals(&sc.wavelet).0);
    let bands = sa["bands"].as_array().unwrap();
    assert_eq!(bands.len(), 2);
    for b in bands {
        let band = floats(&b["band_hz"]);
        let avg = scale_average(&sc, &bg, "band", (band[0], band[1]), LEVEL).unwrap();
        let at = |what: &str| format!("{what}, band {} – {} Hz", band[0], band[1]);
        let rows = (
            b["j1"].as_u64().unwrap() as usize,
            b["j2"].as_u64().unwrap() as usize,
        );
        assert_eq!(avg.rows, rows, "{}", at("rows"));
        let s_avg = 1.0
            / sc.scales_s[rows.0..=rows.1]
                .iter()
                .map(|s| 1.0 / s)
                .sum::<f64>();
        assert_rel(&at("S_avg"), s_avg, num(&b["S_avg"]), 1e-12);
        let nu = num(&b["nu"]);
        assert_rel(&at("ν"), avg.dof, nu, 1e-9);
        let q = chi2_quantile(LEVEL, nu).unwrap() / nu;
        assert_rel(&at("χ²_ν/ν"), q, num(&b["chi2_95_over_nu"]), 1e-9);
        let bare = avg.level_power * PI.sqrt() * fs * s_avg / (2.0 * c * bg.variance);
        assert_rel(
            &at("P̄·χ²_ν/ν"),
            bare,
            num(&b["bare_level_P_bar_chi2_over_nu"]),
            1e-9,
        );
        let p_bar = bare * avg.dof / chi2_quantile(LEVEL, avg.dof).unwrap();
        assert_rel(&at("P̄"), p_bar, num(&b["P_bar"]), 1e-9);
    }
}

/// The FFT amplitude level `sqrt(4σ²P(f)·Σw²/(Σw)²·χ²₂(0.95)/2)`. Σw and Σw² of the window
/// hdi's spectrum applies are measured through the spectrum itself: an impulse at N/2 (where
/// the periodic Hann is 1) reads `A_k = 2/Σw` for 2 ≤ k < N/2 (the removed mean's windowed
/// DFT is zero there); the alternating series ±1 (mean 0) gives Σw² by Parseval,
/// `N·Σw² = (Σw)²·(A_0² + A_{N/2}² + ½ Σ_{0<k<N/2} A_k²)`.
#[test]
fn fft_levels_match_the_periodic_hann_of_scipy() {
    use crate::signal::spectrum::Window;
    let r = reference();
    let fl = &r["fft_level"];
    let n = fl["n"].as_u64().unwrap() as usize;
    let fs = 1e6; // any rate: the reference is per f/fs
    let mut impulse = vec![0.0; n];
    impulse[n / 2] = 1.0;
    let sp = spectrum(&impulse, fs, Window::Hann).unwrap();
    let sum_w = 2.0 / sp.amplitude[n / 4];
    assert_rel("Σw", sum_w, num(&fl["sum_w"]), 1e-9);
    let alternating: Vec<f64> = (0..n)
        .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let a = spectrum(&alternating, fs, Window::Hann).unwrap().amplitude;
    let inner: f64 = a[1..n / 2].iter().map(|v| v * v).sum();
    let sum_w2 = sum_w * sum_w * (a[0] * a[0] + a[n / 2] * a[n / 2] + 0.5 * inner) / n as f64;
    assert_rel("Σw²", sum_w2, num(&fl["sum_w2"]), 1e-9);

    let x = series(&r);
    assert_eq!(x.len(), n);
    let sp = spectrum(&x, fs, Window::Hann).unwrap();
    assert_eq!(num(&fl["sigma2"]), 1.0);
    let ffs = floats(&fl["f_over_fs"]);
    let chi = chi2_quantile(LEVEL, 2.0).unwrap() / 2.0;
    let levels = fl["levels"].as_object().unwrap();
    assert_eq!(levels.len(), 2);
    for (key, block) in levels {
        let alpha: f64 = key.strip_prefix("alpha_").unwrap().parse().unwrap();
        let bg = RedNoise::new(alpha, 1.0).unwrap();
        let (p, ea2, lvl) = (
            floats(&block["P"]),
            floats(&block["expected_A2"]),
            floats(&block["level_A_95"]),
        );
        for (i, &q) in ffs.iter().enumerate() {
            let at = |what: &str| format!("{what}, α = {alpha}, f/fs = {q}");
            assert_rel(&at("P"), bg.normalized_spectrum(q * fs, fs), p[i], 1e-9);
            let got = spectrum_level(&sp, n, &bg, q * fs, LEVEL).unwrap();
            assert_rel(&at("E[A²]"), got * got / chi, ea2[i], 1e-9);
            assert_rel(&at("95 % level"), got, lvl[i], 1e-9);
        }
    }
}
