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
//! * `builder`: the directives and the graphics state.
//! * `plymesh` files (`.ply`, `.ply.gz`) are read by the crate's one PLY
//!   reader, [`crate::scene::mesh::ply`].
//!
//! Errors ([`PbrtError`]) name `file:line:column`: syntax, unknown
//! directives, parameters of the wrong type, unterminated strings and lists,
//! unbalanced `AttributeBegin`/`AttributeEnd`, missing or cyclic `Include`s,
//! malformed meshes. What the file may say but this reader does not express
//! (`ribbon` curves, media, motion...) is not an error here: it is
//! listed in [`PbrtScene::unsupported`] for the converter to decide.

mod builder;
pub(crate) mod cie;
pub mod convert;
pub mod error;
mod ir;
pub mod lexer;
pub mod params;
mod shapes;
pub mod spectrum;

#[cfg(test)]
mod tests;

pub use builder::{look_at, rotate, MAX_INCLUDE_DEPTH, MAX_SHAPES};
pub use error::{Loc, PbrtError, Result};
pub use ir::*;
pub use params::{FloatOrTexture, Param, ParamType, Params, SpectrumOrTexture, Values};
pub use spectrum::{SampledSpectrum, SpectrumValue};

use crate::scene::mesh::{Disk as FileSystem, FileSource};
use std::path::Path;

/// Reads a pbrt-v4 scene file (and what it includes) from the file system.
pub fn load(path: &Path) -> Result<PbrtScene> {
    load_from(path, &FileSystem)
}

/// Reads a pbrt-v4 scene file through `files` (tests and fuzzing serve
/// files from memory). A `.gz` scene file is decompressed first.
pub fn load_from(path: &Path, files: &dyn FileSource) -> Result<PbrtScene> {
    let bytes = files.read(path).map_err(|source| PbrtError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let bytes = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz")) {
        crate::scene::mesh::ply::gunzip(&bytes).map_err(|m| PbrtError::At {
            loc: Loc::new(std::sync::Arc::new(path.to_path_buf()), 1, 1),
            message: m,
        })?
    } else {
        bytes
    };
    parse_bytes(path, bytes, files)
}

/// Reads a scene from its text; `path` names it in messages and is where
/// relative Include and mesh names are resolved from, through `files`.
pub fn parse_bytes(path: &Path, bytes: Vec<u8>, files: &dyn FileSource) -> Result<PbrtScene> {
    builder::Builder::new(files, path).run(path, bytes)
}
