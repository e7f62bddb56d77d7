//! Sparse voxel grids, as OpenVDB and NanoVDB store them (leaves of 8^3
//! voxels where a volume has detail, one value for whole regions where it
//! has none), flattened for lookups: a table with one entry for each 8^3
//! block of the grid's bounding box, naming either a leaf's 512 values or a
//! constant. A lookup is then one table read and one value read, where a
//! walk down the VDB tree takes three levels of nodes.

use super::majorant::MajorantGrid;
use crate::math::Vec3;
use std::collections::HashMap;

/// Voxels along each axis of a block (a VDB leaf).
pub const BLOCK: i32 = 8;
/// Table entries with this bit name a constant, the others a leaf.
const CONSTANT: u32 = 1 << 31;
/// The most blocks a table may hold (at four bytes each, a gigabyte).
pub const MAX_BLOCKS: u64 = 1 << 28;

/// Values at the integer points of index space (voxel (i, j, k) at the
/// point (i, j, k), as VDB places them), `background` outside the blocks.
#[derive(Clone, PartialEq)]
pub struct SparseGrid {
    /// Index coordinates of the first block's first voxel (multiples of 8).
    origin: [i32; 3],
    /// Blocks along each axis.
    blocks: [usize; 3],
    /// Per block, x fastest: a leaf's number, or `CONSTANT` | a constant's.
    table: Vec<u32>,
    /// 512 values a leaf, voxel (i, j, k) of it at 64 i + 8 j + k (VDB's
    /// order: z fastest).
    leaves: Vec<f32>,
    constants: Vec<f32>,
    background: f32,
}

impl std::fmt::Debug for SparseGrid {
    // A digest: scene fingerprints print media, and a grid may hold
    // hundreds of millions of values.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let digest = self
            .leaves
            .iter()
            .chain(&self.constants)
            .map(|v| v.to_bits())
            .chain(self.table.iter().copied())
            .fold(0x9E37_79B9_7F4A_7C15u64, |h, v| crate::sampling::mix64(h ^ v as u64));
        write!(
            f,
            "SparseGrid {{ origin: {:?}, blocks: {:?}, leaves: {}, background: {}, values: {digest:016x} }}",
            self.origin,
            self.blocks,
            self.leaves.len() / 512,
            self.background
        )
    }
}

/// A [`SparseGrid`] as it is filled in, from a VDB tree's nodes.
pub struct SparseBuilder {
    grid: SparseGrid,
    constant_index: HashMap<u32, u32>,
}

impl SparseBuilder {
    /// A grid covering the voxels from `lo` to `hi` (inclusive), all
    /// `background` until filled; an error when that takes more than
    /// [`MAX_BLOCKS`] blocks.
    pub fn new(lo: [i32; 3], hi: [i32; 3], background: f32) -> Result<Self, String> {
        let origin = lo.map(|v| v.div_euclid(BLOCK) * BLOCK);
        let mut blocks = [0usize; 3];
        for a in 0..3 {
            if hi[a] < lo[a] {
                return Err(format!("an empty bounding box from {lo:?} to {hi:?}"));
            }
            blocks[a] = ((hi[a] as i64 - origin[a] as i64) / BLOCK as i64 + 1) as usize;
        }
        // Each axis may span 2^29 blocks: their product overflows.
        let count = blocks
            .iter()
            .try_fold(1u64, |a, &b| a.checked_mul(b as u64))
            .unwrap_or(u64::MAX);
        if count > MAX_BLOCKS {
            return Err(format!(
                "a bounding box from {lo:?} to {hi:?}: {count} blocks of 8^3 voxels, more than the limit of {MAX_BLOCKS}"
            ));
        }
        let mut b = SparseBuilder {
            grid: SparseGrid {
                origin,
                blocks,
                table: Vec::new(),
                leaves: Vec::new(),
                constants: Vec::new(),
                background,
            },
            constant_index: HashMap::new(),
        };
        let bg = b.constant(background);
        b.grid.table = vec![bg; count as usize];
        Ok(b)
    }

