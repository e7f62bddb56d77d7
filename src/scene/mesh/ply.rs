//! Stanford PLY (Turk, "The PLY Polygon File Format", 1994): ASCII,
//! binary_little_endian and binary_big_endian, gzip-compressed when the
//! name ends in `.gz`. We read the `vertex` element's x, y, z (and nx, ny,
//! nz when all three are there, and texture coordinates u, v or s, t or
//! texture_u, texture_v or texture_s, texture_t) and the `face` element's
//! `vertex_indices` (or `vertex_index`) list; every other property and
//! element is skipped whatever its type.
//!
//! The one PLY reader of the crate: [`read`] serves both the mesh loader
//! (OBJ/PLY meshes, [`Polygons::Fan`]: polygons of any size are
//! fan-triangulated) and pbrt-v4's `plymesh` ([`Polygons::TrianglesAndQuads`]:
//! pbrt-v4's util/mesh.cpp `TriQuadMesh::ReadPLY` keeps triangles and quads
//! and skips other faces with a warning; a quad, a bilinear patch there,
//! becomes the two triangles of its fan here, exact when it is planar).
//! Errors name the file and the line (ASCII) or byte offset (binary).
//!
//! A header's counts are never trusted for allocation: before reading, the
//! smallest size the declared elements could take is checked against the
//! bytes that follow the header, so a header claiming 10^12 vertices fails at
//! once instead of reserving memory for them.

use super::{Mesh, MeshPart};
use crate::error::{Error, Result};
use crate::math::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

/// Decompressed `.gz` files larger than this are refused.
pub const MAX_DECOMPRESSED: u64 = 4 << 30;

/// Decompresses gzip data (a `.gz` file), refusing more than `MAX_DECOMPRESSED` bytes.
pub fn gunzip(bytes: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let mut out = Vec::new();
    flate2::read::MultiGzDecoder::new(bytes)
        .take(MAX_DECOMPRESSED + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("cannot decompress: {e}"))?;
    if out.len() as u64 > MAX_DECOMPRESSED {
        return Err(format!("decompresses to more than {MAX_DECOMPRESSED} bytes"));
    }
    Ok(out)
}

/// What becomes of a face's polygon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Polygons {
    /// Every polygon is fan-triangulated; fewer than three vertices add nothing.
    Fan,
    /// pbrt-v4's `plymesh`: triangles, and quads as their two fan
    /// triangles; other faces are skipped and counted.
    TrianglesAndQuads,
}

/// A PLY file's vertices and triangles.
#[derive(Clone, Debug, Default)]
pub struct PlyData {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub triangles: Vec<[u32; 3]>,
    /// Quads (each two triangles).
    pub quads: usize,
    /// Under [`Polygons::TrianglesAndQuads`], which triangles are a quad's
    /// second (empty where there are no quads).
    pub second_halves: Vec<bool>,
    /// Faces skipped under [`Polygons::TrianglesAndQuads`].
    pub skipped_faces: usize,
    /// Vertices whose normal is not finite (some exporters write NaN where
    /// a normal is undefined): read as having no normal, so that the
    /// triangles around them are shaded flat.
    pub non_finite_normals: usize,
    /// ASCII: the line where data follows the last element the header
    /// declares (ignored, as pbrt-v4's reader ignores it; most likely the
    /// header's counts are wrong).
    pub trailing_line: Option<usize>,
}

/// The names PLY writers give a vertex's texture coordinates, in the order tried.
const UV_NAMES: [[&str; 2]; 4] = [
    ["u", "v"],
    ["s", "t"],
    ["texture_u", "texture_v"],
    ["texture_s", "texture_t"],
];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

/// Scalar types, by their PLY names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Debug)]
enum PropertyType {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    ty: PropertyType,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    /// Header line that declared the element.
    line: usize,
}

