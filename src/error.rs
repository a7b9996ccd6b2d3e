//! The one error type of hmdist, with its kinds.
//!
//! Every error here is the user's to fix or the machine's to explain: a file that cannot be
//! read or parsed, a scene whose geometry is unusable, a parameter out of range, a GPU that is
//! missing or fails. The CLI prints the message as one paragraph and exits with status 2.
//! Bugs in hmdist itself are panics, not `Error`s; a panic inside a parsing crate on a
//! malformed file is caught ([`catch_file_panic`]) and becomes an [`Error::File`]. Match on
//! the variant (and on [`DeviceErrorKind`]) rather than on the text.

use std::cell::Cell;
use std::fmt;
use std::panic::PanicHookInfo;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

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
    /// The work was stopped by [`crate::interrupt::request`] (the CLI: Ctrl-C or SIGTERM)
    /// before it finished; nothing was written.
    Interrupted,
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
            Error::Interrupted => write!(f, "interrupted before the work was done: nothing was written"),
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

/// Runs `parse`, code of a parsing crate that may panic on malformed input, turning a panic
/// into an [`Error::File`] on `path` ("malformed file (the parser failed: ...)").
///
/// The panic's message is not printed: while a thread is inside this function the process's
/// panic hook is wrapped by one that stays silent for that thread's panics (and passes every
/// other thread's to the hook it wraps); the last thread to leave restores the wrapped hook,
/// so a program using the library keeps its own. Nothing the closure touches outlives a
/// panic, so asserting unwind safety is sound.
pub fn catch_file_panic<T>(path: &Path, parse: impl FnOnce() -> Result<T>) -> Result<T> {
    let _silence = SilentPanics::enter();
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(parse)).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown error".to_string());
        let what = what.split_whitespace().collect::<Vec<_>>().join(" ");
        Err(Error::file(
            path,
            format!("malformed file (the parser failed: {what})"),
        ))
    })
}

/// A panic hook as the standard library keeps it.
type Hook = Arc<Box<dyn Fn(&PanicHookInfo<'_>) + Sync + Send + 'static>>;

thread_local! {
    /// Whether this thread is inside [`catch_file_panic`].
    static SILENT: Cell<bool> = const { Cell::new(false) };
}

/// Threads inside [`catch_file_panic`] and the hook that was in place before the first one
/// entered.
static WRAPPED: Mutex<(usize, Option<Hook>)> = Mutex::new((0, None));

/// This thread's panics are silent while it lives.
struct SilentPanics {
    /// Whether the thread was already silent (nested calls).
    was_silent: bool,
}

impl SilentPanics {
    fn enter() -> SilentPanics {
        let mut wrapped = WRAPPED.lock().unwrap_or_else(|e| e.into_inner());
        if wrapped.0 == 0 {
            let previous: Hook = Arc::new(std::panic::take_hook());
            let inner = previous.clone();
            std::panic::set_hook(Box::new(move |info| {
                if !SILENT.get() {
                    inner(info)
                }
            }));
            wrapped.1 = Some(previous);
        }
        wrapped.0 += 1;
        SilentPanics {
            was_silent: SILENT.replace(true),
        }
    }
}

impl Drop for SilentPanics {
    fn drop(&mut self) {
        SILENT.set(self.was_silent);
        let mut wrapped = WRAPPED.lock().unwrap_or_else(|e| e.into_inner());
        wrapped.0 -= 1;
        if wrapped.0 == 0 {
            if let Some(previous) = wrapped.1.take() {
                // Drop our wrapper, the other owner of the hook, and put the hook itself
                // back: wrapping it again would nest one closure deeper on every call.
                drop(std::panic::take_hook());
                match Arc::try_unwrap(previous) {
                    Ok(hook) => std::panic::set_hook(hook),
                    Err(shared) => std::panic::set_hook(Box::new(move |info| shared(info))),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_caught_panic_is_a_file_error_and_silent_and_the_hook_is_restored() {
        // Counts the panics of this thread that reach the process's hook.
        use std::sync::atomic::{AtomicUsize, Ordering};
        static SEEN: AtomicUsize = AtomicUsize::new(0);
        let me = std::thread::current().id();
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |_| {
            if std::thread::current().id() == me {
                SEEN.fetch_add(1, Ordering::SeqCst);
            }
        }));

        let path = Path::new("broken.glb");
        let caught = catch_file_panic(path, || -> Result<()> { panic!("index {} out of range", 7) });
        let message = caught.expect_err("an error").to_string();
        assert_eq!(
            message,
            "broken.glb: malformed file (the parser failed: index 7 out of range)"
        );
        assert_eq!(SEEN.load(Ordering::SeqCst), 0, "the hook saw the caught panic");
        assert_eq!(catch_file_panic(path, || Ok(3)).unwrap(), 3);

        // Outside the guard, panics reach the hook that was in place before.
        let _ = std::panic::catch_unwind(|| panic!("outside"));
        assert_eq!(SEEN.load(Ordering::SeqCst), 1, "the hook was not restored");

        // The very hook, not a wrapper of it: a million calls must not nest a million
        // closures (the fuzzer found this one as memory growing without end).
        let hook = std::panic::take_hook();
        let address = &*hook as *const _ as *const ();
        std::panic::set_hook(hook);
        for _ in 0..3 {
            catch_file_panic(path, || Ok(())).unwrap();
        }
        let hook = std::panic::take_hook();
        assert_eq!(
            &*hook as *const _ as *const (), address,
            "the hook came back wrapped"
        );
        std::panic::set_hook(previous);
    }
}
