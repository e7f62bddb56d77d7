//! An orthonormal frame for moving directions between world space and the
//! local shading frame in which BxDFs work (pbrt-v4's `Frame`, `util/vecmath.h`).

use crate::math::{orthonormal_basis, Vec3};

/// Right-handed orthonormal basis: `x` x `y` = `z`; `z` is the shading normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl Frame {
    /// A frame around the unit normal `z`, with an arbitrary (but
    /// continuous away from z = -1) tangent.
    pub fn from_z(z: Vec3) -> Self {
        let (x, y) = orthonormal_basis(z);
        Frame { x, y, z }
    }

    /// A frame around the unit normal `z` whose x axis is `x` made
    /// orthogonal to `z`: anisotropic BxDFs follow the surface's dp/du this
    /// way. Falls back to [`Frame::from_z`] when `x` is (nearly) parallel to
    /// `z` or not finite.
    pub fn from_xz(x: Vec3, z: Vec3) -> Self {
        let t = x - z * z.dot(x);
        let len2 = t.length_squared();
        if len2 <= 1e-12 || !len2.is_finite() {
            return Frame::from_z(z);
        }
        let x = t / len2.sqrt();
        Frame { x, y: z.cross(x), z }
    }

    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }

    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_and_invert() {
        let normals = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::new(-1.0, 2.0, -0.5).normalize(),
        ];
        for n in normals {
            for f in [Frame::from_z(n), Frame::from_xz(Vec3::new(1.0, 0.2, 0.1), n)] {
                assert!((f.x.cross(f.y) - f.z).length() < 1e-5, "{f:?}");
                assert!(f.x.dot(f.z).abs() < 1e-6 && f.y.dot(f.z).abs() < 1e-6);
                let v = Vec3::new(0.2, -0.7, 0.4);
                assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
                assert!((f.to_local(n) - Vec3::Z).length() < 1e-5);
            }
        }
        // A tangent parallel to the normal falls back to an arbitrary one.
        let f = Frame::from_xz(Vec3::Z * 2.0, Vec3::Z);
        assert_eq!(f, Frame::from_z(Vec3::Z));
        // The given tangent is kept when it is one.
        let f = Frame::from_xz(Vec3::Y, Vec3::Z);
        assert!((f.x - Vec3::Y).length() < 1e-6 && (f.y + Vec3::X).length() < 1e-6);
    }
}
