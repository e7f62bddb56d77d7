//! Bounding volume hierarchy over triangles: a four-wide BVH (a BVH4) whose
//! leaves hold packets of four triangles.
//!
//! Build: top-down binned SAH (Wald 2007, "On fast Construction of SAH-based
//! Bounding Volume Hierarchies"). Each BVH4 node starts as one child holding
//! all its triangles and splits, by the best binned SAH plane, the child of
//! largest surface area until it has four, as Embree's wide builders do (Wald
//! et al. 2014, "Embree: A Kernel Framework for Efficient CPU Ray Tracing").
//! Leaf cost counts blocks of four triangles, since a leaf is tested four
//! triangles at a time. Big subtrees build in parallel (`rayon`) and big nodes
//! bin in parallel; every decision depends only on the input, so the tree is
//! the same for any number of threads.
//!
//! Traversal tests a ray against the four child boxes of a node at once (SIMD
//! lanes: glam's `Vec4` is an SSE register on x86-64), with the near and far
//! planes chosen by the sign of the direction. Closest-hit queries visit the
//! nearest child first and skip stacked nodes farther than the closest hit so
//! far; `occluded` stops at the first blocker. The far distance of every box
//! is widened by 1 + 2 gamma(3) (Ize 2013, "Robust BVH Ray Traversal"), so
//! rounding never culls a box the ray touches; rays parallel to an axis, even
//! lying in a box face, are handled exactly (see `TraversalRay::new`). Leaves
//! test four triangles at once with exactly the arithmetic of
//! `Triangle::intersect_mt`, so a query returns bit for bit what a loop over
//! all triangles would (but for the test's spurious hits far off a triangle
//! for rays almost in its plane, which the boxes rightly cull).

use super::triangle::{TriHit, Triangle};
use crate::math::{Aabb, Ray, Vec3};
use arrayvec::ArrayVec;
use glam::{BVec4A, Vec3A, Vec4};
use rayon::prelude::*;

/// Children of one node and triangles of one leaf packet.
const WIDTH: usize = 4;
/// SAH bins per axis.
const BINS: usize = 32;
/// Most triangles in one leaf (four packets).
const MAX_LEAF: usize = 16;
/// SAH cost of visiting a node relative to testing one packet of triangles.
const TRAVERSAL_COST: f32 = 1.0;
const INTERSECT_COST: f32 = 1.0;
/// Below this node depth splits follow the SAH; deeper ones (only pathological
/// inputs get there) halve by count, which bounds the depth and so the stack.
const SAH_DEPTH: usize = 40;
/// Traversal stack entries: at most three pushes per level of a tree at most
/// SAH_DEPTH + 16 levels deep (halving by count four ways).
const STACK: usize = 3 * (SAH_DEPTH + 16) + 1;
/// Subtrees with more triangles than this build on their own rayon task.
const PARALLEL_SUBTREE: usize = 4096;
/// Nodes with more triangles than this bin in parallel chunks of this size.
const PARALLEL_BINNING: usize = 16384;

/// A child reference: a node index, or (top bit set) a leaf given by its
/// first packet and its packet count.
const LEAF: u32 = 1 << 31;
const LEAF_COUNT_SHIFT: u32 = 27;
const LEAF_FIRST_MASK: u32 = (1 << LEAF_COUNT_SHIFT) - 1;
/// Unused child lanes: a leaf of no packets behind an empty box.
const EMPTY_CHILD: u32 = LEAF;

/// One node: the boxes of its four children, lane by lane, and their references.
/// Aligned to a cache line so that a node spans exactly two.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
struct Node4 {
    /// `bounds[axis][0]` holds the children's minima along `axis`, `[1]` the maxima.
    bounds: [[Vec4; 2]; 3],
    child: [u32; WIDTH],
}

/// Four triangles in the layout of `Triangle` (vertex and two edges), lane by
/// lane; `slot[i]` is the slot of lane i, or `u32::MAX` for padding (a
/// degenerate triangle no ray hits).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
struct Tri4 {
    v0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
    slot: [u32; WIDTH],
}

