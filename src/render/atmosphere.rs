//! A physically based sky: single scattering by air molecules (Rayleigh) and
//! aerosols (Mie), absorption by ozone, sunlight attenuated by Beer's law, the
//! sun's disc, and stars at night.
//!
//! The planet is a sphere of radius 6360 km under an atmosphere 60 km deep.
//! Densities fall off exponentially (Rayleigh scale height 8 km, Mie 1.2 km);
//! ozone follows a tent from 10 km through 25 km to 40 km. The constants are
//! Bruneton's (2017) at 680, 550 and 440 nm:
//!
//! | constituent | coefficient (m⁻¹, R / G / B) | profile |
//! | --- | --- | --- |
//! | Rayleigh scattering | 1.24062e-6·λ⁻⁴ (λ in µm) = 5.80e-6 / 1.36e-5 / 3.31e-5 | e^(−h / 8 km) |
//! | Mie extinction | 4.44e-6 (single-scattering albedo 0.9, g = 0.8) | e^(−h / 1.2 km) |
//! | ozone absorption | 6.50e-7 / 1.881e-6 / 8.5e-8 | tent 10–25–40 km |
//!
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

use super::sky::{Sky, SunDisc};
use crate::math::splitmix64;
use crate::scene::description::Sun;
use glam::DVec3;
use std::f64::consts::PI;

/// Radius of the ground sphere (metres).
pub const BOTTOM_RADIUS: f64 = 6_360_000.0;
/// Radius of the top of the atmosphere (metres).
pub const TOP_RADIUS: f64 = 6_420_000.0;
/// The wavelengths of the R, G and B channels (µm).
pub const WAVELENGTHS_UM: [f64; 3] = [0.680, 0.550, 0.440];
/// The sun's angular radius (radians).
pub const SUN_ANGULAR_RADIUS: f64 = 0.004675;

/// The constituents of the atmosphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Atmosphere {
    /// Ground radius (metres).
    pub bottom_radius: f64,
    /// Top radius (metres).
    pub top_radius: f64,
    /// Rayleigh scattering coefficient at sea level, per channel (m⁻¹).
    pub rayleigh_scattering: [f64; 3],
    /// Rayleigh scale height (metres).
    pub rayleigh_scale_height: f64,
    /// Mie scattering coefficient at sea level (m⁻¹).
    pub mie_scattering: f64,
    /// Mie extinction coefficient at sea level (m⁻¹).
    pub mie_extinction: f64,
    /// Mie scale height (metres).
    pub mie_scale_height: f64,
    /// Mie asymmetry parameter.
    pub mie_g: f64,
    /// Ozone absorption at the peak of its tent, per channel (m⁻¹).
    pub ozone_absorption: [f64; 3],
    /// Bottom, peak and top of the ozone tent (metres).
    pub ozone_tent: [f64; 3],
}

impl Default for Atmosphere {
    fn default() -> Self {
        Atmosphere::earth(1.0, 1.0, true)
    }
}

impl Atmosphere {
    /// The Earth's atmosphere with the molecular and aerosol densities scaled,
    /// and ozone on or off.
    pub fn earth(rayleigh_scale: f64, mie_scale: f64, ozone: bool) -> Atmosphere {
        let mie_extinction = 4.44e-6 * mie_scale;
        Atmosphere {
            bottom_radius: BOTTOM_RADIUS,
            top_radius: TOP_RADIUS,
            rayleigh_scattering: WAVELENGTHS_UM.map(|l| rayleigh_scale * 1.24062e-6 / l.powi(4)),
            rayleigh_scale_height: 8000.0,
            mie_scattering: 0.9 * mie_extinction,
            mie_extinction,
            mie_scale_height: 1200.0,
            mie_g: 0.8,
            ozone_absorption: if ozone {
                [0.650e-6, 1.881e-6, 0.085e-6]
            } else {
                [0.0; 3]
            },
            ozone_tent: [10_000.0, 25_000.0, 40_000.0],
        }
    }

