//! Participating media: homogeneous volumes that absorb and scatter light
//! between surfaces (pbrt-v4's `HomogeneousMedium` with its Henyey-Greenstein
//! phase function), and the interfaces that bound them.
//!
//! A medium fills the space on one side of the surfaces that name it
//! (pbrt-v4's `MediumInterface`): a ray crossing such a surface enters the
//! medium on the side it leaves towards, outside along the surface's normal,
//! inside against it. A surface whose two sides are the same medium leaves
//! a ray in the medium it was in. Surfaces of no material (pbrt-v4's
//! `interface`) only bound media: rays pass through them unchanged.
//!
//! Coefficients are per RGB channel, in inverse scene units. Light travels
//! through a distance d with transmittance exp(-sigma_t d), sigma_t =
//! sigma_a + sigma_s, and a fraction sigma_s / sigma_t of what a medium
//! stops is scattered, into directions the phase function gives. A medium
//! may also emit, sigma_a Le per unit length ([`Emission`]).

mod majorant;
pub mod nanovdb;
pub mod presets;
mod sparse;

use crate::math::{to_world, Vec2, Vec3};
use crate::sampling::{mix64, Rng};
use crate::texture::noise::{noise, noise_gradient};
use glam::Mat4;
use majorant::MajorantGrid;
use sparse::SparseGrid;
use std::f32::consts::PI;
use std::sync::Arc;

/// A medium: homogeneous, or scaled from point to point by a density grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Absorption coefficient (where the density is one).
    pub sigma_a: Vec3,
    /// Scattering coefficient (where the density is one).
    pub sigma_s: Vec3,
    /// Henyey-Greenstein asymmetry in (-1, 1): > 0 scatters forwards.
    pub g: f32,
    /// The density that scales both coefficients (pbrt-v4's `uniformgrid`);
    /// `None`: one everywhere.
    pub density: Option<Arc<Density>>,
    /// Light the medium emits (pbrt-v4's `Le`); `None`: none.
    pub emission: Option<Arc<Emission>>,
}

/// Light a medium emits, as pbrt-v4's media do: radiance Le per unit of
/// absorption, so that sigma_a Le is emitted per unit length (and a medium
/// that only absorbs, thick enough, looks Le bright).
#[derive(Clone, Debug, PartialEq)]
pub struct Emission {
    /// Le where the scale is one (linear RGB).
    pub le: Vec3,
    /// Grid media: the scale at each point (pbrt-v4's `Lescale`, samples on
    /// the density's grid, looked up as the density is; by default one
    /// sample of 1, which pbrt-v4's lookup fades towards the box's faces).
    scale: Option<Field>,
    /// Grid media: Le from the blackbody of each point's temperature instead.
    temperature: Option<Temperature>,
    /// `rgbgrid` media: Le per grid point instead (times `le`'s first channel).
    grid: Option<([usize; 3], Vec<Vec3>)>,
}

/// Temperatures on a medium's grid: (value - offset) x scale kelvin, whose
/// peak-normalised blackbody (pbrt-v4's `BlackbodySpectrum`) is Le where
/// it is above 100 K (none below).
#[derive(Clone, PartialEq)]
struct Temperature {
    field: Field,
    offset: f32,
    scale: f32,
    /// The blackbody's RGB at `TABLE_LOW + i step` kelvin.
    table: Vec<Vec3>,
    step: f32,
}

impl Temperature {
    /// Temperatures `field`, whose values lie in `range` (its lookups
    /// interpolate between values and zero), their glow times `factor`.
    fn new(
        field: Field,
        range: (f32, f32),
        offset: f32,
        scale: f32,
        factor: f32,
        rgb: &dyn Fn(f32) -> Vec3,
    ) -> Result<Self, String> {
        if !(offset.is_finite() && scale.is_finite()) {
            return Err("the temperature's offset and scale must be finite".into());
        }
        let kelvin = |v: f32| (v - offset) * scale;
        let hottest = kelvin(0.0).max(kelvin(range.0)).max(kelvin(range.1));
        let step = ((hottest - TABLE_LOW) / (TABLE_SIZE - 1) as f32).max(f32::MIN_POSITIVE);
        let table = (0..TABLE_SIZE)
            .map(|i| rgb(TABLE_LOW + i as f32 * step) * factor)
            .collect();
        Ok(Temperature {
            field,
            offset,
            scale,
            table,
            step,
        })
    }
}

impl std::fmt::Debug for Temperature {
    // The table follows from the rest.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Temperature {{ {:?}, offset: {}, scale: {} }}",
            self.field, self.offset, self.scale
        )
    }
}

/// A grid of temperatures as a scene file gives it: one value per grid
/// point (x fastest), kelvin = (value - `offset`) x `scale`, and the colour
/// `rgb` of the blackbody at a temperature.
pub struct TemperatureGrid<'a> {
    pub values: Vec<f32>,
    pub offset: f32,
    pub scale: f32,
    pub rgb: &'a dyn Fn(f32) -> Vec3,
}

/// The lowest temperature that glows (pbrt-v4's cut-off).
const TABLE_LOW: f32 = 100.0;
/// Entries of a temperature's colour table.
const TABLE_SIZE: usize = 4096;

impl Emission {
    /// A homogeneous medium's: `le` everywhere.
    pub fn uniform(le: Vec3) -> Self {
        Emission {
            le,
            scale: None,
            temperature: None,
            grid: None,
        }
    }

    /// An `rgbgrid` medium's: `values` per grid point (x fastest, looked up
    /// as its coefficients are) times `scale` (pbrt-v4's `Lescale`).
    pub fn rgb_grid(n: [usize; 3], values: Vec<Vec3>, scale: f32) -> Result<Self, String> {
        if values.len() != n.iter().product::<usize>() {
            return Err(format!(
                "{} \"Le\" values for a grid of {} x {} x {}",
                values.len(),
                n[0],
                n[1],
                n[2]
            ));
        }
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && v.min_element() >= 0.0)) {
            return Err(format!("an \"Le\" of {v}: it must be finite and not negative"));
        }
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!("an \"Lescale\" of {scale}"));
        }
        Ok(Emission {
            le: Vec3::splat(scale),
            scale: None,
            temperature: None,
            grid: Some((n, values)),
        })
    }

    /// A grid medium's: `le` times the scale at each point (`scale`: one
    /// sample per grid point, x fastest; `None`: pbrt-v4's single sample of
    /// 1), or with `temperature` (values per grid point, the offset and scale
    /// that turn them into kelvin, and the blackbody's RGB at a temperature)
    /// the blackbody of each point's temperature times that scale.
    pub fn grid(
        n: [usize; 3],
        le: Vec3,
        scale: Option<Vec<f32>>,
        temperature: Option<TemperatureGrid>,
    ) -> Result<Self, String> {
        let count = n.iter().product::<usize>();
        let samples = |name: &str, values: Vec<f32>| -> Result<Field, String> {
            if values.len() != count {
                return Err(format!(
                    "{} \"{name}\" values for a grid of {} values",
                    values.len(),
                    count
                ));
            }
            if let Some(v) = values.iter().find(|v| !v.is_finite()) {
                return Err(format!("a \"{name}\" value of {v}"));
            }
            Ok(Field::Samples { n, values })
        };
        let scale = Some(match scale {
            Some(v) => samples("Lescale", v)?,
            None => Field::Samples {
                n: [1, 1, 1],
                values: vec![1.0],
            },
        });
        let temperature = match temperature {
            None => None,
            Some(TemperatureGrid {
                values,
                offset,
                scale: tscale,
                rgb,
            }) => {
                let range = values
                    .iter()
                    .fold((0.0f32, 0.0f32), |(lo, hi), &v| (lo.min(v), hi.max(v)));
                let field = samples("temperature", values)?;
                Some(Temperature::new(field, range, offset, tscale, 1.0, rgb)?)
            }
        };
        Ok(Emission {
            le,
            scale,
            temperature,
            grid: None,
        })
    }

    /// A NanoVDB medium's (pbrt-v4's `NanoVDBMedium`): `lescale` times the
    /// blackbody of the temperature `grid` holds, seen from the density's
    /// box from `lo` to `hi` in the medium's space.
    pub fn nanovdb_temperature(
        grid: nanovdb::VdbGrid,
        (lo, hi): (Vec3, Vec3),
        lescale: f32,
        offset: f32,
        scale: f32,
        rgb: &dyn Fn(f32) -> Vec3,
    ) -> Result<Self, String> {
        if !(lescale.is_finite() && lescale >= 0.0) {
            return Err(format!("an \"Lescale\" of {lescale}"));
        }
        let range = grid
            .values
            .values()
            .fold((0.0f32, 0.0f32), |(lo, hi), v| (lo.min(v), hi.max(v)));
        let map = grid.index_from_world;
        let field = SparseField::new(grid.values, lo, hi, |p| nanovdb::apply(&map, p))?;
        Ok(Emission {
            le: Vec3::ONE,
            scale: None,
            temperature: Some(Temperature::new(
                Field::Sparse(Box::new(field)),
                range,
                offset,
                scale,
                lescale,
                rgb,
            )?),
            grid: None,
        })
    }

    /// Le at `q` in the grid's unit cube (anywhere, for a homogeneous medium).
    fn at(&self, q: Vec3) -> Vec3 {
        if let Some((n, v)) = &self.grid {
            let c = |k: usize| trilinear_by(*n, q, |i| v[i][k]);
            return Vec3::new(c(0), c(1), c(2)) * self.le.x;
        }
        let s = self.scale.as_ref().map_or(1.0, |f| f.lookup(q));
        if s <= 0.0 {
            return Vec3::ZERO;
        }
        match &self.temperature {
            None => self.le * s,
            Some(t) => {
                let k = (t.field.lookup(q) - t.offset) * t.scale;
                if k.is_nan() || k <= TABLE_LOW {
                    return Vec3::ZERO;
                }
                let x = ((k - TABLE_LOW) / t.step).min((TABLE_SIZE - 1) as f32);
                let i = (x as usize).min(TABLE_SIZE - 2);
                let f = x - i as f32;
                (t.table[i] * (1.0 - f) + t.table[i + 1] * f) * s
            }
        }
    }

    /// What it emits, in a few words (for `info`).
    pub fn summary(&self) -> String {
        let scaled = match &self.scale {
            Some(Field::Samples { n, .. }) if *n != [1, 1, 1] => " times a grid of Lescale",
            _ => "",
        };
        if let Some((n, _)) = &self.grid {
            return format!(
                "emits Le from a grid of {} x {} x {} RGB values times {}",
                n[0], n[1], n[2], self.le.x
            );
        }
        match &self.temperature {
            Some(t) => format!(
                "emits the blackbody of a temperature grid (kelvin = (value - {}) x {}){scaled}",
                t.offset, t.scale
            ),
            None => format!("emits Le {}{scaled}", self.le),
        }
    }

    /// Whether the medium emits anything at all.
    pub fn is_dark(&self) -> bool {
        self.temperature.is_none() && self.le.max_element() <= 0.0
            || self
                .grid
                .as_ref()
                .is_some_and(|(_, v)| v.iter().all(|c| c.max_element() <= 0.0))
    }
}

