//! A photo problem's `photo` section and `marks` as written, and their
//! validation into a [`PhotoSetup`] (`docs/photo.md`).
//!
//! Validation checks every field by name: exactly one focal-length form
//! (or the image's EXIF), a positive sensor width, a field of view in
//! (0, 180), finite distortion, a principal point inside the image,
//! orientation angles finite, tilt in (−90, 90); each mark's pixel inside
//! the image (±0.5 pixel: the image's edge), a target that is not behind
//! the camera, a horizon mark only over a round earth.

use super::camera::{CameraParam, CameraParams, FocalSource};
use crate::error::FieldError;
use crate::geo::{Horizon, Point, Site};
use crate::validate::finite;
use serde::{Deserialize, Serialize};

/// The `photo` section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhotoSpec {
    /// The photograph (PNG or JPEG), relative to the problem file.
    pub image: String,
    /// The camera.
    pub camera: CameraSpec,
    /// How far a ray may travel to meet the sea for a horizon mark (m,
    /// default 100,000).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizon_range: Option<f64>,
}

/// The camera as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Focal length (mm), with `sensor_width`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focal_length: Option<f64>,
    /// Sensor width (mm), with `focal_length`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor_width: Option<f64>,
    /// Horizontal field of view (degrees), instead of the focal length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizontal_fov: Option<f64>,
    /// Principal point (pixels); default the image's centre.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub principal_point: Option<[f64; 2]>,
    /// Brown–Conrady coefficients (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distortion: Option<Distortion>,
    /// Azimuth of the optical axis (degrees from north toward east).
    pub azimuth: f64,
    /// Elevation of the optical axis (degrees, up positive).
    pub tilt: f64,
    /// Roll about the axis (degrees, clockwise as one looks through).
    #[serde(default)]
    pub roll: f64,
    /// Where the camera stands (default: the site).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<Point>,
}

/// OpenCV's Brown–Conrady coefficients.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Distortion {
    /// Radial r².
    #[serde(default)]
    pub k1: f64,
    /// Radial r⁴.
    #[serde(default)]
    pub k2: f64,
    /// Radial r⁶.
    #[serde(default)]
    pub k3: f64,
    /// Tangential p1.
    #[serde(default)]
    pub p1: f64,
    /// Tangential p2.
    #[serde(default)]
    pub p2: f64,
}

/// One mark as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarkEntry {
    /// What it is (default `mark N`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The marked pixel (u right, v down).
    pub pixel: [f64; 2],
    /// The known point seen there.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target: Option<Point>,
    /// The pixel lies on the apparent sea horizon.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub horizon: bool,
}

/// A validated mark.
#[derive(Clone, Debug, PartialEq)]
pub struct Mark {
    /// Its name.
    pub name: String,
    /// The marked pixel.
    pub pixel: [f64; 2],
    /// The target in the local frame, or `None` for a horizon mark.
    pub target: Option<[f64; 3]>,
}

/// The photo side of a validated problem.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotoSetup {
    /// The image's path (as resolved against the problem file).
    pub image: std::path::PathBuf,
    /// The camera's numbers, place and frame.
    pub camera: CameraParams,
    /// Where f came from, in words (for reports).
    pub focal_note: String,
    /// The marks, in file order.
    pub marks: Vec<Mark>,
    /// The free camera parameters, in the order of `free`.
    pub free: Vec<CameraParam>,
    /// Their bounds.
    pub bounds: Vec<(f64, f64)>,
    /// Horizon marks' range limit (m).
    pub horizon_range: f64,
    /// The marks' noise σ (pixels), if given.
    pub noise: Option<f64>,
}

/// The default `horizon_range` (m).
pub const DEFAULT_HORIZON_RANGE: f64 = 100_000.0;

/// What the image tells: its size and, when its EXIF has one, the focal
/// length in pixels with words on its source.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageFacts {
    /// Width and height (pixels).
    pub size: [u32; 2],
    /// f from EXIF (pixels) and where it came from.
    pub exif_focal: Option<(f64, String)>,
}

