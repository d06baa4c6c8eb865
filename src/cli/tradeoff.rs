//! `mirage tradeoff`: the speed/accuracy trade of the integrators on a problem.

use crate::error::Result;
use crate::io::{Output, OutputKind, check_outputs, write_json};
use crate::problem::Problem;
use crate::tradeoff::Tradeoff;
use std::path::PathBuf;

/// Measure the speed/accuracy trade of the integrators on a problem.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct TradeoffOptions {
    /// Problem file (JSON).
    pub problem: PathBuf,
    /// Write the measurements as JSON here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write the measurements as CSV here.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Pareto plot, error against time (.png or .svg).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Measure traces only, no fits.
    #[arg(long)]
    pub no_fit: bool,
}

/// Measures endpoint error, trace cost and fit quality for a range of RK4
/// steps and Dormand–Prince tolerances; prints a table and writes JSON, CSV and
/// a Pareto plot where asked. All outputs are checked before measuring.
pub fn run(o: &TradeoffOptions) -> Result<Tradeoff> {
    let problem = Problem::load(&o.problem)?;
    check_outputs(
        [
            Output::optional("-o", o.output.as_ref(), OutputKind::Any),
            Output::optional("--csv", o.csv.as_ref(), OutputKind::Any),
            Output::optional("--plot", o.plot.as_ref(), OutputKind::Plot),
        ]
        .into_iter()
        .flatten(),
        &[o.problem.as_path()],
    )?;
    let fit = !o.no_fit;
    if fit {
        crate::tradeoff::check_fit(&problem)?;
    }
    let t = crate::tradeoff::measure(&problem, fit)?;
    // The last cancellation point: once writing starts, it finishes.
    crate::interrupt::check()?;
    if let Some(out) = &o.output {
        write_json(out, &t)?;
    }
    if let Some(c) = &o.csv {
        crate::io::write_atomic(c, t.to_csv().as_bytes())?;
    }
    if let Some(p) = &o.plot {
        crate::plot::draw_tradeoff(&t, p)?;
    }
    print!("{}", t.to_table());
    Ok(t)
}
