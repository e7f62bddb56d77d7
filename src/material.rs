//! Surface scattering: Lambertian, perfect mirror and smooth dielectric
//! (glass). Every surface is two-sided. The specular models follow pbrt-v4
//! 9.3-9.5 (Fresnel equations for dielectrics, Snell's law, total internal
//! reflection); they are sampled, never evaluated, since their BSDFs are
//! delta distributions.

use crate::math::Vec3;
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian: f = albedo / pi.
    Diffuse { albedo: Vec3 },
    /// Lambertian that also emits radiance `le` from both sides, uniformly. It is
    /// seen by camera and bounce rays only: shadow rays and photons come from
    /// `Light`s, so use it for analytic scenes (the white furnace), not as a lamp.
    Emissive { albedo: Vec3, le: Vec3 },
    /// Perfect specular reflection, scaled by `reflectance`.
    Mirror { reflectance: Vec3 },
    /// Smooth dielectric with index of refraction `ior` (outside is vacuum/air).
    Glass { ior: f32 },
}

/// Whether a path carries radiance (from the camera) or importance/power
/// (from a light): refraction compresses radiance by 1/eta^2 but not power.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    Radiance,
    Importance,
}

/// A sampled specular scattering: the new direction and the throughput factor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularSample {
    pub wi: Vec3,
    pub weight: Vec3,
    /// True when the ray went through the surface.
    pub transmitted: bool,
}

impl Material {
    pub fn diffuse(r: f32, g: f32, b: f32) -> Self {
        Material::Diffuse {
            albedo: Vec3::new(r, g, b),
        }
    }

    /// The Lambertian BRDF value (zero for specular materials, whose BSDF is a delta).
    pub fn f(&self) -> Vec3 {
        self.albedo() * FRAC_1_PI
    }

    /// Diffuse reflectance (zero for specular materials).
    pub fn albedo(&self) -> Vec3 {
        match self {
            Material::Diffuse { albedo } | Material::Emissive { albedo, .. } => *albedo,
            _ => Vec3::ZERO,
        }
    }

    /// Emitted radiance, the same in every direction.
    pub fn le(&self) -> Vec3 {
        match self {
            Material::Emissive { le, .. } => *le,
            _ => Vec3::ZERO,
        }
    }

    pub fn is_specular(&self) -> bool {
        matches!(self, Material::Mirror { .. } | Material::Glass { .. })
    }

    /// Samples the specular lobe for outgoing direction `wo` (pointing away
    /// from the surface) at a surface with unit normal `n` (either side). `u`
    /// chooses between reflection and refraction with probability equal to the
    /// Fresnel reflectance, so the weight is 1 (or 1/eta^2 for radiance).
    pub fn sample_specular(&self, wo: Vec3, n: Vec3, u: f32, mode: Transport) -> Option<SpecularSample> {
        match *self {
            Material::Diffuse { .. } | Material::Emissive { .. } => None,
            Material::Mirror { reflectance } => Some(SpecularSample {
                wi: reflect(wo, n),
                weight: reflectance,
                transmitted: false,
            }),
            Material::Glass { ior } => {
                // Orient the normal towards wo; entering when wo is on the side n points to.
                let cos_o = wo.dot(n);
                let (n, eta) = if cos_o >= 0.0 { (n, ior) } else { (-n, 1.0 / ior) };
                let cos_i = cos_o.abs();
                let f = fresnel_dielectric(cos_i, eta);
                if u < f {
                    return Some(SpecularSample {
                        wi: reflect(wo, n),
                        weight: Vec3::ONE,
                        transmitted: false,
                    });
                }
                let wi = refract(wo, n, eta)?;
                let scale = match mode {
                    Transport::Radiance => 1.0 / (eta * eta),
                    Transport::Importance => 1.0,
                };
                Some(SpecularSample {
                    wi,
                    weight: Vec3::splat(scale),
                    transmitted: true,
                })
            }
        }
    }
}

/// Mirror reflection of `wo` about `n`.
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + n * (2.0 * wo.dot(n))
}

/// Refraction of `wo` (on the side `n` points to) into the other medium, with
/// `eta` = n_transmitted / n_incident; `None` on total internal reflection.
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.dot(n);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wo / eta + n * (cos_i / eta - cos_t)).normalize())
}

/// Unpolarised Fresnel reflectance of a smooth dielectric interface for
/// light arriving at cosine `cos_i` (>= 0) from the side with relative index
/// `eta` = n_t / n_i. Returns 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_at_normal_incidence() {
        for n in [1.33f32, 1.5, 2.4] {
            let want = ((n - 1.0) / (n + 1.0)).powi(2);
            assert!((fresnel_dielectric(1.0, n) - want).abs() < 1e-6);
            // The same from inside.
            assert!((fresnel_dielectric(1.0, 1.0 / n) - want).abs() < 1e-6);
        }
    }

    #[test]
    fn total_internal_reflection_past_the_critical_angle() {
        let n = 1.5f32;
        let critical = (1.0 / n).asin();
        let just_inside = (critical - 0.01).cos();
        let past = (critical + 0.01).cos();
        assert!(fresnel_dielectric(just_inside, 1.0 / n) < 1.0);
        assert_eq!(fresnel_dielectric(past, 1.0 / n), 1.0);
        let wo = Vec3::new((critical + 0.01).sin(), 0.0, past);
        assert!(refract(wo, Vec3::Z, 1.0 / n).is_none());
        // From inside past the critical angle, glass always reflects.
        let g = Material::Glass { ior: n };
        for u in [0.0, 0.5, 0.999] {
            let s = g.sample_specular(wo, -Vec3::Z, u, Transport::Importance).unwrap();
            assert!(!s.transmitted);
        }
    }

    #[test]
    fn reflected_plus_refracted_energy_is_one() {
        let g = Material::Glass { ior: 1.5 };
        for theta in [0.0f32, 0.3, 0.8, 1.2, 1.5] {
            let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
            let n = 10_000;
            let (mut refl, mut trans) = (0.0, 0.0);
            for i in 0..n {
                let s = g
                    .sample_specular(wo, Vec3::Z, (i as f32 + 0.5) / n as f32, Transport::Importance)
                    .unwrap();
                if s.transmitted {
                    trans += s.weight.x;
                    assert!(s.wi.z < 0.0);
                } else {
                    refl += s.weight.x;
                    assert!((s.wi - Vec3::new(-wo.x, 0.0, wo.z)).length() < 1e-5);
                }
            }
            let (r, t) = (refl / n as f32, trans / n as f32);
            assert!((r + t - 1.0).abs() < 1e-4, "theta {theta}: {r} + {t}");
            assert!((r - fresnel_dielectric(theta.cos(), 1.5)).abs() < 2e-4);
        }
    }

    #[test]
    fn refraction_obeys_snell() {
        let wo = Vec3::new(0.5f32.sin(), 0.0, 0.5f32.cos());
        let t = refract(wo, Vec3::Z, 1.5).unwrap();
        let sin_t = (t.x * t.x + t.y * t.y).sqrt();
        assert!((0.5f32.sin() - 1.5 * sin_t).abs() < 1e-5);
        assert!(t.z < 0.0 && t.x < 0.0);
    }

    #[test]
    fn mirror_reflects_about_the_normal() {
        let m = Material::Mirror { reflectance: Vec3::ONE };
        let wo = Vec3::new(1.0, 1.0, 0.0).normalize();
        let s = m.sample_specular(wo, Vec3::Y, 0.5, Transport::Radiance).unwrap();
        assert!((s.wi - Vec3::new(-1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    }
}
