//! Random numbers and sample warps.
//!
//! Every random number of a render is a pure function of (seed, pixel, sample
//! index, dimension): a camera sample's [`Sampler`] reads Owen-scrambled
//! Sobol points keyed by a hash of (seed, pixel, dimension), or a PCG32
//! stream keyed by a hash of (seed, pixel, sample) read in a fixed order.
//! That is what makes renders bit-identical for any thread count, tile order
//! or crop (pbrt-v4's sampler discipline).
//! Warps follow pbrt-v4, chapter A.5 ("Sampling Multidimensional Functions").

use crate::math::{Vec2, Vec3};
use std::f32::consts::PI;

/// SplitMix64 finaliser: a strong 64-bit mixer for building keys.
#[inline(always)]
pub fn mix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// A uniform number in [0, 1) from the bits of some floats: the same bits,
/// the same number. For decisions that must follow the geometry rather than
/// a sample stream (which material of a mix, whether an alpha cut-out lets a
/// ray through), as pbrt-v4's `HashFloat`.
pub fn hash_unit(v: &[f32]) -> f32 {
    let h = v.chunks(2).rev().fold(None, |acc: Option<u64>, pair| {
        let bits = pair[0].to_bits() as u64 | (pair.get(1).map_or(0, |b| b.to_bits()) as u64) << 32;
        Some(mix64(acc.map_or(bits, |a| bits ^ a)))
    });
    (h.unwrap_or(0) >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
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
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    #[inline(always)]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

/// The second dimension of the Sobol sequence: the column of its generator
/// matrix for index bit i (the first dimension's is `1 << (31 - i)`, the
/// radical inverse). Its direction numbers are all one (primitive polynomial
/// x + 1), so each column is the last one xored with itself shifted right:
/// Pascal's triangle mod 2.
const SOBOL_1: [u32; 32] = {
    let mut m = [0u32; 32];
    let mut v = 1u32 << 31;
    let mut i = 0;
    while i < 32 {
        m[i] = v;
        v ^= v >> 1;
        i += 1;
    }
    m
};

/// `SOBOL_1` by bytes: entry [k][b] is the xor of the columns that the set
/// bits of byte b select among index bits 8k..8k + 8.
const SOBOL_1_BYTES: [[u32; 256]; 4] = {
    let mut t = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut b = 0;
        while b < 256 {
            let mut v = 0;
            let mut j = 0;
            while j < 8 {
                if b & (1 << j) != 0 {
                    v ^= SOBOL_1[8 * k + j];
                }
                j += 1;
            }
            t[k][b] = v;
            b += 1;
        }
        k += 1;
    }
    t
};

/// `SOBOL_1_BYTES` with every entry bit reversed: the scramble hashes a
/// point in reversed order, so the 2D request looks it up reversed.
const SOBOL_1_REVERSED_BYTES: [[u32; 256]; 4] = {
    let mut t = SOBOL_1_BYTES;
    let mut k = 0;
    while k < 4 {
        let mut b = 0;
        while b < 256 {
            t[k][b] = t[k][b].reverse_bits();
            b += 1;
        }
        k += 1;
    }
    t
};

/// Sobol point `index` in dimension 0 or 1, as a 0.32 fixed-point fraction.
pub fn sobol_u32(index: u32, dim: u32) -> u32 {
    if dim == 0 {
        return index.reverse_bits();
    }
    by_bytes(&SOBOL_1_BYTES, index)
}

/// The xor of a byte table's entries for the four bytes of `index`.
#[inline(always)]
fn by_bytes(t: &[[u32; 256]; 4], index: u32) -> u32 {
    let i = index as usize;
    t[0][i & 255] ^ t[1][(i >> 8) & 255] ^ t[2][(i >> 16) & 255] ^ t[3][i >> 24]
}

/// Burley's improved Laine-Karras hash: each output bit depends only on the
/// input bits at or below it, and it is a bijection.
#[inline(always)]
fn laine_karras(mut v: u32, seed: u32) -> u32 {
    v = v.wrapping_add(seed);
    v ^= v.wrapping_mul(0x6c50_b47c);
    v ^= v.wrapping_mul(0xb82f_1e52);
    v ^= v.wrapping_mul(0xc7af_e638);
    v ^ v.wrapping_mul(0x8d22_f6e6)
}

/// Nested uniform (Owen) scrambling of a 0.32 fraction, keyed by `seed`
/// (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4), with its
/// improved Laine-Karras hash): each bit is flipped by a hash of the bits
/// above it. Every output bit depends only on the input bits at or above it,
/// and the map is a bijection, so dyadic intervals go to dyadic intervals of
/// the same size: nets stay nets. Applied to a sample index it is Burley's
/// shuffle: indices 0..2^k map one to one onto an aligned block of 2^k.
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    // In reversed order the hash's carries run from the top bit down.
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// Three 32-bit seeds from a request's 64-bit key: the shuffle's, then the
/// scrambles' of dimensions 0 and 1.
#[inline(always)]
fn seeds(key: u64) -> (u32, u32, u32) {
    let k2 = (key ^ (key >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    (key as u32, (key >> 32) as u32, (k2 >> 32) as u32)
}

/// The point of a 1D request of a padded, shuffled and Owen-scrambled Sobol
/// sampler: `key` hashes (seed, pixel, dimension). The sample index comes bit
/// reversed (`Sampler` reverses it once for all its requests), which is the
/// order Burley's shuffle hashes it in.
#[inline(always)]
fn sobol_1d(rev_index: u32, key: u64) -> u32 {
    let (s0, s1, _) = seeds(key);
    // owen_scramble(index, s0), its first reversal done.
    let shuffled = laine_karras(rev_index, s0).reverse_bits();
    // owen_scramble(sobol_u32(shuffled, 0), s1), one reversal fewer.
    laine_karras(shuffled, s1).reverse_bits()
}

/// The point of a 2D request: Sobol dimensions 0 and 1 at the same shuffled
/// index, each scrambled with its own seed.
#[inline(always)]
fn sobol_2d(rev_index: u32, key: u64) -> (u32, u32) {
    let (s0, s1, s2) = seeds(key);
    let shuffled = laine_karras(rev_index, s0).reverse_bits();
    // owen_scramble(sobol_u32(shuffled, d), s) for d = 0, 1, the hashes'
    // inputs already reversed and their outputs reversed together in one
    // 64-bit reversal: bit reversal is most of a request's work.
    let y = by_bytes(&SOBOL_1_REVERSED_BYTES, shuffled);
    let (a, b) = (laine_karras(shuffled, s1), laine_karras(y, s2));
    let both = (((b as u64) << 32) | a as u64).reverse_bits();
    ((both >> 32) as u32, both as u32)
}

/// The point of a Z-order request: the global index (a pixel's Morton index
/// followed by the sample index, bit reversed) nested-uniform scrambled with
/// a seed of the request's own, then Sobol dimensions 0 and 1 at its low 32
/// bits (all that a 32-bit point of those dimensions depends on), each
/// Owen-scrambled as in [`sobol_2d`]. The scramble maps every aligned block
/// of 2^k indices onto another, so the samples of a pixel, of two pixels
/// side by side, of a 2 x 2 square of pixels and so on are each a (0, k, 2)-net.
fn zsobol_2d(rev_global: u64, key: u64) -> (u32, u32) {
    let (_, s1, s2) = seeds(key);
    let scrambled = laine_karras64(rev_global, mix64(key ^ 0x6A09_E667_F3BC_C908));
    // The scrambled index's low 32 bits are the reversed top half.
    let index = ((scrambled >> 32) as u32).reverse_bits();
    // As in `sobol_2d`: dimension 0's point reversed is the index itself.
    let y = by_bytes(&SOBOL_1_REVERSED_BYTES, index);
    let (a, b) = (laine_karras(index, s1), laine_karras(y, s2));
    let both = (((b as u64) << 32) | a as u64).reverse_bits();
    ((both >> 32) as u32, both as u32)
}

/// [`laine_karras`] over 64 bits (Burley's multipliers as the high halves,
/// other even numbers as the low ones; even, so each step is a bijection): each
/// output bit depends only on the input bits at or below it, a bijection.
fn laine_karras64(mut v: u64, seed: u64) -> u64 {
    v = v.wrapping_add(seed);
    v ^= v.wrapping_mul(0x6c50_b47c_e1d2_a5b6);
    v ^= v.wrapping_mul(0xb82f_1e52_7a3c_9d14);
    v ^= v.wrapping_mul(0xc7af_e638_4b91_f2e2);
    v ^ v.wrapping_mul(0x8d22_f6e6_35c8_1a0e)
}

/// The Morton (Z-order) index of pixel (x, y): x in the even bits, y in the odd.
pub fn morton2(x: u32, y: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut v = v as u64;
        v = (v | (v << 16)) & 0x0000_FFFF_0000_FFFF;
        v = (v | (v << 8)) & 0x00FF_00FF_00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F_0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    }
    spread(x) | (spread(y) << 1)
}

/// A 0.32 fixed-point fraction as an f32 in [0, 1) (24 bits kept).
#[inline(always)]
fn fraction(v: u32) -> f32 {
    (v >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// The random numbers of one camera sample (pixel, sample index), read one
/// request at a time by the integrators (`next_f32`, `next_2d`).
///
/// `Independent`: the keyed PCG32 stream of (seed, pixel, sample).
/// `Sobol`: pbrt-v4's `PaddedSobolSampler` with Burley's (2020) hash-based
/// Owen scrambling. Request d (1D or 2D) of sample i takes dimension d: the
/// index i is shuffled by a nested uniform scramble keyed by hash(seed,
/// pixel, d), the shuffled index picks a point of Sobol dimension 0 (and 1
/// for a 2D request), and the point is Owen-scrambled with another hash of
/// (seed, pixel, d). So each request's values over a pixel's first 2^k
/// samples are stratified (a (0, k, 2)-net in 2D), requests are independent
/// of each other (their own shuffles and scrambles), and every value is a
/// pure function of (seed, pixel, sample index, dimension), for any number
/// of samples per pixel, and in any order. After `SOBOL_DIMENSIONS`
/// requests (long paths) the rest come from the keyed PCG32 stream.
///
/// `zsobol`: pbrt-v4's `ZSobolSampler` idea (Ahmed and Wonka 2020): the
/// samples of all pixels are one Sobol sequence, pixel after pixel in Z
/// order, so that neighbouring pixels' samples, which a pixel filter mixes,
/// are stratified together; each request scrambles the whole index and the
/// point with seeds of its own (hash(seed, dimension)), so it needs the
/// render's samples per pixel up front.
#[derive(Clone, Debug)]
pub struct Sampler {
    sobol: bool,
    /// hash(seed, pixel); hash(seed) for `zsobol`.
    key: u64,
    /// The sample index, bit reversed.
    rev_index: u32,
    /// `zsobol`: the pixel's Morton index followed by the sample index, bit
    /// reversed.
    rev_global: Option<u64>,
    dim: u32,
    rng: Stream,
}

/// A sampler's PCG32 stream, keyed when it is made but seeded only when
/// first read: a Sobol sampler seldom reads it (past `SOBOL_DIMENSIONS`
/// requests, or for another stream), and seeding it is four hashes.
#[derive(Clone, Debug)]
struct Stream {
    /// `Rng::keyed`'s (seed, a, b).
    key: (u64, u64, u64),
    rng: Option<Rng>,
}

impl Stream {
    fn keyed(seed: u64, pixel: u64, index: u64) -> Self {
        Stream {
            key: (seed, pixel, index),
            rng: None,
        }
    }

    fn seeded(rng: Rng) -> Self {
        Stream {
            key: (0, 0, 0),
            rng: Some(rng),
        }
    }

    /// The stream as it stands, seeded if it was not.
    fn rng(&self) -> Rng {
        let (seed, a, b) = self.key;
        self.rng.clone().unwrap_or_else(|| Rng::keyed(seed, a, b))
    }

    #[inline(always)]
    fn get(&mut self) -> &mut Rng {
        let (seed, a, b) = self.key;
        self.rng.get_or_insert_with(|| Rng::keyed(seed, a, b))
    }
}

/// Requests a Sobol sampler answers before handing over to its PCG32 stream.
pub const SOBOL_DIMENSIONS: u32 = 64;

impl Sampler {
    /// The sampler of sample `index` of `pixel` (a pixel's index in the full
    /// frame): Sobol points when `sobol`, else the keyed PCG32 stream.
    pub fn new(sobol: bool, seed: u64, pixel: u64, index: u32) -> Self {
        Sampler {
            sobol,
            key: mix64(seed ^ mix64(pixel ^ 0x2545_F491_4F6C_DD1D)),
            rev_index: index.reverse_bits(),
            rev_global: None,
            dim: 0,
            rng: Stream::keyed(seed, pixel, index as u64),
        }
    }

    /// The Z-order sampler of sample `index` (below 2^`log2_spp`) of pixel
    /// (x, y) (`pixel` is its index in the full frame, for the PCG32 stream
    /// past the Sobol requests). Every value is a pure function of (seed, x,
    /// y, log2_spp, index, dimension).
    pub fn zsobol(seed: u64, x: u32, y: u32, log2_spp: u32, pixel: u64, index: u32) -> Self {
        debug_assert!(log2_spp < 32 && (index as u64) < 1u64 << log2_spp);
        let global = (morton2(x, y) << log2_spp) | index as u64;
        Sampler {
            sobol: true,
            key: mix64(seed ^ 0x2545_F491_4F6C_DD1D),
            rev_index: 0,
            rev_global: Some(global.reverse_bits()),
            dim: 0,
            rng: Stream::keyed(seed, pixel, index as u64),
        }
    }

    /// Another sampler of the same sample: its own requests from the first
    /// dimension on, keyed by `stream` (so that a second path of the sample,
    /// as a bidirectional path tracer's light subpath, has dimensions of its
    /// own, stratified over the pixel's samples like the first's, whatever
    /// the first path's length).
    pub fn stream(&self, stream: u64) -> Sampler {
        let key = mix64(self.key ^ mix64(stream));
        // The PCG32 stream's own state keys the new one too: a sampler made
        // from a bare stream (`independent`) has no other key.
        let mut rng = self.rng.rng();
        let state = (rng.next_u32() as u64) << 32 | rng.next_u32() as u64;
        Sampler {
            sobol: self.sobol,
            key,
            rev_index: self.rev_index,
            rev_global: self.rev_global,
            dim: 0,
            rng: Stream::seeded(Rng::keyed(
                key ^ state,
                stream,
                self.rev_global.unwrap_or(self.rev_index as u64),
            )),
        }
    }

    /// A sampler that reads `rng` alone.
    pub fn independent(rng: Rng) -> Self {
        Sampler {
            sobol: false,
            key: 0,
            rev_index: 0,
            rev_global: None,
            dim: 0,
            rng: Stream::seeded(rng),
        }
    }

    pub fn is_sobol(&self) -> bool {
        self.sobol
    }

    /// The key of the next Sobol request, or `None` for the PCG32 stream.
    #[inline(always)]
    fn next_key(&mut self) -> Option<u64> {
        if !self.sobol || self.dim >= SOBOL_DIMENSIONS {
            return None;
        }
        let d = self.dim;
        self.dim += 1;
        // SplitMix64's stream from the pixel's key.
        Some(mix64(
            self.key.wrapping_add((d as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)),
        ))
    }

    /// Passes over the next 1D request: what follows is what it would be
    /// after `next_f32`, without computing a value nobody reads.
    #[inline(always)]
    pub fn skip_1d(&mut self) {
        if self.sobol && self.dim < SOBOL_DIMENSIONS {
            self.dim += 1;
        } else {
            self.rng.get().next_u32();
        }
    }

    /// The lobe-choice value of a BSDF sample: read only when the BSDF has
    /// lobes to choose between (else skipped, and 0.5).
    #[inline(always)]
    pub fn lobe_choice(&mut self, needed: bool) -> f32 {
        if needed {
            self.next_f32()
        } else {
            self.skip_1d();
            0.5
        }
    }

    /// Uniform in [0, 1).
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        match (self.next_key(), self.rev_global) {
            (Some(key), None) => fraction(sobol_1d(self.rev_index, key)),
            (Some(key), Some(g)) => fraction(zsobol_2d(g, key).0),
            (None, _) => self.rng.get().next_f32(),
        }
    }

    /// Uniform in [0, 1)^2.
    #[inline(always)]
    pub fn next_2d(&mut self) -> Vec2 {
        let (x, y) = match (self.next_key(), self.rev_global) {
            (Some(key), None) => sobol_2d(self.rev_index, key),
            (Some(key), Some(g)) => zsobol_2d(g, key),
            (None, _) => return self.rng.get().next_2d(),
        };
        Vec2::new(fraction(x), fraction(y))
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
    // The angle is pi/4 times a ratio in [-1, 1] (or pi/2 less that, whose
    // cosine and sine are the sine and cosine of that), where short
    // polynomials are as good as the library's sin and cos, and cheaper: this
    // runs at every diffuse bounce.
    // The two cases as selects around one division and one polynomial:
    // which applies is a coin toss a branch would mispredict half the time.
    let wide = o.x.abs() > o.y.abs();
    let (r, other) = if wide { (o.x, o.y) } else { (o.y, o.x) };
    let (s, c) = sin_cos_quarter_pi((PI / 4.0) * (other / r));
    let (a, b) = if wide { (c, s) } else { (s, c) };
    Vec2::new(r * a, r * b)
}

/// sin x and cos x for |x| <= pi/4, by their Taylor series to the x^7 and
/// x^8 terms: absolute errors below 3.2e-7 and 2.5e-8 there (a few ulps).
fn sin_cos_quarter_pi(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let s = x * (1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0))));
    let c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40320.0))));
    (s, c)
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

