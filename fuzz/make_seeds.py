"""Writes the fuzz targets' seed corpora into fuzz/corpus/<target>/ (run from the repository
root: .venv/bin/python fuzz/make_seeds.py). Small inputs fuzz fastest, so each format gets a
tiny record or map written here with independent writers (numpy, pyarrow, h5py, Python's wave
and struct), beside the repository's own small test files. scripts/fuzz.sh reads the result;
Beside these, `found_*` files are what the long runs added, pruned with afl-cmin to
the inputs under 4 KiB (LDV: 1.5 kB) among those that reach coverage nothing else does (docs/reliability.md,
"Coverage-guided fuzzing"); this script leaves them alone.
"""
import io
import json
import os
import shutil
import struct
import zlib
import wave
from pathlib import Path

import h5py
import numpy as np
import pyarrow as pa
import pyarrow.feather as feather
import pyarrow.ipc as ipc
import pyarrow.parquet as pq

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "fuzz" / "corpus"


def target(name):
    d = OUT / name
    d.mkdir(parents=True, exist_ok=True)
    return d


def copy(target_dir, *paths, limit=200_000):
    for p in paths:
        p = ROOT / p
        if p.stat().st_size <= limit:
            shutil.copy(p, target_dir / p.name)


# --- LDV records: 64 samples at 100 kHz, velocity in V, a once-per-rev index pulse.
ldv = target("ldv")
N, FS = 64, 100e3
i = np.arange(N)
t = 0.125 + i / FS
v = np.round(0.2 * np.sin(2 * np.pi * 3 * i / N) * 1024) / 1024
idx = np.where(i % 32 < 2, 4.875, 0.0195)
with open(ldv / "record.csv", "w") as f:
    f.write("# sample_rate = 100 kHz\n# sensitivity = 0.025\n# rpm = 6000\n")
    f.write("time_s,velocity_V,index_V\n")
    for row in zip(t, v, idx):
        f.write(",".join(repr(float(x)) for x in row) + "\n")
with open(ldv / "record.tsv", "w") as f:
    f.write("# fs: 100000\n# layout = averaged\nsample\tvelocity_m_s\n")
    for k, x in zip(i, v):
        f.write(f"{k}\t{x!r}\n")
with open(ldv / "record_semicolon.txt", "w") as f:
    f.write("t (ms);U [mV];trigger\n")
    for row in zip(t * 1e3, v * 1e3, idx):
        f.write(";".join(repr(float(x)) for x in row) + "\n")
table = pa.table({"time_s": t, "velocity_V": v, "index_V": idx})
pq.write_table(
    table.replace_schema_metadata({"sample_rate": "100000", "rpm": "6000"}),
    ldv / "record.parquet", compression="zstd")
pq.write_table(pa.table({"sample_index": i, "velocity_m_s": v.astype(np.float32)}),
               ldv / "record_plain.parquet", compression="none")
feather.write_feather(table, ldv / "record_lz4.feather")
feather.write_feather(table, ldv / "record_plain.arrow", compression="uncompressed")
sink = io.BytesIO()
with ipc.new_stream(sink, table.schema) as w:
    w.write_table(table)
(ldv / "record.arrows").write_bytes(sink.getvalue())
with h5py.File(ldv / "record.h5", "w") as f:
    f.attrs["NX_class"] = "NXroot"
    f.attrs["default"] = "ldv"
    g = f.create_group("ldv")
    g.attrs.update({"NX_class": "NXdata", "signal": "velocity", "sampling_rate": FS,
                    "t0": 0.125, "layout": "continuous", "rpm": 6000.0})
    g.create_dataset("velocity", data=v).attrs["units"] = "V"
    g.create_dataset("index", data=idx).attrs["units"] = "V"
    g.create_dataset("time", data=t).attrs["units"] = "s"
with h5py.File(ldv / "record_counts.h5", "w") as f:
    g = f.create_group("ldv")
    g.attrs.update({"sampling_rate": FS, "layout": "segments"})
    d = g.create_dataset("velocity", data=np.round(v * 1000).astype(np.int16).reshape(2, 32),
                         chunks=(1, 32), shuffle=True, compression="gzip")
    d.attrs.update({"scale": 1e-3, "offset": 0.0, "units": "V"})
