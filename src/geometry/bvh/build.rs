//! The BVH build, apart from traversal so that tuning it (bins, split rules,
//! parallelism) never touches the render's hot loop; the two agree only on
//! the layout declared in `mod.rs`.
//!
//! Build: top-down binned SAH (Wald 2007, "On fast Construction of SAH-based
//! Bounding Volume Hierarchies"). Each node starts as one child holding all
//! its triangles and splits, by the best binned SAH plane, the child of
//! largest surface area until it has eight (four for `BoxBvh`), as Embree's
//! wide builders do (Wald et al. 2014, "Embree: A Kernel Framework for
//! Efficient CPU Ray Tracing").
//! Leaf cost counts blocks of four triangles, since a leaf is tested four
//! triangles at a time. Whether a set of up to `MAX_LEAF` triangles becomes
//! a leaf is decided bottom-up, against the SAH cost of the subtree built
//! below it (the SAH leaf collapsing of Karras and Aila 2013, "Fast Parallel
//! Construction of High-Quality Bounding Volume Hierarchies"), not from one
//! cut's estimate.
//! Big subtrees build in parallel (`rayon`) and big nodes
//! bin in parallel; every decision depends only on the input, so the tree is
//! the same for any number of threads.

use super::{
    Bvh, Node4, Node8, Tri4, EMPTY_CHILD, INTERSECT_COST, LEAF, LEAF_COUNT_SHIFT, MAX_LEAF, NODE_WIDTH, SAH_DEPTH,
    TRAVERSAL_COST, WIDTH,
};
use crate::geometry::triangle::Triangle;
use crate::math::Vec3;
use arrayvec::ArrayVec;
use glam::{Vec3A, Vec4};
use rayon::prelude::*;

/// SAH bins per axis.
const BINS: usize = 32;
/// Subtrees with more triangles than this build on their own rayon task.
const PARALLEL_SUBTREE: usize = 4096;
/// Nodes with more triangles than this bin in parallel chunks of this size.
const PARALLEL_BINNING: usize = 16384;

impl Bvh {
    /// Builds over the triangles; slot `i` of every query result is triangle
    /// `order[i]` of `tris`.
    ///
    /// # Panics
    /// With more than [`Bvh::MAX_TRIANGLES`] triangles.
    pub fn build(tris: &[Triangle]) -> Bvh {
        assert!(tris.len() <= Self::MAX_TRIANGLES, "too many triangles for the BVH");
        let refs: Vec<PrimRef> = tris
            .par_iter()
            .map(|t| {
                let [a, b, c] = t.vertices().map(Vec3A::from);
                PrimRef {
                    min: a.min(b).min(c),
                    max: a.max(b).max(c),
                }
            })
            .collect();
        let tree = build_tree::<{ WIDTH as u32 }, NODE_WIDTH, Node8>(refs);
        let ids = tree.ids;
        let packets = tree
            .packet_slots
            .par_iter()
            .map(|&(first, count)| make_packet(first, count, &ids, tris))
            .collect();
        let order = ids;
        Bvh {
            nodes: tree.nodes,
            packets,
            order,
        }
    }
}

/// A tree over boxes, before its leaves are filled: the nodes, each leaf
/// packet's first slot and size (a leaf reference numbers its packets), and
/// the input index of the primitive at each slot.
pub(super) struct Tree<N> {
    pub(super) nodes: Vec<N>,
    pub(super) packet_slots: Vec<(u32, u32)>,
    pub(super) ids: Vec<u32>,
}