/// The tree, its triangle packets, and the order of the triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    /// `nodes[0]` is the root.
    nodes: Vec<Node4>,
    packets: Vec<Tri4>,
    /// `order[i]` is the input index of the triangle stored at slot `i`.
    pub order: Vec<u32>,
}

/// Figures `raytracer info` prints.
#[derive(Clone, Debug)]
pub struct BvhStats {
    pub nodes: usize,
    pub leaves: usize,
    pub depth: usize,
    /// `leaf_sizes[k]` = number of leaves holding k triangles.
    pub leaf_sizes: Vec<usize>,
    /// Expected cost of a random ray (node visits + packet tests), SAH model.
    pub sah_cost: f32,
    pub bytes: usize,
}

impl Default for Bvh {
    fn default() -> Self {
        Bvh::build(&[])
    }
}

impl Bvh {
    /// The most triangles a BVH can hold: the packet index field of a leaf
    /// reference, with at worst one packet per triangle.
    pub const MAX_TRIANGLES: usize = LEAF_FIRST_MASK as usize + 1;

    /// Builds over the triangles; slot `i` of every query result is triangle
    /// `order[i]` of `tris`.
    ///
    /// # Panics
    /// With more than [`Bvh::MAX_TRIANGLES`] triangles.
    pub fn build(tris: &[Triangle]) -> Bvh {
        assert!(tris.len() <= Self::MAX_TRIANGLES, "too many triangles for the BVH");
        let mut refs: Vec<PrimRef> = tris
            .par_iter()
            .map(|t| {
                let [a, b, c] = t.vertices().map(Vec3A::from);
                PrimRef {
                    min: a.min(b).min(c),
                    max: a.max(b).max(c),
                }
            })
            .collect();
        let mut ids: Vec<u32> = (0..tris.len() as u32).collect();
        let (bounds, cbounds) = bounds_of(&refs);
        let prims = Prims {
            refs: &mut refs,
            ids: &mut ids,
        };
        let root = match plan_split(prims.refs, &bounds, &cbounds, 0) {
            Some(split) => build_node(prims, 0, bounds, cbounds, split, 0),
            None => BuildNode::Leaf {
                start: 0,
                count: tris.len(),
            },
        };
        // The root is always a node, even over a single leaf.
        let root = match root {
            BuildNode::Leaf { .. } => BuildNode::Inner(vec![(bounds, root)]),
            inner => inner,
        };
        let mut nodes = Vec::with_capacity(tris.len() / 4 + 1);
        let mut packet_slots = Vec::with_capacity(tris.len() / 2 + 1);
        flatten(&root, &mut nodes, &mut packet_slots);
        let packets = packet_slots
            .par_iter()
            .map(|&(first, count)| make_packet(first, count, &ids, tris))
            .collect();
        let order = ids;
        Bvh { nodes, packets, order }
    }

    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for lane in 0..WIDTH {
            if let Some(l) = self.child_bounds(&self.nodes[0], lane) {
                b = b.union(&l);
            }
        }
        b
    }

    fn child_bounds(&self, node: &Node4, lane: usize) -> Option<Aabb> {
        if node.child[lane] == EMPTY_CHILD {
            return None;
        }
        let b = &node.bounds;
        Some(Aabb {
            min: Vec3::new(b[0][0][lane], b[1][0][lane], b[2][0][lane]),
            max: Vec3::new(b[0][1][lane], b[1][1][lane], b[2][1][lane]),
        })
    }

    /// Closest hit in (t_min, t_max): the slot of the triangle and the hit.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(u32, TriHit)> {
        let r = TraversalRay::new(ray, t_min);
        let mut t_max = t_max;
        let mut best: Option<(u32, TriHit)> = None;
        // An ArrayVec starts uninitialised; zeroing a fixed array per ray
        // took a tenth of the traversal time.
        let mut stack: ArrayVec<(u32, f32), STACK> = ArrayVec::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mask, t_near) = r.hit_boxes(node, t_max);
                if mask != 0 {
                    if mask & (mask - 1) == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    // Two or more children: push all but the nearest, farthest first.
                    let t = t_near.to_array();
                    let mut hits = [(0u32, 0.0f32); WIDTH];
                    let mut n = 0;
                    let mut m = mask;
                    while m != 0 {
                        let lane = m.trailing_zeros() as usize;
                        let mut j = n;
                        // Insertion sort, descending by entry distance.
                        while j > 0 && hits[j - 1].1 < t[lane] {
                            hits[j] = hits[j - 1];
                            j -= 1;
                        }
                        hits[j] = (node.child[lane], t[lane]);
                        n += 1;
                        m &= m - 1;
                    }
                    for &h in &hits[..n - 1] {
                        stack.push(h);
                    }
                    cur = hits[n - 1].0;
                    continue;
                }
            } else {
                for p in self.leaf_packets(cur) {
                    if let Some((slot, h)) = r.hit_triangles(p, t_max) {
                        t_max = h.t;
                        best = Some((slot, h));
                    }
                }
            }
            // Pop the next node that can still hold a closer hit.
            loop {
                let Some((n, t_enter)) = stack.pop() else {
                    return best;
                };
                if t_enter <= t_max {
                    cur = n;
                    break;
                }
            }
        }
    }

    /// Whether any triangle blocks the ray in (t_min, t_max).
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        let r = TraversalRay::new(ray, t_min);
        let mut stack: ArrayVec<u32, STACK> = ArrayVec::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mut mask, _) = r.hit_boxes(node, t_max);
                if mask != 0 {
                    cur = node.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    while mask != 0 {
                        stack.push(node.child[mask.trailing_zeros() as usize]);
                        mask &= mask - 1;
                    }
                    continue;
                }
            } else if self.leaf_packets(cur).iter().any(|p| r.hits_any_triangle(p, t_max)) {
                return true;
            }
            match stack.pop() {
                Some(n) => cur = n,
                None => return false,
            }
        }
    }

    #[inline(always)]
    fn leaf_packets(&self, leaf: u32) -> &[Tri4] {
        let first = (leaf & LEAF_FIRST_MASK) as usize;
        let count = ((leaf & !LEAF) >> LEAF_COUNT_SHIFT) as usize;
        &self.packets[first..first + count]
    }

    pub fn stats(&self) -> BvhStats {
        let mut s = BvhStats {
            nodes: self.nodes.len(),
            leaves: 0,
            depth: 0,
            leaf_sizes: vec![0; MAX_LEAF + 1],
            sah_cost: 0.0,
            bytes: self.nodes.len() * std::mem::size_of::<Node4>()
                + self.packets.len() * std::mem::size_of::<Tri4>()
                + self.order.len() * 4,
        };
        let root_area = self.bounds().surface_area().max(f32::MIN_POSITIVE);
        s.sah_cost = TRAVERSAL_COST;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, d)) = stack.pop() {
            let node = &self.nodes[i];
            s.depth = s.depth.max(d);
            for lane in 0..WIDTH {
                let Some(b) = self.child_bounds(node, lane) else {
                    continue;
                };
                let p = b.surface_area() / root_area;
                let c = node.child[lane];
                if c & LEAF == 0 {
                    s.sah_cost += p * TRAVERSAL_COST;
                    stack.push((c as usize, d + 1));
                } else {
                    let packets = self.leaf_packets(c);
                    let tris: usize = packets
                        .iter()
                        .map(|p| p.slot.iter().filter(|&&x| x != u32::MAX).count())
                        .sum();
                    s.leaves += 1;
                    if tris >= s.leaf_sizes.len() {
                        s.leaf_sizes.resize(tris + 1, 0);
                    }
                    s.leaf_sizes[tris] += 1;
                    s.sah_cost += p * INTERSECT_COST * packets.len() as f32;
                }
            }
        }
        s
    }
}

