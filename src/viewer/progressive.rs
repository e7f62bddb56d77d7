//! Progressive refinement for the preview window: a quick low-resolution
//! image first, then passes that add camera samples to per-pixel sums while
//! nothing moves, until the render's full sample count is reached.
//!
//! Pass k adds sample indices [a_k, b_k) of each pixel's fixed sequence
//! through `integrator::accumulate_tiles`, the loop the offline render runs
//! over 0..spp in one go; so after the last pass the image is bit for bit the
//! offline render with the same settings and seed. Pass sizes double (1, 1,
//! 2, 4, ...) so the first images come fast and later passes spend little on
//! per-pass overhead, the classic progressive scheme of interactive ray
//! tracers (e.g. pbrt-v4's and Mitsuba's interactive viewers).
//!
//! What renders is a [`ViewIntegrator`]: besides the per-ray estimators it
//! has the light transport it caches. [`PhotonView`] traces the photon map
//! the offline render traces (same settings, same seed) once per light
//! position: [`ViewIntegrator::light_moved`] forgets it, and
//! [`ViewIntegrator::prepare`] traces it, stopping when a move cancels it and
//! keeping the photon chunks already traced, so a camera move costs no
//! photons at all.
//!
use crate::film::{Film, PixelSum};
use crate::integrator::photon::{map_settings, with_caustics, PhotonPipeline};
use crate::integrator::{accumulate_tiles, direct, IntegratorKind, RadianceEstimator, RayStats, RenderSettings};
use crate::math::{Vec2, Vec3};
use crate::photon::trace::ResumableTrace;
use crate::photon::{map_from_trace, PhotonMap, PhotonStats};
use crate::sampling::{Rng, Sampler};
use crate::scene::Scene;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

/// Side, in pixels, of the blocks the first low-resolution pass shades with one ray each.
pub const LOW_RES_BLOCK: u32 = 4;

/// An integrator as the preview window drives it.
pub trait ViewIntegrator: Send {
    /// The scene's lights moved: forget light transport traced for the old
    /// positions. Camera moves never call it.
    fn light_moved(&mut self);

    /// Brings the cached light transport up to date with the scene's lights
    /// before the accumulation passes. Returns false when `cancel` stopped
    /// it; the work done so far is kept, and the next call carries on.
    fn prepare(&mut self, scene: &Scene, settings: &RenderSettings, cancel: &AtomicBool) -> bool;

    /// The estimator whose samples accumulate into the image (after `prepare`).
    fn estimator(&self) -> Box<dyn RadianceEstimator + '_>;

    /// A cheap estimator (direct light) for the first low-resolution pass,
    /// which needs no `prepare`.
    fn low_res_estimator(&self) -> &dyn RadianceEstimator;

    /// What `prepare` still has to do, for the title bar (None when nothing).
    fn pending(&self) -> Option<String> {
        None
    }
}

/// Direct lighting: nothing to trace when the light moves.
pub struct DirectView {
    full: direct::DirectLighting,
    quick: direct::DirectLighting,
}

impl DirectView {
    pub fn new(settings: &RenderSettings) -> Self {
        DirectView {
            full: direct::DirectLighting {
                shadow_samples: settings.shadow_samples,
            },
            quick: direct::DirectLighting {
                shadow_samples: settings.shadow_samples.min(1),
            },
        }
    }
}

impl ViewIntegrator for DirectView {
    fn light_moved(&mut self) {}

    fn prepare(&mut self, _scene: &Scene, _settings: &RenderSettings, _cancel: &AtomicBool) -> bool {
        true
    }

    fn estimator(&self) -> Box<dyn RadianceEstimator + '_> {
        Box::new(self.full)
    }

    fn low_res_estimator(&self) -> &dyn RadianceEstimator {
        &self.quick
    }
}

/// Photon mapping: direct light by shadow rays plus indirect light from a
/// photon map traced for the current light positions.
pub struct PhotonView {
    settings: RenderSettings,
    quick: direct::DirectLighting,
    /// The trace in progress, when the map is not there yet.
    trace: Option<ResumableTrace>,
    /// Time spent on the trace in progress, over its runs.
    trace_seconds: f64,
    /// The offline render's maps and precomputed irradiance for the current
    /// lights; `None` until traced.
    pipeline: Option<PhotonPipeline>,
}

impl PhotonView {
    pub fn new(settings: &RenderSettings) -> Self {
        PhotonView {
            settings: settings.clone(),
            quick: direct::DirectLighting {
                shadow_samples: settings.shadow_samples.min(1),
            },
            trace: None,
            trace_seconds: 0.0,
            pipeline: None,
        }
    }

