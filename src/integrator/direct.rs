//! Direct lighting: shadow rays to every light, stratified over the light
//! and decorrelated between shading points. Indirect light is not estimated.

use super::{RadianceEstimator, RayStats};
use crate::math::{offset_origin, Ray, Vec3};
use crate::sampling::{hammersley_shifted, Rng};
use crate::scene::{Hit, Scene};

pub struct DirectLighting {
    pub shadow_samples: u32,
}

impl RadianceEstimator for DirectLighting {
    fn li(&self, scene: &Scene, ray: &Ray, rng: &mut Rng, stats: &mut RayStats) -> Vec3 {
        let Some(hit) = scene.intersect(ray, 0.0, f32::INFINITY) else {
            return Vec3::ZERO;
        };
        if let Some(l) = hit.light {
            return scene.lights[l as usize].radiance();
        }
        let f = scene.material(hit.material).f();
        f * irradiance(scene, &hit, -ray.d, self.shadow_samples, rng, stats)
    }
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
    for light in &scene.lights {
        let shift = rng.next_2d();
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            let u = hammersley_shifted(i, n, shift);
            let Some(ls) = light.sample_li(hit.p, u) else {
                continue;
            };
            let cos = ns.dot(ls.wi);
            if cos <= 0.0 || ng.dot(ls.wi) <= 0.0 {
                continue;
            }
            let o = offset_origin(hit.p, ng, ls.wi);
            let dist = (ls.wi * ls.dist + hit.p - o).length();
            stats.shadow_rays += 1;
            if !scene.occluded(&Ray::new(o, ls.wi), 0.0, dist * (1.0 - 1e-4)) {
                sum += ls.weight * cos;
            }
        }
        e += sum / n as f32;
    }
    e
}
