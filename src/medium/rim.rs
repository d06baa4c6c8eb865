//! The rim of a circular hot spot, shared by every kind that has hot spots:
//! w(x, z) = 1 − σ(e·(ρ − R)), ρ = |(x − x_j, z − z_j)| (`docs/model.md`).
//!
//! ρ is computed from components scaled by their magnitude, so dx² + dz²
//! can neither overflow nor underflow, and the cone tip ρ = 0 is handled
//! apart (its horizontal derivative is taken as 0, as the contract says);
//! w is σ(e·(R − ρ)), which has no cancellation near 1.

use crate::math::{Real, sigmoid};

/// The rim weight at offset (dx, dz) from a hot spot's centre: `(w, dw/dρ,
/// ρ̂_x, ρ̂_z)` with ρ̂ the horizontal unit vector away from the centre (zero at
/// the centre, where dw/dρ is also reported as 0).
#[inline]
pub(crate) fn rim_weight<T: Real>(dx: T, dz: T, radius: T, edge: T) -> (T, T, T, T) {
    let zero = T::cst(0.0);
    let big = dx.val().abs().max(dz.val().abs());
    if big == 0.0 || !big.is_finite() {
        let (w, _) = if big == 0.0 {
            sigmoid(edge * radius)
        } else {
            (zero, zero)
        };
        return (w, zero, zero, zero);
    }
    // Divide, not multiply by 1/big: for a subnormal offset (|dx| < 2.2e-308)
    // 1/big overflows to ∞ and ∞/∞ made ρ̂ NaN (found by fuzzing).
    let (sx, sz) = (dx / big, dz / big);
    let unit = (sx * sx + sz * sz).sqrt();
    let rho = unit * big;
    let (w, dw) = sigmoid(edge * (radius - rho));
    (w, -(edge * dw), sx / unit, sz / unit)
}
