//! The `mirage` command line: the [`Cli`] parser and one module per command.
//!
//! Every flag is defined once, on the options struct its command takes
//! (`#[derive(clap::Args)]`, the field's doc comment is its help), and its value
//! is checked by its clap value parser; a check that needs several flags is done
//! by the command and reported as [`Error::Usage`]. A value a parser refuses is
//! reported like a usage error, one line naming the flag ([`parse_error`]).
//!
//! Exit codes ([`EXIT_CODES`], printed by `mirage --help`): 0 when the command
//! did its work and every check asked of it passed; 1 when a check asked of
//! it failed (`mirage compare`'s limits, `mirage fit`'s target objective when
//! the problem or `--target-objective` sets one; the outputs are still
//! written) or the work itself failed (a file could not be written, the GPU,
//! the solver); 2 for bad input (a file, a flag, an output path), found before
//! any work starts ([`crate::io::check_outputs`]); 130 when Ctrl-C stopped a
//! long run (`fit`, `render`, `tradeoff`, `preview --headless`) before it
//! wrote anything ([`crate::interrupt`]).

pub mod air;
pub mod compare;
pub mod ensemble;
pub mod fit;
pub mod overlay;
#[cfg(feature = "preview")]
pub mod preview;
pub mod rays;
pub mod refraction;
pub mod refractivity;
pub mod render;
pub(crate) mod sightline;
pub mod sky;
pub mod sounding;
pub mod trace;
pub mod tradeoff;

use crate::error::{Error, Result};
use clap::error::{ContextKind, ContextValue, ErrorKind};
use std::process::ExitCode;

/// What each exit code means, for every command (the end of `mirage --help`).
pub const EXIT_CODES: &str = "\
Exit codes:
  0  done, and every check asked for passed
  1  a check asked for failed (compare: a --max-*/--min-* limit; fit: F above the
     target objective that the problem's solver.target_objective or
     --target-objective sets; the outputs are written all the same), or the
     work failed (writing a file, the GPU, the solver)
  2  bad input: a problem or scene file, a flag, or an output path (its folder
     missing, its extension wrong, an input's path), all checked before any
     work starts
  130  interrupted (Ctrl-C) during fit, render, tradeoff or preview --headless:
     stopped within a second, no output written";

/// The exit codes of `mirage fit` (the end of `mirage fit --help`).
pub const FIT_EXIT_CODES: &str = "\
Exit codes:
  0  the fit ran, and F is at or below the target objective if one is set
     (solver.target_objective in the problem, or --target-objective); with
     none set, the default target (1e-12 m²) steers the solver but does not
     fail the fit
  1  F ended above the target objective so set (the outputs are written all
     the same; the result's solver.reached_target is false), or writing an
     output or the solver failed
  2  bad input: the problem, a flag, or an output path (checked before the fit)
  130  interrupted (Ctrl-C): stopped within a second, no output written";

/// The whole command line.
#[derive(Debug, clap::Parser)]
#[command(
    name = "mirage",
    version,
    about = "Inverse design of atmospheric mirages",
    after_help = EXIT_CODES
)]
pub struct Cli {
    /// Worker threads (default: all cores).
    #[arg(long, global = true, value_parser = thread_count)]
    pub threads: Option<usize>,
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, clap::Subcommand)]
pub enum Command {
    /// Trace every point pair through the problem's medium and report endpoints.
    Trace(trace::TracePairsOptions),
    /// Fit the free parameters so that every pair's ray lands on its target.
    #[command(after_help = FIT_EXIT_CODES)]
    Fit(fit::FitOptions),
    /// Fit a problem N times to resampled observations: the parameters' spread and the profiles' envelopes.
    Ensemble(ensemble::EnsembleOptions),
    /// Draw a photo problem's marks on its photo where its starting air and camera put them.
    Overlay(overlay::OverlayOptions),
    /// Measure the speed/accuracy trade of the integrators on a problem.
    Tradeoff(tradeoff::TradeoffOptions),
    /// Draw the ray diagram of a problem's pairs through its medium.
    Rays(rays::RaysOptions),
    /// Render a scene seen through its air along curved rays.
    Render(render::CommandOptions),
    /// Compare an image with a reference: RMSE, PSNR, SSIM, share of pixels over a threshold.
    Compare(compare::CompareOptions),
    /// Write a scene's sky as a lat-long environment map (Mitsuba's envmap convention).
    Sky(sky::SkyOptions),
    /// Print n − 1 of air at a temperature, pressure, humidity and wavelength.
    Refractivity(refractivity::RefractivityOptions),
    /// Write and draw a medium's T, P, n − 1 and dn/dh against height (implied air for a logistic medium).
    Air(air::AirOptions),
    /// Tabulate the astronomical refraction near the horizon, the dip of the horizon and k, through real air.
    Refraction(refraction::RefractionOptions),
    /// Read a radiosonde or mast profile (IGRA 2, Wyoming, CSV) into a real-air medium.
    Sounding(sounding::SoundingOptions),
    /// Preview a scene (or a problem's medium) live on the GPU, and edit the air.
    #[cfg(feature = "preview")]
    Preview(preview::PreviewOptions),
}