    fn constant(&mut self, v: f32) -> u32 {
        let n = self.grid.constants.len() as u32;
        let i = *self.constant_index.entry(v.to_bits()).or_insert(n);
        if i == n {
            self.grid.constants.push(v);
        }
        CONSTANT | i
    }

    /// The blocks (as ranges of block indices along each axis) within the
    /// cube of `size` voxels from `lo`, clipped to the grid.
    fn block_range(&self, lo: [i32; 3], size: i64) -> Option<[(usize, usize); 3]> {
        let mut r = [(0, 0); 3];
        for a in 0..3 {
            let first = (lo[a] as i64 - self.grid.origin[a] as i64).div_euclid(BLOCK as i64);
            let last = (lo[a] as i64 + size - 1 - self.grid.origin[a] as i64).div_euclid(BLOCK as i64);
            let n = self.grid.blocks[a] as i64;
            if last < 0 || first >= n {
                return None;
            }
            r[a] = (first.max(0) as usize, last.min(n - 1) as usize);
        }
        Some(r)
    }

    /// `value` over the cube of `size` voxels (a multiple of 8) from `lo`
    /// (a tile of a VDB node).
    pub fn fill(&mut self, lo: [i32; 3], size: i64, value: f32) {
        let Some([x, y, z]) = self.block_range(lo, size) else {
            return;
        };
        let c = self.constant(value);
        let [nx, ny, _] = self.grid.blocks;
        for bz in z.0..=z.1 {
            for by in y.0..=y.1 {
                let row = (bz * ny + by) * nx;
                self.grid.table[row + x.0..=row + x.1].fill(c);
            }
        }
    }

    /// A leaf of 512 values (z fastest) from `lo` (a multiple of 8).
    pub fn leaf(&mut self, lo: [i32; 3], values: impl IntoIterator<Item = f32>) {
        let Some([x, y, z]) = self.block_range(lo, BLOCK as i64) else {
            return;
        };
        let n = (self.grid.leaves.len() / 512) as u32;
        self.grid.leaves.extend(values.into_iter().take(512));
        self.grid.leaves.resize(512 * (n as usize + 1), self.grid.background);
        let [nx, ny, _] = self.grid.blocks;
        self.grid.table[(z.0 * ny + y.0) * nx + x.0] = n;
    }

    pub fn finish(self) -> SparseGrid {
        self.grid
    }
}

impl SparseGrid {
    /// The value of voxel (i, j, k).
    #[inline(always)]
    pub fn voxel(&self, i: i32, j: i32, k: i32) -> f32 {
        let rel = [
            i.wrapping_sub(self.origin[0]),
            j.wrapping_sub(self.origin[1]),
            k.wrapping_sub(self.origin[2]),
        ];
        let b = rel.map(|r| (r >> 3) as usize);
        // A negative offset wraps to a huge block index.
        if rel.iter().any(|&r| r < 0) || b[0] >= self.blocks[0] || b[1] >= self.blocks[1] || b[2] >= self.blocks[2] {
            return self.background;
        }
        let e = self.table[(b[2] * self.blocks[1] + b[1]) * self.blocks[0] + b[0]];
        if e & CONSTANT != 0 {
            self.constants[(e & !CONSTANT) as usize]
        } else {
            let offset = ((i & 7) << 6 | (j & 7) << 3 | (k & 7)) as usize;
            self.leaves[e as usize * 512 + offset]
        }
    }

