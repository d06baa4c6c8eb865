//! The two integrators behind one interface: classic RK4 with a fixed step, and
//! Dormand–Prince 5(4) (Hairer's DOPRI5 coefficients, local extrapolation) with
//! absolute error control.

use super::state::{RayRate, RayState, rate};
use crate::math::{Real, V3};
use crate::medium::IndexField;
use crate::trace::fastexp::pow_neg_fifth;

/// How rays are integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Classic fourth-order Runge–Kutta with a fixed step (in τ, metres; τ equals
    /// arc length to within δ, i.e. a few parts in 10⁴).
    Rk4 {
        /// Step (metres).
        step: f64,
    },
    /// Dormand–Prince 5(4) with error control: the local error of each step, in
    /// position (metres) and in v (dimensionless), is kept below `tolerance`
    /// (RMS over the components).
    Dopri5 {
        /// Local error bound per step.
        tolerance: f64,
    },
}

impl Method {
    /// The name used in files and reports.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Rk4 { .. } => "rk4",
            Method::Dopri5 { .. } => "dopri5",
        }
    }
}

/// One classic RK4 step of size `h` (τ) from `y`, whose rate is `f0`; returns the
/// new state and its rate (the next step's first stage, and the end rate a
/// [`Segment`](super::Segment) needs). Five right-hand-side evaluations are
/// counted in `evals` (four new ones per step when chained, since the last is the
/// next step's first).
#[inline]
pub fn rk4_step<T: Real, F: IndexField<T> + ?Sized>(
    field: &F,
    y: &RayState<T>,
    f0: &RayRate<T>,
    h: f64,
    evals: &mut u64,
) -> (RayState<T>, RayRate<T>) {
    let (y1, [_, _, _, f1]) = rk4_stages(y, f0, h, |s| rate(field, s, evals));
    (y1, f1)
}

/// A state the tableaux below advance: the whole ray state, or its vertical
/// part in a stratified medium ([`Vertical`]). One tableau serves both, so the
/// planar steps perform the 3-D steps' operations on the components they keep.
pub(crate) trait Stage: Copy {
    /// Its rate.
    type Rate: Copy;
    /// `self + h · Σ c_i k_i`, skipping zero coefficients.
    fn advanced(&self, h: f64, terms: &[(f64, &Self::Rate)]) -> Self;
}

impl<T: Real> Stage for RayState<T> {
    type Rate = RayRate<T>;
    #[inline(always)]
    fn advanced(&self, h: f64, terms: &[(f64, &RayRate<T>)]) -> Self {
        RayState::advanced(self, h, terms)
    }
}

/// RK4's stages from `y` (rate `f0`) over `h`: the new state and the rates
/// k2, k3, k4 and the end rate.
#[inline(always)]
fn rk4_stages<S: Stage>(
    y: &S,
    f0: &S::Rate,
    h: f64,
    mut rate: impl FnMut(&S) -> S::Rate,
) -> (S, [S::Rate; 4]) {
    let k2 = rate(&y.advanced(h, &[(0.5, f0)]));
    let k3 = rate(&y.advanced(h, &[(0.5, &k2)]));
    let k4 = rate(&y.advanced(h, &[(1.0, &k3)]));
    let y1 = y.advanced(
        h,
        &[
            (1.0 / 6.0, f0),
            (1.0 / 3.0, &k2),
            (1.0 / 3.0, &k3),
            (1.0 / 6.0, &k4),
        ],
    );
    let f1 = rate(&y1);
    (y1, [k2, k3, k4, f1])
}

/// RK4's weights, for the horizontal part of a planar step.
const RK4_WEIGHTS: [f64; 4] = [1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0];

