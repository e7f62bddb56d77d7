//! The `raytracer` binary: parse the command line, call the library, and map
//! every error to one line on stderr and exit status 2, and every panic to
//! one line and exit status 101.

mod cli;

use anyhow::Result;
use clap::Parser;
use cli::{Cli, Command};
use indicatif::{ProgressBar, ProgressStyle};
use raytracer::integrator;
use raytracer::light::Light;
use raytracer::scene::LoadedScene;
use raytracer::Scene;
use std::io::IsTerminal;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Exit status after a panic, as Rust's own panic handling gives.
const EXIT_PANIC: i32 = 101;

/// A panic anywhere, worker threads included, prints one line and ends the
/// process with status 101 at once: the first panic only, the others wait
/// for the exit. Outputs are written to hidden temporary files and renamed,
/// so none is left half-written; the temporary files of writes in progress
/// are removed.
fn install_panic_hook() {
    static PANICKED: AtomicBool = AtomicBool::new(false);
    std::panic::set_hook(Box::new(|info| {
        if PANICKED.swap(true, Ordering::SeqCst) {
            loop {
                std::thread::park();
            }
        }
        let message = info
            .payload_as_str()
            .unwrap_or("a panic without a message")
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        let place = info
            .location()
            .map(|l| format!("{}:{}", l.file(), l.line()))
            .unwrap_or_else(|| "an unknown place".to_string());
        raytracer::image_io::remove_unfinished_temporary_files();
        // On a terminal, over the progress bar rather than after it.
        let clear = if std::io::stderr().is_terminal() {
            "\r\x1b[2K"
        } else {
            ""
        };
        eprintln!("{clear}internal error: {message} at {place} (this is a bug in raytracer; please report it)");
        std::process::exit(EXIT_PANIC);
    }));
}

fn main() -> ExitCode {
    install_panic_hook();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            eprintln!("{}", clap_error_line(&e.render().to_string()));
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            ExitCode::from(2)
        }
    }
}

/// clap's error on one line: its first line, and when that ends in a colon
/// (the missing arguments), the indented lines it introduces.
fn clap_error_line(text: &str) -> String {
    let mut lines = text.lines().skip_while(|l| l.trim().is_empty());
    let Some(first) = lines.next() else {
        return "invalid arguments".into();
    };
    let mut line = first.trim_end().to_string();
    if line.ends_with(':') {
        let items: Vec<&str> = lines
            .take_while(|l| l.starts_with(char::is_whitespace) && !l.trim().is_empty())
            .map(str::trim)
            .collect();
        line = format!("{} {}", line, items.join(", "));
    }
    line
}

/// The error and its causes on one line. Library errors that name their
/// source in their own message (`path: os error`) are not repeated by it.
fn one_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string().replace('\n', " ");
        if line.ends_with(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Some(Command::Info(args)) => info(&args).map(|_| ExitCode::SUCCESS),
        Some(Command::Compare(args)) => compare(&args).map(|_| ExitCode::SUCCESS),
        Some(Command::Merge(args)) => merge(&args).map(|_| ExitCode::SUCCESS),
        Some(Command::View(args)) => view(&args.render).map(|_| ExitCode::SUCCESS),
        Some(Command::Photons(args)) => photons(&args.render).map(|_| ExitCode::SUCCESS),
        None => render(&cli.render),
    }
}

/// Exit status after SIGINT/SIGTERM, as shells report a death by SIGINT.
const EXIT_INTERRUPTED: u8 = 130;

/// Where an interrupted render's pixels go: `name.partial.ext` beside the output.
fn partial_path(output: &std::path::Path) -> std::path::PathBuf {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = output
        .extension()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    output.with_file_name(format!("{stem}.partial.{ext}"))
}

/// Tells the user anything odd in the meshes.
fn report_meshes(loaded: &LoadedScene, args: &cli::SceneArgs, quiet: bool) {
    if quiet {
        return;
    }
    for m in &loaded.meshes {
        for w in &m.warnings {
            eprintln!("warning: {w}");
        }
        if args.smooth && !m.has_normals {
            eprintln!(
                "warning: --smooth: {} has no vertex normals; it is flat-shaded",
                m.path.display()
            );
        }
    }
}

/// Degenerate triangles are dropped, not refused; say how many.
fn report_dropped(scene: &Scene, quiet: bool) {
    if !quiet && scene.dropped_triangles > 0 {
        eprintln!(
            "warning: {} degenerate triangles (zero area or non-finite) dropped",
            scene.dropped_triangles
        );
    }
}

