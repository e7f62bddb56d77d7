//! pbrt-v4's named camera sensors, for a renderer that works in RGB.
//!
//! pbrt-v4 renders spectrally and sees radiance L(λ) through a camera's
//! measured responses r̄, ḡ, b̄; a 3 x 3 matrix fitted by least squares maps
//! the camera's RGB of the 24 ColorChecker patches lit by the white-balance
//! illuminant D(T) to their XYZ under the output space's D65, scaled so that
//! the camera's green of the illuminant is its luminance
//! (`PixelSensor`'s constructor). We compute that matrix the same way.
//!
//! Our film holds linear sRGB: what pbrt-v4's default CIE 1931 observer would
//! record. So the camera becomes a second fit, from one pipeline to the
//! other: the patches lit by D65 (the spectrum pbrt-v4 gives every RGB light
//! of an sRGB scene) seen once through the CIE observer and once through the
//! camera and its matrix; the 3 x 3 matrix that best maps the first set of
//! colours onto the second is what the camera does to a finished film. Lit
//! by D65, a camera balanced at 6500 K is then the identity within 0.3%; at
//! other temperatures it departs from a von Kries balance by the camera's
//! own colour rendering (BENCHMARKS.md, "Named camera sensors against pbrt-v4").
//!
//! What no 3 x 3 matrix can carry is how the camera departs from the
//! observer patch by patch (metamerism): a spectral renderer sees it, we do
//! not. Over the patches the fit leaves 1.4 to 1.9% on average at 6500 K.

use super::cameras::{CAMERAS, D65, DAYLIGHT_BASIS, SWATCHES};
use crate::scene::pbrt::cie::cie_1931;
use crate::scene::pbrt::spectrum::blackbody_normalized;
use glam::{DMat3, DVec3, Mat3};

/// pbrt-v4 integrates its sensors over whole nanometres in this range.
const LAMBDA: std::ops::RangeInclusive<u32> = 360..=830;

/// The sensor names pbrt-v4 knows (besides its default, "cie1931").
pub fn names() -> impl Iterator<Item = &'static str> {
    CAMERAS.iter().map(|(n, _)| *n)
}

/// A tabulated spectrum starting at `first` nm, every `step` nm, linearly
/// interpolated and zero outside its range (pbrt-v4's `PiecewiseLinearSpectrum`).
fn tabulated(values: &[f32], first: f64, step: f64, lambda: f64) -> f64 {
    let x = (lambda - first) / step;
    if x < 0.0 || x > (values.len() - 1) as f64 {
        return 0.0;
    }
    let i = (x as usize).min(values.len() - 2);
    let t = x - i as f64;
    values[i] as f64 * (1.0 - t) + values[i + 1] as f64 * t
}

fn d65(lambda: f64) -> f64 {
    tabulated(&D65, 360.0, 5.0, lambda)
}

/// pbrt-v4's `Spectra::D`: the CIE daylight illuminant at the correlated
/// colour temperature `kelvin * 1.4388 / 1.4380`, a blackbody below 4000 K.
fn daylight(kelvin: f64) -> impl Fn(f64) -> f64 {
    let cct = kelvin * 1.4388 / 1.4380;
    let (x, y) = super::illuminant_xy(kelvin as f32);
    let (x, y) = (x as f64, y as f64);
    let m = 0.0241 + 0.2562 * x - 0.7341 * y;
    let m1 = (-1.3515 - 1.7703 * x + 5.9114 * y) / m;
    let m2 = (0.0300 - 31.4424 * x + 30.0717 * y) / m;
    let basis: Vec<f32> = DAYLIGHT_BASIS
        .iter()
        .map(|s| s[0] + s[1] * m1 as f32 + s[2] * m2 as f32)
        .collect();
    move |lambda| {
        if cct < 4000.0 {
            blackbody_normalized(lambda, cct)
        } else {
            0.01 * tabulated(&basis, 360.0, 5.0, lambda)
        }
    }
}

/// The sum over whole nanometres of `reflectance x illuminant x` each of
/// three responses.
fn project(
    reflectance: &dyn Fn(f64) -> f64,
    illuminant: &dyn Fn(f64) -> f64,
    responses: &dyn Fn(f64) -> DVec3,
) -> DVec3 {
    LAMBDA
        .map(|l| {
            let l = l as f64;
            responses(l) * (reflectance(l) * illuminant(l))
        })
        .sum()
}

/// The matrix M minimising the sum of |M a_i - b_i|^2 (normal equations);
/// `None` when the a_i do not span three dimensions.
fn least_squares(a: &[DVec3], b: &[DVec3]) -> Option<DMat3> {
    let outer = |u: DVec3, v: DVec3| DMat3::from_cols(u * v.x, u * v.y, u * v.z);
    let ata: DMat3 = a.iter().map(|&x| outer(x, x)).fold(DMat3::ZERO, |s, m| s + m);
    let bta: DMat3 = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| outer(y, x))
        .fold(DMat3::ZERO, |s, m| s + m);
    let det = ata.determinant();
    (det.is_finite() && det.abs() > 1e-12 * ata.to_cols_array().iter().map(|v| v.abs()).fold(0.0, f64::max).powi(3))
        .then(|| bta * ata.inverse())
}

