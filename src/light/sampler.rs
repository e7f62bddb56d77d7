//! Choosing the light for a shadow ray: pbrt-v4's light samplers
//! (`Integrator "string lightsampler"`). `power` chooses in proportion to
//! each light's power wherever the ray leaves from, `uniform` chooses every
//! light alike, and `bvh` weighs each light by what it may bring to the
//! point being lit: a tree over the lights' bounds of emission (where they
//! are, how much they emit, towards which directions), walked from the root
//! by choosing each child in proportion to a bound on its importance at the
//! point (Conty Estevez and Kulla 2018, "Importance Sampling of Many Lights
//! with Adaptive Tree Splitting"; pbrt-v4's `BVHLightSampler`). In a scene
//! of many lights each point is then lit mostly by the lights near it and
//! facing it, where choosing by power spends most shadow rays on lights far
//! away or turned away.
//!
//! A leaf of the tree is one light, or the two triangles of a quad chosen
//! between by their power (`Unit`).
//!
//! Lights without bounds (distant and infinite ones) are chosen apart from
//! the tree, each as likely as the whole tree, as pbrt-v4 chooses them.
//! Each bound is conservative: a light that can light a point has an
//! importance above zero there, so the choice stays unbiased.

use super::Light;
use crate::math::Vec3;
use crate::sampling::ONE_MINUS_EPS;
use glam::{BVec4A, Vec4};
use std::f32::consts::PI;

/// How a light is chosen for a shadow ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSamplerKind {
    /// In proportion to power (the largest channel), wherever the point.
    #[default]
    Power,
    /// Every light alike.
    Uniform,
    /// By the light tree's importance at the point.
    Bvh,
}

impl LightSamplerKind {
    pub const NAMES: [&'static str; 3] = ["power", "uniform", "bvh"];

    pub fn name(self) -> &'static str {
        match self {
            LightSamplerKind::Power => "power",
            LightSamplerKind::Uniform => "uniform",
            LightSamplerKind::Bvh => "bvh",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "power" => Some(LightSamplerKind::Power),
            "uniform" => Some(LightSamplerKind::Uniform),
            "bvh" => Some(LightSamplerKind::Bvh),
            _ => None,
        }
    }
}

/// The point a light is chosen for: where it is and, at a surface, the
/// shading normal there (zero in a medium, which scatters every way).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightContext {
    pub p: Vec3,
    pub n: Vec3,
}

impl LightContext {
    pub fn surface(p: Vec3, n: Vec3) -> LightContext {
        LightContext { p, n }
    }

    pub fn medium(p: Vec3) -> LightContext {
        LightContext { p, n: Vec3::ZERO }
    }
}

/// The numbers of one light sample: `choice` chooses the light, `point` the
/// point on it. With a choice that ignores the point, `point.x` is `choice`
/// itself, rescaled within the chosen light's share once it is made (one 2D
/// sample covers all the lights together, see `Scene::pick_light`); a tree
/// walk would leave too few bits of it, so the tree takes a number of its own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSampleU {
    pub choice: f32,
    pub point: crate::math::Vec2,
}

/// Where a set of lights emits, how much, and which way: every emitting
/// point lies in the box [`min`, `max`], every emitting normal within
/// `theta_o` of `w`, and each emits only within `theta_e` of its normal (on
/// both sides of it when `two_sided`). `phi` is the set's power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    min: Vec3,
    max: Vec3,
    phi: f32,
    w: Vec3,
    cos_theta_o: f32,
    cos_theta_e: f32,
    two_sided: bool,
}

/// The largest importance: four of them still sum to a finite number.
const MAX_IMPORTANCE: f32 = 1e30;

/// cos(max(0, a - b)) from the sines and cosines of a and b in [0, pi].
#[inline(always)]
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// sin(max(0, a - b)), as `cos_sub_clamped`.
#[inline(always)]
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
    }
}

#[inline(always)]
fn sin_from_cos(c: f32) -> f32 {
    (1.0 - c * c).max(0.0).sqrt()
}

impl LightBounds {
    /// The bounds of one light, `None` for lights without a place (distant
    /// and infinite ones) and for lights that emit nothing.
    pub fn of(light: &Light) -> Option<LightBounds> {
        let phi = light.power().max_element();
        if !(phi > 0.0 && phi.is_finite()) {
            return None;
        }
        // A point, or a shape, emitting every way.
        let everywhere = |min: Vec3, max: Vec3| LightBounds {
            min,
            max,
            phi,
            w: Vec3::Z,
            cos_theta_o: -1.0,
            cos_theta_e: 0.0,
            two_sided: false,
        };
        let b = match light {
            Light::Sphere { sphere, .. } => {
                let r = Vec3::splat(sphere.radius);
                everywhere(sphere.centre - r, sphere.centre + r)
            }
            Light::Point { position, .. }
            | Light::Goniometric { position, .. }
            | Light::Projection { position, .. } => everywhere(*position, *position),
            Light::Triangle {
                vertices, two_sided, ..
            } => {
                let [a, b, c] = *vertices;
                let w = super::triangle_normal(vertices);
                if w == Vec3::ZERO {
                    return None;
                }
                LightBounds {
                    min: a.min(b).min(c),
                    max: a.max(b).max(c),
                    phi,
                    w,
                    cos_theta_o: 1.0,
                    cos_theta_e: 0.0,
                    two_sided: *two_sided,
                }
            }
            Light::Disk { disk, two_sided, .. } => {
                let r = Vec3::splat(disk.radius);
                LightBounds {
                    min: disk.centre - r,
                    max: disk.centre + r,
                    phi,
                    w: disk.normal,
                    cos_theta_o: 1.0,
                    cos_theta_e: 0.0,
                    two_sided: *two_sided,
                }
            }
            Light::Spot {
                position,
                direction,
                cos_falloff_start,
                cos_falloff_end,
                ..
            } => {
                // Full within the falloff's start, nothing beyond its end.
                let theta_o = cos_falloff_start.clamp(-1.0, 1.0).acos();
                let theta_end = cos_falloff_end.clamp(-1.0, 1.0).acos();
                LightBounds {
                    min: *position,
                    max: *position,
                    phi,
                    w: *direction,
                    cos_theta_o: theta_o.cos(),
                    cos_theta_e: (theta_end - theta_o).max(0.0).cos(),
                    two_sided: false,
                }
            }
            Light::Distant { .. } | Light::Infinite { .. } => return None,
        };
        Some(b)
    }

    fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// A bound on what these lights bring to `ctx`: the power over the
    /// squared distance, times a bound on the cosine at the lights (no
    /// light's emission reaches the point from outside the cone of normals
    /// widened by the box's angle seen from the point, and by `theta_e`) and
    /// on the cosine at the point. Zero only where none of them can light it.
    pub fn importance(&self, ctx: &LightContext) -> f32 {
        let pc = self.centre();
        let to_p = ctx.p - pc;
        let dc2 = to_p.length_squared();
        // The box's bounding sphere; within it, no angle bounds anything.
        let r2 = 0.25 * (self.max - self.min).length_squared();
        let d2 = dc2.max(r2);
        if dc2 <= r2 {
            return (self.phi / d2).min(MAX_IMPORTANCE);
        }
        let wi = to_p / dc2.sqrt();
        let sin2_u = r2 / dc2;
        let sin_u = sin2_u.sqrt();
        let cos_u = (1.0 - sin2_u).max(0.0).sqrt();
        let mut cos_w = self.w.dot(wi);
        if self.two_sided {
            cos_w = cos_w.abs();
        }
        let cos_w = cos_w.clamp(-1.0, 1.0);
        let sin_w = sin_from_cos(cos_w);
        let sin_o = sin_from_cos(self.cos_theta_o);
        // The angle between the cone and the direction to the point, less
        // the box's angle: cos(max(0, theta_w - theta_o - theta_u)).
        let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, self.cos_theta_o);
        let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, self.cos_theta_o);
        let cos_p = cos_sub_clamped(sin_x, cos_x, sin_u, cos_u);
        if cos_p <= self.cos_theta_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / d2;
        if ctx.n != Vec3::ZERO {
            let cos_i = wi.dot(ctx.n).abs().min(1.0);
            let sin_i = sin_from_cos(cos_i);
            importance *= cos_sub_clamped(sin_i, cos_i, sin_u, cos_u).max(0.0);
        }
        if importance.is_nan() {
            0.0
        } else {
            importance.clamp(0.0, MAX_IMPORTANCE)
        }
    }

    /// The bounds of both sets together.
    fn union(&self, o: &LightBounds) -> LightBounds {
        let (w, cos_theta_o) = cone_union((self.w, self.cos_theta_o), (o.w, o.cos_theta_o));
        LightBounds {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
            phi: self.phi + o.phi,
            w,
            cos_theta_o,
            cos_theta_e: self.cos_theta_e.min(o.cos_theta_e),
            two_sided: self.two_sided || o.two_sided,
        }
    }

    /// The solid-angle measure of the directions the set may emit into,
    /// weighted by cosine (Conty Estevez and Kulla's M_Omega).
    fn orientation_measure(&self) -> f32 {
        let theta_o = self.cos_theta_o.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_theta_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = theta_o.sin();
        2.0 * PI * (1.0 - self.cos_theta_o)
            + PI / 2.0
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + self.cos_theta_o)
    }
}

/// The narrowest cone (axis, cosine of its half-angle) holding two cones.
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    const WHOLE: f32 = -1.0;
    if a == b {
        return a;
    }
    if a.1 <= WHOLE || b.1 <= WHOLE {
        return (a.0, WHOLE);
    }
    let theta_a = a.1.clamp(-1.0, 1.0).acos();
    let theta_b = b.1.clamp(-1.0, 1.0).acos();
    // atan2 rather than acos: exact enough for nearly parallel axes.
    let theta_d = a.0.cross(b.0).length().atan2(a.0.dot(b.0));
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    // Half the angle from a's far edge to b's, slightly widened so that
    // rounding never leaves an edge outside.
    let theta_o = 0.5 * (theta_a + theta_d + theta_b) * (1.0 + 1e-5) + 1e-6;
    if theta_o >= PI {
        return (a.0, WHOLE);
    }
    // The axis turned from a's towards b's.
    let k = a.0.cross(b.0);
    let len = k.length();
    if len.is_nan() || len <= 1e-12 {
        return (a.0, WHOLE);
    }
    let k = k / len;
    let turn = theta_o - theta_a;
    let w = (a.0 * turn.cos() + k.cross(a.0) * turn.sin()).normalize_or_zero();
    if w == Vec3::ZERO {
        return (a.0, WHOLE);
    }
    (w, theta_o.cos())
}

/// The bounds of a non-empty set of lights together.
fn union_of(items: &[(u32, LightBounds)]) -> LightBounds {
    items[1..].iter().fold(items[0].1, |acc, (_, b)| acc.union(b))
}

/// The bucket of a centre `c` along an axis whose centres span [lo, hi].
fn bucket_of(c: f32, lo: f32, hi: f32) -> usize {
    (((c - lo) / (hi - lo) * BUCKETS as f32) as usize).min(BUCKETS - 1)
}

