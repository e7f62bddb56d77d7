//! Lights, with pbrt's two faces: incident-light sampling for shadow rays
//! (`sample_li`, with its solid-angle density `pdf_li`) and particle emission
//! for photon tracing (`sample_le`, `sample_le_flux`, `pdf_le`).
//! A sphere light is a Lambertian emitter given by its total power Phi, so
//! its radiance is Phi / (pi * area). A point light of the same power has
//! intensity Phi / (4 pi). A triangle light is a diffuse area light (pbrt-v4's
//! `DiffuseAreaLight` on one triangle; meshes and quads are several) given by
//! its radiance, emitting on the side its normal, (v1 - v0) x (v2 - v0),
//! points to, or on both sides; its power is L * pi * area per side.
//!
//! After pbrt-v4 (`lights.cpp`) besides: a spot light (`SpotLight`: a point
//! whose intensity falls off with a smoothstep between two cones), a distant
//! light (`DistantLight`: parallel light from one direction) and an infinite
//! light (`UniformInfiniteLight` and `ImageInfiniteLight`: radiance from
//! every direction, constant or from an environment image, see `envmap`).
//! Distant and infinite lights have no surface a ray can hit; their power,
//! and the rays they emit, depend on the scene's bounding sphere, which
//! `Scene::build` hands them (`set_scene_bounds`): photons leave a disk of
//! that sphere's radius facing the light, as in pbrt-v4.

mod emission_image;
mod envmap;
mod portal;
mod projection;
mod sampler;

pub use emission_image::{EmissionImage, ImageOnSphere, ImageOnTriangle};
pub use envmap::{EnvMap, EnvMapping};
pub use portal::Portal;
pub use projection::Projector;
pub use sampler::{LightBounds, LightContext, LightSampleU, LightSamplerKind, LightTree};

use crate::geometry::{Disk, Sphere};
use crate::math::{orthonormal_basis, to_world, Ray, Vec2, Vec3};
use crate::sampling::{concentric_disk, cosine_hemisphere, sample_smoothstep, uniform_cone, uniform_sphere};
use glam::Mat3;
use std::f32::consts::PI;
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// `power` (over every side it emits from) as if the image, where there
    /// is one, were 1 everywhere.
    Sphere {
        sphere: Sphere,
        power: Vec3,
        image: Option<Arc<ImageOnSphere>>,
        emits: Emits,
    },
    Point {
        position: Vec3,
        power: Vec3,
    },
    /// `radiance` times, where there is one, the emission image read at
    /// the point's texture coordinates (pbrt-v4's `filename`).
    Triangle {
        vertices: [Vec3; 3],
        radiance: Vec3,
        two_sided: bool,
        image: Option<Arc<ImageOnTriangle>>,
    },
    /// A diffuse area light on a disk or annulus (pbrt-v4's `diffuse` area
    /// light on `disk`), emitting on the side of its normal, or both.
    Disk {
        disk: Disk,
        radiance: Vec3,
        two_sided: bool,
        /// Read at the disk's own texture coordinates (`Disk::uv_dpdu`).
        image: Option<Arc<EmissionImage>>,
    },
    /// pbrt-v4's `spot`: a point light at `position` whose intensity towards
    /// a direction at angle theta from the axis `direction` (unit) is
    /// `intensity * smoothstep(cos theta, cos_falloff_end, cos_falloff_start)`:
    /// full inside the falloff start, none outside the cone.
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        cos_falloff_start: f32,
        cos_falloff_end: f32,
    },
    /// Parallel light travelling along `direction` (unit) from infinitely far
    /// away; `radiance` is pbrt-v4's `L` times `scale`, the irradiance on a
    /// surface facing it. `world` is the scene's bounding sphere.
    Distant {
        direction: Vec3,
        radiance: Vec3,
        world: Sphere,
    },
    /// Radiance arriving from every direction: `radiance` where there is no
    /// map, otherwise the map's texel times `radiance` (the map's scale per
    /// channel). `to_world` turns the map's frame into the world's (an
    /// orthogonal matrix); `world` is the scene's bounding sphere. With a
    /// `portal` the light arrives only through it (pbrt-v4's
    /// `PortalImageInfiniteLight`), from the map resampled over the portal.
    Infinite {
        radiance: Vec3,
        map: Option<Arc<EnvMap>>,
        to_world: Mat3,
        world: Sphere,
        portal: Option<Arc<Portal>>,
    },
    /// pbrt-v4's `goniometric`: a point light whose intensity towards a
    /// direction is `intensity` times a grey equal-area image (`map`, an
    /// octahedral map with equal channels) of directions in the light's
    /// frame; `to_light` (orthogonal) turns world directions into that frame.
    Goniometric {
        position: Vec3,
        intensity: Vec3,
        to_light: Mat3,
        map: Arc<EnvMap>,
    },
    /// pbrt-v4's `projection`: a point light casting `projector`'s image
    /// through a frustum about the light frame's +z, times `intensity`;
    /// `to_light` (orthogonal) turns world directions into that frame.
    Projection {
        position: Vec3,
        intensity: Vec3,
        to_light: Mat3,
        projector: Arc<Projector>,
    },
}

/// The most a light may emit (power, radiance or intensity, per channel):
/// far beyond any scene's, and far enough below f32's range that the light
/// sample weights built on it stay finite.
pub const MAX_EMISSION: f32 = 1e15;

/// The bounding sphere of a light before `Scene::build` has given it the scene's.
const NO_WORLD: Sphere = Sphere {
    centre: Vec3::ZERO,
    radius: 0.0,
};

/// One sample of the light arriving at a point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction towards the light.
    pub wi: Vec3,
    /// Distance to the sampled point on the light.
    pub dist: f32,
    /// Incident radiance divided by the solid-angle pdf (for a point light,
    /// the irradiance at normal incidence).
    pub weight: Vec3,
    /// The solid-angle density of `wi` (0 for a delta light): what
    /// `pdf_li_hit` would say at the sampled point, without computing it
    /// again for multiple importance sampling.
    pub pdf: f32,
}

