//! The objective's photo facet: a camera whose free numbers follow the
//! medium's in x (`docs/photo.md`).
//!
//! # Residuals
//!
//! - A **target mark** is a pair launched along its pixel's ray, weighted
//!   f/|target − camera|: r = f·(e − t)/|t − o|, pixels (f the focal length
//!   in pixels at x).
//! - A **horizon mark** is one row: r = f·(elevation of its pixel's ray −
//!   e_h), e_h the apparent horizon of the air at x
//!   ([`crate::photo::horizon`]).
//!
//! # Jacobian, exact
//!
//! A target mark's camera columns: ∂r/∂θ = (∂f/∂θ/f)·r + w·(∂e/∂d)(∂d/∂θ).
//! ∂d/∂θ and ∂f/∂θ come from the camera evaluated in dual numbers seeded on
//! θ (the undistortion's implicit derivative included); ∂e/∂d from one
//! trace of the pair's ray with its launch direction in dual numbers along
//! two unit vectors square to d (∂d/∂θ is square to d, the direction being
//! unit), through the same discrete steps as the value
//! ([`crate::trace::trace_launched`]). A horizon mark's medium columns are
//! −f·∂e_h/∂p (the envelope theorem at the minimum of n·r, evaluated in
//! dual numbers), its camera columns ∂f/∂θ·(elevation − e_h) + f·∂elev/∂θ.
//! `tests/photo.rs` checks every column against central differences.

use crate::math::{Real, V3};
use crate::medium::{IndexField, Medium, PairFields, Param};
use crate::pair::PointPair;
use crate::photo::camera::{Camera, CameraParam, CameraParams, FocalSource};
use crate::photo::horizon::apparent_horizon;
use crate::photo::spec::PhotoSetup;
use crate::trace::{Earth, TraceOptions, trace_launched};
use nalgebra::{DMatrix, DVector};
use num_dual::{DualNum, DualSVec64};
use rayon::prelude::*;

type D1 = DualSVec64<1>;
type D2 = DualSVec64<2>;

/// The derivative part of a one-seed dual number.
pub fn eps1(t: D1) -> f64 {
    t.eps.unwrap_generic(nalgebra::Const::<1>, nalgebra::U1)[0]
}

/// The derivative parts of a two-seed dual number.
pub fn eps2(t: D2) -> [f64; 2] {
    let e = t.eps.unwrap_generic(nalgebra::Const::<2>, nalgebra::U1);
    [e[0], e[1]]
}

/// The camera of a photo problem as the objective sees it.
#[derive(Clone, Debug)]
pub struct PhotoPart {
    camera: CameraParams,
    free: Vec<CameraParam>,
    /// Per pair (target mark, in pair order): its pixel.
    pixels: Vec<[f64; 2]>,
    /// Per horizon mark: its pixel.
    horizon: Vec<[f64; 2]>,
    /// Every mark: name, pixel, whether it has a target.
    marks: Vec<(String, [f64; 2], bool)>,
    /// Where f came from.
    focal_note: String,
    /// The sea's radius (m; ∞ over the flat ground, which has no horizon
    /// marks).
    radius: f64,
    /// The camera's height above the sea (m).
    height: f64,
}

impl PhotoPart {
    /// The part of a validated photo problem whose target marks are
    /// `pairs`.
    pub fn new(setup: &PhotoSetup, pairs: &[PointPair], earth: Earth) -> PhotoPart {
        let pixels: Vec<[f64; 2]> = setup
            .marks
            .iter()
            .filter(|m| m.target.is_some())
            .map(|m| m.pixel)
            .collect();
        debug_assert_eq!(pixels.len(), pairs.len());
        PhotoPart {
            camera: setup.camera.clone(),
            free: setup.free.clone(),
            pixels,
            horizon: setup
                .marks
                .iter()
                .filter(|m| m.target.is_none())
                .map(|m| m.pixel)
                .collect(),
            marks: setup
                .marks
                .iter()
                .map(|m| (m.name.clone(), m.pixel, m.target.is_some()))
                .collect(),
            focal_note: setup.focal_note.clone(),
            radius: earth.radius().unwrap_or(f64::INFINITY),
            height: earth.height(V3::from(setup.camera.position)),
        }
    }

    /// The free camera numbers, in x's order after the medium's.
    pub fn free(&self) -> &[CameraParam] {
        &self.free
    }

    /// Their starting values.
    pub fn start(&self) -> Vec<f64> {
        self.free.iter().map(|p| self.camera.get(*p)).collect()
    }

