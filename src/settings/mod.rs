//! Render settings: what they are, where each value came from, and the one
//! resolver that decides between them.
//!
//! Every setting is declared once in [`table::SETTINGS`]. A value can come from
//! four places, in this order of precedence: the command line (or any caller
//! that plays its part), the scene file's `[settings]` table, the preset the
//! scene names (a built-in scene's settings), and the default. [`resolve`]
//! takes one [`Layer`] for each, checks every value once, and returns the
//! [`RenderSettings`] the integrators read. An error names the setting, the
//! value and where it came from ([`Origin`]), so a value from a scene file is
//! reported at its line rather than as a flag the user never typed.
//!
//! The module is plain data: it imports nothing from the scene, the
//! integrators or the photon map, which all import it.

pub mod table;

use crate::film::Filter;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;
pub use table::SETTINGS;

/// Which light transport algorithm renders the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Direct light only (shadow rays to the lights).
    #[default]
    Direct,
    /// Direct light by shadow rays, indirect light from a photon map.
    Photon,
    /// Reference path tracer (unbiased, slow to converge).
    Path,
    /// Stochastic progressive photon mapping (consistent; refines over passes).
    Sppm,
    /// Bidirectional path tracer (unbiased; finds light through glossy
    /// reflections of small lights that the path tracer rarely does).
    Bdpt,
}

impl IntegratorKind {
    pub const ALL: [IntegratorKind; 5] = [Self::Direct, Self::Photon, Self::Path, Self::Sppm, Self::Bdpt];

    pub fn name(self) -> &'static str {
        match self {
            Self::Direct => "direct",
            Self::Photon => "photon",
            Self::Path => "path",
            Self::Sppm => "sppm",
            Self::Bdpt => "bdpt",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

impl std::fmt::Display for IntegratorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which photons a gather may use, by the cosine between the photon's stored
/// surface normal and the shaded point's normal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GatherFilter {
    /// Any photon that arrived on the shaded side.
    #[default]
    None,
    /// Photons whose surface normal is within ~26 degrees (cosine > 0.9): no leaks round corners.
    Normal,
    /// The original report's rule (cosine > 0.25): surfaces meeting at an obtuse angle share photons.
    Report,
}

impl GatherFilter {
    pub const ALL: [GatherFilter; 3] = [Self::None, Self::Normal, Self::Report];

    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Normal => "normal",
            Self::Report => "report",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// How the path tracer finds the light arriving at a non-specular vertex
/// (Veach 1997, chapter 9).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSampling {
    /// Shadow rays and BSDF-sampled rays, weighted by the power heuristic.
    #[default]
    Mis,
    /// Shadow rays only (lights hit by BSDF-sampled rays count nothing).
    Light,
    /// BSDF-sampled rays only (no shadow rays).
    Bsdf,
}

impl LightSampling {
    pub const ALL: [LightSampling; 3] = [Self::Mis, Self::Light, Self::Bsdf];

    pub fn name(self) -> &'static str {
        match self {
            Self::Mis => "mis",
            Self::Light => "light",
            Self::Bsdf => "bsdf",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// Where a camera sample's random numbers come from (`sampling::Sampler`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol points, one dimension (pair) per request.
    #[default]
    Sobol,
    /// A PCG32 stream per sample; the pixel position stratified on a grid.
    Independent,
    /// Owen-scrambled Sobol points of one sequence over all pixels in Z
    /// order (pbrt-v4's `zsobol`): neighbouring pixels stratified together.
    ZSobol,
}

impl SamplerKind {
    pub const ALL: [SamplerKind; 3] = [Self::Sobol, Self::Independent, Self::ZSobol];

