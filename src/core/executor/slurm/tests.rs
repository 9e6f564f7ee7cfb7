use super::*;
use std::os::unix::fs::PermissionsExt;

/// A directory of fake Slurm tools: shell scripts that append their arguments to
/// `<tool>.args` and print canned output.
struct FakeSlurm {
    dir: tempfile::TempDir,
}

impl FakeSlurm {
    fn new() -> Self {
        Self {
            dir: tempfile::tempdir().unwrap(),
        }
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    fn tool(&self, name: &str, body: &str) {
        let script = format!(
            "#!/bin/sh\nD='{}'\nprintf '%s\\n' \"$*\" >> \"$D/{name}.args\"\n{body}\n",
            self.dir.path().display()
        );
        let p = self.path(name);
        std::fs::write(&p, script).unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
    }

    /// A tool printing `outputs[k]` on its k-th call, then the last one forever.
    fn sequence(&self, name: &str, outputs: &[&str]) {
        for (k, out) in outputs.iter().enumerate() {
            std::fs::write(self.path(&format!("{name}.{k}")), out).unwrap();
        }
        let last = outputs.len() - 1;
        self.tool(
            name,
            &format!(
                "n=$(cat \"$D/{name}.count\" 2>/dev/null || echo 0)\n\
                 echo $((n + 1)) > \"$D/{name}.count\"\n\
                 [ \"$n\" -gt {last} ] && n={last}\n\
                 cat \"$D/{name}.$n\""
            ),
        );
    }

    fn args(&self, name: &str) -> Vec<String> {
        std::fs::read_to_string(self.path(&format!("{name}.args")))
            .unwrap_or_default()
            .lines()
            .map(str::to_string)
            .collect()
    }

    fn client(&self) -> SlurmClient {
        SlurmClient::with_bin_dir(self.dir.path())
    }
}

fn options() -> ScriptOptions {
    ScriptOptions {
        hdi: PathBuf::from("/opt/hdi's build/hdi"),
        workdir: PathBuf::from("/home/lab/study"),
        processed: PathBuf::from("/home/lab/study/processed"),
        job_name: "hdi-cases".into(),
        partition: Some("short".into()),
        max_running: Some(50),
        extra_directives: vec!["--time=00:30:00".into()],
    }
}

#[test]
fn script_has_the_array_header_and_exec_line() {
    let array = ArraySubmission {
        offset: 2000,
        tasks: 1000,
        cases: 4000..6000,
    };
    let manifest = Path::new("/home/lab/study/processed/.hdi/slurm/manifests/m.json");
    let s = sbatch_script(&options(), manifest, &array).unwrap();
    let lines: Vec<&str> = s.lines().collect();
    assert_eq!(lines[0], "#!/bin/sh");
    for want in [
        "#SBATCH --job-name=hdi-cases",
        "#SBATCH --array=0-999%50",
        "#SBATCH --output=/home/lab/study/processed/.hdi/slurm/%A_%a.log",
        "#SBATCH --chdir=/home/lab/study",
        "#SBATCH --partition=short",
        "#SBATCH --time=00:30:00",
    ] {
        assert!(lines.contains(&want), "missing {want:?} in\n{s}");
    }
    assert_eq!(
        *lines.last().unwrap(),
        "exec '/opt/hdi'\\''s build/hdi' exec-cases \
         '/home/lab/study/processed/.hdi/slurm/manifests/m.json' \
         --task \"$SLURM_ARRAY_TASK_ID\" --offset 2000"
    );
    // Every directive precedes the first command (sbatch stops reading at it).
    let first_cmd = lines.iter().position(|l| !l.starts_with('#')).unwrap();
    assert!(lines[first_cmd..].iter().all(|l| !l.starts_with("#SBATCH")));

    let mut o = options();
    (o.partition, o.max_running) = (None, None);
    let s = sbatch_script(
        &o,
        manifest,
        &ArraySubmission {
            offset: 0,
            tasks: 1,
            cases: 0..1,
        },
    )
    .unwrap();
    assert!(s.contains("#SBATCH --array=0-0\n") && !s.contains("--partition"));
}

#[test]
fn script_refuses_values_sbatch_would_cut() {
    let array = ArraySubmission {
        offset: 0,
        tasks: 3,
        cases: 0..3,
    };
    let mut o = options();
    o.processed = PathBuf::from("/home/my study/processed");
    let e = sbatch_script(&o, Path::new("m.json"), &array).unwrap_err();
    assert!(
        matches!(&e, ExecutorError::UnsafeDirective { directive, .. } if directive == "output")
    );
    let mut o = options();
    o.partition = Some("a\nb".into());
    assert!(sbatch_script(&o, Path::new("m.json"), &array).is_err());
    let empty = ArraySubmission {
        offset: 0,
        tasks: 0,
        cases: 0..0,
    };
    assert!(sbatch_script(&options(), Path::new("m.json"), &empty).is_err());
}

#[test]
fn parses_sbatch_parsable() {
    assert_eq!(parse_sbatch_parsable("4242\n").unwrap(), 4242);
    assert_eq!(parse_sbatch_parsable("4242;cluster\n").unwrap(), 4242);
    assert_eq!(parse_sbatch_parsable("\n  77 \n").unwrap(), 77);
    assert!(parse_sbatch_parsable("").is_err());
    assert!(parse_sbatch_parsable("Submitted batch job 12").is_err());
}

#[test]
fn parses_array_task_ids() {
    let p = |s| ArrayTasks::parse(s).unwrap();
    assert_eq!(
        p("123"),
        ArrayTasks {
            job_id: 123,
            tasks: None
        }
    );
    assert_eq!(p("123_4").tasks, Some(vec![(4, 4)]));
    assert_eq!(p("123_[5-9]").tasks, Some(vec![(5, 9)]));
    let t = p("123_[1,3,5-7%2]");
    assert_eq!(t.tasks, Some(vec![(1, 1), (3, 3), (5, 7)]));
    assert_eq!(t.count(10), 5);
    assert_eq!(t.ids(10), vec![1, 3, 5, 6, 7]);
    assert_eq!(p("123").count(8), 8);
    for bad in ["", "x", "123_", "123_[5-9", "123_[9-5]", "123_a"] {
        assert!(ArrayTasks::parse(bad).is_none(), "{bad:?}");
    }
}

#[test]
fn parses_squeue_and_sacct() {
    let q = parse_squeue("123_[5-9%2] PENDING\n123_3 RUNNING\n\n123_4 COMPLETING\n").unwrap();
    assert_eq!(q.len(), 3);
    assert_eq!(q[0].state, JobState::Pending);
    assert_eq!(q[2].state, JobState::Completing);
    let s = ArrayStatus::from_queue(123, 10, &q);
    assert_eq!((s.pending, s.running, s.finished), (5, 2, 3));
    assert!(!s.is_finished());
    assert!(ArrayStatus::from_queue(123, 10, &[]).is_finished());
    assert!(parse_squeue("garbage").is_err());

    let a = parse_sacct(
        "123_0|COMPLETED|0:0\n123_0.batch|COMPLETED|0:0\n123_0.extern|COMPLETED|0:0\n\
         123_1|FAILED|1:0\n123_1.batch|FAILED|1:0\n123_2|CANCELLED by 1000|0:15\n\
         123_[3-4]|TIMEOUT|0:0\n",
    )
    .unwrap();
    assert_eq!(a.len(), 4);
    assert_eq!(a[2].state, JobState::Cancelled);
    let f = failed_tasks(123, 5, &a);
    let ids: Vec<u32> = f.iter().map(|t| t.task_id).collect();
    assert_eq!(ids, vec![1, 2, 3, 4]);
    assert_eq!(f[0].exit_code, "1:0");
    assert!(parse_sacct("123_0|COMPLETED").is_err());
}

#[test]
fn missing_tools_are_named() {
    let fake = FakeSlurm::new();
    let e = fake.client().submit(Path::new("job.sh")).unwrap_err();
    let text = e.to_string();
    assert!(matches!(e, ExecutorError::ToolMissing { .. }), "{text}");
    assert!(
        text.contains("`sbatch` not found")
            && text.contains(&fake.dir.path().display().to_string())
    );
    // A non-executable file does not count.
    std::fs::write(fake.path("squeue"), "#!/bin/sh\n").unwrap();
    assert!(matches!(
        fake.client().queue(1),
        Err(ExecutorError::ToolMissing { .. })
    ));
}

#[test]
fn submits_and_records_arguments() {
    let fake = FakeSlurm::new();
    fake.tool(
        "sbatch",
        "cp \"$2\" \"$D/submitted.sh\"\necho '4242;cluster'",
    );
    let script = fake.path("job.sh");
    std::fs::write(&script, "#!/bin/sh\ntrue\n").unwrap();
    assert_eq!(fake.client().submit(&script).unwrap(), 4242);
    assert_eq!(
        fake.args("sbatch"),
        vec![format!("--parsable {}", script.display())]
    );
    assert!(fake.path("submitted.sh").exists());

    fake.tool(
        "sbatch",
        "echo 'sbatch: error: invalid partition specified: gpu' >&2\nexit 1",
    );
    let e = fake.client().submit(&script).unwrap_err();
    assert!(
        matches!(&e, ExecutorError::ToolFailed { stderr, .. } if stderr.contains("invalid partition")),
        "{e}"
    );
}

#[test]
fn waits_through_pending_running_completed_with_one_failed_task() {
    let fake = FakeSlurm::new();
    fake.sequence(
        "squeue",
        &[
            "4242_[0-3] PENDING\n",
            "4242_[2-3] PENDING\n4242_0 RUNNING\n4242_1 RUNNING\n",
            "4242_3 RUNNING\n",
            "",
        ],
    );
    fake.tool(
        "sacct",
        "printf '4242_0|COMPLETED|0:0\\n4242_0.batch|COMPLETED|0:0\\n4242_1|COMPLETED|0:0\\n\
         4242_2|FAILED|1:0\\n4242_2.batch|FAILED|1:0\\n4242_3|COMPLETED|0:0\\n'",
    );
    let mut seen = Vec::new();
    let status = fake
        .client()
        .wait(4242, 4, Duration::from_millis(1), |s| {
            seen.push((s.pending, s.running, s.finished))
        })
        .unwrap();
    assert_eq!(seen, vec![(4, 0, 0), (2, 2, 0), (0, 1, 3), (0, 0, 4)]);
    assert!(status.accounting);
    assert_eq!(
        status.failed,
        vec![FailedTask {
            task_id: 2,
            state: JobState::Failed,
            exit_code: "1:0".into()
        }]
    );
    let q = fake.args("squeue");
    assert_eq!(q.len(), 4);
    assert!(q.iter().all(|a| a == "-h -j 4242 -o %i %T"), "{q:?}");
    // sacct only once the queue is empty.
    assert_eq!(
        fake.args("sacct"),
        vec!["-n -P -j 4242 -o JobID,State,ExitCode"]
    );
}

#[test]
fn purged_job_and_disabled_accounting() {
    let fake = FakeSlurm::new();
    fake.tool(
        "squeue",
        "echo 'slurm_load_jobs error: Invalid job id specified' >&2\nexit 1",
    );
    fake.tool(
        "sacct",
        "echo 'sacct: error: Slurm accounting storage is disabled' >&2\nexit 1",
    );
    let s = fake.client().status(7, 3).unwrap();
    assert!(s.is_finished() && !s.accounting && s.failed.is_empty());

    // Any other squeue failure is an error.
    fake.tool(
        "squeue",
        "echo 'squeue: error: slurm_receive_msg: Socket timed out' >&2\nexit 1",
    );
    let e = fake.client().status(7, 3).unwrap_err();
    assert!(e.to_string().contains("Socket timed out"), "{e}");
}

#[test]
fn log_path_matches_the_output_pattern() {
    let p = log_path(Path::new("/p/processed"), 4242, 7);
    assert_eq!(p, PathBuf::from("/p/processed/.hdi/slurm/4242_7.log"));
}

fn study(n: usize, cases_per_task: usize) -> CaseManifest {
    let specs = (0..n)
        .map(|i| {
            super::super::CaseSpec::new(
                "simulate",
                "test-1",
                serde_json::json!({"actuation_m": i as f64 * 1e-12}),
                serde_json::json!({}),
            )
        })
        .collect();
    CaseManifest::new(specs, cases_per_task).unwrap()
}

/// sbatch numbering its jobs 100, 101, ...; failing on call `fail_at` (0-based) if given.
fn numbering_sbatch(fake: &FakeSlurm, fail_at: Option<usize>) {
    let fail = fail_at.map_or(String::new(), |k| {
        format!("[ \"$n\" -eq {k} ] && {{ echo 'sbatch: error: QOSMaxSubmitJobPerUserLimit' >&2; exit 1; }}\n")
    });
    fake.tool(
        "sbatch",
        &format!(
            "n=$(cat \"$D/sbatch.count\" 2>/dev/null || echo 0)\n{fail}\
             echo $((n + 1)) > \"$D/sbatch.count\"\necho $((100 + n))"
        ),
    );
}

#[test]
fn ten_thousand_cases_submit_as_arrays_within_the_limit() {
    let fake = FakeSlurm::new();
    numbering_sbatch(&fake, None);
    let processed = fake.dir.path().join("processed");
    let m = study(10_000, 1);
    let path = super::super::manifest_path(&processed, &m.id());
    m.write(&path).unwrap();
    let opts = ScriptOptions {
        processed: processed.clone(),
        ..options()
    };
    let t0 = std::time::Instant::now();
    let subs = submit_manifest(&fake.client(), &opts, &path, &m, 1000).unwrap();
    eprintln!(
        "10,000 cases → {} arrays submitted in {:?}",
        subs.len(),
        t0.elapsed()
    );
    assert_eq!(subs.len(), 10);
    for (k, s) in subs.iter().enumerate() {
        assert_eq!(
            (s.job_id, s.offset, s.tasks),
            (100 + k as u64, 1000 * k, 1000)
        );
        let script = std::fs::read_to_string(script_path(&path, s.offset)).unwrap();
        assert!(script.contains("#SBATCH --array=0-999%50\n"), "{script}");
        assert!(
            script.ends_with(&format!("--offset {}\n", s.offset)),
            "{script}"
        );
    }
    assert_eq!(read_submissions(&path).unwrap(), subs);
    // Nothing left to submit for this manifest.
    assert!(submit_manifest(&fake.client(), &opts, &path, &m, 1000)
        .unwrap()
        .is_empty());
    assert_eq!(fake.args("sbatch").len(), 10);

    // 25 cases per task: one array of 400 tasks.
    let m = study(10_000, 25);
    let path = super::super::manifest_path(&processed, "per25");
    m.write(&path).unwrap();
    let subs = submit_manifest(&fake.client(), &opts, &path, &m, 1000).unwrap();
    assert_eq!(subs.len(), 1);
    assert_eq!(subs[0].tasks, 400);
}

#[test]
fn a_refused_submission_keeps_the_record_of_what_was_queued() {
    let fake = FakeSlurm::new();
    numbering_sbatch(&fake, Some(2));
    let processed = fake.dir.path().join("processed");
    let m = study(50, 2); // 25 tasks → arrays of 10, 10, 5
                          // A manifest kept elsewhere: the log directory is still created.
    let path = fake.dir.path().join("elsewhere").join("m.json");
    m.write(&path).unwrap();
    let opts = ScriptOptions {
        processed,
        ..options()
    };
    let e = submit_manifest(&fake.client(), &opts, &path, &m, 10).unwrap_err();
    assert!(e.to_string().contains("QOSMaxSubmitJobPerUserLimit"), "{e}");
    let offsets: Vec<usize> = read_submissions(&path)
        .unwrap()
        .iter()
        .map(|s| s.offset)
        .collect();
    assert_eq!(offsets, vec![0, 10]);
    // Retried (sbatch accepts again): only the third array goes in.
    numbering_sbatch(&fake, None);
    let subs = submit_manifest(&fake.client(), &opts, &path, &m, 10).unwrap();
    assert_eq!(subs.len(), 1);
    assert_eq!((subs[0].offset, subs[0].tasks), (20, 5));
    assert!(slurm_dir(&opts.processed).is_dir());
    let mut m2 = study(3, 1);
    m2.created = "2099-01-01T00:00:00Z".into();
    let path2 = super::super::manifest_path(&opts.processed, &m2.id());
    m2.write(&path2).unwrap();
    submit_manifest(&fake.client(), &opts, &path2, &m2, 10).unwrap();
    // Scripts and job records beside a manifest are not manifests.
    assert_eq!(
        super::super::list_manifests(&opts.processed).unwrap(),
        vec![path2]
    );
}

#[test]
fn polls_all_arrays_and_marks_tasks_killed_before_reporting() {
    let fake = FakeSlurm::new();
    // Array 100 (tasks 0-1) has finished; array 101 (tasks 0-2) still has one running task.
    fake.tool("squeue", "case \"$3\" in 101) echo '101_2 RUNNING' ;; esac");
    fake.tool(
        "sacct",
        "case \"$4\" in 100) printf '100_0|COMPLETED|0:0\\n100_1|TIMEOUT|0:0\\n' ;; esac",
    );
    let subs = [
        SubmissionRecord {
            job_id: 100,
            offset: 0,
            tasks: 2,
            submitted: String::new(),
        },
        SubmissionRecord {
            job_id: 101,
            offset: 2,
            tasks: 3,
            submitted: String::new(),
        },
    ];
    let (total, each) = fake.client().status_all(&subs).unwrap();
    assert_eq!((total.tasks, total.running, total.finished), (5, 1, 4));
    assert!(!total.is_finished() && !total.accounting);
    assert!(each[0].accounting && !each[1].accounting);
    assert_eq!(each[0].failed.len(), 1);

    // Manifest of 10 cases at 2 per task: array 100 task 1 = global task 1 = cases 2..4.
    let processed = fake.dir.path().join("processed");
    let mut m = study(10, 2);
    m.cases[3].status = super::super::CaseStatus::Done; // it did report this one
    assert_eq!(m.mark_unreported(&processed, &subs[0], &each[0].failed), 1);
    let failed: Vec<_> = m.failed().collect();
    assert_eq!(failed.len(), 1);
    assert_eq!(failed[0].0, 2);
    let super::super::CaseStatus::Failed {
        error,
        job_id,
        task_id,
        log,
    } = &failed[0].1.status
    else {
        unreachable!()
    };
    assert_eq!(
        error,
        "task ended TIMEOUT (exit 0:0) without reporting this case"
    );
    assert_eq!((*job_id, *task_id), (Some(100), Some(1)));
    assert_eq!(log.as_deref(), Some(log_path(&processed, 100, 1).as_path()));
    // A task id outside the array is ignored.
    let bogus = [FailedTask {
        task_id: 7,
        state: JobState::Failed,
        exit_code: "1:0".into(),
    }];
    assert_eq!(m.mark_unreported(&processed, &subs[0], &bogus), 0);
}
