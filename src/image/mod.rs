//! HMD images and the files they are written to (spec §4, §7).
//!
//! An [`HmdImage`] holds H per pixel, row-major, row 0 at the top; NaN marks background
//! pixels and holes, `+inf` pixels where every sample escaped. Every file is written to a
//! temporary name beside its destination and renamed into place: a failed or interrupted write
//! never leaves a half-written output. Files that belong together (a render's EXR, PNG and
//! JSON) go through an [`OutputSet`]: all of them are written, or none. Once an interruption is
//! requested ([`crate::interrupt`]) nothing more is renamed into place.

pub mod exr;
pub mod picture;

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// H per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct HmdImage {
    /// Columns of pixels.
    pub width: u32,
    /// Rows of pixels.
    pub height: u32,
    /// H per pixel, row-major, row 0 at the top: `width · height` values.
    pub data: Vec<f32>,
}

impl HmdImage {
    /// An image of `data` (row-major, row 0 at the top); panics unless it holds
    /// `width · height` values.
    pub fn new(width: u32, height: u32, data: Vec<f32>) -> Self {
        assert_eq!(
            data.len(),
            width as usize * height as usize,
            "image size mismatch"
        );
        HmdImage { width, height, data }
    }

    /// H at pixel (x, y), row 0 at the top.
    pub fn at(&self, x: u32, y: u32) -> f32 {
        self.data[y as usize * self.width as usize + x as usize]
    }
}

/// The temporary file beside `path` that it is written to before the rename.
fn temporary(path: &Path) -> Result<PathBuf> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| Error::file(path, "not a file name"))?;
    Ok(dir.join(format!(".{}.{}.tmp", name.to_string_lossy(), std::process::id())))
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename; if an
/// interruption was requested meanwhile ([`crate::interrupt`]), removes the temporary and
/// returns [`Error::Interrupted`] instead of renaming.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let temp = temporary(path)?;
    let written = std::fs::File::create(&temp)
        .and_then(|mut f| f.write_all(bytes).and_then(|_| f.sync_all()))
        .map_err(|e| Error::io(path, "write", e))
        .and_then(|_| crate::interrupt::check())
        .and_then(|_| std::fs::rename(&temp, path).map_err(|e| Error::io(path, "write", e)));
    written.inspect_err(|_| {
        let _ = std::fs::remove_file(&temp);
    })
}

/// Output files that are written together or not at all, e.g. a render's EXR, PNG and JSON.
///
/// [`OutputSet::reserve`] creates each file's temporary beside it before the work starts, so
/// an unwritable path fails at once (the error names that path, not the temporary).
/// [`OutputSet::commit`] fills the temporaries and renames them into place; if any step fails
/// it removes every temporary and puts back what each path held before (an older file, or
/// nothing), so a failure leaves the folder as it was. Dropped without a commit, it removes
/// its temporaries. No output may be a file the command reads, a directory or a device
/// ([`crate::files::check_output`]).
pub struct OutputSet {
    /// (destination, temporary), in the order given.
    files: Vec<(PathBuf, PathBuf)>,
}

impl OutputSet {
    /// Creates the temporary of each of `paths`: a path named twice, one of `inputs` (the
    /// files the command reads, by any name), a directory, a device or a file that cannot be
    /// created is an error.
    pub fn reserve(paths: &[&Path], inputs: &[&Path]) -> Result<OutputSet> {
        let mut set = OutputSet { files: vec![] };
        remove_stale_temporaries(paths);
        for (i, &path) in paths.iter().enumerate() {
            if paths[..i]
                .iter()
                .any(|&p| p == path || crate::files::same_file(p, path))
            {
                return Err(Error::file(
                    path,
                    "is named for two outputs: each needs its own file",
                ));
            }
            crate::files::check_output(path, inputs)?;
            let temp = temporary(path)?;
            std::fs::File::create(&temp).map_err(|e| Error::io(path, "write", e))?;
            pending::add(&temp);
            set.files.push((path.to_path_buf(), temp));
        }
        Ok(set)
    }

