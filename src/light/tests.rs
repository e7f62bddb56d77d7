//! Tests of every light: sampling against closed forms, densities, emitted power.

use super::*;
use crate::sampling::Rng;
use crate::sampling::{concentric_disk, uniform_sphere};

#[test]
fn sphere_light_radiance_matches_scene_definition() {
    let l = Light::Sphere {
        sphere: Sphere {
            centre: Vec3::ZERO,
            radius: 0.1,
        },
        power: Vec3::splat(14.0 * PI),
        image: None,
        emits: Default::default(),
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
        image: None,
        emits: Default::default(),
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
        image: None,
        emits: Default::default(),
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
        image: None,
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
        assert_eq!(
            l.le(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec2::ZERO),
            Vec3::splat(1.5)
        );
        assert_eq!(
            l.le(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), Vec2::ZERO).x,
            if two_sided { 1.5 } else { 0.0 }
        );
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
        image: None,
        emits: Default::default(),
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

// ---- Spot, distant and infinite lights ----

use crate::sampling::equal_area_square_to_sphere;

/// A lat-long or octahedral map with smooth variation and a bright patch,
/// dim towards the lat-long poles.
fn test_map(mapping: EnvMapping) -> Arc<EnvMap> {
    let (w, h) = match mapping {
        EnvMapping::LatLong => (48u32, 24u32),
        EnvMapping::Octahedral => (32, 32),
    };
    let mut texels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (u, v) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let base = 0.2 + 0.15 * (2.0 * PI * u).sin() * (PI * v).sin();
            let patch = (-((u - 0.3).powi(2) + (v - 0.4).powi(2)) / 0.01).exp() * 4.0;
            texels.push(Vec3::new(base + patch, base + 0.5 * patch, base * 0.8 + 0.1 * patch));
        }
    }
    Arc::new(EnvMap::new(w, h, texels, mapping, "test").unwrap())
}

/// A rotation that moves every axis, so that the frames cannot be confused.
fn tilted() -> Mat3 {
    Mat3::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 1.1)
}

/// Wilson-Hilferty: the chi-square statistic with `dof` degrees of freedom
/// as a standard normal deviate (large when the fit is bad).
fn chi_square_z(chi2: f64, dof: f64) -> f64 {
    let k = 2.0 / (9.0 * dof);
    ((chi2 / dof).powf(1.0 / 3.0) - (1.0 - k)) / k.sqrt()
}

