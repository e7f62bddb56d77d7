//! NanoVDB files (`.nvdb`), as pbrt-v4's `nanovdb` medium reads them: a
//! file of segments, each a 16-byte header (magic "NanoVDB0", version,
//! grid count, codec), then per grid 176 bytes of metadata and its name,
//! then the grids' buffers, raw or zlib-compressed. A buffer is NanoVDB's
//! tree as it lies in memory: the grid's header (its index-to-world map
//! and world bounds), the tree's node offsets, the root's tiles, upper
//! internal nodes of 32^3 entries, lower ones of 16^3, leaves of 8^3
//! values. Layouts are those of NanoVDB 32 (the major version is the file
//! format's); only grids of 32-bit floats are read, into a [`SparseGrid`].

use super::sparse::{SparseBuilder, SparseGrid};
use crate::math::Vec3;
use std::io::Read;

const MAGIC: u64 = 0x3042_4456_6f6e_614e;
/// What errors about features of the format that are not read say (the
/// file may be sound).
pub const UNSUPPORTED: &str = "not supported";
const MAJOR_VERSION: u32 = 32;
const HEADER_SIZE: usize = 16;
const META_SIZE: usize = 176;
const GRID_DATA_SIZE: usize = 672;
const GRID_TYPE_FLOAT: u32 = 1;
/// Each of a file's grids and their names may be no larger (NanoVDB's
/// names are at most 255 bytes).
const MAX_NAME: usize = 256;

/// One float grid of a NanoVDB file.
#[derive(Clone, Debug)]
pub struct VdbGrid {
    pub name: String,
    pub values: SparseGrid,
    /// World (the medium's space) to index space: index = m (p - v), `m`
    /// row by row (NanoVDB's single-precision inverse map).
    pub index_from_world: ([f32; 9], [f32; 3]),
    /// The bounds of its active values in world space.
    pub world_bounds: (Vec3, Vec3),
}

impl VdbGrid {
    pub fn index_from_world(&self, p: Vec3) -> Vec3 {
        apply(&self.index_from_world, p)
    }
}

/// A grid's map from world to index space applied to `p`.
pub fn apply((m, v): &([f32; 9], [f32; 3]), p: Vec3) -> Vec3 {
    {
        let d = [p.x - v[0], p.y - v[1], p.z - v[2]];
        Vec3::new(
            m[0] * d[0] + m[1] * d[1] + m[2] * d[2],
            m[3] * d[0] + m[4] * d[1] + m[5] * d[2],
            m[6] * d[0] + m[7] * d[1] + m[8] * d[2],
        )
    }
}

/// Little-endian reads from a buffer, each an error past its end.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn get<const N: usize>(&self, at: usize) -> Result<[u8; N], String> {
        at.checked_add(N)
            .and_then(|end| self.0.get(at..end))
            .map(|s| {
                let mut a = [0u8; N];
                a.copy_from_slice(s);
                a
            })
            .ok_or_else(|| format!("truncated: a read at byte {at} past the end ({} bytes)", self.0.len()))
    }
    fn u32(&self, at: usize) -> Result<u32, String> {
        self.get::<4>(at).map(u32::from_le_bytes)
    }
    fn i32(&self, at: usize) -> Result<i32, String> {
        self.get::<4>(at).map(i32::from_le_bytes)
    }
    fn u64(&self, at: usize) -> Result<u64, String> {
        self.get::<8>(at).map(u64::from_le_bytes)
    }
    fn i64(&self, at: usize) -> Result<i64, String> {
        self.get::<8>(at).map(i64::from_le_bytes)
    }
    fn f32(&self, at: usize) -> Result<f32, String> {
        self.get::<4>(at).map(f32::from_le_bytes)
    }
    fn f64(&self, at: usize) -> Result<f64, String> {
        self.get::<8>(at).map(f64::from_le_bytes)
    }
    fn u16(&self, at: usize) -> Result<u16, String> {
        self.get::<2>(at).map(u16::from_le_bytes)
    }
    /// `base + offset`, where a node's child lies, within the buffer.
    fn child(&self, base: usize, offset: i64) -> Result<usize, String> {
        let at = base as i64 + offset;
        if offset == 0 || at < 0 || at as usize >= self.0.len() {
            return Err(format!("a node offset {offset} from byte {base} out of the grid"));
        }
        Ok(at as usize)
    }
}

