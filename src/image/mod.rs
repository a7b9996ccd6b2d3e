//! HMD images and the files they are written to (SPEC §4, §7).
//!
//! An [`HmdImage`] holds H per pixel, row-major, row 0 at the top; NaN marks background
//! pixels and holes, `+inf` pixels where every sample escaped. Every file is written to a
//! temporary name beside its destination and renamed into place: a failed or interrupted write
//! never leaves a half-written output.

pub mod exr;
pub mod picture;

use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};

/// H per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct HmdImage {
    pub width: u32,
    pub height: u32,
    pub data: Vec<f32>,
}

impl HmdImage {
    pub fn new(width: u32, height: u32, data: Vec<f32>) -> Self {
        assert_eq!(
            data.len(),
            width as usize * height as usize,
            "image size mismatch"
        );
        HmdImage { width, height, data }
    }

    pub fn at(&self, x: u32, y: u32) -> f32 {
        self.data[y as usize * self.width as usize + x as usize]
    }
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| Error::file(path, "not a file name"))?;
    let temp = dir.join(format!(".{}.{}.tmp", name.to_string_lossy(), std::process::id()));
    let written = std::fs::File::create(&temp)
        .and_then(|mut f| f.write_all(bytes).and_then(|_| f.sync_all()))
        .and_then(|_| std::fs::rename(&temp, path));
    written.map_err(|e| {
        let _ = std::fs::remove_file(&temp);
        Error::io(path, "write", e)
    })
}
