//! Bidirectional path tracer: pbrt-v4's `BDPTIntegrator` (Veach 1997,
//! chapter 10; pbrt-v3 16.3).
//!
//! Each sample traces a camera subpath and a light subpath (a light chosen
//! in proportion to its power, a particle emitted from it), then joins every
//! prefix of one to every prefix of the other: s light vertices and t camera
//! vertices make one path of s + t - 2 bounces, weighted against every other
//! (s, t) that could have made the same path by the power heuristic over the
//! densities of its vertices, each in area measure ("MISWeight"). s = 0 is a
//! camera path that found a light, s = 1 is next-event estimation (a fresh
//! light sample at the camera vertex), t = 1 is light tracing (a light
//! subpath's vertex joined to the pinhole, its light landing on whichever
//! pixel sees it). Paths the path tracer finds only rarely, such as diffuse
//! -> glossy -> small light (the fireflies of `veach-mis`), are found easily
//! from the light's side.
//!
//! Departures from pbrt-v4, each keeping the estimate unbiased:
//! - light tracing has light subpaths of its own, one per pixel and sample
//!   of the whole frame ([`trace_light_pass`]), rather than each camera
//!   sample's: a crop or tile then gets the light the whole frame's
//!   particles bring it, and is the frame's own bit for bit;
//! - t = 1 only for a pinhole camera (`Camera::is_pinhole`); with a lens, an
//!   orthographic or a spherical camera the weights leave it out;
//! - Russian roulette on each subpath from the path tracer's depth on, so
//!   that the file's unlimited depths end (the weights use the densities
//!   without it: every (s, t) keeps the same weights, which still sum to 1);
//! - the path tracer's rule for shading normals: a connection is made only
//!   where both normals at each end let light through that way.
//!
//! Infinite and distant lights take part as in pbrt-v4: a particle from
//! one starts on a disk across the scene's bounding sphere, its first
//! vertex at infinity, and a camera subpath that leaves the scene ends on a
//! vertex at infinity standing for every infinite light (`Kind::Infinity`);
//! so a distant light's caustics, which no camera subpath reaches, are
//! found by light tracing.
//!
//! Emissive materials that are not lights count where a camera subpath
//! finds them (no other strategy samples them), as in the path tracer.
//! Scenes with participating media or a portal light are refused (`check_scene`).

use super::direct::{scatters_towards, unoccluded_light_sample};
use super::path::{MAX_SURVIVAL, ROULETTE_DEPTH};
use super::{RadianceEstimator, RayStats};
use crate::bsdf::{Bsdf, BsdfSample, TransportMode};
use crate::camera::Differentials;
use crate::film::{Filter, PixelRect, PixelSum};
use crate::light::{triangle_normal, Emits, Light};
use crate::math::{offset_origin, Ray, Vec2, Vec3};
use crate::sampling::Sampler;
use crate::scene::{Hit, Scene};

pub struct Bdpt {
    /// Most bounces (s + t - 2); `None`: roulette ends paths.
    pub max_depth: Option<u32>,
    /// Whether light subpaths are also joined to the camera (t = 1): a
    /// pinhole camera's.
    pub light_tracing: bool,
    /// Microfacet surfaces made glossy after a subpath's first
    /// non-specular bounce (pbrt-v4's `regularize`, as its BDPT has it).
    pub regularize: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Camera,
    Surface,
    /// A point on light `i`: a light subpath's first vertex, a light sample,
    /// or where a camera subpath hit an emitter.
    Light(usize),
    /// Light at infinity (pbrt's infinite-light vertices): a light subpath
    /// leaving infinite or distant light `Some(i)`, a light sample of one,
    /// or, `None`, where a camera subpath left the scene (every infinite
    /// light at once). Its `wo` is the direction towards the light; its
    /// position, far along it, serves only to give directions.
    Infinity(Option<usize>),
}

#[derive(Clone, Copy, Debug)]
struct Vertex {
    kind: Kind,
    p: Vec3,
    /// Unit geometric normal (for a light endpoint, the emitting side's);
    /// zero where there is no surface (cameras, point and spot lights).
    ng: Vec3,
    /// The hit and its BSDF, for surface vertices.
    hit: Option<Hit>,
    bsdf: Option<Bsdf>,
    /// Unit direction towards the vertex before on its own subpath.
    wo: Vec3,
    /// Throughput of the subpath arriving here (pbrt's `beta`).
    beta: Vec3,
    /// Area densities of sampling this vertex from the one before (forward)
    /// and from the one after (reverse), on its subpath.
    pdf_fwd: f32,
    pdf_rev: f32,
    /// Scattered by a specular lobe: no connection can end here.
    delta: bool,
    mode: TransportMode,
    /// The time of the shutter the vertex is at (its subpath's): the
    /// camera's, where the camera moves.
    time: f32,
    /// Texture coordinates where a camera subpath met a light or a surface:
    /// where an emission image is read.
    uv: Vec2,
}

impl Vertex {
    fn endpoint(kind: Kind, p: Vec3, ng: Vec3, mode: TransportMode) -> Vertex {
        Vertex {
            kind,
            p,
            ng,
            hit: None,
            bsdf: None,
            wo: Vec3::ZERO,
            beta: Vec3::ONE,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta: false,
            mode,
            time: 0.0,
            uv: Vec2::ZERO,
        }
    }

    /// The camera's vertex at `p` (where it is at `time`).
    fn camera(p: Vec3, time: f32) -> Vertex {
        Vertex {
            time,
            ..Vertex::endpoint(Kind::Camera, p, Vec3::ZERO, TransportMode::Radiance)
        }
    }

    fn surface(hit: Hit, bsdf: Bsdf, wo: Vec3, beta: Vec3, mode: TransportMode) -> Vertex {
        Vertex {
            kind: Kind::Surface,
            p: hit.p,
            ng: hit.ng,
            time: hit.time,
            hit: Some(hit),
            bsdf: Some(bsdf),
            wo,
            beta,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta: false,
            mode,
            uv: hit.uv,
        }
    }

    /// The light this vertex emits by: a light endpoint's, or that of an
    /// emitter a subpath went on from because it reflects.
    fn emitter(&self) -> Option<usize> {
        match self.kind {
            Kind::Light(li) => Some(li),
            Kind::Surface => self.hit.and_then(|h| h.light).map(|li| li as usize),
            _ => None,
        }
    }

    fn is_on_surface(&self) -> bool {
        self.ng != Vec3::ZERO
    }

    fn is_at_infinity(&self) -> bool {
        matches!(self.kind, Kind::Infinity(_))
    }

    /// A surface vertex whose BSDF has a lobe a connection can use.
    fn is_connectible(&self) -> bool {
        self.kind == Kind::Surface && self.bsdf.is_some_and(|b| b.flags().is_non_specular())
    }

