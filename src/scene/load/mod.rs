//! Scene files: OBJ, PLY, glTF 2.0 / GLB meshes and the TOML scene description (spec §7).
//!
//! The format follows the extension (case-insensitive): `.obj`, `.ply`, `.gltf`, `.glb`,
//! `.toml`. A mesh file gives triangles, and a glTF file may also give a camera and a spot
//! light; what a file lacks is filled in from its bounds ([`framing_camera`],
//! [`default_display_scale`]). Only positions and faces are read: normals, texture
//! coordinates and materials play no part in H (surfaces are diffuse and two-sided, spec §1).
//!
//! Every error is an [`Error::File`] naming the file, and the line where the format has
//! lines. Loaders never panic on bad input: where a parsing crate can panic on malformed
//! data, the call is guarded and the panic turned into an error, silently
//! ([`crate::error::catch_file_panic`]). [`load_bytes`] and [`load_mesh_bytes`] take the file's
//! bytes, already read (the fuzz targets in `fuzz/` call them); the path then gives the
//! format, the name in errors and the folder of the files the file refers to.

mod assembly;
mod common;
mod gltf;
mod meshes;
mod obj;
mod pbrt;
mod ply;
mod toml;

pub use common::MeshFile;
pub use meshes::{load_mesh, load_mesh_bytes};

use std::path::Path;

use crate::error::Result;
use crate::scene::model::{default_display_scale, framing_camera, Scene};
use common::{file_name, format_of, in_file, read_bytes, Format};

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
        Format::Pbrt => pbrt::load(path, bytes)?,
        _ => {
            let file = load_mesh_bytes(path, bytes)?;
            let bounds = file.mesh.bounds();
            Scene {
                name: file_name(path),
                camera: file.camera.unwrap_or_else(|| framing_camera(bounds)),
                light: file.light,
                display_scale: default_display_scale(bounds),
                notes: Default::default(),
                mesh: file.mesh,
            }
        }
    };
    scene.validate().map_err(|e| in_file(path, e))?;
    Ok(scene)
}

/// Every file that loading the scene file at `path` reads: the file, and a TOML scene's
/// meshes (as far as the file can be read; a file that cannot fails its load anyway).
pub fn files_read(path: &Path) -> Vec<std::path::PathBuf> {
    let mut files = vec![path.to_path_buf()];
    match format_of(path) {
        Ok(Format::SceneToml) => {
            if let Ok(bytes) = read_bytes(path) {
                files.extend(toml::mesh_paths(path, &bytes));
            }
        }
        Ok(Format::Pbrt) => return pbrt::files_read(path),
        _ => {}
    }
    files
}