impl Command {
    /// Whether the command polls [`crate::interrupt`]'s flag, so that Ctrl-C
    /// should set it rather than end the process: `fit`, `render`,
    /// `tradeoff` and `preview --headless`. The other commands are short, or
    /// (the window) stop on their own; Ctrl-C ends them as it ends any
    /// process, which their atomic writes make safe.
    pub fn polls_interrupts(&self) -> bool {
        match self {
            Command::Fit(_) | Command::Ensemble(_) | Command::Render(_) | Command::Tradeoff(_) => {
                true
            }
            #[cfg(feature = "preview")]
            Command::Preview(o) => o.headless,
            _ => false,
        }
    }

    /// Whether the command may keep the main thread in a window's event loop.
    fn runs_a_window(&self) -> bool {
        #[cfg(feature = "preview")]
        if let Command::Preview(_) = self {
            return true;
        }
        false
    }
}

/// `--threads`: at least 1.
fn thread_count(s: &str) -> std::result::Result<usize, crate::error::ValueError> {
    crate::validate::at_least_one(s)
}

impl Cli {
    /// Sizes rayon's global pool to `--threads`, if given (else all cores).
    /// With one thread the main thread is that pool's worker, so no thread is
    /// started at all (a short `trace` spent 5 % of its time starting one and
    /// handing work to it). Not for the previewer, whose main thread runs the
    /// window while the pool fits in the background.
    pub fn set_threads(&self) {
        if let Some(n) = self.threads {
            let mut pool = rayon::ThreadPoolBuilder::new().num_threads(n);
            if n == 1 && !self.command.runs_a_window() {
                pool = pool.use_current_thread();
            }
            // Only fails if a pool already exists, which cannot happen before
            // the command runs.
            let _ = pool.build_global();
        }
    }

    /// Installs the Ctrl-C handler ([`crate::interrupt::install_handler`])
    /// when the command polls its flag ([`Command::polls_interrupts`]); if
    /// none can be installed, says so and leaves Ctrl-C to end the process.
    pub fn handle_interrupts(&self) {
        if self.command.polls_interrupts()
            && let Err(e) = crate::interrupt::install_handler()
        {
            eprintln!("warning: cannot catch Ctrl-C ({e}): it will end the run at once");
        }
    }

    /// Runs the command.
    pub fn run(&self) -> Result<()> {
        match &self.command {
            Command::Trace(o) => trace::run(o).map(|_| ()),
            Command::Fit(o) => fit::run(o).map(|_| ()),
            Command::Ensemble(o) => ensemble::run(o).map(|_| ()),
            Command::Overlay(o) => overlay::run(o).map(|_| ()),
            Command::Tradeoff(o) => tradeoff::run(o).map(|_| ()),
            Command::Rays(o) => rays::run(o),
            Command::Render(o) => render::run(o),
            Command::Compare(o) => compare::run(o),
            Command::Sky(o) => sky::run(o),
            Command::Refractivity(o) => refractivity::run(o).map(|_| ()),
            Command::Air(o) => air::run(o).map(|_| ()),
            Command::Refraction(o) => refraction::run(o).map(|_| ()),
            Command::Sounding(o) => sounding::run(o).map(|_| ()),
            #[cfg(feature = "preview")]
            Command::Preview(o) => preview::run(o),
        }
    }
}

/// A flag's value refused by its parser (out of range, not a number, not one
/// of the choices) as a usage error naming the flag; `None` for every other
/// parse failure (help, version, a missing or unknown argument), which clap
/// prints itself.
pub fn parse_error(e: &clap::Error) -> Option<Error> {
    let flag = match e.get(ContextKind::InvalidArg) {
        // "--spp <SPP>": the flag as typed, without its value name.
        Some(ContextValue::String(arg)) => arg.split(' ').next().unwrap_or(arg).to_string(),
        _ => return None,
    };
    match e.kind() {
        ErrorKind::ValueValidation => {
            let message = std::error::Error::source(e)?.to_string();
            Some(Error::usage(flag, message))
        }
        ErrorKind::InvalidValue => {
            let value = match e.get(ContextKind::InvalidValue) {
                Some(ContextValue::String(v)) => v.clone(),
                _ => return None,
            };
            let expected = match e.get(ContextKind::ValidValue) {
                Some(ContextValue::Strings(names)) => {
                    names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>()
                }
                _ => return None,
            };
            let expected = match expected.split_last() {
                Some((last, [])) => last.clone(),
                Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
                None => return None,
            };
            Some(Error::usage(
                flag,
                format!("unknown value `{value}` (expected {expected})"),
            ))
        }
        _ => None,
    }
}

/// Prints a parse failure and gives its exit code: a refused value as one line
/// `error: --flag: message` (exit code 2), anything else as clap words it (exit
/// code 0 for `--help` and `--version`, 2 otherwise).
pub fn report_parse_error(e: &clap::Error) -> ExitCode {
    match parse_error(e) {
        Some(usage) => {
            eprintln!("error: {usage}");
            ExitCode::from(usage.exit_code() as u8)
        }
        None => {
            let _ = e.print();
            ExitCode::from(e.exit_code().clamp(0, 255) as u8)
        }
    }
}
