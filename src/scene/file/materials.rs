//! The `[textures.NAME]` and `[materials.NAME]` tables. Each is read as a
//! table of spanned values, so that every error points at the key it is
//! about: a key of another type, a bad value, an unknown texture name.

use super::Source;
use crate::bsdf::{named_metal, MeasuredBxdf, MeasuredData};
use crate::error::Result;
use crate::material::{CoatMedium, ConductorFresnel, Material, Roughness};
use crate::math::Vec3;
use crate::scene::mesh::FileSource;
use crate::texture::{
    Encoding, ImageOptions, ImageTexture, Mapping2D, MipFilter, NoiseTexture, Pattern, Texture, UvMapping, WrapMode,
};
use glam::Affine3A;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use toml::Spanned;

/// A table's keys and their values, with spans.
pub(super) type Table = BTreeMap<String, Spanned<toml::Value>>;

/// Finds a texture by the name written at a span.
type Lookup<'a> = dyn FnMut(&str, std::ops::Range<usize>) -> Result<Arc<Texture>> + 'a;

/// Reads the keys of one table, each error at the key's line.
struct Keys<'a> {
    src: &'a Source<'a>,
    table: &'a Table,
    span: std::ops::Range<usize>,
    /// "material 'x'" or "texture 'x'".
    what: String,
    /// Keys that every type takes (a material's `displacement`).
    shared: &'static [&'static str],
}

impl Keys<'_> {
    fn err(&self, key: Option<&str>, m: String) -> crate::error::Error {
        let span = key
            .and_then(|k| self.table.get(k))
            .map_or(self.span.clone(), |v| v.span());
        self.src.error(span, format!("{}: {m}", self.what))
    }

    fn has(&self, key: &str) -> bool {
        self.table.contains_key(key)
    }

    /// Refuses every key not in `allowed` (besides `type`).
    fn only(&self, kind: &str, allowed: &[&str]) -> Result<()> {
        for key in self.table.keys() {
            if key != "type" && !allowed.contains(&key.as_str()) && !self.shared.contains(&key.as_str()) {
                let known = if allowed.is_empty() {
                    "none".to_string()
                } else {
                    allowed.join(", ")
                };
                return Err(self.err(
                    Some(key),
                    format!("`{key}` does not apply to this type ({kind} takes: {known})"),
                ));
            }
        }
        Ok(())
    }

    fn num(&self, key: &str) -> Result<Option<f32>> {
        let Some(v) = self.table.get(key) else {
            return Ok(None);
        };
        let f = match v.get_ref() {
            toml::Value::Integer(i) => *i as f32,
            toml::Value::Float(f) => *f as f32,
            other => return Err(self.err(Some(key), format!("`{key}` must be a number, not {}", other.type_str()))),
        };
        if !f.is_finite() {
            return Err(self.err(Some(key), format!("`{key}` must be a finite number")));
        }
        Ok(Some(f))
    }

    fn string(&self, key: &str) -> Result<Option<&str>> {
        match self.table.get(key).map(|v| v.get_ref()) {
            None => Ok(None),
            Some(toml::Value::String(s)) => Ok(Some(s)),
            Some(other) => Err(self.err(Some(key), format!("`{key}` must be a string, not {}", other.type_str()))),
        }
    }

    fn boolean(&self, key: &str) -> Result<Option<bool>> {
        match self.table.get(key).map(|v| v.get_ref()) {
            None => Ok(None),
            Some(toml::Value::Boolean(b)) => Ok(Some(*b)),
            Some(other) => Err(self.err(
                Some(key),
                format!("`{key}` must be true or false, not {}", other.type_str()),
            )),
        }
    }

    /// A number or `[r, g, b]`.
    fn rgb(&self, key: &str) -> Result<Option<Vec3>> {
        let Some(v) = self.table.get(key) else {
            return Ok(None);
        };
        match v.get_ref() {
            toml::Value::Array(a) if a.len() == 3 => {
                let mut c = [0.0f32; 3];
                for (i, x) in a.iter().enumerate() {
                    c[i] = match x {
                        toml::Value::Integer(n) => *n as f32,
                        toml::Value::Float(f) => *f as f32,
                        _ => return Err(self.err(Some(key), format!("`{key}` must hold three numbers"))),
                    };
                }
                let c = Vec3::from_array(c);
                if !c.is_finite() {
                    return Err(self.err(Some(key), format!("`{key}` must hold finite numbers")));
                }
                Ok(Some(c))
            }
            toml::Value::Integer(_) | toml::Value::Float(_) => Ok(self.num(key)?.map(Vec3::splat)),
            _ => Err(self.err(Some(key), format!("`{key}` must be a number or [r, g, b]"))),
        }
    }

    /// A point or direction: `[x, y, z]`.
    fn vector(&self, key: &str) -> Result<Option<Vec3>> {
        match self.table.get(key).map(|v| v.get_ref()) {
            None => Ok(None),
            Some(toml::Value::Array(a)) if a.len() == 3 => self.rgb(key),
            Some(_) => Err(self.err(Some(key), format!("`{key}` must be [x, y, z]"))),
        }
    }

    /// A colour parameter: a number, `[r, g, b]` or the name of a texture,
    /// found by `lookup` (which reports unknown names and cycles).
    fn param(&self, key: &str, lookup: &mut Lookup) -> Result<Option<Texture>> {
        let Some(v) = self.table.get(key) else {
            return Ok(None);
        };
        if let toml::Value::String(name) = v.get_ref() {
            return Ok(Some((*lookup(name, v.span())?).clone()));
        }
        match self.rgb(key) {
            Ok(c) => Ok(c.map(Texture::Constant)),
            Err(_) => Err(self.err(
                Some(key),
                format!("`{key}` must be a number, [r, g, b] or the name of a texture"),
            )),
        }
    }
}

