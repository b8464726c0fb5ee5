//! SIGINT, SIGTERM and SIGHUP while the station runs, at the desk or in the headset.
//!
//! The first such signal asks the running loop to stop as a clean exit does: the sculpt is
//! saved, the autosave session is closed, and the process then exits with the conventional
//! status, 128 plus the signal's number (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP). A
//! second signal exits at once with that status: the stroke journal still holds the work, and
//! `argile recover` (or the next start) gives it back.
//!
//! The loops poll [`received`] once a frame (or once a wait, in the headset while no session
//! runs); handlers only store the signal's number, which is all a handler may safely do.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

use anyhow::{Context, Result};
use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};

/// The signals that stop the station.
pub const STOPPING: [i32; 3] = [SIGINT, SIGTERM, SIGHUP];

struct Flags {
    /// Set by the first signal; a signal arriving while it is set exits at once.
    any: Arc<AtomicBool>,
    /// The number of the last signal received, 0 for none.
    which: Arc<AtomicUsize>,
}

static FLAGS: OnceLock<Flags> = OnceLock::new();

/// Installs the handlers (once per process; later calls do nothing).
pub fn install() -> Result<()> {
    if FLAGS.get().is_some() {
        return Ok(());
    }
    let flags = Flags { any: Arc::new(AtomicBool::new(false)), which: Arc::new(AtomicUsize::new(0)) };
    for signal in STOPPING {
        // Handlers run in the order they were registered: the exit checks the flag before
        // this signal sets it, so only a second signal exits.
        signal_hook::flag::register_conditional_shutdown(signal, exit_status(signal), Arc::clone(&flags.any))
            .and_then(|_| signal_hook::flag::register(signal, Arc::clone(&flags.any)))
            .and_then(|_| {
                signal_hook::flag::register_usize(signal, Arc::clone(&flags.which), signal as usize)
            })
            .with_context(|| format!("cannot handle the signal {}", name(signal)))?;
    }
    let _ = FLAGS.set(flags);
    Ok(())
}

/// The signal received since [`install`], if any.
pub fn received() -> Option<i32> {
    let flags = FLAGS.get()?;
    if !flags.any.load(Ordering::SeqCst) {
        return None;
    }
    Some(flags.which.load(Ordering::SeqCst) as i32)
}

/// The exit status for a process stopped by `signal`: 128 plus its number.
pub fn exit_status(signal: i32) -> i32 {
    128 + signal
}

/// The signal's name (`SIGTERM`).
pub fn name(signal: i32) -> &'static str {
    match signal {
        SIGINT => "SIGINT",
        SIGTERM => "SIGTERM",
        SIGHUP => "SIGHUP",
        _ => "a signal",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statuses_and_names_are_the_conventional_ones() {
        assert_eq!(exit_status(SIGINT), 130);
        assert_eq!(exit_status(SIGTERM), 143);
        assert_eq!(exit_status(SIGHUP), 129);
        assert_eq!(name(SIGHUP), "SIGHUP");
    }
}
