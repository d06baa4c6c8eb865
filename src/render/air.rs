//! What the renderer needs to know about the air beyond δ and ∇δ: bounds on n
//! and on the rays' curvature (for safe sphere-tracing steps), where the air is
//! not stratified (hot-spot zones), how long an RK4 step may be, and — from
//! Snell's invariant — when a ray's fate is already decided.
//!
//! # Snell decisions
//!
//! Outside the hot-spot zones δ depends on y alone, so a ray keeps its vertical
//! plane and `c = n·cos(elevation) = |v_h|` (v = n·t). It can reach a height y'
//! only if `n(y') ≥ c`. With the stratified profile tabulated once (prefix and
//! suffix minima of δ over height), a ray that will never again meet an object
//! nor a zone is decided at once:
//!
//! - rising with `min_{y' ≥ y} n(y') > c`: it never turns down and leaves to
//!   the sky, seen along its direction at the top of the model (where δ is
//!   constant), from Snell: `cos(elevation_∞) = c / n_∞`;
//! - descending with `min_{0 ≤ y' ≤ y} n(y') > c`: it reaches the ground (still
//!   integrated, to find where, but with no more distance queries);
//! - descending and turning before the ground (some tabulated n below it is < c),
//!   then escaping as above: sky.
//!
//! Anything else (a ray trapped in a duct, a ray inside a zone) is integrated.
//!
//! # Over the round earth
//!
//! Over the sphere of radius R (centre (0, −R, 0)) the medium takes the height
//! h above the sphere for y ([`Optics`], [`OnEarth`]), the zones are cylinders
//! in (x, h, z), and the rays are integrated in that air. Outside the zones
//! the air is spherically symmetric, so a ray stays in the plane through the
//! centre and its own direction and keeps Bouguer's invariant
//! `L = n·r·cos(elevation) = |(p − c) × v|` (r = R + h). With the profile of
//! the modified refractivity M(h) = n(h)·(1 + h/R) − 1 tabulated in place of
//! δ, the decisions above hold word for word with `c = L/R`: a ray reaches h
//! only if 1 + M(h) ≥ c. Objects and zones count as met unless their bounding
//! ball misses the ray's plane, its heights or the half of the plane ahead of
//! the ray. A ray that escapes shows the sky along the straight line it
//! leaves the profile's top on: its elevation there from Bouguer, turned by
//! the angle the ray sweeps around the centre on its way (integrated over the
//! tabulated M, see [`Air::sky_direction`]); above the top, a rising ray is
//! straight. No path table is built over the sphere (its paths are those of
//! the flat ground): every ray is integrated.

use super::accel::Aabb;
use crate::math::V3;
use crate::medium::cull::{HotSpotGrid, Reach};
use crate::medium::{Field, IndexField, LogisticMedium, Medium, VerticalFeature};
use crate::trace::batch::PackStepper;
use crate::trace::{Earth, OnEarth};
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Where a logistic term's σ is within e^(−ZONE_UNITS) of its limit: the term
/// is then constant to far below anything an image can show (δ changes by
/// < 1e-8 of the term's amplitude, i.e. < 1e-12 in n).
const ZONE_UNITS: f64 = 20.0;

/// Largest factor by which a step may grow over the scene's step.
const STEP_GROWTH_MAX: f64 = 32.0;

/// A hot spot's region of influence: a vertical cylinder (disc radius R plus
/// the rim's tail) up to the height where its layer has died out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Zone {
    /// Centre x.
    pub x: f64,
    /// Centre z.
    pub z: f64,
    /// Radius of the cylinder (metres).
    pub radius: f64,
    /// Top of the cylinder (metres; infinite for a layer that grows upward).
    pub top: f64,
    /// |a| of a layer decaying upward (a < 0), else 0.
    pub decay: f64,
}

impl Zone {
    fn contains(&self, p: DVec3) -> bool {
        p.y < self.top && DVec2::new(p.x - self.x, p.z - self.z).length() < self.radius
    }

