//! Scattering from a hair fibre (pbrt-v4 9.9, `HairBxDF`; Chiang et al.
//! 2016, after Marschner et al. 2003 and d'Eon et al. 2011).
//!
//! The fibre is a dielectric cylinder that absorbs inside. Light leaves it
//! after p internal paths: reflected at once (p = 0, R), through it (p = 1,
//! TT), back after one internal reflection (p = 2, TRT), and the rest
//! lumped together (p = 3). Each term is a longitudinal lobe `Mp` (a von
//! Mises-Fisher-like distribution in theta, its width from `beta_m`), an
//! attenuation `Ap` (Fresnel and absorption along the internal path) and an
//! azimuthal lobe `Np` (a trimmed logistic around the term's exit angle,
//! its width from `beta_n`); the cuticle's scales tilt each lobe by a
//! multiple of `alpha`.
//!
//! The local frame is pbrt-v4's: x along the fibre (the curve's dp/du), z
//! any direction perpendicular to it; only the difference of the azimuths
//! of `wo` and `wi` about x enters, so the frame's turn about x does not
//! matter. Where the ray met the fibre is `h` in [-1, 1], the offset from
//! its axis in radii (a curve's v across its width: h = 2v - 1).
//!
//! Light leaves a fibre on every side, so the lobes are glossy reflection
//! where `wi` is on the side of `wo` (of the local z) and glossy
//! transmission otherwise.

use super::{BsdfSample, BxdfFlags, TransportMode};
use crate::math::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// Terms modelled one by one; the rest are lumped into the last.
const P_MAX: usize = 3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HairBxdf {
    h: f32,
    gamma_o: f32,
    eta: f32,
    sigma_a: Vec3,
    /// Longitudinal variance of each term.
    v: [f32; P_MAX + 1],
    /// Azimuthal logistic scale.
    s: f32,
    sin_2k_alpha: [f32; P_MAX],
    cos_2k_alpha: [f32; P_MAX],
}

impl HairBxdf {
    /// A fibre met at offset `h` (in [-1, 1]), of index `eta`, absorption
    /// `sigma_a` per unit of the fibre's diameter, longitudinal and azimuthal
    /// roughness `beta_m`, `beta_n` (in (0, 1]) and scale tilt `alpha`
    /// (degrees).
    pub fn new(h: f32, eta: f32, sigma_a: Vec3, beta_m: f32, beta_n: f32, alpha: f32) -> Self {
        let h = if h.is_finite() { h.clamp(-1.0, 1.0) } else { 0.0 };
        let v0 = sqr(0.726 * beta_m + 0.812 * sqr(beta_m) + 3.7 * beta_m.powi(20));
        let v = [v0, 0.25 * v0, 4.0 * v0, 4.0 * v0];
        const SQRT_PI_OVER_8: f32 = 0.626_657_07;
        let s = SQRT_PI_OVER_8 * (0.265 * beta_n + 1.194 * sqr(beta_n) + 5.372 * beta_n.powi(22));
        let mut sin_2k_alpha = [0.0; P_MAX];
        let mut cos_2k_alpha = [0.0; P_MAX];
        sin_2k_alpha[0] = alpha.to_radians().sin();
        cos_2k_alpha[0] = safe_sqrt(1.0 - sqr(sin_2k_alpha[0]));
        for i in 1..P_MAX {
            sin_2k_alpha[i] = 2.0 * cos_2k_alpha[i - 1] * sin_2k_alpha[i - 1];
            cos_2k_alpha[i] = sqr(cos_2k_alpha[i - 1]) - sqr(sin_2k_alpha[i - 1]);
        }
        HairBxdf {
            h,
            gamma_o: safe_asin(h),
            eta,
            sigma_a: sigma_a.max(Vec3::ZERO),
            v,
            s,
            sin_2k_alpha,
            cos_2k_alpha,
        }
    }

    /// Absorption of a fibre with eumelanin and pheomelanin concentrations
    /// `ce`, `cp` (pbrt-v4's `SigmaAFromConcentration`, d'Eon et al. 2011).
    pub fn sigma_a_from_concentration(ce: f32, cp: f32) -> Vec3 {
        Vec3::new(0.419, 0.697, 1.37) * ce + Vec3::new(0.187, 0.4, 1.05) * cp
    }