/// The sides of a sphere light that emit: pbrt-v4's sphere emits outwards,
/// inwards under `ReverseOrientation`, and both ways when two-sided.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Emits {
    #[default]
    Outwards,
    Inwards,
    Both,
}

impl Emits {
    /// How many sides emit.
    pub fn sides(self) -> f32 {
        if self == Emits::Both {
            2.0
        } else {
            1.0
        }
    }

    /// Whether the side seen from a point inside (else outside) emits.
    pub fn seen_from(self, inside: bool) -> bool {
        match self {
            Emits::Outwards => !inside,
            Emits::Inwards => inside,
            Emits::Both => true,
        }
    }
}

/// One particle leaving a light (`Light::sample_le_flux`).
#[derive(Clone, Copy, Debug)]
pub struct LeSample {
    pub ray: Ray,
    /// The surface normal at the ray's origin for area lights; the ray's
    /// direction for distant and infinite lights (the disk it leaves faces
    /// it); zero for point and spot lights.
    pub n: Vec3,
    /// The particle's flux, Le cos / (pdf_pos pdf_dir): its expectation is
    /// `power()`. It equals `power()` for every light but an infinite light
    /// with a map, whose directions follow the map's luminance (so the
    /// flux's luminance is constant and its colour is the texel's).
    pub flux: Vec3,
}

impl Light {
    /// A spot light after pbrt-v4: full `intensity` within `cone_angle -
    /// cone_delta` degrees of `direction`, falling off smoothly to zero at
    /// `cone_angle` degrees.
    pub fn spot(position: Vec3, direction: Vec3, intensity: Vec3, cone_angle: f32, cone_delta: f32) -> Light {
        Light::Spot {
            position,
            direction: direction.normalize(),
            intensity,
            cos_falloff_start: (cone_angle - cone_delta).to_radians().cos(),
            cos_falloff_end: cone_angle.to_radians().cos(),
        }
    }

    /// A distant light: light travelling along `direction` with irradiance
    /// `radiance` on a surface facing it.
    pub fn distant(direction: Vec3, radiance: Vec3) -> Light {
        Light::Distant {
            direction: direction.normalize(),
            radiance,
            world: NO_WORLD,
        }
    }

    /// An infinite light: constant `radiance`, or `map` scaled by it, turned
    /// into the world by `to_world` (a rotation, or any orthogonal matrix).
    pub fn infinite(radiance: Vec3, map: Option<Arc<EnvMap>>, to_world: Mat3) -> Light {
        Light::Infinite {
            radiance,
            map,
            to_world,
            world: NO_WORLD,
            portal: None,
        }
    }

    /// An infinite light whose light enters only through `portal` (built
    /// from the same map and turn).
    pub fn infinite_through(radiance: Vec3, map: Option<Arc<EnvMap>>, to_world: Mat3, portal: Portal) -> Light {
        Light::Infinite {
            radiance,
            map,
            to_world,
            world: NO_WORLD,
            portal: Some(Arc::new(portal)),
        }
    }

    /// Total emitted power. For distant and infinite lights it is the power
    /// that crosses the scene's bounding sphere (pbrt-v4's `Phi`), zero until
    /// `set_scene_bounds`.
    pub fn power(&self) -> Vec3 {
        match self {
            Light::Sphere { power, image, .. } => *power * image.as_ref().map_or(Vec3::ONE, |t| t.image.mean()),
            Light::Point { power, .. } => *power,
            Light::Triangle {
                vertices,
                radiance,
                two_sided,
                image,
            } => {
                // With an image, its mean over the whole image, as pbrt-v4's
                // `Phi` takes it: the triangle may cover only part of it.
                let sides = if *two_sided { 2.0 } else { 1.0 };
                let texels = image.as_ref().map_or(Vec3::ONE, |t| t.image.mean());
                *radiance * texels * (PI * triangle_area(vertices) * sides)
            }
            Light::Disk {
                disk,
                radiance,
                two_sided,
                image,
            } => {
                let sides = if *two_sided { 2.0 } else { 1.0 };
                let texels = image.as_ref().map_or(Vec3::ONE, |im| im.mean());
                *radiance * texels * (PI * disk.area() * sides)
            }
            Light::Spot {
                intensity,
                cos_falloff_start: cs,
                cos_falloff_end: ce,
                ..
            } => *intensity * (2.0 * PI * ((1.0 - cs) + (cs - ce) / 2.0)),
            Light::Distant { radiance, world, .. } => *radiance * (PI * world.radius * world.radius),
            Light::Goniometric { intensity, map, .. } => *intensity * map.integral(),
            Light::Projection {
                intensity, projector, ..
            } => *intensity * projector.power(),
            Light::Infinite {
                radiance,
                portal: Some(p),
                ..
            } => *radiance * p.flux(),
            Light::Infinite {
                radiance, map, world, ..
            } => {
                let integral = map.as_ref().map_or(Vec3::splat(4.0 * PI), |m| m.integral());
                *radiance * integral * (PI * world.radius * world.radius)
            }
        }
    }

    /// Gives a distant or infinite light the scene's bounding sphere (its
    /// photons leave a disk of that radius; its power depends on it). Other
    /// lights ignore it.
    pub fn set_scene_bounds(&mut self, bounds: Sphere) {
        match self {
            Light::Distant { world, .. } | Light::Infinite { world, .. } => *world = bounds,
            _ => {}
        }
    }

