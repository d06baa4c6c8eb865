//! Shadow rays through the objects seen along the sun.
//!
//! Shadow rays are straight and all parallel (to the sun's direction d), so
//! which objects one can meet depends only on where its start projects onto
//! the plane perpendicular to d. A 2-D grid over that plane lists, per cell,
//! the objects whose bounding sphere's shadow (a disc of the sphere's radius
//! around its centre's projection, grown by the cell's half-diagonal and a
//! millimetre) covers some of the cell. A shadow ray then
//!
//! - ends at once, sunlit, where its cell lists no object ahead of it (most
//!   of the ground of a scene: no distance query at all);
//! - else asks each listed object ahead whether the stretch of the ray its
//!   bounding sphere spans meets it, in closed form
//!   ([`Sdf::segment_meets`](crate::scene::sdf::Sdf::segment_meets): unions
//!   of boxes, cylinders, spheres and capsules, moved, turned and scaled);
//! - and sphere-traces through the objects left undecided only (a rounded
//!   box met near its rounded edges, a smooth union, …), over the stretch
//!   their bounding spheres span, each bounded by its sphere while that is
//!   more than a metre away.
//!
//! The closed forms matter most for points on an object: a ray leaving a
//! ship's side grew its sphere-tracing steps from the sub-millimetre start
//! offset only geometrically, 20–30 evaluations of the whole ship a point
//! (sea: 7.0 shadow evaluations a pixel before, 0.0 after, the trace 30 %
//! faster).
//!
//! Exact, not approximate: an object left out of a ray's list has its
//! bounding sphere more than a millimetre away from the whole ray, so it can
//! neither block the ray nor come within the hit tolerance of it. The closed
//! forms are for the exact surfaces; the sphere tracer's hit tolerance
//! (10⁻⁴ m + 10⁻⁷ of the distance) can call a ray that passes that close to
//! a surface blocked, the closed forms do not (on road.json, one row of 30
//! pixels under a van's number plate).

use super::accel::Counters;
use crate::scene::sdf::SceneObject;
use glam::{DVec2, DVec3};

/// Cells along the longer side of the projected grid.
const CELLS: f64 = 128.0;

/// The objects' shadows on the plane perpendicular to the sun (see the
/// module documentation).
#[derive(Clone, Debug)]
pub struct SunColumns {
    /// The sun's unit direction and a basis of the plane perpendicular to it.
    sun: DVec3,
    u: DVec3,
    w: DVec3,
    /// Lowest corner of the grid in (u, w), cell side, cells per side.
    origin: DVec2,
    cell: f64,
    dims: [usize; 2],
    /// Cell c's objects: `list[start[c] .. start[c + 1]]`.
    start: Vec<u32>,
    list: Vec<u32>,
    /// Each object's bounding sphere.
    spheres: Vec<(DVec3, f64)>,
}

