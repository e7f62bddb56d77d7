//! Integrators and the render loop they share.
//!
//! The loop (pbrt-v4's `ImageTileIntegrator::Render`, Mitsuba's blocks):
//! 32x32 tiles handed out dynamically by rayon; each pixel's samples are
//! summed in a fixed order from random numbers keyed by (seed, pixel,
//! sample), so the image is bit-identical for any thread count or tile order.

#[cfg(test)]
pub(crate) mod analytic;
pub mod bdpt;
pub mod checkpoint;
pub mod direct;
pub mod lanes;
pub mod path;
pub mod photon;
pub mod plain;
pub mod sppm;
pub mod volpath;

use crate::error::{Error, Result};
use crate::film::{Film, FrameWindow, PixelRect, PixelSum, SplatBlock};
use crate::math::{Ray, Vec2, Vec3};
use crate::photon::PhotonStats;
use crate::sampling::{hammersley_shifted, stratified, Rng, Sampler};
use crate::scene::Scene;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

pub use crate::settings::{IntegratorKind, LightSampling, RenderSettings, SamplerKind, StateFiles};

/// Tile side in pixels. A pass ends when its last tile does, the other
/// threads idle meanwhile: half a tile a thread on average, so small tiles;
/// 16 x 16 is still far more work than a tile's own cost (its splat block,
/// one merge).
pub const TILE: u32 = 16;

/// Asks a render to stop: tiles not yet started are skipped, progressive
/// renders stop after the pass in flight (saving their checkpoint), and the
/// render returns what it finished. The caller owns it: the binary trips it
/// from its SIGINT/SIGTERM handler, an embedding program from wherever it
/// likes, and tests after a fixed number of tiles, so that an interruption
/// is as deterministic as the render.
#[derive(Clone, Debug, Default)]
pub struct CancelToken {
    flag: Arc<AtomicBool>,
    /// Tiles still to finish before the token trips by itself.
    tiles_left: Option<Arc<AtomicU64>>,
}

impl CancelToken {
    pub fn new() -> Self {
        Self::default()
    }

    /// A token that trips once `tiles` tiles have been rendered.
    pub fn after_tiles(tiles: u64) -> Self {
        CancelToken {
            flag: Arc::new(AtomicBool::new(tiles == 0)),
            tiles_left: Some(Arc::new(AtomicU64::new(tiles))),
        }
    }

    pub fn cancel(&self) {
        self.flag.store(true, Ordering::SeqCst);
    }

    pub fn is_cancelled(&self) -> bool {
        self.flag.load(Ordering::SeqCst)
    }

    fn tile_done(&self) {
        if let Some(left) = &self.tiles_left {
            let before = left.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| n.checked_sub(1));
            if before == Ok(1) {
                self.cancel();
            }
        }
    }
}

/// What a render reports as it goes and how it is stopped: `on_tile` is
/// called once per finished tile (per pass for progressive renders), and the
/// cancel token is checked before each tile and pass.
#[derive(Clone, Copy)]
pub struct Progress<'a> {
    on_tile: &'a (dyn Fn() + Sync),
    cancel: &'a CancelToken,
}

impl<'a> Progress<'a> {
    pub fn new(on_tile: &'a (dyn Fn() + Sync), cancel: &'a CancelToken) -> Self {
        Progress { on_tile, cancel }
    }

    /// Reports to `on_tile` and never stops.
    pub fn reporting(on_tile: &'a (dyn Fn() + Sync)) -> Self {
        static NEVER: std::sync::OnceLock<CancelToken> = std::sync::OnceLock::new();
        Progress {
            on_tile,
            cancel: NEVER.get_or_init(CancelToken::new),
        }
    }

    /// Reports nothing and never stops.
    pub fn silent() -> Progress<'static> {
        Progress::reporting(&|| {})
    }

    pub(crate) fn tile_done(&self) {
        (self.on_tile)();
        self.cancel.tile_done();
    }

    /// Reports `ticks` done earlier (a resumed render's passes).
    pub(crate) fn skip(&self, ticks: u64) {
        for _ in 0..ticks {
            (self.on_tile)();
        }
    }

    pub(crate) fn stopped(&self) -> bool {
        self.cancel.is_cancelled()
    }
}

