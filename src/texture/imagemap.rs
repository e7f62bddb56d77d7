//! Image textures (pbrt-v4 `imagemap`): an RGB image looked up at (u, v)
//! with bilinear filtering, pbrt-v4's texture coordinate convention and wrap
//! modes.
//!
//! Convention (pbrt-v4 `SpectrumImageTexture::Evaluate` and
//! `Image::Bilerp`): (s, t) = (uscale u + udelta, vscale v + vdelta), then
//! t = 1 - t, and the image, whose first row is its top, is read at pixel
//! coordinates (s w - 0.5, t h - 0.5): texel centres sit at half-integers.
//! So (u, v) = (0, 0) is the bottom-left corner of the picture as seen, and
//! v grows upwards.
//!
//! A lookup with a [`Footprint`] reads a MIP map level as pbrt-v4's
//! `MIPMap::Filter` does (its `filter` parameter: point, bilinear by default,
//! trilinear; EWA is read as trilinear): the level where a texel is as wide
//! as twice the largest of the footprint's (s, t) derivatives. The pyramid
//! is pbrt-v4's: sides rounded up to powers of two, each level the 2 x 2 box
//! average of the one below, stored as the file was (an 8-bit image's levels
//! are 8-bit again, in its encoding). Two departures: the finest level is the
//! image as stored, not resampled to the powers of two (pbrt-v4 resamples it
//! with a windowed sinc), and the second level of such an image averages
//! bilinear samples of the first. A lookup without a footprint reads the
//! finest level, as pbrt-v4 does without ray differentials.
//!
//! Decoded images are shared: [`load_image`] keeps a cache of the images
//! alive in the process, keyed by canonical path and encoding, so a scene
//! that uses one file in several textures (or several scenes in one process)
//! decodes it once.

use super::Footprint;
use crate::error::{Error, Result};
use crate::math::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock, Weak};

/// What happens to lookups outside [0, 1]^2 (pbrt-v4's `WrapMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WrapMode {
    /// The image tiles the plane.
    #[default]
    Repeat,
    /// The edge texels extend outwards.
    Clamp,
    /// Black outside the image.
    Black,
}

impl WrapMode {
    /// pbrt-v4's names: "repeat", "clamp", "black".
    pub fn parse(name: &str) -> Option<WrapMode> {
        match name {
            "repeat" => Some(WrapMode::Repeat),
            "clamp" => Some(WrapMode::Clamp),
            "black" => Some(WrapMode::Black),
            _ => None,
        }
    }
}

/// How the integer values of an 8- or 16-bit image map to linear values
/// (pbrt-v4's `ColorEncoding`). Float images (EXR, PFM) are always linear.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Encoding {
    /// The sRGB transfer curve (the default, as pbrt-v4's for PNG, JPEG, TGA).
    #[default]
    Srgb,
    Linear,
    /// value^gamma.
    Gamma(f32),
}

impl Encoding {
    /// pbrt-v4's names: "sRGB", "linear", "gamma G" (G > 0).
    pub fn parse(name: &str) -> Option<Encoding> {
        match name {
            "sRGB" | "srgb" => Some(Encoding::Srgb),
            "linear" => Some(Encoding::Linear),
            _ => {
                let g: f32 = name.strip_prefix("gamma ")?.trim().parse().ok()?;
                (g.is_finite() && g > 0.0).then_some(Encoding::Gamma(g))
            }
        }
    }

    /// A stored value in [0, 1] as a linear one.
    pub fn to_linear(self, v: f32) -> f32 {
        match self {
            Encoding::Linear => v,
            Encoding::Gamma(g) => v.max(0.0).powf(g),
            Encoding::Srgb => srgb_to_linear(v),
        }
    }

    /// A linear value in [0, 1] as stored: the inverse of `to_linear`.
    pub fn encode(self, v: f32) -> f32 {
        match self {
            Encoding::Linear => v,
            Encoding::Gamma(g) => v.max(0.0).powf(1.0 / g),
            Encoding::Srgb => linear_to_srgb(v),
        }
    }

    /// A key for the cache (f32 is not `Hash`).
    fn key(self) -> (u8, u32) {
        match self {
            Encoding::Srgb => (0, 0),
            Encoding::Linear => (1, 0),
            Encoding::Gamma(g) => (2, g.to_bits()),
        }
    }
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB opto-electronic transfer function, the inverse of [`srgb_to_linear`].
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.0031308 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// A decoded image: linear RGB, first row at the top.
pub struct TexImage {
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    /// Linear RGB, first row at the top (`pixel`, `pixels`).
    texels: Texels,
    /// FNV-1a 64 of the file's bytes and the encoding: two images with the
    /// same hash hold the same pixels.
    pub hash: u64,
    /// Whether the file held integers (and `encoding` applied).
    pub integer: bool,
    pub encoding: Encoding,
    /// Per-channel largest and smallest pixel values.
    pub max: Vec3,
    pub min: Vec3,
    /// The alpha channel, decoded as the colour channels are, when the file
    /// has one that is not 1 everywhere: pbrt-v4 keeps such a channel, and a
    /// float lookup of the image reads it (an `alpha` cut-out's mask).
    pub alpha: Option<Vec<f32>>,
    /// Whether the file held 8 bits a channel: the MIP map's levels are
    /// quantised to them again, as pbrt-v4 stores its levels.
    pub eight_bit: bool,
    /// The MIP map's levels above the finest (the image itself), built at
    /// the first lookup that needs one.
    pyramid: OnceLock<Vec<MipLevel>>,
}

/// An image's texels: linear floats, or the bytes of an 8-bit file with
/// the table that decodes them (what a float copy gave, value for value, in
/// a quarter of the memory: textures are most of a large scene's).
enum Texels {
    Linear(Vec<Vec3>),
    Bytes {
        texels: Vec<[u8; 3]>,
        table: Box<[f32; 256]>,
    },
}

impl Texels {
    fn len(&self) -> usize {
        match self {
            Texels::Linear(p) => p.len(),
            Texels::Bytes { texels, .. } => texels.len(),
        }
    }

    /// Every texel, linear, in order.
    fn all(&self) -> impl Iterator<Item = Vec3> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }

    #[inline]
    fn get(&self, i: usize) -> Vec3 {
        match self {
            Texels::Linear(p) => p[i],
            Texels::Bytes { texels, table } => {
                let [r, g, b] = texels[i];
                Vec3::new(table[r as usize], table[g as usize], table[b as usize])
            }
        }
    }
}

/// One level of a MIP map above the finest: linear RGB, first row at the
/// top (an 8-bit image's levels in its bytes too), and the alpha channel if
/// the image has one.
struct MipLevel {
    width: u32,
    height: u32,
    pixels: Texels,
    alpha: Option<Vec<f32>>,
}