/// Samples `sample_li` and compares the histogram of directions over bins
/// in (cos theta, phi) with the counts `pdf_li_escaped` predicts (integrated
/// over each bin on a fine grid); bins expecting fewer than 5 are pooled.
fn chi_square_of_sample_li(light: &Light, seed: u64) -> (f64, f64, f64) {
    let (nc, np, n) = (12usize, 24usize, 120_000usize);
    let bin = |w: Vec3| {
        let c = (((w.z + 1.0) * 0.5 * nc as f32) as usize).min(nc - 1);
        let mut phi = w.y.atan2(w.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        c * np + ((phi / (2.0 * PI) * np as f32) as usize).min(np - 1)
    };
    let mut observed = vec![0f64; nc * np];
    let mut rng = Rng::new(seed, 9);
    for _ in 0..n {
        let s = light.sample_li(Vec3::ZERO, rng.next_2d()).expect("a sample");
        assert!(s.dist.is_infinite() && (s.wi.length() - 1.0).abs() < 1e-4);
        // The weight is the radiance over the density.
        let pdf = light.pdf_li_escaped(Vec3::ZERO, s.wi);
        let le = light.le_escaped(Vec3::ZERO, s.wi);
        assert!(
            (s.weight * pdf - le).abs().max_element() <= 2e-3 * le.max_element(),
            "{s:?} {pdf} {le}"
        );
        observed[bin(s.wi)] += 1.0;
    }
    let sub = 40;
    let mut expected = vec![0f64; nc * np];
    let (dc, dp) = (2.0 / (nc * sub) as f64, 2.0 * std::f64::consts::PI / (np * sub) as f64);
    for i in 0..nc * sub {
        let c = -1.0 + (i as f64 + 0.5) * dc;
        let s = (1.0 - c * c).max(0.0).sqrt();
        for j in 0..np * sub {
            let phi = (j as f64 + 0.5) * dp;
            let w = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
            expected[(i / sub) * np + j / sub] += light.pdf_li_escaped(Vec3::ZERO, w) as f64 * dc * dp * n as f64;
        }
    }
    let total: f64 = expected.iter().sum::<f64>() / n as f64;
    let (mut chi2, mut bins, mut pooled_o, mut pooled_e) = (0.0, 0.0, 0.0, 0.0);
    for (o, e) in observed.iter().zip(&expected) {
        if *e < 5.0 {
            pooled_o += o;
            pooled_e += e;
        } else {
            chi2 += (o - e).powi(2) / e;
            bins += 1.0;
        }
    }
    if pooled_e >= 5.0 {
        chi2 += (pooled_o - pooled_e).powi(2) / pooled_e;
        bins += 1.0;
    }
    (chi2, bins - 1.0, total)
}

#[test]
fn environment_map_sampling_passes_a_chi_square_test_against_its_pdf() {
    for (k, mapping) in [EnvMapping::LatLong, EnvMapping::Octahedral].into_iter().enumerate() {
        for to_world in [Mat3::IDENTITY, tilted()] {
            let light = Light::infinite(Vec3::splat(1.5), Some(test_map(mapping)), to_world);
            let (chi2, dof, total) = chi_square_of_sample_li(&light, 11 + k as u64);
            assert!((total - 1.0).abs() < 2e-3, "{mapping:?}: the pdf integrates to {total}");
            let z = chi_square_z(chi2, dof);
            eprintln!("{mapping:?}: chi2 {chi2:.1}, {dof} dof, z {z:.2}");
            // z > 3.7 has a probability of 1e-4 under the null hypothesis.
            assert!(
                z < 3.7,
                "{mapping:?} {to_world}: chi2 {chi2:.1} with {dof} dof (z = {z:.2})"
            );
        }
    }
    // A uniform infinite light too.
    let (chi2, dof, total) = chi_square_of_sample_li(&Light::infinite(Vec3::ONE, None, Mat3::IDENTITY), 3);
    assert!(
        (total - 1.0).abs() < 1e-3 && chi_square_z(chi2, dof) < 3.7,
        "{chi2} {dof}"
    );
}

#[test]
fn a_wrong_pdf_fails_the_chi_square_test() {
    // The test has power: a map sampled by one image but evaluated by another fails.
    let a = Light::infinite(Vec3::ONE, Some(test_map(EnvMapping::LatLong)), Mat3::IDENTITY);
    let b = Light::infinite(Vec3::ONE, Some(test_map(EnvMapping::LatLong)), tilted());
    let (mut chi2, dof) = (0.0, 287.0);
    let mut rng = Rng::new(1, 1);
    // Directions sampled from `a`, binned against `b`'s density: count by hand.
    let n = 20_000;
    let (nc, np) = (12usize, 24usize);
    let mut observed = vec![0f64; nc * np];
    for _ in 0..n {
        let s = a.sample_li(Vec3::ZERO, rng.next_2d()).unwrap();
        let c = (((s.wi.z + 1.0) * 0.5 * nc as f32) as usize).min(nc - 1);
        let phi = s.wi.y.atan2(s.wi.x).rem_euclid(2.0 * PI);
        observed[c * np + ((phi / (2.0 * PI) * np as f32) as usize).min(np - 1)] += 1.0;
    }
    for (i, o) in observed.iter().enumerate() {
        let (c, p) = (i / np, i % np);
        let cz = -1.0 + (c as f32 + 0.5) * 2.0 / nc as f32;
        let phi = (p as f32 + 0.5) * 2.0 * PI / np as f32;
        let s = (1.0 - cz * cz).sqrt();
        let w = Vec3::new(s * phi.cos(), s * phi.sin(), cz);
        let e = b.pdf_li_escaped(Vec3::ZERO, w) as f64
            * (2.0 / nc as f64)
            * (2.0 * std::f64::consts::PI / np as f64)
            * n as f64;
        chi2 += (o - e).powi(2) / e.max(1.0);
    }
    assert!(chi_square_z(chi2, dof) > 10.0, "{chi2}");
}

#[test]
fn uniform_infinite_light_gives_pi_l_on_a_plane() {
    let light = Light::infinite(Vec3::new(0.5, 1.0, 2.0), None, Mat3::IDENTITY);
    assert!(light.is_infinite() && !light.is_delta());
    for n in [Vec3::Z, Vec3::new(1.0, -2.0, 0.5).normalize()] {
        let mut rng = Rng::new(4, 4);
        let count = 200_000;
        let mut e = Vec3::ZERO;
        for _ in 0..count {
            let s = light.sample_li(Vec3::new(3.0, -1.0, 2.0), rng.next_2d()).unwrap();
            e += s.weight * s.wi.dot(n).max(0.0);
        }
        let e = e / count as f32;
        let expected = Vec3::new(0.5, 1.0, 2.0) * PI;
        assert!(
            ((e - expected) / expected).abs().max_element() < 0.01,
            "{e} vs {expected}"
        );
    }
    assert_eq!(light.le_escaped(Vec3::ZERO, Vec3::X), Vec3::new(0.5, 1.0, 2.0));
    assert_eq!(light.pdf_li_escaped(Vec3::ZERO, Vec3::Y), 1.0 / (4.0 * PI));
}

#[test]
fn a_single_bright_texel_draws_the_samples() {
    for mapping in [EnvMapping::LatLong, EnvMapping::Octahedral] {
        let (w, h) = (16u32, 16u32);
        let (bx, by) = (11u32, 5u32);
        let mut texels = vec![Vec3::splat(1e-3); (w * h) as usize];
        texels[(by * w + bx) as usize] = Vec3::new(4000.0, 3000.0, 2000.0);
        let map = Arc::new(EnvMap::new(w, h, texels, mapping, "bright").unwrap());
        let centre_uv = Vec2::new((bx as f32 + 0.5) / w as f32, (by as f32 + 0.5) / h as f32);
        let local = match mapping {
            EnvMapping::Octahedral => equal_area_square_to_sphere(centre_uv),
            EnvMapping::LatLong => {
                let (t, p) = (PI * centre_uv.y, 2.0 * PI * centre_uv.x);
                Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
            }
        };
        let to_world = tilted();
        let towards = to_world * local;
        let light = Light::infinite(Vec3::ONE, Some(map), to_world);
        assert_eq!(light.le_escaped(Vec3::ZERO, towards), Vec3::new(4000.0, 3000.0, 2000.0));
        let mut rng = Rng::new(8, 1);
        let (mut near, n) = (0, 10_000);
        for _ in 0..n {
            let s = light.sample_li(Vec3::ZERO, rng.next_2d()).unwrap();
            // Within the texel: a fraction of a radian of its centre.
            if s.wi.dot(towards) > 0.9 && light.le_escaped(Vec3::ZERO, s.wi).x == 4000.0 {
                near += 1;
            }
        }
        assert!(near as f32 > 0.99 * n as f32, "{mapping:?}: {near} of {n}");
    }
}

/// The scene's bounding sphere handed to lights at infinity in the tests.
const WORLD: Sphere = Sphere {
    centre: Vec3::new(0.5, -0.2, 0.3),
    radius: 2.0,
};

/// Flux a light delivers onto the front face of a disk (centre, unit normal,
/// radius), two ways: photons (`sample_le_flux`) that cross the disk from
/// the front, and the integral over the disk of the irradiance `sample_li`
/// estimates.
fn flux_on_disk(light: &Light, centre: Vec3, normal: Vec3, radius: f32, n: usize, seed: u64) -> (Vec3, Vec3) {
    let mut rng = Rng::new(seed, 1);
    let mut photons = glam::DVec3::ZERO;
    for _ in 0..n {
        let s = light.sample_le_flux(rng.next_2d(), rng.next_2d());
        let denom = s.ray.d.dot(normal);
        if denom >= 0.0 {
            continue;
        }
        let t = (centre - s.ray.o).dot(normal) / denom;
        if t > 0.0 && (s.ray.at(t) - centre).length() < radius {
            photons += s.flux.as_dvec3();
        }
    }
    let mut shading = glam::DVec3::ZERO;
    for _ in 0..n {
        let d = concentric_disk(rng.next_2d()) * radius;
        let x = centre + to_world(Vec3::new(d.x, d.y, 0.0), normal);
        if let Some(s) = light.sample_li(x, rng.next_2d()) {
            shading += (s.weight * s.wi.dot(normal).max(0.0)).as_dvec3();
        }
    }
    let area = (PI * radius * radius) as f64;
    ((photons / n as f64).as_vec3(), (shading * area / n as f64).as_vec3())
}

/// Flux through a sphere around the light (its inside), from the
/// irradiance `sample_li` gives: an estimate of the light's power
/// independent of `power()` and `sample_le`.
fn flux_through_sphere(light: &Light, centre: Vec3, radius: f32, n: usize) -> Vec3 {
    let mut rng = Rng::new(17, 3);
    let mut sum = glam::DVec3::ZERO;
    for _ in 0..n {
        let out = uniform_sphere(rng.next_2d());
        if let Some(s) = light.sample_li(centre + out * radius, rng.next_2d()) {
            sum += (s.weight * s.wi.dot(-out).max(0.0)).as_dvec3();
        }
    }
    (sum * (4.0 * std::f64::consts::PI * (radius * radius) as f64) / n as f64).as_vec3()
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    ((a - b).abs() / b.abs().max(Vec3::splat(1e-6))).max_element() < tol
}

/// Every kind of light, with its scene bounds set.
fn every_light() -> Vec<(&'static str, Light)> {
    let mut lights = vec![
        (
            "sphere",
            Light::Sphere {
                sphere: Sphere {
                    centre: Vec3::new(0.2, 0.1, 0.0),
                    radius: 0.3,
                },
                power: Vec3::new(10.0, 8.0, 6.0),
                image: None,
                emits: Default::default(),
            },
        ),
        (
            "point",
            Light::Point {
                position: Vec3::new(0.1, 0.0, 0.2),
                power: Vec3::new(3.0, 2.0, 1.0),
            },
        ),
        ("triangle", quad(1.0, 0.6, 0.2, 2.0, false)[0].clone()),
        ("two-sided triangle", quad(0.8, 0.5, -0.1, 1.0, true)[1].clone()),
        (
            "annulus",
            Light::Disk {
                disk: crate::geometry::Disk::new(Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.3, -1.0, 0.2), 0.5, 0.2, None)
                    .unwrap(),
                radiance: Vec3::new(2.0, 1.5, 1.0),
                two_sided: false,
                image: None,
            },
        ),
        (
            "two-sided disk",
            Light::Disk {
                disk: crate::geometry::Disk::new(Vec3::new(-0.1, 0.0, 0.2), Vec3::Z, 0.4, 0.0, None).unwrap(),
                radiance: Vec3::new(1.0, 2.0, 3.0),
                two_sided: true,
                image: None,
            },
        ),
        (
            "spot",
            Light::spot(
                Vec3::new(0.1, 0.2, 0.0),
                Vec3::new(0.2, 0.1, 1.0),
                Vec3::new(5.0, 4.0, 3.0),
                40.0,
                15.0,
            ),
        ),
        (
            "distant",
            Light::distant(Vec3::new(0.3, -0.5, -1.0), Vec3::new(2.0, 1.0, 0.5)),
        ),
        (
            "uniform infinite",
            Light::infinite(Vec3::new(0.5, 1.0, 0.25), None, Mat3::IDENTITY),
        ),
        (
            "lat-long map",
            Light::infinite(Vec3::splat(2.0), Some(test_map(EnvMapping::LatLong)), tilted()),
        ),
        (
            "octahedral map",
            Light::infinite(Vec3::splat(0.5), Some(test_map(EnvMapping::Octahedral)), tilted()),
        ),
    ];
    lights.iter_mut().for_each(|(_, l)| l.set_scene_bounds(WORLD));
    lights
}

