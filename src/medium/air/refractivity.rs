//! The refractivity n − 1 of air from its state: temperature, pressure, humidity,
//! vacuum wavelength and CO₂, by one of three published formulas ([`Formula`]).
//!
//! - **Ciddor** (P. E. Ciddor, "Refractive index of air: new equations for the
//!   visible and near infrared", Applied Optics 35:1566, 1996), in the procedure of
//!   NIST's calculator documentation (J. A. Stone and J. H. Zimmerman, *Index of
//!   Refraction of Air*, NIST Engineering Metrology Toolbox, appendix A-III). With
//!   S = 1/λ² (λ in µm):
//!   - the refractivities of standard dry air (15 °C, 101 325 Pa, 450 ppm CO₂) and
//!     of standard water vapour (20 °C, 1333 Pa), r_as = 10⁻⁸ (k₁/(k₀ − S) +
//!     k₃/(k₂ − S)) and r_vs = 1.022·10⁻⁸ (w₀ + w₁S + w₂S² + w₃S³);
//!   - CO₂: r_axs = r_as (1 + 5.34·10⁻⁷ (x_c − 450)), molar mass of dry air
//!     M_a = 0.0289635 + 1.2011·10⁻⁸ (x_c − 400) kg/mol;
//!   - the compressibility Z_m of the moist air (BIPM 1981/91 form) and the
//!     densities ρ_a, ρ_v of its dry and vapour parts (ideal gas over Z_m), the
//!     mole fraction x_v from [`vapour_mole_fraction`];
//!   - n − 1 = (ρ_a/ρ_axs) r_axs + (ρ_v/ρ_vs) r_vs.
//! - **Edlén** as updated by Birch and Downs (Metrologia 30:155, 1993; 31:315,
//!   1994), in NIST's form (appendix A-IV), which replaces the vapour term's
//!   constant by 292.75/T to hold away from 20 °C:
//!   (n_s − 1) = 10⁻⁸ (A + B/(130 − S) + C/(38.9 − S)),
//!   X = (1 + 10⁻⁸ (E − F t) p)/(1 + G t),
//!   n − 1 = p (n_s − 1) X / D − 10⁻¹⁰ (292.75/T)(3.7345 − 0.0401 S) p_v,
//!   p_v from [`vapour_pressure`]. Its standard air holds **450 ppm CO₂**, fixed:
//!   the state's `co2_ppm` is not used (NIST's Edlén page has no CO₂ input; a
//!   change of 150 ppm would move n by about 2·10⁻⁸).
//! - **Gladstone–Dale** `GladstoneDale(K)`: n − 1 = K (P / 101 325 Pa) / T, T in
//!   kelvin, K in kelvin (the simple law of many mirage papers). No humidity,
//!   wavelength or CO₂.
//!
//! Beyond NIST: where a relative humidity asks for more vapour than the air can
//! hold (x_v > 1, p_v > p: warm air at a few pascals), the vapour is held at the
//! whole of the air, so that Z_m stays positive (min 0.02, at −150 °C and 28 MPa)
//! and every accepted state gives a finite n − 1. Real states never reach it.
//!
//! Accuracy: the Ciddor and Edlén functions reproduce a separate implementation
//! of the same NIST procedure to 1e-15 in n − 1 (the tests); the formulas
//! themselves agree with measurements to a few parts in 10⁸ inside their stated
//! ranges ([`validity`]), and extrapolate smoothly outside them: finite for
//! temperatures from −150 °C to 100 °C, every pressure > 0, humidity in [0, 1]
//! and wavelengths of 300 … 1700 nm.
//!
//! Everything is generic over [`Real`], branching only on real parts (the
//! water/ice choice of the saturation pressure), so dual numbers carry exact
//! derivatives; [`refractivity_partials`] gets ∂/∂T and ∂/∂P with a nested dual.

use super::humidity::{vapour_mole_fraction, vapour_pressure};
use crate::math::Real;
use num_dual::Dual;

