//! What a pbrt-v4 scene says, independent of this renderer: the scene-wide
//! settings, materials, textures, lights and shapes, every transform already
//! composed into world space, object instances flattened, each thing with the
//! place in the file that made it.

use super::error::Loc;
use super::params::Params;
use crate::math::{Vec2, Vec3};
use glam::Mat4;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// A scene-wide setting (`Film`, `Sampler`, `PixelFilter`, `Integrator`,
/// `Accelerator`): its type and parameters. `loc` is None where the file
/// does not give the directive and pbrt-v4's default applies (film `rgb`,
/// sampler `zsobol`, filter `gaussian`, integrator `volpath`, accelerator
/// `bvh`, all with no parameters).
#[derive(Clone, Debug, PartialEq)]
pub struct Entity {
    pub ty: String,
    pub params: Params,
    pub loc: Option<Loc>,
}

impl Entity {
    pub fn default_of(ty: &str) -> Entity {
        Entity {
            ty: ty.to_string(),
            params: Params::default(),
            loc: None,
        }
    }
}

/// The `Camera` directive (default: `perspective`, identity transform).
///
/// pbrt-v4's camera space is left-handed: +x is right in the image, +y up,
/// +z the viewing direction. `camera_from_world` is the transformation in
/// force at the `Camera` directive (pbrt's CTM), `world_from_camera` its
/// inverse; the named coordinate system `camera` is `world_from_camera`.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub ty: String,
    pub params: Params,
    pub loc: Option<Loc>,
    pub camera_from_world: Mat4,
    pub world_from_camera: Mat4,
    /// Camera to world at the end of the transformation times, for a camera
    /// that moves (`ActiveTransform`).
    pub world_from_camera_end: Option<Mat4>,
    /// The outside medium of `MediumInterface` at the `Camera` directive.
    pub medium: Option<String>,
}

impl Camera {
    /// A perspective camera's screen window `[xmin, xmax, ymin, ymax]` for a
    /// film of `width` x `height` pixels, as pbrt-v4's `PerspectiveCamera::Create`:
    /// the `screenwindow` parameter if given, else [-1, 1] on the shorter
    /// image axis and [-a, a] on the longer, a being the `frameaspectratio`
    /// parameter (default width / height) or its inverse.
    ///
    /// With `t = tan(fov / 2)` (`fov` in degrees, default 90), pbrt's camera
    /// ray through raster point (x, y) (x right, y down, in pixels over the
    /// full resolution) has the camera-space direction
    /// `(sx * t, sy * t, 1)` where `sx = xmin + x / width * (xmax - xmin)`
    /// and `sy = ymax - y / height * (ymax - ymin)`; so `fov` spans the
    /// shorter image axis. `world_from_camera` takes it to world space.
    pub fn screen_window(&self, width: u32, height: u32) -> super::error::Result<[f32; 4]> {
        let frame = self
            .params
            .get_float("frameaspectratio", width as f32 / height.max(1) as f32)?;
        let mut w = if frame > 1.0 {
            [-frame, frame, -1.0, 1.0]
        } else {
            [-1.0, 1.0, -1.0 / frame, 1.0 / frame]
        };
        let sw = self.params.get_floats("screenwindow");
        if sw.len() == 4 {
            w.copy_from_slice(sw);
        } else if !sw.is_empty() {
            if let Some(p) = self.params.get("screenwindow") {
                return Err(super::error::PbrtError::at(
                    &p.loc,
                    format!("\"screenwindow\" needs four values, not {}", sw.len()),
                ));
            }
        }
        Ok(w)
    }
}

/// A material: `Material` (anonymous, `name` None) or `MakeNamedMaterial`
/// (its `"string type"` taken out of the parameters into `ty`).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: Option<String>,
    pub ty: String,
    pub params: Params,
    /// None for the default material (`diffuse`, no parameters) shapes get
    /// before any `Material` or `NamedMaterial`.
    pub loc: Option<Loc>,
}

/// Whether a texture gives a float or a spectrum.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TextureKind {
    Float,
    Spectrum,
}

/// `Texture "name" "float"|"spectrum" "class" params`.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub kind: TextureKind,
    /// `imagemap`, `checkerboard`, `scale`, `mix`, `constant`...
    pub class: String,
    pub params: Params,
    /// The transformation in force at the directive (pbrt's texture space for
    /// 3D mappings).
    pub world_from_texture: Mat4,
    pub loc: Loc,
}

/// `LightSource`.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub ty: String,
    pub params: Params,
    pub world_from_light: Mat4,
    pub medium: Option<String>,
    pub loc: Loc,
}

/// `AreaLightSource`: emission of the shapes that follow it in its attribute
/// block. Shapes refer to it by index, so its parameters are read once.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLight {
    pub ty: String,
    pub params: Params,
    pub loc: Loc,
}

