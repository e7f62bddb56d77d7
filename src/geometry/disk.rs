//! Disks and annuli, as pbrt-v4's `disk` shape: in world space, a centre,
//! a unit normal, an outer and an inner radius, and the two axes the
//! parametrisation measures its angle from.
//!
//! pbrt-v4's disk lies in the plane z = height of its object space, with
//! normal +z (negated by `ReverseOrientation` or a transformation that swaps
//! handedness), and is parametrised by
//!
//! ```text
//! phi = atan2(y, x) in [0, 2 pi)     u = phi / phi_max
//! r   = sqrt(x^2 + y^2)              v = (radius - r) / (radius - inner_radius)
//! dp/du = (-phi_max y, phi_max x, 0)
//! ```
//!
//! Here (x, y) are the hit's coordinates along `axes[0]` and `axes[1]`, the
//! world directions of the object's x and y axes, and phi_max = 2 pi (partial
//! disks are not supported). A ray meets the disk from either side; the
//! normal says which side is the front (for one-sided emission), shading is
//! two-sided like every other surface's.

use crate::math::{orthonormal_basis, Aabb, Ray, Vec2, Vec3};
use std::f32::consts::TAU;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    pub centre: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    pub radius: f32,
    /// Radius of the hole, in [0, radius).
    pub inner_radius: f32,
    /// Unit, perpendicular to each other and to `normal`: where the
    /// parametrisation's phi = 0 and phi = pi / 2 point.
    pub axes: [Vec3; 2],
}

