//! Subsurface scattering: pbrt-v4's tabulated BSSRDF (`TabulatedBSSRDF`,
//! `bssrdf.h`; Physically Based Rendering, 4th edition, 11.4 and 14.4).
//!
//! Light that enters a translucent object at `po` leaves it at `pi` with the
//! radially symmetric profile Sr(|pi - po|) of a semi-infinite slab of the
//! object's medium, computed once per (g, eta) by photon beam diffusion
//! (Habel et al. 2013: single scattering plus a dipole per depth, integrated
//! over the beam) for 100 albedos and 64 optical radii, and scaled to the
//! medium's extinction at a point. An integrator finds `pi` by sampling a
//! radius from the profile and a probe segment through the object along one
//! of three axes of the frame at `po`, and takes the probe's hits on the same
//! material; the exit direction then follows a Fresnel-weighted Lambertian
//! lobe ([`crate::bsdf::NormalizedFresnelBxdf`]).
//!
//! The splines follow pbrt-v4's Catmull-Rom helpers (`util/math.cpp`,
//! `util/sampling.cpp`): profiles are interpolated over albedo and radius,
//! radii are sampled by inverting the interpolated cumulative profile.

use crate::bsdf::{fr_dielectric, fresnel_moment1, fresnel_moment2, Frame};
use crate::math::{Vec2, Vec3};
use crate::medium::henyey_greenstein;
use rayon::prelude::*;
use std::f64::consts::PI as PI64;
use std::sync::{Arc, Mutex, Weak};

/// Albedos and optical radii of the table (pbrt-v4's).
const RHO_SAMPLES: usize = 100;
const RADIUS_SAMPLES: usize = 64;
/// Depths each beam-diffusion integral takes.
const BEAM_SAMPLES: usize = 100;
/// The profile is cut where its cumulative reaches this fraction: probe
/// segments are no longer than its radius allows.
const PROBE_QUANTILE: f32 = 0.999;

/// Multiple scattering of photon beam diffusion at radius `r` in a medium of
/// unit extinction (pbrt-v4's `BeamDiffusionMS`): dipoles for real sources
/// at depths spread by the reduced extinction, with Grosjean's diffusion
/// coefficient and the boundary condition of a dielectric interface.
fn beam_diffusion_ms(sigma_s: f64, sigma_a: f64, g: f64, eta: f64, r: f64) -> f64 {
    let sigmap_s = sigma_s * (1.0 - g);
    let sigmap_t = sigma_a + sigmap_s;
    let rhop = sigmap_s / sigmap_t;
    let d_g = (2.0 * sigma_a + sigmap_s) / (3.0 * sigmap_t * sigmap_t);
    let sigma_tr = (sigma_a / d_g).max(0.0).sqrt();
    let (fm1, fm2) = (fresnel_moment1(eta as f32) as f64, fresnel_moment2(eta as f32) as f64);
    let ze = -2.0 * d_g * (1.0 + 3.0 * fm2) / (1.0 - 2.0 * fm1);
    let (c_phi, c_e) = (0.25 * (1.0 - 2.0 * fm1), 0.5 * (1.0 - 3.0 * fm2));
    let mut ed = 0.0;
    for i in 0..BEAM_SAMPLES {
        let zr = sample_exponential((i as f64 + 0.5) / BEAM_SAMPLES as f64, sigmap_t);
        let zv = -zr + 2.0 * ze;
        let (dr, dv) = ((r * r + zr * zr).sqrt(), (r * r + zv * zv).sqrt());
        let phi_d = (0.25 / PI64) / d_g * ((-sigma_tr * dr).exp() / dr - (-sigma_tr * dv).exp() / dv);
        let ed_n = (0.25 / PI64)
            * (zr * (1.0 + sigma_tr * dr) * (-sigma_tr * dr).exp() / dr.powi(3)
                - zv * (1.0 + sigma_tr * dv) * (-sigma_tr * dv).exp() / dv.powi(3));
        let e = phi_d * c_phi + ed_n * c_e;
        let kappa = 1.0 - (-2.0 * sigmap_t * (dr + zr)).exp();
        ed += kappa * rhop * rhop * e;
    }
    ed / BEAM_SAMPLES as f64
}

