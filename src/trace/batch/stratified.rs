//! The stratified fast path: with no hot spots δ depends on the height alone,
//! so a ray stays in the vertical plane of its launch direction (`docs/model.md`)
//! and is a 2-D curve in it.
//!
//! In the τ form the horizontal part of `dv/dτ = n∇δ` is exactly 0, so v_x and
//! v_z are constants (Snell's invariant n·t, per horizontal axis) and only the
//! vertical pair (y, v_y) and the arc length are integrated, by RK4 or
//! Dormand–Prince 5(4) with each lane's own adaptive step (see `adaptive`),
//! with the rate of δ(y): one term loop per layer per stage, no hot spots,
//! no horizontal gradient, no v_x, v_z updates. These are the scalar planar
//! stepper's operations (`Stepper::attempt_planar`), lane-wise. The
//! horizontal position is advanced by the constant v_x, v_z with the
//! method's own weights, the operations the 3-D step performs on it (its
//! horizontal rate is exactly 0 here), so the horizontal rounding, which over
//! thousands of steps drifts by up to 10⁻¹³ of the distance, is the 3-D
//! path's too, and the endpoints agree with the 3-D paths to the rounding of
//! the exponential.
//!
//! The state maps back to 3-D as `v = (v_x, v_y, v_z)`, `dv/dτ = (0, a_y, 0)`.
//! Events are the 3-D ones, evaluated on the mapped step by the same scalar
//! code (see [`batch`](super)): the plane crossing (along the ray's
//! azimuth), the ground (dips between steps included), the maximum length and
//! the step limit.
//!
//! Call it through [`trace_batch`](super::trace_batch), which
//! takes this path whenever the field allows it, or directly with
//! [`trace_batch_2d`] (the logistic kind) and `trace_air_2d` (real air).

// Lane loops index several arrays in lockstep (see `lanes.rs`).
#![allow(clippy::needless_range_loop)]

use super::adaptive::{advance, constant_error_term, error_term, judge, keep, prepare};
use super::air::AirLanes;
use super::driver::Kernel;
use super::field::{LaneField, LogisticLanes};
use super::isa::{Isa, run};
use super::job::{BatchOptions, RayJob};
use super::lanes::{Attempts, Control, LANES, LaneBuf, LaneSet, combine};
use crate::math::V3;
use crate::medium::LogisticField;
use crate::medium::air::AirField;
use crate::trace::fastexp::fmadd;
use crate::trace::stepper::{
    A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65, B1, B3, B4, B5, B6,
    DOPRI5_WEIGHTS,
};
use crate::trace::{Earth, Method, RayRate, RayState, Segment, Trace};

/// The field has hot spots, so δ depends on x and z too, or it lies over the
/// round earth, whose vertical turns with the position: either way a ray
/// does not keep a constant horizontal velocity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "the medium has hot spots or lies over the round earth: it is not stratified, use the 3-D path"
)]
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
    trace_2d(isa, &LogisticLanes::new(field), jobs, options, out)
}

/// [`trace_batch_2d`] for real air.
///
/// # Panics
/// If `out.len() != jobs.len()`, or if this CPU cannot run `isa`.
pub fn trace_air_2d(
    isa: Isa,
    field: &AirField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) -> Result<(), NotStratified> {
    trace_2d(isa, &AirLanes::new(field), jobs, options, out)
}

