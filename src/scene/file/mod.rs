//! Scene files in TOML: camera, settings, named materials, lights and shapes
//! (quads, boxes, triangles, spheres, disks, meshes). The format, with every key and
//! its default, is described in `docs/scene-format.md`.
//!
//! Unknown keys are errors, and every error names the file and the line: the
//! `toml` crate's spans give it for syntax and type errors, and each table
//! keeps its span so that later checks (a missing key, a key that does not
//! apply to the shape's type, an unknown material) can point at it too.
//! The file's types are in `types`; here is one parse function per table.

use super::mesh::{load_mesh_timed_from, Disk, FileSource, MeshReport};
use super::motion::Motion;
use super::transform::{Fit, Transform};
use super::{
    Boundary, CameraDesc, CutShapes, Cutout, DiskDesc, LoadOptions, LoadedScene, MovingShape, MovingTriangles,
    SceneDesc, SphereDesc, TriangleDesc,
};
use crate::camera::{SphericalMapping, ThinLens};
use crate::error::{Error, Result};
use crate::geometry::Sphere;
use crate::light::Light;
use crate::material::Material;
use crate::math::{Vec2, Vec3};
use crate::medium::{Emission, Medium, MediumInterface};
use crate::settings::{self, Kind, Origin, SceneSettings, Value};
use crate::texture::Texture;
use glam::Mat4;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use toml::Spanned;
use types::*;

mod materials;
mod types;

/// 1-based line of a byte offset.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Builds errors that point into one scene file.
struct Source<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Source<'_> {
    fn error(&self, span: std::ops::Range<usize>, message: impl Into<String>) -> Error {
        Error::Syntax {
            path: self.path.to_path_buf(),
            line: line_of(self.text, span.start),
            message: message.into(),
        }
    }
}

/// Reads a scene file. `opts.mesh` replaces the path of the file's mesh
/// shape (there must be exactly one); `opts.smooth` smooth-shades every mesh.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<LoadedScene> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    parse(path, &text, opts)
}

/// Parses the text of a scene file; `path` names it in errors and anchors
/// the relative paths of meshes.
pub fn parse(path: &Path, text: &str, opts: &LoadOptions) -> Result<LoadedScene> {
    parse_with(path, text, opts, &Disk)
}

/// Parses a scene file's text, reading its meshes through `files`.
pub fn parse_with(path: &Path, text: &str, opts: &LoadOptions, files: &dyn FileSource) -> Result<LoadedScene> {
    let src = Source { path, text };
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        let message = e.message().trim().replace('\n', "; ");
        match e.span() {
            Some(span) => src.error(span, message),
            None => Error::Parse {
                path: path.to_path_buf(),
                message,
            },
        }
    })?;

    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let camera = camera(&src, &file.camera, &dir, files)?;
    let name = file.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    });
    let mut desc = SceneDesc::empty(&name, camera);
    if let Some(shutter) = &file.camera.get_ref().shutter {
        desc.shutter = match shutter.get_ref()[..] {
            [open, close] if open.0 <= close.0 => [open.0, close.0],
            [open, close] => {
                let m = format!(
                    "camera: the shutter closes at {}, before it opens at {}",
                    close.0, open.0
                );
                return Err(src.error(shutter.span(), m));
            }
            _ => {
                let m = "camera: `shutter` needs two numbers, [open, close]";
                return Err(src.error(shutter.span(), m));
            }
        };
    }
    if let Some(table) = &file.settings {
        desc.settings = scene_settings(&src, table)?;
    }

    // Textures, then materials, checked here; materials are numbered in
    // order of first use.
    let textures = materials::textures(&src, &file.textures, &dir, files)?;
    let materials = materials::materials(&src, &file.materials, &textures, &dir, files)?;
    for l in &file.lights {
        // The surface an area light reflects by, if it names a material.
        let reflecting = match &l.get_ref().material {
            Some(name) => Some(material_index(&src, &materials, &mut desc, name)?),
            None => None,
        };
        for (k, light) in light(&src, l)?.into_iter().enumerate() {
            light.check(1.0).map_err(|m| src.error(l.span(), m))?;
            if let Some(material) = reflecting {
                let uvs = matches!(light, Light::Triangle { .. }).then_some(AREA_LIGHT_UVS[k]);
                desc.light_surfaces.resize(desc.lights.len(), None);
                desc.light_surfaces.push(Some(crate::scene::LightSurface {
                    material,
                    uvs,
                    ..Default::default()
                }));
            }
            desc.lights.push(light);
        }
    }

    let mut media = Media {
        specs: &file.media,
        used: BTreeMap::new(),
    };
    if let Some(name) = &file.camera.get_ref().medium {
        desc.camera_medium = Some(media.index(&src, &mut desc, name)?);
    }
    let meshes = shapes(
        &src,
        &file.shapes,
        (&materials, &textures),
        &mut media,
        opts,
        files,
        &mut desc,
    )?;
    // Materials no shape uses still belong to the scene, after the used ones.
    for (name, m) in &materials {
        desc.material(name, m.clone());
    }
    if let Some(motion) = &file.camera.get_ref().motion {
        let at = |m: String| src.error(motion.span(), format!("camera: `motion`: {m}"));
        // A camera that grows or shrinks would change the solid angle its
        // rays cover, which light tracing's densities do not follow.
        if motion.get_ref().scale.is_some() {
            return Err(at(
                "a camera does not scale; give `translate`, `rotate` and `about`".into()
            ));
        }
        let (end, about) = motion_end(motion.get_ref(), desc.camera.position).map_err(at)?;
        desc.camera_motion = Some(moving(end, about).map_err(at)?);
    }
    let camera_motion = file.camera.get_ref().motion.as_ref();
    if let Some(at) = file
        .shapes
        .iter()
        .find_map(|s| s.get_ref().motion.as_ref())
        .or(camera_motion)
    {
        // Light samples through media and below surfaces would see the
        // shapes where they start.
        if !desc.media.is_empty() || desc.materials.iter().any(|(_, m)| m.has_subsurface()) {
            let m = "`motion` in a scene with participating media or subsurface materials is not supported";
            return Err(src.error(at.span(), m));
        }
    }
    // Only the path tracer renders media: a scene with them that names no
    // integrator gets it, in place of its preset's or the default.
    if !desc.media.is_empty() && desc.settings.scene_file.get("integrator").is_none() {
        let origin = Origin::Preset("participating media".into());
        let path_tracer = Value::Name(settings::IntegratorKind::Path.name());
        let set = desc.settings.preset.set("integrator", path_tracer, origin);
        debug_assert!(set.is_ok(), "{set:?}");
    }
    Ok(LoadedScene {
        desc,
        meshes,
        fov_axis: super::FovAxis::Vertical,
        crop: None,
    })
}

