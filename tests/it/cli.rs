//! End-to-end tests through the binary: outputs, determinism, orientation,
//! soft shadows and bad input.

use raytracer::image_io::read_image;
use raytracer::Film;
use std::path::Path;
use std::process::{Command, Output};

fn raytracer(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the binary runs")
}

fn render_pfm(dir: &Path, name: &str, args: &[&str]) -> Film {
    let mut all = vec!["--quiet", "-o", name];
    all.extend_from_slice(args);
    let out = raytracer(&all, dir);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    read_image(&dir.join(name)).unwrap()
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn thread_count_does_not_change_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let common = ["--width", "96", "--height", "80", "--ssaa", "2", "--seed", "7"];
    let mut a = vec!["--threads", "1"];
    a.extend_from_slice(&common);
    let mut b = vec!["--threads", "2"];
    b.extend_from_slice(&common);
    render_pfm(dir.path(), "one.pfm", &a);
    render_pfm(dir.path(), "two.pfm", &b);
    let one = std::fs::read(dir.path().join("one.pfm")).unwrap();
    let two = std::fs::read(dir.path().join("two.pfm")).unwrap();
    assert!(one == two, "1-thread and 2-thread renders differ");
    // A different seed gives a different image (the seed is used at all).
    let mut c = vec!["--seed", "8"];
    c.extend_from_slice(&common[..6]);
    render_pfm(dir.path(), "seed.pfm", &c);
    assert!(std::fs::read(dir.path().join("seed.pfm")).unwrap() != one);
}

#[test]
fn default_render_has_the_walls_where_the_scene_says() {
    let dir = tempfile::tempdir().unwrap();
    let f = render_pfm(dir.path(), "o.pfm", &["--width", "64", "--height", "64", "--ssaa", "2"]);
    let (w, h) = (f.width, f.height);
    let band = 4;
    let left = f.mean(0, h / 4, band, 3 * h / 4);
    let right = f.mean(w - band, h / 4, w, 3 * h / 4);
    let top = f.mean(w / 4, 0, 3 * w / 4, band);
    let bottom = f.mean(w / 4, h - band, 3 * w / 4, h);
    // Purple: red and blue above green. Yellow: red and green above blue.
    assert!(left.x > 2.0 * left.y && left.z > 2.0 * left.y, "left {left:?}");
    assert!(right.x > 2.0 * right.z && right.y > 2.0 * right.z, "right {right:?}");
    assert!(top.y > 2.0 * top.x && top.z > 2.0 * top.x, "top {top:?}");
    assert!(
        bottom.y > 2.0 * bottom.x && bottom.y > 2.0 * bottom.z,
        "bottom {bottom:?}"
    );
}

#[test]
fn all_three_formats_are_written_and_agree() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["--quiet", "--width", "40", "--height", "30", "--ssaa", "1"];
    for name in ["a.png", "a.exr", "a.pfm"] {
        let mut v = args.to_vec();
        v.extend_from_slice(&["-o", name]);
        assert!(raytracer(&v, dir.path()).status.success());
    }
    assert_eq!(files_in(dir.path()), vec!["a.exr", "a.pfm", "a.png"]);
    let exr = read_image(&dir.path().join("a.exr")).unwrap();
    let pfm = read_image(&dir.path().join("a.pfm")).unwrap();
    assert_eq!(exr, pfm);
    let png = image::open(dir.path().join("a.png")).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (40, 30));
    // PNG is the sRGB encoding of the same radiance.
    let p = pfm.get(20, 25);
    let want = (raytracer::film::srgb_oetf(p.y.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8;
    assert_eq!(png.get_pixel(20, 25)[1], want);
}

#[test]
fn exposure_brightens_png_only() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["--quiet", "--width", "32", "--height", "32", "--ssaa", "1"];
    for (name, ev) in [
        ("dark.png", "-1"),
        ("bright.png", "1"),
        ("dark.pfm", "-1"),
        ("bright.pfm", "1"),
    ] {
        let mut v = args.to_vec();
        v.extend_from_slice(&["-o", name, "--exposure", ev]);
        assert!(raytracer(&v, dir.path()).status.success());
    }
    let sum = |n: &str| -> u64 {
        image::open(dir.path().join(n))
            .unwrap()
            .to_rgb8()
            .pixels()
            .map(|p| p[1] as u64)
            .sum()
    };
    assert!(sum("bright.png") > sum("dark.png"));
    assert_eq!(
        std::fs::read(dir.path().join("dark.pfm")).unwrap(),
        std::fs::read(dir.path().join("bright.pfm")).unwrap()
    );
}