/// Four children's bounds side by side, one lane each, so that their
/// importances are found together; an empty lane has no power.
#[derive(Clone, Debug, PartialEq)]
struct Node {
    centre: [Vec4; 3],
    /// The radius of each box's bounding sphere, and its square.
    radius: Vec4,
    radius2: Vec4,
    w: [Vec4; 3],
    cos_o: Vec4,
    sin_o: Vec4,
    cos_e: Vec4,
    phi: Vec4,
    two_sided: BVec4A,
    /// Each lane's child: a node, or with `LEAF` set a unit of lights.
    child: [u32; 4],
}

const LEAF: u32 = 1 << 31;

/// Square roots of four lanes (the compiler makes one instruction of them).
#[inline(always)]
fn sqrt4(v: Vec4) -> Vec4 {
    Vec4::from_array(v.to_array().map(f32::sqrt))
}
const EMPTY: u32 = u32::MAX;

impl Node {
    fn new(lanes: &[(LightBounds, u32)]) -> Node {
        let lane = |k: usize, f: &dyn Fn(&LightBounds) -> f32, empty: f32| lanes.get(k).map_or(empty, |(b, _)| f(b));
        let v = |f: &dyn Fn(&LightBounds) -> f32, empty: f32| {
            Vec4::new(
                lane(0, f, empty),
                lane(1, f, empty),
                lane(2, f, empty),
                lane(3, f, empty),
            )
        };
        let mut child = [EMPTY; 4];
        for (k, (_, c)) in lanes.iter().enumerate() {
            child[k] = *c;
        }
        let radius = |b: &LightBounds| 0.5 * (b.max - b.min).length();
        Node {
            centre: [0, 1, 2].map(|a| v(&|b| b.centre()[a], 0.0)),
            radius: v(&radius, 0.0),
            radius2: v(&|b| radius(b) * radius(b), 0.0),
            w: [0, 1, 2].map(|a| v(&|b| b.w[a], 0.0)),
            cos_o: v(&|b| b.cos_theta_o, 1.0),
            sin_o: v(&|b| sin_from_cos(b.cos_theta_o), 0.0),
            cos_e: v(&|b| b.cos_theta_e, 1.0),
            phi: v(&|b| b.phi, 0.0),
            two_sided: BVec4A::new(
                lanes.first().is_some_and(|l| l.0.two_sided),
                lanes.get(1).is_some_and(|l| l.0.two_sided),
                lanes.get(2).is_some_and(|l| l.0.two_sided),
                lanes.get(3).is_some_and(|l| l.0.two_sided),
            ),
            child,
        }
    }

    /// [`LightBounds::importance`] of the four lanes at once (zero in empty
    /// ones), its branches made selections.
    #[inline]
    fn importance(&self, ctx: &LightContext) -> Vec4 {
        let one = Vec4::ONE;
        let zero = Vec4::ZERO;
        let d = [0, 1, 2].map(|a| Vec4::splat(ctx.p[a]) - self.centre[a]);
        let dc2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let inside = dc2.cmple(self.radius2);
        let d2 = dc2.max(self.radius2);
        let inv_d = one / sqrt4(dc2);
        let cos_w = (self.w[0] * d[0] + self.w[1] * d[1] + self.w[2] * d[2]) * inv_d;
        let cos_w = Vec4::select(self.two_sided, cos_w.abs(), cos_w).clamp(-one, one);
        let sin_w = sqrt4((one - cos_w * cos_w).max(zero));
        let before = cos_w.cmpgt(self.cos_o);
        let cos_x = Vec4::select(before, one, cos_w * self.cos_o + sin_w * self.sin_o);
        let sin_x = Vec4::select(before, zero, sin_w * self.cos_o - cos_w * self.sin_o);
        let sin_u = (self.radius * inv_d).min(one);
        let cos_u = sqrt4((one - sin_u * sin_u).max(zero));
        let cos_p = Vec4::select(cos_x.cmpgt(cos_u), one, cos_x * cos_u + sin_x * sin_u);
        let mut outside = Vec4::select(cos_p.cmple(self.cos_e), zero, self.phi * cos_p / d2);
        if ctx.n != Vec3::ZERO {
            let cos_i = ((d[0] * ctx.n.x + d[1] * ctx.n.y + d[2] * ctx.n.z) * inv_d)
                .abs()
                .min(one);
            let sin_i = sqrt4((one - cos_i * cos_i).max(zero));
            let f = Vec4::select(cos_i.cmpgt(cos_u), one, cos_i * cos_u + sin_i * sin_u);
            outside *= f.max(zero);
        }
        let i = Vec4::select(inside, self.phi / d2, outside);
        // Overflow counts as the most; no power (an empty lane) as none.
        let i = i.min(Vec4::splat(MAX_IMPORTANCE));
        Vec4::select(self.phi.cmpgt(zero) & i.cmpgt(zero), i, zero)
    }

    /// The probability of each lane's child for `ctx`, or `None` when none
    /// can light it.
    #[inline]
    fn probabilities(&self, ctx: &LightContext) -> Option<[f32; 4]> {
        let i = self.importance(ctx);
        let sum = i.element_sum();
        (sum > 0.0).then(|| (i / sum).to_array())
    }
}

/// Where a light is in the choice: apart from the tree, or at the end of a
/// path through it (two bits a level: the lane taken), chosen there with
/// `share` of its leaf's probability.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Place {
    None,
    Infinite,
    Tree { lanes: u64, depth: u8, share: f32 },
}

