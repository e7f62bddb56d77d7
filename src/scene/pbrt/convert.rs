//! From a [`PbrtScene`] to this renderer's [`SceneDesc`], for the subset the
//! renderer supports (see `docs/pbrt.md`): a perspective camera (a pinhole
//! or a thin lens, any screen window) and the film's crop,
//! diffuse and smooth dielectric materials, diffuse area lights on triangle
//! meshes, full spheres and disks, point lights, triangle meshes and full spheres,
//! and the film, sampler, filter and integrator as recommended settings.
//!
//! What the scene uses and the renderer cannot render is collected, each at
//! its place (`file:line: ...`), and refused as one error; with `lenient`,
//! unsupported materials become grey diffuse, unsupported shapes and lights
//! are skipped, and one warning per kind says how many. Parameters no
//! conversion read are warnings, as in pbrt-v4.
//!
//! # Conventions
//!
//! * Camera: pbrt-v4's camera space is left-handed (+x right in the image,
//!   +y up, +z forward) and `fov` spans the shorter image axis. The
//!   position and axes come from `world_from_camera`. This renderer's image
//!   right is `forward x up`; when pbrt's image right (camera +x in world
//!   space) is the opposite, pbrt's picture is the mirror image of ours, and
//!   the whole scene is reflected across the camera's vertical plane (the
//!   plane through the camera spanned by its forward and up axes). The
//!   camera is unchanged by that reflection and sees exactly pbrt's picture.
//! * Triangles are wound so that their geometric normal lies on the side of
//!   pbrt's surface normal: for a mesh with normals `N`, the side of the
//!   normals (turned by `ReverseOrientation`, as pbrt-v4's `TriangleMesh`
//!   does; pbrt-v4 turns its geometric normal to them); otherwise the side
//!   of `cross(p1 - p0, p2 - p0)` in world space, turned when
//!   [`Shape::flips_normals`]. A dielectric's inside, an interface's media
//!   and a one-sided area light's emission follow it.
//!   A disk emits on the side of the normal pbrt-v4's `Disk::Intersect`
//!   reports: the transformed +z, turned when [`Shape::flips_normals`].
//!   (pbrt-v4's `Disk::Sample` turns it for `ReverseOrientation` only, so
//!   pbrt itself disagrees with its hits under a handedness-swapping
//!   transformation; we follow what a ray that meets the disk sees.)
//! * A diffuse area light's `power` is met per shape as pbrt-v4 does it: a
//!   mesh is one light per triangle there, so each triangle emits `power`.

use super::error::{Loc, PbrtError};
use super::ir::{Geometry, PbrtScene, Shape, TextureKind};
use super::params::{FloatOrTexture, Param, Params, SpectrumOrTexture};
use super::shapes;
use super::spectrum::{spectrum_to_xyz, xyz_to_linear_srgb, SpectrumValue};
use crate::bsdf::{HairBxdf, MeasuredBxdf, MeasuredData};
use crate::error::{Error, Result};
use crate::geometry::curve::bezier_part;
use crate::geometry::motion::Motion;
use crate::geometry::{Curve, Sphere};
use crate::light::{EmissionImage, Emits, ImageOnSphere, ImageOnTriangle, Light, LightSamplerKind};
use crate::material::{CoatMedium, ConductorFresnel, Material, MaterialRoughness, Roughness};
use crate::math::{Vec2, Vec3};
use crate::medium::{nanovdb, Density, Emission as MediumEmission, Medium, MediumInterface, TemperatureGrid};
use crate::scene::mesh::MeshReport;
use crate::scene::FilmCrop;
use crate::scene::{
    Boundary, CameraDesc, CutShapes, Cutout, FaceUvs, LoadOptions, LoadedScene, SceneDesc, SphereDesc, DEFAULT_UV,
};
use crate::scene::{CurveDesc, DiskDesc, LightSurface, MovingShape, MovingTriangles};
use crate::settings::{Origin, SceneSettings, Value};
use crate::texture::Texture;
use glam::Mat4;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::f32::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// How many unsupported places an error lists before "and N more".
const LISTED: usize = 4;

/// Reads a pbrt-v4 scene file and converts it. The report in
/// `LoadedScene::meshes` names the scene file and carries the warnings.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<LoadedScene> {
    let start = std::time::Instant::now();
    if let Some(m) = &opts.mesh {
        return Err(Error::InvalidSetting(format!(
            "--mesh {}: a pbrt-v4 scene names its own meshes",
            m.display()
        )));
    }
    let scene = super::load(path)?;
    let converted = convert(&scene, path, opts.lenient)?;
    let mut vertices = 0;
    let mut has_normals = false;
    for s in &scene.shapes {
        if let Geometry::Mesh(m) = &s.geometry {
            vertices += m.positions.len();
            has_normals |= m.normals.is_some();
        }
    }
    let report = MeshReport {
        path: path.to_path_buf(),
        vertices,
        triangles: scene.triangle_count(),
        has_normals,
        seconds: start.elapsed().as_secs_f64(),
        warnings: converted.warnings,
    };
    Ok(LoadedScene {
        desc: converted.desc,
        meshes: vec![report],
        fov_axis: crate::scene::FovAxis::Shorter,
        crop: converted.crop,
    })
}

/// A converted scene and what the conversion has to say.
#[derive(Clone, Debug)]
pub struct Converted {
    pub desc: SceneDesc,
    /// One line each, without a `warning: ` prefix.
    pub warnings: Vec<String>,
    /// Whether the scene was reflected to show pbrt's (mirrored) picture.
    pub mirrored: bool,
    /// The part of the frame the film asks for.
    pub crop: Option<FilmCrop>,
}

/// What kind of thing an unsupported feature is, for `--lenient`'s summary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    Material,
    Shape,
    Light,
    Other,
}

#[derive(Clone, Debug)]
struct Problem {
    loc: Loc,
    message: String,
    kind: Kind,
}

/// A diffuse area light, read once for all its shapes.
#[derive(Clone, Debug)]
struct Emission {
    /// Radiance before `power` scaling (`L` times `scale`; with an image,
    /// the image's scale).
    radiance: Vec3,
    /// `power`, when given (> 0).
    power: Option<f32>,
    two_sided: bool,
    /// The emission image (`filename`), read at the shapes' texture
    /// coordinates.
    image: Option<Arc<EmissionImage>>,
}

impl Emission {
    /// The radiance of one shape of `area`: `power`, when given, is met by
    /// it (pbrt-v4's k_e: power / (sides area pi) times `scale`, and over
    /// the image's mean luminance where there is one).
    fn radiance_for(&self, area: f32) -> Vec3 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        let k = self.image.as_ref().map_or(1.0, |im| crate::math::luminance(im.mean()));
        match self.power {
            Some(phi) => self.radiance * (phi / (sides * area * PI * k)),
            None => self.radiance,
        }
    }
}

/// Converts a scene; `path` (the top-level file) names it. Unsupported
/// features are an error unless `lenient`.
pub fn convert(scene: &PbrtScene, path: &Path, lenient: bool) -> Result<Converted> {
    let name = path
        .file_name()
        .map(|s| {
            s.to_string_lossy()
                .trim_end_matches(".gz")
                .trim_end_matches(".pbrt")
                .to_string()
        })
        .unwrap_or_default();
    let mut c = Conv {
        scene,
        problems: vec![],
        warnings: vec![],
        materials: HashMap::new(),
        emissions: HashMap::new(),
        media: HashMap::new(),
        read: vec![],
        skipped_shapes: HashSet::new(),
        replaced_materials: 0,
        skipped_shapes_count: 0,
        skipped_lights: 0,
        dropped_light_triangles: 0,
        emitters_bounding_media: 0,
        emitters_unbumped: 0,
        invisible: false,
        imaging_ratio: 1.0,
        shutter: [0.0, 1.0],
        first_motion: None,
    };
    let (camera, mirror, crop) = c.camera()?;
    let mut desc = SceneDesc::empty(&name, camera);
    desc.shutter = c.shutter;
    if let Some(end) = scene.camera.world_from_camera_end {
        match Motion::new(scene.camera.world_from_camera, end, scene.transform_times) {
            Ok(m) => {
                desc.camera_motion = Some(m);
                c.first_motion = scene.camera.loc.clone();
            }
            Err(why) => {
                let at = scene.camera.loc.clone().unwrap_or_else(|| c.default_loc());
                c.problem(
                    Kind::Other,
                    &at,
                    format!("a moving camera (ActiveTransform): {why}; --lenient uses the start transformation"),
                );
            }
        }
    }
    desc.settings = c.settings()?;
    // Held until the conversion has taken what it needs of them.
    let _images = decode_images(scene);
    c.lights(&mut desc)?;
    c.shapes(&mut desc)?;
    if let Some(name) = &scene.camera.medium {
        let at = scene.camera.loc.clone().unwrap_or_else(|| c.default_loc());
        desc.camera_medium = c.medium(&mut desc, name, &at)?;
    }
    if !desc.media.is_empty() && matches!(scene.integrator.ty.as_str(), "path" | "simplepath") {
        let at = scene.integrator.loc.clone().unwrap_or_else(|| c.default_loc());
        c.warn(
            &at,
            format!(
                "Integrator \"{}\": pbrt-v4's ignores participating media; they are rendered here, as its \"volpath\" renders them",
                scene.integrator.ty
            ),
        );
    }
    // Other integrators than the path tracer are warned of when they render.
    let subsurface = desc.materials.iter().any(|(_, m)| m.has_subsurface());
    if let Some(at) = c.first_motion.clone().filter(|_| subsurface || !desc.media.is_empty()) {
        // Light samples through media and below surfaces see time 0.
        c.problem(
            Kind::Other,
            &at,
            "motion (ActiveTransform) in a scene with participating media or subsurface materials is not supported; --lenient renders it still, at the start transformations",
        );
        desc.moving.clear();
        desc.moving_shapes.clear();
        desc.camera_motion = None;
    }
    if subsurface && matches!(scene.integrator.ty.as_str(), "path" | "simplepath") {
        let at = scene.integrator.loc.clone().unwrap_or_else(|| c.default_loc());
        c.warn(
            &at,
            format!(
                "Integrator \"{}\": pbrt-v4's ignores subsurface scattering (its surface alone is seen); it is rendered here, as its \"volpath\" renders it",
                scene.integrator.ty
            ),
        );
    }
    let portal = desc
        .lights
        .iter()
        .any(|l| matches!(l, Light::Infinite { portal: Some(_), .. }));
    if (!desc.media.is_empty() || portal) && scene.integrator.ty == "bdpt" {
        // Our bidirectional path tracer has no media, nor portals; the path
        // tracer renders them.
        let at = scene.integrator.loc.clone().unwrap_or_else(|| c.default_loc());
        let what = if portal {
            "an infinite light with a portal"
        } else {
            "participating media"
        };
        c.warn(
            &at,
            format!("Integrator \"bdpt\": the scene has {what}, rendered here by the path tracer"),
        );
        desc.settings
            .scene_file
            .set("integrator", Value::Name("path"), origin(&at))
            .map_err(|e| located(&at, e.to_string()))?;
    }
    if c.imaging_ratio != 1.0 {
        // The film scales what it records; the lights scaled instead give the
        // same image, and photon maps with it.
        for l in &mut desc.lights {
            l.scale_emission(c.imaging_ratio);
        }
    }
    for n in &scene.warnings {
        c.warnings.push(format!("{}: {}", n.loc.file_line(), n.message));
    }
    for n in &scene.unsupported {
        let kind = if c.skipped_shapes.contains(&n.loc) {
            Kind::Shape
        } else {
            Kind::Other
        };
        c.problems.push(Problem {
            loc: n.loc.clone(),
            message: n.message.clone(),
            kind,
        });
    }
    c.report_unused();
    if c.emitters_bounding_media > 0 {
        c.warnings.push(format!(
            "{} emitting shapes bound a medium: they reflect nothing here, where pbrt-v4 reflects by their material",
            c.emitters_bounding_media
        ));
    }
    if c.emitters_unbumped > 0 {
        c.warnings.push(format!(
            "{} emitting shapes have a bump or normal map, which is not applied on emitters",
            c.emitters_unbumped
        ));
    }
    if c.dropped_light_triangles > 0 {
        c.warnings.push(format!(
            "{} emitting triangles of zero area dropped",
            c.dropped_light_triangles
        ));
    }
    if !c.problems.is_empty() {
        if !lenient {
            return Err(c.error());
        }
        c.lenient_summary();
    }
    if mirror {
        reflect(&mut desc);
    }
    Ok(Converted {
        desc,
        warnings: c.warnings,
        mirrored: mirror,
        crop,
    })
}

struct Conv<'a> {
    scene: &'a PbrtScene,
    /// pbrt-v4's `exposureTime * ISO / 100`: what the film multiplies radiance by.
    imaging_ratio: f32,
    /// The camera's `shutteropen` and `shutterclose`.
    shutter: [f32; 2],
    /// Where the first motion kept was given.
    first_motion: Option<Loc>,
    problems: Vec<Problem>,
    warnings: Vec<String>,
    /// pbrt material index -> this scene's material index.
    materials: HashMap<usize, u32>,
    /// Area light index -> its emission (None: unsupported, reported).
    emissions: HashMap<usize, Option<Emission>>,
    /// Medium name -> its index in `SceneDesc::media` (None: unsupported,
    /// reported), converted when first named.
    media: HashMap<String, Option<u32>>,
    /// Parameter lists whose unused entries are reported (supported
    /// directives only).
    read: Vec<&'a Params>,
    skipped_shapes: HashSet<Loc>,
    replaced_materials: usize,
    skipped_shapes_count: usize,
    skipped_lights: usize,
    dropped_light_triangles: usize,
    /// Emitting shapes whose material would reflect but that bound a
    /// medium, and those whose material is bumped (warned of once each).
    emitters_bounding_media: usize,
    emitters_unbumped: usize,
    /// Whether the shape being converted is an invisible area light.
    invisible: bool,
}

fn origin(loc: &Loc) -> Origin {
    Origin::SceneFile {
        path: loc.file.as_ref().clone(),
        line: loc.line as usize,
    }
}

/// The place of a parameter if given, else of its directive.
fn place<'p>(params: &'p Params, name: &str, directive: &'p Loc) -> &'p Loc {
    params.loc_of(name).unwrap_or(directive)
}

impl<'a> Conv<'a> {
    /// Adds a light, refusing at its place one that cannot be rendered once
    /// the film's imaging ratio scales it.
    fn push_light(&self, desc: &mut SceneDesc, light: Light, loc: &Loc) -> Result<()> {
        light.check(self.imaging_ratio).map_err(|m| located(loc, m))?;
        desc.lights.push(light);
        Ok(())
    }

    /// Adds an area light, with the surface it reflects by if any.
    fn push_emitter(&self, desc: &mut SceneDesc, light: Light, surface: Option<LightSurface>, loc: &Loc) -> Result<()> {
        self.push_light(desc, light, loc)?;
        if self.invisible {
            desc.invisible_lights.resize(desc.lights.len() - 1, false);
            desc.invisible_lights.push(true);
        }
        if let Some(s) = surface {
            desc.light_surfaces.resize(desc.lights.len() - 1, None);
            desc.light_surfaces.push(Some(s));
        }
        Ok(())
    }

    fn problem(&mut self, kind: Kind, loc: &Loc, message: impl Into<String>) {
        self.problems.push(Problem {
            loc: loc.clone(),
            message: message.into(),
            kind,
        });
    }

    fn warn(&mut self, loc: &Loc, message: impl AsRef<str>) {
        self.warnings.push(format!("{}: {}", loc.file_line(), message.as_ref()));
    }

    /// The error listing every unsupported place, on one line.
    fn error(&self) -> Error {
        let mut problems = self.problems.clone();
        // A file included twice reports each of its places twice: listed once.
        problems.sort_by(|a, b| {
            (a.loc.file.as_ref(), a.loc.line, &a.message).cmp(&(b.loc.file.as_ref(), b.loc.line, &b.message))
        });
        problems.dedup_by(|a, b| a.loc.file == b.loc.file && a.loc.line == b.loc.line && a.message == b.message);
        let first = &problems[0];
        let mut message = first.message.clone();
        for p in problems.iter().skip(1).take(LISTED - 1) {
            message += &format!("; {}: {}", p.loc.file_line(), p.message);
        }
        if problems.len() > LISTED {
            message += &format!("; and {} more", problems.len() - LISTED);
        }
        message += " (not supported: --lenient renders the rest)";
        Error::Syntax {
            path: first.loc.file.as_ref().clone(),
            line: first.loc.line as usize,
            message,
        }
    }

    /// With `--lenient`: one warning per kind of substitution.
    fn lenient_summary(&mut self) {
        let first = |k: Kind| {
            self.problems
                .iter()
                .find(|p| p.kind == k)
                .map(|p| format!("{}: {}", p.loc.file_line(), p.message))
                .unwrap_or_default()
        };
        let others = self.problems.iter().filter(|p| p.kind == Kind::Other).count();
        let lines = [
            (
                self.replaced_materials,
                "materials of unsupported types replaced by grey diffuse (0.5)",
                first(Kind::Material),
            ),
            (
                self.skipped_shapes_count,
                "unsupported shapes skipped",
                first(Kind::Shape),
            ),
            (self.skipped_lights, "unsupported lights skipped", first(Kind::Light)),
            (others, "unsupported features ignored", first(Kind::Other)),
        ];
        for (n, what, example) in lines {
            if n > 0 {
                self.warnings.push(format!("--lenient: {n} {what} (first: {example})"));
            }
        }
    }

    fn report_unused(&mut self) {
        // Shapes of one instance share their parameters: each list once.
        let mut seen = HashSet::new();
        let mut groups: BTreeMap<(String, String), (Loc, usize)> = BTreeMap::new();
        let mut order = vec![];
        // Textures are converted where they are named.
        let textures = self.scene.textures.iter().map(|t| &t.params).filter(|p| p.touched());
        for params in self.read.iter().copied().chain(textures) {
            if !seen.insert(params as *const Params) {
                continue;
            }
            for p in params.unused() {
                let key = (p.ty.name().to_string(), p.name.clone());
                match groups.get_mut(&key) {
                    Some(g) => g.1 += 1,
                    None => {
                        groups.insert(key.clone(), (p.loc.clone(), 1));
                        order.push(key);
                    }
                }
            }
        }
        for key in order {
            let (loc, n) = &groups[&key];
            let more = if *n > 1 {
                format!(" (and {} more places)", n - 1)
            } else {
                String::new()
            };
            self.warn(loc, format!("parameter \"{} {}\" is not used{more}", key.0, key.1));
        }
    }

    // ---- camera and film ---------------------------------------------------

    /// The camera and film, whether pbrt's picture is our mirror image, and
    /// the part of the frame the film asks for.
    fn camera(&mut self) -> Result<(CameraDesc, bool, Option<FilmCrop>)> {
        let scene = self.scene;
        let film = &scene.film;
        let film_loc = film.loc.clone().unwrap_or_else(|| self.default_loc());
        let fp = &film.params;
        if film.ty == "gbuffer" {
            // pbrt-v4's G-buffer film records the same RGB image as "rgb",
            // with the geometry's channels beside it.
            self.warn(
                &film_loc,
                "Film \"gbuffer\": its RGB image is rendered, its geometry channels are not written",
            );
            fp.mark_used("coordinatesystem", super::ParamType::String);
        } else if film.ty != "rgb" {
            self.problem(
                Kind::Other,
                &film_loc,
                format!("Film \"{}\" is not supported (only \"rgb\" and \"gbuffer\")", film.ty),
            );
        }
        let width = fp.get_int("xresolution", 1280)?;
        let height = fp.get_int("yresolution", 720)?;
        if width <= 0 || height <= 0 {
            return Err(located(
                &film_loc,
                format!("Film: resolution {width}x{height} must be positive"),
            ));
        }
        let (width, height) = (width as u32, height as u32);
        crate::limits::check_resolution(width, height).map_err(|m| located(&film_loc, format!("Film: {m}")))?;
        fp.mark_used("filename", super::ParamType::String);
        fp.mark_used("savefp16", super::ParamType::Bool);
        // The film's size in millimetres: only a real lens sees it.
        let diagonal = fp.get_float("diagonal", 35.0)?;
        let crop = self.film_crop(fp, &film_loc, width, height)?;
        // pbrt-v4's imaging ratio: the sensor's sensitivity times the
        // shutter's open time (the camera's), 1 by default.
        let iso = fp.get_float("iso", 100.0)?;
        if !(iso > 0.0 && iso.is_finite()) {
            return Err(located(
                place(fp, "iso", &film_loc),
                format!("Film: iso {iso} must be positive"),
            ));
        }
        self.read.push(fp);

        let cam = &scene.camera;
        let cam_loc = cam.loc.clone().unwrap_or_else(|| self.default_loc());
        let orthographic = cam.ty == "orthographic";
        let realistic = cam.ty == "realistic";
        if !["perspective", "orthographic", "spherical", "realistic"].contains(&cam.ty.as_str()) {
            self.problem(
                Kind::Other,
                &cam_loc,
                format!(
                    "Camera \"{}\" is not supported (\"perspective\", \"orthographic\", \"spherical\" and \"realistic\" are)",
                    cam.ty
                ),
            );
        }
        let cp = &cam.params;
        let lens_system = if realistic {
            Some(self.lens_system(cp, &cam_loc, diagonal)?)
        } else {
            None
        };
        let spherical = if cam.ty == "spherical" {
            let name = cp.get_string_or("mapping", "equalarea")?;
            let Some(m) = crate::camera::SphericalMapping::parse(&name) else {
                return Err(located(
                    place(cp, "mapping", &cam_loc),
                    format!("Camera \"spherical\": unknown mapping \"{name}\" (\"equalarea\" or \"equirectangular\")"),
                ));
            };
            Some(m)
        } else {
            None
        };
        // Orthographic, spherical and realistic cameras have no field of
        // view (pbrt-v4 reads none).
        let fov = if orthographic || spherical.is_some() || realistic {
            90.0
        } else {
            cp.get_float("fov", 90.0)?
        };
        if !(fov > 0.0 && fov < 180.0) {
            return Err(located(
                &cam_loc,
                format!("Camera: fov {fov} must be in (0, 180) degrees"),
            ));
        }
        let window = cam.screen_window(width, height)?;
        let frame = width as f32 / height as f32;
        let default = if frame > 1.0 {
            [-frame, frame, -1.0, 1.0]
        } else {
            [-1.0, 1.0, -1.0 / frame, 1.0 / frame]
        };
        // A window of the file's own (an off-centre or stretched projection),
        // else the film's, which follows the image's shape when resized.
        // pbrt-v4's spherical camera reads a window and ignores it; a real
        // lens has none.
        let own_window = spherical.is_none()
            && !realistic
            && window
                .iter()
                .zip(default)
                .any(|(a, b)| (a - b).abs() > 1e-4 * b.abs().max(1.0));
        if own_window && !(window.iter().all(|v| v.is_finite()) && window[0] != window[1] && window[2] != window[3]) {
            let p = if cp.has("screenwindow") {
                "screenwindow"
            } else {
                "frameaspectratio"
            };
            return Err(located(
                place(cp, p, &cam_loc),
                format!("Camera: the screen window {window:?} is empty or not finite"),
            ));
        }
        let (lens_radius, focal_distance) = if realistic {
            (0.0, 1e6)
        } else {
            (cp.get_float("lensradius", 0.0)?, cp.get_float("focaldistance", 1e6)?)
        };
        if orthographic && lens_radius > 0.0 {
            // pbrt-v4's orthographic lens starts every ray about the camera's
            // centre instead of its point of the image plane: refused rather
            // than copied or silently changed.
            self.problem(
                Kind::Other,
                place(cp, "lensradius", &cam_loc),
                "Camera \"orthographic\": a lens (\"lensradius\" > 0) is not supported",
            );
        }
        if lens_radius < 0.0 || lens_radius.is_nan() {
            return Err(located(
                place(cp, "lensradius", &cam_loc),
                format!("Camera: lensradius {lens_radius} must be >= 0 (0: a pinhole)"),
            ));
        }
        // pbrt-v4's spherical camera reads a lens and ignores it too.
        let lens_radius = if orthographic || spherical.is_some() {
            0.0
        } else {
            lens_radius
        };
        if lens_radius > 0.0 && !(lens_radius.is_finite() && focal_distance > 0.0 && focal_distance.is_finite()) {
            return Err(located(
                place(cp, "focaldistance", &cam_loc),
                format!(
                    "Camera: lens radius {lens_radius} and focal distance {focal_distance} must be finite and positive"
                ),
            ));
        }
        let open = cp.get_float("shutteropen", 0.0)?;
        let close = cp.get_float("shutterclose", 1.0)?;
        let exposure_time = close - open;
        if !(exposure_time > 0.0 && exposure_time.is_finite()) {
            return Err(located(
                place(cp, "shutterclose", &cam_loc),
                format!("Camera: the shutter closes at {close}, not after it opens at {open}"),
            ));
        }
        self.imaging_ratio = exposure_time * iso / 100.0;
        self.shutter = [open, close];
        self.read.push(cp);

        // pbrt's camera axes in world space.
        let m = cam.world_from_camera;
        let position = m.transform_point3(Vec3::ZERO);
        let x = m.transform_vector3(Vec3::X);
        let y = m.transform_vector3(Vec3::Y);
        let z = m.transform_vector3(Vec3::Z);
        let (lx, ly, lz) = (x.length(), y.length(), z.length());
        let orthogonal = x.dot(y).abs() <= 1e-4 * lx * ly
            && x.dot(z).abs() <= 1e-4 * lx * lz
            && y.dot(z).abs() <= 1e-4 * ly * lz
            && (lx - ly).abs() <= 1e-4 * lx.max(ly)
            && m.row(3).abs_diff_eq(glam::Vec4::W, 1e-6);
        if !(orthogonal && lx > 0.0 && lz > 0.0 && position.is_finite()) {
            return Err(located(
                &cam_loc,
                "Camera: the camera transformation shears, scales x and y differently or projects: not supported",
            ));
        }
        let (forward, up) = (z / lz, y / ly);
        // pbrt's ray through screen point (sx, sy) goes along sx t X + sy t Y + Z.
        let tan = (fov.to_radians() * 0.5).tan() * lx / lz;
        // Orthographic: a unit of the screen window is one of camera space,
        // lx world units (the default window spans [-1, 1] on the shorter axis).
        let (ortho_unit, ortho_y) = (
            lx,
            if width >= height {
                lx
            } else {
                lx * height as f32 / width as f32
            },
        );
        let orthographic = orthographic.then_some(if own_window { ortho_unit } else { ortho_y });
        let (fov_y_deg, window) = if own_window {
            // The window in units of t itself.
            let [left, right, bottom, top] = window;
            (
                2.0 * tan.atan().to_degrees(),
                Some(crate::camera::ScreenWindow {
                    left,
                    right,
                    bottom,
                    top,
                }),
            )
        } else {
            let tan_y = if width >= height {
                tan
            } else {
                tan * height as f32 / width as f32
            };
            (2.0 * tan_y.atan().to_degrees(), None)
        };
        // pbrt's lens lies in camera space's xy plane and focuses at camera z
        // = focaldistance: world lengths lx and lz times those.
        let lens = (lens_radius > 0.0).then_some(crate::camera::ThinLens {
            radius: lens_radius * lx,
            focal_distance: focal_distance * lz,
        });
        if lens.is_some_and(|l| !l.is_valid()) {
            return Err(located(
                place(cp, "lensradius", &cam_loc),
                "Camera: the lens is degenerate under the camera transformation",
            ));
        }
        let mirror = forward.cross(up).dot(x) < 0.0;
        let realistic = match lens_system {
            Some(mut l) => {
                // The lens' metres are camera space's units: lx world units.
                if (lz - lx).abs() > 1e-4 * lx.max(lz) {
                    return Err(located(
                        &cam_loc,
                        "Camera \"realistic\": the camera transformation scales z apart from x and y: not supported",
                    ));
                }
                l.scale = lx as f64;
                Some(std::sync::Arc::new(l))
            }
            None => None,
        };
        Ok((
            CameraDesc {
                position,
                look_at: position + forward,
                up,
                fov_y_deg,
                width,
                height,
                window,
                lens,
                orthographic,
                spherical,
                realistic,
            },
            mirror,
            crop,
        ))
    }