    /// Point, spot and distant lights: a delta distribution in position or
    /// direction, which no BSDF-sampled ray finds (`pdf_li` is 0).
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point { .. }
                | Light::Spot { .. }
                | Light::Distant { .. }
                | Light::Goniometric { .. }
                | Light::Projection { .. }
        )
    }

    /// Infinite and distant lights: at infinity, no surface a ray can hit;
    /// their `sample_li` returns `dist = f32::INFINITY`.
    pub fn is_infinite(&self) -> bool {
        matches!(self, Light::Infinite { .. } | Light::Distant { .. })
    }

    /// Radiance reaching a ray from `o` that leaves the scene in direction
    /// `dir` (unit): non-zero only for infinite lights (and for one with a
    /// portal, only through the portal).
    pub fn le_escaped(&self, o: Vec3, dir: Vec3) -> Vec3 {
        match self {
            Light::Infinite {
                radiance,
                portal: Some(p),
                ..
            } => *radiance * p.le(o, dir),
            Light::Infinite {
                radiance,
                map: Some(m),
                to_world,
                ..
            } => *radiance * m.le((to_world.transpose() * dir).normalize()),
            Light::Infinite { radiance, .. } => *radiance,
            _ => Vec3::ZERO,
        }
    }

    /// The solid-angle density with which `sample_li` at `p` returns `dir`
    /// (unit) for a light at infinity: the weight of an escaped ray in
    /// multiple importance sampling. Zero for every other light (and for a
    /// distant light, a delta).
    pub fn pdf_li_escaped(&self, p: Vec3, dir: Vec3) -> f32 {
        match self {
            Light::Infinite { portal: Some(q), .. } => q.pdf_li(p, dir),
            Light::Infinite {
                map: Some(m), to_world, ..
            } => m.pdf((to_world.transpose() * dir).normalize()),
            Light::Infinite { .. } => 1.0 / (4.0 * PI),
            _ => 0.0,
        }
    }

    /// A spot, goniometric or projection light's intensity towards `w`
    /// (unit); zero for other lights.
    pub fn intensity(&self, w: Vec3) -> Vec3 {
        match self {
            Light::Spot {
                direction,
                intensity,
                cos_falloff_start,
                cos_falloff_end,
                ..
            } => *intensity * smoothstep(w.dot(*direction), *cos_falloff_end, *cos_falloff_start),
            Light::Goniometric {
                intensity,
                to_light,
                map,
                ..
            } => *intensity * map.le((*to_light * w).normalize()),
            Light::Projection {
                intensity,
                to_light,
                projector,
                ..
            } => *intensity * projector.intensity((*to_light * w).normalize()),
            _ => Vec3::ZERO,
        }
    }

    /// Where the light is: its centre (a triangle's centroid); for distant
    /// and infinite lights, the centre of the scene's bounding sphere.
    pub fn position(&self) -> Vec3 {
        match self {
            Light::Sphere { sphere, .. } => sphere.centre,
            Light::Point { position, .. }
            | Light::Spot { position, .. }
            | Light::Goniometric { position, .. }
            | Light::Projection { position, .. } => *position,
            Light::Triangle { vertices: v, .. } => (v[0] + v[1] + v[2]) / 3.0,
            Light::Disk { disk, .. } => disk.centre,
            Light::Distant { world, .. } | Light::Infinite { world, .. } => world.centre,
        }
    }

    /// Emitted radiance of the surface (zero for point, spot, distant and
    /// infinite lights, which have none; see `le_escaped`).
    pub fn radiance(&self) -> Vec3 {
        match self {
            Light::Sphere {
                sphere, power, emits, ..
            } => *power / (PI * sphere.area() * emits.sides()),
            Light::Triangle { radiance, .. } | Light::Disk { radiance, .. } => *radiance,
            Light::Point { .. }
            | Light::Spot { .. }
            | Light::Distant { .. }
            | Light::Infinite { .. }
            | Light::Goniometric { .. }
            | Light::Projection { .. } => Vec3::ZERO,
        }
    }

    /// Radiance leaving the light's surface at `p` towards `w`, where its
    /// texture coordinates are `uv` (a one-sided light is dark from behind,
    /// a sphere from inside: seen through a glass that emits).
    pub fn le(&self, p: Vec3, w: Vec3, uv: Vec2) -> Vec3 {
        match self {
            // Leaving the inside (towards the centre) or the outside.
            Light::Sphere { sphere, emits, .. } if !emits.seen_from((p - sphere.centre).dot(w) < 0.0) => Vec3::ZERO,
            Light::Triangle {
                vertices,
                two_sided: false,
                ..
            } if triangle_normal(vertices).dot(w) <= 0.0 => Vec3::ZERO,
            Light::Triangle {
                radiance,
                image: Some(t),
                ..
            } => *radiance * t.image.lookup(uv),
            Light::Disk {
                disk, two_sided: false, ..
            } if disk.normal.dot(w) <= 0.0 => Vec3::ZERO,
            Light::Disk {
                radiance,
                image: Some(im),
                ..
            } => *radiance * im.lookup(uv),
            Light::Sphere { image: Some(t), .. } => self.radiance() * t.image.lookup(uv),
            _ => self.radiance(),
        }
    }

    /// The kind of light, as `info` names it.
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Sphere { .. } => "sphere",
            Light::Point { .. } => "point",
            Light::Triangle { .. } => "triangle",
            Light::Disk { .. } => "disk",
            Light::Spot { .. } => "spot",
            Light::Goniometric { .. } => "goniometric",
            Light::Projection { .. } => "projection",
            Light::Distant { .. } => "distant",
            Light::Infinite { .. } => "infinite",
        }
    }

    /// Why the light cannot be rendered once its emission is multiplied by
    /// `k`, if it cannot: one line, for the user who wrote it.
    pub fn check(&self, k: f32) -> Result<(), String> {
        let kind = self.kind();
        if !self.position().is_finite() {
            return Err(format!("{kind} light: its position is not finite"));
        }
        if let Light::Sphere { sphere, .. } = self {
            if !(sphere.radius > 0.0 && sphere.radius.is_finite()) {
                return Err(format!("sphere light: radius {} must be finite and > 0", sphere.radius));
            }
        }
        let emission = match self {
            Light::Sphere { power, image, .. } => {
                let k = image.as_ref().map_or(1.0, |t| t.image.max());
                vec![("power", *power * k), ("radiance", self.radiance() * k)]
            }
            Light::Disk {
                radiance,
                image: Some(im),
                ..
            } => vec![("radiance", *radiance * im.max())],
            Light::Triangle {
                radiance,
                image: Some(t),
                ..
            } => vec![("radiance", *radiance * t.image.max())],
            Light::Point { power, .. } => vec![("power", *power)],
            Light::Triangle { radiance, .. }
            | Light::Disk { radiance, .. }
            | Light::Distant { radiance, .. }
            | Light::Infinite { radiance, .. } => vec![("radiance", *radiance)],
            Light::Spot { intensity, .. }
            | Light::Goniometric { intensity, .. }
            | Light::Projection { intensity, .. } => vec![("intensity", *intensity)],
        };
        for (what, v) in emission {
            let v = v * k;
            if v.is_nan() || !v.max_element().is_finite() || v.max_element() > MAX_EMISSION {
                let value = if v.is_nan() {
                    "not a number".into()
                } else {
                    format!("{:e}", v.max_element())
                };
                return Err(format!(
                    "{kind} light: its {what} is {value}, beyond the limit of {MAX_EMISSION:e} (a light too small for its power, or too large a scale?)"
                ));
            }
            if v.min_element() < 0.0 {
                return Err(format!("{kind} light: its {what} {v} must be >= 0"));
            }
        }
        Ok(())
    }

    /// Multiplies what the light emits by `k` (a camera's exposure).
    pub fn scale_emission(&mut self, k: f32) {
        match self {
            Light::Sphere { power, .. } | Light::Point { power, .. } => *power *= k,
            Light::Triangle { radiance, .. }
            | Light::Disk { radiance, .. }
            | Light::Distant { radiance, .. }
            | Light::Infinite { radiance, .. } => *radiance *= k,
            Light::Spot { intensity, .. }
            | Light::Goniometric { intensity, .. }
            | Light::Projection { intensity, .. } => *intensity *= k,
        }
    }

    /// Moves the light's centre to `to`, keeping its size, shape and power
    /// (distant and infinite lights stay where they are, at infinity).
    pub fn move_to(&mut self, to: Vec3) {
        let by = to - self.position();
        match self {
            Light::Sphere { sphere, .. } => sphere.centre = to,
            Light::Point { position, .. }
            | Light::Spot { position, .. }
            | Light::Goniometric { position, .. }
            | Light::Projection { position, .. } => *position = to,
            Light::Triangle { vertices, .. } => vertices.iter_mut().for_each(|v| *v += by),
            Light::Disk { disk, .. } => disk.centre = to,
            Light::Distant { .. } | Light::Infinite { .. } => {}
        }
    }

    /// Samples a direction towards the light from `p`: uniformly over the
    /// cone a sphere subtends (pbrt-v4 6.2.4: exact for a sphere, every
    /// sample lands on the visible cap), uniformly in area on a triangle,
    /// the one direction of point, spot and distant lights, and for an
    /// infinite light uniformly over the sphere or, with a map, in proportion
    /// to the map's luminance. Distant and infinite lights return
    /// `dist = f32::INFINITY`.
    // Inlined into each integrator's light sampling, as it was when it had
    // one caller (BENCHMARKS.md, "What media cost scenes without them").
    #[inline(always)]
    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        match self {
            Light::Spot { position, .. } | Light::Goniometric { position, .. } | Light::Projection { position, .. } => {
                let v = *position - p;
                let d2 = v.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let dist = d2.sqrt();
                let wi = v / dist;
                let weight = self.intensity(-wi) / d2;
                (weight != Vec3::ZERO).then_some(LightSample {
                    wi,
                    dist,
                    weight,
                    pdf: 0.0,
                })
            }
            Light::Distant {
                direction, radiance, ..
            } => Some(LightSample {
                wi: -*direction,
                dist: f32::INFINITY,
                weight: *radiance,
                pdf: 0.0,
            }),
            Light::Infinite {
                radiance,
                portal: Some(q),
                ..
            } => {
                let (wi, le, pdf) = q.sample_li(p, u)?;
                let weight = *radiance * le / pdf;
                (weight != Vec3::ZERO && weight.is_finite()).then_some(LightSample {
                    wi,
                    dist: f32::INFINITY,
                    weight,
                    pdf,
                })
            }
            Light::Infinite {
                radiance, map: None, ..
            } => Some(LightSample {
                wi: uniform_sphere(u),
                dist: f32::INFINITY,
                weight: *radiance * (4.0 * PI),
                pdf: 1.0 / (4.0 * PI),
            }),
            Light::Infinite {
                radiance,
                map: Some(m),
                to_world,
                ..
            } => {
                let (wl, le, pdf) = m.sample(u)?;
                let weight = *radiance * le / pdf;
                (weight != Vec3::ZERO && weight.is_finite()).then(|| {
                    let wi = (*to_world * wl).normalize();
                    LightSample {
                        wi,
                        dist: f32::INFINITY,
                        weight,
                        pdf: self.pdf_li_escaped(p, wi),
                    }
                })
            }
            Light::Point { position, power } => {
                let v = *position - p;
                let d2 = v.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let dist = d2.sqrt();
                Some(LightSample {
                    wi: v / dist,
                    dist,
                    weight: *power / (4.0 * PI * d2),
                    pdf: 0.0,
                })
            }
            Light::Sphere {
                sphere, image, emits, ..
            } => {
                let v = sphere.centre - p;
                let dc2 = v.length_squared();
                let r2 = sphere.radius * sphere.radius;
                let inside = counts_as_inside(sphere, p);
                if !emits.seen_from(inside) {
                    return None;
                }
                if inside {
                    // All of the inside is in view: a point uniform in area.
                    let n = uniform_sphere(u);
                    let q = sphere.centre + n * sphere.radius;
                    let d = q - p;
                    let dist = d.length();
                    let wi = d / dist;
                    let cos_l = n.dot(wi);
                    if !(dist > 0.0 && cos_l > 0.0) {
                        return None;
                    }
                    let pdf = dist * dist / (cos_l * sphere.area());
                    let radiance = match image {
                        Some(t) => self.radiance() * t.at_normal(n),
                        None => self.radiance(),
                    };
                    return Some(LightSample {
                        wi,
                        dist,
                        weight: radiance / pdf,
                        pdf,
                    });
                }
                let dc = dc2.sqrt();
                let axis = v / dc;
                let sin2_max = r2 / dc2;
                let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
                // 1 - cos_max without cancellation for small, distant lights.
                let one_minus_cos_max = sin2_max / (1.0 + cos_max);
                let wi = to_world(uniform_cone(u, one_minus_cos_max), axis).normalize();
                // Distance to the near side of the sphere along wi.
                let b = wi.dot(v);
                let disc = r2 - (v - wi * b).length_squared();
                let dist = if disc > 0.0 {
                    b - disc.sqrt()
                } else {
                    (dc2 - r2).max(0.0).sqrt()
                };
                let solid_angle = 2.0 * PI * one_minus_cos_max;
                let radiance = match image {
                    // The point seen along wi, on the near side.
                    Some(t) => self.radiance() * t.at_normal(((p + wi * dist) - sphere.centre) / sphere.radius),
                    None => self.radiance(),
                };
                Some(LightSample {
                    wi,
                    dist,
                    weight: radiance * solid_angle,
                    pdf: 1.0 / solid_angle,
                })
            }
            Light::Disk {
                disk,
                radiance,
                two_sided,
                image,
            } => {
                let q = disk_area_point(disk, u);
                let d = q - p;
                let d2 = d.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let dist = d2.sqrt();
                let wi = d / dist;
                let cos_l = -disk.normal.dot(wi);
                let cos_l = if *two_sided { cos_l.abs() } else { cos_l };
                if cos_l <= 0.0 {
                    return None;
                }
                let radiance = match image {
                    Some(im) => *radiance * im.lookup(disk.uv_dpdu(q).0),
                    None => *radiance,
                };
                Some(LightSample {
                    wi,
                    dist,
                    weight: radiance * (cos_l * disk.area() / d2),
                    pdf: d2 / (cos_l * disk.area()),
                })
            }
            Light::Triangle {
                vertices: v,
                radiance,
                two_sided,
                image,
            } => {
                let (normal, area) = triangle_normal_area(v);
                let s = triangle_point_seen(v, (normal, area), *two_sided, p, u)?;
                let radiance = match image {
                    Some(t) => {
                        let (b0, b1) = uniform_triangle_barycentric(u);
                        *radiance * t.at_barycentric(b0, b1)
                    }
                    None => *radiance,
                };
                Some(LightSample {
                    wi: s.wi,
                    dist: s.dist,
                    weight: radiance * s.to_solid_angle,
                    pdf: s.pdf,
                })
            }
        }
    }

    /// `pdf_li` for a direction known to reach the light at `q` (a ray from
    /// `p` hit it there): no intersection test that could disagree with the
    /// one that found the hit near an edge or silhouette.
    pub fn pdf_li_hit(&self, p: Vec3, wi: Vec3, q: Vec3) -> f32 {
        match self {
            Light::Point { .. }
            | Light::Spot { .. }
            | Light::Distant { .. }
            | Light::Goniometric { .. }
            | Light::Projection { .. } => 0.0,
            Light::Infinite { .. } => self.pdf_li_escaped(p, wi),
            Light::Sphere { sphere, emits, .. } => {
                let dc2 = (sphere.centre - p).length_squared();
                let r2 = sphere.radius * sphere.radius;
                let inside = counts_as_inside(sphere, p);
                if !emits.seen_from(inside) {
                    return 0.0;
                }
                if inside {
                    return inside_sphere_pdf(sphere, p, wi, q);
                }
                let sin2_max = r2 / dc2;
                let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
                1.0 / (2.0 * PI * (sin2_max / (1.0 + cos_max)))
            }
            Light::Disk { disk, two_sided, .. } => {
                let cos_l = -disk.normal.dot(wi);
                let cos_l = if *two_sided { cos_l.abs() } else { cos_l };
                if cos_l <= 0.0 {
                    return 0.0;
                }
                (q - p).length_squared() / (cos_l * disk.area())
            }
            Light::Triangle {
                vertices: v, two_sided, ..
            } => {
                let (normal, area) = triangle_normal_area(v);
                let cos_l = -normal.dot(wi);
                let cos_l = if *two_sided { cos_l.abs() } else { cos_l };
                if cos_l <= 0.0 || area == 0.0 {
                    return 0.0;
                }
                (q - p).length_squared() / (cos_l * area)
            }
        }
    }

    /// Solid-angle density with which `sample_li` at `p` picks direction `wi`
    /// (zero where it never does; a delta light's, point, spot or distant,
    /// is reported as 0).
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        match self {
            Light::Point { .. }
            | Light::Spot { .. }
            | Light::Distant { .. }
            | Light::Goniometric { .. }
            | Light::Projection { .. } => 0.0,
            Light::Infinite { .. } => self.pdf_li_escaped(p, wi),
            Light::Sphere { sphere, emits, .. } => {
                let v = sphere.centre - p;
                let dc2 = v.length_squared();
                let r2 = sphere.radius * sphere.radius;
                let inside = counts_as_inside(sphere, p);
                if !emits.seen_from(inside) {
                    return 0.0;
                }
                if inside {
                    // Where the ray leaves the sphere.
                    let b = wi.dot(v);
                    let t = b + (r2 - (dc2 - b * b)).max(0.0).sqrt();
                    return inside_sphere_pdf(sphere, p, wi, p + wi * t);
                }
                let sin2_max = r2 / dc2;
                let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
                if wi.dot(v) < cos_max * dc2.sqrt() {
                    return 0.0;
                }
                1.0 / (2.0 * PI * (sin2_max / (1.0 + cos_max)))
            }
            Light::Disk { disk, two_sided, .. } => {
                let Some(t) = disk.intersect(&Ray::new(p, wi), 0.0, f32::INFINITY) else {
                    return 0.0;
                };
                let cos_l = -disk.normal.dot(wi);
                let cos_l = if *two_sided { cos_l.abs() } else { cos_l };
                if cos_l <= 0.0 {
                    return 0.0;
                }
                t * t / (cos_l * disk.area())
            }
            Light::Triangle {
                vertices: v, two_sided, ..
            } => {
                let tri = crate::geometry::Triangle::new(v[0], v[1], v[2]);
                let Some(t) = tri.intersect_mt(&Ray::new(p, wi), 0.0, f32::INFINITY).map(|h| h.t) else {
                    return 0.0;
                };
                let cos_l = -triangle_normal(v).dot(wi);
                let cos_l = if *two_sided { cos_l.abs() } else { cos_l };
                let area = triangle_area(v);
                if cos_l <= 0.0 || area == 0.0 {
                    return 0.0;
                }
                t * t / (cos_l * area)
            }
        }
    }

    /// Emits a particle: a ray leaving the light, distributed as its emission
    /// (uniform over a sphere's surface, cosine-weighted outward; uniform in
    /// direction for a point light; a spot light's directions in proportion
    /// to its intensity; for distant and infinite lights, uniform over a disk
    /// of the scene's bounding sphere facing the direction of travel), and
    /// the normal described at `LeSample::n`. Each particle carries Phi / N,
    /// except from an infinite light with a map, whose directions follow the
    /// map's luminance: there `sample_le_flux` gives each particle's flux.
    pub fn sample_le(&self, u1: Vec2, u2: Vec2) -> (Ray, Vec3) {
        match self {
            Light::Spot {
                position,
                direction,
                cos_falloff_start: cs,
                cos_falloff_end: ce,
                ..
            } => {
                // pbrt-v4: the inner cone or the falloff ring, by their shares of power.
                let (inner, ring) = (1.0 - cs, (cs - ce) / 2.0);
                let local = if u2.x * (inner + ring) < inner || ring <= 0.0 {
                    uniform_cone(u1, inner)
                } else {
                    let cos_t = sample_smoothstep(u1.x, *ce, *cs);
                    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                    let (sin_p, cos_p) = (2.0 * PI * u1.y).sin_cos();
                    Vec3::new(sin_t * cos_p, sin_t * sin_p, cos_t)
                };
                (Ray::new(*position, to_world(local, *direction).normalize()), Vec3::ZERO)
            }
            Light::Distant { direction, world, .. } => {
                let d = *direction;
                (Ray::new(disk_point(world, d, u1) - d * world.radius, d), d)
            }
            Light::Infinite {
                portal: Some(p), world, ..
            } => match p.sample_le(u1, u2, behind_portal(p, world)) {
                Some((ray, _)) => (ray, ray.d),
                None => (Ray::new(world.centre, Vec3::Z), Vec3::Z),
            },
            Light::Infinite {
                map, to_world, world, ..
            } => {
                // wi points towards the light; the photon travels along -wi.
                let wi = match map {
                    None => uniform_sphere(u1),
                    Some(m) => match m.sample(u1) {
                        Some((wl, ..)) => (*to_world * wl).normalize(),
                        None => Vec3::Z,
                    },
                };
                (Ray::new(disk_point(world, -wi, u2) + wi * world.radius, -wi), -wi)
            }
            Light::Point { position, .. } => (Ray::new(*position, uniform_sphere(u1)), Vec3::ZERO),
            Light::Goniometric {
                position,
                to_light,
                map,
                ..
            } => {
                // In proportion to the image: each particle carries the power.
                let wl = map.sample(u1).map_or(Vec3::Z, |(w, ..)| w);
                (Ray::new(*position, (to_light.transpose() * wl).normalize()), Vec3::ZERO)
            }
            Light::Projection {
                position,
                to_light,
                projector,
                ..
            } => {
                let wl = projector.sample(u1).map_or(Vec3::Z, |(w, _)| w);
                (Ray::new(*position, (to_light.transpose() * wl).normalize()), Vec3::ZERO)
            }
            Light::Sphere { sphere, emits, .. } => {
                let n = uniform_sphere(u1);
                let mut u2 = u2;
                // The side: a two-sided sphere's as a two-sided disk's.
                let inwards = match emits {
                    Emits::Outwards => false,
                    Emits::Inwards => true,
                    Emits::Both => {
                        let inwards = u2.x >= 0.5;
                        u2.x = (if inwards { u2.x * 2.0 - 1.0 } else { u2.x * 2.0 }).min(1.0 - f32::EPSILON);
                        inwards
                    }
                };
                let (n, step) = if inwards { (-n, 1.0 - 1e-4) } else { (n, 1.0 + 1e-4) };
                let d = to_world(cosine_hemisphere(u2), n).normalize();
                let o = sphere.centre - n * (sphere.radius * if inwards { step } else { -step });
                (Ray::new(o, d), n)
            }
            Light::Disk { disk, two_sided, .. } => emit_cosine(disk_area_point(disk, u1), disk.normal, *two_sided, u2),
            Light::Triangle {
                vertices: v, two_sided, ..
            } => emit_cosine(uniform_triangle(v, u1), triangle_normal(v), *two_sided, u2),
        }
    }

    /// `sample_le` with the particle's flux (see `LeSample::flux`): photon
    /// tracing that starts N particles from this light gives each flux / N.
    pub fn sample_le_flux(&self, u1: Vec2, u2: Vec2) -> LeSample {
        if let Light::Infinite {
            radiance,
            portal: Some(p),
            world,
            ..
        } = self
        {
            return match p.sample_le(u1, u2, behind_portal(p, world)) {
                Some((ray, flux)) => LeSample {
                    ray,
                    n: ray.d,
                    flux: *radiance * flux,
                },
                None => LeSample {
                    ray: Ray::new(world.centre, Vec3::Z),
                    n: Vec3::Z,
                    flux: Vec3::ZERO,
                },
            };
        }
        let (ray, n) = self.sample_le(u1, u2);
        let flux = match self {
            Light::Infinite {
                radiance,
                map: Some(m),
                to_world,
                world,
                ..
            } => {
                let wl = (to_world.transpose() * -ray.d).normalize();
                let pdf = m.pdf(wl);
                if pdf > 0.0 {
                    *radiance * m.le(wl) * (PI * world.radius * world.radius) / pdf
                } else {
                    Vec3::ZERO
                }
            }
            Light::Projection {
                intensity,
                to_light,
                projector,
                ..
            } => {
                // Drawn by the texels' mean, not in proportion to each
                // colour: the flux follows the direction's own intensity.
                let wl = (*to_light * ray.d).normalize();
                let pdf = projector.pdf(wl);
                if pdf > 0.0 {
                    *intensity * projector.intensity(wl) / pdf
                } else {
                    Vec3::ZERO
                }
            }
            Light::Sphere {
                sphere,
                power,
                image: Some(t),
                ..
            } => {
                // The image is read at the outward normal, whichever side emits.
                let outward = if n.dot(ray.o - sphere.centre) < 0.0 { -n } else { n };
                *power * t.at_normal(outward)
            }
            Light::Disk {
                disk,
                radiance,
                two_sided,
                image: Some(im),
            } => {
                let sides = if *two_sided { 2.0 } else { 1.0 };
                let q = disk_area_point(disk, u1);
                *radiance * im.lookup(disk.uv_dpdu(q).0) * (PI * disk.area() * sides)
            }
            Light::Triangle {
                vertices,
                radiance,
                two_sided,
                image: Some(t),
            } => {
                // The point `sample_le` drew from u1, uniform in area.
                let (b0, b1) = uniform_triangle_barycentric(u1);
                let sides = if *two_sided { 2.0 } else { 1.0 };
                *radiance * t.at_barycentric(b0, b1) * (PI * triangle_area(vertices) * sides)
            }
            _ => self.power(),
        };
        LeSample { ray, n, flux }
    }

    /// The densities with which `sample_le` emits `ray` from a point with
    /// normal `n` (as it returned them): (area density of the origin,
    /// solid-angle density of the direction), as pbrt-v4's `PDF_Le`. A delta
    /// part (the position of point and spot lights, the direction of distant
    /// lights) is reported as 0.
    pub fn pdf_le(&self, ray: &Ray, n: Vec3) -> (f32, f32) {
        let disk = |world: &Sphere| {
            let a = PI * world.radius * world.radius;
            if a > 0.0 {
                1.0 / a
            } else {
                0.0
            }
        };
        match self {
            Light::Point { .. } => (0.0, 1.0 / (4.0 * PI)),
            Light::Goniometric { to_light, map, .. } => (0.0, map.pdf((*to_light * ray.d).normalize())),
            Light::Projection {
                to_light, projector, ..
            } => (0.0, projector.pdf((*to_light * ray.d).normalize())),
            Light::Sphere { sphere, emits, .. } => (1.0 / sphere.area(), n.dot(ray.d).max(0.0) / (PI * emits.sides())),
            Light::Disk { disk, two_sided, .. } => {
                let cos = n.dot(ray.d).max(0.0);
                let side = if *two_sided { 0.5 } else { 1.0 };
                (1.0 / disk.area(), side * cos / PI)
            }
            Light::Triangle {
                vertices, two_sided, ..
            } => {
                let area = triangle_area(vertices);
                let cos = n.dot(ray.d).max(0.0);
                let side = if *two_sided { 0.5 } else { 1.0 };
                (if area > 0.0 { 1.0 / area } else { 0.0 }, side * cos / PI)
            }
            Light::Spot {
                direction,
                cos_falloff_start: cs,
                cos_falloff_end: ce,
                ..
            } => {
                let (inner, ring) = (1.0 - cs, (cs - ce) / 2.0);
                let cos_t = ray.d.dot(*direction);
                let pdf = if cos_t >= *cs {
                    if inner > 0.0 {
                        1.0 / (2.0 * PI * (inner + ring))
                    } else {
                        0.0
                    }
                } else if cos_t > *ce {
                    // The ring's share times the smoothstep density in cos theta, over 2 pi.
                    ring / (inner + ring) * 2.0 * smoothstep(cos_t, *ce, *cs) / (cs - ce) / (2.0 * PI)
                } else {
                    0.0
                };
                (0.0, pdf)
            }
            Light::Distant { world, .. } => (disk(world), 0.0),
            Light::Infinite { portal: Some(p), .. } => p.pdf_le(ray),
            Light::Infinite { world, .. } => (disk(world), self.pdf_li_escaped(ray.o, -ray.d)),
        }
    }
}

