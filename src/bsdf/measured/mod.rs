//! Measured BRDFs of the RGL material database (Dupuy & Jakob 2018, "An
//! Adaptive Parameterization for Efficient Material Acquisition and
//! Rendering"), as pbrt-v4's `MeasuredBxDF` renders them.
//!
//! A file holds, over the unit square of (u_theta, u_phi) = (sqrt(2 theta /
//! pi), phi / 2 pi + 1/2): the microfacet distribution `ndf` of the half
//! vector and the projected area `sigma` of the outgoing direction; and per
//! incident angle (phi_i, theta_i) on a grid, the visible normals' density
//! `vndf`, a `luminance` density of the sampled square, and the spectra
//! measured over that square. The BRDF is
//! `spectra(R^-1(wm)) D(wm) / (4 sigma(wo) cos theta_i)`, where R warps the
//! square by the visible normals; sampling warps by the luminance first,
//! then by R. An isotropic file (at most two phi_i) gives phi relative to
//! the outgoing direction's.
//!
//! This renderer works in RGB: the spectra are turned into RGB once, at
//! load, by the weights the caller gives each wavelength. Since that is
//! linear, it commutes with the interpolation over the square and the
//! angles, which pbrt-v4 does per wavelength.

mod tensor;
mod warp;

pub use warp::PiecewiseLinear2D;

use super::{BsdfSample, BxdfFlags, TransportMode};
use crate::math::{Vec2, Vec3};
use std::collections::HashMap;
use std::f32::consts::PI;
use std::fmt;
use std::path::Path;
use std::sync::Mutex;
use tensor::TensorFile;

/// A hash of a file's bytes, for telling files apart.
fn digest(bytes: &[u8]) -> u64 {
    let mut h = crate::texture::Fnv64::default();
    h.bytes(bytes);
    h.0
}

/// A measured BRDF's tables, in RGB.
pub struct MeasuredData {
    /// The file it came from, for messages.
    pub name: String,
    /// A hash of the file's bytes: scene fingerprints (checkpoints, photon
    /// files) hash a material's Debug form, which shows this.
    digest: u64,
    isotropic: bool,
    /// Of an anisotropic file, the symmetry that lets it cover 1, 1/2 or 1/4
    /// of the incident azimuths (Mitsuba's `reduction`; pbrt-v4 reads 1 only).
    reduction: u8,
    /// Whether the colour table still wants the Jacobian D(wm) / (4 sigma)
    /// (every database file: its `jacobian` byte is 1); else it is f cos_i.
    jacobian: bool,
    ndf: PiecewiseLinear2D,
    sigma: PiecewiseLinear2D,
    vndf: PiecewiseLinear2D,
    luminance: PiecewiseLinear2D,
    /// Parameters (phi_i, theta_i, channel 0..3).
    rgb: PiecewiseLinear2D,
}

impl fmt::Debug for MeasuredData {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Not the folder: the same scene read elsewhere is the same scene.
        let name = Path::new(&self.name)
            .file_name()
            .map(|n| n.to_string_lossy())
            .unwrap_or_default();
        write!(f, "MeasuredData {{ file: {name:?}, hash: {:016x} }}", self.digest)
    }
}

/// The channels' parameter values of the RGB table.
const CHANNELS: [f32; 3] = [0.0, 1.0, 2.0];

