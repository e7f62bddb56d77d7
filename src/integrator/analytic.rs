//! Scenes with known answers for integrator and photon tests: the inside of a
//! diffuse sphere (white furnace, or lit by a small sphere light at its centre),
//! a closed diffuse box, and a closed box whose walls are lights that reflect.

use crate::geometry::Sphere;
use crate::light::Light;
use crate::material::Material;
use crate::math::Vec3;
use crate::scene::{CameraDesc, LightSurface, Scene, SceneDesc, SphereDesc, TriangleDesc};

/// The description of a scene given as pbrt-v4 text.
pub fn pbrt_desc(text: &str) -> SceneDesc {
    let path = std::path::Path::new("test.pbrt");
    let parsed = crate::scene::pbrt::parse_bytes(path, text.as_bytes().to_vec(), &crate::scene::mesh::Disk)
        .unwrap_or_else(|e| panic!("{e}"));
    crate::scene::pbrt::convert::convert(&parsed, path, false)
        .unwrap_or_else(|e| panic!("{e}"))
        .desc
}

/// A pbrt-v4 `trianglemesh` quad with corners `p` (twelve numbers), and
/// vertex normal `n` (three) at every corner when given.
pub fn pbrt_quad(p: &str, n: Option<&str>) -> String {
    let normals = n.map_or(String::new(), |n| format!("\"normal N\" [ {n} {n} {n} {n} ] "));
    format!("Shape \"trianglemesh\" \"point3 P\" [ {p} ] {normals}\"integer indices\" [ 0 1 2 0 2 3 ]\n")
}

fn empty(camera: CameraDesc) -> SceneDesc {
    SceneDesc::empty("analytic", camera)
}

/// A camera inside, off the centre, looking away from it at the wall.
fn inside_camera(size: u32) -> CameraDesc {
    CameraDesc {
        position: Vec3::new(0.0, 0.0, 0.3),
        look_at: Vec3::new(0.0, 0.0, 1.0),
        up: Vec3::Y,
        fov_y_deg: 60.0,
        width: size,
        height: size,
        window: None,
        lens: None,
        orthographic: None,
        spherical: None,
        realistic: None,
    }
}

/// The inside of a sphere of radius 1 at the origin, of the given material,
/// with an optional sphere light (radius, power) at its centre.
pub fn closed_sphere(material: Material, light: Option<(f32, f32)>, size: u32) -> Scene {
    Scene::build(closed_sphere_desc(material, light, size)).unwrap()
}

/// `closed_sphere`'s description.
pub fn closed_sphere_desc(material: Material, light: Option<(f32, f32)>, size: u32) -> SceneDesc {
    let mut d = empty(inside_camera(size));
    let m = d.material("wall", material);
    d.spheres.push(SphereDesc {
        axes: None,
        sphere: Sphere {
            centre: Vec3::ZERO,
            radius: 1.0,
        },
        material: m,
    });
    if let Some((radius, power)) = light {
        d.lights.push(Light::Sphere {
            sphere: Sphere {
                centre: Vec3::ZERO,
                radius,
            },
            power: Vec3::splat(power),
            image: None,
            emits: Default::default(),
        });
    }
    d
}

/// A grey floor (albedo 0.5, the plane z = 0) under a one-sided 1 x 1 quad
/// light of radiance 2 facing down at height 1, over [0, 1]^2, seen from
/// (0, 0, 3).
pub fn floor_under_quad() -> SceneDesc {
    let camera = CameraDesc {
        position: Vec3::new(0.0, 0.0, 3.0),
        look_at: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_deg: 40.0,
        width: 8,
        height: 8,
        window: None,
        lens: None,
        orthographic: None,
        spherical: None,
        realistic: None,
    };
    let mut d = SceneDesc::empty("floor", camera);
    let grey = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
    d.triangles.push(TriangleDesc {
        vertices: [
            Vec3::new(-9.0, -9.0, 0.0),
            Vec3::new(9.0, -9.0, 0.0),
            Vec3::new(0.0, 9.0, 0.0),
        ],
        normals: None,
        uvs: None,
        material: grey,
    });
    let (a, b, c, e) = (
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
    );
    for vertices in [[a, b, c], [a, c, e]] {
        d.lights.push(Light::Triangle {
            vertices,
            radiance: Vec3::splat(2.0),
            two_sided: false,
            image: None,
        });
    }
    d
}

