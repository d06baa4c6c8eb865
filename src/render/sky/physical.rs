//! A physically based sky: single scattering by air molecules (Rayleigh) and
//! aerosols (Mie), absorption by ozone, sunlight attenuated by Beer's law, the
//! sun's disc, and stars at night.
//!
//! The constituents and their constants are in [`atmosphere`](super::atmosphere).
//! Two tables make it fast, and the same two tables are what a GPU needs:
//!
//! - [`TransmittanceTable`]: the optical depth from any altitude to the top of
//!   the atmosphere along any direction that misses the ground, in Bruneton's
//!   parametrisation (exact at the horizon, where mirages look). Its worst
//!   relative error in transmittance against direct integration is checked in
//!   the tests: below 1e-3 relative from altitudes under 10 km, where the
//!   camera and most of the scattering air are, and 5e-3 at worst (rays that
//!   graze the ground from 50–60 km up), wherever the transmittance is above
//!   1e-3.
//! - the sky-view table of [`PhysicalSky`]: single-scattered radiance seen
//!   from the camera, over elevation (square-root spacing, so that the first
//!   row above the horizon is 0.0014° up) and azimuth from the sun (square-root
//!   spacing again, dense near the sun's forward-scattering peak). Checked
//!   against direct integration in the tests (below 1 % relative).
//!
//! Directions below the horizon see the horizon's radiance: in a mirage
//! scene, a camera ray that ends pointing down has met neither the ground nor
//! an object within its range, and what lies there is haze.
//!
//! ```json
//! "sky": { "type": "physical", "mie_scale": 1.0, "ozone": true, "stars": true }
//! ```
//!
//! | field | meaning | default |
//! | --- | --- | --- |
//! | `rayleigh_scale` | multiplies the molecular density | 1 |
//! | `mie_scale` | multiplies the aerosol density (haze) | 1 |
//! | `ozone` | ozone absorption on/off | true |
//! | `sun_disc` | draw the sun's disc | true |
//! | `stars` | stars at night | true |
//! | `star_brightness` | multiplies the stars' flux | 1 |

use super::atmosphere::{Atmosphere, SUN_ANGULAR_RADIUS, cornette_shanks_phase, rayleigh_phase};
use super::stars::{STAR_FADE, STAR_FLUX, star_radiance, star_radius};
use super::transmittance::TransmittanceTable;
use super::view_table::{SkyViewTable, VIEW_SAMPLES, local_direction};
use super::{Sky, SunDisc};
use crate::scene::description::Sun;
use glam::DVec3;
use std::f64::consts::PI;

/// What the `sky` section of type `physical` sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhysicalSkySettings {
    /// Multiplies the molecular density.
    pub rayleigh_scale: f64,
    /// Multiplies the aerosol density.
    pub mie_scale: f64,
    /// Ozone absorption on/off.
    pub ozone: bool,
    /// Draw the sun's disc.
    pub sun_disc: bool,
    /// Stars at night.
    pub stars: bool,
    /// Multiplies the stars' flux.
    pub star_brightness: f64,
}

impl Default for PhysicalSkySettings {
    fn default() -> Self {
        PhysicalSkySettings {
            rayleigh_scale: 1.0,
            mie_scale: 1.0,
            ozone: true,
            sun_disc: true,
            stars: true,
            star_brightness: 1.0,
        }
    }
}

/// The physically based sky seen from one camera position.
#[derive(Clone, Debug)]
pub struct PhysicalSky {
    settings: PhysicalSkySettings,
    table: TransmittanceTable,
    /// Unit vector toward the sun.
    sun_direction: DVec3,
    /// The sun's irradiance above the atmosphere (linear RGB).
    sun_irradiance: [f64; 3],
    /// Radius of the observer (metres from the planet's centre).
    observer_radius: f64,
    /// Single-scattered radiance over (elevation row, azimuth column).
    view: SkyViewTable,
    ambient: [f64; 3],
    sun_transmittance: [f64; 3],
    /// Angular radius at which stars are drawn (radians): about a pixel, so
    /// that point-like stars are not missed between pixel centres.
    star_radius: f64,
}

