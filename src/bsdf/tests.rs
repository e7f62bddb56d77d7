//! Tests of the BxDFs as distributions: chi-square goodness of fit of
//! `sample_f` against `pdf` (as Mitsuba 3's `chi2` suite and pbrt-v4's
//! `bsdfs_test.cpp` do), normalisation of `pdf`, consistency of sampled
//! values with `f` and `pdf`, reciprocity, white furnaces and energy
//! conservation. Every random number comes from a fixed seed, so the tests
//! are deterministic.

use super::*;
use crate::sampling::{uniform_sphere, Rng};
use std::f64::consts::PI;

// ---------------------------------------------------------------------------
// Directions and numerical integration over the sphere

/// Unit vector at polar angle `theta` and azimuth `phi` (radians).
fn spherical(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
}

/// Unit vector from cos(theta) and phi.
fn from_cos_phi(cos_t: f64, phi: f64) -> Vec3 {
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    Vec3::new((sin_t * phi.cos()) as f32, (sin_t * phi.sin()) as f32, cos_t as f32)
}

/// Integrates `f(x, y)` over a rectangle by adaptive Simpson quadrature on
/// a quadtree: each cell is refined until its 2x2 children agree with it to
/// `eps`, after at least `min_depth` levels (so that narrow peaks are seen).
struct Simpson2d<'a> {
    f: &'a dyn Fn(f64, f64) -> f64,
    min_depth: u32,
    max_depth: u32,
}

impl Simpson2d<'_> {
    fn integrate(&self, x0: f64, x1: f64, y0: f64, y1: f64, eps: f64) -> f64 {
        let v = self.grid3(x0, x1, y0, y1);
        let whole = simpson9(&v, x1 - x0, y1 - y0);
        self.refine(x0, x1, y0, y1, &v, whole, eps, 0)
    }

    fn grid3(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> [[f64; 3]; 3] {
        let mut v = [[0.0; 3]; 3];
        for (i, row) in v.iter_mut().enumerate() {
            for (j, val) in row.iter_mut().enumerate() {
                let x = x0 + (x1 - x0) * i as f64 / 2.0;
                let y = y0 + (y1 - y0) * j as f64 / 2.0;
                *val = (self.f)(x, y);
            }
        }
        v
    }

    #[allow(clippy::too_many_arguments)]
    fn refine(&self, x0: f64, x1: f64, y0: f64, y1: f64, v: &[[f64; 3]; 3], whole: f64, eps: f64, depth: u32) -> f64 {
        // The 5x5 grid of the four children, reusing the parent's 3x3 values.
        let mut g = [[0.0; 5]; 5];
        for (i, row) in g.iter_mut().enumerate() {
            for (j, val) in row.iter_mut().enumerate() {
                *val = if i % 2 == 0 && j % 2 == 0 {
                    v[i / 2][j / 2]
                } else {
                    let x = x0 + (x1 - x0) * i as f64 / 4.0;
                    let y = y0 + (y1 - y0) * j as f64 / 4.0;
                    (self.f)(x, y)
                };
            }
        }
        let (hx, hy) = (0.5 * (x1 - x0), 0.5 * (y1 - y0));
        let mut children = [[[[0.0; 3]; 3]; 2]; 2];
        let mut sums = [[0.0; 2]; 2];
        for ci in 0..2 {
            for cj in 0..2 {
                for a in 0..3 {
                    for b in 0..3 {
                        children[ci][cj][a][b] = g[2 * ci + a][2 * cj + b];
                    }
                }
                sums[ci][cj] = simpson9(&children[ci][cj], hx, hy);
            }
        }
        let total: f64 = sums.iter().flatten().sum();
        let converged = (total - whole).abs() <= 15.0 * eps;
        if depth >= self.max_depth || (depth >= self.min_depth && converged) {
            return total + (total - whole) / 15.0;
        }
        let mut result = 0.0;
        for ci in 0..2 {
            for cj in 0..2 {
                let (cx0, cy0) = (x0 + hx * ci as f64, y0 + hy * cj as f64);
                result += self.refine(
                    cx0,
                    cx0 + hx,
                    cy0,
                    cy0 + hy,
                    &children[ci][cj],
                    sums[ci][cj],
                    eps / 4.0,
                    depth + 1,
                );
            }
        }
        result
    }
}

/// Simpson's rule on a 3x3 grid of values over a w x h rectangle.
fn simpson9(v: &[[f64; 3]; 3], w: f64, h: f64) -> f64 {
    const K: [f64; 3] = [1.0, 4.0, 1.0];
    let mut s = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            s += K[i] * K[j] * v[i][j];
        }
    }
    s * w * h / 36.0
}

/// The chi-square test's binning of the sphere: uniform in cos(theta) and phi.
const THETA_BINS: usize = 10;
const PHI_BINS: usize = 20;
const SPHERE_BINS: usize = THETA_BINS * PHI_BINS;