/// The `[camera]` table.
fn camera(src: &Source, spanned: &Spanned<CameraSpec>, dir: &Path, files: &dyn FileSource) -> Result<CameraDesc> {
    let cam_span = spanned.span();
    let cam = spanned.get_ref();
    let spherical = match &cam.spherical {
        None => None,
        Some(name) => Some(SphericalMapping::parse(name).ok_or_else(|| {
            src.error(
                cam_span.clone(),
                format!("camera spherical '{name}': use equalarea or equirectangular"),
            )
        })?),
    };
    let realistic = match &cam.lens_file {
        Some(file) => Some(lens_system(src, cam, file, dir, files)?),
        None => None,
    };
    let lens_keys = [
        ("aperture", cam.aperture.is_some()),
        ("focus_distance", cam.focus_distance.is_some()),
        ("film_diagonal", cam.film_diagonal.is_some()),
        ("aperture_shape", cam.aperture_shape.is_some()),
    ];
    if let (None, Some((key, _))) = (&realistic, lens_keys.iter().find(|(_, given)| *given)) {
        return Err(src.error(cam_span, format!("camera: `{key}` needs a `lens_file`")));
    }
    if realistic.is_some() && (spherical.is_some() || cam.lens_radius.is_some() || cam.fov_y.is_some()) {
        return Err(src.error(
            cam_span,
            "camera: a `lens_file` camera has no `fov_y`, `lens_radius` or `spherical` (its lens sets them)"
                .to_string(),
        ));
    }
    let fov_y = match (cam.fov_y, spherical) {
        (Some(f), _) => f.0,
        // Unused: the camera sees every direction, or the lens says.
        (None, Some(_)) => 90.0,
        (None, None) if realistic.is_some() => 90.0,
        (None, None) => return Err(src.error(cam_span, "camera: missing `fov_y`".to_string())),
    };
    let camera = CameraDesc {
        position: cam.position.0,
        look_at: cam.look_at.0,
        up: cam.up.map_or(Vec3::new(0.0, -1.0, 0.0), |u| u.0),
        fov_y_deg: fov_y,
        width: cam.width.unwrap_or(512),
        height: cam.height.unwrap_or(512),
        window: None,
        lens: None,
        orthographic: None,
        spherical,
        realistic,
    };
    if spherical.is_some() && cam.lens_radius.is_some_and(|r| r.0 != 0.0) {
        return Err(src.error(cam_span, "camera: a spherical camera has no lens".to_string()));
    }
    if !(camera.fov_y_deg > 0.0 && camera.fov_y_deg < 180.0) {
        return Err(src.error(
            cam_span,
            format!("camera fov_y {} must be in (0, 180) degrees", camera.fov_y_deg),
        ));
    }
    let lens = match (cam.lens_radius.map(|n| n.0), cam.focal_distance.map(|n| n.0)) {
        (None, None) | (Some(0.0), _) => None,
        (Some(radius), Some(focal_distance)) => Some(ThinLens { radius, focal_distance }),
        _ => {
            return Err(src.error(
                cam_span,
                "camera: a lens needs both lens_radius and focal_distance".to_string(),
            ))
        }
    };
    if let Some(l) = lens {
        if !l.is_valid() {
            return Err(src.error(
                cam_span,
                format!(
                    "camera lens_radius {} and focal_distance {} must be positive (lens_radius 0: a pinhole)",
                    l.radius, l.focal_distance
                ),
            ));
        }
    }
    let camera = CameraDesc { lens, ..camera };
    // An absurd size is refused here, at its line, before anything is sized by it.
    crate::limits::check_resolution(camera.width, camera.height)
        .map_err(|m| src.error(cam_span.clone(), format!("camera {m}")))?;
    if camera.camera().is_none() {
        return Err(src.error(cam_span, camera.problem()));
    }
    Ok(camera)
}

