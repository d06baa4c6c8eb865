//! The GPU previewer: the CPU renderer's scene, medium, curved rays, sky and
//! shading in a WGSL compute shader, shown live in a window with controls to
//! edit the air, or rendered headless to a PNG.
//!
//! Data flow: a scene or problem file ([`Input`]) → [`pack::pack`] (f32
//! buffers laid out as in [`layout`], the objects compiled by [`program`], the
//! medium in δ form) → [`gpu::Tracer`] (one compute
//! dispatch per frame into a linear HDR image) → either read back and written
//! like `mirage render`'s PNG (headless), or tone-mapped on the GPU and drawn
//! under the egui panels ([`window`]).
//!
//! Not ported: the CPU renderer's path table for stratified air (the GPU
//! integrates every ray; the table is an approximation of exactly that) and its
//! distance grid (the GPU evaluates every object whose bounding sphere is
//! nearer than the best distance so far).

pub mod camera;
pub mod display;
pub mod editing;
pub mod gpu;
pub mod layout;
pub mod pack;
pub mod program;
pub mod shader;
pub mod window;

use crate::error::{Error, FieldError, Result};
use crate::io::json::{parse_json, read_input};
use crate::io::{check_not_input, write_atomic};
use crate::medium::{LogisticMedium, Medium};
use crate::plot::ImageFormat;
use crate::problem::Problem;
use crate::render::output::{ToneMap, encode_png};
use crate::render::{RenderOptions, Shading};
use crate::scene::Scene;
use crate::scene::description::{CameraSpec, SceneFile};
use gpu::{Gpu, Tracer};
use pack::{View, pack};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Default size of a headless frame when the input does not fix one (a problem
/// file) and for `--bench`.
pub const BENCH_SIZE: (u32, u32) = (1280, 720);

/// What the previewer shows: a scene, and for a problem file its pairs.
#[derive(Clone, Debug)]
pub struct Input {
    /// The file given.
    pub path: PathBuf,
    /// The scene (for a problem: its medium over a plain ground, seen from
    /// the first pair's origin).
    pub scene: Scene,
    /// The problem, when the input is one.
    pub problem: Option<Problem>,
}

/// The logistic parameters of `medium`, or the error that the previewer (whose
/// shader and editor evaluate the logistic model) cannot show this kind.
pub fn logistic<'a>(medium: &'a Medium, file: &Path) -> Result<&'a LogisticMedium> {
    medium.as_logistic().ok_or_else(|| {
        FieldError::new(
            "medium",
            format!(
                "the previewer shows the logistic model only; this medium is of kind `{}` (use `mirage render`)",
                medium.kind_name()
            ),
        )
        .in_file(file)
    })
}

/// Reads a scene or a problem file (a scene has a `camera`, a problem `pairs`);
/// its medium must be of the logistic kind ([`logistic`]).
pub fn load_input(path: &Path) -> Result<Input> {
    let input = load_any_input(path)?;
    logistic(&input.scene.medium, path)?;
    Ok(input)
}

fn load_any_input(path: &Path) -> Result<Input> {
    let text = read_input(path)?;
    let value: serde_json::Value = parse_json(&text, path, "scene or problem")?;
    let is_scene = value.get("camera").is_some();
    let is_problem = value.get("pairs").is_some();
    match (is_scene, is_problem) {
        (true, _) => Ok(Input {
            path: path.to_path_buf(),
            scene: Scene::parse(&text, path)?,
            problem: None,
        }),
        (false, true) => {
            let problem = Problem::parse(&text, path)?;
            let scene = problem_scene(&problem, path)?;
            Ok(Input {
                path: path.to_path_buf(),
                scene,
                problem: Some(problem),
            })
        }
        (false, false) => Err(Error::input(
            path,
            "-",
            "neither a scene (no `camera`) nor a problem (no `pairs`)",
        )),
    }
}

