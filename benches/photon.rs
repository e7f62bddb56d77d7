//! Photon mapping benchmarks on `cornell`: tracing rate, kd-tree build time and
//! memory, and fixed-radius queries against the linear scan at 10k, 100k, 750k
//! and 5M stored photons.
//!
//!     cargo bench --bench photon
//!
//! Photons are traced once (enough for 5M stored) and every map is a prefix of
//! them, i.e. a random subset in emission order. Queries are at the stored
//! positions of an independent photon trace (points on the surfaces, where a
//! render would ask), taken in that trace's kd-tree order, so that successive
//! queries are near each other as a render's are. Two radii: `cornell`'s 0.1
//! (about 1000 photons a query at 750k) and one that finds about 100 photons
//! at every map size (0.1 * sqrt(100 / found at 0.1)).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use raytracer::math::Vec3;
use raytracer::photon::trace::trace;
use raytracer::photon::{Photon, PhotonMap, PhotonSettings};
use raytracer::scene::builtin::cornell;
use raytracer::Scene;
use std::hint::black_box;
use std::time::{Duration, Instant};

const SIZES: [usize; 4] = [10_000, 100_000, 750_000, 5_000_000];
const RADIUS: f32 = 0.1;

fn scene() -> Scene {
    Scene::build(cornell()).unwrap()
}

fn traced(scene: &Scene, emitted: u64, seed: u64) -> (Vec<Photon>, f32) {
    let s = PhotonSettings {
        photons: emitted,
        ..PhotonSettings::default()
    };
    let t = trace(scene, &s, seed);
    (t.photons, t.unit)
}

fn photon_tracing(c: &mut Criterion) {
    let scene = scene();
    let n = 200_000u64;
    let mut g = c.benchmark_group("trace");
    g.throughput(Throughput::Elements(n));
    g.bench_function("cornell_200k_emitted", |b| {
        b.iter(|| black_box(traced(&scene, n, 1).0.len()))
    });
    g.finish();
}

fn build_and_query(c: &mut Criterion) {
    let scene = scene();
    let start = Instant::now();
    // About 0.8 photons are stored per photon emitted in cornell.
    let (mut all, unit) = traced(&scene, 6_500_000, 1);
    assert!(all.len() >= 5_000_000, "only {} photons stored", all.len());
    all.truncate(5_000_000);
    eprintln!("traced {} photons in {:.2} s", all.len(), start.elapsed().as_secs_f64());
    let (q, _) = traced(&scene, 4_000, 99);
    let queries: Vec<Vec3> = PhotonMap::build(q, 1.0).photons().iter().map(|p| p.p).collect();

    let mut g = c.benchmark_group("kdtree_build");
    for n in [100_000, 750_000, 5_000_000] {
        let photons = all[..n].to_vec();
        let map = PhotonMap::build(photons.clone(), unit);
        eprintln!(
            "{n} photons: {} bytes, {:.1} bytes per photon, index included",
            map.bytes(),
            map.bytes() as f64 / n as f64
        );
        g.bench_with_input(BenchmarkId::from_parameter(n), &photons, |b, p| {
            b.iter_batched(
                || p.clone(),
                |p| PhotonMap::build(p, unit),
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();

    let mut g = c.benchmark_group("radius_query");
    for n in SIZES {
        let map = PhotonMap::build(all[..n].to_vec(), unit);
        let found = |r: f32| {
            let mut found = 0usize;
            for q in &queries {
                map.for_each_within(*q, r * r, |_, _| found += 1);
            }
            found as f64 / queries.len() as f64
        };
        let r100 = RADIUS * (100.0 / found(RADIUS)).sqrt() as f32;
        eprintln!(
            "{n} photons: {:.0} photons a query at r = {RADIUS}, {:.0} at r = {r100:.4}",
            found(RADIUS),
            found(r100)
        );
        let mut i = 0;
        for (name, r) in [("kdtree_r0.1", RADIUS), ("kdtree_100_photons", r100)] {
            g.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| {
                    i = (i + 1) % queries.len();
                    let mut sum = Vec3::ZERO;
                    map.for_each_within(queries[i], r * r, |_, p| sum += p.power());
                    black_box(sum)
                })
            });
        }
        // Milliseconds a query at 5M: criterion's 10 samples keep it short.
        g.bench_function(BenchmarkId::new("linear", n), |b| {
            b.iter(|| {
                i = (i + 1) % queries.len();
                let (q, r2) = (queries[i], RADIUS * RADIUS);
                let mut sum = Vec3::ZERO;
                for p in map.photons() {
                    if (p.p - q).length_squared() <= r2 {
                        sum += p.power();
                    }
                }
                black_box(sum)
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = photon_tracing, build_and_query
}
criterion_main!(benches);
