//! Path reuse for stratified air.
//!
//! When δ depends on the height alone, a ray from the camera stays in the
//! vertical plane of its launch direction, its horizontal speed `c = n₀·cos θ₀`
//! is constant in τ (so its horizontal distance is exactly `ρ = c·τ`), and its
//! height `y(τ)` depends only on the launch elevation θ₀. One table of paths
//! `y(τ; θ₀)` therefore serves every pixel: a ray between two tabulated
//! elevations follows their linear interpolation, and sphere tracing walks along
//! that closed-form curve with no medium evaluations at all.
//!
//! The table is refined until the interpolation is accurate: for each pair of
//! neighbours the path at their mid-elevation is traced and compared with the
//! interpolation, node by node, as an angle seen from the camera
//! (|Δposition| / ρ); an interval is halved until that angle is below the
//! tolerance (or the interval is tiny, which only happens across the folds of a
//! mirage, where neighbouring rays part for good).

use super::accel::Aabb;
use super::air::Air;
use crate::math::V3;
use crate::trace::batch::{PACK, PackStepper};
use crate::trace::state::rate;
use crate::trace::{Earth, RayRate, RayState, rk4_step};
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Paths that dive this far below the ground are stopped (and extended as
/// straight lines): their ground crossing has long been found.
const BELOW_STOP: f64 = 2.0;
/// Paths that have escaped this far above everything are stopped likewise.
const ABOVE_STOP: f64 = 50.0;

/// One tabulated path.
#[derive(Clone, Debug)]
struct TablePath {
    theta: f64,
    /// Horizontal speed n₀ cos θ₀ (ρ = c·τ).
    c: f64,
    /// Height and vertical speed dy/dτ at τ = i·h.
    nodes: Vec<[f64; 2]>,
    /// Lower bound of the height over each interval (beyond the nodes: the
    /// straight extension): the exact minimum where that is below the
    /// ground, else a bound no lower than the ground ([`height_bound`]).
    mins: Vec<f64>,
    /// First interval whose lower bound is below the ground.
    first_low: usize,
    /// τ after which the path stays above every object, rising (∞: never).
    tau_escape: f64,
    /// τ at which the arc length reaches the scene's maximum distance.
    tau_max: f64,
    /// Elevation at the end (at the maximum distance, or when leaving the
    /// top of the model after escaping).
    final_elevation: f64,
    /// Whether the path left for the sky (then its final elevation follows
    /// from its invariant c alone).
    escaped: bool,
}

impl TablePath {
    /// Hermite data (y0, dy0, y1, dy1), slopes per unit τ, of interval i; past
    /// the last node, the straight extension.
    #[inline]
    fn interval(&self, i: usize, h: f64) -> [f64; 4] {
        let n = self.nodes.len();
        if i + 1 < n {
            let [y0, v0] = self.nodes[i];
            let [y1, v1] = self.nodes[i + 1];
            [y0, v0, y1, v1]
        } else {
            let [yl, vl] = self.nodes[n - 1];
            let t0 = (i + 1 - n) as f64 * h;
            [yl + vl * t0, vl, yl + vl * (t0 + h), vl]
        }
    }

    #[inline]
    fn interval_min(&self, i: usize, h: f64) -> f64 {
        if i < self.mins.len() {
            self.mins[i]
        } else {
            let [y0, _, y1, _] = self.interval(i, h);
            y0.min(y1)
        }
    }

    /// Height at node i (τ = i·h), past the last node on the straight
    /// extension: what the interpolation gives there, without it.
    #[inline]
    fn node_height(&self, i: usize, h: f64) -> f64 {
        let n = self.nodes.len();
        if i < n {
            self.nodes[i][0]
        } else {
            let [yl, vl] = self.nodes[n - 1];
            yl + vl * ((i + 1 - n) as f64 * h)
        }
    }
}

/// The Hermite data of a table ray between two paths: `w` of `a`'s and
/// 1 − w of `b`'s (the interpolated curve is linear in them).
#[inline]
fn blend(w: f64, a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let u = 1.0 - w;
    [
        w * a[0] + u * b[0],
        w * a[1] + u * b[1],
        w * a[2] + u * b[2],
        w * a[3] + u * b[3],
    ]
}

/// Cubic Hermite value and τ-derivative at θ ∈ [0, 1] of interval data
/// (y0, dy0/dτ, y1, dy1/dτ) over a step h, with 1/h given (the derivative
/// by a product).
#[inline]
fn hermite_scaled([y0, v0, y1, v1]: [f64; 4], t: f64, h: f64, inv_h: f64) -> (f64, f64) {
    let t2 = t * t;
    let t3 = t2 * t;
    let y = (2.0 * t3 - 3.0 * t2 + 1.0) * y0
        + (t3 - 2.0 * t2 + t) * h * v0
        + (-2.0 * t3 + 3.0 * t2) * y1
        + (t3 - t2) * h * v1;
    let dy = ((6.0 * t2 - 6.0 * t) * (y0 - y1)) * inv_h
        + (3.0 * t2 - 4.0 * t + 1.0) * v0
        + (3.0 * t2 - 2.0 * t) * v1;
    (y, dy)
}

/// The cubic's coefficients [a, b, c, d] (a t³ + b t² + c t + d) on θ ∈ [0, 1].
fn cubic([y0, v0, y1, v1]: [f64; 4], h: f64) -> [f64; 4] {
    let (m0, m1) = (h * v0, h * v1);
    [
        2.0 * y0 + m0 - 2.0 * y1 + m1,
        -3.0 * y0 - 2.0 * m0 + 3.0 * y1 - m1,
        m0,
        y0,
    ]
}

fn eval_cubic([a, b, c, d]: [f64; 4], t: f64) -> f64 {
    ((a * t + b) * t + c) * t + d
}

/// The critical points of the cubic inside (0, 1), ascending.
fn critical_points([a, b, c, _]: [f64; 4]) -> ([f64; 2], usize) {
    // 3a t² + 2b t + c = 0
    let (qa, qb, qc) = (3.0 * a, 2.0 * b, c);
    let mut out = [0.0; 2];
    let mut n = 0;
    let mut push = |t: f64| {
        if t > 0.0 && t < 1.0 && n < 2 {
            out[n] = t;
            n += 1;
        }
    };
    if qa.abs() < 1e-300 {
        if qb != 0.0 {
            push(-qc / qb);
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let s = disc.sqrt();
            // Numerically stable pair of roots.
            let q = -0.5 * (qb + qb.signum() * s);
            let (r1, r2) = if q != 0.0 {
                (q / qa, qc / q)
            } else {
                (0.0, 0.0)
            };
            let (lo, hi) = if r1 <= r2 { (r1, r2) } else { (r2, r1) };
            push(lo);
            push(hi);
        }
    }
    (out, n)
}

/// A lower bound of the Hermite interval `d` over its step h, exact where
/// the interval may go below the ground (y < 0): the least of the cubic's
/// Bernstein coefficients (the curve lies in their convex hull) when that is
/// not negative, else [`cubic_min`]. Where it matters, below the ground,
/// the bound is the minimum itself; elsewhere a cheaper bound serves, since
/// the table only asks whether an interval can reach the ground.
fn height_bound(d: [f64; 4], h: f64) -> f64 {
    let [y0, v0, y1, v1] = d;
    let hull = y0.min(y1).min(y0 + h * v0 / 3.0).min(y1 - h * v1 / 3.0);
    if hull >= 0.0 {
        hull
    } else {
        cubic_min(cubic(d, h))
    }
}

/// Lower bound (exact minimum) of the cubic over [0, 1].
fn cubic_min(k: [f64; 4]) -> f64 {
    let (cp, n) = critical_points(k);
    let mut m = eval_cubic(k, 0.0).min(eval_cubic(k, 1.0));
    for &t in &cp[..n] {
        m = m.min(eval_cubic(k, t));
    }
    m
}

/// The first θ ∈ [0, 1] where the cubic (≥ 0 at 0) becomes negative.
fn cubic_first_zero(k: [f64; 4]) -> Option<f64> {
    let (cp, n) = critical_points(k);
    let mut a = 0.0;
    let mut stops = [1.0; 3];
    stops[..n].copy_from_slice(&cp[..n]);
    stops[n] = 1.0;
    for &b in &stops[..=n] {
        if eval_cubic(k, b) < 0.0 {
            // Monotone on [a, b]: Newton kept inside the bracket.
            let [c3, c2, c1, _] = k;
            return Some(crate::trace::hermite::bracketed_root(a, b, |t| {
                (eval_cubic(k, t), (3.0 * c3 * t + 2.0 * c2) * t + c1)
            }));
        }
        a = b;
    }
    None
}

/// Statistics of a table.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TableStats {
    /// Paths traced (kept and rejected midpoints alike: all are kept).
    pub paths: usize,
    /// RK4 steps over all paths.
    pub rk4_steps: u64,
    /// Largest interpolation error measured at a checked midpoint, as an angle
    /// seen from the camera (radians), over the intervals finally kept (after
    /// their halving: the measured value / 4, the interpolation error scaling
    /// with the square of the interval).
    pub error_estimate: f64,
    /// Intervals that reached the smallest allowed width without meeting the
    /// tolerance (folds of the mirage).
    pub unresolved: usize,
}