    /// The relative densities (Rayleigh, Mie, ozone) at an altitude.
    #[inline]
    pub fn densities(&self, altitude: f64) -> [f64; 3] {
        let h = altitude.max(0.0);
        let [lo, peak, hi] = self.ozone_tent;
        let ozone = if h <= lo || h >= hi {
            0.0
        } else if h <= peak {
            (h - lo) / (peak - lo)
        } else {
            (hi - h) / (hi - peak)
        };
        [
            (-h / self.rayleigh_scale_height).exp(),
            (-h / self.mie_scale_height).exp(),
            ozone,
        ]
    }

    /// The extinction coefficient (m⁻¹) per channel at an altitude.
    #[inline]
    pub fn extinction(&self, altitude: f64) -> [f64; 3] {
        let [r, m, o] = self.densities(altitude);
        [0, 1, 2].map(|c| {
            self.rayleigh_scattering[c] * r + self.mie_extinction * m + self.ozone_absorption[c] * o
        })
    }

    /// Distance from radius `r` along a direction with cosine `mu` to the
    /// zenith to the top of the atmosphere.
    #[inline]
    pub fn distance_to_top(&self, r: f64, mu: f64) -> f64 {
        let disc = r * r * (mu * mu - 1.0) + self.top_radius * self.top_radius;
        (-r * mu + disc.max(0.0).sqrt()).max(0.0)
    }

    /// Whether the ray from radius `r` with zenith cosine `mu` meets the
    /// ground.
    #[inline]
    pub fn hits_ground(&self, r: f64, mu: f64) -> bool {
        mu < 0.0 && r * r * (mu * mu - 1.0) + self.bottom_radius * self.bottom_radius >= 0.0
    }

    /// Optical depth from radius `r` to the top of the atmosphere along zenith
    /// cosine `mu`, by composite Simpson integration with `intervals`
    /// (rounded up to even) intervals. Rays that meet the ground are
    /// integrated through it as if it were air: callers decide what the ground
    /// means.
    pub fn optical_depth(&self, r: f64, mu: f64, intervals: usize) -> [f64; 3] {
        let n = intervals.max(2).next_multiple_of(2);
        let d = self.distance_to_top(r, mu);
        let dt = d / n as f64;
        let mut sum = [0.0; 3];
        for i in 0..=n {
            let t = i as f64 * dt;
            let h = (t * t + 2.0 * r * mu * t + r * r).sqrt() - self.bottom_radius;
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let e = self.extinction(h);
            for c in 0..3 {
                sum[c] += w * e[c];
            }
        }
        sum.map(|s| s * dt / 3.0)
    }
}

/// The Rayleigh phase function, 3/(16π)(1 + ν²), of the cosine ν of the
/// scattering angle.
#[inline]
pub fn rayleigh_phase(nu: f64) -> f64 {
    3.0 / (16.0 * PI) * (1.0 + nu * nu)
}

/// The Cornette–Shanks phase function with asymmetry `g`.
#[inline]
pub fn cornette_shanks_phase(nu: f64, g: f64) -> f64 {
    let g2 = g * g;
    3.0 / (8.0 * PI) * (1.0 - g2) * (1.0 + nu * nu)
        / ((2.0 + g2) * (1.0 + g2 - 2.0 * g * nu).powf(1.5))
}

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

