//! Camera: continuous pixel position (and a lens sample) -> primary ray.
//! Perspective (a pinhole by default; a thin lens, pbrt-v4's
//! `PerspectiveCamera`, when it has one) or orthographic (pbrt-v4's
//! `OrthographicCamera`: parallel rays from the image plane) or spherical
//! (pbrt-v4's `SphericalCamera`: the whole sphere of directions about a
//! point, in an equal-area or an equirectangular image) or realistic
//! (pbrt-v4's `RealisticCamera`: rays traced through a lens prescription,
//! [`lens_system`]).

pub mod lens_system;

pub use lens_system::{Aperture, LensSystem, SharedLens};

use crate::math::{Ray, Vec2, Vec3};
use crate::sampling::{concentric_disk, equal_area_sphere_to_square, equal_area_square_to_sphere};

/// The image's window on the plane at unit distance before the camera, in
/// units of the tangent of half the field of view: x from `left` to `right`
/// along the image's width, y from `top` (the image's first row) down to
/// `bottom`. The default is [-aspect, aspect] x [-1, 1]; pbrt-v4's
/// `screenwindow` sets another (an off-centre or stretched projection).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenWindow {
    pub left: f32,
    pub right: f32,
    pub bottom: f32,
    pub top: f32,
}

/// A thin lens: rays leave a disk of `radius` about the camera position,
/// perpendicular to the view direction, and every ray of one image point
/// meets the plane at `focal_distance` along the view direction in one point
/// (pbrt-v4 6.2.3). Lengths in world units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLens {
    pub radius: f32,
    pub focal_distance: f32,
}

impl ThinLens {
    /// A lens that blurs anything: a positive, finite radius and focal distance.
    pub fn is_valid(&self) -> bool {
        self.radius > 0.0 && self.radius.is_finite() && self.focal_distance > 0.0 && self.focal_distance.is_finite()
    }
}

/// How a spherical camera lays the sphere of directions on its image
/// (pbrt-v4's `mapping`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SphericalMapping {
    /// pbrt-v4's equal-area octahedral square (Clarberg's), its default.
    EqualArea,
    /// Latitude and longitude: x from 0 to 2 pi about the up axis, y from
    /// up (the top row) to down.
    Equirectangular,
}