    /// The photon map for the current lights, once `prepare` has finished.
    pub fn map(&self) -> Option<&PhotonMap> {
        self.pipeline.as_ref().and_then(|p| p.maps().global.as_ref())
    }
}

impl ViewIntegrator for PhotonView {
    fn light_moved(&mut self) {
        self.trace = None;
        self.trace_seconds = 0.0;
        self.pipeline = None;
    }

    fn prepare(&mut self, scene: &Scene, _settings: &RenderSettings, cancel: &AtomicBool) -> bool {
        if self.pipeline.is_some() {
            return true;
        }
        let photon = map_settings(&self.settings);
        let mut global = None;
        let mut stats = PhotonStats::default();
        if photon.photons > 0 {
            // The offline render's `build_map`, in resumable chunks.
            let start = std::time::Instant::now();
            let trace = self
                .trace
                .get_or_insert_with(|| ResumableTrace::new(scene, &photon, self.settings.seed));
            let complete = trace.run(scene, &|| cancel.load(Ordering::Relaxed));
            self.trace_seconds += start.elapsed().as_secs_f64();
            if !complete {
                return false;
            }
            if let Some((map, s)) = self
                .trace
                .take()
                .map(|t| map_from_trace(t.finish(), self.trace_seconds))
            {
                (global, stats) = (Some(map), s);
            }
        }
        // The rest as offline; neither part is cancellable, and both take a
        // fraction of the global trace's time.
        let maps = with_caustics(scene, &self.settings, global, stats);
        self.pipeline = Some(PhotonPipeline::new(scene, maps, &self.settings));
        true
    }

    fn estimator(&self) -> Box<dyn RadianceEstimator + '_> {
        match &self.pipeline {
            Some(p) => Box::new(p.estimator()),
            // Not prepared: nothing but direct light is known.
            None => Box::new(direct::DirectLighting {
                shadow_samples: self.settings.shadow_samples,
            }),
        }
    }

    fn low_res_estimator(&self) -> &dyn RadianceEstimator {
        &self.quick
    }

    fn pending(&self) -> Option<String> {
        match &self.trace {
            Some(t) if self.pipeline.is_none() => Some(format!("tracing photons {:.0}%", 100.0 * t.progress())),
            None if self.pipeline.is_none() && self.settings.photon.photons > 0 => Some("tracing photons".into()),
            _ => None,
        }
    }
}

/// The view integrator for the render settings' integrator.
pub fn view_integrator(settings: &RenderSettings) -> Box<dyn ViewIntegrator> {
    match settings.integrator {
        IntegratorKind::Photon => Box::new(PhotonView::new(settings)),
        // The path tracer's and SPPM's previews show their direct light only.
        IntegratorKind::Direct | IntegratorKind::Path | IntegratorKind::Bdpt | IntegratorKind::Sppm => {
            Box::new(DirectView::new(settings))
        }
    }
}

/// Per-pixel sample sums and how many samples of each pixel they hold.
#[derive(Clone, Debug)]
pub struct Progressive {
    width: u32,
    height: u32,
    sums: Vec<PixelSum>,
    /// The pass in flight, zero between passes (a cancelled pass leaves no trace).
    pass: Vec<PixelSum>,
    done: u32,
    target: u32,
    /// The white balance the film is shown with.
    balance: Option<glam::Mat3>,
    /// Rays of the completed passes since the last reset.
    pub stats: RayStats,
}

impl Progressive {
    /// An empty accumulator for a `width` x `height` image that stops at the
    /// settings' ssaa^2 samples per pixel.
    pub fn new(width: u32, height: u32, settings: &RenderSettings) -> Self {
        Progressive {
            width,
            height,
            sums: vec![PixelSum::default(); width as usize * height as usize],
            pass: vec![PixelSum::default(); width as usize * height as usize],
            done: 0,
            target: settings.ssaa * settings.ssaa,
            balance: crate::sensor::film_matrix(settings.sensor, settings.white_balance),
            stats: RayStats::default(),
        }
    }

    /// Forgets every sample (the camera or the light moved).
    pub fn reset(&mut self) {
        self.sums.fill(PixelSum::default());
        self.done = 0;
        self.stats = RayStats::default();
    }

    /// Samples per pixel accumulated so far.
    pub fn samples(&self) -> u32 {
        self.done
    }

