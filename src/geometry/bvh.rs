//! Bounding volume hierarchy over triangles.
//!
//! Binned SAH build (Wald 2007, "On fast Construction of SAH-based Bounding
//! Volume Hierarchies"), flattened into one array of 32-byte nodes whose
//! children sit side by side, and an ordered traversal that visits the nearer
//! child first and skips stacked nodes farther than the closest hit so far.
//! Shadow rays use `occluded`, which stops at the first blocker.

use super::triangle::{TriHit, Triangle};
use crate::math::{Aabb, Ray, Vec3};

/// One node: bounds plus either the index of the left child (the right one
/// follows it) or, for a leaf, the first primitive and the count.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct BvhNode {
    min: [f32; 3],
    /// Leaf: first primitive; interior: left child (right = left + 1).
    offset: u32,
    max: [f32; 3],
    /// Number of primitives in a leaf; 0 for an interior node.
    count: u32,
}

const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);

impl BvhNode {
    fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from(self.min),
            max: Vec3::from(self.max),
        }
    }

    fn set_bounds(&mut self, b: &Aabb) {
        self.min = b.min.to_array();
        self.max = b.max.to_array();
    }

    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// The flattened tree and the order in which it wants its primitives stored.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// `order[i]` is the input index of the primitive stored at slot `i`.
    pub order: Vec<u32>,
    /// The triangles in slot order.
    tris: Vec<Triangle>,
}

/// Figures `raytracer info` prints.
#[derive(Clone, Debug)]
pub struct BvhStats {
    pub nodes: usize,
    pub leaves: usize,
    pub depth: usize,
    /// `leaf_sizes[k]` = number of leaves holding k primitives.
    pub leaf_sizes: Vec<usize>,
    /// Expected cost of a random ray (traversal steps + triangle tests), SAH model.
    pub sah_cost: f32,
    pub bytes: usize,
}

const BINS: usize = 16;
/// Traversal stack depth; the build caps tree depth below it.
const STACK: usize = 128;
const MAX_LEAF: usize = 8;
const TRAVERSAL_COST: f32 = 1.0;
const INTERSECT_COST: f32 = 1.0;

struct BuildPrim {
    bounds: Aabb,
    centroid: Vec3,
    index: u32,
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

impl Bvh {
    /// Builds over the triangles; slot `i` of every query result is
    /// triangle `order[i]` of `tris`.
    pub fn build(tris: &[Triangle]) -> Bvh {
        let bounds: Vec<Aabb> = tris.iter().map(|t| t.bounds()).collect();
        let mut prims: Vec<BuildPrim> = bounds
            .iter()
            .enumerate()
            .map(|(i, b)| BuildPrim {
                bounds: *b,
                centroid: b.centre(),
                index: i as u32,
            })
            .collect();
        let mut nodes = Vec::with_capacity(2 * prims.len().max(1));
        nodes.push(BvhNode {
            min: [0.0; 3],
            offset: 0,
            max: [0.0; 3],
            count: 0,
        });
        if prims.is_empty() {
            // An empty leaf with empty bounds: every ray misses it.
            nodes[0].set_bounds(&Aabb::EMPTY);
            return Bvh {
                nodes,
                order: vec![],
                tris: vec![],
            };
        }
        build_node(&mut nodes, 0, &mut prims, 0, 0);
        let order: Vec<u32> = prims.iter().map(|p| p.index).collect();
        let tris = order.iter().map(|&i| tris[i as usize]).collect();
        Bvh { nodes, order, tris }
    }

    pub fn bounds(&self) -> Aabb {
        self.nodes[0].bounds()
    }

