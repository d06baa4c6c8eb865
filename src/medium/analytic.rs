//! Media with exact ray solutions, for tests and as a reference.

use super::IndexField;
use crate::math::{Real, V3};

/// No air at all: δ ≡ 0, so every ray is a straight line.
#[derive(Clone, Copy, Debug, Default)]
pub struct Vacuum;

impl<T: Real> IndexField<T> for Vacuum {
    fn delta_gradient(&self, _p: V3<T>) -> (T, V3<T>) {
        let z = T::cst(0.0);
        (z, V3::new(z, z, z))
    }
    fn is_stratified(&self) -> bool {
        true
    }
}

/// A medium whose n² is linear in height: n² = n0² + g·y.
///
/// With the optical parameter τ (dτ = ds/n) the ray equation becomes
/// d²x/dτ² = ½∇(n²) = (0, g/2, 0), so every ray is exactly the parabola
/// `x(τ) = o + v0·τ + ¼·(0, g, 0)·τ²` with `v0 = n(o)·d`.
#[derive(Clone, Copy, Debug)]
pub struct LinearSquare {
    /// n at y = 0.
    pub n0: f64,
    /// d(n²)/dy, per metre.
    pub g: f64,
}

impl LinearSquare {
    /// n² at height y, kept positive so the medium is defined everywhere.
    fn n_squared(&self, y: f64) -> f64 {
        (self.n0 * self.n0 + self.g * y).max(1e-12)
    }

    /// The exact position at optical parameter τ of the ray launched from `o`
    /// along the unit direction `d`.
    pub fn exact_position(&self, o: V3, d: V3, tau: f64) -> V3 {
        let v0 = d * self.n_squared(o.y).sqrt();
        o + v0 * tau + V3::new(0.0, 0.25 * self.g * tau * tau, 0.0)
    }
}

impl<T: Real> IndexField<T> for LinearSquare {
    fn delta_gradient(&self, p: V3<T>) -> (T, V3<T>) {
        let n2 = T::cst(self.n0 * self.n0) + p.y * self.g;
        let n2 = if n2.val() < 1e-12 { T::cst(1e-12) } else { n2 };
        let n = n2.sqrt();
        let z = T::cst(0.0);
        // δ = n − 1, ∇δ = ∇n = g / (2n) ŷ.
        (n - 1.0, V3::new(z, n.recip() * (0.5 * self.g), z))
    }
    fn is_stratified(&self) -> bool {
        true
    }
}