    /// Absorption that gives roughly the colour `c` to a fibre of azimuthal
    /// roughness `beta_n` (pbrt-v4's `SigmaAFromReflectance`, Chiang et al.).
    pub fn sigma_a_from_reflectance(c: Vec3, beta_n: f32) -> Vec3 {
        let d = 5.969 - 0.215 * beta_n + 2.532 * sqr(beta_n) - 10.73 * beta_n.powi(3)
            + 5.574 * beta_n.powi(4)
            + 0.245 * beta_n.powi(5);
        let one = |c: f32| sqr(c.clamp(1e-6, 1.0).ln() / d);
        Vec3::new(one(c.x), one(c.y), one(c.z))
    }

    pub fn flags(&self) -> BxdfFlags {
        BxdfFlags::GLOSSY | BxdfFlags::REFLECTION | BxdfFlags::TRANSMISSION
    }

    /// sin and cos of theta_o tilted for term `p` by the scales.
    fn tilted(&self, p: usize, sin_o: f32, cos_o: f32) -> (f32, f32) {
        let (s, c) = match p {
            0 => (
                sin_o * self.cos_2k_alpha[1] - cos_o * self.sin_2k_alpha[1],
                cos_o * self.cos_2k_alpha[1] + sin_o * self.sin_2k_alpha[1],
            ),
            1 => (
                sin_o * self.cos_2k_alpha[0] + cos_o * self.sin_2k_alpha[0],
                cos_o * self.cos_2k_alpha[0] - sin_o * self.sin_2k_alpha[0],
            ),
            2 => (
                sin_o * self.cos_2k_alpha[2] + cos_o * self.sin_2k_alpha[2],
                cos_o * self.cos_2k_alpha[2] - sin_o * self.sin_2k_alpha[2],
            ),
            _ => (sin_o, cos_o),
        };
        (s, c.abs())
    }

    /// gamma_t of the refracted ray and the attenuation of each term, for
    /// `wo` at sin/cos theta_o.
    fn attenuation(&self, sin_o: f32, cos_o: f32) -> (f32, [Vec3; P_MAX + 1]) {
        let sin_t = sin_o / self.eta;
        let cos_t = safe_sqrt(1.0 - sqr(sin_t));
        let etap = safe_sqrt(sqr(self.eta) - sqr(sin_o)) / cos_o;
        let sin_gamma_t = self.h / etap;
        let cos_gamma_t = safe_sqrt(1.0 - sqr(sin_gamma_t));
        let gamma_t = safe_asin(sin_gamma_t);
        // Transmittance of one crossing of the cylinder.
        let t = exp3(-self.sigma_a * (2.0 * cos_gamma_t / cos_t));
        let cos_theta = cos_o * safe_sqrt(1.0 - sqr(self.h));
        let f = super::fr_dielectric(cos_theta, self.eta);
        let mut ap = [Vec3::ZERO; P_MAX + 1];
        ap[0] = Vec3::splat(f);
        ap[1] = t * sqr(1.0 - f);
        for p in 2..P_MAX {
            ap[p] = ap[p - 1] * t * f;
        }
        let rest = Vec3::ONE - t * f;
        ap[P_MAX] = Vec3::new(
            if rest.x != 0.0 {
                ap[P_MAX - 1].x * f * t.x / rest.x
            } else {
                0.0
            },
            if rest.y != 0.0 {
                ap[P_MAX - 1].y * f * t.y / rest.y
            } else {
                0.0
            },
            if rest.z != 0.0 {
                ap[P_MAX - 1].z * f * t.z / rest.z
            } else {
                0.0
            },
        );
        (gamma_t, ap)
    }

    /// The probability of sampling each term: its attenuation's channel mean.
    fn term_pmf(ap: &[Vec3; P_MAX + 1]) -> [f32; P_MAX + 1] {
        let mean = |a: Vec3| (a.x + a.y + a.z) / 3.0;
        let sum: f32 = ap.iter().map(|&a| mean(a)).sum();
        let mut pmf = [0.0; P_MAX + 1];
        if sum > 0.0 {
            for (q, &a) in pmf.iter_mut().zip(ap) {
                *q = mean(a) / sum;
            }
        }
        pmf
    }