impl Disk {
    /// A disk from its description: the normal is normalised; `axes`, if
    /// given, are projected into the disk's plane and made orthonormal (the
    /// first keeps its direction, the second its side of the first); without
    /// them the axes are `math::orthonormal_basis(normal)` (for normal +z,
    /// the x and y axes, as pbrt's disk without a transformation). The error
    /// says what is wrong: a radius not > 0, an inner radius outside
    /// [0, radius), a zero or non-finite normal, degenerate axes.
    pub fn new(
        centre: Vec3,
        normal: Vec3,
        radius: f32,
        inner_radius: f32,
        axes: Option<[Vec3; 2]>,
    ) -> Result<Disk, String> {
        if !centre.is_finite() {
            return Err(format!("centre {:?} is not finite", centre.to_array()));
        }
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(format!("radius {radius} must be > 0"));
        }
        if !(inner_radius >= 0.0 && inner_radius < radius) {
            return Err(format!(
                "inner_radius {inner_radius} must be >= 0 and less than the radius {radius}"
            ));
        }
        let n = normal.normalize_or_zero();
        if n == Vec3::ZERO || !n.is_finite() {
            return Err(format!("normal {:?} must be a non-zero direction", normal.to_array()));
        }
        let axes = match axes {
            None => {
                let (s, t) = orthonormal_basis(n);
                [s, t]
            }
            Some([a, b]) => {
                let x = (a - n * a.dot(n)).normalize_or_zero();
                let y = (b - n * b.dot(n) - x * b.dot(x)).normalize_or_zero();
                if x == Vec3::ZERO || y == Vec3::ZERO || !x.is_finite() || !y.is_finite() {
                    return Err(format!(
                        "axes {:?}, {:?} do not span the disk's plane",
                        a.to_array(),
                        b.to_array()
                    ));
                }
                [x, y]
            }
        };
        Ok(Disk {
            centre,
            normal: n,
            radius,
            inner_radius,
            axes,
        })
    }

    /// Nearest intersection in (t_min, t_max), as pbrt-v4's `Disk`: the
    /// plane's, if it lies within the annulus (its edges included).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let dn = ray.d.dot(self.normal);
        if dn == 0.0 {
            return None;
        }
        let t = (self.centre - ray.o).dot(self.normal) / dn;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let dist2 = (ray.at(t) - self.centre).length_squared();
        if dist2 > self.radius * self.radius || dist2 < self.inner_radius * self.inner_radius {
            return None;
        }
        Some(t)
    }

    /// Texture coordinates and dp/du at a point of the disk, by pbrt-v4's
    /// formulas (see the module's documentation). dp/du is zero at the centre.
    pub fn uv_dpdu(&self, p: Vec3) -> (Vec2, Vec3) {
        let q = p - self.centre;
        let (x, y) = (q.dot(self.axes[0]), q.dot(self.axes[1]));
        let phi = y.atan2(x);
        let phi = if phi < 0.0 { phi + TAU } else { phi };
        let r = (x * x + y * y).sqrt();
        let uv = Vec2::new(phi / TAU, (self.radius - r) / (self.radius - self.inner_radius));
        let dpdu = (self.axes[1] * x - self.axes[0] * y) * TAU;
        (uv, dpdu)
    }

    /// The point at texture coordinates (u, v): the inverse of `uv_dpdu`.
    pub fn point_at(&self, uv: Vec2) -> Vec3 {
        let phi = uv.x * TAU;
        let r = self.radius - uv.y * (self.radius - self.inner_radius);
        self.centre + (self.axes[0] * phi.cos() + self.axes[1] * phi.sin()) * r
    }

    /// The tight box of the outer circle.
    pub fn bounds(&self) -> Aabb {
        let n = self.normal;
        let e = (Vec3::ONE - n * n).max(Vec3::ZERO).map(f32::sqrt) * self.radius;
        Aabb {
            min: self.centre - e,
            max: self.centre + e,
        }
    }

    pub fn area(&self) -> f32 {
        std::f32::consts::PI * (self.radius * self.radius - self.inner_radius * self.inner_radius)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn annulus() -> Disk {
        Disk::new(Vec3::new(0.0, 0.0, 2.0), Vec3::Z, 1.0, 0.5, None).unwrap()
    }

    #[test]
    fn hits_the_annulus_from_both_sides_and_misses_the_hole() {
        let d = annulus();
        let down = Ray::new(Vec3::new(0.75, 0.0, 5.0), -Vec3::Z);
        assert_eq!(d.intersect(&down, 0.0, f32::INFINITY), Some(3.0));
        let up = Ray::new(Vec3::new(0.0, -0.75, -1.0), Vec3::Z);
        assert_eq!(d.intersect(&up, 0.0, f32::INFINITY), Some(3.0));
        // The hole, outside, parallel, behind, beyond t_max.
        let hole = Ray::new(Vec3::new(0.25, 0.25, 5.0), -Vec3::Z);
        assert_eq!(d.intersect(&hole, 0.0, f32::INFINITY), None);
        let outside = Ray::new(Vec3::new(0.8, 0.8, 5.0), -Vec3::Z);
        assert_eq!(d.intersect(&outside, 0.0, f32::INFINITY), None);
        let parallel = Ray::new(Vec3::new(-5.0, 0.75, 2.0), Vec3::X);
        assert_eq!(d.intersect(&parallel, 0.0, f32::INFINITY), None);
        assert_eq!(d.intersect(&down, 3.0, f32::INFINITY), None);
        assert_eq!(d.intersect(&down, 0.0, 3.0), None);
    }

    #[test]
    fn rejects_bad_shapes() {
        assert!(Disk::new(Vec3::ZERO, Vec3::Z, 0.0, 0.0, None).is_err());
        assert!(Disk::new(Vec3::ZERO, Vec3::Z, 1.0, 1.0, None).is_err());
        assert!(Disk::new(Vec3::ZERO, Vec3::Z, 1.0, -0.1, None).is_err());
        assert!(Disk::new(Vec3::ZERO, Vec3::ZERO, 1.0, 0.0, None).is_err());
        assert!(Disk::new(Vec3::ZERO, Vec3::Z, 1.0, 0.0, Some([Vec3::Z, Vec3::Y])).is_err());
        assert!(Disk::new(Vec3::ZERO, Vec3::Z, 1.0, 0.0, Some([Vec3::X, Vec3::X])).is_err());
    }

    /// pbrt-v4's `Disk::InteractionFromIntersection` for a disk of radius r,
    /// inner radius ri at height h, without a transformation.
    fn pbrt(p: Vec3, r: f32, ri: f32) -> (Vec2, Vec3) {
        let phi_max = 2.0 * std::f32::consts::PI;
        let mut phi = p.y.atan2(p.x);
        if phi < 0.0 {
            phi += 2.0 * std::f32::consts::PI;
        }
        let r_hit = (p.x * p.x + p.y * p.y).sqrt();
        let u = phi / phi_max;
        let v = (r - r_hit) / (r - ri);
        (Vec2::new(u, v), Vec3::new(-phi_max * p.y, phi_max * p.x, 0.0))
    }

    #[test]
    fn uv_and_dpdu_are_pbrts() {
        let d = Disk::new(Vec3::new(0.0, 0.0, 0.5), Vec3::Z, 2.0, 0.5, None).unwrap();
        assert_eq!(d.axes, [Vec3::X, Vec3::Y]);
        for p in [
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::new(0.0, 1.5, 0.5),
            Vec3::new(-0.7, -0.9, 0.5),
            Vec3::new(1.2, -1.1, 0.5),
            Vec3::new(-2.0, 0.0, 0.5),
        ] {
            let (uv, dpdu) = d.uv_dpdu(p);
            let (want_uv, want_dpdu) = pbrt(p, 2.0, 0.5);
            assert!((uv - want_uv).abs().max_element() < 1e-6, "{p}: {uv} vs {want_uv}");
            assert!(
                (dpdu - want_dpdu).abs().max_element() < 1e-5,
                "{p}: {dpdu} vs {want_dpdu}"
            );
            assert!((d.point_at(uv) - p).length() < 1e-5);
        }
        // Named points: phi = 0 on the outer edge is (0, 0); a quarter turn
        // on the inner edge is (0.25, 1).
        let (uv, _) = d.uv_dpdu(Vec3::new(2.0, 0.0, 0.5));
        assert!((uv - Vec2::new(0.0, 0.0)).length() < 1e-6);
        let (uv, _) = d.uv_dpdu(Vec3::new(0.0, 0.5, 0.5));
        assert!((uv - Vec2::new(0.25, 1.0)).length() < 1e-6);
    }

    #[test]
    fn axes_carry_a_transformation() {
        // pbrt: Translate 1 2 3, Rotate 90 about x, disk radius 1: the object's
        // x stays x, its y goes to z, its z (the normal) to -y.
        let d = Disk::new(Vec3::new(1.0, 2.0, 3.0), -Vec3::Y, 1.0, 0.0, Some([Vec3::X, Vec3::Z])).unwrap();
        // Object point (0, 0.5, 0): phi = pi / 2, r = 0.5.
        let (uv, dpdu) = d.uv_dpdu(Vec3::new(1.0, 2.0, 3.5));
        assert!((uv - Vec2::new(0.25, 0.5)).length() < 1e-6);
        // dp/du = (-2 pi 0.5, 0, 0) in object space, (-pi, 0, 0) in world.
        assert!((dpdu - Vec3::new(-std::f32::consts::PI, 0.0, 0.0)).length() < 1e-5);
        // Given axes are made orthonormal in the plane.
        let d = Disk::new(
            Vec3::ZERO,
            Vec3::Z,
            1.0,
            0.0,
            Some([Vec3::new(2.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 0.0)]),
        )
        .unwrap();
        assert_eq!(d.axes, [Vec3::X, Vec3::Y]);
    }

    #[test]
    fn bounds_are_tight_and_contain_the_rim() {
        let n = Vec3::new(1.0, 2.0, -0.5).normalize();
        let d = Disk::new(Vec3::new(0.3, -1.0, 2.0), n, 1.5, 0.0, None).unwrap();
        let b = d.bounds();
        let mut seen = Aabb::EMPTY;
        for i in 0..3600 {
            let p = d.point_at(Vec2::new(i as f32 / 3600.0, 0.0));
            seen.grow(p);
            assert!(p.cmpge(b.min - Vec3::splat(1e-5)).all() && p.cmple(b.max + Vec3::splat(1e-5)).all());
        }
        assert!((seen.min - b.min).abs().max_element() < 1e-4);
        assert!((seen.max - b.max).abs().max_element() < 1e-4);
        assert!((d.area() - std::f32::consts::PI * 2.25).abs() < 1e-5);
    }
}
