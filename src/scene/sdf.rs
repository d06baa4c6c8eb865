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
//!    [`sphere_trace`].
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
#![warn(missing_docs)]

use glam::{DMat3, DQuat, DVec2, DVec3};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Maximum number of distance evaluations [`sphere_trace`] spends on one ray.
pub const MAX_TRACE_STEPS: u32 = 4096;

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

impl Plane {
    /// Half-space `n̂·p < offset` with `n̂ = normal / |normal|`.
    ///
    /// A zero or non-finite `normal` is kept as given (and yields a zero unit
    /// normal); [`Sdf::validate`] rejects it.
    pub fn new(normal: DVec3, offset: f64) -> Self {
        let unit_normal = if normal.is_finite() {
            normal.normalize_or_zero()
        } else {
            DVec3::ZERO
        };
        Self {
            normal,
            offset,
            unit_normal,
        }
    }

    /// The normal as given (not normalised).
    pub fn normal(&self) -> DVec3 {
        self.normal
    }

    /// The unit outward normal (zero if the given normal was degenerate).
    pub fn unit_normal(&self) -> DVec3 {
        self.unit_normal
    }

    /// Signed distance of the plane from the origin along the unit normal.
    pub fn offset(&self) -> f64 {
        self.offset
    }
}

impl Rotate {
    /// Rotation of `child` by `degrees` (right-handed) about `axis` through
    /// the origin.
    ///
    /// A zero or non-finite axis yields the identity matrix here;
    /// [`Sdf::validate`] rejects it.
    pub fn new(axis: DVec3, degrees: f64, child: Sdf) -> Self {
        let unit = if axis.is_finite() {
            axis.normalize_or_zero()
        } else {
            DVec3::ZERO
        };
        let local_to_world = if unit == DVec3::ZERO || !degrees.is_finite() {
            DMat3::IDENTITY
        } else {
            DMat3::from_quat(DQuat::from_axis_angle(unit, degrees.to_radians()))
        };
        Self {
            axis,
            degrees,
            child: Box::new(child),
            world_to_local: local_to_world.transpose(),
        }
    }

    /// The axis as given (not normalised).
    pub fn axis(&self) -> DVec3 {
        self.axis
    }

    /// The angle in degrees.
    pub fn degrees(&self) -> f64 {
        self.degrees
    }

    /// The rotated shape.
    pub fn child(&self) -> &Sdf {
        &self.child
    }

    /// Matrix taking world points into the child's frame (the inverse
    /// rotation).
    pub fn world_to_local(&self) -> DMat3 {
        self.world_to_local
    }

    /// Matrix taking the child's frame to world (the rotation itself).
    pub fn local_to_world(&self) -> DMat3 {
        self.world_to_local.transpose()
    }
}

impl Scale {
    /// Uniform scale of `child` by `factor` about the origin.
    ///
    /// [`Sdf::validate`] rejects `factor ≤ 0` or non-finite.
    pub fn new(factor: f64, child: Sdf) -> Self {
        Self {
            factor,
            child: Box::new(child),
            inv_factor: 1.0 / factor,
        }
    }

    /// The scale factor.
    pub fn factor(&self) -> f64 {
        self.factor
    }

    /// The scaled shape.
    pub fn child(&self) -> &Sdf {
        &self.child
    }
}

// ---------------------------------------------------------------------------
// serde for the payloads with derived fields: (de)serialize the plain fields
// through a spec struct that denies unknown fields, derive the rest.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneSpec {
    normal: DVec3,
    offset: f64,
}

#[derive(Serialize)]
struct PlaneRef {
    normal: DVec3,
    offset: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RotateSpec {
    axis: DVec3,
    degrees: f64,
    child: Sdf,
}

#[derive(Serialize)]
struct RotateRef<'a> {
    axis: DVec3,
    degrees: f64,
    child: &'a Sdf,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScaleSpec {
    factor: f64,
    child: Sdf,
}

#[derive(Serialize)]
struct ScaleRef<'a> {
    factor: f64,
    child: &'a Sdf,
}

impl<'de> Deserialize<'de> for Plane {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let s = PlaneSpec::deserialize(deserializer)?;
        Ok(Plane::new(s.normal, s.offset))
    }
}

impl Serialize for Plane {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        PlaneRef {
            normal: self.normal,
            offset: self.offset,
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Rotate {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let s = RotateSpec::deserialize(deserializer)?;
        Ok(Rotate::new(s.axis, s.degrees, s.child))
    }
}

impl Serialize for Rotate {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        RotateRef {
            axis: self.axis,
            degrees: self.degrees,
            child: &self.child,
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let s = ScaleSpec::deserialize(deserializer)?;
        Ok(Scale::new(s.factor, s.child))
    }
}

impl Serialize for Scale {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        ScaleRef {
            factor: self.factor,
            child: &self.child,
        }
        .serialize(serializer)
    }
}

// ---------------------------------------------------------------------------
// Evaluation.

/// Inigo Quilez's quadratic polynomial smooth minimum with blend width `k`.
///
/// 1-Lipschitz in `(a, b)` jointly (its partial derivatives are `h` and
/// `1 − h` with `h ∈ [0, 1]`), never above `min(a, b)` and never below
/// `min(a, b) − k/4`.
#[inline]
fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// Smallest sphere enclosing two spheres (infinite if either is).
fn enclose(a: (DVec3, f64), b: (DVec3, f64)) -> (DVec3, f64) {
    let ((c1, r1), (c2, r2)) = (a, b);
    if !r1.is_finite() {
        return a;
    }
    if !r2.is_finite() {
        return b;
    }
    let d = (c2 - c1).length();
    if d + r2 <= r1 {
        return a;
    }
    if d + r1 <= r2 {
        return b;
    }
    let r = 0.5 * (d + r1 + r2);
    let c = c1 + (c2 - c1) * ((r - r1) / d);
    // A hair of slack so rounding never leaves a point outside.
    (c, r * (1.0 + 1e-12))
}

fn join(prefix: &str, field: &str) -> String {
    if prefix.is_empty() {
        field.to_string()
    } else {
        format!("{prefix}.{field}")
    }
}

fn check_finite(prefix: &str, field: &str, x: f64) -> Result<(), String> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(format!("{}: must be finite, got {x}", join(prefix, field)))
    }
}

fn check_positive(prefix: &str, field: &str, x: f64) -> Result<(), String> {
    check_finite(prefix, field, x)?;
    if x > 0.0 {
        Ok(())
    } else {
        Err(format!("{}: must be > 0, got {x}", join(prefix, field)))
    }
}

fn check_vec_finite(prefix: &str, field: &str, v: DVec3) -> Result<(), String> {
    for (i, x) in v.to_array().into_iter().enumerate() {
        check_finite(prefix, &format!("{field}[{i}]"), x)?;
    }
    Ok(())
}

fn check_vec_positive(prefix: &str, field: &str, v: DVec3) -> Result<(), String> {
    for (i, x) in v.to_array().into_iter().enumerate() {
        check_positive(prefix, &format!("{field}[{i}]"), x)?;
    }
    Ok(())
}

fn check_nonzero_direction(prefix: &str, field: &str, v: DVec3) -> Result<(), String> {
    check_vec_finite(prefix, field, v)?;
    if v.length_squared() > 0.0 && v.length().is_normal() {
        Ok(())
    } else {
        Err(format!(
            "{}: must be a non-zero vector, got [{}, {}, {}]",
            join(prefix, field),
            v.x,
            v.y,
            v.z
        ))
    }
}

fn validate_children(prefix: &str, children: &[Sdf]) -> Result<(), String> {
    if children.is_empty() {
        return Err(format!(
            "{}: must contain at least one shape",
            join(prefix, "children")
        ));
    }
    for (i, c) in children.iter().enumerate() {
        c.validate(&join(prefix, &format!("children[{i}]")))?;
    }
    Ok(())
}

impl Sdf {
    /// Sphere of `radius` at `center`.
    pub fn sphere(center: DVec3, radius: f64) -> Self {
        Sdf::Sphere { center, radius }
    }

    /// Axis-aligned box (JSON type `box`; `box` is a Rust keyword).
    pub fn cuboid(center: DVec3, half_extents: DVec3) -> Self {
        Sdf::Box {
            center,
            half_extents,
        }
    }

    /// Axis-aligned box of outer half size `half_extents` with edges rounded
    /// by `radius`.
    pub fn rounded_box(center: DVec3, half_extents: DVec3, radius: f64) -> Self {
        Sdf::RoundedBox {
            center,
            half_extents,
            radius,
        }
    }

    /// Half-space `n̂·p < offset`, see [`Plane::new`].
    pub fn plane(normal: DVec3, offset: f64) -> Self {
        Sdf::Plane(Plane::new(normal, offset))
    }

    /// Torus around the `y` axis.
    pub fn torus(center: DVec3, major_radius: f64, minor_radius: f64) -> Self {
        Sdf::Torus {
            center,
            major_radius,
            minor_radius,
        }
    }

    /// Capped cylinder with axis `y`.
    pub fn cylinder(center: DVec3, radius: f64, half_height: f64) -> Self {
        Sdf::Cylinder {
            center,
            radius,
            half_height,
        }
    }

    /// Capsule around the segment `a`–`b`.
    pub fn capsule(a: DVec3, b: DVec3, radius: f64) -> Self {
        Sdf::Capsule { a, b, radius }
    }