/// A ray prepared for box and packet tests: its origin and direction in all
/// lanes, the reciprocal direction, which box plane is near on each axis,
/// and the origin the near and far planes are measured from.
struct TraversalRay {
    o: [Vec4; 3],
    d: [Vec4; 3],
    inv_d: [Vec4; 3],
    /// Index into `Node4::bounds[axis]` of the near plane: 1 (the maxima) for
    /// a negative direction.
    near: [bool; 3],
    /// The origin for near-plane and far-plane distances. They differ from `o`
    /// only on axes the ray is parallel to (see `new`).
    o_near: [Vec4; 3],
    o_far: [Vec4; 3],
    t_min: Vec4,
}

/// 1 + 2 gamma(3) with gamma(n) = n u / (1 - n u), u = 2^-24 (pbrt-v3, 3.9).
const FAR_WIDEN: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

impl TraversalRay {
    #[inline(always)]
    fn new(ray: &Ray, t_min: f32) -> Self {
        let o = ray.o.to_array();
        let d = ray.d.to_array();
        let mut inv = [0.0; 3];
        let (mut o_near, mut o_far) = (o, o);
        for a in 0..3 {
            if d[a].abs() >= 1e-30 {
                inv[a] = 1.0 / d[a];
            } else {
                // Parallel to the slabs of this axis. 1/0 would make 0 * inf =
                // NaN for a ray lying in a box face, and a finite stand-in alone
                // gives distance 0 there, culling a box the ray runs along. So:
                // a finite stand-in, and the origin moved outwards for each
                // plane by delta (many ulps, and delta * 1e30 beyond any ray
                // length): within the slab, faces included, the near distance
                // is hugely negative and the far one hugely positive; outside
                // it by more than delta the box is culled.
                inv[a] = 1e30f32.copysign(d[a]);
                let delta = o[a].abs() * 1e-6 + 1e-15;
                let (up, down) = (o[a] + delta, o[a] - delta);
                (o_near[a], o_far[a]) = if inv[a] > 0.0 { (up, down) } else { (down, up) };
            }
        }
        TraversalRay {
            o: o.map(Vec4::splat),
            d: d.map(Vec4::splat),
            inv_d: inv.map(Vec4::splat),
            near: inv.map(|x| x < 0.0),
            o_near: o_near.map(Vec4::splat),
            o_far: o_far.map(Vec4::splat),
            t_min: Vec4::splat(t_min),
        }
    }

