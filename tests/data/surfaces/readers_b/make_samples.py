"""Writes the small .x3p test files of hdi's x3p reader, and expected.json with numpy's
statistics of the same arrays.

The files are built from the format description, independently of hdi's Rust code:
ISO 25178-71 / ISO 5436-2 layout (ZIP with main.xml, bindata/data.bin little-endian
with x fastest, MD5 of the point data, optional bindata/valid.bin bit mask with the least
significant bit first, or an inline DataList of <Datum> values); written with Python's
zipfile + numpy. The bad_*.x3p files are valid ZIP archives (correct CRCs) whose content is
wrong, for the reader's error paths.

Run once (python3 make_samples.py); the outputs are committed and must not be regenerated.
"""
import hashlib
import json
import zipfile

import numpy as np

rng = np.random.default_rng(20261125)
expected = {}


def stats(z):
    v = z[np.isfinite(z)]
    return {"mean": float(v.mean()), "std": float(v.std()), "n_invalid": int((~np.isfinite(z)).sum())}


def main_xml(nx, ny, dx, dy, x0, y0, dtype, z_inc=None, z_off=None, datalink=None, datalist=None,
             valid_link=None):
    cz = f"<AxisType>A</AxisType><DataType>{dtype}</DataType>"
    if z_inc is not None:
        cz += f"<Increment>{z_inc!r}</Increment><Offset>{z_off!r}</Offset>"
    if datalink is not None:
        link, md5 = datalink
        rec3 = (f"<DataLink><PointDataLink>{link}</PointDataLink>"
                f"<MD5ChecksumPointData>{md5}</MD5ChecksumPointData>")
        if valid_link is not None:
            rec3 += (f"<ValidPointsLink>{valid_link[0]}</ValidPointsLink>"
                     f"<MD5ChecksumValidPoints>{valid_link[1]}</MD5ChecksumValidPoints>")
        rec3 += "</DataLink>"
    else:
        rec3 = "<DataList>" + "".join(datalist) + "</DataList>"
    return f"""<?xml version="1.0" encoding="UTF-8" standalone="no" ?>
<!-- written by hdi's tests/data/surfaces/readers_b/make_samples.py -->
<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2">
  <Record1>
    <Revision>ISO5436 - 2000</Revision>
    <FeatureType>SUR</FeatureType>
    <Axes>
      <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>{dx!r}</Increment><Offset>{x0!r}</Offset></CX>
      <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>{dy!r}</Increment><Offset>{y0!r}</Offset></CY>
      <CZ>{cz}</CZ>
    </Axes>
  </Record1>
  <Record2>
    <Date>2026-11-25T20:00:00</Date>
    <Instrument><Manufacturer>numpy &amp; zipfile</Manufacturer><Model>make_samples.py</Model>
      <Serial>none</Serial><Version>1</Version></Instrument>
    <CalibrationDate>2026-11-25T20:00:00</CalibrationDate>
    <ProbingSystem><Type>Software</Type><Identification>none</Identification></ProbingSystem>
    <Comment/>
  </Record2>
  <Record3>
    <MatrixDimension><SizeX>{nx}</SizeX><SizeY>{ny}</SizeY><SizeZ>1</SizeZ></MatrixDimension>
    {rec3}
  </Record3>
  <Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4>
</p:ISO5436_2>
"""


def write_x3p(name, xml, members, compression=zipfile.ZIP_DEFLATED):
    with zipfile.ZipFile(name, "w", compression) as z:
        z.writestr("main.xml", xml)
        for member, data in members:
            z.writestr(member, data)
        z.writestr("md5checksum.hex", hashlib.md5(xml.encode()).hexdigest().upper() + " *main.xml\n")


def x3p_case(name, dtype, nx, ny, raw, z, dx, dy, x0, y0, z_inc=None, z_off=None, valid=None,
             compression=zipfile.ZIP_DEFLATED):
    # raw: (ny, nx) array in the file's type; C order = x fastest.
    data = raw.astype(raw.dtype.newbyteorder("<")).tobytes()
    members = [("bindata/data.bin", data)]
    valid_link = None
    if valid is not None:
        bits = np.packbits(valid.ravel().astype(np.uint8), bitorder="little").tobytes()
        members.append(("bindata/valid.bin", bits))
        valid_link = ("bindata/valid.bin", hashlib.md5(bits).hexdigest().upper())
    xml = main_xml(nx, ny, dx, dy, x0, y0, dtype, z_inc, z_off,
                   ("bindata/data.bin", hashlib.md5(data).hexdigest().upper()), valid_link=valid_link)
    write_x3p(name, xml, members, compression)
    expected[name] = {"nx": nx, "ny": ny, "dx": dx, "dy": dy, "x0": x0, "y0": y0,
                      "z_0_0": float(z[0, 0]), "z_1_2": float(z[1, 2]),
                      "z_last": float(z[-1, -1]), **stats(z)}


