"""Independent writers for hdi's .ibw and .sdf reader tests (run once; outputs are committed).

Written from the public format descriptions, not from hdi's Rust code:
* Igor binary wave v5: WaveMetrics Technical Note PTN003 (BinHeader5 = 64 bytes,
  WaveHeader5 = 320 bytes, data column-major, then formula, note, extended units, labels
  of 32 bytes each, the first label of a dimension naming the dimension itself).
* SDF binary: ISO 25178-71 / BCR "bBCR-1.0" header of 81 bytes (little-endian), DataType
  5 = int16 with -32768 marking an invalid point.

Also prints the reference values (numpy) the Rust tests assert, and those of the
SurfaceTopography sample `spot_1-1000nm.ibw` as read by the independent `igor2` package.
Requires: numpy, igor2 (pip install numpy igor2).
"""
import struct
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent


def ibw_v5(path, data, endian, type_code, sfa, data_units, dim_units, labels, note):
    """data: numpy array indexed [x, y, layer] (Igor dim order)."""
    nx, ny, nl = data.shape
    raw = data.astype(data.dtype.newbyteorder(endian)).tobytes(order="F")  # column-major
    note_b = note.encode("latin-1")
    # Dimension 2 labels: the dimension's own label, then one per layer, 32 bytes each.
    lab = b"".join(s.encode().ljust(32, b"\0") for s in ["Layers"] + labels)
    wave_header = bytearray(320)
    struct.pack_into(endian + "i", wave_header, 12, nx * ny * nl)  # npnts
    struct.pack_into(endian + "h", wave_header, 16, type_code)
    struct.pack_into(endian + "h", wave_header, 26, 1)  # whVersion
    wave_header[28:28 + 8] = b"testwave"
    struct.pack_into(endian + "4i", wave_header, 68, nx, ny, nl, 0)  # nDim
    struct.pack_into(endian + "4d", wave_header, 84, *sfa, 1.0, 1.0)  # sfA
    struct.pack_into(endian + "4d", wave_header, 116, 0.0, 0.0, 0.0, 0.0)  # sfB
    wave_header[148:148 + len(data_units)] = data_units.encode()
    for d, u in enumerate(dim_units):
        wave_header[152 + 4 * d:152 + 4 * d + len(u)] = u.encode()
    bin_header = struct.pack(
        endian + "hhiiii4i4iiii",
        5, 0, 320 + len(raw), 0, len(note_b), 0, 0, 0, 0, 0, 0, 0, len(lab), 0, 0, 0, 0,
    )
    assert len(bin_header) == 64
    path.write_bytes(bin_header + bytes(wave_header) + raw + note_b + lab)


def main():
    rng = np.random.default_rng(20261125)
    # 8 x (x) by 6 (y) by 3 layers, big-endian int16, heights in nm as the data unit.
    data = rng.integers(-3000, 3000, size=(8, 6, 3)).astype(np.int16)
    ibw_v5(
        HERE / "igor_be_int16_3layers.ibw", data, ">", 0x10, (2e-9, 3e-9),
        "nm", ["m", "m", "", ""], ["AmplitudeRetrace", "HeightRetrace", "ZSensorRetrace"],
        "ScanSize: 1.6e-08\rImagingMode: AC Mode\r",
    )
    for k, name in enumerate(["AmplitudeRetrace", "HeightRetrace", "ZSensorRetrace"]):
        z = data[:, :, k].astype(float) * 1e-9
        # hdi row 0 = top = Igor line ny-1.
        print(f"ibw {name}: sigma = {z.std():.17e} m, top-left = {z[0, -1]:.17e}, "
              f"bottom-right = {z[-1, 0]:.17e}")

    # Binary SDF: 9 points x 5 profiles, int16, Zscale 1 nm, one invalid point.
    z = rng.integers(-500, 500, size=(5, 9)).astype("<i2")
    z[2, 3] = -32768
    header = struct.pack(
        "<8s10s12s12sHHddddBBB", b"bBCR-1.0", b"hdi-test", b"251120262100",
        b"251120262100", 9, 5, 0.5e-6, 0.25e-6, 1e-9, 1e-9, 0, 5, 0,
    )
    assert len(header) == 81
    (HERE / "bcr_binary_int16.sdf").write_bytes(header + z.tobytes() + b"*")
    valid = z.astype(float)[z != -32768] * 1e-9
    print(f"sdf: n_valid = {valid.size}, sigma = {valid.std():.17e} m, z[0,0] = {z[0,0]*1e-9:.17e}, "
          f"z[4,8] = {z[4,8]*1e-9:.17e}")

    # SurfaceTopography's sample as igor2 reads it (independent of hdi).
    from igor2 import binarywave
    w = binarywave.load(str(HERE / "spot_1-1000nm.ibw"))["wave"]
    d = w["wData"].astype(float)
    h = d[:, :, 1]  # HeightRetrace (labels: HeightTrace, HeightRetrace, ...)
    print("spot HeightTrace sigma =", f"{d[:, :, 0].std():.17e}")
    print("spot HeightRetrace sigma =", f"{h.std():.17e}",
          f"top-left {h[0, -1]:.17e} bottom-left {h[0, 0]:.17e} (x=10,line=20) {h[10, 20]:.17e}")
    w10 = binarywave.load(str(HERE / "10x10-one_channel_without_name.ibw"))["wave"]["wData"]
    print("10x10: sigma =", f"{w10[:, :, 0].astype(float).std():.17e}",
          f"top-left {float(w10[0, -1, 0]):.17e} [x=3, line=7] {float(w10[3, 7, 0]):.17e}")


if __name__ == "__main__":
    main()
