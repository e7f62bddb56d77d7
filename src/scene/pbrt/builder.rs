//! The directives and the graphics state, after pbrt-v4's parser.cpp
//! (`parse`) and scene.cpp (`BasicSceneBuilder`).
//!
//! Transformation directives post-multiply the current transformation (CTM);
//! `AttributeBegin`/`AttributeEnd` save and restore the whole graphics state
//! (CTM, reverse orientation, material, area light, attributes, colour space,
//! media); `WorldBegin` resets the CTM and names it `world`; `Camera` names
//! the inverse of the CTM at the camera `camera`; `Include` reads a file as if
//! its text stood there, `Import` (world block only) reads one whose changes
//! to the graphics state end with it. Object instances are flattened: each
//! shape of the definition is placed with CTM(at `ObjectInstance`) x
//! CTM(at the `Shape` in `ObjectBegin`), pbrt's composition.
//!
//! Relative file names (Include, Import, PLY files; `PbrtScene::candidates`
//! for the converter's texture files) are looked for in the folder of the
//! file that names them, then in the folder of the top-level scene file,
//! where pbrt-v4 looks (it resolves every name against that folder only).

use super::error::{Loc, PbrtError, Result};
use super::ir::*;
use super::lexer::{Lexer, Token, TokenKind};
use super::params::{Param, ParamType, Params, Values};
use super::shapes::{self, Findings};
use super::spectrum::is_named_spectrum;
use crate::scene::mesh::ply;
use crate::scene::mesh::FileSource;
use glam::{Mat4, Vec3};
use std::collections::{HashMap, HashSet};
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

/// At most this many files open at once through Include and Import.
pub const MAX_INCLUDE_DEPTH: usize = 64;
/// At most this many shapes after instances are flattened.
pub const MAX_SHAPES: usize = 20_000_000;

/// The current transformation at the start and end of the shutter interval
/// (pbrt's `TransformSet` of two; they differ only with `ActiveTransform`).
type Ctm = [Mat4; 2];

#[derive(Clone, Debug)]
enum MaterialRef {
    Index(usize),
    Named(String),
}

#[derive(Clone, Debug)]
struct GraphicsState {
    ctm: Ctm,
    active: [bool; 2],
    reverse_orientation: bool,
    material: MaterialRef,
    area_light: Option<usize>,
    shape_attributes: Vec<Param>,
    light_attributes: Vec<Param>,
    material_attributes: Vec<Param>,
    medium_attributes: Vec<Param>,
    texture_attributes: Vec<Param>,
    color_space: Arc<str>,
    inside_medium: Option<String>,
    outside_medium: Option<String>,
}

impl GraphicsState {
    fn new() -> Self {
        GraphicsState {
            ctm: [Mat4::IDENTITY; 2],
            active: [true; 2],
            reverse_orientation: false,
            material: MaterialRef::Index(0),
            area_light: None,
            shape_attributes: vec![],
            light_attributes: vec![],
            material_attributes: vec![],
            medium_attributes: vec![],
            texture_attributes: vec![],
            color_space: Arc::from("srgb"),
            inside_medium: None,
            outside_medium: None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Block {
    Options,
    World,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pushed {
    Attribute,
    Object,
}

/// A shape before named materials are resolved.
#[derive(Clone, Debug)]
struct PendingShape {
    shape: Shape,
    material: MaterialRef,
}

#[derive(Debug)]
enum Item {
    Shape(Box<PendingShape>),
    Instance { name: String, ctm: Ctm, loc: Loc },
}

struct ObjectDef {
    name: String,
    loc: Loc,
    shapes: Vec<PendingShape>,
}

/// A `plymesh` file read while the scene is, decoded with the others once
/// it has been: decoding is most of the reading of a scene of many meshes,
/// and the files decode apart, on every core.
struct PlyJob {
    path: PathBuf,
    bytes: Vec<u8>,
    loc: Loc,
    name: String,
    /// What the shapes hold for the mesh until it is decoded (one of its
    /// own, known by its address).
    stand_in: Arc<TriMesh>,
}

/// The files being read by one `parse` pass: Includes stack on it.
struct Stream {
    lexers: Vec<Lexer>,
    pending: Option<Token>,
}

pub struct Builder<'a> {
    files: &'a dyn FileSource,
    scene_dir: PathBuf,
    streams: Vec<Stream>,
    block: Block,
    gs: GraphicsState,
    pushed: Vec<(GraphicsState, Pushed, Loc)>,
    named_coordinate_systems: HashMap<String, Ctm>,
    active_object: Option<ObjectDef>,
    objects: HashMap<String, (Loc, Arc<Vec<PendingShape>>)>,
    items: Vec<Item>,
    texture_names: HashSet<(String, TextureKind)>,
    ply_cache: HashMap<PathBuf, Arc<TriMesh>>,
    ply_jobs: Vec<PlyJob>,
    last_loc: Loc,
    scene: PbrtScene,
}

fn identity_entity(ty: &str) -> Entity {
    Entity::default_of(ty)
}

/// `a/./b/../c` as `a/c`, without touching the file system.
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if matches!(out.components().next_back(), Some(Component::Normal(_))) {
                    out.pop();
                } else {
                    out.push("..");
                }
            }
            c => out.push(c.as_os_str()),
        }
    }
    out
}

/// Where a relative name given in `file` may be: in `scene_dir`, the top-level
/// file's folder, where pbrt-v4 resolves every relative name whichever file
/// names it; then beside `file`, for scenes written as if names were relative
/// to the file that holds them, which pbrt-v4 finds only when run from that
/// folder.
pub fn candidates(file: &Path, scene_dir: &Path, name: &str) -> Vec<PathBuf> {
    let name = Path::new(name);
    if name.is_absolute() {
        return vec![name.to_path_buf()];
    }
    let dir = file.parent().unwrap_or(Path::new(""));
    let mut out = vec![normalize(&scene_dir.join(name))];
    let beside = normalize(&dir.join(name));
    if beside != out[0] {
        out.push(beside);
    }
    out
}

fn invert(m: Mat4) -> Option<Mat4> {
    let d = m.determinant();
    if d == 0.0 || !d.is_finite() {
        return None;
    }
    let inv = m.inverse();
    inv.is_finite().then_some(inv)
}

/// pbrt-v4's `LookAt`: the camera-from-world transformation of an eye at
/// `eye` looking at `look` with `up` up (left-handed camera space).
pub fn look_at(eye: Vec3, look: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (look - eye).normalize_or_zero();
    let right = up.normalize_or_zero().cross(dir);
    if dir == Vec3::ZERO || right.length() == 0.0 || !right.is_finite() {
        return None;
    }
    let right = right.normalize();
    let new_up = dir.cross(right);
    let world_from_camera = Mat4::from_cols(right.extend(0.0), new_up.extend(0.0), dir.extend(0.0), eye.extend(1.0));
    invert(world_from_camera)
}

