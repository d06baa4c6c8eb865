//! The `mirage` command line: parses arguments and calls the library.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "mirage",
    version,
    about = "Inverse design of atmospheric mirages"
)]
struct Cli {
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Trace every point pair through the problem's medium and report endpoints.
    Trace {
        /// Problem file (JSON).
        problem: PathBuf,
        /// Write the JSON report here.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Fit the free parameters so that every pair's ray lands on its target.
    Fit {
        /// Problem file (JSON).
        problem: PathBuf,
        /// Write the JSON result here.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Convergence plot (.png or .svg).
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Ray diagram of the fitted medium (.png or .svg).
        #[arg(long)]
        rays: Option<PathBuf>,
        /// Solver: lm, nelder-mead or auto (overrides the problem file).
        #[arg(long)]
        method: Option<String>,
        /// No progress line.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Measure the speed/accuracy trade of the integrators on a problem.
    Tradeoff {
        /// Problem file (JSON).
        problem: PathBuf,
        /// Write the measurements as JSON here.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Write the measurements as CSV here.
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Pareto plot, error against time (.png or .svg).
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Measure traces only, no fits.
        #[arg(long)]
        no_fit: bool,
    },
    /// Draw the ray diagram of a problem's pairs through its medium.
    Rays {
        /// Problem file (JSON).
        problem: PathBuf,
        /// Output image (.png or .svg).
        #[arg(short, long)]
        output: PathBuf,
    },
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            // clap: 0 for --help/--version, 2 for usage errors.
            return ExitCode::from(e.exit_code().clamp(0, 255) as u8);
        }
    };
    if let Some(n) = cli.threads {
        if n == 0 {
            eprintln!("error: <command line>: --threads: must be at least 1");
            return ExitCode::from(2);
        }
        // Only fails if a pool already exists, which cannot happen here.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global();
    }
    let result = match &cli.command {
        Command::Trace { problem, output } => {
            mirage::app::trace(problem, output.as_deref()).map(|_| ())
        }
        Command::Fit {
            problem,
            output,
            plot,
            rays,
            method,
            quiet,
        } => {
            let options = mirage::app::FitOptions {
                output: output.clone(),
                plot: plot.clone(),
                rays: rays.clone(),
                method: method.clone(),
                progress: !quiet,
            };
            mirage::app::fit(problem, &options).map(|_| ())
        }
        Command::Rays { problem, output } => mirage::app::rays(problem, output),
        Command::Tradeoff {
            problem,
            output,
            csv,
            plot,
            no_fit,
        } => mirage::app::tradeoff(
            problem,
            output.as_deref(),
            csv.as_deref(),
            plot.as_deref(),
            !no_fit,
        )
        .map(|_| ()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
