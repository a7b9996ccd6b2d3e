//! The `hmdist` command: argument parsing, progress bars and files. The work is in the library.

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    die_quietly_on_a_closed_pipe();
    let args = cli::parse();
    let runtime_dir = quiet_headless_vulkan();
    let signals = cli::signals::Signals::catch();
    let kept = cli::kept_when_interrupted(&args);
    let code = match cli::run(args) {
        Ok(code) => code,
        Err(hmdist::error::Error::Interrupted) => {
            let (status, name) = signals.interrupted_by();
            eprintln!("hmdist: interrupted by {name}: {kept}");
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
/// folder to remove at exit. The empty folders of runs killed outright (SIGKILL), whose PID is
/// gone, are removed first.
fn quiet_headless_vulkan() -> Option<std::path::PathBuf> {
    #[cfg(target_os = "linux")]
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        use std::os::unix::fs::DirBuilderExt;
        const PREFIX: &str = "hmdist-runtime-";
        let temp = std::env::temp_dir();
        for entry in std::fs::read_dir(&temp).into_iter().flatten().flatten() {
            let name = entry.file_name();
            let pid = name
                .to_str()
                .and_then(|n| n.strip_prefix(PREFIX)?.parse::<u32>().ok());
            if pid.is_some_and(|pid| !hmdist::files::process_alive(pid)) {
                let _ = std::fs::remove_dir(entry.path()); // only if empty: nothing of anyone's lost
            }
        }
        let dir = temp.join(format!("{PREFIX}{}", std::process::id()));
        if std::fs::DirBuilder::new().mode(0o700).create(&dir).is_ok() {
            std::env::set_var("XDG_RUNTIME_DIR", &dir);
            return Some(dir);
        }
    }
    None
}

/// The system allocator, except that an allocation it cannot make ends the process with the
/// CLI's status for an error (2) and a one-line message, instead of Rust's abort (134) with a
/// backtrace. Under an address-space limit (`ulimit -v`) or a full machine that is where a
/// request the memory checks did not foresee ends. Outputs are renamed into place only at
/// the end, so none is half-written, and the run's temporaries are removed on the way out
/// (where they cannot be, by the next run that writes the same outputs).
struct ExitOnOutOfMemory;

// SAFETY: every call is passed to the system allocator unchanged; only a null result is
// turned into an exit.
unsafe impl std::alloc::GlobalAlloc for ExitOnOutOfMemory {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        checked(unsafe { std::alloc::System.alloc(layout) }, layout.size())
    }

    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        checked(unsafe { std::alloc::System.alloc_zeroed(layout) }, layout.size())
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        checked(
            unsafe { std::alloc::System.realloc(ptr, layout, new_size) },
            new_size,
        )
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: the caller's contract, passed on.
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: ExitOnOutOfMemory = ExitOnOutOfMemory;

/// `ptr`, unless it is null: then the message and exit status 2, allocating nothing.
fn checked(ptr: *mut u8, size: usize) -> *mut u8 {
    if ptr.is_null() && size > 0 {
        out_of_memory(size);
    }
    ptr
}

fn out_of_memory(size: usize) -> ! {
    // The size in decimal, on the stack.
    let mut digits = [0u8; 20];
    let mut at = digits.len();
    let mut n = size;
    loop {
        at -= 1;
        digits[at] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    let parts: [&[u8]; 3] = [
        b"hmdist: error: out of memory: an allocation of ",
        &digits[at..],
        b" bytes failed (the machine's memory, or the address-space limit of ulimit -v, is too small for this request); no output was written\n",
    ];
    #[cfg(unix)]
    // SAFETY: writes of valid buffers to stderr, then an immediate exit that runs nothing else
    // (no allocation, no destructor, no lock another thread may hold).
    unsafe {
        hmdist::image::remove_pending_temporaries();
        for part in parts {
            libc::write(2, part.as_ptr().cast(), part.len());
        }
        libc::_exit(2)
    }
    #[cfg(not(unix))]
    {
        let _ = parts;
        std::process::abort()
    }
}