/// A value in [a, b] with density proportional to the smoothstep from a to b
/// (pbrt-v4's `SampleSmoothStep`): t = (x - a) / (b - a) has CDF 2t^3 - t^4,
/// inverted by Newton's method safeguarded by bisection.
pub fn sample_smoothstep(u: f32, a: f32, b: f32) -> f32 {
    let u = u as f64;
    let (mut lo, mut hi, mut t) = (0.0f64, 1.0f64, 0.5f64);
    for _ in 0..40 {
        let f = t * t * t * (2.0 - t) - u;
        if f.abs() < 1e-9 {
            break;
        }
        if f > 0.0 {
            hi = t;
        } else {
            lo = t;
        }
        let df = t * t * (6.0 - 4.0 * t);
        let next = t - f / df;
        t = if df > 0.0 && next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
    }
    a + (t as f32) * (b - a)
}

/// A piecewise-constant density on [0, 1) from `n` non-negative values
/// (pbrt-v4's `PiecewiseConstant1D`): segment i covers [i/n, (i+1)/n) and is
/// chosen in proportion to its value. Negative and non-finite values count
/// as zero; when every value is zero the distribution is empty (`integral`
/// is 0) and sampling returns a zero pdf.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    func: Vec<f32>,
    /// n + 1 entries from 0 to 1.
    cdf: Vec<f32>,
    /// The integral of the function over [0, 1]: its mean.
    integral: f32,
}

