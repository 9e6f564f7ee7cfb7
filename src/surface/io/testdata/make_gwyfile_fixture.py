"""Writes gwyfile_writer.gwy with the independent MIT `gwyfile` package (not hdi's encoder).

    python3 -m venv /tmp/gwyvenv && /tmp/gwyvenv/bin/pip install gwyfile numpy
    /tmp/gwyvenv/bin/python make_gwyfile_fixture.py

Channel /0 "Phase" (deg, 5x4) and channel /3 "Topography" (m, 37x29, 2 um x 1.5 um,
offsets 1e-7 / -2e-7 m) with z[j, i] = (0.25 i - 0.5 j + (i j mod 7)) * 1e-9, a formula the
Rust test recomputes exactly.
"""
import numpy as np
from gwyfile.objects import GwyContainer, GwyDataField, GwySIUnit

j, i = np.mgrid[0:29, 0:37]
topo = (0.25 * i - 0.5 * j + (i * j) % 7) * 1e-9
phase = np.arange(20, dtype=np.float64).reshape(4, 5)

container = GwyContainer()
container["/0/data"] = GwyDataField(phase, xreal=1e-6, yreal=1e-6,
                                    si_unit_xy=GwySIUnit(unitstr="m"),
                                    si_unit_z=GwySIUnit(unitstr="deg"))
container["/0/data/title"] = "Phase"
container["/3/data"] = GwyDataField(topo.astype(np.float64), xreal=2e-6, yreal=1.5e-6,
                                    xoff=1e-7, yoff=-2e-7,
                                    si_unit_xy=GwySIUnit(unitstr="m"),
                                    si_unit_z=GwySIUnit(unitstr="m"))
container["/3/data/title"] = "Topography"
container.tofile("gwyfile_writer.gwy")
