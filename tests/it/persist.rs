//! Work carried between runs, through the binary: a photon map traced once
//! and loaded by other renders, and progressive renders stopped and resumed;
//! each gives the image of a single uninterrupted run, byte for byte, and
//! damaged or mismatched files are refused with one line naming the file and
//! exit status 2. Renders are stopped by the hidden options that trip the
//! interruption (as SIGINT does) after N passes or tiles: deterministic,
//! where a signal sent after a sleep lands anywhere.

use std::path::Path;
use std::process::{Command, Output};

fn run(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

fn ok(args: &[&str], dir: &Path) -> Output {
    let o = run(args, dir);
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    o
}

/// Runs, expects exit status 2 with one line naming `file` and containing `needle`.
fn refused(args: &[&str], dir: &Path, file: &str, needle: &str) {
    let o = run(args, dir);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    assert!(err.contains(file) && err.contains(needle), "{args:?}: {err}");
}

fn read(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap()
}

const PHOTON: [&str; 9] = [
    "--quiet",
    "--integrator",
    "photon",
    "--width",
    "40",
    "--height",
    "32",
    "--photons",
    "5000",
];

fn photon<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = PHOTON.to_vec();
    a.extend_from_slice(extra);
    a
}

#[test]
fn a_saved_photon_map_renders_the_traced_image_and_bad_maps_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(&photon(&["-o", "traced.pfm", "--save-photons", "map.phm"]), d);
    // `photons` traces and saves only, at any image size: the same file.
    let only = [
        "photons",
        "--quiet",
        "--photons",
        "5000",
        "--width",
        "8",
        "--save-photons",
        "only.phm",
    ];
    ok(&only, d);
    assert_eq!(read(d, "map.phm"), read(d, "only.phm"));
    assert!(!d.join("render.png").exists());
    // Loaded by workers rendering at other gather settings or in parts.
    ok(&photon(&["-o", "loaded.pfm", "--load-photons", "map.phm"]), d);
    assert!(
        read(d, "traced.pfm") == read(d, "loaded.pfm"),
        "loaded map renders differently"
    );
    ok(
        &photon(&["-o", "wide.pfm", "--gather-radius", "0.2", "--load-photons", "map.phm"]),
        d,
    );
    ok(&photon(&["-o", "wide-traced.pfm", "--gather-radius", "0.2"]), d);
    assert!(read(d, "wide.pfm") == read(d, "wide-traced.pfm"));

    let map = read(d, "map.phm");
    let mut flipped = map.clone();
    flipped[map.len() / 2] ^= 0x01;
    std::fs::write(d.join("flipped.phm"), &flipped).unwrap();
    std::fs::write(d.join("short.phm"), &map[..map.len() - 100]).unwrap();
    let bad = |file: &str, extra: &[&str], needle: &str| {
        let mut a = photon(&["-o", "bad.pfm", "--load-photons", file]);
        a.extend_from_slice(extra);
        refused(&a, d, file, needle);
        assert!(!d.join("bad.pfm").exists());
    };
    bad("flipped.phm", &[], "checksum");
    bad("short.phm", &[], "truncated");
    bad("map.phm", &["--max-bounces", "3"], "max_bounces=10");
    bad("map.phm", &["--seed", "1"], "other settings");
    bad("map.phm", &["--light-radius", "0.2"], "different scene");
    bad("render.pfm", &[], "no such file");
    refused(&["photons", "--quiet"], d, "--save-photons", "FILE");
    refused(
        &["--integrator", "path", "--quiet", "--load-photons", "map.phm"],
        d,
        "--load-photons",
        "photon integrator",
    );
    // Nothing left behind but the files written on purpose.
    let mut names: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "flipped.phm",
            "loaded.pfm",
            "map.phm",
            "only.phm",
            "short.phm",
            "traced.pfm",
            "wide-traced.pfm",
            "wide.pfm"
        ]
    );
}

const PATH: [&str; 10] = [
    "--quiet",
    "--integrator",
    "path",
    "--width",
    "48",
    "--height",
    "32",
    "--spp",
    "96",
    "--checkpoint-every",
];

