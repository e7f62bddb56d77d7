//! Spectra as pbrt-v4 scene files give them, and their conversion to linear
//! sRGB where the reader does one (blackbody; sampled spectra on request).
//!
//! # The conversion
//!
//! pbrt-v4 renders spectrally; this renderer works in linear sRGB. A spectrum
//! `S(λ)` is taken to CIE 1931 XYZ as pbrt-v4's `SpectrumToXYZ` does,
//! `X = ∫ S x̄ dλ / ∫ ȳ dλ` (likewise Y, Z) over 360-830 nm in 1 nm steps,
//! and XYZ to linear sRGB (D65, no chromatic adaptation: what pbrt-v4's RGB
//! film writes with its default `cie1931` sensor) by the standard matrix.
//! The colour matching functions are the multi-lobe analytic fit of Wyman,
//! Sloan and Shirley, "Simple Analytic Approximations to the CIE XYZ Color
//! Matching Functions" (JCGT 2(2), 2013), whose error is well under the
//! differences between spectral and RGB rendering; `∫ ȳ` is taken of the same
//! fit, so a constant spectrum of 1 has Y = 1 exactly.
//!
//! A `blackbody` value is pbrt-v4's `BlackbodySpectrum`: Planck's law at the
//! temperature, divided by its value at the peak wavelength (Wien's law,
//! 2.8977721e-3 m K / T), so the spectrum's maximum is 1; [`blackbody_rgb`] is
//! that spectrum's colour by the conversion above.
//!
//! pbrt-v4's lights then divide their spectrum by its photometric value
//! (`scale /= SpectrumToPhotometric(L)`, lights.cpp) for every spectrum but
//! an RGB one, whose illuminant is already normalised: a blackbody or sampled
//! emission spectrum therefore shines with luminance Y = 1 times the light's
//! `scale`. [`SpectrumValue::light_rgb`] does that normalisation.

use crate::math::Vec3;

/// The named spectra pbrt-v4 knows (`GetNamedSpectrum`), other than camera
/// sensor curves: the conversion of a named spectrum is left to whoever
/// uses it (a conductor's `metal-Cu-eta`, a dielectric's `glass-BK7`).
pub const NAMED_SPECTRA: &[&str] = &[
    "glass-BK7",
    "glass-BAF10",
    "glass-FK51A",
    "glass-LASF9",
    "glass-F5",
    "glass-F10",
    "glass-F11",
    "metal-Ag-eta",
    "metal-Ag-k",
    "metal-Al-eta",
    "metal-Al-k",
    "metal-Au-eta",
    "metal-Au-k",
    "metal-Cu-eta",
    "metal-Cu-k",
    "metal-CuZn-eta",
    "metal-CuZn-k",
    "metal-MgO-eta",
    "metal-MgO-k",
    "metal-TiO2-eta",
    "metal-TiO2-k",
    "stdillum-A",
    "stdillum-D50",
    "stdillum-D65",
    "stdillum-F1",
    "stdillum-F2",
    "stdillum-F3",
    "stdillum-F4",
    "stdillum-F5",
    "stdillum-F6",
    "stdillum-F7",
    "stdillum-F8",
    "stdillum-F9",
    "stdillum-F10",
    "stdillum-F11",
    "stdillum-F12",
    "illum-acesD60",
];

/// The index of refraction at 550 nm of pbrt-v4's named glass spectra
/// (interpolated in its tables, which are Schott's: BK7's is 1.5168 at the
/// sodium d line, 587.6 nm, as the catalogue says).
pub fn glass_eta_550(name: &str) -> Option<f32> {
    Some(match name {
        "glass-BK7" => 1.518_54,
        "glass-BAF10" => 1.673_05,
        "glass-FK51A" => 1.487_80,
        "glass-LASF9" => 1.855_81,
        "glass-F5" => 1.677_09,
        "glass-F10" => 1.733_57,
        "glass-F11" => 1.791_12,
        _ => return None,
    })
}

pub fn is_named_spectrum(name: &str) -> bool {
    NAMED_SPECTRA.contains(&name)
}

/// A piecewise-linear spectrum given inline as wavelength (nm) / value pairs,
/// wavelengths strictly increasing; zero outside the given range, as pbrt-v4's
/// `PiecewiseLinearSpectrum`.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledSpectrum {
    pub lambda: Vec<f32>,
    pub value: Vec<f32>,
}

impl SampledSpectrum {
    /// The value at `lambda` nm, linearly interpolated.
    pub fn eval(&self, lambda: f32) -> f32 {
        let (l, v) = (&self.lambda, &self.value);
        if l.is_empty() || lambda < l[0] || lambda > l[l.len() - 1] {
            return 0.0;
        }
        if l.len() == 1 || v.len() != l.len() {
            return v.first().copied().unwrap_or(0.0);
        }
        let i = l.partition_point(|&x| x <= lambda).clamp(1, l.len() - 1);
        let (l0, l1) = (l[i - 1], l[i]);
        let t = if l1 > l0 { (lambda - l0) / (l1 - l0) } else { 0.0 };
        v[i - 1] + t * (v[i] - v[i - 1])
    }

    /// The spectrum's colour as emitted (see the module documentation).
    pub fn to_rgb(&self) -> Vec3 {
        xyz_to_linear_srgb(spectrum_to_xyz(|l| self.eval(l)))
    }
}

/// A spectrum-valued parameter (`rgb`, `blackbody` or `spectrum`).
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumValue {
    /// An `rgb` value in the parameter's colour space (see `Param::color_space`).
    Rgb(Vec3),
    /// A `blackbody` temperature in kelvin.
    Blackbody(f32),
    /// One of [`NAMED_SPECTRA`].
    Named(String),
    /// Inline wavelength / value pairs.
    Sampled(SampledSpectrum),
}