/// Settings of a table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableSettings {
    /// Lowest and highest launch elevation to cover (radians).
    pub theta_range: (f64, f64),
    /// Spacing of the first, uniform set of paths (radians).
    pub initial_spacing: f64,
    /// Smallest spacing refinement may reach (radians).
    pub min_spacing: f64,
    /// Largest interpolation error accepted, as an angle (radians).
    pub tolerance: f64,
    /// Arc length of one RK4 step (metres).
    pub step: f64,
    /// Arc length at which a ray ends in the sky (metres).
    pub max_distance: f64,
    /// Whether the ground plane y = 0 stops rays.
    pub ground: bool,
}

/// The table of paths for one camera position.
#[derive(Clone, Debug)]
pub struct PathTable {
    origin: DVec3,
    h: f64,
    n_max: f64,
    paths: Vec<TablePath>,
    thetas: Vec<f64>,
    /// Where to start looking for an elevation in `thetas`.
    index: ThetaIndex,
    objects: Option<Aabb>,
    /// Horizontal centre and radius of every object's bounding sphere.
    footprints: Vec<(DVec2, f64)>,
    ground: bool,
    /// n at the top of the model, for the final direction of escaping rays.
    n_top: f64,
    stats: TableStats,
}

/// Uniform buckets over the table's elevations, each with the number of
/// elevations at or below its start: a camera ray's place in the table in a
/// few comparisons instead of a binary search over every path (which was a
/// quarter of the time spent setting up a table ray).
#[derive(Clone, Debug)]
struct ThetaIndex {
    first: f64,
    per_bucket: f64,
    counts: Vec<u32>,
}

