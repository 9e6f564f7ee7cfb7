#!/usr/bin/env python3
"""hdi against its Python anchors, side by side, in one run (bench/README.md).

    python bench/compare.py --hdi target/release/hdi [--repeat 3] [--only cwt,fft,...] [--json]
                            [--fcwt-wisdom DIR]

Usually started by bench/compare.sh, which makes the venv and builds hdi first. Writes the same
inputs for both sides into a temp dir (numpy .npy: a 10⁶-sample and a 10⁷-sample signal at
4 MS/s, a 1024² height map), then for each figure runs hdi and its anchor alternately,
`--repeat` rounds, and keeps the best of each side:

  figure      hdi                                        anchor
  ----------  -----------------------------------------  ------------------------------------------
  cwt         hdi bench --only cwt --input sig6.npy      pywt.cwt(x - mean, 100 scales 5 kHz–1 MHz,
              (analytic Morlet ω0 = 6, f32 |W|)          'cmor1.5-1.0', method='fft'); fCWT (Arts &
                                                         van den Broek 2022) Morlet(3/π), same grid,
                                                         all cores, with and without FFTW wisdom
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

fCWT (bench/requirements.txt says how to install it) gets one untimed warm-up whose |W| is
checked against `hdi analyze --out`'s scalogram of the same series, then its FFTW_MEASURE wisdom
is made (timed apart, not in the figure; `--fcwt-wisdom DIR` keeps and reuses it); each round
then times it without wisdom (`estimate`) and with (`wisdom`). Its figure is the transform as
fCWT delivers it (complex64), |W| not taken; hdi's includes |W|.
"""
import argparse
import contextlib
import ctypes
import json
import math
import os
import shutil
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


# fCWT's Morlet (fcwt.cpp, Morlet::generate, frequency domain) is
# √(2π)·π^(-1/4)·exp(−fb²(sω − 2π)²/2) at scale s (samples), tuned to f = fs/s; hdi's is
# exp(−(sω − ω0)²/2) tuned to f = ω0/(2πs) (docs/analysis.md "CWT"). Over ν = f_signal/f_tuned
# they read exp(−(2π·fb)²(ν − 1)²/2) and exp(−ω0²(ν − 1)²/2): fb = ω0/(2π) = 3/π gives the same
# wavelet exactly (same σ), not an approximation. fCWT's default fb = 2 would be ω0 ≈ 12.6.
FCWT_BANDWIDTH = 6.0 / (2 * math.pi)
# A real tone A·cos reads |W| = A·(that peak)/2 in fCWT (analytic half, normalised inverse FFT),
# |W| = A in hdi's L1 scalogram: the expected ratio of the two magnitudes, not a fitted one.
FCWT_L1_RATIO = math.sqrt(2 * math.pi) * math.pi**-0.25 / 2


@contextlib.contextmanager
def c_stdout_to_stderr(cwd):
    """fCWT prints progress and warnings with std::cout and reads/writes its wisdom files
    (n<N>_t<threads>.wis) in the working directory: keep both out of the table and of the
    caller's directory. Yields a list that receives what it printed (also echoed to stderr)."""
    sys.stdout.flush()
    libc = ctypes.CDLL(None)
    saved, here = os.dup(1), os.getcwd()
    printed = []
    with tempfile.TemporaryFile() as cap:
        os.dup2(cap.fileno(), 1)
        os.chdir(cwd)
        try:
            yield printed
        finally:
            libc.fflush(None)
            os.chdir(here)
            os.dup2(saved, 1)
            os.close(saved)
            cap.seek(0)
            printed.append(cap.read().decode(errors="replace"))
            sys.stderr.write(printed[0])