/// The linear-sRGB-to-linear-sRGB matrix of camera `name` balanced at
/// `kelvin` (see the module documentation); `None` for a name pbrt-v4 does
/// not know.
pub fn camera_matrix(name: &str, kelvin: f32) -> Option<Mat3> {
    let (_, curves) = CAMERAS.iter().find(|(n, _)| *n == name)?;
    let camera = |l: f64| DVec3::from_array([0, 1, 2].map(|c| tabulated(&curves[c], 380.0, 10.0, l)));
    let observer = |l: f64| DVec3::from_array(cie_1931(l));
    let patches: Vec<Box<dyn Fn(f64) -> f64>> = SWATCHES
        .iter()
        .map(|s| Box::new(move |l| tabulated(s, 380.0, 10.0, l)) as Box<dyn Fn(f64) -> f64>)
        .collect();
    let white = |_: f64| 1.0;

    // pbrt-v4's XYZFromSensorRGB: patches under D(T) through the camera,
    // each normalised by the camera's green of the illuminant, onto their
    // XYZ under D65 normalised by its luminance, times the camera's ratio
    // of luminance to green for the illuminant.
    let illuminant = daylight(kelvin as f64);
    let cam_white = project(&white, &illuminant, &camera);
    let obs_white_d = project(&white, &illuminant, &observer);
    let obs_white_65 = project(&white, &d65, &observer);
    let scale = obs_white_d.y / cam_white.y;
    let camera_rgb: Vec<DVec3> = patches
        .iter()
        .map(|p| project(p, &illuminant, &camera) / cam_white.y)
        .collect();
    let xyz_out: Vec<DVec3> = patches
        .iter()
        .map(|p| project(p, &d65, &observer) / obs_white_65.y * scale)
        .collect();
    let xyz_from_camera = least_squares(&camera_rgb, &xyz_out)?;

    // Our film's colours of the patches under D65 and the camera's, both in
    // linear sRGB; the matrix from the first to the second.
    let rgb_from_xyz = super::xyz_from_srgb().inverse().as_dmat3();
    let ours: Vec<DVec3> = patches
        .iter()
        .map(|p| rgb_from_xyz * project(p, &d65, &observer))
        .collect();
    let theirs: Vec<DVec3> = patches
        .iter()
        .map(|p| rgb_from_xyz * xyz_from_camera * project(p, &d65, &camera))
        .collect();
    least_squares(&ours, &theirs).map(|m| m.as_mat3())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_camera_balanced_for_daylight_is_the_observer_under_daylight() {
        // Lit by D65 and balanced at 6500 K, pbrt-v4's fit makes a camera
        // record the patches' colours; what is left is no more than a few
        // tenths of a percent (a wrong normalisation or a transposed fit
        // is tens of percent off).
        assert_eq!(names().count(), 17);
        for name in names() {
            let m = camera_matrix(name, 6500.0).unwrap();
            let d = (m - Mat3::IDENTITY).to_cols_array();
            assert!(d.iter().all(|v| v.abs() < 4e-3), "{name}: {m:?}");
        }
    }

    #[test]
    fn every_camera_has_a_finite_matrix_over_the_whole_temperature_range() {
        let (lo, hi) = super::super::KELVIN_RANGE;
        for name in names() {
            for kelvin in [lo, 2000.0, 3999.0, 4001.0, 25_000.0, hi] {
                let m = camera_matrix(name, kelvin).unwrap();
                assert!(m.is_finite() && m.determinant().abs() > 1e-3, "{name} {kelvin}: {m:?}");
            }
        }
    }

    #[test]
    fn unknown_cameras_have_no_matrix() {
        assert!(camera_matrix("cie1931", 6500.0).is_none());
        assert!(camera_matrix("canon_eos_100", 6500.0).is_none());
    }

    #[test]
    fn a_camera_balanced_for_tungsten_turns_daylight_blue_as_a_von_kries_balance_does() {
        // Balanced at 3200 K, daylight white comes out blue: red down, blue
        // up by about the factors of the Bradford balance at 3200 K, not
        // exactly (the camera's own colour rendering), and with the same
        // luminance to a few percent.
        for name in ["canon_eos_100d", "nikon_d850", "sony_ilce_9"] {
            let m = camera_matrix(name, 3200.0).unwrap();
            let w = super::super::white_balance(3200.0);
            let (cw, ww) = (m * glam::Vec3::ONE, w * glam::Vec3::ONE);
            assert!(cw.x < 0.5 && cw.z > 2.0, "{name}: {cw}");
            for c in 0..3 {
                assert!((cw[c] / ww[c] - 1.0).abs() < 0.2, "{name}: {cw} against {ww}");
            }
            let y = |v: glam::Vec3| 0.2126729 * v.x + 0.7151522 * v.y + 0.072175 * v.z;
            assert!((y(cw) / y(ww) - 1.0).abs() < 0.06, "{name}: {cw} against {ww}");
        }
    }

    #[test]
    fn daylight_spectra_have_the_chromaticity_of_their_temperature() {
        // The spectrum from the basis has the chromaticity the locus gives
        // (and the blackbody below 4000 K its Planckian one), integrated
        // through the observer.
        for kelvin in [3000.0, 4500.0, 6500.0, 9000.0] {
            let s = daylight(kelvin);
            let xyz = project(&|_| 1.0, &s, &|l| DVec3::from_array(cie_1931(l)));
            let (x, y) = (xyz.x / xyz.element_sum(), xyz.y / xyz.element_sum());
            let (ex, ey) = super::super::illuminant_xy(kelvin as f32);
            assert!(
                (x - ex as f64).abs() < 2e-3 && (y - ey as f64).abs() < 2e-3,
                "{kelvin}: {x} {y} vs {ex} {ey}"
            );
        }
    }
}
