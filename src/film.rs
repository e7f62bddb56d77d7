//! The film: pixel storage, the reconstruction filter, and tone mapping.
//!
//! Filtering is done by importance sampling the filter (pbrt-v4 5.4.3): each
//! camera sample's offset from the pixel centre is drawn from the filter's
//! distribution and every sample carries weight one. A pixel then depends only
//! on its own samples, so tiles and crops stitch exactly and no sample is
//! shared between threads.

use crate::math::{Vec2, Vec3};
use crate::sampling::sample_tent;

/// Pixel reconstruction filter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    /// Average over the pixel's own area.
    #[default]
    Box,
    /// Triangle of radius one pixel.
    Tent,
    /// Gaussian with sigma 0.5 pixel, truncated at 1.5 pixels.
    Gaussian,
}

impl Filter {
    pub const ALL: [Filter; 3] = [Filter::Box, Filter::Tent, Filter::Gaussian];

    pub fn name(self) -> &'static str {
        match self {
            Filter::Box => "box",
            Filter::Tent => "tent",
            Filter::Gaussian => "gaussian",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Offset from the pixel centre, in pixels, for a stratified sample `u` in [0,1)^2.
    pub fn sample(&self, u: Vec2) -> Vec2 {
        match self {
            Filter::Box => u - Vec2::splat(0.5),
            Filter::Tent => Vec2::new(sample_tent(u.x), sample_tent(u.y)),
            Filter::Gaussian => Vec2::new(truncated_gaussian(u.x), truncated_gaussian(u.y)),
        }
    }
}

const GAUSS_SIGMA: f64 = 0.5;
const GAUSS_RADIUS: f64 = 1.5;

fn truncated_gaussian(u: f32) -> f32 {
    let lo = normal_cdf(-GAUSS_RADIUS / GAUSS_SIGMA);
    let hi = normal_cdf(GAUSS_RADIUS / GAUSS_SIGMA);
    let p = (lo + (hi - lo) * u as f64).clamp(1e-12, 1.0 - 1e-12);
    (inverse_normal_cdf(p) * GAUSS_SIGMA).clamp(-GAUSS_RADIUS, GAUSS_RADIUS) as f32
}

fn normal_cdf(x: f64) -> f64 {
    0.5 * (1.0 + erf(x / std::f64::consts::SQRT_2))
}

/// Abramowitz and Stegun 7.1.26 (|error| < 1.5e-7).
fn erf(x: f64) -> f64 {
    let s = x.signum();
    let x = x.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let y = 1.0
        - (((((1.061_405_429 * t - 1.453_152_027) * t) + 1.421_413_741) * t - 0.284_496_736) * t + 0.254_829_592)
            * t
            * (-x * x).exp();
    s * y
}

/// Acklam's rational approximation of the normal quantile (relative error < 1.2e-9).
fn inverse_normal_cdf(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// A rectangle of pixels [x0, x1) x [y0, y1) within a full frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl PixelRect {
    pub fn full(width: u32, height: u32) -> Self {
        PixelRect {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    pub fn is_empty(&self) -> bool {
        self.x1 <= self.x0 || self.y1 <= self.y0
    }

    /// The I-th of N horizontal bands of a frame (rows split as evenly as possible).
    pub fn band(index: u32, count: u32, width: u32, height: u32) -> Self {
        let row = |i: u32| (i as u64 * height as u64 / count as u64) as u32;
        PixelRect {
            x0: 0,
            y0: row(index),
            x1: width,
            y1: row(index + 1),
        }
    }
}

/// Where a film sits in the full frame: the frame's size and the film's
/// rectangle in it (the OpenEXR display and data windows).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameWindow {
    pub full_width: u32,
    pub full_height: u32,
    pub rect: PixelRect,
}

impl FrameWindow {
    pub fn full(width: u32, height: u32) -> Self {
        FrameWindow {
            full_width: width,
            full_height: height,
            rect: PixelRect::full(width, height),
        }
    }
}

/// Linear RGB radiance per pixel, rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Film {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width + x) as usize]
    }

    pub fn set(&mut self, x: u32, y: u32, v: Vec3) {
        self.pixels[(y * self.width + x) as usize] = v;
    }

