//! The ground under the air: the flat plane y = 0, or the round earth, a
//! sphere of radius R centred at (0, −R, 0) (`docs/air.md`, "The round
//! earth"). Its observer stands where the flat ground's does: the sphere
//! touches the plane y = 0 at the origin.
//!
//! Over the round earth the height of a point p is h = |p − c| − R, and every
//! medium takes h where it took y ([`OnEarth`]): δ(p) = δ_flat(x, h(p), z),
//! so hot spots keep their (x, z), and the gradient follows by the chain rule,
//! ∇δ = (∂δ/∂x, 0, ∂δ/∂z) + ∂δ/∂h · ∇h with ∇h = (p − c)/|p − c|, the local
//! vertical. The geometry is exact (no earth-flattening approximation).
//!
//! Numerics: h is computed as (x² + z² + y(2R + y)) / (|p − c| + R), which
//! has no cancellation between |p − c| ≈ 6.4·10⁶ m and R (the plain
//! difference loses 10⁻⁹ m of every height to rounding), and is exact on the
//! plane's scale: for |p| ≪ R it is y + (x² + z²)/2R to rounding. Everything
//! is generic over [`Real`], so dual numbers carry exact derivatives through
//! the geometry too.

use crate::error::FieldError;
use crate::math::{Real, V3};
use crate::medium::IndexField;
use serde::{Deserialize, Serialize};

/// The smallest earth radius a file may give (m): below it, a scene a few
/// hundred metres wide would already wrap around the sphere.
pub const MIN_RADIUS: f64 = 1000.0;

/// The largest radius of a round earth (m): 10¹⁵ m, 10⁸ earths, beyond which
/// the ground is flat to any precision a scene has. Heights take y·(2R + y),
/// which overflowed to ∞ for a radius of 6·10³⁰³ m (found by fuzzing).
pub const MAX_RADIUS: f64 = 1.0e15;

/// The mean radius of the earth (m), the default of `mirage refraction`.
pub const EARTH_RADIUS: f64 = 6_371_000.0;

/// The `earth` section of a problem or scene file: `{"radius": R}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EarthSpec {
    /// The sphere's radius (m), from [`MIN_RADIUS`] to [`MAX_RADIUS`].
    pub radius: f64,
}

impl EarthSpec {
    /// Checks the radius: a finite number of [`MIN_RADIUS`] to [`MAX_RADIUS`] metres.
    pub fn validate(&self) -> Result<(), FieldError> {
        let r = self.radius;
        if !r.is_finite() || r <= 0.0 {
            return Err(FieldError::new(
                "radius",
                format!("must be a positive number of metres, got {r}"),
            ));
        }
        if r < MIN_RADIUS {
            return Err(FieldError::new(
                "radius",
                format!(
                    "must be at least {MIN_RADIUS} m (the earth's is 6371000), got {r}: below a kilometre the ground wraps around within the scene"
                ),
            ));
        }
        if r > MAX_RADIUS {
            return Err(FieldError::new(
                "radius",
                format!(
                    "must be at most {MAX_RADIUS:e} m (the earth's is 6371000), got {r}: for a flatter ground leave out `earth`"
                ),
            ));
        }
        Ok(())
    }
}

/// The shape of the ground.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Earth {
    /// The plane y = 0, heights are y.
    #[default]
    Flat,
    /// The sphere of this radius (m) centred at (0, −radius, 0).
    Round {
        /// Radius (m).
        radius: f64,
    },
}

impl From<Option<EarthSpec>> for Earth {
    fn from(spec: Option<EarthSpec>) -> Self {
        match spec {
            None => Earth::Flat,
            Some(EarthSpec { radius }) => Earth::Round { radius },
        }
    }
}

impl Earth {
    /// The file form: `None` for the flat ground.
    pub fn spec(self) -> Option<EarthSpec> {
        match self {
            Earth::Flat => None,
            Earth::Round { radius } => Some(EarthSpec { radius }),
        }
    }

    /// The sphere's radius (m); `None` for the flat ground.
    pub fn radius(self) -> Option<f64> {
        match self {
            Earth::Round { radius } => Some(radius),
            Earth::Flat => None,
        }
    }

