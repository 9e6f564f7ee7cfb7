#!/usr/bin/env python3
"""hdi against its Python anchors, side by side, in one run (bench/README.md).

    python bench/compare.py --hdi target/release/hdi [--repeat 3] [--only cwt,fft,...] [--json]

Usually started by bench/compare.sh, which makes the venv and builds hdi first. Writes the same
inputs for both sides into a temp dir (numpy .npy: a 10⁶-sample and a 10⁷-sample signal at
4 MS/s, a 1024² height map), then for each figure runs hdi and its anchor alternately,
`--repeat` rounds, and keeps the best of each side:

  figure      hdi                                        anchor
  ----------  -----------------------------------------  ------------------------------------------
  cwt         hdi bench --only cwt --input sig6.npy      pywt.cwt(x - mean, 100 scales 5 kHz–1 MHz,
              (analytic Morlet ω0 = 6, f32 |W|)          'cmor1.5-1.0', method='fft')
  fft         hdi bench --only fft --input sig7.npy      Hann amplitude spectrum with numpy rfft
  roughness   hdi bench --only roughness --input map.npy bench/roughness_surfacetopography.py
              (plane level + roughness)                  map.npy --json (total_seconds)
  two-dof     hdi bench --only two-dof (8.5 / 12 nm,     bench/two_dof_scipy.py --synthetic-dmw
              2 ms, synthetic DMW)                       --init static --max-step inf (RK45)
  bem         hdi bench --only bem --input map.npy       tamaas PolonskyKeerRey, same map, E* = 1,
              (one periodic load step, tolerance 1e-10;  p̄ = 0.05·h′_rms, tolerance 1e-10, cold
              the non-periodic 2n² padded step too)      start (needs `pip install tamaas`)

hdi's figures are timed inside the hdi process after a warm-up run (`--repeat 1`: one warm-up,
one timed run per round), so start-up and reading the .npy are excluded on both sides. Ratio =
anchor / hdi (> 1: hdi faster). Prints one table: figure, hdi, anchor, ratio, goal.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
FS = 4e6
GROUPS = ["two-dof", "cwt", "fft", "roughness", "bem"]


def series(n):
    """The chirp 10 kHz → 500 kHz plus a 275 kHz line of hdi bench / benches/analysis.rs."""
    t = np.arange(n) / FS
    total = n / FS
    return np.cos(2 * np.pi * (10e3 * t + 0.5 * 490e3 / total * t**2)) + 0.3 * np.sin(
        2 * np.pi * 275e3 * t
    )


def gaussian_map(n, seed=7, size_m=4e-6, sigma=0.5e-9, corr=40e-9):
    """A Gaussian-ACF height map (σ 0.5 nm, correlation length 40 nm over 4 µm), metres."""
    rng = np.random.default_rng(seed)
    d = size_m / n
    kx = 2 * np.pi * np.fft.rfftfreq(n, d)
    ky = 2 * np.pi * np.fft.fftfreq(n, d)
    spec = np.fft.rfft2(rng.standard_normal((n, n)))
    spec *= np.exp(-(kx[None, :] ** 2 + ky[:, None] ** 2) * corr**2 / 8.0)
    z = np.fft.irfft2(spec, s=(n, n))
    return z * (sigma / z.std())


def hdi_figures(hdi, args):
    """`hdi bench ARGS --json --repeat 1`: {name: figure}."""
    out = subprocess.run(
        [hdi, "bench", *args, "--json", "--repeat", "1"],
        check=True,
        capture_output=True,
        text=True,
    )
    return {f["name"]: f for f in json.loads(out.stdout)["figures"]}


def numpy_spectrum(x):
    n = x.size
    w = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / n)
    X = np.fft.rfft((x - x.mean()) * w)
    a = 2 * np.abs(X) / w.sum()
    a[0] /= 2
    return a


def say(msg):
    """Progress on stderr: the table comes at the end, a round can take a minute."""
    print(msg, file=sys.stderr, flush=True)


def timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def row(figure, hdi_v, anchor_v, unit, goal, note=""):
    ratio = anchor_v / hdi_v if (anchor_v and hdi_v) else None
    return dict(figure=figure, hdi=hdi_v, anchor=anchor_v, unit=unit, ratio=ratio, goal=goal, note=note)


def bem_load(h, dx):
    """p̄ = 0.05·E*·h′_rms with E* = 1 and periodic forward differences (hdi bench's load)."""
    gx = (np.roll(h, -1, axis=1) - h) / dx
    gy = (np.roll(h, -1, axis=0) - h) / dx
    return 0.05 * math.sqrt(float(np.mean(gx**2 + gy**2)))


def bem_rows(hdi, mp, n, size):
    """One periodic load step: hdi's and tamaas's, alternating, best of n; hdi's padded step."""
    try:
        import tamaas as tm
    except ImportError:
        return [row(f"BEM load step {size}²", None, None, "s", "≥ 1×", "anchor missing: pip install tamaas")]
    h = np.ascontiguousarray(np.load(mp), dtype=np.float64)
    side = 4e-6  # hdi bench reads map.npy as a 4 µm square
    load = bem_load(h, side / h.shape[0])
    tm.set_log_level(tm.LogLevel.error)
    bh, ba, bp, fig, its = math.inf, math.inf, math.inf, None, None
    for k in range(n):
        say(f"bem round {k + 1}/{n}")
        f = hdi_figures(hdi, ["--only", "bem", "--input", mp])
        if f["bem_periodic_load_step"]["value"] < bh:
            bh, fig = f["bem_periodic_load_step"]["value"], f
        bp = min(bp, f["bem_non_periodic_load_step"]["value"])
        model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [side, side], list(h.shape))
        model.E, model.nu = 1.0, 0.0
        solver = tm.PolonskyKeerRey(model, h, 1e-10)
        ba = min(ba, timed(lambda: solver.solve(load)))
        area = float((np.array(model.traction) > 0).mean())
    d = fig["bem_periodic_load_step"]["details"]
    hdi_area = fig["bem_periodic_load_step"]["label"].rsplit("= ", 1)[-1].rstrip(")")
    dp = fig["bem_non_periodic_load_step"]["details"]
    threads = os.environ.get("OMP_NUM_THREADS", "default")
    return [
        row(f"BEM load step {size}² periodic", bh, ba, "s", "≥ 1×",
            f"hdi {d['iterations']} iterations, {d['memory_bytes'] / 2**20:.0f} MiB, A_r/A_0 = "
            f"{hdi_area}; tamaas {tm.__version__} A_r/A_0 = {area:.4f} "
            f"(OMP_NUM_THREADS {threads})"),
        row(f"BEM load step {size}² non-periodic", bp, None, "s", "-",
            f"padded {2 * size}², {dp['iterations']} iterations, "
            f"{dp['memory_bytes'] / 2**20:.0f} MiB"),
    ]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hdi", required=True, help="the hdi binary (a release build)")
    ap.add_argument("--repeat", type=int, default=3, help="alternating rounds (best of N)")
    ap.add_argument("--only", default=",".join(GROUPS), help="comma-separated: " + ",".join(GROUPS))
    ap.add_argument("--map-size", type=int, default=1024)
    ap.add_argument("--json", action="store_true", help="print the rows as JSON too")
    a = ap.parse_args()
    only = [g for g in a.only.split(",") if g]
    for g in only:
        if g not in GROUPS:
            ap.error(f"unknown group {g!r} (groups: {', '.join(GROUPS)})")
    n = max(1, a.repeat)
    py = sys.executable
    rows = []
    with tempfile.TemporaryDirectory(prefix="hdi-compare-") as tmp:
        sig6, sig7, mp = (os.path.join(tmp, f) for f in ("sig6.npy", "sig7.npy", "map.npy"))
        if "cwt" in only:
            np.save(sig6, series(1_000_000))
        if "fft" in only:
            np.save(sig7, series(10_000_000))
        if "roughness" in only or "bem" in only:
            np.save(mp, gaussian_map(a.map_size))

        if "two-dof" in only:
            best_h = {}
            best_s = {}
            for k in range(n):
                say(f"two-dof round {k + 1}/{n}")
                f = hdi_figures(a.hdi, ["--only", "two-dof"])
                for h in ("8.5", "12"):
                    fig = f[f"two_dof_{h}nm_us_per_step"]
                    prev = best_h.get(h)
                    if prev is None or fig["details"]["case_ms"] < prev["details"]["case_ms"]:
                        best_h[h] = fig
                for h in ("8.5", "12"):
                    o = subprocess.run(
                        [py, os.path.join(HERE, "two_dof_scipy.py"), "--actuation", h,
                         "--synthetic-dmw", "--init", "static", "--max-step", "inf", "--json"],
                        check=True, capture_output=True, text=True,
                    )
                    r = json.loads(o.stdout)
                    r = r["cases"][0] if isinstance(r, dict) and "cases" in r else (r[0] if isinstance(r, list) else r)
                    best_s[h] = min(best_s.get(h, math.inf), r["wall_s"] * 1e3)
            for h in ("8.5", "12"):
                fig = best_h[h]
                d = fig["details"]
                rows.append(row(
                    f"2-DOF {h} nm, one 2 ms case", d["case_ms"], best_s[h], "ms",
                    "≤ 1.5 µs/step",
                    f"hdi {fig['value']:.2f} µs/step, {d['accepted_steps']} steps, "
                    f"{d['rhs_evaluations']} RHS; scipy RK45 on its own synthetic DMW",
                ))

        if "cwt" in only:
            import pywt

            x = np.load(sig6)
            freqs = np.geomspace(5e3, 1e6, 100)
            scales = 1.0 * FS / freqs
            bh, ba = math.inf, math.inf
            for k in range(n):
                say(f"cwt round {k + 1}/{n}")
                f = hdi_figures(a.hdi, ["--only", "cwt", "--input", sig6])
                bh = min(bh, f["cwt_morlet_100_frequencies"]["value"])
                ba = min(ba, timed(lambda: pywt.cwt(
                    x - x.mean(), scales, "cmor1.5-1.0", sampling_period=1 / FS, method="fft")))
            rows.append(row("CWT 10⁶ × 100 (5 kHz–1 MHz)", bh, ba, "s", "≥ 10×",
                            f"PyWavelets {pywt.__version__} cwt(method='fft')"))

        if "fft" in only:
            x = np.load(sig7)
            bh, ba = math.inf, math.inf
            for k in range(n):
                say(f"fft round {k + 1}/{n}")
                f = hdi_figures(a.hdi, ["--only", "fft", "--input", sig7])
                bh = min(bh, f["hann_amplitude_spectrum"]["value"])
                ba = min(ba, timed(lambda: numpy_spectrum(x)))
            rows.append(row("Hann spectrum 10⁷ samples", bh, ba, "s", "≥ 1×",
                            f"numpy {np.__version__} rfft"))

        if "roughness" in only:
            script = os.path.join(HERE, "roughness_surfacetopography.py")
            bh, ba = math.inf, math.inf
            note = "SurfaceTopography (bench/roughness_surfacetopography.py)"
            for k in range(n):
                say(f"roughness round {k + 1}/{n}")
                f = hdi_figures(a.hdi, ["--only", "roughness", "--input", mp])
                bh = min(bh, f["roughness_default"]["value"])
                if not os.path.exists(script):
                    note = "anchor missing: bench/roughness_surfacetopography.py not found"
                    continue
                o = subprocess.run([py, script, mp, "--json", "--repeat", "1"],
                                   capture_output=True, text=True)
                try:
                    ba = min(ba, float(json.loads(o.stdout)["total_seconds"]))
                except (ValueError, KeyError, TypeError):
                    note = "anchor failed: " + (o.stderr.strip().splitlines() or ["no output"])[-1]
            rows.append(row(f"roughness {a.map_size}²", bh, ba if ba < math.inf else None,
                            "s", "≥ 5×", note))

        if "bem" in only:
            rows.extend(bem_rows(a.hdi, mp, n, a.map_size))

    print(f"{'figure':<30} {'hdi':>10} {'anchor':>10} {'unit':<5} {'ratio':>7}  {'goal':<14} note")
    for r in rows:
        fmt = lambda v: f"{v:10.4g}" if v is not None else f"{'n/a':>10}"
        ratio = f"{r['ratio']:6.2f}×" if r["ratio"] is not None else f"{'n/a':>7}"
        print(f"{r['figure']:<30} {fmt(r['hdi'])} {fmt(r['anchor'])} {r['unit']:<5} {ratio}  "
              f"{r['goal']:<14} {r['note']}")
    print(f"(best of {n} alternating rounds; ratio = anchor / hdi, > 1 means hdi is faster; "
          f"hdi {os.path.abspath(a.hdi)}, Python {sys.version.split()[0]})")
    if a.json:
        print(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
