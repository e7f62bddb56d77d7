//! Inputs the fuzz targets (`fuzz/`, see docs/robustness.md) found or that
//! the issue names: each must give a clean error (or load), never a panic, a
//! hang or an allocation sized by a number in the file. Inputs too long to
//! read inline are files under tests/fuzz-crashers/, named after the target.

use raytracer::material::Material;
use raytracer::scene::file::parse_with;
use raytracer::scene::mesh::{parse_mesh, FileSource, Mesh, MeshFormat};
use raytracer::scene::transform::Transform;
use raytracer::scene::{builtin, pbrt, LoadOptions, Scene};
use std::path::{Path, PathBuf};

/// No files at all: the loaders must not reach the machine's files.
struct NoFiles;

impl FileSource for NoFiles {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!("{} is not served", path.display()),
        ))
    }
}

/// What the mesh targets do with a loaded mesh: place it, smooth-shaded,
/// in a scene and build that.
fn place(m: &Mesh) -> Result<(), String> {
    let _ = m.bounds();
    let mut desc = builtin::cornell();
    let grey = desc.material("grey", Material::diffuse(0.5, 0.5, 0.5));
    m.add_to_scene(&mut desc, &Transform::default(), Some(grey), true)
        .map_err(|e| e.to_string())?;
    Scene::build(desc).map_err(|e| e.to_string())?;
    Ok(())
}

fn obj(bytes: &[u8]) -> Result<(), String> {
    place(&parse_mesh(Path::new("t.obj"), bytes, MeshFormat::Obj, &NoFiles).map_err(|e| e.to_string())?)
}

fn ply(bytes: &[u8]) -> Result<(), String> {
    place(&parse_mesh(Path::new("t.ply"), bytes, MeshFormat::Ply, &NoFiles).map_err(|e| e.to_string())?)
}

/// What the pbrt target does: the scene up to the first NUL, the rest served
/// as every `.ply` (and `.ply.gz`), `.spd` and `.nvdb` it names, `inc.pbrt` a fixed file; read,
/// converted leniently and built.
fn pbrt(bytes: &[u8]) -> Result<(), String> {
    let (text, ply) = match bytes.iter().position(|&b| b == 0) {
        Some(i) => (&bytes[..i], &bytes[i + 1..]),
        None => (bytes, &[][..]),
    };
    let files = PbrtFiles { ply: ply.to_vec() };
    let path = Path::new("virtual/scene.pbrt");
    let parsed = pbrt::parse_bytes(path, text.to_vec(), &files).map_err(|e| e.to_string())?;
    let converted = pbrt::convert::convert(&parsed, path, true).map_err(|e| e.to_string())?;
    Scene::build(converted.desc).map_err(|e| e.to_string())?;
    Ok(())
}

/// The files the pbrt target serves (see fuzz/fuzz_targets/pbrt.rs).
struct PbrtFiles {
    ply: Vec<u8>,
}

impl FileSource for PbrtFiles {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        let name = path.to_string_lossy();
        if path == Path::new("virtual/inc.pbrt") {
            // The same text as the target's `INCLUDE`.
            Ok(b"MakeNamedMaterial \"m\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\n\
AttributeBegin\nNamedMaterial \"m\"\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\nAttributeEnd\n"
                .to_vec())
        } else if name.ends_with(".ply")
            || name.ends_with(".ply.gz")
            || name.ends_with(".spd")
            || name.ends_with(".nvdb")
        {
            Ok(self.ply.clone())
        } else {
            NoFiles.read(path)
        }
    }
}

fn scene(text: &str) -> Result<(), String> {
    let loaded = parse_with(Path::new("t.toml"), text, &LoadOptions::default(), &NoFiles).map_err(|e| e.to_string())?;
    Scene::build(loaded.desc).map_err(|e| e.to_string())?;
    Ok(())
}

/// Where the committed inputs live, one folder per target. It is part of
/// the test: a checkout without it fails rather than testing nothing.
/// The measured target: a tensor file read, and any BRDF it gives
/// evaluated and sampled at a few directions in both transport modes:
/// values and densities finite and never negative (else an error).
fn measured(bytes: &[u8]) -> Result<(), String> {
    use raytracer::bsdf::{MeasuredBxdf, MeasuredData, TransportMode};
    use raytracer::math::{Vec2, Vec3};
    let grey = |l: &[f32]| vec![Vec3::splat(1.0 / l.len().max(1) as f32); l.len()];
    let m = MeasuredData::from_bytes(bytes, "fuzz.bsdf", grey)?;
    let b = MeasuredBxdf::new(Box::leak(Box::new(m)));
    let dirs = [
        Vec3::Z,
        Vec3::new(0.6, 0.0, 0.8),
        Vec3::new(-0.3, 0.5, 0.812404),
        Vec3::new(0.0, -0.99, 0.141067),
    ];
    for mode in [TransportMode::Radiance, TransportMode::Importance] {
        for wo in dirs {
            for wi in dirs {
                let (f, pdf) = (b.f(wo, wi, mode), b.pdf(wo, wi));
                if !(f.is_finite() && f.min_element() >= 0.0 && pdf.is_finite() && pdf >= 0.0) {
                    return Err(format!("f {f}, pdf {pdf} at {wo} {wi}"));
                }
            }
            for u in [Vec2::new(0.1, 0.2), Vec2::new(0.5, 0.5), Vec2::new(0.97, 0.01)] {
                if let Some(s) = b.sample_f(wo, u, mode) {
                    if !(s.f.is_finite() && s.f.min_element() >= 0.0 && s.pdf > 0.0 && s.pdf.is_finite()) {
                        return Err(format!("sample {s:?} at {wo}"));
                    }
                }
            }
        }
    }
    Ok(())
}