/// A path's weight: its throughput `beta` over the mean of its channels'
/// densities relative to the hero's (`ratio`); see [`Medium::sample_distance`].
#[inline(always)]
pub fn path_weight(beta: Vec3, ratio: Vec3) -> Vec3 {
    beta * (3.0 / ratio.element_sum())
}

/// A density over a box that scales a medium's coefficients point by point:
/// samples on a grid (pbrt-v4's `GridMedium` and its `SampledGrid`), or
/// pbrt-v4's procedural `CloudMedium`. Zero outside the box.
#[derive(Clone, PartialEq)]
pub struct Density {
    /// The box as the unit cube in world space, and its inverse.
    world_from_grid: Mat4,
    grid_from_world: Mat4,
    field: Field,
    /// The largest density.
    max: f32,
    /// The largest density (or an `rgbgrid`'s sigma_t) over each cell of a
    /// coarse grid over the box: the majorants for tracking through it.
    majorants: MajorantGrid,
    /// pbrt-v4's `rgbgrid`: coefficients of their own at each grid point,
    /// which take the place of the medium's scaled by `field`.
    rgb: Option<RgbCoefficients>,
}

/// An `rgbgrid`'s coefficients: sigma_a and sigma_s per grid point (x
/// fastest), looked up as densities are (trilinear, zero beyond the
/// samples); one where a grid is not given (everywhere in the box), as in
/// pbrt-v4. Already multiplied by the medium's scale.
#[derive(Clone, PartialEq)]
struct RgbCoefficients {
    n: [usize; 3],
    sigma_a: Option<Vec<Vec3>>,
    sigma_s: Option<Vec<Vec3>>,
    scale: f32,
    /// The largest sigma_t and sigma_s in each channel (the majorant, and
    /// whether it scatters at all).
    max_t: Vec3,
    max_s: Vec3,
}

/// What a grid holds at a point: a density scaling the medium's own
/// coefficients, or an RGB grid's (sigma_a, sigma_s). Each coefficient is
/// made only where tracking needs it (most tentative collisions need
/// sigma_t alone).
#[derive(Clone, Copy)]
enum Local {
    Density(f32),
    Rgb(Vec3, Vec3),
}

impl Local {
    /// The coefficient of a medium whose own are `own` = (sigma_a, sigma_s):
    /// `pick` 0 for sigma_a, 1 for sigma_s.
    #[inline(always)]
    fn sigma(self, own: Vec3, pick: usize) -> Vec3 {
        match self {
            Local::Density(d) => own * d,
            Local::Rgb(a, s) => [a, s][pick],
        }
    }
}

impl RgbCoefficients {
    /// (sigma_a, sigma_s) at `q` in the unit cube.
    fn at(&self, q: Vec3) -> (Vec3, Vec3) {
        let get = |g: &Option<Vec<Vec3>>| match g {
            None => Vec3::splat(self.scale),
            Some(v) => {
                let c = |k: usize| trilinear_by(self.n, q, |i| v[i][k]);
                Vec3::new(c(0), c(1), c(2)) * self.scale
            }
        };
        (get(&self.sigma_a), get(&self.sigma_s))
    }
}

#[derive(Clone, PartialEq)]
enum Field {
    /// Sample (i, j, k) sits at the centre of its cell of the box, a point
    /// between samples takes their trilinear interpolation, and samples
    /// beyond the grid count as zero, so the density falls to zero over the
    /// box's outer half cells. Values x fastest, then y, then z.
    Samples {
        n: [usize; 3],
        values: Vec<f32>,
    },
    Cloud(Cloud),
    /// A NanoVDB grid's voxels, placed in the box by its map.
    Sparse(Box<SparseField>),
}

/// A sparse grid's voxels over a box: the voxel space's point for a point
/// `q` of the box's unit cube is `a q + b`.
#[derive(Clone, PartialEq)]
pub struct SparseField {
    grid: SparseGrid,
    a: glam::Mat3,
    b: Vec3,
}

impl SparseField {
    /// `grid` seen from the box from `lo` to `hi` of the medium's space,
    /// which `index_from_medium` takes to the grid's voxel space.
    fn new(grid: SparseGrid, lo: Vec3, hi: Vec3, index_from_medium: impl Fn(Vec3) -> Vec3) -> Result<Self, String> {
        let b = index_from_medium(lo);
        let axis = |k: usize| {
            let mut p = lo;
            p[k] = hi[k];
            index_from_medium(p) - b
        };
        let a = glam::Mat3::from_cols(axis(0), axis(1), axis(2));
        if !(a.is_finite() && b.is_finite() && a.determinant().abs() > 0.0) {
            return Err("the grid's map from its voxels to space is singular".into());
        }
        Ok(SparseField { grid, a, b })
    }

    fn lookup(&self, q: Vec3) -> f32 {
        self.grid.trilinear(self.a * q + self.b)
    }

    fn majorants(&self) -> MajorantGrid {
        let inv = self.a.inverse();
        let b = self.b;
        // pbrt-v4's 64 cells an axis, but none narrower than a leaf (8
        // voxels): a cell's bound takes in the voxels a voxel beyond it, so
        // narrower cells bound scarcely tighter and cost the tracking more
        // steps (BENCHMARKS.md, "NanoVDB media against pbrt-v4").
        let res = [0, 1, 2].map(|k| ((self.a.col(k).length() / 8.0).ceil() as usize).clamp(1, MAX_MAJORANT_CELLS));
        self.grid.majorants(res, |p| inv * (p - b))
    }
}

/// Most cells along each axis of a NanoVDB medium's majorant grid (pbrt-v4's).
const MAX_MAJORANT_CELLS: usize = 64;

impl std::fmt::Debug for Field {
    // A digest of the values: scene fingerprints print media, and a grid
    // may hold millions of values.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Field::Samples { n, values } => {
                let digest = values
                    .iter()
                    .fold(0x9E37_79B9_7F4A_7C15u64, |h, v| mix64(h ^ v.to_bits() as u64));
                write!(f, "Samples {{ n: {n:?}, values: {digest:016x} }}")
            }
            Field::Cloud(c) => write!(f, "{c:?}"),
            Field::Sparse(s) => write!(f, "{:?} a: {:?} b: {}", s.grid, s.a, s.b),
        }
    }
}

impl Field {
    fn lookup(&self, q: Vec3) -> f32 {
        match self {
            Field::Samples { n, values } => trilinear(*n, values, q),
            Field::Cloud(c) => cloud_density(c.lo + q * c.size, c.density, c.wispiness, c.frequency),
            Field::Sparse(s) => s.lookup(q),
        }
    }
}

