//! A problem's photo facet (`docs/photo.md`): the `photo` section, the
//! `marks` and the camera's names in `free` and `bounds`, validated into a
//! [`PhotoSetup`] and the pairs of the target marks.
//!
//! A target mark becomes a pair whose origin is the camera, whose launch
//! direction is the pixel's ray at the starting camera, and whose weight is
//! f/|target − camera| (f in pixels): its residual is the miss as an angle
//! seen from the camera, in pixels (`geo.md`'s angle residual times f). The
//! fit's objective recomputes the direction and f from the camera's free
//! numbers at every point.

use crate::error::{Error, FieldError, Result};
use crate::geo::Site;
use crate::pair::PointPair;
use crate::photo::camera::CameraParam;
use crate::photo::exif::focal_from_exif;
use crate::photo::picture::Picture;
use crate::photo::spec::{DEFAULT_HORIZON_RANGE, ImageFacts, MarkEntry, PhotoSetup, PhotoSpec};
use crate::trace::Earth;
use std::collections::BTreeMap;
use std::path::Path;

/// The photo facet of a problem file, as read.
pub struct PhotoFields<'a> {
    /// `photo`.
    pub photo: Option<&'a PhotoSpec>,
    /// `marks`.
    pub marks: &'a [MarkEntry],
    /// `noise` (pixels).
    pub noise: Option<f64>,
    /// The camera's entries of `free`, with their index there.
    pub free: Vec<(usize, &'a str)>,
    /// The camera's entries of `bounds`.
    pub bounds: BTreeMap<&'a str, [f64; 2]>,
}