    /// A solid-angle density at this vertex towards `next`, in area measure
    /// there (pbrt's `ConvertDensity`). A vertex at infinity keeps the
    /// solid-angle density: its "area" is the sphere of directions. From a
    /// vertex at infinity, `pdf` is an area density across the direction of
    /// travel (the disk a particle starts on), projected onto `next`.
    fn convert_density(&self, pdf: f32, next: &Vertex) -> f32 {
        if next.is_at_infinity() {
            return pdf;
        }
        if self.is_at_infinity() {
            return if next.is_on_surface() {
                pdf * next.ng.dot(self.wo).abs()
            } else {
                pdf
            };
        }
        let w = next.p - self.p;
        let d2 = w.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let mut pdf = pdf / d2;
        if next.is_on_surface() {
            pdf *= next.ng.dot(w / d2.sqrt()).abs();
        }
        pdf
    }

    /// The BSDF at a surface vertex for light between `wo` and the unit
    /// direction `wi`, with the adjoint's shading-normal factor for
    /// importance (Veach 1997, 5.3); zero where the path tracer's rule for
    /// shading normals forbids the scattering.
    fn f(&self, wi: Vec3) -> Vec3 {
        let (Some(hit), Some(bsdf)) = (&self.hit, &self.bsdf) else {
            return Vec3::ZERO;
        };
        if !scatters_towards(hit, self.wo, bsdf, wi) {
            return Vec3::ZERO;
        }
        let f = bsdf.f(self.wo, wi, self.mode);
        if self.mode == TransportMode::Importance {
            f * shading_correction(hit, bsdf, self.wo, wi)
        } else {
            f
        }
    }

    /// The area density at `next` of sampling it from this vertex, reached
    /// from `prev` (pbrt's `Vertex::PDF`): the BSDF's for surfaces, the
    /// emission's for lights, the camera rays' for the camera.
    fn pdf(&self, scene: &Scene, prev: Option<&Vertex>, next: &Vertex) -> f32 {
        let Some(wn) = (next.p - self.p).try_normalize() else {
            return 0.0;
        };
        match self.kind {
            Kind::Light(li) => self.pdf_light(scene, li, next),
            Kind::Infinity(_) => self.convert_density(disk_density(scene), next),
            Kind::Camera => self.convert_density(scene.camera.pdf_dir_at(wn, self.time), next),
            Kind::Surface => {
                let (Some(hit), Some(bsdf), Some(prev)) = (&self.hit, &self.bsdf, prev) else {
                    return 0.0;
                };
                let Some(wp) = (prev.p - self.p).try_normalize() else {
                    return 0.0;
                };
                if !scatters_towards(hit, wp, bsdf, wn) {
                    return 0.0;
                }
                self.convert_density(bsdf.pdf(wp, wn, self.mode), next)
            }
        }
    }

    /// The area density at `next` of light `li` emitting towards it from here.
    fn pdf_light(&self, scene: &Scene, li: usize, next: &Vertex) -> f32 {
        let Some(w) = (next.p - self.p).try_normalize() else {
            return 0.0;
        };
        let light = &scene.lights[li];
        // A surface vertex's normal is the hit's, not the emitting side's.
        let n = match self.kind {
            Kind::Surface => light_normal(light, self.p, next.p),
            _ => self.ng,
        };
        let (_, pdf_dir) = light.pdf_le(&Ray::new(self.p, w), n);
        self.convert_density(pdf_dir, next)
    }

    /// The density of a light subpath starting at this vertex, whichever
    /// light it belongs to (pbrt's `PdfLightOrigin`): for a vertex at
    /// infinity the density of its direction over every infinite light
    /// (pbrt's `InfiniteLightDensity`; 0 for distant lights), else that of
    /// the point on its light.
    fn pdf_origin(&self, scene: &Scene) -> f32 {
        match self.kind {
            Kind::Light(_) | Kind::Surface => self.emitter().map_or(0.0, |li| self.pdf_light_origin(scene, li)),
            Kind::Infinity(_) => scene
                .infinite_lights()
                .iter()
                .map(|&i| scene.light_pmf(i as usize) * scene.lights[i as usize].pdf_li_escaped(self.p, self.wo))
                .sum(),
            _ => 0.0,
        }
    }

    /// Whether this is a light vertex whose light no path can end on by
    /// chance: a delta in position or direction, or an invisible area light.
    fn is_delta_light(&self, scene: &Scene) -> bool {
        match self.kind {
            Kind::Light(li) | Kind::Infinity(Some(li)) => !scene.light_is_met(li),
            _ => false,
        }
    }

    /// A vertex at infinity in direction `towards` (unit) from `from`.
    fn at_infinity(light: Option<usize>, scene: &Scene, from: Vec3, towards: Vec3, mode: TransportMode) -> Vertex {
        let far = 2.0 * world_radius(scene) + from.length();
        let mut v = Vertex::endpoint(Kind::Infinity(light), from + towards * far, Vec3::ZERO, mode);
        v.wo = towards;
        v
    }

    /// The area density of choosing light `li` and this point on it as a
    /// light subpath's start: 0 for point and spot lights.
    fn pdf_light_origin(&self, scene: &Scene, li: usize) -> f32 {
        let light = &scene.lights[li];
        if light.is_delta() {
            return 0.0;
        }
        let (pdf_pos, _) = light.pdf_le(&Ray::new(self.p, self.ng), self.ng);
        scene.light_pmf(li) * pdf_pos
    }
}

/// Veach's (1997, 5.3) factor of the adjoint BSDF with shading normals:
/// |wo . ns| |wi . ng| / (|wo . ng| |wi . ns|), as the photon tracer's.
fn shading_correction(hit: &Hit, bsdf: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    let ns = bsdf.frame.z;
    let c = (wo.dot(ns) * wi.dot(hit.ng) / (wo.dot(hit.ng) * wi.dot(ns))).abs();
    if c.is_finite() {
        c
    } else {
        0.0
    }
}

/// The unit normal of light `light`'s surface at `p`, on the side facing
/// `towards` for two-sided lights; zero for lights without a surface.
fn light_normal(light: &Light, p: Vec3, towards: Vec3) -> Vec3 {
    let (n, two_sided) = match light {
        Light::Sphere { sphere, emits, .. } => {
            let n = (p - sphere.centre).normalize_or_zero();
            match emits {
                Emits::Outwards => (n, false),
                Emits::Inwards => (-n, false),
                Emits::Both => (n, true),
            }
        }
        Light::Triangle {
            vertices, two_sided, ..
        } => (triangle_normal(vertices), *two_sided),
        Light::Disk { disk, two_sided, .. } => (disk.normal, *two_sided),
        _ => (Vec3::ZERO, false),
    };
    if two_sided && n.dot(towards - p) < 0.0 {
        -n
    } else {
        n
    }
}

/// Radius of the scene's bounding sphere, as lights at infinity know it.
fn world_radius(scene: &Scene) -> f32 {
    scene
        .lights
        .iter()
        .find_map(|l| match l {
            Light::Infinite { world, .. } | Light::Distant { world, .. } => Some(world.radius),
            _ => None,
        })
        .unwrap_or(0.0)
}

/// The area density of a particle's start on the disk across the scene
/// that lights at infinity emit from (pbrt's planar density).
fn disk_density(scene: &Scene) -> f32 {
    let r = world_radius(scene);
    if r > 0.0 {
        1.0 / (std::f32::consts::PI * r * r)
    } else {
        0.0
    }
}