/// What a leaf of the tree holds: one light, or the two triangles of a
/// quad, `first` chosen with probability `share` (its part of the pair's
/// power) and `second` otherwise. A quad is one light to the eye, and
/// weighing its halves apart would cost a weighing at every point lit for
/// nothing: their bounds are the quad's but for its extent.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Unit {
    first: u32,
    second: u32,
    share: f32,
}

/// Whether lights `a` and `b` make a quad: triangles sharing an edge,
/// facing the same way in one plane, emitting on the same sides.
fn make_quad(a: &Light, b: &Light) -> bool {
    let (
        Light::Triangle {
            vertices: va,
            two_sided: sa,
            ..
        },
        Light::Triangle {
            vertices: vb,
            two_sided: sb,
            ..
        },
    ) = (a, b)
    else {
        return false;
    };
    let shared = vb.iter().filter(|v| va.contains(v)).count();
    sa == sb && shared == 2 && super::triangle_normal(va).dot(super::triangle_normal(vb)) > 1.0 - 1e-5
}

/// Deeper than this (in binary cuts) the build halves sets by count, so
/// that every path's lanes fit their 64 bits.
const MAX_SAH_DEPTH: usize = 40;
/// Buckets a split is sought among, per axis.
const BUCKETS: usize = 12;

/// pbrt-v4's `bvh` light sampler: lights without bounds chosen apart, the
/// others through a tree of four children a node.
#[derive(Clone, Debug, PartialEq)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// The leaves' lights, by the index a leaf's child holds.
    units: Vec<Unit>,
    /// The tree is one leaf: nothing to weigh, its light is the choice.
    single: bool,
    infinite: Vec<u32>,
    places: Vec<Place>,
}

/// A tree built apart: its nodes in preorder (its root first, child
/// indices its own), and the places of the lights at its leaves.
struct Subtree {
    nodes: Vec<Node>,
    leaves: Vec<(u32, Place)>,
}

/// A lane's child as a subtree builds it: a light and its place, or a
/// subtree of its own.
enum Child {
    Light(u32, Place),
    Tree(Subtree),
}

/// Sets at least this large build their children's subtrees on threads
/// of their own; smaller ones are not worth a task.
const PARALLEL_LIGHTS: usize = 2048;

/// Builds the tree over `items` (more than one, or the whole tree's single
/// light) at `level`, reached by `lanes`; `cuts` binary cuts so far. The
/// nodes come in the preorder of a depth-first build whatever the threads,
/// so the tree is the same on any machine.
fn subtree(items: &mut [(u32, LightBounds)], level: usize, lanes: u64, cuts: usize) -> Subtree {
    use rayon::prelude::*;
    let parallel = items.len() >= PARALLEL_LIGHTS;
    // Up to four groups: two cuts of the set, then of each side.
    let mut groups: Vec<&mut [(u32, LightBounds)]> = Vec::with_capacity(4);
    if items.len() <= 4 {
        groups.extend(items.chunks_mut(1));
    } else {
        let mid = split(items, cuts);
        let (l, r) = items.split_at_mut(mid);
        let cut_side = |side: &mut [(u32, LightBounds)]| match side.len() {
            1 => None,
            _ => Some(split(side, cuts + 1)),
        };
        let (ml, mr) = match parallel {
            true => rayon::join(|| cut_side(l), || cut_side(r)),
            false => (cut_side(l), cut_side(r)),
        };
        for (side, m) in [(l, ml), (r, mr)] {
            match m {
                None => groups.push(side),
                Some(m) => {
                    let (a, b) = side.split_at_mut(m);
                    groups.push(a);
                    groups.push(b);
                }
            }
        }
    }
    let build = |(k, g): (usize, &mut &mut [(u32, LightBounds)])| {
        let bounds = union_of(g);
        let path = lanes | (k as u64) << (2 * level);
        let child = match &**g {
            [(light, _)] => Child::Light(
                *light,
                Place::Tree {
                    lanes: path,
                    depth: (level + 1) as u8,
                    share: 1.0,
                },
            ),
            _ => Child::Tree(subtree(g, level + 1, path, cuts + 2)),
        };
        (bounds, child)
    };
    let children: Vec<_> = match parallel {
        true => groups.par_iter_mut().enumerate().map(build).collect(),
        false => groups.iter_mut().enumerate().map(build).collect(),
    };
    let mut nodes = vec![Node::new(&[])];
    let mut leaves = Vec::new();
    let mut lanes_of = Vec::with_capacity(4);
    for (bounds, child) in children {
        let index = match child {
            Child::Light(light, place) => {
                leaves.push((light, place));
                LEAF | light
            }
            Child::Tree(sub) => {
                let offset = nodes.len() as u32;
                nodes.extend(sub.nodes.into_iter().map(|mut n| {
                    for c in &mut n.child {
                        if *c != EMPTY && *c & LEAF == 0 {
                            *c += offset;
                        }
                    }
                    n
                }));
                leaves.extend(sub.leaves);
                offset
            }
        };
        lanes_of.push((bounds, index));
    }
    nodes[0] = Node::new(&lanes_of);
    Subtree { nodes, leaves }
}