    /// pbrt-v4's `RealisticCamera`: the prescription in `lensfile` (found
    /// as other files are), stopped to `aperturediameter` mm (1), focused at
    /// `focusdistance` (10), over a film `diagonal` mm across, with a
    /// diaphragm of `aperture`'s shape (a built-in name or a grey image).
    fn lens_system(&mut self, cp: &Params, cam_loc: &Loc, diagonal: f32) -> Result<crate::camera::LensSystem> {
        use crate::camera::{Aperture, LensSystem};
        let scene = self.scene;
        let at = place(cp, "lensfile", cam_loc).clone();
        let Some(file) = cp.get_string("lensfile")? else {
            return Err(located(
                cam_loc,
                "Camera \"realistic\": no \"lensfile\" was given".to_string(),
            ));
        };
        let Some(path) = scene.candidates(&at, &file).into_iter().find(|c| c.is_file()) else {
            return Err(located(
                &at,
                format!("Camera \"realistic\": lens file \"{file}\" not found"),
            ));
        };
        let bytes = crate::scene::mesh::FileSource::read(&crate::scene::mesh::Disk, &path)
            .map_err(|e| located(&at, format!("Camera \"realistic\": {e}")))?;
        let text = String::from_utf8_lossy(&bytes);
        let rows = crate::camera::lens_system::parse_prescription(&text)
            .map_err(|(line, m)| located(&at, format!("Camera \"realistic\": {}:{line}: {m}", path.display())))?;
        let aperture_diameter = cp.get_float("aperturediameter", 1.0)?;
        let focus_distance = cp.get_float("focusdistance", 10.0)?;
        let aperture = match cp.get_string("aperture")? {
            None => None,
            Some(name) if name.is_empty() => None,
            Some(name) => {
                let at = place(cp, "aperture", cam_loc).clone();
                let a = match Aperture::builtin(&name) {
                    Some(a) => Some(a),
                    None => {
                        let Some(path) = scene.candidates(&at, &name).into_iter().find(|c| c.is_file()) else {
                            return Err(located(
                                &at,
                                format!(
                                    "Camera \"realistic\": aperture \"{name}\" is neither a built-in shape (gaussian, square, pentagon, star) nor a file found"
                                ),
                            ));
                        };
                        let img = crate::texture::load_image(&path, crate::texture::Encoding::Srgb)
                            .map_err(|e| located(&at, format!("Camera \"realistic\": aperture: {e}")))?;
                        let grey = img.pixels().iter().map(|p| (p.x + p.y + p.z) / 3.0).collect();
                        Aperture::normalized(&name, img.width as usize, img.height as usize, grey)
                    }
                };
                Some(a.ok_or_else(|| {
                    located(
                        &at,
                        format!("Camera \"realistic\": aperture \"{name}\" lets no light through"),
                    )
                })?)
            }
        };
        let name = path
            .file_name()
            .map_or(file.clone(), |n| n.to_string_lossy().into_owned());
        let (lens, clamped) = LensSystem::new(&name, &rows, aperture_diameter, focus_distance, diagonal, aperture)
            .map_err(|m| located(&at, format!("Camera \"realistic\": {}: {m}", path.display())))?;
        if let Some(max) = clamped {
            self.warn(
                place(cp, "aperturediameter", cam_loc),
                format!(
                    "Camera \"realistic\": aperturediameter {aperture_diameter} mm is larger than the lens' stop ({max} mm): the stop's is used"
                ),
            );
        }
        Ok(lens)
    }

    /// The part of the frame the film asks for: `cropwindow` (fractions of
    /// the frame) or `pixelbounds` (pixels), as pbrt-v4's `FilmBaseParameters`
    /// reads them: the crop window wins when both are given (a warning),
    /// each is clamped to the frame (pixel bounds beyond it with a warning),
    /// and an empty result is an error.
    fn film_crop(&mut self, fp: &Params, film_loc: &Loc, width: u32, height: u32) -> Result<Option<FilmCrop>> {
        let cr = fp.get_floats("cropwindow");
        let pb = fp.get_ints("pixelbounds");
        let crop = if !cr.is_empty() {
            let loc = place(fp, "cropwindow", film_loc).clone();
            if cr.len() != 4 || cr.iter().any(|v| !v.is_finite()) {
                return Err(located(
                    &loc,
                    format!("Film: \"cropwindow\" needs four finite numbers, not {cr:?}"),
                ));
            }
            if !pb.is_empty() {
                self.warn(
                    &loc,
                    "Film: both \"pixelbounds\" and \"cropwindow\" given: the crop window is used",
                );
            }
            let c = |v: f32| v.clamp(0.0, 1.0);
            FilmCrop::Window([
                c(cr[0].min(cr[1])),
                c(cr[0].max(cr[1])),
                c(cr[2].min(cr[3])),
                c(cr[2].max(cr[3])),
            ])
        } else if !pb.is_empty() {
            let loc = place(fp, "pixelbounds", film_loc).clone();
            if pb.len() != 4 {
                return Err(located(
                    &loc,
                    format!("Film: \"pixelbounds\" needs four integers, not {}", pb.len()),
                ));
            }
            let clamp = |v: i32, hi: u32| v.clamp(0, hi as i32) as u32;
            let b = [
                clamp(pb[0], width),
                clamp(pb[1], width),
                clamp(pb[2], height),
                clamp(pb[3], height),
            ];
            if b.iter().zip(pb).any(|(&c, &v)| c as i64 != v as i64) {
                self.warn(&loc, "Film: \"pixelbounds\" reach beyond the image: clamped to it");
            }
            FilmCrop::Pixels {
                bounds: b,
                size: (width, height),
            }
        } else {
            return Ok(None);
        };
        if crop.rect(width, height).is_none() {
            let p = if cr.is_empty() { "pixelbounds" } else { "cropwindow" };
            return Err(located(
                place(fp, p, film_loc),
                format!("Film: \"{p}\" leaves no pixel of the {width}x{height} image"),
            ));
        }
        Ok(Some(crop))
    }

    /// Where defaults "are": line 1 of the top-level file.
    fn default_loc(&self) -> Loc {
        let file = self.scene.files.first().cloned().unwrap_or_default();
        Loc::new(std::sync::Arc::new(file), 1, 1)
    }

    // ---- settings ----------------------------------------------------------

    /// The render settings the file asks for (scene layer) and pbrt-v4's
    /// defaults for what it does not say (preset layer).
    fn settings(&mut self) -> Result<SceneSettings> {
        let scene = self.scene;
        let mut out = SceneSettings::default();
        let defaults = Origin::Preset("pbrt-v4 defaults".into());
        // A value no setting can take (no pixel samples, a clamp of 0) is
        // an error of the file, named where it is written, lenient or not.
        let mut invalid: Option<Error> = None;
        let mut set = |_: &mut Self, given: Option<&Loc>, name: &str, value: Value| {
            let (layer, o) = match given {
                Some(l) => (&mut out.scene_file, origin(l)),
                None => (&mut out.preset, defaults.clone()),
            };
            if let Err(e) = layer.set(name, value, o) {
                invalid.get_or_insert(Error::Setting(e));
            }
        };

        // Sampler.
        let s = &scene.sampler;
        let sp = &s.params;
        let (spp, counts) = if s.ty == "stratified" {
            let (x, y) = (sp.get_int("xsamples", 4)?, sp.get_int("ysamples", 4)?);
            (
                x as i64 * y as i64,
                (x < 0 || y < 0).then(|| format!("xsamples {x}, ysamples {y}")),
            )
        } else {
            let n = sp.get_int("pixelsamples", 16)?;
            (n as i64, (n < 0).then(|| format!("pixelsamples {n}")))
        };
        let spp_loc = sp
            .loc_of("pixelsamples")
            .or(sp.loc_of("xsamples"))
            .or(s.loc.as_ref())
            .cloned();
        if let Some(counts) = counts {
            let at = spp_loc.clone().unwrap_or_else(|| self.default_loc());
            // (A count of 0 is the settings' to refuse, with their range.)
            return Err(located(&at, format!("Sampler: {counts}: must be at least 1")));
        }
        set(self, spp_loc.as_ref(), "spp", Value::Int(spp.max(0) as u64));
        // pbrt-v4's samplers onto ours: its default and Z-order `zsobol`;
        // the other low-discrepancy ones onto the per-pixel Sobol points; the
        // random and jittered ones onto independent samples (a grid when
        // the count is a square).
        let sampler = match s.ty.as_str() {
            "zsobol" => "zsobol",
            "independent" | "stratified" => "independent",
            "sobol" | "paddedsobol" | "halton" | "pmj02bn" => "sobol",
            other => {
                self.warn(
                    s.loc.as_ref().unwrap_or(&self.default_loc()),
                    format!("Sampler \"{other}\" is not supported: sobol is used"),
                );
                "sobol"
            }
        };
        set(self, s.loc.as_ref(), "sampler", Value::Name(sampler));
        let seed = sp.get_int("seed", 0)?;
        if let Some(l) = sp.loc_of("seed").cloned() {
            set(self, Some(&l), "seed", Value::Int(seed.max(0) as u64));
        } else if let Some(o) = scene.options.iter().rev().find(|o| o.name == "seed") {
            // pbrt-v4's samplers default their seed to the `seed` option.
            match o.value.parse::<i64>() {
                Ok(v) => set(self, Some(&o.loc), "seed", Value::Int(v.max(0) as u64)),
                Err(_) => {
                    return Err(located(
                        &o.loc,
                        format!("Option \"seed\": {} is not an integer", o.value),
                    ))
                }
            }
        }
        for (name, ty) in [
            ("jitter", super::ParamType::Bool),
            ("randomization", super::ParamType::String),
        ] {
            sp.mark_used(name, ty);
        }
        // The film's clamp of each sample (pbrt-v4: infinite by default).
        let fp = &scene.film.params;
        if let Some(l) = fp.loc_of("maxcomponentvalue").cloned() {
            let max = fp.get_float("maxcomponentvalue", f32::INFINITY)?;
            if max < f32::MAX {
                set(self, Some(&l), "max_component", Value::Real(max));
            }
        }
        // The film's sensor: pbrt-v4's CIE 1931 observer unless a camera is
        // named, balanced to white at `whitebalance` kelvin (a named camera
        // at 6500 K unless given, which the sensor's matrix assumes).
        let sensor = fp.get_string_or("sensor", crate::sensor::OBSERVER)?;
        let kelvin = fp.get_float("whitebalance", 0.0)?;
        let kelvin_loc = fp.loc_of("whitebalance").cloned();
        if sensor != crate::sensor::OBSERVER {
            let at = fp
                .loc_of("sensor")
                .or(scene.film.loc.as_ref())
                .cloned()
                .unwrap_or_else(|| self.default_loc());
            match crate::sensor::SENSORS.iter().find(|&&s| s == sensor) {
                Some(&name) => set(self, Some(&at), "sensor", Value::Name(name)),
                // pbrt-v4 stops on a name it does not know.
                None => {
                    return Err(located(
                        &at,
                        format!(
                            "Film: unknown camera sensor \"{sensor}\" (known: {})",
                            crate::sensor::SENSORS.join(", ")
                        ),
                    ))
                }
            }
        }
        if kelvin != 0.0 {
            set(self, kelvin_loc.as_ref(), "white_balance", Value::Real(kelvin));
        }
        self.read.push(sp);

        // Pixel filter.
        let f = &scene.filter;
        let fp = &f.params;
        let floc = f.loc.clone().unwrap_or_else(|| self.default_loc());
        let (ours, default_radius) = match f.ty.as_str() {
            "box" => ("box", 0.5),
            "triangle" => ("tent", 2.0),
            "gaussian" => ("gaussian", 1.5),
            other => {
                self.warn(
                    &floc,
                    format!("PixelFilter \"{other}\" is not supported: the gaussian filter is used"),
                );
                ("gaussian", 1.5)
            }
        };
        let xr = fp.get_float("xradius", default_radius)?;
        let yr = fp.get_float("yradius", default_radius)?;
        let sigma = fp.get_float("sigma", 0.5)?;
        let ours_radius = match ours {
            "box" => 0.5,
            "tent" => 1.0,
            _ => 1.5,
        };
        let known = f.ty == ours || f.ty == "triangle";
        if known && (xr != ours_radius || yr != ours_radius || (ours == "gaussian" && sigma != 0.5)) {
            {
                self.warn(
                    &floc,
                    format!(
                        "PixelFilter \"{}\" of radius {xr} x {yr}{}: rendered with radius {ours_radius}{}",
                        f.ty,
                        if ours == "gaussian" {
                            format!(", sigma {sigma}")
                        } else {
                            String::new()
                        },
                        if ours == "gaussian" { ", sigma 0.5" } else { "" }
                    ),
                );
            }
        }
        for n in ["B", "C", "tau"] {
            fp.mark_used(n, super::ParamType::Float);
        }
        set(self, f.loc.as_ref(), "filter", Value::Name(ours));
        self.read.push(fp);

        // Integrator.
        let i = &scene.integrator;
        let ip = &i.params;
        let iloc = i.loc.clone().unwrap_or_else(|| self.default_loc());
        let depth_loc = ip.loc_of("maxdepth").cloned();
        let max_depth = ip.get_int("maxdepth", 5)?;
        if max_depth < 0 {
            let at = depth_loc.clone().unwrap_or_else(|| iloc.clone());
            return Err(located(&at, format!("Integrator: maxdepth {max_depth} must be >= 0")));
        }
        match i.ty.as_str() {
            "path" | "volpath" | "bdpt" | "mlt" | "simplepath" | "simplevolpath" | "randomwalk" | "lightpath" => {
                let ours = if i.ty == "bdpt" { "bdpt" } else { "path" };
                set(self, i.loc.as_ref(), "integrator", Value::Name(ours));
                set(
                    self,
                    depth_loc.as_ref().or(i.loc.as_ref()),
                    "max_depth",
                    Value::Int(max_depth.max(0) as u64),
                );
                // Photon mapping asked for on the scene follows its depth
                // too, as its SPPM does: photon paths cut at our default of
                // five hits left `cornell-box` 3% dark (BENCHMARKS.md,
                // "Bitterli's scenes").
                set(
                    self,
                    depth_loc.as_ref().or(i.loc.as_ref()),
                    "max_bounces",
                    Value::Int(max_depth.clamp(1, 100) as u64),
                );
                // pbrt-v4's path, volpath, bdpt and mlt regularize when asked.
                if matches!(i.ty.as_str(), "path" | "volpath" | "bdpt" | "mlt") && ip.get_bool("regularize", false)? {
                    set(
                        self,
                        ip.loc_of("regularize").or(i.loc.as_ref()),
                        "regularize",
                        Value::Bool(true),
                    );
                }
            }
            "sppm" => {
                set(self, i.loc.as_ref(), "integrator", Value::Name("sppm"));
                let passes = ip.get_int("iterations", ip.get_int("numiterations", 64)?)?;
                let at = |n: &str| ip.loc_of(n).cloned();
                let passes_loc = at("iterations").or(at("numiterations"));
                set(self, passes_loc.as_ref(), "passes", Value::Int(passes.max(0) as u64));
                let photons = ip.get_int("photonsperiteration", -1)?;
                let photons = if photons > 0 {
                    photons as u64
                } else {
                    self.scene_pixels()
                };
                set(self, at("photonsperiteration").as_ref(), "photons", Value::Int(photons));
                let radius = ip.get_float("radius", 1.0)?;
                set(self, at("radius").as_ref(), "gather_radius", Value::Real(radius));
                set(
                    self,
                    depth_loc.as_ref(),
                    "max_bounces",
                    Value::Int(max_depth.clamp(1, 100) as u64),
                );
                if !(1..=100).contains(&max_depth) {
                    self.warn(
                        &iloc,
                        format!("Integrator \"sppm\": maxdepth {max_depth} clamped to 1..100"),
                    );
                }
                ip.mark_used("seed", super::ParamType::Integer);
            }
            other => {
                self.problem(Kind::Other, &iloc, format!("Integrator \"{other}\" is not supported"));
                set(self, Some(&iloc), "integrator", Value::Name("path"));
            }
        }
        // pbrt-v4's light samplers; its default is the tree.
        let at = ip.loc_of("lightsampler").or(i.loc.as_ref()).cloned();
        let chosen = match ip.get_string_or("lightsampler", "bvh")?.as_str() {
            "exhaustive" => {
                self.warn(
                    place(ip, "lightsampler", &iloc),
                    "Integrator: lightsampler \"exhaustive\" is rendered with \"bvh\"",
                );
                "bvh"
            }
            name => match LightSamplerKind::from_name(name) {
                Some(kind) => kind.name(),
                None => {
                    return Err(located(
                        place(ip, "lightsampler", &iloc),
                        format!("Integrator: unknown lightsampler \"{name}\" (uniform, power, bvh, exhaustive)"),
                    ))
                }
            },
        };
        set(self, at.as_ref(), "light_sampler", Value::Name(chosen));
        self.read.push(ip);
        for o in scene.options.iter().filter(|o| o.name != "seed") {
            self.warn(&o.loc, format!("Option \"{}\" is ignored", o.name));
        }
        if let Some(e) = invalid {
            return Err(e);
        }
        Ok(out)
    }

    fn scene_pixels(&self) -> u64 {
        let p = &self.scene.film.params;
        let w = p.get_int("xresolution", 1280).unwrap_or(1280).max(1) as u64;
        let h = p.get_int("yresolution", 720).unwrap_or(720).max(1) as u64;
        w * h
    }

    // ---- lights ------------------------------------------------------------