/// Builds the tree over the primitives' boxes, in nodes of up to `W`
/// children laid out as `N`; the triangle BVH and the BVH of analytic shapes
/// (`BoxBvh`) share it. `P` is how many primitives a leaf tests at once, for
/// the SAH's leaf cost: 4 for triangle packets, 1 for shapes tested one by
/// one.
pub(super) fn build_tree<const P: u32, const W: usize, N: FlatNode>(mut refs: Vec<PrimRef>) -> Tree<N> {
    let n = refs.len();
    let mut ids: Vec<u32> = (0..n as u32).collect();
    let (bounds, cbounds) = bounds_of(&refs);
    let prims = Prims {
        refs: &mut refs,
        ids: &mut ids,
    };
    let root = match plan_split::<P>(prims.refs, &cbounds, 0) {
        Some(split) => build_node::<P, W>(prims, 0, bounds, cbounds, split, 0),
        None => BuildNode::Leaf { start: 0, count: n },
    };
    // The root is always a node, even over a single leaf.
    let root = match root {
        BuildNode::Leaf { .. } => BuildNode::Inner(vec![(bounds, root)]),
        inner => inner,
    };
    let mut nodes = Vec::with_capacity(n / W + 1);
    let mut packet_slots = Vec::with_capacity(n / 2 + 1);
    flatten(&root, &mut nodes, &mut packet_slots);
    Tree {
        nodes,
        packet_slots,
        ids,
    }
}

/// A node layout the build fills: an empty node, and one child's reference
/// and box put in a lane.
pub(super) trait FlatNode {
    const EMPTY: Self;
    fn set(&mut self, lane: usize, child: u32, b: &Bounds3);
}

impl FlatNode for Node4 {
    const EMPTY: Self = Node4 {
        bounds: [[Vec4::INFINITY, Vec4::NEG_INFINITY]; 3],
        child: [EMPTY_CHILD; WIDTH],
    };

    fn set(&mut self, lane: usize, child: u32, b: &Bounds3) {
        self.child[lane] = child;
        for axis in 0..3 {
            self.bounds[axis][0][lane] = b.min[axis];
            self.bounds[axis][1][lane] = b.max[axis];
        }
    }
}

impl FlatNode for Node8 {
    const EMPTY: Self = Node8 {
        bounds: [[[Vec4::INFINITY; 2], [Vec4::NEG_INFINITY; 2]]; 3],
        child: [EMPTY_CHILD; NODE_WIDTH],
    };

    fn set(&mut self, lane: usize, child: u32, b: &Bounds3) {
        self.child[lane] = child;
        for axis in 0..3 {
            self.bounds[axis][0][lane / WIDTH][lane % WIDTH] = b.min[axis];
            self.bounds[axis][1][lane / WIDTH][lane % WIDTH] = b.max[axis];
        }
    }
}

/// A primitive's bounds during the build (its input index lives beside it,
/// in a separate array, to keep this at 32 bytes).
#[derive(Clone, Copy)]
pub(super) struct PrimRef {
    pub(super) min: Vec3A,
    pub(super) max: Vec3A,
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

