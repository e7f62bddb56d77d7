//! A portal for a light at infinity (pbrt-v4's `PortalImageInfiniteLight`):
//! a rectangle, usually a window, through which alone the environment's
//! light enters the scene. A point sees the environment only in the
//! directions that pass through the rectangle, so a room lit through its
//! window needs no shadow ray that is sure to hit a wall.
//!
//! The environment is resampled once into a square image over the
//! portal's hemisphere, parameterised by the two angles a direction makes
//! with the portal's normal in the planes of its two sides: the directions
//! from a point through the rectangle are then an axis-aligned box of that
//! image (its window), and light samples are drawn from the image within the
//! window, in proportion to radiance times solid angle, with a summed-area
//! table.

use super::envmap::EnvMap;
use crate::math::{Ray, Vec2, Vec3};
use glam::Mat3;
use std::f32::consts::{FRAC_PI_2, PI};

#[derive(Clone, Debug, PartialEq)]
pub struct Portal {
    /// The corners in order round the rectangle.
    corners: [Vec3; 4],
    /// Columns: unit x along corner 0 -> 3, y along 0 -> 1, z = x cross y
    /// (the side the environment is on). Kept as three axes so that a
    /// reflected scene reflects them all.
    frame: Mat3,
    area: f32,
    /// The environment's radiance over the portal's hemisphere, `res` x `res`.
    res: usize,
    image: Vec<Vec3>,
    window: Windowed,
    /// Power through the rectangle per unit of the light's radiance scale.
    flux: Vec3,
}

impl Portal {
    /// A portal with corners `corners` (a rectangle, in order) in front of
    /// the environment `map` (None: constant radiance 1) whose directions
    /// reach the world through `to_world` (a rotation or reflection).
    pub fn new(corners: [Vec3; 4], map: Option<&EnvMap>, to_world: Mat3) -> Result<Portal, String> {
        if corners.iter().any(|c| !c.is_finite()) {
            return Err("portal: its corners must be finite".into());
        }
        let edge = |a: usize, b: usize| (corners[b] - corners[a]).try_normalize();
        let (Some(p01), Some(p12), Some(p32), Some(p03)) = (edge(0, 1), edge(1, 2), edge(3, 2), edge(0, 3)) else {
            return Err("portal: two of its corners coincide".into());
        };
        // pbrt-v4's tolerances: opposite sides parallel, neighbours square.
        let parallel = (p01.dot(p32) - 1.0).abs() <= 1e-3 && (p12.dot(p03) - 1.0).abs() <= 1e-3;
        let square = [p01.dot(p12), p12.dot(p32), p32.dot(p03), p03.dot(p01)]
            .iter()
            .all(|d| d.abs() <= 1e-3);
        if !parallel || !square {
            return Err("portal: its four corners, in order, must make a rectangle".into());
        }
        let z = p03.cross(p01).normalize();
        let frame = Mat3::from_cols(p03, p01, z);
        let area = (corners[1] - corners[0]).length() * (corners[3] - corners[0]).length();
        // As fine as the map across (pbrt-v4 keeps an equal-area map's size).
        let res = map.map_or(1, |m| m.width() as usize);
        let from_world = to_world.transpose();
        let mut image = Vec::with_capacity(res * res);
        let mut weights = Vec::with_capacity(res * res);
        for y in 0..res {
            for x in 0..res {
                let uv = Vec2::new((x as f32 + 0.5) / res as f32, (y as f32 + 0.5) / res as f32);
                let (local, jacobian) = local_direction(uv);
                let le = match map {
                    Some(m) => {
                        let w = (from_world * (frame * local)).normalize();
                        m.le_smooth(w)
                    }
                    None => Vec3::ONE,
                }
                .max(Vec3::ZERO);
                image.push(le);
                weights.push((le.x + le.y + le.z) / 3.0 * jacobian);
            }
        }
        let mut portal = Portal {
            corners,
            frame,
            area,
            res,
            image,
            window: Windowed::new(res, weights),
            flux: Vec3::ZERO,
        };
        // The power through the portal, area x the integral of radiance x
        // cos over the hemisphere, by the midpoint rule on at least 256 x 256
        // points (a small image's cells are too coarse for the cosine).
        let m = res.max(256);
        let mut flux = glam::DVec3::ZERO;
        for y in 0..m {
            for x in 0..m {
                let uv = Vec2::new((x as f32 + 0.5) / m as f32, (y as f32 + 0.5) / m as f32);
                let (local, jacobian) = local_direction(uv);
                flux += (portal.lookup(uv) * (local.z * jacobian)).as_dvec3();
            }
        }
        portal.flux = (flux * (area as f64 / (m * m) as f64)).as_vec3();
        Ok(portal)
    }

