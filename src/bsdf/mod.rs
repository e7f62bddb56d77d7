//! Surface scattering models (BxDFs) in a local shading frame.
//!
//! The layer follows pbrt-v4, chapter 9 ("Reflection Models"), and its
//! source (`bxdfs.h`, `util/scattering.h`): every model evaluates `f`,
//! samples an incident direction with `sample_f`, and returns the density of
//! that sampling with `pdf`, all in a local frame whose normal is +z, with the
//! transport mode (radiance or importance) passed in. Integrators never ask
//! which model they hold; they ask the [`BxdfFlags`].
//!
//! | model | module | follows |
//! |---|---|---|
//! | [`DiffuseBxdf`], [`DiffuseTransmissionBxdf`] | `diffuse` | pbrt-v4 9.2; its `DiffuseTransmissionBxDF` |
//! | [`ConductorBxdf`] | `conductor` | pbrt-v4 9.4 (complex Fresnel), 9.6 (Torrance-Sparrow, Trowbridge-Reitz) |
//! | [`DielectricBxdf`], [`ThinDielectricBxdf`] | `dielectric` | pbrt-v4 9.3, 9.5, 9.7; Walter et al. 2007 |
//! | [`DispersiveBxdf`] | `dispersive` | a dielectric per colour channel, one-sample MIS over the channels |
//! | [`CoatedDiffuseBxdf`] | `coated` | closed form after Weidlich & Wilkie 2007 / Mitsuba's `roughplastic`, checked against pbrt-v4's `LayeredBxDF` |
//! | [`CoatedConductorBxdf`] | `layered` | pbrt-v4's `LayeredBxDF` random walk (Guo et al. 2018) for `f`; a deterministic mixture for sampling |
//! | [`ScatteringCoatBxdf`] | `scattering_coat` | the same walk with a scattering medium in the coat, over a Lambertian base or a metal |
//! | [`HairBxdf`] | `hair` | pbrt-v4 9.9 (Chiang et al. 2016) |
//! | [`MeasuredBxdf`] | `measured` | pbrt-v4's `MeasuredBxDF` (Dupuy & Jakob 2018): the RGL database's tensor files |
//! | [`TrowbridgeReitz`] | `microfacet` | pbrt-v4 9.6; Heitz 2014 (masking), Heitz 2018 (visible normals) |
//! | Fresnel terms | `fresnel` | pbrt-v4 9.3-9.4 |
//! | named metals | `metals` | pbrt-v4's `metal-*-eta/k` spectra, fitted to RGB |
//!
//! Conventions (those of pbrt-v4): `wo` and `wi` are unit vectors pointing
//! away from the surface; `f` is the BSDF value without the cosine; a sampled
//! [`BsdfSample`] carries `f`, `wi` and `pdf` so that the throughput update is
//! `f * |cos(wi)| / pdf`. For specular (delta) lobes `f` and `pdf` are both
//! relative to the delta, so only their ratio means anything; `f()` and
//! `pdf()` return zero for them. Colours are linear RGB in a [`Vec3`].
//!
//! The shading-normal correction for light paths (Veach 1997, 5.3) and
//! Russian roulette belong to the integrators, not here.

mod coated;
mod conductor;
mod dielectric;
pub(crate) mod diffuse;
mod dispersive;
pub(crate) mod frame;
mod fresnel;
mod hair;
mod layered;
mod measured;
mod metals;
mod microfacet;
mod scattering_coat;

#[cfg(test)]
mod spectral_data;
#[cfg(test)]
mod tests;

pub use coated::{CoatTable, CoatedDiffuseBxdf};
pub use conductor::ConductorBxdf;
pub use dielectric::{DielectricBxdf, ThinDielectricBxdf};
pub use diffuse::{DiffuseBxdf, DiffuseTransmissionBxdf, NormalizedFresnelBxdf};
pub use dispersive::DispersiveBxdf;
pub use frame::Frame;
pub use fresnel::{fr_complex, fr_complex_rgb, fr_dielectric, fresnel_moment1, fresnel_moment2, reflect, refract};
pub use hair::HairBxdf;
pub use layered::CoatedConductorBxdf;
#[cfg(test)]
pub use measured::test_file as measured_test_file;
pub use measured::{MeasuredBxdf, MeasuredData};
pub use metals::{named_metal, named_spectrum_rgb, NAMED_METALS};
pub use microfacet::TrowbridgeReitz;
pub use scattering_coat::ScatteringCoatBxdf;

