//! A measured BRDF tabulated from a closed form (Trowbridge-Reitz normals,
//! no Fresnel) must give back that closed form, and sample what it says.

use super::tensor::{write, TestData};
use super::*;
use crate::sampling::Rng;

const ALPHA: f32 = 0.3;
const RADIANCE: TransportMode = TransportMode::Radiance;

fn ggx_d(cos_m: f32) -> f32 {
    if cos_m <= 0.0 {
        return 0.0;
    }
    let c2 = cos_m * cos_m;
    let tan2 = (1.0 - c2) / c2;
    let a2 = ALPHA * ALPHA;
    1.0 / (PI * a2 * c2 * c2 * (1.0 + tan2 / a2).powi(2))
}

fn ggx_g1(cos_o: f32) -> f32 {
    let c2 = (cos_o * cos_o).max(1e-12);
    let tan2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + ALPHA * ALPHA * tan2).sqrt())
}

/// theta and phi of a point of the unit square.
fn square_to_angles(u: Vec2) -> (f32, f32) {
    (u.x * u.x * PI / 2.0, (2.0 * u.y - 1.0) * PI)
}

/// A colour factor of the half vector, the same under a turn by pi and
/// under mirroring in x or y (so reduced files may hold it).
fn colour_of(wm: Vec3) -> f32 {
    let (sin2, phi) = (1.0 - wm.z * wm.z, wm.y.atan2(wm.x));
    (1.0 + 0.5 * sin2 * (2.0 * phi).cos()) / 1.5
}

/// A factor of the outgoing direction (of its azimuth too when the file is
/// anisotropic), so that values read from the wrong incident slice show.
fn wo_factor(wo: Vec3, isotropic: bool) -> f32 {
    let turn = if isotropic { 1.0 } else { (2.0 * wo.y.atan2(wo.x)).cos() };
    1.0 + 0.3 * (1.0 - wo.z * wo.z) * turn
}

/// The closed form: R D(wm) G1(wo) / (4 cos_o cos_i).
fn closed_form(wo: Vec3, wi: Vec3, r: Vec3) -> Vec3 {
    let wm = (wo + wi).normalize();
    r * (ggx_d(wm.z) * ggx_g1(wo.z) / (4.0 * wo.z * wi.z))
}

/// Wavelengths 400 and 700 nm: blue and yellow. Reflectance 0.3 and 0.9.
fn rgb_of(l: &[f32]) -> Vec<Vec3> {
    l.iter()
        .map(|&l| {
            if l < 550.0 {
                Vec3::new(0.0, 0.0, 1.0)
            } else {
                Vec3::new(1.0, 1.0, 0.0)
            }
        })
        .collect()
}

const R: Vec3 = Vec3::new(0.9, 0.9, 0.3);

/// A tensor file of the closed form at `n` x `n`, its luminance density
/// deliberately not constant (sampling must still be exact). Isotropic with
/// one `phi_i`; else tabulated at each of `phis` (the closed form is
/// isotropic, but the tables then hold absolute azimuths). With `rgb`, the
/// colours as RGB instead of spectra.
fn ggx_file_with(n: usize, phis: &[f32], rgb: bool) -> Vec<u8> {
    ggx_file_varied(n, phis, rgb, false)
}