/// Dormand–Prince's stages from `y` (rate `k1`) over `hs`: the 5th-order
/// state and the rates k2 … k7 (k7 is the rate at the new state).
#[inline(always)]
fn dopri5_stages<S: Stage>(
    y: &S,
    k1: &S::Rate,
    hs: f64,
    mut rate: impl FnMut(&S) -> S::Rate,
) -> (S, [S::Rate; 6]) {
    let k2 = rate(&y.advanced(hs, &[(A21, k1)]));
    let k3 = rate(&y.advanced(hs, &[(A31, k1), (A32, &k2)]));
    let k4 = rate(&y.advanced(hs, &[(A41, k1), (A42, &k2), (A43, &k3)]));
    let k5 = rate(&y.advanced(hs, &[(A51, k1), (A52, &k2), (A53, &k3), (A54, &k4)]));
    let k6 = rate(&y.advanced(
        hs,
        &[(A61, k1), (A62, &k2), (A63, &k3), (A64, &k4), (A65, &k5)],
    ));
    let y1 = y.advanced(hs, &[(B1, k1), (B3, &k3), (B4, &k4), (B5, &k5), (B6, &k6)]);
    let k7 = rate(&y1);
    (y1, [k2, k3, k4, k5, k6, k7])
}

/// Dormand–Prince's 5th-order weights, for the horizontal part of a planar step.
pub(crate) const DOPRI5_WEIGHTS: [f64; 5] = [B1, B3, B4, B5, B6];

/// The error estimate's weighted sum of one component of the rates
/// k1, k3 … k7, in the order the 3-D estimate adds them.
#[inline(always)]
pub(crate) fn error_sum(k: [f64; 6]) -> f64 {
    k[0] * E1 + k[1] * E3 + k[2] * E4 + k[3] * E5 + k[4] * E6 + k[5] * E7
}

/// [`error_sum`] of one component `c` of the rates `ks`, times the step.
#[inline(always)]
fn weighted<K>(ks: [&K; 6], c: impl Fn(&K) -> f64, hs: f64) -> f64 {
    error_sum(ks.map(c)) * hs
}

/// The vertical part of a ray state in a stratified medium: height, v_y and
/// arc length. There δ depends on the height alone, so n∇δ has no horizontal
/// part: v_x and v_z are constants, x and z advance by them, and only these
/// three components need stages (see [`Stepper::attempt_planar`]).
#[derive(Clone, Copy, Debug)]
struct Vertical<T> {
    y: T,
    vy: T,
    s: T,
}

/// The rate of a [`Vertical`]: dy/dτ = v_y, dv_y/dτ = n·dδ/dy, ds/dτ = n.
#[derive(Clone, Copy, Debug)]
struct VerticalRate<T> {
    dy: T,
    a: T,
    ds: T,
}

impl<T: Real> Stage for Vertical<T> {
    type Rate = VerticalRate<T>;
    /// The operations of [`RayState::advanced`] on the three components.
    #[inline(always)]
    fn advanced(&self, h: f64, terms: &[(f64, &VerticalRate<T>)]) -> Self {
        let mut out = *self;
        for &(c, k) in terms {
            if c != 0.0 {
                let f = c * h;
                out.y += k.dy * f;
                out.vy += k.a * f;
                out.s += k.ds * f;
            }
        }
        out
    }
}

impl<T: Real> Vertical<T> {
    fn of(y: &RayState<T>) -> Self {
        Vertical {
            y: y.x.y,
            vy: y.v.y,
            s: y.s,
        }
    }
}

impl<T: Real> VerticalRate<T> {
    fn of(f: &RayRate<T>) -> Self {
        VerticalRate {
            dy: f.dx.y,
            a: f.dv.y,
            ds: f.ds,
        }
    }
}

/// A horizontal coordinate after a planar step: `x + Σ (c_i·h)·v`, added in
/// the order [`RayState::advanced`] adds the stages' (equal) rates.
#[inline(always)]
fn horizontal<T: Real>(x: T, v: T, h: f64, weights: &[f64]) -> T {
    let mut out = x;
    for &c in weights {
        if c != 0.0 {
            out += v * (c * h);
        }
    }
    out
}

/// The vertical rate at `s` (horizontal position `(hx, hz)`, which a
/// stratified field ignores), with the full gradient kept in `grad` for the
/// end rate. Counts one evaluation.
#[inline(always)]
fn vertical_rate<T: Real, F: IndexField<T> + ?Sized>(
    field: &F,
    hx: T,
    hz: T,
    s: &Vertical<T>,
    grad: &mut V3<T>,
    evals: &mut u64,
) -> VerticalRate<T> {
    *evals += 1;
    let (delta, g) = field.delta_gradient(V3::new(hx, s.y, hz));
    let n = delta + 1.0;
    *grad = g;
    VerticalRate {
        dy: s.vy,
        a: g.y * n,
        ds: n,
    }
}

