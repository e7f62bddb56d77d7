//! Spheres and disks in the scene's BVH: closest hits, occlusion and hit
//! records against a loop over every primitive, and disks in scene files.

use raytracer::geometry::{Disk, Sphere, Triangle};
use raytracer::light::Light;
use raytracer::material::Material;
use raytracer::math::{Ray, Vec2, Vec3};
use raytracer::sampling::{uniform_sphere, Rng};
use raytracer::scene::{file, CameraDesc, DiskDesc, LoadOptions, PrimKind, SceneDesc, SphereDesc, TriangleDesc};
use raytracer::Scene;
use std::path::Path;

fn camera() -> CameraDesc {
    CameraDesc {
        position: Vec3::new(0.0, 0.0, -5.0),
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
    }
}

fn point(r: &mut Rng, half: f32) -> Vec3 {
    Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * (2.0 * half) - Vec3::splat(half)
}

/// `spheres` random spheres and `disks` random disks and annuli in
/// [-2, 2]^3, two big triangles through the middle, and `lights` sphere
/// lights among them.
fn random_scene(spheres: usize, disks: usize, lights: usize, seed: u64) -> SceneDesc {
    let mut r = Rng::new(seed, 1);
    let mut d = SceneDesc::empty("shapes", camera());
    let grey = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
    let white = d.material("white", Material::diffuse(0.8, 0.8, 0.8));
    for (a, b, c) in [
        (
            Vec3::new(-3.0, 0.3, -3.0),
            Vec3::new(3.0, 0.3, -3.0),
            Vec3::new(3.0, 0.3, 3.0),
        ),
        (
            Vec3::new(-3.0, -3.0, 0.7),
            Vec3::new(3.0, -3.0, 0.7),
            Vec3::new(0.0, 3.0, 0.7),
        ),
    ] {
        d.triangles.push(TriangleDesc {
            vertices: [a, b, c],
            normals: None,
            uvs: None,
            material: grey,
        });
    }
    for i in 0..spheres {
        d.spheres.push(SphereDesc {
            axes: None,
            sphere: Sphere {
                centre: point(&mut r, 2.0),
                radius: 0.01 + 0.07 * r.next_f32(),
            },
            material: if i % 2 == 0 { grey } else { white },
        });
    }
    for i in 0..disks {
        let radius = 0.02 + 0.1 * r.next_f32();
        let inner_radius = if i % 2 == 0 { 0.0 } else { radius * 0.8 * r.next_f32() };
        let mut disk = DiskDesc::new(
            point(&mut r, 2.0),
            uniform_sphere(r.next_2d()),
            radius,
            inner_radius,
            grey,
        );
        if i % 3 == 0 {
            disk.axes = Some([uniform_sphere(r.next_2d()), uniform_sphere(r.next_2d())]);
        }
        d.disks.push(disk);
    }
    for _ in 0..lights {
        d.lights.push(Light::Sphere {
            sphere: Sphere {
                centre: point(&mut r, 2.0),
                radius: 0.05 + 0.1 * r.next_f32(),
            },
            power: Vec3::splat(10.0),
            image: None,
            emits: Default::default(),
        });
    }
    d
}

/// The closest hit by a loop over every primitive, in the scene's object
/// numbering: (t, object id). `skip_light` leaves out that light's sphere.
fn brute(d: &SceneDesc, ray: &Ray, t_min: f32, t_max: f32, skip_light: Option<usize>) -> Option<(f32, u32)> {
    let mut best: Option<(f32, u32)> = None;
    let mut t_best = t_max;
    let mut id = 0u32;
    let mut take = |t: Option<f32>, id: u32, t_best: &mut f32| {
        if let Some(t) = t {
            *t_best = t;
            best = Some((t, id));
        }
    };
    for tri in d.triangles.iter() {
        let [a, b, c] = tri.vertices;
        take(
            Triangle::new(a, b, c).intersect_mt(ray, t_min, t_best).map(|h| h.t),
            id,
            &mut t_best,
        );
        id += 1;
    }
    for s in &d.spheres {
        take(s.sphere.intersect(ray, t_min, t_best), id, &mut t_best);
        id += 1;
    }
    for disk in &d.disks {
        take(disk.disk().unwrap().intersect(ray, t_min, t_best), id, &mut t_best);
        id += 1;
    }
    for (i, l) in d.lights.iter().enumerate() {
        if let (Light::Sphere { sphere, .. }, false) = (l, skip_light == Some(i)) {
            take(sphere.intersect(ray, t_min, t_best), id, &mut t_best);
        }
        id += 1;
    }
    best
}

