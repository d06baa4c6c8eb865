//! The 3-D lane kernel: RK4 or Dormand–Prince 5(4) (each lane with its own
//! adaptive step, see `adaptive`) over the full field, hot spots included,
//! one branch-free loop over the lanes per right-hand-side term.

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::adaptive::{advance, error_norm2, judge, keep, prepare};
use super::air::AirLanes;
use super::driver::Kernel;
use super::field::{EarthLanes, LaneField, LogisticLanes};
use super::isa::{Isa, run};
use super::job::{BatchOptions, RayJob};
use super::lanes::{Attempts, Control, LANES, LaneBuf, LaneSet, combine};
use super::stratified::stages_per_attempt;
use crate::math::V3;
use crate::medium::LogisticField;
use crate::medium::air::AirField;
use crate::trace::fastexp::fmadd;
use crate::trace::stepper::{
    A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65, B1, B3, B4, B5, B6,
};
use crate::trace::{Earth, Method, RayRate, RayState, Segment, Trace};

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
    trace_3d(isa, &LogisticLanes::new(field), jobs, options, out);
}

/// [`trace_batch_3d`] for real air.
///
/// # Panics
/// If `out.len() != jobs.len()`, or if this CPU cannot run `isa`.
pub fn trace_air_3d(
    isa: Isa,
    field: &AirField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    trace_3d(isa, &AirLanes::new(field), jobs, options, out);
}

/// The 3-D kernel over any lane field, over the flat ground or the sphere
/// (the field then seen through [`EarthLanes`]).
fn trace_3d<F: LaneField>(
    isa: Isa,
    field: &F,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    match options.earth {
        Earth::Flat => run_3d(isa, field, jobs, options, out),
        Earth::Round { radius } => run_3d(isa, &EarthLanes::new(field, radius), jobs, options, out),
    }
}

/// The 3-D kernel over a lane field as the tracer sees it.
fn run_3d<F: LaneField>(
    isa: Isa,
    field: &F,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    // A small batch (a fit with few pairs, split over threads) would leave
    // half of the lanes idle, yet computed: take the half-width kernel.
    if jobs.len() <= LANES / 2 {
        run(
            isa,
            &mut Lanes3::<F, { LANES / 2 }>::new(field, options),
            jobs,
            options,
            out,
        );
    } else {
        run(
            isa,
            &mut Lanes3::<F, LANES>::new(field, options),
            jobs,
            options,
            out,
        );
    }
}