impl SphericalMapping {
    /// pbrt-v4's names: "equalarea", "equirectangular".
    pub fn parse(name: &str) -> Option<SphericalMapping> {
        match name {
            "equalarea" => Some(SphericalMapping::EqualArea),
            "equirectangular" => Some(SphericalMapping::Equirectangular),
            _ => None,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Camera {
    pub position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half_fov: f32,
    /// The window as half-size and centre per axis (in units of
    /// `tan_half_fov`), so that the default window is the plain formula.
    half: Vec2,
    centre: Vec2,
    lens: Option<ThinLens>,
    /// Rays parallel to `forward` from the plane through `position`;
    /// `tan_half_fov` is then the world length of a unit of the window.
    orthographic: bool,
    /// Rays from `position` in every direction, the image a map of the sphere.
    spherical: Option<SphericalMapping>,
    /// Rays traced through a real lens. The pinhole of the other fields then
    /// has the lens' focal length: it stands in where a single ray a pixel
    /// is wanted (texture footprints, projections).
    realistic: Option<SharedLens>,
    pub width: u32,
    pub height: u32,
    /// When the shutter opens and closes, where the scene has moving shapes
    /// (`None` otherwise: camera rays are then all at time 0 and draw no
    /// sample for their time).
    pub shutter: Option<[f32; 2]>,
    /// The camera's motion over the shutter, from where it is placed.
    pub motion: Option<crate::geometry::motion::Motion>,
}

impl Camera {
    /// `fov_y_deg` is the vertical field of view; a non-square image keeps it
    /// and widens or narrows the horizontal one. Image x grows along
    /// forward x up, image y (downwards in the picture) along -up.
    /// Returns `None` for a degenerate frame (look_at at the position, up
    /// parallel to the view direction, fov outside (0, 180)).
    pub fn new(position: Vec3, look_at: Vec3, up: Vec3, fov_y_deg: f32, width: u32, height: u32) -> Option<Camera> {
        let forward = (look_at - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) || width == 0 || height == 0 {
            return None;
        }
        Some(Camera {
            position,
            forward,
            right,
            up,
            tan_half_fov: (fov_y_deg.to_radians() * 0.5).tan(),
            half: Vec2::new(width as f32 / height as f32, 1.0),
            centre: Vec2::ZERO,
            lens: None,
            orthographic: false,
            spherical: None,
            realistic: None,
            width,
            height,
            shutter: None,
            motion: None,
        })
    }

    /// A spherical camera at `position`: its image maps every direction,
    /// laid out by `mapping` in the frame of the view direction and `up` as
    /// pbrt-v4 lays it out (the sphere's pole is `up`; in the
    /// equirectangular layout the top row looks up and the column a quarter
    /// of the way across looks along `look_at`); `None` as [`Camera::new`].
    pub fn spherical(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        mapping: SphericalMapping,
        width: u32,
        height: u32,
    ) -> Option<Camera> {
        let mut c = Camera::new(position, look_at, up, 90.0, width, height)?;
        c.spherical = Some(mapping);
        Some(c)
    }

    /// An orthographic camera whose image spans `2 half_height` world units
    /// vertically (and as many times the aspect ratio across); `None` as
    /// [`Camera::new`] for a degenerate frame or a non-positive height.
    pub fn orthographic(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        half_height: f32,
        width: u32,
        height: u32,
    ) -> Option<Camera> {
        if !(half_height > 0.0 && half_height.is_finite()) {
            return None;
        }
        let mut c = Camera::new(position, look_at, up, 90.0, width, height)?;
        c.tan_half_fov = half_height;
        c.orthographic = true;
        Some(c)
    }

    /// A camera with a real lens at `position`, its image's top-left corner
    /// towards `up` and left of `look_at`; `None` as [`Camera::new`].
    pub fn realistic(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        lens: SharedLens,
        width: u32,
        height: u32,
    ) -> Option<Camera> {
        if width == 0 || height == 0 {
            return None;
        }
        let half = lens.half_film(Vec2::new(width as f32, height as f32));
        let fov = 2.0 * (half.y / lens.focal_length).atan().to_degrees() as f32;
        let mut c = Camera::new(position, look_at, up, fov, width, height)?;
        c.realistic = Some(lens);
        Some(c)
    }

    /// The camera with another image window (`fov_y_deg` now sets the unit
    /// of the window, not the vertical field of view); `None` for an empty
    /// or non-finite window.
    pub fn with_window(mut self, w: ScreenWindow) -> Option<Camera> {
        let ok =
            [w.left, w.right, w.bottom, w.top].iter().all(|v| v.is_finite()) && w.left != w.right && w.bottom != w.top;
        if !ok {
            return None;
        }
        self.half = Vec2::new(0.5 * (w.right - w.left), 0.5 * (w.top - w.bottom));
        self.centre = Vec2::new(0.5 * (w.right + w.left), 0.5 * (w.top + w.bottom));
        Some(self)
    }

    /// The camera with a thin lens; `None` for a lens that is not valid or
    /// an orthographic camera (pbrt-v4's orthographic lens starts every ray
    /// about the camera's centre, a model we do not copy).
    pub fn with_lens(mut self, lens: ThinLens) -> Option<Camera> {
        if !lens.is_valid() || self.orthographic || self.spherical.is_some() || self.realistic.is_some() {
            return None;
        }
        self.lens = Some(lens);
        Some(self)
    }

    /// The camera with the window and lens a scene gives, if any.
    pub fn with_optics(self, window: Option<ScreenWindow>, lens: Option<ThinLens>) -> Option<Camera> {
        let cam = match window {
            Some(w) => self.with_window(w)?,
            None => self,
        };
        match lens {
            Some(l) => cam.with_lens(l),
            None => Some(cam),
        }
    }

    /// Whether rays need a lens sample ([`Camera::sample_ray`]).
    pub fn has_lens(&self) -> bool {
        self.lens.is_some() || self.realistic.is_some()
    }

    /// The real lens rays are traced through, if any.
    pub fn lens_system(&self) -> Option<&LensSystem> {
        self.realistic.as_deref()
    }

    /// The ray through (x, y) and the lens point `u`, with its weight
    /// (pbrt-v4's `CameraRay`): 1 but for a real lens, whose rays carry its
    /// radiometry (the fall-off towards the corners, the stop's
    /// transmission) and are 0 where the lens blocks them (then the ray is
    /// the pinhole's, and its radiance is not wanted).
    pub fn sample_ray(&self, x: f32, y: f32, u: Vec2) -> (Ray, f32) {
        let Some(lens) = &self.realistic else {
            return (self.generate_ray_through_lens(x, y, u), 1.0);
        };
        match self.realistic_ray(lens, x, y, u) {
            Some(r) => r,
            None => (self.pinhole_ray(x, y), 0.0),
        }
    }

    /// A ray of a real lens, in world space, and its weight.
    fn realistic_ray(&self, lens: &LensSystem, x: f32, y: f32, u: Vec2) -> Option<(Ray, f32)> {
        let size = Vec2::new(self.width as f32, self.height as f32);
        let (o, d, w) = lens.ray(Vec2::new(x, y), size, u)?;
        let o = self.position + self.camera_to_world(o) * lens.scale as f32;
        let d = self.camera_to_world(d).try_normalize()?;
        Some((Ray::new(o, d), w))
    }

    /// The ray of a pinhole at the camera's position through (x, y).
    fn pinhole_ray(&self, x: f32, y: f32) -> Ray {
        Ray::new(self.position, self.direction(x, y).normalize())
    }

    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// The ray through continuous pixel coordinates (x, y), with (0, 0) the
    /// top-left corner of the image and (width, height) the bottom-right one.
    /// The ray leaves the lens' centre (the pinhole's ray); a real lens'
    /// ray through the middle of its exit pupil, or where none passes there
    /// the pinhole's of the lens' focal length.
    #[inline(always)]
    pub fn generate_ray(&self, x: f32, y: f32) -> Ray {
        if let Some(lens) = &self.realistic {
            return match self.realistic_ray(lens, x, y, Vec2::splat(0.5)) {
                Some((r, _)) => r,
                None => self.pinhole_ray(x, y),
            };
        }
        if let Some(mapping) = self.spherical {
            let c = spherical_direction(mapping, Vec2::new(x / self.width as f32, y / self.height as f32));
            return Ray::new(self.position, self.camera_to_world(c).normalize());
        }
        if self.orthographic {
            let (sx, sy) = self.screen(x, y);
            return Ray::new(self.position + self.right * sx + self.up * sy, self.forward);
        }
        Ray::new(self.position, self.direction(x, y).normalize())
    }

    /// The ray through (x, y) leaving the lens at the point `u` in [0, 1)^2
    /// picks (uniform over its disk); the pinhole's ray without a lens.
    pub fn generate_ray_through_lens(&self, x: f32, y: f32, u: Vec2) -> Ray {
        let Some(lens) = self.lens else {
            return self.generate_ray(x, y);
        };
        let d = self.direction(x, y);
        // `d` is one unit long along the view direction: the plane in focus
        // is `focal_distance` of them away.
        let focus = self.position + d * lens.focal_distance;
        let p = concentric_disk(u) * lens.radius;
        let o = self.position + self.right * p.x + self.up * p.y;
        Ray::new(o, (focus - o).normalize())
    }

    /// The unnormalised direction through (x, y), one unit along `forward`.
    #[inline]
    fn direction(&self, x: f32, y: f32) -> Vec3 {
        let (sx, sy) = self.screen(x, y);
        self.forward + self.right * sx + self.up * sy
    }

    /// Where (x, y) lies on the image plane at unit distance (perspective) or
    /// through the camera (orthographic), along `right` and `up`.
    #[inline]
    fn screen(&self, x: f32, y: f32) -> (f32, f32) {
        // With the default window (half height 1, centre 0) this is the plain
        // pinhole formula, bit for bit, signed zeros included.
        let t = self.tan_half_fov;
        let mut sx = (2.0 * x / self.width as f32 - 1.0) * t * self.half.x;
        let mut sy = (1.0 - 2.0 * y / self.height as f32) * t * self.half.y;
        if self.centre != Vec2::ZERO {
            sx += self.centre.x * t;
            sy += self.centre.y * t;
        }
        (sx, sy)
    }

    /// A direction in the camera's frame: x right, y up, z forward (pbrt-v4's
    /// camera space).
    fn to_camera(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.right), v.dot(self.up), v.dot(self.forward))
    }

    fn camera_to_world(&self, c: Vec3) -> Vec3 {
        self.right * c.x + self.up * c.y + self.forward * c.z
    }

    /// What pbrt-v4's `CameraBase::FindMinimumDifferentials` finds: the
    /// shortest changes of a camera ray's origin (camera space) and
    /// direction (in the frame of the ray) from one pixel to the next, over
    /// 512 points of the image's diagonal, for a render of `spp` samples a
    /// pixel.
    pub fn pixel_footprint(&self, spp: u32) -> PixelFootprint {
        let mut min_pos = [Vec3::INFINITY; 2];
        let mut min_dir = [Vec3::INFINITY; 2];
        let n = 512;
        for i in 0..n {
            let x = i as f32 / (n - 1) as f32 * self.width as f32;
            let y = i as f32 / (n - 1) as f32 * self.height as f32;
            let ray = self.generate_ray(x, y);
            let (z, tx, ty) = frame_from_z(ray.d);
            let local = |d: Vec3| Vec3::new(d.dot(tx), d.dot(ty), d.dot(z));
            let df = local(ray.d);
            for (k, r) in [self.generate_ray(x + 1.0, y), self.generate_ray(x, y + 1.0)]
                .into_iter()
                .enumerate()
            {
                let dox = self.to_camera(r.o - ray.o);
                if dox.length() < min_pos[k].length() {
                    min_pos[k] = dox;
                }
                let dd = local(r.d).normalize() - df;
                if dd.length() < min_dir[k].length() {
                    min_dir[k] = dd;
                }
            }
        }
        PixelFootprint {
            min_pos,
            min_dir,
            scale: (1.0 / (spp.max(1) as f32).sqrt()).max(0.125),
        }
    }

    /// Where a world-space point lands in continuous pixel coordinates, if in front.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32)> {
        let v = p - self.position;
        if let Some(mapping) = self.spherical {
            let uv = spherical_uv(mapping, self.to_camera(v).try_normalize()?);
            return Some((uv.x * self.width as f32, uv.y * self.height as f32));
        }
        let z = v.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        // Orthographic: no division by depth.
        let z = if self.orthographic { 1.0 } else { z };
        let sx = (v.dot(self.right) / z / self.tan_half_fov - self.centre.x) / self.half.x;
        let sy = (v.dot(self.up) / z / self.tan_half_fov - self.centre.y) / self.half.y;
        Some((
            (sx + 1.0) * 0.5 * self.width as f32,
            (1.0 - sy) * 0.5 * self.height as f32,
        ))
    }