    /// The number of horizon marks (one residual each).
    pub fn horizon_len(&self) -> usize {
        self.horizon.len()
    }

    /// The camera's numbers with the free ones at `x`.
    pub fn values(&self, x: &[f64]) -> [f64; 12] {
        let mut v = self.camera.values;
        for (p, xi) in self.free.iter().zip(x) {
            v[p.index()] = *xi;
        }
        v
    }

    /// The camera at `x` (its free numbers).
    pub fn camera_at(&self, x: &[f64]) -> Camera {
        self.camera.camera(&self.values(x))
    }

    /// The camera's numbers and frame.
    pub fn params(&self) -> &CameraParams {
        &self.camera
    }

    /// The camera at `x` in dual numbers seeded on free number `k`.
    fn seeded(&self, x: &[f64], k: usize) -> Camera<D1> {
        let mut v: [D1; 12] = self.values(x).map(D1::from_re);
        let i = self.free[k].index();
        v[i] = v[i].derivative(0);
        self.camera.camera(&v)
    }

    /// The pairs at `x`: each launched along its pixel's ray, weighted
    /// f/range. A pixel the camera cannot undistort gets a NaN weight (an
    /// infinite cost: the solver steps back).
    pub fn pairs_at(&self, base: &[PointPair], x: &[f64]) -> Vec<PointPair> {
        let camera = self.camera_at(x);
        base.iter()
            .zip(&self.pixels)
            .map(|(pair, px)| {
                let o = pair.origin();
                let range = (pair.target() - o).norm();
                let mut p = *pair;
                match camera.ray(*px) {
                    Some(d) => {
                        p.through = (o + d * range).to_array();
                        p.weight = camera.f / range;
                    }
                    None => p.weight = f64::NAN,
                }
                p
            })
            .collect()
    }

    /// The local up at the camera.
    pub fn up(&self) -> V3 {
        V3::from(self.camera.frame.up)
    }

    /// The apparent horizon's elevation in `medium` (radians).
    pub fn horizon_elevation_at(&self, medium: &Medium) -> f64 {
        self.horizon_elevation(medium, medium)
    }

    /// The marks in file order: name, pixel, whether it has a target.
    pub fn marks(&self) -> Vec<(String, [f64; 2], bool)> {
        self.marks.clone()
    }

    /// Where f came from, in words.
    pub fn focal_note(&self) -> &str {
        &self.focal_note
    }

    /// Whether the camera uses `p` (the focal form the file chose).
    pub fn uses(&self, p: CameraParam) -> bool {
        match p {
            CameraParam::FocalLength => {
                matches!(self.camera.focal, FocalSource::Millimetres { .. })
            }
            CameraParam::HorizontalFov => matches!(self.camera.focal, FocalSource::FieldOfView),
            _ => true,
        }
    }

    /// The apparent horizon's elevation in `medium` (radians), in `T`.
    fn horizon_elevation<T: Real>(&self, plain: &Medium, medium: &Medium<T>) -> T {
        let f = plain.field();
        let ft = medium.field();
        apparent_horizon(
            |h| f.delta(V3::new(0.0, h, 0.0)),
            |h| ft.delta(V3::new(T::cst(0.0), T::cst(h), T::cst(0.0))),
            self.radius,
            self.height,
        )
    }

    /// The horizon marks' residuals at `medium` and camera `x` (pixels).
    pub fn horizon_residuals(&self, medium: &Medium, x: &[f64]) -> Vec<f64> {
        if self.horizon.is_empty() {
            return Vec::new();
        }
        let e_h: f64 = self.horizon_elevation(medium, medium);
        let camera = self.camera_at(x);
        let up = self.up();
        self.horizon
            .iter()
            .map(|px| match camera.ray(*px) {
                Some(d) => camera.f * (d.dot(up).clamp(-1.0, 1.0).asin() - e_h),
                None => f64::NAN,
            })
            .collect()
    }

