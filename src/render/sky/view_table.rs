//! The sky-view table: single-scattered radiance seen from the camera, over
//! elevation (square-root spacing, so that the first row above the horizon is
//! 0.0014° up) and azimuth from the sun (square-root spacing again, dense near
//! the sun's forward-scattering peak), looked up bilinearly.
//!
//! Directions are in the sun's frame: x toward the sun's azimuth, y up.

use glam::DVec3;
use std::f64::consts::PI;

/// Rows (elevation) and columns (azimuth from the sun) of the sky-view table.
pub const VIEW_ROWS: usize = 192;
/// Columns (azimuth from the sun) of the sky-view table.
pub const VIEW_COLUMNS: usize = 96;
/// Integration samples along a view ray when building the sky-view table.
pub const VIEW_SAMPLES: usize = 96;

/// The unit direction of an elevation and an azimuth from the sun, in the
/// sun's frame (x toward the sun's azimuth, y up).
pub fn local_direction(elevation: f64, azimuth: f64) -> DVec3 {
    DVec3::new(
        elevation.cos() * azimuth.cos(),
        elevation.sin(),
        elevation.cos() * azimuth.sin(),
    )
}

/// Radiance over (elevation row, azimuth column), row-major, linear RGB.
#[derive(Clone, Debug, Default)]
pub struct SkyViewTable {
    values: Vec<[f64; 3]>,
}

fn row_elevation(row: f64) -> f64 {
    let v = row / (VIEW_ROWS - 1) as f64;
    0.5 * PI * v * v
}

fn column_azimuth(column: f64) -> f64 {
    let u = column / (VIEW_COLUMNS - 1) as f64;
    PI * u * u
}

impl SkyViewTable {
    /// The table of `radiance` (of a unit direction in the sun's frame) at
    /// every node, computed in parallel.
    pub fn build(radiance: impl Fn(DVec3) -> [f64; 3] + Sync) -> SkyViewTable {
        use rayon::prelude::*;
        let values = (0..VIEW_ROWS * VIEW_COLUMNS)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k / VIEW_COLUMNS, k % VIEW_COLUMNS);
                let dir = local_direction(row_elevation(i as f64), column_azimuth(j as f64));
                radiance(dir)
            })
            .collect();
        SkyViewTable { values }
    }

    /// The table's value at an elevation and azimuth (bilinear in the table's
    /// square-root coordinates).
    pub fn lookup(&self, elevation: f64, azimuth: f64) -> [f64; 3] {
        let fr = (elevation.max(0.0) / (0.5 * PI)).sqrt().min(1.0) * (VIEW_ROWS - 1) as f64;
        let fc = (azimuth.clamp(0.0, PI) / PI).sqrt() * (VIEW_COLUMNS - 1) as f64;
        let i = (fr.floor() as usize).min(VIEW_ROWS - 2);
        let j = (fc.floor() as usize).min(VIEW_COLUMNS - 2);
        let (tr, tc) = (fr - i as f64, fc - j as f64);
        let at = |i: usize, j: usize| self.values[i * VIEW_COLUMNS + j];
        let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
        [0, 1, 2].map(|k| {
            (1.0 - tr) * ((1.0 - tc) * a[k] + tc * b[k]) + tr * ((1.0 - tc) * c[k] + tc * d[k])
        })
    }

    /// The cosine-weighted mean of the table over the upper hemisphere.
    pub fn hemisphere_mean(&self) -> [f64; 3] {
        // With μ = sin(elevation), the cosine-weighted measure is uniform in
        // μ² and in azimuth: midpoints in s = μ² and φ.
        let (ns, nphi) = (48, 48);
        let mut sum = [0.0; 3];
        for i in 0..ns {
            let s = (i as f64 + 0.5) / ns as f64;
            let e = s.sqrt().asin();
            for j in 0..nphi {
                let phi = PI * (j as f64 + 0.5) / nphi as f64;
                let l = self.lookup(e, phi);
                for c in 0..3 {
                    sum[c] += l[c];
                }
            }
        }
        sum.map(|s| s / (ns * nphi) as f64)
    }

    /// The rows, the columns and the values (row-major, linear RGB); rows are
    /// at elevation (π/2)·(i/(rows−1))² and columns at azimuth from the sun
    /// π·(j/(columns−1))².
    pub fn parts(&self) -> (usize, usize, &[[f64; 3]]) {
        (VIEW_ROWS, VIEW_COLUMNS, &self.values)
    }
}