    /// How much longer than the scene's step an RK4 step may be at height y:
    /// every derivative of a layer σ(y/a) with a < 0 (and of its rim term)
    /// decays like e^(−y/|a|) above the ground, and RK4's error per unit length
    /// grows like h⁴ times those derivatives, so h ∝ e^(y/(4|a|)) keeps the
    /// error per metre at its value at the ground. A layer that grows upward
    /// (a > 0) keeps its rim at every height: no growth.
    fn step_growth(&self, y: f64) -> f64 {
        if self.decay > 0.0 {
            (y.max(0.0) / (4.0 * self.decay))
                .min(STEP_GROWTH_MAX.ln())
                .exp()
        } else {
            1.0
        }
    }

    fn distance(&self, p: DVec3) -> f64 {
        let dh = (DVec2::new(p.x - self.x, p.z - self.z).length() - self.radius).max(0.0);
        let dv = (p.y - self.top).max(0.0);
        dh.hypot(dv)
    }
}

/// The stratified part of δ tabulated over height, with running minima for
/// Snell decisions.
#[derive(Clone, Debug)]
struct Profile {
    dy: f64,
    delta: Vec<f64>,
    prefix_min: Vec<f64>,
    suffix_min: Vec<f64>,
    /// Bound on how far δ can dip between two samples, plus rounding.
    margin: f64,
}

impl Profile {
    fn top(&self) -> f64 {
        self.dy * (self.delta.len() - 1) as f64
    }

    /// A lower bound of δ over [y, ∞) (y ≥ 0).
    fn min_above(&self, y: f64) -> f64 {
        // `as usize` is the floor here (negatives give 0), without libm.
        let i = ((y / self.dy) as usize).min(self.delta.len() - 1);
        self.suffix_min[i] - self.margin
    }

    /// A lower bound of δ over [0, y].
    fn min_below(&self, y: f64) -> f64 {
        let i = ((y / self.dy).ceil() as usize).min(self.delta.len() - 1);
        self.prefix_min[i] - self.margin
    }

    /// Whether some tabulated height in [0, y] has δ < `c1` exactly (then a
    /// descending ray with `n·cos = 1 + c1` turns before reaching it).
    fn dips_below(&self, y: f64, c1: f64) -> bool {
        // `as usize` is the floor here (negatives give 0), without libm.
        let i = ((y / self.dy) as usize).min(self.delta.len() - 1);
        self.prefix_min[i] < c1
    }

    fn at_top(&self) -> f64 {
        self.delta[self.delta.len() - 1]
    }
}

/// The fate of a ray decided early (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fate {
    /// It will meet nothing: the sky, seen along this final unit direction.
    Sky(DVec3),
    /// It will reach the ground and nothing else: integrate it there without
    /// distance queries.
    GroundBound,
}

/// The air as the renderer sees it.
#[derive(Clone, Debug)]
pub struct Air {
    field: Field,
    straight: bool,
    stratified: bool,
    n_max: f64,
    curvature_max: f64,
    step_inside: f64,
    step_outside: f64,
    zones: Vec<Zone>,
    /// The zones near a point, for many hot spots: each zone's disc grown by
    /// the longest step (a zone farther away than that cannot shorten a step
    /// nor contain the point), so a step pays for the zones nearby only.
    near_zones: Option<HotSpotGrid>,
    profile: Profile,
    ground: bool,
    objects: Option<Aabb>,
    earth: Earth,
}

/// The air's index field as the rays see it: the medium itself over the flat
/// ground, [`OnEarth`] (heights above the sphere) over the round earth. Over
/// the flat ground every call goes straight to the medium, so flat renders
/// are bit for bit those of the medium alone.
#[derive(Clone, Copy, Debug)]
pub struct Optics<'a> {
    field: &'a Field,
    earth: Earth,
}

impl IndexField<f64> for Optics<'_> {
    #[inline]
    fn delta(&self, p: V3) -> f64 {
        match self.earth {
            Earth::Flat => self.field.delta(p),
            Earth::Round { radius } => OnEarth {
                field: self.field,
                radius,
            }
            .delta(p),
        }
    }

    #[inline]
    fn delta_gradient(&self, p: V3) -> (f64, V3) {
        match self.earth {
            Earth::Flat => self.field.delta_gradient(p),
            Earth::Round { radius } => OnEarth {
                field: self.field,
                radius,
            }
            .delta_gradient(p),
        }
    }

    fn is_stratified(&self) -> bool {
        self.earth.is_flat() && self.field.is_stratified()
    }

    fn ceiling(&self) -> f64 {
        self.field.ceiling()
    }

    fn step_limit(&self, h: f64, vh: f64) -> f64 {
        self.field.step_limit(h, vh)
    }
}

