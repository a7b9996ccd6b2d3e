//! The one error type of hmdist, with its kinds.
//!
//! Every error here is the user's to fix or the machine's to explain: a file that cannot be
//! read or parsed, a scene whose geometry is unusable, a parameter out of range, a GPU that is
//! missing or fails. The CLI prints the message as one paragraph and exits with status 2.
//! Bugs in hmdist itself are panics, not `Error`s. Match on the variant (and on
//! [`DeviceErrorKind`]) rather than on the text.

use std::fmt;
use std::path::{Path, PathBuf};

/// What went wrong, with enough context for the person who asked for it.
#[derive(Debug)]
pub enum Error {
    /// A file could not be read, written or parsed.
    File {
        /// The file, as the caller named it.
        path: PathBuf,
        /// 1-based line, where the format has lines and the problem has one.
        line: Option<usize>,
        /// What is wrong with it.
        message: String,
        /// The operating system's error, where there was one; also [`std::error::Error::source`].
        source: Option<std::io::Error>,
    },
    /// The scene's geometry cannot be rendered (no triangles, a non-finite vertex, ...).
    Scene(String),
    /// A parameter is out of range or inconsistent with the others.
    Parameter {
        /// The library's name of the parameter (`rays`, `max_distance`); the CLI shows it as
        /// its flag (`--rays`). `None` where no single parameter is to blame.
        name: Option<&'static str>,
        /// What is wrong, phrased to follow the name: "must be at least 1, not 0".
        message: String,
    },
    /// A GPU (or other device) is missing or failed.
    Device {
        /// What kind of failure.
        kind: DeviceErrorKind,
        /// The device's own words.
        message: String,
    },
}

/// The kinds of [`Error::Device`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceErrorKind {
    /// No suitable adapter: no Vulkan, Metal or DX12 driver, or this build has no GPU support.
    NoAdapter,
    /// The adapter lacks something the pipeline needs (a feature, a large enough texture).
    Unsupported,
    /// The device ran out of memory.
    OutOfMemory,
    /// Reading results back from the device failed.
    Readback,
    /// Any other failure the device reported (validation, a lost device).
    Failed,
}

/// `std::result::Result` with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// A problem with the file at `path`.
    pub fn file(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::File {
            path: path.as_ref().to_path_buf(),
            line: None,
            message: message.into(),
            source: None,
        }
    }

    /// A problem at line `line` (1-based) of the file at `path`.
    pub fn file_line(path: impl AsRef<Path>, line: usize, message: impl Into<String>) -> Self {
        Error::File {
            path: path.as_ref().to_path_buf(),
            line: Some(line),
            message: message.into(),
            source: None,
        }
    }

    /// An I/O error on `path`, phrased for a person ("cannot read file: No such file or
    /// directory"), keeping the `io::Error` as the source.
    pub fn io(path: impl AsRef<Path>, verb: &str, err: std::io::Error) -> Self {
        Error::File {
            path: path.as_ref().to_path_buf(),
            line: None,
            message: format!("cannot {verb} file: {err}"),
            source: Some(err),
        }
    }

    /// The scene cannot be rendered.
    pub fn scene(message: impl Into<String>) -> Self {
        Error::Scene(message.into())
    }

    /// A bad combination of parameters that no single one is to blame for.
    pub fn parameter(message: impl Into<String>) -> Self {
        Error::Parameter {
            name: None,
            message: message.into(),
        }
    }

    /// Parameter `name` has a bad value; `message` follows the name ("must be at least 1").
    pub fn invalid(name: &'static str, message: impl Into<String>) -> Self {
        Error::Parameter {
            name: Some(name),
            message: message.into(),
        }
    }

    /// Refuses `value` of parameter `name` unless it is absent or a positive number.
    pub fn check_positive(name: &'static str, value: Option<f32>) -> Result<()> {
        match value {
            Some(v) if v.is_nan() || v <= 0.0 => {
                Err(Error::invalid(name, format!("must be positive, not {v}")))
            }
            _ => Ok(()),
        }
    }

    /// A device failure of `kind`.
    pub fn device(kind: DeviceErrorKind, message: impl Into<String>) -> Self {
        Error::Device {
            kind,
            message: message.into(),
        }
    }

    /// The message with each parameter name written by `spell` (the CLI spells `rays` as
    /// `--rays`); [`Display`](fmt::Display) writes the name as it is.
    pub fn describe(&self, spell: impl Fn(&'static str) -> String) -> String {
        match self {
            Error::Parameter {
                name: Some(name),
                message,
            } => format!("bad parameter: {} {message}", spell(name)),
            other => other.to_string(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::File {
                path,
                line: Some(line),
                message,
                ..
            } => write!(f, "{}:{line}: {message}", path.display()),
            Error::File {
                path,
                line: None,
                message,
                ..
            } => write!(f, "{}: {message}", path.display()),
            Error::Scene(message) => write!(f, "bad scene: {message}"),
            Error::Parameter {
                name: Some(name),
                message,
            } => write!(f, "bad parameter: {name} {message}"),
            Error::Parameter { name: None, message } => write!(f, "bad parameter: {message}"),
            Error::Device { message, .. } => write!(f, "GPU: {message}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::File {
                source: Some(err), ..
            } => Some(err),
            _ => None,
        }
    }
}
