"""Writes one small LDV record in every format hdi reads, with independent writers:
the CSV with Python's csv module, UFF58/58b with pyuff, Arrow IPC/Feather v2 with pyarrow,
.npy/.npz with numpy, WAV with Python's wave module (PCM int) and scipy.io.wavfile (float).

The record: 4200 samples at 100 kHz from t0 = 0.125 s, four revolutions of a disk at 6000 rpm
(1000 samples each). velocity_V is a sum of harmonics of 100 Hz, quantised to 2^-10 V so that
every format's text rendering (UFF double: 12 significant digits) is exact; index_V is a
0.02 V baseline with a 4.9 V (quantised) pulse of 5 samples at the start of each revolution.
Run: python3 make_ldv_formats.py (numpy 2.4, pyarrow 26, pyuff 2.5, scipy 1.17).
"""
import csv
import struct
import wave

import numpy as np
import pyarrow as pa
import pyarrow.feather as feather
import pyarrow.ipc as ipc
import pyuff
import scipy.io.wavfile

N, FS, T0 = 4200, 100e3, 0.125
i = np.arange(N)
t = T0 + i / FS
v = sum(a * np.sin(2 * np.pi * 100 * h * i / FS + p)
        for h, a, p in [(1, 0.2, 0.3), (7, 0.05, 1.1), (23, 0.02, 2.0), (61, 0.01, 0.4)])
v = np.round(v * 1024) / 1024
idx = np.where((i - 100) % 1000 < 5, np.round(4.9 * 1024) / 1024, np.round(0.02 * 1024) / 1024)
idx[:100] = np.round(0.02 * 1024) / 1024
META = {"sample_rate": "100000", "sensitivity": "0.025", "rpm": "6000"}

# CSV (the reference the other formats are compared with).
with open("record.csv", "w", newline="") as f:
    f.write("# sensitivity = 0.025\n# rpm = 6000\n")
    w = csv.writer(f)
    w.writerow(["time_s", "velocity_V", "index_V"])
    for row in zip(t, v, idx):
        w.writerow([repr(float(x)) for x in row])


# UFF 58 (ASCII double, ASCII single, ASCII uneven) and 58b (binary double).
def uff(name, binary, single=False, even=True, ids=("velocity", "index")):
    sets = []
    for k, (data, ident) in enumerate([(v, ids[0]), (idx, ids[1])]):
        d = pyuff.prepare_58(
            binary=binary, id1=ident, id2="hdi test record", func_type=1, rsp_node=k + 1,
            rsp_dir=3, ref_node=0, ref_dir=0, data=data, x=t, spec_data_type=0,
            abscissa_spacing=1 if even else 0, abscissa_spec_data_type=17,
            abscissa_axis_units_lab="s", ordinate_spec_data_type=0,
            ordinate_axis_units_lab="V", orddenom_spec_data_type=0, z_axis_spec_data_type=0)
        if single:
            d["ord_data_type"] = 2
        sets.append(d)
    # pyuff writes double precision unless force_double=False. Its binary writer reopens the
    # file in "wb" mode for mode="overwrite", which drops what it wrote before: start from an
    # empty file and append every set.
    open(name, "w").close()
    u = pyuff.UFF(name)
    u.write_sets(sets, mode="add", force_double=not single)


uff("record_ascii.uff", 0)
uff("record_ascii_single.uff", 0, single=True)
uff("record_ascii_uneven.uff", 0, even=False)
uff("record_binary.uff", 1)
uff("record_binary_noname.uff", 1, ids=("Point 1 +Z", "Point 2 +Z"))

# Arrow IPC: uncompressed file, Feather v2 with pyarrow's default LZ4, ZSTD, and a stream.
table = pa.table({"time_s": t, "velocity_V": v, "index_V": idx}).replace_schema_metadata(META)
feather.write_feather(table, "record_plain.arrow", compression="uncompressed")
feather.write_feather(table, "record_lz4.feather")
feather.write_feather(table, "record_zstd.feather", compression="zstd")
with ipc.new_stream("record_stream.arrows", table.schema) as s:
    s.write_table(table, max_chunksize=1000)
f32 = pa.table({"velocity_V": pa.array(v, pa.float32()), "index_V": pa.array(idx, pa.float32())})
f32 = f32.replace_schema_metadata(META | {"t0": "0.125"})
feather.write_feather(f32, "record_f32.feather", compression="uncompressed")

# NumPy: (n, 3) C order, Fortran order, big-endian, structured, 1-D; .npz stored and deflated.
np.save("record_c.npy", np.stack([t, v, idx], axis=1))
np.save("record_fortran.npy", np.asfortranarray(np.stack([t, v, idx], axis=1)))
np.save("record_be.npy", np.stack([t, v, idx], axis=1).astype(">f8"))
st = np.zeros(N, dtype=[("time", "<f8"), ("velocity", "<f4"), ("index", "<f8")])
st["time"], st["velocity"], st["index"] = t, v, idx
np.save("record_structured.npy", st)
np.save("record_velocity.npy", v)
np.savez("record.npz", time=t, velocity=v, index=idx)
np.savez_compressed("record_deflate.npz", velocity=v, index=idx, sample_rate=FS, t0=T0)


# WAV: velocity on channel 0, index/5 on channel 1 (PCM full scale is ±1).
def pcm(name, width):
    full = 2 ** (8 * width - 1)
    data = np.stack([v, idx / 5], axis=1)
    q = np.clip(np.round(data * full), -full, full - 1).astype("<i8")
    with wave.open(name, "wb") as w:
        w.setnchannels(2)
        w.setsampwidth(width)
        w.setframerate(int(FS))
        w.writeframes(b"".join(int(x).to_bytes(width, "little", signed=True) for x in q.ravel()))


pcm("record_int16.wav", 2)
pcm("record_int24.wav", 3)
pcm("record_int32.wav", 4)
scipy.io.wavfile.write("record_f32.wav", int(FS), np.stack([v, idx], axis=1).astype(np.float32))
scipy.io.wavfile.write("record_f64.wav", int(FS), np.stack([v, idx], axis=1))
