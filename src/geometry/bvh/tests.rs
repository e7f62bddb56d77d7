//! Checks the BVH against a loop over all triangles, the reference both
//! the build and the traversal must agree with.

use super::*;
use crate::geometry::triangle::Triangle;
use crate::math::Ray;
use crate::sampling::Rng;

fn random_tris(n: usize, seed: u64) -> Vec<Triangle> {
    let mut r = Rng::new(seed, 3);
    let mut p = || Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
    (0..n)
        .map(|_| {
            let c = p() * 4.0 - Vec3::splat(2.0);
            Triangle::new(
                c,
                c + (p() - Vec3::splat(0.5)) * 0.4,
                c + (p() - Vec3::splat(0.5)) * 0.4,
            )
        })
        .collect()
}

fn brute(tris: &[Triangle], ray: &Ray) -> Option<(u32, f32)> {
    let mut best: Option<(u32, f32)> = None;
    for (i, t) in tris.iter().enumerate() {
        if let Some(h) = t.intersect_mt(ray, 0.0, best.map_or(f32::INFINITY, |b| b.1)) {
            best = Some((i as u32, h.t));
        }
    }
    best
}

#[test]
fn matches_brute_force_on_random_soup() {
    let tris = random_tris(3000, 9);
    let bvh = Bvh::build(&tris);
    let mut r = Rng::new(5, 5);
    let mut hits = 0;
    for _ in 0..5000 {
        let o = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 6.0 - Vec3::splat(3.0);
        let d = crate::sampling::uniform_sphere(r.next_2d());
        let ray = Ray::new(o, d);
        let got = bvh
            .intersect(&ray, 0.0, f32::INFINITY)
            .map(|(s, h)| (bvh.order[s as usize], h.t));
        let want = brute(&tris, &ray);
        assert_eq!(got, want);
        assert_eq!(bvh.occluded(&ray, 0.0, f32::INFINITY), want.is_some());
        hits += want.is_some() as usize;
    }
    assert!(hits > 500);
    let s = bvh.stats();
    assert_eq!(s.leaf_sizes.iter().enumerate().map(|(k, c)| k * c).sum::<usize>(), 3000);
    assert!(s.depth < 64);
}

#[test]
fn coincident_primitives_build_a_bounded_tree() {
    let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
    let tris = vec![t; 100];
    let bvh = Bvh::build(&tris);
    let s = bvh.stats();
    assert!(s.leaf_sizes.iter().enumerate().all(|(k, &c)| c == 0 || k <= MAX_LEAF));
    let ray = Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z);
    assert!(bvh.intersect(&ray, 0.0, f32::INFINITY).is_some());
}

#[test]
fn empty_bvh_misses() {
    let bvh = Bvh::build(&[]);
    let ray = Ray::new(Vec3::ZERO, Vec3::Z);
    assert!(bvh.intersect(&ray, 0.0, f32::INFINITY).is_none());
    assert!(!bvh.occluded(&ray, 0.0, f32::INFINITY));
}
