//! The scene's sky as a latitude–longitude environment map (`mirage sky`), in
//! Mitsuba 3's `envmap` convention, so that a reference renderer sees the same
//! sky as mirage.
//!
//! Mitsuba looks up a direction d (world frame, identity `to_world`, y up) at
//! u = atan2(d.x, −d.z) / 2π (wrapped to [0, 1)), v = acos(d.y) / π, with u
//! running across the columns and v down the rows, and interpolates bilinearly
//! between samples: its columns sit at texel centres, u = (i + ½)/W (wrapping
//! around), but its rows run from pole to pole, v = j/(H − 1) (the first row is
//! the zenith, the last the nadir). Texel (i, j) of a W × H map is therefore
//! the sky at
//!
//! ```text
//! φ = 2π·u,  θ = π·v,  d = (sin φ · sin θ,  cos θ,  −cos φ · sin θ)
//! ```
//!
//! Near the horizon the gradient sky changes fast (with √sin(elevation)), and
//! telephoto views are a degree tall: there a map must be tall for the bilinear
//! lookup to be accurate. [`lookup_error`] measures it; `mirage sky` prints it.

use crate::error::{Error, Result};
use crate::io::{Output, OutputKind, check_outputs, write_atomic};
use crate::render::sky::{Sky, SkyModel};
use crate::scene::Scene;
use glam::DVec3;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Largest side of an exported map (texels).
pub const MAX_SIDE: u32 = 65_536;

/// The unit direction of continuous map coordinates (u, v) ∈ [0, 1]².
pub fn direction(u: f64, v: f64) -> DVec3 {
    let (phi, theta) = (2.0 * PI * u, PI * v);
    DVec3::new(
        phi.sin() * theta.sin(),
        theta.cos(),
        -phi.cos() * theta.sin(),
    )
}

