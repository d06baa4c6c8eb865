//! Sphere tracing along curved rays.
//!
//! A ray is integrated in the τ form of the ray equation with RK4
//! ([`crate::trace::rk4_step`]); every step's arc length is bounded by the free
//! radius a distance query returned at its start, so no surface can be crossed:
//! the curve stays within its arc length of its start (chord ≤ arc), and an arc
//! of τ-length h is at most h·n_max long, so steps are taken as
//! `h = radius / n_max`. A step may also be cut by the RK4 step of the air
//! ([`Air::step_at`]); several RK4 steps then share one query, which is why the
//! number of distance queries does not depend on the RK4 step. A 5 cm pole is
//! therefore never stepped over, whatever that step.
//!
//! Three tracers:
//!
//! - **plain**: every object's SDF at every query, steps of the free radius;
//! - **enhanced** (Keinert et al. 2014, "Enhanced sphere tracing"): steps of
//!   ω·radius (ω = 1.6); the next query checks that the two spheres still cover
//!   the arc between their centres (`r_prev + r ≥ arc`, with the arc length, not
//!   the chord, so it holds on a curve); if not, the ray goes back to the
//!   previous point, takes the plain step, and stays plain (ω = 1);
//! - **quadric**: the grid of unbounding spheres ([`super::accel::Grid`]): far
//!   from surfaces a query costs no SDF evaluation and the step runs to where
//!   the ray leaves the cell's empty sphere or its clear box
//!   ([`super::clear`]), whichever reaches further; near surfaces the cell's
//!   short object list is evaluated; over-relaxed as in *enhanced*.
//!
//! The ground (y = 0, or the sphere of the round earth, [`Air::earth`]) is not
//! an SDF (a plane would throttle every grazing ray to steps of its height):
//! each RK4 step's quintic Hermite interpolant is tested for a crossing, dips
//! between nodes included, and the crossing is located to full precision.
//! Over the round earth the rays are integrated in the air of heights above
//! the sphere ([`Air::optics`]). A ray that travels the maximum distance, or whose fate
//! [`Air::fate`] decides as the sky, shows the sky along its final direction.

use super::accel::{Counters, NearCache, Query, SceneDistance};
use super::air::{Air, Fate};
use super::paths::{PathTable, TableRay};
use crate::math::V3;
use crate::scene::sdf::nearest_object;
use crate::trace::state::rate;
use crate::trace::{Earth, RayRate, RayState, Segment, rk4_step};
use glam::DVec3;

/// Over-relaxation factor of the enhanced and quadric tracers.
pub const OMEGA: f64 = 1.6;
/// Largest number of distance queries for one ray (grazing rays converge
/// slowly); after that the ray counts as hitting the nearest object.
pub const MAX_QUERIES: u32 = 2000;

/// Which sphere tracer to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TracerKind {
    /// Every SDF at every query, plain steps.
    Plain,
    /// Every SDF at every query, over-relaxed steps.
    Enhanced,
    /// Grid of unbounding spheres and near lists, over-relaxed steps.
    #[default]
    Quadric,
}

impl TracerKind {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TracerKind::Plain => "plain",
            TracerKind::Enhanced => "enhanced",
            TracerKind::Quadric => "quadric",
        }
    }

    /// The tracer a name denotes.
    pub fn from_name(name: &str) -> Option<TracerKind> {
        match name {
            "plain" => Some(TracerKind::Plain),
            "enhanced" => Some(TracerKind::Enhanced),
            "quadric" => Some(TracerKind::Quadric),
            _ => None,
        }
    }
}

/// What a camera ray ends on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// An object's surface (within the hit tolerance of it).
    Object {
        /// Index in the scene's objects.
        index: usize,
        /// The hit point.
        point: DVec3,
        /// Unit direction of the ray there.
        direction: DVec3,
        /// Arc length from the camera (metres).
        distance: f64,
    },
    /// The ground (the plane y = 0, or the sphere).
    Ground {
        /// The hit point (on the ground).
        point: DVec3,
        /// Unit direction of the ray there.
        direction: DVec3,
        /// Arc length from the camera (metres).
        distance: f64,
    },
    /// Nothing: the sky along this final unit direction.
    Sky {
        /// The final direction.
        direction: DVec3,
    },
}

