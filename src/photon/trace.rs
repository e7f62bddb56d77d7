//! Photon tracing: emission from the lights, diffuse and specular bounces, storage.
//!
//! Jensen (2001), "Realistic Image Synthesis Using Photon Mapping", chapter 5:
//! each of N photons leaves a light chosen in proportion to its power, from a
//! point uniform over the light's surface in a cosine-distributed direction,
//! carrying Phi / (N p_light). At each diffuse surface it reaches it is stored
//! (position, incoming direction, power, normal, object), then survives Russian
//! roulette with probability p = max albedo component and, if it does, carries
//! power * albedo / p onward in a cosine-distributed direction (5.2: the power
//! of surviving photons stays comparable, so the map's photons are of similar
//! weight). At a mirror or glass surface (9.2) the photon is never stored: it
//! is reflected or refracted (Fresnel picks which), its power scaled by the
//! mirror's reflectance (by roulette when below 1). Photons stop after
//! `max_bounces` surface hits of either kind, on a light that reflects nothing, or
//! when they leave the scene.
//!
//! Stored photons are tagged by the path that brought them: direct (light ->
//! here), caustic (light -> specular+ -> here) or indirect (a diffuse bounce
//! before). The caustic map (`trace_caustics`) keeps only caustic photons, from
//! its own emission; the global map keeps caustic and indirect photons, and
//! direct ones too when asked.
//!
//! Photons are traced on every core in fixed chunks of consecutive indices;
//! photon i draws from an RNG keyed by (seed, i) and chunks are concatenated in
//! chunk order, so the map is identical for any thread count.

use super::map::Photon;
use super::PhotonSettings;
use crate::bsdf::TransportMode;
use crate::math::{offset_origin, Ray, Vec3};
use crate::sampling::Rng;
use crate::scene::{Hit, Scene};
use rayon::prelude::*;

/// Photons per parallel work item.
const CHUNK: u64 = 4096;
/// Second key of photon RNG streams, apart from the camera's sample indices.
const PHOTON_STREAM: u64 = 0x7068_6f74_6f6e_0000;
/// Second key of the caustic photons' RNG streams.
const CAUSTIC_STREAM: u64 = 0x6361_7573_7469_6300;

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

/// What to keep of a photon's path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Keep {
    /// The global map: every diffuse hit (first hits only if asked).
    Global,
    /// The caustic map: only the first diffuse hit after one or more specular
    /// bounces; the photon ends there.
    Caustics,
}

/// How photons leave the lights: one chosen in proportion to its power
/// (largest channel), each photon carrying Phi / (n p_light) relative to `unit`.
struct Emitter {
    weights: Vec<f32>,
    total: f32,
    last: usize,
    /// The largest emitted photon power, so that stored powers are at most ~1.
    unit: f32,
    n: u64,
    /// The time every photon leaves at (an SPPM pass's); `None`: each its
    /// own over the shutter, where things move.
    time: Option<f32>,
}

impl Emitter {
    /// `None` when no light emits anything.
    fn new(scene: &Scene, n: u64) -> Option<Emitter> {
        let weights: Vec<f32> = scene.lights.iter().map(|l| l.power().max_element().max(0.0)).collect();
        let total: f32 = weights.iter().sum();
        if n == 0 || total <= 0.0 {
            return None;
        }
        let unit = scene
            .lights
            .iter()
            .zip(&weights)
            .filter(|(_, &w)| w > 0.0)
            .map(|(l, &w)| (l.power() / (n as f32 * w / total)).max_element())
            .fold(0.0f32, f32::max);
        let last = weights.iter().rposition(|&w| w > 0.0).unwrap_or(0);
        Some(Emitter {
            weights,
            total,
            last,
            unit,
            n,
            time: None,
        })
    }

    /// Chooses a light, a point on it and a direction: the ray and its relative power.
    fn emit(&self, scene: &Scene, rng: &mut Rng) -> (Ray, Vec3) {
        let mut u = rng.next_f32() * self.total;
        let mut li = 0;
        while li < self.last && (u >= self.weights[li] || self.weights[li] == 0.0) {
            u -= self.weights[li];
            li += 1;
        }
        let light = &scene.lights[li];
        // An environment map's photons follow its luminance, not its colour:
        // each carries the flux of its own direction.
        let le = light.sample_le_flux(rng.next_2d(), rng.next_2d());
        let mut ray = le.ray;
        // Where things move, each photon leaves at a time of its own over
        // the shutter, unless all leave at an SPPM pass's: the map holds
        // the light of the whole exposure (and `record` keeps what moving
        // shapes catch with them).
        if let Some([open, close]) = scene.camera.shutter {
            ray.time = self.time.unwrap_or_else(|| open + (close - open) * rng.next_f32());
        }
        let power = le.flux / (self.n as f32 * self.weights[li] / self.total) / self.unit;
        (ray, power)
    }
}