/// pbrt-v4's `Rotate`: `angle` degrees about `axis`, counter-clockwise
/// looking down the axis towards the origin (right-handed rule).
pub fn rotate(angle_deg: f32, axis: Vec3) -> Option<Mat4> {
    let a = axis.normalize_or_zero();
    (a != Vec3::ZERO).then(|| Mat4::from_axis_angle(a, angle_deg.to_radians()))
}

const COLOR_SPACES: &[&str] = &["srgb", "dci-p3", "rec2020", "aces2065-1"];
const OPTIONS: &[&str] = &[
    "disablepixeljitter",
    "disabletexturefiltering",
    "disablewavelengthjitter",
    "displacementedgescale",
    "msereferenceimage",
    "msereferenceout",
    "rendercoordsys",
    "seed",
    "forcediffuse",
    "pixelstats",
    "wavefront",
];

impl<'a> Builder<'a> {
    pub fn new(files: &'a dyn FileSource, main: &Path) -> Builder<'a> {
        let main_file = Arc::new(main.to_path_buf());
        let default_material = Material {
            name: None,
            ty: "diffuse".into(),
            params: Params::default(),
            loc: None,
        };
        Builder {
            files,
            scene_dir: main.parent().unwrap_or(Path::new("")).to_path_buf(),
            streams: vec![],
            block: Block::Options,
            gs: GraphicsState::new(),
            pushed: vec![],
            named_coordinate_systems: HashMap::new(),
            active_object: None,
            objects: HashMap::new(),
            items: vec![],
            texture_names: HashSet::new(),
            ply_cache: HashMap::new(),
            ply_jobs: Vec::new(),
            last_loc: Loc::new(main_file, 1, 1),
            scene: PbrtScene {
                camera: Camera {
                    ty: "perspective".into(),
                    params: Params::default(),
                    loc: None,
                    camera_from_world: Mat4::IDENTITY,
                    world_from_camera: Mat4::IDENTITY,
                    world_from_camera_end: None,
                    medium: None,
                },
                film: identity_entity("rgb"),
                sampler: identity_entity("zsobol"),
                filter: identity_entity("gaussian"),
                integrator: identity_entity("volpath"),
                accelerator: identity_entity("bvh"),
                options: vec![],
                materials: vec![default_material],
                named_materials: HashMap::new(),
                textures: vec![],
                lights: vec![],
                area_lights: vec![],
                media: vec![],
                shapes: vec![],
                warnings: vec![],
                unsupported: vec![],
                transform_times: [0.0, 1.0],
                files: vec![],
                scene_dir: main.parent().unwrap_or(Path::new("")).to_path_buf(),
            },
        }
    }

    // ---- files and tokens -------------------------------------------------

    fn open_files(&self) -> impl Iterator<Item = &Path> {
        self.streams
            .iter()
            .flat_map(|s| s.lexers.iter().map(|l| l.file().as_path()))
    }

    fn note_file(&mut self, path: &Path) {
        if !self.scene.files.iter().any(|f| f == path) {
            self.scene.files.push(path.to_path_buf());
        }
    }

    /// Reads a file named in a directive at `loc`, trying each candidate.
    fn read_named(&mut self, loc: &Loc, what: &str, name: &str) -> Result<(PathBuf, Vec<u8>)> {
        if name.is_empty() {
            return Err(PbrtError::at(loc, format!("{what}: no file name given")));
        }
        let mut first_error = None;
        for path in candidates(&loc.file, &self.scene_dir, name) {
            match self.files.read(&path) {
                Ok(bytes) => {
                    self.note_file(&path);
                    return Ok((path, bytes));
                }
                Err(e) => {
                    if first_error.is_none() || e.kind() != std::io::ErrorKind::NotFound {
                        first_error = Some((path, e));
                    }
                }
            }
        }
        let Some((path, e)) = first_error else {
            return Err(PbrtError::at(loc, format!("{what} \"{name}\": cannot be found")));
        };
        Err(PbrtError::at(
            loc,
            format!("{what} \"{name}\": cannot read {}: {e}", path.display()),
        ))
    }

    /// Opens a scene file named at `loc` (Include, Import) as a lexer.
    fn open_scene_file(&mut self, loc: &Loc, what: &str, name: &str) -> Result<Lexer> {
        if self.open_files().count() >= MAX_INCLUDE_DEPTH {
            return Err(PbrtError::at(
                loc,
                format!("{what} \"{name}\": more than {MAX_INCLUDE_DEPTH} files open at once (an include cycle?)"),
            ));
        }
        let (path, bytes) = self.read_named(loc, what, name)?;
        if self.open_files().any(|p| p == path) {
            let chain: Vec<String> = self
                .open_files()
                .map(|p| p.display().to_string())
                .chain(std::iter::once(path.display().to_string()))
                .collect();
            return Err(PbrtError::at(
                loc,
                format!("{what} \"{name}\": include cycle: {}", chain.join(" -> ")),
            ));
        }
        let bytes = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz")) {
            ply::gunzip(&bytes).map_err(|m| PbrtError::at(loc, format!("{what} \"{name}\": {m}")))?
        } else {
            bytes
        };
        Lexer::new(Arc::new(path), bytes)
    }

    fn next(&mut self) -> Result<Option<Token>> {
        let Some(stream) = self.streams.last_mut() else {
            return Ok(None);
        };
        if let Some(t) = stream.pending.take() {
            return Ok(Some(t));
        }
        while let Some(lexer) = stream.lexers.last_mut() {
            if let Some(t) = lexer.next_token()? {
                self.last_loc = t.loc.clone();
                return Ok(Some(t));
            }
            stream.lexers.pop();
        }
        Ok(None)
    }

    fn unget(&mut self, t: Token) {
        if let Some(s) = self.streams.last_mut() {
            s.pending = Some(t);
        }
    }

    /// The next token, which must be there.
    fn need(&mut self, what: &str) -> Result<Token> {
        match self.next()? {
            Some(t) => Ok(t),
            None => Err(PbrtError::at(
                &self.last_loc,
                format!("the file ends where {what} was expected"),
            )),
        }
    }

