//! Ray queries against a built BVH: the render's innermost loop, apart from
//! the build so that its exactness (every hit bit for bit as a loop over all
//! triangles would find it) can be read and checked on its own.
//!
//! Traversal tests a ray against the eight child boxes of a node at once: in
//! one AVX register where the CPU has AVX (chosen at run time, as Embree
//! chooses its kernels; the build targets baseline x86-64), else as two SSE
//! halves (glam's `Vec4`), with the same operations lane by lane, so that
//! both give the same bits. The near and far planes are chosen by the sign
//! of the direction. Closest-hit queries visit the
//! nearest child first and skip stacked nodes farther than the closest hit so
//! far; `occluded` tests a node's leaf children before it descends and stops
//! at the first blocker. The far distance of every box
//! is widened by 1 + 2 gamma(3) (Ize 2013, "Robust BVH Ray Traversal"), so
//! rounding never culls a box the ray touches; rays parallel to an axis, even
//! lying in a box face, are handled exactly (see `TraversalRay::new`). Leaves
//! test four triangles at once with exactly the arithmetic of
//! `Triangle::intersect_mt`, so a query returns bit for bit what a loop over
//! all triangles would (but for the test's spurious hits far off a triangle
//! for rays almost in its plane, which the boxes rightly cull).

use super::{Bvh, Node8, Tri4, LEAF, NODE_WIDTH, SAH_DEPTH, WIDTH};
use crate::geometry::triangle::TriHit;
use crate::math::Ray;
use arrayvec::ArrayVec;
use glam::{BVec4A, Vec4};

/// Traversal stack entries: at most seven pushes per level of a tree at most
/// SAH_DEPTH + 32 levels deep (below SAH_DEPTH the build halves by count, and
/// a BVH holds fewer than 2^32 triangles).
pub(super) const STACK: usize = (NODE_WIDTH - 1) * (SAH_DEPTH + 32) + 1;

/// Which of the triangles a ray meets count as hits: all of them, or those
/// a test accepts (a surface cut out by an alpha texture lets rays through).
/// Monomorphised, so that the query without a test pays nothing for it.
trait Accept {
    const ALL: bool;
    fn accept(&self, slot: u32, hit: &TriHit) -> bool;
}

/// Every hit counts.
struct All;

impl Accept for All {
    const ALL: bool = true;
    #[inline(always)]
    fn accept(&self, _: u32, _: &TriHit) -> bool {
        true
    }
}

/// The hits `.0` accepts, given the triangle's slot and the hit.
struct Where<F>(F);

impl<F: Fn(u32, &TriHit) -> bool> Accept for Where<F> {
    const ALL: bool = false;
    #[inline(always)]
    fn accept(&self, slot: u32, hit: &TriHit) -> bool {
        (self.0)(slot, hit)
    }
}

/// A closest-hit query's answer as it leaves the traversal: the triangle's
/// slot (`NO_HIT` for none) and the hit's distance and barycentrics, packed
/// into one `u128`, which comes back in two registers. Returned through
/// memory as an `Option<(u32, TriHit)>`, it was stored field by field and
/// read back with wider loads, which the processor cannot forward from the
/// stores: the caller waited for them to reach the cache, on every query.
#[derive(Clone, Copy)]
struct Closest(u128);

const NO_HIT: u32 = u32::MAX;

impl Closest {
    const NONE: Closest = Closest(NO_HIT as u128);

    #[inline(always)]
    fn new(slot: u32, h: TriHit) -> Closest {
        let [t, u, v] = [h.t, h.u, h.v].map(|x| x.to_bits() as u128);
        Closest(slot as u128 | t << 32 | u << 64 | v << 96)
    }

    #[inline(always)]
    fn found(self) -> Option<(u32, TriHit)> {
        let slot = self.0 as u32;
        let f = |k: u32| f32::from_bits((self.0 >> (32 * k)) as u32);
        (slot != NO_HIT).then(|| {
            (
                slot,
                TriHit {
                    t: f(1),
                    u: f(2),
                    v: f(3),
                },
            )
        })
    }
}