    /// The trilinear interpolation of the voxels at index-space point `p`
    /// (NanoVDB's `TrilinearSampler`: the eight voxels around it).
    pub fn trilinear(&self, p: Vec3) -> f32 {
        if !p.is_finite() || p.abs().max_element() >= 1e9 {
            return self.background;
        }
        // floor without the library's `floorf` (a call, on the baseline
        // instruction set): truncate, then step down below zero.
        let floor = |x: f32| {
            let t = x as i32;
            t - (x < t as f32) as i32
        };
        let (i, j, k) = (floor(p.x), floor(p.y), floor(p.z));
        let d = p - Vec3::new(i as f32, j as f32, k as f32);
        let lerp = |t: f32, a: f32, b: f32| a + t * (b - a);
        let mix = |v: [f32; 8]| {
            let x00 = lerp(d.x, v[0], v[1]);
            let x10 = lerp(d.x, v[2], v[3]);
            let x01 = lerp(d.x, v[4], v[5]);
            let x11 = lerp(d.x, v[6], v[7]);
            lerp(d.z, lerp(d.y, x00, x10), lerp(d.y, x01, x11))
        };
        // Most lookups weigh eight voxels of one block: one table read.
        if (i & 7) != 7 && (j & 7) != 7 && (k & 7) != 7 {
            let rel = [
                i.wrapping_sub(self.origin[0]),
                j.wrapping_sub(self.origin[1]),
                k.wrapping_sub(self.origin[2]),
            ];
            let b = rel.map(|r| (r >> 3) as usize);
            if rel.iter().all(|&r| r >= 0) && b[0] < self.blocks[0] && b[1] < self.blocks[1] && b[2] < self.blocks[2] {
                let e = self.table[(b[2] * self.blocks[1] + b[1]) * self.blocks[0] + b[0]];
                if e & CONSTANT != 0 {
                    return self.constants[(e & !CONSTANT) as usize];
                }
                let base = e as usize * 512 + ((i & 7) << 6 | (j & 7) << 3 | (k & 7)) as usize;
                let Some(l) = self.leaves.get(base..base + 74) else {
                    return self.background;
                };
                // Voxel (i + a, j + b, k + c) at base + 64 a + 8 b + c.
                return mix([l[0], l[64], l[8], l[72], l[1], l[65], l[9], l[73]]);
            }
        }
        let v = |a: i32, b: i32, c: i32| self.voxel(i + a, j + b, k + c);
        mix([
            v(0, 0, 0),
            v(1, 0, 0),
            v(0, 1, 0),
            v(1, 1, 0),
            v(0, 0, 1),
            v(1, 0, 1),
            v(0, 1, 1),
            v(1, 1, 1),
        ])
    }

    /// Blocks of 8^3 voxels along each axis of the grid's box.
    pub fn blocks(&self) -> [usize; 3] {
        self.blocks
    }

    /// Leaves (blocks of 512 values of their own).
    pub fn leaf_count(&self) -> usize {
        self.leaves.len() / 512
    }

    /// The largest value anywhere.
    pub fn max(&self) -> f32 {
        self.leaves
            .iter()
            .chain(&self.constants)
            .fold(self.background, |a, &v| a.max(v))
    }

