//! Reading pbrt-v4 scene files into a renderer-independent description,
//! [`PbrtScene`]: what the file says, with every transformation composed
//! into world space and every item's place in the file, for a converter to
//! turn into this renderer's scene (and to report what it cannot render as
//! `file:line: ...`).
//!
//! pbrt-v4's own source is the specification: parser.cpp (tokens and
//! directives), scene.cpp (`BasicSceneBuilder`: graphics state, named
//! coordinate systems, instances), paramdict.cpp (parameter types),
//! shapes.cpp and util/mesh.cpp (shape parameters, PLY meshes).
//!
//! * [`lexer`]: tokens with file, line and column.
//! * [`params`]: parameter lists and typed look-ups that record what was read.
//! * [`spectrum`]: `blackbody` and sampled spectra to RGB (the conversion is
//!   documented there).
//!
//! Errors ([`PbrtError`]) name `file:line:column`: syntax, unknown
//! directives, parameters of the wrong type, unterminated strings and lists,
//! unbalanced `AttributeBegin`/`AttributeEnd`, missing or cyclic `Include`s,
//! malformed meshes. What the file may say but this reader does not express
//! (partial spheres, curves, media, motion...) is not an error here: it is
//! listed in [`PbrtScene::unsupported`] for the converter to decide.

pub mod error;
pub mod lexer;
pub mod params;
pub mod spectrum;

#[cfg(test)]
mod tests;

pub use error::{Loc, PbrtError, Result};
pub use params::{FloatOrTexture, Param, ParamType, Params, SpectrumOrTexture, Values};
pub use spectrum::{SampledSpectrum, SpectrumValue};