/// pbrt-v4's cloud: octaves of Perlin noise at `frequency` a unit of the
/// medium's space, the lookup point perturbed by `wispiness`, thinning with
/// height; in [0, 1]. `lo` and `size`: the box in the medium's space, where
/// the noise lives.
#[derive(Clone, Debug, PartialEq)]
struct Cloud {
    density: f32,
    wispiness: f32,
    frequency: f32,
    lo: Vec3,
    size: Vec3,
}

impl std::fmt::Debug for Density {
    // Sizes, place and a digest of the values: scene fingerprints print
    // media, and a grid may hold millions of values.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(c) = &self.rgb {
            let digest = |g: &Option<Vec<Vec3>>| {
                g.as_ref().map(|v| {
                    v.iter().fold(0x9E37_79B9_7F4A_7C15u64, |h, c| {
                        c.to_array().iter().fold(h, |h, x| mix64(h ^ x.to_bits() as u64))
                    })
                })
            };
            return write!(
                f,
                "RgbGrid {{ n: {:?}, world_from_grid: {:?}, scale: {}, sigma_a: {:?}, sigma_s: {:?} }}",
                c.n,
                self.world_from_grid,
                c.scale,
                digest(&c.sigma_a),
                digest(&c.sigma_s)
            );
        }
        match &self.field {
            Field::Samples { n, values } => {
                let digest = values
                    .iter()
                    .fold(0x9E37_79B9_7F4A_7C15u64, |h, v| mix64(h ^ v.to_bits() as u64));
                write!(
                    f,
                    "Density {{ n: {n:?}, world_from_grid: {:?}, max: {}, values: {digest:016x} }}",
                    self.world_from_grid, self.max
                )
            }
            Field::Cloud(c) => write!(f, "Density {{ {c:?}, world_from_grid: {:?} }}", self.world_from_grid),
            Field::Sparse(s) => write!(
                f,
                "Density {{ {:?}, a: {:?}, b: {}, world_from_grid: {:?} }}",
                s.grid, s.a, s.b, self.world_from_grid
            ),
        }
    }
}

/// The box from `p0` to `p1` in the space `world_from_medium` places, as
/// the unit cube's image, with its corner and size; an error if it is empty.
fn unit_box(p0: Vec3, p1: Vec3, world_from_medium: Mat4) -> Result<(Mat4, Vec3, Vec3), String> {
    let (lo, hi) = (p0.min(p1), p0.max(p1));
    let size = hi - lo;
    if !(lo.is_finite() && hi.is_finite() && size.min_element() > 0.0) {
        return Err(format!("the medium's box from {p0} to {p1} is empty"));
    }
    Ok((
        world_from_medium * Mat4::from_translation(lo) * Mat4::from_scale(size),
        lo,
        size,
    ))
}

impl Density {
    /// pbrt-v4's `rgbgrid` over the box from `p0` to `p1`: `sigma_a` and
    /// `sigma_s` per grid point (either may be absent: one everywhere), both
    /// times `scale`; an error saying why when a count is not the product, a
    /// value is negative or not finite, or the box is degenerate.
    pub fn rgb_grid(
        n: [usize; 3],
        sigma_a: Option<Vec<Vec3>>,
        sigma_s: Option<Vec<Vec3>>,
        scale: f32,
        p0: Vec3,
        p1: Vec3,
        world_from_medium: Mat4,
    ) -> Result<Self, String> {
        let count = n.iter().try_fold(1usize, |a, &k| a.checked_mul(k));
        if n.contains(&0) {
            return Err(format!("a grid of {} x {} x {}", n[0], n[1], n[2]));
        }
        let mut max = [Vec3::splat(scale); 2];
        for (k, (name, values)) in [("sigma_a", &sigma_a), ("sigma_s", &sigma_s)].into_iter().enumerate() {
            let Some(values) = values else { continue };
            if count != Some(values.len()) {
                return Err(format!(
                    "{} \"{name}\" values for a grid of {} x {} x {}",
                    values.len(),
                    n[0],
                    n[1],
                    n[2]
                ));
            }
            if let Some(v) = values.iter().find(|v| !(v.is_finite() && v.min_element() >= 0.0)) {
                return Err(format!(
                    "a \"{name}\" of {v}: coefficients must be finite and not negative"
                ));
            }
            max[k] = values.iter().fold(Vec3::ZERO, |a, &v| a.max(v)) * scale;
        }
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!("a scale of {scale}"));
        }
        // Trilinear lookups stay below the largest sample: so does their sum.
        let max_t = match (&sigma_a, &sigma_s) {
            (Some(a), Some(s)) => a.iter().zip(s).fold(Vec3::ZERO, |m, (&a, &s)| m.max(a + s)) * scale,
            _ => max[0] + max[1],
        };
        let (world_from_grid, _, _) = unit_box(p0, p1, world_from_medium)?;
        let mut d = Self::placed(
            world_from_grid,
            Field::Samples {
                n: [1, 1, 1],
                values: vec![1.0],
            },
            1.0,
        )?;
        let value = |g: &Option<Vec<Vec3>>, i: usize| g.as_ref().map_or(Vec3::ONE, |v| v[i]);
        d.majorants = MajorantGrid::over_samples(n, |i| (value(&sigma_a, i) + value(&sigma_s, i)) * scale);
        d.rgb = Some(RgbCoefficients {
            n,
            sigma_a,
            sigma_s,
            scale,
            max_t,
            max_s: max[1],
        });
        Ok(d)
    }

    /// What the grid holds at `q` in the unit cube.
    #[inline(always)]
    fn local(&self, q: Vec3) -> Local {
        match &self.rgb {
            None => Local::Density(self.lookup(q)),
            Some(c) => {
                let (a, s) = c.at(q);
                Local::Rgb(a, s)
            }
        }
    }

    /// The majorant sigma_t in each channel, for a medium whose own is
    /// `st`, of a cell whose value is `cell`.
    #[inline(always)]
    fn cell_majorant(&self, cell: Vec3, st: Vec3) -> Vec3 {
        if self.rgb.is_some() {
            cell
        } else {
            st * cell.x
        }
    }

    /// An `rgbgrid`'s largest sigma_t in each channel (`None` for others).
    pub fn rgb_majorant(&self) -> Option<Vec3> {
        self.rgb.as_ref().map(|c| c.max_t)
    }

    /// A grid of `n[0] x n[1] x n[2]` values (x fastest) over the box from
    /// `p0` to `p1` in the space `world_from_medium` places; an error saying
    /// why when the count is not the product, a value is negative or not
    /// finite, or the box or the transformation is degenerate.
    pub fn grid(n: [usize; 3], values: Vec<f32>, p0: Vec3, p1: Vec3, world_from_medium: Mat4) -> Result<Self, String> {
        let count = n.iter().try_fold(1usize, |a, &k| a.checked_mul(k));
        if n.contains(&0) || count != Some(values.len()) {
            return Err(format!(
                "{} density values for a grid of {} x {} x {}",
                values.len(),
                n[0],
                n[1],
                n[2]
            ));
        }
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(format!("a density of {v}: densities must be finite and not negative"));
        }
        let (world_from_grid, _, _) = unit_box(p0, p1, world_from_medium)?;
        let max = values.iter().fold(0.0f32, |a, &v| a.max(v));
        Self::placed(world_from_grid, Field::Samples { n, values }, max)
    }

    /// pbrt-v4's procedural cloud (`CloudMedium`) over the box from `p0` to
    /// `p1`: `density` scales it before it is clamped to [0, 1].
    pub fn cloud(
        density: f32,
        wispiness: f32,
        frequency: f32,
        p0: Vec3,
        p1: Vec3,
        world_from_medium: Mat4,
    ) -> Result<Self, String> {
        if ![density, wispiness, frequency].iter().all(|v| v.is_finite()) {
            return Err("the cloud's density, wispiness and frequency must be finite".into());
        }
        let (world_from_grid, lo, size) = unit_box(p0, p1, world_from_medium)?;
        let field = Field::Cloud(Cloud {
            density,
            wispiness,
            frequency,
            lo,
            size,
        });
        Self::placed(world_from_grid, field, 1.0)
    }

    /// pbrt-v4's `nanovdb` medium: the density NanoVDB `grid` holds, over
    /// its world bounds (joined with `also`, the temperature grid's) in the
    /// space `world_from_medium` places; the box, in the medium's space,
    /// with it.
    pub fn nanovdb(
        grid: nanovdb::VdbGrid,
        also: Option<(Vec3, Vec3)>,
        world_from_medium: Mat4,
    ) -> Result<(Self, (Vec3, Vec3)), String> {
        if let Some(v) = grid.values.values().find(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(format!("a density of {v}: densities must be finite and not negative"));
        }
        let (mut lo, mut hi) = grid.world_bounds;
        if let Some((a, b)) = also {
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let (world_from_grid, _, _) = unit_box(lo, hi, world_from_medium)?;
        let max = grid.values.max();
        let map = grid.index_from_world;
        let field = SparseField::new(grid.values, lo, hi, |p| nanovdb::apply(&map, p))?;
        Ok((
            Self::placed(world_from_grid, Field::Sparse(Box::new(field)), max)?,
            (lo, hi),
        ))
    }

    fn placed(world_from_grid: Mat4, field: Field, max: f32) -> Result<Self, String> {
        let grid_from_world = world_from_grid.inverse();
        if !(grid_from_world.is_finite() && world_from_grid.determinant().abs() > 0.0) {
            return Err("the medium's transformation is singular".into());
        }
        let majorants = match &field {
            Field::Samples { n, values } => MajorantGrid::over_samples(*n, |i| Vec3::splat(values[i])),
            Field::Cloud(_) => MajorantGrid::uniform(Vec3::splat(max)),
            Field::Sparse(s) => s.majorants(),
        };
        Ok(Density {
            world_from_grid,
            grid_from_world,
            field,
            max,
            majorants,
            rgb: None,
        })
    }

    /// The same grid moved by the reflection `r` (its own inverse), as the
    /// scene around it is reflected.
    pub fn reflected(&self, r: Mat4) -> Self {
        Density {
            world_from_grid: r * self.world_from_grid,
            grid_from_world: self.grid_from_world * r,
            ..self.clone()
        }
    }

    /// Samples along x, y and z of a grid (`None` for a cloud).
    pub fn resolution(&self) -> Option<[usize; 3]> {
        if let Some(c) = &self.rgb {
            return Some(c.n);
        }
        match &self.field {
            Field::Samples { n, .. } => Some(*n),
            Field::Cloud { .. } | Field::Sparse(_) => None,
        }
    }

    /// What the density is, in a few words (for `info`).
    pub fn describe(&self) -> String {
        match &self.field {
            Field::Samples { n, .. } => format!(
                "a density grid of {} x {} x {}, densities up to {}",
                n[0], n[1], n[2], self.max
            ),
            Field::Cloud(_) => "a procedural cloud (pbrt-v4's), densities up to 1".to_string(),
            Field::Sparse(s) => {
                let [x, y, z] = s.grid.blocks();
                format!(
                    "a NanoVDB grid, {} leaves of 8^3 voxels in a box of {x} x {y} x {z} such blocks, densities up to {}",
                    s.grid.leaf_count(),
                    self.max
                )
            }
        }
    }

    /// The largest density.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// The density at `q` in the box's unit cube.
    fn lookup(&self, q: Vec3) -> f32 {
        self.field.lookup(q)
    }

    /// The density at world point `p`: zero outside the grid's box (as in
    /// pbrt-v4, whose rays meet the grid only within it).
    pub fn density(&self, p: Vec3) -> f32 {
        let q = self.grid_from_world.transform_point3(p);
        if q.cmplt(Vec3::ZERO).any() || q.cmpgt(Vec3::ONE).any() {
            return 0.0;
        }
        self.lookup(q)
    }

    /// The ray `o + t d`, t in [0, t_max], in grid space, and the part of
    /// it within the grid's box, if any.
    fn clip(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(Vec3, Vec3, f32, f32)> {
        let (go, gd) = (
            self.grid_from_world.transform_point3(o),
            self.grid_from_world.transform_vector3(d),
        );
        let (mut t0, mut t1) = (0.0f32, t_max);
        for a in 0..3 {
            let inv = 1.0 / gd[a];
            let (mut near, mut far) = ((0.0 - go[a]) * inv, (1.0 - go[a]) * inv);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            // NaN (a ray in a face's plane) leaves the bound as it was.
            t0 = if near > t0 { near } else { t0 };
            t1 = if far < t1 { far } else { t1 };
            if t0 > t1 {
                return None;
            }
        }
        Some((go, gd, t0, t1))
    }
}

/// The sides of a surface that bounds media: indices into the scene's
/// media, `None` for vacuum. `outside` is on the side of the surface's
/// normal as the scene stores it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MediumInterface {
    pub inside: Option<u32>,
    pub outside: Option<u32>,
}

