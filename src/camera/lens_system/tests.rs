use super::*;

/// A biconvex singlet (f 50.85 mm) with the stop behind it, so that the
/// exit pupil is the stop itself: `stop` mm across, 40 mm before the film
/// before focusing.
fn singlet(stop: f32) -> Vec<[f32; 4]> {
    vec![[50.0, 5.0, 1.5, 40.0], [-50.0, 2.0, 1.0, 40.0], [0.0, 40.0, 0.0, stop]]
}

/// A lens that vignettes: small elements on both sides of the stop, far
/// from it.
fn vignetting() -> Vec<[f32; 4]> {
    vec![
        [40.0, 6.0, 1.6, 18.0],
        [-120.0, 10.0, 1.0, 18.0],
        [0.0, 8.0, 0.0, 10.0],
        [-30.0, 3.0, 1.7, 14.0],
        [-60.0, 30.0, 1.0, 14.0],
    ]
}

fn lens(rows: &[[f32; 4]], focus: f32) -> LensSystem {
    LensSystem::new("test", rows, 100.0, focus, 35.0, None).unwrap().0
}

/// The mean weight of rays from continuous pixel `pixel` over an n x n grid
/// of pupil samples.
fn mean_weight(l: &LensSystem, pixel: Vec2, size: Vec2, n: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..n * n {
        let u = Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
        if let Some((_, _, w)) = l.ray(pixel, size, u) {
            sum += w as f64;
        }
    }
    sum / (n * n) as f64
}

#[test]
fn prescriptions_are_read_as_pbrt_reads_them_and_errors_name_their_line() {
    let rows =
        parse_prescription("# radius thickness eta aperture\n29.5 3.76 1.67 25.2 # front\n\n0 4.5\t0 17.1\n").unwrap();
    assert_eq!(rows, vec![[29.5, 3.76, 1.67, 25.2], [0.0, 4.5, 0.0, 17.1]]);
    assert_eq!(parse_prescription("1 2 3 4\n5 6 x7 8\n").unwrap_err().0, 2);
    let (line, m) = parse_prescription("1 2 3 4\n5 6 7\n").unwrap_err();
    assert!(m.contains("multiple of four"), "{m}");
    assert_eq!(line, 2);
    assert!(parse_prescription("# nothing\n").is_err());
    assert!(parse_prescription("1 2 3 inf\n").is_err());
    let huge = "50 1 1.5 20\n".repeat(MAX_INTERFACES + 1);
    let (_, m) = parse_prescription(&huge).unwrap_err();
    assert!(m.contains("at most"), "{m}");
    assert!(parse_prescription(&"50 1 1.5 20\n".repeat(MAX_INTERFACES)).is_ok());
}

#[test]
fn the_thick_lens_has_the_lensmakers_focal_length() {
    let l = lens(&singlet(6.0), 2.0);
    // Lensmaker's equation with thickness: 1/f = (n-1) (1/R1 - 1/R2 + (n-1) d / (n R1 R2)).
    let (n, r1, r2, d) = (1.5f64, 50.0, -50.0, 5.0);
    let f = 1.0 / ((n - 1.0) * (1.0 / r1 - 1.0 / r2 + (n - 1.0) * d / (n * r1 * r2))) / 1000.0;
    assert!((l.focal_length - f).abs() < 1e-3 * f, "{} against {f}", l.focal_length);
}

#[test]
fn on_the_axis_the_weights_integrate_to_the_stops_solid_angle_term() {
    // Behind the lens the stop (radius a, z from the film) is the exit
    // pupil: E[cos^4 / (pdf z^2)] = integral over the disk of cos^4 / z^2
    // dA = pi a^2 / (a^2 + z^2), the irradiance a unit radiance makes.
    for stop in [4.0f32, 12.0] {
        let l = lens(&singlet(stop), 2.0);
        let (a, z) = (stop as f64 / 2000.0, l.rear_z());
        let want = std::f64::consts::PI * a * a / (a * a + z * z);
        let size = Vec2::new(64.0, 48.0);
        let got = mean_weight(&l, size * 0.5, size, 200);
        assert!((got / want - 1.0).abs() < 5e-3, "stop {stop}: {got} against {want}");
    }
}