/// The outcome of one attempted step.
pub(crate) enum Attempt<T> {
    /// The step was taken: new state, its rate, and the step used.
    Accepted(RayState<T>, RayRate<T>, f64),
    /// The error was too large; the stepper has shrunk its step.
    Rejected,
    /// The step shrank below what f64 can resolve.
    Underflow,
}

/// A stepper's working state (the adaptive one remembers its step size).
pub(crate) enum Stepper {
    Rk4 {
        h: f64,
    },
    Dopri5 {
        tolerance: f64,
        h: f64,
        h_max: f64,
        grow_max: f64,
    },
}

// Dormand–Prince 5(4) tableau (Hairer, Nørsett & Wanner, "Solving ODEs I").
pub(crate) const A21: f64 = 1.0 / 5.0;
pub(crate) const A31: f64 = 3.0 / 40.0;
pub(crate) const A32: f64 = 9.0 / 40.0;
pub(crate) const A41: f64 = 44.0 / 45.0;
pub(crate) const A42: f64 = -56.0 / 15.0;
pub(crate) const A43: f64 = 32.0 / 9.0;
pub(crate) const A51: f64 = 19372.0 / 6561.0;
pub(crate) const A52: f64 = -25360.0 / 2187.0;
pub(crate) const A53: f64 = 64448.0 / 6561.0;
pub(crate) const A54: f64 = -212.0 / 729.0;
pub(crate) const A61: f64 = 9017.0 / 3168.0;
pub(crate) const A62: f64 = -355.0 / 33.0;
pub(crate) const A63: f64 = 46732.0 / 5247.0;
pub(crate) const A64: f64 = 49.0 / 176.0;
pub(crate) const A65: f64 = -5103.0 / 18656.0;
pub(crate) const B1: f64 = 35.0 / 384.0;
pub(crate) const B3: f64 = 500.0 / 1113.0;
pub(crate) const B4: f64 = 125.0 / 192.0;
pub(crate) const B5: f64 = -2187.0 / 6784.0;
pub(crate) const B6: f64 = 11.0 / 84.0;
// Difference between the 5th- and 4th-order weights.
pub(crate) const E1: f64 = 71.0 / 57600.0;
pub(crate) const E3: f64 = -71.0 / 16695.0;
pub(crate) const E4: f64 = 71.0 / 1920.0;
pub(crate) const E5: f64 = -17253.0 / 339200.0;
pub(crate) const E6: f64 = 22.0 / 525.0;
pub(crate) const E7: f64 = -1.0 / 40.0;

impl Stepper {
    pub(crate) fn new(method: Method, max_length: f64) -> Self {
        match method {
            Method::Rk4 { step } => Stepper::Rk4 { h: step },
            Method::Dopri5 { tolerance } => {
                // No step longer than a quarter of the path, so no event can hide
                // in one step; the controller cuts the first step if it is too long.
                let h_max = if max_length.is_finite() {
                    0.25 * max_length
                } else {
                    1e3
                };
                Stepper::Dopri5 {
                    tolerance,
                    h: h_max.min(0.2 * h_max.max(1.0)),
                    h_max,
                    grow_max: 5.0,
                }
            }
        }
    }

    /// Attempts one step from `y` (whose rate is `f0`).
    /// Caps the next adaptive step at `cap` (τ units); RK4 keeps its step.
    /// The medium asks for it ([`IndexField::step_limit`]) so that a long
    /// step cannot leap over a thin layer that none of its stages samples.
    #[inline]
    pub(crate) fn limit(&mut self, cap: f64) {
        if let Stepper::Dopri5 { h, .. } = self
            && *h > cap
        {
            *h = cap;
        }
    }

