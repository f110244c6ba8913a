//! Interruption of a long computation from outside (the Python package's Ctrl-C): a flag that
//! the step loops ([`crate::run::simulate_with`], [`crate::fleet`]'s records) read every 500
//! steps, so a run, a sweep's points and a fleet record end within a fraction of a second of
//! [`raise`], with an error.
//!
//! The command line does not use it (Ctrl-C ends the process there, and the output directory
//! keeps the previous result: `output::OutputDir`).

use std::sync::atomic::{AtomicBool, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Asks every computation in progress to stop.
pub fn raise() {
    INTERRUPTED.store(true, Ordering::Relaxed);
}

/// Clears the request (before a new computation starts).
pub fn reset() {
    INTERRUPTED.store(false, Ordering::Relaxed);
}

/// Whether a stop was asked for.
pub fn requested() -> bool {
    INTERRUPTED.load(Ordering::Relaxed)
}

/// `Err` when a stop was asked for.
pub fn check() -> anyhow::Result<()> {
    if requested() {
        anyhow::bail!("interrupted");
    }
    Ok(())
}