    fn lights(&mut self, desc: &mut SceneDesc) -> Result<()> {
        let scene = self.scene;
        for l in &scene.lights {
            let p = &l.params;
            match l.ty.as_str() {
                "point" => {
                    let Some(i) = self.light_colour(p, "I", &l.loc)? else {
                        self.skipped_lights += 1;
                        continue;
                    };
                    let scale = p.get_float("scale", 1.0)?;
                    let from = p.get_point3("from", Vec3::ZERO)?;
                    let position = l.world_from_light.transform_point3(from);
                    let mut power = i * scale * 4.0 * PI;
                    let phi = p.get_float("power", -1.0)?;
                    if phi > 0.0 {
                        power = i * scale * phi;
                    }
                    self.push_light(desc, Light::Point { position, power }, &l.loc)?;
                    self.read.push(p);
                }
                "spot" => {
                    let Some(i) = self.light_colour(p, "I", &l.loc)? else {
                        self.skipped_lights += 1;
                        continue;
                    };
                    let mut scale = p.get_float("scale", 1.0)?;
                    let cone_angle = p.get_float("coneangle", 30.0)?;
                    let cone_delta = p.get_float("conedelta", 5.0)?;
                    let from = p.get_point3("from", Vec3::ZERO)?;
                    let to = p.get_point3("to", Vec3::Z)?;
                    let m = l.world_from_light;
                    let position = m.transform_point3(from);
                    let direction = m.transform_vector3(to - from);
                    if !(direction.length() > 0.0 && direction.is_finite() && position.is_finite()) {
                        return Err(located(&l.loc, "spot: \"from\" and \"to\" must differ"));
                    }
                    if !(cone_angle > 0.0 && cone_angle <= 180.0 && (0.0..=cone_angle).contains(&cone_delta)) {
                        return Err(located(
                            &l.loc,
                            format!("spot: coneangle {cone_angle} and conedelta {cone_delta} out of range"),
                        ));
                    }
                    let phi = p.get_float("power", -1.0)?;
                    if phi > 0.0 {
                        // pbrt-v4: the power of intensity 1 over the cone and its falloff.
                        let cos_end = cone_angle.to_radians().cos();
                        let cos_start = (cone_angle - cone_delta).to_radians().cos();
                        let k_e = 2.0 * PI * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0);
                        scale *= phi / k_e;
                    }
                    let spot = Light::spot(position, direction, i * scale, cone_angle, cone_delta);
                    self.push_light(desc, spot, &l.loc)?;
                    self.read.push(p);
                }
                "distant" => {
                    let Some(radiance) = self.light_colour(p, "L", &l.loc)? else {
                        self.skipped_lights += 1;
                        continue;
                    };
                    let mut scale = p.get_float("scale", 1.0)?;
                    let from = p.get_point3("from", Vec3::ZERO)?;
                    let to = p.get_point3("to", Vec3::Z)?;
                    // pbrt-v4: light arrives from (from - to), so it travels along to - from.
                    let direction = l.world_from_light.transform_vector3(to - from);
                    if !(direction.length() > 0.0 && direction.is_finite()) {
                        return Err(located(&l.loc, "distant: \"from\" and \"to\" must differ"));
                    }
                    let e = p.get_float("illuminance", -1.0)?;
                    if e > 0.0 {
                        scale *= e;
                    }
                    self.push_light(desc, Light::distant(direction, radiance * scale), &l.loc)?;
                    self.read.push(p);
                }
                kind @ ("goniometric" | "projection" | "infinite") => {
                    let light = match kind {
                        "infinite" => self.infinite(l)?,
                        "goniometric" => self.goniometric(l)?,
                        _ => self.projection(l)?,
                    };
                    if let Some(light) = light {
                        self.push_light(desc, light, &l.loc)?;
                        self.read.push(p);
                    } else {
                        self.skipped_lights += 1;
                    }
                }
                other => {
                    self.problem(Kind::Light, &l.loc, format!("light \"{other}\" is not supported"));
                    self.skipped_lights += 1;
                }
            }
        }
        Ok(())
    }

    /// pbrt-v4's `goniometric` light: a point at the light's origin whose
    /// intensity `I` times `scale` (or set by `power`) is modulated by the
    /// equal-area image `filename` (its channels averaged), read at the
    /// direction in the light's frame with y and z exchanged (pbrt-v4's
    /// convention: the image's +z is the frame's +y); None when unsupported
    /// (reported).
    fn goniometric(&mut self, l: &super::ir::Light) -> Result<Option<Light>> {
        use crate::light::{EnvMap, EnvMapping};
        let p = &l.params;
        let Some(i) = self.light_colour(p, "I", &l.loc)? else {
            return Ok(None);
        };
        let mut scale = p.get_float("scale", 1.0)?;
        let Some((film, file, at, from_light)) = self.light_image(l, "goniometric")? else {
            return Ok(None);
        };
        let grey = film
            .pixels
            .iter()
            .map(|c| Vec3::splat((c.x + c.y + c.z) / 3.0))
            .collect();
        let map = EnvMap::new(film.width, film.height, grey, EnvMapping::Octahedral, &file)
            .map_err(|e| located(&at, format!("goniometric: image \"{file}\": {e}")))?;
        let phi = p.get_float("power", -1.0)?;
        if phi > 0.0 {
            // The power of intensity 1: 4 pi times the image's mean.
            let k = map.integral().x;
            if k <= 0.0 {
                return Err(located(
                    place(p, "power", &l.loc),
                    format!("goniometric: \"power\": image \"{file}\" is black"),
                ));
            }
            scale *= phi / k;
        }
        // World directions into the image's frame: the light's turn undone,
        // then y and z exchanged.
        let swap_yz = glam::Mat3::from_cols(Vec3::X, Vec3::Z, Vec3::Y);
        let to_light = swap_yz * from_light;
        Ok(Some(Light::Goniometric {
            position: l.world_from_light.transform_point3(Vec3::ZERO),
            intensity: i * scale,
            to_light,
            map: std::sync::Arc::new(map),
        }))
    }

    /// What goniometric and projection lights share: their image (its
    /// file name and place) and the turn from world directions into the
    /// light's frame; None when the light's transformation is more than a
    /// rotation and uniform scale (reported).
    fn light_image(
        &mut self,
        l: &super::ir::Light,
        kind: &str,
    ) -> Result<Option<(crate::film::Film, String, Loc, glam::Mat3)>> {
        let p = &l.params;
        let turn = glam::Mat3::from_mat4(l.world_from_light);
        let Some((_, s)) = similarity(Mat4::from_mat3(turn)) else {
            self.problem(
                Kind::Light,
                &l.loc,
                format!("{kind}: a transformation other than rotation and uniform scale is not supported"),
            );
            return Ok(None);
        };
        let Some(file) = p.get_string("filename")? else {
            return Err(located(&l.loc, format!("{kind}: \"filename\" is required")));
        };
        let at = place(p, "filename", &l.loc).clone();
        let film = self.read_light_image(&at, &file, kind)?;
        Ok(Some((film, file, at, (turn * (1.0 / s)).transpose())))
    }

    /// The image `file` a light of `kind` names at `at`, found as meshes
    /// and includes are, read as pbrt-v4 reads it: EXR, PFM and Radiance HDR
    /// as they are, 8-bit formats (PNG, JPEG, TGA) decoded from sRGB.
    fn read_light_image(&self, at: &Loc, file: &str, kind: &str) -> Result<crate::film::Film> {
        let Some(path) = self.scene.candidates(at, file).into_iter().find(|c| c.is_file()) else {
            // With the column, as a missing mesh or include is reported.
            return Err(PbrtError::at(at, format!("{kind}: image \"{file}\" not found")).into());
        };
        let img = crate::texture::load_image(&path, crate::texture::Encoding::Srgb)
            .map_err(|e| located(at, format!("{kind}: image \"{file}\": {e}")))?;
        let mut film = crate::film::Film::new(img.width, img.height);
        film.pixels = img.pixels();
        Ok(film)
    }

    /// pbrt-v4's `projection` light: a point at the light's origin casting
    /// the image `filename` over a frustum of `fov` degrees (90) about the
    /// light's +z, its y flipped so that the image stands upright, times
    /// `scale` (or set by `power`, the image's luminous power); None when
    /// unsupported (reported).
    fn projection(&mut self, l: &super::ir::Light) -> Result<Option<Light>> {
        let p = &l.params;
        let mut scale = p.get_float("scale", 1.0)?;
        let fov = p.get_float("fov", 90.0)?;
        let Some((film, file, at, from_light)) = self.light_image(l, "projection")? else {
            return Ok(None);
        };
        let projector = crate::light::Projector::new(film.width, film.height, film.pixels, fov).map_err(|e| {
            let at = if e.starts_with("fov") {
                place(p, "fov", &l.loc)
            } else {
                &at
            };
            located(at, format!("projection: {e}"))
        })?;
        let phi = p.get_float("power", -1.0)?;
        if phi > 0.0 {
            let k = projector.luminous_power();
            if k <= 0.0 {
                return Err(located(
                    place(p, "power", &l.loc),
                    format!("projection: \"power\": image \"{file}\" is black"),
                ));
            }
            scale *= phi / k;
        }
        let flip_y = glam::Mat3::from_diagonal(Vec3::new(1.0, -1.0, 1.0));
        Ok(Some(Light::Projection {
            position: l.world_from_light.transform_point3(Vec3::ZERO),
            intensity: Vec3::splat(scale),
            to_light: flip_y * from_light,
            projector: std::sync::Arc::new(projector),
        }))
    }

    /// pbrt-v4's `infinite` light: constant `L`, or an equal-area
    /// octahedral image `filename`, times `scale`, turned by the light's
    /// transformation (a rotation, possibly with uniform scale); None when
    /// unsupported (reported).
    fn infinite(&mut self, l: &super::ir::Light) -> Result<Option<Light>> {
        use crate::light::{EnvMap, EnvMapping};
        let p = &l.params;
        let mut scale = p.get_float("scale", 1.0)?;
        // A portal's corners are in world space, whatever the transformation
        // (pbrt-v4 takes them so).
        let portal = match p.has("portal") {
            false => None,
            true => {
                let at = place(p, "portal", &l.loc).clone();
                let points = p.get_point3s("portal");
                let Ok(corners) = <[Vec3; 4]>::try_from(points.as_slice()) else {
                    return Err(located(
                        &at,
                        format!("infinite: \"portal\" needs 4 points (12 numbers), not {}", points.len()),
                    ));
                };
                Some((corners, at))
            }
        };
        let through = |map: Option<std::sync::Arc<EnvMap>>, radiance: Vec3, to_world: glam::Mat3| match &portal {
            None => Ok(Light::infinite(radiance, map, to_world)),
            Some((corners, at)) => crate::light::Portal::new(*corners, map.as_deref(), to_world)
                .map(|q| Light::infinite_through(radiance, map, to_world, q))
                .map_err(|e| located(at, format!("infinite: {e}"))),
        };
        // Only directions reach a light at infinity, and pbrt-v4 turns them
        // by the upper 3 x 3 of the transformation and of its inverse: its
        // translation and any projective row do nothing, unless together
        // they make those two disagree.
        let turn = glam::Mat3::from_mat4(l.world_from_light);
        let inverse_turn = glam::Mat3::from_mat4(l.world_from_light.inverse());
        let directions = (turn * inverse_turn).abs_diff_eq(glam::Mat3::IDENTITY, 1e-4);
        let Some((_, s)) = similarity(Mat4::from_mat3(turn)).filter(|_| directions) else {
            self.problem(
                Kind::Light,
                &l.loc,
                "infinite: a transformation other than rotation and uniform scale is not supported",
            );
            return Ok(None);
        };
        let to_world = glam::Mat3::from_mat4(l.world_from_light) * (1.0 / s);
        let e = p.get_float("illuminance", -1.0)?;
        let Some(file) = p.get_string("filename")? else {
            let Some(radiance) = self.light_colour(p, "L", &l.loc)? else {
                return Ok(None);
            };
            if e > 0.0 {
                // pbrt-v4: constant radiance 1 gives illuminance pi.
                scale *= e / PI;
            }
            return through(None, radiance * scale, to_world).map(Some);
        };
        let at = place(p, "filename", &l.loc).clone();
        if p.has("L") {
            return Err(located(&at, "infinite: give \"L\" or \"filename\", not both"));
        }
        let film = self.read_light_image(&at, &file, "infinite")?;
        let map = EnvMap::new(film.width, film.height, film.pixels, EnvMapping::Octahedral, &file)
            .map_err(|e| located(&at, format!("infinite: image \"{file}\": {e}")))?;
        if e > 0.0 {
            // Scaled so that a surface facing the map's +z receives `e`, as
            // the format says. pbrt-v4 sums the upper hemisphere's texels
            // with 2 pi / N for each where each covers 4 pi / N, so its
            // render gets twice `e`; a constant `L` gets `e` in both.
            let upper = map.upper_illuminance();
            if upper <= 0.0 {
                return Err(located(
                    place(p, "illuminance", &l.loc),
                    format!("infinite: \"illuminance\": image \"{file}\" is black above its horizon"),
                ));
            }
            scale *= e / upper;
        }
        through(Some(std::sync::Arc::new(map)), Vec3::splat(scale), to_world).map(Some)
    }

    /// A light's colour parameter as RGB (pbrt's default: the colour space's
    /// illuminant, white); None when unsupported (reported).
    fn light_colour(&mut self, p: &Params, name: &str, loc: &Loc) -> Result<Option<Vec3>> {
        let Some(v) = p.get_spectrum(name)? else {
            return Ok(Some(Vec3::ONE));
        };
        let at = place(p, name, loc).clone();
        if let Some(cs) = colour_space(p, name) {
            self.problem(
                Kind::Light,
                &at,
                format!("\"{name}\": rgb in colour space \"{cs}\" is not supported"),
            );
            return Ok(None);
        }
        let rgb = match &v {
            // Normalised to luminance 1 by pbrt, D65 is white in sRGB.
            SpectrumValue::Named(n) if n == "stdillum-D65" => Some(Vec3::ONE),
            _ => v.light_rgb(),
        };
        match rgb {
            Some(c) if c.is_finite() && c.min_element() >= 0.0 => Ok(Some(c)),
            Some(c) => Err(located(
                &at,
                format!("\"{name}\" {c:?}: must be finite and not negative"),
            )),
            None => {
                self.problem(Kind::Light, &at, format!("\"{name}\": this spectrum is not supported"));
                Ok(None)
            }
        }
    }

    fn emission(&mut self, index: usize) -> Result<Option<Emission>> {
        if let Some(e) = self.emissions.get(&index) {
            return Ok(e.clone());
        }
        let scene = self.scene;
        let al = &scene.area_lights[index];
        let p = &al.params;
        let e = if al.ty != "diffuse" {
            self.problem(
                Kind::Light,
                &al.loc,
                format!("AreaLightSource \"{}\" is not supported", al.ty),
            );
            None
        } else {
            let image = self.emission_image(index)?;
            let colour = match image {
                Some(_) => Some(Vec3::ONE),
                None => self.light_colour(p, "L", &al.loc)?,
            };
            let scale = p.get_float("scale", 1.0)?;
            let two_sided = p.get_bool("twosided", false)?;
            let power = p.get_float("power", -1.0)?;
            self.read.push(p);
            if let (Some(im), true) = (&image, power > 0.0) {
                if crate::math::luminance(im.mean()) <= 0.0 {
                    return Err(located(
                        place(p, "power", &al.loc),
                        "AreaLightSource: \"power\": the emission image is black",
                    ));
                }
            }
            colour.map(|c| Emission {
                radiance: c * scale,
                power: (power > 0.0).then_some(power),
                two_sided,
                image,
            })
        };
        if e.is_none() {
            // Its shapes are drawn without emission.
            self.skipped_lights += 1;
        }
        self.emissions.insert(index, e.clone());
        Ok(e)
    }

    /// A diffuse area light's emission image (`filename`), as pbrt-v4 reads
    /// it: not together with `L`.
    fn emission_image(&mut self, index: usize) -> Result<Option<Arc<EmissionImage>>> {
        let al = &self.scene.area_lights[index];
        let p = &al.params;
        let Some(file) = p.get_string("filename")? else {
            return Ok(None);
        };
        let at = place(p, "filename", &al.loc).clone();
        if p.has("L") {
            return Err(located(
                &at,
                "AreaLightSource: both \"L\" and \"filename\" are given (pbrt-v4 refuses them together)",
            ));
        }
        let film = self.read_light_image(&at, &file, "AreaLightSource")?;
        let image = EmissionImage::new(film.width, film.height, film.pixels)
            .map_err(|e| located(&at, format!("AreaLightSource: image \"{file}\": {e}")))?;
        Ok(Some(Arc::new(image)))
    }

    // ---- materials -----------------------------------------------------------

    fn material(&mut self, desc: &mut SceneDesc, index: usize) -> Result<u32> {
        if let Some(&i) = self.materials.get(&index) {
            return Ok(i);
        }
        let scene = self.scene;
        let m = &scene.materials[index];
        let loc = m.loc.clone().unwrap_or_else(|| self.default_loc());
        let name = match (&m.name, &m.loc) {
            (Some(n), _) => n.clone(),
            (None, Some(l)) => format!("{} ({})", m.ty, l.file_line()),
            (None, None) => "default".into(),
        };
        let mut approximated = vec![];
        let converted = match convert_material(scene, &m.ty, &m.params, &loc, &mut approximated)? {
            Ok(mat) => {
                self.read.push(&m.params);
                for (at, what) in approximated {
                    let label = match &m.name {
                        Some(n) => format!("material \"{n}\""),
                        None => format!("material of type \"{}\"", m.ty),
                    };
                    self.problem(Kind::Other, &at, format!("{label}: {what}"));
                }
                mat
            }
            Err(why) => {
                let what = match &m.name {
                    Some(n) => format!("material \"{n}\" ({why})"),
                    None => format!("material ({why})"),
                };
                self.problem(Kind::Material, &loc, what);
                self.replaced_materials += 1;
                Material::diffuse(0.5, 0.5, 0.5)
            }
        };
        let i = desc.material(&name, converted);
        self.materials.insert(index, i);
        Ok(i)
    }

    // ---- shapes --------------------------------------------------------------

    fn skip_shape(&mut self, shape: &Shape) {
        self.skipped_shapes.insert(shape.loc.clone());
        self.skipped_shapes_count += 1;
    }

    /// A shape's material, or none (`Material::Interface`) for a shape of
    /// pbrt-v4's `interface` material that bounds media.
    fn surface_material(&mut self, desc: &mut SceneDesc, index: usize, no_surface: bool) -> Result<u32> {
        if no_surface {
            Ok(desc.material("<interface>", Material::Interface))
        } else {
            self.material(desc, index)
        }
    }

    /// The media on a shape's two sides when they differ (pbrt-v4's
    /// `MediumInterface` being a transition), as pbrt-v4 orients them:
    /// outside along its surface normal.
    fn interface(&mut self, desc: &mut SceneDesc, shape: &Shape) -> Result<Option<MediumInterface>> {
        let mut side = |name: &Option<String>| match name {
            Some(n) => self.medium(desc, n, &shape.loc),
            None => Ok(None),
        };
        let mi = MediumInterface {
            inside: side(&shape.inside_medium)?,
            outside: side(&shape.outside_medium)?,
        };
        Ok(mi.is_transition().then_some(mi))
    }

    /// The index in `SceneDesc::media` of the medium `name`, converted when
    /// first named; `None` when it cannot be rendered (reported at its
    /// definition; `--lenient` renders it as vacuum). Naming an undefined
    /// medium is an error at `at`, as in pbrt-v4.
    fn medium(&mut self, desc: &mut SceneDesc, name: &str, at: &Loc) -> Result<Option<u32>> {
        if let Some(&i) = self.media.get(name) {
            return Ok(i);
        }
        let scene = self.scene;
        let Some(m) = scene.media.iter().find(|m| m.name == name) else {
            return Err(located(at, format!("medium \"{name}\" is not defined")));
        };
        let index = match convert_medium(m)? {
            Ok(medium) => {
                self.read.push(&m.params);
                desc.media.push((name.to_string(), medium));
                Some(desc.media.len() as u32 - 1)
            }
            Err(why) => {
                self.problem(Kind::Other, &m.loc, format!("MakeNamedMedium \"{name}\": {why}"));
                None
            }
        };
        self.media.insert(name.to_string(), index);
        Ok(index)
    }

    /// Marks `moved`, just added for `shape` (its triangles, or a sphere or
    /// disk), as moving as the transformation interpolated from `start` to
    /// `end` over the transformation times moves what it places; a motion
    /// that cannot be rendered is a problem at the shape, and the shape
    /// then holds still at the start.
    fn moving(&mut self, desc: &mut SceneDesc, shape: &Shape, moved: CutShapes, [start, end]: [Mat4; 2], alpha: bool) {
        if alpha {
            let why = "an \"alpha\" cut-out on a moving shape (ActiveTransform) is not supported; --lenient uses the start transformation";
            self.problem(Kind::Other, &shape.loc, why);
            return;
        }
        match Motion::new(start, end, self.scene.transform_times) {
            Ok(motion) => {
                match moved {
                    CutShapes::Triangles(triangles) => desc.moving.push(MovingTriangles { triangles, motion }),
                    shape => desc.moving_shapes.push(MovingShape { shape, motion }),
                }
                self.first_motion.get_or_insert_with(|| shape.loc.clone());
            }
            Err(why) => self.problem(
                Kind::Other,
                &shape.loc,
                format!("a moving shape (ActiveTransform): {why}; --lenient uses the start transformation"),
            ),
        }
    }

    fn shapes(&mut self, desc: &mut SceneDesc) -> Result<()> {
        let scene = self.scene;
        // Room for every mesh's triangles at once: grown by doubling, the
        // list of a large scene would take up to twice its size and be
        // copied as it grows.
        let meshes: usize = scene
            .shapes
            .iter()
            .map(|s| match &s.geometry {
                Geometry::Mesh(m) => m.triangles.len(),
                _ => 0,
            })
            .sum();
        desc.triangles.reserve_exact(meshes);
        for shape in &scene.shapes {
            let p: &Params = &shape.params;
            if shape.geometry == Geometry::Other {
                self.skip_shape(shape);
                continue;
            }
            // pbrt-v4 cuts a shape out where its alpha is below 1; a number
            // of 1 or more leaves it whole.
            let mut alpha = match float_or_texture(scene, p, "alpha", "", &shape.loc)? {
                Ok(Some(t)) if t.as_constant().is_some_and(|a| a.x >= 1.0) => None,
                Ok(alpha) => alpha,
                Err(why) => {
                    self.problem(Kind::Shape, place(p, "alpha", &shape.loc), format!("\"alpha\": {why}"));
                    self.skip_shape(shape);
                    continue;
                }
            };
            let interface = self.interface(desc, shape)?;
            // pbrt-v4's "interface" and "none" materials make no surface: the
            // shape only bounds media, and where it bounds none it is not there.
            let mut no_surface = false;
            if let Some(m) = scene.materials.get(shape.material) {
                if matches!(m.ty.as_str(), "interface" | "none" | "") {
                    no_surface = true;
                    if shape.area_light.is_some() {
                        self.warn(
                            &shape.loc,
                            format!(
                                "area light ignored: the shape's material is \"{}\", which makes no surface (as pbrt-v4 does)",
                                m.ty
                            ),
                        );
                    }
                    if interface.is_none() {
                        continue;
                    }
                }
            }
            let emission = match shape.area_light {
                Some(i) if !no_surface => self.emission(i)?,
                _ => None,
            };
            // pbrt-v4 makes an area light of constant alpha 0 invisible: it
            // emits whole, but no ray meets its surface, so light sampling
            // alone finds it (pbrt-v4 marks it a delta light for that).
            self.invisible =
                emission.is_some() && alpha.as_ref().and_then(|a| a.as_constant()).is_some_and(|a| a.x == 0.0);
            if self.invisible {
                alpha = None;
            } else if emission.is_some() && alpha.is_some() {
                // pbrt-v4 would also mask the light's emission and its samples.
                self.problem(
                    Kind::Light,
                    place(p, "alpha", &shape.loc),
                    "an \"alpha\" cut-out on an area light is not supported, only \"float alpha\" 0 (an invisible light)",
                );
                alpha = None;
            }
            // pbrt-v4's emitters also reflect by their material; one that
            // reflects nothing ends paths as our lights do by default.
            let emitter_material = match (&emission, scene.materials.get(shape.material)) {
                // An emitter bounds no medium here: its surface would let
                // rays into one they do not enter. It reflects nothing.
                (Some(_), Some(m)) if reflects(m) && interface.is_some() => {
                    self.emitters_bounding_media += 1;
                    None
                }
                (Some(_), Some(m)) if reflects(m) => {
                    if m.params.get("displacement").is_some() || m.params.get("normalmap").is_some() {
                        self.emitters_unbumped += 1;
                    }
                    Some(self.material(desc, shape.material)?)
                }
                _ => None,
            };
            let surface = |normals: Option<[Vec3; 3]>, uvs: Option<[Vec2; 3]>, axes: Option<glam::Mat3>| {
                emitter_material.map(|material| LightSurface {
                    material,
                    normals,
                    uvs,
                    axes,
                })
            };
            let m = shape.world_from_object;
            let alpha_given = alpha.is_some();
            if shape.motion.is_some()
                && !matches!(
                    shape.geometry,
                    Geometry::Mesh(_) | Geometry::Sphere(_) | Geometry::Disk(_)
                )
            {
                self.problem(
                    Kind::Other,
                    &shape.loc,
                    format!(
                        "a moving \"{}\" (ActiveTransform) is not supported, only moving meshes, spheres and disks; --lenient uses the start transformation",
                        shape.ty
                    ),
                );
            }
            // A partial sphere or disk, or one under a transformation the
            // analytic shapes do not take, is a mesh (as a cylinder is).
            let similar = similarity(m);
            if let Geometry::Disk(d) = &shape.geometry {
                if !(d.radius > 0.0 && (0.0..d.radius).contains(&d.inner_radius)) {
                    return Err(located(
                        &shape.loc,
                        format!(
                            "disk: radius {} must be > 0 and innerradius {} in [0, radius)",
                            d.radius, d.inner_radius
                        ),
                    ));
                }
            }
            let tessellated = match &shape.geometry {
                Geometry::Sphere(s) if s.is_partial() || similar.is_none() => {
                    Some(Geometry::Mesh(Arc::new(shapes::sphere_mesh(s))))
                }
                Geometry::Disk(d) if d.is_partial() || similar.is_none() => {
                    Some(Geometry::Mesh(Arc::new(shapes::disk_mesh(d))))
                }
                _ => None,
            };
            match tessellated.as_ref().unwrap_or(&shape.geometry) {
                Geometry::Mesh(mesh) => {
                    let world: Vec<Vec3> = mesh.positions.iter().map(|&v| m.project_point3(v)).collect();
                    let normal_matrix = m.inverse().transpose();
                    let flip = if mesh.quadric {
                        shape.flips_normals()
                    } else {
                        shape.reverse_orientation
                    };
                    let sign = if flip { -1.0 } else { 1.0 };
                    let normals: Option<Vec<Vec3>> = mesh.normals.as_ref().map(|ns| {
                        ns.iter()
                            .map(|&n| normal_matrix.transform_vector3(n).normalize_or_zero() * sign)
                            .collect()
                    });
                    if let Some(e) = emission {
                        let flip = shape.flips_normals();
                        let image = e.image.clone();
                        for (k, t) in mesh.triangles.iter().enumerate() {
                            let [a, b, c] = t.map(|i| world[i as usize]);
                            let cross = (b - a).cross(c - a);
                            let area = 0.5 * cross.length();
                            if !(area > 0.0 && area.is_finite()) {
                                self.dropped_light_triangles += 1;
                                continue;
                            }
                            let side = match &normals {
                                Some(ns) => t.iter().map(|&i| ns[i as usize]).sum::<Vec3>(),
                                None if flip => -cross,
                                None => cross,
                            };
                            let turn = side.dot(cross) < 0.0;
                            let vertices = if turn { [a, c, b] } else { [a, b, c] };
                            let radiance = e.radiance_for(area);
                            // The coordinates pbrt-v4's triangle reports
                            // without "uv", turned with the vertices.
                            let [ua, ub, uc] = mesh.triangle_uvs(k).unwrap_or(DEFAULT_UV);
                            let uv = if turn { [ua, uc, ub] } else { [ua, ub, uc] };
                            let image = image.as_ref().map(|image| {
                                Arc::new(ImageOnTriangle {
                                    image: image.clone(),
                                    uv,
                                })
                            });
                            let light = Light::Triangle {
                                vertices,
                                radiance,
                                two_sided: e.two_sided,
                                image,
                            };
                            let ns = normals.as_ref().map(|ns| {
                                let [na, nb, nc] = t.map(|i| ns[i as usize]);
                                if turn {
                                    [na, nc, nb]
                                } else {
                                    [na, nb, nc]
                                }
                            });
                            self.push_emitter(desc, light, surface(ns, Some(uv), None), &shape.loc)?;
                        }
                    } else {
                        let material = self.surface_material(desc, shape.material, no_surface)?;
                        let first = desc.triangles.len();
                        let flip = shape.flips_normals();
                        // The mesh's vertices, shared by its triangles.
                        let base = desc
                            .triangles
                            .add_vertices(&world, normals.as_deref(), mesh.uvs.as_deref());
                        for (k, t) in mesh.triangles.iter().enumerate() {
                            // Wound so that the geometric normal lies on the
                            // side of pbrt-v4's surface normal: the vertex
                            // normals' side (pbrt-v4 takes them as
                            // authoritative), else the winding's turned when
                            // `flips_normals`. A dielectric's inside, an
                            // interface's media and a bump's direction
                            // follow it.
                            let [a, b, c] = t.map(|i| world[i as usize]);
                            let cross = (b - a).cross(c - a);
                            let side = match &normals {
                                Some(ns) => t.iter().map(|&i| ns[i as usize]).sum::<Vec3>(),
                                None if flip => -cross,
                                None => cross,
                            };
                            let turn = side.dot(cross) < 0.0;
                            let t = if turn { [t[0], t[2], t[1]] } else { *t };
                            // A triangle turned keeps the coordinates of
                            // its vertices, pbrt-v4's default ones too.
                            let uvs = match (mesh.uvs.is_some(), mesh.triangle_uvs(k), turn) {
                                (true, _, _) => FaceUvs::Vertices,
                                (false, Some([a, b, c]), true) => FaceUvs::Own([a, c, b]),
                                (false, None, true) => FaceUvs::Own([DEFAULT_UV[0], DEFAULT_UV[2], DEFAULT_UV[1]]),
                                (false, Some(uvs), false) => FaceUvs::Own(uvs),
                                (false, None, false) => FaceUvs::None,
                            };
                            if let Some(mi) = interface {
                                // pbrt-v4's normal, whose side is outside: the
                                // triangle's, as wound above.
                                let i = desc.triangles.len();
                                match desc.boundaries.last_mut() {
                                    Some(Boundary {
                                        interface,
                                        shapes: CutShapes::Triangles(r),
                                    }) if *interface == mi && r.end == i && r.start >= first => r.end = i + 1,
                                    _ => desc.boundaries.push(Boundary {
                                        interface: mi,
                                        shapes: CutShapes::Triangles(i..i + 1),
                                    }),
                                }
                            }
                            desc.triangles.push_face(base, t, normals.is_some(), uvs, material);
                        }
                        if let Some(alpha) = alpha {
                            let shapes = CutShapes::Triangles(first..desc.triangles.len());
                            desc.cutouts.push(Cutout { alpha, shapes });
                        }
                        if let Some(ends) = shape.motion {
                            let moved = CutShapes::Triangles(first..desc.triangles.len());
                            self.moving(desc, shape, moved, ends, alpha_given);
                        }
                    }
                }
                Geometry::Sphere(s) => {
                    // (A mesh above otherwise.)
                    let Some((centre, scale)) = similar else {
                        continue;
                    };
                    let sphere = Sphere {
                        centre,
                        radius: s.radius.abs() * scale,
                    };
                    if let Some(e) = emission {
                        // pbrt-v4 emits on the side of the normal its hits
                        // report: inwards when `flips_normals`.
                        let emits = match (e.two_sided, shape.flips_normals()) {
                            (true, _) => Emits::Both,
                            (false, true) => Emits::Inwards,
                            (false, false) => Emits::Outwards,
                        };
                        let area = 4.0 * PI * sphere.radius * sphere.radius;
                        let radiance = e.radiance_for(area);
                        // The image is read at pbrt-v4's sphere coordinates,
                        // in the sphere's frame (which turns and mirrors).
                        let axes = glam::Mat3::from_cols(
                            m.transform_vector3(Vec3::X) / scale,
                            m.transform_vector3(Vec3::Y) / scale,
                            m.transform_vector3(Vec3::Z) / scale,
                        );
                        let image = e.image.clone().map(|image| Arc::new(ImageOnSphere { image, axes }));
                        let light = Light::Sphere {
                            sphere,
                            power: radiance * PI * area * emits.sides(),
                            image,
                            emits,
                        };
                        self.push_emitter(desc, light, surface(None, None, Some(axes)), &shape.loc)?;
                    } else {
                        let material = self.surface_material(desc, shape.material, no_surface)?;
                        if let Some(alpha) = alpha {
                            let shapes = CutShapes::Sphere(desc.spheres.len());
                            desc.cutouts.push(Cutout { alpha, shapes });
                        }
                        if let Some(mi) = interface {
                            // Ours is the outward normal; pbrt-v4's turns with `flips_normals`.
                            desc.boundaries.push(Boundary {
                                interface: if shape.flips_normals() { mi.flipped() } else { mi },
                                shapes: CutShapes::Sphere(desc.spheres.len()),
                            });
                        }
                        // Its texture coordinates turn with it (and mirror).
                        let axes = glam::Mat3::from_cols(
                            m.transform_vector3(Vec3::X) / scale,
                            m.transform_vector3(Vec3::Y) / scale,
                            m.transform_vector3(Vec3::Z) / scale,
                        );
                        let axes = (axes != glam::Mat3::IDENTITY).then_some(axes);
                        desc.spheres.push(SphereDesc { sphere, material, axes });
                        if let Some(ends) = shape.motion {
                            let moved = CutShapes::Sphere(desc.spheres.len() - 1);
                            self.moving(desc, shape, moved, ends, alpha_given);
                        }
                    }
                }
                Geometry::Disk(d) => {
                    let Some((_, scale)) = similar else {
                        continue;
                    };
                    let centre = m.transform_point3(Vec3::new(0.0, 0.0, d.height));
                    let axes = [
                        m.transform_vector3(Vec3::X) / scale,
                        m.transform_vector3(Vec3::Y) / scale,
                    ];
                    let normal = m.inverse().transpose().transform_vector3(Vec3::Z).normalize();
                    let normal = if shape.flips_normals() { -normal } else { normal };
                    let (radius, inner_radius) = (d.radius * scale, d.inner_radius * scale);
                    if let Some(e) = emission {
                        // pbrt-v4 emits on the side of the normal its ray
                        // hits report (`flips_normals`, as for the disk
                        // without a light above).
                        let disk = crate::geometry::Disk::new(centre, normal, radius, inner_radius, Some(axes))
                            .map_err(|msg| located(&shape.loc, format!("disk: {msg}")))?;
                        let radiance = e.radiance_for(disk.area());
                        let light = Light::Disk {
                            disk,
                            radiance,
                            two_sided: e.two_sided,
                            image: e.image.clone(),
                        };
                        self.push_emitter(desc, light, surface(None, None, None), &shape.loc)?;
                    } else {
                        let material = self.surface_material(desc, shape.material, no_surface)?;
                        if let Some(interface) = interface {
                            // `normal` is pbrt-v4's already.
                            let shapes = CutShapes::Disk(desc.disks.len());
                            desc.boundaries.push(Boundary { interface, shapes });
                        }
                        let mut disk = DiskDesc::new(centre, normal, radius, inner_radius, material);
                        disk.axes = Some(axes);
                        if let Some(alpha) = alpha {
                            let shapes = CutShapes::Disk(desc.disks.len());
                            desc.cutouts.push(Cutout { alpha, shapes });
                        }
                        desc.disks.push(disk);
                        if let Some(ends) = shape.motion {
                            let moved = CutShapes::Disk(desc.disks.len() - 1);
                            self.moving(desc, shape, moved, ends, alpha_given);
                        }
                    }
                }
                Geometry::Curves(c) => {
                    let Some((_, scale)) = similarity(m) else {
                        self.problem(
                            Kind::Shape,
                            &shape.loc,
                            "a curve under a transformation other than rotation, uniform scale and translation is not supported",
                        );
                        self.skip_shape(shape);
                        continue;
                    };
                    if emission.is_some() {
                        // pbrt-v4 cannot sample points on curves either.
                        self.problem(Kind::Light, &shape.loc, "an area light on a curve is not supported");
                        self.skipped_lights += 1;
                        continue;
                    }
                    if alpha.is_some() || interface.is_some() {
                        self.problem(
                            Kind::Shape,
                            &shape.loc,
                            "a curve cut out by \"alpha\" or bounding a medium is not supported",
                        );
                        self.skip_shape(shape);
                        continue;
                    }
                    let material = self.surface_material(desc, shape.material, no_surface)?;
                    let pieces = 1u32 << c.split_depth;
                    let total = desc.curves.len() as u64 + c.segments.len() as u64 * pieces as u64;
                    if total > MAX_CURVE_PIECES {
                        return Err(located(
                            &shape.loc,
                            format!(
                                "curve: {} segments of {pieces} pieces each (\"splitdepth\" {}) take the scene past \
                                 the limit of {MAX_CURVE_PIECES} curve pieces",
                                c.segments.len(),
                                c.split_depth
                            ),
                        ));
                    }
                    desc.curves.reserve(c.segments.len() * pieces as usize);
                    for (k, (seg, w)) in c.segments.iter().zip(&c.widths).enumerate() {
                        let world = seg.map(|q| m.transform_point3(q));
                        // Under a similarity a normal turns as a vector does.
                        let n = match c.normals.get(k..k + 2) {
                            Some(&[a, b]) => [a, b].map(|v| m.transform_vector3(v).normalize()),
                            _ => [Vec3::ZERO; 2],
                        };
                        for i in 0..pieces {
                            let u = [i as f32 / pieces as f32, (i + 1) as f32 / pieces as f32];
                            desc.curves.push(CurveDesc {
                                curve: Curve {
                                    cp: bezier_part(&world, u[0], u[1]),
                                    u,
                                    width: [w[0] * scale, w[1] * scale],
                                    kind: c.kind,
                                    n,
                                },
                                material,
                            });
                        }
                    }
                }
                _ => unreachable!("skipped above"),
            }
            self.read.push(p);
        }
        Ok(())
    }
}

/// Most curve pieces a scene may hold (pbrt-v4 splits each Bezier segment
/// into 2^splitdepth pieces; at about 80 bytes a piece with its share of
/// the BVH, this is over a gigabyte).
const MAX_CURVE_PIECES: u64 = 1 << 24;

/// A pbrt-v4 `MakeNamedMedium` as ours (pbrt-v4's `HomogeneousMedium::Create`:
/// `sigma_a` and `sigma_s` default to 1, both times `scale`; `g`), or why it
/// cannot be.
fn convert_medium(m: &super::ir::Medium) -> Result<std::result::Result<Medium, String>> {
    let p = &m.params;
    let (grid, cloud) = match m.ty.as_str() {
        "homogeneous" => (false, false),
        "uniformgrid" => (true, false),
        "cloud" => (false, true),
        "nanovdb" => (false, false),
        "rgbgrid" => return rgb_grid_medium(m).map(Ok),
        other => {
            return Ok(Err(format!(
                "media of type \"{other}\" are not supported (homogeneous, uniformgrid, rgbgrid, cloud and nanovdb ones are)"
            )))
        }
    };
    let vdb = m.ty == "nanovdb";
    // pbrt-v4 reads `preset` for homogeneous media alone: a measured
    // medium's coefficients in mm^-1 (`medium::presets`), then `scale`.
    let preset = if !grid && !cloud && !vdb {
        p.get_string_or("preset", "")?
    } else {
        String::new()
    };
    let preset = if preset.is_empty() {
        None
    } else {
        match crate::medium::presets::scattering_preset(&preset) {
            Some(v) => Some(v),
            None => {
                return Err(located(
                    place(p, "preset", &m.loc),
                    format!(
                        "MakeNamedMedium \"{}\": no measured medium is named \"{preset}\"",
                        m.name
                    ),
                ))
            }
        }
    };
    // An `rgb` coefficient as given (pbrt-v4's unbounded spectrum of it), a
    // sampled one projected as a reflectance is.
    let coefficient = |name: &str| -> Result<std::result::Result<Vec3, String>> {
        Ok(match p.get_spectrum(name)? {
            None => Ok(Vec3::ONE),
            Some(v) => match reflectance_rgb(&v) {
                Some(c) => Ok(c),
                None => Err(format!("\"{name}\" given as this spectrum is not supported")),
            },
        })
    };
    let (sigma_a, sigma_s) = match preset {
        Some(v) => v,
        None => match (coefficient("sigma_a")?, coefficient("sigma_s")?) {
            (Ok(a), Ok(s)) => (a, s),
            (Err(why), _) | (_, Err(why)) => return Ok(Err(why)),
        },
    };
    // pbrt-v4's cloud emits nothing, its nanovdb medium only by temperature
    // (their "Le" is left unread, and reported).
    let le = if cloud || vdb {
        None
    } else {
        match medium_le(m)? {
            Ok(le) => le,
            Err(why) => return Ok(Err(why)),
        }
    };
    let (density, emission) = if grid {
        let density = grid_density(m)?;
        let emission = grid_emission(m, &density, le)?;
        (Some(std::sync::Arc::new(density)), emission)
    } else if cloud {
        (cloud_density(m)?, None)
    } else if vdb {
        let (density, emission) = match nanovdb_medium(m)? {
            Ok(v) => v,
            Err(why) => return Ok(Err(why)),
        };
        (Some(std::sync::Arc::new(density)), emission)
    } else {
        let lescale = p.get_float("Lescale", 1.0)?;
        (None, le.map(|c| MediumEmission::uniform(c * lescale)))
    };
    // pbrt-v4's cloud has no "scale" (left unread, it is reported unused).
    let scale = if cloud { 1.0 } else { p.get_float("scale", 1.0)? };
    let medium = Medium {
        sigma_a: sigma_a * scale,
        sigma_s: sigma_s * scale,
        g: p.get_float("g", 0.0)?,
        density,
        emission: emission.filter(|e| !e.is_dark()).map(std::sync::Arc::new),
    };
    medium
        .check()
        .map_err(|why| located(&m.loc, format!("MakeNamedMedium \"{}\": {why}", m.name)))?;
    Ok(Ok(medium))
}