    #[inline]
    pub(crate) fn attempt<T: Real, F: IndexField<T> + ?Sized>(
        &mut self,
        field: &F,
        y: &RayState<T>,
        f0: &RayRate<T>,
        evals: &mut u64,
    ) -> Attempt<T> {
        match self {
            Stepper::Rk4 { h } => {
                let (y1, f1) = rk4_step(field, y, f0, *h, evals);
                Attempt::Accepted(y1, f1, *h)
            }
            Stepper::Dopri5 { .. } => {
                let Some(hs) = self.next_step(y) else {
                    return Attempt::Underflow;
                };
                let (y1, [_, k3, k4, k5, k6, k7]) =
                    dopri5_stages(y, f0, hs, |s| rate(field, s, evals));
                // Error estimate from real parts only: the step sequence is then a
                // function of the real trajectory, which freezes it for the dual
                // (derivative) pass and keeps the endpoint map smooth.
                let ks = [f0, &k3, &k4, &k5, &k6, &k7];
                let err_x = V3::new(
                    weighted(ks, |k| k.dx.x.val(), hs),
                    weighted(ks, |k| k.dx.y.val(), hs),
                    weighted(ks, |k| k.dx.z.val(), hs),
                );
                let err_v = V3::new(
                    weighted(ks, |k| k.dv.x.val(), hs),
                    weighted(ks, |k| k.dv.y.val(), hs),
                    weighted(ks, |k| k.dv.z.val(), hs),
                );
                self.judge(hs, err_x, err_v, || (y1, k7))
            }
        }
    }

    /// [`Stepper::attempt`] for a stratified field ([`IndexField::is_stratified`]):
    /// the same step, with stages for the vertical part alone ([`Vertical`]).
    /// There n∇δ is vertical, so the 3-D stages change x, z, v_x and v_z by
    /// exactly nothing but `v·c·h` in x and z; this performs the 3-D step's
    /// operations on the components that change, in the same order, and gives
    /// the same state, rate and step as [`Stepper::attempt`] bit for bit (for
    /// dual numbers too: `tests/planar.rs`), at about half the arithmetic.
    #[inline]
    pub(crate) fn attempt_planar<T: Real, F: IndexField<T> + ?Sized>(
        &mut self,
        field: &F,
        y: &RayState<T>,
        f0: &RayRate<T>,
        evals: &mut u64,
    ) -> Attempt<T> {
        let (hx, hz) = (y.x.x, y.x.z);
        let (vx, vz) = (y.v.x, y.v.z);
        let mut grad = f0.dv;
        let v0 = Vertical::of(y);
        let k1 = VerticalRate::of(f0);
        // The 3-D state and rate at the end of a step of `h` with these weights.
        let finish = |v1: &Vertical<T>, k: &VerticalRate<T>, grad: V3<T>, h: f64, w: &[f64]| {
            let y1 = RayState {
                x: V3::new(horizontal(hx, vx, h, w), v1.y, horizontal(hz, vz, h, w)),
                v: V3::new(vx, v1.vy, vz),
                s: v1.s,
            };
            let f1 = RayRate {
                dx: y1.v,
                dv: grad * k.ds,
                ds: k.ds,
            };
            (y1, f1)
        };
        match self {
            Stepper::Rk4 { h } => {
                let h = *h;
                let (v1, [_, _, _, f1]) = rk4_stages(&v0, &k1, h, |s| {
                    vertical_rate(field, hx, hz, s, &mut grad, evals)
                });
                let (y1, f1) = finish(&v1, &f1, grad, h, &RK4_WEIGHTS);
                Attempt::Accepted(y1, f1, h)
            }
            Stepper::Dopri5 { .. } => {
                let Some(hs) = self.next_step(y) else {
                    return Attempt::Underflow;
                };
                let (v1, [_, k3, k4, k5, k6, k7]) = dopri5_stages(&v0, &k1, hs, |s| {
                    vertical_rate(field, hx, hz, s, &mut grad, evals)
                });
                // The 3-D estimate's components: dx = v (constant v_x, v_z),
                // dv = (0, a, 0).
                let ks = [&k1, &k3, &k4, &k5, &k6, &k7];
                let err_x = V3::new(
                    error_sum([vx.val(); 6]) * hs,
                    weighted(ks, |k| k.dy.val(), hs),
                    error_sum([vz.val(); 6]) * hs,
                );
                let err_v = V3::new(0.0, weighted(ks, |k| k.a.val(), hs), 0.0);
                self.judge(hs, err_x, err_v, || {
                    finish(&v1, &k7, grad, hs, &DOPRI5_WEIGHTS)
                })
            }
        }
    }

