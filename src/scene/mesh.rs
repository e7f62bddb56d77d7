//! Triangle meshes read from files: Wavefront OBJ (parsed by `tobj`, with
//! its MTL materials) and Stanford PLY (our own reader, `ply.rs`, after Greg
//! Turk's format description). A mesh is kept in object space; a
//! [`Transform`] places it in the scene when its triangles are added.
//!
//! Every error names the file and the line (or, for binary PLY, the byte
//! offset). Degenerate triangles are not errors here: `Scene::build` drops
//! and counts them.

mod obj;
pub mod ply;

use super::transform::Transform;
use super::{FaceUvs, SceneDesc};
use crate::error::{Error, Result};
use crate::material::Material;
use crate::math::{Aabb, Vec2, Vec3};
use crate::texture::{Encoding, TexImage};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A named part of a mesh (an OBJ group or object; the whole of a PLY file).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshPart {
    pub name: String,
    /// Material name given by `usemtl` (when its MTL file was found).
    pub material: Option<String>,
    /// Lambertian albedo from the material's MTL `Kd`.
    pub albedo: Option<Vec3>,
    /// The part's triangles, a range of `Mesh::triangles`.
    pub triangles: Range<usize>,
}

/// An indexed triangle mesh in object space.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    pub path: PathBuf,
    pub positions: Vec<Vec3>,
    /// Per-vertex normals, as many as positions; zero where a vertex has none.
    /// `None` when the file has no normals at all.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, as many as positions (OBJ `vt`, PLY
    /// `u`/`v` and their other names); `None` when the file has none.
    pub uvs: Option<Vec<Vec2>>,
    /// Vertex index triples, all within `positions`.
    pub triangles: Vec<[u32; 3]>,
    pub parts: Vec<MeshPart>,
    /// Things worth telling the user that do not stop the load (a missing MTL file).
    pub warnings: Vec<String>,
}

/// Where meshes and their material libraries are read from: the file system,
/// or a fixed set of in-memory files (fuzzing and tests parse scenes without
/// letting a scene's paths reach arbitrary files).
pub trait FileSource {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>>;

    /// An image texture's pixels; by default decoded from `read`'s bytes.
    fn read_image(&self, path: &Path, encoding: Encoding) -> Result<Arc<TexImage>> {
        let bytes = self.read(path).map_err(|e| Error::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        Ok(Arc::new(crate::texture::decode_bytes(path, &bytes, encoding, false)?))
    }
}

/// The file system.
pub struct Disk;

impl FileSource for Disk {
    /// Reads regular files only: a device such as /dev/zero named as a
    /// material library would otherwise be read until memory runs out.
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        use std::io::Read;
        let mut file = std::fs::File::open(path)?;
        let meta = file.metadata()?;
        if !meta.is_file() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a regular file",
            ));
        }
        let mut bytes = Vec::with_capacity(meta.len().min(1 << 30) as usize);
        file.read_to_end(&mut bytes)?;
        Ok(bytes)
    }

    /// Decoded once per file and encoding, and shared (`load_image`).
    fn read_image(&self, path: &Path, encoding: Encoding) -> Result<Arc<TexImage>> {
        crate::texture::load_image(path, encoding)
    }
}

/// The mesh file formats we read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Obj,
    Ply,
}

impl MeshFormat {
    /// The format a file's extension names (.obj, .ply or .ply.gz, any case).
    pub fn from_path(path: &Path) -> Option<MeshFormat> {
        let name = path.file_name()?.to_str()?.to_ascii_lowercase();
        if name.ends_with(".ply.gz") {
            return Some(MeshFormat::Ply);
        }
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(MeshFormat::Obj),
            "ply" => Some(MeshFormat::Ply),
            _ => None,
        }
    }
}

/// Reads a mesh, choosing the format by the file's extension (.obj or .ply).
pub fn load_mesh(path: &Path) -> Result<Mesh> {
    load_mesh_from(path, &Disk)
}

