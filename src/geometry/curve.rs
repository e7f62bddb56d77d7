//! Thin curves: cubic Bezier pieces swept by a width, for hair and fur
//! (pbrt-v4 6.7, `Curve`). A curve is not a tube: it is a ribbon that turns
//! to face each ray, so it costs no more than its axis, and a `Cylinder`
//! curve only shades as if it were round (its normal turns across the
//! width). A `Ribbon` keeps the normals it is given, and looks as much
//! narrower as it is turned from the ray. A ray meets it where its projection on the plane across the
//! ray comes within half the width of the curve's projected axis, found by
//! subdividing the Bezier until its pieces are near enough to straight
//! (pbrt-v4's `RecursiveIntersect`).
//!
//! The pieces are those of pbrt-v4: each Bezier segment of a `curve` shape
//! split into 2^splitdepth parts of its parameter range, each part with
//! its own control points, here in world space.

use crate::math::{orthonormal_basis, Aabb, Ray, Vec3};

/// How a curve faces the ray and shades across its width (pbrt-v4's
/// `flat`, `cylinder` and `ribbon`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// Its normal faces the ray everywhere.
    Flat,
    /// Its normal turns from -90 to 90 degrees across the width, as a
    /// cylinder's would.
    Cylinder,
    /// A strip whose normal is given at the segment's two ends and turned
    /// between them (spherical interpolation): seen at an angle it is
    /// narrower, edge on it is not seen at all.
    Ribbon,
}

/// One piece of a cubic Bezier segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curve {
    /// The piece's control points (world space).
    pub cp: [Vec3; 4],
    /// The piece's parameter range on its segment.
    pub u: [f32; 2],
    /// The segment's width at its start and end (u = 0 and 1).
    pub width: [f32; 2],
    pub kind: CurveKind,
    /// A ribbon's unit normals at its segment's start and end (unused by
    /// the other kinds).
    pub n: [Vec3; 2],
}

/// Where a ray met a curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveHit {
    pub t: f32,
    /// Along the segment, in [0, 1].
    pub u: f32,
    /// Across the width, in [0, 1] (0.5 on the axis).
    pub v: f32,
    /// dp/du along the segment.
    pub dpdu: Vec3,
    /// Unit normal, perpendicular to the curve: along the ray's line for
    /// flat and cylinder curves, a ribbon's own normal for a ribbon.
    pub ng: Vec3,
    /// Unit shading normal: `ng`, or turned across the width for a
    /// cylinder.
    pub ns: Vec3,
}

fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

fn lerp3(t: f32, a: Vec3, b: Vec3) -> Vec3 {
    a * (1.0 - t) + b * t
}

/// The cubic Bezier `cp` at `u` and its derivative there (de Casteljau).
pub fn evaluate_bezier(cp: &[Vec3; 4], u: f32) -> (Vec3, Vec3) {
    let cp1 = [lerp3(u, cp[0], cp[1]), lerp3(u, cp[1], cp[2]), lerp3(u, cp[2], cp[3])];
    let cp2 = [lerp3(u, cp1[0], cp1[1]), lerp3(u, cp1[1], cp1[2])];
    let d = if (cp2[1] - cp2[0]).length_squared() > 0.0 {
        (cp2[1] - cp2[0]) * 3.0
    } else {
        // The first and last control points may coincide with their neighbours.
        cp[3] - cp[0]
    };
    (lerp3(u, cp2[0], cp2[1]), d)
}

/// The two halves of a cubic Bezier, sharing their middle point.
fn subdivide(cp: &[Vec3; 4]) -> [Vec3; 7] {
    [
        cp[0],
        (cp[0] + cp[1]) / 2.0,
        (cp[0] + cp[1] * 2.0 + cp[2]) / 4.0,
        (cp[0] + cp[1] * 3.0 + cp[2] * 3.0 + cp[3]) / 8.0,
        (cp[1] + cp[2] * 2.0 + cp[3]) / 4.0,
        (cp[2] + cp[3]) / 2.0,
        cp[3],
    ]
}

