//! Hydrostatic pressure over a horizontally uniform temperature profile
//! (`docs/air.md`: dP/dh = −g·M·P/(R·T(h))).
//!
//! With T in kelvin the law integrates to P(h) = P0·exp(−(gM/R)·I(h)),
//! I(h) = ∫₀ʰ dh′/T(h′). [`Hydrostatic::new`] tabulates I once, on nodes h_j:
//!
//! - **Nodes.** The feature centres, 0, and both ends are nodes (so a kink of T at a
//!   centre, e.g. a layer boundary of the US 1976 profile, falls on a node). The
//!   spacing follows σ(h) = min(cap, min_j(s_j/8 + 0.2·max(0, |h − c_j| − 12·s_j)))
//!   for the features (c_j, s_j): at most s_j/8 within ±12 s_j of each centre,
//!   growing away from it by a factor ≤ 1.16 from one interval to the next, up to the
//!   cap of [`MAX_SPACING`] m. Each step is 0.8·σ at its start, which is below σ
//!   all along it (σ is 0.2-Lipschitz). 0 … 86 km: ≈ 2 200 nodes (40 m steps);
//!   with a 0.05 m surface layer and a 1.5 m inversion too, ≈ 2 700.
//! - **Integral.** Composite 8-point Gauss–Legendre on every interval, accumulated
//!   outward from the node at h = 0 with Kahan's compensated sum (so I(0) = 0
//!   exactly, and rounding does not pile up over thousands of pieces).
//! - **Between nodes,** the cubic Hermite interpolant of I through I(h_j) and
//!   I′(h_j) = 1/T(h_j): no evaluation of T at evaluation time. Its error is
//!   ≤ w⁴/384·max|(1/T)‴| for an interval of width w, which sets the cap: a
//!   standard lapse of 6.5 K/km gives |(1/T)‴| = 6L³/T⁴ ≈ 2.4e-16 m⁻³, so
//!   steps of 40 m keep gM/R·δI, the relative error of P, near 5e-14.
//! - **The gradient** is the law itself at the point: dP/dh = −(gM/R)·P/T(h) with
//!   the exact T(h) passed to [`Hydrostatic::eval`].
//! - **Beyond the table's ends** the end node's temperature is held (isothermal):
//!   P stays finite, continuous and monotone for every finite h (its exponent is
//!   clamped at 600 far below the ground, where the pressure would overflow).
//!
//! Measured accuracy (the tests, relative error of P): isothermal to 86 km against
//! the closed form, 4e-15; a 6.5 K/km lapse to 11 km against its closed form,
//! 2e-13; the exponential surface layer of `docs/air.md` on 0 … 20 m against an
//! adaptive Simpson reference, 8e-15; the US 1976 profile to 86 km (its
//! [`US1976_BREAKS`](super::standard::US1976_BREAKS) given as features, so its kinks
//! are nodes), 2e-13. A kink of T between nodes costs accuracy (the US 1976 profile
//! without its breaks as features: 5e-8): give every kink as a feature. The
//! returned dP/dh and the derivative of the returned P agree to 2e-8 (the finite
//! difference's own rounding). All of it is generic in [`Real`], so dual parameters
//! in P0 or inside T carry exact derivatives of the table.
//!
//! g is constant with geometric height, as the contract says; the US 1976 standard
//! integrates in geopotential height (g falling with height), so its own pressure is
//! higher than this law's over its temperatures: by 0.27 % at 11 km, 1 % at 20 km,
//! 5 % at 50 km and 16 % at 86 km.

use crate::math::Real;

/// Standard gravity g, m/s².
pub const G: f64 = 9.806_65;
/// The molar mass of dry air M, kg/mol.
pub const M: f64 = 0.028_964_4;
/// The molar gas constant R, J/(mol·K) (CODATA 2018).
pub const R: f64 = 8.314_462_618;

/// gM/R, kelvin per metre: the hydrostatic exponent's coefficient.
const K: f64 = G * M / R;

/// The widest node spacing, in metres (see the module documentation).
pub const MAX_SPACING: f64 = 50.0;

/// The most nodes a table gets: beyond it the cap on the spacing grows, so an
/// absurd `h_max` cannot exhaust memory.
const MAX_NODES: f64 = 100_000.0;