/// The grids of a NanoVDB file named in `wanted`, in that order (`None`
/// for each the file lacks); an error saying what is wrong with the file.
pub fn read_grids(file: &[u8], wanted: &[&str]) -> Result<Vec<Option<VdbGrid>>, String> {
    let mut found: Vec<Option<VdbGrid>> = vec![None; wanted.len()];
    let mut at = 0usize;
    let b = Bytes(file);
    if file.len() < HEADER_SIZE {
        return Err("not a NanoVDB file (shorter than its header)".into());
    }
    while at < file.len() {
        let magic = b.u64(at)?;
        if magic != MAGIC {
            return Err(if magic.swap_bytes() == MAGIC {
                "a NanoVDB file of the other byte order".into()
            } else {
                format!("not a NanoVDB file (no \"NanoVDB0\" at byte {at})")
            });
        }
        let version = b.u32(at + 8)?;
        let major = version >> 21;
        if major != MAJOR_VERSION {
            return Err(format!(
                "NanoVDB files of version {major}.{}.{} are {UNSUPPORTED} (version {MAJOR_VERSION} ones are)",
                (version >> 10) & 0x7ff,
                version & 0x3ff
            ));
        }
        let count = b.u16(at + 12)? as usize;
        let codec = b.u16(at + 14)?;
        at += HEADER_SIZE;
        let mut metas = Vec::with_capacity(count.min(1024));
        for _ in 0..count {
            let grid_size = b.u64(at)?;
            let file_size = b.u64(at + 8)?;
            let name_size = b.u32(at + 136)? as usize;
            if name_size > MAX_NAME {
                return Err(format!("a grid name of {name_size} bytes"));
            }
            let name = file
                .get(at + META_SIZE..at + META_SIZE + name_size)
                .ok_or("truncated in a grid's name")?;
            let name = String::from_utf8_lossy(name.split(|&c| c == 0).next().unwrap_or(&[])).into_owned();
            metas.push((name, grid_size, file_size));
            at += META_SIZE + name_size;
        }
        for (name, grid_size, file_size) in metas {
            let file_size = usize::try_from(file_size).map_err(|_| "a grid larger than memory")?;
            let end = at
                .checked_add(file_size)
                .filter(|&e| e <= file.len())
                .ok_or_else(|| format!("truncated in grid \"{name}\" ({file_size} bytes from byte {at})"))?;
            if let Some(slot) = wanted.iter().position(|w| *w == name) {
                if found[slot].is_none() {
                    let stored = &file[at..end];
                    let grid = match codec {
                        0 => read_grid(stored, &name),
                        1 => inflate(stored, grid_size).and_then(|buf| read_grid(&buf, &name)),
                        2 => Err(format!(
                            "BLOSC-compressed grids are {UNSUPPORTED} (raw and ZIP ones are)"
                        )),
                        c => Err(format!("an unknown codec {c}")),
                    }
                    .map_err(|e| format!("grid \"{name}\": {e}"))?;
                    found[slot] = Some(grid);
                }
            }
            at = end;
        }
    }
    Ok(found)
}

/// A ZIP-coded grid: its compressed size, then zlib's stream of it.
fn inflate(stored: &[u8], grid_size: u64) -> Result<Vec<u8>, String> {
    let b = Bytes(stored);
    let size = b.u64(0)? as usize;
    let data = stored
        .get(8..8usize.saturating_add(size))
        .ok_or("truncated compressed data")?;
    let grid_size = usize::try_from(grid_size).map_err(|_| "a grid larger than memory")?;
    // The declared size bounds what is inflated, whatever the stream says.
    let mut out = Vec::with_capacity(grid_size.min(1 << 30));
    flate2::read::ZlibDecoder::new(data)
        .take(grid_size as u64)
        .read_to_end(&mut out)
        .map_err(|e| format!("cannot decompress: {e}"))?;
    if out.len() != grid_size {
        return Err(format!("decompressed to {} bytes, not {grid_size}", out.len()));
    }
    Ok(out)
}

/// Bytes of each kind of node (NanoVDB 32's float nodes).
const UPPER_SIZE: usize = 270_400;
const LOWER_SIZE: usize = 33_856;
const LEAF_SIZE: usize = 2_144;

fn spend(budget: &mut [usize; 3], kind: usize) -> Result<(), String> {
    if budget[kind] == 0 {
        return Err(format!(
            "more {} nodes than the grid's bytes can hold (its offsets overlap)",
            ["upper", "lower", "leaf"][kind]
        ));
    }
    budget[kind] -= 1;
    Ok(())
}