/// The part [u0, u1] of a cubic Bezier, as a Bezier of its own.
pub fn bezier_part(cp: &[Vec3; 4], u0: f32, u1: f32) -> [Vec3; 4] {
    let (p0, d0) = evaluate_bezier(cp, u0);
    let (p1, d1) = evaluate_bezier(cp, u1);
    let s = (u1 - u0) / 3.0;
    [p0, p0 + d0 * s, p1 - d1 * s, p1]
}

/// A cubic B-spline span's Bezier control points (uniform knots).
pub fn bspline_to_bezier(p: &[Vec3; 4]) -> [Vec3; 4] {
    let p012 = lerp3(2.0 / 3.0, p[0], p[1]);
    let p121 = lerp3(1.0 / 3.0, p[1], p[2]);
    let p122 = lerp3(2.0 / 3.0, p[1], p[2]);
    let p232 = lerp3(1.0 / 3.0, p[2], p[3]);
    [lerp3(0.5, p012, p121), p121, p122, lerp3(0.5, p122, p232)]
}

/// A quadratic B-spline span's Bezier control points (uniform knots).
pub fn quadratic_bspline_to_bezier(p: &[Vec3; 3]) -> [Vec3; 3] {
    [lerp3(0.5, p[0], p[1]), p[1], lerp3(0.5, p[1], p[2])]
}

/// A quadratic Bezier as the cubic that traces it.
pub fn elevate_quadratic(p: &[Vec3; 3]) -> [Vec3; 4] {
    [p[0], lerp3(2.0 / 3.0, p[0], p[1]), lerp3(1.0 / 3.0, p[1], p[2]), p[2]]
}

/// The angle between unit vectors, accurate near 0 and pi (pbrt-v4's
/// `AngleBetween`).
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        std::f32::consts::PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).min(1.0).asin()
    }
}

/// Whether a ribbon's end normals can be interpolated: unit length, and
/// not so near opposite that the way between them is undefined.
pub fn ribbon_normals_valid(n: [Vec3; 2]) -> bool {
    n.iter().all(|v| v.is_finite() && (v.length() - 1.0).abs() < 1e-3)
        && angle_between(n[0], n[1]) < std::f32::consts::PI - 1e-3
}

/// The ray's frame: origin at its origin, z along its direction, y along
/// `up` made perpendicular to it (pbrt-v4's `LookAt`).
struct RayFrame {
    o: Vec3,
    x: Vec3,
    y: Vec3,
    z: Vec3,
}

impl RayFrame {
    fn new(ray: &Ray, up: Vec3) -> Option<RayFrame> {
        let z = ray.d.normalize();
        let x = up.normalize().cross(z);
        if x.length_squared() <= 0.0 || !x.is_finite() {
            return None;
        }
        let x = x.normalize();
        Some(RayFrame {
            o: ray.o,
            x,
            y: z.cross(x),
            z,
        })
    }

    fn point(&self, p: Vec3) -> Vec3 {
        let v = p - self.o;
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }

    fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }

    fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }
}

/// Whether the box of `cp` grown by `half_width` overlaps the ray's
/// segment from 0 to `z_max` (in the ray's frame).
fn overlaps_ray(cp: &[Vec3], half_width: f32, z_max: f32) -> bool {
    let mut b = Aabb::EMPTY;
    for &p in cp {
        b.grow(p);
    }
    b.min -= Vec3::splat(half_width);
    b.max += Vec3::splat(half_width);
    b.min.x <= 0.0 && b.max.x >= 0.0 && b.min.y <= 0.0 && b.max.y >= 0.0 && b.min.z <= z_max && b.max.z >= 0.0
}

