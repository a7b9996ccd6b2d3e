//! `hmdist.Scene`: loading and building one, what it holds, and pickling it. What it computes
//! is in `render.rs`, `cache.rs` and `rays.rs`.

use std::sync::OnceLock;

use glam::Vec3;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use hmdist::accel::{Accel, BuildQuality, Kernel};
use hmdist::scene::{default_display_scale, framing_camera, Camera, Mesh, SceneNotes};

use crate::camera::PyCamera;
use crate::convert::{py_error, value_error, vectors};

/// Counts by name, as [`SceneNotes`] keeps them.
type Counts = Vec<(String, usize)>;

/// A triangle scene, its camera and light, and its BVH once something casts rays. Read-only
/// once built (`frozen`): any number of threads may render it at once.
#[pyclass(name = "Scene", module = "hmdist._hmdist", frozen)]
pub(crate) struct PyScene {
    pub(crate) scene: hmdist::scene::Scene,
    accel: OnceLock<Accel>,
}

impl PyScene {
    pub(crate) fn new(scene: hmdist::scene::Scene) -> PyResult<Self> {
        scene.validate().map_err(py_error)?;
        Ok(PyScene {
            scene,
            accel: OnceLock::new(),
        })
    }

    /// The scene as `camera` sees it: itself, or (for another camera) a copy with that camera.
    pub(crate) fn seen_by(&self, camera: Option<&PyCamera>) -> std::borrow::Cow<'_, hmdist::scene::Scene> {
        match camera {
            Some(c) if c.camera != self.scene.camera => {
                let mut scene = self.scene.clone();
                scene.camera = c.camera;
                std::borrow::Cow::Owned(scene)
            }
            _ => std::borrow::Cow::Borrowed(&self.scene),
        }
    }

    /// The image size a call renders at where it is not the one `size=` names: the camera's,
    /// else (no `size=` either) the scene file's own, as a pbrt Film's; `None` leaves it to
    /// the keywords.
    pub(crate) fn size_for(&self, camera: Option<&PyCamera>, size_named: bool) -> Option<(u32, u32)> {
        match camera {
            Some(c) => Some(c.size),
            None if !size_named => self.scene.notes.size,
            None => None,
        }
    }

    /// The BVH for `hmd_at` and `cast`, built (without the GIL) at the first call.
    pub(crate) fn accel(&self, py: Python<'_>) -> PyResult<&Accel> {
        if let Some(accel) = self.accel.get() {
            return Ok(accel);
        }
        let kernel = Kernel::from_env().map_err(py_error)?;
        let mesh = &self.scene.mesh;
        let (accel, _) = py
            .detach(|| Accel::for_work(mesh, BuildQuality::Fast, 0, kernel))
            .map_err(py_error)?;
        Ok(self.accel.get_or_init(|| accel))
    }
}

#[pymethods]
impl PyScene {
    /// A built-in scene (cube, hall, sphere, slab, dome) or a file (OBJ, PLY, glTF, GLB, TOML,
    /// pbrt-v4 `.pbrt`/`.pbrt.gz`, Mitsuba 3 `.xml`).
    #[staticmethod]
    fn load(py: Python<'_>, name_or_path: &str) -> PyResult<Self> {
        let name = name_or_path.to_string();
        let scene = py
            .detach(move || hmdist::scene::Scene::load(&name))
            .map_err(py_error)?;
        PyScene::new(scene)
    }

    /// Triangles from float64 vertices [n, 3] and uint64 faces [m, 3] (indices into the
    /// vertices); a camera framing them.
    #[staticmethod]
    fn from_arrays(
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f64>,
        faces: PyReadonlyArray2<'_, u64>,
        name: &str,
    ) -> PyResult<Self> {
        let positions = vectors(&vertices)?;
        let indices = faces.as_slice().map_err(|e| value_error(e.to_string()))?;
        let mesh = py.detach(|| {
            let mut mesh = Mesh::new();
            mesh.add_vertices(positions.iter().copied());
            for (i, f) in indices.chunks_exact(3).enumerate() {
                if let Some(bad) = f.iter().find(|&&v| v >= positions.len() as u64) {
                    let message = format!(
                        "faces[{i}] refers to vertex {bad}, but there are {}",
                        positions.len()
                    );
                    return Err(value_error(message));
                }
                mesh.add_triangle(f[0] as u32, f[1] as u32, f[2] as u32);
            }
            mesh.validate().map_err(py_error)?;
            Ok(mesh)
        })?;
        let bounds = mesh.bounds();
        PyScene::new(hmdist::scene::Scene {
            name: name.into(),
            mesh,
            camera: framing_camera(bounds),
            light: None,
            display_scale: default_display_scale(bounds),
            notes: Default::default(),
        })
    }

