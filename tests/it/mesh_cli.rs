//! End to end through the binary: bad meshes and scene files exit with
//! status 2 and one line naming the file, and leave no output behind.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn raytracer(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The Stanford bunny, when `../shared/assets` has it; without it the test
/// says it skips, except under CI (`CI` set), where `../shared` is always
/// there and a missing bunny fails the test.
fn bunny() -> Option<PathBuf> {
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

/// Renders with `args` into a fresh folder and checks the run failed as it
/// should: status 2, one line on stderr containing each of `expect`, and no
/// image (or temporary file) left in the folder.
fn assert_refused(dir: &Path, args: &[&str], expect: &[&str]) {
    let out = dir.join("out.pfm");
    let mut all = args.to_vec();
    let out_s = out.display().to_string();
    all.extend(["-o", &out_s, "--width", "8", "--height", "8", "--ssaa", "1"]);
    let o = raytracer(&all);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: not one line: {err}");
    for e in expect {
        assert!(err.contains(e), "{args:?}: '{err}' does not contain '{e}'");
    }
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("out"))
        .collect();
    assert!(left.is_empty(), "{args:?}: left {left:?}");
}

const SCENE: &str = "[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
                     [materials.grey]\nalbedo = [0.5, 0.5, 0.5]\n\
                     [[lights]]\ntype = \"point\"\nposition = [0, 0, -2]\npower = 10\n";

fn mesh_scene(dir: &Path, mesh: &str) -> String {
    let p = dir.join("scene.toml");
    let text = format!("{SCENE}[[shapes]]\ntype = \"mesh\"\npath = \"{mesh}\"\nmaterial = \"grey\"\n");
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn malformed_meshes_exit_2_naming_the_file_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
    let scene = mesh_scene(d, "bad.obj");
    assert_refused(d, &["--scene", &scene], &["bad.obj:4:", "out of range"]);
    // --mesh replaces the scene's mesh path, and is checked the same way.
    std::fs::write(d.join("nan.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n").unwrap();
    let nan = d.join("nan.ply").display().to_string();
    assert_refused(d, &["--scene", &scene, "--mesh", &nan], &["nan.ply:11:", "not finite"]);
    let mut cut = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    let h = cut.len();
    cut.extend([0u8; 36]);
    cut.extend([3u8, 0, 0, 0, 0, 0]);
    std::fs::write(d.join("cut.ply"), &cut).unwrap();
    let cut = d.join("cut.ply").display().to_string();
    assert_refused(
        d,
        &["--scene", &scene, "--mesh", &cut],
        &["cut.ply", &format!("byte offset {}", h + 41), "truncated"],
    );
    let missing = mesh_scene(d, "absent.obj");
    assert_refused(
        d,
        &["--scene", &missing],
        &["scene.toml:11:", "absent.obj not found", "--mesh PATH"],
    );
    assert_refused(
        d,
        &["--scene", "cornell-bunny", "--mesh", "no/such/bunny.ply"],
        &["no/such/bunny.ply", "No such file"],
    );
    assert_refused(
        d,
        &["--scene", &scene, "--mesh", "bunny.stl"],
        &["bunny.stl", "unknown mesh format"],
    );
}

#[test]
fn malformed_scene_files_exit_2_naming_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let p = d.join("typo.toml");
    std::fs::write(
        &p,
        format!("{SCENE}[[shapes]]\ntype = \"sphere\"\nmaterial = \"grey\"\ncentre = [0, 0, 0]\nradiu = 1\n"),
    )
    .unwrap();
    assert_refused(
        d,
        &["--scene", &p.display().to_string()],
        &["typo.toml:15:", "unknown field `radiu`"],
    );
    let p = d.join("syntax.toml");
    std::fs::write(&p, "[camera\n").unwrap();
    assert_refused(d, &["--scene", &p.display().to_string()], &["syntax.toml:1:"]);
    assert_refused(d, &["--scene", "absent.toml"], &["absent.toml", "No such file"]);
    assert_refused(
        d,
        &["--scene", "cornel"],
        &["unknown scene 'cornel'", "cornell, cornell-bunny, cornell-final"],
    );
    assert_refused(
        d,
        &["--scene", "cornell", "--mesh", "x.obj"],
        &["--mesh", "has no mesh"],
    );
}

#[test]
fn bunny_scenes_without_mesh_say_where_to_get_it() {
    let dir = tempfile::tempdir().unwrap();
    for scene in ["cornell-bunny", "cornell-final"] {
        let hint = [
            "needs the Stanford bunny",
            "Stanford 3D Scanning Repository",
            "bun_zipper.ply",
            "--mesh PATH",
        ];
        assert_refused(dir.path(), &["--scene", scene], &hint);
        let o = raytracer(&["info", "--scene", scene]);
        assert_eq!(o.status.code(), Some(2));
        assert!(stderr(&o).contains("--mesh PATH"));
    }
}

#[test]
fn info_works_for_every_scene() {
    let o = raytracer(&["info", "--scene", "scenes/cornell.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("triangles: 30 "));
    let Some(bunny) = bunny() else { return };
    let bunny = bunny.display().to_string();
    for scene in ["cornell-bunny", "cornell-final", "scenes/cornell-bunny.toml"] {
        let o = raytracer(&["info", "--scene", scene, "--mesh", &bunny]);
        assert!(o.status.success(), "{scene}: {}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(
            out.contains("69451 triangles") && out.contains("loaded in"),
            "{scene}: {out}"
        );
        // The mesh's vertices are stored once, not once a triangle; the
        // room's triangles bring three each.
        let count = |prefix: &str| -> usize {
            out.lines()
                .find_map(|l| l.strip_prefix(prefix)?.split([' ', ',']).next()?.parse().ok())
                .unwrap_or_else(|| panic!("{scene}: no {prefix:?} in {out}"))
        };
        let (vertices, triangles) = (count("vertices: "), count("triangles: "));
        let mesh: usize = out
            .split_once(" vertices, 69451 triangles")
            .and_then(|(head, _)| head.rsplit('(').next()?.parse().ok())
            .unwrap_or_else(|| panic!("{scene}: no mesh line in {out}"));
        assert_eq!(vertices, mesh + 3 * (triangles - 69_451), "{scene}: {out}");
    }
}

#[test]
fn degenerate_triangles_are_dropped_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("flat.obj"),
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n",
    )
    .unwrap();
    let scene = mesh_scene(d, "flat.obj");
    let out = d.join("ok.pfm").display().to_string();
    let args = [
        "--scene", &scene, "-o", &out, "--width", "8", "--height", "8", "--ssaa", "1",
    ];
    let o = raytracer(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: 1 degenerate triangles"), "{}", stderr(&o));
    assert!(d.join("ok.pfm").is_file());
    let mut quiet = args.to_vec();
    quiet.push("--quiet");
    let o = raytracer(&quiet);
    assert!(o.status.success() && o.stderr.is_empty(), "{}", stderr(&o));
}