use crate::math::{Vec2, Vec3};
use std::fmt;
use std::ops::{BitOr, BitOrAssign, Not};

/// Whether a path carries radiance (from the camera) or importance (from a
/// light, as photons do). Only transmission into a medium of another index
/// of refraction cares: radiance is scaled by 1/eta^2 there, importance is not
/// (Veach 1997, 5.2; pbrt-v4 9.5, "non-symmetric scattering").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TransportMode {
    Radiance,
    Importance,
}

impl Not for TransportMode {
    type Output = TransportMode;

    /// The adjoint mode: the one a path traced from the other end carries.
    fn not(self) -> TransportMode {
        match self {
            TransportMode::Radiance => TransportMode::Importance,
            TransportMode::Importance => TransportMode::Radiance,
        }
    }
}

/// What kinds of scattering a BxDF (or one sampled lobe) does: reflection
/// and/or transmission, each diffuse, glossy or specular (pbrt-v4 `BxDFFlags`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct BxdfFlags(u8);

impl BxdfFlags {
    pub const UNSET: BxdfFlags = BxdfFlags(0);
    pub const REFLECTION: BxdfFlags = BxdfFlags(1);
    pub const TRANSMISSION: BxdfFlags = BxdfFlags(1 << 1);
    pub const DIFFUSE: BxdfFlags = BxdfFlags(1 << 2);
    pub const GLOSSY: BxdfFlags = BxdfFlags(1 << 3);
    pub const SPECULAR: BxdfFlags = BxdfFlags(1 << 4);
    pub const DIFFUSE_REFLECTION: BxdfFlags = BxdfFlags(1 | 1 << 2);
    pub const DIFFUSE_TRANSMISSION: BxdfFlags = BxdfFlags(1 << 1 | 1 << 2);
    pub const GLOSSY_REFLECTION: BxdfFlags = BxdfFlags(1 | 1 << 3);
    pub const GLOSSY_TRANSMISSION: BxdfFlags = BxdfFlags(1 << 1 | 1 << 3);
    pub const SPECULAR_REFLECTION: BxdfFlags = BxdfFlags(1 | 1 << 4);
    pub const SPECULAR_TRANSMISSION: BxdfFlags = BxdfFlags(1 << 1 | 1 << 4);
    pub const ALL: BxdfFlags = BxdfFlags(0b1_1111);

    pub const fn bits(self) -> u8 {
        self.0
    }

    /// True when every flag of `other` is set in `self`.
    pub const fn contains(self, other: BxdfFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// True when `self` and `other` share a flag.
    pub const fn intersects(self, other: BxdfFlags) -> bool {
        self.0 & other.0 != 0
    }

    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    pub const fn is_reflective(self) -> bool {
        self.intersects(Self::REFLECTION)
    }

    pub const fn is_transmissive(self) -> bool {
        self.intersects(Self::TRANSMISSION)
    }

    pub const fn is_diffuse(self) -> bool {
        self.intersects(Self::DIFFUSE)
    }

    pub const fn is_glossy(self) -> bool {
        self.intersects(Self::GLOSSY)
    }

    pub const fn is_specular(self) -> bool {
        self.intersects(Self::SPECULAR)
    }

    /// True when some lobe can be evaluated (diffuse or glossy): light
    /// sampling and MIS make sense at such a vertex.
    pub const fn is_non_specular(self) -> bool {
        self.intersects(BxdfFlags(Self::DIFFUSE.0 | Self::GLOSSY.0))
    }
}

impl BitOr for BxdfFlags {
    type Output = BxdfFlags;