    /// Union of `children`.
    pub fn union(children: Vec<Sdf>) -> Self {
        Sdf::Union { children }
    }

    /// Intersection of `children`.
    pub fn intersection(children: Vec<Sdf>) -> Self {
        Sdf::Intersection { children }
    }

    /// `base` minus `subtract`.
    pub fn difference(base: Sdf, subtract: Sdf) -> Self {
        Sdf::Difference {
            base: Box::new(base),
            subtract: Box::new(subtract),
        }
    }

    /// Smooth union of `children` with blend width `k`.
    pub fn smooth_union(children: Vec<Sdf>, k: f64) -> Self {
        Sdf::SmoothUnion { children, k }
    }

    /// `child` moved by `offset`.
    pub fn translate(offset: DVec3, child: Sdf) -> Self {
        Sdf::Translate {
            offset,
            child: Box::new(child),
        }
    }

    /// `child` rotated by `degrees` about `axis` through the origin, see
    /// [`Rotate::new`].
    pub fn rotate(axis: DVec3, degrees: f64, child: Sdf) -> Self {
        Sdf::Rotate(Rotate::new(axis, degrees, child))
    }

    /// `child` scaled uniformly by `factor` about the origin.
    pub fn scale(factor: f64, child: Sdf) -> Self {
        Sdf::Scale(Scale::new(factor, child))
    }

    /// Signed distance from `p` to the surface: exact for primitives, a
    /// conservative bound (never larger in magnitude than the true distance)
    /// for combinators. Negative inside. Does not allocate.
    pub fn distance(&self, p: DVec3) -> f64 {
        match self {
            Sdf::Sphere { center, radius } => (p - *center).length() - radius,
            Sdf::Box {
                center,
                half_extents,
            } => {
                let q = (p - *center).abs() - *half_extents;
                q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
            }
            Sdf::RoundedBox {
                center,
                half_extents,
                radius,
            } => {
                let q = (p - *center).abs() - *half_extents + DVec3::splat(*radius);
                q.max(DVec3::ZERO).length() + q.max_element().min(0.0) - radius
            }
            Sdf::Plane(plane) => plane.unit_normal.dot(p) - plane.offset,
            Sdf::Torus {
                center,
                major_radius,
                minor_radius,
            } => {
                let q = p - *center;
                let rho = DVec2::new(q.x, q.z).length();
                DVec2::new(rho - major_radius, q.y).length() - minor_radius
            }
            Sdf::Cylinder {
                center,
                radius,
                half_height,
            } => {
                let q = p - *center;
                let d = DVec2::new(
                    DVec2::new(q.x, q.z).length() - radius,
                    q.y.abs() - half_height,
                );
                d.x.max(d.y).min(0.0) + d.max(DVec2::ZERO).length()
            }
            Sdf::Capsule { a, b, radius } => {
                let pa = p - *a;
                let ba = *b - *a;
                let bb = ba.length_squared();
                let h = if bb > 0.0 {
                    (pa.dot(ba) / bb).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (pa - ba * h).length() - radius
            }
            Sdf::Union { children } => children
                .iter()
                .fold(f64::INFINITY, |m, c| m.min(c.distance(p))),
            Sdf::Intersection { children } => children
                .iter()
                .fold(f64::NEG_INFINITY, |m, c| m.max(c.distance(p))),
            Sdf::Difference { base, subtract } => base.distance(p).max(-subtract.distance(p)),
            Sdf::SmoothUnion { children, k } => {
                let mut it = children.iter();
                match it.next() {
                    None => f64::INFINITY,
                    Some(first) => {
                        it.fold(first.distance(p), |m, c| smooth_min(m, c.distance(p), *k))
                    }
                }
            }
            Sdf::Translate { offset, child } => child.distance(p - *offset),
            Sdf::Rotate(r) => r.child.distance(r.world_to_local * p),
            Sdf::Scale(s) => s.factor * s.child.distance(p * s.inv_factor),
        }
    }

    /// Gradient of [`distance`](Self::distance) by central differences with
    /// the step `h = NORMAL_RELATIVE_STEP · max(‖p‖∞, 1)` (see
    /// [`NORMAL_RELATIVE_STEP`]). Its length is ≈ 1 for exact distances away
    /// from the medial axis, and ≤ 1 for the bounds.
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        self.gradient_with_step(p, NORMAL_RELATIVE_STEP * p.abs().max_element().max(1.0))
    }

    /// Gradient by central differences with an explicit step `h` (6
    /// evaluations).
    pub fn gradient_with_step(&self, p: DVec3, h: f64) -> DVec3 {
        let dx = DVec3::new(h, 0.0, 0.0);
        let dy = DVec3::new(0.0, h, 0.0);
        let dz = DVec3::new(0.0, 0.0, h);
        DVec3::new(
            self.distance(p + dx) - self.distance(p - dx),
            self.distance(p + dy) - self.distance(p - dy),
            self.distance(p + dz) - self.distance(p - dz),
        ) / (2.0 * h)
    }

    /// Outward unit surface normal at (or near) `p`: the normalised
    /// [`gradient`](Self::gradient); zero where the gradient vanishes.
    pub fn normal(&self, p: DVec3) -> DVec3 {
        self.gradient(p).normalize_or_zero()
    }

    /// A sphere `(center, radius)` containing the whole solid, for culling:
    /// outside it the distance is positive. The radius is `f64::INFINITY`
    /// for unbounded shapes (planes, and unions containing them).
    ///
    /// Walks the tree (no allocation); cache the result if needed per ray.
    pub fn bounding_sphere(&self) -> (DVec3, f64) {
        match self {
            Sdf::Sphere { center, radius } => (*center, *radius),
            Sdf::Box {
                center,
                half_extents,
            }
            | Sdf::RoundedBox {
                center,
                half_extents,
                ..
            } => (*center, half_extents.length()),
            Sdf::Plane(plane) => (plane.unit_normal * plane.offset, f64::INFINITY),
            Sdf::Torus {
                center,
                major_radius,
                minor_radius,
            } => (*center, major_radius + minor_radius),
            Sdf::Cylinder {
                center,
                radius,
                half_height,
            } => (*center, DVec2::new(*radius, *half_height).length()),
            Sdf::Capsule { a, b, radius } => ((*a + *b) * 0.5, (*b - *a).length() * 0.5 + radius),
            Sdf::Union { children } => children
                .iter()
                .map(Sdf::bounding_sphere)
                .reduce(enclose)
                .unwrap_or((DVec3::ZERO, 0.0)),
            Sdf::Intersection { children } => children
                .iter()
                .map(Sdf::bounding_sphere)
                .reduce(|a, b| if b.1 < a.1 { b } else { a })
                .unwrap_or((DVec3::ZERO, f64::INFINITY)),
            Sdf::Difference { base, .. } => base.bounding_sphere(),
            Sdf::SmoothUnion { children, k } => {
                let (c, r) = children
                    .iter()
                    .map(Sdf::bounding_sphere)
                    .reduce(enclose)
                    .unwrap_or((DVec3::ZERO, 0.0));
                // Each fold step lowers the field by at most k/4.
                let blends = children.len().saturating_sub(1) as f64;
                (c, r + blends * k * 0.25)
            }
            Sdf::Translate { offset, child } => {
                let (c, r) = child.bounding_sphere();
                (c + *offset, r)
            }
            Sdf::Rotate(rot) => {
                let (c, r) = rot.child.bounding_sphere();
                (rot.local_to_world() * c, r)
            }
            Sdf::Scale(s) => {
                let (c, r) = s.child.bounding_sphere();
                (c * s.factor, r * s.factor)
            }
        }
    }