class Fcwt:
    """fCWT on the cwt group's grid: 100 log-spaced frequencies 5 kHz–1 MHz at FS, Morlet with
    hdi's σ, `threads` threads (OpenMP for the per-scale products if the extension was built with
    it, FFTW's threads for the transforms). Two modes, alternated in every round:
    `estimate` (no wisdom: FFTW_ESTIMATE plans, fCWT's default) and `wisdom` (fCWT's
    optimisation plan: FFTW_MEASURE wisdom made once by `plan()`, timed apart, read back from its
    file inside every timed call, as fCWT does)."""

    def __init__(self, wdir, threads):
        import fcwt
        from importlib.metadata import version

        self.fcwt, self.wdir, self.threads = fcwt, wdir, threads
        self.version = version("fCWT")
        self.wavelet = fcwt.Morlet(FCWT_BANDWIDTH)
        # FCWT_LOGSCALES: scales fs/f_max … fs/f_min geometric (float32), f = fs/scale: hdi's
        # log grid to < 1e-6; rows come out high → low frequency.
        self.scales = fcwt.Scales(self.wavelet, fcwt.FCWT_LOGSCALES, int(FS), 5e3, 1e6, 100)
        self.modes = {m: fcwt.FCWT(self.wavelet, threads, m == "wisdom", True)
                      for m in ("estimate", "wisdom")}
        so = fcwt._fcwt.__file__
        with open(so, "rb") as f:
            # The sdist's setup.py compiles without -fopenmp on Linux: then only FFTW's own
            # transforms are threaded (bench/requirements.txt says how to build it with OpenMP).
            self.openmp = b"GOMP_parallel" in f.read()
        self.fftw = ctypes.CDLL("libfftw3f.so.3")  # the instance _fcwt loaded (same soname)
        self.fftw_version = (ctypes.c_char * 64).in_dll(self.fftw, "fftwf_version").value.decode()
        self.plan_seconds = None
        self.started = False
        self.wisdom_missed = False

    def plan(self):
        """fCWT's create_FFT_optimization_plan(2²⁰, FFTW_MEASURE), its default method: wisdom
        for 2¹¹ … 2²⁰ points (10⁶ samples pad to 2²⁰), unless `wdir` already holds it."""
        if os.path.exists(os.path.join(self.wdir, f"n{1 << 20}_t{self.threads}.wis")):
            return False
        with c_stdout_to_stderr(self.wdir):
            self.plan_seconds = timed(lambda: self.modes["wisdom"].create_FFT_optimization_plan(
                1 << 20, "FFTW_MEASURE"))
        self.started = True
        return True

    def run(self, x, mode):
        """One transform as a caller gets it: mean removed, float32 input, a fresh complex64
        output (|W| not taken). `estimate` first forgets the wisdom FFTW keeps in memory (FFTW
        keeps wisdom process-wide: an ESTIMATE plan would use it). Not before the first call:
        forgetting before fCWT has started FFTW's threads makes every later import of threaded
        wisdom fail (measured with FFTW 3.3.10)."""
        if mode == "estimate" and self.started:
            self.fftw.fftwf_forget_wisdom()
        with c_stdout_to_stderr(self.wdir) as printed:
            xs = (x - x.mean()).astype(np.float32)
            out = np.zeros((100, x.size), dtype=np.complex64)
            self.modes[mode].cwt(xs, self.scales, out)
        if mode == "wisdom" and "WARNING" in printed[0]:
            self.wisdom_missed = True  # fCWT fell back to ESTIMATE plans: say so in the row
        self.started = True
        return out


