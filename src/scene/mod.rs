//! The scene: what the integrators see. A `SceneDesc` (built in, or read from
//! a file) is turned into a `Scene` by building the BVH; data flows one way,
//! from description to renderable scene.

pub mod builtin;
pub mod file;
pub mod mesh;
pub mod pbrt;
pub mod transform;
pub mod triangles;

use crate::bsdf::BxdfFlags;
use crate::camera::Camera;
use crate::camera::{Differentials, PixelFootprint};
use crate::error::{Error, Result};
use crate::geometry::curve::CurveHit;
pub use crate::geometry::motion;
use crate::geometry::triangle::TriHit;
use crate::geometry::{BoxBvh, Bvh, Curve, Disk, Sphere, Triangle};
use crate::light::{Light, LightContext, LightSampleU, LightSamplerKind, LightTree};
use crate::material::Material;
use crate::material::{ShadingGeometry, SurfacePoint};
use crate::math::{Ray, Vec2, Vec3};
use crate::medium::{Medium, MediumInterface};
use crate::sampling::hash_unit;
pub use crate::settings::SceneSettings;
use crate::texture::{Footprint, TexCoord, Texture};
use mesh::MeshReport;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
pub use triangles::{FaceUvs, Triangles};
use triangles::{ShadingSource, ShadingTable};

/// How to load a scene: the mesh path that replaces the scene's own (or
/// supplies one a built-in scene needs), and whether meshes are smooth-shaded.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    pub mesh: Option<PathBuf>,
    /// Interpolate vertex normals where a mesh file has them.
    pub smooth: bool,
    /// pbrt-v4 scenes: render what is supported, replacing or skipping the
    /// rest with a warning, instead of refusing the scene.
    pub lenient: bool,
}

/// A scene description and what loading its meshes took.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    pub desc: SceneDesc,
    pub meshes: Vec<MeshReport>,
    /// Which image axis the scene file's field of view spans, kept when the
    /// image is resized ([`LoadedScene::set_resolution`]).
    pub fov_axis: FovAxis,
    /// The part of the frame the scene file asks to render (pbrt-v4's
    /// `cropwindow` and `pixelbounds`); `--crop` and `--tile` replace it.
    pub crop: Option<FilmCrop>,
}

impl LoadedScene {
    /// Renders the scene at `width` x `height` (`--width`, `--height`),
    /// keeping its field of view as its format defines it.
    pub fn set_resolution(&mut self, width: u32, height: u32) {
        self.desc.camera.resize(width, height, self.fov_axis);
    }

    /// The pixels of `crop` at the current image size.
    pub fn crop_rect(&self) -> Option<Option<crate::film::PixelRect>> {
        let c = &self.desc.camera;
        self.crop.map(|crop| crop.rect(c.width, c.height))
    }
}

/// A part of the frame, as a scene file gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilmCrop {
    /// Fractions of the frame's width and height, `[x0, x1, y0, y1]` in
    /// [0, 1]: pixels ceil(x0 w) to ceil(x1 w), as pbrt-v4 rounds them.
    Window([f32; 4]),
    /// Pixels `[x0, x1, y0, y1]` (ends excluded) of an image of `size`; at
    /// another size they scale with it (rounded up, as the window is).
    Pixels { bounds: [u32; 4], size: (u32, u32) },
}

impl FilmCrop {
    /// The pixel rectangle at `width` x `height`; `None` when it is empty.
    pub fn rect(&self, width: u32, height: u32) -> Option<crate::film::PixelRect> {
        let [x0, x1, y0, y1] = match *self {
            FilmCrop::Window(w) => {
                // In f32, as pbrt-v4 computes it, for the same pixels.
                let up = |f: f32, n: u32| ((n as f32 * f).ceil() as u32).min(n);
                [up(w[0], width), up(w[1], width), up(w[2], height), up(w[3], height)]
            }
            FilmCrop::Pixels {
                bounds: b,
                size: (sw, sh),
            } => {
                let scale = |v: u32, from: u32, to: u32| {
                    if from == to || from == 0 {
                        v.min(to)
                    } else {
                        (v as u64 * to as u64).div_ceil(from as u64).min(to as u64) as u32
                    }
                };
                [
                    scale(b[0], sw, width),
                    scale(b[1], sw, width),
                    scale(b[2], sh, height),
                    scale(b[3], sh, height),
                ]
            }
        };
        (x0 < x1 && y0 < y1).then_some(crate::film::PixelRect { x0, y0, x1, y1 })
    }
}

/// Which image axis a scene format's field of view spans.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FovAxis {
    /// The vertical one, whatever the image's shape (this renderer's scene
    /// files and built-in scenes).
    #[default]
    Vertical,
    /// The shorter one (pbrt-v4's `fov`): resizing a landscape image to a
    /// portrait one moves the field of view to the horizontal axis.
    Shorter,
}

/// Loads a scene given as a built-in name, a TOML file or a pbrt-v4 file
/// (a path ending in `.pbrt` or `.pbrt.gz`). A path ending in `.toml` is
/// always a file; otherwise a built-in name wins over a file of the same
/// name (write `./NAME` for the file).
pub fn load(spec: &str, opts: &LoadOptions) -> Result<LoadedScene> {
    let path = Path::new(spec);
    let lower = spec.to_ascii_lowercase();
    if lower.ends_with(".pbrt") || lower.ends_with(".pbrt.gz") {
        return pbrt::convert::load(path, opts);
    }
    let is_toml = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if is_toml {
        return file::load(path, opts);
    }
    if let Some(scene) = builtin::by_name(spec, opts)? {
        return Ok(scene);
    }
    if path.is_file() {
        return file::load(path, opts);
    }
    Err(Error::UnknownScene {
        name: spec.to_string(),
        known: builtin::NAMES.join(", "),
    })
}

/// The camera as a scene states it.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraDesc {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    pub fov_y_deg: f32,
    pub width: u32,
    pub height: u32,
    /// Another image window than [-aspect, aspect] x [-1, 1] (pbrt-v4's
    /// `screenwindow`), in units of tan(fov_y_deg / 2); it does not change
    /// with the image size.
    pub window: Option<crate::camera::ScreenWindow>,
    pub lens: Option<crate::camera::ThinLens>,
    /// An orthographic camera, whose image spans twice this many world units
    /// vertically (`fov_y_deg` unused); with a `window`, the world length of
    /// a unit of the window.
    pub orthographic: Option<f32>,
    /// A spherical camera (pbrt-v4's `spherical`): the whole sphere of
    /// directions in this layout (`fov_y_deg`, `window` and `lens` unused).
    pub spherical: Option<crate::camera::SphericalMapping>,
    /// A real lens (pbrt-v4's `realistic` camera): rays are traced through
    /// it (`fov_y_deg`, `window`, `lens` and `orthographic` unused).
    pub realistic: Option<crate::camera::SharedLens>,
}

impl CameraDesc {
    /// The camera it describes; `None` for a degenerate one.
    pub fn camera(&self) -> Option<Camera> {
        self.camera_at(self.position, self.look_at, self.up)
    }

    /// Why `camera()` gives no camera: one line for the user.
    pub fn problem(&self) -> String {
        let forward = self.look_at - self.position;
        if !(self.position.is_finite() && self.look_at.is_finite() && self.up.is_finite()) {
            "the camera's position, look_at or up is not finite".into()
        } else if forward.length_squared() == 0.0 || !forward.length_squared().is_finite() {
            format!("the camera looks at its own position {}", self.position)
        } else if forward.cross(self.up).length_squared() == 0.0 {
            format!("the camera's up {} is zero or along its viewing direction", self.up)
        } else {
            format!(
                "the camera's field of view ({} degrees), orthographic window, screen window or lens is out of range",
                self.fov_y_deg
            )
        }
    }

    /// The camera it describes, moved to `position`, looking at `look_at`
    /// with `up` (the preview's moves).
    pub fn camera_at(&self, position: Vec3, look_at: Vec3, up: Vec3) -> Option<Camera> {
        let (w, h) = (self.width, self.height);
        if let Some(lens) = &self.realistic {
            return Camera::realistic(position, look_at, up, lens.clone(), w, h);
        }
        if let Some(mapping) = self.spherical {
            return Camera::spherical(position, look_at, up, mapping, w, h);
        }
        match self.orthographic {
            Some(half) => Camera::orthographic(position, look_at, up, half, w, h),
            None => Camera::new(position, look_at, up, self.fov_y_deg, w, h),
        }?
        .with_optics(self.window, self.lens)
    }

    /// Sets the image size. With [`FovAxis::Vertical`] `fov_y_deg` stays;
    /// with [`FovAxis::Shorter`] the field of view of the shorter axis
    /// (which `fov_y_deg` implies at the old size) stays, on the shorter
    /// axis of the new size. A window of its own stays as it is, as pbrt-v4
    /// keeps a `screenwindow` whatever the film's resolution.
    pub fn resize(&mut self, width: u32, height: u32, axis: FovAxis) {
        let shorter = axis == FovAxis::Shorter && self.window.is_none();
        if shorter && self.width > 0 && self.height > 0 && width > 0 && height > 0 {
            // The vertical extent (a tangent, or an orthographic half height)
            // from the shorter axis' one, which stays.
            let vertical = |v: f32| {
                let shorter = v * (self.width as f32 / self.height as f32).min(1.0);
                shorter * (height as f32 / width as f32).max(1.0)
            };
            match self.orthographic {
                Some(h) => self.orthographic = Some(vertical(h)),
                None => {
                    let tan_y = vertical((self.fov_y_deg.to_radians() * 0.5).tan());
                    self.fov_y_deg = 2.0 * tan_y.atan().to_degrees();
                }
            }
        }
        self.width = width;
        self.height = height;
    }
}

/// A triangle with its material (an index into `SceneDesc::materials`) and
/// optional per-vertex normals for smooth shading.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleDesc {
    pub vertices: [Vec3; 3],
    pub normals: Option<[Vec3; 3]>,
    /// Texture coordinates per vertex; without them a triangle's are pbrt's
    /// default (0, 0), (1, 0), (1, 1).
    pub uvs: Option<[Vec2; 3]>,
    pub material: u32,
}

/// How an area light's surface reflects: by `material`; for a triangle,
/// with these vertex normals and texture coordinates (as a
/// `TriangleDesc`'s); for a sphere, with texture coordinates in the frame
/// `axes` (as a `SphereDesc`'s). A disk has its own.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightSurface {
    pub material: u32,
    pub normals: Option<[Vec3; 3]>,
    pub uvs: Option<[Vec2; 3]>,
    pub axes: Option<glam::Mat3>,
}

/// Shapes cut out by an alpha texture (pbrt-v4's `alpha` shape parameter):
/// where the texture's scalar value `a` at a ray's hit is below 1, the hit
/// counts with probability `a` (never where `a` is 0), decided by a hash of
/// the ray and the primitive, as pbrt-v4 decides it; a ray not stopped goes
/// on to whatever lies behind. Shadow rays, photons and camera rays alike.
#[derive(Clone, Debug, PartialEq)]
pub struct Cutout {
    pub alpha: Texture,
    pub shapes: CutShapes,
}

/// Shapes that bound participating media, and the media on their sides
/// (`outside` on the side of each shape's stored normal: a triangle's
/// winding, a sphere's outward normal, a disk's `normal`).
#[derive(Clone, Debug, PartialEq)]
pub struct Boundary {
    pub interface: MediumInterface,
    pub shapes: CutShapes,
}

/// The shapes of a description a [`Cutout`] or a [`Boundary`] applies to.
#[derive(Clone, Debug, PartialEq)]
pub enum CutShapes {
    /// `triangles[range]`: a mesh's.
    Triangles(std::ops::Range<usize>),
    Sphere(usize),
    Disk(usize),
}

#[derive(Clone, Debug, PartialEq)]
pub struct SphereDesc {
    pub sphere: Sphere,
    pub material: u32,
    /// World directions of the sphere's own x, y and z axes (the columns;
    /// orthonormal, a reflection where the determinant is negative), about
    /// which its texture coordinates run: pbrt-v4's sphere turned by its
    /// transformation. `None`: the world's axes.
    pub axes: Option<glam::Mat3>,
}

/// A disk or annulus (pbrt-v4's `disk` shape) in world space. A ray meets
/// it from either side and it is shaded on both; `normal` is its geometric
/// normal (the front, for one-sided emission). Texture coordinates and dp/du
/// are pbrt-v4's: u = phi / 2 pi with phi the angle from `axes[0]` towards
/// `axes[1]`, v = (radius - r) / (radius - inner_radius) at distance r from
/// the centre, dp/du = 2 pi (x axes[1] - y axes[0]) at coordinates (x, y)
/// along the axes.
///
/// From pbrt-v4's `Shape "disk"` (`height` h, `radius` r, `innerradius` ri)
/// under a rotation, uniform scale s and translation M (world from object):
///
/// - `centre` = M (0, 0, h); `radius` = s r; `inner_radius` = s ri;
/// - `axes` = `Some([M (1, 0, 0) / s, M (0, 1, 0) / s])`, the images of the
///   object's x and y axes;
/// - `normal` = M (0, 0, 1) / s carried as a normal, negated when
///   `ReverseOrientation` xor M swaps handedness
///   (`pbrt::ir::Shape::flips_normals`); equivalently
///   `axes[0] x axes[1]`, negated under `ReverseOrientation` alone.
///
/// Mirroring the scene (as the pbrt converter does) maps `centre` as a point
/// and `normal` and both `axes` as vectors; the texture then stays on the
/// mirrored surface as it was. `Scene::build` normalises `normal`,
/// orthonormalises `axes` within the disk's plane, and refuses a radius not
/// > 0, an inner radius outside [0, radius) and a zero normal.
#[derive(Clone, Debug, PartialEq)]
pub struct DiskDesc {
    pub centre: Vec3,
    pub normal: Vec3,
    pub radius: f32,
    /// Radius of the hole; 0 for a full disk.
    pub inner_radius: f32,
    pub material: u32,
    /// World directions of phi = 0 and phi = pi / 2; `None`:
    /// `math::orthonormal_basis(normal)`, which for normal +z is the x and y
    /// axes (pbrt's disk without a transformation).
    pub axes: Option<[Vec3; 2]>,
}

impl DiskDesc {
    /// A disk with the default axes.
    pub fn new(centre: Vec3, normal: Vec3, radius: f32, inner_radius: f32, material: u32) -> DiskDesc {
        DiskDesc {
            centre,
            normal,
            radius,
            inner_radius,
            material,
            axes: None,
        }
    }

    /// The disk it describes, or what is wrong with it.
    pub fn disk(&self) -> std::result::Result<Disk, String> {
        Disk::new(self.centre, self.normal, self.radius, self.inner_radius, self.axes)
    }
}

/// A piece of a thin curve (`geometry::Curve`, world space) and its
/// material. Curves emit no light and bound no media.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveDesc {
    pub curve: Curve,
    pub material: u32,
}

/// Everything needed to build a scene, before any acceleration structure.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDesc {
    pub name: String,
    pub camera: CameraDesc,
    pub materials: Vec<(String, Material)>,
    pub triangles: Triangles,
    pub spheres: Vec<SphereDesc>,
    pub disks: Vec<DiskDesc>,
    pub curves: Vec<CurveDesc>,
    pub lights: Vec<Light>,
    /// The surface each area light reflects by, by light index (pbrt-v4's
    /// emitters keep their shape's material). A light missing here, or
    /// `None`, reflects nothing.
    pub light_surfaces: Vec<Option<LightSurface>>,
    /// Area lights that no ray meets, by light index (pbrt-v4's area
    /// lights of `alpha` 0): they light the scene through light sampling
    /// alone, are not seen and cast no shadow. A light missing here is met
    /// as any surface is.
    pub invisible_lights: Vec<bool>,
    /// Shapes cut out by alpha textures.
    pub cutouts: Vec<Cutout>,
    /// Participating media, by name.
    pub media: Vec<(String, Medium)>,
    /// The medium the camera is in (an index into `media`).
    pub camera_medium: Option<u32>,
    /// Shapes that bound media. A shape in none is no boundary: a ray
    /// crossing it stays in its medium.
    pub boundaries: Vec<Boundary>,
    /// The render settings the scene recommends: its file's and its preset's.
    pub settings: SceneSettings,
    /// The samples a pixel of the render, which scale texture footprints
    /// (`camera::PixelFootprint`); the render's settings set it.
    pub texture_spp: u32,
    /// Runs of `triangles` that move while the shutter is open (placed as
    /// at their motion's start).
    pub moving: Vec<MovingTriangles>,
    /// Spheres and disks that move while the shutter is open (placed as at
    /// their motion's start).
    pub moving_shapes: Vec<MovingShape>,
    /// The times the shutter opens and closes: camera rays' times are
    /// uniform between them when anything moves.
    pub shutter: [f32; 2],
    /// The camera's motion, from where `camera` places it.
    pub camera_motion: Option<motion::Motion>,
    /// How shadow rays choose their light; the render's settings set it.
    pub light_sampler: LightSamplerKind,
}