impl Element {
    /// The fewest bytes one item can take: in binary the scalars and list
    /// counts; in ASCII one character and one separator per property.
    fn min_item_bytes(&self, format: Format) -> u64 {
        match format {
            Format::Ascii => 2 * self.properties.len() as u64,
            _ => self
                .properties
                .iter()
                .map(|p| match p.ty {
                    PropertyType::Scalar(s) => s.size() as u64,
                    PropertyType::List { count, .. } => count.size() as u64,
                })
                .sum(),
        }
    }

    fn index_of(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name)
    }
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body: usize,
    /// Line number of the first body line (for ASCII errors).
    body_line: usize,
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    let err = |line: usize, message: String| Error::Syntax {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut pos = 0;
    let mut line = 0;
    let mut format = None;
    let mut elements: Vec<Element> = vec![];
    loop {
        line += 1;
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(err(line, "the header has no end_header line".into()));
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        let text = std::str::from_utf8(raw).map_err(|_| err(line, "header is not ASCII text".into()))?;
        let words: Vec<&str> = text.split_whitespace().collect();
        if line == 1 {
            if words != ["ply"] {
                return Err(err(1, "not a PLY file (the first line must be 'ply')".into()));
            }
            continue;
        }
        match words.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    _ => return Err(err(line, format!("unknown format '{f}'"))),
                });
            }
            ["element", name, count] => {
                let count = count
                    .parse::<u64>()
                    .map_err(|_| err(line, format!("bad element count '{count}'")))?;
                // A second vertex list would leave indices and normals meaning
                // different lists; nothing writes one, so it is an error.
                if let Some(first) = elements
                    .iter()
                    .find(|e| e.name == *name && matches!(*name, "vertex" | "face"))
                {
                    return Err(err(
                        line,
                        format!("element '{name}' is declared twice (first at line {})", first.line),
                    ));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: vec![],
                    line,
                });
            }
            ["property", rest @ ..] => {
                let Some(el) = elements.last_mut() else {
                    return Err(err(line, "property before any element".into()));
                };
                let scalar =
                    |s: &str| Scalar::parse(s).ok_or_else(|| err(line, format!("unknown property type '{s}'")));
                let (ty, name) = match rest {
                    ["list", c, i, name] => {
                        let (count, item) = (scalar(c)?, scalar(i)?);
                        if !count.is_integer() {
                            return Err(err(line, format!("list count type '{c}' is not an integer type")));
                        }
                        (PropertyType::List { count, item }, name)
                    }
                    [t, name] => (PropertyType::Scalar(scalar(t)?), name),
                    _ => return Err(err(line, format!("malformed property line '{text}'"))),
                };
                el.properties.push(Property {
                    name: name.to_string(),
                    ty,
                });
            }
            ["end_header"] => break,
            _ => return Err(err(line, format!("unexpected header line '{text}'"))),
        }
    }
    let format = format.ok_or_else(|| err(line, "the header has no format line".into()))?;
    // Refuse counts the file cannot hold before anything is allocated for them.
    let available = (bytes.len() - pos) as u128;
    let mut needed: u128 = 0;
    for el in &elements {
        needed += el.count as u128 * el.min_item_bytes(format) as u128;
        if needed > available + 1 {
            return Err(err(
                el.line,
                format!(
                    "element '{}' declares {} items, more than the {} bytes after the header can hold",
                    el.name, el.count, available
                ),
            ));
        }
    }
    Ok(Header {
        format,
        elements,
        body: pos,
        body_line: line + 1,
    })
}

/// Reads the body's numbers one at a time, in either encoding, and reports
/// where it is (line for ASCII, byte offset for binary).
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: Format,
    line: usize,
    /// Line of the last ASCII token read.
    token_line: usize,
}

