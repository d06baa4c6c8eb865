//! The site, geographic points, and where a point goes in the site's frame
//! (the module doc of [`crate::geo`] states the frame and the accuracy).

use crate::error::FieldError;
use geographiclib_rs::{Geodesic, InverseGeodesic};
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::fmt;

/// Heights a site or geographic point may have (m): from the bottom of the
/// deepest trench to far above any air mirage reaches.
pub const HEIGHT_RANGE: (f64, f64) = (-11_000.0, 100_000.0);

/// Where the local frame stands: latitude and longitude on WGS 84, height
/// above mean sea level.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Site {
    /// Degrees north, in [−90, 90].
    pub latitude: f64,
    /// Degrees east, in [−360, 360].
    pub longitude: f64,
    /// Metres above mean sea level (default 0).
    #[serde(default)]
    pub height: f64,
}

/// A point given by latitude, longitude and height above the sea.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeoPoint {
    /// Degrees north, in [−90, 90].
    pub latitude: f64,
    /// Degrees east, in [−360, 360].
    pub longitude: f64,
    /// Metres above mean sea level (default 0).
    #[serde(default)]
    pub height: f64,
}

/// A point as a file gives it: `[x, y, z]` in the local frame (metres), or
/// a geographic point (needs a site).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Point {
    /// Local coordinates (m).
    Local([f64; 3]),
    /// Latitude, longitude, height.
    Geo(GeoPoint),
}

impl From<[f64; 3]> for Point {
    fn from(v: [f64; 3]) -> Self {
        Point::Local(v)
    }
}

impl<'de> Deserialize<'de> for Point {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Point, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Point;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "a point: [x, y, z] in metres, or {\"latitude\": …, \"longitude\": …, \"height\": …}",
                )
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Point, A::Error> {
                <[f64; 3]>::deserialize(de::value::SeqAccessDeserializer::new(seq))
                    .map(Point::Local)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Point, A::Error> {
                GeoPoint::deserialize(de::value::MapAccessDeserializer::new(map)).map(Point::Geo)
            }
        }
        d.deserialize_any(V)
    }
}

fn check_place(latitude: f64, longitude: f64, height: f64) -> Result<(), FieldError> {
    if !(-90.0..=90.0).contains(&latitude) {
        return Err(FieldError::new(
            "latitude",
            format!("must lie in [-90, 90] degrees, got {latitude}"),
        ));
    }
    if !(-360.0..=360.0).contains(&longitude) {
        return Err(FieldError::new(
            "longitude",
            format!("must lie in [-360, 360] degrees, got {longitude}"),
        ));
    }
    let (lo, hi) = HEIGHT_RANGE;
    if !(lo..=hi).contains(&height) {
        return Err(FieldError::new(
            "height",
            format!("must lie in [{lo}, {hi}] metres above the sea, got {height}"),
        ));
    }
    Ok(())
}

impl GeoPoint {
    /// Checks the ranges: latitude in [−90, 90], longitude in [−360, 360],
    /// height in [`HEIGHT_RANGE`].
    pub fn validate(&self) -> Result<(), FieldError> {
        check_place(self.latitude, self.longitude, self.height)
    }
}

impl Site {
    /// Checks the ranges, as [`GeoPoint::validate`].
    pub fn validate(&self) -> Result<(), FieldError> {
        check_place(self.latitude, self.longitude, self.height)
    }

    /// The Gaussian mean radius of curvature of WGS 84 at the site's
    /// latitude, √(M·N) = a·√(1 − e²) / (1 − e²·sin²φ) (m).
    pub fn gaussian_radius(&self) -> f64 {
        let g = Geodesic::wgs84();
        let (a, f) = (g.equatorial_radius(), g.flattening());
        let e2 = f * (2.0 - f);
        let s = self.latitude.to_radians().sin();
        a * (1.0 - e2).sqrt() / (1.0 - e2 * s * s)
    }

    /// The geodesic distance (m) and initial azimuth (degrees from north
    /// toward east, in (−180, 180]) from the site to `p` on WGS 84.
    pub fn geodesic_to(&self, p: &GeoPoint) -> (f64, f64) {
        let (s12, azi1, _azi2, _a12): (f64, f64, f64, f64) =
            Geodesic::wgs84().inverse(self.latitude, self.longitude, p.latitude, p.longitude);
        (s12, azi1)
    }

