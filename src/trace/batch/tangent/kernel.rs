//! The tangent lane kernel: the 3-D kernel's RK4 and Dormand–Prince steps
//! with every state component carried as a [`TanLanes`] (value and `P`
//! derivative parts), and the endpoint's derivative found where the value
//! trace crosses its plane.
//!
//! The value parts are stepped by the same operations as the plain 3-D
//! kernel, so the driver (`driver::drive`) decides every event and step on
//! them exactly as it does for a plain batch. A step's derivative parts are
//! the same linear combination of the stages' derivative parts (the step
//! size has none: Dormand–Prince's steps are chosen from the values, which
//! freezes the step sequence for the derivative, as in the dual-number
//! path). When a ray crosses its plane, the crossing step is rebuilt as a
//! dual-number [`Segment`] and located by the scalar tracer's own
//! `event::locate`, whose Newton step carries the implicit derivative of
//! the crossing.

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::super::adaptive::{error_norm2, judge, keep, prepare};
use super::super::driver::Kernel;
use super::super::field::LaneField;
use super::super::job::RayJob;
use super::super::lanes::{Attempts, Control, LaneBuf, LaneSet};
use super::super::num::{Tan, TanLanes};
use super::super::stratified::stages_per_attempt;
use super::field::{TanField, dual_of, parts};
use crate::math::V3;
use crate::trace::event::locate;
use crate::trace::fastexp::fmadd;
use crate::trace::stepper::{
    A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65, B1, B3, B4, B5, B6,
};
use crate::trace::{Earth, Method, RayRate, RayState, Segment};
use num_dual::DualSVec64;

/// One buffer of lane states with derivative parts: position, v = n·t, arc
/// length, and the rate's parts a = n∇n and n.
#[derive(Clone, Copy)]
pub(crate) struct TanBuf<const N: usize, const P: usize> {
    x: TanLanes<N, P>,
    y: TanLanes<N, P>,
    z: TanLanes<N, P>,
    vx: TanLanes<N, P>,
    vy: TanLanes<N, P>,
    vz: TanLanes<N, P>,
    s: TanLanes<N, P>,
    ax: TanLanes<N, P>,
    ay: TanLanes<N, P>,
    az: TanLanes<N, P>,
    n: TanLanes<N, P>,
}

impl<const N: usize, const P: usize> TanBuf<N, P> {
    const ZERO: Self = TanBuf {
        x: TanLanes::splat(0.0),
        y: TanLanes::splat(0.0),
        z: TanLanes::splat(0.0),
        vx: TanLanes::splat(0.0),
        vy: TanLanes::splat(0.0),
        vz: TanLanes::splat(0.0),
        s: TanLanes::splat(0.0),
        ax: TanLanes::splat(0.0),
        ay: TanLanes::splat(0.0),
        az: TanLanes::splat(0.0),
        // n = 1 in idle lanes, as in the plain kernel.
        n: TanLanes::splat(1.0),
    };

    /// Every component, in a fixed order.
    #[inline(always)]
    fn parts_mut(&mut self) -> [&mut TanLanes<N, P>; 11] {
        [
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.vx,
            &mut self.vy,
            &mut self.vz,
            &mut self.s,
            &mut self.ax,
            &mut self.ay,
            &mut self.az,
            &mut self.n,
        ]
    }

    /// Every component, in the order of [`Self::parts_mut`].
    #[inline(always)]
    fn parts(&self) -> [&TanLanes<N, P>; 11] {
        [
            &self.x, &self.y, &self.z, &self.vx, &self.vy, &self.vz, &self.s, &self.ax, &self.ay,
            &self.az, &self.n,
        ]
    }

    /// Lane `i`'s state and rate, values only.
    fn state(&self, i: usize) -> (RayState, RayRate) {
        let v = V3::new(self.vx.v[i], self.vy.v[i], self.vz.v[i]);
        (
            RayState {
                x: V3::new(self.x.v[i], self.y.v[i], self.z.v[i]),
                v,
                s: self.s.v[i],
            },
            RayRate {
                dx: v,
                dv: V3::new(self.ax.v[i], self.ay.v[i], self.az.v[i]),
                ds: self.n.v[i],
            },
        )
    }

