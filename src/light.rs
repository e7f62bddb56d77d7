//! Lights, with pbrt's two faces: incident-light sampling for shadow rays
//! (`sample_li`) and particle emission for photon tracing (`sample_le`).
//! A sphere light is a Lambertian emitter given by its total power Phi, so
//! its radiance is Phi / (pi * area). A point light of the same power has
//! intensity Phi / (4 pi).

use crate::geometry::Sphere;
use crate::math::{to_world, Ray, Vec2, Vec3};
use crate::sampling::{cosine_hemisphere, uniform_cone, uniform_sphere};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    Sphere { sphere: Sphere, power: Vec3 },
    Point { position: Vec3, power: Vec3 },
}

/// One sample of the light arriving at a point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction towards the light.
    pub wi: Vec3,
    /// Distance to the sampled point on the light.
    pub dist: f32,
    /// Incident radiance divided by the solid-angle pdf (for a point light,
    /// the irradiance at normal incidence).
    pub weight: Vec3,
}

impl Light {
    pub fn power(&self) -> Vec3 {
        match self {
            Light::Sphere { power, .. } | Light::Point { power, .. } => *power,
        }
    }

    pub fn position(&self) -> Vec3 {
        match self {
            Light::Sphere { sphere, .. } => sphere.centre,
            Light::Point { position, .. } => *position,
        }
    }

    /// Emitted radiance of the surface (zero for a point light, which has none).
    pub fn radiance(&self) -> Vec3 {
        match self {
            Light::Sphere { sphere, power } => *power / (PI * sphere.area()),
            Light::Point { .. } => Vec3::ZERO,
        }
    }

    /// Samples a direction towards the light from `p`, uniformly over the
    /// cone the sphere subtends (pbrt-v4 6.2.4: exact for a sphere, every
    /// sample lands on the visible cap).
    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        match self {
            Light::Point { position, power } => {
                let v = *position - p;
                let d2 = v.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let dist = d2.sqrt();
                Some(LightSample {
                    wi: v / dist,
                    dist,
                    weight: *power / (4.0 * PI * d2),
                })
            }
            Light::Sphere { sphere, .. } => {
                let v = sphere.centre - p;
                let dc2 = v.length_squared();
                let r2 = sphere.radius * sphere.radius;
                if dc2 <= r2 {
                    return None;
                }
                let dc = dc2.sqrt();
                let axis = v / dc;
                let sin2_max = r2 / dc2;
                let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
                // 1 - cos_max without cancellation for small, distant lights.
                let one_minus_cos_max = sin2_max / (1.0 + cos_max);
                let wi = to_world(uniform_cone(u, one_minus_cos_max), axis).normalize();
                // Distance to the near side of the sphere along wi.
                let b = wi.dot(v);
                let disc = r2 - (v - wi * b).length_squared();
                let dist = if disc > 0.0 {
                    b - disc.sqrt()
                } else {
                    (dc2 - r2).max(0.0).sqrt()
                };
                let solid_angle = 2.0 * PI * one_minus_cos_max;
                Some(LightSample {
                    wi,
                    dist,
                    weight: self.radiance() * solid_angle,
                })
            }
        }
    }

    /// Emits a particle: a ray leaving the light, distributed as its emission
    /// (uniform over a sphere's surface, cosine-weighted outward; uniform in
    /// direction for a point light). Each particle carries Phi / N.
    pub fn sample_le(&self, u1: Vec2, u2: Vec2) -> (Ray, Vec3) {
        match self {
            Light::Point { position, .. } => (Ray::new(*position, uniform_sphere(u1)), Vec3::ZERO),
            Light::Sphere { sphere, .. } => {
                let n = uniform_sphere(u1);
                let d = to_world(cosine_hemisphere(u2), n).normalize();
                let o = sphere.centre + n * (sphere.radius * (1.0 + 1e-4));
                (Ray::new(o, d), n)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn sphere_light_radiance_matches_scene_definition() {
        let l = Light::Sphere {
            sphere: Sphere {
                centre: Vec3::ZERO,
                radius: 0.1,
            },
            power: Vec3::splat(14.0 * PI),
        };
        assert!((l.radiance().x - 111.41).abs() < 0.01);
    }

    #[test]
    fn small_sphere_irradiance_matches_point_light() {
        let power = Vec3::splat(14.0 * PI);
        let sphere = Light::Sphere {
            sphere: Sphere {
                centre: Vec3::new(0.0, 0.0, 2.0),
                radius: 0.01,
            },
            power,
        };
        let point = Light::Point {
            position: Vec3::new(0.0, 0.0, 2.0),
            power,
        };
        let mut rng = Rng::new(1, 1);
        let mut e = 0.0;
        let n = 10_000;
        for _ in 0..n {
            let s = sphere.sample_li(Vec3::ZERO, rng.next_2d()).unwrap();
            assert!((s.dist - 1.99).abs() < 0.011);
            e += s.weight.x * s.wi.z;
        }
        let e = e / n as f32;
        let p = point.sample_li(Vec3::ZERO, Vec2::ZERO).unwrap();
        assert!((e - p.weight.x).abs() / p.weight.x < 1e-3, "{e} vs {}", p.weight.x);
    }

    #[test]
    fn emitted_particles_leave_the_surface_outwards() {
        let l = Light::Sphere {
            sphere: Sphere {
                centre: Vec3::new(1.0, 2.0, 3.0),
                radius: 0.5,
            },
            power: Vec3::ONE,
        };
        let mut rng = Rng::new(3, 3);
        for _ in 0..1000 {
            let (ray, n) = l.sample_le(rng.next_2d(), rng.next_2d());
            assert!(((ray.o - Vec3::new(1.0, 2.0, 3.0)).length() - 0.5).abs() < 1e-3);
            assert!(ray.d.dot(n) >= 0.0);
        }
    }
}