/// A `nanovdb` medium's density and emission (pbrt-v4's
/// `NanoVDBMedium::Create`): the float grids named by `gridname`
/// ("density") and `temperaturename` ("temperature", optional) of the file
/// `filename`; emission `Lescale` (1) times the blackbody of the
/// temperature, less `temperatureoffset` (or `temperaturecutoff`, 0), times
/// `temperaturescale` (1), in kelvin.
/// A grid the file holds in a way we do not read is `Ok(Err(why))`.
fn nanovdb_medium(m: &super::ir::Medium) -> Result<std::result::Result<(Density, Option<MediumEmission>), String>> {
    let p = &m.params;
    let at = |name: &str| p.loc_of(name).unwrap_or(&m.loc);
    let what = format!("MakeNamedMedium \"{}\"", m.name);
    let Some((path, bytes)) = &m.file else {
        return Err(located(&m.loc, format!("{what}: no \"filename\" was read")));
    };
    let density_name = p.get_string_or("gridname", "density")?;
    let temperature_name = p.get_string_or("temperaturename", "temperature")?;
    let in_file = |e: String| located(at("filename"), format!("{what}: {}: {e}", path.display()));
    let mut grids = match nanovdb::read_grids(bytes, &[&density_name, &temperature_name]) {
        Ok(grids) => grids,
        Err(e) if e.contains(nanovdb::UNSUPPORTED) => return Ok(Err(format!("{}: {e}", path.display()))),
        Err(e) => return Err(in_file(e)),
    };
    let temperature = grids.pop().flatten();
    let Some(density) = grids.pop().flatten() else {
        return Err(in_file(format!("no grid named \"{density_name}\"")));
    };
    let lescale = p.get_float("Lescale", 1.0)?;
    let offset = p.get_float("temperatureoffset", p.get_float("temperaturecutoff", 0.0)?)?;
    let tscale = p.get_float("temperaturescale", 1.0)?;
    let (density, bounds) = Density::nanovdb(
        density,
        temperature.as_ref().map(|t| t.world_bounds),
        m.world_from_medium,
    )
    .map_err(in_file)?;
    // As pbrt-v4: a medium emits only with a temperature grid and a
    // positive Lescale.
    let emission = match temperature {
        Some(t) if lescale > 0.0 => Some(
            MediumEmission::nanovdb_temperature(t, bounds, lescale, offset, tscale, &|k| {
                super::spectrum::blackbody_film_rgb(k)
            })
            .map_err(|e| located(at("Lescale"), format!("{what}: {e}")))?,
        ),
        _ => None,
    };
    Ok(Ok((density, emission)))
}

/// A medium's `Le` as the RGB radiance the film records (pbrt-v4 reads it
/// as an illuminant and divides by its luminance, as for area lights), when
/// it has one that is not black; `Err` when it is given as a spectrum we
/// cannot read.
fn medium_le(m: &super::ir::Medium) -> Result<std::result::Result<Option<Vec3>, String>> {
    let p = &m.params;
    let Some(v) = p.get_spectrum("Le")? else {
        return Ok(Ok(None));
    };
    let rgb = match &v {
        SpectrumValue::Named(n) if n == "stdillum-D65" => Some(Vec3::ONE),
        _ => v.light_rgb(),
    };
    match rgb {
        None => Ok(Err("\"Le\" given as this spectrum is not supported".into())),
        Some(c) if !(c.is_finite() && c.min_element() >= 0.0) => Err(located(
            p.loc_of("Le").unwrap_or(&m.loc),
            format!(
                "MakeNamedMedium \"{}\": \"Le\" {c}: must be finite and not negative",
                m.name
            ),
        )),
        Some(c) => Ok(Ok((c.max_element() > 0.0).then_some(c))),
    }
}

/// A `uniformgrid` medium's emission (pbrt-v4's `GridMedium::Create`): `Le`
/// times `Lescale` at each point (one value per grid point; by default a
/// single 1), or instead of `Le` a grid of `temperature`s, in kelvin after
/// `temperatureoffset` (or `temperaturecutoff`, 0) is taken off and
/// `temperaturescale` (1) multiplies.
fn grid_emission(m: &super::ir::Medium, density: &Density, le: Option<Vec3>) -> Result<Option<MediumEmission>> {
    let p = &m.params;
    let at = |name: &str| p.loc_of(name).unwrap_or(&m.loc);
    let what = format!("MakeNamedMedium \"{}\"", m.name);
    let temperature = p.get_floats("temperature");
    let n = density.resolution().unwrap_or([1, 1, 1]);
    let offset = p.get_float("temperatureoffset", p.get_float("temperaturecutoff", 0.0)?)?;
    let tscale = p.get_float("temperaturescale", 1.0)?;
    if p.has("Le") && !temperature.is_empty() {
        return Err(located(
            at("temperature"),
            format!("{what}: both \"Le\" and \"temperature\" are given"),
        ));
    }
    let lescale = p.get_floats("Lescale");
    if le.is_none() && temperature.is_empty() {
        return Ok(None);
    }
    let rgb = |k: f32| super::spectrum::blackbody_film_rgb(k);
    MediumEmission::grid(
        n,
        le.unwrap_or(Vec3::ZERO),
        (!lescale.is_empty()).then(|| lescale.to_vec()),
        (!temperature.is_empty()).then(|| TemperatureGrid {
            values: temperature.to_vec(),
            offset,
            scale: tscale,
            rgb: &rgb,
        }),
    )
    .map(Some)
    .map_err(|why| {
        let name = if why.contains("Lescale") {
            "Lescale"
        } else {
            "temperature"
        };
        located(at(name), format!("{what}: {why}"))
    })
}

/// A `uniformgrid` medium's density (pbrt-v4's `GridMedium::Create`:
/// `density` of `nx` x `ny` x `nz` values, x fastest, over the box from `p0`
/// (0, 0, 0) to `p1` (1, 1, 1) in the medium's space).
fn grid_density(m: &super::ir::Medium) -> Result<Density> {
    let p = &m.params;
    let at = |name: &str| p.loc_of(name).unwrap_or(&m.loc);
    let what = format!("MakeNamedMedium \"{}\"", m.name);
    let values = p.get_floats("density");
    if values.is_empty() {
        return Err(located(&m.loc, format!("{what}: no \"density\" values for the grid")));
    }
    let n = grid_resolution(m)?;
    let p0 = p.get_point3("p0", Vec3::ZERO)?;
    let p1 = p.get_point3("p1", Vec3::ONE)?;
    Density::grid(n, values.to_vec(), p0, p1, m.world_from_medium)
        .map_err(|why| located(at("density"), format!("{what}: {why}")))
}

/// A grid medium's `nx`, `ny`, `nz` (1 each by default).
fn grid_resolution(m: &super::ir::Medium) -> Result<[usize; 3]> {
    let p = &m.params;
    let mut n = [0usize; 3];
    for (k, name) in ["nx", "ny", "nz"].into_iter().enumerate() {
        let v = p.get_int(name, 1)?;
        if v < 1 {
            return Err(located(
                p.loc_of(name).unwrap_or(&m.loc),
                format!("MakeNamedMedium \"{}\": \"{name}\" must be at least 1, not {v}", m.name),
            ));
        }
        n[k] = v as usize;
    }
    Ok(n)
}

/// An `rgbgrid` medium (pbrt-v4's `RGBGridMedium::Create`): `sigma_a` and
/// `sigma_s` as `rgb` values per grid point (at least one of them; one where
/// the other is not given), times `scale`; `Le` per grid point (with
/// `sigma_a`) times `Lescale`; `p0`, `p1`, `g` as for `uniformgrid`.
fn rgb_grid_medium(m: &super::ir::Medium) -> Result<Medium> {
    let p = &m.params;
    let at = |name: &str| p.loc_of(name).unwrap_or(&m.loc);
    let what = format!("MakeNamedMedium \"{}\"", m.name);
    let (sigma_a, sigma_s, le) = (p.get_rgbs("sigma_a"), p.get_rgbs("sigma_s"), p.get_rgbs("Le"));
    if sigma_a.is_empty() && sigma_s.is_empty() {
        return Err(located(
            &m.loc,
            format!("{what}: an rgbgrid needs \"sigma_a\" or \"sigma_s\" values"),
        ));
    }
    if !le.is_empty() && sigma_a.is_empty() {
        return Err(located(at("Le"), format!("{what}: \"Le\" needs \"sigma_a\" values")));
    }
    let n = grid_resolution(m)?;
    let given = |v: Vec<Vec3>| (!v.is_empty()).then_some(v);
    let density = Density::rgb_grid(
        n,
        given(sigma_a),
        given(sigma_s),
        p.get_float("scale", 1.0)?,
        p.get_point3("p0", Vec3::ZERO)?,
        p.get_point3("p1", Vec3::ONE)?,
        m.world_from_medium,
    )
    .map_err(|why| {
        let name = if why.contains("sigma_s") { "sigma_s" } else { "sigma_a" };
        located(at(name), format!("{what}: {why}"))
    })?;
    // pbrt-v4 reads these as illuminants (an RGB times its colour space's
    // white of luminance one) but, unlike a light's or another medium's
    // `Le`, does not normalise them: its film records each 106.86 times
    // the RGB given (`blackbody_film_rgb`).
    let to_film = super::spectrum::cie_y_integral();
    let emission = match given(le) {
        None => None,
        Some(le) => Some(
            MediumEmission::rgb_grid(n, le, p.get_float("Lescale", 1.0)? * to_film)
                .map_err(|why| located(at("Le"), format!("{what}: {why}")))?,
        ),
    };
    let medium = Medium {
        sigma_a: Vec3::ONE,
        sigma_s: Vec3::ONE,
        g: p.get_float("g", 0.0)?,
        density: Some(std::sync::Arc::new(density)),
        emission: emission.filter(|e| !e.is_dark()).map(std::sync::Arc::new),
    };
    medium
        .check()
        .map_err(|why| located(&m.loc, format!("{what}: {why}")))?;
    Ok(medium)
}

/// A `cloud` medium's density (pbrt-v4's `CloudMedium::Create`: `density`
/// 1, `wispiness` 1, `frequency` 5, over the box from `p0` (0, 0, 0) to
/// `p1` (1, 1, 1) in the medium's space).
fn cloud_density(m: &super::ir::Medium) -> Result<Option<std::sync::Arc<Density>>> {
    let p = &m.params;
    let cloud = Density::cloud(
        p.get_float("density", 1.0)?,
        p.get_float("wispiness", 1.0)?,
        p.get_float("frequency", 5.0)?,
        p.get_point3("p0", Vec3::ZERO)?,
        p.get_point3("p1", Vec3::ONE)?,
        m.world_from_medium,
    )
    .map_err(|why| located(&m.loc, format!("MakeNamedMedium \"{}\": {why}", m.name)))?;
    Ok(Some(std::sync::Arc::new(cloud)))
}

fn located(loc: &Loc, message: impl Into<String>) -> Error {
    Error::Syntax {
        path: loc.file.as_ref().clone(),
        line: loc.line as usize,
        message: message.into(),
    }
}

/// The colour space of an `rgb` parameter when it is not sRGB.
fn colour_space(p: &Params, name: &str) -> Option<String> {
    let param: &Param = p.get(name)?;
    (param.ty == super::ParamType::Rgb && &*param.color_space != "srgb").then(|| param.color_space.to_string())
}

/// Whether a material (as pbrt would render it) may reflect light: all but
/// a diffuse one of a black reflectance (not a texture), as emitters that
/// only emit are written.
fn reflects(m: &super::ir::Material) -> bool {
    match m.ty.as_str() {
        "diffuse" => match m.params.get("reflectance") {
            Some(p) if p.ty != super::ParamType::Texture => p
                .spectra()
                .iter()
                .any(|s| s.to_rgb().is_none_or(|c| c.max_element() > 0.0)),
            _ => true,
        },
        _ => true,
    }
}

/// Materials a `mix` may nest (a cycle of named materials would not end).
const MAX_MIX_DEPTH: u32 = 16;

/// A pbrt material as ours, or why it cannot be (`Ok(Err(why))`). What it
/// renders only approximately (a dispersive index) is added to `approximated`
/// with its place: an unsupported feature that `--lenient` keeps.
fn convert_material(
    scene: &PbrtScene,
    ty: &str,
    p: &Params,
    loc: &Loc,
    approximated: &mut Vec<(Loc, String)>,
) -> Result<std::result::Result<Material, String>> {
    convert_nested(scene, ty, p, loc, 0, approximated)
}

/// `convert_material` of a material `depth` mixes deep, with its normal or
/// bump map (the normal map wins where both are given, as in pbrt-v4).
fn convert_nested(
    scene: &PbrtScene,
    ty: &str,
    p: &Params,
    loc: &Loc,
    depth: u32,
    approximated: &mut Vec<(Loc, String)>,
) -> Result<std::result::Result<Material, String>> {
    let base = match convert_surface(scene, ty, p, loc, depth, approximated)? {
        Ok(m) => m,
        Err(why) => return Ok(Err(why)),
    };
    if let Some(file) = p.get_string("normalmap")? {
        // Read as linear RGB, whatever the file, as pbrt-v4 reads it.
        let at = place(p, "normalmap", loc).clone();
        let Some(path) = scene.candidates(&at, &file).into_iter().find(|c| c.is_file()) else {
            return Err(PbrtError::at(&at, format!("normal map \"{file}\" not found")).into());
        };
        let map = crate::texture::load_image(&path, crate::texture::Encoding::Linear)
            .map_err(|e| located(&at, format!("normal map: {e}")))?;
        p.mark_used("displacement", super::ParamType::Float);
        p.mark_used("displacement", super::ParamType::Texture);
        return Ok(Ok(Material::NormalMapped {
            base: Box::new(base),
            map,
            mirrored: false,
        }));
    }
    let displacement = match float_or_texture(scene, p, "displacement", "", loc)? {
        Ok(Some(t)) => t,
        Ok(None) => return Ok(Ok(base)),
        Err(why) => return Ok(Err(why)),
    };
    Ok(Ok(Material::Bumped {
        base: Box::new(base),
        displacement,
    }))
}

/// A float parameter that may be given by a texture (a mix's `amount`, a
/// bump map's `displacement`): `None` when absent. A number that is not
/// finite is the file's error at its place (`label` prefixes the message).
fn float_or_texture(
    scene: &PbrtScene,
    p: &Params,
    name: &str,
    label: &str,
    loc: &Loc,
) -> Result<std::result::Result<Option<Texture>, String>> {
    Ok(Ok(Some(match p.get_float_or_texture(name)? {
        None => return Ok(Ok(None)),
        Some(FloatOrTexture::Value(v)) if v.is_finite() => Texture::from(Vec3::splat(v)),
        Some(FloatOrTexture::Value(v)) => {
            return Err(located(
                place(p, name, loc),
                format!("{label}\"{name}\" {v} must be finite"),
            ))
        }
        Some(FloatOrTexture::Texture(t)) => match float_texture(scene, p, name, &t, loc)? {
            Ok(t) => t,
            Err(why) => return Ok(Err(why)),
        },
    })))
}

/// The `encoding` of an image texture that names none: pbrt-v4's sRGB for
/// 8-bit formats (PNG and the like), linear otherwise.
fn default_encoding(file: &str) -> &'static str {
    let lower = file.to_ascii_lowercase();
    match [".png", ".jpg", ".jpeg", ".tga", ".bmp"]
        .iter()
        .any(|e| lower.ends_with(e))
    {
        true => "sRGB",
        false => "linear",
    }
}

/// Decodes the image of every `imagemap` texture in the scene, in parallel,
/// into the image cache: the conversion then asks for them one at a time
/// and finds them there. Read as the conversion reads them (the file found
/// for `filename`, the `encoding` or pbrt-v4's default for the file), but
/// without marking the parameters read; a file that cannot be read is left
/// for the conversion to report at its place.
pub(super) fn decode_images(scene: &PbrtScene) -> Vec<Arc<crate::texture::TexImage>> {
    use crate::texture::Encoding;
    use rayon::prelude::*;
    let string = |p: &Params, name: &str| {
        p.iter()
            .find(|q| q.name == name && q.ty == super::ParamType::String)
            .and_then(|q| match &q.values {
                super::Values::Strings(v) => v.first().cloned(),
                _ => None,
            })
    };
    let mut wanted: Vec<(std::path::PathBuf, Encoding)> = Vec::new();
    for t in scene.textures.iter().filter(|t| t.class == "imagemap") {
        let p = &t.params;
        let Some(file) = string(p, "filename") else { continue };
        let at = place(p, "filename", &t.loc);
        let Some(path) = scene.candidates(at, &file).into_iter().find(|c| c.is_file()) else {
            continue;
        };
        let name = string(p, "encoding").unwrap_or_else(|| default_encoding(&file).into());
        if let Some(encoding) = Encoding::parse(&name) {
            if !wanted.iter().any(|(q, e)| *q == path && *e == encoding) {
                wanted.push((path, encoding));
            }
        }
    }
    wanted
        .par_iter()
        .filter_map(|(path, encoding)| crate::texture::load_image(path, *encoding).ok())
        .collect()
}

/// A material's scattering, `depth` mixes deep.
fn convert_surface(
    scene: &PbrtScene,
    ty: &str,
    p: &Params,
    loc: &Loc,
    depth: u32,
    approximated: &mut Vec<(Loc, String)>,
) -> Result<std::result::Result<Material, String>> {
    match ty {
        "mix" => {
            let names = p.get_strings("materials");
            let at = place(p, "materials", loc);
            let [a, b] = names else {
                return Err(located(
                    at,
                    format!("mix: \"materials\" names {} materials, not two", names.len()),
                ));
            };
            if depth >= MAX_MIX_DEPTH {
                return Err(located(
                    at,
                    format!("mix: materials nest more than {MAX_MIX_DEPTH} deep (a cycle?)"),
                ));
            }
            let mut parts = Vec::with_capacity(2);
            for name in [a, b] {
                let Some(m) = scene.named_materials.get(name).and_then(|&i| scene.materials.get(i)) else {
                    return Err(located(at, format!("mix: material \"{name}\" is not defined")));
                };
                if matches!(m.ty.as_str(), "interface" | "none" | "") {
                    return Ok(Err(format!("a mix with the \"{}\" material \"{name}\"", m.ty)));
                }
                let m_loc = m.loc.clone().unwrap_or_else(|| loc.clone());
                match convert_nested(scene, &m.ty, &m.params, &m_loc, depth + 1, approximated)? {
                    Ok(m) => parts.push(m),
                    Err(why) => return Ok(Err(format!("mix: material \"{name}\": {why}"))),
                }
            }
            let amount = match float_or_texture(scene, p, "amount", "mix: ", loc)? {
                Ok(t) => t.unwrap_or_else(|| Texture::from(Vec3::splat(0.5))),
                Err(why) => return Ok(Err(why)),
            };
            match <[Material; 2]>::try_from(parts) {
                Ok(materials) => Ok(Ok(Material::Mix {
                    materials: Box::new(materials),
                    amount,
                })),
                Err(_) => Ok(Err("mix: two materials expected".into())),
            }
        }
        "diffuse" => {
            let albedo = match p.get_spectrum_or_texture("reflectance")? {
                None => Vec3::splat(0.5),
                Some(SpectrumOrTexture::Texture(t)) => {
                    let at = place(p, "reflectance", loc);
                    return Ok(texture(scene, &t, TextureKind::Spectrum, at, 0)?.map(|reflectance| {
                        Material::Diffuse {
                            reflectance: clamped(reflectance),
                        }
                    }));
                }
                Some(SpectrumOrTexture::Value(v)) => {
                    if let Some(cs) = colour_space(p, "reflectance") {
                        return Ok(Err(format!("rgb in colour space \"{cs}\" is not supported")));
                    }
                    check_albedo(p, "reflectance", loc, approximated)?;
                    match reflectance_rgb(&v) {
                        Some(c) => c,
                        None => return Ok(Err("a reflectance given as this spectrum is not supported".into())),
                    }
                }
            };
            if !albedo.is_finite() {
                return Err(located(loc, "diffuse: \"reflectance\" must be finite"));
            }
            let a = albedo.clamp(Vec3::ZERO, Vec3::ONE);
            Ok(Ok(Material::diffuse(a.x, a.y, a.z)))
        }
        "dielectric" => {
            let roughness = match roughness(scene, p, loc)? {
                Ok(r) => r,
                Err(why) => return Ok(Err(why)),
            };
            let eta = match eta_param(p, "eta")? {
                Ok(Eta::Constant(eta)) => eta,
                Ok(Eta::Dispersive { channels, .. }) => {
                    return Ok(Ok(Material::Dispersive {
                        eta: channels,
                        roughness,
                    }))
                }
                Err(why) => return Ok(Err(why)),
            };
            if !(eta.is_finite() && eta > 0.0) {
                return Err(located(
                    loc,
                    format!("dielectric: \"eta\" {eta} must be a positive number"),
                ));
            }
            Ok(Ok(Material::Dielectric { eta, roughness }))
        }
        "thindielectric" => {
            let eta = p.get_float("eta", 1.5)?;
            if !(eta.is_finite() && eta > 0.0) {
                return Err(located(
                    loc,
                    format!("thindielectric: \"eta\" {eta} must be a positive number"),
                ));
            }
            Ok(Ok(Material::ThinDielectric { eta }))
        }
        "conductor" => {
            let roughness = match roughness(scene, p, loc)? {
                Ok(r) => r,
                Err(why) => return Ok(Err(why)),
            };
            let fresnel = match conductor_fresnel(scene, p, loc, "conductor", "")? {
                Ok(f) => f,
                Err(why) => return Ok(Err(why)),
            };
            Ok(Ok(Material::Conductor { fresnel, roughness }))
        }
        "coateddiffuse" => {
            let max_depth = p.get_int("maxdepth", 10)?;
            let samples = p.get_int("nsamples", 1)?;
            let medium = match coat_medium(scene, p, "coateddiffuse", max_depth, samples, loc)? {
                Ok(m) => m,
                Err(why) => return Ok(Err(why)),
            };
            let roughness = match roughness(scene, p, loc)? {
                Ok(r) => r,
                Err(why) => return Ok(Err(why)),
            };
            check_albedo(p, "reflectance", loc, approximated)?;
            let reflectance = match spectrum_texture(scene, p, "reflectance", 0.5, loc)? {
                Ok(r) => clamped(r),
                Err(why) => return Ok(Err(why)),
            };
            let eta = p.get_float("eta", 1.5)?;
            let thickness = p.get_float("thickness", 0.01)?;
            if !(eta.is_finite() && eta > 0.0 && thickness.is_finite() && thickness >= 0.0) {
                return Err(located(
                    loc,
                    "coateddiffuse: \"eta\" must be positive and \"thickness\" not negative",
                ));
            }
            Ok(Ok(Material::CoatedDiffuse {
                reflectance,
                roughness,
                eta,
                thickness,
                medium,
            }))
        }
        "coatedconductor" => {
            let interface_roughness = match roughness_of(scene, p, loc, "interface.")? {
                Ok(r) => r,
                Err(why) => return Ok(Err(why)),
            };
            let conductor_roughness = match roughness_of(scene, p, loc, "conductor.")? {
                Ok(r) => r,
                Err(why) => return Ok(Err(why)),
            };
            let conductor = match conductor_fresnel(scene, p, loc, "coatedconductor", "conductor.")? {
                Ok(f) => f,
                Err(why) => return Ok(Err(why)),
            };
            let eta = match constant_eta(p, "interface.eta", loc, approximated)? {
                Ok(eta) => eta,
                Err(why) => return Ok(Err(why)),
            };
            let thickness = p.get_float("thickness", 0.01)?;
            let max_depth = p.get_int("maxdepth", 10)?;
            let samples = p.get_int("nsamples", 1)?;
            if !(eta.is_finite() && eta > 0.0 && thickness.is_finite() && thickness >= 0.0) {
                return Err(located(
                    loc,
                    "coatedconductor: \"interface.eta\" must be positive and \"thickness\" not negative",
                ));
            }
            let medium = match coat_medium(scene, p, "coatedconductor", max_depth, samples, loc)? {
                Ok(m) => m,
                Err(why) => return Ok(Err(why)),
            };
            Ok(Ok(Material::CoatedConductor {
                interface_roughness,
                eta,
                thickness,
                conductor,
                conductor_roughness,
                max_depth: max_depth as u32,
                samples: samples as u32,
                medium,
            }))
        }
        "diffusetransmission" => {
            let scale = p.get_float("scale", 1.0)?;
            let mut rt = Vec::new();
            for n in ["reflectance", "transmittance"] {
                check_albedo(p, n, loc, approximated)?;
                match spectrum_texture(scene, p, n, 0.25, loc)? {
                    Ok(Texture::Constant(c)) => rt.push(Texture::from((c * scale).clamp(Vec3::ZERO, Vec3::ONE))),
                    Ok(t) if scale == 1.0 => rt.push(clamped(t)),
                    Ok(t) => rt.push(clamped(Texture::Scale {
                        tex: Arc::new(t),
                        scale: Arc::new(Texture::from(Vec3::splat(scale))),
                    })),
                    Err(why) => return Ok(Err(why)),
                }
            }
            let transmittance = rt.pop().unwrap_or_default_texture();
            let reflectance = rt.pop().unwrap_or_default_texture();
            Ok(Ok(Material::DiffuseTransmission {
                reflectance,
                transmittance,
            }))
        }
        "hair" => hair(p),
        "measured" => {
            let at = place(p, "filename", loc).clone();
            let Some(file) = p.get_string("filename")? else {
                return Err(located(loc, "measured: no \"filename\" was given".to_string()));
            };
            let Some(path) = scene.candidates(&at, &file).into_iter().find(|c| c.is_file()) else {
                return Err(PbrtError::at(&at, format!("measured: file \"{file}\" not found")).into());
            };
            let in_file = |e: String| located(&at, format!("measured: {}: {e}", path.display()));
            let bytes = crate::scene::mesh::FileSource::read(&crate::scene::mesh::Disk, &path)
                .map_err(|e| in_file(e.to_string()))?;
            let data = MeasuredData::shared(&path, &bytes, super::spectrum::wavelength_rgb).map_err(in_file)?;
            Ok(Ok(Material::Measured(MeasuredBxdf::new(data))))
        }
        "subsurface" => subsurface(scene, p, loc),
        other => Ok(Err(format!("type \"{other}\" is not supported"))),
    }
}

