//! Photon maps on disk, so that many renders (tiles on other machines, or
//! renders of other image sizes and gather settings) share one traced map.
//!
//! The file is a `state_file` (header with the scene's fingerprint and the
//! tracing settings as a key, each part checksummed) whose body is a list of
//! named maps, so that a photon mapper with several maps (global, caustic)
//! keeps them in one file:
//!
//! ```text
//! map count   u32 (at most 16)
//! per map:    tag (u8 length + ASCII, e.g. "global"), photons emitted u64,
//!             unit (W of a stored power of 1.0) f32, photon count u64,
//!             count x 32-byte photon records (`Photon::to_le_bytes`), in kd-tree order
//! ```
//!
//! Records are stored in the balanced tree's order, so loading is a read,
//! not a rebuild, and the loaded map is the traced one bit for bit. The
//! scene fingerprint leaves the camera out and the key holds only what
//! decides the photons (count, bounces, first-hit storage, roulette, seed),
//! so one map serves any image size, crop, gather radius or filter.

use super::map::{Photon, PhotonMap};
use super::PhotonSettings;
use crate::error::Result;
use crate::scene::Scene;
use crate::state_file::{self, Header};
use std::path::Path;

const MAGIC: [u8; 8] = *b"RTPHOTON";
/// Layout version of the file.
const VERSION: u32 = 1;
/// Bump when photon tracing changes what it stores for the same inputs, so
/// that maps traced by an older build are refused (3: a textured
/// reflectance is kept within [0, 1]).
const TRACER_VERSION: u32 = 3;
/// Most maps a file may list.
const MAX_MAPS: u32 = 16;
const RECORD: usize = 32;
const _: () = assert!(std::mem::size_of::<Photon>() == RECORD);

/// A map as stored: its name, the photons emitted to make it, the map.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredMap {
    pub tag: String,
    pub emitted: u64,
    pub map: PhotonMap,
}

/// The canonical text of the settings that decide a traced map; `settings`
/// are the effective ones (first hits stored when final gathering needs them).
pub fn key(settings: &PhotonSettings, seed: u64) -> String {
    format!(
        "photons={} caustic_photons={} max_bounces={} store_first_hit={} roulette={} seed={seed} tracer={TRACER_VERSION}",
        settings.photons, settings.caustic_photons, settings.max_bounces, settings.store_first_hit, settings.roulette
    )
}

/// What a photon map file for this scene and key must carry.
pub fn header(scene: &Scene, key: String) -> Header {
    Header {
        kind: "photon map",
        magic: MAGIC,
        version: VERSION,
        fingerprint: state_file::scene_fingerprint(&scene.desc, false),
        key,
    }
}

/// Writes the maps to `path` atomically.
pub fn save(path: &Path, header: &Header, maps: &[StoredMap]) -> Result<()> {
    state_file::write(path, header, |w| {
        w.u32(maps.len() as u32)?;
        for m in maps {
            w.tag(&m.tag)?;
            w.u64(m.emitted)?;
            w.f32(m.map.unit)?;
            w.u64(m.map.len() as u64)?;
            // Records in blocks: one write call per block, not per photon.
            for chunk in m.map.photons().chunks(4096) {
                let bytes: Vec<u8> = chunk.iter().flat_map(|p| p.to_le_bytes()).collect();
                w.bytes(&bytes)?;
            }
        }
        Ok(())
    })
}

/// Reads the maps of a file that matches `header`, refusing anything else
/// with a one-line reason naming the file.
pub fn load(path: &Path, header: &Header) -> Result<Vec<StoredMap>> {
    state_file::read(path, header, |r| {
        let count = r.u32()?;
        if count > MAX_MAPS {
            return Err(r.error(format!("corrupt photon map: {count} maps listed (at most {MAX_MAPS})")));
        }
        let mut maps = Vec::with_capacity(count as usize);
        for _ in 0..count {
            let tag = r.tag()?;
            let emitted = r.u64()?;
            let unit = r.f32()?;
            if !(unit.is_finite() && unit > 0.0) {
                return Err(r.error(format!("corrupt photon map '{tag}': power unit {unit}")));
            }
            let n = r.u64()?;
            let photons =
                r.records::<_, RECORD>(n, |b| Photon::from_le_bytes(b).ok_or_else(|| bad_record(path, &tag)))?;
            maps.push(StoredMap {
                tag,
                emitted,
                map: PhotonMap::from_balanced(photons, unit),
            });
        }
        Ok(maps)
    })
}

