//! Placing a mesh in the scene. A vertex p goes to world space in this order:
//! scale (per axis), rotate about x, then y, then z (degrees, right-handed),
//! then, with a fit, a uniform scale and shift that put the box's bottom centre
//! at a given point with a given height, and last the translation.
//!
//! World y points down (SCENES.md), so the *bottom* of a bounding box is its
//! face at the largest y: a fitted mesh stands on the plane y = point.y.
//! The arithmetic is done in f64 and multiples of 90 degrees are exact, so a
//! turn of 180 degrees moves no vertex off its mirror image.

use super::mesh::{Mesh, PlacedVertices};
use crate::error::{Error, Result};
use crate::math::Vec3;
use glam::{DMat3, DVec3};

/// Scale the (rotated) mesh uniformly to `height` along y and put the centre
/// of its bounding box's bottom face (largest y) at `bottom_centre`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fit {
    pub height: f32,
    pub bottom_centre: Vec3,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Per-axis scale, applied first; no component may be zero.
    pub scale: Vec3,
    /// Rotations about x, y and z in degrees, applied in that order.
    pub rotate_deg: Vec3,
    pub fit: Option<Fit>,
    /// Added last.
    pub translate: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            scale: Vec3::ONE,
            rotate_deg: Vec3::ZERO,
            fit: None,
            translate: Vec3::ZERO,
        }
    }
}

/// Sine and cosine of an angle in degrees, exact at multiples of 90.
fn sin_cos_deg(deg: f64) -> (f64, f64) {
    let r = deg.rem_euclid(360.0);
    if r % 90.0 == 0.0 {
        match (r / 90.0) as u32 {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        }
    } else {
        r.to_radians().sin_cos()
    }
}

/// The rotation of `rotate` degrees about x, then y, then z (as a mesh's).
pub fn rotation(rotate_deg: Vec3) -> glam::Mat3 {
    Transform {
        rotate_deg,
        ..Transform::default()
    }
    .linear()
    .as_mat3()
}

impl Transform {
    /// Checks the numbers a user gave; the message names the offending key.
    pub fn validate(&self) -> std::result::Result<(), String> {
        if !self.scale.is_finite() || self.scale.cmpeq(Vec3::ZERO).any() {
            return Err(format!("scale {:?} must be finite and non-zero", self.scale.to_array()));
        }
        if !self.rotate_deg.is_finite() || !self.translate.is_finite() {
            return Err("rotate and translate must be finite".into());
        }
        if let Some(f) = &self.fit {
            if !(f.height.is_finite() && f.height > 0.0 && f.bottom_centre.is_finite()) {
                return Err(format!("fit height {} must be a finite number > 0", f.height));
            }
        }
        Ok(())
    }

    /// Rotation and scale as one matrix: Rz * Ry * Rx * S.
    fn linear(&self) -> DMat3 {
        let r = self.rotate_deg.as_dvec3();
        let (sx, cx) = sin_cos_deg(r.x);
        let (sy, cy) = sin_cos_deg(r.y);
        let (sz, cz) = sin_cos_deg(r.z);
        let rx = DMat3::from_cols(DVec3::X, DVec3::new(0.0, cx, sx), DVec3::new(0.0, -sx, cx));
        let ry = DMat3::from_cols(DVec3::new(cy, 0.0, -sy), DVec3::Y, DVec3::new(sy, 0.0, cy));
        let rz = DMat3::from_cols(DVec3::new(cz, sz, 0.0), DVec3::new(-sz, cz, 0.0), DVec3::Z);
        rz * ry * rx * DMat3::from_diagonal(self.scale.as_dvec3())
    }