impl Air {
    /// Analyses `medium` (or δ ≡ 0 when `straight`) for rendering with RK4
    /// steps of `step` metres. `ground`: whether the ground (the plane y = 0,
    /// or the sphere of `earth`) stops rays; `objects`: the box holding every
    /// object (None: no objects).
    pub fn new(
        medium: &Medium,
        straight: bool,
        step: f64,
        ground: bool,
        objects: Option<Aabb>,
        earth: Earth,
    ) -> Air {
        let medium = if straight || !medium.has_terms() {
            Medium::Logistic(LogisticMedium::vacuum())
        } else {
            medium.clone()
        };
        let straight = !medium.has_terms();
        let field = medium.field();
        let envelope = medium.envelope();
        let (n_max, curvature_max) = if straight {
            (1.0, 0.0)
        } else {
            // A ray's curvature is |∇n ⊥ t| / n ≤ |∇δ|max / n_min.
            (envelope.n_max, envelope.gradient_max / envelope.n_min)
        };

        let zones: Vec<Zone> = envelope
            .patches
            .iter()
            .map(|h| Zone {
                x: h.x,
                z: h.z,
                radius: h.radius + ZONE_UNITS / h.edge,
                top: if h.rate < 0.0 {
                    ZONE_UNITS * h.rate.abs()
                } else {
                    f64::INFINITY
                },
                decay: if h.rate < 0.0 { h.rate.abs() } else { 0.0 },
            })
            .collect();

        // Finest feature of the whole air, and of its stratified part: steps
        // outside the zones may grow by their ratio (capped), since RK4's error
        // scales with (step / feature)^4.
        let strat_scale = envelope
            .layers
            .iter()
            .map(|t| t.scale)
            .fold(f64::INFINITY, f64::min);
        let fine_scale = envelope
            .patches
            .iter()
            .flat_map(|h| [h.rate.abs(), 1.0 / h.edge])
            .fold(strat_scale, f64::min);
        let step_inside = if straight { f64::INFINITY } else { step };
        let step_outside = if straight {
            f64::INFINITY
        } else if fine_scale.is_finite() {
            step * (strat_scale / fine_scale).clamp(1.0, STEP_GROWTH_MAX)
        } else {
            STEP_GROWTH_MAX * step
        };

        let profile = match earth {
            Earth::Flat => Self::profile(&field, &envelope.layers, curvature_max * n_max),
            Earth::Round { radius } => Self::modified_profile(
                &field,
                &envelope.layers,
                curvature_max * n_max,
                n_max,
                radius,
            ),
        };
        let near_zones = HotSpotGrid::new(
            &zones
                .iter()
                .map(|z| Reach {
                    x: z.x,
                    z: z.z,
                    radius: z.radius + step_outside,
                })
                .collect::<Vec<_>>(),
        );
        Air {
            field,
            near_zones,
            straight,
            stratified: envelope.patches.is_empty(),
            n_max,
            curvature_max,
            step_inside,
            step_outside,
            zones,
            profile,
            ground,
            objects,
            earth,
        }
    }