impl MeasuredData {
    /// Reads a tensor file's bytes; `rgb_of` gives the RGB weight of each
    /// of the file's wavelengths (nm), so that a spectrum's colour is the
    /// sum of its values times these. Errors say what is wrong with the file.
    pub fn from_bytes(file: &[u8], name: &str, rgb_of: impl Fn(&[f32]) -> Vec<Vec3>) -> Result<Self, String> {
        let t = TensorFile::parse(file)?;
        let floats = |field: &str, rank: usize| -> Result<(Vec<usize>, Vec<f32>), String> {
            let f = t.field(field)?;
            if f.shape.len() != rank {
                return Err(format!(
                    "field \"{field}\" has {} dimensions, not {rank}",
                    f.shape.len()
                ));
            }
            let v = f.floats().map_err(|e| format!("field \"{field}\" {e}"))?;
            if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
                return Err(format!("field \"{field}\" holds {bad}"));
            }
            Ok((f.shape.clone(), v))
        };
        for bytes in ["description", "jacobian"] {
            if !t.field(bytes)?.is_bytes() {
                return Err(format!("field \"{bytes}\" is not bytes"));
            }
        }
        let jacobian = t.field("jacobian")?.bytes().first().is_none_or(|&b| b != 0);
        let (_, theta_i) = floats("theta_i", 1)?;
        let (_, phi_i) = floats("phi_i", 1)?;
        let (ndf_shape, ndf) = floats("ndf", 2)?;
        let (sigma_shape, sigma) = floats("sigma", 2)?;
        let (vndf_shape, vndf) = floats("vndf", 4)?;
        let (lum_shape, lum) = floats("luminance", 4)?;
        let (np, nt) = (phi_i.len(), theta_i.len());
        let (ny, nx) = (lum_shape[2], lum_shape[3]);
        // The colours over the square: spectra (pbrt-v4 and Mitsuba read
        // those), else the RGB that the database's RGB files hold instead.
        let spectral = t.field("spectra").is_ok();
        let (colour_shape, colours) = if spectral {
            floats("spectra", 5)?
        } else {
            floats("rgb", 5)?
        };
        let channels = if spectral {
            let (_, wavelengths) = floats("wavelengths", 1)?;
            if wavelengths.windows(2).any(|w| w[0] >= w[1]) {
                return Err("field \"wavelengths\" is not ascending".into());
            }
            let w = rgb_of(&wavelengths);
            if w.len() != wavelengths.len() || w.is_empty() {
                return Err("no colour for the file's wavelengths".into());
            }
            w
        } else {
            vec![Vec3::X, Vec3::Y, Vec3::Z]
        };
        let nl = channels.len();
        let shapes_agree =
            vndf_shape[..2] == [np, nt] && lum_shape[..2] == [np, nt] && colour_shape == [np, nt, nl, ny, nx];
        if !shapes_agree {
            return Err(format!(
                "inconsistent shapes: phi_i {np}, theta_i {nt}, colours {nl}, vndf {vndf_shape:?}, \
                 luminance {lum_shape:?}, {} {colour_shape:?}",
                if spectral { "spectra" } else { "rgb" }
            ));
        }
        // Densities and areas: a negative value (rounding in a fit) is none.
        // (Colours are clamped after interpolation, as pbrt-v4 clamps them.)
        let clamp = |v: Vec<f32>| -> Vec<f32> { v.into_iter().map(|x| x.max(0.0)).collect() };
        let (ndf, sigma, vndf, lum) = (clamp(ndf), clamp(sigma), clamp(vndf), clamp(lum));
        let isotropic = np <= 2;
        let mut reduction = 1;
        if !isotropic {
            let span = phi_i[np - 1] - phi_i[0];
            let r = (2.0 * PI / span).round();
            if ![1.0, 2.0, 4.0].contains(&r) {
                return Err(format!(
                    "phi_i spans {span} radians: a file covers the full circle, a half or a quarter"
                ));
            }
            // Directions are folded into the azimuths from -pi on.
            if (phi_i[0] + PI).abs() > 1e-3 {
                return Err(format!("phi_i starts at {}: files start at -pi", phi_i[0]));
            }
            reduction = r as u8;
        }
        let table = |what: &str, r: Result<PiecewiseLinear2D, String>| r.map_err(|e| format!("field \"{what}\": {e}"));
        let ndf = table(
            "ndf",
            PiecewiseLinear2D::new(&ndf, ndf_shape[1], ndf_shape[0], &[], false),
        )?;
        let sigma = table(
            "sigma",
            PiecewiseLinear2D::new(&sigma, sigma_shape[1], sigma_shape[0], &[], false),
        )?;
        let angles: [&[f32]; 2] = [&phi_i, &theta_i];
        let vndf = table(
            "vndf",
            PiecewiseLinear2D::new(&vndf, vndf_shape[3], vndf_shape[2], &angles, true),
        )?;
        let luminance = table("luminance", PiecewiseLinear2D::new(&lum, nx, ny, &angles, true))?;
        let n = nx * ny;
        let mut rgb = vec![0.0f32; np * nt * 3 * n];
        for a in 0..np * nt {
            for (l, w) in channels.iter().enumerate() {
                let src = &colours[(a * nl + l) * n..(a * nl + l + 1) * n];
                for c in 0..3 {
                    let dst = &mut rgb[(a * 3 + c) * n..(a * 3 + c + 1) * n];
                    for (d, s) in dst.iter_mut().zip(src) {
                        *d += w[c] * s;
                    }
                }
            }
        }
        let rgb = table(
            if spectral { "spectra" } else { "rgb" },
            PiecewiseLinear2D::new(&rgb, nx, ny, &[&phi_i, &theta_i, &CHANNELS], false),
        )?;
        Ok(MeasuredData {
            name: name.to_string(),
            digest: digest(file),
            isotropic,
            reduction,
            jacobian,
            ndf,
            sigma,
            vndf,
            luminance,
            rgb,
        })
    }

    /// The data of a file's bytes, parsed once per process and kept (as
    /// pbrt-v4 keeps it): a scene may name one file for many materials, and
    /// renders hold BSDFs that refer to it. Files of the same name and bytes
    /// share their data.
    pub fn shared(
        path: &Path,
        file: &[u8],
        rgb_of: impl Fn(&[f32]) -> Vec<Vec3>,
    ) -> Result<&'static MeasuredData, String> {
        static LOADED: Mutex<Option<HashMap<(String, u64), &'static MeasuredData>>> = Mutex::new(None);
        let key = (path.display().to_string(), digest(file));
        let mut loaded = LOADED.lock().unwrap_or_else(|e| e.into_inner());
        let loaded = loaded.get_or_insert_with(HashMap::new);
        if let Some(&d) = loaded.get(&key) {
            return Ok(d);
        }
        let data = MeasuredData::from_bytes(file, &key.0, rgb_of)?;
        let data: &'static MeasuredData = Box::leak(Box::new(data));
        loaded.insert(key, data);
        Ok(data)
    }
}

