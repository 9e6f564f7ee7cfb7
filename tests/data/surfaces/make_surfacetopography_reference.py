"""What SurfaceTopography (MIT, https://github.com/ContactEngineering/SurfaceTopography; tested
with 1.27.1) reads from the public instrument samples beside this script, copied unchanged from
its `test/file_format_examples/` (provenance in tests/data/README.md): grid size, physical size and RMS height (`rms_height_from_area`,
about the mean, no levelling) in SI units. Writes `surfacetopography_reference.json`, which the
reader tests compare against.

Two formats get a documented correction of SurfaceTopography's reading, applied below to its own
values (tests/data/README.md gives the evidence):
- FRT (`frt-1.frt`): pixels whose raw count lies outside the valid range of the file's block
  0x0070 (`first_valid`, `last_valid`, from SurfaceTopography's metadata) are masked too; in
  frt-1 that is the one line, all 0, the aborted measurement did not scan.
- NanoFocus NMS: SurfaceTopography's `NMSReader` (its format detection takes nms-2 for MATLAB)
  maps counts 0…65534 onto zmin…zmax where the header's raw range is 0…65535, and reads the
  pixel spacing as millimetres where it is nanometres; heights are rescaled by 65534/65535
  about zmin and sizes by 1e-6.

    python -m venv /tmp/st && /tmp/st/bin/pip install SurfaceTopography
    /tmp/st/bin/python tests/data/surfaces/make_surfacetopography_reference.py
"""
import json
import pathlib

import numpy as np
import SurfaceTopography
from SurfaceTopography import Topography, read_topography
from SurfaceTopography.IO import NMSReader

here = pathlib.Path(__file__).parent
to_m = {"m": 1.0, "mm": 1e-3, "µm": 1e-6, "um": 1e-6, "nm": 1e-9, "Å": 1e-10, "pm": 1e-12}

out = {"SurfaceTopography": SurfaceTopography.__version__, "files": {}}
names = ["di-3.di", "opd-1.opd", "tmd-1.tmd", "top-1.top", "stp-1.stp"]
names += ["plu-1.plu", "al3d-1.al3d", "frt-1.frt", "frt-2.frt", "nms-1.nms", "nms-2.nms"]
names += ["example_ps.tiff"]
names += ["nid-1.nid", "mi-1.mi", "bcrf-1.bcrf", "mnt-1.mnt", "mnt-2.mnt"]
for name in names:
    path = here / name
    if not path.exists():
        continue
    if name.endswith(".nms"):
        reader = NMSReader(str(path))
        t = reader.topography()
        zmin = reader.channels[0].info["raw_metadata"]["zmin"]
        h = (t.heights() - zmin) * (65534 / 65535) + zmin
        t = Topography(h, [s * 1e-6 for s in t.physical_sizes], unit=t.unit)
    else:
        t = read_topography(str(path))
    if name.endswith(".frt"):
        blocks = t.info["raw_metadata"]
        lo, hi = blocks["0x70"]["first_valid"], blocks["0x70"]["last_valid"]
        h = t.heights()
        raw = np.round(np.ma.getdata(h) / blocks["0x6c"]["height_scale_factor"])
        h = np.ma.masked_array(np.ma.getdata(h), np.ma.getmaskarray(h) | (raw < lo) | (raw > hi))
        t = Topography(h, t.physical_sizes, unit=t.unit)
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
            for x, y in [(0, 0), (nx - 1, 0), (0, ny - 1), (nx // 3, ny // 5), (nx // 2, ny // 2),
                         (2 * nx // 3, 3 * ny // 4)]
            if not np.ma.is_masked(h[x, y])
        ],
    }
(here / "surfacetopography_reference.json").write_text(json.dumps(out, indent=1) + "\n")
print(json.dumps(out, indent=1))
