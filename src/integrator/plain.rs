//! The path tracer's loop for plain scenes: every surface Lambertian of one
//! reflectance, lights chosen by power.
//!
//! The same estimator as [`super::path::PathTracer`], drawing the same
//! numbers in the same order and doing the same arithmetic on them, so the
//! image is the general loop's bit for bit (the tests hold it to that). What
//! it leaves out is what such a scene never needs: the general loop builds a
//! [`crate::bsdf::Bsdf`] at every vertex (a large enum, chosen among a dozen
//! models and then dispatched on at every use), a hit's texture coordinates
//! and dp/du, ray differentials, and the checks for media, transmission and
//! regularization. On Bitterli's `cornell-box` that was a fifth of the
//! instructions and an eighth of the time (BENCHMARKS.md, "A path loop for
//! plain scenes"). Scenes of still triangles lit by triangle lights trace
//! these paths eight at a time ([`super::lanes`]).
//!
//! Plain: no participating media or subsurface scattering; every material
//! `Diffuse` with a constant reflectance; the light chosen by power (the
//! light tree, or choosing uniformly, takes the general loop). Any shape,
//! camera, light and sampler will do, as will motion and cut-outs: those go
//! through the scene's own queries.

use super::direct::{emitted_radiance, escaped_radiance, power_heuristic, shadow_ray_blocked};
use super::lanes::TriangleLight;
use super::path::{MAX_SURVIVAL, ROULETTE_DEPTH};
use super::{IntegratorKind, LightSampling, RadianceEstimator, RayStats, RenderSettings, Tile};
use crate::bsdf::diffuse::DiffuseBxdf;
use crate::bsdf::frame::Frame;
use crate::film::SplatBlock;
use crate::light::{LightContext, LightSamplerKind};
use crate::material::Material;
use crate::math::{offset_origin, Ray, Vec2, Vec3};
use crate::sampling::{cosine_hemisphere, Sampler};
use crate::scene::{Hit, Scene};
use std::f32::consts::FRAC_1_PI;
use std::sync::atomic::AtomicBool;

pub struct PlainPathTracer {
    max_depth: Option<u32>,
    /// Each material's reflectance, as its `DiffuseBxdf` holds it.
    reflectance: Vec<Vec3>,
    /// The scene's lights, when paths are traced in lanes
    /// ([`super::lanes`]): scenes of still triangles lit by triangles.
    lanes: Option<Vec<TriangleLight>>,
}

impl PlainPathTracer {
    /// The plain loop for path tracing `scene` with `settings`, when the
    /// scene is plain and the settings ask for what the general loop would
    /// do there by default (multiple importance sampling, no
    /// regularization); `None` otherwise. A photon guide (`guide_photons`)
    /// changes nothing here: no photon reaches a Lambertian surface through
    /// a glossy or specular one in a scene of Lambertian surfaces alone.
    pub fn for_scene(scene: &Scene, settings: &RenderSettings) -> Option<Self> {
        if settings.integrator != IntegratorKind::Path
            || settings.light_sampling != LightSampling::Mis
            || settings.regularize
            || scene.has_media()
            || scene.has_subsurface()
            || scene.chooses_by_tree()
            || scene.light_sampler() == LightSamplerKind::Uniform
        {
            return None;
        }
        let reflectance = scene
            .materials
            .iter()
            .map(|m| match m {
                // As `Material::bsdf` makes it: the texture's value clamped,
                // then the BxDF's own clamp.
                Material::Diffuse { reflectance } => reflectance
                    .as_constant()
                    .map(|r| DiffuseBxdf::new(r.clamp(Vec3::ZERO, Vec3::ONE)).r),
                _ => None,
            })
            .collect::<Option<Vec<_>>>()?;
        let lanes = scene
            .only_still_triangles()
            .then(|| super::lanes::triangle_lights(scene))
            .flatten();
        Some(PlainPathTracer {
            max_depth: settings.max_depth,
            reflectance,
            lanes,
        })
    }

    /// The same loop, a path at a time.
    pub fn one_at_a_time(self) -> Self {
        PlainPathTracer { lanes: None, ..self }
    }

    /// Each material's reflectance.
    pub fn reflectance(&self) -> &[Vec3] {
        &self.reflectance
    }

