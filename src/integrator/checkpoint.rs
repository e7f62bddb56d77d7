//! Progressive renders and their checkpoints: a render that advances in
//! passes can be saved between passes (`--checkpoint FILE`, every
//! `--checkpoint-every` minutes and when interrupted) and continued later
//! (`--resume FILE`) to the same final image, bit for bit.
//!
//! The hook for progressive integrators is [`Progressive`]: an integrator
//! keeps its per-pixel state between passes, runs one pass at a time
//! (leaving its state as it was when a pass is interrupted), and exposes the
//! state as named numeric buffers. [`run`] drives any of them: passes,
//! interruption, the checkpoint timer and the files. The path tracer
//! (`path::Progressive`) keeps one buffer, the per-pixel fixed-point sums of
//! filter-weighted samples and weights; SPPM
//! (`sppm::Progressive`) keeps its per-pixel direct-light sums, radius,
//! photon count N and flux tau (its visible points are recomputed each pass,
//! so they need no saving), with pass k's photons keyed by k so that a
//! resumed pass k traces what the uninterrupted one would have.
//!
//! A checkpoint is a `state_file` (header with the scene's fingerprint,
//! camera included, and the integrator's key, each part checksummed) whose
//! body is:
//!
//! ```text
//! passes done  u32
//! buffer count u32 (at most 64)
//! per buffer:  tag (u8 length + ASCII), element type u8 (1: f32, 2: f64, 3: i128),
//!              element count u64, the elements little-endian
//! ```
//!
//! It is written to a temporary file and renamed into place, so a crash
//! while writing leaves the previous checkpoint.

use super::RenderSettings;
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::state_file::{self, Header};
use std::path::Path;
use std::time::Instant;

const MAGIC: [u8; 8] = *b"RTCHECKP";
const VERSION: u32 = 1;
const MAX_BUFFERS: u32 = 64;

/// A named array of numbers, one of the pieces of a progressive render's state.
#[derive(Clone, Debug, PartialEq)]
pub enum Buffer {
    F32(Vec<f32>),
    F64(Vec<f64>),
    /// Fixed-point sums (`film::PixelSum`).
    I128(Vec<i128>),
}