/// Growth of the spacing per metre away from a feature.
const GROWTH: f64 = 0.2;

/// The largest exponent of P/P0 (e^600 ≈ 4e260, so P0·e^600 stays finite).
const MAX_EXPONENT: f64 = 600.0;

/// The highest pressure the table gives (Pa), some 50 km below the ground:
/// deeper (only rays that went through the ground get there) it is held,
/// with a zero derivative. Held higher, the formulas' P² terms overflowed and
/// a dual number's derivative became ∞ − ∞ (the `photo` fuzz target: a ray
/// launched straight down ended 2,000 km underground with a NaN Jacobian).
const MAX_PRESSURE: f64 = 1e8;

/// Gauss–Legendre abscissae (positive half) and weights, 8 points on [−1, 1].
const GL_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
const GL_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// P(h) over a tabulated ∫dh/T; see the module documentation.
#[derive(Clone, Debug)]
pub struct Hydrostatic<U> {
    /// The pressure at h = 0, Pa.
    p0: U,
    /// The node heights, strictly increasing, one of them 0.
    nodes: Vec<f64>,
    /// I(h_j) = ∫₀^{h_j} dh/T.
    integral: Vec<U>,
    /// 1/T(h_j).
    inv_t: Vec<U>,
}

/// The node heights from `lo` ≤ 0 to `hi` ≥ 0 for the features `scales`.
fn place_nodes(lo: f64, hi: f64, scales: &[(f64, f64)]) -> Vec<f64> {
    let features: Vec<(f64, f64)> = scales
        .iter()
        .copied()
        .filter(|&(c, s)| c.is_finite() && s.is_finite() && s > 0.0)
        .collect();
    let cap = MAX_SPACING.max((hi - lo) / MAX_NODES);
    let spacing = |h: f64| {
        features.iter().fold(cap, |acc, &(c, s)| {
            let far = ((h - c).abs() - 12.0 * s).max(0.0);
            acc.min(s / 8.0 + GROWTH * far)
        })
    };
    let mut anchors: Vec<f64> = vec![lo, 0.0, hi];
    anchors.extend(features.iter().map(|f| f.0).filter(|&c| c > lo && c < hi));
    anchors.sort_by(f64::total_cmp);
    anchors.dedup();
    let mut nodes = vec![lo];
    for pair in anchors.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let mut h = a;
        loop {
            let step = 0.8 * spacing(h);
            // A feature's scale below the spacing of floats where it lies
            // (an inversion at 10⁸³ m, 2 m thick: fuzzing found it) would
            // add nodes that never advance: stop at the last distinct one.
            // The node count is capped too, whatever the features.
            if b - h <= step || h + step <= h || nodes.len() as f64 > 4.0 * MAX_NODES {
                break;
            }
            h += step;
            nodes.push(h);
        }
        // Drop a node that would leave a sliver of an interval before b.
        if let Some(&last) = nodes.last()
            && last > a
            && b - last < 1e-3 * spacing(last)
        {
            nodes.pop();
        }
        nodes.push(b);
    }
    nodes
}

/// One step of Kahan's compensated summation: (sum + x, the new lost low part).
fn kahan<U: Real>(sum: U, carry: U, x: U) -> (U, U) {
    let y = x - carry;
    let t = sum + y;
    (t, (t - sum) - y)
}

