//! The shapes the reader decodes from their parameters (pbrt-v4 shapes.cpp):
//! `trianglemesh`, `bilinearmesh`, `loopsubdiv`, `sphere`, `disk`; `plymesh` files are read
//! by the builder (it owns file access) through [`super::ply`].

use super::error::{Loc, PbrtError, Result};
use super::ir::{Disk, Sphere, TriMesh};
use super::params::Params;
use crate::geometry::subdivision::loop_subdivide;

/// What decoding a shape found worth telling, besides errors.
#[derive(Default)]
pub struct Findings {
    pub warnings: Vec<String>,
    pub unsupported: Vec<String>,
}

fn check_indices(ty: &str, indices: &[i32], n: usize, loc: &Loc) -> Result<()> {
    if let Some(&bad) = indices.iter().find(|&&i| i < 0 || i as usize >= n) {
        return Err(PbrtError::at(
            loc,
            format!("{ty}: vertex index {bad} is out of range (\"P\" has {n} points)"),
        ));
    }
    Ok(())
}

/// Reads `P`, `N` and `uv` into a mesh; `N` and `uv` of the wrong length
/// are dropped with a warning, as pbrt-v4 does.
fn vertices(ty: &str, params: &Params, loc: &Loc, found: &mut Findings) -> Result<TriMesh> {
    let positions = params.get_point3s("P");
    if positions.is_empty() {
        return Err(PbrtError::at(loc, format!("{ty}: vertex positions \"P\" are required")));
    }
    if positions.len() > u32::MAX as usize {
        return Err(PbrtError::at(loc, format!("{ty}: too many vertices")));
    }
    let n = positions.len();
    let mut mesh = TriMesh {
        positions,
        ..TriMesh::default()
    };
    let normals = params.get_normals("N");
    if !normals.is_empty() {
        if normals.len() == n {
            mesh.normals = Some(normals);
        } else {
            found.warnings.push(format!(
                "{ty}: {} normals \"N\" for {n} points; the normals are ignored",
                normals.len()
            ));
        }
    }
    let uvs = params.get_point2s("uv");
    if !uvs.is_empty() {
        if uvs.len() == n {
            mesh.uvs = Some(uvs);
        } else {
            found.warnings.push(format!(
                "{ty}: {} texture coordinates \"uv\" for {n} points; they are ignored",
                uvs.len()
            ));
        }
    }
    Ok(mesh)
}

/// `indices` in groups of `k`, the default when there are exactly `k`
/// points, excess indices dropped with a warning.
fn grouped_indices(ty: &str, params: &Params, k: usize, n: usize, loc: &Loc, found: &mut Findings) -> Result<Vec<i32>> {
    let mut indices = params.get_ints("indices").to_vec();
    if indices.is_empty() {
        if n == k {
            indices = (0..k as i32).collect();
        } else {
            return Err(PbrtError::at(
                loc,
                format!("{ty}: vertex indices \"indices\" are required unless \"P\" has exactly {k} points"),
            ));
        }
    } else if !indices.len().is_multiple_of(k) {
        found.warnings.push(format!(
            "{ty}: {} vertex indices is not a multiple of {k}; the last {} are ignored",
            indices.len(),
            indices.len() % k
        ));
        indices.truncate(indices.len() - indices.len() % k);
    }
    check_indices(ty, &indices, n, loc)?;
    Ok(indices)
}

pub fn triangle_mesh(params: &Params, loc: &Loc, found: &mut Findings) -> Result<TriMesh> {
    let mut mesh = vertices("trianglemesh", params, loc, found)?;
    let indices = grouped_indices("trianglemesh", params, 3, mesh.positions.len(), loc, found)?;
    mesh.triangles = indices
        .chunks_exact(3)
        .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
        .collect();
    Ok(mesh)
}

