//! Directions learned from caustic photons, for the path tracer to aim its
//! diffuse bounces with (Jensen 1995, "Importance driven path tracing using
//! the photon map").
//!
//! A diffuse point lit through a glossy or specular surface by a small light
//! (a wall seeing a lamp in a polished plate) receives that light through a
//! solid angle a cosine-distributed bounce almost never finds: the rare path
//! that does carries a huge weight, a firefly. Photons find such paths
//! easily, since they start at the light. Each caustic photon (light ->
//! glossy or specular surfaces -> the first diffuse surface) is binned by
//! where it landed (a cell of a uniform grid, and which of the six axis
//! directions the surface faces, so that a floor and the wall at its corner
//! stay apart) and by the direction it came from. A cell's histogram of
//! directions, each bin weighted by the photons' power, is a density over
//! the sphere that the path tracer mixes with its BSDF's.
//!
//! Photons fall densely in a bright caustic and sparsely elsewhere, so the
//! grid comes in four sizes, 128 to 16 cells along the scene's longest side,
//! and a point takes the finest of its cells that holds enough photons to
//! say where its light comes from. A photon adds its power to its own
//! direction bin and, by a tent, to the eight around it: directions between
//! the photons' own are found too.
//!
//! The direction bins are equal in solid angle: 64 bands of equal height in
//! z (Archimedes: equal heights on the sphere are equal areas) times 128
//! sectors of longitude, 1.5 msr each. Only occupied bins are stored, sorted,
//! with the cell's cumulative distribution; sampling and density lookups
//! are binary searches, so a density is exactly the probability its sample
//! was drawn with.

use super::Photon;
use crate::math::{Aabb, Vec2, Vec3};
use std::f32::consts::PI;

const BANDS: u32 = 64;
const SECTORS: u32 = 128;
/// Cells holding fewer photons than this guide nothing: a handful of
/// photons says too little about where the light comes from.
const MIN_PHOTONS: usize = 32;
/// Grid cells along the scene's longest side, finest first.
const LEVELS: [f32; 4] = [128.0, 64.0, 32.0, 16.0];

/// The caustic photons' directions, cell by cell.
#[derive(Clone, Debug, Default)]
pub struct PhotonGuide {
    origin: Vec3,
    /// Inverse cell size of each level.
    inv_cell: [f32; LEVELS.len()],
    /// Cell keys, sorted; `cells[i]` is key `keys[i]`'s range of `bins`.
    keys: Vec<u64>,
    /// Open addressing over `keys` (index + 1, 0 empty), a power of two
    /// long: a point looks up to four cells up, most of them absent, and a
    /// binary search over every cell took 4% of a guided render.
    table: Vec<u32>,
    cells: Vec<(u32, u32)>,
    /// Occupied direction bins of each cell, ascending.
    bins: Vec<u16>,
    /// Each cell's cumulative distribution over its bins (its last is 1).
    cdf: Vec<f32>,
}

/// One cell's distribution of directions.
#[derive(Clone, Copy, Debug)]
pub struct GuideCell<'a> {
    bins: &'a [u16],
    cdf: &'a [f32],
}