    /// The same portal in a scene reflected by `point` and `vector`.
    pub fn reflected(&self, point: impl Fn(Vec3) -> Vec3, vector: impl Fn(Vec3) -> Vec3) -> Portal {
        Portal {
            corners: self.corners.map(point),
            frame: Mat3::from_cols(
                vector(self.frame.x_axis),
                vector(self.frame.y_axis),
                vector(self.frame.z_axis),
            ),
            ..self.clone()
        }
    }

    pub fn corners(&self) -> [Vec3; 4] {
        self.corners
    }

    /// The power that enters through the portal, per unit radiance scale.
    pub fn flux(&self) -> Vec3 {
        self.flux
    }

    /// The image coordinates of world direction `w` (unit) and the solid
    /// angle per unit image area there; None behind the portal's plane.
    fn uv(&self, w: Vec3) -> Option<(Vec2, f32)> {
        let l = self.frame.transpose() * w;
        if l.z <= 0.0 {
            return None;
        }
        let jacobian = solid_angle_per_area(l);
        let alpha = l.x.atan2(l.z);
        let beta = l.y.atan2(l.z);
        let uv = Vec2::new(
            ((alpha + FRAC_PI_2) / PI).clamp(0.0, 1.0),
            ((beta + FRAC_PI_2) / PI).clamp(0.0, 1.0),
        );
        Some((uv, jacobian))
    }

    /// The window of image coordinates through which `p` sees the
    /// environment; None from the environment's side of the portal.
    fn window_from(&self, p: Vec3) -> Option<Bounds> {
        let (a, _) = self.uv((self.corners[0] - p).try_normalize()?)?;
        let (b, _) = self.uv((self.corners[2] - p).try_normalize()?)?;
        Some(Bounds {
            min: a.min(b),
            max: a.max(b),
        })
    }

    fn lookup(&self, uv: Vec2) -> Vec3 {
        let n = self.res;
        let x = ((uv.x * n as f32) as usize).min(n - 1);
        let y = ((uv.y * n as f32) as usize).min(n - 1);
        self.image[y * n + x]
    }

    /// Radiance (per unit scale) reaching `o` from direction `d` (unit):
    /// the environment's where the ray leaves through the portal, else none.
    pub fn le(&self, o: Vec3, d: Vec3) -> Vec3 {
        match (self.uv(d), self.window_from(o)) {
            (Some((uv, _)), Some(b)) if b.contains(uv) => self.lookup(uv),
            _ => Vec3::ZERO,
        }
    }

