//! Photon mapping (Jensen 2001, "Realistic Image Synthesis Using Photon
//! Mapping"): the first pass traces photons from the lights and stores them
//! (`trace`), balances them into a kd-tree (`map`), and the render pass
//! estimates indirect light from the photons near each shading point
//! (`estimate`; the integrator is `integrator::photon`).

pub mod estimate;
pub mod file;
pub mod guide;
pub mod map;
pub mod trace;

pub use estimate::{Admit, Gather, GatherFilter};
pub use guide::{GuideCell, PhotonGuide};
pub use map::{Photon, PhotonMap};

use crate::scene::Scene;

pub use crate::settings::{PhotonSettings, MAX_MAP_BYTES};

/// What the photon pass did, for the summary line and benchmarks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonStats {
    pub emitted: u64,
    pub stored: usize,
    pub bytes: usize,
    pub trace_seconds: f64,
    pub build_seconds: f64,
    /// Reading the map from a file (`--load-photons`) instead of tracing it.
    pub load_seconds: f64,
    /// Writing the map to a file (`--save-photons`).
    pub save_seconds: f64,
    /// Estimating the precomputed irradiance (`--precompute-irradiance`).
    pub precompute_seconds: f64,
    /// The caustic map: photons emitted and stored (zero without one).
    pub caustic_emitted: u64,
    pub caustic_stored: usize,
}

/// Traces the photons and balances them into a map (on the current rayon pool).
pub fn build_map(scene: &Scene, settings: &PhotonSettings, seed: u64) -> (PhotonMap, PhotonStats) {
    let start = std::time::Instant::now();
    let traced = trace::trace(scene, settings, seed);
    map_from_trace(traced, start.elapsed().as_secs_f64())
}

/// Balances traced photons into a map; `trace_seconds` is what tracing took.
pub fn map_from_trace(traced: trace::PhotonTrace, trace_seconds: f64) -> (PhotonMap, PhotonStats) {
    let start = std::time::Instant::now();
    let emitted = traced.emitted;
    let map = PhotonMap::build(traced.photons, traced.unit);
    let stats = PhotonStats {
        emitted,
        stored: map.len(),
        bytes: map.bytes(),
        trace_seconds,
        build_seconds: start.elapsed().as_secs_f64(),
        ..PhotonStats::default()
    };
    (map, stats)
}

/// Traces the caustic map (`None` when the scene has no caustics to trace)
/// and adds what it did to `stats`.
pub fn build_caustic_map(
    scene: &Scene,
    settings: &PhotonSettings,
    seed: u64,
    stats: &mut PhotonStats,
) -> Option<PhotonMap> {
    let start = std::time::Instant::now();
    let traced = trace::trace_caustics(scene, settings, seed);
    stats.trace_seconds += start.elapsed().as_secs_f64();
    if traced.photons.is_empty() {
        return None;
    }
    let start = std::time::Instant::now();
    stats.caustic_emitted = traced.emitted;
    stats.caustic_stored = traced.photons.len();
    let map = PhotonMap::build(traced.photons, traced.unit);
    stats.bytes += map.bytes();
    stats.build_seconds += start.elapsed().as_secs_f64();
    Some(map)
}

/// What building a photon guide did, for the summary line.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GuideStats {
    /// Photons emitted, and those that reached a diffuse surface through
    /// glossy or specular ones.
    pub emitted: u64,
    pub stored: usize,
    /// Cells that guide.
    pub cells: usize,
    pub seconds: f64,
}

/// Traces `photons` caustic photons (light -> glossy or specular surfaces ->
/// a diffuse one, at most `max_bounces` hits) and bins them into a guide for
/// the path tracer's diffuse bounces (`guide`).
pub fn build_guide(scene: &Scene, photons: u64, max_bounces: u32, seed: u64) -> (PhotonGuide, GuideStats) {
    let start = std::time::Instant::now();
    let settings = PhotonSettings {
        caustic_photons: photons,
        max_bounces,
        ..PhotonSettings::default()
    };
    let traced = trace::trace_caustics(scene, &settings, seed);
    let guide = PhotonGuide::build(&traced.photons, scene.bounds());
    let stats = GuideStats {
        emitted: traced.emitted,
        stored: traced.photons.len(),
        cells: guide.cells(),
        seconds: start.elapsed().as_secs_f64(),
    };
    (guide, stats)
}
