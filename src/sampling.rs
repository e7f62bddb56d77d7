//! Random numbers and sample warps.
//!
//! Every random number is a pure function of (seed, pixel, sample index,
//! dimension): a PCG32 stream is keyed by a hash of (seed, pixel, sample) and
//! read in a fixed order. That is what makes renders bit-identical for any
//! thread count, tile order or crop (pbrt-v4's sampler discipline).
//! Warps follow pbrt-v4, chapter A.5 ("Sampling Multidimensional Functions").

use crate::math::{Vec2, Vec3};
use std::f32::consts::PI;

/// SplitMix64 finaliser: a strong 64-bit mixer for building keys.
pub fn mix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// PCG32 (O'Neill 2014): small state, good statistics, cheap to key.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    const MULT: u64 = 6364136223846793005;

    /// A stream keyed by `(seed, a, b)`, e.g. (seed, pixel index, sample index).
    pub fn keyed(seed: u64, a: u64, b: u64) -> Self {
        let k = mix64(seed ^ mix64(a ^ mix64(b.wrapping_add(0x5851_F42D_4C95_7F2D))));
        Self::new(k, mix64(k ^ 0xDA3E_39CB_94B9_5BDB))
    }

    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Rng {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

/// Van der Corput radical inverse in base 2, in [0, 1).
pub fn radical_inverse2(i: u32) -> f32 {
    (i.reverse_bits() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// The i-th of n points of a Hammersley set shifted by `shift` (Cranley-Patterson
/// rotation). The set is stratified; the per-shading-point shift decorrelates
/// neighbouring pixels, so no banding appears where fixed samples would show it.
pub fn hammersley_shifted(i: u32, n: u32, shift: Vec2) -> Vec2 {
    let u = (i as f32 + 0.5) / n as f32 + shift.x;
    let v = radical_inverse2(i) + shift.y;
    Vec2::new(u.fract(), v.fract())
}

/// Jittered sample `i` of an `n` x `n` stratified grid on the unit square.
pub fn stratified(i: u32, n: u32, jitter: Vec2) -> Vec2 {
    let sx = (i % n) as f32;
    let sy = (i / n) as f32;
    let inv = 1.0 / n as f32;
    Vec2::new(
        ((sx + jitter.x) * inv).min(ONE_MINUS_EPS),
        ((sy + jitter.y) * inv).min(ONE_MINUS_EPS),
    )
}

/// Largest f32 below one.
pub const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;

/// Uniform direction on the unit sphere.
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Cosine-weighted direction on the hemisphere around +z (Malley's method);
/// pdf = cos(theta) / pi.
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Shirley-Chiu concentric map from the square to the unit disk.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = u * 2.0 - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, (PI / 4.0) * (o.y / o.x))
    } else {
        (o.y, PI / 2.0 - (PI / 4.0) * (o.x / o.y))
    };
    Vec2::new(r * theta.cos(), r * theta.sin())
}

/// Uniform direction in the cone around +z with half-angle cosine `cos_max`;
/// `one_minus_cos_max` is passed separately because it loses all precision in
/// f32 for narrow cones when computed as `1 - cos_max`.
pub fn uniform_cone(u: Vec2, one_minus_cos_max: f32) -> Vec3 {
    let one_minus_cos = u.x * one_minus_cos_max;
    let cos_t = 1.0 - one_minus_cos;
    let sin_t = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Inverse CDF of the tent filter of radius 1 on [-1, 1].
pub fn sample_tent(u: f32) -> f32 {
    if u < 0.5 {
        (2.0 * u).sqrt() - 1.0
    } else {
        1.0 - (2.0 - 2.0 * u).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_keyed_and_uniform() {
        let mut a = Rng::keyed(1, 2, 3);
        let mut b = Rng::keyed(1, 2, 3);
        let mut c = Rng::keyed(1, 2, 4);
        let (mut same, mut sum) = (0, 0.0f64);
        for _ in 0..10_000 {
            let x = a.next_f32();
            assert_eq!(x, b.next_f32());
            assert!((0.0..1.0).contains(&x));
            if x == c.next_f32() {
                same += 1;
            }
            sum += x as f64;
        }
        assert!(same < 5, "streams with different keys must differ");
        assert!((sum / 10_000.0 - 0.5).abs() < 0.01);
    }

    #[test]
    fn warps_land_where_they_should() {
        let mut r = Rng::new(7, 0);
        let mut mean_cos = 0.0;
        for _ in 0..20_000 {
            let u = r.next_2d();
            let s = uniform_sphere(u);
            assert!((s.length() - 1.0).abs() < 1e-5);
            let c = cosine_hemisphere(u);
            assert!(c.z >= 0.0 && (c.length() - 1.0).abs() < 1e-5);
            mean_cos += c.z as f64;
            let k = uniform_cone(u, 0.1);
            assert!(k.z >= 0.9 - 1e-6);
        }
        // E[cos] under the cosine distribution is 2/3.
        assert!((mean_cos / 20_000.0 - 2.0 / 3.0).abs() < 0.01);
    }

    #[test]
    fn hammersley_is_stratified_in_both_axes() {
        let n = 64;
        let mut xs = vec![0; n as usize];
        let mut ys = vec![0; n as usize];
        for i in 0..n {
            let p = hammersley_shifted(i, n, Vec2::new(0.37, 0.81));
            xs[(p.x * n as f32) as usize] += 1;
            ys[(p.y * n as f32) as usize] += 1;
        }
        assert!(xs.iter().all(|&c| c == 1));
        assert!(ys.iter().all(|&c| c == 1));
    }

    #[test]
    fn tent_inverse_cdf_is_monotone_and_symmetric() {
        assert!((sample_tent(0.5)).abs() < 1e-6);
        assert!((sample_tent(0.0) + 1.0).abs() < 1e-6);
        assert!((sample_tent(0.25) + sample_tent(0.75)).abs() < 1e-6);
    }
}
