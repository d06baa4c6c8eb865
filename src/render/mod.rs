//! The CPU renderer: scenes of SDF objects seen through refracting air along
//! curved rays.
//!
//! Data flow: a [`Scene`] file → [`Renderer::new`] (camera, [`air::Air`]
//! analysis, distance acceleration, and for stratified air a
//! [`paths::PathTable`]) → per sample a ray ([`march`]) ending on an object, the
//! ground or the sky → shading → a linear HDR image ([`Rendered`]) → PNG
//! (tone-mapped sRGB) and EXR (linear), written atomically.
//!
//! - **Rays** are integrated with RK4 in the τ form of the ray equation and
//!   sphere-traced with steps bounded by the scene's distance, so thin objects
//!   are never stepped over ([`march`]); with `straight`, δ ≡ 0.
//! - **Shading** ([`Shading::Lit`]): Lambert under the sun with a shadow ray,
//!   plus ambient light from the sky. Shadow rays are straight: the sun is
//!   degrees above the horizon while refraction bends rays by fractions of a
//!   milliradian over an object's shadow, far below a pixel's worth of shadow
//!   edge at any sensible sun elevation; they are all parallel, so the
//!   objects seen along the sun ([`shadow::SunColumns`]) tell most of them
//!   at once that nothing is in the way. [`Shading::Albedo`] shows the albedo
//!   of what a ray hits (the sky's radiance for a miss), for validation.
//! - **Speed**: rayon over 16 × 16 tiles with an indicatif progress bar; each
//!   pixel depends on nothing but its own samples, so the image is bitwise the
//!   same for any number of threads. Each tile is a cancellation point
//!   ([`crate::interrupt`]).

pub mod accel;
pub mod air;
pub mod camera;
pub mod clear;
pub mod dispersion;
pub mod glare;
pub mod march;
pub mod output;
pub mod packs;
pub mod paths;
pub mod shadow;
pub mod sky;

use crate::error::Result;
use crate::io::{Output, OutputKind, check_outputs, write_atomic};
use crate::scene::Scene;
use crate::trace::batch::PACK;
use accel::{Aabb, Counters, Grid, SceneDistance};
use air::Air;
use camera::{Camera, sample_offset};
use glam::DVec3;
use march::{HitTolerance, MarchStats, Marcher, Outcome, TracerKind};
use packs::Packer;
use paths::{PathTable, TableSettings, TableStats};
use rayon::prelude::*;
use shadow::SunColumns;
use sky::{Sky, SkyModel};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Side of the square tiles the image is split into for the threads.
pub const TILE: u32 = 16;

/// What a pixel shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Shading {
    /// Sunlight with shadows and sky light.
    #[default]
    Lit,
    /// The albedo of what the ray hits; the sky's radiance for a miss.
    Albedo,
}

/// How to render, beyond the scene file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Lit or albedo.
    pub shading: Shading,
    /// δ ≡ 0: straight rays, for comparison.
    pub straight: bool,
    /// The sphere tracer.
    pub tracer: TracerKind,
    /// For stratified air, reuse a table of paths across the image.
    pub path_reuse: bool,
    /// Overrides the scene's samples per pixel.
    pub samples_per_pixel: Option<u32>,
    /// Overrides the image width (the height follows the aspect ratio unless
    /// given too).
    pub width: Option<u32>,
    /// Overrides the image height.
    pub height: Option<u32>,
    /// Draw a progress bar on stderr.
    pub progress: bool,
    /// The hit tolerance as a fraction of a pixel's footprint. Objects grow by
    /// that much; the default 0.001 keeps edges where exact surfaces put them
    /// (at 0.05, edge pixels of a 16-spp render differed from Mitsuba's in
    /// 0.3–3.8 % of pixels) for 10–80 % more distance queries.
    pub hit_fraction: f64,
    /// Add the scene's veiling glare (if it has one) to lit renders.
    pub glare: bool,
    /// Through hot-spot air, integrate neighbouring camera rays together in
    /// SIMD lanes ([`packs`]) instead of each on its own.
    pub packs: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            shading: Shading::Lit,
            straight: false,
            tracer: TracerKind::default(),
            path_reuse: true,
            samples_per_pixel: None,
            width: None,
            height: None,
            progress: false,
            hit_fraction: 0.001,
            glare: true,
            packs: true,
        }
    }
}