with h5py.File(ldv / "record_root.h5", "w") as f:
    d = f.create_dataset("U_mV", data=(v * 1e3).astype(np.float32))
    d.attrs["scale_factor"] = 1.0
    d.attrs["fs"] = FS
np.save(ldv / "record.npy", np.stack([t, v, idx], axis=1))
np.save(ldv / "record_velocity.npy", v.astype(">f4"))
rec = np.zeros(N, dtype=[("time_s", "<f8"), ("velocity_V", "<f4")])
rec["time_s"], rec["velocity_V"] = t, v
np.save(ldv / "record_structured.npy", rec)
np.savez(ldv / "record.npz", velocity_V=v, index_V=idx, sample_rate=np.array(FS))
np.savez_compressed(ldv / "record_deflate.npz", velocity=v, sample_rate=np.array(FS))
for name, width in [("record_int16.wav", 2), ("record_int24.wav", 3)]:
    with wave.open(str(ldv / name), "wb") as w:
        w.setnchannels(2)
        w.setsampwidth(width)
        w.setframerate(int(FS))
        scale = 2 ** (8 * width - 1) - 1
        frames = b"".join(
            int(a * scale).to_bytes(width, "little", signed=True)
            + int(b / 5 * scale).to_bytes(width, "little", signed=True)
            for a, b in zip(v, idx))
        w.writeframes(frames)
# IEEE-float WAV (format tag 3), written by hand: the wave module writes PCM only.
data = v.astype("<f4").tobytes()
fmt = struct.pack("<HHIIHH", 3, 1, int(FS), int(FS) * 4, 4, 32)
wav = b"WAVE" + b"fmt " + struct.pack("<I", len(fmt)) + fmt + b"data" + struct.pack("<I", len(data)) + data
(ldv / "record_f32.wav").write_bytes(b"RIFF" + struct.pack("<I", len(wav)) + wav)
copy(ldv, "tests/data/ldv/record_binary.uff", "tests/data/ldv/record_ascii_single.uff")

# --- Height maps: 8×6 maps in the formats Python writes easily, plus the small test files.
maps = target("height_map")
nx, ny = 8, 6
z = np.round(np.sin(np.arange(nx * ny) * 0.7).reshape(ny, nx) * 1e-9, 15)
hdr = ("Gwyddion Simple Field 1.0\n"
       f"XRes = {nx}\nYRes = {ny}\nXReal = 8e-07\nYReal = 6e-07\n"
       "XYUnits = m\nZUnits = m\nTitle = Height\n").encode()
hdr += b"\0" * (4 - len(hdr) % 4)
(maps / "map.gsf").write_bytes(hdr + z.astype("<f4").tobytes())
with open(maps / "map.txt", "w") as f:
    f.write("# Channel: Height\n# Width: 0.8 um\n# Height: 0.6 um\n# Value units: nm\n")
    for row in z * 1e9:
        f.write("\t".join(f"{x:.4f}" for x in row) + "\n")
with open(maps / "map.csv", "w") as f:
    for row in z * 1e9:
        f.write(",".join(f"{x:.4f}" for x in row) + "\n")
with open(maps / "map.xyz", "w") as f:
    f.write("# xy_unit: um\n# z_unit: nm\n")
    for j in range(ny):
        for k in range(nx):
            f.write(f"{k * 0.1:.2f} {j * 0.1:.2f} {z[j, k] * 1e9:.4f}\n")