    /// Triangles, bounds, diagonal, camera, light, display scale, and what its file said: the
    /// image `size` it asks for (or None), triangles by source, what was skipped, remarks.
    #[getter]
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.scene;
        let bounds = s.bounds();
        let info = PyDict::new(py);
        info.set_item("name", &s.name)?;
        info.set_item("triangles", s.mesh.triangle_count())?;
        info.set_item("bounds", (bounds.min.to_array(), bounds.max.to_array()))?;
        info.set_item("l_diag", bounds.diagonal())?;
        let camera = PyDict::new(py);
        camera.set_item("eye", s.camera.eye.to_array())?;
        camera.set_item("target", s.camera.target.to_array())?;
        camera.set_item("up", s.camera.up.to_array())?;
        camera.set_item("fov_y_deg", s.camera.fov_y_deg)?;
        camera.set_item("mirrored", s.camera.mirrored)?;
        info.set_item("camera", camera)?;
        let light = match s.light {
            Some(l) => {
                let light = PyDict::new(py);
                light.set_item("position", l.position.to_array())?;
                light.set_item("direction", l.direction.to_array())?;
                light.set_item("cone_half_angle_deg", l.cone_half_angle_deg)?;
                Some(light)
            }
            None => None,
        };
        info.set_item("light", light)?;
        info.set_item("display_scale", s.display_scale)?;
        info.set_item("size", s.notes.size)?;
        info.set_item("sources", s.notes.sources.clone())?;
        info.set_item("skipped", s.notes.skipped.clone())?;
        info.set_item("remarks", s.notes.remarks.clone())?;
        Ok(info)
    }

    /// For pickle: [`PyScene::from_state`] and the scene's name, vertices (float32 bytes),
    /// faces (uint32 bytes), camera, light, display scale and notes (size, sources, skipped,
    /// remarks).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let s = &slf.get().scene;
        let positions: Vec<u8> = s
            .mesh
            .positions
            .iter()
            .flat_map(|p| p.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        let indices: Vec<u8> = s
            .mesh
            .indices
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let c = &s.camera;
        let camera = (
            c.eye.to_array(),
            c.target.to_array(),
            c.up.to_array(),
            c.fov_y_deg,
            c.mirrored,
        );
        let light = s.light.map(|l| {
            (
                l.position.to_array(),
                l.direction.to_array(),
                l.cone_half_angle_deg,
            )
        });
        let args = (
            s.name.as_str(),
            pyo3::types::PyBytes::new(py, &positions),
            pyo3::types::PyBytes::new(py, &indices),
            camera,
            light,
            s.display_scale,
            (
                s.notes.size,
                s.notes.sources.clone(),
                s.notes.skipped.clone(),
                s.notes.remarks.clone(),
            ),
        );
        let from_state = slf.get_type().getattr("_from_state")?;
        Ok((from_state, args.into_pyobject(py)?.into_any()))
    }

    /// The scene [`PyScene::__reduce__`] described.
    #[staticmethod]
    #[allow(clippy::type_complexity)]
    fn _from_state(
        name: String,
        positions: &[u8],
        indices: &[u8],
        camera: ([f32; 3], [f32; 3], [f32; 3], f32, bool),
        light: Option<([f32; 3], [f32; 3], f32)>,
        display_scale: f32,
        notes: (Option<(u32, u32)>, Counts, Counts, Vec<String>),
    ) -> PyResult<Self> {
        let word = |b: &[u8]| -> [u8; 4] { [b[0], b[1], b[2], b[3]] };
        let floats: Vec<f32> = positions
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(word(b)))
            .collect();
        let ints: Vec<u32> = indices
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes(word(b)))
            .collect();
        let mesh = Mesh {
            positions: floats.chunks_exact(3).map(Vec3::from_slice).collect(),
            indices: ints.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        };
        let (eye, target, up, fov_y_deg, mirrored) = camera;
        let camera = Camera {
            eye: eye.into(),
            target: target.into(),
            up: up.into(),
            fov_y_deg,
            mirrored,
        };
        let light = light.map(
            |(position, direction, cone_half_angle_deg)| hmdist::scene::SpotLight {
                position: position.into(),
                direction: direction.into(),
                cone_half_angle_deg,
            },
        );
        PyScene::new(hmdist::scene::Scene {
            name,
            mesh,
            camera,
            light,
            display_scale,
            notes: SceneNotes {
                size: notes.0,
                sources: notes.1,
                skipped: notes.2,
                remarks: notes.3,
            },
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene('{}', {} triangles)",
            self.scene.name,
            self.scene.mesh.triangle_count()
        )
    }
}