/// The camera's real lens (`lens_file` and what goes with it).
fn lens_system(
    src: &Source,
    cam: &CameraSpec,
    file: &Spanned<String>,
    dir: &Path,
    files: &dyn FileSource,
) -> Result<crate::camera::SharedLens> {
    use crate::camera::{lens_system::parse_prescription, Aperture, LensSystem};
    let path = dir.join(file.get_ref());
    let fail = |m: String| src.error(file.span(), format!("camera lens_file: {}: {m}", path.display()));
    let bytes = files.read(&path).map_err(|e| fail(e.to_string()))?;
    let rows =
        parse_prescription(&String::from_utf8_lossy(&bytes)).map_err(|(line, m)| fail(format!("line {line}: {m}")))?;
    let shape = match &cam.aperture_shape {
        None => None,
        Some(name) => Some(Aperture::builtin(name).ok_or_else(|| {
            fail(format!(
                "unknown aperture_shape '{name}' (gaussian, square, pentagon, star)"
            ))
        })?),
    };
    // Wide open unless stopped down: the lens' own stop.
    let aperture = cam.aperture.map_or(f32::MAX, |a| a.0);
    let focus = cam
        .focus_distance
        .map_or((cam.look_at.0 - cam.position.0).length(), |f| f.0);
    let diagonal = cam.film_diagonal.map_or(35.0, |d| d.0);
    let name = path
        .file_name()
        .map_or_else(|| file.get_ref().clone(), |n| n.to_string_lossy().into_owned());
    let (lens, _) = LensSystem::new(&name, &rows, aperture, focus, diagonal, shape).map_err(fail)?;
    Ok(std::sync::Arc::new(lens))
}

/// The `[[shapes]]` tables, added to `desc`; returns what loading each mesh took.
/// The file's `[media.NAME]` tables, each added to the scene when first named.
struct Media<'a> {
    specs: &'a BTreeMap<String, Spanned<MediumSpec>>,
    used: BTreeMap<String, u32>,
}

impl Media<'_> {
    /// The index in `desc.media` of the medium `name` names.
    fn index(&mut self, src: &Source, desc: &mut SceneDesc, name: &Spanned<String>) -> Result<u32> {
        let n = name.get_ref();
        if let Some(&i) = self.used.get(n) {
            return Ok(i);
        }
        let Some(spec) = self.specs.get(n) else {
            let known: Vec<&str> = self.specs.keys().map(String::as_str).collect();
            let known = if known.is_empty() {
                "none".into()
            } else {
                known.join(", ")
            };
            return Err(src.error(name.span(), format!("unknown medium '{n}' (defined: {known})")));
        };
        let m = spec.get_ref();
        let medium = Medium {
            sigma_a: m.sigma_a.map_or(Vec3::ZERO, RgbSpec::rgb),
            sigma_s: m.sigma_s.map_or(Vec3::ZERO, RgbSpec::rgb),
            g: m.g.map_or(0.0, |g| g.0),
            density: None,
            emission: m
                .le
                .map(RgbSpec::rgb)
                .filter(|le| *le != Vec3::ZERO)
                .map(|le| std::sync::Arc::new(Emission::uniform(le))),
        };
        medium
            .check()
            .map_err(|why| src.error(spec.span(), format!("medium '{n}': {why}")))?;
        desc.media.push((n.clone(), medium));
        let i = desc.media.len() as u32 - 1;
        self.used.insert(n.clone(), i);
        Ok(i)
    }
}

/// The index in `desc` of the material `name`, added at its first use.
fn material_index(
    src: &Source,
    materials: &BTreeMap<String, Material>,
    desc: &mut SceneDesc,
    name: &Spanned<String>,
) -> Result<u32> {
    match materials.get(name.get_ref()) {
        Some(m) => Ok(desc.material(name.get_ref(), m.clone())),
        None => Err(src.error(
            name.span(),
            format!(
                "unknown material '{}' (defined: {})",
                name.get_ref(),
                materials.keys().cloned().collect::<Vec<_>>().join(", ")
            ),
        )),
    }
}

