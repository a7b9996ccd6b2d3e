//! Long work without the GIL, stopped by Ctrl-C, and its progress on stderr.

use std::time::Duration;

use pyo3::prelude::*;

use hmdist::progress::Progress;

/// How often the calling thread looks at Python's signals while hmdist works.
pub(crate) const SIGNAL_POLL: Duration = Duration::from_millis(25);

/// Runs `work` without the GIL, stopping it on Ctrl-C (see the module docs): the work's result,
/// or the exception a signal handler raised.
pub(crate) fn interruptible<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    std::thread::scope(|scope| {
        let worker = scope.spawn(work);
        let mut raised = None;
        while !worker.is_finished() {
            py.detach(|| std::thread::park_timeout(SIGNAL_POLL));
            if raised.is_none() {
                if let Err(error) = py.check_signals() {
                    hmdist::interrupt::request();
                    raised = Some(error);
                }
            }
        }
        let result = py
            .detach(|| worker.join())
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        match raised {
            Some(error) => {
                hmdist::interrupt::clear();
                Err(error)
            }
            None => Ok(result),
        }
    })
}

/// Progress on stderr, one line per phase (for `progress=True`).
pub(crate) struct Stderr;

impl Progress for Stderr {
    fn start(&self, label: &str, total: u64) {
        eprintln!("hmdist: {label} ({total} steps)");
    }
    fn advance(&self, _: u64) {}
    fn finish(&self) {}
}