    fn bitor(self, rhs: BxdfFlags) -> BxdfFlags {
        BxdfFlags(self.0 | rhs.0)
    }
}

impl BitOrAssign for BxdfFlags {
    fn bitor_assign(&mut self, rhs: BxdfFlags) {
        self.0 |= rhs.0;
    }
}

impl fmt::Debug for BxdfFlags {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names = [
            (Self::REFLECTION, "Reflection"),
            (Self::TRANSMISSION, "Transmission"),
            (Self::DIFFUSE, "Diffuse"),
            (Self::GLOSSY, "Glossy"),
            (Self::SPECULAR, "Specular"),
        ];
        let set: Vec<&str> = names
            .iter()
            .filter(|(flag, _)| self.contains(*flag))
            .map(|(_, name)| *name)
            .collect();
        if set.is_empty() {
            write!(f, "BxdfFlags(Unset)")
        } else {
            write!(f, "BxdfFlags({})", set.join(" | "))
        }
    }
}

/// A direction sampled from a BxDF, with everything the path update needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// BSDF value for (`wo`, `wi`) in the given transport mode (for a
    /// specular lobe, relative to the delta, like `pdf`).
    pub f: Vec3,
    /// The sampled incident direction (local frame unless it came from [`Bsdf`]).
    pub wi: Vec3,
    /// Solid-angle density of `wi` (for a specular lobe: the discrete
    /// probability of choosing that lobe).
    pub pdf: f32,
    /// The kind of lobe that was sampled.
    pub flags: BxdfFlags,
    /// Relative index of refraction along the path for transmission
    /// (eta_transmitted / eta_incident), 1 for reflection. Integrators use
    /// it to keep Russian roulette independent of the 1/eta^2 scaling.
    pub eta: f32,
}

impl BsdfSample {
    pub fn is_reflection(&self) -> bool {
        self.flags.is_reflective()
    }

    pub fn is_transmission(&self) -> bool {
        self.flags.is_transmissive()
    }

    pub fn is_specular(&self) -> bool {
        self.flags.is_specular()
    }

    /// The throughput factor `f |cos(wi)| / pdf` (local-frame samples only).
    pub fn weight(&self) -> Vec3 {
        if self.pdf > 0.0 {
            self.f * (abs_cos_theta(self.wi) / self.pdf)
        } else {
            Vec3::ZERO
        }
    }
}

/// One scattering model, evaluated in the local shading frame (normal +z).
/// A closed set of models, dispatched by `match` (pbrt-v4's tagged `BxDF`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bxdf {
    Diffuse(DiffuseBxdf),
    DiffuseTransmission(DiffuseTransmissionBxdf),
    Conductor(ConductorBxdf),
    Dielectric(DielectricBxdf),
    Dispersive(DispersiveBxdf),
    ThinDielectric(ThinDielectricBxdf),
    CoatedDiffuse(CoatedDiffuseBxdf),
    CoatedConductor(CoatedConductorBxdf),
    ScatteringCoat(ScatteringCoatBxdf),
    Hair(HairBxdf),
    NormalizedFresnel(NormalizedFresnelBxdf),
    Measured(MeasuredBxdf),
}

impl Bxdf {
    /// Lambertian reflection with reflectance `r` (pbrt-v4 `diffuse`).
    pub fn diffuse(r: Vec3) -> Self {
        Bxdf::Diffuse(DiffuseBxdf::new(r))
    }

    /// Lambertian reflection `r` and transmission `t` (pbrt-v4 `diffusetransmission`).
    pub fn diffuse_transmission(r: Vec3, t: Vec3) -> Self {
        Bxdf::DiffuseTransmission(DiffuseTransmissionBxdf::new(r, t))
    }

    /// A metal with complex index of refraction `eta + i k` per RGB channel.
    pub fn conductor(distrib: TrowbridgeReitz, eta: Vec3, k: Vec3) -> Self {
        Bxdf::Conductor(ConductorBxdf::new(distrib, eta, k))
    }

    /// A metal given by its reflectance at normal incidence (pbrt-v4's
    /// `conductor` with `reflectance`).
    pub fn conductor_from_reflectance(distrib: TrowbridgeReitz, r: Vec3) -> Self {
        Bxdf::Conductor(ConductorBxdf::from_reflectance(distrib, r))
    }

    /// A dielectric interface with relative index `eta` (inside / outside).
    pub fn dielectric(distrib: TrowbridgeReitz, eta: f32) -> Self {
        Bxdf::Dielectric(DielectricBxdf::new(distrib, eta))
    }

