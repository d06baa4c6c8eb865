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
//!
//! The two tables built on these ([`TransmittanceTable`](super::TransmittanceTable)
//! and the sky-view table of [`PhysicalSky`](super::PhysicalSky)) are in their
//! own files.

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
