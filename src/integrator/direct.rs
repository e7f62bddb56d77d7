//! Direct lighting, and what every integrator shares about light arriving at
//! a surface: shadow rays (`unoccluded_light_sample`), direct light at a
//! vertex from all lights (`direct_radiance`) or from one light chosen by
//! power with multiple importance sampling (`sample_direct`), and the walk of
//! a camera path through specular and glossy surfaces to the vertices where a
//! diffuse lobe lets density estimates take over (`walk_camera_path`).
//!
//! The `direct` integrator walks the camera path like the photon mappers and
//! estimates only the direct light at its diffuse vertices.

use super::{RadianceEstimator, RayStats};
use crate::bsdf::{Bsdf, BsdfSample, TransportMode};
use crate::light::{LightContext, LightSample, LightSampleU};
use crate::math::{offset_origin, Ray, Vec2, Vec3};
use crate::sampling::{hammersley_shifted, Sampler};
use crate::scene::{Hit, Scene};

#[derive(Clone, Copy, Debug)]
pub struct DirectLighting {
    pub shadow_samples: u32,
}

/// Specular and glossy bounces a camera ray may take before it gives up.
pub const MAX_SPECULAR_DEPTH: u32 = 16;

impl RadianceEstimator for DirectLighting {
    fn li(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Vec3 {
        walk_camera_path(scene, *ray, sampler, stats, |v, sampler, stats| {
            (direct_radiance(scene, v, self.shadow_samples, sampler, stats), true)
        })
    }
}

/// The power heuristic's weight of a sample drawn with density `a` against
/// one drawn with density `b` (Veach 1997, 9.2.4, beta = 2).
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && (a2 + b2).is_finite() {
        a2 / (a2 + b2)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

/// A camera-path vertex whose BSDF has a diffuse lobe.
pub struct DiffuseVertex {
    pub hit: Hit,
    /// Unit direction back along the incoming ray.
    pub wo: Vec3,
    pub bsdf: Bsdf,
    /// Throughput of the path from the camera to here.
    pub beta: Vec3,
}

/// Walks a camera path from `ray` and returns the light it brings back, apart
/// from what `at_diffuse` estimates. Specular and glossy vertices are path
/// traced: at a glossy one, one light sample by power with multiple importance
/// sampling; emission found by a BSDF-sampled ray counts with its MIS weight
/// (whole after a specular bounce or from the camera), environment light too.
/// At a vertex with a diffuse lobe `at_diffuse` returns the radiance it
/// estimates there (the caller's estimators: direct light by shadow rays,
/// photon density), to be multiplied by the throughput, and whether the walk
/// may go on; it goes on only along the BSDF's specular lobes (a smooth
/// coat's reflection), which no estimate at the vertex covers.
pub fn walk_camera_path(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    stats: &mut RayStats,
    mut at_diffuse: impl FnMut(&DiffuseVertex, &mut Sampler, &mut RayStats) -> (Vec3, bool),
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    // How the last direction was chosen: `None` when specular (or the camera's).
    let mut from: Option<(LightContext, f32)> = None;
    // The ray's differentials, while it has any: the camera's, carried
    // through specular bounces.
    let mut diffs = None;
    for depth in 0..=MAX_SPECULAR_DEPTH {
        if depth > 0 {
            stats.other_rays += 1;
        }
        let Some(hit) = scene.intersect(&ray, 0.0, f32::INFINITY) else {
            l += beta * escaped_radiance(scene, &ray, from);
            break;
        };
        let wo = -ray.d;
        if let Some(li) = hit.light {
            l += beta * emitted_radiance(scene, li as usize, &ray, &hit, from);
            if !scene.reflects(&hit) {
                break;
            }
        }
        let m = scene.material(hit.material);
        l += beta * m.le();
        if depth == 0 {
            diffs = scene.camera_differentials(&hit);
        }
        let sp = scene.surface_seen(&hit, diffs.as_ref());
        let mut bsdf = m.bsdf(&sp, wo);
        bsdf.carry(beta);
        let flags = bsdf.flags();
        if flags.is_empty() {
            break;
        }
        let mut only_specular = false;
        if flags.is_diffuse() {
            let v = DiffuseVertex { hit, wo, bsdf, beta };
            let (lv, go_on) = at_diffuse(&v, sampler, stats);
            l += beta * lv;
            if !go_on || !flags.is_specular() {
                break;
            }
            only_specular = true;
        } else if flags.is_glossy() {
            l += beta * sample_direct(scene, &hit, wo, &bsdf, true, sampler, stats);
        }
        let Some(bs) = sample_bsdf(&bsdf, wo, sampler) else {
            break;
        };
        if only_specular && !bs.is_specular() {
            break;
        }
        if !hit.keeps_side(wo, bs.wi, bs.flags) {
            break;
        }
        beta *= bs.f * (bs.wi.dot(bsdf.frame.z).abs() / bs.pdf);
        if !beta.is_finite() || beta.max_element() <= 0.0 {
            break;
        }
        from = (!bs.is_specular()).then_some((LightContext::surface(hit.p, bsdf.frame.z), bs.pdf));
        diffs = diffs.filter(|_| bs.is_specular()).and_then(|d| {
            scene.specular_differentials(&hit, &d, (wo, bs.wi), bs.is_transmission(), bs.eta, bsdf.frame.z)
        });
        ray = Ray::timed(offset_origin(hit.p, hit.ng, bs.wi), bs.wi, hit.time);
    }
    l
}

/// A camera path's next direction from the BSDF at a vertex: the lobe
/// choice (passed over when the BSDF has one lobe), then the 2D sample.
#[inline(always)]
pub fn sample_bsdf(bsdf: &Bsdf, wo: Vec3, sampler: &mut Sampler) -> Option<BsdfSample> {
    let uc = sampler.lobe_choice(bsdf.uses_lobe_choice());
    bsdf.sample_f(wo, uc, sampler.next_2d(), TransportMode::Radiance)
}

/// Radiance from the environment along a ray that left the scene, weighted
/// against light sampling when the ray was BSDF-sampled at `from` (the vertex
/// and the sampling density).
pub fn escaped_radiance(scene: &Scene, ray: &Ray, from: Option<(LightContext, f32)>) -> Vec3 {
    let mut l = Vec3::ZERO;
    for &i in scene.infinite_lights() {
        let light = &scene.lights[i as usize];
        let le = light.le_escaped(ray.o, ray.d);
        let w = match from {
            None => 1.0,
            Some((ctx, pdf)) => power_heuristic(
                pdf,
                scene.light_pmf_at(&ctx, i as usize) * light.pdf_li_escaped(ctx.p, ray.d),
            ),
        };
        l += le * w;
    }
    l
}

/// Radiance of light `li` where `ray` hit it, weighted as `escaped_radiance`.
pub fn emitted_radiance(scene: &Scene, li: usize, ray: &Ray, hit: &Hit, from: Option<(LightContext, f32)>) -> Vec3 {
    let light = &scene.lights[li];
    let le = light.le(hit.p, -ray.d, hit.uv);
    match from {
        None => le,
        Some((ctx, pdf)) => {
            le * power_heuristic(
                pdf,
                scene.light_pmf_at(&ctx, li) * light.pdf_li_hit(ctx.p, ray.d, hit.p),
            )
        }
    }
}

/// The numbers of a light sample at a vertex: one 2D sample when the
/// choice ignores the vertex (its first number chooses the light and is
/// reused for the point), else a number for the choice and a 2D sample for
/// the point (`LightSampleU`).
#[inline(always)]
pub fn light_sample_u(scene: &Scene, sampler: &mut Sampler) -> LightSampleU {
    if scene.chooses_by_tree() {
        let choice = sampler.next_f32();
        LightSampleU {
            choice,
            point: sampler.next_2d(),
        }
    } else {
        let point = sampler.next_2d();
        LightSampleU { choice: point.x, point }
    }
}

/// Direct light reflected towards `wo` at a vertex from one light chosen by
/// the scene's light sampler and one sample on it, weighted against BSDF
/// sampling by the power heuristic when `mis` (else weight 1).
pub fn sample_direct(
    scene: &Scene,
    hit: &Hit,
    wo: Vec3,
    bsdf: &Bsdf,
    mis: bool,
    sampler: &mut Sampler,
    stats: &mut RayStats,
) -> Vec3 {
    let u = light_sample_u(scene, sampler);
    sample_direct_with(scene, hit, wo, bsdf, mis, u, stats, |_, pdf| pdf)
}

/// [`sample_direct`] with its numbers `u` already drawn, for a vertex whose
/// next direction may be sampled by a mixture of the BSDF and something
/// else (a photon guide): `mixed(wi, pdf_bsdf)` is the density of the
/// vertex's own sampling, which the light sample's MIS weight is taken
/// against (`|_, pdf| pdf` for the BSDF alone).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn sample_direct_with(
    scene: &Scene,
    hit: &Hit,
    wo: Vec3,
    bsdf: &Bsdf,
    mis: bool,
    u: LightSampleU,
    stats: &mut RayStats,
    mixed: impl Fn(Vec3, f32) -> f32,
) -> Vec3 {
    let ctx = LightContext::surface(hit.p, bsdf.frame.z);
    let Some((li, pmf, u)) = scene.choose_light(&ctx, u) else {
        return Vec3::ZERO;
    };
    let Some(ls) = light_sample_towards(scene, hit, wo, bsdf, li, u) else {
        return Vec3::ZERO;
    };
    // What the light brings if nothing blocks it, reckoned before the shadow
    // ray is traced: this work does not depend on the ray, so the processor
    // overlaps it with the traversal rather than waiting for both in turn.
    let (f, w) = if mis && scene.light_is_met(li) {
        let (f, pdf_bsdf) = bsdf.f_pdf(wo, ls.wi, TransportMode::Radiance);
        (f, power_heuristic(pmf * ls.pdf, mixed(ls.wi, pdf_bsdf)))
    } else {
        (bsdf.f(wo, ls.wi, TransportMode::Radiance), 1.0)
    };
    let f = f * ls.wi.dot(bsdf.frame.z).abs();
    let l = f * ls.weight * (w / pmf);
    if shadow_ray_blocked(scene, hit, &ls, li, stats) {
        return Vec3::ZERO;
    }
    l
}

/// Direct light reflected towards the vertex's `wo` from every light, `n`
/// stratified samples each: (1/N) sum f Li |cos| / pdf.
pub fn direct_radiance(scene: &Scene, v: &DiffuseVertex, n: u32, sampler: &mut Sampler, stats: &mut RayStats) -> Vec3 {
    if n == 0 {
        return Vec3::ZERO;
    }
    let mut l = Vec3::ZERO;
    for li in 0..scene.lights.len() {
        let shift = sampler.next_2d();
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            let u = hammersley_shifted(i, n, shift);
            if let Some(ls) = unoccluded_light_sample(scene, &v.hit, v.wo, &v.bsdf, li, u, stats) {
                let f = v.bsdf.f(v.wo, ls.wi, TransportMode::Radiance);
                sum += f * ls.weight * ls.wi.dot(v.bsdf.frame.z).abs();
            }
        }
        l += sum / n as f32;
    }
    l
}

