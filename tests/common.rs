//! Shared helpers: a project copy in a temp dir and a way to run the real `hdi` binary.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn hdi() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hdi"))
}

pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The reference data the tests read (`tests/data`, provenance in its README.md); tests never
/// read outside the repository.
pub fn test_data() -> PathBuf {
    repo_root().join("tests").join("data")
}

/// A copy of the shipped pipeline.toml and raw/ in a fresh temp dir.
pub struct Project {
    pub dir: tempfile::TempDir,
}

impl Project {
    pub fn shipped() -> Self {
        let dir = tempfile::tempdir().expect("tempdir");
        copy_dir(&repo_root().join("raw"), &dir.path().join("raw"));
        // The shipped sweep (76 slider cases) is the main job's; the tests' unoptimised binary
        // runs four cases of it (0, 5, 10, 15 nm), enough for every pipeline behaviour.
        let text =
            std::fs::read_to_string(repo_root().join("pipeline.toml")).expect("read pipeline.toml");
        // (Their touchdowns stay on the 5 nm grid: refining to 0.02 nm would add ~12 cases a
        // branch; the refinement itself is tested on a small sweep in tests/simulate_cli.rs.)
        let text = text.replace(
            "actuation_step = \"0.2 nm\"",
            "actuation_step = \"5 nm\"\nrefine_touchdown = false",
        );
        // …and the heater-power sweep at four powers (0, 16, 32, 48 mW).
        let text = text.replace(
            "power_step = \"2 mW\"",
            "power_step = \"16 mW\"\nrefine_touchdown = false",
        );
        // …and a two-target, one-knob calibration of a few evaluations judged on three
        // held-out targets of the sweep grid (the shipped one runs ~7000 cases).
        let text = text.replace(
            "\nmax_evaluations = 400",
            "\nmax_evaluations = 3\nknobs = [\"dmw_scale\"]\ntargets = [\"clearance_8.5nm\", \"fhm_8.5nm\"]\nheld_out = [\"regime_solid_start\", \"full_contact_onset\", \"touchdown_clearance\"]",
        );
        // (The shipped warm start names all five knobs: the one-knob fit starts at the defaults.)
        let text: String = text
            .lines()
            .filter(|l| {
                !l.starts_with("start = {")
                    && !l.starts_with("initial_step = ")
                    && !l.starts_with("start_fitted_for = ")
            })
            .map(|l| format!("{l}\n"))
            .collect();
        // …and a DOE with a short annealing and coarse Table 2.8 sweeps (the design's 108
        // cases stay: they are what the stage is about).
        let text = text
            .replace("sa_max_evaluations = 400", "sa_max_evaluations = 12")
            .replace("compare_step = \"0.2 nm\"", "compare_step = \"3 nm\"");
        // …and the end-of-run HTML report without the validation table (seconds per fresh
        // project in a debug build; tests/report_cli.rs turns it on).
        let text = format!("{text}\n[report]\nvalidation = false\n");
        std::fs::write(dir.path().join("pipeline.toml"), text).expect("write pipeline.toml");
        Self { dir }
    }
    /// A copy of [`Project::shipped`] after one cold `hdi run`: the run is made once per test
    /// process and each caller gets its own copy (files copied, the store's relative links
    /// kept), so a test that damages or edits it touches nothing shared. For the tests whose
    /// subject is what happens *after* a completed run (a rerun, a broken input, a damaged
    /// entry, gc); the cold run itself is covered by the tests that make their own.
    pub fn shipped_after_run() -> Self {
        Self::shipped_with_cold_run().0
    }

    /// [`Project::shipped_after_run`] with the output of the shared cold run (`hdi run --jobs
    /// 2`, made once per test process).
    pub fn shipped_with_cold_run() -> (Self, Output) {
        static BASE: std::sync::OnceLock<(Project, Output)> = std::sync::OnceLock::new();
        let (base, output) = BASE.get_or_init(|| {
            let p = Project::shipped();
            let o = p.run(&["run", "--jobs", "2"]);
            assert!(o.status.success(), "{}", stderr(&o));
            (p, o)
        });
        let dir = tempfile::tempdir().expect("tempdir");
        copy_dir(base.path(), dir.path());
        (Self { dir }, output.clone())
    }
    pub fn path(&self) -> &Path {
        self.dir.path()
    }
    pub fn run(&self, args: &[&str]) -> Output {
        hdi()
            .current_dir(self.path())
            .args(args)
            .output()
            .expect("run hdi")
    }
    pub fn config(&self) -> String {
        std::fs::read_to_string(self.path().join("pipeline.toml")).unwrap()
    }
    pub fn set_config(&self, text: &str) {
        std::fs::write(self.path().join("pipeline.toml"), text).unwrap();
    }
    pub fn processed(&self) -> PathBuf {
        self.path().join("processed")
    }
}

