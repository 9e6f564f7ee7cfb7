#!/usr/bin/env python3
"""Times the numpy / PyWavelets side of benches/analysis.rs on the same cases:

- Hann amplitude spectrum of 10**7 samples (np.fft.fft as the Rust side does, and np.fft.rfft);
- pywt.cwt of 10**6 samples at 100 scales, cmor1.5-1.0, method='fft' (the frequencies of the
  Rust bench, 5 kHz–1 MHz log-spaced at fs = 4 MHz, scales C*fs/f).

Prints seconds (best of `--repeat`). Usage: /tmp/sp/bin/python bench/analysis_numpy.py [--repeat N]
"""
import argparse
import time

import numpy as np
import pywt

FS = 4e6


def series(n):
    t = np.arange(n) / FS
    total = n / FS
    return np.cos(2 * np.pi * (10e3 * t + 0.5 * 490e3 / total * t**2)) + 0.3 * np.sin(
        2 * np.pi * 275e3 * t
    )


def best(f, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def amplitude_spectrum(x, transform):
    n = x.size
    w = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / n)
    X = transform((x - x.mean()) * w)
    a = 2 * np.abs(X[: n // 2 + 1]) / w.sum()
    a[0] /= 2
    return a


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    print(f"numpy {np.__version__}, PyWavelets {pywt.__version__}")
    x7 = series(10_000_000)
    t = best(lambda: amplitude_spectrum(x7, np.fft.fft), args.repeat)
    print(f"amplitude spectrum 1e7 samples, np.fft.fft : {t:.3f} s")
    t = best(lambda: amplitude_spectrum(x7, np.fft.rfft), args.repeat)
    print(f"amplitude spectrum 1e7 samples, np.fft.rfft: {t:.3f} s")
    x6 = series(1_000_000)
    freqs = np.geomspace(5e3, 1e6, 100)
    scales = 1.0 * FS / freqs
    t = best(
        lambda: pywt.cwt(x6 - x6.mean(), scales, "cmor1.5-1.0", sampling_period=1 / FS, method="fft"),
        args.repeat,
    )
    print(f"pywt.cwt 1e6 samples x 100 scales (cmor1.5-1.0, fft): {t:.3f} s")


if __name__ == "__main__":
    main()
