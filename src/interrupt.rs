//! Cancellation of long runs: one process-wide flag, set by Ctrl-C (SIGINT)
//! in the command line, polled by the long loops.
//!
//! The command line installs the handler ([`install_handler`]) for the
//! commands that poll the flag: `fit`, `render`, `tradeoff` and `preview
//! --headless`. The handler sets the flag; the work notices it at its next
//! cancellation point and unwinds as [`Error::Interrupted`] (exit code 130,
//! one line, no output written). A step that cannot poll (a GPU driver
//! compiling the shader, which takes seconds on a software device) is cut
//! short by the handler itself: [`GRACE`] after the signal it ends the
//! process with the same line and code, once no output is being written
//! ([`Writing`]).
//!
//! Cancellation points, each bounded in work so the run stops well within a
//! second of the signal on the bundled problems and scenes:
//! - the fit: every evaluation of the residuals, the Jacobian or F, and every
//!   iterate of every solver run (restarts and growth's candidate fits run on
//!   rayon's workers and poll the same flag);
//! - the renderer: every 16 × 16 tile (rayon's workers skip the tiles left
//!   once the flag is up);
//! - `tradeoff`: every setting measured, every timed repeat, and its fits;
//! - the headless previewer: every compute pass of every sample's frame (one
//!   pass marches every pixel's ray on by a bounded number of iterations).
//!
//! Outputs are written only after the work, and the flag is checked once more
//! before the first is written: an interrupted run leaves no output file (and
//! the atomic writes of [`crate::io`] leave no partial one).
//!
//! The library never installs a handler: inside a Python process the flag is
//! never set (Python turns Ctrl-C into `KeyboardInterrupt` itself), and
//! [`requested`] is one relaxed atomic load, free to poll.

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

/// Set once Ctrl-C has been pressed (or [`request`] called).
static REQUESTED: AtomicBool = AtomicBool::new(false);

/// The exit code of an interrupted run: 128 + SIGINT (2), as shells report a
/// process that SIGINT ended.
pub const EXIT_CODE: u8 = crate::error::INTERRUPTED_EXIT_CODE;

/// Outputs being written now ([`Writing`]).
static WRITING: AtomicUsize = AtomicUsize::new(0);

/// How long the handler leaves the work to stop on its own before it ends
/// the process: the cancellation points answer within ~0.5 s on the bundled
/// problems and scenes (one residual evaluation of a fit at 1 mm RK4 steps
/// is the longest), and the whole must stay within a second with room for
/// a loaded machine.
pub const GRACE: Duration = Duration::from_millis(600);

/// Held while an output file is written ([`crate::io::write_atomic`]): the
/// handler's forced exit waits for it, so that no temporary file is left
/// behind. A write starts only after the last cancellation point, so one
/// under way when Ctrl-C comes finishes (milliseconds) and the run exits
/// as it would have.
pub struct Writing(());

impl Writing {
    /// Marks a write as under way until the guard is dropped.
    pub fn start() -> Writing {
        WRITING.fetch_add(1, Ordering::SeqCst);
        Writing(())
    }
}

impl Drop for Writing {
    fn drop(&mut self) {
        WRITING.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Asks every long loop of this process to stop at its next cancellation
/// point. What the Ctrl-C handler does; tests call it directly.
pub fn request() {
    REQUESTED.store(true, Ordering::Relaxed);
}

/// Whether a stop has been asked for.
#[inline]
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// A cancellation point: [`Error::Interrupted`] once a stop has been asked for.
#[inline]
pub fn check() -> Result<()> {
    if requested() {
        Err(Error::Interrupted)
    } else {
        Ok(())
    }
}

/// Installs the Ctrl-C handler: the first Ctrl-C sets the flag and, if the
/// process is still running [`GRACE`] later (and writes nothing), ends it
/// with [`EXIT_CODE`]. The handler runs on a thread of its own (the `ctrlc`
/// crate's), where it may wait; a second Ctrl-C waits for the first (the
/// process ends within [`GRACE`] anyway). For the command line
/// only (a library must leave the process's signals to its host). `Err` with the reason when
/// no handler can be installed; Ctrl-C then ends the process as it would
/// without one.
pub fn install_handler() -> std::result::Result<(), ctrlc::Error> {
    ctrlc::set_handler(|| {
        request();
        std::thread::sleep(GRACE);
        while WRITING.load(Ordering::SeqCst) > 0 {
            std::thread::sleep(Duration::from_millis(5));
        }
        eprintln!("error: {}", Error::Interrupted);
        std::process::exit(i32::from(EXIT_CODE));
    })
}