/// The CO₂ content of air when none is given (ppm by mole), as NIST's calculator.
pub const DEFAULT_CO2_PPM: f64 = 450.0;

/// The reference pressure of the Gladstone–Dale law and of standard air (Pa).
pub const STANDARD_PRESSURE: f64 = 101_325.0;

/// 0 °C in kelvin.
const ZERO_CELSIUS: f64 = 273.15;

/// Which published formula turns the state of the air into n − 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Formula<T = f64> {
    /// Ciddor 1996 (the default of docs/air.md), with CO₂.
    Ciddor,
    /// Edlén as modified by Birch and Downs, in NIST's form; CO₂ fixed at 450 ppm.
    Edlen,
    /// n − 1 = K · (P / 101 325 Pa) / T_kelvin, with this K (kelvin).
    GladstoneDale(T),
}

impl<T> Formula<T> {
    /// The same formula with its constant mapped (e.g. lifted to a dual number).
    pub fn map<V>(self, f: impl FnOnce(T) -> V) -> Formula<V> {
        match self {
            Formula::Ciddor => Formula::Ciddor,
            Formula::Edlen => Formula::Edlen,
            Formula::GladstoneDale(k) => Formula::GladstoneDale(f(k)),
        }
    }
}

/// The state of the air at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AirState<U = f64> {
    /// Temperature, °C.
    pub celsius: U,
    /// Pressure, Pa (> 0).
    pub pressure: U,
    /// Relative humidity, a fraction in [0, 1].
    pub humidity: U,
    /// Wavelength of the light in vacuum, nm.
    pub wavelength_nm: U,
    /// Carbon dioxide, ppm by mole (used by Ciddor only).
    pub co2_ppm: U,
}

impl<U> AirState<U> {
    /// The same state with every number mapped (e.g. lifted to dual numbers).
    pub fn map<V>(self, mut f: impl FnMut(U) -> V) -> AirState<V> {
        AirState {
            celsius: f(self.celsius),
            pressure: f(self.pressure),
            humidity: f(self.humidity),
            wavelength_nm: f(self.wavelength_nm),
            co2_ppm: f(self.co2_ppm),
        }
    }
}

/// The ranges a formula is stated to be valid over, for messages (NIST's
/// calculator documentation, section VI; both equations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Validity {
    /// (min, max) temperature, °C.
    pub celsius: (f64, f64),
    /// (min, max) pressure, Pa.
    pub pressure: (f64, f64),
    /// (min, max) vacuum wavelength, nm.
    pub wavelength_nm: (f64, f64),
}

/// The stated validity ranges of a formula, for messages: (min, max) of celsius,
/// pressure, wavelength. `None` for Gladstone–Dale, which states none.
pub fn validity<T>(formula: &Formula<T>) -> Option<Validity> {
    match formula {
        // NIST: −40 … 100 °C, 10 … 140 kPa, 300 … 1700 nm for both equations (the
        // calculator warns outside 0 … 40 °C, 60 … 120 kPa, 350 … 1600 nm).
        Formula::Ciddor | Formula::Edlen => Some(Validity {
            celsius: (-40.0, 100.0),
            pressure: (10e3, 140e3),
            wavelength_nm: (300.0, 1700.0),
        }),
        Formula::GladstoneDale(_) => None,
    }
}

/// n − 1 of `air` by `formula`.
pub fn refractivity<U: Real>(formula: Formula<U>, air: &AirState<U>) -> U {
    match formula {
        Formula::Ciddor => ciddor(air),
        Formula::Edlen => edlen(air),
        Formula::GladstoneDale(k) => {
            k * (air.pressure / STANDARD_PRESSURE) / (air.celsius + ZERO_CELSIUS)
        }
    }
}

