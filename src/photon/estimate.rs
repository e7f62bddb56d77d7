//! The radiance estimate: density estimation over the photons near a point.
//!
//! Jensen (2001), "Realistic Image Synthesis Using Photon Mapping", 7.1: the
//! reflected radiance at x is L = sum_p f(x) Phi_p / (pi r^2) over the photons
//! within r of x, with r fixed (`--gather-radius`) or the distance to the k-th
//! nearest photon (`--gather-k`, the radius then bounding the search). The cone
//! filter (7.1.1) weights photon p by 1 - d_p / (k r), k = 1.1, and divides by
//! its integral (1 - 2 / (3k)) so that constant density is estimated without
//! bias. Photons that arrived from behind the shaded side are never used;
//! `GatherFilter` can also demand that their surface faced the same way.

use super::map::{Neighbour, Photon, PhotonMap};
use crate::math::Vec3;
use std::f32::consts::PI;

/// Jensen's cone filter constant (7.1.1): weights fall to 1 - 1/k at the radius.
pub const CONE_K: f32 = 1.1;

pub use crate::settings::{Gather, GatherFilter};

impl GatherFilter {
    /// Smallest cosine between the normals that passes (exclusive).
    pub fn min_cos(&self) -> f32 {
        match self {
            GatherFilter::None => -1.0,
            GatherFilter::Normal => 0.9,
            GatherFilter::Report => 0.25,
        }
    }
}

/// Which photons that reached a surface with no diffuse bounce before it a
/// gather may use; photons after a diffuse bounce (indirect light) always
/// count, if they lie on the same kind of surface (`Place`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Admit {
    /// First hits straight from a light (direct light).
    pub direct: bool,
    /// First diffuse hits after mirrors or glass only (caustics).
    pub caustic: bool,
    pub place: Place,
}

/// Where a gather's photons lie: on what stays still, or on one moving run
/// of triangles, kept where it is at its motion's start (`Photon::moving`).
/// A moving shape carries its photons along; the still world keeps its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Place {
    Still,
    /// The run's objects, `first..end`.
    Moving {
        first: u32,
        end: u32,
    },
}

impl Place {
    /// Where photons on objects `run` lie (`None`: on still ones).
    pub fn of(run: Option<std::ops::Range<u32>>) -> Place {
        match run {
            Some(r) => Place::Moving {
                first: r.start,
                end: r.end,
            },
            None => Place::Still,
        }
    }

    /// Small enough to stay inside the gathers' loops with a still scene's
    /// photons; a moving one's range is checked out of line.
    #[inline(always)]
    fn holds(&self, ph: &Photon) -> bool {
        if ph.is_moving() {
            self.holds_moving(ph)
        } else {
            *self == Place::Still
        }
    }

    #[inline(never)]
    fn holds_moving(&self, ph: &Photon) -> bool {
        match *self {
            Place::Still => false,
            Place::Moving { first, end } => (first..end).contains(&ph.object),
        }
    }
}

impl Admit {
    pub const ALL: Admit = Admit {
        direct: true,
        caustic: true,
        place: Place::Still,
    };
    pub const INDIRECT: Admit = Admit {
        direct: false,
        caustic: false,
        place: Place::Still,
    };

    /// The same admission on a moving run of triangles (or the still world).
    pub fn at(self, place: Place) -> Admit {
        Admit { place, ..self }
    }

    pub fn accepts(&self, ph: &Photon) -> bool {
        (self.direct || !ph.is_direct()) && (self.caustic || !ph.is_caustic()) && self.place.holds(ph)
    }
}

/// Photon irradiance at `p` on the side whose unit normal is `n`: the sum of
/// (filter-weighted) photon powers over the disc area. Multiply by a Lambertian
/// BRDF for reflected radiance. `admit` says which light-path kinds count.
pub fn irradiance(map: &PhotonMap, g: &Gather, p: Vec3, n: Vec3, admit: Admit, scratch: &mut Vec<Neighbour>) -> Vec3 {
    let min_cos = g.filter.min_cos();
    let accept = |ph: &Photon| {
        admit.accepts(ph) && ph.arrived_from(n) && (g.filter == GatherFilter::None || ph.normal().dot(n) > min_cos)
    };
    let weight = |d2: f32, r: f32| {
        if g.cone {
            1.0 - d2.sqrt() / (CONE_K * r)
        } else {
            1.0
        }
    };
    let (sum, r2) = match g.k {
        None => {
            let r2 = g.radius * g.radius;
            let mut sum = Vec3::ZERO;
            map.for_each_within(p, r2, |_, ph| {
                if accept(ph) {
                    sum += ph.power() * weight((ph.p - p).length_squared(), g.radius);
                }
            });
            (sum, r2)
        }
        Some(k) => {
            let mut r2 = map.k_nearest(p, k as usize, g.radius * g.radius, accept, scratch);
            if !r2.is_finite() {
                // Fewer than k photons in an unbounded search: the farthest found sets the radius.
                r2 = scratch.iter().map(|nb| nb.d2).fold(0.0, f32::max);
            }
            let r = r2.sqrt();
            let ph = map.photons();
            let sum = scratch
                .iter()
                .map(|nb| ph[nb.index as usize].power() * weight(nb.d2, r))
                .fold(Vec3::ZERO, |a, b| a + b);
            (sum, r2)
        }
    };
    if r2.is_nan() || r2 <= 0.0 || sum == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let norm = if g.cone { 1.0 - 2.0 / (3.0 * CONE_K) } else { 1.0 };
    sum * (map.unit / (norm * PI * r2))
}