/// Rows (elevation) and columns (azimuth from the sun) of the sky-view table.
const VIEW_ROWS: usize = 192;
const VIEW_COLUMNS: usize = 96;
/// Integration samples along a view ray when building the sky-view table.
const VIEW_SAMPLES: usize = 96;

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
    view: Vec<[f64; 3]>,
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
            view: Vec::new(),
            ambient: [0.0; 3],
            sun_transmittance: [0.0; 3],
            star_radius: star_radius(pixel_angle),
        };
        sky.sun_transmittance = sky
            .table
            .transmittance(observer_radius, sky.sun_direction.y);
        sky.view = sky.build_view_table();
        sky.ambient = sky.hemisphere_mean();
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

    /// The unit direction of an elevation and an azimuth from the sun, in the
    /// sun's frame (x toward the sun's azimuth, y up).
    fn local_direction(elevation: f64, azimuth: f64) -> DVec3 {
        DVec3::new(
            elevation.cos() * azimuth.cos(),
            elevation.sin(),
            elevation.cos() * azimuth.sin(),
        )
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
        self.integrate(Self::local_direction(e, az), 2000, true)
    }

    fn row_elevation(row: f64) -> f64 {
        let v = row / (VIEW_ROWS - 1) as f64;
        0.5 * PI * v * v
    }

    fn column_azimuth(column: f64) -> f64 {
        let u = column / (VIEW_COLUMNS - 1) as f64;
        PI * u * u
    }

    fn build_view_table(&self) -> Vec<[f64; 3]> {
        use rayon::prelude::*;
        (0..VIEW_ROWS * VIEW_COLUMNS)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k / VIEW_COLUMNS, k % VIEW_COLUMNS);
                let dir = Self::local_direction(
                    Self::row_elevation(i as f64),
                    Self::column_azimuth(j as f64),
                );
                self.integrate(dir, VIEW_SAMPLES, false)
            })
            .collect()
    }

    /// The sky-view table's value at an elevation and azimuth (bilinear in
    /// the table's square-root coordinates).
    fn view_lookup(&self, elevation: f64, azimuth: f64) -> [f64; 3] {
        let fr = (elevation.max(0.0) / (0.5 * PI)).sqrt().min(1.0) * (VIEW_ROWS - 1) as f64;
        let fc = (azimuth.clamp(0.0, PI) / PI).sqrt() * (VIEW_COLUMNS - 1) as f64;
        let i = (fr.floor() as usize).min(VIEW_ROWS - 2);
        let j = (fc.floor() as usize).min(VIEW_COLUMNS - 2);
        let (tr, tc) = (fr - i as f64, fc - j as f64);
        let at = |i: usize, j: usize| self.view[i * VIEW_COLUMNS + j];
        let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
        [0, 1, 2].map(|k| {
            (1.0 - tr) * ((1.0 - tc) * a[k] + tc * b[k]) + tr * ((1.0 - tc) * c[k] + tc * d[k])
        })
    }

    /// The cosine-weighted mean of the table over the upper hemisphere.
    fn hemisphere_mean(&self) -> [f64; 3] {
        // With μ = sin(elevation), the cosine-weighted measure is uniform in
        // μ² and in azimuth: midpoints in s = μ² and φ.
        let (ns, nphi) = (48, 48);
        let mut sum = [0.0; 3];
        for i in 0..ns {
            let s = (i as f64 + 0.5) / ns as f64;
            let e = s.sqrt().asin();
            for j in 0..nphi {
                let phi = PI * (j as f64 + 0.5) / nphi as f64;
                let l = self.view_lookup(e, phi);
                for c in 0..3 {
                    sum[c] += l[c];
                }
            }
        }
        sum.map(|s| s / (ns * nphi) as f64)
    }

    /// The sky-view table's rows and columns and its values (row-major,
    /// linear RGB), for a GPU texture; rows are at elevation (π/2)·(i/(rows−1))²
    /// and columns at azimuth from the sun π·(j/(columns−1))².
    pub fn view_table(&self) -> (usize, usize, &[[f64; 3]]) {
        (VIEW_ROWS, VIEW_COLUMNS, &self.view)
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

    /// Star light along `dir` (before fading).
    fn star(&self, dir: DVec3) -> [f64; 3] {
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
        let margin = (self.star_radius / cell).min(STAR_MARGIN_MAX);
        let cu = iu + margin + u1 * (1.0 - 2.0 * margin);
        let cv = iv + margin + u2 * (1.0 - 2.0 * margin);
        let (du, dv) = ((fu - cu) * cell, (fv - cv) * cell);
        if du * du + dv * dv > self.star_radius * self.star_radius {
            return [0.0; 3];
        }
        // The brightest stars send about 1e-10 of the sun's flux (Sirius
        // against the sun), spread over the drawn disc.
        let flux = STAR_FLUX * u3.powi(6) * self.settings.star_brightness;
        let radiance = flux / (PI * self.star_radius * self.star_radius);
        let e = (self.sun_irradiance[0] + self.sun_irradiance[1] + self.sun_irradiance[2]) / 3.0;
        [
            radiance * e * tint,
            radiance * e,
            radiance * e * (2.0 - tint),
        ]
    }
}

