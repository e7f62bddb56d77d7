//! Surface scattering. Every surface is two-sided.

use crate::math::Vec3;
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian: f = albedo / pi.
    Diffuse { albedo: Vec3 },
}

impl Material {
    pub fn diffuse(r: f32, g: f32, b: f32) -> Self {
        Material::Diffuse {
            albedo: Vec3::new(r, g, b),
        }
    }

    /// The BRDF value for any pair of directions on the same side.
    pub fn f(&self) -> Vec3 {
        match self {
            Material::Diffuse { albedo } => *albedo * FRAC_1_PI,
        }
    }

    pub fn albedo(&self) -> Vec3 {
        match self {
            Material::Diffuse { albedo } => *albedo,
        }
    }
}
