//! Wavefront OBJ through `tobj` (triangulated, one index per vertex), with
//! MTL `Kd` as each part's albedo. `tobj` reports what went wrong but not
//! where, so a failed load is scanned again by `diagnose`, which finds the
//! line. MTL files are checked before `tobj` reads them (it panics on a `Kd`
//! with fewer than three numbers).

use super::{FileSource, Mesh, MeshPart};
use crate::error::{Error, Result};
use crate::math::{Vec2, Vec3};
use std::cell::RefCell;
use std::io::Cursor;
use std::path::Path;

pub(super) fn parse(path: &Path, bytes: &[u8], files: &dyn FileSource) -> Result<Mesh> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    // The loader closure cannot return our error, so it leaves it here.
    let mtl_error: RefCell<Option<Error>> = RefCell::new(None);
    let warnings: RefCell<Vec<String>> = RefCell::new(vec![]);
    // tobj's index arithmetic overflows (a panic, or in release a wrapped
    // index) on relative indices reaching before the first vertex, so face
    // and line indices are checked before it sees them; the error is the file's first
    // problem, which may come before the bad face.
    if scan(bytes, true).is_some() {
        return Err(locate(path, bytes, "a face index is out of range"));
    }
    let loaded = tobj::load_obj_buf(&mut Cursor::new(bytes), &opts, |name| {
        let mtl_path = dir.join(name);
        let text = match files.read(&mtl_path) {
            Ok(t) => t,
            Err(e) => {
                warnings.borrow_mut().push(format!(
                    "{}: cannot read material library {}: {e}; its parts have no albedo",
                    path.display(),
                    mtl_path.display()
                ));
                return Err(tobj::LoadError::OpenFileFailed);
            }
        };
        if let Err(e) = check_mtl(&mtl_path, &text) {
            mtl_error.borrow_mut().get_or_insert(e);
            return Err(tobj::LoadError::MaterialParseError);
        }
        tobj::load_mtl_buf(&mut Cursor::new(&text))
    });
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let (models, materials) = loaded.map_err(|e| locate(path, bytes, &e.to_string()))?;
    let materials = materials.unwrap_or_default();

    let mut mesh = Mesh {
        path: path.to_path_buf(),
        positions: vec![],
        normals: None,
        uvs: None,
        triangles: vec![],
        parts: vec![],
        warnings: warnings.into_inner(),
    };
    let mut normals: Vec<Vec3> = vec![];
    let mut any_normals = false;
    let mut uvs: Vec<Vec2> = vec![];
    let mut any_uvs = false;
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let first = mesh.triangles.len();
        mesh.positions
            .extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        // A part whose faces do not all give normals gets none.
        if !m.normals.is_empty() && m.normals.len() == m.positions.len() {
            any_normals = true;
            normals.extend(m.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])));
        } else {
            normals.resize(mesh.positions.len(), Vec3::ZERO);
        }
        // Texture coordinates likewise, part by part.
        if !m.texcoords.is_empty() && m.texcoords.len() / 2 == m.positions.len() / 3 {
            any_uvs = true;
            uvs.extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
        } else {
            uvs.resize(mesh.positions.len(), Vec2::ZERO);
        }
        mesh.triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
        let mat = m.material_id.and_then(|i| materials.get(i));
        mesh.parts.push(MeshPart {
            name: model.name.clone(),
            material: mat.map(|m| m.name.clone()),
            albedo: mat.and_then(|m| m.diffuse).map(Vec3::from_array),
            triangles: first..mesh.triangles.len(),
        });
    }
    if any_normals {
        mesh.normals = Some(normals);
    }
    if any_uvs {
        if uvs.iter().any(|t| !t.is_finite()) {
            return Err(locate(path, bytes, "a texture coordinate is not a finite number"));
        }
        mesh.uvs = Some(uvs);
    }
    let finite = |v: &Vec<Vec3>| v.iter().all(|p| p.is_finite());
    if !finite(&mesh.positions) || !mesh.normals.as_ref().is_none_or(finite) {
        return Err(locate(path, bytes, "a vertex or normal is not a finite number"));
    }
    Ok(mesh)
}

/// The error for a file `tobj` refused (or that holds NaNs), at the first
/// line `diagnose` finds fault with.
fn locate(path: &Path, bytes: &[u8], what: &str) -> Error {
    match diagnose(bytes) {
        Some((line, message)) => Error::Syntax {
            path: path.to_path_buf(),
            line,
            message,
        },
        None => Error::Parse {
            path: path.to_path_buf(),
            message: what.to_string(),
        },
    }
}

/// Parses `n` numbers from `words`, naming the first bad one.
fn numbers<'a>(
    words: &mut impl Iterator<Item = &'a str>,
    n: usize,
    what: &str,
) -> std::result::Result<Vec<f32>, String> {
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let w = words.next().ok_or_else(|| format!("{what} needs {n} numbers"))?;
        let x: f32 = w.parse().map_err(|_| format!("bad number '{w}' in {what}"))?;
        out.push(x);
    }
    Ok(out)
}