    fn string(&mut self, directive: &Token, what: &str) -> Result<(String, Loc)> {
        let t = self.need(what)?;
        match t.kind {
            TokenKind::Str(s) => Ok((s, t.loc)),
            _ => Err(PbrtError::at(
                &t.loc,
                format!(
                    "{}: expected {what} (a quoted string), got {}",
                    name_of(directive),
                    t.describe()
                ),
            )),
        }
    }

    fn number(&mut self, directive: &Token) -> Result<f32> {
        let t = self.need("a number")?;
        match t.kind {
            TokenKind::Num { value, .. } => to_f32(value, &t),
            _ => Err(PbrtError::at(
                &t.loc,
                format!("{}: expected a number, got {}", name_of(directive), t.describe()),
            )),
        }
    }

    fn numbers<const N: usize>(&mut self, directive: &Token) -> Result<[f32; N]> {
        let mut v = [0.0; N];
        for x in &mut v {
            *x = self.number(directive)?;
        }
        Ok(v)
    }

    /// `[ 16 numbers ]` of Transform and ConcatTransform, as a matrix: pbrt
    /// reads them into a row-major matrix and transposes it, so they are the
    /// matrix's columns in order (glam's column-major layout).
    fn matrix(&mut self, directive: &Token) -> Result<Mat4> {
        let t = self.need("'['")?;
        if t.kind != TokenKind::Open {
            return Err(PbrtError::at(
                &t.loc,
                format!(
                    "{}: expected '[' and 16 numbers, got {}",
                    name_of(directive),
                    t.describe()
                ),
            ));
        }
        let m: [f32; 16] = self.numbers(directive)?;
        let t = self.need("']'")?;
        if t.kind != TokenKind::Close {
            return Err(PbrtError::at(
                &t.loc,
                format!(
                    "{}: expected ']' after 16 numbers, got {}",
                    name_of(directive),
                    t.describe()
                ),
            ));
        }
        Ok(Mat4::from_cols_array(&m))
    }

    /// A parameter list: `"type name" value` or `"type name" [ values ]`,
    /// until a token that is not a quoted string.
    fn params(&mut self) -> Result<Vec<Param>> {
        let mut out = vec![];
        loop {
            let Some(t) = self.next()? else {
                return Ok(out);
            };
            let TokenKind::Str(decl) = &t.kind else {
                self.unget(t);
                return Ok(out);
            };
            let mut words = decl.split([' ', '\t']).filter(|w| !w.is_empty());
            let (Some(ty_name), Some(name)) = (words.next(), words.next()) else {
                return Err(PbrtError::at(
                    &t.loc,
                    format!("\"{decl}\": a parameter is declared as \"type name\" (or is this a stray string?)"),
                ));
            };
            let Some(ty) = ParamType::parse(ty_name) else {
                return Err(PbrtError::at(
                    &t.loc,
                    format!("\"{decl}\": unknown parameter type '{ty_name}'"),
                ));
            };
            let name = name.to_string();
            let values = self.values(&t, ty, &name)?;
            if let (ParamType::Blackbody, Values::Floats(kelvin)) = (ty, &values) {
                if let Some(k) = kelvin.iter().find(|k| !(**k > 0.0 && k.is_finite())) {
                    return Err(PbrtError::at(
                        &t.loc,
                        format!("\"{decl}\": a blackbody's temperature {k} (kelvin) must be positive and finite"),
                    ));
                }
            }
            out.push(Param::new(ty, name, values, t.loc.clone(), self.gs.color_space.clone()));
        }
    }

    fn values(&mut self, decl: &Token, ty: ParamType, name: &str) -> Result<Values> {
        let label = format!("\"{} {name}\"", ty.name());
        let first = self.need(&format!("the value of {label}"))?;
        let mut tokens = vec![];
        if first.kind == TokenKind::Open {
            loop {
                let Some(t) = self.next()? else {
                    return Err(PbrtError::at(
                        &first.loc,
                        format!("{label}: unterminated '[': the file ends before its ']'"),
                    ));
                };
                match t.kind {
                    TokenKind::Close => break,
                    TokenKind::Open => return Err(PbrtError::at(&t.loc, format!("{label}: '[' inside a value list"))),
                    // A directive name (capitalised) here means a missing ']'.
                    TokenKind::Word(ref w) if w.starts_with(|c: char| c.is_ascii_uppercase()) => {
                        return Err(PbrtError::at(
                            &t.loc,
                            format!(
                                "{label}: {} in a value list (missing ']' for the '[' at {}:{}?)",
                                t.describe(),
                                first.loc.line,
                                first.loc.col
                            ),
                        ))
                    }
                    _ => tokens.push(t),
                }
            }
        } else {
            tokens.push(first);
        }
        if tokens.is_empty() {
            return Err(PbrtError::at(&decl.loc, format!("{label}: no values")));
        }
        let bad = |t: &Token, want: &str| {
            Err(PbrtError::at(
                &t.loc,
                format!("{label}: expected {want}, got {}", t.describe()),
            ))
        };
        let values = match ty {
            ParamType::Integer => {
                let mut v = Vec::with_capacity(tokens.len());
                for t in &tokens {
                    match t.kind {
                        TokenKind::Num { int: Some(i), .. } if i32::try_from(i).is_ok() => v.push(i as i32),
                        TokenKind::Num { int: Some(_), .. } => return bad(t, "an integer that fits in 32 bits"),
                        _ => return bad(t, "an integer"),
                    }
                }
                Values::Ints(v)
            }
            ParamType::Bool => {
                let mut v = Vec::with_capacity(tokens.len());
                for t in &tokens {
                    match &t.kind {
                        // Bare words are pbrt-v4's; quoted ones pbrt-v3's.
                        TokenKind::Word(w) | TokenKind::Str(w) if w == "true" => v.push(true),
                        TokenKind::Word(w) | TokenKind::Str(w) if w == "false" => v.push(false),
                        _ => return bad(t, "true or false"),
                    }
                }
                Values::Bools(v)
            }
            ParamType::String | ParamType::Texture => {
                let mut v = Vec::with_capacity(tokens.len());
                for t in &tokens {
                    match &t.kind {
                        TokenKind::Str(s) => v.push(s.clone()),
                        _ => return bad(t, "a quoted string"),
                    }
                }
                Values::Strings(v)
            }
            ParamType::Spectrum if matches!(tokens[0].kind, TokenKind::Str(_)) => {
                // One string that names no spectrum of pbrt-v4's is a file of
                // wavelength / value pairs, read as if given inline.
                if let [t] = &tokens[..] {
                    if let TokenKind::Str(s) = &t.kind {
                        if !is_named_spectrum(s) {
                            return self.spectrum_file(t, &label, s);
                        }
                    }
                }
                let mut v = Vec::with_capacity(tokens.len());
                for t in &tokens {
                    match &t.kind {
                        TokenKind::Str(s) if is_named_spectrum(s) => v.push(s.clone()),
                        TokenKind::Str(s) => {
                            return Err(PbrtError::at(
                                &t.loc,
                                format!(
                                    "{label}: \"{s}\" is not a spectrum pbrt-v4 names (such as \"metal-Cu-eta\"); \
                                     spectrum files are read only as a parameter's one value"
                                ),
                            ))
                        }
                        _ => return bad(t, "a quoted spectrum name"),
                    }
                }
                Values::Strings(v)
            }
            _ => {
                let mut v = Vec::with_capacity(tokens.len());
                for t in &tokens {
                    match t.kind {
                        TokenKind::Num { value, .. } => v.push(to_f32(value, t)?),
                        _ => return bad(t, "a number"),
                    }
                }
                let k = ty.per_item();
                if v.len() % k != 0 {
                    return Err(PbrtError::at(
                        &decl.loc,
                        format!("{label}: {} values, not a multiple of {k}", v.len()),
                    ));
                }
                if ty == ParamType::Spectrum {
                    if v.len() % 2 != 0 {
                        return Err(PbrtError::at(
                            &decl.loc,
                            format!("{label}: an odd number of values; a spectrum is wavelength / value pairs"),
                        ));
                    }
                    if let Some(w) = v
                        .chunks_exact(2)
                        .collect::<Vec<_>>()
                        .windows(2)
                        .find(|w| w[1][0] <= w[0][0])
                    {
                        return Err(PbrtError::at(
                            &decl.loc,
                            format!("{label}: wavelengths must increase ({} then {})", w[0][0], w[1][0]),
                        ));
                    }
                }
                if ty == ParamType::Rgb && v.iter().any(|&x| x < 0.0) {
                    return Err(PbrtError::at(&decl.loc, format!("{label}: a negative component")));
                }
                Values::Floats(v)
            }
        };
        Ok(values)
    }