/// n − 1 and its partial derivatives by temperature (per kelvin) and pressure
/// (per Pa), the other inputs fixed (computed exactly, e.g. with a nested
/// num_dual Dual, or analytically).
///
/// Exact to rounding: each derivative is the dual part of one evaluation in
/// `Dual<U, f64>`, so `U` may itself be a dual number (the fitter's parameters).
pub fn refractivity_partials<U: Real>(formula: Formula<U>, air: &AirState<U>) -> (U, U, U) {
    let formula = formula.map(Dual::from_re);
    let lifted = air.map(Dual::from_re);
    let by_t = refractivity(
        formula,
        &AirState {
            celsius: Dual::new(air.celsius, U::one()),
            ..lifted
        },
    );
    let by_p = refractivity(
        formula,
        &AirState {
            pressure: Dual::new(air.pressure, U::one()),
            ..lifted
        },
    );
    (by_t.re, by_t.eps, by_p.eps)
}

/// ∂(n − 1)/∂RH of `air` by `formula` (per unit of relative humidity, the
/// other inputs fixed), exact to rounding as [`refractivity_partials`]: for a
/// humidity that changes with height. 0 for Gladstone–Dale, which has no
/// humidity.
pub fn humidity_partial<U: Real>(formula: Formula<U>, air: &AirState<U>) -> U {
    if let Formula::GladstoneDale(_) = formula {
        return U::cst(0.0);
    }
    let by_rh = refractivity(
        formula.map(Dual::from_re),
        &AirState {
            humidity: Dual::new(air.humidity, U::one()),
            ..air.map(Dual::from_re)
        },
    );
    by_rh.eps
}

/// S = 1/λ² in µm⁻², λ given in nm.
fn wavenumber_squared<U: Real>(wavelength_nm: U) -> U {
    (wavelength_nm * 1e-3).powi(2).recip()
}

/// Ciddor's constants, as NIST's appendix A-III prints them (Ciddor 1996,
/// appendix A); checked against a second transcription (M. Hervig's
/// `index_air.pro`, from the same NIST page).
mod ciddor_constants {
    /// Water-vapour dispersion w₀…w₃ (µm⁻²ⁿ).
    pub const W: [f64; 4] = [295.235, 2.6422, -0.032380, 0.004028];
    /// Dry-air dispersion k₀…k₃ (µm⁻²).
    pub const K: [f64; 4] = [238.0185, 5_792_105.0, 57.362, 167_917.0];
    /// Compressibility a₀ (K/Pa), a₁ (1/Pa), a₂ (1/(K·Pa)).
    pub const A: [f64; 3] = [1.58123e-6, -2.9331e-8, 1.1043e-10];
    /// Compressibility b₀ (K/Pa), b₁ (1/Pa).
    pub const B: [f64; 2] = [5.707e-6, -2.051e-8];
    /// Compressibility c₀ (K/Pa), c₁ (1/Pa).
    pub const C: [f64; 2] = [1.9898e-4, -2.376e-6];
    /// Compressibility d (K²/Pa²).
    pub const D: f64 = 1.83e-11;
    /// Compressibility e (K²/Pa²).
    pub const E: f64 = -0.765e-8;
    /// Standard dry air: pressure (Pa) and temperature (K).
    pub const P_R1: f64 = 101_325.0;
    /// See [`P_R1`].
    pub const T_R1: f64 = 288.15;
    /// Compressibility of standard dry air.
    pub const Z_A: f64 = 0.9995922115;
    /// Density of standard water vapour (20 °C, 1333 Pa), kg/m³.
    pub const RHO_VS: f64 = 0.00985938;
    /// The gas constant as Ciddor's procedure has it (J/(mol·K)).
    pub const R: f64 = 8.314472;
    /// Molar mass of water, kg/mol.
    pub const M_V: f64 = 0.018015;
}