#[test]
fn rays_of_one_film_point_meet_on_the_plane_in_focus() {
    // A stop small enough that the singlet's spherical aberration (which
    // moves a wide stop's best focus nearer) does not count: focusing is
    // paraxial, by the thick-lens approximation.
    let focus = 1.5;
    let l = lens(&singlet(1.5), focus);
    let size = Vec2::new(100.0, 100.0);
    // Spread of the rays' points on the plane z = at (camera space).
    let spread = |pixel: Vec2, at: f32| {
        let mut pts = Vec::new();
        for i in 0..64 {
            let u = Vec2::new((i % 8) as f32 / 8.0 + 0.06, (i / 8) as f32 / 8.0 + 0.06);
            if let Some((o, d, _)) = l.ray(pixel, size, u) {
                pts.push(o + d * ((at - o.z) / d.z));
            }
        }
        assert!(pts.len() > 20);
        let c = pts.iter().copied().sum::<Vec3>() / pts.len() as f32;
        (pts.iter().map(|p| (*p - c).length()).fold(0.0f32, f32::max), c)
    };
    // On the axis (off it, a singlet's field curves: its best focus there
    // is nearer, as a real one's).
    let centre = Vec2::new(50.0, 50.0);
    let (in_focus, _) = spread(centre, focus);
    let (near, _) = spread(centre, 0.8 * focus);
    let (far, _) = spread(centre, 1.25 * focus);
    assert!(in_focus < 0.1 * near && in_focus < 0.1 * far, "{in_focus} {near} {far}");
    // The lens turns the picture over on the film, and back: the image's
    // top-left quarter sees up and to the left.
    let (_, c) = spread(Vec2::new(20.0, 10.0), focus);
    assert!(c.x < 0.0 && c.y > 0.0, "{c}");
}

#[test]
fn every_ray_that_passes_the_lens_lies_within_its_bands_pupil_bounds() {
    // Rays from film points to points of the rear element's plane, far
    // beyond the pupil: those the lens lets through must be inside the
    // bounds (else sampling the bounds would miss light), here for a lens
    // that vignettes (small front elements far from the stop).
    let l = lens(&vignetting(), 3.0);
    let size = Vec2::new(60.0, 40.0);
    let half = l.half_film(size);
    let rear = 1.5 * l.rear_radius();
    let mut rng = crate::sampling::Rng::keyed(1, 2, 3);
    let (mut passed, mut inside) = (0, 0);
    for _ in 0..200_000 {
        let f = rng.next_2d();
        let film = DVec3::new(
            (2.0 * f.x as f64 - 1.0) * half.x,
            (2.0 * f.y as f64 - 1.0) * half.y,
            0.0,
        );
        let p = rng.next_2d();
        let rp = DVec3::new(
            (2.0 * p.x as f64 - 1.0) * rear,
            (2.0 * p.y as f64 - 1.0) * rear,
            l.rear_z(),
        );
        if l.trace_from_film(film, rp - film, false).is_none() {
            continue;
        }
        passed += 1;
        let r = (film.x * film.x + film.y * film.y).sqrt();
        let band = ((r / (l.film_diagonal / 2.0) * PUPIL_BANDS as f64) as usize).min(PUPIL_BANDS - 1);
        let b = l.pupil_bounds[band].expect("a band with rays through has bounds");
        // Into the band's frame, where the bounds lie along +x.
        let (sin, cos) = if r != 0.0 { (film.y / r, film.x / r) } else { (0.0, 1.0) };
        let q = DVec2::new(cos * rp.x + sin * rp.y, -sin * rp.x + cos * rp.y);
        if q.cmpge(b.min).all() && q.cmple(b.max).all() {
            inside += 1;
        }
    }
    assert!(passed > 1000, "{passed}");
    assert_eq!(inside, passed);
    // Vignetting: the corners get less light than the centre, by more than
    // cos^4 alone.
    let centre = mean_weight(&l, size * 0.5, size, 64);
    let corner = mean_weight(&l, Vec2::new(1.0, 1.0), size, 64);
    assert!(corner < 0.9 * centre && corner > 0.0, "{corner} {centre}");
}

