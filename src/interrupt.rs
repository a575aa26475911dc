//! Ctrl-C during a headless run: the first one stops the run between two ticks, so that
//! everything recorded so far is written as at the run's end; a second one ends the
//! process at once, as usual.

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by the first SIGINT once [`catch`] has been called.
static REQUESTED: AtomicBool = AtomicBool::new(false);

/// The exit code of a run stopped by Ctrl-C (128 + SIGINT, as shells report it).
pub const EXIT_CODE: u8 = 130;

#[cfg(unix)]
extern "C" fn on_sigint(_: libc::c_int) {
    REQUESTED.store(true, Ordering::SeqCst);
    // SAFETY: signal() is async-signal-safe; the next Ctrl-C gets the default action.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
    }
}

/// From now on, the first Ctrl-C only asks the run to stop (see [`requested`]), unless
/// SIGINT was ignored (a background job of a non-interactive shell), which it stays.
pub fn catch() {
    #[cfg(unix)]
    // SAFETY: the handler only stores to an atomic and restores the default action.
    unsafe {
        let before = libc::signal(
            libc::SIGINT,
            on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t,
        );
        if before == libc::SIG_IGN {
            libc::signal(libc::SIGINT, libc::SIG_IGN);
        }
    }
}

/// Whether Ctrl-C has asked the run to stop.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
