//! Tests of every light: sampling against closed forms, densities, emitted power.

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
