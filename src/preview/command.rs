//! `mirage preview`: its options (each flag defined once, checked by clap) and
//! the command: the window, or a headless frame to a PNG and the `--bench`
//! timing.

use super::gpu::Tracer;
use super::pack::{View, pack};
use crate::error::{Error, Result};
use crate::io::{Output, OutputKind, check_outputs, write_atomic};
use crate::render::output::{ToneMap, encode_png};
use crate::render::{RenderOptions, Shading};
use crate::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::frame::{open_gpu, render_frame};
use super::input::{BENCH_SIZE, load_input};

/// Preview a scene (or a problem's medium) live on the GPU, and edit the air.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct PreviewOptions {
    /// Scene or problem file (JSON).
    pub input: PathBuf,
    /// No window: render one frame offscreen (to --output).
    #[arg(long)]
    pub headless: bool,
    /// The headless frame (.png).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Frame width in pixels (default: the scene's, or the window's).
    #[arg(long, value_parser = crate::render::image_side)]
    pub width: Option<u32>,
    /// Frame height in pixels.
    #[arg(long, value_parser = crate::render::image_side)]
    pub height: Option<u32>,
    /// Samples per pixel: of the headless frame (default: the scene's), or
    /// the most the window accumulates while the view is still (default
    /// 16). The samples are the renderer's fixed sequence, so N accumulated
    /// in the window make the headless frame at --spp N.
    #[arg(long, value_parser = crate::render::samples_per_pixel)]
    pub spp: Option<u32>,
    /// Show the albedo of what each ray hits.
    #[arg(long)]
    pub albedo: bool,
    /// Straight rays (δ ≡ 0), for comparison.
    #[arg(long)]
    pub straight: bool,
    /// With --headless: print the time per frame (1280×720 unless sized).
    #[arg(long)]
    pub bench: bool,
    /// Close the window after this many frames.
    #[arg(long, value_parser = frame_count)]
    pub frames: Option<u64>,
    /// Save the window (frame and panels) here when it closes (.png).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Leave out the scene's veiling glare.
    #[arg(long)]
    pub no_glare: bool,
    /// A photo problem's window: play this script of clicks, drags, typing
    /// and button presses (one a line: `click U V`, `drag U0 V0 U1 V1`,
    /// `button LABEL`, `type TEXT`, `wait N`, `wait-fit`), then close.
    #[arg(long)]
    pub script: Option<PathBuf>,
}

/// `--frames`: at least 1.
fn frame_count(s: &str) -> std::result::Result<u64, crate::error::ValueError> {
    crate::validate::at_least_one(s)
}

/// The frame size for the options: both given, one given (the other from the
/// scene's aspect ratio), or the scene's.
fn frame_size(scene: &Scene, width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let (w0, h0) = (scene.camera.width as f64, scene.camera.height as f64);
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, ((w as f64 * h0 / w0).round() as u32).max(1)),
        (None, Some(h)) => (((h as f64 * w0 / h0).round() as u32).max(1), h),
        (None, None) => (scene.camera.width, scene.camera.height),
    }
}