impl Reader<'_> {
    /// The error at the reader's position, or at `at` (line, offset) when given.
    fn error(&self, path: &Path, at: Option<(usize, usize)>, message: String) -> Error {
        let (line, pos) = at.unwrap_or((self.line, self.pos));
        match self.format {
            Format::Ascii => Error::Syntax {
                path: path.to_path_buf(),
                line,
                message,
            },
            _ => Error::Binary {
                path: path.to_path_buf(),
                offset: pos as u64,
                message,
            },
        }
    }

    /// Moves past whitespace to the next ASCII token (no-op for binary).
    fn skip_space(&mut self) {
        if self.format != Format::Ascii {
            return;
        }
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            if self.bytes[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// Next ASCII token, or None at the end of the file.
    fn token(&mut self) -> Option<&[u8]> {
        self.skip_space();
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if self.pos == start {
            // At the end of the file, blame the line the last token was on.
            self.line = self.token_line;
            return None;
        }
        self.token_line = self.line;
        Some(&self.bytes[start..self.pos])
    }

    /// Reads one scalar as f64 (exact for every PLY integer type).
    fn read(&mut self, ty: Scalar, what: &dyn Fn() -> String) -> std::result::Result<f64, String> {
        match self.format {
            Format::Ascii => {
                let tok = self
                    .token()
                    .ok_or_else(|| format!("unexpected end of file reading {}", what()))?;
                let s = std::str::from_utf8(tok).unwrap_or("?");
                let v = if ty.is_integer() {
                    s.parse::<i64>().map(|v| v as f64).ok()
                } else {
                    s.parse::<f64>().ok()
                };
                v.ok_or_else(|| format!("bad number '{s}' in {}", what()))
            }
            Format::BinaryLe | Format::BinaryBe => {
                let n = ty.size();
                if self.bytes.len() - self.pos < n {
                    return Err(format!("file truncated reading {}", what()));
                }
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(&self.bytes[self.pos..self.pos + n]);
                if self.format == Format::BinaryBe {
                    b[..n].reverse();
                }
                self.pos += n;
                let [b0, b1, b2, b3, ..] = b;
                Ok(match ty {
                    Scalar::I8 => b0 as i8 as f64,
                    Scalar::U8 => b0 as f64,
                    Scalar::I16 => i16::from_le_bytes([b0, b1]) as f64,
                    Scalar::U16 => u16::from_le_bytes([b0, b1]) as f64,
                    Scalar::I32 => i32::from_le_bytes([b0, b1, b2, b3]) as f64,
                    Scalar::U32 => u32::from_le_bytes([b0, b1, b2, b3]) as f64,
                    Scalar::F32 => f32::from_le_bytes([b0, b1, b2, b3]) as f64,
                    Scalar::F64 => f64::from_le_bytes(b),
                })
            }
        }
    }

    /// Skips a list's items, refusing counts the rest of the file cannot hold.
    fn skip_list(&mut self, n: usize, item: Scalar, what: &dyn Fn() -> String) -> std::result::Result<(), String> {
        if self.format != Format::Ascii {
            if (self.bytes.len() - self.pos) / item.size() < n {
                return Err(format!("file truncated reading {}", what()));
            }
            self.pos += n * item.size();
            return Ok(());
        }
        for _ in 0..n {
            self.read(item, what)?;
        }
        Ok(())
    }
}

/// A mesh of the mesh loader: polygons fan-triangulated, one part named
/// after the file.
pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let data = read(path, bytes, Polygons::Fan)?;
    if let (true, Some(line)) = (data.triangles.is_empty(), data.trailing_line) {
        // "No faces" would mislead: the header's counts stop short of the data.
        return Err(Error::Syntax {
            path: path.to_path_buf(),
            line,
            message: format!(
                "data beyond the {} vertices and the faces the header declares, and no faces among those: are the header's counts right?",
                data.positions.len()
            ),
        });
    }
    let warnings = data.normals_note().into_iter().chain(data.trailing_note()).collect();
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let parts = vec![MeshPart {
        name,
        material: None,
        albedo: None,
        triangles: 0..data.triangles.len(),
    }];
    Ok(Mesh {
        path: path.to_path_buf(),
        positions: data.positions,
        normals: data.normals,
        uvs: data.uvs,
        triangles: data.triangles,
        parts,
        warnings,
    })
}

