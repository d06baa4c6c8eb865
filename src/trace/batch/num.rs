//! The numbers the lane terms are written in: `f64` for the plain kernels,
//! and [`Tan<P>`], a value with `P` forward-mode partial derivatives, for the
//! tangent kernel (`tangent`), which carries each ray's sensitivities to up
//! to eight parameters beside its state.
//!
//! One term implementation (`terms`) serves both through [`LaneNum`]; for
//! `f64` every operation is the plain one, so the plain kernels compute
//! exactly what they computed before the terms were made generic. A
//! [`Tan`]'s value part is computed by the same `f64` operations as the
//! plain kernels' (its derivative parts never feed back into it), so a
//! tangent trace follows the plain trace bit for bit; the derivative parts
//! follow the chain rule of each operation, as `num_dual`'s dual numbers do,
//! so they agree with the dual-number reference to rounding.
//!
//! `Tan` is a plain `Copy` struct of `P + 1` floats, every operation
//! `#[inline(always)]`: inside a lane loop the compiler splits it into
//! `P + 1` scalars and can vectorize each over the lanes, as it does the
//! plain kernels' `f64` loops, when the loop is small enough (the tangent
//! kernel runs a hot spot's term as three loops for that).
//! [`TanLanes<N, P>`] holds `N` lanes of `Tan<P>` in structure-of-arrays
//! form.

// Lane and part loops index several arrays in lockstep; `for k in 0..P` over
// fixed-size arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use crate::trace::fastexp::{fmadd, sigmoid};
use std::ops::{Add, Div, Mul, Neg, Sub};

/// What a lane term needs of its number type.
pub(crate) trait LaneNum:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    /// `1 / self` where the value is above 0, else 0 (derivatives too).
    fn recip_or_zero(self) -> Self;
    /// `a·b + c`, fused when `FMA`.
    fn fmadd<const FMA: bool>(a: Self, b: Self, c: Self) -> Self;
    /// The square root; where the value is 0 its derivative is taken as 0
    /// (the callers guard that point themselves).
    fn sqrt(self) -> Self;
    /// `1 / self`.
    fn recip(self) -> Self;
    /// The logistic function and its derivative, σ(t) and σ'(t), as
    /// [`fastexp::sigmoid`](crate::trace::fastexp) computes them.
    fn sigmoid<const FMA: bool>(self) -> (Self, Self);
}

impl LaneNum for f64 {
    #[inline(always)]
    fn recip_or_zero(self) -> Self {
        if self > 0.0 { 1.0 / self } else { 0.0 }
    }
    #[inline(always)]
    fn fmadd<const FMA: bool>(a: Self, b: Self, c: Self) -> Self {
        fmadd::<FMA>(a, b, c)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn recip(self) -> Self {
        1.0 / self
    }
    #[inline(always)]
    fn sigmoid<const FMA: bool>(self) -> (Self, Self) {
        sigmoid::<FMA>(self)
    }
}

/// A value `v` with its partial derivatives `d[k]` along `P` seeds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tan<const P: usize> {
    /// The value.
    pub v: f64,
    /// ∂v/∂p_k.
    pub d: [f64; P],
}

impl<const P: usize> Tan<P> {
    /// A value with no derivative parts.
    #[inline(always)]
    pub(crate) fn constant(v: f64) -> Self {
        Tan { v, d: [0.0; P] }
    }

    /// Each derivative part times `f`, the value `v`.
    #[inline(always)]
    fn with(v: f64, d: [f64; P], f: f64) -> Self {
        let mut out = [0.0; P];
        for k in 0..P {
            out[k] = d[k] * f;
        }
        Tan { v, d: out }
    }
}

impl<const P: usize> Add for Tan<P> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        let mut d = [0.0; P];
        for k in 0..P {
            d[k] = self.d[k] + o.d[k];
        }
        Tan { v: self.v + o.v, d }
    }
}

impl<const P: usize> Sub for Tan<P> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        let mut d = [0.0; P];
        for k in 0..P {
            d[k] = self.d[k] - o.d[k];
        }
        Tan { v: self.v - o.v, d }
    }
}

impl<const P: usize> Mul for Tan<P> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        let mut d = [0.0; P];
        for k in 0..P {
            d[k] = self.d[k] * o.v + self.v * o.d[k];
        }
        Tan { v: self.v * o.v, d }
    }
}

impl<const P: usize> Div for Tan<P> {
    type Output = Self;
    /// The quotient rule: d(a/b) = (da − (a/b)·db)/b.
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        let v = self.v / o.v;
        let mut d = [0.0; P];
        for k in 0..P {
            d[k] = (self.d[k] - v * o.d[k]) / o.v;
        }
        Tan { v, d }
    }
}

