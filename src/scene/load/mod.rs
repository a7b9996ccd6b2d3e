//! Scene files: OBJ, PLY, glTF 2.0 / GLB meshes and the TOML scene description (SPEC §7).
//!
//! The format follows the extension (case-insensitive): `.obj`, `.ply`, `.gltf`, `.glb`,
//! `.toml`. A mesh file gives triangles, and a glTF file may also give a camera and a spot
//! light; what a file lacks is filled in from its bounds ([`framing_camera`],
//! [`default_display_scale`]). Only positions and faces are read: normals, texture
//! coordinates and materials play no part in H (surfaces are diffuse and two-sided, SPEC §1).
//!
//! Every error is an [`Error::File`] naming the file, and the line where the format has
//! lines. Loaders never panic on bad input: where a parsing crate can panic on malformed
//! data, the call is guarded and the panic turned into an error, silently
//! ([`crate::error::catch_file_panic`]). [`load_bytes`] and [`load_mesh_bytes`] take the file's
//! bytes, already read (the fuzz targets in `fuzz/` call them); the path then gives the
//! format, the name in errors and the folder of the files the file refers to.

mod gltf;
mod obj;
mod ply;
mod toml;

use std::path::Path;

use crate::error::{Error, Result};
use crate::scene::{default_display_scale, framing_camera, Camera, Mesh, Scene, SpotLight};

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
enum Format {
    Obj,
    Ply,
    Gltf,
    SceneToml,
}

fn format_of(path: &Path) -> Result<Format> {
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

/// Loads a scene file: a mesh file (with a framing camera unless it carries one) or a TOML
/// scene description. The result passes [`Scene::validate`].
pub fn load_file(path: &Path) -> Result<Scene> {
    format_of(path)?;
    load_bytes(path, &read_bytes(path)?)
}

/// [`load_file`] of the file at `path` whose bytes are `bytes`.
pub fn load_bytes(path: &Path, bytes: &[u8]) -> Result<Scene> {
    let scene = match format_of(path)? {
        Format::SceneToml => toml::load_scene(path, bytes)?,
        _ => {
            let file = load_mesh_bytes(path, bytes)?;
            let bounds = file.mesh.bounds();
            Scene {
                name: file_name(path),
                camera: file.camera.unwrap_or_else(|| framing_camera(bounds)),
                light: file.light,
                display_scale: default_display_scale(bounds),
                mesh: file.mesh,
            }
        }
    };
    scene.validate().map_err(|e| in_file(path, e))?;
    Ok(scene)
}

/// Loads a mesh file (OBJ, PLY, glTF/GLB). The mesh is checked: it has triangles, every
/// index is in range and every used vertex is finite.
pub fn load_mesh(path: &Path) -> Result<MeshFile> {
    format_of(path)?;
    load_mesh_bytes(path, &read_bytes(path)?)
}

/// [`load_mesh`] of the file at `path` whose bytes are `bytes`.
pub fn load_mesh_bytes(path: &Path, bytes: &[u8]) -> Result<MeshFile> {
    let file = match format_of(path)? {
        Format::Obj => obj::load(path, bytes)?,
        Format::Ply => ply::load(path, bytes)?,
        Format::Gltf => gltf::load(path, bytes)?,
        Format::SceneToml => {
            return Err(Error::file(
                path,
                "a TOML scene description cannot be used as a mesh: expected .obj, .ply, .gltf or .glb",
            ))
        }
    };
    file.mesh.validate().map_err(|e| in_file(path, e))?;
    Ok(file)
}

/// The name a scene loaded from `path` goes by in reports: its file name.
fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// Reads the whole file, with the error phrased for a person.
fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    crate::files::read_regular(path)
}

/// Every file that loading the scene file at `path` reads: the file, and a TOML scene's
/// meshes (as far as the file can be read; a file that cannot fails its load anyway).
pub fn files_read(path: &Path) -> Vec<std::path::PathBuf> {
    let mut files = vec![path.to_path_buf()];
    if let (Ok(Format::SceneToml), Ok(bytes)) = (format_of(path), read_bytes(path)) {
        files.extend(toml::mesh_paths(path, &bytes));
    }
    files
}

/// Turns a geometry error ("the scene has no triangles") into one that names the file.
fn in_file(path: &Path, err: Error) -> Error {
    match err {
        Error::Scene(message) => Error::file(path, message),
        other => other,
    }
}

/// The 1-based line of byte `offset` in `text`.
fn line_of_offset(text: &[u8], offset: usize) -> usize {
    1 + text[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}