#[test]
fn photon_emission_of_every_light_carries_its_power() {
    for (name, light) in every_light() {
        let power = light.power();
        assert!(power.min_element() > 0.0, "{name}");
        if light.is_infinite() {
            // Photons from the disk: the flux onto a disk inside the scene,
            // against shadow rays, and the total against power().
            let (centre, normal) = (
                WORLD.centre + Vec3::new(0.3, 0.2, -0.4),
                Vec3::new(-0.3, 1.0, 0.6).normalize(),
            );
            let (photons, shading) = flux_on_disk(&light, centre, normal, 0.7, 400_000, 5);
            assert!(
                close(photons, shading, 0.02),
                "{name}: photons {photons} vs shadow rays {shading}"
            );
            let mut rng = Rng::new(6, 6);
            let n = 100_000;
            let mut total = Vec3::ZERO;
            for _ in 0..n {
                let s = light.sample_le_flux(rng.next_2d(), rng.next_2d());
                // Rays start outside the bounding sphere, aimed through it.
                let to_centre = WORLD.centre - s.ray.o;
                assert!(
                    to_centre.length() >= WORLD.radius * 0.999 && s.ray.d.dot(to_centre) > 0.0,
                    "{name}"
                );
                total += s.flux / n as f32;
            }
            assert!(close(total, power, 0.01), "{name}: {total} vs {power}");
        } else {
            // Everything the light emits crosses a sphere around it.
            let through = flux_through_sphere(&light, light.position(), 3.0, 400_000);
            assert!(close(through, power, 0.02), "{name}: {through} vs power() {power}");
            let mut rng = Rng::new(7, 7);
            let s = light.sample_le_flux(rng.next_2d(), rng.next_2d());
            assert_eq!(s.flux, power, "{name}");
        }
    }
}

