//! Fast versions of the fault campaigns (scripts/faults/, docs/reliability.md "Fault
//! campaigns") for the behaviours they made hdi fix: a read-only `processed/` and a disk that
//! fills mid-run each give one clear error naming the cause, the instance and the path; nothing
//! half-written is trusted (`hdi verify --all` stays clean); the next run with access or space
//! completes with the same results.
//!
//! A read-only directory needs a read-only bind mount when running as root (root ignores
//! permission bits) and `chmod a-w` otherwise; the disk-full test needs root for its tmpfs.
//! Where the test cannot set the fault up it prints why and returns.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

const PIPELINE: &str = r#"[project]
name = "faults test"

[surface.disk]
file = "raw/afm/disk_dlc_1um.gwy"

[surface.slider]
file = "raw/afm/slider_tfc_1um.spm"
filter_s = "16 nm"

[interface.hdi]
surfaces = ["disk", "slider"]
rule = "sum_surface"

[report]
validation = false
"#;

fn project() -> Project {
    let dir = tempfile::tempdir().expect("tempdir");
    copy_dir(&repo_root().join("raw/afm"), &dir.path().join("raw/afm"));
    std::fs::write(dir.path().join("pipeline.toml"), PIPELINE).unwrap();
    Project { dir }
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

/// Unmounts on drop, so a failed assertion does not leave a mount behind.
struct Mount(PathBuf);
impl Drop for Mount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

fn mount(args: &[&str]) -> bool {
    Command::new("mount")
        .args(args)
        .status()
        .is_ok_and(|s| s.success())
}

/// The result and bookkeeping files a failed run must not change (the run's views, the report
/// and `.hdi/last-run.json`, are excluded by `snapshot`).
fn state(p: &Project) -> Vec<(String, String)> {
    snapshot(&p.processed())
}

fn make_disk_stale(p: &Project) {
    let old = "[surface.disk]\nfile = \"raw/afm/disk_dlc_1um.gwy\"\n";
    p.set_config(
        &p.config()
            .replace(old, &format!("{old}filter_l = \"250 nm\"\n")),
    );
}

#[test]
fn a_read_only_processed_dir_fails_clearly_and_changes_nothing() {
    let p = project();
    assert_ok(&p.run(&["run"]));
    make_disk_stale(&p);
    let processed = p.processed();
    let root = is_root();
    let _guard = if root {
        let dir = processed.to_string_lossy().to_string();
        if !(mount(&["--bind", &dir, &dir]) && mount(&["-o", "remount,bind,ro", &dir])) {
            let _ = Command::new("umount").arg(&dir).status();
            eprintln!("skipped: cannot make a read-only bind mount here");
            return;
        }
        Some(Mount(processed.clone()))
    } else {
        chmod_tree(&processed, false);
        None
    };
    let before = state(&p);
    let o = p.run(&["run"]);
    let (cause, needle) = if root {
        ("is on a read-only filesystem", "Read-only file system")
    } else {
        ("permission denied writing to", "Permission denied")
    };
    assert_clean_failure(&o, cause);
    let err = stderr(&o);
    assert!(err.contains(needle), "{err}");
    assert!(err.contains(".hdi/lock"), "the error names the path: {err}");
    assert_eq!(state(&p), before, "a refused run changed processed/");
    // Reading still works: status says the disk is stale (exit 1), verify finds no damage.
    let st = p.run(&["status"]);
    assert_eq!(st.status.code(), Some(1), "{}", stderr(&st));
    assert!(stdout(&st).contains("stale    disk"), "{}", stdout(&st));
    assert_ok(&p.run(&["verify"]));
    drop(_guard);
    if !root {
        chmod_tree(&processed, true);
    }
    assert_ok(&p.run(&["run"]));
    assert_ok(&p.run(&["status"]));
}

/// `chmod -R a-w` (or `u+w`) on the directories under `dir`.
fn chmod_tree(dir: &Path, writable: bool) {
    let mode = if writable { "u+w" } else { "a-w" };
    let ok = Command::new("find")
        .arg(dir)
        .args(["-type", "d", "-exec", "chmod", mode, "{}", "+"])
        .status()
        .unwrap()
        .success();
    assert!(ok);
}

#[test]
fn a_disk_that_fills_mid_run_names_the_instance_and_trusts_nothing_half_written() {
    if !is_root() {
        eprintln!("skipped: a tmpfs for processed/ needs root");
        return;
    }
    // The clean run's result files, for the comparison at the end.
    let clean = project();
    assert_ok(&clean.run(&["run"]));
    let results = |p: &Project| -> Vec<(String, String)> {
        snapshot(&p.processed())
            .into_iter()
            .filter(|(rel, _)| !rel.starts_with(".hdi/") || rel.starts_with(".hdi/store/"))
            .filter(|(rel, _)| !rel.ends_with("manifest.json"))
            .filter(|(rel, _)| !rel.starts_with("report/"))
            .collect()
    };
    let reference = results(&clean);

    let p = project();
    let processed = p.processed();
    std::fs::create_dir_all(&processed).unwrap();
    let dir = processed.to_string_lossy().to_string();
    // 256 KiB: the store's directories fit, the first surface's HDF5 and plots do not.
    if !mount(&["-t", "tmpfs", "-o", "size=256k", "tmpfs", &dir]) {
        eprintln!("skipped: cannot mount a tmpfs here");
        return;
    }
    let _guard = Mount(processed.clone());
    let o = p.run(&["run", "-j", "1"]);
    let err = stderr(&o);
    assert!(!o.status.success(), "the run fit in 256 KiB: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_else(|| panic!("no error line: {err}"));
    assert!(line.contains("no space left on device"), "{err}");
    assert!(
        line.contains("stage `"),
        "the error names the instance: {err}"
    );
    assert!(
        line.contains("processed/.hdi/tmp/"),
        "the error names the path: {err}"
    );
    // Nothing half-written is in the store, and the work dirs were cleaned up.
    let v = p.run(&["verify", "--all"]);
    assert_ok(&v);
    assert!(!stdout(&v).contains("leftover"), "{}", stdout(&v));
    // With space the next run completes, with the clean run's results.
    assert!(mount(&["-o", "remount,size=64m", &dir]));
    assert_ok(&p.run(&["run"]));
    assert_eq!(results(&p), reference);
    assert_ok(&p.run(&["verify"]));
}
