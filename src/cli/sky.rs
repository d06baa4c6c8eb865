//! `mirage sky`: a scene's sky as a lat-long environment map. The flags are
//! [`SkyOptions`], the work [`sky_command`].

pub use crate::envmap::SkyOptions;
use crate::envmap::sky_command;
use crate::error::Result;

/// Bakes and writes the map, and prints its lookup error near the horizon.
pub fn run(o: &SkyOptions) -> Result<()> {
    sky_command(o).map(|_| ())
}
