//! The pinhole camera: pixel coordinates to ray directions and back.
//!
//! Continuous pixel coordinates run from (0, 0) at the top-left corner of the
//! image to (width, height) at the bottom-right one; pixel (i, j) covers
//! [i, i + 1) × [j, j + 1) and its centre is (i + ½, j + ½).

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
        Camera {
            origin: c.position,
            forward,
            right,
            up,
            tan_half: (0.5 * c.vertical_fov.to_radians()).tan(),
            width,
            height,
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
        let (sx, sy) = self.plane(px, py);
        (self.forward + self.right * sx + self.up * sy).normalize()
    }

    /// Continuous pixel coordinates where the straight line from the eye to `p`
    /// meets the image, or `None` if `p` is not in front of the camera.
    pub fn project(&self, p: DVec3) -> Option<(f64, f64)> {
        let d = p - self.origin;
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
