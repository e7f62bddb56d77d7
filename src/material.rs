//! Materials: what a surface is made of, named as in pbrt-v4 (chapter 10,
//! `materials.h`). A material holds parameters, some of them textures; at a
//! shading point it becomes a [`Bsdf`] (a [`Bxdf`] in the local shading frame).
//! Integrators only ever see the `Bsdf`.
//!
//! Every surface but a dielectric is two-sided: its shading frame is turned
//! towards the side it is seen from. A dielectric's frame keeps the surface's
//! outward normal, because which side is inside decides its relative index.

use crate::bsdf::{
    Bsdf, Bxdf, ConductorBxdf, DielectricBxdf, Frame, HairBxdf, MeasuredBxdf, ScatteringCoatBxdf, TrowbridgeReitz,
};
use crate::bssrdf::{Bssrdf, BssrdfTable};
use crate::math::{Vec2, Vec3};
use crate::sampling::hash_unit;
use crate::texture::{Footprint, TexCoord, TexImage, Texture, WrapMode};
use glam::Affine3A;
use std::sync::Arc;

/// Microfacet roughness as pbrt-v4's materials take it: `uroughness` and
/// `vroughness` along the surface's u and v, remapped to the distribution's
/// alpha by pbrt-v4's `RoughnessToAlpha` when `remap` is set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roughness {
    pub u: f32,
    pub v: f32,
    pub remap: bool,
}

impl Roughness {
    pub const SMOOTH: Roughness = Roughness {
        u: 0.0,
        v: 0.0,
        remap: true,
    };

    pub fn isotropic(r: f32, remap: bool) -> Roughness {
        Roughness { u: r, v: r, remap }
    }

    pub fn distribution(&self) -> TrowbridgeReitz {
        TrowbridgeReitz::from_roughness(self.u, self.v, self.remap)
    }

    pub fn is_smooth(&self) -> bool {
        self.distribution().effectively_smooth()
    }
}

/// The scattering of a coat's medium (pbrt-v4's `albedo` and `g` of
/// `coateddiffuse` and `coatedconductor`), with the walk's limits.
#[derive(Clone, Debug, PartialEq)]
pub struct CoatMedium {
    /// Single-scattering albedo, kept within [0, 1] where it is looked up.
    pub albedo: Texture,
    /// Henyey-Greenstein asymmetry, in (-1, 1).
    pub g: f32,
    /// Scattering events a walk may take (pbrt-v4's `maxdepth`, 10).
    pub max_depth: u32,
    /// Walks per evaluation (pbrt-v4's `nsamples`, 1).
    pub samples: u32,
}

/// A material's roughness: a constant (decided once, as most scenes give
/// it), or float textures looked up at each shading point and then remapped
/// as a constant is (pbrt-v4's `FloatTexture` `uroughness` / `vroughness`).
#[derive(Clone, PartialEq)]
pub enum MaterialRoughness {
    Constant(Roughness),
    /// `u` and `v` are one `Arc` when both come from one texture (pbrt-v4's
    /// `roughness`): it is then looked up once per point.
    Textured {
        u: Arc<Texture>,
        v: Arc<Texture>,
        remap: bool,
    },
}

impl MaterialRoughness {
    fn needs_footprint(&self) -> bool {
        match self {
            MaterialRoughness::Constant(_) => false,
            MaterialRoughness::Textured { u, v, .. } => u.needs_footprint() || v.needs_footprint(),
        }
    }

    /// The microfacet distribution at a shading point. Where a texture is
    /// (near) zero it is effectively smooth, and the BxDF built from it is
    /// specular there, with specular flags, as pbrt-v4's is.
    #[inline]
    pub fn distribution(&self, tc: &TexCoord) -> TrowbridgeReitz {
        match self {
            MaterialRoughness::Constant(r) => r.distribution(),
            MaterialRoughness::Textured { u, v, remap } => {
                let ru = u.evaluate_scalar(tc);
                let rv = if Arc::ptr_eq(u, v) { ru } else { v.evaluate_scalar(tc) };
                TrowbridgeReitz::from_roughness(ru, rv, *remap)
            }
        }
    }

    /// True when the surface is smooth at every point. A texture may reach
    /// zero somewhere without being zero everywhere, so only a constant can
    /// say so.
    pub fn is_smooth(&self) -> bool {
        match self {
            MaterialRoughness::Constant(r) => r.is_smooth(),
            MaterialRoughness::Textured { .. } => false,
        }
    }
}

impl From<Roughness> for MaterialRoughness {
    fn from(r: Roughness) -> Self {
        MaterialRoughness::Constant(r)
    }
}

impl std::fmt::Debug for MaterialRoughness {
    // A constant prints as the bare `Roughness` it was before textures
    // were possible: scene fingerprints hash a material's Debug form, so the
    // checkpoints and photon maps of existing scenes stay valid.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MaterialRoughness::Constant(r) => r.fmt(f),
            MaterialRoughness::Textured { u, v, remap } => f
                .debug_struct("TexturedRoughness")
                .field("u", u)
                .field("v", v)
                .field("remap", remap)
                .finish(),
        }
    }
}

/// How a conductor's Fresnel reflectance is given.
#[derive(Clone, Debug, PartialEq)]
pub enum ConductorFresnel {
    /// Complex index of refraction eta + i k per RGB channel.
    Ior { eta: Vec3, k: Vec3 },
    /// Reflectance at normal incidence (pbrt-v4's `reflectance` parameter).
    Reflectance(Texture),
}