#[test]
fn a_stopped_path_render_resumes_to_the_uninterrupted_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fn path<'a>(extra: &[&'a str]) -> Vec<&'a str> {
        let mut a = PATH.to_vec();
        a.push("0");
        a.extend_from_slice(extra);
        a
    }
    ok(&path(&["-o", "whole.pfm"]), d);
    let stopped = run(
        &path(&["-o", "r.exr", "--checkpoint", "r.ckpt", "--stop-after-passes", "7"]),
        d,
    );
    assert_eq!(stopped.status.code(), Some(130));
    // The partial image holds the passes done, and says so.
    let (_, _, attrs) = raytracer::image_io::read_exr_in_frame(&d.join("r.partial.exr")).unwrap();
    assert!(
        attrs.iter().any(|(k, v)| k == "raytracer.passes" && v == "7/24"),
        "{attrs:?}"
    );
    // Resumed on another thread count, from and to the same checkpoint file.
    let mut a = path(&[
        "-o",
        "r.exr",
        "--checkpoint",
        "r.ckpt",
        "--resume",
        "r.ckpt",
        "--threads",
        "1",
    ]);
    a.extend_from_slice(&["--stop-after-passes", "9"]);
    assert_eq!(run(&a, d).status.code(), Some(130));
    ok(&path(&["-o", "r.pfm", "--resume", "r.ckpt"]), d);
    assert!(read(d, "whole.pfm") == read(d, "r.pfm"), "resumed render differs");

    let ckpt = read(d, "r.ckpt");
    let mut flipped = ckpt.clone();
    flipped[ckpt.len() - 1000] ^= 0x40;
    std::fs::write(d.join("flipped.ckpt"), &flipped).unwrap();
    refused(
        &path(&["-o", "x.exr", "--resume", "flipped.ckpt"]),
        d,
        "flipped.ckpt",
        "checksum",
    );
    refused(
        &path(&["-o", "x.exr", "--resume", "r.ckpt", "--seed", "2"]),
        d,
        "r.ckpt",
        "other settings",
    );
    refused(
        &path(&["-o", "x.exr", "--resume", "r.ckpt", "--light-radius", "0.2"]),
        d,
        "r.ckpt",
        "different scene",
    );
    refused(
        &["--quiet", "-o", "x.exr", "--checkpoint", "c.ckpt"],
        d,
        "--checkpoint",
        "progressive",
    );
    refused(
        &[
            "--quiet",
            "--integrator",
            "path",
            "--checkpoint-every",
            "nan",
            "-o",
            "x.exr",
        ],
        d,
        "--checkpoint-every",
        "minutes",
    );
    assert!(!d.join("x.exr").exists());
}

#[test]
fn a_stopped_sppm_render_resumes_to_the_uninterrupted_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fn sppm<'a>(passes: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
        let mut a = vec![
            "--quiet",
            "--integrator",
            "sppm",
            "--width",
            "24",
            "--height",
            "24",
            "--photons",
            "3000",
            "--passes",
            passes,
            "--checkpoint-every",
            "0",
        ];
        a.extend_from_slice(extra);
        a
    }
    ok(&sppm("6", &["-o", "whole.pfm"]), d);
    // What --write-every writes after pass 4 of 6 is a 4-pass render.
    ok(&sppm("4", &["-o", "four.pfm"]), d);
    let stopped = run(
        &sppm(
            "6",
            &["-o", "r.pfm", "--checkpoint", "r.ckpt", "--stop-after-passes", "2"],
        ),
        d,
    );
    assert_eq!(stopped.status.code(), Some(130));
    assert!(d.join("r.partial.pfm").exists() && !d.join("r.pfm").exists());
    // Resumed on one thread, writing the image every 4 passes: pass 4 is
    // counted from the start of the render, not of this run.
    let resumed = run(
        &sppm(
            "6",
            &[
                "-o",
                "r.pfm",
                "--checkpoint",
                "r.ckpt",
                "--resume",
                "r.ckpt",
                "--threads",
                "1",
                "--write-every",
                "4",
                "--stop-after-passes",
                "3",
            ],
        ),
        d,
    );
    assert_eq!(resumed.status.code(), Some(130));
    assert!(read(d, "four.pfm") == read(d, "r.pfm"), "image after pass 4 differs");
    ok(&sppm("6", &["-o", "r.pfm", "--resume", "r.ckpt", "--threads", "2"]), d);
    assert!(read(d, "whole.pfm") == read(d, "r.pfm"), "resumed render differs");
    for (option, value) in [
        ("--alpha", "0.5"),
        ("--gather-radius", "0.2"),
        ("--max-bounces", "8"),
        ("--seed", "3"),
    ] {
        refused(
            &sppm("6", &["-o", "x.pfm", "--resume", "r.ckpt", option, value]),
            d,
            "r.ckpt",
            "other settings",
        );
    }
    refused(
        &sppm("7", &["-o", "x.pfm", "--resume", "r.ckpt"]),
        d,
        "r.ckpt",
        "other settings",
    );
    assert!(!d.join("x.pfm").exists());
}

