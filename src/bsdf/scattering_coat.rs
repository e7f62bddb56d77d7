//! A dielectric coat whose medium scatters (pbrt-v4's `coateddiffuse` and
//! `coatedconductor` with `albedo` > 0), over a Lambertian base or a metal.
//!
//! `f` is pbrt-v4's stochastic estimate (`LayeredBxDF::f`, after Guo, Hašan,
//! Yan and Zhao 2018) with its medium: a walk in through the coat, then
//! free flights of unit extinction through the coat's thickness. Where a
//! flight ends inside, the light scatters by the Henyey-Greenstein phase
//! function (asymmetry `g`) with probability `albedo`, and the light that
//! leaves towards `wi` from there is found by two strategies (a direction
//! sampled through the coat from `wi`, and the phase function's own sample)
//! weighed by the power heuristic. A flight that reaches the base or the
//! coat's underside scatters there as in [`super::CoatedConductorBxdf`]'s
//! walk, with the same densities in the weights (the competing strategy's
//! density of the direction it would have drawn; see that module). Its
//! random numbers are keyed by the two directions, so renders stay
//! deterministic.
//!
//! `sample_f` draws from a deterministic mixture whose density `pdf` returns
//! exactly: the coat's reflection, the metal's lobe seen through the coat,
//! and a cosine lobe for the light the medium and the base spread. With a
//! smooth coat over a smooth metal, the light that crosses the coat without
//! scattering is one specular reflection summed in closed form (as for the
//! clear coat), and the cosine lobe carries what the medium scatters.

use super::dielectric::Lobes;
use super::fresnel::{fr_complex_rgb, fr_dielectric};
use super::layered::{
    mirror_reflectance, mixture_direction, mixture_pdf, outside, power_heuristic, roulette, valid, walk_ends,
    walks_mean,
};
use super::{
    coat_reflection, mirror, two_sided, two_sided_sample, BsdfSample, BxdfFlags, ConductorBxdf, DielectricBxdf,
    TransportMode,
};
use crate::math::{Vec2, Vec3};
use crate::medium::{henyey_greenstein, sample_henyey_greenstein};
use crate::sampling::{cosine_hemisphere, Rng};
use std::f32::consts::FRAC_1_PI;

/// Key of the walk's random numbers (another than the clear coat's).
const WALK_SEED: u64 = 0x5ca7_7e12;

/// Laid out to keep [`super::Bxdf`] at its size: a Lambertian base keeps
/// its reflectance in `base.eta` (`diffuse_base`), and the counts are bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScatteringCoatBxdf {
    pub coat: DielectricBxdf,
    /// The metal, its index relative to the coat's; or, with
    /// `diffuse_base`, the Lambertian reflectance in `eta`.
    base: ConductorBxdf,
    /// Optical thickness of the coat (unit extinction).
    pub thickness: f32,
    /// Single-scattering albedo of the coat's medium, each channel in [0, 1].
    pub albedo: Vec3,
    /// Henyey-Greenstein asymmetry of its scattering, in (-1, 1).
    pub g: f32,
    /// Scattering events a walk may take (pbrt-v4's `maxdepth`, 10).
    pub max_depth: u8,
    /// Walks averaged per evaluation of `f` (pbrt-v4's `nsamples`, 1).
    pub samples: u8,
    diffuse_base: bool,
}

impl ScatteringCoatBxdf {
    /// Both interfaces regularized (pbrt-v4's `LayeredBxDF::Regularize`);
    /// a Lambertian base has none.
    pub fn regularize(&mut self) {
        self.coat.distrib = self.coat.distrib.regularized();
        if !self.diffuse_base {
            self.base.distrib = self.base.distrib.regularized();
        }
    }

    /// Over a Lambertian base of reflectance `r`.
    pub fn over_diffuse(
        coat: DielectricBxdf,
        r: Vec3,
        thickness: f32,
        albedo: Vec3,
        g: f32,
        max_depth: u32,
        samples: u32,
    ) -> Self {
        let base = ConductorBxdf {
            distrib: coat.distrib,
            eta: r.clamp(Vec3::ZERO, Vec3::ONE),
            k: Vec3::ZERO,
        };
        Self::with_base(coat, base, true, thickness, albedo, g, max_depth, samples)
    }

    /// Over a metal given as it would be in air (its index is divided by
    /// the coat's here, as pbrt-v4 does).
    pub fn over_conductor(
        coat: DielectricBxdf,
        base: ConductorBxdf,
        thickness: f32,
        albedo: Vec3,
        g: f32,
        max_depth: u32,
        samples: u32,
    ) -> Self {
        let eta = coat.eta;
        let base = ConductorBxdf::new(base.distrib, base.eta / eta, base.k / eta);
        Self::with_base(coat, base, false, thickness, albedo, g, max_depth, samples)
    }