    /// Where the camera moves at `time`: from its placement to its place
    /// then (`None` when it stays).
    fn moved(&self, time: f32) -> Option<glam::Mat4> {
        self.motion.as_ref().map(|m| m.relative(time))
    }

    /// The pinhole's place at `time`.
    pub fn position_at(&self, time: f32) -> Vec3 {
        self.moved(time)
            .map_or(self.position, |m| m.transform_point3(self.position))
    }

    /// [`Camera::project`] of the camera where it is at `time`.
    pub fn project_at(&self, p: Vec3, time: f32) -> Option<(f32, f32)> {
        match self.moved(time) {
            None => self.project(p),
            Some(m) => self.project(m.inverse().transform_point3(p)),
        }
    }

    /// [`Camera::pdf_dir`] of the camera where it is at `time`.
    pub fn pdf_dir_at(&self, d: Vec3, time: f32) -> f32 {
        match self.moved(time) {
            None => self.pdf_dir(d),
            Some(m) => match m.inverse().transform_vector3(d).try_normalize() {
                Some(d) => self.pdf_dir(d),
                None => 0.0,
            },
        }
    }

    /// A perspective camera without a lens: one point every ray leaves,
    /// which light tracing can connect to.
    pub fn is_pinhole(&self) -> bool {
        !self.orthographic && self.spherical.is_none() && self.lens.is_none() && self.realistic.is_none()
    }

