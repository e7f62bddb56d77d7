//! Photon tracing: emission from the lights, diffuse bounces, storage.
//!
//! Jensen (2001), "Realistic Image Synthesis Using Photon Mapping", chapter 5:
//! each of N photons leaves a light chosen in proportion to its power, from a
//! point uniform over the light's surface in a cosine-distributed direction,
//! carrying Phi / (N p_light). At each diffuse surface it reaches it is stored
//! (position, incoming direction, power, normal, object), then survives Russian
//! roulette with probability p = max albedo component and, if it does, carries
//! power * albedo / p onward in a cosine-distributed direction (5.2: the power
//! of surviving photons stays comparable, so the map's photons are of similar
//! weight). Photons stop after `max_bounces` surface hits, on a light (lights
//! are black), or when they leave the scene.
//!
//! Photons are traced on every core in fixed chunks of consecutive indices;
//! photon i draws from an RNG keyed by (seed, i) and chunks are concatenated in
//! chunk order, so the map is identical for any thread count.

use super::map::Photon;
use super::PhotonSettings;
use crate::math::{offset_origin, to_world, Ray};
use crate::sampling::{cosine_hemisphere, Rng};
use crate::scene::Scene;
use rayon::prelude::*;

/// Photons per parallel work item.
const CHUNK: u64 = 4096;
/// Second key of photon RNG streams, apart from the camera's sample indices.
const PHOTON_STREAM: u64 = 0x7068_6f74_6f6e_0000;

/// The stored photons and what was traced.
#[derive(Clone, Debug)]
pub struct PhotonTrace {
    /// Photons in emission order, powers relative to `unit`.
    pub photons: Vec<Photon>,
    /// Power (W) of a relative power of 1.0: the largest per-photon emitted power.
    pub unit: f32,
    /// Photons emitted.
    pub emitted: u64,
    /// Total power (W) arriving at the k-th surface hit (k = 0 is the first),
    /// stored or not, before roulette.
    pub power_per_hit: Vec<[f64; 3]>,
    /// Rays traced.
    pub rays: u64,
}

/// Traces `settings.photons` photons from the scene's lights.
pub fn trace(scene: &Scene, settings: &PhotonSettings, seed: u64) -> PhotonTrace {
    let mut t = ResumableTrace::new(scene, settings, seed);
    t.run(scene, &|| false);
    t.finish()
}

/// One chunk's photons, arrived power per hit and rays.
type Chunk = (Vec<Photon>, Vec<[f64; 3]>, u64);

/// A trace that can stop between chunks and carry on later with the same
/// result: chunk c depends only on (seed, c), so the chunks done before a
/// stop are kept and only the rest are traced on the next run. The preview
/// window stops tracing when the camera moves and picks up where it stopped.
/// The scene's lights and geometry must not change in between.
pub struct ResumableTrace {
    settings: PhotonSettings,
    seed: u64,
    /// Light selection weights (largest power channel) and their sum.
    weights: Vec<f32>,
    total: f32,
    /// Index of the last light with a positive weight.
    last: usize,
    unit: f32,
    chunks: Vec<Option<Chunk>>,
}

impl ResumableTrace {
    pub fn new(scene: &Scene, settings: &PhotonSettings, seed: u64) -> Self {
        // Pick lights in proportion to their power (largest channel).
        let weights: Vec<f32> = scene.lights.iter().map(|l| l.power().max_element().max(0.0)).collect();
        let total: f32 = weights.iter().sum();
        let n = settings.photons;
        let traced = n > 0 && total > 0.0;
        // The largest emitted photon power, so that stored powers are at most ~1.
        let unit = if traced {
            scene
                .lights
                .iter()
                .zip(&weights)
                .filter(|(_, &w)| w > 0.0)
                .map(|(l, &w)| (l.power() / (n as f32 * w / total)).max_element())
                .fold(0.0f32, f32::max)
        } else {
            1.0
        };
        let chunks = if traced { n.div_ceil(CHUNK) as usize } else { 0 };
        ResumableTrace {
            settings: *settings,
            seed,
            last: weights.iter().rposition(|&w| w > 0.0).unwrap_or(0),
            weights,
            total,
            unit,
            chunks: vec![None; chunks],
        }
    }

    /// Traces the chunks not yet done, in parallel; `stop` is asked before
    /// each chunk. Returns true when every chunk is done.
    pub fn run(&mut self, scene: &Scene, stop: &(dyn Fn() -> bool + Sync)) -> bool {
        let this = &*self;
        let todo: Vec<usize> = (0..this.chunks.len()).filter(|&c| this.chunks[c].is_none()).collect();
        let done: Vec<(usize, Option<Chunk>)> = todo
            .into_par_iter()
            .map(|c| (c, (!stop()).then(|| this.chunk(scene, c as u64))))
            .collect();
        for (c, chunk) in done {
            self.chunks[c] = chunk;
        }
        self.is_complete()
    }