/// Work counters of marching.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MarchStats {
    /// Distance queries and SDF evaluations.
    pub counters: Counters,
    /// RK4 steps.
    pub rk4_steps: u64,
    /// Of which integrated ahead in packs of SIMD lanes ([`super::packs`]).
    pub pack_steps: u64,
    /// Evaluations of δ and ∇δ.
    pub medium_evaluations: u64,
    /// Over-relaxed steps taken back.
    pub fallbacks: u64,
}

impl std::ops::AddAssign for MarchStats {
    fn add_assign(&mut self, o: MarchStats) {
        self.counters += o.counters;
        self.rk4_steps += o.rk4_steps;
        self.pack_steps += o.pack_steps;
        self.medium_evaluations += o.medium_evaluations;
        self.fallbacks += o.fallbacks;
    }
}

/// The hit tolerance: a ray hits when the free radius drops below
/// `max(absolute, relative · arc length)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitTolerance {
    /// Metres.
    pub absolute: f64,
    /// Per metre travelled (a fraction of the pixel's footprint).
    pub relative: f64,
}

impl HitTolerance {
    #[inline]
    fn at(&self, s: f64) -> f64 {
        self.absolute.max(self.relative * s)
    }
}

/// Everything a ray needs: the air, the distances, the settings.
#[derive(Clone, Copy, Debug)]
pub struct Marcher<'a> {
    /// The air.
    pub air: &'a Air,
    /// The objects' distances.
    pub distance: &'a SceneDistance,
    /// Over-relaxation (1: plain).
    pub omega: f64,
    /// When a ray hits.
    pub tolerance: HitTolerance,
    /// Arc length after which a ray shows the sky (metres).
    pub max_distance: f64,
    /// Whether the ground (the plane y = 0, or the sphere) stops rays.
    pub ground: bool,
}

/// One RK4 step integrated ahead ([`super::packs`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AheadStep {
    /// The state where the step ends.
    pub y: RayState,
    /// The rate there.
    pub f: RayRate,
    /// The step's τ-length.
    pub h: f64,
    /// The arc length it was given (an upper bound of its length).
    pub arc: f64,
}

/// The launch point of camera rays: what their starting states share (the
/// rate's dx/dτ = v is each ray's own).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Launch {
    x: V3,
    n0: f64,
    rate: RayRate,
}

impl Launch {
    /// The state and rate of the ray along the unit `dir`: v = n·dir.
    pub fn along(&self, dir: DVec3) -> (RayState, RayRate) {
        let v = V3::new(dir.x, dir.y, dir.z) * self.n0;
        (
            RayState {
                x: self.x,
                v,
                s: 0.0,
            },
            RayRate { dx: v, ..self.rate },
        )
    }
}

/// One step of a path.
enum Advance {
    /// Moved by this much arc (an upper bound); `free_after`: no object can be
    /// met from here on.
    Moved { arc: f64, free_after: bool },
    /// The ray ended `at` this arc (upper bound) into the step.
    End { at: f64, outcome: Outcome },
}

/// A ray's path, as the sphere tracer drives it.
trait RayPath {
    type State: Copy;
    fn state(&self) -> Self::State;
    fn restore(&mut self, s: Self::State);
    fn position(&self) -> DVec3;
    /// Position and dx/dτ (|dx/dτ| ≈ n) where the ray is.
    fn probe(&self) -> (DVec3, DVec3);
    /// The unit tangent of a ray vector from [`RayPath::probe`] (a path whose
    /// probe gives it unit already returns it as it is).
    #[inline]
    fn unit(v: DVec3) -> DVec3 {
        v.normalize()
    }
    /// Arc length from the camera (for the hit tolerance).
    fn arc(&self) -> f64;
    /// Moves on by at most `limit` of arc (unlimited when `None`: no object can
    /// be met any more).
    fn advance(&mut self, limit: Option<f64>, stats: &mut MarchStats) -> Advance;
    /// The ray's fate from position `p` with ray vector `v`, if decided.
    fn fate(&self, p: DVec3, v: DVec3) -> Option<Fate>;
    /// Moves the ray over a stretch where nothing can be hit, if it is in
    /// one; `Some(true)` when no object can be met any more.
    fn skip_gap(&mut self) -> Option<bool> {
        None
    }
}

