//! `mirage rays`: the ray diagram of a problem's pairs through its medium.

use crate::error::Result;
use crate::io::{Output, OutputKind, check_outputs};
use crate::problem::Problem;
use std::path::PathBuf;

/// Draw the ray diagram of a problem's pairs through its medium.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct RaysOptions {
    /// Problem file (JSON).
    pub problem: PathBuf,
    /// Output image (.png or .svg).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Draws the diagram of the problem's own medium to `output`.
pub fn run(o: &RaysOptions) -> Result<()> {
    let problem = Problem::load(&o.problem)?;
    check_outputs(
        [Output::new("-o", &o.output, OutputKind::Plot)],
        &[o.problem.as_path()],
    )?;
    crate::plot::draw_rays(&problem, &problem.medium, &o.output)
}