/// `sum` plus, over the strategies that take vertices `lowest..n` of one
/// subpath from the other side, their densities' squared ratios to this
/// strategy's (pbrt's `MISWeight` loops): walking from the joined end
/// (`at(n - 1)`, whose and whose predecessor's reverse densities the join
/// gives as `revs`) towards the subpath's start. A strategy counts unless
/// it would join at a specular vertex, or at one whose predecessor is
/// (`delta_before(i)`).
fn ratio_sum<'a>(
    mut sum: f32,
    n: usize,
    lowest: usize,
    at: impl Fn(usize) -> &'a Vertex,
    revs: (f32, f32),
    delta_before: impl Fn(usize) -> bool,
) -> f32 {
    let mut ri = 1.0;
    for i in (lowest..n).rev() {
        let v = at(i);
        let rev = if i + 1 == n {
            revs.0
        } else if i + 2 == n {
            revs.1
        } else {
            v.pdf_rev
        };
        let r = remap0(rev) / remap0(v.pdf_fwd);
        ri *= r * r;
        let delta = i + 1 != n && v.delta;
        if !delta && !delta_before(i) {
            sum += ri;
        }
    }
    sum
}

fn remap0(f: f32) -> f32 {
    if f != 0.0 {
        f
    } else {
        1.0
    }
}

impl Bdpt {
    /// Surface vertices a subpath may have beyond its endpoint.
    fn limit(&self, extra: u32) -> usize {
        self.max_depth.map_or(usize::MAX, |d| (d + extra) as usize)
    }

    /// The camera subpath from `ray`: its vertices after the camera's, and
    /// the light it finds on the way that only it can find (emissive
    /// materials, and environment light weighed against light samples).
    fn camera_subpath(
        &self,
        scene: &Scene,
        ray: &Ray,
        sampler: &mut Sampler,
        stats: &mut RayStats,
        path: &mut Vec<Vertex>,
    ) -> Vec3 {
        let mut l = Vec3::ZERO;
        let mut ray = *ray;
        let mut beta = Vec3::ONE;
        let mut roulette = Vec3::ONE;
        let mut rough_before = false;
        let mut pdf_fwd = scene.camera.pdf_dir_at(ray.d, ray.time);
        let mut diffs: Option<Differentials> = None;
        let max_vertices = self.limit(1);
        path.push(Vertex::camera(ray.o, ray.time));
        loop {
            let Some(hit) = scene.intersect(&ray, 0.0, f32::INFINITY) else {
                // Into the environment: a vertex at infinity, weighed as
                // any light vertex is.
                if !scene.infinite_lights().is_empty() {
                    let mut v = Vertex::at_infinity(None, scene, ray.o, ray.d, TransportMode::Radiance);
                    v.beta = beta;
                    v.pdf_fwd = path[path.len() - 1].convert_density(pdf_fwd, &v);
                    path.push(v);
                }
                break;
            };
            if let Some(li) = hit.light.filter(|_| !scene.reflects(&hit)) {
                let light = &scene.lights[li as usize];
                let mut v = Vertex::endpoint(
                    Kind::Light(li as usize),
                    hit.p,
                    light_normal(light, hit.p, ray.o),
                    TransportMode::Radiance,
                );
                v.uv = hit.uv;
                v.beta = beta;
                v.pdf_fwd = path[path.len() - 1].convert_density(pdf_fwd, &v);
                path.push(v);
                break;
            }
            let m = scene.material(hit.material);
            l += beta * m.le();
            let wo = -ray.d;
            if path.len() == 1 {
                diffs = scene.camera_differentials(&hit);
            }
            let sp = scene.surface_seen(&hit, diffs.as_ref());
            let mut bsdf = m.bsdf(&sp, wo);
            bsdf.carry(beta);
            if self.regularize && rough_before {
                bsdf.bxdf.regularize();
            }
            let v = Vertex::surface(hit, bsdf, wo, beta, TransportMode::Radiance);
            let Some((bs, next)) = Self::bounce(path, v, pdf_fwd, max_vertices, (&mut beta, &mut roulette), sampler)
            else {
                break;
            };
            rough_before |= !bs.is_specular();
            pdf_fwd = next;
            diffs = diffs.filter(|_| bs.is_specular()).and_then(|d| {
                scene.specular_differentials(&hit, &d, (wo, bs.wi), bs.is_transmission(), bs.eta, bsdf.frame.z)
            });
            stats.other_rays += 1;
            ray = Ray::timed(offset_origin(hit.p, hit.ng, bs.wi), bs.wi, hit.time);
        }
        l
    }

    /// A subpath's new surface vertex `v`, reached with the solid-angle
    /// density `pdf_fwd` from the vertex before: pushed, then scattered
    /// (unless the subpath has its `max_vertices` surface vertices) by a
    /// BSDF sample in the vertex's mode. The sample and the next vertex's
    /// forward density, or `None` where the subpath ends.
    fn bounce(
        path: &mut Vec<Vertex>,
        mut v: Vertex,
        pdf_fwd: f32,
        max_vertices: usize,
        (beta, roulette): (&mut Vec3, &mut Vec3),
        sampler: &mut Sampler,
    ) -> Option<(BsdfSample, f32)> {
        let (Some(hit), Some(bsdf)) = (v.hit, v.bsdf) else {
            return None;
        };
        v.pdf_fwd = path.last()?.convert_density(pdf_fwd, &v);
        path.push(v);
        // Surface vertices so far: all but the subpath's endpoint.
        let surfaces = path.len() - 1;
        if surfaces >= max_vertices || bsdf.flags().is_empty() {
            return None;
        }
        let uc = sampler.lobe_choice(bsdf.uses_lobe_choice());
        let bs = bsdf.sample_f(v.wo, uc, sampler.next_2d(), v.mode)?;
        if !hit.keeps_side(v.wo, bs.wi, bs.flags) {
            return None;
        }
        let next = Self::scatter(path, &bsdf, v.wo, &bs, (beta, roulette), surfaces, sampler)?;
        Some((bs, next))
    }

    /// The step both subpaths share after a BSDF sample at their last
    /// vertex: the throughput, the vertex before's reverse density, the
    /// specular flag and the roulette. The forward solid-angle density of
    /// the next vertex, or `None` when the subpath ends.
    fn scatter(
        path: &mut [Vertex],
        bsdf: &Bsdf,
        wo: Vec3,
        bs: &BsdfSample,
        (beta, roulette): (&mut Vec3, &mut Vec3),
        surfaces: usize,
        sampler: &mut Sampler,
    ) -> Option<f32> {
        let n = path.len();
        let (v, mode) = (path[n - 1], path[n - 1].mode);
        let mut scale = bs.f * (bs.wi.dot(bsdf.frame.z).abs() / bs.pdf);
        if mode == TransportMode::Importance {
            scale *= v.hit.map_or(0.0, |h| shading_correction(&h, bsdf, wo, bs.wi));
        }
        let (mut fwd, mut rev) = (bs.pdf, bsdf.pdf(bs.wi, wo, mode));
        if bs.is_specular() {
            path[n - 1].delta = true;
            (fwd, rev) = (0.0, 0.0);
        }
        path[n - 2].pdf_rev = v.convert_density(rev, &path[n - 2]);
        *beta *= scale;
        // As the path tracer's, on the subpath's scattering so far (a light
        // subpath's throughput also carries the light's power), times the
        // squared relative indices of refraction crossed.
        *roulette *= scale;
        if bs.is_transmission() {
            *roulette *= bs.eta * bs.eta;
        }
        if surfaces >= ROULETTE_DEPTH as usize {
            let q = roulette.max_element().min(MAX_SURVIVAL);
            if sampler.next_f32() >= q {
                return None;
            }
            *beta /= q;
            *roulette /= q;
        }
        (beta.is_finite() && beta.max_element() > 0.0).then_some(fwd)
    }

