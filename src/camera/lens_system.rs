//! A camera with a real lens (pbrt-v4's `RealisticCamera`, after Kolb,
//! Mitchell and Hanrahan 1995): rays leave the film, cross each spherical
//! glass interface and the aperture stop of a lens prescription, and go on
//! into the scene. Focus, depth of field, vignetting, distortion and the
//! fall-off of light towards the film's corners all come from tracing.
//!
//! Lens space is pbrt-v4's: the optical axis along z, the film at z = 0, the
//! lens towards negative z, lengths in metres. Camera space (x right, y up,
//! z forward) is lens space with z negated. Interface arithmetic is in f64:
//! a ray crosses a dozen surfaces of small curvature, where f32 loses the
//! rays near the optical axis' rim.

use std::sync::Arc;

use glam::{DVec2, DVec3, Vec2, Vec3};

/// One interface of a prescription: a spherical surface (`curvature_radius`
/// non-zero, positive when its centre lies on the film's side) or the
/// aperture stop (zero), `thickness` to the next
/// interface towards the film, the index of refraction after it (0: air),
/// and the radius of its clear aperture.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Interface {
    curvature_radius: f64,
    thickness: f64,
    eta: f64,
    aperture_radius: f64,
}

impl Interface {
    /// Where the ray (lens space) meets this interface, whose vertex is at
    /// `z` on the axis, and the surface normal there facing the ray (zero
    /// on the stop's plane); `None` when it misses or lies behind.
    fn hit(&self, z: f64, o: DVec3, d: DVec3) -> Option<(DVec3, DVec3)> {
        let (t, n) = if self.curvature_radius == 0.0 {
            let t = (z - o.z) / d.z;
            if t.is_nan() || t < 0.0 {
                return None;
            }
            (t, DVec3::ZERO)
        } else {
            intersect_element(self.curvature_radius, z + self.curvature_radius, o, d)?
        };
        Some((o + d * t, n))
    }
}

/// A bounding box on the plane of the rear element.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bounds {
    min: DVec2,
    max: DVec2,
}

impl Bounds {
    fn area(&self) -> f64 {
        let d = self.max - self.min;
        d.x * d.y
    }
}

/// A diaphragm shape other than the round stop: transmission over the
/// stop's square [-r, r]^2, scaled so that a fully open stop lets as much
/// light through as the round one (pbrt-v4's aperture images).
#[derive(Clone, PartialEq)]
pub struct Aperture {
    pub name: String,
    pub width: usize,
    pub height: usize,
    /// Rows from the top of the picture, as images are stored.
    pub values: Vec<f32>,
}

impl std::fmt::Debug for Aperture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // The scene's fingerprint hashes this: a digest, not 65,536 numbers.
        let mut h = crate::texture::Fnv64::default();
        for v in &self.values {
            h.bytes(&v.to_bits().to_le_bytes());
        }
        write!(f, "Aperture({} {}x{} {:016x})", self.name, self.width, self.height, h.0)
    }
}

impl Aperture {
    /// The built-in shapes pbrt-v4 names: "gaussian", "square", "pentagon",
    /// "star"; `None` for another name.
    pub fn builtin(name: &str) -> Option<Aperture> {
        const RES: usize = 256;
        let centre = |i: usize| -1.0 + 2.0 * (i as f64 + 0.5) / RES as f64;
        let mut values = vec![0.0f32; RES * RES];
        match name {
            "gaussian" => {
                for (i, v) in values.iter_mut().enumerate() {
                    let (x, y) = (centre(i % RES), centre(i / RES));
                    *v = ((-(x * x + y * y)).exp() - (-1.0f64).exp()).max(0.0) as f32;
                }
            }
            "square" => {
                for (i, v) in values.iter_mut().enumerate() {
                    let (x, y) = (i % RES, i / RES);
                    if (RES / 4..3 * RES / 4).contains(&x) && (RES / 4..3 * RES / 4).contains(&y) {
                        *v = 1.0;
                    }
                }
            }
            "pentagon" => {
                let c1 = (5f64.sqrt() - 1.0) / 4.0;
                let c2 = (5f64.sqrt() + 1.0) / 4.0;
                let s1 = (10.0 + 2.0 * 5f64.sqrt()).sqrt() / 4.0;
                let s2 = (10.0 - 2.0 * 5f64.sqrt()).sqrt() / 4.0;
                let vert = [(0.0, 1.0), (s1, c1), (s2, -c2), (-s2, -c2), (-s1, c1)].map(|(x, y)| (0.8 * x, 0.8 * y));
                rasterize(&mut values, RES, &vert);
            }
            "star" => {
                let inner = 72f64.to_radians().cos() / 36f64.to_radians().cos();
                let mut vert: Vec<(f64, f64)> = (0..10)
                    .map(|i| {
                        let r = if i % 2 == 1 { 1.0 } else { inner };
                        let a = std::f64::consts::PI * i as f64 / 5.0;
                        (r * a.cos(), r * a.sin())
                    })
                    .collect();
                vert.reverse();
                rasterize(&mut values, RES, &vert);
            }
            _ => return None,
        }
        // Row 0 holds the shape's y = -1 and is read as the stop's top (its
        // +y), as pbrt-v4 lays its built-in shapes: they stand upside down
        // on the stop, where image files stand upright.
        Aperture::normalized(name, RES, RES, values)
    }

