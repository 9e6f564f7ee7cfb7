"""Writes the small Zygo .datx test files of hdi's datx reader, and datx_expected.json with
numpy's statistics of the same arrays.

The files follow the .datx layout as the public readers describe it (SurfaceTopography's
IO/DATX.py and prysm's read_zygo_datx), written with h5py; they are NOT from a Zygo
instrument. Layout:
  /MetaData            compound (Source, Link, Destination) strings; '{...}' values name
                       further nodes: Root -> Measurement -> Surface -> Path = dataset path
  /Data/Surface/{..}   2-D heights (rows = y) with attributes 'No Data' (1 element), 'Unit'
                       (1-element string array) and 'X/Y/Z Converter' (1-element compound
                       arrays (Category, BaseUnit, HWUnit, Parameters); Parameters[1] = lateral
                       spacing in metres for X/Y)
  /Data/Intensity/{..} the same for the intensity (counts)
  /Attributes/{..}     a group whose attributes carry 'System Serial Number'/'System Type'
Two string/array encodings are written: variable-length strings + variable-length Parameters
(datx_vlen.datx) and fixed-length strings + a fixed 4-element Parameters array
(datx_fixed.datx). The bad_*.datx files are valid HDF5 with wrong content.

Run once (python3 make_datx.py); the outputs are committed and must not be regenerated.
"""
import json

import h5py
import numpy as np

rng = np.random.default_rng(20261126)
expected = {}

VLEN_STR = h5py.special_dtype(vlen=bytes)
VLEN_F64 = h5py.vlen_dtype(np.float64)


def str_dtype(fixed):
    return np.dtype("S80") if fixed else VLEN_STR


def metadata(fixed, entries):
    s = str_dtype(fixed)
    dt = np.dtype([("Source", s), ("Link", s), ("Destination", s)])
    return np.array([tuple(x.encode() for x in e) for e in entries], dtype=dt)


def converter(fixed, category, base, hw, params):
    s = str_dtype(fixed)
    p = np.dtype(("<f8", (4,))) if fixed else VLEN_F64
    dt = np.dtype([("Category", s), ("BaseUnit", s), ("HWUnit", s), ("Parameters", p)])
    a = np.zeros(1, dtype=dt)
    a[0]["Category"] = category.encode()
    a[0]["BaseUnit"] = base.encode()
    a[0]["HWUnit"] = hw.encode()
    a[0]["Parameters"] = np.array(params, dtype=np.float64)
    return a


SURF = "/Data/Surface/{4C2F1A30-0000-4000-8000-000000000001}"
INTEN = "/Data/Intensity/{4C2F1A30-0000-4000-8000-000000000002}"
ATTRS = "/Attributes/{4C2F1A30-0000-4000-8000-000000000003}"


def entries(surface_path=SURF, with_intensity=True):
    e = [
        ("Root", "Measurement", "{M}"),
        ("Root", "Attributes", "{A}"),
        ("{A}", "Path", ATTRS),
        ("{M}", "Surface", "{S}"),
        ("{S}", "Path", surface_path),
        ("{S}", "Name", "Surface"),
    ]
    if with_intensity:
        e += [("{M}", "Intensity", "{I}"), ("{I}", "Path", INTEN)]
    return e


def write(name, fixed, z_stored, no_data, unit, z_base, dx, dy, intensity=None,
          surface_path=SURF, meta=True, x_category="LateralCat"):
    s = str_dtype(fixed)
    with h5py.File(name, "w") as f:
        if meta:
            f.create_dataset("MetaData", data=metadata(fixed, entries(surface_path, intensity is not None)))
        ds = f.create_dataset(SURF, data=z_stored)
        ds.attrs["No Data"] = np.array([no_data], dtype=z_stored.dtype)
        ds.attrs.create("Unit", np.array([unit.encode()], dtype=s))
        ds.attrs["X Converter"] = converter(fixed, x_category, "MicroMeters", "Pixels", [1.0, dx, 0.0, 0.0])
        ds.attrs["Y Converter"] = converter(fixed, "LateralCat", "MicroMeters", "Pixels", [1.0, dy, 0.0, 0.0])
        ds.attrs["Z Converter"] = converter(fixed, "HeightCat", z_base, z_base, [0.0, 632.8e-9, 0.5, 1.0])
        if intensity is not None:
            di = f.create_dataset(INTEN, data=intensity)
            di.attrs["No Data"] = np.array([65535], dtype=intensity.dtype)
            di.attrs.create("Unit", np.array(b"", dtype=s).reshape(1))
            di.attrs["X Converter"] = converter(fixed, "LateralCat", "MicroMeters", "Pixels", [1.0, dx, 0.0, 0.0])
            di.attrs["Y Converter"] = converter(fixed, "LateralCat", "MicroMeters", "Pixels", [1.0, dy, 0.0, 0.0])
        g = f.create_group(ATTRS)
        g.attrs.create("Data Context.Data Attributes.System Serial Number",
                       np.array([b"87266"], dtype=s))
        g.attrs.create("Data Context.Data Attributes.System Type", np.array([b"NewView 9000"], dtype=s))