    pub fn name(self) -> &'static str {
        match self {
            Self::Sobol => "sobol",
            Self::Independent => "independent",
            Self::ZSobol => "zsobol",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// How the photons around a shading point are gathered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gather {
    /// Gather radius; with `k`, the largest radius searched (may be infinite).
    pub radius: f32,
    /// Use the k nearest photons (radius = distance to the k-th).
    pub k: Option<u32>,
    /// Weight photons with Jensen's cone filter.
    pub cone: bool,
    pub filter: GatherFilter,
}

/// Photon tracing and gathering settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonSettings {
    /// Photons emitted (0: no photon map, direct light only).
    pub photons: u64,
    /// Surface hits traced per photon (the first is the direct hit).
    pub max_bounces: u32,
    /// Store first hits (direct light) too; final gathering and
    /// `shadow_samples = 0` store them whatever this says.
    pub store_first_hit: bool,
    /// Russian roulette on the albedo; off, photons keep going (power scaled by
    /// the albedo) until `max_bounces` (for tests of power conservation).
    pub roulette: bool,
    pub gather: Gather,
    /// Final-gather rays per shading point (0: read the map at the visible point).
    pub final_gather: u32,
    /// Estimate irradiance once at every few photons and look the nearest up
    /// instead of gathering at each sample.
    pub precompute_irradiance: bool,
    /// Photons wanted in the caustic map (light -> mirror/glass+ -> diffuse);
    /// 0: no caustic map, so such paths are not rendered at all.
    pub caustic_photons: u64,
    /// Gather radius of the caustic map.
    pub caustic_radius: f32,
}

impl Default for PhotonSettings {
    fn default() -> Self {
        RenderSettings::default().photon
    }
}

/// Bytes of one stored photon (the photon map checks its record against this).
pub const PHOTON_RECORD_BYTES: u64 = 32;
/// Photons the caustic pass may store beyond those asked for (one round).
pub const CAUSTIC_ROUND: u64 = 16 * 4096;
/// Largest photon map we ever try to allocate, whatever the machine has.
pub const MAX_MAP_BYTES: u64 = 64 << 30;

impl PhotonSettings {
    /// Bytes of the map if every photon were stored at every hit.
    pub fn worst_case_bytes(&self) -> u128 {
        self.photons as u128 * self.max_bounces as u128 * PHOTON_RECORD_BYTES as u128
    }
}

/// Files that carry work between runs: photon maps and checkpoints of
/// progressive renders. All off by default. They are named by the caller
/// (the command line), never by a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StateFiles {
    /// Write the traced photon map here.
    pub save_photons: Option<PathBuf>,
    /// Read the photon map from here instead of tracing it.
    pub load_photons: Option<PathBuf>,
    /// Write a progressive render's state here between passes, at most every
    /// `checkpoint_every`, and when interrupted.
    pub checkpoint: Option<PathBuf>,
    pub checkpoint_every: Duration,
    /// Continue the progressive render saved here.
    pub resume: Option<PathBuf>,
    /// Stop as if interrupted after this many passes of this run (for tests).
    pub stop_after_passes: Option<u32>,
}

/// Everything an integrator needs to know besides the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Camera samples per pixel per axis (ssaa^2 samples per pixel).
    pub ssaa: u32,
    /// Shadow rays per light per shading point.
    pub shadow_samples: u32,
    pub filter: Filter,
    pub seed: u64,
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
    pub integrator: IntegratorKind,
    /// Render only this rectangle of the frame (`None`: the whole frame).
    pub crop: Option<crate::film::PixelRect>,
    /// Samples per pixel of the path tracer (it ignores `ssaa`).
    pub spp: u32,
    /// Path tracer: most bounces (1 = direct light only); `None`: unlimited.
    pub max_depth: Option<u32>,
    /// Path tracer: how direct light is sampled.
    pub light_sampling: LightSampling,
    /// How shadow rays choose their light (`SceneDesc::light_sampler`).
    pub light_sampler: crate::light::LightSamplerKind,
    /// Path tracers: microfacet surfaces made glossy after a path's first
    /// non-specular bounce (pbrt-v4's `regularize`).
    pub regularize: bool,
    /// Path tracer: caustic photons traced to aim diffuse bounces
    /// (`photon::guide`); 0: bounces follow the BSDF alone.
    pub guide_photons: u64,
    /// Where camera samples' random numbers come from.
    pub sampler: SamplerKind,
    /// Largest RGB component a camera sample keeps (the sample is scaled
    /// down to it); `None`: no clamp. SPPM ignores it, as pbrt-v4 does.
    pub max_component: Option<f32>,
    /// The colour temperature (kelvin) the film balances to white; `None`:
    /// the film records colours as they are.
    pub white_balance: Option<f32>,
    /// The film's sensor: `sensor::OBSERVER` or one of `sensor::SENSORS`.
    pub sensor: &'static str,
    /// Photon mapping settings.
    pub photon: PhotonSettings,
    /// Files that carry work between runs.
    pub files: StateFiles,
    /// SPPM: camera and photon passes.
    pub passes: u32,
    /// SPPM: fraction of each pass's photons kept as the radius shrinks.
    pub alpha: f32,
}

