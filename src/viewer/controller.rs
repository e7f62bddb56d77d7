//! What the preview window's movement keys do: each key maps the current
//! pose (camera position and view direction, light offset) to a new one.
//! Plain functions of the pose, so they are tested without a window.
//!
//! The camera walks along its view direction and turns about the scene's up
//! axis, like a first-person walk-through. The light moves in the camera's
//! horizontal frame (right, forward, up), so D always moves it towards the
//! right of the picture. Steps are a fixed fraction of the scene's size.

use crate::camera::Camera;
use crate::math::{Aabb, Vec3};
use crate::scene::CameraDesc;
use glam::Quat;

/// Fraction of the scene's bounding-box diagonal one key press moves by.
pub const STEP_FRACTION: f32 = 1.0 / 25.0;
/// Degrees one press of Left or Right turns the camera by.
pub const TURN_DEGREES: f32 = 5.0;

/// The keys that change the pose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Key {
    /// Camera forward along its view direction.
    Up,
    /// Camera backward.
    Down,
    /// Turn the camera left about the up axis.
    Left,
    /// Turn the camera right.
    Right,
    /// Light away from the viewer (horizontal forward).
    W,
    /// Light towards the left of the picture.
    A,
    /// Light towards the viewer.
    S,
    /// Light towards the right of the picture.
    D,
    /// Light down.
    Q,
    /// Light up.
    E,
    /// Back to the scene's own camera and light.
    R,
}

/// Where the camera and the light are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub camera_position: Vec3,
    /// Unit view direction.
    pub camera_forward: Vec3,
    /// Added to the position every light has in the scene description.
    pub light_offset: Vec3,
}

/// The key-to-pose mapping for one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Controller {
    /// The scene's own pose, which R restores.
    pub initial: Pose,
    /// Unit up axis of the scene's camera: the camera turns about it.
    pub up: Vec3,
    /// Distance one press moves the camera or the light.
    pub step: f32,
    /// Angle one press turns the camera by, in radians.
    pub turn: f32,
}

impl Controller {
    /// The controller for a scene's camera, with steps scaled to `bounds`
    /// (`Scene::bounds`). Returns `None` for a degenerate camera.
    pub fn new(camera: &CameraDesc, bounds: &Aabb) -> Option<Controller> {
        let forward = (camera.look_at - camera.position).try_normalize()?;
        let up = camera.up.try_normalize()?;
        forward.cross(up).try_normalize()?;
        let diagonal = if bounds.is_empty() {
            0.0
        } else {
            bounds.extent().length()
        };
        // An empty or unbounded scene still needs a usable step.
        let step = if diagonal.is_finite() && diagonal > 0.0 {
            diagonal * STEP_FRACTION
        } else {
            0.1
        };
        Some(Controller {
            initial: Pose {
                camera_position: camera.position,
                camera_forward: forward,
                light_offset: Vec3::ZERO,
            },
            up,
            step,
            turn: TURN_DEGREES.to_radians(),
        })
    }

    /// The pose after pressing `key` in `pose`.
    pub fn apply(&self, pose: &Pose, key: Key) -> Pose {
        let mut p = *pose;
        let (right, ahead) = self.horizontal_frame(pose);
        let f = pose.camera_forward;
        match key {
            Key::Up => p.camera_position += f * self.step,
            Key::Down => p.camera_position -= f * self.step,
            // A positive turn about `up` swings the view towards -right (left).
            Key::Left => p.camera_forward = self.turned(f, self.turn),
            Key::Right => p.camera_forward = self.turned(f, -self.turn),
            Key::W => p.light_offset += ahead * self.step,
            Key::S => p.light_offset -= ahead * self.step,
            Key::D => p.light_offset += right * self.step,
            Key::A => p.light_offset -= right * self.step,
            Key::E => p.light_offset += self.up * self.step,
            Key::Q => p.light_offset -= self.up * self.step,
            Key::R => p = self.initial,
        }
        p
    }

    /// The camera of `pose`, with the field of view, size, window and lens of `desc`.
    pub fn camera(&self, pose: &Pose, desc: &CameraDesc) -> Option<Camera> {
        desc.camera_at(
            pose.camera_position,
            pose.camera_position + pose.camera_forward,
            self.up,
        )
    }

    /// Unit vectors towards the picture's right and straight ahead, both
    /// perpendicular to `up`.
    fn horizontal_frame(&self, pose: &Pose) -> (Vec3, Vec3) {
        // Same convention as the camera: image x grows along forward x up.
        let right = pose.camera_forward.cross(self.up).normalize_or_zero();
        (right, self.up.cross(right))
    }