/// A moving run of triangles at its motion's start, from one time of the
/// shutter (`Scene::rest_frame`).
#[derive(Clone, Debug, PartialEq)]
pub struct RestFrame {
    /// The run's triangles (`Hit::object`s).
    pub objects: std::ops::Range<u32>,
    /// From the time's placement to the start's.
    pub to_rest: glam::Mat4,
    /// From the start's placement to the time's.
    pub from_rest: glam::Mat4,
}

impl RestFrame {
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.to_rest.transform_point3(p)
    }

    /// A unit direction carried to the start's placement.
    pub fn direction(&self, d: Vec3) -> Vec3 {
        self.to_rest.transform_vector3(d).normalize_or_zero()
    }

    /// A unit direction carried back from the start's placement.
    pub fn direction_back(&self, d: Vec3) -> Vec3 {
        self.from_rest.transform_vector3(d).normalize_or_zero()
    }

    /// A unit surface normal carried to the start's placement (by the
    /// inverse transpose, so that it stays normal under a stretch).
    pub fn normal(&self, n: Vec3) -> Vec3 {
        (glam::Mat3::from_mat4(self.from_rest).transpose() * n).normalize_or_zero()
    }

    /// How much larger a piece of surface with unit normal `n_rest` (at
    /// the start's placement) is at the time's: 1 for a rigid motion.
    pub fn area_scale(&self, n_rest: Vec3) -> f32 {
        let l = glam::Mat3::from_mat4(self.from_rest);
        l.determinant().abs() * (l.inverse().transpose() * n_rest).length()
    }
}

/// A sphere or a disk of a scene (`CutShapes::Sphere` or `CutShapes::Disk`,
/// indices into `SceneDesc::spheres` or `disks`), moving by `motion`.
#[derive(Clone, Debug, PartialEq)]
pub struct MovingShape {
    pub shape: CutShapes,
    pub motion: motion::Motion,
}

/// Triangles `triangles` of a scene, moving by `motion`.
#[derive(Clone, Debug, PartialEq)]
pub struct MovingTriangles {
    pub triangles: std::ops::Range<usize>,
    pub motion: motion::Motion,
}

impl SceneDesc {
    /// A scene with a camera and nothing else yet.
    pub fn empty(name: &str, camera: CameraDesc) -> SceneDesc {
        SceneDesc {
            name: name.into(),
            camera,
            materials: vec![],
            triangles: Triangles::new(),
            spheres: vec![],
            disks: vec![],
            curves: vec![],
            lights: vec![],
            light_surfaces: vec![],
            invisible_lights: vec![],
            cutouts: vec![],
            media: vec![],
            camera_medium: None,
            boundaries: vec![],
            settings: SceneSettings::default(),
            texture_spp: 64,
            moving: vec![],
            moving_shapes: vec![],
            shutter: [0.0, 1.0],
            camera_motion: None,
            light_sampler: LightSamplerKind::Power,
        }
    }

    /// Index of the named material, adding it if new.
    pub fn material(&mut self, name: &str, m: Material) -> u32 {
        if let Some(i) = self.materials.iter().position(|(n, _)| n == name) {
            self.materials[i].1 = m;
            return i as u32;
        }
        self.materials.push((name.to_string(), m));
        (self.materials.len() - 1) as u32
    }

    /// Sets the radius of every sphere light; 0 turns them into point lights.
    /// A sphere keeps the sides it emits from and its surface; a light
    /// made a sphere or a point has no surface to reflect by.
    pub fn set_light_radius(&mut self, radius: f32) {
        for (i, l) in self.lights.iter_mut().enumerate() {
            if !matches!(l, Light::Sphere { .. } | Light::Point { .. } | Light::Triangle { .. }) {
                continue;
            }
            let (position, power) = (l.position(), l.power());
            let was_sphere = match l {
                Light::Sphere { emits, .. } => Some(*emits),
                _ => None,
            };
            *l = if radius > 0.0 {
                Light::Sphere {
                    sphere: Sphere {
                        centre: position,
                        radius,
                    },
                    power,
                    image: None,
                    emits: was_sphere.unwrap_or_default(),
                }
            } else {
                Light::Point { position, power }
            };
            if radius <= 0.0 || was_sphere.is_none() {
                if let Some(s) = self.light_surfaces.get_mut(i) {
                    *s = None;
                }
            }
        }
    }
}

/// A triangle's vertex normals, where all are finite and nonzero (else it
/// is shaded flat).
fn shading_normals(ns: Option<[Vec3; 3]>) -> Option<[Vec3; 3]> {
    ns.filter(|ns| ns.iter().all(|v| v.is_finite() && v.length_squared() > 0.0))
}

/// A triangle's texture coordinates, where all are finite (else it takes
/// the default ones).
fn texture_uvs(uvs: Option<[Vec2; 3]>) -> Option<[Vec2; 3]> {
    uvs.filter(|uv| uv.iter().all(|c| c.is_finite()))
}

/// What a primitive is, for the hit record and photon storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimKind {
    Triangle,
    Sphere,
    Disk,
    Curve,
    Light,
}

impl Hit {
    /// Whether a direction `wi` scattered from `wo` leaves on the side of the
    /// geometric surface its lobe says (reflection: the side of `wo`):
    /// shading normals must not let light leak through a surface.
    pub fn keeps_side(&self, wo: Vec3, wi: Vec3, lobe: BxdfFlags) -> bool {
        let same = (wi.dot(self.ng) > 0.0) == (wo.dot(self.ng) > 0.0);
        same != lobe.is_transmissive()
    }

    /// What the hit's material needs to build its BSDF.
    pub fn surface(&self) -> SurfacePoint {
        SurfacePoint {
            p: self.p,
            uv: self.uv,
            ng: self.ng,
            ns: self.ns,
            dpdu: self.dpdu,
            shading: None,
            footprint: Footprint::NONE,
        }
    }
}

/// A triangle as a path meets it: its corner and edges, unit normal,
/// vertex normals (when it shades with them), material and light.
#[derive(Clone, Copy, Debug)]
pub struct TriangleGeometry {
    pub triangle: Triangle,
    pub ng: Vec3,
    pub normals: Option<[Vec3; 3]>,
    pub material: u32,
    pub light: Option<u32>,
}

/// The shading normal at barycentrics (u, v) of a triangle with vertex
/// normals `n` and unit normal `ng`: `n` interpolated, on `ng`'s side; `ng`
/// where the interpolation vanishes.
#[inline(always)]
pub fn interpolated_normal(n: [Vec3; 3], ng: Vec3, u: f32, v: f32) -> Vec3 {
    let s = (n[0] * (1.0 - u - v) + n[1] * u + n[2] * v).normalize_or_zero();
    if s == Vec3::ZERO {
        ng
    } else if s.dot(ng) < 0.0 {
        -s
    } else {
        s
    }
}

/// A ray's closest hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub p: Vec3,
    /// Unit geometric normal, as stored (not flipped towards the ray).
    pub ng: Vec3,
    /// Unit shading normal, on the same side as `ng`.
    pub ns: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// The surface's dp/du (not normalised), for anisotropic BSDFs.
    pub dpdu: Vec3,
    pub material: u32,
    /// Object id: the triangle's index in the description; triangle count +
    /// sphere index for spheres; triangle count + sphere count + disk index
    /// for disks; for lights, triangle + sphere + disk count + light index;
    /// for curves, triangle + sphere + disk + light count + curve index.
    pub object: u32,
    pub kind: PrimKind,
    /// Index into `Scene::lights` when the hit is on an emitter.
    pub light: Option<u32>,
    /// The ray's time: rays leaving the hit keep it.
    pub time: f32,
}

/// The change of (u, v) for changes `dpdx`, `dpdy` of the point on a surface
/// with derivatives `dpdu`, `dpdv`: pbrt-v4's least-squares solution
/// (`SurfaceInteraction::ComputeDifferentials`), zero where it fails; with
/// `dpdx` and `dpdy` themselves.
fn uv_footprint(dpdu: Vec3, dpdv: Vec3, dpdx: Vec3, dpdy: Vec3) -> Footprint {
    let (a00, a01, a11) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
    let inv = 1.0 / (a00 * a11 - a01 * a01);
    let inv = if inv.is_finite() { inv } else { 0.0 };
    let (b0x, b1x) = (dpdu.dot(dpdx), dpdv.dot(dpdx));
    let (b0y, b1y) = (dpdu.dot(dpdy), dpdv.dot(dpdy));
    let clamp = |v: f32| if v.is_finite() { v.clamp(-1e8, 1e8) } else { 0.0 };
    Footprint {
        dudx: clamp((a11 * b0x - a01 * b1x) * inv),
        dvdx: clamp((a00 * b1x - a01 * b0x) * inv),
        dudy: clamp((a11 * b0y - a01 * b1y) * inv),
        dvdy: clamp((a00 * b1y - a01 * b0y) * inv),
        dpdx: if dpdx.is_finite() { dpdx } else { Vec3::ZERO },
        dpdy: if dpdy.is_finite() { dpdy } else { Vec3::ZERO },
    }
}

/// Texture coordinates of a triangle without its own: pbrt-v4's.
pub const DEFAULT_UV: [Vec2; 3] = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0)];

/// `triangle_shading` for a moving triangle, stored as placed at its
/// motion's start and hit where `to_world` took it.
fn moved_shading(
    hit: &Hit,
    to_world: glam::Mat4,
    shading: impl FnOnce(&Hit) -> Option<(ShadingGeometry, [Vec3; 2])>,
) -> Option<(ShadingGeometry, [Vec3; 2])> {
    let m = glam::Mat3::from_mat4(to_world);
    let (back, normals) = (m.inverse(), m.inverse().transpose());
    let placed = Hit {
        p: to_world.inverse().transform_point3(hit.p),
        ng: (m.transpose() * hit.ng).normalize(),
        ns: (m.transpose() * hit.ns).normalize(),
        dpdu: back * hit.dpdu,
        ..*hit
    };
    let (g, [dpdu, dpdv]) = shading(&placed)?;
    let g = ShadingGeometry {
        n: (normals * g.n).normalize(),
        dpdu: m * g.dpdu,
        dpdv: m * g.dpdv,
        dndu: normals * g.dndu,
        dndv: normals * g.dndv,
    };
    Some((g, [m * dpdu, m * dpdv]))
}

/// A ray carried back from its time into a moving shape's start placement,
/// and the transformation from there to the ray's time.
fn carried_back(m: &motion::Motion, ray: &Ray) -> (Ray, glam::Mat4) {
    let to_world = m.relative(ray.time);
    let inv = to_world.inverse();
    let local = Ray::timed(inv.transform_point3(ray.o), inv.transform_vector3(ray.d), ray.time);
    (local, to_world)
}

/// A hit found in a moving shape's start placement, placed where the shape
/// is by `to_world`.
fn placed_hit(h: Hit, to_world: glam::Mat4) -> Hit {
    let normals = glam::Mat3::from_mat4(to_world).inverse().transpose();
    Hit {
        p: to_world.transform_point3(h.p),
        ng: (normals * h.ng).normalize(),
        ns: (normals * h.ns).normalize(),
        dpdu: to_world.transform_vector3(h.dpdu),
        ..h
    }
}

/// The light tree the scene's sampler asks for, unless it has nothing to
/// weigh: a tree of one leaf (a light, or a quad's two triangles) and no
/// lights apart from it chooses as choosing by power does, and then does so
/// without the tree's number of its own.
fn light_tree(lights: &[Light], kind: LightSamplerKind) -> Option<LightTree> {
    (kind == LightSamplerKind::Bvh)
        .then(|| LightTree::build(lights))
        .filter(|t| !t.is_power_choice())
}

/// pbrt-v4's `Triangle` shading geometry: the derivatives of the point along
/// the texture coordinates; with vertex normals, pbrt-v4's shading frame
/// (dp/du made perpendicular to the shading normal, dp/dv their cross
/// product) and the normals' derivatives.
fn triangle_shading(t: &TriangleDesc, hit: &Hit) -> Option<(ShadingGeometry, [Vec3; 2])> {
    let uv = t.uvs.unwrap_or(DEFAULT_UV);
    let [p0, p1, p2] = t.vertices;
    let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
    let (dp02, dp12) = (p0 - p2, p1 - p2);
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    let degenerate = det.abs() < 1e-9;
    let (mut dpdu, mut dpdv) = (Vec3::ZERO, Vec3::ZERO);
    if !degenerate {
        dpdu = (dp02 * duv12.y - dp12 * duv02.y) / det;
        dpdv = (dp12 * duv02.x - dp02 * duv12.x) / det;
    }
    if degenerate || dpdu.cross(dpdv).length_squared() == 0.0 || !dpdu.is_finite() || !dpdv.is_finite() {
        let ng = (p2 - p0).cross(p1 - p0).try_normalize()?;
        (dpdu, dpdv) = crate::math::orthonormal_basis(ng);
    }
    let Some(normals) = t.normals else {
        let g = ShadingGeometry {
            n: hit.ng,
            dpdu,
            dpdv,
            dndu: Vec3::ZERO,
            dndv: Vec3::ZERO,
        };
        return Some((g, [dpdu, dpdv]));
    };
    // The vertex normals orient pbrt-v4's shading normal; ours keeps to
    // the side of the winding.
    let n = if (normals[0] + normals[1] + normals[2]).dot(hit.ng) < 0.0 {
        -hit.ns
    } else {
        hit.ns
    };
    let (ss, ts) = match n.cross(dpdu) {
        ts if ts.length_squared() > 0.0 => (ts.cross(n), ts),
        _ => crate::math::orthonormal_basis(n),
    };
    let (dndu, dndv) = if !degenerate {
        let (dn1, dn2) = (normals[0] - normals[2], normals[1] - normals[2]);
        (
            (dn1 * duv12.y - dn2 * duv02.y) / det,
            (dn2 * duv02.x - dn1 * duv12.x) / det,
        )
    } else {
        match (normals[2] - normals[0]).cross(normals[1] - normals[0]).try_normalize() {
            Some(dn) => crate::math::orthonormal_basis(dn),
            None => (Vec3::ZERO, Vec3::ZERO),
        }
    };
    let g = ShadingGeometry {
        n,
        dpdu: ss,
        dpdv: ts,
        dndu,
        dndv,
    };
    Some((g, [dpdu, dpdv]))
}

#[derive(Clone, Copy, Debug)]
struct TriInfo {
    material: u32,
    object: u32,
    normal: Vec3,
    /// The triangle light it is, if any.
    light: Option<u32>,
    /// Its cut-out's index in `Scene::alphas`, or `SOLID`.
    alpha: u32,
}

/// `Scene::object_interfaces` of an object that bounds no medium.
const NO_INTERFACE: u32 = u32::MAX;

/// Surfaces of no material a ray or shadow ray passes through before it
/// gives up (nested or grazing boundaries could otherwise go on forever).
pub const MAX_CROSSINGS: u32 = 256;

/// The scene's media, checked, and the interface of each object id
/// (`Hit::object`) that bounds any, with the table of distinct interfaces.
#[allow(clippy::type_complexity)]
fn media_tables(desc: &SceneDesc, lights: usize) -> Result<(Vec<Medium>, Vec<u32>, Vec<MediumInterface>)> {
    let n = desc.media.len();
    for (name, m) in &desc.media {
        m.check()
            .map_err(|why| Error::Scene(format!("medium \"{name}\": {why}")))?;
    }
    let media: Vec<Medium> = desc.media.iter().map(|(_, m)| m.clone()).collect();
    let valid = |m: Option<u32>| m.is_none_or(|i| (i as usize) < n);
    if !valid(desc.camera_medium) {
        return Err(Error::Scene(format!(
            "the camera is in medium {:?} of {n}",
            desc.camera_medium
        )));
    }
    if desc.boundaries.is_empty() {
        return Ok((media, vec![], vec![]));
    }
    let (nt, ns, nd) = (desc.triangles.len(), desc.spheres.len(), desc.disks.len());
    let mut object = vec![NO_INTERFACE; nt + ns + nd + lights];
    let mut interfaces: Vec<MediumInterface> = vec![];
    for (k, b) in desc.boundaries.iter().enumerate() {
        let mi = b.interface;
        if !valid(mi.inside) || !valid(mi.outside) {
            return Err(Error::Scene(format!(
                "boundary {k} names a medium beyond the {n} there are"
            )));
        }
        let i = match interfaces.iter().position(|&x| x == mi) {
            Some(i) => i,
            None => {
                interfaces.push(mi);
                interfaces.len() - 1
            }
        } as u32;
        let ids = match &b.shapes {
            CutShapes::Triangles(r) if r.end <= nt => r.clone(),
            CutShapes::Sphere(s) if *s < ns => nt + s..nt + s + 1,
            CutShapes::Disk(d) if *d < nd => nt + ns + d..nt + ns + d + 1,
            other => return Err(Error::Scene(format!("boundary {k}: {other:?} is not in the scene"))),
        };
        object[ids].fill(i);
    }
    Ok((media, object, interfaces))
}

/// `TriInfo::alpha` of a triangle that is not cut out.
const SOLID: u32 = u32::MAX;

#[derive(Clone, Debug)]
struct SphereObject {
    sphere: Sphere,
    material: u32,
    light: Option<u32>,
    alpha: Option<u32>,
    /// `SphereDesc::axes`, the identity for the world's.
    axes: glam::Mat3,
}

