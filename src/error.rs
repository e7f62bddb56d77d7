//! The library's error type: every failure a user can cause, each with the
//! file, line or option it concerns.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{0}")]
    InvalidSetting(String),
    #[error("unknown scene '{name}' (known scenes: {known})")]
    UnknownScene { name: String, known: String },
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
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
