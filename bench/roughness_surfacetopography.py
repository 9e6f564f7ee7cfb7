#!/usr/bin/env python3
"""SurfaceTopography side of the roughness comparison (docs/performance.md, "Surfaces stage").

    python bench/roughness_surfacetopography.py FILE.npy [--size-m 4e-6] [--repeat 3] [--json]
    python bench/roughness_surfacetopography.py --write-synthetic N PREFIX [--seed 7]

The first form loads a square height map (metres, float64, row = y) from FILE.npy and times the
SurfaceTopography calls that compute what `hdi surface` computes on an already-read map:

  hdi (src/surface/*)                          SurfaceTopography call timed here
  -------------------------------------------  ------------------------------------------------
  level `plane` (the default recipe's plane)   topo.detrend('center')   (mean removal)
                                               topo.detrend('height')   (plane fit)
  σ (Sq), Sa, Ssk, Sku                         rms_height_from_area, mean_abs_height, skewness,
                                               kurtosis (scipy on the heights if absent)
  m2 (rms slope), m4 (rms curvature), Rdq      rms_gradient, rms_laplacian,
                                               rms_slope_from_profile, rms_curvature_from_profile
  9-point summits, η, mean summit curvature R  (SurfaceTopography 1.x has no summit call:
                                               vectorised numpy on topo.heights(), strict
                                               maxima over 8 neighbours in the interior, κ
                                               from the x, y and diagonal second differences,
                                               R = 1/mean κ, as docs/surfaces.md defines)

The best of `--repeat` runs of each call is printed (wall and CPU seconds) with its value.
`--json` prints one object: {"file", "n", "calls": {name: {"seconds", "cpu_seconds", "value"}},
"total_seconds", "total_cpu_seconds", versions}.

The second form writes a synthetic Gaussian-ACF surface (σ 0.5 nm, correlation length 40 nm,
4 µm side, periodic) as PREFIX.npy (float64, metres) and PREFIX.gsf (Gwyddion Simple Field,
float32, which `hdi surface` reads). The .npy holds the float32-rounded heights, so both tools
see the same numbers.
"""
import argparse
import json
import sys
import time

import numpy as np


def write_synthetic(n, prefix, seed, size_m=4e-6, sigma=0.5e-9, corr=40e-9):
    rng = np.random.default_rng(seed)
    d = size_m / n
    # Gaussian ACF exp(−r²/ℓ²) ⇔ PSD ∝ exp(−k²ℓ²/4); filter white noise in the half spectrum.
    kx = 2 * np.pi * np.fft.rfftfreq(n, d)
    ky = 2 * np.pi * np.fft.fftfreq(n, d)
    spec = np.fft.rfft2(rng.standard_normal((n, n)))
    for j in range(n):  # row by row keeps the 8192² case within a few GB
        spec[j] *= np.exp(-(kx**2 + ky[j] ** 2) * corr**2 / 8.0)
    z = np.fft.irfft2(spec, s=(n, n))
    del spec
    z *= sigma / z.std()
    z32 = z.astype("<f4")
    np.save(prefix + ".npy", z32.astype(np.float64))
    header = (
        "Gwyddion Simple Field 1.0\n"
        f"XRes = {n}\nYRes = {n}\nXReal = {size_m:e}\nYReal = {size_m:e}\n"
        "XOffset = 0\nYOffset = 0\nXYUnits = m\nZUnits = m\nTitle = synthetic\n"
    ).encode()
    with open(prefix + ".gsf", "wb") as f:
        f.write(header + b"\0" * (4 - len(header) % 4))
        z32.tofile(f)


def best_of(repeat, fn):
    """Best wall time, best CPU time (process_time: this process, all threads) and the value."""
    best, best_cpu, value = float("inf"), float("inf"), None
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        value = fn()
        best = min(best, time.perf_counter() - t)
        best_cpu = min(best_cpu, time.process_time() - c)
    return best, best_cpu, value


