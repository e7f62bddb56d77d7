//! Dielectric interfaces (pbrt-v4 9.3, 9.5 and 9.7, `DielectricBxDF` and
//! `ThinDielectricBxDF`).
//!
//! A smooth interface reflects with the Fresnel reflectance F and refracts
//! with 1 - F; a rough one does the same on Trowbridge-Reitz microfacets,
//! with the generalized half vector and the transmission Jacobian of Walter,
//! Marschner, Li and Torrance, "Microfacet Models for Refraction through Rough
//! Surfaces" (EGSR 2007), and visible-normal sampling. Reflection and
//! transmission are chosen with probabilities R and T, so the sampled weights
//! carry no Fresnel noise.
//!
//! Radiance is not symmetric under refraction: crossing into a medium with
//! relative index eta compresses it by 1/eta^2 (pbrt-v4 9.5). That factor is
//! applied in [`TransportMode::Radiance`] only; importance (photons) carries
//! power, which is conserved.

use super::fresnel::{fr_dielectric, reflect, refract};
use super::{abs_cos_theta, cos_theta, mirror, same_hemisphere, BsdfSample, BxdfFlags, TransportMode, TrowbridgeReitz};
use crate::math::{Vec2, Vec3};

/// Which of an interface's lobes a sample may take (pbrt-v4's
/// `BxDFReflTransFlags`): a layered model walks inside a coat by asking for
/// one of them, with the density of that choice alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Lobes {
    All,
    Reflection,
    Transmission,
}

impl Lobes {
    /// The probabilities of reflecting and transmitting, R and T masked.
    fn mask(self, r: f32, t: f32) -> (f32, f32) {
        match self {
            Lobes::All => (r, t),
            Lobes::Reflection => (r, 0.0),
            Lobes::Transmission => (0.0, t),
        }
    }
}

/// An interface between the outside (+z side) and a medium of relative index
/// `eta` (inside / outside) below it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricBxdf {
    pub distrib: TrowbridgeReitz,
    pub eta: f32,
}

impl DielectricBxdf {
    /// `eta` must be positive; a non-positive or NaN one is taken as 1 (an
    /// index-matched boundary), as pbrt-v4 does for eta = 0.
    pub fn new(distrib: TrowbridgeReitz, eta: f32) -> Self {
        let eta = if eta > 0.0 && eta.is_finite() { eta } else { 1.0 };
        DielectricBxdf { distrib, eta }
    }

    /// True when the interface scatters only in the specular directions.
    pub(super) fn is_specular(&self) -> bool {
        self.eta == 1.0 || self.distrib.effectively_smooth()
    }

    /// Reflection and transmission, specular or glossy; an index-matched
    /// interface (eta = 1) only passes light straight through, whatever its
    /// roughness (pbrt-v4 calls it glossy when rough but samples it as specular).
    pub fn flags(&self) -> BxdfFlags {
        if self.eta == 1.0 {
            return BxdfFlags::SPECULAR_TRANSMISSION;
        }
        BxdfFlags::REFLECTION
            | BxdfFlags::TRANSMISSION
            | if self.distrib.effectively_smooth() {
                BxdfFlags::SPECULAR
            } else {
                BxdfFlags::GLOSSY
            }
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        self.sample_lobes(wo, uc, u, mode, Lobes::All)
    }

    /// `sample_f` limited to `lobes`, its density that of the choice within them.
    pub(super) fn sample_lobes(
        &self,
        wo: Vec3,
        uc: f32,
        u: Vec2,
        mode: TransportMode,
        lobes: Lobes,
    ) -> Option<BsdfSample> {
        if self.is_specular() {
            self.sample_specular(wo, uc, mode, lobes)
        } else {
            self.sample_rough(wo, uc, u, mode, lobes)
        }
    }