/// Width in pixels of the shadow's edge along a floor scanline that runs from
/// the core of the short block's shadow out to the lit floor: the distance
/// between the points where luminance crosses 20% and 80% of the way from
/// the core to the lit level.
fn penumbra_width(f: &Film) -> usize {
    let y = f.height * 29 / 32;
    let lum: Vec<f32> = (0..f.width).map(|x| raytracer::math::luminance(f.get(x, y))).collect();
    let x0 = (f.width as f32 * 0.76) as usize;
    let x1 = (f.width as f32 * 0.95) as usize;
    let seg = &lum[x0..x1];
    let (core, lo) = seg
        .iter()
        .cloned()
        .enumerate()
        .fold((0, f32::MAX), |a, (i, l)| if l < a.1 { (i, l) } else { a });
    let hi = seg[core..].iter().cloned().fold(f32::MIN, f32::max);
    let cross = |frac: f32| {
        core + seg[core..]
            .iter()
            .position(|&l| l >= lo + frac * (hi - lo))
            .unwrap_or(0)
    };
    cross(0.8) - cross(0.2)
}

#[test]
fn penumbra_widens_with_light_radius() {
    let dir = tempfile::tempdir().unwrap();
    let common = [
        "--width",
        "256",
        "--height",
        "256",
        "--ssaa",
        "2",
        "--shadow-samples",
        "64",
        "--integrator",
        "direct",
    ];
    let mut widths = vec![];
    for r in ["0", "0.05", "0.2"] {
        let mut a = vec!["--light-radius", r];
        a.extend_from_slice(&common);
        let f = render_pfm(dir.path(), &format!("r{r}.pfm"), &a);
        widths.push(penumbra_width(&f));
        eprintln!("light radius {r}: penumbra {} px", widths.last().unwrap());
    }
    assert!(widths[0] <= 2, "point light shadow should be hard: {widths:?}");
    assert!(widths[1] > widths[0] && widths[2] > widths[1] + 2, "widths {widths:?}");
}

#[test]
fn point_light_is_not_visible_but_sphere_light_is() {
    let dir = tempfile::tempdir().unwrap();
    // The light at (0, -0.5, -0.7) projects to pixel (32, 16.8) of a 64x64 frame.
    let lit = render_pfm(dir.path(), "s.pfm", &["--width", "64", "--height", "64", "--ssaa", "2"]);
    assert!(lit.get(32, 17).x > 50.0, "{:?}", lit.get(32, 17));
    let point = render_pfm(
        dir.path(),
        "p.pfm",
        &["--width", "64", "--height", "64", "--ssaa", "2", "--light-radius", "0"],
    );
    assert!(point.get(32, 17).x < 5.0);
}

