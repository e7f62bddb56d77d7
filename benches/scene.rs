//! Ray queries through `Scene` (the triangle BVH and the BVH over spheres
//! and disks together, as the integrators call them), on three scenes:
//!
//! - `triangles`: `cornell-bunny` (the shared Stanford bunny; `cornell`
//!   without it) with its sphere light made a point light: triangles only;
//! - `cornell-bunny`: the same with its sphere light (one sphere);
//! - `spheres-2000`: `cornell` with 2000 random spheres in the room.
//!
//! Each has three ray sets of 2^16 rays, single-threaded: primary (128 x 128
//! pixels x 4, closest hit), incoherent (closest hit) and shadow rays to the
//! light (`occluded_before_light`), as in BENCHMARKS.md. Criterion reports
//! the time of one pass over a set; time is the benchmark thread's CPU time.
//! The file uses only what `Scene` had before disks, so the same file
//! measures an earlier commit side by side.
//!
//! cargo bench --bench scene

#[path = "common/mod.rs"]
mod common;

use common::{incoherent_rays, primary_rays, shadow_rays, Query, RaySet};
use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use raytracer::geometry::Sphere;
use raytracer::math::Vec3;
use raytracer::sampling::Rng;
use raytracer::scene::{builtin, SceneDesc, SphereDesc};
use raytracer::Scene;
use std::time::Duration;

const RAYS: usize = 1 << 16;

/// Criterion measurement by the thread's CPU time, shown like wall time.
struct ThreadCpuTime;

static WALL: WallTime = WallTime;

impl Measurement for ThreadCpuTime {
    type Intermediate = cpu_time::ThreadTime;
    type Value = Duration;

    fn start(&self) -> Self::Intermediate {
        cpu_time::ThreadTime::now()
    }
    fn end(&self, start: Self::Intermediate) -> Duration {
        start.elapsed()
    }
    fn add(&self, a: &Duration, b: &Duration) -> Duration {
        *a + *b
    }
    fn zero(&self) -> Duration {
        Duration::ZERO
    }
    fn to_f64(&self, d: &Duration) -> f64 {
        d.as_nanos() as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        WALL.formatter()
    }
}

/// `cornell-bunny`, or `cornell` when the shared bunny is not there.
fn bunny_or_cornell() -> SceneDesc {
    common::cornell_bunny_scene().unwrap_or_else(|e| {
        println!("cornell-bunny: {e}; using cornell");
        builtin::cornell()
    })
}

/// `cornell` with `n` spheres of radius 0.005 to 0.03 inside the room.
fn with_spheres(n: usize) -> SceneDesc {
    let mut d = builtin::cornell();
    let mut r = Rng::new(12, 1);
    for i in 0..n {
        let c = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 1.9 - Vec3::splat(0.95);
        d.spheres.push(SphereDesc {
            axes: None,
            sphere: Sphere {
                centre: c,
                radius: 0.005 + 0.025 * r.next_f32(),
            },
            material: (i % d.materials.len()) as u32,
        });
    }
    d
}

fn sets(d: &SceneDesc) -> Vec<RaySet> {
    vec![primary_rays(d, 128, 4), incoherent_rays(RAYS), shadow_rays(d, RAYS)]
}

fn run(scene: &Scene, set: &RaySet) -> usize {
    match set.query {
        Query::Closest => set
            .rays
            .iter()
            .filter(|r| black_box(scene).intersect(&r.ray, r.t_min, r.t_max).is_some())
            .count(),
        Query::Occluded => set
            .rays
            .iter()
            .filter(|r| black_box(scene).occluded_before_light(&r.ray, r.t_min, r.t_max, 0))
            .count(),
    }
}

fn bench(c: &mut Criterion<ThreadCpuTime>) {
    let mut triangles = bunny_or_cornell();
    triangles.set_light_radius(0.0);
    let scenes = [
        ("triangles", triangles),
        ("cornell-bunny", bunny_or_cornell()),
        ("spheres-2000", with_spheres(2000)),
    ];
    for (name, desc) in scenes {
        let sets = sets(&desc);
        let scene = Scene::build(desc).expect("the scene builds");
        let mut g = c.benchmark_group(name);
        g.throughput(Throughput::Elements(RAYS as u64));
        for set in &sets {
            println!(
                "{name}/{}: {} of {} rays hit",
                set.name,
                run(&scene, set),
                set.rays.len()
            );
            g.bench_function(set.name, |b| b.iter(|| run(&scene, set)));
        }
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .with_measurement(ThreadCpuTime)
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
