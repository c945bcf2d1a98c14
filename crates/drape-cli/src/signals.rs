//! Ctrl-C (SIGINT), SIGTERM and SIGHUP during `drape run`.
//!
//! While the scenario is read and built — before the output directory is
//! written — a signal ends the process at once with a message and the
//! shell's code for it, 128 + the signal (130 for SIGINT, 143 for
//! SIGTERM, 129 for SIGHUP): there is nothing to save yet, and a large
//! mesh may take seconds to build. From [`setup_done`] on, a signal only
//! sets [`STOP`] and records which signal it was ([`received`]): the run
//! ends after its current step with a checkpoint and the summary
//! `"interrupted"`, and the process exits with the same 128 + the signal.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

/// Set by a signal once the set-up is done: the run stops after its step.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// The first signal that asked the run to stop (0: none yet).
static RECEIVED: AtomicI32 = AtomicI32::new(0);

/// Whether the set-up is still going on (a signal then ends the process).
static SETUP: AtomicBool = AtomicBool::new(true);

/// SIGINT's number, the signal a stop is taken for when none was recorded
/// (on Windows, Ctrl-C).
const SIGINT: i32 = 2;

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
    let _ = ctrlc::set_handler(|| {
        let _ = RECEIVED.compare_exchange(0, SIGINT, Ordering::SeqCst, Ordering::SeqCst);
        STOP.store(true, Ordering::SeqCst);
    });
}

/// The set-up is over: a signal from now on stops the run after its step.
pub fn setup_done() {
    SETUP.store(false, Ordering::SeqCst);
}

/// The signal that stopped the run — its number and its name — SIGINT
/// when none was recorded.
pub fn received() -> (i32, &'static str) {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => (SIGINT, name(SIGINT)),
        signal => (signal, name(signal)),
    }
}

/// The exit code of a run stopped by `signal`: the shell's 128 + the
/// signal (130, 143, 129).
pub fn exit_code(signal: i32) -> u8 {
    u8::try_from(128 + signal).unwrap_or(130)
}

/// The name of a signal this module handles.
fn name(signal: i32) -> &'static str {
    #[cfg(unix)]
    match signal {
        libc::SIGTERM => return "SIGTERM",
        libc::SIGHUP => return "SIGHUP",
        _ => {}
    }
    if signal == SIGINT {
        "SIGINT"
    } else {
        "a signal"
    }
}

#[cfg(unix)]
extern "C" fn on_signal(signal: libc::c_int) {
    if !SETUP.load(Ordering::SeqCst) {
        // The first signal is the one the exit code reports.
        let _ = RECEIVED.compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst);
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
