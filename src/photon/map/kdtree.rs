//! The kd-tree over the photons: how the photons near a point are found again
//! (build, balance, queries), apart from the packed record it stores.
//!
//! Jensen (2001), "Realistic Image Synthesis Using Photon Mapping", 5.1-5.2 and
//! 6.3: photons are stored in a flat array and balanced into a kd-tree that
//! splits at the median of the widest axis of each subtree's bounding box. Our
//! tree is implicit: the array itself is reordered so that the photon at the
//! middle of every range is that range's splitting node, its left half below the
//! plane and its right half above. No node is allocated; the split axis sits in
//! two bits of the photon. Ranges of at most `LEAF` photons are left unsorted and
//! scanned.
//!
//! Queries (fixed radius and k nearest) accept exactly the photons a linear
//! scan accepts: both compare the same squared distance, and the tree prunes a
//! subtree only when its splitting plane alone is farther than the radius.

use super::record::Photon;
use crate::math::{Aabb, Vec3};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Ranges this small are not split further; queries scan them.
pub const LEAF: usize = 16;
/// Subtrees larger than this are built in parallel.
const PARALLEL_BUILD: usize = 1 << 15;
/// Deep enough for any tree that fits in memory (depth ~ log2(n / LEAF)).
const STACK: usize = 64;

/// The squared distance every query compares with the squared radius.
#[inline]
fn dist2(a: Vec3, b: Vec3) -> f32 {
    (a - b).length_squared()
}

/// A neighbour found by a k-nearest query: squared distance and photon index,
/// ordered by distance, then index, so that ties are broken the same way in
/// the tree and in the linear scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    pub d2: f32,
    pub index: u32,
}

impl Eq for Neighbour {}

impl PartialOrd for Neighbour {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl Ord for Neighbour {
    fn cmp(&self, o: &Self) -> Ordering {
        self.d2.total_cmp(&o.d2).then(self.index.cmp(&o.index))
    }
}

/// Photons balanced into an implicit kd-tree, plus the unit their powers are in.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonMap {
    photons: Vec<Photon>,
    /// Power (W) of a stored power of 1.0.
    pub unit: f32,
}

impl PhotonMap {
    /// Balances the photons into a kd-tree in place (in parallel on the current
    /// rayon pool; the result does not depend on the number of threads).
    pub fn build(mut photons: Vec<Photon>, unit: f32) -> PhotonMap {
        balance(&mut photons);
        PhotonMap { photons, unit }
    }

    /// A map from photons already in kd-tree order (as `photons()` gives
    /// them), e.g. read back from a file.
    pub fn from_balanced(photons: Vec<Photon>, unit: f32) -> PhotonMap {
        PhotonMap { photons, unit }
    }

    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// The photons in tree order (indices of queries refer to this order).
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }

    /// Bytes held by the map, index included.
    pub fn bytes(&self) -> usize {
        self.photons.len() * std::mem::size_of::<Photon>()
    }

    /// Calls `f(index, photon)` for every photon with |p - q|^2 <= r2.
    pub fn for_each_within(&self, q: Vec3, r2: f32, mut f: impl FnMut(u32, &Photon)) {
        let ph = &self.photons[..];
        let mut stack = [(0u32, 0u32); STACK];
        stack[0] = (0, ph.len() as u32);
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (lo, hi) = stack[sp];
            // A leaf's photons, or an inner node's own: one call of `f`,
            // which the compiler then keeps inline.
            let (leaf, m) = ((hi - lo) as usize <= LEAF, lo + (hi - lo) / 2);
            let own = if leaf { lo..hi } else { m..m + 1 };
            for i in own {
                if dist2(ph[i as usize].p, q) <= r2 {
                    f(i, &ph[i as usize]);
                }
            }
            if leaf {
                continue;
            }
            let node = &ph[m as usize];
            let d = q[node.axis()] - node.p[node.axis()];
            let (near, far) = if d < 0.0 {
                ((lo, m), (m + 1, hi))
            } else {
                ((m + 1, hi), (lo, m))
            };
            // Every photon of the far side is at least |d| away along the axis.
            if d * d <= r2 {
                stack[sp] = far;
                sp += 1;
            }
            stack[sp] = near;
            sp += 1;
        }
    }

    /// The (up to) k nearest photons with |p - q|^2 <= r2_max among those
    /// `accept` admits, into `out` (unordered; reuses its allocation). Returns
    /// the squared search radius reached: the k-th distance when k were found,
    /// else `r2_max`.
    pub fn k_nearest(
        &self,
        q: Vec3,
        k: usize,
        r2_max: f32,
        accept: impl Fn(&Photon) -> bool,
        out: &mut Vec<Neighbour>,
    ) -> f32 {
        out.clear();
        if k == 0 {
            return r2_max;
        }
        let mut heap = BinaryHeap::from(std::mem::take(out));
        let mut r2 = r2_max;
        let ph = &self.photons[..];
        let consider =
            |i: u32, heap: &mut BinaryHeap<Neighbour>, r2: &mut f32| consider_nearest(ph, q, k, &accept, i, heap, r2);
        // Each stacked range carries a lower bound on its photons' squared
        // distance (from the splitting planes crossed to reach it); it is
        // skipped when popped if the radius has shrunk below that bound.
        let mut stack = [(0u32, 0u32, 0.0f32); STACK];
        stack[0] = (0, ph.len() as u32, 0.0);
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (lo, hi, bound) = stack[sp];
            if bound > r2 {
                continue;
            }
            if (hi - lo) as usize <= LEAF {
                for i in lo..hi {
                    consider(i, &mut heap, &mut r2);
                }
                continue;
            }
            let m = lo + (hi - lo) / 2;
            let node = &ph[m as usize];
            let d = q[node.axis()] - node.p[node.axis()];
            consider(m, &mut heap, &mut r2);
            let (near, far) = if d < 0.0 {
                ((lo, m), (m + 1, hi))
            } else {
                ((m + 1, hi), (lo, m))
            };
            // Far side first on the stack, so that it is popped after the near
            // side has shrunk the radius.
            if d * d <= r2 {
                stack[sp] = (far.0, far.1, bound.max(d * d));
                sp += 1;
            }
            stack[sp] = (near.0, near.1, bound);
            sp += 1;
        }
        *out = heap.into_vec();
        r2
    }
}

