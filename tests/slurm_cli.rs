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

/// The shipped sections whose headers start with one of `keep_headers`, and the tests'
/// `[report]` settings (no validation table: seconds per run in a debug build).
fn sections(full: &str, keep_headers: &[&str]) -> String {
    let mut out = String::new();
    let mut keep = false;
    for line in full.lines() {
        if line.starts_with('[') {
            keep = line == "[report]" || keep_headers.iter().any(|s| line.starts_with(s));
        }
        if keep {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// Fake `sbatch`/`squeue`/`sacct` in `bin/`. `FAIL_TASK` (an array task id) makes that task
/// exit 1 before computing anything. Shared with tests/slurm_calibration.rs.
pub(crate) fn fake_slurm(bin: &Path, fail_task: Option<usize>) {
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

/// `hdi ARGS` in the project with the fake scheduler of `bin` first on PATH.
pub(crate) fn run_with(p: &Project, bin: &Path, args: &[&str]) -> std::process::Output {
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
    // Two of the four actuations: 54 design cases are as good a test of the road as 108.
    let four = "actuations = [\"5 nm\", \"9 nm\", \"12 nm\", \"15 nm\"]";
    assert!(
        config.contains(four),
        "the shipped [doe.bulge_design] changed"
    );
    let config = config.replace(four, "actuations = [\"9 nm\", \"12 nm\"]");
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
    // Every design case came from the Slurm tasks: the local DOE run found all 54 cached.
    assert_eq!(cases_cached(&remote.processed().join("bulge_design")), 54);
    let remote_design = std::fs::read(remote.processed().join("bulge_design/design.csv")).unwrap();
    assert_eq!(
        local_design, remote_design,
        "slurm and local DOE designs differ"
    );
}

/// The one manifest under `processed/.hdi/slurm/manifests/` (panics on none or several).
fn only_manifest(processed: &Path) -> (std::path::PathBuf, serde_json::Value) {
    let dir = processed.join(".hdi/slurm/manifests");
    let manifests: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy().to_string();
            n.ends_with(".json") && !n.ends_with(".jobs.json")
        })
        .collect();
    assert_eq!(manifests.len(), 1, "{manifests:?}");
    let text = std::fs::read_to_string(&manifests[0]).unwrap();
    (manifests[0].clone(), serde_json::from_str(&text).unwrap())
}

/// A length in nm from a `key = "X nm"` line of one section of a pipeline file.
fn section_nm(config: &str, header: &str, key: &str) -> f64 {
    let section: String = config
        .split("\n[")
        .find(|s| s.starts_with(header.trim_start_matches('[')))
        .unwrap_or_else(|| panic!("no {header}"))
        .to_string();
    let line = section
        .lines()
        .find(|l| l.starts_with(&format!("{key} = ")))
        .unwrap_or_else(|| panic!("no {key} in {header}"));
    line.split('"')
        .nth(1)
        .unwrap()
        .trim_end_matches(" nm")
        .parse()
        .unwrap()
}

/// `--only <sweep>` on a pipeline with two sweeps and a DOE submits exactly that sweep's grid
/// (the engine's `--only` selection: the sweep and what it consumes); the other sweep and the
/// DOE are neither submitted nor run. The manifest written matches its JSON Schema.
#[test]
fn only_submits_exactly_the_named_sweeps_cases() {
    let full = Project::shipped().config();
    // The improved sweep on a 3 nm grid (6 points), the optimised one on the tests' 5 nm.
    let config = sections(
        &full,
        &[
            "[dmw.disk_md]",
            "[contact.improved]",
            "[simulate.improved_sweep]",
            "[simulate.optimised_sweep]",
            "[doe.bulge_design]",
        ],
    )
    .replacen("actuation_step = \"5 nm\"", "actuation_step = \"3 nm\"", 1);
    let (start, stop, step) = (
        section_nm(&config, "[simulate.improved_sweep]", "actuation_start"),
        section_nm(&config, "[simulate.improved_sweep]", "actuation_stop"),
        section_nm(&config, "[simulate.improved_sweep]", "actuation_step"),
    );
    let grid = ((stop - start) / step + 1e-9).floor() as usize + 1;
    assert_eq!(grid, 6);
    assert_eq!(
        section_nm(&config, "[simulate.optimised_sweep]", "actuation_step"),
        5.0
    );

    let p = Project::shipped();
    p.set_config(&config);
    let bin = p.path().join("bin");
    fake_slurm(&bin, None);
    let o = run_with(
        &p,
        &bin,
        &[
            "run",
            "--executor",
            "slurm",
            "--only",
            "improved_sweep",
            "--cases-per-task",
            "4",
        ],
    );
    assert_ok(&o);
    let e = stderr(&o);
    assert!(
        e.contains(&format!("{grid} cases in 2 tasks submitted")),
        "{e}"
    );
    // The manifest lists the sweep's cases and nothing else, at the grid's actuations.
    let (path, m) = only_manifest(&p.processed());
    let cases = m["cases"].as_array().unwrap();
    assert_eq!(cases.len(), grid);
    let mut actuations_nm: Vec<f64> = cases
        .iter()
        .map(|c| {
            assert_eq!(c["kind"], "simulate", "{c}");
            assert_eq!(c["recipe"]["instance"], "improved_sweep", "{c}");
            assert_eq!(c["status"]["state"], "done", "{c}");
            c["recipe"]["case"]["actuation_m"].as_f64().unwrap() * 1e9
        })
        .collect();
    actuations_nm.sort_by(f64::total_cmp);
    for (i, a) in actuations_nm.iter().enumerate() {
        assert!(
            (a - (start + i as f64 * step)).abs() < 1e-6,
            "{actuations_nm:?}"
        );
    }
    assert_matches_schema("case-manifest", &std::fs::read_to_string(&path).unwrap());
    // The fake ran 2 tasks (one job) and the local run found every case cached.
    let logs = std::fs::read_dir(&bin)
        .unwrap()
        .filter(|e| {
            let n = e.as_ref().unwrap().file_name();
            n.to_string_lossy().starts_with("task_")
        })
        .count();
    assert_eq!(logs, 2);
    // Both continuation branches (the default `branches = "both"`) look every grid point up;
    // on this grid their start equilibria coincide, so the manifest lists each case once and
    // the 2 × 6 lookups all hit the cases the tasks stored.
    assert_eq!(
        cases_cached(&p.processed().join("improved_sweep")),
        2 * grid as u64
    );
    // Neither the other sweep nor the DOE ran or had cases computed.
    for other in ["optimised_sweep", "bulge_design"] {
        assert!(!p.processed().join(other).exists(), "{other} ran");
    }
    let st = run_with(&p, &bin, &["status"]);
    let out = stdout(&st);
    assert!(out.contains("fresh    improved_sweep"), "{out}");
    assert!(out.contains("missing  optimised_sweep"), "{out}");
    assert!(out.contains("missing  bulge_design"), "{out}");
}

/// The shipped constant-actuation 3-DOF scenario shortened to 0.4 ms (its two cases, ISBL
/// and MTL): enough for the case machinery.
fn three_dof_config() -> String {
    sections(
        &Project::shipped().config(),
        &[
            "[dmw.disk_md]",
            "[contact.slider3]",
            "[three_dof.constant_12nm]",
        ],
    )
    .replace(
        "interfaces = [\"isbl\", \"mtl\"]",
        "duration = \"0.4 ms\"\nsteady_start = \"0.2 ms\"\ninterfaces = [\"isbl\", \"mtl\"]",
    )
}

/// Every file of an instance's output directory but `manifest.json` (run facts), by path.
fn instance_files(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    let mut out = std::collections::BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let path = e.unwrap().path();
            if path.is_dir() {
                todo.push(path);
            } else if path.file_name().unwrap() != "manifest.json" {
                let rel = path.strip_prefix(dir).unwrap().display().to_string();
                out.insert(rel, std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

/// The 3-DOF cases run in Slurm tasks (fake scheduler); a failed task's case is reported and
/// listed by `hdi status`, the rerun submits only it; the local run then finds both cases
/// cached and the stage's outputs are byte-identical to a local-only run's.
#[test]
fn three_dof_cases_run_on_slurm_and_match_the_local_run() {
    let config = three_dof_config();
    let local = Project::shipped();
    local.set_config(&config);
    assert_ok(&local.run(&["run"]));
    let local_files = instance_files(&local.processed().join("constant_12nm"));
    assert!(
        local_files.contains_key("cases/isbl.h5"),
        "{:?}",
        local_files.keys()
    );
    assert!(local_files.contains_key("cases/mtl_reference.h5"));

    let remote = Project::shipped();
    remote.set_config(&config);
    let bin = remote.path().join("bin");
    fake_slurm(&bin, Some(0));
    let args = ["run", "--executor", "slurm", "--cases-per-task", "1"];
    let o = run_with(&remote, &bin, &args);
    assert!(!o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("2 cases in 2 tasks submitted"), "{e}");
    assert!(e.contains("1 case(s) failed on Slurm"), "{e}");
    let (path, m) = only_manifest(&remote.processed());
    assert_matches_schema("case-manifest", &std::fs::read_to_string(&path).unwrap());
    let labels: Vec<&str> = m["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            assert_eq!(c["kind"], "three_dof", "{c}");
            assert_eq!(
                c["model_version"],
                hdi::stages::three_dof::MODEL_VERSION,
                "{c}"
            );
            c["recipe"]["case"].as_str().unwrap()
        })
        .collect();
    assert_eq!(labels, ["isbl", "mtl_reference"]);
    let st = run_with(&remote, &bin, &["status"]);
    let (out, err) = (stdout(&st), stderr(&st));
    assert!(out.contains("failed cases in"), "{out}");
    assert!(err.contains("FAILED  case 0 three_dof"), "{err}");
    assert!(!err.contains("case 1 three_dof"), "{err}");

    fake_slurm(&bin, None);
    let o = run_with(&remote, &bin, &args);
    assert_ok(&o);
    assert!(
        stderr(&o).contains("1 cases in 1 tasks submitted"),
        "{}",
        stderr(&o)
    );
    assert_eq!(cases_cached(&remote.processed().join("constant_12nm")), 2);
    let remote_files = instance_files(&remote.processed().join("constant_12nm"));
    assert_eq!(
        local_files.keys().collect::<Vec<_>>(),
        remote_files.keys().collect::<Vec<_>>()
    );
    for (name, bytes) in &local_files {
        assert!(
            remote_files[name] == *bytes,
            "{name} differs from the local run's"
        );
    }
    let st = run_with(&remote, &bin, &["status"]);
    assert!(!stdout(&st).contains("failed cases"), "{}", stdout(&st));
}

/// Opt-in (`HDI_SLURM_TESTS=1`): the 3-DOF cases (ISBL and MTL, 0.4 ms) as array tasks on a
/// real single-node Slurm; every output file of the stage equals a local-only run's (`cmp`),
/// and a rerun submits nothing.
#[test]
fn real_slurm_three_dof_cases_match_local() {
    if std::env::var("HDI_SLURM_TESTS").as_deref() != Ok("1") {
        eprintln!(
            "skipped: set HDI_SLURM_TESTS=1 with a running Slurm (scripts/slurm-local-up.sh)"
        );
        return;
    }
    let config = three_dof_config();
    let local = Project::shipped();
    local.set_config(&config);
    assert_ok(&local.run(&["run"]));

    let remote = Project::shipped();
    remote.set_config(&config);
    let no_bin = remote.path().join("no-fakes");
    let started = std::time::Instant::now();
    let o = run_with(
        &remote,
        &no_bin,
        &["run", "--executor", "slurm", "--cases-per-task", "1"],
    );
    assert_ok(&o);
    eprintln!(
        "3-DOF cases on Slurm, submission to finished local run: {:.1} s",
        started.elapsed().as_secs_f64()
    );
    let e = stderr(&o);
    assert!(e.contains("2 cases in 2 tasks submitted"), "{e}");
    assert_eq!(cases_cached(&remote.processed().join("constant_12nm")), 2);
    let local_dir = local.processed().join("constant_12nm");
    let remote_dir = remote.processed().join("constant_12nm");
    let files = instance_files(&local_dir);
    assert!(files.contains_key("cases/isbl.h5") && files.contains_key("cases/mtl_reference.h5"));
    assert_eq!(
        files.keys().collect::<Vec<_>>(),
        instance_files(&remote_dir).keys().collect::<Vec<_>>()
    );
    for name in files.keys() {
        let cmp = std::process::Command::new("cmp")
            .arg(local_dir.join(name))
            .arg(remote_dir.join(name))
            .output()
            .expect("cmp");
        assert!(cmp.status.success(), "{name}: {}", stdout(&cmp));
    }
    let o = run_with(&remote, &no_bin, &["run", "--executor", "slurm"]);
    assert_ok(&o);
    assert!(
        stderr(&o).contains("no stale [simulate], [doe] or [three_dof] case to submit"),
        "{}",
        stderr(&o)
    );
}

/// A pipeline file edited between submission and the task: the worker re-derives the case's
/// key from the file, finds another one and refuses to compute, so nothing is filed under the
/// manifest's key (it would be another case's results).
#[test]
fn a_task_refuses_cases_whose_pipeline_changed_since_submission() {
    let p = Project::shipped();
    let config = three_dof_config();
    p.set_config(&config);
    // An `sbatch` that queues and runs nothing.
    let bin = p.path().join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let sbatch = bin.join("sbatch");
    std::fs::write(&sbatch, "#!/bin/sh\necho 77\n").unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&sbatch, std::fs::Permissions::from_mode(0o755)).unwrap();
    let o = run_with(
        &p,
        &bin,
        &[
            "run",
            "--executor",
            "slurm",
            "--no-wait",
            "--cases-per-task",
            "2",
        ],
    );
    assert_ok(&o);
    assert!(
        stderr(&o).contains("2 cases in 1 tasks submitted"),
        "{}",
        stderr(&o)
    );
    let (path, _) = only_manifest(&p.processed());
    // Submitted, not run: `hdi status` lists the cases as missing.
    let st = run_with(&p, &bin, &["status"]);
    assert!(
        stdout(&st).contains("slurm: 2 of 2 submitted cases (three_dof) missing from the store"),
        "{}",
        stdout(&st)
    );
    assert!(config.contains("actuation = \"12 nm\""));
    p.set_config(&config.replace("actuation = \"12 nm\"", "actuation = \"11 nm\""));
    let task = hdi()
        .current_dir(p.path())
        .args(["exec-cases", path.to_str().unwrap(), "--task", "0"])
        .output()
        .unwrap();
    assert!(!task.status.success(), "{}", stderr(&task));
    assert!(
        stderr(&task).contains("2 case(s) of task 0 failed"),
        "{}",
        stderr(&task)
    );
    let outcome = std::fs::read_to_string(path.with_file_name(format!(
        "{}.outcomes/0.json",
        path.file_stem().unwrap().to_string_lossy()
    )))
    .unwrap();
    assert!(
        outcome.contains("the pipeline file now gives key")
            && outcome.contains("changed since submission"),
        "{outcome}"
    );
    let store = p.processed().join(".hdi/store/case");
    let filed = std::fs::read_dir(&store).map_or(0, |d| d.count());
    assert_eq!(filed, 0, "cases filed in {}", store.display());
}
