//! A dielectric coat over a metal (pbrt-v4's `coatedconductor`), evaluated
//! as pbrt-v4 evaluates it: a random walk between the two interfaces
//! (`LayeredBxDF`, after Guo, Hašan, Yan and Zhao, "Position-Free Monte
//! Carlo Simulation for Arbitrary Layered BSDFs", 2018).
//!
//! # Why a random walk here, and a closed form for `coateddiffuse`
//!
//! Under a coat, a rough metal reflects much of the light it receives into
//! directions the coat reflects back by total internal reflection (with
//! alpha 0.3 and eta 1.5, 38% of it at normal incidence: what leaves the
//! metal more than 41.8 degrees from the normal), and that light scatters
//! again and again before it leaves, with a colour that deepens at every
//! bounce. A single-scattering closed form would lose all
//! of it; a diffuse base forgets directions, which is what made a closed form
//! possible for [`super::CoatedDiffuseBxdf`]. So `f` is pbrt-v4's stochastic
//! estimate: an unbiased estimate of the layered BSDF (cut, as pbrt-v4's,
//! after `max_depth` scattering events, and by Russian roulette), its random
//! numbers keyed by the two directions, so the same pair always gets the same
//! value and renders stay deterministic.
//!
//! What differs from pbrt-v4 is sampling: `sample_f` draws from a
//! deterministic mixture (the coat's reflection, the metal's lobe seen
//! through the smooth coat, and a cosine lobe for the light that bounced
//! more), whose density `pdf` returns exactly. Its weight is the estimate of
//! `f` over that density: unbiased, and the MIS weights of the integrators
//! are exact (pbrt-v4 returns a density proportional to the walk's and a
//! noisy `pdf`). When the coat and the metal are both smooth, the whole BSDF
//! is one specular reflection, whose reflectance is summed in closed form:
//! F + (1 - F)^2 R A^2 / (1 - F R A^2), with F the coat's Fresnel
//! reflectance, R the metal's at the refracted angle and A the absorption
//! of one crossing of the coat.
//!
//! One departure from pbrt-v4's walk: at every visit to the metal, light
//! towards `wi` is found by two strategies (a direction sampled through the
//! coat from `wi`, and the metal's own sample), weighed by the power
//! heuristic. pbrt-v4 weighs the second by the density of sampling `wi`
//! from the inside direction, where the first strategy's density is that of
//! sampling the inside direction from `wi`; the weights then do not sum to
//! one when both interfaces are rough, and its `f` comes out 8.7% too bright
//! in albedo (coat and metal alpha 0.3, normal incidence) against the analog
//! walk, its own `Sample_f`. We use the first strategy's density there, and
//! agree with the analog walk within its noise (the test
//! `coated_conductor_against_layered_random_walk`).
//!
//! The coat only absorbs (pbrt-v4's `albedo` 0, its default); a coat whose
//! medium scatters is [`super::ScatteringCoatBxdf`].

use super::dielectric::Lobes;
use super::fresnel::{fr_complex_rgb, fr_dielectric};
use super::{
    coat_reflection, mirror, two_sided, two_sided_sample, BsdfSample, BxdfFlags, ConductorBxdf, DielectricBxdf,
    TransportMode,
};
use crate::math::{Vec2, Vec3};
use crate::sampling::{cosine_hemisphere, mix64, Rng};
use std::f32::consts::FRAC_1_PI;

/// Key of the walk's random numbers (pbrt-v4 hashes its global seed in).
const WALK_SEED: u64 = 0x1a7e_12ed;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatedConductorBxdf {
    pub coat: DielectricBxdf,
    /// The metal, its index relative to the coat's.
    pub base: ConductorBxdf,
    /// Optical thickness of the coat (unit extinction).
    pub thickness: f32,
    /// Scattering events a walk may take (pbrt-v4's `maxdepth`, 10).
    pub max_depth: u32,
    /// Walks averaged per evaluation of `f` (pbrt-v4's `nsamples`, 1).
    pub samples: u32,
}