impl SphereObject {
    /// pbrt-v4's parametrisation about the sphere's own z axis: the texture
    /// coordinates and dp/du at the point of unit normal `n`.
    fn uv_dpdu(&self, n: Vec3) -> (Vec2, Vec3) {
        // The axes are orthonormal: their transpose takes world to object.
        let q = self.axes.transpose() * n;
        let dpdu = Vec3::new(-q.y, q.x, 0.0) * (std::f32::consts::TAU * self.sphere.radius);
        (crate::geometry::sphere_uv(q), self.axes * dpdu)
    }
}

#[derive(Clone, Debug)]
struct DiskObject {
    disk: Disk,
    material: u32,
    light: Option<u32>,
    alpha: Option<u32>,
}

/// Which cut-out, as an index into the alpha textures, each shape of a
/// description has.
struct CutIndex {
    /// Per triangle (`SOLID`: none); empty when no triangle is cut out.
    triangles: Vec<u32>,
    spheres: Vec<Option<u32>>,
    disks: Vec<Option<u32>>,
}

/// The description's cut-outs: their alpha textures and each shape's. A
/// shape named by two cut-outs takes the later.
fn cutout_indices(desc: &SceneDesc) -> Result<(Vec<Texture>, CutIndex)> {
    let mut cut = CutIndex {
        triangles: vec![],
        spheres: vec![None; desc.spheres.len()],
        disks: vec![None; desc.disks.len()],
    };
    let mut alphas = vec![];
    for (k, c) in desc.cutouts.iter().enumerate() {
        let i = alphas.len() as u32;
        let out_of_range = |what: &str, n: usize| Error::Scene(format!("cut-out {k} names {what} of {n}"));
        match &c.shapes {
            CutShapes::Triangles(r) => {
                if r.start > r.end || r.end > desc.triangles.len() {
                    return Err(out_of_range(
                        &format!("triangles {}..{}", r.start, r.end),
                        desc.triangles.len(),
                    ));
                }
                if cut.triangles.is_empty() {
                    cut.triangles = vec![SOLID; desc.triangles.len()];
                }
                cut.triangles[r.clone()].fill(i);
            }
            &CutShapes::Sphere(j) => {
                *cut.spheres
                    .get_mut(j)
                    .ok_or_else(|| out_of_range(&format!("sphere {j}"), desc.spheres.len()))? = Some(i);
            }
            &CutShapes::Disk(j) => {
                *cut.disks
                    .get_mut(j)
                    .ok_or_else(|| out_of_range(&format!("disk {j}"), desc.disks.len()))? = Some(i);
            }
        }
        alphas.push(c.alpha.clone());
    }
    Ok((alphas, cut))
}

/// The primitive a closest-hit query found.
#[derive(Clone, Copy)]
enum Found {
    /// A triangle's slot in BVH order and the hit's barycentrics.
    Triangle(usize, f32, f32),
    /// An index into `Scene::spheres`, then `Scene::disks` (`Scene::shapes`' ids).
    Shape(u32),
}

/// A scene ready to render.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub camera: Camera,
    pub materials: Vec<Material>,
    pub material_names: Vec<String>,
    /// The material of emitters that reflect nothing.
    black_emitter: u32,
    pub lights: Vec<Light>,
    /// Cumulative light powers (largest channel) for choosing one light in
    /// proportion to its power; the last entry is the total.
    light_cdf: Vec<f32>,
    /// Each light's probability of being chosen (from `light_cdf`, once).
    light_pmfs: Vec<f32>,
    /// Indices of the infinite lights.
    infinite_lights: Vec<u32>,
    /// Whether a ray can meet each light, by light index (`light_is_met`).
    lights_met: Vec<bool>,
    /// The light tree, when shadow rays choose their light by it.
    light_tree: Option<LightTree>,
    pub bvh: Bvh,
    /// Runs of triangles that move while the shutter is open (empty for a
    /// still scene), each with a BVH of its own.
    movers: Vec<Mover>,
    /// The BVH over the movers' boxes.
    mover_bvh: BoxBvh,
    /// Triangles in BVH order: the static BVH's, then each mover's.
    triangles: Vec<Triangle>,
    info: Vec<TriInfo>,
    /// Vertex normals and texture coordinates by triangle (BVH order).
    shading: ShadingTable,
    /// dp/du of each triangle (constant over it), computed once: per hit it
    /// was a division and most of the hit's cost on small scenes.
    dpdus: Vec<Vec3>,
    /// Spheres: the description's, then the lights'.
    spheres: Vec<SphereObject>,
    disks: Vec<DiskObject>,
    /// The BVH over spheres, disks and curves: id i < spheres.len() is
    /// sphere i, then come the disks, then the curves (`desc.curves`, not
    /// copied: a scene of hair may hold millions).
    shapes: BoxBvh,
    /// The motion of each sphere and disk (ids as in `shapes`; empty when
    /// none moves).
    shape_motions: Vec<Option<motion::Motion>>,
    /// The cut-outs' alpha textures.
    alphas: Vec<Texture>,
    /// Participating media (`SceneDesc::media`, without their names).
    pub media: Vec<Medium>,
    /// The medium camera rays start in.
    pub camera_medium: Option<u32>,
    /// The interface of each object that bounds media, by `Hit::object`
    /// (an index into `interfaces`, or `NO_INTERFACE`); empty without media.
    object_interfaces: Vec<u32>,
    interfaces: Vec<MediumInterface>,
    /// Triangles dropped for zero area or non-finite coordinates.
    pub dropped_triangles: usize,
    pub desc: SceneDesc,
    pub bvh_build_seconds: f64,
    /// What each material needs of a hit's differential geometry: its
    /// shading geometry (`Material::is_bumped`), its texture footprint
    /// (`Material::needs_footprint`).
    differentials: Vec<(bool, bool)>,
    any_footprints: bool,
    footprint: PixelFootprint,
    /// Whether any material scatters below its surface (`Material::has_subsurface`).
    any_subsurface: bool,
}

/// Triangles moving together: their BVH over them as placed at the start of
/// their motion, where their triangles begin in `Scene::triangles`, and a
/// box holding them wherever they move.
#[derive(Clone, Debug)]
struct Mover {
    bvh: Bvh,
    base: usize,
    motion: motion::Motion,
    bounds: crate::math::Aabb,
}

impl Mover {
    /// The ray in the mover's start placement, with the transformation from
    /// there to the ray's time; `None` when the ray misses the mover's box
    /// before `t_max` (the tree over the boxes hands a few movers over
    /// untested, and carrying a ray costs an interpolation and an inverse).
    fn local_ray(&self, ray: &Ray, t_max: f32) -> Option<(Ray, glam::Mat4)> {
        if !self.bounds.hit_by(ray, t_max) {
            return None;
        }
        Some(carried_back(&self.motion, ray))
    }
}

/// `items` in `order` (`order[k]` is the index of the k-th), consumed.
fn permuted<T: Copy + Send + Sync>(items: Vec<T>, order: &[u32]) -> Vec<T> {
    // Gathers at random from large tables: bound by memory latency, which
    // threads hide together.
    order.par_iter().map(|&i| items[i as usize]).collect()
}

