//! Constructors: the shape builders, and the payloads whose derived data
//! (unit normal, rotation matrix, reciprocal factor) is computed here once so
//! evaluation never recomputes it.

use glam::{DMat3, DQuat, DVec3};

use super::{Plane, Rotate, Scale, Sdf};

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
}
