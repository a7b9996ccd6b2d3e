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
        _ => {
            let format = if ext.is_empty() {
                "no extension".to_string()
            } else {
                format!("'.{ext}'")
            };
            let message = format!("unknown scene format {format}: expected .obj, .ply, .gltf, .glb or .toml");
            Err(Error::file(path, message))
        }
    }
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
