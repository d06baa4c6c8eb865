//! What a photo fit reports beside the air (`docs/photo.md`, "What comes
//! out"): each mark's residual in pixels, where the air puts its target
//! (the predicted pixel), where straight rays would, the apparent horizon
//! across the image, and the RMS residual.
//!
//! # Predicted pixels
//!
//! The pixel whose ray, traced through the air, reaches the target: Gauss–
//! Newton on the launch direction d (two angles square to d), with ∂e/∂d
//! from a trace in dual numbers; it stops when the miss is below 1e-12 of
//! the range (at most 12 steps), then projects d through the camera. A
//! target no launch direction reaches (behind a hill of air, occluded) has
//! no predicted pixel. The horizon across the image: for each of 64
//! columns, the v whose ray's elevation is the apparent horizon's, by
//! bisection on v (the camera's elevation falls monotonically with v for
//! tilts and rolls a photo has).

use super::objective::Objective;
use super::objective::{eps2, square_to, with_eps};
use crate::math::V3;
use crate::medium::PairFields;
use crate::pair::PointPair;
use crate::photo::camera::Camera;
use crate::trace::{TraceOptions, trace_launched};
use num_dual::DualSVec64;
use serde::{Deserialize, Serialize};

type D2 = DualSVec64<2>;

/// One mark in a photo result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MarkReport {
    /// Its name.
    pub name: String,
    /// The marked pixel.
    pub pixel: [f64; 2],
    /// A horizon mark.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub horizon: bool,
    /// Where the fitted air and camera put its target (for a horizon mark:
    /// the apparent horizon in its column); `None` where no ray reaches it.
    pub predicted: Option<[f64; 2]>,
    /// Where straight rays would put its target (none for horizon marks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub straight: Option<[f64; 2]>,
    /// Its residual (pixels): the angle miss times f for a target mark (the
    /// norm of the residual's three components), the elevation difference
    /// times f for a horizon mark.
    pub residual: f64,
}

/// The photo section of a fit result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhotoReport {
    /// The image.
    pub image: String,
    /// Its width and height.
    pub size: [u32; 2],
    /// The focal length (pixels) and where it came from.
    pub focal_pixels: f64,
    /// Where f came from.
    pub focal_source: String,
    /// The camera's numbers by path (every one, fitted or not).
    pub camera: Vec<(String, f64)>,
    /// The marks.
    pub marks: Vec<MarkReport>,
    /// √(Σ residual² / number of pixel coordinates marked) (pixels): two
    /// per target mark, one per horizon mark.
    pub rms_pixels: f64,
    /// The apparent horizon's elevation (degrees), when the earth is round.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizon_elevation: Option<f64>,
    /// The apparent horizon across the image (pixels), left to right.
    pub horizon_line: Vec<[f64; 2]>,
}

