//! Reference path tracer: the unbiased estimate every other integrator is
//! measured against.
//!
//! pbrt-v4's `PathIntegrator` (13.4). At every vertex whose BSDF has a
//! diffuse or glossy lobe, next-event estimation: one light chosen by the
//! scene's light sampler (by power unless asked otherwise; pbrt-v4 scenes
//! by the light tree, `light::LightTree`), one point on it, one shadow ray.
//! Then the BSDF is sampled for the next direction and the throughput takes
//! f |cos| / pdf. The
//! light a path finds at such a vertex is sampled twice, by the shadow ray and
//! by the BSDF-sampled ray when it hits a light (or leaves the scene towards
//! an environment light), and the two are combined by multiple importance
//! sampling with the power heuristic (Veach 1997, 9.2), both densities in
//! solid angle at the vertex (the light's times the probability of choosing
//! it). `light_sampling` can keep either one alone (weight 1), for
//! comparisons. After a specular bounce there is no next-event estimation (a
//! shadow ray cannot hit the one direction a delta lobe scatters into), so a
//! light hit then, or by a camera ray, gives its whole Le. From the sixth
//! vertex on (as Mitsuba; pbrt-v4 starts at the third), Russian roulette on
//! the throughput times the square of the relative index of refraction
//! crossed (so that radiance compressed by refraction into glass is not
//! killed for it), with survival probability at most 0.95. Emissive
//! surfaces are not sampled by shadow rays, so their Le counts wherever a
//! path hits them.
//!
//! With `guide_photons`, caustic photons are traced first
//! (`photon::guide`), and at a vertex whose BSDF reflects diffusely (a
//! Lambertian surface, or a coated one) the next direction is drawn from
//! the photons' directions there or from the BSDF, one or the other with
//! probability one half each (a coat's specular reflection keeps the
//! BSDF's half of its probability). Either way the
//! sample's density is the mixture's, in the throughput and in both MIS
//! weights (the light sample's against it, and a light the bounce finds),
//! so the estimate stays unbiased whatever the photons say: they only
//! move samples towards lights seen in glossy and specular surfaces,
//! whose light a cosine-distributed bounce almost never finds. (Not yet
//! in scenes with media or subsurface scattering.)
//!
//! Scenes with participating media are path traced by `volpath`, the same
//! estimator with the media's absorption and scattering along each segment.
//!
//! Parameters: `--spp N` samples per pixel [64]; `--max-depth D`, the most
//! bounces (0: emitted light only, 1: direct light only; default: no limit,
//! roulette ends paths).
//!
//! The render is progressive ([`Progressive`]): passes of consecutive sample
//! indices, max(ceil(spp / 64), 4) samples each (fewer when spp is below 4),
//! added onto per-pixel sums. Each
//! pixel's samples are added in index order whatever the passes, so the image
//! is the one-pass render bit for bit, and a render can be checkpointed
//! between passes and resumed (`integrator::checkpoint`).

use super::bdpt::{trace_light_pass, Bdpt};
use super::checkpoint::{self, Buffer};
use super::direct::{emitted_radiance, escaped_radiance, light_sample_u, sample_bsdf, sample_direct_with};
use super::{accumulate_tiles, merge_sums, IntegratorKind, LightSampling, RadianceEstimator, RayStats, RenderSettings};
use crate::bsdf::{Bsdf, BsdfSample, BxdfFlags, TransportMode};
use crate::film::{Film, PixelRect, PixelSum};
use crate::light::LightContext;
use crate::math::{offset_origin, Ray, Vec3};
use crate::photon::{GuideCell, GuideStats, PhotonGuide};
use crate::sampling::Sampler;
use crate::scene::Scene;
use std::sync::atomic::AtomicBool;

/// A render is cut into at most this many passes.
const MAX_PASSES: u32 = 64;
/// Samples a pixel in a pass, at least: each pass has a fixed cost (its
/// buffers, and both threads waiting for the last tile), which at one
/// sample a pass took 14% of a 64-spp render's wall time on `cornell-box`
/// (BENCHMARKS.md, "Against Mitsuba 3").
const MIN_SAMPLES_PER_PASS: u32 = 4;