impl MediumInterface {
    /// Whether crossing the surface changes the medium (pbrt-v4's
    /// `IsMediumTransition`); if not, rays keep the medium they were in.
    pub fn is_transition(&self) -> bool {
        self.inside != self.outside
    }

    /// The same sides seen from a normal turned the other way.
    pub fn flipped(self) -> MediumInterface {
        MediumInterface {
            inside: self.outside,
            outside: self.inside,
        }
    }
}

/// Where a ray in a medium stopped: scattered at distance `t`, or passed
/// the whole segment. The path's throughput takes `beta` (the event's value
/// over its density when distances are sampled for the path's hero channel)
/// and its channel ratios take `ratio` (each channel's density over the
/// hero's); see [`Medium::sample_distance`].
#[derive(Clone, Copy, Debug)]
pub enum MediumEvent {
    Scatter { t: f32, beta: Vec3, ratio: Vec3 },
    Pass { beta: Vec3, ratio: Vec3 },
}

impl Medium {
    pub fn sigma_t(&self) -> Vec3 {
        self.sigma_a + self.sigma_s
    }

    /// What `Scene::build` refuses: coefficients must be finite and not
    /// negative, `g` within (-1, 1).
    pub fn check(&self) -> Result<(), String> {
        let ok = |v: Vec3| v.is_finite() && v.min_element() >= 0.0;
        if !ok(self.sigma_a) || !ok(self.sigma_s) {
            return Err(format!(
                "sigma_a {} and sigma_s {} must be finite and not negative",
                self.sigma_a, self.sigma_s
            ));
        }
        if !(self.g > -1.0 && self.g < 1.0) {
            return Err(format!("g {} must lie strictly between -1 and 1", self.g));
        }
        if let Some(e) = self.emission.as_deref().filter(|e| !ok(e.le)) {
            return Err(format!("le {} must be finite and not negative", e.le));
        }
        Ok(())
    }

    /// The medium's (sigma_a, sigma_s) at world point `p`: zero outside a
    /// grid's box.
    pub fn coefficients_at(&self, p: Vec3) -> (Vec3, Vec3) {
        let Some(g) = &self.density else {
            return (self.sigma_a, self.sigma_s);
        };
        let q = g.grid_from_world.transform_point3(p);
        if q.cmplt(Vec3::ZERO).any() || q.cmpgt(Vec3::ONE).any() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let local = g.local(q);
        (local.sigma(self.sigma_a, 0), local.sigma(self.sigma_s, 1))
    }

    /// The Le the medium emits at world point `p` (sigma_a Le per unit
    /// length): zero outside a grid's box.
    pub fn le(&self, p: Vec3) -> Vec3 {
        let Some(e) = &self.emission else {
            return Vec3::ZERO;
        };
        match &self.density {
            None => e.at(Vec3::ZERO),
            Some(g) => {
                let q = g.grid_from_world.transform_point3(p);
                if q.cmplt(Vec3::ZERO).any() || q.cmpgt(Vec3::ONE).any() {
                    return Vec3::ZERO;
                }
                e.at(q)
            }
        }
    }

    /// Whether light is ever scattered (else it is only absorbed, and a
    /// path's throughput just takes the transmittance).
    pub fn scatters(&self) -> bool {
        match self.density.as_ref().and_then(|g| g.rgb.as_ref()) {
            Some(c) => c.max_s.max_element() > 0.0,
            None => self.sigma_s.max_element() > 0.0 && self.density.as_ref().is_none_or(|g| g.max > 0.0),
        }
    }

    /// Whether tracking through the medium needs random numbers.
    pub fn is_random(&self) -> bool {
        self.scatters() || self.density.is_some()
    }

    /// Transmittance over distance `d` (infinite: zero where sigma_t > 0).
    pub fn transmittance(&self, d: f32) -> Vec3 {
        let st = self.sigma_t();
        Vec3::new(tr(st.x, d), tr(st.y, d), tr(st.z, d))
    }

    /// Samples where a ray travelling `t_max` through the medium next
    /// interacts, by the exponential distance of the path's `hero` channel
    /// (0, 1 or 2) with `u`.
    ///
    /// Coloured media sample a different distance in each channel. As in
    /// pbrt-v4 (hero wavelength sampling, Wilkie et al. 2014), a path keeps
    /// one channel, chosen uniformly, for all its distances, and carries with
    /// its throughput beta (value over the hero's density) the ratio r of
    /// each channel's density to the hero's; its estimate is beta / mean(r),
    /// value over the mean of the three channels' densities: one-sample MIS
    /// over the channels, with the balance heuristic, for the whole path. Each
    /// channel is unbiased, and the weight stays below 3 times what a path of
    /// its own channel would carry (choosing the channel afresh at every
    /// event instead lets the weights multiply without bound).
    ///
    /// Media that only absorb never scatter: their transmittance is taken as
    /// it is, the ratios unchanged.
    pub fn sample_distance(&self, o: Vec3, d: Vec3, t_max: f32, hero: usize, u: f32) -> MediumEvent {
        self.sample_distance_emitting(o, d, t_max, hero, u, None).0
    }

