//! Checks the BVH against a loop over all triangles, the reference both
//! the build and the traversal must agree with.

use super::*;
use crate::geometry::triangle::{TriHit, Triangle};
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
        let baseline = bvh
            .intersect_baseline(&ray, 0.0, f32::INFINITY)
            .map(|(s, h)| (bvh.order[s as usize], h.t));
        assert_eq!(baseline, want);
        assert_eq!(bvh.occluded(&ray, 0.0, f32::INFINITY), want.is_some());
        assert_eq!(bvh.occluded_baseline(&ray, 0.0, f32::INFINITY), want.is_some());
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

/// Triangle count and SAH cost (node visits and packet tests weighted by
/// box half area, not normalised) of the subtree under node `i`.
fn subtree_cost(bvh: &Bvh, i: usize, area: f32, check: &mut dyn FnMut(usize, f32, f32)) -> (usize, f32) {
    let node = &bvh.nodes[i];
    let mut tris = 0;
    let mut cost = TRAVERSAL_COST * area;
    for lane in 0..NODE_WIDTH {
        let Some(b) = bvh.child_bounds(node, lane) else {
            continue;
        };
        let e = b.max - b.min;
        let a = e.x * e.y + e.y * e.z + e.z * e.x;
        let c = node.child[lane];
        if c & LEAF == 0 {
            let (t, k) = subtree_cost(bvh, c as usize, a, check);
            check(t, k, a);
            tris += t;
            cost += k;
        } else {
            let packets = bvh.leaf_packets(c);
            tris += packets
                .iter()
                .map(|p| p.slot.iter().filter(|&&s| s != u32::MAX).count())
                .sum::<usize>();
            cost += INTERSECT_COST * packets.len() as f32 * a;
        }
    }
    (tris, cost)
}

#[test]
fn no_small_subtree_costs_more_than_one_leaf_would() {
    // Scattered triangles, and clusters of ten almost coincident ones: cut
    // apart, a cluster's children keep its whole box, so only collapsing
    // it back into one leaf is cheap.
    let mut tris = random_tris(1000, 4);
    let mut r = Rng::new(8, 1);
    for c in random_tris(100, 6) {
        for _ in 0..10 {
            let mut jitter = || Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 0.01;
            let [a, b, d] = c.vertices();
            tris.push(Triangle::new(a + jitter(), b + jitter(), d + jitter()));
        }
    }
    let bvh = Bvh::build(&tris);
    let mut small = 0;
    let mut check = |t: usize, cost: f32, area: f32| {
        if t <= MAX_LEAF {
            small += 1;
            let leaf = INTERSECT_COST * t.div_ceil(WIDTH) as f32 * area;
            assert!(
                cost < leaf * 1.0001,
                "a node over {t} triangles costs {cost}, one leaf {leaf}"
            );
        }
    };
    subtree_cost(&bvh, 0, 1.0, &mut check);
    assert!(small > 50, "only {small} small subtrees");
}

#[test]
fn four_triangles_far_apart_get_a_leaf_each() {
    // Tiny triangles at four corners of a cube: one leaf would be tested by
    // every ray through the cube, four leaves only by rays near a corner.
    let corner = |x: f32, y: f32, z: f32| {
        let c = Vec3::new(x, y, z);
        Triangle::new(c, c + Vec3::X * 0.01, c + Vec3::Y * 0.01)
    };
    let tris = vec![
        corner(0.0, 0.0, 0.0),
        corner(1.0, 0.0, 1.0),
        corner(0.0, 1.0, 1.0),
        corner(1.0, 1.0, 0.0),
    ];
    let bvh = Bvh::build(&tris);
    assert_eq!(bvh.stats().leaf_sizes.get(1), Some(&4));
    let ray = Ray::new(Vec3::new(1.005, 1.002, -1.0), Vec3::Z);
    assert_eq!(
        bvh.intersect(&ray, 0.0, f32::INFINITY)
            .map(|(s, _)| bvh.order[s as usize]),
        Some(3)
    );
}

/// The closest hit a filter accepts, by a loop over all triangles.
fn brute_where(tris: &[Triangle], ray: &Ray, accept: impl Fn(u32, &TriHit) -> bool) -> Option<(u32, f32)> {
    let mut best: Option<(u32, f32)> = None;
    for (i, t) in tris.iter().enumerate() {
        if let Some(h) = t.intersect_mt(ray, 0.0, best.map_or(f32::INFINITY, |b| b.1)) {
            if accept(i as u32, &h) {
                best = Some((i as u32, h.t));
            }
        }
    }
    best
}

#[test]
fn filtered_queries_find_the_closest_accepted_hit() {
    let tris = random_tris(3000, 21);
    let bvh = Bvh::build(&tris);
    // Rejects by the input triangle (two in three) and by where the ray
    // meets it (half of each triangle), as an alpha texture would.
    let keep = |i: u32, h: &TriHit| i.is_multiple_of(3) || h.u > 0.5;
    let mut r = Rng::new(8, 1);
    let (mut hits, mut skipped) = (0, 0);
    for _ in 0..5000 {
        let o = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 6.0 - Vec3::splat(3.0);
        let ray = Ray::new(o, crate::sampling::uniform_sphere(r.next_2d()));
        let want = brute_where(&tris, &ray, keep);
        let got = bvh
            .intersect_where(&ray, 0.0, f32::INFINITY, |s, h| keep(bvh.order[s as usize], h))
            .map(|(s, h)| (bvh.order[s as usize], h.t));
        assert_eq!(got, want);
        let blocked = bvh.occluded_where(&ray, 0.0, f32::INFINITY, |s, h| keep(bvh.order[s as usize], h));
        assert_eq!(blocked, want.is_some());
        hits += want.is_some() as usize;
        skipped += (brute(&tris, &ray).map(|b| b.0) != want.map(|w| w.0)) as usize;
    }
    // Both outcomes occur often: the filter decides, not the geometry alone.
    assert!(
        hits > 300 && skipped > 300,
        "{hits} hits, {skipped} rays passed a rejected hit"
    );
    // Accepting everything is the unfiltered query.
    let ray = Ray::new(Vec3::new(-3.0, 0.1, 0.2), Vec3::X);
    assert_eq!(
        bvh.intersect_where(&ray, 0.0, f32::INFINITY, |_, _| true),
        bvh.intersect(&ray, 0.0, f32::INFINITY)
    );
}
