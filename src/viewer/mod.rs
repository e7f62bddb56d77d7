//! `raytracer view`: an interactive preview window that refines the image
//! progressively while nothing moves.
//!
//! Three parts, one concept each: [`controller`] maps keys to camera and
//! light poses (plain functions, no window), [`progressive`] accumulates
//! samples pass by pass into the offline render's exact image, and `window`
//! (behind the `preview` cargo feature) runs the window and the render thread.

pub mod controller;
pub mod progressive;
#[cfg(feature = "preview")]
mod window;

use crate::error::{Error, Result};
use crate::integrator::RenderSettings;
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The key list shown by H.
pub const KEYS_HELP: &str =
    "arrows: walk/turn camera | W/S A/D Q/E: light forward/back left/right down/up | R: reset | P: save | H: help | Esc: quit";

/// How the window saves and shows pictures.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// Saved pictures are named after it: `view.png` gives `view-0001.png`
    /// and `view-0001.exr`, then `-0002`, skipping numbers already taken.
    pub output: PathBuf,
    /// Exposure in stops for the window and the saved PNG.
    pub exposure: f32,
    /// Print nothing on stdout.
    pub quiet: bool,
}

/// Whether the environment names a display to open a window on.
pub fn display_available() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// Opens the preview window on `scene` and runs it until it is closed.
pub fn run(scene: Scene, settings: RenderSettings, options: ViewOptions) -> Result<()> {
    crate::integrator::check_scene(&scene, settings.integrator)?;
    if !display_available() {
        return Err(Error::Window(
            "no display to open a window on (DISPLAY and WAYLAND_DISPLAY are unset); render to a file instead".into(),
        ));
    }
    #[cfg(feature = "preview")]
    {
        window::run(scene, settings, options)
    }
    #[cfg(not(feature = "preview"))]
    {
        let _ = (scene, settings, options);
        Err(Error::Window(
            "this raytracer was built without the preview window (cargo feature `preview`)".into(),
        ))
    }
}

/// The PNG and EXR paths of saved picture number `n`.
pub fn numbered_paths(output: &Path, n: u32) -> (PathBuf, PathBuf) {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "view".into());
    let base = output.with_file_name(format!("{stem}-{n:04}"));
    (base.with_extension("png"), base.with_extension("exr"))
}

/// The first picture number from `from` on whose PNG and EXR are both free.
pub fn next_free_number(output: &Path, from: u32) -> u32 {
    let mut n = from.max(1);
    loop {
        let (png, exr) = numbered_paths(output, n);
        if !png.exists() && !exr.exists() {
            return n;
        }
        n += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saved_pictures_are_numbered_beside_the_output_name() {
        let (png, exr) = numbered_paths(Path::new("out/shot.png"), 7);
        assert_eq!(png, PathBuf::from("out/shot-0007.png"));
        assert_eq!(exr, PathBuf::from("out/shot-0007.exr"));
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("view.png");
        assert_eq!(next_free_number(&out, 1), 1);
        std::fs::write(dir.path().join("view-0001.exr"), b"").unwrap();
        std::fs::write(dir.path().join("view-0002.png"), b"").unwrap();
        assert_eq!(next_free_number(&out, 1), 3);
    }
}