/// `MakeNamedMedium` (its `"string type"` taken out into `ty`).
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    pub name: String,
    pub ty: String,
    pub params: Params,
    pub world_from_medium: Mat4,
    pub loc: Loc,
    /// A `nanovdb` medium's file: where it was found, and its bytes.
    pub file: Option<(PathBuf, Arc<Vec<u8>>)>,
}

/// A triangle mesh in object space: from `trianglemesh` (its `P`, `N`, `uv`,
/// `indices`), `bilinearmesh` and `plymesh` (each bilinear patch as two
/// triangles), with every index checked against `positions`.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, as many as positions.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, as many as positions.
    pub uvs: Option<Vec<Vec2>>,
    pub triangles: Vec<[u32; 3]>,
    /// How many bilinear patches (quads) were split into two triangles each:
    /// exact for planar quads, an approximation of pbrt's curved patch for
    /// others.
    pub quads_split: usize,
    /// Which triangles are the second half of a split patch (empty where
    /// none is): without `uv`, pbrt-v4 gives a patch its own (u, v), which
    /// at this half's vertices is (0, 0), (1, 1), (0, 1), where a lone
    /// triangle's is (0, 0), (1, 0), (1, 1).
    pub second_halves: Vec<bool>,
    /// The mesh file, for `plymesh`.
    pub file: Option<PathBuf>,
    /// A quadric made a mesh (`cylinder`, and a partial or stretched
    /// `sphere` or `disk`): its normals turn, as pbrt-v4 turns a quadric's,
    /// under a transformation that swaps handedness too, not only under
    /// `ReverseOrientation` as a mesh's do.
    pub quadric: bool,
}

impl TriMesh {
    /// Texture coordinates at triangle `k`'s vertices as pbrt-v4 reports
    /// them: the mesh's `uv`; without, a split patch's own, or None for a
    /// triangle's default.
    pub fn triangle_uvs(&self, k: usize) -> Option<[Vec2; 3]> {
        match &self.uvs {
            Some(uv) => Some(self.triangles[k].map(|i| uv[i as usize])),
            None if self.second_halves.get(k) == Some(&true) => Some([Vec2::ZERO, Vec2::ONE, Vec2::new(0.0, 1.0)]),
            None => None,
        }
    }
}

/// A (possibly partial) sphere, pbrt-v4's defaults: radius 1, zmin = -radius,
/// zmax = radius, phimax 360 degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub radius: f32,
    pub zmin: f32,
    pub zmax: f32,
    pub phimax_deg: f32,
}

impl Sphere {
    /// Whether it is cut by zmin, zmax or phimax.
    pub fn is_partial(&self) -> bool {
        let r = self.radius.abs();
        self.zmin.max(-r) > -r || self.zmax.min(r) < r || self.phimax_deg.clamp(0.0, 360.0) < 360.0
    }
}

/// A `curve` shape's cubic Bezier segments in object space (B-splines and
/// quadratics turned into them, as pbrt-v4 does), each with its widths at
/// its ends, split into 2^`split_depth` pieces when placed.
#[derive(Clone, Debug, PartialEq)]
pub struct Curves {
    pub segments: Vec<[Vec3; 4]>,
    pub widths: Vec<[f32; 2]>,
    pub kind: crate::geometry::CurveKind,
    pub split_depth: u32,
    /// A ribbon's unit normals `N` (object space) at the segments' ends:
    /// one more than the segments; empty for the other kinds.
    pub normals: Vec<Vec3>,
}

/// A disk in the z = height plane, pbrt-v4's defaults: height 0, radius 1,
/// innerradius 0, phimax 360 degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    pub height: f32,
    pub radius: f32,
    pub inner_radius: f32,
    pub phimax_deg: f32,
}

impl Disk {
    /// Whether it is cut by phimax (a hole, `innerradius`, is supported).
    pub fn is_partial(&self) -> bool {
        self.phimax_deg.clamp(0.0, 360.0) < 360.0
    }
}

/// What a shape is, where the reader decodes it.
#[derive(Clone, Debug, PartialEq)]
pub enum Geometry {
    Mesh(Arc<TriMesh>),
    Sphere(Sphere),
    Disk(Disk),
    Curves(Curves),
    /// A shape type the reader does not decode (`cylinder`, a `ribbon`
    /// curve, or not a pbrt-v4 type); listed in `PbrtScene::unsupported`.
    Other,
}

/// The `ObjectInstance` a shape came from.
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceUse {
    pub object: String,
    /// Where the `ObjectInstance` directive is.
    pub loc: Loc,
}