impl<const P: usize> Neg for Tan<P> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Tan::with(-self.v, self.d, -1.0)
    }
}

impl<const P: usize> LaneNum for Tan<P> {
    #[inline(always)]
    fn recip_or_zero(self) -> Self {
        if self.v > 0.0 {
            self.recip()
        } else {
            Tan::constant(0.0)
        }
    }
    #[inline(always)]
    fn fmadd<const FMA: bool>(a: Self, b: Self, c: Self) -> Self {
        let mut d = [0.0; P];
        for k in 0..P {
            d[k] = fmadd::<FMA>(a.d[k], b.v, fmadd::<FMA>(a.v, b.d[k], c.d[k]));
        }
        Tan {
            v: fmadd::<FMA>(a.v, b.v, c.v),
            d,
        }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        let f = if r > 0.0 { 0.5 / r } else { 0.0 };
        Tan::with(r, self.d, f)
    }
    #[inline(always)]
    fn recip(self) -> Self {
        let r = 1.0 / self.v;
        Tan::with(r, self.d, -(r * r))
    }
    #[inline(always)]
    fn sigmoid<const FMA: bool>(self) -> (Self, Self) {
        let (s, ds) = sigmoid::<FMA>(self.v);
        // σ'' = σ'·(1 − 2σ).
        let dds = ds * (1.0 - 2.0 * s);
        (Tan::with(s, self.d, ds), Tan::with(ds, self.d, dds))
    }
}

/// `N` lanes of [`Tan<P>`] in structure-of-arrays form: `v[i]` is lane
/// i's value, `d[k][i]` its derivative along seed k.
#[derive(Clone, Copy)]
pub(crate) struct TanLanes<const N: usize, const P: usize> {
    /// Each lane's value.
    pub v: [f64; N],
    /// `d[k][i]`: lane i's derivative along seed k.
    pub d: [[f64; N]; P],
}

impl<const N: usize, const P: usize> TanLanes<N, P> {
    /// Every lane `x`, no derivative parts.
    pub(crate) const fn splat(x: f64) -> Self {
        TanLanes {
            v: [x; N],
            d: [[0.0; N]; P],
        }
    }

    /// Lane `i` as one number.
    #[inline(always)]
    pub(crate) fn at(&self, i: usize) -> Tan<P> {
        let mut d = [0.0; P];
        for k in 0..P {
            d[k] = self.d[k][i];
        }
        Tan { v: self.v[i], d }
    }

    /// Writes lane `i`.
    #[inline(always)]
    pub(crate) fn put(&mut self, i: usize, t: Tan<P>) {
        self.v[i] = t.v;
        for k in 0..P {
            self.d[k][i] = t.d[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each operation's derivative part against a central difference of its
    /// value part, along two seeds at once.
    #[test]
    fn derivative_parts_follow_the_chain_rule() {
        let seed = |v: f64, a: f64, b: f64| Tan::<2> { v, d: [a, b] };
        let f = |t: f64| {
            let x = seed(0.7 + t, 1.0, 0.0);
            let y = seed(-1.3 + 2.0 * t, 0.0, 1.0) * x;
            let z = LaneNum::fmadd::<true>(x, y, x.recip());
            let (s, ds) = (z - y * x).sigmoid::<false>();
            (s * ds + (x * x + y * y).sqrt() - (-z)).v
        };
        let x = seed(0.7, 1.0, 0.0);
        let y = seed(-1.3, 0.0, 1.0) * x;
        let z = LaneNum::fmadd::<true>(x, y, x.recip());
        let (s, ds) = (z - y * x).sigmoid::<false>();
        let r = s * ds + (x * x + y * y).sqrt() - (-z);
        assert_eq!(r.v, f(0.0));
        // Along t, x moves by 1 and the second seed's variable by 2.
        let along = r.d[0] + 2.0 * r.d[1];
        let e = 1e-5;
        let fd = (f(e) - f(-e)) / (2.0 * e);
        assert!(
            (along - fd).abs() < 1e-8 * fd.abs().max(1.0),
            "{along} vs {fd}"
        );
    }

    /// At a zero value the square root's derivative is 0, not NaN.
    #[test]
    fn sqrt_of_zero_has_no_nan() {
        let r = Tan::<3> {
            v: 0.0,
            d: [1.0, 2.0, 3.0],
        }
        .sqrt();
        assert_eq!(r, Tan::constant(0.0));
    }
}