    /// An aperture from grey values, rows from the top, scaled so that its
    /// mean over the square is pi / 4 (the round stop's share of it);
    /// `None` when nothing would pass.
    pub fn normalized(name: &str, width: usize, height: usize, mut values: Vec<f32>) -> Option<Aperture> {
        let n = width * height;
        if n == 0 || values.len() != n || values.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return None;
        }
        let mean = values.iter().map(|&v| v as f64).sum::<f64>() / n as f64;
        if mean <= 0.0 {
            return None;
        }
        let scale = (std::f64::consts::FRAC_PI_4 / mean) as f32;
        for v in &mut values {
            *v *= scale;
        }
        Some(Aperture {
            name: name.to_string(),
            width,
            height,
            values,
        })
    }

    /// Bilinear transmission at (u, v) in [0, 1]^2 (v up), black outside.
    pub fn at(&self, u: f64, v: f64) -> f64 {
        // Image space: rows down from the top.
        let x = u * self.width as f64 - 0.5;
        let y = (1.0 - v) * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |i: f64, j: f64| -> f64 {
            if i < 0.0 || j < 0.0 || i >= self.width as f64 || j >= self.height as f64 {
                0.0
            } else {
                self.values[j as usize * self.width + i as usize] as f64
            }
        };
        (1.0 - fx) * (1.0 - fy) * texel(x0, y0)
            + fx * (1.0 - fy) * texel(x0 + 1.0, y0)
            + (1.0 - fx) * fy * texel(x0, y0 + 1.0)
            + fx * fy * texel(x0 + 1.0, y0 + 1.0)
    }
}

/// Fills a polygon (non-zero winding) into a `res` x `res` grid over
/// [-1, 1]^2, row 0 at y = -1.
fn rasterize(values: &mut [f32], res: usize, vert: &[(f64, f64)]) {
    for (i, v) in values.iter_mut().enumerate() {
        let p = (
            -1.0 + 2.0 * ((i % res) as f64 + 0.5) / res as f64,
            -1.0 + 2.0 * ((i / res) as f64 + 0.5) / res as f64,
        );
        let mut winding = 0;
        for k in 0..vert.len() {
            let (a, b) = (vert[k], vert[(k + 1) % vert.len()]);
            let e = (p.0 - a.0) * (b.1 - a.1) - (p.1 - a.1) * (b.0 - a.0);
            if a.1 <= p.1 {
                if b.1 > p.1 && e > 0.0 {
                    winding += 1;
                }
            } else if b.1 <= p.1 && e < 0.0 {
                winding -= 1;
            }
        }
        *v = if winding != 0 { 1.0 } else { 0.0 };
    }
}

/// Reads a lens prescription as pbrt-v4 does: numbers separated by white
/// space, `#` to the end of the line a comment, four a row (curvature
/// radius, thickness, index of refraction, aperture diameter; millimetres),
/// from the scene side to the film. An error names the line.
pub fn parse_prescription(text: &str) -> Result<Vec<[f32; 4]>, (usize, String)> {
    let mut values = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let body = line.split('#').next().unwrap_or("");
        for word in body.split_whitespace() {
            let v: f32 = word
                .parse()
                .map_err(|_| (line_no, format!("\"{word}\" is not a number")))?;
            if !v.is_finite() {
                return Err((line_no, format!("{word} is not finite")));
            }
            values.push(v);
        }
    }
    if values.is_empty() {
        return Err((
            1,
            "no lens interfaces (four numbers each: radius, thickness, eta, aperture)".into(),
        ));
    }
    if values.len() > 4 * MAX_INTERFACES {
        return Err((
            text.lines().count().max(1),
            format!("{} interfaces; a lens has at most {MAX_INTERFACES}", values.len() / 4),
        ));
    }
    if values.len() % 4 != 0 {
        return Err((
            text.lines().count().max(1),
            format!(
                "{} numbers is not a multiple of four (radius, thickness, eta, aperture a row)",
                values.len()
            ),
        ));
    }
    Ok(values.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect())
}