    /// A direction from `p` through the portal, sampled in proportion to
    /// radiance times solid angle: (direction, radiance per unit scale,
    /// solid-angle density).
    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        let b = self.window_from(p)?;
        let (uv, pdf_uv) = self.window.sample(u, &b)?;
        let (local, jacobian) = local_direction(uv);
        if jacobian <= 0.0 || pdf_uv <= 0.0 {
            return None;
        }
        Some(((self.frame * local).normalize(), self.lookup(uv), pdf_uv / jacobian))
    }

    /// The solid-angle density with which `sample_li` at `p` returns `w`.
    pub fn pdf_li(&self, p: Vec3, w: Vec3) -> f32 {
        let (Some((uv, jacobian)), Some(b)) = (self.uv(w), self.window_from(p)) else {
            return 0.0;
        };
        if jacobian <= 0.0 || !b.contains(uv) {
            return 0.0;
        }
        self.window.pdf(uv, &b) / jacobian
    }

    /// A particle entering through the portal: a point uniform on it and a
    /// direction from the whole image, the particle starting `far` behind
    /// the portal (outside the scene, so that what stands outside the window
    /// shadows it) and crossing the portal at that point. Returns the ray
    /// and its flux per unit scale (radiance x cos x area / density), or
    /// None for a black environment.
    pub fn sample_le(&self, u1: Vec2, u2: Vec2, far: f32) -> Option<(Ray, Vec3)> {
        let (uv, pdf_uv) = self.window.sample(u1, &Bounds::UNIT)?;
        let (local, jacobian) = local_direction(uv);
        if jacobian <= 0.0 || pdf_uv <= 0.0 {
            return None;
        }
        let w = (self.frame * local).normalize();
        let q =
            self.corners[0] + (self.corners[1] - self.corners[0]) * u2.y + (self.corners[3] - self.corners[0]) * u2.x;
        let flux = self.lookup(uv) * (local.z * self.area * jacobian / pdf_uv);
        Some((Ray::new(q + w * far, -w), flux))
    }

    /// The densities with which `sample_le` emits `ray`: of its start,
    /// per unit area across the ray, and of its direction.
    pub fn pdf_le(&self, ray: &Ray) -> (f32, f32) {
        let w = -ray.d;
        let Some((uv, jacobian)) = self.uv(w) else {
            return (0.0, 0.0);
        };
        let cos = (self.frame.z_axis.dot(w)).max(0.0);
        let crosses = self.crossing(ray).is_some();
        if !crosses || cos <= 0.0 || jacobian <= 0.0 {
            return (0.0, 0.0);
        }
        (1.0 / (self.area * cos), self.window.pdf(uv, &Bounds::UNIT) / jacobian)
    }

    /// Where `ray` crosses the portal, if it does.
    fn crossing(&self, ray: &Ray) -> Option<Vec3> {
        let n = self.frame.z_axis;
        let denom = n.dot(ray.d);
        if denom == 0.0 {
            return None;
        }
        let t = n.dot(self.corners[0] - ray.o) / denom;
        if t.is_nan() || t < 0.0 {
            return None;
        }
        let q = ray.o + ray.d * t - self.corners[0];
        let (e1, e3) = (self.corners[1] - self.corners[0], self.corners[3] - self.corners[0]);
        let (s, r) = (q.dot(e1) / e1.length_squared(), q.dot(e3) / e3.length_squared());
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r)).then_some(q)
    }
}

/// The portal-frame direction of image coordinates `uv`, and the solid
/// angle per unit image area there.
fn local_direction(uv: Vec2) -> (Vec3, f32) {
    let alpha = -FRAC_PI_2 + uv.x * PI;
    let beta = -FRAC_PI_2 + uv.y * PI;
    let w = Vec3::new(alpha.tan(), beta.tan(), 1.0).normalize();
    if !w.is_finite() {
        return (Vec3::Z, 0.0);
    }
    (w, solid_angle_per_area(w))
}

/// The solid angle per unit image area at portal-frame direction `w`
/// (unit, z > 0): pi^2 (1 - x^2) (1 - y^2) / z, with 1 - x^2 written as
/// y^2 + z^2 (and 1 - y^2 likewise), which keeps its precision at grazing
/// directions.
fn solid_angle_per_area(w: Vec3) -> f32 {
    PI * PI * (w.y * w.y + w.z * w.z) * (w.x * w.x + w.z * w.z) / w.z
}

/// An axis-aligned box of image coordinates.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: Vec2,
    max: Vec2,
}

impl Bounds {
    const UNIT: Bounds = Bounds {
        min: Vec2::ZERO,
        max: Vec2::ONE,
    };

    fn contains(&self, p: Vec2) -> bool {
        p.x >= self.min.x && p.x <= self.max.x && p.y >= self.min.y && p.y <= self.max.y
    }
}

