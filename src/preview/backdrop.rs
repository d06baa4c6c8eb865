//! The render behind the photo in the previewer's photo mode: the problem's
//! air and ground (sea), at the current numbers (fitted after a fit, else the
//! file's starting ones), rendered by the CPU renderer through the photo's
//! own camera, so that a blend of the two shows where the air puts the sea
//! horizon against the photo's.
//!
//! # Algorithm
//!
//! The problem's objective gives the medium at x
//! ([`Objective::medium`]) and the photo camera at x's camera numbers
//! (azimuth, tilt, roll, focal length, distortion: [`PhotoPart::camera_at`]).
//! The camera is scaled to the backdrop's width w (a factor s = w / W of the
//! photo's width W: f·s, principal point (c + ½)·s − ½, the distortion
//! coefficients unchanged, as they act on normalised coordinates), and each
//! backdrop pixel's ray is that camera's ray ([`Camera::from_lens`]). The
//! scene is the problem's medium and earth, a dark sea, the default sky and
//! sun, no objects and no glare; lit shading, one sample per pixel, tone
//! mapped as `mirage render` does.
//!
//! # Invariants and accuracy
//!
//! - The backdrop is in the photo's frame, pixel for pixel (scaled): a
//!   backdrop pixel (i, j) is the photo's continuous pixel ((i + ½)/s − ½,
//!   (j + ½)/s − ½). Rays are traced in the problem's own frame (x east,
//!   z north), as the fit traces them: no mirror between the two.
//! - Over the round earth the rendered boundary between sea and sky is the
//!   apparent horizon of the problem's air: within one backdrop pixel of the
//!   photo report's horizon line (Bouguer's invariant,
//!   [`crate::photo::horizon`]); tested below.
//!
//! [`PhotoPart::camera_at`]: crate::fit::objective::PhotoPart::camera_at

use crate::error::{Error, Result};
use crate::fit::objective::Objective;
use crate::problem::Problem;
use crate::render::camera::Camera;
use crate::render::output::to_srgb8;
use crate::render::{RenderOptions, Renderer, Shading, tone_map};
use crate::scene::Scene;
use glam::DVec3;
use std::sync::{Arc, Mutex};

/// The backdrop's width when the photo is wider (pixels): a render of a
/// few seconds on two cores for real air over the round earth.
pub const BACKDROP_WIDTH: u32 = 400;

/// The sea's albedo (linear RGB).
const SEA: [f64; 3] = [0.03, 0.07, 0.1];

/// The render of `problem`'s air behind its photo at `x` (else the
/// starting numbers), `width` pixels wide (at most the photo's), as 8-bit
/// sRGB.
pub fn render_backdrop(
    problem: &Problem,
    x: Option<&[f64]>,
    width: u32,
) -> Result<image::RgbImage> {
    let objective = Objective::from_problem(problem);
    let start = objective.start();
    let x = x
        .filter(|x| x.len() == start.len())
        .unwrap_or(start.as_slice());
    let no_photo = || Error::input(&problem.source, "photo", "not a photo problem");
    let photo = objective.photo().ok_or_else(no_photo)?;
    let lens = photo.camera_at(&x[objective.free().len()..]);
    let params = photo.params();
    let [w0, h0] = params.size;
    let width = width.clamp(1, w0);
    let s = width as f64 / w0 as f64;
    let height = ((h0 as f64 * s).round() as u32).max(1);
    let mut scaled = lens;
    scaled.f = lens.f * s;
    scaled.c = lens.c.map(|c| (c + 0.5) * s - 0.5);
    let origin = DVec3::from_array(params.position);
    let axis = DVec3::new(lens.axis.x, lens.axis.y, lens.axis.z);
    let fov = 2.0 * (0.5 * height as f64 / scaled.f).atan().to_degrees();
    let medium = serde_json::to_value(objective.medium(x)).map_err(|e| {
        Error::input(
            &problem.source,
            "medium",
            format!("the air at the current numbers cannot be written: {e}"),
        )
    })?;
    let mut scene_json = serde_json::json!({
        "name": format!("{} (the air behind the photo)", problem.name),
        "camera": {
            "position": params.position,
            "look_at": (origin + axis * 1000.0).to_array(),
            "vertical_fov": fov.clamp(1e-3, 179.0),
            "width": width,
            "height": height,
        },
        "medium": medium,
        "ground": { "albedo": SEA },
    });
    if let Some(r) = problem.trace.earth.radius() {
        scene_json["earth"] = serde_json::json!({ "radius": r });
    }
    let scene = Scene::parse(&scene_json.to_string(), &problem.source)?;
    let options = RenderOptions {
        samples_per_pixel: Some(1),
        glare: false,
        ..RenderOptions::default()
    };
    let camera = Camera::from_lens(origin, scaled, width, height);
    let renderer = Renderer::with_camera(&scene, &options, camera);
    let image = renderer.render();
    let bytes = to_srgb8(&image.pixels, tone_map(Shading::Lit, scene.exposure));
    image::RgbImage::from_raw(image.width, image.height, bytes).ok_or_else(|| {
        Error::input(
            &problem.source,
            "photo",
            "the render behind the photo has the wrong size",
        )
    })
}

/// A backdrop rendered in the background.
pub struct BackdropJob {
    done: Arc<Mutex<Option<Result<image::RgbImage>>>>,
}

