//! Textures: values that vary over a surface, looked up at a shading point's
//! texture coordinates (pbrt-v4 chapter 10). A texture here is RGB-valued; a
//! scalar parameter (a roughness, a mix amount, an alpha mask) reads the mean
//! of the channels, as pbrt-v4's float lookup of an RGB image does, or an
//! image's alpha channel where it has one.
//!
//! Textures form a small tree (scale and mix hold other textures), cloned
//! cheaply: the leaves that hold data share it (an image texture's pixels are
//! an `Arc`, decoded once per file; see [`load_image`]).

use crate::math::{Vec2, Vec3};
use std::sync::Arc;

mod imagemap;

pub use imagemap::{
    decode_bytes, load_image, srgb_to_linear, Encoding, ImageOptions, ImageTexture, MipFilter, TexImage, UvMapping,
    WrapMode,
};

/// Where a texture is looked up: the surface's (u, v), the point itself,
/// and how far (u, v) moves from one pixel to the next there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexCoord {
    pub uv: Vec2,
    pub p: Vec3,
    pub footprint: Footprint,
}

impl TexCoord {
    /// A lookup at a point, with no footprint: an image's finest level.
    pub fn at(uv: Vec2, p: Vec3) -> TexCoord {
        TexCoord {
            uv,
            p,
            footprint: Footprint::NONE,
        }
    }
}

/// The change of (u, v) from one pixel to the next at a surface point, along
/// the image's x and y (pbrt-v4's dudx, dvdx, dudy, dvdy, estimated as its
/// `SurfaceInteraction::ComputeDifferentials` does and scaled, as there, by
/// the sampling rate). It chooses an image's MIP level and a bump map's
/// finite-difference step. Zero: no footprint (the finest level, pbrt-v4's
/// default step).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    pub dudx: f32,
    pub dvdx: f32,
    pub dudy: f32,
    pub dvdy: f32,
}

impl Footprint {
    pub const NONE: Footprint = Footprint {
        dudx: 0.0,
        dvdx: 0.0,
        dudy: 0.0,
        dvdy: 0.0,
    };
}

#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Constant(Vec3),
    /// Two textures alternating over a `u_scale` x `v_scale` grid of squares
    /// per unit of (u, v) (pbrt-v4 `checkerboard`, 2D, no filtering).
    Checkerboard {
        even: Arc<Texture>,
        odd: Arc<Texture>,
        u_scale: f32,
        v_scale: f32,
    },
    /// The product of two textures (pbrt-v4 `scale`).
    Scale {
        tex: Arc<Texture>,
        scale: Arc<Texture>,
    },
    /// (1 - amount) a + amount b (pbrt-v4 `mix`).
    Mix {
        a: Arc<Texture>,
        b: Arc<Texture>,
        amount: Arc<Texture>,
    },
    /// An image looked up at (u, v), bilinearly (pbrt-v4 `imagemap`).
    Image(Arc<ImageTexture>),
}

impl Texture {
    pub fn constant(v: Vec3) -> Texture {
        Texture::Constant(v)
    }

    /// The texture's value at `tc`. Inlined for the constant case, which
    /// most materials are: the call of the recursive evaluation cost more
    /// than the constant.
    #[inline]
    pub fn evaluate(&self, tc: &TexCoord) -> Vec3 {
        match self {
            Texture::Constant(v) => *v,
            _ => self.evaluate_varying(tc),
        }
    }

    fn evaluate_varying(&self, tc: &TexCoord) -> Vec3 {
        self.eval(tc)
    }

    /// The value of a scalar texture, as pbrt-v4's float textures compute it:
    /// a colour is the mean of its channels (exactly the value of a grey
    /// one), an image its alpha channel where it has one
    /// ([`ImageTexture::evaluate_scalar`]), and scale, mix and checkerboard
    /// combine their parts' scalar values.
    pub fn evaluate_scalar(&self, tc: &TexCoord) -> f32 {
        self.eval(tc)
    }

    /// The texture's value as a colour or as a number: the tree is walked
    /// alike, the leaves give one or the other.
    fn eval<V: TexValue>(&self, tc: &TexCoord) -> V {
        match self {
            Texture::Constant(v) => V::constant(*v),
            Texture::Checkerboard {
                even,
                odd,
                u_scale,
                v_scale,
            } => {
                let (su, sv) = ((tc.uv.x * u_scale).floor(), (tc.uv.y * v_scale).floor());
                // Parity of the square; rem_euclid keeps negative coordinates alternating too.
                if (su + sv).rem_euclid(2.0) == 0.0 {
                    even.eval(tc)
                } else {
                    odd.eval(tc)
                }
            }
            Texture::Scale { tex, scale } => tex.eval::<V>(tc) * scale.eval::<V>(tc),
            Texture::Mix { a, b, amount } => {
                let t: f32 = amount.eval(tc);
                a.eval::<V>(tc) * (1.0 - t) + b.eval::<V>(tc) * t
            }
            Texture::Image(img) => V::image(img, tc),
        }
    }

    /// Whether an image is looked up anywhere in the texture (its lookups
    /// then want a footprint).
    pub fn has_image(&self) -> bool {
        match self {
            Texture::Constant(_) => false,
            Texture::Checkerboard { even, odd, .. } => even.has_image() || odd.has_image(),
            Texture::Scale { tex, scale } => tex.has_image() || scale.has_image(),
            Texture::Mix { a, b, amount } => a.has_image() || b.has_image() || amount.has_image(),
            Texture::Image(_) => true,
        }
    }

