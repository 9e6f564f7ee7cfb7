#!/usr/bin/env python3
"""Reference CWT of a linear chirp with PyWavelets, for src/analysis/tests.rs.

Writes tests/data/cwt_linear_chirp_pywt.json: the chirp's parameters, the frequencies and
PyWavelets scales, and the complex coefficients of
    pywt.cwt(x - x.mean(), scales, 'cmor1.5-1.0', sampling_period=1/fs, method='fft',
             precision=18)
at every `stride`-th sample. The Rust test regenerates the same chirp and compares
`cwt_morlet_complex` with `Wavelet::Cmor{1.5, 1.0}` and `Normalization::Pywt { precision: Some(18) }`.

Run once (PyWavelets + numpy): /tmp/sp/bin/python bench/pywt_reference.py
"""
import json
import pathlib

import numpy as np
import pywt

FS = 4e6  # Hz
N = 4000  # samples (1 ms)
F0, F1 = 20e3, 400e3  # Hz, linear sweep over the record
AMPLITUDE = 1.0
WAVELET = "cmor1.5-1.0"
CENTER = 1.0
FREQUENCIES = np.geomspace(30e3, 350e3, 8)  # Hz
STRIDE = 25
# PyWavelets tabulates the integrated wavelet on 2**precision points; at its default 12 that
# table's coarseness alone moves |W| by up to ~5 % here, at 18 its result has converged.
PRECISION = 18

t = np.arange(N) / FS
T = N / FS
x = AMPLITUDE * np.cos(2 * np.pi * (F0 * t + 0.5 * (F1 - F0) / T * t**2))
x = x - x.mean()
scales = CENTER * FS / FREQUENCIES  # PyWavelets scale in samples
coef, freqs = pywt.cwt(x, scales, WAVELET, sampling_period=1 / FS, method="fft", precision=PRECISION)
idx = np.arange(0, N, STRIDE)
out = {
    "generator": "bench/pywt_reference.py",
    "pywt_version": pywt.__version__,
    "wavelet": WAVELET,
    "precision": PRECISION,
    "signal": {
        "kind": "linear chirp A*cos(2*pi*(f0*t + (f1-f0)/(2*T)*t^2)), t = n/fs, mean removed",
        "fs_hz": FS,
        "n": N,
        "f0_hz": F0,
        "f1_hz": F1,
        "amplitude": AMPLITUDE,
    },
    "frequencies_hz": FREQUENCIES.tolist(),
    "pywt_frequencies_hz": freqs.tolist(),
    "scales_samples": scales.tolist(),
    "time_index": idx.tolist(),
    "re": [[float(f"{v:.12e}") for v in row] for row in coef[:, idx].real],
    "im": [[float(f"{v:.12e}") for v in row] for row in coef[:, idx].imag],
}
path = pathlib.Path(__file__).resolve().parent.parent / "tests/data/cwt_linear_chirp_pywt.json"
path.write_text(json.dumps(out, indent=1) + "\n")
print(f"wrote {path} ({path.stat().st_size} bytes), |W| max {np.abs(coef).max():.4f}")