#[test]
fn spot_light_photons_follow_its_falloff() {
    // A disk straddling the falloff ring: photons and shadow rays agree there
    // only if sample_le distributes directions as the smoothstep intensity.
    let light = Light::spot(Vec3::ZERO, Vec3::Z, Vec3::splat(2.0), 30.0, 12.0);
    for (centre, radius) in [(Vec3::new(0.42, 0.0, 1.0), 0.12), (Vec3::new(0.0, 0.1, 1.0), 0.2)] {
        let (photons, shading) = flux_on_disk(&light, centre, -Vec3::Z, radius, 400_000, 9);
        assert!(close(photons, shading, 0.02), "{photons} vs {shading}");
    }
    // Outside the cone nothing arrives; inside the falloff start, all of it.
    assert!(light.sample_li(Vec3::new(1.0, 0.0, 1.0), Vec2::ZERO).is_none());
    let full = light.sample_li(Vec3::new(0.0, 0.0, 2.0), Vec2::ZERO).unwrap();
    assert_eq!(full.weight, Vec3::splat(2.0 / 4.0));
    assert!(light.is_delta() && !light.is_infinite() && light.pdf_li(Vec3::new(0.0, 0.0, 2.0), -Vec3::Z) == 0.0);
}

#[test]
fn emission_densities_integrate_to_one() {
    // pdf_le's directional density over the sphere, for the lights whose
    // directions are not a delta, at a particle they emit.
    for (name, light) in every_light() {
        if matches!(light, Light::Distant { .. }) {
            continue;
        }
        let mut rng = Rng::new(2, 3);
        let (ray, n) = light.sample_le(rng.next_2d(), rng.next_2d());
        let (pos, _) = light.pdf_le(&ray, n);
        let count = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..count {
            let d = uniform_sphere(rng.next_2d());
            sum += light.pdf_le(&Ray::new(ray.o, d), n).1 as f64 * 4.0 * std::f64::consts::PI;
        }
        let sum = sum / count as f64;
        let expected = if matches!(
            light,
            Light::Triangle { two_sided: true, .. } | Light::Disk { two_sided: true, .. }
        ) {
            0.5
        } else {
            1.0
        };
        assert!((sum - expected).abs() < 0.02, "{name}: {sum}");
        assert_eq!(
            pos == 0.0,
            matches!(light, Light::Point { .. } | Light::Spot { .. }),
            "{name}"
        );
    }
}

