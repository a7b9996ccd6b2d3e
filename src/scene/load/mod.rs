//! Scene files: OBJ, PLY, glTF 2.0 / GLB meshes, the TOML scene description, pbrt-v4 and
//! Mitsuba 3 scenes (spec §7).
//!
//! The format follows the extension (case-insensitive): `.obj`, `.ply`, `.gltf`, `.glb`,
//! `.toml`, `.pbrt` (`.pbrt.gz`), `.xml`. A mesh file gives triangles, and a glTF file may also
//! give a camera and a spot light; a pbrt or Mitsuba scene gives its camera, film size and
//! spot light, and says what it skipped ([`crate::scene::SceneNotes`]). What a file lacks is
//! filled in from its bounds ([`framing_camera`], [`default_display_scale`]). Only positions
//! and faces are read: normals, texture coordinates and materials play no part in H (surfaces
//! are diffuse and two-sided, spec §1).
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
mod mitsuba;
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
        Format::Mitsuba => mitsuba::load(path, bytes)?,
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

/// The triangles of mesh `shape_index` of a Mitsuba `.serialized` file whose bytes are
/// `bytes` (versions 3 to 5), as a `<shape type="serialized">` reads them; errors name `path`.
pub fn load_serialized_bytes(
    path: &Path,
    bytes: &[u8],
    shape_index: usize,
) -> Result<crate::scene::mesh::Mesh> {
    let (positions, indices) =
        mitsuba::serialized(bytes, shape_index).map_err(|m| crate::error::Error::file(path, m))?;
    Ok(crate::scene::mesh::Mesh {
        positions: positions.iter().map(|p| p.as_vec3()).collect(),
        indices,
    })
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
        Ok(Format::Mitsuba) => return mitsuba::files_read(path),
        _ => {}
    }
    files
}
