//! Scene files: what the renderer looks at, from where, through which air.
//! The format, every field with its default and its checks: `docs/scene-format.md`.
//!
//! ```json
//! {
//!   "name": "hot-road",
//!   "description": "Cars on a hot road, seen from a driver's seat.",
//!   "camera": { "position": [0, 1.2, 0], "look_at": [0, 1.0, 300],
//!               "up": [0, 1, 0], "vertical_fov": 1.2, "width": 1280, "height": 720 },
//!   "medium": { "scale": 0.02, "background": { "n": 1.0, "a": 150.0 } },
//!   "ground": { "checker": { "size": 2.0, "colors": [[0.08, 0.08, 0.09], [0.12, 0.12, 0.13]] } },
//!   "sun": { "elevation": 35, "azimuth": 150 },
//!   "sky": { "type": "gradient", "zenith": [0.25, 0.45, 0.9], "horizon": [0.8, 0.87, 0.95] },
//!   "objects": [ { "name": "pole", "albedo": [0.7, 0.7, 0.7],
//!                  "shape": { "type": "cylinder", "center": [3, 3, 280], "radius": 0.06, "half_height": 3 } } ],
//!   "samples_per_pixel": 1,
//!   "trace": { "step": 4.0, "max_distance": 3000 }
//! }
//! ```
//!
//! | field | meaning |
//! | --- | --- |
//! | `camera` | pinhole camera: `position`, `look_at` (metres), `up` (default `[0, 1, 0]`), `vertical_fov` (degrees, any value in (0, 179]; telephoto fractions of a degree are fine), `width`, `height` (pixels); optional `roll` (degrees, clockwise as one looks through) and `distortion` (`k1`, `k2`, `k3`, `p1`, `p2`: OpenCV's Brown–Conrady, as in `docs/photo.md`; focal length (height / 2) / tan(vertical_fov / 2) pixels, principal point the image's centre) |
//! | `medium` | the air, inline ([`Medium`], as in problem files) |
//! | `medium_from` | instead of `medium`: a JSON file (path relative to the scene file) whose `medium` field is read, e.g. the result of `mirage fit`, or a problem file (its starting air) |
//! | `ground` | optional plane y = 0: either `albedo` `[r, g, b]`, or `checker` with `size` (metres) and two `colors`; absent: no ground |
//! | `earth` | optional `{"radius": R}` (metres, ≥ 1000): the ground and the air's heights follow the sphere of radius R touching y = 0 at the origin ([`crate::trace::Earth`]); absent: the flat ground |
//! | `objects` | signed-distance objects ([`SceneObject`], see [`super::sdf`]) |
//! | `sun` | `elevation`, `azimuth` (degrees; azimuth from +z toward +x), `irradiance` (default 3.5, linear units), `color` (default white) |
//! | `sky` | `{"type": "gradient", "zenith": rgb, "horizon": rgb}` (linear radiance; both optional), or `{"type": "physical", ...}`: Rayleigh + Mie single scattering with ozone, sun disc and stars (options in [`crate::render::sky`]) |
//! | `glare` | veiling glare of the sun and its mirage images: `enabled`, `strength`, `threshold`, `epsilon`, `kernels` ([`crate::scene::glare`]); absent: none |
//! | `exposure` | multiplies the radiance before tone mapping (default 1) |
//! | `samples_per_pixel` | default 1 (the pixel centre); more: a low-discrepancy pattern inside the pixel |
//! | `dispersion` | `true`: R, G and B are each traced through the air at their own wavelength (real air only; default false; [`crate::render::dispersion`]) |
//! | `trace` | `step`: the RK4 step (metres, default 4), `max_distance`: the arc length after which a ray sees the sky along its final direction (metres, default 20000) |
//!
//! Exactly one of `medium` and `medium_from` is given; unknown fields anywhere are
//! errors, and every error names the file and the field.

