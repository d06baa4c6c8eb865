//! What a line of sight over the round earth shows (`docs/geo.md`, "What a
//! trace and a fit report over the round earth"): the apparent and the
//! geometric elevation, the refraction angle between them, the effective
//! refraction coefficient k, whether the target lies below the geometric
//! horizon, and the straight line's clearance above the sea.
//!
//! With o the origin, d the launch direction, t the target and R the
//! sphere's radius (centre c = (0, −R, 0)):
//!
//! - apparent elevation: d's elevation above o's horizontal plane (normal
//!   to o − c); geometric elevation: that of t − o;
//! - refraction ρ = apparent − geometric; k = 2·R·ρ / s, with s = R·∠(o − c,
//!   t − c) the arc between the two feet (the circular-arc model of a ray
//!   of constant curvature k/R, exact for small angles: a ray of curvature
//!   κ meets a target at arc s when launched κ·s/2 above the chord);
//! - the geometric horizon's elevation −acos(R / (R + h)), h the origin's
//!   height; the target lies below it when its geometric elevation is lower;
//! - clearance: the lowest height above the sphere of the segment o → t
//!   (negative: the sea hides the target from the straight line).
//!
//! Everything is closed-form in f64 on the pair's points: exact to round-off
//! (atan2 forms, no acos of numbers near 1 for the angles).

use crate::geo::Horizon;
use crate::pair::PointPair;
use crate::trace::Earth;
use serde::Serialize;

/// Arcseconds per radian.
pub const ARCSEC_PER_RADIAN: f64 = 648_000.0 / std::f64::consts::PI;

/// One pair's line of sight over the round earth.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sightline {
    /// The launch direction's elevation above the origin's horizontal (°).
    pub apparent_elevation: f64,
    /// The straight line's elevation to the target (°).
    pub geometric_elevation: f64,
    /// Apparent − geometric (°).
    pub refraction: f64,
    /// The same in arcseconds.
    pub refraction_arcsec: f64,
    /// The effective refraction coefficient along the line, 2·R·ρ / s.
    pub k: f64,
    /// Arc distance between the origin's and the target's feet (m).
    pub arc_distance: f64,
    /// The geometric horizon's elevation at the origin (°).
    pub horizon_elevation: f64,
    /// The target lies below the geometric horizon.
    pub below_horizon: bool,
    /// The straight line's lowest height above the sphere (m).
    pub clearance: f64,
    /// The traced ray's miss along the target's vertical, seen from the
    /// origin (″, positive: the ray passes above the target).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub miss_up_arcsec: Option<f64>,
    /// The refraction the air gives a ray that meets the target (″):
    /// `refraction_arcsec − miss_up_arcsec`, to first order in the miss.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub air_refraction_arcsec: Option<f64>,
    /// The air's own k along the line: 2·R·(air refraction) / s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub air_k: Option<f64>,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