# MetroPro header format 3 with a 4×3 phase map (the byte layout of metropro.rs's test).
b = bytearray(4096)
b[:4] = bytes.fromhex("881b0371")
b[4:6] = struct.pack(">H", 3)
b[6:10] = struct.pack(">I", 4096)
b[68:72] = struct.pack(">HH", 4, 3)
b[164:168] = struct.pack(">f", 0.5)
b[168:172] = struct.pack(">f", 632.8e-9)
b[176:180] = struct.pack(">f", 1.0)
b[184:188] = struct.pack(">f", 2e-6)
b[232:234] = struct.pack(">h", 1)
b += b"".join(struct.pack(">i", 100 * k - 300) for k in range(12))
(maps / "map_metropro.dat").write_bytes(bytes(b))
# Wyko OPD: directory, a 4×3 int16 array and the four scalars (the layout of opd.rs's test).
blocks = [(b"RAW DATA", 3, struct.pack("<HHH", 4, 3, 2) + struct.pack("<12h", *range(12))),
          (b"Wavelength", 7, struct.pack("<f", 600.0)), (b"Mult", 6, struct.pack("<H", 1)),
          (b"Aspect", 7, struct.pack("<f", 1.0)), (b"Pixel_size", 7, struct.pack("<f", 0.002))]
entry = lambda name, kind, n: name.ljust(16, b"\0") + struct.pack("<hiH", kind, n, 0)
opd = b"\x01\x00" + entry(b"Directory", 1, 24 * (len(blocks) + 1))
opd += b"".join(entry(n, k, len(c)) for n, k, c in blocks) + b"".join(c for _, _, c in blocks)
(maps / "map.opd").write_bytes(opd)
# TrueMap v2.0: magic, comment, a 4×3 float32 grid (the layout of tmd.rs's test).
tmd = b"Binary TrueMap Data File v2.0\r\n\0" + b"seed\0" + struct.pack("<II4f", 4, 3, 4.0, 3.0, 0.0, 0.0)
tmd += struct.pack("<12f", *[0.1 * k for k in range(12)])
(maps / "map.tmd").write_bytes(tmd)
# WSxM: the three lines, a minimal header and a 4×3 int16 image (the layout of wsxm.rs's test).
body = ("\n[Control]\n    X Amplitude: 2 nm\n    Y Amplitude: 1.5 nm\n[General Info]\n"
        "    Image Data Type: short\n    Number of columns: 4\n    Number of rows: 3\n"
        "    Z Amplitude: 1 nm\n[Miscellaneous]\n    Maximum: 11\n    Minimum: 0\n[Header end]\n")
head = lambda n: f"WSxM file copyright UAM\r\nSxM Image file\r\nImage header size: {n}\r\n{body}".encode()
n = len(head(len(head(0))))
(maps / "map.top").write_bytes(head(n) + struct.pack("<12h", *range(12)))
# Nanosurf NID: the INI header and one 4×3 int16 data set after `#!` (the layout of nid.rs's test).
nid = ("[DataSet]\r\nGroupCount=1\r\nGr0-Count=1\r\nGr0-Ch0=DataSet-0:0\r\n\r\n[DataSet-0:0]\r\n"
       "Points=4\r\nLines=3\r\nFrame=Scan forward\r\nDim0Range=2e-06\r\nDim0Unit=m\r\n"
       "Dim1Range=1.5e-06\r\nDim1Unit=m\r\nDim2Name=Z-Axis\r\nDim2Unit=m\r\nDim2Range=1e-06\r\n"
       "Dim2Min=-5e-07\r\nSaveMode=Binary\r\nSaveBits=16\r\nSaveSign=Signed\r\nSaveOrder=Intel\r\n\r\n#!")
(maps / "map.nid").write_bytes(nid.encode() + struct.pack("<12h", *range(12)))
# Molecular Imaging: 14-character key column, one µm channel, int32 data (the layout of mi.rs's test).
mi = "".join(f"{k:<14}{v}\n" for k, v in [
    ("fileType", "Image"), ("xPixels", "4"), ("yPixels", "3"), ("xLength", "2e-6"),
    ("yLength", "1.5e-6"), ("bufferLabel", "Topography"), ("bufferRange", "1.5"),
    ("bufferUnit", "um"), ("data", "BINARY_32")])