/// How a lookup with a footprint reads the MIP map (pbrt-v4's
/// `FilterFunction`; its `EWA` is read as `Trilinear`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MipFilter {
    /// The nearest texel of the level below the footprint's.
    Point,
    /// A bilinear lookup in the level below the footprint's (pbrt-v4's default).
    #[default]
    Bilinear,
    /// Bilinear lookups in the two levels about the footprint's, blended.
    Trilinear,
}

impl MipFilter {
    /// pbrt-v4's names: "point", "bilinear", "trilinear", "ewa".
    pub fn parse(name: &str) -> Option<MipFilter> {
        match name {
            "point" => Some(MipFilter::Point),
            "bilinear" => Some(MipFilter::Bilinear),
            "trilinear" | "ewa" | "EWA" => Some(MipFilter::Trilinear),
            _ => None,
        }
    }
}

/// Two images are equal when their files' bytes and encodings are: the hash
/// says so (pixels made in code hash their values).
impl PartialEq for TexImage {
    fn eq(&self, o: &Self) -> bool {
        self.hash == o.hash && self.width == o.width && self.height == o.height
    }
}

impl std::fmt::Debug for TexImage {
    // Not the pixels: scene fingerprints hash a material's Debug form. Nor
    // the folder: the same scene read from another folder or machine (a
    // shared photon map, a checkpoint resumed elsewhere) is the same scene.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = self.path.file_name().unwrap_or(self.path.as_os_str());
        write!(
            f,
            "TexImage {{ file: {:?}, size: {}x{}, hash: {:016x} }}",
            name, self.width, self.height, self.hash
        )
    }
}

impl TexImage {
    /// An image from linear pixels (first row at the top), for textures made
    /// in code.
    pub fn from_pixels(name: &str, width: u32, height: u32, pixels: Vec<Vec3>) -> TexImage {
        assert_eq!(pixels.len(), width as usize * height as usize, "pixel count");
        assert!(width > 0 && height > 0, "empty image");
        let mut h = Fnv64::default();
        for p in &pixels {
            for c in p.to_array() {
                h.bytes(&c.to_bits().to_le_bytes());
            }
        }
        Self::finish(
            PathBuf::from(name),
            width,
            height,
            Texels::Linear(pixels),
            h.0,
            false,
            Encoding::Linear,
        )
    }

    fn finish(
        path: PathBuf,
        width: u32,
        height: u32,
        texels: Texels,
        hash: u64,
        integer: bool,
        encoding: Encoding,
    ) -> TexImage {
        let (mut max, mut min) = (Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY));
        for p in texels.all() {
            (max, min) = (max.max(p), min.min(p));
        }
        TexImage {
            path,
            width,
            height,
            texels,
            hash,
            integer,
            encoding,
            max,
            min,
            alpha: None,
            eight_bit: false,
            pyramid: OnceLock::new(),
        }
    }

    /// Texel `i` (row by row from the top), linear.
    #[inline]
    pub fn pixel(&self, i: usize) -> Vec3 {
        self.texels.get(i)
    }

    /// Bytes the texels take (an 8-bit file's keep their bytes).
    pub fn texel_bytes(&self) -> usize {
        match &self.texels {
            Texels::Linear(p) => p.len() * std::mem::size_of::<Vec3>(),
            Texels::Bytes { texels, table } => texels.len() * 3 + std::mem::size_of_val(&**table),
        }
    }

    /// Every texel, linear, row by row from the top: a copy.
    pub fn pixels(&self) -> Vec<Vec3> {
        self.texels.all().collect()
    }

    /// Bilinear lookup at image coordinates `st` in [0, 1]^2 (t down from the
    /// top row), as pbrt-v4's `Image::Bilerp`.
    pub fn bilerp(&self, st: Vec2, wrap: WrapMode) -> Vec3 {
        self.bilerp_with(st, wrap, |i| self.texels.get(i))
    }

    fn bilerp_with<T>(&self, st: Vec2, wrap: WrapMode, texel: impl Fn(usize) -> T) -> T
    where
        T: Default + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        bilerp_grid(self.width, self.height, st, wrap, texel)
    }

    /// Levels of the MIP map: 1 + log2 of the longer side rounded up to a
    /// power of two (pbrt-v4's count).
    fn level_count(&self) -> usize {
        let side = self.width.max(self.height).next_power_of_two();
        1 + side.trailing_zeros() as usize
    }

    /// The levels above the finest, built once.
    fn pyramid(&self) -> &[MipLevel] {
        self.pyramid.get_or_init(|| build_pyramid(self))
    }

    /// A bilinear lookup in MIP level `level` (0: the image itself), colour
    /// or the float lookup (alpha, else the channels' mean).
    fn level_bilerp(&self, level: usize, st: Vec2, wrap: WrapMode) -> Vec3 {
        if level == 0 {
            return self.bilerp(st, wrap);
        }
        let l = &self.pyramid()[level - 1];
        bilerp_grid(l.width, l.height, st, wrap, |i| l.pixels.get(i))
    }

    fn level_bilerp_scalar(&self, level: usize, st: Vec2, wrap: WrapMode) -> f32 {
        let alpha = if level == 0 {
            self.alpha.as_ref().map(|a| self.bilerp_with(st, wrap, |i| a[i]))
        } else {
            let l = &self.pyramid()[level - 1];
            l.alpha
                .as_ref()
                .map(|a| bilerp_grid(l.width, l.height, st, wrap, |i| a[i]))
        };
        alpha.unwrap_or_else(|| channel_mean(self.level_bilerp(level, st, wrap)))
    }

    /// The texel of level `level` nearest to `st` (pbrt-v4's point filter).
    fn level_nearest(&self, level: usize, st: Vec2, wrap: WrapMode) -> (Vec3, Option<f32>) {
        let (w, h) = match level {
            0 => (self.width, self.height),
            k => (self.pyramid()[k - 1].width, self.pyramid()[k - 1].height),
        };
        let x = (st.x as f64 * w as f64 - 0.5).round();
        let y = (st.y as f64 * h as f64 - 0.5).round();
        if !(x.is_finite() && y.is_finite()) {
            return (Vec3::ZERO, None);
        }
        let Some(i) = texel_index(w, h, x as i64, y as i64, wrap) else {
            return (Vec3::ZERO, self.alpha.as_ref().map(|_| 0.0));
        };
        match level {
            0 => (self.pixel(i), self.alpha.as_ref().map(|a| a[i])),
            k => {
                let l = &self.pyramid()[k - 1];
                (l.pixels.get(i), l.alpha.as_ref().map(|a| a[i]))
            }
        }
    }

    /// pbrt-v4's `MIPMap::Filter` (not EWA) for a filter `width` in (s, t):
    /// the colour, or with `scalar` the float lookup in its first channel.
    fn filter(&self, st: Vec2, width: f32, filter: MipFilter, wrap: WrapMode, scalar: bool) -> Vec3 {
        let levels = self.level_count();
        let level = (levels - 1) as f32 + width.max(1e-8).log2();
        let scalar_of = |c: Vec3, a: Option<f32>| a.unwrap_or_else(|| channel_mean(c));
        if level >= (levels - 1) as f32 || level.is_nan() {
            // The one texel of the top level; pbrt-v4's float lookup of it
            // reads its first channel whatever the image's channels are.
            let top = self.level_nearest(levels - 1, Vec2::ZERO, WrapMode::Clamp).0;
            return if scalar { Vec3::splat(top.x) } else { top };
        }
        let i = (level.floor().max(0.0)) as usize;
        let at = |k: usize| {
            if scalar {
                Vec3::splat(self.level_bilerp_scalar(k, st, wrap))
            } else {
                self.level_bilerp(k, st, wrap)
            }
        };
        match filter {
            MipFilter::Point => {
                let (c, a) = self.level_nearest(i, st, wrap);
                if scalar {
                    Vec3::splat(scalar_of(c, a))
                } else {
                    c
                }
            }
            MipFilter::Bilinear => at(i),
            MipFilter::Trilinear if i == 0 => at(0),
            MipFilter::Trilinear => {
                let f = level - i as f32;
                at(i) * (1.0 - f) + at(i + 1) * f
            }
        }
    }
}

