//! Signed distance fields (SDFs) for the scene description.
//!
//! The renderer sphere-traces (curved) rays through the scene: at every point
//! `p` it asks the scene for a distance `d(p)` such that no surface lies
//! closer than `|d(p)|`, and advances the ray by at most that much. This
//! module provides the shapes that make up a scene, as one closed enum
//! ([`Sdf`]) evaluated by a `match` (static dispatch, pbrt-style), plus the
//! per-object data the renderer needs at a hit ([`SceneObject`]).
//!
//! All quantities are `f64` metres: scenes are kilometres wide and contain
//! centimetre-thin poles, which `f32` cannot resolve at that range.
//!
//! # Sign convention and guarantees
//!
//! `d(p) < 0` inside, `d(p) > 0` outside, `d(p) = 0` on the surface.
//!
//! * **Primitives** return the *exact* Euclidean signed distance (inside and
//!   outside): sphere, box, rounded box, plane, torus, capped cylinder,
//!   capsule.
//! * **Combinators and transforms** return a *conservative bound*: a
//!   1-Lipschitz function with the right sign whose magnitude never exceeds
//!   the true distance to the surface, so a sphere-tracing step never jumps
//!   over a surface. (`union` of disjoint children is exact outside; in
//!   general `|d|` may underestimate, which only costs extra steps.)
//!
//! # Life cycle
//!
//! 1. Deserialize (`serde_json::from_str::<Vec<SceneObject>>`) or build with
//!    the constructors ([`Sdf::sphere`], [`Sdf::rotate`], …). Derived data
//!    (unit plane normals, rotation matrices, inverse scale factors) is
//!    computed here, once, so evaluation never allocates nor recomputes it.
//! 2. [`validate_objects`] / [`SceneObject::validate`] / [`Sdf::validate`]
//!    with a path prefix: every parameter is checked and an error names the
//!    offending field, e.g.
//!    `objects[2].shape.children[1].radius: must be > 0, got -1`.
//!    Evaluating a shape that failed validation gives meaningless numbers.
//! 3. Evaluate: [`Sdf::distance`], [`Sdf::normal`], [`nearest_object`],
//!    [`sphere_trace`]; for straight segments, [`Sdf::segment_meets`] (in
//!    closed form where the shapes allow).
//!
//! # JSON schema
//!
//! Every shape is an object with a `"type"` tag (snake_case variant name)
//! and exactly the fields listed below; unknown fields and unknown types are
//! errors. Vectors are `[x, y, z]` arrays. The `y` axis is up.
//!
//! ## Primitives
//!
//! | `type` | field | type | meaning |
//! |---|---|---|---|
//! | `sphere` | `center` | vec3 | centre |
//! | | `radius` | f64 > 0 | radius |
//! | `box` | `center` | vec3 | centre (axis-aligned; rotate with `rotate`) |
//! | | `half_extents` | vec3, each > 0 | half the side lengths |
//! | `rounded_box` | `center` | vec3 | centre |
//! | | `half_extents` | vec3, each > 0 | half the side lengths of the *outer* box (rounding included) |
//! | | `radius` | 0 < f64 ≤ min(`half_extents`) | edge/corner rounding radius |
//! | `plane` | `normal` | vec3 ≠ 0 | outward normal (normalised on construction) |
//! | | `offset` | f64 | signed distance of the plane from the origin along the unit normal: the plane is `n̂·p = offset`, the solid is `n̂·p < offset` |
//! | `torus` | `center` | vec3 | centre; the ring lies in the `xz` plane (axis `y`) |
//! | | `major_radius` | f64 > 0 | ring radius (centre to tube centre) |
//! | | `minor_radius` | 0 < f64 ≤ `major_radius` | tube radius |
//! | `cylinder` | `center` | vec3 | centre; capped, axis `y` |
//! | | `radius` | f64 > 0 | radius |
//! | | `half_height` | f64 > 0 | half the length along `y` (caps at `center.y ± half_height`) |
//! | `capsule` | `a` | vec3 | first end point of the core segment |
//! | | `b` | vec3 | second end point (`a == b` gives a sphere) |
//! | | `radius` | f64 > 0 | radius around the segment |
//!
//! ## Combinators
//!
//! | `type` | field | type | meaning |
//! |---|---|---|---|
//! | `union` | `children` | non-empty array of shapes | `min` of the children |
//! | `intersection` | `children` | non-empty array of shapes | `max` of the children |
//! | `difference` | `base` | shape | the solid … |
//! | | `subtract` | shape | … minus this one: `max(base, −subtract)` |
//! | `smooth_union` | `children` | non-empty array of shapes | polynomial smooth minimum (Inigo Quilez), folded left to right |
//! | | `k` | f64 > 0 | blend width in metres: children closer than `k` in distance are blended; the blend adds at most `k/4` of material |
//!
//! ## Transforms
//!
//! | `type` | field | type | meaning |
//! |---|---|---|---|
//! | `translate` | `offset` | vec3 | moves `child` by `offset` |
//! | | `child` | shape | |
//! | `rotate` | `axis` | vec3 ≠ 0 | rotation axis through the **origin** (normalised on construction); wrap in `translate` to rotate about a pivot |
//! | | `degrees` | f64 | angle, right-handed (counter-clockwise looking down the axis) |
//! | | `child` | shape | |
//! | `scale` | `factor` | f64 > 0 | uniform scale about the origin: `d(p) = s·child(p/s)` (uniform only, so the bound stays exact) |
//! | | `child` | shape | |
//!
//! ## Scene objects
//!
//! | field | type | meaning |
//! |---|---|---|
//! | `name` | string, optional | for messages and debugging |
//! | `albedo` | `[r, g, b]`, each in [0, 1] | linear-RGB diffuse albedo applied at hits on this object |
//! | `shape` | shape | the geometry |
//!
//! ## Example
//!
//! A ground slab, a 5 cm pole 1 km away and a rounded, rotated sign board:
//!
//! ```json
//! [
//!   { "name": "ground", "albedo": [0.3, 0.25, 0.2],
//!     "shape": { "type": "plane", "normal": [0, 1, 0], "offset": 0 } },
//!   { "name": "pole", "albedo": [0.8, 0.8, 0.8],
//!     "shape": { "type": "cylinder", "center": [1000, 2, 0],
//!                "radius": 0.025, "half_height": 2 } },
//!   { "name": "sign", "albedo": [0.9, 0.1, 0.1],
//!     "shape": { "type": "translate", "offset": [1000, 4.5, 0],
//!                "child": { "type": "rotate", "axis": [0, 1, 0], "degrees": 30,
//!                           "child": { "type": "smooth_union", "k": 0.05,
//!                                      "children": [
//!                                        { "type": "rounded_box", "center": [0, 0, 0],
//!                                          "half_extents": [0.5, 0.3, 0.02], "radius": 0.01 },
//!                                        { "type": "capsule", "a": [0, -0.5, 0],
//!                                          "b": [0, 0, 0], "radius": 0.025 } ] } } } }
//! ]
//! ```