    /// A dielectric interface whose relative index differs by colour channel.
    pub fn dispersive(distrib: TrowbridgeReitz, eta: Vec3) -> Self {
        Bxdf::Dispersive(DispersiveBxdf::new(distrib, eta))
    }

    /// A thin dielectric slab with index `eta` (pbrt-v4 `thindielectric`).
    pub fn thin_dielectric(eta: f32) -> Self {
        Bxdf::ThinDielectric(ThinDielectricBxdf::new(eta))
    }

    /// A dielectric coat of index `eta` and absorbing `thickness` (pbrt-v4's
    /// default: 0.01; 0 for a clear coat) over a Lambertian base `r`.
    pub fn coated_diffuse(distrib: TrowbridgeReitz, eta: f32, r: Vec3, thickness: f32) -> Self {
        Bxdf::CoatedDiffuse(CoatedDiffuseBxdf::new(distrib, eta, r, thickness))
    }

    /// A dielectric coat over a metal given as it would be in air (pbrt-v4's
    /// `coatedconductor`; its defaults: thickness 0.01, 10 scattering
    /// events, 1 walk per evaluation).
    pub fn coated_conductor(
        coat: DielectricBxdf,
        base: ConductorBxdf,
        thickness: f32,
        max_depth: u32,
        samples: u32,
    ) -> Self {
        Bxdf::CoatedConductor(CoatedConductorBxdf::new(coat, base, thickness, max_depth, samples))
    }

