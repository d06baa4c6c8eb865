//! Evaluation: the signed distance of every shape, its gradient and normal.

use glam::{DVec2, DVec3};

use super::{NORMAL_RELATIVE_STEP, SceneObject, Sdf};

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

impl Sdf {
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
    ///
    /// A union under translations and rotations (a ship of boxes, a car)
    /// evaluates at the six points only the children that can be nearest
    /// there: every distance here is 1-Lipschitz, so a child farther than
    /// the nearest by more than 2h (plus rounding) at `p` is farther at every
    /// point within h of it, and leaving it out of the minimum changes no
    /// bit of the result; one evaluation at `p` finds them.
    pub fn gradient_with_step(&self, p: DVec3, h: f64) -> DVec3 {
        let dx = DVec3::new(h, 0.0, 0.0);
        let dy = DVec3::new(0.0, h, 0.0);
        let dz = DVec3::new(0.0, 0.0, h);
        let mask = self.near_children(p, h);
        let d = |q: DVec3| match mask {
            Some(m) => self.distance_among(q, m),
            None => self.distance(q),
        };
        DVec3::new(
            d(p + dx) - d(p - dx),
            d(p + dy) - d(p - dy),
            d(p + dz) - d(p - dz),
        ) / (2.0 * h)
    }

    /// For a union of 2–64 children under translations and rotations: the
    /// children (bits) that can be nearest within `h` of `p`.
    pub(super) fn near_children(&self, p: DVec3, h: f64) -> Option<u64> {
        self.union_near(p, 2, |_| h)?.1.map(|(mask, _)| mask)
    }

    /// [`Sdf::distance`] at `p` and, for a union of 3–64 children under
    /// translations and rotations (with two, a mask saves too little to pay
    /// for itself), the children (bits) that can be nearest anywhere within
    /// `reach(d)` of `p`, d being that distance, with that reach: the rule of
    /// [`Sdf::gradient_with_step`], with the ball sized by the distance
    /// found. The distance is the number [`Sdf::distance`] gives (the same
    /// children, the same minimum in the same order).
    pub fn distance_and_near(
        &self,
        p: DVec3,
        reach: impl Fn(f64) -> f64,
    ) -> (f64, Option<(u64, f64)>) {
        self.union_near(p, 3, reach)
            .unwrap_or_else(|| (self.distance(p), None))
    }

    /// For a union of `min_children`–64 children under translations and
    /// rotations (`None` for any other shape, with nothing evaluated): its
    /// distance at `p` and, when that is finite and `reach` of it is not
    /// negative, the children that can be nearest within that reach of `p`
    /// (a child farther than the nearest by more than twice the reach is
    /// farther everywhere in the ball, every distance being 1-Lipschitz),
    /// with the reach.
    fn union_near(
        &self,
        p: DVec3,
        min_children: usize,
        reach: impl Fn(f64) -> f64,
    ) -> Option<(f64, Option<(u64, f64)>)> {
        match self {
            Sdf::Translate { offset, child } => child.union_near(p - *offset, min_children, reach),
            Sdf::Rotate(r) => r
                .child
                .union_near(r.world_to_local * p, min_children, reach),
            Sdf::Union { children } if (min_children..=64).contains(&children.len()) => {
                let mut d = [0.0f64; 64];
                for (di, c) in d.iter_mut().zip(children) {
                    *di = c.distance(p);
                }
                let d = &d[..children.len()];
                let nearest = d.iter().copied().fold(f64::INFINITY, f64::min);
                let h = reach(nearest);
                if !(nearest.is_finite() && h >= 0.0) {
                    return Some((nearest, None));
                }
                // 2h by the Lipschitz bound; the rest covers rounding in the
                // distances and in the rotated points.
                let limit =
                    nearest + 2.0 * h + 1e-9 * (1.0 + nearest.abs() + p.abs().max_element());
                let mask = d
                    .iter()
                    .enumerate()
                    // NaN kept: whatever cannot be compared is not left out.
                    .filter(|(_, di)| {
                        (**di).partial_cmp(&limit) != Some(std::cmp::Ordering::Greater)
                    })
                    .fold(0u64, |m, (i, _)| m | 1 << i);
                Some((nearest, Some((mask, h))))
            }
            _ => None,
        }
    }

    /// [`Sdf::distance`] with the union that [`Sdf::distance_and_near`]
    /// (or the gradient's own search) found limited to the children of `mask`
    /// (the same operations otherwise): the same number wherever the mask
    /// was found to hold.
    pub fn distance_among(&self, p: DVec3, mask: u64) -> f64 {
        match self {
            Sdf::Translate { offset, child } => child.distance_among(p - *offset, mask),
            Sdf::Rotate(r) => r.child.distance_among(r.world_to_local * p, mask),
            Sdf::Union { children } => children
                .iter()
                .enumerate()
                .filter(|(i, _)| mask & (1 << i) != 0)
                .fold(f64::INFINITY, |m, (_, c)| m.min(c.distance(p))),
            _ => self.distance(p),
        }
    }

    /// Outward unit surface normal at (or near) `p`: the normalised
    /// [`gradient`](Self::gradient); zero where the gradient vanishes.
    pub fn normal(&self, p: DVec3) -> DVec3 {
        self.gradient(p).normalize_or_zero()
    }
}

impl SceneObject {
    /// Signed distance to this object's shape.
    pub fn distance(&self, p: DVec3) -> f64 {
        self.shape.distance(p)
    }
}
