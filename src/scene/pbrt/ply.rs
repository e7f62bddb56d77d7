//! PLY meshes as pbrt-v4's `plymesh` reads them (util/mesh.cpp,
//! `TriQuadMesh::ReadPLY`): vertex `x y z`, optional `nx ny nz`, optional
//! texture coordinates under any of the names `u v`, `s t`, `texture_u
//! texture_v`, `texture_s texture_t`; face `vertex_indices` (or
//! `vertex_index`) lists of 3 or 4 vertices. A quad is a bilinear patch in
//! pbrt-v4 and becomes two triangles here (exact when it is planar); faces
//! of other sizes are skipped and counted, as pbrt-v4 skips them with a
//! warning. `.gz` files are decompressed first.
//!
//! The project's own PLY reader (`scene::mesh`) has no texture coordinates,
//! fans polygons of any size and reads no gzip, so this one is separate; like
//! it, it never trusts a header's counts for allocation: the declared
//! elements must fit in the bytes that follow the header.

use super::ir::TriMesh;
use crate::math::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

/// Decompressed `.ply.gz` files larger than this are refused.
pub const MAX_DECOMPRESSED: u64 = 4 << 30;

/// A mesh read from a PLY file and what was skipped.
#[derive(Debug)]
pub struct PlyMesh {
    pub mesh: TriMesh,
    /// Faces of other than 3 or 4 vertices, skipped.
    pub skipped_faces: usize,
}

/// Decompresses gzip data (a `.gz` file), refusing more than `MAX_DECOMPRESSED` bytes.
pub fn gunzip(bytes: &[u8]) -> Result<Vec<u8>, String> {
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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

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

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<(String, Kind)>,
    line: usize,
}

impl Element {
    fn index(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|(n, _)| n == name)
    }

    fn min_bytes(&self, format: Format) -> u64 {
        match format {
            Format::Ascii => 2 * self.props.len() as u64,
            _ => self
                .props
                .iter()
                .map(|(_, k)| match k {
                    Kind::Scalar(s) => s.size() as u64,
                    Kind::List { count, .. } => count.size() as u64,
                })
                .sum(),
        }
    }
}

/// Reads scalars from the body in either encoding.
struct Body<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: Format,
    line: usize,
    /// Where the last value read starts (line, byte offset).
    last: (usize, usize),
}

