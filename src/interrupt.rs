//! Ctrl-C (and the `SIGTERM` a scheduler sends). The binary's signal handler calls
//! [`request`]; long work polls the flag between bands, sample passes and measurements, so
//! it ends at a clean point: nothing half-written, a partial image only where every pixel
//! has a sample. A second signal ends the process at once, unless a file is being written,
//! which finishes first (it takes milliseconds, and a killed write would leave its
//! temporary file behind).
//!
//! OpenCL runtimes built on LLVM (Intel's CPU runtime, PoCL) install LLVM's own `SIGINT`
//! and `SIGTERM` handlers when they load and compile, over the binary's; on some machines
//! (Intel's runtime on an AMD EPYC) LLVM's handler then crashes the process on Ctrl-C. So
//! the binary's handlers are kept ([`keep_handlers`]) and put back ([`reclaim_handlers`])
//! after each step that may load such code, and at every check between stages.

use std::sync::OnceLock;
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
    reclaim_handlers();
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

/// The signals whose handlers [`keep_handlers`] keeps.
const KEPT_SIGNALS: [libc::c_int; 2] = [libc::SIGINT, libc::SIGTERM];

/// The binary's handlers of [`KEPT_SIGNALS`], in that order.
static KEPT: OnceLock<[libc::sigaction; 2]> = OnceLock::new();

/// Remembers the handlers now installed for `SIGINT` and `SIGTERM` as the binary's own:
/// call once, right after installing them.
pub fn keep_handlers() {
    let kept = KEPT_SIGNALS.map(|signal| {
        // SAFETY: sigaction with a null new action only reads the current one into `old`,
        // a zeroed (valid) struct.
        let mut old: libc::sigaction = unsafe { std::mem::zeroed() };
        unsafe { libc::sigaction(signal, std::ptr::null(), &mut old) };
        old
    });
    let _ = KEPT.set(kept);
}

/// Puts the handlers [`keep_handlers`] kept back where something replaced them; nothing
/// where none were kept (the library without the binary, the tests).
pub(crate) fn reclaim_handlers() {
    let Some(kept) = KEPT.get() else { return };
    for (signal, ours) in KEPT_SIGNALS.iter().zip(kept) {
        // SAFETY: as in keep_handlers; the action put back is one the process had
        // installed, with its handler still mapped (it is in the binary).
        let mut now: libc::sigaction = unsafe { std::mem::zeroed() };
        unsafe { libc::sigaction(*signal, std::ptr::null(), &mut now) };
        if now.sa_sigaction != ours.sa_sigaction {
            unsafe { libc::sigaction(*signal, ours, std::ptr::null_mut()) };
        }
    }
}