    pub fn is_complete(&self) -> bool {
        self.chunks.iter().all(Option::is_some)
    }

    /// Fraction of the photons traced so far.
    pub fn progress(&self) -> f32 {
        if self.chunks.is_empty() {
            return 1.0;
        }
        self.chunks.iter().filter(|c| c.is_some()).count() as f32 / self.chunks.len() as f32
    }

    /// The trace, with the chunks concatenated in chunk order (the same map
    /// for any thread count). Panics if a chunk is missing (see `run`).
    pub fn finish(self) -> PhotonTrace {
        let hits = self.settings.max_bounces as usize;
        let mut out = PhotonTrace {
            photons: vec![],
            unit: self.unit,
            emitted: self.settings.photons,
            power_per_hit: vec![[0.0; 3]; hits],
            rays: 0,
        };
        let chunks: Vec<Chunk> = self
            .chunks
            .into_iter()
            .map(|c| c.expect("ResumableTrace::finish before every chunk was traced"))
            .collect();
        out.photons.reserve_exact(chunks.iter().map(|c| c.0.len()).sum());
        for (photons, per_hit, rays) in chunks {
            out.photons.extend_from_slice(&photons);
            for (total, chunk) in out.power_per_hit.iter_mut().zip(per_hit) {
                for (t, c) in total.iter_mut().zip(chunk) {
                    *t += c;
                }
            }
            out.rays += rays;
        }
        out
    }

    /// Photons c * CHUNK .. (c + 1) * CHUNK.
    fn chunk(&self, scene: &Scene, c: u64) -> Chunk {
        let settings = &self.settings;
        let (weights, total, last, unit, n) = (&self.weights, self.total, self.last, self.unit, settings.photons);
        let mut photons = Vec::new();
        let mut per_hit = vec![[0.0f64; 3]; settings.max_bounces as usize];
        let mut rays = 0;
        for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
            let mut rng = Rng::keyed(self.seed, i, PHOTON_STREAM);
            // Emit: choose a light, a point on it and a direction.
            let mut u = rng.next_f32() * total;
            let mut li = 0;
            while li < last && (u >= weights[li] || weights[li] == 0.0) {
                u -= weights[li];
                li += 1;
            }
            let light = &scene.lights[li];
            let (mut ray, _) = light.sample_le(rng.next_2d(), rng.next_2d());
            let mut power = light.power() / (n as f32 * weights[li] / total) / unit;
            for (hit_index, arrived) in per_hit.iter_mut().enumerate() {
                rays += 1;
                let Some(hit) = scene.intersect(&ray, 0.0, f32::INFINITY) else {
                    break;
                };
                if hit.light.is_some() {
                    break;
                }
                // Store on the side the photon arrived from.
                let wi = -ray.d;
                let side = if hit.ng.dot(wi) < 0.0 { -1.0 } else { 1.0 };
                let (ng, ns) = (hit.ng * side, hit.ns * side);
                if hit_index > 0 || settings.store_first_hit {
                    photons.push(Photon::new(hit.p, wi, ng, power, hit.object, hit_index == 0));
                }
                for (s, c) in arrived.iter_mut().zip(power.to_array()) {
                    *s += c as f64 * unit as f64;
                }
                // Reflect: Russian roulette on the albedo, then a cosine-distributed direction.
                let albedo = scene.material(hit.material).albedo();
                if settings.roulette {
                    let p = albedo.max_element();
                    if rng.next_f32() >= p {
                        break;
                    }
                    power *= albedo / p;
                } else {
                    power *= albedo;
                }
                let d = to_world(cosine_hemisphere(rng.next_2d()), ns);
                if d.dot(ng) <= 0.0 || power.max_element() <= 0.0 {
                    break;
                }
                ray = Ray::new(offset_origin(hit.p, ng, d), d);
            }
        }
        (photons, per_hit, rays)
    }
}