fn shapes(
    src: &Source,
    specs: &[Spanned<ShapeSpec>],
    (materials, textures): (&BTreeMap<String, Material>, &BTreeMap<String, Arc<Texture>>),
    media: &mut Media,
    opts: &LoadOptions,
    files: &dyn FileSource,
    desc: &mut SceneDesc,
) -> Result<Vec<MeshReport>> {
    let path = src.path;
    let material = |desc: &mut SceneDesc, name: &Spanned<String>| material_index(src, materials, desc, name);

    let mesh_count = specs.iter().filter(|s| s.get_ref().kind == ShapeKind::Mesh).count();
    if let Some(p) = &opts.mesh {
        if mesh_count != 1 {
            return Err(Error::InvalidSetting(format!(
                "--mesh {}: {} has {mesh_count} mesh shapes; --mesh replaces the path of its only one",
                p.display(),
                path.display()
            )));
        }
    }
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut meshes = vec![];
    for spanned in specs {
        let span = spanned.span();
        let s = spanned.get_ref();
        let kind = s.kind.name();
        let err = |m: String| src.error(span.clone(), format!("{kind} shape: {m}"));
        for (key, given) in s.given() {
            if given && !s.kind.keys().contains(&key) {
                return Err(err(format!("`{key}` does not apply to a {kind}")));
            }
        }
        let need = |key: &str| err(format!("missing `{key}`"));
        let mat = match &s.material {
            Some(m) => Some(material(desc, m)?),
            None if s.kind == ShapeKind::Mesh => None,
            None => return Err(need("material")),
        };
        let alpha = match s.alpha.as_ref().map(|a| (a.get_ref(), a.span())) {
            None => None,
            Some((AlphaSpec::Value(a), _)) if a.0 >= 1.0 => None,
            Some((AlphaSpec::Value(a), _)) => Some(Texture::from(Vec3::splat(a.0))),
            Some((AlphaSpec::Texture(name), at)) => match textures.get(name) {
                Some(t) => Some(Texture::clone(t)),
                None => {
                    return Err(src.error(at, format!("{kind} shape: unknown texture '{name}' for `alpha`")));
                }
            },
        };
        let (first_triangle, sphere, disk) = (desc.triangles.len(), desc.spheres.len(), desc.disks.len());
        let uvs = match &s.uvs {
            None => None,
            Some(uv) => {
                let n = if s.kind == ShapeKind::Quad { 4 } else { 3 };
                if uv.len() != n {
                    return Err(err(format!("`uvs` needs {n} pairs [u, v], found {}", uv.len())));
                }
                Some(uv.iter().map(|t| Vec2::new(t.0[0].0, t.0[1].0)).collect::<Vec<_>>())
            }
        };
        let mut tri = |v: [Vec3; 3], normals: Option<[Vec3; 3]>, uvs: Option<[Vec2; 3]>, m: u32| {
            desc.triangles.push(TriangleDesc {
                vertices: v,
                normals,
                uvs,
                material: m,
            })
        };
        match s.kind {
            ShapeKind::Triangle => {
                let v = points::<3>(s.vertices.as_deref(), "vertices").map_err(err)?;
                let n = match &s.normals {
                    Some(n) => Some(points::<3>(Some(n), "normals").map_err(err)?),
                    None => None,
                };
                let uv = uvs.as_ref().map(|t| [t[0], t[1], t[2]]);
                tri(v, n, uv, mat.unwrap_or(0));
            }
            ShapeKind::Quad => {
                let [a, b, c, d] = points::<4>(s.vertices.as_deref(), "vertices").map_err(err)?;
                let m = mat.unwrap_or(0);
                let (uv1, uv2) = match &uvs {
                    Some(t) => (Some([t[0], t[1], t[2]]), Some([t[0], t[2], t[3]])),
                    None => (None, None),
                };
                tri([a, b, c], None, uv1, m);
                tri([a, c, d], None, uv2, m);
            }
            ShapeKind::Box => {
                let (lo, hi) = match (s.min, s.max) {
                    (Some(lo), Some(hi)) => (lo.0, hi.0),
                    (None, _) => return Err(need("min")),
                    (_, None) => return Err(need("max")),
                };
                if lo.cmpgt(hi).any() {
                    return Err(err(format!("min {:?} exceeds max {:?}", lo.to_array(), hi.to_array())));
                }
                for t in box_triangles(lo, hi) {
                    tri(t, None, None, mat.unwrap_or(0));
                }
            }
            ShapeKind::Sphere => {
                let centre = s.centre.ok_or_else(|| need("centre"))?.0;
                let radius = s.radius.ok_or_else(|| need("radius"))?.0;
                if radius <= 0.0 {
                    return Err(err(format!("radius {radius} must be > 0")));
                }
                desc.spheres.push(SphereDesc {
                    axes: None,
                    sphere: Sphere { centre, radius },
                    material: mat.unwrap_or(0),
                });
            }
            ShapeKind::Disk => {
                let centre = s.centre.ok_or_else(|| need("centre"))?.0;
                let normal = s.normal.ok_or_else(|| need("normal"))?.0;
                let radius = s.radius.ok_or_else(|| need("radius"))?.0;
                let inner_radius = s.inner_radius.map_or(0.0, |r| r.0);
                let d = DiskDesc::new(centre, normal, radius, inner_radius, mat.unwrap_or(0));
                // The checks `Scene::build` makes, reported at the shape's line.
                d.disk().map_err(err)?;
                desc.disks.push(d);
            }
            ShapeKind::Mesh => {
                let file_path = s.path.as_ref().ok_or_else(|| need("path"))?;
                let mesh_path = match &opts.mesh {
                    Some(p) => p.clone(),
                    None => dir.join(file_path),
                };
                let transform = Transform {
                    scale: match s.scale {
                        None => Vec3::ONE,
                        Some(ScaleSpec::Uniform(k)) => Vec3::splat(k.0),
                        Some(ScaleSpec::PerAxis(v)) => v.0,
                    },
                    rotate_deg: s.rotate.map_or(Vec3::ZERO, |r| r.0),
                    fit: s.fit.as_ref().map(|f| Fit {
                        height: f.height.0,
                        bottom_centre: f.bottom_centre.0,
                    }),
                    translate: s.translate.map_or(Vec3::ZERO, |t| t.0),
                };
                transform.validate().map_err(err)?;
                let (mesh, report) = load_mesh_timed_from(&mesh_path, files).map_err(|e| match &opts.mesh {
                    // A path the user gave is reported as given, not at the file's line.
                    Some(_) => e,
                    None => missing_mesh(src, span.clone(), e),
                })?;
                let smooth = s.smooth.unwrap_or(false) || opts.smooth;
                mesh.add_to_scene(desc, &transform, mat, smooth)?;
                meshes.push(report);
            }
        }
        if let Some(motion) = &s.motion {
            let triangles = first_triangle..desc.triangles.len();
            let at = |m: String| src.error(motion.span(), format!("{kind} shape: `motion`: {m}"));
            if alpha.is_some() {
                return Err(at("an `alpha` cut-out on a moving shape is not supported".into()));
            }
            // What it turns about by default: its centre, or its box's.
            let centre = match s.kind {
                ShapeKind::Sphere => desc.spheres[sphere].sphere.centre,
                ShapeKind::Disk => desc.disks[disk].centre,
                _ => {
                    let (lo, hi) = desc
                        .triangles
                        .range(triangles.clone())
                        .flat_map(|t| t.vertices)
                        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
                            (lo.min(v), hi.max(v))
                        });
                    (lo + hi) * 0.5
                }
            };
            let (end, about) = motion_end(motion.get_ref(), centre).map_err(at)?;
            let motion = moving(end, about).map_err(at)?;
            match s.kind {
                ShapeKind::Sphere => desc.moving_shapes.push(MovingShape {
                    shape: CutShapes::Sphere(sphere),
                    motion,
                }),
                ShapeKind::Disk => desc.moving_shapes.push(MovingShape {
                    shape: CutShapes::Disk(disk),
                    motion,
                }),
                _ => desc.moving.push(MovingTriangles { triangles, motion }),
            }
        }
        let shapes = match s.kind {
            ShapeKind::Sphere => CutShapes::Sphere(sphere),
            ShapeKind::Disk => CutShapes::Disk(disk),
            _ => CutShapes::Triangles(first_triangle..desc.triangles.len()),
        };
        let mut side = |name: &Option<Spanned<String>>| match name {
            Some(n) => media.index(src, desc, n).map(Some),
            None => Ok(None),
        };
        let interface = MediumInterface {
            inside: side(&s.medium_inside)?,
            outside: side(&s.medium_outside)?,
        };
        let no_surface = mat.is_some_and(|m| matches!(desc.materials[m as usize].1, Material::Interface));
        if no_surface && !interface.is_transition() {
            return Err(err(
                "its material is an `interface`, no surface, so it must bound media: give `medium_inside` and \
                 `medium_outside`, different"
                    .into(),
            ));
        }
        if interface.is_transition() {
            // A box's faces wind towards its inside; its inside is its interior.
            let interface = if s.kind == ShapeKind::Box {
                interface.flipped()
            } else {
                interface
            };
            desc.boundaries.push(Boundary {
                interface,
                shapes: shapes.clone(),
            });
        }
        if let Some(alpha) = alpha {
            desc.cutouts.push(Cutout { alpha, shapes });
        }
    }
    Ok(meshes)
}