/// The mean of the channels, exactly the value of a grey colour.
fn channel_mean(v: Vec3) -> f32 {
    if v.x == v.y && v.y == v.z {
        v.x
    } else {
        (v.x + v.y + v.z) / 3.0
    }
}

/// The index of the texel at integer coordinates of a `w` x `h` grid after
/// wrapping; `None` outside with `Black`.
fn texel_index(w: u32, h: u32, x: i64, y: i64, wrap: WrapMode) -> Option<usize> {
    let (w, h) = (w as i64, h as i64);
    let (x, y) = match wrap {
        WrapMode::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
        WrapMode::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
        WrapMode::Black => {
            if x < 0 || y < 0 || x >= w || y >= h {
                return None;
            }
            (x, y)
        }
    };
    Some((y * w + x) as usize)
}

/// Bilinear lookup in a `w` x `h` grid at `st` in [0, 1]^2, texel centres at
/// half-integers (pbrt-v4's `Image::Bilerp`).
fn bilerp_grid<T>(w: u32, h: u32, st: Vec2, wrap: WrapMode, texel: impl Fn(usize) -> T) -> T
where
    T: Default + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    // Far outside, f32 -> i64 saturates; repeat's rem_euclid still works.
    let x = st.x as f64 * w as f64 - 0.5;
    let y = st.y as f64 * h as f64 - 0.5;
    if !(x.is_finite() && y.is_finite()) {
        return T::default();
    }
    let (xf, yf) = (x.floor(), y.floor());
    let (dx, dy) = ((x - xf) as f32, (y - yf) as f32);
    let (xi, yi) = (xf as i64, yf as i64);
    let t = |x, y| texel_index(w, h, x, y, wrap).map_or_else(T::default, &texel);
    t(xi, yi) * ((1.0 - dx) * (1.0 - dy))
        + t(xi + 1, yi) * (dx * (1.0 - dy))
        + t(xi, yi + 1) * ((1.0 - dx) * dy)
        + t(xi + 1, yi + 1) * (dx * dy)
}

/// The MIP map's levels above the finest, as pbrt-v4's
/// `Image::GeneratePyramid` makes them: the image at sides rounded up to
/// powers of two, then each level the 2 x 2 box average of the one below,
/// in floats; each level is stored as the file was (8 bits again, in its
/// encoding, for an 8-bit image).
fn build_pyramid(img: &TexImage) -> Vec<MipLevel> {
    let (pw, ph) = (img.width.next_power_of_two(), img.height.next_power_of_two());
    let alpha = img.alpha.as_deref();
    if pw == 1 && ph == 1 {
        return Vec::new();
    }
    // The level above the finest, from the finest at the powers of two:
    // the image itself, or (our departure from pbrt-v4's windowed sinc) its
    // bilinear samples there, never held at that size.
    let (w1, h1) = ((pw / 2).max(1), (ph / 2).max(1));
    let (sx, sy) = (pw / w1, ph / h1);
    let children = |x: u32, y: u32| {
        (0..sy).flat_map(move |j| {
            (0..sx).map(move |i| {
                let (cx, cy) = (x * sx + i, y * sy + j);
                Vec2::new((cx as f32 + 0.5) / pw as f32, (cy as f32 + 0.5) / ph as f32)
            })
        })
    };
    let exact = (pw, ph) == (img.width, img.height);
    let n = (sx * sy) as f32;
    let mut first = Vec::with_capacity(w1 as usize * h1 as usize);
    let mut first_alpha = alpha.map(|_| Vec::with_capacity(w1 as usize * h1 as usize));
    for y in 0..h1 {
        for x in 0..w1 {
            let texel = |cx: u32, cy: u32| (cy as usize) * img.width as usize + cx as usize;
            let (mut c, mut a) = (Vec3::ZERO, 0.0f32);
            for (k, st) in children(x, y).enumerate() {
                let (i, j) = (k as u32 % sx, k as u32 / sx);
                if exact {
                    let t = texel(x * sx + i, y * sy + j);
                    c += img.pixel(t);
                    a += alpha.map_or(0.0, |al| al[t]);
                } else {
                    c += img.bilerp(st, WrapMode::Clamp);
                    a += alpha.map_or(0.0, |al| img.bilerp_with(st, WrapMode::Clamp, |t| al[t]));
                }
            }
            first.push(c * (1.0 / n));
            if let Some(v) = first_alpha.as_mut() {
                v.push(a / n);
            }
        }
    }
    let quantise = |v: f32| {
        if img.eight_bit {
            let stored = img.encoding.encode(v.clamp(0.0, 1.0));
            img.encoding.to_linear((stored * 255.0).round() / 255.0)
        } else {
            v
        }
    };
    // An 8-bit image's levels keep the bytes `quantise` rounds to, read
    // through the image's own table: the same values in a quarter of the
    // memory.
    let table = match &img.texels {
        Texels::Bytes { table, .. } if img.eight_bit => Some(table),
        _ => None,
    };
    let byte = |v: f32| {
        (img.encoding.encode(v.clamp(0.0, 1.0)) * 255.0)
            .round()
            .clamp(0.0, 255.0) as u8
    };
    let store = |w: u32, h: u32, pixels: &[Vec3], alpha: Option<&Vec<f32>>| MipLevel {
        width: w,
        height: h,
        pixels: match table {
            Some(table) => Texels::Bytes {
                texels: pixels.iter().map(|c| [byte(c.x), byte(c.y), byte(c.z)]).collect(),
                table: table.clone(),
            },
            None => Texels::Linear(
                pixels
                    .iter()
                    .map(|c| Vec3::new(quantise(c.x), quantise(c.y), quantise(c.z)))
                    .collect(),
            ),
        },
        alpha: alpha.map(|a| a.iter().map(|&v| quantise(v)).collect()),
    };
    let mut levels = vec![store(w1, h1, &first, first_alpha.as_ref())];
    let (mut colour, mut opacity, mut w, mut h) = (first, first_alpha, w1, h1);
    while w > 1 || h > 1 {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        // The 2 x 2 box below each texel of the next level (a side of one
        // texel averages that texel with itself).
        fn down<T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f32, Output = T>>(
            src: &[T],
            (w, h): (u32, u32),
            (nw, nh): (u32, u32),
        ) -> Vec<T> {
            let at = |x: u32, y: u32| src[y as usize * w as usize + x as usize];
            let mut out = Vec::with_capacity(nw as usize * nh as usize);
            for y in 0..nh {
                for x in 0..nw {
                    let (x0, y0) = (2 * x, 2 * y);
                    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
                    out.push((at(x0, y0) + at(x1, y0) + at(x0, y1) + at(x1, y1)) * 0.25);
                }
            }
            out
        }
        let next = down(&colour, (w, h), (nw, nh));
        let next_alpha = opacity.as_deref().map(|a| down(a, (w, h), (nw, nh)));
        levels.push(store(nw, nh, &next, next_alpha.as_ref()));
        (colour, opacity, w, h) = (next, next_alpha, nw, nh);
    }
    levels
}

