//! The photographer's camera: a pinhole with OpenCV's Brown–Conrady
//! distortion, oriented by azimuth, tilt and roll (`docs/photo.md`).
//!
//! # Model
//!
//! Pixels (u, v): u right, v down, the centre of the top-left pixel at
//! (0, 0). With the focal length f (pixels), the principal point (cx, cy)
//! and normalised coordinates (x, y) of the undistorted pinhole,
//! r² = x² + y² and
//!
//! ```text
//! x_d = x(1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2x²)
//! y_d = y(1 + k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2y²) + 2 p2 x y
//! u = f x_d + cx,   v = f y_d + cy.
//! ```
//!
//! The optical axis a has azimuth az (from north toward east) and elevation
//! t above the local horizontal at the camera; r0 = east·cos az − north·sin
//! az, u0 = a × r0, and the roll ρ (clockwise as the photographer looks)
//! turns them: right = cos ρ·r0 − sin ρ·u0, up = sin ρ·r0 + cos ρ·u0. The
//! ray of the undistorted point (x, y) is a + x·right − y·up, normalised.
//!
//! # Accuracy and derivatives
//!
//! Every map is generic over [`Real`], so dual numbers seeded on the
//! camera's parameters carry exact derivatives ([`CameraParams::lift`]).
//! Undistortion (pixel → ray) is Newton's method on the 2 × 2 distortion
//! map in `f64` to 1e-15 of the normalised coordinates, then one Newton
//! step in `T` from the converged point: at a root that step is the
//! implicit-function derivative, so the derivative is exact, not the
//! derivative of an iteration count.

use crate::geo::Horizon;
use crate::math::{Real, V3};
use std::fmt;
use std::str::FromStr;

/// A camera number addressable by path (`camera.tilt`, …), in the order of
/// [`CameraParams::values`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CameraParam {
    /// Azimuth of the optical axis, degrees from north toward east.
    Azimuth,
    /// Elevation of the optical axis above the local horizontal, degrees.
    Tilt,
    /// Roll about the optical axis, degrees clockwise as one looks through.
    Roll,
    /// Focal length (mm, with `sensor_width`).
    FocalLength,
    /// Horizontal field of view (degrees).
    HorizontalFov,
    /// Principal point u (pixels).
    Cx,
    /// Principal point v (pixels).
    Cy,
    /// Radial distortion k1.
    K1,
    /// Radial distortion k2.
    K2,
    /// Radial distortion k3.
    K3,
    /// Tangential distortion p1.
    P1,
    /// Tangential distortion p2.
    P2,
}

impl CameraParam {
    /// Every camera parameter, in index order.
    pub const ALL: [CameraParam; 12] = [
        CameraParam::Azimuth,
        CameraParam::Tilt,
        CameraParam::Roll,
        CameraParam::FocalLength,
        CameraParam::HorizontalFov,
        CameraParam::Cx,
        CameraParam::Cy,
        CameraParam::K1,
        CameraParam::K2,
        CameraParam::K3,
        CameraParam::P1,
        CameraParam::P2,
    ];

    /// Its index in [`CameraParams::values`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// Its path after `camera.`.
    pub fn path(self) -> &'static str {
        match self {
            CameraParam::Azimuth => "azimuth",
            CameraParam::Tilt => "tilt",
            CameraParam::Roll => "roll",
            CameraParam::FocalLength => "focal_length",
            CameraParam::HorizontalFov => "horizontal_fov",
            CameraParam::Cx => "principal_point[0]",
            CameraParam::Cy => "principal_point[1]",
            CameraParam::K1 => "distortion.k1",
            CameraParam::K2 => "distortion.k2",
            CameraParam::K3 => "distortion.k3",
            CameraParam::P1 => "distortion.p1",
            CameraParam::P2 => "distortion.p2",
        }
    }
}

impl fmt::Display for CameraParam {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "camera.{}", self.path())
    }
}

/// A path that names no camera parameter.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown camera parameter `{name}` (known: {known})")]
pub struct CameraParamError {
    /// The path as written.
    pub name: String,
    /// The known paths, comma-separated.
    pub known: String,
}