#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// No surface at all (pbrt-v4's `interface`): the shape only bounds
    /// participating media, and rays pass through it. Its BSDF has no lobes.
    Interface,
    /// Lambertian: f = reflectance / pi (pbrt-v4 `diffuse`).
    Diffuse { reflectance: Texture },
    /// Lambertian that also emits radiance `le` from both sides, uniformly. It is
    /// seen by camera and bounce rays only: shadow rays and photons come from
    /// `Light`s, so use it for analytic scenes (the white furnace), not as a lamp.
    Emissive { albedo: Vec3, le: Vec3 },
    /// A metal, smooth or rough (pbrt-v4 `conductor`). A perfect mirror is a
    /// smooth conductor of reflectance 1.
    Conductor {
        fresnel: ConductorFresnel,
        roughness: MaterialRoughness,
    },
    /// An interface to a medium of index `eta`, smooth or rough (pbrt-v4
    /// `dielectric`). Glass is a smooth dielectric.
    Dielectric { eta: f32, roughness: MaterialRoughness },
    /// A dielectric whose index `eta` differs by colour channel (dispersion:
    /// pbrt-v4's glass spectra), smooth or rough.
    Dispersive { eta: Vec3, roughness: MaterialRoughness },
    /// A thin slab of index `eta` (pbrt-v4 `thindielectric`).
    ThinDielectric { eta: f32 },
    /// A dielectric coat over a Lambertian base (pbrt-v4 `coateddiffuse`,
    /// the closed-form model of `bsdf::CoatedDiffuseBxdf`).
    CoatedDiffuse {
        reflectance: Texture,
        roughness: MaterialRoughness,
        eta: f32,
        thickness: f32,
        /// A coat medium that scatters (`bsdf::ScatteringCoatBxdf`); `None`
        /// for one that only absorbs (the closed form).
        medium: Option<CoatMedium>,
    },
    /// A dielectric coat of index `eta` over a metal (pbrt-v4
    /// `coatedconductor`, the random-walk model of
    /// `bsdf::CoatedConductorBxdf`); the metal's Fresnel terms are given as
    /// in air.
    CoatedConductor {
        interface_roughness: MaterialRoughness,
        eta: f32,
        thickness: f32,
        conductor: ConductorFresnel,
        conductor_roughness: MaterialRoughness,
        /// Scattering events of a walk inside the coat (pbrt-v4: 10).
        max_depth: u32,
        /// Walks per evaluation (pbrt-v4: 1).
        samples: u32,
        /// A coat medium that scatters (`bsdf::ScatteringCoatBxdf`); `None`
        /// for one that only absorbs.
        medium: Option<CoatMedium>,
    },
    /// Lambertian reflection and transmission (pbrt-v4 `diffusetransmission`).
    DiffuseTransmission {
        reflectance: Texture,
        transmittance: Texture,
    },
    /// A hair fibre (pbrt-v4 `hair`, `bsdf::HairBxdf`), meant for curves:
    /// the offset across the fibre is the surface's v (h = 2v - 1).
    /// `sigma_a` is its absorption per unit of the fibre's diameter (from
    /// pbrt-v4's `sigma_a`, `reflectance` or melanin concentrations, as the
    /// file gave it).
    Hair {
        sigma_a: Vec3,
        eta: f32,
        beta_m: f32,
        beta_n: f32,
        alpha: f32,
    },
    /// A measured BRDF of the RGL database (pbrt-v4's `measured`): glossy
    /// reflection read from a tensor file.
    Measured(MeasuredBxdf),
    /// One of two materials at each shading point, the second with
    /// probability `amount` (a float texture), as pbrt-v4's `mix`: the choice
    /// is a hash of the point and the direction it is seen from, so it is
    /// the same whenever the same point is seen the same way.
    Mix {
        materials: Box<[Material; 2]>,
        amount: Texture,
    },
    /// A material whose surface is displaced along its normal by a float
    /// texture, for shading only (pbrt-v4's `displacement`: a bump map).
    Bumped { base: Box<Material>, displacement: Texture },
    /// A material whose shading normal an image gives (pbrt-v4's
    /// `normalmap`): each texel's linear RGB, times 2 minus 1, is the normal
    /// in the frame of dp/du, n x dp/du and the normal n (dp/du x n when
    /// `mirrored`: the scene was reflected, which turns the frame's
    /// handedness), looked up at (u, 1 - v) with the image repeating.
    NormalMapped {
        base: Box<Material>,
        map: Arc<TexImage>,
        mirrored: bool,
    },
    /// A translucent object (pbrt-v4 `subsurface`): a dielectric surface
    /// over a medium, the light that enters leaving elsewhere by the
    /// object's BSSRDF (`crate::bssrdf`). Only the path tracer follows it
    /// there; other integrators see the dielectric surface.
    Subsurface(Box<Subsurface>),
}

/// A subsurface material's surface, medium and profile table.
#[derive(Clone, Debug, PartialEq)]
pub struct Subsurface {
    pub eta: f32,
    pub roughness: MaterialRoughness,
    pub scattering: SubsurfaceScattering,
    /// The profiles for the medium's g and the surface's eta.
    pub table: Arc<BssrdfTable>,
}

/// How a subsurface material's medium is given.
#[derive(Clone, Debug, PartialEq)]
pub enum SubsurfaceScattering {
    /// Absorption and scattering per unit length, scale applied (negative
    /// values read as zero).
    Coefficients { sigma_a: Texture, sigma_s: Texture },
    /// The total diffuse reflectance wanted at each point and the mean free
    /// path (scale applied): the albedo follows from the profile table
    /// (pbrt-v4's `reflectance` and `mfp`).
    Reflectance { reflectance: Texture, mfp: Texture },
}

/// What a material needs of a surface point to build its BSDF.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub p: Vec3,
    pub uv: Vec2,
    /// Unit geometric normal, as stored (outward for closed shapes).
    pub ng: Vec3,
    /// Unit shading normal, on the side of `ng`.
    pub ns: Vec3,
    /// The surface's dp/du, for anisotropic roughness.
    pub dpdu: Vec3,
    /// The differential geometry a bump map needs, when the material has
    /// one (the scene computes it only then).
    pub shading: Option<ShadingGeometry>,
    /// How (u, v) changes from pixel to pixel here, for image lookups and
    /// bump maps (zero unless the material needs it).
    pub footprint: Footprint,
}

/// pbrt-v4's shading geometry of a surface point: its shading normal (as
/// pbrt-v4 orients it: a mesh's vertex normals decide), the partial
/// derivatives of the point along the texture coordinates and those of the
/// normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingGeometry {
    pub n: Vec3,
    pub dpdu: Vec3,
    pub dpdv: Vec3,
    pub dndu: Vec3,
    pub dndv: Vec3,
}