impl Emitter {
    /// The record of a photon stored at `hit`. On a moving shape, when
    /// photons leave at times of their own, it is kept where the shape is at
    /// its motion's start (`Scene::rest_frame`): a gather at any time of the
    /// shutter then finds the photons the shape caught over the whole
    /// exposure, where it finds the shape, instead of those that fell on the
    /// spot while the shape passed (a share of the shutter). Its power is
    /// divided by how much the motion stretches the surface there, since
    /// gathers measure area at the start's placement.
    fn record(&self, scene: &Scene, hit: &Hit, wi: Vec3, n: Vec3, power: Vec3, direct: bool) -> Photon {
        let rest = match self.time {
            None => scene.rest_frame(hit.object, hit.time),
            Some(_) => None,
        };
        let Some(r) = rest else {
            return Photon::new(hit.p, wi, n, power, hit.object, direct);
        };
        let n_rest = r.normal(n);
        let scale = r.area_scale(n_rest);
        let power = if scale > 0.0 && scale.is_finite() {
            power / scale
        } else {
            power
        };
        Photon::new(r.point(hit.p), r.direction(wi), n_rest, power, hit.object, direct).moving()
    }
}

/// What one chunk of photons left: stored photons, power per hit, rays.
type Chunk = (Vec<Photon>, Vec<[f64; 3]>, u64);

/// Traces photons `indices` (RNG streams keyed by (seed, i, `stream`)).
fn trace_chunk(
    scene: &Scene,
    settings: &PhotonSettings,
    em: &Emitter,
    seed: u64,
    stream: u64,
    keep: Keep,
    indices: std::ops::Range<u64>,
) -> Chunk {
    let hits = settings.max_bounces as usize;
    let mut photons = Vec::new();
    let mut per_hit = vec![[0.0f64; 3]; hits];
    let mut rays = 0;
    for i in indices {
        let mut rng = Rng::keyed(seed, i, stream);
        let (mut ray, mut power) = em.emit(scene, &mut rng);
        // Bounces so far: the kind of light path the photon is on.
        let (mut diffuse, mut specular) = (0u32, 0u32);
        for arrived in per_hit.iter_mut() {
            rays += 1;
            let Some(hit) = scene.intersect(&ray, 0.0, f32::INFINITY) else {
                break;
            };
            if !scene.reflects(&hit) {
                break;
            }
            for (s, c) in arrived.iter_mut().zip(power.to_array()) {
                *s += c as f64 * em.unit as f64;
            }
            // Towards where the photon came from (pbrt's wo on a light path).
            let wi = -ray.d;
            let m = scene.material(hit.material);
            let mut bsdf = m.bsdf(&scene.surface(&hit), wi);
            bsdf.carry(power);
            let flags = bsdf.flags();
            if flags.is_empty() {
                break;
            }
            if flags.is_diffuse() {
                // Store on the side the photon arrived from.
                let ng = if hit.ng.dot(wi) < 0.0 { -hit.ng } else { hit.ng };
                let first = diffuse == 0;
                let caustic = first && specular > 0;
                match keep {
                    Keep::Caustics => {
                        if caustic {
                            photons.push(em.record(scene, &hit, wi, ng, power, false).caustic());
                        }
                        break;
                    }
                    Keep::Global => {
                        // Caustic first hits too: shadow rays cannot reach them.
                        if !first || caustic || settings.store_first_hit {
                            let ph = em.record(scene, &hit, wi, ng, power, first && !caustic);
                            photons.push(if caustic { ph.caustic() } else { ph });
                        }
                    }
                }
            }
            let Some(bs) = bsdf.sample_f(wi, rng.next_f32(), rng.next_2d(), TransportMode::Importance) else {
                break;
            };
            if !hit.keeps_side(wi, bs.wi, bs.flags) {
                break;
            }
            // Veach (1997, 5.3): with shading normals, the adjoint BSDF
            // carries |wi . ns| |wo . ng| / (|wi . ng| |wo . ns|).
            let ns = bsdf.frame.z;
            let correction = (wi.dot(ns) * bs.wi.dot(hit.ng) / (wi.dot(hit.ng) * bs.wi.dot(ns))).abs();
            let scatter = bs.f * (bs.wi.dot(ns).abs() / bs.pdf) * if correction.is_finite() { correction } else { 0.0 };
            if settings.roulette {
                // Survive with the ratio of new to old power (at most 1), so
                // that surviving photons keep comparable powers (Jensen 2001, 5.2).
                let p = scatter.max_element().min(1.0);
                if p <= 0.0 || rng.next_f32() >= p {
                    break;
                }
                power *= scatter / p;
            } else {
                power *= scatter;
            }
            if !power.is_finite() || power.max_element() <= 0.0 {
                break;
            }
            if bs.flags.is_diffuse() {
                diffuse += 1;
            } else {
                specular += 1;
            }
            ray = Ray::timed(offset_origin(hit.p, hit.ng, bs.wi), bs.wi, hit.time);
        }
    }
    (photons, per_hit, rays)
}

