//! Binary files that carry render state between runs and machines: photon
//! maps (`photon::file`) and checkpoints (`integrator::checkpoint`).
//!
//! Both share one layout, all numbers little-endian:
//!
//! ```text
//! magic        8 bytes, names the kind of file
//! version      u32, the layout version of that kind
//! fingerprint  u64, FNV-1a 64 of the scene's canonical bytes (see `scene_fingerprint`)
//! key          u32 length + UTF-8 text: the settings that determine the contents,
//!              canonical ("photons=200000 max_bounces=5 ..."), compared verbatim
//! header crc   u32, CRC-32 (IEEE) of every byte above
//! body         kind-specific
//! body crc     u32, CRC-32 of the body
//! ```
//!
//! The header has its own checksum so that a file made for another scene or
//! other settings is refused before its (possibly large) body is read, and a
//! corrupt header is not mistaken for a mismatch. Anything after the body crc
//! is an error too. The fingerprint is FNV-1a 64 (Fowler, Noll, Vo; offset
//! basis 0xcbf29ce484222325, prime 0x100000001b3) because it is tiny, stable
//! and fully specified; it detects accidents, not forgeries.

use crate::error::{Error, Result};
use crate::light::Light;
use crate::math::Vec3;
use crate::scene::SceneDesc;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// Longest key text a reader accepts.
const MAX_KEY: u32 = 1 << 16;

/// FNV-1a 64 over bytes fed in order.
#[derive(Clone, Copy, Debug)]
pub struct Fnv64(u64);

impl Default for Fnv64 {
    fn default() -> Self {
        Fnv64(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv64 {
    pub fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }

    pub fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }

    pub fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }

    pub fn vec3(&mut self, v: Vec3) {
        self.f32(v.x);
        self.f32(v.y);
        self.f32(v.z);
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// Fingerprint of what a scene is made of: materials, triangles (with their
/// vertex normals, so `--smooth` counts), spheres, disks and lights, in description
/// order, as raw f32 bits. With `camera`, the camera and image size too (a
/// checkpoint's pixels depend on them; a photon map's photons do not, unless
/// image textures or bump maps are looked up with the camera's footprint). The
/// scene's name and its recommended settings are left out: settings that
/// matter are in the file's key.
pub fn scene_fingerprint(desc: &SceneDesc, camera: bool) -> u64 {
    let mut h = Fnv64::default();
    h.u32(desc.materials.len() as u32);
    for (_, m) in &desc.materials {
        // The Debug form lists every parameter, floats in their shortest
        // exact decimal form: equal strings, equal materials.
        h.bytes(format!("{m:?}").as_bytes());
    }
    h.u32(desc.triangles.len() as u32);
    for t in desc.triangles.iter() {
        t.vertices.iter().for_each(|&v| h.vec3(v));
        match t.normals {
            Some(ns) => {
                h.u32(1);
                ns.iter().for_each(|&v| h.vec3(v));
            }
            None => h.u32(0),
        }
        if let Some(uv) = t.uvs {
            h.u32(2);
            uv.iter().for_each(|&c| h.vec3(c.extend(0.0)));
        }
        h.u32(t.material);
    }
    h.u32(desc.spheres.len() as u32);
    for s in &desc.spheres {
        h.vec3(s.sphere.centre);
        h.f32(s.sphere.radius);
        h.u32(s.material);
        // Hashed only when given, so that a sphere without keeps its fingerprint.
        if let Some(a) = s.axes {
            a.to_cols_array().iter().for_each(|&v| h.f32(v));
        }
    }
    // Disks came later: a scene without them keeps the fingerprint it had.
    if !desc.disks.is_empty() {
        h.bytes(b"disks");
        h.u32(desc.disks.len() as u32);
        for d in &desc.disks {
            h.vec3(d.centre);
            h.vec3(d.normal);
            h.f32(d.radius);
            h.f32(d.inner_radius);
            h.u32(d.material);
            match d.axes {
                Some(axes) => {
                    h.u32(1);
                    axes.iter().for_each(|&v| h.vec3(v));
                }
                None => h.u32(0),
            }
        }
    }
    // Curves came later still.
    if !desc.curves.is_empty() {
        h.bytes(b"curves");
        h.u32(desc.curves.len() as u32);
        for c in &desc.curves {
            c.curve.cp.iter().for_each(|&p| h.vec3(p));
            c.curve.u.iter().chain(&c.curve.width).for_each(|&v| h.f32(v));
            h.u32(c.curve.kind as u32);
            // Ribbons came later: their normals only where there are some.
            if c.curve.kind == crate::geometry::CurveKind::Ribbon {
                c.curve.n.iter().for_each(|&v| h.vec3(v));
            }
            h.u32(c.material);
        }
    }
    h.u32(desc.lights.len() as u32);
    // Emission images are shared by a mesh's triangles: each is hashed once.
    // Images came later: hashed only where there is one.
    let mut images: Vec<*const crate::light::EmissionImage> = vec![];
    let mut image = |h: &mut Fnv64, im: &std::sync::Arc<crate::light::EmissionImage>| {
        h.bytes(b"image");
        let ptr = std::sync::Arc::as_ptr(im);
        match images.iter().position(|&p| p == ptr) {
            Some(i) => h.u32(i as u32),
            None => {
                images.push(ptr);
                let (w, height, texels) = im.identity();
                h.u32(w);
                h.u32(height);
                texels.iter().for_each(|&v| h.vec3(v));
            }
        }
    };
    for l in &desc.lights {
        match *l {
            Light::Sphere {
                sphere,
                power,
                image: ref im,
                emits,
            } => {
                h.u32(0);
                h.vec3(sphere.centre);
                h.f32(sphere.radius);
                h.vec3(power);
                if let Some(t) = im {
                    image(&mut h, &t.image);
                    t.axes.to_cols_array().iter().for_each(|&v| h.f32(v));
                }
                // Spheres emitting inwards came later: hashed only then.
                if emits != crate::light::Emits::Outwards {
                    h.bytes(format!("{emits:?}").as_bytes());
                }
            }
            Light::Point { position, power } => {
                h.u32(1);
                h.vec3(position);
                h.vec3(power);
            }
            Light::Triangle {
                vertices,
                radiance,
                two_sided,
                image: ref im,
            } => {
                h.u32(2);
                vertices.iter().for_each(|&v| h.vec3(v));
                h.vec3(radiance);
                h.u32(two_sided as u32);
                if let Some(t) = im {
                    image(&mut h, &t.image);
                    t.uv.iter().for_each(|uv| h.vec3(uv.extend(0.0)));
                }
            }
            Light::Disk {
                disk,
                radiance,
                two_sided,
                image: ref im,
            } => {
                h.u32(7);
                h.bytes(format!("{disk:?}").as_bytes());
                h.vec3(radiance);
                h.u32(two_sided as u32);
                if let Some(im) = im {
                    image(&mut h, im);
                }
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cos_falloff_start,
                cos_falloff_end,
            } => {
                h.u32(3);
                h.vec3(position);
                h.vec3(direction);
                h.vec3(intensity);
                h.f32(cos_falloff_start);
                h.f32(cos_falloff_end);
            }
            Light::Goniometric {
                position,
                intensity,
                to_light,
                ref map,
            } => {
                h.u32(8);
                h.vec3(position);
                h.vec3(intensity);
                to_light.to_cols_array().iter().for_each(|&v| h.f32(v));
                h.u32(map.width());
                map.texels().iter().for_each(|&t| h.vec3(t));
            }
            Light::Projection {
                position,
                intensity,
                to_light,
                ref projector,
            } => {
                h.u32(9);
                h.vec3(position);
                h.vec3(intensity);
                to_light.to_cols_array().iter().for_each(|&v| h.f32(v));
                let (w, height, tan, texels) = projector.identity();
                h.u32(w);
                h.u32(height);
                h.f32(tan);
                texels.iter().for_each(|&t| h.vec3(t));
            }
            Light::Distant {
                direction, radiance, ..
            } => {
                h.u32(4);
                h.vec3(direction);
                h.vec3(radiance);
            }
            Light::Infinite {
                radiance,
                ref map,
                to_world,
                ref portal,
                ..
            } => {
                h.u32(5);
                h.vec3(radiance);
                to_world.to_cols_array().iter().for_each(|&v| h.f32(v));
                match map {
                    Some(m) => {
                        h.u32(m.width());
                        h.u32(m.height());
                        h.u32(m.mapping() as u32);
                        m.texels().iter().for_each(|&t| h.vec3(t));
                    }
                    None => h.u32(0),
                }
                // Portals came later: hashed only where there is one.
                if let Some(p) = portal {
                    h.bytes(b"portal");
                    p.corners().iter().for_each(|&c| h.vec3(c));
                }
            }
        }
    }
    // Cut-outs came later still: hashed only when there are some. The Debug
    // form names an image texture's file by its content hash.
    if !desc.cutouts.is_empty() {
        h.bytes(b"cutouts");
        h.bytes(format!("{:?}", desc.cutouts).as_bytes());
    }
    // So did emitters that reflect, likewise.
    if desc.light_surfaces.iter().any(Option::is_some) {
        h.bytes(b"light surfaces");
        h.bytes(format!("{:?}", desc.light_surfaces).as_bytes());
    }
    // So did invisible lights, likewise.
    if desc.invisible_lights.iter().any(|&b| b) {
        h.bytes(b"invisible lights");
        (0..desc.invisible_lights.len())
            .filter(|&i| desc.invisible_lights[i])
            .for_each(|i| h.u32(i as u32));
    }
    // So did media, likewise.
    if !desc.media.is_empty() {
        h.bytes(b"media");
        h.bytes(format!("{:?} {:?} {:?}", desc.media, desc.camera_medium, desc.boundaries).as_bytes());
    }
    // Motion came later still: hashed only when something moves.
    if let Some(m) = &desc.camera_motion {
        h.bytes(b"camera motion");
        h.bytes(format!("{m:?}").as_bytes());
    }
    if !desc.moving.is_empty() || desc.camera_motion.is_some() {
        h.bytes(b"moving");
        for m in &desc.moving {
            h.u32(m.triangles.start as u32);
            h.u32(m.triangles.end as u32);
            h.bytes(format!("{:?}", m.motion).as_bytes());
        }
        h.f32(desc.shutter[0]);
        h.f32(desc.shutter[1]);
    }
    // Texture lookups filtered by the camera's footprint make even photons
    // depend on the camera and the sample count.
    let footprinted = desc.materials.iter().any(|(_, m)| m.needs_footprint());
    if footprinted {
        h.bytes(b"footprint");
        h.u32(desc.texture_spp);
    }
    if camera || footprinted {
        let c = &desc.camera;
        h.vec3(c.position);
        h.vec3(c.look_at);
        h.vec3(c.up);
        h.f32(c.fov_y_deg);
        h.u32(c.width);
        h.u32(c.height);
        // Hashed only when present, so that the fingerprints of pinhole
        // cameras with the default window are what they were.
        if let Some(w) = c.window {
            h.u32(1);
            for v in [w.left, w.right, w.bottom, w.top] {
                h.f32(v);
            }
        }
        if let Some(l) = c.lens {
            h.u32(2);
            h.f32(l.radius);
            h.f32(l.focal_distance);
        }
        if let Some(o) = c.orthographic {
            h.u32(3);
            h.f32(o);
        }
        if let Some(m) = c.spherical {
            h.u32(4);
            h.bytes(format!("{m:?}").as_bytes());
        }
    }
    h.finish()
}

/// What a file must be to be accepted: its kind, layout version, scene
/// fingerprint and settings key.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Header {
    /// The kind of file, e.g. "photon map".
    pub kind: &'static str,
    pub magic: [u8; 8],
    pub version: u32,
    pub fingerprint: u64,
    pub key: String,
}

/// Writes a state file to a temporary file beside `path` and renames it into
/// place once complete (so a crash leaves the old file or none, never half
/// of one). `body` writes the body through the [`Writer`].
pub fn write(path: &Path, header: &Header, body: impl FnOnce(&mut Writer) -> std::io::Result<()>) -> Result<()> {
    crate::image_io::write_atomic(path, |tmp| {
        let io = |source| Error::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = std::fs::File::create(tmp).map_err(io)?;
        let mut w = Writer {
            out: BufWriter::with_capacity(1 << 20, file),
            crc: crc32fast::Hasher::new(),
        };
        (|| {
            w.bytes(&header.magic)?;
            w.u32(header.version)?;
            w.u64(header.fingerprint)?;
            w.u32(header.key.len() as u32)?;
            w.bytes(header.key.as_bytes())?;
            w.end_section()?;
            body(&mut w)?;
            w.end_section()?;
            let file = w.out.into_inner().map_err(|e| e.into_error())?;
            file.sync_all()
        })()
        .map_err(io)
    })
}

/// Writes little-endian numbers and keeps the running CRC-32.
pub struct Writer {
    out: BufWriter<std::fs::File>,
    crc: crc32fast::Hasher,
}

impl Writer {
    pub fn bytes(&mut self, b: &[u8]) -> std::io::Result<()> {
        self.crc.update(b);
        self.out.write_all(b)
    }