/// A `Shape`, placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    pub ty: String,
    /// Shared between the copies of an instanced shape.
    pub params: Arc<Params>,
    pub geometry: Geometry,
    /// Object to world: for an instanced shape, the transformation at the
    /// `ObjectInstance` times the one at the `Shape` inside `ObjectBegin`.
    pub world_from_object: Mat4,
    /// For a shape that moves (`ActiveTransform`), the transformations at
    /// the start and end of the transformation times that are interpolated
    /// (pbrt-v4's `AnimatedTransform`): the shape's own, or the moving
    /// `ObjectInstance`'s, whose shapes keep their transformation within it.
    /// `None` for a shape that holds still.
    pub motion: Option<[Mat4; 2]>,
    /// `ReverseOrientation` in force at the shape.
    pub reverse_orientation: bool,
    /// Index into `PbrtScene::materials`.
    pub material: usize,
    /// Index into `PbrtScene::area_lights`.
    pub area_light: Option<usize>,
    /// `MediumInterface` in force: (inside, outside); empty names are None.
    pub inside_medium: Option<String>,
    pub outside_medium: Option<String>,
    pub instance: Option<InstanceUse>,
    pub loc: Loc,
}

impl Shape {
    /// Whether pbrt-v4 turns the shape's surface normal (and with it the side
    /// a one-sided area light emits from) around: `ReverseOrientation` xor a
    /// transformation that swaps handedness (negative determinant).
    ///
    /// For a triangle (p0, p1, p2) placed in world space, pbrt-v4's geometric
    /// normal is `cross(p1 - p0, p2 - p0)`, negated when this is true (for
    /// meshes with shading normals pbrt then turns it to their side); for a
    /// sphere or disk it is the outward (disk: +z) normal carried to world
    /// space as a normal, negated when this is true. This holds for
    /// instanced shapes too.
    pub fn flips_normals(&self) -> bool {
        self.reverse_orientation ^ (self.world_from_object.determinant() < 0.0)
    }
}

/// A warning or an unsupported feature, at its place.
#[derive(Clone, Debug, PartialEq)]
pub struct Note {
    pub loc: Loc,
    pub message: String,
}

/// An `Option` directive: name and value as written (a string value keeps
/// its quotes, as pbrt-v4 passes it on).
#[derive(Clone, Debug, PartialEq)]
pub struct OptionSetting {
    pub name: String,
    pub value: String,
    pub loc: Loc,
}

/// A whole pbrt-v4 scene.
#[derive(Clone, Debug, PartialEq)]
pub struct PbrtScene {
    pub camera: Camera,
    pub film: Entity,
    pub sampler: Entity,
    pub filter: Entity,
    pub integrator: Entity,
    pub accelerator: Entity,
    pub options: Vec<OptionSetting>,
    /// Index 0 is pbrt's default material; then every `Material` and
    /// `MakeNamedMaterial` in the order of the file.
    pub materials: Vec<Material>,
    /// Named materials by name, indices into `materials`.
    pub named_materials: HashMap<String, usize>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    pub area_lights: Vec<AreaLight>,
    pub media: Vec<Medium>,
    pub shapes: Vec<Shape>,
    /// Things that did not stop the reading but pbrt-v4 would mention (a
    /// PLY face with five vertices, an unknown coordinate system...).
    pub warnings: Vec<Note>,
    /// Things the scene uses that this reader does not express: partial
    /// spheres and disks, shape types it does not decode, media, motion
    /// (`ActiveTransform`), displacement. Whether they are errors is the
    /// converter's decision.
    pub unsupported: Vec<Note>,
    /// `TransformTimes`: the times of the start and end transformations.
    pub transform_times: [f32; 2],
    /// Every file read: the scene, its Includes and Imports, its meshes.
    pub files: Vec<PathBuf>,
    /// The folder of the top-level scene file (pbrt-v4's search directory).
    pub scene_dir: PathBuf,
}

impl PbrtScene {
    /// The texture of this name and kind.
    pub fn texture(&self, name: &str, kind: TextureKind) -> Option<&Texture> {
        self.textures.iter().find(|t| t.name == name && t.kind == kind)
    }

    /// The named material of this name.
    pub fn named_material(&self, name: &str) -> Option<&Material> {
        self.named_materials.get(name).map(|&i| &self.materials[i])
    }

    /// Where a file named in a directive at `loc` (an image texture's
    /// `filename`, say) may be, in the order to try: beside the file that
    /// names it, then in the top-level scene's folder (where pbrt-v4 looks).
    pub fn candidates(&self, loc: &Loc, name: &str) -> Vec<PathBuf> {
        super::builder::candidates(&loc.file, &self.scene_dir, name)
    }

    /// Triangles in all meshes (each copy of an instance counted).
    pub fn triangle_count(&self) -> usize {
        self.shapes
            .iter()
            .map(|s| match &s.geometry {
                Geometry::Mesh(m) => m.triangles.len(),
                _ => 0,
            })
            .sum()
    }
}
