//! An area light's emission image (pbrt-v4's `filename` on a `diffuse` area
//! light): the radiance at a point of the surface is the image at its
//! texture coordinates, times the light's scale. As in pbrt-v4's
//! `DiffuseAreaLight::L`, v runs up the image (v = 1 is its top row), the
//! lookup is bilinear between texel centres and clamps at the edges, and
//! negative texels count as zero.
//!
//! Light samples stay uniform in area, as pbrt-v4's are: the image weights
//! each sample, so that a dark part of the image costs shadow rays but adds
//! no bias.

use crate::math::{Vec2, Vec3};
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub struct EmissionImage {
    width: u32,
    height: u32,
    /// Row 0 at the top.
    texels: Vec<Vec3>,
    mean: Vec3,
}

impl EmissionImage {
    /// An image of `width` x `height` texels, row 0 at the top; negative
    /// components count as zero.
    pub fn new(width: u32, height: u32, texels: Vec<Vec3>) -> Result<EmissionImage, String> {
        let texels = super::clamped_texels("an image", width, height, texels)?;
        // Summed in f64: a large image's mean would drift in f32.
        let sum = texels.iter().fold([0f64; 3], |s, t| {
            [s[0] + t.x as f64, s[1] + t.y as f64, s[2] + t.z as f64]
        });
        let n = texels.len() as f64;
        let mean = Vec3::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32);
        Ok(EmissionImage {
            width,
            height,
            texels,
            mean,
        })
    }

    /// The image at texture coordinates `uv`.
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * self.width as f32 - 0.5;
        let y = (1.0 - uv.y) * self.height as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return Vec3::ZERO;
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (dx, dy) = (x - x0, y - y0);
        let texel = |i: i64, j: i64| {
            let i = i.clamp(0, w - 1);
            let j = j.clamp(0, h - 1);
            self.texels[(j * w + i) as usize]
        };
        // Far outside the image, clamping keeps the edge texel.
        let (i, j) = (x0.clamp(-2.0, w as f32) as i64, y0.clamp(-2.0, h as f32) as i64);
        (texel(i, j) * (1.0 - dx) + texel(i + 1, j) * dx) * (1.0 - dy)
            + (texel(i, j + 1) * (1.0 - dx) + texel(i + 1, j + 1) * dx) * dy
    }

    /// The texels' mean: what the image emits over a surface it covers once.
    pub fn mean(&self) -> Vec3 {
        self.mean
    }

    /// The largest texel component (a light's emission check).
    pub fn max(&self) -> f32 {
        self.texels.iter().fold(0.0, |m, t| m.max(t.max_element()))
    }

    /// Its size and texels (for a scene's fingerprint).
    pub fn identity(&self) -> (u32, u32, &[Vec3]) {
        (self.width, self.height, &self.texels)
    }
}

/// Where a triangle light reads its emission image: the image and the
/// texture coordinates at its three vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageOnTriangle {
    pub image: Arc<EmissionImage>,
    pub uv: [Vec2; 3],
}

impl ImageOnTriangle {
    /// The image at barycentric coordinates (b0, b1) (b2 = 1 - b0 - b1).
    pub fn at_barycentric(&self, b0: f32, b1: f32) -> Vec3 {
        let uv = self.uv[0] * b0 + self.uv[1] * b1 + self.uv[2] * (1.0 - b0 - b1);
        self.image.lookup(uv)
    }
}

/// A sphere light's emission image: the image and the sphere's axes (its
/// columns: the object frame's x, y, z in the world), read at pbrt-v4's
/// sphere coordinates about the frame's z.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageOnSphere {
    pub image: Arc<EmissionImage>,
    pub axes: glam::Mat3,
}

impl ImageOnSphere {
    /// The image where the sphere's outward unit normal is `n` (world).
    pub fn at_normal(&self, n: Vec3) -> Vec3 {
        self.image.lookup(crate::geometry::sphere_uv(self.axes.transpose() * n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image() -> EmissionImage {
        // Top row red then green, bottom row blue then white.
        EmissionImage::new(2, 2, vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE]).unwrap()
    }

    #[test]
    fn v_runs_up_the_image_and_u_across() {
        let im = image();
        // Texel centres: u 0.25 / 0.75, v 0.75 (top row) / 0.25 (bottom).
        assert_eq!(im.lookup(Vec2::new(0.25, 0.75)), Vec3::X);
        assert_eq!(im.lookup(Vec2::new(0.75, 0.75)), Vec3::Y);
        assert_eq!(im.lookup(Vec2::new(0.25, 0.25)), Vec3::Z);
        assert_eq!(im.lookup(Vec2::new(0.75, 0.25)), Vec3::ONE);
    }

    #[test]
    fn lookups_are_bilinear_between_centres_and_clamp_beyond() {
        let im = image();
        let mid = im.lookup(Vec2::new(0.5, 0.5));
        assert!((mid - Vec3::new(0.5, 0.5, 0.5)).abs().max_element() < 1e-6, "{mid}");
        // Halfway between the top row's centres.
        let top = im.lookup(Vec2::new(0.5, 0.75));
        assert!((top - Vec3::new(0.5, 0.5, 0.0)).abs().max_element() < 1e-6, "{top}");
        // Beyond the corners: the corner texels.
        assert_eq!(im.lookup(Vec2::new(-3.0, 5.0)), Vec3::X);
        assert_eq!(im.lookup(Vec2::new(7.0, -1e9)), Vec3::ONE);
        assert_eq!(im.lookup(Vec2::new(f32::NAN, 0.5)), Vec3::ZERO);
    }

    #[test]
    fn negative_texels_count_as_zero_and_bad_sizes_are_refused() {
        let im = EmissionImage::new(2, 1, vec![Vec3::new(-1.0, 2.0, 0.0), Vec3::new(1.0, 0.0, 4.0)]).unwrap();
        assert_eq!(im.mean(), Vec3::new(0.5, 1.0, 2.0));
        assert_eq!(im.max(), 4.0);
        assert!(EmissionImage::new(2, 2, vec![Vec3::ONE; 3]).is_err());
        assert!(EmissionImage::new(0, 0, vec![]).is_err());
        let e = EmissionImage::new(2, 1, vec![Vec3::ONE, Vec3::splat(f32::INFINITY)]).unwrap_err();
        assert!(e.contains("(1, 0)"), "{e}");
    }

    #[test]
    fn a_triangle_reads_the_image_at_its_interpolated_coordinates() {
        let t = ImageOnTriangle {
            image: Arc::new(image()),
            uv: [Vec2::new(0.25, 0.75), Vec2::new(0.75, 0.75), Vec2::new(0.75, 0.25)],
        };
        assert_eq!(t.at_barycentric(1.0, 0.0), Vec3::X);
        assert_eq!(t.at_barycentric(0.0, 1.0), Vec3::Y);
        assert_eq!(t.at_barycentric(0.0, 0.0), Vec3::ONE);
    }
}