    /// A spectrum file (pbrt-v4's `PiecewiseLinearSpectrum::Read`): numbers
    /// separated by white space, `#` comments, wavelength / value pairs with
    /// the wavelengths increasing.
    fn spectrum_file(&mut self, t: &Token, label: &str, name: &str) -> Result<Values> {
        let (path, bytes) = self.read_named(&t.loc, label, name)?;
        let at = |line: usize, what: String| {
            PbrtError::at(
                &t.loc,
                format!("{label}: spectrum file {}:{line}: {what}", path.display()),
            )
        };
        let text = String::from_utf8_lossy(&bytes);
        let mut pairs: Vec<f32> = vec![];
        for (i, line) in text.lines().enumerate() {
            let line_no = i + 1;
            let data = line.split('#').next().unwrap_or("");
            for word in data.split_whitespace() {
                match word.parse::<f32>() {
                    Ok(x) if x.is_finite() => pairs.push(x),
                    _ => return Err(at(line_no, format!("\"{word}\" is not a number"))),
                }
                if pairs.len().is_multiple_of(2) && pairs.len() >= 4 {
                    let n = pairs.len();
                    if pairs[n - 2] <= pairs[n - 4] {
                        return Err(at(
                            line_no,
                            format!("wavelengths must increase ({} then {})", pairs[n - 4], pairs[n - 2]),
                        ));
                    }
                }
            }
        }
        if pairs.is_empty() || !pairs.len().is_multiple_of(2) {
            return Err(at(
                text.lines().count().max(1),
                format!("{} values; a spectrum file holds wavelength / value pairs", pairs.len()),
            ));
        }
        Ok(Values::Floats(pairs))
    }

    // ---- checks ------------------------------------------------------------

    fn world_only(&self, t: &Token) -> Result<()> {
        if self.block == Block::Options {
            return Err(PbrtError::at(
                &t.loc,
                format!("{} is only allowed after WorldBegin", name_of(t)),
            ));
        }
        Ok(())
    }

    fn options_only(&self, t: &Token) -> Result<()> {
        if self.block == Block::World {
            return Err(PbrtError::at(
                &t.loc,
                format!("{} is not allowed after WorldBegin", name_of(t)),
            ));
        }
        Ok(())
    }

    fn warn(&mut self, loc: &Loc, message: impl Into<String>) {
        self.scene.warnings.push(Note {
            loc: loc.clone(),
            message: message.into(),
        });
    }

    fn unsupported(&mut self, loc: &Loc, message: impl Into<String>) {
        self.scene.unsupported.push(Note {
            loc: loc.clone(),
            message: message.into(),
        });
    }

    /// The CTM at the shutter's opening; motion (a different CTM at its
    /// close) is noted as unsupported.
    fn ctm_static(&mut self, loc: &Loc, what: &str) -> Mat4 {
        let [a, b] = self.gs.ctm;
        if a != b {
            self.unsupported(
                loc,
                format!(
                    "{what}: an animated transformation (ActiveTransform); --lenient uses the start transformation"
                ),
            );
        }
        a
    }

    fn apply(&mut self, f: impl Fn(Mat4) -> Mat4) {
        for i in 0..2 {
            if self.gs.active[i] {
                self.gs.ctm[i] = f(self.gs.ctm[i]);
            }
        }
    }

    // ---- parsing -----------------------------------------------------------

    /// Reads the scene from the top-level file's bytes.
    pub fn run(mut self, main: &Path, bytes: Vec<u8>) -> Result<PbrtScene> {
        self.note_file(main);
        let lexer = Lexer::new(Arc::new(main.to_path_buf()), bytes)?;
        self.parse_stream(lexer)?;
        self.finish()
    }

    fn parse_stream(&mut self, lexer: Lexer) -> Result<()> {
        self.streams.push(Stream {
            lexers: vec![lexer],
            pending: None,
        });
        let result = (|| {
            while let Some(t) = self.next()? {
                self.directive(t)?;
            }
            Ok(())
        })();
        self.streams.pop();
        result
    }

