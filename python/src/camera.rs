//! `hmdist.Camera`.

use glam::Vec3;
use pyo3::prelude::*;

use hmdist::scene::Camera;

use crate::convert::{numbers, shortest, value_error, vec3};

/// A pinhole camera: where it is, what it looks at, and the image it takes.
#[pyclass(name = "Camera", module = "hmdist._hmdist", from_py_object)]
#[derive(Clone)]
pub(crate) struct PyCamera {
    pub(crate) camera: Camera,
    pub(crate) size: (u32, u32),
}

#[pymethods]
impl PyCamera {
    /// `eye`, `target` and `up`: any 3 numbers (list, tuple, numpy array); `size`: any 2
    /// positive integers (width, height); `mirrored`: the picture's right is `up × forward`
    /// (a pbrt camera's).
    #[new]
    #[pyo3(signature = (eye, target, up = None, fov_y_deg = 60.0, size = None, mirrored = false))]
    fn new(
        eye: &Bound<'_, PyAny>,
        target: &Bound<'_, PyAny>,
        up: Option<&Bound<'_, PyAny>>,
        fov_y_deg: f32,
        size: Option<&Bound<'_, PyAny>>,
        mirrored: bool,
    ) -> PyResult<Self> {
        let camera = Camera {
            eye: vec3("eye", eye)?,
            target: vec3("target", target)?,
            up: up.map_or(Ok(Vec3::Y), |up| vec3("up", up))?,
            fov_y_deg,
            mirrored,
        };
        let size = match size {
            None => (512, 512),
            Some(size) => {
                let wh = numbers("size", size, 2)?;
                let whole =
                    |v: f64| (v >= 1.0 && v <= u32::MAX as f64 && v.fract() == 0.0).then_some(v as u32);
                match (whole(wh[0]), whole(wh[1])) {
                    (Some(w), Some(h)) => (w, h),
                    _ => {
                        return Err(value_error(format!(
                            "size must be two positive integers, not {wh:?}"
                        )))
                    }
                }
            }
        };
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err(value_error(format!(
                "fov_y_deg must be in (0, 180), not {fov_y_deg}"
            )));
        }
        camera
            .validate()
            .map_err(|e| value_error(e.to_string().replacen("bad scene: ", "bad camera: ", 1)))?;
        Ok(PyCamera { camera, size })
    }

    /// Where the camera is.
    #[getter]
    fn eye(&self) -> [f64; 3] {
        self.camera.eye.to_array().map(shortest)
    }

    /// The point it looks at.
    #[getter]
    fn target(&self) -> [f64; 3] {
        self.camera.target.to_array().map(shortest)
    }

    /// The world's up direction.
    #[getter]
    fn up(&self) -> [f64; 3] {
        self.camera.up.to_array().map(shortest)
    }

    /// The full vertical field of view, in degrees.
    #[getter]
    fn fov_y_deg(&self) -> f64 {
        shortest(self.camera.fov_y_deg)
    }

    /// Whether the picture's right is `up × forward` rather than `forward × up`.
    #[getter]
    fn mirrored(&self) -> bool {
        self.camera.mirrored
    }

    /// The image it takes: (width, height).
    #[getter]
    fn size(&self) -> (u32, u32) {
        self.size
    }

    /// For pickle: the constructor and its arguments.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let c = slf.borrow();
        let args = (c.eye(), c.target(), c.up(), c.fov_y_deg(), c.size, c.mirrored());
        Ok((
            slf.get_type().into_any(),
            args.into_pyobject(slf.py())?.into_any(),
        ))
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .extract::<PyCamera>()
            .is_ok_and(|o| o.camera == self.camera && o.size == self.size)
    }

    fn __repr__(&self) -> String {
        let c = &self.camera;
        format!(
            "Camera(eye={:?}, target={:?}, up={:?}, fov_y_deg={}, size={:?}{})",
            c.eye.to_array(),
            c.target.to_array(),
            c.up.to_array(),
            c.fov_y_deg,
            self.size,
            if c.mirrored { ", mirrored=True" } else { "" }
        )
    }
}
