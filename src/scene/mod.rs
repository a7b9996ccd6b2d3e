//! Scenes: geometry, camera, spot light and display scale (spec §2, §5, §7).
//!
//! A scene comes from a built-in procedural generator (`cube`, `hall`, and the closed-form
//! validation scenes `sphere`, `slab`, `dome`) or from a file (OBJ, PLY, glTF/GLB, or the TOML
//! scene description of spec §7). Scenes are y-up unless their file says otherwise.

pub mod camera;
pub mod export;
pub mod light;
pub mod load;
pub mod mesh;
pub mod model;
pub mod procedural;

use std::path::Path;

pub use camera::{Camera, CameraRays};
pub use light::SpotLight;
pub use mesh::{Bounds, Mesh};
pub use model::{default_display_scale, framing_camera, stable_hash, stable_hash_of, Scene, SceneNotes};

use crate::error::Result;

impl Scene {
    /// Every file [`Scene::load`] of `name_or_path` reads: none for a built-in scene; the file
    /// and, for a TOML scene, its meshes. Outputs are checked against them
    /// ([`crate::files::check_output`]).
    pub fn files_read(name_or_path: &str) -> Vec<std::path::PathBuf> {
        if procedural::BUILTIN_NAMES.contains(&name_or_path) {
            return vec![];
        }
        load::files_read(Path::new(name_or_path))
    }

    /// Loads a scene by built-in name (`cube`, `hall`, `sphere`, `slab`, `dome`) or file path.
    /// The geometry and camera are validated: the result can be rendered.
    pub fn load(name_or_path: &str) -> Result<Scene> {
        let scene = match procedural::builtin(name_or_path) {
            Some(scene) => scene,
            None => load::load_file(Path::new(name_or_path))?,
        };
        scene.validate()?;
        Ok(scene)
    }
}
