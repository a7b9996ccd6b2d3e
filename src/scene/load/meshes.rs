//! Mesh files (OBJ, PLY, glTF/GLB) by their format, checked.

use std::path::Path;

use super::common::{format_of, in_file, read_bytes, Format, MeshFile};
use super::{gltf, obj, ply};
use crate::error::{Error, Result};

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
        Format::SceneToml | Format::Pbrt | Format::Mitsuba => {
            return Err(Error::file(
                path,
                "a scene description (TOML, pbrt, Mitsuba) cannot be used as a mesh: expected .obj, .ply, .gltf or .glb",
            ))
        }
    };
    file.mesh.validate().map_err(|e| in_file(path, e))?;
    Ok(file)
}