    /// [`Self::sample_distance`], and the light the medium emits along the
    /// way towards a path whose throughput and channel ratios before the
    /// segment are `path` (`None`: none is wanted), weighted as the path's
    /// radiance is (add it to that). Emission is gathered where the tracking
    /// stops to look (pbrt-v4's `VolPathIntegrator`): at the scattering point
    /// in a homogeneous medium (sigma_a Le over sigma_t, the collision's
    /// density having sampled it), at every tentative collision in a grid
    /// (sigma_a Le over the majorant), exactly in a homogeneous medium that
    /// only absorbs (Le (1 - transmittance)).
    pub fn sample_distance_emitting(
        &self,
        o: Vec3,
        d: Vec3,
        t_max: f32,
        hero: usize,
        u: f32,
        path: Option<(Vec3, Vec3)>,
    ) -> (MediumEvent, Vec3) {
        let emit = self.emission.as_deref().filter(|e| !e.is_dark()).zip(path);
        match &self.density {
            None => self.sample_homogeneous(t_max, hero, u, emit),
            Some(g) => self.sample_grid(g, o, d, t_max, hero, u, emit),
        }
    }

    /// The fraction of light that passes from `o` along the unit direction
    /// `d` for `dist` (infinite: out of the scene): exact in a homogeneous
    /// medium; in a grid an unbiased estimate by ratio tracking, seeded by
    /// the ray (as pbrt-v4 seeds its shadow rays), so the same segment gets
    /// the same estimate.
    pub fn transmittance_along(&self, o: Vec3, d: Vec3, dist: f32) -> Vec3 {
        match &self.density {
            None => self.transmittance(dist),
            Some(g) => match g.clip(o, d, dist) {
                None => Vec3::ONE,
                Some((go, gd, t0, t1)) => {
                    let mut rng = Rng::keyed(0x7472_616E_736D, ray_key(o, d), dist.to_bits() as u64);
                    self.ratio_track(g, go, gd, t0, t1, &mut rng, None)
                }
            },
        }
    }

    /// Transmittance over [t0, t1] of the grid-space ray `go + t gd` by
    /// ratio tracking (Novak et al. 2014), against one majorant for all
    /// channels in each cell of the grid's majorant grid, with pbrt-v4's
    /// roulette once it is small. With `emitted`, adds to it the light the
    /// medium emits on the way (at each tentative collision, the
    /// transmittance so far times sigma_a Le over the majorant: an estimate
    /// of its integral along the ray).
    #[allow(clippy::too_many_arguments)]
    fn ratio_track(
        &self,
        g: &Density,
        go: Vec3,
        gd: Vec3,
        t0: f32,
        t1: f32,
        rng: &mut Rng,
        mut emitted: Option<(&Emission, &mut Vec3)>,
    ) -> Vec3 {
        let st = self.sigma_t();
        let mut tr = Vec3::ONE;
        let mut steps = 0;
        // The optical depth, against the majorants, left to the next
        // tentative collision: it carries over from cell to cell.
        let mut tau = -(1.0 - rng.next_f32()).ln();
        for (from, to, cell) in g.majorants.cells(go, gd, t0, t1) {
            let majorant = g.cell_majorant(cell, st).max_element();
            let mut t = from;
            loop {
                if !(majorant > 0.0 && t + tau / majorant < to) {
                    tau = (tau - majorant * (to - t)).max(0.0);
                    break;
                }
                t += tau / majorant;
                tau = -(1.0 - rng.next_f32()).ln();
                let q = go + gd * t;
                let local = g.local(q);
                let fraction = match local {
                    Local::Density(d) => st * (d / majorant),
                    Local::Rgb(a, s) => (a + s) / majorant,
                };
                if let Some((e, sum)) = emitted.as_mut() {
                    let absorbed = match local {
                        Local::Density(d) => self.sigma_a * (d / majorant),
                        Local::Rgb(a, _) => a / majorant,
                    };
                    **sum += tr * absorbed * e.at(q);
                }
                tr *= (Vec3::ONE - fraction).max(Vec3::ZERO);
                let m = tr.max_element();
                if m <= 0.0 {
                    return Vec3::ZERO;
                }
                if m < 0.05 {
                    if rng.next_f32() < 0.75 {
                        return Vec3::ZERO;
                    }
                    tr /= 0.25;
                }
                steps += 1;
                if steps >= MAX_TRACKING_STEPS {
                    return Vec3::ZERO;
                }
            }
        }
        tr
    }

    /// `sample_distance` through a density grid: delta tracking (Woodcock
    /// tracking, as null scattering in pbrt-v4) for the hero channel,
    /// against the majorant sigma_t of each cell of the grid's majorant
    /// grid that the ray crosses (the optical depth to the next tentative
    /// collision carries over from one cell to the next). A tentative
    /// collision at density rho is real with probability
    /// sigma_t rho / majorant in the hero channel, and scatters there with
    /// the albedo as weight as in a homogeneous medium; else it is null and
    /// tracking goes on. Each event multiplies beta by the channels' values
    /// over the hero's density (null: sigma_n exp(-majorant dt); real:
    /// sigma_s rho exp(-majorant dt); passing: exp(-majorant dt)), and the
    /// ratios by the channels' densities over the hero's, so that the
    /// channels' one-sample MIS stays as in the homogeneous case, which a
    /// grid of constant density reproduces exactly. The first distance
    /// uses `u`, the rest a stream seeded by it and the ray.
    #[allow(clippy::too_many_arguments)]
    fn sample_grid(
        &self,
        g: &Density,
        o: Vec3,
        d: Vec3,
        t_max: f32,
        hero: usize,
        u: f32,
        emit: Option<(&Emission, (Vec3, Vec3))>,
    ) -> (MediumEvent, Vec3) {
        let Some((go, gd, t0, t1)) = g.clip(o, d, t_max) else {
            let pass = MediumEvent::Pass {
                beta: Vec3::ONE,
                ratio: Vec3::ONE,
            };
            return (pass, Vec3::ZERO);
        };
        let mut rng = Rng::keyed(u.to_bits() as u64, ray_key(o, d), 0x0064_656C_7461);
        if !self.scatters() {
            let mut sum = Vec3::ZERO;
            let beta = self.ratio_track(g, go, gd, t0, t1, &mut rng, emit.map(|(e, _)| (e, &mut sum)));
            let emitted = emit.map_or(Vec3::ZERO, |(_, (b, r))| path_weight(b, r) * sum);
            let pass = MediumEvent::Pass { beta, ratio: Vec3::ONE };
            return (pass, emitted);
        }
        let st = self.sigma_t();
        let h = hero.min(2);
        let (mut beta, mut ratio) = (Vec3::ONE, Vec3::ONE);
        let mut emitted = Vec3::ZERO;
        // The hero's optical depth, against the majorants, left to the next
        // tentative collision (it carries over from cell to cell), and each
        // channel's since the last event.
        let mut tau = -(1.0 - u).ln();
        let mut depth = Vec3::ZERO;
        let mut steps = 0;
        for (from, to, cell) in g.majorants.cells(go, gd, t0, t1) {
            let majorant = g.cell_majorant(cell, st);
            let mh = majorant[h];
            let mut t = from;
            loop {
                if !(mh > 0.0 && t + tau / mh < to) {
                    depth += majorant * (to - t);
                    tau = (tau - mh * (to - t)).max(0.0);
                    break;
                }
                let step = tau / mh;
                t += step;
                tau = -(1.0 - rng.next_f32()).ln();
                let e = exp(-(depth + majorant * step));
                depth = Vec3::ZERO;
                let q = go + gd * t;
                let local = g.local(q);
                let sigma_t = match local {
                    Local::Density(d) => st * d,
                    Local::Rgb(a, s) => a + s,
                };
                if let Some((em, (b, r))) = emit {
                    let sigma_a = local.sigma(self.sigma_a, 0);
                    // A tentative collision's density in each channel is its
                    // majorant's: the ratios take that, as pbrt-v4's r_e.
                    let p = mh * e[h];
                    let le = em.at(q);
                    emitted += path_weight(b * beta * e * sigma_a * le / p, r * ratio * majorant * e / p);
                }
                let sigma_n = (majorant - sigma_t).max(Vec3::ZERO);
                if sigma_n[h] <= 0.0 || rng.next_f32() * mh < sigma_t[h] {
                    let p = sigma_t[h] * e[h];
                    beta *= local.sigma(self.sigma_s, 1) * e / p;
                    ratio *= sigma_t * e / p;
                    let (beta, ratio) = normalised(beta, ratio);
                    return (MediumEvent::Scatter { t, beta, ratio }, emitted);
                }
                let p = sigma_n[h] * e[h];
                beta *= sigma_n * e / p;
                ratio *= sigma_n * e / p;
                if ratio.max_element() > 1e8 {
                    (beta, ratio) = normalised(beta, ratio);
                }
                steps += 1;
                if steps >= MAX_TRACKING_STEPS {
                    return (
                        MediumEvent::Pass {
                            beta: Vec3::ZERO,
                            ratio: Vec3::ONE,
                        },
                        emitted,
                    );
                }
            }
        }
        let e = exp(-depth);
        let (beta, ratio) = normalised(beta * e / e[h], ratio * e / e[h]);
        (MediumEvent::Pass { beta, ratio }, emitted)
    }