/// Where a shape's `motion` takes it: the transformation from its place
/// at time 0 to its place at time 1, in a frame whose origin is the point
/// it turns and grows about (returned too; `centre`, the centre of its
/// bounding box, by default), so that this point moves in a straight line.
fn motion_end(m: &MotionSpec, centre: Vec3) -> std::result::Result<(Mat4, Vec3), String> {
    let scale = match m.scale {
        None => Vec3::ONE,
        Some(ScaleSpec::Uniform(k)) => Vec3::splat(k.0),
        Some(ScaleSpec::PerAxis(v)) => v.0,
    };
    if scale.cmple(Vec3::ZERO).any() {
        return Err(format!("scale {:?} must be positive", scale.to_array()));
    }
    let about = m.about.map_or(centre, |a| a.0);
    let rotate = super::transform::rotation(m.rotate.map_or(Vec3::ZERO, |r| r.0));
    let translate = m.translate.map_or(Vec3::ZERO, |t| t.0);
    let end = Mat4::from_translation(translate) * Mat4::from_mat3(rotate) * Mat4::from_scale(scale);
    if !end.is_finite() || !about.is_finite() {
        return Err("the motion is not finite".into());
    }
    Ok((end, about))
}

/// The motion from the identity at time 0 to `end` at time 1, given about
/// `about`.
fn moving(end: Mat4, about: Vec3) -> std::result::Result<Motion, String> {
    let motion = Motion::new(Mat4::IDENTITY, end, [0.0, 1.0])?.about(about);
    // Turning about a far point can carry a shape beyond finite numbers.
    if !motion.relative(1.0).is_finite() {
        return Err("the motion takes it beyond finite coordinates".into());
    }
    Ok(motion)
}

/// The `[settings]` table: each key a setting of the table in
/// `crate::settings`, checked there and remembered with its line; `preset`
/// names a built-in scene whose settings apply under the file's own.
fn scene_settings(src: &Source, table: &Spanned<BTreeMap<String, Spanned<toml::Value>>>) -> Result<SceneSettings> {
    let mut out = SceneSettings::default();
    for (key, value) in table.get_ref() {
        let line = line_of(src.text, value.span().start);
        let origin = Origin::SceneFile {
            path: src.path.to_path_buf(),
            line,
        };
        if key == "preset" {
            let name = value
                .get_ref()
                .as_str()
                .ok_or_else(|| src.error(value.span(), "settings: preset must be the name of a built-in scene"))?;
            out.preset =
                super::builtin::preset(name).map_err(|m| src.error(value.span(), format!("settings: preset: {m}")))?;
            continue;
        }
        let Some(spec) = settings::spec(key).filter(|s| s.in_scene_file) else {
            let known: Vec<&str> = settings::SETTINGS
                .iter()
                .filter(|s| s.in_scene_file)
                .map(|s| s.name)
                .chain(["preset"])
                .collect();
            return Err(src.error(
                value.span(),
                format!("settings: unknown key `{key}` (known: {})", known.join(", ")),
            ));
        };
        let v = toml_value(spec, value.get_ref())
            .map_err(|m| settings::SettingError::new(key, value.get_ref(), origin.clone(), m))?;
        out.scene_file.set(key, v, origin)?;
    }
    Ok(out)
}

/// A TOML value as the setting's kind.
fn toml_value(spec: &settings::Spec, v: &toml::Value) -> std::result::Result<Value, String> {
    let wrong = || format!("expected {}", spec.kind_name());
    Ok(match (spec.kind, v) {
        (Kind::Count { .. }, toml::Value::Integer(i)) => Value::Int(u64::try_from(*i).map_err(|_| wrong())?),
        (Kind::Real { .. }, toml::Value::Float(f)) => Value::Real(*f as f32),
        (Kind::Real { .. }, toml::Value::Integer(i)) => Value::Real(*i as f32),
        (Kind::Flag, toml::Value::Boolean(b)) => Value::Bool(*b),
        (Kind::Choice(names), toml::Value::String(s)) => match names.iter().find(|n| *n == s) {
            Some(n) => Value::Name(n),
            None => return Err(wrong()),
        },
        _ => return Err(wrong()),
    })
}