impl RenderSettings {
    /// Camera samples per pixel of the chosen integrator.
    pub fn samples_per_pixel(&self) -> u32 {
        match self.integrator {
            IntegratorKind::Path | IntegratorKind::Bdpt => self.spp,
            IntegratorKind::Sppm => self.passes,
            _ => self.ssaa * self.ssaa,
        }
    }

    /// Checks settings made in code (not through [`resolve`]) with the same
    /// rules; errors name the caller as the origin of the value.
    pub fn validate(&self) -> Result<(), SettingError> {
        let mut layer = Layer::default();
        for (name, value) in self.values() {
            let spec = spec(name).expect("every field has a table entry");
            // Derived defaults (an unbounded radius with gather_k) are values
            // no user can type but the resolver itself produces.
            if !(name == "gather_radius" && self.photon.gather.k.is_some() && value == Value::Real(f32::INFINITY)) {
                spec.check(&value)
                    .map_err(|m| SettingError::new(name, &value, Origin::Caller, m))?;
            }
            layer.values.insert(name, (value, Origin::Caller));
        }
        check_combinations(self, &|name| {
            layer.values.get(name).map_or(Origin::Default, |(_, o)| o.clone())
        })
    }

    /// The settings as (name, value) pairs of the table, for validation.
    fn values(&self) -> Vec<(&'static str, Value)> {
        let p = &self.photon;
        let mut v = vec![
            ("integrator", Value::Name(self.integrator.name())),
            ("ssaa", Value::Int(self.ssaa as u64)),
            ("shadow_samples", Value::Int(self.shadow_samples as u64)),
            ("filter", Value::Name(self.filter.name())),
            ("spp", Value::Int(self.spp as u64)),
            ("light_sampling", Value::Name(self.light_sampling.name())),
            ("sampler", Value::Name(self.sampler.name())),
            ("photons", Value::Int(p.photons)),
            ("max_bounces", Value::Int(p.max_bounces as u64)),
            ("store_first_hit", Value::Bool(p.store_first_hit)),
            ("gather_radius", Value::Real(p.gather.radius)),
            ("cone_filter", Value::Bool(p.gather.cone)),
            ("gather_filter", Value::Name(p.gather.filter.name())),
            ("final_gather", Value::Int(p.final_gather as u64)),
            ("precompute_irradiance", Value::Bool(p.precompute_irradiance)),
            ("caustic_photons", Value::Int(p.caustic_photons)),
            ("caustic_radius", Value::Real(p.caustic_radius)),
            ("passes", Value::Int(self.passes as u64)),
            ("alpha", Value::Real(self.alpha)),
            ("seed", Value::Int(self.seed)),
        ];
        if let Some(d) = self.max_depth {
            v.push(("max_depth", Value::Int(d as u64)));
        }
        if let Some(k) = p.gather.k {
            v.push(("gather_k", Value::Int(k as u64)));
        }
        if let Some(m) = self.max_component {
            v.push(("max_component", Value::Real(m)));
        }
        // Absent for power, so older checkpoints still match.
        if self.light_sampler != crate::light::LightSamplerKind::Power {
            v.push(("light_sampler", Value::Name(self.light_sampler.name())));
        }
        // Absent when off, so older checkpoints still match.
        if self.regularize {
            v.push(("regularize", Value::Bool(true)));
        }
        // Absent when off, so older checkpoints still match.
        if self.guide_photons > 0 {
            v.push(("guide_photons", Value::Int(self.guide_photons)));
        }
        if let Some(k) = self.white_balance {
            v.push(("white_balance", Value::Real(k)));
        }
        // Absent for the observer, so older checkpoints still match.
        if self.sensor != crate::sensor::OBSERVER {
            v.push(("sensor", Value::Name(self.sensor)));
        }
        if let Some(t) = self.threads {
            v.push(("threads", Value::Int(t as u64)));
        }
        v
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        from_values(&|_| None)
    }
}