/// Single scattering of photon beam diffusion at radius `r` (pbrt-v4's
/// `BeamDiffusionSS`): light refracted straight down, scattered once at a
/// depth below the critical angle's, and refracted out at `r`.
fn beam_diffusion_ss(sigma_s: f64, sigma_a: f64, g: f64, eta: f64, r: f64) -> f64 {
    let sigma_t = sigma_a + sigma_s;
    let rho = sigma_s / sigma_t;
    let t_crit = r * (eta * eta - 1.0).max(0.0).sqrt();
    let mut ess = 0.0;
    for i in 0..BEAM_SAMPLES {
        let ti = t_crit + sample_exponential((i as f64 + 0.5) / BEAM_SAMPLES as f64, sigma_t);
        let d = (r * r + ti * ti).sqrt();
        let cos_o = ti / d;
        // pbrt-v4's phase function takes the cosine between directions both
        // pointing away; ours between the travelling and the scattered one.
        let phase = henyey_greenstein(-cos_o as f32, g as f32) as f64;
        let fresnel = fr_dielectric(-cos_o as f32, eta as f32) as f64;
        ess += rho * (-sigma_t * (d + t_crit)).exp() / (d * d) * phase * (1.0 - fresnel) * cos_o.abs();
    }
    ess / BEAM_SAMPLES as f64
}

/// A distance with density a exp(-a x) for `u` in [0, 1).
fn sample_exponential(u: f64, a: f64) -> f64 {
    -(1.0 - u).ln() / a
}

/// A table's (g, eta), by their bits.
type TableKey = (u32, u32);

/// The radial profiles of a medium of phase asymmetry `g` behind an
/// interface of index `eta`, for unit extinction: `profile` holds
/// 2 pi r Sr(r) by albedo (rows) and optical radius (columns), `rho_eff`
/// each row's integral (the slab's total diffuse reflectance at that
/// albedo), `cdf` each row's running integral.
pub struct BssrdfTable {
    g: f32,
    eta: f32,
    rho: Vec<f32>,
    radius: Vec<f32>,
    profile: Vec<f32>,
    rho_eff: Vec<f32>,
    cdf: Vec<f32>,
}

impl BssrdfTable {
    /// The table of pbrt-v4's `ComputeBeamDiffusionBSSRDF`: radii 0, then
    /// from 0.0025 growing by a fifth a step; albedos crowded towards 1,
    /// where the profiles change fastest.
    pub fn new(g: f32, eta: f32) -> Self {
        let mut radius = vec![0.0f32; RADIUS_SAMPLES];
        radius[1] = 2.5e-3;
        for i in 2..RADIUS_SAMPLES {
            radius[i] = radius[i - 1] * 1.2;
        }
        let rho: Vec<f32> = (0..RHO_SAMPLES)
            .map(|i| {
                let x = i as f64 / (RHO_SAMPLES - 1) as f64;
                ((1.0 - (-8.0 * x).exp()) / (1.0 - (-8.0f64).exp())) as f32
            })
            .collect();
        let mut profile = vec![0.0f32; RHO_SAMPLES * RADIUS_SAMPLES];
        let mut cdf = vec![0.0f32; RHO_SAMPLES * RADIUS_SAMPLES];
        let mut rho_eff = vec![0.0f32; RHO_SAMPLES];
        // A row an albedo, each on its own: 50 ms a table on one thread.
        profile
            .par_chunks_mut(RADIUS_SAMPLES)
            .zip(cdf.par_chunks_mut(RADIUS_SAMPLES))
            .zip(rho_eff.par_iter_mut())
            .zip(rho.par_iter())
            .for_each(|(((row, row_cdf), eff), &albedo)| {
                let (a, gg, e) = (albedo as f64, g as f64, eta as f64);
                for (p, &r) in row.iter_mut().zip(&radius) {
                    let r = r as f64;
                    let ss = beam_diffusion_ss(a, 1.0 - a, gg, e, r);
                    let ms = beam_diffusion_ms(a, 1.0 - a, gg, e, r);
                    *p = (2.0 * PI64 * r * (ss + ms)) as f32;
                }
                *eff = integrate_catmull_rom(&radius, row, row_cdf);
            });
        BssrdfTable {
            g,
            eta,
            rho,
            radius,
            profile,
            rho_eff,
            cdf,
        }
    }

