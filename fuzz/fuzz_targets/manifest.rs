//! Case manifests (`processed/.hdi/slurm/manifests/*.json`): `CaseManifest::read`, as
//! `hdi exec-cases` and `hdi status` read them, then what a worker and `hdi status` do with a
//! manifest before computing anything (task ranges, counts, the id); and the submissions
//! file beside it (`read_submissions`).
use hdi::core::executor::{read_submissions, submissions_path, CaseManifest};

fn main() {
    afl::fuzz_nohook!(|data: &[u8]| {
        let path = hdi_fuzz::input_file("manifest.json", data);
        if let Ok(m) = CaseManifest::read(&path) {
            let tasks = m.task_count();
            for task in [0, tasks / 2, tasks.saturating_sub(1), tasks] {
                let _ = m.task_range(task);
            }
            let _ = m.counts();
            let _ = m.failed().count();
            let _ = m.id();
        }
        let subs = submissions_path(&path);
        std::fs::write(&subs, data).expect("write the fuzz input");
        let _ = read_submissions(&path);
    });
}