    fn sample_specular(&self, wo: Vec3, uc: f32, mode: TransportMode, lobes: Lobes) -> Option<BsdfSample> {
        let r0 = fr_dielectric(cos_theta(wo), self.eta);
        let (r, t) = lobes.mask(r0, 1.0 - r0);
        if r + t <= 0.0 {
            return None;
        }
        if uc < r / (r + t) {
            // Specular reflection, chosen with probability R.
            let wi = mirror(wo);
            return Some(BsdfSample {
                f: Vec3::splat(r / abs_cos_theta(wi)),
                wi,
                pdf: r / (r + t),
                flags: BxdfFlags::SPECULAR_REFLECTION,
                eta: 1.0,
            });
        }
        // Specular transmission, chosen with probability T.
        let (wi, etap) = refract(wo, Vec3::Z, self.eta)?;
        if wi.z == 0.0 {
            return None;
        }
        let mut ft = t / abs_cos_theta(wi);
        if mode == TransportMode::Radiance {
            ft /= etap * etap;
        }
        Some(BsdfSample {
            f: Vec3::splat(ft),
            wi,
            pdf: t / (r + t),
            flags: BxdfFlags::SPECULAR_TRANSMISSION,
            eta: etap,
        })
    }

    fn sample_rough(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode, lobes: Lobes) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wm = self.distrib.sample_wm(wo, u);
        let r0 = fr_dielectric(wo.dot(wm), self.eta);
        let (r, t) = lobes.mask(r0, 1.0 - r0);
        if r + t <= 0.0 {
            return None;
        }
        if uc < r / (r + t) {
            // Reflection off the sampled microfacet.
            let wi = reflect(wo, wm);
            if !same_hemisphere(wo, wi) {
                return None;
            }
            let pdf = self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * (r / (r + t));
            let f = self.distrib.d(wm) * self.distrib.g(wo, wi) * r / (4.0 * cos_theta(wi) * cos_theta(wo)).abs();
            return Some(BsdfSample {
                f: Vec3::splat(f),
                wi,
                pdf,
                flags: BxdfFlags::GLOSSY_REFLECTION,
                eta: 1.0,
            });
        }
        // Refraction through the sampled microfacet.
        let (wi, etap) = refract(wo, wm, self.eta)?;
        if same_hemisphere(wo, wi) || wi.z == 0.0 {
            return None;
        }
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
        // Walter et al. 2007, eq. 17: dwm / dwi for refraction.
        let dwm_dwi = wi.dot(wm).abs() / denom;
        let pdf = self.distrib.pdf(wo, wm) * dwm_dwi * (t / (r + t));
        let mut f = t
            * self.distrib.d(wm)
            * self.distrib.g(wo, wi)
            * (wi.dot(wm) * wo.dot(wm) / (cos_theta(wi) * cos_theta(wo) * denom)).abs();
        if mode == TransportMode::Radiance {
            f /= etap * etap;
        }
        Some(BsdfSample {
            f: Vec3::splat(f),
            wi,
            pdf,
            flags: BxdfFlags::GLOSSY_TRANSMISSION,
            eta: etap,
        })
    }

    /// The generalized half vector of Walter et al. 2007 (eq. 16), facing +z,
    /// and the relative index along the path (1 for reflection); `None` for
    /// degenerate configurations and back-facing microfacets.
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32)> {
        let (cos_o, cos_i) = (cos_theta(wo), cos_theta(wi));
        if cos_i == 0.0 || cos_o == 0.0 {
            return None;
        }
        let reflect = cos_i * cos_o > 0.0;
        let etap = match (reflect, cos_o > 0.0) {
            (true, _) => 1.0,
            (false, true) => self.eta,
            (false, false) => 1.0 / self.eta,
        };
        let wm = wi * etap + wo;
        if wm.length_squared() == 0.0 {
            return None;
        }
        let wm = wm.normalize() * wm.z.signum();
        // Discard microfacets seen from behind by either direction.
        if wm.dot(wi) * cos_i < 0.0 || wm.dot(wo) * cos_o < 0.0 {
            return None;
        }
        Some((wm, etap))
    }

    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        if self.is_specular() {
            return Vec3::ZERO;
        }
        let Some((wm, etap)) = self.half_vector(wo, wi) else {
            return Vec3::ZERO;
        };
        let (cos_o, cos_i) = (cos_theta(wo), cos_theta(wi));
        let fr = fr_dielectric(wo.dot(wm), self.eta);
        let d = self.distrib.d(wm);
        let g = self.distrib.g(wo, wi);
        if same_hemisphere(wo, wi) {
            return Vec3::splat(d * g * fr / (4.0 * cos_i * cos_o).abs());
        }
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * cos_i * cos_o;
        let mut ft = d * (1.0 - fr) * g * (wi.dot(wm) * wo.dot(wm) / denom).abs();
        if mode == TransportMode::Radiance {
            ft /= etap * etap;
        }
        Vec3::splat(ft)
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdf_lobes(wo, wi, Lobes::All)
    }

    /// `pdf` of [`Self::sample_lobes`] limited to `lobes`.
    pub(super) fn pdf_lobes(&self, wo: Vec3, wi: Vec3, lobes: Lobes) -> f32 {
        if self.is_specular() {
            return 0.0;
        }
        let Some((wm, etap)) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let r0 = fr_dielectric(wo.dot(wm), self.eta);
        let (r, t) = lobes.mask(r0, 1.0 - r0);
        if r + t <= 0.0 {
            return 0.0;
        }
        if same_hemisphere(wo, wi) {
            self.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * (r / (r + t))
        } else {
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
            let dwm_dwi = wi.dot(wm).abs() / denom;
            self.distrib.pdf(wo, wm) * dwm_dwi * (t / (r + t))
        }
    }
}

