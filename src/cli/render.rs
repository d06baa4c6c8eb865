//! `mirage render`: a scene seen through its air along curved rays, written as
//! a PNG (and an EXR). The flags are [`CommandOptions`], the work
//! [`render_command`].

use crate::error::Result;
pub use crate::render::CommandOptions;
use crate::render::render_command;

/// Renders and writes the images.
pub fn run(o: &CommandOptions) -> Result<()> {
    render_command(o).map(|_| ())
}
