//! A compiled 1-D profile: δ(h) = n − 1 and dδ/dh of a horizontally uniform
//! medium as piecewise polynomials in height, built once from the formula and
//! then evaluated in a few multiply–adds instead of the formula's hundreds of
//! operations (real air's Ciddor, saturation vapour pressure and hydrostatic
//! pressure at every stage of every ray).
//!
//! # Algorithm
//!
//! - **Range.** `[lo, hi)`, the heights rays can reach (for real air: the
//!   bottom of the hydrostatic table, 200 m under the ground, up to the top
//!   of the described air or the ceiling, whichever is lower). Outside it,
//!   [`CompiledProfile::eval`] answers `None` and the caller evaluates the
//!   formula.
//! - **Knots.** The caller's breakpoints (every height where the formula is
//!   not smooth: the ground, a kink of the US 1976 layers, a table's rows,
//!   the ends of the hydrostatic table) are knots; every interval between
//!   them is bisected adaptively until its fit passes the check below, down
//!   to [`MIN_WIDTH`] m.
//! - **Fit.** On a piece [a, b], t = (h − m)/r with m = (a + b)/2, r = (b − a)/2,
//!   δ and dδ/dh are each interpolated, independently, by a polynomial of
//!   degree [`DEGREE`] at the Chebyshev points of the first kind (all inside
//!   the piece, so a branch of the formula at a knot is never sampled), and
//!   stored as monomial coefficients in t for Horner's rule. The gradient is
//!   its own fit, not the derivative of δ's, because the formula's gradient
//!   is the law at the point (real air's dP/dh = −(gM/R)·P/T) while its δ
//!   interpolates a pressure table: the two differ by up to 3e-11 of dδ/dh,
//!   and each compiled part must reproduce its own formula part.
//! - **Check.** At 17 heights per piece (the 15 interior extrema of T₁₆ and
//!   both ends, one part in 10⁹ inside): |δ̃ − δ| ≤ [`CHECK`]·|δ| and
//!   |g̃ − g| ≤ [`CHECK`]·max(|g|, |δ|/[`SLOPE_SCALE`]) (g = dδ/dh; the second
//!   form near g's zeros, where a relative bound means nothing). A piece that
//!   still fails at [`MIN_WIDTH`] (a kink the caller did not name, a value
//!   that is not finite), and every piece past [`MAX_PIECES`], is marked
//!   *exact*: there `eval` answers `None` and the formula is used.
//! - **Lookup** is O(1): a uniform grid of cells over the range, each with
//!   the first and last piece it overlaps, then a binary search between them
//!   (usually none: cells are about as many as pieces, twice over). At a knot
//!   itself `eval` answers `None` too, so the formula picks its own branch
//!   there (the ground's surface layer is held at h ≤ 0, the US 1976 layers
//!   switch at h ≥ a break).
//!
//! # Accuracy
//!
//! Checked with a margin of 10: the stated bound, which
//! `tests/compiled_profile.rs` tests at random heights of random media, is
//! |δ̃ − δ| ≤ 1e-12·|δ| and |g̃ − g| ≤ 1e-12·max(|g|, |δ|/1 km) wherever
//! `eval` answers. Between the check points the interpolation error of a
//! smooth function is of the size the check sees (the points interleave the
//! nodes and reach both ends, where it is largest).

/// The polynomials' degree (8 coefficients: one 64-byte line each for δ
/// and dδ/dh).
pub const DEGREE: usize = 7;
const COEFFS: usize = DEGREE + 1;

/// The relative error a piece must pass at every check point.
pub const CHECK: f64 = 1e-13;

/// The bound the compiled profile is tested at (10 × [`CHECK`]).
pub const BOUND: f64 = 1e-12;

/// Heights over which δ may change by itself (m): the gradient's error is
/// relative to max(|dδ/dh|, |δ|/`SLOPE_SCALE`). Near the gradient's zeros
/// the formula's own dδ/dh is a difference of terms of about |δ|/1 km (dry
/// air and water vapour, pressure and temperature), so its rounding is
/// about 1e-16 of that: a bound finer than 1e-13·|δ|/1 km would test that
/// rounding, not the fit (at 10 km, humidity tables left thousands of
/// pieces near their rows' extrema to the formula).
pub const SLOPE_SCALE: f64 = 1.0e3;

/// The narrowest piece the bisection makes (m).
pub const MIN_WIDTH: f64 = 1.0e-4;