impl Distribution1D {
    /// `f` must not be empty.
    pub fn new(f: &[f32]) -> Distribution1D {
        assert!(!f.is_empty(), "a distribution needs at least one value");
        let func: Vec<f32> = f
            .iter()
            .map(|&v| if v.is_finite() && v > 0.0 { v } else { 0.0 })
            .collect();
        let n = func.len();
        // Accumulated in f64: large maps lose nothing to rounding.
        let mut sums = Vec::with_capacity(n + 1);
        let mut sum = 0.0f64;
        sums.push(0.0);
        for &v in &func {
            sum += v as f64;
            sums.push(sum);
        }
        let cdf = if sum > 0.0 {
            let mut c: Vec<f32> = sums.iter().map(|&s| (s / sum) as f32).collect();
            c[n] = 1.0;
            c
        } else {
            (0..=n).map(|i| i as f32 / n as f32).collect()
        };
        Distribution1D {
            func,
            cdf,
            integral: (sum / n as f64) as f32,
        }
    }

    /// Number of segments.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    pub fn is_empty(&self) -> bool {
        self.integral == 0.0
    }

    /// The function's integral over [0, 1] (the mean of its values).
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// The value of segment `i`.
    pub fn value(&self, i: usize) -> f32 {
        self.func[i]
    }

    /// Segment whose CDF interval holds `u`: one of non-zero value when any.
    fn find(&self, u: f32) -> usize {
        // Largest i < n with cdf[i] <= u.
        let n = self.func.len();
        self.cdf[..n].partition_point(|&c| c <= u).saturating_sub(1)
    }

    /// A point x in [0, 1) distributed as the function, with its density and
    /// segment: (x, pdf(x), segment).
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let i = self.find(u);
        if self.integral == 0.0 {
            return ((i as f32 + 0.5) / self.len() as f32, 0.0, i);
        }
        let (c0, c1) = (self.cdf[i], self.cdf[i + 1]);
        let du = if c1 > c0 {
            ((u - c0) / (c1 - c0)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let x = ((i as f32 + du) / self.len() as f32).min(ONE_MINUS_EPS);
        (x, self.func[i] / self.integral, i)
    }

    /// A segment chosen in proportion to its value, with its probability.
    pub fn sample_discrete(&self, u: f32) -> (usize, f32) {
        let i = self.find(u);
        (i, self.cdf[i + 1] - self.cdf[i])
    }

    /// The density at `x` in [0, 1] (0 for an empty distribution).
    pub fn pdf(&self, x: f32) -> f32 {
        if self.integral == 0.0 || !(0.0..=1.0).contains(&x) {
            return 0.0;
        }
        let i = ((x * self.len() as f32) as usize).min(self.len() - 1);
        self.func[i] / self.integral
    }
}

