//! The TOML scene description of spec §7: meshes placed in a scene, camera, spot light and
//! display scale.
//!
//! ```toml
//! [[mesh]]                     # one or more
//! path = "room.obj"            # OBJ, PLY, glTF or GLB, relative to this file
//! scale = 2.0                  # optional, applied first,
//! rotate_y_deg = 90.0          # optional, then a rotation about +y,
//! translate = [0, 0, 0]        # optional, then a translation
//! [camera]                     # optional: else the first glTF camera, else a framing one
//! eye = [1.0, 4.0, 8.0]
//! target = [0.0, 1.5, 0.0]
//! up = [0, 1, 0]               # optional, +y by default
//! fov_y_deg = 60.0
//! [light]                      # optional: else the first glTF spot light, else none
//! position = [0, 9.9, 0]
//! direction = [0, -1, 0]       # normalised on loading; must not be zero
//! cone_half_angle_deg = 45.0   # 0 < angle <= 180
//! [display]                    # optional: else grey 0.5 at a quarter of the diagonal
//! scale = 0.14
//! ```
//!
//! Unknown keys are errors (a typo must not silently fall back to a default). A glTF mesh's
//! camera and light are moved with the mesh's `scale`/`rotate_y_deg`/`translate`.

use std::path::Path;

use ::toml::Spanned;
use glam::{Affine3A, Quat, Vec3};
use serde::Deserialize;