    /// Every value, for checks.
    pub fn values(&self) -> impl Iterator<Item = f32> + '_ {
        self.leaves.iter().chain(&self.constants).copied()
    }

    /// Bounds on the trilinear lookups over cells of `res` laid over the
    /// unit cube that `q_from_index` (affine) takes voxel space to: each
    /// block reaches lookups up to a voxel beyond it on each side, and the
    /// cube's image of that region is bounded by its corners'.
    pub fn majorants(&self, res: [usize; 3], q_from_index: impl Fn(Vec3) -> Vec3) -> MajorantGrid {
        let [nx, ny, nz] = self.blocks;
        let leaf_max: Vec<f32> = self
            .leaves
            .chunks_exact(512)
            .map(|l| l.iter().fold(f32::NEG_INFINITY, |a, &v| a.max(v)))
            .collect();
        let regions = (0..nz).flat_map(move |bz| (0..ny).flat_map(move |by| (0..nx).map(move |bx| (bx, by, bz))));
        let regions = regions.map(|(bx, by, bz)| {
            let first = Vec3::new(
                (self.origin[0] as i64 + bx as i64 * BLOCK as i64) as f32,
                (self.origin[1] as i64 + by as i64 * BLOCK as i64) as f32,
                (self.origin[2] as i64 + bz as i64 * BLOCK as i64) as f32,
            );
            let e = self.table[(bz * ny + by) * nx + bx];
            let value = if e & CONSTANT != 0 {
                self.constants[(e & !CONSTANT) as usize]
            } else {
                leaf_max[e as usize]
            };
            let (mut a, mut b) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for c in 0..8 {
                let corner = Vec3::new(
                    if c & 1 == 0 { -1.0 } else { BLOCK as f32 },
                    if c & 2 == 0 { -1.0 } else { BLOCK as f32 },
                    if c & 4 == 0 { -1.0 } else { BLOCK as f32 },
                );
                let q = q_from_index(first + corner);
                a = a.min(q);
                b = b.max(q);
            }
            (a, b, value)
        });
        // Beyond the blocks: the background.
        MajorantGrid::over_regions(res, self.background.max(0.0), regions)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_leaves_and_background_are_where_they_were_put() {
        let mut b = SparseBuilder::new([-20, -3, 5], [30, 9, 40], 0.5).unwrap();
        // A tile of 16^3 from (-16, -8, 0), clipped to the box, then a leaf
        // over part of it.
        b.fill([-16, -8, 0], 16, 2.0);
        b.leaf([-8, 0, 8], (0..512).map(|n| n as f32));
        let g = b.finish();
        assert_eq!(g.voxel(-16, -3, 5), 2.0);
        // Voxel (i, j, k) of the leaf at 64 i + 8 j + k.
        assert_eq!(g.voxel(-8, 0, 8), 0.0);
        assert_eq!(g.voxel(-7, 2, 11), (64 + 16 + 3) as f32);
        assert_eq!(g.voxel(-1, 7, 15), 511.0);
        assert_eq!(g.voxel(0, 0, 8), 0.5, "beyond the tile: the background");
        assert_eq!(g.voxel(-17, 0, 8), 0.5);
        assert_eq!(g.voxel(1000, 0, 8), 0.5, "beyond the box");
        assert_eq!(g.voxel(i32::MIN, i32::MAX, 0), 0.5);
        // Halfway between two voxels of the leaf along each axis (local
        // (0, 2, 3) to (1, 3, 4)): the mean of the eight.
        let mid = g.trilinear(Vec3::new(-7.5, 2.5, 11.5));
        assert_eq!(mid, 64.0 * 0.5 + 8.0 * 2.5 + 3.5);
        assert_eq!(g.max(), 511.0);
        assert!(SparseBuilder::new([0, 0, 0], [1 << 20, 1 << 20, 1 << 10], 0.0).is_err());
        // A box over all of index space (a count that overflows 64 bits).
        assert!(SparseBuilder::new([i32::MIN; 3], [i32::MAX; 3], 0.0).is_err());
        // Lookups within a block (one table read) and across blocks agree
        // with the eight voxels' interpolation.
        let mut rng = crate::sampling::Rng::new(1, 2);
        for _ in 0..20_000 {
            let p = Vec3::new(
                rng.next_f32() * 60.0 - 25.0,
                rng.next_f32() * 16.0 - 6.0,
                rng.next_f32() * 40.0 + 3.0,
            );
            let f = p.floor();
            let d = p - f;
            let (i, j, k) = (f.x as i32, f.y as i32, f.z as i32);
            let v = |a, b, c| g.voxel(i + a, j + b, k + c) as f64;
            let mut want = 0.0;
            for (a, wa) in [(0, 1.0 - d.x as f64), (1, d.x as f64)] {
                for (b, wb) in [(0, 1.0 - d.y as f64), (1, d.y as f64)] {
                    for (c, wc) in [(0, 1.0 - d.z as f64), (1, d.z as f64)] {
                        want += wa * wb * wc * v(a, b, c);
                    }
                }
            }
            let got = g.trilinear(p) as f64;
            assert!(
                (got - want).abs() <= 1e-4 * want.abs().max(1.0),
                "{p}: {got} against {want}"
            );
        }
    }
}
