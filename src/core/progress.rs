//! All indicatif set-up in one place. Bars draw to stderr only when it is a terminal, so
//! logs and CI output stay clean.

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::Duration;

pub struct Bars {
    multi: MultiProgress,
    total: ProgressBar,
}

fn draw_target() -> ProgressDrawTarget {
    if std::io::stderr().is_terminal() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    }
}

impl Bars {
    pub fn new(len: u64, what: &str) -> Self {
        let multi = MultiProgress::with_draw_target(draw_target());
        let total = multi.add(ProgressBar::new(len));
        total.set_style(
            ProgressStyle::with_template("{prefix:>10} [{bar:30}] {pos}/{len} {elapsed_precise}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        total.set_prefix(what.to_string());
        Self { multi, total }
    }

    /// A spinner for one running stage; stages may set its message.
    pub fn stage(&self, name: &str) -> ProgressBar {
        let bar = self
            .multi
            .insert_before(&self.total, ProgressBar::new_spinner());
        bar.set_style(
            ProgressStyle::with_template("{spinner} {prefix:>10} {wide_msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        bar.set_prefix(name.to_string());
        bar.enable_steady_tick(Duration::from_millis(120));
        bar
    }

    pub fn finish_stage(&self, bar: ProgressBar, name: &str, ok: bool) {
        bar.finish_and_clear();
        self.multi.remove(&bar);
        if !ok {
            let _ = self.multi.println(format!("failed: {name}"));
        }
        self.total.inc(1);
    }

    pub fn finish(&self) {
        self.total.finish_and_clear();
    }
}