impl Bvh {
    /// Closest hit in (t_min, t_max): the slot of the triangle and the hit.
    /// Where the CPU has AVX, nodes test their eight boxes at once; the
    /// result is the same bit for bit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(u32, TriHit)> {
        self.closest_dispatch(ray, t_min, t_max, &All).found()
    }

    /// The closest hit in (t_min, t_max) that `accept` accepts (given the
    /// triangle's slot and the hit): what a loop over all triangles keeping
    /// the nearest accepted hit finds. Hits are offered in no particular
    /// order, some that a nearer accepted hit hides among them.
    #[inline]
    pub fn intersect_where(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        accept: impl Fn(u32, &TriHit) -> bool,
    ) -> Option<(u32, TriHit)> {
        self.closest_dispatch(ray, t_min, t_max, &Where(accept)).found()
    }

    #[inline(always)]
    fn closest_dispatch<A: Accept>(&self, ray: &Ray, t_min: f32, t_max: f32, accept: &A) -> Closest {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX.
            return unsafe { self.intersect_avx(ray, t_min, t_max, accept) };
        }
        self.intersect_sse(ray, t_min, t_max, accept)
    }

    #[inline(never)]
    fn intersect_sse<A: Accept>(&self, ray: &Ray, t_min: f32, t_max: f32, accept: &A) -> Closest {
        self.closest::<Sse, A>(ray, t_min, t_max, accept)
    }

    /// [`Bvh::intersect`] with nodes tested four boxes at a time (SSE2, every
    /// x86-64 CPU's), whatever the CPU: for checking that both agree.
    pub fn intersect_baseline(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(u32, TriHit)> {
        self.closest::<Sse, All>(ray, t_min, t_max, &All).found()
    }

    /// Whether any triangle blocks the ray in (t_min, t_max); AVX as in
    /// [`Bvh::intersect`].
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.any_hit_dispatch(ray, t_min, t_max, &All)
    }

    /// Whether a hit in (t_min, t_max) that `accept` accepts blocks the ray.
    pub fn occluded_where(&self, ray: &Ray, t_min: f32, t_max: f32, accept: impl Fn(u32, &TriHit) -> bool) -> bool {
        self.any_hit_dispatch(ray, t_min, t_max, &Where(accept))
    }

    #[inline(always)]
    fn any_hit_dispatch<A: Accept>(&self, ray: &Ray, t_min: f32, t_max: f32, accept: &A) -> bool {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX.
            return unsafe { self.occluded_avx(ray, t_min, t_max, accept) };
        }
        self.any_hit::<Sse, A>(ray, t_min, t_max, accept)
    }

    /// [`Bvh::occluded`] without AVX, as [`Bvh::intersect_baseline`].
    pub fn occluded_baseline(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.any_hit::<Sse, All>(ray, t_min, t_max, &All)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn intersect_avx<A: Accept>(&self, ray: &Ray, t_min: f32, t_max: f32, accept: &A) -> Closest {
        self.closest::<Avx, A>(ray, t_min, t_max, accept)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn occluded_avx<A: Accept>(&self, ray: &Ray, t_min: f32, t_max: f32, accept: &A) -> bool {
        self.any_hit::<Avx, A>(ray, t_min, t_max, accept)
    }

    #[inline(always)]
    fn closest<B: BoxTest, A: Accept>(&self, ray: &Ray, t_min: f32, t_max: f32, accept: &A) -> Closest {
        let r = TraversalRay::new(ray, t_min);
        let mut t_max = t_max;
        let mut best = Closest::NONE;
        // An ArrayVec starts uninitialised; zeroing a fixed array per ray
        // took a tenth of the traversal time.
        let mut stack: ArrayVec<(u32, f32), STACK> = ArrayVec::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mask, t_near) = B::hit_boxes8(&r, node, t_max);
                if mask != 0 {
                    if mask & (mask - 1) == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    let t = t_near;
                    let a = mask.trailing_zeros() as usize;
                    let rest = mask & (mask - 1);
                    if rest & (rest - 1) == 0 {
                        // Two children, the most common case: the nearer first;
                        // on a tie the higher lane, as the sort below orders them.
                        let b = rest.trailing_zeros() as usize;
                        let (near, far) = if t[a] < t[b] { (a, b) } else { (b, a) };
                        stack.push((node.child[far], t[far]));
                        cur = node.child[near];
                        continue;
                    }
                    // Three or more children: push all but the nearest, farthest first.
                    let mut hits = [(0u32, 0.0f32); NODE_WIDTH];
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
                    if A::ALL {
                        if let Some((slot, hit)) = r.hit_triangles(p, t_max) {
                            t_max = hit.t;
                            best = Closest::new(slot, hit);
                        }
                    } else if let Some((slot, hit)) = r.hit_accepted_triangles(p, t_max, accept) {
                        t_max = hit.t;
                        best = Closest::new(slot, hit);
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

    #[inline(always)]
    fn any_hit<B: BoxTest, A: Accept>(&self, ray: &Ray, t_min: f32, t_max: f32, accept: &A) -> bool {
        let r = TraversalRay::new(ray, t_min);
        let mut stack: ArrayVec<u32, STACK> = ArrayVec::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mut mask, _) = B::hit_boxes8(&r, node, t_max);
                // Leaf children first: their packets may end the query before
                // another node is loaded. Inner children go on the stack.
                while mask != 0 {
                    let c = node.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    if c & LEAF == 0 {
                        stack.push(c);
                    } else if self
                        .leaf_packets(c)
                        .iter()
                        .any(|p| r.hits_any_triangle(p, t_max, accept))
                    {
                        return true;
                    }
                }
            } else if self
                .leaf_packets(cur)
                .iter()
                .any(|p| r.hits_any_triangle(p, t_max, accept))
            {
                return true;
            }
            match stack.pop() {
                Some(n) => cur = n,
                None => return false,
            }
        }
    }
}

