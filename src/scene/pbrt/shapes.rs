//! The shapes the reader decodes from their parameters (pbrt-v4 shapes.cpp):
//! `trianglemesh`, `bilinearmesh`, `loopsubdiv`, `sphere`, `disk`, `cylinder`, `curve`; `plymesh` files are read
//! by the builder (it owns file access) through [`super::ply`].

use super::error::{Loc, PbrtError, Result};
use super::ir::{Curves, Disk, Sphere, TriMesh};
use super::params::Params;
use crate::geometry::curve::{bspline_to_bezier, elevate_quadratic, quadratic_bspline_to_bezier, ribbon_normals_valid};
use crate::geometry::subdivision::loop_subdivide;
use crate::geometry::CurveKind;
use crate::math::Vec3;

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
        mesh.second_halves.extend([false, true]);
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

pub fn sphere(params: &Params, loc: &Loc) -> Result<Sphere> {
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
    // pbrt-v4 renders such a sphere as nothing; here it is the file's error.
    let (z0, z1) = (s.zmin.min(s.zmax).max(-radius), s.zmin.max(s.zmax).min(radius));
    if z1.partial_cmp(&z0) != Some(std::cmp::Ordering::Greater) {
        return Err(PbrtError::at(
            loc,
            format!(
                "sphere: zmin {} and zmax {} must leave a band of the radius {radius}",
                s.zmin, s.zmax
            ),
        ));
    }
    if s.phimax_deg.is_nan() || s.phimax_deg <= 0.0 {
        return Err(PbrtError::at(
            loc,
            format!("sphere: phimax {} must be > 0", s.phimax_deg),
        ));
    }
    Ok(s)
}

pub fn disk(params: &Params, loc: &Loc) -> Result<Disk> {
    let d = Disk {
        height: params.get_float("height", 0.0)?,
        radius: params.get_float("radius", 1.0)?,
        inner_radius: params.get_float("innerradius", 0.0)?,
        phimax_deg: params.get_float("phimax", 360.0)?,
    };
    if d.phimax_deg.is_nan() || d.phimax_deg <= 0.0 {
        return Err(PbrtError::at(loc, format!("disk: phimax {} must be > 0", d.phimax_deg)));
    }
    Ok(d)
}

/// Segments a whole turn of a sphere's or a disk's mesh is cut into (and a
/// half turn of a sphere's, pole to pole): its silhouette is then within
/// 3e-4 of its radius of the true one, with its shading following the
/// surface, at 16,128 triangles a whole sphere.
const ROUND_SEGMENTS: f32 = 128.0;

/// Turns of `phimax_deg` degrees (clamped to [0, 360], as pbrt-v4 does) in
/// segments of at most a `ROUND_SEGMENTS`th of a turn, and at least 4.
fn segments(phimax_deg: f32) -> u32 {
    (ROUND_SEGMENTS * phimax_deg.clamp(0.0, 360.0) / 360.0).ceil().max(4.0) as u32
}

/// Quads (a, b, c, d) of a grid as two triangles each, leaving out the
/// triangles two of whose corners are one point (a pole, a disk's centre).
fn push_quad(mesh: &mut TriMesh, [a, b, c, d]: [u32; 4]) {
    for t in [[a, b, c], [a, c, d]] {
        let [p, q, r] = t.map(|i| mesh.positions[i as usize]);
        if p != q && q != r && r != p {
            mesh.triangles.push(t);
        }
    }
}

/// A `sphere` as a triangle mesh in object space, for what the analytic
/// sphere does not take: a partial one (`zmin`, `zmax`, `phimax`) or one
/// under a transformation other than a similarity (an ellipsoid). pbrt-v4's
/// parametrisation (its `Sphere`): u = phi / phimax and v = (theta -
/// theta_zmin) / (theta_zmax - theta_zmin), zmin and zmax clamped to the
/// radius. The vertices lie on the sphere, with its outward normals, and
/// the triangles face them.
pub fn sphere_mesh(s: &Sphere) -> TriMesh {
    let r = s.radius;
    let (z0, z1) = (s.zmin.min(s.zmax).clamp(-r, r), s.zmin.max(s.zmax).clamp(-r, r));
    let (theta0, theta1) = ((z0 / r).clamp(-1.0, 1.0).acos(), (z1 / r).clamp(-1.0, 1.0).acos());
    let phimax = s.phimax_deg.clamp(0.0, 360.0).to_radians();
    let np = segments(s.phimax_deg);
    let nt = ((ROUND_SEGMENTS / 2.0) * (theta0 - theta1) / std::f32::consts::PI)
        .ceil()
        .max(1.0) as u32;
    let mut mesh = TriMesh {
        quadric: true,
        ..TriMesh::default()
    };
    let (mut normals, mut uvs) = (vec![], vec![]);
    for j in 0..=nt {
        let v = j as f32 / nt as f32;
        // The cuts exactly where pbrt-v4 makes them; theta in [0, pi].
        let (sin_t, cos_t) = match j {
            0 => ((1.0 - (z0 / r) * (z0 / r)).max(0.0).sqrt(), z0 / r),
            _ if j == nt => ((1.0 - (z1 / r) * (z1 / r)).max(0.0).sqrt(), z1 / r),
            _ => {
                let (sin, cos) = (theta0 + (theta1 - theta0) * v).sin_cos();
                (sin.max(0.0), cos)
            }
        };
        for i in 0..=np {
            let u = i as f32 / np as f32;
            let (sin_p, cos_p) = (u * phimax).sin_cos();
            let n = Vec3::new(sin_t * cos_p, sin_t * sin_p, cos_t);
            mesh.positions.push(n * r);
            normals.push(n);
            uvs.push(crate::math::Vec2::new(u, v));
        }
    }
    let at = |i: u32, j: u32| j * (np + 1) + i;
    for j in 0..nt {
        for i in 0..np {
            let quad = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            // (a, b, c) turns from +phi to +z: outward.
            push_quad(&mut mesh, quad);
        }
    }
    mesh.normals = Some(normals);
    mesh.uvs = Some(uvs);
    mesh
}

