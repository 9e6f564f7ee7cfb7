//! `hdi analyze FILE --stream`: the band CWT of a `.npy` series read block by block, against
//! an independent numpy evaluation of the documented transform (docs/analysis.md, "CWT" and
//! "Streaming band CWT"), its JSON against docs/schemas/analyze-stream.json, and its errors.
use crate::common::*;
use std::path::Path;

/// numpy writes the series and, independently of hdi, evaluates the transform as
/// docs/analysis.md defines it: the mean-removed series zero-padded to 2^⌈log2 2N⌉, one FFT,
/// times the analytic L1 Morlet `2·exp(−(sω − 6)²/2)` on the positive frequencies, one inverse
/// FFT per frequency (f64, no cut-off), then mean |W|² and max |W| per bin of `decimate`
/// samples; the cone of influence `6√2/(2π·t_edge)` at the bin sample nearest an edge.
const SCRIPT: &str = r#"
import sys, os
import numpy as np, h5py
d, fs, n, decimate = sys.argv[1], 2e6, 300_000, 500
f_lo, f_hi, count = 40e3, 200e3, 11
t = np.arange(n) / fs
rng = np.random.default_rng(34)
x = (1.0 + 0.4 * np.sin(2 * np.pi * 150e3 * t + 0.3)
     + np.where(t < 0.6 * n / fs, 0.8 * np.cos(2 * np.pi * 60e3 * t), 0.0)
     + 0.05 * rng.standard_normal(n))
np.save(os.path.join(d, "band.npy"), x)
np.save(os.path.join(d, "band_f32_be.npy"), x.astype(">f4"))
bad = x.copy(); bad[123_456] = np.nan
np.save(os.path.join(d, "nan.npy"), bad)
np.save(os.path.join(d, "two_d.npy"), x[:1000].reshape(2, 500))
np.save(os.path.join(d, "ints.npy"), np.arange(1000, dtype="<i4"))

