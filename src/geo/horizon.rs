//! The local horizontal at a point, and directions by elevation and azimuth.
//!
//! Exact to round-off: the frame is three orthonormal vectors built from
//! the sphere's radius (or y over the flat ground) and the site frame's z.

use crate::error::FieldError;

/// The local up, north and east at a point of the site's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Horizon {
    /// Unit vector along the sphere's radius (y over the flat ground).
    pub up: [f64; 3],
    /// Unit vector of the frame's z projected onto the horizontal.
    pub north: [f64; 3],
    /// Unit vector east: up × north (x east, y up, z north is
    /// right-handed).
    pub east: [f64; 3],
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    // Beyond 10¹⁵⁴ m the squares overflow: n = ∞ made `up` the zero vector.
    let n = if n.is_finite() {
        n
    } else {
        a[0].hypot(a[1]).hypot(a[2])
    };
    [a[0] / n, a[1] / n, a[2] / n]
}

impl Horizon {
    /// The horizon at `point` over the sphere of `radius` centred at
    /// (0, −radius, 0), or over the flat ground y = 0 (`None`). Refused
    /// where north is undefined: a point on the sphere's axis through the
    /// frame's north (a quarter of the earth away).
    pub fn at(point: [f64; 3], radius: Option<f64>) -> Result<Horizon, FieldError> {
        let up = match radius {
            None => [0.0, 1.0, 0.0],
            Some(r) => {
                let c = [point[0], point[1] + r, point[2]];
                if dot(c, c) == 0.0 {
                    return Err(FieldError::whole("the point is the earth's centre"));
                }
                unit(c)
            }
        };
        let z = [0.0, 0.0, 1.0];
        let k = dot(z, up);
        let n = [z[0] - k * up[0], z[1] - k * up[1], z[2] - k * up[2]];
        if dot(n, n) < 1e-20 {
            return Err(FieldError::whole(
                "north is undefined here: the point lies on the line through the earth's centre along the site's north",
            ));
        }
        let north = unit(n);
        let east = [
            up[1] * north[2] - up[2] * north[1],
            up[2] * north[0] - up[0] * north[2],
            up[0] * north[1] - up[1] * north[0],
        ];
        Ok(Horizon { up, north, east })
    }

    /// The unit direction at `elevation` above the horizontal and `azimuth`
    /// from north toward east (degrees).
    pub fn direction(&self, elevation: f64, azimuth: f64) -> [f64; 3] {
        let (se, ce) = elevation.to_radians().sin_cos();
        let (sa, ca) = azimuth.to_radians().sin_cos();
        std::array::from_fn(|k| ce * (ca * self.north[k] + sa * self.east[k]) + se * self.up[k])
    }

    /// The elevation (degrees) of the direction `v` (any length > 0).
    pub fn elevation(&self, v: [f64; 3]) -> f64 {
        let h = dot(v, self.north).hypot(dot(v, self.east));
        dot(v, self.up).atan2(h).to_degrees()
    }

    /// The azimuth (degrees from north toward east, in [0, 360)) of `v`.
    pub fn azimuth(&self, v: [f64; 3]) -> f64 {
        let a = dot(v, self.east).atan2(dot(v, self.north)).to_degrees();
        if a < 0.0 { a + 360.0 } else { a }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_the_site_the_frame_is_the_axes() {
        for radius in [None, Some(6.371e6)] {
            let h = Horizon::at([0.0, 23.42, 0.0], radius).unwrap();
            assert_eq!(h.up, [0.0, 1.0, 0.0]);
            assert_eq!(h.north, [0.0, 0.0, 1.0]);
            assert_eq!(h.east, [1.0, 0.0, 0.0]);
            let d = h.direction(0.0, 90.0);
            assert!((d[0] - 1.0).abs() < 1e-15 && d[1].abs() < 1e-15 && d[2].abs() < 1e-15);
        }
    }

    #[test]
    fn directions_round_trip_anywhere() {
        let mut rng = crate::math::SplitMix64(3);
        for _ in 0..500 {
            let p = [
                (rng.next_f64() - 0.5) * 2e6,
                rng.next_f64() * 1e4,
                (rng.next_f64() - 0.5) * 2e6,
            ];
            let h = Horizon::at(p, Some(6.371e6)).unwrap();
            // Orthonormal and right-handed.
            for (a, b, want) in [
                (h.up, h.up, 1.0),
                (h.north, h.north, 1.0),
                (h.east, h.east, 1.0),
                (h.up, h.north, 0.0),
                (h.up, h.east, 0.0),
                (h.north, h.east, 0.0),
            ] {
                assert!((dot(a, b) - want).abs() < 1e-14);
            }
            let e = (rng.next_f64() - 0.5) * 170.0;
            let a = rng.next_f64() * 359.0;
            let d = h.direction(e, a);
            assert!((h.elevation(d) - e).abs() < 1e-11, "{e}");
            assert!((h.azimuth(d) - a).abs() < 1e-9, "{a}");
        }
    }

    #[test]
    fn on_the_sphere_far_east_the_horizon_tilts() {
        // 100 km east on a 6371 km sphere: up leans east by 100/6371 rad.
        let r: f64 = 6.371e6;
        let t: f64 = 1e5 / r;
        let p = [r * t.sin(), r * t.cos() - r, 0.0];
        let h = Horizon::at(p, Some(r)).unwrap();
        assert!((h.up[0] - t.sin()).abs() < 1e-15);
        assert_eq!(h.north, [0.0, 0.0, 1.0]);
        // Looking back west, level: the direction is −east.
        let d = h.direction(0.0, 270.0);
        assert!((d[0] + t.cos()).abs() < 1e-12 && (d[1] - t.sin()).abs() < 1e-12);
    }
}