    /// Writes `contents[i]` to the `i`-th path: every file, or (on error) none. Two commits
    /// into one folder at once take turns (a lock on the folder), so two runs writing the same
    /// outputs leave one run's set, never a mix.
    pub fn commit(mut self, contents: &[&[u8]]) -> Result<()> {
        assert_eq!(contents.len(), self.files.len(), "one content per output");
        let files = std::mem::take(&mut self.files);
        let _forget = Forget(files.iter().map(|(_, temp)| temp.clone()).collect());
        let _turn = files.first().map(|(path, _)| FolderLock::take(path));
        let mut renamed = vec![];
        let result = write_all(&files, contents, &mut renamed);
        for (path, temp) in &files {
            let _ = std::fs::remove_file(temp);
            if result.is_err() && !renamed.iter().any(|(p, _)| p == path) {
                // Not renamed over: the path holds what it held before; an older file's link
                // made for its restoring is no longer needed.
                let _ = std::fs::remove_file(earlier(path));
            }
        }
        for (path, had_file) in renamed {
            let keep = earlier(&path);
            match (&result, had_file) {
                (Ok(()), true) => drop(std::fs::remove_file(&keep)),
                (Err(_), true) => drop(std::fs::rename(&keep, &path)),
                (Err(_), false) => drop(std::fs::remove_file(&path)),
                (Ok(()), false) => {}
            }
        }
        result
    }
}

/// An exclusive lock on the folder of a path (flock on the folder itself: no lock file to
/// leave behind), held while it lives. Where the folder cannot be locked the commit goes on
/// unlocked.
struct FolderLock {
    #[cfg(unix)]
    _folder: Option<std::fs::File>,
}

impl FolderLock {
    fn take(path: &Path) -> FolderLock {
        #[cfg(unix)]
        {
            use std::os::fd::AsRawFd;
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            let folder = std::fs::File::open(dir).ok().filter(|f| {
                // SAFETY: flock on a descriptor this File owns; released when it is closed.
                unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX) == 0 }
            });
            FolderLock { _folder: folder }
        }
        #[cfg(not(unix))]
        {
            let _ = path;
            FolderLock {}
        }
    }
}

/// Removes the temporaries (`.NAME.PID.tmp`, and the kept earlier files `.NAME.PID.tmp.earlier`)
/// that runs which no longer exist left beside `paths` (a run killed by SIGKILL, or aborted,
/// cannot remove its own): each folder is listed once.
fn remove_stale_temporaries(paths: &[&Path]) {
    let folder = |path: &Path| match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut folders: Vec<PathBuf> = paths.iter().map(|p| folder(p)).collect();
    folders.sort();
    folders.dedup();
    for dir in folders {
        let prefixes: Vec<String> = paths
            .iter()
            .filter(|p| folder(p) == dir)
            .filter_map(|p| p.file_name())
            .map(|name| format!(".{}.", name.to_string_lossy()))
            .collect();
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let file = entry.file_name().to_string_lossy().into_owned();
            let Some(rest) = prefixes
                .iter()
                .find_map(|prefix| file.strip_prefix(prefix.as_str()))
            else {
                continue;
            };
            let pid = rest
                .strip_suffix(".tmp")
                .or_else(|| rest.strip_suffix(".tmp.earlier"));
            if let Some(pid) = pid.and_then(|p| p.parse::<u32>().ok()) {
                if pid != std::process::id() && !crate::files::process_alive(pid) {
                    let _ = std::fs::remove_file(entry.path());
                }
            }
        }
    }
}

/// Where the file `path` held before a commit is kept (a hard link) until the commit is
/// done: put back if it fails.
fn earlier(path: &Path) -> PathBuf {
    let mut name = temporary(path)
        .unwrap_or_else(|_| path.to_path_buf())
        .into_os_string();
    name.push(".earlier");
    PathBuf::from(name)
}