    /// Closest hit among `tris` (stored in BVH order) in (t_min, t_max):
    /// the slot of the triangle and the hit.
    pub fn intersect(&self, ray: &Ray, t_min: f32, mut t_max: f32) -> Option<(u32, TriHit)> {
        let tris = &self.tris;
        if self.order.is_empty() {
            return None;
        }
        let inv_d = ray.d.recip();
        let mut best: Option<(u32, TriHit)> = None;
        let mut stack: [(u32, f32); STACK] = [(0, 0.0); STACK];
        let mut sp = 0usize;
        let root = &self.nodes[0];
        slab(root, ray.o, inv_d, t_min, t_max)?;
        let mut node_idx = 0u32;
        loop {
            let node = &self.nodes[node_idx as usize];
            if node.count > 0 {
                let first = node.offset as usize;
                for (k, tri) in tris[first..first + node.count as usize].iter().enumerate() {
                    if let Some(h) = tri.intersect_mt(ray, t_min, t_max) {
                        t_max = h.t;
                        best = Some(((first + k) as u32, h));
                    }
                }
            } else {
                let l = node.offset;
                let tl = slab(&self.nodes[l as usize], ray.o, inv_d, t_min, t_max);
                let tr = slab(&self.nodes[l as usize + 1], ray.o, inv_d, t_min, t_max);
                match (tl, tr) {
                    (Some(a), Some(b)) => {
                        let (near, far, tfar) = if a <= b { (l, l + 1, b) } else { (l + 1, l, a) };
                        stack[sp] = (far, tfar);
                        sp += 1;
                        node_idx = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node_idx = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        node_idx = l + 1;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next node that can still hold a closer hit.
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                let (n, t_enter) = stack[sp];
                if t_enter < t_max {
                    node_idx = n;
                    break;
                }
            }
        }
    }

    /// Whether any triangle blocks the ray in (t_min, t_max).
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        let tris = &self.tris;
        if self.order.is_empty() {
            return false;
        }
        let inv_d = ray.d.recip();
        let mut stack = [0u32; STACK];
        let mut sp = 0usize;
        if slab(&self.nodes[0], ray.o, inv_d, t_min, t_max).is_none() {
            return false;
        }
        let mut node_idx = 0u32;
        loop {
            let node = &self.nodes[node_idx as usize];
            if node.count > 0 {
                let first = node.offset as usize;
                for tri in &tris[first..first + node.count as usize] {
                    if tri.intersect_mt(ray, t_min, t_max).is_some() {
                        return true;
                    }
                }
            } else {
                let l = node.offset;
                let hl = slab(&self.nodes[l as usize], ray.o, inv_d, t_min, t_max).is_some();
                let hr = slab(&self.nodes[l as usize + 1], ray.o, inv_d, t_min, t_max).is_some();
                match (hl, hr) {
                    (true, true) => {
                        stack[sp] = l + 1;
                        sp += 1;
                        node_idx = l;
                        continue;
                    }
                    (true, false) => {
                        node_idx = l;
                        continue;
                    }
                    (false, true) => {
                        node_idx = l + 1;
                        continue;
                    }
                    (false, false) => {}
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            node_idx = stack[sp];
        }
    }

    pub fn stats(&self) -> BvhStats {
        let mut s = BvhStats {
            nodes: self.nodes.len(),
            leaves: 0,
            depth: 0,
            leaf_sizes: vec![0; MAX_LEAF + 1],
            sah_cost: 0.0,
            bytes: self.nodes.len() * std::mem::size_of::<BvhNode>() + self.order.len() * 4,
        };
        let root_area = self.nodes[0].bounds().surface_area().max(f32::MIN_POSITIVE);
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, d)) = stack.pop() {
            let n = &self.nodes[i];
            s.depth = s.depth.max(d);
            let p = n.bounds().surface_area() / root_area;
            if n.is_leaf() || self.order.is_empty() {
                s.leaves += 1;
                let c = n.count as usize;
                if c >= s.leaf_sizes.len() {
                    s.leaf_sizes.resize(c + 1, 0);
                }
                s.leaf_sizes[c] += 1;
                s.sah_cost += p * INTERSECT_COST * c as f32;
            } else {
                s.sah_cost += p * TRAVERSAL_COST;
                stack.push((n.offset as usize, d + 1));
                stack.push((n.offset as usize + 1, d + 1));
            }
        }
        s
    }
}

/// Entry distance of the ray into the node's box, if it enters within (t_min, t_max).
#[inline(always)]
fn slab(node: &BvhNode, o: Vec3, inv_d: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
    let t0 = (Vec3::from(node.min) - o) * inv_d;
    let t1 = (Vec3::from(node.max) - o) * inv_d;
    let tn = t0.min(t1).max_element().max(t_min);
    let tf = t0.max(t1).min_element().min(t_max);
    if tn <= tf {
        Some(tn)
    } else {
        None
    }
}

fn bounds_of(prims: &[BuildPrim]) -> (Aabb, Aabb) {
    let mut b = Aabb::EMPTY;
    let mut c = Aabb::EMPTY;
    for p in prims {
        b = b.union(&p.bounds);
        c.grow(p.centroid);
    }
    (b, c)
}

fn build_node(nodes: &mut Vec<BvhNode>, idx: usize, prims: &mut [BuildPrim], first: usize, depth: usize) {
    let (bounds, cbounds) = bounds_of(prims);
    nodes[idx].set_bounds(&bounds);
    let n = prims.len();
    let make_leaf = |nodes: &mut Vec<BvhNode>| {
        nodes[idx].offset = first as u32;
        nodes[idx].count = n as u32;
    };
    // The depth cap keeps traversal within its fixed stack whatever the input.
    if n <= 1 || depth + 2 >= STACK {
        make_leaf(nodes);
        return;
    }

    let split = find_split(prims, &bounds, &cbounds);
    let mid = match split {
        Some((axis, pos, cost)) if cost < n as f32 * INTERSECT_COST || n > MAX_LEAF => {
            let mid = partition(prims, |p| p.centroid[axis] < pos);
            if mid == 0 || mid == n {
                n / 2
            } else {
                mid
            }
        }
        None if n > MAX_LEAF => {
            // All centroids coincide: split by count to bound leaf size.
            n / 2
        }
        _ => {
            make_leaf(nodes);
            return;
        }
    };

    let left = nodes.len();
    let empty = nodes[idx];
    nodes.push(empty);
    nodes.push(empty);
    nodes[idx].offset = left as u32;
    nodes[idx].count = 0;
    let (lp, rp) = prims.split_at_mut(mid);
    build_node(nodes, left, lp, first, depth + 1);
    build_node(nodes, left + 1, rp, first + mid, depth + 1);
}

/// Best binned SAH split: (axis, position, cost) relative to intersecting
/// every primitive of this node.
fn find_split(prims: &[BuildPrim], bounds: &Aabb, cbounds: &Aabb) -> Option<(usize, f32, f32)> {
    let ext = cbounds.extent();
    let area = bounds.surface_area().max(f32::MIN_POSITIVE);
    let mut best: Option<(usize, f32, f32)> = None;
    for axis in 0..3 {
        if ext[axis] <= 0.0 {
            continue;
        }
        let lo = cbounds.min[axis];
        let scale = BINS as f32 / ext[axis];
        let mut bins = [Bin {
            bounds: Aabb::EMPTY,
            count: 0,
        }; BINS];
        for p in prims {
            let b = (((p.centroid[axis] - lo) * scale) as usize).min(BINS - 1);
            bins[b].count += 1;
            bins[b].bounds = bins[b].bounds.union(&p.bounds);
        }
        // Sweep from the right to know each suffix's area and count.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0u32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for i in (1..BINS).rev() {
            acc = acc.union(&bins[i].bounds);
            cnt += bins[i].count;
            right_area[i] = if cnt > 0 { acc.surface_area() } else { 0.0 };
            right_count[i] = cnt;
        }
        let mut acc = Aabb::EMPTY;
        let mut cnt = 0;
        for i in 0..BINS - 1 {
            acc = acc.union(&bins[i].bounds);
            cnt += bins[i].count;
            if cnt == 0 || right_count[i + 1] == 0 {
                continue;
            }
            let cost = TRAVERSAL_COST
                + INTERSECT_COST * (acc.surface_area() * cnt as f32 + right_area[i + 1] * right_count[i + 1] as f32)
                    / area;
            if best.is_none_or(|b| cost < b.2) {
                best = Some((axis, lo + (i + 1) as f32 / scale, cost));
            }
        }
    }
    best
}

fn partition<T>(v: &mut [T], pred: impl Fn(&T) -> bool) -> usize {
    let mut i = 0;
    for j in 0..v.len() {
        if pred(&v[j]) {
            v.swap(i, j);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
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
}
