//! Perlin's gradient noise and the sums of its octaves that pbrt-v4's
//! procedural textures and cloud medium are made of (pbrt-v4 10.6), computed
//! as pbrt-v4 computes them: a scene that names them must show the same
//! pattern.

use crate::math::Vec3;

/// Ken Perlin's permutation of 0..256, the lattice hash of his noise (and
/// of pbrt-v4's, whose pictures a cloud must reproduce).
const PERLIN: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37, 240,
    21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177, 33, 88,
    237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83,
    111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216,
    80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173, 186,
    3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17,
    182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129,
    22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238,
    210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184,
    84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195,
    78, 66, 215, 61, 156, 180,
];

/// Gradient noise at `p` (Perlin's, with pbrt-v4's choice of the twelve
/// gradients and quintic fade), about zero, within [-1, 1].
pub(crate) fn noise(p: Vec3) -> f32 {
    // Coordinates past 2^30 wrap, as pbrt-v4's do, before the lattice
    // indices are taken. Below that the floor is taken by conversion (the
    // library's `floorf` and `fmodf` were a third of a cloud's time).
    let limit = (1u32 << 30) as f32;
    let wrap = |x: f32| if x.abs() < limit { x } else { x % limit };
    let floor = |x: f32| {
        let i = x as i64;
        if (i as f32) > x {
            i - 1
        } else {
            i
        }
    };
    let (x, y, z) = (wrap(p.x), wrap(p.y), wrap(p.z));
    let (fx, fy, fz) = (floor(x), floor(y), floor(z));
    let d = Vec3::new(x - fx as f32, y - fy as f32, z - fz as f32);
    let (ix, iy, iz) = ((fx & 255) as usize, (fy & 255) as usize, (fz & 255) as usize);
    let perm = |i: usize| PERLIN[i & 255] as usize;
    let grad = |x: usize, y: usize, z: usize, dx: f32, dy: f32, dz: f32| {
        let h = perm(perm(perm(x) + y) + z) & 15;
        let u = if h < 8 || h == 12 || h == 13 { dx } else { dy };
        let v = if h < 4 || h == 12 || h == 13 { dy } else { dz };
        (if h & 1 != 0 { -u } else { u }) + (if h & 2 != 0 { -v } else { v })
    };
    let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let lerp = |t: f32, a: f32, b: f32| (1.0 - t) * a + t * b;
    let (dx, dy, dz) = (d.x, d.y, d.z);
    let w000 = grad(ix, iy, iz, dx, dy, dz);
    let w100 = grad(ix + 1, iy, iz, dx - 1.0, dy, dz);
    let w010 = grad(ix, iy + 1, iz, dx, dy - 1.0, dz);
    let w110 = grad(ix + 1, iy + 1, iz, dx - 1.0, dy - 1.0, dz);
    let w001 = grad(ix, iy, iz + 1, dx, dy, dz - 1.0);
    let w101 = grad(ix + 1, iy, iz + 1, dx - 1.0, dy, dz - 1.0);
    let w011 = grad(ix, iy + 1, iz + 1, dx, dy - 1.0, dz - 1.0);
    let w111 = grad(ix + 1, iy + 1, iz + 1, dx - 1.0, dy - 1.0, dz - 1.0);
    let (wx, wy, wz) = (fade(dx), fade(dy), fade(dz));
    let y0 = lerp(wy, lerp(wx, w000, w100), lerp(wx, w010, w110));
    let y1 = lerp(wy, lerp(wx, w001, w101), lerp(wx, w011, w111));
    lerp(wz, y0, y1)
}

/// The noise's gradient by forward differences 0.01 apart (pbrt-v4's
/// `DNoise`).
pub(crate) fn noise_gradient(p: Vec3) -> Vec3 {
    let delta = 0.01;
    let n = noise(p);
    let ahead = Vec3::new(
        noise(p + Vec3::new(delta, 0.0, 0.0)),
        noise(p + Vec3::new(0.0, delta, 0.0)),
        noise(p + Vec3::new(0.0, 0.0, delta)),
    );
    (ahead - Vec3::splat(n)) / delta
}

