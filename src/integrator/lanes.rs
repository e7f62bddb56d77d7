//! Plain paths ([`super::plain`]) traced eight at a time, for scenes of
//! still triangles lit by triangle lights.
//!
//! Each of the eight lanes follows one camera sample's path; a lane whose
//! path ends takes the tile's next camera sample. The work of a bounce runs
//! stage by stage over all lanes: the eight rays' queries, then their hits'
//! geometry, shading frames and BSDF samples, then the light samples and
//! their shadow rays, then the next rays. Every lane does the same arithmetic
//! on the same numbers as [`super::plain::PlainPathTracer::li`] on its own,
//! so the image is that loop's bit for bit (tested), whatever the order the
//! lanes finish in: pixel sums are exact.
//!
//! Each stage is a loop over the lanes' arrays, compiled for AVX2 where the
//! CPU has it, and for AVX2 with GFNI (its bit reversal makes the Sobol
//! sampler's requests, inlined into the lanes, a fifth cheaper). Running
//! each kind of work eight times in a row lets the processor overlap eight
//! independent chains of it (8% on `cornell-box`, BENCHMARKS.md, "Paths
//! eight at a time"). The light samples and the next bounce's throughput
//! are written as steps without branches, each case a select, which the
//! compiler turns into vector instructions (eight divisions and square
//! roots at once): 13% more (BENCHMARKS.md, "Light samples in vector
//! registers"). Writing the shading frames and the BSDF samples so, and
//! computing the Sobol requests side by side in AVX2, did not pay (same
//! section).

// A stage reads and writes a lane's entry in many arrays at once: indexing
// by lane says so more plainly than zipped iterators.
#![allow(clippy::needless_range_loop)]

use super::direct::{emitted_radiance, escaped_radiance};
use super::path::{MAX_SURVIVAL, ROULETTE_DEPTH};
use super::plain::PlainPathTracer;
use super::{CameraSample, PixelSamples, RayStats, RenderSettings, Tile};
use crate::bsdf::frame::Frame;
use crate::film::SplatBlock;
use crate::light::{triangle_normal_area, Light, LightContext};
use crate::math::{offset_origin, Ray, Vec2, Vec3};
use crate::sampling::cosine_hemisphere;
use crate::scene::{interpolated_normal, Scene};
use std::f32::consts::FRAC_1_PI;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

/// Paths in flight at once.
const N: usize = 8;

/// A triangle light as light sampling reads it.
#[derive(Clone, Copy, Debug)]
pub struct TriangleLight {
    vertices: [Vec3; 3],
    normal_area: (Vec3, f32),
    radiance: Vec3,
    two_sided: bool,
}

/// The scene's lights, when every one is a triangle without an emission
/// image (`None` otherwise).
pub fn triangle_lights(scene: &Scene) -> Option<Vec<TriangleLight>> {
    scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Triangle {
                vertices,
                radiance,
                two_sided,
                image: None,
            } => Some(TriangleLight {
                vertices: *vertices,
                normal_area: triangle_normal_area(vertices),
                radiance: *radiance,
                two_sided: *two_sided,
            }),
            _ => None,
        })
        .collect()
}

/// A tile's camera samples, pixel after pixel, row after row (a struct
/// rather than a closure, so that it is compiled into each copy of the
/// lanes with their instruction sets).
struct Feed {
    xs: Range<u32>,
    ys: Range<u32>,
    samples: Range<u32>,
    /// The pixel after the current one.
    x: u32,
    y: u32,
    pixel: Option<PixelSamples>,
    /// The current pixel's next sample.
    s: u32,
    /// Whether a cancel stopped it at the start of a row.
    cancelled: bool,
}

impl Feed {
    fn new(tile: &Tile) -> Self {
        Feed {
            xs: tile.xs.clone(),
            ys: tile.ys.clone(),
            samples: tile.samples.clone(),
            x: tile.xs.start,
            y: tile.ys.start,
            pixel: None,
            s: tile.samples.end,
            cancelled: false,
        }
    }