fn bad_record(path: &Path, tag: &str) -> crate::Error {
    crate::Error::Parse {
        path: path.to_path_buf(),
        message: format!("corrupt photon map '{tag}': invalid photon record"),
    }
}

/// The map called `tag` among `maps`, or an error naming the file.
pub fn take(maps: &mut Vec<StoredMap>, tag: &str, path: &Path) -> Result<StoredMap> {
    match maps.iter().position(|m| m.tag == tag) {
        Some(i) => Ok(maps.remove(i)),
        None => Err(crate::Error::Parse {
            path: path.to_path_buf(),
            message: format!(
                "photon map file holds no '{tag}' map (it has: {})",
                maps.iter().map(|m| m.tag.as_str()).collect::<Vec<_>>().join(", ")
            ),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::build_map;

    fn scene() -> Scene {
        let mut d = crate::scene::builtin::cornell();
        d.camera.width = 8;
        d.camera.height = 8;
        Scene::build(d).unwrap()
    }

    fn traced(scene: &Scene, photons: u64) -> (PhotonSettings, StoredMap) {
        let s = PhotonSettings {
            photons,
            ..PhotonSettings::default()
        };
        let (map, stats) = build_map(scene, &s, 3);
        let stored = StoredMap {
            tag: "global".into(),
            emitted: stats.emitted,
            map,
        };
        (s, stored)
    }

    fn message<T: std::fmt::Debug>(r: Result<T>) -> String {
        r.unwrap_err().to_string()
    }

    #[test]
    fn a_saved_map_loads_bit_for_bit_and_damage_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("map.phm");
        let scene = scene();
        let (s, stored) = traced(&scene, 2000);
        assert!(stored.map.len() > 1000);
        let h = header(&scene, key(&s, 3));
        save(&path, &h, std::slice::from_ref(&stored)).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let mut maps = load(&path, &h).unwrap();
        let back = take(&mut maps, "global", &path).unwrap();
        assert_eq!(back, stored);
        assert_eq!(
            back.map.photons().iter().map(|p| p.to_le_bytes()).collect::<Vec<_>>(),
            stored.map.photons().iter().map(|p| p.to_le_bytes()).collect::<Vec<_>>()
        );
        assert!(message(take(&mut maps, "caustic", &path)).contains("no 'caustic' map"));

        // One flipped bit anywhere: in the header, a map header, a record, a checksum.
        for at in [3, 12, 30, bytes.len() / 2, bytes.len() - 40, bytes.len() - 1] {
            let mut bad = bytes.clone();
            bad[at] ^= 0x10;
            std::fs::write(&path, &bad).unwrap();
            let e = message(load(&path, &h));
            assert!(e.contains("map.phm"), "{e}");
            assert!(
                e.contains("corrupt") || e.contains("not a photon map") || e.contains("version"),
                "byte {at}: {e}"
            );
        }
        // Truncated anywhere, or with bytes added.
        for len in [0, 7, 20, 60, bytes.len() / 3, bytes.len() - 1] {
            std::fs::write(&path, &bytes[..len]).unwrap();
            let e = message(load(&path, &h));
            assert!(e.contains("truncated") || e.contains("not a photon map"), "{len}: {e}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        std::fs::write(&path, &longer).unwrap();
        assert!(message(load(&path, &h)).contains("trailing"));

        // Another scene, other photon settings, another seed.
        std::fs::write(&path, &bytes).unwrap();
        let mut other = crate::scene::builtin::cornell();
        other.set_light_radius(0.05);
        let other = Scene::build(other).unwrap();
        assert!(message(load(&path, &header(&other, key(&s, 3)))).contains("different scene"));
        let more = PhotonSettings { photons: 4000, ..s };
        let e = message(load(&path, &header(&scene, key(&more, 3))));
        assert!(e.contains("other settings") && e.contains("photons=2000"), "{e}");
        assert!(message(load(&path, &header(&scene, key(&s, 4)))).contains("seed=3"));
    }

    #[test]
    fn a_file_lists_several_named_maps() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.phm");
        let scene = scene();
        let (s, a) = traced(&scene, 500);
        let (_, mut b) = traced(&scene, 300);
        b.tag = "caustic".into();
        let h = header(&scene, key(&s, 3));
        save(&path, &h, &[a.clone(), b.clone()]).unwrap();
        let mut maps = load(&path, &h).unwrap();
        assert_eq!(take(&mut maps, "caustic", &path).unwrap(), b);
        assert_eq!(take(&mut maps, "global", &path).unwrap(), a);
        // No temporary file is left beside it.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
