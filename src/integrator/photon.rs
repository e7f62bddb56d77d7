//! Photon mapping integrator: direct light by shadow rays, caustics from the
//! caustic map, indirect light from the global photon map (Jensen 2001,
//! "Realistic Image Synthesis Using Photon Mapping", chapter 9).
//!
//! Camera rays go on through mirrors and glass (Fresnel picks reflection or
//! refraction) to their first diffuse surface x, or a light. Light reaches x
//! along disjoint kinds of paths, each counted by one estimate: light -> x by
//! shadow rays (glass and mirrors block them); light -> specular+ -> x by the
//! caustic map (`--caustic-photons`, gathered within `--caustic-radius`, no
//! other photons in it; without it such paths are missing); paths with a
//! diffuse bounce before x by the global map, read without its first-hit and
//! caustic photons. At a camera ray's diffuse hit x:
//! - without final gathering, L = Le + f E_direct(shadow rays) + f E_photons(x),
//!   where the map holds only photons after their first bounce (indirect
//!   light), or first hits too when `--shadow-samples 0` leaves direct light to
//!   the map;
//! - with final gathering (9.3), N cosine-distributed rays leave x and the
//!   indirect light is albedo x the mean radiance they bring back. At a gather
//!   ray's hit y the radiance is Le(y) + f(y) E_photons(y) with the *global*
//!   map, first-hit photons included: they are the direct light at y, i.e. the
//!   one-bounce indirect light at x. A gather ray that reaches a light brings
//!   nothing back, since shadow rays already counted that light (unless they are
//!   off), nor one that reaches it through mirrors or glass (the caustic map
//!   did). Gather rays go through mirrors and glass to y. So every path
//!   light -> ... -> y -> x -> camera is counted once, and the only bias left is
//!   the blur of the density estimate one bounce away.
//!
//! Parameters (see `PhotonSettings`): `--photons`, `--max-bounces`,
//! `--store-first-hit`, `--gather-radius`, `--gather-k`, `--cone-filter`,
//! `--gather-filter`, `--final-gather`, `--caustic-photons`, `--caustic-radius`.

use super::direct::{direct_radiance, sample_bsdf, walk_camera_path, DiffuseVertex, MAX_SPECULAR_DEPTH};
use super::{RadianceEstimator, RayStats};
use crate::bsdf::{Bsdf, Bxdf, TransportMode};
use crate::error::Result;
use crate::math::{offset_origin, to_world, Ray, Vec3};
use crate::photon::estimate::Place;
use crate::photon::estimate::{self, PrecomputedIrradiance};
use crate::photon::file;
use crate::photon::map::Neighbour;
use crate::photon::{Admit, Gather, PhotonMap, PhotonSettings, PhotonStats};
use crate::sampling::{cosine_hemisphere, hammersley_shifted, Sampler};
use crate::scene::{Hit, Scene};
use std::cell::RefCell;

pub struct PhotonMapping<'a> {
    /// `None` when no photons were traced: direct light only.
    pub map: Option<&'a PhotonMap>,
    pub gather: Gather,
    /// `None` when there is none (no mirrors or glass, or `--caustic-photons 0`).
    pub caustics: Option<&'a PhotonMap>,
    pub caustic_radius: f32,
    pub shadow_samples: u32,
    pub final_gather: u32,
    /// Irradiance precomputed at the map's photons, read instead of gathering
    /// on Lambertian surfaces (irradiance is all a Lambertian BRDF needs).
    pub precomputed: Option<&'a PrecomputedIrradiance>,
}

thread_local! {
    /// k-nearest scratch space, reused across shading points of a thread.
    static SCRATCH: RefCell<Vec<Neighbour>> = const { RefCell::new(Vec::new()) };
}

/// Unit normal of a hit on the side `wo` faces.
fn facing(hit: &Hit, wo: Vec3) -> Vec3 {
    if hit.ng.dot(wo) < 0.0 {
        -hit.ng
    } else {
        hit.ng
    }
}

