//! The photon and path options through the binary: bad values are refused
//! with one line and exit status 2 before any work, and nothing is written.

use std::process::Command;

fn raytracer(args: &[&str], out: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(args)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn bad_photon_options_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    for (args, needle) in [
        (&["--gather-radius", "-1"][..], "--gather-radius"),
        (&["--gather-radius", "nan"][..], "--gather-radius"),
        (&["--gather-radius", "inf"][..], "--gather-radius"),
        (&["--gather-k", "0"][..], "--gather-k 0"),
        (&["--max-bounces", "0"][..], "--max-bounces"),
        (&["--photons", "1000000000000"][..], "GiB"),
        (
            &["--photons", "2000000000", "--max-bounces", "5"][..],
            "2000000000 photons x 5 bounces x 32 bytes",
        ),
        (&["--integrator", "path", "--spp", "0"][..], "--spp"),
        (&["--final-gather", "1000000"][..], "--final-gather"),
        (&["--gather-filter", "sideways"][..], "--gather-filter"),
        (&["--caustic-radius", "0"][..], "--caustic-radius"),
        (&["--caustic-radius", "-0.1"][..], "--caustic-radius"),
        (&["--passes", "8"][..], "--passes 8: only for integrator sppm"),
        (&["--integrator", "sppm", "--alpha", "0"][..], "--alpha"),
        (&["--integrator", "sppm", "--alpha", "1.5"][..], "--alpha"),
        (&["--integrator", "sppm", "--passes", "0"][..], "--passes"),
        (&["--integrator", "sppm", "--write-every", "0"][..], "--write-every"),
        (&["--integrator", "sppm", "--gather-k", "10"][..], "--gather-k"),
    ] {
        let o = raytracer(args, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote an image");
    }
}

#[test]
fn photon_and_path_integrators_render_small_images() {
    let dir = tempfile::tempdir().unwrap();
    for (name, args) in [
        ("direct-only.pfm", &["--integrator", "photon", "--photons", "0"][..]),
        (
            "photon.pfm",
            &["--photons", "20000", "--gather-k", "20", "--cone-filter"][..],
        ),
        (
            "gather.pfm",
            &["--photons", "20000", "--final-gather", "4", "--ssaa", "1"][..],
        ),
        (
            "path.pfm",
            &["--integrator", "path", "--spp", "3", "--max-depth", "3"][..],
        ),
    ] {
        let out = dir.path().join(name);
        let mut all = vec!["--width", "16", "--height", "16", "-q"];
        all.extend_from_slice(args);
        let o = raytracer(&all, &out);
        assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        let film = raytracer::image_io::read_image(&out).unwrap();
        assert!(film.pixels.iter().all(|p| p.is_finite() && p.min_element() >= 0.0));
        assert!(film.mean(0, 0, 16, 16).max_element() > 0.01, "{name} is black");
    }
}

#[test]
fn cornell_is_photon_mapped_with_its_preset_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let o = raytracer(&["--width", "8", "--height", "8"], &dir.path().join("x.png"));
    assert!(o.status.success());
    let (text, diag) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(diag.contains("photons: 1000000 emitted"), "{diag}");
    assert!(text.contains("Photon"), "{text}");
    // Command-line options override the preset.
    let o = raytracer(
        &["--width", "8", "--height", "8", "--integrator", "direct"],
        &dir.path().join("y.png"),
    );
    let (text, diag) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(!diag.contains("photons:") && text.contains("Direct"), "{text}");
}