/// The kind of value a setting takes, with its valid range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// A whole number in `min..=max`.
    Count { min: u64, max: u64 },
    /// A number above `min` (or at it, when inclusive) and at most `max`.
    Real { min: f32, min_inclusive: bool, max: f32 },
    /// true or false.
    Flag,
    /// One of the names.
    Choice(&'static [&'static str]),
}

/// A setting's default, as the table states it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DefaultValue {
    Int(u64),
    Real(f32),
    Bool(bool),
    Name(&'static str),
    /// No value: the setting is off; the text says what that means.
    Unset(&'static str),
    /// Computed from other settings, as the text says.
    Derived(&'static str),
}

impl DefaultValue {
    /// The default as `--help` and the docs show it.
    pub fn describe(&self) -> String {
        match self {
            DefaultValue::Int(v) => v.to_string(),
            DefaultValue::Real(v) => v.to_string(),
            DefaultValue::Bool(v) => v.to_string(),
            DefaultValue::Name(v) => v.to_string(),
            DefaultValue::Unset(t) | DefaultValue::Derived(t) => t.to_string(),
        }
    }

    fn value(&self) -> Option<Value> {
        match *self {
            DefaultValue::Int(v) => Some(Value::Int(v)),
            DefaultValue::Real(v) => Some(Value::Real(v)),
            DefaultValue::Bool(v) => Some(Value::Bool(v)),
            DefaultValue::Name(v) => Some(Value::Name(v)),
            DefaultValue::Unset(_) | DefaultValue::Derived(_) => None,
        }
    }
}

/// One setting's declaration.
#[derive(Clone, Copy, Debug)]
pub struct Spec {
    /// The scene file's key; the command line's flag is `--` and the name with dashes.
    pub name: &'static str,
    pub kind: Kind,
    pub default: DefaultValue,
    /// One line for `--help` and the docs.
    pub doc: &'static str,
    /// Whether a scene file may set it (the thread count belongs to the machine, not the scene).
    pub in_scene_file: bool,
    /// Integrators that read it; given on the command line for another, it is refused.
    pub only_for: &'static [&'static str],
}

impl Spec {
    /// The command-line flag, `--max-bounces` for `max_bounces`.
    pub fn flag(&self) -> String {
        format!("--{}", self.name.replace('_', "-"))
    }

    /// Parses a value as typed on the command line.
    pub fn parse(&self, text: &str) -> Result<Value, String> {
        let t = text.trim();
        let value = match self.kind {
            Kind::Count { .. } => Value::Int(t.parse().map_err(|_| "expected a whole number >= 0".to_string())?),
            Kind::Real { .. } => Value::Real(t.parse().map_err(|_| "expected a number".to_string())?),
            Kind::Flag => match t {
                "true" | "on" | "yes" | "1" => Value::Bool(true),
                "false" | "off" | "no" | "0" => Value::Bool(false),
                _ => return Err("expected true or false".into()),
            },
            Kind::Choice(names) => match names.iter().find(|n| **n == t) {
                Some(n) => Value::Name(n),
                None => return Err(format!("expected one of {}", names.join(", "))),
            },
        };
        self.check(&value)?;
        Ok(value)
    }

    /// Checks a value against the kind and range.
    pub fn check(&self, value: &Value) -> Result<(), String> {
        match (self.kind, value) {
            (Kind::Count { min, max }, Value::Int(v)) => {
                if *v < min || *v > max {
                    return Err(if max == u64::MAX {
                        format!("must be at least {min}")
                    } else {
                        format!("must be between {min} and {max}")
                    });
                }
            }
            (
                Kind::Real {
                    min,
                    min_inclusive,
                    max,
                },
                Value::Real(v),
            ) => {
                let above = if min_inclusive { *v >= min } else { *v > min };
                if !(v.is_finite() && above && *v <= max) {
                    let low = if min_inclusive { ">=" } else { ">" };
                    return Err(if max == f32::MAX {
                        format!("must be a finite number {low} {min}")
                    } else {
                        format!("must be a number {low} {min} and <= {max}")
                    });
                }
            }
            (Kind::Flag, Value::Bool(_)) => {}
            (Kind::Choice(names), Value::Name(n)) => {
                if !names.contains(n) {
                    return Err(format!("expected one of {}", names.join(", ")));
                }
            }
            _ => return Err(format!("expected {}", self.kind_name())),
        }
        Ok(())
    }

    /// What the kind looks like, for messages and docs.
    pub fn kind_name(&self) -> String {
        match self.kind {
            Kind::Count { .. } => "a whole number".into(),
            Kind::Real { .. } => "a number".into(),
            Kind::Flag => "true or false".into(),
            Kind::Choice(names) => format!("one of {}", names.join(", ")),
        }
    }
}

/// The declaration of the setting `name`.
pub fn spec(name: &str) -> Option<&'static Spec> {
    SETTINGS.iter().find(|s| s.name == name)
}

