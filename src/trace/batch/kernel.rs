//! The 3-D lane kernel: RK4 over the full field, hot spots included, one
//! branch-free loop over the lanes per right-hand-side term.

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::driver::Kernel;
use super::isa::{Isa, run};
use super::job::{BatchOptions, RayJob};
use super::lanes::{LANES, LaneBuf, LaneSet, combine};
use super::terms::Coefficients;
use crate::math::V3;
use crate::medium::LogisticField;
use crate::trace::fastexp::fmadd;
use crate::trace::{RayRate, RayState, Segment, Trace};

/// Traces every job with the 3-D lanes kernel built for `isa` (any field).
///
/// # Panics
/// If `out.len() != jobs.len()`, or if this CPU cannot run `isa`.
pub fn trace_batch_3d(
    isa: Isa,
    field: &LogisticField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    let c = Coefficients::of(field);
    // A small batch (a fit with few pairs, split over threads) would leave
    // half of the lanes idle, yet computed: take the half-width kernel.
    if jobs.len() <= LANES / 2 {
        run(
            isa,
            &mut Lanes3::<{ LANES / 2 }>::new(c),
            field,
            jobs,
            options,
            out,
        );
    } else {
        run(isa, &mut Lanes3::<LANES>::new(c), field, jobs, options, out);
    }
}

/// One buffer of lane states: position, v = n·t, arc length, and the rate's
/// non-trivial parts (a = dv/dτ = n∇n, n = ds/dτ; dx/dτ is v itself).
#[derive(Clone, Copy)]
struct Buf3<const N: usize> {
    x: [f64; N],
    y: [f64; N],
    z: [f64; N],
    vx: [f64; N],
    vy: [f64; N],
    vz: [f64; N],
    s: [f64; N],
    ax: [f64; N],
    ay: [f64; N],
    az: [f64; N],
    n: [f64; N],
}

impl<const N: usize> Buf3<N> {
    const ZERO: Self = Buf3 {
        x: [0.0; N],
        y: [0.0; N],
        z: [0.0; N],
        vx: [0.0; N],
        vy: [0.0; N],
        vz: [0.0; N],
        s: [0.0; N],
        ax: [0.0; N],
        ay: [0.0; N],
        az: [0.0; N],
        // n = 1 in idle lanes: the state of a ray in vacuum, harmless to step.
        n: [1.0; N],
    };

    fn state(&self, i: usize) -> (RayState, RayRate) {
        let v = V3::new(self.vx[i], self.vy[i], self.vz[i]);
        (
            RayState {
                x: V3::new(self.x[i], self.y[i], self.z[i]),
                v,
                s: self.s[i],
            },
            RayRate {
                dx: v,
                dv: V3::new(self.ax[i], self.ay[i], self.az[i]),
                ds: self.n[i],
            },
        )
    }

    /// Sets the rate from the field at the buffer's positions (n = 1 + δ,
    /// a = ∇δ·n, as `state::rate`), accumulating δ and ∇δ in place.
    #[inline(always)]
    fn set_rate<const FMA: bool>(&mut self, c: &Coefficients) {
        self.n = [0.0; N];
        self.ax = [0.0; N];
        self.ay = [0.0; N];
        self.az = [0.0; N];
        c.delta_gradient::<N, FMA>(
            [&self.x, &self.y, &self.z],
            &mut self.n,
            [&mut self.ax, &mut self.ay, &mut self.az],
        );
        for i in 0..N {
            let n = self.n[i] + 1.0;
            self.n[i] = n;
            self.ax[i] *= n;
            self.ay[i] *= n;
            self.az[i] *= n;
        }
    }
}

impl<const N: usize> LaneBuf<N, 7> for Buf3<N> {
    fn put(&mut self, lane: usize, start: &RayState, rate: &RayRate) {
        self.x[lane] = start.x.x;
        self.y[lane] = start.x.y;
        self.z[lane] = start.x.z;
        self.vx[lane] = start.v.x;
        self.vy[lane] = start.v.y;
        self.vz[lane] = start.v.z;
        self.s[lane] = start.s;
        self.ax[lane] = rate.dv.x;
        self.ay[lane] = rate.dv.y;
        self.az[lane] = rate.dv.z;
        self.n[lane] = rate.ds;
    }

    #[inline(always)]
    fn tracked(&self) -> [&[f64; N]; 7] {
        [
            &self.x, &self.y, &self.z, &self.vx, &self.vy, &self.vz, &self.s,
        ]
    }

    #[inline(always)]
    fn screened(&self) -> [&[f64; N]; 5] {
        [&self.x, &self.y, &self.z, &self.vy, &self.s]
    }
}

/// The 3-D lane kernel: the full field, hot spots included; the nearest
/// point keeps (x, y, z, v_x, v_y, v_z, s).
struct Lanes3<const N: usize> {
    c: Coefficients,
    set: LaneSet<Buf3<N>, N, 7>,
}

impl<const N: usize> Lanes3<N> {
    fn new(c: Coefficients) -> Self {
        Lanes3 {
            c,
            set: LaneSet::new(Buf3::ZERO),
        }
    }
}

impl<const N: usize> Kernel<N> for Lanes3<N> {
    fn load(
        &mut self,
        lane: usize,
        job: &RayJob,
        start: &RayState,
        rate: &RayRate,
        step: f64,
        max_length: f64,
    ) {
        self.set.load(lane, job, start, rate, step, max_length);
    }