mod bounds;
mod construction;
mod distance;
mod segment;
mod serde_payloads;
mod trace;
mod validate;

#[cfg(test)]
mod json_tests;
#[cfg(test)]
mod tests;

pub use trace::{DistanceField, MAX_TRACE_STEPS, nearest_object, sphere_trace};
pub use validate::validate_objects;

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// Relative step of [`Sdf::gradient`] / [`Sdf::normal`]: the central
/// difference step is `NORMAL_RELATIVE_STEP · max(‖p‖∞, 1 m)`.
///
/// At 1 km this is 0.1 mm, far below a 2.5 cm pole radius, while the
/// rounding error of the differenced distances (≈ 1e-16 · 1 km) stays
/// ~1e-9 of the gradient.
pub const NORMAL_RELATIVE_STEP: f64 = 1e-7;

/// A signed distance field: a closed set of primitives, combinators and
/// transforms, evaluated by static dispatch.
///
/// Deserializes from JSON with a `"type"` tag (see the [module
/// documentation](self) for the schema). Unknown fields and types are
/// rejected. Call [`Sdf::validate`] before evaluating a deserialized value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Sdf {
    /// Sphere: `|p − center| − radius` (exact).
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius, > 0.
        radius: f64,
    },
    /// Axis-aligned box (exact). JSON type `box`.
    Box {
        /// Centre.
        center: DVec3,
        /// Half side lengths, each > 0.
        half_extents: DVec3,
    },
    /// Axis-aligned box with rounded edges and corners (exact).
    RoundedBox {
        /// Centre.
        center: DVec3,
        /// Half side lengths of the outer box (rounding included), each > 0.
        half_extents: DVec3,
        /// Rounding radius, `0 < radius ≤ min(half_extents)`.
        radius: f64,
    },
    /// Half-space `n̂·p < offset` (exact). See [`Plane`].
    Plane(Plane),
    /// Torus around the `y` axis (exact).
    Torus {
        /// Centre.
        center: DVec3,
        /// Ring radius (centre to tube centre), > 0.
        major_radius: f64,
        /// Tube radius, `0 < minor_radius ≤ major_radius`.
        minor_radius: f64,
    },
    /// Capped cylinder with axis `y` (exact).
    Cylinder {
        /// Centre.
        center: DVec3,
        /// Radius, > 0.
        radius: f64,
        /// Half the length along `y`, > 0.
        half_height: f64,
    },
    /// All points within `radius` of the segment `a`–`b` (exact).
    Capsule {
        /// First end of the core segment.
        a: DVec3,
        /// Second end of the core segment.
        b: DVec3,
        /// Radius, > 0.
        radius: f64,
    },
    /// Union: minimum of the children (bound).
    Union {
        /// The shapes, at least one.
        children: Vec<Sdf>,
    },
    /// Intersection: maximum of the children (bound).
    Intersection {
        /// The shapes, at least one.
        children: Vec<Sdf>,
    },
    /// `base` minus `subtract`: `max(base, −subtract)` (bound).
    Difference {
        /// The solid to carve.
        base: Box<Sdf>,
        /// The solid removed from `base`.
        subtract: Box<Sdf>,
    },
    /// Polynomial smooth union (Inigo Quilez's quadratic smooth minimum),
    /// folded left to right over the children (bound).
    SmoothUnion {
        /// The shapes, at least one.
        children: Vec<Sdf>,
        /// Blend width in metres, > 0.
        k: f64,
    },
    /// Moves `child` by `offset`.
    Translate {
        /// Displacement.
        offset: DVec3,
        /// The moved shape.
        child: Box<Sdf>,
    },
    /// Rotates a child about an axis through the origin. See [`Rotate`].
    Rotate(Rotate),
    /// Scales a child uniformly about the origin. See [`Scale`].
    Scale(Scale),
}