    /// The fibre's BSDF, or for importance its adjoint, f(wi, wo): the model
    /// is not symmetric (its attenuation follows theta_o, its 1 / cos
    /// theta_i), so particles from lights, which meet it with the
    /// directions' roles swapped, must swap them back.
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        match mode {
            TransportMode::Radiance => self.eval(wo, wi),
            TransportMode::Importance => self.eval(wi, wo),
        }
    }

    /// The BSDF for light arriving along `wi` and leaving along `wo`.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let (sin_o, cos_o) = (wo.x, safe_sqrt(1.0 - sqr(wo.x)));
        let (sin_i, cos_i) = (wi.x, safe_sqrt(1.0 - sqr(wi.x)));
        let phi = wi.z.atan2(wi.y) - wo.z.atan2(wo.y);
        let (gamma_t, ap) = self.attenuation(sin_o, cos_o);
        let mut sum = Vec3::ZERO;
        for (p, &a) in ap.iter().enumerate().take(P_MAX) {
            let (sin_po, cos_po) = self.tilted(p, sin_o, cos_o);
            sum += a * (mp(cos_i, cos_po, sin_i, sin_po, self.v[p]) * np(phi, p, self.s, self.gamma_o, gamma_t));
        }
        sum += ap[P_MAX] * (mp(cos_i, cos_o, sin_i, sin_o, self.v[P_MAX]) / TAU);
        // The integrators multiply by |cos| about the local z; the model
        // has none.
        if wi.z != 0.0 {
            sum /= wi.z.abs();
        }
        if sum.is_finite() {
            sum
        } else {
            Vec3::ZERO
        }
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let (sin_o, cos_o) = (wo.x, safe_sqrt(1.0 - sqr(wo.x)));
        let phi_o = wo.z.atan2(wo.y);
        let (gamma_t, ap) = self.attenuation(sin_o, cos_o);
        let pmf = Self::term_pmf(&ap);
        // Choose a term, and keep what is left of `uc` for its azimuth.
        let mut p = 0;
        let mut uc = uc;
        while p < P_MAX && uc >= pmf[p] {
            uc -= pmf[p];
            p += 1;
        }
        let uc = if pmf[p] > 0.0 {
            (uc / pmf[p]).min(ONE_MINUS_EPSILON)
        } else {
            0.5
        };
        let (sin_po, cos_po) = self.tilted(p, sin_o, cos_o);
        // Sample Mp for theta_i.
        let v = self.v[p];
        let cos_theta = 1.0 + v * (u.x.max(1e-5) + (1.0 - u.x) * (-2.0 / v).exp()).ln();
        let sin_theta = safe_sqrt(1.0 - sqr(cos_theta));
        let cos_phi = (TAU * u.y).cos();
        let sin_i = (-cos_theta * sin_po + sin_theta * cos_phi * cos_po).clamp(-1.0, 1.0);
        let cos_i = safe_sqrt(1.0 - sqr(sin_i));
        // Sample Np for the azimuth.
        let dphi = if p < P_MAX {
            phi_term(p, self.gamma_o, gamma_t) + sample_trimmed_logistic(uc, self.s)
        } else {
            TAU * uc
        };
        let phi_i = phi_o + dphi;
        let wi = Vec3::new(sin_i, cos_i * phi_i.cos(), cos_i * phi_i.sin());
        let pdf = self.pdf_of(sin_o, cos_o, sin_i, cos_i, dphi, gamma_t, &pmf);
        let flags = if wi.z * wo.z > 0.0 {
            BxdfFlags::GLOSSY_REFLECTION
        } else {
            BxdfFlags::GLOSSY_TRANSMISSION
        };
        Some(BsdfSample {
            f: self.f(wo, wi, mode),
            wi,
            pdf,
            flags,
            eta: 1.0,
        })
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (sin_o, cos_o) = (wo.x, safe_sqrt(1.0 - sqr(wo.x)));
        let (sin_i, cos_i) = (wi.x, safe_sqrt(1.0 - sqr(wi.x)));
        let phi = wi.z.atan2(wi.y) - wo.z.atan2(wo.y);
        let (gamma_t, ap) = self.attenuation(sin_o, cos_o);
        self.pdf_of(sin_o, cos_o, sin_i, cos_i, phi, gamma_t, &Self::term_pmf(&ap))
    }

    #[allow(clippy::too_many_arguments)]
    fn pdf_of(
        &self,
        sin_o: f32,
        cos_o: f32,
        sin_i: f32,
        cos_i: f32,
        phi: f32,
        gamma_t: f32,
        pmf: &[f32; P_MAX + 1],
    ) -> f32 {
        let mut pdf = 0.0;
        for (p, &q) in pmf.iter().enumerate().take(P_MAX) {
            let (sin_po, cos_po) = self.tilted(p, sin_o, cos_o);
            pdf += mp(cos_i, cos_po, sin_i, sin_po, self.v[p]) * q * np(phi, p, self.s, self.gamma_o, gamma_t);
        }
        pdf += mp(cos_i, cos_o, sin_i, sin_o, self.v[P_MAX]) * pmf[P_MAX] / TAU;
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }
}

const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

fn sqr(x: f32) -> f32 {
    x * x
}

fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