    fn freeze(&mut self, lane: usize) {
        self.set.freeze(lane);
    }

    #[inline(always)]
    fn step<const FMA: bool>(&mut self) {
        let (h, y0, stages, y1) = self.set.step_parts();
        rk4_3d::<N, FMA>(&self.c, h, y0, stages, y1);
        self.set.flip();
    }

    #[inline(always)]
    fn scan(&mut self) -> u64 {
        self.set.scan()
    }

    fn segment(&self, lane: usize) -> Segment<f64> {
        self.set.segment(lane, Buf3::state)
    }

    fn nearest(&self, lane: usize) -> RayState {
        let [x, y, z, vx, vy, vz, s] = self.set.nearest(lane);
        RayState {
            x: V3::new(x, y, z),
            v: V3::new(vx, vy, vz),
            s,
        }
    }
}

/// One RK4 step of every lane from `y0` into `y1`, the operations of the
/// scalar `rk4_step` in its order. A free function so that every array is a
/// distinct reference: the compiler then knows they do not overlap and
/// vectorizes each lane loop (through `self` it could not tell `y0` from `y1`,
/// two elements of one array, and kept the final sum scalar; see
/// [`LaneSet::step_parts`]).
#[inline(always)]
fn rk4_3d<const N: usize, const FMA: bool>(
    c: &Coefficients,
    h: &[f64; N],
    y0: &Buf3<N>,
    [k2, k3, k4]: &mut [Buf3<N>; 3],
    y1: &mut Buf3<N>,
) {
    // Stage states of the scalar `rk4_step` (y + c·h·k), each with its rate.
    // k2 at y + h/2·k1.
    for i in 0..N {
        let f = 0.5 * h[i];
        k2.x[i] = fmadd::<FMA>(y0.vx[i], f, y0.x[i]);
        k2.y[i] = fmadd::<FMA>(y0.vy[i], f, y0.y[i]);
        k2.z[i] = fmadd::<FMA>(y0.vz[i], f, y0.z[i]);
        k2.vx[i] = fmadd::<FMA>(y0.ax[i], f, y0.vx[i]);
        k2.vy[i] = fmadd::<FMA>(y0.ay[i], f, y0.vy[i]);
        k2.vz[i] = fmadd::<FMA>(y0.az[i], f, y0.vz[i]);
    }
    k2.set_rate::<FMA>(c);
    // k3 at y + h/2·k2.
    for i in 0..N {
        let f = 0.5 * h[i];
        k3.x[i] = fmadd::<FMA>(k2.vx[i], f, y0.x[i]);
        k3.y[i] = fmadd::<FMA>(k2.vy[i], f, y0.y[i]);
        k3.z[i] = fmadd::<FMA>(k2.vz[i], f, y0.z[i]);
        k3.vx[i] = fmadd::<FMA>(k2.ax[i], f, y0.vx[i]);
        k3.vy[i] = fmadd::<FMA>(k2.ay[i], f, y0.vy[i]);
        k3.vz[i] = fmadd::<FMA>(k2.az[i], f, y0.vz[i]);
    }
    k3.set_rate::<FMA>(c);
    // k4 at y + h·k3.
    for i in 0..N {
        let f = h[i];
        k4.x[i] = fmadd::<FMA>(k3.vx[i], f, y0.x[i]);
        k4.y[i] = fmadd::<FMA>(k3.vy[i], f, y0.y[i]);
        k4.z[i] = fmadd::<FMA>(k3.vz[i], f, y0.z[i]);
        k4.vx[i] = fmadd::<FMA>(k3.ax[i], f, y0.vx[i]);
        k4.vy[i] = fmadd::<FMA>(k3.ay[i], f, y0.vy[i]);
        k4.vz[i] = fmadd::<FMA>(k3.az[i], f, y0.vz[i]);
    }
    k4.set_rate::<FMA>(c);
    for i in 0..N {
        let h6 = (1.0 / 6.0) * h[i];
        let h3 = (1.0 / 3.0) * h[i];
        let b = [h6, h3, h3, h6];
        y1.x[i] = combine::<FMA>(y0.x[i], [y0.vx[i], k2.vx[i], k3.vx[i], k4.vx[i]], b);
        y1.y[i] = combine::<FMA>(y0.y[i], [y0.vy[i], k2.vy[i], k3.vy[i], k4.vy[i]], b);
        y1.z[i] = combine::<FMA>(y0.z[i], [y0.vz[i], k2.vz[i], k3.vz[i], k4.vz[i]], b);
        y1.vx[i] = combine::<FMA>(y0.vx[i], [y0.ax[i], k2.ax[i], k3.ax[i], k4.ax[i]], b);
        y1.vy[i] = combine::<FMA>(y0.vy[i], [y0.ay[i], k2.ay[i], k3.ay[i], k4.ay[i]], b);
        y1.vz[i] = combine::<FMA>(y0.vz[i], [y0.az[i], k2.az[i], k3.az[i], k4.az[i]], b);
        y1.s[i] = combine::<FMA>(y0.s[i], [y0.n[i], k2.n[i], k3.n[i], k4.n[i]], b);
    }
    y1.set_rate::<FMA>(c);
}
