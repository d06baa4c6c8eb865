//! The buffers' layouts: the `#[repr(C)]` structs uploaded to the GPU, as the
//! tracing shader declares them (`trace.wgsl`), and the codes their fields
//! carry.
//!
//! Every struct is built of 16-byte `vec4` blocks (or four 4-byte scalars), so
//! that the Rust layout, WGSL's uniform layout and its storage layout agree
//! without padding; [`super::shader`]'s tests check them against the layouts
//! naga computes for the shader.
//!
//! Everything is f32: the medium stays in δ form (see [`super::pack`](mod@super::pack)).

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

/// Stand-in for infinity in the buffers (shader compilers may assume that no
/// value is infinite); the shader's `BIG`.
pub const BIG: f32 = 1e30;

/// [`Params::flags`]`[0]`: lit shading.
pub const SHADING_LIT: u32 = 0;
/// [`Params::flags`]`[0]`: albedo shading.
pub const SHADING_ALBEDO: u32 = 1;
/// [`Params::flags`]`[2]`: no ground.
pub const GROUND_NONE: u32 = 0;
/// [`Params::flags`]`[2]`: a ground of one colour ([`Params::ground0`]).
pub const GROUND_UNIFORM: u32 = 1;
/// [`Params::flags`]`[2]`: a checkered ground ([`Params::ground0`],
/// [`Params::ground1`]).
pub const GROUND_CHECKER: u32 = 2;
/// [`Params::medium`]`[0]`: the logistic model (the uniforms `background`,
/// `inversion` and the hot spots' coefficients).
pub const MEDIUM_LOGISTIC: u32 = 0;
/// [`Params::medium`]`[0]`: real air (the `air_table` buffer; see
/// `real_air`).
pub const MEDIUM_AIR: u32 = 1;
/// [`GpuRay::count`]`[0]`: the pixel's next sample starts from the camera (a
/// cleared buffer says this).
pub const PHASE_START: u32 = 0;
/// [`GpuRay::count`]`[0]`: a sample's ray is on its way.
pub const PHASE_TRACING: u32 = 1;
/// [`GpuRay::count`]`[0]`: every sample is done and the pixel written.
pub const PHASE_DONE: u32 = 2;

/// One instruction of an SDF program (96 bytes, vec4-aligned).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Node {
    /// `[opcode, 0, 0, 0]` (an [`Op`](super::program::Op) code).
    pub kind: [u32; 4],
    /// Rows of the world → local affine map: `local_i = row_i.xyz · p + row_i.w`.
    pub rows: [[f32; 4]; 3],
    /// First parameter block (see [`Op`](super::program::Op)).
    pub p0: [f32; 4],
    /// Second parameter block; `w` is the distance multiplier (primitives).
    pub p1: [f32; 4],
}

/// One object: its program's range, albedo and bounding sphere.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuObject {
    /// `[first node, node count, 0, 0]`.
    pub range: [u32; 4],
    /// Albedo RGB; `w`: bounding-sphere radius (negative: unbounded).
    pub albedo: [f32; 4],
    /// Bounding-sphere centre.
    pub center: [f32; 4],
}

/// One hot spot: compiled coefficients and its zone.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuHotSpot {
    /// `[amp, 1/a, x, z]`.
    pub a: [f32; 4],
    /// `[radius, edge, zone radius, zone top]`.
    pub b: [f32; 4],
    /// `[decay, 0, 0, 0]` (|a| of a layer decaying upward, else 0).
    pub c: [f32; 4],
}