impl<U: Real> Hydrostatic<U> {
    /// Tabulates I(h) on nodes from `h_min` (may be < 0, e.g. −10 m) to `h_max`
    /// (the table always spans 0 too, and at least 1 m), the nodes placed so that every given feature
    /// scale is resolved: `scales` is a list of (centre height, length scale) pairs
    /// of the profile's sharp features and kinks (e.g. a surface layer of scale
    /// height 0.05 m at 0, an inversion of thickness 1.5 m at 12 m, the US 1976
    /// layer boundaries); pairs with a scale that is not positive and finite are
    /// ignored. `kelvin(h)` returns (T, dT/dh), T in kelvin, positive.
    pub fn new(
        p0: U,
        kelvin: impl Fn(U) -> (U, U),
        h_min: f64,
        h_max: f64,
        scales: &[(f64, f64)],
    ) -> Self {
        let (lo, hi) = (h_min.min(0.0), h_max.max(0.0));
        // At least one interval, so that evaluation always has one.
        let hi = if hi > lo { hi } else { lo + 1.0 };
        let nodes = place_nodes(lo, hi, scales);
        let inv_t: Vec<U> = nodes.iter().map(|&h| kelvin(U::cst(h)).0.recip()).collect();
        // ∫ dh/T over [nodes[j], nodes[j + 1]].
        let piece = |j: usize| {
            let (a, b) = (nodes[j], nodes[j + 1]);
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            let mut sum = U::cst(0.0);
            for (x, w) in GL_X.iter().zip(GL_W) {
                let left = kelvin(U::cst(mid - half * x)).0.recip();
                let right = kelvin(U::cst(mid + half * x)).0.recip();
                sum += (left + right) * w;
            }
            sum * half
        };
        // place_nodes always puts a node at 0.
        let zero = nodes.iter().position(|&h| h == 0.0).unwrap_or(0);
        // Kahan-compensated sums: over thousands of near-equal pieces plain
        // rounding would accumulate to ~1e-12 in I.
        let mut integral = vec![U::cst(0.0); nodes.len()];
        let (mut sum, mut carry) = (U::cst(0.0), U::cst(0.0));
        for (j, out) in integral.iter_mut().enumerate().skip(zero + 1) {
            (sum, carry) = kahan(sum, carry, piece(j - 1));
            *out = sum;
        }
        let (mut sum, mut carry) = (U::cst(0.0), U::cst(0.0));
        for (j, out) in integral[..zero].iter_mut().enumerate().rev() {
            (sum, carry) = kahan(sum, carry, -piece(j));
            *out = sum;
        }
        Hydrostatic {
            p0,
            nodes,
            integral,
            inv_t,
        }
    }

    /// The number of nodes of the table.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// (P, dP/dh) at h, given T(h) in kelvin (`kelvin_at_h`, the exact temperature
    /// there); beyond the table's ends, continue with the end node's temperature
    /// held (isothermal), so it stays finite for any finite h.
    pub fn eval(&self, h: U, kelvin_at_h: U) -> (U, U) {
        let n = self.nodes.len();
        let hv = h.val();
        let (first, last) = (self.nodes[0], self.nodes[n - 1]);
        // I(h), and the 1/T that the gradient uses.
        let (integral, inv_t) = if hv < first {
            let inv = self.inv_t[0];
            (self.integral[0] + (h - first) * inv, inv)
        } else if hv > last {
            let inv = self.inv_t[n - 1];
            (self.integral[n - 1] + (h - last) * inv, inv)
        } else {
            let k = self
                .nodes
                .partition_point(|&x| x <= hv)
                .saturating_sub(1)
                .min(n - 2);
            let (a, b) = (self.nodes[k], self.nodes[k + 1]);
            let w = b - a;
            let t = (h - a) / w;
            let (i0, i1) = (self.integral[k], self.integral[k + 1]);
            let (d0, d1) = (self.inv_t[k] * w, self.inv_t[k + 1] * w);
            let c2 = (i1 - i0) * 3.0 - d0 * 2.0 - d1;
            let c3 = (i0 - i1) * 2.0 + d0 + d1;
            (i0 + t * (d0 + t * (c2 + t * c3)), kelvin_at_h.recip())
        };
        let exponent = integral * (-K);
        let limit = (MAX_PRESSURE / self.p0.val()).ln().min(MAX_EXPONENT);
        if exponent.val() > limit {
            // Tens of kilometres below the ground: held, not overflowing.
            return (U::cst(self.p0.val() * limit.exp()), U::cst(0.0));
        }
        let p = self.p0 * exponent.exp();
        (p, p * inv_t * (-K))
    }
}

#[cfg(test)]
mod tests {
    use super::super::standard::{US1976_BREAKS, US1976_T0, US1976_TOP, us1976_offset};
    use super::*;
    use num_dual::{Dual64, DualNum};

    const P0: f64 = 101_325.0;