/// Appends chunks in chunk order: the same result for any thread count.
fn gather_chunks(out: &mut PhotonTrace, chunks: Vec<Chunk>) {
    out.photons.reserve(chunks.iter().map(|c| c.0.len()).sum());
    for (photons, per_hit, rays) in chunks {
        out.photons.extend_from_slice(&photons);
        for (total, chunk) in out.power_per_hit.iter_mut().zip(per_hit) {
            for (t, c) in total.iter_mut().zip(chunk) {
                *t += c;
            }
        }
        out.rays += rays;
    }
}

/// Traces `settings.photons` photons from the scene's lights into the global map.
/// Photons are reflected and refracted by mirrors and glass, never stored there.
pub fn trace(scene: &Scene, settings: &PhotonSettings, seed: u64) -> PhotonTrace {
    trace_at(scene, settings, seed, None)
}

/// `trace` with every photon leaving at `time` where things move (`None`:
/// each at a time of its own over the shutter).
pub fn trace_at(scene: &Scene, settings: &PhotonSettings, seed: u64, time: Option<f32>) -> PhotonTrace {
    let mut t = ResumableTrace::new(scene, settings, seed);
    if let Some(e) = &mut t.emitter {
        e.time = time;
    }
    t.run(scene, &|| false);
    t.finish()
}

/// A global-map trace that can stop between chunks and carry on later with
/// the same result: chunk c depends only on (seed, c), so the chunks done
/// before a stop are kept and only the rest are traced on the next run. The
/// preview window stops tracing when the camera moves and picks up where it
/// stopped. The scene's lights and geometry must not change in between.
pub struct ResumableTrace {
    settings: PhotonSettings,
    seed: u64,
    /// `None` when nothing is emitted (no photons asked for, or no light).
    emitter: Option<Emitter>,
    chunks: Vec<Option<Chunk>>,
}

impl ResumableTrace {
    pub fn new(scene: &Scene, settings: &PhotonSettings, seed: u64) -> Self {
        let emitter = Emitter::new(scene, settings.photons);
        let chunks = match emitter {
            Some(_) => settings.photons.div_ceil(CHUNK) as usize,
            None => 0,
        };
        ResumableTrace {
            settings: *settings,
            seed,
            emitter,
            chunks: vec![None; chunks],
        }
    }

    /// Traces the chunks not yet done, in parallel; `stop` is asked before
    /// each chunk. Returns true when every chunk is done.
    pub fn run(&mut self, scene: &Scene, stop: &(dyn Fn() -> bool + Sync)) -> bool {
        let this = &*self;
        let Some(em) = &this.emitter else {
            return true;
        };
        let n = this.settings.photons;
        let todo: Vec<usize> = (0..this.chunks.len()).filter(|&c| this.chunks[c].is_none()).collect();
        let done: Vec<(usize, Option<Chunk>)> = todo
            .into_par_iter()
            .map(|c| {
                let range = c as u64 * CHUNK..((c as u64 + 1) * CHUNK).min(n);
                let chunk = (!stop())
                    .then(|| trace_chunk(scene, &this.settings, em, this.seed, PHOTON_STREAM, Keep::Global, range));
                (c, chunk)
            })
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
        let mut out = PhotonTrace {
            photons: vec![],
            unit: self.emitter.as_ref().map_or(1.0, |e| e.unit),
            emitted: self.settings.photons,
            power_per_hit: vec![[0.0; 3]; self.settings.max_bounces as usize],
            rays: 0,
        };
        let chunks: Vec<Chunk> = self
            .chunks
            .into_iter()
            .map(|c| c.expect("ResumableTrace::finish before every chunk was traced"))
            .collect();
        gather_chunks(&mut out, chunks);
        out
    }
}