/// A setting's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Int(u64),
    Real(f32),
    Bool(bool),
    Name(&'static str),
}

impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Int(v) => write!(f, "{v}"),
            Value::Real(v) => write!(f, "{v}"),
            Value::Bool(v) => write!(f, "{v}"),
            Value::Name(v) => write!(f, "{v}"),
        }
    }
}

/// Where a value came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// The command line (its flag is the setting's name with dashes).
    CommandLine,
    /// A scene file's `[settings]` table, at this line.
    SceneFile { path: PathBuf, line: usize },
    /// The named preset (a built-in scene's settings).
    Preset(String),
    /// Settings built in code and handed to the library.
    Caller,
    /// The table's default.
    Default,
}

/// A setting whose value cannot be used: which one, the value, where it came
/// from and why. Its one line reads as the user wrote the value: `--ssaa 0:
/// ...`, `scene.toml:12: ssaa = 0: ...` or `preset cornell-final: ssaa = 0: ...`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", self.line())]
pub struct SettingError {
    pub setting: String,
    pub value: String,
    pub origin: Origin,
    pub message: String,
}

impl SettingError {
    pub fn new(setting: &str, value: &dyn std::fmt::Display, origin: Origin, message: impl Into<String>) -> Self {
        SettingError {
            setting: setting.to_string(),
            value: value.to_string(),
            origin,
            message: message.into(),
        }
    }

