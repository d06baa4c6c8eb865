//! The U.S. Standard Atmosphere 1976 (NOAA-S/T 76-1562, U.S. Government Printing
//! Office, Washington D.C., 1976), below 86 km geometric: its temperature as an offset
//! from the sea-level 288.15 K (for the `"lapse": "standard"` profile of
//! `docs/air.md`), and its own pressure (for tests and comparison).
//!
//! The standard defines a *molecular-scale* temperature T_M, piecewise linear in the
//! geopotential height H = r0·h/(r0 + h) (r0 = 6 356 766 m, h geometric), with the
//! base heights and lapse rates of its Table 4:
//!
//! | H (km)   | 0     | 11 | 20 | 32  | 47 | 51   | 71   | 84.852 |
//! |----------|-------|----|----|-----|----|------|------|--------|
//! | L (K/km) | −6.5  | 0  | +1 | +2.8| 0  | −2.8 | −2.0 | (top)  |
//!
//! The kinetic temperature is T = T_M · (M/M0), where the molecular-weight ratio
//! M/M0 is 1 below 80 km geometric and, from 80 to 86 km, the standard's Table 8
//! (tabulated every 0.5 km, linearly interpolated here). That ratio is what makes
//! T(86 km) = 186.87 K (T_M = 186.946 K). H is taken in geometric metres (the lapse
//! rates are per geopotential metre), so the slope per geometric metre is
//! dT/dh = L · (M/M0) · (r0/(r0+h))² + T_M · d(M/M0)/dh.
//!
//! Invariants: T is continuous everywhere; dT/dh is piecewise continuous with jumps at
//! the layer boundaries ([`US1976_BREAKS`], which a quadrature must take as nodes).
//! Below the ground (h < 0) the first layer continues linearly in h with its
//! sea-level slope −6.5 K/km (the geopotential formula would be singular at h = −r0);
//! above 86 km ([`US1976_TOP`]) T is held at its 86 km value. Exact (to rounding) with
//! respect to the standard's defining formulas.

use crate::math::Real;

/// The top of the profile, in geometric metres (84.852 km geopotential).
pub const US1976_TOP: f64 = 86_000.0;

/// The effective earth radius r0 of the geopotential height, in metres.
pub const US1976_R0: f64 = 6_356_766.0;

/// Sea-level temperature, in kelvin.
pub const US1976_T0: f64 = 288.15;

/// The universal gas constant of the standard, R* = 8.31432 J/(mol·K) (not the
/// CODATA value: its pressures are defined with this one).
const R_STAR: f64 = 8.31432;
/// Sea-level mean molar mass M0, kg/mol.
const M0: f64 = 0.028_964_4;
/// Standard gravity g0, m/s².
const G0: f64 = 9.806_65;

/// Base geopotential heights (m) of the layers, and the top of the last one.
const LAYER_BASE: [f64; 8] = [
    0.0, 11_000.0, 20_000.0, 32_000.0, 47_000.0, 51_000.0, 71_000.0, 84_852.0,
];
/// Lapse rates dT_M/dH (K per geopotential metre) of the seven layers.
const LAPSE: [f64; 7] = [-6.5e-3, 0.0, 1.0e-3, 2.8e-3, 0.0, -2.8e-3, -2.0e-3];

/// The molecular-weight ratio M/M0 of Table 8, geometric 80 … 86 km every 0.5 km.
const MW_RATIO: [f64; 13] = [
    1.0, 0.999996, 0.999989, 0.999971, 0.999941, 0.999909, 0.999870, 0.999829, 0.999786, 0.999741,
    0.999694, 0.999641, 0.999579,
];
/// Geometric height (m) where [`MW_RATIO`] starts, and its spacing.
const MW_START: f64 = 80_000.0;
const MW_STEP: f64 = 500.0;

/// The geometric heights (m) where dT/dh jumps: the layer bases above the ground, the
/// top, and the nodes of the molecular-weight table (80 … 86 km). A table of the
/// integral of 1/T must have nodes there to stay accurate.
pub const US1976_BREAKS: [f64; 19] = [
    // Layer bases at H = 11, 20, 32, 47, 51, 71 km, as geometric heights r0·H/(r0 − H).
    11_019.067_832_000_108,
    20_063.123_681_701_36,
    32_161.903_222_980_898,
    47_350.092_222_120_44,
    51_412.479_625_790_11,
    71_801.970_674_695_81,
    80_000.0,
    80_500.0,
    81_000.0,
    81_500.0,
    82_000.0,
    82_500.0,
    83_000.0,
    83_500.0,
    84_000.0,
    84_500.0,
    85_000.0,
    85_500.0,
    US1976_TOP,
];