    fn directive(&mut self, t: Token) -> Result<()> {
        let TokenKind::Word(word) = &t.kind else {
            return Err(PbrtError::at(
                &t.loc,
                format!("expected a directive, got {}", t.describe()),
            ));
        };
        match word.as_str() {
            "Identity" => self.apply(|_| Mat4::IDENTITY),
            "Translate" => {
                let [x, y, z] = self.numbers(&t)?;
                self.apply(|m| m * Mat4::from_translation(Vec3::new(x, y, z)));
            }
            "Scale" => {
                let [x, y, z] = self.numbers(&t)?;
                self.apply(|m| m * Mat4::from_scale(Vec3::new(x, y, z)));
            }
            "Rotate" => {
                let [angle, x, y, z] = self.numbers(&t)?;
                let r = rotate(angle, Vec3::new(x, y, z))
                    .ok_or_else(|| PbrtError::at(&t.loc, "Rotate: the axis is zero"))?;
                self.apply(|m| m * r);
            }
            "LookAt" => {
                let v: [f32; 9] = self.numbers(&t)?;
                let l = look_at(
                    Vec3::new(v[0], v[1], v[2]),
                    Vec3::new(v[3], v[4], v[5]),
                    Vec3::new(v[6], v[7], v[8]),
                )
                .ok_or_else(|| {
                    PbrtError::at(
                        &t.loc,
                        "LookAt: the eye is at the target, or the up vector is zero or along the viewing direction",
                    )
                })?;
                self.apply(|m| m * l);
            }
            "Transform" => {
                let m = self.matrix(&t)?;
                self.apply(|_| m);
            }
            "ConcatTransform" => {
                let c = self.matrix(&t)?;
                self.apply(|m| m * c);
            }
            "CoordinateSystem" => {
                let (name, _) = self.string(&t, "a coordinate system name")?;
                self.named_coordinate_systems.insert(name, self.gs.ctm);
            }
            "CoordSysTransform" => {
                let (name, _) = self.string(&t, "a coordinate system name")?;
                match self.named_coordinate_systems.get(&name) {
                    Some(&ctm) => self.gs.ctm = ctm,
                    None => self.warn(
                        &t.loc,
                        format!("CoordSysTransform: no coordinate system \"{name}\"; ignored"),
                    ),
                }
            }
            "ActiveTransform" => {
                let a = self.need("All, StartTime or EndTime")?;
                self.gs.active = match &a.kind {
                    TokenKind::Word(w) if w == "All" => [true, true],
                    TokenKind::Word(w) if w == "StartTime" => [true, false],
                    TokenKind::Word(w) if w == "EndTime" => [false, true],
                    _ => {
                        return Err(PbrtError::at(
                            &a.loc,
                            format!(
                                "ActiveTransform: expected All, StartTime or EndTime, got {}",
                                a.describe()
                            ),
                        ))
                    }
                };
            }
            "TransformTimes" => {
                self.options_only(&t)?;
                let times: [f32; 2] = self.numbers(&t)?;
                if !(times[0].is_finite() && times[1].is_finite() && times[0] < times[1]) {
                    return Err(PbrtError::at(
                        &t.loc,
                        format!(
                            "TransformTimes {} {}: the times must be finite and increasing",
                            times[0], times[1]
                        ),
                    ));
                }
                self.scene.transform_times = times;
            }
            "ReverseOrientation" => {
                self.world_only(&t)?;
                self.gs.reverse_orientation = !self.gs.reverse_orientation;
            }
            "AttributeBegin" | "TransformBegin" => {
                self.world_only(&t)?;
                self.pushed.push((self.gs.clone(), Pushed::Attribute, t.loc.clone()));
            }
            "AttributeEnd" | "TransformEnd" => {
                self.world_only(&t)?;
                match self.pushed.pop() {
                    None => {
                        return Err(PbrtError::at(
                            &t.loc,
                            format!("{word} without a matching AttributeBegin"),
                        ))
                    }
                    Some((_, Pushed::Object, loc)) => {
                        return Err(PbrtError::at(
                            &t.loc,
                            format!(
                                "{word} closes the ObjectBegin at {}:{} (mismatched nesting)",
                                loc.line, loc.col
                            ),
                        ))
                    }
                    Some((gs, Pushed::Attribute, _)) => self.gs = gs,
                }
            }
            "Attribute" => {
                let (target, _) = self.string(&t, "an attribute target")?;
                let mut params = self.params()?;
                for p in &mut params {
                    p.from_attribute = true;
                }
                let list = match target.as_str() {
                    "shape" => &mut self.gs.shape_attributes,
                    "light" => &mut self.gs.light_attributes,
                    "material" => &mut self.gs.material_attributes,
                    "medium" => &mut self.gs.medium_attributes,
                    "texture" => &mut self.gs.texture_attributes,
                    _ => {
                        return Err(PbrtError::at(
                            &t.loc,
                            format!(
                                "Attribute: unknown target \"{target}\" (shape, light, material, medium or texture)"
                            ),
                        ))
                    }
                };
                list.extend(params);
            }
            "ColorSpace" => {
                let (name, _) = self.string(&t, "a colour space name")?;
                let lower = name.to_ascii_lowercase();
                if COLOR_SPACES.contains(&lower.as_str()) {
                    self.gs.color_space = Arc::from(lower.as_str());
                } else {
                    self.warn(
                        &t.loc,
                        format!("ColorSpace: unknown colour space \"{name}\" (srgb, dci-p3, rec2020, aces2065-1)"),
                    );
                }
            }
            "Option" => {
                let (name, _) = self.string(&t, "an option name")?;
                let v = self.need("an option value")?;
                let value = match &v.kind {
                    TokenKind::Str(s) => format!("\"{s}\""),
                    TokenKind::Word(w) => w.clone(),
                    TokenKind::Num { value, int } => int.map_or_else(|| value.to_string(), |i| i.to_string()),
                    _ => {
                        return Err(PbrtError::at(
                            &v.loc,
                            format!("Option: expected a value, got {}", v.describe()),
                        ))
                    }
                };
                let normalized: String = name
                    .chars()
                    .filter(|c| *c != '_' && *c != '-')
                    .map(|c| c.to_ascii_lowercase())
                    .collect();
                if !OPTIONS.contains(&normalized.as_str()) {
                    return Err(PbrtError::at(&t.loc, format!("Option: unknown option \"{name}\"")));
                }
                self.scene.options.push(OptionSetting {
                    name: normalized,
                    value,
                    loc: t.loc.clone(),
                });
            }
            "Camera" => {
                let (ty, _) = self.string(&t, "a camera type")?;
                let params = self.params()?;
                self.options_only(&t)?;
                let [from0, from1] = self.gs.ctm;
                let (Some(inv0), Some(inv1)) = (invert(from0), invert(from1)) else {
                    return Err(PbrtError::at(
                        &t.loc,
                        "Camera: the current transformation is not invertible",
                    ));
                };
                self.named_coordinate_systems.insert("camera".into(), [inv0, inv1]);
                self.scene.camera = Camera {
                    ty,
                    params: Params::new(params),
                    loc: Some(t.loc.clone()),
                    camera_from_world: from0,
                    world_from_camera: inv0,
                    world_from_camera_end: (from0 != from1).then_some(inv1),
                    medium: self.gs.outside_medium.clone(),
                };
            }
            "Film" | "Sampler" | "PixelFilter" | "Integrator" | "Accelerator" => {
                let (ty, _) = self.string(&t, "a type")?;
                let params = self.params()?;
                self.options_only(&t)?;
                let e = Entity {
                    ty,
                    params: Params::new(params),
                    loc: Some(t.loc.clone()),
                };
                match word.as_str() {
                    "Film" => self.scene.film = e,
                    "Sampler" => self.scene.sampler = e,
                    "PixelFilter" => self.scene.filter = e,
                    "Integrator" => self.scene.integrator = e,
                    _ => self.scene.accelerator = e,
                }
            }
            "WorldBegin" => {
                self.options_only(&t)?;
                self.block = Block::World;
                self.gs.ctm = [Mat4::IDENTITY; 2];
                self.gs.active = [true; 2];
                self.named_coordinate_systems
                    .insert("world".into(), [Mat4::IDENTITY; 2]);
            }
            "WorldEnd" => {
                return Err(PbrtError::at(
                    &t.loc,
                    "unknown directive WorldEnd (pbrt-v3 syntax: pbrt-v4 files have none)",
                ))
            }
            "Include" | "Import" => {
                let (name, _) = self.string(&t, "a file name")?;
                if word == "Include" {
                    // Nothing is read ahead after a file name, so the included
                    // file's tokens come next.
                    let lexer = self.open_scene_file(&t.loc, "Include", &name)?;
                    if let Some(s) = self.streams.last_mut() {
                        s.lexers.push(lexer);
                    }
                } else {
                    if self.block != Block::World {
                        return Err(PbrtError::at(&t.loc, "Import is only allowed after WorldBegin"));
                    }
                    let lexer = self.open_scene_file(&t.loc, "Import", &name)?;
                    let saved = self.gs.clone();
                    let depth = self.pushed.len();
                    self.parse_stream(lexer)?;
                    if self.pushed.len() != depth {
                        let (_, kind, loc) = self.pushed[self.pushed.len() - 1].clone();
                        let what = if kind == Pushed::Object {
                            "ObjectBegin"
                        } else {
                            "AttributeBegin"
                        };
                        return Err(PbrtError::at(
                            &loc,
                            format!("{what} without its end in an imported file"),
                        ));
                    }
                    self.gs = saved;
                }
            }
            "MakeNamedMaterial" => {
                let (name, _) = self.string(&t, "a material name")?;
                let params = self.params()?;
                self.world_only(&t)?;
                if self.scene.named_materials.contains_key(&name) {
                    return Err(PbrtError::at(
                        &t.loc,
                        format!("MakeNamedMaterial: \"{name}\" is defined twice"),
                    ));
                }
                let params = Params::with_attributes(params, &self.gs.material_attributes);
                let ty = params.get_string("type")?.ok_or_else(|| {
                    PbrtError::at(
                        &t.loc,
                        format!("MakeNamedMaterial \"{name}\": no \"string type\" parameter"),
                    )
                })?;
                self.scene
                    .named_materials
                    .insert(name.clone(), self.scene.materials.len());
                self.scene.materials.push(Material {
                    name: Some(name),
                    ty,
                    params,
                    loc: Some(t.loc.clone()),
                });
            }
            "Material" => {
                let (ty, _) = self.string(&t, "a material type")?;
                let params = self.params()?;
                self.world_only(&t)?;
                self.gs.material = MaterialRef::Index(self.scene.materials.len());
                self.scene.materials.push(Material {
                    name: None,
                    ty,
                    params: Params::with_attributes(params, &self.gs.material_attributes),
                    loc: Some(t.loc.clone()),
                });
            }
            "NamedMaterial" => {
                let (name, _) = self.string(&t, "a material name")?;
                self.world_only(&t)?;
                self.gs.material = MaterialRef::Named(name);
            }
            "Texture" => {
                let (name, _) = self.string(&t, "a texture name")?;
                let (kind, kind_loc) = self.string(&t, "\"float\" or \"spectrum\"")?;
                let (class, _) = self.string(&t, "a texture class")?;
                let params = self.params()?;
                self.world_only(&t)?;
                let kind = match kind.as_str() {
                    "float" => TextureKind::Float,
                    // "color" is pbrt-v3's name.
                    "spectrum" | "color" => TextureKind::Spectrum,
                    _ => {
                        return Err(PbrtError::at(
                            &kind_loc,
                            format!("Texture \"{name}\": type \"{kind}\" is neither \"float\" nor \"spectrum\""),
                        ))
                    }
                };
                if !self.texture_names.insert((name.clone(), kind)) {
                    return Err(PbrtError::at(&t.loc, format!("Texture \"{name}\" is defined twice")));
                }
                let world_from_texture = self.ctm_static(&t.loc, "Texture");
                self.scene.textures.push(Texture {
                    name,
                    kind,
                    class,
                    params: Params::with_attributes(params, &self.gs.texture_attributes),
                    world_from_texture,
                    loc: t.loc.clone(),
                });
            }
            "LightSource" => {
                let (ty, _) = self.string(&t, "a light type")?;
                let params = self.params()?;
                self.world_only(&t)?;
                let world_from_light = self.ctm_static(&t.loc, "LightSource");
                self.scene.lights.push(Light {
                    ty,
                    params: Params::with_attributes(params, &self.gs.light_attributes),
                    world_from_light,
                    medium: self.gs.outside_medium.clone(),
                    loc: t.loc.clone(),
                });
            }
            "AreaLightSource" => {
                let (ty, _) = self.string(&t, "an area light type")?;
                let params = self.params()?;
                self.world_only(&t)?;
                self.gs.area_light = Some(self.scene.area_lights.len());
                self.scene.area_lights.push(AreaLight {
                    ty,
                    params: Params::with_attributes(params, &self.gs.light_attributes),
                    loc: t.loc.clone(),
                });
            }
            "MakeNamedMedium" => {
                let (name, _) = self.string(&t, "a medium name")?;
                let params = self.params()?;
                if self.scene.media.iter().any(|m| m.name == name) {
                    return Err(PbrtError::at(
                        &t.loc,
                        format!("MakeNamedMedium: \"{name}\" is defined twice"),
                    ));
                }
                let params = Params::with_attributes(params, &self.gs.medium_attributes);
                let ty = params.get_string("type")?.ok_or_else(|| {
                    PbrtError::at(
                        &t.loc,
                        format!("MakeNamedMedium \"{name}\": no \"string type\" parameter"),
                    )
                })?;
                let world_from_medium = self.ctm_static(&t.loc, "MakeNamedMedium");
                // A NanoVDB file is read here, where files are found (as
                // pbrt-v4 finds it: beside the scene file).
                let file = if ty == "nanovdb" {
                    let at = params.loc_of("filename").unwrap_or(&t.loc).clone();
                    let file_name = params.get_string("filename")?.unwrap_or_default();
                    let what = format!("MakeNamedMedium \"{name}\": nanovdb");
                    let (path, bytes) = self.read_named(&at, &what, &file_name)?;
                    Some((path, Arc::new(bytes)))
                } else {
                    None
                };
                self.scene.media.push(Medium {
                    name,
                    ty,
                    params,
                    world_from_medium,
                    loc: t.loc.clone(),
                    file,
                });
            }
            "MediumInterface" => {
                let (inside, _) = self.string(&t, "a medium name")?;
                let outside = match self.next()? {
                    Some(Token {
                        kind: TokenKind::Str(s),
                        ..
                    }) => s,
                    Some(other) => {
                        self.unget(other);
                        inside.clone()
                    }
                    None => inside.clone(),
                };
                let some = |s: String| (!s.is_empty()).then_some(s);
                self.gs.inside_medium = some(inside);
                self.gs.outside_medium = some(outside);
            }
            "Shape" => {
                let (ty, _) = self.string(&t, "a shape type")?;
                let params = self.params()?;
                self.world_only(&t)?;
                self.shape(&t, ty, params)?;
            }
            "ObjectBegin" => {
                let (name, _) = self.string(&t, "an object name")?;
                self.world_only(&t)?;
                if let Some(def) = &self.active_object {
                    return Err(PbrtError::at(
                        &t.loc,
                        format!(
                            "ObjectBegin inside the definition of \"{}\" (begun at {}:{})",
                            def.name, def.loc.line, def.loc.col
                        ),
                    ));
                }
                if self.objects.contains_key(&name) {
                    return Err(PbrtError::at(
                        &t.loc,
                        format!("ObjectBegin: \"{name}\" is defined twice"),
                    ));
                }
                self.pushed.push((self.gs.clone(), Pushed::Object, t.loc.clone()));
                self.active_object = Some(ObjectDef {
                    name,
                    loc: t.loc.clone(),
                    shapes: vec![],
                });
            }
            "ObjectEnd" => {
                self.world_only(&t)?;
                let Some(def) = self.active_object.take() else {
                    return Err(PbrtError::at(&t.loc, "ObjectEnd without ObjectBegin"));
                };
                match self.pushed.pop() {
                    Some((gs, Pushed::Object, _)) => self.gs = gs,
                    Some((_, Pushed::Attribute, loc)) => {
                        return Err(PbrtError::at(
                            &t.loc,
                            format!(
                                "ObjectEnd closes the AttributeBegin at {}:{} (mismatched nesting)",
                                loc.line, loc.col
                            ),
                        ))
                    }
                    None => return Err(PbrtError::at(&t.loc, "ObjectEnd without ObjectBegin")),
                }
                self.objects.insert(def.name, (def.loc, Arc::new(def.shapes)));
            }
            "ObjectInstance" => {
                let (name, _) = self.string(&t, "an object name")?;
                self.world_only(&t)?;
                if let Some(def) = &self.active_object {
                    return Err(PbrtError::at(
                        &t.loc,
                        format!("ObjectInstance inside the definition of \"{}\"", def.name),
                    ));
                }
                // A moving instance moves its shapes (flattened).
                let ctm = self.gs.ctm;
                self.items.push(Item::Instance {
                    name,
                    ctm,
                    loc: t.loc.clone(),
                });
            }
            _ => {
                return Err(PbrtError::at(&t.loc, format!("unknown directive {}", t.describe())));
            }
        }
        Ok(())
    }