#[test]
fn distant_light_is_parallel_and_at_infinity() {
    let mut light = Light::distant(Vec3::new(0.0, 0.0, -2.0), Vec3::splat(3.0));
    light.set_scene_bounds(WORLD);
    let s = light.sample_li(Vec3::new(5.0, 1.0, 0.0), Vec2::new(0.3, 0.8)).unwrap();
    assert_eq!((s.wi, s.dist, s.weight), (Vec3::Z, f32::INFINITY, Vec3::splat(3.0)));
    assert!(light.is_delta() && light.is_infinite());
    assert_eq!(light.le_escaped(Vec3::ZERO, Vec3::Z), Vec3::ZERO);
    assert_eq!(light.pdf_li_escaped(Vec3::ZERO, Vec3::Z), 0.0);
    assert!((light.power().x - 3.0 * PI * 4.0).abs() < 1e-4);
    // Other lights see nothing of an escaped ray.
    for (name, l) in every_light() {
        if !matches!(l, Light::Infinite { .. }) {
            assert_eq!(l.le_escaped(Vec3::ZERO, Vec3::Y), Vec3::ZERO, "{name}");
            assert_eq!(l.pdf_li_escaped(Vec3::ZERO, Vec3::Y), 0.0, "{name}");
        }
    }
}

#[test]
fn shadow_rays_reach_lights_at_infinity_unless_blocked() {
    use crate::integrator::direct::{direct_radiance, DiffuseVertex};
    use crate::integrator::RayStats;
    use crate::material::Material;
    use crate::scene::{CameraDesc, Scene, SceneDesc, TriangleDesc};
    let camera = CameraDesc {
        position: Vec3::new(0.0, -1.0, -3.0),
        look_at: Vec3::ZERO,
        up: Vec3::new(0.0, -1.0, 0.0),
        fov_y_deg: 40.0,
        width: 16,
        height: 16,
        window: None,
        lens: None,
        orthographic: None,
        spherical: None,
        realistic: None,
    };
    let quad = |desc: &mut SceneDesc, [a, b, c, d]: [Vec3; 4]| {
        for vertices in [[a, b, c], [a, c, d]] {
            desc.triangles.push(TriangleDesc {
                vertices,
                normals: None,
                uvs: None,
                material: 0,
            });
        }
    };
    // A floor at y = 0 (world y points down: the sky is at -y), lit by a
    // uniform sky and a distant light slanting down along +y.
    let d = Vec3::new(0.0, 1.0, 0.6).normalize();
    let scene_with = |blocker: bool| {
        let mut desc = SceneDesc::empty("sky", camera.clone());
        desc.material("grey", Material::diffuse(0.5, 0.5, 0.5));
        let floor = [(-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0)].map(|(x, z)| Vec3::new(x, 0.0, z));
        quad(&mut desc, floor);
        if blocker {
            // A small roof at height 0.5 over x in [0.5, 1.5]: in the distant light's way from
            // (1, 0, 0.3), tiny in the sky seen from (-1, 0, 0).
            let roof = [(0.5, -0.2), (1.5, -0.2), (1.5, 0.2), (0.5, 0.2)].map(|(x, z)| Vec3::new(x, -0.5, z));
            quad(&mut desc, roof);
        }
        desc.lights
            .push(Light::infinite(Vec3::splat(0.7), None, Mat3::IDENTITY));
        desc.lights.push(Light::distant(d, Vec3::splat(2.0)));
        Scene::build(desc).unwrap()
    };
    let e_at = |scene: &Scene, x: f32, z: f32| {
        let ray = Ray::new(Vec3::new(x, -1.0, z), Vec3::Y);
        let hit = scene.intersect(&ray, 0.0, f32::INFINITY).unwrap();
        assert!(hit.p.y.abs() < 1e-4, "{hit:?}");
        let mut sampler = crate::sampling::Sampler::independent(Rng::new(3, 1));
        let mut stats = RayStats::default();
        let n = 4000;
        let mut e = Vec3::ZERO;
        let wo = -ray.d;
        let bsdf = scene.material(hit.material).bsdf(&scene.surface(&hit), wo);
        let v = DiffuseVertex {
            hit,
            wo,
            bsdf,
            beta: Vec3::ONE,
        };
        for _ in 0..n {
            e += direct_radiance(scene, &v, 4, &mut sampler, &mut stats);
        }
        // Reflected by albedo 0.5: radiance = 0.5 / pi * irradiance.
        e.x / n as f32 * PI / 0.5
    };
    let sky = PI * 0.7;
    let sun = 2.0 * d.y;
    let open = scene_with(false);
    assert_eq!(open.infinite_lights(), &[0]);
    let e = e_at(&open, -1.0, 0.0);
    assert!((e - (sky + sun)).abs() < 0.01 * (sky + sun), "{e} vs {}", sky + sun);
    // Under the roof, the distant light is blocked; the sky nearly all there.
    let roofed = scene_with(true);
    let shade = Vec3::new(1.0, 0.0, 0.3);
    assert!(roofed.occluded(&Ray::new(shade, -d), 1e-3, f32::INFINITY));
    let e = e_at(&roofed, shade.x, shade.z);
    assert!(
        e < sky && e > 0.6 * sky,
        "{e}: the sun is blocked, most of the sky is not"
    );
    let e_far = e_at(&roofed, -1.0, 0.0);
    assert!((e_far - (sky + sun)).abs() < 0.02 * (sky + sun), "{e_far}");
}

