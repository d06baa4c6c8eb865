//! Water vapour in the air: relative humidity turned into the partial pressure and
//! the mole fraction that the refractivity formulas take.
//!
//! Everything follows the documentation of NIST's refractive-index-of-air
//! calculator (J. A. Stone and J. H. Zimmerman, *Index of Refraction of Air*,
//! NIST Engineering Metrology Toolbox, appendix A-I and A-II):
//!
//! - the saturation vapour pressure over water, at t ≥ 0 °C, is the saturation
//!   equation of IAPWS-IF97 (region 4, with the coefficients n₁…n₁₀ rounded to
//!   12 digits as NIST prints them): Ω = T + K₉/(T − K₁₀), A = Ω² + K₁Ω + K₂,
//!   B = K₃Ω² + K₄Ω + K₅, C = K₆Ω² + K₇Ω + K₈, X = −B + √(B² − 4AC),
//!   p_sv = 10⁶ (2C/X)⁴ Pa;
//! - over ice, below 0 °C, the sublimation equation of Wagner, Saul and Pruss
//!   (1994): Θ = T/273.16, Y = A₁(1 − Θ^−1.5) + A₂(1 − Θ^−1.25),
//!   p_sv = 611.657 e^Y Pa;
//! - the enhancement factor f = 1.00062 + 3.14·10⁻⁸ p + 5.6·10⁻⁷ t² (p in Pa, t in
//!   °C) and the mole fraction x_v = RH · f · p_sv / p.
//!
//! Accuracy: the water branch reproduces the IF97 verification values (its
//! table 35) to 1e-9 relative with NIST's rounded coefficients; the formulas are
//! those of the calculator, so its results are reproduced to rounding. The two
//! branches differ by 0.06 Pa at 0 °C (saturation over supercooled water is not
//! saturation over ice), so p_sv has a small step there, as in NIST's calculator.
//!
//! Relative humidity is a fraction in [0, 1] here (NIST's page takes per cent).
//! The branch is chosen on the real part of the temperature only, so dual
//! numbers carry the derivative of the branch taken.

use crate::math::Real;

/// 0 °C in kelvin.
const ZERO_CELSIUS: f64 = 273.15;

/// IAPWS-IF97 saturation-line coefficients n₁…n₁₀, as NIST's appendix A-I
/// prints them (K₁…K₁₀).
const K: [f64; 10] = [
    1.16705214528e3,
    -7.24213167032e5,
    -1.70738469401e1,
    1.20208247025e4,
    -3.23255503223e6,
    1.49151086135e1,
    -4.82326573616e3,
    4.05113405421e5,
    -2.38555575678e-1,
    6.50175348448e2,
];

/// Sublimation-curve coefficients A₁, A₂ (Wagner, Saul and Pruss), NIST A-I.
const ICE_A1: f64 = -13.928169;
/// See [`ICE_A1`].
const ICE_A2: f64 = 34.7078238;
/// The triple point of water: temperature (K) and pressure (Pa).
const TRIPLE_POINT: (f64, f64) = (273.16, 611.657);

/// Saturation vapour pressure (Pa) at `celsius`: over water at ≥ 0 °C
/// (IAPWS-IF97), over ice below 0 °C, as NIST's appendix A-I.
pub fn saturation_vapour_pressure<U: Real>(celsius: U) -> U {
    let kelvin = celsius + ZERO_CELSIUS;
    if celsius.val() >= 0.0 {
        over_water(kelvin)
    } else {
        over_ice(kelvin)
    }
}

/// IF97 saturation pressure (Pa) at `t` kelvin.
fn over_water<U: Real>(t: U) -> U {
    let omega = t + (t - K[9]).recip() * K[8];
    let a = omega * omega + omega * K[0] + K[1];
    let b = omega * omega * K[2] + omega * K[3] + K[4];
    let c = omega * omega * K[5] + omega * K[6] + K[7];
    let x = -b + (b * b - a * c * 4.0).sqrt();
    (c * 2.0 / x).powi(4) * 1e6
}

/// Sublimation pressure (Pa) at `t` kelvin.
fn over_ice<U: Real>(t: U) -> U {
    let theta = t / TRIPLE_POINT.0;
    let y = (-theta.powf(-1.5) + 1.0) * ICE_A1 + (-theta.powf(-1.25) + 1.0) * ICE_A2;
    y.exp() * TRIPLE_POINT.1
}

/// The enhancement factor f = 1.00062 + 3.14·10⁻⁸ p + 5.6·10⁻⁷ t² (NIST A-II):
/// how much more vapour moist air holds than pure vapour would, at `celsius` and
/// `pressure` (Pa).
pub fn enhancement_factor<U: Real>(celsius: U, pressure: U) -> U {
    pressure * 3.14e-8 + celsius * celsius * 5.6e-7 + 1.00062
}