impl FromStr for CameraParam {
    type Err = CameraParamError;
    fn from_str(s: &str) -> Result<Self, CameraParamError> {
        let rest = s.strip_prefix("camera.").unwrap_or("");
        CameraParam::ALL
            .into_iter()
            .find(|p| p.path() == rest)
            .ok_or_else(|| CameraParamError {
                name: s.to_string(),
                known: CameraParam::ALL
                    .iter()
                    .map(|p| p.to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }
}

/// How the focal length in pixels follows from the numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FocalSource {
    /// `focal_length` (mm) over `sensor_width` (mm): f = focal_length · W / sensor_width.
    Millimetres {
        /// The sensor's width (mm).
        sensor_width: f64,
    },
    /// `horizontal_fov` (degrees): f = (W/2) / tan(fov/2).
    FieldOfView,
    /// Given in pixels (from the image's EXIF), not a parameter.
    Pixels(f64),
}

/// A camera's numbers (values indexed by [`CameraParam`]), its place and
/// frame, the image width, and how f is made.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraParams {
    /// Values by [`CameraParam::index`]; unused ones (the focal form not
    /// chosen) are 0.
    pub values: [f64; 12],
    /// How the focal length is made.
    pub focal: FocalSource,
    /// Image width and height (pixels).
    pub size: [u32; 2],
    /// The camera's position in the local frame (metres).
    pub position: [f64; 3],
    /// The local horizontal at the camera.
    pub frame: Horizon,
}

/// A camera evaluated in numbers `T` (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera<T = f64> {
    /// Focal length (pixels).
    pub f: T,
    /// Principal point (pixels).
    pub c: [T; 2],
    /// k1, k2, k3, p1, p2.
    pub dist: [T; 5],
    /// The optical axis (unit).
    pub axis: V3<T>,
    /// The image's right (unit).
    pub right: V3<T>,
    /// The image's up (unit).
    pub up: V3<T>,
}

fn v3(a: [f64; 3]) -> V3 {
    V3::from(a)
}

fn cross<T: Real>(a: V3<T>, b: V3<T>) -> V3<T> {
    V3::new(
        a.y * b.z - a.z * b.y,
        a.z * b.x - a.x * b.z,
        a.x * b.y - a.y * b.x,
    )
}

fn comb<T: Real>(a: V3, ka: T, b: V3, kb: T, c: V3, kc: T) -> V3<T> {
    V3::new(
        ka * a.x + kb * b.x + kc * c.x,
        ka * a.y + kb * b.y + kc * c.y,
        ka * a.z + kb * b.z + kc * c.z,
    )
}

impl CameraParams {
    /// The value of `p`.
    pub fn get(&self, p: CameraParam) -> f64 {
        self.values[p.index()]
    }

    /// The camera in `T`, with `values` (by index) in place of the numbers.
    pub fn camera<T: Real>(&self, values: &[T; 12]) -> Camera<T> {
        let deg = std::f64::consts::PI / 180.0;
        let w = self.size[0] as f64;
        let f = match self.focal {
            FocalSource::Millimetres { sensor_width } => {
                values[CameraParam::FocalLength.index()] * (w / sensor_width)
            }
            FocalSource::FieldOfView => {
                let half = values[CameraParam::HorizontalFov.index()] * (0.5 * deg);
                T::cst(0.5 * w) / half.tan()
            }
            FocalSource::Pixels(f) => T::cst(f),
        };
        let az = values[CameraParam::Azimuth.index()] * deg;
        let t = values[CameraParam::Tilt.index()] * deg;
        let rho = values[CameraParam::Roll.index()] * deg;
        let (east, up, north) = (v3(self.frame.east), v3(self.frame.up), v3(self.frame.north));
        let (sa, ca) = (az.sin(), az.cos());
        let (st, ct) = (t.sin(), t.cos());
        let axis = comb(east, sa * ct, up, st, north, ca * ct);
        let r0 = comb(east, ca, up, T::cst(0.0), north, -sa);
        let u0 = cross(axis, r0);
        let (sr, cr) = (rho.sin(), rho.cos());
        let right = V3::new(
            cr * r0.x - sr * u0.x,
            cr * r0.y - sr * u0.y,
            cr * r0.z - sr * u0.z,
        );
        let upv = V3::new(
            sr * r0.x + cr * u0.x,
            sr * r0.y + cr * u0.y,
            sr * r0.z + cr * u0.z,
        );
        let i = |p: CameraParam| values[p.index()];
        Camera {
            f,
            c: [i(CameraParam::Cx), i(CameraParam::Cy)],
            dist: [
                i(CameraParam::K1),
                i(CameraParam::K2),
                i(CameraParam::K3),
                i(CameraParam::P1),
                i(CameraParam::P2),
            ],
            axis,
            right,
            up: upv,
        }
    }

