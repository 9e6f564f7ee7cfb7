"""Writes python-zipfile.zip with CPython's zipfile module (an independent ZIP writer) for
the tests of src/formats/zip.rs: a stored member, a deflated member and a ZIP64 member
(force_zip64=True, as numpy.savez writes its members). Fixed timestamps: reproducible bytes."""
import zipfile

with zipfile.ZipFile("python-zipfile.zip", "w") as z:
    info = zipfile.ZipInfo("a.txt", date_time=(2026, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_STORED
    z.writestr(info, b"hello\n" * 3)
    info = zipfile.ZipInfo("b.bin", date_time=(2026, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_DEFLATED
    z.writestr(info, bytes(range(256)) * 4)
    info = zipfile.ZipInfo("dir/c64.bin", date_time=(2026, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_DEFLATED
    with z.open(info, "w", force_zip64=True) as f:
        f.write(bytes([7]) * 1000)