/// Half-space bounded by a plane; the [`Sdf::Plane`] payload.
///
/// The surface is `n̂·p = offset` with `n̂` the unit normal; the solid is the
/// side the normal points away from (`n̂·p < offset`); `d(p) = n̂·p − offset`.
/// The normal is normalised on construction (the given vector is kept for
/// serialization); a zero or non-finite normal is rejected by
/// [`Sdf::validate`].
///
/// JSON: `{"type": "plane", "normal": [0, 1, 0], "offset": 0}`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    normal: DVec3,
    offset: f64,
    unit_normal: DVec3,
}

/// Rotation of a child about an axis through the origin; the
/// [`Sdf::Rotate`] payload.
///
/// The world-to-local matrix is computed once on construction.
///
/// JSON: `{"type": "rotate", "axis": [0, 1, 0], "degrees": 30, "child": {…}}`.
#[derive(Debug, Clone, PartialEq)]
pub struct Rotate {
    axis: DVec3,
    degrees: f64,
    child: Box<Sdf>,
    world_to_local: DMat3,
}

/// Uniform scale of a child about the origin; the [`Sdf::Scale`] payload.
///
/// `d(p) = factor · child(p / factor)`; the reciprocal is computed once on
/// construction.
///
/// JSON: `{"type": "scale", "factor": 2, "child": {…}}`.
#[derive(Debug, Clone, PartialEq)]
pub struct Scale {
    factor: f64,
    child: Box<Sdf>,
    inv_factor: f64,
}

/// One object of the scene: a shape and the albedo the renderer applies at
/// hits on it.
///
/// JSON: `{"name": "pole", "albedo": [0.8, 0.8, 0.8], "shape": {…}}`
/// (`name` optional; unknown fields rejected).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneObject {
    /// Optional name, for messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Linear-RGB diffuse albedo, each channel in [0, 1].
    pub albedo: [f64; 3],
    /// The geometry.
    pub shape: Sdf,
}
