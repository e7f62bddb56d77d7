//! `raytracer view` end to end: without a display it refuses in one line;
//! under Xvfb it opens, takes keys from xdotool, saves with P, and the saved
//! pictures follow the moved light. The window test skips, saying why, where
//! Xvfb or xdotool is missing or the build has no `preview` feature; under CI
//! (`CI` set) missing Xvfb or xdotool fails it instead.

use raytracer::image_io::read_image;
use raytracer::math::luminance;
use raytracer::Film;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Generous: the machine may be busy; these only bound a hang.
const WINDOW_TIMEOUT: Duration = Duration::from_secs(60);
const RENDER_TIMEOUT: Duration = Duration::from_secs(180);
/// Small, so the window finishes refining in a moment.
const SIZE_AND_SAMPLES: [&str; 8] = [
    "--width",
    "96",
    "--height",
    "72",
    "--ssaa",
    "2",
    "--shadow-samples",
    "2",
];

#[test]
fn view_without_a_display_exits_2_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(["view", "--width", "16", "--height", "16"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("display"), "{err}");
    assert!(out.stdout.is_empty());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing is written");
}

#[test]
fn view_on_a_display_that_cannot_be_opened_exits_2_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(["view", "--width", "16", "--height", "16"])
        .env("DISPLAY", ":54321")
        .env_remove("WAYLAND_DISPLAY")
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: view: "), "{err}");
}

/// Says why the window test skips; under CI (`CI` set), where `.ci/run`
/// installs Xvfb and xdotool, fails it instead.
fn skip_unless_ci(why: &str) {
    if std::env::var_os("CI").is_some() {
        panic!("{why}: under CI (CI is set) the window test must run");
    }
    println!("skipped: {why}");
}

fn on_path(tool: &str) -> bool {
    std::env::var_os("PATH")
        .map(|p| std::env::split_paths(&p).any(|d| d.join(tool).is_file()))
        .unwrap_or(false)
}

/// A child process killed when the test ends, pass or fail.
struct Guard(Child);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts Xvfb on a free display it picks itself; returns it and ":N".
fn start_xvfb() -> Option<(Guard, String)> {
    let mut child = Command::new("Xvfb")
        // -noreset: by default the server resets when its last client
        // leaves, and a client connecting during the reset (the viewer,
        // right after the probe below) is refused: "XOpenDisplay failed".
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "640x480x24",
            "-nolisten",
            "tcp",
            "-noreset",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    let mut line = String::new();
    BufReader::new(child.stdout.take()?).read_line(&mut line).ok()?;
    let n: u32 = line.trim().parse().ok()?;
    Some((Guard(child), format!(":{n}")))
}