    fn turned(&self, forward: Vec3, angle: f32) -> Vec3 {
        (Quat::from_axis_angle(self.up, angle) * forward).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    fn cornell() -> (Controller, CameraDesc) {
        let desc = builtin::cornell();
        let bounds = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        (Controller::new(&desc.camera, &bounds).unwrap(), desc.camera)
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn forward_and_back_move_along_the_view_direction_by_one_step() {
        let (c, _) = cornell();
        let p0 = c.initial;
        let p1 = c.apply(&p0, Key::Up);
        assert!(close(p1.camera_position, p0.camera_position + Vec3::Z * c.step));
        assert_eq!(p1.camera_forward, p0.camera_forward);
        assert_eq!(p1.light_offset, Vec3::ZERO);
        let p2 = c.apply(&c.apply(&p1, Key::Down), Key::Down);
        assert!(close(p2.camera_position, p0.camera_position - Vec3::Z * c.step));
        // After a turn, forward follows the new view direction.
        let t = c.apply(&p0, Key::Right);
        let m = c.apply(&t, Key::Up);
        assert!(close(m.camera_position - t.camera_position, t.camera_forward * c.step));
    }

    #[test]
    fn turning_keeps_the_position_and_rotates_about_up() {
        let (c, desc) = cornell();
        let p0 = c.initial;
        let left = c.apply(&p0, Key::Left);
        assert_eq!(left.camera_position, p0.camera_position);
        // The angle between old and new view is one turn, about the up axis.
        let cos = left.camera_forward.dot(p0.camera_forward);
        assert!((cos - c.turn.cos()).abs() < 1e-6, "{cos}");
        assert!(left.camera_forward.dot(c.up).abs() < 1e-6);
        // Left swings the view towards the picture's left: there the image
        // x coordinate of what was straight ahead grows.
        let cam0 = c.camera(&p0, &desc).unwrap();
        let ahead = p0.camera_position + p0.camera_forward * 2.0;
        let (x0, _) = cam0.project(ahead).unwrap();
        let (xl, _) = c.camera(&left, &desc).unwrap().project(ahead).unwrap();
        let (xr, _) = c
            .camera(&c.apply(&p0, Key::Right), &desc)
            .unwrap()
            .project(ahead)
            .unwrap();
        assert!(xl > x0 + 1.0 && xr < x0 - 1.0, "{xl} {x0} {xr}");
        // Right undoes left; 72 turns of 5 degrees come full circle.
        let back = c.apply(&left, Key::Right);
        assert!(close(back.camera_forward, p0.camera_forward));
        let mut p = p0;
        for _ in 0..72 {
            p = c.apply(&p, Key::Left);
        }
        assert!(close(p.camera_forward, p0.camera_forward));
    }

    #[test]
    fn light_keys_move_along_the_world_axes_of_the_cornell_view() {
        // The Cornell camera looks along +z with up = -y and right = +x.
        let (c, _) = cornell();
        let p0 = c.initial;
        let s = c.step;
        for (key, dir) in [
            (Key::D, Vec3::X),
            (Key::A, -Vec3::X),
            (Key::W, Vec3::Z),
            (Key::S, -Vec3::Z),
            (Key::E, -Vec3::Y),
            (Key::Q, Vec3::Y),
        ] {
            let p = c.apply(&p0, key);
            assert!(close(p.light_offset, dir * s), "{key:?}: {:?}", p.light_offset);
            assert_eq!(p.camera_position, p0.camera_position, "{key:?}");
            assert_eq!(p.camera_forward, p0.camera_forward, "{key:?}");
        }
    }

    #[test]
    fn reset_restores_the_initial_pose() {
        let (c, _) = cornell();
        let mut p = c.initial;
        for k in [Key::Up, Key::Left, Key::D, Key::E, Key::W, Key::Up] {
            p = c.apply(&p, k);
        }
        assert_ne!(p, c.initial);
        assert_eq!(c.apply(&p, Key::R), c.initial);
    }

    #[test]
    fn steps_scale_with_the_scene_size() {
        let desc = builtin::cornell();
        let small = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let big = Aabb {
            min: Vec3::splat(-10.0),
            max: Vec3::splat(10.0),
        };
        let a = Controller::new(&desc.camera, &small).unwrap();
        let b = Controller::new(&desc.camera, &big).unwrap();
        assert!((a.step - 12f32.sqrt() * STEP_FRACTION).abs() < 1e-6);
        assert!((b.step - 10.0 * a.step).abs() < 1e-5);
        let pa = a.apply(&a.initial, Key::D).light_offset.length();
        let pb = b.apply(&b.initial, Key::D).light_offset.length();
        assert!((pb - 10.0 * pa).abs() < 1e-5);
        // An empty scene still moves.
        let e = Controller::new(&desc.camera, &Aabb::EMPTY).unwrap();
        assert!(e.step > 0.0);
    }
}
