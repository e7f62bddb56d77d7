//! The `raytracer` binary: parse the command line, call the library, and map
//! every error to one line on stderr and exit status 2.

mod cli;

use anyhow::Result;
use clap::Parser;
use cli::{Cli, Command};
use indicatif::{ProgressBar, ProgressStyle};
use raytracer::integrator::{self, tile_count};
use raytracer::Scene;
use std::io::IsTerminal;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            let text = e.render().to_string();
            let line = text
                .lines()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("invalid arguments");
            eprintln!("{line}");
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", format!("{e:#}").replace('\n', " "));
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Some(Command::Info(args)) => info(&args),
        Some(Command::View(args)) => view(&args.render),
        None => render(&cli.render),
    }
}

fn render(args: &cli::RenderArgs) -> Result<()> {
    let (desc, settings) = cli::prepare(args)?;
    let scene = Scene::build(desc)?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let bar = if !args.quiet && std::io::stderr().is_terminal() {
        let b = ProgressBar::new(tile_count(w, h));
        if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} tiles, {elapsed} elapsed, {eta} left") {
            b.set_style(style);
        }
        b
    } else {
        ProgressBar::hidden()
    };
    let out = integrator::render(&scene, &settings, &|| bar.inc(1))?;
    bar.finish_and_clear();
    raytracer::image_io::write_image(&out.film, &args.output, args.exposure)?;
    if !args.quiet {
        println!(
            "{} {}x{}, {} spp, {} shadow samples, {:?}: {:.2} s, {:.2} Mrays/s -> {}",
            scene.name,
            w,
            h,
            settings.ssaa * settings.ssaa,
            settings.shadow_samples,
            settings.integrator,
            out.seconds,
            out.stats.total() as f64 / out.seconds.max(1e-9) / 1e6,
            args.output.display()
        );
    }
    Ok(())
}

fn view(args: &cli::RenderArgs) -> Result<()> {
    let (desc, settings) = cli::prepare(args)?;
    let scene = Scene::build(desc)?;
    let options = raytracer::viewer::ViewOptions {
        output: args.output.clone(),
        exposure: args.exposure,
        quiet: args.quiet,
    };
    Ok(raytracer::viewer::run(scene, settings, options)?)
}

fn info(args: &cli::SceneArgs) -> Result<()> {
    let desc = cli::load_scene(args)?;
    let scene = Scene::build(desc)?;
    let s = scene.bvh.stats();
    println!("scene: {}", scene.name);
    println!(
        "triangles: {} ({} dropped as degenerate)",
        scene.triangle_count(),
        scene.dropped_triangles
    );
    println!("bvh nodes: {} ({} leaves), depth {}", s.nodes, s.leaves, s.depth);
    let hist: Vec<String> = s
        .leaf_sizes
        .iter()
        .enumerate()
        .filter(|(_, &c)| c > 0)
        .map(|(k, c)| format!("{k}:{c}"))
        .collect();
    println!("leaf sizes (triangles:leaves): {}", hist.join(" "));
    println!("sah cost: {:.2}", s.sah_cost);
    println!("build time: {:.2} ms", scene.bvh_build_seconds * 1e3);
    println!("memory: {:.2} MiB (nodes and index)", s.bytes as f64 / (1 << 20) as f64);
    Ok(())
}