    fn sample_homogeneous(
        &self,
        t_max: f32,
        hero: usize,
        u: f32,
        emit: Option<(&Emission, (Vec3, Vec3))>,
    ) -> (MediumEvent, Vec3) {
        if !self.scatters() {
            let tr = self.transmittance(t_max);
            // sigma_t = sigma_a: the integral of sigma_a Le exp(-sigma_a t).
            let emitted = emit.map_or(Vec3::ZERO, |(e, (b, r))| {
                path_weight(b, r) * e.at(Vec3::ZERO) * (Vec3::ONE - tr)
            });
            let pass = MediumEvent::Pass {
                beta: tr,
                ratio: Vec3::ONE,
            };
            return (pass, emitted);
        }
        let st = self.sigma_t();
        let sc = st[hero.min(2)];
        let t = if sc > 0.0 { -(1.0 - u).ln() / sc } else { f32::INFINITY };
        if t < t_max {
            let tr = self.transmittance(t);
            let p = st * tr;
            let ph = p[hero.min(2)];
            let emitted = emit.map_or(Vec3::ZERO, |(e, (b, r))| {
                path_weight(b * tr * self.sigma_a * e.at(Vec3::ZERO) / ph, r * p / ph)
            });
            let scatter = MediumEvent::Scatter {
                t,
                beta: self.sigma_s * tr / ph,
                ratio: p / ph,
            };
            return (scatter, emitted);
        }
        let tr = self.transmittance(t_max);
        let ph = tr[hero.min(2)];
        let pass = MediumEvent::Pass {
            beta: tr / ph,
            ratio: tr / ph,
        };
        (pass, Vec3::ZERO)
    }

    /// The phase function's value for light travelling along `d` scattered
    /// into `wi`.
    pub fn phase(&self, d: Vec3, wi: Vec3) -> f32 {
        henyey_greenstein(d.dot(wi), self.g)
    }

    /// A direction scattered from travelling along `d`, drawn from the phase
    /// function, and its density (the phase function's value: it is
    /// normalised over the sphere, and sampled exactly).
    pub fn sample_phase(&self, d: Vec3, u: Vec2) -> (Vec3, f32) {
        sample_henyey_greenstein(d, self.g, u)
    }
}

/// A direction scattered from travelling along `d` by the Henyey-Greenstein
/// phase function of asymmetry `g`, and its density (the phase function's
/// value: it is sampled exactly).
pub fn sample_henyey_greenstein(d: Vec3, g: f32, u: Vec2) -> (Vec3, f32) {
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u.x
    } else {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
    let wi = to_world(local, d).normalize();
    (wi, henyey_greenstein(cos, g))
}

/// `beta` and `ratio` both divided by the largest ratio, which leaves the
/// path's weight beta / mean(ratio) as it was. Through a grid the
/// channels' densities part by exp(-(majorant difference) x distance):
/// kept as they come they would overflow where a dense channel is the hero
/// (and the weight become inf / inf).
pub fn normalised(beta: Vec3, ratio: Vec3) -> (Vec3, Vec3) {
    let s = ratio.max_element();
    if s > 0.0 && s.is_finite() {
        (beta / s, ratio / s)
    } else {
        (beta, ratio)
    }
}

/// `trilinear` of the values `value(i)` of sample i (x fastest).
fn trilinear_by(n: [usize; 3], q: Vec3, value: impl Fn(usize) -> f32) -> f32 {
    let s = q * Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32) - 0.5;
    let f = s.floor();
    let d = s - f;
    let (x, y, z) = (f.x as i64, f.y as i64, f.z as i64);
    let [nx, ny, nz] = n.map(|v| v as i64);
    let at = |i: i64, j: i64, k: i64| -> f32 {
        if i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz {
            return 0.0;
        }
        value(((k * ny + j) * nx + i) as usize)
    };
    let lerp = |t: f32, a: f32, b: f32| (1.0 - t) * a + t * b;
    let d00 = lerp(d.x, at(x, y, z), at(x + 1, y, z));
    let d10 = lerp(d.x, at(x, y + 1, z), at(x + 1, y + 1, z));
    let d01 = lerp(d.x, at(x, y, z + 1), at(x + 1, y, z + 1));
    let d11 = lerp(d.x, at(x, y + 1, z + 1), at(x + 1, y + 1, z + 1));
    lerp(d.z, lerp(d.y, d00, d10), lerp(d.y, d01, d11))
}

/// The samples' trilinear interpolation at `q` in the unit cube, zero
/// beyond them (pbrt-v4's `SampledGrid::Lookup`).
fn trilinear(n: [usize; 3], values: &[f32], q: Vec3) -> f32 {
    trilinear_by(n, q, |i| values[i])
}

/// pbrt-v4's cloud density at `p` in the medium's space: five octaves of
/// noise (weights halving, frequencies 1.99 times each) at `frequency` p,
/// first displaced twice along the noise's gradient by `wispiness`; then
/// scaled by (1 - y) 4.5 `density`, clamped to [0, 1], with 2 (0.5 - y)
/// added below y = 0.5, clamped again.
fn cloud_density(p: Vec3, density: f32, wispiness: f32, frequency: f32) -> f32 {
    let mut pp = p * frequency;
    if wispiness > 0.0 {
        let (mut omega, mut lambda) = (0.05 * wispiness, 10.0f32);
        for _ in 0..2 {
            pp += omega * noise_gradient(pp * lambda);
            omega *= 0.5;
            lambda *= 1.99;
        }
    }
    let (mut d, mut omega, mut lambda) = (0.0f32, 0.5f32, 1.0f32);
    for _ in 0..5 {
        d += omega * noise(pp * lambda);
        omega *= 0.5;
        lambda *= 1.99;
    }
    let d = ((1.0 - p.y) * 4.5 * density * d).clamp(0.0, 1.0);
    (d + 2.0 * (0.5 - p.y).max(0.0)).clamp(0.0, 1.0)
}

/// Most steps of delta or ratio tracking along one segment.
const MAX_TRACKING_STEPS: u32 = 1 << 20;

fn exp(v: Vec3) -> Vec3 {
    Vec3::new(v.x.exp(), v.y.exp(), v.z.exp())
}

/// A key for a ray's random stream, from its bits.
fn ray_key(o: Vec3, d: Vec3) -> u64 {
    let bits = |v: Vec3| ((v.x.to_bits() as u64) << 32 | v.y.to_bits() as u64) ^ mix64(v.z.to_bits() as u64);
    mix64(bits(o) ^ mix64(bits(d)))
}

fn tr(sigma: f32, d: f32) -> f32 {
    if sigma == 0.0 {
        1.0
    } else {
        (-sigma * d).exp()
    }
}