fn safe_asin(x: f32) -> f32 {
    x.clamp(-1.0, 1.0).asin()
}

fn exp3(v: Vec3) -> Vec3 {
    Vec3::new(v.x.exp(), v.y.exp(), v.z.exp())
}

/// The longitudinal lobe of variance `v` (d'Eon et al. 2011; the log form
/// for small `v`, where I0 and sinh overflow).
fn mp(cos_i: f32, cos_o: f32, sin_i: f32, sin_o: f32, v: f32) -> f32 {
    let a = cos_i * cos_o / v;
    let b = sin_i * sin_o / v;
    let m = if v <= 0.1 {
        (log_i0(a) - b - 1.0 / v + std::f32::consts::LN_2 + (1.0 / (2.0 * v)).ln()).exp()
    } else {
        ((-b).exp() * i0(a)) / ((1.0 / v).sinh() * 2.0 * v)
    };
    if m.is_finite() {
        m
    } else {
        0.0
    }
}

/// The modified Bessel function of the first kind, order 0 (its series to
/// ten terms, as pbrt-v4).
fn i0(x: f32) -> f32 {
    let mut val = 0.0f32;
    let mut x2i = 1.0f32;
    let mut ifact = 1.0f32;
    let mut i4 = 1.0f32;
    for i in 0..10 {
        if i > 1 {
            ifact *= i as f32;
        }
        val += x2i / (i4 * ifact * ifact);
        x2i *= x * x;
        i4 *= 4.0;
    }
    val
}

fn log_i0(x: f32) -> f32 {
    if x > 12.0 {
        x + 0.5 * (-(TAU).ln() + (1.0 / x).ln() + 1.0 / (8.0 * x))
    } else {
        i0(x).ln()
    }
}

/// The azimuth at which term `p` leaves.
fn phi_term(p: usize, gamma_o: f32, gamma_t: f32) -> f32 {
    let p = p as f32;
    2.0 * p * gamma_t - 2.0 * gamma_o + p * PI
}

/// The azimuthal lobe of term `p`: a logistic of scale `s` around its exit
/// azimuth, trimmed to [-pi, pi].
fn np(phi: f32, p: usize, s: f32, gamma_o: f32, gamma_t: f32) -> f32 {
    let mut dphi = phi - phi_term(p, gamma_o, gamma_t);
    // Into [-pi, pi] (a bounded number of turns: phi and the exit azimuth
    // are each within a few turns).
    dphi -= TAU * (dphi / TAU).round();
    trimmed_logistic(dphi, s)
}

fn logistic(x: f32, s: f32) -> f32 {
    let e = (-x.abs() / s).exp();
    e / (s * sqr(1.0 + e))
}

fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + (-x / s).exp())
}

fn trimmed_logistic(x: f32, s: f32) -> f32 {
    logistic(x, s) / (logistic_cdf(PI, s) - logistic_cdf(-PI, s))
}