/// Random rays: half from anywhere in [-3, 3]^3 in any direction, half aimed
/// at a random point near a random sphere or disk, so that many hit.
fn rays(d: &SceneDesc, n: usize, seed: u64) -> Vec<Ray> {
    let mut r = Rng::new(seed, 2);
    (0..n)
        .map(|i| {
            let o = point(&mut r, 3.0);
            if i % 2 == 0 {
                return Ray::new(o, uniform_sphere(r.next_2d()));
            }
            let k = (r.next_f32() * (d.spheres.len() + d.disks.len()) as f32) as usize;
            let target = match d.spheres.get(k) {
                Some(s) => s.sphere.centre + uniform_sphere(r.next_2d()) * s.sphere.radius,
                None => {
                    let disk = d.disks[k - d.spheres.len()].disk().unwrap();
                    disk.point_at(Vec2::new(r.next_f32(), r.next_f32() * 1.3 - 0.15))
                }
            };
            Ray::new(o, (target - o).normalize())
        })
        .collect()
}

#[test]
fn thousands_of_spheres_and_disks_hit_as_a_loop_over_all_of_them() {
    let d = random_scene(2000, 600, 3, 7);
    let scene = Scene::build(d.clone()).unwrap();
    let (mut hits, mut sphere_hits, mut disk_hits, mut light_hits) = (0, 0, 0, 0);
    let n_tri = d.triangles.len() as u32;
    let n_sph = d.spheres.len() as u32;
    let n_disk = d.disks.len() as u32;
    let mut r = Rng::new(3, 3);
    for ray in rays(&d, 20_000, 11) {
        let want = brute(&d, &ray, 0.0, f32::INFINITY, None);
        let got = scene.intersect(&ray, 0.0, f32::INFINITY);
        assert_eq!(got.map(|h| (h.t, h.object)), want, "{ray:?}");
        if let Some(h) = got {
            hits += 1;
            match h.object {
                o if o < n_tri => assert_eq!(h.kind, PrimKind::Triangle),
                o if o < n_tri + n_sph => {
                    assert_eq!(h.kind, PrimKind::Sphere);
                    sphere_hits += 1;
                }
                o if o < n_tri + n_sph + n_disk => {
                    assert_eq!(h.kind, PrimKind::Disk);
                    disk_hits += 1;
                    let disk = d.disks[(o - n_tri - n_sph) as usize].disk().unwrap();
                    assert_eq!(h.ng, disk.normal);
                    assert_eq!(h.ns, disk.normal);
                    assert_eq!((h.uv, h.dpdu), disk.uv_dpdu(h.p));
                    // On the disk's plane, where the ray meets it.
                    assert!((h.p - ray.at(h.t)).length() <= 1e-5 * (1.0 + h.p.abs().max_element()));
                    assert!((h.p - disk.centre).dot(disk.normal).abs() <= 1e-6 * (1.0 + h.p.abs().max_element()));
                }
                o => {
                    assert_eq!(h.kind, PrimKind::Light);
                    assert_eq!(h.light, Some(o - n_tri - n_sph - n_disk));
                    light_hits += 1;
                }
            }
        }
        // Occlusion over a random part of the ray agrees with the closest hit.
        let t_max = match want {
            Some((t, _)) => t * 2.0 * r.next_f32(),
            None => 10.0 * r.next_f32(),
        };
        let t_min = 0.01 * r.next_f32();
        assert_eq!(
            scene.occluded(&ray, t_min, t_max),
            scene.intersect(&ray, t_min, t_max).is_some(),
            "{ray:?} in ({t_min}, {t_max})"
        );
        assert_eq!(
            scene.occluded(&ray, t_min, t_max),
            brute(&d, &ray, t_min, t_max, None).is_some()
        );
    }
    assert!(
        sphere_hits > 3000 && disk_hits > 1500 && light_hits > 0 && hits > 8000,
        "hits {hits}, spheres {sphere_hits}, disks {disk_hits}, lights {light_hits}"
    );
}

