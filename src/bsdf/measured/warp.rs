//! Piecewise-bilinear densities on the unit square, sampled and inverted
//! (Dupuy & Jakob 2018, "An Adaptive Parameterization for Efficient Material
//! Acquisition and Rendering", section 5; pbrt-v4's `PiecewiseLinear2D`).
//!
//! A table of `nx` x `ny` values at the corners of a regular grid over
//! [0, 1]^2 is one density: bilinear within each patch. It may depend on
//! further parameters (a measured BRDF's incident angles), each with its own
//! grid of values; a density between two grid values is the linear blend of
//! the tables on either side, and so are its cumulative tables, so that
//! sampling and inversion stay consistent at every parameter value.

use crate::math::Vec2;
use crate::sampling::ONE_MINUS_EPS;

/// At most this many parameters (a measured BRDF's spectra use three).
const MAX_PARAMS: usize = 3;

/// A density (or, unnormalised, just an interpolant) over [0, 1]^2.
#[derive(Clone, Debug)]
pub struct PiecewiseLinear2D {
    nx: usize,
    ny: usize,
    /// Each parameter's grid values, ascending.
    params: Vec<Vec<f32>>,
    /// Each parameter's step between slices (0 for a parameter of one value).
    strides: Vec<usize>,
    /// The values, slice by slice (the last parameter fastest), row by row.
    data: Vec<f32>,
    /// Per slice: the cumulative integral of the rows (`ny` values).
    marginal: Vec<f32>,
    /// Per slice and row: the cumulative integral along the row.
    conditional: Vec<f32>,
    /// What `evaluate` multiplies the bilinear value by: the patch count
    /// for a normalised density (its values integrate to 1 in index units),
    /// 1 for an interpolant.
    scale: f32,
}

/// Where a parameter vector falls: the first slice and the blend weights of
/// each parameter's lower and upper grid value.
struct Slice {
    offset: usize,
    weights: [(f32, f32); MAX_PARAMS],
}