    fn line(&self) -> String {
        let (s, v, m) = (&self.setting, &self.value, &self.message);
        match &self.origin {
            Origin::CommandLine => {
                let flag = format!("--{}", s.replace('_', "-"));
                if v.is_empty() {
                    format!("{flag}: {m}")
                } else {
                    format!("{flag} {v}: {m}")
                }
            }
            Origin::SceneFile { path, line } => format!("{}:{line}: {s} = {v}: {m}", path.display()),
            Origin::Preset(p) => format!("preset {p}: {s} = {v}: {m}"),
            Origin::Caller => format!("setting {s} = {v}: {m}"),
            Origin::Default => format!("{s} = {v} (the default): {m}"),
        }
    }
}

/// Values given at one level of precedence, each with its origin.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layer {
    pub values: BTreeMap<&'static str, (Value, Origin)>,
}

impl Layer {
    /// Sets `name` to `value`, checked against its declaration.
    pub fn set(&mut self, name: &str, value: Value, origin: Origin) -> Result<(), SettingError> {
        let Some(spec) = spec(name) else {
            return Err(SettingError::new(name, &value, origin, "no such setting"));
        };
        spec.check(&value)
            .map_err(|m| SettingError::new(name, &value, origin.clone(), m))?;
        self.values.insert(spec.name, (value, origin));
        Ok(())
    }

    /// Parses and sets `name` from text typed on the command line.
    pub fn set_text(&mut self, name: &str, text: &str, origin: Origin) -> Result<(), SettingError> {
        let Some(spec) = spec(name) else {
            return Err(SettingError::new(name, &text, origin, "no such setting"));
        };
        let value = spec
            .parse(text)
            .map_err(|m| SettingError::new(name, &text, origin.clone(), m))?;
        self.values.insert(spec.name, (value, origin));
        Ok(())
    }

    pub fn get(&self, name: &str) -> Option<&(Value, Origin)> {
        self.values.get(name)
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// The render settings a scene recommends: its file's `[settings]` and the
/// preset they name (for a built-in scene, its own settings).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneSettings {
    pub scene_file: Layer,
    pub preset: Layer,
}

/// The layers [`resolve`] decides between, highest precedence first.
#[derive(Clone, Copy, Debug)]
pub struct Layers<'a> {
    pub command_line: &'a Layer,
    pub scene_file: &'a Layer,
    pub preset: &'a Layer,
}

/// Resolves every setting (command line over scene file over preset over
/// default), checks each value and their combinations once, and returns
/// the settings with the caller's state files (which only the caller names).
pub fn resolve(layers: Layers, files: StateFiles) -> Result<RenderSettings, SettingError> {
    let order = [layers.command_line, layers.scene_file, layers.preset];
    // Which layer gave a value: the k nearest photons bound only by a radius
    // given at the same level or above (a scene's radius is meant for its own
    // fixed-radius gathers, not for a k the user asks for).
    let level = |name: &str| order.iter().position(|l| l.get(name).is_some());
    let k_level = level("gather_k");
    let lookup = |name: &str| -> Option<(Value, Origin)> {
        let mut layers = order.iter().enumerate();
        layers.find_map(|(i, l)| {
            if name == "gather_radius" && k_level.is_some_and(|k| i > k) {
                return None;
            }
            l.get(name).cloned()
        })
    };
    for l in order {
        for (name, (v, o)) in &l.values {
            let s = spec(name).ok_or_else(|| SettingError::new(name, v, o.clone(), "no such setting"))?;
            s.check(v).map_err(|m| SettingError::new(name, v, o.clone(), m))?;
        }
    }
    let mut settings = from_values(&|name| lookup(name).map(|(v, _)| v));
    settings.files = files;
    let origin = |name: &str| lookup(name).map_or(Origin::Default, |(_, o)| o);
    // Options for one integrator, typed for another, are mistakes.
    if let Some(layer) = Some(layers.command_line) {
        for (name, (v, o)) in &layer.values {
            let s = spec(name).expect("checked above");
            if !s.only_for.is_empty() && !s.only_for.contains(&settings.integrator.name()) {
                return Err(SettingError::new(
                    name,
                    v,
                    o.clone(),
                    format!("only for integrator {}", s.only_for.join(", ")),
                ));
            }
        }
    }
    check_combinations(&settings, &origin)?;
    Ok(settings)
}

