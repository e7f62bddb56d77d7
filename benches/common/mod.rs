//! Shared pieces of the BVH benchmarks and tests: the built-in `cornell-bunny`
//! scene with the shared Stanford bunny, the three ray sets of BENCHMARKS.md,
//! and the binary ray file the Embree comparison (`bench/embree/embree_bench.c`)
//! reads.

// Each bench, example and test that includes this file uses a different part.
#![allow(dead_code)]

use raytracer::camera::Camera;
use raytracer::math::{Ray, Vec3};
use raytracer::sampling::{stratified, uniform_sphere, Rng};
use raytracer::scene::{LoadOptions, SceneDesc};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Where the shared bunny sits relative to the crate root.
pub fn bunny_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/stanford-bunny.obj")
}

/// Loads the built-in `cornell-bunny` with the shared bunny, or says why it cannot.
pub fn cornell_bunny_scene() -> Result<SceneDesc, String> {
    let path = bunny_path();
    if !path.exists() {
        return Err(format!("{} not found", path.display()));
    }
    let opts = LoadOptions {
        mesh: Some(path),
        smooth: false,
        lenient: false,
    };
    match raytracer::scene::builtin::by_name("cornell-bunny", &opts) {
        Ok(Some(l)) => Ok(l.desc),
        Ok(None) => Err("no built-in scene cornell-bunny".into()),
        Err(e) => Err(e.to_string()),
    }
}

/// [`cornell_bunny_scene`] for tests: `None` (saying why the test skips)
/// without the shared bunny, except under CI (`CI` set), where `../shared`
/// is always there and a missing bunny fails the test.
pub fn cornell_bunny_scene_or_skip() -> Option<SceneDesc> {
    match cornell_bunny_scene() {
        Ok(d) => Some(d),
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("cornell-bunny: {e}: under CI (CI is set) the shared assets must be there")
        }
        Err(e) => {
            println!("skipped: cornell-bunny: {e}");
            None
        }
    }
}

/// What a ray set asks of the acceleration structure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// Closest hit (`Bvh::intersect`, `rtcIntersect1`).
    Closest = 0,
    /// Any hit (`Bvh::occluded`, `rtcOccluded1`).
    Occluded = 1,
}

/// A ray with its valid segment (t_min, t_max).
#[derive(Clone, Copy, Debug)]
pub struct BenchRay {
    pub ray: Ray,
    pub t_min: f32,
    pub t_max: f32,
}

pub struct RaySet {
    pub name: &'static str,
    pub query: Query,
    pub rays: Vec<BenchRay>,
}

/// Set (a): `spp` jittered primary rays per pixel of a `size` x `size` image,
/// pixel by pixel in scanline order (as coherent as a renderer's tiles).
pub fn primary_rays(desc: &SceneDesc, size: u32, spp: u32) -> RaySet {
    let c = &desc.camera;
    let cam = Camera::new(c.position, c.look_at, c.up, c.fov_y_deg, size, size).expect("cornell camera is valid");
    let n = (spp as f32).sqrt().round() as u32;
    let mut rays = Vec::with_capacity((size * size * spp) as usize);
    for y in 0..size {
        for x in 0..size {
            let pixel = (y * size + x) as u64;
            for s in 0..spp {
                let mut rng = Rng::keyed(1, pixel, s as u64);
                let u = stratified(s % (n * n), n, rng.next_2d());
                let ray = cam.generate_ray(x as f32 + u.x, y as f32 + u.y);
                rays.push(BenchRay {
                    ray,
                    t_min: 0.0,
                    t_max: f32::INFINITY,
                });
            }
        }
    }
    RaySet {
        name: "primary",
        query: Query::Closest,
        rays,
    }
}

/// Set (b): `count` rays from uniform random points of the box [-1, 1]^3 in
/// uniform random directions.
pub fn incoherent_rays(count: usize) -> RaySet {
    let mut rng = Rng::new(2, 7);
    let rays = (0..count)
        .map(|_| {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
            BenchRay {
                ray: Ray::new(o, uniform_sphere(rng.next_2d())),
                t_min: 0.0,
                t_max: f32::INFINITY,
            }
        })
        .collect();
    RaySet {
        name: "incoherent",
        query: Query::Closest,
        rays,
    }
}

/// Set (c): `count` shadow rays from uniform random floor points to uniform
/// random points on the light sphere's surface, any hit, t_max = distance.
pub fn shadow_rays(desc: &SceneDesc, count: usize) -> RaySet {
    let light = &desc.lights[0];
    let (centre, radius) = match light {
        raytracer::light::Light::Sphere { sphere, .. } => (sphere.centre, sphere.radius),
        // The built-in cornell scenes have a sphere light; anything else is
        // aimed at as a point at its centre.
        other => (other.position(), 0.0),
    };
    let mut rng = Rng::new(3, 11);
    let rays = (0..count)
        .map(|_| {
            let o = Vec3::new(rng.next_f32() * 2.0 - 1.0, 1.0, rng.next_f32() * 2.0 - 1.0);
            let target = centre + uniform_sphere(rng.next_2d()) * radius;
            let to = target - o;
            let dist = to.length();
            BenchRay {
                ray: Ray::new(o, to / dist),
                // The origin lies on the floor: skip the floor itself.
                t_min: 1e-4,
                t_max: dist,
            }
        })
        .collect();
    RaySet {
        name: "shadow",
        query: Query::Occluded,
        rays,
    }
}

/// The three sets of BENCHMARKS.md: 512x512x4 primary, 2^20 incoherent, 2^20 shadow.
pub fn standard_ray_sets(desc: &SceneDesc) -> Vec<RaySet> {
    vec![
        primary_rays(desc, 512, 4),
        incoherent_rays(1 << 20),
        shadow_rays(desc, 1 << 20),
    ]
}

/// World-space triangles of a description, in input order.
pub fn world_triangles(desc: &SceneDesc) -> Vec<[Vec3; 3]> {
    desc.triangles.iter().map(|t| t.vertices).collect()
}

const MAGIC: &[u8; 8] = b"RTRAYS01";

/// Writes triangles and ray sets in the little-endian layout that
/// `bench/embree/embree_bench.c` reads:
///
/// ```text
/// "RTRAYS01"  u32 triangle count  { f32 x 9 } per triangle (v0, v1, v2)
/// u32 set count, then per set:
///   u32 query (0 closest, 1 occluded)  u32 name length  name bytes
///   u32 ray count  { f32 ox oy oz t_min dx dy dz t_max } per ray
/// ```
pub fn write_ray_file(path: &Path, tris: &[[Vec3; 3]], sets: &[RaySet]) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let u32le = |w: &mut dyn Write, v: u32| w.write_all(&v.to_le_bytes());
    w.write_all(MAGIC)?;
    u32le(&mut w, tris.len() as u32)?;
    for t in tris {
        for v in t {
            for c in v.to_array() {
                w.write_all(&c.to_le_bytes())?;
            }
        }
    }
    u32le(&mut w, sets.len() as u32)?;
    for s in sets {
        u32le(&mut w, s.query as u32)?;
        u32le(&mut w, s.name.len() as u32)?;
        w.write_all(s.name.as_bytes())?;
        u32le(&mut w, s.rays.len() as u32)?;
        for r in &s.rays {
            let o = r.ray.o;
            let d = r.ray.d;
            for c in [o.x, o.y, o.z, r.t_min, d.x, d.y, d.z, r.t_max] {
                w.write_all(&c.to_le_bytes())?;
            }
        }
    }
    w.flush()
}
