//! Scalars and 3-vectors shared by the medium and the tracer.
//!
//! Everything numeric in mirage is generic over [`Real`], which is `f64` for
//! ordinary evaluation and a forward-mode dual number (`num_dual::DualSVec64<N>`)
//! when the fitter needs exact derivatives of the *discrete* endpoint map. One
//! generic implementation then serves both, so the Jacobian can never drift away
//! from the function it differentiates.

use num_dual::DualNum;
use std::ops::{Add, AddAssign, Mul, Neg, Sub};

/// A scalar that mirage's physics can be evaluated in: `f64`, or a dual number
/// whose real part is an `f64`.
pub trait Real: DualNum<f64> + Copy + Send + Sync + 'static {
    /// The `f64` real part (the value without derivatives).
    #[inline]
    fn val(&self) -> f64 {
        self.re()
    }
    /// A constant (no derivative part).
    #[inline]
    fn cst(x: f64) -> Self {
        Self::from(x)
    }
}
impl<T: DualNum<f64> + Copy + Send + Sync + 'static> Real for T {}

/// A 3-vector of [`Real`]s: positions (metres) and directions, y up.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct V3<T = f64> {
    /// Horizontal coordinate x.
    pub x: T,
    /// Height above the ground.
    pub y: T,
    /// Horizontal coordinate z.
    pub z: T,
}

impl<T> V3<T> {
    /// Builds a vector from its components.
    #[inline]
    pub const fn new(x: T, y: T, z: T) -> Self {
        Self { x, y, z }
    }
}

impl V3<f64> {
    /// The zero vector.
    pub const ZERO: V3 = V3::new(0.0, 0.0, 0.0);

    /// Lifts an `f64` vector to constants of another [`Real`] type.
    #[inline]
    pub fn lift<T: Real>(self) -> V3<T> {
        V3::new(T::cst(self.x), T::cst(self.y), T::cst(self.z))
    }

    /// Euclidean length.
    #[inline]
    pub fn norm(self) -> f64 {
        self.dot(self).sqrt()
    }

    /// This vector scaled to unit length (the zero vector stays zero).
    #[inline]
    pub fn normalized(self) -> V3 {
        let n = self.norm();
        if n > 0.0 { self * (1.0 / n) } else { self }
    }

    /// Whether every component is finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// Components as an array, for JSON output.
    #[inline]
    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

impl<T: Real> V3<T> {
    /// Dot product.
    #[inline]
    pub fn dot(self, o: Self) -> T {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Multiplies by a plain `f64` constant.
    #[inline]
    pub fn scale(self, c: f64) -> Self {
        V3::new(self.x * c, self.y * c, self.z * c)
    }

    /// The real parts.
    #[inline]
    pub fn val(self) -> V3 {
        V3::new(self.x.val(), self.y.val(), self.z.val())
    }
}

impl From<[f64; 3]> for V3 {
    fn from(a: [f64; 3]) -> Self {
        V3::new(a[0], a[1], a[2])
    }
}

impl<T: Real> Add for V3<T> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl<T: Real> AddAssign for V3<T> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl<T: Real> Sub for V3<T> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl<T: Real> Neg for V3<T> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        V3::new(-self.x, -self.y, -self.z)
    }
}

impl<T: Real> Mul<T> for V3<T> {
    type Output = Self;
    #[inline]
    fn mul(self, c: T) -> Self {
        V3::new(self.x * c, self.y * c, self.z * c)
    }
}

/// The logistic function σ(t) = 1 / (1 + e^(−t)) and its derivative σ'(t),
/// evaluated from e^(−|t|) so that neither can overflow for any finite t (the
/// textbook e^t / (e^t + 1) is inf/inf = NaN for t > 709).
#[inline]
pub fn sigmoid<T: Real>(t: T) -> (T, T) {
    let e = if t.val() >= 0.0 { (-t).exp() } else { t.exp() };
    let one_plus = e + 1.0;
    let inv = one_plus.recip();
    let s = if t.val() >= 0.0 { inv } else { e * inv };
    // σ' = σ(1 − σ) = e / (1 + e)²: exact in this form at both tails.
    (s, e * inv * inv)
}

/// SplitMix64's increment γ (the golden ratio times 2⁶⁴).
const SPLITMIX_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64 (Steele, Lea & Flood 2014) as a hash: the generator's output
/// for the state `x`, i.e. `x + γ` mixed. Tiny, seedable and identical on
/// every platform, which is all mirage needs of random numbers (reproducible
/// starting points, star fields, test rays).
#[inline]
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(SPLITMIX_GAMMA);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The SplitMix64 generator: its state, advanced by γ per number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let z = splitmix64(self.0);
        self.0 = self.0.wrapping_add(SPLITMIX_GAMMA);
        z
    }

    /// The next number, uniform in [0, 1) (53 random bits).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigmoid_is_finite_and_symmetric_at_extremes() {
        for &t in &[-1e308, -800.0, -40.0, -1.0, 0.0, 1.0, 40.0, 800.0, 1e308] {
            let (s, d) = sigmoid(t);
            let (sm, dm) = sigmoid(-t);
            assert!(s.is_finite() && d.is_finite(), "t = {t}");
            assert!((s + sm - 1.0).abs() < 1e-15, "σ(t) + σ(−t) = 1 at t = {t}");
            assert_eq!(d, dm);
            assert!((0.0..=0.25).contains(&d));
        }
        assert_eq!(sigmoid(0.0), (0.5, 0.25));
    }

    #[test]
    fn sigmoid_derivative_matches_finite_difference() {
        for &t in &[-30.0, -3.0, -0.1, 0.0, 0.7, 5.0, 25.0] {
            // h = 1e-4: truncation error h² σ'''/6 ~ 1e-10, rounding ~1e-16/h.
            let h = 1e-4;
            let fd = (sigmoid(t + h).0 - sigmoid(t - h).0) / (2.0 * h);
            let (_, d) = sigmoid(t);
            assert!((fd - d).abs() <= 1e-8 * d + 1e-11, "t = {t}: {fd} vs {d}");
        }
    }
}