    /// The profile over the sphere of radius `r`: the modified refractivity
    /// M(h) = n(h)·(1 + h/R) − 1 in place of δ, so that Bouguer's invariant
    /// of a ray, L = n·r·cos(elevation) (r = R + h), reads as Snell's does on
    /// the flat ground: the ray reaches h only if 1 + M(h) ≥ L/R. The margin
    /// bounds M's slope, δ's plus n/R.
    fn modified_profile(
        field: &Field,
        layers: &[VerticalFeature],
        gradient_max: f64,
        n_max: f64,
        r: f64,
    ) -> Profile {
        let flat = Self::profile(field, layers, gradient_max);
        let top = flat.top();
        let delta: Vec<f64> = flat
            .delta
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let h = i as f64 * flat.dy;
                // (1 + δ)(1 + h/R) − 1 without losing δ to the 1.
                d + h / r + d * h / r
            })
            .collect();
        let n = delta.len();
        let mut prefix_min = delta.clone();
        for i in 1..n {
            prefix_min[i] = prefix_min[i - 1].min(delta[i]);
        }
        let mut suffix_min = delta.clone();
        for i in (0..n - 1).rev() {
            suffix_min[i] = suffix_min[i + 1].min(delta[i]);
        }
        let slope = gradient_max * (1.0 + top / r) + n_max / r;
        Profile {
            dy: flat.dy,
            delta,
            prefix_min,
            suffix_min,
            margin: 0.5 * slope * flat.dy + 1e-15,
        }
    }

    /// The shape of the ground.
    pub fn earth(&self) -> Earth {
        self.earth
    }

    /// The index field the rays are integrated in ([`Optics`]).
    pub fn optics(&self) -> Optics<'_> {
        Optics {
            field: &self.field,
            earth: self.earth,
        }
    }

    /// `p` with its height above the ground for y (the frame the medium and
    /// its zones are written in); `p` itself over the flat ground.
    #[inline]
    fn local(&self, p: DVec3) -> DVec3 {
        match self.earth {
            Earth::Flat => p,
            Earth::Round { .. } => DVec3::new(p.x, self.earth.height(V3::new(p.x, p.y, p.z)), p.z),
        }
    }

    fn profile(field: &Field, layers: &[VerticalFeature], gradient_max: f64) -> Profile {
        let top = layers
            .iter()
            .map(|l| l.centre + 2.0 * ZONE_UNITS * l.scale)
            .fold(100.0, f64::max)
            .min(50_000.0);
        let finest = layers.iter().map(|l| l.scale).fold(f64::INFINITY, f64::min);
        let dy = (finest / 16.0).max(top / 400_000.0).min(1.0);
        let n = (top / dy).ceil() as usize + 1;
        // Far outside every hot spot the rim factor w underflows to exactly 0,
        // leaving the stratified terms (with the full S, as in the model).
        let far = 1e12;
        // Up to ~400,000 evaluations: on all threads (the same values, in
        // order), as the rest of the set-up waits on them.
        let delta: Vec<f64> = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| field.delta(V3::new(far, i as f64 * dy, far)))
            .collect();
        let mut prefix_min = delta.clone();
        for i in 1..n {
            prefix_min[i] = prefix_min[i - 1].min(delta[i]);
        }
        let mut suffix_min = delta.clone();
        for i in (0..n - 1).rev() {
            suffix_min[i] = suffix_min[i + 1].min(delta[i]);
        }
        Profile {
            dy,
            delta,
            prefix_min,
            suffix_min,
            margin: 0.5 * gradient_max * dy + 1e-15,
        }
    }

    /// The compiled field (δ ≡ 0 when straight).
    pub fn field(&self) -> &Field {
        &self.field
    }

    /// Whether δ ≡ 0 (rays are straight lines).
    pub fn is_straight(&self) -> bool {
        self.straight
    }

    /// What integrates packs of rays in SIMD lanes through this air
    /// ([`super::packs`]), where that pays: curved rays through hot-spot
    /// zones or over the round earth (where no path table serves them; over
    /// the flat ground stratified air takes a table, or few steps), in a
    /// medium kind the lanes evaluate.
    pub fn pack_stepper(&self) -> Option<PackStepper<'_>> {
        if self.straight || (self.zones.is_empty() && self.earth.is_flat()) {
            return None;
        }
        PackStepper::new(&self.field, self.earth)
    }

    /// Whether δ depends on the height alone.
    pub fn is_stratified(&self) -> bool {
        self.stratified
    }

    /// An upper bound of n over all space: a τ step h covers at most h·n_max
    /// of arc length.
    pub fn n_max(&self) -> f64 {
        self.n_max
    }

    /// The bound on n that turns a step's arc length into its τ-length
    /// (h = arc / bound): a hair above [`Air::n_max`], so that rounding in n
    /// never lets a step run further than the arc it was given; 1 for
    /// straight rays.
    pub fn step_n_max(&self) -> f64 {
        if self.straight {
            1.0
        } else {
            self.n_max * (1.0 + 1e-9)
        }
    }

    /// An upper bound of a ray's curvature |dt/ds| = |∇n⊥|/n (1/metre).
    pub fn curvature_max(&self) -> f64 {
        self.curvature_max
    }

    /// The hot-spot zones.
    pub fn zones(&self) -> &[Zone] {
        &self.zones
    }

    /// Whether `p` lies in a hot-spot zone (where the air is not stratified).
    pub fn in_zone(&self, p: DVec3) -> bool {
        let p = self.local(p);
        self.zones_near(p).any(|z| z.contains(p))
    }

    /// The zones that can contain the point `p` (local coordinates) or lie
    /// within the longest step of it: all of them where there is no grid.
    #[inline]
    fn zones_near(&self, p: DVec3) -> impl Iterator<Item = &Zone> {
        let (listed, all) = match &self.near_zones {
            Some(grid) => (grid.candidates(p.x, p.z), &[][..]),
            None => (&[][..], &self.zones[..]),
        };
        listed.iter().map(|&j| &self.zones[j as usize]).chain(all)
    }

    /// The RK4 step (arc length, metres) to take from `p`: in a zone, the
    /// scene's step, grown with the height above a layer that decays upward
    /// (by e^(y/(4|a|)), which keeps RK4's error per metre constant); outside, the longer stratified step, but
    /// never so long that a step leaps into a zone from afar. Infinite for
    /// straight rays.
    pub fn step_at(&self, p: DVec3) -> f64 {
        if self.zones.is_empty() {
            return self.step_outside;
        }
        let p = self.local(p);
        let mut inside = f64::INFINITY;
        let mut approach = f64::INFINITY;
        // A zone farther than `step_outside` gives max(grown, d) above it,
        // which cannot lower the result: the nearby zones decide.
        for z in self.zones_near(p) {
            let grown = self.step_inside * z.step_growth(p.y);
            let d = z.distance(p);
            if d == 0.0 {
                inside = inside.min(grown);
            } else {
                approach = approach.min(grown.max(d));
            }
        }
        self.step_outside.min(inside).min(approach)
    }

    /// δ of the stratified terms at height y (exact, from the field).
    pub fn stratified_delta(&self, y: f64) -> f64 {
        self.field.delta(V3::new(1e12, y, 1e12))
    }

    /// Whether a ray at height `y` ≥ 0 with `c = |v_h|`, rising, can never
    /// turn down again (Snell, with the profile's margin: false when unsure).
    pub fn escapes(&self, y: f64, c: f64) -> bool {
        y >= 0.0 && self.profile.min_above(y) > c - 1.0
    }

    /// The direction in which a ray with horizontal unit direction `h` and
    /// invariant `c` leaves the top of the model (where δ is constant).
    pub fn asymptotic_direction(&self, h: DVec2, c: f64) -> DVec3 {
        let n_top = 1.0 + self.profile.at_top();
        let vy = (n_top * n_top - c * c).max(0.0).sqrt();
        DVec3::new(h.x * c, vy, h.y * c).normalize()
    }

    /// The elevation (radians) at which a ray leaves the top of the model.
    pub fn asymptotic_elevation(&self, c: f64) -> f64 {
        let n_top = 1.0 + self.profile.at_top();
        (c / n_top).clamp(-1.0, 1.0).acos()
    }

    /// Height of the top of the tabulated profile (metres).
    pub fn profile_top(&self) -> f64 {
        self.profile.top()
    }

    /// The RK4 step inside the hot-spot zones and outside them (metres; see
    /// [`Air::step_at`]), for the GPU previewer, which takes the same steps.
    pub fn steps(&self) -> (f64, f64) {
        (self.step_inside, self.step_outside)
    }

    /// The tabulated stratified profile, for the GPU previewer's Snell
    /// decisions: the height spacing, the margin of the minima, and per height
    /// δ (over the round earth: the modified refractivity M), its minimum
    /// below and its minimum above.
    pub fn profile_tables(&self) -> (f64, f64, &[f64], &[f64], &[f64]) {
        let p = &self.profile;
        (p.dy, p.margin, &p.delta, &p.prefix_min, &p.suffix_min)
    }

    /// The fate of a ray at `p` with ray vector `v` (= n·t), if it is already
    /// decided: see the module documentation. `None`: keep integrating.
    pub fn fate(&self, p: DVec3, v: DVec3) -> Option<Fate> {
        self.fate_past(p, v, true)
    }

    /// The direction in which a ray given up on at `p` (at the largest
    /// distance) sees the sky: where it will leave the model if its fate is
    /// decided once objects no longer count (it can only climb away, or it
    /// dips and climbs through stratified air), else its direction here.
    /// Using the limiting direction keeps the sky of a ray independent of
    /// where along its escape the tracer happened to stop.
    pub fn sky_direction(&self, p: DVec3, v: DVec3) -> DVec3 {
        match self.fate_past(p, v, false) {
            Some(Fate::Sky(direction)) => direction,
            _ => v.normalize(),
        }
    }

    /// [`Air::fate`], with or without regard to the objects.
    fn fate_past(&self, p: DVec3, v: DVec3, objects: bool) -> Option<Fate> {
        if let Earth::Round { radius } = self.earth {
            return self.round_fate(p, v, objects, radius);
        }
        if p.y < 0.0 || v.y == 0.0 || self.in_zone(p) {
            return None;
        }
        let vh = DVec2::new(v.x, v.z);
        let c = vh.length();
        let c1 = c - 1.0;
        let rising = v.y > 0.0;
        let escape = self.profile.min_above(p.y) > c1;
        // The heights the ray will visit, and whether it ends on the ground.
        let (low, high, ground_bound) = if rising {
            if !escape {
                return None;
            }
            (p.y, f64::INFINITY, false)
        } else if self.ground && self.profile.min_below(p.y) > c1 {
            (0.0, p.y, true)
        } else if self.profile.dips_below(p.y, c1) && escape {
            (0.0, f64::INFINITY, false)
        } else {
            return None;
        };
        let h = if c > 0.0 { vh / c } else { DVec2::ZERO };
        let origin = DVec2::new(p.x, p.z);
        if let Some(b) = &self.objects
            && objects
            && low <= b.max.y
            && high >= b.min.y
            && b.halfline_meets_xz(origin, h)
        {
            return None;
        }
        for z in &self.zones {
            if low < z.top && halfline_meets_disc(origin, h, DVec2::new(z.x, z.z), z.radius) {
                return None;
            }
        }
        Some(if ground_bound {
            Fate::GroundBound
        } else {
            Fate::Sky(self.asymptotic_direction(h, c))
        })
    }
}

