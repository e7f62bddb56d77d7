//! Majorant grids: the largest extinction within each cell of a coarse grid
//! laid over a grid medium's box (pbrt-v4's `MajorantGrid`, 16^3 cells, and
//! its `DDAMajorantIterator`). Tracking through the medium then takes steps
//! sized to the densest point near the ray instead of the densest point of
//! the whole medium, and crosses empty cells without stopping: in a sparse
//! grid most tentative collisions against one global majorant are null
//! events in thin or empty space, and each costs a trilinear lookup.

use crate::math::Vec3;

/// Cells along each axis (pbrt-v4's choice for its grid media).
pub const RESOLUTION: usize = 16;

/// The largest value of a field over each cell of a grid laid over the
/// unit cube.
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    res: [usize; 3],
    /// Per cell, x fastest.
    max: Vec<Vec3>,
}

impl MajorantGrid {
    /// One cell over the whole cube, holding `max`.
    pub fn uniform(max: Vec3) -> Self {
        MajorantGrid {
            res: [1, 1, 1],
            max: vec![max],
        }
    }

    /// Bounds on the trilinear interpolation of `n` samples placed at the
    /// centres of the cube's cells (zero beyond them, as `trilinear_by`
    /// looks them up), sample i holding `value(i)`, not negative. An
    /// interpolation never exceeds the largest of the eight samples it
    /// weighs, so each cell holds the largest sample that any point of it
    /// (widened by a thousandth of a cell, for points computed near its
    /// faces) can weigh.
    pub fn over_samples(n: [usize; 3], value: impl Fn(usize) -> Vec3) -> Self {
        let res = [RESOLUTION; 3];
        // The samples a lookup within cell c of `r` along an axis of `n`
        // samples can weigh: those at floor(q n - 0.5) and the next.
        let reach = |n: usize, r: usize, c: usize| {
            let (nf, rf, pad) = (n as f64, r as f64, 1e-3);
            let lo = ((c as f64 - pad) / rf * nf - 0.5).floor() as i64;
            let hi = ((c as f64 + 1.0 + pad) / rf * nf - 0.5).floor() as i64 + 1;
            (lo.max(0) as usize, (hi.max(0) as usize).min(n - 1))
        };
        let mut max = Vec::with_capacity(res.iter().product());
        for cz in 0..res[2] {
            let (z0, z1) = reach(n[2], res[2], cz);
            for cy in 0..res[1] {
                let (y0, y1) = reach(n[1], res[1], cy);
                for cx in 0..res[0] {
                    let (x0, x1) = reach(n[0], res[0], cx);
                    let mut m = Vec3::ZERO;
                    for z in z0..=z1 {
                        for y in y0..=y1 {
                            let row = (z * n[1] + y) * n[0];
                            for x in x0..=x1 {
                                m = m.max(value(row + x));
                            }
                        }
                    }
                    max.push(m);
                }
            }
        }
        MajorantGrid { res, max }
    }

    /// Bounds on a field given as regions of the cube, `res` cells along
    /// each axis: each cell holds `base` (the field's value outside every
    /// region) or the largest value of a region reaching into it (widened by
    /// a thousandth of a cell), as boxes (lo, hi, value).
    pub fn over_regions(res: [usize; 3], base: f32, regions: impl IntoIterator<Item = (Vec3, Vec3, f32)>) -> Self {
        let mut max = vec![Vec3::splat(base); res.iter().product()];
        let span = |lo: f32, hi: f32, r: usize| -> Option<(usize, usize)> {
            let (a, b) = (lo * r as f32 - 1e-3, hi * r as f32 + 1e-3);
            if !(a < r as f32 && b >= 0.0) {
                return None;
            }
            let clamp = |x: f32| (x.floor().max(0.0) as usize).min(r - 1);
            Some((clamp(a), clamp(b)))
        };
        for (lo, hi, value) in regions {
            let (Some(x), Some(y), Some(z)) = (
                span(lo.x, hi.x, res[0]),
                span(lo.y, hi.y, res[1]),
                span(lo.z, hi.z, res[2]),
            ) else {
                continue;
            };
            for cz in z.0..=z.1 {
                for cy in y.0..=y.1 {
                    let row = (cz * res[1] + cy) * res[0];
                    for m in &mut max[row + x.0..=row + x.1] {
                        *m = m.max(Vec3::splat(value));
                    }
                }
            }
        }
        MajorantGrid { res, max }
    }

