//! Scenes: geometry, camera, spot light and display scale (SPEC §2, §5, §7).
//!
//! A scene comes from a built-in procedural generator (`cube`, `hall`, and the closed-form
//! validation scenes `sphere`, `slab`, `dome`) or from a file (OBJ, PLY, glTF/GLB, or the TOML
//! scene description of SPEC §7). Scenes are y-up unless their file says otherwise.

pub mod camera;
pub mod export;
pub mod light;
pub mod load;
pub mod mesh;
pub mod procedural;

use std::path::Path;

pub use camera::{Camera, CameraRays};
pub use light::SpotLight;
pub use mesh::{Bounds, Mesh};

use crate::error::Result;

/// Everything an estimator needs to render an HMD image of a scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// A short name for reports: the built-in name or the file name.
    pub name: String,
    /// The triangles, in scene units.
    pub mesh: Mesh,
    /// The camera the HMD image is rendered from.
    pub camera: Camera,
    /// The spot light for light-sourced photons, where the scene has one.
    pub light: Option<SpotLight>,
    /// Grey level per unit of H in pictures: grey = clamp(display_scale · H) (SPEC §4).
    pub display_scale: f32,
}

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

    /// Checks that the scene can be rendered: see [`Mesh::validate`] and [`Camera::validate`].
    pub fn validate(&self) -> Result<()> {
        self.mesh.validate()?;
        self.camera.validate()
    }

    /// Bounds of the vertices that triangles use ([`Mesh::bounds`]).
    pub fn bounds(&self) -> Bounds {
        self.mesh.bounds()
    }

    /// `l_diag`: the length of the bounding-box diagonal (SPEC §1, §4).
    pub fn diagonal(&self) -> f32 {
        self.bounds().diagonal()
    }

    /// A hash of everything in the scene that a render depends on: the vertices and triangles,
    /// the camera, the spot light and the display scale (not the name). The same on every
    /// machine; it changes when any file a scene was loaded from changes what was loaded.
    pub fn fingerprint(&self) -> u64 {
        let mut floats: Vec<f32> = self.mesh.positions.iter().flat_map(|p| p.to_array()).collect();
        let c = &self.camera;
        floats.extend(
            c.eye
                .to_array()
                .into_iter()
                .chain(c.target.to_array())
                .chain(c.up.to_array()),
        );
        floats.extend([c.fov_y_deg, self.display_scale]);
        if let Some(l) = &self.light {
            floats.extend(l.position.to_array().into_iter().chain(l.direction.to_array()));
            floats.push(l.cone_half_angle_deg);
        }
        let words = floats
            .iter()
            .map(|f| f.to_bits())
            .chain([self.light.is_some() as u32])
            .chain(self.mesh.indices.iter().flatten().copied());
        stable_hash(&words.flat_map(u32::to_le_bytes).collect::<Vec<u8>>())
    }
}

/// FNV-1a, 64-bit: a hash that is the same in every build and on every machine.
pub fn stable_hash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A camera for a file that has none: looking at the centre of `bounds` from the front
/// (+z), slightly above, far enough out to see all of it with a 50° field of view.
pub fn framing_camera(bounds: Bounds) -> Camera {
    let center = bounds.center();
    let radius = 0.5 * bounds.diagonal().max(f32::MIN_POSITIVE);
    let distance = radius / (25f32.to_radians()).sin();
    let toward_eye = glam::Vec3::new(0.0, 0.3, 1.0).normalize();
    Camera {
        eye: center + distance * toward_eye,
        target: center,
        up: glam::Vec3::Y,
        fov_y_deg: 50.0,
    }
}

/// Display scale for a scene that names none: grey 0.5 at a quarter of the diagonal.
pub fn default_display_scale(bounds: Bounds) -> f32 {
    2.0 / bounds.diagonal().max(f32::MIN_POSITIVE)
}