    /// Adaptive Simpson quadrature of `f` on [a, b] to an absolute `tol`: the
    /// reference, independent of the Gauss–Legendre table.
    fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> f64 {
        #[allow(clippy::too_many_arguments)]
        fn go(
            f: &dyn Fn(f64) -> f64,
            a: f64,
            b: f64,
            fa: f64,
            fm: f64,
            fb: f64,
            whole: f64,
            tol: f64,
            depth: u32,
        ) -> f64 {
            let m = 0.5 * (a + b);
            let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
            let (flm, frm) = (f(lm), f(rm));
            let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
            let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
            let diff = left + right - whole;
            if depth == 0 || diff.abs() <= 15.0 * tol {
                return left + right + diff / 15.0;
            }
            go(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1)
                + go(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1)
        }
        if a == b {
            return 0.0;
        }
        let m = 0.5 * (a + b);
        let (fa, fm, fb) = (f(a), f(m), f(b));
        let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
        go(f, a, b, fa, fm, fb, whole, tol, 40)
    }

    /// The reference pressure at increasing heights `hs` (≥ 0) by adaptive Simpson
    /// between consecutive heights and the given breaks.
    fn reference(t: &dyn Fn(f64) -> f64, hs: &[f64], breaks: &[f64]) -> Vec<f64> {
        let inv = |h: f64| 1.0 / t(h);
        let mut out = Vec::new();
        let (mut at, mut integral) = (0.0, 0.0);
        for &h in hs {
            let mut cuts: Vec<f64> = breaks
                .iter()
                .copied()
                .filter(|&b| b > at && b < h)
                .collect();
            cuts.push(h);
            for c in cuts {
                integral += simpson(&inv, at, c, 1e-16);
                at = c;
            }
            out.push(P0 * (-K * integral).exp());
        }
        out
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a / b - 1.0).abs()
    }

    #[test]
    fn gauss_legendre_is_exact_to_degree_15() {
        for k in 0..8 {
            let deg = 2 * k;
            let sum: f64 = GL_X
                .iter()
                .zip(GL_W)
                .map(|(x, w)| 2.0 * w * x.powi(deg))
                .sum();
            assert!((sum - 2.0 / (deg as f64 + 1.0)).abs() < 1e-15, "{deg}");
        }
    }

    #[test]
    fn isothermal() {
        let t = 250.0;
        let hy = Hydrostatic::new(P0, |_| (t, 0.0), -10.0, US1976_TOP, &[(0.0, 0.05)]);
        let mut worst = 0.0f64;
        for i in 0..=2000 {
            let h = -10.0 + i as f64 * 43.1;
            let (p, dp) = hy.eval(h, t);
            let exact = P0 * (-K * h / t).exp();
            worst = worst.max(rel(p, exact));
            assert!(rel(dp, -K * exact / t) < 1e-13, "{h}");
        }
        println!("isothermal: worst {worst:.1e}");
        assert!(worst < 1e-13, "{worst}");
        assert_eq!(hy.eval(0.0, t).0, P0);
    }

    #[test]
    fn linear_lapse() {
        let (t0, l) = (288.15, -0.0065);
        let kelvin = |h: f64| (t0 + l * h, l);
        let hy = Hydrostatic::new(P0, kelvin, -10.0, 11_000.0, &[]);
        let mut worst = 0.0f64;
        for i in 0..=5000 {
            let h = -10.0 + i as f64 * 2.2019;
            let exact = P0 * ((t0 + l * h) / t0).powf(-K / l);
            worst = worst.max(rel(hy.eval(h, kelvin(h).0).0, exact));
        }
        println!("linear lapse: worst {worst:.1e}, {} nodes", hy.node_count());
        assert!(worst < 1e-12, "{worst}");
        assert!(hy.node_count() < 400, "{}", hy.node_count());
    }

    fn surface_layer(h: f64) -> (f64, f64) {
        let e = 3.15 * (-20.1 * h).exp();
        (283.18 + e, -20.1 * e)
    }

    #[test]
    fn exponential_surface_layer() {
        let scales = [(0.0, 1.0 / 20.1), (12.0, 1.5)];
        let hy = Hydrostatic::new(P0, surface_layer, -10.0, 200.0, &scales);
        let hs: Vec<f64> = (1..=2000).map(|i| i as f64 * 0.01 - 0.0037).collect();
        let refs = reference(&|h| surface_layer(h).0, &hs, &[]);
        let mut worst = 0.0f64;
        for (&h, &r) in hs.iter().zip(&refs) {
            worst = worst.max(rel(hy.eval(h, surface_layer(h).0).0, r));
        }
        assert!(worst < 1e-12, "{worst}");
        println!("surface layer: worst relative error {worst:.1e}");
    }

    fn us1976(h: f64) -> (f64, f64) {
        let (dt, slope) = us1976_offset(h);
        (US1976_T0 + dt, slope)
    }

    #[test]
    fn us1976_profile() {
        // The kinks only need to be nodes: a scale of 8 × the cap adds no refinement.
        let scales: Vec<(f64, f64)> = US1976_BREAKS
            .iter()
            .map(|&b| (b, 8.0 * MAX_SPACING))
            .collect();
        let hy = Hydrostatic::new(P0, us1976, -10.0, US1976_TOP, &scales);
        assert!(hy.node_count() < 2500, "{}", hy.node_count());
        // With the fine features of docs/air.md's example on top.
        let mut fine = scales.clone();
        fine.extend([(0.0, 0.0497512), (12.0, 1.5)]);
        let count = Hydrostatic::new(P0, us1976, -10.0, US1976_TOP, &fine).node_count();
        println!("US 1976 with a surface layer and an inversion: {count} nodes");
        assert!(count < 3000, "{count}");
        let hs: Vec<f64> = (1..=860).map(|i| i as f64 * 100.0 - 3.7).collect();
        let refs = reference(&|h| us1976(h).0, &hs, &US1976_BREAKS);
        let (mut worst, mut at) = (0.0f64, 0.0);
        for (&h, &r) in hs.iter().zip(&refs) {
            let e = rel(hy.eval(h, us1976(h).0).0, r);
            if e > worst {
                (worst, at) = (e, h);
            }
        }
        println!(
            "US 1976: {} nodes, worst {worst:.1e} at {at} m",
            hy.node_count()
        );
        assert!(worst < 1e-10, "{worst}");
        // For information: against the standard's own pressure, which integrates
        // the molecular-scale temperature in geopotential height (printed, not
        // asserted tightly).
        for km in [1.0, 5.0, 11.0, 20.0, 32.0, 47.0, 51.0, 71.0, 86.0] {
            let h = km * 1000.0;
            let (p, std) = (
                hy.eval(h, us1976(h).0).0,
                super::super::standard::us1976_pressure(h),
            );
            println!(
                "{km:5} km: {p:.6e} Pa, standard {std:.6e} Pa, {:+.3} %",
                100.0 * (p / std - 1.0)
            );
            assert!(rel(p, std) < 0.25, "{km}");
        }
    }

    #[test]
    fn gradient_is_the_derivative() {
        // The surface layer, the inversion of docs/air.md and a standard lapse.
        let kelvin = |h: f64| {
            let (a, da) = surface_layer(h);
            let (s, ds) = crate::math::sigmoid((h - 12.0) / 1.5);
            (a + 4.0 * s - 0.0065 * h, da + 4.0 / 1.5 * ds - 0.0065)
        };
        let scales = [(0.0, 1.0 / 20.1), (12.0, 1.5)];
        let hy = Hydrostatic::new(P0, kelvin, -10.0, 3000.0, &scales);
        let eps = 1e-4;
        let mut worst = 0.0f64;
        for i in 0..3000 {
            // From within the resolved zone below the ground to above the table.
            let h = -0.5 + i as f64 * 1.0057;
            let at = |x: f64| hy.eval(x, kelvin(x).0).0;
            // Fourth-order central difference (T varies on 0.05 m scales here).
            let fd = (8.0 * (at(h + eps) - at(h - eps)) - (at(h + 2.0 * eps) - at(h - 2.0 * eps)))
                / (12.0 * eps);
            let (p, dp) = hy.eval(h, kelvin(h).0);
            // The difference's rounding is ~1e-16·P/eps, which matters below the
            // ground, where this T grows as e^(20 |h|) and dP/dh falls to ~1e-2.
            assert!(
                (fd - dp).abs() < 1e-7 * dp.abs() + 1e-12 * p,
                "{h}: {fd} vs {dp}"
            );
            if h > 0.0 {
                worst = worst.max((fd / dp - 1.0).abs());
            }
        }
        println!("dP/dh against the finite difference of P: worst {worst:.1e}");
    }

    #[test]
    fn dual_derivatives_match_finite_differences() {
        let scales = [(0.0, 1.0 / 20.1)];
        let kelvin_a = |a: Dual64| {
            move |h: Dual64| {
                let e = (h * -20.1).exp() * a;
                (e + 283.18, e * -20.1)
            }
        };
        let heights = [-3.0, 0.0, 0.01, 0.3, 5.0, 150.0, 250.0];
        // With respect to p0.
        let hy = Hydrostatic::new(
            Dual64::from(P0).derivative(),
            kelvin_a(Dual64::from(3.15)),
            -5.0,
            200.0,
            &scales,
        );
        for h in heights {
            let t = kelvin_a(Dual64::from(3.15))(Dual64::from(h)).0;
            let (p, dp) = hy.eval(Dual64::from(h), t);
            assert!(rel(p.eps, p.re / P0) < 1e-14, "{h}");
            assert!(rel(dp.eps, dp.re / P0) < 1e-14, "{h}");
        }
        // With respect to the surface layer's delta, inside kelvin().
        let hy = Hydrostatic::new(
            Dual64::from(P0),
            kelvin_a(Dual64::from(3.15).derivative()),
            -5.0,
            200.0,
            &scales,
        );
        let eps = 1e-3;
        let at = |a: f64, h: f64| {
            let k = |h: f64| {
                let e = a * (-20.1 * h).exp();
                (283.18 + e, -20.1 * e)
            };
            Hydrostatic::new(P0, k, -5.0, 200.0, &scales).eval(h, k(h).0)
        };
        for h in heights {
            let t = kelvin_a(Dual64::from(3.15).derivative())(Dual64::from(h)).0;
            let (p, dp) = hy.eval(Dual64::from(h), t);
            let fd = (at(3.15 + eps, h).0 - at(3.15 - eps, h).0) / (2.0 * eps);
            let fd_dp = (at(3.15 + eps, h).1 - at(3.15 - eps, h).1) / (2.0 * eps);
            // The finite differences carry ~1e-8 of rounding (P ~ 1e5, step 1e-3).
            assert!(
                (p.eps - fd).abs() < 1e-6 * fd.abs() + 1e-7,
                "{h}: {} vs {fd}",
                p.eps
            );
            assert!((dp.eps - fd_dp).abs() < 1e-6 * fd_dp.abs() + 1e-9, "{h}");
        }
    }

    #[test]
    fn beyond_the_ends() {
        let (t0, l) = (288.15, -0.0065);
        let kelvin = |h: f64| (t0 + l * h, l);
        let hy = Hydrostatic::new(P0, kelvin, -10.0, 11_000.0, &[]);
        // Continuous at both ends, isothermal beyond them.
        for end in [-10.0, 11_000.0] {
            let (below, above) = (
                hy.eval(end - 1e-9, kelvin(end).0),
                hy.eval(end + 1e-9, kelvin(end).0),
            );
            assert!(rel(below.0, above.0) < 1e-12, "{end}");
            assert!(rel(below.1, above.1) < 1e-9, "{end}");
        }
        let (t_top, p_top) = (kelvin(11_000.0).0, hy.eval(11_000.0, kelvin(11_000.0).0).0);
        let (p, dp) = hy.eval(20_000.0, 123.0);
        assert!(rel(p, p_top * (-K * 9000.0 / t_top).exp()) < 1e-13);
        assert!(rel(dp, -K * p / t_top) < 1e-13);
        // A degenerate table still has an interval.
        let flat = Hydrostatic::new(P0, kelvin, 0.0, 0.0, &[]);
        assert_eq!(flat.eval(0.0, t0).0, P0);
        assert!(flat.eval(-5.0, t0).0 > P0 && flat.eval(5.0, t0).0 < P0);
        // Finite and monotone for any finite height.
        let mut last = f64::INFINITY;
        for h in [
            -1e300, -1e12, -1e7, -1e5, -100.0, -11.0, 0.0, 5e3, 2e4, 1e5, 1e7, 1e300,
        ] {
            let (p, dp) = hy.eval(h, 250.0);
            assert!(p.is_finite() && dp.is_finite() && p >= 0.0, "{h}");
            assert!(p <= last, "{h}");
            last = p;
        }
    }
}
