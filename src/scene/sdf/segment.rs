//! Straight segments against solids, decided in closed form.
//!
//! Shadow rays are straight. Sphere-tracing one away from the surface it
//! starts on costs a distance evaluation per step, and the steps grow only
//! geometrically from the start's sub-millimetre offset: 20–30 evaluations
//! of the whole object before the ray leaves a ship's bounding sphere. The
//! primitives most scenes are built of meet a line where a quadratic or a
//! slab test says, so [`Sdf::segment_meets`] answers "does the segment
//! `o + t·d`, `t ∈ [t0, t1]`, touch the closed solid?" with a few dozen
//! flops, exactly:
//!
//! - **sphere**: the segment's point nearest the centre (the clamped
//!   projection) against the radius;
//! - **box**: the slab test, the three axes' entry and exit parameters
//!   intersected with `[t0, t1]`;
//! - **capped cylinder**: the slab test along the axis, then the nearest
//!   point of that stretch to the axis (`|q(t)|²` is a convex quadratic, so
//!   its least value over an interval is at the clamped vertex);
//! - **capsule**: the distance between the segment and the core segment
//!   (Ericson, *Real-Time Collision Detection*, §5.1.9) against the radius;
//! - **plane**: the sign of the signed distance at the two ends (it is
//!   linear along the segment);
//! - **union**: meets when a child meets; misses when every child misses;
//! - **translate, rotate, scale**: the segment moved into the child's frame
//!   (`d` is transformed with `o`, so `t` keeps its meaning).
//!
//! Where no closed form is at hand the answer is `None` and the caller
//! sphere-traces: a rounded box the segment meets only near its rounded
//! edges (outside its box: `Some(false)`; through one of the three
//! square-edged boxes it contains: `Some(true)`), a torus inside its box, an
//! intersection, difference or smooth union that no bounding test settles.
//!
//! The answer is for the exact surfaces, with no tolerance: a sphere tracer
//! declares a hit within its tolerance of a surface, so the two can differ
//! for segments that pass within that tolerance (a tenth of a millimetre in
//! the renderer) of a surface without touching it.

use glam::DVec3;

use super::Sdf;

/// Clips `[lo, hi]` to the parameters where `o + t·d` lies in the slab
/// `|x − c| ≤ h` along one axis (components `o`, `d`, `c`, `h`); `false` when
/// nothing is left.
#[inline]
fn clip_slab(o: f64, d: f64, c: f64, h: f64, lo: &mut f64, hi: &mut f64) -> bool {
    if d == 0.0 {
        return (o - c).abs() <= h;
    }
    let ta = (c - h - o) / d;
    let tb = (c + h - o) / d;
    *lo = lo.max(ta.min(tb));
    *hi = hi.min(ta.max(tb));
    *lo <= *hi
}

/// Whether `o + t·d`, `t ∈ [t0, t1]`, meets the box of centre `c` and half
/// extents `h`.
#[inline]
fn box_meets(o: DVec3, d: DVec3, t0: f64, t1: f64, c: DVec3, h: DVec3) -> bool {
    let (mut lo, mut hi) = (t0, t1);
    clip_slab(o.x, d.x, c.x, h.x, &mut lo, &mut hi)
        && clip_slab(o.y, d.y, c.y, h.y, &mut lo, &mut hi)
        && clip_slab(o.z, d.z, c.z, h.z, &mut lo, &mut hi)
}

/// The least squared distance between the segments `p1 + s·d1` and
/// `p2 + u·d2`, `s, u ∈ [0, 1]` (Ericson §5.1.9, with the degenerate
/// segments that are points).
fn segment_segment_distance_squared(p1: DVec3, d1: DVec3, p2: DVec3, d2: DVec3) -> f64 {
    let r = p1 - p2;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let f = d2.dot(r);
    let (s, u) = if a == 0.0 && e == 0.0 {
        (0.0, 0.0)
    } else if a == 0.0 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e == 0.0 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            // Parallel segments (denom 0): any s works; take 0.
            let s = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let u = (b * s + f) / e;
            if u < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if u > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s, u)
            }
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * u)).length_squared()
}

