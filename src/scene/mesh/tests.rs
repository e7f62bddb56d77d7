use super::*;
use std::io::Write;

/// The triangles of a mesh as coordinates, so that loaders that number
/// vertices differently compare equal.
fn corners(m: &Mesh) -> Vec<[[f32; 3]; 3]> {
    m.triangles
        .iter()
        .map(|t| t.map(|i| m.positions[i as usize].to_array()))
        .collect()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::File::create(&p).unwrap().write_all(bytes).unwrap();
    p
}

/// Asserts that loading fails with a message naming the file and `place`
/// (e.g. ":3:" for line 3, "byte offset 17") and containing `what`.
fn assert_error(path: &Path, place: &str, what: &str) {
    let e = load_mesh(path).expect_err("the load should fail").to_string();
    let name = path.display().to_string();
    assert!(e.starts_with(&name), "'{e}' does not start with '{name}'");
    assert!(e.contains(place), "'{e}' does not give '{place}'");
    assert!(e.contains(what), "'{e}' does not say '{what}'");
    assert!(!e.contains('\n'), "'{e}' is not one line");
}

const SQUARE: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];

#[test]
fn obj_with_quads_negative_indices_and_mtl_loads() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "m.mtl",
        b"# two colours\nnewmtl red\nKd 0.8 0.1 0.1\nNs 10\n\nnewmtl blue\nKd 0.1 0.1 0.8\n",
    );
    let obj = write(
        dir.path(),
        "m.obj",
        b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng quad\nusemtl red\nf 1 2 3 4\n\
          g tri\nusemtl blue\nf -4 -3 -1\n",
    );
    let m = load_mesh(&obj).unwrap();
    let s = SQUARE;
    // The quad is fanned from its first vertex; -4 -3 -1 are vertices 1, 2, 4.
    assert_eq!(
        corners(&m),
        vec![[s[0], s[1], s[2]], [s[0], s[2], s[3]], [s[0], s[1], s[3]]]
    );
    assert_eq!(m.normals, None);
    assert_eq!(m.parts.len(), 2);
    assert_eq!(m.parts[0].name, "quad");
    assert_eq!(m.parts[0].material.as_deref(), Some("red"));
    assert_eq!(m.parts[0].albedo, Some(Vec3::new(0.8, 0.1, 0.1)));
    assert_eq!(m.parts[0].triangles, 0..2);
    assert_eq!(m.parts[1].name, "tri");
    assert_eq!(m.parts[1].albedo, Some(Vec3::new(0.1, 0.1, 0.8)));
    assert_eq!(m.parts[1].triangles, 2..3);
    assert!(m.warnings.is_empty());
}

#[test]
fn obj_normals_are_kept_per_vertex_and_missing_mtl_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "n.obj",
        b"mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\nvn 0 1 0\ng a\nf 1//1 2//2 3//1\ng b\nf 1 3 2\n",
    );
    let m = load_mesh(&obj).unwrap();
    let n = m.normals.as_ref().expect("normals");
    assert_eq!(n.len(), m.positions.len());
    let t = m.triangles[0].map(|i| n[i as usize]);
    assert_eq!(t, [Vec3::Z, Vec3::Y, Vec3::Z]);
    // The part without normals has zeros, which shading treats as flat.
    assert!(m.triangles[1].iter().all(|&i| n[i as usize] == Vec3::ZERO));
    assert_eq!(m.warnings.len(), 1);
    assert!(m.warnings[0].contains("gone.mtl"), "{:?}", m.warnings);
    assert_eq!(m.parts[0].albedo, None);
}