/// A piecewise-constant density over the unit square, `n` x `n` cells,
/// that can be sampled within any axis-aligned window (pbrt-v4's
/// `WindowedPiecewiseConstant2D`): the integral over a window comes from a
/// summed-area table, exact for a piecewise-constant function; the window's
/// marginal in x and its conditional in y are piecewise linear, each
/// inverted by a binary search over cell edges and a linear step.
#[derive(Clone, Debug, PartialEq)]
struct Windowed {
    n: usize,
    func: Vec<f32>,
    /// (n + 1)^2 sums: entry (x, y) is the sum of the cells left of x and
    /// above y.
    sat: Vec<f64>,
}

impl Windowed {
    fn new(n: usize, func: Vec<f32>) -> Windowed {
        let m = n + 1;
        let mut sat = vec![0.0f64; m * m];
        for y in 0..n {
            let mut row = 0.0f64;
            for x in 0..n {
                row += func[y * n + x].max(0.0) as f64;
                sat[(y + 1) * m + x + 1] = sat[y * m + x + 1] + row;
            }
        }
        Windowed { n, func, sat }
    }

    /// The integral over [0, x] x [0, y] (in the unit square; the function
    /// is its cells' values).
    fn cumulative(&self, x: f32, y: f32) -> f64 {
        let n = self.n;
        let (fx, fy) = (
            (x.clamp(0.0, 1.0) * n as f32) as f64,
            (y.clamp(0.0, 1.0) * n as f32) as f64,
        );
        let (i, j) = ((fx as usize).min(n - 1), (fy as usize).min(n - 1));
        let (dx, dy) = (fx - i as f64, fy - j as f64);
        let m = n + 1;
        let s = |a: usize, b: usize| self.sat[b * m + a];
        let v = s(i, j) * (1.0 - dx) * (1.0 - dy)
            + s(i + 1, j) * dx * (1.0 - dy)
            + s(i, j + 1) * (1.0 - dx) * dy
            + s(i + 1, j + 1) * dx * dy;
        v / (n * n) as f64
    }

    fn integral(&self, b: &Bounds) -> f64 {
        let v =
            self.cumulative(b.max.x, b.max.y) - self.cumulative(b.min.x, b.max.y) - self.cumulative(b.max.x, b.min.y)
                + self.cumulative(b.min.x, b.min.y);
        v.max(0.0)
    }

    fn value(&self, p: Vec2) -> f32 {
        let n = self.n;
        let x = ((p.x * n as f32) as usize).min(n - 1);
        let y = ((p.y * n as f32) as usize).min(n - 1);
        self.func[y * n + x].max(0.0)
    }

    /// A point of window `b` in proportion to the function, and its density.
    fn sample(&self, u: Vec2, b: &Bounds) -> Option<(Vec2, f32)> {
        let (n, m) = (self.n, self.n + 1);
        let sat = |x: usize, y: usize| self.sat[y * m + x];
        // Where a coordinate falls: its cell and the fraction across it.
        let cell = |v: f32| {
            let f = (v.clamp(0.0, 1.0) * n as f32) as f64;
            let i = (f as usize).min(n - 1);
            (i, f - i as f64)
        };
        // The integral from x = 0 to edge k between the window's rows, as
        // the table interpolated at those rows (unnormalised, as the table).
        let ((j0, d0), (j1, d1)) = (cell(b.min.y), cell(b.max.y));
        let at_rows = |k: usize, j: usize, d: f64| sat(k, j) * (1.0 - d) + sat(k, j + 1) * d;
        let band = |k: usize| at_rows(k, j1, d1) - at_rows(k, j0, d0);
        let band_at = |x: f32| {
            let (i, d) = cell(x);
            band(i) * (1.0 - d) + band(i + 1) * d
        };
        let (x, total) = self.draw(u.x, b.min.x, b.max.x, band, band_at)?;
        // Within the column of cells x is in, the integral from y = 0 to
        // edge k: exact at the table's entries.
        let (i, _) = cell(x);
        let column = |k: usize| sat(i + 1, k) - sat(i, k);
        let column_at = |y: f32| {
            let (j, d) = cell(y);
            column(j) * (1.0 - d) + column(j + 1) * d
        };
        let (y, _) = self.draw(u.y, b.min.y, b.max.y, column, column_at)?;
        let p = Vec2::new(x, y);
        let total = total / (n * n) as f64;
        Some((p, (self.value(p) as f64 / total) as f32))
    }