/// Scans an OBJ file for the first line `tobj` would refuse or that holds a
/// non-finite number; returns its (1-based) number and what is wrong.
pub(super) fn diagnose(bytes: &[u8]) -> Option<(usize, String)> {
    scan(bytes, false)
}

/// `diagnose`, or with `faces_only` just the face indices: vertex lines are
/// only counted (tobj refuses malformed ones itself, at no risk).
fn scan(bytes: &[u8], faces_only: bool) -> Option<(usize, String)> {
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let Ok(text) = std::str::from_utf8(raw) else {
            if faces_only {
                continue;
            }
            return Some((line, "not valid UTF-8 text".into()));
        };
        let mut words = text.split_whitespace();
        let fail = |m: String| Some((line, m));
        let keyword = words.next();
        if faces_only {
            match keyword {
                Some("v") => nv += 1,
                Some("vt") => nvt += 1,
                Some("vn") => nvn += 1,
                // tobj reads `l` lines as faces too (two indices are a line,
                // but four a quad), whatever `ignore_lines` says.
                Some("f" | "l") => {}
                _ => continue,
            }
        }
        match keyword {
            _ if faces_only && !matches!(keyword, Some("f" | "l")) => {}
            Some("v") => {
                let p = match numbers(&mut words, 3, "vertex") {
                    Ok(p) => p,
                    Err(m) => return fail(m),
                };
                if p.iter().any(|x| !x.is_finite()) {
                    return fail(format!("vertex coordinate is not finite ({} {} {})", p[0], p[1], p[2]));
                }
                let rest: Vec<&str> = words.collect();
                match rest.len() {
                    0 => {}
                    1 => match rest[0].parse::<f32>() {
                        Ok(w) if w != 0.0 && w.is_finite() => {}
                        _ => return fail(format!("bad vertex weight '{}'", rest[0])),
                    },
                    // tobj skips unreadable colour components.
                    3 => {}
                    n => return fail(format!("vertex has {} numbers (expected 3, 4 or 6)", n + 3)),
                }
                nv += 1;
            }
            Some("vt") => match numbers(&mut words, 2, "texture coordinate") {
                Ok(t) if t.iter().all(|x| x.is_finite()) => nvt += 1,
                Ok(t) => return fail(format!("texture coordinate is not finite ({} {})", t[0], t[1])),
                Err(m) => return fail(m),
            },
            Some("vn") => match numbers(&mut words, 3, "normal") {
                Ok(n) if n.iter().all(|x| x.is_finite()) => nvn += 1,
                Ok(_) => return fail("normal is not finite".into()),
                Err(m) => return fail(m),
            },
            Some("f") | Some("l") => {
                for w in words {
                    let parts: Vec<&str> = w.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return fail(format!("bad face vertex '{w}'"));
                    }
                    for (k, (p, count)) in parts.iter().zip([nv, nvt, nvn]).enumerate() {
                        if p.is_empty() {
                            continue;
                        }
                        let Ok(x) = p.parse::<i64>() else {
                            return fail(format!("bad face index '{p}' in '{w}'"));
                        };
                        let kind = ["vertex", "texture coordinate", "normal"][k];
                        // 1..=count, or -count..=-1 counting back from the last one read.
                        if x == 0 || x.unsigned_abs() > count as u64 {
                            return fail(format!(
                                "face {kind} index {x} is out of range (1..{count} defined so far)"
                            ));
                        }
                    }
                }
            }
            Some("usemtl") if text.split_once(' ').is_none_or(|(_, n)| n.trim().is_empty()) => {
                return fail("usemtl without a material name".into());
            }
            _ => {}
        }
    }
    None
}

/// Checks an MTL file before `tobj` parses it: colours need three numbers,
/// scalars one, and `Kd` must be finite and non-negative.
fn check_mtl(path: &Path, bytes: &[u8]) -> Result<()> {
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let err = |message: String| Error::Syntax {
            path: path.to_path_buf(),
            line: i + 1,
            message,
        };
        let text = std::str::from_utf8(raw).map_err(|_| err("not valid UTF-8 text".into()))?;
        let mut words = text.split_whitespace();
        match words.next() {
            Some(k @ ("Ka" | "Kd" | "Ks" | "Ke")) => {
                let c = numbers(&mut words, 3, k).map_err(err)?;
                if k == "Kd" && !c.iter().all(|x| x.is_finite() && *x >= 0.0) {
                    return Err(err(format!("Kd {} {} {} must be finite and >= 0", c[0], c[1], c[2])));
                }
            }
            Some(k @ ("Ns" | "Ni" | "d")) => {
                numbers(&mut words, 1, k).map_err(err)?;
            }
            Some("illum") => {
                let w = words.next().unwrap_or("");
                w.parse::<u8>().map_err(|_| err(format!("bad illum '{w}'")))?;
            }
            Some("newmtl") if text.trim().len() <= "newmtl".len() => {
                return Err(err("newmtl without a name".into()));
            }
            Some(k) if (k.starts_with("map_") || k == "bump") && words.next().is_none() => {
                return Err(err(format!("{k} without a file name")));
            }
            _ => {}
        }
    }
    Ok(())
}