/// The geopotential height H (m) of the geometric height `h` (m), for h > −r0.
fn geopotential(h: f64) -> f64 {
    US1976_R0 * h / (US1976_R0 + h)
}

/// The base molecular-scale temperatures of the layers (K), from the lapse rates.
fn base_temperatures() -> [f64; 8] {
    let mut t = [US1976_T0; 8];
    for i in 0..7 {
        t[i + 1] = t[i] + LAPSE[i] * (LAYER_BASE[i + 1] - LAYER_BASE[i]);
    }
    t
}

/// The layer index (0 … 6) holding geopotential height `big_h` (m), for
/// 0 ≤ big_h ≤ 84 852 m; a boundary belongs to the layer above it.
fn layer(big_h: f64) -> usize {
    LAYER_BASE[1..7].iter().take_while(|&&b| big_h >= b).count()
}

/// (T − 288.15 K, dT/dh per geometric metre) of the US Standard Atmosphere 1976 at
/// geometric height `h` (m); see the module documentation for the extensions below 0
/// and above 86 km.
pub fn us1976_offset<U: Real>(h: U) -> (U, U) {
    let hv = h.val();
    if hv < 0.0 {
        // Linear continuation: dH/dh = 1 at h = 0, so the slope is continuous.
        return (h * LAPSE[0], U::cst(LAPSE[0]));
    }
    if hv >= US1976_TOP {
        return (layered(U::cst(US1976_TOP)).0, U::cst(0.0));
    }
    layered(h)
}

/// [`us1976_offset`] for 0 ≤ h ≤ 86 km: the layers of T_M times M/M0.
fn layered<U: Real>(h: U) -> (U, U) {
    let tb = base_temperatures();
    let r = h + US1976_R0;
    let big_h = h * US1976_R0 / r;
    let i = layer(big_h.val());
    let tm = (big_h - LAYER_BASE[i]) * LAPSE[i] + tb[i];
    // dH/dh = (r0 / (r0 + h))².
    let dh_ratio = (r.recip() * US1976_R0).powi(2);
    let dtm = dh_ratio * LAPSE[i];
    let (ratio, dratio) = molecular_weight_ratio(h);
    let t = tm * ratio;
    (t - US1976_T0, dtm * ratio + tm * dratio)
}

/// M/M0 and its derivative per geometric metre, 0 ≤ h < 86 km.
fn molecular_weight_ratio<U: Real>(h: U) -> (U, U) {
    let hv = h.val();
    if hv < MW_START {
        return (U::cst(1.0), U::cst(0.0));
    }
    let j = (((hv - MW_START) / MW_STEP) as usize).min(MW_RATIO.len() - 2);
    let slope = (MW_RATIO[j + 1] - MW_RATIO[j]) / MW_STEP;
    let base = MW_START + MW_STEP * j as f64;
    ((h - base) * slope + MW_RATIO[j], U::cst(slope))
}