impl PhotonGuide {
    /// The guide of `photons` (their powers relative to any common unit)
    /// in a scene of bounds `bounds`.
    pub fn build(photons: &[Photon], bounds: Aabb) -> PhotonGuide {
        let extent = (bounds.max - bounds.min).max_element();
        if photons.is_empty() || !extent.is_finite() || extent <= 0.0 {
            return PhotonGuide::default();
        }
        let inv_cell = LEVELS.map(|n| n / extent);
        let origin = bounds.min;
        let mut records: Vec<(u64, u16, f32)> = Vec::new();
        for ph in photons {
            let w = ph.power().dot(Vec3::splat(1.0 / 3.0));
            if !(w > 0.0 && w.is_finite()) {
                continue;
            }
            let (n, wi) = (ph.normal(), ph.wi());
            for (level, &inv) in inv_cell.iter().enumerate() {
                if let Some(key) = cell_key(origin, inv, level, ph.p, n) {
                    records.push((key, bin_of(wi), w));
                }
            }
        }
        // Sorted by cell and bin, stably: ties keep the photons' order,
        // which the trace fixes whatever the threads, so the sums and the
        // guide are the same bit for bit.
        records.sort_by_key(|r| (r.0, r.1));
        let mut guide = PhotonGuide {
            origin,
            inv_cell,
            ..PhotonGuide::default()
        };
        let mut spread: Vec<(u16, f32)> = Vec::new();
        for cell in records.chunk_by(|a, b| a.0 == b.0) {
            if cell.len() < MIN_PHOTONS {
                continue;
            }
            spread.clear();
            for r in cell {
                splat(r.1, |bin, share| spread.push((bin, r.2 * share)));
            }
            spread.sort_by_key(|r| r.0);
            let total: f64 = spread.iter().map(|r| r.1 as f64).sum();
            let start = guide.bins.len() as u32;
            let mut sum = 0.0f64;
            for bin in spread.chunk_by(|a, b| a.0 == b.0) {
                sum += bin.iter().map(|r| r.1 as f64).sum::<f64>();
                guide.bins.push(bin[0].0);
                guide.cdf.push((sum / total) as f32);
            }
            if let Some(last) = guide.cdf.last_mut() {
                *last = 1.0;
            }
            guide.keys.push(cell[0].0);
            guide.cells.push((start, guide.bins.len() as u32));
        }
        guide.table = vec![0; (guide.keys.len() * 2).next_power_of_two()];
        let mask = guide.table.len() - 1;
        for (i, &key) in guide.keys.iter().enumerate() {
            let mut slot = hash(key) & mask;
            while guide.table[slot] != 0 {
                slot = (slot + 1) & mask;
            }
            guide.table[slot] = i as u32 + 1;
        }
        guide
    }

    /// The index of the cell of key `key`, if it guides.
    #[inline]
    fn find(&self, key: u64) -> Option<usize> {
        let mask = self.table.len() - 1;
        let mut slot = hash(key) & mask;
        loop {
            let i = self.table[slot].checked_sub(1)? as usize;
            if self.keys[i] == key {
                return Some(i);
            }
            slot = (slot + 1) & mask;
        }
    }

    /// Cells that guide.
    pub fn cells(&self) -> usize {
        self.keys.len()
    }

    /// The distribution of directions at `p` on a surface facing `n` (the
    /// side the path is on), if photons told of any there.
    #[inline]
    pub fn cell(&self, p: Vec3, n: Vec3) -> Option<GuideCell<'_>> {
        if self.keys.is_empty() {
            return None;
        }
        let i = (0..LEVELS.len()).find_map(|level| {
            let key = cell_key(self.origin, self.inv_cell[level], level, p, n)?;
            self.find(key)
        })?;
        let (a, b) = self.cells[i];
        let r = a as usize..b as usize;
        Some(GuideCell {
            bins: &self.bins[r.clone()],
            cdf: &self.cdf[r],
        })
    }
}

impl GuideCell<'_> {
    /// A direction: a bin by its weight (`u1`), a point uniform in it (`u2`).
    pub fn sample(&self, u1: f32, u2: Vec2) -> Vec3 {
        let i = self.cdf.partition_point(|&c| c <= u1).min(self.cdf.len() - 1);
        let bin = self.bins[i] as u32;
        let (band, sector) = (bin / SECTORS, bin % SECTORS);
        let z = (-1.0 + 2.0 * (band as f32 + u2.x) / BANDS as f32).clamp(-1.0, 1.0);
        let phi = 2.0 * PI * (sector as f32 + u2.y) / SECTORS as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// Solid-angle density of `sample` drawing direction `w`.
    pub fn pdf(&self, w: Vec3) -> f32 {
        let bin = bin_of(w);
        match self.bins.binary_search(&bin) {
            Ok(i) => {
                let before = if i == 0 { 0.0 } else { self.cdf[i - 1] };
                (self.cdf[i] - before) * (BANDS * SECTORS) as f32 / (4.0 * PI)
            }
            Err(_) => 0.0,
        }
    }
}