/// Work and time of a render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Camera samples traced.
    pub samples: u64,
    /// Of which along interpolated table paths.
    pub table_samples: u64,
    /// Camera-ray work.
    pub march: MarchStats,
    /// Shadow-ray distance work.
    pub shadow: Counters,
    /// The path table, if one was built.
    pub table: Option<TableStats>,
    /// Seconds spent building the table.
    pub table_seconds: f64,
    /// Seconds spent building the distance grid.
    pub grid_seconds: f64,
    /// Seconds of setup: the grid and the table, built side by side.
    pub setup_seconds: f64,
    /// Seconds spent tracing and shading.
    pub trace_seconds: f64,
    /// The veiling glare's sources and cost, if applied.
    pub glare: Option<glare::GlareStats>,
}

impl RenderStats {
    /// Adds `other`'s work counters (samples, march and shadow work) to these.
    fn add_counts(&mut self, other: &RenderStats) {
        self.samples += other.samples;
        self.table_samples += other.table_samples;
        self.march += other.march;
        self.shadow += other.shadow;
    }
}

/// A rendered image: linear HDR RGB, row-major, top row first.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Width (pixels).
    pub width: u32,
    /// Height (pixels).
    pub height: u32,
    /// Linear RGB per pixel.
    pub pixels: Vec<[f32; 3]>,
    /// Work and time.
    pub stats: RenderStats,
}

impl Rendered {
    /// The pixel at column `x`, row `y`.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// A scene prepared for rendering.
pub struct Renderer {
    scene: Scene,
    options: RenderOptions,
    camera: Camera,
    air: Air,
    distance: SceneDistance,
    sky: SkyModel,
    table: Option<PathTable>,
    samples: u32,
    setup: RenderStats,
    objects_box: Option<Aabb>,
    /// The objects seen along the sun, for shadow rays (lit renders with
    /// the sun up).
    sun_columns: Option<SunColumns>,
    /// For a dispersive scene, one renderer per colour channel, each with
    /// the air at its wavelength ([`dispersion`]).
    channels: Option<Box<[Renderer; 3]>>,
}

impl Renderer {
    /// Prepares `scene` for rendering: the camera, the air's analysis, the
    /// distance grid (quadric tracer) and, for stratified air, the path table.
    pub fn new(scene: &Scene, options: &RenderOptions) -> Renderer {
        let (w0, h0) = (scene.camera.width, scene.camera.height);
        let (width, height) = match (options.width, options.height) {
            (Some(w), Some(h)) => (w, h),
            (Some(w), None) => (
                w,
                ((w as f64 * h0 as f64 / w0 as f64).round() as u32).max(1),
            ),
            (None, Some(h)) => (
                ((h as f64 * w0 as f64 / h0 as f64).round() as u32).max(1),
                h,
            ),
            (None, None) => (w0, h0),
        };
        Renderer::with_camera(
            scene,
            options,
            Camera::with_size(&scene.camera, width, height),
        )
    }