impl Curve {
    pub fn width_at(&self, u: f32) -> f32 {
        lerp(u, self.width[0], self.width[1])
    }

    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &p in &self.cp {
            b.grow(p);
        }
        let r = 0.5 * self.width_at(self.u[0]).max(self.width_at(self.u[1]));
        b.min -= Vec3::splat(r);
        b.max += Vec3::splat(r);
        b
    }

    /// Whether the curve's numbers can be intersected: finite, widths > 0,
    /// and a ribbon's normals of unit length and not opposite.
    pub fn is_valid(&self) -> bool {
        self.cp.iter().all(|p| p.is_finite())
            && self.width.iter().all(|w| w.is_finite() && *w > 0.0)
            && self.u[0].is_finite()
            && self.u[1].is_finite()
            && (self.kind != CurveKind::Ribbon || ribbon_normals_valid(self.n))
    }

    /// A ribbon's normal at `u` along its segment: pbrt-v4's spherical
    /// interpolation of the two ends' normals.
    pub fn ribbon_normal(&self, u: f32) -> Vec3 {
        let angle = angle_between(self.n[0], self.n[1]);
        if angle == 0.0 {
            return self.n[0];
        }
        let inv_sin = 1.0 / angle.sin();
        self.n[0] * (((1.0 - u) * angle).sin() * inv_sin) + self.n[1] * ((u * angle).sin() * inv_sin)
    }

    /// The nearest hit in (t_min, t_max]. A hit closer to the ray's origin
    /// than the curve's width there is no hit: a ray leaving a curve starts
    /// within its width, and would meet the ribbon that turns to face it
    /// (pbrt-v4 starts such rays a width away instead). A ribbon, which
    /// does not turn, is closer only by what its own width along the ray
    /// can account for.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<CurveHit> {
        let mut up = ray.d.cross(self.cp[3] - self.cp[0]);
        if up.length_squared() <= 0.0 || !up.is_finite() {
            up = orthonormal_basis(ray.d.normalize()).0;
        }
        let frame = RayFrame::new(ray, up)?;
        let cp = self.cp.map(|p| frame.point(p));
        let len = ray.d.length();
        let z_max = len * t_max;
        let max_width = self.width_at(self.u[0]).max(self.width_at(self.u[1]));
        if !overlaps_ray(&cp, 0.5 * max_width, z_max) {
            return None;
        }
        // Subdivide until the pieces are within a twentieth of the width
        // of straight (pbrt-v4's refinement depth).
        let mut l0 = 0.0f32;
        for i in 0..2 {
            let d = cp[i] - cp[i + 1] * 2.0 + cp[i + 2];
            l0 = l0.max(d.x.abs()).max(d.y.abs()).max(d.z.abs());
        }
        let mut depth = 0;
        if l0 > 0.0 {
            let eps = self.width[0].max(self.width[1]) * 0.05;
            let x = std::f32::consts::SQRT_2 * 6.0 * l0 / (8.0 * eps);
            if x >= 1.0 && x.is_finite() {
                depth = ((x.log2().round() as i32) / 2).clamp(0, 10);
            } else if !x.is_finite() {
                depth = 10;
            }
        }
        let mut best: Option<CurveHit> = None;
        let mut search = Search {
            curve: self,
            frame: &frame,
            len,
            z_min: len * t_min,
            z_max,
            best: &mut best,
        };
        search.recurse(&cp, self.u[0], self.u[1], depth);
        best
    }
}

struct Search<'a> {
    curve: &'a Curve,
    frame: &'a RayFrame,
    len: f32,
    z_min: f32,
    z_max: f32,
    best: &'a mut Option<CurveHit>,
}

