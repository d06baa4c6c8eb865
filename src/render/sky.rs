//! What a ray sees when it hits nothing: the sky, behind one interface, with
//! two models: a cheap gradient and the physically based
//! [`PhysicalSky`].

use super::atmosphere::{PhysicalSky, PhysicalSkySettings};
use crate::scene::description::{SkySpec, Sun};
use glam::DVec3;

/// Radiance arriving from a direction that meets no surface.
pub trait Sky: Sync {
    /// Linear RGB radiance seen along the unit direction `dir` (the ray's
    /// final direction, pointing away from the camera).
    fn radiance(&self, dir: DVec3) -> [f64; 3];

    /// Mean radiance over the upper hemisphere, cosine-weighted: the ambient
    /// light on an upward-facing surface.
    fn ambient(&self) -> [f64; 3];

    /// The smooth part of [`Sky::radiance`]: without the sun's disc and the
    /// stars, so that it can be tabulated (the GPU previewer bakes it into a
    /// texture and draws the disc and stars itself).
    fn diffuse(&self, dir: DVec3) -> [f64; 3] {
        self.radiance(dir)
    }

    /// The fraction of the sun's (top-of-atmosphere) irradiance that reaches
    /// the ground, per channel: what lights the scene.
    fn sun_transmittance(&self) -> [f64; 3] {
        [1.0; 3]
    }

    /// The sun's disc as seen from the camera, if the model draws one.
    fn sun_disc(&self) -> Option<SunDisc> {
        None
    }
}

/// The sun's disc in the sky: a uniform disc of `radiance` within
/// `angular_radius` of `direction`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunDisc {
    /// Unit direction toward the sun's centre.
    pub direction: DVec3,
    /// Angular radius (radians).
    pub angular_radius: f64,
    /// Linear RGB radiance of the disc as seen through the air.
    pub radiance: [f64; 3],
}

/// A sky that blends from the horizon colour to the zenith colour with the
/// square root of the sine of the elevation: fast enough near the horizon that
/// a telephoto view of half a degree still shows a gradient. Below the horizon
/// it keeps the horizon colour (rays that end there saw haze, not ground).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GradientSky {
    /// Radiance straight up.
    pub zenith: [f64; 3],
    /// Radiance at (and below) the horizon.
    pub horizon: [f64; 3],
}

/// Default zenith radiance (linear RGB).
pub const DEFAULT_ZENITH: [f64; 3] = [0.22, 0.42, 0.85];
/// Default horizon radiance (linear RGB).
pub const DEFAULT_HORIZON: [f64; 3] = [0.78, 0.85, 0.95];

impl Sky for GradientSky {
    #[inline]
    fn radiance(&self, dir: DVec3) -> [f64; 3] {
        let t = dir.y.clamp(0.0, 1.0).sqrt();
        [0, 1, 2].map(|c| self.horizon[c] + (self.zenith[c] - self.horizon[c]) * t)
    }

    fn ambient(&self) -> [f64; 3] {
        // With μ = sin(elevation), cosine weighting gives μ the density 2μ on
        // [0, 1], and the mean of √μ under it is 4/5.
        [0, 1, 2].map(|c| self.horizon[c] + (self.zenith[c] - self.horizon[c]) * 0.8)
    }
}

/// The sky models a scene can name.
#[derive(Clone, Debug)]
pub enum SkyModel {
    /// [`GradientSky`].
    Gradient(GradientSky),
    /// [`PhysicalSky`]: Rayleigh and Mie single scattering, ozone, the sun's
    /// disc and stars.
    Physical(Box<PhysicalSky>),
}

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