/// How a node's eight boxes are tested: the traversal loops are written once
/// and compiled for each.
trait BoxTest {
    /// Which of the node's children the ray enters within (t_min, t_max)
    /// (bit i for lane i), and the entry distances. Every lane is computed
    /// with the same operations in the same order by each implementation, so
    /// all agree bit for bit.
    fn hit_boxes8(r: &TraversalRay, node: &Node8, t_max: f32) -> (u32, [f32; NODE_WIDTH]);
}

/// Two groups of four lanes (SSE2).
struct Sse;

impl BoxTest for Sse {
    #[inline(always)]
    fn hit_boxes8(r: &TraversalRay, node: &Node8, t_max: f32) -> (u32, [f32; NODE_WIDTH]) {
        let b = &node.bounds;
        let (m0, t0) = r.slabs(|axis, side| b[axis][side][0], t_max);
        let (m1, t1) = r.slabs(|axis, side| b[axis][side][1], t_max);
        let (t0, t1) = (t0.to_array(), t1.to_array());
        (
            m0 | m1 << WIDTH,
            [t0[0], t0[1], t0[2], t0[3], t1[0], t1[1], t1[2], t1[3]],
        )
    }
}

/// Eight lanes at once; only the functions compiled with AVX use it.
#[cfg(target_arch = "x86_64")]
struct Avx;

#[cfg(target_arch = "x86_64")]
impl BoxTest for Avx {
    #[inline(always)]
    fn hit_boxes8(r: &TraversalRay, node: &Node8, t_max: f32) -> (u32, [f32; NODE_WIDTH]) {
        // SAFETY: `Avx` is used only by `intersect_avx` and `occluded_avx`,
        // which are called only where the CPU has AVX.
        unsafe { hit_boxes8_avx(r, node, t_max) }
    }
}

