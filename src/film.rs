//! The film: pixel storage, the reconstruction filter, and tone mapping.
//!
//! Filtering splats (pbrt-v3 7.8, Mitsuba 3's image blocks): camera samples
//! are uniform over their pixel and each adds its radiance, weighted by the
//! filter, to every pixel whose filter covers it; a pixel is the weighted sum
//! over the weights' sum. Against importance sampling the filter (pbrt-v4
//! 5.4.3, one pixel a sample), a tent of radius one then has 4/9 of the noise
//! variance per pixel at the same samples. The sums are fixed point
//! ([`PixelSum`]), so that adding them is exact and the order in which tiles,
//! threads, passes or crops deliver them cannot change a bit of the image.
//! SPPM, whose visible points belong to one pixel, still importance-samples
//! the filter ([`Filter::sample`]).

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

    /// Radius of the filter's support, in pixels.
    pub fn radius(self) -> f32 {
        match self {
            Filter::Box => 0.5,
            Filter::Tent => 1.0,
            Filter::Gaussian => GAUSS_RADIUS as f32,
        }
    }

    /// The filter's value at offset `v` (pixels) from a pixel's centre; the
    /// Gaussian less its value at the radius, as pbrt-v4's, so that it falls
    /// to zero there. Every filter is separable: the product of `profile`
    /// along x and y.
    pub fn eval(self, v: Vec2) -> f32 {
        (self.profile(v.x) * self.profile(v.y)) as f32
    }

    /// The filter's 1D profile, zero from the radius on. In f64 so that the
    /// product of two is exact for the tent (two f32 factors) and the
    /// Gaussian keeps its precision until the one rounding in `eval`.
    #[inline(always)]
    pub fn profile(self, x: f32) -> f64 {
        match self {
            // Zero from the radius on without a branch (whether a splat's
            // outer column is within reach is a coin toss): 1 - |x| is
            // +0 or negative there.
            Filter::Tent => (1.0 - x.abs()).max(0.0) as f64,
            _ if x.abs() >= self.radius() => 0.0,
            Filter::Box => 1.0,
            Filter::Gaussian => ((-0.5 * (x as f64 / GAUSS_SIGMA).powi(2)).exp() - GAUSS_EDGE).max(0.0),
        }
    }

    /// Pixels a sample reaches beyond its own on each side, when samples are
    /// uniform over their pixel.
    pub fn reach(self) -> u32 {
        (self.radius() - 0.5).ceil().max(0.0) as u32
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

/// The most pixels any filter reaches beyond a sample's own (`Filter::reach`).
const MAX_REACH: u32 = 2;

const GAUSS_SIGMA: f64 = 0.5;
const GAUSS_RADIUS: f64 = 1.5;
/// exp(-r^2 / (2 sigma^2)) at the radius: exp(-4.5).
const GAUSS_EDGE: f64 = 0.011_108_996_538_242_306;

/// Inverts the CDF of the filter's 1D profile g(x) - g(r) on [-r, r] by
/// bisection (SPPM's visible points sample the filter).
fn truncated_gaussian(u: f32) -> f32 {
    let cdf = |x: f64| {
        let area = GAUSS_SIGMA * (2.0 * std::f64::consts::PI).sqrt();
        area * (normal_cdf(x / GAUSS_SIGMA) - normal_cdf(-GAUSS_RADIUS / GAUSS_SIGMA)) - GAUSS_EDGE * (x + GAUSS_RADIUS)
    };
    let target = cdf(GAUSS_RADIUS) * u as f64;
    let (mut lo, mut hi) = (-GAUSS_RADIUS, GAUSS_RADIUS);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if cdf(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)) as f32
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

/// Fractional bits of [`PixelSum`]'s fixed point: a resolution of 3.6e-15
/// and room for sums up to 6e23, far beyond any radiance times sample count.
const FIXED_ONE: f64 = (1u64 << 48) as f64;

/// The largest sample radiance a pixel sum takes: 2^20 samples a pixel
/// (the most a render asks for), each splatted with weight at most 1 into
/// the 5 x 5 pixels the widest filter reaches, sum to at most 2.6e23, within
/// the fixed point's 6e23. Lights emit at most 1e15 (`light::MAX_EMISSION`),
/// so only a firefly of a million times that meets this.
pub const MAX_SAMPLE: f32 = 1e16;

/// One pixel's filter-weighted radiance sum and weight sum, in fixed point.
/// Integer addition is associative (wrapping, it is exact modulo 2^128), so
/// sums merged in any order are the same bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelSum {
    pub rgb: [i128; 3],
    pub weight: i128,
}

