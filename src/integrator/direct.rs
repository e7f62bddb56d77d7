//! Direct lighting: shadow rays to every light, stratified over the light
//! and decorrelated between shading points. Indirect light is not estimated.

use super::{RadianceEstimator, RayStats};
use crate::light::LightSample;
use crate::material::Transport;
use crate::math::{offset_origin, Ray, Vec2, Vec3};
use crate::sampling::{hammersley_shifted, Rng};
use crate::scene::{Hit, Scene};

#[derive(Clone, Copy, Debug)]
pub struct DirectLighting {
    pub shadow_samples: u32,
}

/// Specular bounces a camera ray may take before it gives up.
pub const MAX_SPECULAR_DEPTH: u32 = 16;

impl RadianceEstimator for DirectLighting {
    fn li(&self, scene: &Scene, ray: &Ray, rng: &mut Rng, stats: &mut RayStats) -> Vec3 {
        let Some((hit, wo, beta)) = first_diffuse_hit(scene, *ray, rng, stats) else {
            return Vec3::ZERO;
        };
        if let Some(l) = hit.light {
            return beta * scene.lights[l as usize].le(wo);
        }
        let m = scene.material(hit.material);
        beta * (m.le() + m.f() * irradiance(scene, &hit, wo, self.shadow_samples, rng, stats))
    }
}

/// Follows a camera ray through mirrors and glass to its first diffuse (or
/// emitting) surface: the hit, the direction back along the ray, and the
/// throughput of the specular chain.
pub fn first_diffuse_hit(
    scene: &Scene,
    mut ray: Ray,
    rng: &mut Rng,
    stats: &mut RayStats,
) -> Option<(Hit, Vec3, Vec3)> {
    let mut beta = Vec3::ONE;
    for depth in 0..=MAX_SPECULAR_DEPTH {
        if depth > 0 {
            stats.other_rays += 1;
        }
        let hit = scene.intersect(&ray, 0.0, f32::INFINITY)?;
        let wo = -ray.d;
        let m = scene.material(hit.material);
        if hit.light.is_some() || !m.is_specular() {
            return Some((hit, wo, beta));
        }
        let s = m.sample_specular(wo, hit.ng, rng.next_f32(), Transport::Radiance)?;
        beta *= s.weight;
        ray = Ray::new(offset_origin(hit.p, hit.ng, s.wi), s.wi);
    }
    None
}

/// Direct irradiance at a hit from all lights, seen from the side `wo` faces:
/// E = (1/N) sum Li cos / pdf over N stratified light samples per light.
/// Multiply by a BRDF value to get reflected radiance.
pub fn irradiance(scene: &Scene, hit: &Hit, wo: Vec3, n: u32, rng: &mut Rng, stats: &mut RayStats) -> Vec3 {
    if n == 0 {
        return Vec3::ZERO;
    }
    // Two-sided surfaces: shade the side the viewer is on.
    let flip = if hit.ng.dot(wo) < 0.0 { -1.0 } else { 1.0 };
    let ng = hit.ng * flip;
    let ns = hit.ns * flip;
    let mut e = Vec3::ZERO;
    for li in 0..scene.lights.len() {
        let shift = rng.next_2d();
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            let u = hammersley_shifted(i, n, shift);
            if let Some((ls, cos)) = unoccluded_light_sample(scene, hit.p, ng, ns, li, u, stats) {
                sum += ls.weight * cos;
            }
        }
        e += sum / n as f32;
    }
    e
}

/// One shadow ray towards light `li`, sampled with `u`, from the point `p`
/// whose geometric and shading normals `ng`, `ns` face the viewer: the light
/// sample and the cosine at `p`, when the light is above both normals and
/// nothing blocks it.
pub fn unoccluded_light_sample(
    scene: &Scene,
    p: Vec3,
    ng: Vec3,
    ns: Vec3,
    li: usize,
    u: Vec2,
    stats: &mut RayStats,
) -> Option<(LightSample, f32)> {
    let ls = scene.lights[li].sample_li(p, u)?;
    let cos = ns.dot(ls.wi);
    if cos <= 0.0 || ng.dot(ls.wi) <= 0.0 {
        return None;
    }
    // Aim from the offset origin at the sampled point itself: a ray parallel
    // to wi would meet a sphere light short of it and the light would shadow
    // itself.
    let o = offset_origin(p, ng, ls.wi);
    // A light at infinity (dist = inf) is unoccluded if nothing at all is in the way.
    let (d, t_max) = if ls.dist.is_finite() {
        let to_light = p + ls.wi * ls.dist - o;
        let dist = to_light.length();
        (to_light / dist, dist * (1.0 - 1e-4))
    } else {
        (ls.wi, f32::INFINITY)
    };
    stats.shadow_rays += 1;
    let blocked = scene.occluded_before_light(&Ray::new(o, d), 0.0, t_max, li as u32);
    (!blocked).then_some((ls, cos))
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
        let mut rng = Rng::new(1, 2);
        let mut stats = RayStats::default();
        let n = 2000;
        let e: Vec3 = (0..n)
            .map(|_| irradiance(&scene, &hit, -ray.d, 4, &mut rng, &mut stats))
            .sum::<Vec3>()
            / n as f32;
        let cos_d2 = (hit.p - Vec3::new(0.0, -0.5, -0.7)).normalize().y.abs()
            / (hit.p - Vec3::new(0.0, -0.5, -0.7)).length_squared();
        let expected = 14.0 * PI / (4.0 * PI) * cos_d2;
        assert!((e.x - expected).abs() / expected < 0.01, "{e:?} vs {expected}");
    }
}