(maps / "map.mi").write_bytes(mi.encode() + struct.pack("<12i", *range(12)))
# Image Metrology BCR-STM: a 2048-character header and 4×3 int16 values (the layout of bcr.rs's test).
bcr = "fileformat = bcrstm\nxpixels = 4\nypixels = 3\nxlength = 2\nylength = 1.5\nbit2nm = 0.5\n"
(maps / "map.bcr").write_bytes(bcr.ljust(2048).encode() + struct.pack("<12h", *range(12)))
# Digital Surf Mountains: a version-3 compound file (MS-CFB, 512-byte sectors) whose one stream
# `ScopedContents` holds a document with one 4×3 surface (the TLV layout of mnt.rs), padded past
# the 4096-byte mini-stream cutoff.
tlv = lambda tag, value: struct.pack("<HQ", tag, len(value)) + value
text = lambda t: b"\x04" + t.encode("utf-16-le")
obj = lambda cls, body: tlv(1, tlv(1, struct.pack("<I", cls))) + tlv(2, body)
scale = lambda step, unit: tlv(1, struct.pack("<d", step)) + tlv(2, text(unit)) + tlv(5, struct.pack("<d", 0.0))
counts = struct.pack("<12i", *range(12))
z = zlib.compress(counts)
blocks = struct.pack("<Q", len(counts)) + struct.pack("<QII", 0, 12, len(z)) + z
heights = obj(9049, tlv(1, struct.pack("<I", 12)) + tlv(2, blocks))
axis = lambda n: tlv(0xFFFF, tlv(0xFFFF, scale(0.5, "µm")) + tlv(1, struct.pack("<I", n)))
grid = tlv(0xFFFF, tlv(0xFFFF, tlv(0xFFFF, tlv(1, text("seed")))) + tlv(1, axis(4)) + tlv(2, axis(3)))
measurement = obj(9062, tlv(0xFFFF, grid + tlv(1, heights) + tlv(2, tlv(0xFFFF, scale(1e-3, "nm")))))
surface = obj(9012, tlv(1, measurement))
doc = tlv(1, tlv(0x2BD, tlv(2, tlv(1, struct.pack("<Q", 0) + tlv(1, surface)))))
contents = struct.pack("<Q", len(doc)) + doc
contents += b"\0" * (4608 - len(contents))
sectors = [contents[k:k + 512] for k in range(0, len(contents), 512)]
n = len(sectors)  # stream in sectors 0…n−1, directory in n, FAT in n + 1
fat = list(range(1, n)) + [0xFFFFFFFE, 0xFFFFFFFE, 0xFFFFFFFD]
fat_sector = struct.pack(f"<{len(fat)}I", *fat).ljust(512, b"\xff")
def direntry(name, kind, start, size, child=0xFFFFFFFF):
    units = (name + "\0").encode("utf-16-le")
    return (units.ljust(64, b"\0") + struct.pack("<HBB3I", len(units), kind, 1, 0xFFFFFFFF, 0xFFFFFFFF, child)
            + b"\0" * 36 + struct.pack("<IQ", start, size)).ljust(128, b"\0")
directory = (direntry("Root Entry", 5, 0xFFFFFFFE, 0, child=1)
             + direntry("ScopedContents", 2, 0, len(contents))).ljust(512, b"\0")
header = (b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + b"\0" * 16
          + struct.pack("<HHHHH", 0x3E, 3, 0xFFFE, 9, 6) + b"\0" * 6
          + struct.pack("<IIIIIIIII", 0, 1, n, 0, 4096, 0xFFFFFFFE, 0, 0xFFFFFFFE, 0)
          + struct.pack("<I", n + 1) + b"\xff" * 4 * 108)
(maps / "map.mnt").write_bytes(header + b"".join(sectors) + directory + fat_sector)
# A classic TIFF IFD (tag, type, count, value or offset), values past 4 bytes after the IFD.
def tiff_le(entries, tail=b""):
    out = b"II*\0" + struct.pack("<I", 8) + struct.pack("<H", len(entries))
    extra, at = b"", 8 + 2 + 12 * len(entries) + 4
    for tag, kind, count, value in sorted(entries):
        if len(value) <= 4:
            out += struct.pack("<HHI", tag, kind, count) + value.ljust(4, b"\0")
        else:
            out += struct.pack("<HHII", tag, kind, count, at + len(extra))
            extra += value
    return out + struct.pack("<I", 0) + extra + tail