use super::glare::{AngularGlare, GlareSpec};
use super::sdf::{SceneObject, Sdf, validate_objects};
use crate::error::{Error, Result};
use crate::geo::{Angle, Horizon, Point, Site, earth_of};
use crate::io::json::{parse_json, read_input};
use crate::medium::Medium;
use crate::photo::spec::Distortion;
use crate::trace::{Earth, EarthSpec};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Default RK4 step of a scene (metres).
pub const DEFAULT_STEP: f64 = 4.0;
/// Default largest arc length of a camera ray (metres).
pub const DEFAULT_MAX_DISTANCE: f64 = 20_000.0;
/// Default sun irradiance (linear units: a white surface facing the sun has
/// radiance `irradiance / π`).
pub const DEFAULT_SUN_IRRADIANCE: f64 = 3.5;
/// Largest image side accepted (pixels).
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// Largest number of samples per pixel accepted.
pub const MAX_SAMPLES_PER_PIXEL: u32 = 4096;

/// The `camera` section as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Eye position: `[x, y, z]` (metres) or a geographic point (needs a
    /// `site`).
    pub position: Point,
    /// A point the camera looks at (the image centre), local or geographic;
    /// or leave it out and give `elevation` and `azimuth`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub look_at: Option<Point>,
    /// Instead of `look_at`: the view's elevation above the local horizontal
    /// at the camera (degrees, or a degrees-minutes-seconds string).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub elevation: Option<Angle>,
    /// With `elevation`: the view's azimuth, degrees from north (the frame's
    /// z) toward east (x).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub azimuth: Option<Angle>,
    /// Up direction (default: the local vertical at the camera, the
    /// sphere's normal over the round earth, +y over the flat ground).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<[f64; 3]>,
    /// Vertical field of view, degrees.
    pub vertical_fov: f64,
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// Roll about the view direction, degrees, positive when the camera is
    /// turned clockwise as one looks through it (its right side lower), as
    /// in a photo problem's camera (`docs/photo.md`); default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roll: Option<f64>,
    /// OpenCV's Brown–Conrady lens distortion (`k1`, `k2`, `k3`, `p1`,
    /// `p2`), as in a photo problem's camera; default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distortion: Option<Distortion>,
}

/// An object as a scene file gives it: a [`SceneObject`] (`name`, `albedo`,
/// `shape`) and, optionally, `at`: the point its shape's own origin stands
/// on.
///
/// With `at` (`[x, y, z]` or a geographic point), the shape is written in
/// a frame of its own whose origin is that point and whose y axis is the
/// local vertical there (the sphere's normal over the round earth), x and z
/// turned with it along the great circle from the frame's origin: a
/// mountain 250 km away is written as if it stood at the origin, upright.
/// Without `at` the shape's coordinates are the scene's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneObjectEntry {
    /// Optional name, for messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Linear-RGB diffuse albedo, each channel in [0, 1].
    pub albedo: [f64; 3],
    /// Where the shape's origin stands (absent: the scene's origin, no turn).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<Point>,
    /// The geometry, in the frame of `at`.
    pub shape: Sdf,
}

impl From<SceneObject> for SceneObjectEntry {
    fn from(o: SceneObject) -> Self {
        SceneObjectEntry {
            name: o.name,
            albedo: o.albedo,
            at: None,
            shape: o.shape,
        }
    }
}

/// The local vertical at `p`: the sphere's normal over the round earth
/// (centre (0, −R, 0)), +y over the flat ground.
fn vertical_at(p: DVec3, earth: Earth) -> DVec3 {
    match earth {
        Earth::Flat => DVec3::Y,
        Earth::Round { radius } => (p + DVec3::new(0.0, radius, 0.0)).normalize(),
    }
}

/// `shape` written in the frame standing at `p` (origin `p`, y the local
/// vertical), in the scene's frame: turned about y × up by the angle
/// between them, then moved to `p`.
fn stand_at(shape: Sdf, p: DVec3, earth: Earth) -> Sdf {
    let up = vertical_at(p, earth);
    let axis = DVec3::Y.cross(up);
    let s = axis.length();
    let shape = if s > 0.0 {
        Sdf::rotate(axis, s.atan2(up.y).to_degrees(), shape)
    } else {
        shape
    };
    if p == DVec3::ZERO {
        shape
    } else {
        Sdf::translate(p, shape)
    }
}