/// A thin slab of dielectric (a window pane, a soap bubble): light either
/// reflects or passes straight through, after any number of internal
/// reflections between the two parallel faces, summed in closed form
/// (pbrt-v4 9.5, `ThinDielectricBxDF`). Purely specular. No 1/eta^2 scaling applies: the light
/// leaves into the medium it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectricBxdf {
    pub eta: f32,
}

impl ThinDielectricBxdf {
    pub fn new(eta: f32) -> Self {
        let eta = if eta > 0.0 && eta.is_finite() { eta } else { 1.0 };
        ThinDielectricBxdf { eta }
    }

    pub fn flags(&self) -> BxdfFlags {
        BxdfFlags::REFLECTION | BxdfFlags::TRANSMISSION | BxdfFlags::SPECULAR
    }

    /// Total reflectance and transmittance of the slab for `wo`.
    pub fn reflectance_transmittance(&self, wo: Vec3) -> (f32, f32) {
        let mut r = fr_dielectric(abs_cos_theta(wo), self.eta);
        let mut t = 1.0 - r;
        // Geometric series of the inter-reflections: R + T^2 R / (1 - R^2).
        if r < 1.0 {
            r += t * t * r / (1.0 - r * r);
            t = 1.0 - r;
        }
        (r, t)
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32) -> Option<BsdfSample> {
        let (r, t) = self.reflectance_transmittance(wo);
        let cos = abs_cos_theta(wo);
        if r + t <= 0.0 || cos == 0.0 {
            return None;
        }
        if uc < r / (r + t) {
            Some(BsdfSample {
                f: Vec3::splat(r / cos),
                wi: mirror(wo),
                pdf: r / (r + t),
                flags: BxdfFlags::SPECULAR_REFLECTION,
                eta: 1.0,
            })
        } else {
            Some(BsdfSample {
                f: Vec3::splat(t / cos),
                wi: -wo,
                pdf: t / (r + t),
                flags: BxdfFlags::SPECULAR_TRANSMISSION,
                eta: 1.0,
            })
        }
    }
}
