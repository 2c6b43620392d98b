//! Ctrl-C (and the `SIGTERM` a scheduler sends). The binary's signal handler calls
//! [`request`]; long work polls the flag between bands, sample passes and measurements, so
//! it ends at a clean point: nothing half-written, a partial image only where every pixel
//! has a sample. A second signal ends the process at once, unless a file is being written,
//! which finishes first (it takes milliseconds, and a killed write would leave its
//! temporary file behind).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use crate::error::{Error, Result};

/// Set once an interruption is asked for; never cleared.
static STOP: AtomicBool = AtomicBool::new(false);
/// Files being written now (see [`Writing`]).
static WRITING: AtomicUsize = AtomicUsize::new(0);

/// What a signal should do, as [`request`] decides it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    /// The first signal: the work stops at its next clean point.
    Stop,
    /// A second signal: end the process now.
    Exit,
    /// A second signal while a file is being written: that file finishes first.
    Wait,
}

/// Asks the work to stop; what the caller (the signal handler) should do next.
pub fn request() -> Request {
    if !STOP.swap(true, Ordering::SeqCst) {
        Request::Stop
    } else if WRITING.load(Ordering::SeqCst) > 0 {
        Request::Wait
    } else {
        Request::Exit
    }
}

/// Whether an interruption was asked for.
pub fn requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// `Err(Error::Interrupted)` once an interruption was asked for: the check between stages.
pub(crate) fn check() -> Result<()> {
    match requested() {
        true => Err(Error::Interrupted),
        false => Ok(()),
    }
}

/// The flag itself, for loops that take an `&AtomicBool` to stop on.
pub(crate) fn flag() -> &'static AtomicBool {
    &STOP
}

/// Held while an output file is written: a second signal then waits for it.
pub(crate) struct Writing(());

impl Writing {
    pub(crate) fn start() -> Self {
        WRITING.fetch_add(1, Ordering::SeqCst);
        Writing(())
    }
}

impl Drop for Writing {
    fn drop(&mut self) {
        WRITING.fetch_sub(1, Ordering::SeqCst);
    }
}