impl PhysicalSky {
    /// The sky of `settings` lit by `sun`, seen from `observer_altitude`
    /// metres above the ground by a camera whose pixels subtend
    /// `pixel_angle` radians.
    pub fn new(
        settings: &PhysicalSkySettings,
        sun: &Sun,
        observer_altitude: f64,
        pixel_angle: f64,
    ) -> PhysicalSky {
        let atmosphere =
            Atmosphere::earth(settings.rayleigh_scale, settings.mie_scale, settings.ozone);
        let table = TransmittanceTable::new(&atmosphere);
        let observer_radius = atmosphere.bottom_radius + observer_altitude.clamp(0.0, 50_000.0);
        let mut sky = PhysicalSky {
            settings: *settings,
            table,
            sun_direction: sun.direction.normalize(),
            sun_irradiance: sun.irradiance,
            observer_radius,
            view: SkyViewTable::default(),
            ambient: [0.0; 3],
            sun_transmittance: [0.0; 3],
            star_radius: star_radius(pixel_angle),
        };
        sky.sun_transmittance = sky
            .table
            .transmittance(observer_radius, sky.sun_direction.y);
        let view = SkyViewTable::build(|dir| sky.integrate(dir, VIEW_SAMPLES, false));
        sky.view = view;
        sky.ambient = sky.view.hemisphere_mean();
        sky
    }

    /// The transmittance table.
    pub fn transmittance_table(&self) -> &TransmittanceTable {
        &self.table
    }

    /// The sun's elevation (radians).
    fn sun_elevation(&self) -> f64 {
        self.sun_direction.y.clamp(-1.0, 1.0).asin()
    }

    /// Elevation (radians, ≥ 0) and azimuth from the sun (radians, [0, π]) of
    /// a direction.
    fn angles(&self, dir: DVec3) -> (f64, f64) {
        let d = dir.normalize();
        let elevation = d.y.clamp(0.0, 1.0).asin();
        let horiz = DVec3::new(d.x, 0.0, d.z);
        let sun_h = DVec3::new(self.sun_direction.x, 0.0, self.sun_direction.z);
        let azimuth = if horiz.length_squared() < 1e-30 || sun_h.length_squared() < 1e-30 {
            0.0
        } else {
            horiz
                .normalize()
                .dot(sun_h.normalize())
                .clamp(-1.0, 1.0)
                .acos()
        };
        (elevation, azimuth)
    }

    /// The sun in the same frame.
    fn local_sun(&self) -> DVec3 {
        let e = self.sun_elevation();
        DVec3::new(e.cos(), e.sin(), 0.0)
    }

    /// Single-scattered radiance along a view direction given in the sun's
    /// frame, by integration over `samples` points spaced quadratically
    /// (dense near the observer, where the air is dense). With `exact`, the
    /// transmittances come from direct integration instead of the table: the
    /// reference the table-based sky is checked against.
    fn integrate(&self, view: DVec3, samples: usize, exact: bool) -> [f64; 3] {
        let a = self.table.atmosphere();
        let sun = self.local_sun();
        let r0 = self.observer_radius;
        let origin = DVec3::new(0.0, r0, 0.0);
        let mu0 = view.y;
        let t_max = a.distance_to_top(r0, mu0);
        let nu = view.dot(sun);
        let phase_r = rayleigh_phase(nu);
        let phase_m = cornette_shanks_phase(nu, a.mie_g);
        let depth_to_top = |r: f64, mu: f64| -> [f64; 3] {
            if exact {
                a.optical_depth(r, mu, 4000)
            } else {
                self.table.optical_depth(r, mu)
            }
        };
        let depth0 = depth_to_top(r0, mu0);
        let mut sum = [0.0; 3];
        for i in 0..samples {
            let s = (i as f64 + 0.5) / samples as f64;
            let t = t_max * s * s;
            let dt = t_max * 2.0 * s / samples as f64;
            let p = origin + view * t;
            let r = p.length();
            let up = p / r;
            let h = r - a.bottom_radius;
            let mu_sun = up.dot(sun);
            if a.hits_ground(r, mu_sun) {
                continue;
            }
            let depth_sun = depth_to_top(r, mu_sun);
            // The optical depth from the observer to the sample is the
            // difference of the depths to the top along the same line.
            let depth_p = depth_to_top(r, up.dot(view));
            let [rho_r, rho_m, _] = a.densities(h);
            for c in 0..3 {
                let tau = (depth0[c] - depth_p[c]).max(0.0) + depth_sun[c];
                let scatter =
                    a.rayleigh_scattering[c] * rho_r * phase_r + a.mie_scattering * rho_m * phase_m;
                sum[c] += (-tau).exp() * scatter * dt;
            }
        }
        [0, 1, 2].map(|c| sum[c] * self.sun_irradiance[c])
    }

