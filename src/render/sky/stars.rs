//! The star field: a hashed cube map of cells, each holding at most one star.
//!
//! The CPU sky and the GPU previewer draw the same stars from
//! [`star_cell`], so a star seen in a preview is where the render puts it.

use glam::DVec3;
use std::f64::consts::PI;

/// Star cells along each edge of a cube-map face (about 1° wide).
pub const STAR_CELLS: usize = 90;

/// The brightest star's flux as a fraction of the sun's (Sirius against the
/// sun).
pub const STAR_FLUX: f64 = 1e-10;

/// The angular radius (radians) at which stars are drawn for pixels of
/// `pixel_angle` radians: about a pixel, so that point-like stars are not
/// missed between pixel centres.
pub fn star_radius(pixel_angle: f64) -> f64 {
    (0.8 * pixel_angle).clamp(2e-5, 0.01)
}

/// The star of cube-map cell (`face`, `iu`, `iv`), if it has one: its place
/// in the cell (two units in [0, 1]), its brightness unit (the flux is
/// [`STAR_FLUX`] times its sixth power) and its tint (red × tint, blue ×
/// (2 − tint)). A cell holds a star with probability 0.35.
pub fn star_cell(face: u64, iu: u64, iv: u64) -> Option<[f64; 4]> {
    let seed = face << 40 | iu << 20 | iv;
    let h = crate::math::splitmix64(seed);
    let unit = |k: u32| ((h >> (16 * k)) & 0xffff) as f64 / 65535.0;
    if unit(0) > 0.35 {
        return None;
    }
    let tint = 0.85 + 0.3 * (((h >> 56) & 0xff) as f64 / 255.0);
    Some([unit(1), unit(2), unit(3), tint])
}

/// Star light fades against a bright sky: by e^(−L_sky / L_fade), where
/// L_fade is this fraction of the sun's irradiance (the sky of late
/// twilight).
pub const STAR_FADE: f64 = 1e-7;

/// The largest margin (a fraction of a star cell) that keeps a star's place
/// away from its cell's edges: the margin is a star radius, at most this.
pub const STAR_MARGIN_MAX: f64 = 0.45;

/// Star light along `dir` (before fading against the sky), for stars drawn
/// with angular radius `star_radius`, their flux scaled by `brightness`,
/// under a sun of mean top-of-atmosphere irradiance `sun_irradiance`.
pub fn star_radiance(
    dir: DVec3,
    star_radius: f64,
    brightness: f64,
    sun_irradiance: f64,
) -> [f64; 3] {
    // Cells of a cube map, 90 per face edge (about 1° wide): each holds a
    // star with probability 0.35, at a hashed place inside the cell and
    // kept a star radius away from its edges, with a hashed brightness
    // from a steep power law (few bright stars, many faint ones).
    const CELLS: f64 = STAR_CELLS as f64;
    let d = dir.normalize();
    let a = d.abs();
    let (face, u, v) = if a.x >= a.y && a.x >= a.z {
        (if d.x > 0.0 { 0 } else { 1 }, d.y / a.x, d.z / a.x)
    } else if a.y >= a.z {
        (if d.y > 0.0 { 2 } else { 3 }, d.x / a.y, d.z / a.y)
    } else {
        (if d.z > 0.0 { 4 } else { 5 }, d.x / a.z, d.y / a.z)
    };
    let (fu, fv) = ((u + 1.0) * 0.5 * CELLS, (v + 1.0) * 0.5 * CELLS);
    let (iu, iv) = (fu.floor().min(CELLS - 1.0), fv.floor().min(CELLS - 1.0));
    let Some([u1, u2, u3, tint]) = star_cell(face, iu as u64, iv as u64) else {
        return [0.0; 3];
    };
    // Cell size in radians is about 2/CELLS (the face spans ±45°).
    let cell = 2.0 / CELLS;
    let margin = (star_radius / cell).min(STAR_MARGIN_MAX);
    let cu = iu + margin + u1 * (1.0 - 2.0 * margin);
    let cv = iv + margin + u2 * (1.0 - 2.0 * margin);
    let (du, dv) = ((fu - cu) * cell, (fv - cv) * cell);
    if du * du + dv * dv > star_radius * star_radius {
        return [0.0; 3];
    }
    // The brightest stars send about 1e-10 of the sun's flux (Sirius
    // against the sun), spread over the drawn disc.
    let flux = STAR_FLUX * u3.powi(6) * brightness;
    let radiance = flux / (PI * star_radius * star_radius);
    let e = sun_irradiance;
    [
        radiance * e * tint,
        radiance * e,
        radiance * e * (2.0 - tint),
    ]
}
