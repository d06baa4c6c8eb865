//! Quintic Hermite interpolation of a step, for locating events inside it.
//!
//! Position, first and second τ-derivatives are known at both ends of every step
//! (x, v and n∇n), so the quintic Hermite interpolant has an O(h⁶) local error:
//! far below both RK4's and Dormand–Prince's, and exact for the parabola.

use super::state::{RayRate, RayState};
use crate::math::{Real, V3};

/// One integration step, as seen by event location.
#[derive(Clone, Copy, Debug)]
pub struct Segment<T> {
    /// State at the start.
    pub y0: RayState<T>,
    /// Rate at the start.
    pub f0: RayRate<T>,
    /// State at the end.
    pub y1: RayState<T>,
    /// Rate at the end.
    pub f1: RayRate<T>,
    /// Step in τ.
    pub h: f64,
}

/// Quintic Hermite basis weights for (x0, h·x0', h²·x0'', h²·x1'', h·x1', x1) at θ,
/// and their θ-derivatives.
#[inline]
fn basis<T: Real>(t: T) -> ([T; 6], [T; 6]) {
    let t2 = t * t;
    let t3 = t2 * t;
    let t4 = t3 * t;
    let t5 = t4 * t;
    let one = T::cst(1.0);
    let h5 = t3 * 10.0 - t4 * 15.0 + t5 * 6.0;
    let w = [
        one - h5,
        t - t3 * 6.0 + t4 * 8.0 - t5 * 3.0,
        t2 * 0.5 - t3 * 1.5 + t4 * 1.5 - t5 * 0.5,
        t3 * 0.5 - t4 + t5 * 0.5,
        -(t3 * 4.0) + t4 * 7.0 - t5 * 3.0,
        h5,
    ];
    let d5 = t2 * 30.0 - t3 * 60.0 + t4 * 30.0;
    let d = [
        -d5,
        one - t2 * 18.0 + t3 * 32.0 - t4 * 15.0,
        t - t2 * 4.5 + t3 * 6.0 - t4 * 2.5,
        t2 * 1.5 - t3 * 4.0 + t4 * 2.5,
        -(t2 * 12.0) + t3 * 28.0 - t4 * 15.0,
        d5,
    ];
    (w, d)
}

impl<T: Real> Segment<T> {
    /// Interpolated position at θ ∈ [0, 1] (θ may carry derivatives).
    #[inline]
    pub fn position(&self, theta: T) -> V3<T> {
        let (w, _) = basis(theta);
        self.combine(&w)
    }

    /// Interpolated position and its derivative with respect to θ.
    #[inline]
    pub fn position_and_slope(&self, theta: T) -> (V3<T>, V3<T>) {
        let (w, d) = basis(theta);
        (self.combine(&w), self.combine(&d))
    }

    /// Interpolated state at θ: position (quintic), v (cubic Hermite on v and
    /// dv/dτ, which avoids the cancellation of differentiating positions), and arc
    /// length (linear in θ: its error is O(δ·h), irrelevant for the uses of s).
    pub fn state(&self, theta: T) -> RayState<T> {
        let t = theta;
        let t2 = t * t;
        let t3 = t2 * t;
        let one = T::cst(1.0);
        let h01 = t2 * 3.0 - t3 * 2.0;
        let (h00, h10, h11) = (one - h01, t - t2 * 2.0 + t3, t3 - t2);
        let v = self.y0.v * h00
            + self.f0.dv.scale(self.h) * h10
            + self.y1.v * h01
            + self.f1.dv.scale(self.h) * h11;
        RayState {
            x: self.position(theta),
            v,
            s: self.y0.s + (self.y1.s - self.y0.s) * theta,
        }
    }

    #[inline]
    fn combine(&self, w: &[T; 6]) -> V3<T> {
        let h = self.h;
        let h2 = h * h;
        self.y0.x * w[0]
            + self.f0.dx.scale(h) * w[1]
            + self.f0.dv.scale(h2) * w[2]
            + self.f1.dv.scale(h2) * w[3]
            + self.f1.dx.scale(h) * w[4]
            + self.y1.x * w[5]
    }

    /// The segment's real parts.
    pub fn val(&self) -> Segment<f64> {
        let st = |y: &RayState<T>| RayState {
            x: y.x.val(),
            v: y.v.val(),
            s: y.s.val(),
        };
        let rt = |f: &RayRate<T>| RayRate {
            dx: f.dx.val(),
            dv: f.dv.val(),
            ds: f.ds.val(),
        };
        Segment {
            y0: st(&self.y0),
            f0: rt(&self.f0),
            y1: st(&self.y1),
            f1: rt(&self.f1),
            h: self.h,
        }
    }
}

/// The root in [a, b] of a function with g(a) < 0 ≤ g(b) (or the reverse), by
/// Newton steps kept inside a shrinking bracket (bisection when Newton leaves
/// it). Converges to full f64 precision in a handful of iterations on the
/// quintic interpolants used here.
pub fn bracketed_root(mut a: f64, mut b: f64, g: impl Fn(f64) -> (f64, f64)) -> f64 {
    let (ga, _) = g(a);
    let rising = ga < 0.0;
    let mut t = 0.5 * (a + b);
    for _ in 0..100 {
        let (gt, dg) = g(t);
        if gt == 0.0 {
            return t;
        }
        if (gt < 0.0) == rising {
            a = t;
        } else {
            b = t;
        }
        let newton = t - gt / dg;
        let next = if newton.is_finite() && newton > a && newton < b {
            newton
        } else {
            0.5 * (a + b)
        };
        if (next - t).abs() <= 4.0 * f64::EPSILON * t.abs().max(1e-300) || b - a <= f64::EPSILON {
            return next;
        }
        t = next;
    }
    t
}
