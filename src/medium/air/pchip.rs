//! A shape-preserving (monotone) piecewise cubic Hermite interpolant, for the measured
//! temperature tables of `docs/air.md`.
//!
//! The slopes at the rows are those of Fritsch & Butland (1984, SIAM J. Sci. Stat.
//! Comput. 5:300), the Fritsch–Carlson (1980, SIAM J. Numer. Anal. 17:238) family, in
//! exactly the form of SciPy's `PchipInterpolator`: with h_k = x_{k+1} − x_k and
//! m_k = (y_{k+1} − y_k)/h_k,
//!
//! - inside, d_k = 0 where m_{k−1} and m_k differ in sign or either is 0 (a local
//!   extremum or a flat stretch), else the weighted harmonic mean
//!   (w1 + w2)/d_k = w1/m_{k−1} + w2/m_k, w1 = 2h_k + h_{k−1}, w2 = h_k + 2h_{k−1};
//! - at the ends, the one-sided three-point estimate
//!   d_0 = ((2h_0 + h_1)m_0 − h_0 m_1)/(h_0 + h_1), set to 0 if its sign differs from
//!   m_0's, and limited to 3m_0 where m_0 and m_1 differ in sign (mirrored at the
//!   other end);
//! - with two rows, the straight line.
//!
//! Invariants: the interpolant passes through every row, is C¹, is monotone on every
//! interval where the data are, never leaves [min, max] of an interval's two rows'
//! values on monotone data (no overshoot), and reproduces linear data exactly (to
//! rounding). Beyond the end rows it is held at the end values (derivative 0 there).
//! Everything is generic in [`Real`], branching only on `.val()`, so rows that are
//! fit parameters (dual numbers) carry exact derivatives; flat or repeated values
//! give d = 0, never a division by zero.

use crate::math::Real;

/// A monotone cubic Hermite interpolant through rows (h_i, T_i).
#[derive(Clone, Debug)]
pub struct Pchip<U> {
    /// The abscissae h_i, strictly increasing.
    x: Vec<U>,
    /// The values T_i.
    y: Vec<U>,
    /// The slopes dT/dh at the rows.
    d: Vec<U>,
}

/// The sign of `v` as SciPy's `np.sign`: −1, 0 or 1.
fn sign(v: f64) -> i8 {
    if v > 0.0 {
        1
    } else if v < 0.0 {
        -1
    } else {
        0
    }
}

/// SciPy's one-sided end slope from the two end intervals (h0, m0) next to the end
/// and (h1, m1) beyond it.
fn end_slope<U: Real>(h0: U, h1: U, m0: U, m1: U) -> U {
    let d = ((h0 * 2.0 + h1) * m0 - h0 * m1) / (h0 + h1);
    if sign(d.val()) != sign(m0.val()) {
        U::cst(0.0)
    } else if sign(m0.val()) != sign(m1.val()) && d.val().abs() > 3.0 * m0.val().abs() {
        m0 * 3.0
    } else {
        d
    }
}

impl<U: Real> Pchip<U> {
    /// The interpolant through `rows` (h strictly increasing, at least two rows;
    /// validated by the caller). With fewer than two rows it is the constant of the
    /// one row (or 0), so it never panics.
    pub fn new(rows: &[(U, U)]) -> Pchip<U> {
        let x: Vec<U> = rows.iter().map(|r| r.0).collect();
        let y: Vec<U> = rows.iter().map(|r| r.1).collect();
        let n = rows.len();
        if n < 2 {
            let d = vec![U::cst(0.0); n];
            return Pchip { x, y, d };
        }
        let h: Vec<U> = (0..n - 1).map(|k| x[k + 1] - x[k]).collect();
        let m: Vec<U> = (0..n - 1).map(|k| (y[k + 1] - y[k]) / h[k]).collect();
        if n == 2 {
            return Pchip {
                x,
                y,
                d: vec![m[0], m[0]],
            };
        }
        let mut d = vec![U::cst(0.0); n];
        for k in 1..n - 1 {
            let (ml, mr) = (m[k - 1], m[k]);
            if sign(ml.val()) != sign(mr.val()) || ml.val() == 0.0 || mr.val() == 0.0 {
                continue;
            }
            let w1 = h[k] * 2.0 + h[k - 1];
            let w2 = h[k] + h[k - 1] * 2.0;
            d[k] = (w1 + w2) / (w1 / ml + w2 / mr);
        }
        d[0] = end_slope(h[0], h[1], m[0], m[1]);
        d[n - 1] = end_slope(h[n - 2], h[n - 3], m[n - 2], m[n - 3]);
        Pchip { x, y, d }
    }

