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

/// Sellmeier's coefficients (B1, B2, B3, C1, C2, C3; C in square
/// micrometres) of the Schott glasses behind pbrt-v4's named glass spectra,
/// from Schott's catalogue. pbrt-v4's tables are these dispersion formulas
/// sampled every 20 nm or so: BK7's agree to 1e-13, the others within 5e-4
/// (a test checks a few of their values).
fn glass_sellmeier(name: &str) -> Option<[f64; 6]> {
    Some(match name {
        "glass-BK7" => [
            1.039_612_12,
            0.231_792_344,
            1.010_469_45,
            0.006_000_698_67,
            0.020_017_914_4,
            103.560_653,
        ],
        "glass-BAF10" => [
            1.585_149_5,
            0.143_559_385,
            1.085_212_69,
            0.009_266_812_82,
            0.042_448_980_5,
            105.613_573,
        ],
        "glass-FK51A" => [
            0.971_247_817,
            0.216_901_417,
            0.904_651_666,
            0.004_723_019_95,
            0.015_357_561_2,
            168.681_33,
        ],
        "glass-LASF9" => [
            2.000_295_47,
            0.298_926_886,
            1.806_918_43,
            0.012_142_601_7,
            0.053_873_623_6,
            156.530_829,
        ],
        // pbrt-v4's F5, F10 and F11 are Schott's SF5, SF10 and SF11.
        "glass-F5" => [
            1.524_818_89,
            0.187_085_527,
            1.427_290_15,
            0.011_254_756,
            0.058_899_539_2,
            129.141_675,
        ],
        "glass-F10" => [
            1.621_539_02,
            0.256_287_842,
            1.644_475_52,
            0.012_224_145_7,
            0.059_573_677_5,
            147.468_793,
        ],
        "glass-F11" => [
            1.737_596_95,
            0.313_747_346,
            1.898_781_01,
            0.013_188_707,
            0.062_306_814_2,
            155.236_29,
        ],
        _ => return None,
    })
}

/// The index of refraction of one of pbrt-v4's named glasses at `lambda_nm`.
pub fn glass_eta(name: &str, lambda_nm: f64) -> Option<f64> {
    let [b1, b2, b3, c1, c2, c3] = glass_sellmeier(name)?;
    let l2 = (lambda_nm * 1e-3).powi(2);
    Some((1.0 + b1 * l2 / (l2 - c1) + b2 * l2 / (l2 - c2) + b3 * l2 / (l2 - c3)).sqrt())
}

/// The index of refraction at 550 nm of pbrt-v4's named glass spectra
/// (BK7's is 1.5168 at the sodium d line, 587.6 nm, as the catalogue says).
pub fn glass_eta_550(name: &str) -> Option<f32> {
    glass_eta(name, 550.0).map(|e| e as f32)
}