/// A reflectance or transmittance looked up at `tc`, kept within [0, 1] as
/// pbrt-v4's diffuse, coated diffuse, diffuse transmission and conductor
/// materials keep theirs: a texture may leave that range (a scaled image, a
/// noise pattern below zero) where a surface cannot.
#[inline]
fn albedo(t: &Texture, tc: &TexCoord) -> Vec3 {
    t.evaluate(tc).clamp(Vec3::ZERO, Vec3::ONE)
}

/// The step along u or v of a bump map's finite differences without a
/// footprint (pbrt-v4's when its derivatives are zero).
const BUMP_STEP: f32 = 0.0005;

impl SurfacePoint {
    /// The point with its shading normal and dp/du perturbed by the
    /// displacement texture `d` as pbrt-v4's `BumpMap` does: the displaced
    /// surface p + d(u, v) n differentiated by finite steps in u and v, each
    /// half the footprint's extent along it (so the bumps a pixel resolves,
    /// read at the MIP level the footprint picks), `BUMP_STEP` without one.
    /// Without shading geometry the point is returned as it is.
    pub fn bumped(&self, d: &Texture) -> SurfacePoint {
        let Some(g) = self.shading else {
            return *self;
        };
        let f = self.footprint;
        let n = self.ng;
        let at = |uv: Vec2, p: Vec3| d.evaluate_scalar(&TexCoord { uv, p, n, footprint: f });
        let step = |d: f32| if d == 0.0 { BUMP_STEP } else { d };
        let du = step(0.5 * (f.dudx.abs() + f.dudy.abs()));
        let dv = step(0.5 * (f.dvdx.abs() + f.dvdy.abs()));
        let here = at(self.uv, self.p);
        let along_u = at(self.uv + Vec2::new(du, 0.0), self.p + g.dpdu * du);
        let along_v = at(self.uv + Vec2::new(0.0, dv), self.p + g.dpdv * dv);
        let dpdu = g.dpdu + g.n * ((along_u - here) / du) + g.dndu * here;
        let dpdv = g.dpdv + g.n * ((along_v - here) / dv) + g.dndv * here;
        self.shaded_by(dpdu, dpdv)
    }

    /// The point shaded by the surface whose derivatives are `dpdu` and
    /// `dpdv` (pbrt-v4's `SetShadingGeometry` after a bump or normal map):
    /// the shading normal their cross product, on the geometric normal's
    /// side. Where they degenerate the point is returned as it is.
    fn shaded_by(&self, dpdu: Vec3, dpdv: Vec3) -> SurfacePoint {
        let n = dpdu.cross(dpdv).normalize_or_zero();
        if n == Vec3::ZERO || !n.is_finite() || !dpdu.is_finite() {
            return *self;
        }
        SurfacePoint {
            ns: if n.dot(self.ng) < 0.0 { -n } else { n },
            dpdu,
            ..*self
        }
    }

    /// The point with the shading normal and dp/du of the normal map `map`,
    /// as pbrt-v4's `NormalMap` gives them: the map's normal in the frame of
    /// dp/du and the shading normal (left-handed if `mirrored`), dp/du made
    /// perpendicular to it (its length kept), dp/dv their cross product.
    /// Without shading geometry the point is returned as it is.
    pub fn normal_mapped(&self, map: &TexImage, mirrored: bool) -> SurfacePoint {
        let Some(g) = self.shading else {
            return *self;
        };
        let texel = map.bilerp(Vec2::new(self.uv.x, 1.0 - self.uv.y), WrapMode::Repeat);
        let local = (texel * 2.0 - Vec3::ONE).normalize_or_zero();
        if local == Vec3::ZERO {
            return *self;
        }
        let x = g.dpdu.normalize_or_zero();
        let y = if mirrored { x.cross(g.n) } else { g.n.cross(x) };
        let ns = x * local.x + y * local.y + g.n * local.z;
        let dpdu = (g.dpdu - ns * g.dpdu.dot(ns)).normalize_or_zero() * g.dpdu.length();
        let dpdv = ns.cross(dpdu).normalize_or_zero() * g.dpdv.length();
        self.shaded_by(dpdu, dpdv)
    }
}

impl Material {
    pub fn diffuse(r: f32, g: f32, b: f32) -> Self {
        Material::Diffuse {
            reflectance: Texture::from(Vec3::new(r, g, b)),
        }
    }

    /// A smooth conductor of the given reflectance; reflectance 1 is a
    /// perfect mirror.
    pub fn mirror(reflectance: Vec3) -> Self {
        Material::Conductor {
            fresnel: ConductorFresnel::Reflectance(Texture::from(reflectance)),
            roughness: Roughness::SMOOTH.into(),
        }
    }

    /// Smooth glass of index `eta`.
    pub fn glass(eta: f32) -> Self {
        Material::Dielectric {
            eta,
            roughness: Roughness::SMOOTH.into(),
        }
    }

    /// Emitted radiance, the same in every direction.
    pub fn le(&self) -> Vec3 {
        match self {
            Material::Emissive { le, .. } => *le,
            _ => Vec3::ZERO,
        }
    }

    /// True when the material can only scatter into specular directions
    /// (whatever the texture values), so photons never stay on it.
    pub fn is_specular(&self) -> bool {
        match self {
            Material::Conductor { roughness, .. }
            | Material::Dielectric { roughness, .. }
            | Material::Dispersive { roughness, .. } => roughness.is_smooth(),
            Material::ThinDielectric { .. } => true,
            Material::Subsurface(s) => s.roughness.is_smooth(),
            Material::CoatedConductor {
                interface_roughness,
                conductor_roughness,
                medium,
                ..
            } => interface_roughness.is_smooth() && conductor_roughness.is_smooth() && medium.is_none(),
            Material::Mix { materials, .. } => materials.iter().all(Material::is_specular),
            Material::Bumped { base, .. } | Material::NormalMapped { base, .. } => base.is_specular(),
            _ => false,
        }
    }

