//! Fresnel reflectance and the specular directions (pbrt-v4 9.3-9.4):
//! the unpolarised Fresnel equations for dielectrics and, with a complex
//! index of refraction, for conductors; mirror reflection and Snell's law.

use crate::math::Vec3;

/// Mirror reflection of `wo` about the unit vector `n` (either side).
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    n * (2.0 * wo.dot(n)) - wo
}

/// Refraction of `wi` through an interface with unit normal `n` and relative
/// index `eta` = eta_below / eta_above (below: the side opposite `n`). When
/// `wi` arrives from below, the interface is flipped first. Returns the
/// transmitted direction and the relative index along the path
/// (eta_transmitted / eta_incident), or `None` under total internal reflection.
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = n.dot(wi);
    let (n, eta) = if cos_i < 0.0 {
        cos_i = -cos_i;
        (-n, 1.0 / eta)
    } else {
        (n, eta)
    };
    // Snell's law gives sin^2 of the transmitted angle.
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let wt = -wi / eta + n * (cos_i / eta - cos_t);
    Some((wt, eta))
}

/// Unpolarised Fresnel reflectance of a dielectric interface with relative
/// index `eta` (below / above) for light at cosine `cos_theta_i` to the
/// normal; a negative cosine means the light comes from below. 1 under total
/// internal reflection.
pub fn fr_dielectric(cos_theta_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_theta_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
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

/// Unpolarised Fresnel reflectance of a conductor with complex relative index
/// `eta + i k`, for light at cosine `cos_theta_i` (clamped to [0, 1]).
pub fn fr_complex(cos_theta_i: f32, eta: f32, k: f32) -> f32 {
    let cos_i = cos_theta_i.clamp(0.0, 1.0);
    let n = Complex::new(eta, k);
    if n.norm() == 0.0 {
        // The limit of a vanishing index: everything is reflected.
        return 1.0;
    }
    // Snell's law with a complex index: sin^2 and cos of the transmitted angle.
    let sin2_t = Complex::real(1.0 - cos_i * cos_i) / (n * n);
    let cos_t = (Complex::real(1.0) - sin2_t).sqrt();
    let ci = Complex::real(cos_i);
    let r_parl = (n * ci - cos_t) / (n * ci + cos_t);
    let r_perp = (ci - n * cos_t) / (ci + n * cos_t);
    0.5 * (r_parl.norm() + r_perp.norm())
}

/// [`fr_complex`] for each RGB channel.
pub fn fr_complex_rgb(cos_theta_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    Vec3::new(
        fr_complex(cos_theta_i, eta.x, k.x),
        fr_complex(cos_theta_i, eta.y, k.y),
        fr_complex(cos_theta_i, eta.z, k.z),
    )
}

/// The little complex arithmetic the conductor Fresnel equations need.
#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f32,
    im: f32,
}

impl Complex {
    fn new(re: f32, im: f32) -> Self {
        Complex { re, im }
    }

    fn real(re: f32) -> Self {
        Complex { re, im: 0.0 }
    }

    /// Squared magnitude.
    fn norm(self) -> f32 {
        self.re * self.re + self.im * self.im
    }

    /// Principal square root.
    fn sqrt(self) -> Self {
        let m = self.norm().sqrt();
        if m == 0.0 {
            return Complex::real(0.0);
        }
        let re = (0.5 * (m + self.re)).max(0.0).sqrt();
        let im = (0.5 * (m - self.re)).max(0.0).sqrt();
        Complex::new(re, if self.im < 0.0 { -im } else { im })
    }
}

impl std::ops::Add for Complex {
    type Output = Complex;
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
}

impl std::ops::Sub for Complex {
    type Output = Complex;
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
}

impl std::ops::Mul for Complex {
    type Output = Complex;
    fn mul(self, o: Complex) -> Complex {
        Complex::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }
}