/// Roulette starts after this many bounces: Mitsuba's `rr_depth` of 5 rather
/// than pbrt-v4's 2, since the noise the longer paths save outweighs their
/// time (BENCHMARKS.md, "Low-discrepancy samples and roulette depth").
pub(super) const ROULETTE_DEPTH: u32 = 5;
/// Survival probability cap, so that paths in a white furnace end too.
pub(super) const MAX_SURVIVAL: f32 = 0.95;
/// Surface hits of a guide's photon paths at most.
const GUIDE_HITS: u32 = 8;

pub struct PathTracer {
    /// Most bounces: emission is counted up to this many bounces, next-event
    /// estimation at one fewer (1: direct light only); `None`: unlimited.
    pub max_depth: Option<u32>,
    pub light_sampling: LightSampling,
    /// Microfacet surfaces made glossy after the path's first non-specular
    /// bounce (pbrt-v4's `regularize`).
    pub regularize: bool,
    /// Caustic photons' directions, mixed into diffuse bounces.
    pub guide: Option<PhotonGuide>,
}

/// The share of a guided vertex's bounces drawn from the guide; the rest
/// follow the BSDF, so that light the photons never brought is still found.
const GUIDED_SHARE: f32 = 0.5;

/// The density of direction `wi` at a guided vertex: the mixture of the
/// photons' cell and the BSDF (whose own density there is `pdf_bsdf`).
#[inline]
fn guided_pdf(cell: GuideCell, wi: Vec3, pdf_bsdf: f32) -> f32 {
    GUIDED_SHARE * cell.pdf(wi) + (1.0 - GUIDED_SHARE) * pdf_bsdf
}

/// A diffuse vertex's next direction from the mixture of its BSDF and the
/// photons' cell: the density of either choice is the mixture's. The
/// number that chooses is the lobe choice's (which a lone diffuse lobe
/// leaves unread), stretched back to [0, 1) for the BSDF's own choice.
fn sample_guided(bsdf: &Bsdf, wo: Vec3, cell: GuideCell, sampler: &mut Sampler) -> Option<BsdfSample> {
    let uc = sampler.next_f32();
    let u = sampler.next_2d();
    let mixed = |wi: Vec3, pdf_bsdf: f32| guided_pdf(cell, wi, pdf_bsdf);
    if uc < GUIDED_SHARE {
        let wi = cell.sample(uc / GUIDED_SHARE, u);
        let (f, pdf_bsdf) = bsdf.f_pdf(wo, wi, TransportMode::Radiance);
        let pdf = mixed(wi, pdf_bsdf);
        (f != Vec3::ZERO && pdf > 0.0).then_some(BsdfSample {
            f,
            wi,
            pdf,
            flags: BxdfFlags::DIFFUSE_REFLECTION,
            eta: 1.0,
        })
    } else {
        let uc = (uc - GUIDED_SHARE) / (1.0 - GUIDED_SHARE);
        let mut bs = bsdf.sample_f(wo, uc, u, TransportMode::Radiance)?;
        // A smooth coat's reflection is a delta no guided direction meets:
        // its probability is the BSDF's share of it.
        bs.pdf = if bs.is_specular() {
            (1.0 - GUIDED_SHARE) * bs.pdf
        } else {
            mixed(bs.wi, bs.pdf)
        };
        Some(bs)
    }
}