def record(name, z_m, dx, dy, extra=None):
    valid = np.isfinite(z_m)
    v = z_m[valid]
    ny, nx = z_m.shape
    expected[name] = {
        "nx": nx, "ny": ny, "dx": dx, "dy": dy,
        "mean": float(v.mean()), "std": float(v.std()), "n_invalid": int((~valid).sum()),
        "z_0_0": float(z_m[0, 0]), "z_1_2": float(z_m[1, 2]), "z_last": float(z_m[-1, -1]),
        "serial": "87266", "system_type": "NewView 9000",
    }
    if extra:
        expected[name].update(extra)


def surface(ny, nx, amplitude):
    y, x = np.mgrid[0:ny, 0:nx]
    return amplitude * (np.sin(0.31 * x) * np.cos(0.17 * y) + 0.3 * rng.standard_normal((ny, nx)))


# 1. vlen strings, vlen Parameters, float64 heights in nm, 3 no-data pixels, uint16 intensity.
ny, nx = 30, 40
z_nm = surface(ny, nx, 12.0)
no_data = np.finfo(np.float64).max
stored = z_nm.copy()
for j, i in [(3, 5), (17, 0), (28, 39)]:
    stored[j, i] = no_data
inten = rng.integers(0, 4000, size=(ny, nx)).astype(np.uint16)
inten[2, 2] = 65535
write("datx_vlen.datx", False, stored, no_data, "nm", "NanoMeters", 0.8e-6, 1.2e-6, intensity=inten)
z_m = np.where(stored == no_data, np.nan, stored * 1e-9)
iv = np.where(inten == 65535, np.nan, inten.astype(np.float64))
record("datx_vlen.datx", z_m, 0.8e-6, 1.2e-6,
       {"intensity_mean": float(np.nanmean(iv)), "intensity_n_invalid": int(np.isnan(iv).sum())})

# 2. fixed-length strings, fixed [4] Parameters, float32 heights in um, one NaN + 2 no-data.
ny, nx = 25, 33
z_um = surface(ny, nx, 0.04).astype(np.float32)
no_data32 = np.float32(3.4e38)
z_um[0, 7] = np.nan
z_um[10, 10] = no_data32
z_um[24, 1] = no_data32
write("datx_fixed.datx", True, z_um, no_data32, "um", "MicroMeters", 2.5e-6, 2.5e-6)
zf = z_um.astype(np.float64)
z_m = np.where((z_um == no_data32) | np.isnan(z_um), np.nan, zf * 1e-6)
record("datx_fixed.datx", z_m, 2.5e-6, 2.5e-6)

# Bad files: valid HDF5, wrong content.
small = surface(6, 7, 5.0)
with h5py.File("bad_no_metadata.datx", "w") as f:
    f.create_dataset("Data/Surface/x", data=small)
write("bad_path.datx", False, small, no_data, "nm", "NanoMeters", 1e-6, 1e-6,
      surface_path="/Data/Surface/{does-not-exist}")
write("bad_category.datx", False, small, no_data, "nm", "NanoMeters", 1e-6, 1e-6, x_category="HeightCat")
write("bad_units.datx", True, small, no_data, "nm", "MicroMeters", 1e-6, 1e-6)

with open("datx_expected.json", "w") as f:
    json.dump(expected, f, indent=1, sort_keys=True)
    f.write("\n")
