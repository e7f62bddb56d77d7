//! pbrt-v4 scene files through the library's pbrt reader
//! (`scene::pbrt::parse_bytes`), the converter (`pbrt::convert::convert`,
//! lenient, so that unsupported features are skipped rather than ending the
//! run early), the film's crop at a few sizes, into a built scene (BVH
//! included), and a few camera rays into that: hits, shadow tests, BSDFs,
//! and a short path of each: through participating media in scenes with
//! them, else the bidirectional path tracer's (with a particle traced to
//! the camera).
//!
//! The input is the scene file up to its first NUL; the bytes after it are
//! served as any `.ply` file the scene names (and, decompressed by the
//! reader, as any `.ply.gz`) and as any `.spd` spectrum file, so the fuzzer
//! mutates the `plymesh`, spectrum and NanoVDB file paths too (every
//! `.nvdb` file a `nanovdb` medium names is that tail as well).
//! `virtual/inc.pbrt` is a small fixed file for `Include` and `Import`.

#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use raytracer::integrator::bdpt::Bdpt;
use raytracer::integrator::path::PathTracer;
use raytracer::integrator::{LightSampling, RadianceEstimator, RayStats};
use raytracer::sampling::Sampler;
use raytracer::scene::mesh::FileSource;
use raytracer::scene::pbrt::{convert::convert, parse_bytes};
use raytracer::scene::Scene;
use std::io::{Error, ErrorKind};
use std::path::Path;

const INCLUDE: &[u8] = b"MakeNamedMaterial \"m\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n\
AttributeBegin\nNamedMaterial \"m\"\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\nAttributeEnd\n";

/// The fixed include file, and the input's tail as every PLY and spectrum file.
struct Files<'a> {
    ply: &'a [u8],
}

impl FileSource for Files<'_> {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        let name = path.to_string_lossy();
        if path == Path::new("virtual/inc.pbrt") {
            Ok(INCLUDE.to_vec())
        } else if name.ends_with(".ply")
            || name.ends_with(".ply.gz")
            || name.ends_with(".spd")
            || name.ends_with(".nvdb")
        {
            Ok(self.ply.to_vec())
        } else {
            Err(Error::new(ErrorKind::NotFound, "not among the fuzz target's files"))
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let (scene, ply) = common::split_mtl(data);
    let files = Files {
        ply: ply.unwrap_or(&[]),
    };
    let path = Path::new("virtual/scene.pbrt");
    let Ok(parsed) = parse_bytes(path, scene.to_vec(), &files) else {
        return;
    };
    if let Ok(converted) = convert(&parsed, path, true) {
        // The film's crop at its own size and at two others (a resize).
        if let Some(crop) = converted.crop {
            let c = &converted.desc.camera;
            for (w, h) in [(c.width, c.height), (c.width * 2 + 1, c.height / 3 + 1), (1, 1)] {
                let _ = crop.rect(w, h);
            }
        }
        let Ok(scene) = Scene::build(converted.desc) else {
            return;
        };
        // A few camera rays into it: hits (through cut-outs), shadow tests
        // and the BSDF at each hit (bump and normal maps included).
        let c = &scene.camera;
        let (w, h) = (c.width as f32, c.height as f32);
        for (k, (x, y)) in [(0.5, 0.5), (w * 0.5, h * 0.5), (w - 0.5, h - 0.5), (w * 0.25, h * 0.75)]
            .into_iter()
            .enumerate()
        {
            let ray = c.generate_ray(x, y);
            if let Some(hit) = scene.intersect(&ray, 0.0, f32::INFINITY) {
                let _ = scene.occluded(&ray, 0.0, hit.t);
                let _ = scene.material(hit.material).bsdf(&scene.surface(&hit), -ray.d);
            }
            let mut sampler = Sampler::new(true, 1, (x + w * y) as u64, 0);
            if scene.has_media() {
                // Every other ray regularized, so that both ways are walked.
                let pt = PathTracer {
                    max_depth: Some(6),
                    light_sampling: LightSampling::Mis,
                    regularize: k % 2 == 1,
                };
                let _ = pt.li(&scene, &ray, &mut sampler, &mut RayStats::default());
            } else {
                let bdpt = Bdpt {
                    max_depth: Some(4),
                    light_tracing: c.is_pinhole(),
                    regularize: k % 2 == 1,
                };
                let mut stats = RayStats::default();
                let _ = bdpt.li(&scene, &ray, &mut sampler, &mut stats);
                if bdpt.light_tracing {
                    bdpt.trace_light(&scene, &mut sampler, &mut stats, &mut |_, _| {});
                }
            }
        }
    }
});
