//! The scene file's tables as serde reads them. Each shape is one flat table
//! with a `type` key rather than a serde tagged enum, because a tagged enum is
//! buffered before it is read and its errors lose their line.

use crate::math::Vec3;
use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

/// A finite number (TOML reads f64; we keep the nearest f32).
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "f64")]
pub(super) struct Num(pub(super) f32);

impl TryFrom<f64> for Num {
    type Error = String;
    fn try_from(v: f64) -> std::result::Result<Self, String> {
        let f = v as f32;
        if f.is_finite() {
            Ok(Num(f))
        } else {
            Err(format!("{v} is not a finite single-precision number"))
        }
    }
}

/// Three finite numbers: a point, a direction or an RGB colour.
#[derive(Clone, Copy, Debug, Deserialize)]
// Read as a list: serde's fixed-size arrays take the first three values of
// a longer one and drop the rest unseen.
#[serde(try_from = "Vec<f64>")]
pub(super) struct Vec3Spec(pub(super) Vec3);

impl TryFrom<Vec<f64>> for Vec3Spec {
    type Error = String;
    fn try_from(v: Vec<f64>) -> std::result::Result<Self, String> {
        if v.len() != 3 {
            return Err(format!("expected an array of three numbers, found {} numbers", v.len()));
        }
        let p = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
        if p.is_finite() {
            Ok(Vec3Spec(p))
        } else {
            Err(format!(
                "{v:?} has a number that is not a finite single-precision number"
            ))
        }
    }
}

/// Two finite numbers: texture coordinates.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "Vec<Num>")]
pub(super) struct UvSpec(pub(super) [Num; 2]);

impl TryFrom<Vec<Num>> for UvSpec {
    type Error = String;
    fn try_from(v: Vec<Num>) -> std::result::Result<Self, String> {
        match v[..] {
            [u, v] => Ok(UvSpec([u, v])),
            _ => Err(format!("expected an array of two numbers, found {} numbers", v.len())),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) name: Option<String>,
    pub(super) camera: Spanned<CameraSpec>,
    pub(super) settings: Option<Spanned<BTreeMap<String, Spanned<toml::Value>>>>,
    #[serde(default)]
    pub(super) textures: BTreeMap<String, Spanned<super::materials::Table>>,
    #[serde(default)]
    pub(super) materials: BTreeMap<String, Spanned<super::materials::Table>>,
    #[serde(default)]
    pub(super) lights: Vec<Spanned<LightSpec>>,
    #[serde(default)]
    pub(super) shapes: Vec<Spanned<ShapeSpec>>,
    #[serde(default)]
    pub(super) media: BTreeMap<String, Spanned<MediumSpec>>,
}

/// A `[media.NAME]` table: a homogeneous medium.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MediumSpec {
    pub(super) sigma_a: Option<RgbSpec>,
    pub(super) sigma_s: Option<RgbSpec>,
    pub(super) g: Option<Num>,
    pub(super) le: Option<RgbSpec>,
}

/// A number for all three channels, or one each.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(untagged, expecting = "a number or an array of three numbers")]
pub(super) enum RgbSpec {
    Grey(Num),
    Rgb(Vec3Spec),
}