impl CoatedConductorBxdf {
    /// `base` is the metal as it would be in air: its index is divided by
    /// the coat's here, as pbrt-v4 does.
    pub fn new(coat: DielectricBxdf, base: ConductorBxdf, thickness: f32, max_depth: u32, samples: u32) -> Self {
        let eta = coat.eta;
        CoatedConductorBxdf {
            coat,
            base: ConductorBxdf::new(base.distrib, base.eta / eta, base.k / eta),
            thickness: if thickness > 0.0 { thickness.min(f32::MAX) } else { 0.0 },
            max_depth,
            samples: samples.max(1),
        }
    }

    fn coat_smooth(&self) -> bool {
        self.coat.is_specular()
    }

    fn base_smooth(&self) -> bool {
        self.base.distrib.effectively_smooth()
    }

    pub fn flags(&self) -> BxdfFlags {
        match (self.coat_smooth(), self.base_smooth()) {
            (true, true) => BxdfFlags::SPECULAR_REFLECTION,
            (true, false) => BxdfFlags::SPECULAR_REFLECTION | BxdfFlags::GLOSSY,
            _ => BxdfFlags::GLOSSY_REFLECTION,
        }
    }

    /// Fraction of light surviving a crossing of the coat along `w`.
    fn tr(&self, w: Vec3) -> f32 {
        if w.z == 0.0 {
            return 0.0;
        }
        (-self.thickness / w.z.abs()).exp()
    }

    /// The lobes `sample_f` chooses between for `wo` (upper side): the
    /// coat's reflection, the metal's lobe through the coat, the cosine.
    fn lobe_weights(&self, cos_o: f32) -> (f32, f32, f32) {
        let f = fr_dielectric(cos_o, self.coat.eta);
        let rest = 1.0 - f;
        match (self.coat_smooth(), self.base_smooth()) {
            // A rough coat over a mirror: its own lobe is the likeliest shape.
            (false, true) => (f + 0.8 * rest, 0.0, 0.2 * rest),
            (false, false) => (f + 0.2 * rest, 0.6 * rest, 0.2 * rest),
            _ => (f, 0.8 * rest, 0.2 * rest),
        }
    }

    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        two_sided(wo, wi, |wo, wi| self.f_upper(wo, wi, mode))
    }

    /// pbrt-v4's estimate of the layered BSDF, for `wo` and `wi` above.
    fn f_upper(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        if self.coat_smooth() && self.base_smooth() {
            return Vec3::ZERO;
        }
        walks_mean(&self.coat, wo, wi, mode, WALK_SEED, self.samples, |rng| {
            self.walk(wo, wi, mode, rng)
        })
    }

    /// One walk: in through the coat at `wo`, then between the metal and the
    /// underside of the coat, adding at every visit to the metal the light
    /// that leaves towards `wi`, by both of pbrt-v4's strategies weighed by
    /// the power heuristic.
    fn walk(&self, wo: Vec3, wi: Vec3, mode: TransportMode, rng: &mut Rng) -> Vec3 {
        let (coat, base) = (&self.coat, &self.base);
        let Some((wos, wis)) = walk_ends(coat, wo, wi, mode, rng) else {
            return Vec3::ZERO;
        };
        let mut f = Vec3::ZERO;
        let mut beta = wos.f * (wos.wi.z.abs() / wos.pdf);
        let mut w = wos.wi;
        let mut at_base = false;
        for depth in 0..self.max_depth {
            if roulette(depth, &mut beta, rng) {
                break;
            }
            beta *= self.tr(w);
            at_base = !at_base;
            if !at_base {
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
            if !self.base_smooth() {
                // Towards the presampled way out.
                let wt = if self.coat_smooth() {
                    1.0
                } else {
                    power_heuristic(wis.pdf, base.pdf(-w, -wis.wi))
                };
                f += beta * base.f(-w, -wis.wi) * (wis.wi.z.abs() * wt * self.tr(wis.wi) / wis.pdf) * wis.f;
            }
            let Some(bs) = base.sample_f(-w, rng.next_2d()).filter(valid) else {
                break;
            };
            beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
            w = bs.wi;
            if !self.coat_smooth() {
                // Out through the coat from the metal's sampled direction.
                let f_exit = coat.f(-w, wi, mode);
                if f_exit != Vec3::ZERO {
                    let wt = if self.base_smooth() {
                        1.0
                    } else {
                        power_heuristic(bs.pdf, coat.pdf_lobes(wi, -w, Lobes::Transmission))
                    };
                    f += beta * f_exit * (self.tr(bs.wi) * wt);
                }
            }
        }
        f
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        two_sided_sample(wo, |wo| {
            if wo.z == 0.0 {
                return None;
            }
            let bs = if self.coat_smooth() && self.base_smooth() {
                let r = mirror_reflectance(&self.coat, &self.base, self.thickness, wo.z);
                BsdfSample {
                    f: r / wo.z,
                    wi: mirror(wo),
                    pdf: 1.0,
                    flags: BxdfFlags::SPECULAR_REFLECTION,
                    eta: 1.0,
                }
            } else {
                let (p_coat, p_base, _) = self.lobe_weights(wo.z);
                if uc < p_coat && self.coat_smooth() {
                    coat_reflection(wo, self.coat.eta, p_coat)
                } else {
                    let wi = mixture_direction(&self.coat, &self.base, (p_coat, p_base), wo, uc, u)?;
                    BsdfSample {
                        f: self.f_upper(wo, wi, mode),
                        wi,
                        pdf: self.pdf_upper(wo, wi),
                        flags: BxdfFlags::GLOSSY_REFLECTION,
                        eta: 1.0,
                    }
                }
            };
            Some(bs)
        })
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        two_sided(wo, wi, |wo, wi| self.pdf_upper(wo, wi))
    }

    /// Density of the mixture's non-specular lobes.
    fn pdf_upper(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.coat_smooth() && self.base_smooth() {
            return 0.0;
        }
        mixture_pdf(&self.coat, &self.base, self.lobe_weights(wo.z), wo, wi)
    }
}

