//! Bounding volume hierarchy over triangles: an eight-wide BVH (a BVH8, as
//! Embree's on CPUs with AVX) whose leaves hold packets of four triangles.
//!
//! The build (`build`) and the traversal (`traverse`) share nothing but the
//! layout declared here: the nodes, the triangle packets, and how a child
//! reference encodes a leaf. They live apart because they change for different
//! reasons: the build trades build time against tree quality, the traversal is
//! the render's innermost loop and must agree bit for bit with
//! `Triangle::intersect_mt`; either can be read, tuned and tested alone.
//!
//! `BoxBvh` (in `boxes`) is the same build over bounding boxes, for the
//! analytic shapes, with four-wide nodes: it shares the build and the box
//! test, not the leaves.

mod boxes;
mod build;
mod traverse;

#[cfg(test)]
mod tests;

use crate::math::{Aabb, Vec3};
use glam::Vec4;

pub use boxes::BoxBvh;

/// Triangles of one leaf packet, SSE lanes of a box test, and children of a
/// `BoxBvh` node.
const WIDTH: usize = 4;
/// Children of one node of the triangle BVH.
const NODE_WIDTH: usize = 8;
/// Most triangles in one leaf (four packets).
const MAX_LEAF: usize = 16;
/// SAH cost of visiting a node relative to testing one packet of triangles:
/// pbrt-v4's ratio of a node to a primitive (1/2), a node's four boxes and a
/// packet's four triangles each being one SIMD test. A node's box test here
/// is about 20 vector operations and a packet's triangle test about 60, but a
/// node also orders and stacks its children. It was 1 until the build
/// collapsed leaves bottom-up (see BENCHMARKS.md for both).
const TRAVERSAL_COST: f32 = 0.5;
const INTERSECT_COST: f32 = 1.0;
/// Below this node depth splits follow the SAH; deeper ones (only pathological
/// inputs get there) halve by count, which bounds the depth and so the stack.
const SAH_DEPTH: usize = 40;

/// A child reference: a node index, or (top bit set) a leaf given by its
/// first packet and its packet count.
const LEAF: u32 = 1 << 31;
const LEAF_COUNT_SHIFT: u32 = 27;
const LEAF_FIRST_MASK: u32 = (1 << LEAF_COUNT_SHIFT) - 1;
/// Unused child lanes: a leaf of no packets behind an empty box.
const EMPTY_CHILD: u32 = LEAF;

/// One node of a `BoxBvh`: the boxes of its four children, lane by lane,
/// and their references.
/// Aligned to a cache line so that a node spans exactly two.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
struct Node4 {
    /// `bounds[axis][0]` holds the children's minima along `axis`, `[1]` the maxima.
    bounds: [[Vec4; 2]; 3],
    child: [u32; WIDTH],
}

/// One node of the traversed tree: the boxes of its eight children, lane
/// by lane, and their references. The eight minima (or maxima) along an axis
/// are contiguous, so AVX tests them at once and SSE as two halves. Aligned
/// to cache lines (four of them).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
struct Node8 {
    /// `bounds[axis][0][half]` holds the minima along `axis` of children
    /// 4 * half .. 4 * half + 4, `[1]` their maxima.
    bounds: [[[Vec4; 2]; 2]; 3],
    child: [u32; NODE_WIDTH],
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
    nodes: Vec<Node8>,
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

    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for lane in 0..NODE_WIDTH {
            if let Some(l) = self.child_bounds(&self.nodes[0], lane) {
                b = b.union(&l);
            }
        }
        b
    }

    fn child_bounds(&self, node: &Node8, lane: usize) -> Option<Aabb> {
        if node.child[lane] == EMPTY_CHILD {
            return None;
        }
        let (b, h, l) = (&node.bounds, lane / WIDTH, lane % WIDTH);
        Some(Aabb {
            min: Vec3::new(b[0][0][h][l], b[1][0][h][l], b[2][0][h][l]),
            max: Vec3::new(b[0][1][h][l], b[1][1][h][l], b[2][1][h][l]),
        })
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
            bytes: self.nodes.len() * std::mem::size_of::<Node8>()
                + self.packets.len() * std::mem::size_of::<Tri4>()
                + self.order.len() * 4,
        };
        let root_area = self.bounds().surface_area().max(f32::MIN_POSITIVE);
        s.sah_cost = TRAVERSAL_COST;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, d)) = stack.pop() {
            let node = &self.nodes[i];
            s.depth = s.depth.max(d);
            for lane in 0..NODE_WIDTH {
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
