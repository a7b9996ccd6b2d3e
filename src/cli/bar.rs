//! A progress bar with ETA on stderr; hidden with `--quiet` or when stderr is not a terminal.
//! It redraws twice a second whether or not a step was done, so the elapsed time moves and the
//! ETA follows the steps done so far from the first second (the render driver counts pixels).

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use hmdist::progress::Progress;

pub struct Bar(ProgressBar);

impl Bar {
    pub fn new(quiet: bool) -> Bar {
        let target = if quiet || !std::io::stderr().is_terminal() {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        };
        let bar = ProgressBar::with_draw_target(None, target);
        bar.set_style(
            ProgressStyle::with_template("{msg:>10} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta}")
                .expect("valid template"),
        );
        Bar(bar)
    }

    /// Prints a line on stderr above the bar (whether or not the bar is shown).
    pub fn note(&self, line: &str) {
        self.0.suspend(|| eprintln!("{line}"));
    }

    /// Shows a one-line status (a phase without steps, such as loading).
    pub fn status(&self, message: &str) {
        self.0.set_length(0);
        self.0.set_message(message.to_string());
        self.0.tick();
    }
}

impl Progress for Bar {
    fn start(&self, label: &str, total: u64) {
        self.0.reset();
        self.0.set_length(total);
        self.0.set_message(label.to_string());
        self.0.enable_steady_tick(Duration::from_millis(500));
    }

    fn advance(&self, steps: u64) {
        self.0.inc(steps);
    }

    fn finish(&self) {
        self.0.finish_and_clear();
    }
}
