"""Full-precision roughness numbers of the canonical surface, computed with numpy alone.

An independent implementation of the definitions in docs/surfaces.md (Nayak's profile
moments by periodic finite differences and by the FFT; Greenwood's discrete 9-point summits
with the 4-direction curvature) on gaussian_acf_256_seed12345.txt, written to
canonical_roughness_numpy.json. hdi's `canonical_full_precision_reference` test compares its
Rust results with these values. Run once: python3 make_canonical_roughness_reference.py
"""
import json
import pathlib

import numpy as np

here = pathlib.Path(__file__).parent
z = np.loadtxt(here / "gaussian_acf_256_seed12345.txt", comments="#")
assert z.shape == (256, 256)
h = 1e-6 / 256  # dx = dy (1 µm over 256 pixels)
z = z - z.mean()
roll = np.roll  # periodic map: every pixel has all its neighbours

# Finite-difference moments: forward first differences, central second differences.
gx = (roll(z, -1, axis=1) - z) / h
gy = (roll(z, -1, axis=0) - z) / h
m2_fd = 0.5 * np.mean(gx**2 + gy**2)
cxx = (roll(z, -1, axis=1) - 2 * z + roll(z, 1, axis=1)) / h**2
cyy = (roll(z, -1, axis=0) - 2 * z + roll(z, 1, axis=0)) / h**2
m4_fd = 0.5 * np.mean(cxx**2 + cyy**2)

# Spectral moments: m_2k = ½ Σ |Ẑ|² (kx^2k + ky^2k) / N² with angular wavenumbers.
Z = np.fft.fft2(z)
power = np.abs(Z) ** 2 / z.size**2
kx = 2 * np.pi * np.fft.fftfreq(z.shape[1], d=h)[None, :]
ky = 2 * np.pi * np.fft.fftfreq(z.shape[0], d=h)[:, None]
m2_spec = 0.5 * np.sum(power * (kx**2 + ky**2))
m4_spec = 0.5 * np.sum(power * (kx**4 + ky**4))

# 9-point summits: strictly higher than all eight neighbours.
shifts = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]
is_summit = np.ones_like(z, dtype=bool)
for dy, dx in shifts:
    is_summit &= z > roll(roll(z, dy, axis=0), dx, axis=1)
d2 = 2 * h**2  # squared diagonal spacing
cdiag1 = (roll(roll(z, -1, 0), -1, 1) - 2 * z + roll(roll(z, 1, 0), 1, 1)) / d2
cdiag2 = (roll(roll(z, -1, 0), 1, 1) - 2 * z + roll(roll(z, 1, 0), -1, 1)) / d2
kappa = -(cxx + cyy + cdiag1 + cdiag2)[is_summit] / 4
heights = z[is_summit]
radii = 1 / kappa[kappa > 0]

out = {
    "source": "numpy " + np.__version__ + ", make_canonical_roughness_reference.py",
    "sigma_m": np.sqrt(np.mean(z**2)),
    "n_summits_9": int(is_summit.sum()),
    "m2_fd": m2_fd,
    "m4_fd": m4_fd,
    "m2_spectral": m2_spec,
    "m4_spectral": m4_spec,
    "r9_inverse_mean_curvature_m": 1 / kappa.mean(),
    "r9_mean_of_inverse_m": radii.mean(),
    "r9_median_of_inverse_m": float(np.median(radii)),
    "sigma_s9_m": heights.std(ddof=0),
    "mean_summit_height_9_m": heights.mean(),
}
(here / "canonical_roughness_numpy.json").write_text(
    json.dumps({k: (float(v) if isinstance(v, np.floating) else v) for k, v in out.items()}, indent=1)
    + "\n"
)
print(json.dumps(out, indent=1, default=float))