    /// The density of `p` when sampled within `b` (zero outside it).
    fn pdf(&self, p: Vec2, b: &Bounds) -> f32 {
        let total = self.integral(b);
        if total.is_nan() || total <= 0.0 || !b.contains(p) {
            return 0.0;
        }
        (self.value(p) as f64 / total) as f32
    }

    /// A point of [lo, hi] drawn with `u` in proportion to the slope of the
    /// non-decreasing, cell-wise linear cumulative function given by
    /// `edge` and `at` (see `invert`), and the function's rise over [lo, hi].
    fn draw(
        &self,
        u: f32,
        lo: f32,
        hi: f32,
        edge: impl Fn(usize) -> f64,
        at: impl Fn(f32) -> f64,
    ) -> Option<(f32, f64)> {
        let start = at(lo);
        let rise = at(hi) - start;
        if rise.is_nan() || rise <= 0.0 {
            return None;
        }
        Some((self.invert(start + u as f64 * rise, lo, hi, edge, at)?, rise))
    }

    /// The x in [lo, hi] where the non-decreasing, cell-wise linear
    /// function reaches `target`, given by its values at cell edges (`edge`,
    /// k for x = k / n) and anywhere (`at`): a binary search over the edges
    /// inside the interval, then the linear step within the cell found.
    fn invert(
        &self,
        target: f64,
        lo: f32,
        hi: f32,
        edge: impl Fn(usize) -> f64,
        at: impl Fn(f32) -> f64,
    ) -> Option<f32> {
        let n = self.n as f32;
        // Edges strictly inside (lo, hi): k for k in first..=last.
        let first = ((lo * n).floor() as i64 + 1).max(0);
        let last = ((hi * n).ceil() as i64 - 1).min(self.n as i64);
        let (mut k0, mut k1) = (first, last);
        let mut found = None;
        // The last edge whose value is at most the target.
        while k0 <= k1 {
            let mid = k0 + (k1 - k0) / 2;
            if edge(mid as usize) <= target {
                found = Some(mid);
                k0 = mid + 1;
            } else {
                k1 = mid - 1;
            }
        }
        let (a, fa, next) = match found {
            Some(k) => (k as f32 / n, edge(k as usize), k + 1),
            None => (lo, at(lo), first),
        };
        let (b, fb) = if next <= last {
            (next as f32 / n, edge(next as usize))
        } else {
            (hi, at(hi))
        };
        let t = if fb > fa {
            ((target - fa) / (fb - fa)) as f32
        } else {
            0.0
        };
        let x = (a + t.clamp(0.0, 1.0) * (b - a)).clamp(lo, hi);
        x.is_finite().then_some(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn unit_portal() -> Portal {
        // A unit square in the plane z = 1, its environment side up (+z).
        let c = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        ];
        // x along 0 -> 3 (+y), y along 0 -> 1 (+x): z = x cross y = -z. The
        // environment is on the side z points to, so list them the other way
        // round for +z.
        let c = [c[0], c[3], c[2], c[1]];
        Portal::new(c, None, Mat3::IDENTITY).unwrap()
    }

    #[test]
    fn image_coordinates_and_directions_round_trip_with_the_solid_angle() {
        let p = unit_portal();
        assert!((p.frame.z_axis - Vec3::Z).length() < 1e-6, "{:?}", p.frame);
        let mut rng = Rng::new(3, 4);
        for _ in 0..200 {
            let uv = Vec2::new(rng.next_f32() * 0.98 + 0.01, rng.next_f32() * 0.98 + 0.01);
            let (l, j) = local_direction(uv);
            let (back, j2) = p.uv(p.frame * l).unwrap();
            assert!((back - uv).length() < 1e-4, "{uv} -> {back}");
            assert!((j - j2).abs() <= 1e-3 * j, "{j} {j2}");
        }
        // The solid angle over the whole image is the hemisphere's.
        let n = 400;
        let total: f64 = (0..n * n)
            .map(|i| {
                let uv = Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
                local_direction(uv).1 as f64
            })
            .sum::<f64>()
            / (n * n) as f64;
        // The midpoint rule's own error at this size is about 1e-3.
        assert!((total - 2.0 * std::f64::consts::PI).abs() < 2e-3 * total, "{total}");
    }

    #[test]
    fn a_point_sees_the_environment_only_through_the_portal() {
        let p = unit_portal();
        let mut rng = Rng::new(5, 6);
        let (mut through, mut blocked) = (0, 0);
        for _ in 0..4000 {
            let o = Vec3::new(
                rng.next_f32() * 3.0 - 1.0,
                rng.next_f32() * 3.0 - 1.0,
                rng.next_f32() * 2.0 - 1.5,
            );
            let d = crate::sampling::uniform_sphere(rng.next_2d());
            let crosses = p.crossing(&Ray::new(o, d)).is_some() && d.z > 0.0;
            let le = p.le(o, d);
            // Away from the rectangle's edges, where rounding may decide.
            let t = (1.0 - o.z) / d.z;
            let q = o + d * t;
            let edge = [q.x, 1.0 - q.x, q.y, 1.0 - q.y].iter().any(|e| e.abs() < 1e-3);
            if edge {
                continue;
            }
            assert_eq!(le != Vec3::ZERO, crosses, "o {o} d {d}");
            if crosses {
                through += 1;
            } else {
                blocked += 1;
            }
        }
        assert!(through > 50 && blocked > 50, "{through} {blocked}");
        // From the environment's side nothing arrives.
        assert_eq!(p.le(Vec3::new(0.5, 0.5, 2.0), Vec3::Z), Vec3::ZERO);
    }

    /// Irradiance at a point below a corner of a rectangle a x b at height c
    /// facing it, of radiance 1: pi times the point-to-rectangle form factor
    /// (Howell's catalogue, B-3).
    fn corner_irradiance(a: f64, b: f64, c: f64) -> f64 {
        let (x, y) = (a / c, b / c);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        0.5 * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan())
    }