/// The over-relaxed step not yet verified.
struct Pending<S> {
    saved: S,
    /// Arc from the saved point known to be free.
    safe: f64,
    /// Arc of the over-relaxed step.
    total: f64,
}

impl Marcher<'_> {
    /// Traces the ray from `origin` along the unit `dir` by integrating it.
    pub fn march(&self, origin: DVec3, dir: DVec3, stats: &mut MarchStats) -> Outcome {
        self.march_ahead(self.launch(origin, dir, stats), &[], stats)
    }

    /// [`Marcher::march`] from a launch `start` ([`Marcher::launch`]) with
    /// the ray's first RK4 steps already integrated ([`super::packs`]):
    /// `ahead[k]` is the k-th step from there, as [`Marcher::step_length`]
    /// makes them; past the last one the ray is integrated here.
    pub fn march_ahead(
        &self,
        start: (RayState, RayRate),
        ahead: &[AheadStep],
        stats: &mut MarchStats,
    ) -> Outcome {
        let (y, f) = start;
        let mut path = CurvedPath {
            marcher: self,
            seg: Segment {
                y0: y,
                f0: f,
                y1: y,
                f1: f,
                h: 0.0,
            },
            theta: 1.0,
            arc_per_theta: 0.0,
            ground_theta: None,
            n_max: self.step_n_max(),
            ahead,
            next: 0,
        };
        self.drive(&mut path, stats)
    }

    /// The state and rate a ray from `origin` along the unit `dir` starts
    /// with: v = n·dir.
    pub fn launch(&self, origin: DVec3, dir: DVec3, stats: &mut MarchStats) -> (RayState, RayRate) {
        self.launch_at(origin, stats).along(dir)
    }

    /// What every ray launched from `origin` shares.
    pub fn launch_at(&self, origin: DVec3, stats: &mut MarchStats) -> Launch {
        let field = self.air.optics();
        let x = V3::new(origin.x, origin.y, origin.z);
        let n0 = 1.0 + crate::medium::IndexField::delta(&field, x);
        let y = RayState {
            x,
            v: V3::new(0.0, 0.0, 0.0),
            s: 0.0,
        };
        Launch {
            x,
            n0,
            rate: rate(&field, &y, &mut stats.medium_evaluations),
        }
    }

    /// [`Air::step_n_max`] of the marcher's air.
    pub fn step_n_max(&self) -> f64 {
        self.air.step_n_max()
    }

    /// The arc length of the RK4 step a ray at `x` takes next.
    #[inline]
    pub fn step_length(&self, x: V3) -> f64 {
        self.air.step_at(dvec(x)).min(self.max_distance)
    }

    /// Traces a camera ray along an interpolated path of `table`.
    pub fn march_table(
        &self,
        table: &PathTable,
        ray: &TableRay,
        stats: &mut MarchStats,
    ) -> Outcome {
        let mut path = TablePathRay {
            table,
            ray,
            tau: 0.0,
        };
        self.drive(&mut path, stats)
    }

    fn drive<P: RayPath>(&self, path: &mut P, stats: &mut MarchStats) -> Outcome {
        let kappa = self.air.curvature_max();
        let mut free = self.distance.objects().is_empty();
        let mut budget = 0.0f64;
        let mut since = 0.0f64;
        let mut omega = self.omega;
        let mut pending: Option<Pending<P::State>> = None;
        let mut queries = 0u32;
        let mut near = NearCache::default();
        // Radius at the previous query and the step taken from there.
        let mut last: Option<(f64, f64)> = None;
        loop {
            if !free && budget <= 0.0 {
                if pending.is_none() {
                    match path.skip_gap() {
                        None => {}
                        Some(false) => last = None,
                        Some(true) => {
                            free = true;
                            continue;
                        }
                    }
                }
                let (p, v) = path.probe();
                let t = P::unit(v);
                let (q, free_arc) =
                    self.distance
                        .probe(p, t, kappa, &mut stats.counters, &mut near);
                queries += 1;
                if let Some(pd) = pending.take()
                    && (q.radius < 0.0 || pd.safe + q.radius < pd.total)
                {
                    // The spheres do not overlap: the over-relaxed step may
                    // have jumped a surface. Back to its start, plain from now.
                    path.restore(pd.saved);
                    omega = 1.0;
                    budget = pd.safe;
                    since = 0.0;
                    last = None;
                    stats.fallbacks += 1;
                    continue;
                }
                if q.radius < self.tolerance.at(path.arc()) || queries >= MAX_QUERIES {
                    return self.object_hit(path, q, p, t);
                }
                // Everything up to here is verified: decide the fate if we can.
                match path.fate(p, v) {
                    None => {}
                    Some(Fate::Sky(direction)) => return Outcome::Sky { direction },
                    Some(Fate::GroundBound) => {
                        free = true;
                        continue;
                    }
                }
                // Over-relax only as far as a planar surface approached at the
                // rate seen since the last query would still let the spheres
                // overlap (r + r − a·L ≥ L ⇔ L ≤ 2r/(1 + a)), so head-on
                // approaches take plain steps instead of failing.
                let factor = match last {
                    Some((r_prev, l_prev)) if l_prev > 0.0 => {
                        let a = ((r_prev - q.radius) / l_prev).clamp(0.0, 1.0);
                        omega.min(0.9 * 2.0 / (1.0 + a)).max(1.0)
                    }
                    // No history: a plain first step (the nearest surface may
                    // lie straight ahead).
                    _ => 1.0,
                };
                let relaxed = factor * q.radius;
                since = 0.0;
                if relaxed > free_arc {
                    pending = Some(Pending {
                        saved: path.state(),
                        safe: free_arc,
                        total: relaxed,
                    });
                    budget = relaxed;
                } else {
                    budget = free_arc;
                }
                last = Some((q.radius, budget));
            }
            match path.advance((!free).then_some(budget), stats) {
                Advance::Moved { arc, free_after } => {
                    budget -= arc;
                    since += arc;
                    if free_after {
                        if let Some(pd) = pending.take() {
                            if since > pd.safe {
                                path.restore(pd.saved);
                                omega = 1.0;
                                budget = pd.safe;
                                since = 0.0;
                                last = None;
                                stats.fallbacks += 1;
                                continue;
                            }
                        }
                        free = true;
                    }
                }
                Advance::End { at, outcome } => {
                    if let Some(pd) = pending.take()
                        && since + at > pd.safe
                        && !self.covers(path, &pd, since, at, stats)
                    {
                        path.restore(pd.saved);
                        omega = 1.0;
                        budget = pd.safe;
                        since = 0.0;
                        last = None;
                        stats.fallbacks += 1;
                        continue;
                    }
                    return outcome;
                }
            }
        }
    }

    /// Whether one query here shows that the unverified span, from the saved
    /// point to `at` beyond here, is free: the sphere here must overlap the
    /// safe part behind and reach the event ahead.
    fn covers<P: RayPath>(
        &self,
        path: &P,
        pd: &Pending<P::State>,
        since: f64,
        at: f64,
        stats: &mut MarchStats,
    ) -> bool {
        let r = self
            .distance
            .query(path.position(), &mut stats.counters)
            .radius;
        r >= at && pd.safe + r >= since
    }

    fn object_hit<P: RayPath>(&self, path: &P, q: Query, point: DVec3, t: DVec3) -> Outcome {
        let index = match q.object {
            Some(i) => i,
            None => nearest_object(self.distance.objects(), point)
                .1
                .unwrap_or(0),
        };
        Outcome::Object {
            index,
            point,
            direction: t,
            distance: path.arc(),
        }
    }
}