impl RadianceEstimator for PathTracer {
    fn li(&self, scene: &Scene, camera_ray: &Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Vec3 {
        if scene.has_media() || scene.has_subsurface() {
            return super::volpath::li(self, scene, camera_ray, sampler, stats);
        }
        let mut l = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        let mut ray = *camera_ray;
        let mut depth = 0;
        // Squared relative indices of refraction crossed, for the roulette.
        let mut eta_scale = 1.0f32;
        // Where the last non-specular bounce left from and its density; `None`
        // after a specular bounce or for the camera ray (no light sample competed).
        let mut from: Option<(LightContext, f32)> = None;
        // The ray's differentials, while it has any: the camera's, carried
        // through specular bounces (texture footprints).
        let mut diffs = None;
        // Whether the path has bounced off a non-specular lobe (regularization
        // starts there, as in pbrt-v4).
        let mut rough_before = false;
        // Emission found by a BSDF-sampled ray: MIS-weighted, or all or nothing.
        let weigh = |from: Option<(LightContext, f32)>| match (from, self.light_sampling) {
            (None, _) | (_, LightSampling::Mis) => (from, 1.0),
            (Some(_), LightSampling::Bsdf) => (None, 1.0),
            (Some(_), LightSampling::Light) => (None, 0.0),
        };
        loop {
            let Some(hit) = scene.intersect(&ray, 0.0, f32::INFINITY) else {
                let (from, w) = weigh(from);
                l += beta * escaped_radiance(scene, &ray, from) * w;
                break;
            };
            if let Some(li) = hit.light {
                let (from, w) = weigh(from);
                l += beta * emitted_radiance(scene, li as usize, &ray, &hit, from) * w;
                if !scene.reflects(&hit) {
                    break;
                }
            }
            let m = scene.material(hit.material);
            l += beta * m.le();
            // The last vertex only adds what it emits (D vertices: D bounces).
            if self.max_depth.is_some_and(|d| depth >= d) {
                break;
            }
            let wo = -ray.d;
            depth += 1;
            // The camera ray's hit has the ray's own texture footprint.
            if depth == 1 {
                diffs = scene.camera_differentials(&hit);
            }
            let sp = scene.surface_seen(&hit, diffs.as_ref());
            let mut bsdf = m.bsdf(&sp, wo);
            bsdf.carry(beta);
            if self.regularize && rough_before {
                bsdf.bxdf.regularize();
            }
            let flags = bsdf.flags();
            if flags.is_empty() {
                break;
            }
            // The light sample's numbers are drawn first, as always, but the
            // BSDF is sampled before the shadow ray is traced: the next
            // direction's chain of divisions and square roots then runs while
            // the processor works through the light sample, which does not
            // depend on it, instead of holding up the next ray.
            let nee = flags.is_non_specular() && self.light_sampling != LightSampling::Bsdf;
            let u_light = nee.then(|| light_sample_u(scene, sampler));
            let cell = match &self.guide {
                // Surfaces that reflect diffusely, coated or not: their
                // densities are exact, so the mixture's is.
                Some(g) if flags.is_diffuse() && !flags.is_transmissive() => {
                    g.cell(hit.p, if hit.ng.dot(wo) < 0.0 { -hit.ng } else { hit.ng })
                }
                _ => None,
            };
            let bs = match cell {
                Some(c) => sample_guided(&bsdf, wo, c, sampler),
                None => sample_bsdf(&bsdf, wo, sampler),
            };
            if let Some(u) = u_light {
                let mis = self.light_sampling == LightSampling::Mis;
                l += beta
                    * match cell {
                        Some(c) => {
                            sample_direct_with(scene, &hit, wo, &bsdf, mis, u, stats, |wi, pdf| guided_pdf(c, wi, pdf))
                        }
                        None => sample_direct_with(scene, &hit, wo, &bsdf, mis, u, stats, |_, pdf| pdf),
                    };
            }
            let Some(bs) = bs else {
                break;
            };
            if !hit.keeps_side(wo, bs.wi, bs.flags) {
                break;
            }
            beta *= bs.f * (bs.wi.dot(bsdf.frame.z).abs() / bs.pdf);
            if !beta.is_finite() || beta.max_element() <= 0.0 {
                break;
            }
            if bs.is_transmission() {
                eta_scale *= bs.eta * bs.eta;
            }
            from = (!bs.is_specular()).then_some((LightContext::surface(hit.p, bsdf.frame.z), bs.pdf));
            rough_before |= !bs.is_specular();
            diffs = diffs.filter(|_| bs.is_specular()).and_then(|d| {
                scene.specular_differentials(&hit, &d, (wo, bs.wi), bs.is_transmission(), bs.eta, bsdf.frame.z)
            });
            if depth >= ROULETTE_DEPTH {
                let q = (beta * eta_scale).max_element().min(MAX_SURVIVAL);
                if sampler.next_f32() >= q {
                    break;
                }
                beta /= q;
            }
            stats.other_rays += 1;
            ray = Ray::timed(offset_origin(hit.p, hit.ng, bs.wi), bs.wi, hit.time);
        }
        l
    }
}

/// The path tracer's render in passes: the per-pixel sums of the samples so far.
pub struct Progressive<'a> {
    settings: &'a RenderSettings,
    /// The path tracer, or the bidirectional one (which shares its passes).
    est: Box<dyn RadianceEstimator>,
    rect: PixelRect,
    sums: Vec<PixelSum>,
    /// The pass in flight, zero between passes: merged into `sums` only
    /// when every tile is done.
    pass: Vec<PixelSum>,
    /// The bidirectional path tracer's light tracing, when it has any: its
    /// splatted light so far and the pass in flight's (empty otherwise).
    light_tracer: Option<Bdpt>,
    light: Vec<PixelSum>,
    light_pass: Vec<PixelSum>,
    stats: RayStats,
    guide_stats: Option<GuideStats>,
}