/// How far behind a portal its particles start: outside the scene's
/// bounding sphere, so that whatever stands outside the window shadows them.
fn behind_portal(p: &Portal, world: &Sphere) -> f32 {
    let reach = p
        .corners()
        .iter()
        .map(|c| (*c - world.centre).length())
        .fold(0.0, f32::max);
    2.0 * world.radius + reach + 1.0
}

/// A point uniform on the disk through `world`'s centre, of its radius,
/// perpendicular to `axis` (pbrt-v4's distant and infinite light emission).
fn disk_point(world: &Sphere, axis: Vec3, u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let (s, t) = orthonormal_basis(axis);
    world.centre + (s * d.x + t * d.y) * world.radius
}

/// 0 below `a`, 1 above `b`, 3x^2 - 2x^3 of x = (v - a) / (b - a) between;
/// a step at `a` when `a == b`.
pub fn smoothstep(v: f32, a: f32, b: f32) -> f32 {
    if a == b {
        return if v < a { 0.0 } else { 1.0 };
    }
    let t = ((v - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A particle leaving a flat emitter at `q` with normal `n`, cosine-weighted
/// about the side it leaves from, and that side's normal. Both sides of a
/// two-sided emitter emit alike: `u2.x` picks one and is reused.
fn emit_cosine(q: Vec3, n: Vec3, two_sided: bool, mut u2: Vec2) -> (Ray, Vec3) {
    let mut n = n;
    if two_sided {
        if u2.x < 0.5 {
            u2.x *= 2.0;
        } else {
            u2.x = u2.x * 2.0 - 1.0;
            n = -n;
        }
        u2.x = u2.x.min(1.0 - f32::EPSILON);
    }
    let d = to_world(cosine_hemisphere(u2), n).normalize();
    (Ray::new(crate::math::offset_origin(q, n, d), d), n)
}

/// Whether `p` is inside `sphere` for its light: a point on the surface
/// counts as inside, whichever side rounding put it on, as pbrt-v4 counts
/// it (by its origin offset towards the centre). A sphere light that
/// reflects samples itself from its own surface: from inside, where the
/// whole inside is in view (an integrating sphere), and never by a cone
/// that shrinks to the point itself.
fn counts_as_inside(sphere: &Sphere, p: Vec3) -> bool {
    let slack = 1e-4 * sphere.radius + 8.0 * f32::EPSILON * (sphere.centre.abs().max_element() + sphere.radius);
    (p - sphere.centre).length() <= sphere.radius + slack
}

/// The solid-angle density at `p`, inside `sphere`, of the point `q` on it
/// along `wi` when points are drawn uniformly over its area.
fn inside_sphere_pdf(sphere: &Sphere, p: Vec3, wi: Vec3, q: Vec3) -> f32 {
    let cos_l = ((q - sphere.centre) / sphere.radius).dot(wi);
    if cos_l <= 0.0 {
        return 0.0;
    }
    (q - p).length_squared() / (cos_l * sphere.area())
}

/// A point uniformly distributed in area over a disk or annulus.
fn disk_area_point(disk: &Disk, u: Vec2) -> Vec3 {
    let (r0, r1) = (disk.inner_radius, disk.radius);
    let r = (r0 * r0 + u.x * (r1 * r1 - r0 * r0)).sqrt();
    let phi = std::f32::consts::TAU * u.y;
    disk.centre + (disk.axes[0] * phi.cos() + disk.axes[1] * phi.sin()) * r
}

/// A point of a triangle light seen from a point: the unit direction to it,
/// its distance, the change from area to solid angle |cos| A / d^2, and the
/// density in solid angle (its reciprocal).
#[derive(Clone, Copy, Debug)]
pub struct TrianglePoint {
    pub wi: Vec3,
    pub dist: f32,
    pub to_solid_angle: f32,
    pub pdf: f32,
}

/// The point of triangle `v` (whose unit normal and area are `normal_area`,
/// as [`triangle_normal_area`] gives them) that `u` picks uniformly in area
/// (pbrt-v4 6.5.4), seen from `p`; `None` when `p` sees its back and it
/// emits only from its front, or when the triangle or the distance is zero.
#[inline(always)]
pub fn triangle_point_seen(
    v: &[Vec3; 3],
    (normal, area): (Vec3, f32),
    two_sided: bool,
    p: Vec3,
    u: Vec2,
) -> Option<TrianglePoint> {
    let q = uniform_triangle(v, u);
    let d = q - p;
    let d2 = d.length_squared();
    if d2 == 0.0 || area == 0.0 {
        return None;
    }
    let dist = d2.sqrt();
    let wi = d / dist;
    let cos_l = -normal.dot(wi);
    let cos_l = if two_sided { cos_l.abs() } else { cos_l };
    if cos_l <= 0.0 {
        return None;
    }
    Some(TrianglePoint {
        wi,
        dist,
        to_solid_angle: cos_l * area / d2,
        pdf: d2 / (cos_l * area),
    })
}

/// `triangle_normal` and `triangle_area` from one cross product and one
/// square root (light sampling needs both per sample), bit for bit the same.
pub fn triangle_normal_area(v: &[Vec3; 3]) -> (Vec3, f32) {
    let c = (v[1] - v[0]).cross(v[2] - v[0]);
    let len = c.length();
    let rcp = 1.0 / len;
    let n = if rcp.is_finite() && rcp > 0.0 {
        c * rcp
    } else {
        Vec3::ZERO
    };
    (n, 0.5 * len)
}

/// Unit normal (v1 - v0) x (v2 - v0) of a triangle (zero if degenerate).
pub fn triangle_normal(v: &[Vec3; 3]) -> Vec3 {
    (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero()
}

pub fn triangle_area(v: &[Vec3; 3]) -> f32 {
    0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length()
}

/// A light's image of `width` x `height` texels with negative components
/// made zero; an error when the size does not match (`what` names the
/// image) or a texel is not finite.
fn clamped_texels(what: &str, width: u32, height: u32, texels: Vec<Vec3>) -> Result<Vec<Vec3>, String> {
    if width == 0 || height == 0 || texels.len() as u64 != width as u64 * height as u64 {
        return Err(format!("{what} of {width}x{height} texels needs as many values"));
    }
    if let Some(i) = texels.iter().position(|t| !t.is_finite()) {
        return Err(format!(
            "texel ({}, {}) is not a finite number",
            i as u32 % width,
            i as u32 / width
        ));
    }
    Ok(texels.into_iter().map(|t| t.max(Vec3::ZERO)).collect())
}

/// A point uniformly distributed over the triangle (pbrt-v4's
/// `SampleUniformTriangle`, which keeps strata apart).
pub fn uniform_triangle(v: &[Vec3; 3], u: Vec2) -> Vec3 {
    let (b0, b1) = uniform_triangle_barycentric(u);
    v[0] * b0 + v[1] * b1 + v[2] * (1.0 - b0 - b1)
}

/// The barycentric coordinates (b0, b1) of `uniform_triangle`'s point.
#[inline(always)]
fn uniform_triangle_barycentric(u: Vec2) -> (f32, f32) {
    // The two cases as selects, each the same arithmetic on the same
    // numbers: which one applies is a coin toss a branch would mispredict
    // half the time.
    let lower = u.x < u.y;
    let half = if lower { u.x } else { u.y } / 2.0;
    let rest = if lower { u.y } else { u.x } - half;
    if lower {
        (half, rest)
    } else {
        (rest, half)
    }
}

#[cfg(test)]
mod tests;