/// Validates the photo facet: `None` when the file has no `photo` (and
/// then no `marks`, no `noise` and no camera names either).
pub fn load(
    fields: PhotoFields<'_>,
    path: &Path,
    site: Option<&Site>,
    earth: Earth,
) -> Result<Option<(PhotoSetup, Vec<PointPair>)>> {
    let bad = |field: String, message: String| Error::input(path, field, message);
    let Some(photo) = fields.photo else {
        if !fields.marks.is_empty() {
            return Err(bad(
                "marks".into(),
                "marks are pixels of a photograph: give the `photo` section (its `image` and `camera`)".into(),
            ));
        }
        if fields.noise.is_some() {
            return Err(bad(
                "noise".into(),
                "a top-level `noise` is the marks' noise in pixels, for photo problems; give a pair's noise in `pairs[i].noise` or `solver.noise`".into(),
            ));
        }
        if let Some((i, name)) = fields.free.first() {
            return Err(bad(
                format!("free[{i}]"),
                format!("`{name}` is a camera parameter, but this problem has no `photo` section"),
            ));
        }
        if let Some(name) = fields.bounds.keys().next() {
            return Err(bad(
                format!("bounds.{name}"),
                "a camera parameter's bounds, but this problem has no `photo` section".into(),
            ));
        }
        return Ok(None);
    };
    if fields.marks.is_empty() {
        return Err(bad(
            "marks".into(),
            "missing: a photo problem needs at least one mark (a pixel with its `target`, or `\"horizon\": true`)".into(),
        ));
    }
    if let Some(s) = fields.noise
        && !(s.is_finite() && s > 0.0)
    {
        return Err(bad(
            "noise".into(),
            format!("must be a finite number > 0 (pixels), got {s}"),
        ));
    }
    let range = match photo.horizon_range {
        Some(r) if !(r.is_finite() && r > 0.0) => {
            return Err(bad(
                "photo.horizon_range".into(),
                format!("must be a finite number > 0 (metres), got {r}"),
            ));
        }
        Some(r) => r,
        None => DEFAULT_HORIZON_RANGE,
    };
    let image_path = path
        .parent()
        .unwrap_or_else(|| Path::new("."))
        .join(&photo.image);
    let picture = Picture::read(&image_path).map_err(|e| {
        bad(
            "photo.image".into(),
            format!("`{}`: {e}", image_path.display()),
        )
    })?;
    let exif_focal = focal_from_exif(&picture.bytes, picture.width, picture.height)
        .ok()
        .flatten()
        .map(|f| (f.pixels, f.source));
    let facts = ImageFacts {
        size: [picture.width, picture.height],
        exif_focal,
    };
    let radius = earth.radius();
    let position = match &photo.camera.position {
        Some(p) => p
            .resolve(site, radius.unwrap_or(f64::INFINITY))
            .map_err(|e| e.within("photo.camera.position").in_file(path))?,
        None => match site {
            Some(s) => s.origin(),
            None => {
                return Err(bad(
                    "photo.camera.position".into(),
                    "missing: without a `site` the camera's place must be given (`[x, y, z]`, metres)".into(),
                ));
            }
        },
    };
    if position.iter().any(|c| !c.is_finite()) {
        return Err(bad(
            "photo.camera.position".into(),
            format!("must be finite, got {position:?}"),
        ));
    }
    if earth.height(position.into()) < 0.0 {
        return Err(bad(
            "photo.camera.position".into(),
            "lies below the ground: a camera stands on or above it".into(),
        ));
    }
    let (camera, focal_note) = photo
        .camera
        .params(&facts, position, radius)
        .map_err(|e| e.within("photo.camera").in_file(path))?;

    let mut free = Vec::new();
    for (i, name) in &fields.free {
        let p: CameraParam =
            name.parse()
                .map_err(|e: crate::photo::camera::CameraParamError| {
                    bad(format!("free[{i}]"), e.to_string())
                })?;
        let usable = match p {
            CameraParam::FocalLength => photo.camera.focal_length.is_some(),
            CameraParam::HorizontalFov => photo.camera.horizontal_fov.is_some(),
            _ => true,
        };
        if !usable {
            return Err(bad(
                format!("free[{i}]"),
                format!(
                    "`{name}` is not how this camera's focal length is given: free the field the file sets (`camera.focal_length` with `sensor_width`, or `camera.horizontal_fov`)"
                ),
            ));
        }
        if free.contains(&p) {
            return Err(bad(
                format!("free[{i}]"),
                format!("`{name}` is listed twice"),
            ));
        }
        free.push(p);
    }
    let mut bounds = vec![(f64::NEG_INFINITY, f64::INFINITY); free.len()];
    for (name, &[low, high]) in &fields.bounds {
        let field = format!("bounds.{name}");
        let p: CameraParam =
            name.parse()
                .map_err(|e: crate::photo::camera::CameraParamError| {
                    bad(field.clone(), e.to_string())
                })?;
        let Some(k) = free.iter().position(|q| *q == p) else {
            return Err(bad(
                field,
                format!(
                    "`{name}` is not a free parameter; bounds apply only to parameters listed in `free`"
                ),
            ));
        };
        let start = camera.get(p);
        if low.is_nan() || high.is_nan() || low > high || !(low..=high).contains(&start) {
            return Err(bad(
                field,
                format!("[{low}, {high}] must be numbers, low ≤ high, holding the start {start}"),
            ));
        }
        bounds[k] = (low, high);
    }

    let mut marks = Vec::with_capacity(fields.marks.len());
    let mut pairs = Vec::new();
    let start = camera.at_values();
    for (i, entry) in fields.marks.iter().enumerate() {
        let within = |e: FieldError| e.within(&format!("marks[{i}]")).in_file(path);
        let mark = entry.resolve(i, &camera, site, radius).map_err(within)?;
        // Every mark's pixel, a target's or the horizon's, needs a ray.
        let ray = start.ray(mark.pixel).ok_or_else(|| {
            within(FieldError::new(
                "pixel",
                "cannot be undistorted: the distortion coefficients fold the image over before this pixel",
            ))
        })?;
        if let Some(target) = mark.target {
            let o = crate::math::V3::from(position);
            let range = (crate::math::V3::from(target) - o).norm();
            let pair = PointPair {
                origin: position,
                through: (o + ray * range).to_array(),
                target,
                weight: start.f / range,
                wavelength: None,
            };
            pair.validate_on(earth)
                .map_err(|e| within(e.within("target")))?;
            pairs.push(pair);
        } else if earth.height(position.into()) <= 0.0 {
            return Err(within(FieldError::new(
                "horizon",
                "the camera stands at sea level: it sees no sea horizon below it",
            )));
        }
        marks.push(mark);
    }
    Ok(Some((
        PhotoSetup {
            image: image_path,
            camera,
            focal_note,
            marks,
            free,
            bounds,
            horizon_range: range,
            noise: fields.noise,
        },
        pairs,
    )))
}
