//! Image files: PNG (8-bit sRGB), OpenEXR and PFM (linear float RGB).
//! Every write goes to a temporary file beside the target and is renamed into
//! place, so a reader never sees half an image and a failure leaves nothing.

use crate::error::{Error, Result};
use crate::film::{Film, FrameWindow, PixelRect};
use crate::math::Vec3;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Output formats, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Exr,
    Pfm,
}

impl Format {
    pub fn from_path(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("exr") => Ok(Format::Exr),
            Some("pfm") => Ok(Format::Pfm),
            _ => Err(Error::InvalidSetting(format!(
                "--output {}: unknown image format (use a .png, .exr or .pfm file name)",
                path.display()
            ))),
        }
    }
}

/// Checks, before any rendering, that `path` can be written: a known
/// extension and an existing, writable folder.
pub fn check_writable(path: &Path) -> Result<Format> {
    let fmt = Format::from_path(path)?;
    check_file_writable("--output", path)?;
    Ok(fmt)
}

/// Checks that the file `option` names can be written (atomically: its
/// folder must take a temporary file), before any work that would be lost.
pub fn check_file_writable(option: &str, path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::InvalidSetting(format!(
            "{option} {}: is a directory",
            path.display()
        )));
    }
    let dir = parent_dir(path);
    let probe = temp_path(path);
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(Error::InvalidSetting(format!(
            "{option} {}: cannot write to {}: {e}",
            path.display(),
            dir.display()
        ))),
    }
}

fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The name of the temporary file a write of `path` goes through:
/// `.<file name>.<host>.<pid>.<random>.tmp` beside it. Hidden and ending in
/// `.tmp`, it cannot be taken for output; the host name, process id and
/// random part keep apart writers on several machines sharing one folder
/// (parts and photon maps on shared storage), and two writes in one process.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let suffix = format!(".{}.{}.{:016x}.tmp", host_name(), std::process::id(), random_part());
    // File names are limited to 255 bytes: shorten a long target's name, not the suffix.
    let mut keep = name.len().min(255usize.saturating_sub(1 + suffix.len()));
    while !name.is_char_boundary(keep) {
        keep -= 1;
    }
    parent_dir(path).join(format!(".{}{suffix}", &name[..keep]))
}

/// This machine's name as a file name part (`localhost` when unknown).
fn host_name() -> String {
    let name = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "localhost".to_string());
    name.chars()
        .take(64)
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// A number that differs between calls and processes: the standard
/// library's randomly keyed hasher over the time and a per-process counter.
fn random_part() -> u64 {
    use std::hash::{BuildHasher, Hasher};
    static CALLS: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or_default();
    h.write_u128(now);
    h.write_u64(CALLS.fetch_add(1, Ordering::Relaxed));
    h.finish()
}

/// Temporary files being written, for [`remove_unfinished_temporary_files`].
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes the temporary files of writes still in progress in this process.
/// For a program about to exit in the middle of one (the binary's panic
/// report); never waits for a lock, so it is safe to call from a panic hook.
pub fn remove_unfinished_temporary_files() {
    if let Ok(files) = UNFINISHED.try_lock() {
        for f in files.iter() {
            let _ = std::fs::remove_file(f);
        }
    }
}

/// A temporary file being written: listed in [`UNFINISHED`] while it lives,
/// removed (if still there, that is, not renamed) when dropped, unwinding included.
struct Unfinished(PathBuf);

impl Unfinished {
    fn new(tmp: PathBuf) -> Self {
        UNFINISHED.lock().unwrap_or_else(|e| e.into_inner()).push(tmp.clone());
        Unfinished(tmp)
    }
}

impl Drop for Unfinished {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
        UNFINISHED
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .retain(|f| *f != self.0);
    }
}

/// Writes through `write` into a temporary file, then renames it to `path`.
pub fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = Unfinished::new(temp_path(path));
    write(&tmp.0).and_then(|_| {
        std::fs::rename(&tmp.0, path).map_err(|e| Error::Io {
            path: path.to_path_buf(),
            source: e,
        })
    })
}

/// Writes the film in the format its extension names. `exposure` (in stops)
/// applies to PNG only; the float formats hold radiance.
pub fn write_image(film: &Film, path: &Path, exposure: f32) -> Result<()> {
    write_image_in_frame(film, &FrameWindow::full(film.width, film.height), &[], path, exposure)
}