fn sample_trimmed_logistic(u: f32, s: f32) -> f32 {
    let (a, b) = (logistic_cdf(-PI, s), logistic_cdf(PI, s));
    let u = a + u * (b - a);
    let x = -s * (1.0 / u - 1.0).ln();
    if x.is_nan() {
        0.0
    } else {
        x.clamp(-PI, PI)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn uniform_sphere(u: Vec2) -> Vec3 {
        let z = 1.0 - 2.0 * u.x;
        let r = safe_sqrt(1.0 - z * z);
        let phi = TAU * u.y;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    fn random_fibre(rng: &mut Rng, sigma_a: Vec3) -> HairBxdf {
        let beta_m = 0.1 + 0.9 * rng.next_f32();
        let beta_n = 0.1 + 0.9 * rng.next_f32();
        let h = -1.0 + 2.0 * rng.next_f32();
        HairBxdf::new(h, 1.55, sigma_a, beta_m, beta_n, 2.0)
    }

    /// The integral of f |cos| over the sphere for one `wo`, by uniform
    /// sphere samples.
    fn albedo(b: &HairBxdf, wo: Vec3, rng: &mut Rng, n: usize) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for _ in 0..n {
            let wi = uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            sum += b.f(wo, wi, TransportMode::Radiance) * wi.z.abs();
        }
        sum * (4.0 * PI / n as f32)
    }

    #[test]
    fn a_fibre_that_absorbs_nothing_reflects_everything() {
        // White furnace (pbrt-v4's HairBxDF test): with sigma_a = 0 each
        // term's attenuation sums to one and Mp and Np are normalised, so
        // the albedo is 1 for any wo, h and roughness.
        let mut rng = Rng::new(7, 1);
        for _ in 0..12 {
            let b = random_fibre(&mut rng, Vec3::ZERO);
            let wo = uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            let a = albedo(&b, wo, &mut rng, 300_000);
            assert!((a.x - 1.0).abs() < 0.05, "{b:?} wo {wo}: albedo {a}");
        }
    }

    #[test]
    fn absorbing_fibres_reflect_less_and_redder_hair_less_red_light_absorbed() {
        let mut rng = Rng::new(8, 1);
        let sigma = HairBxdf::sigma_a_from_concentration(1.3, 0.0);
        let b = HairBxdf::new(0.3, 1.55, sigma, 0.3, 0.3, 2.0);
        let a = albedo(&b, Vec3::new(0.2, 0.6, 0.77).normalize(), &mut rng, 200_000);
        // Eumelanin absorbs blue most: brown hair.
        assert!(a.x < 0.95 && a.x > a.y && a.y > a.z, "{a}");
    }

    #[test]
    fn sampling_weights_match_f_cos_over_pdf_and_the_pdf_integrates_to_one() {
        let mut rng = Rng::new(9, 1);
        for _ in 0..8 {
            let b = random_fibre(&mut rng, Vec3::new(0.3, 0.5, 0.9));
            let wo = uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            // The density sample_f reports is the one pdf() gives.
            for _ in 0..200 {
                let bs = b
                    .sample_f(
                        wo,
                        rng.next_f32(),
                        Vec2::new(rng.next_f32(), rng.next_f32()),
                        TransportMode::Radiance,
                    )
                    .unwrap();
                let pdf = b.pdf(wo, bs.wi);
                assert!((bs.pdf - pdf).abs() <= 1e-3 * pdf.max(1.0), "{} vs {pdf}", bs.pdf);
                assert!((bs.wi.length() - 1.0).abs() < 1e-4);
                assert_eq!(bs.flags.is_transmissive(), bs.wi.z * wo.z <= 0.0);
            }
            // pdf() is a density on the sphere.
            let n = 200_000;
            let mut integral = 0.0;
            for _ in 0..n {
                let wi = uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
                integral += b.pdf(wo, wi);
            }
            let integral = integral * 4.0 * PI / n as f32;
            assert!((integral - 1.0).abs() < 0.05, "{b:?}: pdf integrates to {integral}");
        }
    }

    #[test]
    fn importance_sees_the_adjoint() {
        // The model is not symmetric, so light traced from the lights must
        // evaluate it with the directions swapped (its adjoint).
        let mut rng = Rng::new(11, 1);
        let b = random_fibre(&mut rng, Vec3::new(0.3, 0.5, 0.9));
        let (wo, wi) = (
            Vec3::new(0.6, 0.3, 0.74).normalize(),
            Vec3::new(-0.2, -0.9, 0.4).normalize(),
        );
        let (f, g) = (
            b.f(wo, wi, TransportMode::Radiance),
            b.f(wi, wo, TransportMode::Radiance),
        );
        assert!(
            (f - g).abs().max_element() > 0.01 * f.max_element(),
            "symmetric here: {f} {g}"
        );
        assert_eq!(b.f(wo, wi, TransportMode::Importance), g);
        let bs = b
            .sample_f(wo, 0.3, Vec2::new(0.4, 0.6), TransportMode::Importance)
            .unwrap();
        assert_eq!(bs.f, b.f(bs.wi, wo, TransportMode::Radiance));
    }

    #[test]
    fn sampled_directions_follow_the_pdf() {
        // The mean of f |cos| / pdf over sampled directions is the albedo
        // estimated by uniform directions (importance sampling is unbiased
        // only where samples land where pdf() says).
        let mut rng = Rng::new(10, 1);
        for _ in 0..6 {
            let b = random_fibre(&mut rng, Vec3::new(0.2, 0.6, 1.2));
            let wo = uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            let n = 200_000;
            let mut sum = Vec3::ZERO;
            for _ in 0..n {
                if let Some(bs) = b.sample_f(
                    wo,
                    rng.next_f32(),
                    Vec2::new(rng.next_f32(), rng.next_f32()),
                    TransportMode::Radiance,
                ) {
                    sum += bs.f * (bs.wi.z.abs() / bs.pdf);
                }
            }
            let sampled = sum / n as f32;
            let uniform = albedo(&b, wo, &mut rng, 400_000);
            for c in 0..3 {
                assert!(
                    (sampled[c] - uniform[c]).abs() < 0.03 * uniform[c].max(0.1),
                    "{b:?} wo {wo}: sampled {sampled} against {uniform}"
                );
            }
        }
    }
}
