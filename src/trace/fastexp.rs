//! A polynomial `exp` and logistic function that vectorize.
//!
//! `f64::exp` is a libm call, so a loop over ray lanes that calls it cannot be
//! vectorized; this one is straight-line arithmetic and bit operations, which
//! the compiler turns into SIMD code inside a lane loop.
//!
//! # Method and accuracy
//!
//! Cody–Waite reduction `x = n·ln 2 + r`, `|r| ≤ ½ ln 2`, with ln 2 split into a
//! 32-bit head (so `n·ln2_hi` is exact) and a tail; then e^r by a minimax
//! polynomial of degree 11 in Horner form (relative error 3.7·10⁻¹⁸ on that
//! interval, see `COEFFS`), and the scaling by 2ⁿ through the exponent bits.
//!
//! - For −708 ≤ x ≤ 709 the result is within **1 ulp** of `f64::exp` with fused
//!   multiply–add and within **2 ulp** without (the maximum seen over 10⁷
//!   arguments in `tests/fast_paths.rs`; the bound is the test's).
//! - For x < −708 (where e^x < 3.3·10⁻³⁰⁸, a subnormal or zero) the result is
//!   exactly 0: an absolute error below 3.3·10⁻³⁰⁸, and never NaN, also for
//!   −∞ and for arguments like −10³⁰⁰.
//! - [`exp`] returns +∞ for x > 709 (exactly: e^x is finite up to 709.78); the
//!   tracer only evaluates e^(−|t|), so it never goes there.

/// log₂ e.
const LOG2E: f64 = std::f64::consts::LOG2_E;
/// ln 2 rounded to 32 significant bits: n·LN2_HI is exact for |n| < 2²¹.
const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
/// ln 2 − LN2_HI.
const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
/// 1.5·2⁵²: adding it rounds a number of magnitude < 2⁵¹ to an integer, which
/// then sits in the low mantissa bits.
const SHIFTER: f64 = 6_755_399_441_055_744.0;
/// Below this the result would be subnormal, where the exponent-bit scaling
/// does not work; the result there is 0.
const LOWEST: f64 = -708.0;
/// Above this 2ⁿ would overflow the exponent field.
const HIGHEST: f64 = 709.0;

/// Coefficients c₁₁ down to c₂ of the minimax polynomial
/// 1 + r + Σ c_k r^k for e^r on |r| ≤ 1.0005·½ ln 2 (relative error weight,
/// c₀ = c₁ = 1 kept exact for accuracy near 0), found by the Remez exchange
/// in 60-digit arithmetic: its relative error is 3.7·10⁻¹⁸ (0.03 ulp), so the
/// result's error is the arithmetic's. Degree 11 instead of the 13 a Taylor
/// polynomial needs: two multiply–adds fewer in the kernels' innermost chain.
const COEFFS: [f64; 10] = [
    2.500_001_883_318_737_4e-8,
    2.763_030_625_029_36e-7,
    2.755_758_680_389_532_6e-6,
    2.480_149_294_963_387e-5,
    1.984_126_950_577_377_6e-4,
    1.388_888_894_375_996_5e-3,
    8.333_333_333_494_976e-3,
    4.166_666_666_652_972_5e-2,
    1.666_666_666_666_641e-1,
    5.000_000_000_000_011e-1,
];

/// `a·b + c`, fused when `FMA` (a single rounding) and plain otherwise: the
/// fused form is a libm call without hardware FMA, so callers only set `FMA`
/// inside code compiled for a CPU that has it.
#[inline(always)]
pub(crate) fn fmadd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

/// e^x for x ≤ 709, 0 for x < −708 (see the module documentation); the
/// building block of the lane kernels.
#[inline(always)]
pub(crate) fn exp_core<const FMA: bool>(x: f64) -> f64 {
    // Selects, not branches: inside a lane loop these become blends.
    let e = exp_in_range::<FMA>(if x < LOWEST { LOWEST } else { x });
    if x < LOWEST { 0.0 } else { e }
}

/// e^x for −708 ≤ x ≤ 709; outside, the exponent bits wrap (garbage). NaN
/// stays NaN.
#[inline(always)]
fn exp_in_range<const FMA: bool>(x: f64) -> f64 {
    let t = fmadd::<FMA>(x, LOG2E, SHIFTER);
    let n = t - SHIFTER;
    let r = fmadd::<FMA>(n, -LN2_HI, x);
    let r = fmadd::<FMA>(n, -LN2_LO, r);
    let mut p = COEFFS[0];
    for c in &COEFFS[1..] {
        p = fmadd::<FMA>(p, r, *c);
    }
    p = fmadd::<FMA>(p, r, 1.0);
    p = fmadd::<FMA>(p, r, 1.0);
    // t's low mantissa bits hold n + 2⁵¹ (two's complement for n < 0), so the
    // low 12 bits plus the bias, shifted into the exponent field, are 2ⁿ for
    // −1022 < n < 1024.
    let scale = f64::from_bits(t.to_bits().wrapping_add(1023) << 52);
    p * scale
}

/// e^x by the polynomial of this module, with hardware FMA when this build's
/// target has it. Within 1–2 ulp of `f64::exp` on [−708, 709], 0 below −708,
/// +∞ above 709; NaN only for NaN.
pub fn exp(x: f64) -> f64 {
    const FMA: bool = cfg!(target_feature = "fma");
    if x.is_nan() {
        return x;
    }
    if x > HIGHEST {
        f64::INFINITY
    } else {
        exp_core::<FMA>(x)
    }
}