/// Reads a mesh (and an OBJ's material libraries) through `files`.
pub fn load_mesh_from(path: &Path, files: &dyn FileSource) -> Result<Mesh> {
    let Some(format) = MeshFormat::from_path(path) else {
        return Err(Error::Parse {
            path: path.to_path_buf(),
            message: "unknown mesh format (use a .obj or .ply file)".into(),
        });
    };
    let bytes = files.read(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    parse_mesh(path, &bytes, format, files)
}

/// Parses a mesh from its bytes; `path` names it in errors, and an OBJ's
/// material libraries are read through `files` relative to it.
pub fn parse_mesh(path: &Path, bytes: &[u8], format: MeshFormat, files: &dyn FileSource) -> Result<Mesh> {
    let mesh = match format {
        MeshFormat::Obj => obj::parse(path, bytes, files)?,
        MeshFormat::Ply => ply::parse(path, bytes)?,
    };
    if mesh.triangles.is_empty() {
        return Err(Error::Parse {
            path: path.to_path_buf(),
            message: "the mesh has no faces".into(),
        });
    }
    Ok(mesh)
}

/// Reads a mesh and reports how long it took.
pub fn load_mesh_timed(path: &Path) -> Result<(Mesh, MeshReport)> {
    load_mesh_timed_from(path, &Disk)
}

/// Reads a mesh through `files` and reports how long it took.
pub fn load_mesh_timed_from(path: &Path, files: &dyn FileSource) -> Result<(Mesh, MeshReport)> {
    let start = std::time::Instant::now();
    let mesh = load_mesh_from(path, files)?;
    let report = MeshReport::new(&mesh, start.elapsed().as_secs_f64());
    Ok((mesh, report))
}

impl Mesh {
    /// Bounding box of the vertices the triangles use.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for t in &self.triangles {
            for &i in t {
                b.grow(self.positions[i as usize]);
            }
        }
        b
    }

    /// Adds the mesh's triangles to the scene, placed by `transform`. With
    /// `material` every triangle uses it; without, each part uses its MTL
    /// albedo as a diffuse material named `<file stem>/<material>`.
    /// `smooth` passes the file's vertex normals on for shading; texture
    /// coordinates are passed on whenever the file has them.
    pub fn add_to_scene(
        &self,
        desc: &mut SceneDesc,
        transform: &Transform,
        material: Option<u32>,
        smooth: bool,
    ) -> Result<()> {
        let placed = transform.apply(self)?;
        let stem = self
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        desc.triangles.reserve(self.triangles.len());
        // The mesh's vertices, shared by its triangles.
        let normals = placed.normals.as_deref().filter(|_| smooth);
        let base = desc
            .triangles
            .add_vertices(&placed.positions, normals, self.uvs.as_deref());
        for part in &self.parts {
            let m = match (material, &part.albedo) {
                (Some(m), _) => m,
                (None, Some(albedo)) => {
                    let name = format!("{stem}/{}", part.material.as_deref().unwrap_or(&part.name));
                    desc.material(&name, Material::diffuse(albedo.x, albedo.y, albedo.z))
                }
                (None, None) => {
                    return Err(Error::Parse {
                        path: self.path.clone(),
                        message: format!(
                            "part '{}' has no MTL material with a Kd albedo; give the mesh a material",
                            part.name
                        ),
                    })
                }
            };
            for t in &self.triangles[part.triangles.clone()] {
                // A vertex without a normal makes the triangle flat.
                let smooth = match (&placed.normals, smooth) {
                    (Some(n), true) => t.iter().all(|&i| n[i as usize] != Vec3::ZERO),
                    _ => false,
                };
                let uvs = match self.uvs {
                    Some(_) => FaceUvs::Vertices,
                    None => FaceUvs::None,
                };
                desc.triangles.push_face(base, *t, smooth, uvs, m);
            }
        }
        Ok(())
    }
}

/// What loading a mesh took, for `raytracer info` and the render summary.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshReport {
    pub path: PathBuf,
    pub vertices: usize,
    pub triangles: usize,
    pub has_normals: bool,
    pub seconds: f64,
    pub warnings: Vec<String>,
}

impl MeshReport {
    pub fn new(mesh: &Mesh, seconds: f64) -> Self {
        MeshReport {
            path: mesh.path.clone(),
            vertices: mesh.positions.len(),
            triangles: mesh.triangles.len(),
            has_normals: mesh.normals.is_some(),
            seconds,
            warnings: mesh.warnings.clone(),
        }
    }
}

/// A mesh's vertices in world space (see `Transform::apply`).
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedVertices {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
}

#[cfg(test)]
pub(crate) mod tests;