/// A `disk` as a triangle mesh in object space, for what the analytic disk
/// does not take: a partial one (`phimax`) or one under a transformation
/// other than a similarity (an ellipse). pbrt-v4's parametrisation (its
/// `Disk`): u = phi / phimax, v = (radius - r) / (radius - innerradius) at
/// distance r from the axis; one ring of quads from the rim to the hole (or
/// the centre). Normals +z.
pub fn disk_mesh(d: &Disk) -> TriMesh {
    let phimax = d.phimax_deg.clamp(0.0, 360.0).to_radians();
    let np = segments(d.phimax_deg);
    let mut mesh = TriMesh {
        quadric: true,
        ..TriMesh::default()
    };
    let (mut normals, mut uvs) = (vec![], vec![]);
    for i in 0..=np {
        let u = i as f32 / np as f32;
        let (sin, cos) = (u * phimax).sin_cos();
        for (rho, v) in [(d.radius, 0.0), (d.inner_radius, 1.0)] {
            mesh.positions.push(Vec3::new(rho * cos, rho * sin, d.height));
            normals.push(Vec3::Z);
            uvs.push(crate::math::Vec2::new(u, v));
        }
    }
    for i in 0..np {
        // Rim, next rim, next hole, hole: +z.
        let quad = [2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1];
        push_quad(&mut mesh, quad);
    }
    mesh.normals = Some(normals);
    mesh.uvs = Some(uvs);
    mesh
}

/// Segments a whole turn of a `cylinder` is cut into: its silhouette is
/// then within 8e-5 of its radius of the true one.
const CYLINDER_SEGMENTS: f32 = 256.0;

/// A `cylinder` (pbrt-v4's: `radius` 1, `zmin` -1, `zmax` 1, `phimax` 360
/// degrees; open, about the object's z axis) as a triangle mesh: one row of
/// quads around it, as many as a 256th of a turn each, with the surface's
/// own normals at the vertices (outward, pbrt-v4's) and its texture
/// coordinates, u = phi / phimax and v = (z - zmin) / (zmax - zmin). Exact
/// along z; around it the mesh is a polygon whose shading follows the
/// circle.
pub fn cylinder(params: &Params, loc: &Loc) -> Result<TriMesh> {
    let radius = params.get_float("radius", 1.0)?;
    let z0 = params.get_float("zmin", -1.0)?;
    let z1 = params.get_float("zmax", 1.0)?;
    let phimax = params.get_float("phimax", 360.0)?.clamp(0.0, 360.0);
    let (zmin, zmax) = (z0.min(z1), z0.max(z1));
    if !(radius > 0.0 && radius.is_finite() && zmin.is_finite() && zmax.is_finite() && zmax > zmin && phimax > 0.0) {
        return Err(PbrtError::at(
            loc,
            format!(
                "cylinder: radius {radius} must be positive and finite, zmin {z0} and zmax {z1} finite and apart, phimax {phimax} > 0"
            ),
        ));
    }
    let n = (CYLINDER_SEGMENTS * phimax / 360.0).ceil().max(4.0) as u32;
    let mut mesh = TriMesh {
        quadric: true,
        ..TriMesh::default()
    };
    let (mut normals, mut uvs) = (vec![], vec![]);
    for i in 0..=n {
        let u = i as f32 / n as f32;
        let phi = (u * phimax).to_radians();
        let (sin, cos) = phi.sin_cos();
        for (z, v) in [(zmin, 0.0), (zmax, 1.0)] {
            mesh.positions.push(Vec3::new(radius * cos, radius * sin, z));
            normals.push(Vec3::new(cos, sin, 0.0));
            uvs.push(crate::math::Vec2::new(u, v));
        }
    }
    for i in 0..n {
        let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        mesh.triangles.push([a, c, d]);
        mesh.triangles.push([a, d, b]);
    }
    mesh.normals = Some(normals);
    mesh.uvs = Some(uvs);
    Ok(mesh)
}

