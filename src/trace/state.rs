//! The ray equation in the optical parameter τ (dτ = ds / n):
//! `dx/dτ = v`, `dv/dτ = n∇n = (1 + δ)∇δ`, `ds/dτ = n`, with `v = n·t`.
//!
//! This form needs no division by n, and when n² is linear in y its right-hand
//! side is constant, so RK4 reproduces the exact parabola to rounding.

use crate::math::{Real, V3};
use crate::medium::IndexField;

/// A point of the ray: position, `v = n·t`, and the arc length travelled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayState<T = f64> {
    /// Position (metres).
    pub x: V3<T>,
    /// The ray vector n·t (|v| = n).
    pub v: V3<T>,
    /// Arc length from the origin (metres).
    pub s: T,
}

/// The derivative of a [`RayState`] with respect to τ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayRate<T = f64> {
    /// dx/dτ = v.
    pub dx: V3<T>,
    /// dv/dτ = n∇n.
    pub dv: V3<T>,
    /// ds/dτ = n.
    pub ds: T,
}

impl<T: Real> RayState<T> {
    /// `self + h · Σ c_i k_i`, skipping zero coefficients.
    #[inline(always)]
    pub fn advanced(&self, h: f64, terms: &[(f64, &RayRate<T>)]) -> Self {
        let mut out = *self;
        for &(c, k) in terms {
            if c != 0.0 {
                let f = c * h;
                out.x += k.dx.scale(f);
                out.v += k.dv.scale(f);
                out.s += k.ds * f;
            }
        }
        out
    }
}

/// The right-hand side of the ray equation at `y`. Counts one evaluation.
#[inline(always)]
pub fn rate<T: Real, F: IndexField<T> + ?Sized>(
    field: &F,
    y: &RayState<T>,
    evaluations: &mut u64,
) -> RayRate<T> {
    *evaluations += 1;
    let (delta, grad) = field.delta_gradient(y.x);
    let n = delta + 1.0;
    RayRate {
        dx: y.v,
        dv: grad * n,
        ds: n,
    }
}