    /// The table for (g, eta), shared with every other material of the same
    /// pair that is still alive: a scene of many translucent materials
    /// computes each table once.
    pub fn shared(g: f32, eta: f32) -> Arc<BssrdfTable> {
        static TABLES: Mutex<Vec<(TableKey, Weak<BssrdfTable>)>> = Mutex::new(Vec::new());
        let key = (g.to_bits(), eta.to_bits());
        let mut tables = TABLES.lock().unwrap_or_else(|e| e.into_inner());
        tables.retain(|(_, t)| t.strong_count() > 0);
        if let Some(t) = tables.iter().find(|(k, _)| *k == key).and_then(|(_, t)| t.upgrade()) {
            return t;
        }
        let t = Arc::new(BssrdfTable::new(g, eta));
        tables.push((key, Arc::downgrade(&t)));
        t
    }

    /// The slab's total diffuse reflectance at single-scattering albedo `rho`.
    pub fn rho_eff(&self, rho: f32) -> f32 {
        let Some((offset, w)) = catmull_rom_weights(&self.rho, rho) else {
            return 0.0;
        };
        spline_sum(offset, &w, |j| self.rho_eff[j])
    }

    /// The albedos whose total diffuse reflectance is `reflectance` (each
    /// channel clamped to [0, 1]), and from them and the mean free paths
    /// `mfp` the coefficients (sigma_a, sigma_s) (pbrt-v4's
    /// `SubsurfaceFromDiffuse`).
    pub fn coefficients_for(&self, reflectance: Vec3, mfp: Vec3) -> (Vec3, Vec3) {
        let mut sigma_a = Vec3::ZERO;
        let mut sigma_s = Vec3::ZERO;
        for c in 0..3 {
            let rho = invert_catmull_rom(&self.rho, &self.rho_eff, reflectance[c].clamp(0.0, 1.0));
            sigma_s[c] = rho / mfp[c];
            sigma_a[c] = (1.0 - rho) / mfp[c];
        }
        (sigma_a, sigma_s)
    }

    fn profile_at(&self, rho_index: usize, radius_index: usize) -> f32 {
        self.profile[rho_index * RADIUS_SAMPLES + radius_index]
    }
}

impl std::fmt::Debug for BssrdfTable {
    // The table follows from (g, eta); scene fingerprints hash this form.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BssrdfTable")
            .field("g", &self.g)
            .field("eta", &self.eta)
            .finish()
    }
}

impl PartialEq for BssrdfTable {
    fn eq(&self, other: &Self) -> bool {
        self.g == other.g && self.eta == other.eta
    }
}

/// The BSSRDF at an entry point `po` with shading normal `ns`, for a medium
/// of extinction `sigma_t` and albedo `rho` per channel.
pub struct Bssrdf<'a> {
    pub po: Vec3,
    pub ns: Vec3,
    pub eta: f32,
    sigma_t: Vec3,
    rho: Vec3,
    table: &'a BssrdfTable,
}