/// Star cells along each edge of a cube-map face (about 1° wide).
pub const STAR_CELLS: usize = 90;

/// The largest margin (a fraction of a star cell) that keeps a star's place
/// away from its cell's edges: the margin is a star radius, at most this.
pub const STAR_MARGIN_MAX: f64 = 0.45;

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
    let h = splitmix64(seed);
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
                let s = self.star(dir);
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
        self.view_lookup(e, az)
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

#[cfg(test)]
mod tests {
    use super::*;

    fn sun(elevation_deg: f64) -> Sun {
        let e = elevation_deg.to_radians();
        Sun {
            direction: DVec3::new(0.0, e.sin(), e.cos()),
            irradiance: [1.0; 3],
        }
    }

    #[test]
    fn vertical_transmittance_matches_closed_form() {
        let a = Atmosphere::default();
        let table = TransmittanceTable::new(&a);
        let h_top = a.top_radius - a.bottom_radius;
        let [lo, _, hi] = a.ozone_tent;
        for c in 0..3 {
            let closed = a.rayleigh_scattering[c]
                * a.rayleigh_scale_height
                * (1.0 - (-h_top / a.rayleigh_scale_height).exp())
                + a.mie_extinction
                    * a.mie_scale_height
                    * (1.0 - (-h_top / a.mie_scale_height).exp())
                + a.ozone_absorption[c] * 0.5 * (hi - lo);
            let expected = (-closed).exp();
            let direct = (-a.optical_depth(a.bottom_radius, 1.0, 4000)[c]).exp();
            let tabled = table.transmittance(a.bottom_radius, 1.0)[c];
            assert!(
                (direct - expected).abs() < 1e-6,
                "{c}: {direct} vs {expected}"
            );
            assert!(
                (tabled - expected).abs() < 1e-3,
                "{c}: {tabled} vs {expected}"
            );
        }
        let t = table.transmittance(a.bottom_radius, 1.0);
        for (got, want) in t.iter().zip([0.940, 0.868, 0.762]) {
            assert!((got - want).abs() < 1e-3, "{t:?}");
        }
    }

    #[test]
    fn transmittance_table_error_against_direct_integration() {
        let a = Atmosphere::default();
        let table = TransmittanceTable::new(&a);
        let (mut worst, mut worst_low): (f64, f64) = (0.0, 0.0);
        for i in 0..40 {
            let h = 60_000.0 * (i as f64 / 39.0).powi(3);
            let r = a.bottom_radius + h;
            let mu_horizon = -(1.0 - (a.bottom_radius / r).powi(2)).max(0.0).sqrt();
            for j in 0..60 {
                // Dense near the horizon, where mirages look.
                let s = j as f64 / 59.0;
                let mu = mu_horizon + 1e-9 + (1.0 - mu_horizon) * s.powi(3);
                let t_ref = a.optical_depth(r, mu, 8000).map(|d| (-d).exp());
                let t_tab = table.transmittance(r, mu);
                for c in 0..3 {
                    if t_ref[c] > 1e-3 {
                        let e = (t_tab[c] / t_ref[c] - 1.0).abs();
                        worst = worst.max(e);
                        if h < 10_000.0 {
                            worst_low = worst_low.max(e);
                        }
                    }
                }
            }
        }
        eprintln!(
            "transmittance table: worst relative error {worst:.2e} (below 10 km: {worst_low:.2e})"
        );
        assert!(worst < 6e-3, "worst relative error {worst}");
        assert!(
            worst_low < 1e-3,
            "worst relative error below 10 km {worst_low}"
        );
    }