/// (s, t) = (su u + du, sv v + dv): pbrt-v4's `UVMapping`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMapping {
    pub su: f32,
    pub sv: f32,
    pub du: f32,
    pub dv: f32,
}

impl Default for UvMapping {
    fn default() -> Self {
        UvMapping {
            su: 1.0,
            sv: 1.0,
            du: 0.0,
            dv: 0.0,
        }
    }
}

impl UvMapping {
    pub fn map(&self, uv: Vec2) -> Vec2 {
        Vec2::new(self.su * uv.x + self.du, self.sv * uv.y + self.dv)
    }
}

/// How an image file is read and looked up: the options of pbrt-v4's `imagemap`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageOptions {
    pub wrap: WrapMode,
    /// For 8- and 16-bit images; float images are linear whatever it says.
    pub encoding: Encoding,
    /// Multiplies the looked-up value.
    pub scale: f32,
    /// Returns 1 - value (after `scale`), clamped at 0.
    pub invert: bool,
    pub mapping: UvMapping,
    /// How lookups with a footprint read the MIP map.
    pub filter: MipFilter,
}

impl Default for ImageOptions {
    fn default() -> Self {
        ImageOptions {
            wrap: WrapMode::Repeat,
            encoding: Encoding::Srgb,
            scale: 1.0,
            invert: false,
            mapping: UvMapping::default(),
            filter: MipFilter::default(),
        }
    }
}

/// An image texture: a shared image and how it is looked up.
#[derive(Clone, Debug)]
pub struct ImageTexture {
    pub image: Arc<TexImage>,
    pub wrap: WrapMode,
    pub scale: f32,
    pub invert: bool,
    pub mapping: UvMapping,
    pub filter: MipFilter,
}

impl PartialEq for ImageTexture {
    fn eq(&self, o: &Self) -> bool {
        (Arc::ptr_eq(&self.image, &o.image) || self.image.hash == o.image.hash)
            && self.wrap == o.wrap
            && self.scale == o.scale
            && self.invert == o.invert
            && self.mapping == o.mapping
            && self.filter == o.filter
    }
}

impl ImageTexture {
    /// Reads (or takes from the cache) the image at `path` and wraps it with
    /// `opts`. This is what a scene reader calls: PNG, JPEG, TGA (8 or 16
    /// bits, decoded by `opts.encoding`), EXR and PFM (linear).
    pub fn open(path: &Path, opts: &ImageOptions) -> Result<ImageTexture> {
        Ok(Self::new(load_image(path, opts.encoding)?, opts))
    }

    pub fn new(image: Arc<TexImage>, opts: &ImageOptions) -> ImageTexture {
        ImageTexture {
            image,
            wrap: opts.wrap,
            scale: opts.scale,
            invert: opts.invert,
            mapping: opts.mapping,
            filter: opts.filter,
        }
    }

    /// The value at surface coordinates `uv`.
    pub fn evaluate(&self, uv: Vec2) -> Vec3 {
        let st = self.mapping.map(uv);
        // Images are stored top row first; v grows upwards (pbrt-v4 flips t).
        self.finish(self.image.bilerp(Vec2::new(st.x, 1.0 - st.y), self.wrap) * self.scale)
    }

    /// The value at `uv` for a lookup whose (u, v) changes by `footprint`
    /// from pixel to pixel: a MIP map level's (the finest without one).
    pub fn evaluate_filtered(&self, uv: Vec2, footprint: &Footprint) -> Vec3 {
        match self.filter_width(footprint) {
            None => self.evaluate(uv),
            Some(width) => self.finish(self.filtered(uv, width, false)),
        }
    }

    /// `evaluate_scalar` with a footprint, as `evaluate_filtered`.
    pub fn evaluate_scalar_filtered(&self, uv: Vec2, footprint: &Footprint) -> f32 {
        match self.filter_width(footprint) {
            None => self.evaluate_scalar(uv),
            Some(width) => self.finish(self.filtered(uv, width, true)).x,
        }
    }

    /// The MIP map's value for a filter `width`, scaled (a float lookup's in
    /// every channel with `scalar`).
    fn filtered(&self, uv: Vec2, width: f32, scalar: bool) -> Vec3 {
        let st = self.mapping.map(uv);
        let st = Vec2::new(st.x, 1.0 - st.y);
        self.image.filter(st, width, self.filter, self.wrap, scalar) * self.scale
    }

    /// The width in (s, t) pbrt-v4's MIP map filter takes for a footprint:
    /// twice the largest of its derivatives; `None` without a footprint.
    fn filter_width(&self, f: &Footprint) -> Option<f32> {
        if *f == Footprint::NONE {
            return None;
        }
        let (su, sv) = (self.mapping.su.abs(), self.mapping.sv.abs());
        let w = 2.0
            * (su * f.dudx.abs())
                .max(sv * f.dvdx.abs())
                .max(su * f.dudy.abs())
                .max(sv * f.dvdy.abs());
        w.is_finite().then_some(w)
    }

    fn finish(&self, v: Vec3) -> Vec3 {
        if self.invert {
            (Vec3::ONE - v).max(Vec3::ZERO)
        } else {
            v.max(Vec3::ZERO)
        }
    }