impl Scene {
    pub fn build(desc: SceneDesc) -> Result<Scene> {
        let c = &desc.camera;
        let mut camera = c.camera().ok_or_else(|| Error::Scene(c.problem()))?;
        if !desc.moving.is_empty() || !desc.moving_shapes.is_empty() || desc.camera_motion.is_some() {
            let [open, close] = desc.shutter;
            if !(open.is_finite() && close.is_finite() && open <= close) {
                return Err(Error::Scene(format!(
                    "the shutter opens at {open} and closes at {close}: they must be finite and in order"
                )));
            }
            camera.shutter = Some(desc.shutter);
            camera.motion = desc.camera_motion.clone();
            // Their light samples see the scene at time 0 (`transmittance`).
            if !desc.media.is_empty() || desc.materials.iter().any(|(_, m)| m.has_subsurface()) {
                return Err(Error::Scene(
                    "moving shapes in a scene with participating media or subsurface scattering are not supported"
                        .into(),
                ));
            }
        }
        let nmat = desc.materials.len() as u32;
        // Room for the triangle lights too: one more push past a full vector
        // would double it, hundreds of megabytes on a large scene.
        let capacity = desc.triangles.len()
            + desc
                .lights
                .iter()
                .filter(|l| matches!(l, Light::Triangle { .. }))
                .count();
        let tris = Vec::with_capacity(capacity);
        // The description's index of each triangle kept; what the hits
        // read of them is gathered in the BVH's order once it is built, so
        // that it never exists twice. The lights' is made as they are.
        let objects: Vec<u32> = Vec::with_capacity(desc.triangles.len());
        let mut info = Vec::new();
        let mut light_shading = Vec::new();
        let mut dropped = 0;
        let (alphas, cut) = cutout_indices(&desc)?;
        // Which run of moving triangles each description triangle is in.
        let mut run_of = vec![u32::MAX; desc.triangles.len()];
        for (k, m) in desc.moving.iter().enumerate() {
            let r = &m.triangles;
            if r.start > r.end || r.end > desc.triangles.len() || run_of[r.clone()].iter().any(|&g| g != u32::MAX) {
                return Err(Error::Scene(format!(
                    "moving triangles {}..{}: out of the scene's {} triangles or overlapping another run",
                    r.start,
                    r.end,
                    desc.triangles.len()
                )));
            }
            if r.clone().any(|i| cut.triangles.get(i).is_some_and(|&a| a != SOLID)) {
                return Err(Error::Scene(format!(
                    "moving triangles {}..{}: an alpha cut-out on a moving shape is not supported",
                    r.start, r.end
                )));
            }
            run_of[r.clone()].fill(k as u32);
        }
        let nt = desc.triangles.len();
        if let Some((i, m)) = (0..nt)
            .filter_map(|i| desc.triangles.material(i).map(|m| (i, m)))
            .find(|&(_, m)| m >= nmat)
        {
            return Err(Error::Scene(format!("triangle {i} names material {m} of {nmat}")));
        }
        // Zero-area and non-finite triangles cannot be hit or shaded. The
        // rest are made on every core, in their order.
        let mut made = (tris, objects);
        made.par_extend((0..nt).into_par_iter().filter_map(|i| {
            let v = desc.triangles.vertices(i)?;
            let tri = Triangle::new(v[0], v[1], v[2]);
            let n = tri.normal_raw();
            let finite = v.iter().all(|p| p.is_finite());
            (finite && n.is_finite() && n.length_squared() != 0.0).then_some((tri, i as u32))
        }));
        let (mut tris, objects) = made;
        dropped += nt - objects.len();
        // The run of each triangle kept (static ones and lights: none).
        let mut runs: Vec<u32> = objects.iter().map(|&i| run_of[i as usize]).collect();
        let mut lights = desc.lights.clone();
        let mut spheres: Vec<SphereObject> = desc
            .spheres
            .iter()
            .enumerate()
            .map(|(i, s)| SphereObject {
                sphere: s.sphere,
                material: s.material,
                light: None,
                alpha: cut.spheres.get(i).copied().flatten(),
                axes: s.axes.unwrap_or(glam::Mat3::IDENTITY),
            })
            .collect();
        for s in &spheres {
            if s.material >= nmat {
                return Err(Error::Scene(format!(
                    "a sphere names material {} of {nmat}",
                    s.material
                )));
            }
            if s.sphere.radius <= 0.0 || !s.sphere.centre.is_finite() || !s.sphere.radius.is_finite() {
                return Err(Error::Scene(format!(
                    "a sphere at {} of radius {}: the radius must be finite and > 0, the centre finite",
                    s.sphere.centre, s.sphere.radius
                )));
            }
        }
        let mut disks = desc
            .disks
            .iter()
            .enumerate()
            .map(|(i, d)| {
                if d.material >= nmat {
                    return Err(Error::Scene(format!(
                        "disk {i} names material {} of {nmat}",
                        d.material
                    )));
                }
                let disk = d.disk().map_err(|m| Error::Scene(format!("disk {i}: {m}")))?;
                Ok(DiskObject {
                    disk,
                    material: d.material,
                    light: None,
                    alpha: cut.disks.get(i).copied().flatten(),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let black = nmat;
        let mut materials: Vec<Material> = desc.materials.iter().map(|(_, m)| m.clone()).collect();
        let mut names: Vec<String> = desc.materials.iter().map(|(n, _)| n.clone()).collect();
        materials.push(Material::diffuse(0.0, 0.0, 0.0));
        names.push("<light>".into());
        let invisible = |i: usize| desc.invisible_lights.get(i).copied().unwrap_or(false);
        let lights_met = (0..lights.len())
            .map(|i| !lights[i].is_delta() && !invisible(i))
            .collect();
        for (i, l) in lights.iter_mut().enumerate() {
            l.check(1.0).map_err(|m| Error::Scene(format!("light {i}: {m}")))?;
            if invisible(i) {
                continue;
            }
            // An emitter reflects by its material, or nothing (`black`), and
            // blocks light like any surface.
            let reflecting = desc.light_surfaces.get(i).and_then(|s| s.as_ref());
            let surface = match reflecting.map(|s| s.material) {
                Some(m) if m >= nmat => {
                    return Err(Error::Scene(format!("light {i} names material {m} of {nmat}")));
                }
                Some(m) => m,
                None => black,
            };
            match l {
                Light::Sphere { sphere, image, .. } => {
                    spheres.push(SphereObject {
                        sphere: *sphere,
                        material: surface,
                        light: Some(i as u32),
                        alpha: None,
                        // Hits read an emission image, and textures, in the
                        // sphere's frame.
                        axes: image
                            .as_ref()
                            .map(|t| t.axes)
                            .or(reflecting.and_then(|s| s.axes))
                            .unwrap_or(glam::Mat3::IDENTITY),
                    });
                }
                Light::Triangle { vertices: v, image, .. } => {
                    let tri = Triangle::new(v[0], v[1], v[2]);
                    let n = tri.normal_raw();
                    if !v.iter().all(|p| p.is_finite()) || !n.is_finite() || n.length_squared() == 0.0 {
                        return Err(Error::Scene(format!("light {i}: a triangle of zero area")));
                    }
                    tris.push(tri);
                    info.push(TriInfo {
                        material: surface,
                        object: (desc.triangles.len() + desc.spheres.len() + desc.disks.len() + i) as u32,
                        normal: n.normalize(),
                        light: Some(i as u32),
                        alpha: SOLID,
                    });
                    // Hits read an emission image at these coordinates,
                    // which are the surface's own where it has any.
                    let surface_uvs = texture_uvs(reflecting.and_then(|s| s.uvs));
                    light_shading.push((
                        shading_normals(reflecting.and_then(|s| s.normals)),
                        image.as_ref().map(|t| t.uv).or(surface_uvs),
                    ));
                }
                Light::Disk { disk, .. } => disks.push(DiskObject {
                    disk: *disk,
                    material: surface,
                    light: Some(i as u32),
                    alpha: None,
                }),
                // Point, spot, goniometric and distant lights have no
                // surface; infinite lights are seen by the rays that escape
                // (`infinite_lights`).
                Light::Point { .. }
                | Light::Spot { .. }
                | Light::Goniometric { .. }
                | Light::Projection { .. }
                | Light::Distant { .. }
                | Light::Infinite { .. } => {}
            }
        }
        let infinite_lights = (0..lights.len() as u32)
            .filter(|&i| matches!(lights[i as usize], Light::Infinite { .. }))
            .collect();

        if tris.len() > Bvh::MAX_TRIANGLES {
            return Err(Error::Scene(format!(
                "{} triangles; the BVH holds at most {}",
                tris.len(),
                Bvh::MAX_TRIANGLES
            )));
        }
        runs.resize(tris.len(), u32::MAX);
        let start = std::time::Instant::now();
        // The static triangles' BVH, then each moving run's over its
        // triangles as placed at its start; the triangles are stored in that
        // order, each run's after the static ones.
        let (bvh, mut order) = if desc.moving.is_empty() {
            let bvh = Bvh::build(&tris);
            let order = bvh.order.clone();
            (bvh, order)
        } else {
            let statics: Vec<u32> = (0..tris.len() as u32)
                .filter(|&k| runs[k as usize] == u32::MAX)
                .collect();
            let bvh = Bvh::build(&statics.iter().map(|&k| tris[k as usize]).collect::<Vec<_>>());
            let order = bvh.order.iter().map(|&j| statics[j as usize]).collect();
            (bvh, order)
        };
        let mut members = vec![Vec::new(); desc.moving.len()];
        for (k, &run) in runs.iter().enumerate() {
            if let Some(m) = members.get_mut(run as usize) {
                m.push(k as u32);
            }
        }
        let mut movers = Vec::with_capacity(desc.moving.len());
        for (m, members) in desc.moving.iter().zip(members).filter(|(_, ms)| !ms.is_empty()) {
            let run_bvh = Bvh::build(&members.iter().map(|&j| tris[j as usize]).collect::<Vec<_>>());
            let base = order.len();
            order.extend(run_bvh.order.iter().map(|&j| members[j as usize]));
            let b = run_bvh.bounds();
            let (min, max) = m.motion.bounds(b.min, b.max);
            if !(min.is_finite() && max.is_finite()) {
                return Err(Error::Scene(format!(
                    "moving triangles {}..{}: their motion takes them beyond finite coordinates",
                    m.triangles.start, m.triangles.end
                )));
            }
            movers.push(Mover {
                bvh: run_bvh,
                base,
                motion: m.motion.clone(),
                bounds: crate::math::Aabb { min, max },
            });
        }
        if movers.len() > BoxBvh::MAX_BOXES {
            return Err(Error::Scene(format!(
                "{} moving meshes; the BVH over them holds at most {}",
                movers.len(),
                BoxBvh::MAX_BOXES
            )));
        }
        let mover_bvh = BoxBvh::build(&movers.iter().map(|m| m.bounds).collect::<Vec<_>>());
        let bvh_build_seconds = start.elapsed().as_secs_f64();
        // The triangles, the largest table, put in BVH order while the others
        // are not yet made; those are gathered from the description in that
        // order.
        let triangles: Vec<Triangle> = permuted(tris, &order);
        let kept = objects.len();
        let info = (order.as_slice(), triangles.as_slice())
            .into_par_iter()
            .map(|(&j, tri)| match objects.get(j as usize) {
                Some(&i) => TriInfo {
                    material: desc.triangles.material(i as usize).unwrap_or_default(),
                    object: i,
                    normal: tri.normal_raw().normalize(),
                    light: None,
                    alpha: cut.triangles.get(i as usize).copied().unwrap_or(SOLID),
                },
                None => info[j as usize - kept],
            })
            .collect();
        // What hits read of vertex normals and texture coordinates: each
        // triangle's corners in the description's shared tables.
        let shading = ShadingTable::gather(
            &desc.triangles,
            order.len(),
            |k| match objects.get(order[k] as usize) {
                Some(&i) => ShadingSource::Listed(i as usize),
                None => ShadingSource::Own(order[k] as usize - kept),
            },
            &light_shading,
            |ns| shading_normals(Some(ns)).is_some(),
            |uv| texture_uvs(Some(uv)).is_some(),
        );
        drop(objects);
        for (i, c) in desc.curves.iter().enumerate() {
            if c.material >= nmat {
                return Err(Error::Scene(format!(
                    "curve {i} names material {} of {nmat}",
                    c.material
                )));
            }
            if !c.curve.is_valid() {
                return Err(Error::Scene(format!(
                    "curve {i}: its control points must be finite and its widths finite and > 0"
                )));
            }
        }
        let shape_motions = shape_motions(&desc, &spheres, &disks)?;
        let shapes = shape_bvh(&spheres, &disks, &desc.curves, &shape_motions)?;
        let (media, object_interfaces, interfaces) = media_tables(&desc, lights.len())?;
        let footprint = camera.pixel_footprint(desc.texture_spp);
        let mut scene = Scene {
            name: desc.name.clone(),
            camera,
            materials,
            material_names: names,
            black_emitter: black,
            lights,
            light_cdf: vec![],
            light_pmfs: vec![],
            infinite_lights,
            lights_met,
            light_tree: None,
            bvh,
            movers,
            mover_bvh,
            triangles,
            info,
            shading,
            dpdus: vec![],
            spheres,
            disks,
            shapes,
            shape_motions,
            alphas,
            media,
            camera_medium: desc.camera_medium,
            object_interfaces,
            interfaces,
            dropped_triangles: dropped,
            differentials: vec![],
            any_footprints: false,
            footprint,
            any_subsurface: false,
            desc,
            bvh_build_seconds,
        };
        scene.differentials = scene
            .materials
            .iter()
            .map(|m| (m.is_bumped(), m.needs_footprint()))
            .collect();
        scene.any_footprints = scene.differentials.iter().any(|&(_, f)| f);
        scene.any_subsurface = scene.materials.iter().any(Material::has_subsurface);
        // Lights at infinity reach the scene through its bounding sphere. A
        // scene of no surfaces (a medium around the camera under a sky) has
        // none: a unit sphere stands in, so that such lights have a power
        // to be chosen by (pbrt-v4 samples them apart from the others).
        let bounds = scene.bounds();
        let world = if bounds.is_empty() {
            Sphere {
                centre: Vec3::ZERO,
                radius: 1.0,
            }
        } else {
            Sphere {
                centre: bounds.centre(),
                radius: 0.5 * bounds.extent().length(),
            }
        };
        scene.lights.iter_mut().for_each(|l| l.set_scene_bounds(world));
        // Their power depends on it: lights are chosen (by power, or through
        // the light tree, which bounds their power too) only now.
        scene.light_cdf = scene
            .lights
            .iter()
            .scan(0.0f32, |acc, l| {
                *acc += l.power().max_element().max(0.0);
                Some(*acc)
            })
            .collect();
        scene.light_pmfs = (0..scene.light_cdf.len()).map(|i| scene.pmf_from_cdf(i)).collect();
        scene.light_tree = light_tree(&scene.lights, scene.desc.light_sampler);
        scene.dpdus = (0..scene.triangles.len())
            .into_par_iter()
            .map(|i| scene.triangle_dpdu(i))
            .collect();
        Ok(scene)
    }

    /// Indices of the lights that shine on rays leaving the scene (whose
    /// `le_escaped` is not zero): the infinite lights.
    pub fn infinite_lights(&self) -> &[u32] {
        &self.infinite_lights
    }

    /// Chooses a light in proportion to its power: its index, the
    /// probability of that choice, and `u` rescaled to [0, 1) within the
    /// light's share of the unit interval. The rescaled value is uniform and
    /// independent of the choice, so it can serve as the first coordinate of
    /// the point sampled on the light (as Mitsuba's `sample_emitter` reuses
    /// it): one 2D sample then covers all the lights together, and a
    /// stratified set of them stays stratified over the lights' union (the
    /// two triangles of a quad light, say) instead of splitting into two
    /// unrelated sets.
    pub fn pick_light(&self, u: f32) -> Option<(usize, f32, f32)> {
        let total = *self.light_cdf.last()?;
        if total <= 0.0 || !total.is_finite() {
            return None;
        }
        let target = u * total;
        // The CDF rises, so the entries at or below the target are a prefix:
        // counting them is the binary search's answer. For a few lights the
        // count runs without branches, where the search's, on a random
        // target, are mispredicted half the time.
        let below = if self.light_cdf.len() <= 8 {
            self.light_cdf.iter().map(|&c| (c <= target) as usize).sum()
        } else {
            self.light_cdf.partition_point(|&c| c <= target)
        };
        let i = below.min(self.light_cdf.len() - 1);
        // Skip lights of no power that share the cumulative value.
        let i = (i..self.light_cdf.len()).find(|&j| self.light_pmfs[j] > 0.0)?;
        let before = if i == 0 { 0.0 } else { self.light_cdf[i - 1] };
        let rest = ((target - before) / (self.light_cdf[i] - before)).clamp(0.0, crate::sampling::ONE_MINUS_EPS);
        Some((i, self.light_pmfs[i], rest))
    }

    /// Whether a ray can meet light `i`, so that a BSDF sample may find it
    /// too: not a delta light, nor an invisible area light. Samples of the
    /// others take no MIS weight, being their only way in.
    pub fn light_is_met(&self, i: usize) -> bool {
        self.lights_met[i]
    }

    /// The probability that `pick_light` chooses light `i`.
    pub fn light_pmf(&self, i: usize) -> f32 {
        self.light_pmfs[i]
    }

    /// How shadow rays choose their light.
    pub fn light_sampler(&self) -> LightSamplerKind {
        self.desc.light_sampler
    }

    /// Whether shadow rays choose their light through the light tree: asked
    /// for, and with more than one leaf or lights apart from it to choose
    /// among (a tree of one leaf would choose by power).
    pub fn chooses_by_tree(&self) -> bool {
        self.light_tree.is_some()
    }

    /// Chooses the light of a shadow ray from `ctx` with `u`: its index, the
    /// probability of the choice, and the 2D sample for the point on it.
    /// By power or uniformly, as `pick_light` (`u.point.x` replaced by the
    /// choice's number rescaled); by the light tree, with `u.choice` alone.
    /// `pick_light` and `light_pmf` stay by power whatever the sampler, for
    /// bdpt's light subpaths, as pbrt-v4's BDPT chooses.
    #[inline]
    pub fn choose_light(&self, ctx: &LightContext, u: LightSampleU) -> Option<(usize, f32, Vec2)> {
        if let Some(tree) = &self.light_tree {
            let (i, pmf) = tree.pick(ctx, u.choice)?;
            return Some((i, pmf, u.point));
        }
        let (i, pmf, rest) = match self.desc.light_sampler {
            LightSamplerKind::Uniform if !self.lights.is_empty() => {
                let n = self.lights.len();
                let x = u.choice * n as f32;
                let i = (x as usize).min(n - 1);
                let rest = (x - i as f32).clamp(0.0, crate::sampling::ONE_MINUS_EPS);
                (i, 1.0 / n as f32, rest)
            }
            _ => self.pick_light(u.choice)?,
        };
        Some((i, pmf, Vec2::new(rest, u.point.y)))
    }

    /// The probability that `choose_light` chooses light `i` from `ctx`.
    #[inline]
    pub fn light_pmf_at(&self, ctx: &LightContext, i: usize) -> f32 {
        match (&self.light_tree, self.desc.light_sampler) {
            (Some(tree), _) => tree.pmf(ctx, i),
            (None, LightSamplerKind::Uniform) => 1.0 / self.lights.len() as f32,
            (None, _) => self.light_pmfs[i],
        }
    }

    fn pmf_from_cdf(&self, i: usize) -> f32 {
        let Some(&total) = self.light_cdf.last() else {
            return 0.0;
        };
        let before = if i == 0 { 0.0 } else { self.light_cdf[i - 1] };
        if total > 0.0 {
            (self.light_cdf[i] - before) / total
        } else {
            0.0
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Triangles in BVH order (for benchmarks and statistics).
    pub fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    /// Closest hit along the ray in (t_min, t_max).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        // Scenes of still, solid triangles alone build the hit in the
        // caller: returned from a call, the record comes back through memory,
        // written field by field and read back whole, which stalls the
        // caller until the stores reach the cache.
        if self.only_still_triangles() {
            let (slot, h) = self.bvh.intersect(ray, t_min, t_max)?;
            let tri = &self.triangles[slot as usize];
            let p = tri.v0 + tri.e1 * h.u + tri.e2 * h.v;
            let mut hit = self.triangle_hit::<false>(slot as usize, h.u, h.v, h.t, p);
            hit.time = ray.time;
            return Some(hit);
        }
        self.intersect_any(ray, t_min, t_max)
    }

    /// [`Scene::intersect`] for paths that read of a hit only its point,
    /// normals, material and light (and, on a light, its texture
    /// coordinates): in scenes of still, solid triangles alone, the rest of
    /// the record is left out (zero).
    #[inline(always)]
    pub fn intersect_bare(&self, ray: &Ray) -> Option<Hit> {
        if !self.only_still_triangles() {
            return self.intersect_any(ray, 0.0, f32::INFINITY);
        }
        let (slot, h) = self.bvh.intersect(ray, 0.0, f32::INFINITY)?;
        Some(self.bare_hit(slot, &h, ray))
    }

    /// [`Scene::intersect_bare`]'s record of a hit `h` on triangle `slot`.
    #[inline(always)]
    pub fn bare_hit(&self, slot: u32, h: &TriHit, ray: &Ray) -> Hit {
        let tri = &self.triangles[slot as usize];
        let p = tri.v0 + tri.e1 * h.u + tri.e2 * h.v;
        let mut hit = self.triangle_hit::<true>(slot as usize, h.u, h.v, h.t, p);
        hit.time = ray.time;
        hit
    }

    /// Whether the scene holds nothing but still triangles without cut-outs.
    #[inline(always)]
    pub fn only_still_triangles(&self) -> bool {
        self.movers.is_empty() && self.alphas.is_empty() && self.shapes.is_empty()
    }

    /// [`Scene::intersect`] in any scene.
    #[inline(never)]
    fn intersect_any(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let mut hit = self.intersect_still(ray, t_min, t_max);
        if !self.movers.is_empty() {
            hit = self.intersect_movers(ray, t_min, hit.map_or(t_max, |h| h.t)).or(hit);
        }
        // Also where only the camera moves: light tracing joins a hit to
        // the camera where it is at the hit's time.
        if let Some(h) = &mut hit {
            h.time = ray.time;
        }
        hit
    }

    /// The closest hit on a moving triangle before `t_max`, placed where the
    /// triangle is at the ray's time.
    #[inline(never)]
    fn intersect_movers(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        // The tree offers movers with t_max shrinking: each hit found is
        // closer than the last.
        let mut best = None;
        let (_, best_t) = self.mover_bvh.intersect(ray, t_min, t_max, |id, t_max| {
            let m = &self.movers[id as usize];
            let (local, to_world) = m.local_ray(ray, t_max)?;
            let (slot, h) = m.bvh.intersect(&local, t_min, t_max)?;
            best = Some((m.base + slot as usize, h.u, h.v, to_world));
            Some(h.t)
        })?;
        let (slot, u, v, to_world) = best?;
        let tri = &self.triangles[slot];
        let h = self.triangle_hit::<false>(slot, u, v, best_t, tri.v0 + tri.e1 * u + tri.e2 * v);
        Some(placed_hit(h, to_world))
    }

    /// Whether a moving triangle blocks the ray before `t_max`.
    #[inline(never)]
    fn movers_block(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.mover_bvh.occluded(ray, t_min, t_max, |id| {
            let m = &self.movers[id as usize];
            m.local_ray(ray, t_max)
                .is_some_and(|(local, _)| m.bvh.occluded(&local, t_min, t_max))
        })
    }

    /// The motion of object `object` (a `Hit::object`), if it moves.
    fn motion_of(&self, object: u32) -> Option<&motion::Motion> {
        self.moving_run(object).map(|m| &m.motion)
    }

    /// Where moving triangle `object` was at its motion's start, seen from
    /// `time`; `None` when it does not move. Photons traced over the
    /// shutter are kept there, so that the light a moving shape carries
    /// with it gathers where the shape is.
    #[inline]
    pub fn rest_frame(&self, object: u32, time: f32) -> Option<RestFrame> {
        let (objects, motion) = self.moving_object(object)?;
        let from_rest = motion.relative(time);
        Some(RestFrame {
            objects,
            to_rest: from_rest.inverse(),
            from_rest,
        })
    }

    /// The objects moving together with object `object` (a `Hit::object`:
    /// its run of triangles, or the sphere or disk alone) and their motion;
    /// `None` when it does not move.
    #[inline]
    pub fn moving_object(&self, object: u32) -> Option<(std::ops::Range<u32>, &motion::Motion)> {
        if let Some(m) = self.moving_run(object) {
            return Some((m.triangles.start as u32..m.triangles.end as u32, &m.motion));
        }
        if self.shape_motions.is_empty() {
            return None;
        }
        let k = (object as usize).checked_sub(self.desc.triangles.len())?;
        let id = match k.checked_sub(self.desc.spheres.len()) {
            None => k,
            Some(j) if j < self.desc.disks.len() => self.spheres.len() + j,
            Some(_) => return None,
        };
        let m = self.shape_motions.get(id)?.as_ref()?;
        Some((object..object + 1, m))
    }

    /// The moving run of triangles object `object` (a `Hit::object`) is in.
    #[inline]
    pub fn moving_run(&self, object: u32) -> Option<&MovingTriangles> {
        if self.movers.is_empty() {
            return None;
        }
        let i = object as usize;
        self.desc.moving.iter().find(|m| m.triangles.contains(&i))
    }

    /// The closest hit on what does not move.
    #[inline(always)]
    fn intersect_still(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let mut best_t = t_max;
        let mut best = None;
        let triangle = if self.alphas.is_empty() {
            self.bvh.intersect(ray, t_min, t_max)
        } else {
            self.bvh
                .intersect_where(ray, t_min, t_max, |slot, h| self.triangle_solid(slot, h, ray))
        };
        if let Some((slot, h)) = triangle {
            best_t = h.t;
            best = Some(Found::Triangle(slot as usize, h.u, h.v));
        }
        let shape = if self.alphas.is_empty() {
            self.shapes.intersect(ray, t_min, best_t, |id, t_max| {
                self.shape_hit::<false>(id, ray, t_min, t_max)
            })
        } else {
            self.shapes.intersect(ray, t_min, best_t, |id, t_max| {
                self.shape_hit::<true>(id, ray, t_min, t_max)
            })
        };
        if let Some((id, t)) = shape {
            best_t = t;
            best = Some(Found::Shape(id));
        }
        // Each hit point is put on its surface (from a triangle's
        // barycentrics, onto a sphere or a disk's plane) rather than taken
        // along the ray: accurate to the surface's own rounding however far
        // the ray came, so that rays leaving it need only a small offset
        // (`offset_origin`) and still meet a surface a hair's breadth away.
        let idx = match best? {
            Found::Triangle(slot, u, v) => {
                let tri = &self.triangles[slot];
                let p = tri.v0 + tri.e1 * u + tri.e2 * v;
                return Some(self.triangle_hit::<false>(slot, u, v, best_t, p));
            }
            Found::Shape(id) => id as usize,
        };
        if let Some(Some(m)) = self.shape_motions.get(idx) {
            let (local, to_world) = carried_back(m, ray);
            return Some(placed_hit(self.shape_record(idx, &local, t_min, best_t), to_world));
        }
        Some(self.shape_record(idx, ray, t_min, best_t))
    }

    /// The hit record of sphere, disk or curve `idx` (ids as `shapes`'s),
    /// met by `ray` at `best_t`.
    fn shape_record(&self, idx: usize, ray: &Ray, t_min: f32, best_t: f32) -> Hit {
        let p = ray.at(best_t);
        let before = self.desc.triangles.len() + self.desc.spheres.len() + self.desc.disks.len();
        if let Some(s) = self.spheres.get(idx) {
            let c = s.sphere.centre;
            let p = c + (p - c) * (s.sphere.radius / (p - c).length());
            let n = (p - c) / s.sphere.radius;
            let (uv, dpdu) = s.uv_dpdu(n);
            return Hit {
                t: best_t,
                p,
                ng: n,
                ns: n,
                uv,
                dpdu,
                material: s.material,
                object: match s.light {
                    Some(l) => (before + l as usize) as u32,
                    None => (self.desc.triangles.len() + idx) as u32,
                },
                kind: if s.light.is_some() {
                    PrimKind::Light
                } else {
                    PrimKind::Sphere
                },
                light: s.light,
                time: 0.0,
            };
        }
        let j = idx - self.spheres.len();
        if j >= self.disks.len() {
            return self.curve_hit(j - self.disks.len(), ray, t_min, best_t);
        }
        let d = &self.disks[j];
        let p = p - d.disk.normal * (p - d.disk.centre).dot(d.disk.normal);
        let (uv, dpdu) = d.disk.uv_dpdu(p);
        Hit {
            t: best_t,
            p,
            ng: d.disk.normal,
            ns: d.disk.normal,
            uv,
            dpdu,
            material: d.material,
            object: match d.light {
                Some(l) => (before + l as usize) as u32,
                None => (self.desc.triangles.len() + self.desc.spheres.len() + j) as u32,
            },
            kind: if d.light.is_some() {
                PrimKind::Light
            } else {
                PrimKind::Disk
            },
            light: d.light,
            time: 0.0,
        }
    }

    /// The hit record of curve `k`, met by `ray` at `t` (its intersection
    /// again, now with what shading needs).
    #[inline(never)]
    fn curve_hit(&self, k: usize, ray: &Ray, t_min: f32, t: f32) -> Hit {
        let c = &self.desc.curves[k];
        let h = c.curve.intersect(ray, t_min, t).unwrap_or(CurveHit {
            t,
            u: c.curve.u[0],
            v: 0.5,
            dpdu: c.curve.cp[3] - c.curve.cp[0],
            ng: -ray.d.normalize(),
            ns: -ray.d.normalize(),
        });
        Hit {
            t: h.t,
            p: ray.at(h.t),
            ng: h.ng,
            ns: h.ns,
            uv: Vec2::new(h.u, h.v),
            dpdu: h.dpdu,
            material: c.material,
            object: (self.desc.triangles.len()
                + self.desc.spheres.len()
                + self.desc.disks.len()
                + self.lights.len()
                + k) as u32,
            kind: PrimKind::Curve,
            light: None,
            time: 0.0,
        }
    }

    /// Shape `id` of `shapes` (a sphere, a disk, then a curve): its hit in (t_min,
    /// t_max), passing through where it is cut out if `CUT` (when the scene
    /// has cut-outs: without, the test is the plain one it always was).
    #[inline(always)]
    fn shape_hit<const CUT: bool>(&self, id: u32, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        if let Some(Some(m)) = self.shape_motions.get(id as usize) {
            // Met in its start placement by the ray carried back from its
            // time (the same t along both: the map is affine).
            let (local, _) = carried_back(m, ray);
            return self.shape_hit_placed::<CUT>(id, &local, t_min, t_max);
        }
        self.shape_hit_placed::<CUT>(id, ray, t_min, t_max)
    }

    #[inline(always)]
    fn shape_hit_placed<const CUT: bool>(&self, id: u32, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        match self.spheres.get(id as usize) {
            Some(s) => {
                let t = s.sphere.intersect(ray, t_min, t_max)?;
                match s.alpha {
                    Some(a) if CUT => self.cut_sphere_hit(s, a, id, ray, t, t_max),
                    _ => Some(t),
                }
            }
            None => {
                let j = id as usize - self.spheres.len();
                let Some(d) = self.disks.get(j) else {
                    return Some(
                        self.desc.curves[j - self.disks.len()]
                            .curve
                            .intersect(ray, t_min, t_max)?
                            .t,
                    );
                };
                let t = d.disk.intersect(ray, t_min, t_max)?;
                match d.alpha {
                    None => Some(t),
                    Some(_) if !CUT => Some(t),
                    Some(a) => {
                        let p = ray.at(t);
                        self.solid(a, d.disk.uv_dpdu(p).0, p, ray, [id, 3]).then_some(t)
                    }
                }
            }
        }
    }

    /// The hit on sphere `s` (shape `id`, under cut-out `alpha`) whose near
    /// side the ray meets at `t`: there, or through it on the far side, or
    /// none. Kept out of line: the uncut spheres' test stays small.
    #[inline(never)]
    fn cut_sphere_hit(&self, s: &SphereObject, alpha: u32, id: u32, ray: &Ray, t: f32, t_max: f32) -> Option<f32> {
        let solid = |t: f32, side: u32| {
            let p = ray.at(t);
            let (uv, _) = s.uv_dpdu((p - s.sphere.centre) / s.sphere.radius);
            self.solid(alpha, uv, p, ray, [id, 1 + side])
        };
        if solid(t, 0) {
            return Some(t);
        }
        let far = s.sphere.intersect(ray, t, t_max)?;
        solid(far, 1).then_some(far)
    }

    /// Whether a hit on triangle `slot` counts: it is not cut out there.
    fn triangle_solid(&self, slot: u32, h: &TriHit, ray: &Ray) -> bool {
        let a = self.info[slot as usize].alpha;
        a == SOLID
            || self.solid(
                a,
                self.triangle_uv(slot as usize, h.u, h.v),
                ray.at(h.t),
                ray,
                [slot, 0],
            )
    }

    /// pbrt-v4's stochastic alpha test: whether `ray`'s hit at `p` (texture
    /// coordinates `uv`) on a primitive (`prim`: its index and kind, so that
    /// two cut-out surfaces along one ray decide independently) under
    /// cut-out `alpha` counts. The mask is looked up without the surface's
    /// normal, which the test does not compute (a `directionmix` in it
    /// shows its second texture).
    #[inline(never)]
    fn solid(&self, alpha: u32, uv: Vec2, p: Vec3, ray: &Ray, prim: [u32; 2]) -> bool {
        let a = self.alphas[alpha as usize].evaluate_scalar(&TexCoord::at(uv, p, Vec3::ZERO));
        if a >= 1.0 {
            return true;
        }
        // Not there at all at 0, and where the texture gives NaN.
        if a.is_nan() || a <= 0.0 {
            return false;
        }
        let (o, d) = (ray.o, ray.d);
        let [i, kind] = prim.map(f32::from_bits);
        hash_unit(&[o.x, o.y, o.z, d.x, d.y, d.z, i, kind]) <= a
    }

    /// Whether a triangle (not cut out where the ray meets it) blocks the ray.
    fn triangles_block(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        if self.alphas.is_empty() {
            self.bvh.occluded(ray, t_min, t_max)
        } else {
            self.bvh
                .occluded_where(ray, t_min, t_max, |slot, h| self.triangle_solid(slot, h, ray))
        }
    }

    /// The light shape `id` of `shapes` emits for, if any.
    #[inline(always)]
    fn shape_light(&self, id: u32) -> Option<u32> {
        match self.spheres.get(id as usize) {
            Some(s) => s.light,
            None => self.disks.get(id as usize - self.spheres.len()).and_then(|d| d.light),
        }
    }

    /// What the hit's material needs to build its BSDF: the hit's surface
    /// point, with the shading geometry a bump map needs when the material
    /// has one.
    pub fn surface(&self, hit: &Hit) -> SurfacePoint {
        self.surface_seen(hit, None)
    }

    /// [`Scene::surface`] of a hit found by a ray with differentials (a
    /// camera ray's, or one's carried through specular bounces): its
    /// texture footprint is where they meet the surface, where other hits
    /// take the camera's approximation at their distance (as pbrt-v4 does).
    pub fn surface_seen(&self, hit: &Hit, along: Option<&Differentials>) -> SurfacePoint {
        let mut sp = hit.surface();
        let (shaded, footprinted) = self.differentials[hit.material as usize];
        if shaded || footprinted {
            if let Some((g, [dpdu, dpdv])) = self.shading_geometry(hit) {
                sp.shading = shaded.then_some(g);
                if footprinted {
                    let (dpdx, dpdy) = self.footprint.dp_dxy(&self.camera, hit.p, hit.ng, along);
                    sp.footprint = uv_footprint(dpdu, dpdv, dpdx, dpdy);
                }
            }
        }
        sp
    }

    /// Whether any material looks up images or bumps: only then do rays
    /// carry differentials.
    pub fn has_footprints(&self) -> bool {
        self.any_footprints
    }

    /// The differentials of the camera ray that found `hit` (`None` when no
    /// material needs them).
    pub fn camera_differentials(&self, hit: &Hit) -> Option<Differentials> {
        if !self.has_footprints() {
            return None;
        }
        self.footprint.camera_differentials(&self.camera, hit.p)
    }

    /// The differentials of the ray a specular bounce sends on from `hit`,
    /// which a ray with differentials `d` reached from direction `wo`, into
    /// `wi` (a reflection, or a refraction into relative index `eta`), about
    /// the shading normal `n`: pbrt-v4's `SurfaceInteraction::SpawnRay`,
    /// the change of the reflected or refracted direction with the incoming
    /// one and with the normal's turn across the footprint. One departure:
    /// a refracted direction changes with the incoming one by 1 / eta, as
    /// Snell's law differentiated gives, where pbrt-v4 multiplies by eta.
    pub fn specular_differentials(
        &self,
        hit: &Hit,
        d: &Differentials,
        (wo, wi): (Vec3, Vec3),
        transmission: bool,
        eta: f32,
        n: Vec3,
    ) -> Option<Differentials> {
        let (dpdx, dpdy) = d.on_plane(hit.p, hit.ng)?;
        // The shading normal's turn across the footprint.
        let (dndx, dndy) = match self.shading_geometry(hit) {
            Some((g, [dpdu, dpdv])) => {
                let f = uv_footprint(dpdu, dpdv, dpdx, dpdy);
                let s = if g.n.dot(n) < 0.0 { -1.0 } else { 1.0 };
                (
                    (g.dndu * f.dudx + g.dndv * f.dvdx) * s,
                    (g.dndu * f.dudy + g.dndv * f.dvdy) * s,
                )
            }
            None => (Vec3::ZERO, Vec3::ZERO),
        };
        let (dwodx, dwody) = (-d.rx.d - wo, -d.ry.d - wo);
        let bent = |dwo: Vec3, dn: Vec3| {
            if !transmission {
                let dcos = dwo.dot(n) + wo.dot(dn);
                return wi - dwo + (dn * wo.dot(n) + n * dcos) * 2.0;
            }
            // Snell's law, wi = -wo / eta + mu n about the normal on wo's side.
            let (n, dn) = if wo.dot(n) < 0.0 { (-n, -dn) } else { (n, dn) };
            let dcos = dwo.dot(n) + wo.dot(dn);
            let mu = wo.dot(n) / eta - wi.dot(n).abs();
            let dmu = dcos * (1.0 / eta + wo.dot(n) / (eta * eta * wi.dot(n)));
            wi - dwo / eta + dn * mu + n * dmu
        };
        let out = Differentials {
            rx: Ray::new(hit.p + dpdx, bent(dwodx, dndx)),
            ry: Ray::new(hit.p + dpdy, bent(dwody, dndy)),
        };
        // pbrt-v4's guard against differentials gone wild.
        let sane = |r: &Ray| r.d.length_squared() <= 1e16 && r.o.length_squared() <= 1e16 && r.d.is_finite();
        (sane(&out.rx) && sane(&out.ry)).then_some(out)
    }

    /// pbrt-v4's shading geometry at a hit on a triangle, sphere or disk
    /// (`None` on emitters and where the parametrisation degenerates), and
    /// the surface's own dp/du and dp/dv.
    fn shading_geometry(&self, hit: &Hit) -> Option<(ShadingGeometry, [Vec3; 2])> {
        let tris = self.desc.triangles.len();
        match hit.kind {
            PrimKind::Triangle => {
                let t = self.desc.triangles.get(hit.object as usize)?;
                match self.motion_of(hit.object) {
                    None => triangle_shading(&t, hit),
                    Some(m) => moved_shading(hit, m.relative(hit.time), |h| triangle_shading(&t, h)),
                }
            }
            PrimKind::Sphere | PrimKind::Disk => {
                // Spheres' ids in `shapes` are their objects' after the
                // triangles'; disks' come after every sphere's.
                let k = (hit.object as usize).checked_sub(tris)?;
                let id = match hit.kind {
                    PrimKind::Sphere => k,
                    _ => self.spheres.len() + k.checked_sub(self.desc.spheres.len())?,
                };
                match self.shape_motions.get(id).and_then(Option::as_ref) {
                    None => self.shape_shading(hit),
                    Some(m) => moved_shading(hit, m.relative(hit.time), |h| self.shape_shading(h)),
                }
            }
            PrimKind::Curve | PrimKind::Light => None,
        }
    }

    /// `shading_geometry` of a sphere or disk as placed in the description.
    fn shape_shading(&self, hit: &Hit) -> Option<(ShadingGeometry, [Vec3; 2])> {
        let tris = self.desc.triangles.len();
        match hit.kind {
            PrimKind::Sphere => {
                let object = self.spheres.get((hit.object as usize).checked_sub(tris)?)?;
                let s = &object.sphere;
                let q = object.axes.transpose() * ((hit.p - s.centre) / s.radius);
                let sin_theta = (q.x * q.x + q.y * q.y).sqrt();
                if sin_theta < 1e-6 {
                    return None;
                }
                // pbrt-v4's sphere: theta runs from pi at -z to 0 at +z.
                let dpdv = object.axes
                    * Vec3::new(q.z * q.x / sin_theta, q.z * q.y / sin_theta, -sin_theta)
                    * (-std::f32::consts::PI * s.radius);
                let g = ShadingGeometry {
                    n: hit.ng,
                    dpdu: hit.dpdu,
                    dpdv,
                    dndu: hit.dpdu / s.radius,
                    dndv: dpdv / s.radius,
                };
                Some((g, [hit.dpdu, dpdv]))
            }
            PrimKind::Disk => {
                let j = (hit.object as usize).checked_sub(tris + self.desc.spheres.len())?;
                let d = &self.disks.get(j)?.disk;
                let q = hit.p - d.centre;
                let planar = q - d.normal * q.dot(d.normal);
                let r = planar.length();
                if r < 1e-6 * d.radius {
                    return None;
                }
                let dpdv = planar * ((d.inner_radius - d.radius) / r);
                let g = ShadingGeometry {
                    n: hit.ng,
                    dpdu: hit.dpdu,
                    dpdv,
                    dndu: Vec3::ZERO,
                    dndv: Vec3::ZERO,
                };
                Some((g, [hit.dpdu, dpdv]))
            }
            _ => None,
        }
    }

    /// The hit record of triangle `slot` (BVH order) at barycentrics (u, v);
    /// `BARE`: texture coordinates only on a light, no dp/du
    /// ([`Scene::intersect_bare`]).
    #[inline(always)]
    fn triangle_hit<const BARE: bool>(&self, idx: usize, u: f32, v: f32, t: f32, p: Vec3) -> Hit {
        let inf = &self.info[idx];
        let ns = self.shading_normal(idx, u, v);
        let (uv, dpdu) = if !BARE {
            (self.triangle_uv(idx, u, v), self.dpdus[idx])
        } else if inf.light.is_some() {
            (self.triangle_uv(idx, u, v), Vec3::ZERO)
        } else {
            (Vec2::ZERO, Vec3::ZERO)
        };
        Hit {
            t,
            p,
            ng: inf.normal,
            ns,
            uv,
            dpdu,
            material: inf.material,
            object: inf.object,
            kind: if inf.light.is_some() {
                PrimKind::Light
            } else {
                PrimKind::Triangle
            },
            light: inf.light,
            time: 0.0,
        }
    }

    /// The shading normal at barycentrics (u, v) of triangle `idx`: its
    /// vertex normals interpolated, on the geometric normal's side; the
    /// geometric normal where it has none.
    #[inline(always)]
    fn shading_normal(&self, idx: usize, u: f32, v: f32) -> Vec3 {
        let ng = self.info[idx].normal;
        match self.shading.normals(&self.desc.triangles, idx) {
            Some(n) => interpolated_normal(n, ng, u, v),
            _ => ng,
        }
    }

    /// What a path traced in lanes (`integrator::lanes`) reads of triangle
    /// `slot` (BVH order) once a ray has hit it.
    #[inline(always)]
    pub fn triangle_geometry(&self, slot: u32) -> TriangleGeometry {
        let idx = slot as usize;
        let inf = &self.info[idx];
        TriangleGeometry {
            triangle: self.triangles[idx],
            ng: inf.normal,
            normals: self.shading.normals(&self.desc.triangles, idx),
            material: inf.material,
            light: inf.light,
        }
    }

    /// The closest triangle `ray` meets in a scene of still, solid triangles
    /// alone ([`Scene::only_still_triangles`]): its slot and where.
    #[inline(always)]
    pub fn intersect_triangle(&self, ray: &Ray) -> Option<(u32, TriHit)> {
        self.bvh.intersect(ray, 0.0, f32::INFINITY)
    }

    /// Texture coordinates at barycentrics (u, v) of triangle `slot` (BVH
    /// order), as pbrt-v4's `Triangle` computes them.
    fn triangle_uv(&self, slot: usize, b1: f32, b2: f32) -> Vec2 {
        let uv = self.shading.uvs(&self.desc.triangles, slot).unwrap_or(DEFAULT_UV);
        let b0 = 1.0 - b1 - b2;
        uv[0] * b0 + uv[1] * b1 + uv[2] * b2
    }

    /// dp/du of triangle `slot`, as pbrt-v4's `Triangle` computes it.
    fn triangle_dpdu(&self, slot: usize) -> Vec3 {
        let uv = self.shading.uvs(&self.desc.triangles, slot).unwrap_or(DEFAULT_UV);
        let [p0, p1, p2] = self.triangles[slot].vertices();
        let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
        let (dp02, dp12) = (p0 - p2, p1 - p2);
        let det = duv02.x * duv12.y - duv02.y * duv12.x;
        let dpdu = (dp02 * duv12.y - dp12 * duv02.y) / det;
        // Degenerate texture coordinates: any tangent will do.
        if det.abs() < 1e-9 || !dpdu.is_finite() {
            p1 - p0
        } else {
            dpdu
        }
    }

    /// Whether the scene has participating media: its paths then need the
    /// volumetric path tracer.
    pub fn has_media(&self) -> bool {
        !self.media.is_empty()
    }

    /// Whether any material scatters below its surface: the path tracer
    /// then takes the volumetric path tracer's loop, which follows it.
    pub fn has_subsurface(&self) -> bool {
        self.any_subsurface
    }

    /// Whether any shape, or the camera, moves while the shutter is open.
    pub fn has_motion(&self) -> bool {
        self.camera.shutter.is_some()
    }

    /// The media on the two sides of the surface a hit is on, when it
    /// bounds any.
    pub fn interface(&self, hit: &Hit) -> Option<MediumInterface> {
        let i = *self.object_interfaces.get(hit.object as usize)?;
        self.interfaces.get(i as usize).copied()
    }

    /// Whether the surface hit is no surface, only a boundary of media
    /// (rays pass through it).
    pub fn is_interface(&self, hit: &Hit) -> bool {
        matches!(self.material(hit.material), Material::Interface)
    }

    /// The medium of a ray leaving `hit` along `w`, having arrived there in
    /// `current`: the side of the surface it leaves towards when the surface
    /// is a transition between media (pbrt-v4's `GetMedium`), else `current`.
    pub fn medium_after(&self, hit: &Hit, current: Option<u32>, w: Vec3) -> Option<u32> {
        match self.interface(hit) {
            Some(mi) if mi.is_transition() => {
                if w.dot(hit.ng) > 0.0 {
                    mi.outside
                } else {
                    mi.inside
                }
            }
            _ => current,
        }
    }

    /// The fraction of light that travels from `o` along the unit direction
    /// `d` for `dist` (infinite: out of the scene) starting in `medium`,
    /// passing through surfaces that only bound media and taking each
    /// medium's transmittance; zero when any other surface is in the way.
    /// The segment is a shadow ray towards `light`, whose own surface does
    /// not count (as in `occluded_before_light`).
    pub fn transmittance(&self, o: Vec3, d: Vec3, dist: f32, medium: Option<u32>, light: u32) -> Vec3 {
        let mut tr = Vec3::ONE;
        let (mut o, mut medium) = (o, medium);
        let end = o + d * dist;
        for _ in 0..MAX_CROSSINGS {
            let left = if dist.is_finite() {
                (end - o).dot(d)
            } else {
                f32::INFINITY
            };
            let t_max = if dist.is_finite() { left * (1.0 - 1e-4) } else { left };
            let hit = self.intersect(&Ray::new(o, d), 0.0, t_max.max(0.0));
            let reached = match &hit {
                None => true,
                Some(h) => h.light == Some(light),
            };
            let seg = if reached {
                left.max(0.0)
            } else {
                hit.as_ref().map_or(0.0, |h| h.t)
            };
            if let Some(m) = medium {
                tr *= self.media[m as usize].transmittance_along(o, d, seg);
            }
            if reached || tr == Vec3::ZERO {
                return tr;
            }
            let Some(h) = hit else { return tr };
            if !self.is_interface(&h) {
                return Vec3::ZERO;
            }
            medium = self.medium_after(&h, medium, d);
            o = crate::math::offset_origin(h.p, h.ng, d);
        }
        Vec3::ZERO
    }

    /// Whether anything blocks the segment (t_min, t_max) of the ray.
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.shapes_block(ray, t_min, t_max, None)
            || self.triangles_block(ray, t_min, t_max)
            || (!self.movers.is_empty() && self.movers_block(ray, t_min, t_max))
    }

    /// Whether anything but light `light`'s own sphere (or disk) blocks the
    /// segment: the shadow test towards a point sampled on that light. The
    /// light itself is left out because near its silhouette the sampled
    /// point's distance is ill-conditioned (a tangent ray), and a relative
    /// epsilon on `t_max` then lets the light shadow itself.
    pub fn occluded_before_light(&self, ray: &Ray, t_min: f32, t_max: f32, light: u32) -> bool {
        if self.only_still_triangles() {
            return self.bvh.occluded(ray, t_min, t_max);
        }
        self.shapes_block(ray, t_min, t_max, Some(light))
            || self.triangles_block(ray, t_min, t_max)
            || (!self.movers.is_empty() && self.movers_block(ray, t_min, t_max))
    }

    /// Whether a sphere or disk (other than light `but`'s) blocks the ray.
    #[inline(always)]
    fn shapes_block(&self, ray: &Ray, t_min: f32, t_max: f32, but: Option<u32>) -> bool {
        let other = |id: u32| but.is_none() || self.shape_light(id) != but;
        if self.alphas.is_empty() {
            self.shapes.occluded(ray, t_min, t_max, |id| {
                other(id) && self.shape_hit::<false>(id, ray, t_min, t_max).is_some()
            })
        } else {
            self.shapes.occluded(ray, t_min, t_max, |id| {
                other(id) && self.shape_hit::<true>(id, ray, t_min, t_max).is_some()
            })
        }
    }

    pub fn material(&self, id: u32) -> &Material {
        &self.materials[id as usize]
    }

    /// Whether light goes on from `hit`: true on every surface but an
    /// emitter that reflects nothing, where paths end.
    pub fn reflects(&self, hit: &Hit) -> bool {
        hit.light.is_none() || hit.material != self.black_emitter
    }

    /// Moves light `index` (and the sphere it emits from) to `position`,
    /// keeping its size and power. The triangle BVH holds no sphere lights,
    /// so only the small BVH over spheres and disks is rebuilt; an index out
    /// of range changes nothing.
    pub fn move_light(&mut self, index: usize, position: Vec3) {
        let Some(light) = self.lights.get_mut(index) else {
            return;
        };
        if matches!(light, Light::Triangle { .. }) {
            // Its triangle is in the BVH: moving it would mean a rebuild.
            return;
        }
        light.move_to(position);
        if let Some(l) = self.desc.lights.get_mut(index) {
            *l = light.clone();
        }
        for s in &mut self.spheres {
            if s.light == Some(index as u32) {
                s.sphere.centre = position;
            }
        }
        // The count is unchanged, so this cannot fail.
        if let Ok(shapes) = shape_bvh(&self.spheres, &self.disks, &self.desc.curves, &self.shape_motions) {
            self.shapes = shapes;
        }
        self.light_tree = light_tree(&self.lights, self.desc.light_sampler);
    }

    /// Bounding box of all geometry (triangles, spheres and lights).
    pub fn bounds(&self) -> crate::math::Aabb {
        let mut b = if self.triangles.len() == self.movers.iter().map(|m| m.bvh.order.len()).sum::<usize>() {
            crate::math::Aabb::EMPTY
        } else {
            self.bvh.bounds()
        };
        for m in &self.movers {
            b = b.union(&m.bounds);
        }
        let shapes = self.spheres.iter().map(|s| s.sphere.bounds());
        for (k, sb) in shapes.chain(self.disks.iter().map(|d| d.disk.bounds())).enumerate() {
            // A moving sphere's or disk's box over its whole motion.
            b = match self.shape_motions.get(k).and_then(Option::as_ref) {
                None => b.union(&sb),
                Some(m) => {
                    let (min, max) = m.bounds(sb.min, sb.max);
                    b.union(&crate::math::Aabb { min, max })
                }
            };
        }
        for c in &self.desc.curves {
            b = b.union(&c.curve.bounds());
        }
        for l in self.lights.iter().filter(|l| !l.is_infinite()) {
            b.grow(l.position());
        }
        b
    }
}

/// The motions of the spheres and disks (ids as `shape_bvh`'s: every
/// sphere, lights' included, then every disk), empty when none moves.
fn shape_motions(
    desc: &SceneDesc,
    spheres: &[SphereObject],
    disks: &[DiskObject],
) -> Result<Vec<Option<motion::Motion>>> {
    if desc.moving_shapes.is_empty() {
        return Ok(vec![]);
    }
    let mut motions = vec![None; spheres.len() + disks.len()];
    for m in &desc.moving_shapes {
        let (id, cut) = match m.shape {
            CutShapes::Sphere(i) if i < desc.spheres.len() => (i, spheres[i].alpha.is_some()),
            CutShapes::Disk(j) if j < desc.disks.len() => (spheres.len() + j, disks[j].alpha.is_some()),
            ref other => {
                return Err(Error::Scene(format!(
                    "a moving shape names {other:?}, not a sphere or disk of the scene"
                )))
            }
        };
        if cut {
            return Err(Error::Scene(format!(
                "moving {:?}: an alpha cut-out on a moving shape is not supported",
                m.shape
            )));
        }
        if motions[id].replace(m.motion.clone()).is_some() {
            return Err(Error::Scene(format!("{:?} is given two motions", m.shape)));
        }
    }
    Ok(motions)
}

/// The BVH over the spheres', the disks' and the curves' boxes (ids:
/// spheres, then disks, then curves).
fn shape_bvh(
    spheres: &[SphereObject],
    disks: &[DiskObject],
    curves: &[CurveDesc],
    motions: &[Option<motion::Motion>],
) -> Result<BoxBvh> {
    let mut boxes: Vec<crate::math::Aabb> = spheres
        .iter()
        .map(|s| s.sphere.bounds())
        .chain(disks.iter().map(|d| d.disk.bounds()))
        .chain(curves.iter().map(|c| c.curve.bounds()))
        .collect();
    // A moving shape's box holds it over its whole motion.
    for (b, m) in boxes.iter_mut().zip(motions) {
        if let Some(m) = m {
            let (min, max) = m.bounds(b.min, b.max);
            if !(min.is_finite() && max.is_finite()) {
                return Err(Error::Scene(
                    "a moving sphere or disk: its motion takes it beyond finite coordinates".into(),
                ));
            }
            *b = crate::math::Aabb { min, max };
        }
    }
    if boxes.len() > BoxBvh::MAX_BOXES {
        return Err(Error::Scene(format!(
            "{} spheres, disks and curve pieces; the BVH holds at most {}",
            boxes.len(),
            BoxBvh::MAX_BOXES
        )));
    }
    Ok(BoxBvh::build(&boxes))
}

#[cfg(test)]
mod shading_tests {
    use super::*;

    fn scene_with(add: impl FnOnce(&mut SceneDesc)) -> Scene {
        let mut d = SceneDesc::empty("bumps", builtin::cornell().camera);
        let base = Box::new(Material::diffuse(0.5, 0.5, 0.5));
        let flat = Texture::from(Vec3::ZERO);
        d.material(
            "bumped",
            Material::Bumped {
                base,
                displacement: flat,
            },
        );
        d.material("plain", Material::diffuse(0.5, 0.5, 0.5));
        add(&mut d);
        Scene::build(d).unwrap()
    }

    fn shading_at(scene: &Scene, o: Vec3, towards: Vec3) -> (Hit, ShadingGeometry) {
        let h = scene
            .intersect(&Ray::new(o, (towards - o).normalize()), 1e-4, f32::INFINITY)
            .unwrap();
        let g = scene
            .surface(&h)
            .shading
            .expect("a bumped material gets shading geometry");
        (h, g)
    }

    fn near(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).length() <= tol * b.length().max(1.0)
    }

    #[test]
    fn sphere_and_disk_derivatives_are_those_of_their_parametrisations() {
        let (c, r) = (Vec3::new(1.0, 2.0, 3.0), 2.0);
        let scene = scene_with(|d| {
            d.spheres.push(SphereDesc {
                axes: None,
                sphere: Sphere { centre: c, radius: r },
                material: 0,
            });
            d.disks
                .push(DiskDesc::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 2.0, 0.5, 0));
        });
        // pbrt-v4's sphere: phi = 2 pi u about z, theta = pi (1 - v) from +z.
        let on_sphere = |uv: Vec2| {
            let (phi, theta) = (uv.x * std::f32::consts::TAU, std::f32::consts::PI * (1.0 - uv.y));
            c + Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()) * r
        };
        let (h, g) = shading_at(&scene, c + Vec3::new(5.0, 3.0, 2.0), c);
        let e = 1e-3;
        let dpdu = (on_sphere(h.uv + Vec2::new(e, 0.0)) - on_sphere(h.uv - Vec2::new(e, 0.0))) / (2.0 * e);
        let dpdv = (on_sphere(h.uv + Vec2::new(0.0, e)) - on_sphere(h.uv - Vec2::new(0.0, e))) / (2.0 * e);
        assert!(
            near(g.dpdu, dpdu, 1e-2) && near(g.dpdv, dpdv, 1e-2),
            "{g:?} {dpdu} {dpdv}"
        );
        // The unit normal of a sphere is (p - c) / r: it turns as p / r does.
        assert!(near(g.dndu, dpdu / r, 1e-2) && near(g.dndv, dpdv / r, 1e-2));
        assert!(near(g.n, (h.p - c) / r, 1e-4) && g.dpdu.cross(g.dpdv).dot(g.n) > 0.0);

        let disk = &scene.disks[0].disk;
        let (h, g) = shading_at(&scene, Vec3::new(0.7, -1.1, 0.0), Vec3::new(0.3, 1.2, -5.0));
        let dpdu = (disk.point_at(h.uv + Vec2::new(e, 0.0)) - disk.point_at(h.uv - Vec2::new(e, 0.0))) / (2.0 * e);
        let dpdv = (disk.point_at(h.uv + Vec2::new(0.0, e)) - disk.point_at(h.uv - Vec2::new(0.0, e))) / (2.0 * e);
        assert!(
            near(g.dpdu, dpdu, 1e-2) && near(g.dpdv, dpdv, 1e-2),
            "{g:?} {dpdu} {dpdv}"
        );
        assert_eq!((g.n, g.dndu, g.dndv), (Vec3::Z, Vec3::ZERO, Vec3::ZERO));
    }

    #[test]
    fn the_uv_footprint_is_the_least_squares_change_of_uv() {
        let (dpdu, dpdv) = (Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.5, 3.0, 1.0));
        // Changes within the surface are recovered exactly...
        let f = uv_footprint(dpdu, dpdv, dpdu * 0.1 + dpdv * 0.2, dpdu * -0.3 + dpdv * 0.05);
        for (got, want) in [(f.dudx, 0.1), (f.dvdx, 0.2), (f.dudy, -0.3), (f.dvdy, 0.05)] {
            assert!((got - want).abs() < 1e-6, "{f:?}");
        }
        // ...a change along the normal adds nothing, and a degenerate
        // parametrisation gives no footprint.
        let n = dpdu.cross(dpdv);
        let uv_only = |f: Footprint| Footprint {
            dpdx: Vec3::ZERO,
            dpdy: Vec3::ZERO,
            ..f
        };
        assert_eq!(uv_only(uv_footprint(dpdu, dpdv, n, n)), Footprint::NONE);
        assert_eq!(uv_only(uv_footprint(dpdu, dpdu, dpdu, dpdu)), Footprint::NONE);
        // The point's own change is kept, for textures of space.
        assert_eq!(uv_footprint(dpdu, dpdv, n, -n).dpdy, -n);
    }