/// x^(−1/5), the step-size controller's factor (`Stepper::control`), by
/// e^(−ln(x)/5) with a vectorizable logarithm and [`exp_core`], so that the
/// scalar controller and the lanes' compute the same factor (the lanes' only
/// difference is fused multiply–adds). Arguments are clamped to
/// [10⁻³⁰⁰, 10³⁰⁰] first (the controller clamps the factor far inside
/// that), so no input gives NaN or ∞ (NaN gives some finite number: the
/// controller replaces a non-finite error before it asks).
///
/// Accuracy: within 4·10⁻¹⁶·(1 + |ln x|/5) relative of `powf(x, −0.2)` on
/// [10⁻³⁰⁰, 10³⁰⁰] (the rounding of ln x, ~ε·|ln x|, becomes a relative error
/// of the result through the exponential; the logarithm's series is cut
/// where its next term is below 10⁻¹⁸); 2.5·10⁻¹⁴ at the ends, 10⁻¹⁵ for the
/// errors a controller sees (`tests` checks the bound over 10⁵ arguments).
#[inline(always)]
pub(crate) fn pow_neg_fifth<const FMA: bool>(x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    const HUGE: f64 = 1e300;
    const MANTISSA: u64 = (1 << 52) - 1;
    const ONE: u64 = 0x3FF0_0000_0000_0000;
    // 2⁵² + 1023 as the bit pattern's float: (bits >> 52) | its exponent is
    // 2⁵² + e_biased, so subtracting it leaves the unbiased exponent exactly.
    const EXP_MAGIC: u64 = 0x4330_0000_0000_0000;
    const EXP_BIAS: f64 = 4_503_599_627_370_496.0 + 1023.0;
    let x = if x < TINY { TINY } else { x };
    let x = if x > HUGE { HUGE } else { x };
    let bits = x.to_bits();
    let mut e = f64::from_bits((bits >> 52) | EXP_MAGIC) - EXP_BIAS;
    let mut m = f64::from_bits((bits & MANTISSA) | ONE);
    // m in [1, 2) → [√½, √2), so that |s| below is at most 0.1716.
    let big = m > std::f64::consts::SQRT_2;
    m = if big { 0.5 * m } else { m };
    e = if big { e + 1.0 } else { e };
    // ln m = 2·atanh(s), s = (m − 1)/(m + 1): 2(s + s³/3 + … + s¹⁹/19).
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let mut p = 1.0 / 19.0;
    for k in [17.0, 15.0, 13.0, 11.0, 9.0, 7.0, 5.0, 3.0, 1.0] {
        p = fmadd::<FMA>(p, s2, 1.0 / k);
    }
    let ln_m = 2.0 * s * p;
    let ln_x = fmadd::<FMA>(e, LN2_HI, fmadd::<FMA>(e, LN2_LO, ln_m));
    exp_in_range::<FMA>(-0.2 * ln_x)
}

/// The logistic function and its derivative, (σ(t), σ'(t)), from e^(−|t|) with
/// the same operations in the same order as [`crate::math::sigmoid`], so that
/// the two differ only by the exponential's rounding. For |t| > 708 it uses
/// e^(−708) ≈ 3.3·10⁻³⁰⁸ in place of e^(−|t|): σ is then 1 (t > 0) or below
/// 3.3·10⁻³⁰⁸ (t < 0) either way, and clamping the argument costs one
/// instruction where the zero of [`exp_core`] costs two.
#[inline(always)]
pub(crate) fn sigmoid<const FMA: bool>(t: f64) -> (f64, f64) {
    let a = t.abs();
    let e = exp_in_range::<FMA>(-(if a > -LOWEST { -LOWEST } else { a }));
    let inv = 1.0 / (e + 1.0);
    let ei = e * inv;
    let s = if t >= 0.0 { inv } else { ei };
    (s, ei * inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_edges() {
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-709.0), 0.0);
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp(-1e300), 0.0);
        assert_eq!(exp(710.0), f64::INFINITY);
        assert!(exp(f64::NAN).is_nan());
        assert!((exp(-708.0) / (-708.0f64).exp() - 1.0).abs() < 1e-15);
        assert!((exp(709.0) / 709.0f64.exp() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn pow_neg_fifth_matches_powf() {
        // Log-uniform over the controller's whole range, plus the edges.
        let mut worst: f64 = 0.0;
        for k in 0..=100_000 {
            let x = 10f64.powf(-300.0 + 600.0 * k as f64 / 100_000.0);
            let scale = 1.0 + x.ln().abs() / 5.0;
            for fma in [false, true] {
                let got = if fma {
                    pow_neg_fifth::<true>(x)
                } else {
                    pow_neg_fifth::<false>(x)
                };
                let want = x.powf(-0.2);
                worst = worst.max((got / want - 1.0).abs() / scale);
            }
        }
        assert!(
            worst < 4e-16,
            "worst relative error / (1 + |ln x|/5): {worst:e}"
        );
        for x in [1.0, 2.0, std::f64::consts::SQRT_2, 0.5, 32.0, 1e10] {
            let rel = (pow_neg_fifth::<false>(x) / x.powf(-0.2) - 1.0).abs();
            assert!(rel < 1e-15, "{x}: {rel:e}");
        }
        // Clamped, never NaN or infinite: 0, subnormals, ∞.
        assert_eq!(pow_neg_fifth::<false>(0.0), pow_neg_fifth::<false>(1e-300));
        assert_eq!(
            pow_neg_fifth::<false>(5e-324),
            pow_neg_fifth::<false>(1e-300)
        );
        assert_eq!(
            pow_neg_fifth::<false>(f64::INFINITY),
            pow_neg_fifth::<false>(1e300)
        );
        assert!(pow_neg_fifth::<false>(f64::NAN).is_finite());
    }
}