/// `Sse::hit_boxes8` in 256-bit registers: the same operations on the same
/// operands in the same order, lane by lane.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
fn hit_boxes8_avx(r: &TraversalRay, node: &Node8, t_max: f32) -> (u32, [f32; NODE_WIDTH]) {
    use std::arch::x86_64::*;
    let splat = |v: Vec4| {
        let v = __m128::from(v);
        _mm256_set_m128(v, v)
    };
    let bound = |axis: usize, side: usize| {
        let [lo, hi] = node.bounds[axis][side];
        _mm256_set_m128(__m128::from(hi), __m128::from(lo))
    };
    let slab = |axis: usize| {
        let near = r.near[axis] as usize;
        let inv = splat(r.inv_d[axis]);
        let t0 = _mm256_mul_ps(_mm256_sub_ps(bound(axis, near), splat(r.o_near[axis])), inv);
        let t1 = _mm256_mul_ps(_mm256_sub_ps(bound(axis, 1 - near), splat(r.o_far[axis])), inv);
        (t0, t1)
    };
    let (nx, fx) = slab(0);
    let (ny, fy) = slab(1);
    let (nz, fz) = slab(2);
    let t_near = _mm256_max_ps(_mm256_max_ps(nx, ny), _mm256_max_ps(nz, splat(r.t_min)));
    let far = _mm256_min_ps(_mm256_min_ps(fx, fy), _mm256_min_ps(fz, _mm256_set1_ps(t_max)));
    let t_far = _mm256_mul_ps(far, _mm256_set1_ps(FAR_WIDEN));
    let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(t_near, t_far)) as u32;
    let mut t = [0.0f32; NODE_WIDTH];
    // SAFETY: `t` holds eight floats; an unaligned store needs no more.
    unsafe { _mm256_storeu_ps(t.as_mut_ptr(), t_near) };
    (mask, t)
}

/// A ray prepared for box and packet tests: its origin and direction in all
/// lanes, the reciprocal direction, which box plane is near on each axis,
/// and the origin the near and far planes are measured from.
pub(super) struct TraversalRay {
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
    pub(super) fn new(ray: &Ray, t_min: f32) -> Self {
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

    /// Which of four boxes (`bounds[axis][0]` their minima along `axis`,
    /// `[1]` their maxima) the ray enters within (t_min, t_max) (bit i for
    /// lane i), and the entry distances.
    #[inline(always)]
    pub(super) fn hit_boxes(&self, b: &[[Vec4; 2]; 3], t_max: f32) -> (u32, Vec4) {
        self.slabs(|axis, side| b[axis][side], t_max)
    }

    /// `hit_boxes` of the boxes `bound(axis, side)` gives (side 0: minima).
    #[inline(always)]
    fn slabs(&self, bound: impl Fn(usize, usize) -> Vec4, t_max: f32) -> (u32, Vec4) {
        let slab = |axis: usize| {
            let near = self.near[axis] as usize;
            let t0 = (bound(axis, near) - self.o_near[axis]) * self.inv_d[axis];
            let t1 = (bound(axis, 1 - near) - self.o_far[axis]) * self.inv_d[axis];
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

    /// The nearest hit among a packet's triangles that `accept` accepts,
    /// if any is closer than t_max. Lanes are offered in slot order and a
    /// tie keeps the first, as in `hit_triangles`.
    #[inline(always)]
    fn hit_accepted_triangles<A: Accept>(&self, p: &Tri4, t_max: f32, accept: &A) -> Option<(u32, TriHit)> {
        let (ok, t, u, v) = self.test_packet(p, t_max);
        let mut mask = ok.bitmask();
        if mask == 0 {
            return None;
        }
        let (t, u, v) = (t.to_array(), u.to_array(), v.to_array());
        let mut t_max = t_max;
        let mut best = None;
        while mask != 0 {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let h = TriHit {
                t: t[lane],
                u: u[lane],
                v: v[lane],
            };
            if h.t < t_max && accept.accept(p.slot[lane], &h) {
                t_max = h.t;
                best = Some((p.slot[lane], h));
            }
        }
        best
    }

    #[inline(always)]
    fn hits_any_triangle<A: Accept>(&self, p: &Tri4, t_max: f32, accept: &A) -> bool {
        let (ok, t, u, v) = self.test_packet(p, t_max);
        if A::ALL {
            return ok.any();
        }
        let mut mask = ok.bitmask();
        while mask != 0 {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let h = TriHit {
                t: t.to_array()[lane],
                u: u.to_array()[lane],
                v: v.to_array()[lane],
            };
            if accept.accept(p.slot[lane], &h) {
                return true;
            }
        }
        false
    }
}