    /// The value of a float lookup at `uv`: the alpha channel where the image
    /// has one (pbrt-v4's `MIPMap::Bilerp<Float>` of a four-channel image),
    /// else the mean of the colour channels (of three), exactly the value of
    /// a grey image.
    pub fn evaluate_scalar(&self, uv: Vec2) -> f32 {
        let Some(alpha) = &self.image.alpha else {
            let v = self.evaluate(uv);
            return if v.x == v.y && v.y == v.z {
                v.x
            } else {
                (v.x + v.y + v.z) / 3.0
            };
        };
        let st = self.mapping.map(uv);
        let a = self
            .image
            .bilerp_with(Vec2::new(st.x, 1.0 - st.y), self.wrap, |i| alpha[i])
            * self.scale;
        if self.invert {
            (1.0 - a).max(0.0)
        } else {
            a.max(0.0)
        }
    }

    /// The largest value `evaluate` can return, per channel.
    pub fn max_value(&self) -> Vec3 {
        // Bilinear weights are convex, so lookups stay within the texels'
        // range; black wrapping adds 0.
        let (mut lo, mut hi) = (self.image.min, self.image.max);
        if self.wrap == WrapMode::Black {
            lo = lo.min(Vec3::ZERO);
            hi = hi.max(Vec3::ZERO);
        }
        let (a, b) = (lo * self.scale, hi * self.scale);
        let top = a.max(b);
        let bottom = a.min(b);
        if self.invert {
            (Vec3::ONE - bottom).max(Vec3::ZERO)
        } else {
            top.max(Vec3::ZERO)
        }
    }
}

/// FNV-1a 64 over bytes fed in order: the content hash of images and of
/// measured BRDF files, which scene fingerprints see.
#[derive(Clone, Copy)]
pub(crate) struct Fnv64(pub(crate) u64);

