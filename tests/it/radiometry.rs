//! Radiometry against closed-form answers: a Lambertian plane under a point
//! light, and a small sphere light against the point light of equal power.

use raytracer::geometry::Sphere;
use raytracer::integrator::{render, IntegratorKind, RenderSettings};
use raytracer::light::Light;
use raytracer::material::Material;
use raytracer::math::Vec3;
use raytracer::scene::{CameraDesc, SceneDesc, SceneSettings, TriangleDesc};
use raytracer::Scene;
use std::f32::consts::PI;

const ALBEDO: f32 = 0.6;
const POWER: f32 = 10.0;
const HEIGHT: f32 = 2.0;

/// A 20x20 plane at y = 0 seen from above by a narrow camera aimed at the
/// point straight below the light at (0, HEIGHT, 0).
fn plane_scene(light: Light) -> SceneDesc {
    let mut d = SceneDesc {
        name: "plane".into(),
        camera: CameraDesc {
            position: Vec3::new(0.0, 1.0, 0.0),
            look_at: Vec3::ZERO,
            up: Vec3::Z,
            fov_y_deg: 0.5,
            width: 5,
            height: 5,
            window: None,
            lens: None,
            orthographic: None,
            spherical: None,
            realistic: None,
        },
        materials: vec![],
        triangles: Default::default(),
        spheres: vec![],
        disks: vec![],
        curves: vec![],
        lights: vec![light],
        light_surfaces: vec![],
        invisible_lights: vec![],
        cutouts: vec![],
        media: vec![],
        camera_medium: None,
        boundaries: vec![],
        settings: SceneSettings::default(),
        texture_spp: 64,
        moving: vec![],
        moving_shapes: vec![],
        shutter: [0.0, 1.0],
        camera_motion: None,
        light_sampler: Default::default(),
    };
    let m = d.material("plane", Material::diffuse(ALBEDO, ALBEDO, ALBEDO));
    let s = 10.0;
    let (a, b, c, e) = (
        Vec3::new(-s, 0.0, -s),
        Vec3::new(s, 0.0, -s),
        Vec3::new(s, 0.0, s),
        Vec3::new(-s, 0.0, s),
    );
    for v in [[a, b, c], [a, c, e]] {
        d.triangles.push(TriangleDesc {
            vertices: v,
            normals: None,
            uvs: None,
            material: m,
        });
    }
    d
}

fn centre_radiance(desc: SceneDesc, shadow_samples: u32) -> f32 {
    let scene = Scene::build(desc).unwrap();
    let settings = RenderSettings {
        ssaa: 2,
        shadow_samples,
        integrator: IntegratorKind::Direct,
        ..RenderSettings::default()
    };
    let out = render(&scene, &settings, &|| {}).unwrap();
    out.film.get(2, 2).x
}

#[test]
fn plane_under_point_light_matches_closed_form() {
    let light = Light::Point {
        position: Vec3::new(0.0, HEIGHT, 0.0),
        power: Vec3::splat(POWER),
    };
    let got = centre_radiance(plane_scene(light), 1);
    let want = ALBEDO / PI * POWER / (4.0 * PI * HEIGHT * HEIGHT);
    assert!((got - want).abs() / want < 0.005, "radiance {got}, expected {want}");
}

#[test]
fn small_sphere_light_matches_point_light() {
    let point = Light::Point {
        position: Vec3::new(0.0, HEIGHT, 0.0),
        power: Vec3::splat(POWER),
    };
    let sphere = Light::Sphere {
        sphere: Sphere {
            centre: Vec3::new(0.0, HEIGHT, 0.0),
            radius: 0.05,
        },
        power: Vec3::splat(POWER),
        image: None,
        emits: Default::default(),
    };
    let lp = centre_radiance(plane_scene(point), 1);
    let ls = centre_radiance(plane_scene(sphere), 64);
    assert!((ls - lp).abs() / lp < 0.01, "sphere {ls} vs point {lp}");
}

#[test]
fn radiance_falls_with_the_square_of_height() {
    let near = Light::Point {
        position: Vec3::new(0.0, 1.5, 0.0),
        power: Vec3::splat(POWER),
    };
    let far = Light::Point {
        position: Vec3::new(0.0, 3.0, 0.0),
        power: Vec3::splat(POWER),
    };
    let (a, b) = (
        centre_radiance(plane_scene(near), 1),
        centre_radiance(plane_scene(far), 1),
    );
    assert!((a / b - 4.0).abs() < 0.02, "ratio {}", a / b);
}

