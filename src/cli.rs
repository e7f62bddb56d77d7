//! Command-line interface: option definitions (with their defaults, which
//! `--help` shows) and their validation into library settings.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use raytracer::film::Filter;
use raytracer::integrator::{IntegratorKind, RenderSettings};
use raytracer::scene::builtin;
use raytracer::SceneDesc;
use std::path::PathBuf;

/// Largest image side we accept; beyond it the film alone would not fit.
const MAX_SIDE: u32 = 32_768;
/// Largest pixel count: 2^28 pixels is 3 GiB of float RGB film.
const MAX_PIXELS: u64 = 1 << 28;

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

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Print statistics of a scene: triangles, BVH nodes, depth, leaf sizes, SAH cost, build time, memory.
    Info(SceneArgs),
    /// Open an interactive preview window that refines the image while nothing moves (press H for the keys).
    View(ViewArgs),
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
    /// Built-in scene name (cornell).
    #[arg(long, default_value = "cornell", value_name = "NAME|FILE")]
    pub scene: String,
}

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output image; the extension picks the format: .png (8-bit sRGB), .exr or .pfm (linear radiance).
    #[arg(short, long, default_value = "render.png")]
    pub output: PathBuf,
    /// Image width in pixels [default: the scene's, 512 for cornell].
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels [default: the scene's, 512 for cornell].
    #[arg(long)]
    pub height: Option<u32>,
    /// Supersampling: NxN stratified, jittered camera samples per pixel [default: 4].
    #[arg(long, value_name = "N")]
    pub ssaa: Option<u32>,
    /// Shadow rays per light per shading point, stratified over the light [default: 4].
    #[arg(long, value_name = "N")]
    pub shadow_samples: Option<u32>,
    /// Radius of the sphere light, overriding the scene's; 0 makes it a point light (hard shadows).
    #[arg(long, value_name = "R")]
    pub light_radius: Option<f32>,
    /// Pixel reconstruction filter.
    #[arg(long, value_enum, default_value_t = Filter::Box)]
    pub filter: Filter,
    /// Light transport algorithm.
    #[arg(long, value_enum, default_value_t = IntegratorKind::Direct)]
    pub integrator: IntegratorKind,
    /// Worker threads [default: all cores].
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Random seed; the same seed gives the same image on any thread count.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Exposure in stops applied to PNG output (linear outputs hold radiance).
    #[arg(long, value_name = "EV", default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// Print nothing (no progress bar, no summary).
    #[arg(short, long)]
    pub quiet: bool,
}

/// Resolves `--scene` to a description.
pub fn load_scene(args: &SceneArgs) -> Result<SceneDesc> {
    match builtin::by_name(&args.scene) {
        Some(d) => Ok(d),
        None => bail!(raytracer::Error::UnknownScene {
            name: args.scene.clone(),
            known: builtin::NAMES.join(", "),
        }),
    }
}

/// Checks every option and applies it to the scene, before any work starts.
pub fn prepare(args: &RenderArgs) -> Result<(SceneDesc, RenderSettings)> {
    let mut desc = load_scene(&args.scene)?;
    if let Some(w) = args.width {
        desc.camera.width = w;
    }
    if let Some(h) = args.height {
        desc.camera.height = h;
    }
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
    let ssaa = args.ssaa.or(desc.settings.ssaa).unwrap_or(4);
    if ssaa == 0 || ssaa > 64 {
        bail!("--ssaa {ssaa}: must be between 1 and 64");
    }
    let shadow_samples = args.shadow_samples.or(desc.settings.shadow_samples).unwrap_or(4);
    if shadow_samples > 65_536 {
        bail!("--shadow-samples {shadow_samples}: at most 65536");
    }
    if let Some(r) = args.light_radius {
        if !(r.is_finite() && r >= 0.0) {
            bail!("--light-radius {r}: must be a finite number >= 0");
        }
        desc.set_light_radius(r);
    }
    if let Some(t) = args.threads {
        if t == 0 || t > 1024 {
            bail!("--threads {t}: must be between 1 and 1024");
        }
    }
    if !args.exposure.is_finite() {
        bail!("--exposure {}: must be a finite number", args.exposure);
    }
    raytracer::image_io::check_writable(&args.output).context("cannot write the output")?;
    let settings = RenderSettings {
        ssaa,
        shadow_samples,
        filter: args.filter,
        seed: args.seed,
        threads: args.threads,
        integrator: args.integrator,
    };
    Ok((desc, settings))
}