/// A `curve` (pbrt-v4's `Curve::Create`): its control points `P` as
/// cubic Bezier segments, with `basis` "bezier" or "bspline", `degree` 2 or
/// 3, `type` "flat", "cylinder" or "ribbon" (with normals `N` at the
/// segments' ends), `width` (or `width0` and `width1`) and `splitdepth`.
pub fn curves(params: &Params, loc: &Loc, found: &mut Findings) -> Result<Option<Curves>> {
    let err = |m: String| Err(PbrtError::at(loc, format!("curve: {m}")));
    let width = params.get_float("width", 1.0)?;
    let width0 = params.get_float("width0", width)?;
    let width1 = params.get_float("width1", width)?;
    let degree = params.get_int("degree", 3)?;
    if degree != 2 && degree != 3 {
        return err(format!("degree {degree}: only 2 and 3 are supported"));
    }
    let degree = degree as usize;
    let basis = params.get_string_or("basis", "bezier")?;
    let kind = match params.get_string_or("type", "flat")?.as_str() {
        "flat" => CurveKind::Flat,
        "cylinder" => CurveKind::Cylinder,
        "ribbon" => CurveKind::Ribbon,
        other => {
            // pbrt-v4 warns and takes a cylinder.
            found
                .warnings
                .push(format!("curve: unknown type \"{other}\"; a cylinder is used"));
            CurveKind::Cylinder
        }
    };
    let split_depth = params.get_int("splitdepth", 3)?;
    if !(0..=10).contains(&split_depth) {
        return err(format!("splitdepth {split_depth} must be in [0, 10]"));
    }
    if !(width0 > 0.0 && width1 > 0.0 && width0.is_finite() && width1.is_finite()) {
        return err(format!("widths {width0} and {width1} must be finite and > 0"));
    }
    let cp = params.get_point3s("P");
    if let Some(bad) = cp.iter().find(|p| !p.is_finite()) {
        return err(format!("control point {bad} is not finite"));
    }
    let segments: Vec<[Vec3; 4]> = match basis.as_str() {
        "bezier" => {
            if cp.len() < degree + 1 || !(cp.len() - 1 - degree).is_multiple_of(degree) {
                return err(format!(
                    "{} control points: a degree {degree} Bezier curve needs {} + n x {degree}",
                    cp.len(),
                    degree + 1
                ));
            }
            (0..(cp.len() - 1) / degree)
                .map(|i| {
                    let p = &cp[i * degree..];
                    if degree == 2 {
                        elevate_quadratic(&[p[0], p[1], p[2]])
                    } else {
                        [p[0], p[1], p[2], p[3]]
                    }
                })
                .collect()
        }
        "bspline" => {
            if cp.len() < degree + 1 {
                return err(format!(
                    "{} control points: a degree {degree} B-spline needs at least {}",
                    cp.len(),
                    degree + 1
                ));
            }
            (0..cp.len() - degree)
                .map(|i| {
                    let p = &cp[i..];
                    if degree == 2 {
                        elevate_quadratic(&quadratic_bspline_to_bezier(&[p[0], p[1], p[2]]))
                    } else {
                        bspline_to_bezier(&[p[0], p[1], p[2], p[3]])
                    }
                })
                .collect()
        }
        other => {
            return err(format!(
                "basis \"{other}\": only \"bezier\" and \"bspline\" are supported"
            ))
        }
    };
    let n = segments.len() as f32;
    let lerp = |t: f32| (1.0 - t) * width0 + t * width1;
    let widths = (0..segments.len())
        .map(|i| [lerp(i as f32 / n), lerp((i + 1) as f32 / n)])
        .collect();
    let mut normals = vec![];
    if kind == CurveKind::Ribbon {
        let given = params.get_normals("N");
        if given.len() != segments.len() + 1 {
            return err(format!(
                "a ribbon of {} segment{} needs {} normals \"N\" (one at each segment's end), not {}",
                segments.len(),
                if segments.len() == 1 { "" } else { "s" },
                segments.len() + 1,
                given.len()
            ));
        }
        for (i, n) in given.iter().enumerate() {
            // Scaled first, so that huge components keep their direction.
            let unit = (*n / n.abs().max_element()).normalize_or_zero();
            if !(n.is_finite() && unit.is_finite() && unit != Vec3::ZERO) {
                return err(format!("normal {i} of \"N\", {n}, has no direction"));
            }
            normals.push(unit);
        }
        if let Some(i) = (0..segments.len()).find(|&i| !ribbon_normals_valid([normals[i], normals[i + 1]])) {
            return err(format!(
                "normals {i} and {} of \"N\" point opposite ways: the ribbon cannot turn between them",
                i + 1
            ));
        }
    } else if params.has("N") {
        params.mark_used("N", super::params::ParamType::Normal);
        found
            .warnings
            .push("curve: normals \"N\" are only used by \"ribbon\" curves".into());
    }
    Ok(Some(Curves {
        segments,
        widths,
        kind,
        split_depth: split_depth as u32,
        normals,
    }))
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