impl<'a> Bssrdf<'a> {
    pub fn new(po: Vec3, ns: Vec3, sigma_a: Vec3, sigma_s: Vec3, table: &'a BssrdfTable) -> Self {
        let sigma_t = sigma_a + sigma_s;
        let rho = Vec3::from_array(std::array::from_fn(|c| {
            if sigma_t[c] > 0.0 {
                sigma_s[c] / sigma_t[c]
            } else {
                0.0
            }
        }));
        Bssrdf {
            po,
            ns,
            eta: table.eta,
            sigma_t,
            rho,
            table,
        }
    }

    /// The profile in channel `c` at optical radius `r_optical` and the
    /// interpolated total reflectance, per unit area of the unit-extinction
    /// slab; `None` outside the table.
    fn profile(&self, c: usize, r_optical: f32) -> Option<(f32, f32)> {
        let t = self.table;
        let (ro, rw) = catmull_rom_weights(&t.rho, self.rho[c])?;
        let (xo, xw) = catmull_rom_weights(&t.radius, r_optical)?;
        let mut sr = 0.0;
        let mut rho_eff = 0.0;
        for (j, &wj) in rw.iter().enumerate() {
            let Some(rj) = (wj != 0.0).then(|| (ro + j).checked_sub(1)).flatten() else {
                continue;
            };
            rho_eff += t.rho_eff[rj] * wj;
            for (k, &wk) in xw.iter().enumerate() {
                if let Some(xk) = (wk != 0.0).then(|| (xo + k).checked_sub(1)).flatten() {
                    sr += t.profile_at(rj, xk) * wj * wk;
                }
            }
        }
        // The table holds 2 pi r Sr(r): the marginal density in r.
        if r_optical != 0.0 {
            sr /= 2.0 * std::f32::consts::PI * r_optical;
        }
        Some((sr, rho_eff))
    }

    /// Sr(r) per channel, at distance `r` in scene units.
    pub fn sr(&self, r: f32) -> Vec3 {
        Vec3::from_array(std::array::from_fn(|c| {
            let s = self.sigma_t[c];
            self.profile(c, r * s).map_or(0.0, |(sr, _)| (sr * s * s).max(0.0))
        }))
    }

    /// The density, per unit area of the plane, of [`Bssrdf::sample_sr`]'s
    /// radii in each channel: Sr over the slab's total reflectance.
    pub fn pdf_sr(&self, r: f32) -> Vec3 {
        Vec3::from_array(std::array::from_fn(|c| {
            let s = self.sigma_t[c];
            match self.profile(c, r * s) {
                Some((sr, rho_eff)) if rho_eff > 0.0 => (sr * s * s / rho_eff).max(0.0),
                _ => 0.0,
            }
        }))
    }

    /// A radius from channel `c`'s profile, `u` in [0, 1); `None` where the
    /// channel has no extinction.
    pub fn sample_sr(&self, c: usize, u: f32) -> Option<f32> {
        let s = self.sigma_t[c];
        if s <= 0.0 {
            return None;
        }
        let t = self.table;
        let r = sample_catmull_rom_2d(&t.rho, &t.radius, &t.profile, &t.cdf, self.rho[c], u)?;
        Some(r / s)
    }

    /// A probe segment (start, end) for channel `c`: a radius from its
    /// profile and an angle, about one of three axes at `po` (the normal
    /// with probability 1/2, each tangent with 1/4), through the whole
    /// sphere of the profile's `PROBE_QUANTILE` radius.
    pub fn sample_probe(&self, c: usize, u1: f32, u2: Vec2) -> Option<(Vec3, Vec3)> {
        let f = Frame::from_z(self.ns);
        let (axis, a, b) = if u1 < 0.25 {
            (f.x, f.y, f.z)
        } else if u1 < 0.5 {
            (f.y, f.z, f.x)
        } else {
            (f.z, f.x, f.y)
        };
        let r = self.sample_sr(c, u2.x)?;
        let r_max = self.sample_sr(c, PROBE_QUANTILE)?;
        if r.is_nan() || r >= r_max {
            return None;
        }
        let phi = 2.0 * std::f32::consts::PI * u2.y;
        let l = 2.0 * (r_max * r_max - r * r).sqrt();
        let start = self.po + (a * phi.cos() + b * phi.sin()) * r - axis * (0.5 * l);
        Some((start, start + axis * l))
    }