#[test]
fn a_shaped_stop_passes_as_much_light_as_the_round_one() {
    let rows = vec![[50.0, 5.0, 1.5, 40.0], [-50.0, 2.0, 1.0, 40.0], [0.0, 40.0, 0.0, 3.0]];
    let size = Vec2::new(64.0, 48.0);
    let round = mean_weight(&lens(&rows, 2.0), size * 0.5, size, 200);
    for name in ["gaussian", "square", "pentagon", "star"] {
        let a = Aperture::builtin(name).unwrap();
        let mean = a.values.iter().map(|&v| v as f64).sum::<f64>() / a.values.len() as f64;
        assert!((mean - std::f64::consts::FRAC_PI_4).abs() < 1e-5, "{name}: {mean}");
        let l = LensSystem::new("test", &rows, 100.0, 2.0, 35.0, Some(a)).unwrap().0;
        let shaped = mean_weight(&l, size * 0.5, size, 200);
        assert!((shaped / round - 1.0).abs() < 0.02, "{name}: {shaped} against {round}");
    }
    assert!(Aperture::builtin("hexagon").is_none());
    assert!(Aperture::normalized("black", 2, 2, vec![0.0; 4]).is_none());
    // pbrt-v4's built-in shapes stand upside down on the stop: the
    // pentagon's point (its +y) is read at the stop's -y.
    let p = Aperture::builtin("pentagon").unwrap();
    assert!(p.at(0.5, 0.15) > 0.0 && p.at(0.5, 0.85) == 0.0);
}

#[test]
fn lenses_that_cannot_work_are_refused_with_a_reason() {
    // Focused closer than four focal lengths allow.
    let e = LensSystem::new("test", &singlet(6.0), 100.0, 0.1, 35.0, None).unwrap_err();
    assert!(e.contains("too close"), "{e}");
    // Flat glass bends nothing: no focal length.
    let flat = vec![[0.0, 5.0, 0.0, 20.0], [0.0, 40.0, 0.0, 20.0]];
    assert!(LensSystem::new("test", &flat, 100.0, 2.0, 35.0, None).is_err());
    // A negative aperture, a zero one.
    assert!(LensSystem::new("test", &[[50.0, 5.0, 1.5, -4.0]], 100.0, 2.0, 35.0, None).is_err());
    assert!(LensSystem::new("test", &singlet(6.0), 0.0, 2.0, 35.0, None).is_err());
    assert!(LensSystem::new("test", &singlet(6.0), 4.0, 2.0, f32::NAN, None).is_err());
    // Stopping down past the stop's own size is clamped, and said.
    let (l, clamped) = LensSystem::new("test", &singlet(6.0), 100.0, 2.0, 35.0, None).unwrap();
    assert_eq!(clamped, Some(6.0));
    assert!((l.interfaces[2].aperture_radius - 0.003).abs() < 1e-9);
    let (l, clamped) = LensSystem::new("test", &singlet(6.0), 2.0, 2.0, 35.0, None).unwrap();
    assert_eq!(clamped, None);
    assert!((l.interfaces[2].aperture_radius - 0.001).abs() < 1e-9);
}

