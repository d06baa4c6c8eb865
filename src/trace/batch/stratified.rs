//! The stratified fast path: with no hot spots δ depends on the height alone,
//! so a ray stays in the vertical plane of its launch direction (`docs/model.md`)
//! and is a 2-D curve in it.
//!
//! In the τ form the horizontal part of `dv/dτ = n∇δ` is exactly 0, so v_x and
//! v_z are constants (Snell's invariant n·t, per horizontal axis) and only the
//! vertical pair (y, v_y) and the arc length are integrated by RK4 with the
//! rate of δ(y): one term loop per layer per stage, no hot spots, no
//! horizontal gradient, no v_x, v_z updates. The horizontal position is
//! advanced by the constant v_x, v_z with RK4's own weights, the operations
//! the 3-D RK4 performs on it (its horizontal rate is exactly 0 here), so the
//! horizontal rounding, which over thousands of steps drifts by up to 10⁻¹³
//! of the distance, is the 3-D path's too, and the endpoints agree with the
//! 3-D paths to the rounding of the exponential.
//!
//! The state maps back to 3-D as `v = (v_x, v_y, v_z)`, `dv/dτ = (0, a_y, 0)`.
//! Events are the 3-D ones, evaluated on the mapped step by the same scalar
//! code (see [`batch`](super)): the plane crossing (along the ray's
//! azimuth), the ground (dips between steps included), the maximum length and
//! the step limit.
//!
//! Call it through [`trace_batch`](super::trace_batch), which
//! takes this path whenever the field allows it, or directly with
//! [`trace_batch_2d`].

// Lane loops index several arrays in lockstep (see `lanes.rs`).
#![allow(clippy::needless_range_loop)]

use super::driver::Kernel;
use super::isa::{Isa, run};
use super::job::{BatchOptions, RayJob};
use super::lanes::{LANES, LaneBuf, LaneSet, combine};
use super::terms::Coefficients;
use crate::math::V3;
use crate::medium::{IndexField, LogisticField};
use crate::trace::fastexp::fmadd;
use crate::trace::{RayRate, RayState, Segment, Trace};

/// The field has hot spots, so δ depends on x and z too.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the medium has hot spots: it is not stratified, use the 3-D path")]
pub struct NotStratified;

/// Traces every job with the 2-D kernel built for `isa`, or returns
/// [`NotStratified`] (and leaves `out` alone) if the field has hot spots.
///
/// # Panics
/// If `out.len() != jobs.len()`, or if this CPU cannot run `isa`.
pub fn trace_batch_2d(
    isa: Isa,
    field: &LogisticField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) -> Result<(), NotStratified> {
    if !field.is_stratified() {
        return Err(NotStratified);
    }
    let c = Coefficients::of(field);
    // Half-width lanes for small batches, as in `trace_batch_3d`.
    if jobs.len() <= LANES / 2 {
        run(
            isa,
            &mut Lanes2::<{ LANES / 2 }>::new(c),
            field,
            jobs,
            options,
            out,
        );
    } else {
        run(isa, &mut Lanes2::<LANES>::new(c), field, jobs, options, out);
    }
    Ok(())
}

/// One buffer of lane states: position, v_y, arc length, and the rate's
/// non-trivial parts (a = dv_y/dτ = n·dδ/dy, n = ds/dτ).
#[derive(Clone, Copy)]
struct Buf2<const N: usize> {
    x: [f64; N],
    y: [f64; N],
    z: [f64; N],
    vy: [f64; N],
    s: [f64; N],
    ay: [f64; N],
    n: [f64; N],
}

impl<const N: usize> Buf2<N> {
    const ZERO: Self = Buf2 {
        x: [0.0; N],
        y: [0.0; N],
        z: [0.0; N],
        vy: [0.0; N],
        s: [0.0; N],
        ay: [0.0; N],
        n: [1.0; N],
    };

    /// n = 1 + δ and a = n·dδ/dy at the buffer's heights (as `state::rate`).
    #[inline(always)]
    fn set_rate<const FMA: bool>(&mut self, c: &Coefficients) {
        self.n = [0.0; N];
        self.ay = [0.0; N];
        c.layers::<N, FMA>(&self.y, &mut self.n, &mut self.ay);
        for i in 0..N {
            let n = self.n[i] + 1.0;
            self.n[i] = n;
            self.ay[i] *= n;
        }
    }
}

impl<const N: usize> LaneBuf<N, 5> for Buf2<N> {
    fn put(&mut self, lane: usize, start: &RayState, rate: &RayRate) {
        self.x[lane] = start.x.x;
        self.y[lane] = start.x.y;
        self.z[lane] = start.x.z;
        self.vy[lane] = start.v.y;
        self.s[lane] = start.s;
        self.ay[lane] = rate.dv.y;
        self.n[lane] = rate.ds;
    }

    #[inline(always)]
    fn tracked(&self) -> [&[f64; N]; 5] {
        self.screened()
    }

    #[inline(always)]
    fn screened(&self) -> [&[f64; N]; 5] {
        [&self.x, &self.y, &self.z, &self.vy, &self.s]
    }
}