/// Fills every temporary, then (unless an interruption was requested meanwhile) renames
/// every one into place, first keeping a link to the file each path held (`renamed` gets
/// each path renamed over, and whether it held a file).
fn write_all(
    files: &[(PathBuf, PathBuf)],
    contents: &[&[u8]],
    renamed: &mut Vec<(PathBuf, bool)>,
) -> Result<()> {
    for ((path, temp), bytes) in files.iter().zip(contents) {
        std::fs::File::create(temp)
            .and_then(|mut f| f.write_all(bytes).and_then(|_| f.sync_all()))
            .map_err(|e| Error::io(path, "write", e))?;
    }
    crate::interrupt::check()?;
    let mut had = vec![];
    for (path, _) in files {
        let keep = earlier(path);
        let _ = std::fs::remove_file(&keep);
        // A file or a link is kept (on anything else there, the rename fails).
        let had_file =
            std::fs::symlink_metadata(path).is_ok_and(|m| m.is_file() || m.file_type().is_symlink());
        if had_file && std::fs::hard_link(path, &keep).is_err() {
            // A file system without hard links: a copy keeps it as well.
            std::fs::copy(path, &keep).map_err(|e| Error::io(path, "keep a copy of", e))?;
        }
        had.push(had_file);
    }
    for ((path, temp), had_file) in files.iter().zip(had) {
        std::fs::rename(temp, path).map_err(|e| Error::io(path, "write", e))?;
        renamed.push((path.clone(), had_file));
    }
    Ok(())
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        for (_, temp) in &self.files {
            let _ = std::fs::remove_file(temp);
            pending::remove(temp);
        }
    }
}

/// Takes temporaries off [`pending`] when a commit is over, however it ended.
struct Forget(Vec<PathBuf>);

impl Drop for Forget {
    fn drop(&mut self) {
        for temp in &self.0 {
            pending::remove(temp);
        }
    }
}

/// The temporaries of the output sets reserved and not yet committed, so that a process
/// ending where no destructor runs (out of memory: the CLI's allocator) can remove them
/// without allocating ([`remove_pending_temporaries`]).
mod pending {
    use std::ffi::CString;
    use std::path::Path;
    use std::sync::Mutex;

    pub(super) static PENDING: Mutex<Vec<CString>> = Mutex::new(Vec::new());

    pub(super) fn add(temp: &Path) {
        #[cfg(unix)]
        {
            use std::os::unix::ffi::OsStrExt;
            if let (Ok(name), Ok(mut list)) = (CString::new(temp.as_os_str().as_bytes()), PENDING.lock()) {
                list.push(name);
            }
        }
        #[cfg(not(unix))]
        let _ = temp;
    }

    pub(super) fn remove(temp: &Path) {
        #[cfg(unix)]
        {
            use std::os::unix::ffi::OsStrExt;
            if let Ok(mut list) = PENDING.lock() {
                list.retain(|name| name.as_bytes() != temp.as_os_str().as_bytes());
            }
        }
        #[cfg(not(unix))]
        let _ = temp;
    }
}