    /// The largest value over the whole cube.
    #[cfg(test)]
    pub fn overall(&self) -> Vec3 {
        self.max.iter().fold(Vec3::ZERO, |a, &m| a.max(m))
    }

    /// The cell holding `q` in the unit cube (clamped into the grid).
    #[cfg(test)]
    pub fn at(&self, q: Vec3) -> Vec3 {
        let c = |a: usize| ((q[a] * self.res[a] as f32).floor() as i64).clamp(0, self.res[a] as i64 - 1) as usize;
        self.max[(c(2) * self.res[1] + c(1)) * self.res[0] + c(0)]
    }

    /// The cells the ray `o + t d` (in the cube's space) crosses for t in
    /// [t0, t1], which must lie within the cube: each as the stretch
    /// [from, to] of t within it and its value, in order, the stretches
    /// covering [t0, t1] end to end.
    pub fn cells(&self, o: Vec3, d: Vec3, t0: f32, t1: f32) -> Cells<'_> {
        let p = o + d * t0;
        let mut cells = Cells {
            grid: self,
            cell: [0; 3],
            step: [0; 3],
            next: [f32::INFINITY; 3],
            delta: [f32::INFINITY; 3],
            t: t0,
            t1,
        };
        for a in 0..3 {
            let r = self.res[a] as i64;
            let c = ((p[a] * r as f32).floor() as i64).clamp(0, r - 1);
            cells.cell[a] = c;
            if d[a] == 0.0 || r == 1 {
                // Never leaves this cell along the axis (a one-cell axis ends
                // at the cube's face, where t1 does).
                continue;
            }
            let (face, step) = if d[a] > 0.0 { (c + 1, 1) } else { (c, -1) };
            cells.step[a] = step;
            cells.next[a] = (t0 + (face as f32 / r as f32 - p[a]) / d[a]).max(t0);
            cells.delta[a] = 1.0 / (r as f32 * d[a].abs());
        }
        cells
    }
}

/// The cells along a ray: [`MajorantGrid::cells`].
pub struct Cells<'a> {
    grid: &'a MajorantGrid,
    cell: [i64; 3],
    step: [i64; 3],
    /// Where the ray crosses into the next cell along each axis.
    next: [f32; 3],
    delta: [f32; 3],
    t: f32,
    t1: f32,
}