    #[inline(always)]
    fn next(&mut self, scene: &Scene, settings: &RenderSettings, cancel: &AtomicBool) -> Option<CameraSample> {
        loop {
            if let Some(p) = &self.pixel {
                if self.s < self.samples.end {
                    self.s += 1;
                    return Some(p.sample(scene, settings, self.s - 1));
                }
            }
            if self.cancelled || self.xs.is_empty() || self.y >= self.ys.end {
                self.pixel = None;
                return None;
            }
            if self.x == self.xs.start && cancel.load(Ordering::Relaxed) {
                self.cancelled = true;
                self.pixel = None;
                return None;
            }
            self.pixel = Some(PixelSamples::new(scene, settings, self.x, self.y));
            self.s = self.samples.start;
            self.x += 1;
            if self.x == self.xs.end {
                (self.x, self.y) = (self.xs.start, self.y + 1);
            }
        }
    }
}

/// Three coordinates of every lane.
#[derive(Clone, Copy, Default)]
struct V3s {
    x: [f32; N],
    y: [f32; N],
    z: [f32; N],
}

impl V3s {
    #[inline(always)]
    fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    #[inline(always)]
    fn set(&mut self, i: usize, v: Vec3) {
        (self.x[i], self.y[i], self.z[i]) = (v.x, v.y, v.z);
    }
}

/// The lanes' paths: what each carries from bounce to bounce.
struct Paths {
    /// The camera sample a lane traces, `None` when the lane is idle.
    sample: [Option<CameraSample>; N],
    o: V3s,
    d: V3s,
    beta: V3s,
    l: V3s,
    depth: [u32; N],
    /// Where the last bounce left from and its density (`None` for a camera
    /// ray), for the MIS weight of emission a bounce finds.
    from: [Option<(LightContext, f32)>; N],
}

/// A bounce's hit, lane by lane.
#[derive(Default)]
struct Hits {
    /// Lanes whose path goes on from this hit.
    live: [bool; N],
    // The triangle: corner, edges, normal, vertex normals, where it was hit.
    v0: V3s,
    e1: V3s,
    e2: V3s,
    ng: V3s,
    smooth: [bool; N],
    n0: V3s,
    n1: V3s,
    n2: V3s,
    u: [f32; N],
    v: [f32; N],
    /// The reflectance's value r / pi.
    f: V3s,
    /// The sample numbers: the light sample's 2D, then the BSDF's.
    u_light: [Vec2; N],
    u_bsdf: [Vec2; N],
}

/// Where a bounce's hit leads, lane by lane: the point, the shading frame,
/// the BSDF sample and the light sample.
#[derive(Default)]
struct Bounce {
    p: V3s,
    wo: V3s,
    fx: V3s,
    fy: V3s,
    fz: V3s,
    wo_l: V3s,
    /// The BSDF sample: direction (shading frame), density, whether valid.
    wi_l: V3s,
    pdf: [f32; N],
    sampled: [bool; N],
    /// The light chosen, the probability of the choice and the 2D sample
    /// for the point on it.
    light: [u32; N],
    pmf: [f32; N],
    u_point: [Vec2; N],
    chosen: [bool; N],
    /// The light sample's radiance reflected towards the viewer if nothing
    /// blocks it, and its shadow ray (origin, direction, length), for lanes
    /// with `shadow` set.
    direct: V3s,
    so: V3s,
    sd: V3s,
    st: [f32; N],
    shadow: [bool; N],
}

impl Paths {
    fn new() -> Self {
        Paths {
            sample: Default::default(),
            o: V3s::default(),
            d: V3s::default(),
            beta: V3s::default(),
            l: V3s::default(),
            depth: [0; N],
            from: [None; N],
        }
    }

    fn start(&mut self, i: usize, cs: CameraSample) {
        self.o.set(i, cs.ray.o);
        self.d.set(i, cs.ray.d);
        self.beta.set(i, Vec3::ONE);
        self.l.set(i, Vec3::ZERO);
        self.depth[i] = 0;
        self.from[i] = None;
        self.sample[i] = Some(cs);
    }

    #[inline(always)]
    fn ray(&self, i: usize, time: f32) -> Ray {
        Ray::timed(self.o.get(i), self.d.get(i), time)
    }

    #[inline(always)]
    fn add(&mut self, i: usize, l: Vec3) {
        self.l.set(i, self.l.get(i) + l);
    }