impl ThetaIndex {
    fn new(thetas: &[f64]) -> Self {
        let buckets = (4 * thetas.len()).max(1);
        let first = thetas.first().copied().unwrap_or(0.0);
        let span = thetas.last().copied().unwrap_or(0.0) - first;
        let per_bucket = if span > 0.0 {
            buckets as f64 / span
        } else {
            0.0
        };
        let counts = (0..buckets)
            .map(|b| {
                let start = first + b as f64 / per_bucket.max(f64::MIN_POSITIVE);
                thetas.partition_point(|&t| t <= start) as u32
            })
            .collect();
        ThetaIndex {
            first,
            per_bucket,
            counts,
        }
    }

    /// The number of `thetas` (sorted) at or below `theta` (not NaN):
    /// exactly `partition_point(|t| t <= theta)`, whatever the bucket's guess
    /// (it is corrected by walking, a step or two at most).
    #[inline]
    fn count_at_most(&self, thetas: &[f64], theta: f64) -> usize {
        let b = ((theta - self.first) * self.per_bucket) as usize;
        let mut k = self.counts[b.min(self.counts.len() - 1)] as usize;
        while k > 0 && thetas[k - 1] > theta {
            k -= 1;
        }
        while k < thetas.len() && thetas[k] <= theta {
            k += 1;
        }
        k
    }
}