fn bin_of(w: Vec3) -> usize {
    let c = (w.z as f64).clamp(-1.0, 1.0);
    let i = (((c + 1.0) * 0.5 * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
    let mut phi = (w.y as f64).atan2(w.x as f64);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let j = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    i * PHI_BINS + j
}

/// Integral of `g` over each bin of the sphere, in bin order, each to an
/// absolute tolerance of about `eps`. The bins are uniform in cos(theta),
/// but the quadrature runs in theta (dw = sin(theta) dtheta dphi): a lobe
/// around a pole is then a bump, not a sliver along the bin's edge.
fn integrate_bins(g: &dyn Fn(Vec3) -> f64, eps: f64) -> Vec<f64> {
    let f = |theta: f64, phi: f64| g(from_cos_phi(theta.cos(), phi)) * theta.sin();
    let simpson = Simpson2d {
        f: &f,
        min_depth: 2,
        max_depth: 8,
    };
    let mut out = Vec::with_capacity(SPHERE_BINS);
    for i in 0..THETA_BINS {
        let c0 = -1.0 + 2.0 * i as f64 / THETA_BINS as f64;
        let c1 = -1.0 + 2.0 * (i + 1) as f64 / THETA_BINS as f64;
        for j in 0..PHI_BINS {
            let p0 = 2.0 * PI * j as f64 / PHI_BINS as f64;
            let p1 = 2.0 * PI * (j + 1) as f64 / PHI_BINS as f64;
            out.push(simpson.integrate(c1.acos(), c0.acos(), p0, p1, eps));
        }
    }
    out
}

// ---------------------------------------------------------------------------
// Chi-square test

/// ln(Gamma(a)) for a a positive multiple of 1/2, exactly by recursion from
/// Gamma(1) = 1 and Gamma(1/2) = sqrt(pi).
fn ln_gamma_half_integer(a: f64) -> f64 {
    let (mut x, mut acc) = if (a * 2.0).round() as i64 % 2 == 0 {
        (1.0, 0.0)
    } else {
        (0.5, 0.5 * PI.ln())
    };
    while x < a - 0.25 {
        acc += x.ln();
        x += 1.0;
    }
    acc
}

/// Regularised upper incomplete gamma function Q(a, x), for a a multiple of
/// 1/2: the series for P below a + 1, a continued fraction (modified Lentz)
/// above.
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let prefactor = (-x + a * x.ln() - ln_gamma_half_integer(a)).exp();
    if x < a + 1.0 {
        let (mut term, mut sum, mut n) = (1.0 / a, 1.0 / a, a);
        while term.abs() > sum.abs() * 1e-15 {
            n += 1.0;
            term *= x / n;
            sum += term;
        }
        1.0 - sum * prefactor
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        prefactor * h
    }
}

/// p-value of a chi-square statistic with `dof` degrees of freedom.
fn chi2_p_value(chi2: f64, dof: usize) -> f64 {
    gamma_q(dof as f64 / 2.0, chi2 / 2.0)
}

#[test]
fn chi2_p_values_match_tables() {
    // Critical values at p = 0.05 and 0.01 from standard tables.
    for (x, dof, p) in [
        (3.841, 1, 0.05),
        (6.635, 1, 0.01),
        (18.307, 10, 0.05),
        (124.342, 100, 0.05),
        (135.807, 100, 0.01),
    ] {
        let got = chi2_p_value(x, dof);
        assert!((got - p).abs() < 2e-4, "chi2 {x} dof {dof}: {got} vs {p}");
    }
}

/// Samples per chi-square test.
const CHI2_SAMPLES: usize = 150_000;

/// Tolerance of the integral of the pdf over a bin: 0.15 samples in 150 000.
const CHI2_EPS: f64 = 1e-6;

/// The outcome of one chi-square test.
struct Chi2Outcome {
    p_value: f64,
    /// Integral of `pdf` over the sphere plus the probability of delta lobes.
    pdf_mass: f64,
    /// What went wrong before any statistics (a sample where pdf is zero...).
    failure: Option<String>,
}

/// Samples `bxdf` at `wo` `n` times and compares the histogram of the
/// directions, over the sphere bins plus one bin for delta lobes and one for
/// failed samples, with the counts `pdf` predicts. Bins expecting fewer than
/// 5 samples are pooled (smallest first), as Mitsuba's test does.
fn chi2_test(bxdf: &Bxdf, wo: Vec3, n: usize, seed: u64) -> Chi2Outcome {
    let mode = TransportMode::Radiance;
    let (delta_bin, none_bin) = (SPHERE_BINS, SPHERE_BINS + 1);
    let mut observed = vec![0.0f64; SPHERE_BINS + 2];
    let mut rng = Rng::new(seed, 0x5eed);
    let mut failure = None;
    for _ in 0..n {
        let uc = rng.next_f32();
        let u = rng.next_2d();
        match bxdf.sample_f(wo, uc, u, mode) {
            None => observed[none_bin] += 1.0,
            Some(bs) if bs.is_specular() => observed[delta_bin] += 1.0,
            Some(bs) => {
                if !(bs.pdf > 0.0 && bs.pdf.is_finite()) || (bs.wi.length() - 1.0).abs() > 1e-3 {
                    failure.get_or_insert(format!("bad sample {bs:?}"));
                    continue;
                }
                observed[bin_of(bs.wi)] += 1.0;
            }
        }
    }
    // The probability of the delta lobes: a sample with uc = 0 picks the
    // first lobe, which is the specular one in the models that have one.
    let delta_p = match bxdf.sample_f(wo, 0.0, Vec2::splat(0.5), mode) {
        Some(bs) if bs.is_specular() => bs.pdf as f64,
        _ => 0.0,
    };
    let mut expected = integrate_bins(&|wi| bxdf.pdf(wo, wi, mode) as f64, CHI2_EPS);
    let pdf_mass = expected.iter().sum::<f64>() + delta_p;
    expected.push(delta_p);
    expected.push((1.0 - pdf_mass).max(0.0));
    for e in expected.iter_mut() {
        *e *= n as f64;
    }
    // Samples where the pdf says none can be fail the test outright.
    for (i, (&o, &e)) in observed.iter().zip(&expected).enumerate() {
        if o > 0.0 && e < 1e-9 * n as f64 {
            failure.get_or_insert(format!("{o} samples in bin {i}, where pdf integrates to {e}"));
        }
    }
    // Pool the bins with small expectations, smallest first.
    let mut cells: Vec<(f64, f64)> = observed.into_iter().zip(expected).collect();
    cells.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (mut chi2, mut dof, mut pool) = (0.0, 0usize, (0.0, 0.0));
    for (o, e) in cells {
        if e <= 0.0 {
            continue;
        }
        let (o, e) = if e < 5.0 || pool.1 > 0.0 {
            pool = (pool.0 + o, pool.1 + e);
            if pool.1 < 5.0 {
                continue;
            }
            std::mem::take(&mut pool)
        } else {
            (o, e)
        };
        chi2 += (o - e) * (o - e) / e;
        dof += 1;
    }
    if pool.1 > 0.0 {
        chi2 += (pool.0 - pool.1) * (pool.0 - pool.1) / pool.1;
        dof += 1;
    }
    let p_value = if dof > 1 { chi2_p_value(chi2, dof - 1) } else { 1.0 };
    Chi2Outcome {
        p_value,
        pdf_mass,
        failure,
    }
}

/// The non-specular BxDFs the statistical tests cover: every model at
/// several roughnesses, isotropic and anisotropic.
fn sampled_bxdfs() -> Vec<(String, Bxdf)> {
    let tr = TrowbridgeReitz::new;
    let (cu_eta, cu_k) = named_metal("Cu").unwrap_or((Vec3::ONE, Vec3::ONE));
    let mut cases = vec![
        ("diffuse".to_string(), Bxdf::diffuse(Vec3::new(0.5, 0.6, 0.7))),
        (
            "diffuse transmission".to_string(),
            Bxdf::diffuse_transmission(Vec3::new(0.3, 0.2, 0.1), Vec3::new(0.5, 0.6, 0.4)),
        ),
    ];
    for (ax, ay) in [(0.05, 0.05), (0.3, 0.3), (0.08, 0.4), (1.0, 1.0)] {
        cases.push((
            format!("conductor alpha {ax}/{ay}"),
            Bxdf::conductor(tr(ax, ay), cu_eta, cu_k),
        ));
    }
    for (ax, ay, eta) in [
        (0.1, 0.1, 1.5),
        (0.4, 0.4, 1.5),
        (0.05, 0.3, 1.5),
        (0.3, 0.3, 1.0 / 1.33),
    ] {
        cases.push((
            format!("dielectric alpha {ax}/{ay} eta {eta}"),
            Bxdf::dielectric(tr(ax, ay), eta),
        ));
    }
    for (ax, ay, eta) in [
        (0.1, 0.1, Vec3::new(1.45, 1.5, 1.6)),
        (0.3, 0.2, Vec3::new(1.0 / 1.3, 1.0 / 1.33, 1.0 / 1.4)),
    ] {
        cases.push((
            format!("dispersive alpha {ax}/{ay} eta {eta}"),
            Bxdf::dispersive(tr(ax, ay), eta),
        ));
    }
    for (ax, ay, eta, r, d) in [
        (0.0, 0.0, 1.5, 0.5, 0.0),
        (0.2, 0.2, 1.5, 0.5, 0.01),
        (0.1, 0.5, 1.5, 0.8, 0.0),
        (0.7, 0.7, 1.3, 0.3, 0.2),
    ] {
        cases.push((
            format!("coated diffuse alpha {ax}/{ay} eta {eta} r {r} thickness {d}"),
            Bxdf::coated_diffuse(tr(ax, ay), eta, Vec3::new(r, 0.5 * r, 0.25), d),
        ));
    }
    let (al_eta, al_k) = named_metal("Al").unwrap_or((Vec3::ONE, Vec3::ONE));
    for (coat, (bx, by), thickness) in [(0.0, (0.3, 0.3), 0.01), (0.3, (0.1, 0.3), 0.0), (0.2, (0.0, 0.0), 0.05)] {
        cases.push((
            format!("coated conductor coat {coat} base {bx}/{by} thickness {thickness}"),
            Bxdf::coated_conductor(
                DielectricBxdf::new(TrowbridgeReitz::isotropic(coat), 1.5),
                ConductorBxdf::new(tr(bx, by), al_eta, al_k),
                thickness,
                10,
                1,
            ),
        ));
    }
    cases
}

/// Outgoing directions of the chi-square test: near normal, oblique,
/// grazing, and from below the surface.
fn test_directions() -> Vec<Vec3> {
    [0.05f32, 30.0, 60.0, 85.0, 125.0]
        .iter()
        .map(|deg| spherical(deg.to_radians(), 0.7))
        .collect()
}

/// Runs the chi-square test for every (BxDF, wo) in `cases` and checks the
/// p-values against 1% overall, Sidak-corrected for the `total_tests` run
/// by all chi-square tests together.
fn run_chi2(cases: &[(String, Bxdf)], total_tests: usize) {
    let alpha = 1.0 - (1.0f64 - 0.01).powf(1.0 / total_tests as f64);
    for (ci, (name, bxdf)) in cases.iter().enumerate() {
        for (wi, wo) in test_directions().into_iter().enumerate() {
            let seed = (ci * 100 + wi) as u64;
            let out = chi2_test(bxdf, wo, CHI2_SAMPLES, seed);
            if let Some(why) = out.failure {
                panic!("{name}, wo {wo}: {why}");
            }
            assert!(
                out.pdf_mass <= 1.0 + 1e-3,
                "{name}, wo {wo}: pdf integrates to {}",
                out.pdf_mass
            );
            assert!(
                out.p_value > alpha,
                "{name}, wo {wo}: chi-square p-value {:.3e} below {alpha:.3e}",
                out.p_value
            );
        }
    }
}

fn chi2_total_tests() -> usize {
    sampled_bxdfs().len() * test_directions().len()
}

fn cases_named(prefix: &str) -> Vec<(String, Bxdf)> {
    sampled_bxdfs()
        .into_iter()
        .filter(|(n, _)| n.starts_with(prefix))
        .collect()
}

#[test]
fn chi2_diffuse() {
    run_chi2(&cases_named("diffuse"), chi2_total_tests());
}

#[test]
fn chi2_conductor() {
    run_chi2(&cases_named("conductor"), chi2_total_tests());
}

#[test]
fn chi2_dielectric() {
    run_chi2(&cases_named("dielectric"), chi2_total_tests());
}

#[test]
fn chi2_dispersive() {
    run_chi2(&cases_named("dispersive"), chi2_total_tests());
}

#[test]
fn chi2_coated_diffuse() {
    run_chi2(&cases_named("coated diffuse"), chi2_total_tests());
}

#[test]
fn chi2_coated_conductor() {
    run_chi2(&cases_named("coated conductor"), chi2_total_tests());
}

/// The chi-square test must be able to fail: samples of one conductor
/// binned against the pdf of a slightly smoother one (alpha 0.33 vs 0.3).
#[test]
fn chi2_rejects_a_wrong_pdf() {
    let sampled = Bxdf::conductor(TrowbridgeReitz::isotropic(0.33), Vec3::ONE, Vec3::ONE);
    let claimed = Bxdf::conductor(TrowbridgeReitz::isotropic(0.3), Vec3::ONE, Vec3::ONE);
    let wo = spherical(0.5, 0.7);
    let mode = TransportMode::Radiance;
    let mut rng = Rng::new(99, 1);
    let mut observed = vec![0.0f64; SPHERE_BINS];
    let n = CHI2_SAMPLES;
    for _ in 0..n {
        if let Some(bs) = sampled.sample_f(wo, rng.next_f32(), rng.next_2d(), mode) {
            observed[bin_of(bs.wi)] += 1.0;
        }
    }
    let expected = integrate_bins(&|wi| claimed.pdf(wo, wi, mode) as f64, CHI2_EPS);
    let (mut chi2, mut dof) = (0.0, 0);
    for (o, e) in observed.iter().zip(&expected) {
        let e = e * n as f64;
        if e >= 5.0 {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    assert!(
        chi2_p_value(chi2, dof - 1) < 1e-6,
        "a 10% roughness error went unnoticed"
    );
}

// ---------------------------------------------------------------------------
// Microfacet distribution

/// Integrates g(wm) over the hemisphere of microfacet normals of `d` in its
/// stretched slope space: wm = normalize(alpha_x s_x, alpha_y s_y, 1), with
/// |s| = tan(beta), so that dw_m = cos^3(theta_m) alpha_x alpha_y
/// tan(beta) sec^2(beta) dbeta dphi; the integrand is smooth for any alpha.
fn integrate_normals(d: &TrowbridgeReitz, g: impl Fn(Vec3) -> f64) -> f64 {
    let n = 400;
    let (ax, ay) = (d.alpha_x() as f64, d.alpha_y() as f64);
    let mut sum = 0.0;
    for i in 0..n {
        let beta = (i as f64 + 0.5) / n as f64 * PI / 2.0;
        let (t, sec2) = (beta.tan(), 1.0 / (beta.cos() * beta.cos()));
        for j in 0..n {
            let phi = (j as f64 + 0.5) / n as f64 * 2.0 * PI;
            let m = [ax * t * phi.cos(), ay * t * phi.sin(), 1.0];
            let len = (m[0] * m[0] + m[1] * m[1] + 1.0).sqrt();
            let wm = Vec3::new((m[0] / len) as f32, (m[1] / len) as f32, (1.0 / len) as f32);
            let cos3 = (1.0 / len).powi(3);
            sum += g(wm) * cos3 * ax * ay * t * sec2;
        }
    }
    sum * (PI / 2.0 / n as f64) * (2.0 * PI / n as f64)
}

#[test]
fn microfacet_normals_are_normalised_and_the_weak_white_furnace_holds() {
    for (ax, ay) in [
        (0.02, 0.02),
        (0.1, 0.1),
        (0.5, 0.5),
        (1.0, 1.0),
        (2.0, 2.0),
        (0.05, 0.5),
        (1.5, 0.2),
    ] {
        let d = TrowbridgeReitz::new(ax, ay);
        // Projected microfacet area is the macro-surface area.
        let proj = integrate_normals(&d, |wm| d.d(wm) as f64 * wm.z as f64);
        assert!((proj - 1.0).abs() < 2e-3, "alpha {ax}/{ay}: int D cos = {proj}");
        // Heitz 2014 weak white furnace: int G1(wo) max(0, wo.wm) D / cos_o = 1,
        // i.e. the visible normal density is normalised, for any wo.
        for theta in [0.0f32, 45.0, 75.0, 89.0] {
            let wo = spherical(theta.to_radians(), 0.4);
            let weak = integrate_normals(&d, |wm| (d.g1(wo) * wo.dot(wm).max(0.0) * d.d(wm) / wo.z) as f64);
            let visible = integrate_normals(&d, |wm| {
                if wo.dot(wm) > 0.0 {
                    d.d_visible(wo, wm) as f64
                } else {
                    0.0
                }
            });
            assert!((weak - 1.0).abs() < 3e-3, "alpha {ax}/{ay} theta {theta}: {weak}");
            assert!((visible - weak).abs() < 1e-4);
        }
    }
}

#[test]
fn microfacet_basics() {
    assert_eq!(TrowbridgeReitz::roughness_to_alpha(0.25), 0.5);
    let remapped = TrowbridgeReitz::from_roughness(0.04, 0.09, true);
    assert!((remapped.alpha_x() - 0.2).abs() < 1e-6 && (remapped.alpha_y() - 0.3).abs() < 1e-6);
    let direct = TrowbridgeReitz::from_roughness(0.04, 0.09, false);
    assert_eq!((direct.alpha_x(), direct.alpha_y()), (0.04, 0.09));
    // pbrt-v4's threshold: alpha below 1e-3 in both directions is smooth.
    assert!(TrowbridgeReitz::isotropic(0.000_99).effectively_smooth());
    assert!(!TrowbridgeReitz::isotropic(0.001).effectively_smooth());
    assert!(!TrowbridgeReitz::new(0.0, 0.01).effectively_smooth());
    // A rough direction lifts the other alpha off zero.
    assert_eq!(TrowbridgeReitz::new(0.0, 0.01).alpha_x(), 1e-4);
    assert!(TrowbridgeReitz::new(f32::NAN, -1.0).effectively_smooth());
    // Masking: G1 = 1 at normal incidence, falls towards grazing, and G <= G1.
    let d = TrowbridgeReitz::new(0.3, 0.1);
    assert!((d.g1(Vec3::Z) - 1.0).abs() < 1e-6);
    let (a, b) = (spherical(1.0, 0.2), spherical(1.4, 2.0));
    assert!(d.g1(b) < d.g1(a) && d.g(a, b) <= d.g1(a).min(d.g1(b)));
    // Anisotropy: grazing along the rough x axis is masked more than along y.
    assert!(d.g1(spherical(1.4, 0.0)) < d.g1(spherical(1.4, PI as f32 / 2.0)));
    // Sampled normals face the viewer and the +z side, for wo on either side.
    let mut rng = Rng::new(3, 3);
    for _ in 0..1000 {
        let wo = uniform_sphere(rng.next_2d());
        let wm = d.sample_wm(wo, rng.next_2d());
        assert!(wm.z > 0.0 && (wm.length() - 1.0).abs() < 1e-4);
        assert!(wo.dot(wm) * wo.z.signum() >= -1e-4);
    }
}

// ---------------------------------------------------------------------------
// Consistency of sample_f with f and pdf, and reciprocity

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-6
}

#[test]
fn sampled_values_match_f_and_pdf() {
    let mut rng = Rng::new(11, 0);
    for (name, bxdf) in sampled_bxdfs() {
        for mode in [TransportMode::Radiance, TransportMode::Importance] {
            for _ in 0..4000 {
                let wo = uniform_sphere(rng.next_2d());
                let (uc, u) = (rng.next_f32(), rng.next_2d());
                let Some(bs) = bxdf.sample_f(wo, uc, u, mode) else {
                    continue;
                };
                if bs.is_specular() {
                    continue;
                }
                let (f, pdf) = (bxdf.f(wo, bs.wi, mode), bxdf.pdf(wo, bs.wi, mode));
                for c in 0..3 {
                    assert!(
                        close(bs.f[c], f[c], 1e-3),
                        "{name} {mode:?}: sampled f {} vs f {f}",
                        bs.f
                    );
                }
                assert!(close(bs.pdf, pdf, 1e-3), "{name}: sampled pdf {} vs pdf {pdf}", bs.pdf);
                assert!(bs.f.is_finite() && bs.f.min_element() >= 0.0);
                assert_eq!(bs.is_transmission(), !same_hemisphere(wo, bs.wi), "{name}");
                assert!(
                    bxdf.flags().contains(bs.flags),
                    "{name}: {:?} not in {:?}",
                    bs.flags,
                    bxdf.flags()
                );
            }
        }
    }
}

#[test]
fn specular_lobes_have_no_density() {
    let smooth = [
        Bxdf::conductor(TrowbridgeReitz::smooth(), Vec3::splat(0.2), Vec3::splat(3.0)),
        Bxdf::dielectric(TrowbridgeReitz::isotropic(0.0005), 1.5),
        Bxdf::dielectric(TrowbridgeReitz::isotropic(0.3), 1.0),
        Bxdf::thin_dielectric(1.5),
    ];
    let mut rng = Rng::new(12, 0);
    for bxdf in smooth {
        assert!(
            bxdf.flags().is_specular() && !bxdf.flags().is_non_specular(),
            "{bxdf:?}"
        );
        for _ in 0..200 {
            let wo = uniform_sphere(rng.next_2d());
            let bs = bxdf.sample_f(wo, rng.next_f32(), rng.next_2d(), TransportMode::Radiance);
            if let Some(bs) = bs {
                assert!(bs.is_specular());
                assert_eq!(bxdf.f(wo, bs.wi, TransportMode::Radiance), Vec3::ZERO);
                assert_eq!(bxdf.pdf(wo, bs.wi, TransportMode::Radiance), 0.0);
            }
        }
    }
}

#[test]
fn reflection_is_reciprocal_and_transmission_is_adjoint() {
    let tr = TrowbridgeReitz::new;
    let (au_eta, au_k) = named_metal("Au").unwrap_or((Vec3::ONE, Vec3::ONE));
    let bxdfs = [
        Bxdf::diffuse(Vec3::new(0.2, 0.5, 0.9)),
        Bxdf::diffuse_transmission(Vec3::splat(0.3), Vec3::new(0.1, 0.4, 0.5)),
        Bxdf::conductor(tr(0.2, 0.2), au_eta, au_k),
        Bxdf::conductor(tr(0.05, 0.6), au_eta, au_k),
        Bxdf::conductor_from_reflectance(tr(0.4, 0.1), Vec3::new(0.9, 0.5, 0.2)),
        Bxdf::dielectric(tr(0.3, 0.3), 1.5),
        Bxdf::dielectric(tr(0.1, 0.4), 1.0 / 1.33),
        Bxdf::coated_diffuse(tr(0.0, 0.0), 1.5, Vec3::new(0.8, 0.4, 0.1), 0.01),
        Bxdf::coated_diffuse(tr(0.3, 0.3), 1.5, Vec3::new(0.8, 0.4, 0.1), 0.0),
        Bxdf::coated_diffuse(tr(0.05, 0.5), 1.4, Vec3::splat(1.0), 0.3),
    ];
    let mut rng = Rng::new(13, 0);
    let (mut nonzero, mut transmitted) = (0, 0);
    for bxdf in bxdfs {
        for _ in 0..2000 {
            let wo = uniform_sphere(rng.next_2d());
            let wi = uniform_sphere(rng.next_2d());
            let rad = TransportMode::Radiance;
            let imp = TransportMode::Importance;
            let a = bxdf.f(wo, wi, rad);
            // Radiance-mode f is the adjoint of importance-mode f (Veach 1997,
            // 5.2); for reflection, and transmission without refraction,
            // both are the plain reciprocity f(wo, wi) = f(wi, wo).
            let b = bxdf.f(wi, wo, imp);
            for c in 0..3 {
                assert!(close(a[c], b[c], 2e-3), "{bxdf:?}\nwo {wo} wi {wi}: {a} vs {b}");
            }
            if same_hemisphere(wo, wi) || matches!(bxdf, Bxdf::DiffuseTransmission(_)) {
                let b = bxdf.f(wi, wo, rad);
                for c in 0..3 {
                    assert!(close(a[c], b[c], 2e-3), "{bxdf:?}\nwo {wo} wi {wi}: {a} vs {b}");
                }
            } else if a != Vec3::ZERO {
                transmitted += 1;
            }
            nonzero += (a != Vec3::ZERO) as usize;
        }
    }
    assert!(nonzero > 5000 && transmitted > 300, "too few non-zero pairs tested");
}

// ---------------------------------------------------------------------------
// Furnaces and energy

/// Mean of the sampled throughput `f |cos| / pdf` for `wo` over about `n`
/// stratified samples, and its standard error (of the largest channel,
/// computed as if the samples were independent: an overestimate).
fn sampled_albedo(bxdf: &Bxdf, wo: Vec3, mode: TransportMode, n: u32, seed: u64) -> (Vec3, f32) {
    let mut rng = Rng::new(seed, 7);
    let (mut sum, mut sum2) = (Vec3::ZERO, 0.0f64);
    let side = (n as f64).sqrt() as u32;
    for i in 0..side * side {
        let u = crate::sampling::stratified(i, side, rng.next_2d());
        let uc = rng.next_f32();
        if let Some(bs) = bxdf.sample_f(wo, uc, u, mode) {
            let w = bs.weight();
            sum += w;
            sum2 += (w.max_element() as f64).powi(2);
        }
    }
    let m = (side * side) as f64;
    let mean = sum / m as f32;
    let var = (sum2 / m - (mean.max_element() as f64).powi(2)).max(0.0);
    (mean, (var / m).sqrt() as f32)
}

/// Integral of f |cos| over the sphere (each channel), by quadrature:
/// independent of the sampler, but only reliable for lobes the quadrature
/// resolves (alpha >= 0.1 or so).
fn quadrature_albedo(bxdf: &Bxdf, wo: Vec3, mode: TransportMode) -> Vec3 {
    quadrature_albedo_where(bxdf, wo, mode, |_| true)
}

/// [`quadrature_albedo`] restricted to the directions `keep` accepts. Grey
/// BxDFs (the same f in every channel at a probe pair) integrate one channel.
fn quadrature_albedo_where(bxdf: &Bxdf, wo: Vec3, mode: TransportMode, keep: impl Fn(Vec3) -> bool) -> Vec3 {
    let probe = bxdf.f(wo, Vec3::new(-wo.x, -wo.y + 0.1, wo.z).normalize(), mode);
    let grey =
        probe.x == probe.y && probe.y == probe.z && !matches!(bxdf, Bxdf::Diffuse(_) | Bxdf::DiffuseTransmission(_));
    let mut out = Vec3::ZERO;
    for c in 0..if grey { 1 } else { 3 } {
        let g = |wi: Vec3| {
            if keep(wi) {
                (bxdf.f(wo, wi, mode)[c] * wi.z.abs()) as f64
            } else {
                0.0
            }
        };
        out[c] = integrate_bins(&g, 1e-5).iter().sum::<f64>() as f32;
    }
    if grey {
        out = Vec3::splat(out.x);
    }
    out
}

#[test]
fn lambertian_under_constant_light_gives_albedo() {
    let r = Vec3::new(0.2, 0.5, 0.8);
    let bxdf = Bxdf::diffuse(r);
    let l = 3.0;
    for wo in test_directions() {
        // Sampled: every weight is exactly r.
        let (mean, _) = sampled_albedo(&bxdf, wo, TransportMode::Radiance, 1024, 1);
        assert!((mean - r).abs().max_element() < 1e-5);
        // Uniform sphere sampling of f cos L / (1 / 4 pi): an independent estimate.
        let mut rng = Rng::new(21, 0);
        let n = 200_000;
        let mut est = Vec3::ZERO;
        for i in 0..n {
            let wi = uniform_sphere(crate::sampling::stratified(i, 447, rng.next_2d()));
            est += bxdf.f(wo, wi, TransportMode::Radiance) * wi.z.abs() * l * 4.0 * PI as f32;
        }
        est /= n as f32;
        assert!(
            ((est - r * l) / (r * l)).abs().max_element() < 0.01,
            "{est} vs {}",
            r * l
        );
        let q = quadrature_albedo(&bxdf, wo, TransportMode::Radiance);
        assert!((q - r).abs().max_element() < 1e-4, "{q}");
    }
    // Diffuse transmission: reflected plus transmitted is r + t.
    let t = Vec3::new(0.6, 0.3, 0.1);
    let dt = Bxdf::diffuse_transmission(r, t);
    let q = quadrature_albedo(&dt, spherical(0.3, 0.1), TransportMode::Radiance);
    assert!((q - (r + t)).abs().max_element() < 1e-4, "{q}");
}

#[test]
fn white_furnace_conductor() {
    // eta = 1, k = 1e4: Fresnel reflectance 1 - 4e-8 at worst.
    let white = |alpha: f32| Bxdf::conductor(TrowbridgeReitz::isotropic(alpha), Vec3::ONE, Vec3::splat(1e4));
    for theta in [0.0f32, 30.0, 60.0, 85.0] {
        let wo = spherical(theta.to_radians(), 0.3);
        let bs = white(0.0).sample_f(wo, 0.5, Vec2::splat(0.5), TransportMode::Radiance);
        let w = bs.map(|b| b.weight()).unwrap_or(Vec3::ZERO);
        assert!((w - Vec3::ONE).abs().max_element() < 1e-4, "smooth, theta {theta}: {w}");
    }
    // Rough: the single-scattering loss of GGX is below 1% for these. (It
    // is not for much rougher ones: GGX's long tail tilts a fraction
    // alpha^2 / (1 + alpha^2) of the normals seen at normal incidence past
    // 45 degrees, whose reflections leave below the horizon and are lost.)
    for alpha in [0.02f32, 0.05] {
        for theta in [0.0f32, 30.0, 60.0] {
            let wo = spherical(theta.to_radians(), 0.3);
            let (mean, se) = sampled_albedo(&white(alpha), wo, TransportMode::Radiance, 40_000, 2);
            assert!(
                (mean - Vec3::ONE).abs().max_element() < 0.01 && mean.max_element() <= 1.0 + 3.0 * se,
                "alpha {alpha}, theta {theta}: {mean} +- {se}"
            );
        }
    }
}

#[test]
fn white_furnace_dielectric() {
    let imp = TransportMode::Importance;
    let rad = TransportMode::Radiance;
    let eta = 1.5f32;
    // Smooth: every sampled weight is 1 in importance mode, from either side
    // (inside, past the critical angle, everything reflects).
    let smooth = Bxdf::dielectric(TrowbridgeReitz::smooth(), eta);
    for theta in [0.0f32, 30.0, 60.0, 85.0, 100.0, 140.0, 175.0] {
        let wo = spherical(theta.to_radians(), 0.3);
        for uc in [0.0f32, 0.02, 0.3, 0.7, 0.999] {
            if let Some(bs) = smooth.sample_f(wo, uc, Vec2::splat(0.5), imp) {
                assert!((bs.weight() - Vec3::ONE).abs().max_element() < 1e-5, "theta {theta}");
            }
        }
    }
    // Rough, lossless: the energy returned is 1 minus the (< 1%) loss of
    // single scattering, from outside and from inside.
    for alpha in [0.02f32, 0.05] {
        let rough = Bxdf::dielectric(TrowbridgeReitz::isotropic(alpha), eta);
        for theta in [0.0f32, 30.0, 60.0, 120.0, 150.0, 180.0] {
            let wo = spherical(theta.to_radians(), 0.3);
            let (mean, se) = sampled_albedo(&rough, wo, imp, 40_000, 3);
            assert!(
                (mean.x - 1.0).abs() < 0.01 && mean.x <= 1.0 + 3.0 * se,
                "alpha {alpha}, theta {theta}: {mean} +- {se}"
            );
        }
    }
    // Radiance mode: what is transmitted into the glass is compressed by
    // 1/eta^2, what leaves it expanded by eta^2; reflection is the same.
    let rough = Bxdf::dielectric(TrowbridgeReitz::isotropic(0.3), eta);
    for (theta, scale) in [(0.4f32, 1.0 / (eta * eta)), (PI as f32 - 0.4, eta * eta)] {
        let wo = spherical(theta, 0.3);
        let below = |wi: Vec3| !same_hemisphere(wo, wi);
        let t_rad = quadrature_albedo_where(&rough, wo, rad, below).x;
        let t_imp = quadrature_albedo_where(&rough, wo, imp, below).x;
        assert!(t_imp > 0.1 && (t_rad / t_imp - scale).abs() < 1e-3, "{t_rad} / {t_imp}");
        let above = |wi: Vec3| same_hemisphere(wo, wi);
        let r_rad = quadrature_albedo_where(&rough, wo, rad, above).x;
        let r_imp = quadrature_albedo_where(&rough, wo, imp, above).x;
        assert!(r_imp > 0.01 && (r_rad - r_imp).abs() < 1e-6);
        // And the whole, in importance, agrees with the sampled estimate.
        let (mean, se) = sampled_albedo(&rough, wo, imp, 40_000, 8);
        assert!(
            (mean.x - (t_imp + r_imp)).abs() < 4.0 * se + 2e-3,
            "{mean} vs {}",
            t_imp + r_imp
        );
    }
    // A thin slab reflects and transmits everything it does not absorb: all.
    let thin = Bxdf::thin_dielectric(eta);
    for theta in [0.0f32, 50.0, 89.0, 130.0] {
        let wo = spherical(theta.to_radians(), 0.3);
        let (mean, _) = sampled_albedo(&thin, wo, rad, 10_000, 4);
        assert!(
            (mean - Vec3::ONE).abs().max_element() < 1e-4,
            "thin, theta {theta}: {mean}"
        );
    }
}

#[test]
fn smooth_dielectric_splits_by_fresnel_and_scales_radiance_only() {
    let eta = 1.5f32;
    let glass = Bxdf::dielectric(TrowbridgeReitz::smooth(), eta);
    for theta in [0.0f32, 0.5, 1.0, 1.4] {
        let wo = spherical(theta, 0.0);
        let fr = fr_dielectric(wo.z, eta);
        let n = 10_000;
        let mut reflected = 0;
        for i in 0..n {
            let uc = (i as f32 + 0.5) / n as f32;
            let rad = glass.sample_f(wo, uc, Vec2::ZERO, TransportMode::Radiance).unwrap();
            let imp = glass.sample_f(wo, uc, Vec2::ZERO, TransportMode::Importance).unwrap();
            assert_eq!(rad.wi, imp.wi);
            if rad.is_reflection() {
                reflected += 1;
                assert_eq!(rad.flags, BxdfFlags::SPECULAR_REFLECTION);
                assert!((rad.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
                assert!((rad.weight().x - 1.0).abs() < 1e-5 && rad.eta == 1.0);
            } else {
                assert_eq!(rad.flags, BxdfFlags::SPECULAR_TRANSMISSION);
                assert!(rad.wi.z < 0.0 && rad.eta == eta);
                // Radiance is compressed by 1/eta^2 entering the glass...
                assert!((rad.weight().x - 1.0 / (eta * eta)).abs() < 1e-5);
                // ...importance (power) is not.
                assert!((imp.weight().x - 1.0).abs() < 1e-5);
                // Snell's law.
                let sin_t = (rad.wi.x * rad.wi.x + rad.wi.y * rad.wi.y).sqrt();
                assert!((theta.sin() - eta * sin_t).abs() < 1e-4);
            }
        }
        // Reflection is chosen with probability F.
        let frac = reflected as f32 / n as f32;
        assert!((frac - fr).abs() < 2e-4, "theta {theta}: {frac} vs F {fr}");
    }
    // Leaving the glass, radiance is multiplied by eta^2 and eta is 1/eta.
    let wo = spherical(PI as f32 - 0.3, 0.0);
    let bs = glass.sample_f(wo, 0.999, Vec2::ZERO, TransportMode::Radiance).unwrap();
    assert!(bs.is_transmission() && (bs.eta - 1.0 / eta).abs() < 1e-6);
    assert!((bs.weight().x - eta * eta).abs() < 1e-4);
    // Past the critical angle inside, every sample reflects.
    let wo = spherical(PI as f32 - 0.9, 0.0);
    for uc in [0.0, 0.5, 0.999] {
        let bs = glass.sample_f(wo, uc, Vec2::ZERO, TransportMode::Radiance).unwrap();
        assert!(bs.is_reflection());
    }
    // eta = 1 is an index-matched boundary: straight through, nothing reflected.
    let matched = Bxdf::dielectric(TrowbridgeReitz::smooth(), 1.0);
    assert_eq!(matched.flags(), BxdfFlags::SPECULAR_TRANSMISSION);
    let bs = matched.sample_f(spherical(0.7, 1.0), 0.0, Vec2::ZERO, TransportMode::Radiance);
    let bs = bs.unwrap();
    assert!((bs.wi + spherical(0.7, 1.0)).length() < 1e-5 && (bs.weight().x - 1.0).abs() < 1e-5);
}

#[test]
fn a_smooth_dispersive_interface_is_each_channels_dielectric_on_average() {
    // Over its samples, each channel of a dispersive interface reflects its
    // own Fresnel reflectance into the mirror direction and transmits the
    // rest along its own refracted direction, which no other channel takes.
    let eta = Vec3::new(1.45, 1.5, 1.6);
    let glass = Bxdf::dispersive(TrowbridgeReitz::smooth(), eta);
    assert_eq!(
        glass.flags(),
        BxdfFlags::SPECULAR_REFLECTION | BxdfFlags::SPECULAR_TRANSMISSION
    );
    for theta in [0.3f32, 1.0, 1.4, PI as f32 - 0.3, PI as f32 - 0.75] {
        let wo = spherical(theta, 0.4);
        for mode in [TransportMode::Radiance, TransportMode::Importance] {
            let n = 30_000;
            let (mut reflected, mut transmitted) = (Vec3::ZERO, Vec3::ZERO);
            for i in 0..n {
                let uc = (i as f32 + 0.5) / n as f32;
                let bs = glass.sample_f(wo, uc, Vec2::ZERO, mode).unwrap();
                if bs.is_reflection() {
                    assert!((bs.wi - mirror(wo)).length() < 1e-6);
                    reflected += bs.weight() / n as f32;
                    continue;
                }
                let c = (0..3).find(|&c| bs.f[c] > 0.0).unwrap();
                assert_eq!(bs.f[(c + 1) % 3] + bs.f[(c + 2) % 3], 0.0, "{}", bs.f);
                let one = Bxdf::dielectric(TrowbridgeReitz::smooth(), eta[c]);
                let want = one.sample_f(wo, 0.999_99, Vec2::ZERO, mode).unwrap();
                assert!((bs.wi - want.wi).length() < 1e-5 && bs.eta == want.eta);
                transmitted += bs.weight() / n as f32;
            }
            for c in 0..3 {
                let r = fr_dielectric(wo.z, eta[c]);
                let etap = if wo.z > 0.0 { eta[c] } else { 1.0 / eta[c] };
                let t = (1.0 - r)
                    / if mode == TransportMode::Radiance {
                        etap * etap
                    } else {
                        1.0
                    };
                assert!(
                    (reflected[c] - r).abs() < 2e-3,
                    "theta {theta}, {c}: {reflected} vs R {r}"
                );
                assert!(
                    (transmitted[c] - t).abs() < 2e-3,
                    "theta {theta}, {c}: {transmitted} vs T {t}"
                );
            }
        }
    }
}

#[test]
fn a_dispersive_interface_follows_the_channels_a_path_carries() {
    // Once a path carries green alone, every refraction is green's, with
    // weight T / T = 1 (importance), and a reflection weighs each channel
    // by its reflectance over green's; rough samples stay consistent with
    // f and pdf under the same weights.
    let eta = Vec3::new(1.45, 1.5, 1.6);
    let wo = spherical(0.8, 0.2);
    for alpha in [0.0f32, 0.2] {
        let mut bsdf = Bsdf::new(
            Bxdf::dispersive(TrowbridgeReitz::isotropic(alpha), eta),
            Vec3::Z,
            Vec3::X,
        );
        bsdf.carry(Vec3::new(0.0, 0.7, 0.0));
        let green = Bxdf::dielectric(TrowbridgeReitz::isotropic(alpha), eta.y);
        for i in 0..1000 {
            let (uc, u) = ((i as f32 + 0.5) / 1000.0, Vec2::new(0.3, (i % 7) as f32 / 7.0));
            let Some(bs) = bsdf.sample_f(wo, uc, u, TransportMode::Importance) else {
                continue;
            };
            if bs.is_specular() && bs.is_transmission() {
                let want = green.sample_f(wo, 0.999_99, u, TransportMode::Importance).unwrap();
                assert!((bs.wi - want.wi).length() < 1e-5);
                assert!((bs.weight() - Vec3::Y).abs().max_element() < 1e-5, "{}", bs.weight());
            } else if bs.is_specular() {
                let r = eta.to_array().map(|e| fr_dielectric(wo.z, e));
                let want = Vec3::from_array(r) / r[1];
                assert!((bs.weight() - want).abs().max_element() < 1e-4, "{}", bs.weight());
            } else {
                let (f, pdf) = bsdf.f_pdf(wo, bs.wi, TransportMode::Importance);
                assert!(close(bs.pdf, pdf, 1e-3) && (bs.f - f).abs().max_element() <= 1e-3 * f.max_element());
                // Green's density alone: the others are never followed.
                let green_pdf = green.pdf(wo, bsdf.frame.to_local(bs.wi), TransportMode::Importance);
                assert!(close(pdf, green_pdf, 1e-4), "{pdf} vs {green_pdf}");
            }
        }
    }
}

#[test]
fn conductor_reflectance_mode_matches_at_normal_incidence() {
    let r = Vec3::new(0.95, 0.64, 0.54);
    let Bxdf::Conductor(c) = Bxdf::conductor_from_reflectance(TrowbridgeReitz::smooth(), r) else {
        unreachable!()
    };
    assert_eq!(c.eta, Vec3::ONE);
    let f0 = fr_complex_rgb(1.0, c.eta, c.k);
    assert!((f0 - r).abs().max_element() < 1e-5, "{f0}");
    // Grazing incidence reflects everything, as for any conductor.
    assert!(fr_complex_rgb(1e-4, c.eta, c.k).min_element() > 0.99);
    // r = 1 is clamped as pbrt-v4 does, so k stays finite.
    let Bxdf::Conductor(c) = Bxdf::conductor_from_reflectance(TrowbridgeReitz::smooth(), Vec3::ONE) else {
        unreachable!()
    };
    assert!(c.k.is_finite() && (fr_complex(1.0, 1.0, c.k.x) - 0.9999).abs() < 1e-5);
}

#[test]
fn named_metals_have_their_colours() {
    let f0 = |name: &str| {
        let (eta, k) = named_metal(name).unwrap_or((Vec3::ONE, Vec3::ZERO));
        fr_complex_rgb(1.0, eta, k)
    };
    let (au, cu, ag, al) = (f0("Au"), f0("Cu"), f0("Ag"), f0("Al"));
    // Gold and copper are warm, copper more orange (less green for its red);
    // silver and aluminium grey and bright.
    assert!(au.x > au.y && au.y > au.z && cu.x > cu.y && cu.y > cu.z);
    assert!(cu.y / cu.x < au.y / au.x - 0.05);
    assert!(ag.min_element() > 0.85 && al.min_element() > 0.85);
    assert!((ag.max_element() - ag.min_element()) < 0.1);
}

#[test]
fn no_bxdf_creates_energy() {
    let mut rng = Rng::new(17, 0);
    let rand_rgb = |rng: &mut Rng| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    for case in 0..30 {
        let alpha_x = rng.next_f32().powi(2) * 1.2;
        let alpha_y = if case % 3 == 0 { rng.next_f32() } else { alpha_x };
        let distrib = TrowbridgeReitz::new(alpha_x, alpha_y);
        let eta = 1.0 + 1.5 * rng.next_f32();
        let eta = if case % 4 == 1 { 1.0 / eta } else { eta };
        let r = rand_rgb(&mut rng);
        let t = (Vec3::ONE - r) * rng.next_f32();
        let (m_eta, m_k) = (rand_rgb(&mut rng) * 3.0, rand_rgb(&mut rng) * 6.0);
        let bxdfs = [
            Bxdf::diffuse(r),
            Bxdf::diffuse_transmission(r, t),
            Bxdf::conductor(distrib, m_eta, m_k),
            Bxdf::conductor_from_reflectance(distrib, r),
            Bxdf::dielectric(distrib, eta),
            Bxdf::thin_dielectric(eta),
            // A few coat indices only: each new one costs a table.
            Bxdf::coated_diffuse(distrib, [1.2, 1.5, 2.4][case as usize % 3], r, 0.1 * rng.next_f32()),
            Bxdf::coated_diffuse(distrib, [1.33, 1.5, 2.0][case as usize % 3], Vec3::ONE, 0.0),
        ];
        for bxdf in bxdfs {
            let wo = uniform_sphere(rng.next_2d());
            // Power (importance) is conserved or lost; never created.
            let (mean, se) = sampled_albedo(&bxdf, wo, TransportMode::Importance, 4096, case);
            assert!(
                mean.max_element() <= 1.0 + 4.0 * se + 1e-3,
                "{bxdf:?}\nwo {wo}: albedo {mean} +- {se}"
            );
        }
    }
}

#[test]
fn quadrature_albedo_never_exceeds_one() {
    // The same without the sampler: the integral of f |cos| itself.
    let tr = TrowbridgeReitz::new;
    let bxdfs = [
        Bxdf::conductor(tr(0.5, 0.5), Vec3::ONE, Vec3::splat(1e4)),
        Bxdf::conductor(tr(1.0, 0.3), Vec3::ONE, Vec3::splat(1e4)),
        Bxdf::dielectric(tr(0.5, 0.5), 1.5),
        Bxdf::dielectric(tr(0.8, 0.2), 1.0 / 1.5),
        Bxdf::coated_diffuse(tr(0.0, 0.0), 1.5, Vec3::ONE, 0.0),
        Bxdf::coated_diffuse(tr(0.3, 0.3), 1.5, Vec3::ONE, 0.0),
        Bxdf::coated_diffuse(tr(1.0, 1.0), 2.5, Vec3::ONE, 0.0),
    ];
    for bxdf in bxdfs {
        for theta in [0.1f32, 45.0, 80.0, 89.0, 135.0] {
            let wo = spherical(theta.to_radians(), 0.9);
            let mut q = quadrature_albedo(&bxdf, wo, TransportMode::Importance);
            if let Bxdf::CoatedDiffuse(c) = bxdf {
                if c.distrib.effectively_smooth() {
                    q += Vec3::splat(fr_dielectric(wo.z.abs(), c.eta));
                }
            }
            assert!(q.max_element() <= 1.0 + 2e-3, "{bxdf:?}\ntheta {theta}: {q}");
        }
    }
}

#[test]
fn white_furnace_coated_diffuse() {
    // A white base under a clear smooth coat reflects everything: what the
    // coat does not reflect reaches the base, and all of it leaves in the end.
    let smooth = Bxdf::coated_diffuse(TrowbridgeReitz::smooth(), 1.5, Vec3::ONE, 0.0);
    for theta in [0.0f32, 30.0, 60.0, 85.0, 150.0] {
        let wo = spherical(theta.to_radians(), 0.3);
        let (mean, se) = sampled_albedo(&smooth, wo, TransportMode::Radiance, 40_000, 5);
        assert!(
            (mean - Vec3::ONE).abs().max_element() < 0.01,
            "theta {theta}: {mean} +- {se}"
        );
        let q = quadrature_albedo(&smooth, wo, TransportMode::Radiance).x + fr_dielectric(wo.z.abs(), 1.5);
        assert!((q - 1.0).abs() < 0.01, "theta {theta}: {q}");
    }
    // Rough coats lose what single scattering at their interface loses, once
    // from outside and at every internal reflection: the base's light meets
    // the coat 1 / (1 - rho) = 2.5 times on average at eta 1.5. That stays
    // below 1% for alpha up to 0.02 (it is 2% at alpha 0.05, 6% at 0.1, as in
    // pbrt-v4's layered model, which uses the same interface).
    for alpha in [0.01f32, 0.02] {
        let rough = Bxdf::coated_diffuse(TrowbridgeReitz::isotropic(alpha), 1.5, Vec3::ONE, 0.0);
        for theta in [0.0f32, 30.0, 60.0] {
            let wo = spherical(theta.to_radians(), 0.3);
            let (mean, se) = sampled_albedo(&rough, wo, TransportMode::Radiance, 40_000, 5);
            assert!(
                (mean.x - 1.0).abs() < 0.01,
                "alpha {alpha} theta {theta}: {mean} +- {se}"
            );
        }
    }
}

// ---------------------------------------------------------------------------
// The world-space wrapper

#[test]
fn bsdf_in_world_space_matches_the_local_bxdf() {
    let bxdf = Bxdf::conductor(TrowbridgeReitz::new(0.1, 0.5), Vec3::splat(0.2), Vec3::splat(3.0));
    let n = Vec3::new(0.3, -0.5, 0.8).normalize();
    let bsdf = Bsdf::new(bxdf, n, Vec3::new(1.0, 1.0, 0.0));
    let mut rng = Rng::new(19, 0);
    for _ in 0..500 {
        let wo = uniform_sphere(rng.next_2d());
        let (uc, u) = (rng.next_f32(), rng.next_2d());
        let Some(bs) = bsdf.sample_f(wo, uc, u, TransportMode::Radiance) else {
            continue;
        };
        let local = bxdf.sample_f(bsdf.frame.to_local(wo), uc, u, TransportMode::Radiance);
        let local = local.unwrap_or(bs);
        assert!((bsdf.frame.to_local(bs.wi) - local.wi).length() < 1e-5);
        assert!(close(bsdf.pdf(wo, bs.wi, TransportMode::Radiance), bs.pdf, 1e-3));
        let f = bsdf.f(wo, bs.wi, TransportMode::Radiance);
        assert!(close(f.x, bs.f.x, 1e-3));
        // Reflection stays on wo's side of the shading normal.
        assert!(wo.dot(n) * bs.wi.dot(n) > 0.0);
    }
    // Directions in the tangent plane scatter nothing.
    let flat = Bsdf::new(bxdf, Vec3::Z, Vec3::X);
    assert_eq!(flat.f(Vec3::Y, Vec3::Z, TransportMode::Radiance), Vec3::ZERO);
    assert_eq!(flat.pdf(Vec3::Y, Vec3::Z, TransportMode::Radiance), 0.0);
    assert!(flat
        .sample_f(Vec3::Y, 0.5, Vec2::splat(0.5), TransportMode::Radiance)
        .is_none());
}

#[test]
fn flags_describe_the_lobes() {
    let tr = TrowbridgeReitz::isotropic;
    assert_eq!(Bxdf::diffuse(Vec3::ONE).flags(), BxdfFlags::DIFFUSE_REFLECTION);
    assert_eq!(Bxdf::diffuse(Vec3::ZERO).flags(), BxdfFlags::UNSET);
    assert_eq!(
        Bxdf::conductor(tr(0.0), Vec3::ONE, Vec3::ONE).flags(),
        BxdfFlags::SPECULAR_REFLECTION
    );
    assert_eq!(
        Bxdf::conductor(tr(0.2), Vec3::ONE, Vec3::ONE).flags(),
        BxdfFlags::GLOSSY_REFLECTION
    );
    let glass = Bxdf::dielectric(tr(0.2), 1.5).flags();
    assert!(glass.contains(BxdfFlags::GLOSSY_REFLECTION | BxdfFlags::GLOSSY_TRANSMISSION));
    let coated = Bxdf::coated_diffuse(tr(0.0), 1.5, Vec3::splat(0.5), 0.01).flags();
    assert!(coated.contains(BxdfFlags::DIFFUSE_REFLECTION | BxdfFlags::SPECULAR) && !coated.is_transmissive());
    assert!(coated.is_non_specular());
    assert_eq!(
        format!("{:?}", BxdfFlags::GLOSSY_TRANSMISSION),
        "BxdfFlags(Transmission | Glossy)"
    );
    assert_eq!(!TransportMode::Radiance, TransportMode::Importance);
}

// ---------------------------------------------------------------------------
// The coated diffuse against pbrt-v4's stochastic layered model

/// Directional albedo of pbrt-v4's `CoatedDiffuseBxDF` (a `LayeredBxDF` with
/// a dielectric top, a diffuse bottom, no scattering medium) for light
/// leaving at `wo`, by the analog random walk its `Sample_f` performs:
/// enter through the top (or reflect off it), then alternate between the
/// interfaces, each crossing of the layer attenuated by exp(-thickness / |cos|),
/// for at most `max_depth` scattering events. Returns the mean and its
/// standard error.
fn layered_albedo(
    distrib: TrowbridgeReitz,
    eta: f32,
    r: f32,
    thickness: f32,
    max_depth: usize,
    wo: Vec3,
    n: usize,
) -> (f64, f64) {
    let top = Bxdf::dielectric(distrib, eta);
    let bottom = Bxdf::diffuse(Vec3::splat(r));
    walk_albedo(top, bottom, thickness, max_depth, wo, n)
}

/// The analog random walk of [`layered_albedo`] between any two interfaces
/// (first channel).
fn walk_albedo(top: Bxdf, bottom: Bxdf, thickness: f32, max_depth: usize, wo: Vec3, n: usize) -> (f64, f64) {
    let mode = TransportMode::Radiance;
    let mut rng = Rng::new(23, 0);
    let (mut total, mut total2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let Some(bs) = top.sample_f(wo, rng.next_f32(), rng.next_2d(), mode) else {
            continue;
        };
        let mut beta = bs.weight().x as f64;
        if bs.is_reflection() {
            total += beta;
            total2 += beta * beta;
            continue;
        }
        let (mut w, mut at_top) = (bs.wi, true);
        for _ in 0..max_depth {
            // Cross the layer to the other interface.
            beta *= (-(thickness / w.z.abs()) as f64).exp();
            at_top = !at_top;
            let interface = if at_top { &top } else { &bottom };
            let Some(bs) = interface.sample_f(-w, rng.next_f32(), rng.next_2d(), mode) else {
                break;
            };
            beta *= bs.weight().x as f64;
            w = bs.wi;
            if bs.is_transmission() {
                total += beta;
                total2 += beta * beta;
                break;
            }
        }
    }
    let mean = total / n as f64;
    (mean, ((total2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt())
}

#[test]
fn coated_diffuse_against_layered_random_walk() {
    let n = 40_000;
    println!("alpha  r    cos_o  thickness  ours    layered         layered, maxdepth 10");
    for alpha in [0.0f32, 0.3] {
        let distrib = TrowbridgeReitz::isotropic(alpha);
        for r in [0.5f32, 0.9] {
            for thickness in [0.0f32, 0.01] {
                let ours = Bxdf::coated_diffuse(distrib, 1.5, Vec3::splat(r), thickness);
                for theta in [0.0f32, 80.0] {
                    let wo = spherical(theta.to_radians(), 0.0);
                    let (mine, se) = sampled_albedo(&ours, wo, TransportMode::Radiance, n as u32, 6);
                    // The same physics as ours, without pbrt-v4's depth limit...
                    let (walk, walk_se) = layered_albedo(distrib, 1.5, r, thickness, 1000, wo, n);
                    // ...and with it (pbrt-v4's default maxdepth), for the record.
                    let pbrt = if thickness > 0.0 {
                        format!("{:.4}", layered_albedo(distrib, 1.5, r, thickness, 10, wo, n).0)
                    } else {
                        String::new()
                    };
                    println!(
                        "{alpha:.1}    {r:.1}  {:.3}  {thickness:.2}       {:.4}  {walk:.4}+-{walk_se:.4}  {pbrt}",
                        wo.z, mine.x
                    );
                    // Exact for smooth coats (up to the noise of both
                    // estimates); approximations for rough ones.
                    let model = if alpha == 0.0 { 0.0 } else { 0.02 * walk };
                    let noise = 4.0 * (walk_se * walk_se + (se * se) as f64).sqrt();
                    assert!(
                        (mine.x as f64 - walk).abs() < model + noise,
                        "alpha {alpha} r {r} thickness {thickness} theta {theta}: ours {} vs layered {walk}",
                        mine.x
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------
// The coated conductor against the analog walk of pbrt-v4's model

#[test]
fn coated_conductor_against_layered_random_walk() {
    // Grey metals, so the walk's first channel says it all.
    let (eta, k) = (Vec3::splat(0.9), Vec3::splat(3.5));
    let n = 40_000;
    println!("coat  base  thickness  cos_o  ours             walk");
    for coat in [0.0f32, 0.3] {
        for base in [0.0f32, 0.3] {
            for thickness in [0.0f32, 0.05] {
                let top = DielectricBxdf::new(TrowbridgeReitz::isotropic(coat), 1.5);
                let metal = ConductorBxdf::new(TrowbridgeReitz::isotropic(base), eta, k);
                let ours = Bxdf::coated_conductor(top, metal, thickness, 100, 1);
                // The walk sees the metal from inside the coat.
                let bottom = Bxdf::conductor(TrowbridgeReitz::isotropic(base), eta / 1.5, k / 1.5);
                for theta in [0.0f32, 70.0] {
                    let wo = spherical(theta.to_radians(), 0.3);
                    let (mine, se) = sampled_albedo(&ours, wo, TransportMode::Radiance, n as u32, 6);
                    let (walk, walk_se) = walk_albedo(Bxdf::Dielectric(top), bottom, thickness, 100, wo, n);
                    println!(
                        "{coat:.1}   {base:.1}   {thickness:.2}       {:.3}  {:.4}+-{se:.4}  {walk:.4}+-{walk_se:.4}",
                        wo.z, mine.x
                    );
                    // Both estimate the same quantity: they differ by noise only.
                    let noise = 4.0 * (walk_se * walk_se + (se * se) as f64).sqrt() + 2e-3;
                    assert!(
                        (mine.x as f64 - walk).abs() < noise,
                        "coat {coat} base {base} thickness {thickness} theta {theta}: ours {} vs walk {walk}",
                        mine.x
                    );
                    // Photons see the same reflectance: the coat's 1/eta^2
                    // going in is undone coming out in either mode.
                    let (imp, imp_se) = sampled_albedo(&ours, wo, TransportMode::Importance, n as u32, 7);
                    let noise = 4.0 * (imp_se * imp_se + se * se).sqrt() + 2e-3;
                    assert!(
                        (imp.x - mine.x).abs() < noise,
                        "importance {} vs radiance {}",
                        imp.x,
                        mine.x
                    );
                }
            }
        }
    }
}

#[test]
fn coated_conductor_is_deterministic_and_two_sided() {
    let b = Bxdf::coated_conductor(
        DielectricBxdf::new(TrowbridgeReitz::isotropic(0.2), 1.5),
        ConductorBxdf::new(TrowbridgeReitz::isotropic(0.3), Vec3::splat(0.2), Vec3::splat(3.0)),
        0.01,
        10,
        1,
    );
    let (wo, wi) = (spherical(0.4, 0.1), spherical(0.7, 2.0));
    let f = b.f(wo, wi, TransportMode::Radiance);
    assert!(f.min_element() > 0.0);
    assert_eq!(f, b.f(wo, wi, TransportMode::Radiance));
    assert_eq!(f, b.f(-wo, -wi, TransportMode::Radiance));
    assert_eq!(b.f(wo, -wi, TransportMode::Radiance), Vec3::ZERO);
}

#[test]
fn a_bsdf_that_says_it_reads_no_lobe_choice_reads_none() {
    let mut cases = sampled_bxdfs();
    cases.push((
        "smooth conductor".into(),
        Bxdf::conductor(TrowbridgeReitz::smooth(), Vec3::splat(0.2), Vec3::splat(3.0)),
    ));
    cases.push(("thin dielectric".into(), Bxdf::thin_dielectric(1.5)));
    cases.push((
        "smooth dielectric".into(),
        Bxdf::dielectric(TrowbridgeReitz::smooth(), 1.5),
    ));
    let mut rng = Rng::new(3, 8);
    for (name, bxdf) in cases {
        let bsdf = Bsdf::new(bxdf, Vec3::Z, Vec3::X);
        let mut differs = false;
        for wo in test_directions() {
            for _ in 0..64 {
                let u = rng.next_2d();
                let a = bsdf.sample_f(wo, 0.05, u, TransportMode::Radiance);
                let b = bsdf.sample_f(wo, 0.95, u, TransportMode::Radiance);
                let key = |s: Option<BsdfSample>| s.map(|s| (s.wi, s.f, s.pdf));
                differs |= key(a) != key(b);
            }
        }
        // Whoever ignores it must; the others choose lobes with it.
        assert_eq!(differs, bsdf.uses_lobe_choice(), "{name}");
    }
}

#[test]
fn f_pdf_is_f_and_pdf_together() {
    let mut rng = Rng::new(12, 4);
    for (name, bxdf) in sampled_bxdfs() {
        let bsdf = Bsdf::new(bxdf, Vec3::new(0.3, -0.2, 0.9).normalize(), Vec3::X);
        for _ in 0..200 {
            let (wo, wi) = (uniform_sphere(rng.next_2d()), uniform_sphere(rng.next_2d()));
            for mode in [TransportMode::Radiance, TransportMode::Importance] {
                let (f, pdf) = bsdf.f_pdf(wo, wi, mode);
                assert_eq!(f, bsdf.f(wo, wi, mode), "{name}");
                assert_eq!(pdf.to_bits(), bsdf.pdf(wo, wi, mode).to_bits(), "{name}");
            }
        }
    }
}

// ---------------------------------------------------------------------------
// A coat whose medium scatters, against the analog walk through it

/// The analog walk of [`walk_albedo`] with a medium of unit extinction
/// between the interfaces: free flights, Henyey-Greenstein scattering with
/// probability `albedo`, each event counted against `max_depth` (first
/// channel).
#[allow(clippy::too_many_arguments)]
fn medium_walk_albedo(
    top: Bxdf,
    bottom: Bxdf,
    thickness: f32,
    albedo: f32,
    g: f32,
    max_depth: usize,
    wo: Vec3,
    n: usize,
) -> (f64, f64) {
    let mode = TransportMode::Radiance;
    let mut rng = Rng::new(29, 0);
    let (mut total, mut total2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let Some(bs) = top.sample_f(wo, rng.next_f32(), rng.next_2d(), mode) else {
            continue;
        };
        let mut beta = bs.weight().x as f64;
        if bs.is_reflection() {
            total += beta;
            total2 += beta * beta;
            continue;
        }
        let (mut w, mut z) = (bs.wi, thickness);
        for _ in 0..max_depth {
            let dz = -(1.0 - rng.next_f32()).ln() * w.z.abs();
            let zp = if w.z > 0.0 { z + dz } else { z - dz };
            if 0.0 < zp && zp < thickness {
                beta *= albedo as f64;
                w = crate::medium::sample_henyey_greenstein(w, g, rng.next_2d()).0;
                z = zp;
                continue;
            }
            z = zp.clamp(0.0, thickness);
            let interface = if z == thickness { &top } else { &bottom };
            let Some(bs) = interface.sample_f(-w, rng.next_f32(), rng.next_2d(), mode) else {
                break;
            };
            beta *= bs.weight().x as f64;
            w = bs.wi;
            if bs.is_transmission() {
                total += beta;
                total2 += beta * beta;
                break;
            }
        }
    }
    let mean = total / n as f64;
    (mean, ((total2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt())
}

#[test]
fn scattering_coats_against_the_analog_walk() {
    let n = 40_000;
    let (eta, k) = (Vec3::splat(0.9), Vec3::splat(3.5));
    println!("base        coat  albedo  g     thickness  cos_o  ours             walk");
    // A white base under a white medium and a smooth coat loses nothing:
    // both give 1.
    let mut furnace = 0;
    for (base, r) in [
        ("diffuse", 1.0f32),
        ("diffuse", 0.5),
        ("metal 0.3", 0.0),
        ("metal 0", 0.0),
    ] {
        for coat in [0.0f32, 0.3] {
            for (albedo, g, thickness) in [(1.0f32, 0.0f32, 0.5f32), (0.8, 0.6, 0.2), (0.5, -0.3, 1.0)] {
                let top = DielectricBxdf::new(TrowbridgeReitz::isotropic(coat), 1.5);
                let (ours, bottom) = if base == "diffuse" {
                    let ours = ScatteringCoatBxdf::over_diffuse(
                        top,
                        Vec3::splat(r),
                        thickness,
                        Vec3::splat(albedo),
                        g,
                        255,
                        1,
                    );
                    (ours, Bxdf::diffuse(Vec3::splat(r)))
                } else {
                    let alpha = if base == "metal 0" { 0.0 } else { 0.3 };
                    let metal = ConductorBxdf::new(TrowbridgeReitz::isotropic(alpha), eta, k);
                    let ours =
                        ScatteringCoatBxdf::over_conductor(top, metal, thickness, Vec3::splat(albedo), g, 255, 1);
                    // The walk sees the metal from inside the coat.
                    (
                        ours,
                        Bxdf::conductor(TrowbridgeReitz::isotropic(alpha), eta / 1.5, k / 1.5),
                    )
                };
                let ours = Bxdf::ScatteringCoat(ours);
                for theta in [0.0f32, 70.0] {
                    let wo = spherical(theta.to_radians(), 0.3);
                    let (mine, se) = sampled_albedo(&ours, wo, TransportMode::Radiance, n as u32, 6);
                    let (walk, walk_se) =
                        medium_walk_albedo(Bxdf::Dielectric(top), bottom, thickness, albedo, g, 1000, wo, n);
                    println!(
                        "{base:10}  {coat:.1}   {albedo:.1}     {g:4.1}  {thickness:.1}        {:.3}  {:.4}+-{se:.4}  {walk:.4}+-{walk_se:.4}",
                        wo.z, mine.x
                    );
                    let noise = 4.0 * (walk_se * walk_se + (se * se) as f64).sqrt() + 2e-3;
                    assert!(
                        (mine.x as f64 - walk).abs() < noise,
                        "{base} coat {coat} albedo {albedo} g {g} thickness {thickness} theta {theta}: ours {} vs walk {walk}",
                        mine.x
                    );
                    // (A rough coat loses what its microfacets scatter
                    // more than once, at every crossing.)
                    if r == 1.0 && albedo == 1.0 && coat == 0.0 {
                        assert!(
                            (walk - 1.0).abs() < 4.0 * walk_se + 1e-3,
                            "the walk loses energy: {walk}"
                        );
                        assert!((mine.x as f64 - 1.0).abs() < 4.0 * se as f64 + 2e-3, "ours: {}", mine.x);
                        furnace += 1;
                    }
                }
            }
        }
    }
    assert_eq!(furnace, 2);
}

#[test]
fn regularizing_makes_smooth_interfaces_glossy_as_pbrt_does() {
    // pbrt-v4's rule: alphas below 0.3 doubled, kept within [0.1, 0.3].
    let r = |ax: f32, ay: f32| {
        let d = TrowbridgeReitz::new(ax, ay).regularized();
        (d.alpha_x(), d.alpha_y())
    };
    assert_eq!(r(0.0, 0.0), (0.1, 0.1));
    assert_eq!(r(0.02, 0.12), (0.1, 0.24));
    assert_eq!(r(0.2, 0.3), (0.3, 0.3));
    assert_eq!(r(0.5, 0.05), (0.5, 0.1));
    // A mirror becomes a glossy reflector; a smooth coat over a metal, both
    // interfaces; a Lambertian surface stays as it is.
    let mut mirror = Bxdf::conductor(TrowbridgeReitz::smooth(), Vec3::ONE, Vec3::splat(3.0));
    assert!(mirror.flags().is_specular());
    mirror.regularize();
    assert!(mirror.flags().is_non_specular() && !mirror.flags().is_specular());
    let Bxdf::Conductor(c) = mirror else { panic!() };
    assert_eq!((c.distrib.alpha_x(), c.distrib.alpha_y()), (0.1, 0.1));
    let mut coated = Bxdf::coated_conductor(
        DielectricBxdf::new(TrowbridgeReitz::smooth(), 1.5),
        ConductorBxdf::new(TrowbridgeReitz::isotropic(0.04), Vec3::splat(0.2), Vec3::splat(3.0)),
        0.01,
        10,
        1,
    );
    coated.regularize();
    let Bxdf::CoatedConductor(c) = coated else { panic!() };
    assert_eq!((c.coat.distrib.alpha_x(), c.base.distrib.alpha_x()), (0.1, 0.1));
    let mut diffuse = Bxdf::diffuse(Vec3::splat(0.5));
    let before = diffuse;
    diffuse.regularize();
    assert_eq!(diffuse, before);
}
