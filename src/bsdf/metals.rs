//! Named metals: RGB complex indices of refraction for the measured spectra
//! pbrt-v4 ships as `metal-<name>-eta` and `metal-<name>-k`
//! (`src/pbrt/util/spectrum.cpp`).
//!
//! # How the RGB values were derived
//!
//! An RGB renderer cannot use a spectral index of refraction directly, and
//! converting eta(lambda) and k(lambda) to RGB separately (averaging each
//! against colour matching functions) does not give the colour of the metal:
//! the Fresnel reflectance is far from linear in eta and k. What a spectral
//! renderer such as pbrt-v4 shows under white light is the colour of the
//! spectral Fresnel reflectance, so that is what we match:
//!
//! 1. For cos(theta) at the 64 midpoints of [0, 1], the spectral reflectance
//!    R(theta, lambda) = Fr(cos(theta), eta(lambda) + i k(lambda)) is
//!    computed from pbrt-v4's data (linear interpolation, as pbrt-v4 does)
//!    every 5 nm from 360 to 830 nm.
//! 2. It is converted to linear sRGB as a reflectance under the sRGB white,
//!    D65: rgb_c = sum R(lambda) D65(lambda) s_c(lambda) / sum D65(lambda)
//!    s_c(lambda), where s = M (x-bar, y-bar, z-bar) are the CIE 1931
//!    2-degree matching functions taken to linear sRGB by the standard
//!    XYZ-to-sRGB matrix M (IEC 61966-2-1). A perfect reflector gives
//!    exactly (1, 1, 1). This is the colour pbrt-v4 renders for the metal lit
//!    by an RGB-white light, which in pbrt-v4 is a D65 spectrum.
//! 3. Per channel, (eta_c, k_c) is fitted so that the conductor Fresnel curve
//!    Fr(cos(theta), eta_c + i k_c) matches rgb_c(theta) in least squares
//!    weighted by projected solid angle (2 cos(theta) d cos(theta)), by
//!    Nelder-Mead in (ln eta, ln k) from the naive per-channel averages.
//!
//! The test `named_metal_rgb_is_regenerated_from_the_spectra` in this file
//! reruns steps 1-3 from the data in `spectral_data.rs`, checks the constants
//! below against it, and prints them (`cargo test --release
//! named_metal_rgb -- --nocapture`). The fitted curves reproduce the spectral
//! colour within the residuals printed there; the naive averages do not
//! (their normal-incidence colours are printed alongside).

use crate::math::Vec3;

/// (name, eta, k) per linear sRGB channel, fitted as described above.
pub const NAMED_METALS: [(&str, [f32; 3], [f32; 3]); 5] = [
    ("Ag", [0.1293, 0.1253, 0.1513], [4.1107, 3.3513, 2.4129]),
    ("Al", [1.4275, 0.9295, 0.5916], [7.7361, 6.6057, 5.3648]),
    ("Au", [0.1601, 0.4063, 1.7262], [5.4191, 2.3470, 1.7965]),
    ("Cu", [0.2093, 0.9764, 1.2113], [4.1247, 2.6211, 2.3663]),
    ("CuZn", [0.4675, 0.5234, 1.1263], [4.2720, 2.6680, 1.8111]),
];

/// The RGB (eta, k) of a named metal: "Ag", "Al", "Au", "Cu" or "CuZn"
/// (brass), also accepted with pbrt-v4's "metal-" prefix.
pub fn named_metal(name: &str) -> Option<(Vec3, Vec3)> {
    let name = name.strip_prefix("metal-").unwrap_or(name);
    NAMED_METALS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, eta, k)| (Vec3::from_array(*eta), Vec3::from_array(*k)))
}