    /// (T, dT/dh) at `h`; the end values and slope 0 beyond the end rows (at an end
    /// row itself, its one-sided slope).
    pub fn eval(&self, h: U) -> (U, U) {
        let n = self.x.len();
        let zero = U::cst(0.0);
        if n == 0 {
            return (zero, zero);
        }
        let hv = h.val();
        // A row belongs to the interval below it, as the ground does for the
        // surface terms and a node does in the previewer's tables: the first
        // row is held (slope 0), the last keeps its one-sided slope.
        if n == 1 || hv <= self.x[0].val() {
            return (self.y[0], zero);
        }
        let last = self.x[n - 1].val();
        if hv >= last {
            // The end row itself keeps its one-sided slope; beyond it, held.
            let slope = if hv == last { self.d[n - 1] } else { zero };
            return (self.y[n - 1], slope);
        }
        // The interval k with x_k ≤ h < x_{k+1}: the number of rows ≤ h, less one.
        let k = self.x.partition_point(|x| x.val() <= hv).saturating_sub(1);
        let w = self.x[k + 1] - self.x[k];
        let t = (h - self.x[k]) / w;
        let (y0, y1) = (self.y[k], self.y[k + 1]);
        let (d0, d1) = (self.d[k] * w, self.d[k + 1] * w);
        // Hermite basis in the form y0 + t·(d0 + t·(c2 + t·c3)), exact at t = 0.
        let c2 = (y1 - y0) * 3.0 - d0 * 2.0 - d1;
        let c3 = (y0 - y1) * 2.0 + d0 + d1;
        let value = y0 + t * (d0 + t * (c2 + t * c3));
        let slope = (d0 + t * (c2 * 2.0 + t * c3 * 3.0)) / w;
        (value, slope)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::Dual64;

    fn pchip(rows: &[(f64, f64)]) -> Pchip<f64> {
        Pchip::new(rows)
    }

    /// A small, non-uniform data set with a maximum, a flat stretch and a steep step.
    const ROWS: [(f64, f64); 7] = [
        (0.0, 10.0),
        (0.5, 12.0),
        (2.0, 12.5),
        (3.0, 9.0),
        (4.5, 9.0),
        (5.0, 3.0),
        (8.0, 2.5),
    ];

    #[test]
    fn reproduces_rows_exactly_and_holds_beyond_the_ends() {
        let p = pchip(&ROWS);
        for &(h, t) in &ROWS {
            assert_eq!(p.eval(h).0, t, "{h}");
        }
        assert_eq!(p.eval(-3.0), (10.0, 0.0));
        assert_eq!(p.eval(1e9), (2.5, 0.0));
    }

    /// Reference values from SciPy 1.17.1, produced by
    /// `PchipInterpolator(x, y)(q)` and `(q, 1)` for the rows of [`ROWS`] at
    /// q = 0.1, 0.3, 0.9, 1.7, 2.4, 2.95, 3.5, 4.7, 4.99, 6.0, 7.9.
    #[test]
    fn matches_scipy() {
        let expected: [(f64, f64, f64); 11] = [
            (0.1, 10.511203980099504, 5.21273631840796),
            (0.3, 11.48041791044776, 4.100696517412935),
            (0.9, 12.24181315644002, 0.4961857379767827),
            (1.7, 12.482388059701494, 0.11940298507462688),
            (2.4, 11.268, -5.04),
            (2.95, 9.025375, -0.9974999999999952),
            (3.5, 9.0, 0.0),
            (4.7, 6.908536502546687, -17.14308998302208),
            (4.99, 3.0112130118845517, -1.8053297113751938),
            (6.0, 2.6802175690121364, -0.22222222222222224),
            (7.9, 2.5002510218197824, -0.005125448028673929),
        ];
        let p = pchip(&ROWS);
        for (q, v, d) in expected {
            let (pv, pd) = p.eval(q);
            assert!(
                (pv - v).abs() < 1e-13 * v.abs().max(1.0),
                "{q}: {pv} vs {v}"
            );
            assert!(
                (pd - d).abs() < 1e-12 * d.abs().max(1.0),
                "{q}: {pd} vs {d}"
            );
        }
    }

    #[test]
    fn no_overshoot_on_monotone_data() {
        let rows = [
            (0.0, 0.0),
            (0.1, 0.0),
            (0.3, 5.0),
            (0.35, 5.01),
            (2.0, 5.02),
            (2.1, 9.0),
            (10.0, 9.0),
        ];
        let p = pchip(&rows);
        for w in rows.windows(2) {
            let (lo, hi) = (w[0].1.min(w[1].1), w[0].1.max(w[1].1));
            for i in 0..=1000 {
                let h = w[0].0 + (w[1].0 - w[0].0) * i as f64 / 1000.0;
                let (v, d) = p.eval(h);
                assert!(v >= lo - 1e-14 && v <= hi + 1e-14, "{h}: {v}");
                assert!(d >= -1e-12, "{h}: {d}");
            }
        }
        // Decreasing data too.
        let down: Vec<(f64, f64)> = rows.iter().map(|&(h, t)| (h, -t)).collect();
        let p = pchip(&down);
        for i in 0..=10_000 {
            let (_, d) = p.eval(i as f64 * 1e-3);
            assert!(d <= 1e-12);
        }
    }

    #[test]
    fn linear_data_is_reproduced() {
        let rows: Vec<(f64, f64)> = [0.0, 0.3, 1.0, 1.1, 4.0, 9.5]
            .iter()
            .map(|&h| (h, 280.0 - 0.0065 * h))
            .collect();
        let p = pchip(&rows);
        // The first row itself belongs to the held outside (slope 0): from
        // the next sample on, the line.
        assert_eq!(p.eval(0.0), (280.0, 0.0));
        for i in 1..=950 {
            let h = i as f64 * 0.01;
            let (v, d) = p.eval(h);
            assert!((v - (280.0 - 0.0065 * h)).abs() < 1e-12, "{h}");
            assert!((d + 0.0065).abs() < 1e-12, "{h}: {d}");
        }
        // Two rows: the straight line.
        let p = pchip(&[(1.0, 2.0), (3.0, 6.0)]);
        assert_eq!(p.eval(2.0), (4.0, 2.0));
    }

    #[test]
    fn flat_and_degenerate_data_stay_finite() {
        let p = pchip(&[(0.0, 5.0), (1.0, 5.0), (2.0, 5.0)]);
        for i in -10..40 {
            let (v, d) = p.eval(i as f64 * 0.1);
            assert_eq!((v, d), (5.0, 0.0));
        }
        for rows in [&[][..], &[(1.0, 3.0)][..]] {
            let p = pchip(rows);
            let (v, d) = p.eval(0.5);
            assert!(v.is_finite() && d == 0.0);
        }
    }

    #[test]
    fn derivative_matches_finite_differences() {
        let p = pchip(&ROWS);
        let eps = 1e-6;
        for i in 1..800 {
            let h = i as f64 * 0.01 + 0.0013;
            let fd = (p.eval(h + eps).0 - p.eval(h - eps).0) / (2.0 * eps);
            let d = p.eval(h).1;
            assert!((fd - d).abs() < 1e-6 * d.abs().max(1.0), "{h}: {fd} vs {d}");
        }
    }

    #[test]
    fn dual_derivative_with_respect_to_a_row_value() {
        let eps = 1e-6;
        for row in [0, 1, 2, 5, 6] {
            let dual_rows: Vec<(Dual64, Dual64)> = ROWS
                .iter()
                .enumerate()
                .map(|(i, &(h, t))| {
                    let t = if i == row {
                        Dual64::from(t).derivative()
                    } else {
                        Dual64::from(t)
                    };
                    (Dual64::from(h), t)
                })
                .collect();
            let p = Pchip::new(&dual_rows);
            let shifted = |s: f64| {
                let mut r = ROWS;
                r[row].1 += s;
                pchip(&r)
            };
            let (plus, minus) = (shifted(eps), shifted(-eps));
            for i in 0..90 {
                let h = i as f64 * 0.0913 - 0.1;
                let (v, d) = p.eval(Dual64::from(h));
                let fd_v = (plus.eval(h).0 - minus.eval(h).0) / (2.0 * eps);
                let fd_d = (plus.eval(h).1 - minus.eval(h).1) / (2.0 * eps);
                assert!(
                    (v.eps - fd_v).abs() < 1e-6,
                    "{row} {h}: {} vs {fd_v}",
                    v.eps
                );
                assert!(
                    (d.eps - fd_d).abs() < 1e-5,
                    "{row} {h}: {} vs {fd_d}",
                    d.eps
                );
            }
        }
    }
}