/// The standard's pressure (Pa) at geometric height `h` (m): its hydrostatic law over
/// T_M in geopotential height with its own constants (R* = 8.31432), 101 325 Pa at
/// sea level. Below 0 the first layer continues; above 86 km the isothermal law at
/// T_M(86 km) continues. For tests and comparison.
pub fn us1976_pressure(h: f64) -> f64 {
    let gmr = G0 * M0 / R_STAR;
    let tb = base_temperatures();
    // Geopotential height, clamped to the top (above it, the isothermal tail).
    let big_h = geopotential(h.clamp(-0.5 * US1976_R0, US1976_TOP));
    let mut p = 101_325.0;
    for i in 0..7 {
        let last = i == 6 || big_h < LAYER_BASE[i + 1];
        let end = if last { big_h } else { LAYER_BASE[i + 1] };
        let dz = end - LAYER_BASE[i];
        p *= if LAPSE[i] == 0.0 {
            (-gmr * dz / tb[i]).exp()
        } else {
            (tb[i] / (tb[i] + LAPSE[i] * dz)).powf(gmr / LAPSE[i])
        };
        if last {
            break;
        }
    }
    if h > US1976_TOP {
        // Isothermal above the top, in geopotential height.
        p *= (-gmr * (geopotential(h) - geopotential(US1976_TOP)) / tb[7]).exp();
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual64;

    fn kelvin(h: f64) -> f64 {
        us1976_offset(h).0 + US1976_T0
    }

    /// Temperatures at geometric heights of the standard's Table I (its values
    /// rounded to 0.01 K: 11 km 216.77 K, 20 km 216.65 K, 32 km 228.49 K,
    /// 47 km 269.68 K, 51 km 270.65 K, 71 km 216.85 K, 86 km 186.87 K).
    #[test]
    fn temperatures_match_the_published_table() {
        for (h, t) in [
            (0.0, 288.15),
            (11_000.0, 216.77),
            (20_000.0, 216.65),
            (32_000.0, 228.49),
            (47_000.0, 269.68),
            (51_000.0, 270.65),
            (71_000.0, 216.85),
            (86_000.0, 186.87),
        ] {
            assert!(
                (kelvin(h) - t).abs() <= 0.005 + 1e-9,
                "{h}: {} vs {t}",
                kelvin(h)
            );
        }
        // Above the top: held.
        assert_eq!(kelvin(120_000.0), kelvin(US1976_TOP));
        assert_eq!(us1976_offset(120_000.0).1, 0.0);
        // The molecular-scale temperature at the top is 186.946 K (Table 4).
        assert!((base_temperatures()[7] - 186.946).abs() < 1e-9);
    }

    #[test]
    fn breaks_are_the_geometric_layer_bases() {
        for (i, &b) in LAYER_BASE[1..7].iter().enumerate() {
            let h = US1976_R0 * b / (US1976_R0 - b);
            assert!((US1976_BREAKS[i] - h).abs() < 1e-6, "{i}: {h}");
            assert!((geopotential(US1976_BREAKS[i]) - b).abs() < 1e-6);
        }
    }

    #[test]
    fn derivative_matches_finite_differences() {
        let eps = 1e-3;
        let mut h = -500.0;
        while h < 90_000.0 {
            // Skip points within eps of a break, where dT/dh jumps.
            if US1976_BREAKS.iter().all(|b| (b - h).abs() > 2.0 * eps) {
                let fd = (kelvin(h + eps) - kelvin(h - eps)) / (2.0 * eps);
                let d = us1976_offset(h).1;
                assert!((fd - d).abs() < 1e-9, "{h}: {fd} vs {d}");
                let dual = us1976_offset(Dual64::from(h).derivative());
                assert!((dual.0.eps - d).abs() < 1e-15);
                assert_eq!(dual.1.re, d);
            }
            h += 137.3;
        }
    }

    #[test]
    fn continuous_at_boundaries() {
        let mut points = US1976_BREAKS.to_vec();
        points.push(0.0);
        for b in points {
            let below = kelvin(b - 1e-7);
            let above = kelvin(b + 1e-7);
            assert!((below - above).abs() < 1e-8, "{b}: {below} vs {above}");
            assert!(kelvin(b).is_finite());
        }
        // The slope is continuous at the ground.
        assert!((us1976_offset(-1e-9).1 - us1976_offset(1e-9).1).abs() < 1e-12);
        for h in [-1e7, -1e5, 1e9] {
            let (t, d) = us1976_offset(h);
            assert!(t.is_finite() && d.is_finite());
        }
    }

    /// The standard's Table I pressures at the layer bases (geopotential 11, 20, 32,
    /// 47, 51, 71, 84.852 km): 22632.06, 5474.889, 868.0187, 110.9063, 66.93887,
    /// 3.956420, 0.3733836 Pa.
    #[test]
    fn pressure_matches_the_published_table() {
        assert_eq!(us1976_pressure(0.0), 101_325.0);
        let published = [
            22_632.06,
            5_474.889,
            868.0187,
            110.9063,
            66.938_87,
            3.956_420,
            0.373_383_6,
        ];
        for (i, p) in published.iter().enumerate() {
            // 84.852 km geopotential is 85 999.953 m geometric (the standard's "86 km").
            let h = if i < 6 {
                US1976_BREAKS[i]
            } else {
                US1976_R0 * 84_852.0 / (US1976_R0 - 84_852.0)
            };
            let got = us1976_pressure(h);
            assert!((got / p - 1.0).abs() < 2e-6, "{h}: {got} vs {p}");
        }
        // Continuous and decreasing through the layers and beyond the top.
        let mut last = us1976_pressure(-100.0);
        let mut h = -99.0;
        while h < 100_000.0 {
            let p = us1976_pressure(h);
            assert!(p < last && p > 0.0, "{h}");
            last = p;
            h += 97.0;
        }
    }
}