    /// `p` in the site's frame over the sphere of `radius` (m) centred at
    /// (0, −radius, 0): at arc [`Site::geodesic_to`]'s distance from the
    /// site's foot along its azimuth, raised `p.height` along the normal.
    /// An infinite `radius` is the flat ground y = 0, the sphere's limit:
    /// at that distance along that azimuth on the plane, raised `p.height`.
    pub fn place(&self, p: &GeoPoint, radius: f64) -> [f64; 3] {
        let (s, azimuth) = self.geodesic_to(p);
        let (sa, ca) = azimuth.to_radians().sin_cos();
        if radius == f64::INFINITY {
            // (R + h)·sin(s/R) and (R + h)·cos(s/R) − R as R → ∞; the
            // sphere's formulas give ∞·0 and ∞ − ∞ = NaN (found by fuzzing).
            return [s * sa, p.height, s * ca];
        }
        let theta = s / radius;
        let (st, ct) = theta.sin_cos();
        let r = radius + p.height;
        [r * st * sa, r * ct - radius, r * st * ca]
    }

    /// The site itself in its frame: (0, height, 0).
    pub fn origin(&self) -> [f64; 3] {
        [0.0, self.height, 0.0]
    }
}

impl Point {
    /// The point in the local frame: `[x, y, z]` as given, or a geographic
    /// point placed from `site` over the sphere of `radius` (infinite: the
    /// flat ground, as [`Site::place`]).
    pub fn resolve(&self, site: Option<&Site>, radius: f64) -> Result<[f64; 3], FieldError> {
        match self {
            Point::Local(v) => Ok(*v),
            Point::Geo(g) => {
                g.validate()?;
                let site = site.ok_or_else(|| {
                    FieldError::whole(
                        "a geographic point (latitude, longitude) needs a `site` at the top of the file: the place the local frame stands on",
                    )
                })?;
                Ok(site.place(g, radius))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gaussian_radius_is_between_the_meridian_and_normal_radii() {
        // At the equator √(M·N) = a·√(1 − e²) = b, the semi-minor axis
        // (6,356,752.314 m); at the poles M = N = a²/b (6,399,593.626 m).
        let r0 = Site {
            latitude: 0.0,
            longitude: 0.0,
            height: 0.0,
        }
        .gaussian_radius();
        assert!((r0 - 6_356_752.314).abs() < 1e-3, "{r0}");
        let r90 = Site {
            latitude: 90.0,
            longitude: 0.0,
            height: 0.0,
        }
        .gaussian_radius();
        assert!((r90 - 6_399_593.626).abs() < 1e-3, "{r90}");
    }

    #[test]
    fn a_point_keeps_its_distance_and_azimuth_on_the_sphere() {
        let site = Site {
            latitude: 43.0,
            longitude: 5.0,
            height: 164.0,
        };
        let r = site.gaussian_radius();
        let p = GeoPoint {
            latitude: 44.2,
            longitude: 7.1,
            height: 3000.0,
        };
        let (s, az) = site.geodesic_to(&p);
        let x = site.place(&p, r);
        // Back on the sphere: the arc from the foot and the bearing.
        let c = [x[0], x[1] + r, x[2]];
        let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        assert!((n - r - 3000.0).abs() < 1e-6);
        let arc = r * (c[0].hypot(c[2])).atan2(c[1]);
        assert!((arc - s).abs() < 1e-6, "{arc} vs {s}");
        let bearing = x[0].atan2(x[2]).to_degrees();
        assert!((bearing - az).abs() < 1e-12, "{bearing} vs {az}");
    }

    #[test]
    fn bad_places_name_their_field() {
        let bad = GeoPoint {
            latitude: 91.0,
            longitude: 0.0,
            height: 0.0,
        };
        assert!(bad.validate().unwrap_err().to_string().contains("latitude"));
        let bad = GeoPoint {
            latitude: 0.0,
            longitude: f64::NAN,
            height: 0.0,
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("longitude")
        );
        let far = Point::Geo(GeoPoint {
            latitude: 1.0,
            longitude: 2.0,
            height: 0.0,
        });
        assert!(
            far.resolve(None, 6.4e6)
                .unwrap_err()
                .to_string()
                .contains("needs a `site`")
        );
    }

    #[test]
    fn points_read_as_arrays_or_places() {
        let a: Point = serde_json::from_str("[1, 2, 3]").unwrap();
        assert_eq!(a, Point::Local([1.0, 2.0, 3.0]));
        let b: Point = serde_json::from_str(r#"{"latitude": 1, "longitude": 2}"#).unwrap();
        assert_eq!(
            b,
            Point::Geo(GeoPoint {
                latitude: 1.0,
                longitude: 2.0,
                height: 0.0
            })
        );
        let e = serde_json::from_str::<Point>(r#"{"latitude": 1, "longitude": 2, "hieght": 3}"#)
            .unwrap_err();
        assert!(e.to_string().contains("hieght"), "{e}");
        assert!(serde_json::from_str::<Point>("[1, 2]").is_err());
    }
}
