//! Specular light paths seen from the camera.

use raytracer::integrator::{render, IntegratorKind, RenderSettings};
use raytracer::light::Light;
use raytracer::material::Material;
use raytracer::math::Vec3;
use raytracer::scene::{CameraDesc, SceneDesc, SceneSettings, TriangleDesc};
use raytracer::Scene;
use std::f32::consts::PI;

fn quad(d: &mut SceneDesc, c: Vec3, u: Vec3, v: Vec3, m: u32) {
    let (a, b, e, f) = (c - u - v, c + u - v, c + u + v, c - u + v);
    d.triangles.push(TriangleDesc {
        vertices: [a, b, e],
        normals: None,
        material: m,
    });
    d.triangles.push(TriangleDesc {
        vertices: [a, e, f],
        normals: None,
        material: m,
    });
}

#[test]
fn mirror_at_45_degrees_shows_the_wall_beside_it() {
    let power = 20.0;
    let albedo = Vec3::new(0.7, 0.2, 0.1);
    let mut d = SceneDesc {
        name: "mirror".into(),
        camera: CameraDesc {
            position: Vec3::ZERO,
            look_at: Vec3::Z,
            up: Vec3::Y,
            fov_y_deg: 1.0,
            width: 3,
            height: 3,
        },
        materials: vec![],
        triangles: vec![],
        spheres: vec![],
        lights: vec![Light::Point {
            position: Vec3::new(1.5, 0.0, 2.0),
            power: Vec3::splat(power),
        }],
        settings: SceneSettings::default(),
    };
    let mirror = d.material("mirror", Material::Mirror { reflectance: Vec3::ONE });
    let wall = d.material("wall", Material::Diffuse { albedo });
    let diag = Vec3::new(1.0, 0.0, 1.0).normalize() * 0.5;
    quad(&mut d, Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.5, 0.0), diag, mirror);
    quad(
        &mut d,
        Vec3::new(3.0, 0.0, 2.0),
        Vec3::new(0.0, 5.0, 0.0),
        Vec3::new(0.0, 0.0, 5.0),
        wall,
    );
    let scene = Scene::build(d).unwrap();
    let settings = RenderSettings {
        ssaa: 2,
        integrator: IntegratorKind::Direct,
        ..Default::default()
    };
    let px = render(&scene, &settings, &|| {}).unwrap().film.get(1, 1);
    // The camera sees the wall point (3, 0, 2), 1.5 from the light, head on.
    let want = albedo / PI * power / (4.0 * PI * 1.5 * 1.5);
    assert!(
        (px - want).abs().max_element() < 0.01 * want.max_element(),
        "{px:?} vs {want:?}"
    );
}

#[test]
fn path_tracer_sees_a_light_in_a_mirror() {
    // The camera looks at a half-silvered mirror at 45 degrees that shows a
    // sphere light: next-event estimation cannot reach a light through a
    // delta BSDF, so the path tracer must count the light's Le right after the
    // specular bounce, times the reflectance.
    let power = 20.0;
    let r = 0.5;
    let mut d = SceneDesc {
        name: "mirror-light".into(),
        camera: CameraDesc {
            position: Vec3::ZERO,
            look_at: Vec3::Z,
            up: Vec3::Y,
            fov_y_deg: 1.0,
            width: 3,
            height: 3,
        },
        materials: vec![],
        triangles: vec![],
        spheres: vec![],
        lights: vec![Light::Sphere {
            sphere: raytracer::geometry::Sphere {
                centre: Vec3::new(3.0, 0.0, 2.0),
                radius: r,
            },
            power: Vec3::splat(power),
        }],
        settings: SceneSettings::default(),
    };
    let reflectance = Vec3::new(0.5, 0.8, 1.0);
    let mirror = d.material("mirror", Material::Mirror { reflectance });
    let diag = Vec3::new(1.0, 0.0, 1.0).normalize() * 0.5;
    quad(&mut d, Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.5, 0.0), diag, mirror);
    let scene = Scene::build(d).unwrap();
    let le = power / (PI * 4.0 * PI * r * r);
    for integrator in [IntegratorKind::Path, IntegratorKind::Direct] {
        let settings = RenderSettings {
            ssaa: 2,
            spp: 4,
            integrator,
            ..Default::default()
        };
        let px = render(&scene, &settings, &|| {}).unwrap().film.get(1, 1);
        let want = reflectance * le;
        assert!(
            (px - want).abs().max_element() < 1e-3 * want.max_element(),
            "{integrator:?}: {px:?} vs {want:?}"
        );
    }
}
