"""What tamaas (https://gitlab.com/tamaas/tamaas, AGPL-3.0; tested with 2.9.0 from pip)
computes for the frictionless, non-adhesive contact of the measured interface map beside this
script: the independent check of hdi's FFT-BEM solver (docs/contact.md, "Deterministic
contact"; the `bem` rows of `hdi validate` and `src/contact/bem` tests read the JSON).

Map: `interface_hdi.x3p`, the `composite.x3p` hdi's `[contact_bem.bem_measured]` wrote for the
shipped pipeline (the sum of raw/afm's disk and slider maps after the surface stage's levelling
and filtering), 256 × 256 elements of 3.906 nm, periodic. It is read here with
SurfaceTopography (MIT; 1.27.1), not with hdi. Heights in metres; SurfaceTopography's [x, y]
order is kept (the periodic half-space problem is the same on the transposed grid).

Model: tamaas `basic_2d`, E* = 149.33 GPa (DLC/DLC, E = 280 GPa, ν = 0.25, as hdi's
`[contact.measured]`), PolonskyKeerRey with a pressure constraint and the tolerance below, at
three mean pressures (near h/σ = 3, 2 and 1 on hdi's curve). Contact fraction = share of
elements with traction > 0; mean gap = mean of (displacement − heights), tamaas's gap field.

    python3 -m venv /tmp/tmenv && /tmp/tmenv/bin/pip install tamaas SurfaceTopography
    /tmp/tmenv/bin/python tests/data/bem/make_tamaas_reference.py
"""
import hashlib
import json
import pathlib

import numpy as np
import tamaas as tm
from SurfaceTopography import read_topography

here = pathlib.Path(__file__).parent
MAP = here / "interface_hdi.x3p"
E_STAR = 280e9 / (1 - 0.25**2) / 2  # two DLC bodies: E* = [2(1 − ν²)/E]⁻¹
NU = 0.25
TOLERANCE = 1e-10
PRESSURES = [3e6, 3e7, 2e8]  # Pa


def main():
    topo = read_topography(str(MAP))
    heights = np.ascontiguousarray(topo.heights(), dtype=np.float64)
    sx, sy = topo.physical_sizes
    nx, ny = heights.shape
    tm.set_log_level(tm.LogLevel.error)
    loads = []
    for p in PRESSURES:
        model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [sx, sy], [nx, ny])
        model.E = E_STAR * (1 - NU**2)
        model.nu = NU
        solver = tm.PolonskyKeerRey(model, heights, TOLERANCE)
        solver.solve(p)
        traction = np.array(model.traction)
        gap = np.array(model.displacement) - heights
        loads.append(
            {
                "mean_pressure_pa": p,
                "tamaas_mean_pressure_pa": float(traction.mean()),
                "contact_fraction": float((traction > 0).mean()),
                "mean_gap_m": float(gap.mean()),
            }
        )
    out = {
        "generator": "tests/data/bem/make_tamaas_reference.py",
        "tamaas": tm.__version__,
        "map": MAP.name,
        "map_sha256": hashlib.sha256(MAP.read_bytes()).hexdigest(),
        "grid": [nx, ny],
        "e_star_pa": E_STAR,
        "tolerance": TOLERANCE,
        "loads": loads,
    }
    (here / "tamaas_reference.json").write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
