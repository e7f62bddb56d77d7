//! The render settings, each declared once: name, kind and range, default and
//! one-line doc. The command line's options, the scene file's `[settings]`
//! keys, `--help` and `docs/scene-format.md` all come from this table, so a
//! new setting is one entry here plus its field in [`super::RenderSettings`].

use super::{DefaultValue, Kind, Spec};

const INTEGRATORS: &[&str] = &["direct", "photon", "path", "sppm", "bdpt"];
const FILTERS: &[&str] = &["box", "tent", "gaussian"];
const GATHER_FILTERS: &[&str] = &["none", "normal", "report"];
const LIGHT_SAMPLING: &[&str] = &["mis", "light", "bsdf"];
const SAMPLERS: &[&str] = &["sobol", "independent", "zsobol"];

/// Largest count of samples, passes and the like we accept (2^20).
const MILLION: u64 = 1 << 20;

pub const SETTINGS: &[Spec] = &[
    Spec {
        name: "integrator",
        kind: Kind::Choice(INTEGRATORS),
        default: DefaultValue::Name("direct"),
        doc: "Light transport algorithm: direct (shadow rays only), photon (photon mapping), path (the reference \
              path tracer), sppm (stochastic progressive photon mapping), bdpt (bidirectional path tracing)",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "ssaa",
        kind: Kind::Count { min: 1, max: 64 },
        default: DefaultValue::Int(4),
        doc: "Supersampling: NxN stratified camera samples per pixel (direct and photon integrators)",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "shadow_samples",
        kind: Kind::Count { min: 0, max: 65_536 },
        default: DefaultValue::Int(4),
        doc: "Shadow rays per light per shading point, stratified over the light",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "filter",
        kind: Kind::Choice(FILTERS),
        default: DefaultValue::Name("box"),
        doc: "Pixel reconstruction filter: box (the pixel's area), tent (radius one pixel), gaussian (sigma 0.5, \
              truncated at 1.5 pixels, less its value there, as pbrt-v4's); samples are splatted into every pixel \
              the filter covers (SPPM samples the filter instead)",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "spp",
        kind: Kind::Count { min: 1, max: MILLION },
        default: DefaultValue::Int(64),
        doc: "Path tracers (path, bdpt): samples per pixel (replaces ssaa)",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "max_depth",
        kind: Kind::Count { min: 0, max: 1 << 16 },
        default: DefaultValue::Unset("no limit: Russian roulette ends paths"),
        doc: "Path tracers (path, bdpt): most bounces: 0 = emitted light only, 1 = direct light only",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "light_sampling",
        kind: Kind::Choice(LIGHT_SAMPLING),
        default: DefaultValue::Name("mis"),
        doc: "Path tracer: how light reaching a diffuse vertex is found: mis (shadow rays and BSDF-sampled rays, \
              combined by the power heuristic), light (shadow rays only), bsdf (BSDF-sampled rays only)",
        in_scene_file: true,
        only_for: &["path"],
    },
    Spec {
        name: "light_sampler",
        kind: Kind::Choice(&crate::light::LightSamplerKind::NAMES),
        default: DefaultValue::Name("power"),
        doc: "How a shadow ray that samples one light chooses it (path tracers; glossy surfaces in the others; bdpt \
              chooses by power whatever this says, as pbrt-v4's does): power (in proportion to each light's power), uniform \
              (every light alike), bvh (a tree over the lights' bounds of emission, in proportion to what each may \
              bring to the point lit: pbrt-v4's default, for scenes of many lights); a pbrt-v4 scene takes its \
              Integrator's \"lightsampler\", bvh without one",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "regularize",
        kind: Kind::Flag,
        default: DefaultValue::Bool(false),
        doc: "Path tracers (path, bdpt): after a path's first non-specular bounce, make smooth and nearly smooth \
              microfacet surfaces glossy (pbrt-v4's Integrator \"regularize\": alphas below 0.3 doubled, kept \
              within [0.1, 0.3]), so that lights seen through mirrors and glass from diffuse surfaces are found, \
              at the price of a bias",
        in_scene_file: true,
        only_for: &["path", "bdpt"],
    },
    Spec {
        name: "guide_photons",
        kind: Kind::Count { min: 0, max: 10 * MILLION },
        default: DefaultValue::Int(0),
        doc: "Path tracer: trace this many caustic photons (light -> glossy or specular surfaces -> diffuse) first \
              and aim half of the diffuse bounces where they came from, the other half by the BSDF (Jensen 1995): \
              unbiased, and it finds lights seen in polished surfaces that cosine-distributed bounces rarely \
              find; 0 leaves bounces to the BSDF",
        in_scene_file: true,
        only_for: &["path"],
    },
    Spec {
        name: "sampler",
        kind: Kind::Choice(SAMPLERS),
        default: DefaultValue::Name("sobol"),
        doc: "Random numbers of each camera sample: sobol (Owen-scrambled Sobol points, one dimension per request, \
              stratified over a pixel's samples), zsobol (the same, one sequence over all pixels in Z order: \
              neighbouring pixels stratified together), independent (a random stream per sample, the pixel \
              position stratified on a grid)",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "max_component",
        kind: Kind::Real {
            min: 0.0,
            min_inclusive: false,
            max: f32::MAX,
        },
        default: DefaultValue::Unset("no clamp"),
        doc: "Scale down each camera sample whose largest RGB component exceeds this, to it, before it reaches the \
              film (pbrt-v4's Film \"maxcomponentvalue\"; not SPPM, as there): fireflies go, at the price of darkening \
              what is bright",
        in_scene_file: true,
        only_for: &["direct", "photon", "path", "bdpt"],
    },
    Spec {
        name: "white_balance",
        kind: Kind::Real {
            min: crate::sensor::KELVIN_RANGE.0,
            min_inclusive: true,
            max: crate::sensor::KELVIN_RANGE.1,
        },
        default: DefaultValue::Unset("none"),
        doc: "White balance in kelvin, as a camera's: light of a daylight illuminant of this colour temperature \
              (a blackbody below 4000 K) comes out white (pbrt-v4's Film \"whitebalance\")",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "sensor",
        kind: Kind::Choice(&crate::sensor::SENSORS),
        default: DefaultValue::Name(crate::sensor::OBSERVER),
        doc: "The film's sensor: cie1931 (the CIE 1931 observer: colours as they are) or one of pbrt-v4's \
              measured cameras (canon_eos_100d, nikon_d850, sony_ilce_9, ...), balanced at white_balance \
              (6500 K unless given) as pbrt-v4 balances them, applied to the finished film as a colour \
              matrix fitted to the camera's spectra (pbrt-v4's Film \"sensor\")",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "photons",
        kind: Kind::Count { min: 0, max: 1 << 40 },
        default: DefaultValue::Int(200_000),
        doc: "Photons emitted (SPPM: per pass); 0 turns photon mapping off (direct light only)",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "max_bounces",
        kind: Kind::Count { min: 1, max: 100 },
        default: DefaultValue::Derived("5; 100 with integrator sppm, whose photons end by Russian roulette"),
        doc: "Surface hits traced per photon, the first being its direct-light hit",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "store_first_hit",
        kind: Kind::Flag,
        default: DefaultValue::Bool(false),
        doc: "Store the photons' first hits (direct light) too; final gathering always does",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "gather_radius",
        kind: Kind::Real {
            min: 0.0,
            min_inclusive: false,
            max: f32::MAX,
        },
        default: DefaultValue::Derived("0.1; unbounded with gather_k"),
        doc: "Photon gather radius (SPPM: the initial radius); with gather_k, the largest radius searched",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "gather_k",
        kind: Kind::Count {
            min: 1,
            max: u32::MAX as u64,
        },
        default: DefaultValue::Unset("none: all photons within the radius"),
        doc: "Gather the K nearest photons (the radius is the distance to the K-th) instead of all within the radius",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "cone_filter",
        kind: Kind::Flag,
        default: DefaultValue::Bool(false),
        doc: "Weight gathered photons with Jensen's cone filter (k = 1.1), normalised",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "gather_filter",
        kind: Kind::Choice(GATHER_FILTERS),
        default: DefaultValue::Name("none"),
        doc: "Photons a gather may use, by the cosine between their surface normal and the shaded one: none (any \
              photon arriving on the shaded side), normal (> 0.9), report (> 0.25)",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "final_gather",
        kind: Kind::Count { min: 0, max: 65_536 },
        default: DefaultValue::Int(0),
        doc: "Final-gather rays per shading point; 0 reads the photon map at the visible point",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "precompute_irradiance",
        kind: Kind::Flag,
        default: DefaultValue::Bool(false),
        doc: "Estimate photon irradiance once at every 4th photon and read the nearest estimate at each shading \
              point (Christensen 1999): much faster with wide gathers",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "caustic_photons",
        kind: Kind::Count { min: 0, max: 1 << 40 },
        default: DefaultValue::Int(100_000),
        doc: "Photons wanted in the caustic map (paths light -> mirror/glass -> diffuse, shown directly); 0 leaves \
              caustics out",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "caustic_radius",
        kind: Kind::Real {
            min: 0.0,
            min_inclusive: false,
            max: f32::MAX,
        },
        default: DefaultValue::Real(0.025),
        doc: "Gather radius of the caustic map",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "passes",
        kind: Kind::Count { min: 1, max: MILLION },
        default: DefaultValue::Int(64),
        doc: "SPPM: camera and photon passes (photons each; gather_radius is the initial radius)",
        in_scene_file: true,
        only_for: &["sppm"],
    },
    Spec {
        name: "alpha",
        kind: Kind::Real {
            min: 0.0,
            min_inclusive: false,
            max: 1.0,
        },
        default: DefaultValue::Real(0.7),
        doc: "SPPM: fraction of each pass's photons kept as the radius shrinks, in (0, 1]",
        in_scene_file: true,
        only_for: &["sppm"],
    },
    Spec {
        name: "seed",
        kind: Kind::Count { min: 0, max: u64::MAX },
        default: DefaultValue::Int(0),
        doc: "Random seed; the same seed gives the same image on any thread count",
        in_scene_file: true,
        only_for: &[],
    },
    Spec {
        name: "threads",
        kind: Kind::Count { min: 1, max: 1024 },
        default: DefaultValue::Unset("all cores"),
        doc: "Worker threads",
        in_scene_file: false,
        only_for: &[],
    },
];