/// A sample worth following in a walk.
pub(super) fn valid(b: &BsdfSample) -> bool {
    b.pdf > 0.0 && b.wi.z != 0.0 && b.f != Vec3::ZERO
}

/// The layered estimate for `wo` and `wi` above: the coat's own reflection
/// and the mean of `samples` walks, their random numbers keyed by the two
/// directions (pbrt-v4 hashes its global seed in too), so that the same
/// pair always gets the same value.
pub(super) fn walks_mean(
    coat: &DielectricBxdf,
    wo: Vec3,
    wi: Vec3,
    mode: TransportMode,
    seed: u64,
    samples: u32,
    mut walk: impl FnMut(&mut Rng) -> Vec3,
) -> Vec3 {
    let n = samples.max(1);
    let mut f = coat.f(wo, wi, mode) * n as f32;
    let key = |w: Vec3| mix64((w.x.to_bits() as u64) | (w.y.to_bits() as u64) << 32) ^ w.z.to_bits() as u64;
    let mut rng = Rng::keyed(seed, key(wo), key(wi));
    for _ in 0..n {
        f += walk(&mut rng);
    }
    f / n as f32
}

/// A walk's two ends: the way in through the coat at `wo`, and the way out
/// to `wi`, sampled from its side (adjoint transport).
pub(super) fn walk_ends(
    coat: &DielectricBxdf,
    wo: Vec3,
    wi: Vec3,
    mode: TransportMode,
    rng: &mut Rng,
) -> Option<(BsdfSample, BsdfSample)> {
    let wos = coat
        .sample_lobes(wo, rng.next_f32(), rng.next_2d(), mode, Lobes::Transmission)
        .filter(valid)?;
    let wis = coat
        .sample_lobes(wi, rng.next_f32(), rng.next_2d(), !mode, Lobes::Transmission)
        .filter(valid)?;
    Some((wos, wis))
}