fn corpus() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-crashers");
    assert!(
        dir.is_dir(),
        "{} is missing: the committed fuzz inputs are part of this test",
        dir.display()
    );
    dir
}

/// The committed inputs of one target; its folder must exist.
fn crashers(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = corpus().join(target);
    let mut out: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| {
            panic!(
                "{}: {e}: the committed fuzz inputs are part of this test",
                dir.display()
            )
        })
        .map(|e| e.unwrap().path())
        .collect();
    out.sort();
    out.into_iter()
        .map(|p| (p.clone(), std::fs::read(&p).unwrap()))
        .collect()
}

#[test]
fn obj_with_absurd_indices_is_refused_at_its_line() {
    for (face, index) in [
        ("f 1 2 99999999999", "99999999999"),
        ("f 1 2 -4", "-4"),
        ("f 1 2 0", "0"),
    ] {
        let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\n{face}\n");
        let e = obj(text.as_bytes()).unwrap_err();
        assert!(e.starts_with("t.obj:4:") && e.contains(index), "{face}: {e}");
    }
    // Beyond i64: not a number we can use at all.
    let e = obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 999999999999999999999999\n").unwrap_err();
    assert!(e.starts_with("t.obj:4:"), "{e}");
}

#[test]
fn ply_header_counts_beyond_the_file_are_refused() {
    let e = ply(
        b"ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\n\
property float z\nend_header\n0 0 0\n",
    )
    .unwrap_err();
    assert!(
        e.starts_with("t.ply:3:") && e.contains("declares 1000000000000 items"),
        "{e}"
    );
}

#[test]
fn scene_sizes_beyond_the_limits_are_refused_at_the_camera() {
    let camera = "[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nfov_y = 40\n";
    for (size, what) in [
        ("width = 1000000000", "width 1000000000"),
        ("height = 0", "height 0"),
        ("width = 30000\nheight = 30000", "30000x30000"),
    ] {
        let e = scene(&format!("{camera}{size}\n")).unwrap_err();
        assert!(e.starts_with("t.toml:1:") && e.contains(what), "{size}: {e}");
    }
    scene(&format!("{camera}width = 32768\nheight = 16\n")).unwrap();
}

#[test]
fn committed_fuzz_inputs_load_or_fail_cleanly() {
    // Every target folder present is run; obj and ply have findings, so they must be there.
    let mut targets: Vec<String> = std::fs::read_dir(corpus())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    targets.sort();
    for needed in ["obj", "ply"] {
        assert!(
            targets.iter().any(|t| t == needed),
            "no {needed} folder in the corpus: {targets:?}"
        );
    }
    let mut seen = 0;
    for target in &targets {
        let run: fn(&[u8]) -> Result<(), String> = match target.as_str() {
            "obj" => obj,
            "ply" => ply,
            "scene" => |b: &[u8]| scene(std::str::from_utf8(b).unwrap_or("")),
            "pbrt" => pbrt,
            "measured" => measured,
            other => panic!("tests/fuzz-crashers/{other}: not a fuzz target (obj, ply, scene, pbrt, measured)"),
        };
        for (path, bytes) in crashers(target) {
            // Ok or Err are both fine; a panic fails the test, naming the file.
            let r = std::panic::catch_unwind(|| run(&bytes));
            assert!(r.is_ok(), "{} panicked", path.display());
            seen += 1;
        }
    }
    assert!(seen >= 3, "only {seen} committed fuzz inputs");
    println!("{seen} committed fuzz inputs");
}

/// Serves one OBJ (with the MTL after its NUL, as the obj target splits its
/// input) and one PLY under any name with their extension.
struct Seeds {
    obj: Vec<u8>,
    ply: Vec<u8>,
}

impl FileSource for Seeds {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        let (obj, mtl) = match self.obj.iter().position(|&b| b == 0) {
            Some(i) => (&self.obj[..i], &self.obj[i + 1..]),
            None => (&self.obj[..], &[][..]),
        };
        match path.extension().and_then(|e| e.to_str()) {
            Some("obj") => Ok(obj.to_vec()),
            Some("mtl") => Ok(mtl.to_vec()),
            Some("ply") => Ok(self.ply.clone()),
            _ => NoFiles.read(path),
        }
    }
}