    /// Single-scattered radiance along `dir` by direct integration (slow: the
    /// reference the tables are checked against).
    pub fn single_scattering_reference(&self, dir: DVec3) -> [f64; 3] {
        let (e, az) = self.angles(dir);
        self.integrate(local_direction(e, az), 2000, true)
    }

    /// The sky-view table's rows and columns and its values (row-major,
    /// linear RGB), for a GPU texture; rows are at elevation (π/2)·(i/(rows−1))²
    /// and columns at azimuth from the sun π·(j/(columns−1))².
    pub fn view_table(&self) -> (usize, usize, &[[f64; 3]]) {
        self.view.parts()
    }

    /// Whether stars are drawn, their flux scale ([`STAR_FLUX`] × the
    /// brightness setting) and the sun's mean irradiance above the
    /// atmosphere (what the stars' flux and their fade are relative to).
    pub fn star_light(&self) -> (bool, f64, f64) {
        let e = (self.sun_irradiance[0] + self.sun_irradiance[1] + self.sun_irradiance[2]) / 3.0;
        (
            self.settings.stars && self.settings.star_brightness > 0.0,
            STAR_FLUX * self.settings.star_brightness,
            e,
        )
    }
}

impl Sky for PhysicalSky {
    fn radiance(&self, dir: DVec3) -> [f64; 3] {
        let mut l = self.diffuse(dir);
        if let Some(disc) = self.sun_disc() {
            let d = dir.normalize();
            if d.dot(disc.direction) >= disc.angular_radius.cos() {
                for (c, v) in l.iter_mut().enumerate() {
                    *v += disc.radiance[c];
                }
            }
        }
        if self.settings.stars && self.settings.star_brightness > 0.0 {
            let e =
                (self.sun_irradiance[0] + self.sun_irradiance[1] + self.sun_irradiance[2]) / 3.0;
            let sky = (l[0] + l[1] + l[2]) / 3.0;
            let fade = if e > 0.0 {
                (-sky / (STAR_FADE * e)).exp()
            } else {
                1.0
            };
            if fade > 1e-6 {
                let s = star_radiance(dir, self.star_radius, self.settings.star_brightness, e);
                for c in 0..3 {
                    l[c] += s[c] * fade;
                }
            }
        }
        l
    }

    fn ambient(&self) -> [f64; 3] {
        self.ambient
    }

    fn diffuse(&self, dir: DVec3) -> [f64; 3] {
        let (e, az) = self.angles(dir);
        self.view.lookup(e, az)
    }

    fn sun_transmittance(&self) -> [f64; 3] {
        self.sun_transmittance
    }

    fn sun_disc(&self) -> Option<SunDisc> {
        if !self.settings.sun_disc {
            return None;
        }
        // The disc is seen through the air along the camera's line of sight
        // to it: the sun's transmittance at the observer (zero once it has
        // set below the geometric horizon).
        let solid = PI * SUN_ANGULAR_RADIUS * SUN_ANGULAR_RADIUS;
        let t = self.sun_transmittance;
        Some(SunDisc {
            direction: self.sun_direction,
            angular_radius: SUN_ANGULAR_RADIUS,
            radiance: [0, 1, 2].map(|c| self.sun_irradiance[c] * t[c] / solid),
        })
    }
}