/// pbrt-v4's `subsurface` material (`SubsurfaceMaterial::Create`): its
/// medium by `name` (a measured preset, in mm^-1, with g = 0), else by
/// `sigma_a` and `sigma_s`, else by `reflectance` and `mfp` (1), else
/// pbrt-v4's default (whole milk's coefficients, per mm); the coefficients
/// or `mfp` (numbers or textures) times `scale`; `eta` 1.33; `g` 0; a
/// dielectric surface of that index and `roughness`.
fn subsurface(scene: &PbrtScene, p: &Params, loc: &Loc) -> Result<std::result::Result<Material, String>> {
    use crate::bssrdf::BssrdfTable;
    use crate::material::{Subsurface, SubsurfaceScattering};
    let mut g = p.get_float("g", 0.0)?;
    let scale = p.get_float("scale", 1.0)?;
    let eta = p.get_float("eta", 1.33)?;
    if !(eta.is_finite() && eta > 0.0) {
        return Err(located(
            loc,
            format!("subsurface: \"eta\" {eta} must be a positive number"),
        ));
    }
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(located(
            loc,
            format!("subsurface: \"scale\" {scale} must be a non-negative number"),
        ));
    }
    if !(g.is_finite() && g > -1.0 && g < 1.0) {
        return Err(located(loc, format!("subsurface: \"g\" {g} must lie in (-1, 1)")));
    }
    let name = p.get_string_or("name", "")?;
    // A coefficient times `scale`: a constant multiplied out, a texture wrapped.
    let scaled = |t: Texture| match t {
        Texture::Constant(c) => Texture::from(c * scale),
        t if scale == 1.0 => t,
        t => Texture::Scale {
            tex: Arc::new(t),
            scale: Arc::new(Texture::from(Vec3::splat(scale))),
        },
    };
    let coefficients = |a: Texture, s: Texture| SubsurfaceScattering::Coefficients {
        sigma_a: scaled(a),
        sigma_s: scaled(s),
    };
    let texture_of = |name: &str, default: f32| -> Result<std::result::Result<Texture, String>> {
        Ok(spectrum_texture(scene, p, name, default, loc)?.map_err(|why| format!("subsurface: {why}")))
    };
    let scattering = if !name.is_empty() {
        let Some((a, s)) = crate::medium::presets::scattering_preset(&name) else {
            return Err(located(
                place(p, "name", loc),
                format!("subsurface: no measured medium is named \"{name}\""),
            ));
        };
        // The presets' scattering coefficients are reduced ones.
        g = 0.0;
        coefficients(Texture::from(a), Texture::from(s))
    } else if p.has("sigma_a") || p.has("sigma_s") {
        match (p.has("sigma_a"), p.has("sigma_s")) {
            (true, true) => {}
            (true, false) => return Err(located(loc, "subsurface: \"sigma_a\" given without \"sigma_s\"")),
            _ => return Err(located(loc, "subsurface: \"sigma_s\" given without \"sigma_a\"")),
        }
        match (texture_of("sigma_a", 0.0)?, texture_of("sigma_s", 0.0)?) {
            (Ok(a), Ok(s)) => coefficients(a, s),
            (Err(why), _) | (_, Err(why)) => return Ok(Err(why)),
        }
    } else if p.has("reflectance") {
        let reflectance = match texture_of("reflectance", 1.0)? {
            Ok(t) => t,
            Err(why) => return Ok(Err(why)),
        };
        let mfp = match texture_of("mfp", 1.0)? {
            Ok(t) => t,
            Err(why) => return Ok(Err(why)),
        };
        if let Texture::Constant(m) = &mfp {
            if !(m.is_finite() && m.min_element() > 0.0) {
                return Err(located(
                    place(p, "mfp", loc),
                    format!("subsurface: \"mfp\" {m} must be positive"),
                ));
            }
        }
        SubsurfaceScattering::Reflectance {
            reflectance,
            mfp: scaled(mfp),
        }
    } else {
        coefficients(
            Texture::from(Vec3::new(0.0011, 0.0024, 0.014)),
            Texture::from(Vec3::new(2.55, 3.21, 3.77)),
        )
    };
    let roughness = match roughness(scene, p, loc)? {
        Ok(r) => r,
        Err(why) => return Ok(Err(why)),
    };
    Ok(Ok(Material::Subsurface(Box::new(Subsurface {
        eta,
        roughness,
        scattering,
        table: BssrdfTable::shared(g, eta),
    }))))
}

/// pbrt-v4's `hair` material (`HairMaterial::Create`): its absorption from
/// `sigma_a`, else `reflectance` (or `color`), else the melanin
/// concentrations, else brown hair (eumelanin 1.3); `eta` 1.55, `beta_m`
/// and `beta_n` 0.3 (kept within [0.01, 1]), `alpha` 2 degrees. Constant
/// values only.
fn hair(p: &Params) -> Result<std::result::Result<Material, String>> {
    for name in [
        "sigma_a",
        "reflectance",
        "color",
        "eumelanin",
        "pheomelanin",
        "eta",
        "beta_m",
        "beta_n",
        "alpha",
    ] {
        if p.get_texture(name)?.is_some() {
            return Ok(Err(format!("hair: a textured \"{name}\" is not supported")));
        }
    }
    let beta_m = p.get_float("beta_m", 0.3)?.clamp(0.01, 1.0);
    let beta_n = p.get_float("beta_n", 0.3)?.clamp(0.01, 1.0);
    let eta = p.get_float("eta", 1.55)?;
    let alpha = p.get_float("alpha", 2.0)?;
    let rgb = |name: &str| -> Result<Option<std::result::Result<Vec3, String>>> {
        Ok(p.get_spectrum(name)?.map(|v| {
            reflectance_rgb(&v).ok_or_else(|| format!("hair: \"{name}\" given as this spectrum is not supported"))
        }))
    };
    let (ce, cp) = (p.has("eumelanin"), p.has("pheomelanin"));
    let sigma_a = if let Some(s) = rgb("sigma_a")? {
        match s {
            Ok(s) => s.max(Vec3::ZERO),
            Err(why) => return Ok(Err(why)),
        }
    } else if let Some(c) = match rgb("reflectance")? {
        None => rgb("color")?,
        some => some,
    } {
        match c {
            Ok(c) => HairBxdf::sigma_a_from_reflectance(c.clamp(Vec3::ZERO, Vec3::ONE), beta_n),
            Err(why) => return Ok(Err(why)),
        }
    } else if ce || cp {
        HairBxdf::sigma_a_from_concentration(
            p.get_float("eumelanin", 0.0)?.max(0.0),
            p.get_float("pheomelanin", 0.0)?.max(0.0),
        )
    } else {
        HairBxdf::sigma_a_from_concentration(1.3, 0.0)
    };
    if !(eta.is_finite()
        && eta > 0.0
        && alpha.is_finite()
        && sigma_a.is_finite()
        && beta_m.is_finite()
        && beta_n.is_finite())
    {
        return Ok(Err("hair: its parameters must be finite and \"eta\" > 0".into()));
    }
    Ok(Ok(Material::Hair {
        sigma_a,
        eta,
        beta_m,
        beta_n,
        alpha,
    }))
}

trait OrDefaultTexture {
    fn unwrap_or_default_texture(self) -> Texture;
}

impl OrDefaultTexture for Option<Texture> {
    fn unwrap_or_default_texture(self) -> Texture {
        self.unwrap_or_else(|| Texture::from(Vec3::ZERO))
    }
}

/// A reflectance kept within [0, 1]: a constant is clamped; a texture is
/// left as it is (an image's texels are reflectances already).
fn clamped(t: Texture) -> Texture {
    match t {
        Texture::Constant(c) => Texture::from(c.clamp(Vec3::ZERO, Vec3::ONE)),
        t => t,
    }
}

/// A spectrum parameter of a material that may be a texture (`default`
/// grey when absent).
fn spectrum_texture(
    scene: &PbrtScene,
    p: &Params,
    name: &str,
    default: f32,
    loc: &Loc,
) -> Result<std::result::Result<Texture, String>> {
    match p.get_spectrum_or_texture(name)? {
        None => Ok(Ok(Texture::from(Vec3::splat(default)))),
        Some(SpectrumOrTexture::Texture(t)) => texture(scene, &t, TextureKind::Spectrum, place(p, name, loc), 0),
        Some(SpectrumOrTexture::Value(_)) => Ok(colour(p, name, loc)?.map(Texture::from)),
    }
}

/// An operand of a texture: a value or another texture of `kind`.
fn operand(
    scene: &PbrtScene,
    t: &super::ir::Texture,
    name: &str,
    kind: TextureKind,
    default: f32,
    depth: usize,
) -> Result<std::result::Result<Texture, String>> {
    let p = &t.params;
    let reference = match kind {
        TextureKind::Float => match p.get_float_or_texture(name)? {
            None => return Ok(Ok(Texture::from(Vec3::splat(default)))),
            Some(FloatOrTexture::Value(v)) => return Ok(Ok(Texture::from(Vec3::splat(v)))),
            Some(FloatOrTexture::Texture(r)) => r,
        },
        TextureKind::Spectrum => match p.get_spectrum_or_texture(name)? {
            None => return Ok(Ok(Texture::from(Vec3::splat(default)))),
            Some(SpectrumOrTexture::Value(_)) => return Ok(colour(p, name, &t.loc)?.map(Texture::from)),
            Some(SpectrumOrTexture::Texture(r)) => r,
        },
    };
    texture(scene, &reference, kind, place(p, name, &t.loc), depth + 1)
}

/// The texture named `name` of `kind`, referred to at `at`: an unknown
/// name or a missing image is an error there; an unsupported texture is
/// `Ok(Err(why))`.
fn texture(
    scene: &PbrtScene,
    name: &str,
    kind: TextureKind,
    at: &Loc,
    depth: usize,
) -> Result<std::result::Result<Texture, String>> {
    use crate::texture::{Encoding, ImageOptions, Mapping2D, MipFilter, NoiseTexture, Pattern, UvMapping, WrapMode};
    use glam::Affine3A;
    let kind_name = match kind {
        TextureKind::Float => "float",
        TextureKind::Spectrum => "spectrum",
    };
    let Some(t) = scene.texture(name, kind) else {
        return Err(located(at, format!("{kind_name} texture \"{name}\" is not defined")));
    };
    if depth > 64 {
        return Err(located(&t.loc, format!("texture \"{name}\": textures nested too deep")));
    }
    let p = &t.params;
    p.touch();
    let uv = |p: &Params| -> Result<UvMapping> {
        Ok(UvMapping {
            su: p.get_float("uscale", 1.0)?,
            sv: p.get_float("vscale", 1.0)?,
            du: p.get_float("udelta", 0.0)?,
            dv: p.get_float("vdelta", 0.0)?,
        })
    };
    // From the world to the texture's space: the inverse of the
    // transformation in force where the texture was defined.
    let to_texture = || -> Result<Affine3A> {
        let m = t.world_from_texture.inverse();
        if !m.is_finite() || t.world_from_texture.determinant() == 0.0 {
            return Err(located(
                &t.loc,
                format!("texture \"{name}\": its transformation is singular"),
            ));
        }
        Ok(Affine3A::from_mat4(m))
    };
    // The 2D mapping of an imagemap, checkerboard, dots or bilerp texture.
    let mapping = || -> Result<Mapping2D> {
        let kind = p.get_string_or("mapping", "uv")?;
        Ok(match kind.as_str() {
            "uv" => Mapping2D::Uv(uv(p)?),
            "spherical" => Mapping2D::Spherical(to_texture()?),
            "cylindrical" => Mapping2D::Cylindrical(to_texture()?),
            "planar" => Mapping2D::Planar {
                to_texture: to_texture()?,
                vs: p.get_vector3("v1", Vec3::X)?,
                vt: p.get_vector3("v2", Vec3::Y)?,
                ds: p.get_float("udelta", 0.0)?,
                dt: p.get_float("vdelta", 0.0)?,
            },
            other => {
                return Err(located(
                    place(p, "mapping", &t.loc),
                    format!(
                        "texture \"{name}\": unknown mapping \"{other}\" (\"uv\", \"spherical\", \"cylindrical\" or \"planar\")"
                    ),
                ))
            }
        })
    };
    // The octaves of a noise texture: pbrt-v4's default 8; beyond 32 the
    // octaves are finer than a float can place.
    let octaves = || -> Result<u32> {
        let n = p.get_int("octaves", 8)?;
        u32::try_from(n).ok().filter(|&n| n <= 32).ok_or_else(|| {
            located(
                place(p, "octaves", &t.loc),
                format!("texture \"{name}\": \"octaves\" {n} is not within 0..=32"),
            )
        })
    };
    let float_only = |class: &str| -> Result<()> {
        match kind {
            TextureKind::Float => Ok(()),
            TextureKind::Spectrum => Err(located(
                &t.loc,
                format!("texture \"{name}\": \"{class}\" is a float texture only (as in pbrt-v4)"),
            )),
        }
    };
    let arc = |t: Texture| Arc::new(t);
    // Two operands, or why one is not supported.
    type Pair = (Arc<Texture>, Arc<Texture>);
    let pair = |a: (&str, f32), b: (&str, f32)| -> Result<std::result::Result<Pair, String>> {
        let first = match operand(scene, t, a.0, kind, a.1, depth)? {
            Ok(x) => x,
            Err(why) => return Ok(Err(why)),
        };
        let second = match operand(scene, t, b.0, kind, b.1, depth)? {
            Ok(x) => x,
            Err(why) => return Ok(Err(why)),
        };
        Ok(Ok((arc(first), arc(second))))
    };
    let noise = |pattern: Pattern| -> Result<std::result::Result<Texture, String>> {
        Ok(Ok(Texture::Noise(Arc::new(NoiseTexture {
            to_texture: to_texture()?,
            pattern,
        }))))
    };
    match t.class.as_str() {
        "constant" => operand(scene, t, "value", kind, 1.0, depth),
        "scale" => {
            let tex = match operand(scene, t, "tex", kind, 1.0, depth)? {
                Ok(x) => x,
                Err(why) => return Ok(Err(why)),
            };
            let scale = match operand(scene, t, "scale", TextureKind::Float, 1.0, depth)? {
                Ok(x) => x,
                Err(why) => return Ok(Err(why)),
            };
            Ok(Ok(Texture::Scale {
                tex: arc(tex),
                scale: arc(scale),
            }))
        }
        "mix" => {
            let mut v = Vec::new();
            for (n, k, d) in [
                ("tex1", kind, 0.0),
                ("tex2", kind, 1.0),
                ("amount", TextureKind::Float, 0.5),
            ] {
                match operand(scene, t, n, k, d, depth)? {
                    Ok(x) => v.push(arc(x)),
                    Err(why) => return Ok(Err(why)),
                }
            }
            let amount = v.pop().expect("three");
            let b = v.pop().expect("three");
            let a = v.pop().expect("three");
            Ok(Ok(Texture::Mix { a, b, amount }))
        }
        "directionmix" => {
            let dir = t
                .world_from_texture
                .transform_vector3(p.get_vector3("dir", Vec3::Y)?)
                .normalize_or_zero();
            if dir == Vec3::ZERO || !dir.is_finite() {
                return Err(located(
                    place(p, "dir", &t.loc),
                    format!("texture \"{name}\": \"dir\" is not a direction"),
                ));
            }
            let (a, b) = match pair(("tex1", 0.0), ("tex2", 1.0))? {
                Ok(x) => x,
                Err(why) => return Ok(Err(why)),
            };
            Ok(Ok(Texture::DirectionMix {
                a,
                b,
                dir: Arc::new(dir),
            }))
        }
        "checkerboard" => {
            let dimension = p.get_int("dimension", 2)?;
            if dimension != 2 && dimension != 3 {
                return Err(located(
                    place(p, "dimension", &t.loc),
                    format!("texture \"{name}\": a checkerboard of dimension {dimension} (2 or 3)"),
                ));
            }
            let (even, odd) = match pair(("tex1", 1.0), ("tex2", 0.0))? {
                Ok(x) => x,
                Err(why) => return Ok(Err(why)),
            };
            Ok(Ok(if dimension == 2 {
                Texture::Checkerboard {
                    even,
                    odd,
                    mapping: Arc::new(mapping()?),
                }
            } else {
                Texture::Checkerboard3D {
                    even,
                    odd,
                    to_texture: Arc::new(to_texture()?),
                }
            }))
        }
        "dots" => {
            let (inside, outside) = match pair(("inside", 1.0), ("outside", 0.0))? {
                Ok(x) => x,
                Err(why) => return Ok(Err(why)),
            };
            Ok(Ok(Texture::Dots {
                inside,
                outside,
                mapping: Arc::new(mapping()?),
            }))
        }
        "bilerp" => {
            let mut corners = [Vec3::ZERO; 4];
            for (c, (n, d)) in corners
                .iter_mut()
                .zip([("v00", 0.0), ("v01", 1.0), ("v10", 0.0), ("v11", 1.0)])
            {
                *c = match kind {
                    TextureKind::Float => Vec3::splat(p.get_float(n, d)?),
                    TextureKind::Spectrum if p.get(n).is_none() => Vec3::splat(d),
                    TextureKind::Spectrum => match colour(p, n, &t.loc)? {
                        Ok(v) => v,
                        Err(why) => return Ok(Err(why)),
                    },
                };
            }
            Ok(Ok(Texture::Bilerp(Arc::new((corners, mapping()?)))))
        }
        "fbm" | "wrinkled" => {
            float_only(&t.class)?;
            let (octaves, omega) = (octaves()?, p.get_float("roughness", 0.5)?);
            noise(if t.class == "fbm" {
                Pattern::Fbm { octaves, omega }
            } else {
                Pattern::Wrinkled { octaves, omega }
            })
        }
        "windy" => {
            float_only("windy")?;
            noise(Pattern::Windy)
        }
        "marble" => {
            if kind == TextureKind::Float {
                return Err(located(
                    &t.loc,
                    format!("texture \"{name}\": \"marble\" is a spectrum texture only (as in pbrt-v4)"),
                ));
            }
            noise(Pattern::Marble {
                octaves: octaves()?,
                omega: p.get_float("roughness", 0.5)?,
                scale: p.get_float("scale", 1.0)?,
                variation: p.get_float("variation", 0.2)?,
            })
        }
        "imagemap" => {
            let Some(file) = p.get_string("filename")? else {
                return Err(located(&t.loc, format!("imagemap \"{name}\": \"filename\" is missing")));
            };
            let file_at = place(p, "filename", &t.loc).clone();
            let Some(path) = scene.candidates(&file_at, &file).into_iter().find(|c| c.is_file()) else {
                return Err(PbrtError::at(&file_at, format!("imagemap \"{name}\": image \"{file}\" not found")).into());
            };
            let wrap_name = p.get_string_or("wrap", "repeat")?;
            let Some(wrap) = WrapMode::parse(&wrap_name) else {
                return Err(located(
                    &t.loc,
                    format!("imagemap \"{name}\": unknown wrap \"{wrap_name}\""),
                ));
            };
            let enc_name = p.get_string_or("encoding", default_encoding(&file))?;
            let Some(encoding) = Encoding::parse(&enc_name) else {
                return Err(located(
                    &t.loc,
                    format!("imagemap \"{name}\": unknown encoding \"{enc_name}\""),
                ));
            };
            let filter_name = p.get_string_or("filter", "bilinear")?;
            let Some(filter) = MipFilter::parse(&filter_name) else {
                return Err(located(
                    &t.loc,
                    format!("imagemap \"{name}\": unknown filter \"{filter_name}\""),
                ));
            };
            // A mapping other than (u, v) is applied before the image is
            // looked up, which then takes (s, t) as they are.
            let mapped = match mapping()? {
                Mapping2D::Uv(m) => Err(m),
                other => Ok(other),
            };
            let opts = ImageOptions {
                wrap,
                encoding,
                scale: p.get_float("scale", 1.0)?,
                invert: p.get_bool("invert", false)?,
                mapping: mapped.clone().err().unwrap_or_default(),
                filter,
            };
            let tex =
                Texture::image(&path, &opts).map_err(|e| located(&file_at, format!("imagemap \"{name}\": {e}")))?;
            Ok(Ok(match mapped {
                Ok(mapping) => Texture::Mapped {
                    mapping: Arc::new(mapping),
                    tex: Arc::new(tex),
                },
                Err(_) => tex,
            }))
        }
        other => Ok(Err(format!("texture \"{name}\" of class \"{other}\" is not supported"))),
    }
}

/// The microfacet roughness of a pbrt-v4 material: `uroughness` and
/// `vroughness`, each defaulting to `roughness` (default 0), each a float or
/// a float texture, and `remaproughness`. A constant texture becomes a
/// number: a roughness that does not vary keeps the constant path.
fn roughness(scene: &PbrtScene, p: &Params, loc: &Loc) -> Result<std::result::Result<MaterialRoughness, String>> {
    roughness_of(scene, p, loc, "")
}

/// An index of refraction as a pbrt-v4 file gives it.
enum Eta {
    Constant(f32),
    /// A spectrum that varies (dispersion): its index at 550 nm, near the
    /// eye's peak sensitivity, and each colour channel's.
    Dispersive {
        at_550: f32,
        channels: Vec3,
    },
}

/// An index of refraction that pbrt-v4 takes as a float or a spectrum (never
/// a texture; only its hair material does): 1.5 when absent.
fn eta_param(p: &Params, name: &str) -> Result<std::result::Result<Eta, String>> {
    let spectrum = match p.get(name) {
        None => return Ok(Ok(Eta::Constant(1.5))),
        Some(e) if e.ty == super::ParamType::Float => return Ok(Ok(Eta::Constant(p.get_float(name, 1.5)?))),
        Some(e) if e.ty == super::ParamType::Texture => {
            return Ok(Err(format!(
                "a textured \"{name}\" is not supported (pbrt-v4 takes a float or a spectrum)"
            )))
        }
        Some(_) => p.get_spectrum(name)?,
    };
    let eta = match &spectrum {
        Some(SpectrumValue::Sampled(s)) if s.value.windows(2).all(|w| w[0] == w[1]) && !s.value.is_empty() => {
            return Ok(Ok(Eta::Constant(s.value[0])))
        }
        Some(SpectrumValue::Sampled(s)) => {
            // Beyond its wavelengths a sampled index keeps its end values
            // (pbrt-v4's would drop to 0, an index no glass has).
            let (lo, hi) = (s.lambda[0], s.lambda[s.lambda.len() - 1]);
            Eta::Dispersive {
                at_550: s.eval(550f32.clamp(lo, hi)),
                channels: super::spectrum::channel_etas(|l| s.eval((l as f32).clamp(lo, hi)) as f64),
            }
        }
        Some(SpectrumValue::Named(n)) => match super::spectrum::glass_eta_550(n) {
            Some(at_550) => Eta::Dispersive {
                at_550,
                channels: super::spectrum::channel_etas(|l| super::spectrum::glass_eta(n, l).unwrap_or(1.0)),
            },
            None => {
                return Ok(Err(format!(
                    "the spectrum \"{n}\" as \"{name}\" is not supported (only pbrt-v4's glass spectra)"
                )))
            }
        },
        _ => return Ok(Err(format!("\"{name}\" given as this spectrum is not supported"))),
    };
    if let Eta::Dispersive { at_550, channels } = eta {
        if !(at_550.is_finite() && at_550 > 0.0 && channels.is_finite() && channels.min_element() > 0.0) {
            return Ok(Err(format!(
                "an \"{name}\" spectrum must be positive over the visible wavelengths"
            )));
        }
    }
    Ok(Ok(eta))
}

/// An index of refraction where one index serves all three colour channels
/// (thin dielectrics and coats): a spectrum that varies (dispersion) is
/// taken at 550 nm and noted in `approximated`.
fn constant_eta(
    p: &Params,
    name: &str,
    loc: &Loc,
    approximated: &mut Vec<(Loc, String)>,
) -> Result<std::result::Result<f32, String>> {
    Ok(match eta_param(p, name)? {
        Ok(Eta::Constant(eta)) => Ok(eta),
        Ok(Eta::Dispersive { at_550, .. }) => {
            approximated.push((
                place(p, name, loc).clone(),
                format!(
                    "an \"{name}\" that varies with wavelength (dispersion) is not supported here (--lenient uses \
                     {at_550:.4}, its value at 550 nm)"
                ),
            ));
            Ok(at_550)
        }
        Err(why) => Err(why),
    })
}

/// A metal's Fresnel terms: `reflectance` (a colour or a texture), or
/// `prefix` + `eta` and `k` (copper by default, as pbrt-v4's); both at once
/// is an error, as there.
fn conductor_fresnel(
    scene: &PbrtScene,
    p: &Params,
    loc: &Loc,
    ty: &str,
    prefix: &str,
) -> Result<std::result::Result<ConductorFresnel, String>> {
    let (eta_name, k_name) = (format!("{prefix}eta"), format!("{prefix}k"));
    if p.has("reflectance") && (p.has(&eta_name) || p.has(&k_name)) {
        return Err(located(
            loc,
            format!("{ty}: give \"reflectance\" or \"{eta_name}\" and \"{k_name}\", not both"),
        ));
    }
    if p.has("reflectance") {
        return Ok(
            spectrum_texture(scene, p, "reflectance", 1.0, loc)?.map(|r| ConductorFresnel::Reflectance(clamped(r)))
        );
    }
    let (cu_eta, cu_k) = crate::bsdf::named_metal("Cu").unwrap_or((Vec3::ONE, Vec3::ZERO));
    let read = |name: &str, default: Vec3| -> Result<std::result::Result<Vec3, String>> {
        if p.has(name) {
            colour(p, name, loc)
        } else {
            Ok(Ok(default))
        }
    };
    match (read(&eta_name, cu_eta)?, read(&k_name, cu_k)?) {
        (Ok(eta), Ok(k)) => {
            if eta.min_element() <= 0.0 || k.min_element() < 0.0 {
                return Err(located(
                    loc,
                    format!("{ty}: \"{eta_name}\" must be positive and \"{k_name}\" not negative"),
                ));
            }
            Ok(Ok(ConductorFresnel::Ior { eta, k }))
        }
        (Err(why), _) | (_, Err(why)) => Ok(Err(why)),
    }
}

/// The roughness of one interface of a layered material, whose parameters
/// are `prefix` + `roughness` and so on (`interface.`, `conductor.`).
fn roughness_of(
    scene: &PbrtScene,
    p: &Params,
    loc: &Loc,
    prefix: &str,
) -> Result<std::result::Result<MaterialRoughness, String>> {
    let remap = p.get_bool("remaproughness", true)?;
    let both = format!("{prefix}roughness");
    let r = p.get_float_or_texture(&both)?;
    // `roughness` is converted once when both directions take it: its
    // texture is then one `Arc`, looked up once per point.
    let mut shared: Option<OneRoughness> = None;
    let mut uv = [OneRoughness::Value(0.0), OneRoughness::Value(0.0)];
    let names = [format!("{prefix}uroughness"), format!("{prefix}vroughness")];
    for (i, n) in names.iter().map(String::as_str).enumerate() {
        let (from, given) = match p.get_float_or_texture(n)? {
            Some(x) => (n, Some(x)),
            None => (both.as_str(), r.clone()),
        };
        let x = match shared.as_ref().filter(|_| from == both) {
            Some(x) => x.clone(),
            None => {
                let x = match given {
                    None => OneRoughness::Value(0.0),
                    Some(FloatOrTexture::Value(v)) => OneRoughness::Value(v),
                    Some(FloatOrTexture::Texture(name)) => match float_texture(scene, p, from, &name, loc)? {
                        Err(why) => return Ok(Err(why)),
                        Ok(Texture::Constant(c)) => OneRoughness::Value(c.x),
                        Ok(t) => OneRoughness::Texture(Arc::new(t)),
                    },
                };
                if from == both {
                    shared = Some(x.clone());
                }
                x
            }
        };
        if let OneRoughness::Value(v) = x {
            if !(v.is_finite() && v >= 0.0) {
                return Err(located(loc, format!("\"{n}\" {v} must be a number >= 0")));
            }
        }
        uv[i] = x;
    }
    Ok(Ok(match uv {
        [OneRoughness::Value(u), OneRoughness::Value(v)] => Roughness { u, v, remap }.into(),
        [u, v] => MaterialRoughness::Textured {
            u: u.into_texture(),
            v: v.into_texture(),
            remap,
        },
    }))
}

/// One direction's roughness as a material gives it.
#[derive(Clone)]
enum OneRoughness {
    Value(f32),
    Texture(Arc<Texture>),
}

impl OneRoughness {
    fn into_texture(self) -> Arc<Texture> {
        match self {
            OneRoughness::Value(v) => Arc::new(Texture::from(Vec3::splat(v))),
            OneRoughness::Texture(t) => t,
        }
    }
}

/// The float texture `name` that parameter `param` of a material refers to.
/// pbrt-v4 keeps float and spectrum textures apart, so a spectrum texture
/// of that name is an error that says so.
fn float_texture(
    scene: &PbrtScene,
    p: &Params,
    param: &str,
    name: &str,
    loc: &Loc,
) -> Result<std::result::Result<Texture, String>> {
    let at = place(p, param, loc);
    if scene.texture(name, TextureKind::Float).is_none() && scene.texture(name, TextureKind::Spectrum).is_some() {
        return Err(located(
            at,
            format!("\"{param}\": texture \"{name}\" is a spectrum texture, not a float texture"),
        ));
    }
    texture(scene, name, TextureKind::Float, at, 0)
}

/// An RGB parameter given as a number, an `rgb`, a named spectrum (pbrt-v4's
/// metal spectra, fitted to RGB once: `bsdf::metals`) or sampled values.
fn colour(p: &Params, name: &str, loc: &Loc) -> Result<std::result::Result<Vec3, String>> {
    if p.get(name).is_some_and(|e| e.ty == super::ParamType::Float) {
        return Ok(Ok(Vec3::splat(p.get_float(name, 0.0)?)));
    }
    if let Some(cs) = colour_space(p, name) {
        return Ok(Err(format!("rgb in colour space \"{cs}\" is not supported")));
    }
    let v = match p.get_spectrum_or_texture(name)? {
        None => return Ok(Err(format!("\"{name}\" is missing"))),
        Some(SpectrumOrTexture::Texture(t)) => {
            return Ok(Err(format!("a textured \"{name}\" (texture \"{t}\") is not supported")))
        }
        Some(SpectrumOrTexture::Value(v)) => v,
    };
    let c = match &v {
        SpectrumValue::Named(n) => match crate::bsdf::named_spectrum_rgb(n) {
            Some(c) => c,
            None => return Ok(Err(format!("the spectrum \"{n}\" is not supported for \"{name}\""))),
        },
        other => match reflectance_rgb(other) {
            Some(c) => c,
            None => return Ok(Err(format!("\"{name}\" given as this spectrum is not supported"))),
        },
    };
    if !c.is_finite() {
        return Err(located(loc, format!("\"{name}\" must be finite")));
    }
    Ok(Ok(c))
}

