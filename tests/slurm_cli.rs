//! `hdi run --executor slurm` against a fake scheduler (no cluster needed): `sbatch` runs
//! every array task at once through the job script, `squeue` shows an empty queue and `sacct`
//! reports each task's state. The sweep table must equal the local executor's, a rerun must
//! submit nothing, and a failed task's cases are the only ones resubmitted.
use crate::common::*;
use std::path::Path;

/// The shipped sections a slurm sweep needs: the DMW, the contact set and one sweep.
fn sweep_only_config(full: &str) -> String {
    sections(
        full,
        &[
            "[dmw.disk_md]",
            "[contact.improved]",
            "[simulate.improved_sweep]",
        ],
    )
}

/// The shipped sections whose headers start with one of `keep_headers`.
fn sections(full: &str, keep_headers: &[&str]) -> String {
    let mut out = String::new();
    let mut keep = false;
    for line in full.lines() {
        if line.starts_with('[') {
            keep = keep_headers.iter().any(|s| line.starts_with(s));
        }
        if keep {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// Fake `sbatch`/`squeue`/`sacct` in `bin/`. `FAIL_TASK` (an array task id) makes that task
/// exit 1 before computing anything.
fn fake_slurm(bin: &Path, fail_task: Option<usize>) {
    std::fs::create_dir_all(bin).unwrap();
    let fail = fail_task.map_or("-1".to_string(), |t| t.to_string());
    let sbatch = format!(
        r#"#!/bin/sh
# fake sbatch --parsable SCRIPT: run every array task now, in the script's --chdir
script="$2"
dir=$(dirname "$0")
spec=$(sed -n 's/^#SBATCH --array=\([0-9]*-[0-9]*\).*/\1/p' "$script")
chdir=$(sed -n 's/^#SBATCH --chdir=//p' "$script")
id=$(( $(cat "$dir/next_id" 2>/dev/null || echo 4241) + 1 ))
echo $id > "$dir/next_id"
i=${{spec%-*}}
: > "$dir/sacct_$id"
while [ "$i" -le "${{spec#*-}}" ]; do
  if [ "$i" -eq {fail} ]; then
    echo "${{id}}_$i|FAILED|1:0" >> "$dir/sacct_$id"
  elif (cd "$chdir" && SLURM_ARRAY_JOB_ID=$id SLURM_ARRAY_TASK_ID=$i sh "$script") > "$dir/task_${{id}}_$i.log" 2>&1; then
    echo "${{id}}_$i|COMPLETED|0:0" >> "$dir/sacct_$id"
  else
    echo "${{id}}_$i|FAILED|1:0" >> "$dir/sacct_$id"
  fi
  i=$((i + 1))
done
echo $id
"#
    );
    let squeue = "#!/bin/sh\nexit 0\n";
    let sacct = "#!/bin/sh\n# sacct -n -P -j ID -o ...\ndir=$(dirname \"$0\")\nwhile [ $# -gt 0 ]; do [ \"$1\" = -j ] && id=$2; shift; done\ncat \"$dir/sacct_$id\"\n";
    for (name, text) in [
        ("sbatch", sbatch.as_str()),
        ("squeue", squeue),
        ("sacct", sacct),
    ] {
        let p = bin.join(name);
        std::fs::write(&p, text).unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}

fn run_with(p: &Project, bin: &Path, args: &[&str]) -> std::process::Output {
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    hdi()
        .current_dir(p.path())
        .env("PATH", path)
        .env("HDI_SLURM_POLL_MS", "10")
        .args(args)
        .output()
        .expect("run hdi")
}

#[test]
fn slurm_sweep_equals_local_and_resubmits_only_failures() {
    let local = Project::shipped();
    let config = sweep_only_config(&local.config());
    local.set_config(&config);
    assert_ok(&local.run(&["run"]));
    let local_table = std::fs::read(local.processed().join("improved_sweep/sweep.csv")).unwrap();

    // A failing task first: its cases are reported and stay missing, the others are cached.
    let remote = Project::shipped();
    remote.set_config(&config);
    let bin = remote.path().join("bin");
    fake_slurm(&bin, Some(0));
    let o = run_with(
        &remote,
        &bin,
        &["run", "--executor", "slurm", "--cases-per-task", "1"],
    );
    assert!(!o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("4 cases in 4 tasks submitted"), "{e}");
    assert!(e.contains("1 case(s) failed on Slurm"), "{e}");
    assert!(e.contains("task ended FAILED"), "{e}");
    let st = run_with(&remote, &bin, &["status"]);
    assert!(stdout(&st).contains("failed cases in"), "{}", stdout(&st));
    // While a submitted manifest still misses cases, gc leaves tmp/ (tasks' work dirs) alone.
    let work = remote.processed().join(".hdi/tmp/case-running-task");
    std::fs::create_dir_all(&work).unwrap();
    assert_ok(&run_with(&remote, &bin, &["gc"]));
    assert!(
        work.is_dir(),
        "gc removed a work dir while Slurm cases were missing"
    );

    // The rerun submits only the missing case, then finishes the pipeline locally.
    fake_slurm(&bin, None);
    let o = run_with(
        &remote,
        &bin,
        &["run", "--executor", "slurm", "--cases-per-task", "1"],
    );
    assert_ok(&o);
    let e = stderr(&o);
    assert!(e.contains("1 cases in 1 tasks submitted"), "{e}");
    let remote_table = std::fs::read(remote.processed().join("improved_sweep/sweep.csv")).unwrap();
    assert_eq!(
        local_table, remote_table,
        "slurm and local sweep tables differ"
    );
    // Every case is in: gc cleans tmp/ again and keeps the cases.
    assert_ok(&run_with(&remote, &bin, &["gc"]));
    assert!(
        !work.exists(),
        "gc kept a stale work dir after the cases were in"
    );

    // Nothing left to submit.
    let o = run_with(&remote, &bin, &["run", "--executor", "slurm"]);
    assert_ok(&o);
    let e = stderr(&o);
    assert!(
        e.contains("no stale [simulate], [doe] or [three_dof] case to submit"),
        "{e}"
    );
    assert!(e.contains("nothing to do"), "{e}");
}

/// Opt-in (`HDI_SLURM_TESTS=1`, a Slurm from `scripts/slurm-local-up.sh`): the 76-case sweep
/// through a real single-node Slurm equals the local run, a rerun submits nothing, and a task
/// cancelled with `scancel` is the only work a rerun submits again.
#[test]
fn real_slurm_sweep_matches_local_and_scancel_loses_only_that_task() {
    if std::env::var("HDI_SLURM_TESTS").as_deref() != Ok("1") {
        eprintln!(
            "skipped: set HDI_SLURM_TESTS=1 with a running Slurm (scripts/slurm-local-up.sh)"
        );
        return;
    }
    let config = sweep_only_config(&Project::shipped().config())
        .replace("actuation_step = \"5 nm\"", "actuation_step = \"0.2 nm\"");
    let local = Project::shipped();
    local.set_config(&config);
    assert_ok(&local.run(&["run"]));
    let local_table = std::fs::read(local.processed().join("improved_sweep/sweep.csv")).unwrap();

    let remote = Project::shipped();
    remote.set_config(&config);
    let no_bin = remote.path().join("no-fakes");
    // Submit without waiting, cancel task 1 at once (38 cases), let task 0 finish.
    let o = run_with(
        &remote,
        &no_bin,
        &[
            "run",
            "--executor",
            "slurm",
            "--cases-per-task",
            "38",
            "--no-wait",
        ],
    );
    assert_ok(&o);
    let e = stderr(&o);
    assert!(e.contains("76 cases in 2 tasks submitted"), "{e}");
    let job: String = e
        .split("as job(s) ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .expect("job id")
        .to_string();
    let cancel = std::process::Command::new("scancel")
        .arg(format!("{job}_1"))
        .status()
        .expect("scancel");
    assert!(cancel.success());
    let started = std::time::Instant::now();
    loop {
        let q = std::process::Command::new("squeue")
            .args(["-h", "-j", &job])
            .output()
            .expect("squeue");
        if String::from_utf8_lossy(&q.stdout).trim().is_empty() {
            break;
        }
        assert!(
            started.elapsed().as_secs() < 600,
            "job {job} never finished"
        );
        std::thread::sleep(std::time::Duration::from_millis(200));
    }
    // The rerun submits only what the cancelled task did not store (at most its 38 cases).
    let o = run_with(&remote, &no_bin, &["run", "--executor", "slurm"]);
    assert_ok(&o);
    let e = stderr(&o);
    let resubmitted: usize = e
        .split("slurm: ")
        .nth(1)
        .and_then(|r| r.split(" cases in").next())
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or_else(|| panic!("no resubmission line: {e}"));
    assert!((1..=38).contains(&resubmitted), "{e}");
    let remote_table = std::fs::read(remote.processed().join("improved_sweep/sweep.csv")).unwrap();
    assert_eq!(
        local_table, remote_table,
        "slurm and local sweep tables differ"
    );
    let o = run_with(&remote, &no_bin, &["run", "--executor", "slurm"]);
    assert_ok(&o);
    assert!(
        stderr(&o).contains("no stale [simulate], [doe] or [three_dof] case to submit"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn doe_design_cases_run_on_slurm_and_match_the_local_design() {
    let full = Project::shipped().config();
    let config = sections(
        &full,
        &[
            "[dmw.disk_md]",
            "[contact.improved]",
            "[simulate.improved_sweep]",
            "[doe.bulge_design]",
        ],
    );
    let local = Project::shipped();
    local.set_config(&config);
    assert_ok(&local.run(&["run", "--only", "bulge_design"]));
    let local_design = std::fs::read(local.processed().join("bulge_design/design.csv")).unwrap();

    let remote = Project::shipped();
    remote.set_config(&config);
    let bin = remote.path().join("bin");
    fake_slurm(&bin, None);
    let o = run_with(
        &remote,
        &bin,
        &["run", "--executor", "slurm", "--cases-per-task", "27"],
    );
    assert_ok(&o);
    assert!(stderr(&o).contains("cases in"), "{}", stderr(&o));
    // Every design case came from the Slurm tasks: the local DOE run found all 108 cached.
    assert_eq!(cases_cached(&remote.processed().join("bulge_design")), 108);
    let remote_design = std::fs::read(remote.processed().join("bulge_design/design.csv")).unwrap();
    assert_eq!(
        local_design, remote_design,
        "slurm and local DOE designs differ"
    );
}
