//! Media with exact ray solutions, for tests and as a reference.

use super::IndexField;
use super::envelope::{Envelope, VerticalFeature};
use crate::error::FieldError;
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
///
/// It is also a kind of [`Medium`](super::Medium) (`Medium::LinearSquare`),
/// with the parameters `linear_square.n0` and `linear_square.g`: the second
/// kind that shows the tracer, the fit and the renderer take any kind. It is
/// built in code (tests, validation), not read from files.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearSquare<T = f64> {
    /// n at y = 0.
    pub n0: T,
    /// d(n²)/dy, per metre.
    pub g: T,
}

/// The floor under n², so that the medium is defined everywhere.
const N2_FLOOR: f64 = 1e-12;

impl LinearSquare {
    /// n² at height y, kept positive so the medium is defined everywhere.
    fn n_squared(&self, y: f64) -> f64 {
        (self.n0 * self.n0 + self.g * y).max(N2_FLOOR)
    }

    /// The exact position at optical parameter τ of the ray launched from `o`
    /// along the unit direction `d`.
    pub fn exact_position(&self, o: V3, d: V3, tau: f64) -> V3 {
        let v0 = d * self.n_squared(o.y).sqrt();
        o + v0 * tau + V3::new(0.0, 0.25 * self.g * tau * tau, 0.0)
    }

    /// Bounds and features for stepping through the air, up to
    /// [`LinearSquare::ENVELOPE_TOP`]: n is monotonic in y, so its extremes are
    /// at the ground and at that height; the medium has no vertical feature
    /// finer than that height.
    pub fn envelope(&self) -> Envelope {
        let top = Self::ENVELOPE_TOP;
        let (a, b) = (self.n_squared(0.0).sqrt(), self.n_squared(top).sqrt());
        let n_min = a.min(b);
        Envelope {
            n_max: a.max(b),
            n_min,
            gradient_max: 0.5 * self.g.abs() / n_min,
            layers: vec![VerticalFeature {
                scale: top / 40.0,
                centre: 0.0,
            }],
            patches: Vec::new(),
        }
    }

    /// The height up to which [`LinearSquare::envelope`] bounds n (metres).
    pub const ENVELOPE_TOP: f64 = 50_000.0;

    /// Checks that n0 and g are finite and n0 > 0; paths relative to the medium.
    pub fn validate(&self) -> Result<(), FieldError> {
        if !(self.n0.is_finite() && self.n0 > 0.0) {
            return Err(FieldError::new(
                "linear_square.n0",
                format!("must be a finite number > 0, got {}", self.n0),
            ));
        }
        if !self.g.is_finite() {
            return Err(FieldError::new(
                "linear_square.g",
                format!("must be a finite number, got {}", self.g),
            ));
        }
        Ok(())
    }
}

impl<T: Real> IndexField<T> for LinearSquare<T> {
    fn delta_gradient(&self, p: V3<T>) -> (T, V3<T>) {
        let n2 = self.n0 * self.n0 + p.y * self.g;
        let n2 = if n2.val() < N2_FLOOR {
            T::cst(N2_FLOOR)
        } else {
            n2
        };
        let n = n2.sqrt();
        let z = T::cst(0.0);
        // δ = n − 1, ∇δ = ∇n = g / (2n) ŷ.
        (n - 1.0, V3::new(z, n.recip() * self.g * 0.5, z))
    }
    fn is_stratified(&self) -> bool {
        true
    }
}