impl SpectrumValue {
    /// Linear sRGB for an `rgb` value (as given), a blackbody (peak-normalised
    /// spectrum) or a sampled spectrum (as emitted); None for a named one.
    pub fn to_rgb(&self) -> Option<Vec3> {
        match self {
            SpectrumValue::Rgb(c) => Some(*c),
            SpectrumValue::Blackbody(t) => Some(blackbody_rgb(*t)),
            SpectrumValue::Named(_) => None,
            SpectrumValue::Sampled(s) => Some(s.to_rgb()),
        }
    }

    /// The radiance (or intensity) colour a pbrt-v4 light gives this
    /// spectrum before its `scale`: an RGB value as it is, any other
    /// spectrum normalised to luminance 1 (pbrt's division by
    /// `SpectrumToPhotometric`). None for a named spectrum or a spectrum
    /// without luminance.
    pub fn light_rgb(&self) -> Option<Vec3> {
        match self {
            SpectrumValue::Rgb(c) => Some(*c),
            SpectrumValue::Named(_) => None,
            SpectrumValue::Blackbody(t) => normalise_luminance(blackbody_xyz(*t)),
            SpectrumValue::Sampled(s) => normalise_luminance(spectrum_to_xyz(|l| s.eval(l))),
        }
    }
}

fn normalise_luminance(xyz: Vec3) -> Option<Vec3> {
    (xyz.y > 0.0 && xyz.is_finite()).then(|| xyz_to_linear_srgb(xyz / xyz.y))
}

/// Planck's law: spectral radiance of a blackbody at `lambda_nm` and `kelvin`
/// (W sr^-1 m^-3); 0 for a temperature that is not positive.
pub fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    if kelvin <= 0.0 {
        return 0.0;
    }
    const C: f64 = 299_792_458.0;
    const H: f64 = 6.626_070_15e-34;
    const KB: f64 = 1.380_649e-23;
    let l = lambda_nm * 1e-9;
    (2.0 * H * C * C) / (l.powi(5) * (((H * C) / (l * KB * kelvin)).exp_m1()))
}

/// pbrt-v4's `BlackbodySpectrum`: Planck's law divided by its peak value.
pub fn blackbody_normalized(lambda_nm: f64, kelvin: f64) -> f64 {
    if kelvin <= 0.0 {
        return 0.0;
    }
    let peak_nm = 2.897_772_1e-3 / kelvin * 1e9;
    let v = planck(lambda_nm, kelvin) / planck(peak_nm, kelvin);
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

/// CIE XYZ of the peak-normalised blackbody spectrum.
pub fn blackbody_xyz(kelvin: f32) -> Vec3 {
    spectrum_to_xyz(|l| blackbody_normalized(l as f64, kelvin as f64) as f32)
}

/// Linear sRGB of the peak-normalised blackbody spectrum (see the module
/// documentation).
pub fn blackbody_rgb(kelvin: f32) -> Vec3 {
    xyz_to_linear_srgb(blackbody_xyz(kelvin))
}

/// One lobe of the Wyman-Sloan-Shirley fit: a Gaussian with different widths
/// below and above its mean.
fn lobe(lambda: f64, mean: f64, below: f64, above: f64) -> f64 {
    let t = (lambda - mean) / if lambda < mean { below } else { above };
    (-0.5 * t * t).exp()
}

/// CIE 1931 2° colour matching functions (x̄, ȳ, z̄), analytic fit.
pub fn cie_xyz_bar(lambda: f64) -> [f64; 3] {
    let x = 1.056 * lobe(lambda, 599.8, 37.9, 31.0) + 0.362 * lobe(lambda, 442.0, 16.0, 26.7)
        - 0.065 * lobe(lambda, 501.1, 20.4, 26.2);
    let y = 0.821 * lobe(lambda, 568.8, 46.9, 40.5) + 0.286 * lobe(lambda, 530.9, 16.3, 31.1);
    let z = 1.217 * lobe(lambda, 437.0, 11.8, 36.0) + 0.681 * lobe(lambda, 459.0, 26.0, 13.8);
    [x, y, z]
}

const LAMBDA_MIN: u32 = 360;
const LAMBDA_MAX: u32 = 830;

/// XYZ of a spectrum, `∫ S x̄ / ∫ ȳ` over 360-830 nm in 1 nm steps.
pub fn spectrum_to_xyz(s: impl Fn(f32) -> f32) -> Vec3 {
    let (mut x, mut y, mut z, mut y_integral) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for l in LAMBDA_MIN..=LAMBDA_MAX {
        let [xb, yb, zb] = cie_xyz_bar(l as f64);
        let v = s(l as f32) as f64;
        x += v * xb;
        y += v * yb;
        z += v * zb;
        y_integral += yb;
    }
    Vec3::new(
        (x / y_integral) as f32,
        (y / y_integral) as f32,
        (z / y_integral) as f32,
    )
}

/// CIE XYZ to linear sRGB (D65 white).
pub fn xyz_to_linear_srgb(xyz: Vec3) -> Vec3 {
    Vec3::new(
        3.240_454_2 * xyz.x - 1.537_138_5 * xyz.y - 0.498_531_4 * xyz.z,
        -0.969_266 * xyz.x + 1.876_010_8 * xyz.y + 0.041_556 * xyz.z,
        0.055_643_4 * xyz.x - 0.204_025_9 * xyz.y + 1.057_225_2 * xyz.z,
    )
}

/// Luminance (CIE Y) of a linear sRGB colour.
pub fn luminance(rgb: Vec3) -> f32 {
    0.212_639 * rgb.x + 0.715_169 * rgb.y + 0.072_192 * rgb.z
}
