"""Line scans of the shipped synthetic bulge (raw/bulge/tfc_*mW.gsf, docs/bulge.md), as a
stylus profilometer would give them, for the line-scan bulge fit's acceptance test
(tests/bulge_cli.rs). Independent of hdi: numpy reads the Gwyddion Simple Field files
(text header, NUL padding to a multiple of 4, little-endian float32 row-major, row 0 first)
and writes, per heater power, the rows at y_c + offset for offsets 0, ±10 µm and ±20 µm
(y_c and the row spacing from raw/bulge/truth.json): the centre and ±20 µm lines as Dektak CSV
exports (`Scan Parameters` header, `Lateral um,Raw Micrometer,` columns, CRLF), the ±10 µm
lines as plain x–z text (`# x_unit: um`, `# z_unit: nm`). x is the map's i·dx from its first
pixel. `lines.json` lists file, offset and power for each.

    python3 tests/data/bulge_lines/make_bulge_lines.py   # numpy (1.26 and 2.x give the same files)
"""
import json
import pathlib

import numpy as np

here = pathlib.Path(__file__).parent
raw = here.parent.parent.parent / "raw" / "bulge"
truth = json.loads((raw / "truth.json").read_text())


def read_gsf(path):
    data = path.read_bytes()
    end = data.index(b"\0")
    header = dict(
        line.split("=", 1)
        for line in data[:end].decode().splitlines()[1:]
        if "=" in line
    )
    header = {k.strip(): v.strip() for k, v in header.items()}
    nx, ny = int(header["XRes"]), int(header["YRes"])
    start = (end // 4 + 1) * 4
    z = np.frombuffer(data[start : start + 4 * nx * ny], "<f4").astype(float)
    return z.reshape(ny, nx), float(header["XReal"]) / nx, float(header["YReal"]) / ny


lines = []
for scan in truth["scans"]:
    z, dx, dy = read_gsf(raw / scan["file"])
    power = scan["heater_power_mW"]
    for offset_um in [-20, -10, 0, 10, 20]:
        row = int(round((scan["y_c_m"] + offset_um * 1e-6) / dy))
        assert abs(row * dy - scan["y_c_m"] - offset_um * 1e-6) < 1e-12
        x_um = np.arange(z.shape[1]) * dx * 1e6
        stem = f"tfc_{power:02.0f}mW_y{offset_um:+03d}um"
        if offset_um % 20 == 0:
            name = stem + ".csv"
            text = [
                "Scan Parameters",
                "Scan Type,Standard Scan",
                f"Length,{x_um[-1]:.1f} um",
                f"Resolution,{dx * 1e6:.3f} um/sample",
                "Stylus,Radius: 2.5 um",
                "",
                "Scan Data",
                "Lateral um,Raw Micrometer,",
            ]
            text += [f"{x:.4f},{h * 1e6:.9f},," for x, h in zip(x_um, z[row])]
            (here / name).write_bytes(("\r\n".join(text) + "\r\n").encode())
        else:
            name = stem + ".txt"
            text = ["# x_unit: um", "# z_unit: nm"]
            text += [f"{x:.4f} {h * 1e9:.6f}" for x, h in zip(x_um, z[row])]
            (here / name).write_text("\n".join(text) + "\n")
        lines.append({"file": name, "offset_um": offset_um, "heater_power_mW": power})
(here / "lines.json").write_text(json.dumps({"y_c_m": truth["scans"][0]["y_c_m"], "lines": lines}, indent=1) + "\n")
print(len(lines), "lines")
