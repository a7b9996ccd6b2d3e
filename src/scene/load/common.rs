//! What the loaders share: the mesh file they return, the format by extension, file names,
//! reading, and errors that name the file and its line.

use std::path::Path;

use crate::error::{Error, Result};
use crate::scene::{Camera, Mesh, SpotLight};

/// What a mesh file holds: its triangles, and the camera and spot light where the format can
/// carry them (glTF). Positions are in the file's world space (node transforms applied).
#[derive(Clone, Debug, Default)]
pub struct MeshFile {
    /// The triangles, in world space.
    pub mesh: Mesh,
    /// The first perspective camera of a glTF file; `None` for OBJ and PLY.
    pub camera: Option<Camera>,
    /// The first spot light of a glTF file (`KHR_lights_punctual`); `None` for OBJ and PLY.
    pub light: Option<SpotLight>,
}

/// The file formats hmdist reads, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Format {
    Obj,
    Ply,
    Gltf,
    SceneToml,
    /// pbrt-v4, `.pbrt` or `.pbrt.gz`.
    Pbrt,
    /// Mitsuba 3 XML, `.xml`.
    Mitsuba,
}

pub(super) fn format_of(path: &Path) -> Result<Format> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "obj" => Ok(Format::Obj),
        "ply" => Ok(Format::Ply),
        "gltf" | "glb" => Ok(Format::Gltf),
        "toml" => Ok(Format::SceneToml),
        "pbrt" => Ok(Format::Pbrt),
        "gz" if lower_name(path).ends_with(".pbrt.gz") => Ok(Format::Pbrt),
        "xml" => Ok(Format::Mitsuba),
        _ => {
            let format = if ext.is_empty() {
                "no extension".to_string()
            } else {
                format!("'.{ext}'")
            };
            let message = format!("unknown scene format {format}: expected .obj, .ply, .gltf, .glb, .toml, .pbrt, .pbrt.gz or .xml (Mitsuba 3)");
            Err(Error::file(path, message))
        }
    }
}

/// The file's name in lower case.
fn lower_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// The most a gzipped file may hold once inflated.
pub(super) const MAX_INFLATED: u64 = 4 << 30;

/// `bytes`, inflated where the file's name ends `.gz` (pbrt's rule for scenes and PLY
/// meshes), as they are otherwise.
pub(super) fn gunzip_if_named(path: &Path, bytes: &[u8]) -> Result<Vec<u8>> {
    if !lower_name(path).ends_with(".gz") {
        return Ok(bytes.to_vec());
    }
    use std::io::Read;
    let mut inflated = Vec::new();
    flate2::read::MultiGzDecoder::new(bytes)
        .take(MAX_INFLATED + 1)
        .read_to_end(&mut inflated)
        .map_err(|e| Error::file(path, format!("not a readable gzip file: {e}")))?;
    if inflated.len() as u64 > MAX_INFLATED {
        return Err(Error::file(path, "inflates to more than 4 GiB"));
    }
    Ok(inflated)
}

/// The name a scene loaded from `path` goes by in reports: its file name.
pub(super) fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// Reads the whole file, with the error phrased for a person.
pub(super) fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    crate::files::read_regular(path)
}

/// Turns a geometry error ("the scene has no triangles") into one that names the file.
pub(super) fn in_file(path: &Path, err: Error) -> Error {
    match err {
        Error::Scene(message) => Error::file(path, message),
        other => other,
    }
}

/// The 1-based line of byte `offset` in `text`.
pub(super) fn line_of_offset(text: &[u8], offset: usize) -> usize {
    1 + text[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// A line of the file being read and what is wrong there.
pub(super) type Located = (usize, String);

/// An error of a scene file that names other files: at a line of the file being read, or one
/// already complete (from an included or mesh file, which names itself).
pub(super) enum Failure {
    Here(Located),
    Error(Error),
}

impl From<Located> for Failure {
    fn from(located: Located) -> Self {
        Failure::Here(located)
    }
}

impl Failure {
    /// The error, a line of `file` where it is one.
    pub(super) fn in_file(self, file: &Path) -> Error {
        match self {
            Failure::Here((line, message)) => Error::file_line(file, line, message),
            Failure::Error(e) => e,
        }
    }
}