/// A checkerboard on the ground.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckerSpec {
    /// Side of one square (metres).
    pub size: f64,
    /// Albedo of the two kinds of squares (linear RGB, each in [0, 1]).
    pub colors: [[f64; 3]; 2],
}

/// The `ground` section as written: exactly one of `albedo` and `checker`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroundSpec {
    /// Uniform albedo.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub albedo: Option<[f64; 3]>,
    /// Checkerboard albedo.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checker: Option<CheckerSpec>,
}

/// The `sun` section as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunSpec {
    /// Elevation above the horizon (degrees, −90 … 90).
    pub elevation: f64,
    /// Azimuth (degrees), from +z toward +x.
    pub azimuth: f64,
    /// Irradiance on a surface facing the sun (linear units).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub irradiance: Option<f64>,
    /// Colour (linear RGB, multiplies the irradiance; default white).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f64; 3]>,
}

impl Default for SunSpec {
    fn default() -> Self {
        SunSpec {
            elevation: 40.0,
            azimuth: 135.0,
            irradiance: None,
            color: None,
        }
    }
}

/// The `sky` section as written: a tagged model, so that a physical sky can be
/// added as another `type` without touching existing files.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum SkySpec {
    /// Blend from `horizon` (elevation 0) to `zenith` (elevation 90°).
    Gradient {
        /// Radiance straight up (linear RGB, ≥ 0).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        zenith: Option<[f64; 3]>,
        /// Radiance at the horizon (linear RGB, ≥ 0); also below it.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        horizon: Option<[f64; 3]>,
    },
    /// Rayleigh and Mie single scattering with ozone, the sun's disc and
    /// stars ([`crate::render::sky`]).
    Physical {
        /// Multiplies the molecular density (default 1).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rayleigh_scale: Option<f64>,
        /// Multiplies the aerosol density: haze (default 1).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mie_scale: Option<f64>,
        /// Ozone absorption (default true).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        ozone: Option<bool>,
        /// Draw the sun's disc (default true).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sun_disc: Option<bool>,
        /// Stars at night (default true).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        stars: Option<bool>,
        /// Multiplies the stars' flux (default 1).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        star_brightness: Option<f64>,
    },
}

/// The `trace` section as written.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneTraceSpec {
    /// RK4 step (metres).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// Largest arc length of a camera ray (metres).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_distance: Option<f64>,
}

/// A scene file exactly as written.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Short name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// What the picture shows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Where the local frame stands on the earth (needed by geographic
    /// points; makes the earth round).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub site: Option<Site>,
    /// The camera.
    pub camera: CameraSpec,
    /// The air, inline.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub medium: Option<Medium>,
    /// The air, read from another file's `medium` field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub medium_from: Option<PathBuf>,
    /// The ground plane y = 0, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<GroundSpec>,
    /// The round earth (absent: the flat ground).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub earth: Option<EarthSpec>,
    /// The objects.
    #[serde(default)]
    pub objects: Vec<SceneObjectEntry>,
    /// The sun.
    #[serde(default)]
    pub sun: SunSpec,
    /// The sky.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sky: Option<SkySpec>,
    /// Veiling glare of bright sources (none if absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glare: Option<GlareSpec>,
    /// Multiplies the radiance before tone mapping (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exposure: Option<f64>,
    /// Samples per pixel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples_per_pixel: Option<u32>,
    /// Integration settings.
    #[serde(default)]
    pub trace: SceneTraceSpec,
    /// Trace R, G and B through the air each at its own wavelength (real air
    /// only; default false).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dispersion: Option<bool>,
}

/// A validated pinhole camera description.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSettings {
    /// Eye position (metres).
    pub position: DVec3,
    /// Point at the image centre.
    pub look_at: DVec3,
    /// Up hint (not parallel to the view direction).
    pub up: DVec3,
    /// Vertical field of view (degrees).
    pub vertical_fov: f64,
    /// Width (pixels).
    pub width: u32,
    /// Height (pixels).
    pub height: u32,
    /// Roll and lens distortion (none by default).
    pub lens: Lens,
}

