//! `mirage compare`: an image against a reference, with limits that fail the
//! command. The flags are [`CompareOptions`], the work [`compare_command`].

use crate::compare::compare_command;
pub use crate::compare::{CompareOptions, Limits};
use crate::error::Result;

/// Compares, prints and writes the metrics; fails when a limit is missed.
pub fn run(o: &CompareOptions) -> Result<()> {
    compare_command(o).map(|_| ())
}