    /// For a pinhole: the solid-angle density of camera rays towards the
    /// unit direction `d`, for rays uniform over the whole image: 1 / (A
    /// cos^3 theta), A the image's area on the plane one unit ahead (pbrt-v4's
    /// `PerspectiveCamera::PDF_We`, whose importance We is this over cos
    /// theta). Zero behind the camera or outside the image.
    pub fn pdf_dir(&self, d: Vec3) -> f32 {
        let cos = d.dot(self.forward);
        if cos <= 0.0 {
            return 0.0;
        }
        match self.project(self.position + d) {
            Some((x, y)) if x >= 0.0 && y >= 0.0 && x < self.width as f32 && y < self.height as f32 => {
                let t = self.tan_half_fov;
                let area = 4.0 * t * t * self.half.x * self.half.y;
                1.0 / (area * cos * cos * cos)
            }
            _ => 0.0,
        }
    }
}

/// How far a surface point moves on its tangent plane from one pixel to the
/// next, as pbrt-v4 estimates it for texture filtering and bump maps:
/// exactly for a camera ray's hit (its ray differentials), and for any other
/// hit from the camera's smallest differentials at the point's distance
/// (`Camera::Approximate_dp_dxy`), both scaled by max(1/8, 1/sqrt(spp)), the
/// spacing of a pixel's samples; `Scene::specular_differentials` carries a
/// camera ray's on through specular bounces. One departure: a camera ray's
/// differentials are those of the pinhole through the lens' centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelFootprint {
    min_pos: [Vec3; 2],
    min_dir: [Vec3; 2],
    scale: f32,
}

/// A ray's differentials (pbrt-v4's `RayDifferential`): the rays one pixel
/// over in x and in y, already scaled by the sample spacing.
#[derive(Clone, Copy, Debug)]
pub struct Differentials {
    pub rx: Ray,
    pub ry: Ray,
}

impl Differentials {
    /// dp/dx and dp/dy of the point `p` of the plane through it with normal
    /// `n`: where the two rays meet that plane (`None` where one misses it).
    pub fn on_plane(&self, p: Vec3, n: Vec3) -> Option<(Vec3, Vec3)> {
        let meet = |r: &Ray| {
            let t = n.dot(p - r.o) / n.dot(r.d);
            let q = r.at(t) - p;
            (t.is_finite() && q.is_finite()).then_some(q)
        };
        Some((meet(&self.rx)?, meet(&self.ry)?))
    }
}

impl PixelFootprint {
    /// dp/dx and dp/dy at the point `p` of a surface with normal `n`: from
    /// the differentials of the ray that found it, or the camera's
    /// approximation at its distance (zero where neither can be found).
    pub fn dp_dxy(&self, cam: &Camera, p: Vec3, n: Vec3, along: Option<&Differentials>) -> (Vec3, Vec3) {
        along
            .and_then(|d| d.on_plane(p, n))
            .unwrap_or_else(|| self.approximate(cam, p, n))
    }

    /// The differentials of the camera ray through the image point where
    /// `p` projects, scaled by the sample spacing as pbrt-v4 scales them.
    pub fn camera_differentials(&self, cam: &Camera, p: Vec3) -> Option<Differentials> {
        let (x, y) = cam.project(p)?;
        let ray = cam.generate_ray(x, y);
        let scaled = |r: Ray| Ray::new(ray.o + (r.o - ray.o) * self.scale, ray.d + (r.d - ray.d) * self.scale);
        Some(Differentials {
            rx: scaled(cam.generate_ray(x + 1.0, y)),
            ry: scaled(cam.generate_ray(x, y + 1.0)),
        })
    }