/// A piecewise-constant density on [0, 1)^2 from an `nu` x `nv` grid of
/// values, row by row (value (iu, iv) at `f[iv * nu + iu]`): a marginal
/// distribution over rows and one conditional distribution per row
/// (pbrt-v4's `PiecewiseConstant2D`).
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    conditional: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    pub fn new(f: &[f32], nu: usize, nv: usize) -> Distribution2D {
        assert!(
            nu > 0 && nv > 0 && f.len() == nu * nv,
            "a {nu} x {nv} grid needs {} values",
            nu * nv
        );
        let conditional: Vec<Distribution1D> = f.chunks_exact(nu).map(Distribution1D::new).collect();
        let marginal = Distribution1D::new(&conditional.iter().map(|c| c.integral()).collect::<Vec<_>>());
        Distribution2D { conditional, marginal }
    }

    /// The function's integral over the unit square.
    pub fn integral(&self) -> f32 {
        self.marginal.integral()
    }

    /// A point distributed as the function and its density (0 when the
    /// function is zero everywhere).
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, iv) = self.marginal.sample_continuous(u.y);
        let (x, pdf_u, _) = self.conditional[iv].sample_continuous(u.x);
        (Vec2::new(x, v), pdf_u * pdf_v)
    }

    /// The density at `p` in the unit square.
    pub fn pdf(&self, p: Vec2) -> f32 {
        let integral = self.marginal.integral();
        if integral == 0.0 || !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y) {
            return 0.0;
        }
        let nv = self.conditional.len();
        let iv = ((p.y * nv as f32) as usize).min(nv - 1);
        let row = &self.conditional[iv];
        let iu = ((p.x * row.len() as f32) as usize).min(row.len() - 1);
        row.value(iu) / integral
    }
}