impl Sdf {
    /// Whether the straight segment `o + t·d`, `t ∈ [t0, t1]` (finite,
    /// `t0 ≤ t1`; `d` need not be a unit vector), meets the closed solid:
    /// `Some(true)` or `Some(false)` when a closed form decides it, `None`
    /// when the caller must sphere-trace: spheres, boxes, capped cylinders,
    /// capsules and planes in closed form; a rounded box by the boxes
    /// around and inside it; unions by their children; translations,
    /// rotations and scalings by moving the segment; a torus inside its box,
    /// and intersections, differences and smooth unions that no bounding
    /// test settles, are left to the caller.
    pub fn segment_meets(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<bool> {
        match self {
            Sdf::Sphere { center, radius } => {
                let a = d.length_squared();
                let t = if a > 0.0 {
                    ((*center - o).dot(d) / a).clamp(t0, t1)
                } else {
                    t0
                };
                Some((o + d * t - *center).length_squared() <= radius * radius)
            }
            Sdf::Box {
                center,
                half_extents,
            } => Some(box_meets(o, d, t0, t1, *center, *half_extents)),
            Sdf::RoundedBox {
                center,
                half_extents,
                radius,
            } => {
                if !box_meets(o, d, t0, t1, *center, *half_extents) {
                    return Some(false);
                }
                // The rounded box holds the three boxes that keep the full
                // extent along one axis and lose the rounding along the
                // other two.
                let inner = *half_extents - DVec3::splat(*radius);
                let through = [DVec3::X, DVec3::Y, DVec3::Z].iter().any(|&axis| {
                    let h = inner + axis * *radius;
                    box_meets(o, d, t0, t1, *center, h)
                });
                if through { Some(true) } else { None }
            }
            Sdf::Plane(plane) => {
                let n = plane.unit_normal();
                let f0 = n.dot(o + d * t0) - plane.offset();
                let f1 = n.dot(o + d * t1) - plane.offset();
                Some(f0.min(f1) <= 0.0)
            }
            Sdf::Torus {
                center,
                major_radius,
                minor_radius,
            } => {
                let h = DVec3::new(
                    major_radius + minor_radius,
                    *minor_radius,
                    major_radius + minor_radius,
                );
                if box_meets(o, d, t0, t1, *center, h) {
                    None
                } else {
                    Some(false)
                }
            }
            Sdf::Cylinder {
                center,
                radius,
                half_height,
            } => {
                let (mut lo, mut hi) = (t0, t1);
                if !clip_slab(o.y, d.y, center.y, *half_height, &mut lo, &mut hi) {
                    return Some(false);
                }
                let (qx, qz) = (o.x - center.x, o.z - center.z);
                let a = d.x * d.x + d.z * d.z;
                let t = if a > 0.0 {
                    (-(qx * d.x + qz * d.z) / a).clamp(lo, hi)
                } else {
                    lo
                };
                let (x, z) = (qx + d.x * t, qz + d.z * t);
                Some(x * x + z * z <= radius * radius)
            }
            Sdf::Capsule { a, b, radius } => {
                let d2 = segment_segment_distance_squared(o + d * t0, d * (t1 - t0), *a, *b - *a);
                Some(d2 <= radius * radius)
            }
            Sdf::Union { children } => {
                let mut all_miss = true;
                for c in children {
                    match c.segment_meets(o, d, t0, t1) {
                        Some(true) => return Some(true),
                        Some(false) => {}
                        None => all_miss = false,
                    }
                }
                if all_miss { Some(false) } else { None }
            }
            Sdf::Intersection { children } => {
                if children
                    .iter()
                    .any(|c| c.segment_meets(o, d, t0, t1) == Some(false))
                {
                    Some(false)
                } else {
                    None
                }
            }
            Sdf::Difference { base, .. } => match base.segment_meets(o, d, t0, t1) {
                Some(false) => Some(false),
                _ => None,
            },
            Sdf::SmoothUnion { .. } => None,
            Sdf::Translate { offset, child } => child.segment_meets(o - *offset, d, t0, t1),
            Sdf::Rotate(r) => {
                let m = r.world_to_local;
                r.child.segment_meets(m * o, m * d, t0, t1)
            }
            Sdf::Scale(s) => s
                .child
                .segment_meets(o * s.inv_factor, d * s.inv_factor, t0, t1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::SplitMix64;

    struct Rng(SplitMix64);
    impl Rng {
        fn u(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.0.next_f64()
        }
        fn v(&mut self, lo: f64, hi: f64) -> DVec3 {
            DVec3::new(self.u(lo, hi), self.u(lo, hi), self.u(lo, hi))
        }
    }

    /// A random primitive; `closed` picks only the kinds every segment is
    /// decided for in closed form.
    fn primitive(g: &mut Rng, closed: bool) -> Sdf {
        let c = g.v(-2.0, 2.0);
        let kinds = if closed { 4 } else { 6 };
        match (g.u(0.0, kinds as f64) as usize).min(kinds - 1) {
            0 => Sdf::sphere(c, g.u(0.2, 2.0)),
            1 => Sdf::cuboid(c, g.v(0.1, 2.0)),
            2 => Sdf::cylinder(c, g.u(0.1, 1.5), g.u(0.1, 2.0)),
            3 => Sdf::capsule(c, g.v(-2.0, 2.0), g.u(0.1, 1.0)),
            4 => {
                let h = g.v(0.3, 2.0);
                Sdf::rounded_box(c, h, g.u(0.05, 1.0) * h.min_element())
            }
            _ => {
                let major = g.u(0.5, 2.0);
                Sdf::torus(c, major, g.u(0.1, 1.0) * major)
            }
        }
    }

    /// A random shape: a primitive, or a union of two or three, under up to
    /// two random transforms.
    fn shape(g: &mut Rng, closed: bool) -> Sdf {
        let mut s = if g.u(0.0, 1.0) < 0.4 {
            let n = 2 + (g.u(0.0, 1.0) < 0.5) as usize;
            Sdf::union((0..n).map(|_| primitive(g, closed)).collect())
        } else {
            primitive(g, closed)
        };
        for _ in 0..(g.u(0.0, 3.0) as usize) {
            s = match g.u(0.0, 3.0) as usize {
                0 => Sdf::translate(g.v(-3.0, 3.0), s),
                1 => Sdf::rotate(g.v(-1.0, 1.0), g.u(-180.0, 180.0), s),
                _ => Sdf::scale(g.u(0.5, 2.0), s),
            };
        }
        s
    }

    /// What sampling and sphere tracing say of the segment: `Some(true)`
    /// when a sample lies more than 1e-6 inside, `Some(false)` when a sphere
    /// trace at 1e-6 runs its whole length without a hit, `None` for the
    /// grazing rest.
    fn reference(s: &Sdf, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<bool> {
        let n = 4000;
        if (0..=n).any(|k| {
            let t = t0 + (t1 - t0) * k as f64 / n as f64;
            s.distance(o + d * t) < -1e-6
        }) {
            return Some(true);
        }
        let len = (t1 - t0) * d.length();
        match super::super::sphere_trace(s, o + d * t0, d, len, 1e-6) {
            None => Some(false),
            Some(_) => None,
        }
    }

    fn check(closed: bool, seed: u64) {
        let mut g = Rng(SplitMix64(seed));
        let (mut meets, mut misses, mut grazing, mut open) = (0, 0, 0, 0);
        for case in 0..6000 {
            let s = shape(&mut g, closed);
            let (c, r) = s.bounding_sphere();
            // Aim near the shape so that meeting and missing both happen.
            let o = c + g.v(-1.0, 1.0).normalize_or(DVec3::X) * g.u(1.2, 3.0) * r;
            let aim = c + g.v(-1.0, 1.0) * r;
            let d = (aim - o) * g.u(0.1, 2.0) / (aim - o).length().max(1e-9);
            let t0 = g.u(-2.0, 1.0) * r / d.length();
            let t1 = t0 + g.u(0.0, 4.0) * r / d.length();
            let got = s.segment_meets(o, d, t0, t1);
            match (got, reference(&s, o, d, t0, t1)) {
                (None, _) => {
                    assert!(!closed, "case {case}: undecided for {s:?}");
                    open += 1;
                }
                (_, None) => grazing += 1,
                (Some(a), Some(b)) => {
                    assert_eq!(a, b, "case {case}: {s:?}, o {o}, d {d}, t ∈ [{t0}, {t1}]");
                    if a { meets += 1 } else { misses += 1 }
                }
            }
        }
        assert!(meets > 1000 && misses > 1000, "{meets} meet, {misses} miss");
        assert!(grazing < 60, "{grazing} grazing segments of 6000");
        if !closed {
            assert!(open < 3000, "{open} of 6000 left to sphere tracing");
        }
    }

    #[test]
    fn closed_forms_agree_with_sampling_and_sphere_tracing() {
        check(true, 7);
    }

    #[test]
    fn rounded_boxes_and_tori_are_decided_or_left_open_never_wrong() {
        check(false, 11);
    }

    #[test]
    fn a_segment_touching_a_box_face_meets_it() {
        let b = Sdf::cuboid(DVec3::ZERO, DVec3::ONE);
        // Ends exactly on the face x = 1.
        assert_eq!(
            b.segment_meets(DVec3::new(3.0, 0.0, 0.0), -DVec3::X, 0.0, 2.0),
            Some(true)
        );
        assert_eq!(
            b.segment_meets(DVec3::new(3.0, 0.0, 0.0), -DVec3::X, 0.0, 1.999),
            Some(false)
        );
        // Parallel to a face, inside its slab and outside it.
        assert_eq!(
            b.segment_meets(DVec3::new(-5.0, 1.0, 0.0), DVec3::X, 0.0, 10.0),
            Some(true)
        );
        assert_eq!(
            b.segment_meets(DVec3::new(-5.0, 1.001, 0.0), DVec3::X, 0.0, 10.0),
            Some(false)
        );
        // A point segment.
        assert_eq!(
            b.segment_meets(DVec3::ZERO, DVec3::ZERO, 0.0, 0.0),
            Some(true)
        );
    }

    #[test]
    fn parallel_and_degenerate_capsules() {
        let c = Sdf::capsule(DVec3::ZERO, DVec3::new(0.0, 2.0, 0.0), 0.5);
        // Parallel to the core at distance 0.4 and 0.6.
        let up = DVec3::Y;
        assert_eq!(
            c.segment_meets(DVec3::new(0.4, -3.0, 0.0), up, 0.0, 10.0),
            Some(true)
        );
        assert_eq!(
            c.segment_meets(DVec3::new(0.6, -3.0, 0.0), up, 0.0, 10.0),
            Some(false)
        );
        // Stops 0.1 short of the lower cap.
        assert_eq!(
            c.segment_meets(DVec3::new(0.0, -3.0, 0.0), up, 0.0, 2.4),
            Some(false)
        );
        assert_eq!(
            c.segment_meets(DVec3::new(0.0, -3.0, 0.0), up, 0.0, 2.6),
            Some(true)
        );
        // A capsule whose core is a point is a ball.
        let ball = Sdf::capsule(DVec3::ONE, DVec3::ONE, 0.5);
        assert_eq!(
            ball.segment_meets(DVec3::new(1.45, -5.0, 1.0), up, 0.0, 10.0),
            Some(true)
        );
        assert_eq!(
            ball.segment_meets(DVec3::new(1.55, -5.0, 1.0), up, 0.0, 10.0),
            Some(false)
        );
    }
}