/// Over the round earth: the same decisions from Bouguer's invariant (see
/// the module documentation), with the profile of the modified refractivity.
impl Air {
    fn round_fate(&self, p: DVec3, v: DVec3, objects: bool, radius: f64) -> Option<Fate> {
        let (h, up) = self.earth.height_and_up(V3::new(p.x, p.y, p.z));
        let up = DVec3::new(up.x, up.y, up.z);
        if h.is_nan()
            || h < 0.0
            || self
                .zones_near(DVec3::new(p.x, h, p.z))
                .any(|z| z.contains(DVec3::new(p.x, h, p.z)))
        {
            return None;
        }
        let vr = v.dot(up);
        if vr == 0.0 {
            return None;
        }
        let vt = v - up * vr;
        // L/R = n·r·cos(elevation)/R.
        let c = (radius + h) * vt.length() / radius;
        let c1 = c - 1.0;
        let rising = vr > 0.0;
        // Above the profile's top δ no longer changes and M grows with h: a
        // rising ray there never turns down.
        let above = h >= self.profile.top();
        let escape = (rising && above) || self.profile.min_above(h) > c1;
        let (low, high, ground_bound) = if rising {
            if !escape {
                return None;
            }
            (h, f64::INFINITY, false)
        } else if self.ground && self.profile.min_below(h) > c1 {
            (0.0, h, true)
        } else if self.profile.dips_below(h, c1) && escape {
            (0.0, f64::INFINITY, false)
        } else {
            return None;
        };
        if let Some(b) = &self.objects
            && objects
            && may_meet_ball(p, v, radius, ball(b), low, high)
        {
            return None;
        }
        for z in &self.zones {
            if low >= z.top {
                continue;
            }
            if !z.top.is_finite() {
                return None;
            }
            // The zone's cylinder in world coordinates: heights in [0, top]
            // lie at y ∈ [−ρ²/R − 1, top] within ρ of the axis (ρ ≪ R).
            let rho = (z.x.abs() + z.radius).hypot(z.z.abs() + z.radius);
            let b = Aabb {
                min: DVec3::new(z.x - z.radius, -rho * rho / radius - 1.0, z.z - z.radius),
                max: DVec3::new(z.x + z.radius, z.top, z.z + z.radius),
            };
            if may_meet_ball(p, v, radius, ball(&b), low, high) {
                return None;
            }
        }
        Some(if ground_bound {
            Fate::GroundBound
        } else if rising && above {
            // Straight from here on.
            Fate::Sky(v.normalize())
        } else {
            Fate::Sky(self.round_sky(h, up, vt, vr, c, radius))
        })
    }