impl BackdropJob {
    /// Starts rendering `problem`'s backdrop at `x`.
    pub fn start(problem: &Problem, x: Option<Vec<f64>>, width: u32) -> BackdropJob {
        let done = Arc::new(Mutex::new(None));
        let out = Arc::clone(&done);
        let problem = problem.clone();
        std::thread::spawn(move || {
            let r = render_backdrop(&problem, x.as_deref(), width);
            if let Ok(mut d) = out.lock() {
                *d = Some(r);
            }
        });
        BackdropJob { done }
    }

    /// The render, once done (taken: a second call gives `None`).
    pub fn take(&self) -> Option<Result<image::RgbImage>> {
        self.done.lock().ok().and_then(|mut d| d.take())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::photo::photo_report;
    use crate::math::SplitMix64;
    use serde_json::json;
    use std::path::Path;

    /// A seeded round-earth photo problem in `dir`: a camera 3–40 m above
    /// the sea looking at the horizon with a roll and a lens distortion,
    /// through one of several airs (the logistic model with and without an
    /// inversion, real air standard or over a cold or warm sea), one
    /// horizon mark.
    fn generated(dir: &Path, seed: u64) -> Problem {
        let mut rng = SplitMix64(seed);
        let mut uniform = |a: f64, b: f64| a + (b - a) * rng.next_f64();
        let (w, h) = (uniform(240.0, 480.0) as u32, uniform(140.0, 300.0) as u32);
        image::RgbImage::from_pixel(w, h, image::Rgb([90, 120, 160]))
            .save(dir.join("photo.png"))
            .unwrap();
        let height: f64 = uniform(3.0, 40.0);
        let dip = -(2.0 * height / 6.371e6f64).sqrt().to_degrees();
        let medium = match seed % 4 {
            0 => json!({"scale": 0.0025, "background": {"n": 1.0, "a": 8000.0}}),
            1 => json!({"scale": 0.0025, "background": {"n": 1.0, "a": 8000.0},
                        "inversion": {"n": 0.3, "a": 4.0, "height": uniform(2.0, 20.0)}}),
            2 => json!({"air": {"humidity": 0.5, "temperature": {"base": 15.0, "lapse": -0.0065}}}),
            _ => json!({"air": {"temperature": {"base": 10.0, "lapse": -0.0065,
                "exponential": {"delta": uniform(-2.0, 2.0), "scale_height": 15.0}}}}),
        };
        let v = json!({
            "name": format!("backdrop-{seed}"),
            "photo": {"image": "photo.png", "camera": {
                "horizontal_fov": uniform(3.0, 10.0),
                "azimuth": uniform(0.0, 360.0),
                "tilt": dip + uniform(-0.1, 0.1),
                "roll": uniform(-3.0, 3.0),
                "distortion": {"k1": uniform(-1.0, 0.5)},
                "position": [0.0, height, 0.0]}},
            "earth": {"radius": 6.371e6},
            "medium": medium,
            "marks": [{"name": "sea", "pixel": [0.5 * w as f64, 0.5 * h as f64], "horizon": true}],
        });
        let path = dir.join(format!("p{seed}.json"));
        std::fs::write(&path, v.to_string()).unwrap();
        Problem::load(&path).unwrap()
    }

    fn luminance(p: &image::Rgb<u8>) -> f64 {
        0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
    }

    /// The rendered sea horizon lies where the photo report's apparent
    /// horizon (Bouguer's invariant, an independent computation) puts it,
    /// column by column, within one backdrop pixel.
    #[test]
    fn the_rendered_sea_horizon_is_the_apparent_horizon_line() {
        let dir = tempfile::tempdir().unwrap();
        for seed in 0..8 {
            let problem = generated(dir.path(), seed);
            let width = 96;
            let img = render_backdrop(&problem, None, width).unwrap();
            let objective = Objective::from_problem(&problem);
            let report =
                photo_report(&objective, objective.start().as_slice(), "photo.png").unwrap();
            let w0 = report.size[0] as f64;
            let s = width as f64 / w0;
            let line = &report.horizon_line;
            assert!(line.len() > 10, "seed {seed}");
            let mut checked = 0;
            let mut worst = 0.0f64;
            for i in 0..img.width() {
                let u = (i as f64 + 0.5) / s - 0.5;
                let Some(k) = line.windows(2).position(|p| p[0][0] <= u && u <= p[1][0]) else {
                    continue;
                };
                let (a, b) = (line[k], line[k + 1]);
                let v = a[1] + (b[1] - a[1]) * (u - a[0]) / (b[0] - a[0]);
                let y = (v + 0.5) * s;
                if y < 2.0 || y > img.height() as f64 - 2.0 {
                    continue;
                }
                let top = luminance(img.get_pixel(i, 0));
                let bottom = luminance(img.get_pixel(i, img.height() - 1));
                assert!(top > bottom + 20.0, "seed {seed}: sky {top}, sea {bottom}");
                let mid = 0.5 * (top + bottom);
                let j = (0..img.height())
                    .find(|&j| luminance(img.get_pixel(i, j)) < mid)
                    .unwrap();
                // Sky at row j − 1's centre, sea at row j's: the boundary
                // lies within half a row of j.
                worst = worst.max((y - j as f64).abs());
                checked += 1;
            }
            assert!(checked > 40, "seed {seed}: {checked} columns");
            assert!(worst <= 1.0, "seed {seed}: {worst} rows");
            eprintln!("seed {seed}: {checked} columns, worst {worst:.3} rows");
        }
    }
}
