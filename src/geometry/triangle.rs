//! Ray-triangle intersection in a precomputed layout (vertex + two edges).
//!
//! Two tests are kept: Cramer's rule, as the original coursework solved the
//! 3x3 system, and Moller-Trumbore (1997), which is the same solution with the
//! shared cross products factored out. `cargo bench --bench intersect`
//! compares them; Moller-Trumbore is the default.

use crate::math::{Aabb, Ray, Vec3};

/// A triangle stored as `v0` and the edges `e1 = v1 - v0`, `e2 = v2 - v0`, the
/// layout both tests read directly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub v0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
}

/// Which ray-triangle test to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TriangleTest {
    #[default]
    MollerTrumbore,
    Cramer,
}

/// Where a ray meets a triangle: distance and barycentrics of v1 and v2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl Triangle {
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        Triangle {
            v0: a,
            e1: b - a,
            e2: c - a,
        }
    }

    pub fn vertices(&self) -> [Vec3; 3] {
        [self.v0, self.v0 + self.e1, self.v0 + self.e2]
    }

    /// Unnormalised geometric normal (e1 x e2); its length is twice the area.
    pub fn normal_raw(&self) -> Vec3 {
        self.e1.cross(self.e2)
    }

    pub fn area(&self) -> f32 {
        0.5 * self.normal_raw().length()
    }

    pub fn bounds(&self) -> Aabb {
        let [a, b, c] = self.vertices();
        let mut bb = Aabb::from_point(a);
        bb.grow(b);
        bb.grow(c);
        bb
    }

    pub fn centroid(&self) -> Vec3 {
        self.v0 + (self.e1 + self.e2) * (1.0 / 3.0)
    }

    pub fn point_at(&self, u: f32, v: f32) -> Vec3 {
        self.v0 + self.e1 * u + self.e2 * v
    }

    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32, test: TriangleTest) -> Option<TriHit> {
        match test {
            TriangleTest::MollerTrumbore => self.intersect_mt(ray, t_min, t_max),
            TriangleTest::Cramer => self.intersect_cramer(ray, t_min, t_max),
        }
    }

    /// Moller-Trumbore. Both faces are hit; a ray in the triangle's plane misses.
    #[inline(always)]
    pub fn intersect_mt(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<TriHit> {
        let p = ray.d.cross(self.e2);
        let det = self.e1.dot(p);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let s = ray.o - self.v0;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = ray.d.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = self.e2.dot(q) * inv;
        if t > t_min && t < t_max {
            Some(TriHit { t, u, v })
        } else {
            None
        }
    }

    /// Cramer's rule on `[e1 e2 -d] (u v t)^T = o - v0`, each unknown the ratio
    /// of a determinant with one column replaced to the system's determinant.
    pub fn intersect_cramer(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<TriHit> {
        let (a, b, c) = (self.e1, self.e2, -ray.d);
        let s = ray.o - self.v0;
        let det3 = |x: Vec3, y: Vec3, z: Vec3| -> f32 {
            x.x * (y.y * z.z - z.y * y.z) - y.x * (x.y * z.z - z.y * x.z) + z.x * (x.y * y.z - y.y * x.z)
        };
        let det = det3(a, b, c);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let u = det3(s, b, c) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let v = det3(a, s, c) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = det3(a, b, s) * inv;
        if t > t_min && t < t_max {
            Some(TriHit { t, u, v })
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn tri() -> Triangle {
        Triangle::new(
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        )
    }

    fn both(ray: Ray) -> [Option<TriHit>; 2] {
        let t = tri();
        [
            t.intersect_mt(&ray, 0.0, f32::INFINITY),
            t.intersect_cramer(&ray, 0.0, f32::INFINITY),
        ]
    }

    #[test]
    fn hit_inside_reports_distance_and_barycentrics() {
        for h in both(Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::Z)) {
            let h = h.expect("must hit");
            assert!((h.t - 1.0).abs() < 1e-6);
            assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.25).abs() < 1e-6);
        }
    }

    #[test]
    fn miss_outside() {
        for h in both(Ray::new(Vec3::new(0.8, 0.8, 0.0), Vec3::Z)) {
            assert!(h.is_none());
        }
        for h in both(Ray::new(Vec3::new(-0.01, 0.5, 0.0), Vec3::Z)) {
            assert!(h.is_none());
        }
    }

    #[test]
    fn edges_and_vertices_are_hit() {
        for o in [
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ] {
            for h in both(Ray::new(o, Vec3::Z)) {
                let h = h.unwrap_or_else(|| panic!("edge/vertex {o:?} must hit"));
                assert!((h.t - 1.0).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn parallel_ray_misses() {
        for h in both(Ray::new(Vec3::new(-1.0, 0.25, 1.0), Vec3::X)) {
            assert!(h.is_none());
        }
        for h in both(Ray::new(Vec3::new(-1.0, 0.25, 0.5), Vec3::X)) {
            assert!(h.is_none());
        }
    }

    #[test]
    fn hit_behind_origin_is_rejected() {
        for h in both(Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::Z)) {
            assert!(h.is_none());
        }
    }

    #[test]
    fn both_faces_are_hit() {
        for h in both(Ray::new(Vec3::new(0.25, 0.25, 2.0), -Vec3::Z)) {
            assert!((h.expect("back face must hit").t - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn respects_t_range() {
        let ray = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::Z);
        assert!(tri().intersect_mt(&ray, 0.0, 0.9).is_none());
        assert!(tri().intersect_cramer(&ray, 1.1, 5.0).is_none());
    }

    #[test]
    fn cramer_and_moller_trumbore_agree_on_random_rays() {
        let mut rng = Rng::new(42, 1);
        fn rng_u(r: &mut Rng) -> f32 {
            r.next_f32() * 0.7
        }
        let mut gen = Rng::new(43, 2);
        let mut r3 = |s: f32| Vec3::new(gen.next_f32(), gen.next_f32(), gen.next_f32()) * s - Vec3::splat(s / 2.0);
        let (mut hits, mut disagreements) = (0, 0);
        for _ in 0..20_000 {
            let t = Triangle::new(r3(2.0), r3(2.0), r3(2.0));
            // Aim near the triangle so that most rays hit and many graze edges.
            let o = r3(6.0);
            let target = t.point_at(rng_u(&mut rng), rng_u(&mut rng)) + r3(0.2);
            let ray = Ray::new(o, (target - o).normalize());
            let a = t.intersect_mt(&ray, 0.0, f32::INFINITY);
            let b = t.intersect_cramer(&ray, 0.0, f32::INFINITY);
            match (a, b) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert!((a.t - b.t).abs() <= 1e-3 * a.t.max(1.0), "{a:?} vs {b:?}");
                    assert!((a.u - b.u).abs() < 1e-3 && (a.v - b.v).abs() < 1e-3);
                }
                (None, None) => {}
                // Rays grazing an edge may round differently in the two formulas.
                _ => disagreements += 1,
            }
        }
        assert!(hits > 1000, "too few hits ({hits}) to compare");
        assert!(disagreements <= 5, "{disagreements} disagreements");
    }
}