#[test]
fn ply_normals_that_are_not_finite_shade_their_triangles_flat() {
    // Some exporters write NaN normals where a normal is undefined (three
    // meshes of Bitterli's `lamp` in a public pbrt-v4 conversion): such a
    // vertex has no normal, and the triangles around it are flat; the rest
    // of the mesh keeps its normals. A position that is not finite is
    // still an error (`ply_errors_...`).
    let dir = tempfile::tempdir().unwrap();
    let ply = write(
        dir.path(),
        "nan-normal.ply",
        b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
          property float nx\nproperty float ny\nproperty float nz\nelement face 2\n\
          property list uchar int vertex_indices\nend_header\n\
          0 0 0 0 0.6 0.8\n1 0 0 0 0.6 0.8\n0 1 0 nan nan nan\n1 1 0 0 0.6 0.8\n3 0 1 2\n3 1 3 0\n",
    );
    let m = load_mesh(&ply).unwrap();
    let n = m.normals.as_ref().expect("normals");
    assert_eq!(n[2], Vec3::ZERO);
    assert_eq!(n[0], Vec3::new(0.0, 0.6, 0.8));
    assert_eq!(m.warnings.len(), 1);
    assert!(
        m.warnings[0].contains("1 of 4 vertices have a normal that is not finite"),
        "{:?}",
        m.warnings
    );
    let read = ply::read(&ply, &std::fs::read(&ply).unwrap(), ply::Polygons::TrianglesAndQuads).unwrap();
    assert_eq!(read.non_finite_normals, 1);
}

/// One mesh, written as PLY in each encoding: a quad and a triangle over four
/// vertices with normals, extra properties of several types, an element we
/// do not know, and a face list with an extra property after it.
fn ply_file(format: &str) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment made by a test\nelement vertex 4\n\
         property double x\nproperty float y\nproperty float z\nproperty uchar red\nproperty float nx\n\
         property float ny\nproperty float nz\nproperty list uchar short junk\n\
         element edge 1\nproperty int a\nproperty int b\n\
         element face 2\nproperty list uchar int vertex_indices\nproperty ushort flags\nend_header\n"
    )
    .into_bytes();
    let verts = [
        (SQUARE[0], 1u8, [0.0f32, 0.0, 1.0]),
        (SQUARE[1], 2, [0.0, 1.0, 0.0]),
        (SQUARE[2], 3, [1.0, 0.0, 0.0]),
        (SQUARE[3], 4, [0.0, 0.0, -1.0]),
    ];
    let faces: [&[i32]; 2] = [&[0, 1, 2, 3], &[3, 1, 0]];
    if format == "ascii" {
        for (p, r, n) in verts {
            out.extend(format!("{} {} {} {r} {} {} {} 2 -7 9\n", p[0], p[1], p[2], n[0], n[1], n[2]).bytes());
        }
        out.extend(b"0 1\n");
        for f in faces {
            let idx: Vec<String> = f.iter().map(|i| i.to_string()).collect();
            out.extend(format!("{} {} 65535\n", f.len(), idx.join(" ")).bytes());
        }
        return out;
    }
    let be = format == "binary_big_endian";
    let mut put = |b: &[u8]| {
        let mut b = b.to_vec();
        if be {
            b.reverse();
        }
        out.extend(b);
    };
    for (p, r, n) in verts {
        put(&(p[0] as f64).to_le_bytes());
        put(&p[1].to_le_bytes());
        put(&p[2].to_le_bytes());
        put(&[r]);
        for c in n {
            put(&c.to_le_bytes());
        }
        put(&[2]);
        put(&(-7i16).to_le_bytes());
        put(&9i16.to_le_bytes());
    }
    put(&0i32.to_le_bytes());
    put(&1i32.to_le_bytes());
    for f in faces {
        put(&[f.len() as u8]);
        for i in f {
            put(&i.to_le_bytes());
        }
        put(&65535u16.to_le_bytes());
    }
    out
}

#[test]
fn ply_loads_the_same_in_all_three_encodings() {
    let dir = tempfile::tempdir().unwrap();
    let s = SQUARE;
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let p = write(dir.path(), &format!("{format}.ply"), &ply_file(format));
        let m = load_mesh(&p).unwrap_or_else(|e| panic!("{format}: {e}"));
        assert_eq!(
            corners(&m),
            vec![[s[0], s[1], s[2]], [s[0], s[2], s[3]], [s[3], s[1], s[0]]],
            "{format}"
        );
        let n = m.normals.as_ref().expect("normals");
        assert_eq!(n, &vec![Vec3::Z, Vec3::Y, Vec3::X, -Vec3::Z], "{format}");
        assert_eq!(m.parts.len(), 1);
        assert_eq!(m.parts[0].triangles, 0..3);
    }
}