/// [`ggx_file_with`], the colours varying over the square with `vary`
/// (so that a value reads the colour where the half vector's inversion
/// lands, and a wrong inversion shows).
fn ggx_file_varied(n: usize, phis: &[f32], rgb: bool, vary: bool) -> Vec<u8> {
    let thetas: Vec<f32> = (0..9).map(|k| (k as f32 / 8.0).powi(2) * 85f32.to_radians()).collect();
    let isotropic = phis.len() <= 2;
    let grid = |f: &dyn Fn(Vec2) -> f32| -> Vec<f32> {
        let mut v = Vec::with_capacity(n * n);
        for y in 0..n {
            for x in 0..n {
                v.push(f(Vec2::new(x as f32 / (n - 1) as f32, y as f32 / (n - 1) as f32)));
            }
        }
        v
    };
    let ndf = grid(&|u| ggx_d(square_to_angles(u).0.cos()));
    let sigma = grid(&|u| {
        let c = square_to_angles(u).0.cos().max(0.0);
        c / ggx_g1(c)
    });
    let mut vndf = Vec::new();
    let mut lum = Vec::new();
    let mut colours = Vec::new();
    for &phi_o in phis {
        for &theta_o in &thetas {
            let wo = dir(theta_o, if isotropic { 0.0 } else { phi_o });
            let slice = grid(&|u| {
                let (t, p) = square_to_angles(u);
                let wm = dir(t, if isotropic { p + phi_o } else { p });
                let d_wo = ggx_g1(wo.z) * wo.dot(wm).max(0.0) * ggx_d(wm.z) / wo.z.max(1e-4);
                d_wo * 2.0 * PI * PI * u.x * t.sin()
            });
            // The colour table is over the square the visible normals warp:
            // a colour of the half vector is read where the warp sends it.
            let warp = PiecewiseLinear2D::new(&slice, n, n, &[], true).unwrap();
            let k = |u: Vec2| {
                if !vary {
                    return 1.0;
                }
                let (t, p) = square_to_angles(warp.sample(u, &[]).0);
                colour_of(dir(t, if isotropic { p + phi_o } else { p })) * wo_factor(wo, isotropic)
            };
            vndf.extend(slice);
            lum.extend(grid(&|u| 1.0 + 0.6 * u.x + 0.3 * u.y));
            if rgb {
                for c in R.to_array() {
                    colours.extend(grid(&|u| c * k(u)));
                }
            } else {
                colours.extend(grid(&|u| 0.3 * k(u)));
                colours.extend(grid(&|u| 0.9 * k(u)));
            }
        }
    }
    let (np, nt) = (phis.len(), thetas.len());
    let nc = if rgb { 3 } else { 2 };
    let mut fields = vec![
        ("description", vec![4], TestData::U8(b"test".to_vec())),
        ("jacobian", vec![1], TestData::U8(vec![1])),
        ("theta_i", vec![nt], TestData::F32(thetas)),
        ("phi_i", vec![np], TestData::F32(phis.to_vec())),
        ("ndf", vec![n, n], TestData::F32(ndf)),
        ("sigma", vec![n, n], TestData::F32(sigma)),
        ("vndf", vec![np, nt, n, n], TestData::F32(vndf)),
        ("luminance", vec![np, nt, n, n], TestData::F32(lum)),
    ];
    if rgb {
        fields.push(("rgb", vec![np, nt, nc, n, n], TestData::F32(colours)));
    } else {
        fields.push(("wavelengths", vec![2], TestData::F32(vec![400.0, 700.0])));
        fields.push(("spectra", vec![np, nt, nc, n, n], TestData::F32(colours)));
    }
    write(&fields)
}

pub(super) fn ggx_file(n: usize) -> Vec<u8> {
    ggx_file_with(n, &[0.0], false)
}

fn leak(file: &[u8]) -> MeasuredBxdf {
    let data = MeasuredData::from_bytes(file, "ggx", rgb_of).unwrap();
    MeasuredBxdf::new(Box::leak(Box::new(data)))
}

fn bxdf() -> MeasuredBxdf {
    leak(&ggx_file(48))
}

/// Azimuths over `[-pi, pi / reduction - pi]`, as a file reduced so covers them.
fn phis(reduction: u32) -> Vec<f32> {
    let k = 24 / reduction as usize;
    (0..=k).map(|i| -PI + i as f32 * 2.0 * PI / 24.0).collect()
}

fn dir(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
}

