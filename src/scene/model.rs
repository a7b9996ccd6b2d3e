//! The scene itself: its triangles, camera, light and display scale, what is derived from
//! them (bounds, diagonal, fingerprint), and the camera and scale a scene without its own
//! gets. Loading one (by name or file) is `Scene::load`, in the module above.

use crate::error::Result;
use crate::scene::camera::Camera;
use crate::scene::light::SpotLight;
use crate::scene::mesh::{Bounds, Mesh};

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
    /// Grey level per unit of H in pictures: grey = clamp(display_scale · H) (spec §4).
    pub display_scale: f32,
    /// What the scene's file said besides (its image size) and what was made of it (where
    /// the triangles came from, what was skipped). Not part of the [`Scene::fingerprint`].
    pub notes: SceneNotes,
}

/// What loading a scene file found beyond triangles, camera and light: the image size the
/// file asks for, the triangles by their source, and what was read and not used. Empty for
/// built-in scenes and for mesh files.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneNotes {
    /// The image size, (width, height), the file renders at (pbrt's `Film`, Mitsuba's
    /// `<film>`): the size of a render that names none.
    pub size: Option<(u32, u32)>,
    /// Triangles by where they came from ("trianglemesh", "plymesh geometry/bunny.ply",
    /// "sphere", ...), in the order first met.
    pub sources: Vec<(String, usize)>,
    /// Things read and not used (a `curve` shape, an `infinite` light), by kind, with counts,
    /// in the order first met.
    pub skipped: Vec<(String, usize)>,
    /// Other things the user should know, once each ("2 object instances flattened").
    pub remarks: Vec<String>,
}

impl SceneNotes {
    /// Counts `triangles` more for `source`.
    pub fn add_source(&mut self, source: &str, triangles: usize) {
        add_count(&mut self.sources, source, triangles);
    }

    /// Counts one more skipped `kind`.
    pub fn skip(&mut self, kind: &str) {
        add_count(&mut self.skipped, kind, 1);
    }

    /// Adds a remark, unless it is already there.
    pub fn remark(&mut self, remark: impl Into<String>) {
        let remark = remark.into();
        if !self.remarks.contains(&remark) {
            self.remarks.push(remark);
        }
    }

    /// The skipped things as one line ("2 curve shapes, 1 infinite light"); `None` if none.
    pub fn skipped_line(&self) -> Option<String> {
        (!self.skipped.is_empty()).then(|| {
            let parts: Vec<String> = self.skipped.iter().map(|(k, n)| format!("{n} × {k}")).collect();
            parts.join(", ")
        })
    }
}

fn add_count(counts: &mut Vec<(String, usize)>, key: &str, n: usize) {
    match counts.iter_mut().find(|(k, _)| k == key) {
        Some((_, count)) => *count += n,
        None => counts.push((key.to_string(), n)),
    }
}

impl Scene {
    /// Checks that the scene can be rendered: see [`Mesh::validate`] and [`Camera::validate`].
    pub fn validate(&self) -> Result<()> {
        self.mesh.validate()?;
        self.camera.validate()
    }

    /// Bounds of the vertices that triangles use ([`Mesh::bounds`]).
    pub fn bounds(&self) -> Bounds {
        self.mesh.bounds()
    }

    /// `l_diag`: the length of the bounding-box diagonal (spec §1, §4).
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
        // A mirrored camera adds a word; an unmirrored one leaves every older fingerprint as it was.
        let words = floats
            .iter()
            .map(|f| f.to_bits())
            .chain([self.light.is_some() as u32])
            .chain(self.camera.mirrored.then_some(u32::from_le_bytes(*b"mirr")))
            .chain(self.mesh.indices.iter().flatten().copied());
        stable_hash_of(words.flat_map(u32::to_le_bytes))
    }
}

/// FNV-1a, 64-bit: a hash that is the same in every build and on every machine.
pub fn stable_hash(bytes: &[u8]) -> u64 {
    stable_hash_of(bytes.iter().copied())
}

/// [`stable_hash`] of bytes as they come, with no buffer to hold them.
pub fn stable_hash_of(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
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
        mirrored: false,
    }
}

/// Display scale for a scene that names none: grey 0.5 at a quarter of the diagonal.
pub fn default_display_scale(bounds: Bounds) -> f32 {
    2.0 / bounds.diagonal().max(f32::MIN_POSITIVE)
}