    /// The direction in which a ray that escapes leaves the top of the
    /// profile, where it goes straight: its local elevation there follows
    /// from Bouguer, cos e = (L/R) / (1 + M_top), and the local vertical has
    /// turned by the angle φ the ray sweeps around the centre on its way,
    /// dφ/dh = (L/R) / ((1 + h/R)·R·√F), F = (1 + M)² − (L/R)², integrated
    /// over the tabulated M as exactly as a piecewise linear F allows
    /// (∫ dh/√F = 2Δh/(√F_a + √F_b)), which keeps the turning point's
    /// integrable singularity exact. The elevation seen from here is e − φ.
    fn round_sky(&self, h: f64, up: DVec3, vt: DVec3, vr: f64, c: f64, radius: f64) -> DVec3 {
        let vtl = vt.length();
        if vtl == 0.0 {
            return up * vr.signum();
        }
        let forward = vt / vtl;
        // F at the ray's own point, exactly: (r·v_r/R)².
        let f0 = ((radius + h) * vr / radius).powi(2);
        let phi = if vr > 0.0 {
            self.sweep_up(h, f0, c, radius)
        } else {
            let (turn, down) = self.sweep_down(h, f0, c, radius);
            down + self.sweep_up(turn, 0.0, c, radius)
        };
        // acos(c/(1 + M_top)) through 1 − cos = (M_top − (c − 1))/(1 + M_top),
        // which keeps its digits near the horizon (acos near 1 does not).
        let m_top = self.profile.at_top();
        let one_minus_cos = ((m_top - (c - 1.0)) / (1.0 + m_top)).max(0.0);
        let e_top = 2.0 * (0.5 * one_minus_cos).sqrt().min(1.0).asin();
        let e = e_top - phi;
        forward * e.cos() + up * e.sin()
    }