impl PhotonMapping<'_> {
    /// Reflected radiance towards `wo` from the photons of `map` near a hit
    /// whose BSDF is `bsdf`. A Lambertian BRDF needs only the irradiance
    /// (precomputed, when it was); any other BSDF weighs each photon by
    /// f(wo, wi) (Jensen 2001, 7.1).
    ///
    /// On a moving shape the gather reads the photons the shape caught, kept
    /// where it is at its motion's start (`photon::trace`), around the
    /// hit carried there; elsewhere those on what stays still.
    #[allow(clippy::too_many_arguments)]
    fn photon_radiance(
        &self,
        scene: &Scene,
        map: &PhotonMap,
        hit: &Hit,
        wo: Vec3,
        bsdf: &Bsdf,
        admit: Admit,
        g: &Gather,
    ) -> Vec3 {
        let rest = match scene.has_motion() {
            true => scene.rest_frame(hit.object, hit.time),
            false => None,
        };
        let (p, n, place) = match &rest {
            None => (hit.p, facing(hit, wo), Place::Still),
            Some(r) => (
                r.point(hit.p),
                r.normal(facing(hit, wo)),
                Place::of(Some(r.objects.clone())),
            ),
        };
        let admit = admit.at(place);
        SCRATCH.with(|s| {
            let scratch = &mut s.borrow_mut();
            if let Bxdf::Diffuse(d) = bsdf.bxdf {
                let e = match self.precomputed {
                    // Built with the admission this integrator reads the global map with.
                    Some(pre) if std::ptr::eq(map, self.map.unwrap_or(map)) && g == &self.gather => pre
                        .lookup(p, n, place, scratch)
                        .unwrap_or_else(|| estimate::irradiance(map, g, p, n, admit, scratch)),
                    _ => estimate::irradiance(map, g, p, n, admit, scratch),
                };
                return e * d.r * std::f32::consts::FRAC_1_PI;
            }
            estimate::radiance(map, g, p, n, admit, scratch, |wi| {
                let wi = rest.as_ref().map_or(wi, |r| r.direction_back(wi));
                bsdf.f(wo, wi, TransportMode::Radiance)
            })
        })
    }

    /// Caustic radiance from the caustic map: a plain fixed-radius estimate
    /// with its own, smaller radius.
    fn caustic_radiance(&self, scene: &Scene, v: &DiffuseVertex) -> Vec3 {
        let Some(map) = self.caustics else {
            return Vec3::ZERO;
        };
        let g = Gather {
            radius: self.caustic_radius,
            k: None,
            cone: false,
            filter: self.gather.filter,
        };
        self.photon_radiance(scene, map, &v.hit, v.wo, &v.bsdf, Admit::ALL, &g)
    }

    /// Indirect light reflected at a diffuse vertex, by final gathering: rays
    /// leave it (cosine-distributed and stratified on a Lambertian surface,
    /// else sampled from the BSDF's non-specular lobes) and bring back the
    /// global map's radiance estimate where they reach a surface with a
    /// diffuse lobe, through specular and glossy surfaces.
    fn final_gather(
        &self,
        scene: &Scene,
        map: &PhotonMap,
        v: &DiffuseVertex,
        sampler: &mut Sampler,
        stats: &mut RayStats,
    ) -> Vec3 {
        let hit = &v.hit;
        let n = self.final_gather;
        let shift = sampler.next_2d();
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            let u = hammersley_shifted(i, n, shift);
            let (d, weight, lobe) = if let Bxdf::Diffuse(dif) = v.bsdf.bxdf {
                // f cos / pdf = albedo for a cosine-distributed direction.
                (to_world(cosine_hemisphere(u), v.bsdf.frame.z), dif.r, v.bsdf.flags())
            } else {
                let Some(bs) = v.bsdf.sample_f(v.wo, sampler.next_f32(), u, TransportMode::Radiance) else {
                    continue;
                };
                if bs.is_specular() {
                    continue;
                }
                (bs.wi, bs.f * (bs.wi.dot(v.bsdf.frame.z).abs() / bs.pdf), bs.flags)
            };
            if d.dot(hit.ng) == 0.0 || !hit.keeps_side(v.wo, d, lobe) {
                continue;
            }
            stats.other_rays += 1;
            let mut ray = Ray::timed(offset_origin(hit.p, hit.ng, d), d, hit.time);
            let mut beta = weight;
            for depth in 0..=MAX_SPECULAR_DEPTH {
                let Some(y) = scene.intersect(&ray, 0.0, f32::INFINITY) else {
                    break;
                };
                if let Some(l) = y.light {
                    // Shadow rays counted this light, or the caustic map did
                    // when it came through specular or glossy surfaces.
                    if self.shadow_samples == 0 && depth == 0 {
                        sum += beta * scene.lights[l as usize].le(y.p, -ray.d, y.uv);
                    }
                    if !scene.reflects(&y) {
                        break;
                    }
                }
                let m = scene.material(y.material);
                let wo = -ray.d;
                let mut bsdf = m.bsdf(&scene.surface(&y), wo);
                bsdf.carry(beta);
                let flags = bsdf.flags();
                if flags.is_diffuse() {
                    sum += beta * (m.le() + self.photon_radiance(scene, map, &y, wo, &bsdf, Admit::ALL, &self.gather));
                    break;
                }
                let Some(bs) = sample_bsdf(&bsdf, wo, sampler) else {
                    break;
                };
                if !y.keeps_side(wo, bs.wi, bs.flags) {
                    break;
                }
                beta *= bs.f * (bs.wi.dot(bsdf.frame.z).abs() / bs.pdf);
                stats.other_rays += 1;
                ray = Ray::timed(offset_origin(y.p, y.ng, bs.wi), bs.wi, y.time);
            }
        }
        sum / n as f32
    }

    /// Light reflected at a camera path's diffuse vertex: direct by shadow
    /// rays, caustics by the caustic map, the rest by the global map.
    fn shade(&self, scene: &Scene, v: &DiffuseVertex, sampler: &mut Sampler, stats: &mut RayStats) -> Vec3 {
        let mut l = direct_radiance(scene, v, self.shadow_samples, sampler, stats) + self.caustic_radiance(scene, v);
        if let Some(map) = self.map {
            l += if self.final_gather > 0 {
                self.final_gather(scene, map, v, sampler, stats)
            } else {
                let admit = Admit {
                    direct: self.shadow_samples == 0,
                    caustic: false,
                    place: Place::Still,
                };
                self.photon_radiance(scene, map, &v.hit, v.wo, &v.bsdf, admit, &self.gather)
            };
        }
        l
    }
}

