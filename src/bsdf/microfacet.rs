//! The anisotropic Trowbridge-Reitz (GGX) microfacet distribution
//! (Trowbridge & Reitz 1975; Walter et al. 2007), as pbrt-v4 9.6 uses it:
//! the normal distribution `d`, Smith's height-correlated masking-shadowing
//! `g` with its auxiliary `lambda` (Heitz 2014, "Understanding the
//! Masking-Shadowing Function"), and sampling of the distribution of visible
//! normals (Heitz 2018, "Sampling the GGX Distribution of Visible Normals").
//! All directions are in the local frame (macro-normal +z).

use crate::math::{Vec2, Vec3};
use std::f32::consts::PI;

/// Trowbridge-Reitz distribution with roughness `alpha_x` along the local x
/// axis and `alpha_y` along y (alpha = the slope's standard scale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrowbridgeReitz {
    alpha_x: f32,
    alpha_y: f32,
}

impl TrowbridgeReitz {
    /// Below this alpha (in both directions) a surface is treated as a
    /// perfect specular one: pbrt-v4's threshold.
    pub const SMOOTH_ALPHA: f32 = 1e-3;

    /// A distribution with the given alphas. Negative or NaN alphas count as
    /// zero. When the surface is rough in one direction, the other alpha is
    /// raised to at least 1e-4, as pbrt-v4 does: `d` overflows otherwise.
    pub fn new(alpha_x: f32, alpha_y: f32) -> Self {
        let clean = |a: f32| if a.is_nan() { 0.0 } else { a.clamp(0.0, 1e4) };
        let (ax, ay) = (clean(alpha_x), clean(alpha_y));
        if ax.max(ay) < Self::SMOOTH_ALPHA {
            TrowbridgeReitz {
                alpha_x: ax,
                alpha_y: ay,
            }
        } else {
            TrowbridgeReitz {
                alpha_x: ax.max(1e-4),
                alpha_y: ay.max(1e-4),
            }
        }
    }

    pub fn isotropic(alpha: f32) -> Self {
        Self::new(alpha, alpha)
    }

    /// A perfectly smooth surface.
    pub fn smooth() -> Self {
        Self::new(0.0, 0.0)
    }

    /// The distribution pbrt-v4's materials build from `uroughness` /
    /// `vroughness`: remapped by [`Self::roughness_to_alpha`] when
    /// `remap_roughness` is set (pbrt-v4's `remaproughness`, default true),
    /// used as alphas directly otherwise.
    pub fn from_roughness(u_roughness: f32, v_roughness: f32, remap_roughness: bool) -> Self {
        if remap_roughness {
            Self::new(
                Self::roughness_to_alpha(u_roughness),
                Self::roughness_to_alpha(v_roughness),
            )
        } else {
            Self::new(u_roughness, v_roughness)
        }
    }

    /// pbrt-v4's `RoughnessToAlpha`: alpha = sqrt(roughness). (pbrt-v4 keeps
    /// the square root for compatibility although roughness^2 would be more
    /// perceptually uniform; we keep it to render its scenes alike.)
    pub fn roughness_to_alpha(roughness: f32) -> f32 {
        roughness.max(0.0).sqrt()
    }

    pub fn alpha_x(&self) -> f32 {
        self.alpha_x
    }

    pub fn alpha_y(&self) -> f32 {
        self.alpha_y
    }

    /// pbrt-v4's `Regularize`: each alpha below 0.3 doubled, and kept
    /// within [0.1, 0.3], so that a smooth surface becomes a glossy one.
    pub fn regularized(&self) -> Self {
        let r = |a: f32| if a < 0.3 { (2.0 * a).clamp(0.1, 0.3) } else { a };
        Self::new(r(self.alpha_x), r(self.alpha_y))
    }

    /// True when the surface is to be treated as a perfect specular one.
    pub fn effectively_smooth(&self) -> bool {
        self.alpha_x.max(self.alpha_y) < Self::SMOOTH_ALPHA
    }

