//! Every integrator against the path tracer on surfaces other than
//! Lambertian: the cornell room lit by a quad area light, a disk light and a
//! sky through its open front, with a rough copper ball and a rough
//! coated-diffuse ball. Photon mapping and SPPM must agree
//! with the path tracer in the mean (within 2%): a photon scattered wrongly
//! by a glossy surface, or a density estimate that ignores the BSDF, moves it.

use raytracer::integrator::{render, IntegratorKind, RenderSettings};
use raytracer::light::Light;
use raytracer::material::{ConductorFresnel, Material, Roughness};
use raytracer::math::{luminance, Vec2, Vec3};
use raytracer::photon::PhotonSettings;
use raytracer::scene::{Scene, SphereDesc};

fn glossy_room(size: u32) -> Scene {
    let mut d = raytracer::scene::builtin::cornell();
    d.camera.width = size;
    d.camera.height = size;
    // A 0.5 x 0.5 quad just under the ceiling (y = -1), emitting downwards (+y).
    let (y, h) = (-0.98, 0.25);
    let (a, b, c, e) = (
        Vec3::new(-h, y, -h - 0.3),
        Vec3::new(h, y, -h - 0.3),
        Vec3::new(h, y, h - 0.3),
        Vec3::new(-h, y, h - 0.3),
    );
    d.lights = [[a, c, b], [a, e, c]]
        .into_iter()
        .map(|vertices| Light::Triangle {
            vertices,
            radiance: Vec3::splat(12.0),
            two_sided: false,
            image: None,
        })
        .collect();
    assert!(
        d.lights.iter().all(|l| l.le(Vec3::ZERO, Vec3::Y, Vec2::ZERO).x > 0.0),
        "the quad must face the floor"
    );
    // A round lamp on the ceiling (away from the walls: photon density
    // estimates darken the corners near a light, a bias of their own, 5% in
    // the mean with this lamp in a corner), and a sky seen through the
    // room's open front.
    d.lights.push(Light::Disk {
        disk: raytracer::geometry::Disk::new(Vec3::new(0.0, -0.98, 0.4), Vec3::Y, 0.12, 0.0, None).unwrap(),
        radiance: Vec3::new(20.0, 16.0, 10.0),
        two_sided: false,
        image: None,
    });
    d.lights
        .push(Light::infinite(Vec3::new(0.3, 0.4, 0.6), None, glam::Mat3::IDENTITY));
    let (eta, k) = raytracer::bsdf::named_metal("Cu").unwrap();
    let copper = d.material(
        "copper",
        Material::Conductor {
            fresnel: ConductorFresnel::Ior { eta, k },
            roughness: Roughness::isotropic(0.1, true).into(),
        },
    );
    let coated = d.material(
        "coated",
        Material::CoatedDiffuse {
            reflectance: Vec3::new(0.2, 0.4, 0.7).into(),
            roughness: Roughness::isotropic(0.05, true).into(),
            eta: 1.5,
            thickness: 0.01,
            medium: None,
        },
    );
    for (x, r, m) in [(-0.45, 0.3, copper), (0.45, 0.3, coated)] {
        d.spheres.push(SphereDesc {
            axes: None,
            sphere: raytracer::geometry::Sphere {
                centre: Vec3::new(x, 1.0 - r, -0.2),
                radius: r,
            },
            material: m,
        });
    }
    Scene::build(d).unwrap()
}

fn mean_luminance(scene: &Scene, settings: &RenderSettings) -> f64 {
    let film = render(scene, settings, &|| {}).unwrap().film;
    film.pixels.iter().map(|p| luminance(*p) as f64).sum::<f64>() / film.pixels.len() as f64
}

#[test]
fn photon_mapping_and_sppm_agree_with_the_path_tracer_on_glossy_surfaces() {
    let scene = glossy_room(32);
    let path = RenderSettings {
        integrator: IntegratorKind::Path,
        spp: 2048,
        ..RenderSettings::default()
    };
    let reference = mean_luminance(&scene, &path);
    let mut photon = RenderSettings {
        integrator: IntegratorKind::Photon,
        ssaa: 4,
        ..RenderSettings::default()
    };
    photon.photon = PhotonSettings {
        photons: 400_000,
        caustic_photons: 200_000,
        ..PhotonSettings::default()
    };
    let mut sppm = RenderSettings {
        integrator: IntegratorKind::Sppm,
        passes: 64,
        ..RenderSettings::default()
    };
    sppm.photon = PhotonSettings {
        photons: 50_000,
        max_bounces: 100,
        ..PhotonSettings::default()
    };
    for (name, s) in [("photon", photon), ("sppm", sppm)] {
        let mean = mean_luminance(&scene, &s);
        let ratio = mean / reference;
        eprintln!("{name}: mean luminance {mean:.5} against the path tracer's {reference:.5} (ratio {ratio:.4})");
        assert!((ratio - 1.0).abs() < 0.02, "{name}: ratio {ratio}");
    }
}
