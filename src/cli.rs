//! Command-line interface: option definitions (with their defaults, which
//! `--help` shows) and their validation into library settings.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use raytracer::film::PixelRect;
use raytracer::integrator::{IntegratorKind, RenderSettings, StateFiles};
use raytracer::scene::{LoadOptions, LoadedScene};
use raytracer::settings::{Kind, Layer, Layers, Origin, SETTINGS};
use std::path::PathBuf;

use raytracer::limits::{MAX_PIXELS, MAX_SIDE};

#[derive(Parser, Debug)]
#[command(
    name = "raytracer",
    version,
    about = "A physically based CPU ray tracer built around photon mapping",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub render: RenderArgs,
}

// Parsed once per run: the size of the render options in `View` costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Print statistics of a scene: triangles, spheres and disks, lights by kind, materials, BVH nodes, depth, leaf sizes, SAH cost, build time, memory.
    Info(SceneArgs),
    /// Compare two linear images (EXR or PFM): RMSE, relative MSE, mean luminance ratio.
    Compare(CompareArgs),
    /// Assemble EXR parts rendered with --crop or --tile into the whole frame.
    Merge(MergeArgs),
    /// Open an interactive preview window that refines the image while nothing moves (press H for the keys).
    View(ViewArgs),
    /// Trace the photon map of a scene and save it (--save-photons FILE) for renders that --load-photons it.
    Photons(PhotonsArgs),
}

/// `photons` takes the render options (those that decide the map count) and needs --save-photons.
#[derive(Args, Debug, Clone)]
pub struct PhotonsArgs {
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Args, Debug, Clone)]
pub struct MergeArgs {
    /// The merged image (.exr, .pfm or .png).
    pub output: PathBuf,
    /// The parts (.exr files written with --crop or --tile).
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
}

#[derive(Args, Debug, Clone)]
pub struct CompareArgs {
    /// The image to judge (.exr or .pfm).
    pub image: PathBuf,
    /// The reference image (.exr or .pfm).
    pub reference: PathBuf,
    /// Write a false-colour picture of the relative error to this PNG.
    #[arg(long, value_name = "PNG")]
    pub diff: Option<PathBuf>,
    /// Relative error shown as full red in the --diff picture.
    #[arg(long, default_value_t = 0.5)]
    pub diff_scale: f32,
    /// Leave out pixels whose reference luminance is above this (a visible
    /// light, say), so they do not dominate the figures.
    #[arg(long, value_name = "L")]
    pub max_luminance: Option<f32>,
}

/// `view` takes the render options; `--output` names the pictures P saves:
/// `view.png` gives `view-0001.png` and `view-0001.exr`, then `-0002`, ...
#[derive(Args, Debug, Clone)]
#[command(mut_arg("output", |a| a
    .default_value("view.png")
    .help("Name for pictures saved with P: NAME.png saves NAME-0001.png and NAME-0001.exr, then -0002, ...")))]
pub struct ViewArgs {
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// Built-in scene (cornell, cornell-bunny, cornell-final, cornell-specular), a TOML scene file (a path ending
    /// in .toml, or any existing file that is not a built-in name) or a pbrt-v4 scene (.pbrt, .pbrt.gz).
    #[arg(long, default_value = "cornell", value_name = "NAME|FILE")]
    pub scene: String,
    /// Mesh file (.obj or .ply): the Stanford bunny for cornell-bunny and cornell-final, or a replacement for the
    /// path of a scene file's mesh [default: none; the scene file's own path].
    #[arg(long, value_name = "PATH")]
    pub mesh: Option<PathBuf>,
    /// Smooth-shade meshes with their vertex normals when the file has them [default: off, flat shading].
    #[arg(long)]
    pub smooth: bool,
    /// pbrt-v4 scenes: render despite unsupported features (unknown materials become grey diffuse, unsupported
    /// shapes and lights are skipped), with a warning per kind [default: off, such a scene is refused].
    #[arg(long)]
    pub lenient: bool,
}

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output image; the extension picks the format: .png (8-bit sRGB), .exr or .pfm (linear radiance).
    #[arg(short, long, default_value = "render.png")]
    pub output: PathBuf,
    /// Image width in pixels; given alone, the height follows the scene's aspect ratio [default: the scene's: 512
    /// for cornell and cornell-bunny, 600 for cornell-final].
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels; given alone, the width follows the scene's aspect ratio [default: the scene's: 512
    /// for cornell and cornell-bunny, 600 for cornell-final].
    #[arg(long)]
    pub height: Option<u32>,
    /// Radius of the sphere light, overriding the scene's; 0 makes it a point light (hard shadows) [default: the
    /// scene's: 0.1 for cornell, 0.02 for cornell-final].
    #[arg(long, value_name = "R", allow_negative_numbers = true)]
    pub light_radius: Option<f32>,
    #[command(flatten)]
    pub settings: SettingArgs,
    /// SPPM: also write the image so far to --output every K passes.
    #[arg(long, value_name = "K")]
    pub write_every: Option<u32>,
    /// Exposure in stops applied to PNG output (linear outputs hold radiance).
    #[arg(long, value_name = "EV", default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// Render only the pixel rectangle [X0, X1) x [Y0, Y1) of the frame; EXR output records its place.
    #[arg(long, value_name = "X0,Y0,X1,Y1", conflicts_with = "tile")]
    pub crop: Option<String>,
    /// Render the I-th (from 0) of N horizontal bands of the frame; `auto/N` (or `auto` with
    /// SLURM_ARRAY_TASK_COUNT set) takes I from SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX.
    #[arg(long, value_name = "I/N")]
    pub tile: Option<String>,
    /// Print nothing (no progress bar, no summary, no warnings) [default: off].
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub files: StateFileArgs,
}