#[test]
fn shadow_rays_leave_out_only_their_lights_own_sphere() {
    let d = random_scene(1500, 300, 4, 8);
    let scene = Scene::build(d.clone()).unwrap();
    let mut r = Rng::new(4, 4);
    let (mut blocked, mut free) = (0, 0);
    for i in 0..20_000 {
        let light = i % d.lights.len();
        let Light::Sphere { sphere, .. } = d.lights[light] else {
            unreachable!()
        };
        let o = point(&mut r, 2.5);
        let target = sphere.centre + uniform_sphere(r.next_2d()) * sphere.radius;
        let dist = (target - o).length();
        let ray = Ray::new(o, (target - o) / dist);
        let t_max = dist * (1.0 - 1e-4);
        let want = brute(&d, &ray, 1e-4, t_max, Some(light)).is_some();
        assert_eq!(scene.occluded_before_light(&ray, 1e-4, t_max, light as u32), want);
        // Without leaving it out, the light's own sphere can block too.
        assert_eq!(
            scene.occluded(&ray, 1e-4, t_max),
            brute(&d, &ray, 1e-4, t_max, None).is_some()
        );
        if want {
            blocked += 1;
        } else {
            free += 1;
        }
    }
    assert!(blocked > 1000 && free > 1000, "blocked {blocked}, free {free}");
}

#[test]
fn a_few_shapes_are_tested_in_order_without_a_tree() {
    // Two coincident spheres: the first in the description wins, as a loop's.
    let mut d = random_scene(0, 0, 0, 1);
    d.triangles.clear();
    for m in 0..2 {
        d.spheres.push(SphereDesc {
            axes: None,
            sphere: Sphere {
                centre: Vec3::ZERO,
                radius: 1.0,
            },
            material: m,
        });
    }
    let scene = Scene::build(d).unwrap();
    let h = scene
        .intersect(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z), 0.0, f32::INFINITY)
        .unwrap();
    assert_eq!((h.t, h.object, h.material), (4.0, 0, 0));
}

#[test]
fn disks_hit_inside_the_annulus_and_miss_the_hole_and_outside() {
    let mut d = SceneDesc::empty("disk", camera());
    let m = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
    let n = Vec3::new(1.0, -2.0, 0.5).normalize();
    let disk = DiskDesc::new(Vec3::new(0.2, 0.1, 1.0), n, 1.0, 0.4, m);
    let geo = disk.disk().unwrap();
    d.disks.push(disk);
    // Enough other disks far away that the scene has a tree.
    for i in 0..20 {
        d.disks.push(DiskDesc::new(
            Vec3::new(10.0 + i as f32, 0.0, 0.0),
            Vec3::Y,
            0.3,
            0.0,
            m,
        ));
    }
    let scene = Scene::build(d).unwrap();
    let o = Vec3::new(0.2, 0.1, 1.0) + n * 3.0 + Vec3::new(0.01, 0.02, 0.0);
    let mut r = Rng::new(9, 9);
    let (mut inside, mut hole, mut outside) = (0, 0, 0);
    for _ in 0..5000 {
        // A point on the plane up to 1.3 radii out, and rays at it from both sides.
        let (rr, phi) = (1.3 * r.next_f32(), std::f32::consts::TAU * r.next_f32());
        let p = geo.centre + (geo.axes[0] * phi.cos() + geo.axes[1] * phi.sin()) * rr;
        let dist = (p - geo.centre).length();
        for origin in [o, 2.0 * geo.centre - o] {
            let ray = Ray::new(origin, (p - origin).normalize());
            let hit = scene.intersect(&ray, 0.0, f32::INFINITY);
            if dist < 0.999 && dist > 0.401 {
                let h = hit.expect("inside the annulus");
                assert_eq!(h.object, 0);
                assert!((h.p - p).length() < 1e-4);
                assert_eq!(h.kind, PrimKind::Disk);
                inside += 1;
            } else if dist < 0.399 {
                assert!(hit.is_none(), "the hole at {dist}");
                hole += 1;
            } else if dist > 1.001 {
                assert!(hit.is_none(), "outside at {dist}");
                outside += 1;
            }
        }
    }
    assert!(
        inside > 1000 && hole > 500 && outside > 200,
        "{inside} {hole} {outside}"
    );
}