impl Iterator for Cells<'_> {
    type Item = (f32, f32, Vec3);

    fn next(&mut self) -> Option<(f32, f32, Vec3)> {
        // Every call steps into the next cell, so the walk ends within
        // the sum of the resolutions' calls even where rounding (or a NaN) leaves t short of t1.
        if self.t >= self.t1 {
            return None;
        }
        let a = if self.next[0] <= self.next[1] && self.next[0] <= self.next[2] {
            0
        } else if self.next[1] <= self.next[2] {
            1
        } else {
            2
        };
        let res = self.grid.res;
        let index = (self.cell[2] as usize * res[1] + self.cell[1] as usize) * res[0] + self.cell[0] as usize;
        let from = self.t;
        let to = self.next[a].min(self.t1);
        self.t = to;
        self.cell[a] += self.step[a];
        self.next[a] += self.delta[a];
        if self.cell[a] < 0 || self.cell[a] >= res[a] as i64 {
            // Out of the grid: this was the last cell, whatever rounding
            // left of [t0, t1].
            self.t = self.t1;
            return Some((from, self.t1, self.grid.max[index]));
        }
        Some((from, to, self.grid.max[index]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn trilinear(n: [usize; 3], v: &[f32], q: Vec3) -> f32 {
        super::super::trilinear_by(n, q, |i| v[i])
    }

    #[test]
    fn cells_bound_every_lookup_within_them() {
        // Random grids of several sizes, sparse and dense: every lookup at a
        // random point is at most its cell's value, and some cell is tight
        // (its value is a sample's, not more).
        let mut rng = Rng::new(3, 4);
        for n in [[1, 1, 1], [4, 1, 1], [3, 5, 2], [16, 16, 16], [37, 20, 9], [70, 3, 33]] {
            let count = n.iter().product::<usize>();
            let v: Vec<f32> = (0..count)
                .map(|_| {
                    if rng.next_f32() < 0.7 {
                        0.0
                    } else {
                        rng.next_f32() * 10.0
                    }
                })
                .collect();
            let g = MajorantGrid::over_samples(n, |i| Vec3::splat(v[i]));
            let top = v.iter().fold(0.0f32, |a, &b| a.max(b));
            assert_eq!(g.overall(), Vec3::splat(top));
            for _ in 0..20_000 {
                let q = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                let d = trilinear(n, &v, q);
                assert!(d <= g.at(q).x, "{n:?} at {q}: {d} above {}", g.at(q).x);
            }
        }
        // A grid empty but for one corner sample: it reaches only the
        // corner cell (lookups elsewhere weigh other samples), and tracking
        // skips the rest.
        let n = [32, 32, 32];
        let mut v = vec![0.0; 32 * 32 * 32];
        v[0] = 1.0;
        let g = MajorantGrid::over_samples(n, |i| Vec3::splat(v[i]));
        assert_eq!(g.at(Vec3::splat(0.01)), Vec3::ONE);
        assert_eq!(g.at(Vec3::splat(0.5)), Vec3::ZERO);
        assert_eq!(g.max.iter().filter(|m| m.x > 0.0).count(), 1);
    }

    #[test]
    fn cells_along_a_ray_cover_it_in_order_and_are_the_cells_it_is_in() {
        let n = [16, 16, 16];
        let v: Vec<f32> = (0..16 * 16 * 16).map(|i| i as f32).collect();
        let g = MajorantGrid::over_samples(n, |i| Vec3::splat(v[i]));
        let mut rng = Rng::new(9, 1);
        for k in 0..2000 {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let mut d = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            if k % 5 == 0 {
                d.y = 0.0; // a ray in a plane of the grid
            }
            // From o to where the ray leaves the cube.
            let t1 = (0..3)
                .map(|a| match d[a] {
                    x if x > 0.0 => (1.0 - o[a]) / x,
                    x if x < 0.0 => -o[a] / x,
                    _ => f32::INFINITY,
                })
                .fold(f32::INFINITY, f32::min);
            let mut t = 0.0;
            let mut count = 0;
            for (from, to, m) in g.cells(o, d, 0.0, t1) {
                assert_eq!(from, t, "{o} {d}: stretches end to end");
                assert!(to >= from);
                // The middle of the stretch lies in the cell given.
                if to - from > 1e-4 {
                    let mid = o + d * (0.5 * (from + to));
                    assert_eq!(m, g.at(mid), "{o} {d} at {}", 0.5 * (from + to));
                }
                t = to;
                count += 1;
            }
            assert_eq!(t, t1, "{o} {d}: covers [t0, t1]");
            assert!(count <= 3 * 16 + 1, "{count} cells");
        }
        // A one-cell grid gives the whole stretch at once.
        let u = MajorantGrid::uniform(Vec3::splat(2.0));
        let cells: Vec<_> = u.cells(Vec3::splat(0.5), Vec3::X, 0.1, 0.4).collect();
        assert_eq!(cells, vec![(0.1, 0.4, Vec3::splat(2.0))]);
    }
}