#[test]
fn an_interruption_mid_pass_writes_a_checkpoint_that_resumes_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 16 tiles a pass, 16 passes of four samples. On one thread the interruption
    // (the cancel token a signal trips, here tripped by the hidden option)
    // lands after exactly 56 tiles: 3 passes done, the 4th half done.
    let args = |out: &'static str, extra: &[&'static str]| {
        let mut a = vec![
            "--quiet",
            "--integrator",
            "path",
            "--width",
            "64",
            "--height",
            "64",
            "--spp",
            "64",
            "--threads",
            "1",
            "-o",
            out,
        ];
        a.extend_from_slice(extra);
        a
    };
    let stopped = run(
        &args("s.pfm", &["--checkpoint", "s.ckpt", "--stop-after-tiles", "56"]),
        d,
    );
    let stderr = String::from_utf8_lossy(&stopped.stderr);
    assert_eq!(stopped.status.code(), Some(130), "{stderr}");
    assert_eq!(
        stderr.trim(),
        "interrupted: 3/16 passes rendered, saved to s.partial.pfm; checkpoint s.ckpt (continue with --resume)"
    );
    let mut names: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["s.ckpt", "s.partial.pfm"]);
    // The half-done pass left no trace: the checkpoint and the partial image
    // are those of a render stopped between passes 3 and 4.
    let between = run(
        &args("p.pfm", &["--checkpoint", "p.ckpt", "--stop-after-passes", "3"]),
        d,
    );
    assert_eq!(between.status.code(), Some(130));
    assert!(read(d, "s.ckpt") == read(d, "p.ckpt"), "checkpoints differ");
    assert!(
        read(d, "s.partial.pfm") == read(d, "p.partial.pfm"),
        "partial images differ"
    );
    // Resuming and stopping at once gives back the interrupted state exactly.
    let partial = read(d, "s.partial.pfm");
    let again = args("s.pfm", &["--resume", "s.ckpt", "--stop-after-passes", "0"]);
    assert_eq!(run(&again, d).status.code(), Some(130));
    assert!(partial == read(d, "s.partial.pfm"), "resumed state differs");
    // And resuming to the end gives the uninterrupted image.
    ok(&args("s.pfm", &["--resume", "s.ckpt"]), d);
    ok(&args("whole.pfm", &[]), d);
    assert!(read(d, "whole.pfm") == read(d, "s.pfm"), "resumed render differs");
}

#[test]
fn the_caustic_map_travels_with_the_global_map() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "--quiet",
            "--scene",
            "cornell-specular",
            "--width",
            "24",
            "--height",
            "24",
            "--ssaa",
            "1",
            "--photons",
            "3000",
        ];
        a.extend_from_slice(extra);
        if !extra.contains(&"--caustic-photons") {
            a.extend_from_slice(&["--caustic-photons", "3000"]);
        }
        a
    };
    ok(&args(&["-o", "traced.pfm", "--save-photons", "map.phm"]), d);
    ok(&args(&["-o", "loaded.pfm", "--load-photons", "map.phm"]), d);
    assert!(
        read(d, "traced.pfm") == read(d, "loaded.pfm"),
        "loaded maps render differently"
    );
    // Without its caustic map the image differs, so the loaded one was used.
    ok(&args(&["-o", "none.pfm", "--caustic-photons", "0"]), d);
    assert!(read(d, "traced.pfm") != read(d, "none.pfm"));
    refused(
        &args(&["-o", "bad.pfm", "--caustic-photons", "100", "--load-photons", "map.phm"]),
        d,
        "map.phm",
        "caustic_photons=3000",
    );
}