    /// Mean of the pixels in [x0, x1) x [y0, y1).
    pub fn mean(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> Vec3 {
        let mut s = Vec3::ZERO;
        for y in y0..y1 {
            for x in x0..x1 {
                s += self.get(x, y);
            }
        }
        s / ((x1 - x0) * (y1 - y0)) as f32
    }

    /// 8-bit sRGB after scaling by 2^exposure and clamping.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        let scale = exposure.exp2();
        self.pixels
            .iter()
            .flat_map(|p| {
                let c = *p * scale;
                [c.x, c.y, c.z].map(|v| (srgb_oetf(v.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
            })
            .collect()
    }
}

/// Assembles films that each cover a rectangle of the same frame into the
/// whole frame, refusing parts from different frames, overlaps and gaps.
/// `names` label the parts in error messages.
pub fn assemble(parts: &[(Film, FrameWindow)], names: &[String]) -> std::result::Result<Film, String> {
    let Some((_, first)) = parts.first() else {
        return Err("no parts to merge".into());
    };
    let (fw, fh) = (first.full_width, first.full_height);
    let mut owner: Vec<u32> = vec![u32::MAX; fw as usize * fh as usize];
    let mut out = Film::new(fw, fh);
    for (i, (film, w)) in parts.iter().enumerate() {
        if (w.full_width, w.full_height) != (fw, fh) {
            return Err(format!(
                "{} belongs to a {}x{} frame, {} to a {fw}x{fh} frame",
                names[i], w.full_width, w.full_height, names[0]
            ));
        }
        let r = w.rect;
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                let k = (y * fw + x) as usize;
                if owner[k] != u32::MAX {
                    return Err(format!(
                        "{} and {} overlap at pixel ({x}, {y})",
                        names[owner[k] as usize], names[i]
                    ));
                }
                owner[k] = i as u32;
                out.set(x, y, film.get(x - r.x0, y - r.y0));
            }
        }
    }
    if let Some(k) = owner.iter().position(|&o| o == u32::MAX) {
        return Err(format!(
            "gap: no part covers pixel ({}, {})",
            k as u32 % fw,
            k as u32 / fw
        ));
    }
    Ok(out)
}

/// The sRGB transfer function (IEC 61966-2-1).
pub fn srgb_oetf(v: f32) -> f32 {
    if v.is_nan() {
        0.0
    } else if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_quantile_inverts_cdf() {
        for &x in &[-2.0, -0.5, 0.0, 0.3, 1.7] {
            assert!((inverse_normal_cdf(normal_cdf(x)) - x).abs() < 1e-5);
        }
    }

    #[test]
    fn filters_stay_within_their_radius_and_are_centred() {
        for f in [Filter::Box, Filter::Tent, Filter::Gaussian] {
            let mut mean = Vec2::ZERO;
            let n = 64;
            for i in 0..n {
                for j in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    let o = f.sample(u);
                    assert!(o.abs().max_element() <= 1.5);
                    mean += o;
                }
            }
            assert!((mean / (n * n) as f32).length() < 1e-3);
        }
    }

    fn part(x0: u32, y0: u32, x1: u32, y1: u32) -> (Film, FrameWindow) {
        let mut f = Film::new(x1 - x0, y1 - y0);
        for y in y0..y1 {
            for x in x0..x1 {
                f.set(x - x0, y - y0, Vec3::new(x as f32, y as f32, 1.0));
            }
        }
        let w = FrameWindow {
            full_width: 6,
            full_height: 4,
            rect: PixelRect { x0, y0, x1, y1 },
        };
        (f, w)
    }

    #[test]
    fn assemble_stitches_parts_and_refuses_overlaps_and_gaps() {
        let names: Vec<String> = (0..3).map(|i| format!("p{i}")).collect();
        let whole = assemble(&[part(0, 0, 6, 2), part(0, 2, 3, 4), part(3, 2, 6, 4)], &names).unwrap();
        assert_eq!(whole.get(4, 3), Vec3::new(4.0, 3.0, 1.0));
        assert_eq!(whole.get(0, 0), Vec3::new(0.0, 0.0, 1.0));
        let overlap = assemble(&[part(0, 0, 6, 3), part(0, 2, 6, 4)], &names).unwrap_err();
        assert!(overlap.contains("overlap"), "{overlap}");
        let gap = assemble(&[part(0, 0, 6, 2), part(0, 3, 6, 4)], &names).unwrap_err();
        assert!(gap.contains("gap"), "{gap}");
        let mut other = part(0, 2, 6, 4);
        other.1.full_width = 7;
        assert!(assemble(&[part(0, 0, 6, 2), other], &names).is_err());
        assert_eq!(
            PixelRect::band(2, 3, 6, 10),
            PixelRect {
                x0: 0,
                y0: 6,
                x1: 6,
                y1: 10
            }
        );
    }

    #[test]
    fn srgb_endpoints() {
        assert_eq!(srgb_oetf(0.0), 0.0);
        assert!((srgb_oetf(1.0) - 1.0).abs() < 1e-6);
        let f = Film {
            width: 1,
            height: 1,
            pixels: vec![Vec3::new(0.5, 2.0, -1.0)],
        };
        assert_eq!(f.to_srgb8(0.0), vec![188, 255, 0]);
        assert_eq!(f.to_srgb8(1.0)[0], 255);
    }
}