    /// F = (1 + M)² − c² at profile node i.
    fn bouguer_f(&self, i: usize, c: f64) -> f64 {
        let m = self.profile.delta[i];
        // (1 + m)² − c² = (1 + m − c)(1 + m + c), without cancelling 1s.
        (m - (c - 1.0)) * (1.0 + m + c)
    }

    /// φ swept from height `h` (where F = `f`) up to the profile's top, on a
    /// mesh that follows the nodes near `h` and grows by 1/32 of the distance
    /// beyond (the integrand is smooth away from the turning point), in
    /// pieces of at most R/1000 (where 1/(1 + h/R) is linear to 10⁻⁶).
    fn sweep_up(&self, h: f64, f: f64, c: f64, radius: f64) -> f64 {
        let p = &self.profile;
        let last = p.delta.len() - 1;
        let stride_max = ((1e-3 * radius / p.dy) as usize).max(1);
        let i0 = ((h / p.dy).floor() as usize + 1).min(last + 1);
        let (mut ha, mut fa) = (h, f.max(0.0));
        let mut phi = 0.0;
        let mut i = i0;
        while i <= last {
            let hb = i as f64 * p.dy;
            let fb = self.bouguer_f(i, c).max(0.0);
            phi += sweep_piece(ha, fa, hb, fb, c, radius);
            if i == last {
                break;
            }
            (ha, fa) = (hb, fb);
            i = (i + (1 + (i - i0) / 32).min(stride_max)).min(last);
        }
        phi
    }

