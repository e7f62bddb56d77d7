//! The BVH against a brute-force loop over all triangles: closest hit
//! (distance and triangle) and occlusion, on random meshes (property tests)
//! and on `cornell-bunny`; and the build's independence of the thread count.

#[path = "../../benches/common/mod.rs"]
mod common;

use proptest::prelude::*;
use raytracer::geometry::{Bvh, Triangle};
use raytracer::math::{Ray, Vec3};
use raytracer::sampling::{uniform_sphere, Rng};

/// Closest hit by testing every triangle in input order: (index, t).
fn brute_closest(tris: &[Triangle], ray: &Ray, t_min: f32, t_max: f32) -> Option<(u32, f32)> {
    let mut best: Option<(u32, f32)> = None;
    for (i, t) in tris.iter().enumerate() {
        if let Some(h) = t.intersect_mt(ray, t_min, best.map_or(t_max, |b| b.1)) {
            best = Some((i as u32, h.t));
        }
    }
    best
}

/// Whether a Moller-Trumbore hit lies on its triangle. For rays almost
/// parallel to a triangle's plane the test can report a "hit" far from the
/// triangle (rounding in a near-zero determinant); any BVH culls those by the
/// triangle's box, so they are not compared.
fn genuine(tri: &Triangle, ray: &Ray, t: f32) -> bool {
    let p = ray.at(t);
    let b = tri.bounds();
    let tol = 1e-4 * (1.0 + p.abs().max_element());
    (p - b.min).min_element() >= -tol && (b.max - p).min_element() >= -tol
}

/// Whether any triangle is hit in (t_min, t_max): (by any hit, by a genuine hit).
fn brute_occluded(tris: &[Triangle], ray: &Ray, t_min: f32, t_max: f32) -> (bool, bool) {
    let hits: Vec<_> = tris
        .iter()
        .filter_map(|t| t.intersect_mt(ray, t_min, t_max).map(|h| genuine(t, ray, h.t)))
        .collect();
    (!hits.is_empty(), hits.iter().any(|&g| g))
}

#[derive(Debug, PartialEq)]
enum Outcome {
    Hit,
    Miss,
    /// The brute-force answer rests on a spurious hit.
    Skipped,
}

/// Checks one ray against brute force.
fn check_ray(bvh: &Bvh, tris: &[Triangle], ray: &Ray, t_min: f32, t_max: f32) -> Result<Outcome, TestCaseError> {
    let want = brute_closest(tris, ray, t_min, t_max);
    if want.is_some_and(|(i, t)| !genuine(&tris[i as usize], ray, t)) {
        return Ok(Outcome::Skipped);
    }
    let got = bvh.intersect(ray, t_min, t_max);
    // The wide (AVX) node test, where the CPU has it, agrees with SSE bit
    // for bit, hit for hit.
    let baseline = bvh.intersect_baseline(ray, t_min, t_max);
    prop_assert_eq!(
        got.map(|(s, h)| (s, h.t.to_bits(), h.u.to_bits(), h.v.to_bits())),
        baseline.map(|(s, h)| (s, h.t.to_bits(), h.u.to_bits(), h.v.to_bits())),
        "AVX and SSE traversals differ for {:?}",
        ray
    );
    match (got, want) {
        (None, None) => {}
        (Some((slot, h)), Some((id, t))) => {
            let got_id = bvh.order[slot as usize];
            prop_assert_eq!(h.t, t, "distance differs for {:?}", ray);
            // The same distance on another triangle is a genuine tie (a shared
            // edge or a duplicate); the BVH may meet it first.
            if got_id != id {
                let alt = tris[got_id as usize].intersect_mt(ray, t_min, t_max);
                prop_assert_eq!(alt.map(|a| a.t), Some(t), "triangle {} vs {} for {:?}", got_id, id, ray);
            }
            let own = tris[got_id as usize].intersect_mt(ray, t_min, t_max);
            prop_assert_eq!(own, Some(h), "hit record differs from the triangle's own test");
        }
        (got, want) => prop_assert!(false, "bvh {:?} vs brute force {:?} for {:?}", got, want, ray),
    }
    // Occlusion over the whole segment and over a part that may end before the hit.
    let part = want.map_or(t_max, |(_, t)| t * 0.999);
    for end in [t_max, part] {
        let (any, any_genuine) = brute_occluded(tris, ray, t_min, end);
        prop_assert_eq!(bvh.occluded(ray, t_min, end), bvh.occluded_baseline(ray, t_min, end));
        if any == any_genuine {
            prop_assert_eq!(
                bvh.occluded(ray, t_min, end),
                any,
                "occluded up to {} for {:?}",
                end,
                ray
            );
        }
    }
    Ok(if want.is_some() { Outcome::Hit } else { Outcome::Miss })
}

