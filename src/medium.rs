//! Participating media: homogeneous volumes that absorb and scatter light
//! between surfaces (pbrt-v4's `HomogeneousMedium` with its Henyey-Greenstein
//! phase function), and the interfaces that bound them.
//!
//! A medium fills the space on one side of the surfaces that name it
//! (pbrt-v4's `MediumInterface`): a ray crossing such a surface enters the
//! medium on the side it leaves towards, outside along the surface's normal,
//! inside against it. A surface whose two sides are the same medium leaves
//! a ray in the medium it was in. Surfaces of no material (pbrt-v4's
//! `interface`) only bound media: rays pass through them unchanged.
//!
//! Coefficients are per RGB channel, in inverse scene units. Light travels
//! through a distance d with transmittance exp(-sigma_t d), sigma_t =
//! sigma_a + sigma_s, and a fraction sigma_s / sigma_t of what a medium
//! stops is scattered, into directions the phase function gives.

use crate::math::{to_world, Vec2, Vec3};
use std::f32::consts::PI;

/// A homogeneous medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    /// Absorption coefficient.
    pub sigma_a: Vec3,
    /// Scattering coefficient.
    pub sigma_s: Vec3,
    /// Henyey-Greenstein asymmetry in (-1, 1): > 0 scatters forwards.
    pub g: f32,
}

/// The sides of a surface that bounds media: indices into the scene's
/// media, `None` for vacuum. `outside` is on the side of the surface's
/// normal as the scene stores it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MediumInterface {
    pub inside: Option<u32>,
    pub outside: Option<u32>,
}

impl MediumInterface {
    /// Whether crossing the surface changes the medium (pbrt-v4's
    /// `IsMediumTransition`); if not, rays keep the medium they were in.
    pub fn is_transition(&self) -> bool {
        self.inside != self.outside
    }

    /// The same sides seen from a normal turned the other way.
    pub fn flipped(self) -> MediumInterface {
        MediumInterface {
            inside: self.outside,
            outside: self.inside,
        }
    }
}

/// Where a ray in a medium stopped: scattered at distance `t`, or passed
/// the whole segment. The path's throughput takes `beta` (the event's value
/// over its density when distances are sampled for the path's hero channel)
/// and its channel ratios take `ratio` (each channel's density over the
/// hero's); see [`Medium::sample_distance`].
#[derive(Clone, Copy, Debug)]
pub enum MediumEvent {
    Scatter { t: f32, beta: Vec3, ratio: Vec3 },
    Pass { beta: Vec3, ratio: Vec3 },
}

impl Medium {
    pub fn sigma_t(&self) -> Vec3 {
        self.sigma_a + self.sigma_s
    }

    /// What `Scene::build` refuses: coefficients must be finite and not
    /// negative, `g` within (-1, 1).
    pub fn check(&self) -> Result<(), String> {
        let ok = |v: Vec3| v.is_finite() && v.min_element() >= 0.0;
        if !ok(self.sigma_a) || !ok(self.sigma_s) {
            return Err(format!(
                "sigma_a {} and sigma_s {} must be finite and not negative",
                self.sigma_a, self.sigma_s
            ));
        }
        if !(self.g > -1.0 && self.g < 1.0) {
            return Err(format!("g {} must lie strictly between -1 and 1", self.g));
        }
        Ok(())
    }

    /// Whether light is ever scattered (else it is only absorbed, and a
    /// path's throughput just takes the transmittance).
    pub fn scatters(&self) -> bool {
        self.sigma_s.max_element() > 0.0
    }

    /// Transmittance over distance `d` (infinite: zero where sigma_t > 0).
    pub fn transmittance(&self, d: f32) -> Vec3 {
        let st = self.sigma_t();
        Vec3::new(tr(st.x, d), tr(st.y, d), tr(st.z, d))
    }

    /// Samples where a ray travelling `t_max` through the medium next
    /// interacts, by the exponential distance of the path's `hero` channel
    /// (0, 1 or 2) with `u`.
    ///
    /// Coloured media sample a different distance in each channel. As in
    /// pbrt-v4 (hero wavelength sampling, Wilkie et al. 2014), a path keeps
    /// one channel, chosen uniformly, for all its distances, and carries with
    /// its throughput beta (value over the hero's density) the ratio r of
    /// each channel's density to the hero's; its estimate is beta / mean(r),
    /// value over the mean of the three channels' densities: one-sample MIS
    /// over the channels, with the balance heuristic, for the whole path. Each
    /// channel is unbiased, and the weight stays below 3 times what a path of
    /// its own channel would carry (choosing the channel afresh at every
    /// event instead lets the weights multiply without bound).
    ///
    /// Media that only absorb never scatter: their transmittance is taken as
    /// it is, the ratios unchanged.
    pub fn sample_distance(&self, t_max: f32, hero: usize, u: f32) -> MediumEvent {
        if !self.scatters() {
            return MediumEvent::Pass {
                beta: self.transmittance(t_max),
                ratio: Vec3::ONE,
            };
        }
        let st = self.sigma_t();
        let sc = st[hero.min(2)];
        let t = if sc > 0.0 { -(1.0 - u).ln() / sc } else { f32::INFINITY };
        if t < t_max {
            let tr = self.transmittance(t);
            let p = st * tr;
            let ph = p[hero.min(2)];
            return MediumEvent::Scatter {
                t,
                beta: self.sigma_s * tr / ph,
                ratio: p / ph,
            };
        }
        let tr = self.transmittance(t_max);
        let ph = tr[hero.min(2)];
        MediumEvent::Pass {
            beta: tr / ph,
            ratio: tr / ph,
        }
    }