/// A ray integrated step by step. RK4 steps are as long as the air allows
/// ([`Air::step_at`]); sphere tracing then walks along each step's quintic
/// Hermite interpolant (accurate to O(h⁶), far below RK4's own error), so the
/// number of distance queries and the number of RK4 steps are independent.
struct CurvedPath<'m, 'a> {
    marcher: &'m Marcher<'a>,
    /// The current step.
    seg: Segment<f64>,
    /// Where on it the ray is, θ ∈ [0, 1].
    theta: f64,
    /// An upper bound of the arc length per unit θ (h·n_max).
    arc_per_theta: f64,
    /// The step's first ground crossing.
    ground_theta: Option<f64>,
    n_max: f64,
    /// Steps integrated ahead, and the next one to take.
    ahead: &'m [AheadStep],
    next: usize,
}

/// The glam vector of a tracer vector.
#[inline]
pub(super) fn dvec(v: V3) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

impl CurvedPath<'_, '_> {
    /// Integrates the next step from the end of the current one.
    fn next_step(&mut self, stats: &mut MarchStats) {
        let m = self.marcher;
        let (y, f) = (self.seg.y1, self.seg.f1);
        let (y1, f1, h, h_arc) = match self.ahead.get(self.next) {
            // Integrated ahead (and counted there) from this very state.
            Some(a) => {
                self.next += 1;
                (a.y, a.f, a.h, a.arc)
            }
            None => {
                let h_arc = m.step_length(y.x);
                let h = h_arc / self.n_max;
                let (y1, f1) = rk4_step(&m.air.optics(), &y, &f, h, &mut stats.medium_evaluations);
                stats.rk4_steps += 1;
                (y1, f1, h, h_arc)
            }
        };
        self.seg = Segment {
            y0: y,
            f0: f,
            y1,
            f1,
            h,
        };
        self.theta = 0.0;
        self.arc_per_theta = h_arc;
        self.ground_theta = if m.ground {
            ground_crossing(&self.seg, m.air.earth())
        } else {
            None
        };
    }
}