    /// A scene of big z-facing squares at the given depths (material 0 is
    /// bumped: the scene carries differentials), seen by a 30-degree camera
    /// 5 units before z = 0, looking along +z.
    fn planes_at(zs: &[(f32, u32)]) -> Scene {
        let mut d = SceneDesc::empty("planes", builtin::cornell().camera);
        d.camera.position = Vec3::new(0.0, 0.0, -5.0);
        d.camera.look_at = Vec3::ZERO;
        d.camera.up = Vec3::Y;
        d.camera.fov_y_deg = 30.0;
        (d.camera.width, d.camera.height) = (100, 100);
        let base = Box::new(Material::diffuse(0.5, 0.5, 0.5));
        d.material(
            "bumped",
            Material::Bumped {
                base,
                displacement: Texture::from(Vec3::ZERO),
            },
        );
        for &(z, material) in zs {
            let c = [(-50.0, -50.0), (50.0, -50.0), (50.0, 50.0), (-50.0, 50.0)].map(|(x, y)| Vec3::new(x, y, z));
            for t in [[c[0], c[1], c[2]], [c[0], c[2], c[3]]] {
                d.triangles.push(TriangleDesc {
                    vertices: t,
                    normals: None,
                    uvs: None,
                    material,
                });
            }
        }
        Scene::build(d).unwrap()
    }