    /// Prepares `scene` for rendering through `camera` instead of the
    /// scene's own (the previewer renders a photo problem's air through the
    /// photo's camera, [`crate::photo::camera::Camera`], in the problem's
    /// frame). The camera's origin should be the scene camera's position:
    /// the sky is set up for that height.
    pub fn with_camera(scene: &Scene, options: &RenderOptions, camera: Camera) -> Renderer {
        let objects_box = Aabb::of_objects(&scene.objects);
        let air = Air::new(
            &scene.medium,
            options.straight,
            scene.step,
            scene.ground.is_some(),
            objects_box,
            scene.earth,
        );
        let mut setup = RenderStats::default();
        let channels = Renderer::channel_renderers(scene, options);
        // A dispersive render traces through its channels' renderers: this
        // one's own table would go unused. The table's paths are those of a
        // flat ground (heights along y): over the sphere every ray is
        // integrated.
        let wants_table = options.path_reuse
            && channels.is_none()
            && scene.earth.is_flat()
            && air.is_stratified()
            && !air.is_straight();
        // The distance grid and the path table do not depend on each other:
        // built side by side (each is partly serial inside).
        let start = Instant::now();
        let ((distance, grid_seconds), table) = rayon::join(
            || {
                let start = Instant::now();
                let d = Renderer::scene_distance(scene, options);
                (d, start.elapsed().as_secs_f64())
            },
            || {
                wants_table.then(|| {
                    let start = Instant::now();
                    let t = Renderer::build_table(&camera, &air, scene);
                    (t, start.elapsed().as_secs_f64())
                })
            },
        );
        setup.setup_seconds = start.elapsed().as_secs_f64();
        setup.grid_seconds = grid_seconds;
        if let Some((t, seconds)) = &table {
            setup.table_seconds = *seconds;
            setup.table = Some(t.stats());
        }
        let samples = options
            .samples_per_pixel
            .unwrap_or(scene.samples_per_pixel)
            .max(1);
        Renderer {
            scene: scene.clone(),
            options: *options,
            camera,
            air,
            distance,
            sky: SkyModel::from_spec(
                &scene.sky,
                &scene.sun,
                scene.earth.height(crate::math::V3::new(
                    scene.camera.position.x,
                    scene.camera.position.y,
                    scene.camera.position.z,
                )),
                camera.pixel_angle(),
            ),
            table: table.map(|(t, _)| t),
            samples,
            setup,
            objects_box,
            sun_columns: if options.shading == Shading::Lit && scene.sun.direction.y > 0.0 {
                SunColumns::new(&scene.objects, scene.sun.direction)
            } else {
                None
            },
            channels,
        }
    }

    /// The objects' distances as the tracer queries them.
    fn scene_distance(scene: &Scene, options: &RenderOptions) -> SceneDistance {
        match options.tracer {
            TracerKind::Plain | TracerKind::Enhanced => {
                SceneDistance::Direct(scene.objects.clone())
            }
            TracerKind::Quadric => {
                // Over the sphere the ground sinks below y = 0 away from the
                // origin: no floor to cut the grid at.
                let floor = if scene.ground.is_some() && scene.earth.is_flat() {
                    0.0
                } else {
                    f64::NEG_INFINITY
                };
                match Grid::build(&scene.objects, floor) {
                    Some(g) => SceneDistance::Grid(Box::new(g)),
                    None => SceneDistance::Direct(scene.objects.clone()),
                }
            }
        }
    }

    fn build_table(camera: &Camera, air: &Air, scene: &Scene) -> PathTable {
        let (lo, hi) = Renderer::elevation_range(camera);
        let px = camera.pixel_angle();
        let settings = TableSettings {
            theta_range: (lo - 2.0 * px, hi + 2.0 * px),
            initial_spacing: 4.0 * px,
            min_spacing: px / 512.0,
            tolerance: 0.02 * px,
            step: scene.step,
            max_distance: scene.max_distance,
            ground: scene.ground.is_some(),
        };
        PathTable::build(air, camera.origin, &scene.objects, &settings)
    }

    /// The lowest and highest elevation (radians) of the image's rays: the
    /// border, where the extremes of a pinhole image lie, and a coarse
    /// interior grid for safety (a ray outside the table is simply integrated).
    fn elevation_range(camera: &Camera) -> (f64, f64) {
        let (w, h) = (camera.width as f64, camera.height as f64);
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let mut see = |px: f64, py: f64| {
            let d = camera.direction(px, py);
            let e = d.y.atan2(d.x.hypot(d.z));
            lo = lo.min(e);
            hi = hi.max(e);
        };
        let n = 256;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            see(t * w, 0.0);
            see(t * w, h);
            see(0.0, t * h);
            see(w, t * h);
            for j in 0..=16 {
                see(t * w, j as f64 / 16.0 * h);
            }
        }
        (lo, hi)
    }