    /// Ends lane `i`'s path: its sample is splatted and the lane is idle.
    fn finish(&mut self, i: usize, settings: &RenderSettings, block: &mut SplatBlock) {
        if let Some(cs) = self.sample[i].take() {
            cs.splat(settings, self.l.get(i), block);
        }
    }
}

/// A render's paths in lanes: the plain loop's materials and depth, the
/// scene's triangle lights.
pub struct Job<'a> {
    pub plain: &'a PlainPathTracer,
    pub lights: &'a [TriangleLight],
    pub scene: &'a Scene,
    pub settings: &'a RenderSettings,
}

impl Job<'_> {
    /// Traces the tile's samples (each pixel's as [`PixelSamples`] makes
    /// them) through plain paths in lanes and splats them into `block`;
    /// false when `cancel` stopped it before the last row (the paths in
    /// flight are finished first).
    pub fn add_tile_samples(
        &self,
        tile: &Tile,
        block: &mut SplatBlock,
        stats: &mut RayStats,
        cancel: &AtomicBool,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            if std::arch::is_x86_feature_detected!("gfni") {
                // SAFETY: the CPU has AVX2 and GFNI.
                return unsafe { self.rows_gfni(tile, block, stats, cancel) };
            }
            // SAFETY: the CPU has AVX2.
            return unsafe { self.rows_avx2(tile, block, stats, cancel) };
        }
        self.rows(tile, block, stats, cancel)
    }

    /// With GFNI a bit reversal, of which each Sobol request makes two, is
    /// one instruction.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,gfni")]
    fn rows_gfni(&self, tile: &Tile, block: &mut SplatBlock, stats: &mut RayStats, cancel: &AtomicBool) -> bool {
        self.rows(tile, block, stats, cancel)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn rows_avx2(&self, tile: &Tile, block: &mut SplatBlock, stats: &mut RayStats, cancel: &AtomicBool) -> bool {
        self.rows(tile, block, stats, cancel)
    }

    #[inline(always)]
    fn rows(&self, tile: &Tile, block: &mut SplatBlock, stats: &mut RayStats, cancel: &AtomicBool) -> bool {
        let (scene, settings) = (self.scene, self.settings);
        let (reflectance, max_depth, lights) = (self.plain.reflectance(), self.plain.max_depth(), self.lights);
        // The lanes run through the whole tile: refilled row by row, they
        // would run part empty at the end of every row.
        let mut feed = Feed::new(tile);
        let mut paths = Paths::new();
        loop {
            for i in 0..N {
                while paths.sample[i].is_none() {
                    let Some(cs) = feed.next(scene, settings, cancel) else {
                        break;
                    };
                    stats.camera_rays += 1;
                    if cs.weight > 0.0 {
                        paths.start(i, cs);
                    } else {
                        // A ray the lens blocks is a sample of black.
                        cs.splat(settings, Vec3::ZERO, block);
                    }
                }
            }
            if paths.sample.iter().all(Option::is_none) {
                return !feed.cancelled;
            }
            let hits = find_hits(reflectance, max_depth, scene, settings, &mut paths, block);
            let mut b = Bounce::default();
            shade(&hits, &paths, &mut b);
            choose_lights(scene, &hits, &mut b);
            sample_lights(scene, lights, &hits, &mut b);
            for i in 0..N {
                if b.shadow[i] {
                    stats.shadow_rays += 1;
                    let ray = Ray::timed(b.so.get(i), b.sd.get(i), time_of(&paths, i));
                    let blocked = if b.st[i].is_finite() {
                        scene.occluded_before_light(&ray, 0.0, b.st[i], b.light[i])
                    } else {
                        scene.occluded(&ray, 0.0, f32::INFINITY)
                    };
                    if !blocked {
                        paths.add(i, paths.beta.get(i) * b.direct.get(i));
                    }
                }
            }
            let go_on = continue_paths(&hits, &mut paths, &b);
            for i in 0..N {
                if !hits.live[i] {
                    continue;
                }
                if !go_on[i] {
                    paths.finish(i, settings, block);
                    continue;
                }
                let wi = paths.d.get(i);
                if paths.depth[i] >= ROULETTE_DEPTH {
                    let beta = paths.beta.get(i);
                    let q = beta.max_element().min(MAX_SURVIVAL);
                    let Some(cs) = paths.sample[i].as_mut() else {
                        continue;
                    };
                    if cs.sampler.next_f32() >= q {
                        paths.finish(i, settings, block);
                        continue;
                    }
                    paths.beta.set(i, beta / q);
                }
                stats.other_rays += 1;
                paths.o.set(i, offset_origin(b.p.get(i), hits.ng.get(i), wi));
            }
        }
    }
}

