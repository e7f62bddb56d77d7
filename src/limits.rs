//! Up-front memory estimates, so that an absurd resolution or sample count is
//! refused with a message before any work starts rather than failing hours in.

use crate::error::{Error, Result};

/// Largest image side we accept; beyond it the film alone would not fit.
pub const MAX_SIDE: u32 = 32_768;
/// Largest pixel count: 2^28 pixels is 3 GiB of float RGB film.
pub const MAX_PIXELS: u64 = 1 << 28;

/// Refuses an image size outside [`MAX_SIDE`] and [`MAX_PIXELS`], with a
/// message naming the offending dimension (the caller adds where it came from).
pub fn check_resolution(width: u32, height: u32) -> std::result::Result<(), String> {
    for (name, v) in [("width", width), ("height", height)] {
        if v == 0 || v > MAX_SIDE {
            return Err(format!("{name} {v} must be between 1 and {MAX_SIDE}"));
        }
    }
    let pixels = width as u64 * height as u64;
    if pixels > MAX_PIXELS {
        return Err(format!(
            "{width}x{height} is {pixels} pixels, more than the limit of {MAX_PIXELS}"
        ));
    }
    Ok(())
}

/// Memory the system says is available (Linux `MemAvailable`), if known.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses `bytes` for `what` when it exceeds the available memory (or
/// `fallback` where that is unknown).
pub fn check_memory(what: &str, bytes: u64, fallback: u64) -> Result<()> {
    let limit = available_memory().unwrap_or(fallback);
    if bytes > limit {
        return Err(Error::InvalidSetting(format!(
            "{what} needs about {} but only {} is available",
            human_bytes(bytes),
            human_bytes(limit)
        )));
    }
    Ok(())
}

/// Bytes a render of `pixels` pixels holds at its peak: the fixed-point
/// sums of the samples so far and of the pass in flight, the film (3 x f32)
/// and the 8-bit output copy.
pub fn film_bytes(pixels: u64) -> u64 {
    pixels * (2 * std::mem::size_of::<crate::film::PixelSum>() as u64 + 12 + 3)
}

pub fn human_bytes(b: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    format!("{v:.1} {}", UNITS[u])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_requests_are_refused_with_the_estimate() {
        let e = check_memory("a 10^15-byte thing", 1_000_000_000_000_000, 1 << 30).unwrap_err();
        let m = e.to_string();
        assert!(m.contains("needs about") && m.contains("TiB"), "{m}");
        assert!(check_memory("a small thing", 1024, 1 << 30).is_ok());
        assert_eq!(human_bytes(1536), "1.5 KiB");
    }
}