    /// True when light can pass through it by a specular or glossy path, or
    /// reflect off it so: light paths through such surfaces are caustics.
    pub fn is_caustic_caster(&self) -> bool {
        match self {
            Material::Mix { materials, .. } => materials.iter().any(Material::is_caustic_caster),
            Material::Bumped { base, .. } | Material::NormalMapped { base, .. } => base.is_caustic_caster(),
            _ => matches!(
                self,
                Material::Conductor { .. }
                    | Material::Dielectric { .. }
                    | Material::Dispersive { .. }
                    | Material::ThinDielectric { .. }
                    | Material::CoatedDiffuse { .. }
                    | Material::CoatedConductor { .. }
                    | Material::Subsurface(_)
                    | Material::Measured(_)
            ),
        }
    }

    /// The material as it shades a scene reflected by `r`: normal maps turn
    /// their frames' handedness (a bump map's normal follows from the
    /// reflected surface itself), and textures of space look up the point
    /// carried back ([`Texture::reflected`]).
    pub fn reflect(&mut self, r: &Affine3A) {
        let tex = |t: &mut Texture| *t = t.reflected(r);
        let rough = |m: &mut MaterialRoughness| {
            if let MaterialRoughness::Textured { u, v, .. } = m {
                // One texture for both stays one.
                let same = Arc::ptr_eq(u, v);
                *u = Arc::new(u.reflected(r));
                *v = if same { u.clone() } else { Arc::new(v.reflected(r)) };
            }
        };
        let fresnel = |f: &mut ConductorFresnel| {
            if let ConductorFresnel::Reflectance(t) = f {
                *t = t.reflected(r);
            }
        };
        match self {
            Material::NormalMapped { base, mirrored, .. } => {
                *mirrored = !*mirrored;
                base.reflect(r);
            }
            Material::Bumped { base, displacement } => {
                tex(displacement);
                base.reflect(r)
            }
            Material::Mix { materials, amount } => {
                tex(amount);
                materials.iter_mut().for_each(|m| m.reflect(r))
            }
            Material::Diffuse { reflectance } => tex(reflectance),
            Material::Conductor { fresnel: f, roughness } => {
                fresnel(f);
                rough(roughness)
            }
            Material::Dielectric { roughness, .. } | Material::Dispersive { roughness, .. } => rough(roughness),
            Material::CoatedDiffuse {
                reflectance,
                roughness,
                medium,
                ..
            } => {
                tex(reflectance);
                rough(roughness);
                if let Some(m) = medium {
                    tex(&mut m.albedo)
                }
            }
            Material::CoatedConductor {
                interface_roughness,
                conductor,
                conductor_roughness,
                medium,
                ..
            } => {
                rough(interface_roughness);
                fresnel(conductor);
                rough(conductor_roughness);
                if let Some(m) = medium {
                    tex(&mut m.albedo)
                }
            }
            Material::DiffuseTransmission {
                reflectance,
                transmittance,
            } => {
                tex(reflectance);
                tex(transmittance)
            }
            Material::Subsurface(s) => {
                rough(&mut s.roughness);
                match &mut s.scattering {
                    SubsurfaceScattering::Coefficients { sigma_a, sigma_s } => {
                        tex(sigma_a);
                        tex(sigma_s)
                    }
                    SubsurfaceScattering::Reflectance { reflectance, mfp } => {
                        tex(reflectance);
                        tex(mfp)
                    }
                }
            }
            Material::Interface
            | Material::Emissive { .. }
            | Material::ThinDielectric { .. }
            | Material::Hair { .. } => {}
            // Its azimuths follow the frame's turned handedness back.
            Material::Measured(m) => m.mirrored = !m.mirrored,
        }
    }

    /// Whether the material (or one it mixes) looks up an image texture or
    /// is bump mapped: its lookups then take the surface's footprint.
    pub fn needs_footprint(&self) -> bool {
        let fresnel = |f: &ConductorFresnel| matches!(f, ConductorFresnel::Reflectance(r) if r.needs_footprint());
        let medium_footprint = |m: &Option<CoatMedium>| m.as_ref().is_some_and(|m| m.albedo.needs_footprint());
        match self {
            Material::Diffuse { reflectance } => reflectance.needs_footprint(),
            Material::Emissive { .. }
            | Material::ThinDielectric { .. }
            | Material::Interface
            | Material::Hair { .. }
            | Material::Measured(_) => false,
            Material::Conductor { fresnel: f, roughness } => fresnel(f) || roughness.needs_footprint(),
            Material::Dielectric { roughness, .. } | Material::Dispersive { roughness, .. } => {
                roughness.needs_footprint()
            }
            Material::CoatedDiffuse {
                reflectance,
                roughness,
                medium,
                ..
            } => reflectance.needs_footprint() || roughness.needs_footprint() || medium_footprint(medium),
            Material::CoatedConductor {
                interface_roughness,
                conductor,
                conductor_roughness,
                medium,
                ..
            } => {
                interface_roughness.needs_footprint()
                    || fresnel(conductor)
                    || conductor_roughness.needs_footprint()
                    || medium_footprint(medium)
            }
            Material::DiffuseTransmission {
                reflectance,
                transmittance,
            } => reflectance.needs_footprint() || transmittance.needs_footprint(),
            Material::Mix { materials, amount } => {
                amount.needs_footprint() || materials.iter().any(Material::needs_footprint)
            }
            Material::Bumped { .. } => true,
            Material::NormalMapped { base, .. } => base.needs_footprint(),
            Material::Subsurface(s) => {
                s.roughness.needs_footprint()
                    || match &s.scattering {
                        SubsurfaceScattering::Coefficients { sigma_a, sigma_s } => {
                            sigma_a.needs_footprint() || sigma_s.needs_footprint()
                        }
                        SubsurfaceScattering::Reflectance { reflectance, mfp } => {
                            reflectance.needs_footprint() || mfp.needs_footprint()
                        }
                    }
            }
        }
    }

    /// Whether the material (or one it mixes) is bump or normal mapped: its
    /// BSDF then needs the surface point's `shading` geometry.
    pub fn is_bumped(&self) -> bool {
        match self {
            Material::Bumped { .. } | Material::NormalMapped { .. } => true,
            Material::Mix { materials, .. } => materials.iter().any(Material::is_bumped),
            _ => false,
        }
    }