impl RayPath for CurvedPath<'_, '_> {
    type State = (Segment<f64>, f64, f64, Option<f64>, usize);

    fn state(&self) -> Self::State {
        (
            self.seg,
            self.theta,
            self.arc_per_theta,
            self.ground_theta,
            self.next,
        )
    }

    fn restore(&mut self, s: Self::State) {
        (
            self.seg,
            self.theta,
            self.arc_per_theta,
            self.ground_theta,
            self.next,
        ) = s;
    }

    fn position(&self) -> DVec3 {
        dvec(self.seg.position(self.theta))
    }

    fn probe(&self) -> (DVec3, DVec3) {
        if self.seg.h == 0.0 {
            // Before the first step: the launch point and direction.
            return (dvec(self.seg.y1.x), dvec(self.seg.y1.v));
        }
        let (x, dx) = self.seg.position_and_slope(self.theta);
        (dvec(x), dvec(dx) * (1.0 / self.seg.h))
    }

    fn arc(&self) -> f64 {
        self.seg.y0.s + self.theta * (self.seg.y1.s - self.seg.y0.s)
    }

    fn fate(&self, p: DVec3, v: DVec3) -> Option<Fate> {
        self.marcher.air.fate(p, v)
    }

    fn advance(&mut self, limit: Option<f64>, stats: &mut MarchStats) -> Advance {
        let m = self.marcher;
        if self.theta >= 1.0 {
            self.next_step(stats);
        }
        let room = (1.0 - self.theta) * self.arc_per_theta;
        let go = limit.map_or(room, |l| l.min(room));
        let target = if go >= room {
            1.0
        } else {
            self.theta + go / self.arc_per_theta
        };
        if let Some(tg) = self.ground_theta
            && tg <= target
        {
            let st = self.seg.state(tg);
            let point = on_ground(st.x, m.air.earth());
            return Advance::End {
                at: (tg - self.theta).max(0.0) * self.arc_per_theta,
                outcome: Outcome::Ground {
                    point,
                    direction: dvec(st.v).normalize(),
                    distance: st.s,
                },
            };
        }
        let (s0, s1) = (self.seg.y0.s, self.seg.y1.s);
        if s1 >= m.max_distance {
            let t_max = ((m.max_distance - s0) / (s1 - s0)).clamp(0.0, 1.0);
            if t_max <= target {
                let st = self.seg.state(t_max);
                return Advance::End {
                    at: (t_max - self.theta).max(0.0) * self.arc_per_theta,
                    outcome: Outcome::Sky {
                        direction: m.air.sky_direction(dvec(st.x), dvec(st.v)),
                    },
                };
            }
        }
        self.theta = target;
        Advance::Moved {
            arc: go,
            free_after: false,
        }
    }
}