/// The most pieces a profile gets; past them the formula is used.
pub const MAX_PIECES: usize = 1 << 16;

/// One piece: its centre, the inverse of its half-width, and the monomial
/// coefficients in t of δ and dδ/dh (constant term first).
#[derive(Clone, Copy, Debug)]
pub struct Piece {
    /// Centre m of the piece (m).
    pub mid: f64,
    /// 1/r, r the half-width (1/m).
    pub inv_half: f64,
    /// δ's coefficients.
    pub value: [f64; COEFFS],
    /// dδ/dh's coefficients.
    pub slope: [f64; COEFFS],
}

impl Piece {
    /// (δ, dδ/dh) at height h in this piece, by Horner's rule.
    #[inline(always)]
    pub fn eval(&self, h: f64) -> (f64, f64) {
        let t = (h - self.mid) * self.inv_half;
        let mut v = self.value[DEGREE];
        let mut g = self.slope[DEGREE];
        for k in (0..DEGREE).rev() {
            v = v * t + self.value[k];
            g = g * t + self.slope[k];
        }
        (v, g)
    }
}

/// A compiled profile (see the module documentation).
#[derive(Clone, Debug)]
pub struct CompiledProfile {
    lo: f64,
    hi: f64,
    /// Piece k spans `knots[k]..knots[k + 1]`.
    knots: Vec<f64>,
    pieces: Vec<Piece>,
    /// Whether piece k is left to the formula.
    exact: Vec<bool>,
    /// 1 / the cells' width.
    inv_cell: f64,
    /// The first and last piece each cell overlaps.
    cells: Vec<(u32, u32)>,
}

/// The Chebyshev points of the first kind, cos(π(j + ½)/8).
fn nodes() -> [f64; COEFFS] {
    std::array::from_fn(|j| (std::f64::consts::PI * (j as f64 + 0.5) / COEFFS as f64).cos())
}

/// The check points: the interior extrema of T₁₆ and both ends, 1e-9 inside.
fn check_points() -> [f64; 17] {
    std::array::from_fn(|j| match j {
        0 => -(1.0 - 1e-9),
        16 => 1.0 - 1e-9,
        _ => (std::f64::consts::PI * j as f64 / 16.0).cos(),
    })
}

/// Monomial coefficients (in t) of the polynomial through `(nodes()[j], f[j])`.
fn interpolate(f: &[f64; COEFFS]) -> [f64; COEFFS] {
    let x = nodes();
    // Chebyshev coefficients c_k = (2/n)·Σ_j f_j·T_k(x_j), c_0 halved.
    let n = COEFFS as f64;
    let mut c = [0.0; COEFFS];
    for (j, &fj) in f.iter().enumerate() {
        let (mut t0, mut t1) = (1.0, x[j]);
        c[0] += fj;
        c[1] += fj * t1;
        for ck in c.iter_mut().skip(2) {
            let t2 = 2.0 * x[j] * t1 - t0;
            *ck += fj * t2;
            (t0, t1) = (t1, t2);
        }
    }
    for ck in &mut c {
        *ck *= 2.0 / n;
    }
    c[0] *= 0.5;
    // Σ c_k·T_k in monomials, T_{k+1} = 2t·T_k − T_{k−1}.
    let mut mono = [0.0; COEFFS];
    let mut prev = [0.0; COEFFS];
    let mut cur = [0.0; COEFFS];
    prev[0] = 1.0;
    cur[1] = 1.0;
    mono[0] += c[0];
    for m in 0..COEFFS {
        mono[m] += c[1] * cur[m];
    }
    for ck in c.iter().skip(2) {
        let mut next = [0.0; COEFFS];
        for m in 0..COEFFS {
            let up = if m > 0 { 2.0 * cur[m - 1] } else { 0.0 };
            next[m] = up - prev[m];
        }
        for m in 0..COEFFS {
            mono[m] += ck * next[m];
        }
        (prev, cur) = (cur, next);
    }
    mono
}

/// Whether the fit `piece` of `f` passes the check on [a, b].
fn passes(piece: &Piece, a: f64, b: f64, f: &impl Fn(f64) -> (f64, f64)) -> bool {
    let (m, r) = (0.5 * (a + b), 0.5 * (b - a));
    check_points().iter().all(|&t| {
        let h = m + r * t;
        let (d, g) = f(h);
        let (dc, gc) = piece.eval(h);
        let dv = (dc - d).abs();
        let gv = (gc - g).abs();
        d.is_finite()
            && g.is_finite()
            && dv <= CHECK * d.abs()
            && gv <= CHECK * g.abs().max(d.abs() / SLOPE_SCALE)
    })
}