/// Removes every temporary of an output set not yet committed, allocating nothing: for a
/// process about to end where no destructor runs. Skips them where the list is being changed
/// at that moment (the next run that writes there removes them: they name a dead process).
pub fn remove_pending_temporaries() {
    #[cfg(unix)]
    if let Ok(list) = pending::PENDING.try_lock() {
        for name in list.iter() {
            // SAFETY: a NUL-terminated path that the list owns.
            unsafe { libc::unlink(name.as_ptr()) };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh folder for one test.
    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("hmdist-outputs-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_set_is_written_whole() {
        let dir = folder("whole");
        let (a, b) = (dir.join("a.exr"), dir.join("a.json"));
        OutputSet::reserve(&[&a, &b], &[])
            .unwrap()
            .commit(&[b"exr", b"json"])
            .unwrap();
        assert_eq!(entries(&dir), ["a.exr", "a.json"]);
        assert_eq!(std::fs::read(&b).unwrap(), b"json");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_unwritable_path_is_refused_at_reservation_by_its_own_name() {
        let dir = folder("reserve");
        let (exr, json) = (dir.join("hmd.exr"), dir.join("no/such/folder/hmd.json"));
        let e = OutputSet::reserve(&[&exr, &json], &[])
            .err()
            .expect("refused")
            .to_string();
        assert!(e.starts_with(&json.display().to_string()), "{e}");
        assert!(!e.contains(".tmp"), "{e}");
        assert_eq!(
            entries(&dir),
            Vec::<String>::new(),
            "the EXR's temporary is removed"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_failed_commit_puts_back_the_files_it_had_replaced() {
        // Old hmd.exr and hmd.png exist; the JSON's destination turns into a folder after the
        // reservation, so its rename fails after the EXR's and the PNG's have succeeded.
        let dir = folder("restore");
        let (exr, png, json) = (dir.join("hmd.exr"), dir.join("hmd.png"), dir.join("hmd.json"));
        std::fs::write(&exr, b"old exr").unwrap();
        std::fs::write(&png, b"old png").unwrap();
        let set = OutputSet::reserve(&[&exr, &png, &json], &[]).unwrap();
        std::fs::create_dir(&json).unwrap();
        assert!(set.commit(&[b"exr", b"png", b"json"]).is_err());
        assert_eq!(
            entries(&dir),
            ["hmd.exr", "hmd.json", "hmd.png"],
            "nothing else left"
        );
        assert_eq!(std::fs::read(&exr).unwrap(), b"old exr");
        assert_eq!(std::fs::read(&png).unwrap(), b"old png");
        // And a commit that succeeds leaves no kept copy behind.
        std::fs::remove_dir(&json).unwrap();
        let set = OutputSet::reserve(&[&exr, &png, &json], &[]).unwrap();
        set.commit(&[b"exr", b"png", b"json"]).unwrap();
        assert_eq!(entries(&dir), ["hmd.exr", "hmd.json", "hmd.png"]);
        assert_eq!(std::fs::read(&exr).unwrap(), b"exr");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_commit_waits_while_another_holds_the_folder() {
        // Two runs committing the same outputs take turns: while one holds the folder's lock
        // the other's files do not move, so the set on disk is one run's.
        let dir = folder("turns");
        let (exr, json) = (dir.join("o.exr"), dir.join("o.json"));
        let set = OutputSet::reserve(&[&exr, &json], &[]).unwrap();
        let held = FolderLock::take(&exr);
        let committing = std::thread::spawn(move || set.commit(&[b"exr", b"json"]));
        std::thread::sleep(std::time::Duration::from_millis(300));
        assert!(
            !exr.exists() && !json.exists(),
            "nothing renamed while the folder is held"
        );
        drop(held);
        committing.join().unwrap().unwrap();
        assert_eq!(std::fs::read(&json).unwrap(), b"json");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_failure_after_the_first_file_is_in_place_leaves_none_of_the_set() {
        // The PNG's destination turns into a folder after the reservation: its rename fails
        // after the EXR's has succeeded.
        let dir = folder("commit");
        let (exr, png, json) = (dir.join("hmd.exr"), dir.join("hmd.png"), dir.join("hmd.json"));
        let set = OutputSet::reserve(&[&exr, &png, &json], &[]).unwrap();
        std::fs::create_dir(&png).unwrap();
        std::fs::write(png.join("keep"), b"").unwrap();
        let e = set
            .commit(&[b"exr", b"png", b"json"])
            .expect_err("fails")
            .to_string();
        assert!(e.starts_with(&png.display().to_string()), "{e}");
        assert_eq!(entries(&dir), ["hmd.png"], "only the folder that was in the way");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