/// A camera ray's interpolated path: everything the sphere tracer needs.
#[derive(Clone, Copy, Debug)]
pub struct TableRay {
    origin: DVec3,
    /// Horizontal unit direction.
    pub horizontal: DVec2,
    /// Horizontal speed (ρ = c·τ).
    pub c: f64,
    k: usize,
    w: f64,
    h: f64,
    /// 1 / h.
    inv_h: f64,
    /// τ after which no object can be met (left the objects' rectangle,
    /// escaped above them, reached the ground or the maximum distance).
    pub tau_objects_end: f64,
    /// τ of the first ground crossing (∞: none before the maximum distance).
    pub tau_ground: f64,
    /// τ at the maximum distance.
    pub tau_max: f64,
    /// Elevation of the final direction (radians), for rays ending in the sky.
    pub final_elevation: f64,
    /// The τ intervals in which the ray is over some object's footprint (the
    /// horizontal disc of its bounding sphere), sorted and merged: outside
    /// them nothing can be hit. Exact, since the ray's horizontal track is a
    /// straight line in stratified air.
    windows: [(f64, f64); MAX_WINDOWS],
    n_windows: usize,
}

/// Most footprint windows kept per ray; beyond, they merge into one.
const MAX_WINDOWS: usize = 8;

impl TableRay {
    /// The start of the first window that ends after τ (τ itself if inside
    /// one), or `None` when no window is left.
    #[inline]
    pub fn next_window(&self, tau: f64) -> Option<f64> {
        self.windows[..self.n_windows]
            .iter()
            .find(|w| w.1 > tau)
            .map(|w| w.0.max(tau))
    }
}

impl PathTable {
    /// Traces and refines the table for a camera at `origin` in the stratified
    /// `air`. `objects`: the box of the objects (their top decides escapes).
    pub fn build(
        air: &Air,
        origin: DVec3,
        objects: &[crate::scene::sdf::SceneObject],
        s: &TableSettings,
    ) -> PathTable {
        let footprints: Vec<(DVec2, f64)> = objects
            .iter()
            .map(|o| {
                let (c, r) = o.shape.bounding_sphere();
                (DVec2::new(c.x, c.z), r)
            })
            .collect();
        let objects = Aabb::of_objects(objects);
        let y_top = objects.map_or(origin.y, |b| b.max.y.max(origin.y));
        let h = s.step / air.step_n_max();
        let (lo, hi) = s.theta_range;
        let n0 = ((hi - lo) / s.initial_spacing).ceil().max(1.0) as usize;
        let mut thetas: Vec<f64> = (0..=n0)
            .map(|i| lo + (hi - lo) * i as f64 / n0 as f64)
            .collect();
        let geometry = PathGeometry {
            h,
            max_distance: s.max_distance,
            y_top,
        };
        let mut paths = trace_paths(air, origin, &thetas, &geometry);
        let mut stats = TableStats {
            paths: paths.len(),
            ..Default::default()
        };
        // Intervals still to check, by their left index in `paths`.
        let mut open: Vec<bool> = vec![true; paths.len() - 1];
        loop {
            let todo: Vec<usize> = (0..open.len())
                .filter(|&i| open[i] && thetas[i + 1] - thetas[i] > s.min_spacing)
                .collect();
            for i in 0..open.len() {
                if open[i] && thetas[i + 1] - thetas[i] <= s.min_spacing {
                    open[i] = false;
                    stats.unresolved += 1;
                }
            }
            if todo.is_empty() {
                break;
            }
            let middles: Vec<f64> = todo
                .iter()
                .map(|&i| 0.5 * (thetas[i] + thetas[i + 1]))
                .collect();
            let mids: Vec<(usize, TablePath, f64)> = trace_paths(air, origin, &middles, &geometry)
                .into_par_iter()
                .zip(todo.par_iter())
                .map(|(m, &i)| {
                    let e = midpoint_error(&paths[i], &paths[i + 1], &m, h);
                    (i, m, e)
                })
                .collect();
            stats.paths += mids.len();
            // Merge the middles in, in one pass (inserting them one by one
            // moved the whole tail of the table each time).
            let mut mids = mids.into_iter().peekable();
            let old = std::mem::take(&mut paths).into_iter().enumerate();
            let n = old.len() + todo.len();
            let (mut merged_paths, mut merged_open) =
                (Vec::with_capacity(n), Vec::with_capacity(n));
            for (i, p) in old {
                merged_paths.push(p);
                if i == open.len() {
                    break;
                }
                match mids.next_if(|m| m.0 == i) {
                    Some((_, m, e)) => {
                        let ok = e <= s.tolerance;
                        if ok {
                            stats.error_estimate = stats.error_estimate.max(0.25 * e);
                        }
                        merged_paths.push(m);
                        merged_open.extend([!ok, !ok]);
                    }
                    None => merged_open.push(open[i]),
                }
            }
            paths = merged_paths;
            open = merged_open;
            thetas = paths.iter().map(|p| p.theta).collect();
        }
        stats.rk4_steps = paths.iter().map(|p| p.nodes.len() as u64 - 1).sum();
        PathTable {
            origin,
            h,
            n_max: air.step_n_max(),
            paths,
            index: ThetaIndex::new(&thetas),
            thetas,
            objects,
            footprints,
            ground: s.ground,
            n_top: 1.0 + air.stratified_delta(air.profile_top()),
            stats,
        }
    }