/// Reorders `items` into two non-empty sides and returns the first's
/// size: the cheapest of the bucket boundaries along each axis by
/// Conty Estevez and Kulla's cost (power times orientation measure times
/// surface area, each axis weighed by the box's extent over its own),
/// else in halves by count.
fn split(items: &mut [(u32, LightBounds)], cuts: usize) -> usize {
    let n = items.len();
    let bounds = union_of(items);
    let (cmin, cmax) = items
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (_, b)| {
            (lo.min(b.centre()), hi.max(b.centre()))
        });
    let extent = bounds.max - bounds.min;
    // The cheapest cut along one axis: (cost, cut), the later of equals.
    let along = |axis: usize| -> Option<(f32, usize)> {
        let (lo, hi) = (cmin[axis], cmax[axis]);
        if hi.is_nan() || lo.is_nan() || hi <= lo {
            return None;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (_, b) in items.iter() {
            let k = bucket_of(b.centre()[axis], lo, hi);
            buckets[k] = Some(buckets[k].map_or(*b, |acc| acc.union(b)));
        }
        let cost = |b: &LightBounds| {
            let e = b.max - b.min;
            let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
            b.phi * b.orientation_measure() * area
        };
        let join = |acc: Option<LightBounds>, b: &Option<LightBounds>| match (acc, b) {
            (Some(a), Some(b)) => Some(a.union(b)),
            (a, b) => a.or(*b),
        };
        // Each cut's two sides, swept from both ends.
        let mut below = [None; BUCKETS];
        let mut acc = None;
        for k in 0..BUCKETS {
            acc = join(acc, &buckets[k]);
            below[k] = acc;
        }
        let regular = extent.max_element() / extent[axis].max(f32::MIN_POSITIVE);
        let mut above: Option<LightBounds> = None;
        let mut best: Option<(f32, usize)> = None;
        for cut in (1..BUCKETS).rev() {
            above = join(above, &buckets[cut]);
            let (Some(l), Some(r)) = (below[cut - 1], above) else {
                continue;
            };
            let c = regular * (cost(&l) + cost(&r));
            if best.is_none_or(|(bc, _)| c <= bc) {
                best = Some((c, cut));
            }
        }
        best
    };
    let per_axis: [Option<(f32, usize)>; 3] = match (cuts < MAX_SAH_DEPTH, n >= PARALLEL_LIGHTS) {
        (false, _) => [None; 3],
        // Each axis's buckets on a thread of its own: the top of a large
        // tree is one set, which nothing else can share out.
        (true, true) => {
            let ((x, y), z) = rayon::join(|| rayon::join(|| along(0), || along(1)), || along(2));
            [x, y, z]
        }
        (true, false) => [along(0), along(1), along(2)],
    };
    // The later axis of equal costs, as one sweep over all three would take.
    let mut best: Option<(f32, usize, usize)> = None;
    for (axis, found) in per_axis.into_iter().enumerate() {
        if let Some((c, cut)) = found {
            if best.is_none_or(|(bc, _, _)| c <= bc) {
                best = Some((c, axis, cut));
            }
        }
    }
    if let Some((_, axis, cut)) = best {
        let (lo, hi) = (cmin[axis], cmax[axis]);
        // A stable partition keeps the tree the same run to run.
        let (mut left, right): (Vec<_>, Vec<_>) = items
            .iter()
            .partition(|(_, b)| bucket_of(b.centre()[axis], lo, hi) < cut);
        let mid = left.len();
        if mid > 0 && mid < n {
            left.extend(right);
            items.copy_from_slice(&left);
            return mid;
        }
    }
    n / 2
}

impl LightTree {
    pub fn build(lights: &[Light]) -> LightTree {
        let mut places = vec![Place::None; lights.len()];
        let mut infinite = Vec::new();
        let mut bounded = Vec::new();
        for (i, light) in lights.iter().enumerate() {
            match LightBounds::of(light) {
                Some(b) => bounded.push((i as u32, b)),
                None if matches!(light, Light::Distant { .. } | Light::Infinite { .. })
                    && light.power().max_element() > 0.0 =>
                {
                    places[i] = Place::Infinite;
                    infinite.push(i as u32);
                }
                None => {}
            }
        }
        // A quad's two triangles come one after the other from every mesh
        // loader: one leaf, chosen between by power.
        let mut units = Vec::with_capacity(bounded.len());
        let mut items = Vec::with_capacity(bounded.len());
        let mut k = 0;
        while k < bounded.len() {
            let (a, ba) = bounded[k];
            let unit = items.len() as u32;
            match bounded.get(k + 1) {
                Some(&(b, bb)) if b == a + 1 && make_quad(&lights[a as usize], &lights[b as usize]) => {
                    units.push(Unit {
                        first: a,
                        second: b,
                        share: ba.phi / (ba.phi + bb.phi),
                    });
                    items.push((unit, ba.union(&bb)));
                    k += 2;
                }
                _ => {
                    units.push(Unit {
                        first: a,
                        second: EMPTY,
                        share: 1.0,
                    });
                    items.push((unit, ba));
                    k += 1;
                }
            }
        }
        let mut tree = LightTree {
            nodes: Vec::with_capacity(items.len() / 2 + 1),
            single: items.len() == 1,
            units,
            infinite,
            places,
        };
        if !items.is_empty() {
            let sub = subtree(&mut items, 0, 0, 0);
            tree.nodes = sub.nodes;
            for (unit, place) in sub.leaves {
                let Place::Tree { lanes, depth, .. } = place else {
                    continue;
                };
                let u = tree.units[unit as usize];
                tree.places[u.first as usize] = Place::Tree {
                    lanes,
                    depth,
                    share: u.share,
                };
                if u.second != EMPTY {
                    tree.places[u.second as usize] = Place::Tree {
                        lanes,
                        depth,
                        share: 1.0 - u.share,
                    };
                }
            }
        }
        tree
    }

    /// Whether the tree is one leaf and no light is chosen apart from it:
    /// then it chooses each light in proportion to its power, as
    /// [`LightSamplerKind::Power`] does.
    pub fn is_power_choice(&self) -> bool {
        self.single && self.infinite.is_empty()
    }