/// Counters kept per tile and summed, never shared between threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayStats {
    pub camera_rays: u64,
    pub shadow_rays: u64,
    pub other_rays: u64,
}

impl RayStats {
    pub fn total(&self) -> u64 {
        self.camera_rays + self.shadow_rays + self.other_rays
    }

    pub(crate) fn add(&mut self, o: &RayStats) {
        self.camera_rays += o.camera_rays;
        self.shadow_rays += o.shadow_rays;
        self.other_rays += o.other_rays;
    }
}

/// What a render produced.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The rendered pixels: the crop rectangle, or the whole frame.
    pub film: Film,
    /// Tiles rendered and tiles in the frame; fewer done means interrupted
    /// (the missing tiles are black).
    pub tiles_done: u64,
    pub tiles_total: u64,
    pub window: FrameWindow,
    pub stats: RayStats,
    pub seconds: f64,
    /// The photon pass, when there was one.
    pub photons: Option<PhotonStats>,
    /// The path tracer's photon guide, when it had one.
    pub guide: Option<crate::photon::GuideStats>,
    /// Passes done and passes in all, for a progressive render; fewer done
    /// means interrupted (the film averages the passes done).
    pub passes: Option<(u32, u32)>,
}

impl RenderOutput {
    /// Whether every tile and pass was rendered.
    pub fn is_complete(&self) -> bool {
        self.tiles_done == self.tiles_total && self.passes.is_none_or(|(done, all)| done == all)
    }
}

/// The radiance carried along one camera ray.
pub trait RadianceEstimator: Sync {
    fn li(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Vec3;

    /// Splats a tile's samples into `block`: [`add_pixel_samples`] pixel by
    /// pixel, unless the estimator traces many camera rays at once. Returns
    /// false when `cancel` stopped it before the tile's last row.
    fn add_tile_samples(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        tile: &Tile,
        block: &mut SplatBlock,
        stats: &mut RayStats,
        cancel: &AtomicBool,
    ) -> bool {
        tile.add_samples(scene, settings, self, block, stats, cancel)
    }
}

/// Samples `samples` of the pixels `xs` x `ys` of the frame: a tile's, and
/// on the crop's edge those beyond it that the filter reaches in from.
#[derive(Clone, Debug)]
pub struct Tile {
    pub xs: Range<u32>,
    pub ys: Range<u32>,
    pub samples: Range<u32>,
}

impl Tile {
    /// Splats the tile's samples into `block`, [`add_pixel_samples`] pixel
    /// by pixel, each ray's radiance from `est`; false when `cancel` stopped
    /// it.
    pub fn add_samples<E: RadianceEstimator + ?Sized>(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        est: &E,
        block: &mut SplatBlock,
        stats: &mut RayStats,
        cancel: &AtomicBool,
    ) -> bool {
        for y in self.ys.clone() {
            if cancel.load(Ordering::Relaxed) {
                return false;
            }
            for x in self.xs.clone() {
                add_pixel_samples(scene, settings, est, x, y, self.samples.clone(), block, stats);
            }
        }
        true
    }
}

/// Runs `f` on a pool of `threads` workers (all cores when `None`).
pub fn with_threads<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        b = b.num_threads(n);
    }
    let pool = b
        .build()
        .map_err(|e| Error::InvalidSetting(format!("--threads: cannot start worker threads: {e}")))?;
    Ok(pool.install(f))
}

/// Renders the scene's full frame (or the crop) with the chosen integrator.
pub fn render(scene: &Scene, settings: &RenderSettings, on_tile: &(dyn Fn() + Sync)) -> Result<RenderOutput> {
    render_observed(scene, settings, Progress::reporting(on_tile), &|_, _| Ok(()))
}