    /// The first hit along a ray from `o` in direction `d`.
    fn first_hit(scene: &Scene, o: Vec3, d: Vec3) -> Hit {
        scene.intersect(&Ray::new(o, d), 0.0, f32::INFINITY).unwrap()
    }

    #[test]
    fn differentials_carried_through_a_mirror_see_the_unfolded_distance() {
        // A mirror at z = 0 sends the centre ray back to a plane at z = -10:
        // 15 units of path, where the point is 5 from the camera.
        let scene = planes_at(&[(0.0, 0), (-10.0, 0)]);
        let pixel = 2.0 * 15f32.to_radians().tan() / 100.0 * 0.125;
        let ray = scene.camera.generate_ray(50.0, 50.0);
        let mirror = first_hit(&scene, ray.o, ray.d);
        let d = scene.camera_differentials(&mirror).unwrap();
        let (dx, _) = d.on_plane(mirror.p, mirror.ng).unwrap();
        assert!(
            (dx.length() / (5.0 * pixel) - 1.0).abs() < 1e-3,
            "{}",
            dx.length() / pixel
        );
        let (wo, wi) = (-ray.d, ray.d - mirror.ng * 2.0 * ray.d.dot(mirror.ng));
        let out = scene
            .specular_differentials(&mirror, &d, (wo, wi), false, 1.0, mirror.ng)
            .unwrap();
        let back = first_hit(&scene, crate::math::offset_origin(mirror.p, mirror.ng, wi), wi);
        assert!((back.p.z + 10.0).abs() < 1e-4);
        let (bx, by) = out.on_plane(back.p, back.ng).unwrap();
        for b in [bx, by] {
            assert!(
                (b.length() / (15.0 * pixel) - 1.0).abs() < 1e-3,
                "{}",
                b.length() / pixel
            );
        }
        // Without them, pbrt-v4's approximation at the point's distance, 5.
        let (ax, _) = scene.footprint.dp_dxy(&scene.camera, back.p, back.ng, None);
        assert!(ax.length() < 6.0 * pixel, "{}", ax.length() / pixel);
    }

