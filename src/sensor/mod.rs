//! The film's sensor: its white balance, or a measured camera's response.
//!
//! pbrt-v4's films see radiance through a `PixelSensor`. Its default, the
//! CIE 1931 observer, records XYZ, which the film turns into the output
//! colour space: in an RGB renderer working in linear sRGB, no change at
//! all. Given a colour temperature (`whitebalance`), the sensor also adapts
//! colours as a camera's white balance does: light of a daylight illuminant
//! of that temperature comes out as the output space's white. The
//! adaptation is von Kries scaling in the Bradford cone space (pbrt-v4's
//! `WhiteBalance`), from the illuminant's chromaticity to sRGB's D65 white.
//!
//! The illuminant of a temperature is pbrt-v4's `Spectra::D`: the CIE
//! daylight locus at the correlated colour temperature `T * 1.4388 /
//! 1.4380` (the second radiation constant's revision), a blackbody below
//! 4000 K where the daylight series is not defined. Its chromaticity is
//! taken from the locus formulas directly where pbrt-v4 integrates the
//! spectrum; the two differ by 4e-4 in x and y at most, a few tenths of a
//! percent in the balanced colour.
//!
//! Sensors with measured spectral responses (pbrt-v4's camera names) are
//! matrices on the finished film too, fitted from the cameras' spectra
//! (`camera`).

use crate::math::Vec3;
use glam::Mat3;

mod camera;
mod cameras;

pub use camera::{camera_matrix, names as camera_names};

/// The default sensor: the CIE 1931 observer (pbrt-v4's "cie1931").
pub const OBSERVER: &str = "cie1931";

/// The sensors a film may name: the observer, then pbrt-v4's cameras.
pub const SENSORS: [&str; 18] = [
    "cie1931",
    "canon_eos_100d",
    "canon_eos_1dx_mkii",
    "canon_eos_200d",
    "canon_eos_200d_mkii",
    "canon_eos_5d",
    "canon_eos_5d_mkii",
    "canon_eos_5d_mkiii",
    "canon_eos_5d_mkiv",
    "canon_eos_5ds",
    "canon_eos_m",
    "hasselblad_l1d_20c",
    "nikon_d810",
    "nikon_d850",
    "sony_ilce_6400",
    "sony_ilce_7m3",
    "sony_ilce_7rm3",
    "sony_ilce_9",
];

/// What the film's sensor does to a finished film in linear sRGB: a named
/// camera's matrix (balanced at `kelvin`, 6500 K unless given, as pbrt-v4
/// balances cameras), or the observer's white balance when a temperature
/// is given; `None`: the film as it is.
pub fn film_matrix(sensor: &str, kelvin: Option<f32>) -> Option<Mat3> {
    if sensor == OBSERVER {
        kelvin.map(white_balance)
    } else {
        camera_matrix(sensor, kelvin.unwrap_or(6500.0))
    }
}

/// Temperatures a white balance may name, in kelvin: below 1000 K a
/// blackbody has no visible light to speak of, and the daylight locus is
/// a formula for up to 25,000 K that stops changing long before 100,000.
pub const KELVIN_RANGE: (f32, f32) = (1000.0, 100_000.0);

/// sRGB's white point (D65) as pbrt-v4's colour space computes it.
const SRGB_WHITE: (f32, f32) = (0.3127, 0.3290);

/// Linear sRGB to CIE XYZ (the sRGB primaries and D65), by columns.
fn xyz_from_srgb() -> Mat3 {
    Mat3::from_cols_array(&[
        0.412_456_4,
        0.212_672_9,
        0.019_333_9,
        0.357_576_1,
        0.715_152_2,
        0.119_192,
        0.180_437_5,
        0.072_175,
        0.950_304_1,
    ])
}

/// The Bradford cone response matrix (pbrt-v4's `LMSFromXYZ`), by columns.
fn lms_from_xyz() -> Mat3 {
    Mat3::from_cols_array(&[
        0.8951, -0.7502, 0.0389, 0.2664, 1.7135, -0.0685, -0.1614, 0.0367, 1.0296,
    ])
}

/// XYZ of chromaticity (x, y) at luminance Y = 1.
fn xyz_of(xy: (f32, f32)) -> Vec3 {
    let (x, y) = xy;
    Vec3::new(x / y, 1.0, (1.0 - x - y) / y)
}

/// The chromaticity of pbrt-v4's illuminant for a white balance of
/// `kelvin` (see the module documentation).
pub fn illuminant_xy(kelvin: f32) -> (f32, f32) {
    let cct = kelvin as f64 * 1.4388 / 1.4380;
    if cct < 4000.0 {
        return planckian_xy(cct);
    }
    let (t, t2, t3) = (cct, cct * cct, cct * cct * cct);
    let x = if cct <= 7000.0 {
        -4.607e9 / t3 + 2.9678e6 / t2 + 0.09911e3 / t + 0.244063
    } else {
        -2.0064e9 / t3 + 1.9018e6 / t2 + 0.24748e3 / t + 0.23704
    };
    let y = -3.0 * x * x + 2.870 * x - 0.275;
    (x as f32, y as f32)
}

