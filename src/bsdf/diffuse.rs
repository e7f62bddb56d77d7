//! Lambertian reflection (pbrt-v4 9.2, `DiffuseBxDF`) and Lambertian
//! reflection plus transmission (pbrt-v4 `DiffuseTransmissionBxDF`). Both
//! are two-sided and sampled with the cosine-weighted hemisphere.

use super::fresnel::{fr_dielectric, fresnel_moment1};
use super::{abs_cos_theta, cos_theta, same_hemisphere, BsdfSample, BxdfFlags, TransportMode};
use crate::math::{Vec2, Vec3};
use crate::sampling::cosine_hemisphere;
use std::f32::consts::FRAC_1_PI;

/// f = r / pi on the side of `wo`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseBxdf {
    /// Reflectance (albedo), clamped to [0, 1] per channel.
    pub r: Vec3,
}

impl DiffuseBxdf {
    pub fn new(r: Vec3) -> Self {
        DiffuseBxdf { r: clamp_unit(r) }
    }

    pub fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if !same_hemisphere(wo, wi) {
            return Vec3::ZERO;
        }
        self.r * FRAC_1_PI
    }

    pub fn sample_f(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        let wi = hemisphere_of(cosine_hemisphere(u), wo.z >= 0.0);
        Some(BsdfSample {
            f: self.r * FRAC_1_PI,
            wi,
            pdf: abs_cos_theta(wi) * FRAC_1_PI,
            flags: BxdfFlags::DIFFUSE_REFLECTION,
            eta: 1.0,
        })
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !same_hemisphere(wo, wi) {
            return 0.0;
        }
        abs_cos_theta(wi) * FRAC_1_PI
    }

    pub fn flags(&self) -> BxdfFlags {
        if self.r == Vec3::ZERO {
            BxdfFlags::UNSET
        } else {
            BxdfFlags::DIFFUSE_REFLECTION
        }
    }
}

/// f = r / pi on the side of `wo`, t / pi on the other. Reflection and
/// transmission are chosen in proportion to the largest channel of `r` and `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseTransmissionBxdf {
    pub r: Vec3,
    pub t: Vec3,
}

impl DiffuseTransmissionBxdf {
    /// `r` and `t` are clamped to [0, 1]; the caller keeps r + t <= 1.
    pub fn new(r: Vec3, t: Vec3) -> Self {
        DiffuseTransmissionBxdf {
            r: clamp_unit(r),
            t: clamp_unit(t),
        }
    }

    pub fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if same_hemisphere(wo, wi) {
            self.r * FRAC_1_PI
        } else {
            self.t * FRAC_1_PI
        }
    }

    /// Probability of sampling reflection rather than transmission.
    fn reflect_probability(&self) -> Option<f32> {
        let (pr, pt) = (self.r.max_element(), self.t.max_element());
        if pr + pt > 0.0 {
            Some(pr / (pr + pt))
        } else {
            None
        }
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
        let p_r = self.reflect_probability()?;
        let w = cosine_hemisphere(u);
        let (wi, p, flags) = if uc < p_r {
            (hemisphere_of(w, wo.z >= 0.0), p_r, BxdfFlags::DIFFUSE_REFLECTION)
        } else {
            (hemisphere_of(w, wo.z < 0.0), 1.0 - p_r, BxdfFlags::DIFFUSE_TRANSMISSION)
        };
        Some(BsdfSample {
            f: self.f(wo, wi),
            wi,
            pdf: p * abs_cos_theta(wi) * FRAC_1_PI,
            flags,
            eta: 1.0,
        })
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(p_r) = self.reflect_probability() else {
            return 0.0;
        };
        let p = if same_hemisphere(wo, wi) { p_r } else { 1.0 - p_r };
        p * abs_cos_theta(wi) * FRAC_1_PI
    }

    pub fn flags(&self) -> BxdfFlags {
        let mut flags = BxdfFlags::UNSET;
        if self.r != Vec3::ZERO {
            flags |= BxdfFlags::DIFFUSE_REFLECTION;
        }
        if self.t != Vec3::ZERO {
            flags |= BxdfFlags::DIFFUSE_TRANSMISSION;
        }
        flags
    }
}

/// Where subsurface light leaves a translucent object (pbrt-v4's
/// `NormalizedFresnelBxDF`): a Lambertian lobe weighted by the Fresnel
/// transmittance of the interface of index `eta`, normalised to reflect all
/// of it, on the side of `wo` (the outward normal). In radiance transport
/// it carries eta^2 back: the refraction into the object took it away.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalizedFresnelBxdf {
    pub eta: f32,
}

impl NormalizedFresnelBxdf {
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        if !same_hemisphere(wo, wi) {
            return Vec3::ZERO;
        }
        let c = 1.0 - 2.0 * fresnel_moment1(1.0 / self.eta);
        let f = (1.0 - fr_dielectric(cos_theta(wi), self.eta)) / (c * std::f32::consts::PI);
        let f = if mode == TransportMode::Radiance {
            f * self.eta * self.eta
        } else {
            f
        };
        Vec3::splat(f)
    }

    /// Sampled as a Lambertian lobe is, the cosine on the side of `wo`.
    pub fn sample_f(&self, wo: Vec3, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let mut bs = LAMBERTIAN.sample_f(wo, u)?;
        bs.f = self.f(wo, bs.wi, mode);
        Some(bs)
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        LAMBERTIAN.pdf(wo, wi)
    }
}

/// The white Lambertian lobe whose sampling the Fresnel-weighted one shares.
const LAMBERTIAN: DiffuseBxdf = DiffuseBxdf { r: Vec3::ONE };

/// `w` (with w.z >= 0) moved to the upper hemisphere if `upper`, else the lower.
fn hemisphere_of(w: Vec3, upper: bool) -> Vec3 {
    if upper {
        w
    } else {
        Vec3::new(w.x, w.y, -w.z)
    }
}

/// Clamps each channel to [0, 1] (NaN becomes 0).
pub(crate) fn clamp_unit(c: Vec3) -> Vec3 {
    let f = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    Vec3::new(f(c.x), f(c.y), f(c.z))
}