/// Only the `[settings]` table of a scene file (a built-in scene's, as a preset).
pub fn settings_of(path: &Path, text: &str) -> Result<SceneSettings> {
    #[derive(serde::Deserialize)]
    struct SettingsOnly {
        settings: Option<Spanned<BTreeMap<String, Spanned<toml::Value>>>>,
    }
    let src = Source { path, text };
    let file: SettingsOnly = toml::from_str(text).map_err(|e| Error::Parse {
        path: path.to_path_buf(),
        message: e.message().trim().replace('\n', "; "),
    })?;
    match &file.settings {
        Some(table) => scene_settings(&src, table),
        None => Ok(SceneSettings::default()),
    }
}

/// A missing mesh file is reported at the scene file's line, with the hint
/// that `--mesh` can point elsewhere; other mesh errors name the mesh file.
fn missing_mesh(src: &Source, span: std::ops::Range<usize>, e: Error) -> Error {
    match e {
        Error::Io { path, source } if source.kind() == std::io::ErrorKind::NotFound => src.error(
            span,
            format!(
                "mesh file {} not found (pass --mesh PATH to use another file)",
                path.display()
            ),
        ),
        e => e,
    }
}

/// Exactly `N` points from a shape's list key.
fn points<const N: usize>(v: Option<&[Vec3Spec]>, key: &str) -> std::result::Result<[Vec3; N], String> {
    let v = v.ok_or_else(|| format!("missing `{key}`"))?;
    if v.len() != N {
        return Err(format!("`{key}` needs {N} points, found {}", v.len()));
    }
    Ok(std::array::from_fn(|i| v[i].0))
}

/// The 12 triangles of an axis-aligned box.
fn box_triangles(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let c = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    // Each face as four corner indices in order around it.
    const FACES: [[usize; 4]; 6] = [
        [0, 2, 6, 4], // x = min
        [1, 5, 7, 3], // x = max
        [0, 4, 5, 1], // y = min
        [2, 3, 7, 6], // y = max
        [0, 1, 3, 2], // z = min
        [4, 6, 7, 5], // z = max
    ];
    FACES
        .iter()
        .flat_map(|f| [[c(f[0]), c(f[1]), c(f[2])], [c(f[0]), c(f[2]), c(f[3])]])
        .collect()
}

/// The texture coordinates of a triangle or quad light's triangles, for its
/// emission image and its material: a quad's span from its first vertex,
/// (0, 0), to its third, (1, 1), the image's bottom row along the first
/// edge; a triangle takes (0, 0), (1, 0), (1, 1).
const AREA_LIGHT_UVS: [[Vec2; 3]; 2] = [
    [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::ONE],
    [Vec2::ZERO, Vec2::ONE, Vec2::new(0.0, 1.0)],
];