    /// The material a `Mix` shows at a point seen from `wo` (itself otherwise).
    /// Out of line: inlined into `bsdf`, its hash was computed ahead of the
    /// match for every material (BENCHMARKS.md, "What media cost scenes
    /// without them").
    #[inline(never)]
    fn chosen(&self, tc: &TexCoord, wo: Vec3) -> &Material {
        let Material::Mix { materials, amount } = self else {
            return self;
        };
        let a = amount.evaluate_scalar(tc);
        let second = if a <= 0.0 || a.is_nan() {
            false
        } else if a >= 1.0 {
            true
        } else {
            mix_choice(tc.p, wo) <= a
        };
        materials[second as usize].chosen(tc, wo)
    }

    /// The BSDF at a surface point seen from direction `wo`.
    pub fn bsdf(&self, sp: &SurfacePoint, wo: Vec3) -> Bsdf {
        let tc = TexCoord {
            uv: sp.uv,
            p: sp.p,
            n: sp.ng,
            footprint: sp.footprint,
        };
        if let Material::Mix { .. } = self {
            return self.chosen(&tc, wo).bsdf(sp, wo);
        }
        if let Material::Bumped { base, displacement } = self {
            return base.bsdf(&sp.bumped(displacement), wo);
        }
        if let Material::NormalMapped { base, map, mirrored } = self {
            return base.bsdf(&sp.normal_mapped(map, *mirrored), wo);
        }
        let bxdf = match self {
            Material::Diffuse { reflectance } => Bxdf::diffuse(albedo(reflectance, &tc)),
            Material::Emissive { albedo, .. } => Bxdf::diffuse(*albedo),
            Material::Conductor { fresnel, roughness } => {
                let d = roughness.distribution(&tc);
                match fresnel {
                    ConductorFresnel::Ior { eta, k } => Bxdf::conductor(d, *eta, *k),
                    ConductorFresnel::Reflectance(r) => Bxdf::conductor_from_reflectance(d, albedo(r, &tc)),
                }
            }
            Material::Dielectric { eta, roughness } => {
                // The outward normal stays: it says which side is inside.
                return Bsdf::new(Bxdf::dielectric(roughness.distribution(&tc), *eta), sp.ns, sp.dpdu);
            }
            Material::Dispersive { eta, roughness } => {
                return Bsdf::new(Bxdf::dispersive(roughness.distribution(&tc), *eta), sp.ns, sp.dpdu);
            }
            Material::Subsurface(s) => {
                return Bsdf::new(Bxdf::dielectric(s.roughness.distribution(&tc), s.eta), sp.ns, sp.dpdu);
            }
            Material::ThinDielectric { eta } => Bxdf::thin_dielectric(*eta),
            Material::Measured(m) => Bxdf::Measured(*m),
            Material::CoatedDiffuse {
                reflectance,
                roughness,
                eta,
                thickness,
                medium,
            } => match medium {
                None => Bxdf::coated_diffuse(roughness.distribution(&tc), *eta, albedo(reflectance, &tc), *thickness),
                Some(m) => Bxdf::ScatteringCoat(ScatteringCoatBxdf::over_diffuse(
                    DielectricBxdf::new(roughness.distribution(&tc), *eta),
                    albedo(reflectance, &tc),
                    *thickness,
                    albedo(&m.albedo, &tc),
                    m.g,
                    m.max_depth,
                    m.samples,
                )),
            },
            Material::CoatedConductor {
                interface_roughness,
                eta,
                thickness,
                conductor,
                conductor_roughness,
                max_depth,
                samples,
                medium,
            } => {
                let coat = DielectricBxdf::new(interface_roughness.distribution(&tc), *eta);
                let d = conductor_roughness.distribution(&tc);
                let metal = match conductor {
                    ConductorFresnel::Ior { eta, k } => ConductorBxdf::new(d, *eta, *k),
                    ConductorFresnel::Reflectance(r) => ConductorBxdf::from_reflectance(d, albedo(r, &tc)),
                };
                match medium {
                    None => Bxdf::coated_conductor(coat, metal, *thickness, *max_depth, *samples),
                    Some(m) => Bxdf::ScatteringCoat(ScatteringCoatBxdf::over_conductor(
                        coat,
                        metal,
                        *thickness,
                        albedo(&m.albedo, &tc),
                        m.g,
                        *max_depth,
                        *samples,
                    )),
                }
            }
            Material::DiffuseTransmission {
                reflectance,
                transmittance,
            } => Bxdf::diffuse_transmission(albedo(reflectance, &tc), albedo(transmittance, &tc)),
            Material::Hair {
                sigma_a,
                eta,
                beta_m,
                beta_n,
                alpha,
            } => {
                // The fibre's frame: x along it, z facing `wo` across it
                // (the geometric normal: the hair's lobes leave on every
                // side, and only the turn about x between wo and wi counts).
                let h = -1.0 + 2.0 * sp.uv.y;
                let bxdf = Bxdf::Hair(HairBxdf::new(h, *eta, *sigma_a, *beta_m, *beta_n, *alpha));
                let ng = if sp.ng.dot(wo) < 0.0 { -sp.ng } else { sp.ng };
                return Bsdf::new(bxdf, ng, sp.dpdu);
            }
            // Resolved above; a black surface if not.
            Material::Mix { .. } | Material::Bumped { .. } | Material::NormalMapped { .. } => Bxdf::diffuse(Vec3::ZERO),
            // No lobes: integrators that do not pass through it see black.
            Material::Interface => Bxdf::diffuse(Vec3::ZERO),
        };
        let ns = if sp.ng.dot(wo) < 0.0 { -sp.ns } else { sp.ns };
        if matches!(
            self,
            Material::Diffuse { .. } | Material::Emissive { .. } | Material::DiffuseTransmission { .. }
        ) {
            // Lambertian lobes look the same from every azimuth: any tangent
            // will do, and one without a square root is cheaper.
            return Bsdf {
                bxdf,
                frame: Frame::from_z(ns),
            };
        }
        Bsdf::new(bxdf, ns, sp.dpdu)
    }