/// pbrt-v4's Russian roulette in a walk: true to end it.
pub(super) fn roulette(depth: u32, beta: &mut Vec3, rng: &mut Rng) -> bool {
    if depth > 3 && beta.max_element() < 0.25 {
        let q = (1.0 - beta.max_element()).max(0.0);
        if rng.next_f32() < q {
            return true;
        }
        *beta /= 1.0 - q;
    }
    false
}

/// The direction inside a coat of index `eta` that leaves as `w` (both
/// pointing up), or `None` for a coat of index below 1 that `w` cannot come
/// from.
fn inside(eta: f32, w: Vec3) -> Option<Vec3> {
    let (x, y) = (w.x / eta, w.y / eta);
    let z2 = 1.0 - x * x - y * y;
    (z2 > 0.0).then(|| Vec3::new(x, y, z2.sqrt()))
}

/// The direction outside that light inside going up along `w` leaves as;
/// `None` under total internal reflection.
pub(super) fn outside(eta: f32, w: Vec3) -> Option<Vec3> {
    let (x, y) = (w.x * eta, w.y * eta);
    let z2 = 1.0 - x * x - y * y;
    (z2 > 0.0).then(|| Vec3::new(x, y, z2.sqrt()))
}

/// Reflectance of a smooth coat over a smooth metal (relative index), for
/// light that crosses the coat's `thickness` without meeting its medium.
pub(super) fn mirror_reflectance(coat: &DielectricBxdf, metal: &ConductorBxdf, thickness: f32, cos_o: f32) -> Vec3 {
    let eta = coat.eta;
    let f = fr_dielectric(cos_o, eta);
    let cos_t2 = 1.0 - (1.0 - cos_o * cos_o) / (eta * eta);
    if cos_t2 <= 0.0 {
        return Vec3::splat(f);
    }
    let cos_t = cos_t2.sqrt();
    let a = (-thickness / cos_t).exp();
    let r = fr_complex_rgb(cos_t, metal.eta, metal.k) * (a * a);
    Vec3::splat(f) + r * ((1.0 - f) * (1.0 - f)) / (Vec3::ONE - r * f)
}

/// A direction (upper side) from the coats' sampling mixture for `wo`: the
/// coat's rough reflection with probability `p_coat`, the metal's lobe seen
/// through the smooth coat with `p_base`, else the cosine lobe.
pub(super) fn mixture_direction(
    coat: &DielectricBxdf,
    metal: &ConductorBxdf,
    (p_coat, p_base): (f32, f32),
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<Vec3> {
    let wi = if uc < p_coat {
        let wm = coat.distrib.sample_wm(wo, u);
        super::reflect(wo, wm)
    } else if uc < p_coat + p_base {
        let inner = metal.sample_f(inside(coat.eta, wo)?, u)?.wi;
        outside(coat.eta, inner)?
    } else {
        cosine_hemisphere(u)
    };
    (wi.z > 0.0).then_some(wi)
}

/// The density of [`mixture_direction`]'s non-specular lobes, with the
/// probabilities of the coat, the metal and the cosine lobe.
pub(super) fn mixture_pdf(
    coat: &DielectricBxdf,
    metal: &ConductorBxdf,
    (p_coat, p_base, p_cos): (f32, f32, f32),
    wo: Vec3,
    wi: Vec3,
) -> f32 {
    let mut pdf = p_cos * wi.z * FRAC_1_PI;
    if !coat.is_specular() {
        let wm = (wo + wi).normalize();
        pdf += p_coat * coat.distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs());
    }
    if p_base > 0.0 {
        let eta = coat.eta;
        if let (Some(o), Some(i)) = (inside(eta, wo), inside(eta, wi)) {
            // Refraction compresses solid angle: dw_in / dw_out =
            // cos_out / (eta^2 cos_in).
            pdf += p_base * metal.pdf(o, i) * wi.z / (eta * eta * i.z);
        }
    }
    pdf
}

pub(super) fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2.is_infinite() {
        return 1.0;
    }
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}