    #[test]
    fn differentials_through_a_glass_slab_see_its_thickness_shortened_by_its_index() {
        // Glass from z = 0 to z = 3, index 1.5, then a plane at z = 5: seen
        // along the axis, the plane looks 5 - 3 + 3 / 1.5 = 4 units beyond
        // z = 0, so its footprint is that of a plane 9 units from the camera.
        let scene = planes_at(&[(0.0, 0), (3.0, 0), (5.0, 0)]);
        let pixel = 2.0 * 15f32.to_radians().tan() / 100.0 * 0.125;
        let eta = 1.5;
        let ray = scene.camera.generate_ray(50.0, 50.0);
        let front = first_hit(&scene, ray.o, ray.d);
        let d = scene.camera_differentials(&front).unwrap();
        // Along the axis the refracted direction is the incoming one.
        let (wo, wi) = (-ray.d, ray.d);
        let inside = scene
            .specular_differentials(&front, &d, (wo, wi), true, eta, -Vec3::Z)
            .unwrap();
        let back = first_hit(&scene, front.p + wi * 1e-3, wi);
        let out = scene
            .specular_differentials(&back, &inside, (wo, wi), true, 1.0 / eta, -Vec3::Z)
            .unwrap();
        let plane = first_hit(&scene, back.p + wi * 1e-3, wi);
        assert!((plane.p.z - 5.0).abs() < 1e-4);
        let (px, py) = out.on_plane(plane.p, plane.ng).unwrap();
        for p in [px, py] {
            assert!(
                (p.length() / (9.0 * pixel) - 1.0).abs() < 2e-3,
                "{}",
                p.length() / pixel
            );
        }
    }

    #[test]
    fn only_materials_that_look_up_images_or_bump_get_a_footprint() {
        let scene = scene_with(|d| {
            for (i, material) in [0, 1].into_iter().enumerate() {
                let shift = Vec3::new(10.0 * i as f32, 0.0, 0.0);
                d.triangles.push(TriangleDesc {
                    vertices: [Vec3::ZERO, Vec3::X * 2.0, Vec3::Y * 2.0].map(|v| v + shift),
                    normals: None,
                    uvs: None,
                    material,
                });
            }
        });
        let hit = |x: f32| {
            let o = Vec3::new(x + 0.5, 0.5, 3.0);
            scene.intersect(&Ray::new(o, -Vec3::Z), 1e-4, f32::INFINITY).unwrap()
        };
        let (bumped, plain) = (hit(0.0), hit(10.0));
        assert_eq!(scene.surface(&plain).footprint, Footprint::NONE);
        let approximate = scene.surface(&bumped).footprint;
        let exact = scene
            .surface_seen(&bumped, scene.camera_differentials(&bumped).as_ref())
            .footprint;
        assert_ne!(approximate, Footprint::NONE);
        assert_ne!(approximate, exact);
        // Both about an eighth of the pixel: the same order of size.
        let size = |f: Footprint| f.dudx.abs() + f.dvdx.abs() + f.dudy.abs() + f.dvdy.abs();
        let ratio = size(approximate) / size(exact);
        assert!(ratio > 0.2 && ratio < 5.0, "{ratio}");
    }

    #[test]
    fn triangle_derivatives_follow_the_texture_coordinates_and_vertex_normals() {
        let vertices = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.5),
        ];
        let uvs = [Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.3), Vec2::new(0.2, 0.7)];
        let normals = [
            Vec3::new(0.1, -0.4, 1.0),
            Vec3::new(-0.2, -0.5, 1.0),
            Vec3::new(0.0, -0.3, 0.9),
        ];
        let scene = scene_with(|d| {
            for (i, (normals, material)) in [(None, 0), (Some(normals), 0), (None, 1)].into_iter().enumerate() {
                let shift = Vec3::new(10.0 * i as f32, 0.0, 0.0);
                d.triangles.push(TriangleDesc {
                    vertices: vertices.map(|v| v + shift),
                    normals,
                    uvs: Some(uvs),
                    material,
                });
            }
        });
        let inside = (vertices[0] + vertices[1] + vertices[2]) / 3.0;
        let from = Vec3::new(0.3, 0.2, 4.0);
        // p is affine in (u, v): each edge is dp/du du + dp/dv dv.
        let (h, g) = shading_at(&scene, from, inside);
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            let duv = uvs[b] - uvs[a];
            assert!(near(g.dpdu * duv.x + g.dpdv * duv.y, vertices[b] - vertices[a], 1e-4));
        }
        assert_eq!(g.n, h.ng);
        // With vertex normals: pbrt-v4's frame about the shading normal, and
        // the (unnormalised) normals affine in (u, v) as the points are.
        let shift = Vec3::new(10.0, 0.0, 0.0);
        let (h, g) = shading_at(&scene, from + shift, inside + shift);
        assert_eq!(g.n, h.ns);
        let perpendicular = |a: Vec3, b: Vec3| a.dot(b).abs() <= 1e-5 * a.length() * b.length();
        assert!(
            perpendicular(g.dpdu, g.n) && perpendicular(g.dpdv, g.n) && perpendicular(g.dpdu, g.dpdv),
            "{g:?}"
        );
        assert!(g.dpdu.cross(g.dpdv).dot(g.n) > 0.0 && g.dpdu.dot(h.dpdu) > 0.0);
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            let duv = uvs[b] - uvs[a];
            assert!(near(g.dndu * duv.x + g.dndv * duv.y, normals[b] - normals[a], 1e-4));
        }
        // A material without a bump map is not given any.
        let shift = Vec3::new(20.0, 0.0, 0.0);
        let h = scene
            .intersect(
                &Ray::new(from + shift, (inside - from).normalize()),
                1e-4,
                f32::INFINITY,
            )
            .unwrap();
        assert_eq!(h.material, 1);
        assert!(scene.surface(&h).shading.is_none());
    }
}

#[cfg(test)]
mod offset_tests {
    use super::*;
    use crate::math::offset_origin;

    #[test]
    fn a_ray_leaving_a_sheet_meets_the_sheet_right_behind_it() {
        // The two sides of a thin slat, 2.5e-4 apart, three units from the
        // origin (a blind in Bitterli's kitchen): a shadow ray from the
        // front side towards a light behind must meet the back side, at
        // every angle, seen from a camera near or far; and a ray leaving
        // either side must not meet the side it leaves. And a ray leaving a
        // sphere inwards meets the sphere nested 5e-3 inside it.
        let gap = 2.5e-4f32;
        let mut d = SceneDesc::empty("sheets", builtin::cornell().camera);
        let m = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
        let z0 = -2.748f32;
        for (z, flip) in [(z0, false), (z0 - gap, true)] {
            let v = [(-1.0, 2.0), (1.0, 2.0), (1.0, 4.0), (-1.0, 4.0)].map(|(x, y)| Vec3::new(x, y, z));
            for t in [[0, 1, 2], [0, 2, 3]] {
                let t = if flip { [t[0], t[2], t[1]] } else { t };
                d.triangles.push(TriangleDesc {
                    vertices: t.map(|i| v[i]),
                    normals: None,
                    uvs: None,
                    material: m,
                });
            }
        }
        let (centre, radius) = (Vec3::new(40.0, 3.0, -30.0), 5.0);
        for r in [radius, radius - gap * 20.0] {
            d.spheres.push(SphereDesc {
                sphere: crate::geometry::Sphere { centre, radius: r },
                material: m,
                axes: None,
            });
        }
        let scene = Scene::build(d).unwrap();
        let mut rng = crate::sampling::Rng::new(3, 4);
        let mut spheres = 0;
        for k in 0..2000 {
            // From a camera 1 to 1000 units in front of the sheet.
            let dist = 10f32.powf(3.0 * rng.next_f32());
            let target = Vec3::new(rng.next_f32() - 0.5, 2.5 + rng.next_f32(), z0);
            let from = target + Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 1.0).normalize() * dist;
            let ray = Ray::new(from, (target - from).normalize());
            let hit = scene.intersect(&ray, 0.0, f32::INFINITY).unwrap();
            assert!((hit.p.z - z0).abs() < 1e-5, "{k}: {}", hit.p);
            let behind = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, -1.0).normalize();
            let next = scene.intersect(
                &Ray::new(offset_origin(hit.p, hit.ng, behind), behind),
                0.0,
                f32::INFINITY,
            );
            let next = next.unwrap_or_else(|| panic!("{k}: the back side missed"));
            assert!((next.p.z - (z0 - gap)).abs() < 1e-5 && next.t > 0.0, "{k}: {}", next.p);
            let back = -ray.d;
            let out = Ray::new(offset_origin(hit.p, hit.ng, back), back);
            assert!(
                scene.intersect(&out, 0.0, f32::INFINITY).is_none(),
                "{k}: met the side it left"
            );
            // The same off the outer sphere, whose inner shell is 5e-3 in.
            let to_sphere = (centre + Vec3::new(0.0, 0.0, radius) - from).normalize();
            let Some(s) = scene.intersect(&Ray::new(from, to_sphere), 0.0, f32::INFINITY) else {
                continue;
            };
            if s.kind != PrimKind::Sphere || ((s.p - centre).length() - radius).abs() > 1e-3 {
                continue;
            }
            let inward = -s.ng;
            let inner = scene.intersect(&Ray::new(offset_origin(s.p, s.ng, inward), inward), 0.0, f32::INFINITY);
            let inner = inner.unwrap_or_else(|| panic!("{k}: the inner sphere missed"));
            assert!(
                ((inner.p - centre).length() - (radius - gap * 20.0)).abs() < 1e-4,
                "{k}"
            );
            spheres += 1;
        }
        assert!(spheres > 1000, "{spheres}");
    }
}

/// A quad of side `size` at height `z` centred over (0.5, 0.5), its
/// texture coordinates its x and y over [0, 1]^2 when `size` is 1, as two
/// triangles of material `m`.
#[cfg(test)]
fn test_quad(m: u32, z: f32, size: f32) -> [TriangleDesc; 2] {
    let c = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(x, y)| Vec2::new(x, y));
    let v = c.map(|c| ((c - Vec2::splat(0.5)) * size + Vec2::splat(0.5)).extend(z));
    [[0, 1, 2], [0, 2, 3]].map(|t| TriangleDesc {
        vertices: t.map(|i| v[i]),
        normals: None,
        uvs: Some(t.map(|i| c[i])),
        material: m,
    })
}

#[cfg(test)]
mod build_tests {
    use super::*;

    #[test]
    fn triangles_that_cannot_be_hit_are_dropped_and_the_rest_keep_their_places() {
        // 3,000 small quads in a row at z = 0, every seventh triangle made
        // flat and every eleventh given a corner at infinity: the rest are
        // made on every core and must each answer to its own index.
        let mut d = SceneDesc::empty("many", builtin::cornell().camera);
        let m = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
        let mut expected_drops = 0;
        for q in 0..3000 {
            for (h, mut t) in test_quad(m, 0.0, 0.5).into_iter().enumerate() {
                let i = 2 * q + h;
                for v in &mut t.vertices {
                    v.x += q as f32;
                }
                if i % 7 == 3 {
                    t.vertices[2] = t.vertices[1];
                    expected_drops += 1;
                } else if i % 11 == 5 {
                    t.vertices[0].y = f32::INFINITY;
                    expected_drops += 1;
                }
                d.triangles.push(t);
            }
        }
        let scene = Scene::build(d.clone()).unwrap();
        assert_eq!(scene.dropped_triangles, expected_drops);
        assert_eq!(scene.triangles().len(), 6000 - expected_drops);
        let mut seen = 0;
        for i in 0..6000 {
            let Some(v) = d.triangles.vertices(i) else { continue };
            let dropped = i % 7 == 3 || (i % 11 == 5);
            let c = (v[0] + v[1] + v[2]) / 3.0;
            if dropped {
                continue;
            }
            let hit = scene
                .intersect(&Ray::new(c + Vec3::Z, -Vec3::Z), 0.0, f32::INFINITY)
                .unwrap_or_else(|| panic!("triangle {i} is not there"));
            assert_eq!(hit.object as usize, i);
            seen += 1;
        }
        assert_eq!(seen, 6000 - expected_drops);
        // A material out of range is named for the first triangle that has it.
        let mut bad = d;
        for i in [4100, 2500, 5000] {
            let mut t = bad.triangles.get(i).unwrap();
            t.material = 7;
            bad.triangles.set(i, t);
        }
        let e = Scene::build(bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("triangle 2500 names material 7 of 1"), "{e}");
    }
}

#[cfg(test)]
mod cutout_tests {
    use super::*;
    use std::sync::Arc;

    /// A unit quad at z = 0 (texture coordinates its x and y) cut out by
    /// `alpha`, a large solid quad at z = -1 behind it, and the shapes `add`
    /// puts in.
    fn scene_with(alpha: Texture, add: impl FnOnce(&mut SceneDesc)) -> Scene {
        let mut d = SceneDesc::empty("cut-outs", builtin::cornell().camera);
        let m = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
        let quad = |z: f32, size: f32| test_quad(m, z, size);
        d.triangles.extend(quad(0.0, 1.0));
        d.triangles.extend(quad(-1.0, 10.0));
        d.cutouts.push(Cutout {
            alpha,
            shapes: CutShapes::Triangles(0..2),
        });
        add(&mut d);
        Scene::build(d).unwrap()
    }

    fn down_at(x: f32, y: f32) -> Ray {
        Ray::new(Vec3::new(x, y, 1.0), -Vec3::Z)
    }

    fn checker(u_scale: f32, v_scale: f32) -> Texture {
        Texture::checkerboard(
            Arc::new(Texture::from(Vec3::ONE)),
            Arc::new(Texture::from(Vec3::ZERO)),
            u_scale,
            v_scale,
        )
    }