    /// The table's statistics.
    pub fn stats(&self) -> TableStats {
        self.stats
    }

    /// Number of paths.
    pub fn len(&self) -> usize {
        self.paths.len()
    }

    /// Whether the table has no paths (never, once built).
    pub fn is_empty(&self) -> bool {
        self.paths.is_empty()
    }

    /// The RK4 step in τ of every path (nodes lie at τ = i·step).
    pub fn step(&self) -> f64 {
        self.h
    }

    /// Upper bound of the speed |dx/dτ| of every path (n_max).
    pub fn n_max(&self) -> f64 {
        self.n_max
    }

    /// The interpolated path of the camera ray along the unit direction `dir`,
    /// or `None` if its elevation is outside the table (or it is vertical).
    pub fn ray(&self, dir: DVec3) -> Option<TableRay> {
        let hl = DVec2::new(dir.x, dir.z).length();
        if hl == 0.0 {
            return None;
        }
        let theta = dir.y.atan2(hl);
        let (first, last) = (self.thetas[0], self.thetas[self.thetas.len() - 1]);
        if !(theta >= first && theta <= last) {
            return None;
        }
        let k = self
            .index
            .count_at_most(&self.thetas, theta)
            .clamp(1, self.thetas.len() - 1)
            - 1;
        let (a, b) = (&self.paths[k], &self.paths[k + 1]);
        let w = (b.theta - theta) / (b.theta - a.theta);
        let horizontal = DVec2::new(dir.x, dir.z) / hl;
        let c = w * a.c + (1.0 - w) * b.c;
        let tau_max = w * a.tau_max + (1.0 - w) * b.tau_max;
        let mut ray = TableRay {
            origin: self.origin,
            horizontal,
            c,
            k,
            w,
            h: self.h,
            inv_h: 1.0 / self.h,
            tau_objects_end: tau_max,
            tau_ground: f64::INFINITY,
            tau_max,
            final_elevation: w * a.final_elevation + (1.0 - w) * b.final_elevation,
            windows: [(0.0, 0.0); MAX_WINDOWS],
            n_windows: 0,
        };
        if self.ground {
            ray.tau_ground = self.ground_tau(&ray);
        }
        if a.escaped && b.escaped {
            // Snell with the ray's own invariant: exact, where interpolating
            // the neighbours' final elevations is not (near the edge of a
            // duct they change like a square root).
            ray.final_elevation = (c / self.n_top).clamp(-1.0, 1.0).acos();
        }
        let tau_escape = a.tau_escape.max(b.tau_escape);
        let tau_rect = match &self.objects {
            None => 0.0,
            Some(bx) => {
                let rho = bx.xz_exit(DVec2::new(self.origin.x, self.origin.z), horizontal);
                if c > 0.0 { rho / c } else { f64::INFINITY }
            }
        };
        ray.tau_objects_end = tau_max.min(ray.tau_ground).min(tau_escape).min(tau_rect);
        self.footprint_windows(&mut ray);
        Some(ray)
    }