    fn approximate(&self, cam: &Camera, p: Vec3, n: Vec3) -> (Vec3, Vec3) {
        let pc = cam.to_camera(p - cam.position);
        let Some(dir) = pc.try_normalize() else {
            return (Vec3::ZERO, Vec3::ZERO);
        };
        let r = rotate_from_to(dir, Vec3::Z);
        let pd = r * pc;
        let nd = r * cam.to_camera(n);
        let d = nd.z * pd.z;
        let at = |k: usize| {
            let (o, dir) = (self.min_pos[k], Vec3::Z + self.min_dir[k]);
            let t = -(nd.dot(o) - d) / nd.dot(dir);
            let dp = cam.camera_to_world(r.transpose() * (o + dir * t - pd)) * self.scale;
            if dp.is_finite() {
                dp
            } else {
                Vec3::ZERO
            }
        };
        (at(0), at(1))
    }
}

/// The camera-space direction (x right, y up, z forward) of the point `uv`
/// of a spherical camera's image (pbrt-v4's `SphericalCamera::GenerateRay`:
/// the sphere's z axis is the camera's up, its x the camera's right).
fn spherical_direction(mapping: SphericalMapping, uv: Vec2) -> Vec3 {
    let d = match mapping {
        SphericalMapping::Equirectangular => {
            let (sin_t, cos_t) = (std::f32::consts::PI * uv.y).sin_cos();
            let (sin_p, cos_p) = (2.0 * std::f32::consts::PI * uv.x).sin_cos();
            Vec3::new(sin_t * cos_p, sin_t * sin_p, cos_t)
        }
        SphericalMapping::EqualArea => equal_area_square_to_sphere(wrap_equal_area_square(uv)),
    };
    Vec3::new(d.x, d.z, d.y)
}

/// The image point of a unit camera-space direction: `spherical_direction`'s inverse.
fn spherical_uv(mapping: SphericalMapping, c: Vec3) -> Vec2 {
    let d = Vec3::new(c.x, c.z, c.y);
    match mapping {
        SphericalMapping::Equirectangular => {
            let phi = d.y.atan2(d.x).rem_euclid(2.0 * std::f32::consts::PI);
            let theta = Vec2::new(d.x, d.y).length().atan2(d.z);
            Vec2::new(phi / (2.0 * std::f32::consts::PI), theta / std::f32::consts::PI)
        }
        SphericalMapping::EqualArea => equal_area_sphere_to_square(d),
    }
}

/// pbrt-v4's `WrapEqualAreaSquare`: a point beyond the square's edge folded
/// back across it, where the octahedral map continues.
fn wrap_equal_area_square(mut uv: Vec2) -> Vec2 {
    if uv.x < 0.0 {
        uv = Vec2::new(-uv.x, 1.0 - uv.y);
    } else if uv.x > 1.0 {
        uv = Vec2::new(2.0 - uv.x, 1.0 - uv.y);
    }
    if uv.y < 0.0 {
        uv = Vec2::new(1.0 - uv.x, -uv.y);
    } else if uv.y > 1.0 {
        uv = Vec2::new(1.0 - uv.x, 2.0 - uv.y);
    }
    uv
}

/// pbrt-v4's `Frame::FromZ`: the unit vector `z` and two tangents, by
/// `CoordinateSystem` (Duff et al. 2017).
fn frame_from_z(z: Vec3) -> (Vec3, Vec3, Vec3) {
    let sign = 1.0f32.copysign(z.z);
    let a = -1.0 / (sign + z.z);
    let b = z.x * z.y * a;
    let x = Vec3::new(1.0 + sign * z.x * z.x * a, sign * b, -sign * z.x);
    let y = Vec3::new(b, sign + z.y * z.y * a, -z.y);
    (z, x, y)
}

