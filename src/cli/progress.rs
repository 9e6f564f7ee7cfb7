//! All indicatif set-up in one place: the library reports through `hdi::core::progress`'s
//! observers, these draw them. Pipeline bars draw to stderr only when it is a terminal, so
//! logs and CI output stay clean (indicatif's own stderr target does the same for the others).

use hdi::core::progress::{Progress, RunObserver};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::HashMap;
use std::io::IsTerminal;
use std::path::Path;
use std::sync::{Mutex, OnceLock};
use std::time::Duration;

fn draw_target() -> ProgressDrawTarget {
    if std::io::stderr().is_terminal() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    }
}

/// `hdi run`: a bar over the stale instances and a spinner per running one (its stage sets
/// the spinner's message).
pub struct StageBars {
    what: &'static str,
    bars: OnceLock<(MultiProgress, ProgressBar)>,
    running: Mutex<HashMap<String, ProgressBar>>,
}

impl StageBars {
    /// `what` prefixes the total bar ("stages").
    pub fn new(what: &'static str) -> Self {
        Self {
            what,
            bars: OnceLock::new(),
            running: Mutex::new(HashMap::new()),
        }
    }
}

impl RunObserver for StageBars {
    fn run_started(&self, stages: usize) {
        self.bars.get_or_init(|| {
            let multi = MultiProgress::with_draw_target(draw_target());
            let total = multi.add(ProgressBar::new(stages as u64));
            total.set_style(
                ProgressStyle::with_template(
                    "{prefix:>10} [{bar:30}] {pos}/{len} {elapsed_precise}",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
            );
            total.set_prefix(self.what);
            (multi, total)
        });
    }

    fn stage_started(&self, name: &str) -> Box<dyn Progress> {
        let Some((multi, total)) = self.bars.get() else {
            return Box::new(hdi::core::progress::NoProgress);
        };
        let bar = multi.insert_before(total, ProgressBar::new_spinner());
        bar.set_style(
            ProgressStyle::with_template("{spinner} {prefix:>10} {wide_msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        bar.set_prefix(name.to_string());
        bar.enable_steady_tick(Duration::from_millis(120));
        if let Ok(mut running) = self.running.lock() {
            running.insert(name.to_string(), bar.clone());
        }
        Box::new(Spinner(bar))
    }

    fn stage_finished(&self, name: &str, ok: bool) {
        let Some((multi, total)) = self.bars.get() else {
            return;
        };
        let bar = self.running.lock().ok().and_then(|mut r| r.remove(name));
        if let Some(bar) = bar {
            bar.finish_and_clear();
            multi.remove(&bar);
        }
        if !ok {
            let _ = multi.println(format!("failed: {name}"));
        }
        total.inc(1);
    }

    fn run_finished(&self) {
        if let Some((_, total)) = self.bars.get() {
            total.finish_and_clear();
        }
    }

    fn waiting_for_lock(&self, holder: &str, lock: &Path) {
        LockNotice.waiting_for_lock(holder, lock);
    }
}

/// Commands without bars that take the workspace lock (`hdi gc`, `hdi verify --repair`):
/// only say when they wait for another run.
pub struct LockNotice;

impl RunObserver for LockNotice {
    fn waiting_for_lock(&self, holder: &str, lock: &Path) {
        // Always printed (terminal or not): a run that seems to hang says why.
        eprintln!(
            "waiting for another hdi run (pid {holder}) holding {}",
            lock.display()
        );
    }
}

/// A running stage's spinner: shows the stage's message only.
struct Spinner(ProgressBar);

impl Progress for Spinner {
    fn message(&self, msg: String) {
        self.0.set_message(msg);
    }
}

/// `hdi simulate`: one bar over the cases of a sweep.
pub struct CaseBar(ProgressBar);

impl CaseBar {
    pub fn new(cases: usize) -> Self {
        let bar = ProgressBar::new(cases as u64);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} cases {elapsed} (eta {eta})")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Self(bar)
    }

    pub fn finish(&self) {
        self.0.finish_and_clear();
    }
}

impl Progress for CaseBar {
    fn message(&self, msg: String) {
        self.0.set_message(msg);
    }
    fn set_length(&self, len: u64) {
        self.0.set_length(len);
    }
    fn inc(&self, delta: u64) {
        self.0.inc(delta);
    }
}

/// `hdi run --executor slurm` waiting for its arrays: finished tasks of all of them.
pub fn task_bar(tasks: usize) -> ProgressBar {
    ProgressBar::new(tasks as u64)
}
