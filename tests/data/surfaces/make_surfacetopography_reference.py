"""What SurfaceTopography (MIT, https://github.com/ContactEngineering/SurfaceTopography; tested
with 1.27.1) reads from the public instrument samples beside this script, copied unchanged from
its `test/file_format_examples/` (the JPK files from AFMReader's `tests/resources/`; provenance
in tests/data/README.md): grid size, physical size and RMS height (`rms_height_from_area`,
about the mean, no levelling) in SI units. Writes `surfacetopography_reference.json`, which the
reader tests compare against.

    python -m venv /tmp/st && /tmp/st/bin/pip install SurfaceTopography
    /tmp/st/bin/python tests/data/surfaces/make_surfacetopography_reference.py
"""
import json
import pathlib

import numpy as np
import SurfaceTopography
from SurfaceTopography import read_topography

here = pathlib.Path(__file__).parent
to_m = {"m": 1.0, "mm": 1e-3, "µm": 1e-6, "um": 1e-6, "nm": 1e-9, "Å": 1e-10, "pm": 1e-12}

out = {"SurfaceTopography": SurfaceTopography.__version__, "files": {}}
for name in [
    "di-3.di", "opd-1.opd", "tmd-1.tmd", "top-1.top", "stp-1.stp", "example_ps.tiff",
    "sample_0.jpk", "sample_0.jpk-qi-image",
]:
    path = here / name
    if not path.exists():
        continue
    t = read_topography(str(path))
    k = to_m[t.unit]
    nx, ny = t.nb_grid_pts
    sx, sy = t.physical_sizes
    h = t.heights()
    out["files"][name] = {
        "unit": t.unit,
        "nx": int(nx),
        "ny": int(ny),
        "size_x_m": float(sx) * k,
        "size_y_m": float(sy) * k,
        "rms_height_m": float(t.rms_height_from_area()) * k,
        "n_undefined": int(np.ma.count_masked(h)) if np.ma.isMaskedArray(h) else 0,
        # Pixels by SurfaceTopography's [x, y] index (hdi's row y, column x), in metres.
        "pixels_m": [
            [x, y, float(h[x, y]) * k]
            for x, y in [(0, 0), (nx - 1, 0), (0, ny - 1), (nx // 3, ny // 5)]
            if not np.ma.is_masked(h[x, y])
        ],
    }
(here / "surfacetopography_reference.json").write_text(json.dumps(out, indent=1) + "\n")
print(json.dumps(out, indent=1))
