//! The preview window and its render thread.
//!
//! The main thread owns the window (minifb, X11): it reads keys at 60 Hz,
//! turns movement keys into a new pose through the controller, and shows the
//! newest finished image. A render thread owns the scene and a rayon pool:
//! it applies the newest pose, renders a low-resolution direct-light image,
//! traces the photon map again if the light moved (the photon integrator),
//! then adds sample passes until the full sample count. A move sets an atomic
//! cancel flag that the passes check per tile row and the photon trace per
//! chunk, so the work in flight stops at once and the new pose starts; a
//! camera move keeps the photons traced so far.

use super::controller::{Controller, Key, Pose};
use super::progressive::{low_res_pass, view_integrator, Progressive, LOW_RES_BLOCK};
use super::{next_free_number, numbered_paths, ViewOptions, KEYS_HELP};
use crate::error::{Error, Result};
use crate::film::Film;
use crate::image_io::write_image;
use crate::integrator::{with_threads, RenderSettings};
use crate::scene::Scene;
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};

/// Window refresh and input rate.
const FPS: usize = 60;

/// An image the render thread finished.
#[derive(Clone)]
struct Frame {
    film: Arc<Film>,
    /// Which pose it shows (counts pose changes).
    pose_id: u64,
    /// Samples per pixel in it; 0 for the low-resolution image.
    samples: u32,
    target: u32,
    /// Work still to do before refinement starts (tracing photons).
    pending: Option<String>,
}

/// What the two threads share, behind one lock.
struct State {
    pose: Pose,
    pose_id: u64,
    quit: bool,
    frame: Option<Frame>,
    /// Bumped on every new frame so the window knows when to redraw.
    frame_version: u64,
}

struct Shared {
    state: Mutex<State>,
    wake: Condvar,
    /// Set with every pose change; the passes poll it.
    cancel: AtomicBool,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        // A panicked render thread is reported at join; keep the window usable.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn publish(&self, frame: Frame) {
        let mut st = self.lock();
        st.frame = Some(frame);
        st.frame_version += 1;
    }

    /// Hands a new pose to the render thread and stops its current work.
    fn set_pose(&self, pose: Pose) {
        let mut st = self.lock();
        st.pose = pose;
        st.pose_id += 1;
        self.cancel.store(true, Ordering::Relaxed);
        self.wake.notify_all();
    }

    fn quit(&self) {
        let mut st = self.lock();
        st.quit = true;
        self.cancel.store(true, Ordering::Relaxed);
        self.wake.notify_all();
    }
}