/// Builds the settings from a lookup of the values given; what is not given
/// takes the table's default, or the derived default the table describes.
fn from_values(get: &dyn Fn(&str) -> Option<Value>) -> RenderSettings {
    let value = |name: &str| get(name).or_else(|| spec(name).and_then(|s| s.default.value()));
    let int = |name: &str| match value(name) {
        Some(Value::Int(v)) => Some(v),
        _ => None,
    };
    let real = |name: &str| match value(name) {
        Some(Value::Real(v)) => Some(v),
        _ => None,
    };
    let flag = |name: &str| matches!(value(name), Some(Value::Bool(true)));
    let choice = |name: &str| match value(name) {
        Some(Value::Name(v)) => v,
        _ => "",
    };
    let integrator = IntegratorKind::from_name(choice("integrator")).unwrap_or_default();
    let k = int("gather_k").map(|k| k as u32);
    RenderSettings {
        ssaa: int("ssaa").unwrap_or_default() as u32,
        shadow_samples: int("shadow_samples").unwrap_or_default() as u32,
        filter: Filter::from_name(choice("filter")).unwrap_or_default(),
        seed: int("seed").unwrap_or_default(),
        threads: int("threads").map(|t| t as usize),
        integrator,
        crop: None,
        spp: int("spp").unwrap_or_default() as u32,
        max_depth: int("max_depth").map(|d| d as u32),
        light_sampling: LightSampling::from_name(choice("light_sampling")).unwrap_or_default(),
        light_sampler: crate::light::LightSamplerKind::from_name(choice("light_sampler")).unwrap_or_default(),
        regularize: flag("regularize"),
        guide_photons: int("guide_photons").unwrap_or_default(),
        sampler: SamplerKind::from_name(choice("sampler")).unwrap_or_default(),
        max_component: real("max_component"),
        white_balance: real("white_balance"),
        sensor: crate::sensor::SENSORS
            .iter()
            .copied()
            .find(|&s| s == choice("sensor"))
            .unwrap_or(crate::sensor::OBSERVER),
        photon: PhotonSettings {
            photons: int("photons").unwrap_or_default(),
            // SPPM converges to the answer only if photon paths are not cut
            // short: Russian roulette, not this limit, should end nearly every
            // path (a 0.75 albedo keeps 1% after 16 hits).
            max_bounces: int("max_bounces").unwrap_or(if integrator == IntegratorKind::Sppm { 100 } else { 5 }) as u32,
            store_first_hit: flag("store_first_hit"),
            roulette: true,
            gather: Gather {
                radius: real("gather_radius").unwrap_or(if k.is_some() { f32::INFINITY } else { 0.1 }),
                k,
                cone: flag("cone_filter"),
                filter: GatherFilter::from_name(choice("gather_filter")).unwrap_or_default(),
            },
            final_gather: int("final_gather").unwrap_or_default() as u32,
            precompute_irradiance: flag("precompute_irradiance"),
            caustic_photons: int("caustic_photons").unwrap_or_default(),
            caustic_radius: real("caustic_radius").unwrap_or_default(),
        },
        files: StateFiles::default(),
        passes: int("passes").unwrap_or_default() as u32,
        alpha: real("alpha").unwrap_or_default(),
    }
}