    /// Samples per pixel at which refinement stops.
    pub fn target(&self) -> u32 {
        self.target
    }

    pub fn is_complete(&self) -> bool {
        self.done >= self.target
    }

    /// Sample indices the next pass adds: as many as are done already (at
    /// least one), capped at the target.
    pub fn next_pass(&self) -> Option<Range<u32>> {
        if self.is_complete() {
            return None;
        }
        let n = self.done.max(1).min(self.target - self.done);
        Some(self.done..self.done + n)
    }

    /// Adds the next pass's samples. Returns false, with the sums as they
    /// were, when `cancel` was set during the pass or nothing was left to do.
    pub fn run_pass(
        &mut self,
        scene: &Scene,
        settings: &RenderSettings,
        est: &dyn RadianceEstimator,
        cancel: &AtomicBool,
    ) -> bool {
        let Some(range) = self.next_pass() else {
            return false;
        };
        let end = range.end;
        match accumulate_tiles(
            scene,
            settings,
            est,
            range,
            &mut self.pass,
            cancel,
            crate::integrator::Progress::silent(),
        ) {
            Some((s, _)) => {
                crate::integrator::merge_sums(&mut self.sums, &mut self.pass);
                self.done = end;
                self.stats.camera_rays += s.camera_rays;
                self.stats.shadow_rays += s.shadow_rays;
                self.stats.other_rays += s.other_rays;
                true
            }
            None => {
                self.pass.fill(PixelSum::default());
                false
            }
        }
    }

    /// The mean of the samples so far (black before the first pass); the
    /// same division as the offline render, so equal to it once complete.
    pub fn film(&self) -> Film {
        let mut film = Film::from_sums(self.width, self.height, &self.sums);
        if let Some(m) = self.balance {
            film.transform_colours(m);
        }
        film
    }
}

