//! Packing a scene for the GPU: the camera, the compiled medium, the air's
//! analysis (steps, hot-spot zones, the stratified profile for Snell
//! decisions), the objects as a flat SDF program ([`super::program`]), the
//! sun, the sky table and the physical sky's star cells, into the buffers of
//! [`super::layout`].
//!
//! Over the round earth the profile is that of the modified refractivity M
//! ([`Air::profile_tables`]) and the shader gets the radius (`profile.w`).
//!
//! Real air packs as tables of its uniform profile and of its formula
//! ([`super::real_air`]), its hot spots as `[δT, 1/H, x, z, radius, edge]`.
//!
//! Everything is f32, and the medium stays in δ form: the amplitudes are the
//! compiled `C·|k_s|·n/S` (≈ 1e-5), which f32 keeps to 7 digits, whereas
//! `1 + δ` would keep three.
//!
//! # Passes
//!
//! The shader traces a frame in passes of at most [`PASS_ITERATIONS`]
//! iterations of its march a pixel (see `trace.wgsl`): Mesa's software
//! Vulkan (llvmpipe) silently breaks out of every loop once an invocation
//! group has run 65535 loop iterations in all, inner loops included, and one
//! march iteration of real air runs about 85 of them (the profile's binary
//! searches, the hot-spot and formula loops, the ground-crossing searches), so
//! a frame traced in one pass gave up every ray longer than about 800 RK4
//! steps and drew it as sky. Each iteration of the march ends an RK4 step or
//! spends one distance query's budget, so a sample takes at most
//! [`march_iterations`] of them, and a frame at most [`passes`] passes; the
//! later ones find most pixels done and return at once.

use super::accumulate::Samples;
use super::layout::{
    BIG, GROUND_CHECKER, GROUND_NONE, GROUND_UNIFORM, GpuCell, GpuHotSpot, GpuObject,
    MEDIUM_LOGISTIC, Node, Params, SHADING_ALBEDO, SHADING_LIT, rgb4, v4,
};
use super::program::compile_objects;
use super::real_air::pack_air;
use crate::error::FieldError;
use crate::medium::{Field, LogisticMedium, Medium};
use crate::render::accel::{Aabb, Grid};
use crate::render::air::Air;
use crate::render::camera::Camera;
use crate::render::sky::{STAR_CELLS, STAR_FADE, star_cell, star_radius};
use crate::render::sky::{Sky, SkyModel};
use crate::render::{RenderOptions, Shading};
use crate::scene::Scene;
use crate::scene::description::GroundAlbedo;
use crate::trace::Earth;
use glam::DVec3;

/// Sky table: columns over azimuth (wrapping).
pub const SKY_WIDTH: u32 = 256;
/// Sky table: rows over the signed elevation coordinate v ∈ [−1, 1], where
/// elevation = sign(v)·v²·90° (dense near the horizon; row (H − 1)/2 is the
/// horizon itself).
pub const SKY_HEIGHT: u32 = 1025;
/// Largest number of distance queries for one ray (as the CPU's
/// [`crate::render::march::MAX_QUERIES`]).
pub const MAX_QUERIES: u32 = crate::render::march::MAX_QUERIES;
/// Scenes with more objects than this are queried through the distance grid.
pub const GRID_MIN_OBJECTS: usize = 8;
/// March iterations a pass advances a pixel's ray by at most: 128 iterations
/// of about 85 loop iterations each, plus one shading (a shadow ray of up to
/// 512 distance queries), stay below llvmpipe's 65535 for the bundled scenes
/// (see the module documentation).
pub const PASS_ITERATIONS: u32 = 128;