/// The 2-D kernel over any lane field.
fn trace_2d<F: LaneField>(
    isa: Isa,
    field: &F,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) -> Result<(), NotStratified> {
    if !field.is_stratified() || !options.earth.is_flat() {
        return Err(NotStratified);
    }
    // Half-width lanes for small batches, as in `trace_batch_3d`.
    if jobs.len() <= LANES / 2 {
        run(
            isa,
            &mut Lanes2::<F, { LANES / 2 }>::new(field, options.method),
            jobs,
            options,
            out,
        );
    } else {
        run(
            isa,
            &mut Lanes2::<F, LANES>::new(field, options.method),
            jobs,
            options,
            out,
        );
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
    fn set_rate<F: LaneField, const FMA: bool>(&mut self, f: &F) {
        f.layers::<N, FMA>(&self.y, &mut self.n, &mut self.ay);
        for i in 0..N {
            let n = self.n[i] + 1.0;
            self.n[i] = n;
            self.ay[i] *= n;
        }
    }

    /// Copies the lanes of `mask` from `from`.
    #[inline(always)]
    fn keep(&mut self, mask: u64, from: &Self) {
        keep(mask, &from.x, &mut self.x);
        keep(mask, &from.y, &mut self.y);
        keep(mask, &from.z, &mut self.z);
        keep(mask, &from.vy, &mut self.vy);
        keep(mask, &from.s, &mut self.s);
        keep(mask, &from.ay, &mut self.ay);
        keep(mask, &from.n, &mut self.n);
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
struct Lanes2<'a, F, const N: usize> {
    field: &'a F,
    set: LaneSet<Buf2<N>, N, 5>,
    /// v_x and v_z, constant along each ray.
    vx: [f64; N],
    vz: [f64; N],
}

impl<'a, F: LaneField, const N: usize> Lanes2<'a, F, N> {
    fn new(field: &'a F, method: Method) -> Self {
        Lanes2 {
            field,
            set: LaneSet::new(Buf2::ZERO, method, field.ceiling(), Earth::Flat),
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

impl<F: LaneField, const N: usize> Kernel<N> for Lanes2<'_, F, N> {
    type Field = F;

    fn field(&self) -> &F {
        self.field
    }

    fn load(
        &mut self,
        lane: usize,
        job: &RayJob,
        start: &RayState,
        rate: &RayRate,
        max_length: f64,
    ) {
        self.vx[lane] = start.v.x;
        self.vz[lane] = start.v.z;
        self.set.load(lane, job, start, rate, max_length);
    }

    fn freeze(&mut self, lane: usize) {
        self.set.freeze(lane);
    }

    fn stages(&self) -> u64 {
        stages_per_attempt(self.set.method())
    }

    #[inline(always)]
    fn step<const FMA: bool>(&mut self) -> Attempts {
        let method = self.set.method();
        let (control, y0, stages, y1) = self.set.step_parts();
        let speeds = [&self.vx, &self.vz];
        let attempts = match method {
            Method::Rk4 { .. } => {
                let [k2, k3, k4, _, _] = stages;
                rk4_2d::<F, N, FMA>(self.field, &control.h, speeds, y0, [k2, k3, k4], y1);
                Attempts::all::<N>()
            }
            Method::Dopri5 { .. } => {
                dopri5_2d::<F, N, FMA>(self.field, control, speeds, y0, stages, y1)
            }
        };
        self.set.flip();
        attempts
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

/// Right-hand-side evaluations per attempted step: 4 for RK4 (the fifth is
/// the next step's first), 6 for Dormand–Prince (first same as last).
pub(crate) fn stages_per_attempt(method: Method) -> u64 {
    match method {
        Method::Rk4 { .. } => 4,
        Method::Dopri5 { .. } => 6,
    }
}

/// One RK4 step of every lane from `y0` into `y1` (see `rk4_3d` in `kernel.rs`
/// for why this is a free function on distinct references).
#[inline(always)]
fn rk4_2d<F: LaneField, const N: usize, const FMA: bool>(
    c: &F,
    h: &[f64; N],
    [vx, vz]: [&[f64; N]; 2],
    y0: &Buf2<N>,
    [k2, k3, k4]: [&mut Buf2<N>; 3],
    y1: &mut Buf2<N>,
) {
    // The stages of the scalar `rk4_step`, restricted to (y, v_y): the
    // stage x, z and s never enter the rate.
    for i in 0..N {
        let f = 0.5 * h[i];
        k2.y[i] = fmadd::<FMA>(y0.vy[i], f, y0.y[i]);
        k2.vy[i] = fmadd::<FMA>(y0.ay[i], f, y0.vy[i]);
    }
    k2.set_rate::<F, FMA>(c);
    for i in 0..N {
        let f = 0.5 * h[i];
        k3.y[i] = fmadd::<FMA>(k2.vy[i], f, y0.y[i]);
        k3.vy[i] = fmadd::<FMA>(k2.ay[i], f, y0.vy[i]);
    }
    k3.set_rate::<F, FMA>(c);
    for i in 0..N {
        let f = h[i];
        k4.y[i] = fmadd::<FMA>(k3.vy[i], f, y0.y[i]);
        k4.vy[i] = fmadd::<FMA>(k3.ay[i], f, y0.vy[i]);
    }
    k4.set_rate::<F, FMA>(c);
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
    y1.set_rate::<F, FMA>(c);
}

/// One Dormand–Prince attempt of every lane from `y0` into `y1`: the scalar
/// `Stepper::attempt_planar`'s stages on (y, v_y), the horizontal position by
/// the constant v_x, v_z with the 5th-order weights, the error estimate of the
/// 3-D step's six components, and each lane's controller (see `adaptive`).
/// Rejected and underflowed lanes end where they started.
#[inline(always)]
fn dopri5_2d<F: LaneField, const N: usize, const FMA: bool>(
    f: &F,
    control: &mut Control<N>,
    [vx, vz]: [&[f64; N]; 2],
    y0: &Buf2<N>,
    [k2, k3, k4, k5, k6]: &mut [Buf2<N>; 5],
    y1: &mut Buf2<N>,
) -> Attempts {
    let underflow = prepare(f, control, [&y0.x, &y0.y, &y0.z], [vx, &y0.vy, vz]);
    let h = control.used;
    advance::<N, 1, FMA>(&y0.y, &h, [A21], [&y0.vy], &mut k2.y);
    advance::<N, 1, FMA>(&y0.vy, &h, [A21], [&y0.ay], &mut k2.vy);
    k2.set_rate::<F, FMA>(f);
    advance::<N, 2, FMA>(&y0.y, &h, [A31, A32], [&y0.vy, &k2.vy], &mut k3.y);
    advance::<N, 2, FMA>(&y0.vy, &h, [A31, A32], [&y0.ay, &k2.ay], &mut k3.vy);
    k3.set_rate::<F, FMA>(f);
    let c4 = [A41, A42, A43];
    advance::<N, 3, FMA>(&y0.y, &h, c4, [&y0.vy, &k2.vy, &k3.vy], &mut k4.y);
    advance::<N, 3, FMA>(&y0.vy, &h, c4, [&y0.ay, &k2.ay, &k3.ay], &mut k4.vy);
    k4.set_rate::<F, FMA>(f);
    let c5 = [A51, A52, A53, A54];
    advance::<N, 4, FMA>(&y0.y, &h, c5, [&y0.vy, &k2.vy, &k3.vy, &k4.vy], &mut k5.y);
    advance::<N, 4, FMA>(&y0.vy, &h, c5, [&y0.ay, &k2.ay, &k3.ay, &k4.ay], &mut k5.vy);
    k5.set_rate::<F, FMA>(f);
    let c6 = [A61, A62, A63, A64, A65];
    let dy6 = [&y0.vy, &k2.vy, &k3.vy, &k4.vy, &k5.vy];
    advance::<N, 5, FMA>(&y0.y, &h, c6, dy6, &mut k6.y);
    let a6 = [&y0.ay, &k2.ay, &k3.ay, &k4.ay, &k5.ay];
    advance::<N, 5, FMA>(&y0.vy, &h, c6, a6, &mut k6.vy);
    k6.set_rate::<F, FMA>(f);
    let b = [B1, B3, B4, B5, B6];
    advance::<N, 5, FMA>(
        &y0.y,
        &h,
        b,
        [&y0.vy, &k3.vy, &k4.vy, &k5.vy, &k6.vy],
        &mut y1.y,
    );
    advance::<N, 5, FMA>(
        &y0.vy,
        &h,
        b,
        [&y0.ay, &k3.ay, &k4.ay, &k5.ay, &k6.ay],
        &mut y1.vy,
    );
    advance::<N, 5, FMA>(&y0.s, &h, b, [&y0.n, &k3.n, &k4.n, &k5.n, &k6.n], &mut y1.s);
    advance::<N, 5, FMA>(&y0.x, &h, DOPRI5_WEIGHTS, [vx; 5], &mut y1.x);
    advance::<N, 5, FMA>(&y0.z, &h, DOPRI5_WEIGHTS, [vz; 5], &mut y1.z);
    y1.set_rate::<F, FMA>(f);
    // The 3-D estimate's components: dx = v (constant v_x, v_z), dv = (0, a, 0).
    let (mut ex, mut ey, mut ez, mut evy) = ([0.0; N], [0.0; N], [0.0; N], [0.0; N]);
    constant_error_term(vx, &h, &mut ex);
    error_term(
        [&y0.vy, &k3.vy, &k4.vy, &k5.vy, &k6.vy, &y1.vy],
        &h,
        &mut ey,
    );
    constant_error_term(vz, &h, &mut ez);
    error_term(
        [&y0.ay, &k3.ay, &k4.ay, &k5.ay, &k6.ay, &y1.ay],
        &h,
        &mut evy,
    );
    let mut err2 = [0.0; N];
    for i in 0..N {
        err2[i] = (ex[i] * ex[i] + ey[i] * ey[i] + ez[i] * ez[i])
            + (0.0 * 0.0 + evy[i] * evy[i] + 0.0 * 0.0);
    }
    let accepted = judge::<N, FMA>(control, &err2) & !underflow;
    y1.keep(!accepted, y0);
    Attempts {
        accepted,
        underflow,
    }
}