    /// The BSSRDF at a surface point seen from `wo`, for a subsurface
    /// material (the one a `Mix` shows there, bump and normal maps applied
    /// to the point); `None` for every other.
    pub fn bssrdf(&self, sp: &SurfacePoint, wo: Vec3) -> Option<Bssrdf<'_>> {
        let tc = TexCoord {
            uv: sp.uv,
            p: sp.p,
            n: sp.ng,
            footprint: sp.footprint,
        };
        match self {
            Material::Mix { .. } => self.chosen(&tc, wo).bssrdf(sp, wo),
            Material::Bumped { base, displacement } => base.bssrdf(&sp.bumped(displacement), wo),
            Material::NormalMapped { base, map, mirrored } => base.bssrdf(&sp.normal_mapped(map, *mirrored), wo),
            Material::Subsurface(s) => {
                let (sigma_a, sigma_s) = match &s.scattering {
                    SubsurfaceScattering::Coefficients { sigma_a, sigma_s } => (
                        sigma_a.evaluate(&tc).max(Vec3::ZERO),
                        sigma_s.evaluate(&tc).max(Vec3::ZERO),
                    ),
                    SubsurfaceScattering::Reflectance { reflectance, mfp } => s
                        .table
                        .coefficients_for(reflectance.evaluate(&tc), mfp.evaluate(&tc).max(Vec3::ZERO)),
                };
                Some(Bssrdf::new(sp.p, sp.ns, sigma_a, sigma_s, &s.table))
            }
            _ => None,
        }
    }

    /// Whether the material (or one it mixes or maps) scatters below its
    /// surface.
    pub fn has_subsurface(&self) -> bool {
        match self {
            Material::Subsurface(_) => true,
            Material::Mix { materials, .. } => materials.iter().any(Material::has_subsurface),
            Material::Bumped { base, .. } | Material::NormalMapped { base, .. } => base.has_subsurface(),
            _ => false,
        }
    }
}