/// Everything the shader reads, ready to upload.
#[derive(Clone, Debug)]
pub struct SceneBuffers {
    /// The uniform block.
    pub params: Params,
    /// Hot spots (at least one element: a zero-sized buffer cannot be bound).
    pub hotspots: Vec<GpuHotSpot>,
    /// Objects (at least one element).
    pub objects: Vec<GpuObject>,
    /// The SDF programs of all objects (at least one element).
    pub nodes: Vec<Node>,
    /// Per profile height `[δ, min below, min above, 0]` (at least one).
    pub profile: Vec<[f32; 4]>,
    /// The sky's smooth radiance, `SKY_WIDTH × SKY_HEIGHT` RGBA, row-major.
    pub sky: Vec<[f32; 4]>,
    /// The distance grid's cells (at least one element).
    pub cells: Vec<GpuCell>,
    /// The grid's near lists (at least one element).
    pub near: Vec<u32>,
    /// Real air's tables ([`super::real_air::AirTables::table`]; at least
    /// one element).
    pub air_table: Vec<[f32; 4]>,
    /// The physical sky's star cells (`STAR_CELLS² × 6`, face-major):
    /// `[place u, place v, brightness unit⁶, tint]`, tint 0 where a cell has
    /// no star (at least one element).
    pub stars: Vec<[f32; 4]>,
}

/// What the GPU frame shows, beyond the scene: the view and the switches the
/// previewer changes every frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The camera (origin, axes, field of view, image size).
    pub camera: Camera,
    /// Lit or albedo.
    pub shading: Shading,
    /// δ ≡ 0.
    pub straight: bool,
    /// Samples per pixel.
    pub samples_per_pixel: u32,
    /// The hit tolerance as a fraction of a pixel's footprint.
    pub hit_fraction: f64,
}

impl View {
    /// The view a CPU render of `scene` with `options` would have.
    pub fn of_scene(scene: &Scene, options: &RenderOptions, width: u32, height: u32) -> View {
        View {
            camera: Camera::with_size(&scene.camera, width, height),
            shading: options.shading,
            straight: options.straight,
            samples_per_pixel: options
                .samples_per_pixel
                .unwrap_or(scene.samples_per_pixel)
                .max(1),
            hit_fraction: options.hit_fraction,
        }
    }
}

fn finite_or_big(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else if x > 0.0 {
        BIG as f64
    } else {
        -BIG as f64
    }
}

/// The sky's smooth radiance over azimuth × the signed elevation coordinate
/// (see [`SKY_HEIGHT`]).
pub fn bake_sky(sky: &SkyModel) -> Vec<[f32; 4]> {
    let mut out = Vec::with_capacity((SKY_WIDTH * SKY_HEIGHT) as usize);
    for row in 0..SKY_HEIGHT {
        let v = -1.0 + 2.0 * row as f64 / (SKY_HEIGHT - 1) as f64;
        let elevation = v.signum() * v * v * std::f64::consts::FRAC_PI_2;
        let (se, ce) = elevation.sin_cos();
        for col in 0..SKY_WIDTH {
            let azimuth = std::f64::consts::TAU * col as f64 / SKY_WIDTH as f64;
            let (sa, ca) = azimuth.sin_cos();
            let dir = DVec3::new(ce * sa, se, ce * ca);
            out.push(rgb4(sky.diffuse(dir), 1.0));
        }
    }
    out
}

/// The star of every cube-map cell of the physical sky, as
/// [`SceneBuffers::stars`] holds them.
pub fn star_cells() -> Vec<[f32; 4]> {
    let n = STAR_CELLS as u64;
    let mut out = Vec::with_capacity(6 * STAR_CELLS * STAR_CELLS);
    for face in 0..6 {
        for iu in 0..n {
            for iv in 0..n {
                out.push(match star_cell(face, iu, iv) {
                    Some([u, v, b, tint]) => [u as f32, v as f32, b.powi(6) as f32, tint as f32],
                    None => [0.0; 4],
                });
            }
        }
    }
    out
}

