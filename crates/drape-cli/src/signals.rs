//! Ctrl-C (SIGINT), SIGTERM and SIGHUP during `drape run`.
//!
//! While the scenario is read and built — before the output directory is
//! written — a signal ends the process at once with a message and the
//! shell's code for it, 128 + the signal (130 for SIGINT, 143 for
//! SIGTERM): there is nothing to save yet, and a large mesh may take
//! seconds to build. From [`setup_done`] on, a signal only sets [`STOP`]:
//! the run ends after its current step with a checkpoint and the summary
//! `"interrupted"` (exit 130, as the README says).

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by a signal once the set-up is done: the run stops after its step.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// Whether the set-up is still going on (a signal then ends the process).
static SETUP: AtomicBool = AtomicBool::new(true);

/// Installs the handler of SIGINT, SIGTERM and SIGHUP.
#[cfg(unix)]
pub fn install() {
    let handler = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
    for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
        // SAFETY: the handler only stores into atomics, writes a static
        // message with write(2) and calls _exit(2), all async-signal-safe.
        unsafe {
            libc::signal(signal, handler);
        }
    }
}

/// Installs the handler of Ctrl-C (the set-up then ends with the run's
/// first step).
#[cfg(not(unix))]
pub fn install() {
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::SeqCst));
}

/// The set-up is over: a signal from now on stops the run after its step.
pub fn setup_done() {
    SETUP.store(false, Ordering::SeqCst);
}

#[cfg(unix)]
extern "C" fn on_signal(signal: libc::c_int) {
    if !SETUP.load(Ordering::SeqCst) {
        STOP.store(true, Ordering::SeqCst);
        return;
    }
    let message: &[u8] = match signal {
        libc::SIGINT => {
            b"interrupted (SIGINT) while setting up the run; nothing was run or written\n"
        }
        libc::SIGTERM => {
            b"terminated (SIGTERM) while setting up the run; nothing was run or written\n"
        }
        _ => b"hung up (SIGHUP) while setting up the run; nothing was run or written\n",
    };
    // SAFETY: write(2) and _exit(2) are async-signal-safe; the message is
    // a static buffer of the length given.
    unsafe {
        libc::write(2, message.as_ptr().cast(), message.len());
        libc::_exit(128 + signal);
    }
}
