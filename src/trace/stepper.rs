//! The two integrators behind one interface: classic RK4 with a fixed step, and
//! Dormand–Prince 5(4) (Hairer's DOPRI5 coefficients, local extrapolation) with
//! absolute error control.

use super::state::{RayRate, RayState, rate};
use crate::math::Real;
use crate::medium::IndexField;

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
    let k2 = rate(field, &y.advanced(h, &[(0.5, f0)]), evals);
    let k3 = rate(field, &y.advanced(h, &[(0.5, &k2)]), evals);
    let k4 = rate(field, &y.advanced(h, &[(1.0, &k3)]), evals);
    let y1 = y.advanced(
        h,
        &[
            (1.0 / 6.0, f0),
            (1.0 / 3.0, &k2),
            (1.0 / 3.0, &k3),
            (1.0 / 6.0, &k4),
        ],
    );
    let f1 = rate(field, &y1, evals);
    (y1, f1)
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
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
// Difference between the 5th- and 4th-order weights.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;

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
            Stepper::Dopri5 {
                tolerance,
                h,
                h_max,
                grow_max,
            } => {
                let hs = *h;
                if hs <= 1e-12 * (1.0 + y.x.val().norm()) {
                    return Attempt::Underflow;
                }
                let k1 = f0;
                let k2 = rate(field, &y.advanced(hs, &[(A21, k1)]), evals);
                let k3 = rate(field, &y.advanced(hs, &[(A31, k1), (A32, &k2)]), evals);
                let k4 = rate(
                    field,
                    &y.advanced(hs, &[(A41, k1), (A42, &k2), (A43, &k3)]),
                    evals,
                );
                let k5 = rate(
                    field,
                    &y.advanced(hs, &[(A51, k1), (A52, &k2), (A53, &k3), (A54, &k4)]),
                    evals,
                );
                let k6 = rate(
                    field,
                    &y.advanced(
                        hs,
                        &[(A61, k1), (A62, &k2), (A63, &k3), (A64, &k4), (A65, &k5)],
                    ),
                    evals,
                );
                let y1 = y.advanced(hs, &[(B1, k1), (B3, &k3), (B4, &k4), (B5, &k5), (B6, &k6)]);
                let k7 = rate(field, &y1, evals);
                // Error estimate from real parts only: the step sequence is then a
                // function of the real trajectory, which freezes it for the dual
                // (derivative) pass and keeps the endpoint map smooth.
                let err_x = (k1.dx.val().scale(E1)
                    + k3.dx.val().scale(E3)
                    + k4.dx.val().scale(E4)
                    + k5.dx.val().scale(E5)
                    + k6.dx.val().scale(E6)
                    + k7.dx.val().scale(E7))
                .scale(hs);
                let err_v = (k1.dv.val().scale(E1)
                    + k3.dv.val().scale(E3)
                    + k4.dv.val().scale(E4)
                    + k5.dv.val().scale(E5)
                    + k6.dv.val().scale(E6)
                    + k7.dv.val().scale(E7))
                .scale(hs);
                let err = ((err_x.dot(err_x) + err_v.dot(err_v)) / 6.0).sqrt() / *tolerance;
                let err = if err.is_finite() { err } else { 1e10 };
                if err <= 1.0 {
                    let factor = if err == 0.0 {
                        *grow_max
                    } else {
                        (0.9 * err.powf(-0.2)).clamp(0.2, *grow_max)
                    };
                    *h = (hs * factor).min(*h_max);
                    *grow_max = 5.0;
                    Attempt::Accepted(y1, k7, hs)
                } else {
                    *h = hs * (0.9 * err.powf(-0.2)).clamp(0.1, 0.9);
                    // No growth right after a rejection (Hairer's advice).
                    *grow_max = 1.0;
                    Attempt::Rejected
                }
            }
        }
    }
}