    /// The BSDF value for the pair (`wo`, `wi`), without the cosine; zero
    /// for specular lobes.
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        match self {
            Bxdf::Diffuse(b) => b.f(wo, wi),
            Bxdf::DiffuseTransmission(b) => b.f(wo, wi),
            Bxdf::Conductor(b) => b.f(wo, wi),
            Bxdf::Dielectric(b) => b.f(wo, wi, mode),
            Bxdf::Dispersive(b) => b.f(wo, wi, mode),
            Bxdf::ThinDielectric(_) => Vec3::ZERO,
            Bxdf::CoatedDiffuse(b) => b.f(wo, wi),
            Bxdf::CoatedConductor(b) => b.f(wo, wi, mode),
            Bxdf::ScatteringCoat(b) => b.f(wo, wi, mode),
            Bxdf::Hair(b) => b.f(wo, wi, mode),
            Bxdf::NormalizedFresnel(b) => b.f(wo, wi, mode),
            Bxdf::Measured(b) => b.f(wo, wi, mode),
        }
    }

    /// Samples an incident direction for `wo`: `uc` picks a lobe, `u` the
    /// direction within it. `None` when no direction could be produced
    /// (including degenerate ones: zero or non-finite pdf, `wi` in the
    /// tangent plane).
    // Inlined into `Bsdf::sample_f`, its one caller: left to itself the
    // compiler's choice changes with unrelated code (BENCHMARKS.md, "What
    // media cost scenes without them").
    #[inline(always)]
    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let bs = match self {
            Bxdf::Diffuse(b) => b.sample_f(wo, u),
            Bxdf::DiffuseTransmission(b) => b.sample_f(wo, uc, u),
            Bxdf::Conductor(b) => b.sample_f(wo, u),
            Bxdf::Dielectric(b) => b.sample_f(wo, uc, u, mode),
            Bxdf::Dispersive(b) => b.sample_f(wo, uc, u, mode),
            Bxdf::ThinDielectric(b) => b.sample_f(wo, uc),
            Bxdf::CoatedDiffuse(b) => b.sample_f(wo, uc, u),
            Bxdf::CoatedConductor(b) => b.sample_f(wo, uc, u, mode),
            Bxdf::ScatteringCoat(b) => b.sample_f(wo, uc, u, mode),
            Bxdf::Hair(b) => b.sample_f(wo, uc, u, mode),
            Bxdf::NormalizedFresnel(b) => b.sample_f(wo, u, mode),
            Bxdf::Measured(b) => b.sample_f(wo, u, mode),
        }?;
        (bs.pdf > 0.0 && bs.pdf.is_finite() && bs.wi.z != 0.0).then_some(bs)
    }

    /// The solid-angle density with which `sample_f` returns `wi` for `wo`
    /// (its non-specular part: zero for delta lobes).
    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
        let _ = mode; // No model's sampling depends on the mode.
        match self {
            Bxdf::Diffuse(b) => b.pdf(wo, wi),
            Bxdf::DiffuseTransmission(b) => b.pdf(wo, wi),
            Bxdf::Conductor(b) => b.pdf(wo, wi),
            Bxdf::Dielectric(b) => b.pdf(wo, wi),
            Bxdf::Dispersive(b) => b.pdf(wo, wi),
            Bxdf::ThinDielectric(_) => 0.0,
            Bxdf::CoatedDiffuse(b) => b.pdf(wo, wi),
            Bxdf::CoatedConductor(b) => b.pdf(wo, wi),
            Bxdf::ScatteringCoat(b) => b.pdf(wo, wi),
            Bxdf::Hair(b) => b.pdf(wo, wi),
            Bxdf::NormalizedFresnel(b) => b.pdf(wo, wi),
            Bxdf::Measured(b) => b.pdf(wo, wi),
        }
    }

    /// pbrt-v4's `Regularize`: every microfacet interface made at least
    /// somewhat rough (`TrowbridgeReitz::regularized`), so that paths a
    /// smooth one would make impossible to sample (a light seen through a
    /// mirror from a diffuse surface) are found, at the price of a bias.
    /// Lambertian, thin dielectric, hair, measured and subsurface lobes
    /// stay as they are, as in pbrt-v4.
    pub fn regularize(&mut self) {
        match self {
            Bxdf::Conductor(b) => b.distrib = b.distrib.regularized(),
            Bxdf::Dielectric(b) => b.distrib = b.distrib.regularized(),
            Bxdf::Dispersive(b) => b.distrib = b.distrib.regularized(),
            Bxdf::CoatedDiffuse(b) => b.distrib = b.distrib.regularized(),
            Bxdf::CoatedConductor(b) => {
                b.coat.distrib = b.coat.distrib.regularized();
                b.base.distrib = b.base.distrib.regularized();
            }
            Bxdf::ScatteringCoat(b) => b.regularize(),
            Bxdf::Diffuse(_)
            | Bxdf::DiffuseTransmission(_)
            | Bxdf::ThinDielectric(_)
            | Bxdf::Hair(_)
            | Bxdf::NormalizedFresnel(_)
            | Bxdf::Measured(_) => {}
        }
    }

    pub fn flags(&self) -> BxdfFlags {
        match self {
            Bxdf::Diffuse(b) => b.flags(),
            Bxdf::DiffuseTransmission(b) => b.flags(),
            Bxdf::Conductor(b) => b.flags(),
            Bxdf::Dielectric(b) => b.flags(),
            Bxdf::Dispersive(b) => b.flags(),
            Bxdf::ThinDielectric(b) => b.flags(),
            Bxdf::CoatedDiffuse(b) => b.flags(),
            Bxdf::CoatedConductor(b) => b.flags(),
            Bxdf::ScatteringCoat(b) => b.flags(),
            Bxdf::Hair(b) => b.flags(),
            Bxdf::NormalizedFresnel(_) => BxdfFlags::DIFFUSE_REFLECTION,
            Bxdf::Measured(b) => b.flags(),
        }
    }
}

/// A BxDF placed in the world by a shading frame (pbrt-v4 `BSDF`): takes and
/// returns world-space directions, and rejects the degenerate samples an
/// integrator must not follow (zero `f` or `pdf`, `wi` in the tangent plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bsdf {
    pub bxdf: Bxdf,
    pub frame: Frame,
}

impl Bsdf {
    /// A BSDF around the shading normal `ns`, with the local x axis along
    /// `dpdus` (projected into the tangent plane; any tangent if degenerate).
    pub fn new(bxdf: Bxdf, ns: Vec3, dpdus: Vec3) -> Self {
        Bsdf {
            bxdf,
            frame: Frame::from_xz(dpdus, ns),
        }
    }

    pub fn flags(&self) -> BxdfFlags {
        self.bxdf.flags()
    }

    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Vec3 {
        let wo = self.frame.to_local(wo);
        if wo.z == 0.0 {
            return Vec3::ZERO;
        }
        self.bxdf.f(wo, self.frame.to_local(wi), mode)
    }