/// The uniform block (`Params` in the shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Params {
    /// Eye position; `w`: tan(vertical FOV / 2).
    pub origin: [f32; 4],
    /// View direction; `w`: aspect ratio.
    pub forward: [f32; 4],
    /// Right; `w`: the pixel angle (radians).
    pub right: [f32; 4],
    /// Up; `w`: the largest arc length of a ray.
    pub up: [f32; 4],
    /// `[width, height, hot spots, objects]`.
    pub size: [u32; 4],
    /// `[shading (`SHADING_*`), straight, ground kind (`GROUND_*`), profile
    /// length]`.
    pub flags: [u32; 4],
    /// Background `[amp, 1/a, present, 0]`.
    pub background: [f32; 4],
    /// Inversion `[amp, 1/a, height, present]`.
    pub inversion: [f32; 4],
    /// `[n_max, step inside zones, step outside, 0]`.
    pub air: [f32; 4],
    /// Profile `[dy, margin, δ at the top (M over the sphere), the earth's
    /// radius (0: the flat ground)]`.
    pub profile: [f32; 4],
    /// `[absolute hit tolerance, relative, 0, 0]`.
    pub tolerance: [f32; 4],
    /// Ground colour 0 (or the uniform one); `w`: checker size.
    pub ground0: [f32; 4],
    /// Ground colour 1.
    pub ground1: [f32; 4],
    /// Objects' box, low corner; `w`: 1 if there are objects.
    pub box_min: [f32; 4],
    /// Objects' box, high corner.
    pub box_max: [f32; 4],
    /// Unit vector toward the sun.
    pub sun_dir: [f32; 4],
    /// Sunlight reaching the ground (irradiance × colour × transmittance).
    pub sun_irradiance: [f32; 4],
    /// The sky's ambient light.
    pub ambient: [f32; 4],
    /// The sun's disc direction; `w`: angular radius (negative: none).
    pub disc_dir: [f32; 4],
    /// The disc's radiance.
    pub disc_radiance: [f32; 4],
    /// `[sky table width, height, samples per pixel, max queries]`.
    pub counts: [u32; 4],
    /// Distance grid's box, low corner (its y is the floor); `w`: 1 if there
    /// is a grid.
    pub grid_min: [f32; 4],
    /// Distance grid's box, high corner; `w`: the cheap-query threshold.
    pub grid_max: [f32; 4],
    /// Cells along x, y, z.
    pub grid_dims: [u32; 4],
    /// Cell size.
    pub grid_cell: [f32; 4],
    /// Stars of the physical sky: `[angular radius, flux scale × the sun's
    /// irradiance, fade scale (0: no fade), drawn (1) or not (0)]`.
    pub stars: [f32; 4],
    /// `[medium kind (`MEDIUM_*`), real air's height intervals, its formula
    /// grid's cells along T, along P]` (see `real_air::AirTables`).
    pub medium: [u32; 4],
    /// Real air: `[lowest node, highest node, Gladstone–Dale K (0: the
    /// grid), T floor (K)]`.
    pub air_range: [f32; 4],
    /// Real air's formula grid: `[T₀, ΔT, P₀, ΔP]`.
    pub air_grid: [f32; 4],
    /// `[march iterations of one sample at most, iterations per pass, 0, 0]`
    /// (see [`super::pack`](mod@super::pack)).
    pub march: [u32; 4],
    /// Accumulation ([`super::accumulate`]): `[samples already summed in the
    /// accumulation buffer (the first sample this frame traces), keep the
    /// sums there (1) or not (0), 0, 0]`; all 0 for a frame of its own.
    pub accumulate: [u32; 4],
}

/// A pixel's ray between the passes of a frame (`Ray` in the shader; the
/// shader alone reads and writes them, the host only clears them to
/// [`PHASE_START`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuRay {
    /// The current RK4 step's start: position; `w`: arc length.
    pub x: [f32; 4],
    /// Its ray vector v = n·t; `w`: δ.
    pub v: [f32; 4],
    /// Its dv/dτ; `w`: the step's τ length (0: no step yet).
    pub a: [f32; 4],
    /// `[θ on the step, arc per unit θ, distance budget, free flight]`.
    pub at: [f32; 4],
    /// The radiance of the pixel's finished samples.
    pub sum: [f32; 4],
    /// `[phase (`PHASE_*`), sample, distance queries, march iterations]`.
    pub count: [u32; 4],
}

/// One cell of the distance grid ([`crate::render::accel::Grid`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCell {
    /// No surface within this distance of the cell's centre.
    pub empty: f32,
    /// Lower bound of the distance to every object off the near list.
    pub far: f32,
    /// Near list start in [`SceneBuffers::near`](super::pack::SceneBuffers::near).
    pub start: u32,
    /// Near list length.
    pub len: u32,
}

/// `v` and `w` as one vec4.
pub(super) fn v4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

/// The colour `c` and `w` as one vec4.
pub(super) fn rgb4(c: [f64; 3], w: f64) -> [f32; 4] {
    [c[0] as f32, c[1] as f32, c[2] as f32, w as f32]
}