/// The time of lane `i`'s rays: its camera ray's.
#[inline(always)]
fn time_of(paths: &Paths, i: usize) -> f32 {
    paths.sample[i].as_ref().map_or(0.0, |cs| cs.ray.time)
}

/// Traces each lane's ray, adds what it finds emitted, ends the paths that
/// end there, and gathers the rest's hits and sample numbers.
#[inline(always)]
fn find_hits(
    reflectance: &[Vec3],
    max_depth: Option<u32>,
    scene: &Scene,
    settings: &RenderSettings,
    paths: &mut Paths,
    block: &mut SplatBlock,
) -> Hits {
    let mut hits = Hits::default();
    for i in 0..N {
        if paths.sample[i].is_none() {
            continue;
        }
        let ray = paths.ray(i, time_of(paths, i));
        let beta = paths.beta.get(i);
        let Some((slot, h)) = scene.intersect_triangle(&ray) else {
            paths.add(i, beta * escaped_radiance(scene, &ray, paths.from[i]));
            paths.finish(i, settings, block);
            continue;
        };
        let g = scene.triangle_geometry(slot);
        if let Some(li) = g.light {
            let hit = scene.bare_hit(slot, &h, &ray);
            paths.add(
                i,
                beta * emitted_radiance(scene, li as usize, &ray, &hit, paths.from[i]),
            );
            if !scene.reflects(&hit) {
                paths.finish(i, settings, block);
                continue;
            }
        }
        if max_depth.is_some_and(|d| paths.depth[i] >= d) {
            paths.finish(i, settings, block);
            continue;
        }
        paths.depth[i] += 1;
        let r = reflectance[g.material as usize];
        if r == Vec3::ZERO {
            paths.finish(i, settings, block);
            continue;
        }
        let Some(cs) = paths.sample[i].as_mut() else {
            continue;
        };
        hits.u_light[i] = cs.sampler.next_2d();
        cs.sampler.skip_1d();
        hits.u_bsdf[i] = cs.sampler.next_2d();
        hits.live[i] = true;
        hits.v0.set(i, g.triangle.v0);
        hits.e1.set(i, g.triangle.e1);
        hits.e2.set(i, g.triangle.e2);
        hits.ng.set(i, g.ng);
        if let Some([n0, n1, n2]) = g.normals {
            hits.smooth[i] = true;
            hits.n0.set(i, n0);
            hits.n1.set(i, n1);
            hits.n2.set(i, n2);
        }
        hits.u[i] = h.u;
        hits.v[i] = h.v;
        hits.f.set(i, r * FRAC_1_PI);
    }
    hits
}

/// The hit point, the shading frame and the BSDF sample of every lane.
#[inline(always)]
fn shade(h: &Hits, paths: &Paths, b: &mut Bounce) {
    for i in 0..N {
        let (u, v) = (h.u[i], h.v[i]);
        b.p.set(i, h.v0.get(i) + h.e1.get(i) * u + h.e2.get(i) * v);
        let ng = h.ng.get(i);
        let ns = if h.smooth[i] {
            interpolated_normal([h.n0.get(i), h.n1.get(i), h.n2.get(i)], ng, u, v)
        } else {
            ng
        };
        let wo = -paths.d.get(i);
        let ns = if ng.dot(wo) < 0.0 { -ns } else { ns };
        let frame = Frame::from_z(ns);
        let wo_l = frame.to_local(wo);
        let d = cosine_hemisphere(h.u_bsdf[i]);
        let wi = if wo_l.z >= 0.0 { d } else { Vec3::new(d.x, d.y, -d.z) };
        let pdf = wi.z.abs() * FRAC_1_PI;
        b.sampled[i] = wo_l.z != 0.0 && pdf > 0.0 && pdf.is_finite() && wi.z != 0.0 && h.f.get(i) != Vec3::ZERO;
        b.wi_l.set(i, wi);
        b.pdf[i] = pdf;
        b.wo.set(i, wo);
        b.wo_l.set(i, wo_l);
        b.fx.set(i, frame.x);
        b.fy.set(i, frame.y);
        b.fz.set(i, frame.z);
    }
}