/// Voxels along each axis of the nodes below the root.
const UPPER_SPAN: i64 = 4096;
const LOWER_SPAN: i64 = 128;
const LEAF_SPAN: i64 = 8;

fn read_grid(buf: &[u8], name: &str) -> Result<VdbGrid, String> {
    let b = Bytes(buf);
    if b.u64(0)? != MAGIC {
        return Err("no grid header".into());
    }
    let grid_type = b.u32(636)?;
    if grid_type != GRID_TYPE_FLOAT {
        return Err(format!(
            "grids of NanoVDB value type {grid_type} are {UNSUPPORTED} (32-bit float ones, type 1, are)"
        ));
    }
    let map = 296;
    let mut m = [0f32; 9];
    for (k, v) in m.iter_mut().enumerate() {
        *v = b.f32(map + 36 + 4 * k)?;
    }
    let vec = [b.f32(map + 72)?, b.f32(map + 76)?, b.f32(map + 80)?];
    let mut bounds = [0f64; 6];
    for (k, v) in bounds.iter_mut().enumerate() {
        *v = b.f64(560 + 8 * k)?;
    }
    let world_bounds = (
        Vec3::new(bounds[0] as f32, bounds[1] as f32, bounds[2] as f32),
        Vec3::new(bounds[3] as f32, bounds[4] as f32, bounds[5] as f32),
    );
    if !(m.iter().chain(&vec).all(|v| v.is_finite()) && world_bounds.0.is_finite() && world_bounds.1.is_finite()) {
        return Err("its map or bounds are not finite".into());
    }
    let tree = GRID_DATA_SIZE;
    let root = b.child(tree, b.i64(tree + 24)?)?;
    let lo = [b.i32(root)?, b.i32(root + 4)?, b.i32(root + 8)?];
    let hi = [b.i32(root + 12)?, b.i32(root + 16)?, b.i32(root + 20)?];
    let tiles = b.u32(root + 24)? as usize;
    let background = b.f32(root + 28)?;
    if (0..3).any(|a| hi[a] < lo[a]) {
        return Err("it has no active voxels".into());
    }
    // Lookups reach one voxel beyond the active ones.
    let widen = |v: i32, d: i32| v.checked_add(d).ok_or("bounds at the edge of index space");
    let mut out = SparseBuilder::new(
        [widen(lo[0], -1)?, widen(lo[1], -1)?, widen(lo[2], -1)?],
        [widen(hi[0], 1)?, widen(hi[1], 1)?, widen(hi[2], 1)?],
        background,
    )?;
    if tiles > buf.len() / 32 {
        return Err(format!("{tiles} root tiles in a grid of {} bytes", buf.len()));
    }
    // Nodes do not overlap in a NanoVDB buffer, so there are at most as
    // many of each kind as fit in it: a file whose offsets share or overlap
    // nodes could otherwise make the walk take far longer than it is large.
    let mut budget = [buf.len() / UPPER_SIZE, buf.len() / LOWER_SIZE, buf.len() / LEAF_SIZE];
    for t in 0..tiles {
        let tile = root + 64 + 32 * t;
        let key = b.u64(tile)?;
        // x, y and z in 21 bits each, of the coordinates over 4096.
        let coord = |shift: u32| ((((key >> shift) & 0x1f_ffff) << 12) as u32) as i32;
        let origin = [coord(42), coord(21), coord(0)];
        let child = b.i64(tile + 8)?;
        if child == 0 {
            let value = b.f32(tile + 20)?;
            if value.to_bits() != background.to_bits() {
                out.fill(origin, UPPER_SPAN, value);
            }
            continue;
        }
        let upper = b.child(root, child)?;
        read_internal(&b, upper, origin, 5, &mut out, background, &mut budget)?;
    }
    let values = out.finish();
    if let Some(v) = values.values().find(|v| !v.is_finite()) {
        return Err(format!("a value of {v}"));
    }
    Ok(VdbGrid {
        name: name.to_string(),
        values,
        index_from_world: (m, vec),
        world_bounds,
    })
}