/// The most interfaces a prescription may have (real lenses have a few
/// dozen at most; each costs every camera ray a sphere test).
pub const MAX_INTERFACES: usize = 256;

/// How many radial bands of the film have their own exit pupil bounds.
const PUPIL_BANDS: usize = 64;
/// Sample points tried a band to find its exit pupil (pbrt-v4 tries 2^20;
/// the bounds grow by two sample spacings, so fewer only loosen them).
const PUPIL_SAMPLES: usize = 1 << 16;

/// A traced lens: its interfaces, the film's size and the exit pupil's
/// bounds over the film.
#[derive(Clone, Debug, PartialEq)]
pub struct LensSystem {
    /// The prescription's name (its file), for messages and fingerprints.
    pub name: String,
    interfaces: Vec<Interface>,
    film_diagonal: f64,
    pupil_bounds: Vec<Option<Bounds>>,
    aperture: Option<Aperture>,
    /// The thick lens' effective focal length, metres.
    pub focal_length: f64,
    /// World units a metre of the lens (the camera transformation's scale).
    pub scale: f64,
}

/// Why a lens cannot be built, for the user.
pub type LensError = String;

impl LensSystem {
    /// A lens from its prescription (millimetres, as the file has it),
    /// stopped down to `aperture_diameter` mm (the stop's own diameter if
    /// larger; the second value says so), focused at `focus_distance`
    /// metres, over a film of `film_diagonal` mm.
    pub fn new(
        name: &str,
        rows: &[[f32; 4]],
        aperture_diameter: f32,
        focus_distance: f32,
        film_diagonal: f32,
        aperture: Option<Aperture>,
    ) -> Result<(LensSystem, Option<f32>), LensError> {
        if !(film_diagonal > 0.0 && film_diagonal.is_finite()) {
            return Err(format!("the film's diagonal {film_diagonal} mm must be positive"));
        }
        if !(aperture_diameter > 0.0 && aperture_diameter.is_finite()) {
            return Err(format!("aperturediameter {aperture_diameter} mm must be positive"));
        }
        if !(focus_distance > 0.0 && focus_distance.is_finite()) {
            return Err(format!("focusdistance {focus_distance} must be positive"));
        }
        let mut clamped = None;
        let mut interfaces = Vec::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            let [radius, thickness, eta, diameter] = r.map(|v| v as f64);
            if !(diameter > 0.0 && thickness >= 0.0 && eta >= 0.0) {
                return Err(format!(
                    "interface {} ({radius} {thickness} {eta} {diameter}): its aperture must be positive, its thickness and eta not negative",
                    i + 1
                ));
            }
            let mut diameter = diameter;
            if radius == 0.0 {
                if aperture_diameter as f64 > diameter {
                    clamped = Some(diameter as f32);
                } else {
                    diameter = aperture_diameter as f64;
                }
            }
            interfaces.push(Interface {
                curvature_radius: radius / 1000.0,
                thickness: thickness / 1000.0,
                eta,
                aperture_radius: diameter / 2000.0,
            });
        }
        if interfaces.is_empty() {
            return Err("the prescription has no interfaces".into());
        }
        let diagonal = film_diagonal as f64 / 1000.0;
        let mut lens = LensSystem {
            name: name.to_string(),
            interfaces,
            film_diagonal: diagonal,
            pupil_bounds: Vec::new(),
            aperture,
            focal_length: 0.0,
            scale: 1.0,
        };
        let (pz, fz) = lens.thick_lens()?;
        lens.focal_length = fz[0] - pz[0];
        // Move the lens so that the plane focus_distance ahead of the film
        // is in focus (thick-lens approximation, pbrt-v4's FocusThickLens).
        let f = lens.focal_length;
        let z = -(focus_distance as f64);
        let c = (pz[1] - z - pz[0]) * (pz[1] - z - 4.0 * f - pz[0]);
        if !(c > 0.0 && f > 0.0) {
            return Err(format!(
                "cannot focus at {focus_distance}: too close for this lens (focal length {:.4} m)",
                f
            ));
        }
        // pbrt-v4's (pz1 - z + pz0 - sqrt(c)) / 2, without its cancellation
        // for a far focus.
        let a = pz[1] - z - pz[0];
        let delta = pz[0] + 2.0 * f * a / (a + c.sqrt());
        let last = lens.interfaces.len() - 1;
        lens.interfaces[last].thickness += delta;
        if !(lens.interfaces[last].thickness > 0.0 && delta.is_finite()) {
            return Err(format!(
                "cannot focus at {focus_distance}: the lens would sit behind the film"
            ));
        }
        lens.pupil_bounds = {
            use rayon::prelude::*;
            (0..PUPIL_BANDS)
                .into_par_iter()
                .map(|i| {
                    let r0 = i as f64 / PUPIL_BANDS as f64 * diagonal / 2.0;
                    let r1 = (i + 1) as f64 / PUPIL_BANDS as f64 * diagonal / 2.0;
                    lens.bound_exit_pupil(r0, r1)
                })
                .collect()
        };
        if lens.pupil_bounds.iter().all(Option::is_none) {
            return Err("no ray from the film passes through the lens".into());
        }
        Ok((lens, clamped))
    }

    /// Half the film's width and height (metres) for an image of `size`
    /// pixels: the diagonal is the film's, the shape the image's.
    pub fn half_film(&self, size: Vec2) -> DVec2 {
        let aspect = size.y as f64 / size.x as f64;
        let x = (self.film_diagonal * self.film_diagonal / (1.0 + aspect * aspect)).sqrt();
        DVec2::new(x / 2.0, aspect * x / 2.0)
    }

    /// The stop's shape, if it is not round.
    pub fn aperture(&self) -> Option<&Aperture> {
        self.aperture.as_ref()
    }

    /// How many interfaces the prescription has, and the stop's diameter
    /// (mm) as set, if it has a stop.
    pub fn summary(&self) -> (usize, Option<f64>) {
        let stop = self.interfaces.iter().find(|e| e.curvature_radius == 0.0);
        (self.interfaces.len(), stop.map(|e| e.aperture_radius * 2000.0))
    }

    /// The film-to-rear-element distance, metres.
    pub fn rear_z(&self) -> f64 {
        self.interfaces[self.interfaces.len() - 1].thickness
    }

    fn front_z(&self) -> f64 {
        self.interfaces.iter().map(|e| e.thickness).sum()
    }

    fn rear_radius(&self) -> f64 {
        self.interfaces[self.interfaces.len() - 1].aperture_radius
    }

    /// A ray from the film (camera space) through every interface to the
    /// scene: the ray leaving the front element, and the stop's
    /// transmission (1 for a round stop); `None` when it is blocked.
    /// `covering`: a shaped stop is taken as the round one about its
    /// image's square (transmission 1), which passes every ray the shape
    /// passes and looks the same from every film point at one distance
    /// from the centre, as the exit pupil's bands need.
    fn trace_from_film(&self, o: DVec3, d: DVec3, covering: bool) -> Option<(DVec3, DVec3, f64)> {
        let mut o = DVec3::new(o.x, o.y, -o.z);
        let mut d = DVec3::new(d.x, d.y, -d.z);
        let mut z = 0.0;
        let mut weight = 1.0;
        for i in (0..self.interfaces.len()).rev() {
            let e = self.interfaces[i];
            z -= e.thickness;
            let stop = e.curvature_radius == 0.0;
            let (p, n) = e.hit(z, o, d)?;
            match (&self.aperture, stop) {
                (Some(_), true) if covering => {
                    let r = e.aperture_radius;
                    if p.x * p.x + p.y * p.y > 2.0 * r * r {
                        return None;
                    }
                }
                (Some(a), true) => {
                    weight = a.at(
                        (p.x / e.aperture_radius + 1.0) / 2.0,
                        (p.y / e.aperture_radius + 1.0) / 2.0,
                    );
                    if weight <= 0.0 {
                        return None;
                    }
                }
                _ => {
                    if p.x * p.x + p.y * p.y > e.aperture_radius * e.aperture_radius {
                        return None;
                    }
                }
            }
            o = p;
            if !stop {
                let eta_i = e.eta;
                let eta_t = if i > 0 && self.interfaces[i - 1].eta != 0.0 {
                    self.interfaces[i - 1].eta
                } else {
                    1.0
                };
                d = refract(-d.normalize(), n, eta_t / if eta_i == 0.0 { 1.0 } else { eta_i })?;
            }
        }
        Some((DVec3::new(o.x, o.y, -o.z), DVec3::new(d.x, d.y, -d.z), weight))
    }

    /// A ray from the scene (camera space) through every interface to the
    /// film side; `None` when blocked. The stop is taken as round.
    fn trace_from_scene(&self, o: DVec3, d: DVec3) -> Option<(DVec3, DVec3)> {
        let mut z = -self.front_z();
        let mut o = DVec3::new(o.x, o.y, -o.z);
        let mut d = DVec3::new(d.x, d.y, -d.z);
        for (i, e) in self.interfaces.iter().enumerate() {
            let stop = e.curvature_radius == 0.0;
            let (p, n) = e.hit(z, o, d)?;
            if p.x * p.x + p.y * p.y > e.aperture_radius * e.aperture_radius {
                return None;
            }
            o = p;
            if !stop {
                let eta_i = if i == 0 || self.interfaces[i - 1].eta == 0.0 {
                    1.0
                } else {
                    self.interfaces[i - 1].eta
                };
                let eta_t = if e.eta != 0.0 { e.eta } else { 1.0 };
                d = refract(-d.normalize(), n, eta_t / eta_i)?;
            }
            z += e.thickness;
        }
        Some((DVec3::new(o.x, o.y, -o.z), DVec3::new(d.x, d.y, -d.z)))
    }

    /// The principal planes' and focal points' z, film side first, from
    /// rays parallel to the axis traced each way (pbrt-v4's
    /// ComputeThickLensApproximation).
    fn thick_lens(&self) -> Result<([f64; 2], [f64; 2]), LensError> {
        let x = 0.001 * self.film_diagonal;
        let blocked = || "no ray near the axis passes through the lens: is its stop closed?".to_string();
        let o_scene = DVec3::new(x, 0.0, self.front_z() + 1.0);
        let (o, d) = self
            .trace_from_scene(o_scene, DVec3::new(0.0, 0.0, -1.0))
            .ok_or_else(blocked)?;
        let (p0, f0) = cardinal_points(o_scene, o, d);
        let o_film = DVec3::new(x, 0.0, self.rear_z() - 1.0);
        let (o, d, _) = self
            .trace_from_film(o_film, DVec3::new(0.0, 0.0, 1.0), false)
            .ok_or_else(blocked)?;
        let (p1, f1) = cardinal_points(o_film, o, d);
        let all = [p0, f0, p1, f1];
        if all.iter().any(|v| !v.is_finite()) {
            return Err("the lens does not bend rays parallel to its axis: it has no focal length".into());
        }
        Ok(([p0, p1], [f0, f1]))
    }

    /// The bounds on the rear element's plane of where rays from film
    /// points at distance r0..r1 along x pass the whole lens, grown by two
    /// sample spacings; `None` when none do.
    fn bound_exit_pupil(&self, r0: f64, r1: f64) -> Option<Bounds> {
        let rear = 1.5 * self.rear_radius();
        let rear_z = self.rear_z();
        let mut b: Option<Bounds> = None;
        for i in 0..PUPIL_SAMPLES {
            let film = DVec3::new(r0 + (i as f64 + 0.5) / PUPIL_SAMPLES as f64 * (r1 - r0), 0.0, 0.0);
            let u = DVec2::new(radical_inverse(2, i as u64), radical_inverse(3, i as u64));
            let p = DVec2::splat(-rear) + u * 2.0 * rear;
            if b.is_some_and(|b| p.cmpge(b.min).all() && p.cmple(b.max).all()) {
                continue;
            }
            if self.trace_from_film(film, p.extend(rear_z) - film, true).is_some() {
                b = Some(match b {
                    Some(b) => Bounds {
                        min: b.min.min(p),
                        max: b.max.max(p),
                    },
                    None => Bounds { min: p, max: p },
                });
            }
        }
        let grow = 2.0 * (2.0 * rear * std::f64::consts::SQRT_2) / (PUPIL_SAMPLES as f64).sqrt();
        b.map(|b| Bounds {
            min: b.min - DVec2::splat(grow),
            max: b.max + DVec2::splat(grow),
        })
    }

    /// The ray (camera space, metres) from continuous pixel position
    /// `pixel` of an image of `size` through the exit pupil's point `u`,
    /// and its weight (cos^4 theta over the pupil sample's density times the
    /// square of the film-to-rear distance, and the stop's transmission);
    /// `None` when the lens blocks it.
    pub fn ray(&self, pixel: Vec2, size: Vec2, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        let s = DVec2::new(pixel.x as f64 / size.x as f64, pixel.y as f64 / size.y as f64);
        let half = self.half_film(size);
        // The film is behind the lens, which turns the picture over: the
        // image's top-left corner sees the film's (x, -y) corner.
        let film = DVec3::new(-(-half.x + 2.0 * half.x * s.x), -half.y + 2.0 * half.y * s.y, 0.0);
        let r = (film.x * film.x + film.y * film.y).sqrt();
        let band = ((r / (self.film_diagonal / 2.0) * PUPIL_BANDS as f64) as usize).min(PUPIL_BANDS - 1);
        let b = self.pupil_bounds[band]?;
        let l = b.min + (b.max - b.min) * DVec2::new(u.x as f64, u.y as f64);
        let pdf = 1.0 / b.area();
        // The bounds were found along +x: turn them to the film point's angle.
        let (sin, cos) = if r != 0.0 { (film.y / r, film.x / r) } else { (0.0, 1.0) };
        let pupil = DVec3::new(cos * l.x - sin * l.y, sin * l.x + cos * l.y, self.rear_z());
        let d = pupil - film;
        let (o, dir, weight) = self.trace_from_film(film, d, false)?;
        let cos_theta = d.normalize().z;
        let rear = self.rear_z();
        let w = weight * cos_theta.powi(4) / (pdf * rear * rear);
        let dir = dir.normalize();
        (w > 0.0 && w.is_finite() && dir.is_finite()).then(|| (o.as_vec3(), dir.as_vec3(), w as f32))
    }
}