impl SunColumns {
    /// The grid for `objects` lit from the unit direction `sun`; `None` when
    /// there are no objects or one is unbounded (a plane).
    pub fn new(objects: &[SceneObject], sun: DVec3) -> Option<SunColumns> {
        let spheres: Vec<(DVec3, f64)> =
            objects.iter().map(|o| o.shape.bounding_sphere()).collect();
        if spheres.is_empty()
            || spheres
                .iter()
                .any(|&(c, r)| !(c.is_finite() && r.is_finite()))
        {
            return None;
        }
        let sun = sun.normalize();
        let u = sun.any_orthonormal_vector();
        let w = sun.cross(u);
        let project = |c: DVec3| DVec2::new(c.dot(u), c.dot(w));
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &(c, r) in &spheres {
            lo = lo.min(project(c) - r);
            hi = hi.max(project(c) + r);
        }
        let cell = ((hi - lo).max_element() / CELLS).max(1e-6);
        let dims = [0, 1].map(|k| (((hi[k] - lo[k]) / cell).ceil() as usize).clamp(1, 4096));
        let half_diag = cell * std::f64::consts::FRAC_1_SQRT_2;
        let mut per_cell: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1]];
        for (o, &(c, r)) in spheres.iter().enumerate() {
            let reach = r + half_diag + 1e-3;
            let q = (project(c) - lo) / cell;
            let span = reach / cell;
            let i0 = (q.x - span).max(0.0) as usize;
            let j0 = (q.y - span).max(0.0) as usize;
            let i1 = ((q.x + span) as usize).min(dims[0] - 1);
            let j1 = ((q.y + span) as usize).min(dims[1] - 1);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let centre = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
                    if (centre - q).length() * cell <= reach {
                        per_cell[i + dims[0] * j].push(o as u32);
                    }
                }
            }
        }
        let mut start = Vec::with_capacity(per_cell.len() + 1);
        let mut list = Vec::new();
        for objects in per_cell {
            start.push(list.len() as u32);
            list.extend(objects);
        }
        start.push(list.len() as u32);
        Some(SunColumns {
            sun,
            u,
            w,
            origin: lo,
            cell,
            dims,
            start,
            list,
            spheres,
        })
    }

    /// The objects whose shadows may cover `p`.
    #[inline]
    fn candidates(&self, p: DVec3) -> &[u32] {
        let q = (DVec2::new(p.dot(self.u), p.dot(self.w)) - self.origin) / self.cell;
        if !(q.x >= 0.0 && q.y >= 0.0) {
            return &[];
        }
        let (i, j) = (q.x as usize, q.y as usize);
        if i >= self.dims[0] || j >= self.dims[1] {
            return &[];
        }
        let c = i + self.dims[0] * j;
        &self.list[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// Whether the ray from `p` toward the sun meets no object of `objects`
    /// (the ones the grid was built for): hit where the distance drops below
    /// 10⁻⁴ m + 10⁻⁷ of the distance travelled, as the renderer's shadow
    /// march has it, sphere-tracing through the listed objects ahead only,
    /// over the stretch of the ray their bounding spheres span.
    pub fn sunlit(&self, objects: &[SceneObject], p: DVec3, counters: &mut Counters) -> bool {
        let cands = self.candidates(p);
        let mut near = [0u32; 16];
        let mut count = 0;
        let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
        for &o in cands {
            let (c, r) = self.spheres[o as usize];
            let s = (c - p).dot(self.sun);
            if s + r < 0.0 {
                continue; // behind the point
            }
            let (a, b) = ((s - r).max(0.0), s + r);
            // Most shapes settle the question in closed form.
            match objects[o as usize].shape.segment_meets(p, self.sun, a, b) {
                Some(true) => return false,
                Some(false) => continue,
                None => {}
            }
            if let Some(slot) = near.get_mut(count) {
                *slot = o;
            }
            count += 1;
            t0 = t0.min(a);
            t1 = t1.max(b);
        }
        // A crowded cell (more than 16 left to march) marches through its
        // whole list.
        let list = match count {
            0 => return true,
            n if n <= near.len() => &near[..n],
            _ => cands,
        };
        let mut t = t0;
        for _ in 0..512 {
            let x = p + self.sun * t;
            counters.queries += 1;
            // The least distance over the list; an object whose bounding
            // sphere is farther than the least so far, or farther than a
            // metre, is bounded by the sphere's distance without its SDF.
            let mut r = f64::INFINITY;
            for &o in list {
                let (c, radius) = self.spheres[o as usize];
                let lb = (x - c).length() - radius;
                if lb >= r {
                    continue;
                }
                let d = if lb > 1.0 {
                    lb
                } else {
                    counters.object_evaluations += 1;
                    objects[o as usize].shape.distance(x)
                };
                r = r.min(d);
            }
            if r < 1e-4 + 1e-7 * t {
                return false;
            }
            t += r;
            if t > t1 {
                return true;
            }
        }
        true
    }
}