impl Default for Fnv64 {
    fn default() -> Self {
        Fnv64(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv64 {
    pub(crate) fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

type CacheKey = (PathBuf, (u8, u32));

/// Decoded images still in use somewhere, by canonical path and encoding.
static CACHE: Mutex<Option<HashMap<CacheKey, Weak<TexImage>>>> = Mutex::new(None);

/// Reads an image file as linear RGB, or returns the copy already in
/// memory. A missing file is `Error::Io`; a file that is not an image of a
/// known format is `Error::Parse`, naming the file.
pub fn load_image(path: &Path, encoding: Encoding) -> Result<Arc<TexImage>> {
    let io = |e: std::io::Error| Error::Io {
        path: path.to_path_buf(),
        source: e,
    };
    let canonical = std::fs::canonicalize(path).map_err(io)?;
    let key = (canonical, encoding.key());
    {
        let cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(img) = cache.as_ref().and_then(|c| c.get(&key)).and_then(Weak::upgrade) {
            return Ok(img);
        }
    }
    // Decoded outside the lock: two threads may both decode one file, and
    // the second's copy replaces the first's in the cache; both are right.
    let img = Arc::new(decode(path, encoding)?);
    let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    let map = cache.get_or_insert_with(HashMap::new);
    map.retain(|_, w| w.strong_count() > 0);
    map.insert(key, Arc::downgrade(&img));
    Ok(img)
}

/// Reads and decodes an image file, by its extension for EXR and PFM and by
/// its contents for the rest.
fn decode(path: &Path, encoding: Encoding) -> Result<TexImage> {
    let meta = std::fs::metadata(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    if !meta.is_file() {
        return Err(Error::Parse {
            path: path.to_path_buf(),
            message: "not a regular file".into(),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    decode_bytes(path, &bytes, encoding, true)
}

/// Decodes an image file's bytes (not cached); `path` names it in errors and
/// gives the extension. EXR is read from the file itself, so it needs
/// `on_disk`.
pub fn decode_bytes(path: &Path, bytes: &[u8], encoding: Encoding, on_disk: bool) -> Result<TexImage> {
    let perr = |m: String| Error::Parse {
        path: path.to_path_buf(),
        message: m,
    };
    let mut h = Fnv64::default();
    h.bytes(bytes);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    if ext == "exr" || ext == "pfm" {
        let film = if ext == "pfm" {
            crate::image_io::read_pfm(bytes).map_err(perr)?
        } else if on_disk {
            crate::image_io::read_image(path)?
        } else {
            return Err(perr("EXR textures are read from files on disk only".into()));
        };
        if film.width == 0 || film.height == 0 {
            return Err(perr("the image is empty".into()));
        }
        if let Some(i) = film.pixels.iter().position(|p| !p.is_finite()) {
            return Err(perr(format!(
                "texel ({}, {}) is not a finite number",
                i as u32 % film.width,
                i as u32 / film.width
            )));
        }
        return Ok(TexImage::finish(
            path.to_path_buf(),
            film.width,
            film.height,
            Texels::Linear(film.pixels),
            h.0,
            false,
            Encoding::Linear,
        ));
    }
    let mut reader = ::image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| perr(e.to_string()))?;
    if reader.format().is_none() {
        // TGA has no signature: trust the extension.
        match ::image::ImageFormat::from_path(path) {
            Ok(f) if f.reading_enabled() => reader.set_format(f),
            _ => {
                return Err(perr(
                    "not an image file of a known format (PNG, JPEG, TGA, HDR, EXR, PFM)".into(),
                ))
            }
        }
    }
    let img = reader
        .decode()
        .map_err(|e| perr(format!("cannot decode the image: {e}")))?;
    let (width, height) = (img.width(), img.height());
    if width == 0 || height == 0 {
        return Err(perr("the image is empty".into()));
    }
    use ::image::DynamicImage as D;
    let integer = !matches!(img, D::ImageRgb32F(_) | D::ImageRgba32F(_));
    // pbrt-v4 keeps the alpha of colour images (not of grey ones, which it
    // reads as grey alone) unless it is 1 everywhere.
    let rgba = (img.color().has_alpha() && img.color().has_color()).then(|| img.to_rgba32f());
    let rgb = img.to_rgb32f();
    let enc = if integer { encoding } else { Encoding::Linear };
    // 8-bit images go through a table; 16-bit ones are decoded per value.
    let table: Option<Vec<f32>> = matches!(img.color().bytes_per_pixel() / img.color().channel_count(), 1)
        .then(|| (0..256).map(|i| enc.to_linear(i as f32 / 255.0)).collect());
    let lin = |v: f32| match &table {
        Some(t) => t[(v * 255.0).round().clamp(0.0, 255.0) as usize],
        None => enc.to_linear(v),
    };
    let texels = match &table {
        // The bytes the table reads, found as `lin` finds them.
        Some(t) => {
            let byte = |v: f32| (v * 255.0).round().clamp(0.0, 255.0) as u8;
            let texels = rgb
                .pixels()
                .map(|p| [byte(p.0[0]), byte(p.0[1]), byte(p.0[2])])
                .collect();
            let mut table = Box::new([0.0; 256]);
            table.copy_from_slice(t);
            Texels::Bytes { texels, table }
        }
        None => Texels::Linear(
            rgb.pixels()
                .map(|p| Vec3::new(lin(p.0[0]), lin(p.0[1]), lin(p.0[2])))
                .collect(),
        ),
    };
    // Decoded as the colour is: pbrt-v4 applies an 8-bit image's encoding to
    // each of its channels, alpha included.
    let alpha = rgba
        .filter(|im| im.pixels().any(|p| p.0[3] != 1.0))
        .map(|im| im.pixels().map(|p| lin(p.0[3])).collect());
    h.bytes(&[enc.key().0]);
    h.bytes(&enc.key().1.to_le_bytes());
    let eight_bit = table.is_some();
    let mut image = TexImage::finish(path.to_path_buf(), width, height, texels, h.0, integer, enc);
    image.alpha = alpha;
    image.eight_bit = eight_bit;
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Film;

    fn two_texels() -> ImageTexture {
        // One row: black on the left, white on the right.
        let img = TexImage::from_pixels("two", 2, 1, vec![Vec3::ZERO, Vec3::ONE]);
        ImageTexture::new(Arc::new(img), &ImageOptions::default())
    }

    #[test]
    fn an_eight_bit_image_keeps_its_bytes_and_gives_what_decoding_to_floats_gave() {
        let dir = tempfile::tempdir().unwrap();
        // Every byte value in every channel, in a 16 x 16 image.
        let px: Vec<u8> = (0..256u32)
            .flat_map(|i| [i as u8, (255 - i) as u8, (i * 7 % 256) as u8])
            .collect();
        for (k, encoding) in [Encoding::Srgb, Encoding::Linear, Encoding::Gamma(2.2)]
            .into_iter()
            .enumerate()
        {
            let png = dir.path().join(format!("b{k}.png"));
            ::image::save_buffer(&png, &px, 16, 16, ::image::ColorType::Rgb8).unwrap();
            let img = load_image(&png, encoding).unwrap();
            assert_eq!(
                img.texel_bytes(),
                256 * 3 + 256 * 4,
                "{encoding:?}: bytes and the table"
            );
            let (mut max, mut min) = (Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY));
            for (i, c) in px.chunks(3).enumerate() {
                let want = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) / 255.0;
                let want = Vec3::new(
                    encoding.to_linear(want.x),
                    encoding.to_linear(want.y),
                    encoding.to_linear(want.z),
                );
                assert_eq!(img.pixel(i), want, "{encoding:?}: texel {i}");
                (max, min) = (max.max(want), min.min(want));
            }
            assert_eq!(img.pixels().len(), 256);
            assert_eq!((img.max, img.min), (max, min), "{encoding:?}");
        }
        // A float image keeps its floats.
        let img = TexImage::from_pixels("f", 2, 1, vec![Vec3::ZERO, Vec3::splat(7.5)]);
        assert_eq!((img.texel_bytes(), img.pixel(1)), (24, Vec3::splat(7.5)));
    }

    #[test]
    fn bilinear_lookup_between_two_texels() {
        let mut t = two_texels();
        t.wrap = WrapMode::Clamp;
        // Texel centres at u = 0.25 and 0.75; halfway between them, half.
        assert_eq!(t.evaluate(Vec2::new(0.25, 0.5)), Vec3::ZERO);
        assert_eq!(t.evaluate(Vec2::new(0.75, 0.5)), Vec3::ONE);
        assert!((t.evaluate(Vec2::new(0.5, 0.5)) - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        assert!(
            (t.evaluate(Vec2::new(0.375, 0.1)) - Vec3::splat(0.25))
                .abs()
                .max_element()
                < 1e-6
        );
        // Clamp holds the edge texels beyond the centres.
        assert_eq!(t.evaluate(Vec2::new(0.0, 0.5)), Vec3::ZERO);
        assert_eq!(t.evaluate(Vec2::new(1.0, 0.5)), Vec3::ONE);
        assert_eq!(t.evaluate(Vec2::new(-3.0, 0.5)), Vec3::ZERO);
        assert_eq!(t.max_value(), Vec3::ONE);
    }

    #[test]
    fn wrap_modes_repeat_clamp_and_black() {
        let mut t = two_texels();
        // Repeat: u = 0 lies between the last texel and the first, wrapped.
        t.wrap = WrapMode::Repeat;
        assert!((t.evaluate(Vec2::new(0.0, 0.5)) - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        assert_eq!(t.evaluate(Vec2::new(1.75, 0.5)), Vec3::ONE);
        assert_eq!(t.evaluate(Vec2::new(-0.75, 0.5)), Vec3::ZERO);
        t.wrap = WrapMode::Clamp;
        assert_eq!(t.evaluate(Vec2::new(1.75, 0.5)), Vec3::ONE);
        t.wrap = WrapMode::Black;
        assert_eq!(t.evaluate(Vec2::new(1.0, 0.5)), Vec3::splat(0.5));
        assert_eq!(t.evaluate(Vec2::new(2.0, 0.5)), Vec3::ZERO);
        // scale and invert, as pbrt-v4's imagemap.
        t.wrap = WrapMode::Clamp;
        t.scale = 0.5;
        t.invert = true;
        assert_eq!(t.evaluate(Vec2::new(0.75, 0.5)), Vec3::splat(0.5));
        assert_eq!(t.evaluate(Vec2::new(0.25, 0.5)), Vec3::ONE);
        assert_eq!(t.max_value(), Vec3::ONE);
    }

    #[test]
    fn v_grows_upwards_from_the_bottom_row() {
        // Two rows: top red, bottom blue.
        let img = TexImage::from_pixels("rows", 1, 2, vec![Vec3::X, Vec3::Z]);
        let t = ImageTexture::new(Arc::new(img), &ImageOptions::default());
        assert_eq!(t.evaluate(Vec2::new(0.5, 0.25)), Vec3::Z);
        assert_eq!(t.evaluate(Vec2::new(0.5, 0.75)), Vec3::X);
    }

    #[test]
    fn encodings_decode_8_bit_values() {
        assert!((Encoding::Srgb.to_linear(128.0 / 255.0) - 0.2158605).abs() < 1e-5);
        assert_eq!(Encoding::Linear.to_linear(0.5), 0.5);
        assert!((Encoding::parse("gamma 2.2").unwrap().to_linear(0.5) - 0.5f32.powf(2.2)).abs() < 1e-6);
        assert_eq!(Encoding::parse("sRGB"), Some(Encoding::Srgb));
        assert_eq!(Encoding::parse("gamma -1"), None);
        assert_eq!(Encoding::parse("log"), None);
    }

    #[test]
    fn png_jpeg_tga_pfm_and_exr_files_load_and_are_shared() {
        let dir = tempfile::tempdir().unwrap();
        // 2 x 2, top row (128, 0, 255) and (0, 0, 0), bottom row white and grey 64.
        let px: [u8; 12] = [128, 0, 255, 0, 0, 0, 255, 255, 255, 64, 64, 64];
        let png = dir.path().join("a.png");
        ::image::save_buffer(&png, &px, 2, 2, ::image::ColorType::Rgb8).unwrap();
        let img = load_image(&png, Encoding::Srgb).unwrap();
        assert_eq!((img.width, img.height), (2, 2));
        assert!((img.pixel(0) - Vec3::new(0.2158605, 0.0, 1.0)).abs().max_element() < 1e-5);
        assert_eq!(img.pixel(2), Vec3::ONE);
        // Loaded once: the same file and encoding give the same pixels.
        assert!(Arc::ptr_eq(&img, &load_image(&png, Encoding::Srgb).unwrap()));
        let linear = load_image(&png, Encoding::Linear).unwrap();
        assert!((linear.pixel(0).x - 128.0 / 255.0).abs() < 1e-6);
        assert_ne!(linear.hash, img.hash);
        // The Debug form names the file and size, not the pixels.
        let dbg = format!("{img:?}");
        assert!(dbg.contains("a.png") && dbg.contains("2x2") && dbg.len() < 200, "{dbg}");

        // The image's top-left texel is where v = 1, u = 0.
        let t = ImageTexture::new(
            img.clone(),
            &ImageOptions {
                wrap: WrapMode::Clamp,
                ..Default::default()
            },
        );
        assert!((t.evaluate(Vec2::new(0.0, 1.0)) - img.pixel(0)).abs().max_element() < 1e-6);
        assert_eq!(t.evaluate(Vec2::new(0.0, 0.0)), Vec3::ONE);

        for name in ["a.tga", "a.jpg"] {
            let p = dir.path().join(name);
            ::image::save_buffer(&p, &px, 2, 2, ::image::ColorType::Rgb8).unwrap();
            let i = load_image(&p, Encoding::Srgb).unwrap();
            assert_eq!((i.width, i.height), (2, 2), "{name}");
            // JPEG is lossy (and 2 x 2 shares its colour): the white corner stays bright.
            assert!(i.pixel(2).x > 0.8 && i.pixel(1).x < 0.1, "{name}: {:?}", i.pixels());
            if name == "a.tga" {
                assert_eq!(i.pixels(), img.pixels());
            }
        }

        let mut film = Film::new(3, 2);
        for (i, p) in film.pixels.iter_mut().enumerate() {
            *p = Vec3::new(i as f32, 2.5 * i as f32, 0.125);
        }
        for name in ["a.pfm", "a.exr"] {
            let p = dir.path().join(name);
            crate::image_io::write_image(&film, &p, 0.0).unwrap();
            // Float images are linear whatever the encoding says.
            let i = load_image(&p, Encoding::Srgb).unwrap();
            assert_eq!((i.width, i.height), (3, 2), "{name}");
            assert_eq!(i.pixels(), film.pixels, "{name}");
            assert_eq!(i.max, Vec3::new(5.0, 12.5, 0.125));
            let t = ImageTexture::open(&p, &ImageOptions::default()).unwrap();
            assert_eq!(t.max_value(), Vec3::new(5.0, 12.5, 0.125));
        }
    }

    #[test]
    fn a_float_lookup_reads_the_alpha_channel_where_an_image_has_one() {
        let dir = tempfile::tempdir().unwrap();
        // 2 x 1: red, opaque; blue, alpha 128 (0.2158605 once sRGB-decoded,
        // as pbrt-v4 decodes every channel of an 8-bit image).
        let px: [u8; 8] = [255, 0, 0, 255, 0, 0, 255, 128];
        let png = dir.path().join("rgba.png");
        ::image::save_buffer(&png, &px, 2, 1, ::image::ColorType::Rgba8).unwrap();
        let opts = ImageOptions {
            wrap: WrapMode::Clamp,
            ..Default::default()
        };
        let t = ImageTexture::open(&png, &opts).unwrap();
        let (left, right) = (Vec2::new(0.0, 0.5), Vec2::new(1.0, 0.5));
        assert_eq!(t.evaluate(left), Vec3::X);
        assert_eq!(t.evaluate(right), Vec3::Z);
        assert_eq!(t.evaluate_scalar(left), 1.0);
        assert!((t.evaluate_scalar(right) - 0.2158605).abs() < 1e-6);
        // Halfway between the texel centres, half of each.
        assert!((t.evaluate_scalar(Vec2::new(0.5, 0.5)) - 0.5 * (1.0 + 0.2158605)).abs() < 1e-6);
        let linear = ImageTexture::open(
            &png,
            &ImageOptions {
                encoding: Encoding::Linear,
                invert: true,
                ..opts
            },
        )
        .unwrap();
        assert!((linear.evaluate_scalar(right) - (1.0 - 128.0 / 255.0)).abs() < 1e-6);

        // Alpha 1 everywhere is no alpha (pbrt-v4 drops it): the mean of the colour.
        let opaque: [u8; 8] = [255, 0, 0, 255, 0, 0, 255, 255];
        let png = dir.path().join("opaque.png");
        ::image::save_buffer(&png, &opaque, 2, 1, ::image::ColorType::Rgba8).unwrap();
        let t = ImageTexture::open(&png, &opts).unwrap();
        assert!(t.image.alpha.is_none());
        assert!((t.evaluate_scalar(left) - 1.0 / 3.0).abs() < 1e-7);
        // A grey image with alpha is read as grey alone, as pbrt-v4 reads it.
        let png = dir.path().join("grey-alpha.png");
        ::image::save_buffer(&png, &[255, 0, 0, 0], 2, 1, ::image::ColorType::La8).unwrap();
        let t = ImageTexture::open(&png, &opts).unwrap();
        assert_eq!((t.evaluate_scalar(left), t.evaluate_scalar(right)), (1.0, 0.0));
    }

    #[test]
    fn missing_and_non_image_files_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let e = load_image(&dir.path().join("none.png"), Encoding::Srgb).unwrap_err();
        assert!(matches!(e, Error::Io { .. }), "{e}");
        let p = dir.path().join("text.png");
        std::fs::write(&p, "not an image").unwrap();
        let e = load_image(&p, Encoding::Srgb).unwrap_err().to_string();
        assert!(e.contains("text.png") && !e.contains('\n'), "{e}");
        let p = dir.path().join("bad.pfm");
        std::fs::write(&p, "PF\n2 2\n-1\nxx").unwrap();
        assert!(load_image(&p, Encoding::Srgb).is_err());
    }

    /// A texture over a `w` x `h` checkerboard of 0 and 1 texels.
    fn checker(w: u32, h: u32, filter: MipFilter) -> ImageTexture {
        let pixels = (0..w * h).map(|i| Vec3::splat(((i % w + i / w) % 2) as f32)).collect();
        let opts = ImageOptions {
            encoding: Encoding::Linear,
            filter,
            ..ImageOptions::default()
        };
        ImageTexture::new(Arc::new(TexImage::from_pixels("checker", w, h, pixels)), &opts)
    }

    fn footprint(d: f32) -> Footprint {
        Footprint {
            dudx: d,
            dvdy: d,
            ..Footprint::NONE
        }
    }

    #[test]
    fn mip_levels_are_box_averages_chosen_by_the_footprint() {
        let t = checker(8, 8, MipFilter::Bilinear);
        assert_eq!(t.image.level_count(), 4);
        let uv = Vec2::new(0.3, 0.6);
        // No footprint, or one smaller than a texel: the texels themselves
        // (bilinear between 0 and 1 away from their centres).
        let fine = t.evaluate(uv);
        assert_eq!(t.evaluate_filtered(uv, &Footprint::NONE), fine);
        assert_eq!(t.evaluate_filtered(uv, &footprint(0.01)), fine);
        assert!(fine.x > 0.05 && fine.x < 0.95, "{fine}");
        // A footprint of two texels and more: the 2 x 2 averages of a
        // checkerboard, grey everywhere.
        for d in [2.0 / 8.0, 0.5, 10.0] {
            let v = t.evaluate_filtered(uv, &footprint(d));
            assert!((v - Vec3::splat(0.5)).abs().max_element() < 1e-6, "{d}: {v}");
        }
        // The level is the one where a texel is as wide as twice the largest
        // derivative: 2 x 0.0625 = 1/8 is level 0; 1/4 is level 1.
        let level = |d: f32| t.image.level_count() as f32 - 1.0 + (2.0 * d).log2();
        assert_eq!(level(1.0 / 16.0), 0.0);
        assert_eq!(level(1.0 / 8.0), 1.0);
        // The texture's (u, v) scale scales the footprint.
        let mut scaled = checker(8, 8, MipFilter::Bilinear);
        scaled.mapping.su = 8.0;
        scaled.mapping.sv = 8.0;
        let v = scaled.evaluate_filtered(uv, &footprint(1.0 / 32.0));
        assert!((v - Vec3::splat(0.5)).abs().max_element() < 1e-6, "{v}");
    }

    #[test]
    fn trilinear_blends_two_levels_and_point_takes_the_nearest_texel() {
        // 8 x 8, pairs of rows of 0 and of 1: level 1 has rows 0, 1, 0, 1,
        // level 2 is grey.
        let pixels = (0..64).map(|i| Vec3::splat(((i / 8 / 2) % 2) as f32)).collect();
        let opts = |filter| ImageOptions {
            encoding: Encoding::Linear,
            filter,
            ..ImageOptions::default()
        };
        let image = Arc::new(TexImage::from_pixels("rows", 8, 8, pixels));
        let tri = ImageTexture::new(image.clone(), &opts(MipFilter::Trilinear));
        // The centre of level 1's top row (0); level 2 is 0.5 there.
        let uv = Vec2::new(0.5, 1.0 - 0.125);
        // Level 1.5 (a filter width of 2^-1.5): halfway between them.
        let at = |level: f32| footprint(2f32.powf(level - 3.0) / 2.0);
        let v = tri.evaluate_filtered(uv, &at(1.5)).x;
        assert!((v - 0.25).abs() < 1e-6, "{v}");
        // Below level 1 pbrt-v4 reads level 0 alone.
        assert_eq!(tri.evaluate_filtered(uv, &at(0.5)), tri.evaluate(uv));
        // Bilinear reads the level below: level 1's 0.
        let bi = ImageTexture::new(image.clone(), &opts(MipFilter::Bilinear));
        assert_eq!(bi.evaluate_filtered(uv, &at(1.5)).x, 0.0);
        // Point: the nearest texel of that level (row 1 of level 1: 1).
        let point = ImageTexture::new(image, &opts(MipFilter::Point));
        assert_eq!(point.evaluate_filtered(Vec2::new(0.3, 0.6), &at(1.5)).x, 1.0);
    }

    #[test]
    fn levels_of_8_bit_images_are_8_bit_and_odd_sizes_round_up_to_powers_of_two() {
        let dir = tempfile::tempdir().unwrap();
        // 3 x 1, grey 0, 255, 128: rounded up to 4 x 1, then 2 x 1 and 1 x 1.
        let path = dir.path().join("odd.png");
        ::image::GrayImage::from_raw(3, 1, vec![0, 255, 128])
            .unwrap()
            .save(&path)
            .unwrap();
        let image = load_image(&path, Encoding::Linear).unwrap();
        assert!(image.eight_bit);
        assert_eq!(image.level_count(), 3);
        let levels = image.pyramid();
        assert_eq!(
            levels.iter().map(|l| (l.width, l.height)).collect::<Vec<_>>(),
            [(2, 1), (1, 1)]
        );
        for l in levels {
            for p in l.pixels.all() {
                let stored = p.x * 255.0;
                assert!((stored - stored.round()).abs() < 1e-3, "{stored} is not an 8-bit value");
            }
        }
        // A power-of-two image: each level averages the floats of the level
        // below (not its 8-bit copy), then keeps 8 bits.
        let path4 = dir.path().join("four.png");
        ::image::GrayImage::from_raw(4, 1, vec![0, 255, 128, 64])
            .unwrap()
            .save(&path4)
            .unwrap();
        let four = load_image(&path4, Encoding::Linear).unwrap();
        let v = [0.0, 255.0, 128.0, 64.0].map(|x: f32| x / 255.0);
        let eight = |x: f32| (x * 255.0).round() / 255.0;
        let level1 = [eight((v[0] + v[1]) * 0.5), eight((v[2] + v[3]) * 0.5)];
        let top = eight(((v[0] + v[1]) * 0.5 + (v[2] + v[3]) * 0.5) * 0.5);
        let got = four.pyramid();
        assert_eq!([got[0].pixels.get(0).x, got[0].pixels.get(1).x], level1);
        assert_eq!(got[1].pixels.get(0).x, top);
        // Kept as bytes, and equal to the quantised floats they stand for.
        assert!(matches!(got[0].pixels, Texels::Bytes { .. }));
        // sRGB levels are quantised in the encoding: values stay on its grid.
        let srgb = load_image(&path, Encoding::Srgb).unwrap();
        for p in srgb.pyramid()[0].pixels.all() {
            let stored = Encoding::Srgb.encode(p.x) * 255.0;
            assert!((stored - stored.round()).abs() < 1e-2, "{stored}");
        }
    }
}