pub fn run(scene: Scene, settings: RenderSettings, options: ViewOptions) -> Result<()> {
    let controller = Controller::new(&scene.desc.camera, &scene.bounds())
        .ok_or_else(|| Error::Window("the scene's camera is degenerate".into()))?;
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let mut window = minifb::Window::new(
        &title_text(&scene.name, None, false),
        w,
        h,
        minifb::WindowOptions::default(),
    )
    .map_err(|e| Error::Window(format!("cannot open a window: {e}")))?;
    window.set_target_fps(FPS);
    let pressed = Rc::new(RefCell::new(Vec::new()));
    window.set_input_callback(Box::new(KeyQueue(Rc::clone(&pressed))));
    if !options.quiet {
        println!("{KEYS_HELP}");
    }

    let shared = Arc::new(Shared {
        state: Mutex::new(State {
            pose: controller.initial,
            pose_id: 0,
            quit: false,
            frame: None,
            frame_version: 0,
        }),
        wake: Condvar::new(),
        cancel: AtomicBool::new(false),
    });
    let name = scene.name.clone();
    let worker = {
        let shared = Arc::clone(&shared);
        let controller = controller.clone();
        let settings = settings.clone();
        std::thread::Builder::new()
            .name("render".into())
            .spawn(move || with_threads(settings.threads, || render_loop(scene, &settings, &controller, &shared)))
            .map_err(|e| Error::Window(format!("cannot start the render thread: {e}")))?
    };

    let mut pose = controller.initial;
    let mut buffer = vec![0u32; w * h];
    let mut shown: Option<Frame> = None;
    let mut shown_version = 0;
    let mut help = false;
    let mut saves = Vec::new();
    let mut next_save = 1;
    let mut title = String::new();
    while window.is_open() {
        let keys: Vec<minifb::Key> = pressed.borrow_mut().drain(..).collect();
        for key in keys {
            let movement = match key {
                minifb::Key::Escape => {
                    shared.quit();
                    None
                }
                minifb::Key::H => {
                    help = !help;
                    None
                }
                minifb::Key::P => {
                    match &shown {
                        Some(f) => {
                            next_save = next_free_number(&options.output, next_save);
                            saves.push(save(&f.film, &options, next_save));
                            next_save += 1;
                        }
                        None => eprintln!("view: nothing to save yet"),
                    }
                    None
                }
                minifb::Key::Up => Some(Key::Up),
                minifb::Key::Down => Some(Key::Down),
                minifb::Key::Left => Some(Key::Left),
                minifb::Key::Right => Some(Key::Right),
                minifb::Key::W => Some(Key::W),
                minifb::Key::A => Some(Key::A),
                minifb::Key::S => Some(Key::S),
                minifb::Key::D => Some(Key::D),
                minifb::Key::Q => Some(Key::Q),
                minifb::Key::E => Some(Key::E),
                minifb::Key::R => Some(Key::R),
                _ => None,
            };
            if let Some(k) = movement {
                let next = controller.apply(&pose, k);
                if next != pose {
                    pose = next;
                    shared.set_pose(pose);
                }
            }
        }
        if shared.lock().quit {
            break;
        }
        let fresh = {
            let st = shared.lock();
            let fresh = st.frame_version != shown_version;
            if fresh {
                shown_version = st.frame_version;
                shown = st.frame.clone();
            }
            fresh
        };
        if let Some(f) = shown.as_ref().filter(|_| fresh) {
            to_window_pixels(&f.film, options.exposure, &mut buffer);
        }
        let t = title_text(&name, shown.as_ref(), help);
        if t != title {
            window.set_title(&t);
            title = t;
        }
        if let Err(e) = window.update_with_buffer(&buffer, w, h) {
            shared.quit();
            let _ = worker.join();
            return Err(Error::Window(format!("cannot draw: {e}")));
        }
    }
    shared.quit();
    for s in saves {
        let _ = s.join();
    }
    match worker.join() {
        Ok(r) => r.and_then(|r| r),
        Err(_) => Err(Error::Window("the render thread failed".into())),
    }
}

/// Collects every key press (auto-repeats included) as it arrives. Polling
/// key states once a frame would miss a press released within the frame.
struct KeyQueue(Rc<RefCell<Vec<minifb::Key>>>);

impl minifb::InputCallback for KeyQueue {
    fn add_char(&mut self, _uni_char: u32) {}

    fn set_key_state(&mut self, key: minifb::Key, down: bool) {
        if down {
            self.0.borrow_mut().push(key);
        }
    }
}

/// Title bar: scene, pose, refinement state, or the key list.
fn title_text(scene: &str, frame: Option<&Frame>, help: bool) -> String {
    if help {
        return format!("raytracer view | {KEYS_HELP}");
    }
    let status = match frame {
        None => "starting".to_string(),
        Some(f) if f.samples == 0 => match &f.pending {
            Some(p) => format!("pose {} | low-res preview, {p}", f.pose_id),
            None => format!("pose {} | low-res preview", f.pose_id),
        },
        Some(f) if f.samples >= f.target => format!("pose {} | {}/{} spp, done", f.pose_id, f.samples, f.target),
        Some(f) => format!("pose {} | {}/{} spp", f.pose_id, f.samples, f.target),
    };
    format!("raytracer view: {scene} | {status} | H: keys")
}