    /// The horizon marks' residuals and rows of the Jacobian (the medium's
    /// `free` columns, then the camera's).
    pub fn horizon_rows(
        &self,
        medium: &Medium,
        free: &[Param],
        x: &[f64],
    ) -> (Vec<f64>, Vec<Vec<f64>>) {
        if self.horizon.is_empty() {
            return (Vec::new(), Vec::new());
        }
        let r = self.horizon_residuals(medium, x);
        let e_h: f64 = self.horizon_elevation(medium, medium);
        // ∂e_h/∂p per medium parameter.
        let de_h: Vec<f64> = free
            .iter()
            .map(|p| {
                let seeded: Medium<D1> = medium.map(|q, v| {
                    if q == *p {
                        D1::from_re(v).derivative(0)
                    } else {
                        D1::from_re(v)
                    }
                });
                eps1(self.horizon_elevation(medium, &seeded))
            })
            .collect();
        let camera = self.camera_at(x);
        let up = self.up();
        let seeded: Vec<Camera<D1>> = (0..self.free.len()).map(|k| self.seeded(x, k)).collect();
        let rows = self
            .horizon
            .iter()
            .map(|px| {
                let mut row: Vec<f64> = de_h.iter().map(|d| -camera.f * d).collect();
                for cam in &seeded {
                    let v = match cam.ray(*px) {
                        Some(d) => {
                            let elev = d.dot(up.lift()).asin();
                            eps1(cam.f * (elev - e_h))
                        }
                        None => f64::NAN,
                    };
                    row.push(v);
                }
                row
            })
            .collect();
        (r, rows)
    }

    /// Fills the target marks' camera columns (from column `offset`) of
    /// `jac`, whose residuals at `x` are `r`; `pairs` are the pairs at `x`.
    #[allow(clippy::too_many_arguments)]
    pub fn camera_columns(
        &self,
        medium: &Medium,
        pairs: &[PointPair],
        options: &TraceOptions,
        x: &[f64],
        r: &DVector<f64>,
        jac: &mut DMatrix<f64>,
        offset: usize,
    ) {
        if self.free.is_empty() || pairs.is_empty() {
            return;
        }
        let lifted: Medium<D2> = medium.map(|_, v| D2::from_re(v));
        let fields = PairFields::new(&lifted, pairs.iter().map(|p| p.wavelength));
        let camera = self.camera_at(x);
        let seeded: Vec<Camera<D1>> = (0..self.free.len()).map(|k| self.seeded(x, k)).collect();
        let rows: Vec<Vec<[f64; 3]>> = (0..pairs.len())
            .into_par_iter()
            .map(|i| {
                let pair = &pairs[i];
                let d = pair.direction();
                let (b1, b2) = square_to(d);
                let launch = V3::new(
                    D2::from_re(d.x) + D2::from_re(0.0),
                    D2::from_re(d.y),
                    D2::from_re(d.z),
                );
                let launch = V3::new(
                    with_eps(launch.x, b1.x, b2.x),
                    with_eps(launch.y, b1.y, b2.y),
                    with_eps(launch.z, b1.z, b2.z),
                );
                let plane = pair.plane_on(options.earth);
                let t = trace_launched(
                    fields.of(i),
                    pair.origin(),
                    launch,
                    Some(&plane),
                    options,
                    None,
                );
                let de = [eps2(t.endpoint.x), eps2(t.endpoint.y), eps2(t.endpoint.z)];
                let ri = [r[3 * i], r[3 * i + 1], r[3 * i + 2]];
                seeded
                    .iter()
                    .map(|cam| {
                        let Some(dd) = cam.ray(self.pixels[i]) else {
                            return [f64::NAN; 3];
                        };
                        let dd = V3::new(eps1(dd.x), eps1(dd.y), eps1(dd.z));
                        let (a1, a2) = (b1.dot(dd), b2.dot(dd));
                        let df = eps1(cam.f) / camera.f;
                        std::array::from_fn(|c| {
                            ri[c] * df + pair.weight * (a1 * de[c][0] + a2 * de[c][1])
                        })
                    })
                    .collect()
            })
            .collect();
        for (i, row) in rows.into_iter().enumerate() {
            for (k, col) in row.into_iter().enumerate() {
                for c in 0..3 {
                    jac[(3 * i + c, offset + k)] = col[c];
                }
            }
        }
    }
}

/// `v` with derivative parts `a` and `b`.
pub fn with_eps(v: D2, a: f64, b: f64) -> D2 {
    D2::new(
        v.re,
        num_dual::Derivative::some(nalgebra::SVector::<f64, 2>::new(a, b)),
    )
}

/// Two unit vectors square to the unit `d` and to each other.
pub fn square_to(d: V3) -> (V3, V3) {
    let helper = if d.y.abs() < 0.9 {
        V3::new(0.0, 1.0, 0.0)
    } else {
        V3::new(1.0, 0.0, 0.0)
    };
    let cross = |a: V3, b: V3| {
        V3::new(
            a.y * b.z - a.z * b.y,
            a.z * b.x - a.x * b.z,
            a.x * b.y - a.y * b.x,
        )
    };
    let b1 = cross(d, helper).normalized();
    let b2 = cross(d, b1).normalized();
    (b1, b2)
}
