//! Rendering a frame in parts (crops and bands, as separate processes) and
//! merging them gives the single render, byte for byte.

use std::path::Path;
use std::process::{Command, Output};

const SIZE: [&str; 6] = ["--width", "72", "--height", "56", "--ssaa", "2"];

fn run(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(args)
        .current_dir(dir)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_ARRAY_TASK_COUNT")
        .env_remove("JOB_COMPLETION_INDEX")
        .output()
        .unwrap()
}

fn render(dir: &Path, out: &str, extra: &[&str]) {
    let mut a = vec!["--quiet", "-o", out];
    a.extend_from_slice(&SIZE);
    a.extend_from_slice(extra);
    let o = run(&a, dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn bands_rendered_by_separate_processes_merge_to_the_full_render() {
    let dir = tempfile::tempdir().unwrap();
    render(dir.path(), "full.pfm", &[]);
    // One process per band, all running at once, as a scheduler would start them.
    let children: Vec<_> = (0..3)
        .map(|i| {
            let tile = format!("{i}/3");
            let out = format!("band{i}.exr");
            let mut a = vec![
                "--quiet".to_string(),
                "-o".into(),
                out,
                "--tile".into(),
                tile,
                "--threads".into(),
                "1".into(),
            ];
            a.extend(SIZE.iter().map(|s| s.to_string()));
            Command::new(env!("CARGO_BIN_EXE_raytracer"))
                .args(&a)
                .current_dir(dir.path())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut c in children {
        assert!(c.wait().unwrap().success());
    }
    let o = run(
        &["merge", "merged.pfm", "band2.exr", "band0.exr", "band1.exr"],
        dir.path(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let full = std::fs::read(dir.path().join("full.pfm")).unwrap();
    assert!(
        full == std::fs::read(dir.path().join("merged.pfm")).unwrap(),
        "merged bands differ"
    );
}

#[test]
fn splatting_filters_stitch_crops_exactly() {
    // A tent or Gaussian spreads each sample over neighbouring pixels, so a
    // crop's edge needs the samples of the pixels beyond it. The Z-order
    // sampler's points depend on the pixel's place in the frame, not in the crop.
    let dir = tempfile::tempdir().unwrap();
    for (filter, sampler) in [("tent", "sobol"), ("gaussian", "sobol"), ("tent", "zsobol")] {
        let common = [
            "--integrator",
            "path",
            "--spp",
            "3",
            "--filter",
            filter,
            "--sampler",
            sampler,
        ];
        let full = format!("full-{filter}-{sampler}.pfm");
        render(dir.path(), &full, &common);
        let mut names = vec![];
        for (i, crop) in ["0,0,33,30", "33,0,72,30", "0,30,33,56", "33,30,72,56"]
            .iter()
            .enumerate()
        {
            let name = format!("{filter}-{sampler}{i}.exr");
            let mut a = common.to_vec();
            a.extend(["--crop", crop, "--threads", "1"]);
            render(dir.path(), &name, &a);
            names.push(name);
        }
        let merged = format!("merged-{filter}-{sampler}.pfm");
        let mut a = vec!["merge", merged.as_str()];
        a.extend(names.iter().map(String::as_str));
        let o = run(&a, dir.path());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            std::fs::read(dir.path().join(&full)).unwrap() == std::fs::read(dir.path().join(&merged)).unwrap(),
            "{filter}, {sampler}: merged crops differ from the full render"
        );
    }
}

#[test]
fn crops_merge_to_the_full_render_and_bad_sets_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    render(dir.path(), "full.pfm", &[]);
    for (name, crop) in [
        ("a.exr", "0,0,40,30"),
        ("b.exr", "40,0,72,30"),
        ("c.exr", "0,30,40,56"),
        ("d.exr", "40,30,72,56"),
    ] {
        render(dir.path(), name, &["--crop", crop]);
    }
    let o = run(&["merge", "merged.pfm", "a.exr", "b.exr", "c.exr", "d.exr"], dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let full = std::fs::read(dir.path().join("full.pfm")).unwrap();
    assert!(
        full == std::fs::read(dir.path().join("merged.pfm")).unwrap(),
        "merged crops differ"
    );

    render(dir.path(), "overlap.exr", &["--crop", "30,0,72,30"]);
    let gap = run(&["merge", "x.exr", "a.exr", "c.exr", "d.exr"], dir.path());
    assert_eq!(gap.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&gap.stderr).contains("gap"));
    let overlap = run(
        &["merge", "x.exr", "a.exr", "overlap.exr", "c.exr", "d.exr"],
        dir.path(),
    );
    assert_eq!(overlap.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&overlap.stderr).contains("overlap"));
    assert!(!dir.path().join("x.exr").exists());
    // The output may not be one of the parts, however it is named.
    let a = std::fs::read(dir.path().join("a.exr")).unwrap();
    let onto = run(&["merge", "./a.exr", "a.exr", "b.exr", "c.exr", "d.exr"], dir.path());
    assert_eq!(onto.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&onto.stderr).contains("is one of the parts"));
    assert_eq!(std::fs::read(dir.path().join("a.exr")).unwrap(), a);

    let mut other = vec![
        "--quiet",
        "-o",
        "other.exr",
        "--width",
        "80",
        "--height",
        "56",
        "--crop",
        "40,0,80,30",
    ];
    other.extend_from_slice(&["--ssaa", "1"]);
    assert!(run(&other, dir.path()).status.success());
    let mismatch = run(&["merge", "x.exr", "a.exr", "other.exr", "c.exr", "d.exr"], dir.path());
    assert_eq!(mismatch.status.code(), Some(2));

    for bad in [
        ["--crop", "0,0,100,10"],
        ["--crop", "1,2"],
        ["--tile", "3/3"],
        ["--tile", "auto"],
    ] {
        let mut a = vec!["-o", "bad.exr"];
        a.extend_from_slice(&SIZE);
        a.extend_from_slice(&bad);
        let o = run(&a, dir.path());
        assert_eq!(o.status.code(), Some(2), "{bad:?}");
        assert!(!dir.path().join("bad.exr").exists());
    }
}

#[test]
fn an_interrupted_render_leaves_a_valid_partial_exr_and_no_temporary_files() {
    let dir = tempfile::tempdir().unwrap();
    // 8 x 6 tiles; on one thread the interruption (the cancel token a
    // signal trips, here tripped by the hidden option) lands after exactly 6,
    // the first six of the top row.
    let o = run(
        &[
            "--quiet",
            "-o",
            "big.exr",
            "--width",
            "128",
            "--height",
            "96",
            "--ssaa",
            "2",
            "--threads",
            "1",
            // Few photons: the photon pass is not what this is about.
            "--photons",
            "20000",
            "--stop-after-tiles",
            "6",
        ],
        dir.path(),
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.trim() == "interrupted: 6/48 tiles rendered, saved to big.partial.exr",
        "{stderr}"
    );
    let files: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(files, vec!["big.partial.exr".to_string()]);
    let (film, window, attrs) = raytracer::image_io::read_exr_in_frame(&dir.path().join("big.partial.exr")).unwrap();
    assert_eq!((film.width, window.full_width, window.full_height), (128, 128, 96));
    for (key, value) in [("raytracer.partial", "true"), ("raytracer.tiles", "6/48")] {
        assert!(attrs.iter().any(|(k, v)| k == key && v == value), "{attrs:?}");
    }
    // Those six were finished and the other 42 are black; of the six, the
    // first sees no room (the frame's outer columns of tiles lie beside the
    // box) and the other five are lit.
    let lit: Vec<u32> = (0..48)
        .filter(|t| {
            let (x0, y0) = (t % 8 * 16, t / 8 * 16);
            (y0..y0 + 16).any(|y| (x0..x0 + 16).any(|x| film.get(x, y).max_element() > 0.0))
        })
        .collect();
    assert_eq!(lit, [1, 2, 3, 4, 5]);
}
