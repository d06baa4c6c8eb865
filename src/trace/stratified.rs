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
//! code (see [`lanes`](super::lanes)): the plane crossing (along the ray's
//! azimuth), the ground (dips between steps included), the maximum length and
//! the step limit.
//!
//! Call it through [`lanes::trace_batch`](super::lanes::trace_batch), which
//! takes this path whenever the field allows it, or directly with
//! [`trace_batch_2d`].

// Lane loops index several arrays in lockstep (see `lanes.rs`).
#![allow(clippy::needless_range_loop)]

use super::fastexp::fmadd;
use super::lanes::{
    BatchOptions, CROSSING_MARGIN, Coefficients, Isa, Kernel, LANES, RayJob, combine, run,
};
use super::{RayRate, RayState, Segment, Trace};
use crate::math::V3;
use crate::medium::{IndexField, LogisticField};

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
    // Half-width lanes for small batches, as in `lanes::trace_batch_3d`.
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

/// The 2-D lane kernel.
struct Lanes2<const N: usize> {
    c: Coefficients,
    buf: [Buf2<N>; 2],
    /// The stages k2, k3, k4 of a step.
    stages: [Buf2<N>; 3],
    /// Index of the buffer with the current state (the other: the previous).
    cur: usize,
    h: [f64; N],
    /// v_x and v_z, constant along each ray.
    vx: [f64; N],
    vz: [f64; N],
    /// Target plane: point and normal.
    plane: [[f64; N]; 6],
    max_length: [f64; N],
    /// Distance to the plane of the nearest point so far, and its
    /// (x, y, z, v_y, s).
    near_d: [f64; N],
    near: [[f64; N]; 5],
}

impl<const N: usize> Lanes2<N> {
    fn new(c: Coefficients) -> Self {
        Lanes2 {
            c,
            buf: [Buf2::ZERO; 2],
            stages: [Buf2::ZERO; 3],
            cur: 0,
            h: [0.0; N],
            vx: [0.0; N],
            vz: [0.0; N],
            plane: [[0.0; N]; 6],
            max_length: [f64::INFINITY; N],
            near_d: [f64::INFINITY; N],
            near: [[0.0; N]; 5],
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

    fn buffer_state(&self, b: usize, lane: usize) -> (RayState, RayRate) {
        let q = &self.buf[b];
        self.lift(
            lane,
            [q.x[lane], q.y[lane], q.z[lane], q.vy[lane], q.s[lane]],
            [q.ay[lane], q.n[lane]],
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
        let t = &job.target;
        let plane = [
            t.point.x, t.point.y, t.point.z, t.normal.x, t.normal.y, t.normal.z,
        ];
        for (p, v) in self.plane.iter_mut().zip(plane) {
            p[lane] = v;
        }
        let b = &mut self.buf[self.cur];
        let q = [start.x.x, start.x.y, start.x.z, start.v.y, start.s];
        for (k, (dst, v)) in [&mut b.x, &mut b.y, &mut b.z, &mut b.vy, &mut b.s]
            .into_iter()
            .zip(q)
            .enumerate()
        {
            dst[lane] = v;
            self.near[k][lane] = v;
        }
        b.ay[lane] = rate.dv.y;
        b.n[lane] = rate.ds;
        self.h[lane] = step;
        self.max_length[lane] = max_length;
        self.near_d[lane] = t.signed_distance(start.x).abs();
    }

    fn freeze(&mut self, lane: usize) {
        self.h[lane] = 0.0;
        self.max_length[lane] = f64::INFINITY;
    }

    #[inline(always)]
    fn step<const FMA: bool>(&mut self) {
        let (first, second) = self.buf.split_at_mut(1);
        let (y0, y1) = if self.cur == 0 {
            (&first[0], &mut second[0])
        } else {
            (&second[0], &mut first[0])
        };
        rk4_2d::<N, FMA>(
            &self.c,
            &self.h,
            [&self.vx, &self.vz],
            y0,
            &mut self.stages,
            y1,
        );
        self.cur ^= 1;
    }

    #[inline(always)]
    fn scan(&mut self) -> u64 {
        let y0 = &self.buf[self.cur ^ 1];
        let y1 = &self.buf[self.cur];
        scan_2d(
            y0,
            y1,
            &self.plane,
            &self.max_length,
            &mut self.near_d,
            &mut self.near,
        )
    }

    fn segment(&self, lane: usize) -> Segment<f64> {
        let (y0, f0) = self.buffer_state(self.cur ^ 1, lane);
        let (y1, f1) = self.buffer_state(self.cur, lane);
        Segment {
            y0,
            f0,
            y1,
            f1,
            h: self.h[lane],
        }
    }

    fn nearest(&self, lane: usize) -> RayState {
        let q = [0, 1, 2, 3, 4].map(|k| self.near[k][lane]);
        self.lift(lane, q, [0.0, 1.0]).0
    }
}

/// One RK4 step of every lane from `y0` into `y1` (see `rk4_3d` in `lanes.rs`
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

/// The event screen of the 2-D kernel (see `Kernel::scan`).
#[inline(always)]
fn scan_2d<const N: usize>(
    y0: &Buf2<N>,
    y1: &Buf2<N>,
    plane: &[[f64; N]; 6],
    max_length: &[f64; N],
    near_d: &mut [f64; N],
    near: &mut [[f64; N]; 5],
) -> u64 {
    let [px, py, pz, nx, ny, nz] = plane;
    let mut mask = 0u64;
    for i in 0..N {
        // `TargetPlane::signed_distance`, operation for operation.
        let g = (y1.x[i] - px[i]) * nx[i] + (y1.y[i] - py[i]) * ny[i] + (y1.z[i] - pz[i]) * nz[i];
        let d = g.abs();
        let closer = d < near_d[i];
        near_d[i] = if closer { d } else { near_d[i] };
        let now = [y1.x[i], y1.y[i], y1.z[i], y1.vy[i], y1.s[i]];
        for (k, v) in now.into_iter().enumerate() {
            near[k][i] = if closer { v } else { near[k][i] };
        }
        let crossed = g >= -CROSSING_MARGIN;
        let ground = (y0.y[i] >= 0.0) & ((y1.y[i] < 0.0) | ((y0.vy[i] < 0.0) & (y1.vy[i] > 0.0)));
        let long = y1.s[i] >= max_length[i];
        mask |= u64::from(crossed | ground | long) << i;
    }
    mask
}