impl<'a> Progressive<'a> {
    pub fn new(scene: &Scene, settings: &'a RenderSettings) -> Self {
        let cam = &scene.camera;
        let rect = settings.crop.unwrap_or(PixelRect::full(cam.width, cam.height));
        let bdpt = || Bdpt {
            max_depth: settings.max_depth,
            light_tracing: cam.is_pinhole(),
            regularize: settings.regularize,
        };
        let plain = super::plain::PlainPathTracer::for_scene(scene, settings);
        let mut guide_stats = None;
        let est: Box<dyn RadianceEstimator> = match (settings.integrator, plain) {
            (IntegratorKind::Bdpt, _) => Box::new(bdpt()),
            (_, Some(plain)) => Box::new(plain),
            _ => Box::new(PathTracer {
                max_depth: settings.max_depth,
                light_sampling: settings.light_sampling,
                regularize: settings.regularize,
                // Scenes with media are traced by `volpath`, which has no guide.
                guide: (settings.guide_photons > 0 && !scene.has_media() && !scene.has_subsurface()).then(|| {
                    // Photon paths as long as the camera's may be (its
                    // depth, within 2 to 8 surface hits).
                    let hits = settings.max_depth.map_or(GUIDE_HITS, |d| d.clamp(2, GUIDE_HITS));
                    let (guide, stats) = crate::photon::build_guide(scene, settings.guide_photons, hits, settings.seed);
                    guide_stats = Some(stats);
                    guide
                }),
            }),
        };
        let light_tracer = (settings.integrator == IntegratorKind::Bdpt && cam.is_pinhole()).then(bdpt);
        let pixels = rect.width() as usize * rect.height() as usize;
        let light_pixels = if light_tracer.is_some() { pixels } else { 0 };
        Progressive {
            settings,
            est,
            rect,
            sums: vec![PixelSum::default(); pixels],
            pass: vec![PixelSum::default(); pixels],
            light_tracer,
            light: vec![PixelSum::default(); light_pixels],
            light_pass: vec![PixelSum::default(); light_pixels],
            stats: RayStats::default(),
            guide_stats,
        }
    }

    /// What building the photon guide did, when there is one.
    pub fn guide_stats(&self) -> Option<GuideStats> {
        self.guide_stats
    }

    /// Samples per pass for a render of `spp` samples per pixel.
    pub fn samples_per_pass(spp: u32) -> u32 {
        spp.div_ceil(MAX_PASSES).max(MIN_SAMPLES_PER_PASS.min(spp)).max(1)
    }

    pub fn passes_for(spp: u32) -> u32 {
        spp.div_ceil(Self::samples_per_pass(spp))
    }

    fn samples_after(&self, passes: u32) -> u32 {
        (passes * Self::samples_per_pass(self.settings.spp)).min(self.settings.spp)
    }

    /// The image after `passes` passes (the filter-weighted mean of the
    /// samples so far) and the rays this run traced.
    pub fn finish(self, passes: u32) -> (Film, RayStats) {
        let (w, h) = (self.rect.width(), self.rect.height());
        let film = if self.light_tracer.is_some() {
            // Light tracing's estimate of a pixel: its splats over the
            // samples a pixel so far (each pixel and sample of the frame
            // traced one particle).
            let scale = 1.0 / self.samples_after(passes).max(1) as f32;
            Film::from_sums_and_light(w, h, &self.sums, &self.light, scale)
        } else {
            Film::from_sums(w, h, &self.sums)
        };
        (film, self.stats)
    }
}