/// An internal node of 2^(3 log2) entries at byte `at`, whose first voxel
/// is `origin`: upper nodes (log2 5) hold lower ones, lower (4) leaves.
fn read_internal(
    b: &Bytes,
    at: usize,
    origin: [i32; 3],
    log2: u32,
    out: &mut SparseBuilder,
    background: f32,
    budget: &mut [usize; 3],
) -> Result<(), String> {
    spend(budget, if log2 == 5 { 0 } else { 1 })?;
    let (child_mask, table, span) = if log2 == 5 {
        (at + 4128, at + 8256, LOWER_SPAN)
    } else {
        (at + 544, at + 1088, LEAF_SPAN)
    };
    let dim = 1usize << log2;
    let count = dim * dim * dim;
    b.get::<8>(table + 8 * (count - 1))?;
    for n in 0..count {
        let o = [
            origin[0] as i64 + ((n >> (2 * log2)) & (dim - 1)) as i64 * span,
            origin[1] as i64 + ((n >> log2) & (dim - 1)) as i64 * span,
            origin[2] as i64 + (n & (dim - 1)) as i64 * span,
        ];
        let o = o.map(|v| v as i32);
        let word = b.u64(child_mask + 8 * (n >> 6))?;
        let entry = table + 8 * n;
        if word >> (n & 63) & 1 == 0 {
            let value = b.f32(entry)?;
            if value.to_bits() != background.to_bits() {
                out.fill(o, span, value);
            }
            continue;
        }
        let child = b.child(at, b.i64(entry)?)?;
        if log2 == 5 {
            read_internal(b, child, o, 4, out, background, budget)?;
        } else {
            spend(budget, 2)?;
            let values = b.0.get(child + 96..child + 96 + 2048).ok_or("truncated in a leaf")?;
            out.leaf(
                o,
                values
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Written by NanoVDB 32.3's own writer (ZIP codec) from
    /// `tests/data/nanovdb-fixture.cpp`: a "temperature" grid, then a
    /// "density" grid of the values `density` gives inside an ellipsoid
    /// (one 8^3 block of them a constant tile), voxels of 0.05 from (0.3,
    /// -0.2, 0.1).
    const FIXTURE: &[u8] = include_bytes!("../../tests/data/small-zip.nvdb");

    fn density(i: i32, j: i32, k: i32) -> f32 {
        // One leaf's worth of a constant, which NanoVDB stores as a tile.
        if (24..32).contains(&i) && (8..16).contains(&j) && (16..24).contains(&k) {
            return 0.9;
        }
        let (x, y, z) = ((i - 20) as f64 / 40.0, (j - 10) as f64 / 20.0, (k - 20) as f64 / 20.0);
        if x * x + y * y + z * z > 1.0 {
            return 0.0;
        }
        0.01 * (i + 2 * j + 3 * k).rem_euclid(97) as f32 + 0.1
    }

    /// Values NanoVDB's accessor and its trilinear sampler (at world points,
    /// through the grid's map) gave for the fixture.
    const VOXELS: [(i32, i32, i32, f32); 6] = [
        (20, 10, 20, 0.13),
        (-20, 10, 20, 0.7),
        (-21, 10, 20, 0.0),
        (15, 15, 15, 1.0),
        (-1000, 5, 5, 0.0),
        (33, -2, 25, 0.17),
    ];
    const SAMPLES: [([f32; 3], f32); 9] = [
        ([1.3, 0.3, 1.1], 0.13),
        ([0.51, 0.02, 0.33], 0.368),
        ([1.05, 0.41, 1.27], 0.226),
        ([0.0, 0.0, 0.0], 0.0),
        ([2.2, 0.9, 2.0], 0.0),
        ([0.3, -0.2, 0.1], 0.0),
        ([0.777, 0.123, 0.456], 0.5382),
        ([3.3, 0.5, 1.2], 0.0),
        ([1.0001, 0.2999, 0.9], 0.91998),
    ];

    /// The fixture's grids as a file without compression (codec 0), as
    /// NanoVDB writes one.
    fn uncompressed(file: &[u8]) -> Vec<u8> {
        let b = Bytes(file);
        let count = b.u16(12).unwrap() as usize;
        let mut out = file[..HEADER_SIZE].to_vec();
        out[14..16].copy_from_slice(&0u16.to_le_bytes());
        let mut at = HEADER_SIZE;
        let mut metas = vec![];
        for _ in 0..count {
            let name = b.u32(at + 136).unwrap() as usize;
            metas.push((out.len(), b.u64(at).unwrap(), b.u64(at + 8).unwrap()));
            out.extend_from_slice(&file[at..at + META_SIZE + name]);
            at += META_SIZE + name;
        }
        for (meta, grid_size, file_size) in metas {
            let raw = inflate(&file[at..at + file_size as usize], grid_size).unwrap();
            out[meta + 8..meta + 16].copy_from_slice(&grid_size.to_le_bytes());
            out.extend_from_slice(&raw);
            at += file_size as usize;
        }
        out
    }

    #[test]
    fn voxels_and_samples_are_nanovdbs() {
        for file in [FIXTURE.to_vec(), uncompressed(FIXTURE)] {
            let grids = read_grids(&file, &["density", "temperature", "smoke"]).unwrap();
            assert!(grids[2].is_none());
            let t = grids[1].as_ref().unwrap();
            // Temperatures 500 + 10 i + 3 j - k over voxels of 0.1 from
            // (-0.5, 0, 0.2); its bounds reach the far side of the last voxel.
            assert_eq!(t.values.voxel(4, 5, 6), 500.0 + 40.0 + 15.0 - 6.0);
            let (lo, hi) = t.world_bounds;
            assert!((lo - Vec3::new(-0.5, 0.0, 0.2)).abs().max_element() < 1e-5, "{lo}");
            assert!((hi - Vec3::new(3.6, 2.1, 3.3)).abs().max_element() < 1e-5, "{hi}");
            let g = grids[0].as_ref().unwrap();
            assert_eq!(g.name, "density");
            for i in -26..68 {
                for j in -14..34 {
                    for k in -4..46 {
                        assert_eq!(g.values.voxel(i, j, k), density(i, j, k), "({i}, {j}, {k})");
                    }
                }
            }
            for (i, j, k, v) in VOXELS {
                assert_eq!(g.values.voxel(i, j, k), v);
            }
            for (p, v) in SAMPLES {
                let got = g.values.trilinear(g.index_from_world(Vec3::from(p)));
                assert!((got - v).abs() <= 2e-6, "{p:?}: {got} against NanoVDB's {v}");
            }
            let (lo, hi) = g.world_bounds;
            assert!((lo - Vec3::new(-0.7, -0.7, 0.1)).abs().max_element() < 1e-5, "{lo}");
            assert!((hi - Vec3::new(3.35, 1.35, 2.15)).abs().max_element() < 1e-5, "{hi}");
        }
    }

    #[test]
    fn cells_bound_the_density_within_them() {
        let grids = read_grids(FIXTURE, &["density"]).unwrap();
        let g = grids.into_iter().next().flatten().unwrap();
        let turn = glam::Mat4::from_rotation_y(0.4) * glam::Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        let (d, (lo, hi)) = super::super::Density::nanovdb(g, None, turn).unwrap();
        let mut rng = crate::sampling::Rng::new(7, 8);
        let mut tight = 0;
        for _ in 0..200_000 {
            let q = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let p = turn.transform_point3(lo + q * (hi - lo));
            let (value, bound) = (d.density(p), d.majorants.at(q).x);
            assert!(value <= bound, "at {q}: {value} above its cell's {bound}");
            tight += (value > 0.5 * bound) as u32;
        }
        // Not merely an upper bound: most of the medium's lookups are within
        // a factor two of their cell's.
        assert!(tight > 50_000, "{tight}");
    }

    #[test]
    fn bad_files_are_errors_not_panics() {
        let raw = uncompressed(FIXTURE);
        let err = |f: &[u8]| read_grids(f, &["density", "temperature"]).unwrap_err();
        assert!(err(b"NanoVDB").contains("shorter than its header"));
        assert!(err(&[0u8; 64]).contains("not a NanoVDB file"));
        let mut v = raw.clone();
        v[8..12].copy_from_slice(&(31u32 << 21).to_le_bytes());
        assert!(err(&v).contains("version 31.0.0 are not supported"), "{}", err(&v));
        let mut v = raw.clone();
        v[14] = 2;
        assert!(err(&v).contains("BLOSC"), "{}", err(&v));
        assert!(err(&raw[..raw.len() / 2]).contains("truncated"));
        // Every prefix and many one-byte changes: an error or grids, never
        // a panic (nor a walk out of proportion to the file).
        for n in (0..raw.len()).step_by(997) {
            let _ = read_grids(&raw[..n], &["density", "temperature"]);
        }
        let mut rng = crate::sampling::Rng::new(5, 6);
        for _ in 0..3000 {
            let mut v = raw.clone();
            // The headers and nodes' first bytes, where offsets and counts are.
            let at = (rng.next_u32() as usize) % if rng.next_f32() < 0.5 { 2000 } else { v.len() };
            v[at] = rng.next_u32() as u8;
            let _ = read_grids(&v, &["density", "temperature"]);
        }
    }
}