/// Ciddor 1996, NIST A-III.
fn ciddor<U: Real>(air: &AirState<U>) -> U {
    use ciddor_constants::*;
    let t = air.celsius;
    let p = air.pressure;
    let kelvin = t + ZERO_CELSIUS;
    let xv = vapour_mole_fraction(t, p, air.humidity);
    // At most the whole of the air (see the module docs).
    let xv = if xv.val() > 1.0 { U::one() } else { xv };
    let s = wavenumber_squared(air.wavelength_nm);

    let r_as = ((-s + K[0]).recip() * K[1] + (-s + K[2]).recip() * K[3]) * 1e-8;
    let r_vs = (s * W[1] + s * s * W[2] + s * s * s * W[3] + W[0]) * 1.022e-8;
    let co2 = air.co2_ppm;
    let m_a = (co2 - 400.0) * 1.2011e-8 + 0.0289635;
    let r_axs = r_as * ((co2 - 450.0) * 5.34e-7 + 1.0);

    let pt = p / kelvin;
    let z_m = -pt
        * (t * A[1] + t * t * A[2] + A[0] + (t * B[1] + B[0]) * xv + (t * C[1] + C[0]) * xv * xv)
        + pt * pt * (xv * xv * E + D)
        + 1.0;

    let rho_axs = m_a * (P_R1 / (Z_A * R * T_R1));
    let per_volume = p / (z_m * kelvin * R);
    let rho_v = xv * per_volume * M_V;
    let rho_a = (-xv + 1.0) * per_volume * m_a;
    rho_a / rho_axs * r_axs + rho_v / RHO_VS * r_vs
}