    /// Which of the four child boxes the ray enters within (t_min, t_max)
    /// (bit i for lane i), and the entry distances.
    #[inline(always)]
    fn hit_boxes(&self, node: &Node4, t_max: f32) -> (u32, Vec4) {
        let b = &node.bounds;
        let slab = |axis: usize| {
            let near = self.near[axis] as usize;
            let t0 = (b[axis][near] - self.o_near[axis]) * self.inv_d[axis];
            let t1 = (b[axis][1 - near] - self.o_far[axis]) * self.inv_d[axis];
            (t0, t1)
        };
        let (nx, fx) = slab(0);
        let (ny, fy) = slab(1);
        let (nz, fz) = slab(2);
        let t_near = nx.max(ny).max(nz.max(self.t_min));
        let t_far = fx.min(fy).min(fz.min(Vec4::splat(t_max))) * FAR_WIDEN;
        (t_near.cmple(t_far).bitmask(), t_near)
    }

    /// Moller-Trumbore on four triangles, each lane computed exactly as
    /// `Triangle::intersect_mt` computes it. Returns per lane whether the ray
    /// hits within (t_min, t_max) and the hit's t, u, v.
    #[inline(always)]
    fn test_packet(&self, p: &Tri4, t_max: f32) -> (BVec4A, Vec4, Vec4, Vec4) {
        let [dx, dy, dz] = self.d;
        let [e1x, e1y, e1z] = p.e1;
        let [e2x, e2y, e2z] = p.e2;
        // p = d x e2
        let px = dy * e2z - e2y * dz;
        let py = dz * e2x - e2z * dx;
        let pz = dx * e2y - e2x * dy;
        let det = (e1x * px) + (e1y * py) + (e1z * pz);
        let inv = Vec4::ONE / det;
        let sx = self.o[0] - p.v0[0];
        let sy = self.o[1] - p.v0[1];
        let sz = self.o[2] - p.v0[2];
        let u = ((sx * px) + (sy * py) + (sz * pz)) * inv;
        // q = s x e1
        let qx = sy * e1z - e1y * sz;
        let qy = sz * e1x - e1z * sx;
        let qz = sx * e1y - e1x * sy;
        let v = ((dx * qx) + (dy * qy) + (dz * qz)) * inv;
        let t = ((e2x * qx) + (e2y * qy) + (e2z * qz)) * inv;
        // Finite and non-zero; `abs < inf` is false for NaN too.
        let det_ok = det.cmpne(Vec4::ZERO) & det.abs().cmplt(Vec4::INFINITY);
        let u_ok = u.cmpge(Vec4::ZERO) & u.cmple(Vec4::ONE);
        // Written as the negation of the scalar test's rejection, so NaNs agree.
        let v_ok = !(v.cmplt(Vec4::ZERO) | (u + v).cmpgt(Vec4::ONE));
        let t_ok = t.cmpgt(self.t_min) & t.cmplt(Vec4::splat(t_max));
        (det_ok & u_ok & v_ok & t_ok, t, u, v)
    }