impl Search<'_> {
    fn recurse(&mut self, cp: &[Vec3; 4], u0: f32, u1: f32, depth: i32) {
        if depth > 0 {
            let split = subdivide(cp);
            let u = [u0, (u0 + u1) / 2.0, u1];
            for seg in 0..2 {
                let part = [
                    split[3 * seg],
                    split[3 * seg + 1],
                    split[3 * seg + 2],
                    split[3 * seg + 3],
                ];
                let w = self.curve.width_at(u[seg]).max(self.curve.width_at(u[seg + 1]));
                let z_max = self.best.map_or(self.z_max, |b| b.t * self.len);
                if overlaps_ray(&part, 0.5 * w, z_max) {
                    self.recurse(&part, u[seg], u[seg + 1], depth - 1);
                }
            }
            return;
        }
        // The ray's point (the origin of this frame) must lie between the
        // perpendiculars to the piece's tangents at its two ends.
        let edge = (cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x);
        if edge < 0.0 {
            return;
        }
        let edge = (cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x);
        if edge < 0.0 {
            return;
        }
        // The nearest point of the piece's chord.
        let dir = (cp[3] - cp[0]).truncate();
        let denom = dir.length_squared();
        if denom == 0.0 {
            return;
        }
        let w = (-cp[0].truncate()).dot(dir) / denom;
        let u = lerp(w, u0, u1).clamp(u0, u1);
        let width = self.curve.width_at(u);
        // A ribbon is as wide as it looks from the ray: its width times
        // the cosine between its normal and the ray (pbrt-v4's measure).
        // A ray leaving a curve starts within its width and would meet it
        // again: hits nearer than `near` are none (pbrt-v4 starts such rays
        // a width away instead). A flat or cylinder curve turns to face the
        // ray, so that is its width. A ribbon's point lies up to half its
        // width across from the axis, which puts the nearest axis point
        // that much times the cosine between the ray and the ribbon's
        // across direction, over the sine between the ray and the axis,
        // along the ray; and a hit point lies off the ribbon's plane by up
        // to half the width the ribbon shows the ray. A ray from another
        // surface beyond both still meets it.
        let (hit_width, ribbon_n, near) = match self.curve.kind {
            CurveKind::Ribbon => {
                let n = self.curve.ribbon_normal(u);
                let hit_width = width * n.dot(self.frame.z).abs();
                let along = (cp[3] - cp[0]).normalize_or_zero();
                let across = self.frame.to_local(n).cross(along).normalize_or_zero();
                let sin2 = (1.0 - along.z * along.z).max(1e-6);
                let leave = (0.5 * width * across.z.abs() / sin2.sqrt()).min(width);
                (hit_width, n, hit_width.max(leave))
            }
            _ => (width, Vec3::ZERO, width),
        };
        let (pc, dpcdw) = evaluate_bezier(cp, w.clamp(0.0, 1.0));
        let dist2 = pc.x * pc.x + pc.y * pc.y;
        if dist2 > hit_width * hit_width * 0.25 || hit_width <= 0.0 || hit_width.is_nan() {
            return;
        }
        if pc.z <= self.z_min || pc.z <= near || pc.z > self.z_max {
            return;
        }
        let t = pc.z / self.len;
        if self.best.is_some_and(|b| t > b.t) {
            return;
        }
        let dist = dist2.sqrt();
        let edge = dpcdw.x * -pc.y + pc.x * dpcdw.y;
        let v = if edge > 0.0 {
            0.5 + dist / hit_width
        } else {
            0.5 - dist / hit_width
        };
        // dp/du of the segment at u: the piece's derivative, over the
        // piece's share of the segment.
        let local = if self.curve.u[1] > self.curve.u[0] {
            (u - self.curve.u[0]) / (self.curve.u[1] - self.curve.u[0])
        } else {
            0.0
        };
        let (_, d) = evaluate_bezier(&self.curve.cp, local.clamp(0.0, 1.0));
        let dpdu = d / (self.curve.u[1] - self.curve.u[0]).max(f32::MIN_POSITIVE);
        if self.curve.kind == CurveKind::Ribbon {
            // Its own normal, made perpendicular to the axis.
            let dpdv = ribbon_n.cross(dpdu).normalize();
            let ng = dpdu.cross(dpdv).normalize();
            if ng.is_finite() {
                *self.best = Some(CurveHit {
                    t,
                    u,
                    v: v.clamp(0.0, 1.0),
                    dpdu,
                    ng,
                    ns: ng,
                });
            }
            return;
        }
        let dpdu_plane = self.frame.to_local(dpdu);
        let across = Vec3::new(-dpdu_plane.y, dpdu_plane.x, 0.0);
        if across.length_squared() <= 0.0 || !across.is_finite() || !dpdu.is_finite() {
            return;
        }
        let dpdv_flat = self.frame.to_world(across.normalize());
        let ng = dpdu.cross(dpdv_flat).normalize();
        let ns = match self.curve.kind {
            CurveKind::Flat | CurveKind::Ribbon => ng,
            CurveKind::Cylinder => {
                // dp/dv turned by -theta about dp/du; the normal with it.
                let theta = lerp(v, -90.0f32, 90.0).to_radians();
                let axis = dpdu.normalize();
                let dpdv = dpdv_flat * theta.cos() - axis.cross(dpdv_flat) * theta.sin();
                let n = dpdu.cross(dpdv).normalize();
                if n.dot(ng) > 0.0 && n.is_finite() {
                    n
                } else {
                    ng
                }
            }
        };
        if !ng.is_finite() {
            return;
        }
        *self.best = Some(CurveHit {
            t,
            u,
            v: v.clamp(0.0, 1.0),
            dpdu,
            ng,
            ns,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight curve along x from -1 to 1 at z = 0, of width `w`.
    fn straight(w: f32, kind: CurveKind) -> Curve {
        let p = |x: f32| Vec3::new(x, 0.0, 0.0);
        Curve {
            cp: [p(-1.0), p(-1.0 / 3.0), p(1.0 / 3.0), p(1.0)],
            u: [0.0, 1.0],
            width: [w, w],
            kind,
            n: [Vec3::Z; 2],
        }
    }

    #[test]
    fn a_ray_meets_a_straight_curve_within_half_its_width() {
        let c = straight(0.2, CurveKind::Flat);
        let down = Vec3::new(0.0, 0.0, -1.0);
        // Through the axis at x = 0.5: u = 0.75, v = 0.5, t = 2.
        let h = c
            .intersect(&Ray::new(Vec3::new(0.5, 0.0, 2.0), down), 0.0, f32::INFINITY)
            .unwrap();
        assert!(
            (h.t - 2.0).abs() < 1e-4 && (h.u - 0.75).abs() < 1e-4 && (h.v - 0.5).abs() < 1e-4,
            "{h:?}"
        );
        assert!((h.ng.z.abs() - 1.0).abs() < 1e-4, "{h:?}");
        assert!(h.dpdu.normalize().dot(Vec3::X).abs() > 0.9999);
        // Off the axis by 0.09 of 0.1: inside, v at the edge's side.
        let h = c
            .intersect(&Ray::new(Vec3::new(0.0, 0.09, 2.0), down), 0.0, f32::INFINITY)
            .unwrap();
        assert!((h.v - 0.5).abs() > 0.44 && (h.v - 0.5).abs() < 0.46, "{h:?}");
        // By 0.11: outside. Past the end: outside. Beyond t_max: none.
        assert!(c
            .intersect(&Ray::new(Vec3::new(0.0, 0.11, 2.0), down), 0.0, f32::INFINITY)
            .is_none());
        assert!(c
            .intersect(&Ray::new(Vec3::new(1.05, 0.0, 2.0), down), 0.0, f32::INFINITY)
            .is_none());
        assert!(c
            .intersect(&Ray::new(Vec3::new(0.0, 0.0, 2.0), down), 0.0, 1.9)
            .is_none());
        // Seen from the side (a ray along y), the ribbon faces that ray too.
        let h = c
            .intersect(&Ray::new(Vec3::new(0.2, -3.0, 0.05), Vec3::Y), 0.0, f32::INFINITY)
            .unwrap();
        assert!((h.t - 3.0).abs() < 1e-3 && (h.ng.y.abs() - 1.0).abs() < 1e-4, "{h:?}");
    }

    #[test]
    fn a_ray_leaving_a_curve_does_not_meet_it_again() {
        let c = straight(0.2, CurveKind::Cylinder);
        for d in [
            Vec3::new(0.3, 0.5, 1.0),
            Vec3::new(0.0, -0.2, -1.0),
            Vec3::new(-1.0, 0.1, 0.2),
        ] {
            let o = Vec3::new(0.1, 0.03, 0.0);
            assert!(
                c.intersect(&Ray::new(o, d.normalize()), 0.0, f32::INFINITY).is_none(),
                "{d}"
            );
        }
        // A ribbon in the z = 0 plane: rays leaving a point of it just off
        // its plane, on either side, do not meet it again; but a ray from a
        // point nearer than its width, to which it looks narrower, meets it
        // (at its axis' depth, as pbrt-v4 has it).
        let mut r = straight(0.2, CurveKind::Ribbon);
        r.n = [Vec3::Z; 2];
        for side in [1e-5f32, -1e-5] {
            for d in [
                Vec3::new(0.3, 0.5, 1.0),
                Vec3::new(0.0, -0.2, 1.0),
                Vec3::new(-1.0, 0.1, 0.2),
                Vec3::new(0.2, 0.9, 0.05),
            ] {
                let d = d * side.signum();
                let o = Vec3::new(0.1, 0.03, side);
                assert!(
                    r.intersect(&Ray::new(o, d.normalize()), 0.0, f32::INFINITY).is_none(),
                    "{d}"
                );
            }
        }
        let d = Vec3::new(0.0, 0.8, -0.6);
        let h = r
            .intersect(&Ray::new(Vec3::new(0.3, 0.03, 0.0) - d * 0.15, d), 0.0, f32::INFINITY)
            .unwrap();
        assert!((h.t - 0.126).abs() < 1e-4, "{h:?}");
        let flat = straight(0.2, CurveKind::Flat);
        assert!(flat
            .intersect(&Ray::new(Vec3::new(0.3, 0.03, 0.0) - d * 0.15, d), 0.0, f32::INFINITY)
            .is_none());
    }

    #[test]
    fn a_bent_curve_is_met_where_its_bezier_is() {
        // An arc: the Bezier's point at u = 0.5 is (0, 0.75, 0); a ray down
        // through it meets the curve there, one at x = 0 but y = 0 does not.
        let c = Curve {
            cp: [
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
            ],
            u: [0.0, 1.0],
            width: [0.05, 0.05],
            kind: CurveKind::Flat,
            n: [Vec3::ZERO; 2],
        };
        let down = Vec3::new(0.0, 0.0, -1.0);
        let h = c
            .intersect(&Ray::new(Vec3::new(0.0, 0.75, 1.0), down), 0.0, f32::INFINITY)
            .unwrap();
        assert!((h.u - 0.5).abs() < 0.01 && (h.t - 1.0).abs() < 1e-3, "{h:?}");
        assert!(c
            .intersect(&Ray::new(Vec3::new(0.0, 0.0, 1.0), down), 0.0, f32::INFINITY)
            .is_none());
        // A point off the middle: (u = 0.25) at x = -0.5625, y = 0.5625.
        let (p, _) = evaluate_bezier(&c.cp, 0.25);
        let h = c.intersect(&Ray::new(p + Vec3::Z, down), 0.0, f32::INFINITY).unwrap();
        assert!((h.u - 0.25).abs() < 0.01, "{h:?}");
    }

    #[test]
    fn the_cylinders_normal_turns_across_its_width() {
        let c = straight(0.2, CurveKind::Cylinder);
        let down = Vec3::new(0.0, 0.0, -1.0);
        let at = |y: f32| {
            c.intersect(&Ray::new(Vec3::new(0.0, y, 2.0), down), 0.0, f32::INFINITY)
                .unwrap()
        };
        let (a, b, m) = (at(-0.08), at(0.08), at(0.0));
        assert!((m.ns.dot(m.ng) - 1.0).abs() < 1e-4);
        // 0.8 of the half width: turned by 72 degrees, to either side.
        for h in [a, b] {
            assert!((h.ns.dot(h.ng) - 72f32.to_radians().cos()).abs() < 1e-3, "{h:?}");
            assert!(h.ns.x.abs() < 1e-4);
        }
        assert!(a.ns.y * b.ns.y < 0.0);
    }

    #[test]
    fn a_ribbon_is_as_wide_as_it_looks_from_the_ray() {
        // A strip in the z = 0 plane, 0.2 wide across y: rays that come in
        // at 60 degrees from its normal meet it where they cross the strip,
        // and no ray meets it edge on.
        let mut c = straight(0.2, CurveKind::Ribbon);
        c.n = [Vec3::Z; 2];
        let d = Vec3::new(0.0, 60f32.to_radians().sin(), -60f32.to_radians().cos());
        let aim = |y: f32| Ray::new(Vec3::new(0.3, y, 0.0) - d * 2.0, d);
        let h = c.intersect(&aim(0.09), 0.0, f32::INFINITY).unwrap();
        assert!((h.ng.z.abs() - 1.0).abs() < 1e-5 && h.ns == h.ng, "{h:?}");
        assert!((h.v - 0.95).abs() < 0.01 || (h.v - 0.05).abs() < 0.01, "{h:?}");
        assert!(c.intersect(&aim(-0.09), 0.0, f32::INFINITY).is_some());
        assert!(c.intersect(&aim(0.11), 0.0, f32::INFINITY).is_none());
        assert!(c.intersect(&aim(-0.11), 0.0, f32::INFINITY).is_none());
        // A flat curve turns to face that ray: seen at its whole width, it
        // is met by the ray aimed 0.11 across as well.
        let flat = straight(0.2, CurveKind::Flat);
        assert!(flat.intersect(&aim(0.11), 0.0, f32::INFINITY).is_some());
        let edge_on = Ray::new(Vec3::new(0.3, -2.0, 0.0), Vec3::Y);
        assert!(c.intersect(&edge_on, 0.0, f32::INFINITY).is_none());
        assert!(flat.intersect(&edge_on, 0.0, f32::INFINITY).is_some());
    }

    #[test]
    fn a_ribbons_normal_turns_between_its_ends_as_pbrt_turns_it() {
        // From +z to +y along the segment: a quarter turn about x, at a
        // constant rate (spherical interpolation), perpendicular to the axis.
        let mut c = straight(0.2, CurveKind::Ribbon);
        c.n = [Vec3::Z, Vec3::Y];
        assert!(c.is_valid());
        for u in [0.0f32, 0.25, 1.0 / 3.0, 0.8, 1.0] {
            let a = u * std::f32::consts::FRAC_PI_2;
            let want = Vec3::new(0.0, a.sin(), a.cos());
            assert!((c.ribbon_normal(u) - want).length() < 1e-5, "{u}");
        }
        // Straight down at x = -1/3 (u = 1/3): the normal is 30 degrees
        // from the ray's line, the ribbon cos 30 as wide.
        let down = Vec3::new(0.0, 0.0, -1.0);
        let at = |y: f32| c.intersect(&Ray::new(Vec3::new(-1.0 / 3.0, y, 2.0), down), 0.0, f32::INFINITY);
        let h = at(0.0).unwrap();
        assert!((h.u - 1.0 / 3.0).abs() < 1e-3, "{h:?}");
        assert!(h.ng.dot(Vec3::new(0.0, 0.5, 0.75f32.sqrt())).abs() > 0.9999, "{h:?}");
        let half = 0.1 * 30f32.to_radians().cos();
        assert!(at(half - 0.004).is_some() && at(half + 0.004).is_none());
        // Normals that point opposite ways have no way between them.
        c.n = [Vec3::Z, -Vec3::Z];
        assert!(!c.is_valid());
    }

    #[test]
    fn b_splines_and_parts_trace_the_same_curve() {
        let p = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(3.0, 2.0, 1.0),
            Vec3::new(4.0, 0.0, 0.0),
        ];
        // A uniform cubic B-spline span starts at (p0 + 4 p1 + p2) / 6.
        let b = bspline_to_bezier(&p);
        assert!((b[0] - (p[0] + p[1] * 4.0 + p[2]) / 6.0).length() < 1e-5);
        assert!((b[3] - (p[1] + p[2] * 4.0 + p[3]) / 6.0).length() < 1e-5);
        // A part of a Bezier is the Bezier on that range.
        let part = bezier_part(&p, 0.25, 0.75);
        for s in [0.0, 0.3, 0.6, 1.0] {
            let (a, _) = evaluate_bezier(&part, s);
            let (e, _) = evaluate_bezier(&p, 0.25 + 0.5 * s);
            assert!((a - e).length() < 1e-5, "{a} vs {e}");
        }
        // A quadratic raised to a cubic is the same curve.
        let q = [p[0], p[1], p[2]];
        let c = elevate_quadratic(&q);
        let (a, _) = evaluate_bezier(&c, 0.5);
        assert!((a - (q[0] * 0.25 + q[1] * 0.5 + q[2] * 0.25)).length() < 1e-5);
    }
}