    /// The probability of choosing an infinite light (each as likely as
    /// the tree).
    fn p_infinite(&self) -> f32 {
        let n = self.infinite.len() as f32;
        n / (n + if self.nodes.is_empty() { 0.0 } else { 1.0 })
    }

    /// Chooses a light for `ctx` with `u` in [0, 1): its index and the
    /// probability of the choice, which [`LightTree::pmf`] gives again.
    pub fn pick(&self, ctx: &LightContext, u: f32) -> Option<(usize, f32)> {
        let p_inf = self.p_infinite();
        if u < p_inf {
            let n = self.infinite.len();
            let k = ((u / p_inf * n as f32) as usize).min(n - 1);
            return Some((self.infinite[k] as usize, p_inf / n as f32));
        }
        if self.nodes.is_empty() {
            return None;
        }
        let mut u = ((u - p_inf) / (1.0 - p_inf)).min(ONE_MINUS_EPS);
        let mut pmf = 1.0 - p_inf;
        let mut node = &self.nodes[0];
        let leaf = loop {
            if self.single {
                break node.child[0];
            }
            let p = node.probabilities(ctx)?;
            // The lane whose share of [0, 1) holds u; rounding may leave u
            // past the last share, which then takes it.
            let mut k = 0;
            let mut below = 0.0;
            for (j, &pj) in p.iter().enumerate() {
                if pj > 0.0 {
                    k = j;
                    if u < below + pj {
                        break;
                    }
                    below += pj;
                }
            }
            u = ((u - below) / p[k]).clamp(0.0, ONE_MINUS_EPS);
            pmf *= p[k];
            let child = node.child[k];
            if child & LEAF != 0 {
                break child;
            }
            node = &self.nodes[child as usize];
        };
        let unit = self.units[(leaf & !LEAF) as usize];
        if unit.second == EMPTY {
            Some((unit.first as usize, pmf))
        } else if u < unit.share {
            Some((unit.first as usize, pmf * unit.share))
        } else {
            Some((unit.second as usize, pmf * (1.0 - unit.share)))
        }
    }

    /// The probability that [`LightTree::pick`] chooses light `light` for `ctx`.
    pub fn pmf(&self, ctx: &LightContext, light: usize) -> f32 {
        match self.places.get(light) {
            Some(Place::Infinite) => self.p_infinite() / self.infinite.len() as f32,
            Some(&Place::Tree { lanes, depth, share }) => {
                let mut pmf = 1.0 - self.p_infinite();
                let mut node = &self.nodes[0];
                for level in 0..depth as u32 {
                    if self.single {
                        break;
                    }
                    let Some(p) = node.probabilities(ctx) else {
                        return 0.0;
                    };
                    let k = (lanes >> (2 * level) & 3) as usize;
                    pmf *= p[k];
                    let child = node.child[k];
                    if child & LEAF != 0 {
                        break;
                    }
                    node = &self.nodes[child as usize];
                }
                pmf * share
            }
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Disk, Sphere};
    use crate::light::Emits;
    use crate::math::Vec2;
    use crate::sampling::Rng;

    fn unit(rng: &mut Rng) -> Vec3 {
        loop {
            let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }

    fn point(rng: &mut Rng, size: f32) -> Vec3 {
        (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE) * size
    }

    /// Lights of every kind the tree bounds, scattered at random, with an
    /// infinite light, one that emits nothing and one behind a wall of
    /// others' power.
    fn lights(rng: &mut Rng, n: usize) -> Vec<Light> {
        let mut ls = Vec::new();
        for k in 0..n {
            let c = point(rng, 5.0);
            let l = match k % 6 {
                0 | 1 => {
                    let (a, b) = (unit(rng) * 0.3, unit(rng) * 0.3);
                    // Every other second triangle the other half of the
                    // first's parallelogram: a quad, when both emit alike.
                    let vertices = match ls.last() {
                        Some(Light::Triangle {
                            vertices: [p, q, r], ..
                        }) if k % 12 == 7 => [*q, *q + (*r - *p), *r],
                        _ => [c, c + a, c + b],
                    };
                    Light::Triangle {
                        vertices,
                        radiance: Vec3::splat(1.0 + 9.0 * rng.next_f32()),
                        two_sided: k % 4 == 1,
                        image: None,
                    }
                }
                2 => Light::Sphere {
                    sphere: Sphere {
                        centre: c,
                        radius: 0.05 + 0.2 * rng.next_f32(),
                    },
                    power: Vec3::splat(5.0),
                    image: None,
                    emits: Emits::Outwards,
                },
                3 => Light::Point {
                    position: c,
                    power: Vec3::new(1.0, 2.0, 3.0),
                },
                4 => Light::Spot {
                    position: c,
                    direction: unit(rng),
                    intensity: Vec3::ONE,
                    cos_falloff_start: 0.9,
                    cos_falloff_end: 0.6,
                },
                _ => Light::Disk {
                    disk: Disk::new(c, unit(rng), 0.2, 0.0, None).unwrap(),
                    radiance: Vec3::ONE,
                    two_sided: false,
                    image: None,
                },
            };
            ls.push(l);
        }
        ls.push(Light::Point {
            position: Vec3::ZERO,
            power: Vec3::ZERO,
        });
        ls.push(Light::Infinite {
            radiance: Vec3::ONE,
            map: None,
            to_world: glam::Mat3::IDENTITY,
            world: Sphere {
                centre: Vec3::ZERO,
                radius: 10.0,
            },
            portal: None,
        });
        ls
    }

    fn context(rng: &mut Rng, k: usize) -> LightContext {
        let p = point(rng, 6.0);
        if k.is_multiple_of(5) {
            LightContext::medium(p)
        } else {
            LightContext::surface(p, unit(rng))
        }
    }

    #[test]
    fn the_tree_is_the_same_on_one_thread_and_on_many() {
        // Enough lights for the parallel build, and a set too small for it.
        for n in [PARALLEL_LIGHTS * 3 + 7, 300] {
            let ls = lights(&mut Rng::new(n as u64, 5), n);
            let on = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| LightTree::build(&ls))
            };
            let one = on(1);
            assert_eq!(one, on(3), "{n} lights");
            // Every light the tree holds has its place, and no two the same
            // but a quad's halves, which share a leaf and its probability.
            let mut paths: Vec<_> = one
                .places
                .iter()
                .filter_map(|p| match p {
                    Place::Tree { lanes, depth, share } => Some((*lanes, *depth, *share)),
                    _ => None,
                })
                .collect();
            let held = paths.len();
            paths.sort_unstable_by(|a, b| (a.0, a.1).cmp(&(b.0, b.1)).then(a.2.total_cmp(&b.2)));
            let mut quads = 0;
            for w in paths.windows(2) {
                if (w[0].0, w[0].1) == (w[1].0, w[1].1) {
                    quads += 1;
                    assert_eq!(w[0].2 + w[1].2, 1.0, "a quad's shares");
                }
            }
            assert_eq!(one.units.len(), held - quads);
            assert!(quads >= n / 24, "{quads} quads of {n} lights");
            assert!(held >= n - n / 6, "{held} of {n}");
            // Each walk ends where the light's stored path leads.
            let mut rng = Rng::new(n as u64, 6);
            for k in 0..500 {
                let ctx = context(&mut rng, k);
                if let Some((light, p)) = one.pick(&ctx, rng.next_f32()) {
                    assert_eq!(one.pmf(&ctx, light), p, "light {light}");
                }
            }
        }
    }