/// Edlén as modified by Birch and Downs, NIST A-IV.
fn edlen<U: Real>(air: &AirState<U>) -> U {
    const A: f64 = 8342.54;
    const B: f64 = 2_406_147.0;
    const C: f64 = 15_998.0;
    const D: f64 = 96_095.43;
    const E: f64 = 0.601;
    const F: f64 = 0.00972;
    const G: f64 = 0.003661;
    let t = air.celsius;
    let p = air.pressure;
    let s = wavenumber_squared(air.wavelength_nm);
    let n_s = ((-s + 130.0).recip() * B + (-s + 38.9).recip() * C + A) * 1e-8;
    let x = ((-t * F + E) * p * 1e-8 + 1.0) / (t * G + 1.0);
    let dry = p * n_s * x / D;
    let pv = vapour_pressure(t, air.humidity);
    // At most the whole of the air (see the module docs).
    let pv = if pv.val() > p.val() { p } else { pv };
    let wet = (t + ZERO_CELSIUS).recip() * 292.75 * (-s * 0.0401 + 3.7345) * pv * 1e-10;
    dry - wet
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual64;

    fn air(celsius: f64, pressure: f64, humidity: f64, wavelength_nm: f64) -> AirState {
        AirState {
            celsius,
            pressure,
            humidity,
            wavelength_nm,
            co2_ppm: DEFAULT_CO2_PPM,
        }
    }

    fn relative(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    /// Published n of the NIST procedure, each within `tol` in n − 1.
    fn check(formula: Formula, a: AirState, n: f64, tol: f64) {
        let got = refractivity(formula, &a);
        assert!(
            (got - (n - 1.0)).abs() < tol,
            "{formula:?} {a:?}: n − 1 = {got:e}, published {:e}",
            n - 1.0
        );
    }

    #[test]
    fn nist_procedure_reproduces_published_values() {
        // The example of NIST's documentation (633 nm, 20 °C, 101.325 kPa, 20 %
        // RH, 450 ppm), and the other cases, as computed to 17 digits by
        // P. Nair's `ref_index` (github.com/phn/ref_index, README), a separate
        // implementation of NIST's appendix A.
        let cases = [
            (
                Formula::Ciddor,
                air(20.0, 101_325.0, 0.2, 633.0),
                1.0002716285340578,
            ),
            (
                Formula::Edlen,
                air(20.0, 101_325.0, 0.2, 633.0),
                1.000271629169165,
            ),
            (
                Formula::Edlen,
                air(20.0, 101_325.0, 0.8, 633.0),
                1.0002711197635226,
            ),
            (
                Formula::Ciddor,
                air(20.0, 101_325.0, 0.8, 633.0),
                1.0002711183472626,
            ),
            (
                Formula::Edlen,
                air(60.0, 101_325.0, 0.8, 633.0),
                1.0002339748542823,
            ),
            (
                Formula::Ciddor,
                air(60.0, 101_325.0, 0.8, 633.0),
                1.0002340241754055,
            ),
        ];
        for (formula, a, n) in cases {
            check(formula, a, n, 1e-12);
        }
        // The same package's vac2air (Ciddor): λ_air = λ_vac / n, printed as
        // 632.82500476826874 nm (15 °C, 101325 Pa, dry) and 632.83051710791892
        // nm (20 °C, 100 kPa, 50 %) for 633 nm; 549.84723175 and 399.88692724 nm
        // for 550 and 400 nm (8 decimals: 2e-11 in n).
        check(
            Formula::Ciddor,
            air(15.0, 101_325.0, 0.0, 633.0),
            633.0 / 632.825_004_768_268_7,
            1e-12,
        );
        check(
            Formula::Ciddor,
            air(20.0, 100_000.0, 0.5, 633.0),
            633.0 / 632.830_517_107_918_9,
            1e-12,
        );
        check(
            Formula::Ciddor,
            air(15.0, 101_325.0, 0.0, 550.0),
            550.0 / 549.847_231_75,
            3e-11,
        );
        check(
            Formula::Ciddor,
            air(15.0, 101_325.0, 0.0, 400.0),
            400.0 / 399.886_927_24,
            3e-11,
        );
    }

    #[test]
    fn ciddor_standard_dry_air_is_his_dispersion_formula() {
        // Ciddor 1996, eq. (1): standard air (dry, 15 °C, 101 325 Pa, 450 ppm)
        // has n − 1 = 0.05792105/(238.0185 − σ²) + 0.00167917/(57.362 − σ²), σ in
        // µm⁻¹ (also refractiveindex.info's "Ciddor 1996" entry). The full
        // procedure gives it times Z_a/Z_m, and Z_m there is Z_a to 1e-10.
        for nm in [300.0, 400.0, 550.0, 633.0, 1064.0, 1550.0, 1700.0] {
            let s: f64 = (1e3 / nm) * (1e3 / nm);
            let standard = 0.05792105 / (238.0185 - s) + 0.00167917 / (57.362 - s);
            let n1 = refractivity(Formula::Ciddor, &air(15.0, 101_325.0, 0.0, nm));
            assert!(relative(n1, standard) < 1e-9, "{nm} nm: {n1:e}");
            // At 633 nm: (n − 1)·10⁸ = 27 653.02 (ref_index's vac2air above).
            if nm == 633.0 {
                assert!((n1 * 1e8 - 27_653.02).abs() < 0.01);
            }
        }
    }

    #[test]
    fn gladstone_dale_is_exact() {
        let k = 0.079386;
        let n1 = refractivity(
            Formula::GladstoneDale(k),
            &air(10.0, STANDARD_PRESSURE, 0.7, 633.0),
        );
        assert_eq!(n1, 0.079386 / 283.15);
        let (v, dt, dp) = refractivity_partials(
            Formula::GladstoneDale(k),
            &air(10.0, 2.0 * STANDARD_PRESSURE, 0.0, 550.0),
        );
        assert!(relative(v, 2.0 * k / 283.15) < 1e-15);
        assert!(relative(dt, -2.0 * k / (283.15 * 283.15)) < 1e-15);
        assert!(relative(dp, k / STANDARD_PRESSURE / 283.15) < 1e-15);
        assert_eq!(validity(&Formula::GladstoneDale(k)), None);
    }

    #[test]
    fn co2_moves_ciddor_only() {
        let mut a = air(20.0, 101_325.0, 0.3, 633.0);
        let at_450 = (
            refractivity(Formula::Ciddor, &a),
            refractivity(Formula::Edlen, &a),
        );
        a.co2_ppm = 600.0;
        // NIST: 150 ppm more CO₂ raises n by about 2·10⁻⁸ (5.34e-7·150·2.7e-4).
        let step = refractivity(Formula::Ciddor, &a) - at_450.0;
        assert!((step - 2.16e-8).abs() < 0.05e-8, "{step:e}");
        assert_eq!(refractivity(Formula::Edlen, &a), at_450.1);
    }

    #[test]
    fn partials_match_central_differences() {
        let formulas = [
            Formula::Ciddor,
            Formula::Edlen,
            Formula::GladstoneDale(0.08),
        ];
        for formula in formulas {
            for t in [-120.0, -30.0, -5.0, 5.0, 20.0, 45.0, 95.0] {
                for p in [20e3, 70e3, 101_325.0, 130e3] {
                    for rh in [0.0, 0.5, 1.0] {
                        for nm in [300.0, 633.0, 1700.0] {
                            let a = air(t, p, rh, nm);
                            let (v, dt, dp) = refractivity_partials(formula, &a);
                            assert!(relative(v, refractivity(formula, &a)) < 1e-14);
                            let at = |t, p| {
                                refractivity(
                                    formula,
                                    &AirState {
                                        celsius: t,
                                        pressure: p,
                                        ..a
                                    },
                                )
                            };
                            let (ht, hp) = (1e-3, 1e-5 * p);
                            let fdt = (at(t + ht, p) - at(t - ht, p)) / (2.0 * ht);
                            let fdp = (at(t, p + hp) - at(t, p - hp)) / (2.0 * hp);
                            assert!(
                                relative(dt, fdt) < 1e-6,
                                "{formula:?} {a:?}: ∂T {dt:e} vs {fdt:e}"
                            );
                            assert!(
                                relative(dp, fdp) < 1e-6,
                                "{formula:?} {a:?}: ∂P {dp:e} vs {fdp:e}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn dual_numbers_pass_through() {
        let a = air(12.0, 95_000.0, 0.6, 550.0);
        for formula in [Formula::Ciddor, Formula::Edlen] {
            let (_, dt, dp) = refractivity_partials(formula, &a);
            let by_t = AirState {
                celsius: Dual64::new(a.celsius, 1.0),
                ..a.map(Dual64::from_re)
            };
            let d = refractivity(formula.map(Dual64::from_re), &by_t);
            assert!(
                relative(d.eps, dt) < 1e-13,
                "{formula:?}: {} vs {dt}",
                d.eps
            );
            // Partials of duals: d(∂n/∂P)/dT by a dual in T, against differences.
            let (_, _, dp_dual) = refractivity_partials(formula.map(Dual64::from_re), &by_t);
            assert!(relative(dp_dual.re, dp) < 1e-15);
            let h = 1e-3;
            let dp_at = |t| refractivity_partials(formula, &AirState { celsius: t, ..a }).2;
            let fd = (dp_at(12.0 + h) - dp_at(12.0 - h)) / (2.0 * h);
            assert!(
                relative(dp_dual.eps, fd) < 1e-6,
                "{formula:?}: {} vs {fd}",
                dp_dual.eps
            );
        }
    }

    #[test]
    fn finite_over_every_accepted_input() {
        for formula in [Formula::Ciddor, Formula::Edlen] {
            for t in [-150.0, -40.0, 0.0, 100.0] {
                for p in [1.0, 1e3, 1e5, 2e5] {
                    for rh in [0.0, 1.0] {
                        for nm in [300.0, 1700.0] {
                            for co2 in [0.0, 2000.0] {
                                let a = AirState {
                                    co2_ppm: co2,
                                    ..air(t, p, rh, nm)
                                };
                                let (v, dt, dp) = refractivity_partials(formula, &a);
                                assert!(
                                    v.is_finite() && dt.is_finite() && dp.is_finite(),
                                    "{formula:?} {a:?}"
                                );
                            }
                        }
                    }
                }
            }
        }
        let v = validity(&Formula::<f64>::Ciddor).unwrap();
        assert_eq!(v.wavelength_nm, (300.0, 1700.0));
        assert_eq!(validity(&Formula::<f64>::Edlen), Some(v));
    }
}