    /// Checks every parameter of the tree. `path` is the prefix of the
    /// field path used in messages (e.g. `"objects[2].shape"`, or `""`).
    ///
    /// Rejects non-finite numbers, radii/half extents/half heights ≤ 0,
    /// a rounded-box radius above the smallest half extent, a torus tube
    /// wider than its ring, zero plane normals and rotation axes, empty
    /// `children`, `k ≤ 0` and scale `factor ≤ 0`. The first problem found is
    /// reported as `"<path>.<field>: <reason>, got <value>"`, e.g.
    /// `objects[2].shape.children[1].radius: must be > 0, got -1`.
    pub fn validate(&self, path: &str) -> Result<(), String> {
        match self {
            Sdf::Sphere { center, radius } => {
                check_vec_finite(path, "center", *center)?;
                check_positive(path, "radius", *radius)
            }
            Sdf::Box {
                center,
                half_extents,
            } => {
                check_vec_finite(path, "center", *center)?;
                check_vec_positive(path, "half_extents", *half_extents)
            }
            Sdf::RoundedBox {
                center,
                half_extents,
                radius,
            } => {
                check_vec_finite(path, "center", *center)?;
                check_vec_positive(path, "half_extents", *half_extents)?;
                check_positive(path, "radius", *radius)?;
                let smallest = half_extents.min_element();
                if *radius > smallest {
                    return Err(format!(
                        "{}: must be <= the smallest half extent ({smallest}), got {radius}",
                        join(path, "radius")
                    ));
                }
                Ok(())
            }
            Sdf::Plane(plane) => {
                check_nonzero_direction(path, "normal", plane.normal)?;
                check_finite(path, "offset", plane.offset)
            }
            Sdf::Torus {
                center,
                major_radius,
                minor_radius,
            } => {
                check_vec_finite(path, "center", *center)?;
                check_positive(path, "major_radius", *major_radius)?;
                check_positive(path, "minor_radius", *minor_radius)?;
                if minor_radius > major_radius {
                    return Err(format!(
                        "{}: must be <= major_radius ({major_radius}), got {minor_radius}",
                        join(path, "minor_radius")
                    ));
                }
                Ok(())
            }
            Sdf::Cylinder {
                center,
                radius,
                half_height,
            } => {
                check_vec_finite(path, "center", *center)?;
                check_positive(path, "radius", *radius)?;
                check_positive(path, "half_height", *half_height)
            }
            Sdf::Capsule { a, b, radius } => {
                check_vec_finite(path, "a", *a)?;
                check_vec_finite(path, "b", *b)?;
                check_positive(path, "radius", *radius)
            }
            Sdf::Union { children } | Sdf::Intersection { children } => {
                validate_children(path, children)
            }
            Sdf::Difference { base, subtract } => {
                base.validate(&join(path, "base"))?;
                subtract.validate(&join(path, "subtract"))
            }
            Sdf::SmoothUnion { children, k } => {
                check_positive(path, "k", *k)?;
                validate_children(path, children)
            }
            Sdf::Translate { offset, child } => {
                check_vec_finite(path, "offset", *offset)?;
                child.validate(&join(path, "child"))
            }
            Sdf::Rotate(r) => {
                check_nonzero_direction(path, "axis", r.axis)?;
                check_finite(path, "degrees", r.degrees)?;
                r.child.validate(&join(path, "child"))
            }
            Sdf::Scale(s) => {
                check_positive(path, "factor", s.factor)?;
                s.child.validate(&join(path, "child"))
            }
        }
    }
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

impl SceneObject {
    /// Checks the albedo and the shape; `path` prefixes the messages (e.g.
    /// `"objects[2]"` gives `objects[2].shape.radius: …`).
    pub fn validate(&self, path: &str) -> Result<(), String> {
        for (i, a) in self.albedo.iter().enumerate() {
            let field = format!("albedo[{i}]");
            check_finite(path, &field, *a)?;
            if !(0.0..=1.0).contains(a) {
                return Err(format!(
                    "{}: must be in [0, 1], got {a}",
                    join(path, &field)
                ));
            }
        }
        self.shape.validate(&join(path, "shape"))
    }