    #[test]
    fn four_lanes_weigh_as_one_light_at_a_time() {
        // The lanes' selections must give what the branches of the
        // one-light importance give: a lane taking the other side of a
        // branch would weigh lights wrongly (or not at all).
        let mut rng = Rng::new(7, 1);
        let ls = lights(&mut rng, 60);
        let bounds: Vec<LightBounds> = ls.iter().filter_map(LightBounds::of).collect();
        for chunk in bounds.chunks(4) {
            let lanes: Vec<(LightBounds, u32)> = chunk.iter().map(|b| (*b, 0)).collect();
            let node = Node::new(&lanes);
            for k in 0..200 {
                let ctx = context(&mut rng, k);
                let four = node.importance(&ctx).to_array();
                for (j, b) in chunk.iter().enumerate() {
                    let one = b.importance(&ctx);
                    assert!(
                        (four[j] - one).abs() <= 1e-4 * one.max(four[j]) + 1e-30,
                        "lane {j}: {} against {one} at {ctx:?} for {b:?}",
                        four[j]
                    );
                }
                for (j, v) in four.iter().enumerate().skip(chunk.len()) {
                    assert_eq!(*v, 0.0, "empty lane {j}");
                }
            }
        }
    }

    #[test]
    fn the_tree_chooses_each_light_with_the_probability_it_reports() {
        let mut rng = Rng::new(3, 2);
        for n in [1, 2, 5, 17, 150] {
            let ls = lights(&mut rng, n);
            let tree = LightTree::build(&ls);
            for k in 0..20 {
                let ctx = context(&mut rng, k);
                let pmfs: Vec<f32> = (0..ls.len()).map(|i| tree.pmf(&ctx, i)).collect();
                let total: f64 = pmfs.iter().map(|&p| p as f64).sum();
                // The infinite light is chosen as often as the tree. A walk
                // down the tree may end where no child can light the point
                // (their bounds together could, each alone cannot): no light
                // then, and the pmfs sum to less than one by that much.
                assert_eq!(pmfs[n + 1], 0.5, "the infinite light");
                assert!(total <= 1.0 + 1e-5, "{n} lights: the pmfs sum to {total}");
                assert_eq!(pmfs[n], 0.0, "a light of no power is never chosen");
                let mut none = 0;
                // Stratified numbers: each choice's probability is the one
                // reported, and the choices' frequencies follow it.
                let m = 20_000;
                let mut counts = vec![0u32; ls.len()];
                for j in 0..m {
                    let u = (j as f32 + 0.5) / m as f32;
                    match tree.pick(&ctx, u) {
                        Some((i, p)) => {
                            assert_eq!(
                                p.to_bits(),
                                pmfs[i].to_bits(),
                                "light {i}: picked with {p}, pmf {}",
                                pmfs[i]
                            );
                            counts[i] += 1;
                        }
                        None => {
                            assert!(u >= 0.5, "no light for {u}");
                            none += 1;
                        }
                    }
                }
                let f = none as f64 / m as f64;
                assert!(
                    (f - (1.0 - total)).abs() < 2.5e-4,
                    "no light {f} of the time, pmfs {total}"
                );
                for (i, &c) in counts.iter().enumerate() {
                    let f = c as f64 / m as f64;
                    assert!(
                        (f - pmfs[i] as f64).abs() < 2.5e-4,
                        "light {i}: chosen {f}, pmf {}",
                        pmfs[i]
                    );
                }
            }
        }
    }