/// A scene camera's roll and lens distortion, in the photo camera's terms
/// (`docs/photo.md`): the focal length in pixels is (height / 2) /
/// tan(vertical_fov / 2) and the principal point the image's centre.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lens {
    /// Roll, degrees (clockwise as one looks through the camera).
    pub roll: f64,
    /// Brown–Conrady k1, k2, k3, p1, p2.
    pub distortion: [f64; 5],
}

impl Lens {
    /// Whether the lens is the plain pinhole (no roll, no distortion).
    pub fn is_pinhole(&self) -> bool {
        self.roll == 0.0 && self.distortion.iter().all(|&k| k == 0.0)
    }

    /// Whether every point of the border of a `width` × `height` image with
    /// a vertical field of view of `fov` degrees has a ray (the distortion
    /// can be undone there: Newton's method converges), checked at 65
    /// points a side. Undistortion depends on f, the principal point and
    /// the coefficients alone, so the camera's orientation is left at the
    /// identity.
    pub fn covers(&self, width: u32, height: u32, fov: f64) -> bool {
        use crate::math::V3;
        if self.distortion.iter().all(|&k| k == 0.0) {
            return true;
        }
        let (w, h) = (width as f64, height as f64);
        let camera = crate::photo::camera::Camera {
            f: 0.5 * h / (0.5 * fov.to_radians()).tan(),
            c: [0.5 * (w - 1.0), 0.5 * (h - 1.0)],
            dist: self.distortion,
            axis: V3::new(0.0, 0.0, 1.0),
            right: V3::new(1.0, 0.0, 0.0),
            up: V3::new(0.0, 1.0, 0.0),
        };
        let n = 64;
        (0..=n).all(|i| {
            let t = i as f64 / n as f64;
            [[t * w, 0.0], [t * w, h], [0.0, t * h], [w, t * h]]
                .iter()
                .all(|p| camera.undistort([p[0] - 0.5, p[1] - 0.5]).is_some())
        })
    }
}

/// Albedo of the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GroundAlbedo {
    /// The same everywhere.
    Uniform([f64; 3]),
    /// Squares of side `size` alternating between two colours.
    Checker {
        /// Side (metres).
        size: f64,
        /// The two colours.
        colors: [[f64; 3]; 2],
    },
}

impl GroundAlbedo {
    /// The albedo at the ground point (x, z).
    #[inline]
    pub fn at(&self, x: f64, z: f64) -> [f64; 3] {
        match self {
            GroundAlbedo::Uniform(a) => *a,
            GroundAlbedo::Checker { size, colors } => {
                let i = (x / size).floor() as i64 + (z / size).floor() as i64;
                colors[i.rem_euclid(2) as usize]
            }
        }
    }
}

/// The validated sun.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit vector toward the sun.
    pub direction: DVec3,
    /// Irradiance × colour (linear RGB).
    pub irradiance: [f64; 3],
}

/// A validated scene: everything the renderer needs, nothing left to check.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Where it was read from (for messages; empty for scenes built in code).
    pub source: PathBuf,
    /// Files the scene read besides itself (`medium_from`), so that an output
    /// never overwrites them.
    pub inputs: Vec<PathBuf>,
    /// Short name.
    pub name: String,
    /// What the picture shows.
    pub description: String,
    /// The camera.
    pub camera: CameraSettings,
    /// The air (valid per `docs/model.md`).
    pub medium: Medium,
    /// The ground, if any.
    pub ground: Option<GroundAlbedo>,
    /// The shape of the ground and of the air's layers: the plane y = 0 or
    /// the sphere ([`Earth`]).
    pub earth: Earth,
    /// The objects (validated).
    pub objects: Vec<SceneObject>,
    /// The sun.
    pub sun: Sun,
    /// The sky model, as written (validated).
    pub sky: SkySpec,
    /// Veiling glare, if on.
    pub glare: Option<AngularGlare>,
    /// Multiplies the radiance before tone mapping.
    pub exposure: f64,
    /// Samples per pixel (≥ 1).
    pub samples_per_pixel: u32,
    /// RK4 step (metres, > 0).
    pub step: f64,
    /// Trace R, G and B at their own wavelengths
    /// ([`crate::render::dispersion::CHANNEL_WAVELENGTHS`]); only for real air.
    pub dispersion: bool,
    /// Largest arc length of a camera ray (metres, > 0).
    pub max_distance: f64,
}