    /// The camera (at the rendered size).
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The air as analysed.
    pub fn air(&self) -> &Air {
        &self.air
    }

    /// The path table, if the air is stratified and path reuse is on.
    pub fn table(&self) -> Option<&PathTable> {
        self.table.as_ref()
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.samples
    }

    /// The marcher for this scene and these options.
    pub fn marcher(&self) -> Marcher<'_> {
        Marcher {
            air: &self.air,
            distance: &self.distance,
            omega: match self.options.tracer {
                TracerKind::Plain => 1.0,
                TracerKind::Enhanced | TracerKind::Quadric => march::OMEGA,
            },
            tolerance: HitTolerance {
                absolute: 1e-4,
                relative: self.options.hit_fraction * self.camera.pixel_angle(),
            },
            max_distance: self.scene.max_distance,
            ground: self.scene.ground.is_some(),
        }
    }

    /// Traces the camera ray along the unit direction `dir`: along the path
    /// table when there is one that covers it, else by integration.
    pub fn trace(&self, dir: DVec3, stats: &mut MarchStats) -> Outcome {
        if let Some(t) = &self.table
            && let Some(ray) = t.ray(dir)
        {
            return self.marcher().march_table(t, &ray, stats);
        }
        self.marcher().march(self.camera.origin, dir, stats)
    }

    /// Traces the camera ray through continuous pixel coordinates (px, py).
    pub fn trace_pixel(&self, px: f64, py: f64, stats: &mut MarchStats) -> Outcome {
        self.trace(self.camera.direction(px, py), stats)
    }

    /// The linear RGB a ray's outcome shows.
    pub fn shade(&self, outcome: &Outcome, shadow: &mut Counters) -> [f64; 3] {
        match *outcome {
            Outcome::Sky { direction } => self.sky.radiance(direction),
            Outcome::Object {
                index,
                point,
                distance,
                ..
            } => {
                let obj = &self.distance.objects()[index];
                let albedo = obj.albedo;
                if self.options.shading == Shading::Albedo {
                    return albedo;
                }
                let mut n = obj.shape.normal(point);
                if n == DVec3::ZERO {
                    n = DVec3::Y;
                }
                let eps = self
                    .marcher()
                    .tolerance
                    .absolute
                    .max(self.marcher().tolerance.relative * distance);
                self.light(point + n * (2.0 * eps + 1e-4), n, albedo, shadow)
            }
            Outcome::Ground { point, .. } => {
                let albedo = self
                    .scene
                    .ground
                    .map_or([0.0; 3], |g| g.at(point.x, point.z));
                if self.options.shading == Shading::Albedo {
                    return albedo;
                }
                let up = self
                    .scene
                    .earth
                    .up(crate::math::V3::new(point.x, point.y, point.z));
                let up = DVec3::new(up.x, up.y, up.z);
                self.light(point + up * 1e-3, up, albedo, shadow)
            }
        }
    }

    /// Lambert under the sun (if it is up and not blocked) plus sky light.
    fn light(&self, p: DVec3, n: DVec3, albedo: [f64; 3], shadow: &mut Counters) -> [f64; 3] {
        let sun = &self.scene.sun;
        let cos = n.dot(sun.direction);
        let direct = if cos > 0.0 && sun.direction.y > 0.0 && self.sunlit(p, sun.direction, shadow)
        {
            cos / std::f64::consts::PI
        } else {
            0.0
        };
        let ambient = self.sky.ambient();
        let through = self.sky.sun_transmittance();
        let hemi = 0.5 + 0.5 * n.y;
        [0, 1, 2].map(|c| albedo[c] * (sun.irradiance[c] * through[c] * direct + ambient[c] * hemi))
    }

    /// Whether the straight ray from `p` toward the sun meets no object.
    fn sunlit(&self, p: DVec3, d: DVec3, counters: &mut Counters) -> bool {
        if let Some(columns) = &self.sun_columns
            && d == self.scene.sun.direction
        {
            return columns.sunlit(self.distance.objects(), p, counters);
        }
        let Some(bx) = self.objects_box else {
            return true;
        };
        let Some((t0, t1)) = bx.ray_interval(p, d) else {
            return true;
        };
        let mut t = t0;
        let mut near = accel::NearCache::default();
        for _ in 0..512 {
            // A straight ray (curvature 0): the clear box or empty sphere
            // around the point may reach further than the free radius.
            let (q, free) = self.distance.probe(p + d * t, d, 0.0, counters, &mut near);
            if q.radius < 1e-4 + 1e-7 * t {
                return false;
            }
            t += free.max(q.radius);
            if t > t1 {
                return true;
            }
        }
        true
    }

    /// Renders the image. Once [`crate::interrupt::requested`], the tiles
    /// not yet started are left black: a caller that polls the flag checks
    /// it after this returns ([`render_command`] does).
    pub fn render(&self) -> Rendered {
        if let Some(channels) = &self.channels {
            let mut image = Renderer::render_channels(channels);
            self.apply_glare(&mut image);
            return image;
        }
        let (w, h) = (self.camera.width, self.camera.height);
        let tiles_x = w.div_ceil(TILE);
        let tiles_y = h.div_ceil(TILE);
        let n_tiles = (tiles_x * tiles_y) as u64;
        let bar = if self.options.progress {
            let b = indicatif::ProgressBar::with_draw_target(
                Some(n_tiles),
                indicatif::ProgressDrawTarget::stderr(),
            );
            if let Ok(style) = indicatif::ProgressStyle::with_template(
                "{msg} [{bar:40}] {percent:>3}% {elapsed_precise} (eta {eta})",
            ) {
                b.set_style(style.progress_chars("=> "));
            }
            b.set_message(format!("rendering {w}×{h}"));
            b
        } else {
            indicatif::ProgressBar::hidden()
        };
        let start = Instant::now();
        // Bands of one tile row are written straight into the image, each
        // band's tiles rendered in parallel: the image is held once (12 bytes
        // a pixel) plus the bands in flight, not twice as when every tile was
        // collected first, and the threads still share out single tiles.
        let mut pixels = vec![[0.0f32; 3]; (w * h) as usize];
        let band_stats: Vec<RenderStats> = pixels
            .par_chunks_mut((TILE * w) as usize)
            .enumerate()
            .map(|(ty, band)| {
                let tiles: Vec<(Vec<[f32; 3]>, RenderStats)> = (0..tiles_x)
                    .into_par_iter()
                    .map(|tx| {
                        // A cancellation point per tile: once Ctrl-C is pressed
                        // the workers skip the tiles left (an empty tile stays
                        // black), and the caller reports the interruption.
                        if crate::interrupt::requested() {
                            return (Vec::new(), RenderStats::default());
                        }
                        let out = self.render_tile(tx, ty as u32);
                        bar.inc(1);
                        out
                    })
                    .collect();
                let mut stats = RenderStats::default();
                for (tx, (tile, s)) in tiles.into_iter().enumerate() {
                    let x0 = tx as u32 * TILE;
                    let tw = TILE.min(w - x0);
                    for (k, px) in tile.into_iter().enumerate() {
                        let (dx, dy) = (k as u32 % tw, k as u32 / tw);
                        band[(dy * w + x0 + dx) as usize] = px;
                    }
                    stats.add_counts(&s);
                }
                stats
            })
            .collect();
        bar.finish_and_clear();
        let mut stats = self.setup;
        for s in &band_stats {
            stats.add_counts(s);
        }
        stats.trace_seconds = start.elapsed().as_secs_f64();
        let mut image = Rendered {
            width: w,
            height: h,
            pixels,
            stats,
        };
        self.apply_glare(&mut image);
        image
    }

    /// Adds the scene's veiling glare, if it has one and the options want it
    /// (not to a render Ctrl-C cut short: it is not kept).
    fn apply_glare(&self, image: &mut Rendered) {
        if let Some(g) = &self.scene.glare
            && !crate::interrupt::requested()
            && self.options.glare
            && self.options.shading == Shading::Lit
        {
            let settings = g.in_pixels(self.camera.pixel_angle());
            image.stats.glare = Some(glare::apply(
                &mut image.pixels,
                image.width,
                image.height,
                &settings,
            ));
        }
    }

    fn render_tile(&self, tx: u32, ty: u32) -> (Vec<[f32; 3]>, RenderStats) {
        let (w, h) = (self.camera.width, self.camera.height);
        let (x0, y0) = (tx * TILE, ty * TILE);
        let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
        let mut stats = RenderStats::default();
        let marcher = self.marcher();
        let origin = self.camera.origin;
        let mut packer = if self.options.packs {
            self.air.pack_stepper().map(Packer::new)
        } else {
            None
        };
        // Samples waiting for a full pack: (pixel in the tile, direction).
        let mut queue: Vec<(usize, DVec3)> = Vec::with_capacity(PACK);
        let mut sums = vec![[0.0f64; 3]; ((x1 - x0) * (y1 - y0)) as usize];
        let mut k = 0;
        for y in y0..y1 {
            for x in x0..x1 {
                for i in 0..self.samples {
                    let (u, v) = sample_offset(i);
                    let dir = self.camera.direction(x as f64 + u, y as f64 + v);
                    let on_table = self.table.as_ref().and_then(|t| t.ray(dir).map(|r| (t, r)));
                    let outcome = match (&on_table, &mut packer) {
                        (Some((t, ray)), _) => {
                            stats.table_samples += 1;
                            marcher.march_table(t, ray, &mut stats.march)
                        }
                        (None, Some(p)) => {
                            queue.push((k, dir));
                            if queue.len() == PACK {
                                self.trace_pack(&marcher, p, &mut queue, &mut sums, &mut stats);
                            }
                            continue;
                        }
                        (None, None) => marcher.march(origin, dir, &mut stats.march),
                    };
                    self.add_sample(&outcome, &mut sums[k], &mut stats);
                }
                k += 1;
            }
        }
        if let Some(p) = &mut packer {
            self.trace_pack(&marcher, p, &mut queue, &mut sums, &mut stats);
        }
        let inv = 1.0 / self.samples as f64;
        let out = sums.iter().map(|s| s.map(|s| (s * inv) as f32)).collect();
        (out, stats)
    }

    /// Traces and shades the queued samples as one pack: integrated ahead
    /// together ([`packs`]), then each sphere-traced along its steps.
    fn trace_pack(
        &self,
        marcher: &Marcher,
        packer: &mut Packer,
        queue: &mut Vec<(usize, DVec3)>,
        sums: &mut [[f64; 3]],
        stats: &mut RenderStats,
    ) {
        if queue.is_empty() {
            return;
        }
        let launch = marcher.launch_at(self.camera.origin, &mut stats.march);
        let mut dirs = [DVec3::ZERO; PACK];
        for (d, &(_, dir)) in dirs.iter_mut().zip(queue.iter()) {
            *d = dir;
        }
        let ahead = packer.integrate(marcher, &launch, &dirs[..queue.len()], &mut stats.march);
        for (&(k, dir), steps) in queue.iter().zip(ahead) {
            let outcome = marcher.march_ahead(launch.along(dir), steps, &mut stats.march);
            self.add_sample(&outcome, &mut sums[k], stats);
        }
        queue.clear();
    }

    /// Shades a sample's outcome into its pixel's sum.
    fn add_sample(&self, outcome: &Outcome, sum: &mut [f64; 3], stats: &mut RenderStats) {
        let c = self.shade(outcome, &mut stats.shadow);
        for (s, c) in sum.iter_mut().zip(c) {
            *s += c;
        }
        stats.samples += 1;
    }
}