    #[allow(clippy::too_many_arguments)]
    fn with_base(
        coat: DielectricBxdf,
        base: ConductorBxdf,
        diffuse_base: bool,
        thickness: f32,
        albedo: Vec3,
        g: f32,
        max_depth: u32,
        samples: u32,
    ) -> Self {
        ScatteringCoatBxdf {
            coat,
            base,
            thickness: if thickness > 0.0 { thickness.min(f32::MAX) } else { 0.0 },
            albedo: albedo.clamp(Vec3::ZERO, Vec3::ONE),
            g: if g.is_finite() { g.clamp(-0.99, 0.99) } else { 0.0 },
            max_depth: max_depth.min(u8::MAX as u32) as u8,
            samples: samples.clamp(1, u8::MAX as u32) as u8,
            diffuse_base,
        }
    }

    fn coat_smooth(&self) -> bool {
        self.coat.is_specular()
    }

    fn base_smooth(&self) -> bool {
        !self.diffuse_base && self.base.distrib.effectively_smooth()
    }

    fn base_f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match self.diffuse_base {
            true if wo.z * wi.z > 0.0 => self.base.eta * FRAC_1_PI,
            true => Vec3::ZERO,
            false => self.base.f(wo, wi),
        }
    }

    fn base_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self.diffuse_base {
            true if wo.z * wi.z > 0.0 => wi.z.abs() * FRAC_1_PI,
            true => 0.0,
            false => self.base.pdf(wo, wi),
        }
    }

    /// `wo` above the base.
    fn base_sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if !self.diffuse_base {
            return self.base.sample_f(wo, u);
        }
        let wi = cosine_hemisphere(u);
        (wi.z > 0.0).then(|| BsdfSample {
            f: self.base.eta * FRAC_1_PI,
            wi,
            pdf: wi.z * FRAC_1_PI,
            flags: BxdfFlags::DIFFUSE_REFLECTION,
            eta: 1.0,
        })
    }

    pub fn flags(&self) -> BxdfFlags {
        if self.coat_smooth() {
            BxdfFlags::SPECULAR_REFLECTION | BxdfFlags::GLOSSY
        } else {
            BxdfFlags::GLOSSY_REFLECTION
        }
    }

    /// Fraction of light crossing a height `dz` of the coat along `w`
    /// without meeting its medium.
    fn tr(&self, dz: f32, w: Vec3) -> f32 {
        if w.z == 0.0 {
            return 0.0;
        }
        (-(dz / w.z).abs()).exp()
    }

    /// Probabilities of the coat's reflection, the metal's lobe through
    /// the coat and the cosine lobe, for `wo` (upper side).
    fn lobe_weights(&self, cos_o: f32) -> (f32, f32, f32) {
        let f = fr_dielectric(cos_o, self.coat.eta);
        let rest = 1.0 - f;
        if self.diffuse_base {
            return (f, 0.0, rest);
        }
        match (self.coat_smooth(), self.base_smooth()) {
            (true, true) => (f + 0.5 * rest, 0.0, 0.5 * rest),
            (false, true) => (f + 0.6 * rest, 0.0, 0.4 * rest),
            _ => (f + 0.1 * rest, 0.5 * rest, 0.4 * rest),
        }
    }

    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        two_sided(wo, wi, |wo, wi| self.f_upper(wo, wi, mode))
    }

    fn f_upper(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        walks_mean(&self.coat, wo, wi, mode, WALK_SEED, self.samples as u32, |rng| {
            self.walk(wo, wi, mode, rng)
        })
    }

    /// One walk from the top of the coat (z = thickness) down towards the
    /// base (z = 0), pbrt-v4's `LayeredBxDF::f` loop with its medium.
    fn walk(&self, wo: Vec3, wi: Vec3, mode: TransportMode, rng: &mut Rng) -> Vec3 {
        let coat = &self.coat;
        let Some((wos, wis)) = walk_ends(coat, wo, wi, mode, rng) else {
            return Vec3::ZERO;
        };
        let (coat_smooth, base_smooth) = (self.coat_smooth(), self.base_smooth());
        let top = self.thickness;
        let mut f = Vec3::ZERO;
        let mut beta = wos.f * (wos.wi.z.abs() / wos.pdf);
        let mut z = top;
        let mut w = wos.wi;
        for depth in 0..self.max_depth {
            if roulette(depth as u32, &mut beta, rng) {
                break;
            }
            // A free flight of unit extinction, measured along z.
            let dz = -(1.0 - rng.next_f32()).ln() * w.z.abs();
            let zp = if w.z > 0.0 { z + dz } else { z - dz };
            if zp == z {
                continue;
            }
            if 0.0 < zp && zp < top {
                // Scattered in the coat: light leaving towards wi along the
                // presampled way out, then the phase function's own sample.
                let phase = henyey_greenstein(w.dot(-wis.wi), self.g);
                let wt = if coat_smooth {
                    1.0
                } else {
                    power_heuristic(wis.pdf, phase)
                };
                let out = if coat_smooth && base_smooth {
                    self.mirrored_ways_out(w, zp, -wis.wi)
                } else {
                    Vec3::splat(phase * self.tr(top - zp, wis.wi))
                };
                f += beta * self.albedo * wis.f * out * (wt / wis.pdf);
                let (next, p) = sample_henyey_greenstein(w, self.g, rng.next_2d());
                if p == 0.0 || next.z == 0.0 {
                    continue;
                }
                // The phase function is sampled exactly: p / pdf = 1.
                beta *= self.albedo;
                w = next;
                z = zp;
                if w.z > 0.0 && !coat_smooth {
                    let f_exit = coat.f(-w, wi, mode);
                    if f_exit != Vec3::ZERO {
                        let wt = power_heuristic(p, coat.pdf_lobes(wi, -w, Lobes::Transmission));
                        f += beta * f_exit * (self.tr(top - zp, w) * wt);
                    }
                }
                continue;
            }
            z = zp.clamp(0.0, top);
            if z == top {
                // The underside of the coat sends the light back down.
                let Some(bs) = coat
                    .sample_lobes(-w, rng.next_f32(), rng.next_2d(), mode, Lobes::Reflection)
                    .filter(valid)
                else {
                    break;
                };
                beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
                w = bs.wi;
                continue;
            }
            if !base_smooth {
                let wt = if coat_smooth {
                    1.0
                } else {
                    power_heuristic(wis.pdf, self.base_pdf(-w, -wis.wi))
                };
                f += beta * self.base_f(-w, -wis.wi) * (wis.wi.z.abs() * wt * self.tr(top, wis.wi) / wis.pdf) * wis.f;
            }
            let Some(bs) = self.base_sample(-w, rng.next_2d()).filter(valid) else {
                break;
            };
            beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
            w = bs.wi;
            if !coat_smooth {
                let f_exit = coat.f(-w, wi, mode);
                if f_exit != Vec3::ZERO {
                    let wt = if base_smooth {
                        1.0
                    } else {
                        power_heuristic(bs.pdf, coat.pdf_lobes(wi, -w, Lobes::Transmission))
                    };
                    f += beta * f_exit * (self.tr(top, bs.wi) * wt);
                }
            }
        }
        f
    }

    /// Between a smooth coat and a smooth metal, light scattered at height
    /// `z` (travelling along `w`) leaves along the inside direction `up`
    /// (towards the coat) by a chain of mirror bounces no sample can find:
    /// straight up, or down to the metal first, then any number of times
    /// back from the coat's underside and the metal. The chains' sum, as a
    /// phase function times transmittance (what pbrt-v4's estimate counts
    /// for the first chain alone, which leaves these coats too dark).
    fn mirrored_ways_out(&self, w: Vec3, z: f32, up: Vec3) -> Vec3 {
        let down = Vec3::new(up.x, up.y, -up.z);
        let top = self.thickness;
        let cross = self.tr(top, up);
        let metal = fr_complex_rgb(up.z.abs(), self.base.eta, self.base.k);
        let coat = fr_dielectric(outside(self.coat.eta, up).map_or(1.0, |o| o.z), self.coat.eta);
        let first = Vec3::splat(henyey_greenstein(w.dot(up), self.g) * self.tr(top - z, up))
            + metal * (henyey_greenstein(w.dot(down), self.g) * self.tr(z, up) * cross);
        first / (Vec3::ONE - metal * (coat * cross * cross))
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        two_sided_sample(wo, |wo| {
            if wo.z == 0.0 {
                return None;
            }
            let (p_coat, p_base, _) = self.lobe_weights(wo.z);
            if uc < p_coat && self.coat_smooth() {
                if self.base_smooth() {
                    // The coat's mirror and the metal's seen through it,
                    // for light that meets no medium.
                    let r = mirror_reflectance(&self.coat, &self.base, self.thickness, wo.z);
                    return Some(BsdfSample {
                        f: r / wo.z,
                        wi: mirror(wo),
                        pdf: p_coat,
                        flags: BxdfFlags::SPECULAR_REFLECTION,
                        eta: 1.0,
                    });
                }
                return Some(coat_reflection(wo, self.coat.eta, p_coat));
            }
            let wi = mixture_direction(&self.coat, &self.base, (p_coat, p_base), wo, uc, u)?;
            Some(BsdfSample {
                f: self.f_upper(wo, wi, mode),
                wi,
                pdf: self.pdf_upper(wo, wi),
                flags: BxdfFlags::GLOSSY_REFLECTION,
                eta: 1.0,
            })
        })
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        two_sided(wo, wi, |wo, wi| self.pdf_upper(wo, wi))
    }

    /// Density of the mixture's non-specular lobes.
    fn pdf_upper(&self, wo: Vec3, wi: Vec3) -> f32 {
        mixture_pdf(&self.coat, &self.base, self.lobe_weights(wo.z), wo, wi)
    }
}