impl PixelSum {
    fn fixed(v: f64) -> i128 {
        let x = v * FIXED_ONE;
        // The same truncation; through i64 it is a machine instruction where
        // the direct conversion is a library call.
        if x.abs() < 9.0e18 {
            // SAFETY: finite (NaN fails the test) and within i64's range;
            // `as` would check both again.
            unsafe { x.to_int_unchecked::<i64>() as i128 }
        } else {
            x as i128
        }
    }

    /// Adds radiance `l` with filter weight `w`. A sample brighter than
    /// [`MAX_SAMPLE`] is scaled down to it (keeping its hue), so that no sum
    /// of a pixel's samples can pass the fixed point's range and wrap.
    pub fn add(&mut self, l: Vec3, w: f32) {
        self.add_bounded(Self::bound(l), w);
    }

    /// `l` scaled down to [`MAX_SAMPLE`] if it is brighter.
    fn bound(l: Vec3) -> Vec3 {
        if l.max_element() > MAX_SAMPLE {
            l * (MAX_SAMPLE / l.max_element())
        } else {
            l
        }
    }

    /// `add` of a radiance already `bound`.
    #[inline(always)]
    fn add_bounded(&mut self, l: Vec3, w: f32) {
        let w64 = w as f64;
        for (s, c) in self.rgb.iter_mut().zip(l.to_array()) {
            *s = s.wrapping_add(Self::fixed(c as f64 * w64));
        }
        self.weight = self.weight.wrapping_add(Self::fixed(w64));
    }

    pub fn merge(&mut self, o: &PixelSum) {
        for (s, c) in self.rgb.iter_mut().zip(o.rgb) {
            *s = s.wrapping_add(c);
        }
        self.weight = self.weight.wrapping_add(o.weight);
    }

    /// The weighted mean: black for a pixel no sample reached.
    pub fn value(&self) -> Vec3 {
        if self.weight <= 0 {
            return Vec3::ZERO;
        }
        let w = self.weight as f64;
        let [r, g, b] = self.rgb.map(|c| (c as f64 / w) as f32);
        Vec3::new(r, g, b)
    }

    /// The radiance sum itself, unweighted: light splatted by light tracing,
    /// which the sample count divides.
    pub fn total(&self) -> Vec3 {
        let [r, g, b] = self.rgb.map(|c| (c as f64 / FIXED_ONE) as f32);
        Vec3::new(r, g, b)
    }

    /// The four numbers as a flat list (for checkpoints).
    pub fn to_array(&self) -> [i128; 4] {
        [self.rgb[0], self.rgb[1], self.rgb[2], self.weight]
    }

    pub fn from_array(a: [i128; 4]) -> Self {
        PixelSum {
            rgb: [a[0], a[1], a[2]],
            weight: a[3],
        }
    }
}

/// The pixel sums of a rectangle of the frame that samples are splatted
/// into: one per tile, merged into the render's sums when the tile is done.
#[derive(Clone, Debug)]
pub struct SplatBlock {
    rect: PixelRect,
    filter: Filter,
    pub sums: Vec<PixelSum>,
}

impl SplatBlock {
    pub fn new(rect: PixelRect, filter: Filter) -> Self {
        SplatBlock {
            rect,
            filter,
            sums: vec![PixelSum::default(); rect.width() as usize * rect.height() as usize],
        }
    }

    pub fn rect(&self) -> PixelRect {
        self.rect
    }

