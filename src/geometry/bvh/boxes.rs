//! A BVH over bounding boxes, for the analytic shapes (spheres and disks):
//! the triangle BVH's build and box test, with leaves that name primitives
//! instead of holding triangle packets. What a primitive is and how a ray
//! meets it is the caller's: queries take a closure that tests primitive `id`
//! (its index in the boxes given to `build`).
//!
//! Up to four boxes make no tree: queries test them in input order, as a loop
//! over them would.

use super::build::{build_tree, PrimRef};
use super::traverse::{TraversalRay, STACK};
use super::{Node4, LEAF, LEAF_COUNT_SHIFT, LEAF_FIRST_MASK, WIDTH};
use crate::math::{Aabb, Ray};
use arrayvec::ArrayVec;
use glam::Vec3A;

/// The tree over a set of boxes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BoxBvh {
    /// `nodes[0]` is the root; empty for four boxes or fewer.
    nodes: Vec<Node4>,
    /// The leaves' packets: first slot and number of slots (up to four).
    packets: Vec<(u32, u32)>,
    /// `order[slot]` is the input index of the box at `slot`.
    order: Vec<u32>,
}

/// Relative widening of every box, so that a shape test's rounding never
/// puts a hit outside its box (2^-18: a few ulps at any magnitude).
const PAD: f32 = 1.0 / 262_144.0;

impl BoxBvh {
    /// The most boxes a tree can hold: the packet index field of a leaf
    /// reference, with at worst one packet per box.
    pub const MAX_BOXES: usize = LEAF_FIRST_MASK as usize + 1;

    /// Builds over the boxes, which must be finite. Each is first widened by
    /// a relative 2^-18 of its size and distance from the origin.
    ///
    /// # Panics
    /// With more than [`BoxBvh::MAX_BOXES`] boxes.
    pub fn build(boxes: &[Aabb]) -> BoxBvh {
        assert!(boxes.len() <= Self::MAX_BOXES, "too many boxes for the BVH");
        if boxes.len() <= WIDTH {
            return BoxBvh {
                nodes: vec![],
                packets: vec![],
                order: (0..boxes.len() as u32).collect(),
            };
        }
        let refs = boxes
            .iter()
            .map(|b| {
                let m = b.min.abs().max(b.max.abs()).max_element() + b.extent().max_element();
                let pad = Vec3A::splat(m * PAD);
                PrimRef {
                    min: Vec3A::from(b.min) - pad,
                    max: Vec3A::from(b.max) + pad,
                }
            })
            .collect();
        // Shapes are tested one at a time: the SAH counts each.
        let tree = build_tree::<1, WIDTH, Node4>(refs);
        BoxBvh {
            nodes: tree.nodes,
            packets: tree.packet_slots,
            order: tree.ids,
        }
    }

    /// Number of boxes.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Number of tree nodes (0 for four boxes or fewer).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The input indices of a leaf's boxes.
    #[inline(always)]
    fn leaf(&self, leaf: u32) -> impl Iterator<Item = u32> + '_ {
        let first = (leaf & LEAF_FIRST_MASK) as usize;
        let count = ((leaf & !LEAF) >> LEAF_COUNT_SHIFT) as usize;
        self.packets[first..first + count]
            .iter()
            .flat_map(move |&(s, n)| self.order[s as usize..(s + n) as usize].iter().copied())
    }

    /// Closest hit in (t_min, t_max): `hit(id, t)` tests primitive `id` and
    /// returns its hit distance if it is in (t_min, t). Returns the id and
    /// distance of the closest; among exactly equal distances, the first found.
    #[inline]
    pub fn intersect<F>(&self, ray: &Ray, t_min: f32, t_max: f32, mut hit: F) -> Option<(u32, f32)>
    where
        F: FnMut(u32, f32) -> Option<f32>,
    {
        let mut t_max = t_max;
        let mut best = None;
        if self.nodes.is_empty() {
            for &id in &self.order {
                if let Some(t) = hit(id, t_max) {
                    t_max = t;
                    best = Some((id, t));
                }
            }
            return best;
        }
        let r = TraversalRay::new(ray, t_min);
        let mut stack: ArrayVec<(u32, f32), STACK> = ArrayVec::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mask, t_near) = r.hit_boxes(&node.bounds, t_max);
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
                for id in self.leaf(cur) {
                    if let Some(t) = hit(id, t_max) {
                        t_max = t;
                        best = Some((id, t));
                    }
                }
            }
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

    /// Whether any primitive blocks the ray in (t_min, t_max): `blocks(id)`
    /// tests primitive `id` over that segment. Stops at the first blocker.
    #[inline]
    pub fn occluded<F>(&self, ray: &Ray, t_min: f32, t_max: f32, mut blocks: F) -> bool
    where
        F: FnMut(u32) -> bool,
    {
        if self.nodes.is_empty() {
            return self.order.iter().any(|&id| blocks(id));
        }
        let r = TraversalRay::new(ray, t_min);
        let mut stack: ArrayVec<u32, STACK> = ArrayVec::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mut mask, _) = r.hit_boxes(&node.bounds, t_max);
                if mask != 0 {
                    cur = node.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    while mask != 0 {
                        stack.push(node.child[mask.trailing_zeros() as usize]);
                        mask &= mask - 1;
                    }
                    continue;
                }
            } else if self.leaf(cur).any(&mut blocks) {
                return true;
            }
            match stack.pop() {
                Some(n) => cur = n,
                None => return false,
            }
        }
    }
}