# Park Systems TIFF v2: magic, version, a 4×3 float32 data tag and the 408-byte header (the
# layout of park.rs's test: name, grid, 8 × 6 µm, gain 2, scale 0.5, offset 1, unit nm).
ph = bytearray(408)
ph[4:20] = "Z Height".encode("utf-16-le")
ph[100:108] = struct.pack("<II", 4, 3)
ph[140:156] = struct.pack("<dd", 8.0, 6.0)
ph[220:244] = struct.pack("<ddd", 2.0, 0.5, 1.0)
ph[244:248] = "nm".encode("utf-16-le")
ph[348:352] = struct.pack("<I", 2)
pdata = struct.pack("<12f", *[0.5 * k for k in range(12)])
(maps / "map_park.tiff").write_bytes(tiff_le([
    (50432, 4, 1, struct.pack("<I", 0x0E031301)), (50433, 4, 1, struct.pack("<I", 0x01000002)),
    (50434, 1, len(pdata), pdata), (50435, 7, len(ph), bytes(ph))]))
# Digital Surf: the header of the SurfaceTopography sample with an 8×6 data block.
sur = bytearray((ROOT / "tests/data/surfaces/sur-3.sur").read_bytes())
comment, private = struct.unpack("<HH", sur[334:338])
bits = struct.unpack("<H", sur[16:18])[0]
sur[108:116] = struct.pack("<ii", nx, ny)
start = 512 + comment + private
(maps / "map.sur").write_bytes(bytes(sur[:start + nx * ny * bits // 8]))
# Sensofar PLU: the 500-byte header of the SurfaceTopography sample, one 4×3 layer with one RGB
# image (the layout of plu.rs).
plu = bytearray((ROOT / "tests/data/surfaces/plu-1.plu").read_bytes()[:500])
plu[489], plu[492] = 1, 1
plu += struct.pack("<II", 3, 4) + struct.pack("<12f", *[0.5 * k for k in range(12)])
plu += struct.pack("<2f", 0.0, 5.5) + bytes(range(36))
(maps / "map.plu").write_bytes(bytes(plu))
# Alicona AL3D: magic, Version, TagCount, tags, comment, a 4×3 depth image (rows padded to 8
# bytes) and one texture plane (the layout of al3d.rs).
tag = lambda k, v: k.encode().ljust(20, b"\0") + v.encode().ljust(30, b"\0") + b"\r\n"
magic = b"AliconaImaging\0\r\n"
tags = [("Cols", "4"), ("Rows", "3"), ("PixelSizeXMeter", "1e-06"), ("PixelSizeYMeter", "1e-06"),
        ("InvalidPixelValue", "3e+15"), ("NumberOfPlanes", "1"), ("TexturePtr", "0")]
depth_at = len(magic) + 52 * (2 + len(tags) + 2) + 256
tags += [("DepthImageOffset", str(depth_at)), ("TextureImageOffset", str(depth_at + 3 * 16))]
al3d = magic + tag("Version", "1") + tag("TagCount", str(len(tags)))
al3d += b"".join(tag(k, v) for k, v in tags) + b"seed".ljust(256, b"\0")
al3d += struct.pack("<12f", *[1e-6 * k for k in range(12)]) + bytes(3 * 8)
(maps / "map.al3d").write_bytes(al3d)
# FRT MicroProf 1.00: size, scan, scale, valid-range, topography and image blocks, 4×3 uint16.
frt_block = lambda t, c: struct.pack("<HI", t, len(c)) + c
values = struct.pack("<12H", *[1] + [10 * k for k in range(1, 12)])
frt_blocks = [frt_block(0x66, struct.pack("<3I", 4, 3, 16)),
              frt_block(0x67, struct.pack("<5dI", 4e-3, 3e-3, 0.0, 0.0, 1.0, 1)),
              frt_block(0x6C, struct.pack("<Id", 5, 1e-8)), frt_block(0x0B, values),
              frt_block(0x70, struct.pack("<2I", 1, 65529)),
              frt_block(0x7D, struct.pack("<4H", 0, 0, 0, 0) + struct.pack("<4I", 4, 4, 3, 16)
                        + values + struct.pack("<4I", 2, 4, 3, 16) + values)]
(maps / "map.frt").write_bytes(b"FRTM_GLIDERV1.00" + struct.pack("<H", len(frt_blocks))
                               + b"".join(frt_blocks))
# NanoFocus NMS: the 3468-byte header of the SurfaceTopography sample with a 4×3 grid, uint16
# heights and the 8-bit intensity image (the layout of nms.rs).
nms = bytearray((ROOT / "tests/data/surfaces/nms-1.nms").read_bytes()[:3468])
nms[1368:1376] = struct.pack("<II", 4, 3)
nms += struct.pack("<12H", *[5000 * k for k in range(12)]) + bytes(range(12))
(maps / "map.nms").write_bytes(bytes(nms))
copy(maps, "src/surface/io/testdata/gwyfile_writer.gwy",
     "tests/data/surfaces/bcr_binary_int16.sdf", "tests/data/surfaces/sdf-1.sdf",
     "tests/data/surfaces/10x10-one_channel_without_name.ibw",
     "tests/data/surfaces/igor_be_int16_3layers.ibw",
     "tests/data/surfaces/readers_b/x3p_int16.x3p", "tests/data/surfaces/readers_b/x3p_float64.x3p",
     "tests/data/surfaces/readers_b/x3p_int32_mask.x3p", "tests/data/surfaces/readers_b/x3p_datalist.x3p",
     "tests/data/surfaces/readers_b/datx_fixed.datx", "tests/data/surfaces/readers_b/datx_vlen.datx",
     "raw/bulge/tfc_30mW.gsf", "raw/afm/slider_tfc_1um.spm")

# --- pipeline.toml: the shipped file and the examples'.
pipe = target("pipeline")
copy(pipe, "pipeline.toml")
# Prefixes of the shipped file cut before every fourth instance: valid pipelines of 1, 5, 9, …
# stages.
lines = (ROOT / "pipeline.toml").read_text().splitlines(keepends=True)
heads = [k for k, l in enumerate(lines) if l.startswith("[") and not l.startswith("[project")]
for n, k in list(enumerate(heads[1:], 1))[::4]:
    (pipe / f"pipeline_{n:02d}.toml").write_text("".join(lines[:k]))
# The ```toml blocks of the docs: small pipelines, each one stage kind or feature.
for doc in sorted((ROOT / "docs").glob("*.md")):
    blocks = doc.read_text().split("```toml\n")[1:]
    for k, block in enumerate(blocks):
        (pipe / f"{doc.stem}_{k}.toml").write_text(block.split("```")[0])

# --- Case manifests and the submissions file beside one.
man = target("manifest")
def entry(k, status):
    return {"kind": "simulate", "key": f"{k:064x}", "model_version": "2dof-7",
            "params": {"case": k, "model_parameters": {"variant": "Improved"}},
            "recipe": {"stage": "sweep", "upstream": ["a" * 64]}, "status": status}
cases = [entry(0, {"state": "pending"}), entry(1, {"state": "done"}),
         entry(2, {"state": "failed", "error": "diverged", "job_id": 17, "task_id": 1,
                   "log": "processed/.hdi/slurm/logs/17_1.log"})]
for name, cpt, cs in [("manifest.json", 2, cases), ("manifest_one.json", 1, cases[:1])]:
    (man / name).write_text(json.dumps({
        "schema_version": 1, "hdi_version": "0.1.0", "created": "2026-11-26T08:00:00Z",
        "cases_per_task": cpt, "cases": cs}))
(man / "submissions.json").write_text(json.dumps(
    [{"job_id": 17, "offset": 0, "tasks": 2, "submitted": "2026-11-26T08:00:01Z"}]))
for d in sorted(OUT.iterdir()):
    files = list(d.iterdir())
    print(f"{d.name}: {len(files)} files, {sum(f.stat().st_size for f in files)} bytes")