#[test]
fn ply_gz_loads_as_the_ply_and_pbrt_mode_skips_what_pbrt_skips() {
    // The one PLY reader serves both paths: a .ply.gz mesh loads like its PLY.
    let dir = tempfile::tempdir().unwrap();
    let bytes = ply_file("binary_little_endian");
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&bytes).unwrap();
    let p = write(dir.path(), "m.PLY.gz", &gz.finish().unwrap());
    let plain = load_mesh(&write(dir.path(), "m.ply", &bytes)).unwrap();
    let m = load_mesh(&p).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(corners(&m), corners(&plain));
    assert_error(
        &write(dir.path(), "bad.ply.gz", &bytes),
        "bad.ply.gz",
        "cannot decompress",
    );
    // A pentagon: fanned for meshes, skipped and counted for pbrt's plymesh.
    let text = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
element face 3\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 2 0\n5 0 1 2 3 4\n4 0 1 2 3\n3 0 1 2\n";
    let fan = ply::read(Path::new("p.ply"), text.as_bytes(), ply::Polygons::Fan).unwrap();
    assert_eq!((fan.triangles.len(), fan.quads, fan.skipped_faces), (3 + 2 + 1, 1, 0));
    let pbrt = ply::read(Path::new("p.ply"), text.as_bytes(), ply::Polygons::TrianglesAndQuads).unwrap();
    assert_eq!((pbrt.triangles.len(), pbrt.quads, pbrt.skipped_faces), (2 + 1, 1, 1));
    assert_eq!(pbrt.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2]]);
}

#[test]
fn ply_vertex_index_and_other_integer_types_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "vi.ply",
        b"ply\nformat ascii 1.0\nelement face 1\nproperty list int uint vertex_index\n\
          element vertex 3\nproperty short x\nproperty short y\nproperty short z\nend_header\n\
          3 2 1 0\n0 0 0\n4 0 0\n0 4 0\n",
    );
    let m = load_mesh(&p).unwrap();
    // Faces before vertices are fine: indices are checked against the header's count.
    assert_eq!(corners(&m), vec![[[0.0, 4.0, 0.0], [4.0, 0.0, 0.0], [0.0, 0.0, 0.0]]]);
    assert_eq!(m.normals, None);
}

#[test]
fn malformed_obj_files_name_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&str, &[u8], &str, &str); 9] = [
        (
            "number.obj",
            b"v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n",
            ":2:",
            "bad number 'x'",
        ),
        ("short.obj", b"v 0 0 0\nv 1 0\nf 1 2 3\n", ":2:", "needs 3 numbers"),
        (
            "range.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n",
            ":5:",
            "out of range",
        ),
        (
            "zero.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            ":4:",
            "out of range",
        ),
        (
            "negative.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n",
            ":4:",
            "out of range",
        ),
        (
            "nan.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n",
            ":3:",
            "not finite",
        ),
        (
            "inf.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n",
            ":3:",
            "not finite",
        ),
        (
            "uv-nan.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt nan 0\nvt 1 1\nf 1/1 2/2 3/3\n",
            ":5:",
            "texture coordinate is not finite",
        ),
        (
            "face.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 three\n",
            ":4:",
            "bad face index",
        ),
    ];
    for (name, text, place, what) in cases {
        assert_error(&write(d, name, text), place, what);
    }
    assert_error(&write(d, "empty.obj", b"# nothing\nv 0 0 0\n"), "empty.obj", "no faces");
    assert_error(&d.join("absent.obj"), "absent.obj", "No such file");
    assert_error(&write(d, "mesh.stl", b"solid"), "mesh.stl", "unknown mesh format");
    // A bad MTL file is named with its own line.
    write(d, "bad.mtl", b"newmtl red\nKd 0.8 0.1\n");
    let obj = write(
        d,
        "uses-bad.obj",
        b"mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let e = load_mesh(&obj).unwrap_err().to_string();
    assert!(
        e.starts_with(&d.join("bad.mtl").display().to_string()) && e.contains(":2:"),
        "{e}"
    );
}