#[test]
fn a_sphere_light_never_shadows_its_own_samples() {
    // Every point of the plane sees the whole light, so no single shadow
    // sample may come back black.
    let light = Light::Sphere {
        sphere: Sphere {
            centre: Vec3::new(0.0, HEIGHT, 0.0),
            radius: 0.5,
        },
        power: Vec3::splat(POWER),
        image: None,
        emits: Default::default(),
    };
    let mut desc = plane_scene(light);
    desc.camera.fov_y_deg = 60.0;
    desc.camera.width = 64;
    desc.camera.height = 64;
    let scene = Scene::build(desc).unwrap();
    let settings = RenderSettings {
        ssaa: 1,
        shadow_samples: 1,
        integrator: IntegratorKind::Direct,
        ..Default::default()
    };
    let film = render(&scene, &settings, &|| {}).unwrap().film;
    let black = film.pixels.iter().filter(|p| p.x <= 0.0).count();
    assert_eq!(
        black,
        0,
        "{black} of {} pixels lost their light sample",
        film.pixels.len()
    );
}

#[test]
fn light_choice_follows_power_and_leaves_a_uniform_remainder() {
    // Three point lights of power 1, 0 and 3: chosen with probability 1/4,
    // 0 and 3/4, and the rescaled sample spans [0, 1) within each choice in
    // order, so one uniform number picks the light and still places the point.
    let mut d = plane_scene(Light::Point {
        position: Vec3::new(0.0, HEIGHT, 0.0),
        power: Vec3::splat(1.0),
    });
    for p in [0.0, 3.0] {
        d.lights.push(Light::Point {
            position: Vec3::new(1.0, HEIGHT, 0.0),
            power: Vec3::splat(p),
        });
    }
    let scene = Scene::build(d).unwrap();
    let n = 4096;
    let mut counts = [0usize; 3];
    let mut last = [-1.0f32; 3];
    for k in 0..n {
        let u = (k as f32 + 0.5) / n as f32;
        let (i, pmf, rest) = scene.pick_light(u).unwrap();
        counts[i] += 1;
        assert!((0.0..1.0).contains(&rest), "u {u}: remainder {rest}");
        assert!(rest > last[i], "u {u}: the remainder must grow with u within a choice");
        last[i] = rest;
        let expected_pmf = [0.25, 0.0, 0.75][i];
        assert!((pmf - expected_pmf).abs() < 1e-6, "light {i}: pmf {pmf}");
        // Where u falls within the light's share of the unit interval.
        let start = [0.0, 0.25, 0.25][i];
        let expected_rest = (u - start) / expected_pmf;
        assert!((rest - expected_rest).abs() < 1e-4, "u {u}: {rest} vs {expected_rest}");
    }
    assert_eq!(counts, [n / 4, 0, 3 * n / 4]);
}

#[test]
fn light_choice_at_the_cdfs_own_steps_takes_the_light_that_starts_there() {
    // Targets on the cumulative powers themselves (quarters of a total of
    // 16, exact in f32), where a search for the first entry above the target
    // and one for the first at or above it part: the light that starts at
    // the target is chosen, never one of no power, whether the scene has a
    // few lights (counted) or many (searched).
    let powers = [1.0f32, 0.0, 3.0, 0.0, 0.0, 2.0, 4.0, 1.0, 0.0, 3.0, 1.0, 1.0];
    for (n, total) in [(5, 4.0f32), (12, 16.0)] {
        let mut d = plane_scene(Light::Point {
            position: Vec3::new(0.0, HEIGHT, 0.0),
            power: Vec3::splat(powers[0]),
        });
        for &p in &powers[1..n] {
            d.lights.push(Light::Point {
                position: Vec3::new(1.0, HEIGHT, 0.0),
                power: Vec3::splat(p),
            });
        }
        let scene = Scene::build(d).unwrap();
        let cdf: Vec<f32> = powers[..n]
            .iter()
            .scan(0.0, |acc, p| {
                *acc += p;
                Some(*acc)
            })
            .collect();
        let steps = (4.0 * total) as u32;
        for k in 0..steps {
            let u = k as f32 / steps as f32;
            let target = u * total;
            let expected = cdf.iter().position(|&c| c > target).unwrap();
            let (i, pmf, rest) = scene.pick_light(u).unwrap();
            assert_eq!(i, expected, "{n} lights, u {u}");
            assert_eq!(pmf, powers[i] / total, "{n} lights, u {u}");
            let before = if i == 0 { 0.0 } else { cdf[i - 1] };
            assert!(
                (rest - (target - before) / powers[i]).abs() < 1e-6,
                "{n} lights, u {u}: {rest}"
            );
        }
    }
}
