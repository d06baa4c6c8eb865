//! Bounding spheres and boxes, for culling.

use glam::{DVec2, DVec3};

use super::Sdf;

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

impl Sdf {
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

    /// An axis-aligned box `(min, max)` containing the whole solid: outside
    /// it the distance is positive. Tighter than the bounding sphere for
    /// long or flat shapes (a car's body, a pole), and exact for boxes,
    /// cylinders and spheres, and their unions, translated or turned by
    /// quarter turns. Infinite for unbounded shapes (planes, and unions
    /// containing them).
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        let around = |c: DVec3, h: DVec3| (c - h, c + h);
        match self {
            Sdf::Sphere { center, radius } => around(*center, DVec3::splat(*radius)),
            Sdf::Box {
                center,
                half_extents,
            }
            | Sdf::RoundedBox {
                center,
                half_extents,
                ..
            } => around(*center, *half_extents),
            Sdf::Plane(_) => (DVec3::NEG_INFINITY, DVec3::INFINITY),
            Sdf::Torus {
                center,
                major_radius,
                minor_radius,
            } => {
                let r = major_radius + minor_radius;
                around(*center, DVec3::new(r, *minor_radius, r))
            }
            Sdf::Cylinder {
                center,
                radius,
                half_height,
            } => around(*center, DVec3::new(*radius, *half_height, *radius)),
            Sdf::Capsule { a, b, radius } => (
                a.min(*b) - DVec3::splat(*radius),
                a.max(*b) + DVec3::splat(*radius),
            ),
            Sdf::Union { children } => children
                .iter()
                .map(Sdf::bounding_box)
                .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
                .unwrap_or((DVec3::ZERO, DVec3::ZERO)),
            // The solid lies in every child's box. Disjoint boxes give an
            // inverted (empty) box: no point is inside it, and outside a
            // child's box the distance is positive.
            Sdf::Intersection { children } => children
                .iter()
                .map(Sdf::bounding_box)
                .reduce(|a, b| (a.0.max(b.0), a.1.min(b.1)))
                .unwrap_or((DVec3::NEG_INFINITY, DVec3::INFINITY)),
            Sdf::Difference { base, .. } => base.bounding_box(),
            Sdf::SmoothUnion { children, k } => {
                let (lo, hi) = children
                    .iter()
                    .map(Sdf::bounding_box)
                    .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
                    .unwrap_or((DVec3::ZERO, DVec3::ZERO));
                // Each fold step lowers the field by at most k/4 (as for
                // the sphere).
                let grow = children.len().saturating_sub(1) as f64 * k * 0.25;
                (lo - DVec3::splat(grow), hi + DVec3::splat(grow))
            }
            Sdf::Translate { offset, child } => {
                let (lo, hi) = child.bounding_box();
                (lo + *offset, hi + *offset)
            }
            Sdf::Rotate(rot) => {
                let (lo, hi) = rot.child.bounding_box();
                if !(lo.is_finite() && hi.is_finite()) {
                    return (DVec3::NEG_INFINITY, DVec3::INFINITY);
                }
                // The box of the turned box: centre turned, half extents
                // through |R| (each world axis collects every local one).
                let m = rot.local_to_world();
                let c = m * (0.5 * (lo + hi));
                let h = 0.5 * (hi - lo);
                let abs = glam::DMat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
                // A hair of slack for the rounding of the turn.
                let h = abs * h + DVec3::splat(1e-12 * (c.abs().max_element() + h.max_element()));
                around(c, h)
            }
            Sdf::Scale(s) => {
                let (lo, hi) = s.child.bounding_box();
                (lo * s.factor, hi * s.factor)
            }
        }
    }
}