/// Each lane's light, chosen by power.
#[inline(always)]
fn choose_lights(scene: &Scene, h: &Hits, b: &mut Bounce) {
    for i in 0..N {
        if !h.live[i] {
            continue;
        }
        if let Some((li, pmf, rest)) = scene.pick_light(h.u_light[i].x) {
            b.light[i] = li as u32;
            b.pmf[i] = pmf;
            b.u_point[i] = Vec2::new(rest, h.u_light[i].y);
            b.chosen[i] = true;
        }
    }
}

/// Each lane's light sample, weighed against BSDF sampling by the power
/// heuristic, and its shadow ray: the arithmetic of `triangle_point_seen`,
/// `lambert_light` and `shadow_ray`, operation for operation, each step a
/// loop over the lanes without branches (each case a select), so that the
/// compiler makes each step a handful of vector instructions. Lanes without
/// a light sample compute on stand-in numbers and are dropped at the end.
#[inline(always)]
fn sample_lights(scene: &Scene, lights: &[TriangleLight], h: &Hits, b: &mut Bounce) {
    // The chosen lights, lane by lane.
    let (mut v0, mut v1, mut v2, mut n, mut radiance) = (
        V3s::default(),
        V3s::default(),
        V3s::default(),
        V3s::default(),
        V3s::default(),
    );
    let (mut area, mut two_sided, mut met, mut ok) = ([0.0f32; N], [false; N], [false; N], [false; N]);
    for i in 0..N {
        if !b.chosen[i] {
            continue;
        }
        let li = b.light[i] as usize;
        let Some(light) = lights.get(li) else {
            continue;
        };
        v0.set(i, light.vertices[0]);
        v1.set(i, light.vertices[1]);
        v2.set(i, light.vertices[2]);
        n.set(i, light.normal_area.0);
        area[i] = light.normal_area.1;
        radiance.set(i, light.radiance);
        two_sided[i] = light.two_sided;
        met[i] = scene.light_is_met(li);
        ok[i] = true;
    }
    // `uniform_triangle`: the point, from its barycentrics.
    let (mut q, mut d, mut wi, mut weight) = (V3s::default(), V3s::default(), V3s::default(), V3s::default());
    let (mut d2, mut dist, mut pdf) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for i in 0..N {
        let u = b.u_point[i];
        let lower = u.x < u.y;
        let half = if lower { u.x } else { u.y } / 2.0;
        let rest = if lower { u.y } else { u.x } - half;
        let (b0, b1) = if lower { (half, rest) } else { (rest, half) };
        let b2 = 1.0 - b0 - b1;
        q.x[i] = v0.x[i] * b0 + v1.x[i] * b1 + v2.x[i] * b2;
        q.y[i] = v0.y[i] * b0 + v1.y[i] * b1 + v2.y[i] * b2;
        q.z[i] = v0.z[i] * b0 + v1.z[i] * b1 + v2.z[i] * b2;
    }
    // `triangle_point_seen`: direction, distance, cosine at the light.
    for i in 0..N {
        d.x[i] = q.x[i] - b.p.x[i];
        d.y[i] = q.y[i] - b.p.y[i];
        d.z[i] = q.z[i] - b.p.z[i];
        d2[i] = d.x[i] * d.x[i] + d.y[i] * d.y[i] + d.z[i] * d.z[i];
        dist[i] = d2[i].sqrt();
        wi.x[i] = d.x[i] / dist[i];
        wi.y[i] = d.y[i] / dist[i];
        wi.z[i] = d.z[i] / dist[i];
    }
    for i in 0..N {
        let cos_l = -(n.x[i] * wi.x[i] + n.y[i] * wi.y[i] + n.z[i] * wi.z[i]);
        let cos_l = if two_sided[i] { cos_l.abs() } else { cos_l };
        // A NaN passes, as it passes the scalar test (`cos_l <= 0` rejects).
        ok[i] &= d2[i] != 0.0 && area[i] != 0.0 && (cos_l > 0.0 || cos_l.is_nan());
        let to_solid_angle = cos_l * area[i] / d2[i];
        pdf[i] = d2[i] / (cos_l * area[i]);
        weight.x[i] = radiance.x[i] * to_solid_angle;
        weight.y[i] = radiance.y[i] * to_solid_angle;
        weight.z[i] = radiance.z[i] * to_solid_angle;
    }
    // `lambert_light`: the same side of both normals as the viewer, the
    // BSDF's value and density, the power heuristic.
    for i in 0..N {
        let (wi, ng, wo, z) = (wi.get(i), h.ng.get(i), b.wo.get(i), b.fz.get(i));
        let (wi_ng, wi_z) = (wi.dot(ng), wi.dot(z));
        let geo_same = (wi_ng > 0.0) == (wo.dot(ng) > 0.0);
        let shade_same = (wi_z > 0.0) == (wo.dot(z) > 0.0);
        ok[i] &= geo_same && shade_same && wi_ng != 0.0;
        // Zero below the surface, and where wo lies in it (wo_l.z = 0).
        let above = b.wo_l.z[i] * wi_z > 0.0;
        let f = if above { h.f.get(i) } else { Vec3::ZERO };
        let pdf_bsdf = if above { wi_z.abs() * FRAC_1_PI } else { 0.0 };
        let a = b.pmf[i] * pdf[i];
        let (a2, b2) = (a * a, pdf_bsdf * pdf_bsdf);
        let heuristic = if a2 + b2 > 0.0 && (a2 + b2).is_finite() {
            a2 / (a2 + b2)
        } else if a.is_infinite() {
            1.0
        } else {
            0.0
        };
        let w = if met[i] { heuristic } else { 1.0 };
        b.direct.set(i, f * wi_z.abs() * weight.get(i) * (w / b.pmf[i]));
    }
    // `shadow_ray`: from the offset origin to the sampled point.
    for i in 0..N {
        let (p, ng, wi) = (b.p.get(i), h.ng.get(i), wi.get(i));
        let eps = 1e-5 * (1.0 + p.abs().max_element());
        let o = if ng.dot(wi) >= 0.0 { p + ng * eps } else { p - ng * eps };
        let to_light = p + wi * dist[i] - o;
        let len = to_light.length();
        let finite = dist[i].is_finite();
        b.so.set(i, o);
        b.sd.set(i, if finite { to_light / len } else { wi });
        b.st[i] = if finite { len * (1.0 - 1e-4) } else { f32::INFINITY };
        b.shadow[i] = ok[i];
    }
}

