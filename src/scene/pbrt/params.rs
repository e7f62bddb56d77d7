//! Parameter lists, `"type name" value` or `"type name" [ values ]`, and
//! typed look-ups that remember what was read (pbrt-v4's
//! `ParameterDictionary`, paramdict.cpp).
//!
//! Types and their values, checked when the file is read: `float`,
//! `integer`, `bool`, `string`, `point2`, `vector2`, `point3`, `vector3`,
//! `normal` (also `normal3`), `rgb`, `blackbody` (one temperature per
//! value), `spectrum` (named spectra or wavelength/value pairs), `texture`
//! (a texture's name). The pbrt-v3 names `point`, `vector` and `color` are
//! read as `point3`, `vector3` and `rgb`. Point, vector, normal and rgb lists
//! must hold a multiple of their size; a spectrum's wavelengths must
//! increase; a spectrum named by a string must be one pbrt-v4 knows (a
//! spectrum file is an error: this reader reads none).
//!
//! A directive's parameters come first, then those of the `Attribute`
//! directives in force (pbrt's order: later values win within each). A
//! look-up finds the first parameter of the name *and* type; one of the same
//! name and another type is not found, stays unread, and [`Params::unused`]
//! lists it, as pbrt-v4 reports unused parameters. Single-value look-ups are
//! `Result`s: a parameter of the right type with more than one value is an
//! error at its place, as in pbrt.

use super::error::{Loc, PbrtError, Result};
use super::spectrum::{SampledSpectrum, SpectrumValue};
use crate::math::{Vec2, Vec3};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParamType {
    Float,
    Integer,
    Bool,
    String,
    Point2,
    Vector2,
    Point3,
    Vector3,
    Normal,
    Rgb,
    Blackbody,
    Spectrum,
    Texture,
}

impl ParamType {
    /// The type a declaration names; pbrt-v3's `point`, `vector`, `color`
    /// and the spelling `normal3` are accepted.
    pub fn parse(name: &str) -> Option<ParamType> {
        Some(match name {
            "float" => ParamType::Float,
            "integer" => ParamType::Integer,
            "bool" => ParamType::Bool,
            "string" => ParamType::String,
            "point2" => ParamType::Point2,
            "vector2" => ParamType::Vector2,
            "point3" | "point" => ParamType::Point3,
            "vector3" | "vector" => ParamType::Vector3,
            "normal" | "normal3" => ParamType::Normal,
            "rgb" | "color" => ParamType::Rgb,
            "blackbody" => ParamType::Blackbody,
            "spectrum" => ParamType::Spectrum,
            "texture" => ParamType::Texture,
            _ => return None,
        })
    }

    /// pbrt-v4's name of the type.
    pub fn name(self) -> &'static str {
        match self {
            ParamType::Float => "float",
            ParamType::Integer => "integer",
            ParamType::Bool => "bool",
            ParamType::String => "string",
            ParamType::Point2 => "point2",
            ParamType::Vector2 => "vector2",
            ParamType::Point3 => "point3",
            ParamType::Vector3 => "vector3",
            ParamType::Normal => "normal",
            ParamType::Rgb => "rgb",
            ParamType::Blackbody => "blackbody",
            ParamType::Spectrum => "spectrum",
            ParamType::Texture => "texture",
        }
    }

    /// Numbers per item for the numeric types.
    pub fn per_item(self) -> usize {
        match self {
            ParamType::Point2 | ParamType::Vector2 => 2,
            ParamType::Point3 | ParamType::Vector3 | ParamType::Normal | ParamType::Rgb => 3,
            _ => 1,
        }
    }

    pub fn is_spectrum(self) -> bool {
        matches!(self, ParamType::Rgb | ParamType::Blackbody | ParamType::Spectrum)
    }
}

/// A parameter's values, as the file gave them.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    Floats(Vec<f32>),
    Ints(Vec<i32>),
    Bools(Vec<bool>),
    Strings(Vec<String>),
}