/// One buffer of lane states: position, v = n·t, arc length, and the rate's
/// non-trivial parts (a = dv/dτ = n∇n, n = ds/dτ; dx/dτ is v itself).
#[derive(Clone, Copy)]
pub(super) struct Buf3<const N: usize> {
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
    pub(super) const ZERO: Self = Buf3 {
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

    pub(super) fn state(&self, i: usize) -> (RayState, RayRate) {
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
    /// a = ∇δ·n, as `state::rate`), computing δ and ∇δ in place.
    #[inline(always)]
    fn set_rate<F: LaneField, const FMA: bool>(&mut self, c: &F, cache: &mut F::Cache<N>) {
        c.full::<N, FMA>(
            cache,
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

    /// Copies the lanes of `mask` from `from`.
    #[inline(always)]
    fn keep(&mut self, mask: u64, from: &Self) {
        for (to, from) in [
            (&mut self.x, &from.x),
            (&mut self.y, &from.y),
            (&mut self.z, &from.z),
            (&mut self.vx, &from.vx),
            (&mut self.vy, &from.vy),
            (&mut self.vz, &from.vz),
            (&mut self.s, &from.s),
            (&mut self.ax, &from.ax),
            (&mut self.ay, &from.ay),
            (&mut self.az, &from.az),
            (&mut self.n, &from.n),
        ] {
            keep(mask, from, to);
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

    #[inline(always)]
    fn horizontal_velocity(&self) -> Option<[&[f64; N]; 2]> {
        Some([&self.vx, &self.vz])
    }
}

/// The 3-D lane kernel: the full field, hot spots included; the nearest
/// point keeps (x, y, z, v_x, v_y, v_z, s).
struct Lanes3<'a, F: LaneField, const N: usize> {
    field: &'a F,
    /// What the field keeps between evaluations (its culled hot spots).
    cache: F::Cache<N>,
    set: LaneSet<Buf3<N>, N, 7>,
}

impl<'a, F: LaneField, const N: usize> Lanes3<'a, F, N> {
    fn new(field: &'a F, options: &BatchOptions) -> Self {
        Lanes3 {
            field,
            cache: field.cache(),
            set: LaneSet::new(Buf3::ZERO, options.method, field.ceiling(), options.earth),
        }
    }
}

impl<F: LaneField, const N: usize> Kernel<N> for Lanes3<'_, F, N> {
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
        let attempts = match method {
            Method::Rk4 { .. } => {
                let [k2, k3, k4, _, _] = stages;
                let c = (self.field, &mut self.cache);
                rk4_3d::<F, N, FMA>(c, &control.h, y0, [k2, k3, k4], y1);
                Attempts::all::<N>()
            }
            Method::Dopri5 { .. } => {
                dopri5_3d::<F, N, FMA>((self.field, &mut self.cache), control, y0, stages, y1)
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
pub(super) fn rk4_3d<F: LaneField, const N: usize, const FMA: bool>(
    (c, cache): (&F, &mut F::Cache<N>),
    h: &[f64; N],
    y0: &Buf3<N>,
    [k2, k3, k4]: [&mut Buf3<N>; 3],
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
    k2.set_rate::<F, FMA>(c, cache);
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
    k3.set_rate::<F, FMA>(c, cache);
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
    k4.set_rate::<F, FMA>(c, cache);
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
    y1.set_rate::<F, FMA>(c, cache);
}

/// One Dormand–Prince attempt of every lane from `y0` into `y1`: the scalar
/// `Stepper::attempt`'s stages, error estimate and controller, lane-wise (see
/// `adaptive`). Rejected and underflowed lanes end where they started.
#[inline(always)]
fn dopri5_3d<F: LaneField, const N: usize, const FMA: bool>(
    (f, cache): (&F, &mut F::Cache<N>),
    control: &mut Control<N>,
    y0: &Buf3<N>,
    [k2, k3, k4, k5, k6]: &mut [Buf3<N>; 5],
    y1: &mut Buf3<N>,
) -> Attempts {
    let underflow = prepare(f, control, [&y0.x, &y0.y, &y0.z], [&y0.vx, &y0.vy, &y0.vz]);
    let h = control.used;
    // A stage state y0 + h·Σ a_j k_j, component by component: position
    // from the stages' v, v from their a.
    macro_rules! stage {
        ($out:ident, $len:literal, $c:expr, [$($k:ident),+]) => {{
            let c: [f64; $len] = $c;
            advance::<N, $len, FMA>(&y0.x, &h, c, [$(&$k.vx),+], &mut $out.x);
            advance::<N, $len, FMA>(&y0.y, &h, c, [$(&$k.vy),+], &mut $out.y);
            advance::<N, $len, FMA>(&y0.z, &h, c, [$(&$k.vz),+], &mut $out.z);
            advance::<N, $len, FMA>(&y0.vx, &h, c, [$(&$k.ax),+], &mut $out.vx);
            advance::<N, $len, FMA>(&y0.vy, &h, c, [$(&$k.ay),+], &mut $out.vy);
            advance::<N, $len, FMA>(&y0.vz, &h, c, [$(&$k.az),+], &mut $out.vz);
        }};
    }
    stage!(k2, 1, [A21], [y0]);
    k2.set_rate::<F, FMA>(f, cache);
    stage!(k3, 2, [A31, A32], [y0, k2]);
    k3.set_rate::<F, FMA>(f, cache);
    stage!(k4, 3, [A41, A42, A43], [y0, k2, k3]);
    k4.set_rate::<F, FMA>(f, cache);
    stage!(k5, 4, [A51, A52, A53, A54], [y0, k2, k3, k4]);
    k5.set_rate::<F, FMA>(f, cache);
    stage!(k6, 5, [A61, A62, A63, A64, A65], [y0, k2, k3, k4, k5]);
    k6.set_rate::<F, FMA>(f, cache);
    stage!(y1, 5, [B1, B3, B4, B5, B6], [y0, k3, k4, k5, k6]);
    advance::<N, 5, FMA>(
        &y0.s,
        &h,
        [B1, B3, B4, B5, B6],
        [&y0.n, &k3.n, &k4.n, &k5.n, &k6.n],
        &mut y1.s,
    );
    y1.set_rate::<F, FMA>(f, cache);
    // The error estimate: position from the stages' v, v from their a.
    let err2 = error_norm2(
        [
            [&y0.vx, &k3.vx, &k4.vx, &k5.vx, &k6.vx, &y1.vx],
            [&y0.vy, &k3.vy, &k4.vy, &k5.vy, &k6.vy, &y1.vy],
            [&y0.vz, &k3.vz, &k4.vz, &k5.vz, &k6.vz, &y1.vz],
        ],
        [
            [&y0.ax, &k3.ax, &k4.ax, &k5.ax, &k6.ax, &y1.ax],
            [&y0.ay, &k3.ay, &k4.ay, &k5.ay, &k6.ay, &y1.ay],
            [&y0.az, &k3.az, &k4.az, &k5.az, &k6.az, &y1.az],
        ],
        &h,
    );
    let accepted = judge::<N, FMA>(control, &err2) & !underflow;
    y1.keep(!accepted, y0);
    Attempts {
        accepted,
        underflow,
    }
}