def summits_9pt(h, dx):
    """Strict local maxima over the 8 neighbours, interior pixels only (a non-periodic map),
    and R = 1/mean κ with κ = −¼(δ²x + δ²y + both diagonal second differences)."""
    c = h[1:-1, 1:-1]
    nb = {
        (di, dj): h[1 + di : h.shape[0] - 1 + di, 1 + dj : h.shape[1] - 1 + dj]
        for di in (-1, 0, 1)
        for dj in (-1, 0, 1)
        if (di, dj) != (0, 0)
    }
    peak = np.ones(c.shape, dtype=bool)
    for v in nb.values():
        peak &= c > v
    cc = c[peak]
    second = lambda a, b: (nb[a][peak] - 2 * cc + nb[b][peak])
    kappa = -0.25 * (
        (second((0, -1), (0, 1)) + second((-1, 0), (1, 0))) / dx**2
        + (second((-1, -1), (1, 1)) + second((-1, 1), (1, -1))) / (2 * dx**2)
    )
    return int(peak.sum()), 1.0 / kappa.mean(), c.size


def measure(path, size_m, repeat):
    import SurfaceTopography as st
    from scipy import stats

    z = np.load(path)
    n = z.shape[0]
    # SurfaceTopography indexes heights as [x, y]; hdi's rows are y, so pass the transpose
    # (a view; values and statistics are the same, only the axis names swap).
    raw = st.Topography(z.T, physical_sizes=(size_m, size_m * z.shape[0] / z.shape[1]))
    calls = {}

    def rec(name, fn):
        t, c, v = best_of(repeat, fn)
        calls[name] = {"seconds": t, "cpu_seconds": c, "value": None if v is None else float(v)}
        return v

    topo = None

    def level():
        # SurfaceTopography pipelines are lazy: materialise the detrended heights once, so every
        # later call times only its own work (as hdi levels once, then measures).
        nonlocal topo
        topo = st.Topography(raw.detrend("height").heights(), physical_sizes=raw.physical_sizes)
        return None

    rec("detrend_height", level)
    rec("rms_height_from_area", lambda: topo.rms_height_from_area())
    h = topo.heights()
    rec("mean_abs_height", lambda: np.abs(h - h.mean()).mean())
    rec("skewness", lambda: stats.skew(h, axis=None))
    rec("kurtosis", lambda: stats.kurtosis(h, axis=None, fisher=False))
    rec("rms_gradient", lambda: topo.rms_gradient())
    rec("rms_laplacian", lambda: topo.rms_laplacian())
    rec("rms_slope_from_profile", lambda: topo.rms_slope_from_profile())
    rec("rms_curvature_from_profile", lambda: topo.rms_curvature_from_profile())
    dx = size_m / z.shape[1]
    found = {}

    def summits():
        found["s"] = summits_9pt(h, dx)
        return found["s"][0]

    n_summits = rec("summits_9pt_numpy", summits)
    _, radius, n_candidates = found["s"]
    calls["summit_radius_m"] = {"seconds": 0.0, "cpu_seconds": 0.0, "value": float(radius)}
    calls["eta_per_m2"] = {
        "seconds": 0.0,
        "cpu_seconds": 0.0,
        "value": n_summits / (n_candidates * dx * dx),
    }
    total = sum(c["seconds"] for c in calls.values())
    total_cpu = sum(c["cpu_seconds"] for c in calls.values())
    return {
        "file": str(path),
        "n": [int(z.shape[0]), int(z.shape[1])],
        "size_m": size_m,
        "repeat": repeat,
        "calls": calls,
        "total_seconds": total,
        "total_cpu_seconds": total_cpu,
        "surfacetopography_version": st.__version__,
        "numpy_version": np.__version__,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("file", nargs="?")
    ap.add_argument("--size-m", type=float, default=4e-6, help="side length along x (m)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--write-synthetic", nargs=2, metavar=("N", "PREFIX"))
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    if a.write_synthetic:
        n, prefix = a.write_synthetic
        write_synthetic(int(n), prefix, a.seed, a.size_m)
        return 0
    if not a.file:
        ap.error("give FILE.npy or --write-synthetic N PREFIX")
    out = measure(a.file, a.size_m, a.repeat)
    if a.json:
        print(json.dumps(out))
    else:
        for name, c in out["calls"].items():
            print(f"{name:28s} {c['seconds']:9.4f} s  cpu {c['cpu_seconds']:9.4f} s   {c['value']}")
        print(f"{'total':28s} {out['total_seconds']:9.4f} s  cpu {out['total_cpu_seconds']:9.4f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