/// The report of a photo problem's objective at `x` (medium and camera).
pub fn photo_report(objective: &Objective, x: &[f64], image: &str) -> Option<PhotoReport> {
    let photo = objective.photo()?;
    let n = objective.free().len();
    let camera_x = &x[n..];
    let camera = photo.camera_at(camera_x);
    let medium = objective.medium(x);
    let pairs = objective.pairs_at(x);
    let (r, _) = objective.residuals(x);
    let fields = PairFields::new(
        &medium.map(|_, v| D2::from(v)),
        pairs.iter().map(|p| p.wavelength),
    );
    let options = objective.options();
    let round = options.earth.radius().is_some();
    let e_h = round.then(|| photo.horizon_elevation_at(&medium));
    let params = photo.params();
    let mut marks = Vec::new();
    let mut pair = 0;
    let mut horizon_row = 3 * pairs.len();
    let setup_marks = photo.marks();
    for (name, pixel, is_target) in setup_marks {
        if is_target {
            let p = &pairs[pair];
            let residual = (0..3).map(|c| r[3 * pair + c].powi(2)).sum::<f64>().sqrt();
            let predicted = shoot(fields.of(pair), p, options).and_then(|d| camera.project(d));
            let straight = camera.project(p.target() - p.origin());
            marks.push(MarkReport {
                name,
                pixel,
                horizon: false,
                predicted,
                straight,
                residual,
            });
            pair += 1;
        } else {
            let residual = r[horizon_row].abs();
            horizon_row += 1;
            let predicted = e_h
                .and_then(|e| horizon_v(&camera, photo.up(), e, pixel[0], params.size))
                .map(|v| [pixel[0], v]);
            marks.push(MarkReport {
                name,
                pixel,
                horizon: true,
                predicted,
                straight: None,
                residual,
            });
        }
    }
    // Per pixel coordinate: a target mark's miss has two (its third, along
    // the ray, is ~0), a horizon mark's one.
    let coordinates: usize = marks.iter().map(|m| if m.horizon { 1 } else { 2 }).sum();
    let rms = (marks.iter().map(|m| m.residual * m.residual).sum::<f64>()
        / coordinates.max(1) as f64)
        .sqrt();
    let horizon_line = match e_h {
        Some(e) => (0..=64)
            .filter_map(|k| {
                let u = -0.5 + params.size[0] as f64 * k as f64 / 64.0;
                horizon_v(&camera, photo.up(), e, u, params.size).map(|v| [u, v])
            })
            .collect(),
        None => Vec::new(),
    };
    let values = photo.values(camera_x);
    Some(PhotoReport {
        image: image.to_string(),
        size: params.size,
        focal_pixels: camera.f,
        focal_source: photo.focal_note().to_string(),
        camera: crate::photo::camera::CameraParam::ALL
            .iter()
            .filter(|p| photo.uses(**p))
            .map(|p| (p.to_string(), values[p.index()]))
            .collect(),
        marks,
        rms_pixels: rms,
        horizon_elevation: e_h.map(f64::to_degrees),
        horizon_line,
    })
}

/// The launch direction whose ray through `field` reaches `pair`'s target
/// (see the module doc), or `None`.
fn shoot<F: crate::medium::IndexField<D2>>(
    field: &F,
    pair: &PointPair,
    options: &TraceOptions,
) -> Option<V3> {
    let plane = pair.plane_on(options.earth);
    let range = (pair.target() - pair.origin()).norm();
    let mut d = pair.direction();
    for _ in 0..12 {
        let (b1, b2) = square_to(d);
        let launch = V3::new(
            with_eps(D2::from(d.x), b1.x, b2.x),
            with_eps(D2::from(d.y), b1.y, b2.y),
            with_eps(D2::from(d.z), b1.z, b2.z),
        );
        let t = trace_launched(field, pair.origin(), launch, Some(&plane), options, None);
        if t.unreachable {
            return None;
        }
        let e = t.endpoint.val();
        let miss = e - pair.target();
        if miss.norm() <= 1e-12 * range {
            return Some(d);
        }
        let j = [t.endpoint.x, t.endpoint.y, t.endpoint.z].map(eps2);
        // Normal equations of the 3 × 2 system J·δ = −miss.
        let mut a = [[0.0; 2]; 2];
        let mut b = [0.0; 2];
        let m = [miss.x, miss.y, miss.z];
        for c in 0..3 {
            for p in 0..2 {
                b[p] -= j[c][p] * m[c];
                for q in 0..2 {
                    a[p][q] += j[c][p] * j[c][q];
                }
            }
        }
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        if !(det.is_finite() && det != 0.0) {
            return None;
        }
        let s1 = (b[0] * a[1][1] - b[1] * a[0][1]) / det;
        let s2 = (b[1] * a[0][0] - b[0] * a[1][0]) / det;
        d = (d + b1 * s1 + b2 * s2).normalized();
    }
    None
}

/// The v in column `u` whose ray's elevation is `e` (radians), or `None`
/// when the column does not cross it inside the image (±half the height).
fn horizon_v(camera: &Camera, up: V3, e: f64, u: f64, size: [u32; 2]) -> Option<f64> {
    let h = size[1] as f64;
    let elev = |v: f64| {
        camera
            .ray([u, v])
            .map(|d| d.dot(up).clamp(-1.0, 1.0).asin() - e)
    };
    let (mut lo, mut hi) = (-0.5 - 0.5 * h, h - 0.5 + 0.5 * h);
    let (flo, fhi) = (elev(lo)?, elev(hi)?);
    if flo.signum() == fhi.signum() {
        return None;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        let fm = elev(mid)?;
        if fm.signum() == flo.signum() {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-9 {
            break;
        }
    }
    let v = 0.5 * (lo + hi);
    (-0.5..=h - 0.5).contains(&v).then_some(v)
}