/// The first θ ∈ [0, 1] where the step is below the ground (y = 0 or the
/// sphere): the tracer's own test (an end below ground, or a dip between two
/// nodes above it), so renders and the fitter's occlusion flags agree.
fn ground_crossing(seg: &Segment<f64>, earth: Earth) -> Option<f64> {
    if earth.height(seg.y0.x) < 0.0 {
        return Some(0.0);
    }
    crate::trace::first_ground_crossing(seg, earth)
}

/// The ground point at a crossing found at `x`: y = 0 on the flat ground,
/// the foot of x's vertical on the sphere (x is within rounding of it).
fn on_ground(x: V3, earth: Earth) -> DVec3 {
    match earth {
        Earth::Flat => DVec3::new(x.x, 0.0, x.z),
        Earth::Round { .. } => dvec(earth.foot(x)),
    }
}

/// A camera ray on an interpolated table path.
struct TablePathRay<'t> {
    table: &'t PathTable,
    ray: &'t TableRay,
    tau: f64,
}

impl RayPath for TablePathRay<'_> {
    type State = f64;

    fn state(&self) -> f64 {
        self.tau
    }

    fn restore(&mut self, s: f64) {
        self.tau = s;
    }

    fn position(&self) -> DVec3 {
        self.table.position(self.ray, self.tau).0
    }

    fn probe(&self) -> (DVec3, DVec3) {
        self.table.position(self.ray, self.tau)
    }

    /// The table's tangent is unit already.
    #[inline]
    fn unit(v: DVec3) -> DVec3 {
        v
    }

    fn arc(&self) -> f64 {
        self.tau
    }

    fn fate(&self, _p: DVec3, _v: DVec3) -> Option<Fate> {
        // Decided once for all when the table ray was built.
        None
    }

    fn skip_gap(&mut self) -> Option<bool> {
        match self.ray.next_window(self.tau) {
            None => Some(true),
            Some(t) if t > self.tau => {
                self.tau = t;
                Some(false)
            }
            Some(_) => None,
        }
    }

    fn advance(&mut self, limit: Option<f64>, _stats: &mut MarchStats) -> Advance {
        let n_max = self.table.n_max();
        let r = self.ray;
        let end = r.tau_objects_end;
        let dt = limit.map_or(f64::INFINITY, |l| l / n_max);
        if self.tau + dt < end {
            self.tau += dt;
            return Advance::Moved {
                arc: dt * n_max,
                free_after: false,
            };
        }
        let at = (end - self.tau).max(0.0) * n_max;
        let outcome = if r.tau_ground <= r.tau_max {
            let (mut point, direction) = self.table.position(r, r.tau_ground);
            point.y = 0.0;
            Outcome::Ground {
                point,
                direction,
                distance: r.tau_ground,
            }
        } else {
            let (s, c) = r.final_elevation.sin_cos();
            Outcome::Sky {
                direction: DVec3::new(r.horizontal.x * c, s, r.horizontal.y * c),
            }
        };
        Advance::End { at, outcome }
    }
}