    /// Microfacet normal density D(wm): the area of microfacets with normal
    /// `wm` per unit macro-surface area and solid angle; it integrates to 1
    /// against cos(theta_m).
    pub fn d(&self, wm: Vec3) -> f32 {
        let cos2 = wm.z * wm.z;
        let cos4 = cos2 * cos2;
        if cos4 < 1e-16 {
            return 0.0;
        }
        // tan^2(theta) (cos^2(phi) / ax^2 + sin^2(phi) / ay^2), in Cartesian form.
        let e = ((wm.x / self.alpha_x).powi(2) + (wm.y / self.alpha_y).powi(2)) / cos2;
        1.0 / (PI * self.alpha_x * self.alpha_y * cos4 * (1.0 + e) * (1.0 + e))
    }

    /// Smith's Lambda(w): the ratio of masked to visible projected microfacet
    /// area for direction `w`. Infinite at grazing incidence.
    pub fn lambda(&self, w: Vec3) -> f32 {
        let cos2 = w.z * w.z;
        if cos2 == 0.0 {
            return f32::INFINITY;
        }
        // alpha(phi)^2 tan^2(theta), alpha interpolated with the azimuth.
        let a2t2 = ((w.x * self.alpha_x).powi(2) + (w.y * self.alpha_y).powi(2)) / cos2;
        // (sqrt(1 + x) - 1) / 2, rearranged to keep precision for small x.
        a2t2 / (2.0 * (1.0 + (1.0 + a2t2).sqrt()))
    }

    /// Masking function G1(w): the fraction of microfacets visible from `w`.
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G(wo, wi) (Heitz 2014, eq. 99).
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Distribution of normals visible from `w`:
    /// D_w(wm) = G1(w) |w . wm| D(wm) / |cos(theta_w)|; it integrates to 1
    /// over the normals facing `w` (Heitz 2014, eq. 38).
    pub fn d_visible(&self, w: Vec3, wm: Vec3) -> f32 {
        let cos_w = w.z.abs();
        if cos_w == 0.0 {
            return 0.0;
        }
        self.g1(w) / cos_w * self.d(wm) * w.dot(wm).abs()
    }

    /// Density of [`Self::sample_wm`] for `w`, per solid angle of `wm`.
    pub fn pdf(&self, w: Vec3, wm: Vec3) -> f32 {
        self.d_visible(w, wm)
    }

    /// Samples a microfacet normal visible from `w` (Heitz 2018): stretch
    /// `w` to the configuration where alpha = 1, sample the projected
    /// hemisphere seen from it, and unstretch the normal. A `w` below the
    /// surface is treated as its mirror image above, so the normal returned
    /// always has z > 0.
    pub fn sample_wm(&self, w: Vec3, u: Vec2) -> Vec3 {
        // Transform w to the hemispherical configuration.
        let mut wh = Vec3::new(self.alpha_x * w.x, self.alpha_y * w.y, w.z).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        // Orthonormal basis (t1, t2, wh) around the stretched direction.
        let t1 = if wh.z < 0.99999 {
            Vec3::Z.cross(wh).normalize()
        } else {
            Vec3::X
        };
        let t2 = wh.cross(t1);
        // Uniform point on the unit disk (polar map).
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let (px, mut py) = (r * phi.cos(), r * phi.sin());
        // Squash the disk onto the part of the hemisphere's projection that
        // faces wh (the visible half-disk plus the projected ellipse).
        let h = (1.0 - px * px).max(0.0).sqrt();
        let s = 0.5 * (1.0 + wh.z);
        py = (1.0 - s) * h + s * py;
        // Lift the point to the hemisphere and unstretch the normal.
        let pz = (1.0 - px * px - py * py).max(0.0).sqrt();
        let nh = t1 * px + t2 * py + wh * pz;
        Vec3::new(self.alpha_x * nh.x, self.alpha_y * nh.y, nh.z.max(1e-6)).normalize()
    }
}