/// Renders `scene` with `options` (convenience for [`Renderer::new`] and
/// [`Renderer::render`]).
pub fn render(scene: &Scene, options: &RenderOptions) -> Rendered {
    Renderer::new(scene, options).render()
}

/// Render a scene seen through its air along curved rays.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct CommandOptions {
    /// Scene file (JSON).
    pub scene: PathBuf,
    /// Output image (.png, tone-mapped sRGB).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write the linear HDR image here (.exr).
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// Show the albedo of what each ray hits (the sky's colour for a miss).
    #[arg(long)]
    pub albedo: bool,
    /// Straight rays (δ ≡ 0), for comparison.
    #[arg(long)]
    pub straight: bool,
    /// Samples per pixel (overrides the scene).
    #[arg(long, value_parser = samples_per_pixel)]
    pub spp: Option<u32>,
    /// Image width in pixels (overrides the scene).
    #[arg(long, value_parser = image_side)]
    pub width: Option<u32>,
    /// Image height in pixels (overrides the scene).
    #[arg(long, value_parser = image_side)]
    pub height: Option<u32>,
    /// Sphere tracer.
    #[arg(long, value_enum, default_value_t)]
    pub tracer: TracerKind,
    /// Integrate every ray, even where a table of paths could be reused.
    #[arg(long)]
    pub no_path_reuse: bool,
    /// Integrate every camera ray through hot-spot air on its own, not in
    /// SIMD packs of neighbouring rays (for comparison).
    #[arg(long)]
    pub no_packs: bool,
    /// Leave out the scene's veiling glare.
    #[arg(long)]
    pub no_glare: bool,
    /// No progress bar and no summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Hit tolerance as a fraction of a pixel (default 0.001; larger: faster, objects grow).
    #[arg(long, value_parser = hit_fraction)]
    pub hit_fraction: Option<f64>,
}

