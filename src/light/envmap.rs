//! The image of an infinite light: texels over the sphere of directions in
//! the light's own frame, looked up nearest (as pbrt-v4's
//! `ImageInfiniteLight`), with a piecewise-constant distribution over the
//! image proportional to luminance times each texel's solid angle, so that
//! sampling follows the light.
//!
//! Two parameterisations, both with texel row 0 at the top of the image file
//! and u across, v down:
//! - `LatLong` (equirectangular): u = phi / 2 pi with phi = atan2(y, x) in
//!   [0, 2 pi), v = theta / pi with theta = acos(z); the top row is +z. This
//!   is the convention of pbrt-v3 and of pbrt-v4's `imgtool makeequiarea`,
//!   so a map and its equal-area conversion agree.
//! - `Octahedral`: pbrt-v4's equal-area square (`equal_area_square_to_sphere`);
//!   the image must be square.

use crate::math::{luminance, Vec2, Vec3};
use crate::sampling::{equal_area_sphere_to_square, equal_area_square_to_sphere, Distribution2D};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvMapping {
    LatLong,
    Octahedral,
}

impl EnvMapping {
    pub fn name(self) -> &'static str {
        match self {
            EnvMapping::LatLong => "latlong",
            EnvMapping::Octahedral => "octahedral",
        }
    }
}

/// An environment image ready to be looked up and sampled.
#[derive(Clone, PartialEq)]
pub struct EnvMap {
    width: u32,
    height: u32,
    /// Row-major, row 0 at the top.
    texels: Vec<Vec3>,
    mapping: EnvMapping,
    distribution: Distribution2D,
    /// The integral of the radiance over the sphere, sum of L times solid angle.
    integral: Vec3,
    /// Where the image came from, for messages.
    name: String,
}

impl std::fmt::Debug for EnvMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "EnvMap({}, {}x{} {})",
            self.name,
            self.width,
            self.height,
            self.mapping.name()
        )
    }
}

impl EnvMap {
    /// A map from `width` x `height` texels (row 0 at the top). Negative
    /// components count as zero (as pbrt's `ClampZero`); a texel that is
    /// not finite, a size that does not match, or a non-square octahedral
    /// map is an error.
    pub fn new(
        width: u32,
        height: u32,
        texels: Vec<Vec3>,
        mapping: EnvMapping,
        name: &str,
    ) -> std::result::Result<EnvMap, String> {
        let texels = super::clamped_texels("an environment map", width, height, texels)?;
        if mapping == EnvMapping::Octahedral && width != height {
            return Err(format!(
                "an octahedral (equal-area) environment map must be square, not {width}x{height}"
            ));
        }
        let (w, h) = (width as usize, height as usize);
        let mut weights = Vec::with_capacity(w * h);
        let mut integral = glam::DVec3::ZERO;
        for y in 0..h {
            // Each texel's share of the sphere: exact for the integral, the
            // row centre's sin(theta) for the sampling weight.
            let (omega, sin_centre) = match mapping {
                EnvMapping::Octahedral => (4.0 * std::f64::consts::PI / (w * h) as f64, 1.0),
                EnvMapping::LatLong => {
                    let t0 = std::f64::consts::PI * y as f64 / h as f64;
                    let t1 = std::f64::consts::PI * (y + 1) as f64 / h as f64;
                    let omega = 2.0 * std::f64::consts::PI / w as f64 * (t0.cos() - t1.cos());
                    (omega, (PI * (y as f32 + 0.5) / h as f32).sin())
                }
            };
            for t in &texels[y * w..(y + 1) * w] {
                integral += t.as_dvec3() * omega;
                weights.push(luminance(*t) * sin_centre);
            }
        }
        Ok(EnvMap {
            width,
            height,
            distribution: Distribution2D::new(&weights, w, h),
            texels,
            mapping,
            integral: integral.as_vec3(),
            name: name.to_string(),
        })
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn mapping(&self) -> EnvMapping {
        self.mapping
    }

    /// The texels, row by row from the top.
    pub fn texels(&self) -> &[Vec3] {
        &self.texels
    }

    /// The integral of the radiance over all directions (W / m^2 / ... per
    /// unit of `scale`): 4 pi times the mean for a uniform map.
    pub fn integral(&self) -> Vec3 {
        self.integral
    }

    fn texel(&self, uv: Vec2) -> Vec3 {
        let x = ((uv.x * self.width as f32) as u32).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as u32).min(self.height - 1);
        self.texels[(y * self.width + x) as usize]
    }