/// Packs `scene` (with `medium` instead of the scene's own, so that the
/// editor can change the air without rebuilding the scene) for `view`.
pub fn pack(scene: &Scene, medium: &Medium, view: &View) -> Result<SceneBuffers, FieldError> {
    super::input::previewable(medium)?;
    // As the CPU renderer: seen from the scene camera's altitude.
    let c = scene.camera.position;
    let sky = SkyModel::from_spec(
        &scene.sky,
        &scene.sun,
        scene.earth.height(crate::math::V3::new(c.x, c.y, c.z)),
        view.camera.pixel_angle(),
    );
    let objects_box = Aabb::of_objects(&scene.objects);
    let air = Air::new(
        medium,
        view.straight,
        scene.step,
        scene.ground.is_some(),
        objects_box,
        scene.earth,
    );
    let (records, nodes) = compile_objects(&scene.objects)?;
    let mut buffers = SceneBuffers {
        params: Params::default(),
        hotspots: Vec::new(),
        objects: records,
        nodes,
        profile: Vec::new(),
        sky: bake_sky(&sky),
        cells: Vec::new(),
        near: Vec::new(),
        stars: vec![[0.0; 4]],
        air_table: Vec::new(),
    };
    // The CPU renderer's grid of unbounding spheres and near lists, cut at
    // the ground as there (not over the sphere, which sinks below y = 0).
    let floor = if scene.ground.is_some() && scene.earth.is_flat() {
        0.0
    } else {
        f64::NEG_INFINITY
    };
    // (With few objects, evaluating them all is as cheap and takes longer
    // steps.)
    let grid = if scene.objects.len() > GRID_MIN_OBJECTS {
        Grid::build(&scene.objects, floor)
    } else {
        None
    };
    if let Some(grid) = grid {
        let raw = grid.raw();
        let p = &mut buffers.params;
        p.grid_min = v4(raw.bounds.min, 1.0);
        p.grid_max = v4(raw.bounds.max, raw.cheap_min);
        p.grid_dims = [
            raw.dims[0] as u32,
            raw.dims[1] as u32,
            raw.dims[2] as u32,
            0,
        ];
        p.grid_cell = v4(raw.cell, 0.0);
        buffers.cells = raw
            .cells
            .iter()
            .map(|&(empty, far, start, len)| GpuCell {
                empty: finite_or_big(empty) as f32,
                far: finite_or_big(far) as f32,
                start,
                len,
            })
            .collect();
        buffers.near = raw.near.to_vec();
    }
    if buffers.cells.is_empty() {
        buffers.cells.push(GpuCell::default());
    }
    if buffers.near.is_empty() {
        buffers.near.push(0);
    }
    // (Before set_air, which bounds the march by it.)
    buffers.params.up[3] = scene.max_distance as f32;
    buffers.set_air(medium, &air);
    buffers.set_view(view);
    let p = &mut buffers.params;
    p.size[3] = scene.objects.len() as u32;
    p.flags[2] = match scene.ground {
        None => GROUND_NONE,
        Some(GroundAlbedo::Uniform(c)) => {
            p.ground0 = rgb4(c, 0.0);
            GROUND_UNIFORM
        }
        Some(GroundAlbedo::Checker { size, colors }) => {
            p.ground0 = rgb4(colors[0], size);
            p.ground1 = rgb4(colors[1], 0.0);
            GROUND_CHECKER
        }
    };
    match objects_box {
        Some(b) => {
            p.box_min = v4(b.min.map(finite_or_big), 1.0);
            p.box_max = v4(b.max.map(finite_or_big), 0.0);
        }
        None => p.box_min[3] = 0.0,
    }
    let t = sky.sun_transmittance();
    let sun = &scene.sun;
    p.sun_dir = v4(sun.direction, 0.0);
    p.sun_irradiance = rgb4([0, 1, 2].map(|c| sun.irradiance[c] * t[c]), 0.0);
    p.ambient = rgb4(sky.ambient(), 0.0);
    match sky.sun_disc() {
        Some(d) => {
            p.disc_dir = v4(d.direction, d.angular_radius);
            p.disc_radiance = rgb4(d.radiance, 0.0);
        }
        None => p.disc_dir = [0.0, 1.0, 0.0, -1.0],
    }
    if let SkyModel::Physical(physical) = &sky {
        let (drawn, flux, e) = physical.star_light();
        if drawn {
            p.stars[1] = (flux * e) as f32;
            p.stars[2] = (STAR_FADE * e) as f32;
            p.stars[3] = 1.0;
            buffers.stars = star_cells();
        }
    }
    p.counts = [SKY_WIDTH, SKY_HEIGHT, view.samples_per_pixel, MAX_QUERIES];
    if buffers.objects.is_empty() {
        buffers.objects.push(GpuObject::default());
    }
    if buffers.nodes.is_empty() {
        buffers.nodes.push(Node::default());
    }
    Ok(buffers)
}

