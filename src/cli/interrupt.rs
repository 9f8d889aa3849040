//! SIGINT and SIGTERM (issue 18): a command interrupted leaves nothing at
//! its output names and no temporary behind. A thread waits for the
//! signals; on one it removes the temporaries being written
//! (`output::abandon_temporaries`, whose lock it keeps, so none is created
//! or renamed into place after it) and ends the process with 128 + the
//! signal number. While the progressive `reference` traces, or `bench`
//! times frames ([`FinishOnSignal`]), the first signal only asks it to stop
//! after the pass or frame in flight and write what it has; a second one
//! ends it as above.
//! SIGKILL cannot be caught: there, the temporary names at least keep
//! partial files off the output names.

use caustics::output;
use signal_hook::consts::{SIGINT, SIGTERM};
use std::sync::atomic::{AtomicBool, Ordering};

/// Whether a signal should let the command finish (the reference's passes).
static FINISH: AtomicBool = AtomicBool::new(false);
/// Whether a signal asked the command to finish.
static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Starts the signal thread. Call once, first thing.
pub fn install() -> anyhow::Result<()> {
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            for signal in signals.forever() {
                let name = if signal == SIGINT { "SIGINT" } else { "SIGTERM" };
                if FINISH.load(Ordering::SeqCst) && !REQUESTED.swap(true, Ordering::SeqCst) {
                    eprintln!("{name}: finishing the pass or frame in flight, then writing what there is (again to stop at once)");
                    continue;
                }
                let _held = output::abandon_temporaries();
                eprintln!("error: interrupted by {name}; no output written");
                signal_hook::low_level::exit(128 + signal);
            }
        })?;
    Ok(())
}

/// While alive, a signal asks the command to finish ([`requested`]) instead
/// of ending it.
pub struct FinishOnSignal(());

impl FinishOnSignal {
    pub fn new() -> Self {
        FINISH.store(true, Ordering::SeqCst);
        FinishOnSignal(())
    }

    /// Whether a signal asked to finish.
    pub fn requested(&self) -> bool {
        REQUESTED.load(Ordering::SeqCst)
    }
}

impl Drop for FinishOnSignal {
    fn drop(&mut self) {
        FINISH.store(false, Ordering::SeqCst);
    }
}