    /// Whether the ground is the plane y = 0.
    pub fn is_flat(self) -> bool {
        matches!(self, Earth::Flat)
    }

    /// The height of `p` above the ground (m).
    #[inline]
    pub fn height<T: Real>(self, p: V3<T>) -> T {
        match self {
            Earth::Flat => p.y,
            Earth::Round { radius } => round_height(p, radius).0,
        }
    }

    /// The height of `p` and the local vertical there (∇h, a unit vector).
    #[inline]
    pub fn height_and_up<T: Real>(self, p: V3<T>) -> (T, V3<T>) {
        match self {
            Earth::Flat => (p.y, V3::new(T::cst(0.0), T::cst(1.0), T::cst(0.0))),
            Earth::Round { radius } => round_height(p, radius),
        }
    }

    /// The local vertical at `p` (unit).
    #[inline]
    pub fn up(self, p: V3) -> V3 {
        self.height_and_up(p).1
    }

    /// The unit normal of a pair's target plane: the horizontal direction
    /// from `origin` to `target` at the target (perpendicular to the local
    /// vertical there), so that the plane holds the target and its vertical.
    /// `None` when the target is straight above or below the origin.
    pub fn plane_normal(self, origin: V3, target: V3) -> Option<V3> {
        let d = target - origin;
        let up = self.up(target);
        let horizontal = d - up * d.dot(up);
        let n = horizontal.norm();
        // Relative to the separation: a target within 1e-12 of the vertical
        // has no horizontal direction to speak of.
        (n > 1e-12 * d.norm() && n.is_finite()).then(|| horizontal * (1.0 / n))
    }

    /// The point of the ground below (or above) `p`, along its vertical.
    pub fn foot(self, p: V3) -> V3 {
        let (h, up) = self.height_and_up(p);
        p - up * h
    }
}

/// (h, ∇h) over the sphere of radius `r` centred at (0, −r, 0).
#[inline]
fn round_height<T: Real>(p: V3<T>, r: f64) -> (T, V3<T>) {
    // q = p − c, |q|² − r² = x² + z² + y(2r + y), without cancellation.
    let qy = p.y + r;
    let q_norm = (p.x * p.x + qy * qy + p.z * p.z).sqrt();
    let h = (p.x * p.x + p.z * p.z + p.y * (p.y + 2.0 * r)) / (q_norm + r);
    let inv = q_norm.recip();
    (h, V3::new(p.x * inv, qy * inv, p.z * inv))
}

/// A medium over the round earth: δ at p is the medium's δ at (x, h(p), z),
/// its gradient by the chain rule (see the module documentation). The
/// tracers pass it heights and vertical velocities where the medium asks for
/// them ([`IndexField::ceiling`], [`IndexField::step_limit`]).
#[derive(Clone, Copy, Debug)]
pub struct OnEarth<'a, F: ?Sized> {
    /// The medium, as on the flat ground.
    pub field: &'a F,
    /// The sphere's radius (m).
    pub radius: f64,
}