/// Like [`write_image`], for a film that covers `window.rect` of a larger
/// frame. EXR records the rectangle as its data window within the display
/// window, plus string `attributes`; PNG and PFM hold just the film's pixels.
pub fn write_image_in_frame(
    film: &Film,
    window: &FrameWindow,
    attributes: &[(&str, &str)],
    path: &Path,
    exposure: f32,
) -> Result<()> {
    let fmt = Format::from_path(path)?;
    let werr = |m: String| Error::ImageWrite {
        path: path.to_path_buf(),
        message: m,
    };
    write_atomic(path, |tmp| match fmt {
        Format::Png => image::save_buffer_with_format(
            tmp,
            &film.to_srgb8(exposure),
            film.width,
            film.height,
            image::ExtendedColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| werr(e.to_string())),
        Format::Exr => {
            use exr::prelude::*;
            let w = film.width as usize;
            let mut attrs =
                LayerAttributes::named("rgb").with_position(Vec2(window.rect.x0 as i32, window.rect.y0 as i32));
            for (k, v) in attributes {
                attrs.other.insert(Text::from(*k), AttributeValue::Text(Text::from(*v)));
            }
            let layer = Layer::new(
                (w, film.height as usize),
                attrs,
                // Run lengths, not deflate: a render's radiance is noisy in
                // its low mantissa bits, where ZIP saved 5% of the file for
                // a fifth of a one-sample render's time (BENCHMARKS.md, "The
                // output file"); runs still take in black backgrounds and
                // flat areas.
                Encoding {
                    compression: Compression::RLE,
                    blocks: Blocks::ScanLines,
                    line_order: LineOrder::Increasing,
                },
                SpecificChannels::rgb(|pos: Vec2<usize>| {
                    let p = film.pixels[pos.y() * w + pos.x()];
                    (p.x, p.y, p.z)
                }),
            );
            let mut image = Image::from_layer(layer);
            image.attributes.display_window =
                IntegerBounds::from_dimensions((window.full_width as usize, window.full_height as usize));
            image.write().to_file(tmp).map_err(|e| werr(e.to_string()))
        }
        Format::Pfm => {
            let f = std::fs::File::create(tmp).map_err(|e| Error::Io {
                path: tmp.to_path_buf(),
                source: e,
            })?;
            let mut w = BufWriter::new(f);
            write_pfm(film, &mut w)
                .and_then(|_| w.flush())
                .map_err(|e| werr(e.to_string()))
        }
    })
}

fn write_pfm(film: &Film, w: &mut impl Write) -> std::io::Result<()> {
    write!(w, "PF\n{} {}\n-1.0\n", film.width, film.height)?;
    // PFM stores rows bottom to top.
    for y in (0..film.height).rev() {
        for x in 0..film.width {
            let p = film.get(x, y);
            for v in [p.x, p.y, p.z] {
                w.write_all(&v.to_le_bytes())?;
            }
        }
    }
    Ok(())
}

/// String attributes stored in an EXR header.
pub type Attributes = Vec<(String, String)>;