    /// φ swept from height `h` (where F = `f`) down to the turning height,
    /// where F = 0 (linear between the nodes), and that height.
    fn sweep_down(&self, h: f64, f: f64, c: f64, radius: f64) -> (f64, f64) {
        let p = &self.profile;
        let last = p.delta.len() - 1;
        let (mut ha, mut fa) = (h, f.max(0.0));
        let mut phi = 0.0;
        let mut i = ((h / p.dy).ceil() as usize).min(last + 1);
        while i > 0 {
            i -= 1;
            let hb = i as f64 * p.dy;
            if hb >= ha {
                continue;
            }
            let fb = self.bouguer_f(i, c);
            if fb <= 0.0 {
                let turn = ha - (ha - hb) * fa / (fa - fb);
                phi += sweep_piece(turn, 0.0, ha, fa, c, radius);
                return (turn, phi);
            }
            phi += sweep_piece(hb, fb, ha, fa, c, radius);
            (ha, fa) = (hb, fb);
        }
        (0.0, phi)
    }
}

/// ∫ (c/R) dh / ((1 + h/R)·√F) over [ha, hb] for F linear between fa and fb.
#[inline]
fn sweep_piece(ha: f64, fa: f64, hb: f64, fb: f64, c: f64, radius: f64) -> f64 {
    let s = fa.sqrt() + fb.sqrt();
    if s > 0.0 {
        c / radius * 2.0 * (hb - ha) / s / (1.0 + 0.5 * (ha + hb) / radius)
    } else {
        0.0
    }
}

/// The bounding ball (centre, radius) of a box.
fn ball(b: &Aabb) -> (DVec3, f64) {
    ((b.min + b.max) * 0.5, (b.max - b.min).length() * 0.5)
}

/// Whether a ray at `p` with ray vector `v` over the sphere of radius
/// `radius` may meet the ball (centre, radius) while its height stays in
/// [low, high]: over a spherically symmetric air the ray stays in the plane
/// through the centre, `p` and `v`, and sweeps forward around the centre (by
/// less than half a turn within any scene); the ball must cut that plane,
/// reach the heights, and lie ahead. Conservative: true when unsure. Every
/// quantity is taken relative to `p` (the plane holds p − c, so only the
/// ball's offset from p enters the products), as the shader does in f32.
fn may_meet_ball(
    p: DVec3,
    v: DVec3,
    radius: f64,
    (bc, br): (DVec3, f64),
    low: f64,
    high: f64,
) -> bool {
    if !(bc.is_finite() && br.is_finite()) {
        return true;
    }
    let q = p - DVec3::new(0.0, -radius, 0.0);
    let n = q.cross(v);
    let nl = n.length();
    if nl.is_nan() || nl <= 0.0 {
        return true;
    }
    let normal = n / nl;
    let rel = bc - p;
    if rel.dot(normal).abs() > br {
        return false;
    }
    let hb = Earth::Round { radius }.height(V3::new(bc.x, bc.y, bc.z));
    if hb - br > high || hb + br < low {
        return false;
    }
    let ql = q.length();
    let e1 = q / ql;
    let e2 = normal.cross(e1);
    let (bx, by) = (ql + rel.dot(e1), rel.dot(e2));
    let dp = bx.hypot(by);
    if dp <= br {
        return true;
    }
    let beta = by.atan2(bx);
    let gamma = (br / dp).asin();
    beta + gamma >= 0.0 && beta - gamma < std::f64::consts::PI
}

/// Whether the half-line `o + t·h` (t ≥ 0; h unit or zero) meets the disc.
fn halfline_meets_disc(o: DVec2, h: DVec2, centre: DVec2, radius: f64) -> bool {
    let t = (centre - o).dot(h).max(0.0);
    (o + h * t - centre).length() <= radius
}