/// A uniform number in [0, 1) from the bits of a point and a direction.
fn mix_choice(p: Vec3, wo: Vec3) -> f32 {
    hash_unit(&[p.x, p.y, p.z, wo.x, wo.y, wo.z])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{BxdfFlags, TransportMode};

    fn point(n: Vec3) -> SurfacePoint {
        SurfacePoint {
            p: Vec3::ZERO,
            uv: Vec2::ZERO,
            ng: n,
            ns: n,
            dpdu: Vec3::X,
            shading: None,
            footprint: Footprint::NONE,
        }
    }

    /// The shading geometry of the plane z = 0 parametrised by x and y.
    fn flat_geometry() -> ShadingGeometry {
        ShadingGeometry {
            n: Vec3::Z,
            dpdu: Vec3::X,
            dpdv: Vec3::Y,
            dndu: Vec3::ZERO,
            dndv: Vec3::ZERO,
        }
    }

    #[test]
    fn a_bump_maps_bumps_finer_than_the_footprint_do_not_tilt_the_normal() {
        // 16 x 16 texels of 0 and 0.01 over the unit square of a plane.
        let pixels = (0..256)
            .map(|i| Vec3::splat(0.01 * ((i % 16 + i / 16) % 2) as f32))
            .collect();
        let img = crate::texture::TexImage::from_pixels("fine", 16, 16, pixels);
        let opts = crate::texture::ImageOptions {
            encoding: crate::texture::Encoding::Linear,
            ..Default::default()
        };
        let d = Texture::Image(std::sync::Arc::new(crate::texture::ImageTexture::new(
            std::sync::Arc::new(img),
            &opts,
        )));
        let flat = flat_geometry();
        // Between two texels' centres.
        let sp = SurfacePoint {
            uv: Vec2::new(2.0 / 16.0, 2.5 / 16.0),
            shading: Some(flat),
            ..point(Vec3::Z)
        };
        // Without a footprint, pbrt-v4's step of 0.0005 sees the texels'
        // slope, 0.01 over a texel: a tilt of 9 degrees.
        let sharp = sp.bumped(&d).ns;
        assert!(
            (sharp.z.acos().to_degrees() - 0.16f32.atan().to_degrees()).abs() < 0.5,
            "{sharp}"
        );
        // A pixel four texels wide reads a level where they average out, over
        // a step of its size: no tilt.
        let wide = SurfacePoint {
            footprint: Footprint {
                dudx: 0.25,
                dvdy: 0.25,
                ..Footprint::NONE
            },
            ..sp
        };
        assert!((wide.bumped(&d).ns - Vec3::Z).length() < 1e-6, "{}", wide.bumped(&d).ns);
    }

    #[test]
    fn a_mix_shows_its_second_material_with_probability_amount_the_same_each_time() {
        let grey = |v: f32| Material::diffuse(v, v, v);
        let mix = |amount: f32| Material::Mix {
            materials: Box::new([grey(0.2), grey(0.8)]),
            amount: Texture::from(Vec3::splat(amount)),
        };
        let albedo = |m: &Material, p: Vec3, wo: Vec3| {
            let b = m.bsdf(&point_at(p, Vec3::Z), wo);
            b.f(wo, Vec3::Z, TransportMode::Radiance).x * std::f32::consts::PI
        };
        let mut rng = crate::sampling::Rng::new(7, 0);
        for amount in [0.0, 0.3, 0.75, 1.0] {
            let m = mix(amount);
            let n = 20000;
            let mut second = 0;
            for _ in 0..n {
                let p = Vec3::new(rng.next_f32(), rng.next_f32(), 0.0);
                let wo = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 1.0).normalize();
                let a = albedo(&m, p, wo);
                assert_eq!(a, albedo(&m, p, wo), "the same point and direction choose the same");
                assert!((a - 0.2).abs() < 1e-5 || (a - 0.8).abs() < 1e-5, "{a}");
                second += (a > 0.5) as u32;
            }
            // Four standard deviations of a binomial count.
            let expected = amount * n as f32;
            let sd = (n as f32 * amount * (1.0 - amount)).sqrt();
            assert!(
                (second as f32 - expected).abs() <= 4.0 * sd + 0.5,
                "amount {amount}: {second} of {n}"
            );
        }
        assert!(!mix(0.5).is_specular() && !mix(0.5).is_caustic_caster());
        let glass_or_mirror = Material::Mix {
            materials: Box::new([Material::glass(1.5), Material::mirror(Vec3::ONE)]),
            amount: Texture::from(Vec3::splat(0.5)),
        };
        assert!(glass_or_mirror.is_specular() && glass_or_mirror.is_caustic_caster());
    }

    /// A displacement rising along u: 0 at u = 0.25, 1 at u = 0.75 (two
    /// texels of a 2 x 1 image, bilinear), constant along v.
    fn ramp(scale: f32) -> Texture {
        let img = crate::texture::TexImage::from_pixels("ramp", 2, 1, vec![Vec3::ZERO, Vec3::ONE]);
        let opts = crate::texture::ImageOptions {
            scale,
            ..Default::default()
        };
        Texture::Image(std::sync::Arc::new(crate::texture::ImageTexture::new(
            std::sync::Arc::new(img),
            &opts,
        )))
    }

    #[test]
    fn a_bump_map_tilts_the_shading_normal_as_the_displaced_surface_does() {
        let flat = flat_geometry();
        let sp = SurfacePoint {
            uv: Vec2::new(0.5, 0.3),
            shading: Some(flat),
            ..point(Vec3::Z)
        };
        // p + d n with d = s (2u - 0.5): dp/du = x + 2 s z, dp/dv = y, so the
        // normal is (-2 s, 0, 1) normalised, whatever the step.
        for s in [1.0, 0.1, 0.45] {
            let b = sp.bumped(&ramp(s));
            let want = Vec3::new(-2.0 * s, 0.0, 1.0).normalize();
            assert!((b.ns - want).length() < 1e-4, "scale {s}: {} against {want}", b.ns);
            assert!(b.dpdu.dot(b.ns).abs() < 1e-4 && b.ng == Vec3::Z);
        }
        // A curved surface moves by d along normals that turn with u (dn/du
        // = x, a unit sphere's): dp/du = x + d x + 2 z, with d = 0.5 here.
        let curved = SurfacePoint {
            shading: Some(ShadingGeometry { dndu: Vec3::X, ..flat }),
            ..sp
        };
        let b = curved.bumped(&ramp(1.0));
        assert!((b.ns - Vec3::new(-0.8, 0.0, 0.6)).length() < 1e-4, "{}", b.ns);
        // The BSDF is built in the bumped frame; the bump map is off without
        // shading geometry, and a constant displacement of a plane changes
        // nothing.
        let m = Material::Bumped {
            base: Box::new(Material::diffuse(0.5, 0.5, 0.5)),
            displacement: ramp(1.0),
        };
        assert!(m.is_bumped());
        let frame = m.bsdf(&sp, Vec3::Z).frame;
        assert!((frame.z - Vec3::new(-2.0, 0.0, 1.0).normalize()).length() < 1e-4);
        assert_eq!(m.bsdf(&SurfacePoint { shading: None, ..sp }, Vec3::Z).frame.z, Vec3::Z);
        assert_eq!(sp.bumped(&Texture::from(Vec3::splat(0.2))).ns, Vec3::Z);
        // Seen from below, the normal flips with the geometric one.
        let below = m.bsdf(&sp, -Vec3::Z).frame.z;
        assert!((below + Vec3::new(-2.0, 0.0, 1.0).normalize()).length() < 1e-4);
    }

    #[test]
    fn a_normal_map_gives_the_shading_normal_in_the_frame_of_dpdu_and_the_normal() {
        // A surface whose dp/du runs along y and dp/dv along -x (normal z):
        // the map's x is the world's y, its y the world's -x.
        let g = ShadingGeometry {
            n: Vec3::Z,
            dpdu: Vec3::Y * 2.0,
            dpdv: -Vec3::X * 3.0,
            dndu: Vec3::ZERO,
            dndv: Vec3::ZERO,
        };
        let sp = SurfacePoint {
            uv: Vec2::new(0.25, 0.75),
            shading: Some(g),
            ..point(Vec3::Z)
        };
        // Left texel (0.6, 0.5, 0.9): the local normal (0.2, 0, 0.8); right
        // texel (0.5, 0.7, 0.9): (0, 0.4, 0.8). The image repeats.
        let map = crate::texture::TexImage::from_pixels(
            "normals",
            2,
            1,
            vec![Vec3::new(0.6, 0.5, 0.9), Vec3::new(0.5, 0.7, 0.9)],
        );
        let left = sp.normal_mapped(&map, false);
        let want = Vec3::new(0.0, 0.2, 0.8).normalize();
        assert!((left.ns - want).length() < 1e-5, "{} against {want}", left.ns);
        // dp/du keeps its length, perpendicular to the new normal.
        assert!(left.dpdu.dot(left.ns).abs() < 1e-5 && (left.dpdu.length() - 2.0).abs() < 1e-5);
        let right = SurfacePoint {
            uv: Vec2::new(1.75, -0.25),
            ..sp
        }
        .normal_mapped(&map, false);
        let want = Vec3::new(-0.4, 0.0, 0.8).normalize();
        assert!((right.ns - want).length() < 1e-5, "{} against {want}", right.ns);
        // In a reflected scene the map's y is dp/du x n: here +x.
        let mirrored = SurfacePoint {
            uv: Vec2::new(1.75, -0.25),
            ..sp
        }
        .normal_mapped(&map, true);
        let want = Vec3::new(0.4, 0.0, 0.8).normalize();
        assert!((mirrored.ns - want).length() < 1e-5, "{} against {want}", mirrored.ns);
        // A flat map changes nothing; nor does any map without shading geometry.
        let flat = crate::texture::TexImage::from_pixels("flat", 1, 1, vec![Vec3::new(0.5, 0.5, 1.0)]);
        assert!((sp.normal_mapped(&flat, false).ns - Vec3::Z).length() < 1e-6);
        assert_eq!(
            SurfacePoint { shading: None, ..sp }.normal_mapped(&map, false).ns,
            Vec3::Z
        );
        let m = Material::NormalMapped {
            base: Box::new(Material::diffuse(0.5, 0.5, 0.5)),
            map: std::sync::Arc::new(map),
            mirrored: false,
        };
        assert!(m.is_bumped());
        assert!((m.bsdf(&sp, Vec3::Z).frame.z - Vec3::new(0.0, 0.2, 0.8).normalize()).length() < 1e-5);
    }

    fn point_at(p: Vec3, n: Vec3) -> SurfacePoint {
        SurfacePoint { p, ..point(n) }
    }

    #[test]
    fn two_sided_surfaces_turn_to_the_viewer_and_glass_does_not() {
        let wo = Vec3::new(0.3, 0.0, -1.0).normalize();
        let sp = point(Vec3::Z);
        let d = Material::diffuse(0.5, 0.5, 0.5).bsdf(&sp, wo);
        assert_eq!(d.frame.z, -Vec3::Z);
        let wi = Vec3::new(0.0, 0.2, -1.0).normalize();
        assert!((d.f(wo, wi, TransportMode::Radiance).x - 0.5 / std::f32::consts::PI).abs() < 1e-6);
        let g = Material::glass(1.5).bsdf(&sp, wo);
        assert_eq!(g.frame.z, Vec3::Z);
    }

    #[test]
    fn a_mirror_reflects_about_the_normal_with_full_weight() {
        let m = Material::mirror(Vec3::ONE);
        assert!(m.is_specular());
        let wo = Vec3::new(1.0, 1.0, 0.0).normalize();
        let b = m.bsdf(&point(Vec3::Y), wo);
        let s = b
            .sample_f(wo, 0.5, Vec2::new(0.3, 0.7), TransportMode::Radiance)
            .unwrap();
        assert!((s.wi - Vec3::new(-1.0, 1.0, 0.0).normalize()).length() < 1e-5);
        let w = s.f * (s.wi.dot(Vec3::Y).abs() / s.pdf);
        assert!((w - Vec3::ONE).abs().max_element() < 1e-3, "{w:?}");
    }

    /// A conductor of reflectance 1 whose roughness is a checkerboard of
    /// `even` and `odd` over (u, v), four squares per unit of u.
    fn checkered_conductor(even: f32, odd: f32) -> Material {
        let c = |r: f32| Arc::new(Texture::from(Vec3::splat(r)));
        let check = Arc::new(Texture::checkerboard(c(even), c(odd), 4.0, 1.0));
        Material::Conductor {
            fresnel: ConductorFresnel::Reflectance(Texture::from(Vec3::ONE)),
            roughness: MaterialRoughness::Textured {
                u: check.clone(),
                v: check,
                remap: true,
            },
        }
    }

    #[test]
    fn a_textured_roughness_is_looked_up_per_point_and_never_promised_smooth() {
        let at = |u: f32| SurfacePoint {
            uv: Vec2::new(u, 0.5),
            ..point(Vec3::Z)
        };
        let (even, odd) = (at(0.1), at(0.3));
        let wo = Vec3::Z;
        let off = Vec3::new(70f32.to_radians().sin(), 0.0, 70f32.to_radians().cos());
        let mode = TransportMode::Radiance;

        let m = checkered_conductor(0.3, 0.01);
        assert!(!m.is_specular());
        let (rough, less) = (m.bsdf(&even, wo), m.bsdf(&odd, wo));
        assert!(rough.flags().is_glossy() && less.flags().is_glossy());
        // alpha 0.55 against 0.1: 70 degrees off the mirror direction (half
        // vectors 35 degrees off the normal) the rougher square reflects
        // about ten times as much.
        let (fr, fl) = (rough.f(wo, off, mode).x, less.f(wo, off, mode).x);
        assert!(fr > 5.0 * fl && fl > 0.0, "{fr} {fl}");
        // pbrt-v4 remaps: roughness 0.3 is alpha sqrt(0.3), as a constant is.
        let constant = Material::Conductor {
            fresnel: ConductorFresnel::Reflectance(Texture::from(Vec3::ONE)),
            roughness: Roughness::isotropic(0.3, true).into(),
        };
        assert_eq!(constant.bsdf(&even, wo), rough);

        // Where the texture is zero the surface is a mirror, with the flags
        // of one; elsewhere it stays rough.
        let m = checkered_conductor(0.3, 0.0);
        assert!(!m.is_specular());
        let mirror = m.bsdf(&odd, wo);
        assert_eq!(mirror.flags(), BxdfFlags::SPECULAR_REFLECTION);
        assert_eq!(mirror.f(wo, off, mode), Vec3::ZERO);
        let s = mirror.sample_f(wo, 0.5, Vec2::new(0.3, 0.7), mode).unwrap();
        assert!(s.is_specular() && (s.wi - Vec3::Z).length() < 1e-6, "{s:?}");
        assert_eq!(m.bsdf(&even, wo).flags(), BxdfFlags::GLOSSY_REFLECTION);

        // Even a texture that is zero everywhere is not promised smooth.
        let zero = MaterialRoughness::Textured {
            u: Arc::new(Texture::from(Vec3::ZERO)),
            v: Arc::new(Texture::from(Vec3::ZERO)),
            remap: true,
        };
        assert!(!zero.is_smooth());
        assert!(MaterialRoughness::from(Roughness::SMOOTH).is_smooth());
    }

    #[test]
    fn a_constant_roughness_prints_as_before_and_a_texture_prints_its_values() {
        // Scene fingerprints hash this form.
        let r = Roughness::isotropic(0.2, true);
        assert_eq!(format!("{:?}", MaterialRoughness::from(r)), format!("{r:?}"));
        let a = format!("{:?}", checkered_conductor(0.3, 0.01));
        let b = format!("{:?}", checkered_conductor(0.3, 0.02));
        assert!(a.contains("TexturedRoughness") && a != b, "{a}");
    }

    #[test]
    fn glass_reflects_and_refracts_all_it_receives() {
        let sp = point(Vec3::Z);
        let g = Material::glass(1.5);
        for theta in [0.0f32, 0.6, 1.3] {
            let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
            let b = g.bsdf(&sp, wo);
            let n = 4000;
            let mut sum = 0.0;
            for i in 0..n {
                let uc = (i as f32 + 0.5) / n as f32;
                let s = b
                    .sample_f(wo, uc, Vec2::new(0.5, 0.5), TransportMode::Importance)
                    .unwrap();
                sum += s.f.x * s.wi.z.abs() / s.pdf;
            }
            assert!((sum / n as f32 - 1.0).abs() < 1e-3, "theta {theta}: {}", sum / n as f32);
        }
    }
}