    /// Signed distance to this object's shape.
    pub fn distance(&self, p: DVec3) -> f64 {
        self.shape.distance(p)
    }
}

/// Validates every object, with paths `"<path>[i]…"` (e.g. `path =
/// "objects"` gives `objects[2].shape.children[1].radius: must be > 0, got
/// -1`).
pub fn validate_objects(objects: &[SceneObject], path: &str) -> Result<(), String> {
    for (i, o) in objects.iter().enumerate() {
        o.validate(&format!("{path}[{i}]"))?;
    }
    Ok(())
}

/// Minimum signed distance over `objects` at `p` and the index of the object
/// attaining it (the first one on ties), or `(f64::INFINITY, None)` for an
/// empty slice. At a sphere-tracing hit the index tells which albedo applies.
pub fn nearest_object(objects: &[SceneObject], p: DVec3) -> (f64, Option<usize>) {
    let mut best = (f64::INFINITY, None);
    for (i, o) in objects.iter().enumerate() {
        let d = o.shape.distance(p);
        if d < best.0 {
            best = (d, Some(i));
        }
    }
    best
}

/// Anything that gives a signed distance bound: lets [`sphere_trace`] run on
/// a single [`Sdf`], a [`SceneObject`] or a whole slice of objects, with
/// static dispatch.
pub trait DistanceField {
    /// Signed distance (or conservative bound) at `p`.
    fn distance(&self, p: DVec3) -> f64;
}

impl DistanceField for Sdf {
    fn distance(&self, p: DVec3) -> f64 {
        Sdf::distance(self, p)
    }
}

impl DistanceField for SceneObject {
    fn distance(&self, p: DVec3) -> f64 {
        self.shape.distance(p)
    }
}

impl DistanceField for [SceneObject] {
    fn distance(&self, p: DVec3) -> f64 {
        nearest_object(self, p).0
    }
}

/// Sphere-traces the straight ray `origin + t·dir̂` (`dir` is normalised
/// here, so `t` is a length) through `field`.
///
/// Returns `Some((t, steps))` for the first point with `d < eps`, where
/// `steps` is the number of distance evaluations, or `None` if the ray
/// leaves `[0, max_t]`, the field is NaN, `dir` is degenerate, or
/// [`MAX_TRACE_STEPS`] evaluations did not converge (grazing rays). With an
/// exact or conservative field the returned `t` is never past the true hit
/// and is within about `eps / cos θ` of it (θ: angle to the surface normal).
/// A ray starting inside a solid hits at `t = 0`.
pub fn sphere_trace<F: DistanceField + ?Sized>(
    field: &F,
    origin: DVec3,
    dir: DVec3,
    max_t: f64,
    eps: f64,
) -> Option<(f64, u32)> {
    let dir = dir.normalize_or_zero();
    if dir == DVec3::ZERO {
        return None;
    }
    let mut t = 0.0;
    for step in 1..=MAX_TRACE_STEPS {
        let d = field.distance(origin + dir * t);
        if d.is_nan() {
            return None;
        }
        if d < eps {
            return Some((t, step));
        }
        t += d;
        if t > max_t {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;
    use proptest::prelude::*;

    // ---- helpers ---------------------------------------------------------

    fn v3(lo: f64, hi: f64) -> impl Strategy<Value = DVec3> {
        (lo..hi, lo..hi, lo..hi).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    /// Deterministic PRNG (SplitMix64) for the sampling checks.
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self) -> f64 {
            let mut g = SplitMix64(self.0);
            let u = g.next_f64();
            self.0 = g.0;
            u
        }
        fn unit_vector(&mut self) -> DVec3 {
            loop {
                let v = DVec3::new(
                    2.0 * self.uniform() - 1.0,
                    2.0 * self.uniform() - 1.0,
                    2.0 * self.uniform() - 1.0,
                );
                let l = v.length();
                if l > 1e-3 && l <= 1.0 {
                    return v / l;
                }
            }
        }
    }

    // Independent analytic distance formulas (written differently from the
    // module's, via clamping / explicit case analysis / numeric search).

    fn box_exact(p: DVec3, c: DVec3, he: DVec3) -> f64 {
        let q = p - c;
        let clamped = q.clamp(-he, he);
        if clamped == q {
            // inside or on: distance to the nearest face
            -(he - q.abs()).min_element()
        } else {
            (q - clamped).length()
        }
    }

    fn cylinder_exact(p: DVec3, c: DVec3, r: f64, h: f64) -> f64 {
        let q = p - c;
        let rho = (q.x * q.x + q.z * q.z).sqrt();
        let dx = rho - r;
        let dy = q.y.abs() - h;
        if dx <= 0.0 && dy <= 0.0 {
            dx.max(dy)
        } else {
            dx.max(0.0).hypot(dy.max(0.0))
        }
    }

    fn torus_exact(p: DVec3, c: DVec3, big: f64, small: f64) -> f64 {
        let q = p - c;
        let rho = q.x.hypot(q.z);
        (rho - big).hypot(q.y) - small
    }

    fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
        // ternary search on the convex function t -> |p - seg(t)|
        let f = |t: f64| (p - (a + (b - a) * t)).length();
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..200 {
            let m1 = lo + (hi - lo) / 3.0;
            let m2 = hi - (hi - lo) / 3.0;
            if f(m1) <= f(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        f(0.5 * (lo + hi)).min(f(0.0)).min(f(1.0))
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    /// |∇d| ≈ 1 and projecting along the normal lands on the surface.
    fn check_exactness(s: &Sdf, p: DVec3) -> Result<(), TestCaseError> {
        let d = s.distance(p);
        let g = s.gradient(p);
        prop_assert!(
            close(g.length(), 1.0, 1e-6),
            "|grad| = {} at {p} (d = {d})",
            g.length()
        );
        let n = s.normal(p);
        let q = p - n * d;
        let dq = s.distance(q);
        prop_assert!(
            dq.abs() <= 1e-7 * (1.0 + d.abs()),
            "d(p - d n) = {dq} at p = {p}, d = {d}"
        );
        Ok(())
    }

    // ---- primitives vs analytic formulas -----------------------------------

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn sphere_matches_formula(c in v3(-3.0, 3.0), r in 0.1f64..3.0, p in v3(-6.0, 6.0)) {
            let s = Sdf::sphere(c, r);
            let d = s.distance(p);
            prop_assert!(close(d, (p - c).length() - r, 1e-12));
            if (p - c).length() > 1e-3 {
                check_exactness(&s, p)?;
            }
        }

        #[test]
        fn box_matches_formula(c in v3(-3.0, 3.0), he in v3(0.1, 3.0), p in v3(-6.0, 6.0)) {
            let s = Sdf::cuboid(c, he);
            prop_assert!(close(s.distance(p), box_exact(p, c, he), 1e-12));
            let q = p - c;
            let face = he - q.abs();
            let inside = face.min_element() > 0.0;
            let medial = if inside {
                let mut f = face.to_array();
                f.sort_by(f64::total_cmp);
                f[1] - f[0] < 1e-3
            } else {
                false
            };
            if !medial {
                check_exactness(&s, p)?;
            }
        }

        #[test]
        fn rounded_box_matches_formula(
            c in v3(-3.0, 3.0), he in v3(0.2, 3.0), frac in 0.01f64..1.0, p in v3(-6.0, 6.0)
        ) {
            let r = frac * he.min_element();
            let s = Sdf::rounded_box(c, he, r);
            let inner = he - DVec3::splat(r);
            prop_assert!(close(s.distance(p), box_exact(p, c, inner) - r, 1e-12));
            prop_assert!(s.validate("").is_ok());
            let face = inner - (p - c).abs();
            let medial = if face.min_element() > -1e-3 {
                let mut f = face.to_array();
                f.sort_by(f64::total_cmp);
                f[1] - f[0] < 1e-3 || f[0].abs() < 1e-3
            } else {
                false
            };
            if !medial {
                check_exactness(&s, p)?;
            }
        }

        #[test]
        fn plane_matches_formula(n in v3(-1.0, 1.0), off in -3.0f64..3.0, p in v3(-6.0, 6.0)) {
            prop_assume!(n.length() > 0.05);
            let s = Sdf::plane(n, off);
            let expect = n.dot(p) / n.length() - off;
            prop_assert!(close(s.distance(p), expect, 1e-12));
            check_exactness(&s, p)?;
        }

        #[test]
        fn torus_matches_formula(
            c in v3(-2.0, 2.0), big in 0.5f64..3.0, frac in 0.05f64..1.0, p in v3(-6.0, 6.0)
        ) {
            let small = frac * big;
            let s = Sdf::torus(c, big, small);
            prop_assert!(close(s.distance(p), torus_exact(p, c, big, small), 1e-12));
            let q = p - c;
            let rho = q.x.hypot(q.z);
            // medial axis: the y axis and the core circle
            if rho > 1e-3 && (rho - big).hypot(q.y) > 1e-3 {
                check_exactness(&s, p)?;
            }
        }

        #[test]
        fn cylinder_matches_formula(
            c in v3(-3.0, 3.0), r in 0.05f64..3.0, h in 0.05f64..3.0, p in v3(-6.0, 6.0)
        ) {
            let s = Sdf::cylinder(c, r, h);
            prop_assert!(close(s.distance(p), cylinder_exact(p, c, r, h), 1e-12));
            let q = p - c;
            let rho = q.x.hypot(q.z);
            let inside = rho < r && q.y.abs() < h;
            let medial = inside && (((r - rho) - (h - q.y.abs())).abs() < 1e-3 || rho < 1e-3);
            if !medial {
                check_exactness(&s, p)?;
            }
        }

        #[test]
        fn capsule_matches_formula(
            a in v3(-3.0, 3.0), b in v3(-3.0, 3.0), r in 0.05f64..2.0, p in v3(-6.0, 6.0)
        ) {
            let s = Sdf::capsule(a, b, r);
            prop_assert!(close(s.distance(p), segment_distance(p, a, b) - r, 1e-9));
            if segment_distance(p, a, b) > 1e-3 {
                check_exactness(&s, p)?;
            }
        }
    }

    #[test]
    fn degenerate_capsule_is_sphere() {
        let c = DVec3::new(1.0, 2.0, 3.0);
        let s = Sdf::capsule(c, c, 0.5);
        let p = DVec3::new(4.0, -1.0, 0.5);
        assert!(close(s.distance(p), (p - c).length() - 0.5, 1e-12));
    }

    #[test]
    fn sphere_normal_is_radial() {
        let c = DVec3::new(1000.0, 2.0, -3.0);
        let s = Sdf::sphere(c, 0.025);
        for dir in [DVec3::X, DVec3::NEG_Y, DVec3::new(1.0, 2.0, -2.0) / 3.0] {
            let p = c + dir * 0.025;
            let n = s.normal(p);
            assert!((n - dir).length() < 1e-5, "normal {n} vs {dir}");
        }
    }

    // ---- sphere tracing vs analytic ray intersections ----------------------

    const TRACE_EPS: f64 = 1e-10;

    fn ray_sphere(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
        let oc = o - c;
        let b = oc.dot(d);
        let cc = oc.length_squared() - r * r;
        let disc = b * b - cc;
        if disc < 0.0 {
            return None;
        }
        let t = -b - disc.sqrt();
        (t >= 0.0).then_some(t)
    }

    /// Slab test; returns (t_near, entering axis).
    fn ray_box(o: DVec3, d: DVec3, c: DVec3, he: DVec3) -> Option<(f64, usize)> {
        let lo = c - he;
        let hi = c + he;
        let mut t_near = f64::NEG_INFINITY;
        let mut t_far = f64::INFINITY;
        let mut axis = 0;
        for i in 0..3 {
            let t1 = (lo[i] - o[i]) / d[i];
            let t2 = (hi[i] - o[i]) / d[i];
            let (a, b) = if t1 < t2 { (t1, t2) } else { (t2, t1) };
            if a > t_near {
                t_near = a;
                axis = i;
            }
            t_far = t_far.min(b);
        }
        (t_near <= t_far && t_near >= 0.0).then_some((t_near, axis))
    }

    /// Capped cylinder, axis y; returns (t, outward normal at hit).
    fn ray_cylinder(o: DVec3, d: DVec3, c: DVec3, r: f64, h: f64) -> Option<(f64, DVec3)> {
        let q = o - c;
        let mut best: Option<(f64, DVec3)> = None;
        let mut consider = |t: f64, n: DVec3| {
            if t >= 0.0 && best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, n));
            }
        };
        let a = d.x * d.x + d.z * d.z;
        if a > 0.0 {
            let b = q.x * d.x + q.z * d.z;
            let cc = q.x * q.x + q.z * q.z - r * r;
            let disc = b * b - a * cc;
            if disc >= 0.0 {
                for t in [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a] {
                    let hit = q + d * t;
                    if hit.y.abs() <= h {
                        consider(t, DVec3::new(hit.x, 0.0, hit.z) / r);
                    }
                }
            }
        }
        if d.y != 0.0 {
            for (cap, ny) in [(h, 1.0), (-h, -1.0)] {
                let t = (cap - q.y) / d.y;
                let hit = q + d * t;
                if hit.x * hit.x + hit.z * hit.z <= r * r {
                    consider(t, DVec3::new(0.0, ny, 0.0));
                }
            }
        }
        best
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn trace_sphere(
            c in v3(-2.0, 2.0), r in 0.1f64..2.0, o in v3(-10.0, 10.0), u in v3(-1.3, 1.3)
        ) {
            // aim near the solid: mostly hits, some near misses
            let tgt = c + u * r;
            prop_assume!((o - c).length() > r + 0.01);
            prop_assume!((tgt - o).length() > 1e-3);
            let d = (tgt - o).normalize();
            let s = Sdf::sphere(c, r);
            let exact = ray_sphere(o, d, c, r);
            // closest approach of the ray's line to the centre
            let along = (c - o).dot(d);
            let miss_margin = ((c - o) - d * along).length() - r;
            prop_assume!(miss_margin.abs() > 1e-3 || along < 0.0);
            let got = sphere_trace(&s, o, d, 100.0, TRACE_EPS);
            match exact {
                Some(t) => {
                    let n = (o + d * t - c) / r;
                    prop_assume!(-n.dot(d) > 0.05);
                    let (tt, _) = got.expect("analytic hit, traced miss");
                    prop_assert!((tt - t).abs() <= 1e-6 * t, "traced {tt}, exact {t}");
                    prop_assert!(tt <= t + 1e-12);
                }
                None => {
                    prop_assert!(got.is_none(), "analytic miss, traced {got:?}");
                }
            }
        }

        #[test]
        fn trace_box(
            c in v3(-2.0, 2.0), he in v3(0.1, 2.0), o in v3(-10.0, 10.0), u in v3(-1.3, 1.3)
        ) {
            let tgt = c + u * he;
            let s = Sdf::cuboid(c, he);
            prop_assume!(s.distance(o) > 0.01);
            prop_assume!((tgt - o).length() > 1e-3);
            let d = (tgt - o).normalize();
            let got = sphere_trace(&s, o, d, 100.0, TRACE_EPS);
            match ray_box(o, d, c, he) {
                Some((t, axis)) => {
                    prop_assume!(d[axis].abs() > 0.05);
                    let (tt, _) = got.expect("analytic hit, traced miss");
                    prop_assert!((tt - t).abs() <= 1e-6 * t, "traced {tt}, exact {t}");
                    prop_assert!(tt <= t + 1e-12);
                }
                None => {
                    // skip rays grazing an edge/face (closest approach tiny)
                    let closest = (0..2000)
                        .map(|i| s.distance(o + d * (i as f64 * 0.02)))
                        .fold(f64::INFINITY, f64::min);
                    prop_assume!(closest > 1e-3);
                    prop_assert!(got.is_none(), "analytic miss, traced {got:?}");
                }
            }
        }

        #[test]
        fn trace_plane(
            n in v3(-1.0, 1.0), off in -2.0f64..2.0, o in v3(-10.0, 10.0), dir in v3(-1.0, 1.0)
        ) {
            prop_assume!(n.length() > 0.1 && dir.length() > 0.1);
            let s = Sdf::plane(n, off);
            let nn = n.normalize();
            let d = dir.normalize();
            prop_assume!(s.distance(o) > 0.01);
            let denom = nn.dot(d);
            let got = sphere_trace(&s, o, d, 1000.0, TRACE_EPS);
            let t = (off - nn.dot(o)) / denom;
            if denom < -0.05 && t <= 900.0 {
                let (tt, _) = got.expect("analytic hit, traced miss");
                prop_assert!((tt - t).abs() <= 1e-6 * t, "traced {tt}, exact {t}");
            } else if denom >= 0.0 {
                prop_assert!(got.is_none(), "ray leaves the plane, traced {got:?}");
            }
        }

        #[test]
        fn trace_cylinder(
            c in v3(-2.0, 2.0), r in 0.05f64..2.0, h in 0.05f64..2.0,
            o in v3(-10.0, 10.0), u in v3(-1.3, 1.3)
        ) {
            let tgt = c + u * DVec3::new(r, h, r);
            let s = Sdf::cylinder(c, r, h);
            prop_assume!(s.distance(o) > 0.01);
            prop_assume!((tgt - o).length() > 1e-3);
            let d = (tgt - o).normalize();
            let got = sphere_trace(&s, o, d, 100.0, TRACE_EPS);
            match ray_cylinder(o, d, c, r, h) {
                Some((t, n)) => {
                    prop_assume!(-n.dot(d) > 0.05);
                    let (tt, _) = got.expect("analytic hit, traced miss");
                    prop_assert!((tt - t).abs() <= 1e-6 * t, "traced {tt}, exact {t}");
                    prop_assert!(tt <= t + 1e-12);
                }
                None => {
                    let closest = (0..2000)
                        .map(|i| s.distance(o + d * (i as f64 * 0.02)))
                        .fold(f64::INFINITY, f64::min);
                    prop_assume!(closest > 1e-3);
                    prop_assert!(got.is_none(), "analytic miss, traced {got:?}");
                }
            }
        }
    }

