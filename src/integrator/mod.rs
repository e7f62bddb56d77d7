//! Integrators and the render loop they share.
//!
//! The loop (pbrt-v4's `ImageTileIntegrator::Render`, Mitsuba's blocks):
//! 32x32 tiles handed out dynamically by rayon; each pixel's samples are
//! summed in a fixed order from random numbers keyed by (seed, pixel,
//! sample), so the image is bit-identical for any thread count or tile order.

pub mod direct;

use crate::error::{Error, Result};
use crate::film::{Film, Filter};
use crate::math::{Ray, Vec2, Vec3};
use crate::sampling::{stratified, Rng};
use crate::scene::Scene;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

pub const TILE: u32 = 32;

/// Which light transport algorithm renders the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum IntegratorKind {
    /// Direct light only (shadow rays to the lights).
    #[default]
    Direct,
}

/// Settings common to every integrator.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Camera samples per pixel per axis (ssaa^2 samples per pixel).
    pub ssaa: u32,
    /// Shadow rays per light per shading point.
    pub shadow_samples: u32,
    pub filter: Filter,
    pub seed: u64,
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
    pub integrator: IntegratorKind,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            ssaa: 4,
            shadow_samples: 4,
            filter: Filter::Box,
            seed: 0,
            threads: None,
            integrator: IntegratorKind::Direct,
        }
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

    fn add(&mut self, o: &RayStats) {
        self.camera_rays += o.camera_rays;
        self.shadow_rays += o.shadow_rays;
        self.other_rays += o.other_rays;
    }
}

/// What a render produced.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    pub film: Film,
    pub stats: RayStats,
    pub seconds: f64,
}

/// The radiance carried along one camera ray.
pub trait RadianceEstimator: Sync {
    fn li(&self, scene: &Scene, ray: &Ray, rng: &mut Rng, stats: &mut RayStats) -> Vec3;
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

/// Renders the scene's full frame with the chosen integrator.
pub fn render(scene: &Scene, settings: &RenderSettings, on_tile: &(dyn Fn() + Sync)) -> Result<RenderOutput> {
    if settings.ssaa == 0 {
        return Err(Error::InvalidSetting("--ssaa must be at least 1".into()));
    }
    let start = std::time::Instant::now();
    let (film, stats) = with_threads(settings.threads, || match settings.integrator {
        IntegratorKind::Direct => {
            let est = direct::DirectLighting {
                shadow_samples: settings.shadow_samples,
            };
            render_tiles(scene, settings, &est, on_tile)
        }
    })?;
    Ok(RenderOutput {
        film,
        stats,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Number of tiles the frame is cut into (for progress bars).
pub fn tile_count(width: u32, height: u32) -> u64 {
    (width.div_ceil(TILE) as u64) * (height.div_ceil(TILE) as u64)
}

/// The tile loop shared by every integrator.
pub fn render_tiles(
    scene: &Scene,
    settings: &RenderSettings,
    est: &dyn RadianceEstimator,
    on_tile: &(dyn Fn() + Sync),
) -> (Film, RayStats) {
    let cam = &scene.camera;
    let spp = settings.ssaa * settings.ssaa;
    let mut sums = vec![Vec3::ZERO; cam.width as usize * cam.height as usize];
    let never = AtomicBool::new(false);
    let stats = accumulate_tiles(scene, settings, est, 0..spp, &mut sums, &never, on_tile).unwrap_or_default();
    let mut film = Film::new(cam.width, cam.height);
    for (p, sum) in film.pixels.iter_mut().zip(sums) {
        *p = sum / spp as f32;
    }
    (film, stats)
}

/// Adds camera samples `samples` (indices into each pixel's fixed sequence of
/// ssaa^2 samples) to the per-pixel sums, tile by tile.
///
/// A render is this over `0..spp` followed by a division by spp; the preview
/// window runs it over consecutive ranges. Each pixel's samples are added in
/// index order onto its running sum, so any split into ranges gives the same
/// bits as one pass. `sums` holds one entry per pixel, rows from the top.
/// `cancel` is checked before every row of a tile; when it is set, `sums` is
/// left untouched and `None` returned.
pub fn accumulate_tiles(
    scene: &Scene,
    settings: &RenderSettings,
    est: &dyn RadianceEstimator,
    samples: Range<u32>,
    sums: &mut [Vec3],
    cancel: &AtomicBool,
    on_tile: &(dyn Fn() + Sync),
) -> Option<RayStats> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    assert_eq!(sums.len(), w as usize * h as usize, "one sum per pixel");
    let tiles_x = w.div_ceil(TILE);
    let ntiles = tile_count(w, h) as u32;
    let prior: &[Vec3] = sums;
    let tiles: Option<Vec<(u32, Vec<Vec3>, RayStats)>> = (0..ntiles)
        .into_par_iter()
        .map(|t| {
            let (x0, y0) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
            let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
            let mut stats = RayStats::default();
            let mut out = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
            for y in y0..y1 {
                if cancel.load(Ordering::Relaxed) {
                    return None;
                }
                for x in x0..x1 {
                    let mut sum = prior[y as usize * w as usize + x as usize];
                    add_pixel_samples(scene, settings, est, x, y, samples.clone(), &mut sum, &mut stats);
                    out.push(sum);
                }
            }
            on_tile();
            Some((t, out, stats))
        })
        .collect();
    let mut stats = RayStats::default();
    for (t, px, s) in tiles? {
        let (x0, y0) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
        let tw = (x0 + TILE).min(w) - x0;
        for (i, p) in px.into_iter().enumerate() {
            let (x, y) = (x0 + i as u32 % tw, y0 + i as u32 / tw);
            sums[y as usize * w as usize + x as usize] = p;
        }
        stats.add(&s);
    }
    Some(stats)
}

/// Adds samples `samples` of pixel (x, y) to `sum`, in index order. Sample s
/// is jittered in stratum s of the pixel's ssaa x ssaa grid, with random
/// numbers keyed by (seed, pixel, s).
#[allow(clippy::too_many_arguments)]
pub fn add_pixel_samples(
    scene: &Scene,
    settings: &RenderSettings,
    est: &dyn RadianceEstimator,
    x: u32,
    y: u32,
    samples: Range<u32>,
    sum: &mut Vec3,
    stats: &mut RayStats,
) {
    let cam = &scene.camera;
    let n = settings.ssaa;
    let pixel = y as u64 * cam.width as u64 + x as u64;
    for s in samples {
        let mut rng = Rng::keyed(settings.seed, pixel, s as u64);
        let u = stratified(s, n, rng.next_2d());
        let off = settings.filter.sample(u);
        let ray = cam.generate_ray(x as f32 + 0.5 + off.x, y as f32 + 0.5 + off.y);
        stats.camera_rays += 1;
        let l = est.li(scene, &ray, &mut rng, stats);
        // A NaN or infinite sample would poison the pixel; drop it.
        if l.is_finite() {
            *sum += l;
        }
    }
}

/// A 2D sample for light sampling that is shifted per shading point.
pub fn shading_shift(rng: &mut Rng) -> Vec2 {
    rng.next_2d()
}