    /// The mesh's vertices (and normals) in world space.
    pub fn apply(&self, mesh: &Mesh) -> Result<PlacedVertices> {
        self.validate().map_err(|m| Error::Parse {
            path: mesh.path.clone(),
            message: format!("transform: {m}"),
        })?;
        let m = self.linear();
        let mut pts: Vec<DVec3> = mesh.positions.iter().map(|p| m * p.as_dvec3()).collect();
        let mut offset = self.translate.as_dvec3();
        if let Some(fit) = &self.fit {
            // Bounds of the vertices the triangles use, after rotation.
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for &i in mesh.triangles.iter().flatten() {
                lo = lo.min(pts[i as usize]);
                hi = hi.max(pts[i as usize]);
            }
            let h = hi.y - lo.y;
            // Also catches NaN.
            if h.is_nan() || h <= 0.0 {
                return Err(Error::Parse {
                    path: mesh.path.clone(),
                    message: "cannot fit the mesh to a height: it is flat in y".into(),
                });
            }
            let s = fit.height as f64 / h;
            let bottom = DVec3::new(0.5 * (lo.x + hi.x), hi.y, 0.5 * (lo.z + hi.z));
            for p in &mut pts {
                *p *= s;
            }
            offset += fit.bottom_centre.as_dvec3() - bottom * s;
        }
        let positions = pts.iter().map(|p| (*p + offset).as_vec3()).collect();
        // Normals go by the inverse transpose; the fit's uniform scale does not turn them.
        let normals = mesh.normals.as_ref().map(|ns| {
            let nm = m.inverse().transpose();
            ns.iter()
                .map(|n| (nm * n.as_dvec3()).normalize_or_zero().as_vec3())
                .collect()
        });
        Ok(PlacedVertices { positions, normals })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh_of(points: &[Vec3]) -> Mesh {
        Mesh {
            path: "test.obj".into(),
            positions: points.to_vec(),
            normals: None,
            uvs: None,
            triangles: (0..points.len() as u32 / 3)
                .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                .collect(),
            parts: vec![],
            warnings: vec![],
        }
    }

    #[test]
    fn rotations_follow_the_right_hand_rule_in_order() {
        let t = Transform {
            rotate_deg: Vec3::new(90.0, 0.0, 90.0),
            ..Default::default()
        };
        // x turns y into z; then z turns x into y.
        let p = t.apply(&mesh_of(&[Vec3::X, Vec3::Y, Vec3::Z])).unwrap().positions;
        assert_eq!(p, vec![Vec3::Y, Vec3::Z, Vec3::X]);
        let t = Transform {
            rotate_deg: Vec3::new(0.0, 90.0, 0.0),
            scale: Vec3::new(2.0, 1.0, 1.0),
            translate: Vec3::new(0.0, 0.0, 1.0),
            ..Default::default()
        };
        // Scale first, then rotate (y turns z into x), then translate.
        let p = t.apply(&mesh_of(&[Vec3::X, Vec3::Y, Vec3::Z])).unwrap().positions;
        assert_eq!(
            p,
            vec![
                Vec3::new(0.0, 0.0, -1.0),
                Vec3::new(0.0, 1.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0)
            ]
        );
    }

    #[test]
    fn fit_stands_the_box_on_its_largest_y_face() {
        let pts = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 4.0, 0.0),
            Vec3::new(1.0, 1.0, 6.0),
        ];
        let t = Transform {
            fit: Some(Fit {
                height: 2.0,
                bottom_centre: Vec3::new(10.0, 1.0, -5.0),
            }),
            ..Default::default()
        };
        let p = t.apply(&mesh_of(&pts)).unwrap().positions;
        // Scale 0.5; old bottom centre (1, 4, 3) goes to (10, 1, -5).
        assert_eq!(p[0], Vec3::new(9.5, -1.0, -6.5));
        assert_eq!(p[1], Vec3::new(10.5, 1.0, -6.5));
        assert_eq!(p[2], Vec3::new(10.0, -0.5, -3.5));
    }

    #[test]
    fn normals_follow_the_inverse_transpose() {
        let mut m = mesh_of(&[Vec3::ZERO, Vec3::X, Vec3::Y]);
        m.normals = Some(vec![Vec3::new(1.0, 1.0, 0.0).normalize(), Vec3::ZERO, Vec3::Z]);
        let t = Transform {
            scale: Vec3::new(2.0, 1.0, 1.0),
            ..Default::default()
        };
        let n = t.apply(&m).unwrap().normals.unwrap();
        // The plane x + y = c becomes x/2 + y = c: normal (0.5, 1, 0).
        assert!((n[0] - Vec3::new(0.5, 1.0, 0.0).normalize()).length() < 1e-6);
        assert_eq!(n[1], Vec3::ZERO);
        assert_eq!(n[2], Vec3::Z);
    }

    #[test]
    fn zero_scale_and_flat_fit_are_refused() {
        let m = mesh_of(&[Vec3::ZERO, Vec3::X, Vec3::Z]);
        let t = Transform {
            scale: Vec3::new(1.0, 0.0, 1.0),
            ..Default::default()
        };
        assert!(t.apply(&m).is_err());
        let t = Transform {
            fit: Some(Fit {
                height: 1.0,
                bottom_centre: Vec3::ZERO,
            }),
            ..Default::default()
        };
        let e = t.apply(&m).unwrap_err().to_string();
        assert!(e.contains("test.obj") && e.contains("flat"), "{e}");
    }
}