use super::common::{file_name, line_of_offset};
use super::meshes::load_mesh;
use crate::error::{Error, Result};
use crate::scene::{default_display_scale, framing_camera, Camera, Mesh, Scene, SpotLight};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneToml {
    #[serde(default)]
    mesh: Vec<Spanned<MeshEntry>>,
    camera: Option<Spanned<CameraEntry>>,
    light: Option<Spanned<LightEntry>>,
    display: Option<Spanned<DisplayEntry>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshEntry {
    path: String,
    scale: Option<f32>,
    rotate_y_deg: Option<f32>,
    #[serde(default, deserialize_with = "maybe_three")]
    translate: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraEntry {
    #[serde(deserialize_with = "three")]
    eye: [f32; 3],
    #[serde(deserialize_with = "three")]
    target: [f32; 3],
    #[serde(default, deserialize_with = "maybe_three")]
    up: Option<[f32; 3]>,
    fov_y_deg: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightEntry {
    #[serde(deserialize_with = "three")]
    position: [f32; 3],
    #[serde(deserialize_with = "three")]
    direction: [f32; 3],
    cone_half_angle_deg: f32,
}

/// A vector of exactly three numbers (serde's `[f32; 3]` takes the first three of four).
fn three<'de, D: serde::Deserializer<'de>>(deserializer: D) -> std::result::Result<[f32; 3], D::Error> {
    let numbers = Vec::<f32>::deserialize(deserializer)?;
    <[f32; 3]>::try_from(numbers.as_slice()).map_err(|_| {
        serde::de::Error::custom(format!(
            "expected exactly three numbers [x, y, z], found {}",
            numbers.len()
        ))
    })
}

/// [`three`], where the vector may be left out.
fn maybe_three<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> std::result::Result<Option<[f32; 3]>, D::Error> {
    #[derive(Deserialize)]
    struct Three(#[serde(deserialize_with = "three")] [f32; 3]);
    Ok(Option::<Three>::deserialize(deserializer)?.map(|t| t.0))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DisplayEntry {
    scale: f32,
}

/// The mesh files the TOML scene at `path` (bytes `bytes`) names, resolved beside it; none
/// where it does not parse.
pub(super) fn mesh_paths(path: &Path, bytes: &[u8]) -> Vec<std::path::PathBuf> {
    let directory = path.parent().unwrap_or(Path::new(""));
    let parsed = std::str::from_utf8(bytes)
        .ok()
        .and_then(|text| ::toml::from_str::<SceneToml>(text).ok());
    parsed.map_or(vec![], |d| {
        d.mesh.iter().map(|e| directory.join(&e.get_ref().path)).collect()
    })
}

/// Loads the scene described by the TOML file at `path`, whose bytes are `bytes`, with its
/// meshes.
pub(super) fn load_scene(path: &Path, bytes: &[u8]) -> Result<Scene> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| Error::file_line(path, line_of_offset(bytes, e.valid_up_to()), "not UTF-8 text"))?;
    let description: SceneToml = ::toml::from_str(text).map_err(|e| {
        let message = e.message().trim().to_string();
        match e.span() {
            Some(span) => Error::file_line(path, line_of_offset(bytes, span.start), message),
            None => Error::file(path, message),
        }
    })?;
    // The line where a table starts, for errors about its values.
    let line_of = |span: std::ops::Range<usize>| line_of_offset(bytes, span.start);

    if description.mesh.is_empty() {
        return Err(Error::file(
            path,
            "the scene names no meshes: add a [[mesh]] table with a path",
        ));
    }
    let directory = path.parent().unwrap_or(Path::new(""));
    let mut mesh = Mesh::new();
    let mut file_camera = None;
    let mut file_light = None;
    for entry in &description.mesh {
        let line = line_of(entry.span());
        let entry = entry.get_ref();
        let transform = placement(entry).map_err(|m| Error::file_line(path, line, m))?;
        let file = load_mesh(&directory.join(&entry.path))
            .map_err(|e| Error::file_line(path, line, format!("mesh '{}': {e}", entry.path)))?;
        mesh.append_transformed(&file.mesh, transform);
        file_camera = file_camera.or(file.camera.map(|c| move_camera(c, transform)));
        file_light = file_light.or(file.light.map(|l| move_light(l, transform)));
    }
    let bounds = mesh.bounds();

    let camera = match &description.camera {
        Some(entry) => {
            let c = entry.get_ref();
            let camera = Camera {
                eye: Vec3::from(c.eye),
                target: Vec3::from(c.target),
                up: c.up.map_or(Vec3::Y, Vec3::from),
                fov_y_deg: c.fov_y_deg,
                mirrored: false,
            };
            camera
                .validate()
                .map_err(|e| at_line(path, line_of(entry.span()), e))?;
            camera
        }
        None => file_camera.unwrap_or_else(|| framing_camera(bounds)),
    };
    let light = match &description.light {
        Some(entry) => {
            let light = spot_light(entry.get_ref());
            Some(light.map_err(|m| Error::file_line(path, line_of(entry.span()), m))?)
        }
        None => file_light,
    };
    let display_scale = match &description.display {
        Some(entry) => {
            let scale = entry.get_ref().scale;
            if !(scale.is_finite() && scale > 0.0) {
                let message = format!("the display scale must be a positive number, not {scale}");
                return Err(Error::file_line(path, line_of(entry.span()), message));
            }
            scale
        }
        None => default_display_scale(bounds),
    };
    Ok(Scene {
        name: file_name(path),
        mesh,
        camera,
        light,
        display_scale,
        notes: Default::default(),
    })
}

/// The mesh's placement: scale, then rotation about +y, then translation.
fn placement(entry: &MeshEntry) -> std::result::Result<Affine3A, String> {
    let scale = entry.scale.unwrap_or(1.0);
    let degrees = entry.rotate_y_deg.unwrap_or(0.0);
    let translate = Vec3::from(entry.translate.unwrap_or([0.0; 3]));
    if !(scale.is_finite() && scale != 0.0) {
        return Err(format!("scale must be a non-zero number, not {scale}"));
    }
    if !degrees.is_finite() || !translate.is_finite() {
        return Err("rotate_y_deg and translate must be finite numbers".to_string());
    }
    Ok(Affine3A::from_scale_rotation_translation(
        Vec3::splat(scale),
        Quat::from_rotation_y(degrees.to_radians()),
        translate,
    ))
}

fn spot_light(entry: &LightEntry) -> std::result::Result<SpotLight, String> {
    let position = Vec3::from(entry.position);
    let direction = Vec3::from(entry.direction);
    let angle = entry.cone_half_angle_deg;
    if !position.is_finite() || !direction.is_finite() {
        return Err("the light's position and direction must be finite numbers".to_string());
    }
    let Some(direction) = crate::sampling::unit(direction) else {
        return Err("the light's direction must not be zero".to_string());
    };
    if !(angle > 0.0 && angle <= 180.0) {
        return Err(format!(
            "the light's cone half-angle must be between 0 and 180 degrees, not {angle}"
        ));
    }
    Ok(SpotLight {
        position,
        direction,
        cone_half_angle_deg: angle,
    })
}

/// The camera moved with its mesh; a reflecting placement (a negative scale) mirrors its picture.
fn move_camera(camera: Camera, transform: Affine3A) -> Camera {
    Camera {
        eye: transform.transform_point3(camera.eye),
        target: transform.transform_point3(camera.target),
        up: transform.transform_vector3(camera.up).normalize_or_zero(),
        fov_y_deg: camera.fov_y_deg,
        mirrored: camera.mirrored ^ (transform.matrix3.determinant() < 0.0),
    }
}

fn move_light(light: SpotLight, transform: Affine3A) -> SpotLight {
    SpotLight {
        position: transform.transform_point3(light.position),
        direction: transform.transform_vector3(light.direction).normalize_or_zero(),
        cone_half_angle_deg: light.cone_half_angle_deg,
    }
}

/// A scene error (here: about the camera) at a line of the TOML file.
fn at_line(path: &Path, line: usize, err: Error) -> Error {
    match err {
        Error::Scene(message) => Error::file_line(path, line, message),
        other => other,
    }
}