    fn shape(&mut self, t: &Token, ty: String, params: Vec<Param>) -> Result<()> {
        let params = Params::with_attributes(params, &self.gs.shape_attributes);
        let mut found = Findings::default();
        let geometry = match ty.as_str() {
            "trianglemesh" => Geometry::Mesh(Arc::new(shapes::triangle_mesh(&params, &t.loc, &mut found)?)),
            "bilinearmesh" => Geometry::Mesh(Arc::new(shapes::bilinear_mesh(&params, &t.loc, &mut found)?)),
            "loopsubdiv" => Geometry::Mesh(Arc::new(shapes::loop_subdiv(&params, &t.loc, &mut found)?)),
            "plymesh" => {
                let name = params.get_string("filename")?.unwrap_or_default();
                if params.get_texture("displacement")?.is_some() {
                    found
                        .unsupported
                        .push("plymesh: displacement mapping (\"displacement\") is not supported".into());
                }
                Geometry::Mesh(self.ply(&t.loc, &name)?)
            }
            "sphere" => Geometry::Sphere(shapes::sphere(&params, &t.loc)?),
            "disk" => Geometry::Disk(shapes::disk(&params, &t.loc)?),
            "cylinder" => Geometry::Mesh(Arc::new(shapes::cylinder(&params, &t.loc)?)),
            "curve" => match shapes::curves(&params, &t.loc, &mut found)? {
                Some(c) => Geometry::Curves(c),
                None => Geometry::Other,
            },
            _ if shapes::SHAPE_TYPES.contains(&ty.as_str()) => {
                found.unsupported.push(format!("shape \"{ty}\" is not supported"));
                Geometry::Other
            }
            _ => {
                found.unsupported.push(format!("\"{ty}\" is not a pbrt-v4 shape type"));
                Geometry::Other
            }
        };
        for w in found.warnings {
            self.warn(&t.loc, w);
        }
        for u in found.unsupported {
            self.unsupported(&t.loc, u);
        }
        // A shape outside object definitions may move; pbrt-v4 lights none
        // that moves.
        let [start, end] = self.gs.ctm;
        let moving = start != end && self.active_object.is_none() && self.gs.area_light.is_none();
        let (world_from_object, motion) = if moving {
            (start, Some([start, end]))
        } else {
            (self.ctm_static(&t.loc, "Shape"), None)
        };
        let mut area_light = self.gs.area_light;
        if area_light.is_some() && self.active_object.is_some() {
            self.warn(
                &t.loc,
                "area lights are not supported in object instances (pbrt-v4 ignores them); the shape does not emit",
            );
            area_light = None;
        }
        let pending = PendingShape {
            shape: Shape {
                ty,
                params: Arc::new(params),
                geometry,
                world_from_object,
                motion,
                reverse_orientation: self.gs.reverse_orientation,
                material: 0,
                area_light,
                inside_medium: self.gs.inside_medium.clone(),
                outside_medium: self.gs.outside_medium.clone(),
                instance: None,
                loc: t.loc.clone(),
            },
            material: self.gs.material.clone(),
        };
        match &mut self.active_object {
            Some(def) => def.shapes.push(pending),
            None => self.items.push(Item::Shape(Box::new(pending))),
        }
        Ok(())
    }

