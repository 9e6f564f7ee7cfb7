"""What SurfaceTopography (MIT; tested with 1.27.1) reads from an X3P file hdi wrote, so that the
tests check hdi's X3P writer against an independent reader. The file beside this script was
written by hdi from the public OPD sample (a 64 × 64 crop holding 95 invalid pixels):

    hdi surface tests/data/surfaces/opd-1.opd --crop "11.8um,78.69um,12.59um,12.59um" \
        --x3p-out tests/data/surfaces/x3p_out/opd-1_crop.x3p

Writes `surfacetopography_reading.json`: grid, physical size, RMS height about the mean
(`rms_height_from_area`), the invalid (masked) pixels and a few heights, in metres.

    python -m venv /tmp/st && /tmp/st/bin/pip install SurfaceTopography
    /tmp/st/bin/python tests/data/surfaces/x3p_out/make_reference.py
"""
import json
import pathlib

import numpy as np
import SurfaceTopography
from SurfaceTopography import read_topography

here = pathlib.Path(__file__).parent
t = read_topography(str(here / "opd-1_crop.x3p"))
assert t.unit == "m", t.unit
nx, ny = t.nb_grid_pts
sx, sy = t.physical_sizes
h = t.heights()
mask = np.ma.getmaskarray(h)
out = {
    "SurfaceTopography": SurfaceTopography.__version__,
    "nx": int(nx),
    "ny": int(ny),
    "size_x_m": float(sx),
    "size_y_m": float(sy),
    "rms_height_m": float(t.rms_height_from_area()),
    # [x, y] by SurfaceTopography's index (hdi's column x, row y).
    "undefined": [[int(x), int(y)] for x, y in zip(*np.nonzero(mask))],
    "pixels_m": [
        [x, y, float(h[x, y])]
        for x, y in [(0, 0), (nx - 1, 0), (0, ny - 1), (nx // 3, ny // 5), (40, 50)]
        if not mask[x, y]
    ],
}
(here / "surfacetopography_reading.json").write_text(json.dumps(out, indent=1) + "\n")
print(json.dumps({k: v for k, v in out.items() if k != "undefined"}, indent=1))