    /// Image coordinates of a unit direction in the light's frame.
    pub fn uv(&self, w: Vec3) -> Vec2 {
        match self.mapping {
            EnvMapping::Octahedral => equal_area_sphere_to_square(w),
            EnvMapping::LatLong => {
                let mut phi = w.y.atan2(w.x);
                if phi < 0.0 {
                    phi += 2.0 * PI;
                }
                // atan2 rather than acos(z): exact near the poles.
                let theta = Vec2::new(w.x, w.y).length().atan2(w.z);
                Vec2::new(phi / (2.0 * PI), theta / PI)
            }
        }
    }

    /// The illuminance the map gives a surface facing its +z (luminance
    /// times cos over the upper hemisphere), per unit scale: what pbrt-v4's
    /// `illuminance` parameter sets.
    pub fn upper_illuminance(&self) -> f32 {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut sum = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                let (dir, omega) = match self.mapping {
                    EnvMapping::Octahedral => (equal_area_square_to_sphere(uv), 4.0 * PI / (w * h) as f32),
                    EnvMapping::LatLong => {
                        let (sin_t, cos_t) = (PI * uv.y).sin_cos();
                        let (sin_p, cos_p) = (2.0 * PI * uv.x).sin_cos();
                        let omega = 2.0 * PI * PI * sin_t / (w * h) as f32;
                        (Vec3::new(sin_t * cos_p, sin_t * sin_p, cos_t), omega)
                    }
                };
                if dir.z > 0.0 {
                    sum += (luminance(self.texels[y * w + x]) * dir.z * omega) as f64;
                }
            }
        }
        sum as f32
    }

    /// Radiance from direction `w` (unit, in the light's frame), for an
    /// octahedral map bilinearly interpolated between the four nearest
    /// texel centres, a neighbour beyond an edge being the texel the
    /// equal-area map folds it onto (pbrt-v4's `OctahedralSphere` wrap): how
    /// pbrt-v4 resamples a map for a portal. A lat-long map is read at the
    /// nearest texel, as `le` reads it.
    pub fn le_smooth(&self, w: Vec3) -> Vec3 {
        if self.mapping != EnvMapping::Octahedral {
            return self.le(w);
        }
        let uv = equal_area_sphere_to_square(w);
        let (w, h) = (self.width as i64, self.height as i64);
        let fetch = |mut x: i64, mut y: i64| {
            // Across a vertical edge the square folds over its horizontal
            // centre line, across a horizontal one over its vertical one.
            if x < 0 {
                x = -x;
                y = h - 1 - y;
            } else if x >= w {
                x = 2 * w - 1 - x;
                y = h - 1 - y;
            }
            if y < 0 {
                x = w - 1 - x;
                y = -y;
            } else if y >= h {
                x = w - 1 - x;
                y = 2 * h - 1 - y;
            }
            let (x, y) = (x.clamp(0, w - 1), y.clamp(0, h - 1));
            self.texels[(y * w + x) as usize]
        };
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (dx, dy) = (x - x0, y - y0);
        let (xi, yi) = (x0 as i64, y0 as i64);
        fetch(xi, yi) * ((1.0 - dx) * (1.0 - dy))
            + fetch(xi + 1, yi) * (dx * (1.0 - dy))
            + fetch(xi, yi + 1) * ((1.0 - dx) * dy)
            + fetch(xi + 1, yi + 1) * (dx * dy)
    }

    /// Radiance from direction `w` (unit, in the light's frame).
    pub fn le(&self, w: Vec3) -> Vec3 {
        self.texel(self.uv(w))
    }

    /// A direction (light frame) sampled in proportion to luminance, its
    /// radiance and its solid-angle density; `None` for a black map.
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        let (uv, pdf_uv) = self.distribution.sample(u);
        if pdf_uv == 0.0 {
            return None;
        }
        let (w, jacobian) = match self.mapping {
            EnvMapping::Octahedral => (equal_area_square_to_sphere(uv), 4.0 * PI),
            EnvMapping::LatLong => {
                let (sin_t, cos_t) = (PI * uv.y).sin_cos();
                let (sin_p, cos_p) = (2.0 * PI * uv.x).sin_cos();
                (Vec3::new(sin_t * cos_p, sin_t * sin_p, cos_t), 2.0 * PI * PI * sin_t)
            }
        };
        if jacobian <= 0.0 {
            return None;
        }
        Some((w, self.texel(uv), pdf_uv / jacobian))
    }

    /// The solid-angle density with which `sample` returns `w` (light frame).
    pub fn pdf(&self, w: Vec3) -> f32 {
        let pdf_uv = self.distribution.pdf(self.uv(w));
        match self.mapping {
            EnvMapping::Octahedral => pdf_uv / (4.0 * PI),
            EnvMapping::LatLong => {
                let sin_t = Vec2::new(w.x, w.y).length();
                if sin_t == 0.0 {
                    0.0
                } else {
                    pdf_uv / (2.0 * PI * PI * sin_t)
                }
            }
        }
    }
}