/// Photon radiance estimate at `p` for any BSDF: sum f(wi_p) Phi_p / (pi r^2)
/// over the photons within the fixed radius (or the k nearest), `f` giving
/// the BSDF value (towards the viewer) for a photon that came from `wi_p`.
/// Photons whose `f` is zero (from a side the BSDF does not scatter from)
/// count for nothing; with `GatherFilter` the surfaces' normals must agree
/// up to orientation, so that light transmitted from the other side counts.
pub fn radiance(
    map: &PhotonMap,
    g: &Gather,
    p: Vec3,
    n: Vec3,
    admit: Admit,
    scratch: &mut Vec<Neighbour>,
    f: impl Fn(Vec3) -> Vec3,
) -> Vec3 {
    let min_cos = g.filter.min_cos();
    let accept =
        |ph: &Photon| admit.accepts(ph) && (g.filter == GatherFilter::None || ph.normal().dot(n).abs() > min_cos);
    let weight = |d2: f32, r: f32| {
        if g.cone {
            1.0 - d2.sqrt() / (CONE_K * r)
        } else {
            1.0
        }
    };
    let (sum, r2) = match g.k {
        None => {
            let r2 = g.radius * g.radius;
            let mut sum = Vec3::ZERO;
            map.for_each_within(p, r2, |_, ph| {
                if accept(ph) {
                    sum += f(ph.wi()) * ph.power() * weight((ph.p - p).length_squared(), g.radius);
                }
            });
            (sum, r2)
        }
        Some(k) => {
            let mut r2 = map.k_nearest(p, k as usize, g.radius * g.radius, accept, scratch);
            if !r2.is_finite() {
                r2 = scratch.iter().map(|nb| nb.d2).fold(0.0, f32::max);
            }
            let r = r2.sqrt();
            let ph = map.photons();
            let sum = scratch
                .iter()
                .map(|nb| {
                    let ph = &ph[nb.index as usize];
                    f(ph.wi()) * ph.power() * weight(nb.d2, r)
                })
                .fold(Vec3::ZERO, |a, b| a + b);
            (sum, r2)
        }
    };
    if r2.is_nan() || r2 <= 0.0 || sum == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let norm = if g.cone { 1.0 - 2.0 / (3.0 * CONE_K) } else { 1.0 };
    sum * (map.unit / (norm * PI * r2))
}

/// Every how many photons one is a site of precomputed irradiance.
pub const PRECOMPUTE_STRIDE: usize = 4;

/// What the largest precomputed irradiance is stored as (f16 holds up to
/// 65504 and keeps full precision down to 6e-5: 2^15 leaves headroom above and
/// nine decades below).
const SITE_SCALE: f32 = 32768.0;

/// Irradiance estimated once at a subset of the photons and looked up at the
/// nearest one (Christensen 1999, "Faster photon map global illumination";
/// Jensen 2001, 9.4). With a wide gather radius (the report's 0.4 finds
/// thousands of photons) a full estimate at every shading sample costs far
/// more than all else; the lookup is one nearest-neighbour query. The blur is
/// the same as the full estimate's, plus a step of the sites' spacing, which
/// is a fraction of the radius.
pub struct PrecomputedIrradiance {
    /// One record per site; its power field holds the site's irradiance.
    sites: PhotonMap,
    radius: f32,
    min_cos: f32,
}