    /// The density per unit area, in each channel, of an exit point `pi`
    /// with geometric normal `ni` over the three probe axes.
    pub fn pdf_sp(&self, pi: Vec3, ni: Vec3) -> Vec3 {
        let f = Frame::from_z(self.ns);
        let d = f.to_local(pi - self.po);
        let n = f.to_local(ni);
        let projected = [
            (d.y * d.y + d.z * d.z).sqrt(),
            (d.z * d.z + d.x * d.x).sqrt(),
            (d.x * d.x + d.y * d.y).sqrt(),
        ];
        let axis_prob = [0.25, 0.25, 0.5];
        (0..3).fold(Vec3::ZERO, |pdf, axis| {
            pdf + self.pdf_sr(projected[axis]) * (n[axis].abs() * axis_prob[axis])
        })
    }
}

/// The index of the interval [nodes[i], nodes[i + 1]] in which `pred` turns
/// false (pbrt-v4's `FindInterval`), clamped to the valid intervals.
fn find_interval(size: usize, pred: impl Fn(usize) -> bool) -> usize {
    let (mut first, mut len) = (0usize, size);
    while len > 0 {
        let half = len / 2;
        let middle = first + half;
        if pred(middle) {
            first = middle + 1;
            len -= half + 1;
        } else {
            len = half;
        }
    }
    first.saturating_sub(1).min(size.saturating_sub(2))
}

/// Catmull-Rom spline weights of the four nodes about `x`: the index of the
/// interval's first node and the weights of nodes index - 1 ..= index + 2
/// (zero where a node is missing at an end). `None` outside the nodes.
fn catmull_rom_weights(nodes: &[f32], x: f32) -> Option<(usize, [f32; 4])> {
    let (first, last) = (*nodes.first()?, *nodes.last()?);
    if !(x >= first && x <= last) || nodes.len() < 2 {
        return None;
    }
    let idx = find_interval(nodes.len(), |i| nodes[i] <= x);
    let (x0, x1) = (nodes[idx], nodes[idx + 1]);
    let t = (x - x0) / (x1 - x0);
    let (t2, t3) = (t * t, t * t * t);
    let mut w = [0.0f32; 4];
    w[1] = 2.0 * t3 - 3.0 * t2 + 1.0;
    w[2] = -2.0 * t3 + 3.0 * t2;
    if idx > 0 {
        let w0 = (t3 - 2.0 * t2 + t) * (x1 - x0) / (x1 - nodes[idx - 1]);
        w[0] = -w0;
        w[2] += w0;
    } else {
        let w0 = t3 - 2.0 * t2 + t;
        w[1] -= w0;
        w[2] += w0;
    }
    if idx + 2 < nodes.len() {
        let w3 = (t3 - t2) * (x1 - x0) / (nodes[idx + 2] - x0);
        w[1] -= w3;
        w[3] = w3;
    } else {
        let w3 = t3 - t2;
        w[1] -= w3;
        w[2] += w3;
    }
    Some((idx, w))
}

/// The weighted sum of `value(j)` over the nodes of `catmull_rom_weights`.
fn spline_sum(offset: usize, w: &[f32; 4], value: impl Fn(usize) -> f32) -> f32 {
    w.iter()
        .enumerate()
        .filter(|(_, &wj)| wj != 0.0)
        .filter_map(|(j, &wj)| (offset + j).checked_sub(1).map(|i| value(i) * wj))
        .sum()
}

