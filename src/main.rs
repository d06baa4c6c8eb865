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
    /// Render a scene seen through its air along curved rays.
    Render {
        /// Scene file (JSON).
        scene: PathBuf,
        /// Output image (.png, tone-mapped sRGB).
        #[arg(short, long)]
        output: PathBuf,
        /// Also write the linear HDR image here (.exr).
        #[arg(long)]
        exr: Option<PathBuf>,
        /// Show the albedo of what each ray hits (the sky's colour for a miss).
        #[arg(long)]
        albedo: bool,
        /// Straight rays (δ ≡ 0), for comparison.
        #[arg(long)]
        straight: bool,
        /// Samples per pixel (overrides the scene).
        #[arg(long)]
        spp: Option<u32>,
        /// Image width in pixels (overrides the scene).
        #[arg(long)]
        width: Option<u32>,
        /// Image height in pixels (overrides the scene).
        #[arg(long)]
        height: Option<u32>,
        /// Sphere tracer: plain, enhanced or quadric (default).
        #[arg(long)]
        tracer: Option<String>,
        /// Integrate every ray, even where a table of paths could be reused.
        #[arg(long)]
        no_path_reuse: bool,
        /// Leave out the scene's veiling glare.
        #[arg(long)]
        no_glare: bool,
        /// No progress bar and no summary.
        #[arg(long, short)]
        quiet: bool,
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
        Command::Render {
            scene,
            output,
            exr,
            albedo,
            straight,
            spp,
            width,
            height,
            tracer,
            no_path_reuse,
            no_glare,
            quiet,
        } => mirage::render::render_command(&mirage::render::CommandOptions {
            scene: scene.clone(),
            output: output.clone(),
            exr: exr.clone(),
            albedo: *albedo,
            straight: *straight,
            spp: *spp,
            width: *width,
            height: *height,
            tracer: tracer.clone(),
            no_path_reuse: *no_path_reuse,
            no_glare: *no_glare,
            quiet: *quiet,
        })
        .map(|_| ()),
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