impl Buffer {
    pub fn len(&self) -> usize {
        match self {
            Buffer::F32(v) => v.len(),
            Buffer::F64(v) => v.len(),
            Buffer::I128(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A render that advances in passes and can be saved between them.
pub trait Progressive {
    /// Canonical text of the settings that decide the state after each pass:
    /// a checkpoint is resumed only by a render with the same key.
    fn key(&self) -> String;

    /// Passes in the whole render.
    fn total_passes(&self) -> u32;

    /// Progress ticks the first `passes` passes give (so that a resumed
    /// render's progress starts where it left off).
    fn ticks_after(&self, passes: u32) -> u64;

    /// Runs pass `pass` (from 0). Returns false if it was interrupted, having
    /// left the state as it was before the pass.
    fn run_pass(&mut self, scene: &Scene, pass: u32, on_tile: super::Progress) -> bool;

    /// The state to save, as named buffers.
    fn save(&self) -> Vec<(String, Buffer)>;

    /// Takes back the state `save` gave; `Err` says what does not fit.
    fn restore(&mut self, buffers: Vec<(String, Buffer)>) -> std::result::Result<(), String>;
}

/// Runs the passes of `state` not yet done (after the checkpoint of
/// `settings.files.resume`, if any), writing checkpoints as
/// `settings.files` asks. Returns (passes done, passes in all); fewer done
/// means it was interrupted (or stopped by `stop_after_passes`), and then
/// the checkpoint, if one was asked for, holds every pass done.
pub fn run(
    scene: &Scene,
    settings: &RenderSettings,
    state: &mut dyn Progressive,
    on_tile: super::Progress,
) -> Result<(u32, u32)> {
    let files = &settings.files;
    // Hashing a large scene takes a noticeable part of a second: only a
    // render that reads or writes a checkpoint needs it.
    let fingerprint = if files.resume.is_some() || files.checkpoint.is_some() {
        state_file::scene_fingerprint(&scene.desc, true)
    } else {
        0
    };
    let header = Header {
        kind: "checkpoint",
        magic: MAGIC,
        version: VERSION,
        fingerprint,
        key: state.key(),
    };
    let total = state.total_passes();
    let mut done = 0;
    if let Some(path) = &files.resume {
        let (passes, buffers) = read(path, &header)?;
        if passes > total {
            return Err(Error::Parse {
                path: path.clone(),
                message: format!("checkpoint has {passes} passes done, more than the render's {total}"),
            });
        }
        state.restore(buffers).map_err(|message| Error::Parse {
            path: path.clone(),
            message: format!("checkpoint does not fit this render: {message}"),
        })?;
        done = passes;
        on_tile.skip(state.ticks_after(done));
    }
    let mut last_write = Instant::now();
    let mut this_run = 0;
    while done < total {
        if on_tile.stopped() || files.stop_after_passes.is_some_and(|k| this_run >= k) {
            break;
        }
        if !state.run_pass(scene, done, on_tile) {
            break;
        }
        done += 1;
        this_run += 1;
        if let Some(path) = &files.checkpoint {
            if done < total && last_write.elapsed() >= files.checkpoint_every {
                write(path, &header, done, &state.save())?;
                last_write = Instant::now();
            }
        }
    }
    if done < total {
        if let Some(path) = &files.checkpoint {
            write(path, &header, done, &state.save())?;
        }
    }
    Ok((done, total))
}

/// Writes a checkpoint atomically.
pub fn write(path: &Path, header: &Header, passes: u32, buffers: &[(String, Buffer)]) -> Result<()> {
    state_file::write(path, header, |w| {
        w.u32(passes)?;
        w.u32(buffers.len() as u32)?;
        for (tag, b) in buffers {
            w.tag(tag)?;
            match b {
                Buffer::F32(v) => {
                    w.bytes(&[1])?;
                    w.u64(v.len() as u64)?;
                    for c in v.chunks(4096) {
                        w.bytes(&c.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>())?;
                    }
                }
                Buffer::F64(v) => {
                    w.bytes(&[2])?;
                    w.u64(v.len() as u64)?;
                    for c in v.chunks(4096) {
                        w.bytes(&c.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>())?;
                    }
                }
                Buffer::I128(v) => {
                    w.bytes(&[3])?;
                    w.u64(v.len() as u64)?;
                    for c in v.chunks(4096) {
                        w.bytes(&c.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>())?;
                    }
                }
            }
        }
        Ok(())
    })
}

/// Reads a checkpoint that matches `header`: passes done and the buffers.
pub fn read(path: &Path, header: &Header) -> Result<(u32, Vec<(String, Buffer)>)> {
    state_file::read(path, header, |r| {
        let passes = r.u32()?;
        let count = r.u32()?;
        if count > MAX_BUFFERS {
            return Err(r.error(format!("corrupt checkpoint: {count} buffers listed")));
        }
        let mut buffers = Vec::with_capacity(count as usize);
        for _ in 0..count {
            let tag = r.tag()?;
            let kind = r.u8()?;
            let n = r.u64()?;
            let b = match kind {
                1 => Buffer::F32(r.records::<_, 4>(n, |b| Ok(f32::from_le_bytes(*b)))?),
                2 => Buffer::F64(r.records::<_, 8>(n, |b| Ok(f64::from_le_bytes(*b)))?),
                3 => Buffer::I128(r.records::<_, 16>(n, |b| Ok(i128::from_le_bytes(*b)))?),
                k => return Err(r.error(format!("corrupt checkpoint: buffer '{tag}' of unknown type {k}"))),
            };
            buffers.push((tag, b));
        }
        Ok((passes, buffers))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Film;
    use crate::integrator::{render, render_tiles, IntegratorKind, StateFiles};

    fn scene() -> Scene {
        let mut d = crate::scene::builtin::cornell();
        d.camera.width = 40;
        d.camera.height = 24;
        Scene::build(d).unwrap()
    }

    fn path(spp: u32, files: StateFiles) -> RenderSettings {
        RenderSettings {
            integrator: IntegratorKind::Path,
            spp,
            files,
            ..RenderSettings::default()
        }
    }

    fn bits(f: &Film) -> Vec<u32> {
        f.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect()
    }

    #[test]
    fn passes_give_the_one_pass_image_bit_for_bit() {
        let scene = scene();
        // 100 spp: 25 passes of 4 samples; 5 spp (not a square): 4 and 1;
        // 3 spp: one pass.
        for (spp, passes) in [(100, 25), (5, 2), (3, 1)] {
            let settings = path(spp, StateFiles::default());
            let est = crate::integrator::path::PathTracer {
                max_depth: None,
                light_sampling: Default::default(),
                regularize: false,
                guide: None,
            };
            let (one_pass, ..) = render_tiles(&scene, &settings, &est, crate::integrator::Progress::silent());
            let out = render(&scene, &settings, &|| {}).unwrap();
            assert_eq!(out.passes, Some((passes, passes)));
            assert_eq!(bits(&out.film), bits(&one_pass), "spp {spp}");
        }
    }

    #[test]
    fn a_stopped_render_resumes_to_the_same_image_and_bad_checkpoints_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let ck = dir.path().join("render.ckpt");
        let scene = scene();
        let whole = render(&scene, &path(48, StateFiles::default()), &|| {}).unwrap();
        let stop = |k| StateFiles {
            checkpoint: Some(ck.clone()),
            stop_after_passes: Some(k),
            ..StateFiles::default()
        };
        let first = render(&scene, &path(48, stop(5)), &|| {}).unwrap();
        assert_eq!(first.passes, Some((5, 12)));
        assert!(!first.is_complete());
        // Resume into the same file, stop again, then finish.
        let resume = |k: Option<u32>| StateFiles {
            resume: Some(ck.clone()),
            stop_after_passes: k,
            ..stop(0)
        };
        let second = render(&scene, &path(48, resume(Some(3))), &|| {}).unwrap();
        assert_eq!(second.passes, Some((8, 12)));
        let saved = std::fs::read(&ck).unwrap();
        let last = render(&scene, &path(48, resume(None)), &|| {}).unwrap();
        assert!(last.is_complete());
        assert_eq!(bits(&last.film), bits(&whole.film));
        // Nothing but the checkpoint in the folder: no temporary files.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);

        let refuse = |bytes: &[u8], settings: RenderSettings, scene: &Scene, what: &str| {
            std::fs::write(&ck, bytes).unwrap();
            let e = render(scene, &settings, &|| {}).unwrap_err().to_string();
            assert!(e.contains("render.ckpt") && e.contains(what), "{what}: {e}");
        };
        for at in [10, saved.len() / 2, saved.len() - 2] {
            let mut bad = saved.clone();
            bad[at] ^= 1;
            refuse(&bad, path(48, resume(None)), &scene, "corrupt");
        }
        refuse(&saved[..saved.len() - 9], path(48, resume(None)), &scene, "truncated");
        refuse(&saved, path(64, resume(None)), &scene, "other settings");
        let mut other = scene.desc.clone();
        other.camera.fov_y_deg += 1.0;
        refuse(
            &saved,
            path(48, resume(None)),
            &Scene::build(other).unwrap(),
            "different scene",
        );
    }

    #[test]
    fn a_resumed_render_reports_the_ticks_of_the_whole_render() {
        use crate::integrator::{progress_ticks, render_observed, tile_count, CancelToken, Progress};
        use std::sync::atomic::{AtomicU64, Ordering};
        let dir = tempfile::tempdir().unwrap();
        let ck = dir.path().join("render.ckpt");
        let scene = scene();
        let (w, h) = (scene.camera.width, scene.camera.height);
        // Counts the ticks of one render of `files`; returns them and the passes.
        let ticks_of = |files: StateFiles| {
            let ticks = AtomicU64::new(0);
            let tick = || {
                ticks.fetch_add(1, Ordering::SeqCst);
            };
            let out = render_observed(
                &scene,
                &path(48, files),
                Progress::new(&tick, &CancelToken::new()),
                &|_, _| Ok(()),
            )
            .unwrap();
            (ticks.into_inner(), out.passes)
        };
        let stopped = ticks_of(StateFiles {
            checkpoint: Some(ck.clone()),
            stop_after_passes: Some(5),
            ..StateFiles::default()
        });
        assert_eq!(stopped, (5 * tile_count(w, h), Some((5, 12))));
        // The resumed render reports the 5 restored passes, then its own 7.
        let resumed = ticks_of(StateFiles {
            resume: Some(ck.clone()),
            ..StateFiles::default()
        });
        let all = progress_ticks(&path(48, StateFiles::default()), w, h);
        assert_eq!(all, 12 * tile_count(w, h));
        assert_eq!(resumed, (all, Some((12, 12))));
    }
}