/// The throughput after each lane's BSDF sample, and its next direction;
/// whether the path goes on. Without branches, as `sample_lights`: a lane
/// whose path ends here is finished next and an idle lane is started
/// afresh, so what is written for them is never read.
#[inline(always)]
fn continue_paths(h: &Hits, paths: &mut Paths, b: &Bounce) -> [bool; N] {
    let mut go_on = [false; N];
    let mut wi = V3s::default();
    for i in 0..N {
        let frame = Frame {
            x: b.fx.get(i),
            y: b.fy.get(i),
            z: b.fz.get(i),
        };
        wi.set(i, frame.to_world(b.wi_l.get(i)));
    }
    for i in 0..N {
        let (w, ng, wo, z) = (wi.get(i), h.ng.get(i), b.wo.get(i), b.fz.get(i));
        let same_side = (w.dot(ng) > 0.0) == (wo.dot(ng) > 0.0);
        let beta = paths.beta.get(i) * (h.f.get(i) * (w.dot(z).abs() / b.pdf[i]));
        paths.beta.set(i, beta);
        go_on[i] = h.live[i] & b.sampled[i] & same_side & beta.is_finite() & (beta.max_element() > 0.0);
        paths.from[i] = Some((LightContext::surface(b.p.get(i), z), b.pdf[i]));
        paths.d.set(i, w);
    }
    go_on
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Film;
    use crate::integrator::analytic::{pbrt_desc, pbrt_quad};
    use crate::integrator::path::PathTracer;
    use crate::integrator::{render_tiles, IntegratorKind, LightSampling, Progress, SamplerKind};
    use crate::light::LightSamplerKind;
    use crate::scene::SceneDesc;

    /// A box of Lambertian quads, some with vertex normals, lit by a
    /// one-sided quad and a two-sided triangle, with a tall block inside.
    fn boxed_room() -> SceneDesc {
        boxed_room_with("")
    }

    /// `boxed_room`, with `extra` added to its world.
    fn boxed_room_with(extra: &str) -> SceneDesc {
        let quad = pbrt_quad;
        let mut text = String::from(
            "LookAt 0 1 3.5  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" 50\n\
             Film \"rgb\" \"integer xresolution\" 21 \"integer yresolution\" 17\nWorldBegin\n\
             Material \"diffuse\" \"rgb reflectance\" [ 0.7 0.6 0.5 ]\n",
        );
        text += &quad("-1 0 -1  1 0 -1  1 0 1  -1 0 1", Some("0 1 0.1"));
        text += &quad("-1 2 -1  -1 2 1  1 2 1  1 2 -1", None);
        text += &quad("-1 0 4  -1 2 4  1 2 4  1 0 4", None);
        text += "Material \"diffuse\" \"rgb reflectance\" [ 0.2 0.5 0.1 ]\n";
        text += &quad("-1 0 -1  -1 2 -1  1 2 -1  1 0 -1", Some("0.1 0 1"));
        text += &quad("-1 0 -1  -1 0 4  -1 2 4  -1 2 -1", Some("1 0.2 0"));
        text += &quad("1 0 -1  1 2 -1  1 2 4  1 0 4", None);
        text += &quad("-0.2 0 -0.3  -0.2 1.2 -0.3  0.3 1.2 -0.5  0.3 0 -0.5", None);
        text += "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 4 3 2 ]\nMaterial \"diffuse\" \"rgb reflectance\" [ 0 0 0 ]\n";
        text += &quad(
            "-0.3 1.99 -0.3  -0.3 1.99 0.3  0.3 1.99 0.3  0.3 1.99 -0.3",
            Some("0 -1 0"),
        );
        text +=
            "AttributeEnd\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 1 2 3 ] \"bool twosided\" true\n";
        text += "Shape \"trianglemesh\" \"point3 P\" [ 0.9 0.2 -0.5  0.9 0.8 -0.5  0.9 0.5 0.3 ] \"integer indices\" [ 0 1 2 ]\n";
        text += "AttributeEnd\n";
        text += extra;
        let mut desc = pbrt_desc(&text);
        desc.light_sampler = LightSamplerKind::Power;
        desc
    }

    fn render(scene: &Scene, settings: &RenderSettings, est: &dyn crate::integrator::RadianceEstimator) -> Film {
        render_tiles(scene, settings, est, Progress::silent()).0
    }

    #[test]
    fn paths_in_lanes_give_the_one_path_loops_image_bit_for_bit() {
        let scene = Scene::build(boxed_room()).unwrap();
        for (sampler, max_depth, spp) in [
            (SamplerKind::Sobol, None, 16),
            (SamplerKind::ZSobol, Some(3), 8),
            (SamplerKind::Independent, None, 9),
        ] {
            let settings = RenderSettings {
                integrator: IntegratorKind::Path,
                spp,
                max_depth,
                sampler,
                ..RenderSettings::default()
            };
            let lanes = PlainPathTracer::for_scene(&scene, &settings).expect("a plain scene");
            assert!(lanes.in_lanes());
            let general = PathTracer {
                max_depth,
                light_sampling: LightSampling::Mis,
                regularize: false,
                guide: None,
            };
            let (a, b) = (render(&scene, &settings, &general), render(&scene, &settings, &lanes));
            let one = render(&scene, &settings, &lanes.one_at_a_time());
            for (other, what) in [(&a, "the general loop"), (&one, "one path at a time")] {
                let differ = (b.pixels.iter().zip(&other.pixels))
                    .position(|(x, y)| x.to_array().map(f32::to_bits) != y.to_array().map(f32::to_bits));
                assert_eq!(
                    differ, None,
                    "{sampler:?}, {max_depth:?}: lanes against {what}, first pixel that differs"
                );
            }
            let lit = b.pixels.iter().filter(|p| p.max_element() > 0.0).count();
            assert!(lit > b.pixels.len() * 9 / 10, "{sampler:?}: {lit} pixels lit");
        }
    }

    #[test]
    fn every_build_of_the_lanes_sums_what_the_baseline_sums() {
        let scene = Scene::build(boxed_room()).unwrap();
        let settings = RenderSettings {
            integrator: IntegratorKind::Path,
            spp: 4,
            ..RenderSettings::default()
        };
        let plain = PlainPathTracer::for_scene(&scene, &settings).expect("a plain scene");
        let lights = triangle_lights(&scene).expect("triangle lights");
        let job = Job {
            plain: &plain,
            lights: &lights,
            scene: &scene,
            settings: &settings,
        };
        let rect = crate::film::PixelRect::full(scene.camera.width, scene.camera.height);
        let (mut a, mut b) = (
            SplatBlock::new(rect, settings.filter),
            SplatBlock::new(rect, settings.filter),
        );
        let mut sa = RayStats::default();
        let never = AtomicBool::new(false);
        // Tiles of 5 rows, the last one shorter, so that the lanes run on
        // from row to row.
        let tiles = (0..scene.camera.height).step_by(5).map(|y| Tile {
            xs: 0..scene.camera.width,
            ys: y..(y + 5).min(scene.camera.height),
            samples: 0..4,
        });
        for tile in tiles.clone() {
            assert!(job.rows(&tile, &mut a, &mut sa, &never));
        }
        assert!(sa.shadow_rays > 0 && sa.other_rays > 0);
        // The copy this CPU takes, then each copy it can run.
        type Copy = fn(&Job, &Tile, &mut SplatBlock, &mut RayStats, &AtomicBool) -> bool;
        let mut copies: Vec<(&str, Copy)> = vec![("chosen", |j, t, b, s, c| j.add_tile_samples(t, b, s, c))];
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2.
                copies.push(("avx2", |j, t, b, s, c| unsafe { j.rows_avx2(t, b, s, c) }));
            }
            if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("gfni") {
                // SAFETY: the CPU has AVX2 and GFNI.
                copies.push(("gfni", |j, t, b, s, c| unsafe { j.rows_gfni(t, b, s, c) }));
            }
        }
        for (name, copy) in copies {
            b.sums.fill(Default::default());
            let mut sb = RayStats::default();
            for tile in tiles.clone() {
                assert!(copy(&job, &tile, &mut b, &mut sb, &never));
            }
            assert!(a.sums == b.sums, "{name}: the pixel sums differ from the baseline's");
            assert_eq!(sa, sb, "{name}");
        }
        // A cancelled tile says so, having traced nothing.
        let cancelled = AtomicBool::new(true);
        let mut s = RayStats::default();
        let tile = tiles.clone().next().expect("a tile");
        assert!(!job.add_tile_samples(&tile, &mut b, &mut s, &cancelled));
        assert_eq!(s.camera_rays, 0);
    }

    #[test]
    fn only_triangles_lit_by_triangles_go_in_lanes() {
        let path = RenderSettings {
            integrator: IntegratorKind::Path,
            ..RenderSettings::default()
        };
        let lanes = |desc: SceneDesc| {
            PlainPathTracer::for_scene(&Scene::build(desc).unwrap(), &path).is_some_and(|p| p.in_lanes())
        };
        assert!(lanes(boxed_room()));
        assert!(!lanes(boxed_room_with(
            "LightSource \"point\" \"point3 from\" [ 0 1.5 0 ]\n"
        )));
        assert!(!lanes(boxed_room_with("Shape \"sphere\" \"float radius\" 0.2\n")));
        let mut with_ball = crate::scene::builtin::cornell();
        with_ball.light_sampler = LightSamplerKind::Power;
        assert!(!lanes(with_ball));
    }
}