fn light(src: &Source, spanned: &Spanned<LightSpec>) -> Result<Vec<Light>> {
    let l = spanned.get_ref();
    let err = |m: String| src.error(spanned.span(), m);
    let kind = match l.kind {
        LightKind::Sphere => "sphere",
        LightKind::Point => "point",
        LightKind::Triangle => "triangle",
        LightKind::Quad => "quad",
        LightKind::Disk => "disk",
        LightKind::Spot => "spot",
        LightKind::Distant => "distant",
        LightKind::Infinite => "infinite",
    };
    let colour = l.colour.map_or(Vec3::ONE, |c| c.0);
    if colour.min_element() < 0.0 || l.power.is_some_and(|p| p.0 < 0.0) {
        return Err(err("light power and colour must be >= 0".into()));
    }
    let area_light = matches!(l.kind, LightKind::Triangle | LightKind::Quad);
    let disk = l.kind == LightKind::Disk;
    let at_infinity = matches!(l.kind, LightKind::Distant | LightKind::Infinite);
    let spot = l.kind == LightKind::Spot;
    // Keys that belong to another kind of light are mistakes, not options.
    let given = [
        ("centre", l.centre.is_some(), l.kind == LightKind::Sphere || disk),
        ("radius", l.radius.is_some(), l.kind == LightKind::Sphere || disk),
        ("normal", l.normal.is_some(), disk),
        ("inner_radius", l.inner_radius.is_some(), disk),
        ("position", l.position.is_some(), l.kind == LightKind::Point || spot),
        ("vertices", l.vertices.is_some(), area_light),
        ("radiance", l.radiance.is_some(), area_light || disk || at_infinity),
        (
            "two_sided",
            l.two_sided.is_some(),
            area_light || disk || l.kind == LightKind::Sphere,
        ),
        ("power", l.power.is_some(), !at_infinity),
        ("direction", l.direction.is_some(), spot || l.kind == LightKind::Distant),
        ("intensity", l.intensity.is_some(), spot),
        ("cone_angle", l.cone_angle.is_some(), spot),
        ("cone_delta", l.cone_delta.is_some(), spot),
        ("scale", l.scale.is_some(), spot || at_infinity),
        (
            "file",
            l.file.is_some(),
            l.kind == LightKind::Infinite || area_light || l.kind == LightKind::Sphere,
        ),
        ("mapping", l.mapping.is_some(), l.kind == LightKind::Infinite),
        ("rotate", l.rotate.is_some(), l.kind == LightKind::Infinite),
        ("portal", l.portal.is_some(), l.kind == LightKind::Infinite),
        (
            "material",
            l.material.is_some(),
            area_light || disk || l.kind == LightKind::Sphere,
        ),
    ];
    if let Some((key, ..)) = given.iter().find(|(_, given, applies)| *given && !applies) {
        let article = if kind.starts_with(['a', 'e', 'i', 'o', 'u']) {
            "an"
        } else {
            "a"
        };
        return Err(err(format!("`{key}` does not apply to {article} {kind} light")));
    }
    let power = || -> Result<Vec3> {
        let p = l.power.ok_or_else(|| err(format!("{kind} light: missing `power`")))?;
        Ok(colour * p.0)
    };
    // An area light's radiance, given or from its total power over the
    // emitting sides: L = Phi / (pi A sides).
    let area_radiance = |area: f32, two_sided: bool| -> Result<Vec3> {
        match (l.radiance, l.power) {
            (Some(r), None) => {
                if r.0.min_element() < 0.0 {
                    return Err(err(format!("{kind} light: radiance must be >= 0")));
                }
                Ok(r.0 * colour)
            }
            (None, Some(_)) => Ok(power()? / (std::f32::consts::PI * area * if two_sided { 2.0 } else { 1.0 })),
            _ => Err(err(format!("{kind} light: give `radiance` or `power`, one of them"))),
        }
    };
    let scale = l.scale.map_or(1.0, |s| s.0);
    if scale < 0.0 {
        return Err(err(format!("{kind} light: scale {scale} must be >= 0")));
    }
    let direction = || -> Result<Vec3> {
        let d = l
            .direction
            .ok_or_else(|| err(format!("{kind} light: missing `direction`")))?
            .0;
        let n = d.normalize_or_zero();
        if n == Vec3::ZERO {
            return Err(err(format!("{kind} light: direction {:?} has no length", d.to_array())));
        }
        Ok(n)
    };
    // An area light's emission image, which `power` (the flux) then
    // divides `emission` by its mean luminance.
    let light_emission_image = |emission: &mut Vec3| -> Result<Option<std::sync::Arc<crate::light::EmissionImage>>> {
        let Some(file) = &l.file else {
            return Ok(None);
        };
        let image = emission_image(src, file, kind).map_err(err)?;
        if l.power.is_some() {
            let k = crate::math::luminance(image.mean());
            if k <= 0.0 {
                return Err(err(format!("{kind} light: `power` with a black image")));
            }
            *emission /= k;
        }
        Ok(Some(std::sync::Arc::new(image)))
    };
    let non_negative = |key: &str, v: Vec3| -> Result<Vec3> {
        if v.min_element() < 0.0 {
            return Err(err(format!("{kind} light: {key} {:?} must be >= 0", v.to_array())));
        }
        Ok(v)
    };
    match l.kind {
        LightKind::Sphere => {
            let centre = l.centre.ok_or_else(|| err("sphere light: missing `centre`".into()))?.0;
            let radius = l.radius.ok_or_else(|| err("sphere light: missing `radius`".into()))?.0;
            if radius <= 0.0 {
                return Err(err(format!("sphere light: radius {radius} must be > 0")));
            }
            let emits = if l.two_sided.unwrap_or(false) {
                crate::light::Emits::Both
            } else {
                crate::light::Emits::Outwards
            };
            // An image wraps round the world's z axis, as pbrt-v4's sphere
            // coordinates run about its own.
            let mut power = power()?;
            let image = light_emission_image(&mut power)?.map(|image| {
                std::sync::Arc::new(crate::light::ImageOnSphere {
                    image,
                    axes: glam::Mat3::IDENTITY,
                })
            });
            Ok(vec![Light::Sphere {
                sphere: Sphere { centre, radius },
                power,
                image,
                emits,
            }])
        }
        LightKind::Point => {
            let position = l
                .position
                .ok_or_else(|| err("point light: missing `position`".into()))?
                .0;
            Ok(vec![Light::Point {
                position,
                power: power()?,
            }])
        }
        LightKind::Triangle | LightKind::Quad => {
            let tris: Vec<[Vec3; 3]> = if l.kind == LightKind::Triangle {
                vec![points::<3>(l.vertices.as_deref(), "vertices").map_err(|m| err(format!("{kind} light: {m}")))?]
            } else {
                let [a, b, c, d] =
                    points::<4>(l.vertices.as_deref(), "vertices").map_err(|m| err(format!("{kind} light: {m}")))?;
                vec![[a, b, c], [a, c, d]]
            };
            let two_sided = l.two_sided.unwrap_or(false);
            let area: f32 = tris.iter().map(crate::light::triangle_area).sum();
            if !(area > 0.0 && area.is_finite()) {
                return Err(err(format!("{kind} light: its area is zero")));
            }
            let mut radiance = area_radiance(area, two_sided)?;
            let uvs = AREA_LIGHT_UVS;
            let image = light_emission_image(&mut radiance)?;
            Ok(tris
                .into_iter()
                .zip(uvs)
                .map(|(vertices, uv)| Light::Triangle {
                    vertices,
                    radiance,
                    two_sided,
                    image: image
                        .clone()
                        .map(|image| std::sync::Arc::new(crate::light::ImageOnTriangle { image, uv })),
                })
                .collect())
        }
        LightKind::Disk => {
            let centre = l.centre.ok_or_else(|| err("disk light: missing `centre`".into()))?.0;
            let radius = l.radius.ok_or_else(|| err("disk light: missing `radius`".into()))?.0;
            let normal = l.normal.ok_or_else(|| err("disk light: missing `normal`".into()))?.0;
            let inner = l.inner_radius.map_or(0.0, |r| r.0);
            let disk = crate::geometry::Disk::new(centre, normal, radius, inner, None)
                .map_err(|m| err(format!("disk light: {m}")))?;
            let two_sided = l.two_sided.unwrap_or(false);
            Ok(vec![Light::Disk {
                disk,
                radiance: area_radiance(disk.area(), two_sided)?,
                two_sided,
                image: None,
            }])
        }
        LightKind::Spot => {
            let position = l
                .position
                .ok_or_else(|| err("spot light: missing `position`".into()))?
                .0;
            let direction = direction()?;
            let cone_angle = l.cone_angle.map_or(30.0, |a| a.0);
            let cone_delta = l.cone_delta.map_or(5.0, |a| a.0);
            if !(cone_angle > 0.0 && cone_angle <= 180.0) {
                return Err(err(format!(
                    "spot light: cone_angle {cone_angle} must be in (0, 180] degrees"
                )));
            }
            if !(0.0..=cone_angle).contains(&cone_delta) {
                return Err(err(format!(
                    "spot light: cone_delta {cone_delta} must be in [0, cone_angle = {cone_angle}] degrees"
                )));
            }
            let light = Light::spot(position, direction, Vec3::ONE, cone_angle, cone_delta);
            let intensity = match (l.intensity, l.power) {
                (Some(i), None) => non_negative("intensity", i.0)? * colour,
                // The intensity that emits this power (pbrt-v4's `power`).
                (None, Some(_)) => power()? / light.power().x,
                _ => return Err(err("spot light: give `intensity` or `power`, one of them".into())),
            };
            let Light::Spot {
                cos_falloff_start,
                cos_falloff_end,
                ..
            } = light
            else {
                unreachable!()
            };
            Ok(vec![Light::Spot {
                position,
                direction,
                intensity: intensity * scale,
                cos_falloff_start,
                cos_falloff_end,
            }])
        }
        LightKind::Distant => {
            let radiance = non_negative("radiance", l.radiance.map_or(Vec3::ONE, |r| r.0))?;
            Ok(vec![Light::distant(direction()?, radiance * colour * scale)])
        }
        LightKind::Infinite => {
            let rotate = l.rotate.map_or(Vec3::ZERO, |r| r.0);
            let to_world = super::transform::rotation(rotate);
            let map = match &l.file {
                None => {
                    if l.mapping.is_some() {
                        return Err(err("infinite light: `mapping` needs `file`".into()));
                    }
                    None
                }
                Some(file) => {
                    if l.radiance.is_some() {
                        return Err(err("infinite light: give `radiance` or `file`, not both".into()));
                    }
                    Some(std::sync::Arc::new(
                        environment_map(src, file, l.mapping.as_deref()).map_err(err)?,
                    ))
                }
            };
            let radiance = non_negative("radiance", l.radiance.map_or(Vec3::ONE, |r| r.0))?;
            let radiance = radiance * colour * scale;
            let Some(corners) = &l.portal else {
                return Ok(vec![Light::infinite(radiance, map, to_world)]);
            };
            let corners: Vec<Vec3> = corners.iter().map(|c| c.0).collect();
            let Ok(corners) = <[Vec3; 4]>::try_from(corners.as_slice()) else {
                return Err(err(format!(
                    "infinite light: `portal` needs 4 corners, not {}",
                    corners.len()
                )));
            };
            let portal = crate::light::Portal::new(corners, map.as_deref(), to_world)
                .map_err(|e| err(format!("infinite light: {e}")))?;
            Ok(vec![Light::infinite_through(radiance, map, to_world, portal)])
        }
    }
}