/// A bilinear patch mesh; patch (p00, p10, p01, p11) = indices (a, b, c, d)
/// becomes triangles (a, b, d) and (a, d, c), whose normals agree with the
/// patch's `cross(dp/du, dp/dv)`.
pub fn bilinear_mesh(params: &Params, loc: &Loc, found: &mut Findings) -> Result<TriMesh> {
    let mut mesh = vertices("bilinearmesh", params, loc, found)?;
    let indices = grouped_indices("bilinearmesh", params, 4, mesh.positions.len(), loc, found)?;
    for q in indices.chunks_exact(4) {
        let [a, b, c, d] = [q[0] as u32, q[1] as u32, q[2] as u32, q[3] as u32];
        mesh.triangles.push([a, b, d]);
        mesh.triangles.push([a, d, c]);
        mesh.quads_split += 1;
    }
    if params.get_string("emissionfilename")?.is_some() {
        found
            .unsupported
            .push("bilinearmesh: an emission image (\"emissionfilename\") is not supported".into());
    }
    Ok(mesh)
}

/// A Loop subdivision surface (pbrt-v4 `loopsubdiv`: `levels` [3],
/// `indices`, `P`; `scheme` is read and ignored, as pbrt-v4 does), as the
/// triangles of its limit surface with limit normals. pbrt-v4's limit
/// normals point against the control mesh's winding and its triangles face
/// them; the triangles are wound the other way round here so that they
/// face the normals too, and so face (and, as lights, emit) where pbrt's do.
pub fn loop_subdiv(params: &Params, loc: &Loc, found: &mut Findings) -> Result<TriMesh> {
    let levels = params.get_int("levels", 3)?;
    let _ = params.get_string("scheme")?;
    if levels < 0 {
        return Err(PbrtError::at(loc, format!("loopsubdiv: levels {levels} must be >= 0")));
    }
    let control = vertices("loopsubdiv", params, loc, found)?;
    let indices = grouped_indices("loopsubdiv", params, 3, control.positions.len(), loc, found)?;
    let triangles: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
        .collect();
    let mesh = loop_subdivide(levels as u32, &control.positions, &triangles)
        .map_err(|e| PbrtError::at(loc, format!("loopsubdiv: {e}")))?;
    Ok(TriMesh {
        positions: mesh.positions,
        normals: Some(mesh.normals.into_iter().map(|n| -n).collect()),
        triangles: mesh.triangles.into_iter().map(|[a, b, c]| [a, c, b]).collect(),
        ..TriMesh::default()
    })
}

pub fn sphere(params: &Params, loc: &Loc, found: &mut Findings) -> Result<Sphere> {
    let radius = params.get_float("radius", 1.0)?;
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(PbrtError::at(
            loc,
            format!("sphere: radius {radius} must be positive and finite"),
        ));
    }
    let s = Sphere {
        radius,
        zmin: params.get_float("zmin", -radius)?,
        zmax: params.get_float("zmax", radius)?,
        phimax_deg: params.get_float("phimax", 360.0)?,
    };
    if s.is_partial() {
        found.unsupported.push(format!(
            "a partial sphere (zmin {}, zmax {}, phimax {}) is not supported",
            s.zmin, s.zmax, s.phimax_deg
        ));
    }
    Ok(s)
}

pub fn disk(params: &Params, found: &mut Findings) -> Result<Disk> {
    let d = Disk {
        height: params.get_float("height", 0.0)?,
        radius: params.get_float("radius", 1.0)?,
        inner_radius: params.get_float("innerradius", 0.0)?,
        phimax_deg: params.get_float("phimax", 360.0)?,
    };
    if d.is_partial() {
        found
            .unsupported
            .push(format!("a partial disk (phimax {}) is not supported", d.phimax_deg));
    }
    Ok(d)
}

/// pbrt-v4's shape types.
pub const SHAPE_TYPES: &[&str] = &[
    "sphere",
    "cylinder",
    "disk",
    "bilinearmesh",
    "curve",
    "trianglemesh",
    "plymesh",
    "loopsubdiv",
];
