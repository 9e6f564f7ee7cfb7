//! The calibration's rounds of cases on Slurm (docs/slurm.md, "Calibration on Slurm"): the fit's
//! driver runs in the submitting `hdi run --executor slurm`, each round of cases goes out as a
//! case manifest and array jobs, and the outputs must equal a local run's byte for byte. A
//! fake scheduler (`sbatch` runs the tasks at once) for CI; the real single-node Slurm opt-in.
use crate::common::*;
use crate::slurm_cli::{fake_slurm, run_with};

/// The shipped test pipeline's calibration and what it consumes (the base sweep included:
/// the sweep's own cases then go out first, as `hdi run --executor slurm` does).
fn calibration_config(full: &str) -> String {
    // …and the tests' `[report]` settings (no validation table: seconds per run here).
    let keep = [
        "[dmw.disk_md]",
        "[contact.improved]",
        "[simulate.improved_sweep]",
        "[calibrate.improved_calibration]",
        "[report]",
    ];
    let mut out = String::new();
    let mut on = false;
    for line in full.lines() {
        if line.starts_with('[') {
            on = keep.iter().any(|s| line.starts_with(s));
        }
        if on {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// Every output file of the calibration, by name.
const OUTPUTS: [&str; 7] = [
    "result.json",
    "calibration.csv",
    "calibration.parquet",
    "knobs.csv",
    "calibration.log",
    "convergence.png",
    "residuals.png",
];

fn outputs(p: &Project) -> Vec<(&'static str, Vec<u8>)> {
    let dir = p.processed().join("improved_calibration");
    OUTPUTS
        .iter()
        .map(|f| (*f, std::fs::read(dir.join(f)).unwrap_or_default()))
        .collect()
}

fn assert_same_outputs(local: &[(&str, Vec<u8>)], remote: &[(&str, Vec<u8>)]) {
    for ((name, a), (_, b)) in local.iter().zip(remote) {
        assert!(!a.is_empty(), "local {name} missing");
        assert!(a == b, "{name} differs between the local and the Slurm run");
    }
}

/// `(rounds, submitted rounds, cases, submitted cases)` from the summary line.
fn round_counts(stderr: &str) -> (usize, usize, usize, usize) {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("slurm: calibration rounds: "))
        .unwrap_or_else(|| panic!("no rounds line in:\n{stderr}"));
    let nums: Vec<usize> = line
        .split(|c: char| !c.is_ascii_digit() && c != '.')
        .filter(|s| !s.is_empty() && !s.contains('.'))
        .map(|s| s.parse().unwrap())
        .collect();
    // "rounds: R (S submitted, W s waiting), cases: C (D submitted)"; W has a dot.
    assert_eq!(nums.len(), 4, "{line}");
    (nums[0], nums[1], nums[2], nums[3])
}

#[test]
fn slurm_calibration_rounds_equal_local_and_rerun_from_the_store() {
    let local = Project::shipped();
    let config = calibration_config(&local.config());
    local.set_config(&config);
    assert_ok(&local.run(&["run"]));
    let want = outputs(&local);
    let r: serde_json::Value = serde_json::from_slice(&want[0].1).unwrap();
    let cases = r["cases"].as_u64().unwrap() as usize;

    let remote = Project::shipped();
    remote.set_config(&config);
    let bin = remote.path().join("bin");
    fake_slurm(&bin, None);
    let o = run_with(
        &remote,
        &bin,
        &["run", "--executor", "slurm", "--cases-per-task", "2"],
    );
    assert_ok(&o);
    assert_same_outputs(&want, &outputs(&remote));
    // Every case of the fit went out in some round (the fit reuses nothing across rounds
    // that the local run would not), and rounds are what the driver asked for.
    let (rounds, submitted, asked, sent) = round_counts(&stderr(&o));
    assert_eq!(asked, cases, "{}", stderr(&o));
    assert_eq!(rounds, submitted, "a fresh store has nothing cached");
    assert_eq!(sent, cases);
    assert!(rounds >= 5, "{rounds} rounds");
    // The rounds are case manifests of kind `calibration` beside the sweep's.
    let manifests = remote.processed().join(".hdi/slurm/manifests");
    let calibration_manifests: Vec<String> = std::fs::read_dir(&manifests)
        .unwrap()
        .filter_map(|e| std::fs::read_to_string(e.unwrap().path()).ok())
        .filter(|t| t.contains("\"kind\":\"calibration\""))
        .collect();
    assert_eq!(calibration_manifests.len(), rounds);
    // Their recipes are the one envelope with the calibration's own case type.
    assert_matches_schema("case-manifest", &calibration_manifests[0]);

    // A forced rerun finds every case in the store: no submission, the same bytes.
    let o = run_with(
        &remote,
        &bin,
        &[
            "run",
            "--executor",
            "slurm",
            "--force",
            "--only",
            "improved_calibration",
        ],
    );
    assert_ok(&o);
    let (rounds2, submitted2, asked2, _) = round_counts(&stderr(&o));
    assert_eq!((rounds2, submitted2, asked2), (rounds, 0, cases));
    assert_same_outputs(&want, &outputs(&remote));
}

#[test]
fn a_lost_calibration_task_fails_the_stage_instead_of_the_point() {
    let p = Project::shipped();
    p.set_config(&calibration_config(&p.config()));
    // The sweep locally first, so the first submission is a calibration round.
    assert_ok(&p.run(&["run", "--only", "improved_sweep"]));
    let bin = p.path().join("bin");
    fake_slurm(&bin, Some(0));
    let o = run_with(&p, &bin, &["run", "--executor", "slurm"]);
    assert!(!o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("a round of calibration cases did not come back")
            && e.contains("task ended FAILED"),
        "{e}"
    );
    // Nothing of the void fit was stored as the stage's result.
    assert!(!p.processed().join("improved_calibration").exists());
    // `hdi status` lists the lost case like any other failed Slurm case.
    let st = run_with(&p, &bin, &["status"]);
    assert!(stdout(&st).contains("failed cases in"), "{}", stdout(&st));
}

/// Real single-node Slurm (opt-in `HDI_SLURM_TESTS=1`, `scripts/slurm-local-up.sh`; `.ci/run`'s
/// `real_slurm` filter): the test calibration's rounds as real arrays, outputs identical to
/// the local run.
#[test]
fn real_slurm_calibration_round() {
    if std::env::var("HDI_SLURM_TESTS").as_deref() != Ok("1") {
        eprintln!(
            "skipped: set HDI_SLURM_TESTS=1 with a running Slurm (scripts/slurm-local-up.sh)"
        );
        return;
    }
    let local = Project::shipped();
    let config = calibration_config(&local.config());
    local.set_config(&config);
    assert_ok(&local.run(&["run"]));
    let want = outputs(&local);

    let remote = Project::shipped();
    remote.set_config(&config);
    let no_bin = remote.path().join("no-fakes");
    let o = run_with(&remote, &no_bin, &["run", "--executor", "slurm"]);
    assert_ok(&o);
    let (rounds, submitted, _, sent) = round_counts(&stderr(&o));
    assert!(rounds >= 1 && submitted >= 1 && sent >= 1, "{}", stderr(&o));
    assert_same_outputs(&want, &outputs(&remote));
}