nx, ny = 13, 9
# int16 with a z increment (1 nm steps) and offset.
raw = rng.integers(-3000, 3000, size=(ny, nx), dtype=np.int16)
z = 2.5e-9 + 1e-9 * raw.astype(np.float64)
x3p_case("x3p_int16.x3p", "I", nx, ny, raw, z, 1.5e-6, 2.0e-6, 1e-5, -2e-5, z_inc=1e-9, z_off=2.5e-9)
# int32 with a validity mask (about a quarter of the points invalid), stored uncompressed.
raw = rng.integers(-2**30, 2**30, size=(ny, nx), dtype=np.int32)
valid = rng.random((ny, nx)) > 0.25
valid[0, 0] = valid[1, 2] = valid[-1, -1] = True
z = 1e-12 * raw.astype(np.float64)
z[~valid] = np.nan
x3p_case("x3p_int32_mask.x3p", "L", nx, ny, raw, z, 1e-7, 1e-7, 0.0, 0.0, z_inc=1e-12, z_off=0.0,
         valid=valid, compression=zipfile.ZIP_STORED)
# float32 with NaN holes.
raw = (rng.standard_normal((ny, nx)) * 1e-8).astype(np.float32)
raw[3, 4] = raw[5, 0] = np.nan
x3p_case("x3p_float32.x3p", "F", nx, ny, raw, raw.astype(np.float64), 3e-6, 3e-6, 0.0, 0.0)
# float64, no z increment.
raw = rng.standard_normal((ny, nx)) * 5e-9 + 1e-6
x3p_case("x3p_float64.x3p", "D", nx, ny, raw, raw, 2e-6, 1e-6, 5e-6, 0.0)
# Inline DataList of float64 values, one missing (empty Datum).
raw = rng.standard_normal((ny, nx)) * 2e-9
z = raw.copy()
z[4, 7] = np.nan
datums = ["<Datum/>" if np.isnan(v) else f"<Datum>{float(v)!r}</Datum>" for v in z.ravel()]
xml = main_xml(nx, ny, 1e-6, 1e-6, 0.0, 0.0, "D", datalist=datums)
write_x3p("x3p_datalist.x3p", xml, [])
expected["x3p_datalist.x3p"] = {"nx": nx, "ny": ny, "dx": 1e-6, "dy": 1e-6, "x0": 0.0, "y0": 0.0,
                                "z_0_0": float(z[0, 0]), "z_1_2": float(z[1, 2]),
                                "z_last": float(z[-1, -1]), **stats(z)}

# Hostile archives: valid ZIPs (correct CRCs) whose content is wrong.
good = main_xml(nx, ny, 1e-6, 1e-6, 0.0, 0.0, "D", datalink=("bindata/data.bin", "0" * 32))
data = np.zeros((ny, nx)).tobytes()
write_x3p("bad_md5.x3p", good, [("bindata/data.bin", data)])
with zipfile.ZipFile("bad_no_main.x3p", "w") as zf:
    zf.writestr("bindata/data.bin", data)
md5 = hashlib.md5(data).hexdigest()
huge = main_xml(nx, ny, 1e-6, 1e-6, 0.0, 0.0, "D", datalink=("bindata/data.bin", md5))
write_x3p("bad_huge_size.x3p", huge.replace(f"<SizeX>{nx}</SizeX>", "<SizeX>4294967296</SizeX>")
          .replace(f"<SizeY>{ny}</SizeY>", "<SizeY>4294967296</SizeY>"), [("bindata/data.bin", data)])
write_x3p("bad_short_data.x3p", huge.replace(f"<SizeY>{ny}</SizeY>", f"<SizeY>{ny + 1}</SizeY>"),
          [("bindata/data.bin", data)])
write_x3p("bad_missing_member.x3p", huge, [])
write_x3p("bad_xml.x3p", huge.replace("</Record3>", ""), [("bindata/data.bin", data)])

with open("expected.json", "w") as f:
    json.dump(expected, f, indent=1, sort_keys=True)
print(json.dumps(expected, indent=1, sort_keys=True))