/// The 12 triangles of the cube [-1, 1]^3.
fn cube_triangles() -> Vec<[Vec3; 3]> {
    let c = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -1.0 } else { 1.0 },
        )
    };
    // Each face as two triangles over its four corners.
    let faces = [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 3, 7, 5],
    ];
    faces
        .iter()
        .flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]])
        .map(|t| t.map(c))
        .collect()
}

/// A closed cube [-1, 1]^3 of 12 triangles of one grey albedo, lit by `light`.
pub fn closed_box(albedo: f32, light: Light) -> Scene {
    let mut d = empty(inside_camera(8));
    let m = d.material("wall", Material::diffuse(albedo, albedo, albedo));
    for vertices in cube_triangles() {
        d.triangles.push(TriangleDesc {
            vertices,
            normals: None,
            uvs: None,
            material: m,
        });
    }
    d.lights.push(light);
    Scene::build(d).unwrap()
}

/// The cube [-1, 1]^3 whose walls are one-sided triangle lights of
/// radiance `le` facing in, each reflecting by `wall` (pbrt-v4's emitters
/// keep their material). With a Lambertian `wall` of albedo a the radiance
/// is `le / (1 - a)` everywhere inside.
pub fn glowing_box(wall: Material, le: f32, size: u32) -> SceneDesc {
    let mut d = empty(inside_camera(size));
    let m = d.material("wall", wall);
    for [a, b, c] in cube_triangles() {
        // Emitting on the side of (b - a) x (c - a): inwards.
        let outwards = (b - a).cross(c - a).dot(a + b + c) > 0.0;
        d.lights.push(Light::Triangle {
            vertices: if outwards { [a, c, b] } else { [a, b, c] },
            radiance: Vec3::splat(le),
            two_sided: false,
            image: None,
        });
        d.light_surfaces.push(Some(LightSurface {
            material: m,
            ..LightSurface::default()
        }));
    }
    d
}

/// A white furnace (the inside of a unit sphere of an emissive Lambertian
/// material, whose radiance is `le / (1 - albedo)` everywhere) with balls of
/// other materials (centre, radius, material) in front of the camera. Lossless
/// mirrors and glass leave the uniform radiance unchanged.
pub fn furnace_with_balls(wall: Material, balls: &[(Vec3, f32, Material)], size: u32) -> Scene {
    let mut d = empty(inside_camera(size));
    let m = d.material("wall", wall);
    d.spheres.push(SphereDesc {
        axes: None,
        sphere: Sphere {
            centre: Vec3::ZERO,
            radius: 1.0,
        },
        material: m,
    });
    for (i, (centre, radius, material)) in balls.iter().enumerate() {
        let (centre, radius) = (*centre, *radius);
        let m = d.material(&format!("ball{i}"), material.clone());
        d.spheres.push(SphereDesc {
            axes: None,
            sphere: Sphere { centre, radius },
            material: m,
        });
    }
    Scene::build(d).unwrap()
}

/// A path-traced render's settings: `spp` samples, at most `max_depth` bounces.
#[cfg(test)]
pub fn path_settings(spp: u32, max_depth: Option<u32>) -> super::RenderSettings {
    super::RenderSettings {
        integrator: super::IntegratorKind::Path,
        spp,
        max_depth,
        ..super::RenderSettings::default()
    }
}

/// A grey ball (albedo `a`, radius 0.12) in front of the camera inside a
/// unit sphere light of radiance `le` that emits inwards (pbrt-v4's sphere
/// under `ReverseOrientation`), or both ways, and reflects nothing: the
/// ball's radiance is `a le` everywhere on it (it sees only the light),
/// the light's `le`.
pub fn ball_in_a_glowing_sphere(a: f32, le: f32, emits: crate::light::Emits) -> Scene {
    let mut d = empty(inside_camera(16));
    let m = d.material("ball", Material::diffuse(a, a, a));
    d.spheres.push(SphereDesc {
        axes: None,
        sphere: Sphere {
            centre: Vec3::new(0.0, 0.0, 0.65),
            radius: 0.12,
        },
        material: m,
    });
    d.lights.push(unit_sphere_light(Vec3::ZERO, le, emits));
    Scene::build(d).unwrap()
}

/// A sphere light of radius 1 at `centre` whose radiance is `le` on each
/// side it emits from.
fn unit_sphere_light(centre: Vec3, le: f32, emits: crate::light::Emits) -> Light {
    let sphere = Sphere { centre, radius: 1.0 };
    Light::Sphere {
        power: Vec3::splat(le * std::f32::consts::PI * sphere.area() * emits.sides()),
        sphere,
        image: None,
        emits,
    }
}

