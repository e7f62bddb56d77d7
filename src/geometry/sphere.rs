//! Ray-sphere intersection (the light and glass spheres).

use crate::math::{Aabb, Ray, Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub centre: Vec3,
    pub radius: f32,
}

impl Sphere {
    /// Nearest intersection in (t_min, t_max). Uses the numerically stable
    /// quadratic of Ray Tracing Gems ch. 7: the discriminant is formed from the
    /// perpendicular offset, not from b^2 - 4ac, which cancels badly.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let f = ray.o - self.centre;
        let a = ray.d.length_squared();
        let b = -f.dot(ray.d);
        let perp = f + ray.d * (b / a);
        let disc = self.radius * self.radius - perp.length_squared();
        if disc < 0.0 {
            return None;
        }
        let c = f.length_squared() - self.radius * self.radius;
        let q = b + b.signum() * (a * disc).sqrt();
        if q == 0.0 {
            return None;
        }
        let t0 = c / q;
        let t1 = q / a;
        let (near, far) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
        if near > t_min && near < t_max {
            Some(near)
        } else if far > t_min && far < t_max {
            Some(far)
        } else {
            None
        }
    }

    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.centre - Vec3::splat(self.radius),
            max: self.centre + Vec3::splat(self.radius),
        }
    }

    pub fn area(&self) -> f32 {
        4.0 * std::f32::consts::PI * self.radius * self.radius
    }
}

/// pbrt-v4's sphere parametrisation about the z axis: the texture
/// coordinates of the point whose unit normal is `n` (in the sphere's own
/// frame).
pub fn sphere_uv(n: Vec3) -> Vec2 {
    let phi = n.y.atan2(n.x).rem_euclid(std::f32::consts::TAU);
    Vec2::new(
        phi / std::f32::consts::TAU,
        1.0 - n.z.clamp(-1.0, 1.0).acos() / std::f32::consts::PI,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_front_and_inside() {
        let s = Sphere {
            centre: Vec3::new(0.0, 0.0, 5.0),
            radius: 1.0,
        };
        let t = s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), 0.0, f32::INFINITY).unwrap();
        assert!((t - 4.0).abs() < 1e-5);
        let t = s
            .intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z), 0.0, f32::INFINITY)
            .unwrap();
        assert!((t - 1.0).abs() < 1e-5);
        assert!(s
            .intersect(&Ray::new(Vec3::ZERO, -Vec3::Z), 0.0, f32::INFINITY)
            .is_none());
        assert!(s
            .intersect(&Ray::new(Vec3::new(0.0, 1.01, 0.0), Vec3::Z), 0.0, f32::INFINITY)
            .is_none());
    }
}