    /// Tells a dispersive BSDF the throughput of the path that meets it, so
    /// that it follows a colour channel the path still carries (no-op for
    /// every other BSDF).
    #[inline(always)]
    pub fn carry(&mut self, beta: Vec3) {
        if let Bxdf::Dispersive(d) = &mut self.bxdf {
            d.weights = beta;
        }
    }

    /// `f` and `pdf` of one pair of directions, taken to the local frame
    /// once (a light sample weighed by MIS needs both).
    pub fn f_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (Vec3, f32) {
        let wo = self.frame.to_local(wo);
        if wo.z == 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let wi = self.frame.to_local(wi);
        (self.bxdf.f(wo, wi, mode), self.bxdf.pdf(wo, wi, mode))
    }

    /// Like [`Bxdf::sample_f`], with `wo` and the returned `wi` in world space.
    /// Whether `sample_f` reads its `uc` (to choose between lobes).
    pub fn uses_lobe_choice(&self) -> bool {
        match self.bxdf {
            Bxdf::Diffuse(_) | Bxdf::Conductor(_) | Bxdf::NormalizedFresnel(_) | Bxdf::Measured(_) => false,
            // Both smooth: one specular reflection, no choice.
            Bxdf::CoatedConductor(b) => b.flags() != BxdfFlags::SPECULAR_REFLECTION,
            Bxdf::ScatteringCoat(_) => true,
            _ => true,
        }
    }

    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let wo = self.frame.to_local(wo);
        if wo.z == 0.0 || self.flags().is_empty() {
            return None;
        }
        let mut bs = self.bxdf.sample_f(wo, uc, u, mode)?;
        if bs.f == Vec3::ZERO || bs.pdf.is_nan() || bs.pdf <= 0.0 || bs.wi.z == 0.0 {
            return None;
        }
        bs.wi = self.frame.to_world(bs.wi);
        Some(bs)
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> f32 {
        let wo = self.frame.to_local(wo);
        if wo.z == 0.0 {
            return 0.0;
        }
        self.bxdf.pdf(wo, self.frame.to_local(wi), mode)
    }
}

// Spherical geometry in the local frame (pbrt-v4 3.8).

pub(crate) fn cos_theta(w: Vec3) -> f32 {
    w.z
}

pub(crate) fn abs_cos_theta(w: Vec3) -> f32 {
    w.z.abs()
}

/// True when `a` and `b` lie on the same side of the surface.
pub fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

/// Mirror of `w` about the normal: the specular reflection direction.
pub(crate) fn mirror(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

// Two-sided BxDFs (pbrt-v4's coated materials): the lower side scatters as
// the upper one, so each is written for directions above the surface and
// these mirror both directions through the surface when `wo` is below.

/// `upper(wo, wi)` with both directions mirrored above the surface; zero when
/// they lie on opposite sides (a reflection-only BxDF).
pub(crate) fn two_sided<T: Default>(wo: Vec3, wi: Vec3, upper: impl FnOnce(Vec3, Vec3) -> T) -> T {
    if wo.z * wi.z <= 0.0 {
        T::default()
    } else if wo.z < 0.0 {
        upper(-wo, -wi)
    } else {
        upper(wo, wi)
    }
}

/// A smooth coat's specular reflection of `wo` (above the surface), a delta
/// lobe chosen with probability `p`: Fresnel reflectance over the cosine.
pub(crate) fn coat_reflection(wo: Vec3, eta: f32, p: f32) -> BsdfSample {
    BsdfSample {
        f: Vec3::splat(fresnel::fr_dielectric(wo.z, eta) / wo.z),
        wi: mirror(wo),
        pdf: p,
        flags: BxdfFlags::SPECULAR_REFLECTION,
        eta: 1.0,
    }
}

/// `upper(wo)` with `wo` mirrored above the surface and its sample mirrored back.
pub(crate) fn two_sided_sample(wo: Vec3, upper: impl FnOnce(Vec3) -> Option<BsdfSample>) -> Option<BsdfSample> {
    let flip = wo.z < 0.0;
    let mut bs = upper(if flip { -wo } else { wo })?;
    if flip {
        bs.wi = -bs.wi;
    }
    Some(bs)
}
