//! The pinhole camera: pixel coordinates to ray directions and back.
//!
//! Continuous pixel coordinates run from (0, 0) at the top-left corner of the
//! image to (width, height) at the bottom-right one; pixel (i, j) covers
//! [i, i + 1) × [j, j + 1) and its centre is (i + ½, j + ½).
//!
//! A camera with a roll or a lens distortion (`camera.roll`,
//! `camera.distortion`) maps pixels through the photo camera's model
//! ([`crate::photo::camera::Camera`], `docs/photo.md`): focal length
//! f = (height / 2) / tan(vertical_fov / 2) pixels, principal point the
//! image's centre, the right and up vectors turned by the roll; the ray of
//! continuous pixel (px, py) is the photo camera's ray of pixel
//! (px − ½, py − ½) (the photo convention puts the top-left pixel's centre
//! at (0, 0)), undistorted by Newton's method to 1e-15. Without roll and
//! distortion the two maps agree to rounding, and the plain pinhole is used.

use crate::math::V3;
use crate::photo::camera::Camera as Lens;
use crate::scene::description::CameraSettings;
use glam::DVec3;

/// A pinhole camera with a vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub origin: DVec3,
    /// Unit view direction (the image centre).
    pub forward: DVec3,
    /// Unit vector toward increasing pixel column.
    pub right: DVec3,
    /// Unit vector toward decreasing pixel row (up in the picture).
    pub up: DVec3,
    /// tan(vertical field of view / 2).
    pub tan_half: f64,
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// The photo camera's model when the scene gives a roll or a
    /// distortion (`None`: the plain pinhole).
    pub lens: Option<Lens>,
}

fn v3(d: DVec3) -> V3 {
    V3::new(d.x, d.y, d.z)
}

fn dvec(v: V3) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

impl Camera {
    /// The camera of a scene, at the scene's image size.
    pub fn new(c: &CameraSettings) -> Camera {
        Camera::with_size(c, c.width, c.height)
    }

    /// The camera of a scene at another image size (same vertical field of view).
    pub fn with_size(c: &CameraSettings, width: u32, height: u32) -> Camera {
        let forward = (c.look_at - c.position).normalize();
        let right = forward.cross(c.up).normalize();
        let up = right.cross(forward);
        let tan_half = (0.5 * c.vertical_fov.to_radians()).tan();
        let lens = (!c.lens.is_pinhole()).then(|| {
            let (s, k) = c.lens.roll.to_radians().sin_cos();
            Lens {
                f: 0.5 * height as f64 / tan_half,
                c: [0.5 * (width as f64 - 1.0), 0.5 * (height as f64 - 1.0)],
                dist: c.lens.distortion,
                axis: v3(forward),
                right: v3(right * k - up * s),
                up: v3(right * s + up * k),
            }
        });
        Camera {
            origin: c.position,
            forward,
            right,
            up,
            tan_half,
            width,
            height,
            lens,
        }
    }

    fn aspect(&self) -> f64 {
        self.width as f64 / self.height as f64
    }

    /// Image-plane coordinates (at unit distance) of continuous pixel
    /// coordinates.
    #[inline]
    fn plane(&self, px: f64, py: f64) -> (f64, f64) {
        let sx = (2.0 * px / self.width as f64 - 1.0) * self.tan_half * self.aspect();
        let sy = (1.0 - 2.0 * py / self.height as f64) * self.tan_half;
        (sx, sy)
    }

    /// Unit direction of the ray through continuous pixel coordinates (px, py).
    #[inline]
    pub fn direction(&self, px: f64, py: f64) -> DVec3 {
        if let Some(d) = self.lens.and_then(|l| l.ray([px - 0.5, py - 0.5])) {
            return dvec(d);
        }
        let (sx, sy) = self.plane(px, py);
        (self.forward + self.right * sx + self.up * sy).normalize()
    }

    /// Continuous pixel coordinates where the straight line from the eye to `p`
    /// meets the image, or `None` if `p` is not in front of the camera.
    pub fn project(&self, p: DVec3) -> Option<(f64, f64)> {
        let d = p - self.origin;
        if let Some(lens) = &self.lens {
            let [u, v] = lens.project(v3(d))?;
            return Some((u + 0.5, v + 0.5));
        }
        let zc = d.dot(self.forward);
        if zc <= 0.0 {
            return None;
        }
        let sx = d.dot(self.right) / zc;
        let sy = d.dot(self.up) / zc;
        let px = 0.5 * self.width as f64 * (1.0 + sx / (self.tan_half * self.aspect()));
        let py = 0.5 * self.height as f64 * (1.0 - sy / self.tan_half);
        Some((px, py))
    }

    /// Angle subtended by one pixel at the image centre (radians).
    pub fn pixel_angle(&self) -> f64 {
        2.0 * self.tan_half / self.height as f64
    }
}

/// Offset inside the pixel of sample `i` (of any number): the R2
/// low-discrepancy sequence (Roberts 2018) started at the pixel centre, so one
/// sample per pixel is the centre and every count fills the pixel evenly. The
/// same offsets serve every pixel, which keeps images independent of how the
/// work is split between threads.
#[inline]
pub fn sample_offset(i: u32) -> (f64, f64) {
    // 1/g and 1/g² for the plastic number g, the 2-D golden ratio.
    const A1: f64 = 0.754_877_666_246_692_7;
    const A2: f64 = 0.569_840_290_998_053_3;
    let k = i as f64;
    ((0.5 + A1 * k).fract(), (0.5 + A2 * k).fract())
}