/// The key of the cell holding `p` on a surface facing `n`: the grid cell
/// and the axis direction nearest `n`.
#[inline]
fn cell_key(origin: Vec3, inv_cell: f32, level: usize, p: Vec3, n: Vec3) -> Option<u64> {
    let c = (p - origin) * inv_cell;
    if !c.is_finite() || c.min_element() < -1.0 || c.max_element() >= (1 << 19) as f32 - 1.0 {
        return None;
    }
    // Shifted by one so that points a little outside the bounds still key.
    let [x, y, z] = c.to_array().map(|v| (v.floor() + 1.0) as u64);
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let face = (axis * 2) as u64 + (n[axis] < 0.0) as u64;
    Some(((level as u64) << 62) | (x << 43) | (y << 24) | (z << 5) | face)
}

/// Calls `add(bin, share)` for direction bin `own` and the eight around
/// it, shares by a tent (a half for its own bin, the rest to its
/// neighbours) summing to 1. Bands past the poles are left out (their share
/// goes to the rest); sectors wrap around.
#[inline]
fn splat(own: u16, mut add: impl FnMut(u16, f32)) {
    let own = own as u32;
    let (band, sector) = (own / SECTORS, own % SECTORS);
    let weight = |d: i32| if d == 0 { 0.5 } else { 0.25 };
    let mut total = 0.0;
    for db in -1..=1i32 {
        let b = band as i32 + db;
        if (0..BANDS as i32).contains(&b) {
            total += weight(db);
        }
    }
    for db in -1..=1i32 {
        let b = band as i32 + db;
        if !(0..BANDS as i32).contains(&b) {
            continue;
        }
        for ds in -1..=1i32 {
            let s = (sector as i32 + ds).rem_euclid(SECTORS as i32) as u32;
            add((b as u32 * SECTORS + s) as u16, weight(db) * weight(ds) / total);
        }
    }
}