    #[test]
    fn light_samples_give_the_irradiance_of_the_form_factor() {
        let p = unit_portal();
        let o = Vec3::new(0.0, 0.0, 0.5);
        let expected = corner_irradiance(1.0, 1.0, 0.5);
        let mut rng = Rng::new(7, 8);
        let n = 40_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            // None only at a grazing direction, where the density vanishes.
            let Some((w, le, pdf)) = p.sample_li(o, rng.next_2d()) else {
                continue;
            };
            assert!(p.le(o, w) == le || le == Vec3::ZERO);
            assert!((p.pdf_li(o, w) - pdf).abs() <= 1e-3 * pdf, "{} {pdf}", p.pdf_li(o, w));
            sum += (le.x * w.z / pdf) as f64;
        }
        let e = sum / n as f64;
        assert!((e - expected).abs() < 0.01 * expected, "{e} vs {expected}");
    }

    #[test]
    fn windowed_samples_follow_the_function_inside_the_window() {
        let n = 8;
        let mut rng = Rng::new(9, 10);
        let func: Vec<f32> = (0..n * n).map(|_| rng.next_f32() + 0.05).collect();
        let w = Windowed::new(n, func.clone());
        let b = Bounds {
            min: Vec2::new(0.13, 0.31),
            max: Vec2::new(0.77, 0.9),
        };
        // The area of cell (x, y) inside the window.
        let overlap = |x: usize, y: usize| {
            let (x0, x1) = (
                (x as f32 / n as f32).max(b.min.x),
                ((x + 1) as f32 / n as f32).min(b.max.x),
            );
            let (y0, y1) = (
                (y as f32 / n as f32).max(b.min.y),
                ((y + 1) as f32 / n as f32).min(b.max.y),
            );
            ((x1 - x0).max(0.0) * (y1 - y0).max(0.0)) as f64
        };
        // The window's integral, cell by cell.
        let mut exact = 0.0f64;
        for y in 0..n {
            for x in 0..n {
                exact += func[y * n + x] as f64 * overlap(x, y);
            }
        }
        assert!((w.integral(&b) - exact).abs() < 1e-5, "{} {exact}", w.integral(&b));
        // Histogram over the cells against the expected shares.
        let m = 200_000;
        let mut counts = vec![0u32; n * n];
        for _ in 0..m {
            let (p, pdf) = w.sample(rng.next_2d(), &b).unwrap();
            assert!(b.contains(p), "{p}");
            assert!((w.pdf(p, &b) - pdf).abs() <= 1e-5 * pdf);
            counts[((p.y * n as f32) as usize).min(n - 1) * n + ((p.x * n as f32) as usize).min(n - 1)] += 1;
        }
        let mut chi2 = 0.0;
        let mut cells = 0;
        for y in 0..n {
            for x in 0..n {
                let share = func[y * n + x] as f64 * overlap(x, y) / exact;
                let e = share * m as f64;
                if e == 0.0 {
                    assert_eq!(counts[y * n + x], 0);
                    continue;
                }
                chi2 += (counts[y * n + x] as f64 - e).powi(2) / e;
                cells += 1;
            }
        }
        // 99.9% quantile of chi-square with about 48 degrees of freedom is 84.
        assert!(chi2 < 90.0, "chi2 {chi2} over {cells} cells");
    }

    #[test]
    fn particles_cross_the_portal_and_carry_its_power() {
        let p = unit_portal();
        let mut rng = Rng::new(11, 12);
        let n = 20_000;
        let mut sum = Vec3::ZERO;
        let mut missed = 0;
        for _ in 0..n {
            let Some((ray, flux)) = p.sample_le(rng.next_2d(), rng.next_2d(), 10.0) else {
                missed += 1;
                continue;
            };
            assert!(ray.d.z < 0.0 && ray.o.z > 1.0, "{ray:?}");
            assert!(p.crossing(&ray).is_some());
            let (pos, dir) = p.pdf_le(&ray);
            assert!(pos > 0.0 && dir > 0.0);
            sum += flux / n as f32;
        }
        // Radiance 1 through a unit area from a hemisphere: pi.
        assert!(missed < 5, "{missed}");
        assert!((sum.x - PI).abs() < 0.02 * PI, "{sum}");
        assert!((p.flux().x - PI).abs() < 0.01 * PI, "{}", p.flux());
    }

    #[test]
    fn the_resampled_image_shows_the_environment_the_right_way_round() {
        // A smooth map that tells directions apart, turned into the world.
        let n = 64;
        let texels: Vec<Vec3> = (0..n * n)
            .map(|i| {
                let uv = Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
                let w = crate::sampling::equal_area_square_to_sphere(uv);
                Vec3::new(2.0 + w.x, 2.0 + w.y, 2.0 + w.z)
            })
            .collect();
        let map = EnvMap::new(n as u32, n as u32, texels, crate::light::EnvMapping::Octahedral, "test").unwrap();
        let to_world = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(-1.1);
        let c = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
        ];
        let p = Portal::new(c, Some(&map), to_world).unwrap();
        let mut rng = Rng::new(13, 14);
        let o = Vec3::new(0.5, 0.5, 0.0);
        for _ in 0..500 {
            let d = (Vec3::new(rng.next_f32(), rng.next_f32(), 1.0) - o).normalize();
            let expected = map.le((to_world.transpose() * d).normalize());
            let le = p.le(o, d);
            // Within a few texels' change of the map (each image read at its
            // nearest texel, the resampling bilinear); a mirrored or turned
            // image would be off by up to 2.
            assert!((le - expected).abs().max_element() < 0.15, "{d}: {le} vs {expected}");
        }
    }

    #[test]
    fn a_portal_that_is_no_rectangle_is_refused() {
        let skewed = [Vec3::ZERO, Vec3::X, Vec3::new(1.5, 1.0, 0.0), Vec3::new(0.5, 1.0, 0.0)];
        assert!(Portal::new(skewed, None, Mat3::IDENTITY).is_err());
        let repeated = [Vec3::ZERO, Vec3::ZERO, Vec3::X, Vec3::Y];
        assert!(Portal::new(repeated, None, Mat3::IDENTITY).is_err());
        let nan = [Vec3::NAN, Vec3::X, Vec3::ONE, Vec3::Y];
        assert!(Portal::new(nan, None, Mat3::IDENTITY).is_err());
    }
}