/// Whether the BSDF at a hit can scatter light arriving along `wi` towards
/// `wo`: reflection on the viewer's side, transmission on the other, the
/// geometric and shading normals agreeing.
pub fn scatters_towards(hit: &Hit, wo: Vec3, bsdf: &Bsdf, wi: Vec3) -> bool {
    let flags = bsdf.flags();
    let geo_same = (wi.dot(hit.ng) > 0.0) == (wo.dot(hit.ng) > 0.0);
    let shade_same = (wi.dot(bsdf.frame.z) > 0.0) == (wo.dot(bsdf.frame.z) > 0.0);
    let allowed = if geo_same {
        flags.is_reflective() && shade_same
    } else {
        flags.is_transmissive() && !shade_same
    };
    allowed && wi.dot(hit.ng) != 0.0
}

/// One shadow ray towards light `li`, sampled with `u`, from a hit seen from
/// `wo`: the light sample, when the BSDF can scatter light from there
/// (reflection on the viewer's side, transmission on the other; the geometric
/// and shading normals must agree) and nothing blocks it.
pub fn unoccluded_light_sample(
    scene: &Scene,
    hit: &Hit,
    wo: Vec3,
    bsdf: &Bsdf,
    li: usize,
    u: Vec2,
    stats: &mut RayStats,
) -> Option<LightSample> {
    let ls = light_sample_towards(scene, hit, wo, bsdf, li, u)?;
    (!shadow_ray_blocked(scene, hit, &ls, li, stats)).then_some(ls)
}