/// pbrt-v4's equal-area map from the unit square to the unit sphere
/// (Clarberg 2008, "Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD"):
/// the square's centre goes to +z, its corners to -z, its edges' midpoints
/// to the equator (u = 1, v = 1/2 is +x; u = 1/2, v = 1 is +y). Equal areas
/// of the square cover equal solid angles (4 pi in all).
pub fn equal_area_square_to_sphere(p: Vec2) -> Vec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    // Signed distance from the diagonal |u| + |v| = 1: positive inside (z > 0).
    let signed_distance = 1.0 - (up + vp);
    let r = 1.0 - signed_distance.abs();
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * (PI / 4.0);
    let z = (1.0 - r * r).copysign(signed_distance);
    let (sin_phi, cos_phi) = phi.sin_cos();
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(cos_phi.copysign(u) * s, sin_phi.copysign(v) * s, z)
}

/// The inverse of `equal_area_square_to_sphere` for a unit vector.
pub fn equal_area_sphere_to_square(d: Vec3) -> Vec2 {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let b = if a == 0.0 { 0.0 } else { b / a };
    // The angle from the nearer of the x and y axes, as a fraction of 90 degrees.
    let mut phi = b.atan() * (2.0 / PI);
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        // Southern hemisphere: mirrored into the square's corners.
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    let (u, v) = (u.copysign(d.x), v.copysign(d.y));
    Vec2::new(0.5 * (u + 1.0), 0.5 * (v + 1.0))
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

    /// Whether every elementary interval of `2^a x 2^(m - a)` cells, for every
    /// a, holds exactly one of the 2^m points: a (0, m, 2)-net in base 2.
    fn is_02_net(points: &[(u32, u32)], m: u32) -> bool {
        assert_eq!(points.len(), 1 << m);
        (0..=m).all(|a| {
            let mut seen = vec![false; 1 << m];
            points.iter().all(|&(x, y)| {
                let (cx, cy) = (
                    x.checked_shr(32 - a).unwrap_or(0),
                    y.checked_shr(32 - (m - a)).unwrap_or(0),
                );
                let cell = ((cy << a) | cx) as usize;
                !std::mem::replace(&mut seen[cell], true)
            })
        })
    }

    #[test]
    fn the_quarter_pi_sine_and_cosine_match_the_library() {
        for i in -1000..=1000 {
            let x = std::f32::consts::FRAC_PI_4 * i as f32 / 1000.0;
            let (s, c) = super::sin_cos_quarter_pi(x);
            let (xs, xc) = (x as f64).sin_cos();
            assert!(
                (s as f64 - xs).abs() < 4e-7 && (c as f64 - xc).abs() < 1.2e-7,
                "{x}: {s} {c}"
            );
        }
        // The disk map stays on the disk and covers its rim.
        for (u, want) in [
            (Vec2::new(1.0, 0.5), Vec2::new(1.0, 0.0)),
            (Vec2::new(1.0, 1.0), Vec2::new(0.5f32.sqrt(), 0.5f32.sqrt())),
            (Vec2::new(0.5, 0.0), Vec2::new(0.0, -1.0)),
            (
                Vec2::new(0.0, 0.75),
                Vec2::new(
                    -(0.125f32 * std::f32::consts::PI).cos(),
                    (0.125f32 * std::f32::consts::PI).sin(),
                ) * 1.0,
            ),
        ] {
            let d = concentric_disk(u);
            assert!((d - want).length() < 1e-6, "{u:?}: {d:?} vs {want:?}");
        }
    }

    #[test]
    fn sobol_dimensions_0_and_1_form_02_nets_scrambled_or_not() {
        // The first 2^m points, any aligned block of 2^m, and the same scrambled.
        for m in 0..=10 {
            let n = 1u32 << m;
            for start in [0, n, 5 * n] {
                let raw: Vec<_> = (start..start + n).map(|i| (sobol_u32(i, 0), sobol_u32(i, 1))).collect();
                assert!(is_02_net(&raw, m), "m {m} start {start}");
                let scrambled: Vec<_> = raw
                    .iter()
                    .map(|&(x, y)| (owen_scramble(x, 0xdead_beef), owen_scramble(y, 0x1234_5678)))
                    .collect();
                assert!(is_02_net(&scrambled, m), "scrambled, m {m} start {start}");
            }
        }
        // Dimension 1 is not dimension 0 again (that would be a diagonal, no net).
        assert!(!is_02_net(
            &(0..16).map(|i| (sobol_u32(i, 0), sobol_u32(i, 0))).collect::<Vec<_>>(),
            4
        ));
        assert_eq!(
            (0..8).map(|i| sobol_u32(i, 1) >> 29).collect::<Vec<_>>(),
            [0, 4, 6, 2, 5, 1, 3, 7]
        );
        // The byte tables agree with the generator matrix column by column.
        let mut r = Rng::new(8, 0);
        for _ in 0..1000 {
            let i = r.next_u32();
            let by_bits = (0..32).filter(|b| i >> b & 1 == 1).fold(0, |v, b| v ^ SOBOL_1[b]);
            assert_eq!(sobol_u32(i, 1), by_bits, "{i:#x}");
        }
    }

    #[test]
    fn requests_are_the_scrambled_shuffled_sobol_points() {
        let mut rng = Rng::new(11, 3);
        for _ in 0..2000 {
            let (i, key) = (rng.next_u32(), ((rng.next_u32() as u64) << 32) | rng.next_u32() as u64);
            let (s0, s1, s2) = seeds(key);
            let shuffled = owen_scramble(i, s0);
            let x = owen_scramble(sobol_u32(shuffled, 0), s1);
            let y = owen_scramble(sobol_u32(shuffled, 1), s2);
            assert_eq!(sobol_2d(i.reverse_bits(), key), (x, y), "{i:#x} {key:#x}");
            assert_eq!(sobol_1d(i.reverse_bits(), key), x, "{i:#x} {key:#x}");
        }
    }

    #[test]
    fn zsobol_samples_of_a_pixel_and_of_neighbouring_pixels_form_nets() {
        // 16 samples a pixel; the pixels' Morton blocks: (6, 2), (7, 2),
        // (6, 3), (7, 3) are one 2 x 2 square; x from 4 to 8 and y from 0 to
        // 4 one 4 x 4 square.
        let log2 = 4;
        let points = |pixels: &[(u32, u32)], key: u64| -> Vec<(u32, u32)> {
            pixels
                .iter()
                .flat_map(|&(x, y)| (0..16u64).map(move |i| ((morton2(x, y) << log2) | i).reverse_bits()))
                .map(|g| zsobol_2d(g, key))
                .collect()
        };
        let square = |x0: u32, y0: u32, n: u32| -> Vec<(u32, u32)> {
            (y0..y0 + n).flat_map(|y| (x0..x0 + n).map(move |x| (x, y))).collect()
        };
        let mut r = Rng::new(5, 1);
        for _ in 0..20 {
            let key = ((r.next_u32() as u64) << 32) | r.next_u32() as u64;
            assert!(is_02_net(&points(&[(6, 3)], key), 4), "a pixel");
            assert!(is_02_net(&points(&[(6, 3), (7, 3)], key), 5), "two pixels side by side");
            assert!(is_02_net(&points(&square(6, 2, 2), key), 6), "a 2 x 2 square");
            assert!(is_02_net(&points(&square(4, 0, 4), key), 8), "a 4 x 4 square");
            // The per-pixel sampler's pixels are each a net, but not together.
            let padded: Vec<(u32, u32)> = square(6, 2, 2)
                .iter()
                .flat_map(|&(x, y)| {
                    let k = mix64(key ^ (y * 64 + x) as u64);
                    (0..16u32).map(move |i| sobol_2d(i.reverse_bits(), k))
                })
                .collect();
            assert!(!is_02_net(&padded, 6));
        }
        // Two requests of a sample are not the same point, and a 1D request
        // reads the 2D point's first coordinate.
        let (mut a, mut b) = (Sampler::zsobol(9, 6, 3, 4, 99, 5), Sampler::zsobol(9, 6, 3, 4, 99, 5));
        let first = a.next_2d();
        assert_eq!(b.next_f32(), first.x);
        assert_ne!(a.next_2d(), first);
    }

    #[test]
    fn a_samplers_stream_is_stratified_over_the_pixels_samples_whatever_came_before() {
        let to_u32 = |v: Vec2| ((v.x as f64 * 4294967296.0) as u32, (v.y as f64 * 4294967296.0) as u32);
        for (seed, pixel) in [(1, 5), (7, 1234)] {
            // The stream's requests over 16 samples of a pixel, the parent
            // having made 0 to 15 requests first (a camera path of any length).
            let firsts: Vec<(u32, u32)> = (0..16u32)
                .map(|i| {
                    let mut parent = Sampler::new(true, seed, pixel, i);
                    for _ in 0..i {
                        parent.next_2d();
                    }
                    let mut light = parent.stream(42);
                    to_u32(light.next_2d())
                })
                .collect();
            assert!(is_02_net(&firsts, 4), "seed {seed}, pixel {pixel}");
            // Another key, another point set; and not the parent's own.
            let other = Sampler::new(true, seed, pixel, 3).stream(43).next_2d();
            assert_ne!(to_u32(other), firsts[3]);
            assert_ne!(to_u32(Sampler::new(true, seed, pixel, 3).next_2d()), firsts[3]);
        }
        // Independent samplers' streams differ by their stream's state.
        let (a, b) = (
            Sampler::independent(Rng::new(1, 2)),
            Sampler::independent(Rng::new(3, 4)),
        );
        assert_ne!(a.stream(42).next_2d(), b.stream(42).next_2d());
    }

    #[test]
    fn a_skipped_request_leaves_the_next_ones_as_they_were() {
        for sobol in [true, false] {
            // Past the Sobol dimensions too, where the PCG32 stream takes over.
            for before in [0, 5, SOBOL_DIMENSIONS as usize - 1, SOBOL_DIMENSIONS as usize + 3] {
                let make = |z| match z {
                    true => Sampler::zsobol(4, 13, 5, 6, 77, 9),
                    false => Sampler::new(sobol, 4, 77, 9),
                };
                let zsobol = sobol && before == 5;
                let (mut a, mut b) = (make(zsobol), make(zsobol));
                for _ in 0..before {
                    a.next_2d();
                    b.next_2d();
                }
                a.next_f32();
                b.skip_1d();
                for _ in 0..4 {
                    assert_eq!(a.next_2d(), b.next_2d(), "sobol {sobol}, after {before}");
                    assert_eq!(a.next_f32(), b.next_f32(), "sobol {sobol}, after {before}");
                }
            }
        }
    }

    #[test]
    fn owen_scramble_shuffles_an_index_prefix_onto_an_aligned_block() {
        for seed in [0, 1, 0x9e37_79b9, u32::MAX] {
            for k in [0, 3, 8] {
                let block: Vec<u32> = (0..1u32 << k).map(|i| owen_scramble(i, seed)).collect();
                let base = block[0] >> k;
                assert!(block.iter().all(|&j| j >> k == base), "seed {seed} k {k}");
                let mut low: Vec<u32> = block.iter().map(|&j| j & ((1 << k) - 1)).collect();
                low.sort();
                assert!(low.iter().enumerate().all(|(i, &j)| i as u32 == j), "seed {seed} k {k}");
            }
        }
        // The scramble depends on its seed, and moves points.
        assert_ne!(owen_scramble(0x8000_0000, 1), owen_scramble(0x8000_0000, 2));
        assert!((0..64).any(|i| owen_scramble(i << 26, 7) != i << 26));
    }

    /// The values of request `skip` (after `skip` 1D requests) of samples
    /// 0..n of one pixel, as 2D points (x only for a 1D request).
    fn request(kind: bool, pixel: u64, skip: u32, n: u32, two_d: bool) -> Vec<Vec2> {
        (0..n)
            .map(|i| {
                let mut s = Sampler::new(kind, 42, pixel, i);
                for _ in 0..skip {
                    s.next_f32();
                }
                if two_d {
                    s.next_2d()
                } else {
                    Vec2::new(s.next_f32(), 0.0)
                }
            })
            .collect()
    }

    #[test]
    fn sobol_sampler_requests_are_stratified_in_unit_interval_and_deterministic() {
        let to_u32 = |v: f32| {
            assert!((0.0..1.0).contains(&v), "{v}");
            (v as f64 * 4294967296.0) as u32
        };
        for pixel in [0, 7, 123_456] {
            for skip in [0, 1, 5, SOBOL_DIMENSIONS - 1] {
                for m in [2, 6, 9] {
                    let n = 1u32 << m;
                    let pts = request(true, pixel, skip, n, true);
                    assert_eq!(pts, request(true, pixel, skip, n, true));
                    let fixed: Vec<_> = pts.iter().map(|p| (to_u32(p.x), to_u32(p.y))).collect();
                    assert!(is_02_net(&fixed, m), "pixel {pixel} request {skip} m {m}");
                    // 1D: one point in each of the 2^m intervals.
                    let mut cells = vec![0; n as usize];
                    for p in request(true, pixel, skip, n, false) {
                        cells[(to_u32(p.x) >> (32 - m)) as usize] += 1;
                    }
                    assert!(cells.iter().all(|&c| c == 1), "1D pixel {pixel} request {skip} m {m}");
                }
            }
        }
        // Independent samples are not stratified like that (64 points in 64 cells).
        let mut cells = [0; 64];
        for p in request(false, 3, 0, 64, false) {
            cells[(p.x * 64.0) as usize] += 1;
        }
        assert!(cells.iter().any(|&c| c != 1));
        // Pixels and requests are scrambled apart.
        let a = request(true, 1, 0, 16, true);
        assert_ne!(a, request(true, 2, 0, 16, true));
        assert_ne!(a, request(true, 1, 1, 16, true));
    }

    #[test]
    fn samplers_fall_back_to_the_keyed_stream() {
        // Independent: the keyed PCG32 stream itself.
        let mut s = Sampler::new(false, 9, 11, 13);
        let mut r = Rng::keyed(9, 11, 13);
        for _ in 0..100 {
            assert_eq!(s.next_f32(), r.next_f32());
            assert_eq!(s.next_2d(), r.next_2d());
        }
        // Sobol: that stream after its last Sobol dimension.
        let mut s = Sampler::new(true, 9, 11, 13);
        let mut r = Rng::keyed(9, 11, 13);
        let first = s.next_f32();
        assert_ne!(first, r.clone().next_f32());
        for _ in 1..SOBOL_DIMENSIONS {
            s.next_2d();
        }
        for _ in 0..100 {
            let x = s.next_f32();
            assert!((0.0..1.0).contains(&x));
            assert_eq!(x, r.next_f32());
        }
    }

    #[test]
    fn sobol_sampler_is_unbiased_and_integrates_smooth_functions_better() {
        // A smooth function on the square with a known integral:
        // f = exp(x) sin(pi y) + x y, integral (e - 1) 2 / pi + 1 / 4.
        let f = |p: Vec2| (p.x as f64).exp() * (std::f64::consts::PI * p.y as f64).sin() + (p.x * p.y) as f64;
        let exact = (std::f64::consts::E - 1.0) * 2.0 / std::f64::consts::PI + 0.25;
        let pixels = 200;
        let mut mse = [0.0f64; 2];
        let mut mean = [0.0f64; 2];
        for (k, kind) in [true, false].into_iter().enumerate() {
            for pixel in 0..pixels {
                // A later request too: every dimension must be as good.
                let skip = (pixel % 7) as u32;
                let est = request(kind, pixel, skip, 256, true).into_iter().map(f).sum::<f64>() / 256.0;
                mse[k] += (est - exact).powi(2) / pixels as f64;
                mean[k] += est / pixels as f64;
            }
        }
        // Independent: standard error of the mean over 200 x 256 samples is ~0.0014.
        assert!((mean[1] - exact).abs() < 0.006, "{mean:?} vs {exact}");
        // Scrambled Sobol: unbiased, with an error far below.
        assert!((mean[0] - exact).abs() < 0.001, "{mean:?} vs {exact}");
        assert!(mse[0] < mse[1] / 50.0, "mean squared errors {mse:?}");
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

    #[test]
    fn distribution_1d_samples_in_proportion() {
        let d = Distribution1D::new(&[0.0, 1.0, 3.0, 0.0]);
        assert!((d.integral() - 1.0).abs() < 1e-6);
        let mut counts = [0u32; 4];
        let mut r = Rng::new(4, 0);
        for _ in 0..40_000 {
            let (x, pdf, i) = d.sample_continuous(r.next_f32());
            assert_eq!((x * 4.0) as usize, i);
            assert_eq!(pdf, d.pdf(x));
            counts[i] += 1;
        }
        assert_eq!((counts[0], counts[3]), (0, 0));
        assert!((counts[2] as f32 / 30_000.0 - 1.0).abs() < 0.02, "{counts:?}");
        assert_eq!(d.sample_discrete(0.3), (2, 0.75));
        let empty = Distribution1D::new(&[0.0, f32::NAN, -1.0]);
        assert!(empty.is_empty() && empty.sample_continuous(0.5).1 == 0.0);
    }

    #[test]
    fn distribution_2d_pdf_integrates_to_one() {
        let f: Vec<f32> = (0..12).map(|i| (i % 5) as f32).collect();
        let d = Distribution2D::new(&f, 4, 3);
        let n = 64;
        let mut sum = 0.0;
        for j in 0..n {
            for i in 0..n {
                sum += d.pdf(Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32));
            }
        }
        assert!((sum / (n * n) as f32 - 1.0).abs() < 1e-4, "{sum}");
        let mut r = Rng::new(5, 0);
        for _ in 0..1000 {
            let (p, pdf) = d.sample(r.next_2d());
            assert!(pdf > 0.0 && (d.pdf(p) - pdf).abs() <= 1e-5 * pdf);
        }
    }

    #[test]
    fn equal_area_map_round_trips_and_keeps_pbrt_orientation() {
        let near = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        assert!(near(equal_area_square_to_sphere(Vec2::new(0.5, 0.5)), Vec3::Z));
        assert!(near(equal_area_square_to_sphere(Vec2::new(0.0, 0.0)), -Vec3::Z));
        assert!(near(equal_area_square_to_sphere(Vec2::new(1.0, 0.5)), Vec3::X));
        assert!(near(equal_area_square_to_sphere(Vec2::new(0.5, 1.0)), Vec3::Y));
        let mut r = Rng::new(6, 0);
        for _ in 0..10_000 {
            let p = r.next_2d();
            let d = equal_area_square_to_sphere(p);
            assert!((d.length() - 1.0).abs() < 1e-5);
            let q = equal_area_sphere_to_square(d);
            assert!((p - q).length() < 1e-4, "{p} -> {d} -> {q}");
        }
    }
}
