//! The previewer's camera: where it is, how it turns (in place or around the
//! point looked at, following the pointer at any zoom), and the zoom of the
//! field of view down to fractions of a degree.

use crate::render::camera::Camera;
use crate::scene::description::CameraSettings;
use glam::DVec3;

/// Narrowest field of view the wheel zooms to (degrees).
pub const MIN_FOV: f64 = 0.01;
/// Widest field of view (degrees).
pub const MAX_FOV: f64 = 120.0;

/// Where the camera is and how it turns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraState {
    /// Eye position.
    pub position: DVec3,
    /// Heading (radians, from +z toward +x).
    pub yaw: f64,
    /// Elevation of the view direction (radians).
    pub pitch: f64,
    /// Vertical field of view (degrees).
    pub fov: f64,
    /// Distance to the point orbited.
    pub distance: f64,
    /// Orbit (true) or fly.
    pub orbit: bool,
}

impl CameraState {
    /// The state of a scene's camera.
    pub fn from_settings(c: &CameraSettings) -> CameraState {
        let d = c.look_at - c.position;
        let f = d.normalize();
        CameraState {
            position: c.position,
            yaw: f.x.atan2(f.z),
            pitch: f.y.clamp(-1.0, 1.0).asin(),
            fov: c.vertical_fov,
            distance: d.length(),
            orbit: false,
        }
    }

    /// Unit view direction.
    pub fn forward(&self) -> DVec3 {
        let (sp, cp) = self.pitch.sin_cos();
        let (sy, cy) = self.yaw.sin_cos();
        DVec3::new(cp * sy, sp, cp * cy)
    }

    /// The pinhole camera at an image size.
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        Camera::with_size(
            &CameraSettings {
                position: self.position,
                look_at: self.position + self.forward() * self.distance.max(1.0),
                up: DVec3::Y,
                vertical_fov: self.fov,
                width,
                height,
                lens: Default::default(),
            },
            width,
            height,
        )
    }

    /// Turns by a pointer motion of (dx, dy) pixels in an image `height`
    /// pixels tall: the scene follows the pointer.
    pub fn turn(&mut self, dx: f64, dy: f64, height: f64) {
        let per_pixel = 2.0 * (0.5 * self.fov.to_radians()).tan() / height.max(1.0);
        let target = self.position + self.forward() * self.distance;
        self.yaw += dx * per_pixel;
        self.pitch = (self.pitch + dy * per_pixel).clamp(-1.55, 1.55);
        if self.orbit {
            self.position = target - self.forward() * self.distance;
        }
    }

    /// Zooms the field of view by `steps` wheel steps (positive: narrower).
    pub fn zoom(&mut self, steps: f64) {
        self.fov = (self.fov * 0.9f64.powf(steps)).clamp(MIN_FOV, MAX_FOV);
    }

    /// Moves along the view (forward), sideways (right) and up, in metres.
    pub fn fly(&mut self, forward: f64, right: f64, up: f64) {
        let f = self.forward();
        let r = f.cross(DVec3::Y).normalize_or_zero();
        self.position += f * forward + r * right + DVec3::Y * up;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> CameraState {
        CameraState::from_settings(&CameraSettings {
            position: DVec3::new(0.0, 1.2, 0.0),
            look_at: DVec3::new(0.0, 1.2, 300.0),
            up: DVec3::Y,
            vertical_fov: 1.2,
            width: 1280,
            height: 720,
            lens: Default::default(),
        })
    }

    #[test]
    fn the_scene_camera_round_trips() {
        let s = state();
        assert!((s.forward() - DVec3::Z).length() < 1e-12);
        assert!((s.distance - 300.0).abs() < 1e-9);
    }

    #[test]
    fn turning_follows_the_pointer_at_any_zoom() {
        for fov in [60.0, 1.2, 0.05] {
            let mut s = state();
            s.fov = fov;
            let cam = s.camera(1280, 720);
            // A point at the image centre; drag by 100 px to the right: it must
            // land 100 px right of the centre.
            let p = cam.origin + cam.forward * 1000.0;
            s.turn(100.0, 0.0, 720.0);
            let (x, y) = s.camera(1280, 720).project(p).unwrap();
            assert!((x - 740.0).abs() < 1.0, "fov {fov}: x = {x}");
            assert!((y - 360.0).abs() < 0.5, "fov {fov}: y = {y}");
        }
    }

    #[test]
    fn orbit_keeps_the_target_and_zoom_is_bounded() {
        let mut s = state();
        s.orbit = true;
        let target = s.position + s.forward() * s.distance;
        s.turn(300.0, -50.0, 720.0);
        let again = s.position + s.forward() * s.distance;
        assert!((again - target).length() < 1e-9);
        s.zoom(1000.0);
        assert_eq!(s.fov, MIN_FOV);
        s.zoom(-1000.0);
        assert_eq!(s.fov, MAX_FOV);
    }
}