#[test]
fn a_tabulated_closed_form_evaluates_to_it_on_either_side() {
    // Isotropic with spectra; isotropic with RGB; anisotropic over the
    // whole circle, a half and a quarter of it (folded by symmetry).
    let variants = [
        ("isotropic", leak(&ggx_file_varied(48, &[0.0], false, true))),
        ("rgb", leak(&ggx_file_varied(48, &[0.0], true, true))),
        ("full", leak(&ggx_file_varied(32, &phis(1), false, true))),
        ("half", leak(&ggx_file_varied(32, &phis(2), false, true))),
        ("quarter", leak(&ggx_file_varied(32, &phis(4), false, true))),
    ];
    for (name, b) in variants {
        assert_eq!(
            b.data.reduction,
            if name == "half" {
                2
            } else if name == "quarter" {
                4
            } else {
                1
            }
        );
        for (to, po, ti, pi) in [
            (0.3f32, 0.0f32, 0.4f32, 3.0f32),
            (0.8, 1.0, 0.7, -2.0),
            (0.5, -2.5, 0.2, 0.3),
            (1.1, 2.0, 0.9, -1.5),
        ] {
            let (wo, wi) = (dir(to, po), dir(ti, pi));
            // An isotropic file's azimuths are the half vector's from wo's.
            let wm = (wo + wi).normalize();
            let turn = if b.data.isotropic { -po } else { 0.0 };
            let (s, c) = turn.sin_cos();
            let wm = Vec3::new(c * wm.x - s * wm.y, s * wm.x + c * wm.y, wm.z);
            let want = closed_form(wo, wi, R) * colour_of(wm) * wo_factor(wo, b.data.isotropic);
            let got = b.f(wo, wi, RADIANCE);
            assert!(
                (got - want).abs().max_element() < 0.05 * want.max_element() + 1e-3,
                "{name} {wo} {wi}: {got} against {want}"
            );
            // The lower side mirrors the upper one; opposite sides reflect nothing.
            assert_eq!(b.f(-wo, -wi, RADIANCE), got);
            assert_eq!(b.f(wo, -wi, RADIANCE), Vec3::ZERO);
            assert_eq!(b.pdf(wo, -wi), 0.0);
        }
    }
}

#[test]
fn samples_carry_the_value_and_density_of_their_direction_and_estimate_the_albedo() {
    let mut rng = Rng::new(3, 1);
    for (b, theta_o, phi_o) in [
        (bxdf(), 0.2f32, 0.8f32),
        (bxdf(), 0.7, 0.8),
        (bxdf(), 1.2, 0.8),
        (leak(&ggx_file_with(32, &phis(1), false)), 0.7, 2.2),
        (leak(&ggx_file_with(32, &phis(4), false)), 0.5, 1.0),
    ] {
        let wo = dir(theta_o, phi_o);
        let n = 60_000;
        let mut estimate = Vec3::ZERO;
        for _ in 0..n {
            let Some(s) = b.sample_f(wo, rng.next_2d(), RADIANCE) else {
                continue;
            };
            assert!(s.wi.z > 0.0 && s.flags == BxdfFlags::GLOSSY_REFLECTION);
            let (f, pdf) = (b.f(wo, s.wi, RADIANCE), b.pdf(wo, s.wi));
            assert!(
                (s.f - f).abs().max_element() <= 1e-2 * f.max_element() + 1e-5,
                "{} {f}",
                s.f
            );
            assert!((s.pdf - pdf).abs() <= 1e-2 * pdf, "{} {pdf}", s.pdf);
            estimate += s.f * s.wi.z / s.pdf;
        }
        let estimate = estimate / n as f32;
        // The same integral by quadrature over the hemisphere.
        let (m, k) = (400, 400);
        let mut quad = Vec3::ZERO;
        for j in 0..m {
            let theta = (j as f32 + 0.5) / m as f32 * PI / 2.0;
            for i in 0..k {
                let phi = (i as f32 + 0.5) / k as f32 * 2.0 * PI;
                let wi = dir(theta, phi);
                quad += b.f(wo, wi, RADIANCE) * wi.z * theta.sin();
            }
        }
        let quad = quad * (PI / 2.0 / m as f32) * (2.0 * PI / k as f32);
        assert!(
            (estimate - quad).abs().max_element() < 0.015 * quad.max_element(),
            "theta_o {theta_o}: sampled {estimate} against {quad}"
        );
        // A BRDF of normals alone, no Fresnel: close to R, never above it.
        assert!(quad.cmple(R * 1.02).all() && quad.x > 0.7 * R.x, "{quad}");
    }
}

