//! Metals (pbrt-v4 9.4 and 9.6, `ConductorBxDF`): the Fresnel reflectance of a
//! complex index of refraction on a perfectly smooth surface, or on
//! Trowbridge-Reitz microfacets (the Torrance-Sparrow model with Smith's
//! height-correlated masking-shadowing), sampled through the visible normals.

use super::fresnel::{fr_complex_rgb, reflect};
use super::{abs_cos_theta, mirror, same_hemisphere, BsdfSample, BxdfFlags, TrowbridgeReitz};
use crate::math::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConductorBxdf {
    pub distrib: TrowbridgeReitz,
    /// Real part of the relative index of refraction, per channel.
    pub eta: Vec3,
    /// Absorption coefficient (imaginary part), per channel.
    pub k: Vec3,
}

impl ConductorBxdf {
    pub fn new(distrib: TrowbridgeReitz, eta: Vec3, k: Vec3) -> Self {
        ConductorBxdf { distrib, eta, k }
    }

    /// pbrt-v4's `conductor` with `reflectance` r: eta = 1 and
    /// k = 2 sqrt(r) / sqrt(1 - r), the conductor whose Fresnel reflectance at
    /// normal incidence, ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2), is r. r is
    /// clamped to [0, 0.9999] as pbrt-v4 does (k is infinite at r = 1).
    pub fn from_reflectance(distrib: TrowbridgeReitz, r: Vec3) -> Self {
        let k = |r: f32| {
            let r = if r.is_nan() { 0.0 } else { r.clamp(0.0, 0.9999) };
            2.0 * r.sqrt() / (1.0 - r).sqrt()
        };
        ConductorBxdf {
            distrib,
            eta: Vec3::ONE,
            k: Vec3::new(k(r.x), k(r.y), k(r.z)),
        }
    }

    pub fn flags(&self) -> BxdfFlags {
        if self.distrib.effectively_smooth() {
            BxdfFlags::SPECULAR_REFLECTION
        } else {
            BxdfFlags::GLOSSY_REFLECTION
        }
    }

    pub fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if !same_hemisphere(wo, wi) || self.distrib.effectively_smooth() {
            return Vec3::ZERO;
        }
        let (cos_o, cos_i) = (abs_cos_theta(wo), abs_cos_theta(wi));
        let wm = wi + wo;
        if cos_i == 0.0 || cos_o == 0.0 || wm.length_squared() == 0.0 {
            return Vec3::ZERO;
        }
        self.microfacet_f(wo, wi, wm.normalize(), cos_o, cos_i)
    }

    /// Torrance-Sparrow: D(wm) F(wo . wm) G(wo, wi) / (4 cos_o cos_i).
    fn microfacet_f(&self, wo: Vec3, wi: Vec3, wm: Vec3, cos_o: f32, cos_i: f32) -> Vec3 {
        let fresnel = fr_complex_rgb(wo.dot(wm).abs(), self.eta, self.k);
        fresnel * (self.distrib.d(wm) * self.distrib.g(wo, wi) / (4.0 * cos_o * cos_i))
    }

    pub fn sample_f(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if self.distrib.effectively_smooth() {
            // Perfect specular reflection: f cos / pdf is the Fresnel term.
            let wi = mirror(wo);
            let cos_i = abs_cos_theta(wi);
            if cos_i == 0.0 {
                return None;
            }
            return Some(BsdfSample {
                f: fr_complex_rgb(cos_i, self.eta, self.k) / cos_i,
                wi,
                pdf: 1.0,
                flags: BxdfFlags::SPECULAR_REFLECTION,
                eta: 1.0,
            });
        }
        // Sample a visible microfacet normal and reflect about it.
        if wo.z == 0.0 {
            return None;
        }
        let wm = self.distrib.sample_wm(wo, u);
        let wi = reflect(wo, wm);
        if !same_hemisphere(wo, wi) {
            return None;
        }
        let (cos_o, cos_i) = (abs_cos_theta(wo), abs_cos_theta(wi));
        if cos_i == 0.0 {
            return None;
        }
        let pdf = self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs());
        Some(BsdfSample {
            f: self.microfacet_f(wo, wi, wm, cos_o, cos_i),
            wi,
            pdf,
            flags: BxdfFlags::GLOSSY_REFLECTION,
            eta: 1.0,
        })
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !same_hemisphere(wo, wi) || self.distrib.effectively_smooth() {
            return 0.0;
        }
        let wm = wo + wi;
        if wm.length_squared() == 0.0 {
            return 0.0;
        }
        // The half vector facing +z, as sample_wm returns it.
        let wm = wm.normalize() * wm.z.signum();
        // Jacobian of the reflection map: dwm / dwi = 1 / (4 |wo . wm|).
        self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs())
    }
}