/// `render`, showing progressive integrators' (SPPM's) image after each pass
/// k to `on_pass(k, film)`, which may stop the render with an error.
pub fn render_observed(
    scene: &Scene,
    settings: &RenderSettings,
    on_tile: Progress,
    on_pass: &(dyn Fn(u32, &Film) -> Result<()> + Sync),
) -> Result<RenderOutput> {
    settings.validate()?;
    check_scene(scene, settings.integrator)?;
    let window = frame_window(scene, settings)?;
    let start = std::time::Instant::now();
    let tiles_total = tile_count(window.rect.width(), window.rect.height());
    // The sensor's response is applied to finished films: sums, checkpoints
    // and photon files stay as the light left them.
    let balance = crate::sensor::film_matrix(settings.sensor, settings.white_balance);
    let develop = |mut film: Film| {
        if let Some(m) = balance {
            film.transform_colours(m);
        }
        film
    };
    let on_pass = &|k: u32, film: &Film| match balance {
        Some(_) => on_pass(k, &develop(film.clone())),
        None => on_pass(k, film),
    };
    let mut guide = None;
    let (film, stats, tiles_done, photons, passes) = with_threads(settings.threads, || -> Result<_> {
        Ok(match settings.integrator {
            IntegratorKind::Direct => {
                let est = direct::DirectLighting {
                    shadow_samples: settings.shadow_samples,
                };
                let (film, stats, done) = render_tiles(scene, settings, &est, on_tile);
                (film, stats, done, None, None)
            }
            IntegratorKind::Path | IntegratorKind::Bdpt => {
                let mut state = path::Progressive::new(scene, settings);
                guide = state.guide_stats();
                let passes = checkpoint::run(scene, settings, &mut state, on_tile)?;
                let (film, stats) = state.finish(passes.0);
                (film, stats, tiles_total, None, Some(passes))
            }
            IntegratorKind::Photon => {
                let ((film, stats, done), photons) = photon::render(scene, settings, on_tile)?;
                (film, stats, done, photons, None)
            }
            IntegratorKind::Sppm => {
                let (film, stats, done, photons) = sppm::render(scene, settings, on_tile, on_pass)?;
                (film, stats, tiles_total, Some(photons), Some((done, settings.passes)))
            }
        })
    })??;
    Ok(RenderOutput {
        film: develop(film),
        tiles_done,
        tiles_total,
        window,
        stats,
        seconds: start.elapsed().as_secs_f64(),
        photons,
        guide,
        passes,
    })
}

/// What an integrator cannot render, refused up front: participating media
/// are rendered by the path tracer alone (photons do not yet travel through
/// them), and the bidirectional path tracer does not weigh particles that
/// enter through a portal (its lights at infinity emit from a disk across
/// the scene).
pub fn check_scene(scene: &Scene, integrator: IntegratorKind) -> Result<()> {
    if scene.has_media() && integrator != IntegratorKind::Path {
        return Err(crate::Error::InvalidSetting(format!(
            "integrator \"{}\": the scene has participating media, which only the path tracer renders (--integrator path)",
            integrator.name()
        )));
    }
    let portal = |l: &crate::light::Light| matches!(l, crate::light::Light::Infinite { portal: Some(_), .. });
    if integrator == IntegratorKind::Bdpt && scene.lights.iter().any(portal) {
        return Err(crate::Error::InvalidSetting(
            "integrator \"bdpt\": the scene has an infinite light with a portal, which bdpt does not render (--integrator path, photon or sppm)".into(),
        ));
    }
    Ok(())
}

/// Ticks `render` gives its `on_tile` callback in all: one per tile, per
/// pass for progressive renders.
pub fn progress_ticks(settings: &RenderSettings, width: u32, height: u32) -> u64 {
    let passes = match settings.integrator {
        IntegratorKind::Path | IntegratorKind::Bdpt => path::Progressive::passes_for(settings.spp) as u64,
        _ => 1,
    };
    tile_count(width, height) * passes
}

/// Number of tiles a rectangle is cut into (for progress bars).
pub fn tile_count(width: u32, height: u32) -> u64 {
    (width.div_ceil(TILE) as u64) * (height.div_ceil(TILE) as u64)
}

/// The part of the frame a render covers; refuses crops outside the frame.
pub fn frame_window(scene: &Scene, settings: &RenderSettings) -> Result<FrameWindow> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let rect = settings.crop.unwrap_or(PixelRect::full(w, h));
    if rect.is_empty() || rect.x1 > w || rect.y1 > h {
        return Err(Error::InvalidSetting(format!(
            "--crop {},{},{},{}: must be a non-empty rectangle inside the {w}x{h} frame",
            rect.x0, rect.y0, rect.x1, rect.y1
        )));
    }
    Ok(FrameWindow {
        full_width: w,
        full_height: h,
        rect,
    })
}