/// An integrating sphere: the inside of a unit sphere light of radiance
/// `le` that emits inwards (or both ways) and reflects by a Lambertian of
/// albedo `a`, whose radiance inside is `le / (1 - a)` everywhere. Its
/// points sample the light they lie on.
pub fn integrating_sphere(a: f32, le: f32, emits: crate::light::Emits) -> Scene {
    let mut d = empty(inside_camera(8));
    let m = d.material("wall", Material::diffuse(a, a, a));
    // Off the origin, so that points on it round both ways.
    d.lights.push(unit_sphere_light(Vec3::new(0.3, -0.2, 0.1), le, emits));
    d.light_surfaces.push(Some(LightSurface {
        material: m,
        ..LightSurface::default()
    }));
    Scene::build(d).unwrap()
}

/// A floor of `material` (the plane z = 0, far wider than the view) under a
/// sky of constant radiance `sky`, seen by an orthographic camera along
/// `view` (every pixel sees the floor from that direction): the floor sees
/// only the sky, so its radiance is `sky` times its directional albedo.
pub fn floor_under_sky(material: Material, sky: f32, view: Vec3) -> SceneDesc {
    let camera = CameraDesc {
        position: -view.normalize() * 5.0,
        look_at: Vec3::ZERO,
        up: Vec3::Z,
        fov_y_deg: 40.0,
        width: 8,
        height: 8,
        window: None,
        lens: None,
        orthographic: Some(0.5),
        spherical: None,
        realistic: None,
    };
    let mut d = SceneDesc::empty("floor under sky", camera);
    let m = d.material("floor", material);
    d.triangles.push(TriangleDesc {
        vertices: [
            Vec3::new(-50.0, -50.0, 0.0),
            Vec3::new(50.0, -50.0, 0.0),
            Vec3::new(0.0, 50.0, 0.0),
        ],
        normals: None,
        uvs: None,
        material: m,
    });
    d.lights
        .push(Light::infinite(Vec3::splat(sky), None, glam::Mat3::IDENTITY));
    d
}

#[cfg(test)]
mod tests {
    use super::{ball_in_a_glowing_sphere, floor_under_sky, glowing_box, integrating_sphere};
    use crate::integrator::{render, IntegratorKind, LightSampling, RenderSettings};
    use crate::light::Emits;
    use crate::material::Material;

    /// Each integrator as the closed forms below render it: the path tracer
    /// with each light sampling, bdpt, the photon map with and without final
    /// gather, and SPPM. Photons go deep enough that truncating their paths
    /// costs < 1e-4 at albedo 1/2.
    fn every_integrator() -> Vec<(String, RenderSettings)> {
        let base = RenderSettings {
            spp: 64,
            ..RenderSettings::default()
        };
        let mut runs = vec![];
        for ls in [LightSampling::Mis, LightSampling::Bsdf, LightSampling::Light] {
            let s = RenderSettings {
                integrator: IntegratorKind::Path,
                light_sampling: ls,
                ..base.clone()
            };
            runs.push((format!("path ({ls:?})"), s));
        }
        let bdpt = RenderSettings {
            integrator: IntegratorKind::Bdpt,
            ..base.clone()
        };
        runs.push(("bdpt".into(), bdpt));
        for fg in [0, 16] {
            let mut s = RenderSettings {
                integrator: IntegratorKind::Photon,
                ssaa: 2,
                ..base.clone()
            };
            s.photon.photons = 100_000;
            s.photon.max_bounces = 16;
            s.photon.final_gather = fg;
            runs.push((format!("photon (final gather {fg})"), s));
        }
        let mut s = RenderSettings {
            integrator: IntegratorKind::Sppm,
            passes: 8,
            ..base
        };
        s.photon.photons = 20_000;
        s.photon.max_bounces = 16;
        runs.push(("sppm".into(), s));
        runs
    }