/// The most iterations one sample's march can take: one per RK4 step, of
/// which a ray takes at most `max_distance / (step / n_ratio)` (a step of
/// `step` metres, as the shader takes them, covers at least `step / n_ratio`
/// of arc, `n_ratio` bounding n_max / n_min), one per distance query (at most
/// [`MAX_QUERIES`]), and the switch to free flight; with a margin for f32's
/// rounding of the arc length.
pub fn march_iterations(step: f64, n_ratio: f64, max_distance: f64) -> u32 {
    let steps = (1.01 * max_distance * n_ratio / step).ceil() + 2.0;
    (steps + MAX_QUERIES as f64 + 8.0).min(u32::MAX as f64 / 2.0) as u32
}

/// The passes that trace a frame of `params` (see the module documentation):
/// a sample ends in the pass after its last full one at the latest, and the
/// next starts in the pass after that.
pub fn passes(params: &Params) -> u32 {
    let [per_sample, per_pass, _, _] = params.march;
    let samples = params.counts[2].max(1);
    samples.saturating_mul(per_sample.div_ceil(per_pass.max(1)) + 1)
}

impl SceneBuffers {
    /// Sets the camera, shading and sampling of the frame.
    pub fn set_view(&mut self, view: &View) {
        let c = &view.camera;
        let p = &mut self.params;
        p.origin = v4(c.origin, c.tan_half);
        p.forward = v4(c.forward, c.width as f64 / c.height as f64);
        p.right = v4(c.right, c.pixel_angle());
        let max_distance = p.up[3];
        p.up = v4(c.up, 0.0);
        p.up[3] = max_distance;
        p.size[0] = c.width;
        p.size[1] = c.height;
        p.flags[0] = match view.shading {
            Shading::Lit => SHADING_LIT,
            Shading::Albedo => SHADING_ALBEDO,
        };
        p.tolerance = [1e-4, (view.hit_fraction * c.pixel_angle()) as f32, 0.0, 0.0];
        p.counts[2] = view.samples_per_pixel.max(1);
        p.accumulate = [0; 4];
        p.stars[0] = star_radius(c.pixel_angle()) as f32;
    }

    /// Sets the samples the next frame traces, for the window's accumulation
    /// ([`super::accumulate`]): `samples.first` onwards, added to the sums
    /// of the frames before when `first > 0`; with `keep`, the sums are kept
    /// for the next frame to add to.
    pub fn set_samples(&mut self, samples: Samples, keep: bool) {
        let p = &mut self.params;
        p.counts[2] = samples.count.max(1);
        p.accumulate = [samples.first, u32::from(keep), 0, 0];
    }