def fcwt_agreement(hdi, sig, tmp, wf):
    """fCWT's |W| (rows high → low) beside hdi's own scalogram of the same series
    (`hdi analyze --out`: analysis.h5, L1, Morlet ω0 = 6): the per-row magnitude ratio against
    FCWT_L1_RATIO, the largest deviation and how often the ridge (row of max |W|) is the same."""
    import h5py

    out = os.path.join(tmp, "analyze")
    subprocess.run([hdi, "analyze", sig, "--sample-rate", f"{FS / 1e6:g} MHz", "--f-min", "5 kHz",
                    "--f-max", "1 MHz", "--frequencies", "100", "--out", out],
                   check=True, capture_output=True)
    with h5py.File(os.path.join(out, "analysis.h5"), "r") as f:
        g = f["analysis/scalogram"]
        if (g.attrs["wavelet"], g.attrs["normalization"]) != ("morlet6", "L1"):
            return f"hdi analyze wrote {g.attrs['wavelet']}/{g.attrs['normalization']}, not morlet6/L1"
        wh = g["magnitude"][...]
    shutil.rmtree(out)
    wf = wf[::-1]
    ratio = []
    for j in range(wh.shape[0]):
        f, h = wf[j].astype(np.float64), wh[j].astype(np.float64)  # f32 sums of 10⁶ terms drift
        ratio.append(np.dot(f, h) / np.dot(h, h))
    ratio = np.array(ratio)
    dev = max(float(np.abs(wf[j] / FCWT_L1_RATIO - wh[j]).max()) for j in range(wh.shape[0]))
    same = float((wf.argmax(axis=0) == wh.argmax(axis=0)).mean())
    return (f"|W| vs hdi analyze: ratio {ratio.min():.5f}–{ratio.max():.5f} per row "
            f"(expected {FCWT_L1_RATIO:.5f}), max |Δ| {dev / float(wh.max()):.1e} of max |W|, "
            f"ridge row same at {100 * same:.4f} % of samples")


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
    ap.add_argument("--fcwt-wisdom", metavar="DIR",
                    help="keep fCWT's FFTW wisdom here and reuse it (default: made anew in the temp "
                         "dir; FFTW_MEASURE for 2²⁰ points takes ~40 s idle, minutes under load)")
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
            # hdi's rayon pool takes every core it may run on; fCWT gets as many threads.
            threads = len(os.sched_getaffinity(0))
            fc, fc_note = None, ""
            try:
                wdir = a.fcwt_wisdom or tmp
                os.makedirs(wdir, exist_ok=True)
                fc = Fcwt(wdir, threads)
            except (ImportError, OSError) as e:
                fc_note = f"anchor missing ({e}): fCWT, see bench/requirements.txt"
            if fc is not None:
                # Untimed warm-up (as hdi bench warms up): the first call also starts the thread
                # pools; its output is the agreement check, made before any wisdom exists.
                say("cwt: fCWT warm-up and agreement with hdi analyze")
                w = fc.run(x, "estimate")
                wf = np.abs(w)
                del w
                try:
                    agree = fcwt_agreement(a.hdi, sig6, tmp, wf)
                except (ImportError, OSError, subprocess.CalledProcessError, KeyError) as e:
                    agree = f"agreement not checked: {e}"
                del wf
                say("cwt: fCWT plan (FFTW_MEASURE wisdom)")
                if fc.plan():
                    wisdom = f"FFTW_MEASURE wisdom made once in {fc.plan_seconds:.1f} s, not in the figure"
                else:
                    wisdom = f"FFTW_MEASURE wisdom reused from {os.path.abspath(wdir)}"
            bh, ba = math.inf, math.inf
            bf = {"estimate": math.inf, "wisdom": math.inf}
            babs = math.inf
            for k in range(n):
                say(f"cwt round {k + 1}/{n}")
                f = hdi_figures(a.hdi, ["--only", "cwt", "--input", sig6])
                bh = min(bh, f["cwt_morlet_100_frequencies"]["value"])
                ba = min(ba, timed(lambda: pywt.cwt(
                    x - x.mean(), scales, "cmor1.5-1.0", sampling_period=1 / FS, method="fft")))
                if fc is not None:
                    for m in bf:
                        t = time.perf_counter()
                        out = fc.run(x, m)
                        bf[m] = min(bf[m], time.perf_counter() - t)
                        if m == "wisdom":
                            # What hdi's figure also does: |W| as float32 (numpy, one thread).
                            babs = min(babs, timed(lambda: np.abs(out)))
                        del out
            rows.append(row("CWT 10⁶ × 100 (5 kHz–1 MHz)", bh, ba, "s", "≥ 10×",
                            f"PyWavelets {pywt.__version__} cwt(method='fft'), 1 thread"))
            if fc is None:
                rows.append(row("CWT 10⁶ × 100, fCWT", bh, None, "s", "≥ 1×", fc_note))
            else:
                build = (f"fCWT {fc.version} ({'OpenMP build' if fc.openmp else 'built without OpenMP'}"
                         f", {fc.fftw_version}), Morlet(3/π), {threads} threads, complex64 out")
                rows.append(row("CWT 10⁶ × 100, fCWT wisdom", bh, bf["wisdom"], "s", "≥ 1×",
                                f"{build}; {wisdom}; |W| by np.abs would add {babs:.3f} s"
                                + ("; WISDOM NOT LOADED in some round (fCWT warned)"
                                   if fc.wisdom_missed else "")))
                rows.append(row("CWT 10⁶ × 100, fCWT estimate", bh, bf["estimate"], "s", "≥ 1×",
                                f"{build}; no wisdom (FFTW_ESTIMATE); {agree}"))

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