/// Rules that involve more than one setting, or the machine.
fn check_combinations(s: &RenderSettings, origin: &dyn Fn(&str) -> Origin) -> Result<(), SettingError> {
    let err =
        |name: &str, value: &dyn std::fmt::Display, m: String| Err(SettingError::new(name, value, origin(name), m));
    let p = &s.photon;
    if s.integrator == IntegratorKind::Sppm {
        if let Some(k) = p.gather.k {
            return err(
                "gather_k",
                &k,
                "not with integrator sppm, which needs a finite gather_radius (its initial radius)".into(),
            );
        }
    }
    let photon_map = matches!(s.integrator, IntegratorKind::Photon | IntegratorKind::Sppm);
    if photon_map {
        let available = crate::limits::available_memory()
            .unwrap_or(MAX_MAP_BYTES)
            .min(MAX_MAP_BYTES);
        let need = p.worst_case_bytes();
        if need > available as u128 {
            return err(
                "photons",
                &p.photons,
                format!(
                    "the photon map needs up to {:.1} GiB ({} photons x {} bounces x {PHOTON_RECORD_BYTES} bytes), more than the {:.1} GiB available",
                    need as f64 / (1u64 << 30) as f64,
                    p.photons,
                    p.max_bounces,
                    available as f64 / (1u64 << 30) as f64
                ),
            );
        }
        // The caustic pass stores about as many photons as asked for, plus at most one round.
        let caustic = (p.caustic_photons as u128 + CAUSTIC_ROUND as u128) * PHOTON_RECORD_BYTES as u128;
        if p.caustic_photons > 0 && need + caustic > available as u128 {
            return err(
                "caustic_photons",
                &p.caustic_photons,
                format!(
                    "the caustic map needs up to {:.1} GiB, more than the {:.1} GiB left",
                    caustic as f64 / (1u64 << 30) as f64,
                    (available as u128 - need) as f64 / (1u64 << 30) as f64
                ),
            );
        }
        // Queries index photons with u32 (unreachable under the memory cap).
        let stored = p.photons as u128 * p.max_bounces as u128;
        if stored >= u32::MAX as u128 {
            return err(
                "photons",
                &p.photons,
                format!(
                    "with max_bounces {}: up to {stored} stored photons, more than a map can index (2^32)",
                    p.max_bounces
                ),
            );
        }
    }
    let files = &s.files;
    let has_map = s.integrator == IntegratorKind::Photon && p.photons > 0;
    for (name, given) in [
        ("save_photons", &files.save_photons),
        ("load_photons", &files.load_photons),
    ] {
        if let Some(f) = given.as_ref().filter(|_| !has_map) {
            return Err(SettingError::new(
                name,
                &f.display(),
                Origin::CommandLine,
                "only the photon integrator with photons > 0 has a photon map",
            ));
        }
    }
    let progressive = matches!(
        s.integrator,
        IntegratorKind::Path | IntegratorKind::Bdpt | IntegratorKind::Sppm
    );
    for (name, given) in [("checkpoint", &files.checkpoint), ("resume", &files.resume)] {
        if let Some(f) = given.as_ref().filter(|_| !progressive) {
            return Err(SettingError::new(
                name,
                &f.display(),
                Origin::CommandLine,
                "only progressive renders (integrator path, bdpt or sppm) have checkpoints",
            ));
        }
    }
    Ok(())
}

/// The settings table as Markdown, for `docs/scene-format.md` (a test keeps
/// the document in step with the table).
pub fn markdown_table() -> String {
    let mut out = String::from("| key | value | default | what it does |\n|---|---|---|---|\n");
    for s in SETTINGS.iter().filter(|s| s.in_scene_file) {
        let range = match s.kind {
            Kind::Count { min, max } if max == u64::MAX => format!("whole number >= {min}"),
            Kind::Count { min, max } => format!("whole number {min}..{max}"),
            Kind::Real {
                min,
                min_inclusive,
                max,
            } => {
                let low = if min_inclusive { ">=" } else { ">" };
                if max < f32::MAX {
                    format!("number {low} {min}, <= {max}")
                } else {
                    format!("number {low} {min}")
                }
            }
            Kind::Flag => "true / false".into(),
            Kind::Choice(names) => names.join(" / "),
        };
        out += &format!("| `{}` | {range} | {} | {} |\n", s.name, s.default.describe(), s.doc);
    }
    out
}

#[cfg(test)]
mod tests;