    /// The adaptive stepper's next step from `y`, or none where it has shrunk
    /// below what f64 resolves at `y`'s distance from the origin.
    fn next_step<T: Real>(&self, y: &RayState<T>) -> Option<f64> {
        let hs = match self {
            Stepper::Rk4 { h } | Stepper::Dopri5 { h, .. } => *h,
        };
        (hs > 1e-12 * (1.0 + y.x.val().norm())).then_some(hs)
    }

    /// Accepts a Dormand–Prince step of `hs` with the error estimate
    /// (`err_x`, `err_v`), building its end state and rate with `take` only
    /// then, or rejects it; either way [`Stepper::control`] sets the next step.
    #[inline]
    fn judge<T>(
        &mut self,
        hs: f64,
        err_x: V3,
        err_v: V3,
        take: impl FnOnce() -> (RayState<T>, RayRate<T>),
    ) -> Attempt<T> {
        if self.control(hs, err_x.dot(err_x) + err_v.dot(err_v)) {
            let (y1, f1) = take();
            Attempt::Accepted(y1, f1, hs)
        } else {
            Attempt::Rejected
        }
    }

    /// The step-size control after a Dormand–Prince step of `hs` whose error
    /// estimate has the squared norm `err2` (position and v, six components):
    /// sets the next step and says whether this one is accepted.
    ///
    /// After an accepted step the next is the classic `0.9·err^(−1/5)·h`,
    /// between 0.2 h and 5 h (1 h right after a rejection). Gustafsson's
    /// predictive control (RADAU5's) was tried: it halves the rejections on
    /// the Wigner fan and saves 6 % of the right-hand sides, but the fan's
    /// worst endpoint error rose from 9.0e-5 m to 1.37e-4 m at tolerance 1e-6,
    /// because the rejected steps' smaller successors were what kept it there.
    fn control(&mut self, hs: f64, err2: f64) -> bool {
        let Stepper::Dopri5 {
            tolerance,
            h,
            h_max,
            grow_max,
        } = self
        else {
            return true;
        };
        let (accept, next, grow) = control_step::<false>(hs, err2, *tolerance, *h_max, *grow_max);
        *h = next;
        *grow_max = grow;
        accept
    }
}

/// The step-size control of [`Stepper::control`] as a pure, branch-free
/// function, so that the lanes kernels run the same arithmetic in their lane
/// loops: after a Dormand–Prince step of `hs` whose error estimate has the
/// squared norm `err2` (six components), with the stepper's `tolerance`,
/// longest step `h_max` and growth limit `grow_max`, returns whether the step
/// is accepted, the next step and the next growth limit.
///
/// Accepted (RMS error ≤ tolerance): `0.9·err^(−1/5)·h`, between 0.2 h and
/// `grow_max`·h (an error of exactly 0 gives the full growth), at most
/// `h_max`; the growth limit goes back to 5. Rejected: the same factor
/// between 0.1 and 0.9, and no growth on the next step (Hairer's advice).
/// A non-finite error counts as 10¹⁰ (rejected, shrunk tenfold).
#[inline(always)]
pub(crate) fn control_step<const FMA: bool>(
    hs: f64,
    err2: f64,
    tolerance: f64,
    h_max: f64,
    grow_max: f64,
) -> (bool, f64, f64) {
    let err = (err2 / 6.0).sqrt() / tolerance;
    let err = if err.abs() < f64::INFINITY { err } else { 1e10 };
    // err^(−1/5), once a step; err = 0 is clamped to 1e-300 inside, whose
    // factor (≈ 1e60) clamps to the growth limit, as an exact 0 should.
    let factor = 0.9 * pow_neg_fifth::<FMA>(err);
    let accept = err <= 1.0;
    let up = if factor < 0.2 { 0.2 } else { factor };
    let up = if up > grow_max { grow_max } else { up };
    let grown = hs * up;
    let grown = if grown > h_max { h_max } else { grown };
    let down = if factor < 0.1 { 0.1 } else { factor };
    let down = if down > 0.9 { 0.9 } else { down };
    let shrunk = hs * down;
    if accept {
        (true, grown, 5.0)
    } else {
        (false, shrunk, 1.0)
    }
}