impl RadianceEstimator for PhotonMapping<'_> {
    fn li(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, stats: &mut RayStats) -> Vec3 {
        walk_camera_path(scene, *ray, sampler, stats, |v, sampler, stats| {
            (self.shade(scene, v, sampler, stats), true)
        })
    }
}

/// The photon settings that decide the maps: final gathering and photon-only
/// direct light read first-hit photons, so these store them.
pub fn map_settings(settings: &super::RenderSettings) -> PhotonSettings {
    let mut ps = settings.photon;
    ps.store_first_hit |= ps.final_gather > 0 || settings.shadow_samples == 0;
    ps
}

/// Which stored photons the global map is read with: everything under final
/// gathering (the gather rays' hits see every path); else not the caustic
/// photons (the caustic map has them) nor the direct ones (shadow rays).
pub fn global_admit(settings: &super::RenderSettings) -> Admit {
    if settings.photon.final_gather > 0 {
        Admit::ALL
    } else {
        Admit {
            direct: settings.shadow_samples == 0,
            caustic: false,
            place: Place::Still,
        }
    }
}

/// The photon maps of a render: global and caustic, each `None` when not
/// asked for (or, for the caustic map, when the scene has no mirror or glass).
pub struct PhotonMaps {
    pub global: Option<PhotonMap>,
    pub caustic: Option<PhotonMap>,
    pub stats: PhotonStats,
}

/// Tags of the maps in photon map files.
const GLOBAL: &str = "global";
const CAUSTIC: &str = "caustic";