/// Subsurface scattering is the path tracer's alone; say so when another
/// integrator renders a scene that has it.
fn report_subsurface(scene: &Scene, integrator: integrator::IntegratorKind, quiet: bool) {
    if !quiet && scene.has_subsurface() && integrator != integrator::IntegratorKind::Path {
        eprintln!(
            "warning: subsurface materials scatter below their surface only in the path tracer (--integrator path); {} shows their dielectric surface alone",
            integrator.name()
        );
    }
}

/// A photon guide asked for where it cannot work; say why.
fn report_guide(scene: &Scene, settings: &integrator::RenderSettings, quiet: bool) {
    if quiet || settings.guide_photons == 0 || settings.integrator != integrator::IntegratorKind::Path {
        return;
    }
    if scene.has_media() || scene.has_subsurface() {
        eprintln!(
            "warning: --guide-photons: scenes with media or subsurface scattering are path traced without a guide"
        );
    } else if !scene.materials.iter().any(|m| m.is_caustic_caster()) {
        eprintln!("warning: --guide-photons: no glossy or specular surface brings caustics here; nothing to guide");
    }
}

fn render(args: &cli::RenderArgs) -> Result<ExitCode> {
    // Ctrl-C or a scheduler's SIGTERM: finish the tiles in flight, save them, exit 130.
    // Installed first, so that a signal during loading is not a silent death.
    let cancel = match args.files.stop_after_tiles {
        Some(n) => integrator::CancelToken::after_tiles(n),
        None => integrator::CancelToken::new(),
    };
    let on_signal = cancel.clone();
    let _ = ctrlc::set_handler(move || on_signal.cancel());
    let (loaded, settings) = cli::prepare(args)?;
    report_meshes(&loaded, &args.scene, args.quiet);
    let scene = Scene::build(loaded.desc)?;
    report_dropped(&scene, args.quiet);
    report_subsurface(&scene, settings.integrator, args.quiet);
    report_guide(&scene, &settings, args.quiet);
    let (w, h) = (scene.camera.width, scene.camera.height);
    let rect = settings.crop.unwrap_or(raytracer::film::PixelRect::full(w, h));
    let bar = if !args.quiet && std::io::stderr().is_terminal() {
        let b = ProgressBar::new(integrator::progress_ticks(&settings, rect.width(), rect.height()));
        if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} tiles, {elapsed} elapsed, {eta} left") {
            b.set_style(style);
        }
        b
    } else {
        ProgressBar::hidden()
    };
    // SPPM with --write-every K: the image so far, every K passes, written atomically.
    let window = integrator::frame_window(&scene, &settings)?;
    let on_pass = |k: u32, film: &raytracer::Film| match args.write_every {
        Some(every) if k.is_multiple_of(every) => {
            raytracer::image_io::write_image_in_frame(film, &window, &[], &args.output, args.exposure)
        }
        _ => Ok(()),
    };
    let ticks = AtomicU64::new(0);
    let tick = || {
        bar.inc(1);
        let done = ticks.fetch_add(1, Ordering::SeqCst) + 1;
        if let Some(n) = args.files.panic_after_tiles.filter(|&n| done > n) {
            panic!("--panic-after-tiles {n}: a panic on a worker thread, as asked");
        }
    };
    let out = integrator::render_observed(&scene, &settings, integrator::Progress::new(&tick, &cancel), &on_pass)?;
    bar.finish_and_clear();
    if !out.is_complete() {
        let path = partial_path(&args.output);
        let (what, done) = match out.passes {
            Some((done, all)) => ("passes", format!("{done}/{all}")),
            None => ("tiles", format!("{}/{}", out.tiles_done, out.tiles_total)),
        };
        let key = format!("raytracer.{what}");
        let attrs = [("raytracer.partial", "true"), (key.as_str(), done.as_str())];
        raytracer::image_io::write_image_in_frame(&out.film, &out.window, &attrs, &path, args.exposure)?;
        let checkpoint = match (&settings.files.checkpoint, out.passes) {
            (Some(c), Some(_)) => format!("; checkpoint {} (continue with --resume)", c.display()),
            _ => String::new(),
        };
        eprintln!(
            "interrupted: {done} {what} rendered, saved to {}{checkpoint}",
            path.display()
        );
        return Ok(ExitCode::from(EXIT_INTERRUPTED));
    }
    raytracer::image_io::write_image_in_frame(&out.film, &out.window, &[], &args.output, args.exposure)?;
    if !args.quiet {
        if let Some(p) = &out.photons {
            report_photons(p, &settings.files);
        }
        if let Some(g) = &out.guide {
            eprintln!(
                "guide: {} caustic photons of {} emitted, {} cells, traced and binned in {:.2} s",
                g.stored, g.emitted, g.cells, g.seconds
            );
        }
        println!(
            "{} {}x{}{}, {} spp{}, {:?}: {:.2} s, {:.2} Mrays/s -> {}",
            scene.name,
            w,
            h,
            match settings.crop {
                Some(r) => format!(" (crop {},{},{},{})", r.x0, r.y0, r.x1, r.y1),
                None => String::new(),
            },
            settings.samples_per_pixel(),
            // The path tracer and SPPM take one light sample a vertex.
            match settings.integrator {
                integrator::IntegratorKind::Direct | integrator::IntegratorKind::Photon =>
                    format!(", {} shadow samples", settings.shadow_samples),
                integrator::IntegratorKind::Path
                | integrator::IntegratorKind::Bdpt
                | integrator::IntegratorKind::Sppm => {
                    String::new()
                }
            },
            settings.integrator,
            out.seconds,
            out.stats.total() as f64 / out.seconds.max(1e-9) / 1e6,
            args.output.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The photon pass's summary line.
fn report_photons(p: &raytracer::photon::PhotonStats, files: &integrator::StateFiles) {
    let mib = p.bytes as f64 / (1 << 20) as f64;
    match &files.load_photons {
        Some(f) => eprintln!(
            "photons: {} emitted, {} stored ({mib:.1} MiB), loaded from {} in {:.3} s",
            p.emitted,
            p.stored,
            f.display(),
            p.load_seconds
        ),
        None => eprintln!(
            "photons: {} emitted, {} stored ({mib:.1} MiB), traced in {:.2} s, kd-tree built in {:.3} s{}",
            p.emitted,
            p.stored,
            p.trace_seconds,
            p.build_seconds,
            match &files.save_photons {
                Some(f) => format!(", saved to {} in {:.3} s", f.display(), p.save_seconds),
                None => String::new(),
            }
        ),
    }
    if p.caustic_stored > 0 {
        eprintln!(
            "caustic map: {} photons emitted, {} stored",
            p.caustic_emitted, p.caustic_stored
        );
    }
    if p.precompute_seconds > 0.0 {
        eprintln!("photons: irradiance precomputed in {:.2} s", p.precompute_seconds);
    }
}

/// `photons`: trace the photon map and save it, render nothing.
fn photons(args: &cli::RenderArgs) -> Result<()> {
    if args.files.save_photons.is_none() {
        anyhow::bail!("photons: give --save-photons FILE, where the map goes");
    }
    let mut args = args.clone();
    args.settings.force("integrator", "photon");
    let (loaded, settings) = cli::prepare_settings(&args)?;
    report_meshes(&loaded, &args.scene, args.quiet);
    let scene = Scene::build(loaded.desc)?;
    report_dropped(&scene, args.quiet);
    let maps = integrator::with_threads(settings.threads, || integrator::photon::photon_maps(&scene, &settings))??;
    if !args.quiet {
        report_photons(&maps.stats, &settings.files);
    }
    Ok(())
}

fn view(args: &cli::RenderArgs) -> Result<()> {
    if args.crop.is_some() || args.tile.is_some() {
        anyhow::bail!("view shows the whole frame: --crop and --tile are for offline renders");
    }
    let f = &args.files;
    if f.save_photons.is_some() || f.load_photons.is_some() || f.checkpoint.is_some() || f.resume.is_some() {
        anyhow::bail!("view keeps nothing between runs: --save-photons, --load-photons, --checkpoint and --resume are for offline renders");
    }
    let (loaded, mut settings) = cli::prepare(args)?;
    // The preview shows the whole frame, whatever part the scene file asks for.
    settings.crop = None;
    report_meshes(&loaded, &args.scene, args.quiet);
    let scene = Scene::build(loaded.desc)?;
    let options = raytracer::viewer::ViewOptions {
        output: args.output.clone(),
        exposure: args.exposure,
        quiet: args.quiet,
    };
    Ok(raytracer::viewer::run(scene, settings, options)?)
}

fn info(args: &cli::SceneArgs) -> Result<()> {
    let loaded = cli::load_scene(args)?;
    report_meshes(&loaded, args, false);
    let meshes = loaded.meshes.clone();
    let scene = Scene::build(loaded.desc)?;
    report_dropped(&scene, false);
    let s = scene.bvh.stats();
    println!("scene: {}", scene.name);
    for m in &meshes {
        println!(
            "mesh: {} ({} vertices, {} triangles, {}), loaded in {:.1} ms",
            m.path.display(),
            m.vertices,
            m.triangles,
            if m.has_normals { "with normals" } else { "no normals" },
            m.seconds * 1e3
        );
    }
    println!(
        "triangles: {} ({} dropped as degenerate)",
        scene.triangle_count(),
        scene.dropped_triangles
    );
    let listed = &scene.desc.triangles;
    println!(
        "vertices: {} shared by the description's {} triangles ({:.2} MiB)",
        listed.vertex_count(),
        listed.len(),
        listed.heap_bytes() as f64 / (1 << 20) as f64
    );
    println!(
        "spheres: {}, disks: {} (besides the lights)",
        scene.desc.spheres.len(),
        scene.desc.disks.len()
    );
    if !scene.desc.curves.is_empty() {
        println!("curve pieces: {}", scene.desc.curves.len());
    }
    // Triangles, spheres and disks among sets of shapes.
    let count = |sets: &mut dyn Iterator<Item = &raytracer::scene::CutShapes>| {
        use raytracer::scene::CutShapes;
        let (mut tris, mut spheres, mut disks) = (0, 0, 0);
        for set in sets {
            match set {
                CutShapes::Triangles(r) => tris += r.len(),
                CutShapes::Sphere(_) => spheres += 1,
                CutShapes::Disk(_) => disks += 1,
            }
        }
        format!("{tris} triangles, {spheres} spheres, {disks} disks")
    };
    if !scene.desc.cutouts.is_empty() {
        println!(
            "cut out by alpha textures: {} shapes ({})",
            scene.desc.cutouts.len(),
            count(&mut scene.desc.cutouts.iter().map(|c| &c.shapes))
        );
    }
    if scene.has_motion() {
        let d = &scene.desc;
        let triangles: usize = d.moving.iter().map(|m| m.triangles.len()).sum();
        let spheres = d
            .moving_shapes
            .iter()
            .filter(|m| matches!(m.shape, raytracer::scene::CutShapes::Sphere(_)))
            .count();
        println!(
            "moving: {} meshes ({triangles} triangles), {spheres} spheres, {} disks{}, shutter open from {} to {}",
            d.moving.len(),
            d.moving_shapes.len() - spheres,
            if d.camera_motion.is_some() {
                " and the camera"
            } else {
                ""
            },
            d.shutter[0],
            d.shutter[1]
        );
    }
    for (name, m) in &scene.desc.media {
        let glow = m
            .emission
            .as_ref()
            .map_or(String::new(), |e| format!(", {}", e.summary()));
        if let Some((g, max)) = m.density.as_ref().and_then(|g| Some((g, g.rgb_majorant()?))) {
            let [x, y, z] = g.resolution().unwrap_or([1, 1, 1]);
            println!(
                "medium \"{name}\": an RGB grid of {x} x {y} x {z} coefficients, sigma_t up to {max}, g {}{glow}",
                m.g
            );
            continue;
        }
        let kind = match &m.density {
            None => "homogeneous".to_string(),
            Some(g) => g.describe(),
        };
        println!(
            "medium \"{name}\": {kind}, sigma_a {}, sigma_s {}, g {}{glow}",
            m.sigma_a, m.sigma_s, m.g
        );
    }
    if !scene.desc.media.is_empty() {
        let camera = match scene.desc.camera_medium {
            Some(i) => format!("in \"{}\"", scene.desc.media[i as usize].0),
            None => "in vacuum".into(),
        };
        println!(
            "media bounded by {}; the camera {camera}",
            count(&mut scene.desc.boundaries.iter().map(|b| &b.shapes))
        );
    }
    // Lights by kind, in the order kinds first appear.
    let mut kinds: Vec<(&str, usize)> = vec![];
    for l in &scene.lights {
        match kinds.iter_mut().find(|(k, _)| *k == l.kind()) {
            Some((_, n)) => *n += 1,
            None => kinds.push((l.kind(), 1)),
        }
    }
    let mut kinds: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
    let imaged = scene
        .lights
        .iter()
        .filter(|l| {
            matches!(
                l,
                Light::Triangle { image: Some(_), .. }
                    | Light::Sphere { image: Some(_), .. }
                    | Light::Disk { image: Some(_), .. }
            )
        })
        .count();
    if imaged > 0 {
        kinds.push(format!("{imaged} of them with an emission image"));
    }
    let invisible = |i: usize| scene.desc.invisible_lights.get(i).copied().unwrap_or(false);
    let reflecting = (scene.desc.light_surfaces.iter().enumerate())
        .filter(|(i, s)| s.is_some() && !invisible(*i))
        .count();
    if reflecting > 0 {
        kinds.push(format!("{reflecting} of them reflecting by a material"));
    }
    let invisible = (0..scene.lights.len()).filter(|&i| invisible(i)).count();
    if invisible > 0 {
        kinds.push(format!("{invisible} of them invisible (alpha 0: met by no ray)"));
    }
    println!("lights: {} ({})", scene.lights.len(), kinds.join(", "));
    println!("materials: {}", scene.materials.len());
    if let Some(lens) = scene.camera.lens_system() {
        let (n, stop) = lens.summary();
        let stop = stop.map_or("no stop".to_string(), |d| format!("stop {d:.1} mm"));
        println!(
            "camera: realistic, lens {} ({n} interfaces, focal length {:.1} mm, {stop})",
            lens.name,
            lens.focal_length * 1000.0
        );
    }
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

fn compare(args: &cli::CompareArgs) -> Result<()> {
    use anyhow::{bail, Context};
    use raytracer::image_io::{read_image, write_atomic, Format};
    let img = read_image(&args.image)?;
    let full = read_image(&args.reference)?;
    let reference = raytracer::metrics::downsample_to(&full, img.width, img.height).unwrap_or(full);
    let max_luminance = args.max_luminance.unwrap_or(f32::INFINITY);
    if max_luminance.is_nan() || max_luminance < 0.0 {
        bail!("--max-luminance {max_luminance}: must be a non-negative number");
    }
    let Some(e) = raytracer::metrics::compare_below(&img, &reference, max_luminance) else {
        bail!(
            "{} is {}x{} but {} is {}x{}, not an integer multiple of it",
            args.image.display(),
            img.width,
            img.height,
            args.reference.display(),
            reference.width,
            reference.height
        );
    };
    if let Some(diff) = &args.diff {
        if Format::from_path(diff).ok() != Some(Format::Png) {
            bail!("--diff {}: must be a .png file", diff.display());
        }
        if !(args.diff_scale.is_finite() && args.diff_scale > 0.0) {
            bail!("--diff-scale {}: must be a positive number", args.diff_scale);
        }
        let px = raytracer::metrics::error_image(&img, &reference, args.diff_scale);
        write_atomic(diff, |tmp| {
            image::save_buffer_with_format(
                tmp,
                &px,
                img.width,
                img.height,
                image::ExtendedColorType::Rgb8,
                image::ImageFormat::Png,
            )
            .map_err(|e| raytracer::Error::ImageWrite {
                path: diff.clone(),
                message: e.to_string(),
            })
        })
        .with_context(|| format!("--diff {}", diff.display()))?;
    }
    println!(
        "rmse {:.6}  rel_mse {:.6}  luminance_ratio {:.4}",
        e.rmse, e.rel_mse, e.luminance_ratio
    );
    Ok(())
}

fn merge(args: &cli::MergeArgs) -> Result<()> {
    use raytracer::image_io::{check_writable, read_exr_in_frame};
    check_writable(&args.output)?;
    // Writing over a part would lose it if anything then went wrong.
    if let Ok(out) = std::fs::canonicalize(&args.output) {
        if let Some(p) = args
            .parts
            .iter()
            .find(|p| std::fs::canonicalize(p).is_ok_and(|c| c == out))
        {
            anyhow::bail!("merge: the output {} is one of the parts", p.display());
        }
    }
    let mut parts = vec![];
    let mut names = vec![];
    for p in &args.parts {
        parts.push(read_exr_in_frame(p).map(|(f, w, _)| (f, w))?);
        names.push(p.display().to_string());
    }
    let film = raytracer::film::assemble(&parts, &names).map_err(|m| anyhow::anyhow!("merge: {m}"))?;
    raytracer::image_io::write_image(&film, &args.output, 0.0)?;
    Ok(())
}
