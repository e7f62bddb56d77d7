//! A dielectric whose index of refraction differs by colour channel
//! (dispersion), for an RGB renderer.
//!
//! Each channel is the dielectric of its own index ([`DielectricBxdf`]).
//! Sampling picks one channel and samples its interface; the sample is then
//! weighed as one sample of the mixture of the three channels' samplers
//! (one-sample MIS with the balance heuristic), so that the value in every
//! channel stays unbiased:
//!
//! - a rough interface returns all three channels' values at the sampled
//!   direction over the mixture's density;
//! - a smooth one reflects every channel into the same mirror direction, so
//!   a reflection carries each channel's Fresnel reflectance over the
//!   mixture's probability of reflecting; a refraction leaves in a direction
//!   that only its own channel takes, so it carries that channel alone.
//!
//! The channels are picked in proportion to [`DispersiveBxdf::weights`],
//! which integrators set to their path's throughput: a path that has been
//! refracted as one channel carries that channel alone and so keeps it at
//! the next interface, as pbrt-v4, which renders spectrally, follows one
//! wavelength past such an interface (it terminates the others). Picked
//! afresh at each interface, a path through a glass ball would carry nine
//! times its channel one time in nine.

use super::dielectric::DielectricBxdf;
use super::fresnel::fr_dielectric;
use super::{abs_cos_theta, cos_theta, BsdfSample, BxdfFlags, TransportMode, TrowbridgeReitz};
use crate::math::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DispersiveBxdf {
    pub distrib: TrowbridgeReitz,
    /// Relative index (inside / outside) seen by the red, green and blue channels.
    pub eta: Vec3,
    /// How often each channel is followed, in proportion (uniform unless
    /// set; a channel of weight zero is never followed).
    pub weights: Vec3,
}

impl DispersiveBxdf {
    pub fn new(distrib: TrowbridgeReitz, eta: Vec3) -> Self {
        DispersiveBxdf {
            distrib,
            eta,
            weights: Vec3::ONE,
        }
    }

    fn channel(&self, c: usize) -> DielectricBxdf {
        DielectricBxdf::new(self.distrib, self.eta[c])
    }

    /// The probability of following each channel.
    fn choice(&self) -> Vec3 {
        let w = self.weights.max(Vec3::ZERO);
        let sum = w.element_sum();
        if sum > 0.0 && sum.is_finite() {
            w / sum
        } else {
            Vec3::splat(1.0 / 3.0)
        }
    }

    pub fn flags(&self) -> BxdfFlags {
        (0..3).fold(BxdfFlags::UNSET, |f, c| f | self.channel(c).flags())
    }

    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        // A dielectric's value is the same in every channel: take one.
        Vec3::from_array([0, 1, 2].map(|c| self.channel(c).f(wo, wi, mode).x))
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let p = self.choice();
        (0..3).map(|c| p[c] * self.channel(c).pdf(wo, wi)).sum()
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let p = self.choice();
        let c = if uc < p.x {
            0
        } else if uc < p.x + p.y || p.z == 0.0 {
            1
        } else {
            2
        };
        // The rest of `uc` within the channel's share is uniform again: it
        // chooses the lobe.
        let below = p.to_array()[..c].iter().sum::<f32>();
        let uc = ((uc - below) / p[c]).clamp(0.0, 1.0 - f32::EPSILON / 2.0);
        let chosen = self.channel(c);
        let bs = chosen.sample_f(wo, uc, u, mode)?;
        if !bs.is_specular() {
            return Some(BsdfSample {
                f: self.f(wo, bs.wi, mode),
                pdf: self.pdf(wo, bs.wi),
                ..bs
            });
        }
        if bs.is_transmission() {
            let mut only = Vec3::ZERO;
            only[c] = bs.f.x;
            return Some(BsdfSample {
                f: only,
                pdf: bs.pdf * p[c],
                ..bs
            });
        }
        // The mirror direction, which every channel reflects into with its
        // own probability (its Fresnel reflectance).
        let r = Vec3::from_array([0, 1, 2].map(|k| fr_dielectric(cos_theta(wo), self.eta[k])));
        Some(BsdfSample {
            f: r / abs_cos_theta(bs.wi),
            pdf: r.dot(p),
            ..bs
        })
    }
}
