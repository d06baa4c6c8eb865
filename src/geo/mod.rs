//! Places on the earth (`docs/geo.md`): a site, the local frame below it,
//! geographic points placed in that frame, and angles written in degrees or
//! as degrees, minutes and seconds.
//!
//! # The frame
//!
//! With a [`Site`] (latitude, longitude on WGS 84, height above the sea),
//! the local frame has its origin on the sea-level sphere below the site,
//! **x east, y up, z north**, in metres; the site is (0, height, 0). The
//! earth is the sphere of radius R centred at (0, −R, 0): R is the problem's
//! `earth.radius` if given, else the Gaussian mean radius of curvature of
//! WGS 84 at the site's latitude, √(M·N) ([`Site::gaussian_radius`]).
//!
//! # Placing a point ([`Site::place`])
//!
//! A geographic point (φ, λ, h) is placed by the geodesic from the site on
//! the WGS 84 ellipsoid: GeographicLib's inverse problem (Karney 2013, as the
//! `geographiclib-rs` crate implements it; accurate to about 15 nm) gives its
//! distance s and initial azimuth α; the point goes on the sphere at arc s
//! from the site's foot along azimuth α, raised h along the sphere's normal.
//! What a line of sight from the site depends on, its distance and azimuth,
//! is kept exactly: `tests/geo.rs` checks both against the Python package
//! `geographiclib` to 1 mm and 1e-9° from 1 m to 1,000 km, at latitudes from
//! −89° to 89° and across the antimeridian. (The frame is a sphere: two
//! points far from the site are not their geodesic distance apart.)
//!
//! # Angles ([`Angle`])
//!
//! A number of degrees, or a string of degrees, minutes and seconds:
//! `"-0°02'47\""`, `"212°30′00″"`, `"12d30m5.5s"`, `"-0 2 47"`. The sign
//! applies to the whole angle; minutes and seconds lie in [0, 60).
//!
//! # Lines of sight ([`Horizon`])
//!
//! The local horizontal at a point is the plane normal to the sphere's
//! radius there (y for the flat ground); north is the frame's z projected
//! onto it. An elevation e and azimuth a give the launch direction
//! cos e·(cos a·north + sin a·east) + sin e·up.

mod angle;
mod horizon;
mod site;

pub use angle::{Angle, AngleParseError, format_dms};
pub use horizon::Horizon;
pub use site::{GeoPoint, HEIGHT_RANGE, Point, Site};

use crate::trace::{Earth, EarthSpec};

/// The ground of a file with `earth` and `site` sections: the sphere of
/// `earth.radius`; else, with a site, the sphere of WGS 84's Gaussian mean
/// radius at the site's latitude ([`Site::gaussian_radius`]); else the flat
/// ground. A file with a site is never flat.
pub fn earth_of(earth: Option<EarthSpec>, site: Option<&Site>) -> Earth {
    match (earth, site) {
        (Some(e), _) => Earth::Round { radius: e.radius },
        (None, Some(s)) => Earth::Round {
            radius: s.gaussian_radius(),
        },
        (None, None) => Earth::Flat,
    }
}