/// The fit of `f` on [a, b].
fn fit(a: f64, b: f64, f: &impl Fn(f64) -> (f64, f64)) -> Piece {
    let (m, r) = (0.5 * (a + b), 0.5 * (b - a));
    let x = nodes();
    let mut dv = [0.0; COEFFS];
    let mut gv = [0.0; COEFFS];
    for j in 0..COEFFS {
        (dv[j], gv[j]) = f(m + r * x[j]);
    }
    Piece {
        mid: m,
        inv_half: 1.0 / r,
        value: interpolate(&dv),
        slope: interpolate(&gv),
    }
}

impl CompiledProfile {
    /// Compiles `f` (h ↦ (δ, dδ/dh)) over [lo, hi) with knots at `breaks`
    /// (those outside the range are ignored). An empty or non-finite range
    /// gives a profile that answers `None` everywhere.
    pub fn compile(lo: f64, hi: f64, breaks: &[f64], f: impl Fn(f64) -> (f64, f64)) -> Self {
        let mut bounds: Vec<f64> = vec![lo, hi];
        bounds.extend(breaks.iter().copied().filter(|&b| b > lo && b < hi));
        bounds.retain(|b| b.is_finite());
        bounds.sort_by(f64::total_cmp);
        bounds.dedup();
        let mut knots = Vec::new();
        let mut pieces = Vec::new();
        let mut exact = Vec::new();
        if !(lo.is_finite() && hi.is_finite() && lo < hi) || bounds.len() < 2 {
            return Self::index(lo, hi, knots, pieces, exact);
        }
        knots.push(bounds[0]);
        for w in bounds.windows(2) {
            // Depth first, the left half on top: pieces come out in order.
            let mut stack = vec![(w[0], w[1])];
            while let Some((a, b)) = stack.pop() {
                let full = pieces.len() >= MAX_PIECES;
                let piece = fit(a, b, &f);
                let mid = 0.5 * (a + b);
                let splittable = b - a > 2.0 * MIN_WIDTH && mid > a && mid < b;
                let ok = !full && passes(&piece, a, b, &f);
                if !full && !ok && splittable {
                    stack.push((mid, b));
                    stack.push((a, mid));
                    continue;
                }
                exact.push(!ok);
                pieces.push(piece);
                knots.push(b);
            }
        }
        Self::index(lo, hi, knots, pieces, exact)
    }

    /// Builds the lookup grid over the pieces.
    fn index(lo: f64, hi: f64, knots: Vec<f64>, pieces: Vec<Piece>, exact: Vec<bool>) -> Self {
        let n = pieces.len();
        let count = (2 * n).clamp(1, 1 << 20);
        let width = (hi - lo) / count as f64;
        let mut cells = Vec::with_capacity(if n == 0 { 0 } else { count });
        if n > 0 {
            let mut k = 0usize;
            for c in 0..count {
                let start = lo + c as f64 * width;
                let end = lo + (c + 1) as f64 * width;
                while k + 1 < n && knots[k + 1] <= start {
                    k += 1;
                }
                let mut last = k;
                while last + 1 < n && knots[last + 1] < end {
                    last += 1;
                }
                cells.push((k as u32, last as u32));
            }
        }
        CompiledProfile {
            lo,
            hi,
            knots,
            pieces,
            exact,
            inv_cell: if width > 0.0 { 1.0 / width } else { 0.0 },
            cells,
        }
    }

    /// The range [lo, hi) the profile covers (m).
    pub fn range(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }

    /// How many pieces, and how many of them are left to the formula.
    pub fn pieces(&self) -> (usize, usize) {
        (self.pieces.len(), self.exact.iter().filter(|&&e| e).count())
    }

