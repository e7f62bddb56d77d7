//! Image error metrics for comparing a render against a reference, and a
//! false-colour picture of where they differ.

use crate::film::Film;
use crate::math::{luminance, Vec3};

/// Errors of an image against a reference of the same size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageError {
    /// Root mean squared error over all channels.
    pub rmse: f64,
    /// Mean over channels of (x - ref)^2 / (ref^2 + 0.01): the relative MSE
    /// used in rendering papers; the epsilon keeps black pixels finite.
    pub rel_mse: f64,
    /// Mean luminance of the image divided by that of the reference.
    pub luminance_ratio: f64,
}

const REL_EPS: f64 = 0.01;

/// Compares `img` with `reference`; `None` when the sizes differ.
pub fn compare(img: &Film, reference: &Film) -> Option<ImageError> {
    compare_below(img, reference, f32::INFINITY)
}

/// [`compare`] over the pixels whose reference luminance is at most
/// `max_luminance` and whose neighbours' is too (a one-pixel border around
/// every brighter pixel is left out). A visible light is hundreds of times
/// brighter than the room and identical in every integrator, so it would
/// otherwise dominate the RMSE and pull the luminance ratio towards 1; the
/// pixels on its edge mix it with the room in proportions that the slightest
/// shift of a pixel filter changes, so they would dominate instead.
pub fn compare_below(img: &Film, reference: &Film, max_luminance: f32) -> Option<ImageError> {
    if img.width != reference.width || img.height != reference.height {
        return None;
    }
    let (w, h) = (reference.width as usize, reference.height as usize);
    let bright: Vec<bool> = reference.pixels.iter().map(|p| luminance(*p) > max_luminance).collect();
    let left_out = |x: usize, y: usize| {
        let (x0, x1) = (x.saturating_sub(1), (x + 1).min(w - 1));
        let (y0, y1) = (y.saturating_sub(1), (y + 1).min(h - 1));
        (y0..=y1).any(|yy| (x0..=x1).any(|xx| bright[yy * w + xx]))
    };
    let (mut se, mut rel, mut li, mut lr, mut kept) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0usize);
    for (i, (a, b)) in img.pixels.iter().zip(&reference.pixels).enumerate() {
        if left_out(i % w, i / w) {
            continue;
        }
        kept += 1;
        for k in 0..3 {
            let (x, r) = (a[k] as f64, b[k] as f64);
            se += (x - r) * (x - r);
            rel += (x - r) * (x - r) / (r * r + REL_EPS);
        }
        li += luminance(*a) as f64;
        lr += luminance(*b) as f64;
    }
    let n = (kept * 3).max(1) as f64;
    Some(ImageError {
        rmse: (se / n).sqrt(),
        rel_mse: rel / n,
        luminance_ratio: if lr > 0.0 { li / lr } else { f64::NAN },
    })
}

/// `reference` box-filtered down to `width` x `height`, when its size is
/// the same integer multiple of that in both directions (1 included);
/// `None` otherwise. A reference is often rendered larger than the images
/// judged against it.
pub fn downsample_to(reference: &Film, width: u32, height: u32) -> Option<Film> {
    if width == 0 || height == 0 || !reference.width.is_multiple_of(width) || !reference.height.is_multiple_of(height) {
        return None;
    }
    let k = reference.width / width;
    if reference.height / height != k {
        return None;
    }
    if k == 1 {
        return Some(reference.clone());
    }
    let mut out = Film::new(width, height);
    let scale = 1.0 / (k * k) as f32;
    for y in 0..height {
        for x in 0..width {
            let mut sum = Vec3::ZERO;
            for dy in 0..k {
                for dx in 0..k {
                    sum += reference.get(x * k + dx, y * k + dy);
                }
            }
            out.pixels[(y * width + x) as usize] = sum * scale;
        }
    }
    Some(out)
}

/// A false-colour picture of the per-pixel relative error: black where the
/// images agree, through blue and green to red at `max_rel` relative error
/// and beyond. Returns 8-bit RGB.
pub fn error_image(img: &Film, reference: &Film, max_rel: f32) -> Vec<u8> {
    img.pixels
        .iter()
        .zip(&reference.pixels)
        .flat_map(|(a, b)| {
            let la = luminance(*a);
            let lb = luminance(*b);
            let e = ((la - lb).abs() / (lb.abs() + 0.1)) / max_rel;
            let c = heat(e.clamp(0.0, 1.0));
            [c.x, c.y, c.z].map(|v| (v * 255.0 + 0.5) as u8)
        })
        .collect()
}

/// Black -> blue -> green -> yellow -> red.
fn heat(t: f32) -> Vec3 {
    let stops = [
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
    ];
    let x = t * (stops.len() - 1) as f32;
    let i = (x as usize).min(stops.len() - 2);
    stops[i].lerp(stops[i + 1], x - i as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film(v: &[f32]) -> Film {
        Film {
            width: v.len() as u32,
            height: 1,
            pixels: v.iter().map(|&x| Vec3::splat(x)).collect(),
        }
    }

    #[test]
    fn identical_images_have_zero_error() {
        let a = film(&[0.1, 0.5, 2.0]);
        let e = compare(&a, &a).unwrap();
        assert_eq!(e.rmse, 0.0);
        assert_eq!(e.rel_mse, 0.0);
        assert!((e.luminance_ratio - 1.0).abs() < 1e-9);
    }

    #[test]
    fn errors_measure_the_difference() {
        let a = film(&[1.0, 1.0]);
        let b = film(&[2.0, 2.0]);
        let e = compare(&b, &a).unwrap();
        assert!((e.rmse - 1.0).abs() < 1e-9);
        assert!((e.rel_mse - 1.0 / 1.01).abs() < 1e-6);
        assert!((e.luminance_ratio - 2.0).abs() < 1e-6);
        assert!(compare(&film(&[1.0]), &a).is_none());
    }

    #[test]
    fn bright_reference_pixels_can_be_left_out() {
        let reference = film(&[1.0, 100.0]);
        let img = film(&[1.0, 50.0]);
        assert!(compare(&img, &reference).unwrap().rmse > 1.0);
        let e = compare_below(&img, &reference, 10.0).unwrap();
        assert_eq!((e.rmse, e.rel_mse, e.luminance_ratio), (0.0, 0.0, 1.0));
    }

    #[test]
    fn error_image_is_black_where_equal_and_red_where_far() {
        let r = film(&[1.0, 1.0]);
        let i = film(&[1.0, 3.0]);
        let px = error_image(&i, &r, 0.5);
        assert_eq!(&px[0..3], &[0, 0, 0]);
        assert_eq!(&px[3..6], &[255, 0, 0]);
    }
}