    fn footprint_windows(&self, r: &mut TableRay) {
        let end = r.tau_objects_end;
        let o = DVec2::new(self.origin.x, self.origin.z);
        let mut buf = [(0.0, 0.0); 64];
        let mut n = 0;
        let mut overflow = false;
        for &(c, radius) in &self.footprints {
            let rel = c - o;
            let t = rel.dot(r.horizontal);
            let d2 = rel.length_squared() - t * t;
            let r2 = radius * radius;
            if d2 > r2 {
                continue;
            }
            let half = (r2 - d2).sqrt();
            // A hair wider, against rounding in ρ = c·τ.
            let pad = 1e-9 * (t.abs() + radius) + 1e-9;
            let (a, b) = ((t - half - pad) / r.c, (t + half + pad) / r.c);
            let (a, b) = (a.max(0.0), b.min(end));
            if a >= b {
                continue;
            }
            if n == buf.len() {
                overflow = true;
                break;
            }
            buf[n] = (a, b);
            n += 1;
        }
        if overflow {
            r.windows[0] = (0.0, end);
            r.n_windows = 1;
            return;
        }
        let buf = &mut buf[..n];
        buf.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut k = 0;
        for &(a, b) in buf.iter() {
            if k > 0 && a <= r.windows[k - 1].1 {
                r.windows[k - 1].1 = r.windows[k - 1].1.max(b);
            } else if k < MAX_WINDOWS {
                r.windows[k] = (a, b);
                k += 1;
            } else {
                r.windows[k - 1].1 = r.windows[k - 1].1.max(b);
            }
        }
        r.n_windows = k;
    }

    /// First τ where the interpolated height goes below 0 (∞ if none before
    /// the maximum distance).
    fn ground_tau(&self, r: &TableRay) -> f64 {
        let (a, b) = (&self.paths[r.k], &self.paths[r.k + 1]);
        let w = r.w;
        let h = self.h;
        // Past both paths' last nodes the interpolation is a straight line.
        let last = a.nodes.len().max(b.nodes.len()) - 1;
        let mut i = a.first_low.min(b.first_low);
        while i < last && (i as f64) * h < r.tau_max {
            let lb = w * a.interval_min(i, h) + (1.0 - w) * b.interval_min(i, h);
            if lb < 0.0 {
                let (da, db) = (a.interval(i, h), b.interval(i, h));
                let d = blend(w, da, db);
                if let Some(t) = cubic_first_zero(cubic(d, h)) {
                    let tau = (i as f64 + t) * h;
                    return if tau <= r.tau_max { tau } else { f64::INFINITY };
                }
            }
            i += 1;
        }
        let [y, v, _, _] = blend(w, a.interval(last, h), b.interval(last, h));
        let t0 = last as f64 * h;
        if y < 0.0 {
            return t0;
        }
        if v < 0.0 {
            let tau = t0 - y / v;
            if tau <= r.tau_max {
                return tau;
            }
        }
        f64::INFINITY
    }

    /// Position and unit tangent of the interpolated path at τ.
    ///
    /// The interpolation between the two paths is linear in their Hermite
    /// data, so the data are blended first and one cubic is evaluated (as
    /// the ground crossing does); the tangent's length is
    /// √(c² + (dy/dτ)²), the horizontal direction being unit. This is the
    /// sphere tracer's inner loop: one division and one square root.
    #[inline]
    pub fn position(&self, r: &TableRay, tau: f64) -> (DVec3, DVec3) {
        let (a, b) = (&self.paths[r.k], &self.paths[r.k + 1]);
        let q = tau * r.inv_h;
        // The floor (negatives and NaN give 0) without a libm call.
        let i = q as usize;
        let d = blend(r.w, a.interval(i, r.h), b.interval(i, r.h));
        let (y, vy) = hermite_scaled(d, q - i as f64, r.h, r.inv_h);
        let rho = r.c * tau;
        let p = DVec3::new(
            r.origin.x + r.horizontal.x * rho,
            y,
            r.origin.z + r.horizontal.y * rho,
        );
        let scale = 1.0 / (r.c * r.c + vy * vy).sqrt();
        let t = DVec3::new(
            r.horizontal.x * r.c * scale,
            vy * scale,
            r.horizontal.y * r.c * scale,
        );
        (p, t)
    }
}

