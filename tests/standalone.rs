//! The repository stands alone: a clone with nothing beside it passes its tests. No source,
//! test, benchmark, doc or script reads or cites the project's machine-local reference-data
//! directory; the data the tests use is in tests/data, documented file by file in its README.

use crate::common::repo_root;
use std::path::{Path, PathBuf};

/// Written in two halves so that this file does not contain what it looks for.
const FORBIDDEN: [&str; 3] = [
    concat!("..", "/shared"),
    concat!("shared", "/data"),
    // A string literal that starts by leaving the crate root (CARGO_MANIFEST_DIR, then `/..`).
    concat!("\"/..", "/"),
];

/// Everything a clone ships that could read or cite files: code, tests and their data,
/// benchmarks, docs, CI and scripts (and the Python reference scripts in bench/).
const SCANNED_DIRS: [&str; 7] = ["src", "tests", "benches", "docs", ".ci", "scripts", "bench"];
const SCANNED_FILES: [&str; 3] = ["README.md", "Cargo.toml", "pipeline.toml"];

fn files_under(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.unwrap().path();
        // bench/.venv (made by bench/compare.sh) is installed packages, not the project's files.
        if path.is_dir() && path.file_name().is_some_and(|n| n == ".venv") {
            continue;
        }
        if path.is_dir() {
            files_under(&path, out);
        } else {
            out.push(path);
        }
    }
}

fn contains(haystack: &[u8], needle: &str) -> bool {
    haystack
        .windows(needle.len())
        .any(|w| w == needle.as_bytes())
}

#[test]
fn no_file_reads_or_cites_data_outside_the_repository() {
    let root = repo_root();
    let mut files: Vec<PathBuf> = SCANNED_FILES.iter().map(|f| root.join(f)).collect();
    for dir in SCANNED_DIRS {
        files_under(&root.join(dir), &mut files);
    }
    // The walk really covered the tree (a wrong root or an empty walk must not pass).
    assert!(files.len() > 100, "only {} files scanned", files.len());
    for must in [
        "src/lib.rs",
        "tests/common.rs",
        "tests/data/README.md",
        ".ci/run",
        "scripts/setup.sh",
    ] {
        assert!(files.contains(&root.join(must)), "{must} not scanned");
    }
    // …and the matcher finds what it should.
    for needle in FORBIDDEN {
        let line = format!("let p = concat!(env!(\"CARGO_MANIFEST_DIR\"), {needle}x);");
        assert!(contains(line.as_bytes(), needle), "{line}");
    }
    assert!(!contains(b"tests/data/isbl/initial_2dof.csv", FORBIDDEN[1]));

    let mut hits = Vec::new();
    for f in &files {
        let bytes = std::fs::read(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        for needle in FORBIDDEN {
            if contains(&bytes, needle) {
                let rel = f.strip_prefix(&root).unwrap_or(f);
                hits.push(format!("{}: {needle}", rel.display()));
            }
        }
    }
    assert!(
        hits.is_empty(),
        "files that reach outside the repository (use tests/data, see its README.md):\n{}",
        hits.join("\n")
    );
}

/// Every data file the tests read is documented in tests/data/README.md (what it is, where it
/// comes from, which tests use it).
#[test]
fn every_test_data_file_is_documented() {
    let data = repo_root().join("tests").join("data");
    let readme = std::fs::read_to_string(data.join("README.md")).expect("tests/data/README.md");
    let mut files = Vec::new();
    files_under(&data, &mut files);
    assert!(files.len() >= 13, "{} files in tests/data", files.len());
    for f in files {
        let name = f.file_name().unwrap().to_str().unwrap();
        if name != "README.md" {
            assert!(
                readme.contains(&format!("`{name}`")) || readme.contains(&format!("/{name}`")),
                "tests/data/README.md does not describe {}",
                f.display()
            );
        }
    }
}