/// The scene a problem is previewed in: its medium over a grey ground, seen
/// from the first pair's origin toward its `through` point with a 2° field of
/// view, and the sky behind.
pub fn problem_scene(problem: &Problem, path: &Path) -> Result<Scene> {
    let (position, look_at) = match problem.pairs.first() {
        Some(p) => (p.origin, p.through),
        None => ([0.0, 2.0, 0.0], [0.0, 2.0, 1000.0]),
    };
    let file = SceneFile {
        name: Some(problem.name.clone()),
        description: Some(problem.description.clone()),
        camera: CameraSpec {
            position,
            look_at,
            up: [0.0, 1.0, 0.0],
            vertical_fov: 2.0,
            width: BENCH_SIZE.0,
            height: BENCH_SIZE.1,
        },
        medium: Some(problem.medium.clone()),
        medium_from: None,
        ground: Some(crate::scene::description::GroundSpec {
            albedo: None,
            checker: Some(crate::scene::description::CheckerSpec {
                size: 10.0,
                colors: [[0.10, 0.10, 0.10], [0.16, 0.15, 0.13]],
            }),
        }),
        objects: Vec::new(),
        sun: Default::default(),
        sky: None,
        samples_per_pixel: None,
        trace: Default::default(),
        exposure: None,
        glare: None,
    };
    Scene::from_file(file, path)
}

/// A GPU, or the error every command reports without one.
pub fn open_gpu() -> Result<Gpu> {
    Gpu::new().map_err(|e| match e {
        Error::Gpu { stage, message } => Error::Gpu {
            stage,
            message: format!(
                "{message} (without a GPU, install Mesa's software Vulkan: apt-get install mesa-vulkan-drivers libvulkan1)"
            ),
        },
        other => other,
    })
}

/// Renders one frame of `scene` seen through `medium` on the GPU and reads it
/// back: linear RGB, row-major, top row first.
pub fn render_frame(
    gpu: &Gpu,
    scene: &Scene,
    medium: &Medium,
    view: &View,
) -> Result<Vec<[f32; 3]>> {
    let buffers = pack(scene, medium, view).map_err(|e| e.in_file(&scene.source))?;
    let tracer = Tracer::new(gpu, &buffers);
    let mut pixels = tracer.render_to_cpu(gpu)?;
    apply_glare(scene, view, &mut pixels);
    Ok(pixels)
}

/// Adds the scene's veiling glare to a lit frame of `view` read back from the
/// GPU (`pixels`: linear RGB, row-major), as `mirage render` does: a
/// post-process on the CPU, for headless frames and for the window once its
/// view has settled. `None` when the scene has no glare or the frame is in
/// albedo.
pub fn apply_glare(
    scene: &Scene,
    view: &View,
    pixels: &mut [[f32; 3]],
) -> Option<crate::render::glare::GlareStats> {
    let g = scene.glare.as_ref()?;
    if view.shading != Shading::Lit {
        return None;
    }
    let (w, h) = (view.camera.width, view.camera.height);
    let settings = g.in_pixels(view.camera.pixel_angle());
    Some(crate::render::glare::apply(pixels, w, h, &settings))
}

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
}

/// `--frames`: at least 1.
fn frame_count(s: &str) -> std::result::Result<u64, String> {
    match s
        .parse::<u64>()
        .map_err(|_| format!("not a whole number: `{s}`"))?
    {
        0 => Err("must be at least 1".into()),
        n => Ok(n),
    }
}

fn check_png(path: &Path, inputs: &[&Path]) -> Result<()> {
    match ImageFormat::from_path(path)? {
        ImageFormat::Png => {}
        ImageFormat::Svg => {
            return Err(Error::input(
                path,
                "-",
                "previews are raster images: use a .png output",
            ));
        }
    }
    check_not_input(path, inputs)
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
    let (width, height) = (o.width, o.height);
    let mut input = load_input(&o.input)?;
    if o.no_glare {
        input.scene.glare = None;
    }
    let mut inputs: Vec<&Path> = vec![o.input.as_path()];
    inputs.extend(input.scene.inputs.iter().map(PathBuf::as_path));
    if let Some(out) = &o.output {
        check_png(out, &inputs)?;
    }
    if let Some(shot) = &o.screenshot {
        check_png(shot, &inputs)?;
    }
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
        return window::run(
            input,
            width,
            height,
            o.albedo,
            o.straight,
            o.frames,
            o.screenshot.clone(),
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
            tracer.render(&gpu);
        }
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
        write_atomic(out, &png)?;
    }
    Ok(())
}
