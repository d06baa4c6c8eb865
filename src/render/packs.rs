//! Camera rays through hot-spot air integrated ahead, a pack at a time.
//!
//! Where the air has hot spots no path table serves the rays: each is
//! integrated on its own with RK4, and the scalar field's exponentials (three
//! a hot spot's evaluation, four evaluations a step) were about 40 % of a
//! render's time. Here [`PACK`] neighbouring camera rays are integrated
//! together in SIMD lanes ([`PackStepper`], the batch tracer's RK4 step)
//! before the sphere tracer walks each of them: every lane takes exactly the
//! steps its ray would take on its own (the same launch state, the same step
//! lengths from [`Marcher::step_length`] at each step's start), so
//! [`Marcher::march_ahead`] only reads them back. The steps agree with the
//! scalar ones to rounding (the polynomial exponential is within 1 ulp of
//! libm's); the render is the same to well within its tests' tolerance.
//!
//! # How far ahead
//!
//! A ray is integrated ahead while the air is worth it and the ray surely
//! goes on: it stops at the end of the first step that
//!
//! - ends below the ground (the tracer finds the crossing in that step),
//! - reaches the largest distance,
//! - leaves the ray climbing away from every object and zone for good (its
//!   fate the sky, [`super::air::Air::fate`]: the tracer stops there too),
//! - or is the [`MAX_AHEAD`]-th;
//!
//! and a ray whose fate is the sky from the start is not integrated at all.
//! The rest of a ray, if it needs more, is integrated by the tracer as
//! before. Steps beyond the point where the tracer stops (an object hit) are
//! wasted, but a step in a lane costs about a tenth of a scalar one (30 ns
//! against 400 ns with a hot spot on the CPU this was written on), and the
//! tracer mostly needs them: on `road.json` the packs integrate 19.3 steps a
//! pixel where the tracer alone took 19.2. Neighbouring rays take the same
//! number of steps almost always, so the lanes stay full (over 99.9 % there).

use super::air::Fate;
use super::march::{AheadStep, Launch, MarchStats, Marcher, dvec};
use crate::trace::RayState;
use crate::trace::batch::{PACK, PackCache, PackStepper};
use glam::DVec3;

/// Most steps integrated ahead for one ray.
pub const MAX_AHEAD: usize = 1024;

/// Integrates packs of camera rays ahead; one per thread (it keeps the
/// lanes' cache and the steps' buffers from one pack to the next).
pub struct Packer<'a> {
    stepper: PackStepper<'a>,
    cache: PackCache,
    steps: [Vec<AheadStep>; PACK],
}

impl<'a> Packer<'a> {
    /// A packer stepping with `stepper`.
    pub fn new(stepper: PackStepper<'a>) -> Self {
        Packer {
            cache: stepper.cache(),
            stepper,
            steps: std::array::from_fn(|_| Vec::new()),
        }
    }

    /// Integrates the rays launched at `launch` along the unit `dirs` (at
    /// most [`PACK`]) ahead, counting the work in `stats`; the k-th list
    /// holds the steps of `dirs[k]` for [`Marcher::march_ahead`].
    ///
    /// # Panics
    /// If there are more than [`PACK`] directions.
    pub fn integrate(
        &mut self,
        marcher: &Marcher,
        launch: &Launch,
        dirs: &[DVec3],
        stats: &mut MarchStats,
    ) -> &[Vec<AheadStep>; PACK] {
        assert!(dirs.len() <= PACK, "at most {PACK} rays a pack");
        let air = marcher.air;
        let n_max = marcher.step_n_max();
        // Idle lanes hold any launch state (their steps are of length 0).
        let (y0, f0) = launch.along(DVec3::Z);
        let (mut y, mut f) = ([y0; PACK], [f0; PACK]);
        let mut active = [false; PACK];
        for (k, &dir) in dirs.iter().enumerate() {
            self.steps[k].clear();
            (y[k], f[k]) = launch.along(dir);
            active[k] = !sky_bound(marcher, &y[k]);
        }
        for list in &mut self.steps[dirs.len()..] {
            list.clear();
        }
        let mut h = [0.0; PACK];
        let mut arc = [0.0; PACK];
        while active.iter().any(|&a| a) {
            for k in 0..PACK {
                (h[k], arc[k]) = if active[k] {
                    let a = marcher.step_length(y[k].x);
                    (a / n_max, a)
                } else {
                    (0.0, 0.0)
                };
            }
            self.stepper.rk4(&mut self.cache, &h, &mut y, &mut f);
            for k in 0..PACK {
                if !active[k] {
                    continue;
                }
                stats.rk4_steps += 1;
                stats.pack_steps += 1;
                stats.medium_evaluations += 4;
                self.steps[k].push(AheadStep {
                    y: y[k],
                    f: f[k],
                    h: h[k],
                    arc: arc[k],
                });
                if air.earth().height(y[k].x) < 0.0
                    || y[k].s >= marcher.max_distance
                    || self.steps[k].len() >= MAX_AHEAD
                    || sky_bound(marcher, &y[k])
                {
                    active[k] = false;
                }
            }
        }
        &self.steps
    }
}

/// Whether the ray at `y` climbs away from every object and zone for good
/// ([`super::air::Air::fate`]): the tracer will not integrate it further.
fn sky_bound(marcher: &Marcher, y: &RayState) -> bool {
    matches!(marcher.air.fate(dvec(y.x), dvec(y.v)), Some(Fate::Sky(_)))
}
