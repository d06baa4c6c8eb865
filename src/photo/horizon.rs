//! The apparent sea horizon of stratified air over the round earth, for
//! horizon marks (`docs/photo.md`).
//!
//! # Algorithm
//!
//! In air whose index n depends on the radius r alone, a ray keeps
//! Bouguer's invariant K = n(r)·r·cos e (e its elevation). Launched from
//! the camera at r₀ = R + h₀ with elevation e < 0, it descends until
//! n(r)·r = K; it reaches the sea (r = R) exactly when K < n(r)·r for every
//! r in [R, r₀]. So every ray below e_h meets the sea, and the apparent
//! horizon is
//!
//! ```text
//! cos e_h = m / (n₀ r₀),   m = min over [R, r₀] of n(r)·r,
//! ```
//!
//! the grazing ray when n·r grows with height (ordinary air: the minimum is
//! at the sea), and the ray that grazes the top of a duct below the camera
//! otherwise (the lowest horizon a photo shows there). The range limit
//! (`photo.horizon_range`) is not applied: in stratified air the grazing
//! ray is the horizon at any range.
//!
//! # Accuracy and derivatives
//!
//! With g(h) = n(R + h)(R + h) − R = h + δ(h)(R + h) (δ = n − 1), the
//! formula is evaluated as 1 − cos e_h = ε = (g(h₀) − g(h*))/(R + g(h₀)),
//! e_h = −2 asin √(ε/2): no cancellation of numbers near 1, so e_h is good
//! to ~1e-15 relative. The minimiser h* is found on a grid of 512 heights
//! (uniform and geometric from 1 mm, for thin surface layers) and refined
//! by golden section to 1e-12 of h₀; the value at h* is evaluated in `T`,
//! and by the envelope theorem its derivative with respect to the air's
//! parameters is exact at a minimum (interior or at the sea) without
//! differentiating h*.

use crate::math::Real;

/// Heights of the grid (see the module doc).
const GRID: usize = 256;

/// The apparent horizon's elevation (radians, ≤ 0) seen from `height`
/// metres above a sea of `radius` metres, in air with δ(h) (`delta` in
/// `f64` for the search, `delta_t` in `T` for the value).
pub fn apparent_horizon<T: Real>(
    delta: impl Fn(f64) -> f64,
    delta_t: impl Fn(f64) -> T,
    radius: f64,
    height: f64,
) -> T {
    let g = |h: f64| h + delta(h) * (radius + h);
    let mut hs = Vec::with_capacity(2 * GRID + 1);
    hs.push(0.0);
    for k in 1..=GRID {
        hs.push(height * k as f64 / GRID as f64);
        let geometric = 1e-3 * (height / 1e-3).powf(k as f64 / GRID as f64);
        if geometric < height {
            hs.push(geometric);
        }
    }
    hs.sort_by(f64::total_cmp);
    let values: Vec<f64> = hs.iter().map(|&h| g(h)).collect();
    let k = (0..hs.len())
        .min_by(|&i, &j| values[i].total_cmp(&values[j]))
        .unwrap_or(0);
    let mut h_min = hs[k];
    if k > 0 && k + 1 < hs.len() {
        // Golden section between the grid's neighbours of the minimum.
        let (mut lo, mut hi) = (hs[k - 1], hs[k + 1]);
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        let (mut a, mut b) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
        let (mut ga, mut gb) = (g(a), g(b));
        while hi - lo > 1e-12 * height.max(1e-3) {
            if ga < gb {
                hi = b;
                b = a;
                gb = ga;
                a = hi - phi * (hi - lo);
                ga = g(a);
            } else {
                lo = a;
                a = b;
                ga = gb;
                b = lo + phi * (hi - lo);
                gb = g(b);
            }
        }
        let mid = 0.5 * (lo + hi);
        if g(mid) < values[k] {
            h_min = mid;
        }
    }
    let gt = |h: f64| delta_t(h) * (radius + h) + h;
    let top = gt(height);
    let eps = (top - gt(h_min)) / (top + radius);
    if eps.val() <= 0.0 {
        return T::cst(0.0);
    }
    -((eps * 0.5).sqrt().asin() * 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_air_the_horizon_is_the_geometric_dip() {
        let (r, h) = (6.371e6, 12.0);
        let e: f64 = apparent_horizon(|_| 0.0, |_| 0.0, r, h);
        let exact = -(r / (r + h)).acos();
        assert!((e - exact).abs() < 1e-12 * exact.abs(), "{e} {exact}");
    }

    #[test]
    fn a_uniform_gradient_is_the_dip_of_an_effective_earth() {
        // δ(h) = δ0 − G h: the ray curves with radius 1/G (k = G·R), the
        // dip is that of an earth of radius R/(1 − k) to first order in δ.
        let (r, h, d0, gr) = (6.371e6, 30.0, 2.8e-4, 3.0e-8);
        let e: f64 = apparent_horizon(|y| d0 - gr * y, |y| d0 - gr * y, r, h);
        let k = gr * r;
        let reff = r / (1.0 - k);
        let approx = -(2.0 * h / reff).sqrt();
        assert!((e - approx).abs() < 2e-3 * approx.abs(), "{e} {approx}");
    }

    #[test]
    fn a_duct_below_the_camera_lifts_the_horizon_to_its_top() {
        // n·r falls with height through a strong inversion at 5–8 m: the
        // minimum of g is at the top of the duct, not at the sea.
        let (r, h) = (6.371e6, 20.0);
        let delta = |y: f64| {
            3e-4 - if y < 5.0 {
                0.0
            } else if y < 8.0 {
                1.2e-6 * (y - 5.0)
            } else {
                3.6e-6
            }
        };
        let e: f64 = apparent_horizon(delta, delta, r, h);
        let g = |y: f64| y + delta(y) * (r + y);
        assert!(g(8.0) < g(0.0));
        let exact = -(2.0 * (g(h) - g(8.0)) / (r + g(h))).sqrt();
        assert!((e - exact).abs() < 1e-6 * exact.abs(), "{e} {exact}");
    }
}