    /// The value when the texture does not vary, else `None`.
    pub fn as_constant(&self) -> Option<Vec3> {
        match self {
            Texture::Constant(v) => Some(*v),
            _ => None,
        }
    }

    /// Bounds of the values the texture can take, per channel (for validation
    /// and for the photon tracer's roulette, which must not assume a constant).
    pub fn max_value(&self) -> Vec3 {
        match self {
            Texture::Constant(v) => *v,
            Texture::Checkerboard { even, odd, .. } => even.max_value().max(odd.max_value()),
            Texture::Scale { tex, scale } => tex.max_value() * scale.max_value(),
            Texture::Mix { a, b, .. } => a.max_value().max(b.max_value()),
            Texture::Image(img) => img.max_value(),
        }
    }
}

/// What a texture evaluates to: a colour, or a number (a float texture's).
trait TexValue:
    Copy + std::ops::Mul<Output = Self> + std::ops::Mul<f32, Output = Self> + std::ops::Add<Output = Self>
{
    fn constant(v: Vec3) -> Self;
    fn image(img: &ImageTexture, tc: &TexCoord) -> Self;
}

impl TexValue for Vec3 {
    fn constant(v: Vec3) -> Self {
        v
    }
    fn image(img: &ImageTexture, tc: &TexCoord) -> Self {
        img.evaluate_filtered(tc.uv, &tc.footprint)
    }
}

impl TexValue for f32 {
    /// The mean of the channels, exactly the value of a grey colour.
    fn constant(v: Vec3) -> Self {
        if v.x == v.y && v.y == v.z {
            v.x
        } else {
            (v.x + v.y + v.z) / 3.0
        }
    }
    fn image(img: &ImageTexture, tc: &TexCoord) -> Self {
        img.evaluate_scalar_filtered(tc.uv, &tc.footprint)
    }
}

impl Texture {
    /// An image texture read from `path` (or shared with an earlier read of
    /// the same file and encoding); see [`ImageTexture::open`].
    pub fn image(path: &std::path::Path, opts: &ImageOptions) -> crate::error::Result<Texture> {
        Ok(Texture::Image(Arc::new(ImageTexture::open(path, opts)?)))
    }
}

impl From<Vec3> for Texture {
    fn from(v: Vec3) -> Texture {
        Texture::Constant(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(u: f32, v: f32) -> TexCoord {
        TexCoord::at(Vec2::new(u, v), Vec3::ZERO)
    }

    #[test]
    fn a_scalar_lookup_of_a_colour_is_the_channels_mean_and_of_a_grey_its_value() {
        let pixels = vec![
            Vec3::new(0.9, 0.3, 0.0),
            Vec3::splat(0.1),
            Vec3::splat(0.7),
            Vec3::splat(0.3),
        ];
        let image = Arc::new(TexImage::from_pixels("t", 2, 2, pixels));
        let opts = ImageOptions {
            encoding: Encoding::Linear,
            ..ImageOptions::default()
        };
        let tex = Texture::Image(Arc::new(ImageTexture::new(image, &opts)));
        // Texel centres: (0.25, 0.75) is the top-left texel (v up), (0.75, 0.75) the top-right.
        let colour = tex.evaluate(&at(0.25, 0.75));
        assert_eq!(colour, Vec3::new(0.9, 0.3, 0.0));
        assert!((tex.evaluate_scalar(&at(0.25, 0.75)) - 0.4).abs() < 1e-6);
        assert_eq!(tex.evaluate_scalar(&at(0.75, 0.75)), 0.1);
        // A mix's amount is a scalar too.
        let mix = Texture::Mix {
            a: Arc::new(Texture::from(Vec3::ZERO)),
            b: Arc::new(Texture::from(Vec3::ONE)),
            amount: Arc::new(tex),
        };
        assert!((mix.evaluate(&at(0.25, 0.75)) - Vec3::splat(0.4)).abs().max_element() < 1e-6);
    }

    #[test]
    fn checkerboard_alternates_and_scale_and_mix_combine() {
        let (black, white) = (Arc::new(Texture::from(Vec3::ZERO)), Arc::new(Texture::from(Vec3::ONE)));
        let c = Texture::Checkerboard {
            even: white.clone(),
            odd: black.clone(),
            u_scale: 4.0,
            v_scale: 4.0,
        };
        assert_eq!(c.evaluate(&at(0.1, 0.1)), Vec3::ONE);
        assert_eq!(c.evaluate(&at(0.3, 0.1)), Vec3::ZERO);
        assert_eq!(c.evaluate(&at(0.3, 0.3)), Vec3::ONE);
        assert_eq!(c.evaluate(&at(-0.1, 0.1)), Vec3::ZERO);
        let s = Texture::Scale {
            tex: Arc::new(Texture::from(Vec3::new(0.5, 1.0, 2.0))),
            scale: Arc::new(Texture::from(Vec3::splat(0.5))),
        };
        assert_eq!(s.evaluate(&at(0.0, 0.0)), Vec3::new(0.25, 0.5, 1.0));
        let m = Texture::Mix {
            a: black,
            b: white,
            amount: Arc::new(Texture::from(Vec3::splat(0.25))),
        };
        assert_eq!(m.evaluate(&at(0.0, 0.0)), Vec3::splat(0.25));
        assert_eq!(m.max_value(), Vec3::ONE);
    }
}