fn check_rgb(path: &Path, field: &str, c: [f64; 3], upper: Option<f64>) -> Result<()> {
    for (i, v) in c.iter().enumerate() {
        let bad = !v.is_finite() || *v < 0.0 || upper.is_some_and(|u| *v > u);
        if bad {
            let range = match upper {
                Some(u) => format!("in [0, {u}]"),
                None => "a finite number ≥ 0".to_string(),
            };
            return Err(Error::input(
                path,
                format!("{field}[{i}]"),
                format!("must be {range}, got {v}"),
            ));
        }
    }
    Ok(())
}

fn check_finite3(path: &Path, field: &str, c: [f64; 3]) -> Result<DVec3> {
    for (i, v) in c.iter().enumerate() {
        if !v.is_finite() {
            return Err(Error::input(
                path,
                format!("{field}[{i}]"),
                format!("must be a finite number, got {v}"),
            ));
        }
    }
    Ok(DVec3::from_array(c))
}

fn positive(path: &Path, field: &str, v: f64) -> Result<f64> {
    crate::validate::positive(field, v).map_err(|e| e.in_file(path))
}

/// The `roll` and `distortion` of a camera section, checked finite.
fn lens_of(spec: &CameraSpec, path: &Path) -> Result<Lens> {
    let roll = spec.roll.unwrap_or(0.0);
    if !(roll.is_finite() && roll.abs() <= 180.0) {
        return Err(Error::input(
            path,
            "camera.roll",
            format!("must be a number of degrees in [-180, 180], got {roll}"),
        ));
    }
    let d = spec.distortion.unwrap_or_default();
    let distortion = [d.k1, d.k2, d.k3, d.p1, d.p2];
    for (name, v) in ["k1", "k2", "k3", "p1", "p2"].iter().zip(distortion) {
        if !v.is_finite() {
            return Err(Error::input(
                path,
                format!("camera.distortion.{name}"),
                format!("must be a finite number, got {v}"),
            ));
        }
    }
    Ok(Lens { roll, distortion })
}

impl CameraSettings {
    /// Checks a camera section of a file without a site over the flat
    /// ground; errors name `camera.<field>` in `path`.
    pub fn from_spec(spec: &CameraSpec, path: &Path) -> Result<CameraSettings> {
        CameraSettings::from_spec_on(spec, None, Earth::Flat, path)
    }