/// Traces the paths launched at elevations `thetas` from `origin`, the same
/// paths [`trace_path`] traces one by one, in packs of [`PACK`] in SIMD lanes
/// ([`PackStepper`]) where the medium has a lane form: every lane takes the
/// same fixed step h, so a pack stays full until its paths end (they end
/// within a few steps of each other, neighbours in elevation). The steps
/// agree with the scalar ones to rounding (the polynomial exponential).
fn trace_paths(air: &Air, origin: DVec3, thetas: &[f64], g: &PathGeometry) -> Vec<TablePath> {
    let Some(stepper) = PackStepper::new(air.field(), Earth::Flat) else {
        return thetas
            .par_iter()
            .map(|&t| trace_path(air, origin, t, g))
            .collect();
    };
    thetas
        .par_chunks(PACK)
        .flat_map_iter(|chunk| {
            let mut cache = stepper.cache();
            let field = air.field();
            let mut builders: Vec<PathBuilder> = chunk
                .iter()
                .map(|&t| PathBuilder::new(field, origin, t, g))
                .collect();
            let mut y = [builders[0].y; PACK];
            let mut f = [builders[0].f; PACK];
            let mut active = [false; PACK];
            for (k, b) in builders.iter().enumerate() {
                (y[k], f[k], active[k]) = (b.y, b.f, true);
            }
            let mut h = [0.0; PACK];
            while active.iter().any(|&a| a) {
                for k in 0..PACK {
                    h[k] = if active[k] { g.h } else { 0.0 };
                }
                stepper.rk4(&mut cache, &h, &mut y, &mut f);
                for (k, b) in builders.iter_mut().enumerate() {
                    if active[k] {
                        active[k] = !b.stepped(air, y[k], f[k], g);
                    }
                }
            }
            builders.into_iter().map(move |b| b.finish(g.h))
        })
        .collect()
}

/// What every path of a table shares: the step, where paths end.
#[derive(Clone, Copy, Debug)]
struct PathGeometry {
    /// The τ step.
    h: f64,
    /// The scene's largest arc length.
    max_distance: f64,
    /// The top of the objects (or the camera, if higher).
    y_top: f64,
}

/// Traces the path launched at elevation `theta` from `origin` (in the vertical
/// plane; only the height matters in stratified air).
fn trace_path(air: &Air, origin: DVec3, theta: f64, g: &PathGeometry) -> TablePath {
    let field = air.field();
    let mut b = PathBuilder::new(field, origin, theta, g);
    loop {
        let (y1, f1) = rk4_step(field, &b.y, &b.f, g.h, &mut 0);
        if b.stepped(air, y1, f1, g) {
            return b.finish(g.h);
        }
    }
}

/// One path being traced: its state, nodes and what its end decides.
struct PathBuilder {
    theta: f64,
    c: f64,
    y: RayState,
    f: RayRate,
    nodes: Vec<[f64; 2]>,
    tau: f64,
    tau_escape: f64,
    /// (τ at the maximum distance, final elevation), once the path ended.
    end: Option<(f64, f64)>,
}

impl PathBuilder {
    fn new(field: &crate::medium::Field, origin: DVec3, theta: f64, g: &PathGeometry) -> Self {
        let x0 = V3::new(0.0, origin.y, 0.0);
        let n0 = 1.0 + crate::medium::IndexField::delta(field, x0);
        let y = RayState {
            x: x0,
            v: V3::new(theta.cos(), theta.sin(), 0.0) * n0,
            s: 0.0,
        };
        PathBuilder {
            theta,
            c: y.v.x,
            f: rate(field, &y, &mut 0),
            y,
            nodes: {
                // Room for a path to the largest distance (s grows by about
                // h·n ≥ h·(1 − 10⁻³) a step): one allocation, no copies as it
                // grows; pages beyond its end are never touched.
                let steps = (g.max_distance / g.h * 1.001).min(4e6) as usize + 2;
                let mut nodes = Vec::with_capacity(steps);
                nodes.push([y.x.y, y.v.y]);
                nodes
            },
            tau: 0.0,
            tau_escape: f64::INFINITY,
            end: None,
        }
    }