/// A measured BRDF: glossy reflection on both sides (pbrt-v4 mirrors the
/// directions of the lower side above the surface).
#[derive(Clone, Copy)]
pub struct MeasuredBxdf {
    pub data: &'static MeasuredData,
    /// In a scene reflected as a whole (pbrt-v4's handedness), the shading
    /// frame's y axis turns round: its azimuths are read mirrored back, so
    /// that an anisotropic file keeps pbrt-v4's orientation.
    pub mirrored: bool,
}

impl MeasuredBxdf {
    pub fn new(data: &'static MeasuredData) -> Self {
        MeasuredBxdf { data, mirrored: false }
    }
}

impl PartialEq for MeasuredBxdf {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.data, other.data) && self.mirrored == other.mirrored
    }
}

impl fmt::Debug for MeasuredBxdf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "MeasuredBxdf({:?}, mirrored: {})", self.data, self.mirrored)
    }
}

fn theta_to_u(theta: f32) -> f32 {
    (theta * (2.0 / PI)).sqrt()
}

fn phi_to_u(phi: f32) -> f32 {
    phi * (0.5 / PI) + 0.5
}

/// The polar angle of a unit vector. Not `acos(z)`: near the normal,
/// where measured half vectors crowd, that loses the angle's digits, and
/// the square's u_theta (its square root) doubles the loss.
fn spherical_theta(w: Vec3) -> f32 {
    (w.x * w.x + w.y * w.y).sqrt().atan2(w.z)
}

/// What `f`, `pdf` and `sample_f` share for a pair of directions above the
/// surface: the angles' parameters and the half vector's square position.
struct Pair {
    params: [f32; 2],
    u_wo: Vec2,
    u_wm: Vec2,
}

impl MeasuredBxdf {
    pub fn flags(&self) -> BxdfFlags {
        BxdfFlags::GLOSSY_REFLECTION
    }

    /// The signs that take `wo` into the azimuths a reduced file covers:
    /// y <= 0 for a half (turning by pi), x, y <= 0 for a quarter
    /// (mirroring), as Mitsuba folds them. Applied to both directions.
    fn fold(&self, wo: Vec3) -> Vec3 {
        let neg = |v: f32| if v >= 0.0 { -1.0 } else { 1.0 };
        match self.data.reduction {
            2 => Vec3::new(neg(wo.y), neg(wo.y), 1.0),
            4 => Vec3::new(neg(wo.x), neg(wo.y), 1.0),
            _ => Vec3::ONE,
        }
    }

    fn pair(&self, wo: Vec3, wm: Vec3) -> Pair {
        let (theta_o, phi_o) = (spherical_theta(wo), wo.y.atan2(wo.x));
        let (theta_m, phi_m) = (spherical_theta(wm), wm.y.atan2(wm.x));
        let phi_m = if self.data.isotropic { phi_m - phi_o } else { phi_m };
        let v = phi_to_u(phi_m);
        Pair {
            params: [phi_o, theta_o],
            u_wo: Vec2::new(theta_to_u(theta_o), phi_to_u(phi_o)),
            u_wm: Vec2::new(theta_to_u(theta_m), v - v.floor()),
        }
    }

    /// The BRDF at square point `u` (the colour table's) for a pair whose
    /// half vector is at `u_wm`, with `cos_i` the incident cosine.
    fn value(&self, u: Vec2, params: [f32; 2], u_wo: Vec2, u_wm: Vec2, cos_i: f32) -> Vec3 {
        let d = self.data;
        let c = |k: usize| d.rgb.evaluate(u, &[params[0], params[1], CHANNELS[k]]).max(0.0);
        let colour = Vec3::new(c(0), c(1), c(2));
        let f = if d.jacobian {
            colour * d.ndf.evaluate(u_wm, &[]) / (4.0 * d.sigma.evaluate(u_wo, &[]) * cos_i)
        } else {
            colour / cos_i
        };
        if f.is_finite() {
            f.max(Vec3::ZERO)
        } else {
            Vec3::ZERO
        }
    }

