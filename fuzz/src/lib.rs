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
