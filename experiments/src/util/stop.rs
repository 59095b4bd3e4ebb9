//! Stopping a run from outside: the first Ctrl-C asks every fit in
//! progress to stop at its next optimiser iteration (through its
//! [`FitProgress`]) and every run not yet recorded to record nothing; a
//! second Ctrl-C ends the process at once. Runs recorded before the stop
//! stay, so `--resume` goes on from there.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};

use gpodo_traits::FitProgress;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Asks the process's fits and runs to stop.
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Forgets a stop asked for earlier: a library caller (the Python package)
/// runs again in the same process after Ctrl-C stopped a run.
pub fn clear() {
    REQUESTED.store(false, Ordering::SeqCst);
}

/// Whether a stop was asked for.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// What a fit's progress answers: stop once a stop was asked for.
pub fn control_flow() -> ControlFlow<()> {
    if requested() {
        ControlFlow::Break(())
    } else {
        ControlFlow::Continue(())
    }
}

/// A fit's progress that only listens for the stop.
pub struct StopOnRequest;

impl FitProgress for StopOnRequest {
    fn iteration(&self, _start: usize, _iteration: u64, _objective: f64) -> ControlFlow<()> {
        control_flow()
    }

    fn stop_requested(&self) -> bool {
        requested()
    }
}

/// Installs the Ctrl-C handler: the first asks to stop, the second exits
/// with status 130.
///
/// # Errors
/// When a handler cannot be installed.
pub fn install_ctrl_c() -> Result<(), ctrlc::Error> {
    ctrlc::set_handler(|| {
        if requested() {
            eprintln!("stopped");
            std::process::exit(130);
        }
        request();
        eprintln!(
            "stopping: fits end at their next iteration, unfinished runs record nothing, `gpodo live` leaves its topics (Ctrl-C again to quit at once)"
        );
    })
}