/// A slot of the cells' table for `key` (Fibonacci hashing).
#[inline]
fn hash(key: u64) -> usize {
    (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize
}

/// The direction bin of unit vector `w`.
#[inline]
fn bin_of(w: Vec3) -> u16 {
    let band = (((w.z + 1.0) * 0.5 * BANDS as f32) as u32).min(BANDS - 1);
    let phi = w.y.atan2(w.x);
    let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
    let sector = ((phi * (SECTORS as f32 / (2.0 * PI))) as u32).min(SECTORS - 1);
    (band * SECTORS + sector) as u16
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    const BIN_SOLID_ANGLE: f32 = 4.0 * PI / (BANDS * SECTORS) as f32;

    fn unit_box() -> Aabb {
        Aabb {
            min: Vec3::ZERO,
            max: Vec3::splat(16.0),
        }
    }

    /// `n` photons on the floor (facing +y) uniform over the square of
    /// side `side` at `corner`, arriving from around `wi` (within `spread`
    /// radians), each of power `power`.
    fn floor_photons(
        rng: &mut Rng,
        corner: Vec3,
        side: f32,
        wi: Vec3,
        spread: f32,
        power: f32,
        n: usize,
    ) -> Vec<Photon> {
        (0..n)
            .map(|_| {
                let u = rng.next_2d();
                let p = corner + Vec3::new(u.x * side, 0.0, u.y * side);
                let j = (rng.next_2d() - Vec2::splat(0.5)) * (2.0 * spread);
                let w = (wi + Vec3::new(j.x, 0.0, j.y)).normalize();
                Photon::new(p, w, Vec3::Y, Vec3::splat(power), 0, false)
            })
            .collect()
    }

    #[test]
    fn a_cells_densities_are_the_probabilities_its_samples_are_drawn_with() {
        // Two lobes of directions, one carrying three times the other's power.
        let mut rng = Rng::new(7, 0);
        let (a, b) = (Vec3::new(0.6, 0.8, 0.0), Vec3::new(-0.28, 0.96, 0.0));
        let corner = Vec3::new(4.0, 2.0, 4.0);
        let mut photons = floor_photons(&mut rng, corner, 0.1, a, 0.05, 3.0, 400);
        photons.extend(floor_photons(&mut rng, corner, 0.1, b, 0.05, 1.0, 400));
        let guide = PhotonGuide::build(&photons, unit_box());
        let cell = guide
            .cell(corner + Vec3::new(0.05, 0.0, 0.05), Vec3::Y)
            .expect("a cell");
        // The densities integrate to one over the sphere (bin by bin: each
        // bin's density is constant).
        let mut total = 0.0f64;
        for band in 0..BANDS {
            for sector in 0..SECTORS {
                let z = -1.0 + 2.0 * (band as f32 + 0.5) / BANDS as f32;
                let phi = 2.0 * PI * (sector as f32 + 0.5) / SECTORS as f32;
                let r = (1.0 - z * z).sqrt();
                let w = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                total += (cell.pdf(w) * BIN_SOLID_ANGLE) as f64;
            }
        }
        assert!((total - 1.0).abs() < 1e-4, "{total}");
        // Samples fall in each bin as often as its density says, and each
        // has the density of a bin that was drawn.
        let n = 400_000;
        let mut counts = std::collections::HashMap::new();
        let (mut near_a, mut near_b) = (0, 0);
        for _ in 0..n {
            let w = cell.sample(rng.next_f32(), rng.next_2d());
            assert!((w.length() - 1.0).abs() < 1e-4 && cell.pdf(w) > 0.0, "{w}");
            *counts.entry(bin_of(w)).or_insert(0u32) += 1;
            near_a += (w.dot(a) > 0.99) as u32;
            near_b += (w.dot(b) > 0.99) as u32;
        }
        for (&bin, &count) in &counts {
            let i = cell.bins.binary_search(&bin).expect("a bin of the cell");
            let p = cell.cdf[i] - if i == 0 { 0.0 } else { cell.cdf[i - 1] };
            let expected = p as f64 * n as f64;
            let sigma = expected.sqrt().max(1.0);
            assert!(
                (count as f64 - expected).abs() < 5.0 * sigma,
                "bin {bin}: {count} vs {expected}"
            );
        }
        // The lobes are drawn in proportion to their power.
        let ratio = near_a as f32 / near_b as f32;
        assert!((ratio - 3.0).abs() < 0.3, "{near_a} near a, {near_b} near b");
    }

    #[test]
    fn a_point_takes_the_finest_cell_that_knows_enough_on_the_side_it_faces() {
        let mut rng = Rng::new(3, 0);
        let a = Vec3::new(0.0, 1.0, 0.0);
        let b = Vec3::new(0.8, 0.6, 0.0);
        // Dense light from `a` in a square smaller than the finest cell
        // (1/8), sparse light from `b` over the coarsest cell (1) around it.
        let mut photons = floor_photons(&mut rng, Vec3::new(8.0, 1.0, 8.0), 0.1, a, 0.01, 1.0, 100);
        photons.extend(floor_photons(
            &mut rng,
            Vec3::new(8.0, 1.0, 8.0),
            1.0,
            b,
            0.01,
            1.0,
            200,
        ));
        let guide = PhotonGuide::build(&photons, unit_box());
        // (a few of the sparse photons fall in the fine cell too)
        let inside = guide.cell(Vec3::new(8.05, 1.0, 8.05), Vec3::Y).expect("the fine cell");
        assert!(
            inside.pdf(a) > 10.0 * inside.pdf(b),
            "{} {}",
            inside.pdf(a),
            inside.pdf(b)
        );
        // Where few photons fell, a coarser cell (of side 1/2 here, the
        // first with 32 photons) and its directions.
        let beside = guide.cell(Vec3::new(8.7, 1.0, 8.7), Vec3::Y).expect("a coarse cell");
        assert!(beside.pdf(a) == 0.0 && beside.pdf(b) > 0.0);
        // A wall at the same place faces elsewhere; far away nothing fell.
        assert!(guide.cell(Vec3::new(8.05, 1.0, 8.05), Vec3::X).is_none());
        assert!(guide.cell(Vec3::new(8.05, 1.0, 8.05), -Vec3::Y).is_none());
        assert!(guide.cell(Vec3::new(2.0, 1.0, 2.0), Vec3::Y).is_none());
        // Too few photons anywhere guide nothing.
        let few = PhotonGuide::build(&photons[..MIN_PHOTONS - 1], unit_box());
        assert_eq!(few.cells(), 0);
        assert!(few.cell(Vec3::new(8.05, 1.0, 8.05), Vec3::Y).is_none());
    }
}