/// pbrt-v4's `RotateFromTo`: a rotation taking the unit vector `from` to
/// `to`, made of two reflections through an axis far from both.
fn rotate_from_to(from: Vec3, to: Vec3) -> glam::Mat3 {
    let refl = if from.x.abs() < 0.72 && to.x.abs() < 0.72 {
        Vec3::X
    } else if from.y.abs() < 0.72 && to.y.abs() < 0.72 {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let (u, v) = (refl - from, refl - to);
    let (uu, vv, uv) = (u.dot(u), v.dot(v), u.dot(v));
    let m = |i: usize, j: usize| {
        let delta = if i == j { 1.0 } else { 0.0 };
        delta - 2.0 / uu * u[i] * u[j] - 2.0 / vv * v[i] * v[j] + 4.0 * uv / (uu * vv) * v[i] * u[j]
    };
    // Rows i, columns j.
    glam::Mat3::from_cols(
        Vec3::new(m(0, 0), m(1, 0), m(2, 0)),
        Vec3::new(m(0, 1), m(1, 1), m(2, 1)),
        Vec3::new(m(0, 2), m(1, 2), m(2, 2)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell_camera(w: u32, h: u32) -> Camera {
        let fov = 2.0 * 0.5f32.atan();
        Camera::new(
            Vec3::new(0.0, 0.0, -3.0),
            Vec3::ZERO,
            Vec3::new(0.0, -1.0, 0.0),
            fov.to_degrees(),
            w,
            h,
        )
        .unwrap()
    }

    #[test]
    fn centre_pixel_looks_along_plus_z() {
        let c = cornell_camera(512, 512);
        let r = c.generate_ray(256.0, 256.0);
        assert!((r.d - Vec3::Z).length() < 1e-6);
        assert_eq!(r.o, Vec3::new(0.0, 0.0, -3.0));
    }

    #[test]
    fn corners_are_at_the_expected_angles() {
        let c = cornell_camera(512, 512);
        // tan(half fov) = 0.5, so the top-left corner direction is (-0.5, -0.5, 1)
        // (image up is world -y, image left is world -x).
        let tl = c.generate_ray(0.0, 0.0).d;
        assert!((tl - Vec3::new(-0.5, -0.5, 1.0).normalize()).length() < 1e-6, "{tl:?}");
        let br = c.generate_ray(512.0, 512.0).d;
        assert!((br - Vec3::new(0.5, 0.5, 1.0).normalize()).length() < 1e-6, "{br:?}");
        let angle = tl.dot(Vec3::Z).acos().to_degrees();
        assert!((angle - (0.5f32 * 2.0f32.sqrt()).atan().to_degrees()).abs() < 1e-3);
    }

    #[test]
    fn wide_image_keeps_vertical_fov() {
        let c = cornell_camera(1024, 512);
        let top = c.generate_ray(512.0, 0.0).d;
        assert!((top - Vec3::new(0.0, -0.5, 1.0).normalize()).length() < 1e-6);
        let right = c.generate_ray(1024.0, 256.0).d;
        assert!((right - Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn project_inverts_generate_ray() {
        let c = cornell_camera(300, 200);
        let r = c.generate_ray(37.5, 150.25);
        let (x, y) = c.project(r.at(2.5)).unwrap();
        assert!((x - 37.5).abs() < 1e-3 && (y - 150.25).abs() < 1e-3);
    }

    #[test]
    fn the_default_window_is_the_plain_pinhole_formula_bit_for_bit() {
        let c = Camera::new(
            Vec3::new(0.3, 1.0, -3.0),
            Vec3::ZERO,
            Vec3::new(0.0, -1.0, 0.0),
            37.0,
            300,
            200,
        )
        .unwrap();
        // The camera's own tangent: a constant-folded tan may round otherwise.
        let (t, aspect) = (c.tan_half_fov, 1.5f32);
        for k in 0..500 {
            let (x, y) = ((k * 37 % 301) as f32 * 0.997, (k * 53 % 201) as f32 * 1.003);
            let sx = (2.0 * x / 300.0 - 1.0) * t * aspect;
            let sy = (1.0 - 2.0 * y / 200.0) * t;
            let d = (c.forward + c.right * sx + c.up * sy).normalize();
            assert_eq!(c.generate_ray(x, y).d, d);
        }
        // At the centre sx is zero: its sign must not change either.
        let centre = c.generate_ray(150.0, 100.0).d;
        assert_eq!(
            centre.to_array().map(f32::to_bits),
            c.forward.normalize().to_array().map(f32::to_bits)
        );
    }

    #[test]
    fn a_window_selects_and_stretches_part_of_the_image_plane() {
        // The right half of a 64 x 32 image's window, on a 32 x 32 image.
        let full = cornell_camera(64, 32);
        let half = cornell_camera(32, 32)
            .with_window(ScreenWindow {
                left: 0.0,
                right: 2.0,
                bottom: -1.0,
                top: 1.0,
            })
            .unwrap();
        for (x, y) in [(0.0, 0.0), (7.25, 3.5), (31.9, 31.9), (16.0, 16.0)] {
            let (a, b) = (half.generate_ray(x, y).d, full.generate_ray(x + 32.0, y).d);
            assert!((a - b).length() < 1e-6, "({x}, {y}): {a:?} vs {b:?}");
        }
        // An off-centre window moves the view without turning the camera.
        let up = cornell_camera(32, 32)
            .with_window(ScreenWindow {
                left: -1.0,
                right: 1.0,
                bottom: 0.0,
                top: 2.0,
            })
            .unwrap();
        let d = up.generate_ray(16.0, 32.0).d;
        assert!(
            (d - Vec3::Z).length() < 1e-6,
            "the bottom edge's middle looks ahead: {d:?}"
        );
        let r = up.generate_ray(3.5, 7.25);
        let (x, y) = up.project(r.at(2.0)).unwrap();
        assert!((x - 3.5).abs() < 1e-3 && (y - 7.25).abs() < 1e-3);
        let empty = ScreenWindow {
            left: 1.0,
            right: 1.0,
            bottom: 0.0,
            top: 1.0,
        };
        assert!(cornell_camera(8, 8).with_window(empty).is_none());
    }

    #[test]
    fn a_thin_lens_focuses_every_ray_of_a_point_on_the_focal_plane() {
        let lens = ThinLens {
            radius: 0.2,
            focal_distance: 2.5,
        };
        let c = cornell_camera(64, 48).with_lens(lens).unwrap();
        assert!(c.has_lens() && !cornell_camera(64, 48).has_lens());
        for (x, y) in [(32.0, 24.0), (3.5, 40.25), (60.0, 1.0)] {
            let pin = c.generate_ray(x, y);
            // Where the pinhole ray crosses the plane 2.5 ahead.
            let focus = pin.at(2.5 / pin.d.dot(Vec3::Z));
            let mut spread: f32 = 0.0;
            for k in 0..64 {
                let u = Vec2::new((k % 8) as f32 / 8.0 + 0.06, (k / 8) as f32 / 8.0 + 0.03);
                let r = c.generate_ray_through_lens(x, y, u);
                let off = r.o - c.position;
                // On the lens: in the plane through the camera, across the view.
                assert!(off.dot(Vec3::Z).abs() < 1e-6 && off.length() <= 0.2 + 1e-6, "{off:?}");
                spread = spread.max(off.length());
                let hit = r.at((focus - r.o).dot(Vec3::Z) / r.d.dot(Vec3::Z));
                assert!((hit - focus).length() < 1e-5, "({x}, {y}) {u:?}: {hit:?} vs {focus:?}");
            }
            assert!(spread > 0.15, "the samples cover the lens: {spread}");
            // The lens' centre is the pinhole.
            let mid = c.generate_ray_through_lens(x, y, Vec2::splat(0.5));
            assert!((mid.o - pin.o).length() < 1e-7 && (mid.d - pin.d).length() < 1e-6);
        }
        let bad = |radius, focal_distance| {
            cornell_camera(8, 8)
                .with_lens(ThinLens { radius, focal_distance })
                .is_none()
        };
        assert!(bad(0.0, 1.0) && bad(0.1, 0.0) && bad(f32::NAN, 1.0) && bad(0.1, f32::INFINITY));
    }

    #[test]
    fn an_orthographic_camera_casts_parallel_rays_from_its_image_plane() {
        // 2 units high, 3 across, looking along +z from z = -3.
        let c = Camera::orthographic(
            Vec3::new(0.0, 0.0, -3.0),
            Vec3::ZERO,
            Vec3::new(0.0, -1.0, 0.0),
            1.0,
            300,
            200,
        )
        .unwrap();
        for (x, y) in [(0.0, 0.0), (150.0, 100.0), (299.5, 12.25)] {
            let r = c.generate_ray(x, y);
            assert_eq!(r.d, Vec3::Z);
            // Image right is world +x here, image up world -y (as cornell_camera).
            let expected = Vec3::new(-1.5 + 3.0 * x / 300.0, -(1.0 - 2.0 * y / 200.0), -3.0);
            assert!(
                (r.o - expected).length() < 1e-5,
                "({x}, {y}): {:?} vs {expected:?}",
                r.o
            );
            let (px, py) = c.project(r.at(7.0)).unwrap();
            assert!((px - x).abs() < 1e-3 && (py - y).abs() < 1e-3);
            let through = c.generate_ray_through_lens(x, y, Vec2::new(0.3, 0.9));
            assert_eq!((through.o, through.d), (r.o, r.d));
        }
        let lens = ThinLens {
            radius: 0.1,
            focal_distance: 2.0,
        };
        assert!(c.clone().with_lens(lens).is_none());
        assert!(Camera::orthographic(Vec3::ZERO, Vec3::Z, Vec3::Y, 0.0, 4, 4).is_none());
    }

    #[test]
    fn degenerate_frames_are_refused() {
        assert!(Camera::new(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 60.0, 4, 4).is_none());
        assert!(Camera::new(Vec3::ZERO, Vec3::Y, Vec3::Y, 60.0, 4, 4).is_none());
        assert!(Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 180.0, 4, 4).is_none());
    }

    #[test]
    fn a_spherical_camera_lays_out_the_sphere_as_pbrt_v4_does() {
        let (pos, ahead, up) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 2.0, 4.0), Vec3::Y);
        let eq = Camera::spherical(pos, ahead, up, SphericalMapping::Equirectangular, 400, 200).unwrap();
        let right = Vec3::Z.cross(Vec3::Y);
        // Equirectangular: the top row looks up, the bottom down; across the
        // middle row right, ahead, left and back (pbrt-v4's phi from camera
        // x towards camera z).
        let d = |x: f32, y: f32| eq.generate_ray(x, y).d;
        assert!((d(123.0, 0.0) - Vec3::Y).length() < 1e-5);
        assert!((d(77.0, 200.0) + Vec3::Y).length() < 1e-3);
        for (x, want) in [(0.0, right), (100.0, Vec3::Z), (200.0, -right), (300.0, -Vec3::Z)] {
            assert!((d(x, 100.0) - want).length() < 1e-5, "{x}: {}", d(x, 100.0));
        }
        assert_eq!(eq.generate_ray(5.0, 5.0).o, pos);
        // Equal area: the centre looks up, the corners down, the middles of
        // the edges along the horizon.
        let ea = Camera::spherical(pos, ahead, up, SphericalMapping::EqualArea, 300, 300).unwrap();
        let d = |x: f32, y: f32| ea.generate_ray(x, y).d;
        assert!((d(150.0, 150.0) - Vec3::Y).length() < 1e-5);
        assert!((d(0.0, 0.0) + Vec3::Y).length() < 1e-5 && (d(300.0, 300.0) + Vec3::Y).length() < 1e-5);
        assert!(d(150.0, 0.0).y.abs() < 1e-5 && d(0.0, 150.0).y.abs() < 1e-5);
        // Beyond the square's edge (a filter's reach) the map folds back.
        assert!((d(-10.0, 150.0) - d(10.0, 150.0)).length() < 1e-2);
        // Project inverts both, anywhere on the image.
        for cam in [&eq, &ea] {
            for (x, y) in [(37.5, 20.25), (250.0, 120.0), (133.0, 177.0)] {
                let (px, py) = cam.project(cam.generate_ray(x, y).at(2.5)).unwrap();
                assert!((px - x).abs() < 0.02 && (py - y).abs() < 0.02, "{x} {y}: {px} {py}");
            }
        }
        // No lens on a spherical camera.
        let lens = ThinLens {
            radius: 0.1,
            focal_distance: 2.0,
        };
        assert!(eq.clone().with_lens(lens).is_none());
    }

    #[test]
    fn a_camera_rays_footprint_is_its_pixel_on_the_surface_scaled_by_the_sample_spacing() {
        let c = cornell_camera(512, 512);
        // 64 samples a pixel and more: an eighth of a pixel; 16: a quarter.
        let fp = c.pixel_footprint(64);
        assert_eq!(fp.scale, 0.125);
        assert_eq!(c.pixel_footprint(16).scale, 0.25);
        // The plane z = 0 faces the camera 3 units away: a pixel there is
        // 2 tan(fov / 2) 3 / 512 wide, along +x (image right) and +y (down).
        let pixel = 2.0 * 0.5 * 3.0 / 512.0;
        let cam_rays = fp.camera_differentials(&c, Vec3::ZERO);
        let (dx, dy) = fp.dp_dxy(&c, Vec3::ZERO, -Vec3::Z, cam_rays.as_ref());
        assert!((dx - Vec3::X * pixel * 0.125).length() < 1e-3 * pixel, "{dx}");
        assert!((dy - Vec3::Y * pixel * 0.125).length() < 1e-3 * pixel, "{dy}");
        // Tilted 60 degrees about x, the plane stretches y's footprint twice.
        let n = Vec3::new(0.0, 60f32.to_radians().sin(), -60f32.to_radians().cos());
        let (tx, ty) = fp.dp_dxy(&c, Vec3::ZERO, n, cam_rays.as_ref());
        assert!((tx.length() / dx.length() - 1.0).abs() < 1e-3);
        assert!(
            (ty.length() / dy.length() - 2.0).abs() < 1e-2,
            "{}",
            ty.length() / dy.length()
        );
        assert!(ty.dot(n).abs() < 1e-4 * ty.length() && tx.dot(n).abs() < 1e-4 * tx.length());
        // Away from camera rays, pbrt-v4's approximation: the image's
        // smallest pixel (its corners', 0.53 of its centre's here) at the
        // point's distance, on its plane; a point twice as far, twice as big.
        let (ax, ay) = fp.dp_dxy(&c, Vec3::ZERO, -Vec3::Z, None);
        for a in [ax, ay] {
            let ratio = a.length() / dx.length();
            assert!(ratio > 0.5 && ratio < 0.75, "{ratio}");
            assert!(a.dot(Vec3::Z).abs() < 1e-6 * a.length());
        }
        let (fx, _) = fp.dp_dxy(&c, Vec3::new(0.0, 0.0, 3.0), -Vec3::Z, None);
        assert!((fx.length() / ax.length() - 2.0).abs() < 1e-3);
    }

    #[test]
    fn an_orthographic_footprint_is_the_pixel_whatever_the_distance() {
        let c = Camera::orthographic(Vec3::new(0.0, 0.0, -3.0), Vec3::ZERO, Vec3::Y, 2.0, 100, 100).unwrap();
        let fp = c.pixel_footprint(1);
        assert_eq!(fp.scale, 1.0);
        // On the axis (pbrt-v4's approximation turns the point onto it, and
        // its plane with it) and, for camera rays, anywhere.
        for (from_camera, x, y) in [(true, 0.5, 0.25), (false, 0.0, 0.0)] {
            for z in [0.0, 5.0] {
                let p = Vec3::new(x, y, z);
                let rays = if from_camera {
                    fp.camera_differentials(&c, p)
                } else {
                    None
                };
                let (dx, dy) = fp.dp_dxy(&c, p, -Vec3::Z, rays.as_ref());
                assert!(
                    (dx.length() - 0.04).abs() < 1e-5 && (dy.length() - 0.04).abs() < 1e-5,
                    "{dx} {dy}"
                );
            }
        }
    }
}