    /// The phase function's value for light travelling along `d` scattered
    /// into `wi`.
    pub fn phase(&self, d: Vec3, wi: Vec3) -> f32 {
        henyey_greenstein(d.dot(wi), self.g)
    }

    /// A direction scattered from travelling along `d`, drawn from the phase
    /// function, and its density (the phase function's value: it is
    /// normalised over the sphere, and sampled exactly).
    pub fn sample_phase(&self, d: Vec3, u: Vec2) -> (Vec3, f32) {
        let g = self.g;
        let cos = if g.abs() < 1e-3 {
            1.0 - 2.0 * u.x
        } else {
            let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
            ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
        };
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
        let wi = to_world(local, d).normalize();
        (wi, henyey_greenstein(cos, g))
    }
}

fn tr(sigma: f32, d: f32) -> f32 {
    if sigma == 0.0 {
        1.0
    } else {
        (-sigma * d).exp()
    }
}

/// The Henyey-Greenstein phase function of the cosine between the direction
/// of travel and the scattered direction, per steradian.
pub fn henyey_greenstein(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * PI * denom * denom.max(0.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn henyey_greenstein_integrates_to_one_with_mean_cosine_g() {
        for g in [-0.7f32, 0.0, 0.3, 0.9] {
            // Midpoint rule over cos in [-1, 1], times 2 pi.
            let n = 200_000;
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let c = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                let p = henyey_greenstein(c as f32, g) as f64 * 2.0 * std::f64::consts::PI * 2.0 / n as f64;
                total += p;
                mean += p * c;
            }
            assert!((total - 1.0).abs() < 1e-3, "g {g}: integral {total}");
            assert!((mean - g as f64).abs() < 2e-3, "g {g}: mean cosine {mean}");
        }
    }

    #[test]
    fn phase_samples_follow_the_phase_function() {
        // Histogram of the sampled cosine against the density 2 pi p(cos),
        // chi-square over 20 bins.
        let d = Vec3::new(0.3, -0.5, 0.8).normalize();
        for g in [-0.5f32, 0.0, 0.6, 0.95] {
            let m = Medium {
                sigma_a: Vec3::ZERO,
                sigma_s: Vec3::ONE,
                g,
            };
            let mut rng = Rng::new(7, g.to_bits() as u64);
            let bins = 20;
            let n = 200_000;
            let mut counts = vec![0u32; bins];
            for _ in 0..n {
                let (wi, pdf) = m.sample_phase(d, rng.next_2d());
                assert!((wi.length() - 1.0).abs() < 1e-4);
                let c = d.dot(wi);
                assert!((pdf - m.phase(d, wi)).abs() <= 1e-3 * pdf.max(1.0), "g {g}");
                let b = (((c + 1.0) / 2.0 * bins as f32) as usize).min(bins - 1);
                counts[b] += 1;
            }
            let mut chi2 = 0.0;
            for (b, &k) in counts.iter().enumerate() {
                // Probability of the bin, by the midpoint rule on a fine grid.
                let fine = 400;
                let (lo, w) = (-1.0 + 2.0 * b as f64 / bins as f64, 2.0 / bins as f64);
                let p: f64 = (0..fine)
                    .map(|i| {
                        let c = lo + (i as f64 + 0.5) * w / fine as f64;
                        henyey_greenstein(c as f32, g) as f64 * 2.0 * std::f64::consts::PI * w / fine as f64
                    })
                    .sum();
                let e = p * n as f64;
                chi2 += (k as f64 - e).powi(2) / e;
            }
            // 19 degrees of freedom: 43.8 is the 0.999 quantile.
            assert!(chi2 < 43.8, "g {g}: chi-square {chi2}, counts {counts:?}");
        }
    }

    #[test]
    fn distance_sampling_is_unbiased_per_channel() {
        // With the hero channel uniform, beta / mean(ratio) of one segment
        // has the expected value of the transmittance when it passes, and
        // of sigma_s Tr(t) integrated over the segment, sigma_s / sigma_t
        // (1 - Tr(t_max)), when it scatters; channel by channel.
        let m = Medium {
            sigma_a: Vec3::new(0.1, 0.5, 2.0),
            sigma_s: Vec3::new(1.0, 0.2, 0.0),
            g: 0.0,
        };
        let t_max = 1.3;
        let mut rng = Rng::new(3, 4);
        let n = 400_000;
        let (mut pass, mut scatter) = (Vec3::ZERO, Vec3::ZERO);
        for i in 0..n {
            let mean = |r: Vec3| r.element_sum() / 3.0;
            match m.sample_distance(t_max, i % 3, rng.next_f32()) {
                MediumEvent::Pass { beta, ratio } => pass += beta / mean(ratio),
                MediumEvent::Scatter { t, beta, ratio } => {
                    assert!(t < t_max);
                    scatter += beta / mean(ratio);
                }
            }
        }
        let (pass, scatter) = (pass / n as f32, scatter / n as f32);
        let tr = m.transmittance(t_max);
        let st = m.sigma_t();
        let expected = m.sigma_s / st * (Vec3::ONE - tr);
        assert!((pass - tr).abs().max_element() < 0.01, "{pass} vs {tr}");
        assert!(
            (scatter - expected).abs().max_element() < 0.01,
            "{scatter} vs {expected}"
        );
        // An absorber alone never scatters and passes with exactly Tr.
        let a = Medium {
            sigma_s: Vec3::ZERO,
            ..m
        };
        match a.sample_distance(t_max, 1, 0.5) {
            MediumEvent::Pass { beta, ratio } => assert_eq!((beta, ratio), (a.transmittance(t_max), Vec3::ONE)),
            e => panic!("{e:?}"),
        }
    }
}
