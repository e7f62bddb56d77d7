//! Photon mapping (Jensen 2001, "Realistic Image Synthesis Using Photon
//! Mapping"): the first pass traces photons from the lights and stores them
//! (`trace`), balances them into a kd-tree (`map`), and the render pass
//! estimates indirect light from the photons near each shading point
//! (`estimate`; the integrator is `integrator::photon`).

pub mod estimate;
pub mod file;
pub mod map;
pub mod trace;

pub use estimate::{Admit, Gather, GatherFilter};
pub use map::{Photon, PhotonMap};

use crate::error::{Error, Result};
use crate::scene::Scene;

/// Largest photon map we ever try to allocate, whatever the machine has.
pub const MAX_MAP_BYTES: u64 = 64 << 30;

/// Photon tracing and gathering settings, with their command-line defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonSettings {
    /// Photons emitted (0: no photon map, direct light only).
    pub photons: u64,
    /// Surface hits traced per photon (the first is the direct hit).
    pub max_bounces: u32,
    /// Store first hits (direct light) too; final gathering and
    /// `--shadow-samples 0` store them whatever this says.
    pub store_first_hit: bool,
    /// Russian roulette on the albedo; off, photons keep going (power scaled by
    /// the albedo) until `max_bounces` (for tests of power conservation).
    pub roulette: bool,
    pub gather: Gather,
    /// Final-gather rays per shading point (0: read the map at the visible point).
    pub final_gather: u32,
    /// Estimate irradiance once at every few photons and look the nearest up
    /// (`estimate::PrecomputedIrradiance`) instead of gathering at each sample.
    pub precompute_irradiance: bool,
    /// Photons wanted in the caustic map (light -> mirror/glass+ -> diffuse);
    /// 0: no caustic map, so such paths are not rendered at all.
    pub caustic_photons: u64,
    /// Gather radius of the caustic map.
    pub caustic_radius: f32,
}

impl Default for PhotonSettings {
    fn default() -> Self {
        PhotonSettings {
            photons: 200_000,
            max_bounces: 5,
            store_first_hit: false,
            roulette: true,
            gather: Gather {
                radius: 0.1,
                k: None,
                cone: false,
                filter: GatherFilter::None,
            },
            final_gather: 0,
            precompute_irradiance: false,
            caustic_photons: 100_000,
            caustic_radius: 0.025,
        }
    }
}

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

impl PhotonSettings {
    /// Checks the settings before any work starts. `option` names say which
    /// command-line option is wrong.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidSetting(m));
        let r = self.gather.radius;
        if r.is_nan() || r <= 0.0 || (r.is_infinite() && self.gather.k.is_none()) {
            return bad(format!(
                "--gather-radius {r}: must be a number > 0 (infinite only with --gather-k)"
            ));
        }
        if self.gather.k == Some(0) {
            return bad("--gather-k 0: must be at least 1".into());
        }
        if self.max_bounces == 0 || self.max_bounces > 100 {
            return bad(format!("--max-bounces {}: must be between 1 and 100", self.max_bounces));
        }
        let cr = self.caustic_radius;
        if !(cr.is_finite() && cr > 0.0) {
            return bad(format!("--caustic-radius {cr}: must be a finite number > 0"));
        }
        if self.final_gather > 65_536 {
            return bad(format!("--final-gather {}: at most 65536", self.final_gather));
        }
        let need = self.worst_case_bytes();
        let available = available_memory().unwrap_or(MAX_MAP_BYTES).min(MAX_MAP_BYTES);
        if need > available as u128 {
            return bad(format!(
                "--photons {}: the photon map needs up to {:.1} GiB ({} photons x {} bounces x {} bytes), more than the {:.1} GiB available",
                self.photons,
                need as f64 / (1u64 << 30) as f64,
                self.photons,
                self.max_bounces,
                std::mem::size_of::<Photon>(),
                available as f64 / (1u64 << 30) as f64
            ));
        }
        // The caustic pass stores about as many photons as asked for, plus at most one round.
        let caustic =
            (self.caustic_photons as u128 + trace::CAUSTIC_ROUND as u128) * std::mem::size_of::<Photon>() as u128;
        if self.caustic_photons > 0 && need + caustic > available as u128 {
            return bad(format!(
                "--caustic-photons {}: the caustic map needs up to {:.1} GiB, more than the {:.1} GiB left",
                self.caustic_photons,
                caustic as f64 / (1u64 << 30) as f64,
                (available as u128 - need) as f64 / (1u64 << 30) as f64
            ));
        }
        // Queries index photons with u32 (unreachable under the memory cap).
        let stored = self.photons as u128 * self.max_bounces as u128;
        if stored >= u32::MAX as u128 {
            return bad(format!(
                "--photons {} with --max-bounces {}: up to {stored} stored photons, more than a map can index (2^32)",
                self.photons, self.max_bounces
            ));
        }
        Ok(())
    }

    /// Bytes of the map if every photon were stored at every hit.
    pub fn worst_case_bytes(&self) -> u128 {
        self.photons as u128 * self.max_bounces as u128 * std::mem::size_of::<Photon>() as u128
    }
}

/// Memory the system can still give us (Linux `MemAvailable`), if known.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
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