    /// Lane `i`'s state and rate as dual numbers.
    fn dual_state(&self, i: usize) -> (RayState<DualSVec64<P>>, RayRate<DualSVec64<P>>) {
        let d = |c: &TanLanes<N, P>| dual_of(c.at(i));
        let v = V3::new(d(&self.vx), d(&self.vy), d(&self.vz));
        (
            RayState {
                x: V3::new(d(&self.x), d(&self.y), d(&self.z)),
                v,
                s: d(&self.s),
            },
            RayRate {
                dx: v,
                dv: V3::new(d(&self.ax), d(&self.ay), d(&self.az)),
                ds: d(&self.n),
            },
        )
    }

    /// Sets the rate from the field at the buffer's positions: n = 1 + δ,
    /// a = n·∇δ, derivative parts included.
    #[inline(always)]
    fn set_rate<const FMA: bool>(&mut self, field: &TanField<P>) {
        // On the local result (see `TanField::full`), then stored.
        let [mut n, mut ax, mut ay, mut az] = field.full::<N, FMA>([&self.x, &self.y, &self.z]);
        for i in 0..N {
            let ni = n.at(i) + Tan::constant(1.0);
            n.put(i, ni);
            ax.put(i, ax.at(i) * ni);
            ay.put(i, ay.at(i) * ni);
            az.put(i, az.at(i) * ni);
        }
        (self.n, self.ax, self.ay, self.az) = (n, ax, ay, az);
    }

    /// Copies the lanes of `mask` from `from`, derivative parts included.
    #[inline(always)]
    fn keep(&mut self, mask: u64, from: &Self) {
        for (to, from) in self.parts_mut().into_iter().zip(from.parts()) {
            keep(mask, &from.v, &mut to.v);
            for k in 0..P {
                keep(mask, &from.d[k], &mut to.d[k]);
            }
        }
    }
}

impl<const N: usize, const P: usize> LaneBuf<N, 7> for TanBuf<N, P> {
    /// The values only; [`TanKernel::load`] writes the derivative parts.
    fn put(&mut self, lane: usize, start: &RayState, rate: &RayRate) {
        let values = [
            start.x.x, start.x.y, start.x.z, start.v.x, start.v.y, start.v.z, start.s, rate.dv.x,
            rate.dv.y, rate.dv.z, rate.ds,
        ];
        for (c, v) in self.parts_mut().into_iter().zip(values) {
            c.v[lane] = v;
        }
    }

    #[inline(always)]
    fn tracked(&self) -> [&[f64; N]; 7] {
        [
            &self.x.v, &self.y.v, &self.z.v, &self.vx.v, &self.vy.v, &self.vz.v, &self.s.v,
        ]
    }

    #[inline(always)]
    fn screened(&self) -> [&[f64; N]; 5] {
        [&self.x.v, &self.y.v, &self.z.v, &self.vy.v, &self.s.v]
    }

    #[inline(always)]
    fn horizontal_velocity(&self) -> Option<[&[f64; N]; 2]> {
        Some([&self.vx.v, &self.vz.v])
    }
}

/// The endpoint derivative of one ray: `d[c][k]` = ∂(endpoint_c)/∂p_k;
/// `None` until the ray crossed its plane (a ray that ends otherwise keeps
/// `None`, and its caller takes the dual-number path for it).
pub(crate) type EndDerivative<const P: usize> = Option<[[f64; P]; 3]>;

/// The tangent kernel over a lane field `F` (the plain field the driver
/// starts the rays with and decides events on) and its [`TanField`].
pub(crate) struct TanKernel<'a, F: LaneField, const N: usize, const P: usize> {
    field: &'a F,
    tan: &'a TanField<P>,
    set: LaneSet<TanBuf<N, P>, N, 7>,
    /// Per job of the batch, its endpoint derivative once found.
    pub(crate) ends: Vec<EndDerivative<P>>,
}

impl<'a, F: LaneField, const N: usize, const P: usize> TanKernel<'a, F, N, P> {
    /// A kernel for `jobs` jobs stepped by `method` over `earth`.
    pub(crate) fn new(
        field: &'a F,
        tan: &'a TanField<P>,
        method: Method,
        earth: Earth,
        jobs: usize,
    ) -> Self {
        TanKernel {
            field,
            tan,
            set: LaneSet::new(TanBuf::ZERO, method, field.ceiling(), earth),
            ends: vec![None; jobs],
        }
    }
}