    /// Checks a camera section, placing geographic points from `site` over
    /// `earth`; errors name `camera.<field>` in `path`.
    pub fn from_spec_on(
        spec: &CameraSpec,
        site: Option<&Site>,
        earth: Earth,
        path: &Path,
    ) -> Result<CameraSettings> {
        let radius = earth.radius();
        let place = |p: &Point, field: &str| {
            p.resolve(site, radius.unwrap_or(f64::INFINITY))
                .map_err(|e| e.within(field).in_file(path))
        };
        let position = place(&spec.position, "camera.position")?;
        let position = check_finite3(path, "camera.position", position)?;
        let look_at = match (&spec.look_at, spec.elevation, spec.azimuth) {
            (Some(p), None, None) => {
                let p = place(p, "camera.look_at")?;
                check_finite3(path, "camera.look_at", p)?
            }
            (Some(_), _, _) => {
                let field = if spec.elevation.is_some() {
                    "camera.elevation"
                } else {
                    "camera.azimuth"
                };
                return Err(Error::input(
                    path,
                    field,
                    "give the view once: `look_at`, or `elevation` and `azimuth`, not both",
                ));
            }
            (None, Some(e), Some(a)) => {
                if !(e.degrees > -90.0 && e.degrees < 90.0) {
                    return Err(Error::input(
                        path,
                        "camera.elevation",
                        format!(
                            "must lie strictly between -90 and 90 degrees, got {}",
                            e.degrees
                        ),
                    ));
                }
                let h = Horizon::at(position.to_array(), radius)
                    .map_err(|e| e.within("camera.position").in_file(path))?;
                // 10 km out, so that the frame's round-off (1e-9 m at
                // 6,000 km from the site) turns the view by < 1e-13 rad.
                position + 1e4 * DVec3::from_array(h.direction(e.degrees, a.degrees))
            }
            (None, Some(_), None) => {
                return Err(Error::input(
                    path,
                    "camera.azimuth",
                    "missing: an `elevation` needs an `azimuth` (degrees from north toward east)",
                ));
            }
            (None, None, Some(_)) => {
                return Err(Error::input(
                    path,
                    "camera.elevation",
                    "missing: an `azimuth` needs an `elevation` (degrees above the horizontal)",
                ));
            }
            (None, None, None) => {
                return Err(Error::input(
                    path,
                    "camera.look_at",
                    "missing: give `look_at` (a point), or `elevation` and `azimuth`",
                ));
            }
        };
        let up = match spec.up {
            Some(up) => check_finite3(path, "camera.up", up)?,
            None => vertical_at(position, earth),
        };
        let forward = look_at - position;
        if forward.length() == 0.0 {
            return Err(Error::input(
                path,
                "camera.look_at",
                "must differ from camera.position (the view direction is undefined)",
            ));
        }
        if up.length() == 0.0 {
            return Err(Error::input(path, "camera.up", "must be a non-zero vector"));
        }
        let f = forward.normalize();
        if f.cross(up.normalize()).length() < 1e-9 {
            return Err(Error::input(
                path,
                "camera.up",
                "must not be parallel to the view direction (look_at − position)",
            ));
        }
        let fov = spec.vertical_fov;
        if !(fov.is_finite() && fov > 0.0 && fov <= 179.0) {
            return Err(Error::input(
                path,
                "camera.vertical_fov",
                format!("must be in (0, 179] degrees, got {fov}"),
            ));
        }
        for (field, v) in [("camera.width", spec.width), ("camera.height", spec.height)] {
            if v == 0 || v > MAX_IMAGE_SIDE {
                return Err(Error::input(
                    path,
                    field,
                    format!("must be between 1 and {MAX_IMAGE_SIDE} pixels, got {v}"),
                ));
            }
        }
        let lens = lens_of(spec, path)?;
        let settings = CameraSettings {
            position,
            look_at,
            up,
            vertical_fov: fov,
            width: spec.width,
            height: spec.height,
            lens,
        };
        if !lens.covers(spec.width, spec.height, fov) {
            return Err(Error::input(
                path,
                "camera.distortion",
                "folds the image over: some pixel near the image's edge has no ray \
                 (the distortion is not monotone there); use smaller coefficients",
            ));
        }
        Ok(settings)
    }
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn load(path: &Path) -> Result<Scene> {
        Scene::parse(&read_input(path)?, path)
    }

    /// Parses and validates the text of a scene file; `path` names it in
    /// messages and anchors `medium_from`.
    pub fn parse(text: &str, path: &Path) -> Result<Scene> {
        let file: SceneFile = parse_json(text, path, "scene")?;
        Scene::from_file(file, path)
    }

