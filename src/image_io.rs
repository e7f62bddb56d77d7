//! Image files: PNG (8-bit sRGB), OpenEXR and PFM (linear float RGB).
//! Every write goes to a temporary file beside the target and is renamed into
//! place, so a reader never sees half an image and a failure leaves nothing.

use crate::error::{Error, Result};
use crate::film::Film;
use crate::math::Vec3;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

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
    if path.is_dir() {
        return Err(Error::InvalidSetting(format!(
            "--output {}: is a directory",
            path.display()
        )));
    }
    let dir = parent_dir(path);
    let probe = temp_path(path);
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(fmt)
        }
        Err(e) => Err(Error::InvalidSetting(format!(
            "--output {}: cannot write to {}: {e}",
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

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    parent_dir(path).join(format!(".{name}.{}.tmp", std::process::id()))
}

/// Writes through `write` into a temporary file, then renames it to `path`.
pub fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temp_path(path);
    let result = write(&tmp).and_then(|_| {
        std::fs::rename(&tmp, path).map_err(|e| Error::Io {
            path: path.to_path_buf(),
            source: e,
        })
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Writes the film in the format its extension names. `exposure` (in stops)
/// applies to PNG only; the float formats hold radiance.
pub fn write_image(film: &Film, path: &Path, exposure: f32) -> Result<()> {
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
            write_rgb_file(tmp, w, film.height as usize, |x, y| {
                let p = film.pixels[y * w + x];
                (p.x, p.y, p.z)
            })
            .map_err(|e| werr(e.to_string()))
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
        Format::Exr => {
            use exr::prelude::*;
            let img = read_first_rgba_layer_from_file(
                path,
                |res, _| (res.width(), Film::new(res.width() as u32, res.height() as u32)),
                |(w, film): &mut (usize, Film), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                    film.pixels[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
                },
            )
            .map_err(|e| perr(e.to_string()))?;
            Ok(img.layer_data.channel_data.pixels.1)
        }
        Format::Png => Err(perr("PNG is not a linear format".into())),
    }
}

fn read_pfm(bytes: &[u8]) -> std::result::Result<Film, String> {
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
    fn unknown_extension_and_missing_folder_are_refused() {
        assert!(Format::from_path(Path::new("x.jpg")).is_err());
        assert!(check_writable(Path::new("/nonexistent-folder-xyz/a.png")).is_err());
    }

    #[test]
    fn truncated_pfm_is_an_error() {
        let mut b = b"PF\n2 2\n-1.0\n".to_vec();
        b.extend_from_slice(&[0u8; 40]);
        assert!(read_pfm(&b).is_err());
    }
}