/// Resolves texture names while the `[textures]` tables are read.
struct Resolver<'a> {
    src: &'a Source<'a>,
    specs: &'a BTreeMap<String, Spanned<Table>>,
    dir: &'a Path,
    files: &'a dyn FileSource,
    done: BTreeMap<String, Arc<Texture>>,
    /// Textures being read, innermost last: a name met again is a cycle.
    stack: Vec<String>,
}

impl Resolver<'_> {
    fn get(&mut self, name: &str, span: std::ops::Range<usize>) -> Result<Arc<Texture>> {
        if let Some(t) = self.done.get(name) {
            return Ok(t.clone());
        }
        let Some(spec) = self.specs.get(name) else {
            let known: Vec<&str> = self.specs.keys().map(String::as_str).collect();
            let known = if known.is_empty() {
                "none".to_string()
            } else {
                known.join(", ")
            };
            return Err(self
                .src
                .error(span, format!("unknown texture '{name}' (defined: {known})")));
        };
        if let Some(i) = self.stack.iter().position(|n| n == name) {
            let mut cycle = self.stack[i..].to_vec();
            cycle.push(name.to_string());
            return Err(self.src.error(
                span,
                format!("textures refer to each other in a cycle: {}", cycle.join(" -> ")),
            ));
        }
        self.stack.push(name.to_string());
        let t = Arc::new(self.read(name, spec)?);
        self.stack.pop();
        self.done.insert(name.to_string(), t.clone());
        Ok(t)
    }

    fn read(&mut self, name: &str, spec: &Spanned<Table>) -> Result<Texture> {
        let k = Keys {
            src: self.src,
            table: spec.get_ref(),
            span: spec.span(),
            what: format!("texture '{name}'"),
            shared: &[],
        };
        let kind = match k.string("type")? {
            Some(t) => t,
            None => return Err(k.err(None, format!("missing `type` ({TEXTURE_TYPES})"))),
        };
        let (dir, files) = (self.dir, self.files);
        let mut lookup = |n: &str, s: std::ops::Range<usize>| self.get(n, s);
        let one = Texture::Constant(Vec3::ONE);
        let zero = Texture::Constant(Vec3::ZERO);
        Ok(match kind {
            "constant" => {
                k.only(kind, &["value"])?;
                k.param("value", &mut lookup)?.unwrap_or(one)
            }
            "checkerboard" => {
                let three = match k.num("dimension")? {
                    None => false,
                    Some(d) if d == 2.0 || d == 3.0 => d == 3.0,
                    Some(d) => return Err(k.err(Some("dimension"), format!("dimension {d}: use 2 or 3"))),
                };
                if three {
                    k.only(kind, &["tex1", "tex2", "dimension", "frequency"])?;
                } else {
                    k.only(kind, &with_mapping(&["tex1", "tex2", "dimension"]))?;
                }
                let even = Arc::new(k.param("tex1", &mut lookup)?.unwrap_or(one));
                let odd = Arc::new(k.param("tex2", &mut lookup)?.unwrap_or(zero));
                if three {
                    Texture::Checkerboard3D {
                        even,
                        odd,
                        to_texture: Arc::new(Affine3A::from_scale(Vec3::splat(frequency(&k)?))),
                    }
                } else {
                    Texture::Checkerboard {
                        even,
                        odd,
                        mapping: Arc::new(mapping_2d(&k)?),
                    }
                }
            }
            "scale" => {
                k.only(kind, &["tex", "scale"])?;
                Texture::Scale {
                    tex: Arc::new(k.param("tex", &mut lookup)?.unwrap_or(one.clone())),
                    scale: Arc::new(k.param("scale", &mut lookup)?.unwrap_or(one)),
                }
            }
            "mix" => {
                k.only(kind, &["tex1", "tex2", "amount"])?;
                Texture::Mix {
                    a: Arc::new(k.param("tex1", &mut lookup)?.unwrap_or(zero)),
                    b: Arc::new(k.param("tex2", &mut lookup)?.unwrap_or(one)),
                    amount: Arc::new(
                        k.param("amount", &mut lookup)?
                            .unwrap_or(Texture::Constant(Vec3::splat(0.5))),
                    ),
                }
            }
            "fbm" | "wrinkled" | "windy" | "marble" => {
                let allowed: &[&str] = match kind {
                    "windy" => &["frequency"],
                    "marble" => &["frequency", "octaves", "roughness", "scale", "variation"],
                    _ => &["frequency", "octaves", "roughness"],
                };
                k.only(kind, allowed)?;
                let frequency = frequency(&k)?;
                let octaves = match k.num("octaves")? {
                    None => 8,
                    Some(n) if n.fract() == 0.0 && (0.0..=32.0).contains(&n) => n as u32,
                    Some(n) => return Err(k.err(Some("octaves"), format!("octaves {n}: a whole number in 0..=32"))),
                };
                let omega = k.num("roughness")?.unwrap_or(0.5);
                let pattern = match kind {
                    "fbm" => Pattern::Fbm { octaves, omega },
                    "wrinkled" => Pattern::Wrinkled { octaves, omega },
                    "windy" => Pattern::Windy,
                    _ => Pattern::Marble {
                        octaves,
                        omega,
                        scale: k.num("scale")?.unwrap_or(1.0),
                        variation: k.num("variation")?.unwrap_or(0.2),
                    },
                };
                Texture::Noise(Arc::new(NoiseTexture {
                    to_texture: Affine3A::from_scale(Vec3::splat(frequency)),
                    pattern,
                }))
            }
            "dots" => {
                k.only(kind, &with_mapping(&["inside", "outside"]))?;
                Texture::Dots {
                    inside: Arc::new(k.param("inside", &mut lookup)?.unwrap_or(one)),
                    outside: Arc::new(k.param("outside", &mut lookup)?.unwrap_or(zero)),
                    mapping: Arc::new(mapping_2d(&k)?),
                }
            }
            "bilerp" => {
                k.only(kind, &with_mapping(&["v00", "v01", "v10", "v11"]))?;
                let mut corners = [Vec3::ZERO; 4];
                for (c, (key, d)) in corners
                    .iter_mut()
                    .zip([("v00", 0.0), ("v01", 1.0), ("v10", 0.0), ("v11", 1.0)])
                {
                    *c = match k.param(key, &mut lookup)? {
                        None => Vec3::splat(d),
                        Some(t) => t.as_constant().ok_or_else(|| {
                            k.err(
                                Some(key),
                                format!("`{key}` must be a number or a colour, not a texture"),
                            )
                        })?,
                    };
                }
                Texture::Bilerp(Arc::new((corners, mapping_2d(&k)?)))
            }
            "image" => {
                k.only(
                    kind,
                    &with_mapping(&["file", "wrap", "encoding", "scale", "invert", "filter"]),
                )?;
                let mapping = mapping_2d(&k)?;
                let file = k.string("file")?.ok_or_else(|| k.err(None, "missing `file`".into()))?;
                let wrap = match k.string("wrap")? {
                    None => WrapMode::Repeat,
                    Some(w) => WrapMode::parse(w)
                        .ok_or_else(|| k.err(Some("wrap"), format!("wrap '{w}': use repeat, clamp or black")))?,
                };
                let filter = match k.string("filter")? {
                    None => MipFilter::default(),
                    Some(f) => MipFilter::parse(f).ok_or_else(|| {
                        k.err(
                            Some("filter"),
                            format!("filter '{f}': use point, bilinear, trilinear or ewa"),
                        )
                    })?,
                };
                let encoding = match k.string("encoding")? {
                    None => Encoding::Srgb,
                    Some(e) => Encoding::parse(e).ok_or_else(|| {
                        k.err(
                            Some("encoding"),
                            format!("encoding '{e}': use sRGB, linear or \"gamma G\" with G > 0"),
                        )
                    })?,
                };
                let opts = ImageOptions {
                    wrap,
                    encoding,
                    scale: k.num("scale")?.unwrap_or(1.0),
                    invert: k.boolean("invert")?.unwrap_or(false),
                    // Any mapping but (u, v) is applied before the image
                    // is looked up, which then takes (s, t) as they are.
                    mapping: match &mapping {
                        Mapping2D::Uv(m) => *m,
                        _ => UvMapping::default(),
                    },
                    filter,
                };
                let path = dir.join(file);
                let image = files
                    .read_image(&path, encoding)
                    .map_err(|e| image_error(&k, "file", e))?;
                let image = Texture::Image(Arc::new(ImageTexture::new(image, &opts)));
                match mapping {
                    Mapping2D::Uv(_) => image,
                    mapping => Texture::Mapped {
                        mapping: Arc::new(mapping),
                        tex: Arc::new(image),
                    },
                }
            }
            other => {
                return Err(k.err(
                    Some("type"),
                    format!("unknown texture type '{other}' ({TEXTURE_TYPES})"),
                ))
            }
        })
    }
}