    fn ply(&mut self, loc: &Loc, name: &str) -> Result<Arc<TriMesh>> {
        // Only the first candidate may be taken from the cache unread: a later
        // one is the file only when the earlier ones do not exist.
        if let Some(m) = candidates(&loc.file, &self.scene_dir, name)
            .first()
            .and_then(|p| self.ply_cache.get(p))
        {
            return Ok(m.clone());
        }
        let (path, bytes) = self.read_named(loc, "plymesh", name)?;
        if let Some(m) = self.ply_cache.get(&path) {
            return Ok(m.clone());
        }
        let stand_in = Arc::new(TriMesh {
            positions: Vec::new(),
            normals: None,
            uvs: None,
            triangles: Vec::new(),
            quads_split: 0,
            second_halves: Vec::new(),
            file: Some(path.clone()),
            quadric: false,
        });
        self.ply_cache.insert(path.clone(), stand_in.clone());
        self.ply_jobs.push(PlyJob {
            path,
            bytes,
            loc: loc.clone(),
            name: name.to_string(),
            stand_in: stand_in.clone(),
        });
        Ok(stand_in)
    }

    /// Decodes every `plymesh` file read, in parallel; the first error in
    /// the order of the files, and each file's warnings in that order. The
    /// meshes by the address of their stand-ins.
    fn decode_plys(&mut self) -> Result<HashMap<usize, Arc<TriMesh>>> {
        use rayon::prelude::*;
        let jobs = std::mem::take(&mut self.ply_jobs);
        let reads: Vec<_> = jobs
            .par_iter()
            .map(|j| ply::read(&j.path, &j.bytes, ply::Polygons::TrianglesAndQuads))
            .collect();
        let mut meshes = HashMap::with_capacity(jobs.len());
        for (job, read) in jobs.into_iter().zip(reads) {
            let (loc, name) = (&job.loc, &job.name);
            let read = read.map_err(|e| PbrtError::at(loc, format!("plymesh \"{name}\": {e}")))?;
            if read.skipped_faces > 0 {
                self.warn(
                    loc,
                    format!(
                        "plymesh \"{name}\": {} faces of other than 3 or 4 vertices skipped (as pbrt-v4 does)",
                        read.skipped_faces
                    ),
                );
            }
            for note in read.normals_note().into_iter().chain(read.trailing_note()) {
                self.warn(loc, format!("plymesh \"{name}\": {note}"));
            }
            if read.triangles.is_empty() {
                self.warn(loc, format!("plymesh \"{name}\": the mesh has no faces"));
            }
            let mut second_halves = read.second_halves;
            if !second_halves.is_empty() {
                second_halves.resize(read.triangles.len(), false);
            }
            let mesh = Arc::new(TriMesh {
                positions: read.positions,
                normals: read.normals,
                uvs: read.uvs,
                triangles: read.triangles,
                quads_split: read.quads,
                second_halves,
                file: Some(job.path),
                quadric: false,
            });
            meshes.insert(Arc::as_ptr(&job.stand_in) as usize, mesh);
        }
        Ok(meshes)
    }

