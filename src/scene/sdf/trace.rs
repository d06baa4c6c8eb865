//! Sphere tracing of straight rays through a distance field.

use glam::DVec3;

use super::{SceneObject, Sdf};

/// Maximum number of distance evaluations [`sphere_trace`] spends on one ray.
pub const MAX_TRACE_STEPS: u32 = 4096;

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