/// The largest `i` in [0, n - 2] with `pred(i)` (0 if none), for a
/// predicate true up to some index and false after it.
fn find_interval(n: usize, pred: impl Fn(usize) -> bool) -> usize {
    if n < 2 {
        return 0;
    }
    // Binary search for the first index where `pred` fails.
    let (mut lo, mut hi) = (1usize, n - 1);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if pred(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    (lo - 1).min(n - 2)
}

impl PiecewiseLinear2D {
    /// A density from `data` (`slices` tables of `ny` rows of `nx`, the
    /// last parameter fastest) over parameters of grid values `params`.
    /// `normalise` makes each slice integrate to 1 and builds what sampling
    /// needs; otherwise `evaluate` interpolates the values as given.
    /// Errors: a grid under 2 x 2, data of the wrong length, a parameter
    /// grid that is empty or not ascending, or (normalised) a slice with
    /// nothing to sample.
    pub fn new(data: &[f32], nx: usize, ny: usize, params: &[&[f32]], normalise: bool) -> Result<Self, String> {
        if nx < 2 || ny < 2 {
            return Err(format!("a {nx} x {ny} table: at least 2 x 2 is needed"));
        }
        if params.len() > MAX_PARAMS {
            return Err(format!("{} parameters: at most {MAX_PARAMS}", params.len()));
        }
        let mut strides = vec![0; params.len()];
        let mut slices = 1usize;
        for (d, values) in params.iter().enumerate().rev() {
            if values.is_empty() {
                return Err("a parameter without values".into());
            }
            if values
                .windows(2)
                .any(|w| w[0].partial_cmp(&w[1]) != Some(std::cmp::Ordering::Less))
            {
                return Err("a parameter's values are not ascending".into());
            }
            strides[d] = if values.len() > 1 { slices } else { 0 };
            slices = slices.saturating_mul(values.len());
        }
        let n = nx * ny;
        if data.len() != slices.saturating_mul(n) {
            return Err(format!(
                "{} values where {slices} tables of {ny} x {nx} need {}",
                data.len(),
                slices.saturating_mul(n)
            ));
        }
        let mut out = PiecewiseLinear2D {
            nx,
            ny,
            params: params.iter().map(|p| p.to_vec()).collect(),
            strides,
            data: data.to_vec(),
            marginal: Vec::new(),
            conditional: Vec::new(),
            scale: 1.0,
        };
        if !normalise {
            return Ok(out);
        }
        out.scale = ((nx - 1) * (ny - 1)) as f32;
        out.marginal = vec![0.0; slices * ny];
        out.conditional = vec![0.0; slices * n];
        for s in 0..slices {
            let d = &mut out.data[s * n..(s + 1) * n];
            let cond = &mut out.conditional[s * n..(s + 1) * n];
            let marg = &mut out.marginal[s * ny..(s + 1) * ny];
            for y in 0..ny {
                let mut sum = 0.0f64;
                for x in 0..nx - 1 {
                    let i = y * nx + x;
                    sum += 0.5 * (d[i] as f64 + d[i + 1] as f64);
                    cond[i + 1] = sum as f32;
                }
            }
            let mut sum = 0.0f64;
            for y in 0..ny - 1 {
                sum += 0.5 * (cond[(y + 1) * nx - 1] as f64 + cond[(y + 2) * nx - 1] as f64);
                marg[y + 1] = sum as f32;
            }
            let total = marg[ny - 1];
            if !(total > 0.0 && total.is_finite() && (1.0 / total).is_finite()) {
                return Err(format!(
                    "table {} of {slices} integrates to {total}: nothing to sample",
                    s + 1
                ));
            }
            let norm = 1.0 / total;
            cond.iter_mut()
                .chain(marg.iter_mut())
                .chain(d.iter_mut())
                .for_each(|v| *v *= norm);
        }
        Ok(out)
    }

    /// The slice and blend weights of `param` (clamped to each grid).
    fn slice(&self, param: &[f32]) -> Slice {
        let mut s = Slice {
            offset: 0,
            weights: [(1.0, 0.0); MAX_PARAMS],
        };
        for (d, values) in self.params.iter().enumerate() {
            if values.len() == 1 {
                continue;
            }
            let p = param[d];
            let i = find_interval(values.len(), |k| values[k] <= p);
            let (p0, p1) = (values[i], values[i + 1]);
            let w1 = ((p - p0) / (p1 - p0)).clamp(0.0, 1.0);
            // NaN parameters take the lower value.
            let w1 = if w1.is_nan() { 0.0 } else { w1 };
            s.weights[d] = (1.0 - w1, w1);
            s.offset += self.strides[d] * i;
        }
        s
    }

    /// `table[i]` blended over the slice's parameter corners, where a slice
    /// of `table` holds `size` values.
    #[inline]
    fn lookup(&self, table: &[f32], s: &Slice, i: usize, size: usize) -> f32 {
        let dims = self.params.len();
        let mut v = 0.0;
        for corner in 0..1usize << dims {
            let mut w = 1.0;
            let mut k = i;
            for d in 0..dims {
                if corner >> d & 1 == 1 {
                    w *= s.weights[d].1;
                    k += self.strides[d] * size;
                } else {
                    w *= s.weights[d].0;
                }
            }
            if w != 0.0 {
                v += w * table[k];
            }
        }
        v
    }

    /// The values at the corners of the patch whose lower corner is data
    /// index `i`: (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1).
    fn corners(&self, s: &Slice, i: usize) -> [f32; 4] {
        let (nx, size) = (self.nx, self.nx * self.ny);
        [i, i + 1, i + nx, i + nx + 1].map(|k| self.lookup(&self.data, s, k, size))
    }

    /// The patch holding `pos` (the data index of its lower corner, in the
    /// slice) and where in it `pos` lies, in [0, 1]^2.
    fn cell(&self, s: &Slice, pos: Vec2) -> (usize, f32, f32) {
        let (nx, ny) = (self.nx, self.ny);
        let (gx, gy) = grid_position(pos, nx, ny);
        let (ix, iy) = ((gx as usize).min(nx - 2), (gy as usize).min(ny - 2));
        (s.offset * nx * ny + iy * nx + ix, gx - ix as f32, gy - iy as f32)
    }

    /// The density (or interpolated value) at `pos` in [0, 1]^2.
    pub fn evaluate(&self, pos: Vec2, param: &[f32]) -> f32 {
        let s = self.slice(param);
        let (i, wx, wy) = self.cell(&s, pos);
        let [v00, v10, v01, v11] = self.corners(&s, i);
        let lower = (1.0 - wx) * v00 + wx * v10;
        let upper = (1.0 - wx) * v01 + wx * v11;
        ((1.0 - wy) * lower + wy * upper) * self.scale
    }

    /// A point of [0, 1]^2 with this density, from a uniform `u`, and its
    /// density. Only for a normalised table.
    pub fn sample(&self, u: Vec2, param: &[f32]) -> (Vec2, f32) {
        let s = self.slice(param);
        let (nx, ny) = (self.nx, self.ny);
        let size = nx * ny;
        let lo = 1.0 - ONE_MINUS_EPS;
        let (mut ux, mut uy) = (u.x.clamp(lo, ONE_MINUS_EPS), u.y.clamp(lo, ONE_MINUS_EPS));
        // The row, by the marginal.
        let m0 = s.offset * ny;
        let marginal = |k: usize| self.lookup(&self.marginal, &s, m0 + k, ny);
        let row = find_interval(ny, |k| marginal(k) < uy);
        uy -= marginal(row);
        let base = s.offset * size + row * nx;
        let r0 = self.lookup(&self.conditional, &s, base + nx - 1, size);
        let r1 = self.lookup(&self.conditional, &s, base + 2 * nx - 1, size);
        let y = solve_linear_density(r0, r1, uy);
        // The column, by the row's blend of its two conditional tables.
        ux *= (1.0 - y) * r0 + y * r1;
        let conditional = |k: usize| {
            (1.0 - y) * self.lookup(&self.conditional, &s, base + k, size)
                + y * self.lookup(&self.conditional, &s, base + nx + k, size)
        };
        let col = find_interval(nx, |k| conditional(k) < ux);
        ux -= conditional(col);
        let [v00, v10, v01, v11] = self.corners(&s, base + col);
        let c0 = (1.0 - y) * v00 + y * v01;
        let c1 = (1.0 - y) * v10 + y * v11;
        let x = solve_linear_density(c0, c1, ux);
        let p = Vec2::new((col as f32 + x) / (nx - 1) as f32, (row as f32 + y) / (ny - 1) as f32);
        (p, ((1.0 - x) * c0 + x * c1) * self.scale)
    }

    /// The uniform point `sample` maps to `pos`, and the density at `pos`:
    /// the inverse of [`PiecewiseLinear2D::sample`].
    pub fn invert(&self, pos: Vec2, param: &[f32]) -> (Vec2, f32) {
        let s = self.slice(param);
        let (nx, ny) = (self.nx, self.ny);
        let size = nx * ny;
        let (i, mut x, mut y) = self.cell(&s, pos);
        let iy = (i - s.offset * size) / nx;
        let [v00, v10, v01, v11] = self.corners(&s, i);
        let c0 = (1.0 - y) * v00 + y * v01;
        let c1 = (1.0 - y) * v10 + y * v11;
        let pdf = (1.0 - x) * c0 + x * c1;
        // The integral along the row blend up to x, then over whole rows up to y.
        x *= c0 + 0.5 * x * (c1 - c0);
        let k0 = self.lookup(&self.conditional, &s, i, size);
        let k1 = self.lookup(&self.conditional, &s, i + nx, size);
        x += (1.0 - y) * k0 + y * k1;
        let base = s.offset * size + iy * nx;
        let r0 = self.lookup(&self.conditional, &s, base + nx - 1, size);
        let r1 = self.lookup(&self.conditional, &s, base + 2 * nx - 1, size);
        x /= (1.0 - y) * r0 + y * r1;
        y *= r0 + 0.5 * y * (r1 - r0);
        y += self.lookup(&self.marginal, &s, s.offset * ny + iy, ny);
        (Vec2::new(x, y), pdf * self.scale)
    }
}

/// A point of the unit square in grid units, clamped to the grid (a
/// position a rounding past 1 or NaN would otherwise blend with weights
/// outside [0, 1], and a density turn negative).
fn grid_position(pos: Vec2, nx: usize, ny: usize) -> (f32, f32) {
    let unit = |v: f32| if v > 0.0 { v.min(1.0) } else { 0.0 };
    (unit(pos.x) * (nx - 1) as f32, unit(pos.y) * (ny - 1) as f32)
}

/// The t in [0, 1] at which the integral of the linear density from `a` at
/// 0 to `b` at 1 reaches `u`.
fn solve_linear_density(a: f32, b: f32, u: f32) -> f32 {
    let t = if (a - b).abs() < 1e-4 * (a + b) {
        2.0 * u / (a + b)
    } else {
        (a - (a * a - 2.0 * u * (a - b)).max(0.0).sqrt()) / (a - b)
    };
    if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// A lumpy table of `slices` slices.
    fn table(nx: usize, ny: usize, slices: usize) -> Vec<f32> {
        (0..slices * nx * ny)
            .map(|i| {
                let (s, x, y) = (i / (nx * ny), i % nx, i / nx % ny);
                1.0 + 0.8 * ((x * 3 + y * 5 + s * 7) % 11) as f32 / 11.0 + (x == 2 && y == 1) as u8 as f32 * 4.0
            })
            .collect()
    }

    #[test]
    fn finds_intervals_as_a_clamped_upper_bound() {
        let v = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(find_interval(4, |k| v[k] <= -1.0), 0);
        assert_eq!(find_interval(4, |k| v[k] <= 0.5), 0);
        assert_eq!(find_interval(4, |k| v[k] <= 1.0), 1);
        assert_eq!(find_interval(4, |k| v[k] <= 2.5), 2);
        assert_eq!(find_interval(4, |k| v[k] <= 9.0), 2);
    }

    #[test]
    fn normalised_densities_integrate_to_one_and_interpolants_keep_their_values() {
        let (nx, ny) = (5, 4);
        let d = table(nx, ny, 1);
        let w = PiecewiseLinear2D::new(&d, nx, ny, &[], true).unwrap();
        let n = 400;
        let mut sum = 0.0f64;
        for j in 0..n {
            for i in 0..n {
                let p = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                sum += w.evaluate(p, &[]) as f64;
            }
        }
        assert!((sum / (n * n) as f64 - 1.0).abs() < 1e-3, "{}", sum / (n * n) as f64);
        let raw = PiecewiseLinear2D::new(&d, nx, ny, &[], false).unwrap();
        for y in 0..ny {
            for x in 0..nx {
                let p = Vec2::new(x as f32 / (nx - 1) as f32, y as f32 / (ny - 1) as f32);
                assert!((raw.evaluate(p, &[]) - d[y * nx + x]).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn sampling_inverts_and_reports_the_density_it_draws_from() {
        let (nx, ny) = (6, 5);
        let thetas = [0.0f32, 0.5, 1.2];
        let phis = [-1.0f32, 2.0];
        let d = table(nx, ny, thetas.len() * phis.len());
        let w = PiecewiseLinear2D::new(&d, nx, ny, &[&phis, &thetas], true).unwrap();
        let mut rng = Rng::new(7, 0);
        for param in [[-1.0f32, 0.0], [0.3, 0.9], [2.0, 1.2], [5.0, -3.0]] {
            // Sample, then invert: the same uniform point, the same density.
            for _ in 0..500 {
                let u = rng.next_2d();
                let (p, pdf) = w.sample(u, &param);
                let (back, pdf2) = w.invert(p, &param);
                assert!((back - u).abs().max_element() < 2e-3, "{u} -> {p} -> {back}");
                assert!((pdf - pdf2).abs() < 1e-3 * pdf, "{pdf} {pdf2}");
                assert!((pdf - w.evaluate(p, &param)).abs() < 1e-3 * pdf);
                // Past the square (rounding), the density stays the edge's.
                assert!(w.evaluate(Vec2::new(1.0 + 1e-6, p.y), &param) >= 0.0);
            }
            // Samples land in each cell as often as the density says.
            let cells = 4;
            let mut counts = vec![0u32; cells * cells];
            let n = 40_000;
            for _ in 0..n {
                let (p, _) = w.sample(rng.next_2d(), &param);
                let c = ((p.x * cells as f32) as usize).min(cells - 1)
                    + cells * ((p.y * cells as f32) as usize).min(cells - 1);
                counts[c] += 1;
            }
            let m = 64;
            for (c, &count) in counts.iter().enumerate() {
                let (cx, cy) = (c % cells, c / cells);
                let mut expected = 0.0f64;
                for j in 0..m {
                    for i in 0..m {
                        let p = Vec2::new(
                            (cx as f32 + (i as f32 + 0.5) / m as f32) / cells as f32,
                            (cy as f32 + (j as f32 + 0.5) / m as f32) / cells as f32,
                        );
                        expected += w.evaluate(p, &param) as f64;
                    }
                }
                let expected = expected / (m * m * cells * cells) as f64 * n as f64;
                let sigma = expected.sqrt();
                assert!(
                    (count as f64 - expected).abs() < 5.0 * sigma,
                    "{param:?} cell {c}: {count} against {expected:.0}"
                );
            }
        }
    }

    #[test]
    fn parameters_between_grid_values_blend_the_tables() {
        let (nx, ny) = (3, 3);
        let a = [1.0f32; 9];
        let b: Vec<f32> = (0..9).map(|i| 1.0 + i as f32).collect();
        let d: Vec<f32> = a.iter().chain(&b).copied().collect();
        let w = PiecewiseLinear2D::new(&d, nx, ny, &[&[0.0, 1.0]], false).unwrap();
        let p = Vec2::new(0.5, 1.0);
        assert!((w.evaluate(p, &[0.25]) - (0.75 * 1.0 + 0.25 * 8.0)).abs() < 1e-5);
        assert!((w.evaluate(p, &[-4.0]) - 1.0).abs() < 1e-6);
        assert!((w.evaluate(p, &[9.0]) - 8.0).abs() < 1e-6);
    }

    #[test]
    fn malformed_tables_are_refused() {
        assert!(PiecewiseLinear2D::new(&[1.0; 3], 3, 1, &[], true).is_err());
        assert!(PiecewiseLinear2D::new(&[1.0; 8], 3, 3, &[], true).is_err());
        assert!(PiecewiseLinear2D::new(&[0.0; 9], 3, 3, &[], true).is_err());
        // So small that its reciprocal is infinite: nothing to sample either.
        assert!(PiecewiseLinear2D::new(&[1e-42; 9], 3, 3, &[], true).is_err());
        assert!(PiecewiseLinear2D::new(&[1.0; 18], 3, 3, &[&[1.0, 0.0]], true).is_err());
        assert!(PiecewiseLinear2D::new(&[1.0; 18], 3, 3, &[&[0.0, 1.0]], true).is_ok());
    }
}
