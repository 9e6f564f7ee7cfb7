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

/// Once per process, before fuzzing: HDF5 inputs are read in a child process
/// (`hdi::formats::isolated`), and its time limit goes to 0.5 s, so that the `ldv` target's
/// two reads of one input stay below AFL's hang threshold (2 s in scripts/fuzz.sh): libhdf5
/// spinning on a crafted file is then the clean error hdi gives users, not a hang.
pub fn setup() {
    hdi::formats::isolated::set_time_limit(Some(std::time::Duration::from_millis(500)));
}

/// Whether the fuzz targets hand HDF5 files (`.datx` maps, `.h5` records) to the readers: yes
/// unless `HDI_FUZZ_HDF5=0`. Each HDF5 input costs a fork and libhdf5's own work, so `0` spends
/// a run on hdi's other readers. (Before the readers ran libhdf5 in a child, its crashes on
/// crafted files aborted the targets, and HDF5 was off by default; docs/reliability.md.)
pub fn hdf5_enabled() -> bool {
    static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ON.get_or_init(|| std::env::var_os("HDI_FUZZ_HDF5").is_none_or(|v| v != "0"))
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