impl PrecomputedIrradiance {
    /// Estimates the irradiance at every `PRECOMPUTE_STRIDE`-th photon of
    /// `map`, with the photon's surface normal (in parallel; the result does
    /// not depend on the thread count). `admit` as for [`irradiance`].
    /// `place` says where a photon lies; a site's estimate reads the photons
    /// lying there.
    pub fn build(
        map: &PhotonMap,
        g: &Gather,
        admit: Admit,
        place: impl Fn(&Photon) -> Place + Sync,
    ) -> PrecomputedIrradiance {
        use rayon::prelude::*;
        let photons = map.photons();
        let estimates: Vec<Vec3> = (0..photons.len())
            .into_par_iter()
            .step_by(PRECOMPUTE_STRIDE)
            .map_init(Vec::new, |scratch, i| {
                let ph = &photons[i];
                irradiance(map, g, ph.p, ph.normal(), admit.at(place(ph)), scratch)
            })
            .collect();
        // Stored as f16 relative to a unit that puts the largest estimate well
        // inside f16's range, so that irradiance of any scale (a small light
        // of radiance 10^6 or a dim one) neither clips nor underflows.
        let largest = estimates.iter().map(|e| e.max_element()).fold(0.0f32, f32::max);
        let unit = if largest > 0.0 && largest.is_finite() {
            largest / SITE_SCALE
        } else {
            1.0
        };
        let sites: Vec<Photon> = photons
            .iter()
            .step_by(PRECOMPUTE_STRIDE)
            .zip(&estimates)
            .map(|(ph, e)| {
                let site = Photon::new(ph.p, ph.wi(), ph.normal(), *e / unit, ph.object, ph.is_direct());
                if ph.is_moving() {
                    site.moving()
                } else {
                    site
                }
            })
            .collect();
        PrecomputedIrradiance {
            sites: PhotonMap::build(sites, unit),
            radius: if g.radius.is_finite() {
                g.radius
            } else {
                f32::MAX.sqrt()
            },
            // A site on a surface facing another way (across a corner, the other
            // side of a thin wall) has another irradiance; as in the gather, the
            // filter decides how far apart the normals may be.
            min_cos: g.filter.min_cos().max(0.0),
        }
    }

    /// Irradiance at `p` on the side of unit normal `n`: that of the nearest
    /// site within the gather radius facing the same way; `None` when there
    /// is none. Photons may still be there (one site in `PRECOMPUTE_STRIDE`
    /// photons), so the caller gathers them instead: read as zero, the
    /// sparse places (faint indirect light beside bright direct light) came
    /// out dark.
    pub fn lookup(&self, p: Vec3, n: Vec3, place: Place, scratch: &mut Vec<Neighbour>) -> Option<Vec3> {
        let accept = |s: &Photon| place.holds(s) && s.arrived_from(n) && s.normal().dot(n) > self.min_cos;
        self.sites.k_nearest(p, 1, self.radius * self.radius, accept, scratch);
        scratch
            .first()
            .map(|nb| self.sites.photons()[nb.index as usize].power() * self.sites.unit)
    }

    pub fn sites(&self) -> usize {
        self.sites.len()
    }

    pub fn bytes(&self) -> usize {
        self.sites.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn precomputed_irradiance_keeps_any_scale_of_light() {
        // A unit disc of photons on the plane z = 0, facing +z; the same map
        // in units of 10^-3 and 10^6 W per stored power.
        let mut rng = Rng::new(4, 4);
        let photons: Vec<Photon> = (0..4000)
            .map(|_| {
                let u = rng.next_2d();
                let p = Vec3::new(u.x * 2.0 - 1.0, u.y * 2.0 - 1.0, 0.0);
                Photon::new(p, Vec3::Z, Vec3::Z, Vec3::splat(1.0), 0, false)
            })
            .collect();
        let g = Gather {
            radius: 0.2,
            k: None,
            cone: false,
            filter: GatherFilter::None,
        };
        for unit in [1e-3f32, 1.0, 1e6] {
            let map = PhotonMap::build(photons.clone(), unit);
            let pre = PrecomputedIrradiance::build(&map, &g, Admit::ALL, |_| Place::Still);
            let mut scratch = vec![];
            for ph in map.photons().iter().step_by(97) {
                let full = irradiance(&map, &g, ph.p, Vec3::Z, Admit::ALL, &mut scratch);
                let near = pre.lookup(ph.p, Vec3::Z, Place::Still, &mut scratch).unwrap();
                assert!(full.x > 0.0 && near.x > 0.0);
                // The nearest site's estimate: the same density within the
                // photon noise, and never clipped (f16 would stop at 65504).
                assert!((near.x / full.x - 1.0).abs() < 0.5, "unit {unit}: {near} vs {full}");
                assert!(near.x > 100.0 * unit, "unit {unit}: {near}");
            }
        }
    }
}
