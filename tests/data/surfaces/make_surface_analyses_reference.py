"""What SurfaceTopography (MIT, https://github.com/ContactEngineering/SurfaceTopography; tested
with 1.27.1) computes for the surface analyses of docs/surfaces.md ("Surface analyses") on two
maps beside this script. Writes `surface_analyses_reference.json`, which
`src/surface/spectra.rs`'s tests compare against (1e-9 relative).

Maps, in SI units (metres), SurfaceTopography's [x, y] = hdi's [row y, column x]:
- `di-3.di` (Bruker NanoScope, public SurfaceTopography test file): heights as
  SurfaceTopography reads them, times 1e-9 (its unit is nm), 10 × 10 µm, non-periodic;
- `gaussian_acf_256_seed12345.txt` (hdi's canonical synthetic surface): the matrix in the file
  (rows = y), 1 × 1 µm, periodic.

Every analysis is called with `reliable=False` (hdi reports the full curves and the cutoff
beside them) and SurfaceTopography's defaults otherwise (Hann window for non-periodic PSDs,
log bins, 10 per decade; 5 per decade for the areal ACF). Bins without data (masked by
SurfaceTopography) are left out. The profile slope and curvature use the ACF on the grid
distances (`resampling_method=None`), the areal ones the binned radial ACF (the only one
SurfaceTopography has).

    /tmp/h5env/bin/python tests/data/surfaces/make_surface_analyses_reference.py
"""
import json
import pathlib

import numpy as np
import SurfaceTopography
from SurfaceTopography import Topography, read_topography

here = pathlib.Path(__file__).parent


def compressed(x, y):
    x = np.ma.asarray(x)
    y = np.ma.asarray(y)
    keep = ~(np.ma.getmaskarray(x) | np.ma.getmaskarray(y))
    return [float(v) for v in np.ma.getdata(x)[keep]], [float(v) for v in np.ma.getdata(y)[keep]]


def analyses(t, tip_radii):
    out = {}
    for name, call in [
        ("psd_profile", lambda: t.power_spectrum_from_profile(reliable=False)),
        ("psd_area", lambda: t.power_spectrum_from_area(reliable=False)),
        ("acf_profile", lambda: t.autocorrelation_from_profile(reliable=False)),
        ("acf_area", lambda: t.autocorrelation_from_area(reliable=False)),
        ("slope_profile",
         lambda: t.scale_dependent_slope_from_profile(reliable=False, resampling_method=None)),
        ("curvature_profile",
         lambda: t.scale_dependent_curvature_from_profile(reliable=False, resampling_method=None)),
        ("slope_area", lambda: t.scale_dependent_slope_from_area(reliable=False)),
        ("curvature_area", lambda: t.scale_dependent_curvature_from_area(reliable=False)),
    ]:
        x, y = compressed(*call())
        out[name] = {"x": x, "y": y}
    out["tip_reliability_cutoff_m"] = {
        repr(r): t.scanning_probe_reliability_cutoff(r) for r in tip_radii
    }
    return out


di3 = read_topography(str(here / "di-3.di"))
assert di3.unit == "nm"
di3 = Topography(np.ma.getdata(di3.heights()) * 1e-9,
                 tuple(float(s) * 1e-9 for s in di3.physical_sizes), periodic=False)
z = np.loadtxt(here / "gaussian_acf_256_seed12345.txt")
gauss = Topography(z.T.copy(), (1e-6, 1e-6), periodic=True)

out = {
    "SurfaceTopography": SurfaceTopography.__version__,
    "maps": {
        "di-3.di": analyses(di3, [10e-9, 20e-9, 40e-9, 100e-9, 1e-3]),
        "gaussian_acf_256_seed12345.txt": analyses(gauss, [20e-9, 300e-9, 1e-6, 3e-6, 1e-3]),
    },
}
(here / "surface_analyses_reference.json").write_text(json.dumps(out, indent=1) + "\n")
for m, a in out["maps"].items():
    print(m, {k: len(v["x"]) for k, v in a.items() if isinstance(v, dict) and "x" in v},
          a["tip_reliability_cutoff_m"])