/// The render settings of the library's table (`raytracer::settings`), one
/// option each, with the table's doc and default: declared there, not here.
#[derive(Debug, Clone, Default)]
pub struct SettingArgs {
    /// (setting, text) for each setting typed on the command line.
    pub given: Vec<(&'static str, String)>,
}

impl SettingArgs {
    /// Sets a setting as if typed (e.g. `photons` makes the integrator photon).
    pub fn force(&mut self, name: &'static str, text: &str) {
        self.given.retain(|(n, _)| *n != name);
        self.given.push((name, text.to_string()));
    }

    /// The settings typed, checked against the table.
    pub fn layer(&self) -> Result<Layer> {
        let mut layer = Layer::default();
        for (name, text) in &self.given {
            layer.set_text(name, text, Origin::CommandLine)?;
        }
        Ok(layer)
    }
}

impl clap::FromArgMatches for SettingArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> std::result::Result<Self, clap::Error> {
        let mut s = SettingArgs::default();
        s.update_from_arg_matches(m)?;
        Ok(s)
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> std::result::Result<(), clap::Error> {
        for spec in SETTINGS {
            if let Some(text) = m.get_one::<String>(spec.name) {
                self.force(spec.name, text);
            }
        }
        Ok(())
    }
}

impl clap::Args for SettingArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        SETTINGS.iter().fold(cmd, |cmd, spec| {
            let mut arg = clap::Arg::new(spec.name)
                .long(spec.flag().trim_start_matches('-').to_string())
                .help(if spec.in_scene_file {
                    format!("{} [default: the scene's, else {}]", spec.doc, spec.default.describe())
                } else {
                    format!("{} [default: {}]", spec.doc, spec.default.describe())
                })
                .allow_negative_numbers(true)
                .action(clap::ArgAction::Set);
            arg = match spec.kind {
                Kind::Count { .. } => arg.value_name("N"),
                Kind::Real { .. } => arg.value_name("X"),
                Kind::Flag => arg.value_name("BOOL").num_args(0..=1).default_missing_value("true"),
                Kind::Choice(names) => arg
                    .value_name("NAME")
                    .value_parser(clap::builder::PossibleValuesParser::new(names)),
            };
            cmd.arg(arg)
        })
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

/// Files that carry work between runs (photon maps, checkpoints).
#[derive(Args, Debug, Clone)]
pub struct StateFileArgs {
    /// Photon integrator: write the traced photon map to FILE, for renders that --load-photons it.
    #[arg(long, value_name = "FILE", conflicts_with = "load_photons")]
    pub save_photons: Option<PathBuf>,
    /// Photon integrator: read the photon map from FILE (written by --save-photons for the same scene, --photons,
    /// --max-bounces and --seed) instead of tracing it.
    #[arg(long, value_name = "FILE")]
    pub load_photons: Option<PathBuf>,
    /// Progressive renders (--integrator path, bdpt or sppm): save the render's state to FILE between passes, every
    /// --checkpoint-every minutes and when interrupted; --resume FILE continues it.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Minutes between checkpoints (fractions allowed).
    #[arg(long, value_name = "MINUTES", default_value_t = 5.0)]
    pub checkpoint_every: f64,
    /// Continue the render saved in FILE by --checkpoint (same scene and settings); the image is the one an
    /// uninterrupted render gives.
    #[arg(long, value_name = "FILE")]
    pub resume: Option<PathBuf>,
    /// Stop as if interrupted after this many passes (for tests).
    #[arg(long, value_name = "N", hide = true)]
    pub stop_after_passes: Option<u32>,
    /// Stop as if interrupted once this many tiles are done (for tests).
    #[arg(long, value_name = "N", hide = true)]
    pub stop_after_tiles: Option<u64>,
    /// Panic on a worker thread once this many tiles are done (for tests of the panic report).
    #[arg(long, value_name = "N", hide = true)]
    pub panic_after_tiles: Option<u64>,
}

/// Checks the state-file options (the library checks them against the integrator).
fn state_files(args: &StateFileArgs) -> Result<StateFiles> {
    let minutes = args.checkpoint_every;
    let every = std::time::Duration::try_from_secs_f64(minutes * 60.0).map_err(|_| {
        anyhow::anyhow!("--checkpoint-every {minutes:?}: must be a number of minutes >= 0, at most a few centuries")
    })?;
    for (name, given) in [
        ("--save-photons", &args.save_photons),
        ("--checkpoint", &args.checkpoint),
    ] {
        if let Some(p) = given {
            raytracer::image_io::check_file_writable(name, p)?;
        }
    }
    for (name, given) in [("--load-photons", &args.load_photons), ("--resume", &args.resume)] {
        if let Some(p) = given.as_ref().filter(|p| !p.is_file()) {
            bail!("{name} {}: no such file", p.display());
        }
    }
    Ok(StateFiles {
        save_photons: args.save_photons.clone(),
        load_photons: args.load_photons.clone(),
        checkpoint: args.checkpoint.clone(),
        checkpoint_every: every,
        resume: args.resume.clone(),
        stop_after_passes: args.stop_after_passes,
    })
}

/// Resolves `--scene`, `--mesh` and `--smooth` to a description.
pub fn load_scene(args: &SceneArgs) -> Result<LoadedScene> {
    let opts = LoadOptions {
        mesh: args.mesh.clone(),
        smooth: args.smooth,
        lenient: args.lenient,
    };
    Ok(raytracer::scene::load(&args.scene, &opts)?)
}

/// Checks every option and applies it to the scene, before any work starts.
pub fn prepare(args: &RenderArgs) -> Result<(LoadedScene, RenderSettings)> {
    let prepared = prepare_settings(args)?;
    raytracer::image_io::check_writable(&args.output).context("cannot write the output")?;
    Ok(prepared)
}

/// [`prepare`] for commands that write no image.
pub fn prepare_settings(args: &RenderArgs) -> Result<(LoadedScene, RenderSettings)> {
    let mut loaded = load_scene(&args.scene)?;
    let (w, h) = (loaded.desc.camera.width, loaded.desc.camera.height);
    // One side given: the other keeps the scene's aspect ratio, so that a
    // smaller render of a 1280 x 720 file is the same picture at 320 x 180.
    let follow = |side: u32, new: u32, old: u32| -> u32 {
        if old == 0 {
            return side;
        }
        let scaled = (side as u64 * new as u64 + old as u64 / 2) / old as u64;
        scaled.clamp(1, u32::MAX as u64) as u32
    };
    let (width, height) = match (args.width, args.height) {
        (Some(nw), None) => (nw, follow(h, nw, w)),
        (None, Some(nh)) => (follow(w, nh, h), nh),
        (nw, nh) => (nw.unwrap_or(w), nh.unwrap_or(h)),
    };
    loaded.set_resolution(width, height);
    let file_crop = loaded.crop_rect();
    let desc = &mut loaded.desc;
    let (w, h) = (desc.camera.width, desc.camera.height);
    for (name, v) in [("--width", w), ("--height", h)] {
        if v == 0 || v > MAX_SIDE {
            bail!("{name} {v}: must be between 1 and {MAX_SIDE}");
        }
    }
    if w as u64 * h as u64 > MAX_PIXELS {
        bail!(
            "--width {w} --height {h}: {} pixels exceed the limit of {MAX_PIXELS}",
            w as u64 * h as u64
        );
    }
    let pixels = w as u64 * h as u64;
    raytracer::limits::check_memory(
        &format!("a {w}x{h} image"),
        raytracer::limits::film_bytes(pixels),
        8 << 30,
    )?;
    if !args.exposure.is_finite() {
        bail!("--exposure {}: must be a finite number", args.exposure);
    }
    if let Some(r) = args.light_radius {
        if !(r.is_finite() && r >= 0.0) {
            bail!("--light-radius {r}: must be a finite number >= 0");
        }
        desc.set_light_radius(r);
        for l in &desc.lights {
            l.check(1.0).map_err(|m| anyhow::anyhow!("--light-radius {r}: {m}"))?;
        }
    }
    let crop = match (&args.crop, &args.tile) {
        (Some(c), _) => Some(parse_crop(c, w, h)?),
        (None, Some(t)) => Some(parse_tile(t, w, h, |k| std::env::var(k).ok())?),
        (None, None) => match file_crop {
            Some(Some(r)) => Some(r),
            Some(None) => bail!(
                "{}: the film's crop leaves no pixel of the {w}x{h} image (--width, --height)",
                args.scene.scene
            ),
            None => None,
        },
    };
    let layers = Layers {
        command_line: &args.settings.layer()?,
        scene_file: &desc.settings.scene_file,
        preset: &desc.settings.preset,
    };
    let mut settings = raytracer::settings::resolve(layers, state_files(&args.files)?)?;
    settings.crop = crop;
    loaded.desc.texture_spp = settings.samples_per_pixel();
    loaded.desc.light_sampler = settings.light_sampler;
    match args.write_every {
        Some(_) if settings.integrator != IntegratorKind::Sppm => bail!("--write-every: only for integrator sppm"),
        Some(0) => bail!("--write-every 0: must be at least 1"),
        _ => {}
    }
    Ok((loaded, settings))
}

fn parse_crop(text: &str, w: u32, h: u32) -> Result<PixelRect> {
    let v: Vec<u32> = text
        .split(',')
        .map(|p| p.trim().parse::<u32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("--crop {text}: expected four whole numbers X0,Y0,X1,Y1"))?;
    let [x0, y0, x1, y1] = v[..] else {
        bail!("--crop {text}: expected four whole numbers X0,Y0,X1,Y1");
    };
    if x0 >= x1 || y0 >= y1 || x1 > w || y1 > h {
        bail!("--crop {text}: must be a non-empty rectangle inside the {w}x{h} frame");
    }
    Ok(PixelRect { x0, y0, x1, y1 })
}

/// `I/N`, `auto/N` or `auto`; `env` looks up environment variables.
pub fn parse_tile(text: &str, w: u32, h: u32, env: impl Fn(&str) -> Option<String>) -> Result<PixelRect> {
    let (i, n) = text.split_once('/').unwrap_or((text, ""));
    let count: u32 = if n.is_empty() {
        let Some(c) = env("SLURM_ARRAY_TASK_COUNT") else {
            bail!("--tile {text}: give the band count as I/N or auto/N");
        };
        c.trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--tile {text}: SLURM_ARRAY_TASK_COUNT={c} is not a whole number"))?
    } else {
        n.parse()
            .map_err(|_| anyhow::anyhow!("--tile {text}: N must be a whole number"))?
    };
    let index: u32 = if i == "auto" {
        let (var, val) = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"]
            .iter()
            .find_map(|k| env(k).map(|v| (*k, v)))
            .ok_or_else(|| {
                anyhow::anyhow!("--tile {text}: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set")
            })?;
        val.trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--tile {text}: {var}={val} is not a whole number"))?
    } else {
        i.parse()
            .map_err(|_| anyhow::anyhow!("--tile {text}: I must be a whole number"))?
    };
    if count == 0 || count > h || index >= count {
        bail!("--tile {text}: need 0 <= I < N <= {h} (the image height)");
    }
    Ok(PixelRect::band(index, count, w, h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_parse_from_text_and_scheduler_variables() {
        let none = |_: &str| None;
        assert_eq!(
            parse_tile("1/4", 10, 8, none).ok(),
            Some(PixelRect {
                x0: 0,
                y0: 2,
                x1: 10,
                y1: 4
            })
        );
        assert!(parse_tile("4/4", 10, 8, none).is_err());
        assert!(parse_tile("auto/4", 10, 8, none).is_err());
        let slurm = |k: &str| match k {
            "SLURM_ARRAY_TASK_ID" => Some("3".to_string()),
            "SLURM_ARRAY_TASK_COUNT" => Some("4".to_string()),
            _ => None,
        };
        assert_eq!(parse_tile("auto", 10, 8, slurm).ok().map(|r| r.y0), Some(6));
        let k8s = |k: &str| (k == "JOB_COMPLETION_INDEX").then(|| "0".to_string());
        assert_eq!(parse_tile("auto/2", 10, 8, k8s).ok().map(|r| r.y1), Some(4));
        assert!(parse_crop("1,2,3", 10, 8).is_err());
        assert!(parse_crop("5,2,3,4", 10, 8).is_err());
        assert_eq!(
            parse_crop("1,2,3,4", 10, 8).ok(),
            Some(PixelRect {
                x0: 1,
                y0: 2,
                x1: 3,
                y1: 4
            })
        );
    }
}