#[test]
fn fuzz_seeds_are_valid_inputs() {
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds");
    let files = |t: &str| {
        let mut v: Vec<_> = std::fs::read_dir(seeds.join(t))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        v.sort();
        v
    };
    let ply_seeds = files("ply");
    for p in &ply_seeds {
        let bytes = std::fs::read(p).unwrap();
        parse_mesh(Path::new("s.ply"), &bytes, MeshFormat::Ply, &NoFiles).unwrap_or_else(|e| panic!("{e}"));
    }
    let obj_seeds = files("obj");
    for p in &obj_seeds {
        let src = Seeds {
            obj: std::fs::read(p).unwrap(),
            ply: vec![],
        };
        let m = raytracer::scene::mesh::load_mesh_from(Path::new("s.obj"), &src).unwrap_or_else(|e| panic!("{e}"));
        assert!(m.warnings.is_empty(), "{}: {:?}", p.display(), m.warnings);
    }
    let src = Seeds {
        obj: std::fs::read(obj_seeds.iter().find(|p| p.ends_with("groups-mtl.obj")).unwrap()).unwrap(),
        ply: std::fs::read(&ply_seeds[0]).unwrap(),
    };
    for p in files("scene") {
        let text = std::fs::read_to_string(&p).unwrap();
        let loaded = parse_with(Path::new("s.toml"), &text, &LoadOptions::default(), &src)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        Scene::build(loaded.desc).unwrap();
    }
    let pbrt_seeds = files("pbrt");
    for p in &pbrt_seeds {
        pbrt(&std::fs::read(p).unwrap()).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    }
    assert!(ply_seeds.len() >= 3 && obj_seeds.len() >= 3 && pbrt_seeds.len() >= 3);
    let measured_seeds = files("measured");
    for p in &measured_seeds {
        measured(&std::fs::read(p).unwrap()).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    }
    assert!(measured_seeds.len() >= 2);
}

/// Finding 6: a position a rounding past the unit square blended the
/// bilinear corners with a negative weight, and a density came out
/// negative. The input's visible-normal table also integrates to 2e-40,
/// too little to normalise, and such a file is now refused.
#[test]
fn measured_densities_past_the_square_stay_non_negative() {
    let (_, bytes) = &crashers("measured")[0];
    let e = measured(bytes).unwrap_err();
    assert!(e.contains("\"vndf\"") && e.contains("nothing to sample"), "{e}");
}

#[test]
fn ply_with_a_second_vertex_element_is_refused() {
    // Found by the ply target: the second list's normals replaced the first's
    // while indices were checked against the first, and placing the mesh
    // indexed past the normals.
    let (path, bytes) = &crashers("ply")
        .into_iter()
        .find(|(p, _)| p.ends_with("duplicate-vertex-element.ply"))
        .unwrap();
    let e = ply(bytes).unwrap_err();
    assert!(
        e.contains("element 'vertex' is declared twice"),
        "{}: {e}",
        path.display()
    );
    let e = ply(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 1 1\n",
    )
    .unwrap_err();
    assert!(e.starts_with("t.ply:7:") && e.contains("first at line 3"), "{e}");
}

#[test]
fn a_device_named_as_material_library_is_not_read() {
    // `mtllib /dev/zero` would be read until memory runs out.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("dev.obj");
    std::fs::write(&p, "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let m = raytracer::scene::mesh::load_mesh(&p).unwrap();
    assert!(
        m.warnings.len() == 1 && m.warnings[0].contains("not a regular file"),
        "{:?}",
        m.warnings
    );
}

#[test]
fn obj_relative_index_before_the_first_normal_is_refused_before_tobj() {
    // Found by the obj target: `1//-11` with one normal made tobj's index
    // arithmetic overflow (a panic with overflow checks, a wrapped index without).
    let (_, bytes) = &crashers("obj")
        .into_iter()
        .find(|(p, _)| p.ends_with("relative-index-out-of-range.obj"))
        .unwrap();
    let e = obj(bytes).unwrap_err();
    assert!(e.starts_with("t.obj:12:") && e.contains("normal index -11"), "{e}");
    for face in ["f 1 2 -4", "f 1/-2 2/1 3/1", "f 1//-2 2//1 3//1"] {
        let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n{face}\n");
        let e = obj(text.as_bytes()).unwrap_err();
        assert!(e.starts_with("t.obj:6:") && e.contains("out of range"), "{face}: {e}");
    }
}

#[test]
fn obj_line_element_with_a_bad_index_is_refused_before_tobj() {
    // Found by the obj target: tobj reads an `l` line of four indices as a
    // quad, and `-21` with five texture coordinates overflowed it as above.
    let (_, bytes) = &crashers("obj")
        .into_iter()
        .find(|(p, _)| p.ends_with("line-element-index-out-of-range.obj"))
        .unwrap();
    assert!(obj(bytes).is_err());
    let e = obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nl 1/1 2/-3 3/1 1/1\n").unwrap_err();
    assert!(
        e.starts_with("t.obj:5:") && e.contains("texture coordinate index -3"),
        "{e}"
    );
}