    #[test]
    fn the_tree_never_rules_out_a_light_that_lights_the_point() {
        // Ground truth from the lights themselves: a light sample that
        // brings radiance to the point, arriving other than in the surface's
        // plane, means the light can light it, and then it must be possible
        // to choose it.
        let mut rng = Rng::new(11, 3);
        let ls = lights(&mut rng, 90);
        let tree = LightTree::build(&ls);
        let mut checked = 0;
        for k in 0..300 {
            let ctx = context(&mut rng, k);
            for (i, light) in ls.iter().enumerate() {
                let lights_it = (0..64).any(|j| {
                    let u = Vec2::new((j % 8) as f32 / 8.0 + 0.06, (j / 8) as f32 / 8.0 + 0.06);
                    light.sample_li(ctx.p, u).is_some_and(|s| {
                        s.weight.max_element() > 0.0 && (ctx.n == Vec3::ZERO || s.wi.dot(ctx.n).abs() > 1e-3)
                    })
                });
                if lights_it {
                    checked += 1;
                    assert!(
                        tree.pmf(&ctx, i) > 0.0,
                        "light {i} ({light:?}) lights {ctx:?} but cannot be chosen"
                    );
                }
            }
        }
        assert!(checked > 10_000, "{checked}");
        // And lights facing away are ruled out: a one-sided triangle seen from
        // behind brings nothing, and the tree says so.
        let t = |z: f32| Light::Triangle {
            vertices: [Vec3::new(0.0, 0.0, z), Vec3::new(1.0, 0.0, z), Vec3::new(0.0, 1.0, z)],
            radiance: Vec3::ONE,
            two_sided: false,
            image: None,
        };
        let tree = LightTree::build(&[t(0.0), t(-3.0)]);
        let front = tree.pmf(&LightContext::medium(Vec3::new(0.2, 0.2, 1.0)), 0);
        assert!(front > 0.5 && front < 1.0, "{front}");
        let behind = LightContext::medium(Vec3::new(0.2, 0.2, -1.0));
        assert_eq!(tree.pmf(&behind, 0), 0.0);
        assert_eq!(tree.pmf(&behind, 1), 1.0);
        assert!(tree
            .pick(&LightContext::medium(Vec3::new(0.2, 0.2, -4.0)), 0.5)
            .is_none());
        // A tree of one light has nothing to weigh: it is the choice
        // wherever the point, and lights nothing behind it by itself.
        let tree = LightTree::build(&[t(0.0)]);
        assert_eq!(tree.pmf(&behind, 0), 1.0);
        assert_eq!(tree.pick(&behind, 0.5), Some((0, 1.0)));
    }

    #[test]
    fn a_quad_is_one_leaf_whose_halves_are_chosen_by_their_power() {
        let quad = |radiance: [f32; 2], two_sided: [bool; 2]| {
            let (p, q, r, s) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 2.0, 0.0), Vec3::new(0.0, 2.0, 0.0));
            [[p, q, r], [p, r, s]]
                .into_iter()
                .zip(radiance)
                .zip(two_sided)
                .map(|((vertices, l), two_sided)| Light::Triangle {
                    vertices,
                    radiance: Vec3::splat(l),
                    two_sided,
                    image: None,
                })
        };
        let ctx = LightContext::surface(Vec3::new(0.3, 0.5, 2.0), Vec3::NEG_Z);
        // A point light beside it: the quad's halves are weighed together.
        let point = Light::Point {
            position: Vec3::new(0.0, 0.0, 4.0),
            power: Vec3::splat(40.0),
        };
        let mut ls: Vec<Light> = quad([1.0, 3.0], [false; 2]).collect();
        ls.push(point.clone());
        let tree = LightTree::build(&ls);
        assert_eq!(tree.units.len(), 2);
        let q = tree.pmf(&ctx, 0) + tree.pmf(&ctx, 1);
        assert!((tree.pmf(&ctx, 0) - 0.25 * q).abs() < 1e-6 * q, "by power, 1 : 3");
        assert!((q + tree.pmf(&ctx, 2) - 1.0).abs() < 1e-6);
        // Numbers below the first half's share of the leaf choose it.
        let picks: Vec<usize> = (0..100)
            .filter_map(|j| tree.pick(&ctx, (j as f32 + 0.5) / 100.0).map(|(i, _)| i))
            .collect();
        for i in 0..3 {
            let f = picks.iter().filter(|&&k| k == i).count() as f32 / 100.0;
            assert!((f - tree.pmf(&ctx, i)).abs() <= 0.02, "light {i}: {f}");
        }
        // Triangles that emit on different sides, or are not one after the
        // other, stay apart.
        let apart: Vec<Light> = quad([1.0, 1.0], [false, true]).collect();
        assert_eq!(LightTree::build(&apart).units.len(), 2);
        let mut between: Vec<Light> = quad([1.0, 1.0], [false; 2]).collect();
        between.insert(1, point);
        assert_eq!(LightTree::build(&between).units.len(), 3);
    }

    #[test]
    fn cones_hold_both_cones_they_join() {
        let mut rng = Rng::new(5, 4);
        for _ in 0..2000 {
            let a = (unit(&mut rng), rng.next_f32() * 2.0 - 1.0);
            let b = (unit(&mut rng), rng.next_f32() * 2.0 - 1.0);
            let (w, cos_o) = cone_union(a, b);
            // Each cone's edge, at its widest from the joined axis, lies
            // within the joined cone.
            for (axis, cos) in [a, b] {
                let theta = cos.acos() + axis.cross(w).length().atan2(axis.dot(w));
                assert!(theta.min(PI).cos() >= cos_o - 1e-5, "{a:?} {b:?} -> {w:?} {cos_o}");
            }
        }
    }
}
