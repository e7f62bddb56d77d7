//! Pinhole camera: continuous pixel position -> primary ray.

use crate::math::{Ray, Vec3};

#[derive(Clone, Debug)]
pub struct Camera {
    pub position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half_fov: f32,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    /// `fov_y_deg` is the vertical field of view; a non-square image keeps it
    /// and widens or narrows the horizontal one. Image x grows along
    /// forward x up, image y (downwards in the picture) along -up.
    /// Returns `None` for a degenerate frame (look_at at the position, up
    /// parallel to the view direction, fov outside (0, 180)).
    pub fn new(position: Vec3, look_at: Vec3, up: Vec3, fov_y_deg: f32, width: u32, height: u32) -> Option<Camera> {
        let forward = (look_at - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) || width == 0 || height == 0 {
            return None;
        }
        Some(Camera {
            position,
            forward,
            right,
            up,
            tan_half_fov: (fov_y_deg.to_radians() * 0.5).tan(),
            width,
            height,
        })
    }

    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// The ray through continuous pixel coordinates (x, y), with (0, 0) the
    /// top-left corner of the image and (width, height) the bottom-right one.
    pub fn generate_ray(&self, x: f32, y: f32) -> Ray {
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half_fov * aspect;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half_fov;
        let d = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray::new(self.position, d)
    }

    /// Where a world-space point lands in continuous pixel coordinates, if in front.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32)> {
        let v = p - self.position;
        let z = v.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let aspect = self.width as f32 / self.height as f32;
        let sx = v.dot(self.right) / z / (self.tan_half_fov * aspect);
        let sy = v.dot(self.up) / z / self.tan_half_fov;
        Some((
            (sx + 1.0) * 0.5 * self.width as f32,
            (1.0 - sy) * 0.5 * self.height as f32,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell_camera(w: u32, h: u32) -> Camera {
        let fov = 2.0 * 0.5f32.atan();
        Camera::new(
            Vec3::new(0.0, 0.0, -3.0),
            Vec3::ZERO,
            Vec3::new(0.0, -1.0, 0.0),
            fov.to_degrees(),
            w,
            h,
        )
        .unwrap()
    }

    #[test]
    fn centre_pixel_looks_along_plus_z() {
        let c = cornell_camera(512, 512);
        let r = c.generate_ray(256.0, 256.0);
        assert!((r.d - Vec3::Z).length() < 1e-6);
        assert_eq!(r.o, Vec3::new(0.0, 0.0, -3.0));
    }

    #[test]
    fn corners_are_at_the_expected_angles() {
        let c = cornell_camera(512, 512);
        // tan(half fov) = 0.5, so the top-left corner direction is (-0.5, -0.5, 1)
        // (image up is world -y, image left is world -x).
        let tl = c.generate_ray(0.0, 0.0).d;
        assert!((tl - Vec3::new(-0.5, -0.5, 1.0).normalize()).length() < 1e-6, "{tl:?}");
        let br = c.generate_ray(512.0, 512.0).d;
        assert!((br - Vec3::new(0.5, 0.5, 1.0).normalize()).length() < 1e-6, "{br:?}");
        let angle = tl.dot(Vec3::Z).acos().to_degrees();
        assert!((angle - (0.5f32 * 2.0f32.sqrt()).atan().to_degrees()).abs() < 1e-3);
    }

    #[test]
    fn wide_image_keeps_vertical_fov() {
        let c = cornell_camera(1024, 512);
        let top = c.generate_ray(512.0, 0.0).d;
        assert!((top - Vec3::new(0.0, -0.5, 1.0).normalize()).length() < 1e-6);
        let right = c.generate_ray(1024.0, 256.0).d;
        assert!((right - Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn project_inverts_generate_ray() {
        let c = cornell_camera(300, 200);
        let r = c.generate_ray(37.5, 150.25);
        let (x, y) = c.project(r.at(2.5)).unwrap();
        assert!((x - 37.5).abs() < 1e-3 && (y - 150.25).abs() < 1e-3);
    }

    #[test]
    fn degenerate_frames_are_refused() {
        assert!(Camera::new(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 60.0, 4, 4).is_none());
        assert!(Camera::new(Vec3::ZERO, Vec3::Y, Vec3::Y, 60.0, 4, 4).is_none());
        assert!(Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 180.0, 4, 4).is_none());
    }
}