    /// The light subpath through the scene as it is at `time`: a light
    /// chosen by power, a particle leaving it and its bounces. A particle
    /// from a light at infinity starts on a disk across the scene, its
    /// first vertex at infinity.
    fn light_subpath(
        &self,
        scene: &Scene,
        sampler: &mut Sampler,
        stats: &mut RayStats,
        path: &mut Vec<Vertex>,
        time: f32,
    ) {
        let u = sampler.next_2d();
        let u2 = sampler.next_2d();
        let Some((li, pmf, ux)) = scene.pick_light(u.x) else {
            return;
        };
        let light = &scene.lights[li];
        let mut le = light.sample_le_flux(Vec2::new(ux, u.y), u2);
        le.ray.time = time;
        let (pdf_pos, pdf_dir) = light.pdf_le(&le.ray, le.n);
        // The next vertex's density: from a light at infinity, the start's
        // on the disk (projected by `convert_density`); else the direction's.
        let (v0, pdf_next) = if light.is_infinite() {
            let mut v0 = Vertex::endpoint(
                Kind::Infinity(Some(li)),
                le.ray.o,
                Vec3::ZERO,
                TransportMode::Importance,
            );
            v0.wo = -le.ray.d;
            v0.pdf_fwd = v0.pdf_origin(scene);
            // A distant light's direction is a delta: only the start varies.
            let ok = light.is_delta() || pdf_dir > 0.0;
            (v0, if ok { pdf_pos } else { 0.0 })
        } else {
            let mut v0 = Vertex::endpoint(Kind::Light(li), le.ray.o, le.n, TransportMode::Importance);
            v0.pdf_fwd = if light.is_delta() { 0.0 } else { pmf * pdf_pos };
            (v0, pdf_dir)
        };
        path.push(v0);
        let mut beta = le.flux / pmf;
        if pdf_next <= 0.0 || !beta.is_finite() || beta.max_element() <= 0.0 {
            return;
        }
        let mut roulette = Vec3::ONE;
        let mut rough_before = false;
        let mut pdf_fwd = pdf_next;
        let mut ray = le.ray;
        let max_vertices = self.limit(0);
        if max_vertices == 0 {
            return;
        }
        stats.other_rays += 1;
        // A light subpath ends on a light that reflects nothing.
        while let Some(hit) = scene.intersect(&ray, 0.0, f32::INFINITY).filter(|h| scene.reflects(h)) {
            let m = scene.material(hit.material);
            let wo = -ray.d;
            let sp = scene.surface_seen(&hit, None);
            let mut bsdf = m.bsdf(&sp, wo);
            bsdf.carry(beta);
            if self.regularize && rough_before {
                bsdf.bxdf.regularize();
            }
            let v = Vertex::surface(hit, bsdf, wo, beta, TransportMode::Importance);
            let Some((bs, next)) = Self::bounce(path, v, pdf_fwd, max_vertices, (&mut beta, &mut roulette), sampler)
            else {
                break;
            };
            rough_before |= !bs.is_specular();
            pdf_fwd = next;
            stats.other_rays += 1;
            ray = Ray::timed(offset_origin(hit.p, hit.ng, bs.wi), bs.wi, hit.time);
        }
    }