/// `mirage preview`: the window, or with `headless` one frame to a PNG (and
/// with `bench` the time per frame).
pub fn preview_command(o: &PreviewOptions) -> Result<()> {
    if super::photo::is_photo_problem(&o.input)? {
        return photo_preview(o);
    }
    if o.script.is_some() {
        return Err(Error::usage(
            "--script",
            "only for a photo problem's window (a problem with a `photo` section)",
        ));
    }
    let (width, height) = (o.width, o.height);
    let mut input = load_input(&o.input)?;
    if o.no_glare {
        input.scene.glare = None;
    }
    let mut inputs: Vec<&Path> = vec![o.input.as_path()];
    inputs.extend(input.scene.inputs.iter().map(PathBuf::as_path));
    check_outputs(
        [
            Output::optional(
                "--output",
                o.output.as_ref(),
                OutputKind::Png("a preview frame"),
            ),
            Output::optional(
                "--screenshot",
                o.screenshot.as_ref(),
                OutputKind::Png("a screenshot"),
            ),
        ]
        .into_iter()
        .flatten(),
        &inputs,
    )?;
    if o.headless && (o.frames.is_some() || o.screenshot.is_some()) {
        return Err(Error::usage(
            if o.frames.is_some() {
                "--frames"
            } else {
                "--screenshot"
            },
            "only for the window (a headless frame goes to --output)",
        ));
    }
    if !o.headless {
        if o.output.is_some() || o.bench {
            return Err(Error::usage(
                if o.bench { "--bench" } else { "--output" },
                "only with --headless (the window saves with --screenshot)",
            ));
        }
        return super::window::run(
            input,
            super::window::WindowSettings {
                width,
                height,
                albedo: o.albedo,
                straight: o.straight,
                accumulate: o.spp.unwrap_or(super::accumulate::DEFAULT_TARGET),
                frames: o.frames,
                screenshot: o.screenshot.clone(),
            },
        );
    }
    if o.output.is_none() && !o.bench {
        return Err(Error::usage(
            "--output",
            "a headless preview needs an output image (-o frame.png) or --bench",
        ));
    }
    let options = RenderOptions {
        shading: if o.albedo {
            Shading::Albedo
        } else {
            Shading::Lit
        },
        straight: o.straight,
        samples_per_pixel: o.spp,
        ..RenderOptions::default()
    };
    let gpu = open_gpu()?;
    let scene = &input.scene;
    if o.bench {
        let (w, h) = match (width, height) {
            (None, None) => BENCH_SIZE,
            _ => frame_size(scene, width, height),
        };
        let view = View::of_scene(scene, &options, w, h);
        let buffers = pack(scene, &scene.medium, &view).map_err(|e| e.in_file(&o.input))?;
        let tracer = Tracer::new(&gpu, &buffers);
        tracer.render(&gpu);
        let frames = 3;
        let start = Instant::now();
        for _ in 0..frames {
            // Whole frames, as the window traces them: a cancellation point
            // between frames only.
            crate::interrupt::check()?;
            tracer.render(&gpu);
        }
        crate::interrupt::check()?;
        let ms = start.elapsed().as_secs_f64() * 1000.0 / frames as f64;
        println!(
            "{}: {w}×{h} px on {}: {ms:.1} ms/frame ({:.1} frames/s, mean of {frames})",
            scene.name,
            gpu.describe(),
            1000.0 / ms
        );
    }
    if let Some(out) = &o.output {
        let (w, h) = frame_size(scene, width, height);
        let view = View::of_scene(scene, &options, w, h);
        let pixels = render_frame(&gpu, scene, &scene.medium, &view)?;
        let tone = match options.shading {
            Shading::Lit => ToneMap::Filmic {
                exposure: scene.exposure,
            },
            Shading::Albedo => ToneMap::Clamp,
        };
        let png = encode_png(w, h, &pixels, tone)?;
        // The last cancellation point: once writing starts, it finishes.
        crate::interrupt::check()?;
        write_atomic(out, &png)?;
    }
    Ok(())
}

/// `mirage preview PHOTO-PROBLEM.json`: the photo mode's window
/// ([`super::photo_window`]).
fn photo_preview(o: &PreviewOptions) -> Result<()> {
    let refused = [
        (o.headless, "--headless"),
        (o.output.is_some(), "--output"),
        (o.bench, "--bench"),
        (o.albedo, "--albedo"),
        (o.straight, "--straight"),
        (o.spp.is_some(), "--spp"),
        (o.no_glare, "--no-glare"),
    ];
    if let Some((_, flag)) = refused.iter().find(|(on, _)| *on) {
        return Err(Error::usage(
            *flag,
            "not for a photo problem: its window shows the photo and its marks (`mirage overlay P.json -o O.png` draws them without a window)",
        ));
    }
    let mut inputs: Vec<&Path> = vec![o.input.as_path()];
    inputs.extend(o.script.as_deref());
    check_outputs(
        Output::optional(
            "--screenshot",
            o.screenshot.as_ref(),
            OutputKind::Png("a screenshot"),
        ),
        &inputs,
    )?;
    let session = super::photo::PhotoSession::open(&o.input)?;
    let image = session
        .problem
        .photo
        .as_ref()
        .map(|s| s.image.clone())
        .unwrap_or_default();
    let photo = crate::photo::picture::Picture::read(&image)
        .and_then(|p| p.decode())
        .map_err(|e| Error::input(&o.input, "photo.image", e.to_string()))?;
    let script = match &o.script {
        Some(path) => {
            let text = crate::io::json::read_input(path)?;
            let steps = super::script::parse(&text, path)?;
            Some(super::script::Player::new(steps, path))
        }
        None => None,
    };
    super::photo_window::run(
        session,
        photo,
        super::photo_window::PhotoWindowSettings {
            size: (o.width, o.height),
            frames: o.frames,
            screenshot: o.screenshot.clone(),
            script,
        },
    )
}