#[test]
fn random_prescriptions_give_a_lens_or_a_reason_never_a_panic_or_a_bad_ray() {
    // Lens files are user input: any finite numbers must give an error or
    // a lens whose rays are finite, unit and of finite, positive weight.
    let mut rng = crate::sampling::Rng::keyed(7, 7, 7);
    let mut next = |lo: f32, hi: f32| lo + (hi - lo) * rng.next_f32();
    let (mut built, mut refused) = (0, 0);
    for _ in 0..60 {
        let n = 1 + (next(0.0, 6.0) as usize);
        let rows: Vec<[f32; 4]> = (0..n)
            .map(|k| {
                let radius = if k == n / 2 { 0.0 } else { next(-80.0, 80.0) };
                [
                    radius,
                    next(-1.0, 30.0),
                    [0.0, 1.0, next(1.3, 1.9)][k % 3],
                    next(-2.0, 40.0),
                ]
            })
            .collect();
        match LensSystem::new(
            "random",
            &rows,
            next(0.5, 30.0),
            next(0.05, 20.0),
            next(5.0, 60.0),
            None,
        ) {
            Err(e) => {
                assert!(!e.is_empty());
                refused += 1;
            }
            Ok((l, _)) => {
                built += 1;
                let size = Vec2::new(40.0, 30.0);
                for i in 0..400 {
                    let p = Vec2::new((i % 20) as f32 * 2.0 + 0.5, (i / 20) as f32 * 1.5 + 0.25);
                    let u = Vec2::new(((i * 7) % 400) as f32 / 400.0, ((i * 13) % 400) as f32 / 400.0);
                    if let Some((o, d, w)) = l.ray(p, size, u) {
                        assert!(o.is_finite() && (d.length() - 1.0).abs() < 1e-4 && w > 0.0 && w.is_finite());
                    }
                }
            }
        }
    }
    assert!(built > 0 && refused > 0, "{built} built, {refused} refused");
}

#[test]
fn a_lopsided_stop_loses_no_light_to_the_pupils_bounds() {
    // A stop open in one quadrant only: the lens no longer looks the same
    // from every film point at one distance from the centre, so bounds
    // found along +x and turned would cut light off (pbrt-v4 loses it).
    // Against sampling the whole square before the rear element.
    let res = 64;
    let values = (0..res * res)
        .map(|i| {
            if i % res >= res / 2 && i / res < res / 2 {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    let quadrant = Aperture::normalized("quadrant", res, res, values).unwrap();
    let l = LensSystem::new("test", &vignetting(), 100.0, 3.0, 35.0, Some(quadrant))
        .unwrap()
        .0;
    let size = Vec2::new(60.0, 40.0);
    let rear = 1.5 * l.rear_radius();
    let z = l.rear_z();
    let half = l.half_film(size);
    for pixel in [
        Vec2::new(30.0, 20.0),
        Vec2::new(12.0, 8.0),
        Vec2::new(50.0, 12.0),
        Vec2::new(15.0, 35.0),
    ] {
        let ours = mean_weight(&l, pixel, size, 300);
        // The same film point, every direction through the square.
        let s = DVec2::new(pixel.x as f64 / size.x as f64, pixel.y as f64 / size.y as f64);
        let film = DVec3::new(-(-half.x + 2.0 * half.x * s.x), -half.y + 2.0 * half.y * s.y, 0.0);
        let n = 600;
        let mut sum = 0.0;
        for i in 0..n * n {
            let q = DVec2::new(((i % n) as f64 + 0.5) / n as f64, ((i / n) as f64 + 0.5) / n as f64);
            let p = DVec3::new((2.0 * q.x - 1.0) * rear, (2.0 * q.y - 1.0) * rear, z);
            if let Some((_, _, w)) = l.trace_from_film(film, p - film, false) {
                let cos = (p - film).normalize().z;
                sum += w * cos.powi(4) * (2.0 * rear) * (2.0 * rear) / (z * z);
            }
        }
        let brute = sum / (n * n) as f64;
        assert!(brute > 0.0);
        assert!((ours / brute - 1.0).abs() < 0.02, "{pixel}: {ours} against {brute}");
    }
}
