//! The dispatch of [`SkyModel`]: building the model a scene names, and
//! forwarding each [`Sky`] call to it (static dispatch by `match`).

use super::gradient::{DEFAULT_HORIZON, DEFAULT_ZENITH, GradientSky};
use super::physical::{PhysicalSky, PhysicalSkySettings};
use super::{Sky, SkyModel, SunDisc};
use crate::scene::description::{SkySpec, Sun};
use glam::DVec3;

impl SkyModel {
    /// The model a scene's `sky` section describes, lit by `sun` and seen
    /// from `observer_altitude` metres by a camera whose pixels subtend
    /// `pixel_angle` radians.
    pub fn from_spec(
        spec: &SkySpec,
        sun: &Sun,
        observer_altitude: f64,
        pixel_angle: f64,
    ) -> SkyModel {
        match spec {
            SkySpec::Gradient { zenith, horizon } => SkyModel::Gradient(GradientSky {
                zenith: zenith.unwrap_or(DEFAULT_ZENITH),
                horizon: horizon.unwrap_or(DEFAULT_HORIZON),
            }),
            SkySpec::Physical {
                rayleigh_scale,
                mie_scale,
                ozone,
                sun_disc,
                stars,
                star_brightness,
            } => {
                let d = PhysicalSkySettings::default();
                let settings = PhysicalSkySettings {
                    rayleigh_scale: rayleigh_scale.unwrap_or(d.rayleigh_scale),
                    mie_scale: mie_scale.unwrap_or(d.mie_scale),
                    ozone: ozone.unwrap_or(d.ozone),
                    sun_disc: sun_disc.unwrap_or(d.sun_disc),
                    stars: stars.unwrap_or(d.stars),
                    star_brightness: star_brightness.unwrap_or(d.star_brightness),
                };
                SkyModel::Physical(Box::new(PhysicalSky::new(
                    &settings,
                    sun,
                    observer_altitude,
                    pixel_angle,
                )))
            }
        }
    }
}

impl Sky for SkyModel {
    #[inline]
    fn radiance(&self, dir: DVec3) -> [f64; 3] {
        match self {
            SkyModel::Gradient(g) => g.radiance(dir),
            SkyModel::Physical(p) => p.radiance(dir),
        }
    }
    fn ambient(&self) -> [f64; 3] {
        match self {
            SkyModel::Gradient(g) => g.ambient(),
            SkyModel::Physical(p) => p.ambient(),
        }
    }
    fn diffuse(&self, dir: DVec3) -> [f64; 3] {
        match self {
            SkyModel::Gradient(g) => g.diffuse(dir),
            SkyModel::Physical(p) => p.diffuse(dir),
        }
    }
    fn sun_transmittance(&self) -> [f64; 3] {
        match self {
            SkyModel::Gradient(g) => g.sun_transmittance(),
            SkyModel::Physical(p) => p.sun_transmittance(),
        }
    }
    fn sun_disc(&self) -> Option<SunDisc> {
        match self {
            SkyModel::Gradient(g) => g.sun_disc(),
            SkyModel::Physical(p) => p.sun_disc(),
        }
    }
}