    #[test]
    fn trace_hits_targets_inside_shapes() {
        // Not filtered: rays aimed at the centre of each solid always hit.
        let mut rng = Rng(7);
        let shapes = [
            Sdf::sphere(DVec3::ZERO, 1.0),
            Sdf::cuboid(DVec3::ZERO, DVec3::new(1.0, 0.5, 2.0)),
            Sdf::cylinder(DVec3::ZERO, 0.5, 1.0),
            Sdf::torus(DVec3::ZERO, 1.0, 0.3),
        ];
        for s in &shapes {
            for _ in 0..200 {
                let o = rng.unit_vector() * 20.0;
                let target = if matches!(s, Sdf::Torus { .. }) {
                    DVec3::X
                } else {
                    DVec3::ZERO
                };
                let (t, steps) = sphere_trace(s, o, target - o, 100.0, 1e-9).expect("hit");
                assert!(s.distance(o + (target - o).normalize() * t).abs() < 1e-9);
                assert!(steps < 500);
            }
        }
    }

    #[test]
    fn trace_edge_cases() {
        let s = Sdf::sphere(DVec3::ZERO, 1.0);
        // starting inside: hit at t = 0
        assert_eq!(
            sphere_trace(&s, DVec3::ZERO, DVec3::X, 10.0, 1e-9),
            Some((0.0, 1))
        );
        // degenerate direction
        assert_eq!(
            sphere_trace(&s, DVec3::X * 5.0, DVec3::ZERO, 10.0, 1e-9),
            None
        );
        // max_t shorter than the hit distance
        assert_eq!(
            sphere_trace(&s, DVec3::X * 5.0, DVec3::NEG_X, 3.0, 1e-9),
            None
        );
        // unnormalised direction: t is still a length
        let (t, _) = sphere_trace(&s, DVec3::X * 5.0, DVec3::NEG_X * 7.0, 10.0, 1e-12).unwrap();
        assert!(close(t, 4.0, 1e-9));
        // empty union: infinite distance, miss
        let empty = Sdf::union(vec![]);
        assert_eq!(
            sphere_trace(&empty, DVec3::ZERO, DVec3::X, 10.0, 1e-9),
            None
        );
    }

    // ---- the pole ----------------------------------------------------------

    #[test]
    fn thin_pole_one_km_away() {
        // 5 cm-diameter, 4 m tall pole standing on y = 0, 1 km down +x.
        let axis_x = 1000.0;
        let pole = Sdf::cylinder(DVec3::new(axis_x, 2.0, 0.0), 0.025, 2.0);
        let eye = DVec3::new(0.0, 1.5, 0.0);
        let eps = 1e-6;

        // Aimed at the axis: hits the front surface at 999.975 m.
        let (t, steps) =
            sphere_trace(&pole, eye, DVec3::new(axis_x, 1.5, 0.0) - eye, 2000.0, eps).expect("hit");
        assert!(((t - 999.975) / 999.975).abs() < 1e-6, "t = {t}");
        assert!(steps < 10, "steps = {steps}");

        // Aimed 2 cm off the axis (still within the 2.5 cm radius): hits.
        let tgt = DVec3::new(axis_x, 1.5, 0.02);
        let d = (tgt - eye).normalize();
        let (t, _) = sphere_trace(&pole, eye, d, 2000.0, eps).expect("off-centre hit");
        let exact = ray_cylinder(eye, d, DVec3::new(axis_x, 2.0, 0.0), 0.025, 2.0)
            .unwrap()
            .0;
        assert!(((t - exact) / exact).abs() < 1e-6, "t = {t}, exact {exact}");

        // Passing 3 cm beside the surface (5.5 cm from the axis): misses.
        let beside = DVec3::new(axis_x, 1.5, 0.025 + 0.03);
        assert_eq!(sphere_trace(&pole, eye, beside - eye, 2000.0, eps), None);
        // Even 3 cm from the axis (5 mm beside the surface): misses.
        let beside = DVec3::new(axis_x, 1.5, 0.03);
        assert_eq!(sphere_trace(&pole, eye, beside - eye, 2000.0, eps), None);
        // Passing 3 cm above its top: misses.
        let above = DVec3::new(axis_x, 4.03, 0.0);
        assert_eq!(sphere_trace(&pole, eye, above - eye, 2000.0, eps), None);
    }

    #[test]
    fn pole_in_scene_is_the_nearest_object_at_the_hit() {
        let objects = vec![
            SceneObject {
                name: Some("ground".into()),
                albedo: [0.3, 0.25, 0.2],
                shape: Sdf::plane(DVec3::Y, 0.0),
            },
            SceneObject {
                name: Some("pole".into()),
                albedo: [0.8, 0.8, 0.8],
                shape: Sdf::cylinder(DVec3::new(1000.0, 2.0, 0.0), 0.025, 2.0),
            },
        ];
        validate_objects(&objects, "objects").unwrap();
        let eye = DVec3::new(0.0, 1.5, 0.0);
        let dir = DVec3::X;
        let (t, _) = sphere_trace(objects.as_slice(), eye, dir, 2000.0, 1e-6).expect("hit");
        let (d, idx) = nearest_object(&objects, eye + dir * t);
        assert_eq!(idx, Some(1));
        assert!(d < 1e-6);
        // Looking down hits the ground (index 0).
        let down = DVec3::new(1.0, -1.0, 0.0);
        let (t, _) = sphere_trace(objects.as_slice(), eye, down, 2000.0, 1e-9).expect("hit");
        assert!(close(t, 1.5 * 2f64.sqrt(), 1e-8));
        assert_eq!(
            nearest_object(&objects, eye + down.normalize() * t).1,
            Some(0)
        );
        assert_eq!(nearest_object(&[], eye), (f64::INFINITY, None));
    }

    // ---- combinators never overestimate ------------------------------------

    /// Looks for a point strictly inside the ball of radius |f(p)| around `p`
    /// whose inside/outside status differs from `p`'s (i.e. a surface
    /// crossing closer than claimed), or a wrong sign at `p`.
    fn find_overestimate(
        f: &dyn Fn(DVec3) -> f64,
        inside: &dyn Fn(DVec3) -> bool,
        p: DVec3,
        rng: &mut Rng,
        samples: usize,
    ) -> Option<String> {
        let d = f(p);
        let p_in = inside(p);
        if d.abs() > 1e-9 && (d < 0.0) != p_in {
            return Some(format!("wrong sign at {p}: d = {d}, inside = {p_in}"));
        }
        let r = d.abs() * (1.0 - 1e-9);
        if r < 1e-6 {
            return None;
        }
        for i in 0..samples {
            let dir = rng.unit_vector();
            // half on the ball's boundary, half in its volume
            let rad = if i % 2 == 0 {
                r
            } else {
                r * rng.uniform().cbrt()
            };
            let q = p + dir * rad;
            if inside(q) != p_in {
                return Some(format!(
                    "at p = {p}, d = {d} but {q} (distance {}) is on the other side",
                    (q - p).length()
                ));
            }
        }
        None
    }