impl<F: LaneField, const N: usize, const P: usize> Kernel<N> for TanKernel<'_, F, N, P> {
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
        // The start's derivative parts: the origin and direction are fixed,
        // so v₀ = t·(1 + δ(x₀)) and the rate move with δ's coefficients
        // alone. The field at the origin in one lane, with the values the
        // driver computed kept as they are.
        let mut at = TanBuf::<1, P>::ZERO;
        at.x.v[0] = start.x.x;
        at.y.v[0] = start.x.y;
        at.z.v[0] = start.x.z;
        at.set_rate::<false>(self.tan);
        let n = at.n.at(0);
        let b = self.set.current_mut();
        let dir = job.direction;
        for k in 0..P {
            b.x.d[k][lane] = 0.0;
            b.y.d[k][lane] = 0.0;
            b.z.d[k][lane] = 0.0;
            b.s.d[k][lane] = 0.0;
            b.vx.d[k][lane] = dir.x * n.d[k];
            b.vy.d[k][lane] = dir.y * n.d[k];
            b.vz.d[k][lane] = dir.z * n.d[k];
            b.ax.d[k][lane] = at.ax.d[k][0];
            b.ay.d[k][lane] = at.ay.d[k][0];
            b.az.d[k][lane] = at.az.d[k][0];
            b.n.d[k][lane] = n.d[k];
        }
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
                rk4::<N, P, FMA>(self.tan, &control.h, y0, stages, y1);
                Attempts::all::<N>()
            }
            Method::Dopri5 { .. } => {
                dopri5::<F, N, P, FMA>(self.field, self.tan, control, y0, stages, y1)
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
        self.set.segment(lane, TanBuf::state)
    }

    fn nearest(&self, lane: usize) -> RayState {
        let [x, y, z, vx, vy, vz, s] = self.set.nearest(lane);
        RayState {
            x: V3::new(x, y, z),
            v: V3::new(vx, vy, vz),
            s,
        }
    }

    fn finished(&mut self, lane: usize, index: usize, job: &RayJob, plane: Option<f64>) {
        let Some(theta) = plane else {
            self.ends[index] = None;
            return;
        };
        let (before, after) = self.set.buffers();
        let (y0, f0) = before.dual_state(lane);
        let (y1, f1) = after.dual_state(lane);
        let real = self.segment(lane);
        let seg = Segment {
            y0,
            f0,
            y1,
            f1,
            h: real.h,
        };
        let t = &job.target;
        let (e, _) = locate(&seg, &real, theta, t.normal, t.point);
        self.ends[index] = Some([parts(e.x), parts(e.y), parts(e.z)]);
    }
}