/// A quick full-size image from one ray through the centre of every `block`
/// x `block` pixel block, each block filled with its ray's radiance.
/// Returns `None` when `cancel` was set (checked per block row).
pub fn low_res_pass(
    scene: &Scene,
    settings: &RenderSettings,
    est: &dyn RadianceEstimator,
    block: u32,
    cancel: &AtomicBool,
) -> Option<Film> {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let block = block.max(1);
    let (bw, bh) = (w.div_ceil(block), h.div_ceil(block));
    let rows: Option<Vec<Vec<Vec3>>> = (0..bh)
        .into_par_iter()
        .map(|by| {
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            let mut stats = RayStats::default();
            let row = (0..bw)
                .map(|bx| {
                    let (x0, y0) = (bx * block, by * block);
                    let cx = (x0 as f32 + 0.5 * block as f32).min(w as f32);
                    let cy = (y0 as f32 + 0.5 * block as f32).min(h as f32);
                    // Keyed apart from the accumulation passes' sample indices.
                    let rng = Rng::keyed(settings.seed, (by * bw + bx) as u64, u64::MAX);
                    let mut sampler = Sampler::independent(rng);
                    let (ray, weight) = crate::integrator::camera_ray(cam, Vec2::new(cx, cy), &mut sampler);
                    let l = if weight > 0.0 {
                        est.li(scene, &ray, &mut sampler, &mut stats) * weight
                    } else {
                        Vec3::ZERO
                    };
                    if l.is_finite() {
                        l
                    } else {
                        Vec3::ZERO
                    }
                })
                .collect();
            Some(row)
        })
        .collect();
    let rows = rows?;
    let mut film = Film::new(w, h);
    for y in 0..h {
        for x in 0..w {
            film.set(x, y, rows[(y / block) as usize][(x / block) as usize]);
        }
    }
    if let Some(m) = crate::sensor::film_matrix(settings.sensor, settings.white_balance) {
        film.transform_colours(m);
    }
    Some(film)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Filter;
    use crate::integrator;
    use crate::scene::builtin;

    fn small_cornell() -> Scene {
        let mut d = builtin::cornell();
        d.camera.width = 37;
        d.camera.height = 29;
        Scene::build(d).unwrap()
    }

    fn settings() -> RenderSettings {
        RenderSettings {
            ssaa: 3,
            shadow_samples: 2,
            filter: Filter::Tent,
            seed: 11,
            threads: Some(2),
            integrator: IntegratorKind::Direct,
            ..RenderSettings::default()
        }
    }

    #[test]
    fn passes_double_and_end_at_the_target() {
        let mut p = Progressive::new(4, 4, &settings());
        let mut ranges = vec![];
        while let Some(r) = p.next_pass() {
            ranges.push(r.clone());
            p.done = r.end;
        }
        assert_eq!(ranges, vec![0..1, 1..2, 2..4, 4..8, 8..9]);
        assert!(p.is_complete());
    }

    #[test]
    fn completed_passes_equal_the_offline_render_bit_for_bit() {
        let scene = small_cornell();
        let s = settings();
        let offline = integrator::render(&scene, &s, &|| {}).unwrap();
        let view = view_integrator(&s);
        let never = AtomicBool::new(false);
        let mut p = Progressive::new(scene.camera.width, scene.camera.height, &s);
        let mut passes = 0;
        while p.run_pass(&scene, &s, view.estimator().as_ref(), &never) {
            passes += 1;
            if !p.is_complete() {
                // Part way, the image is a different (noisier) estimate.
                assert_ne!(p.film(), offline.film);
            }
        }
        assert_eq!(passes, 5);
        assert_eq!(p.samples(), 9);
        assert_eq!(p.film(), offline.film);
        assert_eq!(p.stats, offline.stats);
    }

    #[test]
    fn white_balance_and_camera_sensors_map_every_pixel_of_the_offline_and_the_progressive_film() {
        let scene = small_cornell();
        let plain = integrator::render(&scene, &settings(), &|| {}).unwrap().film;
        let s = RenderSettings {
            white_balance: Some(3000.0),
            ..settings()
        };
        let balanced = integrator::render(&scene, &s, &|| {}).unwrap().film;
        let m = crate::sensor::white_balance(3000.0);
        let mut warm = 0;
        for (b, p) in balanced.pixels.iter().zip(&plain.pixels) {
            assert!(
                (*b - m * *p).abs().max_element() <= 1e-6 * p.max_element().max(1.0),
                "{b} {p}"
            );
            warm += (b.z > p.z && b.x < p.x) as u32;
        }
        assert!(warm as usize > plain.pixels.len() / 2, "{warm}");
        let view = view_integrator(&s);
        let never = AtomicBool::new(false);
        let mut p = Progressive::new(scene.camera.width, scene.camera.height, &s);
        while p.run_pass(&scene, &s, view.estimator().as_ref(), &never) {}
        assert_eq!(p.film(), balanced);

        // A named camera is its own matrix at the same temperature, in both
        // films: not the observer's balance.
        let c = RenderSettings {
            sensor: "nikon_d850",
            ..s.clone()
        };
        let camera = integrator::render(&scene, &c, &|| {}).unwrap().film;
        let mc = crate::sensor::camera_matrix("nikon_d850", 3000.0).unwrap();
        assert!((mc - m).to_cols_array().iter().any(|d| d.abs() > 0.01));
        for (b, p) in camera.pixels.iter().zip(&plain.pixels) {
            assert!(
                (*b - mc * *p).abs().max_element() <= 1e-6 * p.max_element().max(1.0),
                "{b} {p}"
            );
        }
        let mut p = Progressive::new(scene.camera.width, scene.camera.height, &c);
        while p.run_pass(&scene, &c, view.estimator().as_ref(), &never) {}
        assert_eq!(p.film(), camera);
    }

    #[test]
    fn a_cancelled_pass_changes_nothing() {
        let scene = small_cornell();
        let s = settings();
        let view = view_integrator(&s);
        let (never, cancelled) = (AtomicBool::new(false), AtomicBool::new(true));
        let mut p = Progressive::new(scene.camera.width, scene.camera.height, &s);
        assert!(p.run_pass(&scene, &s, view.estimator().as_ref(), &never));
        let before = p.film();
        assert!(!p.run_pass(&scene, &s, view.estimator().as_ref(), &cancelled));
        assert_eq!(p.samples(), 1);
        assert_eq!(p.film(), before);
        assert!(low_res_pass(&scene, &s, view.low_res_estimator(), 4, &cancelled).is_none());
        // Refinement carries on to the offline image after the cancel.
        while p.run_pass(&scene, &s, view.estimator().as_ref(), &never) {}
        assert_eq!(p.film(), integrator::render(&scene, &s, &|| {}).unwrap().film);
    }

    #[test]
    fn reset_starts_over() {
        let scene = small_cornell();
        let s = settings();
        let view = view_integrator(&s);
        let never = AtomicBool::new(false);
        let mut p = Progressive::new(scene.camera.width, scene.camera.height, &s);
        p.run_pass(&scene, &s, view.estimator().as_ref(), &never);
        p.run_pass(&scene, &s, view.estimator().as_ref(), &never);
        p.reset();
        assert_eq!(p.samples(), 0);
        assert_eq!(p.next_pass(), Some(0..1));
        assert!(p.film().pixels.iter().all(|&v| v == Vec3::ZERO));
    }

    #[test]
    fn low_res_pass_is_blocky_and_close_to_the_full_image() {
        let mut d = builtin::cornell();
        (d.camera.width, d.camera.height) = (98, 97);
        let scene = Scene::build(d).unwrap();
        let s = settings();
        let view = view_integrator(&s);
        let never = AtomicBool::new(false);
        let f = low_res_pass(&scene, &s, view.low_res_estimator(), 4, &never).unwrap();
        assert_eq!((f.width, f.height), (98, 97));
        // Every 4x4 block (including the clipped last ones) is one colour.
        for y in 0..f.height {
            for x in 0..f.width {
                assert_eq!(f.get(x, y), f.get(x / 4 * 4, y / 4 * 4), "({x}, {y})");
            }
        }
        // Clamped as on screen, so that hitting or missing the small, very
        // bright light with a block's one ray does not dominate the mean.
        let full = integrator::render(&scene, &s, &|| {}).unwrap().film;
        let shown = |f: &Film| f.pixels.iter().map(|p| p.min(Vec3::ONE)).sum::<Vec3>() / f.pixels.len() as f32;
        let (a, b) = (shown(&f), shown(&full));
        assert!((a - b).length() < 0.15 * b.length(), "{a:?} vs {b:?}");
    }

    fn photon_settings() -> RenderSettings {
        let mut s = RenderSettings {
            ssaa: 2,
            integrator: IntegratorKind::Photon,
            ..settings()
        };
        s.photon.photons = 20_000;
        s
    }

    #[test]
    fn photon_passes_equal_the_offline_photon_render_bit_for_bit() {
        let scene = small_cornell();
        let s = photon_settings();
        let offline = integrator::render(&scene, &s, &|| {}).unwrap();
        let (never, cancelled) = (AtomicBool::new(false), AtomicBool::new(true));
        let mut view = view_integrator(&s);
        // A cancelled trace leaves the map to the next call.
        assert!(!view.prepare(&scene, &s, &cancelled));
        assert!(view.pending().is_some());
        assert!(view.prepare(&scene, &s, &never));
        assert!(view.pending().is_none());
        let mut p = Progressive::new(scene.camera.width, scene.camera.height, &s);
        while p.run_pass(&scene, &s, view.estimator().as_ref(), &never) {}
        assert_eq!(p.samples(), 4);
        assert_eq!(p.film(), offline.film);
        assert_eq!(p.stats, offline.stats);
        // The photons add indirect light to what the direct preview shows.
        let direct = RenderSettings {
            integrator: IntegratorKind::Direct,
            ..s.clone()
        };
        let direct = integrator::render(&scene, &direct, &|| {}).unwrap().film;
        let mean = |f: &Film| f.pixels.iter().map(|p| p.min(Vec3::ONE)).sum::<Vec3>() / f.pixels.len() as f32;
        assert!(mean(&p.film()).length() > 1.1 * mean(&direct).length());
    }

    #[test]
    fn photons_are_traced_again_only_when_the_light_moves() {
        let mut scene = small_cornell();
        let s = photon_settings();
        let never = AtomicBool::new(false);
        let mut view = PhotonView::new(&s);
        assert!(view.prepare(&scene, &s, &never));
        let first = view.map().unwrap().clone();
        // A camera move: prepare keeps the map.
        scene.camera = crate::camera::Camera::new(
            scene.camera.position + Vec3::new(0.1, 0.0, 0.0),
            Vec3::ZERO,
            Vec3::new(0.0, -1.0, 0.0),
            40.0,
            scene.camera.width,
            scene.camera.height,
        )
        .unwrap();
        assert!(view.prepare(&scene, &s, &never));
        assert_eq!(view.map(), Some(&first));
        // A light move: the map is forgotten and traced for the new position,
        // as the offline render of the moved scene traces it.
        let moved = scene.lights[0].position() + Vec3::new(0.2, 0.0, 0.0);
        scene.move_light(0, moved);
        view.light_moved();
        assert!(view.map().is_none());
        assert!(view.prepare(&scene, &s, &never));
        let second = view.map().unwrap();
        assert_ne!(second, &first);
        let offline = crate::photon::build_map(&scene, &map_settings(&s), s.seed).0;
        assert_eq!(second, &offline);
    }
}