    fn inside_sphere(p: DVec3, c: DVec3, r: f64) -> bool {
        (p - c).length() < r
    }
    fn inside_box(p: DVec3, c: DVec3, he: DVec3) -> bool {
        let q = (p - c).abs();
        q.x < he.x && q.y < he.y && q.z < he.z
    }
    fn inside_capsule(p: DVec3, a: DVec3, b: DVec3, r: f64) -> bool {
        segment_distance(p, a, b) < r
    }

    fn smin_ref(a: f64, b: f64, k: f64) -> f64 {
        // reference: mix form of the quadratic smooth minimum
        let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
        b * (1.0 - h) + a * h - k * h * (1.0 - h)
    }

    #[derive(Debug, Clone)]
    struct Trio {
        sc: DVec3,
        sr: f64,
        bc: DVec3,
        bh: DVec3,
        ca: DVec3,
        cb: DVec3,
        cr: f64,
    }

    fn trio() -> impl Strategy<Value = Trio> {
        (
            v3(-1.5, 1.5),
            0.3f64..1.5,
            v3(-1.5, 1.5),
            v3(0.2, 1.2),
            v3(-1.5, 1.5),
            v3(-1.5, 1.5),
            0.1f64..0.8,
        )
            .prop_map(|(sc, sr, bc, bh, ca, cb, cr)| Trio {
                sc,
                sr,
                bc,
                bh,
                ca,
                cb,
                cr,
            })
    }

    impl Trio {
        fn shapes(&self) -> Vec<Sdf> {
            vec![
                Sdf::sphere(self.sc, self.sr),
                Sdf::cuboid(self.bc, self.bh),
                Sdf::capsule(self.ca, self.cb, self.cr),
            ]
        }
        fn inside(&self, p: DVec3) -> [bool; 3] {
            [
                inside_sphere(p, self.sc, self.sr),
                inside_box(p, self.bc, self.bh),
                inside_capsule(p, self.ca, self.cb, self.cr),
            ]
        }
        fn exact(&self, p: DVec3) -> [f64; 3] {
            [
                (p - self.sc).length() - self.sr,
                box_exact(p, self.bc, self.bh),
                segment_distance(p, self.ca, self.cb) - self.cr,
            ]
        }
    }

    const SAMPLES: usize = 600;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn union_never_overestimates(t in trio(), p in v3(-4.0, 4.0), seed in any::<u64>()) {
            let s = Sdf::union(t.shapes());
            let inside = |q: DVec3| t.inside(q).iter().any(|&b| b);
            let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
            prop_assert!(bad.is_none(), "{}", bad.unwrap());
        }

        #[test]
        fn intersection_never_overestimates(t in trio(), p in v3(-4.0, 4.0), seed in any::<u64>()) {
            let s = Sdf::intersection(t.shapes());
            let inside = |q: DVec3| t.inside(q).iter().all(|&b| b);
            let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
            prop_assert!(bad.is_none(), "{}", bad.unwrap());
        }

        #[test]
        fn difference_never_overestimates(t in trio(), p in v3(-4.0, 4.0), seed in any::<u64>()) {
            let [a, b, c] = <[Sdf; 3]>::try_from(t.shapes()).unwrap();
            // (sphere ∪ box) − capsule
            let s = Sdf::difference(Sdf::union(vec![a, b]), c);
            let inside = |q: DVec3| {
                let i = t.inside(q);
                (i[0] || i[1]) && !i[2]
            };
            let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
            prop_assert!(bad.is_none(), "{}", bad.unwrap());
        }

        #[test]
        fn smooth_union_never_overestimates(
            t in trio(), k in 0.05f64..1.5, p in v3(-4.0, 4.0), seed in any::<u64>()
        ) {
            let s = Sdf::smooth_union(t.shapes(), k);
            // The surface is by definition the zero set of the smooth minimum
            // of the exact child distances (reference implementation).
            let field = |q: DVec3| {
                let e = t.exact(q);
                smin_ref(smin_ref(e[0], e[1], k), e[2], k)
            };
            prop_assert!(close(s.distance(p), field(p), 1e-9));
            let inside = |q: DVec3| field(q) < 0.0;
            let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
            prop_assert!(bad.is_none(), "{}", bad.unwrap());
            // never above the plain union, never more than 2·k/4 below it
            let m = t.exact(p).into_iter().fold(f64::INFINITY, f64::min);
            prop_assert!(s.distance(p) <= m + 1e-12);
            prop_assert!(s.distance(p) >= m - 0.5 * k - 1e-12);
        }

        #[test]
        fn transforms_never_overestimate(
            t in trio(), off in v3(-2.0, 2.0), axis in v3(-1.0, 1.0), deg in -360.0f64..360.0,
            factor in 0.2f64..5.0, p in v3(-8.0, 8.0), seed in any::<u64>()
        ) {
            prop_assume!(axis.length() > 0.05);
            let base = Sdf::difference(
                Sdf::union(t.shapes()[..2].to_vec()),
                t.shapes()[2].clone(),
            );
            let base_inside = |q: DVec3| {
                let i = t.inside(q);
                (i[0] || i[1]) && !i[2]
            };
            let s = Sdf::scale(factor, Sdf::rotate(axis, deg, Sdf::translate(off, base)));
            prop_assert!(s.validate("").is_ok());
            // independent inverse: undo scale, undo rotation via a quaternion, undo offset
            let undo = DQuat::from_axis_angle(axis.normalize(), -deg.to_radians());
            let inside = |q: DVec3| base_inside(undo * (q / factor) - off);
            let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
            prop_assert!(bad.is_none(), "{}", bad.unwrap());
        }