/// The map coordinates (u ∈ [0, 1), v ∈ [0, 1]) of a unit direction.
pub fn coordinates(d: DVec3) -> (f64, f64) {
    let u = d.x.atan2(-d.z) / (2.0 * PI);
    (u - u.floor(), d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// The map coordinates of texel (i, j) of a `width × height` map.
pub fn texel(i: u32, j: u32, width: u32, height: u32) -> (f64, f64) {
    (
        (i as f64 + 0.5) / width as f64,
        j as f64 / (height - 1) as f64,
    )
}

/// The map: `width × height` (height ≥ 2) texels of linear RGB, row-major,
/// top row (zenith) first.
pub fn bake(sky: &dyn Sky, width: u32, height: u32) -> Vec<[f32; 3]> {
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for j in 0..height {
        for i in 0..width {
            let (u, v) = texel(i, j, width, height);
            let d = direction(u, v);
            out.push(sky.radiance(d).map(|c| c as f32));
        }
    }
    out
}

/// Bilinear lookup of a baked map as Mitsuba does it (see the module
/// documentation: u wraps around, rows span the poles).
pub fn lookup(map: &[[f32; 3]], width: u32, height: u32, d: DVec3) -> [f64; 3] {
    let (u, v) = coordinates(d);
    let x = u * width as f64 - 0.5;
    let y = (v * (height - 1) as f64).clamp(0.0, (height - 1) as f64);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let w = width as i64;
    let col = |i: i64| i.rem_euclid(w) as usize;
    let row = |j: f64| (j as usize).min(height as usize - 1);
    let at = |i: i64, j: usize| map[j * width as usize + col(i)];
    let (i0, j0, j1) = (x0 as i64, row(y0), row(y0 + 1.0));
    [0, 1, 2].map(|c| {
        let top = at(i0, j0)[c] as f64 * (1.0 - fx) + at(i0 + 1, j0)[c] as f64 * fx;
        let bottom = at(i0, j1)[c] as f64 * (1.0 - fx) + at(i0 + 1, j1)[c] as f64 * fx;
        top * (1.0 - fy) + bottom * fy
    })
}

/// The largest channel error of the bilinear lookup against the sky itself,
/// over elevations within `band` radians of the horizon (all azimuths sampled).
pub fn lookup_error(sky: &dyn Sky, map: &[[f32; 3]], width: u32, height: u32, band: f64) -> f64 {
    let mut worst = 0.0f64;
    for k in 0..=400 {
        let el = band * (2.0 * k as f64 / 400.0 - 1.0);
        for a in 0..16 {
            let az = 2.0 * PI * (a as f64 + 0.37) / 16.0;
            let d = DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
            let (want, got) = (sky.radiance(d), lookup(map, width, height, d));
            for c in 0..3 {
                worst = worst.max((want[c] - got[c]).abs());
            }
        }
    }
    worst
}

/// Write a scene's sky as a lat-long environment map (Mitsuba's envmap convention).
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct SkyOptions {
    /// Scene file (JSON).
    pub scene: PathBuf,
    /// Output (.exr).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Width in texels (default 1024).
    #[arg(long, value_parser = map_side)]
    pub width: Option<u32>,
    /// Height in texels (default width / 2; taller maps are more accurate near the horizon).
    #[arg(long, value_parser = map_side)]
    pub height: Option<u32>,
}

/// `--width`/`--height` of a sky map: 2 to [`MAX_SIDE`] texels.
fn map_side(s: &str) -> std::result::Result<u32, crate::error::ValueError> {
    match s
        .parse::<u32>()
        .map_err(|_| crate::error::ValueError::NotAWholeNumber {
            value: s.to_string(),
        })? {
        v if (2..=MAX_SIDE).contains(&v) => Ok(v),
        v => Err(crate::error::ValueError::OutOfRange {
            rule: side_message(v),
        }),
    }
}

fn side_message(v: u32) -> String {
    format!("must be between 2 and {MAX_SIDE} texels, got {v}")
}

/// `mirage sky`: bakes the scene's sky into a lat-long EXR and prints the
/// lookup error within ±2° of the horizon.
pub fn sky_command(o: &SkyOptions) -> Result<f64> {
    let scene = Scene::load(&o.scene)?;
    let mut inputs: Vec<&Path> = vec![o.scene.as_path()];
    inputs.extend(scene.inputs.iter().map(PathBuf::as_path));
    check_outputs(
        [Output::new("-o", &o.output, OutputKind::Exr("the sky map"))],
        &inputs,
    )?;
    let width = o.width.unwrap_or(1024);
    let height = o.height.unwrap_or(width.div_ceil(2));
    // The flags are in range; the height derived from a width of 2 is not.
    if height < 2 {
        return Err(Error::usage("--height", side_message(height)));
    }
    // A map holds nothing finer than a texel: features the sky sizes by the
    // pixel (the stars) are sized by the texel's height instead.
    let texel_angle = PI / (height - 1) as f64;
    let sky = SkyModel::from_spec(&scene.sky, &scene.sun, scene.camera.position.y, texel_angle);
    let map = bake(&sky, width, height);
    let error = lookup_error(&sky, &map, width, height, 2f64.to_radians());
    let bytes = crate::render::output::encode_exr(width, height, &map)?;
    write_atomic(&o.output, &bytes)?;
    println!(
        "{}: sky map {width}×{height} texels; bilinear lookup error within ±2° of the horizon ≤ {error:.2e}",
        o.output.display()
    );
    Ok(error)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sky::GradientSky;

    #[test]
    fn known_directions_land_where_mitsuba_looks() {
        // Mitsuba: u = atan2(x, −z)/2π, v = acos(y)/π.
        let close = |a: DVec3, b: DVec3| (a - b).length() < 1e-12;
        assert!(close(direction(0.0, 0.5), DVec3::new(0.0, 0.0, -1.0)));
        assert!(close(direction(0.25, 0.5), DVec3::new(1.0, 0.0, 0.0)));
        assert!(close(direction(0.5, 0.5), DVec3::new(0.0, 0.0, 1.0)));
        assert!(close(direction(0.3, 0.0), DVec3::Y));
        let (u, v) = coordinates(DVec3::new(-1.0, 0.0, 0.0));
        assert!((u - 0.75).abs() < 1e-12 && (v - 0.5).abs() < 1e-12);
        for (u, v) in [(0.1, 0.2), (0.6, 0.7), (0.99, 0.5)] {
            let (u2, v2) = coordinates(direction(u, v));
            assert!((u - u2).abs() < 1e-12 && (v - v2).abs() < 1e-12);
        }
    }

    #[test]
    fn baked_texels_are_the_sky_at_their_centres() {
        let sky = GradientSky {
            zenith: [0.1, 0.2, 0.9],
            horizon: [0.8, 0.8, 0.8],
        };
        let (w, h) = (8, 4);
        let map = bake(&sky, w, h);
        // Row 0 is the zenith; row 1 of 4 looks up at elevation 30°.
        assert!((map[3][2] as f64 - 0.9).abs() < 1e-6);
        let t = (30f64.to_radians().sin()).sqrt();
        assert!((map[(w + 3) as usize][2] as f64 - (0.8 + (0.9 - 0.8) * t)).abs() < 1e-6);
        // Rows 2 and 3 are below the horizon: horizon colour.
        assert_eq!(map[(2 * w + 5) as usize], [0.8f32; 3]);
        // The columns: texel 2 of 8 looks along u = 2.5/8.
        let (u, v) = texel(2, 1, w, h);
        assert!((u - 2.5 / 8.0).abs() < 1e-15 && (v - 1.0 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn a_tall_map_is_accurate_near_the_horizon() {
        let sky = GradientSky {
            zenith: [0.2, 0.4, 0.85],
            horizon: [0.75, 0.83, 0.95],
        };
        let band = 2f64.to_radians();
        let coarse = lookup_error(&sky, &bake(&sky, 64, 32), 64, 32, band);
        let tall = lookup_error(&sky, &bake(&sky, 64, 8192), 64, 8192, band);
        assert!(coarse > 0.05, "{coarse}");
        assert!(tall < 0.01, "{tall}");
    }
}