/// The photon maps: read from `--load-photons`, or traced (and written to
/// `--save-photons` if asked).
pub fn photon_maps(scene: &Scene, settings: &super::RenderSettings) -> Result<PhotonMaps> {
    super::check_scene(scene, super::IntegratorKind::Photon)?;
    let ps = map_settings(settings);
    // Hashing a large scene takes a noticeable part of a second: only a
    // render that reads or writes photons needs the header.
    let header = || file::header(scene, file::key(&ps, settings.seed));
    if let Some(path) = &settings.files.load_photons {
        let start = std::time::Instant::now();
        let mut maps = file::load(path, &header())?;
        let mut stats = PhotonStats::default();
        let global = if ps.photons > 0 {
            let g = file::take(&mut maps, GLOBAL, path)?;
            (stats.emitted, stats.stored, stats.bytes) = (g.emitted, g.map.len(), g.map.bytes());
            Some(g.map)
        } else {
            None
        };
        // The key includes the caustic count, so a file without a caustic map
        // is one traced for a scene that has no mirror or glass.
        let caustic = file::take(&mut maps, CAUSTIC, path).ok().map(|c| {
            (stats.caustic_emitted, stats.caustic_stored) = (c.emitted, c.map.len());
            stats.bytes += c.map.bytes();
            c.map
        });
        stats.load_seconds = start.elapsed().as_secs_f64();
        return Ok(PhotonMaps { global, caustic, stats });
    }
    let (global, stats) = match ps.photons {
        0 => (None, PhotonStats::default()),
        _ => {
            let (m, s) = crate::photon::build_map(scene, &ps, settings.seed);
            (Some(m), s)
        }
    };
    let PhotonMaps {
        global,
        caustic,
        mut stats,
    } = with_caustics(scene, settings, global, stats);
    if let Some(path) = &settings.files.save_photons {
        let start = std::time::Instant::now();
        let mut stored: Vec<file::StoredMap> = [
            (GLOBAL, stats.emitted, global),
            (CAUSTIC, stats.caustic_emitted, caustic),
        ]
        .into_iter()
        .filter_map(|(tag, emitted, map)| {
            map.map(|map| file::StoredMap {
                tag: tag.into(),
                emitted,
                map,
            })
        })
        .collect();
        file::save(path, &header(), &stored)?;
        stats.save_seconds = start.elapsed().as_secs_f64();
        let global = file::take(&mut stored, GLOBAL, path).ok().map(|m| m.map);
        let caustic = file::take(&mut stored, CAUSTIC, path).ok().map(|m| m.map);
        return Ok(PhotonMaps { global, caustic, stats });
    }
    Ok(PhotonMaps { global, caustic, stats })
}

/// The maps of a render whose global map is traced (or not asked for): the
/// caustic map is traced after it, as `photon_maps` does. The preview, which
/// traces its global map in resumable chunks, finishes it here too.
pub fn with_caustics(
    scene: &Scene,
    settings: &super::RenderSettings,
    global: Option<PhotonMap>,
    mut stats: PhotonStats,
) -> PhotonMaps {
    let ps = map_settings(settings);
    let caustic = crate::photon::build_caustic_map(scene, &ps, settings.seed, &mut stats);
    PhotonMaps { global, caustic, stats }
}

/// What a photon-mapped render reads while it shades: the maps and, when
/// asked for, the irradiance precomputed from the global map. The offline
/// render and the preview both shade through it.
pub struct PhotonPipeline {
    maps: PhotonMaps,
    precomputed: Option<PrecomputedIrradiance>,
    settings: PhotonSettings,
    shadow_samples: u32,
}

impl PhotonPipeline {
    /// Precomputes the irradiance if the settings ask for it.
    pub fn new(scene: &Scene, mut maps: PhotonMaps, settings: &super::RenderSettings) -> Self {
        let ps = map_settings(settings);
        let precomputed = match &maps.global {
            Some(map) if ps.precompute_irradiance => {
                let start = std::time::Instant::now();
                let place = |ph: &crate::photon::Photon| match ph.is_moving() {
                    true => Place::of(scene.moving_object(ph.object).map(|(r, _)| r)),
                    false => Place::Still,
                };
                let pre = PrecomputedIrradiance::build(map, &ps.gather, global_admit(settings), place);
                maps.stats.precompute_seconds = start.elapsed().as_secs_f64();
                Some(pre)
            }
            _ => None,
        };
        PhotonPipeline {
            maps,
            precomputed,
            settings: ps,
            shadow_samples: settings.shadow_samples,
        }
    }

    pub fn maps(&self) -> &PhotonMaps {
        &self.maps
    }

    /// The radiance estimator over these maps.
    pub fn estimator(&self) -> PhotonMapping<'_> {
        PhotonMapping {
            map: self.maps.global.as_ref(),
            gather: self.settings.gather,
            caustics: self.maps.caustic.as_ref(),
            caustic_radius: self.settings.caustic_radius,
            shadow_samples: self.shadow_samples,
            final_gather: self.settings.final_gather,
            precomputed: self.precomputed.as_ref(),
        }
    }
}

/// Gets the photon maps (if any photons are asked for), then renders.
pub fn render(
    scene: &Scene,
    settings: &super::RenderSettings,
    on_tile: super::Progress,
) -> Result<((crate::Film, RayStats, u64), Option<PhotonStats>)> {
    let pipeline = PhotonPipeline::new(scene, photon_maps(scene, settings)?, settings);
    let out = super::render_tiles(scene, settings, &pipeline.estimator(), on_tile);
    let maps = pipeline.maps();
    let any = maps.global.is_some() || maps.caustic.is_some();
    Ok((out, any.then(|| maps.stats.clone())))
}

