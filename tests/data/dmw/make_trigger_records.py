"""Synthetic LDV records with difficult once-per-revolution index pulses, and the DMW std of
an independent numpy/scipy chain over whole revolutions (docs/dmw.md, "The chain").

Writes, beside this script:
  narrow_pulse.h5    10 µs active-high TTL pulse (0.09 % duty cycle) at 5 425 rpm
  inverted_bounce.h5 active-low pulse whose edges bounce, with noise on the index channel
  reference.json     the reference DMW std and the record's parameters

Both records carry the same decoder voltage (int16 counts with `scale`/`offset`); only the index
channel differs. Run once with numpy, scipy and h5py; the tests read the files, not this script.
"""
import json
import pathlib

import h5py
import numpy as np
from scipy import integrate, signal

HERE = pathlib.Path(__file__).parent
FS = 1.0e6  # S/s
P = 11060  # samples per revolution: 60·FS/P = 5 424.95 rpm (§2.1.2: 5 425 rpm)
N_REV = 8  # whole revolutions averaged by the reference
S0 = 1000  # sample of the first index edge
SENS = 0.025  # m/s per V (§2.1.2)
SEGMENT = 2500  # 2.5 ms after each trigger (hdi's default `segment`)
FC = 10e3  # high-pass cutoff (hdi's default)
N = S0 + N_REV * P + 3000  # the 9th trigger's 2.5 ms segment also fits

rng = np.random.default_rng(20261125)
t = np.arange(N) / FS
frot = FS / P
# Repeatable topography: lines at harmonics of the rotation frequency (m), and one
# non-repeating (NRRO) tone that averaging must suppress.
lines = [(118, 1.5e-9, 0.3), (553, 0.4e-9, 1.1), (1327, 0.15e-9, 2.0), (3040, 0.05e-9, 0.7)]
v = np.zeros(N)
for h, a, ph in lines:
    w = 2 * np.pi * h * frot
    v += a * w * np.cos(w * (t - S0 / FS) + ph)
w_nrro = 2 * np.pi * 37.3e3
v += 0.3e-9 * w_nrro * np.cos(w_nrro * t)
u = v / SENS + 0.012 + 2e-3 * rng.standard_normal(N)  # decoder voltage, V
U_SCALE, U_OFF = 2e-5, 0.0
counts = np.round((u - U_OFF) / U_SCALE).astype(np.int16)
u_q = counts.astype(np.float64) * U_SCALE + U_OFF  # what a reader of the file sees

starts = S0 + P * np.arange(N_REV + 1)


def narrow_index():
    x = np.zeros(N)
    for s in starts:
        x[s] = 2.5  # edge sample at mid-level: the crossing is exactly at sample s
        x[s + 1 : s + 10] = 5.0  # 10 µs pulse
    return x


def inverted_bouncing_index():
    x = np.full(N, 5.0) + 0.03 * rng.standard_normal(N)
    for s in starts:
        x[s] = 2.5
        x[s + 1 : s + 40] = 0.0 + 0.03 * rng.standard_normal(39)  # 40 µs low pulse
        x[s + 3 : s + 5] = 4.8  # contact bounce on the falling edge
        x[s + 40 : s + 42] = 0.2  # and on the rising edge
        x[s + 43] = 0.1
    return x


def write(name, index):
    i_scale = 1e-3
    ic = np.round(index / i_scale).astype(np.int16)
    with h5py.File(HERE / name, "w") as f:
        g = f.create_group("ldv")
        g.attrs["sampling_rate"] = FS
        d = g.create_dataset("velocity", data=counts)
        d.attrs["units"] = "V"
        d.attrs["scale"] = U_SCALE
        d.attrs["offset"] = U_OFF
        d = g.create_dataset("index", data=ic)
        d.attrs["units"] = "V"
        d.attrs["scale"] = i_scale
        d.attrs["offset"] = 0.0


write("narrow_pulse.h5", narrow_index())
write("inverted_bounce.h5", inverted_bouncing_index())

# Reference chain: average whole revolutions at the known starts, keep the first 2.5 ms,
# scale, remove the offset, zero-phase 4th-order Butterworth high-pass (padding 3·fs/fc),
# trapezoid integration, least-squares line removed, 3/fc excluded at each end.
avg = np.mean([u_q[s : s + P] for s in starts[:N_REV]], axis=0)[:SEGMENT]
vel = avg * SENS
vel -= vel.mean()
sos = signal.butter(4, FC, "highpass", fs=FS, output="sos")
pad = int(round(3 * FS / FC))
vf = signal.sosfiltfilt(sos, vel, padlen=min(pad, SEGMENT - 1))
d = integrate.cumulative_trapezoid(vf, dx=1 / FS, initial=0.0)
d = signal.detrend(d, type="linear")
edge = int(round(3 * FS / FC))
inner = d[edge : SEGMENT - edge]
ref = {
    "sample_rate_Hz": FS,
    "samples_per_revolution": P,
    "rpm": 60 * FS / P,
    "revolutions_averaged": N_REV,
    "first_trigger_s": S0 / FS,
    "sensitivity_m_s_per_V": SENS,
    "segment_samples": SEGMENT,
    "highpass_Hz": FC,
    "edge_samples": edge,
    "dmw_std_m": float(np.std(inner)),
    "velocity_std_m_s": float(np.std(vf[edge : SEGMENT - edge])),
    "numpy": np.__version__,
    "scipy": __import__("scipy").__version__,
    "h5py": h5py.__version__,
}
(HERE / "reference.json").write_text(json.dumps(ref, indent=2) + "\n")
print(json.dumps(ref, indent=2))