impl std::ops::Div for Complex {
    type Output = Complex;
    fn div(self, o: Complex) -> Complex {
        let d = o.norm();
        Complex::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
}

/// The first moment of the Fresnel reflectance of a dielectric interface,
/// int_0^1 Fr(cos, 1 / eta) cos dcos with `fr_dielectric`'s index (the fits'
/// `eta` is the index of the side the light comes from over the other's):
/// polynomial fits (d'Eon and Irving 2011, as pbrt-v4's `FresnelMoment1`).
pub fn fresnel_moment1(eta: f32) -> f32 {
    let (e2, e3, e4, e5) = (eta * eta, eta.powi(3), eta.powi(4), eta.powi(5));
    if eta < 1.0 {
        0.45966 - 1.73965 * eta + 3.37668 * e2 - 3.904945 * e3 + 2.49277 * e4 - 0.68441 * e5
    } else {
        -4.61686 + 11.1136 * eta - 10.4646 * e2 + 5.11455 * e3 - 1.27198 * e4 + 0.12746 * e5
    }
}

/// The second moment, int_0^1 Fr(cos, 1 / eta) cos^2 dcos (pbrt-v4's
/// `FresnelMoment2`).
pub fn fresnel_moment2(eta: f32) -> f32 {
    let (e2, e3, e4, e5) = (eta * eta, eta.powi(3), eta.powi(4), eta.powi(5));
    if eta < 1.0 {
        0.27614 - 0.87350 * eta + 1.12077 * e2 - 0.65095 * e3 + 0.07883 * e4 + 0.04860 * e5
    } else {
        let (r, r2, r3) = (1.0 / eta, 1.0 / e2, 1.0 / e3);
        -547.033 + 45.3087 * r3 - 218.725 * r2 + 458.843 * r + 404.557 * eta - 189.519 * e2 + 54.9327 * e3
            - 9.00603 * e4
            + 0.63942 * e5
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_fresnel_at_normal_incidence_and_tir() {
        for eta in [1.33f32, 1.5, 2.4] {
            let want = ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!((fr_dielectric(1.0, eta) - want).abs() < 1e-6);
            // From below (negative cosine) the same at normal incidence.
            assert!((fr_dielectric(-1.0, eta) - want).abs() < 1e-6);
            assert!((fr_dielectric(1.0, 1.0 / eta) - want).abs() < 1e-6);
            // Grazing incidence reflects everything.
            assert!(fr_dielectric(1e-7, eta) > 0.999);
            // Past the critical angle from inside: total internal reflection.
            let critical = (1.0 / eta).asin();
            assert_eq!(fr_dielectric(-(critical + 0.01).cos(), eta), 1.0);
            assert!(fr_dielectric(-(critical - 0.01).cos(), eta) < 1.0);
        }
        assert!(fr_dielectric(0.3, 1.0) < 1e-7);
    }

    #[test]
    fn conductor_fresnel_reduces_to_dielectric_and_to_closed_forms() {
        // k = 0 is a dielectric seen from outside.
        for cos in [1.0f32, 0.8, 0.5, 0.2, 0.01] {
            for eta in [1.2f32, 1.5, 3.0] {
                let a = fr_complex(cos, eta, 0.0);
                let b = fr_dielectric(cos, eta);
                assert!((a - b).abs() < 1e-5, "cos {cos} eta {eta}: {a} vs {b}");
            }
        }
        // Normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
        for (n, k) in [(0.2f32, 3.0f32), (1.1, 2.5), (0.05, 4.0)] {
            let want = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
            assert!((fr_complex(1.0, n, k) - want).abs() < 1e-5);
        }
        // The conductor closed form (pbrt-v3's FrConductor) at an oblique angle.
        let (cos, n, k) = (0.4f32, 0.27f32, 2.8f32);
        let sin2 = 1.0 - cos * cos;
        let t0 = n * n - k * k - sin2;
        let a2b2 = (t0 * t0 + 4.0 * n * n * k * k).sqrt();
        let a = (0.5 * (a2b2 + t0)).sqrt();
        let rs = (a2b2 + cos * cos - 2.0 * a * cos) / (a2b2 + cos * cos + 2.0 * a * cos);
        let t3 = cos * cos * a2b2 + sin2 * sin2;
        let t4 = 2.0 * a * cos * sin2;
        let rp = rs * (t3 - t4) / (t3 + t4);
        assert!((fr_complex(cos, n, k) - 0.5 * (rs + rp)).abs() < 1e-5);
    }

    #[test]
    fn refraction_obeys_snell_and_reports_the_relative_index() {
        let wi = Vec3::new(0.5f32.sin(), 0.0, 0.5f32.cos());
        let (wt, etap) = refract(wi, Vec3::Z, 1.5).unwrap();
        assert_eq!(etap, 1.5);
        assert!((wt.length() - 1.0).abs() < 1e-5);
        let sin_t = (wt.x * wt.x + wt.y * wt.y).sqrt();
        assert!((0.5f32.sin() - 1.5 * sin_t).abs() < 1e-5);
        assert!(wt.z < 0.0 && wt.x < 0.0);
        // The reverse path arrives from below: the interface flips.
        let (back, etap) = refract(wt, Vec3::Z, 1.5).unwrap();
        assert!((etap - 1.0 / 1.5).abs() < 1e-7);
        assert!((back - wi).length() < 1e-5);
        // Total internal reflection from below past the critical angle.
        assert!(refract(Vec3::new(0.9, 0.0, -(0.19f32).sqrt()), Vec3::Z, 1.5).is_none());
        let r = reflect(wi, Vec3::Z);
        assert!((r - Vec3::new(-wi.x, 0.0, wi.z)).length() < 1e-6);
    }

    #[test]
    fn fresnel_moments_match_their_integrals() {
        for eta in [0.7f32, 1.0 / 1.33, 1.33, 1.5] {
            let n = 20_000;
            let (mut m1, mut m2) = (0.0f64, 0.0f64);
            for i in 0..n {
                let c = (i as f64 + 0.5) / n as f64;
                let f = fr_dielectric(c as f32, 1.0 / eta) as f64;
                m1 += f * c / n as f64;
                m2 += f * c * c / n as f64;
            }
            // The fits are good to a few thousandths.
            assert!(
                (fresnel_moment1(eta) as f64 - m1).abs() < 0.002,
                "{eta}: {} vs {m1}",
                fresnel_moment1(eta)
            );
            assert!(
                (fresnel_moment2(eta) as f64 - m2).abs() < 0.002,
                "{eta}: {} vs {m2}",
                fresnel_moment2(eta)
            );
        }
    }
}