impl Sightline {
    /// The line of sight of `pair` over `earth`; `None` over the flat
    /// ground (no horizon, no k) or where the origin's horizon is undefined.
    pub fn of(pair: &PointPair, earth: Earth) -> Option<Sightline> {
        let Earth::Round { radius } = earth else {
            return None;
        };
        let (o, t) = (pair.origin, pair.target);
        let h = Horizon::at(o, Some(radius)).ok()?;
        let d = sub(pair.through, o);
        let to = sub(t, o);
        let apparent = h.elevation(d);
        let geometric = h.elevation(to);
        let refraction = apparent - geometric;
        let c = [0.0, -radius, 0.0];
        let (oc, tc) = (sub(o, c), sub(t, c));
        let angle = norm(cross(oc, tc)).atan2(dot(oc, tc));
        let arc = radius * angle;
        let height = norm(oc) - radius;
        // −acos(R/(R+h)) = −atan(√(h(2R+h))/R), without acos near 1.
        let horizon = if height > 0.0 {
            -(height * (2.0 * radius + height))
                .sqrt()
                .atan2(radius)
                .to_degrees()
        } else {
            0.0
        };
        // The segment's point nearest the centre.
        let len2 = dot(to, to);
        let u = if len2 > 0.0 {
            (-dot(oc, to) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let nearest = [oc[0] + u * to[0], oc[1] + u * to[1], oc[2] + u * to[2]];
        let clearance = norm(nearest) - radius;
        let k = if arc > 0.0 {
            2.0 * radius * refraction.to_radians() / arc
        } else {
            f64::NAN
        };
        Some(Sightline {
            apparent_elevation: apparent,
            geometric_elevation: geometric,
            refraction,
            refraction_arcsec: refraction * 3600.0,
            k,
            arc_distance: arc,
            horizon_elevation: horizon,
            below_horizon: geometric < horizon,
            clearance,
            miss_up_arcsec: None,
            air_refraction_arcsec: None,
            air_k: None,
        })
    }

    /// The line of sight of `pair` whose ray ended at `endpoint`: with the
    /// miss and the air's own refraction.
    pub fn traced(pair: &PointPair, earth: Earth, endpoint: [f64; 3]) -> Option<Sightline> {
        let mut l = Sightline::of(pair, earth)?;
        let Earth::Round { radius } = earth else {
            return None;
        };
        let t = pair.target;
        let up = Horizon::at(t, Some(radius)).ok()?.up;
        let range = norm(sub(t, pair.origin));
        if range > 0.0 && endpoint.iter().all(|v| v.is_finite()) {
            let miss = dot(sub(endpoint, t), up) / range * ARCSEC_PER_RADIAN;
            l.miss_up_arcsec = Some(miss);
            let air = l.refraction_arcsec - miss;
            l.air_refraction_arcsec = Some(air);
            if l.arc_distance > 0.0 {
                l.air_k = Some(2.0 * radius * air / ARCSEC_PER_RADIAN / l.arc_distance);
            }
        }
        Some(l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pair from `h0` up, launched `e` radians above the horizontal,
    /// toward a target at arc `s` and height `h1`, on a sphere of `r`.
    fn pair(r: f64, h0: f64, s: f64, h1: f64, e: f64) -> PointPair {
        let a = s / r;
        PointPair {
            origin: [0.0, h0, 0.0],
            through: [0.0, h0 + e.tan() * 1000.0, 1000.0],
            target: [0.0, (r + h1) * a.cos() - r, (r + h1) * a.sin()],
            weight: 1.0,
            wavelength: None,
        }
    }

    #[test]
    fn a_ray_of_curvature_k_over_r_gives_back_k() {
        // A circular ray of curvature κ = k/R from the origin meets the
        // target at arc s: launched at the chord's elevation plus κ·s/2 to
        // first order. Give that launch angle and read k back.
        let r = 6_371_000.0;
        for (k, s, h0, h1) in [(0.13, 20_000.0, 30.0, 10.0), (0.2, 37_642.0, 23.42, 56.08)] {
            let straight = pair(r, h0, s, h1, 0.0);
            let geo = Sightline::of(&straight, Earth::Round { radius: r }).unwrap();
            let e = geo.geometric_elevation.to_radians() + k * s / (2.0 * r);
            let p = pair(r, h0, s, h1, e);
            let l = Sightline::of(&p, Earth::Round { radius: r }).unwrap();
            assert!((l.k - k).abs() < 1e-9, "{k}: {}", l.k);
            assert!((l.arc_distance - s).abs() < 1e-6);
        }
    }

    #[test]
    fn the_horizon_and_the_clearance_are_the_sphere_s() {
        let r = 6_371_000.0;
        let h0: f64 = 164.0;
        // The geometric horizon: 45.7 km from 164 m, at −0.411°.
        let l = Sightline::of(
            &pair(r, h0, 250_000.0, 3000.0, 0.0),
            Earth::Round { radius: r },
        )
        .unwrap();
        let want = -(r / (r + h0)).acos().to_degrees();
        assert!((l.horizon_elevation - want).abs() < 1e-9);
        // A mountain 250 km away, 3000 m high: below the straight line's
        // reach? Its foot's hidden height (250 km − 45.7 km)²/2R ≈ 3.28 km
        // exceeds 3 km: hidden, the segment dips below the sea.
        assert!(l.below_horizon && l.clearance < 0.0, "{l:?}");
        // A target just beyond, high enough, is seen: positive clearance.
        let l = Sightline::of(
            &pair(r, h0, 20_000.0, 100.0, 0.0),
            Earth::Round { radius: r },
        )
        .unwrap();
        assert!(!l.below_horizon && l.clearance > 0.0);
        assert!(Sightline::of(&pair(r, h0, 1.0, 1.0, 0.0), Earth::Flat).is_none());
    }
}