/// The tile loop shared by every integrator. Returns the film (the crop, or
/// the whole frame), the ray counts and the number of tiles rendered.
pub fn render_tiles(
    scene: &Scene,
    settings: &RenderSettings,
    est: &dyn RadianceEstimator,
    on_tile: Progress,
) -> (Film, RayStats, u64) {
    let cam = &scene.camera;
    let rect = settings.crop.unwrap_or(PixelRect::full(cam.width, cam.height));
    let spp = settings.samples_per_pixel();
    let mut sums = vec![PixelSum::default(); rect.width() as usize * rect.height() as usize];
    let never = AtomicBool::new(false);
    let (stats, done) = accumulate_tiles(scene, settings, est, 0..spp, &mut sums, &never, on_tile).unwrap_or_default();
    (Film::from_sums(rect.width(), rect.height(), &sums), stats, done)
}

/// Adds camera samples `samples` (indices into each pixel's fixed sequence of
/// `samples_per_pixel` samples), splatted through the pixel filter, to the
/// pixel sums of the crop rectangle (the whole frame without one), tile by
/// tile.
///
/// A render is this over `0..spp`; the preview window runs it over
/// consecutive ranges. The sums are exact (fixed point), so any split into
/// ranges, tiles or threads gives the same bits. Samples of pixels just
/// outside a crop whose filter reaches into it are taken too (by the tiles on
/// the crop's edge), so that crops stitch into the full frame's image.
/// `sums` holds one entry per pixel of the rectangle, rows from the top.
/// `cancel` is checked before every row of a tile; when it is set, `None` is
/// returned, with the tiles finished before it already added. Tiles not
/// started when `on_tile`'s cancel token is set are skipped; the count of
/// tiles done says so. A caller that must be able to go back to the sums as
/// they were accumulates into zeroed sums and merges them when all is done
/// (`merge_sums`): a buffer it keeps, rather than a copy of the sums each time.
pub fn accumulate_tiles(
    scene: &Scene,
    settings: &RenderSettings,
    est: &dyn RadianceEstimator,
    samples: Range<u32>,
    sums: &mut [PixelSum],
    cancel: &AtomicBool,
    on_tile: Progress,
) -> Option<(RayStats, u64)> {
    let cam = &scene.camera;
    let rect = settings.crop.unwrap_or(PixelRect::full(cam.width, cam.height));
    let (rw, rh) = (rect.width(), rect.height());
    assert_eq!(sums.len(), rw as usize * rh as usize, "one sum per pixel");
    let reach = settings.filter.reach();
    let tiles_x = rw.div_ceil(TILE);
    let ntiles = tile_count(rw, rh) as u32;
    let pass = std::sync::Mutex::new(sums);
    let tiles: Option<Vec<RayStats>> = (0..ntiles)
        .into_par_iter()
        // A tile a task: threads that run out take single tiles from the
        // others, so both finish a pass within about a tile of each other.
        .with_max_len(1)
        .filter(|_| !on_tile.stopped())
        .map(|t| {
            // The tile's pixels in the frame.
            let (x0, y0) = (rect.x0 + (t % tiles_x) * TILE, rect.y0 + (t / tiles_x) * TILE);
            let (x1, y1) = ((x0 + TILE).min(rect.x1), (y0 + TILE).min(rect.y1));
            // Pixels whose samples it takes: its own, and on the crop's edge
            // those beyond it that the filter reaches in from.
            let (sx0, sy0) = (
                if x0 == rect.x0 { x0.saturating_sub(reach) } else { x0 },
                if y0 == rect.y0 { y0.saturating_sub(reach) } else { y0 },
            );
            let (sx1, sy1) = (
                if x1 == rect.x1 { (x1 + reach).min(cam.width) } else { x1 },
                if y1 == rect.y1 {
                    (y1 + reach).min(cam.height)
                } else {
                    y1
                },
            );
            let block_rect = PixelRect {
                x0: x0.saturating_sub(reach).max(rect.x0),
                y0: y0.saturating_sub(reach).max(rect.y0),
                x1: (x1 + reach).min(rect.x1),
                y1: (y1 + reach).min(rect.y1),
            };
            let mut block = SplatBlock::new(block_rect, settings.filter);
            let mut stats = RayStats::default();
            let tile = Tile {
                xs: sx0..sx1,
                ys: sy0..sy1,
                samples: samples.clone(),
            };
            if !est.add_tile_samples(scene, settings, &tile, &mut block, &mut stats, cancel) {
                return None;
            }
            let mut pass = pass.lock().unwrap_or_else(|e| e.into_inner());
            let br = block.rect();
            for (i, s) in block.sums.iter().enumerate() {
                let (x, y) = (br.x0 + i as u32 % br.width(), br.y0 + i as u32 / br.width());
                pass[(y - rect.y0) as usize * rw as usize + (x - rect.x0) as usize].merge(s);
            }
            drop(pass);
            on_tile.tile_done();
            Some(stats)
        })
        .collect();
    let tiles = tiles?;
    let mut stats = RayStats::default();
    for s in &tiles {
        stats.add(s);
    }
    Some((stats, tiles.len() as u64))
}