fn xdotool(display: &str, args: &[&str]) -> Option<String> {
    let out = Command::new("xdotool")
        .args(args)
        .env("DISPLAY", display)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn wait_for(timeout: Duration, mut ok: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < timeout {
        if ok() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    false
}

struct Session {
    display: String,
    window: String,
    dir: PathBuf,
    log: PathBuf,
}

impl Session {
    fn title(&self) -> String {
        xdotool(&self.display, &["getwindowname", &self.window]).unwrap_or_default()
    }

    fn key(&self, keys: &[&str]) {
        let mut args = vec!["key", "--delay", "30"];
        args.extend_from_slice(keys);
        assert!(xdotool(&self.display, &args).is_some(), "xdotool key {keys:?} failed");
    }

    fn fail(&self, what: &str) -> ! {
        let log = std::fs::read_to_string(&self.log).unwrap_or_default();
        panic!("{what}; title '{}'; output: {log}", self.title());
    }

    /// Waits until the window shows the finished image of pose `pose`.
    fn wait_done(&self, pose: u32) {
        let want = format!("| pose {pose} |");
        if !wait_for(RENDER_TIMEOUT, || {
            let t = self.title();
            t.contains(&want) && t.contains("done")
        }) {
            self.fail(&format!("pose {pose} never finished"));
        }
    }

    /// Presses P and returns picture `n` once both its files are there.
    fn save(&self, n: u32) -> Film {
        self.key(&["p"]);
        let png = self.dir.join(format!("view-{n:04}.png"));
        let exr = self.dir.join(format!("view-{n:04}.exr"));
        if !wait_for(WINDOW_TIMEOUT, || png.is_file() && exr.is_file()) {
            self.fail(&format!("picture {n} was not saved"));
        }
        let img = image::open(&png).unwrap().to_rgb8();
        let film = read_image(&exr).unwrap();
        assert_eq!(img.dimensions(), (film.width, film.height));
        film
    }
}

/// Mean luminance of the left and right thirds.
fn left_right(f: &Film) -> (f32, f32) {
    let third = f.width / 3;
    (
        luminance(f.mean(0, 0, third, f.height)),
        luminance(f.mean(f.width - third, 0, f.width, f.height)),
    )
}

#[test]
fn view_under_xvfb_saves_and_follows_the_light() {
    if !cfg!(feature = "preview") {
        println!("skipped: built without the `preview` feature");
        return;
    }
    if !on_path("Xvfb") || !on_path("xdotool") {
        return skip_unless_ci("Xvfb and xdotool are needed (apt-get install xvfb xdotool)");
    }
    let Some((_xvfb, display)) = start_xvfb() else {
        return skip_unless_ci("Xvfb did not start");
    };
    // Once in a CI run the viewer found no server behind the display Xvfb had
    // just announced; a client that gets an answer first tells a server that
    // is slow to accept (waited for) from one that died (a clear failure).
    if !wait_for(Duration::from_secs(20), || {
        xdotool(&display, &["getdisplaygeometry"]).is_some()
    }) {
        panic!("Xvfb announced display {display} but accepts no client");
    }
    let dir = tempfile::tempdir().unwrap();
    let logs = tempfile::tempdir().unwrap();
    let log = logs.path().join("view.log");
    let logfile = std::fs::File::create(&log).unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .arg("view")
        .args(SIZE_AND_SAMPLES)
        .env("DISPLAY", &display)
        .env_remove("WAYLAND_DISPLAY")
        .current_dir(dir.path())
        .stdout(logfile.try_clone().unwrap())
        .stderr(logfile)
        .spawn()
        .unwrap();
    let mut view = Guard(child);
    let mut window = None;
    let found = wait_for(WINDOW_TIMEOUT, || {
        window = xdotool(&display, &["search", "--name", "raytracer view"])
            .and_then(|s| s.lines().next().map(str::to_string));
        window.is_some()
    });
    let s = Session {
        display: display.clone(),
        window: window.unwrap_or_default(),
        dir: dir.path().to_path_buf(),
        log: log.clone(),
    };
    if !found {
        s.fail("no window appeared");
    }
    assert!(xdotool(&display, &["windowfocus", "--sync", &s.window]).is_some());

    s.wait_done(0);
    let first = s.save(1);
    // Refined to the end, the window holds the offline render exactly: the
    // default scene renders with photon mapping, so the preview's photon map
    // must be the offline one, photon for photon.
    let offline = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(["-q", "-o", "offline.exr"])
        .args(SIZE_AND_SAMPLES)
        .current_dir(logs.path())
        .status()
        .unwrap();
    assert!(offline.success());
    assert_eq!(first, read_image(&logs.path().join("offline.exr")).unwrap());

    // Three presses of D move the light towards the picture's right.
    s.key(&["d", "d", "d"]);
    s.wait_done(3);
    let moved = s.save(2);
    let (l1, r1) = left_right(&first);
    let (l2, r2) = left_right(&moved);
    assert!(r2 > r1 * 1.05, "right side did not brighten: {r1} -> {r2}");
    assert!(
        r2 - l2 > (r1 - l1) + 0.02,
        "balance did not move right: {l1} {r1} -> {l2} {r2}"
    );

    // H shows the key list in the title, and hides it again.
    s.key(&["h"]);
    assert!(wait_for(WINDOW_TIMEOUT, || s.title().contains("Esc: quit")));
    s.key(&["h"]);
    assert!(wait_for(WINDOW_TIMEOUT, || s.title().contains("| pose 3 |")));

    // Walking forward changes the picture; R brings back the first one exactly.
    s.key(&["Up"]);
    s.wait_done(4);
    let walked = s.save(3);
    assert_ne!(walked, first);
    s.key(&["r"]);
    s.wait_done(5);
    assert_eq!(s.save(4), first, "R restores the initial camera and light");

    // Esc quits cleanly.
    s.key(&["Escape"]);
    let mut status = None;
    wait_for(WINDOW_TIMEOUT, || {
        status = view.0.try_wait().ok().flatten();
        status.is_some()
    });
    match status {
        Some(st) => assert!(st.success(), "view exited with {st}"),
        None => s.fail("Esc did not quit"),
    }
    let log_text = std::fs::read_to_string(Path::new(&log)).unwrap();
    assert!(log_text.contains("saved view-0004.png and view-0004.exr"), "{log_text}");
}