/// The index of refraction each colour channel sees, for an index `eta(λ)`
/// that varies with wavelength: its mean over 360-830 nm weighted by the
/// channel's colour matching function (the CIE functions taken to linear
/// sRGB, negative lobes and all). A spectral renderer's channel `c` is
/// `∫ I(λ) c̄(λ) dλ` of images `I(λ)` rendered each with the index at `λ`;
/// to first order in the index, that is the image rendered with this mean.
/// A constant index gives itself in every channel.
pub fn channel_etas(eta: impl Fn(f64) -> f64) -> Vec3 {
    let (mut sum, mut weight) = ([0.0f64; 3], [0.0f64; 3]);
    for l in LAMBDA_MIN..=LAMBDA_MAX {
        let [x, y, z] = cie_xyz_bar(l as f64);
        let rgb = xyz_to_linear_srgb(Vec3::new(x as f32, y as f32, z as f32));
        let e = eta(l as f64);
        for c in 0..3 {
            let w = rgb[c] as f64;
            sum[c] += w * e;
            weight[c] += w;
        }
    }
    Vec3::from_array([0, 1, 2].map(|c| (sum[c] / weight[c]) as f32))
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

/// The linear sRGB pbrt-v4's film records for the peak-normalised blackbody
/// where nothing normalised it (the temperature of a medium's grid): its
/// XYZ sensor integrates S x̄ over nanometres without dividing by the
/// integral of ȳ (106.86), which lights' spectra make up for by being
/// normalised to that luminance.
pub fn blackbody_film_rgb(kelvin: f32) -> Vec3 {
    blackbody_rgb(kelvin) * cie_y_integral()
}

/// The integral of ȳ over nanometres (106.86): what pbrt-v4's film records
/// for a spectrum of luminance one that no light normalised.
pub fn cie_y_integral() -> f32 {
    (LAMBDA_MIN..=LAMBDA_MAX).map(|l| cie_xyz_bar(l as f64)[1]).sum::<f64>() as f32
}

/// CIE 1931 2° colour matching functions (x̄, ȳ, z̄): the CIE's table.
pub fn cie_xyz_bar(lambda: f64) -> [f64; 3] {
    super::cie::cie_1931(lambda)
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

/// The RGB weight of each of a sampled spectrum's wavelengths (ascending,
/// nm): a spectrum's colour as a reflectance (as the converter's `reflectance_rgb` takes it) is the sum
/// of its values times these. Between wavelengths the spectrum is linear;
/// beyond the first and the last it keeps their values (as pbrt-v4
/// interpolates a measured BRDF's spectra).
pub fn wavelength_rgb(wavelengths: &[f32]) -> Vec<Vec3> {
    let white = xyz_to_linear_srgb(spectrum_to_xyz(|_| 1.0));
    let n = wavelengths.len();
    (0..n)
        .map(|k| {
            let hat = |l: f32| -> f32 {
                let i = wavelengths.partition_point(|&x| x <= l);
                if i == 0 {
                    (k == 0) as u8 as f32
                } else if i == n {
                    (k == n - 1) as u8 as f32
                } else {
                    let (l0, l1) = (wavelengths[i - 1], wavelengths[i]);
                    let t = if l1 > l0 { (l - l0) / (l1 - l0) } else { 0.0 };
                    if k == i - 1 {
                        1.0 - t
                    } else if k == i {
                        t
                    } else {
                        0.0
                    }
                }
            };
            xyz_to_linear_srgb(spectrum_to_xyz(hat)) / white
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_glasses_follow_the_catalogue_and_pbrt_v4s_tables() {
        // Points of pbrt-v4's tables (BK7 at 586 nm; SF11, its "glass-F11",
        // at 412 and 710 nm) and Schott's BK7 at the d line.
        for (name, lambda, want) in [
            ("glass-BK7", 586.0, 1.516_866),
            ("glass-BK7", 587.56, 1.5168),
            ("glass-F11", 412.0, 1.837_471),
            ("glass-F11", 710.0, 1.770_834),
        ] {
            let eta = glass_eta(name, lambda).unwrap();
            assert!((eta - want).abs() < 5e-4, "{name} at {lambda} nm: {eta}");
        }
        assert!(glass_eta("metal-Cu-eta", 550.0).is_none());
    }

    #[test]
    fn each_channel_sees_the_index_of_its_wavelengths() {
        assert_eq!(channel_etas(|_| 1.33), Vec3::splat(1.33));
        let bk7 = channel_etas(|l| glass_eta("glass-BK7", l).unwrap());
        // Red sees the lowest index, blue the highest, each that of a
        // wavelength within its primary's band.
        let at = |l: f64| glass_eta("glass-BK7", l).unwrap() as f32;
        assert!(at(640.0) < bk7.x && bk7.x < at(580.0), "{bk7}");
        assert!(at(580.0) < bk7.y && bk7.y < at(520.0), "{bk7}");
        assert!(at(490.0) < bk7.z && bk7.z < at(440.0), "{bk7}");
    }
}