#[test]
fn bad_input_exits_2_with_one_line_and_no_file() {
    let cases: &[&[&str]] = &[
        &["--width", "0"],
        &["--height", "0"],
        &["--width", "100000"],
        &["--width", "30000", "--height", "30000"],
        &["--ssaa", "0"],
        &["--threads", "0"],
        &["--scene", "no-such-scene"],
        &["--light-radius", "-1"],
        &["--light-radius", "NaN"],
        &["--light-radius", "1e-20"],
        &["--exposure", "inf"],
        &["--width", "abc"],
        &["--no-such-option"],
        &["-o", "out.jpg"],
        &["-o", "missing-folder/out.png"],
    ];
    for case in cases {
        let dir = tempfile::tempdir().unwrap();
        let mut args = case.to_vec();
        if !case.contains(&"-o") {
            args.extend_from_slice(&["-o", "out.png"]);
        }
        let out = raytracer(&args, dir.path());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{case:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{case:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{case:?}: {stderr}");
        assert!(
            files_in(dir.path()).is_empty(),
            "{case:?} left {:?}",
            files_in(dir.path())
        );
    }
}

#[test]
fn a_missing_argument_is_named_on_the_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for (args, missing) in [
        (&["compare", "a.exr"][..], "<REFERENCE>"),
        (&["merge", "m.exr"][..], "<PARTS>"),
    ] {
        let out = raytracer(args, dir.path());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            stderr.contains("not provided") && stderr.contains(missing),
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn a_missing_scene_file_is_named_once_with_its_cause_once() {
    for name in ["absent.toml", "absent.pbrt"] {
        let dir = tempfile::tempdir().unwrap();
        let out = raytracer(&["--scene", name, "-o", "out.png"], dir.path());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(name), "{stderr}");
        // The OS's reason follows the name, and only once.
        let cause = stderr.split(&format!("{name}: ")).nth(1).unwrap_or("");
        let parts: Vec<&str> = cause.trim().split(": ").collect();
        assert!(!parts[0].is_empty(), "{stderr}");
        assert!(parts[1..].iter().all(|p| p != &parts[0]), "cause repeated: {stderr}");
        assert!(files_in(dir.path()).is_empty());
    }
}

#[test]
fn unknown_scene_lists_the_known_ones() {
    let dir = tempfile::tempdir().unwrap();
    let out = raytracer(&["--scene", "nope"], dir.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("nope") && stderr.contains("cornell"), "{stderr}");
}

#[test]
fn help_lists_options_with_defaults() {
    let out = raytracer(&["--help"], Path::new("."));
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for opt in [
        "--scene",
        "--output",
        "--width",
        "--height",
        "--ssaa",
        "--shadow-samples",
        "--light-radius",
        "--threads",
        "--seed",
        "--exposure",
        "--quiet",
        "--filter",
    ] {
        assert!(help.contains(opt), "--help lacks {opt}");
    }
    assert!(help.contains("[default: render.png]") && help.contains("[default: 0]"));
}

#[test]
fn summary_line_reports_size_samples_time_and_ray_rate() {
    let dir = tempfile::tempdir().unwrap();
    let out = raytracer(&["--width", "48", "--height", "32", "--ssaa", "3"], dir.path());
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(stdout.trim().lines().count(), 1, "{stdout}");
    assert!(
        stdout.contains("48x32") && stdout.contains("9 spp") && stdout.contains("Mrays/s"),
        "{stdout}"
    );
    // The default photon mapper's direct light takes the scene's shadow samples.
    assert!(stdout.contains(", 4 shadow samples,"), "{stdout}");
    assert!(dir.path().join("render.png").exists());
    // The path tracer takes one light sample a vertex: no count to report.
    let out = raytracer(
        &[
            "--width",
            "16",
            "--height",
            "16",
            "--integrator",
            "path",
            "--spp",
            "2",
            "-o",
            "path.png",
        ],
        dir.path(),
    );
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("2 spp, Path") && !stdout.contains("shadow"), "{stdout}");
}

#[test]
fn compare_reports_errors_and_writes_a_diff() {
    let dir = tempfile::tempdir().unwrap();
    let small = ["--width", "32", "--height", "32", "--ssaa", "1"];
    render_pfm(dir.path(), "a.pfm", &small);
    let mut b = small.to_vec();
    b.extend_from_slice(&["--seed", "3"]);
    render_pfm(dir.path(), "b.exr", &b);
    render_pfm(dir.path(), "c.pfm", &["--width", "24", "--height", "24", "--ssaa", "1"]);
    render_pfm(
        dir.path(),
        "half.pfm",
        &["--width", "16", "--height", "16", "--ssaa", "1"],
    );

    let same = raytracer(&["compare", "a.pfm", "a.pfm"], dir.path());
    let text = String::from_utf8_lossy(&same.stdout);
    assert!(
        text.contains("rmse 0.000000") && text.contains("luminance_ratio 1.0000"),
        "{text}"
    );

    let diff = raytracer(&["compare", "b.exr", "a.pfm", "--diff", "d.png"], dir.path());
    assert!(diff.status.success());
    let text = String::from_utf8_lossy(&diff.stdout);
    let rmse: f64 = text.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert!(rmse > 0.0, "{text}");
    assert_eq!(
        image::open(dir.path().join("d.png")).unwrap().to_rgb8().dimensions(),
        (32, 32)
    );

    // A reference twice the size is box-filtered down to the image's.
    // (The filtering itself is tested in `metrics`; one sample a pixel of a
    // visible light is too noisy here to say more than that it ran.)
    let half = raytracer(&["compare", "half.pfm", "a.pfm"], dir.path());
    assert!(half.status.success(), "{}", String::from_utf8_lossy(&half.stderr));
    assert!(String::from_utf8_lossy(&half.stdout).contains("luminance_ratio"));

    let mismatch = raytracer(&["compare", "c.pfm", "a.pfm"], dir.path());
    assert_eq!(mismatch.status.code(), Some(2));
    let missing = raytracer(&["compare", "nope.pfm", "a.pfm"], dir.path());
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("nope.pfm"));
}