    #[test]
    fn rays_pass_where_the_alpha_is_zero_and_stop_where_it_is_one() {
        let scene = scene_with(checker(2.0, 2.0), |_| {});
        for i in 0..20 {
            for j in 0..20 {
                let (x, y) = ((i as f32 + 0.5) / 20.0, (j as f32 + 0.5) / 20.0);
                let solid = ((2.0 * x).floor() + (2.0 * y).floor()) % 2.0 == 0.0;
                let ray = down_at(x, y);
                let z = scene.intersect(&ray, 0.0, f32::INFINITY).unwrap().p.z;
                assert_eq!(z.round(), if solid { 0.0 } else { -1.0 }, "({x}, {y})");
                // Shadow rays see what camera rays see; the back quad is beyond 1.5.
                assert_eq!(scene.occluded(&ray, 0.0, 1.5), solid, "({x}, {y})");
            }
        }
    }

    #[test]
    fn an_alpha_between_zero_and_one_stops_that_share_of_rays_the_same_ones_each_time() {
        let a = 0.3;
        let scene = scene_with(Texture::from(Vec3::splat(a)), |_| {});
        let n = 100;
        let mut stopped = 0;
        for i in 0..n {
            for j in 0..n {
                let ray = down_at((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let z = scene.intersect(&ray, 0.0, f32::INFINITY).unwrap().p.z;
                stopped += (z > -0.5) as usize;
                assert_eq!(scene.intersect(&ray, 0.0, f32::INFINITY).unwrap().p.z, z);
                assert_eq!(scene.occluded(&ray, 0.0, 1.5), z > -0.5);
            }
        }
        // Binomial: the standard deviation of the share is 0.0046.
        let share = stopped as f32 / (n * n) as f32;
        assert!((share - a).abs() < 0.025, "{share}");
    }

    #[test]
    fn a_sphere_cut_out_on_its_near_side_is_hit_on_its_far_side() {
        // Solid for u < 1/2 (y > 0), cut out for y < 0; and a disk that is not there.
        let scene = scene_with(Texture::from(Vec3::ONE), |d| {
            d.spheres.push(SphereDesc {
                axes: None,
                sphere: Sphere {
                    centre: Vec3::new(5.0, 0.0, 0.0),
                    radius: 1.0,
                },
                material: 0,
            });
            d.disks
                .push(DiskDesc::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::Y, 1.0, 0.0, 0));
            d.cutouts.push(Cutout {
                alpha: checker(2.0, 1.0),
                shapes: CutShapes::Sphere(0),
            });
            d.cutouts.push(Cutout {
                alpha: Texture::from(Vec3::ZERO),
                shapes: CutShapes::Disk(0),
            });
        });
        let from_below = Ray::new(Vec3::new(5.0, -5.0, 0.0), Vec3::Y);
        let h = scene.intersect(&from_below, 0.0, f32::INFINITY).unwrap();
        assert!((h.p.y - 1.0).abs() < 1e-4, "{}", h.p);
        let from_above = Ray::new(Vec3::new(5.0, 5.0, 0.0), -Vec3::Y);
        let h = scene.intersect(&from_above, 0.0, f32::INFINITY).unwrap();
        assert!((h.p.y - 1.0).abs() < 1e-4, "{}", h.p);
        // Inside the lower half going down: nothing but the cut-out side.
        assert!(scene
            .intersect(&Ray::new(Vec3::new(5.0, -0.5, 0.0), -Vec3::Y), 0.0, f32::INFINITY)
            .is_none());
        let through_disk = Ray::new(Vec3::new(-5.0, 5.0, 0.0), -Vec3::Y);
        assert!(scene.intersect(&through_disk, 0.0, f32::INFINITY).is_none());
        assert!(!scene.occluded(&through_disk, 0.0, f32::INFINITY));
    }

    #[test]
    fn a_cutout_naming_shapes_that_are_not_there_is_an_error() {
        let mut d = SceneDesc::empty("bad", builtin::cornell().camera);
        d.cutouts.push(Cutout {
            alpha: Texture::from(Vec3::ZERO),
            shapes: CutShapes::Triangles(0..3),
        });
        let e = Scene::build(d).err().unwrap().to_string();
        assert!(e.contains("cut-out 0 names triangles 0..3 of 0"), "{e}");
    }
}

#[cfg(test)]
mod motion_tests {
    use super::*;
    use glam::Mat4;
    use motion::Motion;

    /// A unit quad over [0, 1]^2 at z = 0 (texture coordinates its x and y),
    /// moving by `end` over the times [0, 1], and a large still quad at
    /// z = -1 behind it.
    fn scene_with(end: Mat4) -> Scene {
        let mut d = SceneDesc::empty("moving", builtin::cornell().camera);
        let m = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
        let quad = |z: f32, size: f32| test_quad(m, z, size);
        d.triangles.extend(quad(-1.0, 10.0));
        d.triangles.extend(quad(0.0, 1.0));
        d.moving.push(MovingTriangles {
            triangles: 2..4,
            motion: Motion::new(Mat4::IDENTITY, end, [0.0, 1.0]).unwrap(),
        });
        Scene::build(d).unwrap()
    }

    fn down_at(x: f32, y: f32, time: f32) -> Ray {
        Ray::timed(Vec3::new(x, y, 1.0), -Vec3::Z, time)
    }

    #[test]
    fn a_hit_on_a_moving_quad_is_carried_to_its_start() {
        // Stretched to twice its width along x and moved up by 1 at time 1:
        // at time 0.5, 1.5 times as wide and 0.5 up.
        let end = Mat4::from_translation(Vec3::new(0.0, 1.0, 0.0)) * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let scene = scene_with(end);
        assert!(scene.rest_frame(0, 0.5).is_none() && scene.moving_run(1).is_none());
        let hit = scene.intersect(&down_at(1.2, 0.9, 0.5), 0.0, f32::INFINITY).unwrap();
        assert!((2..4).contains(&hit.object), "{}", hit.object);
        let r = scene.rest_frame(hit.object, hit.time).unwrap();
        assert_eq!(r.objects, 2..4);
        let p = r.point(hit.p);
        assert!((p - Vec3::new(0.8, 0.4, 0.0)).length() < 1e-5, "{p}");
        assert!((r.point(r.from_rest.transform_point3(p)) - p).length() < 1e-5);
        // A slanted direction and the normal, there and back.
        let d = Vec3::new(1.0, 0.0, 1.0).normalize();
        let rest_d = r.direction(d);
        assert!(
            (rest_d - Vec3::new(1.0, 0.0, 1.5).normalize()).length() < 1e-5,
            "{rest_d}"
        );
        assert!((r.direction_back(rest_d) - d).length() < 1e-5);
        let n = r.normal(Vec3::Z);
        assert!((n - Vec3::Z).length() < 1e-6, "{n}");
        // A slanted surface's normal stays normal to it: its tangent
        // (1, 0, -1) at time 0.5 is (1, 0, -1.5) / 1.5 at the start.
        let n = r.normal(Vec3::new(1.0, 0.0, 1.0).normalize());
        assert!(
            n.dot(Vec3::Y).abs() < 1e-6 && n.dot(Vec3::new(1.0, 0.0, -1.5)).abs() < 1e-5,
            "{n}"
        );
        // The quad's area is 1.5 times its start's; a face across x keeps its own.
        assert!((r.area_scale(Vec3::Z) - 1.5).abs() < 1e-5);
        assert!((r.area_scale(Vec3::X) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn moving_spheres_and_disks_are_met_where_they_are_at_the_rays_time() {
        // A bump-mapped sphere (so that hits carry shading geometry)
        // sliding 2 along x and a disk sliding 2 along y over [0, 1],
        // against the same placed still where they are at time 0.5.
        let scene_of = |moving: bool| {
            let mut d = SceneDesc::empty("balls", builtin::cornell().camera);
            let base = Box::new(Material::diffuse(0.5, 0.5, 0.5));
            let displacement = Texture::from(Vec3::ZERO);
            let m = d.material("bumped", Material::Bumped { base, displacement });
            let (ball, plate) = if moving {
                (Vec3::ZERO, Vec3::new(0.0, 0.0, -2.0))
            } else {
                (Vec3::X, Vec3::new(0.0, 1.0, -2.0))
            };
            d.spheres.push(SphereDesc {
                sphere: Sphere {
                    centre: ball,
                    radius: 0.5,
                },
                material: m,
                axes: None,
            });
            d.disks.push(DiskDesc::new(plate, Vec3::Z, 0.5, 0.0, m));
            if moving {
                let slide = |v: Vec3| Motion::new(Mat4::IDENTITY, Mat4::from_translation(v), [0.0, 1.0]).unwrap();
                d.moving_shapes.push(MovingShape {
                    shape: CutShapes::Sphere(0),
                    motion: slide(2.0 * Vec3::X),
                });
                d.moving_shapes.push(MovingShape {
                    shape: CutShapes::Disk(0),
                    motion: slide(2.0 * Vec3::Y),
                });
            }
            Scene::build(d).unwrap()
        };
        let (moving, still) = (scene_of(true), scene_of(false));
        assert!(moving.has_motion());
        let down = |x: f32, y: f32, time: f32| Ray::timed(Vec3::new(x, y, 5.0), -Vec3::Z, time);
        for (x, y) in [(1.2, 0.1), (0.1, 1.2), (0.9, -0.2)] {
            let a = moving.intersect(&down(x, y, 0.5), 0.0, f32::INFINITY).unwrap();
            let b = still.intersect(&down(x, y, 0.0), 0.0, f32::INFINITY).unwrap();
            assert!((a.p - b.p).length() < 1e-5 && (a.t - b.t).abs() < 1e-5, "{a:?} {b:?}");
            assert!((a.ng - b.ng).length() < 1e-5 && (a.dpdu - b.dpdu).length() < 1e-4);
            assert_eq!((a.kind, a.object), (b.kind, b.object));
            assert!((a.uv - b.uv).length() < 1e-5);
            let (ga, gb) = (moving.surface(&a).shading.unwrap(), still.surface(&b).shading.unwrap());
            assert!(
                (ga.n - gb.n).length() < 1e-5 && (ga.dpdv - gb.dpdv).length() < 1e-4,
                "{ga:?} {gb:?}"
            );
            // The photon map's frame carries the hit back to the start.
            let r = moving.rest_frame(a.object, 0.5).unwrap();
            assert_eq!(r.objects, a.object..a.object + 1);
            let back = if a.kind == PrimKind::Sphere { Vec3::X } else { Vec3::Y };
            assert!((r.point(a.p) - (a.p - back)).length() < 1e-5);
            // At time 0 the ray passes where the shapes were not.
            assert!(moving.intersect(&down(x, y, 0.0), 0.0, f32::INFINITY).is_none());
            assert!(moving.occluded(&down(x, y, 0.5), 0.0, 10.0) && !moving.occluded(&down(x, y, 0.0), 0.0, 10.0));
        }
        // A sphere cut out, or given two motions, is refused.
        let mut d = moving.desc.clone();
        d.moving_shapes.push(d.moving_shapes[0].clone());
        let e = Scene::build(d).err().unwrap().to_string();
        assert!(e.contains("Sphere(0) is given two motions"), "{e}");
    }

    #[test]
    fn a_motion_beyond_finite_coordinates_is_refused() {
        let mut d = SceneDesc::empty("far", builtin::cornell().camera);
        let m = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
        d.triangles.extend(test_quad(m, 0.0, 1.0));
        let half_turn = Motion::new(Mat4::IDENTITY, Mat4::from_rotation_y(std::f32::consts::PI), [0.0, 1.0]).unwrap();
        d.moving.push(MovingTriangles {
            triangles: 0..2,
            motion: half_turn.about(Vec3::new(3e38, 0.0, 0.0)),
        });
        let e = Scene::build(d).err().unwrap().to_string();
        assert!(
            e.contains("moving triangles 0..2: their motion takes them beyond finite coordinates"),
            "{e}"
        );
    }

    #[test]
    fn a_moving_quad_is_met_where_it_is_at_the_rays_time() {
        let scene = scene_with(Mat4::from_translation(Vec3::new(2.0, 0.0, 0.0)));
        assert!(scene.has_motion());
        // (x of the ray, time, whether it meets the quad rather than the floor).
        for (x, time, on_quad) in [
            (0.5, 0.0, true),
            (2.5, 0.0, false),
            (2.5, 1.0, true),
            (0.5, 1.0, false),
            (1.5, 0.5, true),
            (1.5, 0.2, false),
            (1.5, 0.8, false),
            (1.5, 0.3, true),
        ] {
            let ray = down_at(x, 0.5, time);
            let hit = scene.intersect(&ray, 0.0, f32::INFINITY).unwrap();
            let z = if on_quad { 0.0 } else { -1.0 };
            assert!(
                (hit.p - Vec3::new(x, 0.5, z)).length() < 1e-5,
                "x {x} time {time}: {:?}",
                hit.p
            );
            assert!((hit.t - (1.0 - z)).abs() < 1e-5 && hit.time == time);
            assert_eq!(scene.occluded(&ray, 0.0, 1.5), on_quad, "x {x} time {time}");
            if on_quad {
                // Its texture coordinates move with it.
                let u = x - 2.0 * time;
                assert!((hit.uv - Vec2::new(u, 0.5)).length() < 1e-5, "{:?}", hit.uv);
            }
        }
        // The still scene's bounds hold the quad's whole path.
        assert!(scene.bounds().max.x >= 3.0 - 1e-4);
    }

    #[test]
    fn a_turning_quad_turns_its_normal_and_surface() {
        // A quarter turn about the x axis over the shutter: at time 0.5 the
        // quad leans 45 degrees and its normal with it.
        let scene = scene_with(Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2));
        let hit = scene.intersect(&down_at(0.5, 0.3, 0.5), 0.0, f32::INFINITY).unwrap();
        let h = std::f32::consts::FRAC_1_SQRT_2;
        // The plane through the x axis with normal (0, -h, h): z = y.
        assert!((hit.p - Vec3::new(0.5, 0.3, 0.3)).length() < 1e-4, "{:?}", hit.p);
        assert!((hit.ng - Vec3::new(0.0, -h, h)).length() < 1e-4, "{:?}", hit.ng);
        assert!((hit.ns - hit.ng).length() < 1e-4);
        assert!(hit.dpdu.dot(hit.ng).abs() < 1e-4);
        // The shading frame of its texture goes with it.
        let (g, [dpdu, dpdv]) = scene.shading_geometry(&hit).unwrap();
        assert!(dpdu.dot(hit.ng).abs() < 1e-4 && dpdv.dot(hit.ng).abs() < 1e-4);
        assert!((g.n - hit.ng).length() < 1e-4, "{:?}", g.n);
        assert!((dpdv - Vec3::new(0.0, h, h)).length() < 1e-4, "{dpdv:?}");
    }

    #[test]
    fn a_still_scene_keeps_its_camera_rays_at_time_zero() {
        let scene = Scene::build(builtin::cornell()).unwrap();
        assert!(!scene.has_motion() && scene.camera.shutter.is_none());
        let moving = scene_with(Mat4::from_translation(Vec3::X));
        assert_eq!(moving.camera.shutter, Some([0.0, 1.0]));
    }

    #[test]
    fn many_moving_quads_are_each_met_at_their_place() {
        // Twenty quads along x, each rising one unit along y over the
        // shutter, found through the tree over their boxes.
        let mut d = SceneDesc::empty("moving", builtin::cornell().camera);
        let m = d.material("grey", Material::diffuse(0.5, 0.5, 0.5));
        for k in 0..20 {
            let first = d.triangles.len();
            let shift = Vec3::new(2.0 * k as f32, 0.0, 0.0);
            d.triangles.extend(test_quad(m, 0.0, 1.0).map(|t| TriangleDesc {
                vertices: t.vertices.map(|v| v + shift),
                ..t
            }));
            d.moving.push(MovingTriangles {
                triangles: first..first + 2,
                motion: Motion::new(Mat4::IDENTITY, Mat4::from_translation(Vec3::Y), [0.0, 1.0]).unwrap(),
            });
        }
        let scene = Scene::build(d).unwrap();
        for k in 0..20 {
            for time in [0.0, 0.3, 0.9] {
                let x = 2.0 * k as f32 + 0.5;
                let hit = scene.intersect(&down_at(x, 0.9 + time, time), 0.0, f32::INFINITY);
                let hit = hit.unwrap_or_else(|| panic!("quad {k} at time {time} missed"));
                assert!(hit.object / 2 == k && (hit.p.z).abs() < 1e-5, "quad {k}: {hit:?}");
                assert!(scene
                    .intersect(&down_at(x, 1.1 + time, time), 0.0, f32::INFINITY)
                    .is_none());
                assert!(scene.occluded(&down_at(x, 0.9 + time, time), 0.0, 2.0));
                assert!(!scene.occluded(&down_at(x + 1.0, 0.5 + time, time), 0.0, 2.0));
            }
        }
    }

    #[test]
    fn bad_runs_of_moving_triangles_are_refused() {
        let mut d = SceneDesc::empty("moving", builtin::cornell().camera);
        d.moving.push(MovingTriangles {
            triangles: 0..3,
            motion: Motion::new(Mat4::IDENTITY, Mat4::from_translation(Vec3::X), [0.0, 1.0]).unwrap(),
        });
        assert!(Scene::build(d).is_err());
    }
}
