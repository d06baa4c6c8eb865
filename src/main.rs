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
        /// Hit tolerance as a fraction of a pixel (default 0.001; larger: faster, objects grow).
        #[arg(long)]
        hit_fraction: Option<f64>,
    },
    /// Compare an image with a reference: RMSE, PSNR, SSIM, share of pixels over a threshold.
    Compare {
        /// Our image (.png, .exr or .npy).
        ours: PathBuf,
        /// The reference image (.png, .exr or .npy).
        reference: PathBuf,
        /// A pixel differs when its largest channel difference exceeds this.
        #[arg(long)]
        threshold: Option<f64>,
        /// Write the difference heat map here (.png).
        #[arg(long)]
        diff: Option<PathBuf>,
        /// Write the metrics as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Fail (exit code 1) if the RMSE is above this.
        #[arg(long)]
        max_rmse: Option<f64>,
        /// Fail if the PSNR (dB) is below this.
        #[arg(long)]
        min_psnr: Option<f64>,
        /// Fail if the SSIM is below this.
        #[arg(long)]
        min_ssim: Option<f64>,
        /// Fail if the share of pixels over the threshold (0 to 1) is above this.
        #[arg(long)]
        max_share_over: Option<f64>,
    },
    /// Write a scene's sky as a lat-long environment map (Mitsuba's envmap convention).
    Sky {
        /// Scene file (JSON).
        scene: PathBuf,
        /// Output (.exr).
        #[arg(short, long)]
        output: PathBuf,
        /// Width in texels (default 1024).
        #[arg(long)]
        width: Option<u32>,
        /// Height in texels (default width / 2; taller maps are more accurate near the horizon).
        #[arg(long)]
        height: Option<u32>,
    },
    /// Preview a scene (or a problem's medium) live on the GPU, and edit the air.
    #[cfg(feature = "preview")]
    Preview {
        /// Scene or problem file (JSON).
        input: PathBuf,
        /// No window: render one frame offscreen (to --output).
        #[arg(long)]
        headless: bool,
        /// The headless frame (.png).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Frame width in pixels (default: the scene's, or the window's).
        #[arg(long)]
        width: Option<u32>,
        /// Frame height in pixels.
        #[arg(long)]
        height: Option<u32>,
        /// Show the albedo of what each ray hits.
        #[arg(long)]
        albedo: bool,
        /// Straight rays (δ ≡ 0), for comparison.
        #[arg(long)]
        straight: bool,
        /// With --headless: print the time per frame (1280×720 unless sized).
        #[arg(long)]
        bench: bool,
        /// Close the window after this many frames.
        #[arg(long)]
        frames: Option<u64>,
        /// Save the window (frame and panels) here when it closes (.png).
        #[arg(long)]
        screenshot: Option<PathBuf>,
        /// Leave out the scene's veiling glare.
        #[arg(long)]
        no_glare: bool,
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
            hit_fraction,
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
            hit_fraction: *hit_fraction,
        })
        .map(|_| ()),
        #[cfg(feature = "preview")]
        Command::Preview {
            input,
            headless,
            output,
            width,
            height,
            albedo,
            straight,
            bench,
            frames,
            screenshot,
            no_glare,
        } => mirage::preview::preview_command(&mirage::preview::PreviewOptions {
            input: input.clone(),
            headless: *headless,
            output: output.clone(),
            width: *width,
            height: *height,
            albedo: *albedo,
            straight: *straight,
            bench: *bench,
            frames: *frames,
            screenshot: screenshot.clone(),
            no_glare: *no_glare,
        }),
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
        Command::Compare {
            ours,
            reference,
            threshold,
            diff,
            json,
            max_rmse,
            min_psnr,
            min_ssim,
            max_share_over,
        } => mirage::compare::compare_command(&mirage::compare::CompareOptions {
            ours: ours.clone(),
            reference: reference.clone(),
            threshold: *threshold,
            diff: diff.clone(),
            json: json.clone(),
            limits: mirage::compare::Limits {
                max_rmse: *max_rmse,
                min_psnr: *min_psnr,
                min_ssim: *min_ssim,
                max_share_over: *max_share_over,
            },
        })
        .map(|_| ()),
        Command::Sky {
            scene,
            output,
            width,
            height,
        } => mirage::envmap::sky_command(&mirage::envmap::SkyOptions {
            scene: scene.clone(),
            output: output.clone(),
            width: *width,
            height: *height,
        })
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
