//! Lights, with pbrt's two faces: incident-light sampling for shadow rays
//! (`sample_li`, with its solid-angle density `pdf_li`) and particle emission
//! for photon tracing (`sample_le`).
//! A sphere light is a Lambertian emitter given by its total power Phi, so
//! its radiance is Phi / (pi * area). A point light of the same power has
//! intensity Phi / (4 pi). A triangle light is a diffuse area light (pbrt-v4's
//! `DiffuseAreaLight` on one triangle; meshes and quads are several) given by
//! its radiance, emitting on the side its normal, (v1 - v0) x (v2 - v0),
//! points to, or on both sides; its power is L * pi * area per side.

use crate::geometry::Sphere;
use crate::math::{to_world, Ray, Vec2, Vec3};
use crate::sampling::{cosine_hemisphere, uniform_cone, uniform_sphere};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    Sphere {
        sphere: Sphere,
        power: Vec3,
    },
    Point {
        position: Vec3,
        power: Vec3,
    },
    Triangle {
        vertices: [Vec3; 3],
        radiance: Vec3,
        two_sided: bool,
    },
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
            Light::Triangle {
                vertices,
                radiance,
                two_sided,
            } => {
                let sides = if *two_sided { 2.0 } else { 1.0 };
                *radiance * (PI * triangle_area(vertices) * sides)
            }
        }
    }

    /// Where the light is: its centre (a triangle's centroid).
    pub fn position(&self) -> Vec3 {
        match self {
            Light::Sphere { sphere, .. } => sphere.centre,
            Light::Point { position, .. } => *position,
            Light::Triangle { vertices: v, .. } => (v[0] + v[1] + v[2]) / 3.0,
        }
    }

    /// Emitted radiance of the surface (zero for a point light, which has none).
    pub fn radiance(&self) -> Vec3 {
        match self {
            Light::Sphere { sphere, power } => *power / (PI * sphere.area()),
            Light::Point { .. } => Vec3::ZERO,
            Light::Triangle { radiance, .. } => *radiance,
        }
    }

    /// Radiance leaving the light's surface towards `w` (a one-sided light
    /// is dark from behind).
    pub fn le(&self, w: Vec3) -> Vec3 {
        match self {
            Light::Triangle {
                vertices,
                two_sided: false,
                ..
            } if triangle_normal(vertices).dot(w) <= 0.0 => Vec3::ZERO,
            _ => self.radiance(),
        }
    }

    /// Moves the light's centre to `to`, keeping its size, shape and power.
    pub fn move_to(&mut self, to: Vec3) {
        let by = to - self.position();
        match self {
            Light::Sphere { sphere, .. } => sphere.centre = to,
            Light::Point { position, .. } => *position = to,
            Light::Triangle { vertices, .. } => vertices.iter_mut().for_each(|v| *v += by),
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
            Light::Triangle {
                vertices: v,
                radiance,
                two_sided,
            } => {
                // Uniform in area (pbrt-v4 6.5.4), then to solid angle at p.
                let q = uniform_triangle(v, u);
                let d = q - p;
                let d2 = d.length_squared();
                let area = triangle_area(v);
                if d2 == 0.0 || area == 0.0 {
                    return None;
                }
                let dist = d2.sqrt();
                let wi = d / dist;
                let cos_l = -triangle_normal(v).dot(wi);
                let cos_l = if *two_sided { cos_l.abs() } else { cos_l };
                if cos_l <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    dist,
                    weight: *radiance * (cos_l * area / d2),
                })
            }
        }
    }

    /// `pdf_li` for a direction known to reach the light at `q` (a ray from
    /// `p` hit it there): no intersection test that could disagree with the
    /// one that found the hit near an edge or silhouette.
    pub fn pdf_li_hit(&self, p: Vec3, wi: Vec3, q: Vec3) -> f32 {
        match self {
            Light::Point { .. } => 0.0,
            Light::Sphere { sphere, .. } => {
                let dc2 = (sphere.centre - p).length_squared();
                let r2 = sphere.radius * sphere.radius;
                if dc2 <= r2 {
                    return 0.0;
                }
                let sin2_max = r2 / dc2;
                let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
                1.0 / (2.0 * PI * (sin2_max / (1.0 + cos_max)))
            }
            Light::Triangle {
                vertices: v, two_sided, ..
            } => {
                let cos_l = -triangle_normal(v).dot(wi);
                let cos_l = if *two_sided { cos_l.abs() } else { cos_l };
                let area = triangle_area(v);
                if cos_l <= 0.0 || area == 0.0 {
                    return 0.0;
                }
                (q - p).length_squared() / (cos_l * area)
            }
        }
    }

    /// Solid-angle density with which `sample_li` at `p` picks direction `wi`
    /// (zero where it never does; a point light's is a delta, reported as 0).
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        match self {
            Light::Point { .. } => 0.0,
            Light::Sphere { sphere, .. } => {
                let v = sphere.centre - p;
                let dc2 = v.length_squared();
                let r2 = sphere.radius * sphere.radius;
                if dc2 <= r2 {
                    return 0.0;
                }
                let sin2_max = r2 / dc2;
                let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
                if wi.dot(v) < cos_max * dc2.sqrt() {
                    return 0.0;
                }
                1.0 / (2.0 * PI * (sin2_max / (1.0 + cos_max)))
            }
            Light::Triangle {
                vertices: v, two_sided, ..
            } => {
                let tri = crate::geometry::Triangle::new(v[0], v[1], v[2]);
                let Some(t) = tri.intersect_mt(&Ray::new(p, wi), 0.0, f32::INFINITY).map(|h| h.t) else {
                    return 0.0;
                };
                let cos_l = -triangle_normal(v).dot(wi);
                let cos_l = if *two_sided { cos_l.abs() } else { cos_l };
                let area = triangle_area(v);
                if cos_l <= 0.0 || area == 0.0 {
                    return 0.0;
                }
                t * t / (cos_l * area)
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
            Light::Triangle {
                vertices: v, two_sided, ..
            } => {
                let mut n = triangle_normal(v);
                let mut u2 = u2;
                // Both sides emit alike: the first coordinate picks one and is reused.
                if *two_sided {
                    if u2.x < 0.5 {
                        u2.x *= 2.0;
                    } else {
                        u2.x = u2.x * 2.0 - 1.0;
                        n = -n;
                    }
                    u2.x = u2.x.min(1.0 - f32::EPSILON);
                }
                let q = uniform_triangle(v, u1);
                let d = to_world(cosine_hemisphere(u2), n).normalize();
                (Ray::new(crate::math::offset_origin(q, n, d), d), n)
            }
        }
    }
}