    /// The most bounces, if limited.
    pub fn max_depth(&self) -> Option<u32> {
        self.max_depth
    }

    /// Whether it traces paths in lanes.
    pub fn in_lanes(&self) -> bool {
        self.lanes.is_some()
    }
}

impl RadianceEstimator for PlainPathTracer {
    fn add_tile_samples(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        tile: &Tile,
        block: &mut SplatBlock,
        stats: &mut RayStats,
        cancel: &AtomicBool,
    ) -> bool {
        match &self.lanes {
            Some(lights) => super::lanes::Job {
                plain: self,
                lights,
                scene,
                settings,
            }
            .add_tile_samples(tile, block, stats, cancel),
            None => tile.add_samples(scene, settings, self, block, stats, cancel),
        }
    }

    fn li(&self, scene: &Scene, camera_ray: &Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Vec3 {
        let mut l = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        let mut ray = *camera_ray;
        let mut depth = 0;
        // Where the last bounce left from and its density (`None` for the
        // camera ray), for the MIS weight of emission a bounce finds.
        let mut from: Option<(LightContext, f32)> = None;
        loop {
            let Some(hit) = scene.intersect_bare(&ray) else {
                l += beta * escaped_radiance(scene, &ray, from);
                break;
            };
            if let Some(li) = hit.light {
                l += beta * emitted_radiance(scene, li as usize, &ray, &hit, from);
                if !scene.reflects(&hit) {
                    break;
                }
            }
            if self.max_depth.is_some_and(|d| depth >= d) {
                break;
            }
            let wo = -ray.d;
            depth += 1;
            let r = self.reflectance[hit.material as usize];
            if r == Vec3::ZERO {
                break;
            }
            // The shading normal on the viewer's side of the surface.
            let ns = if hit.ng.dot(wo) < 0.0 { -hit.ns } else { hit.ns };
            let frame = Frame::from_z(ns);
            // The general loop's requests: the light sample's 2D (its first
            // number also chooses the light), the lobe choice a Lambertian
            // BSDF skips, the BSDF sample's 2D.
            let u_light = sampler.next_2d();
            sampler.skip_1d();
            let u = sampler.next_2d();
            let wo_l = frame.to_local(wo);
            let f = r * FRAC_1_PI;
            let bs = (wo_l.z != 0.0)
                .then(|| {
                    let d = cosine_hemisphere(u);
                    let wi = if wo_l.z >= 0.0 { d } else { Vec3::new(d.x, d.y, -d.z) };
                    (wi, wi.z.abs() * FRAC_1_PI)
                })
                .filter(|&(wi, pdf)| pdf > 0.0 && pdf.is_finite() && wi.z != 0.0 && f != Vec3::ZERO);
            l += beta * direct(scene, &hit, wo, (wo_l, &frame), f, u_light, stats);
            let Some((wi_l, pdf)) = bs else {
                break;
            };
            let wi = frame.to_world(wi_l);
            // A reflection that crosses the geometric surface goes nowhere.
            if (wi.dot(hit.ng) > 0.0) != (wo.dot(hit.ng) > 0.0) {
                break;
            }
            beta *= f * (wi.dot(frame.z).abs() / pdf);
            if !beta.is_finite() || beta.max_element() <= 0.0 {
                break;
            }
            from = Some((LightContext::surface(hit.p, frame.z), pdf));
            if depth >= ROULETTE_DEPTH {
                let q = beta.max_element().min(MAX_SURVIVAL);
                if sampler.next_f32() >= q {
                    break;
                }
                beta /= q;
            }
            stats.other_rays += 1;
            ray = Ray::timed(offset_origin(hit.p, hit.ng, wi), wi, hit.time);
        }
        l
    }
}

/// Next-event estimation at a Lambertian vertex of value `f` (r / pi) seen
/// from `wo` (`wo_l` in the shading frame `frame`): one light chosen by
/// power with `u.x`, one point on it, weighed against BSDF sampling by the
/// power heuristic, as `direct::sample_direct_with` does.
#[inline(always)]
fn direct(
    scene: &Scene,
    hit: &Hit,
    wo: Vec3,
    (wo_l, frame): (Vec3, &Frame),
    f: Vec3,
    u: Vec2,
    stats: &mut RayStats,
) -> Vec3 {
    let Some((li, pmf, rest)) = scene.pick_light(u.x) else {
        return Vec3::ZERO;
    };
    let Some(ls) = scene.lights[li].sample_li(hit.p, Vec2::new(rest, u.y)) else {
        return Vec3::ZERO;
    };
    let light = (ls.wi, ls.weight, ls.pdf, pmf, scene.light_is_met(li));
    let Some(l) = lambert_light(hit.ng, wo, (wo_l, frame), f, light) else {
        return Vec3::ZERO;
    };
    if shadow_ray_blocked(scene, hit, &ls, li, stats) {
        return Vec3::ZERO;
    }
    l
}

/// What a Lambertian vertex of value `f` (r / pi), with geometric normal
/// `ng`, seen from `wo` (`wo_l` in the shading frame `frame`), reflects
/// towards the viewer of a light sample `(wi, weight, pdf, pmf, met)`: its
/// direction, radiance over its density, its density in solid angle, the
/// probability of the light's choice, and whether a ray can meet the light
/// (then the power heuristic weighs it against BSDF sampling).
/// `None` where the BSDF cannot scatter it so: reflection on the viewer's
/// side only, the geometric and shading normals agreeing.
#[inline(always)]
pub(super) fn lambert_light(
    ng: Vec3,
    wo: Vec3,
    (wo_l, frame): (Vec3, &Frame),
    f: Vec3,
    (wi, weight, pdf, pmf, met): (Vec3, Vec3, f32, f32, bool),
) -> Option<Vec3> {
    let geo_same = (wi.dot(ng) > 0.0) == (wo.dot(ng) > 0.0);
    let shade_same = (wi.dot(frame.z) > 0.0) == (wo.dot(frame.z) > 0.0);
    if !(geo_same && shade_same && wi.dot(ng) != 0.0) {
        return None;
    }
    // The BSDF's value and density towards the light, zero below the surface.
    let (f, pdf_bsdf) = if wo_l.z == 0.0 {
        (Vec3::ZERO, 0.0)
    } else {
        let wi_l = frame.to_local(wi);
        if wo_l.z * wi_l.z > 0.0 {
            (f, wi_l.z.abs() * FRAC_1_PI)
        } else {
            (Vec3::ZERO, 0.0)
        }
    };
    let w = if met { power_heuristic(pmf * pdf, pdf_bsdf) } else { 1.0 };
    Some(f * wi.dot(frame.z).abs() * weight * (w / pmf))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Film;
    use crate::integrator::analytic::{pbrt_desc, pbrt_quad};
    use crate::integrator::path::PathTracer;
    use crate::integrator::{render_tiles, Progress, SamplerKind};
    use crate::scene::SceneDesc;

    /// A room of Lambertian quads with vertex normals, lit by a one-sided
    /// quad, a two-sided triangle, a point light and a dim sky, and with a
    /// ball: every kind of light and shape the loop meets through the
    /// scene's own queries.
    fn room() -> SceneDesc {
        let quad = |p: &str, n: &str| pbrt_quad(p, Some(n));
        let mut text = String::from(
            "LookAt 0 1 3.5  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" 50\n\
             Film \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 20\nWorldBegin\n\
             LightSource \"infinite\" \"rgb L\" [ 0.05 0.06 0.08 ]\n\
             LightSource \"point\" \"point3 from\" [ 0.5 1.5 0.5 ] \"rgb I\" [ 0.4 0.3 0.2 ]\n\
             Material \"diffuse\" \"rgb reflectance\" [ 0.7 0.6 0.5 ]\n",
        );
        text += &quad("-1 0 -1  1 0 -1  1 0 1  -1 0 1", "0 1 0.1");
        text += &quad("-1 2 -1  -1 2 1  1 2 1  1 2 -1", "0 -1 0");
        text += "Material \"diffuse\" \"rgb reflectance\" [ 0.2 0.5 0.1 ]\n";
        text += &quad("-1 0 -1  -1 2 -1  1 2 -1  1 0 -1", "0.1 0 1");
        text += "Shape \"sphere\" \"float radius\" 0.3\n";
        text += "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 4 3 2 ]\nMaterial \"diffuse\" \"rgb reflectance\" [ 0 0 0 ]\n";
        text += &quad("-0.3 1.99 -0.3  -0.3 1.99 0.3  0.3 1.99 0.3  0.3 1.99 -0.3", "0 -1 0");
        text +=
            "AttributeEnd\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 1 2 3 ] \"bool twosided\" true\n";
        text += "Shape \"trianglemesh\" \"point3 P\" [ 0.9 0.2 -0.5  0.9 0.8 -0.5  0.9 0.5 0.3 ] \"integer indices\" [ 0 1 2 ]\n";
        text += "AttributeEnd\n";
        let mut desc = pbrt_desc(&text);
        desc.light_sampler = LightSamplerKind::Power;
        desc
    }

    fn films(scene: &Scene, settings: &RenderSettings) -> (Film, Film) {
        let general = PathTracer {
            max_depth: settings.max_depth,
            light_sampling: LightSampling::Mis,
            regularize: false,
            guide: None,
        };
        let plain = PlainPathTracer::for_scene(scene, settings).expect("a plain scene");
        let silent = Progress::silent();
        (
            render_tiles(scene, settings, &general, silent).0,
            render_tiles(scene, settings, &plain, silent).0,
        )
    }

    #[test]
    fn the_plain_loop_renders_the_general_loops_image_bit_for_bit() {
        let room = Scene::build(room()).unwrap();
        let mut cornell = crate::scene::builtin::cornell();
        (cornell.camera.width, cornell.camera.height) = (20, 20);
        let cornell = Scene::build(cornell).unwrap();
        for (scene, name) in [(&room, "room"), (&cornell, "cornell")] {
            for (sampler, max_depth) in [
                (SamplerKind::Sobol, None),
                (SamplerKind::ZSobol, Some(2)),
                (SamplerKind::Independent, None),
            ] {
                let settings = RenderSettings {
                    integrator: IntegratorKind::Path,
                    spp: 8,
                    max_depth,
                    sampler,
                    ..RenderSettings::default()
                };
                let (general, plain) = films(scene, &settings);
                let differ = (general.pixels.iter().zip(&plain.pixels))
                    .position(|(a, b)| a.to_array().map(f32::to_bits) != b.to_array().map(f32::to_bits));
                assert_eq!(
                    differ, None,
                    "{name}, {sampler:?}, max depth {max_depth:?}: first pixel that differs"
                );
                // Lit, and by more than the camera's direct view of a light.
                let lit = plain.pixels.iter().filter(|p| p.max_element() > 0.0).count();
                assert!(lit > plain.pixels.len() * 9 / 10, "{name}: {lit} pixels lit");
            }
        }
    }

    #[test]
    fn only_plain_scenes_and_default_settings_take_the_plain_loop() {
        let path = RenderSettings {
            integrator: IntegratorKind::Path,
            ..RenderSettings::default()
        };
        let scene = Scene::build(room()).unwrap();
        assert!(PlainPathTracer::for_scene(&scene, &path).is_some());
        for settings in [
            RenderSettings {
                integrator: IntegratorKind::Bdpt,
                ..path.clone()
            },
            RenderSettings {
                light_sampling: LightSampling::Light,
                ..path.clone()
            },
            RenderSettings {
                regularize: true,
                ..path.clone()
            },
        ] {
            assert!(PlainPathTracer::for_scene(&scene, &settings).is_none(), "{settings:?}");
        }
        let with = |edit: &dyn Fn(&mut SceneDesc)| {
            let mut desc = room();
            edit(&mut desc);
            PlainPathTracer::for_scene(&Scene::build(desc).unwrap(), &path).is_some()
        };
        assert!(!with(&|d| d.light_sampler = LightSamplerKind::Uniform));
        assert!(!with(&|d| d.light_sampler = LightSamplerKind::Bvh));
        assert!(!with(&|d| {
            d.materials[0].1 = Material::Diffuse {
                reflectance: crate::texture::Texture::checkerboard(
                    std::sync::Arc::new(crate::texture::Texture::constant(Vec3::ONE)),
                    std::sync::Arc::new(crate::texture::Texture::constant(Vec3::ZERO)),
                    4.0,
                    4.0,
                ),
            }
        }));
        assert!(!with(&|d| {
            // Lambertian too, but glowing: the plain loop would miss its glow.
            d.materials[0].1 = Material::Emissive {
                albedo: Vec3::splat(0.5),
                le: Vec3::ONE,
            }
        }));
    }
}