#[test]
fn disk_uv_and_dpdu_are_pbrts_in_a_scene() {
    // pbrt-v4: Translate 0 0 1, Shape "disk" "float radius" 2 "float innerradius" 0.5,
    // seen from above (object and world axes agree).
    let mut d = SceneDesc::empty("disk", camera());
    let m = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
    d.disks
        .push(DiskDesc::new(Vec3::new(0.0, 0.0, 1.0), Vec3::Z, 2.0, 0.5, m));
    let scene = Scene::build(d).unwrap();
    let tau = std::f32::consts::TAU;
    for (x, y) in [(1.0f32, 0.0f32), (0.0, 1.5), (-0.7, -0.9), (1.2, -1.1), (-1.0, 0.01)] {
        let ray = Ray::new(Vec3::new(x, y, 4.0), -Vec3::Z);
        let h = scene.intersect(&ray, 0.0, f32::INFINITY).unwrap();
        assert_eq!(h.t, 3.0);
        // pbrt-v4's Disk::InteractionFromIntersection, phi_max = 2 pi.
        let phi = y.atan2(x).rem_euclid(tau);
        let r_hit = (x * x + y * y).sqrt();
        let uv = Vec2::new(phi / tau, (2.0 - r_hit) / (2.0 - 0.5));
        let dpdu = Vec3::new(-tau * y, tau * x, 0.0);
        assert!((h.uv - uv).abs().max_element() < 1e-6, "{x} {y}: {} vs {uv}", h.uv);
        assert!(
            (h.dpdu - dpdu).abs().max_element() < 1e-5,
            "{x} {y}: {} vs {dpdu}",
            h.dpdu
        );
        assert_eq!(h.ng, Vec3::Z);
    }
    // Along the normal and through the hole: nothing.
    assert!(scene
        .intersect(&Ray::new(Vec3::new(0.2, 0.2, 4.0), -Vec3::Z), 0.0, f32::INFINITY)
        .is_none());
}

#[test]
fn moving_a_sphere_light_moves_it_in_the_tree() {
    let d = random_scene(200, 50, 2, 5);
    let mut scene = Scene::build(d).unwrap();
    let far = Vec3::new(20.0, 0.0, 0.0);
    scene.move_light(1, far);
    let h = scene
        .intersect(&Ray::new(Vec3::new(20.0, 0.0, -5.0), Vec3::Z), 0.0, f32::INFINITY)
        .unwrap();
    assert_eq!(h.light, Some(1));
    assert!(scene.occluded(&Ray::new(Vec3::new(20.0, 0.0, -5.0), Vec3::Z), 0.0, 10.0));
}

const HEAD: &str = "[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nfov_y = 40\n\n[materials.grey]\nalbedo = [0.5, 0.5, 0.5]\n\n";

fn parse(text: &str) -> raytracer::Result<raytracer::scene::LoadedScene> {
    file::parse(Path::new("disk.toml"), text, &LoadOptions::default())
}