/// The chromaticity of a blackbody at `kelvin`, by Krystek's rational
/// approximation of the Planckian locus in CIE 1960 (u, v) ("An algorithm to
/// calculate correlated colour temperature", Color Res. Appl. 10(1), 1985;
/// 1000 to 15,000 K). Against the CIE 1931 tables it is within 4e-4 in x
/// and y; the analytic colour matching functions the pbrt reader converts
/// spectra with miss the locus by 1e-3 at 3000 K, which is 2% of red in a
/// balanced image.
fn planckian_xy(kelvin: f64) -> (f32, f32) {
    let t = kelvin;
    let u = (0.860_117_757 + 1.541_182_54e-4 * t + 1.286_412_12e-7 * t * t)
        / (1.0 + 8.424_202_35e-4 * t + 7.081_451_63e-7 * t * t);
    let v = (0.317_398_726 + 4.228_062_45e-5 * t + 4.204_816_91e-8 * t * t)
        / (1.0 - 2.897_418_16e-5 * t + 1.614_560_53e-7 * t * t);
    let d = 2.0 * u - 8.0 * v + 4.0;
    ((3.0 * u / d) as f32, (2.0 * v / d) as f32)
}

/// The XYZ-to-XYZ matrix that adapts white `from` to white `to` (von Kries
/// in Bradford's cone space).
pub fn adaptation(from: (f32, f32), to: (f32, f32)) -> Mat3 {
    let lms = lms_from_xyz();
    let (src, dst) = (lms * xyz_of(from), lms * xyz_of(to));
    lms.inverse() * Mat3::from_diagonal(dst / src) * lms
}

/// The linear-sRGB-to-linear-sRGB matrix of a white balance at `kelvin`:
/// light of that temperature's illuminant becomes sRGB white.
pub fn white_balance(kelvin: f32) -> Mat3 {
    let to_xyz = xyz_from_srgb();
    to_xyz.inverse() * adaptation(illuminant_xy(kelvin), SRGB_WHITE) * to_xyz
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sensor_names_are_the_observer_and_every_camera() {
        assert_eq!(SENSORS[0], OBSERVER);
        assert!(SENSORS[1..].iter().copied().eq(camera_names()));
        for name in &SENSORS[1..] {
            assert!(
                film_matrix(name, None).is_some() && film_matrix(name, Some(3000.0)).is_some(),
                "{name}"
            );
        }
        assert_eq!(film_matrix(OBSERVER, None), None);
        assert_eq!(film_matrix(OBSERVER, Some(3000.0)), Some(white_balance(3000.0)));
    }

    fn close(a: Mat3, b: Mat3, tol: f32) -> bool {
        (a - b).to_cols_array().iter().all(|d| d.abs() <= tol)
    }

    #[test]
    fn bradford_adaptation_is_the_published_d50_to_d65_matrix() {
        // Lindbloom's Bradford matrix from D50 to D65 (rows), an independent
        // source for the cone matrix, its inverse and the von Kries step.
        let published = Mat3::from_cols_array(&[
            0.955_576_6,
            -0.028_289_5,
            0.012_298_2,
            -0.023_039_3,
            1.009_941_6,
            -0.020_483,
            0.063_163_6,
            0.021_007_7,
            1.329_909_8,
        ]);
        let d50 = (0.345_67, 0.358_5);
        let d65 = (0.312_73, 0.329_03);
        let m = adaptation(d50, d65);
        assert!(close(m, published, 2e-4), "{m:?}");
    }

    #[test]
    fn light_of_the_balanced_temperature_becomes_white() {
        let to_rgb = xyz_from_srgb().inverse();
        for kelvin in [1500.0, 2700.0, 3999.0, 4001.0, 5500.0, 6500.0, 9000.0, 25_000.0] {
            let light = to_rgb * xyz_of(illuminant_xy(kelvin));
            let out = white_balance(kelvin) * light;
            assert!(
                (out - Vec3::ONE).abs().max_element() < 2e-3,
                "{kelvin} K: {light} -> {out}"
            );
        }
    }

    #[test]
    fn daylight_locus_and_blackbody_give_known_whites() {
        // CIE D65 is the daylight illuminant of 6504 K (6500 K before the
        // constant's revision, which pbrt-v4 applies to the value given).
        let (x, y) = illuminant_xy(6500.0);
        assert!((x - 0.3127).abs() < 3e-4 && (y - 0.3290).abs() < 5e-4, "{x} {y}");
        // D50 and D75 likewise.
        let (x, y) = illuminant_xy(5000.0);
        assert!((x - 0.3457).abs() < 3e-4 && (y - 0.3585).abs() < 5e-4, "{x} {y}");
        let (x, y) = illuminant_xy(7500.0);
        assert!((x - 0.2990).abs() < 3e-4 && (y - 0.3149).abs() < 5e-4, "{x} {y}");
        // Blackbodies, against the CIE 1931 tables: CIE illuminant A (2856 K),
        // 1000 K, 2000 K and 3000 K.
        let scale = 1.4380 / 1.4388;
        for (kelvin, x0, y0) in [
            (2856.0, 0.447_57, 0.407_45),
            (1000.0, 0.652_75, 0.344_46),
            (2000.0, 0.526_68, 0.413_30),
            (3001.7, 0.436_81, 0.404_03),
        ] {
            let (x, y) = illuminant_xy(kelvin * scale);
            assert!((x - x0).abs() < 4e-4 && (y - y0).abs() < 4e-4, "{kelvin} K: {x} {y}");
        }
    }

    #[test]
    fn warm_light_is_balanced_by_cutting_red_and_lifting_blue() {
        let m = white_balance(3000.0);
        let grey = m * Vec3::splat(0.5);
        assert!(grey.x < 0.5 && grey.z > 0.5, "{grey}");
        let m = white_balance(10_000.0);
        let grey = m * Vec3::splat(0.5);
        assert!(grey.x > 0.5 && grey.z < 0.5, "{grey}");
        // Near D65 the balance is nearly nothing.
        assert!(close(white_balance(6500.0), Mat3::IDENTITY, 6e-3));
    }
}