/// A step's rows: for each stage state (the last row: the step's end), the
/// terms `(c, m)` of `y0 + h·Σ c·k_m`, where source 0 is the step's start
/// and source m the m-th stage state, each giving its rate, in the plain
/// kernel's order of addition (zero coefficients left out, as there).
type Rows = [&'static [(f64, usize)]];

/// RK4: k2 at y + h/2·k1, k3 at y + h/2·k2, k4 at y + h·k3, then
/// y + h/6·k1 + h/3·k2 + h/3·k3 + h/6·k4.
const RK4_ROWS: &Rows = &[
    &[(0.5, 0)],
    &[(0.5, 1)],
    &[(1.0, 2)],
    &[
        (1.0 / 6.0, 0),
        (1.0 / 3.0, 1),
        (1.0 / 3.0, 2),
        (1.0 / 6.0, 3),
    ],
];

/// Dormand–Prince 5(4): the stages k2 … k6, then the fifth-order end.
const DOPRI5_ROWS: &Rows = &[
    &[(A21, 0)],
    &[(A31, 0), (A32, 1)],
    &[(A41, 0), (A42, 1), (A43, 2)],
    &[(A51, 0), (A52, 1), (A53, 2), (A54, 3)],
    &[(A61, 0), (A62, 1), (A63, 2), (A64, 3), (A65, 4)],
    &[(B1, 0), (B3, 2), (B4, 3), (B5, 4), (B6, 5)],
];

/// One component of a stage state: `y0 + Σ k_t·(c_t·h)` per lane, values
/// and derivative parts (the step has none), added term by term as the
/// plain kernel's `advance`.
#[inline(always)]
fn combo<const N: usize, const P: usize, const FMA: bool>(
    y0: &TanLanes<N, P>,
    h: &[f64; N],
    terms: &[(f64, &TanLanes<N, P>)],
    out: &mut TanLanes<N, P>,
) {
    *out = *y0;
    for &(c, k) in terms {
        let mut f = [0.0; N];
        for i in 0..N {
            f[i] = c * h[i];
        }
        for i in 0..N {
            out.v[i] = fmadd::<FMA>(k.v[i], f[i], out.v[i]);
        }
        for p in 0..P {
            for i in 0..N {
                out.d[p][i] = fmadd::<FMA>(k.d[p][i], f[i], out.d[p][i]);
            }
        }
    }
}

/// The stage states of one step by `rows`, each with its rate, the last
/// into `y1` (with its arc length). One loop over the stages, so that the
/// field's evaluation is compiled once per kernel, not once per stage.
#[inline(always)]
fn run_stages<const N: usize, const P: usize, const FMA: bool>(
    field: &TanField<P>,
    h: &[f64; N],
    rows: &Rows,
    y0: &TanBuf<N, P>,
    stages: &mut [TanBuf<N, P>; 5],
    y1: &mut TanBuf<N, P>,
) {
    let last = rows.len() - 1;
    for (j, row) in rows.iter().enumerate() {
        let (done, rest) = stages.split_at_mut(j.min(5));
        let out: &mut TanBuf<N, P> = if j < last { &mut rest[0] } else { &mut *y1 };
        let source = |m: usize| if m == 0 { y0 } else { &done[m - 1] };
        // Position from the sources' v, v from their a, s from their n.
        macro_rules! component {
            ($to:ident, $rate:ident) => {{
                let mut terms = [(0.0, &y0.$rate); 5];
                for (t, &(c, m)) in row.iter().enumerate() {
                    terms[t] = (c, &source(m).$rate);
                }
                combo::<N, P, FMA>(&y0.$to, h, &terms[..row.len()], &mut out.$to);
            }};
        }
        component!(x, vx);
        component!(y, vy);
        component!(z, vz);
        component!(vx, ax);
        component!(vy, ay);
        component!(vz, az);
        if j == last {
            component!(s, n);
        }
        out.set_rate::<FMA>(field);
    }
}

/// One RK4 step of every lane, as the plain kernel's `rk4_3d`, derivative
/// parts included.
#[inline(always)]
fn rk4<const N: usize, const P: usize, const FMA: bool>(
    field: &TanField<P>,
    h: &[f64; N],
    y0: &TanBuf<N, P>,
    stages: &mut [TanBuf<N, P>; 5],
    y1: &mut TanBuf<N, P>,
) {
    run_stages::<N, P, FMA>(field, h, RK4_ROWS, y0, stages, y1);
}

/// One Dormand–Prince attempt of every lane, as the plain kernel's
/// `dopri5_3d`: stages, error estimate and controller on the values (the
/// plain lane field `f` caps the steps), the derivative parts carried
/// through the same stages. Rejected and underflowed lanes end where they
/// started.
#[inline(always)]
fn dopri5<F: LaneField, const N: usize, const P: usize, const FMA: bool>(
    f: &F,
    field: &TanField<P>,
    control: &mut Control<N>,
    y0: &TanBuf<N, P>,
    stages: &mut [TanBuf<N, P>; 5],
    y1: &mut TanBuf<N, P>,
) -> Attempts {
    let underflow = prepare(
        f,
        control,
        [&y0.x.v, &y0.y.v, &y0.z.v],
        [&y0.vx.v, &y0.vy.v, &y0.vz.v],
    );
    let h = control.used;
    run_stages::<N, P, FMA>(field, &h, DOPRI5_ROWS, y0, stages, y1);
    let [_, k3, k4, k5, k6] = &*stages;
    // The error estimate, on the values only.
    let err2 = error_norm2(
        [
            [&y0.vx.v, &k3.vx.v, &k4.vx.v, &k5.vx.v, &k6.vx.v, &y1.vx.v],
            [&y0.vy.v, &k3.vy.v, &k4.vy.v, &k5.vy.v, &k6.vy.v, &y1.vy.v],
            [&y0.vz.v, &k3.vz.v, &k4.vz.v, &k5.vz.v, &k6.vz.v, &y1.vz.v],
        ],
        [
            [&y0.ax.v, &k3.ax.v, &k4.ax.v, &k5.ax.v, &k6.ax.v, &y1.ax.v],
            [&y0.ay.v, &k3.ay.v, &k4.ay.v, &k5.ay.v, &k6.ay.v, &y1.ay.v],
            [&y0.az.v, &k3.az.v, &k4.az.v, &k5.az.v, &k6.az.v, &y1.az.v],
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