    /// Inside a sphere light that emits inwards (or both ways) every
    /// integrator sees the light's radiance on it and its reflection on a
    /// ball within: light samples drawn over the inside, BSDF hits on it
    /// weighed against them, bdpt's particles leaving it inwards. (Photons
    /// leaving it are checked against light samples in `light::tests`.)
    #[test]
    fn a_sphere_light_emitting_inwards_lights_what_it_holds() {
        let (a, le) = (0.5f32, 2.0);
        for emits in [Emits::Inwards, Emits::Both] {
            let scene = ball_in_a_glowing_sphere(a, le, emits);
            for (what, s) in every_integrator() {
                let film = render(&scene, &s, &|| {}).unwrap().film;
                let ball = film.mean(6, 6, 10, 10).x;
                let wall = film.get(0, 0).x;
                let want = a * le;
                assert!(
                    (ball - want).abs() / want < 0.02,
                    "{emits:?} {what}: ball {ball} vs {want}"
                );
                assert!((wall - le).abs() / le < 0.01, "{emits:?} {what}: wall {wall} vs {le}");
            }
        }
    }

    /// Inside a sphere light that emits inwards and reflects, each point
    /// of it samples the light it lies on, from inside (rounding puts such
    /// a point on either side of the surface): le / (1 - a) everywhere.
    #[test]
    fn an_integrating_sphere_glows_as_radiosity_says() {
        let (a, le) = (0.5f32, 1.0);
        let expected = le / (1.0 - a);
        for emits in [Emits::Inwards, Emits::Both] {
            let scene = integrating_sphere(a, le, emits);
            for (what, s) in every_integrator() {
                let mean = render(&scene, &s, &|| {}).unwrap().film.mean(0, 0, 8, 8).x;
                assert!(
                    (mean - expected).abs() / expected < 0.02,
                    "{emits:?} {what}: {mean} vs {expected}"
                );
            }
        }
    }

    /// A measured BRDF under a constant sky, in every integrator: the floor
    /// shows the sky times the BRDF's directional albedo, which quadrature
    /// over the BRDF itself gives.
    #[test]
    fn a_measured_brdf_under_a_sky_shows_its_albedo_in_every_integrator() {
        use crate::bsdf::{Bxdf, MeasuredBxdf, MeasuredData, TransportMode};
        use crate::math::Vec3;
        let file = crate::bsdf::measured_test_file();
        let grey = |l: &[f32]| vec![Vec3::splat(0.5); l.len()];
        let data: &'static MeasuredData = Box::leak(Box::new(MeasuredData::from_bytes(&file, "test", grey).unwrap()));
        let b = Bxdf::Measured(MeasuredBxdf::new(data));
        let sky = 2.0;
        let view = Vec3::new(0.0, 0.6, -0.8);
        let wo = -view;
        // The albedo towards wo, by quadrature in the local frame (normal +z).
        let (m, k) = (300, 300);
        let mut albedo = 0.0;
        for j in 0..m {
            let theta = (j as f32 + 0.5) / m as f32 * std::f32::consts::FRAC_PI_2;
            for i in 0..k {
                let phi = (i as f32 + 0.5) / k as f32 * std::f32::consts::TAU;
                let wi = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                albedo += b.f(wo, wi, TransportMode::Radiance).x * wi.z * theta.sin();
            }
        }
        albedo *= std::f32::consts::FRAC_PI_2 / m as f32 * std::f32::consts::TAU / k as f32;
        // Spectra 0.3 and 0.9, half each: 0.6 times the normals' albedo, under 1.
        assert!(albedo > 0.5 && albedo < 0.6, "{albedo}");
        let scene =
            crate::Scene::build(floor_under_sky(Material::Measured(MeasuredBxdf::new(data)), sky, view)).unwrap();
        let expected = sky * albedo;
        for (what, s) in every_integrator() {
            let mean = render(&scene, &s, &|| {}).unwrap().film.mean(0, 0, 8, 8);
            for c in mean.to_array() {
                assert!((c - expected).abs() / expected < 0.02, "{what}: {mean} vs {expected}");
            }
        }
    }

    /// Every integrator inside a box of lights that reflect: le / (1 - a),
    /// twice what the walls emit with a = 1/2. Emitters that reflect nothing
    /// would show only le.
    #[test]
    fn emitters_that_reflect_glow_as_radiosity_says_in_every_integrator() {
        let (a, le) = (0.5f32, 1.5);
        let expected = le / (1.0 - a);
        let scene = crate::Scene::build(glowing_box(Material::diffuse(a, a, a), le, 8)).unwrap();
        for (what, s) in every_integrator() {
            let mean = render(&scene, &s, &|| {}).unwrap().film.mean(0, 0, 8, 8);
            for c in mean.to_array() {
                assert!((c - expected).abs() / expected < 0.02, "{what}: {mean} vs {expected}");
            }
        }
    }
}