/// A reflectance spectrum's RGB: an `rgb` as given; a sampled spectrum's
/// colour divided by that of the constant spectrum 1 (so a constant
/// reflectance is that grey).
/// The medium of a coat (`albedo`, `g`; the walk's `maxdepth` and
/// `nsamples`, checked here): `None` for one that only absorbs (`albedo` 0,
/// pbrt-v4's default). The error is the file's; the inner one says what is
/// not supported.
fn coat_medium(
    scene: &PbrtScene,
    p: &Params,
    ty: &str,
    max_depth: i32,
    samples: i32,
    loc: &Loc,
) -> Result<std::result::Result<Option<CoatMedium>, String>> {
    if !(0..=1000).contains(&max_depth) || !(1..=1000).contains(&samples) {
        return Err(located(
            loc,
            format!("{ty}: \"maxdepth\" must be in 0..1000 and \"nsamples\" in 1..1000"),
        ));
    }
    let g = match p.get_float_or_texture("g")? {
        None => 0.0,
        Some(FloatOrTexture::Value(g)) => g,
        Some(FloatOrTexture::Texture(_)) => return Ok(Err("a textured coat \"g\" is not supported".into())),
    };
    if !(g > -1.0 && g < 1.0) {
        return Err(located(loc, format!("{ty}: \"g\" {g} must be in (-1, 1)")));
    }
    let albedo = match p.get_spectrum_or_texture("albedo")? {
        None => return Ok(Ok(None)),
        // Looked up, and kept within [0, 1], at each hit.
        Some(SpectrumOrTexture::Texture(t)) => {
            match texture(scene, &t, TextureKind::Spectrum, place(p, "albedo", loc), 0)? {
                Ok(t) => t,
                Err(why) => return Ok(Err(why)),
            }
        }
        Some(SpectrumOrTexture::Value(v)) => match reflectance_rgb(&v) {
            Some(c) if c.is_finite() => {
                let c = c.clamp(Vec3::ZERO, Vec3::ONE);
                if c == Vec3::ZERO {
                    return Ok(Ok(None));
                }
                Texture::from(c)
            }
            Some(_) => return Err(located(loc, format!("{ty}: \"albedo\" must be finite"))),
            None => return Ok(Err("a coat \"albedo\" given as this spectrum is not supported".into())),
        },
    };
    Ok(Ok(Some(CoatMedium {
        albedo,
        g,
        max_depth: max_depth as u32,
        samples: samples as u32,
    })))
}

/// Notes in `approximated` an `rgb` albedo parameter with a component above
/// 1, which pbrt-v4 refuses ("used as an albedo has > 1 component"); the
/// caller clamps it to 1, what `--lenient` renders.
fn check_albedo(p: &Params, name: &str, loc: &Loc, approximated: &mut Vec<(Loc, String)>) -> Result<()> {
    if let Some(SpectrumValue::Rgb(c)) = p.get_spectrum(name)? {
        if c.max_element() > 1.0 {
            approximated.push((
                place(p, name, loc).clone(),
                format!(
                    "\"rgb {name}\" [ {} {} {} ] has a component above 1, which pbrt-v4 refuses for an albedo \
                     (--lenient clamps it to 1)",
                    c.x, c.y, c.z
                ),
            ));
        }
    }
    Ok(())
}

fn reflectance_rgb(v: &SpectrumValue) -> Option<Vec3> {
    match v {
        SpectrumValue::Rgb(c) => Some(*c),
        SpectrumValue::Sampled(s) => {
            let white = xyz_to_linear_srgb(spectrum_to_xyz(|_| 1.0));
            Some(s.to_rgb() / white)
        }
        _ => None,
    }
}

/// Centre and scale of a transformation that is a rotation (or
/// reflection) times a uniform scale plus a translation.
fn similarity(m: Mat4) -> Option<(Vec3, f32)> {
    if !m.row(3).abs_diff_eq(glam::Vec4::W, 1e-6) {
        return None;
    }
    let axes = [Vec3::X, Vec3::Y, Vec3::Z].map(|a| m.transform_vector3(a));
    let s = axes[0].length();
    let tol = 1e-4 * s;
    let ok = s > 0.0
        && axes.iter().all(|a| (a.length() - s).abs() <= tol)
        && axes[0].dot(axes[1]).abs() <= tol * s
        && axes[0].dot(axes[2]).abs() <= tol * s
        && axes[1].dot(axes[2]).abs() <= tol * s;
    let centre = m.transform_point3(Vec3::ZERO);
    (ok && centre.is_finite() && s.is_finite()).then_some((centre, s))
}

