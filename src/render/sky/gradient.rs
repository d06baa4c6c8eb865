//! The cheap sky: a gradient from the horizon colour to the zenith colour.

use super::Sky;
use glam::DVec3;

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