/// The 2-D lane kernel; the nearest point keeps (x, y, z, v_y, s).
struct Lanes2<const N: usize> {
    c: Coefficients,
    set: LaneSet<Buf2<N>, N, 5>,
    /// v_x and v_z, constant along each ray.
    vx: [f64; N],
    vz: [f64; N],
}

impl<const N: usize> Lanes2<N> {
    fn new(c: Coefficients) -> Self {
        Lanes2 {
            c,
            set: LaneSet::new(Buf2::ZERO),
            vx: [0.0; N],
            vz: [0.0; N],
        }
    }

    /// The 3-D state and rate of `lane` from its values `q` = (x, y, z, v_y,
    /// s) and rate (a_y, n).
    fn lift(&self, lane: usize, q: [f64; 5], rate: [f64; 2]) -> (RayState, RayRate) {
        let [x, y, z, vy, s] = q;
        let v = V3::new(self.vx[lane], vy, self.vz[lane]);
        (
            RayState {
                x: V3::new(x, y, z),
                v,
                s,
            },
            RayRate {
                dx: v,
                dv: V3::new(0.0, rate[0], 0.0),
                ds: rate[1],
            },
        )
    }
}

impl<const N: usize> Kernel<N> for Lanes2<N> {
    fn load(
        &mut self,
        lane: usize,
        job: &RayJob,
        start: &RayState,
        rate: &RayRate,
        step: f64,
        max_length: f64,
    ) {
        self.vx[lane] = start.v.x;
        self.vz[lane] = start.v.z;
        self.set.load(lane, job, start, rate, step, max_length);
    }

    fn freeze(&mut self, lane: usize) {
        self.set.freeze(lane);
    }

    #[inline(always)]
    fn step<const FMA: bool>(&mut self) {
        let (h, y0, stages, y1) = self.set.step_parts();
        rk4_2d::<N, FMA>(&self.c, h, [&self.vx, &self.vz], y0, stages, y1);
        self.set.flip();
    }

    #[inline(always)]
    fn scan(&mut self) -> u64 {
        self.set.scan()
    }

    fn segment(&self, lane: usize) -> Segment<f64> {
        self.set.segment(lane, |q, i| {
            self.lift(
                i,
                [q.x[i], q.y[i], q.z[i], q.vy[i], q.s[i]],
                [q.ay[i], q.n[i]],
            )
        })
    }

    fn nearest(&self, lane: usize) -> RayState {
        self.lift(lane, self.set.nearest(lane), [0.0, 1.0]).0
    }
}

/// One RK4 step of every lane from `y0` into `y1` (see `rk4_3d` in `kernel.rs`
/// for why this is a free function on distinct references).
#[inline(always)]
fn rk4_2d<const N: usize, const FMA: bool>(
    c: &Coefficients,
    h: &[f64; N],
    [vx, vz]: [&[f64; N]; 2],
    y0: &Buf2<N>,
    [k2, k3, k4]: &mut [Buf2<N>; 3],
    y1: &mut Buf2<N>,
) {
    // The stages of the scalar `rk4_step`, restricted to (y, v_y): the
    // stage x, z and s never enter the rate.
    for i in 0..N {
        let f = 0.5 * h[i];
        k2.y[i] = fmadd::<FMA>(y0.vy[i], f, y0.y[i]);
        k2.vy[i] = fmadd::<FMA>(y0.ay[i], f, y0.vy[i]);
    }
    k2.set_rate::<FMA>(c);
    for i in 0..N {
        let f = 0.5 * h[i];
        k3.y[i] = fmadd::<FMA>(k2.vy[i], f, y0.y[i]);
        k3.vy[i] = fmadd::<FMA>(k2.ay[i], f, y0.vy[i]);
    }
    k3.set_rate::<FMA>(c);
    for i in 0..N {
        let f = h[i];
        k4.y[i] = fmadd::<FMA>(k3.vy[i], f, y0.y[i]);
        k4.vy[i] = fmadd::<FMA>(k3.ay[i], f, y0.vy[i]);
    }
    k4.set_rate::<FMA>(c);
    for i in 0..N {
        let h6 = (1.0 / 6.0) * h[i];
        let h3 = (1.0 / 3.0) * h[i];
        let b = [h6, h3, h3, h6];
        y1.x[i] = combine::<FMA>(y0.x[i], [vx[i]; 4], b);
        y1.z[i] = combine::<FMA>(y0.z[i], [vz[i]; 4], b);
        y1.y[i] = combine::<FMA>(y0.y[i], [y0.vy[i], k2.vy[i], k3.vy[i], k4.vy[i]], b);
        y1.vy[i] = combine::<FMA>(y0.vy[i], [y0.ay[i], k2.ay[i], k3.ay[i], k4.ay[i]], b);
        y1.s[i] = combine::<FMA>(y0.s[i], [y0.n[i], k2.n[i], k3.n[i], k4.n[i]], b);
    }
    y1.set_rate::<FMA>(c);
}