impl CameraSpec {
    /// The camera's numbers at `position` with the image's facts; errors
    /// name the field under `photo.camera`.
    pub fn params(
        &self,
        facts: &ImageFacts,
        position: [f64; 3],
        radius: Option<f64>,
    ) -> Result<(CameraParams, String), FieldError> {
        let [w, h] = facts.size.map(f64::from);
        let mut values = [0.0; 12];
        let set = |values: &mut [f64; 12], p: CameraParam, v: f64| -> Result<(), FieldError> {
            values[p.index()] = finite(p.path(), v)?;
            Ok(())
        };
        let (focal, note) = match (self.focal_length, self.sensor_width, self.horizontal_fov) {
            (Some(_), _, Some(_)) => {
                return Err(FieldError::new(
                    "horizontal_fov",
                    "give the focal length once: `focal_length` with `sensor_width`, or `horizontal_fov`, not both",
                ));
            }
            (Some(fl), Some(sw), None) => {
                if !(fl.is_finite() && fl > 0.0) {
                    return Err(FieldError::new(
                        "focal_length",
                        format!("must be a finite number > 0 (mm), got {fl}"),
                    ));
                }
                if !(sw.is_finite() && sw > 0.0) {
                    return Err(FieldError::new(
                        "sensor_width",
                        format!("must be a finite number > 0 (mm), got {sw}"),
                    ));
                }
                values[CameraParam::FocalLength.index()] = fl;
                (
                    FocalSource::Millimetres { sensor_width: sw },
                    format!("focal_length {fl} mm on a sensor {sw} mm wide"),
                )
            }
            (Some(_), None, None) => {
                return Err(FieldError::new(
                    "sensor_width",
                    "missing: a `focal_length` (mm) needs the sensor's width (mm) to make pixels of it",
                ));
            }
            (None, Some(_), None) => {
                return Err(FieldError::new(
                    "focal_length",
                    "missing: a `sensor_width` is only used with a `focal_length` (mm)",
                ));
            }
            (None, Some(_), Some(_)) => {
                return Err(FieldError::new(
                    "sensor_width",
                    "is only used with `focal_length`, not with `horizontal_fov`",
                ));
            }
            (None, None, Some(fov)) => {
                if !(fov > 0.0 && fov < 180.0) {
                    return Err(FieldError::new(
                        "horizontal_fov",
                        format!("must lie strictly between 0 and 180 degrees, got {fov}"),
                    ));
                }
                values[CameraParam::HorizontalFov.index()] = fov;
                (FocalSource::FieldOfView, format!("horizontal_fov {fov}°"))
            }
            (None, None, None) => match &facts.exif_focal {
                Some((f, source)) => (FocalSource::Pixels(*f), source.clone()),
                None => {
                    return Err(FieldError::new(
                        "focal_length",
                        "missing, and the image's EXIF has no usable focal length: give `focal_length` (mm) with `sensor_width` (mm), or `horizontal_fov` (degrees)",
                    ));
                }
            },
        };
        let [cx, cy] = self
            .principal_point
            .unwrap_or([(w - 1.0) / 2.0, (h - 1.0) / 2.0]);
        for (k, (v, size)) in [(cx, w), (cy, h)].into_iter().enumerate() {
            if !(v.is_finite() && v >= -0.5 && v <= size - 0.5) {
                return Err(FieldError::new(
                    format!("principal_point[{k}]"),
                    format!(
                        "must lie inside the image (−0.5 … {} pixels), got {v}",
                        size - 0.5
                    ),
                ));
            }
        }
        values[CameraParam::Cx.index()] = cx;
        values[CameraParam::Cy.index()] = cy;
        let d = self.distortion.unwrap_or_default();
        for (p, v) in [
            (CameraParam::K1, d.k1),
            (CameraParam::K2, d.k2),
            (CameraParam::K3, d.k3),
            (CameraParam::P1, d.p1),
            (CameraParam::P2, d.p2),
        ] {
            set(&mut values, p, v)?;
        }
        set(&mut values, CameraParam::Azimuth, self.azimuth)?;
        set(&mut values, CameraParam::Roll, self.roll)?;
        if !(self.tilt > -90.0 && self.tilt < 90.0) {
            return Err(FieldError::new(
                "tilt",
                format!(
                    "must lie strictly between -90 and 90 degrees, got {}",
                    self.tilt
                ),
            ));
        }
        values[CameraParam::Tilt.index()] = self.tilt;
        let frame = Horizon::at(position, radius).map_err(|e| e.within("position"))?;
        let params = CameraParams {
            values,
            focal,
            size: facts.size,
            position,
            frame,
        };
        Ok((params, note))
    }
}

impl MarkEntry {
    /// The mark in the local frame, checked against the camera (`i`: its
    /// index, for the default name).
    pub fn resolve(
        &self,
        i: usize,
        camera: &CameraParams,
        site: Option<&Site>,
        radius: Option<f64>,
    ) -> Result<Mark, FieldError> {
        let [w, h] = camera.size.map(f64::from);
        for (k, (v, size)) in [(self.pixel[0], w), (self.pixel[1], h)]
            .into_iter()
            .enumerate()
        {
            if !(v.is_finite() && v >= -0.5 && v <= size - 0.5) {
                return Err(FieldError::new(
                    format!("pixel[{k}]"),
                    format!(
                        "lies outside the image ({} × {} pixels: {} from −0.5 to {}), got {v}",
                        camera.size[0],
                        camera.size[1],
                        if k == 0 { "u" } else { "v" },
                        size - 0.5
                    ),
                ));
            }
        }
        let name = self.name.clone().unwrap_or_else(|| format!("mark {i}"));
        let target = match (&self.target, self.horizon) {
            (Some(_), true) => {
                return Err(FieldError::new(
                    "horizon",
                    "a mark is either on a target or on the horizon, not both: remove `target` or `horizon`",
                ));
            }
            (None, false) => {
                return Err(FieldError::new(
                    "target",
                    "missing: give the point seen at this pixel (`[x, y, z]` or a geographic point), or `\"horizon\": true`",
                ));
            }
            (None, true) => {
                if radius.is_none() {
                    return Err(FieldError::new(
                        "horizon",
                        "a horizon mark needs the round earth (a `site` or `earth`): over the flat ground there is no sea horizon",
                    ));
                }
                None
            }
            (Some(p), false) => {
                let t = p
                    .resolve(site, radius.unwrap_or(f64::INFINITY))
                    .map_err(|e| e.within("target"))?;
                let o = camera.position;
                let d: [f64; 3] = std::array::from_fn(|k| t[k] - o[k]);
                let range = d[0].hypot(d[1]).hypot(d[2]);
                if !(range > 1e-3 && range < 1e12) {
                    return Err(FieldError::new(
                        "target",
                        format!(
                            "lies {range} m from the camera: a target must be between 1 mm and 10⁹ km away"
                        ),
                    ));
                }
                let c = camera.at_values();
                let along = d[0] * c.axis.x + d[1] * c.axis.y + d[2] * c.axis.z;
                if along <= 0.0 {
                    return Err(FieldError::new(
                        "target",
                        "lies behind the camera (on the far side of the plane through it, square to its axis): check the target or `camera.azimuth`",
                    ));
                }
                Some(t)
            }
        };
        Ok(Mark {
            name,
            pixel: self.pixel,
            target,
        })
    }
}