    /// A shading-frame direction in the file's frame (and back).
    fn handed(&self, w: Vec3) -> Vec3 {
        if self.mirrored {
            Vec3::new(w.x, -w.y, w.z)
        } else {
            w
        }
    }

    /// Both directions above the surface (mirrored there when `wo` is
    /// below) and folded into the file's azimuths, with their half vector;
    /// None when they lie on opposite sides or the half vector is undefined.
    fn upper(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3, Vec3)> {
        if wo.z * wi.z <= 0.0 {
            return None;
        }
        let (wo, wi) = (self.handed(wo), self.handed(wi));
        let (wo, wi) = if wo.z < 0.0 { (-wo, -wi) } else { (wo, wi) };
        let s = self.fold(wo);
        let (wo, wi) = (wo * s, wi * s);
        let wm = (wo + wi).try_normalize()?;
        Some((wo, wi, wm))
    }

    /// The BRDF for light going from `wi` to `wo`; for importance (light
    /// paths) its adjoint, f(wi, wo): a table need not be reciprocal, and
    /// light and camera paths then see the same surface.
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        match mode {
            TransportMode::Radiance => self.eval(wo, wi),
            TransportMode::Importance => self.eval(wi, wo),
        }
    }

    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let Some((wo, wi, wm)) = self.upper(wo, wi) else {
            return Vec3::ZERO;
        };
        let p = self.pair(wo, wm);
        let (u, _) = self.data.vndf.invert(p.u_wm, &p.params);
        self.value(u, p.params, p.u_wo, p.u_wm, wi.z)
    }

    /// The Jacobian from the square's density of the half vector to the
    /// solid-angle density of the reflected direction.
    fn to_solid_angle(wo: Vec3, wm: Vec3, u_wm: Vec2) -> f32 {
        let sin_theta_m = (wm.x * wm.x + wm.y * wm.y).sqrt();
        4.0 * wo.dot(wm) * (2.0 * PI * PI * u_wm.x * sin_theta_m).max(1e-6)
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some((wo, _, wm)) = self.upper(wo, wi) else {
            return 0.0;
        };
        let d = self.data;
        let p = self.pair(wo, wm);
        let (u, vndf_pdf) = d.vndf.invert(p.u_wm, &p.params);
        let pdf = vndf_pdf * d.luminance.evaluate(u, &p.params) / Self::to_solid_angle(wo, wm, p.u_wm);
        if pdf.is_finite() && pdf >= 0.0 {
            pdf
        } else {
            0.0
        }
    }

    /// Samples `wi` by the file's luminance and visible normals, as pbrt-v4
    /// does, whatever the mode; the value is the mode's ([`Self::f`]).
    pub fn sample_f(&self, wo: Vec3, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let mut bs = self.sample_radiance(wo, u)?;
        if mode == TransportMode::Importance {
            bs.f = self.eval(bs.wi, wo);
        }
        Some(bs)
    }

    fn sample_radiance(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        let wo = self.handed(wo);
        let flip = if wo.z <= 0.0 { -1.0 } else { 1.0 };
        let s = self.fold(wo * flip);
        let wo = wo * flip * s;
        let d = self.data;
        let params = [wo.y.atan2(wo.x), spherical_theta(wo)];
        let (u, lum_pdf) = d.luminance.sample(u, &params);
        let (u_wm, vndf_pdf) = d.vndf.sample(u, &params);
        let theta_m = u_wm.x * u_wm.x * (PI / 2.0);
        let phi_m = (2.0 * u_wm.y - 1.0) * PI + if d.isotropic { params[0] } else { 0.0 };
        let (sin_m, cos_m) = theta_m.sin_cos();
        let wm = Vec3::new(sin_m * phi_m.cos(), sin_m * phi_m.sin(), cos_m);
        let wi = super::reflect(wo, wm);
        if wi.z <= 0.0 {
            return None;
        }
        let u_wo = Vec2::new(theta_to_u(params[1]), phi_to_u(params[0]));
        let f = self.value(u, params, u_wo, u_wm, wi.z);
        let pdf = vndf_pdf * lum_pdf / Self::to_solid_angle(wo, wm, u_wm);
        if !(pdf.is_finite() && pdf > 0.0) {
            return None;
        }
        Some(BsdfSample {
            f,
            wi: self.handed(wi * s * flip),
            pdf,
            flags: BxdfFlags::GLOSSY_REFLECTION,
            eta: 1.0,
        })
    }
}

#[cfg(test)]
mod tests;

/// A small valid file (a Trowbridge-Reitz reflector), for other modules' tests.
#[cfg(test)]
pub fn test_file() -> Vec<u8> {
    tests::ggx_file(8)
}