impl Body<'_> {
    /// Where the last value read (or the failed read) is.
    fn place(&self) -> String {
        match self.format {
            Format::Ascii => format!("line {}", self.last.0),
            _ => format!("byte offset {}", self.last.1),
        }
    }

    fn read(&mut self, ty: Scalar) -> Result<f64, String> {
        self.last = (self.line, self.pos);
        if self.format == Format::Ascii {
            while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
                if self.bytes[self.pos] == b'\n' {
                    self.line += 1;
                }
                self.pos += 1;
            }
            let start = self.pos;
            if start < self.bytes.len() {
                self.last = (self.line, self.pos);
            }
            while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
            if start == self.pos {
                return Err(format!("{}: the file ends early", self.place()));
            }
            let s = std::str::from_utf8(&self.bytes[start..self.pos]).unwrap_or("?");
            let v = if ty.is_integer() {
                s.parse::<i64>().ok().map(|v| v as f64)
            } else {
                s.parse::<f64>().ok()
            };
            return v.ok_or_else(|| format!("{}: bad number '{s}'", self.place()));
        }
        let n = ty.size();
        if self.bytes.len() - self.pos < n {
            return Err(format!("{}: the file ends early", self.place()));
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

/// Parses a PLY file's bytes (already decompressed). Errors are one line,
/// naming the header line or the body's line (ASCII) or byte offset (binary);
/// the caller adds the file name.
pub fn parse(bytes: &[u8], path: &Path) -> Result<PlyMesh, String> {
    let mut pos = 0;
    let mut line = 0;
    let mut format = None;
    let mut elements: Vec<Element> = vec![];
    loop {
        line += 1;
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(format!("line {line}: the header has no end_header line"));
        };
        let text = std::str::from_utf8(&bytes[pos..pos + len])
            .map_err(|_| format!("line {line}: the header is not ASCII text"))?;
        pos += len + 1;
        let words: Vec<&str> = text.split_whitespace().collect();
        if line == 1 {
            if words != ["ply"] {
                return Err("not a PLY file (the first line must be 'ply')".into());
            }
            continue;
        }
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, _] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    _ => return Err(format!("line {line}: unknown format '{f}'")),
                })
            }
            ["element", name, count] => {
                let count = count
                    .parse::<u64>()
                    .map_err(|_| format!("line {line}: bad element count '{count}'"))?;
                if matches!(*name, "vertex" | "face") && elements.iter().any(|e| e.name == *name) {
                    return Err(format!("line {line}: element '{name}' is declared twice"));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: vec![],
                    line,
                });
            }
            ["property", rest @ ..] => {
                let Some(el) = elements.last_mut() else {
                    return Err(format!("line {line}: property before any element"));
                };
                let scalar = |s: &str| Scalar::parse(s).ok_or_else(|| format!("line {line}: unknown type '{s}'"));
                let (kind, name) = match rest {
                    ["list", c, i, name] => {
                        let count = scalar(c)?;
                        if !count.is_integer() {
                            return Err(format!("line {line}: list count type '{c}' is not an integer type"));
                        }
                        (
                            Kind::List {
                                count,
                                item: scalar(i)?,
                            },
                            name,
                        )
                    }
                    [t, name] => (Kind::Scalar(scalar(t)?), name),
                    _ => return Err(format!("line {line}: malformed property line '{text}'")),
                };
                el.props.push((name.to_string(), kind));
            }
            ["end_header"] => break,
            _ => return Err(format!("line {line}: unexpected header line '{text}'")),
        }
    }
    let format = format.ok_or_else(|| format!("line {line}: the header has no format line"))?;
    let available = (bytes.len() - pos) as u128;
    let mut needed = 0u128;
    for el in &elements {
        needed += el.count as u128 * el.min_bytes(format) as u128;
        if needed > available + 1 {
            return Err(format!(
                "line {}: element '{}' declares {} items, more than the {} bytes after the header can hold",
                el.line, el.name, el.count, available
            ));
        }
    }
    let Some(vertex) = elements.iter().find(|e| e.name == "vertex") else {
        return Err("the header declares no vertex element".into());
    };
    let vertex_count = vertex.count;
    if !elements.iter().any(|e| e.name == "face") {
        return Err("the header declares no face element".into());
    }

    let mut body = Body {
        bytes,
        pos,
        format,
        line: line + 1,
        last: (line + 1, pos),
    };
    let mut mesh = TriMesh {
        file: Some(path.to_path_buf()),
        ..TriMesh::default()
    };
    let mut skipped_faces = 0;
    for el in &elements {
        let scalar_index = |names: [&str; 3]| -> Option<[usize; 3]> {
            let mut out = [0; 3];
            for (k, n) in names.iter().enumerate() {
                if n.is_empty() {
                    continue;
                }
                let i = el.index(n)?;
                matches!(el.props[i].1, Kind::Scalar(_)).then_some(())?;
                out[k] = i;
            }
            Some(out)
        };
        let (mut xyz, mut nxyz, mut uv, mut indices) = (None, None, None, None);
        match el.name.as_str() {
            "vertex" => {
                xyz = scalar_index(["x", "y", "z"]);
                if xyz.is_none() {
                    return Err(format!(
                        "line {}: the vertex element has no x, y and z properties",
                        el.line
                    ));
                }
                nxyz = scalar_index(["nx", "ny", "nz"]);
                uv = [
                    ["u", "v"],
                    ["s", "t"],
                    ["texture_u", "texture_v"],
                    ["texture_s", "texture_t"],
                ]
                .iter()
                .find_map(|[a, b]| scalar_index([a, b, ""]));
                let fits = (bytes.len() - body.pos) as u64 / el.min_bytes(format).max(1);
                let n = el.count.min(fits) as usize;
                mesh.positions.reserve(n);
                if nxyz.is_some() {
                    mesh.normals = Some(Vec::with_capacity(n));
                }
                if uv.is_some() {
                    mesh.uvs = Some(Vec::with_capacity(n));
                }
            }
            "face" => {
                indices = el.index("vertex_indices").or_else(|| el.index("vertex_index"));
                match indices.map(|i| el.props[i].1) {
                    Some(Kind::List { item, .. }) if item.is_integer() => {}
                    _ => {
                        return Err(format!(
                            "line {}: the face element has no integer list 'vertex_indices'",
                            el.line
                        ))
                    }
                }
            }
            _ => {}
        }
        if el.props.is_empty() {
            continue;
        }
        let mut values = vec![0.0f64; el.props.len()];
        let mut face = Vec::with_capacity(4);
        for item in 0..el.count {
            for (k, (_, kind)) in el.props.iter().enumerate() {
                match *kind {
                    Kind::Scalar(s) => values[k] = body.read(s)?,
                    Kind::List { count, item: ty } => {
                        let n = body.read(count)?;
                        if n < 0.0 {
                            return Err(format!("{}: negative list length in {} {item}", body.place(), el.name));
                        }
                        let n = n as u64;
                        if Some(k) != indices {
                            if format != Format::Ascii {
                                let skip = n.saturating_mul(ty.size() as u64);
                                if skip > (bytes.len() - body.pos) as u64 {
                                    return Err(format!("{}: the file ends early", body.place()));
                                }
                                body.pos += skip as usize;
                            } else {
                                for _ in 0..n {
                                    body.read(ty)?;
                                }
                            }
                            continue;
                        }
                        face.clear();
                        for _ in 0..n {
                            let i = body.read(ty)?;
                            if !(i >= 0.0 && i < vertex_count as f64) {
                                return Err(format!(
                                    "{}: face {item} has vertex index {i}, out of range (0..{vertex_count})",
                                    body.place()
                                ));
                            }
                            if face.len() < 5 {
                                face.push(i as u32);
                            }
                        }
                        match n {
                            3 => mesh.triangles.push([face[0], face[1], face[2]]),
                            4 => {
                                // pbrt's patch (p00, p10, p01, p11) = (f0, f1, f3, f2),
                                // split as (p00, p10, p11), (p00, p11, p01).
                                mesh.triangles.push([face[0], face[1], face[2]]);
                                mesh.triangles.push([face[0], face[2], face[3]]);
                                mesh.quads_split += 1;
                            }
                            _ => skipped_faces += 1,
                        }
                    }
                }
            }
            if let Some([x, y, z]) = xyz {
                let p = Vec3::new(values[x] as f32, values[y] as f32, values[z] as f32);
                if !p.is_finite() {
                    return Err(format!("{}: vertex {item} is not finite", body.place()));
                }
                mesh.positions.push(p);
                if let (Some([x, y, z]), Some(n)) = (nxyz, mesh.normals.as_mut()) {
                    let v = Vec3::new(values[x] as f32, values[y] as f32, values[z] as f32);
                    if !v.is_finite() {
                        return Err(format!("{}: vertex {item} has a non-finite normal", body.place()));
                    }
                    n.push(v);
                }
                if let (Some([u, v, _]), Some(t)) = (uv, mesh.uvs.as_mut()) {
                    t.push(Vec2::new(values[u] as f32, values[v] as f32));
                }
            }
        }
    }
    Ok(PlyMesh { mesh, skipped_faces })
}
