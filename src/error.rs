//! The one error type of hmdist.
//!
//! Every error here is the user's to fix: a file that cannot be read or parsed, a scene whose
//! geometry is unusable, a parameter out of range. The CLI prints the message as one
//! paragraph and exits with status 2. Bugs in hmdist itself are panics, not `Error`s.

use std::fmt;
use std::path::{Path, PathBuf};

/// What went wrong, with enough context for the person who typed the command.
#[derive(Debug)]
pub enum Error {
    /// A file could not be read, written or parsed. `line` is 1-based where the format has lines.
    File {
        path: PathBuf,
        line: Option<usize>,
        message: String,
    },
    /// The scene's geometry cannot be rendered (no triangles, a non-finite vertex, ...).
    Scene(String),
    /// A parameter is out of range or inconsistent with the others.
    Parameter(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn file(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::File {
            path: path.as_ref().to_path_buf(),
            line: None,
            message: message.into(),
        }
    }

    pub fn file_line(path: impl AsRef<Path>, line: usize, message: impl Into<String>) -> Self {
        Error::File {
            path: path.as_ref().to_path_buf(),
            line: Some(line),
            message: message.into(),
        }
    }

    /// An I/O error on `path`, phrased for a person ("cannot read ...: No such file or directory").
    pub fn io(path: impl AsRef<Path>, verb: &str, err: std::io::Error) -> Self {
        Error::file(path, format!("cannot {verb} file: {err}"))
    }

    pub fn scene(message: impl Into<String>) -> Self {
        Error::Scene(message.into())
    }

    pub fn parameter(message: impl Into<String>) -> Self {
        Error::Parameter(message.into())
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::File {
                path,
                line: Some(line),
                message,
            } => write!(f, "{}:{line}: {message}", path.display()),
            Error::File {
                path,
                line: None,
                message,
            } => write!(f, "{}: {message}", path.display()),
            Error::Scene(message) => write!(f, "bad scene: {message}"),
            Error::Parameter(message) => write!(f, "bad parameter: {message}"),
        }
    }
}

impl std::error::Error for Error {}
