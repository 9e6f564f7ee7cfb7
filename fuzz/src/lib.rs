//! What the fuzz targets share: the readers take a path, so each input is written to a file
//! first (in a per-process directory under `$TMPDIR`; scripts/fuzz.sh points it at /dev/shm).
use std::path::{Path, PathBuf};

/// A scratch directory for this process, made once.
pub fn scratch_dir() -> &'static Path {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("hdi-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch directory for the fuzz input");
        dir
    })
}

/// Writes `data` to `name` in the scratch directory and returns its path. A failing write is
/// the harness's fault, not the reader's: it aborts (AFL reports it as a crash).
pub fn input_file(name: &str, data: &[u8]) -> PathBuf {
    let path = scratch_dir().join(name);
    std::fs::write(&path, data).expect("write the fuzz input");
    path
}

/// Whether the fuzz targets hand HDF5 files (`.datx` maps, `.h5` records) to the readers.
/// Off by default: Debian's libhdf5 (1.10.8) crashes on crafted files inside the C library
/// (out-of-bounds reads in its heap code, invalid frees on close; docs/reliability.md), which
/// hdi cannot catch, and those crashes would drown the readers' own findings. Set
/// `HDI_FUZZ_HDF5=1` to fuzz through libhdf5 as well.
pub fn hdf5_enabled() -> bool {
    static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ON.get_or_init(|| std::env::var_os("HDI_FUZZ_HDF5").is_some_and(|v| v == "1"))
}

/// HDF5's signature at offset 0 or after a user block of 512·2^k bytes, where the readers'
/// detection looks for it (`dmw::io::detect_format`).
pub fn is_hdf5(data: &[u8]) -> bool {
    const MAGIC: &[u8; 8] = b"\x89HDF\r\n\x1a\n";
    let mut offset = 0usize;
    while offset + 8 <= data.len() && offset <= 1 << 20 {
        if &data[offset..offset + 8] == MAGIC {
            return true;
        }
        offset = if offset == 0 { 512 } else { offset * 2 };
    }
    false
}

/// Inputs the targets pass over (see [`hdf5_enabled`]).
pub fn skip(data: &[u8]) -> bool {
    !hdf5_enabled() && is_hdf5(data)
}