    #[test]
    fn phase_functions_integrate_to_one() {
        let n = 20_000;
        let mut r = 0.0;
        let mut m = 0.0;
        for i in 0..n {
            let nu = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
            r += rayleigh_phase(nu);
            m += cornette_shanks_phase(nu, 0.8);
        }
        let w = 2.0 * PI * 2.0 / n as f64;
        assert!((r * w - 1.0).abs() < 2e-3, "{}", r * w);
        assert!((m * w - 1.0).abs() < 2e-3, "{}", m * w);
    }

    #[test]
    fn noon_zenith_is_blue_and_sunset_horizon_is_redder() {
        let s = PhysicalSkySettings::default();
        let noon = PhysicalSky::new(&s, &sun(60.0), 1.5, 1e-3);
        let z = noon.radiance(DVec3::Y);
        assert!(z[2] > z[1] && z[1] > z[0], "zenith {z:?}");
        let sunset = PhysicalSky::new(&s, &sun(1.0), 1.5, 1e-3);
        let toward = DVec3::new(0.0, 0.02, 1.0);
        let a = noon.radiance(toward);
        let b = sunset.radiance(toward);
        assert!(b[0] / b[2] > 1.5 * a[0] / a[2], "noon {a:?}, sunset {b:?}");
        // Sunlight reddens too.
        let tn = noon.sun_transmittance();
        let ts = sunset.sun_transmittance();
        assert!(ts[0] / ts[2] > 5.0 * tn[0] / tn[2], "{tn:?} {ts:?}");
    }

    #[test]
    fn sky_view_table_matches_direct_integration() {
        let s = PhysicalSkySettings::default();
        let mut worst: f64 = 0.0;
        for elev in [60.0, 10.0, 0.5] {
            let sky = PhysicalSky::new(&s, &sun(elev), 1.5, 1e-3);
            for (e, az) in [
                (0.001, 0.3),
                (0.01, 2.0),
                (0.3, 1.0),
                (1.0, 0.05),
                (0.05, 3.0),
                (1.4, 2.5),
            ] {
                let dir = DVec3::new(
                    f64::cos(e) * f64::sin(az),
                    f64::sin(e),
                    f64::cos(e) * f64::cos(az),
                );
                let a = sky.diffuse(dir);
                let b = sky.single_scattering_reference(dir);
                for c in 0..3 {
                    worst = worst.max((a[c] / b[c] - 1.0).abs());
                }
            }
        }
        eprintln!("sky-view table: worst relative error {worst:.2e}");
        assert!(worst < 0.01, "worst relative error {worst}");
    }

    #[test]
    fn sun_disc_and_stars() {
        let s = PhysicalSkySettings::default();
        let noon = PhysicalSky::new(&s, &sun(30.0), 1.5, 1e-3);
        let d = noon.sun_disc().unwrap();
        let at_sun = noon.radiance(d.direction);
        let beside = noon.radiance((d.direction + DVec3::X * 0.01).normalize());
        assert!(at_sun[1] > 1e3 * beside[1]);
        // The disc's flux is the transmitted irradiance.
        let flux = d.radiance[1] * PI * SUN_ANGULAR_RADIUS * SUN_ANGULAR_RADIUS;
        assert!((flux - noon.sun_transmittance()[1]).abs() < 1e-12);
        // No star survives the day; some shine at night.
        let night = PhysicalSky::new(&s, &sun(-30.0), 1.5, 1e-3);
        let (mut day_stars, mut night_stars) = (0, 0);
        for i in 0..200 {
            for j in 0..100 {
                let az = 1.0 + i as f64 * 0.0031;
                let e = 0.5 + j as f64 * 0.0007;
                let dir = DVec3::new(
                    f64::cos(e) * f64::sin(az),
                    f64::sin(e),
                    f64::cos(e) * f64::cos(az),
                );
                if noon.radiance(dir)[1] > noon.diffuse(dir)[1] {
                    day_stars += 1;
                }
                if night.radiance(dir)[1] > night.diffuse(dir)[1] {
                    night_stars += 1;
                }
            }
        }
        assert_eq!(day_stars, 0);
        assert!(night_stars > 0);
        assert_eq!(night.sun_transmittance(), [0.0; 3]);
    }
}
