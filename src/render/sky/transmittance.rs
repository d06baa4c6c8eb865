//! The transmittance table: optical depth to the top of the atmosphere, in
//! Bruneton's parametrisation (exact at the horizon, where mirages look).

use super::atmosphere::Atmosphere;

/// Optical depth to the top of the atmosphere over (radius, direction), for
/// rays that miss the ground, in Bruneton's parametrisation: x_r = ρ/H and
/// x_μ = (d − d_min)/(d_max − d_min), where ρ is the distance to the horizon,
/// H its value at the top, and d the distance to the top along the ray. The
/// horizon maps to x_μ = 1 at every altitude, so grazing rays are sampled as
/// finely as any other.
#[derive(Clone, Debug)]
pub struct TransmittanceTable {
    atmosphere: Atmosphere,
    /// Nodes along x_r.
    pub radius_nodes: usize,
    /// Nodes along x_μ.
    pub mu_nodes: usize,
    /// Optical depth per node, row-major over (x_r, x_μ).
    depth: Vec<[f64; 3]>,
}

/// Simpson intervals per table node: with 400, the optical depth of a
/// horizontal ray from the ground is within 1e-7 relative of the exact value.
const TABLE_INTERVALS: usize = 400;

impl TransmittanceTable {
    /// Default table size: 128 altitudes × 512 directions.
    pub fn new(atmosphere: &Atmosphere) -> TransmittanceTable {
        TransmittanceTable::with_size(atmosphere, 128, 512)
    }

    /// A table with the given numbers of nodes (each ≥ 2).
    pub fn with_size(
        atmosphere: &Atmosphere,
        radius_nodes: usize,
        mu_nodes: usize,
    ) -> TransmittanceTable {
        use rayon::prelude::*;
        let (nr, nm) = (radius_nodes.max(2), mu_nodes.max(2));
        let depth = (0..nr * nm)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k / nm, k % nm);
                let (r, mu) = Self::unmap(
                    atmosphere,
                    i as f64 / (nr - 1) as f64,
                    j as f64 / (nm - 1) as f64,
                );
                atmosphere.optical_depth(r, mu, TABLE_INTERVALS)
            })
            .collect();
        TransmittanceTable {
            atmosphere: *atmosphere,
            radius_nodes: nr,
            mu_nodes: nm,
            depth,
        }
    }

    /// The atmosphere the table is of.
    pub fn atmosphere(&self) -> &Atmosphere {
        &self.atmosphere
    }

    fn horizon_top(a: &Atmosphere) -> f64 {
        (a.top_radius * a.top_radius - a.bottom_radius * a.bottom_radius).sqrt()
    }

    /// (x_r, x_μ) ∈ [0, 1]² of a radius and a zenith cosine.
    pub fn map(a: &Atmosphere, r: f64, mu: f64) -> (f64, f64) {
        let big_h = Self::horizon_top(a);
        let r = r.clamp(a.bottom_radius, a.top_radius);
        let rho = (r * r - a.bottom_radius * a.bottom_radius).max(0.0).sqrt();
        let d = a.distance_to_top(r, mu);
        let d_min = a.top_radius - r;
        let d_max = rho + big_h;
        let x_mu = if d_max > d_min {
            (d - d_min) / (d_max - d_min)
        } else {
            0.0
        };
        (rho / big_h, x_mu.clamp(0.0, 1.0))
    }

    /// The radius and zenith cosine of table coordinates.
    pub fn unmap(a: &Atmosphere, x_r: f64, x_mu: f64) -> (f64, f64) {
        let big_h = Self::horizon_top(a);
        let rho = big_h * x_r;
        let r = (rho * rho + a.bottom_radius * a.bottom_radius).sqrt();
        let d_min = a.top_radius - r;
        let d_max = rho + big_h;
        let d = d_min + x_mu * (d_max - d_min);
        let mu = if d == 0.0 {
            1.0
        } else {
            ((big_h * big_h - rho * rho - d * d) / (2.0 * r * d)).clamp(-1.0, 1.0)
        };
        (r, mu)
    }

    /// Optical depth to the top from radius `r` along zenith cosine `mu`
    /// (bilinear in the table's coordinates).
    pub fn optical_depth(&self, r: f64, mu: f64) -> [f64; 3] {
        let (xr, xm) = Self::map(&self.atmosphere, r, mu);
        let fr = xr * (self.radius_nodes - 1) as f64;
        let fm = xm * (self.mu_nodes - 1) as f64;
        let i = (fr.floor() as usize).min(self.radius_nodes - 2);
        let j = (fm.floor() as usize).min(self.mu_nodes - 2);
        let (tr, tm) = (fr - i as f64, fm - j as f64);
        let at = |i: usize, j: usize| self.depth[i * self.mu_nodes + j];
        let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
        [0, 1, 2].map(|k| {
            (1.0 - tr) * ((1.0 - tm) * a[k] + tm * b[k]) + tr * ((1.0 - tm) * c[k] + tm * d[k])
        })
    }

    /// Transmittance to the top of the atmosphere; zero for rays that meet
    /// the ground (the planet's shadow).
    pub fn transmittance(&self, r: f64, mu: f64) -> [f64; 3] {
        if self.atmosphere.hits_ground(r, mu) {
            return [0.0; 3];
        }
        self.optical_depth(r, mu).map(|t| (-t).exp())
    }

    /// The table's raw optical depths (row-major over x_r, then x_μ), e.g. to
    /// upload as a texture.
    pub fn data(&self) -> &[[f64; 3]] {
        &self.depth
    }
}