/// Coordinates from a coarse grid half the time, so that meshes get shared
/// vertices, axis-aligned (flat-boxed) triangles and exact coincidences.
fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![(-4i32..=4).prop_map(|k| k as f32 * 0.5), -2.0f32..2.0]
}

fn point() -> impl Strategy<Value = Vec3> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn triangle() -> impl Strategy<Value = Triangle> {
    prop_oneof![
        // Small triangles around a random point, like a scanned mesh.
        (point(), point(), point()).prop_map(|(c, a, b)| Triangle::new(c, c + a * 0.2, c + b * 0.2)),
        // Large ones, like walls.
        (point(), point(), point()).prop_map(|(a, b, c)| Triangle::new(a, b, c)),
    ]
}

/// Directions with exactly zero components half the time (axis-parallel rays).
fn direction() -> impl Strategy<Value = Vec3> {
    let comp = prop_oneof![Just(0.0f32), Just(1.0), Just(-1.0), -1.0f32..1.0];
    (comp.clone(), comp.clone(), comp).prop_filter_map("zero direction", |(x, y, z)| Vec3::new(x, y, z).try_normalize())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn closest_hit_and_occlusion_match_brute_force(
        tris in prop::collection::vec(triangle(), 1..400),
        rays in prop::collection::vec((point(), direction()), 64),
        seed in any::<u64>(),
    ) {
        let bvh = Bvh::build(&tris);
        prop_assert_eq!(bvh.order.len(), tris.len());
        // Rays from the strategy, plus random ones from the box aimed at
        // random triangles so that most of them hit.
        let mut rng = Rng::new(seed, 1);
        let mut all: Vec<Ray> = rays.iter().map(|(o, d)| Ray::new(*o * 1.5, *d)).collect();
        for _ in 0..64 {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 6.0 - Vec3::splat(3.0);
            let t = &tris[(rng.next_u32() as usize) % tris.len()];
            let target = t.point_at(rng.next_f32() * 0.5, rng.next_f32() * 0.5);
            if let Some(d) = (target - o).try_normalize() {
                all.push(Ray::new(o, d));
            }
        }
        let mut skipped = 0;
        for ray in &all {
            for (t_min, t_max) in [(0.0, f32::INFINITY), (0.5, 3.0)] {
                skipped += (check_ray(&bvh, &tris, ray, t_min, t_max)? == Outcome::Skipped) as usize;
            }
        }
        prop_assert!(skipped * 20 <= all.len(), "{} of {} rays skipped", skipped, 2 * all.len());
    }
}

#[test]
fn agrees_with_brute_force_on_the_bunny() {
    let Some(desc) = common::cornell_bunny_scene_or_skip() else {
        return;
    };
    let tris: Vec<Triangle> = common::world_triangles(&desc)
        .iter()
        .map(|v| Triangle::new(v[0], v[1], v[2]))
        .collect();
    let bvh = Bvh::build(&tris);
    let mut rng = Rng::new(77, 2);
    let (mut hits, mut skipped) = (0, 0);
    let n = 1500;
    for i in 0..n {
        // Alternate rays from inside the box and rays aimed at the bunny.
        let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
        let d = if i % 2 == 0 {
            uniform_sphere(rng.next_2d())
        } else {
            let target =
                Vec3::new(0.33, 0.7, -0.39) + (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5) * 0.6;
            (target - o).normalize()
        };
        let ray = Ray::new(o, d);
        match check_ray(&bvh, &tris, &ray, 0.0, f32::INFINITY) {
            Ok(o) => {
                hits += (o == Outcome::Hit) as usize;
                skipped += (o == Outcome::Skipped) as usize;
            }
            Err(e) => panic!("{e}"),
        }
    }
    assert!(skipped * 100 <= n, "{skipped} of {n} rays skipped");
    assert!(hits > n * 3 / 4, "only {hits} of {n} rays hit the closed room");
}

#[test]
fn build_is_the_same_for_any_thread_count() {
    // Big enough for parallel binning and parallel subtrees.
    let mut rng = Rng::new(5, 9);
    let mut p = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    let tris: Vec<Triangle> = (0..40_000)
        .map(|_| {
            let c = p() * 4.0;
            Triangle::new(c, c + p() * 0.05, c + p() * 0.05)
        })
        .collect();
    let build = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| Bvh::build(&tris))
    };
    let one = build(1);
    for threads in [2, 3, 8] {
        assert!(build(threads) == one, "tree differs with {threads} threads");
    }
}
