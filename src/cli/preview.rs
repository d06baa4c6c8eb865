//! `mirage preview` (feature `preview`): the GPU previewer's window, or one
//! headless frame. The flags are [`PreviewOptions`], the work
//! [`preview_command`].

use crate::error::Result;
pub use crate::preview::PreviewOptions;
use crate::preview::preview_command;

/// Opens the window, or renders the headless frame (or benchmark).
pub fn run(o: &PreviewOptions) -> Result<()> {
    preview_command(o)
}
