//! Ctrl-C (SIGINT) and SIGTERM. The first one asks the library to stop
//! ([`hmdist::interrupt`]): the work returns `Error::Interrupted`, the outputs' temporaries
//! are removed on the way out, and the program exits with 128 + the signal's number (130,
//! 143), as a shell expects of a process a signal ended. A second one ends the process at
//! once, with the same status, for work that does not look at the flag (a BVH build).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::flag;

/// Which signal arrived first, if any.
pub struct Signals {
    received: Arc<AtomicUsize>,
}

impl Signals {
    /// Installs the handlers. A handler that cannot be installed leaves that signal's default
    /// (the process ends at once), which is what it would do without hmdist's handler.
    pub fn catch() -> Signals {
        let received = Arc::new(AtomicUsize::new(0));
        let requested = hmdist::interrupt::flag();
        for signal in [SIGINT, SIGTERM] {
            // The order matters: the shutdown looks at the flag before the handler below sets it.
            let _ = flag::register_conditional_shutdown(signal, 128 + signal, requested.clone());
            let _ = flag::register(signal, requested.clone());
            let _ = flag::register_usize(signal, received.clone(), signal as usize);
        }
        Signals { received }
    }

    /// The exit status and name of the signal that interrupted the work (SIGINT where none
    /// did: the library was asked to stop some other way).
    pub fn interrupted_by(&self) -> (u8, &'static str) {
        match self.received.load(Ordering::Relaxed) as i32 {
            SIGTERM => (128 + SIGTERM as u8, "SIGTERM"),
            _ => (128 + SIGINT as u8, "SIGINT"),
        }
    }
}