/// Reflects the scene across the camera's vertical plane (through the
/// camera, spanned by forward and up): the camera then sees pbrt's mirror
/// image of our convention. Triangles keep the side they face.
fn reflect(desc: &mut SceneDesc) {
    let c = &desc.camera;
    let forward = (c.look_at - c.position).normalize();
    let n = forward.cross(c.up).normalize();
    let o = c.position;
    let point = |p: Vec3| p - 2.0 * (p - o).dot(n) * n;
    let vector = |v: Vec3| v - 2.0 * v.dot(n) * n;
    // The default coordinates too follow their vertices.
    desc.triangles.reflect(point, vector, DEFAULT_UV);
    let r = Mat4::from_cols(
        vector(Vec3::X).extend(0.0),
        vector(Vec3::Y).extend(0.0),
        vector(Vec3::Z).extend(0.0),
        point(Vec3::ZERO).extend(1.0),
    );
    let affine = glam::Affine3A::from_mat4(r);
    for (_, m) in &mut desc.materials {
        m.reflect(&affine);
    }
    for c in &mut desc.cutouts {
        c.alpha = c.alpha.reflected(&affine);
    }
    for s in &mut desc.spheres {
        s.sphere.centre = point(s.sphere.centre);
        let a = s.axes.unwrap_or(glam::Mat3::IDENTITY);
        s.axes = Some(glam::Mat3::from_cols(
            vector(a.x_axis),
            vector(a.y_axis),
            vector(a.z_axis),
        ));
    }
    for d in &mut desc.disks {
        d.centre = point(d.centre);
        d.normal = vector(d.normal);
        d.axes = d.axes.map(|a| a.map(vector));
    }
    for c in &mut desc.curves {
        c.curve.cp = c.curve.cp.map(point);
        c.curve.n = c.curve.n.map(vector);
    }
    for m in &mut desc.moving {
        m.motion = m.motion.mirrored(r);
    }
    for m in &mut desc.moving_shapes {
        m.motion = m.motion.mirrored(r);
    }
    desc.camera_motion = desc.camera_motion.as_ref().map(|m| m.mirrored(r));
    // Emitters' surfaces follow their lights' vertices (turned as below).
    for s in desc.light_surfaces.iter_mut().flatten() {
        if let Some(ns) = &mut s.normals {
            let [a, b, c] = ns.map(vector);
            *ns = [a, c, b];
        }
        if let Some([a, b, c]) = s.uvs {
            s.uvs = Some([a, c, b]);
        }
        s.axes = s
            .axes
            .map(|a| glam::Mat3::from_cols(vector(a.x_axis), vector(a.y_axis), vector(a.z_axis)));
    }
    for (_, m) in &mut desc.media {
        if let Some(g) = &m.density {
            m.density = Some(std::sync::Arc::new(g.reflected(r)));
        }
    }
    for l in &mut desc.lights {
        match l {
            Light::Sphere { sphere, image, .. } => {
                sphere.centre = point(sphere.centre);
                if let Some(t) = image {
                    let a = t.axes;
                    *image = Some(Arc::new(ImageOnSphere {
                        image: t.image.clone(),
                        axes: glam::Mat3::from_cols(vector(a.x_axis), vector(a.y_axis), vector(a.z_axis)),
                    }));
                }
            }
            Light::Point { position, .. } => *position = point(*position),
            Light::Triangle { vertices, image, .. } => {
                let [a, b, c] = vertices.map(point);
                *vertices = [a, c, b];
                if let Some(t) = image {
                    let [a, b, c] = t.uv;
                    *image = Some(Arc::new(ImageOnTriangle {
                        image: t.image.clone(),
                        uv: [a, c, b],
                    }));
                }
            }
            Light::Spot {
                position, direction, ..
            } => {
                *position = point(*position);
                *direction = vector(*direction);
            }
            Light::Distant { direction, .. } => *direction = vector(*direction),
            Light::Goniometric { position, to_light, .. } | Light::Projection { position, to_light, .. } => {
                *position = point(*position);
                // The image's frame sees the reflected world reflected back.
                *to_light *= glam::Mat3::from_cols(vector(Vec3::X), vector(Vec3::Y), vector(Vec3::Z));
            }
            Light::Disk { disk, .. } => {
                disk.centre = point(disk.centre);
                disk.normal = vector(disk.normal);
                disk.axes = disk.axes.map(vector);
            }
            Light::Infinite { to_world, portal, .. } => {
                *to_world = glam::Mat3::from_cols(
                    vector(to_world.x_axis),
                    vector(to_world.y_axis),
                    vector(to_world.z_axis),
                );
                if let Some(q) = portal {
                    *q = std::sync::Arc::new(q.reflected(point, vector));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{PrimKind, Scene};

    fn convert_text(text: &str, lenient: bool) -> Result<Converted> {
        let path = Path::new("dir/main.pbrt");
        let scene = super::super::parse_bytes(path, text.as_bytes().to_vec(), &crate::scene::mesh::Disk)?;
        convert(&scene, path, lenient)
    }

    fn ok(text: &str) -> Converted {
        convert_text(text, false).unwrap_or_else(|e| panic!("{e}"))
    }

    /// A unit quad in the z = 0 plane at x in [x0, x0 + 1], y in [-0.5, 0.5],
    /// (p1 - p0) x (p2 - p0) along +z.
    fn quad(x0: f32) -> String {
        let x1 = x0 + 1.0;
        format!(
            "Shape \"trianglemesh\" \"point3 P\" [ {x0} -0.5 0  {x1} -0.5 0  {x1} 0.5 0  {x0} 0.5 0 ] \
             \"integer indices\" [ 0 1 2 0 2 3 ]\n"
        )
    }

    /// The material name seen at pixel (x, y).
    fn seen(c: &Converted, x: f32, y: f32) -> Option<String> {
        let scene = Scene::build(c.desc.clone()).unwrap();
        let ray = scene.camera.generate_ray(x, y);
        let hit = scene.intersect(&ray, 1e-4, f32::INFINITY)?;
        (hit.kind != PrimKind::Light).then(|| scene.material_names[hit.material as usize].clone())
    }

    /// A red quad at world x in [0.5, 1.5] and a green one at [-1.5, -0.5],
    /// seen from z = -5 looking at the origin; `pre` comes before LookAt.
    fn two_quads(pre: &str) -> Converted {
        convert_text(
            &two_quads_text(pre, "Camera \"perspective\" \"float fov\" [ 40 ]"),
            false,
        )
        .unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`two_quads`]' file, seen by `camera`.
    fn two_quads_text(pre: &str, camera: &str) -> String {
        format!(
            "{pre}LookAt 0 0 -5  0 0 0  0 1 0\n{camera}\n\
             Film \"rgb\" \"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ]\nWorldBegin\n\
             MakeNamedMaterial \"red\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 0.8 0 0 ]\n\
             MakeNamedMaterial \"green\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 0 0.8 0 ]\n\
             NamedMaterial \"red\"\n{}NamedMaterial \"green\"\n{}",
            quad(0.5),
            quad(-1.5)
        )
    }

    #[test]
    fn alpha_cuts_a_shape_out_as_pbrt_does() {
        // The red quad at x in [0.5, 1.5] in front (z = -1) of a green quad
        // covering both halves of the picture.
        let scene = |alpha: &str| {
            ok(&format!(
                "Scale -1 1 1\nLookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [ 40 ]\n\
                 Film \"rgb\" \"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ]\nWorldBegin\n\
                 Texture \"half\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float vscale\" 1 \
                 \"float tex1\" 1 \"float tex2\" 0\n\
                 MakeNamedMaterial \"red\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 0.8 0 0 ]\n\
                 MakeNamedMaterial \"green\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 0 0.8 0 ]\n\
                 NamedMaterial \"green\"\nShape \"trianglemesh\" \"point3 P\" [ -3 -2 0  3 -2 0  3 2 0  -3 2 0 ] \
                 \"integer indices\" [ 0 1 2 0 2 3 ]\n\
                 NamedMaterial \"red\"\nShape \"trianglemesh\" \"point3 P\" [ 0.5 -0.5 -1  1.5 -0.5 -1  1.5 0.5 -1  0.5 0.5 -1 ] \
                 \"integer indices\" [ 0 1 2 0 2 3 ] \"point2 uv\" [ 0 0  1 0  1 1  0 1 ] {alpha}\n"
            ))
        };
        // Pixel columns where the quad's world x is 0.69 and 1.31 (world +x
        // is the picture's left: `Scale -1 1 1`).
        let (left, right) = (15.0, 11.0);
        let solid = scene("");
        assert!(solid.desc.cutouts.is_empty());
        assert_eq!(seen(&solid, left, 10.0).as_deref(), Some("red"));
        // An alpha of 1 or more is no cut-out at all, pbrt-v4's rule.
        assert!(scene("\"float alpha\" 1").desc.cutouts.is_empty());
        let gone = scene("\"float alpha\" 0");
        assert_eq!(gone.desc.cutouts.len(), 1);
        assert_eq!(seen(&gone, left, 10.0).as_deref(), Some("green"));
        assert_eq!(seen(&gone, right, 10.0).as_deref(), Some("green"));
        // Solid for u < 1/2, which is world x < 1.
        let half = scene("\"texture alpha\" \"half\"");
        assert_eq!(seen(&half, left, 10.0).as_deref(), Some("red"));
        assert_eq!(seen(&half, right, 10.0).as_deref(), Some("green"));
    }

    #[test]
    fn a_spheres_texture_coordinates_turn_and_mirror_with_it() {
        // pbrt's picture of this camera is mirrored: the scene is reflected
        // across x = 0, and the texture coordinates must stay where pbrt's are.
        let uv_at = |pre: &str, pbrt_point: Vec3| {
            let c = ok(&format!(
                "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n{pre}Shape \"sphere\"\n"
            ));
            assert!(c.mirrored);
            let scene = Scene::build(c.desc.clone()).unwrap();
            let ours = pbrt_point * Vec3::new(-1.0, 1.0, 1.0);
            let ray = crate::math::Ray::new(ours * 3.0, -ours);
            let hit = scene.intersect(&ray, 1e-4, f32::INFINITY).unwrap();
            assert!((hit.p - ours).length() < 1e-4);
            hit.uv
        };
        let close = |a: crate::math::Vec2, b: [f32; 2]| (a.x - b[0]).abs() < 1e-4 && (a.y - b[1]).abs() < 1e-4;
        // pbrt-v4: u = phi / 2 pi about the object's z axis, v = 1 at +z.
        let uv = uv_at("", Vec3::new(0.6, 0.8, 0.0));
        assert!(close(uv, [0.8f32.atan2(0.6) / std::f32::consts::TAU, 0.5]), "{uv}");
        // Turned so that the object's +z is the world's +y: the pole on top.
        let uv = uv_at("Rotate -90 1 0 0\n", Vec3::Y);
        assert!((uv.y - 1.0).abs() < 1e-4, "{uv}");
        let uv = uv_at("Rotate -90 1 0 0\n", Vec3::new(0.6, 0.0, -0.8));
        assert!(close(uv, [0.8f32.atan2(0.6) / std::f32::consts::TAU, 0.5]), "{uv}");
    }

    #[test]
    fn alpha_on_an_area_light_or_naming_no_float_texture_is_refused_at_its_place() {
        let light = "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\"\n\
                     Shape \"sphere\" \"float alpha\" 0.5\nAttributeEnd\n";
        let e = convert_text(light, false).unwrap_err().to_string();
        assert!(
            e.contains("main.pbrt:4: an \"alpha\" cut-out on an area light is not supported, only \"float alpha\" 0"),
            "{e}"
        );
        // Leniently, the light shines whole.
        let c = convert_text(light, true).unwrap();
        assert!(c.desc.cutouts.is_empty() && c.desc.lights.len() == 1);
        let e = convert_text("WorldBegin\nShape \"sphere\" \"texture alpha\" \"nothing\"\n", false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("main.pbrt:2") && e.contains("nothing"), "{e}");
    }

    #[test]
    fn an_area_light_of_alpha_zero_is_a_light_no_ray_meets() {
        // A sphere light and a quad light of alpha 0 between two visible
        // emitters, and a grey wall behind them all at z = 5.
        let text = "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [-9 -9 5 9 -9 5 9 9 5 -9 9 5] \"integer indices\" [0 1 2 0 2 3]\n\
                    AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\nTranslate -3 0 2\nShape \"sphere\"\nAttributeEnd\n\
                    AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\nTranslate 0 0 2\nShape \"sphere\" \"float alpha\" 0\nAttributeEnd\n\
                    AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [3 3 3]\n\
                    Shape \"bilinearmesh\" \"point3 P\" [2 -1 2 4 -1 2 2 1 2 4 1 2] \"float alpha\" [ 0 ]\nAttributeEnd\n";
        let c = convert_text(text, false).unwrap();
        assert!(c.desc.cutouts.is_empty());
        // The first sphere, the second, then the quad's two triangles.
        assert_eq!(c.desc.lights.len(), 4);
        assert_eq!(c.desc.invisible_lights, [false, true, true, true]);
        let scene = crate::Scene::build(c.desc).unwrap();
        assert!(scene.light_is_met(0) && !scene.light_is_met(1) && !scene.light_is_met(2));
        // Rays along +z (ours mirrored, x -> -x): the visible sphere stops
        // one; through the invisible ones they reach the wall.
        let hit = |x: f32| {
            let h = scene.intersect(
                &crate::math::Ray::new(Vec3::new(x, 0.0, 0.0), Vec3::Z),
                1e-4,
                f32::INFINITY,
            );
            h.map(|h| (h.t, h.light))
        };
        assert_eq!(hit(3.0), Some((1.0, Some(0))));
        for x in [0.0, -3.0] {
            let (t, light) = hit(x).unwrap();
            assert!((t - 5.0).abs() < 1e-4 && light.is_none(), "{x}: {t} {light:?}");
        }
        // They emit all the same: the middle one's light samples reach the wall.
        let ls = scene.lights[1]
            .sample_li(Vec3::new(0.0, 0.0, 5.0), crate::math::Vec2::new(0.3, 0.6))
            .unwrap();
        assert!(ls.weight.x > 0.0, "{ls:?}");
    }

    #[test]
    fn image_orientation_follows_pbrt() {
        // pbrt's LookAt camera has +x (image right) = up x forward: world +x
        // here, so the quad at +x is on the right of pbrt's picture.
        let c = two_quads("");
        assert!(c.mirrored);
        assert_eq!(seen(&c, 27.0, 10.0).as_deref(), Some("red"));
        assert_eq!(seen(&c, 13.0, 10.0).as_deref(), Some("green"));
        // The exporters' `Scale -1 1 1` turns image right to world -x.
        let c = two_quads("Scale -1 1 1\n");
        assert!(!c.mirrored);
        assert_eq!(seen(&c, 27.0, 10.0).as_deref(), Some("green"));
        assert_eq!(seen(&c, 13.0, 10.0).as_deref(), Some("red"));
        // Up is up: a quad above the axis is in the upper half.
        let c = ok(&format!(
            "Scale -1 1 1\nLookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \
             \"integer xresolution\" [ 20 ] \"integer yresolution\" [ 20 ]\nWorldBegin\nTranslate -0.5 1 0\n{}",
            quad(0.0)
        ));
        assert!(seen(&c, 10.0, 8.0).is_some() && seen(&c, 10.0, 12.0).is_none());
    }

    #[test]
    fn a_realistic_camera_sees_pbrts_picture_and_names_bad_lens_files_at_their_line() {
        let dir = tempfile::tempdir().unwrap();
        // A biconvex singlet, f 50.85 mm, with its stop behind it.
        let lens = dir.path().join("singlet.dat");
        std::fs::write(
            &lens,
            "# radius thickness eta aperture\n50 5 1.5 40\n-50 2 1 40\n0 40 0 8\n",
        )
        .unwrap();
        let bad = dir.path().join("bad.dat");
        std::fs::write(&bad, "50 5 1.5 40\n-50 2 1 40\n0 40 zero 8\n").unwrap();
        let scene =
            |pre: &str, camera: &str| convert_text(&two_quads_text(pre, camera), false).map_err(|e| e.to_string());
        let realistic = format!(
            "Camera \"realistic\" \"string lensfile\" \"{}\" \"float aperturediameter\" 4 \"float focusdistance\" 5",
            lens.display()
        );
        for (pre, right, left) in [("", "red", "green"), ("Scale -1 1 1\n", "green", "red")] {
            let c = scene(pre, &realistic).unwrap();
            let l = c.desc.camera.realistic.as_ref().expect("a lens system");
            assert!((l.focal_length - 0.05085).abs() < 5e-5, "{}", l.focal_length);
            assert_eq!(seen(&c, 27.0, 10.0).as_deref(), Some(right), "{pre}");
            assert_eq!(seen(&c, 13.0, 10.0).as_deref(), Some(left), "{pre}");
            // Rays through the lens carry its weight; the middle one leaves
            // the front of the lens, about 5 cm before the film, straight on.
            let cam = Scene::build(c.desc.clone()).unwrap().camera;
            let (ray, w) = cam.sample_ray(20.0, 10.0, glam::Vec2::splat(0.5));
            assert!(w > 0.0 && w < 0.1, "{w}");
            assert!(
                (ray.d - Vec3::Z).length() < 0.01 && (ray.o.z + 5.0 - 0.047).abs() < 0.01,
                "{ray:?}"
            );
        }
        // A bigger stop than the lens has: the lens' own, with a warning.
        let c = scene("", &realistic.replace("aperturediameter\" 4", "aperturediameter\" 40")).unwrap();
        assert!(
            c.warnings
                .iter()
                .any(|w| w.contains("larger than the lens' stop (8 mm)")),
            "{:?}",
            c.warnings
        );
        let e = scene("", &realistic.replace("singlet.dat", "nope.dat")).unwrap_err();
        assert!(
            e.contains("main.pbrt:2") && e.contains("lens file \"") && e.contains("nope.dat\" not found"),
            "{e}"
        );
        let e = scene("", &realistic.replace("singlet.dat", "bad.dat")).unwrap_err();
        assert!(
            e.contains("main.pbrt:2") && e.contains("bad.dat:3: \"zero\" is not a number"),
            "{e}"
        );
        let e = scene("", "Camera \"realistic\"").unwrap_err();
        assert!(e.contains("main.pbrt:2") && e.contains("no \"lensfile\""), "{e}");
        let e = scene("", &realistic.replace("focusdistance\" 5", "focusdistance\" 0.05")).unwrap_err();
        assert!(e.contains("main.pbrt:2") && e.contains("too close"), "{e}");
        let e = scene("", &format!("{realistic} \"string aperture\" \"hexagon\"")).unwrap_err();
        assert!(e.contains("main.pbrt:2") && e.contains("aperture \"hexagon\""), "{e}");
        assert!(scene("", &format!("{realistic} \"string aperture\" \"pentagon\"")).is_ok());
        // Aperture images stand upright on the stop (the picture's top at
        // the stop's +y, as pbrt-v4 reads them) and pass what the round stop
        // passes, grey 8-bit ones too (pbrt-v4 clamps those in their 8 bits).
        let top_half = |x: u32, y: u32| y < 8 && (x as i32 - 8).pow(2) + (y as i32 - 8).pow(2) < 64;
        let grey = dir.path().join("grey.png");
        ::image::GrayImage::from_fn(16, 16, |x, y| ::image::Luma([if top_half(x, y) { 255 } else { 0 }]))
            .save(&grey)
            .unwrap();
        let rgb = dir.path().join("rgb.png");
        ::image::RgbImage::from_fn(16, 16, |x, y| {
            ::image::Rgb(if top_half(x, y) { [255; 3] } else { [0; 3] })
        })
        .save(&rgb)
        .unwrap();
        for file in [&grey, &rgb] {
            let c = scene("", &format!("{realistic} \"string aperture\" \"{}\"", file.display())).unwrap();
            let lens = c.desc.camera.realistic.as_ref().unwrap();
            let a = lens.aperture().expect("a shaped stop");
            let mean = a.values.iter().map(|&v| v as f64).sum::<f64>() / a.values.len() as f64;
            assert!((mean - std::f64::consts::FRAC_PI_4).abs() < 1e-5, "{mean}");
            assert!(a.at(0.5, 0.75) > 1.0 && a.at(0.5, 0.25) == 0.0, "{file:?}");
        }
        let e = scene("", &format!("{realistic} \"string aperture\" \"none.png\"")).unwrap_err();
        assert!(e.contains("main.pbrt:2") && e.contains("aperture \"none.png\""), "{e}");
    }

    #[test]
    fn fov_spans_the_shorter_axis() {
        let cam = |w: u32, h: u32| {
            ok(&format!(
                "Camera \"perspective\" \"float fov\" [ 60 ]\nFilm \"rgb\" \"integer xresolution\" [ {w} ] \
                 \"integer yresolution\" [ {h} ]\nWorldBegin\n"
            ))
            .desc
            .camera
        };
        assert!((cam(200, 100).fov_y_deg - 60.0).abs() < 1e-4);
        let tall = cam(100, 200).fov_y_deg;
        let expected = 2.0 * (2.0 * 30f32.to_radians().tan()).atan().to_degrees();
        assert!((tall - expected).abs() < 1e-3, "{tall} vs {expected}");
        let c = cam(100, 200);
        assert_eq!((c.width, c.height), (100, 200));
    }

    #[test]
    fn screen_window_and_thin_lens_give_pbrts_rays() {
        // `Scale -1 1 1` first: pbrt's camera x is world -x, no reflection,
        // so world coordinates are pbrt's.
        let c = ok(
            "Scale -1 1 1\nLookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [ 40 ] \
             \"float screenwindow\" [ -0.5 1.5 -1 0.25 ] \"float lensradius\" 0.3 \"float focaldistance\" 4\n\
             Film \"rgb\" \"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ]\nWorldBegin\n",
        );
        assert!(!c.mirrored);
        let lens = c.desc.camera.lens.unwrap();
        assert_eq!((lens.radius, lens.focal_distance), (0.3, 4.0));
        let cam = Scene::build(c.desc.clone()).unwrap().camera;
        let t = 20f32.to_radians().tan();
        let eye = Vec3::new(0.0, 0.0, -5.0);
        for (x, y, u) in [
            (0.0, 0.0, (0.5, 0.5)),
            (13.5, 7.25, (0.1, 0.8)),
            (39.0, 19.5, (0.9, 0.35)),
        ] {
            // pbrt-v4's PerspectiveCamera::GenerateRay, in its camera space,
            // then to the world (camera x is world -x here).
            let sx = -0.5 + x / 40.0 * 2.0;
            let sy = 0.25 - y / 20.0 * 1.25;
            let d = Vec3::new(sx * t, sy * t, 1.0);
            let focus = d * 4.0;
            let p = crate::sampling::concentric_disk(glam::Vec2::new(u.0, u.1)) * 0.3;
            let o = Vec3::new(p.x, p.y, 0.0);
            let to_world = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
            let (o, d) = (eye + to_world(o), to_world((focus - o).normalize()));
            let r = cam.generate_ray_through_lens(x, y, glam::Vec2::new(u.0, u.1));
            assert!(
                (r.o - o).length() < 1e-5 && (r.d - d).length() < 1e-5,
                "({x}, {y}): {r:?} vs {o} {d}"
            );
        }
        // An explicit window keeps its shape when the image is resized, as in pbrt.
        let mut desc = c.desc.camera.clone();
        desc.resize(80, 20, crate::scene::FovAxis::Shorter);
        assert_eq!(
            (desc.fov_y_deg, desc.window),
            (c.desc.camera.fov_y_deg, c.desc.camera.window)
        );
        // frameaspectratio: a square window on a 2:1 film stretches it.
        let c = ok(
            "Camera \"perspective\" \"float fov\" [ 40 ] \"float frameaspectratio\" 1\n\
             Film \"rgb\" \"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ]\nWorldBegin\n",
        );
        let w = c.desc.camera.window.unwrap();
        assert_eq!([w.left, w.right, w.bottom, w.top], [-1.0, 1.0, -1.0, 1.0]);
        // The film's own window is no window of ours (the images stay as they were).
        let c = ok("Camera \"perspective\" \"float screenwindow\" [ -2 2 -1 1 ]\n\
             Film \"rgb\" \"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ]\nWorldBegin\n");
        assert_eq!((c.desc.camera.window, c.desc.camera.lens), (None, None));
        for (params, message) in [
            (
                "\"float screenwindow\" [ 1 1 -1 1 ]",
                "dir/main.pbrt:1: Camera: the screen window [1.0, 1.0, -1.0, 1.0] is empty or not finite",
            ),
            (
                "\"float lensradius\" 0.1 \"float focaldistance\" -2",
                "dir/main.pbrt:1: Camera: lens radius 0.1 and focal distance -2 must be finite and positive",
            ),
        ] {
            let e = convert_text(&format!("Camera \"perspective\" {params}\nWorldBegin\n"), false).unwrap_err();
            assert_eq!(e.to_string(), message);
        }
    }

    #[test]
    fn an_orthographic_camera_gives_pbrts_rays() {
        let text = |film: &str, extra: &str| {
            format!(
                "Scale -1 1 1\nLookAt 0 0 -5  0 0 0  0 1 0\nCamera \"orthographic\" {extra}\n\
                 Film \"rgb\" {film}\nWorldBegin\n"
            )
        };
        let wide = "\"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ]";
        let c = ok(&text(wide, ""));
        assert!(!c.mirrored);
        let cam = Scene::build(c.desc.clone()).unwrap().camera;
        // pbrt-v4: the default window [-2, 2] x [-1, 1] of camera space; the
        // ray from the window's point along camera +z (camera x is world -x).
        for (x, y) in [(0.0, 0.0), (13.5, 7.25), (40.0, 20.0)] {
            let (sx, sy) = (-2.0 + x / 40.0 * 4.0, 1.0 - y / 20.0 * 2.0);
            let r = cam.generate_ray(x, y);
            assert!(
                (r.o - Vec3::new(-sx, sy, -5.0)).length() < 1e-5,
                "({x}, {y}): {:?}",
                r.o
            );
            assert!((r.d - Vec3::Z).length() < 1e-6);
        }
        // Portrait: [-1, 1] across; a resize keeps the shorter axis' extent.
        let tall = "\"integer xresolution\" [ 20 ] \"integer yresolution\" [ 40 ]";
        let c = ok(&text(tall, ""));
        assert_eq!(c.desc.camera.orthographic, Some(2.0));
        let mut d = c.desc.camera.clone();
        d.resize(60, 20, crate::scene::FovAxis::Shorter);
        assert_eq!(d.orthographic, Some(1.0));
        // A screen window of its own: in units of camera space.
        let c = ok(&text(wide, "\"float screenwindow\" [ 0 4 -1 1 ]"));
        let cam = Scene::build(c.desc.clone()).unwrap().camera;
        assert!((cam.generate_ray(10.0, 10.0).o - Vec3::new(-1.0, 0.0, -5.0)).length() < 1e-5);
        // pbrt-v4's orthographic lens is not copied: refused, as a feature.
        let e = convert_text(&text(wide, "\"float lensradius\" 0.1"), false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("Camera \"orthographic\": a lens"), "{e}");
        let lenient = convert_text(&text(wide, "\"float lensradius\" 0.1"), true).unwrap();
        assert_eq!(lenient.desc.camera.lens, None);
    }

    #[test]
    fn a_spherical_camera_is_read_with_its_mapping() {
        let text = |cam: &str| {
            format!(
                "LookAt 0 0 0  0 0 1  0 1 0\n{cam}\n\
                 Film \"rgb\" \"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ]\nWorldBegin\n"
            )
        };
        let c = ok(&text(
            "Camera \"spherical\" \"string mapping\" \"equirectangular\" \"float lensradius\" 0.5",
        ));
        assert_eq!(
            c.desc.camera.spherical,
            Some(crate::camera::SphericalMapping::Equirectangular)
        );
        // pbrt-v4 reads a lens and ignores it; no field of view is read.
        assert_eq!(c.desc.camera.lens, None);
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        let cam = Scene::build(c.desc.clone()).unwrap().camera;
        // The column a quarter across the middle row looks along the view.
        assert!((cam.generate_ray(10.0, 10.0).d - Vec3::Z).length() < 1e-5);
        let c = ok(&text("Camera \"spherical\""));
        assert_eq!(
            c.desc.camera.spherical,
            Some(crate::camera::SphericalMapping::EqualArea)
        );
        let fov = ok(&text("Camera \"spherical\" \"float fov\" 30"));
        assert!(
            fov.warnings.iter().any(|w| w.contains("\"float fov\" is not used")),
            "{:?}",
            fov.warnings
        );
        let e = convert_text(&text("Camera \"spherical\" \"string mapping\" \"cube\""), false)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("dir/main.pbrt:2:"), "{e}");
        assert!(e.contains("unknown mapping \"cube\""), "{e}");
        assert!(!e.contains('\n'));
    }

    #[test]
    fn crop_window_and_pixel_bounds_pick_pbrts_pixels() {
        let film = |params: &str| {
            convert_text(
                &format!(
                    "Film \"rgb\" \"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ] {params}\nWorldBegin\n"
                ),
                false,
            )
        };
        let rect = |c: &Converted, w, h| c.crop.unwrap().rect(w, h).map(|r| [r.x0, r.x1, r.y0, r.y1]);
        // Fractions rounded up, ends sorted and clamped, as pbrt-v4's film.
        let c = film("\"float cropwindow\" [ 0.75 0.21 0 0.5 ]").unwrap();
        assert_eq!(rect(&c, 40, 20), Some([9, 30, 0, 10]));
        assert_eq!(rect(&c, 80, 40), Some([17, 60, 0, 20]));
        let c = film("\"float cropwindow\" [ -1 0.5 0.5 7 ]").unwrap();
        assert_eq!(rect(&c, 40, 20), Some([0, 20, 10, 20]));
        // Pixel bounds: clamped to the image with a warning; scaled with it.
        let c = film("\"integer pixelbounds\" [ 5 15 2 30 ]").unwrap();
        assert_eq!(rect(&c, 40, 20), Some([5, 15, 2, 20]));
        assert_eq!(rect(&c, 80, 40), Some([10, 30, 4, 40]));
        assert_eq!(rect(&c, 20, 10), Some([3, 8, 1, 10]));
        assert!(c.warnings.iter().any(|w| w.contains("clamped")), "{:?}", c.warnings);
        // Both: the crop window, with a warning.
        let c = film("\"integer pixelbounds\" [ 5 15 2 30 ] \"float cropwindow\" [ 0 0.5 0 1 ]").unwrap();
        assert_eq!(rect(&c, 40, 20), Some([0, 20, 0, 20]));
        assert!(c.warnings.iter().any(|w| w.contains("the crop window is used")));
        assert!(film("").unwrap().crop.is_none());
        for (params, message) in [
            (
                "\"float cropwindow\" [ 0.5 0.5 0 1 ]",
                "dir/main.pbrt:1: Film: \"cropwindow\" leaves no pixel of the 40x20 image",
            ),
            (
                "\"float cropwindow\" [ 0 1 0 ]",
                "dir/main.pbrt:1: Film: \"cropwindow\" needs four finite numbers, not [0.0, 1.0, 0.0]",
            ),
            (
                "\"integer pixelbounds\" [ 50 60 0 10 ]",
                "dir/main.pbrt:1: Film: \"pixelbounds\" leaves no pixel of the 40x20 image",
            ),
            (
                "\"integer pixelbounds\" [ 1 2 ]",
                "dir/main.pbrt:1: Film: \"pixelbounds\" needs four integers, not 2",
            ),
        ] {
            assert_eq!(film(params).unwrap_err().to_string(), message);
        }
    }

    fn light_normal(text: &str) -> Vec3 {
        let c = ok(&format!(
            "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ]\n{text}AttributeEnd\n"
        ));
        assert!(c.desc.triangles.is_empty(), "an emitter is the light only");
        assert_eq!(c.desc.lights.len(), 2);
        let Light::Triangle { vertices: v, .. } = c.desc.lights[0] else {
            panic!("not a triangle light")
        };
        let n = crate::light::triangle_normal(&v);
        // Undo the reflection the identity camera implies.
        if c.mirrored {
            Vec3::new(-n.x, n.y, n.z)
        } else {
            n
        }
    }

    #[test]
    fn area_lights_emit_on_pbrts_side() {
        let z = Vec3::Z;
        assert!(light_normal(&quad(0.0)).abs_diff_eq(z, 1e-6));
        assert!(light_normal(&format!("ReverseOrientation\n{}", quad(0.0))).abs_diff_eq(-z, 1e-6));
        // A transformation that swaps handedness turns the triangle's cross
        // product, and pbrt turns it back: the normal as transformed.
        let flip_z = "Scale 1 1 -1\n";
        assert!(light_normal(&format!("{flip_z}{}", quad(0.0))).abs_diff_eq(-z, 1e-6));
        assert!(light_normal(&format!("Scale 1 -1 1\n{}", quad(0.0))).abs_diff_eq(z, 1e-6));
        assert!(light_normal(&format!("ReverseOrientation\n{flip_z}{}", quad(0.0))).abs_diff_eq(z, 1e-6));
        // Normals N decide where given (ReverseOrientation turns them).
        let with_n = quad(0.0).replace("\"integer", "\"normal N\" [ 0 0 -1 0 0 -1 0 0 -1 0 0 -1 ] \"integer");
        assert!(light_normal(&with_n).abs_diff_eq(-z, 1e-6));
        assert!(light_normal(&format!("{flip_z}{with_n}")).abs_diff_eq(z, 1e-6));
        assert!(light_normal(&format!("ReverseOrientation\n{with_n}")).abs_diff_eq(z, 1e-6));
    }

    #[test]
    fn light_power_and_scale() {
        let c = ok(&format!(
            "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 1 2 3 ] \"float scale\" [ 2 ] \
             \"bool twosided\" true\n{}AttributeEnd\n\
             AttributeBegin\nAreaLightSource \"diffuse\" \"float power\" [ 10 ]\n\
             Translate 0 0 1\nShape \"sphere\" \"float radius\" [ 0.5 ]\nAttributeEnd\n\
             LightSource \"point\" \"rgb I\" [ 1 1 1 ] \"point3 from\" [ 0 3 0 ]\n",
            quad(0.0)
        ));
        let Light::Triangle {
            radiance, two_sided, ..
        } = c.desc.lights[1]
        else {
            panic!()
        };
        assert_eq!((radiance, two_sided), (Vec3::new(2.0, 4.0, 6.0), true));
        let Light::Sphere { sphere, power, .. } = c.desc.lights[3] else {
            panic!("{:?}", c.desc.lights)
        };
        assert!((sphere.radius - 0.5).abs() < 1e-6);
        assert!(power.abs_diff_eq(Vec3::splat(10.0), 1e-4), "{power}");
        let Light::Point { power, position } = c.desc.lights[0] else {
            panic!()
        };
        assert!(power.abs_diff_eq(Vec3::splat(4.0 * PI), 1e-4) && position.y == 3.0);
    }

    #[test]
    fn spot_distant_and_infinite_lights_follow_the_transform() {
        let c = ok("WorldBegin\nAttributeBegin\nTranslate 1 2 3\n\
             LightSource \"spot\" \"rgb I\" [ 1 2 3 ] \"float scale\" [ 2 ] \"point3 from\" [ 1 0 0 ] \
             \"point3 to\" [ 1 0 5 ] \"float coneangle\" [ 40 ] \"float conedelta\" [ 10 ]\n\
             Rotate 90 0 0 1\n\
             LightSource \"distant\" \"rgb L\" [ 1 1 1 ] \"point3 from\" [ 0 0 0 ] \"point3 to\" [ 1 0 0 ] \
             \"float scale\" [ 3 ]\n\
             LightSource \"infinite\" \"rgb L\" [ 0.5 0.5 0.5 ]\n\
             AttributeEnd\n\
             LightSource \"spot\" \"float power\" [ 10 ] \"float coneangle\" [ 30 ] \"float conedelta\" [ 30 ]\n\
             LightSource \"infinite\" \"float illuminance\" [ 2 ]\n");
        // The identity camera: the scene is reflected across x = 0.
        assert!(c.mirrored);
        let m = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
        let Light::Spot {
            position,
            direction,
            intensity,
            cos_falloff_start,
            cos_falloff_end,
        } = c.desc.lights[0]
        else {
            panic!("{:?}", c.desc.lights)
        };
        assert!(position.abs_diff_eq(m(Vec3::new(2.0, 2.0, 3.0)), 1e-5), "{position}");
        assert!(direction.abs_diff_eq(Vec3::Z, 1e-6), "{direction}");
        assert_eq!(intensity, Vec3::new(2.0, 4.0, 6.0));
        assert!((cos_falloff_start - 30f32.to_radians().cos()).abs() < 1e-6);
        assert!((cos_falloff_end - 40f32.to_radians().cos()).abs() < 1e-6);
        // Travelling along +x turned 90 degrees about z: +y.
        let Light::Distant {
            direction, radiance, ..
        } = c.desc.lights[1]
        else {
            panic!()
        };
        assert!(direction.abs_diff_eq(m(Vec3::Y), 1e-6), "{direction}");
        assert_eq!(radiance, Vec3::splat(3.0));
        let Light::Infinite {
            radiance,
            to_world,
            map,
            ..
        } = &c.desc.lights[2]
        else {
            panic!()
        };
        assert!(map.is_none() && *radiance == Vec3::splat(0.5));
        // The light's x axis is the world's y (then mirrored).
        assert!((*to_world * Vec3::X).abs_diff_eq(m(Vec3::Y), 1e-6));
        // power: pbrt-v4's k_e for a cone all falloff is 2 pi (1 - cos) / 2.
        let Light::Spot { intensity, .. } = c.desc.lights[3] else {
            panic!()
        };
        let k_e = PI * (1.0 - 30f32.to_radians().cos());
        assert!(intensity.abs_diff_eq(Vec3::splat(10.0 / k_e), 1e-3), "{intensity}");
        let Light::Infinite { radiance, .. } = c.desc.lights[4] else {
            panic!()
        };
        assert!(radiance.abs_diff_eq(Vec3::splat(2.0 / PI), 1e-6));
    }

    #[test]
    fn disks_follow_the_transform() {
        let c = ok(
            "WorldBegin\nAttributeBegin\nTranslate 1 0 4\nRotate 90 0 1 0\nScale 2 2 2\n\
             Shape \"disk\" \"float height\" [ 0.5 ] \"float radius\" [ 1 ] \"float innerradius\" [ 0.25 ]\n\
             AttributeEnd\n",
        );
        assert!(c.mirrored);
        let m = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
        let d = &c.desc.disks[0];
        // Rotate 90 about y takes z to x: centre (1, 0, 4) + 2 * 0.5 x.
        assert!(
            d.centre.abs_diff_eq(m(Vec3::new(2.0, 0.0, 4.0)), 1e-5),
            "{:?}",
            d.centre
        );
        assert!(d.normal.abs_diff_eq(m(Vec3::X), 1e-5), "{:?}", d.normal);
        assert!((d.radius - 2.0).abs() < 1e-5 && (d.inner_radius - 0.5).abs() < 1e-5);
        let [a, b] = d.axes.unwrap();
        assert!(
            a.abs_diff_eq(m(-Vec3::Z), 1e-5) && b.abs_diff_eq(Vec3::Y, 1e-5),
            "{a} {b}"
        );
        // A ray from the camera (origin, looking along +z) through the ring hits it.
        let scene = Scene::build(c.desc.clone()).unwrap();
        let ray = crate::math::Ray::new(Vec3::ZERO, Vec3::new(-2.0, 0.0, 5.0).normalize());
        let hit = scene.intersect(&ray, 1e-4, f32::INFINITY).expect("the ring");
        assert!((hit.t - Vec3::new(-2.0, 0.0, 5.0).length()).abs() < 1e-3, "{}", hit.t);
        assert_eq!(c.desc.disks.len(), 1);
    }

    /// The one disk light of `text` (after WorldBegin and an area light with
    /// `light`), with its normal and axes mirrored back to pbrt's world.
    fn disk_light(light: &str, text: &str) -> (crate::geometry::Disk, Vec3, bool) {
        let c = ok(&format!(
            "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" {light}\n{text}AttributeEnd\n"
        ));
        assert!(c.desc.disks.is_empty(), "an emitter is the light only");
        assert_eq!(c.desc.lights.len(), 1);
        let Light::Disk {
            mut disk,
            radiance,
            two_sided,
            ..
        } = c.desc.lights[0]
        else {
            panic!("not a disk light: {:?}", c.desc.lights[0])
        };
        if c.mirrored {
            let m = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
            disk.centre = m(disk.centre);
            disk.normal = m(disk.normal);
            disk.axes = disk.axes.map(m);
        }
        (disk, radiance, two_sided)
    }

    #[test]
    fn disk_area_lights_follow_pbrt() {
        let shape = "Shape \"disk\" \"float radius\" [ 2 ] \"float innerradius\" [ 1 ] \"float height\" [ 0.5 ]\n";
        let (d, l, two) = disk_light("\"rgb L\" [ 1 2 3 ]", &format!("Translate 0 1 0\nScale 2 2 2\n{shape}"));
        assert!(d.centre.abs_diff_eq(Vec3::new(0.0, 1.0, 1.0), 1e-6), "{}", d.centre);
        assert!((d.radius - 4.0).abs() < 1e-6 && (d.inner_radius - 2.0).abs() < 1e-6);
        assert!(d.normal.abs_diff_eq(Vec3::Z, 1e-6) && !two);
        assert_eq!(l, Vec3::new(1.0, 2.0, 3.0));
        // The emitting side: pbrt's intersection normal, turned by
        // ReverseOrientation and by a transformation that swaps handedness.
        let side = |pre: &str| disk_light("", &format!("{pre}{shape}")).0.normal;
        assert!(side("ReverseOrientation\n").abs_diff_eq(-Vec3::Z, 1e-6));
        assert!(side("Scale 1 1 -1\n").abs_diff_eq(Vec3::Z, 1e-6));
        assert!(side("Scale 1 -1 1\n").abs_diff_eq(-Vec3::Z, 1e-6));
        assert!(side("ReverseOrientation\nScale 1 -1 1\n").abs_diff_eq(Vec3::Z, 1e-6));
        assert!(side("Rotate 90 1 0 0\n").abs_diff_eq(-Vec3::Y, 1e-6));
        // power is met by the annulus (area pi (2^2 - 1^2) = 3 pi), per side;
        // pbrt-v4 multiplies `scale` by power / (sides area pi), keeping it.
        for (two_sided, sides) in [("false", 1.0), ("true", 2.0)] {
            let (_, l, two) = disk_light(
                &format!(
                    "\"rgb L\" [ 1 1 1 ] \"float scale\" [ 3 ] \"float power\" [ 60 ] \"bool twosided\" {two_sided}"
                ),
                shape,
            );
            let expected = 3.0 * 60.0 / (sides * 3.0 * PI * PI);
            assert!(l.abs_diff_eq(Vec3::splat(expected), 1e-4), "{l} vs {expected}");
            assert_eq!(two, sides == 2.0);
        }
        // scale without power multiplies L.
        let (_, l, _) = disk_light("\"rgb L\" [ 1 1 1 ] \"float scale\" [ 3 ]", shape);
        assert!(l.abs_diff_eq(Vec3::splat(3.0), 1e-6), "{l}");
    }

    #[test]
    fn procedural_textures_and_mappings_are_read_in_their_own_space() {
        // fBm in a texture space moved 10 along x, the amount of a mix of
        // black and white on a quad: the quad's colour at a point is the fBm
        // at the point moved back (the transformation's inverse), for the
        // octaves and roughness given. This camera's picture is pbrt's
        // mirror image, so the scene is reflected across x = 0: the point
        // in pbrt's world is the hit's with x negated.
        let head = "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [ 40 ]\nWorldBegin\n";
        let quad = "Shape \"trianglemesh\" \"point3 P\" [ -1 -0.5 0  1 -0.5 0  1 0.5 0  -1 0.5 0 ] \
                    \"point2 uv\" [ 0 0  1 0  1 1  0 1 ] \"integer indices\" [ 0 1 2 0 2 3 ]\n";
        let scene_with = |textures: &str| {
            format!(
                "{head}AttributeBegin\nTranslate 10 0 0\n{textures}\nAttributeEnd\n\
                 Texture \"m\" \"spectrum\" \"mix\" \"texture amount\" \"n\" \"rgb tex1\" [ 0 0 0 ] \"rgb tex2\" [ 1 1 1 ]\n\
                 Material \"diffuse\" \"texture reflectance\" \"m\"\n{quad}"
            )
        };
        let look = |c: &Converted, x: f32| {
            let scene = Scene::build(c.desc.clone()).unwrap();
            let ray = crate::math::Ray::new(Vec3::new(x, 0.1, -5.0), Vec3::Z);
            let hit = scene.intersect(&ray, 1e-4, f32::INFINITY).expect("the quad");
            let Material::Diffuse { reflectance } = &scene.materials[hit.material as usize] else {
                panic!()
            };
            (
                reflectance.evaluate(&crate::texture::TexCoord::at(hit.uv, hit.p, hit.ng)),
                hit,
            )
        };
        let c = ok(&scene_with(
            "Texture \"n\" \"float\" \"fbm\" \"integer octaves\" [ 4 ] \"float roughness\" [ 0.6 ]",
        ));
        assert!(c.mirrored);
        for x in [-0.7f32, 0.2, 0.65] {
            let (v, hit) = look(&c, x);
            let in_pbrt = hit.p * Vec3::new(-1.0, 1.0, 1.0);
            let want = crate::texture::noise::fbm(in_pbrt - Vec3::new(10.0, 0.0, 0.0), Vec3::ZERO, Vec3::ZERO, 0.6, 4);
            assert!((v - Vec3::splat(want)).abs().max_element() < 1e-6, "{x}: {v} vs {want}");
        }
        // Every class and mapping reads; what each holds is checked against
        // pbrt-v4's own values in `texture::procedural`.
        for (texture, holds) in [
            ("Texture \"n\" \"float\" \"wrinkled\"", "Noise"),
            ("Texture \"n\" \"float\" \"windy\"", "Noise"),
            (
                "Texture \"n\" \"float\" \"dots\" \"string mapping\" \"spherical\"",
                "Dots",
            ),
            ("Texture \"n\" \"float\" \"bilerp\" \"float v11\" [ 0.5 ]", "Bilerp"),
            (
                "Texture \"n\" \"float\" \"checkerboard\" \"integer dimension\" [ 3 ]",
                "Checkerboard3D",
            ),
            (
                "Texture \"n\" \"float\" \"checkerboard\" \"string mapping\" \"planar\" \"vector3 v1\" [ 0 0 1 ]",
                "Checkerboard",
            ),
            (
                "Texture \"n\" \"float\" \"directionmix\" \"vector3 dir\" [ 0 0 1 ]",
                "DirectionMix",
            ),
        ] {
            let c = ok(&scene_with(texture));
            let m = format!("{:?}", c.desc.materials[0].1);
            assert!(m.contains(&format!("amount: {holds}")), "{texture}: {m}");
        }
        // A parameter of the wrong type, or one the mapping does not take,
        // stays unread and is reported, as pbrt-v4 reports it.
        let c = ok(&scene_with(
            "Texture \"n\" \"float\" \"dots\" \"string mapping\" \"cylindrical\" \"float uscale\" [ 2 ]",
        ));
        assert!(
            c.warnings.iter().any(|w| w.contains("\"float uscale\" is not used")),
            "{:?}",
            c.warnings
        );
        let c = ok(&scene_with("Texture \"n\" \"float\" \"fbm\" \"float octaves\" [ 3 ]"));
        assert!(
            c.warnings.iter().any(|w| w.contains("\"float octaves\" is not used")),
            "{:?}",
            c.warnings
        );
        // marble is a colour.
        let marble = format!(
            "{head}Texture \"k\" \"spectrum\" \"marble\" \"float scale\" [ 2 ]\n\
             Material \"diffuse\" \"texture reflectance\" \"k\"\n{quad}"
        );
        let (v, _) = look(&ok(&marble), 0.3);
        assert!(v.x > 0.0 && v.z >= v.x, "{v}");
        // A direction mix looks along the surface's normal: the quad faces z.
        let c = ok(&scene_with(
            "Texture \"n\" \"float\" \"directionmix\" \"vector3 dir\" [ 0 0 1 ] \"float tex1\" [ 0.25 ] \"float tex2\" [ 0.75 ]",
        ));
        assert!((look(&c, 0.0).0 - Vec3::splat(0.25)).abs().max_element() < 1e-6);
        // What pbrt-v4 refuses, or cannot mean: one line naming the place.
        for (texture, want) in [
            (
                "Texture \"n\" \"float\" \"marble\"",
                "dir/main.pbrt:6: texture \"n\": \"marble\" is a spectrum texture only",
            ),
            (
                "Texture \"n\" \"float\" \"fbm\" \"integer octaves\" [ 40 ]",
                "dir/main.pbrt:6: texture \"n\": \"octaves\" 40 is not within 0..=32",
            ),
            (
                "Texture \"n\" \"float\" \"dots\" \"string mapping\" \"cubic\"",
                "dir/main.pbrt:6: texture \"n\": unknown mapping \"cubic\"",
            ),
            (
                "Texture \"n\" \"float\" \"checkerboard\" \"integer dimension\" [ 4 ]",
                "dir/main.pbrt:6: texture \"n\": a checkerboard of dimension 4",
            ),
            (
                "Scale 0 1 1\nTexture \"n\" \"float\" \"fbm\"",
                "dir/main.pbrt:7: texture \"n\": its transformation is singular",
            ),
        ] {
            let e = convert_text(&scene_with(texture), false).unwrap_err().to_string();
            assert!(e.starts_with(want), "{texture}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let e = convert_text(
            &scene_with("Texture \"n\" \"float\" \"fbm\"").replace("\"spectrum\" \"mix\"", "\"spectrum\" \"fbm\""),
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("\"fbm\" is a float texture only"), "{e}");
    }

    #[test]
    fn a_conductors_reflectance_may_be_a_texture() {
        let text = |material: &str| {
            format!(
                "WorldBegin\nTexture \"check\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [ 0.9 0.6 0.2 ] \"rgb tex2\" [ 2 2 2 ] \"float uscale\" [ 2 ]\n\
                 Material \"{material}\" \"texture reflectance\" \"check\"\n{}",
                quad(0.0)
            )
        };
        for material in ["conductor", "coatedconductor"] {
            let c = ok(&text(material));
            let fresnel = match &c.desc.materials[0].1 {
                Material::Conductor { fresnel, .. } => fresnel,
                Material::CoatedConductor { conductor, .. } => conductor,
                m => panic!("{m:?}"),
            };
            let ConductorFresnel::Reflectance(Texture::Checkerboard { .. }) = fresnel else {
                panic!("{fresnel:?}")
            };
        }
        // Looked up per point and kept within [0, 1], as pbrt-v4 keeps it: a
        // white metal's BSDF at normal incidence reflects all of a texel of 2.
        let c = ok(&text("conductor"));
        let m = &c.desc.materials[0].1;
        let sp = |u: f32| crate::material::SurfacePoint {
            p: Vec3::ZERO,
            uv: crate::math::Vec2::new(u, 0.5),
            ng: Vec3::Z,
            ns: Vec3::Z,
            dpdu: Vec3::X,
            shading: None,
            footprint: crate::texture::Footprint::NONE,
        };
        let w = Vec3::new(0.3, 0.0, 1.0).normalize();
        let mirror = Vec3::new(-w.x, -w.y, w.z);
        let f = |u: f32| {
            let bsdf = m.bsdf(&sp(u), w);
            bsdf.sample_f(
                w,
                0.5,
                crate::math::Vec2::new(0.5, 0.5),
                crate::bsdf::TransportMode::Radiance,
            )
            .map(|s| (s.f * s.wi.z.abs() / s.pdf, s.wi))
        };
        let (bright, wi) = f(0.75).expect("a reflection");
        assert!((wi - mirror).length() < 1e-4, "{wi}");
        assert!((bright - Vec3::ONE).abs().max_element() < 1e-3, "{bright}");
        let (copper, _) = f(0.25).expect("a reflection");
        assert!(
            (copper - Vec3::new(0.9, 0.6, 0.2)).abs().max_element() < 1e-3,
            "{copper}"
        );
    }

    #[test]
    fn checkerboard_quad_gives_two_reflectances() {
        let text = "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [ 40 ]\n\
             Film \"rgb\" \"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ]\nWorldBegin\n\
             Texture \"a\" \"spectrum\" \"constant\" \"rgb value\" [ 0.8 0.1 0.1 ]\n\
             Texture \"check\" \"spectrum\" \"checkerboard\" \"texture tex1\" \"a\" \"rgb tex2\" [ 0.1 0.1 0.8 ] \
             \"float uscale\" [ 2 ] \"float vscale\" [ 1 ]\n\
             Material \"diffuse\" \"texture reflectance\" \"check\"\n\
             Shape \"trianglemesh\" \"point3 P\" [ -1 -0.5 0  1 -0.5 0  1 0.5 0  -1 0.5 0 ] \
             \"point2 uv\" [ 0 0  1 0  1 1  0 1 ] \"integer indices\" [ 0 1 2 0 2 3 ]\n";
        let c = ok(text);
        assert!(c.desc.triangles.iter().all(|t| t.uvs.is_some()));
        let scene = Scene::build(c.desc.clone()).unwrap();
        let albedo = |x: f32| {
            let ray = crate::math::Ray::new(Vec3::new(x, 0.0, -5.0), Vec3::Z);
            let hit = scene.intersect(&ray, 1e-4, f32::INFINITY).expect("the quad");
            let Material::Diffuse { reflectance } = &scene.materials[hit.material as usize] else {
                panic!()
            };
            reflectance.evaluate(&crate::texture::TexCoord::at(hit.uv, hit.p, hit.ng))
        };
        let (a, b) = (albedo(-0.5), albedo(0.5));
        assert!(a != b, "{a} {b}");
        let red = Vec3::new(0.8, 0.1, 0.1);
        let blue = Vec3::new(0.1, 0.1, 0.8);
        // u < 0.5 (pbrt's x < 0, here x > 0 after the reflection) is tex1.
        assert!(a == blue && b == red, "{a} {b}");
        // An unknown texture, a missing image: one line naming the place.
        let e = convert_text(&text.replace("\"check\"\n", "\"nope\"\n"), false)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("dir/main.pbrt:7: spectrum texture \"nope\" is not defined"),
            "{e}"
        );
        assert!(!e.contains('\n'));
        let missing = text
            .replace(
                "Material",
                "Texture \"img\" \"spectrum\" \"imagemap\" \"string filename\" \"none.png\"\nMaterial",
            )
            .replace("\"check\"\n", "\"img\"\n");
        let e = convert_text(&missing, false).unwrap_err().to_string();
        assert!(
            e.starts_with("dir/main.pbrt:7: column 37: imagemap \"img\": image \"none.png\" not found"),
            "{e}"
        );
        assert!(!e.contains('\n'));
    }

    #[test]
    fn checkerboard_roughness_is_looked_up_per_point() {
        use crate::bsdf::{Bsdf, BxdfFlags, TransportMode};
        use crate::material::MaterialRoughness;
        let text = "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [ 40 ]\n\
             Film \"rgb\" \"integer xresolution\" [ 40 ] \"integer yresolution\" [ 20 ]\nWorldBegin\n\
             Texture \"check\" \"float\" \"checkerboard\" \"float tex1\" [ 0.3 ] \"float tex2\" [ 0.01 ] \
             \"float uscale\" [ 2 ] \"float vscale\" [ 1 ]\n\
             Material \"conductor\" \"texture roughness\" \"check\" \"rgb reflectance\" [ 1 1 1 ]\n\
             Shape \"trianglemesh\" \"point3 P\" [ -1 -0.5 0  1 -0.5 0  1 0.5 0  -1 0.5 0 ] \
             \"point2 uv\" [ 0 0  1 0  1 1  0 1 ] \"integer indices\" [ 0 1 2 0 2 3 ]\n";
        let wo = -Vec3::Z;
        // 70 degrees off the mirror direction: half vectors 35 degrees off
        // the normal, where alpha 0.55 reflects ten times what alpha 0.1 does.
        let off = Vec3::new(70f32.to_radians().sin(), 0.0, -70f32.to_radians().cos());
        // The material and the BSDFs where rays along +z from x = 0.5 (u <
        // 0.5 after the reflection: tex1, the even square) and x = -0.5
        // (tex2) meet the quad.
        let squares = |text: &str| -> (Material, Bsdf, Bsdf) {
            let scene = Scene::build(ok(text).desc).unwrap();
            let at = |x: f32| {
                let ray = crate::math::Ray::new(Vec3::new(x, 0.0, -5.0), Vec3::Z);
                let hit = scene.intersect(&ray, 1e-4, f32::INFINITY).expect("the quad");
                let m = &scene.materials[hit.material as usize];
                (m.clone(), m.bsdf(&hit.surface(), wo))
            };
            let ((m, even), (_, odd)) = (at(0.5), at(-0.5));
            (m, even, odd)
        };
        let (m, even, odd) = squares(text);
        let Material::Conductor {
            roughness: MaterialRoughness::Textured { u, v, remap: true },
            ..
        } = &m
        else {
            panic!("{m:?}")
        };
        assert!(Arc::ptr_eq(u, v), "one texture for both directions");
        assert!(!m.is_specular());
        let f = |b: &Bsdf| b.f(wo, off, TransportMode::Radiance).x;
        assert!(f(&even) > 5.0 * f(&odd) && f(&odd) > 0.0, "{} {}", f(&even), f(&odd));

        // Where the texture is 0 each of the three materials is specular,
        // where it is 0.3 glossy.
        let smooth_odd = text.replace("[ 0.01 ]", "[ 0 ]");
        for ty in ["conductor", "dielectric", "coateddiffuse"] {
            let t = smooth_odd.replace("\"conductor\"", &format!("\"{ty}\""));
            let t = if ty == "conductor" {
                t
            } else {
                t.replace(" \"rgb reflectance\" [ 1 1 1 ]", "")
            };
            let (m, even, odd) = squares(&t);
            assert!(!m.is_specular(), "{ty}");
            let (e, o) = (even.flags(), odd.flags());
            assert!(e.is_glossy() && !e.is_specular(), "{ty}: {e:?}");
            assert!(o.is_specular() && !o.is_glossy(), "{ty}: {o:?}");
            if ty == "conductor" {
                assert_eq!(o, BxdfFlags::SPECULAR_REFLECTION);
            }
        }

        // A texture for u only; v the number it is given.
        let (m, ..) = squares(&text.replace(
            "\"texture roughness\"",
            "\"float vroughness\" [ 0.2 ] \"texture uroughness\"",
        ));
        let Material::Conductor {
            roughness: MaterialRoughness::Textured { u, v, .. },
            ..
        } = &m
        else {
            panic!("{m:?}")
        };
        assert!(matches!(**u, Texture::Checkerboard { .. }), "{u:?}");
        assert_eq!(**v, Texture::from(Vec3::splat(0.2)));

        // A constant texture is the number it holds.
        let constant = text.replace(
            "Material",
            "Texture \"k\" \"float\" \"constant\" \"float value\" [ 0.2 ]\nMaterial",
        );
        let (m, ..) = squares(&constant.replace("\"check\" \"rgb", "\"k\" \"rgb"));
        let (n, ..) = squares(&text.replace("\"texture roughness\" \"check\"", "\"float roughness\" [ 0.2 ]"));
        assert_eq!(m, n);
        assert!(matches!(
            m,
            Material::Conductor {
                roughness: MaterialRoughness::Constant(_),
                ..
            }
        ));

        // An unknown name, a spectrum texture: one line naming the place.
        for (t, want) in [
            (
                text.replace("\"check\" \"rgb", "\"nope\" \"rgb"),
                "dir/main.pbrt:6: float texture \"nope\" is not defined",
            ),
            (
                text.replace("\"float\" \"checkerboard\"", "\"spectrum\" \"checkerboard\""),
                "dir/main.pbrt:6: \"roughness\": texture \"check\" is a spectrum texture, not a float texture",
            ),
        ] {
            let e = convert_text(&t, false).unwrap_err().to_string();
            assert!(e.starts_with(want), "{e}");
            assert!(!e.contains('\n'), "{e}");
        }
        // A texture class we lack is an unsupported material.
        let e = convert_text(&text.replace("\"checkerboard\"", "\"ptex\""), false)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("dir/main.pbrt:6: material (texture \"check\" of class \"ptex\""),
            "{e}"
        );
    }

    #[test]
    fn a_textured_dielectric_eta_is_refused_as_pbrt_v4_does() {
        let e = convert_text(
            &format!(
                "WorldBegin\nTexture \"e\" \"float\" \"constant\" \"float value\" [ 1.5 ]\n\
                 Material \"dielectric\" \"texture eta\" \"e\"\n{}",
                quad(0.0)
            ),
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("dir/main.pbrt:3: material (a textured \"eta\" is not supported"),
            "{e}"
        );
    }

    #[test]
    fn infinite_light_image() {
        let dir = std::env::temp_dir().join(format!("pbrt-env-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut film = crate::film::Film::new(4, 4);
        film.pixels.fill(Vec3::new(1.0, 2.0, 3.0));
        crate::image_io::write_image(&film, &dir.join("sky.pfm"), 0.0).unwrap();
        let path = dir.join("main.pbrt");
        let text = "WorldBegin\nLightSource \"infinite\" \"string filename\" \"sky.pfm\" \"float scale\" [ 2 ]\n";
        let scene = super::super::parse_bytes(&path, text.as_bytes().to_vec(), &crate::scene::mesh::Disk).unwrap();
        let c = convert(&scene, &path, false).unwrap();
        let Light::Infinite { radiance, map, .. } = &c.desc.lights[0] else {
            panic!()
        };
        assert!(map.is_some() && *radiance == Vec3::splat(2.0));
        let missing = text.replace("sky.pfm", "none.exr");
        let scene = super::super::parse_bytes(&path, missing.as_bytes().to_vec(), &crate::scene::mesh::Disk).unwrap();
        let e = convert(&scene, &path, false).unwrap_err().to_string();
        assert!(
            e.contains("main.pbrt:2: column 24: infinite: image \"none.exr\" not found"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn the_light_sampler_is_the_files_and_the_tree_without_one() {
        let d = ok("WorldBegin\n").desc.settings;
        assert_eq!(d.preset.get("light_sampler").map(|v| v.0), Some(Value::Name("bvh")));
        for (name, ours) in [("power", "power"), ("uniform", "uniform"), ("bvh", "bvh")] {
            let c = ok(&format!(
                "Integrator \"path\" \"string lightsampler\" \"{name}\"\nWorldBegin\n"
            ));
            let s = &c.desc.settings.scene_file;
            assert_eq!(s.get("light_sampler").map(|v| v.0), Some(Value::Name(ours)), "{name}");
            assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        }
        // pbrt-v4's exhaustive sampler weighs every light as the tree's
        // leaves are weighed; the tree stands in for it, with a word.
        let c = ok("Integrator \"path\" \"string lightsampler\" \"exhaustive\"\nWorldBegin\n");
        assert_eq!(
            c.desc.settings.scene_file.get("light_sampler").map(|v| v.0),
            Some(Value::Name("bvh"))
        );
        assert!(c
            .warnings
            .iter()
            .any(|w| w.contains("main.pbrt:1") && w.contains("exhaustive")));
        let e = convert_text(
            "Integrator \"path\"\n  \"string lightsampler\" \"nearest\"\nWorldBegin\n",
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("main.pbrt:2") && e.contains("unknown lightsampler \"nearest\""),
            "{e}"
        );
    }

    #[test]
    fn materials_and_settings() {
        let c = ok(&format!(
            "Integrator \"path\" \"integer maxdepth\" [ 7 ]\nSampler \"zsobol\" \"integer pixelsamples\" [ 32 ]\n\
             PixelFilter \"box\"\nWorldBegin\nMaterial \"dielectric\" \"float eta\" [ 1.33 ]\n{}\
             Material \"diffuse\" \"rgb reflectance\" [ 0.2 0.3 0.4 ] \"float bogus\" [ 1 ]\nShape \"sphere\"\n",
            quad(0.0)
        ));
        let mats: Vec<Material> = c.desc.materials.iter().map(|(_, m)| m.clone()).collect();
        assert!(mats.contains(&Material::glass(1.33)));
        assert!(mats.contains(&Material::diffuse(0.2, 0.3, 0.4)));
        let s = &c.desc.settings.scene_file;
        assert_eq!(s.get("max_depth").map(|v| v.0), Some(Value::Int(7)));
        // Photon paths asked for on the scene follow the file's depth.
        assert_eq!(s.get("max_bounces").map(|v| v.0), Some(Value::Int(7)));
        assert_eq!(s.get("spp").map(|v| v.0), Some(Value::Int(32)));
        assert_eq!(s.get("integrator").map(|v| v.0), Some(Value::Name("path")));
        assert_eq!(s.get("filter").map(|v| v.0), Some(Value::Name("box")));
        assert_eq!(
            s.get("spp").map(|v| v.1.clone()),
            Some(Origin::SceneFile {
                path: "dir/main.pbrt".into(),
                line: 2
            })
        );
        assert!(
            c.warnings.iter().any(|w| w.contains("\"float bogus\" is not used")),
            "{:?}",
            c.warnings
        );
        // pbrt's defaults where the file says nothing.
        let d = ok("WorldBegin\n").desc.settings;
        assert_eq!(d.preset.get("spp").map(|v| v.0), Some(Value::Int(16)));
        assert_eq!(d.preset.get("max_depth").map(|v| v.0), Some(Value::Int(5)));
        assert_eq!(d.preset.get("max_bounces").map(|v| v.0), Some(Value::Int(5)));
        assert_eq!(d.preset.get("filter").map(|v| v.0), Some(Value::Name("gaussian")));
        assert_eq!(d.preset.get("sampler").map(|v| v.0), Some(Value::Name("zsobol")));
        assert_eq!(s.get("sampler").map(|v| v.0), Some(Value::Name("zsobol")));
        // The seed option is the samplers' default seed; a sampler's own wins.
        let d = ok("Option \"seed\" 7\nWorldBegin\n").desc.settings;
        assert_eq!(d.scene_file.get("seed").map(|v| v.0), Some(Value::Int(7)));
        let d = ok("Option \"seed\" 7\nSampler \"sobol\" \"integer seed\" 3\nWorldBegin\n")
            .desc
            .settings;
        assert_eq!(d.scene_file.get("seed").map(|v| v.0), Some(Value::Int(3)));
        for (pbrt, ours) in [("sobol", "sobol"), ("pmj02bn", "sobol"), ("stratified", "independent")] {
            let d = ok(&format!("Sampler \"{pbrt}\"\nWorldBegin\n")).desc.settings;
            assert_eq!(
                d.scene_file.get("sampler").map(|v| v.0),
                Some(Value::Name(ours)),
                "{pbrt}"
            );
        }
    }

    #[test]
    fn coated_conductor_reads_pbrt_v4s_parameters() {
        let m = |params: &str| {
            convert_text(
                &format!("WorldBegin\nMaterial \"coatedconductor\" {params}\n{}", quad(0.0)),
                false,
            )
        };
        let c = m(
            "\"float interface.roughness\" [ 0.1 ] \"float conductor.uroughness\" [ 0.2 ] \
                   \"float conductor.vroughness\" [ 0.3 ] \"spectrum conductor.eta\" \"metal-Al-eta\" \
                   \"spectrum conductor.k\" \"metal-Al-k\" \"float interface.eta\" [ 1.4 ] \"integer maxdepth\" [ 7 ]",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let (al_eta, al_k) = crate::bsdf::named_metal("Al").unwrap();
        assert_eq!(
            c.desc.materials[0].1,
            Material::CoatedConductor {
                interface_roughness: Roughness {
                    u: 0.1,
                    v: 0.1,
                    remap: true
                }
                .into(),
                eta: 1.4,
                thickness: 0.01,
                conductor: ConductorFresnel::Ior { eta: al_eta, k: al_k },
                conductor_roughness: Roughness {
                    u: 0.2,
                    v: 0.3,
                    remap: true
                }
                .into(),
                max_depth: 7,
                samples: 1,
                medium: None,
            }
        );
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        // pbrt-v4's defaults: a smooth coat of 1.5 over smooth copper.
        let c = m("").unwrap_or_else(|e| panic!("{e}"));
        let Material::CoatedConductor { eta, conductor, .. } = &c.desc.materials[0].1 else {
            panic!("{:?}", c.desc.materials)
        };
        let (cu_eta, cu_k) = crate::bsdf::named_metal("Cu").unwrap();
        assert_eq!(
            (*eta, conductor),
            (1.5, &ConductorFresnel::Ior { eta: cu_eta, k: cu_k })
        );
        assert!(c.desc.materials[0].1.is_specular());
        let e = m("\"rgb reflectance\" [ 0.5 0.5 0.5 ] \"spectrum conductor.k\" \"metal-Al-k\"")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("dir/main.pbrt:2: coatedconductor: give"), "{e}");
        // A coat medium that scatters, with its walk's limits.
        let c = m("\"rgb albedo\" [ 0.5 0.25 0 ] \"float g\" 0.3 \"integer maxdepth\" 20")
            .unwrap_or_else(|e| panic!("{e}"));
        let Material::CoatedConductor { medium, .. } = &c.desc.materials[0].1 else {
            panic!("{:?}", c.desc.materials)
        };
        assert_eq!(
            *medium,
            Some(CoatMedium {
                albedo: Texture::from(Vec3::new(0.5, 0.25, 0.0)),
                g: 0.3,
                max_depth: 20,
                samples: 1
            })
        );
        assert!(!c.desc.materials[0].1.is_specular());
        let c = m("\"rgb albedo\" [ 0 0 0 ] \"float g\" 0.3").unwrap_or_else(|e| panic!("{e}"));
        assert!(matches!(
            c.desc.materials[0].1,
            Material::CoatedConductor { medium: None, .. }
        ));
        let e = m("\"rgb albedo\" [ 0.5 0.5 0.5 ] \"float g\" 1")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("dir/main.pbrt:2: coatedconductor: \"g\" 1 must be in (-1, 1)"),
            "{e}"
        );
        // A textured albedo is looked up at each hit; a textured g is refused.
        let textured = |param: &str| {
            convert_text(
                &format!(
                    "WorldBegin\nTexture \"t\" \"spectrum\" \"checkerboard\"\nTexture \"f\" \"float\" \"constant\"\n\
                     Material \"coateddiffuse\" {param}\n{}",
                    quad(0.0)
                ),
                false,
            )
        };
        let c = textured("\"texture albedo\" \"t\"").unwrap_or_else(|e| panic!("{e}"));
        let Material::CoatedDiffuse { medium: Some(m), .. } = &c.desc.materials[0].1 else {
            panic!("{:?}", c.desc.materials)
        };
        assert!(m.albedo.as_constant().is_none(), "{m:?}");
        let e = textured("\"texture g\" \"f\"").unwrap_err().to_string();
        assert!(e.contains("a textured coat \"g\" is not supported"), "{e}");
        // So is the plain conductor, as pbrt-v4's.
        let e = convert_text(
            &format!(
                "WorldBegin\nMaterial \"conductor\" \"rgb reflectance\" [ 0.5 0.5 0.5 ] \"float eta\" [ 1.2 ]\n{}",
                quad(0.0)
            ),
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("dir/main.pbrt:2: conductor: give"), "{e}");
    }

    #[test]
    fn an_index_of_refraction_is_a_float_or_a_constant_spectrum() {
        let eta = |material: &str, name: &str, value: &str| {
            convert_text(
                &format!(
                    "WorldBegin\nTexture \"t\" \"float\" \"constant\" \"float value\" [ 1.5 ]\n\
                     Material \"{material}\" {value}\n{}",
                    quad(0.0)
                ),
                false,
            )
            .map(|c| match &c.desc.materials[0].1 {
                Material::Dielectric { eta, .. } | Material::CoatedConductor { eta, .. } => *eta,
                m => panic!("{m:?}"),
            })
            .map_err(|e| e.to_string())
            .map_err(|e| {
                assert!(e.contains(&format!("\"{name}\"")), "{e}");
                e
            })
        };
        for (material, name) in [("dielectric", "eta"), ("coatedconductor", "interface.eta")] {
            assert_eq!(eta(material, name, &format!("\"float {name}\" [ 1.33 ]")), Ok(1.33));
            assert_eq!(eta(material, name, ""), Ok(1.5));
            let flat = format!("\"spectrum {name}\" [ 300 1.7 800 1.7 ]");
            assert_eq!(eta(material, name, &flat), Ok(1.7));
            let e = eta(material, name, &format!("\"texture {name}\" \"t\"")).unwrap_err();
            assert!(e.contains("textured"), "{e}");
        }
        // A coat has one index: a dispersive one is refused, and with
        // --lenient taken at 550 nm (BK7: 1.5185 there, 1.5168 at 587.6 nm
        // as Schott lists it; a sampled spectrum interpolated), with one
        // warning.
        for (value, want) in [
            ("\"spectrum interface.eta\" \"glass-BK7\"", 1.51852),
            ("\"spectrum interface.eta\" \"glass-F11\"", 1.79115),
            ("\"spectrum interface.eta\" [ 500 1.6 600 1.5 ]", 1.55),
        ] {
            let text = format!("WorldBegin\nMaterial \"coatedconductor\"\n  {value}\n{}", quad(0.0));
            let e = convert_text(&text, false).unwrap_err().to_string();
            assert!(
                e.starts_with(
                    "dir/main.pbrt:3: material of type \"coatedconductor\": an \"interface.eta\" that varies"
                ),
                "{e}"
            );
            let c = convert_text(&text, true).unwrap();
            let Material::CoatedConductor { eta, .. } = c.desc.materials[0].1 else {
                panic!("{:?}", c.desc.materials)
            };
            assert!((eta - want).abs() < 1e-5, "{value}: {eta}");
            assert!(
                c.warnings.iter().any(|w| w.contains("1 unsupported features ignored")),
                "{:?}",
                c.warnings
            );
        }
        // A dielectric disperses: each colour channel has its own index,
        // the red one the lowest, for the glasses within their range over
        // the visible wavelengths. (The negative lobes of the channels'
        // weights may take a mean beyond a spectrum's range, as for the
        // sampled one, whose index changes within 100 nm only.)
        for (value, lo, hi) in [
            ("\"spectrum eta\" \"glass-BK7\"", 1.5117, 1.5308),
            ("\"spectrum eta\" \"glass-F11\"", 1.7757, 1.8290),
            ("\"spectrum eta\" [ 500 1.6 600 1.5 ]", 1.45, 1.65),
        ] {
            let text = format!("WorldBegin\nMaterial \"dielectric\"\n  {value}\n{}", quad(0.0));
            let c = convert_text(&text, false).unwrap();
            let Material::Dispersive { eta, .. } = c.desc.materials[0].1 else {
                panic!("{:?}", c.desc.materials)
            };
            assert!(eta.x < eta.y && eta.y < eta.z, "{value}: {eta}");
            assert!(eta.x > lo && eta.z < hi, "{value}: {eta}");
            assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        }
        // A named spectrum that is no glass is refused as a material.
        let text = format!(
            "WorldBegin\nMaterial \"dielectric\" \"spectrum eta\" \"metal-Cu-eta\"\n{}",
            quad(0.0)
        );
        let e = convert_text(&text, false).unwrap_err().to_string();
        assert!(
            e.contains("the spectrum \"metal-Cu-eta\" as \"eta\" is not supported"),
            "{e}"
        );
    }

    #[test]
    fn film_white_balance_and_camera_sensors_are_settings() {
        let c = ok("Film \"rgb\" \"float whitebalance\" [ 3200 ]\nWorldBegin\n");
        let s = &c.desc.settings.scene_file;
        assert_eq!(s.get("white_balance").map(|v| v.0), Some(Value::Real(3200.0)));
        assert!(s.get("sensor").is_none());
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        // pbrt-v4's default sensor neither balances nor names a camera.
        let d = ok("Film \"rgb\" \"string sensor\" \"cie1931\"\nWorldBegin\n")
            .desc
            .settings;
        assert!(d.scene_file.get("white_balance").is_none() && d.preset.get("white_balance").is_none());
        assert!(d.scene_file.get("sensor").is_none());
        // A temperature outside the range is the file's error at its place.
        let e = convert_text("Film \"rgb\"\n  \"float whitebalance\" [ -5 ]\nWorldBegin\n", true)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("dir/main.pbrt:2: white_balance = -5: must be"), "{e}");
        // A measured camera is the sensor setting, with or without a
        // temperature (the film's matrix balances it at 6500 K unless given).
        let text = "Film \"rgb\"\n  \"string sensor\" \"canon_eos_100d\"\nWorldBegin\n";
        let c = convert_text(text, false).unwrap();
        let s = &c.desc.settings.scene_file;
        assert_eq!(s.get("sensor").map(|v| v.0), Some(Value::Name("canon_eos_100d")));
        assert!(s.get("white_balance").is_none());
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        let c = convert_text(
            &text.replace("WorldBegin", "  \"float whitebalance\" 5000\nWorldBegin"),
            false,
        )
        .unwrap();
        let s = &c.desc.settings.scene_file;
        assert_eq!(s.get("white_balance").map(|v| v.0), Some(Value::Real(5000.0)));
        assert_eq!(s.get("sensor").map(|v| v.0), Some(Value::Name("canon_eos_100d")));
        // A name pbrt-v4 does not know is an error at its line, lenient or not.
        for lenient in [false, true] {
            let e = convert_text(&text.replace("eos_100d", "eos_99d"), lenient)
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with(
                    "dir/main.pbrt:2: Film: unknown camera sensor \"canon_eos_99d\" (known: cie1931, canon_eos_100d,"
                ),
                "{e}"
            );
        }
    }

    #[test]
    fn film_clamp_is_the_max_component_setting() {
        let c = ok("Film \"rgb\" \"float maxcomponentvalue\" [ 10 ]\nWorldBegin\n");
        let s = &c.desc.settings.scene_file;
        assert_eq!(s.get("max_component").map(|v| v.0), Some(Value::Real(10.0)));
        assert!(
            c.warnings.iter().all(|w| !w.contains("maxcomponentvalue")),
            "{:?}",
            c.warnings
        );
        // Unset, pbrt-v4's film does not clamp.
        let d = ok("WorldBegin\n").desc.settings;
        assert!(d.scene_file.get("max_component").is_none() && d.preset.get("max_component").is_none());
        // A clamp that leaves nothing is refused where it is written.
        let e = convert_text("Film \"rgb\"\n  \"float maxcomponentvalue\" [ 0 ]\nWorldBegin\n", false)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("dir/main.pbrt:2: max_component = 0: must be"), "{e}");
        // Such a value is the file's error, once, even with --lenient (it
        // was listed as an unsupported feature, its place twice).
        let e = convert_text("Sampler \"halton\" \"integer pixelsamples\" [ 0 ]\nWorldBegin\n", true)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "dir/main.pbrt:1: spp = 0: must be between 1 and 1048576");
    }

    #[test]
    fn unsupported_features_are_one_error_unless_lenient() {
        let text = format!(
            "WorldBegin\nMakeNamedMaterial \"cu\" \"string type\" \"plastic\"\nNamedMaterial \"cu\"\n{}\
             Shape \"teapot\"\nLightSource \"laser\"\nLightSource \"laser\"\nLightSource \"laser\"\n",
            quad(0.0)
        );
        let e = convert_text(&text, false).unwrap_err().to_string();
        assert!(e.starts_with("dir/main.pbrt:2: material \"cu\""), "{e}");
        assert!(e.contains("dir/main.pbrt:6: light \"laser\" is not supported"), "{e}");
        assert!(
            e.contains("dir/main.pbrt:5: \"teapot\"") && e.contains("and 1 more"),
            "{e}"
        );
        assert!(!e.contains('\n'));
        let c = convert_text(&text, true).unwrap();
        assert_eq!(
            c.desc.materials,
            vec![("cu".to_string(), Material::diffuse(0.5, 0.5, 0.5))]
        );
        assert_eq!(c.desc.triangles.len(), 2);
        let w = c.warnings.join("\n");
        assert!(
            w.contains("--lenient: 1 materials") && w.contains("--lenient: 1 unsupported shapes"),
            "{w}"
        );
        assert!(w.contains("--lenient: 3 unsupported lights"), "{w}");
    }

    #[test]
    fn image_lights_without_their_image_are_refused_at_their_line() {
        for kind in ["goniometric", "projection"] {
            let e = convert_text(&format!("WorldBegin\nLightSource \"{kind}\"\n"), true)
                .unwrap_err()
                .to_string();
            assert_eq!(e, format!("dir/main.pbrt:2: {kind}: \"filename\" is required"));
            let e = convert_text(
                &format!("WorldBegin\nLightSource \"{kind}\" \"string filename\" \"no.pfm\"\n"),
                true,
            )
            .unwrap_err()
            .to_string();
            assert!(
                e.starts_with("dir/main.pbrt:2:") && e.contains("image \"no.pfm\" not found"),
                "{e}"
            );
            // Under a stretch: one of the unsupported features.
            let e = convert_text(&format!("WorldBegin\nScale 1 2 1\nLightSource \"{kind}\"\n"), false)
                .unwrap_err()
                .to_string();
            assert!(e.contains("other than rotation and uniform scale"), "{e}");
        }
    }

    #[test]
    fn an_infinite_lights_portal_is_read_in_world_space_and_reflected_with_the_scene() {
        // The portal's corners are taken as given, whatever the transformation.
        let text = "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\nTranslate 5 5 5\n\
                    LightSource \"infinite\" \"rgb L\" [ 1 2 3 ] \"point3 portal\" [ 0 0 4  0 1 4  1 1 4  1 0 4 ]\n";
        let c = convert_text(text, false).unwrap();
        let Light::Infinite { portal: Some(p), .. } = &c.desc.lights[0] else {
            panic!("{:?}", c.desc.lights);
        };
        // pbrt's picture is our mirror image here: the scene is reflected
        // across the camera's vertical plane (x = 0), the portal with it.
        assert!(c.mirrored);
        let expected = [[0.0, 0.0, 4.0], [0.0, 1.0, 4.0], [-1.0, 1.0, 4.0], [-1.0, 0.0, 4.0]];
        for (got, want) in p.corners().iter().zip(expected) {
            assert!((*got - Vec3::from(want)).length() < 1e-6, "{:?}", p.corners());
        }
        // Light from behind the portal (+z) reaches a point in front of it
        // through the portal, and not beside it.
        let l = &c.desc.lights[0];
        assert_eq!(
            l.le_escaped(Vec3::new(-0.5, 0.5, 0.0), Vec3::Z),
            Vec3::new(1.0, 2.0, 3.0)
        );
        assert_eq!(l.le_escaped(Vec3::new(0.5, 0.5, 0.0), Vec3::Z), Vec3::ZERO);
    }
}