impl<T: Real, F: IndexField<T> + ?Sized> IndexField<T> for OnEarth<'_, F> {
    #[inline]
    fn delta_gradient(&self, p: V3<T>) -> (T, V3<T>) {
        let (h, up) = round_height(p, self.radius);
        let (d, g) = self.field.delta_gradient(V3::new(p.x, h, p.z));
        (d, V3::new(g.x + g.y * up.x, g.y * up.y, g.z + g.y * up.z))
    }

    /// Never: the vertical turns with the position, so even a medium that
    /// depends on the height alone has a horizontal gradient here.
    fn is_stratified(&self) -> bool {
        false
    }

    fn ceiling(&self) -> f64 {
        self.field.ceiling()
    }

    fn step_limit(&self, h: f64, vh: f64) -> f64 {
        self.field.step_limit(h, vh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heights_over_the_sphere_are_exact_and_stable() {
        let r = 6_371_000.0;
        let earth = Earth::Round { radius: r };
        // A point of the tangent plane y = 0 at distance d lies √(r² + d²) − r
        // above the sphere, computed here in a form without cancellation.
        for d in [0.0, 1.0, 100.0, 8000.0, 12_000.0, 1e5] {
            let drop = d * d / (r + (r * r + d * d).sqrt());
            for y in [0.0, 1e-6, 2.0, -3.0, 1000.0] {
                let p = V3::new(0.6 * d, y, 0.8 * d);
                let exact = ((y + r).hypot(d) - r).max(f64::MIN);
                let h = earth.height(p);
                // Closed form for y = 0: the drop itself.
                if y == 0.0 {
                    assert!(
                        (h - drop).abs() <= 1e-12 * drop.max(1.0),
                        "{d}: {h} vs {drop}"
                    );
                }
                // |q| − r suffers rounding of r·ε ≈ 7e-10 m; h must be within it.
                assert!((h - exact).abs() < 2e-9, "{d}, {y}: {h} vs {exact}");
            }
        }
        // The origin is on the ground, its vertical is y.
        assert_eq!(earth.height(V3::ZERO), 0.0);
        assert_eq!(earth.up(V3::ZERO), V3::new(0.0, 1.0, 0.0));
        // Straight up: h = y exactly.
        assert_eq!(earth.height(V3::new(0.0, 12.5, 0.0)), 12.5);
    }

    #[test]
    fn the_flat_ground_is_the_plane() {
        let p = V3::new(3.0, -2.0, 7.0);
        assert_eq!(Earth::Flat.height(p), -2.0);
        assert_eq!(Earth::Flat.up(p), V3::new(0.0, 1.0, 0.0));
        let n = Earth::Flat
            .plane_normal(V3::ZERO, V3::new(3.0, 5.0, 4.0))
            .unwrap();
        assert!((n - V3::new(0.6, 0.0, 0.8)).norm() < 1e-15, "{n:?}");
        assert!(
            Earth::Flat
                .plane_normal(V3::ZERO, V3::new(0.0, 5.0, 0.0))
                .is_none()
        );
    }

    #[test]
    fn a_target_plane_holds_the_local_vertical() {
        let earth = Earth::Round {
            radius: 6_371_000.0,
        };
        let target = V3::new(3000.0, 4.0, 8000.0);
        let n = earth.plane_normal(V3::new(0.0, 2.0, 0.0), target).unwrap();
        assert!(n.dot(earth.up(target)).abs() < 1e-15);
        assert!((n.norm() - 1.0).abs() < 1e-15);
        // It faces away from the observer, nearly along (x, z).
        assert!(n.dot(V3::new(3000.0, 0.0, 8000.0).normalized()) > 0.999_999);
    }

    #[test]
    fn the_gradient_over_the_sphere_is_the_chain_rule() {
        // δ = a·h + b·x: its gradient over the sphere is a·∇h + (b, 0, 0).
        struct Linear;
        impl IndexField<f64> for Linear {
            fn delta_gradient(&self, p: V3) -> (f64, V3) {
                (2e-6 * p.y + 1e-8 * p.x, V3::new(1e-8, 2e-6, 0.0))
            }
        }
        let radius = 10_000.0;
        let f = OnEarth {
            field: &Linear,
            radius,
        };
        let p = V3::new(900.0, 30.0, -400.0);
        let (_, g) = f.delta_gradient(p);
        let e = 1e-3;
        for (k, unit) in [
            V3::new(1.0, 0.0, 0.0),
            V3::new(0.0, 1.0, 0.0),
            V3::new(0.0, 0.0, 1.0),
        ]
        .into_iter()
        .enumerate()
        {
            let fd = (f.delta(p + unit * e) - f.delta(p - unit * e)) / (2.0 * e);
            let got = [g.x, g.y, g.z][k];
            assert!((got - fd).abs() < 1e-15, "component {k}: {got:e} vs {fd:e}");
        }
    }

    #[test]
    fn radii_below_a_kilometre_or_not_finite_are_refused() {
        for r in [0.0, -5.0, 999.0, f64::NAN, f64::INFINITY] {
            assert!(EarthSpec { radius: r }.validate().is_err(), "{r}");
        }
        assert!(EarthSpec { radius: 1000.0 }.validate().is_ok());
        assert!(EarthSpec { radius: 1e8 }.validate().is_ok());
    }
}