/// The RGB value of one of pbrt-v4's named metal spectra, such as
/// "metal-Cu-eta" or "metal-Cu-k". The eta and k of a metal were fitted
/// together, so use them as a pair.
pub fn named_spectrum_rgb(name: &str) -> Option<Vec3> {
    let rest = name.strip_prefix("metal-")?;
    if let Some(metal) = rest.strip_suffix("-eta") {
        named_metal(metal).map(|(eta, _)| eta)
    } else if let Some(metal) = rest.strip_suffix("-k") {
        named_metal(metal).map(|(_, k)| k)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::super::fresnel::fr_complex;
    use super::super::spectral_data::*;
    use super::*;

    /// XYZ to linear sRGB (IEC 61966-2-1).
    const XYZ_TO_SRGB: [[f64; 3]; 3] = [
        [3.2404542, -1.5371385, -0.4985314],
        [-0.9692660, 1.8760108, 0.0415560],
        [0.0556434, -0.2040259, 1.0572252],
    ];

    /// Number of cos(theta) midpoints the fit uses.
    const N_MU: usize = 64;

    fn spectral_data(metal: &str) -> (&'static [[f64; 2]], &'static [[f64; 2]]) {
        match metal {
            "Ag" => (&AG_ETA, &AG_K),
            "Al" => (&AL_ETA, &AL_K),
            "Au" => (&AU_ETA, &AU_K),
            "Cu" => (&CU_ETA, &CU_K),
            "CuZn" => (&CUZN_ETA, &CUZN_K),
            _ => unreachable!("no spectral data for {metal}"),
        }
    }

    /// Piecewise-linear interpolation of (wavelength, value) pairs, clamped
    /// at the ends.
    fn interpolate(data: &[[f64; 2]], lambda: f64) -> f64 {
        if lambda <= data[0][0] {
            return data[0][1];
        }
        for w in data.windows(2) {
            if lambda <= w[1][0] {
                let t = (lambda - w[0][0]) / (w[1][0] - w[0][0]);
                return w[0][1] + t * (w[1][1] - w[0][1]);
            }
        }
        data[data.len() - 1][1]
    }

    /// Conductor Fresnel reflectance in f64 (the fit needs a smooth objective).
    fn fresnel64(cos_i: f64, eta: f64, k: f64) -> f64 {
        // Closed form with a^2 + b^2 = |eta^2 - sin^2|, the real formulation.
        let sin2 = 1.0 - cos_i * cos_i;
        let t0 = eta * eta - k * k - sin2;
        let a2b2 = (t0 * t0 + 4.0 * eta * eta * k * k).sqrt();
        let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
        let rs = (a2b2 + cos_i * cos_i - 2.0 * a * cos_i) / (a2b2 + cos_i * cos_i + 2.0 * a * cos_i);
        let t3 = cos_i * cos_i * a2b2 + sin2 * sin2;
        let t4 = 2.0 * a * cos_i * sin2;
        let rp = rs * (t3 - t4) / (t3 + t4);
        0.5 * (rs + rp)
    }

    /// Per-wavelength sRGB weights D65 * (M xyz), each channel normalised to sum 1.
    fn channel_weights() -> Vec<[f64; 3]> {
        let mut w: Vec<[f64; 3]> = CIE_D65_5NM
            .iter()
            .map(|&[_, x, y, z, d65]| {
                let rgb = |r: [f64; 3]| d65 * (r[0] * x + r[1] * y + r[2] * z);
                [rgb(XYZ_TO_SRGB[0]), rgb(XYZ_TO_SRGB[1]), rgb(XYZ_TO_SRGB[2])]
            })
            .collect();
        for c in 0..3 {
            let sum: f64 = w.iter().map(|v| v[c]).sum();
            w.iter_mut().for_each(|v| v[c] /= sum);
        }
        w
    }

    fn mu(j: usize) -> f64 {
        (j as f64 + 0.5) / N_MU as f64
    }

    /// rgb_c(theta_j): the colour of the spectral Fresnel reflectance.
    fn target_curves(metal: &str, weights: &[[f64; 3]]) -> [[f64; N_MU]; 3] {
        let (eta, k) = spectral_data(metal);
        let mut out = [[0.0; N_MU]; 3];
        for (row, w) in CIE_D65_5NM.iter().zip(weights) {
            let (e, kk) = (interpolate(eta, row[0]), interpolate(k, row[0]));
            let r: Vec<f64> = (0..N_MU).map(|j| fresnel64(mu(j), e, kk)).collect();
            for (curve, w_c) in out.iter_mut().zip(w) {
                for (value, r_j) in curve.iter_mut().zip(&r) {
                    *value += w_c * r_j;
                }
            }
        }
        out
    }

    /// Projected-solid-angle weighted squared error of a Fresnel curve.
    fn curve_error(target: &[f64; N_MU], eta: f64, k: f64) -> f64 {
        (0..N_MU)
            .map(|j| 2.0 * mu(j) / N_MU as f64 * (fresnel64(mu(j), eta, k) - target[j]).powi(2))
            .sum()
    }

    /// Nelder-Mead minimisation of `f` over 2 parameters.
    fn nelder_mead(f: impl Fn([f64; 2]) -> f64, start: [f64; 2]) -> [f64; 2] {
        let mut simplex = [start, [start[0] + 0.1, start[1]], [start[0], start[1] + 0.1]];
        let mut values = simplex.map(&f);
        for _ in 0..2000 {
            // Order best to worst.
            let mut idx = [0, 1, 2];
            idx.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
            simplex = idx.map(|i| simplex[i]);
            values = idx.map(|i| values[i]);
            if values[2] - values[0] < 1e-16 {
                break;
            }
            let centroid = [
                0.5 * (simplex[0][0] + simplex[1][0]),
                0.5 * (simplex[0][1] + simplex[1][1]),
            ];
            let along = |t: f64| {
                [
                    centroid[0] + t * (simplex[2][0] - centroid[0]),
                    centroid[1] + t * (simplex[2][1] - centroid[1]),
                ]
            };
            let reflected = along(-1.0);
            let fr = f(reflected);
            if fr < values[0] {
                let expanded = along(-2.0);
                let fe = f(expanded);
                (simplex[2], values[2]) = if fe < fr { (expanded, fe) } else { (reflected, fr) };
            } else if fr < values[1] {
                (simplex[2], values[2]) = (reflected, fr);
            } else {
                let contracted = along(0.5);
                let fc = f(contracted);
                if fc < values[2] {
                    (simplex[2], values[2]) = (contracted, fc);
                } else {
                    // Shrink towards the best vertex.
                    for v in 1..3 {
                        simplex[v] = [
                            0.5 * (simplex[0][0] + simplex[v][0]),
                            0.5 * (simplex[0][1] + simplex[v][1]),
                        ];
                        values[v] = f(simplex[v]);
                    }
                }
            }
        }
        let best = (0..3).min_by(|&a, &b| values[a].total_cmp(&values[b])).unwrap_or(0);
        simplex[best]
    }

    /// (ln eta, ln k) lower and upper bounds: the range the metal's data
    /// spans over the wavelengths of the conversion.
    fn data_range(metal: &str) -> ([f64; 2], [f64; 2]) {
        let (eta, k) = spectral_data(metal);
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for row in CIE_D65_5NM.iter() {
            for (i, v) in [interpolate(eta, row[0]), interpolate(k, row[0])]
                .into_iter()
                .enumerate()
            {
                lo[i] = lo[i].min(v.ln());
                hi[i] = hi[i].max(v.ln());
            }
        }
        (lo, hi)
    }

    /// Naive conversion: eta and k each averaged with the channel weights.
    fn naive_average(metal: &str, weights: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
        let (eta, k) = spectral_data(metal);
        let (mut e, mut kk) = ([0.0; 3], [0.0; 3]);
        for (i, row) in CIE_D65_5NM.iter().enumerate() {
            for c in 0..3 {
                e[c] += weights[i][c] * interpolate(eta, row[0]);
                kk[c] += weights[i][c] * interpolate(k, row[0]);
            }
        }
        (e, kk)
    }

    #[test]
    fn named_metal_rgb_is_regenerated_from_the_spectra() {
        let weights = channel_weights();
        // A perfect reflector is white.
        for c in 0..3 {
            let s: f64 = weights.iter().map(|w| w[c]).sum();
            assert!((s - 1.0).abs() < 1e-12);
        }
        println!("metal  eta (r g b)                k (r g b)                  max |dF|  F(0) fit vs naive");
        let mut code = String::new();
        let mut stale = Vec::new();
        for (name, stored_eta, stored_k) in NAMED_METALS {
            let target = target_curves(name, &weights);
            let (naive_eta, naive_k) = naive_average(name, &weights);
            let (mut eta, mut k) = ([0.0f64; 3], [0.0f64; 3]);
            let mut worst = 0.0f64;
            let (lo, hi) = data_range(name);
            for c in 0..3 {
                // Clamp to the box of the data, with a pull back into it.
                let clamp = |p: [f64; 2]| [p[0].clamp(lo[0], hi[0]), p[1].clamp(lo[1], hi[1])];
                let objective = |p: [f64; 2]| {
                    let q = clamp(p);
                    let outside = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                    curve_error(&target[c], q[0].exp(), q[1].exp()) + outside
                };
                let start = clamp([naive_eta[c].ln(), naive_k[c].ln()]);
                let p = clamp(nelder_mead(objective, start));
                (eta[c], k[c]) = (p[0].exp(), p[1].exp());
                for (j, spectral) in target[c].iter().enumerate() {
                    // The stored constants reproduce the regenerated curve...
                    let stored = fr_complex(mu(j) as f32, stored_eta[c], stored_k[c]) as f64;
                    let fitted = fresnel64(mu(j), eta[c], k[c]);
                    let error = (stored - fitted).abs();
                    if error.is_nan() || error >= 2e-4 {
                        stale.push(format!("{name} channel {c}: {stored} vs {fitted}"));
                    }
                    // ...and the fit reproduces the spectral colour (clipped
                    // to 1 where it is out of gamut).
                    worst = worst.max((fitted - spectral.min(1.0)).abs());
                }
            }
            assert!(worst < 0.03, "{name}: fit residual {worst}");
            let f0 = |e: [f64; 3], k: [f64; 3]| (0..3).map(|c| fresnel64(1.0, e[c], k[c])).collect::<Vec<_>>();
            let spectral_f0: Vec<f64> = (0..3).map(|c| target[c][N_MU - 1]).collect();
            println!(
                "{name:5}  {:.4} {:.4} {:.4}   {:.4} {:.4} {:.4}   {worst:.4}   spectral {:.3?} fit {:.3?} naive {:.3?}",
                eta[0], eta[1], eta[2], k[0], k[1], k[2], spectral_f0, f0(eta, k), f0(naive_eta, naive_k)
            );
            code += &format!(
                "    (\"{name}\", [{:.4}, {:.4}, {:.4}], [{:.4}, {:.4}, {:.4}]),\n",
                eta[0], eta[1], eta[2], k[0], k[1], k[2]
            );
        }
        println!("{code}");
        assert!(stale.is_empty(), "stored constants are stale: {stale:?}");
    }

    #[test]
    fn named_metals_are_found_by_both_spellings() {
        for name in ["Ag", "Al", "Au", "Cu", "CuZn"] {
            let (eta, k) = named_metal(name).unwrap();
            assert_eq!(named_metal(&format!("metal-{name}")), Some((eta, k)));
            assert_eq!(named_spectrum_rgb(&format!("metal-{name}-eta")), Some(eta));
            assert_eq!(named_spectrum_rgb(&format!("metal-{name}-k")), Some(k));
        }
        assert!(named_metal("Fe").is_none());
        assert!(named_spectrum_rgb("metal-Cu").is_none());
        assert!(named_spectrum_rgb("glass-BK7").is_none());
    }
}