impl Values {
    pub fn len(&self) -> usize {
        match self {
            Values::Floats(v) => v.len(),
            Values::Ints(v) => v.len(),
            Values::Bools(v) => v.len(),
            Values::Strings(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One parameter.
#[derive(Debug)]
pub struct Param {
    pub ty: ParamType,
    pub name: String,
    pub values: Values,
    /// Where its `"type name"` string is.
    pub loc: Loc,
    /// The colour space in force where it was given (`ColorSpace`), for `rgb`.
    pub color_space: Arc<str>,
    /// Given by an `Attribute` directive: never reported as unused.
    pub from_attribute: bool,
    used: AtomicBool,
}

impl Clone for Param {
    fn clone(&self) -> Self {
        Param {
            ty: self.ty,
            name: self.name.clone(),
            values: self.values.clone(),
            loc: self.loc.clone(),
            color_space: self.color_space.clone(),
            from_attribute: self.from_attribute,
            used: AtomicBool::new(self.used()),
        }
    }
}

impl PartialEq for Param {
    fn eq(&self, o: &Self) -> bool {
        self.ty == o.ty && self.name == o.name && self.values == o.values && self.loc == o.loc
    }
}

impl Param {
    pub fn new(ty: ParamType, name: String, values: Values, loc: Loc, color_space: Arc<str>) -> Param {
        Param {
            ty,
            name,
            values,
            loc,
            color_space,
            from_attribute: false,
            used: AtomicBool::new(false),
        }
    }

    /// Whether a look-up has read it.
    pub fn used(&self) -> bool {
        self.used.load(Ordering::Relaxed)
    }

    fn mark(&self) {
        self.used.store(true, Ordering::Relaxed);
    }

    fn floats(&self) -> &[f32] {
        match &self.values {
            Values::Floats(v) => v,
            _ => &[],
        }
    }

    fn single_error(&self) -> PbrtError {
        PbrtError::at(
            &self.loc,
            format!(
                "\"{} {}\": expected one value, got {}",
                self.ty.name(),
                self.name,
                self.values.len() / self.ty.per_item()
            ),
        )
    }

    /// The spectrum values of an `rgb`, `blackbody` or `spectrum` parameter.
    pub fn spectra(&self) -> Vec<SpectrumValue> {
        match (self.ty, &self.values) {
            (ParamType::Rgb, Values::Floats(f)) => f
                .chunks_exact(3)
                .map(|c| SpectrumValue::Rgb(Vec3::new(c[0], c[1], c[2])))
                .collect(),
            (ParamType::Blackbody, Values::Floats(f)) => f.iter().map(|&t| SpectrumValue::Blackbody(t)).collect(),
            (ParamType::Spectrum, Values::Strings(s)) => s.iter().map(|n| SpectrumValue::Named(n.clone())).collect(),
            (ParamType::Spectrum, Values::Floats(f)) => vec![SpectrumValue::Sampled(SampledSpectrum {
                lambda: f.iter().step_by(2).copied().collect(),
                value: f.iter().skip(1).step_by(2).copied().collect(),
            })],
            _ => vec![],
        }
    }
}

/// A float parameter that may be given by a texture instead.
#[derive(Clone, Debug, PartialEq)]
pub enum FloatOrTexture {
    Value(f32),
    Texture(String),
}

/// A spectrum parameter that may be given by a texture instead.
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumOrTexture {
    Value(SpectrumValue),
    Texture(String),
}

/// A directive's parameters with the attributes in force, and which of them
/// have been read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params {
    /// The directive's own parameters, in the file's order.
    own: Vec<Param>,
    /// The `Attribute` parameters in force, in the order they were given.
    attributes: Vec<Param>,
    /// Whether the directive was taken up at all (a texture is converted
    /// only where something names it).
    touched: Touched,
}

/// A flag set through a shared reference, which does not take part in
/// comparisons.
#[derive(Debug, Default)]
struct Touched(AtomicBool);

impl Clone for Touched {
    fn clone(&self) -> Self {
        Touched(AtomicBool::new(self.0.load(Ordering::Relaxed)))
    }
}

impl PartialEq for Touched {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl Params {
    pub fn new(own: Vec<Param>) -> Params {
        Params {
            own,
            ..Params::default()
        }
    }

    pub fn with_attributes(own: Vec<Param>, attributes: &[Param]) -> Params {
        Params {
            own,
            attributes: attributes.to_vec(),
            ..Params::default()
        }
    }

    /// Marks the directive as taken up: its unread parameters are then
    /// reported (see `touched`).
    pub fn touch(&self) {
        self.touched.0.store(true, Ordering::Relaxed);
    }

    /// Whether the directive was taken up ([`Params::touch`]) or any of its
    /// own parameters read.
    pub fn touched(&self) -> bool {
        self.touched.0.load(Ordering::Relaxed) || self.own.iter().any(Param::used)
    }

    /// Every parameter in look-up order: own ones last-given first, then attributes.
    pub fn iter(&self) -> impl Iterator<Item = &Param> {
        self.own.iter().rev().chain(self.attributes.iter().rev())
    }

    /// The directive's own parameters, in the file's order.
    pub fn own(&self) -> &[Param] {
        &self.own
    }

    pub fn is_empty(&self) -> bool {
        self.own.is_empty() && self.attributes.is_empty()
    }

    fn find(&self, name: &str, ty: ParamType) -> Option<&Param> {
        self.iter().find(|p| p.name == name && p.ty == ty)
    }

    /// Whether a parameter of this name (any type) is there; reads nothing.
    pub fn has(&self, name: &str) -> bool {
        self.iter().any(|p| p.name == name)
    }

    /// The parameter of this name that a look-up would find first (any type),
    /// without marking it read: for messages about it.
    pub fn get(&self, name: &str) -> Option<&Param> {
        self.iter().find(|p| p.name == name)
    }

    /// Where the parameter of this name is (any type).
    pub fn loc_of(&self, name: &str) -> Option<&Loc> {
        self.get(name).map(|p| &p.loc)
    }

    /// Marks the parameter of this name and type read (e.g. one a converter
    /// deliberately ignores, such as the film's `filename`).
    pub fn mark_used(&self, name: &str, ty: ParamType) {
        if let Some(p) = self.find(name, ty) {
            p.mark();
        }
    }

    fn single(&self, name: &str, ty: ParamType) -> Result<Option<&Param>> {
        let Some(p) = self.find(name, ty) else {
            return Ok(None);
        };
        if p.values.len() != ty.per_item() {
            return Err(p.single_error());
        }
        p.mark();
        Ok(Some(p))
    }

    pub fn get_float(&self, name: &str, default: f32) -> Result<f32> {
        Ok(self
            .single(name, ParamType::Float)?
            .and_then(|p| p.floats().first().copied())
            .unwrap_or(default))
    }

    pub fn get_int(&self, name: &str, default: i32) -> Result<i32> {
        Ok(match self.single(name, ParamType::Integer)? {
            Some(Param {
                values: Values::Ints(v),
                ..
            }) if !v.is_empty() => v[0],
            _ => default,
        })
    }

    pub fn get_bool(&self, name: &str, default: bool) -> Result<bool> {
        Ok(match self.single(name, ParamType::Bool)? {
            Some(Param {
                values: Values::Bools(v),
                ..
            }) if !v.is_empty() => v[0],
            _ => default,
        })
    }

    pub fn get_string(&self, name: &str) -> Result<Option<String>> {
        Ok(match self.single(name, ParamType::String)? {
            Some(Param {
                values: Values::Strings(v),
                ..
            }) => v.first().cloned(),
            _ => None,
        })
    }

    pub fn get_string_or(&self, name: &str, default: &str) -> Result<String> {
        Ok(self.get_string(name)?.unwrap_or_else(|| default.to_string()))
    }

    /// The name of the texture a `texture` parameter refers to.
    pub fn get_texture(&self, name: &str) -> Result<Option<String>> {
        Ok(match self.single(name, ParamType::Texture)? {
            Some(Param {
                values: Values::Strings(v),
                ..
            }) => v.first().cloned(),
            _ => None,
        })
    }

    fn get_vec3(&self, name: &str, ty: ParamType) -> Result<Option<Vec3>> {
        Ok(self
            .single(name, ty)?
            .and_then(|p| p.floats().get(..3).map(Vec3::from_slice)))
    }

    pub fn get_point3(&self, name: &str, default: Vec3) -> Result<Vec3> {
        Ok(self.get_vec3(name, ParamType::Point3)?.unwrap_or(default))
    }

    pub fn get_vector3(&self, name: &str, default: Vec3) -> Result<Vec3> {
        Ok(self.get_vec3(name, ParamType::Vector3)?.unwrap_or(default))
    }

    pub fn get_normal(&self, name: &str, default: Vec3) -> Result<Vec3> {
        Ok(self.get_vec3(name, ParamType::Normal)?.unwrap_or(default))
    }

    pub fn get_point2(&self, name: &str, default: Vec2) -> Result<Vec2> {
        Ok(self
            .single(name, ParamType::Point2)?
            .and_then(|p| p.floats().get(..2).map(Vec2::from_slice))
            .unwrap_or(default))
    }

    /// An `rgb` value (only that type; see [`Params::get_spectrum`] for any).
    pub fn get_rgb(&self, name: &str) -> Result<Option<Vec3>> {
        self.get_vec3(name, ParamType::Rgb)
    }

    /// The first `rgb`, `blackbody` or `spectrum` parameter of the name.
    pub fn get_spectrum(&self, name: &str) -> Result<Option<SpectrumValue>> {
        let Some(p) = self.iter().find(|p| p.name == name && p.ty.is_spectrum()) else {
            return Ok(None);
        };
        let mut s = p.spectra();
        if s.len() != 1 {
            return Err(p.single_error());
        }
        p.mark();
        Ok(s.pop())
    }

    /// A float or the texture giving it, whichever of the name comes first
    /// (pbrt-v4 materials take either for most of their inputs).
    pub fn get_float_or_texture(&self, name: &str) -> Result<Option<FloatOrTexture>> {
        let Some(p) = self
            .iter()
            .find(|p| p.name == name && matches!(p.ty, ParamType::Float | ParamType::Texture))
        else {
            return Ok(None);
        };
        Ok(Some(match p.ty {
            ParamType::Texture => FloatOrTexture::Texture(self.get_texture(name)?.unwrap_or_default()),
            _ => FloatOrTexture::Value(self.get_float(name, 0.0)?),
        }))
    }

    /// A spectrum or the texture giving it, whichever of the name comes first.
    pub fn get_spectrum_or_texture(&self, name: &str) -> Result<Option<SpectrumOrTexture>> {
        let Some(p) = self
            .iter()
            .find(|p| p.name == name && (p.ty.is_spectrum() || p.ty == ParamType::Texture))
        else {
            return Ok(None);
        };
        Ok(match p.ty {
            ParamType::Texture => self.get_texture(name)?.map(SpectrumOrTexture::Texture),
            _ => self.get_spectrum(name)?.map(SpectrumOrTexture::Value),
        })
    }

    fn array(&self, name: &str, ty: ParamType) -> Option<&Param> {
        let p = self.find(name, ty)?;
        p.mark();
        Some(p)
    }

    /// All values of a `float` parameter (empty when there is none).
    pub fn get_floats(&self, name: &str) -> &[f32] {
        self.array(name, ParamType::Float).map_or(&[], |p| p.floats())
    }

    pub fn get_ints(&self, name: &str) -> &[i32] {
        match self.array(name, ParamType::Integer).map(|p| &p.values) {
            Some(Values::Ints(v)) => v,
            _ => &[],
        }
    }

    pub fn get_bools(&self, name: &str) -> &[bool] {
        match self.array(name, ParamType::Bool).map(|p| &p.values) {
            Some(Values::Bools(v)) => v,
            _ => &[],
        }
    }

    pub fn get_strings(&self, name: &str) -> &[String] {
        match self.array(name, ParamType::String).map(|p| &p.values) {
            Some(Values::Strings(v)) => v,
            _ => &[],
        }
    }

    fn vec3s(&self, name: &str, ty: ParamType) -> Vec<Vec3> {
        self.array(name, ty)
            .map_or(vec![], |p| p.floats().chunks_exact(3).map(Vec3::from_slice).collect())
    }

    pub fn get_point3s(&self, name: &str) -> Vec<Vec3> {
        self.vec3s(name, ParamType::Point3)
    }

    pub fn get_vector3s(&self, name: &str) -> Vec<Vec3> {
        self.vec3s(name, ParamType::Vector3)
    }

    pub fn get_normals(&self, name: &str) -> Vec<Vec3> {
        self.vec3s(name, ParamType::Normal)
    }

    pub fn get_rgbs(&self, name: &str) -> Vec<Vec3> {
        self.vec3s(name, ParamType::Rgb)
    }

    pub fn get_point2s(&self, name: &str) -> Vec<Vec2> {
        self.array(name, ParamType::Point2)
            .map_or(vec![], |p| p.floats().chunks_exact(2).map(Vec2::from_slice).collect())
    }

    /// The directive's own parameters no look-up has read, as pbrt-v4's
    /// `ReportUnused`: attributes are never reported, nor a parameter hidden
    /// by a later one of the same name and type that was read.
    pub fn unused(&self) -> Vec<&Param> {
        let mut out = vec![];
        for (i, p) in self.own.iter().enumerate().rev() {
            if p.used() {
                continue;
            }
            let shadowed = self.own[i + 1..]
                .iter()
                .any(|q| q.name == p.name && q.ty == p.ty && q.used());
            if !shadowed {
                out.push(p);
            }
        }
        out.reverse();
        out
    }
}