    /// The nearest hit among a packet's triangles, if any is closer than t_max.
    #[inline(always)]
    fn hit_triangles(&self, p: &Tri4, t_max: f32) -> Option<(u32, TriHit)> {
        let (ok, t, u, v) = self.test_packet(p, t_max);
        if !ok.any() {
            return None;
        }
        let t = Vec4::select(ok, t, Vec4::INFINITY);
        let t_hit = t.min_element();
        // The first lane at the minimum, as a loop in slot order would keep it.
        let lane = t.cmpeq(Vec4::splat(t_hit)).bitmask().trailing_zeros() as usize;
        Some((
            p.slot[lane],
            TriHit {
                t: t_hit,
                u: u.to_array()[lane],
                v: v.to_array()[lane],
            },
        ))
    }

    #[inline(always)]
    fn hits_any_triangle(&self, p: &Tri4, t_max: f32) -> bool {
        self.test_packet(p, t_max).0.any()
    }
}

/// A triangle's bounds during the build (its input index lives beside it,
/// in a separate array, to keep this at 32 bytes).
#[derive(Clone, Copy)]
struct PrimRef {
    min: Vec3A,
    max: Vec3A,
}

impl PrimRef {
    /// Twice the centroid; binning only needs positions relative to each other.
    #[inline(always)]
    fn centroid2(&self) -> Vec3A {
        self.min + self.max
    }
}

/// A range of the build's triangles: bounds and input indices, permuted together.
struct Prims<'a> {
    refs: &'a mut [PrimRef],
    ids: &'a mut [u32],
}

impl<'a> Prims<'a> {
    fn len(&self) -> usize {
        self.refs.len()
    }

    fn split_at(self, mid: usize) -> (Prims<'a>, Prims<'a>) {
        let (rl, rr) = self.refs.split_at_mut(mid);
        let (il, ir) = self.ids.split_at_mut(mid);
        (Prims { refs: rl, ids: il }, Prims { refs: rr, ids: ir })
    }

    fn range(&mut self, start: usize, end: usize) -> Prims<'_> {
        Prims {
            refs: &mut self.refs[start..end],
            ids: &mut self.ids[start..end],
        }
    }
}

/// Bounds of boxes and of their (doubled) centroids, in SIMD registers.
#[derive(Clone, Copy, Debug)]
struct Bounds3 {
    min: Vec3A,
    max: Vec3A,
}