    /// Adds radiance `l` of a sample at `pos` (frame coordinates, pixel (x, y)
    /// spanning [x, x+1) x [y, y+1)) taken in pixel `px` to the pixels of the
    /// block its filter covers. The box filter keeps the sample in `px` (the
    /// pixel it was taken in, even on its edge).
    pub fn splat(&mut self, px: (u32, u32), pos: Vec2, l: Vec3) {
        let r = self.rect;
        let l = PixelSum::bound(l);
        let width = r.width() as usize;
        if self.filter == Filter::Box {
            if (r.x0..r.x1).contains(&px.0) && (r.y0..r.y1).contains(&px.1) {
                self.sums[(px.1 - r.y0) as usize * width + (px.0 - r.x0) as usize].add_bounded(l, 1.0);
            }
            return;
        }
        // The profile at each row and column the filter reaches: 2(2r + 1)
        // evaluations instead of (2r + 1)^2 (a Gaussian's are exponentials).
        const MAX_SPAN: usize = 2 * MAX_REACH as usize + 1;
        let reach = self.filter.reach().min(MAX_REACH) as i64;
        let span = 2 * reach as usize + 1;
        // Only the columns and rows of non-zero weight are kept, packed
        // without branches: which of a tent's three are is where the sample
        // lies in its pixel, a coin toss a branch would mispredict half the
        // time. Sums are integers, so adding a weight that rounds to zero
        // adds nothing.
        let (mut xs, mut ys) = ([(0i64, 0.0f64); MAX_SPAN], [(0i64, 0.0f64); MAX_SPAN]);
        let (mut nx, mut ny) = (0, 0);
        for i in 0..span {
            let (x, y) = (px.0 as i64 + i as i64 - reach, px.1 as i64 + i as i64 - reach);
            let wx = self.filter.profile(pos.x - (x as f32 + 0.5));
            let wy = self.filter.profile(pos.y - (y as f32 + 0.5));
            xs[nx] = (x, wx);
            ys[ny] = (y, wy);
            nx += (wx > 0.0) as usize;
            ny += (wy > 0.0) as usize;
        }
        for &(y, wy) in &ys[..ny] {
            if y < r.y0 as i64 || y >= r.y1 as i64 {
                continue;
            }
            let row = (y - r.y0 as i64) as usize * width;
            for &(x, wx) in &xs[..nx] {
                if x >= r.x0 as i64 && x < r.x1 as i64 {
                    self.sums[row + (x - r.x0 as i64) as usize].add_bounded(l, (wx * wy) as f32);
                }
            }
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

    /// The film of pixel sums: each pixel their weighted mean.
    pub fn from_sums(width: u32, height: u32, sums: &[PixelSum]) -> Self {
        Film {
            width,
            height,
            pixels: sums.iter().map(PixelSum::value).collect(),
        }
    }

    /// `from_sums`, plus light-traced sums `light` (one a pixel) times `scale`.
    pub fn from_sums_and_light(width: u32, height: u32, sums: &[PixelSum], light: &[PixelSum], scale: f32) -> Self {
        Film {
            width,
            height,
            pixels: sums
                .iter()
                .zip(light)
                .map(|(s, l)| s.value() + l.total() * scale)
                .collect(),
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

    /// Maps every pixel through a colour matrix (the sensor's white
    /// balance); the film is linear, so this is the same as mapping each
    /// sample.
    pub fn transform_colours(&mut self, m: glam::Mat3) {
        self.pixels.iter_mut().for_each(|p| *p = m * *p);
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
    use crate::sampling::ONE_MINUS_EPS;

    #[test]
    fn the_brightest_samples_a_pixel_can_take_never_wrap_its_sums() {
        // The most samples a pixel sum can receive, each at the largest f32:
        // the sums stay positive and the mean is the clamp, hue kept.
        let mut s = PixelSum::default();
        let n = (1u64 << 20) * 25;
        let bright = Vec3::new(f32::MAX, f32::MAX / 2.0, 0.0);
        // Adding n equal samples is adding one n times; a few thousand
        // suffice to pass the range without the clamp, the rest are checked
        // by the sums' bound.
        for _ in 0..4096 {
            s.add(bright, 1.0);
        }
        let v = s.value();
        let want = Vec3::new(MAX_SAMPLE, MAX_SAMPLE / 2.0, 0.0);
        assert!(((v - want) / MAX_SAMPLE).abs().max_element() < 1e-6, "{v}");
        assert!((MAX_SAMPLE as f64 * FIXED_ONE * n as f64) < i128::MAX as f64);
        // A sample within the limit is taken as it is.
        let mut t = PixelSum::default();
        t.add(Vec3::new(3.0, 2.0, 1.0), 0.5);
        assert_eq!(t.value(), Vec3::new(3.0, 2.0, 1.0));
    }

    #[test]
    fn sampled_filters_follow_their_profiles() {
        // Histogram of 1D samples against the integral of the filter's
        // profile over each bin (both normalised).
        for f in [Filter::Tent, Filter::Gaussian] {
            let (bins, n) = (24usize, 48_000u32);
            let r = f.radius();
            let mut hist = vec![0f64; bins];
            for i in 0..n {
                let x = f.sample(Vec2::new((i as f32 + 0.5) / n as f32, 0.5)).x;
                hist[(((x + r) / (2.0 * r) * bins as f32) as usize).min(bins - 1)] += 1.0 / n as f64;
            }
            let profile: Vec<f64> = (0..bins)
                .map(|b| {
                    (0..100)
                        .map(|k| {
                            let x = -r + 2.0 * r * (b as f32 + (k as f32 + 0.5) / 100.0) / bins as f32;
                            f.eval(Vec2::new(x, 0.0)) as f64
                        })
                        .sum::<f64>()
                })
                .collect();
            let total: f64 = profile.iter().sum();
            for (b, (h, p)) in hist.iter().zip(&profile).enumerate() {
                assert!((h - p / total).abs() < 4e-4, "{f:?} bin {b}: {h} against {}", p / total);
            }
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

    #[test]
    fn filters_vanish_beyond_the_reach_of_a_sample_in_its_pixel() {
        for f in Filter::ALL {
            assert!(f.reach() <= MAX_REACH, "{f:?}: splat would drop pixels it reaches");
            let reach = f.reach() as f32;
            for i in 0..=16 {
                for j in 0..=16 {
                    // A sample anywhere in pixel (0, 0), and the centre of the
                    // first pixel beyond the reach, along x and along y.
                    let pos = Vec2::new(i as f32 / 16.0, j as f32 / 16.0).min(Vec2::splat(ONE_MINUS_EPS));
                    for c in [Vec2::new(reach + 1.5, 0.5), Vec2::new(-reach - 0.5, 0.5)] {
                        assert_eq!(f.eval(pos - c), 0.0, "{f:?} at {pos:?} reaches {c:?}");
                        assert_eq!(f.eval(pos - Vec2::new(c.y, c.x)), 0.0);
                    }
                }
            }
            assert!(f.eval(Vec2::ZERO) > 0.0);
        }
    }

    #[test]
    fn splatted_pixels_are_weighted_means_whatever_the_order() {
        let rect = PixelRect::full(5, 4);
        for f in Filter::ALL {
            let mut rng = crate::sampling::Rng::new(7, 1);
            let samples: Vec<((u32, u32), Vec2, Vec3)> = (0..400)
                .map(|i| {
                    let (x, y) = (i % 5, (i / 5) % 4);
                    let pos = Vec2::new(x as f32, y as f32) + rng.next_2d();
                    ((x, y), pos, Vec3::new(2.0, 0.5, 0.125))
                })
                .collect();
            let mut forward = SplatBlock::new(rect, f);
            for &(px, pos, l) in &samples {
                forward.splat(px, pos, l);
            }
            // The same samples in reverse, split over two blocks merged after.
            let mut a = SplatBlock::new(rect, f);
            let mut b = SplatBlock::new(rect, f);
            for (k, &(px, pos, l)) in samples.iter().rev().enumerate() {
                if k % 2 == 0 { &mut a } else { &mut b }.splat(px, pos, l);
            }
            for (s, o) in a.sums.iter_mut().zip(&b.sums) {
                s.merge(o);
            }
            assert_eq!(forward.sums, a.sums, "{f:?}");
            // Constant radiance gives that constant in every pixel.
            for s in &forward.sums {
                let v = s.value();
                assert!(
                    (v - Vec3::new(2.0, 0.5, 0.125)).abs().max_element() < 1e-6,
                    "{f:?}: {v:?}"
                );
            }
        }
    }

    #[test]
    fn splatting_a_tent_lowers_the_noise_of_a_pixel() {
        // White noise per sample: the variance of a pixel of n samples is
        // 1/n importance-sampling the filter (every sample weight one), and
        // (4/9)/n for a splatted tent (sum of squared weights over squared
        // sum of weights, four times 1/9 of the samples from each pixel).
        let (w, n) = (40u32, 16u32);
        let rect = PixelRect::full(w, w);
        let mut block = SplatBlock::new(rect, Filter::Tent);
        let mut rng = crate::sampling::Rng::new(11, 3);
        for y in 0..w {
            for x in 0..w {
                for _ in 0..n {
                    let pos = Vec2::new(x as f32, y as f32) + rng.next_2d();
                    let l = Vec3::splat(rng.next_f32() * 2.0);
                    block.splat((x, y), pos, l);
                }
            }
        }
        // Inner pixels only (the frame's edge has fewer neighbours).
        let vals: Vec<f64> = (2..w - 2)
            .flat_map(|y| (2..w - 2).map(move |x| (x, y)))
            .map(|(x, y)| block.sums[(y * w + x) as usize].value().x as f64)
            .collect();
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (vals.len() - 1) as f64;
        let one_pixel = (1.0 / 3.0) / n as f64; // variance of U(0, 2) over n
        let ratio = var / one_pixel;
        assert!((0.3..0.6).contains(&ratio), "variance ratio {ratio}");
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