def reference(x):
    m = int(2 ** np.ceil(np.log2(2 * n)))
    X = np.fft.fft(x - x.mean(), m)
    w = 2 * np.pi * np.fft.fftfreq(m, 1 / fs)
    f = f_lo * np.exp(np.log(f_hi / f_lo) / (count - 1) * np.arange(count))
    bins = -(-n // decimate)
    power, peak = np.zeros((count, bins)), np.zeros((count, bins))
    for j, fj in enumerate(f):
        s = 6.0 / (2 * np.pi * fj)
        psi = np.where(w > 0, 2 * np.exp(-0.5 * (s * w - 6.0) ** 2), 0.0)
        a = np.abs(np.fft.ifft(X * psi)[:n])
        pad = np.full(bins * decimate - n, np.nan)
        a = np.concatenate([a, pad]).reshape(bins, decimate)
        power[j] = np.nanmean(a ** 2, axis=1)
        peak[j] = np.nanmax(a, axis=1)
    lo = np.arange(bins) * decimate
    hi = np.minimum(lo + decimate, n)
    edge = np.minimum(lo, n - hi) / fs
    with np.errstate(divide="ignore"):
        coi = np.where(edge > 0, np.minimum(6 * np.sqrt(2) / (2 * np.pi * edge), fs / 2), fs / 2)
    return f, power, peak, coi

f, power, peak, coi = reference(x)
with h5py.File(os.path.join(d, "reference.h5"), "w") as h:
    h["frequency"], h["mean_power"], h["max_magnitude"], h["coi"] = f, power, peak, coi
    last = n - (power.shape[1] - 1) * decimate
    h["global_power"] = (power[:, :-1].sum(axis=1) * decimate + power[:, -1] * last) / n
"#;

fn read_h5(path: &Path, name: &str) -> Vec<f64> {
    // No HDF5 file lock: a child another test forks meanwhile would inherit it.
    let f = hdf5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open(path)
        .unwrap();
    f.dataset(name).unwrap().read_raw::<f64>().unwrap()
}

fn analyze(file: &Path, extra: &[&str]) -> std::process::Output {
    hdi()
        .arg("analyze")
        .arg(file)
        .args([
            "--stream",
            "--f-min",
            "40 kHz",
            "--f-max",
            "200 kHz",
            "--frequencies",
            "11",
            "--decimate",
            "500",
        ])
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn streamed_band_scalogram_matches_numpy_and_reads_the_tones() {
    let dir = tempfile::tempdir().unwrap();
    let o = std::process::Command::new(python())
        .arg("-c")
        .arg(SCRIPT)
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let reference = dir.path().join("reference.h5");
    let out = dir.path().join("out");
    let o = analyze(
        &dir.path().join("band.npy"),
        &[
            "--sample-rate",
            "2 MHz",
            "--json",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert_matches_schema("analyze-stream", &text);
    let j: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(j["samples"], 300_000);
    assert_eq!(j["dtype"], "float64");
    assert_eq!(j["bins"], 600);
    // 300 000 samples in blocks of at most 2^16: several blocks.
    assert!(j["blocks"]["count"].as_u64().unwrap() >= 4, "{j}");

    let h5 = out.join("analysis.h5");
    let g = "analysis/band_scalogram";
    let got = |name: &str| read_h5(&h5, &format!("{g}/{name}"));
    let want = |name: &str| read_h5(&reference, name);
    let f = got("frequency");
    for (a, b) in f.iter().zip(want("frequency")) {
        assert!((a / b - 1.0).abs() < 1e-12, "{a} vs {b}");
    }
    // |W| to the f32 inverse transforms' rounding: 1e-5 of the largest |W|.
    let (peak, peak_ref) = (got("max_magnitude"), want("max_magnitude"));
    let largest = peak_ref.iter().cloned().fold(0.0, f64::max);
    let err = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / largest
    };
    let rms = |p: Vec<f64>| p.iter().map(|v| v.sqrt()).collect::<Vec<_>>();
    assert_eq!(peak.len(), peak_ref.len());
    assert!(err(&peak, &peak_ref) < 1e-5, "{}", err(&peak, &peak_ref));
    let (power, power_ref) = (rms(got("mean_power")), rms(want("mean_power")));
    assert!(
        err(&power, &power_ref) < 1e-5,
        "{}",
        err(&power, &power_ref)
    );
    let coi = got("coi_frequency");
    for (a, b) in coi.iter().zip(want("coi")) {
        assert!((a / b - 1.0).abs() < 1e-12, "{a} vs {b}");
    }
    for (k, (item, b)) in j["frequencies"]
        .as_array()
        .unwrap()
        .iter()
        .zip(want("global_power"))
        .enumerate()
    {
        let a = item["mean_power"].as_f64().unwrap();
        assert!(
            (a - b).abs() < 1e-5 * largest * largest,
            "row {k}: {a} vs {b}"
        );
    }

    // The tones, as L1 reads them: the ridge sits on 60 kHz while that tone (0.8) lasts,
    // then on 150 kHz (0.4); time is the bin centre.
    let (ridge, time) = (got("ridge_frequency"), got("time"));
    let nf = f.len();
    for (b, (r, t)) in ridge.iter().zip(&time).enumerate() {
        assert!((t - (b as f64 * 500.0 + 249.5) / 2e6).abs() < 1e-12);
        let clear = coi[b] < 40e3 && (*t < 0.08 || *t > 0.095);
        if !clear {
            continue;
        }
        let want_f = if *t < 0.09 { 60e3 } else { 150e3 };
        // On this grid (ratio 5^0.1 = 1.17) the parabola through the Gaussian response of
        // a pure tone places the ridge 0.5 % (60 kHz) and 1.0 % (150 kHz) high.
        assert!((r / want_f - 1.0).abs() < 0.02, "bin {b} at {t} s: {r}");
    }
    assert_eq!(peak.len(), nf * time.len());

    // The same series as big-endian float32: the same transform to float32 rounding.
    let o = analyze(
        &dir.path().join("band_f32_be.npy"),
        &["--sample-rate", "2 MHz", "--json"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let j32: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(j32["dtype"], "float32");
    for (a, b) in j32["frequencies"]
        .as_array()
        .unwrap()
        .iter()
        .zip(j["frequencies"].as_array().unwrap())
    {
        let (a, b) = (
            a["max_magnitude"].as_f64().unwrap(),
            b["max_magnitude"].as_f64().unwrap(),
        );
        assert!((a - b).abs() < 1e-5 * largest, "{a} vs {b}");
    }

    // Errors: one line naming the file.
    let rate = ["--sample-rate", "2 MHz"];
    let nan = dir.path().join("nan.npy");
    assert_clean_failure(
        &analyze(&nan, &rate),
        "non-finite value NaN at sample 123456",
    );
    assert_clean_failure(&analyze(&nan, &rate), "nan.npy");
    assert_clean_failure(
        &analyze(&dir.path().join("two_d.npy"), &rate),
        "two_d.npy: array of shape [2, 500]",
    );
    assert_clean_failure(
        &analyze(&dir.path().join("ints.npy"), &rate),
        "ints.npy: element type i4",
    );
    assert_clean_failure(&analyze(&reference, &rate), "reference.h5: not a .npy file");
    assert_clean_failure(
        &analyze(&dir.path().join("band.npy"), &["--sample-rate", "300 kHz"]),
        "above the Nyquist frequency",
    );
    assert_clean_failure(
        &analyze(&dir.path().join("band.npy"), &[]),
        "band.npy: a .npy array has no time axis: give --sample-rate",
    );
}
