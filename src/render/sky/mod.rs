//! What a ray sees when it hits nothing: the sky, behind one interface, with
//! two models: a cheap gradient and the physically based
//! [`PhysicalSky`].
//!
//! The files, in dependency order (each uses only those above it, and the
//! interface here uses none of them):
//!
//! - [`atmosphere`]: the constituents of the air, their scattering
//!   coefficients and phase functions;
//! - [`transmittance`]: the optical-depth table;
//! - [`view_table`]: the sky-view table of single-scattered radiance;
//! - [`stars`]: the hashed star field;
//! - [`gradient`] and [`physical`]: the two models;
//! - [`model`]: the dispatch of [`SkyModel`] to them.

pub mod atmosphere;
pub mod gradient;
pub mod model;
pub mod physical;
pub mod stars;
pub mod transmittance;
pub mod view_table;

#[cfg(test)]
mod tests;

pub use atmosphere::{
    Atmosphere, BOTTOM_RADIUS, SUN_ANGULAR_RADIUS, TOP_RADIUS, WAVELENGTHS_UM,
    cornette_shanks_phase, rayleigh_phase,
};
pub use gradient::{DEFAULT_HORIZON, DEFAULT_ZENITH, GradientSky};
pub use physical::{PhysicalSky, PhysicalSkySettings};
pub use stars::{
    STAR_CELLS, STAR_FADE, STAR_FLUX, STAR_MARGIN_MAX, star_cell, star_radiance, star_radius,
};
pub use transmittance::TransmittanceTable;

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

/// The sky models a scene can name.
#[derive(Clone, Debug)]
pub enum SkyModel {
    /// [`GradientSky`].
    Gradient(GradientSky),
    /// [`PhysicalSky`]: Rayleigh and Mie single scattering, ozone, the sun's
    /// disc and stars.
    Physical(Box<PhysicalSky>),
}