/// An infinite light's image, `file` relative to the scene file, read with
/// `image_io` (EXR or PFM); the message of an error names the file.
fn environment_map(
    src: &Source,
    file: &str,
    mapping: Option<&str>,
) -> std::result::Result<crate::light::EnvMap, String> {
    use crate::light::{EnvMap, EnvMapping};
    let mapping = match mapping.unwrap_or("latlong") {
        "latlong" => EnvMapping::LatLong,
        "octahedral" => EnvMapping::Octahedral,
        other => {
            return Err(format!(
                "infinite light: unknown mapping '{other}' (latlong, octahedral)"
            ))
        }
    };
    let img = light_image(src, file, "infinite light: environment map")?;
    EnvMap::new(img.width, img.height, img.pixels(), mapping, file)
        .map_err(|m| format!("infinite light: environment map {}: {m}", img.path.display()))
}

/// An area light's emission image `file`.
fn emission_image(src: &Source, file: &str, kind: &str) -> std::result::Result<crate::light::EmissionImage, String> {
    let what = format!("{kind} light: emission image");
    let img = light_image(src, file, &what)?;
    crate::light::EmissionImage::new(img.width, img.height, img.pixels())
        .map_err(|m| format!("{what} {}: {m}", img.path.display()))
}

/// An image a light reads, `file` beside the scene file: EXR, PFM and
/// Radiance HDR as they are, 8-bit formats (PNG, JPEG, TGA) decoded from
/// sRGB, as pbrt-v4 reads them. Errors start with `what` and the path.
fn light_image(
    src: &Source,
    file: &str,
    what: &str,
) -> std::result::Result<std::sync::Arc<crate::texture::TexImage>, String> {
    let path = src.path.parent().map(Path::to_path_buf).unwrap_or_default().join(file);
    let fail = |m: String| format!("{what} {}: {m}", path.display());
    if !path.is_file() {
        return Err(fail("file not found".into()));
    }
    crate::texture::load_image(&path, crate::texture::Encoding::Srgb).map_err(|e| match e {
        Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => fail("file not found".into()),
        Error::Io { source, .. } => fail(source.to_string()),
        Error::Parse { message, .. } => fail(message),
        e => fail(e.to_string()),
    })
}

#[cfg(test)]
mod tests;