#[test]
fn malformed_ply_files_name_the_file_and_line_or_offset() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let ascii = |body: &str| format!("{head}{body}").into_bytes();
    let cases: Vec<(&str, Vec<u8>, &str, &str)> = vec![
        (
            "number.ply",
            ascii("0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n"),
            ":11:",
            "bad number 'zero'",
        ),
        (
            "range.ply",
            ascii("0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
            ":13:",
            "out of range",
        ),
        (
            "nan.ply",
            ascii("0 0 0\n1 0 0\n0 NaN 0\n3 0 1 2\n"),
            ":12:",
            "not finite",
        ),
        ("cut.ply", ascii("0 0 0\n1 0 0\n0 1 0\n3 0 1\n"), ":13:", "end of file"),
        ("magic.ply", b"plx\n".to_vec(), ":1:", "not a PLY file"),
        (
            "type.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float3 x\nend_header\n".to_vec(),
            ":4:",
            "unknown property type",
        ),
        (
            "nohead.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\n".to_vec(),
            ":4:",
            "end_header",
        ),
        (
            "noxyz.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n".to_vec(),
            ":3:",
            "no x, y and z",
        ),
    ];
    for (name, text, place, what) in cases {
        assert_error(&write(d, name, &text), place, what);
    }
    let noface = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                  end_header\n0 0 0\n1 0 0\n0 1 0\n";
    assert_error(&write(d, "noface.ply", noface.as_bytes()), "noface.ply", "no faces");
    // A header that declares fewer vertices than the body holds: the extra
    // vertex reads as an empty face, and the error points at what is left.
    let short = head.replace("element vertex 3", "element vertex 2");
    let more = format!("{short}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    assert_error(
        &write(d, "more.ply", more.as_bytes()),
        ":12:",
        "are the header's counts right?",
    );
    // Data after a well-formed body is ignored, as pbrt-v4 ignores it, with a warning.
    let extra = format!("{head}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n9 9 9\n");
    let m = load_mesh(&write(d, "extra.ply", extra.as_bytes())).unwrap();
    assert_eq!(m.triangles.len(), 1);
    assert!(
        m.warnings.len() == 1 && m.warnings[0].starts_with("line 14: data beyond the 3 vertices"),
        "{:?}",
        m.warnings
    );

    // Binary: the header is 143 bytes, then 3 vertices of 12 bytes each.
    let bin_head = head.replace("ascii", "binary_little_endian");
    let mut bin = bin_head.clone().into_bytes();
    let h = bin.len();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            bin.extend(c.to_le_bytes());
        }
    }
    let mut cut = bin.clone();
    cut.extend([3u8]);
    cut.extend(0i32.to_le_bytes());
    cut.extend([1u8, 0]); // two bytes of the second index
    assert_error(
        &write(d, "cut-bin.ply", &cut),
        &format!("byte offset {}", h + 36 + 5),
        "truncated",
    );
    let mut range = bin.clone();
    range.extend([3u8]);
    for i in [0i32, 1, -1] {
        range.extend(i.to_le_bytes());
    }
    assert_error(
        &write(d, "range-bin.ply", &range),
        &format!("byte offset {}", h + 36 + 9),
        "out of range",
    );
    let mut nan = bin_head.into_bytes();
    for c in [0.0f32, f32::INFINITY, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        nan.extend(c.to_le_bytes());
    }
    nan.extend([3u8]);
    for i in [0i32, 1, 2] {
        nan.extend(i.to_le_bytes());
    }
    assert_error(
        &write(d, "nan-bin.ply", &nan),
        &format!("byte offset {h}"),
        "not finite",
    );
}

#[test]
fn ply_header_claiming_more_than_the_file_holds_fails_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let text = b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\n\
                 property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                 end_header\n\0\0\0\0";
    let p = write(dir.path(), "huge.ply", text);
    assert_error(&p, ":3:", "declares 1000000000000 items");
    // Faces too: a list count may not promise more indices than there are bytes.
    let text = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
                 property float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\n\
                 end_header\n";
    let mut bytes = text.to_vec();
    bytes.extend([0u8; 36]);
    bytes.extend(u32::MAX.to_le_bytes());
    assert_error(&write(dir.path(), "long-list.ply", &bytes), "byte offset", "truncated");
}