/// Photons emitted per round of the caustic pass.
pub use crate::settings::CAUSTIC_ROUND;
const _: () = assert!(CAUSTIC_ROUND == 16 * CHUNK);
/// The caustic pass gives up after emitting this many photons per photon asked for.
const CAUSTIC_EMIT_LIMIT: u64 = 256;

/// Traces the caustic map (Jensen 2001, 9.2): photons are emitted in rounds
/// of fixed size until `settings.caustic_photons` have reached a diffuse
/// surface through mirrors or glass only (about: the last round is kept
/// whole), or the emission limit is reached. Only those first diffuse hits are
/// stored. The number of photons emitted is only known at the end, so powers
/// are computed as if one photon were emitted and the unit divided by the count.
/// Scenes without mirrors or glass have no caustics: nothing is traced.
pub fn trace_caustics(scene: &Scene, settings: &PhotonSettings, seed: u64) -> PhotonTrace {
    let wanted = settings.caustic_photons;
    let mut out = PhotonTrace {
        photons: vec![],
        unit: 1.0,
        emitted: 0,
        power_per_hit: vec![[0.0; 3]; settings.max_bounces as usize],
        rays: 0,
    };
    if wanted == 0 || !scene.materials.iter().any(|m| m.is_caustic_caster()) {
        return out;
    }
    let Some(em) = Emitter::new(scene, 1) else {
        return out;
    };
    let limit = wanted.saturating_mul(CAUSTIC_EMIT_LIMIT);
    while (out.photons.len() as u64) < wanted && out.emitted < limit {
        let base = out.emitted;
        let chunks: Vec<Chunk> = (0..CAUSTIC_ROUND / CHUNK)
            .into_par_iter()
            .map(|c| {
                let range = base + c * CHUNK..base + (c + 1) * CHUNK;
                trace_chunk(scene, settings, &em, seed, CAUSTIC_STREAM, Keep::Caustics, range)
            })
            .collect();
        gather_chunks(&mut out, chunks);
        out.emitted += CAUSTIC_ROUND;
    }
    let scale = 1.0 / out.emitted as f64;
    out.unit = (em.unit as f64 * scale) as f32;
    for p in out.power_per_hit.iter_mut() {
        for c in p.iter_mut() {
            *c *= scale;
        }
    }
    out
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
    fn photons_leave_at_times_over_the_shutter_and_meet_moving_shapes_there() {
        // A narrow spot light straight down onto a large quad that slides
        // out of its beam: the quad covers the beam (radius about 0.1 at
        // the quad) until its edge at x = -4.5 + 20 t passes it, for 0.225
        // of the shutter; the floor behind takes the rest.
        use crate::geometry::motion::Motion;
        use crate::scene::{builtin, MovingTriangles, SceneDesc, TriangleDesc};
        let mut d = SceneDesc::empty("beam", builtin::cornell().camera);
        let m = d.material("grey", crate::material::Material::diffuse(0.5, 0.5, 0.5));
        let quad = |z: f32, size: f32| {
            let v = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| Vec3::new(x * size, y * size, z));
            [[0, 1, 2], [0, 2, 3]].map(|t| TriangleDesc {
                vertices: t.map(|i| v[i]),
                normals: None,
                uvs: None,
                material: m,
            })
        };
        d.triangles.extend(quad(-1.0, 100.0));
        d.triangles.extend(quad(0.0, 5.0));
        d.moving.push(MovingTriangles {
            triangles: 2..4,
            motion: Motion::new(
                glam::Mat4::from_translation(Vec3::new(0.5, 0.0, 0.0)),
                glam::Mat4::from_translation(Vec3::new(20.5, 0.0, 0.0)),
                [0.0, 1.0],
            )
            .unwrap(),
        });
        d.lights.push(Light::Spot {
            position: Vec3::new(0.0, 0.0, 5.0),
            direction: -Vec3::Z,
            intensity: Vec3::ONE,
            cos_falloff_start: 0.9999,
            cos_falloff_end: 0.9998,
        });
        // Quad placed at its start: x from -4.5 to 5.5.
        for i in 2..4 {
            let mut t = d.triangles.get(i).unwrap();
            t.vertices = t.vertices.map(|v| v + Vec3::new(0.5, 0.0, 0.0));
            d.triangles.set(i, t);
        }
        let scene = crate::scene::Scene::build(d).unwrap();
        let t = trace(&scene, &settings(20_000, 1, false), 5);
        let on_quad = t.photons.iter().filter(|p| (2..4).contains(&p.object)).count();
        let share = on_quad as f64 / t.photons.len() as f64;
        assert!(
            t.photons.len() > 19_000 && (share - 0.225).abs() < 0.02,
            "{share} of {}",
            t.photons.len()
        );
        // Those on the quad are kept where the quad is at its start: the
        // beam at x = 0 meets it at x = -20 t there, over the quad's first
        // 4.5 units; those on the floor where they fell.
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for p in &t.photons {
            let on_quad = (2..4).contains(&p.object);
            assert_eq!(p.is_moving(), on_quad);
            if on_quad {
                assert!(
                    p.p.z.abs() < 1e-4 && p.p.y.abs() < 0.15 && p.p.x > -4.55 && p.p.x < 0.15,
                    "{:?}",
                    p.p
                );
                (lo, hi) = (lo.min(p.p.x), hi.max(p.p.x));
            } else {
                assert!(p.p.x.abs() < 0.15 && (p.p.z + 1.0).abs() < 1e-4, "{:?}", p.p);
            }
        }
        assert!(lo < -4.3 && hi > -0.2, "{lo} {hi}");
        // An SPPM pass's photons all leave at its time: before the quad
        // leaves the beam, all on it; after, none. Its visible points are
        // at that time too, so the photons stay where they fell.
        for (time, expected) in [(0.1, 1.0), (0.5, 0.0)] {
            let t = trace_at(&scene, &settings(2_000, 1, false), 5, Some(time));
            let on_quad = t.photons.iter().filter(|p| (2..4).contains(&p.object)).count();
            assert_eq!(on_quad as f64 / t.photons.len() as f64, expected, "time {time}");
            assert!(t.photons.iter().all(|p| !p.is_moving() && p.p.x.abs() < 0.15));
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
    fn caustic_photons_land_on_diffuse_surfaces_after_specular_ones() {
        let scene = crate::Scene::build(crate::scene::builtin::cornell_specular()).unwrap();
        let s = PhotonSettings {
            photons: 20_000,
            caustic_photons: 10_000,
            ..PhotonSettings::default()
        };
        let one = with_threads(Some(1), || trace_caustics(&scene, &s, 3)).unwrap();
        let two = with_threads(Some(2), || trace_caustics(&scene, &s, 3)).unwrap();
        assert_eq!(one.photons, two.photons);
        assert_eq!(one.unit, two.unit);
        // Whole rounds until at least the number asked for.
        assert!(one.photons.len() >= 10_000 && one.emitted % CAUSTIC_ROUND == 0);
        // Never on the glass sphere (which touches the floor at y = 1).
        let centre = Vec3::new(0.33, 0.7, -0.39);
        let on_sphere = |p: &Photon| p.p.y < 0.999 && ((p.p - centre).length() - 0.3).abs() < 1e-3;
        for p in &one.photons {
            assert!(p.is_caustic() && !p.is_direct());
            assert!(!on_sphere(p), "{:?}", p.p);
        }
        // The global map holds no photon on the sphere either, and its first
        // diffuse hits after glass or the mirror are tagged as caustics.
        let global = trace(&scene, &s, 3);
        assert!(!global.photons.iter().any(on_sphere));
        let s = PhotonSettings {
            store_first_hit: true,
            ..s
        };
        let global = trace(&scene, &s, 3);
        let caustic = global.photons.iter().filter(|p| p.is_caustic()).count();
        let direct = global.photons.iter().filter(|p| p.is_direct()).count();
        // A photon's first diffuse hit is direct unless it met the mirror or
        // the sphere first (about 1 in 12 here, by the caustic pass's yield).
        let yield_ = one.photons.len() as f64 / one.emitted as f64;
        let share = caustic as f64 / (caustic + direct) as f64;
        assert!((share - yield_).abs() < 0.2 * yield_, "{share} vs {yield_}");
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