/// Reads a PLY file's bytes (gzip-compressed when `path` ends in `.gz`);
/// `path` names it in errors.
pub fn read(path: &Path, bytes: &[u8], polygons: Polygons) -> Result<PlyData> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz")) {
        let bytes = gunzip(bytes).map_err(|message| Error::Parse {
            path: path.to_path_buf(),
            message,
        })?;
        return read_plain(path, &bytes, polygons);
    }
    read_plain(path, bytes, polygons)
}

fn read_plain(path: &Path, bytes: &[u8], polygons: Polygons) -> Result<PlyData> {
    let header = parse_header(path, bytes)?;
    let herr = |line: usize, message: String| Error::Syntax {
        path: path.to_path_buf(),
        line,
        message,
    };
    let Some(vertex_el) = header.elements.iter().find(|e| e.name == "vertex") else {
        return Err(herr(
            header.body_line - 1,
            "the header declares no vertex element".into(),
        ));
    };
    let vertex_count = vertex_el.count;
    let mut r = Reader {
        bytes,
        pos: header.body,
        format: header.format,
        line: header.body_line,
        token_line: header.body_line,
    };
    let mut mesh = PlyData::default();
    for el in &header.elements {
        // Where the properties we want sit in each item.
        let (mut xyz, mut nxyz, mut indices) = ([None; 3], [None; 3], None);
        let mut uv_ix: [Option<usize>; 2] = [None; 2];
        match el.name.as_str() {
            "vertex" => {
                for (k, n) in ["x", "y", "z"].iter().enumerate() {
                    xyz[k] = el.index_of(n);
                }
                for (k, n) in ["nx", "ny", "nz"].iter().enumerate() {
                    nxyz[k] = el.index_of(n);
                }
                // Texture coordinates under any of their usual names, the first pair present.
                for [u, v] in UV_NAMES {
                    if let (Some(a), Some(b)) = (el.index_of(u), el.index_of(v)) {
                        uv_ix = [Some(a), Some(b)];
                        break;
                    }
                }
                if xyz.iter().any(Option::is_none) {
                    return Err(herr(el.line, "the vertex element has no x, y and z properties".into()));
                }
                for i in xyz.iter().chain(&nxyz).chain(&uv_ix).flatten() {
                    if matches!(el.properties[*i].ty, PropertyType::List { .. }) {
                        return Err(herr(
                            el.line,
                            format!("vertex property '{}' is a list", el.properties[*i].name),
                        ));
                    }
                }
                // Reserve what the file can really hold, never the bare count.
                let fits = (bytes.len() - r.pos) as u64 / el.min_item_bytes(header.format).max(1);
                mesh.positions.reserve(el.count.min(fits) as usize);
            }
            "face" => {
                indices = el.index_of("vertex_indices").or_else(|| el.index_of("vertex_index"));
                match indices.map(|i| &el.properties[i].ty) {
                    Some(PropertyType::List { item, .. }) if item.is_integer() => {}
                    _ => {
                        return Err(herr(
                            el.line,
                            "the face element has no integer list 'vertex_indices' (or 'vertex_index')".into(),
                        ))
                    }
                }
            }
            _ => {}
        }
        // Elements without properties take no bytes (and, in ASCII, no tokens).
        if el.properties.is_empty() {
            continue;
        }
        let has_normals = nxyz.iter().all(Option::is_some);
        let has_uvs = uv_ix.iter().all(Option::is_some);
        let mut normals = vec![];
        let mut uvs = vec![];
        let mut values = vec![0.0f64; el.properties.len()];
        let mut face: Vec<u32> = vec![];
        for item in 0..el.count {
            r.skip_space();
            let start = Some((r.line, r.pos));
            for (k, prop) in el.properties.iter().enumerate() {
                let what = || format!("{} {item} property '{}'", el.name, prop.name);
                match prop.ty {
                    PropertyType::Scalar(s) => values[k] = r.read(s, &what).map_err(|m| r.error(path, None, m))?,
                    PropertyType::List { count, item: ty } => {
                        let n = r.read(count, &what).map_err(|m| r.error(path, None, m))?;
                        if n < 0.0 {
                            return Err(r.error(path, None, format!("negative list length {n} in {}", what())));
                        }
                        let n = n as usize;
                        if Some(k) != indices {
                            r.skip_list(n, ty, &what).map_err(|m| r.error(path, None, m))?;
                            continue;
                        }
                        face.clear();
                        for _ in 0..n {
                            r.skip_space();
                            let at = Some((r.line, r.pos));
                            let i = r.read(ty, &what).map_err(|m| r.error(path, None, m))?;
                            if !(i >= 0.0 && i < vertex_count as f64) {
                                return Err(r.error(
                                    path,
                                    at,
                                    format!("face {item} vertex index {i} is out of range (0..{vertex_count})"),
                                ));
                            }
                            face.push(i as u32);
                        }
                        if polygons == Polygons::TrianglesAndQuads && !(3..=4).contains(&face.len()) {
                            mesh.skipped_faces += 1;
                            continue;
                        }
                        mesh.quads += usize::from(face.len() == 4);
                        if polygons == Polygons::TrianglesAndQuads && face.len() == 4 {
                            mesh.second_halves.resize(mesh.triangles.len(), false);
                            mesh.second_halves.extend([false, true]);
                        }
                        // Fan-triangulate; faces of fewer than three vertices add nothing.
                        for j in 2..face.len() {
                            mesh.triangles.push([face[0], face[j - 1], face[j]]);
                        }
                    }
                }
            }
            if el.name == "vertex" {
                let get = |ix: [Option<usize>; 3]| {
                    Vec3::new(
                        values[ix[0].unwrap_or(0)] as f32,
                        values[ix[1].unwrap_or(0)] as f32,
                        values[ix[2].unwrap_or(0)] as f32,
                    )
                };
                let p = get(xyz);
                if !p.is_finite() {
                    return Err(r.error(path, start, format!("vertex {item} is not finite: {p}")));
                }
                mesh.positions.push(p);
                if has_normals {
                    let n = get(nxyz);
                    if n.is_finite() {
                        normals.push(n);
                    } else {
                        mesh.non_finite_normals += 1;
                        normals.push(Vec3::ZERO);
                    }
                }
                if let [Some(iu), Some(iv)] = uv_ix {
                    let t = Vec2::new(values[iu] as f32, values[iv] as f32);
                    if !t.is_finite() {
                        return Err(r.error(
                            path,
                            start,
                            format!("vertex {item} has a non-finite texture coordinate: {t}"),
                        ));
                    }
                    uvs.push(t);
                }
            }
        }
        if el.name == "vertex" && has_normals {
            mesh.normals = Some(normals);
        }
        if el.name == "vertex" && has_uvs {
            mesh.uvs = Some(uvs);
        }
    }
    if header.format == Format::Ascii {
        r.skip_space();
        if r.pos < bytes.len() {
            mesh.trailing_line = Some(r.line);
        }
    }
    Ok(mesh)
}

impl PlyData {
    /// What the vertices without a finite normal mean for the render, if
    /// there are any.
    pub fn normals_note(&self) -> Option<String> {
        (self.non_finite_normals > 0).then(|| {
            format!(
                "{} of {} vertices have a normal that is not finite: the triangles around them are shaded flat",
                self.non_finite_normals,
                self.positions.len()
            )
        })
    }

    /// What the file's data beyond its declared elements means for the
    /// reader, if there is any.
    pub fn trailing_note(&self) -> Option<String> {
        let counts = format!(
            "beyond the {} vertices and the faces the header declares",
            self.positions.len()
        );
        self.trailing_line
            .map(|line| format!("line {line}: data {counts} is ignored (are the header's counts right?)"))
    }
}
