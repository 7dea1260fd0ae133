//! SIGINT and SIGTERM (and SIGHUP): caught from the program's start, so that every phase ends
//! on them. During the set-up (reading the case, particle files and meshes, seeding an MFIX
//! deck's lattice, placing the particles inserted at the start) nothing has been written yet,
//! and the program ends at once with a message and [`crate::run::EXIT_INTERRUPTED`]; once the
//! run loop has started, the signal raises the run's stop flag, and the run ends at its next
//! look at the state with a checkpoint to continue from.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// True once the run loop has started (it then stops on the flag).
static RUNNING: AtomicBool = AtomicBool::new(false);

/// Installs the handler; the flag it raises is the run's stop flag.
pub fn install() -> Arc<AtomicBool> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    // A second signal while the checkpoint is being written is ignored: the flag is set.
    let handler = move || {
        flag.store(true, Ordering::SeqCst);
        if !RUNNING.load(Ordering::SeqCst) {
            eprintln!("interrupted during the set-up, before the run started: nothing was written");
            std::process::exit(i32::from(crate::run::EXIT_INTERRUPTED));
        }
    };
    if let Err(e) = ctrlc::set_handler(handler) {
        eprintln!(
            "warning: cannot catch SIGINT/SIGTERM ({e}); an interrupted run will not write a checkpoint"
        );
    }
    stop
}

/// The run loop has started: from now on a signal stops it at its next look at the state.
pub fn running() {
    RUNNING.store(true, Ordering::SeqCst);
}