/// Unit normal (v1 - v0) x (v2 - v0) of a triangle (zero if degenerate).
pub fn triangle_normal(v: &[Vec3; 3]) -> Vec3 {
    (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero()
}

pub fn triangle_area(v: &[Vec3; 3]) -> f32 {
    0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length()
}

/// A point uniformly distributed over the triangle (pbrt-v4's
/// `SampleUniformTriangle`, which keeps strata apart).
pub fn uniform_triangle(v: &[Vec3; 3], u: Vec2) -> Vec3 {
    let (b0, b1) = if u.x < u.y {
        let b0 = u.x / 2.0;
        (b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        (u.x - b1, b1)
    };
    v[0] * b0 + v[1] * b1 + v[2] * (1.0 - b0 - b1)
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

    /// A quad light of radiance `l` over [0, w] x [0, len] at height h, facing down.
    fn quad(w: f32, len: f32, h: f32, l: f32, two_sided: bool) -> [Light; 2] {
        let (a, b, c, d) = (
            Vec3::new(0.0, 0.0, h),
            Vec3::new(0.0, len, h),
            Vec3::new(w, len, h),
            Vec3::new(w, 0.0, h),
        );
        [[a, b, c], [a, c, d]].map(|vertices| Light::Triangle {
            vertices,
            radiance: Vec3::splat(l),
            two_sided,
        })
    }

    #[test]
    fn quad_light_irradiance_is_the_rectangle_form_factor() {
        // A point under a corner of a parallel rectangle: E = L pi F, with
        // F = (1 / 2 pi) (a/sqrt(1+a^2) atan(b/sqrt(1+a^2)) + b/sqrt(1+b^2) atan(a/sqrt(1+b^2))),
        // a = w / h, b = len / h (Howell's catalogue, configuration B-3).
        for (w, len, h) in [(1.0f32, 1.0f32, 1.0f32), (2.0, 0.5, 0.7), (0.3, 3.0, 2.0)] {
            let (a, b) = ((w / h) as f64, (len / h) as f64);
            let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
            let f = (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * std::f64::consts::PI);
            let expected = 3.0 * std::f64::consts::PI * f;
            let mut rng = Rng::new(7, 1);
            let n = 200_000;
            let mut e = 0.0f64;
            for l in quad(w, len, h, 3.0, false) {
                for _ in 0..n {
                    if let Some(s) = l.sample_li(Vec3::ZERO, rng.next_2d()) {
                        e += (s.weight.x * s.wi.z.max(0.0)) as f64 / n as f64;
                        // The weight is radiance over the solid-angle density.
                        let pdf = l.pdf_li(Vec3::ZERO, s.wi);
                        assert!((s.weight.x * pdf / 3.0 - 1.0).abs() < 1e-3, "{} {pdf}", s.weight.x);
                        let at = l.pdf_li_hit(Vec3::ZERO, s.wi, s.wi * s.dist);
                        assert!((at / pdf - 1.0).abs() < 1e-3, "{at} vs {pdf}");
                    }
                }
            }
            assert!((e / expected - 1.0).abs() < 0.01, "{w}x{len} at {h}: {e} vs {expected}");
            // From above, a one-sided light gives nothing; a two-sided one the same.
            let above = Vec3::new(0.1, 0.1, 2.0 * h);
            let u = Vec2::new(0.3, 0.6);
            assert!(quad(w, len, h, 3.0, false)[0].sample_li(above, u).is_none());
            assert!(quad(w, len, h, 3.0, true)[0].sample_li(above, u).is_some());
        }
    }

    #[test]
    fn triangle_lights_emit_their_power_from_their_emitting_sides() {
        for two_sided in [false, true] {
            let [l, _] = quad(2.0, 1.0, 1.0, 1.5, two_sided);
            let sides = if two_sided { 2.0 } else { 1.0 };
            assert!((l.power().x - 1.5 * PI * 1.0 * sides).abs() < 1e-4);
            let mut rng = Rng::new(5, 2);
            let (mut down, n) = (0, 20_000);
            for _ in 0..n {
                let (ray, normal) = l.sample_le(rng.next_2d(), rng.next_2d());
                assert!((ray.o.z - 1.0).abs() < 1e-3 && ray.d.dot(normal) >= 0.0);
                assert!(ray.o.x >= -1e-3 && ray.o.y >= ray.o.x * 0.5 - 1e-3, "{:?}", ray.o);
                down += (ray.d.z < 0.0) as u32;
            }
            let expected = if two_sided { 0.5 } else { 1.0 };
            assert!((down as f32 / n as f32 - expected).abs() < 0.02, "{two_sided}: {down}");
            // Seen from below it shines; from above only when two-sided.
            assert_eq!(l.le(Vec3::new(0.0, 0.0, -1.0)), Vec3::splat(1.5));
            assert_eq!(l.le(Vec3::new(0.0, 0.0, 1.0)).x, if two_sided { 1.5 } else { 0.0 });
        }
    }

    #[test]
    fn sphere_pdf_li_is_one_over_the_cone() {
        let l = Light::Sphere {
            sphere: Sphere {
                centre: Vec3::new(0.0, 0.0, 2.0),
                radius: 0.5,
            },
            power: Vec3::ONE,
        };
        let mut rng = Rng::new(2, 2);
        for _ in 0..100 {
            let s = l.sample_li(Vec3::ZERO, rng.next_2d()).unwrap();
            let pdf = l.pdf_li(Vec3::ZERO, s.wi);
            assert!((s.weight.x * pdf / l.radiance().x - 1.0).abs() < 1e-3);
            assert_eq!(l.pdf_li_hit(Vec3::ZERO, s.wi, s.wi * s.dist), pdf);
        }
        assert_eq!(l.pdf_li(Vec3::ZERO, Vec3::X), 0.0);
    }
}