    /// Path (s, t)'s contribution for t >= 2, weighted.
    #[allow(clippy::too_many_arguments)]
    fn connect(
        &self,
        scene: &Scene,
        lights: &[Vertex],
        cameras: &[Vertex],
        s: usize,
        t: usize,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> Vec3 {
        let pt = &cameras[t - 1];
        if s == 0 {
            let l = match (pt.kind, pt.emitter()) {
                (Kind::Light(_) | Kind::Surface, Some(li)) => {
                    let prev = &cameras[t - 2];
                    let Some(w) = (prev.p - pt.p).try_normalize() else {
                        return Vec3::ZERO;
                    };
                    pt.beta * scene.lights[li].le(pt.p, w, pt.uv)
                }
                (Kind::Infinity(_), _) => {
                    let from = cameras[t - 2].p;
                    let le: Vec3 = scene
                        .infinite_lights()
                        .iter()
                        .map(|&i| scene.lights[i as usize].le_escaped(from, pt.wo))
                        .sum();
                    pt.beta * le
                }
                _ => return Vec3::ZERO,
            };
            if l == Vec3::ZERO {
                return l;
            }
            return l * self.mis_weight(scene, lights, cameras, None, s, t);
        }
        if !pt.is_connectible() {
            return Vec3::ZERO;
        }
        let (Some(hit), Some(bsdf)) = (&pt.hit, &pt.bsdf) else {
            return Vec3::ZERO;
        };
        if s == 1 {
            let u = sampler.next_2d();
            let Some((li, pmf, ux)) = scene.pick_light(u.x) else {
                return Vec3::ZERO;
            };
            let Some(ls) = unoccluded_light_sample(scene, hit, pt.wo, bsdf, li, Vec2::new(ux, u.y), stats) else {
                return Vec3::ZERO;
            };
            let light = &scene.lights[li];
            let f = bsdf.f(pt.wo, ls.wi, TransportMode::Radiance);
            let l = pt.beta * f * (ls.wi.dot(bsdf.frame.z).abs() / pmf) * ls.weight;
            if l == Vec3::ZERO {
                return l;
            }
            if light.is_infinite() {
                let mut sampled = Vertex::at_infinity(Some(li), scene, pt.p, ls.wi, TransportMode::Importance);
                sampled.pdf_fwd = sampled.pdf_origin(scene);
                return l * self.mis_weight(scene, lights, cameras, Some(&sampled), s, t);
            }
            let q = pt.p + ls.wi * ls.dist;
            let mut sampled = Vertex::endpoint(
                Kind::Light(li),
                q,
                light_normal(light, q, pt.p),
                TransportMode::Importance,
            );
            sampled.pdf_fwd = sampled.pdf_light_origin(scene, li);
            return l * self.mis_weight(scene, lights, cameras, Some(&sampled), s, t);
        }
        let qs = &lights[s - 1];
        if !qs.is_connectible() {
            return Vec3::ZERO;
        }
        let (Some(qbsdf), Some(qhit)) = (&qs.bsdf, &qs.hit) else {
            return Vec3::ZERO;
        };
        let d = qs.p - pt.p;
        let d2 = d.length_squared();
        let Some(w) = d.try_normalize() else {
            return Vec3::ZERO;
        };
        let g = w.dot(bsdf.frame.z).abs() * w.dot(qbsdf.frame.z).abs() / d2;
        let l = pt.beta * pt.f(w) * qs.f(-w) * qs.beta * g;
        if l == Vec3::ZERO || !l.is_finite() {
            return Vec3::ZERO;
        }
        stats.shadow_rays += 1;
        let o = offset_origin(pt.p, hit.ng, w);
        let span = offset_origin(qs.p, qhit.ng, -w) - o;
        let len = span.length();
        if len > 0.0 && scene.occluded(&Ray::timed(o, span / len, hit.time), 0.0, len * (1.0 - 1e-4)) {
            return Vec3::ZERO;
        }
        l * self.mis_weight(scene, lights, cameras, None, s, t)
    }

    /// The power heuristic's weight of strategy (s, t) for its path (pbrt's
    /// `MISWeight`, squared ratios): the ratios of each other strategy's
    /// density to this one's, walked outwards from the connection along both
    /// subpaths. `sampled` stands in for the light vertex when s = 1 and for
    /// the camera's when t = 1.
    fn mis_weight(
        &self,
        scene: &Scene,
        lights: &[Vertex],
        cameras: &[Vertex],
        sampled: Option<&Vertex>,
        s: usize,
        t: usize,
    ) -> f32 {
        if s + t == 2 {
            return 1.0;
        }
        let light_at = |i: usize| match sampled {
            Some(v) if s == 1 && i == 0 => v,
            _ => &lights[i],
        };
        let camera_at = |i: usize| match sampled {
            Some(v) if t == 1 && i == 0 => v,
            _ => &cameras[i],
        };
        let pt = camera_at(t - 1);
        let pt_minus = (t > 1).then(|| camera_at(t - 2));
        let qs = (s > 0).then(|| light_at(s - 1));
        let qs_minus = (s > 1).then(|| light_at(s - 2));
        // The reverse densities the connection gives the four vertices at its ends.
        let pt_rev = match qs {
            Some(q) => q.pdf(scene, qs_minus, pt),
            None => pt.pdf_origin(scene),
        };
        let pt_minus_rev = match (qs, pt.kind, pt_minus) {
            (Some(q), _, Some(pm)) => pt.pdf(scene, Some(q), pm),
            (None, Kind::Light(_) | Kind::Infinity(_), Some(pm)) => pt.pdf(scene, None, pm),
            // An emitter the camera subpath went on from, as the light it is.
            (None, Kind::Surface, Some(pm)) => pt.emitter().map_or(0.0, |li| pt.pdf_light(scene, li, pm)),
            _ => 0.0,
        };
        let qs_rev = qs.map_or(0.0, |q| pt.pdf(scene, pt_minus, q));
        let qs_minus_rev = match (qs, qs_minus) {
            (Some(q), Some(qm)) => q.pdf(scene, Some(pt), qm),
            _ => 0.0,
        };
        // Fewer camera vertices: down to t = 1 with light tracing, else t = 2.
        let first = if self.light_tracing { 1 } else { 2 };
        let sum = ratio_sum(0.0, t, first, camera_at, (pt_rev, pt_minus_rev), |i| {
            camera_at(i - 1).delta
        });
        // Fewer light vertices, down to s = 0 (none where the light is a delta in position).
        let sum = ratio_sum(sum, s, 0, light_at, (qs_rev, qs_minus_rev), |i| match i {
            0 => light_at(0).is_delta_light(scene),
            _ => light_at(i - 1).delta,
        });
        1.0 / (1.0 + sum)
    }

    /// Light tracing (t = 1): light subpath vertex s - 1 joined to the
    /// pinhole. Where on the film it lands, and what it brings there
    /// (pbrt-v4: the particle's throughput, the BSDF towards the camera, and
    /// the camera's importance over the density of choosing the pinhole,
    /// 1 / (A cos^3 theta d^2)), weighted.
    fn connect_camera(&self, scene: &Scene, lights: &[Vertex], s: usize, stats: &mut RayStats) -> Option<(Vec2, Vec3)> {
        let qs = &lights[s - 1];
        if !qs.is_connectible() {
            return None;
        }
        let (qbsdf, qhit) = (qs.bsdf.as_ref()?, qs.hit.as_ref()?);
        // The camera where it is at the particle's time.
        let (cam, time) = (&scene.camera, qs.time);
        let position = cam.position_at(time);
        let d = position - qs.p;
        let d2 = d.length_squared();
        let w = d.try_normalize()?;
        let pdf_dir = cam.pdf_dir_at(-w, time);
        if pdf_dir <= 0.0 {
            return None;
        }
        let (x, y) = cam.project_at(qs.p, time)?;
        let l = qs.beta * qs.f(w) * (w.dot(qbsdf.frame.z).abs() * pdf_dir / d2);
        if l == Vec3::ZERO || !l.is_finite() {
            return None;
        }
        stats.shadow_rays += 1;
        let o = offset_origin(qs.p, qhit.ng, w);
        let span = position - o;
        let len = span.length();
        if len > 0.0 && scene.occluded(&Ray::timed(o, span / len, time), 0.0, len * (1.0 - 1e-4)) {
            return None;
        }
        let camera = Vertex::camera(position, time);
        let w = self.mis_weight(scene, lights, &[], Some(&camera), s, 1);
        Some((Vec2::new(x, y), l * w))
    }

    /// One sample's light tracing: a light subpath of its own, each vertex
    /// joined to the camera, handed to `splat` as film position and light.
    pub fn trace_light(
        &self,
        scene: &Scene,
        sampler: &mut Sampler,
        stats: &mut RayStats,
        splat: &mut impl FnMut(Vec2, Vec3),
    ) {
        let mut lights = Vec::with_capacity(8);
        // Where things move, the particle's own time over the shutter.
        let time = match scene.camera.shutter {
            Some([open, close]) => open + (close - open) * sampler.next_f32(),
            None => 0.0,
        };
        self.light_subpath(scene, sampler, stats, &mut lights, time);
        for s in 2..=lights.len() {
            if self.max_depth.is_some_and(|d| s - 1 > d as usize) {
                break;
            }
            if let Some((pos, l)) = self.connect_camera(scene, &lights, s, stats) {
                splat(pos, l);
            }
        }
    }
}

impl RadianceEstimator for Bdpt {
    fn li(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Vec3 {
        let mut cameras = Vec::with_capacity(8);
        let mut lights = Vec::with_capacity(8);
        // The light subpath and the light samples draw from streams of their
        // own: each request is then the same dimension in every sample of
        // the pixel, stratified, whatever length the camera subpath had.
        let mut light_sampler = sampler.stream(LIGHT_SUBPATH_STREAM);
        let mut nee_sampler = sampler.stream(LIGHT_SAMPLE_STREAM);
        let mut l = self.camera_subpath(scene, ray, sampler, stats, &mut cameras);
        // The light subpath through the scene as the camera ray sees it.
        self.light_subpath(scene, &mut light_sampler, stats, &mut lights, ray.time);
        let depth_ok = |s: usize, t: usize| self.max_depth.is_none_or(|d| s + t - 2 <= d as usize);
        for t in 2..=cameras.len() {
            // s = 1 samples a light afresh, with or without a light subpath.
            for s in 0..=lights.len().max(1) {
                if depth_ok(s, t) {
                    l += self.connect(scene, &lights, &cameras, s, t, &mut nee_sampler, stats);
                }
            }
        }
        l
    }
}

/// Keys of a camera sample's light subpath and light samples (`Sampler::stream`).
const LIGHT_SUBPATH_STREAM: u64 = 0x6c73_7562_7061_7468;
const LIGHT_SAMPLE_STREAM: u64 = 0x6e65_655f_6c69_6768;

/// Second key of the light-tracing samplers, apart from the camera samples'.
const LIGHT_TRACING_SEED: u64 = 0x6c69_6768_745f_7472;

/// Frame rows a light-tracing work item takes.
const LIGHT_ROWS: u32 = 8;
/// Splats a work item holds before adding them to the pass's sums (24
/// bytes each).
const MAX_HELD_SPLATS: usize = 1 << 16;

/// The light-tracing half of a pass of the bidirectional path tracer: one
/// light subpath per pixel and sample of the whole frame (samples
/// `samples`), even for a crop, so that a crop or tile is the frame's own;
/// each joined to the camera and its light added to `light` (the crop's
/// pixels), spread by the pixel filter over the frame's pixels it reaches,
/// normalised. Fixed-point sums make the order of the additions, and so the
/// thread count, irrelevant. `None` when stopped.
pub fn trace_light_pass(
    est: &Bdpt,
    scene: &Scene,
    settings: &super::RenderSettings,
    samples: std::ops::Range<u32>,
    light: &mut [PixelSum],
    on_tile: super::Progress,
) -> Option<RayStats> {
    use rayon::prelude::*;
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let rect = settings.crop.unwrap_or(PixelRect::full(w, h));
    let spp = settings.samples_per_pixel();
    let light = std::sync::Mutex::new(light);
    let stats: Option<Vec<RayStats>> = (0..h.div_ceil(LIGHT_ROWS))
        .into_par_iter()
        .map(|item| {
            if on_tile.stopped() {
                return None;
            }
            let mut stats = RayStats::default();
            let mut splats: Vec<(usize, Vec3, f32)> = Vec::new();
            let mut weights: Vec<(u32, u32, f32)> = Vec::new();
            let flush = |splats: &mut Vec<(usize, Vec3, f32)>| {
                let mut light = light.lock().unwrap_or_else(|e| e.into_inner());
                for (k, l, wt) in splats.drain(..) {
                    light[k].add(l, wt);
                }
            };
            for y in item * LIGHT_ROWS..((item + 1) * LIGHT_ROWS).min(h) {
                for x in 0..w {
                    let mut splat = |pos: Vec2, l: Vec3| {
                        let l = super::clamp_sample(l, settings.max_component);
                        film_weights(settings.filter, pos, (w, h), &mut weights);
                        let total: f32 = weights.iter().map(|&(.., wt)| wt).sum();
                        if total <= 0.0 || !l.is_finite() {
                            return;
                        }
                        for &(px, py, wt) in &weights {
                            if px >= rect.x0 && px < rect.x1 && py >= rect.y0 && py < rect.y1 {
                                let k = (py - rect.y0) as usize * rect.width() as usize + (px - rect.x0) as usize;
                                splats.push((k, l, wt / total));
                            }
                        }
                    };
                    for s in samples.clone() {
                        let seed = settings.seed ^ LIGHT_TRACING_SEED;
                        let mut sampler = super::camera_sampler(settings.sampler, seed, x, y, w, spp, s);
                        est.trace_light(scene, &mut sampler, &mut stats, &mut splat);
                    }
                    // Bounded memory for wide frames and many samples a pass.
                    if splats.len() >= MAX_HELD_SPLATS {
                        flush(&mut splats);
                    }
                }
            }
            flush(&mut splats);
            Some(stats)
        })
        .collect();
    let mut total = RayStats::default();
    for s in &stats? {
        total.add(s);
    }
    Some(total)
}

/// The pixels of a `w` x `h` frame the filter reaches from film position
/// `pos`, with its weights there.
fn film_weights(filter: Filter, pos: Vec2, (w, h): (u32, u32), out: &mut Vec<(u32, u32, f32)>) {
    out.clear();
    let r = filter.radius();
    let (x0, x1) = (
        (pos.x - r).floor().max(0.0) as u32,
        ((pos.x + r).ceil().max(0.0) as u32).min(w),
    );
    let (y0, y1) = (
        (pos.y - r).floor().max(0.0) as u32,
        ((pos.y + r).ceil().max(0.0) as u32).min(h),
    );
    for py in y0..y1 {
        for px in x0..x1 {
            let wt = filter.eval(Vec2::new(px as f32 + 0.5 - pos.x, py as f32 + 0.5 - pos.y));
            if wt > 0.0 {
                out.push((px, py, wt));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::camera::ThinLens;
    use crate::film::PixelRect;
    use crate::integrator::analytic::{closed_sphere_desc, path_settings};
    use crate::integrator::{render, IntegratorKind, RenderSettings, StateFiles};
    use crate::light::Light;
    use crate::material::Material;
    use crate::math::Vec3;
    use crate::scene::Scene;
    use std::f32::consts::PI;

    fn bdpt(spp: u32, max_depth: Option<u32>) -> RenderSettings {
        RenderSettings {
            integrator: IntegratorKind::Bdpt,
            ..path_settings(spp, max_depth)
        }
    }

    /// The image's mean within 1.5% of the path tracer's, and each 8 x 8
    /// block's within 4% or, in dark blocks (a glass ball's sparse
    /// highlights, say), 1% of the image's mean.
    fn assert_agrees(bd: &crate::Film, path: &crate::Film, what: &str) {
        let (w, h) = (path.width, path.height);
        let whole = (path.mean(0, 0, w, h), bd.mean(0, 0, w, h));
        let err = ((whole.1 - whole.0) / whole.0).abs().max_element();
        assert!(err < 0.015, "{what}: {:?} vs path {:?}", whole.1, whole.0);
        let floor = whole.0 * 0.01;
        for (x, y) in (0..w / 8).flat_map(|x| (0..h / 8).map(move |y| (x * 8, y * 8))) {
            let (p, b) = (path.mean(x, y, x + 8, y + 8), bd.mean(x, y, x + 8, y + 8));
            let ok = ((b - p).abs() - (p * 0.04 + floor)).max_element() < 0.0;
            assert!(ok, "{what}, block ({x}, {y}): {b:?} vs path {p:?}");
        }
    }

    /// `cornell-specular` (a mirror block, a glass ball) at `w` x `h`.
    fn cornell_specular(w: u32, h: u32) -> Scene {
        let mut d = crate::scene::builtin::cornell_specular();
        d.camera.width = w;
        d.camera.height = h;
        Scene::build(d).unwrap()
    }

    fn bits(f: &crate::Film) -> Vec<u32> {
        f.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect()
    }

    #[test]
    fn sphere_lit_from_its_centre_matches_radiosity_with_every_camera_and_light() {
        // Direct irradiance E0 = Phi / (4 pi R^2) on the whole wall; every
        // bounce lands on the wall again: L = a E0 / (pi (1 - a)). A sphere
        // light (area) and a point light (delta: no path reaches it), seen by a
        // pinhole (light tracing joins in) and through a lens (it does not):
        // each set of strategies must weigh up to the whole.
        let (a, phi) = (0.6, 10.0);
        let expected = a * phi / (4.0 * PI) / (PI * (1.0 - a));
        for point in [false, true] {
            for lens in [
                None,
                Some(ThinLens {
                    radius: 0.05,
                    focal_distance: 0.7,
                }),
            ] {
                let mut d = closed_sphere_desc(Material::diffuse(a, a, a), (!point).then_some((0.01, phi)), 16);
                if point {
                    d.lights.push(Light::Point {
                        position: Vec3::ZERO,
                        power: Vec3::splat(phi),
                    });
                }
                d.camera.lens = lens;
                let scene = Scene::build(d).unwrap();
                assert_eq!(scene.camera.is_pinhole(), lens.is_none());
                let film = render(&scene, &bdpt(64, None), &|| {}).unwrap().film;
                let mean = film.mean(0, 0, 16, 16).x;
                assert!(
                    (mean - expected).abs() / expected < 0.01,
                    "point {point}, lens {lens:?}: {mean} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn agrees_with_the_path_tracer_through_mirrors_glass_and_limited_depths() {
        // cornell-specular: a mirror block and a glass sphere; the path tracer
        // is the reference (`assert_agrees`: both renders' noise); measured
        // with four times the samples each, every block within 1%.
        let scene = cornell_specular(24, 24);
        for depth in [Some(1), Some(3), None] {
            let path = render(&scene, &path_settings(4096, depth), &|| {}).unwrap().film;
            let bd = render(&scene, &bdpt(1024, depth), &|| {}).unwrap().film;
            assert_agrees(&bd, &path, &format!("depth {depth:?}"));
        }
    }

    #[test]
    fn agrees_with_the_path_tracer_where_things_and_the_camera_move() {
        // The default room, its short block sliding and turning, the camera
        // sliding: light subpaths, their connections and light tracing all
        // see the scene at the camera ray's or the particle's time. With
        // them all at time 0, the first block checked was 8% off in green.
        use crate::geometry::motion::Motion;
        use glam::Mat4;
        let mut d = crate::scene::builtin::cornell();
        (d.camera.width, d.camera.height) = (24, 24);
        let end = Mat4::from_translation(Vec3::new(0.4, 0.0, 0.2)) * Mat4::from_rotation_y(0.8);
        let block = 10..20;
        let centre = d
            .triangles
            .range(block.clone())
            .flat_map(|t| t.vertices)
            .fold(Vec3::ZERO, |a, v| a + v / 30.0);
        d.moving.push(crate::scene::MovingTriangles {
            triangles: block,
            motion: Motion::new(Mat4::IDENTITY, end, [0.0, 1.0]).unwrap().about(centre),
        });
        d.camera_motion = Some(
            Motion::new(
                Mat4::IDENTITY,
                Mat4::from_translation(Vec3::new(0.1, 0.0, 0.0)),
                [0.0, 1.0],
            )
            .unwrap(),
        );
        // And the camera alone moving (turning): hits then still carry
        // the camera ray's time, though no shape needs it.
        let mut camera_only = d.clone();
        camera_only.moving.clear();
        let turn = Motion::new(Mat4::IDENTITY, Mat4::from_rotation_y(0.2), [0.0, 1.0]).unwrap();
        camera_only.camera_motion = Some(turn.about(camera_only.camera.position));
        for (what, d) in [("moving", d), ("the camera alone moving", camera_only)] {
            let scene = Scene::build(d).unwrap();
            assert!(scene.camera.is_pinhole() && scene.has_motion());
            let path = render(&scene, &path_settings(4096, None), &|| {}).unwrap().film;
            let bd = render(&scene, &bdpt(1024, None), &|| {}).unwrap().film;
            assert_agrees(&bd, &path, what);
        }
    }

    /// A floor under a rough metal ball, a rough glass ball and a coated
    /// one, lit by one light of every kind.
    fn every_light() -> Scene {
        use crate::geometry::{Disk, Sphere};
        use crate::material::Roughness;
        use crate::scene::{CameraDesc, SceneDesc, SphereDesc, TriangleDesc};
        let camera = CameraDesc {
            position: Vec3::new(0.0, -4.0, 3.0),
            look_at: Vec3::new(0.0, 0.0, 0.5),
            up: Vec3::Z,
            fov_y_deg: 50.0,
            width: 32,
            height: 32,
            window: None,
            lens: None,
            orthographic: None,
            spherical: None,
            realistic: None,
        };
        let mut d = SceneDesc::empty("every-light", camera);
        let floor = d.material("floor", Material::diffuse(0.6, 0.5, 0.4));
        let (a, b, c, e) = (
            Vec3::new(-6.0, -6.0, 0.0),
            Vec3::new(6.0, -6.0, 0.0),
            Vec3::new(6.0, 6.0, 0.0),
            Vec3::new(-6.0, 6.0, 0.0),
        );
        for vertices in [[a, b, c], [a, c, e]] {
            d.triangles.push(TriangleDesc {
                vertices,
                normals: None,
                uvs: None,
                material: floor,
            });
        }
        let rough = |r: f32| Roughness::isotropic(r, false).into();
        let balls = [
            (
                Vec3::new(-1.2, 0.0, 0.6),
                Material::Conductor {
                    fresnel: crate::material::ConductorFresnel::Reflectance(crate::texture::Texture::from(Vec3::new(
                        0.9, 0.6, 0.4,
                    ))),
                    roughness: rough(0.15),
                },
            ),
            (
                Vec3::new(0.0, 0.3, 0.6),
                Material::Dielectric {
                    eta: 1.5,
                    roughness: rough(0.2),
                },
            ),
            (
                Vec3::new(1.2, 0.0, 0.6),
                Material::CoatedDiffuse {
                    reflectance: crate::texture::Texture::from(Vec3::new(0.2, 0.4, 0.7)),
                    roughness: rough(0.1),
                    eta: 1.5,
                    thickness: 0.01,
                    medium: None,
                },
            ),
        ];
        for (i, (centre, m)) in balls.into_iter().enumerate() {
            let material = d.material(&format!("ball{i}"), m);
            d.spheres.push(SphereDesc {
                axes: None,
                sphere: Sphere { centre, radius: 0.6 },
                material,
            });
        }
        d.lights.extend([
            Light::spot(
                Vec3::new(2.0, -2.0, 3.0),
                Vec3::new(-0.5, 0.5, -1.0).normalize(),
                Vec3::splat(4.0),
                30.0,
                10.0,
            ),
            Light::Point {
                position: Vec3::new(-2.0, -1.0, 2.0),
                power: Vec3::new(20.0, 15.0, 10.0),
            },
            Light::Disk {
                disk: Disk::new(Vec3::new(0.0, 1.5, 2.5), -Vec3::Z, 0.4, 0.1, None).unwrap(),
                radiance: Vec3::splat(3.0),
                two_sided: false,
                image: None,
            },
            Light::Triangle {
                vertices: [
                    Vec3::new(2.5, 1.0, 0.2),
                    Vec3::new(2.5, 2.0, 0.2),
                    Vec3::new(2.5, 1.5, 1.4),
                ],
                radiance: Vec3::new(2.0, 3.0, 2.0),
                two_sided: true,
                image: None,
            },
            Light::Sphere {
                sphere: Sphere {
                    centre: Vec3::new(-1.5, 1.5, 1.5),
                    radius: 0.1,
                },
                power: Vec3::splat(15.0),
                image: None,
                emits: Default::default(),
            },
            Light::infinite(Vec3::splat(0.1), None, glam::Mat3::IDENTITY),
            Light::distant(Vec3::new(0.3, 0.2, -1.0).normalize(), Vec3::splat(0.5)),
        ]);
        Scene::build(d).unwrap()
    }

    #[test]
    fn sunlight_through_a_thin_pane_reaches_the_floor_only_by_light_tracing() {
        use crate::scene::{CameraDesc, SceneDesc, TriangleDesc};
        // A floor of albedo 0.2 under a distant light straight down (E = 2),
        // a thin glass pane (transmittance (1 - R)^2 / (1 - R^2) = 12/13 at
        // normal incidence, R = 0.04) above part of it. No shadow ray passes
        // the pane: the floor beneath it is lit only by particles from the
        // light at infinity, joined to the camera. Two bounces at most: the
        // pane and the floor.
        let camera = CameraDesc {
            position: Vec3::new(0.0, -4.0, 1.0),
            look_at: Vec3::ZERO,
            up: Vec3::Z,
            fov_y_deg: 40.0,
            width: 48,
            height: 48,
            window: None,
            lens: None,
            orthographic: None,
            spherical: None,
            realistic: None,
        };
        let mut d = SceneDesc::empty("sun-through-a-pane", camera);
        let floor = d.material("floor", Material::diffuse(0.2, 0.2, 0.2));
        let pane = d.material("pane", Material::ThinDielectric { eta: 1.5 });
        let quad = |r: f32, z: f32| {
            let c = [(-r, -r), (r, -r), (r, r), (-r, r)].map(|(x, y)| Vec3::new(x, y, z));
            [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
        };
        for (vertices, material) in quad(2.0, 0.0)
            .map(|v| (v, floor))
            .into_iter()
            .chain(quad(1.0, 1.5).map(|v| (v, pane)))
        {
            d.triangles.push(TriangleDesc {
                vertices,
                normals: None,
                uvs: None,
                material,
            });
        }
        d.lights.push(Light::distant(-Vec3::Z, Vec3::splat(2.0)));
        let scene = Scene::build(d).unwrap();
        let film = render(&scene, &bdpt(128, Some(2)), &|| {}).unwrap().film;
        let around = |p: Vec3| {
            let (x, y) = scene.camera.project(p).unwrap();
            film.mean(x as u32 - 2, y as u32 - 2, x as u32 + 3, y as u32 + 3).x
        };
        let lit = 0.2 / std::f32::consts::PI * 2.0;
        let (under, beside) = (around(Vec3::ZERO), around(Vec3::new(0.0, -1.6, 0.0)));
        assert!((beside - lit).abs() < 0.03 * lit, "in the sun: {beside} against {lit}");
        let through = lit * 12.0 / 13.0;
        assert!(
            (under - through).abs() < 0.05 * through,
            "under the pane: {under} against {through}"
        );
        // The path tracer sees the floor beneath the pane dark.
        let path = render(&scene, &path_settings(16, Some(2)), &|| {}).unwrap().film;
        let (x, y) = scene.camera.project(Vec3::ZERO).unwrap();
        assert!(path.get(x as u32, y as u32).x < 0.01 * lit);
    }

    #[test]
    fn agrees_with_the_path_tracer_under_every_kind_of_light() {
        // The weights' special cases: delta positions (point, spot) and
        // directions (distant), lights at infinity (light subpaths from them), one-
        // and two-sided area lights, a sphere light; rough reflection,
        // transmission and a layered BSDF in between (`assert_agrees`).
        let scene = every_light();
        let path = render(&scene, &path_settings(2048, Some(4)), &|| {}).unwrap().film;
        let bd = render(&scene, &bdpt(512, Some(4)), &|| {}).unwrap().film;
        assert_agrees(&bd, &path, "every light");
    }

    #[test]
    fn images_are_the_same_for_any_thread_count_crop_and_interruption() {
        let scene = cornell_specular(24, 16);
        let one = RenderSettings {
            threads: Some(1),
            ..bdpt(8, Some(4))
        };
        let whole = render(&scene, &one, &|| {}).unwrap().film;
        let two = RenderSettings {
            threads: Some(2),
            ..one.clone()
        };
        assert_eq!(bits(&whole), bits(&render(&scene, &two, &|| {}).unwrap().film));
        // A crop is the frame's own pixels, light-traced light included.
        let rect = PixelRect {
            x0: 5,
            y0: 3,
            x1: 17,
            y1: 11,
        };
        let crop = RenderSettings {
            crop: Some(rect),
            ..two.clone()
        };
        let part = render(&scene, &crop, &|| {}).unwrap().film;
        for y in rect.y0..rect.y1 {
            for x in rect.x0..rect.x1 {
                assert_eq!(part.get(x - rect.x0, y - rect.y0), whole.get(x, y), "pixel ({x}, {y})");
            }
        }
        // Stopped after a pass and resumed from its checkpoint: the same image.
        let dir = tempfile::tempdir().unwrap();
        let ck = dir.path().join("bdpt.ckpt");
        let files = |resume: bool| StateFiles {
            checkpoint: Some(ck.clone()),
            resume: resume.then(|| ck.clone()),
            stop_after_passes: (!resume).then_some(1),
            ..StateFiles::default()
        };
        let first = render(
            &scene,
            &RenderSettings {
                files: files(false),
                ..two.clone()
            },
            &|| {},
        )
        .unwrap();
        assert!(!first.is_complete());
        let last = render(
            &scene,
            &RenderSettings {
                files: files(true),
                ..two.clone()
            },
            &|| {},
        )
        .unwrap();
        assert!(last.is_complete());
        assert_eq!(bits(&last.film), bits(&whole));
        // And the light-traced part is there: without it the image differs.
        let path = render(
            &scene,
            &RenderSettings {
                integrator: IntegratorKind::Path,
                ..two
            },
            &|| {},
        )
        .unwrap();
        assert_ne!(bits(&path.film), bits(&whole));
    }
}