/// Adds `pass` to `sums`, entry by entry, and zeroes `pass` for the next use.
pub fn merge_sums(sums: &mut [PixelSum], pass: &mut [PixelSum]) {
    // On every thread: merged on one, the others would wait for it at the
    // end of every pass (about a millisecond a pass at 256 x 256).
    sums.par_iter_mut()
        .zip(pass.par_iter_mut())
        .with_min_len(4096)
        .for_each(|(s, p)| {
            s.merge(p);
            *p = PixelSum::default();
        });
}

/// Splats samples `samples` of pixel (x, y) into `block`, each with its
/// [`Sampler`] keyed by (seed, pixel, s) ([`PixelSamples`]).
#[allow(clippy::too_many_arguments)]
pub fn add_pixel_samples<E: RadianceEstimator + ?Sized>(
    scene: &Scene,
    settings: &RenderSettings,
    est: &E,
    x: u32,
    y: u32,
    samples: Range<u32>,
    block: &mut SplatBlock,
    stats: &mut RayStats,
) {
    let pixel = PixelSamples::new(scene, settings, x, y);
    for s in samples {
        let mut cs = pixel.sample(scene, settings, s);
        stats.camera_rays += 1;
        // A ray the lens blocks is a sample of black, as in pbrt-v4.
        let l = if cs.weight > 0.0 {
            est.li(scene, &cs.ray, &mut cs.sampler, stats)
        } else {
            Vec3::ZERO
        };
        cs.splat(settings, l, block);
    }
}

/// The camera samples of one pixel. The samples are uniform over the
/// pixel. With the Sobol sampler the pixel position is its first 2D request
/// (a (0, 2)-net over any power-of-two prefix of the pixel's samples). With
/// independent samples, when the sample count is a square n^2, sample s is
/// jittered in stratum s of an n x n grid; otherwise the pixel's samples form
/// a Hammersley set shifted per pixel.
pub struct PixelSamples {
    x: u32,
    y: u32,
    /// n when the sample count is n^2 and the samples independent.
    grid: Option<u32>,
    shift: Vec2,
}

/// A camera sample before its radiance is known: the rest of its numbers,
/// where in the pixel it lies, its ray and the ray's weight (0 where a lens
/// blocks it).
pub struct CameraSample {
    pub sampler: Sampler,
    pub px: (u32, u32),
    pub pos: Vec2,
    pub ray: Ray,
    pub weight: f32,
}

impl PixelSamples {
    pub fn new(scene: &Scene, settings: &RenderSettings, x: u32, y: u32) -> Self {
        let spp = settings.samples_per_pixel();
        let sobol = settings.sampler != SamplerKind::Independent;
        let n = (spp as f64).sqrt().round() as u32;
        let grid = (!sobol && n * n == spp).then_some(n);
        let pixel = y as u64 * scene.camera.width as u64 + x as u64;
        let shift = if grid.is_some() || sobol {
            Vec2::ZERO
        } else {
            Rng::keyed(settings.seed, pixel, u64::MAX).next_2d()
        };
        PixelSamples { x, y, grid, shift }
    }

    /// Sample `s` of the pixel.
    #[inline(always)]
    pub fn sample(&self, scene: &Scene, settings: &RenderSettings, s: u32) -> CameraSample {
        let cam = &scene.camera;
        let spp = settings.samples_per_pixel();
        let mut sampler = camera_sampler(settings.sampler, settings.seed, self.x, self.y, cam.width, spp, s);
        let u = if settings.sampler != SamplerKind::Independent {
            sampler.next_2d()
        } else if let Some(n) = self.grid {
            stratified(s, n, sampler.next_2d())
        } else {
            hammersley_shifted(s, spp, self.shift)
        };
        let pos = Vec2::new(self.x as f32 + u.x, self.y as f32 + u.y);
        let (ray, weight) = camera_ray(cam, pos, &mut sampler);
        CameraSample {
            sampler,
            px: (self.x, self.y),
            pos,
            ray,
            weight,
        }
    }
}