impl Bounds3 {
    const EMPTY: Bounds3 = Bounds3 {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    #[inline(always)]
    fn grow(&mut self, min: Vec3A, max: Vec3A) {
        self.min = self.min.min(min);
        self.max = self.max.max(max);
    }

    #[inline(always)]
    fn union(self, o: Bounds3) -> Bounds3 {
        Bounds3 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Half the surface area (the factor 2 cancels in every SAH ratio).
    #[inline(always)]
    fn half_area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// Bounds of the boxes and of their doubled centroids.
fn bounds_of(refs: &[PrimRef]) -> (Bounds3, Bounds3) {
    let mut b = Bounds3::EMPTY;
    let mut c = Bounds3::EMPTY;
    for p in refs {
        b.grow(p.min, p.max);
        let cp = p.centroid2();
        c.grow(cp, cp);
    }
    (b, c)
}

/// Packets a leaf of `n` triangles needs.
#[inline(always)]
fn blocks(n: u32) -> f32 {
    n.div_ceil(WIDTH as u32) as f32
}

/// How a set of triangles is cut in two.
#[derive(Clone, Copy, Debug)]
enum Split {
    /// Triangles whose centroid falls in a bin below `bin` of `axis` go left.
    Plane {
        axis: usize,
        bin: u32,
        lo: f32,
        scale: f32,
        bins: u32,
    },
    /// The first half by count goes left (coincident centroids, or too deep).
    Half,
}

impl Split {
    /// Reorders the triangles so the left side comes first; returns its size.
    fn partition(&self, prims: &mut Prims) -> usize {
        match *self {
            Split::Plane {
                axis,
                bin,
                lo,
                scale,
                bins,
            } => match axis {
                0 => partition_plane::<0>(prims, bin, lo, scale, bins),
                1 => partition_plane::<1>(prims, bin, lo, scale, bins),
                _ => partition_plane::<2>(prims, bin, lo, scale, bins),
            },
            Split::Half => prims.len() / 2,
        }
    }
}

/// Lomuto partition without a data-dependent branch: the sides are random,
/// so a branch would mispredict half the time. Swapping a right-side element
/// with the first right-side element is harmless, so every element swaps.
fn partition_plane<const AXIS: usize>(prims: &mut Prims, bin: u32, lo: f32, scale: f32, bins: u32) -> usize {
    let mut i = 0;
    for j in 0..prims.len() {
        let left = bin_of(prims.refs[j].centroid2()[AXIS], lo, scale, bins) < bin;
        prims.refs.swap(i, j);
        prims.ids.swap(i, j);
        i += left as usize;
    }
    i
}

#[inline(always)]
fn bin_of(c: f32, lo: f32, scale: f32, bins: u32) -> u32 {
    (((c - lo) * scale) as u32).min(bins - 1)
}

/// Per axis, `N` bins of box bounds and triangle counts.
struct Bins<const N: usize> {
    bounds: [[Bounds3; N]; 3],
    counts: [[u32; N]; 3],
}

impl<const N: usize> Bins<N> {
    fn new() -> Box<Self> {
        Box::new(Bins {
            bounds: [[Bounds3::EMPTY; N]; 3],
            counts: [[0; N]; 3],
        })
    }

    fn fill(mut self: Box<Self>, refs: &[PrimRef], lo: Vec3A, scale: Vec3A) -> Box<Self> {
        let top = Vec3A::splat((N - 1) as f32);
        for p in refs {
            // Same arithmetic as `bin_of`, three axes at once.
            let idx = ((p.centroid2() - lo) * scale).min(top).as_uvec3();
            for axis in 0..3 {
                let i = idx[axis] as usize;
                self.bounds[axis][i].grow(p.min, p.max);
                self.counts[axis][i] += 1;
            }
        }
        self
    }

    fn merge(mut self: Box<Self>, o: &Self) -> Box<Self> {
        for axis in 0..3 {
            for i in 0..N {
                self.bounds[axis][i] = self.bounds[axis][i].union(o.bounds[axis][i]);
                self.counts[axis][i] += o.counts[axis][i];
            }
        }
        self
    }

    /// The cheapest plane: (SAH cost without the constant factors, split).
    fn best_split(&self, cbounds: &Bounds3, scale: Vec3A) -> Option<(f32, Split)> {
        let ext = cbounds.max - cbounds.min;
        let mut best: Option<(f32, Split)> = None;
        for axis in 0..3 {
            if ext[axis] <= 0.0 {
                continue;
            }
            let (bounds, counts) = (&self.bounds[axis], &self.counts[axis]);
            // Sweep from the right for each suffix's area times packets.
            let mut right_cost = [f32::INFINITY; N];
            let mut acc = Bounds3::EMPTY;
            let mut cnt = 0;
            for i in (1..N).rev() {
                acc = acc.union(bounds[i]);
                cnt += counts[i];
                if cnt > 0 {
                    right_cost[i] = acc.half_area() * blocks(cnt);
                }
            }
            let mut acc = Bounds3::EMPTY;
            let mut cnt = 0;
            for i in 0..N - 1 {
                acc = acc.union(bounds[i]);
                cnt += counts[i];
                if cnt == 0 || right_cost[i + 1].is_infinite() {
                    continue;
                }
                let cost = acc.half_area() * blocks(cnt) + right_cost[i + 1];
                if best.is_none_or(|b| cost < b.0) {
                    let split = Split::Plane {
                        axis,
                        bin: i as u32 + 1,
                        lo: cbounds.min[axis],
                        scale: scale[axis],
                        bins: N as u32,
                    };
                    best = Some((cost, split));
                }
            }
        }
        best
    }
}

/// Bins the triangles into `N` bins per axis and finds the cheapest plane.
fn binned_split<const N: usize>(refs: &[PrimRef], cbounds: &Bounds3) -> Option<(f32, Split)> {
    let ext = cbounds.max - cbounds.min;
    // Slightly under N / extent, so the largest centroid lands in bin N - 1.
    let scale = Vec3A::select(
        ext.cmpgt(Vec3A::ZERO),
        Vec3A::splat(N as f32 * 0.999_99) / ext,
        Vec3A::ZERO,
    );
    // Binning is exact whatever the chunking (min, max and integer counts),
    // so parallel binning keeps the build deterministic.
    let bins = if refs.len() > PARALLEL_BINNING {
        refs.par_chunks(PARALLEL_BINNING / 2)
            .map(|c| Bins::<N>::new().fill(c, cbounds.min, scale))
            .reduce(Bins::new, |a, b| a.merge(&b))
    } else {
        Bins::<N>::new().fill(refs, cbounds.min, scale)
    };
    bins.best_split(cbounds, scale)
}

/// The split to make, or `None` when the triangles should stay one leaf.
fn plan_split(refs: &[PrimRef], bounds: &Bounds3, cbounds: &Bounds3, depth: usize) -> Option<Split> {
    let n = refs.len();
    // Up to one packet, a leaf always wins: a split costs a traversal step
    // more and still tests at least one packet on each side.
    if n <= WIDTH {
        return None;
    }
    if depth >= SAH_DEPTH {
        return (n > MAX_LEAF).then_some(Split::Half);
    }
    // Small nodes need fewer bins; clearing and sweeping 32 would dominate.
    let best = match n {
        0..=16 => binned_split::<8>(refs, cbounds),
        17..=64 => binned_split::<16>(refs, cbounds),
        _ => binned_split::<BINS>(refs, cbounds),
    };
    let area = bounds.half_area().max(f32::MIN_POSITIVE);
    match best {
        Some((cost, split)) => {
            let split_cost = TRAVERSAL_COST + INTERSECT_COST * cost / area;
            let leaf_cost = INTERSECT_COST * blocks(n as u32);
            (split_cost < leaf_cost || n > MAX_LEAF).then_some(split)
        }
        // All centroids coincide: only a split by count bounds the leaf size.
        None => (n > MAX_LEAF).then_some(Split::Half),
    }
}

/// The tree as the build makes it, before it is laid out in arrays.
enum BuildNode {
    /// Triangles `start..start + count` of the build order.
    Leaf {
        start: usize,
        count: usize,
    },
    Inner(Vec<(Bounds3, BuildNode)>),
}

/// One child while a node is being filled.
struct Pending {
    start: usize,
    end: usize,
    bounds: Bounds3,
    cbounds: Bounds3,
    split: Option<Split>,
}

/// Builds the node over `prims` (which start at `start` in the build order),
/// whose first cut is `split`.
fn build_node(
    mut prims: Prims,
    start: usize,
    bounds: Bounds3,
    cbounds: Bounds3,
    split: Split,
    depth: usize,
) -> BuildNode {
    let mut children = vec![Pending {
        start: 0,
        end: prims.len(),
        bounds,
        cbounds,
        split: Some(split),
    }];
    // Split the largest child that wants splitting until there are four.
    while children.len() < WIDTH {
        let mut pick: Option<(usize, Split, f32)> = None;
        for (i, c) in children.iter().enumerate() {
            if let Some(split) = c.split {
                let a = c.bounds.half_area();
                if pick.is_none_or(|p| a > p.2) {
                    pick = Some((i, split, a));
                }
            }
        }
        let Some((i, split, _)) = pick else {
            break;
        };
        let (s, e) = (children[i].start, children[i].end);
        let mid = s + split.partition(&mut prims.range(s, e));
        let side = |a: usize, b: usize| {
            let (bounds, cbounds) = bounds_of(&prims.refs[a..b]);
            Pending {
                start: a,
                end: b,
                bounds,
                cbounds,
                split: plan_split(&prims.refs[a..b], &bounds, &cbounds, depth),
            }
        };
        let (left, right) = (side(s, mid), side(mid, e));
        children[i] = left;
        children.insert(i + 1, right);
    }

    // Cut the triangles into the children's disjoint ranges and recurse.
    let n = prims.len();
    let mut parts = Vec::with_capacity(children.len());
    let mut rest = prims;
    let mut offset = 0;
    for c in &children {
        let (part, tail) = rest.split_at(c.end - offset);
        offset = c.end;
        rest = tail;
        parts.push((part, c));
    }
    let build = |(part, c): (Prims, &Pending)| {
        let node = match c.split {
            Some(split) => build_node(part, start + c.start, c.bounds, c.cbounds, split, depth + 1),
            None => BuildNode::Leaf {
                start: start + c.start,
                count: c.end - c.start,
            },
        };
        (c.bounds, node)
    };
    // `collect` keeps the children's order whatever thread builds each.
    let built = if n > PARALLEL_SUBTREE {
        parts.into_par_iter().map(build).collect()
    } else {
        parts.into_iter().map(build).collect()
    };
    BuildNode::Inner(built)
}

/// Lays the tree out depth first; returns the reference to `node`. Leaves
/// only reserve their packets: `packet_slots` gets each packet's first slot
/// and triangle count, and `make_packet` fills it in afterwards, in parallel.
fn flatten(node: &BuildNode, nodes: &mut Vec<Node4>, packet_slots: &mut Vec<(u32, u32)>) -> u32 {
    match node {
        BuildNode::Leaf { start, count } => {
            let first = packet_slots.len() as u32;
            for s in (*start..start + count).step_by(WIDTH) {
                packet_slots.push((s as u32, WIDTH.min(start + count - s) as u32));
            }
            let n = packet_slots.len() as u32 - first;
            LEAF | (n << LEAF_COUNT_SHIFT) | first
        }
        BuildNode::Inner(children) => {
            let idx = nodes.len();
            nodes.push(Node4 {
                bounds: [[Vec4::INFINITY, Vec4::NEG_INFINITY]; 3],
                child: [EMPTY_CHILD; WIDTH],
            });
            for (lane, (b, child)) in children.iter().enumerate() {
                let r = flatten(child, nodes, packet_slots);
                let n = &mut nodes[idx];
                n.child[lane] = r;
                for axis in 0..3 {
                    n.bounds[axis][0][lane] = b.min[axis];
                    n.bounds[axis][1][lane] = b.max[axis];
                }
            }
            idx as u32
        }
    }
}

/// The packet of the `count` triangles from slot `first` on; unused lanes
/// hold a degenerate triangle that no ray hits.
fn make_packet(first: u32, count: u32, ids: &[u32], tris: &[Triangle]) -> Tri4 {
    let mut lanes = [Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO); WIDTH];
    let mut slot = [u32::MAX; WIDTH];
    for lane in 0..count as usize {
        let s = first as usize + lane;
        lanes[lane] = tris[ids[s] as usize];
        slot[lane] = s as u32;
    }
    let gather = |f: fn(&Triangle) -> Vec3| -> [Vec4; 3] {
        let v = lanes.map(|t| f(&t));
        [0, 1, 2].map(|axis| Vec4::new(v[0][axis], v[1][axis], v[2][axis], v[3][axis]))
    };
    Tri4 {
        v0: gather(|t| t.v0),
        e1: gather(|t| t.e1),
        e2: gather(|t| t.e2),
        slot,
    }
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