    /// The height intervals left to the formula (pieces that did not pass
    /// the check down to [`MIN_WIDTH`], or past [`MAX_PIECES`]), merged.
    pub fn formula_spans(&self) -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = Vec::new();
        for (k, &e) in self.exact.iter().enumerate() {
            if !e {
                continue;
            }
            let (a, b) = (self.knots[k], self.knots[k + 1]);
            match out.last_mut() {
                Some(last) if last.1 == a => last.1 = b,
                _ => out.push((a, b)),
            }
        }
        out
    }

    /// The piece whose open interval holds h, or `None` outside the range,
    /// at a knot, or in a piece left to the formula.
    #[inline(always)]
    pub fn locate(&self, h: f64) -> Option<&Piece> {
        // `!(h >= lo)` also takes NaN out.
        if !(h >= self.lo && h < self.hi) || self.cells.is_empty() {
            return None;
        }
        let c = (((h - self.lo) * self.inv_cell) as usize).min(self.cells.len() - 1);
        let (a, b) = self.cells[c];
        let (mut a, mut b) = (a as usize, b as usize);
        // The last piece in [a, b] starting at or below h (the cell's
        // rounding may put h a piece off: then search everywhere).
        if !(self.knots[a] <= h && h < self.knots[b + 1]) {
            (a, b) = (0, self.pieces.len() - 1);
        }
        while a < b {
            let m = (a + b).div_ceil(2);
            if self.knots[m] <= h {
                a = m;
            } else {
                b = m - 1;
            }
        }
        if h == self.knots[a] || self.exact[a] {
            return None;
        }
        Some(&self.pieces[a])
    }

    /// (δ, dδ/dh) at height h, or `None` where the formula must answer
    /// (see [`CompiledProfile::locate`]).
    #[inline]
    pub fn eval(&self, h: f64) -> Option<(f64, f64)> {
        self.locate(h).map(|p| p.eval(h))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_polynomial_of_the_degree_is_reproduced_to_rounding() {
        // Interpolation at 8 points is exact for degree 7.
        let f = |h: f64| {
            let p = 1.0 + h * (0.3 + h * (-0.2 + h * (0.05 + h * 1e-3 * (1.0 + h * h * h))));
            let d = 0.3 + h * (-0.4 + h * (0.15 + h * 1e-3 * (4.0 + 7.0 * h * h * h)));
            (p, d)
        };
        let c = CompiledProfile::compile(-1.0, 2.0, &[], f);
        assert_eq!(c.pieces(), (1, 0));
        for i in 1..100 {
            let h = -1.0 + 3.0 * i as f64 / 100.0;
            let (d, g) = c.eval(h).unwrap();
            let (d0, g0) = f(h);
            assert!((d - d0).abs() < 1e-14 && (g - g0).abs() < 1e-13, "{h}");
        }
    }

    #[test]
    fn a_kink_at_a_break_is_a_knot_and_the_knot_itself_is_the_formulas() {
        // |h − 0.3| + e^h: a kink at 0.3, named as a break.
        let f = |h: f64| ((h - 0.3).abs() + h.exp(), (h - 0.3).signum() + h.exp());
        let c = CompiledProfile::compile(-2.0, 2.0, &[0.3], f);
        let (n, exact) = c.pieces();
        assert_eq!(exact, 0);
        assert!(n < 20, "{n} pieces");
        assert!(c.eval(0.3).is_none() && c.eval(-2.0).is_none() && c.eval(2.0).is_none());
        let mut rng = 12345u64;
        for _ in 0..2000 {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let h = -2.0 + 4.0 * (rng >> 11) as f64 / (1u64 << 53) as f64;
            let Some((d, g)) = c.eval(h) else { continue };
            let (d0, g0) = f(h);
            assert!((d - d0).abs() <= BOUND * d0.abs(), "δ at {h}");
            assert!(
                (g - g0).abs() <= BOUND * g0.abs().max(d0.abs() / SLOPE_SCALE),
                "g at {h}"
            );
        }
    }

    #[test]
    fn an_unnamed_jump_is_left_to_the_formula_in_a_narrow_piece() {
        let f = |h: f64| (if h < 0.123 { 1.0 } else { 2.0 }, 0.0);
        let c = CompiledProfile::compile(0.0, 1.0, &[], f);
        let (n, exact) = c.pieces();
        assert_eq!(exact, 1, "{n} pieces");
        assert!(c.eval(0.123).is_none());
        let (low, _) = c.eval(0.1225).unwrap();
        let (high, _) = c.eval(0.1235).unwrap();
        assert!(
            (low - 1.0).abs() <= BOUND && (high - 2.0).abs() <= 2.0 * BOUND,
            "{low} {high}"
        );
    }
}