    pub fn u32(&mut self, v: u32) -> std::io::Result<()> {
        self.bytes(&v.to_le_bytes())
    }

    pub fn u64(&mut self, v: u64) -> std::io::Result<()> {
        self.bytes(&v.to_le_bytes())
    }

    pub fn f32(&mut self, v: f32) -> std::io::Result<()> {
        self.bytes(&v.to_le_bytes())
    }

    /// A short name: u8 length + ASCII.
    pub fn tag(&mut self, t: &str) -> std::io::Result<()> {
        debug_assert!(t.len() < 256);
        self.bytes(&[t.len() as u8])?;
        self.bytes(t.as_bytes())
    }

    /// Writes the CRC-32 of the section so far (uncounted) and starts the next.
    fn end_section(&mut self) -> std::io::Result<()> {
        let crc = std::mem::take(&mut self.crc).finalize();
        self.out.write_all(&crc.to_le_bytes())
    }
}

/// Reads a state file written by [`write`]: checks its header against
/// `expected` (magic, version, then checksum, then fingerprint and key), runs
/// `body` over the body, and checks the body's checksum and the end of file.
/// Every failure names the file and says what is wrong with it.
pub fn read<T>(path: &Path, expected: &Header, body: impl FnOnce(&mut Reader) -> Result<T>) -> Result<T> {
    let file = std::fs::File::open(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let len = file.metadata().map(|m| m.len()).unwrap_or(u64::MAX);
    let mut r = Reader {
        path: path.to_path_buf(),
        kind: expected.kind,
        input: BufReader::with_capacity(1 << 20, file),
        crc: crc32fast::Hasher::new(),
        offset: 0,
        len,
    };
    let mut magic = [0u8; 8];
    if len < 8 || r.fill(&mut magic).is_err() || magic != expected.magic {
        return Err(r.error(format!("not a {} file", expected.kind)));
    }
    let version = r.u32()?;
    if version != expected.version {
        return Err(r.error(format!(
            "{} format version {version}, but this build reads version {} (a file of another build, or corrupt)",
            expected.kind, expected.version
        )));
    }
    let fingerprint = r.u64()?;
    let key_len = r.u32()?;
    if key_len > MAX_KEY {
        return Err(r.error(format!("corrupt {} header (key of {key_len} bytes)", expected.kind)));
    }
    let key = r.vec(key_len as usize)?;
    r.check_section("header")?;
    let key = String::from_utf8_lossy(&key).into_owned();
    if fingerprint != expected.fingerprint {
        return Err(r.error(format!(
            "{} made for a different scene (fingerprint {fingerprint:016x}, this scene's is {:016x})",
            expected.kind, expected.fingerprint
        )));
    }
    if key != expected.key {
        return Err(r.error(format!(
            "{} made with other settings ({key}), not with these ({})",
            expected.kind, expected.key
        )));
    }
    let value = body(&mut r)?;
    r.check_section("body")?;
    let mut extra = [0u8; 1];
    if r.input.read(&mut extra).map_err(|e| r.io(e))? != 0 {
        return Err(r.error(format!(
            "trailing bytes after the {} at byte {}",
            expected.kind, r.offset
        )));
    }
    Ok(value)
}

/// Reads little-endian numbers, keeps the running CRC-32, and knows the file
/// length so that declared counts are checked before anything is allocated.
pub struct Reader {
    path: PathBuf,
    kind: &'static str,
    input: BufReader<std::fs::File>,
    crc: crc32fast::Hasher,
    offset: u64,
    len: u64,
}

impl Reader {
    /// An error naming the file.
    pub fn error(&self, message: String) -> Error {
        Error::Parse {
            path: self.path.clone(),
            message,
        }
    }

    fn io(&self, source: std::io::Error) -> Error {
        Error::Io {
            path: self.path.clone(),
            source,
        }
    }

    pub fn fill(&mut self, buf: &mut [u8]) -> Result<()> {
        match self.input.read_exact(buf) {
            Ok(()) => {
                self.crc.update(buf);
                self.offset += buf.len() as u64;
                Ok(())
            }
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => Err(self.truncated(buf.len() as u64)),
            Err(e) => Err(self.io(e)),
        }
    }

    fn truncated(&self, want: u64) -> Error {
        self.error(format!(
            "truncated {}: ends at byte {}, needs at least {}",
            self.kind,
            self.len,
            self.offset + want
        ))
    }

    /// Checks that `n` more bytes (plus the closing checksum) fit in the file
    /// before allocating for them.
    pub fn expect(&self, n: u64) -> Result<()> {
        match self.offset.checked_add(n).and_then(|e| e.checked_add(4)) {
            Some(end) if end <= self.len => Ok(()),
            _ => Err(self.truncated(n.saturating_add(4))),
        }
    }

    fn vec(&mut self, n: usize) -> Result<Vec<u8>> {
        self.expect(n as u64)?;
        let mut v = vec![0u8; n];
        self.fill(&mut v)?;
        Ok(v)
    }

    pub fn u8(&mut self) -> Result<u8> {
        let mut b = [0u8; 1];
        self.fill(&mut b)?;
        Ok(b[0])
    }

    pub fn u32(&mut self) -> Result<u32> {
        let mut b = [0u8; 4];
        self.fill(&mut b)?;
        Ok(u32::from_le_bytes(b))
    }

    pub fn u64(&mut self) -> Result<u64> {
        let mut b = [0u8; 8];
        self.fill(&mut b)?;
        Ok(u64::from_le_bytes(b))
    }

    pub fn f32(&mut self) -> Result<f32> {
        Ok(f32::from_bits(self.u32()?))
    }

    pub fn tag(&mut self) -> Result<String> {
        let n = self.u8()?;
        Ok(String::from_utf8_lossy(&self.vec(n as usize)?).into_owned())
    }

    /// Reads `count` records of `SIZE` bytes each through `decode`, in
    /// blocks, after checking that the file holds them.
    pub fn records<T, const SIZE: usize>(
        &mut self,
        count: u64,
        mut decode: impl FnMut(&[u8; SIZE]) -> Result<T>,
    ) -> Result<Vec<T>> {
        self.expect(count.saturating_mul(SIZE as u64))?;
        let mut out = Vec::with_capacity(count as usize);
        let mut block = vec![0u8; SIZE * 4096];
        let mut left = count as usize;
        while left > 0 {
            let n = left.min(4096);
            self.fill(&mut block[..n * SIZE])?;
            for rec in block[..n * SIZE].chunks_exact(SIZE) {
                let rec: &[u8; SIZE] = rec.try_into().map_err(|_| self.error("record size".into()))?;
                out.push(decode(rec)?);
            }
            left -= n;
        }
        Ok(out)
    }

    fn check_section(&mut self, what: &str) -> Result<()> {
        let computed = std::mem::take(&mut self.crc).finalize();
        let mut b = [0u8; 4];
        match self.input.read_exact(&mut b) {
            Ok(()) => self.offset += 4,
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Err(self.truncated(4)),
            Err(e) => return Err(self.io(e)),
        }
        let stored = u32::from_le_bytes(b);
        if stored != computed {
            return Err(self.error(format!(
                "corrupt {}: {what} checksum mismatch (stored {stored:08x}, computed {computed:08x})",
                self.kind
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_matches_the_published_test_vectors() {
        for (text, want) in [
            ("", 0xcbf2_9ce4_8422_2325u64),
            ("a", 0xaf63_dc4c_8601_ec8c),
            ("foobar", 0x8594_4171_f739_67e8),
        ] {
            let mut h = Fnv64::default();
            h.bytes(text.as_bytes());
            assert_eq!(h.finish(), want, "{text:?}");
        }
    }

    #[test]
    fn scene_fingerprint_sees_geometry_lights_and_camera_only_when_asked() {
        let a = crate::scene::builtin::cornell();
        let mut b = a.clone();
        b.camera.width += 1;
        b.name = "other".into();
        assert_eq!(scene_fingerprint(&a, false), scene_fingerprint(&b, false));
        assert_ne!(scene_fingerprint(&a, true), scene_fingerprint(&b, true));
        let mut c = a.clone();
        let mut t = c.triangles.get(3).unwrap();
        t.vertices[1].y += 1e-6;
        c.triangles.set(3, t);
        assert_ne!(scene_fingerprint(&a, false), scene_fingerprint(&c, false));
        let mut d = a.clone();
        d.set_light_radius(0.0);
        assert_ne!(scene_fingerprint(&a, false), scene_fingerprint(&d, false));
    }

    #[test]
    fn scene_fingerprint_sees_a_roughness_texture() {
        use crate::material::{ConductorFresnel, Material, MaterialRoughness};
        use crate::math::Vec3;
        use crate::texture::Texture;
        use std::sync::Arc;
        let with = |odd: f32| {
            let mut d = crate::scene::builtin::cornell();
            let check = Arc::new(Texture::checkerboard(
                Arc::new(Texture::from(Vec3::splat(0.3))),
                Arc::new(Texture::from(Vec3::splat(odd))),
                4.0,
                4.0,
            ));
            d.materials[0].1 = Material::Conductor {
                fresnel: ConductorFresnel::Reflectance(Texture::from(Vec3::ONE)),
                roughness: MaterialRoughness::Textured {
                    u: check.clone(),
                    v: check,
                    remap: true,
                },
            };
            scene_fingerprint(&d, false)
        };
        assert_ne!(with(0.01), with(0.02));
    }

    #[test]
    fn a_photon_fingerprint_sees_the_camera_and_sample_count_only_with_footprinted_textures() {
        use crate::material::Material;
        use crate::math::Vec3;
        use crate::texture::{ImageOptions, ImageTexture, TexImage, Texture};
        use std::sync::Arc;
        let moved = |d: &SceneDesc| {
            let mut m = d.clone();
            m.camera.position.x += 0.1;
            m
        };
        let more = |d: &SceneDesc| SceneDesc {
            texture_spp: 16,
            ..d.clone()
        };
        // Without image textures the photons do not depend on either.
        let plain = crate::scene::builtin::cornell();
        for other in [moved(&plain), more(&plain)] {
            assert_eq!(scene_fingerprint(&plain, false), scene_fingerprint(&other, false));
        }
        // An image's MIP level follows the camera's footprint, so they do.
        let mut textured = plain.clone();
        let img = TexImage::from_pixels("t", 2, 1, vec![Vec3::ZERO, Vec3::ONE]);
        textured.materials[0].1 = Material::Diffuse {
            reflectance: Texture::Image(Arc::new(ImageTexture::new(Arc::new(img), &ImageOptions::default()))),
        };
        for other in [moved(&textured), more(&textured)] {
            assert_ne!(scene_fingerprint(&textured, false), scene_fingerprint(&other, false));
        }
    }

    #[test]
    fn scene_fingerprint_sees_ribbon_normals_and_invisible_lights() {
        use crate::geometry::{Curve, CurveKind};
        use crate::math::Vec3;
        use crate::scene::CurveDesc;
        let a = crate::scene::builtin::cornell();
        let mut b = a.clone();
        let p = |x: f32| Vec3::new(x, 0.5, 0.0);
        b.curves.push(CurveDesc {
            curve: Curve {
                cp: [p(-0.2), p(-0.1), p(0.1), p(0.2)],
                u: [0.0, 1.0],
                width: [0.05, 0.05],
                kind: CurveKind::Ribbon,
                n: [Vec3::Z, Vec3::Y],
            },
            material: 0,
        });
        let fb = scene_fingerprint(&b, false);
        assert_ne!(scene_fingerprint(&a, false), fb);
        let mut c = b.clone();
        c.curves[0].curve.n[1] = Vec3::X;
        assert_ne!(scene_fingerprint(&c, false), fb);
        // An invisible light is another scene; no invisible light is none.
        let mut d = a.clone();
        d.invisible_lights = vec![false; d.lights.len()];
        assert_eq!(scene_fingerprint(&d, false), scene_fingerprint(&a, false));
        d.invisible_lights[0] = true;
        assert_ne!(scene_fingerprint(&d, false), scene_fingerprint(&a, false));
    }

    #[test]
    fn scene_fingerprint_sees_disks() {
        use crate::math::Vec3;
        use crate::scene::DiskDesc;
        let a = crate::scene::builtin::cornell();
        let mut b = a.clone();
        b.disks.push(DiskDesc::new(Vec3::ZERO, Vec3::Y, 0.5, 0.0, 0));
        let fb = scene_fingerprint(&b, false);
        assert_ne!(scene_fingerprint(&a, false), fb);
        let changes: [fn(&mut DiskDesc); 6] = [
            |d| d.centre.x += 1e-6,
            |d| d.normal = Vec3::new(0.0, 1.0, 1e-6),
            |d| d.radius = 0.5001,
            |d| d.inner_radius = 0.1,
            |d| d.material = 1,
            |d| d.axes = Some([Vec3::X, Vec3::Z]),
        ];
        for change in changes {
            let mut c = b.clone();
            change(&mut c.disks[0]);
            assert_ne!(scene_fingerprint(&c, false), fb);
        }
    }

    #[test]
    fn scene_fingerprint_sees_media_and_their_boundaries() {
        use crate::math::Vec3;
        use crate::medium::{Medium, MediumInterface};
        use crate::scene::{Boundary, CutShapes};
        let a = crate::scene::builtin::cornell();
        let mut b = a.clone();
        let fog = Medium {
            sigma_a: Vec3::splat(0.1),
            sigma_s: Vec3::splat(0.2),
            g: 0.0,
            density: None,
            emission: None,
        };
        b.media.push(("fog".into(), fog));
        b.camera_medium = Some(0);
        let fb = scene_fingerprint(&b, false);
        assert_ne!(scene_fingerprint(&a, false), fb);
        let mut c = b.clone();
        c.media[0].1.g = 0.1;
        assert_ne!(scene_fingerprint(&c, false), fb);
        // A density grid, and any one of its values.
        let grid = |v: f32| {
            let g = crate::medium::Density::grid([2, 1, 1], vec![1.0, v], Vec3::ZERO, Vec3::ONE, glam::Mat4::IDENTITY);
            Some(std::sync::Arc::new(g.unwrap()))
        };
        let mut c = b.clone();
        c.media[0].1.density = grid(2.0);
        let fc = scene_fingerprint(&c, false);
        assert_ne!(fc, fb);
        c.media[0].1.density = grid(2.5);
        assert_ne!(scene_fingerprint(&c, false), fc);
        c.media[0].1.density = grid(2.0);
        assert_eq!(scene_fingerprint(&c, false), fc);
        let mut c = b.clone();
        c.camera_medium = None;
        assert_ne!(scene_fingerprint(&c, false), fb);
        let mut c = b.clone();
        c.boundaries.push(Boundary {
            interface: MediumInterface {
                inside: Some(0),
                outside: None,
            },
            shapes: CutShapes::Triangles(0..2),
        });
        assert_ne!(scene_fingerprint(&c, false), fb);
    }
}