    /// The camera in `f64` at its own numbers.
    pub fn at_values(&self) -> Camera {
        self.camera(&self.values)
    }

    /// The values lifted to `T` (constants).
    pub fn lift<T: Real>(&self) -> [T; 12] {
        self.values.map(T::cst)
    }
}

impl<T: Real> Camera<T> {
    /// Brown–Conrady: undistorted normalised (x, y) → distorted.
    pub fn distort(&self, x: T, y: T) -> (T, T) {
        let [k1, k2, k3, p1, p2] = self.dist;
        let r2 = x * x + y * y;
        let radial = T::cst(1.0) + r2 * (k1 + r2 * (k2 + r2 * k3));
        let xy = x * y;
        (
            x * radial + p1 * xy * 2.0 + p2 * (r2 + x * x * 2.0),
            y * radial + p1 * (r2 + y * y * 2.0) + p2 * xy * 2.0,
        )
    }

    /// The pixel of the undistorted normalised point (x, y).
    pub fn pixel_of_normalised(&self, x: T, y: T) -> [T; 2] {
        let (xd, yd) = self.distort(x, y);
        [self.f * xd + self.c[0], self.f * yd + self.c[1]]
    }

    /// The pixel where the direction `d` (any length) lands, or `None`
    /// behind the camera (d·axis ≤ 0).
    pub fn project(&self, d: V3<T>) -> Option<[T; 2]> {
        let z = d.dot(self.axis);
        if z.val() <= 0.0 {
            return None;
        }
        let x = d.dot(self.right) / z;
        let y = -(d.dot(self.up) / z);
        Some(self.pixel_of_normalised(x, y))
    }

    /// The undistorted normalised coordinates of a pixel (see the module
    /// doc), or `None` where Newton's method does not converge (far
    /// outside the distortion model's monotone range).
    pub fn undistort(&self, pixel: [f64; 2]) -> Option<(T, T)> {
        let xd = (T::cst(pixel[0]) - self.c[0]) / self.f;
        let yd = (T::cst(pixel[1]) - self.c[1]) / self.f;
        // Newton in f64 on g(x, y) = distort(x, y) − (x_d, y_d).
        let re = self.val();
        let (txd, tyd) = (xd.val(), yd.val());
        let (mut x, mut y) = (txd, tyd);
        let mut converged = false;
        for _ in 0..50 {
            let (gx, gy, j) = re.distortion_step(x, y);
            let (rx, ry) = (gx - txd, gy - tyd);
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if !det.is_finite() || det == 0.0 {
                return None;
            }
            let dx = (rx * j[1][1] - ry * j[0][1]) / det;
            let dy = (ry * j[0][0] - rx * j[1][0]) / det;
            x -= dx;
            y -= dy;
            if !(x.is_finite() && y.is_finite()) {
                return None;
            }
            if dx.abs().max(dy.abs()) <= 1e-15 * (1.0 + x.abs().max(y.abs())) {
                converged = true;
                break;
            }
        }
        if !converged {
            return None;
        }
        // Only a root on the lens's unfolded side is the pixel's ray: the
        // radial factor positive (not flipped through the centre) and the
        // map orientation-preserving there. Beyond the fold Newton may
        // still find a mirrored root; it is no ray of this pixel.
        let [k1, k2, k3, _, _] = re.dist;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        let (_, _, j) = re.distortion_step(x, y);
        if radial <= 0.0 || j[0][0] * j[1][1] - j[0][1] * j[1][0] <= 0.0 {
            return None;
        }
        // One Newton step in T from the root: the implicit derivative.
        let (gx, gy) = self.distort(T::cst(x), T::cst(y));
        let (_, _, j) = re.distortion_step(x, y);
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let (rx, ry) = (gx - xd, gy - yd);
        let dx = (rx * j[1][1] - ry * j[0][1]) / det;
        let dy = (ry * j[0][0] - rx * j[1][0]) / det;
        Some((T::cst(x) - dx, T::cst(y) - dy))
    }