        #[test]
        fn combinators_are_one_lipschitz(
            t in trio(), k in 0.05f64..1.5, axis in v3(-1.0, 1.0), deg in -180.0f64..180.0,
            factor in 0.2f64..5.0, p in v3(-5.0, 5.0), q in v3(-5.0, 5.0)
        ) {
            prop_assume!(axis.length() > 0.05);
            let [a, b, c] = <[Sdf; 3]>::try_from(t.shapes()).unwrap();
            let shapes = [
                Sdf::union(vec![a.clone(), b.clone(), c.clone()]),
                Sdf::intersection(vec![a.clone(), b.clone(), c.clone()]),
                Sdf::difference(a.clone(), b.clone()),
                Sdf::smooth_union(vec![a.clone(), b.clone(), c.clone()], k),
                Sdf::translate(axis, c.clone()),
                Sdf::rotate(axis, deg, b.clone()),
                Sdf::scale(factor, Sdf::smooth_union(vec![a, b, c], k)),
            ];
            for s in &shapes {
                let (dp, dq) = (s.distance(p), s.distance(q));
                prop_assert!((dp - dq).abs() <= (p - q).length() * (1.0 + 1e-9) + 1e-12);
            }
        }
    }

    #[test]
    fn overestimate_checker_can_fail() {
        // Negative control: the checker must catch a field that claims 1.5x
        // the true union distance.
        let t = Trio {
            sc: DVec3::new(-1.0, 0.0, 0.0),
            sr: 1.0,
            bc: DVec3::new(1.0, 0.5, 0.0),
            bh: DVec3::new(0.5, 0.7, 0.9),
            ca: DVec3::new(0.0, -1.0, -1.0),
            cb: DVec3::new(0.5, -1.0, 1.0),
            cr: 0.3,
        };
        let s = Sdf::union(t.shapes());
        let inside = |q: DVec3| t.inside(q).iter().any(|&b| b);
        let cheat = |q: DVec3| 1.5 * s.distance(q);
        let mut rng = Rng(1);
        let mut caught = 0;
        for _ in 0..50 {
            let p = rng.unit_vector() * 4.0;
            if find_overestimate(&cheat, &inside, p, &mut rng, SAMPLES).is_some() {
                caught += 1;
            }
            assert!(find_overestimate(&|q| s.distance(q), &inside, p, &mut rng, SAMPLES).is_none());
        }
        assert!(caught >= 45, "caught only {caught}/50");
    }

    #[test]
    fn union_of_exact_is_exact_outside() {
        // Outside everything, min of exact distances is the exact distance.
        let a = Sdf::sphere(DVec3::ZERO, 1.0);
        let b = Sdf::cuboid(DVec3::new(5.0, 0.0, 0.0), DVec3::splat(1.0));
        let u = Sdf::union(vec![a, b]);
        assert!(close(u.distance(DVec3::new(2.5, 0.0, 0.0)), 1.5, 1e-12));
        assert!(close(u.distance(DVec3::new(-3.0, 0.0, 0.0)), 2.0, 1e-12));
    }

    #[test]
    fn transforms_move_surfaces_where_expected() {
        let s = Sdf::cuboid(DVec3::ZERO, DVec3::new(2.0, 0.5, 0.5));
        // rotate 90° about z: the long axis now points along y
        let r = Sdf::rotate(DVec3::Z, 90.0, s.clone());
        assert!(close(r.distance(DVec3::new(0.0, 3.0, 0.0)), 1.0, 1e-12));
        assert!(close(r.distance(DVec3::new(3.0, 0.0, 0.0)), 2.5, 1e-12));
        let t = Sdf::translate(DVec3::new(10.0, 0.0, 0.0), s.clone());
        assert!(close(t.distance(DVec3::new(13.0, 0.0, 0.0)), 1.0, 1e-12));
        let k = Sdf::scale(3.0, s);
        assert!(close(k.distance(DVec3::new(9.0, 0.0, 0.0)), 3.0, 1e-12));
        assert!(close(k.distance(DVec3::ZERO), -1.5, 1e-12));
    }

    // ---- bounding spheres --------------------------------------------------

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        #[test]
        fn bounding_sphere_contains_solid(
            t in trio(), k in 0.05f64..1.5, off in v3(-3.0, 3.0), axis in v3(-1.0, 1.0),
            deg in -180.0f64..180.0, factor in 0.2f64..5.0, seed in any::<u64>()
        ) {
            prop_assume!(axis.length() > 0.05);
            let [a, b, c] = <[Sdf; 3]>::try_from(t.shapes()).unwrap();
            let shapes = [
                a.clone(),
                b.clone(),
                c.clone(),
                Sdf::torus(off, 1.0, 0.4),
                Sdf::cylinder(off, 0.3, 2.0),
                Sdf::rounded_box(off, DVec3::new(1.0, 0.3, 0.5), 0.2),
                Sdf::union(vec![a.clone(), b.clone(), c.clone()]),
                Sdf::intersection(vec![a.clone(), b.clone()]),
                Sdf::difference(b.clone(), a.clone()),
                Sdf::smooth_union(vec![a.clone(), b.clone(), c.clone()], k),
                Sdf::scale(factor, Sdf::rotate(axis, deg, Sdf::translate(off,
                    Sdf::smooth_union(vec![a, b, c], k)))),
            ];
            let mut rng = Rng(seed);
            for s in &shapes {
                let (center, radius) = s.bounding_sphere();
                prop_assert!(radius.is_finite());
                for _ in 0..200 {
                    let p = center + rng.unit_vector() * radius * (1.0 + 1e-6 + 3.0 * rng.uniform());
                    let d = s.distance(p);
                    prop_assert!(d > 0.0, "{s:?}: d = {d} outside bounding sphere");
                }
            }
        }
    }

    #[test]
    fn bounding_sphere_of_primitives_is_tight_lower_bound() {
        // For exact primitives, d(p) >= |p - c| - r.
        let shapes = [
            Sdf::sphere(DVec3::new(1.0, 2.0, 3.0), 0.5),
            Sdf::cuboid(DVec3::ONE, DVec3::new(1.0, 2.0, 3.0)),
            Sdf::capsule(DVec3::ZERO, DVec3::new(0.0, 4.0, 0.0), 0.5),
            Sdf::cylinder(DVec3::ZERO, 1.0, 3.0),
        ];
        let mut rng = Rng(3);
        for s in &shapes {
            let (c, r) = s.bounding_sphere();
            for _ in 0..1000 {
                let p = c + rng.unit_vector() * 10.0 * rng.uniform();
                assert!(s.distance(p) >= (p - c).length() - r - 1e-12);
            }
        }
        let (_, r) =
            Sdf::union(vec![Sdf::plane(DVec3::Y, 0.0), shapes[0].clone()]).bounding_sphere();
        assert_eq!(r, f64::INFINITY);
        let (_, r) =
            Sdf::intersection(vec![Sdf::plane(DVec3::Y, 0.0), shapes[0].clone()]).bounding_sphere();
        assert_eq!(r, 0.5);
    }

    // ---- JSON ----------------------------------------------------------------

    /// The example from the module documentation.
    const DOC_EXAMPLE: &str = r#"[
      { "name": "ground", "albedo": [0.3, 0.25, 0.2],
        "shape": { "type": "plane", "normal": [0, 1, 0], "offset": 0 } },
      { "name": "pole", "albedo": [0.8, 0.8, 0.8],
        "shape": { "type": "cylinder", "center": [1000, 2, 0],
                   "radius": 0.025, "half_height": 2 } },
      { "name": "sign", "albedo": [0.9, 0.1, 0.1],
        "shape": { "type": "translate", "offset": [1000, 4.5, 0],
                   "child": { "type": "rotate", "axis": [0, 1, 0], "degrees": 30,
                              "child": { "type": "smooth_union", "k": 0.05,
                                         "children": [
                                           { "type": "rounded_box", "center": [0, 0, 0],
                                             "half_extents": [0.5, 0.3, 0.02], "radius": 0.01 },
                                           { "type": "capsule", "a": [0, -0.5, 0],
                                             "b": [0, 0, 0], "radius": 0.025 } ] } } } }
    ]"#;

    fn nested_scene() -> Vec<SceneObject> {
        let board = Sdf::smooth_union(
            vec![
                Sdf::rounded_box(DVec3::ZERO, DVec3::new(0.5, 0.3, 0.02), 0.01),
                Sdf::capsule(DVec3::new(0.0, -0.5, 0.0), DVec3::ZERO, 0.025),
            ],
            0.05,
        );
        vec![
            SceneObject {
                name: Some("ground".into()),
                albedo: [0.3, 0.25, 0.2],
                shape: Sdf::plane(DVec3::new(0.0, 1.0, 0.0), 0.0),
            },
            SceneObject {
                name: Some("pole".into()),
                albedo: [0.8, 0.8, 0.8],
                shape: Sdf::cylinder(DVec3::new(1000.0, 2.0, 0.0), 0.025, 2.0),
            },
            SceneObject {
                name: Some("sign".into()),
                albedo: [0.9, 0.1, 0.1],
                shape: Sdf::translate(
                    DVec3::new(1000.0, 4.5, 0.0),
                    Sdf::rotate(DVec3::Y, 30.0, board),
                ),
            },
        ]
    }

    #[test]
    fn doc_example_parses_and_matches_builders() {
        let parsed: Vec<SceneObject> = serde_json::from_str(DOC_EXAMPLE).unwrap();
        validate_objects(&parsed, "objects").unwrap();
        assert_eq!(parsed, nested_scene());
    }

    #[test]
    fn json_round_trip_of_nested_scene() {
        let mut scene = nested_scene();
        // Every variant, nested, with awkward numbers.
        scene.push(SceneObject {
            name: None,
            albedo: [0.1, 0.2, 0.3],
            shape: Sdf::scale(
                1.7,
                Sdf::difference(
                    Sdf::intersection(vec![
                        Sdf::sphere(DVec3::new(0.1, -0.2, 1.0 / 3.0), 2.0f64.sqrt()),
                        Sdf::cuboid(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0)),
                        Sdf::torus(DVec3::Y, 1.0, 0.25),
                    ]),
                    Sdf::union(vec![
                        Sdf::cylinder(DVec3::ZERO, 0.3, 5.0),
                        Sdf::plane(DVec3::new(1.0, 1.0, 0.0), -0.7),
                        Sdf::rotate(DVec3::new(1.0, 2.0, 3.0), 17.3, Sdf::sphere(DVec3::X, 0.1)),
                    ]),
                ),
            ),
        });
        validate_objects(&scene, "objects").unwrap();
        let json = serde_json::to_string_pretty(&scene).unwrap();
        let back: Vec<SceneObject> = serde_json::from_str(&json).unwrap();
        assert_eq!(back, scene);
        // and the tags are what the docs say
        for tag in [
            "\"plane\"",
            "\"cylinder\"",
            "\"translate\"",
            "\"rotate\"",
            "\"smooth_union\"",
            "\"rounded_box\"",
            "\"capsule\"",
            "\"scale\"",
            "\"difference\"",
            "\"intersection\"",
            "\"sphere\"",
            "\"box\"",
            "\"torus\"",
            "\"union\"",
        ] {
            assert!(json.contains(tag), "missing {tag} in {json}");
        }
        // a value re-serialized is identical text
        assert_eq!(serde_json::to_string_pretty(&back).unwrap(), json);
        // the plane keeps the normal as written, normalises for evaluation
        let p: Sdf =
            serde_json::from_str(r#"{"type":"plane","normal":[0,2,0],"offset":1}"#).unwrap();
        assert!(close(p.distance(DVec3::new(5.0, 3.0, 1.0)), 2.0, 1e-15));
        assert!(serde_json::to_string(&p).unwrap().contains("[0.0,2.0,0.0]"));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        #[test]
        fn json_round_trip_random_numbers(
            c in v3(-1e4, 1e4), r in 1e-3f64..1e3, axis in v3(-1.0, 1.0), deg in -720.0f64..720.0,
            f in 1e-3f64..1e3, k in 1e-3f64..1.0
        ) {
            let s = Sdf::scale(f, Sdf::rotate(axis, deg, Sdf::smooth_union(vec![
                Sdf::sphere(c, r), Sdf::capsule(c, -c, r), Sdf::plane(axis, r)], k)));
            let back: Sdf = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
            prop_assert_eq!(back, s);
        }
    }

    fn parse_err(json: &str) -> String {
        match serde_json::from_str::<Vec<SceneObject>>(json) {
            Ok(v) => panic!("expected an error, parsed {v:?}"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn unknown_fields_are_rejected_everywhere() {
        let cases = [
            // struct variant (enum-level deny_unknown_fields)
            (
                r#"[{"albedo":[0,0,0],"shape":{"type":"sphere","center":[0,0,0],"radius":1,"colour":3}}]"#,
                "colour",
            ),
            // nested inside a combinator
            (
                r#"[{"albedo":[0,0,0],"shape":{"type":"union","children":[
                    {"type":"box","center":[0,0,0],"half_extents":[1,1,1]},
                    {"type":"cylinder","center":[0,0,0],"radius":1,"half_height":1,"height":2}]}}]"#,
                "height",
            ),
            // newtype variants (spec struct's deny_unknown_fields)
            (
                r#"[{"albedo":[0,0,0],"shape":{"type":"plane","normal":[0,1,0],"offset":0,"d":1}}]"#,
                "`d`",
            ),
            (
                r#"[{"albedo":[0,0,0],"shape":{"type":"rotate","axis":[0,1,0],"degrees":3,"radians":1,
                    "child":{"type":"sphere","center":[0,0,0],"radius":1}}}]"#,
                "radians",
            ),
            (
                r#"[{"albedo":[0,0,0],"shape":{"type":"scale","factor":2,"factors":[1,2,3],
                    "child":{"type":"sphere","center":[0,0,0],"radius":1}}}]"#,
                "factors",
            ),
            // a misspelt field in the deepest level
            (
                r#"[{"albedo":[0,0,0],"shape":{"type":"translate","offset":[0,0,0],
                    "child":{"type":"smooth_union","k":0.1,"children":[
                    {"type":"torus","center":[0,0,0],"major_radius":1,"minor_radus":0.1}]}}}]"#,
                "minor_radus",
            ),
            // the scene object itself
            (
                r#"[{"albedo":[0,0,0],"colour":[1,1,1],"shape":{"type":"sphere","center":[0,0,0],"radius":1}}]"#,
                "colour",
            ),
        ];
        for (json, name) in cases {
            let e = parse_err(json);
            assert!(e.contains("unknown field"), "{e}");
            assert!(e.contains(name), "message {e:?} lacks {name}");
        }
    }

    #[test]
    fn unknown_or_missing_type_is_rejected() {
        let e = parse_err(r#"[{"albedo":[0,0,0],"shape":{"type":"blob","radius":1}}]"#);
        assert!(e.contains("unknown variant") && e.contains("blob"), "{e}");
        let e = parse_err(r#"[{"albedo":[0,0,0],"shape":{"center":[0,0,0],"radius":1}}]"#);
        assert!(e.contains("missing field `type`"), "{e}");
        let e = parse_err(r#"[{"albedo":[0,0,0],"shape":{"type":"sphere","center":[0,0,0]}}]"#);
        assert!(e.contains("missing field `radius`"), "{e}");
        // tags are snake_case only
        let e = parse_err(
            r#"[{"albedo":[0,0,0],"shape":{"type":"RoundedBox","center":[0,0,0],"half_extents":[1,1,1],"radius":0.1}}]"#,
        );
        assert!(e.contains("RoundedBox"), "{e}");
    }

    // ---- validation ------------------------------------------------------------

    #[test]
    fn validation_names_the_path() {
        let json = r#"[
          {"albedo":[0,0,0],"shape":{"type":"plane","normal":[0,1,0],"offset":0}},
          {"albedo":[0,0,0],"shape":{"type":"sphere","center":[0,0,0],"radius":1}},
          {"albedo":[0,0,0],"shape":{"type":"union","children":[
              {"type":"sphere","center":[0,0,0],"radius":1},
              {"type":"sphere","center":[0,0,0],"radius":-1}]}}
        ]"#;
        let objects: Vec<SceneObject> = serde_json::from_str(json).unwrap();
        assert_eq!(
            validate_objects(&objects, "objects").unwrap_err(),
            "objects[2].shape.children[1].radius: must be > 0, got -1"
        );
    }

    #[test]
    fn validation_rejects_each_bad_parameter() {
        let ok = || Sdf::sphere(DVec3::ZERO, 1.0);
        let cases: Vec<(Sdf, &str)> = vec![
            (
                Sdf::sphere(DVec3::ZERO, 0.0),
                "s.radius: must be > 0, got 0",
            ),
            (
                Sdf::sphere(DVec3::new(0.0, f64::NAN, 0.0), 1.0),
                "s.center[1]: must be finite, got NaN",
            ),
            (
                Sdf::sphere(DVec3::ZERO, f64::INFINITY),
                "s.radius: must be finite, got inf",
            ),
            (
                Sdf::cuboid(DVec3::ZERO, DVec3::new(1.0, 1.0, -2.0)),
                "s.half_extents[2]: must be > 0, got -2",
            ),
            (
                Sdf::rounded_box(DVec3::ZERO, DVec3::new(1.0, 0.5, 1.0), 0.0),
                "s.radius: must be > 0, got 0",
            ),
            (
                Sdf::rounded_box(DVec3::ZERO, DVec3::new(1.0, 0.5, 1.0), 0.75),
                "s.radius: must be <= the smallest half extent (0.5), got 0.75",
            ),
            (
                Sdf::plane(DVec3::ZERO, 1.0),
                "s.normal: must be a non-zero vector, got [0, 0, 0]",
            ),
            (
                Sdf::plane(DVec3::new(f64::INFINITY, 0.0, 0.0), 1.0),
                "s.normal[0]: must be finite, got inf",
            ),
            (
                Sdf::plane(DVec3::Y, f64::NAN),
                "s.offset: must be finite, got NaN",
            ),
            (
                Sdf::torus(DVec3::ZERO, -1.0, 0.5),
                "s.major_radius: must be > 0, got -1",
            ),
            (
                Sdf::torus(DVec3::ZERO, 1.0, 0.0),
                "s.minor_radius: must be > 0, got 0",
            ),
            (
                Sdf::torus(DVec3::ZERO, 1.0, 1.5),
                "s.minor_radius: must be <= major_radius (1), got 1.5",
            ),
            (
                Sdf::cylinder(DVec3::ZERO, 1.0, 0.0),
                "s.half_height: must be > 0, got 0",
            ),
            (
                Sdf::cylinder(DVec3::ZERO, -0.1, 1.0),
                "s.radius: must be > 0, got -0.1",
            ),
            (
                Sdf::capsule(DVec3::ZERO, DVec3::new(0.0, 0.0, f64::NAN), 1.0),
                "s.b[2]: must be finite, got NaN",
            ),
            (
                Sdf::capsule(DVec3::ZERO, DVec3::X, -3.0),
                "s.radius: must be > 0, got -3",
            ),
            (
                Sdf::union(vec![]),
                "s.children: must contain at least one shape",
            ),
            (
                Sdf::intersection(vec![]),
                "s.children: must contain at least one shape",
            ),
            (
                Sdf::smooth_union(vec![], 0.1),
                "s.children: must contain at least one shape",
            ),
            (
                Sdf::smooth_union(vec![ok()], 0.0),
                "s.k: must be > 0, got 0",
            ),
            (
                Sdf::smooth_union(vec![ok()], -0.5),
                "s.k: must be > 0, got -0.5",
            ),
            (
                Sdf::difference(ok(), Sdf::sphere(DVec3::ZERO, -1.0)),
                "s.subtract.radius: must be > 0, got -1",
            ),
            (
                Sdf::difference(Sdf::union(vec![]), ok()),
                "s.base.children: must contain at least one shape",
            ),
            (
                Sdf::translate(DVec3::new(f64::NAN, 0.0, 0.0), ok()),
                "s.offset[0]: must be finite, got NaN",
            ),
            (
                Sdf::translate(DVec3::ZERO, Sdf::sphere(DVec3::ZERO, 0.0)),
                "s.child.radius: must be > 0, got 0",
            ),
            (
                Sdf::rotate(DVec3::ZERO, 10.0, ok()),
                "s.axis: must be a non-zero vector, got [0, 0, 0]",
            ),
            (
                Sdf::rotate(DVec3::Y, f64::NAN, ok()),
                "s.degrees: must be finite, got NaN",
            ),
            (Sdf::scale(0.0, ok()), "s.factor: must be > 0, got 0"),
            (Sdf::scale(-2.0, ok()), "s.factor: must be > 0, got -2"),
            (
                Sdf::scale(
                    2.0,
                    Sdf::rotate(
                        DVec3::X,
                        5.0,
                        Sdf::union(vec![ok(), Sdf::smooth_union(vec![ok()], -1.0)]),
                    ),
                ),
                "s.child.child.children[1].k: must be > 0, got -1",
            ),
        ];
        for (s, msg) in cases {
            assert_eq!(s.validate("s").unwrap_err(), msg);
        }
        // empty prefix: no leading dot
        assert_eq!(
            Sdf::sphere(DVec3::ZERO, -1.0).validate("").unwrap_err(),
            "radius: must be > 0, got -1"
        );
        assert!(nested_scene()[2].shape.validate("").is_ok());
    }

    #[test]
    fn validation_rejects_bad_albedo() {
        let mut o = nested_scene().remove(1);
        o.albedo = [0.5, 1.5, 0.0];
        assert_eq!(
            o.validate("objects[1]").unwrap_err(),
            "objects[1].albedo[1]: must be in [0, 1], got 1.5"
        );
        o.albedo = [-0.1, 0.5, 0.0];
        assert_eq!(
            o.validate("o").unwrap_err(),
            "o.albedo[0]: must be in [0, 1], got -0.1"
        );
        o.albedo = [0.1, 0.5, f64::NAN];
        assert_eq!(
            o.validate("o").unwrap_err(),
            "o.albedo[2]: must be finite, got NaN"
        );
        o.albedo = [0.0, 1.0, 0.5];
        assert!(o.validate("o").is_ok());
    }
}
