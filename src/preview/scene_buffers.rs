//! Packing a scene for the GPU: the camera, the compiled medium, the air's
//! analysis (steps, hot-spot zones, the stratified profile for Snell
//! decisions), the objects as a flat SDF program, the sun, the sky table and
//! the physical sky's star cells.
//!
//! Everything is f32, and the medium stays in δ form: the amplitudes are the
//! compiled `C·|k_s|·n/S` (≈ 1e-5), which f32 keeps to 7 digits, whereas
//! `1 + δ` would keep three.
//!
//! # The SDF program
//!
//! Each object's tree becomes a post-order list of [`Node`]s evaluated with a
//! small value stack. Transforms are folded into the primitives at packing
//! time: every primitive carries the affine map world → its local frame and the
//! product of the scale factors above it (`d = factor · child(p / factor)`).
//! n-ary unions, intersections and smooth unions become left folds of binary
//! operations, so the stack never holds more than the tree's depth + 1 values.

use crate::medium::LogisticMedium;
use crate::render::accel::{Aabb, Grid};
use crate::render::air::Air;
use crate::render::camera::Camera;
use crate::render::sky::{STAR_CELLS, STAR_FADE, star_cell, star_radius};
use crate::render::sky::{Sky, SkyModel};
use crate::render::{RenderOptions, Shading};
use crate::scene::Scene;
use crate::scene::description::GroundAlbedo;
use crate::scene::sdf::{SceneObject, Sdf};
use bytemuck::{Pod, Zeroable};
use glam::{DMat3, DVec3};

/// Deepest value stack an SDF program may need (the shader's array size).
pub const STACK_DEPTH: usize = 16;
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
/// Stand-in for infinity in the buffers (shader compilers may assume that no
/// value is infinite).
const BIG: f32 = 1e30;

/// SDF program opcodes (the shader's `K_*` constants).
pub mod op {
    /// Sphere: `p0 = (centre, radius)`.
    pub const SPHERE: u32 = 1;
    /// Box: `p0 = centre`, `p1 = half extents`.
    pub const BOX: u32 = 2;
    /// Rounded box: `p0 = (centre, radius)`, `p1 = half extents`.
    pub const ROUNDED_BOX: u32 = 3;
    /// Plane: `p0 = (unit normal, offset)`.
    pub const PLANE: u32 = 4;
    /// Torus: `p0 = centre`, `p1 = (major, minor)`.
    pub const TORUS: u32 = 5;
    /// Cylinder: `p0 = centre`, `p1 = (radius, half height)`.
    pub const CYLINDER: u32 = 6;
    /// Capsule: `p0 = (a, radius)`, `p1 = b`.
    pub const CAPSULE: u32 = 7;
    /// Pops b, a; pushes min(a, b).
    pub const MIN: u32 = 10;
    /// Pops b, a; pushes max(a, b).
    pub const MAX: u32 = 11;
    /// Pops b, a; pushes max(a, −b).
    pub const DIFF: u32 = 12;
    /// Pops b, a; pushes the smooth minimum with width `p0.x`.
    pub const SMIN: u32 = 13;
}

/// One instruction of an SDF program (96 bytes, vec4-aligned).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Node {
    /// `[opcode, 0, 0, 0]`.
    pub kind: [u32; 4],
    /// Rows of the world → local affine map: `local_i = row_i.xyz · p + row_i.w`.
    pub rows: [[f32; 4]; 3],
    /// First parameter block (see [`op`]).
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
    /// `[shading (0 lit, 1 albedo), straight, ground kind (0 none, 1 uniform,
    /// 2 checker), profile length]`.
    pub flags: [u32; 4],
    /// Background `[amp, 1/a, present, 0]`.
    pub background: [f32; 4],
    /// Inversion `[amp, 1/a, height, present]`.
    pub inversion: [f32; 4],
    /// `[n_max, step inside zones, step outside, 0]`.
    pub air: [f32; 4],
    /// Profile `[dy, margin, δ at the top, 0]`.
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
}