/// The Stanford bunny, when `../shared/assets` has it; without it the test
/// says it skips, except under CI (`CI` set), where `../shared` is always
/// there and a missing bunny fails the test.
pub(crate) fn bunny_path() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/stanford-bunny.obj");
    if p.is_file() {
        Some(p)
    } else if std::env::var_os("CI").is_some() {
        panic!(
            "{} is absent: under CI (CI is set) the shared assets must be there",
            p.display()
        );
    } else {
        println!("skipped: {} is absent", p.display());
        None
    }
}

#[test]
fn bunny_has_the_bounds_scenes_md_gives() {
    let Some(p) = bunny_path() else { return };
    let m = load_mesh(&p).unwrap();
    assert_eq!(m.triangles.len(), 69_451);
    let b = m.bounds();
    let want = [
        (b.min.x, -0.094690),
        (b.max.x, 0.061009),
        (b.min.y, 0.032987),
        (b.max.y, 0.187321),
        (b.min.z, -0.061874),
        (b.max.z, 0.058800),
    ];
    for (got, want) in want {
        assert!((got - want).abs() < 1e-6, "{got} vs {want}");
    }
}

/// A unit square in z = 0 from a mesh file, its texture coordinates
/// (0, 0) .. (2, 1) at its corners, placed in a scene and hit by rays.
fn hit_uv(mesh: &Mesh, x: f32, y: f32) -> crate::math::Vec2 {
    use crate::scene::{CameraDesc, Scene, SceneDesc};
    let camera = CameraDesc {
        position: Vec3::new(0.5, 0.5, -2.0),
        look_at: Vec3::new(0.5, 0.5, 0.0),
        up: Vec3::new(0.0, -1.0, 0.0),
        fov_y_deg: 40.0,
        width: 8,
        height: 8,
        window: None,
        lens: None,
        orthographic: None,
        spherical: None,
        realistic: None,
    };
    let mut desc = SceneDesc::empty("uv", camera);
    let m = desc.material("grey", Material::diffuse(0.5, 0.5, 0.5));
    mesh.add_to_scene(&mut desc, &Transform::default(), Some(m), false)
        .unwrap();
    let scene = Scene::build(desc).unwrap();
    let ray = crate::math::Ray::new(Vec3::new(x, y, -1.0), Vec3::Z);
    scene
        .intersect(&ray, 1e-4, f32::INFINITY)
        .expect("the ray hits the square")
        .uv
}

fn assert_uvs_interpolate(mesh: &Mesh) {
    let uvs = mesh.uvs.as_ref().expect("texture coordinates");
    assert_eq!(uvs.len(), mesh.positions.len());
    for (x, y) in [(0.25f32, 0.5f32), (0.9, 0.1), (0.1, 0.8), (0.5, 0.5)] {
        let uv = hit_uv(mesh, x, y);
        assert!(
            (uv - crate::math::Vec2::new(2.0 * x, y)).abs().max_element() < 1e-5,
            "({x}, {y}): {uv}"
        );
    }
}

#[test]
fn obj_texture_coordinates_reach_the_hit() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "quad.obj",
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 2 0\nvt 2 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n",
    );
    let m = load_mesh(&p).unwrap();
    assert_uvs_interpolate(&m);
    // Faces without vt give no coordinates.
    let p = write(dir.path(), "plain.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
    assert_eq!(load_mesh(&p).unwrap().uvs, None);
}

#[test]
fn ply_texture_coordinates_under_each_name_reach_the_hit() {
    let dir = tempfile::tempdir().unwrap();
    for [u, v] in [
        ["u", "v"],
        ["s", "t"],
        ["texture_u", "texture_v"],
        ["texture_s", "texture_t"],
    ] {
        let text = format!(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             property float {u}\nproperty float {v}\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
             0 0 0 0 0\n1 0 0 2 0\n1 1 0 2 1\n0 1 0 0 1\n4 0 1 2 3\n"
        );
        let p = write(dir.path(), &format!("quad-{u}.ply"), text.as_bytes());
        let m = load_mesh(&p).unwrap();
        assert_uvs_interpolate(&m);
    }
    let p = write(
        dir.path(),
        "nan.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
          property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
          0 0 0 0 0\n1 0 0 nan 0\n1 1 0 1 1\n3 0 1 2\n",
    );
    assert_error(&p, ":13:", "texture coordinate");
}
