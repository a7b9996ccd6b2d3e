//! Stopping long work early: one process-wide request flag, set by whoever wants the work to
//! stop (the `hmdist` program: on Ctrl-C or SIGTERM) and polled by the loops that run for
//! long: the render driver's primary rays and pixels (within a pixel too, every
//! [`POLL_RAYS`] gather rays), the photon trace, the points of [`crate::points::hmd_at`],
//! and the images of an experiment. A loop that sees it returns [`Error::Interrupted`]
//! without writing anything; the files it would have written are written through a temporary
//! and a rename ([`crate::image::write_atomically`]), so an interrupted run leaves the
//! previous files, or none, never a half-written one.
//!
//! The flag stays set until [`clear`]: a caller that goes on after an interruption (a Python
//! session after `KeyboardInterrupt`) clears it first.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

use crate::error::{Error, Result};

/// Gather rays cast between two looks at the flag within one pixel: a pixel of 10⁹ rays
/// stops within milliseconds, and the look costs nothing beside a ray.
pub const POLL_RAYS: u32 = 1 << 14;

fn shared() -> &'static Arc<AtomicBool> {
    static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();
    FLAG.get_or_init(|| Arc::new(AtomicBool::new(false)))
}

/// The flag itself, for a signal handler to set (`signal_hook::flag::register`): setting it
/// is [`request`].
pub fn flag() -> Arc<AtomicBool> {
    shared().clone()
}

/// Asks the work in progress (and any started later, until [`clear`]) to stop.
pub fn request() {
    shared().store(true, Ordering::Relaxed);
}

/// Whether the work has been asked to stop.
#[inline]
pub fn requested() -> bool {
    shared().load(Ordering::Relaxed)
}

/// Whether a loop over rays should stop before ray `index`: every [`POLL_RAYS`] rays it looks
/// at the flag.
#[inline]
pub fn stop_at_ray(index: usize) -> bool {
    index % POLL_RAYS as usize == POLL_RAYS as usize - 1 && requested()
}

/// [`Error::Interrupted`] if the work has been asked to stop.
#[inline]
pub fn check() -> Result<()> {
    if requested() {
        return Err(Error::Interrupted);
    }
    Ok(())
}

/// Withdraws the request: work started from now on runs to the end.
pub fn clear() {
    shared().store(false, Ordering::Relaxed);
}