/// Hits on the sphere of `radius` about (0, 0, `z_centre`): the one the
/// lens' surface is (the nearer or farther by the ray's direction and the
/// sign of the curvature), and its normal facing the ray.
fn intersect_element(radius: f64, z_centre: f64, o: DVec3, d: DVec3) -> Option<(f64, DVec3)> {
    let oc = o - DVec3::new(0.0, 0.0, z_centre);
    let a = d.length_squared();
    let b = 2.0 * d.dot(oc);
    let c = oc.length_squared() - radius * radius;
    let disc = b * b - 4.0 * a * c;
    if disc.is_nan() || disc < 0.0 || a == 0.0 {
        return None;
    }
    let q = -0.5 * (b + disc.sqrt().copysign(b));
    let (mut t0, mut t1) = (q / a, c / q);
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    let closer = (d.z > 0.0) ^ (radius < 0.0);
    let t = if closer { t0 } else { t1 };
    if t.is_nan() || t < 0.0 {
        return None;
    }
    let n = (oc + d * t).normalize();
    let n = if n.dot(-d) < 0.0 { -n } else { n };
    Some((t, n))
}

/// Snell's law for the unit direction `wi` (pointing away from the
/// surface) about the normal `n`, `eta` the ratio of the far side's index to
/// the near side's; `None` at total internal reflection.
fn refract(wi: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    let (mut n, mut eta) = (n, eta);
    let mut cos_i = n.dot(wi);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wi / eta + (cos_i / eta - cos_t) * n)
}

/// Where a ray parallel to the axis at height x0 (`o_in`) crosses the axis
/// after the lens (the focal point) and where it meets its own height again
/// (the principal plane): their z, in pbrt-v4's lens-space sign.
fn cardinal_points(o_in: DVec3, o: DVec3, d: DVec3) -> (f64, f64) {
    let tf = -o.x / d.x;
    let fz = -(o.z + d.z * tf);
    let tp = (o_in.x - o.x) / d.x;
    let pz = -(o.z + d.z * tp);
    (pz, fz)
}

/// The radical inverse of `i` in `base`.
fn radical_inverse(base: u64, mut i: u64) -> f64 {
    let inv = 1.0 / base as f64;
    let (mut f, mut r) = (inv, 0.0);
    while i > 0 {
        r += (i % base) as f64 * f;
        i /= base;
        f *= inv;
    }
    r
}

/// A lens system shared by the cameras built from one scene description.
pub type SharedLens = Arc<LensSystem>;

#[cfg(test)]
mod tests;