#[test]
fn disk_light_irradiance_on_its_axis_is_the_closed_form() {
    // A one-sided disk of radius R and radiance L facing a point at distance
    // h on its axis: E = pi L R^2 / (R^2 + h^2); an annulus is the difference
    // of two disks. Shadow-ray estimates through sample_li, and pdf_li of
    // the sampled directions agrees with sample_li's weight.
    let (l, h) = (3.0f32, 0.8f32);
    let e = |r: f32| std::f32::consts::PI * l * r * r / (r * r + h * h);
    for (r, ri) in [(0.5f32, 0.0f32), (0.6, 0.25)] {
        let light = Light::Disk {
            disk: crate::geometry::Disk::new(Vec3::new(0.0, 0.0, h), -Vec3::Z, r, ri, None).unwrap(),
            radiance: Vec3::splat(l),
            two_sided: false,
            image: None,
        };
        let mut rng = Rng::new(11, 12);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let s = light.sample_li(Vec3::ZERO, rng.next_2d()).unwrap();
            sum += (s.weight.x * s.wi.z) as f64;
            let pdf = light.pdf_li(Vec3::ZERO, s.wi);
            assert!((pdf * s.weight.x / l - 1.0).abs() < 1e-2, "{pdf} {}", s.weight.x);
        }
        let expected = e(r) - e(ri);
        let got = (sum / n as f64) as f32;
        assert!(
            (got / expected - 1.0).abs() < 0.005,
            "R {r}, inner {ri}: {got} vs {expected}"
        );
        // From behind, a one-sided disk is dark.
        assert!(light.sample_li(Vec3::new(0.0, 0.0, 2.0), Vec2::new(0.3, 0.4)).is_none());
    }
}

#[test]
fn a_light_sample_carries_the_density_pdf_li_gives_its_direction() {
    let mut rng = Rng::new(17, 2);
    for (name, light) in every_light() {
        let mut checked = 0;
        // One-sided lights face one of the two points.
        for k in 0..400 {
            let p = Vec3::new(0.05, -0.4, if k % 2 == 0 { 0.3 } else { -0.3 });
            let Some(s) = light.sample_li(p, rng.next_2d()) else {
                continue;
            };
            let expected = if light.is_delta() {
                0.0
            } else if s.dist.is_finite() {
                light.pdf_li_hit(p, s.wi, p + s.wi * s.dist)
            } else {
                light.pdf_li_escaped(p, s.wi)
            };
            assert!(
                (s.pdf - expected).abs() <= 1e-3 * expected.max(1e-6),
                "{name}: sampled pdf {} where pdf_li says {expected}",
                s.pdf
            );
            checked += 1;
        }
        assert!(light.is_delta() || checked > 50, "{name}: only {checked} samples");
    }
}