    /// Takes the step that ended at `(y1, f1)`; true when the path ends.
    fn stepped(&mut self, air: &Air, y1: RayState, f1: RayRate, g: &PathGeometry) -> bool {
        let (y, h, c) = (self.y, g.h, self.c);
        self.tau += h;
        let tau = self.tau;
        self.nodes.push([y1.x.y, y1.v.y]);
        let rising = y1.v.y > 0.0;
        if self.tau_escape.is_infinite() && rising && y1.x.y > g.y_top && air.escapes(y1.x.y, c) {
            self.tau_escape = tau;
        }
        if y1.s >= g.max_distance {
            // Where, inside this step, the arc length reached the maximum.
            let frac = (g.max_distance - y.s) / (y1.s - y.s);
            self.end = Some((tau - h + frac * h, y1.v.y.atan2(c)));
            return true;
        }
        let stop_below = y1.x.y < -BELOW_STOP && !rising;
        let stop_above = self.tau_escape.is_finite() && y1.x.y > g.y_top + ABOVE_STOP;
        if stop_below || stop_above {
            let n1 = y1.v.norm();
            let elevation = if stop_above {
                air.asymptotic_elevation(c)
            } else {
                y1.v.y.atan2(c)
            };
            self.end = Some((tau + (g.max_distance - y1.s) / n1, elevation));
            return true;
        }
        self.y = y1;
        self.f = f1;
        false
    }

    /// The table path of a path that ended.
    fn finish(self, h: f64) -> TablePath {
        let (tau_max, final_elevation) = self.end.expect("a path is finished once it ended");
        let nodes = self.nodes;
        let mut mins = Vec::with_capacity(nodes.len());
        let mut first_low = nodes.len() - 1;
        for i in 0..nodes.len() - 1 {
            let d = [nodes[i][0], nodes[i][1], nodes[i + 1][0], nodes[i + 1][1]];
            let m = height_bound(d, h);
            if m < 0.0 && first_low == nodes.len() - 1 {
                first_low = i;
            }
            mins.push(m);
        }
        TablePath {
            theta: self.theta,
            c: self.c,
            nodes,
            mins,
            first_low,
            tau_escape: self.tau_escape,
            tau_max,
            final_elevation,
            escaped: self.tau_escape.is_finite(),
        }
    }
}

/// The largest angle (seen from the camera) between the path `m` and the
/// average of its neighbours `a` and `b`, over the nodes that matter: until all
/// three are below the ground or have escaped.
fn midpoint_error(a: &TablePath, b: &TablePath, m: &TablePath, h: f64) -> f64 {
    let len = a.nodes.len().max(b.nodes.len()).max(m.nodes.len());
    let c_avg = 0.5 * (a.c + b.c);
    // The worst squared angle; one square root at the end (no overflow:
    // heights and distances are far below 1e150).
    let mut worst = 0.0f64;
    for i in 1..len {
        let tau = i as f64 * h;
        let ya = a.node_height(i, h);
        let yb = b.node_height(i, h);
        let ym = m.node_height(i, h);
        if ya < 0.0 && yb < 0.0 && ym < 0.0 {
            break;
        }
        if tau > a.tau_escape && tau > b.tau_escape && tau > m.tau_escape {
            break;
        }
        let dy = ym - 0.5 * (ya + yb);
        let drho = (m.c - c_avg) * tau;
        let rho = (m.c * tau).max(1e-9);
        worst = worst.max((dy * dy + drho * drho) / (rho * rho));
    }
    worst.sqrt()
}

#[cfg(test)]
mod tests {
    use super::ThetaIndex;

    /// The index counts as the binary search does, for uneven elevations
    /// (a refined table), values between, on and outside them.
    #[test]
    fn theta_index_counts_like_partition_point() {
        let mut thetas: Vec<f64> = (0..200).map(|i| -0.01 + 1e-4 * i as f64).collect();
        thetas.extend((0..300).map(|i| 0.0099 + 1e-7 * i as f64));
        thetas.push(0.02);
        let index = ThetaIndex::new(&thetas);
        let mut probes: Vec<f64> = thetas.clone();
        probes.extend(thetas.windows(2).map(|w| 0.5 * (w[0] + w[1])));
        probes.extend([-1.0, -0.0100001, 0.0200001, 5.0]);
        for t in probes {
            assert_eq!(
                index.count_at_most(&thetas, t),
                thetas.partition_point(|&x| x <= t),
                "at {t}"
            );
        }
    }
}
