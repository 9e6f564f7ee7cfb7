#!/usr/bin/env python3
"""Time the DMW chain on a 10^7-sample LDV record: `hdi dmw` against the same steps in
numpy/scipy (the issue's comparison; figures go to docs/performance.md).

Usage (from the project root, after `cargo build --release`):
    .venv/bin/pip install scipy        # not needed by the tests, only by this comparison
    .venv/bin/python scripts/bench_dmw.py [--hdi target/release/hdi] [--revolutions 227]

Steps timed on both sides, each from the file on disk: read velocity + index and check them
(finite values; the time column, where the file has one, strictly increasing and uniform), find the
once-per-revolution triggers (mid-level rising crossings, sub-sample), average 2.5 ms after each
trigger (integer alignment, and angular: each revolution resampled to the mean speed with a cubic
spline), scale, zero-phase 4th-order 10 kHz Butterworth high-pass (padlen 1200), trapezoid
integration, linear detrend, the three tracks, a Hann amplitude spectrum. hdi's time is the
whole process (startup, read, chain, JSON), without writing HDF5.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

try:
    from scipy import integrate, interpolate, signal
except ImportError:
    sys.exit("scipy is needed for the comparison: .venv/bin/pip install scipy")


def read(path):
    if path.endswith(".parquet"):
        import pyarrow.parquet as pq

        t = pq.read_table(path, columns=["time_s", "velocity_V", "index_V"])
        return checked(t["time_s"].to_numpy(), t["velocity_V"].to_numpy(), t["index_V"].to_numpy())
    if path.endswith(".csv"):
        import pyarrow.csv as pc

        t = pc.read_csv(
            path,
            read_options=pc.ReadOptions(skip_rows=sum(1 for _ in open_comments(path))),
            convert_options=pc.ConvertOptions(include_columns=["time_s", "velocity_V", "index_V"]),
        )
        return checked(t["time_s"].to_numpy(), t["velocity_V"].to_numpy(), t["index_V"].to_numpy())
    import h5py

    with h5py.File(path, "r") as h:
        g = h["ldv"]
        fs = float(g.attrs["sampling_rate"])

        def channel(name):
            d = g[name]
            x = d[()].astype(np.float64)
            if "scale" in d.attrs:
                x = x * d.attrs["scale"] + d.attrs.get("offset", 0.0)
            return x

        u, idx = channel("velocity"), channel("index")
        if "time" in g:
            return checked(g["time"][()], u, idx)
        return checked(None, u, idx, fs)


def checked(t, u, idx, fs=None):
    """What hdi checks on every record: finite channels, a strictly increasing, uniform time."""
    if not (np.isfinite(u).all() and np.isfinite(idx).all()):
        raise ValueError("NaN in a channel")
    if t is not None:
        dt = np.diff(t)
        if not (dt > 0).all():
            raise ValueError("time does not increase")
        mean_dt = (t[-1] - t[0]) / (len(t) - 1)
        if np.abs(dt - mean_dt).max() > 1e-3 * mean_dt:
            raise ValueError("time is not uniform")
        fs = 1.0 / mean_dt
    return fs, u, idx


def open_comments(path):
    with open(path) as f:
        for line in f:
            if not line.startswith("#"):
                return
            yield line


def chain(fs, u, idx, mode):
    lo, hi = np.quantile(idx[:: max(1, len(idx) // 1_000_000)], [0.001, 0.999])
    level = 0.5 * (lo + hi)
    i = np.flatnonzero((idx[:-1] < level) & (idx[1:] >= level))
    t = (i + (level - idx[i]) / (idx[i + 1] - idx[i])) / fs
    t = t[np.concatenate(([True], np.diff(t) > 0.5 * 60 / 5425))]
    n_s = 10_000
    periods = np.diff(t)
    p_mean = periods.mean()
    if mode == "integer":
        starts = np.round(t * fs).astype(np.int64)
        starts = starts[starts + n_s <= len(u)]
        avg = u[starts[:, None] + np.arange(n_s)].mean(axis=0)
    else:
        segs = []
        for k in range(len(t) - 1):
            ratio = periods[k] / p_mean
            pos = t[k] * fs + np.arange(n_s) * ratio
            a, b = int(pos[0]) - 24, int(pos[-1]) + 26
            if a < 0 or b > len(u):
                continue
            cs = interpolate.CubicSpline(np.arange(a, b), u[a:b], bc_type="natural")
            segs.append(cs(pos) * ratio)
        avg = np.mean(segs, axis=0)
    v = 0.025 * avg
    v -= v.mean()
    sos = signal.butter(4, 10e3, "highpass", fs=fs, output="sos")
    vf = signal.sosfiltfilt(sos, v, padlen=1200)
    d = signal.detrend(integrate.cumulative_trapezoid(vf, dx=1 / fs, initial=0))
    tracks = (d, d[::-1], -d[::-1], vf, -vf[::-1], vf[::-1])
    inner = d[1200:-1200]
    f, p = signal.periodogram(inner, fs, window="hann", scaling="spectrum")
    return inner.std(), f[np.argmax(np.sqrt(2 * p))], tracks


def best_of(n, fn):
    best = float("inf")
    out = None
    for _ in range(n):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--hdi", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"), "release", "hdi"))
    ap.add_argument("--revolutions", type=int, default=227)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        files = {}
        for fmt in ["h5", "h5-f64", "parquet", "csv"]:
            out = subprocess.run(
                [args.hdi, "synth", "ldv", "--format", fmt, "--revolutions", str(args.revolutions), "--out-dir", os.path.join(tmp, fmt)],
                check=True, capture_output=True, text=True,
            ).stdout.split()[0]
            files[fmt] = out
        n = None
        print(f"{'file':<28} {'size':>9}  {'step':<34} {'hdi':>8} {'numpy/scipy':>12}  ratio")
        for fmt, path in files.items():
            size = os.path.getsize(path) / 1e6
            for mode in ["integer", "angular"]:
                t_hdi, out = best_of(args.repeat, lambda: subprocess.run(
                    [args.hdi, "dmw", path, "--averaging", mode, "--rpm", "5425", "--json"],
                    check=True, capture_output=True, text=True).stdout)
                j = json.loads(out)
                n = j["n_avg"]
                t_read, (fs, u, idx) = best_of(args.repeat, lambda: read(path))
                t_chain, (std, f0, _) = best_of(args.repeat, lambda: chain(fs, u, idx, mode))
                t_py = t_read + t_chain
                print(f"{os.path.basename(path):<28} {size:7.1f}MB  read + {mode:<8} chain (N={n:3d})   {t_hdi:7.3f}s {t_py:11.3f}s  {t_py / t_hdi:5.1f}×"
                      f"   (std {j['dmw_std_m'] * 1e9:.4f} / {std * 1e9:.4f} nm, f0 {j['dominant_frequency_Hz'] / 1e3:.2f} / {f0 / 1e3:.2f} kHz; scipy read {t_read:.3f}s)")
        print(f"samples per record: {len(u)}")


if __name__ == "__main__":
    main()