#[test]
fn a_panic_on_a_worker_is_one_line_exit_101_and_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    // Two workers, nine tiles: the hidden option panics on a rayon worker
    // once two tiles are done, possibly on both workers at once.
    let out = raytracer(
        &[
            "--integrator",
            "direct",
            "--width",
            "96",
            "--height",
            "96",
            "--threads",
            "2",
            "--panic-after-tiles",
            "2",
            "-o",
            "out.exr",
        ],
        dir.path(),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(101), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("internal error: ") && stderr.contains("--panic-after-tiles 2") && stderr.contains(".rs:"),
        "{stderr}"
    );
    assert!(stderr.contains("bug") && !stderr.contains("panicked"), "{stderr}");
    assert!(files_in(dir.path()).is_empty(), "left {:?}", files_in(dir.path()));
}

#[test]
fn a_guide_where_nothing_brings_caustics_is_said_and_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["--integrator", "path", "--spp", "4", "--width", "24", "--height", "24"];
    let mut guided = vec!["-o", "guided.pfm", "--guide-photons", "1000"];
    guided.extend_from_slice(&args);
    let o = raytracer(&guided, dir.path());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: --guide-photons: no glossy or specular surface"),
        "{err}"
    );
    let plain = render_pfm(dir.path(), "plain.pfm", &args);
    assert_eq!(read_image(&dir.path().join("guided.pfm")).unwrap().pixels, plain.pixels);
    // Only the path tracer has a guide.
    let o = raytracer(&["-o", "photon.png", "--guide-photons", "1000"], dir.path());
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--guide-photons 1000: only for integrator path"), "{err}");
    assert!(!dir.path().join("photon.png").exists());
    // Where a glass ball brings caustics, the summary says what the guide took.
    let o = raytracer(
        &[
            "-o",
            "ball.pfm",
            "--scene",
            "cornell-specular",
            "--integrator",
            "path",
            "--spp",
            "1",
            "--width",
            "16",
            "--height",
            "16",
            "--guide-photons",
            "2000",
        ],
        dir.path(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let line = err.lines().find(|l| l.starts_with("guide: ")).unwrap_or_default();
    let stored: usize = line.split_whitespace().nth(1).and_then(|n| n.parse().ok()).unwrap_or(0);
    assert!(stored >= 2000 && line.contains("caustic photons of"), "{err}");
}