    /// Validates a parsed scene file (reading `medium_from` if given).
    pub fn from_file(file: SceneFile, path: &Path) -> Result<Scene> {
        if let Some(s) = &file.site {
            s.validate().map_err(|e| e.within("site").in_file(path))?;
        }
        if let Some(spec) = &file.earth {
            spec.validate()
                .map_err(|e| e.within("earth").in_file(path))?;
        }
        let earth = earth_of(file.earth, file.site.as_ref());
        let camera = CameraSettings::from_spec_on(&file.camera, file.site.as_ref(), earth, path)?;
        let mut inputs = Vec::new();
        let medium = match (file.medium, &file.medium_from) {
            (Some(_), Some(_)) => {
                return Err(Error::input(
                    path,
                    "medium_from",
                    "give either `medium` or `medium_from`, not both",
                ));
            }
            (None, None) => {
                return Err(Error::input(
                    path,
                    "medium",
                    "missing: give the air inline (`medium`) or read it from a fit result (`medium_from`)",
                ));
            }
            (Some(m), None) => {
                m.validate().map_err(|e| e.within("medium").in_file(path))?;
                m
            }
            (None, Some(from)) => {
                let base = path.parent().unwrap_or(Path::new(""));
                let resolved = base.join(from);
                let m = medium_from_file(&resolved, path)?;
                inputs.push(resolved);
                m
            }
        };
        let ground = match file.ground {
            None => None,
            Some(GroundSpec {
                albedo: Some(_),
                checker: Some(_),
            }) => {
                return Err(Error::input(
                    path,
                    "ground.checker",
                    "give either `albedo` or `checker`, not both",
                ));
            }
            Some(GroundSpec {
                albedo: None,
                checker: None,
            }) => {
                return Err(Error::input(
                    path,
                    "ground",
                    "needs `albedo` ([r, g, b]) or `checker` ({ size, colors }); leave `ground` out for no ground",
                ));
            }
            Some(GroundSpec {
                albedo: Some(a),
                checker: None,
            }) => {
                check_rgb(path, "ground.albedo", a, Some(1.0))?;
                Some(GroundAlbedo::Uniform(a))
            }
            Some(GroundSpec {
                albedo: None,
                checker: Some(c),
            }) => {
                let size = positive(path, "ground.checker.size", c.size)?;
                for (i, col) in c.colors.iter().enumerate() {
                    check_rgb(
                        path,
                        &format!("ground.checker.colors[{i}]"),
                        *col,
                        Some(1.0),
                    )?;
                }
                Some(GroundAlbedo::Checker {
                    size,
                    colors: c.colors,
                })
            }
        };
        let objects: Vec<SceneObject> = file
            .objects
            .iter()
            .map(|o| SceneObject {
                name: o.name.clone(),
                albedo: o.albedo,
                shape: o.shape.clone(),
            })
            .collect();
        validate_objects(&objects).map_err(|e| e.within("objects").in_file(path))?;
        let radius = earth.radius().unwrap_or(f64::INFINITY);
        let mut placed = Vec::with_capacity(objects.len());
        for (i, (mut object, entry)) in objects.into_iter().zip(&file.objects).enumerate() {
            if let Some(at) = &entry.at {
                let field = format!("objects[{i}].at");
                let p = at
                    .resolve(file.site.as_ref(), radius)
                    .map_err(|e| e.within(&field).in_file(path))?;
                let p = check_finite3(path, &field, p)?;
                object.shape = stand_at(object.shape, p, earth);
            }
            placed.push(object);
        }

        let sun = {
            let s = &file.sun;
            if !(s.elevation.is_finite() && (-90.0..=90.0).contains(&s.elevation)) {
                return Err(Error::input(
                    path,
                    "sun.elevation",
                    format!("must be in [−90, 90] degrees, got {}", s.elevation),
                ));
            }
            if !s.azimuth.is_finite() {
                return Err(Error::input(
                    path,
                    "sun.azimuth",
                    format!("must be a finite number of degrees, got {}", s.azimuth),
                ));
            }
            let e = s.irradiance.unwrap_or(DEFAULT_SUN_IRRADIANCE);
            if !(e.is_finite() && e >= 0.0) {
                return Err(Error::input(
                    path,
                    "sun.irradiance",
                    format!("must be a finite number ≥ 0, got {e}"),
                ));
            }
            let color = s.color.unwrap_or([1.0, 1.0, 1.0]);
            check_rgb(path, "sun.color", color, None)?;
            let (el, az) = (s.elevation.to_radians(), s.azimuth.to_radians());
            Sun {
                direction: DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos()),
                irradiance: color.map(|c| c * e),
            }
        };
        let sky = file.sky.unwrap_or(SkySpec::Gradient {
            zenith: None,
            horizon: None,
        });
        match &sky {
            SkySpec::Gradient { zenith, horizon } => {
                if let Some(z) = zenith {
                    check_rgb(path, "sky.zenith", *z, None)?;
                }
                if let Some(h) = horizon {
                    check_rgb(path, "sky.horizon", *h, None)?;
                }
            }
            SkySpec::Physical {
                rayleigh_scale,
                mie_scale,
                star_brightness,
                ..
            } => {
                for (field, v, upper) in [
                    ("sky.rayleigh_scale", rayleigh_scale, 100.0),
                    ("sky.mie_scale", mie_scale, 1000.0),
                    ("sky.star_brightness", star_brightness, 1e12),
                ] {
                    if let Some(v) = v
                        && !(v.is_finite() && (0.0..=upper).contains(v))
                    {
                        return Err(Error::input(
                            path,
                            field,
                            format!("must be a number in [0, {upper}], got {v}"),
                        ));
                    }
                }
            }
        }
        let glare = match &file.glare {
            None => None,
            Some(g) => g.validate().map_err(|e| e.within("glare").in_file(path))?,
        };
        let exposure = positive(path, "exposure", file.exposure.unwrap_or(1.0))?;
        let samples_per_pixel = file.samples_per_pixel.unwrap_or(1);
        if samples_per_pixel == 0 || samples_per_pixel > MAX_SAMPLES_PER_PIXEL {
            return Err(Error::input(
                path,
                "samples_per_pixel",
                format!("must be between 1 and {MAX_SAMPLES_PER_PIXEL}, got {samples_per_pixel}"),
            ));
        }
        let step = positive(path, "trace.step", file.trace.step.unwrap_or(DEFAULT_STEP))?;
        let max_distance = positive(
            path,
            "trace.max_distance",
            file.trace.max_distance.unwrap_or(DEFAULT_MAX_DISTANCE),
        )?;
        let dispersion = file.dispersion.unwrap_or(false);
        if dispersion && !medium.is_dispersive() {
            return Err(Error::input(
                path,
                "dispersion",
                format!(
                    "dispersion needs real air (`medium.air`, whose refractivity depends on the wavelength), but this medium is the {} model, which has no wavelength",
                    medium.kind_name()
                ),
            ));
        }
        let name = file.name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into())
        });
        Ok(Scene {
            source: path.to_path_buf(),
            inputs,
            name,
            description: file.description.unwrap_or_default(),
            camera,
            medium,
            ground,
            earth,
            objects: placed,
            sun,
            sky,
            glare,
            exposure,
            samples_per_pixel,
            step,
            max_distance,
            dispersion,
        })
    }
}

/// Only the `medium` field of a result (or problem) file; every other field is
/// ignored, since result files carry much more.
#[derive(Deserialize)]
struct MediumOnly {
    medium: serde_json::Value,
}

/// Reads the `medium` field of `file`; errors name that file (and, when it
/// cannot be read at all, the scene's `medium_from` field).
fn medium_from_file(file: &Path, scene: &Path) -> Result<Medium> {
    let text = std::fs::read_to_string(file).map_err(|e| {
        Error::input(
            scene,
            "medium_from",
            format!("cannot read `{}`: {e}", file.display()),
        )
    })?;
    let holder: MediumOnly = parse_json(&text, file, "result")?;
    let medium: Medium = serde_path_to_error::deserialize(holder.medium).map_err(|e| {
        let field = e.path().to_string();
        let field = if field == "." {
            "medium".to_string()
        } else {
            format!("medium.{field}")
        };
        Error::input(file, field, e.into_inner().to_string())
    })?;
    medium
        .validate()
        .map_err(|e| e.within("medium").in_file(file))?;
    Ok(medium)
}