/// The finite-difference slopes of a spline segment [i, i + 1], scaled to
/// the segment's width.
fn slopes(nodes: &[f32], f: impl Fn(usize) -> f32, i: usize) -> (f32, f32) {
    let (x0, x1) = (nodes[i], nodes[i + 1]);
    let (f0, f1) = (f(i), f(i + 1));
    let width = x1 - x0;
    let d0 = if i > 0 {
        width * (f1 - f(i - 1)) / (x1 - nodes[i - 1])
    } else {
        f1 - f0
    };
    let d1 = if i + 2 < nodes.len() {
        width * (f(i + 2) - f0) / (nodes[i + 2] - x0)
    } else {
        f1 - f0
    };
    (d0, d1)
}

/// The integral of the spline through (nodes, f), its running integral
/// written to `cdf` (pbrt-v4's `IntegrateCatmullRom`).
fn integrate_catmull_rom(nodes: &[f32], f: &[f32], cdf: &mut [f32]) -> f32 {
    let mut sum = 0.0;
    cdf[0] = 0.0;
    for i in 0..nodes.len() - 1 {
        let (d0, d1) = slopes(nodes, |j| f[j], i);
        sum += (nodes[i + 1] - nodes[i]) * ((f[i] + f[i + 1]) / 2.0 + (d0 - d1) / 12.0);
        cdf[i + 1] = sum;
    }
    sum
}

/// The x at which the spline through (nodes, f), increasing, reaches `u`
/// (pbrt-v4's `InvertCatmullRom`); the end nodes beyond its range.
fn invert_catmull_rom(nodes: &[f32], f: &[f32], u: f32) -> f32 {
    let (Some(&lo), Some(&hi)) = (f.first(), f.last()) else {
        return 0.0;
    };
    if u.is_nan() || u <= lo {
        return nodes[0];
    }
    if u >= hi {
        return nodes[nodes.len() - 1];
    }
    let i = find_interval(f.len(), |i| f[i] <= u);
    let (x0, x1) = (nodes[i], nodes[i + 1]);
    let (f0, f1) = (f[i], f[i + 1]);
    let (d0, d1) = slopes(nodes, |j| f[j], i);
    let t = newton_bisection(|t| {
        let (t2, t3) = (t * t, t * t * t);
        let value =
            (2.0 * t3 - 3.0 * t2 + 1.0) * f0 + (-2.0 * t3 + 3.0 * t2) * f1 + (t3 - 2.0 * t2 + t) * d0 + (t3 - t2) * d1;
        let slope = (6.0 * t2 - 6.0 * t) * f0
            + (-6.0 * t2 + 6.0 * t) * f1
            + (3.0 * t2 - 4.0 * t + 1.0) * d0
            + (3.0 * t2 - 2.0 * t) * d1;
        (value - u, slope)
    });
    x0 + t * (x1 - x0)
}

/// Samples the second variable of the 2D spline `values` (rows over
/// `nodes1`, columns over `nodes2`) at first variable `alpha`, by inverting
/// the interpolated running integral `cdf` (pbrt-v4's `SampleCatmullRom2D`).
fn sample_catmull_rom_2d(
    nodes1: &[f32],
    nodes2: &[f32],
    values: &[f32],
    cdf: &[f32],
    alpha: f32,
    u: f32,
) -> Option<f32> {
    let (offset, w) = catmull_rom_weights(nodes1, alpha)?;
    let n2 = nodes2.len();
    let interpolate = |array: &[f32], idx: usize| spline_sum(offset, &w, |row| array[row * n2 + idx]);
    let maximum = interpolate(cdf, n2 - 1);
    if maximum.is_nan() || maximum <= 0.0 {
        return None;
    }
    let u = u * maximum;
    let idx = find_interval(n2, |i| interpolate(cdf, i) <= u);
    let f = |i: usize| interpolate(values, i);
    let (f0, f1) = (f(idx), f(idx + 1));
    let (x0, x1) = (nodes2[idx], nodes2[idx + 1]);
    let width = x1 - x0;
    let (d0, d1) = slopes(nodes2, f, idx);
    let u = (u - interpolate(cdf, idx)) / width;
    let t = newton_bisection(|t| {
        // The segment's integral from 0 to t, and the spline itself.
        let integral = t
            * (f0
                + t * (0.5 * d0
                    + t * ((1.0 / 3.0) * (-2.0 * d0 - d1) + f1 - f0 + t * (0.25 * (d0 + d1) + 0.5 * (f0 - f1)))));
        let value = f0 + t * (d0 + t * (-2.0 * d0 - d1 + 3.0 * (f1 - f0) + t * (d0 + d1 + 2.0 * (f0 - f1))));
        (integral - u, value)
    });
    Some(x0 + width * t)
}