/// 8-bit sRGB packed as minifb's 0RGB words.
fn to_window_pixels(film: &Film, exposure: f32, out: &mut [u32]) {
    for (o, c) in out.iter_mut().zip(film.to_srgb8(exposure).chunks_exact(3)) {
        *o = (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32;
    }
}

/// Writes picture `n` (PNG and EXR beside each other, each atomically) on
/// its own thread, so the window does not stall.
fn save(film: &Arc<Film>, options: &ViewOptions, n: u32) -> std::thread::JoinHandle<()> {
    let (png, exr) = numbered_paths(&options.output, n);
    let film = Arc::clone(film);
    let (exposure, quiet) = (options.exposure, options.quiet);
    std::thread::spawn(move || {
        let written = write_image(&film, &png, exposure).and_then(|_| write_image(&film, &exr, 0.0));
        match written {
            Ok(()) if !quiet => println!("saved {} and {}", png.display(), exr.display()),
            Ok(()) => {}
            Err(e) => eprintln!("view: {e}"),
        }
    })
}

/// The render thread: applies the newest pose, shows a low-resolution
/// direct-light image, brings the integrator's light transport (the photon
/// map) up to date if the light moved, then refines until done or until the
/// pose changes again; sleeps while there is nothing to do.
fn render_loop(mut scene: Scene, settings: &RenderSettings, controller: &Controller, shared: &Shared) -> Result<()> {
    let home_camera = scene.camera.clone();
    let light_home: Vec<_> = scene.lights.iter().map(|l| l.position()).collect();
    let mut integrator = view_integrator(settings);
    let mut acc = Progressive::new(scene.camera.width, scene.camera.height, settings);
    let mut applied: Option<u64> = None;
    // The light offset the scene's lights were last placed at.
    let mut lights_at: Option<crate::math::Vec3> = None;
    loop {
        let (pose, pose_id) = {
            let mut st = shared.lock();
            while !st.quit && applied == Some(st.pose_id) && acc.is_complete() {
                st = shared.wake.wait(st).unwrap_or_else(|e| e.into_inner());
            }
            if st.quit {
                return Ok(());
            }
            // Cleared under the lock: a later move sets it again after
            // bumping pose_id, so no cancel is lost.
            shared.cancel.store(false, Ordering::Relaxed);
            (st.pose, st.pose_id)
        };
        let cancel = &shared.cancel;
        if applied != Some(pose_id) {
            // The scene's own camera where the pose is the initial one, so the
            // finished image is the offline render's to the bit.
            let camera = if pose.camera_position == controller.initial.camera_position
                && pose.camera_forward == controller.initial.camera_forward
            {
                Some(home_camera.clone())
            } else {
                controller.camera(&pose, &scene.desc.camera)
            };
            if let Some(cam) = camera {
                scene.camera = cam;
            }
            // Light transport is traced again only when the light moved; a
            // camera move keeps the map (or the part of it traced so far).
            if lights_at != Some(pose.light_offset) {
                for (i, home) in light_home.iter().enumerate() {
                    scene.move_light(i, *home + pose.light_offset);
                }
                integrator.light_moved();
                lights_at = Some(pose.light_offset);
            }
            acc.reset();
            applied = Some(pose_id);
            let Some(film) = low_res_pass(&scene, settings, integrator.low_res_estimator(), LOW_RES_BLOCK, cancel)
            else {
                continue;
            };
            shared.publish(Frame {
                film: Arc::new(film),
                pose_id,
                samples: 0,
                target: acc.target(),
                pending: integrator.pending(),
            });
        }
        if !integrator.prepare(&scene, settings, cancel) {
            continue;
        }
        if acc.run_pass(&scene, settings, integrator.estimator().as_ref(), cancel) {
            shared.publish(Frame {
                film: Arc::new(acc.film()),
                pose_id,
                samples: acc.samples(),
                target: acc.target(),
                pending: None,
            });
        }
    }
}
