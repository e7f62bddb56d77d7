//! The library's error type: every failure a user can cause, each with the
//! file, line or option it concerns.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{0}")]
    InvalidSetting(String),
    /// A setting's value, with where it came from.
    #[error(transparent)]
    Setting(#[from] crate::settings::SettingError),
    #[error("unknown scene '{name}' (built-in scenes: {known}; or give a .toml scene file)")]
    UnknownScene { name: String, known: String },
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    /// A malformed text file, at the line where the problem is.
    #[error("{path}:{line}: {message}")]
    Syntax {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// A malformed binary file, at the byte offset where the problem is.
    #[error("{path}: at byte offset {offset}: {message}")]
    Binary {
        path: PathBuf,
        offset: u64,
        message: String,
    },
    /// A built-in scene that draws a mesh the project does not ship.
    #[error(
        "scene '{scene}' needs the Stanford bunny: get bun_zipper.ply (or an OBJ of it) from the \
         Stanford 3D Scanning Repository (https://graphics.stanford.edu/data/3Dscanrep/) and pass it with --mesh PATH"
    )]
    MeshRequired { scene: String },
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: cannot write image: {message}")]
    ImageWrite { path: PathBuf, message: String },
    #[error("invalid scene: {0}")]
    Scene(String),
    /// The preview window cannot run (no display, no window, built without it).
    #[error("view: {0}")]
    Window(String),
}

pub type Result<T> = std::result::Result<T, Error>;