/// Reads an EXR with the rectangle of the frame it covers and its string attributes.
pub fn read_exr_in_frame(path: &Path) -> crate::error::Result<(Film, FrameWindow, Attributes)> {
    use exr::prelude::*;
    let perr = |m: String| crate::error::Error::Parse {
        path: path.to_path_buf(),
        message: m,
    };
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), Film::new(res.width() as u32, res.height() as u32)),
        |(w, film): &mut (usize, Film), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            film.pixels[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
        },
    )
    .map_err(|e| perr(e.to_string()))?;
    let display = img.attributes.display_window;
    let layer = &img.layer_data;
    let pos = layer.attributes.layer_position;
    let film = layer.channel_data.pixels.1.clone();
    if display.position.x() != 0 || display.position.y() != 0 || pos.x() < 0 || pos.y() < 0 {
        return Err(perr(
            "display window must start at (0, 0) and contain the data window".into(),
        ));
    }
    let rect = PixelRect {
        x0: pos.x() as u32,
        y0: pos.y() as u32,
        x1: pos.x() as u32 + film.width,
        y1: pos.y() as u32 + film.height,
    };
    let window = FrameWindow {
        full_width: display.size.x() as u32,
        full_height: display.size.y() as u32,
        rect,
    };
    if rect.x1 > window.full_width || rect.y1 > window.full_height {
        return Err(perr("data window lies outside the display window".into()));
    }
    let attrs = layer
        .attributes
        .other
        .iter()
        .filter_map(|(k, v)| match v {
            exr::meta::attribute::AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    Ok((film, window, attrs))
}

/// Reads a linear image (PFM or EXR).
pub fn read_image(path: &Path) -> Result<Film> {
    let perr = |m: String| Error::Parse {
        path: path.to_path_buf(),
        message: m,
    };
    match Format::from_path(path).map_err(|_| perr("not a .pfm or .exr file".into()))? {
        Format::Pfm => {
            let mut bytes = vec![];
            std::fs::File::open(path)
                .and_then(|mut f| f.read_to_end(&mut bytes))
                .map_err(|e| Error::Io {
                    path: path.to_path_buf(),
                    source: e,
                })?;
            read_pfm(&bytes).map_err(perr)
        }
        Format::Exr => Ok(read_exr_in_frame(path)?.0),
        Format::Png => Err(perr("PNG is not a linear format".into())),
    }
}

pub(crate) fn read_pfm(bytes: &[u8]) -> std::result::Result<Film, String> {
    // Header: three whitespace-separated tokens, then one whitespace byte.
    let mut tokens = Vec::new();
    let mut pos = 0;
    while tokens.len() < 4 && pos < bytes.len() {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        tokens.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
        if tokens.len() == 4 {
            break;
        }
    }
    if tokens.len() < 4 || tokens[0] != "PF" {
        return Err("not a colour PFM file (expected 'PF' header)".into());
    }
    let w: u32 = tokens[1].parse().map_err(|_| format!("bad width '{}'", tokens[1]))?;
    let h: u32 = tokens[2].parse().map_err(|_| format!("bad height '{}'", tokens[2]))?;
    let scale: f32 = tokens[3].parse().map_err(|_| format!("bad scale '{}'", tokens[3]))?;
    pos += 1;
    let n = w as u64 * h as u64 * 12;
    if (bytes.len() - pos.min(bytes.len())) as u64 != n {
        return Err(format!(
            "expected {n} bytes of pixels for {w}x{h}, found {}",
            bytes.len().saturating_sub(pos)
        ));
    }
    let le = scale < 0.0;
    let mut film = Film::new(w, h);
    let data = &bytes[pos..];
    for (i, c) in data.chunks_exact(12).enumerate() {
        let f = |k: usize| {
            let b = [c[k], c[k + 1], c[k + 2], c[k + 3]];
            if le {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            }
        };
        let (x, y) = (i as u32 % w, h - 1 - i as u32 / w);
        film.set(x, y, Vec3::new(f(0), f(4), f(8)));
    }
    Ok(film)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_film() -> Film {
        let mut f = Film::new(3, 2);
        for (i, p) in f.pixels.iter_mut().enumerate() {
            *p = Vec3::new(i as f32, 0.5 * i as f32, 1e-3 * i as f32);
        }
        f
    }

    #[test]
    fn pfm_and_exr_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["a.pfm", "a.exr"] {
            let p = dir.path().join(name);
            write_image(&sample_film(), &p, 0.0).unwrap();
            assert_eq!(read_image(&p).unwrap(), sample_film(), "{name}");
        }
        write_image(&sample_film(), &dir.path().join("a.png"), 0.0).unwrap();
        // Nothing but the three images is left behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3);
    }

    #[test]
    fn exr_keeps_its_place_in_the_frame_and_attributes() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("part.exr");
        let window = FrameWindow {
            full_width: 10,
            full_height: 8,
            rect: PixelRect {
                x0: 4,
                y0: 5,
                x1: 7,
                y1: 7,
            },
        };
        write_image_in_frame(&sample_film(), &window, &[("raytracer.partial", "true")], &p, 0.0).unwrap();
        let (film, w, attrs) = read_exr_in_frame(&p).unwrap();
        assert_eq!(film, sample_film());
        assert_eq!(w, window);
        assert!(attrs.contains(&("raytracer.partial".to_string(), "true".to_string())));
    }

    #[test]
    fn unknown_extension_and_missing_folder_are_refused() {
        assert!(Format::from_path(Path::new("x.jpg")).is_err());
        assert!(check_writable(Path::new("/nonexistent-folder-xyz/a.png")).is_err());
    }

    #[test]
    fn temporary_names_are_unique_hidden_and_beside_the_target() {
        let target = Path::new("some/folder/render.exr");
        let (a, b) = (temp_path(target), temp_path(target));
        assert_ne!(a, b);
        let pid = format!(".{}.", std::process::id());
        for t in [&a, &b] {
            assert_eq!(t.parent(), target.parent(), "{}", t.display());
            let name = t.file_name().unwrap().to_string_lossy();
            assert!(name.starts_with(".render.exr.") && name.ends_with(".tmp"), "{name}");
            assert!(name.contains(&pid) && name.contains(&host_name()), "{name}");
        }
        // A bare file name stays in the current folder; a long one is shortened to fit.
        assert_eq!(temp_path(Path::new("a.png")).parent(), Some(Path::new(".")));
        let long = "\u{e9}".repeat(200) + ".png";
        let t = temp_path(Path::new(&long));
        assert!(t.file_name().unwrap().len() <= 255, "{}", t.display());
    }

    #[test]
    fn a_failed_or_panicking_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.pfm");
        let failed = write_atomic(&p, |tmp| {
            std::fs::write(tmp, b"half").unwrap();
            Err(Error::InvalidSetting("no".into()))
        });
        assert!(failed.is_err());
        let panicked = std::panic::catch_unwind(|| {
            let _ = write_atomic(&p, |tmp| {
                std::fs::write(tmp, b"half").unwrap();
                panic!("in the middle of a write");
            });
        });
        assert!(panicked.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn truncated_pfm_is_an_error() {
        let mut b = b"PF\n2 2\n-1.0\n".to_vec();
        b.extend_from_slice(&[0u8; 40]);
        assert!(read_pfm(&b).is_err());
    }
}