impl checkpoint::Progressive for Progressive<'_> {
    fn key(&self) -> String {
        let s = self.settings;
        let r = self.rect;
        format!(
            "integrator={} film=splat spp={} samples_per_pass={} max_depth={:?} light_sampling={} sampler={} \
             filter={:?} seed={} crop={},{},{},{}{}",
            s.integrator.name(),
            s.spp,
            Self::samples_per_pass(s.spp),
            s.max_depth,
            s.light_sampling.name(),
            s.sampler.name(),
            s.filter,
            s.seed,
            r.x0,
            r.y0,
            r.x1,
            r.y1,
            // Absent when unset, so older checkpoints still match.
            s.max_component.map_or(String::new(), |m| format!(" max_component={m}"))
                + &if s.guide_photons > 0 {
                    format!(" guide_photons={}", s.guide_photons)
                } else {
                    String::new()
                }
        )
    }

    fn total_passes(&self) -> u32 {
        Self::passes_for(self.settings.spp)
    }

    fn ticks_after(&self, passes: u32) -> u64 {
        super::tile_count(self.rect.width(), self.rect.height()) * passes as u64
    }

    fn run_pass(&mut self, scene: &Scene, pass: u32, on_tile: super::Progress) -> bool {
        let samples = self.samples_after(pass)..self.samples_after(pass + 1);
        // Tiles finished before an interruption must not count: they go to
        // the pass's own sums, merged when it is complete.
        let never = AtomicBool::new(false);
        let ntiles = super::tile_count(self.rect.width(), self.rect.height());
        let tiles = accumulate_tiles(
            scene,
            self.settings,
            self.est.as_ref(),
            samples.clone(),
            &mut self.pass,
            &never,
            on_tile,
        );
        let traced = match (&tiles, &self.light_tracer) {
            (Some((_, done)), Some(lt)) if *done == ntiles => {
                trace_light_pass(lt, scene, self.settings, samples, &mut self.light_pass, on_tile)
            }
            _ => Some(RayStats::default()),
        };
        match (tiles, traced) {
            (Some((stats, done)), Some(light_stats)) if done == ntiles => {
                merge_sums(&mut self.sums, &mut self.pass);
                merge_sums(&mut self.light, &mut self.light_pass);
                self.stats.add(&stats);
                self.stats.add(&light_stats);
                true
            }
            _ => {
                self.pass.fill(PixelSum::default());
                self.light_pass.fill(PixelSum::default());
                false
            }
        }
    }

    fn save(&self) -> Vec<(String, Buffer)> {
        let flat = |sums: &[PixelSum]| Buffer::I128(sums.iter().flat_map(|v| v.to_array()).collect());
        let mut buffers = vec![("sums".into(), flat(&self.sums))];
        if self.light_tracer.is_some() {
            buffers.push(("light".into(), flat(&self.light)));
        }
        buffers
    }

    fn restore(&mut self, buffers: Vec<(String, Buffer)>) -> std::result::Result<(), String> {
        let want = self.sums.len() * 4;
        let fill = |sums: &mut [PixelSum], v: &[i128]| {
            for (s, c) in sums.iter_mut().zip(v.chunks_exact(4)) {
                *s = PixelSum::from_array([c[0], c[1], c[2], c[3]]);
            }
        };
        match (&buffers[..], self.light_tracer.is_some()) {
            ([(tag, Buffer::I128(v))], false) if tag == "sums" && v.len() == want => {
                fill(&mut self.sums, v);
                Ok(())
            }
            ([(tag, Buffer::I128(v)), (ltag, Buffer::I128(l))], true)
                if tag == "sums" && ltag == "light" && v.len() == want && l.len() == want =>
            {
                fill(&mut self.sums, v);
                fill(&mut self.light, l);
                Ok(())
            }
            (_, false) => Err(format!("expected one i128 buffer 'sums' of {want} values")),
            (_, true) => Err(format!(
                "expected i128 buffers 'sums' and 'light' of {want} values each"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::integrator::analytic::{closed_sphere, path_settings};
    use crate::integrator::{render, IntegratorKind, RenderSettings};
    use crate::material::Material;
    use crate::math::Vec3;
    use std::f32::consts::PI;

    #[test]
    fn white_furnace_converges_to_le_over_one_minus_albedo() {
        for (a, le) in [(0.5, 1.0), (0.8, 0.3)] {
            let scene = closed_sphere(
                Material::Emissive {
                    albedo: Vec3::splat(a),
                    le: Vec3::new(le, 2.0 * le, 0.5 * le),
                },
                None,
                16,
            );
            let film = render(&scene, &path_settings(256, None), &|| {}).unwrap().film;
            let mean = film.mean(0, 0, 16, 16);
            let expected = Vec3::new(le, 2.0 * le, 0.5 * le) / (1.0 - a);
            let err = ((mean - expected) / expected).abs().max_element();
            assert!(err < 0.01, "albedo {a}: {mean:?} vs {expected:?}");
        }
    }

    #[test]
    fn max_component_scales_each_sample_down_keeping_its_hue() {
        // Every sample here is at least Le (1 + a + ... + a^4), whose green
        // is above 1: clamped to 1, each sample is Le / Le.y exactly.
        let le = Vec3::new(1.0, 2.0, 0.5);
        let scene = closed_sphere(
            Material::Emissive {
                albedo: Vec3::splat(0.5),
                le,
            },
            None,
            8,
        );
        let free = render(&scene, &path_settings(16, None), &|| {}).unwrap().film;
        assert!((free.mean(0, 0, 8, 8).y - 4.0).abs() < 0.1);
        for integrator in [IntegratorKind::Path, IntegratorKind::Direct] {
            let s = RenderSettings {
                integrator,
                max_component: Some(1.0),
                ..path_settings(16, None)
            };
            let film = render(&scene, &s, &|| {}).unwrap().film;
            for p in &film.pixels {
                assert!((*p - le / 2.0).abs().max_element() < 1e-5, "{integrator:?}: {p:?}");
            }
        }
    }

    #[test]
    fn depth_limit_counts_bounces() {
        // With at most D bounces, L = Le (1 + a + ... + a^D); D = 0 sees emission only.
        let (a, le) = (0.5, 1.0);
        let scene = closed_sphere(
            Material::Emissive {
                albedo: Vec3::splat(a),
                le: Vec3::splat(le),
            },
            None,
            8,
        );
        // The first five path vertices are always traced (exact); later ones
        // face Russian roulette (right on average).
        for (d, tolerance) in [(0u32, 1e-4), (1, 1e-4), (4, 1e-4), (8, 0.01)] {
            let film = render(&scene, &path_settings(256, Some(d)), &|| {}).unwrap().film;
            let expected = (0..=d).map(|k| a.powi(k as i32)).sum::<f32>() * le;
            let mean = film.mean(0, 0, 8, 8).x;
            assert!(
                (mean - expected).abs() / expected < tolerance,
                "depth {d}: {mean} vs {expected}"
            );
        }
    }

    #[test]
    fn lossless_glass_and_mirror_vanish_in_a_white_furnace() {
        // In uniform radiance a lossless mirror or glass ball changes nothing:
        // refraction scales radiance by 1/eta^2 going in and eta^2 coming out.
        // A missing factor, or light counted by both shadow rays and specular
        // hits, shows in the pixels that see the balls.
        use crate::integrator::analytic::furnace_with_balls;
        let (a, le) = (0.5, Vec3::new(1.0, 0.5, 0.25));
        let scene = furnace_with_balls(
            Material::Emissive {
                albedo: Vec3::splat(a),
                le,
            },
            &[
                (Vec3::new(-0.15, 0.0, 0.75), 0.15, Material::glass(1.5)),
                (Vec3::new(0.15, 0.0, 0.75), 0.12, Material::mirror(Vec3::ONE)),
            ],
            16,
        );
        let film = render(&scene, &path_settings(256, None), &|| {}).unwrap().film;
        let expected = le / (1.0 - a);
        // Each ball covers the middle columns of its half of the image.
        for (x0, x1) in [(3, 7), (9, 13)] {
            let mean = film.mean(x0, 6, x1, 10);
            let err = ((mean - expected) / expected).abs().max_element();
            eprintln!("columns {x0}..{x1}: {mean:?} vs {expected:?}");
            assert!(err < 0.02, "columns {x0}..{x1}: {mean:?} vs {expected:?}");
        }
    }

    #[test]
    fn a_dispersive_ball_shows_each_channel_what_its_own_index_shows() {
        // A glass ball in front of a bright ball, inside a furnace: what the
        // camera sees through it depends much on the index. A dispersive
        // ball's channel c must be, on average, the picture of a glass of
        // channel c's index, and a lossless one must vanish in the furnace.
        use crate::integrator::analytic::furnace_with_balls;
        use crate::material::Roughness;
        let eta = Vec3::new(1.2, 1.5, 2.0);
        let wall = Material::Emissive {
            albedo: Vec3::splat(0.5),
            le: Vec3::ONE,
        };
        let bright = Material::Emissive {
            albedo: Vec3::ZERO,
            le: Vec3::splat(8.0),
        };
        let region = |glass: Material| {
            let scene = furnace_with_balls(
                wall.clone(),
                &[
                    (Vec3::new(0.0, 0.0, 0.6), 0.12, glass),
                    (Vec3::new(0.03, 0.02, 0.9), 0.06, bright.clone()),
                ],
                16,
            );
            let film = render(&scene, &path_settings(512, None), &|| {}).unwrap().film;
            film.mean(5, 5, 11, 11)
        };
        let dispersive = region(Material::Dispersive {
            eta,
            roughness: Roughness::SMOOTH.into(),
        });
        let single = [0, 1, 2].map(|c| region(Material::glass(eta[c]))[c]);
        for c in 0..3 {
            let err = (dispersive[c] - single[c]).abs() / single[c];
            assert!(err < 0.03, "channel {c}: {} vs {}", dispersive[c], single[c]);
        }
        // The test can tell the indices apart.
        let (lo, hi) = (
            single.iter().copied().fold(f32::MAX, f32::min),
            single.iter().copied().fold(0.0, f32::max),
        );
        assert!(hi / lo > 1.2, "{single:?}");

        let scene = furnace_with_balls(
            wall.clone(),
            &[(
                Vec3::new(0.0, 0.0, 0.6),
                0.12,
                Material::Dispersive {
                    eta,
                    roughness: Roughness::SMOOTH.into(),
                },
            )],
            16,
        );
        let film = render(&scene, &path_settings(256, None), &|| {}).unwrap().film;
        let mean = film.mean(5, 5, 11, 11);
        assert!((mean - Vec3::splat(2.0)).abs().max_element() < 0.04, "{mean}");
    }

    #[test]
    fn rough_lossless_conductors_vanish_in_a_white_furnace() {
        // The same with rough conductor balls of reflectance 1 (alpha 0.05
        // and 0.02): single-scattering microfacets lose light only to masking
        // at grazing angles (7% at 85 degrees for alpha 0.05), about 1% over
        // a ball's disc. (A rough glass ball loses more: light trapped inside
        // by total internal reflection meets the surface at grazing angles
        // many times; the BSDF's own furnace test checks it.)
        use crate::integrator::analytic::furnace_with_balls;
        use crate::material::{ConductorFresnel, Roughness};
        let (a, le) = (0.5, Vec3::new(1.0, 0.5, 0.25));
        let rough = |alpha: f32| Material::Conductor {
            fresnel: ConductorFresnel::Reflectance(Vec3::ONE.into()),
            roughness: Roughness::isotropic(alpha, false).into(),
        };
        let scene = furnace_with_balls(
            Material::Emissive {
                albedo: Vec3::splat(a),
                le,
            },
            &[
                (Vec3::new(-0.15, 0.0, 0.75), 0.15, rough(0.05)),
                (Vec3::new(0.15, 0.0, 0.75), 0.12, rough(0.02)),
            ],
            16,
        );
        let film = render(&scene, &path_settings(256, None), &|| {}).unwrap().film;
        let expected = le / (1.0 - a);
        for (x0, x1) in [(3, 7), (9, 13)] {
            let mean = film.mean(x0, 6, x1, 10);
            let err = ((mean - expected) / expected).abs().max_element();
            assert!(err < 0.02, "columns {x0}..{x1}: {mean:?} vs {expected:?}");
        }
    }

    #[test]
    fn sphere_lit_from_its_centre_matches_radiosity() {
        // Direct irradiance E0 = Phi / (4 pi R^2) everywhere on the wall; with every
        // bounce landing on the wall again, L = a E0 / (pi (1 - a)).
        let (a, phi) = (0.6, 10.0);
        let scene = closed_sphere(Material::diffuse(a, a, a), Some((0.01, phi)), 16);
        let film = render(&scene, &path_settings(256, None), &|| {}).unwrap().film;
        let e0 = phi / (4.0 * PI);
        let expected = a * e0 / (PI * (1.0 - a));
        let mean = film.mean(0, 0, 16, 16).x;
        assert!((mean - expected).abs() / expected < 0.01, "{mean} vs {expected}");
    }

    #[test]
    fn light_bsdf_and_mis_sampling_agree_with_the_form_factor() {
        use super::{LightSampling, PathTracer};
        use crate::integrator::{RadianceEstimator, RayStats, SamplerKind};
        use crate::math::Ray;
        let scene = crate::Scene::build(crate::integrator::analytic::floor_under_quad()).unwrap();
        // Reflected radiance albedo / pi * E, E = L pi F (the rectangle form factor, a = b = 1).
        let f = 2.0 * (1.0 / 2f64.sqrt()) * (1.0 / 2f64.sqrt()).atan() / (2.0 * std::f64::consts::PI);
        let expected = 0.5 * 2.0 * f;
        let ray = Ray::new(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.0, 0.0, -1.0));
        // Pixels of 16 samples: a pixel's Sobol samples are stratified
        // together, different pixels' are independent (or, Z-order, stratified
        // together too, which only makes the spread an overestimate), so the
        // standard error comes from the spread of the pixel means.
        let (pixels, spp) = (2500u64, 16u32);
        for kind in [SamplerKind::Sobol, SamplerKind::Independent, SamplerKind::ZSobol] {
            let mut errors = vec![];
            for mode in [LightSampling::Mis, LightSampling::Light, LightSampling::Bsdf] {
                let est = PathTracer {
                    max_depth: Some(1),
                    light_sampling: mode,
                    regularize: false,
                    guide: None,
                };
                let (mut sum, mut sum2) = (0.0f64, 0.0f64);
                let mut stats = RayStats::default();
                for pixel in 0..pixels {
                    let mut pixel_sum = 0.0f64;
                    for i in 0..spp {
                        let (x, y) = ((pixel % 50) as u32, (pixel / 50) as u32);
                        let mut sampler = crate::integrator::camera_sampler(kind, 3, x, y, 50, spp, i);
                        pixel_sum += est.li(&scene, &ray, &mut sampler, &mut stats).x as f64;
                    }
                    let v = pixel_sum / spp as f64;
                    sum += v;
                    sum2 += v * v;
                }
                let mean = sum / pixels as f64;
                let std_err = ((sum2 / pixels as f64 - mean * mean) / pixels as f64).sqrt();
                // Within four standard errors (and the estimators really differ).
                assert!(
                    (mean - expected).abs() < 4.0 * std_err + 1e-4,
                    "{kind:?} {mode:?}: {mean} vs {expected} (standard error {std_err})"
                );
                errors.push(std_err);
            }
            // Light sampling beats BSDF sampling here, and MIS keeps close to the better one.
            assert!(
                errors[1] < errors[2] && errors[0] < 1.5 * errors[1],
                "{kind:?}: {errors:?}"
            );
            eprintln!("{kind:?}: standard errors (mis, light, bsdf) {errors:?}");
        }
    }

    #[test]
    fn a_tree_of_one_quad_chooses_by_power_and_two_quads_make_a_tree() {
        use crate::light::{Light, LightSamplerKind};
        let with = |kind: LightSamplerKind, second_quad: bool| {
            let mut d = crate::integrator::analytic::floor_under_quad();
            if second_quad {
                let far: Vec<Light> = d
                    .lights
                    .iter()
                    .map(|l| match l {
                        Light::Triangle {
                            vertices,
                            radiance,
                            two_sided,
                            image,
                        } => Light::Triangle {
                            vertices: vertices.map(|v| v + Vec3::new(4.0, 0.0, 0.0)),
                            radiance: *radiance,
                            two_sided: *two_sided,
                            image: image.clone(),
                        },
                        _ => unreachable!("the floor's light is a quad"),
                    })
                    .collect();
                d.lights.extend(far);
            }
            d.light_sampler = kind;
            crate::Scene::build(d).unwrap()
        };
        // The quad's two triangles are one leaf and nothing is apart from
        // it: the tree would choose by power, so the scene does, numbers
        // and all, and the images are the same bit for bit.
        let tree = with(LightSamplerKind::Bvh, false);
        assert!(!tree.chooses_by_tree());
        let film = |scene: &crate::Scene| render(scene, &path_settings(8, None), &|| {}).unwrap().film;
        let power = film(&with(LightSamplerKind::Power, false));
        assert!(power.mean(0, 0, 8, 8).x > 0.0);
        assert_eq!(film(&tree).pixels, power.pixels);
        // Two quads apart are two leaves to weigh at every point.
        assert!(with(LightSamplerKind::Bvh, true).chooses_by_tree());
        assert!(!with(LightSamplerKind::Power, true).chooses_by_tree());
    }
}
