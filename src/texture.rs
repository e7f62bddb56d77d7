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
use glam::Affine3A;
use std::sync::Arc;

mod imagemap;
pub(crate) mod noise;
mod procedural;

pub use procedural::{Mapping2D, NoiseTexture, Pattern};

pub(crate) use imagemap::Fnv64;
pub use imagemap::{
    decode_bytes, load_image, srgb_to_linear, Encoding, ImageOptions, ImageTexture, MipFilter, TexImage, UvMapping,
    WrapMode,
};

/// Where a texture is looked up: the surface's (u, v), the point itself,
/// the surface's geometric normal there, and how far the point and (u, v)
/// move from one pixel to the next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexCoord {
    pub uv: Vec2,
    pub p: Vec3,
    pub n: Vec3,
    pub footprint: Footprint,
}

impl TexCoord {
    /// A lookup at a point with normal `n`, with no footprint: an image's
    /// finest level, every octave of noise.
    pub fn at(uv: Vec2, p: Vec3, n: Vec3) -> TexCoord {
        TexCoord {
            uv,
            p,
            n,
            footprint: Footprint::NONE,
        }
    }
}

/// The change of the point and of (u, v) from one pixel to the next at a
/// surface point, along the image's x and y (pbrt-v4's dpdx, dpdy, dudx,
/// dvdx, dudy, dvdy, estimated as its `SurfaceInteraction::
/// ComputeDifferentials` does and scaled, as there, by the sampling rate).
/// It chooses an image's MIP level, a bump map's finite-difference step,
/// how many octaves of noise show and how much a checkerboard's edges are
/// blurred. Zero: no footprint (the finest level, pbrt-v4's default step,
/// every octave, sharp edges).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    pub dudx: f32,
    pub dvdx: f32,
    pub dudy: f32,
    pub dvdy: f32,
    pub dpdx: Vec3,
    pub dpdy: Vec3,
}

impl Footprint {
    pub const NONE: Footprint = Footprint {
        dudx: 0.0,
        dvdx: 0.0,
        dudy: 0.0,
        dvdy: 0.0,
        dpdx: Vec3::ZERO,
        dpdy: Vec3::ZERO,
    };
}