/// One cell of the distance grid ([`crate::render::accel::Grid`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCell {
    /// No surface within this distance of the cell's centre.
    pub empty: f32,
    /// Lower bound of the distance to every object off the near list.
    pub far: f32,
    /// Near list start in [`SceneBuffers::near`].
    pub start: u32,
    /// Near list length.
    pub len: u32,
}

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

fn v4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

fn rgb4(c: [f64; 3], w: f64) -> [f32; 4] {
    [c[0] as f32, c[1] as f32, c[2] as f32, w as f32]
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

/// The world → local affine map of a primitive and its distance multiplier.
#[derive(Clone, Copy, Debug)]
struct Frame {
    a: DMat3,
    b: DVec3,
    mult: f64,
}

impl Frame {
    const IDENTITY: Frame = Frame {
        a: DMat3::IDENTITY,
        b: DVec3::ZERO,
        mult: 1.0,
    };

    fn node(&self, kind: u32, p0: [f32; 4], p1: [f32; 4]) -> Node {
        let r = self.a.transpose();
        let mut p1 = p1;
        p1[3] = self.mult as f32;
        Node {
            kind: [kind, 0, 0, 0],
            rows: [
                v4(r.x_axis, self.b.x),
                v4(r.y_axis, self.b.y),
                v4(r.z_axis, self.b.z),
            ],
            p0,
            p1,
        }
    }
}

fn binary(kind: u32, k: f64) -> Node {
    Node {
        kind: [kind, 0, 0, 0],
        p0: [k as f32, 0.0, 0.0, 0.0],
        ..Node::default()
    }
}

/// Appends the program of `sdf` in `frame`; returns the stack depth it needs.
fn compile(sdf: &Sdf, frame: Frame, out: &mut Vec<Node>) -> usize {
    let fold = |children: &[Sdf], kind: u32, k: f64, out: &mut Vec<Node>| -> usize {
        let mut depth = 0;
        for (i, c) in children.iter().enumerate() {
            let d = compile(c, frame, out);
            if i == 0 {
                depth = d;
            } else {
                depth = depth.max(1 + d);
                out.push(binary(kind, k * frame.mult));
            }
        }
        depth
    };
    match sdf {
        Sdf::Sphere { center, radius } => {
            out.push(frame.node(op::SPHERE, v4(*center, *radius), [0.0; 4]));
            1
        }
        Sdf::Box {
            center,
            half_extents,
        } => {
            out.push(frame.node(op::BOX, v4(*center, 0.0), v4(*half_extents, 0.0)));
            1
        }
        Sdf::RoundedBox {
            center,
            half_extents,
            radius,
        } => {
            out.push(frame.node(
                op::ROUNDED_BOX,
                v4(*center, *radius),
                v4(*half_extents, 0.0),
            ));
            1
        }
        Sdf::Plane(p) => {
            out.push(frame.node(op::PLANE, v4(p.unit_normal(), p.offset()), [0.0; 4]));
            1
        }
        Sdf::Torus {
            center,
            major_radius,
            minor_radius,
        } => {
            out.push(frame.node(
                op::TORUS,
                v4(*center, 0.0),
                [*major_radius as f32, *minor_radius as f32, 0.0, 0.0],
            ));
            1
        }
        Sdf::Cylinder {
            center,
            radius,
            half_height,
        } => {
            out.push(frame.node(
                op::CYLINDER,
                v4(*center, 0.0),
                [*radius as f32, *half_height as f32, 0.0, 0.0],
            ));
            1
        }
        Sdf::Capsule { a, b, radius } => {
            out.push(frame.node(op::CAPSULE, v4(*a, *radius), v4(*b, 0.0)));
            1
        }
        Sdf::Union { children } => fold(children, op::MIN, 0.0, out),
        Sdf::Intersection { children } => fold(children, op::MAX, 0.0, out),
        Sdf::SmoothUnion { children, k } => fold(children, op::SMIN, *k, out),
        Sdf::Difference { base, subtract } => {
            let a = compile(base, frame, out);
            let b = compile(subtract, frame, out);
            out.push(binary(op::DIFF, 0.0));
            a.max(1 + b)
        }
        Sdf::Translate { offset, child } => compile(
            child,
            Frame {
                b: frame.b - *offset,
                ..frame
            },
            out,
        ),
        Sdf::Rotate(r) => {
            let m = r.world_to_local();
            compile(
                r.child(),
                Frame {
                    a: m * frame.a,
                    b: m * frame.b,
                    mult: frame.mult,
                },
                out,
            )
        }
        Sdf::Scale(s) => {
            let f = s.factor();
            compile(
                s.child(),
                Frame {
                    a: frame.a * (1.0 / f),
                    b: frame.b / f,
                    mult: frame.mult * f,
                },
                out,
            )
        }
    }
}

/// A scene the previewer cannot pack: the field (`objects[3].shape`) and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct PackError {
    /// Path of the offending field in the scene file.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

/// The SDF programs of `objects` and their records; errors when a tree needs
/// a deeper stack than the shader has.
pub fn compile_objects(objects: &[SceneObject]) -> Result<(Vec<GpuObject>, Vec<Node>), PackError> {
    let mut nodes = Vec::new();
    let mut records = Vec::new();
    for (i, o) in objects.iter().enumerate() {
        let start = nodes.len();
        let depth = compile(&o.shape, Frame::IDENTITY, &mut nodes);
        if depth > STACK_DEPTH {
            return Err(PackError {
                field: format!("objects[{i}].shape"),
                message: format!(
                    "nested {depth} levels deep, more than the previewer's {STACK_DEPTH}"
                ),
            });
        }
        let (c, r) = o.shape.bounding_sphere();
        let r = if r.is_finite() && c.is_finite() {
            r
        } else {
            -1.0
        };
        records.push(GpuObject {
            range: [start as u32, (nodes.len() - start) as u32, 0, 0],
            albedo: rgb4(o.albedo, r),
            center: v4(if c.is_finite() { c } else { DVec3::ZERO }, 0.0),
        });
    }
    Ok((records, nodes))
}

/// Evaluates an SDF program on the CPU, in f32 as the shader does (for tests
/// of the packing, and the editor's picking).
pub fn eval_program(nodes: &[Node], p: [f32; 3]) -> f32 {
    let mut stack = [0.0f32; STACK_DEPTH];
    let mut top = 0usize;
    for n in nodes {
        let local = |row: [f32; 4]| row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + row[3];
        let q = [local(n.rows[0]), local(n.rows[1]), local(n.rows[2])];
        let sub = |c: [f32; 4]| [q[0] - c[0], q[1] - c[1], q[2] - c[2]];
        let len3 = |v: [f32; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let box_d = |d: [f32; 3], h: [f32; 4], shrink: f32| {
            let e = [
                d[0].abs() - h[0] + shrink,
                d[1].abs() - h[1] + shrink,
                d[2].abs() - h[2] + shrink,
            ];
            len3([e[0].max(0.0), e[1].max(0.0), e[2].max(0.0)]) + e[0].max(e[1]).max(e[2]).min(0.0)
                - shrink
        };
        let kind = n.kind[0];
        let value = match kind {
            op::SPHERE => Some(len3(sub(n.p0)) - n.p0[3]),
            op::BOX => Some(box_d(sub(n.p0), n.p1, 0.0)),
            op::ROUNDED_BOX => Some(box_d(sub(n.p0), n.p1, n.p0[3])),
            op::PLANE => Some(n.p0[0] * q[0] + n.p0[1] * q[1] + n.p0[2] * q[2] - n.p0[3]),
            op::TORUS => {
                let d = sub(n.p0);
                let rho = (d[0] * d[0] + d[2] * d[2]).sqrt();
                Some((rho - n.p1[0]).hypot(d[1]) - n.p1[1])
            }
            op::CYLINDER => {
                let d = sub(n.p0);
                let a = (d[0] * d[0] + d[2] * d[2]).sqrt() - n.p1[0];
                let b = d[1].abs() - n.p1[1];
                Some(a.max(b).min(0.0) + a.max(0.0).hypot(b.max(0.0)))
            }
            op::CAPSULE => {
                let pa = sub(n.p0);
                let ba = [n.p1[0] - n.p0[0], n.p1[1] - n.p0[1], n.p1[2] - n.p0[2]];
                let bb = ba[0] * ba[0] + ba[1] * ba[1] + ba[2] * ba[2];
                let h = if bb > 0.0 {
                    ((pa[0] * ba[0] + pa[1] * ba[1] + pa[2] * ba[2]) / bb).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                Some(len3([pa[0] - ba[0] * h, pa[1] - ba[1] * h, pa[2] - ba[2] * h]) - n.p0[3])
            }
            _ => None,
        };
        match value {
            Some(d) => {
                stack[top] = d * n.p1[3];
                top += 1;
            }
            None => {
                let b = stack[top - 1];
                let a = stack[top - 2];
                top -= 1;
                stack[top - 1] = match kind {
                    op::MIN => a.min(b),
                    op::MAX => a.max(b),
                    op::DIFF => a.max(-b),
                    _ => {
                        let k = n.p0[0];
                        let h = (k - (a - b).abs()).max(0.0) / k;
                        a.min(b) - h * h * k * 0.25
                    }
                };
            }
        }
    }
    if top == 0 { f32::INFINITY } else { stack[0] }
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
pub fn pack(
    scene: &Scene,
    medium: &LogisticMedium,
    view: &View,
) -> Result<SceneBuffers, PackError> {
    // As the CPU renderer: seen from the scene camera's altitude.
    let sky = SkyModel::from_spec(
        &scene.sky,
        &scene.sun,
        scene.camera.position.y,
        view.camera.pixel_angle(),
    );
    let objects_box = Aabb::of_objects(&scene.objects);
    let air = Air::new(
        medium,
        view.straight,
        scene.step,
        scene.ground.is_some(),
        objects_box,
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
    };
    // The CPU renderer's grid of unbounding spheres and near lists, cut at
    // the ground as there.
    let floor = if scene.ground.is_some() {
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
    buffers.set_air(&air);
    buffers.set_view(view);
    let p = &mut buffers.params;
    p.size[3] = scene.objects.len() as u32;
    p.flags[2] = match scene.ground {
        None => 0,
        Some(GroundAlbedo::Uniform(c)) => {
            p.ground0 = rgb4(c, 0.0);
            1
        }
        Some(GroundAlbedo::Checker { size, colors }) => {
            p.ground0 = rgb4(colors[0], size);
            p.ground1 = rgb4(colors[1], 0.0);
            2
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
    p.up[3] = scene.max_distance as f32;
    p.counts = [SKY_WIDTH, SKY_HEIGHT, view.samples_per_pixel, MAX_QUERIES];
    if buffers.objects.is_empty() {
        buffers.objects.push(GpuObject::default());
    }
    if buffers.nodes.is_empty() {
        buffers.nodes.push(Node::default());
    }
    Ok(buffers)
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
            Shading::Lit => 0,
            Shading::Albedo => 1,
        };
        p.tolerance = [1e-4, (view.hit_fraction * c.pixel_angle()) as f32, 0.0, 0.0];
        p.counts[2] = view.samples_per_pixel.max(1);
        p.stars[0] = star_radius(c.pixel_angle()) as f32;
    }

    /// Sets the medium and what follows from it (the air's analysis).
    pub fn set_air(&mut self, air: &Air) {
        let p = &mut self.params;
        let raw = air.field().coefficients();
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
        p.air = [
            air.n_max() as f32,
            finite_or_big(inside) as f32,
            finite_or_big(outside) as f32,
            0.0,
        ];
        self.hotspots = raw
            .hotspots
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
            0.0,
        ];
        if self.profile.is_empty() {
            self.profile.push([0.0; 4]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shapes() -> Vec<Sdf> {
        let cyl = Sdf::cylinder(DVec3::new(0.0, 0.0, 0.0), 0.34, 0.12);
        vec![
            Sdf::sphere(DVec3::new(1.0, 2.0, 3.0), 0.5),
            Sdf::translate(
                DVec3::new(-1.7, 0.0, 262.0),
                Sdf::rotate(
                    DVec3::Y,
                    180.0,
                    Sdf::union(vec![
                        Sdf::rounded_box(
                            DVec3::new(0.0, 0.78, 0.0),
                            DVec3::new(0.9, 0.45, 2.2),
                            0.18,
                        ),
                        Sdf::translate(
                            DVec3::new(-0.86, 0.34, -1.35),
                            Sdf::rotate(DVec3::Z, 90.0, cyl.clone()),
                        ),
                        Sdf::cuboid(DVec3::new(0.0, 1.5, 0.0), DVec3::new(0.7, 0.3, 1.1)),
                    ]),
                ),
            ),
            Sdf::difference(
                Sdf::scale(2.0, Sdf::torus(DVec3::new(0.0, 1.0, 5.0), 1.0, 0.3)),
                Sdf::capsule(DVec3::new(0.0, 1.0, 9.0), DVec3::new(0.0, 3.0, 11.0), 0.5),
            ),
            Sdf::smooth_union(
                vec![
                    Sdf::sphere(DVec3::new(0.0, 1.0, 0.0), 1.0),
                    Sdf::scale(0.5, Sdf::sphere(DVec3::new(2.0, 2.0, 0.0), 1.0)),
                    Sdf::cylinder(DVec3::new(-1.0, 1.0, 0.0), 0.3, 2.0),
                ],
                0.4,
            ),
            Sdf::intersection(vec![
                Sdf::plane(DVec3::new(0.3, 1.0, 0.0), 2.0),
                Sdf::sphere(DVec3::ZERO, 3.0),
            ]),
        ]
    }

    #[test]
    fn programs_match_the_cpu_distances() {
        for (i, s) in shapes().into_iter().enumerate() {
            let obj = SceneObject {
                name: None,
                albedo: [0.5; 3],
                shape: s.clone(),
            };
            let (records, nodes) = compile_objects(std::slice::from_ref(&obj)).unwrap();
            let r = records[0].range;
            let prog = &nodes[r[0] as usize..(r[0] + r[1]) as usize];
            let (c, _) = s.bounding_sphere();
            let c = if c.is_finite() { c } else { DVec3::ZERO };
            let mut worst = 0.0f64;
            for k in 0..500 {
                // A deterministic cloud of points around the shape.
                let f = k as f64;
                let p = c + DVec3::new(
                    (f * 0.754_877).fract() - 0.5,
                    (f * 0.569_840).fract() - 0.5,
                    (f * 0.381_966).fract() - 0.5,
                ) * 12.0;
                let want = s.distance(p);
                let got = eval_program(prog, [p.x as f32, p.y as f32, p.z as f32]) as f64;
                worst = worst.max((got - want).abs() / want.abs().max(1.0));
            }
            assert!(worst < 2e-5, "shape {i}: worst relative error {worst:e}");
        }
    }

    #[test]
    fn too_deep_trees_are_refused() {
        let mut s = Sdf::sphere(DVec3::ZERO, 1.0);
        for k in 0..20 {
            s = Sdf::difference(Sdf::sphere(DVec3::new(k as f64, 0.0, 0.0), 1.0), s);
        }
        let obj = SceneObject {
            name: None,
            albedo: [0.5; 3],
            shape: s,
        };
        let err = compile_objects(&[obj]).unwrap_err();
        assert_eq!(err.field, "objects[0].shape");
        assert!(err.message.contains("21 levels deep"), "{err}");
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