/// Water-vapour mole fraction x_v = RH · f · p_sv / p (NIST A-II), at `celsius`,
/// `pressure` (Pa, > 0) and relative `humidity` in [0, 1]: what Ciddor's equation
/// takes.
pub fn vapour_mole_fraction<U: Real>(celsius: U, pressure: U, humidity: U) -> U {
    humidity * enhancement_factor(celsius, pressure) * saturation_vapour_pressure(celsius)
        / pressure
}

/// Water-vapour partial pressure p_v = RH · p_sv (Pa), at `celsius` and relative
/// `humidity` in [0, 1]: what NIST's form of Edlén's equation takes.
pub fn vapour_pressure<U: Real>(celsius: U, humidity: U) -> U {
    humidity * saturation_vapour_pressure(celsius)
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual64;

    fn relative(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn water_branch_reproduces_the_if97_verification_values() {
        // IAPWS-IF97 (2007 revision), table 35: p_s(300 K) = 0.353658941e-2 MPa,
        // p_s(500 K) = 0.263889776e1 MPa, p_s(600 K) = 0.123443146e2 MPa (9
        // significant digits; NIST's coefficients are rounded to 12).
        for (kelvin, mpa) in [
            (300.0, 0.353658941e-2),
            (500.0, 0.263889776e1),
            (600.0, 0.123443146e2),
        ] {
            let p = saturation_vapour_pressure(kelvin - ZERO_CELSIUS);
            assert!(relative(p, mpa * 1e6) < 2e-9, "{kelvin} K: {p} Pa");
        }
        // The normal boiling point: 101.418 kPa at 100 °C (IF97's saturation
        // pressure at 373.15 K; 1 atm is 101.325 kPa at 99.97 °C, ITS-90).
        assert!((saturation_vapour_pressure(100.0) - 101_418.0).abs() < 1.0);
    }

    #[test]
    fn ice_branch_meets_the_triple_point_and_the_tables() {
        // The sublimation equation is anchored at the triple point: 611.657 Pa at
        // 273.16 K, i.e. 0.01 °C; just below 0 °C it is ice's 611.15 Pa.
        assert!((over_ice(TRIPLE_POINT.0) - TRIPLE_POINT.1).abs() < 1e-9);
        assert!((saturation_vapour_pressure(-1e-9) - 611.15).abs() < 0.01);
        // Vapour pressure of ice, as tabulated (CRC Handbook, "Vapor pressure of
        // ice", from the same sublimation equation): 259.9 Pa at −10 °C, 103.3 Pa
        // at −20 °C, 12.84 Pa at −40 °C.
        for (t, table, digits) in [
            (-10.0, 259.9, 0.05),
            (-20.0, 103.3, 0.05),
            (-40.0, 12.84, 0.005),
        ] {
            let p = saturation_vapour_pressure(t);
            assert!((p - table).abs() < digits, "{t} °C: {p} Pa");
        }
        // Over water at 0 °C: 611.21 Pa (IF97; CRC 0.61121 kPa).
        assert!((saturation_vapour_pressure(0.0) - 611.213).abs() < 0.01);
        // Far below, still finite and positive (the accepted range goes to −150 °C).
        let cold = saturation_vapour_pressure(-150.0);
        assert!(cold.is_finite() && cold > 0.0 && cold < 1e-3, "{cold}");
    }

    #[test]
    fn mole_fraction_and_partial_pressure_follow_nist_a_ii() {
        // 20 °C, 101325 Pa, 50 %: f = 1.00062 + 3.14e-8·101325 + 5.6e-7·400.
        let f = enhancement_factor(20.0, 101_325.0);
        assert!((f - (1.00062 + 3.14e-8 * 101_325.0 + 5.6e-7 * 400.0)).abs() < 1e-15);
        let psv = saturation_vapour_pressure(20.0);
        // p_sv(20 °C) = 2339.2 Pa (IF97; CRC 2.3393 kPa).
        assert!((psv - 2339.21).abs() < 0.01, "{psv}");
        assert_eq!(vapour_pressure(20.0, 0.5), 0.5 * psv);
        let xv = vapour_mole_fraction(20.0, 101_325.0, 0.5);
        assert!(relative(xv, 0.5 * f * psv / 101_325.0) < 1e-15);
        assert_eq!(vapour_mole_fraction(-30.0, 80_000.0, 0.0), 0.0);
    }

    #[test]
    fn derivatives_of_both_branches_match_differences() {
        for t in [-60.0, -20.0, -0.5, 0.5, 15.0, 40.0, 95.0] {
            let d = saturation_vapour_pressure(Dual64::new(t, 1.0)).eps;
            let h = 1e-4;
            let fd =
                (saturation_vapour_pressure(t + h) - saturation_vapour_pressure(t - h)) / (2.0 * h);
            assert!(relative(d, fd) < 1e-7, "{t} °C: {d} vs {fd}");
        }
    }
}
