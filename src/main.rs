//! The `hmdist` command: argument parsing, progress bars and files. The work is in the library.

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    die_quietly_on_a_closed_pipe();
    let args = cli::parse();
    let runtime_dir = quiet_headless_vulkan();
    let signals = cli::signals::Signals::catch();
    let code = match cli::run(args) {
        Ok(code) => code,
        Err(hmdist::error::Error::Interrupted) => {
            let (status, name) = signals.interrupted_by();
            eprintln!("hmdist: interrupted by {name}: no output was written");
            ExitCode::from(status)
        }
        Err(err) => {
            eprintln!("hmdist: error: {}", cli::describe(&err));
            ExitCode::from(2)
        }
    };
    if let Some(dir) = runtime_dir {
        let _ = std::fs::remove_dir(dir);
    }
    code
}

/// `hmdist diff A B | head -1`: Rust's runtime ignores SIGPIPE, so printing to a pipe whose
/// reader has gone panics ("failed printing to stdout: Broken pipe"). Restore the default
/// action, so that hmdist ends quietly there as any Unix tool does. Files are written to a
/// temporary and renamed, so even then none is left half-written.
fn die_quietly_on_a_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to its default, before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// On a headless Linux machine Mesa's Vulkan driver, probed by the cube map's GPU backend,
/// prints "XDG_RUNTIME_DIR is invalid or not set" when that variable is unset. Point it at a
/// private empty folder for the life of the process (still single-threaded here); returns the
/// folder to remove at exit.
fn quiet_headless_vulkan() -> Option<std::path::PathBuf> {
    #[cfg(target_os = "linux")]
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        use std::os::unix::fs::DirBuilderExt;
        let dir = std::env::temp_dir().join(format!("hmdist-runtime-{}", std::process::id()));
        if std::fs::DirBuilder::new().mode(0o700).create(&dir).is_ok() {
            std::env::set_var("XDG_RUNTIME_DIR", &dir);
            return Some(dir);
        }
    }
    None
}
