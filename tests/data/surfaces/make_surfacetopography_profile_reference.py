"""What SurfaceTopography (MIT, https://github.com/ContactEngineering/SurfaceTopography; tested
with 1.27.1) reads from the public line-profile samples beside this script, copied unchanged
from its `test/file_format_examples/`: it reads them as line scans (`UniformLineScan` or
`NonuniformLineScan`). Writes `surfacetopography_profile_reference.json` with, per file, the
point count, the span from the first to the last position, the RMS height about the mean of
its heights (all points, as numpy computes it from SurfaceTopography's heights; for uniform
scans this is its own `rms_height_from_profile`, checked here) and a few points (index,
position from the first point, height) in SI units. hdi's line-profile tests compare against it
(`src/surface/io/profile/tests.rs`).

SurfaceTopography shifts the positions so that the first is 0; files without a unit (plain
x–z text) are read by hdi as metres and listed here with unit "m".

    /tmp/h5env/bin/python tests/data/surfaces/make_surfacetopography_profile_reference.py
"""
import json
import pathlib

import numpy as np
import SurfaceTopography
from SurfaceTopography.IO import open_topography

here = pathlib.Path(__file__).parent
to_m = {None: 1.0, "m": 1.0, "mm": 1e-3, "µm": 1e-6, "um": 1e-6, "nm": 1e-9}

out = {"SurfaceTopography": SurfaceTopography.__version__, "files": {}}
for name in ["dektak-1.csv", "hfm-1.hfm", "opdx-3.opdx", "opdx-3.txt", "xy-1.txt", "xy-4.txt"]:
    t = open_topography(str(here / name)).topography()
    assert t.dim == 1, name
    k = to_m[t.unit]
    x, h = t.positions_and_heights()
    x = np.asarray(x, dtype=float)
    h = np.ma.getdata(h).astype(float)
    rms = float(np.sqrt(np.mean((h - h.mean()) ** 2)))
    if t.is_uniform:
        assert abs(rms / t.rms_height_from_profile() - 1) < 1e-12, name
    n = len(h)
    out["files"][name] = {
        "unit": t.unit or "m",
        "kind": type(t).__name__,
        "uniform": bool(t.is_uniform),
        "n": int(n),
        "span_m": float(x[-1] - x[0]) * k,
        "physical_size_m": float(t.physical_sizes[0]) * k,
        "rms_height_m": rms * k,
        "points_m": [[int(i), float(x[i] - x[0]) * k, float(h[i]) * k] for i in [0, 1, n // 3, n - 1]],
    }
(here / "surfacetopography_profile_reference.json").write_text(json.dumps(out, indent=1) + "\n")
print(json.dumps(out, indent=1))
