//! Where things are in a scene's files, and the reader's error type.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A place in a scene file: the file as the scene named it (joined to the
/// folder it was resolved against), the line and the column (both from 1;
/// the column counts characters, not bytes).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Loc {
    pub file: Arc<PathBuf>,
    pub line: u32,
    pub col: u32,
}

impl Loc {
    pub fn new(file: Arc<PathBuf>, line: u32, col: u32) -> Loc {
        Loc { file, line, col }
    }

    /// The file and line only, `file:line`, for messages about a whole
    /// directive ("file:line: unsupported material 'hair'").
    pub fn file_line(&self) -> String {
        format!("{}:{}", self.file.display(), self.line)
    }

    pub fn path(&self) -> &Path {
        &self.file
    }
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.col)
    }
}

/// Why a scene could not be read. Every error but an unreadable top-level
/// file names the place in a scene file it concerns; the message is one line.
#[derive(Debug, thiserror::Error)]
pub enum PbrtError {
    /// The scene file given to the reader cannot be read.
    #[error("{path}: {source}", path = path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Anything wrong at a place in a scene file: syntax, a parameter of the
    /// wrong type, a missing Include or mesh file, a malformed mesh...
    #[error("{loc}: {message}")]
    At { loc: Loc, message: String },
}

impl PbrtError {
    pub fn at(loc: &Loc, message: impl Into<String>) -> PbrtError {
        PbrtError::At {
            loc: loc.clone(),
            message: message.into(),
        }
    }

    /// The place the error is about (None for an unreadable top-level file).
    pub fn loc(&self) -> Option<&Loc> {
        match self {
            PbrtError::Read { .. } => None,
            PbrtError::At { loc, .. } => Some(loc),
        }
    }
}

/// The library's error: a located error becomes a `Syntax` error (file and
/// line) whose message starts with the column: `file:line: column C: ...`.
impl From<PbrtError> for crate::error::Error {
    fn from(e: PbrtError) -> Self {
        match e {
            PbrtError::Read { path, source } => crate::error::Error::Io { path, source },
            PbrtError::At { loc, message } => crate::error::Error::Syntax {
                path: loc.file.as_ref().clone(),
                line: loc.line as usize,
                message: format!("column {}: {message}", loc.col),
            },
        }
    }
}

pub type Result<T> = std::result::Result<T, PbrtError>;