    fn resolve_material(&self, r: &MaterialRef, loc: &Loc) -> Result<usize> {
        match r {
            MaterialRef::Index(i) => Ok(*i),
            MaterialRef::Named(name) => self.scene.named_materials.get(name).copied().ok_or_else(|| {
                PbrtError::at(
                    loc,
                    format!("the shape's material \"{name}\" is not defined (NamedMaterial)"),
                )
            }),
        }
    }

    fn finish(mut self) -> Result<PbrtScene> {
        let meshes = self.decode_plys()?;
        if let Some((_, kind, loc)) = self.pushed.last() {
            let what = if *kind == Pushed::Object {
                "ObjectBegin without ObjectEnd"
            } else {
                "AttributeBegin without AttributeEnd"
            };
            return Err(PbrtError::at(loc, what));
        }
        if self.block != Block::World {
            return Err(PbrtError::at(&self.last_loc, "the scene ends before WorldBegin"));
        }
        let items = std::mem::take(&mut self.items);
        let mut shapes = Vec::with_capacity(items.len());
        for item in items {
            match item {
                Item::Shape(p) => {
                    let mut s = p.shape;
                    s.material = self.resolve_material(&p.material, &s.loc)?;
                    shapes.push(s);
                }
                Item::Instance { name, ctm, loc } => {
                    let Some((_, def)) = self.objects.get(&name) else {
                        return Err(PbrtError::at(
                            &loc,
                            format!("ObjectInstance: object \"{name}\" is not defined"),
                        ));
                    };
                    if shapes.len() + def.len() > MAX_SHAPES {
                        return Err(PbrtError::at(
                            &loc,
                            format!("more than {MAX_SHAPES} shapes once object instances are flattened"),
                        ));
                    }
                    for p in def.iter() {
                        let mut s = p.shape.clone();
                        s.material = self.resolve_material(&p.material, &s.loc)?;
                        let [start, end] = ctm;
                        s.motion = (start != end).then_some(ctm);
                        s.world_from_object = start * s.world_from_object;
                        s.instance = Some(InstanceUse {
                            object: name.clone(),
                            loc: loc.clone(),
                        });
                        shapes.push(s);
                    }
                }
            }
        }
        // Shapes of objects never instanced still need their materials.
        for (_, def) in self.objects.values() {
            for p in def.iter() {
                self.resolve_material(&p.material, &p.shape.loc)?;
            }
        }
        for s in &mut shapes {
            if let Geometry::Mesh(m) = &s.geometry {
                if let Some(mesh) = meshes.get(&(Arc::as_ptr(m) as usize)) {
                    s.geometry = Geometry::Mesh(mesh.clone());
                }
            }
        }
        self.scene.shapes = shapes;
        Ok(self.scene)
    }
}

fn name_of(t: &Token) -> String {
    match &t.kind {
        TokenKind::Word(w) => w.clone(),
        _ => t.describe(),
    }
}

fn to_f32(value: f64, t: &Token) -> Result<f32> {
    let v = value as f32;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(PbrtError::at(
            &t.loc,
            format!("{}: the number is too large", t.describe()),
        ))
    }
}