impl CameraSample {
    /// Splats the sample, whose ray brought radiance `l`, into `block`.
    pub fn splat(&self, settings: &RenderSettings, l: Vec3, block: &mut SplatBlock) {
        let l = if self.weight > 0.0 {
            clamp_sample(l * self.weight, settings.max_component)
        } else {
            Vec3::ZERO
        };
        // A NaN or infinite sample would poison the pixel; drop it.
        if l.is_finite() {
            block.splat(self.px, self.pos, l);
        }
    }
}

/// `l` scaled down so that its largest component is at most `max`, as
/// pbrt-v4's film does with `maxcomponentvalue`: scaling the whole colour
/// keeps the sample's hue.
pub fn clamp_sample(l: Vec3, max: Option<f32>) -> Vec3 {
    match max {
        Some(m) if l.max_element() > m => l * (m / l.max_element()),
        _ => l,
    }
}

/// The sampler of sample `s` of pixel (x, y) of a frame `width` pixels wide,
/// in a render of `spp` samples a pixel. The Z-order sampler's sequence is
/// laid out for `spp` rounded up to a power of two; samples past that (the
/// preview's endless passes) take the Sobol sampler's points.
#[inline(always)]
pub fn camera_sampler(kind: SamplerKind, seed: u64, x: u32, y: u32, width: u32, spp: u32, s: u32) -> Sampler {
    let pixel = y as u64 * width as u64 + x as u64;
    match kind {
        SamplerKind::ZSobol => {
            let log2 = spp.max(1).checked_next_power_of_two().map_or(31, u32::trailing_zeros);
            if (s as u64) < 1u64 << log2 {
                Sampler::zsobol(seed, x, y, log2, pixel, s)
            } else {
                Sampler::new(true, seed, pixel, s)
            }
        }
        SamplerKind::Sobol => Sampler::new(true, seed, pixel, s),
        SamplerKind::Independent => Sampler::new(false, seed, pixel, s),
    }
}

/// The camera ray through continuous pixel position `pos`, and its weight
/// ([`crate::camera::Camera::sample_ray`]: 1 but for a real lens, 0 where
/// that blocks the ray). A camera with a lens takes the next 2D request of
/// `sampler` for the point on the lens (after the pixel position, as
/// pbrt-v4's camera sample); a pinhole takes none, so its images are what
/// they were before lenses existed.
#[inline(always)]
pub fn camera_ray(cam: &crate::camera::Camera, pos: Vec2, sampler: &mut Sampler) -> (Ray, f32) {
    camera_ray_at(cam, pos, sampler, None)
}

/// `camera_ray` at `time` where things move (`None`: a time drawn from
/// `sampler`, uniform over the shutter).
#[inline(always)]
pub fn camera_ray_at(cam: &crate::camera::Camera, pos: Vec2, sampler: &mut Sampler, time: Option<f32>) -> (Ray, f32) {
    let (ray, weight) = if cam.has_lens() {
        cam.sample_ray(pos.x, pos.y, sampler.next_2d())
    } else {
        (cam.generate_ray(pos.x, pos.y), 1.0)
    };
    // Its time, uniform over the shutter's, when anything moves: the request
    // after the lens's, so that still scenes draw the samples they drew.
    let Some([open, close]) = cam.shutter else {
        return (ray, weight);
    };
    let time = time.unwrap_or_else(|| open + (close - open) * sampler.next_f32());
    let ray = match &cam.motion {
        Some(m) => {
            let to = m.relative(time);
            Ray::timed(
                to.transform_point3(ray.o),
                to.transform_vector3(ray.d).normalize(),
                time,
            )
        }
        None => Ray { time, ..ray },
    };
    (ray, weight)
}

/// A 2D sample for light sampling that is shifted per shading point.
pub fn shading_shift(rng: &mut Rng) -> Vec2 {
    rng.next_2d()
}