/// The sample of light `li` drawn with `u` from a hit seen from `wo`, when
/// the BSDF can scatter light arriving along it towards `wo`; no shadow ray.
#[inline(always)]
fn light_sample_towards(scene: &Scene, hit: &Hit, wo: Vec3, bsdf: &Bsdf, li: usize, u: Vec2) -> Option<LightSample> {
    let ls = scene.lights[li].sample_li(hit.p, u)?;
    scatters_towards(hit, wo, bsdf, ls.wi).then_some(ls)
}

/// Whether anything blocks the shadow ray from `hit` to the light sample
/// `ls` of light `li`.
#[inline(always)]
pub(super) fn shadow_ray_blocked(scene: &Scene, hit: &Hit, ls: &LightSample, li: usize, stats: &mut RayStats) -> bool {
    stats.shadow_rays += 1;
    let (o, d, t_max) = shadow_ray(hit.p, hit.ng, ls.wi, ls.dist);
    let ray = Ray::timed(o, d, hit.time);
    if t_max.is_finite() {
        scene.occluded_before_light(&ray, 0.0, t_max, li as u32)
    } else {
        scene.occluded(&ray, 0.0, f32::INFINITY)
    }
}

/// The shadow ray from `p` (geometric normal `ng`) towards a light sample
/// in direction `wi` at distance `dist`: origin, direction and length
/// (infinite for a light at infinity). Aimed from the offset origin at the
/// sampled point itself: a ray parallel to wi would meet a sphere light
/// short of it and the light would shadow itself.
#[inline(always)]
pub(super) fn shadow_ray(p: Vec3, ng: Vec3, wi: Vec3, dist: f32) -> (Vec3, Vec3, f32) {
    let o = offset_origin(p, ng, wi);
    if dist.is_finite() {
        let to_light = p + wi * dist - o;
        let dist = to_light.length();
        (o, to_light / dist, dist * (1.0 - 1e-4))
    } else {
        (o, wi, f32::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::cornell;
    use std::f32::consts::PI;

    #[test]
    fn ceiling_above_the_light_gets_the_inverse_square_irradiance() {
        // Outside a uniform Lambertian sphere the irradiance at normal incidence is
        // Phi / (4 pi d^2): 14 pi / (4 pi 0.5^2) = 14 on the ceiling 0.5 above the
        // light's centre. Shadow rays towards the light's silhouette must not be
        // blocked by the light itself.
        let scene = Scene::build(cornell()).unwrap();
        let p = Vec3::new(0.0, -1.0, -0.7);
        let ray = Ray::new(Vec3::new(0.0, 0.0, -0.7), (p - Vec3::new(0.3, 0.0, -0.7)).normalize());
        let hit = scene.intersect(&ray, 0.0, f32::INFINITY).unwrap();
        let wo = -ray.d;
        let bsdf = scene.material(hit.material).bsdf(&scene.surface(&hit), wo);
        let v = DiffuseVertex {
            hit,
            wo,
            bsdf,
            beta: Vec3::ONE,
        };
        let mut sampler = Sampler::independent(crate::sampling::Rng::new(1, 2));
        let mut stats = RayStats::default();
        let n = 2000;
        let l: Vec3 = (0..n)
            .map(|_| direct_radiance(&scene, &v, 4, &mut sampler, &mut stats))
            .sum::<Vec3>()
            / n as f32;
        // Reflected radiance = albedo / pi * E.
        let albedo = bsdf.f(wo, bsdf.frame.z, TransportMode::Radiance) * PI;
        let e = l * PI / albedo;
        let cos_d2 = (hit.p - Vec3::new(0.0, -0.5, -0.7)).normalize().y.abs()
            / (hit.p - Vec3::new(0.0, -0.5, -0.7)).length_squared();
        let expected = 14.0 * PI / (4.0 * PI) * cos_d2;
        assert!((e.x - expected).abs() / expected < 0.01, "{e:?} vs {expected}");
    }
}
