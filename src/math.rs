//! Vector types and the few helpers the renderer needs beyond glam.

pub use glam::{Vec2, Vec3};

/// A ray with origin `o` and direction `d` (not necessarily unit length for
/// shadow rays, always unit for camera and scattering rays), at `time`
/// within the camera's shutter interval (where moving shapes are met).
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    pub time: f32,
}

impl Ray {
    /// A ray at time 0 (the shutter's opening by default).
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Ray { o, d, time: 0.0 }
    }

    /// A ray at `time`: a path's later segments keep its camera ray's time.
    pub fn timed(o: Vec3, d: Vec3, time: f32) -> Self {
        Ray { o, d, time }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// Builds an orthonormal basis (s, t) around the unit vector `n`.
/// Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 2017): branchless
/// and free of the precision loss of the cross-product method near the poles.
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    (s, t)
}

/// Maps a direction given in the local frame (z = `n`) to world space.
pub fn to_world(local: Vec3, n: Vec3) -> Vec3 {
    let (s, t) = orthonormal_basis(n);
    s * local.x + t * local.y + n * local.z
}

/// Rec. 709 luminance of a linear RGB value.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Offsets a ray origin along the geometric normal so that the new ray does not
/// re-hit the surface it leaves; scaled by the magnitude of the point because
/// float spacing grows with it. Hit points lie on their surface to within a
/// few units in the last place (`Scene::intersect` puts them there), some
/// 3e-7 of their magnitude: 1e-5 leaves a wide margin, and a surface as
/// close behind as the two sides of a thin sheet (a blind's slat 2.5e-4
/// thick at 3 units from the origin, in a real scene) is still met. A
/// larger offset stepped over it and let light through.
pub fn offset_origin(p: Vec3, n: Vec3, towards: Vec3) -> Vec3 {
    let eps = 1e-5 * (1.0 + p.abs().max_element());
    if n.dot(towards) >= 0.0 {
        p + n * eps
    } else {
        p - n * eps
    }
}

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn from_point(p: Vec3) -> Self {
        Aabb { min: p, max: p }
    }

    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    pub fn surface_area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }

    /// Whether `ray` meets the box between its origin and `t_max` (slabs;
    /// a ray along a face may count either way).
    pub fn hit_by(&self, ray: &Ray, t_max: f32) -> bool {
        let inv = ray.d.recip();
        let a = (self.min - ray.o) * inv;
        let b = (self.max - ray.o) * inv;
        let near = a.min(b).max_element().max(0.0);
        let far = a.max(b).min_element().min(t_max);
        near <= far
    }
}