/// The root in [0, 1] of a function increasing or decreasing there, given
/// with its derivative: Newton's steps, bisection where they leave the
/// bracket (pbrt-v4's `NewtonBisection`).
fn newton_bisection(f: impl Fn(f32) -> (f32, f32)) -> f32 {
    const X_EPS: f32 = 1e-6;
    const F_EPS: f32 = 1e-6;
    let (mut x0, mut x1) = (0.0f32, 1.0f32);
    let (f0, f1) = (f(x0).0, f(x1).0);
    if f0.abs() < F_EPS {
        return x0;
    }
    if f1.abs() < F_EPS {
        return x1;
    }
    let start_negative = f0 < 0.0;
    let mut x = x0 + (x1 - x0) * -f0 / (f1 - f0);
    // Bisection alone would halve the bracket below X_EPS in 20 steps.
    for _ in 0..64 {
        if !(x0 < x && x < x1) {
            x = 0.5 * (x0 + x1);
        }
        let (fx, dfx) = f(x);
        if start_negative == (fx < 0.0) {
            x0 = x;
        } else {
            x1 = x;
        }
        if x1 - x0 < X_EPS || fx.abs() < F_EPS {
            return x;
        }
        x -= fx / dfx;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splines_interpolate_integrate_and_invert() {
        // A cubic is reproduced by neither, but x^2 on fine nodes nearly is.
        let nodes: Vec<f32> = (0..=20).map(|i| i as f32 / 10.0).collect();
        let f: Vec<f32> = nodes.iter().map(|x| x * x).collect();
        let (offset, w) = catmull_rom_weights(&nodes, 1.23).unwrap();
        let v = spline_sum(offset, &w, |i| f[i]);
        assert!((v - 1.23f32 * 1.23).abs() < 2e-3, "{v}");
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        assert!(catmull_rom_weights(&nodes, 2.5).is_none());
        let mut cdf = vec![0.0; nodes.len()];
        let total = integrate_catmull_rom(&nodes, &f, &mut cdf);
        assert!((total - 8.0 / 3.0).abs() < 2e-3, "{total}");
        assert!(cdf.windows(2).all(|w| w[1] >= w[0]));
        let x = invert_catmull_rom(&nodes, &f, 2.0);
        assert!((x - 2f32.sqrt()).abs() < 1e-3, "{x}");
        assert_eq!(invert_catmull_rom(&nodes, &f, -1.0), 0.0);
        assert_eq!(invert_catmull_rom(&nodes, &f, 9.0), 2.0);
    }

    #[test]
    fn total_reflectance_rises_with_albedo_and_stays_below_one() {
        let t = BssrdfTable::new(0.0, 1.33);
        assert_eq!(t.rho_eff[0], 0.0);
        assert!(t.rho_eff.windows(2).all(|w| w[1] > w[0]), "{:?}", t.rho_eff);
        // A lossless slab behind an interface reflects nearly everything
        // that enters it; photon beam diffusion is close to, not exactly,
        // energy conserving there.
        let top = t.rho_eff[RHO_SAMPLES - 1];
        assert!(top > 0.8 && top < 1.05, "{top}");
        // Reflectance and albedo invert each other.
        let (sa, ss) = t.coefficients_for(Vec3::new(0.2, 0.5, 0.8), Vec3::new(1.0, 2.0, 0.5));
        for c in 0..3 {
            let rho = ss[c] / (sa[c] + ss[c]);
            let back = t.rho_eff(rho);
            assert!((back - [0.2, 0.5, 0.8][c]).abs() < 1e-3, "{c}: {back}");
            assert!(((sa[c] + ss[c]) * [1.0, 2.0, 0.5][c] - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn sampled_radii_follow_the_profile_and_its_density_integrates_to_one() {
        // sigma_t differs by channel; each channel's sampled radii, binned,
        // against the density integrated over each bin, and that density
        // over the plane against 1.
        let t = BssrdfTable::new(0.3, 1.4);
        let b = Bssrdf::new(
            Vec3::ZERO,
            Vec3::Z,
            Vec3::new(0.05, 0.4, 2.0),
            Vec3::new(2.0, 1.0, 2.0),
            &t,
        );
        for c in 0..3 {
            let r_max = b.sample_sr(c, PROBE_QUANTILE).unwrap();
            let bins = 20;
            let n = 200_000;
            let mut counts = vec![0u32; bins];
            for i in 0..n {
                let u = (i as f32 + 0.5) / n as f32;
                let r = b.sample_sr(c, u).unwrap();
                if r < r_max {
                    counts[((r / r_max) * bins as f32) as usize] += 1;
                }
            }
            // Midpoint rule in r of pdf_sr(r) 2 pi r, 200 steps a bin.
            let steps = 200;
            let mut total = 0.0f64;
            for (k, &count) in counts.iter().enumerate() {
                let mut p = 0.0f64;
                for s in 0..steps {
                    let r = (k as f32 + (s as f32 + 0.5) / steps as f32) * r_max / bins as f32;
                    p += (b.pdf_sr(r)[c] * 2.0 * std::f32::consts::PI * r) as f64
                        * (r_max / (bins * steps) as f32) as f64;
                }
                total += p;
                let observed = count as f64 / n as f64;
                assert!(
                    (observed - p).abs() < 0.02 * p.max(0.01),
                    "channel {c}, bin {k}: sampled {observed}, density {p}"
                );
            }
            assert!((total - PROBE_QUANTILE as f64).abs() < 0.01, "channel {c}: {total}");
        }
    }

    #[test]
    fn the_exit_lobe_reflects_all_that_reaches_it() {
        // Normalised: its albedo is 1 for importance, eta^2 for radiance
        // (given back what the refraction into the object took).
        use crate::bsdf::{NormalizedFresnelBxdf, TransportMode};
        for eta in [1.2f32, 1.33, 1.5] {
            let b = NormalizedFresnelBxdf { eta };
            let wo = Vec3::Z;
            let n = 20_000;
            let albedo = |mode| {
                (0..n)
                    .map(|i| {
                        let c = (i as f32 + 0.5) / n as f32;
                        let wi = Vec3::new((1.0 - c * c).sqrt(), 0.0, c);
                        (b.f(wo, wi, mode).x * c) as f64 * 2.0 * std::f64::consts::PI / n as f64
                    })
                    .sum::<f64>()
            };
            let a = albedo(TransportMode::Importance);
            assert!((a - 1.0).abs() < 0.01, "{eta}: {a}");
            let r = albedo(TransportMode::Radiance);
            assert!((r / a - (eta * eta) as f64).abs() < 1e-4, "{eta}: {r}");
            assert_eq!(b.f(wo, -Vec3::Z, TransportMode::Importance), Vec3::ZERO);
        }
    }

    #[test]
    fn materials_of_one_g_and_eta_share_their_table() {
        let a = BssrdfTable::shared(0.1, 1.41);
        let b = BssrdfTable::shared(0.1, 1.41);
        let c = BssrdfTable::shared(0.1, 1.42);
        assert!(Arc::ptr_eq(&a, &b));
        assert!(!Arc::ptr_eq(&a, &c));
        assert_eq!(a.rho_eff, BssrdfTable::new(0.1, 1.41).rho_eff);
    }
}