#[cfg(test)]
mod tests {
    use crate::integrator::analytic::closed_sphere;
    use crate::integrator::{render, IntegratorKind, RenderSettings};
    use crate::material::Material;
    use crate::photon::PhotonSettings;
    use std::f32::consts::PI;

    fn photon(photons: u64, final_gather: u32) -> RenderSettings {
        let mut s = RenderSettings {
            integrator: IntegratorKind::Photon,
            ssaa: 2,
            ..RenderSettings::default()
        };
        s.photon = PhotonSettings {
            photons,
            final_gather,
            ..PhotonSettings::default()
        };
        s
    }

    #[test]
    fn sphere_lit_from_its_centre_matches_truncated_radiosity() {
        // Direct irradiance E0 = Phi / (4 pi R^2) on the whole wall, and a photon's
        // k-th hit carries Phi a^(k-1) spread evenly over it. Photons reach at most
        // B = 5 hits, so L = (a E0 / pi) (1 + a + ... + a^(B-1)); with final
        // gathering the gather rays see all B hits one bounce away, so
        // L = (a E0 / pi) (1 + a (1 + ... + a^(B-1))). A ball of radius r around a
        // point of a sphere cuts out a cap of area exactly pi r^2, so the density
        // estimate has no curvature bias here.
        let (a, phi) = (0.5f32, 10.0);
        let scene = closed_sphere(Material::diffuse(a, a, a), Some((0.01, phi)), 16);
        let e0 = phi / (4.0 * PI);
        let geometric = |n: i32| (1.0 - a.powi(n)) / (1.0 - a);
        for (fg, expected) in [
            (0, a * e0 / PI * geometric(5)),
            (16, a * e0 / PI * (1.0 + a * geometric(5))),
        ] {
            let film = render(&scene, &photon(200_000, fg), &|| {}).unwrap().film;
            let mean = film.mean(0, 0, 16, 16).x;
            assert!(
                (mean - expected).abs() / expected < 0.02,
                "final gather {fg}: {mean} vs {expected}"
            );
        }
    }

    #[test]
    fn precomputed_irradiance_matches_the_full_gather() {
        // Uniform irradiance on the sphere: the nearest site's estimate is the
        // full estimate's, so the truncated radiosity holds as above; and the
        // images with and without precomputation agree pixel by pixel up to the
        // estimates' noise, while a wrong lookup (no site, another side) would
        // leave pixels black.
        let (a, phi) = (0.5f32, 10.0);
        let scene = closed_sphere(Material::diffuse(a, a, a), Some((0.01, phi)), 16);
        let expected = a * phi / (4.0 * PI) / PI * (1.0 - a.powi(5)) / (1.0 - a);
        let mut s = photon(200_000, 0);
        let full = render(&scene, &s, &|| {}).unwrap().film;
        s.photon.precompute_irradiance = true;
        let pre = render(&scene, &s, &|| {}).unwrap().film;
        let mean = pre.mean(0, 0, 16, 16).x;
        assert!((mean - expected).abs() / expected < 0.02, "{mean} vs {expected}");
        for (p, f) in pre.pixels.iter().zip(&full.pixels) {
            assert!((p.x - f.x).abs() / f.x < 0.1, "pixel {} vs {}", p.x, f.x);
        }
    }

    #[test]
    fn no_photons_is_direct_light_only() {
        let scene = crate::Scene::build(crate::scene::builtin::cornell()).unwrap();
        let mut scene = scene;
        scene.camera = crate::camera::Camera::new(
            scene.camera.position,
            glam::Vec3::ZERO,
            glam::Vec3::new(0.0, -1.0, 0.0),
            53.13,
            24,
            24,
        )
        .unwrap();
        let direct = RenderSettings::default();
        let a = render(&scene, &direct, &|| {}).unwrap();
        let b = render(&scene, &photon(0, 0), &|| {}).unwrap();
        let c = render(&scene, &RenderSettings { ssaa: 2, ..direct }, &|| {}).unwrap();
        assert!(a.photons.is_none() && b.photons.is_none());
        assert_eq!(b.film, c.film);
    }

    fn small_cornell(size: u32) -> crate::Scene {
        let mut d = crate::scene::builtin::cornell();
        d.camera.width = size;
        d.camera.height = size;
        crate::Scene::build(d).unwrap()
    }