#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Constant(Vec3),
    /// Two textures alternating over the unit squares of a 2D mapping,
    /// `even` where the cell indices sum to an even number, filtered over
    /// the footprint (pbrt-v4 `checkerboard`).
    Checkerboard {
        even: Arc<Texture>,
        odd: Arc<Texture>,
        mapping: Arc<Mapping2D>,
    },
    /// The same over the unit cubes of the texture's space (pbrt-v4
    /// `checkerboard` of `dimension` 3); the transformation is from the world.
    Checkerboard3D {
        even: Arc<Texture>,
        odd: Arc<Texture>,
        to_texture: Arc<Affine3A>,
    },
    /// `inside` in polka dots over a 2D mapping, `outside` between (pbrt-v4
    /// `dots`).
    Dots {
        inside: Arc<Texture>,
        outside: Arc<Texture>,
        mapping: Arc<Mapping2D>,
    },
    /// Bilinear between four values at the corners of the unit square of a
    /// 2D mapping, [v00, v01, v10, v11] at (s, t) = (0, 0), (0, 1), (1, 0),
    /// (1, 1), and extrapolated beyond it (pbrt-v4 `bilerp`).
    Bilerp(Arc<([Vec3; 4], Mapping2D)>),
    /// |n . dir| a + (1 - |n . dir|) b for the surface normal n (pbrt-v4
    /// `directionmix`; `dir` a unit vector of the world).
    DirectionMix {
        a: Arc<Texture>,
        b: Arc<Texture>,
        dir: Arc<Vec3>,
    },
    /// A pattern of noise (pbrt-v4 `fbm`, `wrinkled`, `windy`, `marble`).
    Noise(Arc<NoiseTexture>),
    /// A texture looked up at the (s, t) of a mapping other than (u, v)
    /// (an image under a spherical, cylindrical or planar mapping).
    Mapped {
        mapping: Arc<Mapping2D>,
        tex: Arc<Texture>,
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

    /// `even` and `odd` alternating over a `u_scale` x `v_scale` grid of
    /// squares per unit of (u, v).
    pub fn checkerboard(even: Arc<Texture>, odd: Arc<Texture>, u_scale: f32, v_scale: f32) -> Texture {
        Texture::Checkerboard {
            even,
            odd,
            mapping: Arc::new(Mapping2D::Uv(UvMapping {
                su: u_scale,
                sv: v_scale,
                ..UvMapping::default()
            })),
        }
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
            Texture::Checkerboard { even, odd, mapping } => {
                let st = mapping.map(tc);
                blend(even, odd, procedural::checkerboard_weight(st.uv, &st.footprint), tc)
            }
            Texture::Checkerboard3D { even, odd, to_texture } => {
                blend(even, odd, procedural::checkerboard_weight_3d(to_texture, tc), tc)
            }
            Texture::Dots {
                inside,
                outside,
                mapping,
            } => {
                if procedural::inside_polka_dot(mapping.map(tc).uv) {
                    inside.eval(tc)
                } else {
                    outside.eval(tc)
                }
            }
            Texture::Bilerp(b) => {
                let ([v00, v01, v10, v11], mapping) = &**b;
                let st = mapping.map(tc).uv;
                let (s, t) = (st.x, st.y);
                V::constant(
                    *v00 * ((1.0 - s) * (1.0 - t)) + *v10 * (s * (1.0 - t)) + *v01 * ((1.0 - s) * t) + *v11 * (s * t),
                )
            }
            Texture::DirectionMix { a, b, dir } => {
                let amount = tc.n.dot(**dir).abs();
                // As pbrt-v4: a texture whose weight is zero is not looked up.
                let first = if amount != 0.0 {
                    a.eval::<V>(tc) * amount
                } else {
                    V::zero()
                };
                let second = if amount != 1.0 {
                    b.eval::<V>(tc) * (1.0 - amount)
                } else {
                    V::zero()
                };
                first + second
            }
            Texture::Noise(n) => V::constant(n.evaluate(tc)),
            Texture::Mapped { mapping, tex } => tex.eval(&mapping.map(tc)),
            Texture::Scale { tex, scale } => tex.eval::<V>(tc) * scale.eval::<V>(tc),
            Texture::Mix { a, b, amount } => {
                let t: f32 = amount.eval(tc);
                a.eval::<V>(tc) * (1.0 - t) + b.eval::<V>(tc) * t
            }
            Texture::Image(img) => V::image(img, tc),
        }
    }

    /// Whether the texture's value depends on the pixel's footprint (an
    /// image's MIP level, a checkerboard's blurred edges, the octaves of
    /// noise that show): its lookups then want one.
    pub fn needs_footprint(&self) -> bool {
        match self {
            Texture::Constant(_) | Texture::Bilerp(_) => false,
            Texture::Checkerboard { .. } | Texture::Checkerboard3D { .. } | Texture::Noise(_) | Texture::Image(_) => {
                true
            }
            Texture::Dots {
                inside: a, outside: b, ..
            }
            | Texture::DirectionMix { a, b, .. }
            | Texture::Scale { tex: a, scale: b } => a.needs_footprint() || b.needs_footprint(),
            Texture::Mix { a, b, amount } => a.needs_footprint() || b.needs_footprint() || amount.needs_footprint(),
            Texture::Mapped { tex, .. } => tex.needs_footprint(),
        }
    }

    /// The texture of a scene reflected by `r` (its own inverse): a texture
    /// of space looks up the point carried back, a direction mix turns its
    /// direction with the scene; what reads (u, v) is unchanged.
    pub fn reflected(&self, r: &Affine3A) -> Texture {
        let re = |t: &Arc<Texture>| Arc::new(t.reflected(r));
        let map = |m: &Arc<Mapping2D>| Arc::new(m.reflected(r));
        match self {
            Texture::Constant(_) | Texture::Image(_) => self.clone(),
            Texture::Checkerboard { even, odd, mapping } => Texture::Checkerboard {
                even: re(even),
                odd: re(odd),
                mapping: map(mapping),
            },
            Texture::Checkerboard3D { even, odd, to_texture } => Texture::Checkerboard3D {
                even: re(even),
                odd: re(odd),
                to_texture: Arc::new(**to_texture * *r),
            },
            Texture::Dots {
                inside,
                outside,
                mapping,
            } => Texture::Dots {
                inside: re(inside),
                outside: re(outside),
                mapping: map(mapping),
            },
            Texture::Bilerp(b) => Texture::Bilerp(Arc::new((b.0, b.1.reflected(r)))),
            Texture::DirectionMix { a, b, dir } => Texture::DirectionMix {
                a: re(a),
                b: re(b),
                dir: Arc::new(r.transform_vector3(**dir)),
            },
            Texture::Noise(n) => Texture::Noise(Arc::new(NoiseTexture {
                to_texture: n.to_texture * *r,
                pattern: n.pattern,
            })),
            Texture::Mapped { mapping, tex } => Texture::Mapped {
                mapping: map(mapping),
                tex: re(tex),
            },
            Texture::Scale { tex, scale } => Texture::Scale {
                tex: re(tex),
                scale: re(scale),
            },
            Texture::Mix { a, b, amount } => Texture::Mix {
                a: re(a),
                b: re(b),
                amount: re(amount),
            },
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
            Texture::Checkerboard { even: a, odd: b, .. }
            | Texture::Checkerboard3D { even: a, odd: b, .. }
            | Texture::Dots {
                inside: a, outside: b, ..
            }
            | Texture::DirectionMix { a, b, .. }
            | Texture::Mix { a, b, .. } => a.max_value().max(b.max_value()),
            // Within the unit square; beyond it a ramp has no bound.
            Texture::Bilerp(b) => b.0.iter().fold(Vec3::ZERO, |m, v| m.max(*v)),
            Texture::Noise(n) => Vec3::splat(n.max_value()),
            Texture::Mapped { tex, .. } => tex.max_value(),
            Texture::Scale { tex, scale } => tex.max_value() * scale.max_value(),
            Texture::Image(img) => img.max_value(),
        }
    }
}

/// `even` and `odd` weighed by 1 - w and w, the one whose weight is zero not
/// looked up (as pbrt-v4's checkerboard).
fn blend<V: TexValue>(even: &Texture, odd: &Texture, w: f32, tc: &TexCoord) -> V {
    if w == 0.0 {
        even.eval(tc)
    } else if w == 1.0 {
        odd.eval(tc)
    } else {
        even.eval::<V>(tc) * (1.0 - w) + odd.eval::<V>(tc) * w
    }
}

/// What a texture evaluates to: a colour, or a number (a float texture's).
trait TexValue:
    Copy + std::ops::Mul<Output = Self> + std::ops::Mul<f32, Output = Self> + std::ops::Add<Output = Self>
{
    fn constant(v: Vec3) -> Self;
    fn zero() -> Self {
        Self::constant(Vec3::ZERO)
    }
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
        TexCoord::at(Vec2::new(u, v), Vec3::ZERO, Vec3::Z)
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
        let c = Texture::checkerboard(white.clone(), black.clone(), 4.0, 4.0);
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