#[test]
fn scene_files_read_disks() {
    let text = format!(
        "{HEAD}[[shapes]]\ntype = \"disk\"\nmaterial = \"grey\"\ncentre = [0, 1, 0]\nnormal = [0, -2, 0]\nradius = 0.4\n\n\
         [[shapes]]\ntype = \"disk\"\nmaterial = \"grey\"\ncentre = [1, 2, 3]\nnormal = [0, 0, 1]\nradius = 2\ninner_radius = 0.5\n"
    );
    let d = parse(&text).unwrap().desc;
    assert_eq!(
        d.disks,
        vec![
            DiskDesc::new(Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, -2.0, 0.0), 0.4, 0.0, 0),
            DiskDesc::new(Vec3::new(1.0, 2.0, 3.0), Vec3::Z, 2.0, 0.5, 0),
        ]
    );
    let scene = Scene::build(d).unwrap();
    let h = scene
        .intersect(&Ray::new(Vec3::new(0.1, -1.0, 0.1), Vec3::Y), 0.0, f32::INFINITY)
        .unwrap();
    assert_eq!((h.t, h.ng, h.kind), (2.0, -Vec3::Y, PrimKind::Disk));
    let disk: Disk = scene.desc.disks[0].disk().unwrap();
    assert_eq!(disk.normal, -Vec3::Y);
}

#[test]
fn bad_disks_are_one_line_errors_at_their_line() {
    let shape = |body: &str| format!("{HEAD}[[shapes]]\ntype = \"disk\"\nmaterial = \"grey\"\n{body}");
    let line = 9;
    let cases = [
        (
            "centre = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = 0\n",
            "disk shape: radius 0 must be > 0",
        ),
        (
            "centre = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = -1\n",
            "radius -1 must be > 0",
        ),
        (
            "centre = [0, 0, 0]\nnormal = [0, 0, 0]\nradius = 1\n",
            "disk shape: normal [0.0, 0.0, 0.0] must be a non-zero direction",
        ),
        (
            "centre = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = 1\ninner_radius = 1\n",
            "disk shape: inner_radius 1 must be >= 0 and less than the radius 1",
        ),
        (
            "centre = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = 1\ninner_radius = 2\n",
            "inner_radius 2 must be",
        ),
        (
            "centre = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = 1\ninner_radius = -0.5\n",
            "inner_radius -0.5 must be",
        ),
        ("centre = [0, 0, 0]\nradius = 1\n", "disk shape: missing `normal`"),
        ("normal = [0, 0, 1]\nradius = 1\n", "disk shape: missing `centre`"),
        (
            "centre = [0, 0, 0]\nnormal = [0, 0, 1]\n",
            "disk shape: missing `radius`",
        ),
        (
            "centre = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = 1\nmin = [0, 0, 0]\n",
            "`min` does not apply to a disk",
        ),
    ];
    for (body, what) in cases {
        let text = shape(body);
        let e = parse(&text).expect_err(&text).to_string();
        assert!(
            e.starts_with(&format!("disk.toml:{line}: ")),
            "wrong line in '{e}' for\n{text}"
        );
        assert!(e.contains(what), "'{e}' does not say '{what}'");
        assert!(!e.contains('\n'), "'{e}' is not one line");
    }
    // `inner_radius` and `normal` belong to disks only.
    let text = format!("{HEAD}[[shapes]]\ntype = \"sphere\"\nmaterial = \"grey\"\ncentre = [0, 0, 0]\nradius = 1\ninner_radius = 0.5\n");
    let e = parse(&text).unwrap_err().to_string();
    assert!(e.contains("`inner_radius` does not apply to a sphere"), "{e}");
}

#[test]
fn scenes_refuse_bad_disks() {
    let mut d = SceneDesc::empty("disk", camera());
    let m = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
    for bad in [
        DiskDesc::new(Vec3::ZERO, Vec3::Z, -1.0, 0.0, m),
        DiskDesc::new(Vec3::ZERO, Vec3::Z, 1.0, 1.5, m),
        DiskDesc::new(Vec3::ZERO, Vec3::ZERO, 1.0, 0.0, m),
        DiskDesc::new(Vec3::splat(f32::NAN), Vec3::Z, 1.0, 0.0, m),
        DiskDesc::new(Vec3::ZERO, Vec3::Z, 1.0, 0.0, m + 5),
    ] {
        let mut e = d.clone();
        e.disks.push(bad.clone());
        assert!(Scene::build(e).is_err(), "{bad:?}");
    }
}