/// The Henyey-Greenstein phase function of the cosine between the direction
/// of travel and the scattered direction, per steradian.
pub fn henyey_greenstein(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * PI * denom * denom.max(0.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn henyey_greenstein_integrates_to_one_with_mean_cosine_g() {
        for g in [-0.7f32, 0.0, 0.3, 0.9] {
            // Midpoint rule over cos in [-1, 1], times 2 pi.
            let n = 200_000;
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let c = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                let p = henyey_greenstein(c as f32, g) as f64 * 2.0 * std::f64::consts::PI * 2.0 / n as f64;
                total += p;
                mean += p * c;
            }
            assert!((total - 1.0).abs() < 1e-3, "g {g}: integral {total}");
            assert!((mean - g as f64).abs() < 2e-3, "g {g}: mean cosine {mean}");
        }
    }

    #[test]
    fn phase_samples_follow_the_phase_function() {
        // Histogram of the sampled cosine against the density 2 pi p(cos),
        // chi-square over 20 bins.
        let d = Vec3::new(0.3, -0.5, 0.8).normalize();
        for g in [-0.5f32, 0.0, 0.6, 0.95] {
            let m = Medium {
                sigma_a: Vec3::ZERO,
                sigma_s: Vec3::ONE,
                g,
                density: None,
                emission: None,
            };
            let mut rng = Rng::new(7, g.to_bits() as u64);
            let bins = 20;
            let n = 200_000;
            let mut counts = vec![0u32; bins];
            for _ in 0..n {
                let (wi, pdf) = m.sample_phase(d, rng.next_2d());
                assert!((wi.length() - 1.0).abs() < 1e-4);
                let c = d.dot(wi);
                assert!((pdf - m.phase(d, wi)).abs() <= 1e-3 * pdf.max(1.0), "g {g}");
                let b = (((c + 1.0) / 2.0 * bins as f32) as usize).min(bins - 1);
                counts[b] += 1;
            }
            let mut chi2 = 0.0;
            for (b, &k) in counts.iter().enumerate() {
                // Probability of the bin, by the midpoint rule on a fine grid.
                let fine = 400;
                let (lo, w) = (-1.0 + 2.0 * b as f64 / bins as f64, 2.0 / bins as f64);
                let p: f64 = (0..fine)
                    .map(|i| {
                        let c = lo + (i as f64 + 0.5) * w / fine as f64;
                        henyey_greenstein(c as f32, g) as f64 * 2.0 * std::f64::consts::PI * w / fine as f64
                    })
                    .sum();
                let e = p * n as f64;
                chi2 += (k as f64 - e).powi(2) / e;
            }
            // 19 degrees of freedom: 43.8 is the 0.999 quantile.
            assert!(chi2 < 43.8, "g {g}: chi-square {chi2}, counts {counts:?}");
        }
    }

    #[test]
    fn distance_sampling_is_unbiased_per_channel() {
        // With the hero channel uniform, beta / mean(ratio) of one segment
        // has the expected value of the transmittance when it passes, and
        // of sigma_s Tr(t) integrated over the segment, sigma_s / sigma_t
        // (1 - Tr(t_max)), when it scatters; channel by channel.
        let m = Medium {
            sigma_a: Vec3::new(0.1, 0.5, 2.0),
            sigma_s: Vec3::new(1.0, 0.2, 0.0),
            g: 0.0,
            density: None,
            emission: None,
        };
        let t_max = 1.3;
        let mut rng = Rng::new(3, 4);
        let n = 400_000;
        let (mut pass, mut scatter) = (Vec3::ZERO, Vec3::ZERO);
        for i in 0..n {
            let mean = |r: Vec3| r.element_sum() / 3.0;
            match m.sample_homogeneous(t_max, i % 3, rng.next_f32(), None).0 {
                MediumEvent::Pass { beta, ratio } => pass += beta / mean(ratio),
                MediumEvent::Scatter { t, beta, ratio } => {
                    assert!(t < t_max);
                    scatter += beta / mean(ratio);
                }
            }
        }
        let (pass, scatter) = (pass / n as f32, scatter / n as f32);
        let tr = m.transmittance(t_max);
        let st = m.sigma_t();
        let expected = m.sigma_s / st * (Vec3::ONE - tr);
        assert!((pass - tr).abs().max_element() < 0.01, "{pass} vs {tr}");
        assert!(
            (scatter - expected).abs().max_element() < 0.01,
            "{scatter} vs {expected}"
        );
        // An absorber alone never scatters and passes with exactly Tr.
        let a = Medium {
            sigma_s: Vec3::ZERO,
            ..m
        };
        match a.sample_homogeneous(t_max, 1, 0.5, None).0 {
            MediumEvent::Pass { beta, ratio } => assert_eq!((beta, ratio), (a.transmittance(t_max), Vec3::ONE)),
            e => panic!("{e:?}"),
        }
    }

    /// A grid of `values` (x fastest) over the box [-1, 1]^3 moved by `m`.
    fn grid(n: [usize; 3], values: &[f32], m: Mat4) -> Arc<Density> {
        Arc::new(Density::grid(n, values.to_vec(), Vec3::splat(-1.0), Vec3::ONE, m).unwrap())
    }

    #[test]
    fn grid_density_is_pbrts_trilinear_lookup_with_zero_beyond() {
        // Three samples along x over [-1, 1]: centres at -2/3, 0, 2/3.
        let g = grid([3, 1, 1], &[1.0, 4.0, 2.0], Mat4::IDENTITY);
        let at = |x: f32| g.density(Vec3::new(x, 0.0, 0.0));
        for (x, d) in [
            (-2.0 / 3.0, 1.0),
            (0.0, 4.0),
            (2.0 / 3.0, 2.0),
            (-1.0 / 3.0, 2.5),
            (1.0 / 3.0, 3.0),
        ] {
            assert!((at(x) - d).abs() < 1e-5, "{x}: {} vs {d}", at(x));
        }
        // Beyond the outer centres the density falls linearly towards the
        // zeros beyond the grid: half way at the box's face, zero outside.
        assert!((at(-1.0) - 0.5).abs() < 1e-5 && (at(1.0) - 1.0).abs() < 1e-5);
        assert_eq!(
            (at(-1.5), at(1.5), g.density(Vec3::new(0.0, 0.0, 1.2))),
            (0.0, 0.0, 0.0)
        );
        // Along y and z the single sample falls off from the box's centre.
        assert!((g.density(Vec3::new(0.0, 0.4, -0.3)) - 4.0 * 0.8 * 0.85).abs() < 1e-5);
        // Moved with its medium: the sample at the centre lands at (5, 0, 0),
        // the grid stretched twice along x.
        let m = Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0)) * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let moved = grid([3, 1, 1], &[1.0, 4.0, 2.0], m);
        assert!((moved.density(Vec3::new(5.0, 0.0, 0.0)) - 4.0).abs() < 1e-5);
        assert!((moved.density(Vec3::new(5.0 + 4.0 / 3.0, 0.0, 0.0)) - 2.0).abs() < 1e-5);
        // The count must be the grid's, the values finite and not negative.
        let bad = |n, v: Vec<f32>| Density::grid(n, v, Vec3::ZERO, Vec3::ONE, Mat4::IDENTITY).is_err();
        assert!(bad([2, 2, 1], vec![1.0; 3]));
        assert!(bad([usize::MAX, 2, 1], vec![1.0; 3]));
        assert!(bad([3, 1, 1], vec![1.0, -1.0, 0.0]));
        assert!(bad([3, 1, 1], vec![1.0, f32::NAN, 0.0]));
        assert!(Density::grid(
            [1, 1, 1],
            vec![1.0],
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 1.0),
            Mat4::IDENTITY
        )
        .is_err());
    }

    #[test]
    fn grid_tracking_is_unbiased_per_channel() {
        // A ray along x through an uneven grid: passing has the expected
        // value of the transmittance exp(-sigma_t tau), tau the density's
        // integral, and scattering that of the integral of
        // sigma_s rho(t) Tr(t); ratio tracking's estimate has the
        // transmittance's. Both against a fine midpoint rule.
        let g = grid([4, 1, 1], &[0.1, 1.0, 0.0, 0.5], Mat4::IDENTITY);
        let m = Medium {
            sigma_a: Vec3::new(0.1, 0.5, 3.0),
            sigma_s: Vec3::new(2.0, 0.4, 0.0),
            g: 0.0,
            density: Some(g.clone()),
            emission: None,
        };
        let (o, d, t_max) = (Vec3::new(-1.6, 0.1, 0.2), Vec3::X, 2.9);
        let st = m.sigma_t();
        let steps = 20_000;
        let h = t_max / steps as f32;
        let (mut tau, mut scattered) = (0.0f32, Vec3::ZERO);
        for i in 0..steps {
            let t = (i as f32 + 0.5) * h;
            let rho = g.density(o + d * t);
            scattered += m.sigma_s * rho * exp(-st * (tau + rho * h / 2.0)) * h;
            tau += rho * h;
        }
        let tr = exp(-st * tau);
        let mut rng = Rng::new(5, 6);
        let n = 400_000;
        let (mut pass, mut scatter, mut ratio_tracked) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        let mean = |r: Vec3| r.element_sum() / 3.0;
        for i in 0..n {
            let o = o + Vec3::new(0.0, 0.0, 1e-6 * (i % 1000) as f32);
            match m.sample_distance(o, d, t_max, i % 3, rng.next_f32()) {
                MediumEvent::Pass { beta, ratio } => pass += beta / mean(ratio),
                MediumEvent::Scatter { t, beta, ratio } => {
                    assert!(t > 0.0 && t < t_max);
                    scatter += beta / mean(ratio);
                }
            }
            if i % 4 == 0 {
                ratio_tracked += m.transmittance_along(o + Vec3::new(0.0, 1e-7 * (i / 1000) as f32, 0.0), d, t_max);
            }
        }
        let (pass, scatter) = (pass / n as f32, scatter / n as f32);
        let ratio_tracked = ratio_tracked / (n / 4) as f32;
        // Within 1% (the estimates' noise is about 0.2%; wrong weights for
        // the channels' MIS, dropping the null events' ratios, are 4% off).
        let near = |a: Vec3, b: Vec3| (a - b).abs().cmple(b.max(Vec3::splat(0.05)) * 0.01).all();
        assert!(near(pass, tr), "{pass} vs {tr}");
        assert!(near(scatter, scattered), "{scatter} vs {scattered}");
        assert!(near(ratio_tracked, tr), "{ratio_tracked} vs {tr}");
        // An absorber alone passes with the ratio-tracked estimate.
        let a = Medium {
            sigma_s: Vec3::ZERO,
            ..m.clone()
        };
        match a.sample_distance(o, d, t_max, 2, 0.3) {
            MediumEvent::Pass { ratio, .. } => assert_eq!(ratio, Vec3::ONE),
            e => panic!("{e:?}"),
        }
        // A ray that misses the grid's box passes untouched.
        match m.sample_distance(Vec3::new(0.0, 2.0, 0.0), Vec3::X, 10.0, 0, 0.99) {
            MediumEvent::Pass { beta, ratio } => assert_eq!((beta, ratio), (Vec3::ONE, Vec3::ONE)),
            e => panic!("{e:?}"),
        }
        assert_eq!(
            m.transmittance_along(Vec3::new(0.0, 2.0, 0.0), Vec3::X, f32::INFINITY),
            Vec3::ONE
        );
    }

    #[test]
    fn a_grid_of_constant_density_tracks_as_the_homogeneous_medium() {
        // Where the density is one everywhere (between the outer samples of
        // a large grid), every tentative collision is real: the events are
        // the homogeneous medium's for the same u, to rounding (and to the
        // scale the grid's events are normalised to). So are those of an
        // RGB grid whose coefficients are the medium's at every sample.
        let g = grid([2, 2, 2], &[1.0; 8], Mat4::from_scale(Vec3::splat(20.0)));
        let h = Medium {
            sigma_a: Vec3::new(0.3, 0.1, 0.0),
            sigma_s: Vec3::new(0.5, 1.0, 2.0),
            g: 0.2,
            density: None,
            emission: None,
        };
        let m = Medium {
            density: Some(g),
            emission: None,
            ..h.clone()
        };
        let rgb = Density::rgb_grid(
            [2, 2, 2],
            Some(vec![h.sigma_a / 2.0; 8]),
            Some(vec![h.sigma_s / 2.0; 8]),
            2.0,
            Vec3::splat(-1.0),
            Vec3::ONE,
            Mat4::from_scale(Vec3::splat(20.0)),
        )
        .unwrap();
        let rgb = Medium {
            sigma_a: Vec3::ONE,
            sigma_s: Vec3::ONE,
            density: Some(Arc::new(rgb)),
            ..m.clone()
        };
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() <= 1e-5 * b.abs().max_element().max(1.0);
        for (k, m) in (0..600).map(|k| (k, if k < 300 { &m } else { &rgb })) {
            let u = ((k % 300) as f32 + 0.5) / 300.0;
            let (o, d) = (Vec3::new(-3.0, 1.0, 2.0), Vec3::new(1.0, 0.5, -0.2).normalize());
            match (
                h.sample_homogeneous(4.0, k % 3, u, None).0,
                m.sample_distance(o, d, 4.0, k % 3, u),
            ) {
                (MediumEvent::Pass { beta: b0, ratio: r0 }, MediumEvent::Pass { beta, ratio }) => {
                    let (b0, r0) = normalised(b0, r0);
                    assert!(close(beta, b0) && close(ratio, r0), "{u}: {beta} {ratio} vs {b0} {r0}")
                }
                (
                    MediumEvent::Scatter {
                        t: t0,
                        beta: b0,
                        ratio: r0,
                    },
                    MediumEvent::Scatter { t, beta, ratio },
                ) => {
                    assert!((t - t0).abs() < 1e-5 * t0.max(1.0), "{u}: {t} vs {t0}");
                    let (b0, r0) = normalised(b0, r0);
                    assert!(close(beta, b0) && close(ratio, r0), "{u}: {beta} {ratio} vs {b0} {r0}")
                }
                (a, b) => panic!("{u}: {a:?} vs {b:?}"),
            }
        }
    }

    #[test]
    fn a_cloud_is_pbrts_cloud_in_its_box() {
        // Dense below y = 0 (2 (0.5 - y) >= 1 there), in [0, 1] everywhere,
        // zero outside its box, and moved with its medium.
        let m = Mat4::from_translation(Vec3::new(0.0, -1.0, 0.0));
        let c = Density::cloud(2.0, 1.0, 5.0, Vec3::splat(-2.0), Vec3::splat(2.0), m).unwrap();
        let mut rng = Rng::new(3, 9);
        let mut sum = 0.0;
        for _ in 0..2000 {
            let q = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
            let d = c.density(q + Vec3::new(0.0, -1.0, 0.0));
            assert!((0.0..=1.0).contains(&d), "{q}: {d}");
            if q.y < 0.0 {
                assert_eq!(d, 1.0, "{q}");
            }
            sum += d;
        }
        // Above, the noise leaves gaps and wisps: neither empty nor solid.
        assert!(sum > 1000.0 && sum < 1900.0, "{sum}");
        assert_eq!(c.density(Vec3::new(0.0, -3.5, 0.0)), 0.0);
        assert_eq!(c.density(Vec3::new(0.0, 1.5, 0.0)), 0.0);
        // Where pbrt-v4 would have it: the same formula at the medium-space point.
        let p = Vec3::new(0.3, 0.8, -0.4);
        assert_eq!(
            c.density(p + Vec3::new(0.0, -1.0, 0.0)),
            cloud_density(p, 2.0, 1.0, 5.0)
        );
        assert!(Density::cloud(f32::NAN, 1.0, 5.0, Vec3::ZERO, Vec3::ONE, Mat4::IDENTITY).is_err());
    }

    #[test]
    fn temperatures_glow_as_their_table_says() {
        // Two grid samples, at q = (0.25, 0.5, 0.5) and (0.75, 0.5, 0.5):
        // 1300 and 2600 kelvin after the offset and scale, the first with a
        // Lescale of 2. The colour of a temperature is read from a table
        // between 100 K and the hottest; a stand-in colour (k / 1000)^2 per
        // channel shows what its interpolation gives.
        let rgb = |k: f32| Vec3::new(1.0, 0.5, 0.25) * (k / 1000.0).powi(2);
        let e = Emission::grid(
            [2, 1, 1],
            Vec3::ONE,
            Some(vec![2.0, 1.0]),
            Some(TemperatureGrid {
                values: vec![700.0, 1350.0],
                offset: 50.0,
                scale: 2.0,
                rgb: &rgb,
            }),
        )
        .unwrap();
        for (q, expected) in [
            (Vec3::new(0.25, 0.5, 0.5), rgb(1300.0) * 2.0),
            (Vec3::new(0.75, 0.5, 0.5), rgb(2600.0)),
            // Half way, the temperature and the scale interpolate.
            (Vec3::new(0.5, 0.5, 0.5), rgb(1950.0) * 1.5),
        ] {
            let got = e.at(q);
            assert!(
                ((got - expected) / expected).abs().max_element() < 1e-4,
                "{q}: {got} vs {expected}"
            );
        }
        // On the box's face the samples count half (pbrt-v4's lookup): 350
        // there, 600 K, and a Lescale of 1.
        let face = e.at(Vec3::new(0.0, 0.5, 0.5));
        assert!(((face - rgb(600.0)) / rgb(600.0)).abs().max_element() < 1e-4, "{face}");
        // Below 100 K nothing glows: 20 K at the second sample here.
        let cold = Some(TemperatureGrid {
            values: vec![700.0, 60.0],
            offset: 50.0,
            scale: 2.0,
            rgb: &rgb,
        });
        let e = Emission::grid([2, 1, 1], Vec3::ONE, None, cold).unwrap();
        assert_eq!(e.at(Vec3::new(0.75, 0.5, 0.5)), Vec3::ZERO);
        assert!(e.at(Vec3::new(0.25, 0.5, 0.5)).max_element() > 0.0);
        // Errors name what is wrong.
        let bad = Emission::grid([2, 1, 1], Vec3::ONE, Some(vec![1.0]), None).unwrap_err();
        assert!(bad.contains("1 \"Lescale\" values for a grid of 2 values"), "{bad}");
        let t = Some(TemperatureGrid {
            values: vec![1.0, f32::NAN],
            offset: 0.0,
            scale: 1.0,
            rgb: &rgb,
        });
        let bad = Emission::grid([2, 1, 1], Vec3::ONE, None, t).unwrap_err();
        assert!(bad.contains("a \"temperature\" value of NaN"), "{bad}");
    }
}