    /// Stable insertion sort by `key` (sets of a few only), ids moving with
    /// their boxes.
    fn sort_small_by<K: PartialOrd>(&mut self, key: impl Fn(&PrimRef) -> K) {
        for i in 1..self.len() {
            let mut j = i;
            while j > 0 && key(&self.refs[j - 1]) > key(&self.refs[j]) {
                self.refs.swap(j - 1, j);
                self.ids.swap(j - 1, j);
                j -= 1;
            }
        }
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
pub(super) struct Bounds3 {
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

/// Tests (packets of `P`) a leaf of `n` primitives needs.
#[inline(always)]
fn blocks<const P: u32>(n: u32) -> f32 {
    n.div_ceil(P) as f32
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
    /// At most one packet's worth, not yet binned: most such sets become a
    /// leaf or a node of single-triangle leaves without ever being cut
    /// (`small_node`); the plane is found only if a node's filling cuts it.
    Lazy,
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
            // `build_node` resolves a lazy split before cutting with it.
            Split::Half | Split::Lazy => prims.len() / 2,
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
    fn best_split<const P: u32>(&self, cbounds: &Bounds3, scale: Vec3A) -> Option<(f32, Split)> {
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
                    right_cost[i] = acc.half_area() * blocks::<P>(cnt);
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
                let cost = acc.half_area() * blocks::<P>(cnt) + right_cost[i + 1];
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
fn binned_split<const N: usize, const P: u32>(refs: &[PrimRef], cbounds: &Bounds3) -> Option<(f32, Split)> {
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
    bins.best_split::<P>(cbounds, scale)
}

/// The cut to make, or `None` when the triangles can only be one leaf. Every
/// set of two or more that has a cut is cut: whether a small node stays a
/// node is decided once its subtree is built (`build_node`), from the
/// subtree's actual SAH cost. One cut's estimate sees only the next level,
/// and a few big triangles whose boxes overlap (a room's walls) need two or
/// three levels before their boxes come apart; nor does a packet of up to
/// four triangles always beat a node, since a node's children are each
/// tested only when the ray enters their box.
fn plan_split<const P: u32>(refs: &[PrimRef], cbounds: &Bounds3, depth: usize) -> Option<Split> {
    let n = refs.len();
    if n <= 1 {
        return None;
    }
    if n <= WIDTH {
        return Some(Split::Lazy);
    }
    if depth >= SAH_DEPTH {
        return (n > MAX_LEAF).then_some(Split::Half);
    }
    // Small nodes need fewer bins; clearing and sweeping 32 would dominate.
    let best = match n {
        0..=16 => binned_split::<8, P>(refs, cbounds),
        17..=64 => binned_split::<16, P>(refs, cbounds),
        _ => binned_split::<BINS, P>(refs, cbounds),
    };
    match best {
        Some((_, split)) => Some(split),
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
fn build_node<const P: u32, const W: usize>(
    mut prims: Prims,
    start: usize,
    bounds: Bounds3,
    cbounds: Bounds3,
    split: Split,
    depth: usize,
) -> BuildNode {
    // On the stack: most nodes are small, and a heap vector each cost more
    // than their binning.
    let mut children: ArrayVec<Pending, NODE_WIDTH> = ArrayVec::new();
    children.push(Pending {
        start: 0,
        end: prims.len(),
        bounds,
        cbounds,
        split: Some(split),
    });
    // Split the largest child that wants splitting until there are W.
    while children.len() < W {
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
        let mid = match split {
            Split::Lazy => match small_split::<P>(&mut prims.range(s, e)) {
                Some(k) => s + k,
                // Coincident centroids: no plane, and no point cutting by count.
                None => {
                    children[i].split = None;
                    continue;
                }
            },
            split => s + split.partition(&mut prims.range(s, e)),
        };
        let side = |a: usize, b: usize| {
            let (bounds, cbounds) = bounds_of(&prims.refs[a..b]);
            Pending {
                start: a,
                end: b,
                bounds,
                cbounds,
                split: plan_split::<P>(&prims.refs[a..b], &cbounds, depth),
            }
        };
        let (left, right) = (side(s, mid), side(mid, e));
        children[i] = left;
        children.insert(i + 1, right);
    }

    // Cut the triangles into the children's disjoint ranges and recurse.
    let n = prims.len();
    let mut parts: ArrayVec<(Prims, &Pending), NODE_WIDTH> = ArrayVec::new();
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
            Some(_) if part.len() <= WIDTH => small_node::<P>(part, start + c.start, &c.bounds),
            Some(split) => build_node::<P, W>(part, start + c.start, c.bounds, c.cbounds, split, depth + 1),
            None => BuildNode::Leaf {
                start: start + c.start,
                count: c.end - c.start,
            },
        };
        (c.bounds, node)
    };
    // `collect` keeps the children's order whatever thread builds each.
    let built = if n > PARALLEL_SUBTREE {
        parts
            .into_iter()
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(build)
            .collect()
    } else {
        parts.into_iter().map(build).collect()
    };
    let node = BuildNode::Inner(built);
    // Bottom-up collapse: one leaf if that costs no more than the subtree.
    if n <= MAX_LEAF && INTERSECT_COST * blocks::<P>(n as u32) * bounds.half_area() <= node.sah::<P>(&bounds) {
        return BuildNode::Leaf { start, count: n };
    }
    node
}

/// The SAH's best cut of a set of at most one packet's worth, over every
/// position between distinct centroids on each axis (for so few, cheaper
/// than binning): reorders the set along that axis and returns the size of
/// the first side, or `None` if all centroids coincide.
fn small_split<const P: u32>(prims: &mut Prims) -> Option<usize> {
    let n = prims.len();
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        let mut order = [0usize; WIDTH];
        for (i, o) in order.iter_mut().enumerate().take(n) {
            *o = i;
        }
        let c = |i: usize| prims.refs[i].centroid2()[axis];
        order[..n].sort_unstable_by(|&a, &b| c(a).total_cmp(&c(b)).then(a.cmp(&b)));
        let mut suffix = [Bounds3::EMPTY; WIDTH];
        let mut acc = Bounds3::EMPTY;
        for k in (1..n).rev() {
            let r = &prims.refs[order[k]];
            acc.grow(r.min, r.max);
            suffix[k] = acc;
        }
        let mut acc = Bounds3::EMPTY;
        for k in 1..n {
            let r = &prims.refs[order[k - 1]];
            acc.grow(r.min, r.max);
            if c(order[k - 1]) == c(order[k]) {
                continue;
            }
            let cost = acc.half_area() * blocks::<P>(k as u32) + suffix[k].half_area() * blocks::<P>((n - k) as u32);
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, k));
            }
        }
    }
    let (_, axis, k) = best?;
    prims.sort_small_by(|r| r.centroid2()[axis]);
    Some(k)
}

/// A set of at most one packet's worth: one leaf, or a node with a leaf for
/// each group of primitives whose centroids coincide (the two halves of a
/// quad; no plane separates them), whichever the SAH finds cheaper. Cutting
/// the set by planes first would end in the same node.
fn small_node<const P: u32>(mut prims: Prims, start: usize, bounds: &Bounds3) -> BuildNode {
    let n = prims.len();
    // Sorted by centroid, so that coincident ones are neighbours.
    let key = |r: &PrimRef| r.centroid2().to_array();
    prims.sort_small_by(key);
    let mut children: Vec<(Bounds3, BuildNode)> = Vec::with_capacity(n);
    let mut first = 0;
    for i in 1..=n {
        if i == n || key(&prims.refs[i]) != key(&prims.refs[first]) {
            let (b, _) = bounds_of(&prims.refs[first..i]);
            let leaf = BuildNode::Leaf {
                start: start + first,
                count: i - first,
            };
            children.push((b, leaf));
            first = i;
        }
    }
    let node = BuildNode::Inner(children);
    if INTERSECT_COST * blocks::<P>(n as u32) * bounds.half_area() <= node.sah::<P>(bounds) {
        BuildNode::Leaf { start, count: n }
    } else {
        node
    }
}

impl BuildNode {
    /// SAH cost of the subtree in units of half area (not yet divided by the
    /// root's): each node visit and leaf test weighted by its box's area.
    fn sah<const P: u32>(&self, bounds: &Bounds3) -> f32 {
        match self {
            BuildNode::Leaf { count, .. } => INTERSECT_COST * blocks::<P>(*count as u32) * bounds.half_area(),
            BuildNode::Inner(children) => {
                TRAVERSAL_COST * bounds.half_area() + children.iter().map(|(b, c)| c.sah::<P>(b)).sum::<f32>()
            }
        }
    }
}

/// Lays the tree out depth first; returns the reference to `node`. Leaves
/// only reserve their packets: `packet_slots` gets each packet's first slot
/// and triangle count, and `make_packet` fills it in afterwards, in parallel.
fn flatten<N: FlatNode>(node: &BuildNode, nodes: &mut Vec<N>, packet_slots: &mut Vec<(u32, u32)>) -> u32 {
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
            nodes.push(N::EMPTY);
            for (lane, (b, child)) in children.iter().enumerate() {
                let r = flatten(child, nodes, packet_slots);
                nodes[idx].set(lane, r, b);
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