/// 0 below `a`, 1 above `b`, a cubic between (pbrt-v4's `SmoothStep`).
fn smooth_step(x: f32, a: f32, b: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// How many octaves a pixel resolves where the point moves by `dpdx` and
/// `dpdy` from one pixel to the next (the noise's features are about one
/// unit wide, each octave's 1.99 times narrower): pbrt-v4's count, with its
/// fraction. Without a footprint, all of them.
fn octaves(dpdx: Vec3, dpdy: Vec3, max_octaves: u32) -> (u32, f32) {
    let len2 = dpdx.length_squared().max(dpdy.length_squared());
    let n = (-1.0 - len2.log2() / 2.0).clamp(0.0, max_octaves as f32);
    let whole = n.floor();
    (whole as u32, n - whole)
}

/// Fractional Brownian motion: octaves of noise, each at 1.99 times the
/// frequency and `omega` times the weight of the last, as many as the
/// footprint resolves, the last one faded in (pbrt-v4's `FBm`).
pub fn fbm(p: Vec3, dpdx: Vec3, dpdy: Vec3, omega: f32, max_octaves: u32) -> f32 {
    let (n, partial) = octaves(dpdx, dpdy, max_octaves);
    let (mut sum, mut lambda, mut o) = (0.0f32, 1.0f32, 1.0f32);
    for _ in 0..n {
        sum += o * noise(lambda * p);
        lambda *= 1.99;
        o *= omega;
    }
    sum + o * smooth_step(partial, 0.3, 0.7) * noise(lambda * p)
}

/// `fbm` of the noise's magnitude; the octaves the footprint cannot resolve
/// count as their average magnitude, 0.2 (pbrt-v4's `Turbulence`, which
/// adds that for the octave after the last resolved one too).
pub fn turbulence(p: Vec3, dpdx: Vec3, dpdy: Vec3, omega: f32, max_octaves: u32) -> f32 {
    let (n, partial) = octaves(dpdx, dpdy, max_octaves);
    let (mut sum, mut lambda, mut o) = (0.0f32, 1.0f32, 1.0f32);
    for _ in 0..n {
        sum += o * noise(lambda * p).abs();
        lambda *= 1.99;
        o *= omega;
    }
    let t = smooth_step(partial, 0.3, 0.7);
    sum += o * ((1.0 - t) * 0.2 + t * noise(lambda * p).abs());
    for _ in n..max_octaves {
        sum += o * 0.2;
        o *= omega;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::excessive_precision)] // as pbrt-v4 printed them
    fn noise_is_pbrts() {
        // Values of pbrt-v4's `Noise` and `DNoise` at these points, printed
        // by a program linked against pbrt-v4: a cloud must be the same
        // cloud. The lattice points are zero.
        let cases = [
            ((0.3, 0.7, 0.1), -0.0971815065, (-0.390984863, 0.379621238, 0.284908712)),
            (
                (1.5, -2.25, 3.75),
                0.0182971954,
                (0.0258257613, -0.146989524, -0.218405947),
            ),
            (
                (12.34, 5.67, -8.9),
                -0.0609646142,
                (-1.54236937, 0.631544352, 0.511443973),
            ),
            (
                (-0.6, 0.05, 0.95),
                -0.102561414,
                (0.917072594, -0.0869899988, 0.386118144),
            ),
            (
                (100.1, 200.2, 300.3),
                0.178256929,
                (0.660148263, 1.1884228, -1.01561403),
            ),
        ];
        for ((x, y, z), n, (gx, gy, gz)) in cases {
            let p = Vec3::new(x, y, z);
            assert!((noise(p) - n).abs() < 1e-6, "{p}: {} vs {n}", noise(p));
            // The differences divide by 0.01: rounding is a hundred times larger.
            let g = noise_gradient(p);
            assert!((g - Vec3::new(gx, gy, gz)).abs().max_element() < 2e-4, "{p}: {g}");
        }
        assert_eq!(noise(Vec3::new(3.0, -7.0, 11.0)), 0.0);
    }

    #[test]
    #[allow(clippy::excessive_precision)] // as pbrt-v4 printed them
    fn fbm_and_turbulence_are_pbrts_at_every_footprint() {
        // pbrt-v4's `FBm` and `Turbulence` at these points and footprints,
        // printed by a program linked against pbrt-v4: with (dpdx, dpdy) =
        // (d, -d), omega 0.5 and 8 octaves, then (d, d / 2), omega 0.7 and
        // 5 octaves. The footprints run from none (every octave) through the
        // fractional octave to a pixel wider than the noise (one octave).
        let cases = [
            (
                (0.3, 0.7, 0.1),
                (0.0, 0.0, 0.0),
                [0.213505715, 0.572375476, 0.42389828, 0.800352514],
            ),
            (
                (0.3, 0.7, 0.1),
                (0.01, 0.0, 0.0),
                [0.220711365, 0.572375476, 0.427183717, 0.800352514],
            ),
            (
                (0.3, 0.7, 0.1),
                (0.0, 0.05, 0.02),
                [0.143259734, 0.325000674, 0.411060274, 0.704583704],
            ),
            (
                (0.3, 0.7, 0.1),
                (0.3, 0.1, 0.0),
                [-0.094585523, -0.094585523, 0.498365581, 0.654548049],
            ),
            (
                (1.5, -2.25, 3.75),
                (0.0, 0.0, 0.0),
                [0.259366333, 0.383206457, 0.328678191, 0.595511377],
            ),
            (
                (1.5, -2.25, 3.75),
                (0.01, 0.0, 0.0),
                [0.257765651, 0.383206457, 0.33415857, 0.595511377],
            ),
            (
                (1.5, -2.25, 3.75),
                (0.0, 0.05, 0.02),
                [0.261781603, 0.375459582, 0.335219115, 0.560679555],
            ),
            (
                (1.5, -2.25, 3.75),
                (0.3, 0.1, 0.0),
                [0.017808428, 0.017808428, 0.42158848, 0.577770948],
            ),
            (
                (12.34, 5.67, -8.9),
                (0.0, 0.0, 0.0),
                [-0.0364585482, -0.12133278, 0.192673802, 0.369175673],
            ),
            (
                (12.34, 5.67, -8.9),
                (0.01, 0.0, 0.0),
                [-0.0421602353, -0.12133278, 0.196786702, 0.369175673],
            ),
            (
                (12.34, 5.67, -8.9),
                (0.0, 0.05, 0.02),
                [0.0107124504, 0.0461498313, 0.2060792, 0.353299081],
            ),
            (
                (12.34, 5.67, -8.9),
                (0.3, 0.1, 0.0),
                [-0.0593360849, -0.0593360849, 0.463116139, 0.619298637],
            ),
            (
                (-0.6, 0.05, 0.95),
                (0.0, 0.0, 0.0),
                [-0.0186536983, 0.015474828, 0.338324279, 0.547626376],
            ),
            (
                (-0.6, 0.05, 0.95),
                (0.01, 0.0, 0.0),
                [-0.0207896344, 0.015474828, 0.345306963, 0.547626376],
            ),
            (
                (-0.6, 0.05, 0.95),
                (0.0, 0.05, 0.02),
                [-0.0594530255, -0.0841260627, 0.368808746, 0.599631548],
            ),
            (
                (-0.6, 0.05, 0.95),
                (0.3, 0.1, 0.0),
                [-0.099821724, -0.099821724, 0.50360173, 0.659784257],
            ),
        ];
        for ((x, y, z), (dx, dy, dz), want) in cases {
            let (p, d) = (Vec3::new(x, y, z), Vec3::new(dx, dy, dz));
            let got = [
                fbm(p, d, -d, 0.5, 8),
                fbm(p, d, d * 0.5, 0.7, 5),
                turbulence(p, d, -d, 0.5, 8),
                turbulence(p, d, d * 0.5, 0.7, 5),
            ];
            for (g, w) in got.iter().zip(want) {
                assert!((g - w).abs() < 2e-5, "{p} {d}: {got:?} vs {want:?}");
            }
        }
    }
}