#[test]
fn malformed_files_are_refused_with_a_reason() {
    let good = ggx_file(8);
    assert!(MeasuredData::from_bytes(&good, "ok", rgb_of).is_ok());
    let e = MeasuredData::from_bytes(&good[..good.len() - 4], "cut", rgb_of).unwrap_err();
    assert!(e.contains("past the file's end"), "{e}");
    let e = MeasuredData::from_bytes(b"hello", "text", rgb_of).unwrap_err();
    assert!(e.contains("header"), "{e}");
    // A field missing, and one of the wrong rank.
    let missing = write(&[("description", vec![1], TestData::U8(vec![0]))]);
    let e = MeasuredData::from_bytes(&missing, "m", rgb_of).unwrap_err();
    assert!(e.contains("no field"), "{e}");
    // A NaN in a table.
    let mut nan = good.clone();
    let t = TensorFile::parse(&good).unwrap();
    let off = t.field("ndf").unwrap().bytes().as_ptr() as usize - good.as_ptr() as usize;
    nan[off..off + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = MeasuredData::from_bytes(&nan, "nan", rgb_of).unwrap_err();
    assert!(e.contains("\"ndf\" holds NaN"), "{e}");
}

#[test]
fn light_paths_see_the_adjoint_and_reflected_scenes_the_mirrored_azimuths() {
    let b = leak(&ggx_file_varied(16, &phis(1), false, true));
    let flip = |w: Vec3| Vec3::new(w.x, -w.y, w.z);
    let mirrored = MeasuredBxdf { mirrored: true, ..b };
    let mut rng = Rng::new(5, 2);
    for _ in 0..50 {
        let (wo, wi) = (
            dir(0.2 + rng.next_f32(), 6.0 * rng.next_f32()),
            dir(0.1 + rng.next_f32(), 6.0 * rng.next_f32()),
        );
        assert_eq!(b.f(wo, wi, TransportMode::Importance), b.f(wi, wo, RADIANCE));
        assert_eq!(mirrored.f(wo, wi, RADIANCE), b.f(flip(wo), flip(wi), RADIANCE));
        assert_eq!(mirrored.pdf(wo, wi), b.pdf(flip(wo), flip(wi)));
        let u = rng.next_2d();
        if let Some(s) = mirrored.sample_f(wo, u, RADIANCE) {
            let t = b.sample_f(flip(wo), u, RADIANCE).unwrap();
            assert_eq!((s.wi, s.f, s.pdf), (flip(t.wi), t.f, t.pdf));
        }
        if let Some(s) = b.sample_f(wo, u, TransportMode::Importance) {
            assert_eq!(s.f, b.f(s.wi, wo, RADIANCE));
        }
    }
    // The scene's reflection turns the flag, twice back.
    let mut m = crate::material::Material::Measured(b);
    let r = glam::Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    m.reflect(&r);
    assert_eq!(m, crate::material::Material::Measured(mirrored));
    m.reflect(&r);
    assert_eq!(m, crate::material::Material::Measured(b));
}

#[test]
fn reduced_files_must_start_at_minus_pi() {
    // A half file over [0, pi]: its folded lookups would all clamp to an edge.
    let shifted: Vec<f32> = phis(2).iter().map(|p| p + PI).collect();
    let e = MeasuredData::from_bytes(&ggx_file_with(8, &shifted, false), "s", rgb_of).unwrap_err();
    assert!(e.contains("phi_i starts at"), "{e}");
}