/// `from` copied to `to` with its symbolic links recreated as links (the store's instance
/// links are relative, so they point into the copy).
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let (p, dest) = (e.path(), to.join(e.file_name()));
        let kind = e.file_type().unwrap();
        if kind.is_symlink() {
            std::os::unix::fs::symlink(std::fs::read_link(&p).unwrap(), &dest).unwrap();
        } else if kind.is_dir() {
            copy_dir(&p, &dest);
        } else {
            std::fs::copy(&p, &dest).unwrap();
        }
    }
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// Assert a failed run: non-zero exit, a one-line `error:` message containing `needle`, no panic.
pub fn assert_clean_failure(o: &Output, needle: &str) {
    let err = stderr(o);
    assert!(
        !o.status.success(),
        "expected failure, got success; stderr: {err}"
    );
    assert!(!err.contains("panicked"), "panic on user input: {err}");
    let error_lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(error_lines.len(), 1, "want exactly one error line: {err}");
    assert!(
        error_lines[0].contains(needle),
        "error line lacks `{needle}`: {err}"
    );
}

/// Every file under `dir` (following no links) with its content hash: to show nothing changed.
pub fn snapshot(dir: &Path) -> Vec<(String, String)> {
    let mut out = Vec::new();
    fn walk(root: &Path, d: &Path, out: &mut Vec<(String, String)>) {
        let Ok(rd) = std::fs::read_dir(d) else { return };
        for e in rd.flatten() {
            let p = e.path();
            let ft = e.file_type().unwrap();
            let rel = p.strip_prefix(root).unwrap().to_string_lossy().to_string();
            if ft.is_symlink() {
                out.push((
                    rel,
                    std::fs::read_link(&p)
                        .unwrap()
                        .to_string_lossy()
                        .to_string(),
                ));
            } else if ft.is_dir() {
                walk(root, &p, out);
            } else if !rel.ends_with("lock")
                && !rel.ends_with("input-hashes.json")
                // The report and the last run's record are views of a run, not results
                // (docs/report.md): a failed run rewrites them.
                && !rel.starts_with("report/")
                && rel != ".hdi/last-run.json"
            {
                let bytes = std::fs::read(&p).unwrap();
                out.push((rel, blake3::hash(&bytes).to_hex().to_string()));
            }
        }
    }
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// The project's Python (h5py, pyarrow), installed by scripts/setup.sh.
pub fn python() -> PathBuf {
    let p = repo_root().join(".venv").join("bin").join("python");
    assert!(
        p.exists(),
        "{} missing: run `bash scripts/setup.sh` first (the README's test command does)",
        p.display()
    );
    p
}

pub fn assert_ok(o: &std::process::Output) {
    assert!(o.status.success(), "hdi failed: {}{}", stdout(o), stderr(o));
}

/// Rows of a CSV written by hdi (no quoted commas in its tables).
pub fn csv_rows(path: &std::path::Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

/// Check a command's `--json` output against its documented schema `docs/schemas/<name>.json`
/// with the Python `jsonschema` package (an independent validator, Draft 2020-12), and that the
/// schema itself is valid. Panics with every violation and its JSON path.
pub fn assert_matches_schema(schema_name: &str, json_text: &str) {
    let schema = repo_root()
        .join("docs")
        .join("schemas")
        .join(format!("{schema_name}.json"));
    assert!(schema.exists(), "{} missing", schema.display());
    let dir = tempfile::tempdir().unwrap();
    let doc = dir.path().join("output.json");
    std::fs::write(&doc, json_text).unwrap();
    let script = r#"
import json, sys
from jsonschema import Draft202012Validator
schema = json.load(open(sys.argv[1]))
Draft202012Validator.check_schema(schema)
doc = json.load(open(sys.argv[2]))
errors = sorted(Draft202012Validator(schema).iter_errors(doc), key=lambda e: list(e.absolute_path))
for e in errors[:20]:
    print("/".join(str(p) for p in e.absolute_path) or "(root)", ":", e.message[:300])
sys.exit(1 if errors else 0)
"#;
    let out = Command::new(python())
        .arg("-c")
        .arg(script)
        .arg(&schema)
        .arg(&doc)
        .output()
        .expect("running python");
    assert!(
        out.status.success(),
        "output does not match {}:\n{}{}",
        schema.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `cases_cached` of the entry a `processed/<instance>` link points at: a fact of the run that
/// made it, kept in its `manifest.json` (`run_log`), not in the results.
pub fn cases_cached(instance_dir: &Path) -> u64 {
    let text = std::fs::read_to_string(instance_dir.join("manifest.json")).unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    m["run_log"]["cases_cached"]
        .as_u64()
        .unwrap_or_else(|| panic!("no run_log.cases_cached in {}", instance_dir.display()))
}