/// The tracers by their command-line names ([`TracerKind::name`]).
impl clap::ValueEnum for TracerKind {
    fn value_variants<'a>() -> &'a [Self] {
        &[TracerKind::Plain, TracerKind::Enhanced, TracerKind::Quadric]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

/// `--width`/`--height` of a render or preview: 1 to
/// [`MAX_IMAGE_SIDE`](crate::scene::description::MAX_IMAGE_SIDE) pixels.
pub(crate) fn image_side(s: &str) -> std::result::Result<u32, crate::error::ValueError> {
    let max = crate::scene::description::MAX_IMAGE_SIDE;
    match s
        .parse::<u32>()
        .map_err(|_| crate::error::ValueError::NotAWholeNumber {
            value: s.to_string(),
        })? {
        v if v == 0 || v > max => Err(crate::error::ValueError::OutOfRange {
            rule: format!("must be between 1 and {max} pixels, got {v}"),
        }),
        v => Ok(v),
    }
}

/// `--spp` of a render or preview: 1 to
/// [`MAX_SAMPLES_PER_PIXEL`](crate::scene::description::MAX_SAMPLES_PER_PIXEL).
pub(crate) fn samples_per_pixel(s: &str) -> std::result::Result<u32, crate::error::ValueError> {
    let max = crate::scene::description::MAX_SAMPLES_PER_PIXEL;
    match s
        .parse::<u32>()
        .map_err(|_| crate::error::ValueError::NotAWholeNumber {
            value: s.to_string(),
        })? {
        n if n == 0 || n > max => Err(crate::error::ValueError::OutOfRange {
            rule: format!("must be between 1 and {max}, got {n}"),
        }),
        n => Ok(n),
    }
}

/// `--hit-fraction`: in (0, 1].
fn hit_fraction(s: &str) -> std::result::Result<f64, crate::error::ValueError> {
    match s
        .parse::<f64>()
        .map_err(|_| crate::error::ValueError::NotANumber {
            value: s.to_string(),
        })? {
        f if f.is_finite() && f > 0.0 && f <= 1.0 => Ok(f),
        f => Err(crate::error::ValueError::OutOfRange {
            rule: format!("must be in (0, 1] (fraction of a pixel), got {f}"),
        }),
    }
}

/// How `mirage render` tone-maps its PNG: shaded images by the scene's
/// `exposure` and the filmic curve, albedo images clamped.
pub fn tone_map(shading: Shading, exposure: f64) -> output::ToneMap {
    match shading {
        Shading::Lit => output::ToneMap::Filmic { exposure },
        Shading::Albedo => output::ToneMap::Clamp,
    }
}

/// `mirage render`: loads the scene, renders it and writes the PNG (and the
/// EXR), atomically; prints a one-paragraph summary unless quiet.
pub fn render_command(o: &CommandOptions) -> Result<Rendered> {
    let scene = Scene::load(&o.scene)?;
    let mut inputs: Vec<&Path> = vec![o.scene.as_path()];
    inputs.extend(scene.inputs.iter().map(PathBuf::as_path));
    check_outputs(
        [
            Some(Output::new("-o", &o.output, OutputKind::Png("a render"))),
            Output::optional("--exr", o.exr.as_ref(), OutputKind::Exr("the HDR render")),
        ]
        .into_iter()
        .flatten(),
        &inputs,
    )?;
    let mut options = RenderOptions {
        shading: if o.albedo {
            Shading::Albedo
        } else {
            Shading::Lit
        },
        straight: o.straight,
        tracer: o.tracer,
        path_reuse: !o.no_path_reuse,
        packs: !o.no_packs,
        samples_per_pixel: o.spp,
        width: o.width,
        height: o.height,
        progress: !o.quiet,
        glare: !o.no_glare,
        ..RenderOptions::default()
    };
    if let Some(f) = o.hit_fraction {
        options.hit_fraction = f;
    }
    let renderer = Renderer::new(&scene, &options);
    crate::interrupt::check()?;
    let image = renderer.render();
    // The last cancellation point: once writing starts, it finishes.
    crate::interrupt::check()?;
    let tone = tone_map(options.shading, scene.exposure);
    let png = output::encode_png(image.width, image.height, &image.pixels, tone)?;
    let exr = match &o.exr {
        Some(_) => Some(output::encode_exr(
            image.width,
            image.height,
            &image.pixels,
        )?),
        None => None,
    };
    write_atomic(&o.output, &png)?;
    if let (Some(path), Some(bytes)) = (&o.exr, exr) {
        write_atomic(path, &bytes)?;
    }
    if !o.quiet {
        println!("{}", summary(&renderer, &image));
    }
    Ok(image)
}

/// A short report of a render: size, time, work per pixel, the table.
pub fn summary(renderer: &Renderer, image: &Rendered) -> String {
    let s = &image.stats;
    let pixels = (image.width as f64) * (image.height as f64);
    let per = |n: u64| n as f64 / pixels;
    let mut out = format!(
        "{}: {}×{} px, {} spp, {} rays{}, tracer {}: {:.3} s (+ {:.3} s setup)\n\
         per pixel: {:.1} distance queries, {:.1} SDF evaluations, {:.1} RK4 steps{}, {:.1} shadow SDF evaluations",
        renderer.scene.name,
        image.width,
        image.height,
        renderer.samples,
        if renderer.air.is_straight() {
            "straight"
        } else {
            "curved"
        },
        if renderer.air.is_stratified() {
            " (stratified air)"
        } else {
            " (air with hot spots)"
        },
        renderer.options.tracer.name(),
        s.trace_seconds,
        s.setup_seconds,
        per(s.march.counters.queries),
        per(s.march.counters.object_evaluations),
        per(s.march.rk4_steps),
        if s.march.pack_steps > 0 {
            format!(" ({:.1} in packs)", per(s.march.pack_steps))
        } else {
            String::new()
        },
        per(s.shadow.object_evaluations),
    );
    if let Some(g) = &s.glare {
        out.push_str(&format!(
            "\nglare: {} source pixels, {}×{} orders ({} coefficients), {:.3} s",
            g.sources, g.orders.0, g.orders.1, g.coefficients, g.seconds
        ));
    }
    if let Some(t) = &s.table {
        out.push_str(&format!(
            "\npath table: {} paths, {} RK4 steps, built in {:.3} s; interpolation error ≤ {:.4} px (estimated); {} of {} samples on the table",
            t.paths,
            t.rk4_steps,
            s.table_seconds,
            t.error_estimate / renderer.camera.pixel_angle(),
            s.table_samples,
            s.samples
        ));
    }
    out
}