/// Offers photon `i` to a k-nearest search around `q` (the heap of the
/// nearest so far, `r2` the radius they reach once k are found). Forced
/// inline: as a closure it was left out of line once `accept` grew, and
/// the call cost the default render 7%.
#[inline(always)]
fn consider_nearest(
    ph: &[Photon],
    q: Vec3,
    k: usize,
    accept: &impl Fn(&Photon) -> bool,
    i: u32,
    heap: &mut BinaryHeap<Neighbour>,
    r2: &mut f32,
) {
    let p = &ph[i as usize];
    let d2 = dist2(p.p, q);
    if d2 > *r2 || !accept(p) {
        return;
    }
    let nb = Neighbour { d2, index: i };
    if heap.len() < k {
        heap.push(nb);
    } else if heap.peek().is_some_and(|top| nb < *top) {
        heap.pop();
        heap.push(nb);
    } else {
        return;
    }
    if heap.len() == k {
        if let Some(top) = heap.peek() {
            *r2 = top.d2;
        }
    }
}

/// Reorders `ph` into the implicit kd-tree: the middle photon of every range
/// larger than `LEAF` is the median along the widest axis of the range's bounds.
fn balance(ph: &mut [Photon]) {
    if ph.len() <= LEAF {
        return;
    }
    let mut b = Aabb::EMPTY;
    for p in ph.iter() {
        b.grow(p.p);
    }
    let e = b.extent();
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let m = ph.len() / 2;
    ph.select_nth_unstable_by(m, |a, b| a.p[axis].total_cmp(&b.p[axis]));
    ph[m].set_axis(axis);
    let parallel = ph.len() > PARALLEL_BUILD;
    let (left, rest) = ph.split_at_mut(m);
    let right = &mut rest[1..];
    if parallel {
        rayon::join(|| balance(left), || balance(right));
    } else {
        balance(left);
        balance(right);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use proptest::prelude::*;

    /// The linear-scan oracles the tree's queries must agree with.
    impl PhotonMap {
        /// Reference: every photon within r2 of q, by a linear scan, in index order.
        fn linear_within(&self, q: Vec3, r2: f32) -> Vec<u32> {
            (0..self.photons.len() as u32)
                .filter(|&i| dist2(self.photons[i as usize].p, q) <= r2)
                .collect()
        }

        /// Reference: the k nearest photons within r2_max of q, by a linear scan,
        /// sorted by (distance, index).
        fn linear_k_nearest(&self, q: Vec3, k: usize, r2_max: f32, accept: impl Fn(&Photon) -> bool) -> Vec<Neighbour> {
            let mut all: Vec<Neighbour> = (0..self.photons.len() as u32)
                .filter_map(|i| {
                    let p = &self.photons[i as usize];
                    let d2 = dist2(p.p, q);
                    (d2 <= r2_max && accept(p)).then_some(Neighbour { d2, index: i })
                })
                .collect();
            all.sort();
            all.truncate(k);
            all
        }
    }

    fn map_of(points: &[Vec3]) -> PhotonMap {
        let photons = points
            .iter()
            .enumerate()
            .map(|(i, &p)| Photon::new(p, Vec3::Z, Vec3::Z, Vec3::ONE, i as u32, i % 3 == 0))
            .collect();
        PhotonMap::build(photons, 1.0)
    }

    fn tree_within(map: &PhotonMap, q: Vec3, r2: f32) -> Vec<u32> {
        let mut v = vec![];
        map.for_each_within(q, r2, |i, _| v.push(i));
        v.sort();
        v
    }

    fn tree_k_nearest(map: &PhotonMap, q: Vec3, k: usize, r2: f32, direct_only: bool) -> Vec<Neighbour> {
        let mut out = vec![];
        map.k_nearest(q, k, r2, |p| !direct_only || p.is_direct(), &mut out);
        out.sort();
        out
    }

    /// Point clouds on a coarse integer grid (many duplicates, many points at
    /// exactly the same distance) mixed with arbitrary points.
    fn cloud() -> impl Strategy<Value = Vec<Vec3>> {
        let grid = (0i32..6, 0i32..6, 0i32..6).prop_map(|(x, y, z)| Vec3::new(x as f32, y as f32, z as f32));
        let free = (-1.0f32..7.0, -1.0f32..7.0, -1.0f32..7.0).prop_map(|(x, y, z)| Vec3::new(x, y, z));
        prop::collection::vec(prop_oneof![grid, free], 0..400)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn radius_search_matches_linear_scan(points in cloud(), qi in 0usize..1000, r in 0.0f32..3.0) {
            let map = map_of(&points);
            // Query at a photon (or a grid point) and with radii that put other
            // photons exactly on the sphere.
            let q = map.photons().get(qi % points.len().max(1)).map_or(Vec3::splat(2.0), |p| p.p);
            let mut radii = vec![r * r, 0.0, 1.0, 2.0, 4.0, 5.0];
            if let Some(p) = map.photons().get((qi / 7) % points.len().max(1)) {
                radii.push((p.p - q).length_squared());
            }
            for r2 in radii {
                prop_assert_eq!(tree_within(&map, q, r2), map.linear_within(q, r2));
            }
        }

        #[test]
        fn k_nearest_matches_linear_scan(points in cloud(), qi in 0usize..1000, k in 1usize..40, r in 0.0f32..4.0) {
            let map = map_of(&points);
            let q = map.photons().get(qi % points.len().max(1)).map_or(Vec3::splat(2.5), |p| p.p + Vec3::new(0.5, 0.0, 0.0));
            for r2 in [r * r, f32::INFINITY, 1.0] {
                for direct_only in [false, true] {
                    let want = map.linear_k_nearest(q, k, r2, |p| !direct_only || p.is_direct());
                    prop_assert_eq!(tree_k_nearest(&map, q, k, r2, direct_only), want);
                }
            }
        }
    }

    #[test]
    fn tree_is_balanced_at_the_median_of_the_widest_axis() {
        let mut rng = Rng::new(5, 1);
        let pts: Vec<Vec3> = (0..10_000)
            .map(|_| Vec3::new(rng.next_f32() * 10.0, rng.next_f32(), rng.next_f32() * 3.0))
            .collect();
        let map = map_of(&pts);
        let ph = map.photons();
        // The root splits x (the widest), half the photons on each side.
        let m = ph.len() / 2;
        assert_eq!(ph[m].axis(), 0);
        assert!(ph[..m].iter().all(|p| p.p.x <= ph[m].p.x));
        assert!(ph[m + 1..].iter().all(|p| p.p.x >= ph[m].p.x));
        // The same photons, reordered.
        let mut a: Vec<u32> = ph.iter().map(|p| p.object).collect();
        a.sort();
        assert!(a.iter().enumerate().all(|(i, &o)| o == i as u32));
        // Large random clouds agree with the linear scan too.
        for i in 0..50 {
            let q = Vec3::new(i as f32 * 0.2, 0.5, 1.5);
            assert_eq!(tree_within(&map, q, 0.09), map.linear_within(q, 0.09));
            assert_eq!(
                tree_k_nearest(&map, q, 50, f32::INFINITY, false),
                map.linear_k_nearest(q, 50, f32::INFINITY, |_| true)
            );
        }
    }
}
