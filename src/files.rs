//! Reading the user's files safely, and keeping outputs off them: only regular files are
//! read (a FIFO would block forever, `/dev/zero` never ends), a read takes no more than the
//! file's size, and an output may not be any file the same command reads.
//!
//! Every file of the user's that hmdist reads is read by [`read_regular`] (or [`read_text`]
//! over it). Where the environment variable [`READS_LOG`] names a file, each path read is
//! appended to it, one per line: how a test (or a user staging a job's inputs on a cluster)
//! finds every file a command reads without a list kept by hand.

use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};

/// The bytes of the regular file at `path` (a symbolic link is followed): a FIFO, device,
/// socket or directory is refused before it is opened, and the read stops at the size the
/// file had when it was looked at, so a file that grows meanwhile cannot make it run on.
pub fn read_regular(path: &Path) -> Result<Vec<u8>> {
    log_read(path);
    let metadata = std::fs::metadata(path).map_err(|e| Error::io(path, "read", e))?;
    if !metadata.is_file() {
        return Err(Error::file(path, not_regular(&metadata)));
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, "read", e))?;
    let mut bytes = Vec::with_capacity(metadata.len() as usize);
    file.take(metadata.len())
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, "read", e))?;
    Ok(bytes)
}

/// [`read_regular`] as UTF-8 text (a JSON report, a sidecar).
pub fn read_text(path: &Path) -> Result<String> {
    String::from_utf8(read_regular(path)?).map_err(|_| Error::file(path, "is not UTF-8 text"))
}

/// The environment variable naming the file that every path read is appended to.
pub const READS_LOG: &str = "HMDIST_READS";

/// Appends `path` to the [`READS_LOG`] file, where one is named. A log that cannot be written
/// changes nothing of the command's own work.
fn log_read(path: &Path) {
    let Some(log) = std::env::var_os(READS_LOG) else {
        return;
    };
    let line = format!("{}\n", path.display());
    let _ = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(log)
        .and_then(|mut file| std::io::Write::write_all(&mut file, line.as_bytes()));
}

/// What a path that is not a regular file is, for a message.
fn not_regular(metadata: &std::fs::Metadata) -> &'static str {
    if metadata.is_dir() {
        "is a directory, not a file"
    } else {
        "is not a regular file (a FIFO, device or socket): hmdist reads and writes only regular files"
    }
}

/// Whether `a` and `b` name the same existing file (through links or different spellings).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        #[cfg(unix)]
        (Ok(x), Ok(y)) => {
            use std::os::unix::fs::MetadataExt;
            (x.dev(), x.ino()) == (y.dev(), y.ino())
        }
        #[cfg(not(unix))]
        (Ok(_), Ok(_)) => matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y),
        _ => false,
    }
}

/// Refuses `output` where writing it would destroy something: it is one of `inputs` (the
/// files the command reads), a directory, or an existing file that is not a regular one (a
/// device or FIFO, which a rename would replace).
pub fn check_output(output: &Path, inputs: &[&Path]) -> Result<()> {
    if let Some(input) = inputs.iter().find(|input| same_file(output, input)) {
        let message = if output == *input {
            "is an input of this command: an output there would overwrite it".to_string()
        } else {
            format!(
                "is the same file as the input {}: an output there would overwrite it",
                input.display()
            )
        };
        return Err(Error::file(output, message));
    }
    match std::fs::metadata(output) {
        Ok(metadata) if !metadata.is_file() => Err(Error::file(output, not_regular(&metadata))),
        _ => Ok(()),
    }
}

/// Refuses an output whose extension names another format than the one written into it
/// (`--out a.png` for an EXR): a file that lies about its format breaks whatever opens it
/// next. No extension, or one that names no data format, is left to the user.
pub fn check_extension(path: &Path, format: &str) -> Result<()> {
    const FORMATS: [&str; 16] = [
        "exr", "png", "json", "jpg", "jpeg", "tif", "tiff", "bmp", "hdr", "npy", "csv", "obj", "ply", "gltf",
        "glb", "toml",
    ];
    let extension = path.extension().map(|e| e.to_string_lossy().to_lowercase());
    match extension {
        Some(e) if e != format && FORMATS.contains(&e.as_str()) => Err(Error::file(
            path,
            format!(
                "is named .{e} but would hold {}: name it .{format}",
                format.to_uppercase()
            ),
        )),
        _ => Ok(()),
    }
}

/// Whether a process `pid` exists (where that cannot be told: assumed alive, so that what a
/// run of it left is never removed).
pub fn process_alive(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(pid) = libc::pid_t::try_from(pid) else {
            return true;
        };
        // SAFETY: signal 0 sends nothing; it only checks that the process exists.
        let alive = unsafe { libc::kill(pid, 0) } == 0;
        alive || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_output_may_not_be_an_input_by_any_name_nor_a_device() {
        let dir = std::env::temp_dir().join(format!("hmdist-files-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (scene, link, other) = (dir.join("s.obj"), dir.join("link.obj"), dir.join("o.exr"));
        std::fs::write(&scene, b"v 0 0 0\n").unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(&scene, &link).unwrap();
        assert!(check_output(&scene, &[&scene])
            .unwrap_err()
            .to_string()
            .contains("is an input"));
        #[cfg(unix)]
        assert!(check_output(&link, &[&scene])
            .unwrap_err()
            .to_string()
            .contains("same file as the input"));
        let dotted = dir.join(".").join("s.obj");
        assert!(check_output(&dotted, &[&scene]).is_err());
        assert!(check_output(&other, &[&scene]).is_ok(), "a new file is fine");
        assert!(check_output(&dir, &[])
            .unwrap_err()
            .to_string()
            .contains("directory"));
        #[cfg(unix)]
        assert!(check_output(Path::new("/dev/null"), &[])
            .unwrap_err()
            .to_string()
            .contains("not a regular file"));
        #[cfg(unix)]
        assert!(read_regular(Path::new("/dev/zero"))
            .unwrap_err()
            .to_string()
            .contains("not a regular file"));
        assert_eq!(read_regular(&scene).unwrap(), b"v 0 0 0\n");
        assert!(check_extension(Path::new("a.png"), "exr")
            .unwrap_err()
            .to_string()
            .contains("name it .exr"));
        assert!(check_extension(Path::new("a.EXR"), "exr").is_ok());
        assert!(
            check_extension(Path::new("a.hmd"), "exr").is_ok(),
            "not a format's name: the user's choice"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
