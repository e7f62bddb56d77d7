//! Ray-triangle tests (issue 2): Cramer's rule against Moller-Trumbore on the
//! same 4096 random (ray, triangle) pairs, about half of them hits. Criterion
//! reports the time of one pass over all pairs; divide by 4096 for ns per
//! test, or read the throughput line (tests per second). Time is the
//! benchmark thread's CPU time, so other work on a shared machine counts as
//! little as it can.
//!
//! cargo bench --bench intersect

use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use raytracer::geometry::Triangle;
use raytracer::math::{Ray, Vec3};
use raytracer::sampling::Rng;
use std::time::Duration;

const PAIRS: usize = 4096;

/// Triangles of random shape around the origin; rays from a sphere of radius 5
/// aimed at `v0 + u e1 + v e2` for uniform u, v in [0, 1), which lies inside
/// the triangle half of the time, so hits and misses mix unpredictably.
fn pairs() -> Vec<(Ray, Triangle)> {
    let mut rng = Rng::new(17, 4);
    let mut shape = Rng::new(18, 5);
    let mut p = |s: f32| Vec3::new(shape.next_f32(), shape.next_f32(), shape.next_f32()) * 2.0 * s - Vec3::splat(s);
    (0..PAIRS)
        .map(|_| {
            let t = Triangle::new(p(1.0), p(1.0), p(1.0));
            let o = p(1.0).normalize() * 5.0;
            let target = t.point_at(rng.next_f32(), rng.next_f32());
            (Ray::new(o, (target - o).normalize()), t)
        })
        .collect()
}

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

fn bench(c: &mut Criterion<ThreadCpuTime>) {
    let pairs = pairs();
    let hits = pairs
        .iter()
        .filter(|(r, t)| t.intersect_mt(r, 0.0, f32::INFINITY).is_some())
        .count();
    println!("{hits} of {PAIRS} pairs hit");
    let mut g = c.benchmark_group("triangle");
    g.throughput(Throughput::Elements(PAIRS as u64));
    g.bench_function("moller_trumbore", |b| {
        b.iter(|| {
            pairs
                .iter()
                .filter(|(r, t)| black_box(t).intersect_mt(black_box(r), 0.0, f32::INFINITY).is_some())
                .count()
        })
    });
    g.bench_function("cramer", |b| {
        b.iter(|| {
            pairs
                .iter()
                .filter(|(r, t)| {
                    black_box(t)
                        .intersect_cramer(black_box(r), 0.0, f32::INFINITY)
                        .is_some()
                })
                .count()
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(ThreadCpuTime);
    targets = bench
}
criterion_main!(benches);