/// The texture types a scene file names.
const TEXTURE_TYPES: &str = "image, checkerboard, scale, mix, constant, fbm, wrinkled, windy, marble, dots or bilerp";

/// (s, t) = (uscale u + udelta, vscale v + vdelta).
fn uv_mapping(k: &Keys) -> Result<UvMapping> {
    Ok(UvMapping {
        su: k.num("uscale")?.unwrap_or(1.0),
        sv: k.num("vscale")?.unwrap_or(1.0),
        du: k.num("udelta")?.unwrap_or(0.0),
        dv: k.num("vdelta")?.unwrap_or(0.0),
    })
}

/// The keys that place a 2D texture on a surface, besides `mapping`.
const MAPPING_KEYS: [&str; 8] = ["uscale", "vscale", "udelta", "vdelta", "centre", "axis", "v1", "v2"];

/// `keys` and the keys of the 2D mappings.
fn with_mapping(keys: &[&'static str]) -> Vec<&'static str> {
    let mut all = keys.to_vec();
    all.push("mapping");
    all.extend(MAPPING_KEYS);
    all
}

/// A 3D texture's `frequency`: its pattern is read at the point times it.
fn frequency(k: &Keys) -> Result<f32> {
    let f = k.num("frequency")?.unwrap_or(1.0);
    if !(f.is_finite() && f > 0.0) {
        return Err(k.err(Some("frequency"), format!("frequency {f} must be positive")));
    }
    Ok(f)
}

/// Where a 2D texture's (s, t) come from (`mapping`): the surface's (u, v)
/// scaled and offset (`uv`, the default); the direction from `centre`
/// (`spherical`: s from `axis`, t about it) or the angle about the line
/// through `centre` along `axis` and the height along it (`cylindrical`);
/// the point's components along `v1` and `v2`, offset (`planar`). Keys of
/// another mapping are refused.
fn mapping_2d(k: &Keys) -> Result<Mapping2D> {
    let kind = k.string("mapping")?.unwrap_or("uv");
    let takes: &[&str] = match kind {
        "uv" => &["uscale", "vscale", "udelta", "vdelta"],
        "spherical" | "cylindrical" => &["centre", "axis"],
        "planar" => &["v1", "v2", "udelta", "vdelta"],
        other => {
            return Err(k.err(
                Some("mapping"),
                format!("mapping '{other}': use uv, spherical, cylindrical or planar"),
            ))
        }
    };
    if let Some(key) = MAPPING_KEYS.iter().find(|key| k.has(key) && !takes.contains(key)) {
        return Err(k.err(
            Some(key),
            format!(
                "`{key}` does not apply to mapping '{kind}' (it takes: {})",
                takes.join(", ")
            ),
        ));
    }
    Ok(match kind {
        "uv" => Mapping2D::Uv(uv_mapping(k)?),
        "planar" => Mapping2D::Planar {
            to_texture: Affine3A::IDENTITY,
            vs: k.vector("v1")?.unwrap_or(Vec3::X),
            vt: k.vector("v2")?.unwrap_or(Vec3::Y),
            ds: k.num("udelta")?.unwrap_or(0.0),
            dt: k.num("vdelta")?.unwrap_or(0.0),
        },
        _ => {
            let centre = k.vector("centre")?.unwrap_or(Vec3::ZERO);
            let axis = k.vector("axis")?.unwrap_or(Vec3::Z).normalize_or_zero();
            if axis == Vec3::ZERO {
                return Err(k.err(Some("axis"), "`axis` must not be zero".into()));
            }
            // Texture space: `centre` at the origin, `axis` along z.
            let to =
                Affine3A::from_quat(glam::Quat::from_rotation_arc(axis, Vec3::Z)) * Affine3A::from_translation(-centre);
            if kind == "spherical" {
                Mapping2D::Spherical(to)
            } else {
                Mapping2D::Cylindrical(to)
            }
        }
    })
}

/// The `[textures.NAME]` tables, with image paths relative to `dir`.
pub(super) fn textures(
    src: &Source,
    specs: &BTreeMap<String, Spanned<Table>>,
    dir: &Path,
    files: &dyn FileSource,
) -> Result<BTreeMap<String, Arc<Texture>>> {
    let mut r = Resolver {
        src,
        specs,
        dir,
        files,
        done: BTreeMap::new(),
        stack: vec![],
    };
    for (name, spec) in specs {
        r.get(name, spec.span())?;
    }
    Ok(r.done)
}

const ROUGHNESS_KEYS: [&str; 4] = ["roughness", "uroughness", "vroughness", "remap_roughness"];

/// The `[materials.NAME]` tables; colour parameters may name `textures`.
/// An image that could not be read, as the error at `key`.
fn image_error(k: &Keys, key: &str, e: crate::error::Error) -> crate::error::Error {
    match e {
        crate::error::Error::Io { path, source } if source.kind() == std::io::ErrorKind::NotFound => {
            k.err(Some(key), format!("`{key}`: image file {} not found", path.display()))
        }
        e => k.err(Some(key), format!("`{key}`: cannot read the image: {e}")),
    }
}

/// The `[materials.NAME]` tables; normal maps' image paths relative to `dir`.
pub(super) fn materials(
    src: &Source,
    specs: &BTreeMap<String, Spanned<Table>>,
    textures: &BTreeMap<String, Arc<Texture>>,
    dir: &Path,
    files: &dyn FileSource,
) -> Result<BTreeMap<String, Material>> {
    let mut out = BTreeMap::new();
    for (name, spec) in specs {
        let k = Keys {
            src,
            table: spec.get_ref(),
            span: spec.span(),
            what: format!("material '{name}'"),
            shared: &["displacement", "normal_map"],
        };
        if k.string("type")? == Some("interface") {
            // No surface: nothing to bump or map either.
            let bare = Keys { shared: &[], ..k };
            bare.only("interface", &[])?;
            out.insert(name.clone(), Material::Interface);
            continue;
        }
        let mut m = material(&k, textures, dir, files)?;
        // A normal map, over any type: an image of normals in the surface's
        // (dp/du, n x dp/du, n) frame, read as linear RGB (pbrt-v4's `normalmap`).
        if let Some(file) = k.string("normal_map")? {
            if k.has("displacement") {
                return Err(k.err(
                    Some("normal_map"),
                    "give `normal_map` or `displacement`, not both".into(),
                ));
            }
            let map = files
                .read_image(&dir.join(file), Encoding::Linear)
                .map_err(|e| image_error(&k, "normal_map", e))?;
            m = Material::NormalMapped {
                base: Box::new(m),
                map,
                mirrored: false,
            };
        }
        out.insert(name.clone(), m);
    }
    Ok(out)
}

fn material(
    k: &Keys,
    textures: &BTreeMap<String, Arc<Texture>>,
    dir: &Path,
    files: &dyn FileSource,
) -> Result<Material> {
    let mut lookup = |n: &str, span: std::ops::Range<usize>| -> Result<Arc<Texture>> {
        textures.get(n).cloned().ok_or_else(|| {
            let known: Vec<&str> = textures.keys().map(String::as_str).collect();
            let known = if known.is_empty() {
                "none".to_string()
            } else {
                known.join(", ")
            };
            k.src
                .error(span, format!("{}: unknown texture '{n}' (defined: {known})", k.what))
        })
    };
    // A bump map, over any type: the surface displaced along its normal by
    // this float texture (pbrt-v4's `displacement`), for shading only.
    let displacement = k.param("displacement", &mut lookup)?;
    // A reflectance-like parameter: [0, 1] everywhere the texture can reach.
    let mut albedo = |key: &str, default: f32| -> Result<Texture> {
        let t = k
            .param(key, &mut lookup)?
            .unwrap_or(Texture::Constant(Vec3::splat(default)));
        let (lo, hi) = match t.as_constant() {
            Some(c) => (c.min_element(), c.max_element()),
            None => (0.0, t.max_value().max_element()),
        };
        if !(lo >= 0.0 && hi <= 1.0) {
            let shown = match t.as_constant() {
                Some(c) => format!("{:?}", c.to_array()),
                None => format!("(a texture reaching {hi})"),
            };
            return Err(k.err(Some(key), format!("{key} {shown} must lie in [0, 1]")));
        }
        Ok(t)
    };
    let kind = k.string("type")?.unwrap_or("diffuse");
    // A coat's medium: `albedo` (0, the default, only absorbs) and `g`.
    let coat_medium = |max_depth: u32, samples: u32| -> Result<Option<CoatMedium>> {
        let g = k.num("g")?.unwrap_or(0.0);
        if !(g > -1.0 && g < 1.0) {
            return Err(k.err(Some("g"), format!("g {g} must lie in (-1, 1)")));
        }
        let albedo = k.rgb("albedo")?.unwrap_or(Vec3::ZERO);
        if !(albedo.min_element() >= 0.0 && albedo.max_element() <= 1.0) {
            let shown = albedo.to_array();
            return Err(k.err(Some("albedo"), format!("albedo {shown:?} must lie in [0, 1]")));
        }
        Ok((albedo != Vec3::ZERO).then_some(CoatMedium {
            albedo: Texture::from(albedo),
            g,
            max_depth,
            samples,
        }))
    };
    let count = |key: &str, default: f32, lo: f32| -> Result<u32> {
        let n = k.num(key)?.unwrap_or(default);
        if n.fract() != 0.0 || !(lo..=1000.0).contains(&n) {
            return Err(k.err(Some(key), format!("{key} {n} must be a whole number in {lo}..1000")));
        }
        Ok(n as u32)
    };
    let eta = |default: f32| -> Result<f32> {
        let e = k.num("eta")?.unwrap_or(default);
        if e <= 0.0 {
            return Err(k.err(Some("eta"), format!("eta {e} must be > 0")));
        }
        Ok(e)
    };
    // The roughness keys of one interface: `roughness`, or, with a prefix,
    // `metal_roughness` and so on.
    let roughness_of = |prefix: &str| -> Result<Roughness> {
        let [r_key, u_key, v_key] = ["roughness", "uroughness", "vroughness"].map(|n| format!("{prefix}{n}"));
        let r = k.num(&r_key)?;
        let (u, v) = (k.num(&u_key)?, k.num(&v_key)?);
        if r.is_some() && (u.is_some() || v.is_some()) {
            return Err(k.err(Some(&r_key), format!("give `{r_key}` or `{u_key}`/`{v_key}`, not both")));
        }
        let (u, v) = (u.or(r).unwrap_or(0.0), v.or(r).unwrap_or(0.0));
        for (key, x) in [(&r_key, r.unwrap_or(0.0)), (&u_key, u), (&v_key, v)] {
            if x < 0.0 {
                let key = if k.has(key) { key } else { &r_key };
                return Err(k.err(Some(key), format!("{key} {x} must be >= 0")));
            }
        }
        Ok(Roughness {
            u,
            v,
            remap: k.boolean("remap_roughness")?.unwrap_or(true),
        })
    };
    let roughness = || roughness_of("");
    // A metal's Fresnel terms: `reflectance`, a named `metal`, or `eta` and
    // `k` (with a prefix: `metal_eta`, `metal_k`); copper by default.
    let metal_fresnel =
        |prefix: &str, albedo: &mut dyn FnMut(&str, f32) -> Result<Texture>| -> Result<ConductorFresnel> {
            let (eta_key, k_key) = (format!("{prefix}eta"), format!("{prefix}k"));
            let (eta_key, k_key) = (eta_key.as_str(), k_key.as_str());
            if k.has("reflectance") {
                if let Some(key) = [eta_key, k_key, "metal"].into_iter().find(|x| k.has(x)) {
                    return Err(k.err(Some(key), format!("give `reflectance` or `{key}`, not both")));
                }
                return Ok(ConductorFresnel::Reflectance(albedo("reflectance", 1.0)?));
            }
            if let Some(m) = k.string("metal")? {
                if let Some(key) = [eta_key, k_key].into_iter().find(|x| k.has(x)) {
                    return Err(k.err(Some(key), format!("give `metal` or `{key}`, not both")));
                }
                let (eta, kk) = named_metal(m).ok_or_else(|| {
                    k.err(
                        Some("metal"),
                        format!("unknown metal '{m}' (known: Ag, Al, Au, Cu, CuZn)"),
                    )
                })?;
                return Ok(ConductorFresnel::Ior { eta, k: kk });
            }
            if k.has(eta_key) || k.has(k_key) {
                let eta = k
                    .rgb(eta_key)?
                    .ok_or_else(|| k.err(Some(k_key), format!("`{k_key}` needs `{eta_key}` too")))?;
                let kk = k
                    .rgb(k_key)?
                    .ok_or_else(|| k.err(Some(eta_key), format!("`{eta_key}` needs `{k_key}` too")))?;
                if eta.min_element() <= 0.0 {
                    return Err(k.err(Some(eta_key), format!("{eta_key} {:?} must be > 0", eta.to_array())));
                }
                if kk.min_element() < 0.0 {
                    return Err(k.err(Some(k_key), format!("{k_key} {:?} must be >= 0", kk.to_array())));
                }
                return Ok(ConductorFresnel::Ior { eta, k: kk });
            }
            // pbrt-v4's default: copper.
            let (eta, kk) = named_metal("Cu").expect("copper is a named metal");
            Ok(ConductorFresnel::Ior { eta, k: kk })
        };
    let base = match kind {
        "diffuse" => {
            k.only(kind, &["reflectance", "albedo"])?;
            if k.has("albedo") && k.has("reflectance") {
                return Err(k.err(
                    Some("albedo"),
                    "give `reflectance` or `albedo` (the same), not both".into(),
                ));
            }
            let key = if k.has("albedo") { "albedo" } else { "reflectance" };
            Material::Diffuse {
                reflectance: albedo(key, 0.5)?,
            }
        }
        "mirror" => {
            k.only(kind, &["reflectance"])?;
            Material::Conductor {
                fresnel: ConductorFresnel::Reflectance(albedo("reflectance", 1.0)?),
                roughness: Roughness::SMOOTH.into(),
            }
        }
        "glass" => {
            k.only(kind, &["ior"])?;
            let ior = k.num("ior")?.unwrap_or(1.5);
            if !(1.0..=5.0).contains(&ior) {
                return Err(k.err(Some("ior"), format!("ior {ior} must lie in [1, 5]")));
            }
            Material::glass(ior)
        }
        "conductor" => {
            let mut keys = vec!["eta", "k", "metal", "reflectance"];
            keys.extend(ROUGHNESS_KEYS);
            k.only(kind, &keys)?;
            let fresnel = metal_fresnel("", &mut albedo)?;
            Material::Conductor {
                fresnel,
                roughness: roughness()?.into(),
            }
        }
        "dielectric" => {
            let mut keys = vec!["eta", "glass"];
            keys.extend(ROUGHNESS_KEYS);
            k.only(kind, &keys)?;
            let roughness = roughness()?.into();
            // An index per colour channel disperses: from three numbers, or
            // from one of pbrt-v4's named glasses.
            let channels = match k.string("glass")? {
                Some(name) => {
                    if k.has("eta") {
                        return Err(k.err(Some("eta"), "give `glass` or `eta`, not both".to_string()));
                    }
                    let full = format!("glass-{name}");
                    if crate::scene::pbrt::spectrum::glass_eta_550(&full).is_none() {
                        let known: Vec<&str> = crate::scene::pbrt::spectrum::NAMED_SPECTRA
                            .iter()
                            .filter_map(|n| n.strip_prefix("glass-"))
                            .collect();
                        return Err(k.err(
                            Some("glass"),
                            format!("unknown glass '{name}' (known: {})", known.join(", ")),
                        ));
                    }
                    let e = |l| crate::scene::pbrt::spectrum::glass_eta(&full, l).unwrap_or(1.0);
                    Some(crate::scene::pbrt::spectrum::channel_etas(e))
                }
                None => match k.table.get("eta").map(|v| v.get_ref()) {
                    Some(toml::Value::Array(_)) => {
                        let e = k.rgb("eta")?.unwrap_or(Vec3::splat(1.5));
                        if e.min_element() <= 0.0 {
                            return Err(k.err(Some("eta"), format!("eta {:?} must be > 0", e.to_array())));
                        }
                        Some(e)
                    }
                    _ => None,
                },
            };
            match channels {
                Some(eta) if eta.x != eta.y || eta.y != eta.z => Material::Dispersive { eta, roughness },
                Some(eta) => Material::Dielectric { eta: eta.x, roughness },
                None => Material::Dielectric {
                    eta: eta(1.5)?,
                    roughness,
                },
            }
        }
        "thindielectric" => {
            k.only(kind, &["eta"])?;
            Material::ThinDielectric { eta: eta(1.5)? }
        }
        "coateddiffuse" => {
            let mut keys = vec!["reflectance", "eta", "thickness", "albedo", "g", "max_depth", "samples"];
            keys.extend(ROUGHNESS_KEYS);
            k.only(kind, &keys)?;
            let thickness = k.num("thickness")?.unwrap_or(0.01);
            if thickness <= 0.0 {
                return Err(k.err(Some("thickness"), format!("thickness {thickness} must be > 0")));
            }
            Material::CoatedDiffuse {
                reflectance: albedo("reflectance", 0.5)?,
                roughness: roughness()?.into(),
                eta: eta(1.5)?,
                thickness,
                medium: coat_medium(count("max_depth", 10.0, 0.0)?, count("samples", 1.0, 1.0)?)?,
            }
        }
        "coatedconductor" => {
            let mut keys = vec![
                "eta",
                "thickness",
                "metal",
                "metal_eta",
                "metal_k",
                "reflectance",
                "metal_roughness",
                "metal_uroughness",
                "metal_vroughness",
                "max_depth",
                "samples",
                "albedo",
                "g",
            ];
            keys.extend(ROUGHNESS_KEYS);
            k.only(kind, &keys)?;
            let thickness = k.num("thickness")?.unwrap_or(0.01);
            if thickness.is_nan() || thickness < 0.0 {
                return Err(k.err(Some("thickness"), format!("thickness {thickness} must be >= 0")));
            }
            let conductor = metal_fresnel("metal_", &mut albedo)?;
            let (max_depth, samples) = (count("max_depth", 10.0, 0.0)?, count("samples", 1.0, 1.0)?);
            Material::CoatedConductor {
                interface_roughness: roughness()?.into(),
                eta: eta(1.5)?,
                thickness,
                conductor,
                conductor_roughness: roughness_of("metal_")?.into(),
                max_depth,
                samples,
                medium: coat_medium(max_depth, samples)?,
            }
        }
        "diffusetransmission" => {
            k.only(kind, &["reflectance", "transmittance"])?;
            Material::DiffuseTransmission {
                reflectance: albedo("reflectance", 0.25)?,
                transmittance: albedo("transmittance", 0.25)?,
            }
        }
        "subsurface" => {
            use crate::material::{Subsurface, SubsurfaceScattering};
            let mut keys = vec!["name", "sigma_a", "sigma_s", "reflectance", "mfp", "scale", "eta", "g"];
            keys.extend(ROUGHNESS_KEYS);
            k.only(kind, &keys)?;
            let scale = k.num("scale")?.unwrap_or(1.0);
            if scale < 0.0 {
                return Err(k.err(Some("scale"), format!("scale {scale} must be >= 0")));
            }
            let g = k.num("g")?.unwrap_or(0.0);
            if !(g > -1.0 && g < 1.0) {
                return Err(k.err(Some("g"), format!("g {g} must lie strictly between -1 and 1")));
            }
            // One way to give the medium; the keys of the others are errors.
            let ways = [
                ("name", &["name"][..]),
                ("sigma_a", &["sigma_a", "sigma_s"][..]),
                ("reflectance", &["reflectance", "mfp"][..]),
            ];
            let given: Vec<&str> = ways
                .iter()
                .filter(|(_, ks)| ks.iter().any(|x| k.has(x)))
                .map(|(w, _)| *w)
                .collect();
            if given.len() > 1 {
                return Err(k.err(
                    Some(given[1]),
                    "give the medium one way: `name`, or `sigma_a` and `sigma_s`, or `reflectance` (and `mfp`)".into(),
                ));
            }
            let coefficient = |key: &str| -> Result<Vec3> {
                let v = k
                    .rgb(key)?
                    .ok_or_else(|| k.err(None, format!("`sigma_a` and `sigma_s` go together: `{key}` is missing")))?;
                if v.min_element() < 0.0 {
                    return Err(k.err(Some(key), format!("{key} {:?} must be >= 0", v.to_array())));
                }
                Ok(v * scale)
            };
            let constant = |v: Vec3| Texture::from(v);
            let (scattering, g) = match given.first().copied() {
                Some("name") => {
                    let name = k.string("name")?.unwrap_or_default();
                    let Some((a, s)) = crate::medium::presets::scattering_preset(name) else {
                        let known: Vec<&str> = crate::medium::presets::preset_names().collect();
                        return Err(k.err(
                            Some("name"),
                            format!("unknown measured medium '{name}' (known: {})", known.join(", ")),
                        ));
                    };
                    if k.has("g") {
                        return Err(k.err(
                            Some("g"),
                            "a measured medium's scattering is already reduced: it takes no `g`".into(),
                        ));
                    }
                    let scattering = SubsurfaceScattering::Coefficients {
                        sigma_a: constant(a * scale),
                        sigma_s: constant(s * scale),
                    };
                    (scattering, 0.0)
                }
                Some("sigma_a") => {
                    let scattering = SubsurfaceScattering::Coefficients {
                        sigma_a: constant(coefficient("sigma_a")?),
                        sigma_s: constant(coefficient("sigma_s")?),
                    };
                    (scattering, g)
                }
                Some(_) => {
                    let mfp = k.rgb("mfp")?.unwrap_or(Vec3::ONE);
                    if mfp.min_element() <= 0.0 {
                        return Err(k.err(Some("mfp"), format!("mfp {:?} must be > 0", mfp.to_array())));
                    }
                    let scattering = SubsurfaceScattering::Reflectance {
                        reflectance: albedo("reflectance", 0.5)?,
                        mfp: constant(mfp * scale),
                    };
                    (scattering, g)
                }
                None => {
                    let scattering = SubsurfaceScattering::Coefficients {
                        sigma_a: constant(Vec3::new(0.0011, 0.0024, 0.014) * scale),
                        sigma_s: constant(Vec3::new(2.55, 3.21, 3.77) * scale),
                    };
                    (scattering, g)
                }
            };
            let eta = eta(1.33)?;
            Material::Subsurface(Box::new(Subsurface {
                eta,
                roughness: roughness()?.into(),
                scattering,
                table: crate::bssrdf::BssrdfTable::shared(g, eta),
            }))
        }
        "measured" => {
            // A measured BRDF of the RGL database (a `.bsdf` tensor file),
            // its path relative to the scene file.
            k.only(kind, &["file"])?;
            let file = k.string("file")?.ok_or_else(|| k.err(None, "missing `file`".into()))?;
            let path = dir.join(file);
            let fail = |e: String| k.err(Some("file"), format!("`file`: {}: {e}", path.display()));
            let bytes = files.read(&path).map_err(|e| fail(e.to_string()))?;
            let data =
                MeasuredData::shared(&path, &bytes, crate::scene::pbrt::spectrum::wavelength_rgb).map_err(fail)?;
            Material::Measured(MeasuredBxdf::new(data))
        }
        other => {
            return Err(k.err(
                Some("type"),
                format!(
                    "unknown material type '{other}' (diffuse, mirror, glass, conductor, dielectric, \
                     thindielectric, coateddiffuse, coatedconductor, diffusetransmission, subsurface, measured, \
                     interface)"
                ),
            ))
        }
    };
    Ok(match displacement {
        Some(displacement) => Material::Bumped {
            base: Box::new(base),
            displacement,
        },
        None => base,
    })
}