    /// Mean over 8x8-pixel blocks, and whether a block shows the light.
    fn blocks(film: &crate::Film) -> Vec<(f32, bool)> {
        let mut out = vec![];
        for by in 0..film.height / 8 {
            for bx in 0..film.width / 8 {
                let (x0, y0) = (bx * 8, by * 8);
                let lum = |x, y| crate::math::luminance(film.get(x, y));
                let light = (y0..y0 + 8).any(|y| (x0..x0 + 8).any(|x| lum(x, y) > 10.0));
                let mean = (y0..y0 + 8).flat_map(|y| (x0..x0 + 8).map(move |x| (x, y)));
                out.push((mean.map(|(x, y)| lum(x, y)).sum::<f32>() / 64.0, light));
            }
        }
        out
    }

    #[test]
    fn cornell_matches_the_path_traced_reference() {
        let scene = small_cornell(64);
        let reference = RenderSettings {
            integrator: IntegratorKind::Path,
            spp: 128,
            ..RenderSettings::default()
        };
        let mut pm = photon(100_000, 0);
        pm.photon.max_bounces = 10;
        let r = blocks(&render(&scene, &reference, &|| {}).unwrap().film);
        let p = blocks(&render(&scene, &pm, &|| {}).unwrap().film);
        let (mut sr, mut sp, mut sq, mut n) = (0.0, 0.0, 0.0, 0.0);
        let mut worst = 0.0f32;
        for (&(a, light), &(b, _)) in r.iter().zip(&p) {
            if light {
                continue;
            }
            sr += a;
            sp += b;
            let e = (b - a) / a;
            sq += e * e;
            worst = worst.max(e.abs());
            n += 1.0;
        }
        let (ratio, rms) = (sp / sr, (sq / n).sqrt());
        // Mean luminance (light left out) within 5%; measured: 0.988. The photon
        // estimate's biases (blur, dark corners and edges, 10-hit truncation) cost
        // about 1% at this radius.
        assert!((ratio - 1.0).abs() < 0.05, "luminance ratio {ratio}");
        // Per 8x8 block: the reference's noise is ~1% (9% per pixel at 64 spp,
        // over 64 pixels at 128 spp) and the photon map's low-frequency noise 2-3%
        // (about 100 photons per gather disc at 100k photons, 10% noise on the
        // indirect light, which is a third of the total, and a block sees about
        // two discs). Its bias is largest where the gather disc reaches past a
        // surface's edge: the floor along the open front of the room and the
        // corners come out 5-10% dark, the floor by the short block 6% bright.
        // Measured: RMS 2.8%, worst block 9.7%; a bug in the power, the density
        // normalisation or the filters moves these by far more.
        assert!(rms < 0.05, "rms block error {rms}, worst {worst}");
        assert!(worst < 0.15, "worst block error {worst}, rms {rms}");
    }

    #[test]
    fn purple_wall_bleeds_onto_the_floor() {
        // How purple the floor looks, (r + b) / 2g, over a band of 27 floor points
        // from the front to the back of the room.
        let scene = small_cornell(128);
        let purple = |film: &crate::Film, x0: f32| {
            let mut c = glam::Vec3::ZERO;
            for (i, j) in (0..9).flat_map(|i| (0..3).map(move |j| (i, j))) {
                let p = glam::Vec3::new(x0 + 0.07 * j as f32, 1.0, -0.9 + 0.1 * i as f32);
                let (x, y) = scene.camera.project(p).unwrap();
                c += film.get(x as u32, y as u32);
            }
            (c.x + c.z) / (2.0 * c.y)
        };
        let (wall, centre) = (-0.94, -0.4);
        let direct = RenderSettings {
            ssaa: 2,
            ..RenderSettings::default()
        };
        let direct = render(&scene, &direct, &|| {}).unwrap().film;
        let pm = render(&scene, &photon(400_000, 0), &|| {}).unwrap().film;
        // Direct light is white: the green floor's own 0.2 everywhere.
        assert!((purple(&direct, wall) - 0.2).abs() < 1e-3);
        assert!((purple(&direct, centre) - 0.2).abs() < 1e-3);
        // The path-traced reference (4096 spp) has 0.2203 by the wall and 0.2113 at
        // the centre: the excess over 0.2 is 1.8 times larger by the wall. Photon
        // maps with seeds 0..5 give ratios of 1.4 to 1.8.
        let (w, c) = (purple(&pm, wall) - 0.2, purple(&pm, centre) - 0.2);
        assert!(c > 0.005, "centre excess {c}");
        assert!(w > 1.25 * c, "excess by the wall {w}, at the centre {c}");
    }
}