    /// The unit ray of a pixel, or `None` where it cannot be undistorted.
    pub fn ray(&self, pixel: [f64; 2]) -> Option<V3<T>> {
        let (x, y) = self.undistort(pixel)?;
        let d = V3::new(
            self.axis.x + x * self.right.x - y * self.up.x,
            self.axis.y + x * self.right.y - y * self.up.y,
            self.axis.z + x * self.right.z - y * self.up.z,
        );
        let n = d.dot(d).sqrt();
        Some(V3::new(d.x / n, d.y / n, d.z / n))
    }

    /// The camera's real parts.
    pub fn val(&self) -> Camera {
        Camera {
            f: self.f.val(),
            c: self.c.map(|c| c.val()),
            dist: self.dist.map(|c| c.val()),
            axis: self.axis.val(),
            right: self.right.val(),
            up: self.up.val(),
        }
    }
}

impl Camera {
    /// The distortion at (x, y) and its 2 × 2 Jacobian.
    fn distortion_step(&self, x: f64, y: f64) -> (f64, f64, [[f64; 2]; 2]) {
        let [k1, k2, k3, p1, p2] = self.dist;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        // d(radial)/d(r²)
        let dr = k1 + r2 * (2.0 * k2 + 3.0 * r2 * k3);
        let gx = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
        let gy = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
        let j = [
            [
                radial + x * dr * 2.0 * x + 2.0 * p1 * y + p2 * 6.0 * x,
                x * dr * 2.0 * y + 2.0 * p1 * x + 2.0 * p2 * y,
            ],
            [
                y * dr * 2.0 * x + 2.0 * p1 * x + 2.0 * p2 * y,
                radial + y * dr * 2.0 * y + p1 * 6.0 * y + 2.0 * p2 * x,
            ],
        ];
        (gx, gy, j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::DualSVec64;

    fn params(roll: f64, dist: [f64; 5]) -> CameraParams {
        let mut values = [0.0; 12];
        values[CameraParam::Azimuth.index()] = 212.0;
        values[CameraParam::Tilt.index()] = -0.05;
        values[CameraParam::Roll.index()] = roll;
        values[CameraParam::FocalLength.index()] = 300.0;
        values[CameraParam::Cx.index()] = 2999.5;
        values[CameraParam::Cy.index()] = 1999.5;
        for (k, p) in [
            CameraParam::K1,
            CameraParam::K2,
            CameraParam::K3,
            CameraParam::P1,
            CameraParam::P2,
        ]
        .into_iter()
        .enumerate()
        {
            values[p.index()] = dist[k];
        }
        CameraParams {
            values,
            focal: FocalSource::Millimetres { sensor_width: 23.5 },
            size: [6000, 4000],
            position: [0.0, 12.0, 0.0],
            frame: Horizon::at([0.0, 12.0, 0.0], Some(6.37e6)).unwrap(),
        }
    }

    #[test]
    fn the_spec_axes_at_zero_azimuth_tilt_and_roll() {
        let mut p = params(0.0, [0.0; 5]);
        p.values[CameraParam::Azimuth.index()] = 0.0;
        p.values[CameraParam::Tilt.index()] = 0.0;
        let c = p.at_values();
        assert!((c.axis - V3::new(0.0, 0.0, 1.0)).norm() < 1e-15);
        assert!((c.right - V3::new(1.0, 0.0, 0.0)).norm() < 1e-15);
        assert!((c.up - V3::new(0.0, 1.0, 0.0)).norm() < 1e-15);
        // The principal point looks along the axis.
        let d = c.ray([2999.5, 1999.5]).unwrap();
        assert!((d - c.axis).norm() < 1e-15);
        // A pixel to the right looks east of north, one below looks down.
        assert!(c.ray([4000.0, 1999.5]).unwrap().x > 0.0);
        assert!(c.ray([2999.5, 3000.0]).unwrap().y < 0.0);
    }

    #[test]
    fn a_clockwise_roll_makes_a_level_horizon_run_up_to_the_right() {
        let mut p = params(2.0, [0.0; 5]);
        p.values[CameraParam::Tilt.index()] = 0.0;
        let c = p.at_values();
        // Two horizontal directions either side of the axis.
        let deg = std::f64::consts::PI / 180.0;
        let az = 212.0 * deg;
        let dir = |a: f64| V3::new(a.sin(), 0.0, a.cos());
        let left = c.project(dir(az - 0.1)).unwrap();
        let right = c.project(dir(az + 0.1)).unwrap();
        assert!(right[0] > left[0]);
        // v down: up to the right means a smaller v on the right.
        assert!(right[1] < left[1], "{left:?} {right:?}");
    }

    #[test]
    fn pixel_to_ray_to_pixel_round_trips_with_distortion() {
        for dist in [
            [0.0; 5],
            [-0.08, 0.01, 0.0, 0.0, 0.0],
            [0.05, -0.02, 0.003, 1e-3, -5e-4],
        ] {
            let c = params(1.5, dist).at_values();
            for &px in &[
                [0.0, 0.0],
                [5999.0, 3999.0],
                [3120.0, 1874.5],
                [100.0, 3900.0],
            ] {
                let d = c.ray(px).unwrap();
                let back = c.project(d).unwrap();
                assert!(
                    (back[0] - px[0]).abs() < 1e-9 && (back[1] - px[1]).abs() < 1e-9,
                    "{dist:?} {px:?} → {back:?}"
                );
            }
        }
    }

    #[test]
    fn the_ray_derivatives_match_central_differences() {
        type D = DualSVec64<1>;
        let p = params(1.5, [-0.08, 0.01, 0.002, 1e-3, -5e-4]);
        let px = [5100.0, 700.0];
        for q in CameraParam::ALL {
            if q == CameraParam::HorizontalFov {
                continue;
            }
            let mut vals: [D; 12] = p.lift();
            vals[q.index()] = D::from_re(p.get(q)).derivative(0);
            let d = p.camera(&vals).ray(px).unwrap();
            // Fourth-order differences; the distortion's small columns take
            // larger steps, or rounding would dominate.
            let h = if q.path().starts_with("distortion.k") {
                1.0
            } else if q.path().starts_with("distortion") {
                1e-2
            } else {
                1e-4 * p.get(q).abs().max(1e-2)
            };
            let at = |s: f64| {
                let mut v = p.values;
                v[q.index()] += s;
                p.camera(&v).ray(px).unwrap()
            };
            let fd = ((at(h) - at(-h)) * 8.0 - (at(2.0 * h) - at(-2.0 * h))) * (1.0 / (12.0 * h));
            let ex = V3::new(
                d.x.eps.unwrap_generic(nalgebra::Const::<1>, nalgebra::U1)[0],
                d.y.eps.unwrap_generic(nalgebra::Const::<1>, nalgebra::U1)[0],
                d.z.eps.unwrap_generic(nalgebra::Const::<1>, nalgebra::U1)[0],
            );
            let scale = ex.norm().max(1e-12);
            assert!(
                (ex - fd).norm() <= 1e-6 * scale + 1e-15,
                "{q}: exact {ex:?} vs differences {fd:?}"
            );
        }
    }

    #[test]
    fn paths_parse_and_print() {
        for p in CameraParam::ALL {
            assert_eq!(p.to_string().parse::<CameraParam>().unwrap(), p);
        }
        assert!(
            "camera.zoom"
                .parse::<CameraParam>()
                .unwrap_err()
                .to_string()
                .contains("camera.tilt")
        );
        assert!("air.x".parse::<CameraParam>().is_err());
    }
}
