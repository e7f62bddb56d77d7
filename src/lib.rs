//! raytracer: a physically based CPU ray tracer built around photon mapping.
//!
//! Data flows one way: a scene description (built in or from a file) becomes
//! a [`scene::Scene`] (with its BVH), an integrator renders it into a
//! [`film::Film`], and [`image_io`] writes the film to disk.

pub mod bsdf;
pub mod bssrdf;
pub mod camera;
pub mod error;
pub mod film;
pub mod geometry;
pub mod image_io;
pub mod integrator;
pub mod light;
pub mod limits;
pub mod material;
pub mod math;
pub mod medium;
pub mod metrics;
pub mod photon;
pub mod sampling;
pub mod scene;
pub mod sensor;
pub mod settings;
pub mod state_file;
pub mod texture;
pub mod viewer;

pub use error::{Error, Result};
pub use film::Film;
pub use integrator::{render, RenderOutput, RenderSettings};
pub use scene::{Scene, SceneDesc};