/// Sum of the decoded powers (W) of photons, for checks and statistics.
pub fn total_power(photons: &[Photon], unit: f32) -> [f64; 3] {
    let mut s = [0.0f64; 3];
    for p in photons {
        for (t, c) in s.iter_mut().zip(p.power().to_array()) {
            *t += c as f64 * unit as f64;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::analytic::closed_box;
    use crate::integrator::with_threads;
    use crate::light::Light;
    use crate::math::Vec3;
    use crate::photon::{build_map, PhotonSettings};

    fn point_light(power: Vec3) -> Light {
        Light::Point {
            position: Vec3::new(0.1, -0.2, 0.3),
            power,
        }
    }

    fn settings(photons: u64, max_bounces: u32, roulette: bool) -> PhotonSettings {
        PhotonSettings {
            photons,
            max_bounces,
            store_first_hit: true,
            roulette,
            ..PhotonSettings::default()
        }
    }

    #[test]
    fn closed_white_box_keeps_all_power_at_every_bounce() {
        // Nothing escapes or is absorbed: each hit receives the light's whole power,
        // both as traced and as stored (the photons' f16 powers decode exactly).
        let phi = Vec3::new(10.0, 20.0, 5.0);
        let scene = closed_box(1.0, point_light(phi));
        let t = trace(&scene, &settings(20_000, 6, false), 3);
        assert_eq!(t.photons.len(), 20_000 * 6);
        for (k, p) in t.power_per_hit.iter().enumerate() {
            for c in 0..3 {
                assert!((p[c] - phi[c] as f64).abs() / (phi[c] as f64) < 1e-5, "hit {k}: {p:?}");
            }
        }
        let stored = total_power(&t.photons, t.unit);
        for c in 0..3 {
            assert!((stored[c] - 6.0 * phi[c] as f64).abs() / (6.0 * phi[c] as f64) < 1e-5);
        }
    }

    #[test]
    fn grey_box_loses_a_fraction_one_minus_albedo_per_bounce() {
        let (a, phi) = (0.6f64, 12.0f32);
        let scene = closed_box(a as f32, point_light(Vec3::splat(phi)));
        // Without roulette the decay is exact; with it, right on average.
        let exact = trace(&scene, &settings(5_000, 5, false), 1);
        let roulette = trace(&scene, &settings(200_000, 5, true), 1);
        for k in 0..5 {
            let expected = phi as f64 * a.powi(k as i32);
            let e = (exact.power_per_hit[k][0] - expected).abs() / expected;
            assert!(e < 1e-5, "hit {k}: {:?} vs {expected}", exact.power_per_hit[k]);
            let r = (roulette.power_per_hit[k][0] - expected).abs() / expected;
            // 200k photons: the survivor count after k hits has relative standard
            // deviation sqrt((1 - a^k) / (200k a^k)) < 0.6% for k <= 4.
            assert!(
                r < 0.025,
                "hit {k} with roulette: {:?} vs {expected}",
                roulette.power_per_hit[k]
            );
        }
        // Roulette keeps the power of surviving photons: all stored photons of a
        // grey scene carry the same power.
        let p0 = roulette.photons[0].power();
        assert!(roulette.photons.iter().all(|p| p.power() == p0));
    }

    #[test]
    fn map_is_identical_for_any_thread_count() {
        let scene = crate::Scene::build(crate::scene::builtin::cornell()).unwrap();
        let s = PhotonSettings {
            photons: 30_000,
            ..PhotonSettings::default()
        };
        let one = with_threads(Some(1), || build_map(&scene, &s, 7)).unwrap().0;
        let two = with_threads(Some(2), || build_map(&scene, &s, 7)).unwrap().0;
        assert!(one.len() > 10_000);
        assert_eq!(one, two);
        let other_seed = with_threads(Some(2), || build_map(&scene, &s, 8)).unwrap().0;
        assert_ne!(one, other_seed);
    }

    #[test]
    fn a_stopped_trace_resumes_to_the_same_photons() {
        let scene = crate::Scene::build(crate::scene::builtin::cornell()).unwrap();
        let s = settings(9 * CHUNK + 100, 5, true);
        let whole = trace(&scene, &s, 5);
        let mut t = ResumableTrace::new(&scene, &s, 5);
        // Stop after four chunks have started; which four depends on the threads.
        let started = std::sync::atomic::AtomicUsize::new(0);
        let stop = || started.fetch_add(1, std::sync::atomic::Ordering::Relaxed) >= 4;
        assert!(!with_threads(Some(2), || t.run(&scene, &stop)).unwrap());
        assert!((t.progress() - 0.4).abs() < 1e-6, "{}", t.progress());
        assert!(!t.run(&scene, &|| true));
        assert!(t.run(&scene, &|| false));
        let resumed = t.finish();
        assert_eq!(resumed.photons, whole.photons);
        assert_eq!(resumed.power_per_hit, whole.power_per_hit);
        assert_eq!(
            (resumed.unit, resumed.emitted, resumed.rays),
            (whole.unit, whole.emitted, whole.rays)
        );
    }
}
