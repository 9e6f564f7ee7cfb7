"""Write `numpy_float32.gsf`, a Gwyddion Simple Field file built with numpy and the format's
published description (gwyddion.net/documentation/user-guide-en/gsf.html), and
`numpy_lattice.xyz`, an XYZ point list on a rectangular lattice with a unit header; both
independent of hdi. Writes the values the reader tests expect (`numpy_float32.json`,
`numpy_lattice.json`).

Layout: the text header `Gwyddion Simple Field 1.0`, `Key = Value` lines, 1-4 NUL bytes so
that the binary part starts at a multiple of 4, then XRes*YRes little-endian float32 values,
row by row (the first row is the top of the image).
"""
import json
import pathlib

import numpy as np

here = pathlib.Path(__file__).parent
nx, ny = 48, 40
x_real, y_real = 2.0e-6, 1.5e-6
rng = np.random.default_rng(20261129)
z = (rng.normal(0.0, 0.8e-9, (ny, nx)) + 1.0e-9 * np.sin(np.arange(nx) / 5.0)[None, :]).astype("<f4")
z[7, 11] = np.nan  # an invalid pixel (NaN in a float GSF)

header = (
    "Gwyddion Simple Field 1.0\n"
    f"XRes = {nx}\nYRes = {ny}\n"
    f"XReal = {x_real!r}\nYReal = {y_real!r}\n"
    "XYUnits = m\nZUnits = m\nTitle = numpy fixture\n"
).encode()
pad = 4 - len(header) % 4
(here / "numpy_float32.gsf").write_bytes(header + b"\0" * pad + z.tobytes())

valid = z[np.isfinite(z)].astype(np.float64)
expected = {
    "nx": nx,
    "ny": ny,
    "dx_m": x_real / nx,
    "dy_m": y_real / ny,
    "n_invalid": int((~np.isfinite(z)).sum()),
    "z_7_12_m": float(z[7, 12]),
    "rms_about_mean_m": float(np.sqrt(np.mean((valid - valid.mean()) ** 2))),
}
(here / "numpy_float32.json").write_text(json.dumps(expected, indent=1) + "\n")
print(json.dumps(expected, indent=1))

# XYZ: x fastest, lengths in µm, heights in nm (the units in the header), one invalid point.
nx, ny, step_um = 20, 16, 0.05
zx = rng.normal(0.0, 1.2, (ny, nx))
zx[3, 4] = np.nan
lines = ["# xy_unit: um", "# z_unit: nm"]
for j in range(ny):
    for i in range(nx):
        lines.append(f"{i * step_um!r} {j * step_um!r} {float(zx[j, i])!r}")
(here / "numpy_lattice.xyz").write_text("\n".join(lines) + "\n")
valid = zx[np.isfinite(zx)] * 1e-9
expected = {
    "nx": nx,
    "ny": ny,
    "dx_m": step_um * 1e-6,
    "n_invalid": 1,
    "rms_about_mean_m": float(np.sqrt(np.mean((valid - valid.mean()) ** 2))),
}
(here / "numpy_lattice.json").write_text(json.dumps(expected, indent=1) + "\n")
print(json.dumps(expected, indent=1))