#[test]
fn the_shared_normal_and_area_are_those_computed_apart() {
    use crate::light::{triangle_area, triangle_normal};
    let mut rng = Rng::new(5, 1);
    let mut p = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
    let (a, b) = (p(), p());
    let mut tris: Vec<[Vec3; 3]> = (0..500).map(|_| [p(), p(), p()]).collect();
    // Degenerate ones: a point, a segment.
    tris.push([a, a, a]);
    tris.push([a, b, a * 2.0 - b]);
    for v in &tris {
        let (n, area) = super::triangle_normal_area(v);
        assert_eq!(
            n.to_array().map(f32::to_bits),
            triangle_normal(v).to_array().map(f32::to_bits)
        );
        assert_eq!(area.to_bits(), triangle_area(v).to_bits());
    }
}

#[test]
fn a_maps_upper_illuminance_is_pi_for_unit_radiance_whatever_the_mapping() {
    for (mapping, w, h) in [(EnvMapping::Octahedral, 32, 32), (EnvMapping::LatLong, 64, 32)] {
        let map = EnvMap::new(w, h, vec![Vec3::ONE; (w * h) as usize], mapping, "unit").unwrap();
        let e = map.upper_illuminance();
        assert!((e - PI).abs() < 0.01 * PI, "{mapping:?}: {e}");
        // Light from below the horizon adds nothing.
        let texels = (0..w * h)
            .map(|i| {
                let uv = Vec2::new(((i % w) as f32 + 0.5) / w as f32, ((i / w) as f32 + 0.5) / h as f32);
                let below = match mapping {
                    EnvMapping::Octahedral => crate::sampling::equal_area_square_to_sphere(uv).z < 0.0,
                    EnvMapping::LatLong => uv.y > 0.5,
                };
                if below {
                    Vec3::splat(50.0)
                } else {
                    Vec3::ONE
                }
            })
            .collect();
        let lit_below = EnvMap::new(w, h, texels, mapping, "below").unwrap();
        assert!((lit_below.upper_illuminance() - e).abs() < 1e-3 * e, "{mapping:?}");
    }
}

#[test]
fn a_goniometric_light_shines_by_its_image_and_emits_its_power() {
    // Light from the map's upper half only, turned by `tilted`.
    let map = test_map(EnvMapping::Octahedral);
    let to_light = tilted();
    let light = Light::Goniometric {
        position: Vec3::new(1.0, 2.0, 3.0),
        intensity: Vec3::new(2.0, 1.0, 0.5),
        to_light,
        map: map.clone(),
    };
    assert!(light.is_delta());
    let mut rng = Rng::new(21, 22);
    // Shadow samples: the image's intensity over the squared distance.
    for _ in 0..50 {
        let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
        let s = light.sample_li(p, rng.next_2d()).unwrap();
        let d = Vec3::new(1.0, 2.0, 3.0) - p;
        let expected = Vec3::new(2.0, 1.0, 0.5) * map.le((to_light * -s.wi).normalize()) / d.length_squared();
        assert!((s.wi - d.normalize()).length() < 1e-5);
        assert!((s.weight - expected).abs().max_element() <= 1e-5 * expected.max_element());
    }
    // Particles: each carries the power, and their directions follow the
    // intensity (so the mean of I / pdf over them is the power too).
    let power = light.power();
    assert!((power - Vec3::new(2.0, 1.0, 0.5) * map.integral()).abs().max_element() < 1e-4);
    let n = 20_000;
    let mut mean = Vec3::ZERO;
    for _ in 0..n {
        let le = light.sample_le_flux(rng.next_2d(), rng.next_2d());
        assert_eq!(le.flux, power);
        assert_eq!(le.ray.o, Vec3::new(1.0, 2.0, 3.0));
        let (pos, dir) = light.pdf_le(&le.ray, le.n);
        assert_eq!(pos, 0.0);
        mean += light.intensity(le.ray.d) / dir / n as f32;
    }
    // Not exactly: a sampled direction near a texel edge may read the
    // neighbouring texel back.
    assert!(
        (mean - power).abs().max_element() < 0.01 * power.max_element(),
        "{mean} vs {power}"
    );
}