impl RgbSpec {
    pub(super) fn rgb(self) -> Vec3 {
        match self {
            RgbSpec::Grey(n) => Vec3::splat(n.0),
            RgbSpec::Rgb(v) => v.0,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraSpec {
    pub(super) position: Vec3Spec,
    pub(super) look_at: Vec3Spec,
    pub(super) up: Option<Vec3Spec>,
    /// Required but for a spherical camera, which has none.
    pub(super) fov_y: Option<Num>,
    pub(super) width: Option<u32>,
    pub(super) height: Option<u32>,
    pub(super) lens_radius: Option<Num>,
    pub(super) focal_distance: Option<Num>,
    /// The medium the camera is in.
    pub(super) medium: Option<Spanned<String>>,
    /// A spherical camera's layout: "equalarea" or "equirectangular".
    pub(super) spherical: Option<String>,
    /// A real lens: a prescription in pbrt-v4's format, relative to the
    /// scene file, with its stop's diameter (mm; the lens' own by default),
    /// the distance in focus (that to `look_at` by default), the film's
    /// diagonal (mm, 35) and the diaphragm's shape (round by default).
    pub(super) lens_file: Option<Spanned<String>>,
    pub(super) aperture: Option<Num>,
    pub(super) focus_distance: Option<Num>,
    pub(super) film_diagonal: Option<Num>,
    pub(super) aperture_shape: Option<String>,
    /// When the shutter opens and closes, as fractions of shapes'
    /// `motion` (which runs from 0 to 1).
    pub(super) shutter: Option<Spanned<Vec<Num>>>,
    /// Where the camera moves while the shutter is open (turning about
    /// its position unless `about` is given).
    pub(super) motion: Option<Spanned<MotionSpec>>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum LightKind {
    Sphere,
    Point,
    Triangle,
    Quad,
    Disk,
    Spot,
    Distant,
    Infinite,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LightSpec {
    #[serde(rename = "type")]
    pub(super) kind: LightKind,
    pub(super) centre: Option<Vec3Spec>,
    pub(super) radius: Option<Num>,
    pub(super) position: Option<Vec3Spec>,
    pub(super) power: Option<Num>,
    pub(super) colour: Option<Vec3Spec>,
    /// Triangle and quad lights: corners, radiance, whether both sides emit.
    pub(super) vertices: Option<Vec<Vec3Spec>>,
    pub(super) radiance: Option<Vec3Spec>,
    pub(super) two_sided: Option<bool>,
    /// Spot and distant lights: the direction of the axis, of travel.
    pub(super) direction: Option<Vec3Spec>,
    /// Spot lights: intensity (W/sr) and the cone (degrees).
    pub(super) intensity: Option<Vec3Spec>,
    pub(super) cone_angle: Option<Num>,
    pub(super) cone_delta: Option<Num>,
    /// Spot, distant and infinite lights: a factor on intensity or radiance.
    pub(super) scale: Option<Num>,
    /// Infinite lights: an environment image, how it covers the sphere, its rotation.
    pub(super) file: Option<String>,
    pub(super) mapping: Option<String>,
    pub(super) rotate: Option<Vec3Spec>,
    /// Infinite lights: the corners of a rectangle (a window) through which
    /// alone its light enters.
    pub(super) portal: Option<Vec<Vec3Spec>>,
    /// Disk lights: the side the disk faces, the radius of its hole.
    pub(super) normal: Option<Vec3Spec>,
    pub(super) inner_radius: Option<Num>,
    /// Lights with a surface: the material it also reflects by.
    pub(super) material: Option<Spanned<String>>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum ShapeKind {
    Triangle,
    Quad,
    Box,
    Sphere,
    Disk,
    Mesh,
}

#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(untagged, expecting = "a number or an array of three numbers")]
pub(super) enum ScaleSpec {
    Uniform(Num),
    PerAxis(Vec3Spec),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FitSpec {
    pub(super) height: Num,
    pub(super) bottom_centre: Vec3Spec,
}

/// A shape's `alpha`: a number or the name of a texture.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged, expecting = "a number or the name of a texture")]
pub(super) enum AlphaSpec {
    Value(Num),
    Texture(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ShapeSpec {
    #[serde(rename = "type")]
    pub(super) kind: ShapeKind,
    pub(super) material: Option<Spanned<String>>,
    pub(super) vertices: Option<Vec<Vec3Spec>>,
    pub(super) normals: Option<Vec<Vec3Spec>>,
    /// Texture coordinates per vertex (triangles and quads).
    pub(super) uvs: Option<Vec<UvSpec>>,
    pub(super) min: Option<Vec3Spec>,
    pub(super) max: Option<Vec3Spec>,
    pub(super) centre: Option<Vec3Spec>,
    pub(super) radius: Option<Num>,
    pub(super) normal: Option<Vec3Spec>,
    pub(super) inner_radius: Option<Num>,
    pub(super) path: Option<String>,
    pub(super) scale: Option<ScaleSpec>,
    pub(super) rotate: Option<Vec3Spec>,
    pub(super) translate: Option<Vec3Spec>,
    pub(super) fit: Option<FitSpec>,
    pub(super) smooth: Option<bool>,
    /// Cuts the shape out where below 1 (pbrt-v4's `alpha`).
    pub(super) alpha: Option<Spanned<AlphaSpec>>,
    /// The media behind and in front of the surface (against and along its
    /// normal), when it bounds any.
    pub(super) medium_inside: Option<Spanned<String>>,
    pub(super) medium_outside: Option<Spanned<String>>,
    /// Where the shape moves to while the shutter is open.
    pub(super) motion: Option<Spanned<MotionSpec>>,
}

/// A shape's `motion`: from where the shape is placed when the shutter
/// opens to where this takes it when it closes: scaled, then rotated
/// (degrees about x, then y, then z) about `about` (the centre of the
/// shape's bounding box unless given), then translated.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MotionSpec {
    pub(super) translate: Option<Vec3Spec>,
    pub(super) rotate: Option<Vec3Spec>,
    pub(super) scale: Option<ScaleSpec>,
    pub(super) about: Option<Vec3Spec>,
}

impl ShapeSpec {
    /// The optional keys that are present, by name.
    pub(super) fn given(&self) -> [(&'static str, bool); 20] {
        [
            ("uvs", self.uvs.is_some()),
            ("material", self.material.is_some()),
            ("vertices", self.vertices.is_some()),
            ("normals", self.normals.is_some()),
            ("min", self.min.is_some()),
            ("max", self.max.is_some()),
            ("centre", self.centre.is_some()),
            ("radius", self.radius.is_some()),
            ("normal", self.normal.is_some()),
            ("inner_radius", self.inner_radius.is_some()),
            ("path", self.path.is_some()),
            ("scale", self.scale.is_some()),
            ("rotate", self.rotate.is_some()),
            ("translate", self.translate.is_some()),
            ("fit", self.fit.is_some()),
            ("smooth", self.smooth.is_some()),
            ("alpha", self.alpha.is_some()),
            ("medium_inside", self.medium_inside.is_some()),
            ("medium_outside", self.medium_outside.is_some()),
            ("motion", self.motion.is_some()),
        ]
    }
}

const MI: &str = "medium_inside";
const MO: &str = "medium_outside";

impl ShapeKind {
    pub(super) fn name(self) -> &'static str {
        match self {
            ShapeKind::Triangle => "triangle",
            ShapeKind::Quad => "quad",
            ShapeKind::Box => "box",
            ShapeKind::Sphere => "sphere",
            ShapeKind::Disk => "disk",
            ShapeKind::Mesh => "mesh",
        }
    }

    /// Keys each shape type reads besides `type`.
    pub(super) fn keys(self) -> &'static [&'static str] {
        match self {
            ShapeKind::Triangle => &["material", "vertices", "normals", "uvs", "alpha", MI, MO, "motion"],
            ShapeKind::Quad => &["material", "vertices", "uvs", "alpha", MI, MO, "motion"],
            ShapeKind::Box => &["material", "min", "max", "alpha", MI, MO, "motion"],
            ShapeKind::Sphere => &["material", "centre", "radius", "alpha", MI, MO, "motion"],
            ShapeKind::Disk => &[
                "material",
                "centre",
                "normal",
                "radius",
                "inner_radius",
                "alpha",
                MI,
                MO,
                "motion",
            ],
            ShapeKind::Mesh => &[
                "material",
                "path",
                "scale",
                "rotate",
                "translate",
                "fit",
                "smooth",
                "alpha",
                MI,
                MO,
                "motion",
            ],
        }
    }
}
