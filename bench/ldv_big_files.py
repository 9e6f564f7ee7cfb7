"""Writes 10^8-sample, two-channel (velocity, index) LDV records in the binary formats hdi
reads, for the memory/throughput probe `examples/ldv_read.rs` (docs/performance.md, "LDV
reader throughput"). Usage: python3 ldv_big_files.py DIR [N]. Needs numpy and pyarrow.
UFF 58b is written by hand in pyuff's layout (pyuff itself is too slow for 10^8 points);
UFF ASCII is written for N/10 samples (the text is 20 bytes per value)."""
import sys
import wave

import numpy as np
import pyarrow as pa
import pyarrow.feather as feather

out = sys.argv[1]
n = int(float(sys.argv[2])) if len(sys.argv) > 2 else 10**8
fs = 4e6
rng = np.random.default_rng(1)
v = np.round(0.3 * np.sin(np.arange(n) * 0.0137) * 1024) / 1024 + rng.normal(0, 1e-3, n)
idx = np.where(np.arange(n) % 44240 < 20, 4.9, 0.02)
meta = {"sample_rate": str(fs)}

np.save(f"{out}/big.npy", np.stack([v, idx], axis=1))
np.savez(f"{out}/big.npz", velocity=v, index=idx, sample_rate=fs)
feather.write_feather(
    pa.table({"velocity_V": v, "index_V": idx}).replace_schema_metadata(meta),
    f"{out}/big.arrow", compression="uncompressed")
feather.write_feather(
    pa.table({"velocity_V": v, "index_V": idx}).replace_schema_metadata(meta),
    f"{out}/big_lz4.feather")
with wave.open(f"{out}/big_int16.wav", "wb") as w:
    w.setnchannels(2)
    w.setsampwidth(2)
    w.setframerate(int(fs))
    w.writeframes((np.stack([v, idx / 5], axis=1) * 32767).astype("<i2").tobytes())


def uff_header(name, node, binary, count):
    head = "%6i\n%6i" % (-1, 58)
    if binary:
        head += "b%6i%6i%12i%12i%6i%6i%12i%12i\n" % (1, 2, 11, count * 8, 0, 0, 0, 0)
    else:
        head += "%74s\n" % " "
    head += "%-80s\n" % name + ("%-80s\n" % "NONE") * 4
    head += "%5i%10i%5i%10i %10s%10i%4i %10s%10i%4i\n" % (1, 0, 0, 0, "NONE", node, 3, "NONE", 0, 0)
    head += "%10i%10i%10i%13.5e%13.5e%13.5e\n" % (4, count, 1, 0.0, 1 / fs, 0.0)
    head += "%10i%5i%5i%5i %-20s %-20s\n" % (17, 0, 0, 0, "NONE", "s")
    head += "%10i%5i%5i%5i %-20s %-20s\n" % (0, 0, 0, 0, "NONE", "V")
    head += ("%10i%5i%5i%5i %-20s %-20s\n" % (0, 0, 0, 0, "NONE", "NONE")) * 2
    return head.encode()


with open(f"{out}/big_binary.uff", "wb") as f:
    for k, (name, data) in enumerate([("velocity", v), ("index", idx)]):
        f.write(uff_header(name, k + 1, True, n))
        f.write(data.astype("<f8").tobytes())
        f.write(b"    -1\n")
m = n // 10
with open(f"{out}/big_ascii.uff", "wb") as f:
    for k, (name, data) in enumerate([("velocity", v[:m]), ("index", idx[:m])]):
        f.write(uff_header(name, k + 1, False, m))
        np.savetxt(f, data.reshape(-1, 4) if m % 4 == 0 else data, fmt="%20.11e", delimiter="")
        f.write(b"    -1\n")