#[test]
fn a_projection_light_casts_its_image_in_its_frustum_and_emits_its_power() {
    // A 4 x 2 slide, each texel its own colour, over 60 degrees.
    let texels: Vec<Vec3> = (0..8).map(|i| Vec3::new(1.0 + i as f32, 0.5, 8.0 - i as f32)).collect();
    let projector = Arc::new(Projector::new(4, 2, texels.clone(), 60.0).unwrap());
    let to_light = tilted();
    let light = Light::Projection {
        position: Vec3::ZERO,
        intensity: Vec3::splat(2.0),
        to_light,
        projector,
    };
    assert!(light.is_delta());
    let world = |l: Vec3| (to_light.transpose() * l).normalize();
    // The frustum's axis shows the middle of the slide: texel (2, 1) is just
    // right of and below the centre, (1, 0) just left of and above it.
    let t = (30f32).to_radians().tan();
    assert_eq!(
        light.intensity(world(Vec3::new(0.1 * t, 0.1 * t, 1.0))),
        texels[6] * 2.0
    );
    assert_eq!(
        light.intensity(world(Vec3::new(-0.1 * t, -0.1 * t, 1.0))),
        texels[1] * 2.0
    );
    // The longer side spans twice the shorter: 2 tan(30) across x.
    assert_eq!(
        light.intensity(world(Vec3::new(1.9 * t, 0.1 * t, 1.0))),
        texels[7] * 2.0
    );
    assert_eq!(light.intensity(world(Vec3::new(2.1 * t, 0.1 * t, 1.0))), Vec3::ZERO);
    assert_eq!(light.intensity(world(Vec3::new(0.0, 0.0, -1.0))), Vec3::ZERO);
    // Power: the intensity integrated over the sphere, and what particles carry.
    let mut rng = Rng::new(31, 32);
    let n = 400_000;
    let mc: Vec3 = (0..n)
        .map(|_| light.intensity(uniform_sphere(rng.next_2d())))
        .sum::<Vec3>()
        * (4.0 * PI / n as f32);
    // `power` takes each texel's solid angle at its centre, as pbrt-v4's
    // `Phi` does: coarse on a slide of 8 texels over a wide frustum.
    let power = light.power();
    assert!(
        (mc - power).abs().max_element() < 0.05 * power.max_element(),
        "{mc} vs {power}"
    );
    let m = 20_000;
    let mut carried = Vec3::ZERO;
    for _ in 0..m {
        let le = light.sample_le_flux(rng.next_2d(), rng.next_2d());
        let (_, pdf) = light.pdf_le(&le.ray, le.n);
        assert!(pdf > 0.0);
        assert!((le.flux - light.intensity(le.ray.d) / pdf).abs().max_element() <= 1e-3 * le.flux.max_element());
        carried += le.flux / m as f32;
    }
    // Particles carry the intensity over their density: exactly the integral.
    assert!(
        (carried - mc).abs().max_element() < 0.02 * mc.max_element(),
        "{carried} vs {mc}"
    );
}

#[test]
fn sphere_lights_emitting_inwards_or_both_ways_agree_with_their_light_samples() {
    // pbrt-v4's sphere under ReverseOrientation emits inwards, a two-sided
    // one both ways. Inside, photons onto a disk bring what shadow rays
    // (points uniform over the inside) find; outside, only a two-sided one
    // sends anything; particles start on the sphere on their side.
    let sphere = Sphere {
        centre: Vec3::new(0.1, -0.2, 0.3),
        radius: 1.5,
    };
    for emits in [Emits::Inwards, Emits::Both] {
        let light = Light::Sphere {
            sphere,
            power: Vec3::new(6.0, 4.0, 2.0),
            image: None,
            emits,
        };
        let (centre, normal) = (
            sphere.centre + Vec3::new(0.4, 0.3, -0.5),
            Vec3::new(0.3, 1.0, -0.2).normalize(),
        );
        let (photons, shading) = flux_on_disk(&light, centre, normal, 0.3, 400_000, 11);
        assert!(
            close(photons, shading, 0.02),
            "{emits:?}: photons {photons} vs shadow rays {shading}"
        );
        let outside = sphere.centre + Vec3::new(0.0, 3.0, 0.0);
        let lit_outside = light.sample_li(outside, Vec2::new(0.3, 0.6)).is_some();
        assert_eq!(lit_outside, emits == Emits::Both, "{emits:?}");
        let mut rng = Rng::new(5, 5);
        let mut inwards = 0;
        for _ in 0..1000 {
            let (ray, n) = light.sample_le(rng.next_2d(), rng.next_2d());
            let out = (ray.o - sphere.centre) / sphere.radius;
            assert!((out.length() - 1.0).abs() < 1e-3 && ray.d.dot(n) >= 0.0);
            if n.dot(out) < 0.0 {
                inwards += 1;
                assert!(out.length() < 1.0, "a particle leaving inwards starts inside");
            }
        }
        let want = if emits == Emits::Both { 400..600 } else { 1000..1001 };
        assert!(want.contains(&inwards), "{emits:?}: {inwards} of 1000 inwards");
        // Radiance leaves the inside, and the outside only when two-sided.
        let p = sphere.centre + Vec3::Z * sphere.radius;
        assert!(light.le(p, -Vec3::Z, Vec2::ZERO).x > 0.0);
        assert_eq!(light.le(p, Vec3::Z, Vec2::ZERO).x > 0.0, emits == Emits::Both);
    }
}
