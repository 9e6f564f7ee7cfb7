//! Progress reaches the caller through these observers; the library never draws or prints
//! progress itself (the command line draws bars with them, tests and benches pass
//! [`NoProgress`]).

/// Progress of one piece of work: a running stage, a sweep of cases.
pub trait Progress: Send + Sync {
    /// The status line: what the work is doing now. Call sites use `set_message` on
    /// `dyn Progress`, which takes literals and `format!`s alike.
    fn message(&self, msg: String);
    /// How many units the work has (the cases of a sweep), once known.
    fn set_length(&self, _len: u64) {}
    /// `delta` more units done.
    fn inc(&self, _delta: u64) {}
}

impl dyn Progress + '_ {
    /// [`Progress::message`] for anything string-like.
    pub fn set_message(&self, msg: impl Into<String>) {
        self.message(msg.into());
    }
}

/// What `engine::run` reports while it runs a pipeline.
pub trait RunObserver: Sync {
    /// Planning is done: `stages` stale instances will run (not called for a dry run).
    fn run_started(&self, _stages: usize) {}
    /// An instance starts; its stage reports through the returned [`Progress`].
    fn stage_started(&self, _name: &str) -> Box<dyn Progress> {
        Box::new(NoProgress)
    }
    /// The instance `stage_started` named has ended: committed to the store (`ok`) or failed.
    fn stage_finished(&self, _name: &str, _ok: bool) {}
    /// Every wave has run.
    fn run_finished(&self) {}
    /// Another hdi run (process `holder`, as its lock file says) holds the workspace lock at
    /// `lock`; this run waits for it before planning.
    fn waiting_for_lock(&self, _holder: &str, _lock: &std::path::Path) {}
}

/// Ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn message(&self, _msg: String) {}
}

impl RunObserver for NoProgress {}
