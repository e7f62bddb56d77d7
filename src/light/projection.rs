//! The image a projection light casts (pbrt-v4's `ProjectionLight`): a
//! point light that shines an image through a perspective frustum, like a
//! slide projector. Directions in the light's frame (looking down +z) meet
//! the plane z = 1 at points that, divided by tan(fov / 2), are the
//! image's screen coordinates: the longer side of the image spans [-aspect,
//! aspect], the shorter [-1, 1].

use crate::math::{Vec2, Vec3};
use crate::sampling::Distribution2D;

/// Directions closer than this to the light's plane get nothing (pbrt-v4's
/// near plane).
const HITHER: f32 = 1e-3;

#[derive(Clone, Debug, PartialEq)]
pub struct Projector {
    width: u32,
    height: u32,
    /// Row 0 at the top.
    texels: Vec<Vec3>,
    /// The screen window: the image's extent on the plane z = 1 over tan.
    min: Vec2,
    max: Vec2,
    tan_half_fov: f32,
    /// Particles leave in proportion to the texels' mean times cos^3, the
    /// solid angle a texel covers.
    distribution: Distribution2D,
}

impl Projector {
    /// An image of `width` x `height` texels (row 0 at the top; negative
    /// components count as zero) cast over a frustum of `fov_deg` degrees
    /// across the image's shorter side.
    pub fn new(width: u32, height: u32, texels: Vec<Vec3>, fov_deg: f32) -> Result<Projector, String> {
        let texels = super::clamped_texels("an image", width, height, texels)?;
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(format!("fov {fov_deg} must be in (0, 180) degrees"));
        }
        let aspect = width as f32 / height as f32;
        let (min, max) = if aspect > 1.0 {
            (Vec2::new(-aspect, -1.0), Vec2::new(aspect, 1.0))
        } else {
            (Vec2::new(-1.0, -1.0 / aspect), Vec2::new(1.0, 1.0 / aspect))
        };
        let mut p = Projector {
            width,
            height,
            texels,
            min,
            max,
            tan_half_fov: (fov_deg.to_radians() / 2.0).tan(),
            distribution: Distribution2D::new(&[1.0], 1, 1),
        };
        let weights: Vec<f32> = (0..width * height)
            .map(|i| {
                let t = p.texels[i as usize];
                (t.x + t.y + t.z) / 3.0 * p.cos3(p.texel_centre(i))
            })
            .collect();
        p.distribution = Distribution2D::new(&weights, width as usize, height as usize);
        Ok(p)
    }

    /// What the image is: its size, tan(fov / 2) and texels (for a scene's
    /// fingerprint).
    pub fn identity(&self) -> (u32, u32, f32, &[Vec3]) {
        (self.width, self.height, self.tan_half_fov, &self.texels)
    }

    /// The area of the screen window on the plane z = 1 (pbrt-v4's `A`).
    fn plane_area(&self) -> f32 {
        let s = self.max - self.min;
        s.x * s.y * self.tan_half_fov * self.tan_half_fov
    }

    fn texel_centre(&self, i: u32) -> Vec2 {
        Vec2::new(
            ((i % self.width) as f32 + 0.5) / self.width as f32,
            ((i / self.width) as f32 + 0.5) / self.height as f32,
        )
    }

    /// The light-frame direction through image coordinates `uv`.
    fn direction(&self, uv: Vec2) -> Vec3 {
        let s = self.min + uv * (self.max - self.min);
        Vec3::new(s.x * self.tan_half_fov, s.y * self.tan_half_fov, 1.0).normalize()
    }

    fn cos3(&self, uv: Vec2) -> f32 {
        self.direction(uv).z.powi(3)
    }

    /// Image coordinates of light-frame direction `w` (unit), if the image
    /// covers it.
    fn uv(&self, w: Vec3) -> Option<Vec2> {
        if w.z < HITHER {
            return None;
        }
        let s = Vec2::new(w.x, w.y) / (w.z * self.tan_half_fov);
        let inside = s.x >= self.min.x && s.x <= self.max.x && s.y >= self.min.y && s.y <= self.max.y;
        inside.then(|| (s - self.min) / (self.max - self.min))
    }

    fn texel(&self, uv: Vec2) -> Vec3 {
        let x = ((uv.x * self.width as f32) as u32).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as u32).min(self.height - 1);
        self.texels[(y * self.width + x) as usize]
    }

    /// The intensity (per unit scale) towards light-frame direction `w`.
    pub fn intensity(&self, w: Vec3) -> Vec3 {
        self.uv(w).map_or(Vec3::ZERO, |uv| self.texel(uv))
    }

    /// Power per unit scale: the intensity integrated over the frustum, each
    /// texel's solid angle its share of the window's area times cos^3 at its
    /// centre (pbrt-v4's `Phi`).
    pub fn power(&self) -> Vec3 {
        let sum: Vec3 = (0..self.width * self.height)
            .map(|i| self.texels[i as usize] * self.cos3(self.texel_centre(i)))
            .sum();
        sum * (self.plane_area() / (self.width * self.height) as f32)
    }

    /// The power of the image's luminance per unit scale (what pbrt-v4's
    /// `power` parameter sets).
    pub fn luminous_power(&self) -> f32 {
        crate::math::luminance(self.power())
    }

    /// A light-frame direction in proportion to the texels' mean times the
    /// solid angle, and its solid-angle density; None for a black image.
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let (uv, pdf_uv) = self.distribution.sample(u);
        let w = self.direction(uv);
        let pdf = self.pdf_from(pdf_uv, w);
        (pdf > 0.0).then_some((w, pdf))
    }

    /// The solid-angle density with which `sample` returns `w`.
    pub fn pdf(&self, w: Vec3) -> f32 {
        self.uv(w).map_or(0.0, |uv| self.pdf_from(self.distribution.pdf(uv), w))
    }

    /// Image-area density to solid angle: the window's area maps to the
    /// plane z = 1, whose area element is dw / cos^3.
    fn pdf_from(&self, pdf_uv: f32, w: Vec3) -> f32 {
        let cos3 = w.z.powi(3);
        if pdf_uv <= 0.0 || cos3 <= 0.0 {
            return 0.0;
        }
        pdf_uv / (self.plane_area() * cos3)
    }
}