    /// Sets the medium and what follows from it (the air's analysis, the
    /// bound of the march at the largest distance already in
    /// `params.up[3]`): `air` is `medium` analysed ([`Air::new`]).
    pub fn set_air(&mut self, medium: &Medium, air: &Air) {
        let p = &mut self.params;
        // Real air: its tables, and its hot spots' coefficients in kelvins.
        let real = match (air.field(), medium.as_air()) {
            (Field::Air(field), Some(m)) => Some((m, pack_air(m, field))),
            _ => None,
        };
        // Anything else packs as the logistic model (δ ≡ 0 when straight).
        let raw = match air.field().as_logistic() {
            Some(f) => f.coefficients(),
            None => LogisticMedium::vacuum().field().coefficients(),
        };
        p.medium = [MEDIUM_LOGISTIC, 0, 0, 0];
        p.air_range = [0.0; 4];
        p.air_grid = [0.0; 4];
        self.air_table = vec![[0.0; 4]];
        p.flags[1] = air.is_straight() as u32;
        p.background = match raw.background {
            Some([amp, inv]) => [amp as f32, inv as f32, 1.0, 0.0],
            None => [0.0; 4],
        };
        p.inversion = match raw.inversion {
            Some([amp, inv, h]) => [amp as f32, inv as f32, h as f32, 1.0],
            None => [0.0; 4],
        };
        let (inside, outside) = air.steps();
        // δ is positive in real air; the logistic terms lower it at most by
        // their negative amplitudes.
        let delta_min = if real.is_some() {
            0.0
        } else {
            raw.background.map_or(0.0, |[amp, _]| amp.min(0.0))
                + raw.inversion.map_or(0.0, |[amp, _, _]| amp.min(0.0))
                + raw.hotspots.iter().map(|h| h[0].min(0.0)).sum::<f64>()
        };
        let step = inside.min(outside).min(p.up[3] as f64);
        p.march = [
            march_iterations(step, air.n_max() / (1.0 + delta_min), p.up[3] as f64),
            PASS_ITERATIONS,
            0,
            0,
        ];
        p.air = [
            air.n_max() as f32,
            finite_or_big(inside) as f32,
            finite_or_big(outside) as f32,
            0.0,
        ];
        let coefficients: Vec<[f64; 6]> = match &real {
            Some((m, tables)) => {
                tables.set_params(p);
                self.air_table = tables.table.clone();
                m.hotspots
                    .iter()
                    .map(|h| [h.delta, h.scale_height.recip(), h.x, h.z, h.radius, h.edge])
                    .collect()
            }
            None => raw.hotspots.to_vec(),
        };
        self.hotspots = coefficients
            .iter()
            .zip(air.zones())
            .map(|(h, z)| GpuHotSpot {
                a: [h[0] as f32, h[1] as f32, h[2] as f32, h[3] as f32],
                b: [
                    h[4] as f32,
                    h[5] as f32,
                    z.radius as f32,
                    finite_or_big(z.top) as f32,
                ],
                c: [z.decay as f32, 0.0, 0.0, 0.0],
            })
            .collect();
        p.size[2] = self.hotspots.len() as u32;
        if self.hotspots.is_empty() {
            self.hotspots.push(GpuHotSpot::default());
        }
        let (dy, margin, delta, below, above) = air.profile_tables();
        self.profile = (0..delta.len())
            .map(|i| [delta[i] as f32, below[i] as f32, above[i] as f32, 0.0])
            .collect();
        p.flags[3] = self.profile.len() as u32;
        p.profile = [
            dy as f32,
            margin as f32,
            delta.last().copied().unwrap_or(0.0) as f32,
            match air.earth() {
                Earth::Flat => 0.0,
                Earth::Round { radius } => radius as f32,
            },
        ];
        if self.profile.is_empty() {
            self.profile.push([0.0; 4]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_has_the_passes_of_its_longest_rays() {
        // 30 km at a 5 m step: 6000 RK4 steps (a percent more for f32's arc
        // length) and the 2000 distance queries.
        let n = march_iterations(5.0, 1.0003, 30_000.0);
        assert!((6002 + MAX_QUERIES..6100 + MAX_QUERIES).contains(&n), "{n}");
        let mut p = Params {
            march: [n, PASS_ITERATIONS, 0, 0],
            ..Default::default()
        };
        p.counts[2] = 2;
        // Each sample's iterations in full passes, and the pass it ends in.
        assert_eq!(passes(&p), 2 * (n.div_ceil(PASS_ITERATIONS) + 1));
        // Straight rays: one step to the largest distance.
        assert_eq!(
            march_iterations(30_000.0, 1.0, 30_000.0),
            4 + MAX_QUERIES + 8
        );
    }

    #[test]
    fn the_sky_table_has_the_horizon_row() {
        let sky = SkyModel::Gradient(crate::render::sky::GradientSky {
            zenith: crate::render::sky::DEFAULT_ZENITH,
            horizon: crate::render::sky::DEFAULT_HORIZON,
        });
        let t = bake_sky(&sky);
        let mid = (SKY_HEIGHT / 2 * SKY_WIDTH) as usize;
        let h = crate::render::sky::DEFAULT_HORIZON;
        assert_eq!(t[mid], rgb4(h, 1.0));
        let top = t[t.len() - 1];
        let z = crate::render::sky::DEFAULT_ZENITH;
        for c in 0..3 {
            assert!((top[c] as f64 - z[c]).abs() < 1e-6);
        }
    }
}
