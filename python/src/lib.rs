//! `hmdist._hmdist`: the Rust half of the Python package. The Python half (`hmdist/__init__.py`)
//! checks and converts arrays; everything here receives C-contiguous float64 (and uint64) arrays
//! of the right shape, releases the GIL while hmdist works, and turns hmdist's errors into
//! Python exceptions: `ValueError` for bad parameters and scenes, `OSError` for files,
//! `hmdist.DeviceError` for GPU failures.
//!
//! Ctrl-C: long work ([`interruptible`]) runs on a helper thread while the calling thread
//! looks at Python's signals every [`SIGNAL_POLL`]; a `KeyboardInterrupt` (or any exception a
//! signal handler raises) asks hmdist to stop ([`hmdist::interrupt`]), waits for the work to
//! return, withdraws the request and raises it, so the next call runs normally.

use std::sync::OnceLock;
use std::time::Duration;

use glam::Vec3;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString};

use hmdist::accel::{Accel, BuildQuality, Kernel, RayCaster};
use hmdist::cache::{cache, CacheParams, Range, Spacing};
use hmdist::error::Error;
use hmdist::estimators::{registry, Aov, Estimator, Gather};
use hmdist::image::HmdImage;
use hmdist::points::{hmd_at, PointQuery, SurfacePoint};
use hmdist::progress::{Progress, Silent};
use hmdist::render::{render, RenderOptions};
use hmdist::scene::{default_display_scale, framing_camera, Camera, Mesh};

create_exception!(_hmdist, DeviceError, PyException, "A GPU is missing or failed.");

/// hmdist's error as the Python exception of its kind, with hmdist's message.
fn py_error(error: Error) -> PyErr {
    let message = error.to_string();
    match error {
        Error::File { .. } => PyOSError::new_err(message),
        Error::Device { .. } => DeviceError::new_err(message),
        Error::Parameter { .. } | Error::Scene(_) => PyValueError::new_err(message),
        Error::Interrupted => PyKeyboardInterrupt::new_err(message),
    }
}

fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// Rows of an [n, 3] float64 array as vectors.
fn vectors(array: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<Vec3>> {
    let slice = array.as_slice().map_err(|e| value_error(e.to_string()))?;
    Ok(slice
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
        .collect())
}

/// How often the calling thread looks at Python's signals while hmdist works.
const SIGNAL_POLL: Duration = Duration::from_millis(25);

/// Runs `work` without the GIL, stopping it on Ctrl-C (see the module docs): the work's result,
/// or the exception a signal handler raised.
fn interruptible<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    std::thread::scope(|scope| {
        let worker = scope.spawn(work);
        let mut raised = None;
        while !worker.is_finished() {
            py.detach(|| std::thread::park_timeout(SIGNAL_POLL));
            if raised.is_none() {
                if let Err(error) = py.check_signals() {
                    hmdist::interrupt::request();
                    raised = Some(error);
                }
            }
        }
        let result = py
            .detach(|| worker.join())
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        match raised {
            Some(error) => {
                hmdist::interrupt::clear();
                Err(error)
            }
            None => Ok(result),
        }
    })
}

/// Any sequence or array of 3 numbers (a list, a tuple, a numpy array) as a vector.
fn vec3(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Vec3> {
    let numbers = numbers(name, value, 3)?;
    Ok(Vec3::new(numbers[0] as f32, numbers[1] as f32, numbers[2] as f32))
}

/// Any sequence or array of `count` numbers, or a `ValueError` naming `name`.
fn numbers(name: &str, value: &Bound<'_, PyAny>, count: usize) -> PyResult<Vec<f64>> {
    let bad = || {
        let shown = value.repr().map_or_else(|_| "?".to_string(), |r| r.to_string());
        value_error(format!("{name} must be {count} numbers, not {shown}"))
    };
    let items = value.try_iter().map_err(|_| bad())?;
    let numbers = items
        .map(|item| item?.extract::<f64>())
        .collect::<PyResult<Vec<f64>>>()
        .map_err(|_| bad())?;
    if numbers.len() != count {
        return Err(bad());
    }
    Ok(numbers)
}

/// `v` as the float64 its shortest decimal form reads as (0.3f32 as 0.3, not 0.30000001192…).
fn shortest(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(v as f64)
}

/// A pinhole camera: where it is, what it looks at, and the image it takes.
#[pyclass(name = "Camera", module = "hmdist._hmdist", from_py_object)]
#[derive(Clone)]
struct PyCamera {
    camera: Camera,
    size: (u32, u32),
}

#[pymethods]
impl PyCamera {
    /// `eye`, `target` and `up`: any 3 numbers (list, tuple, numpy array); `size`: any 2
    /// positive integers (width, height).
    #[new]
    #[pyo3(signature = (eye, target, up = None, fov_y_deg = 60.0, size = None))]
    fn new(
        eye: &Bound<'_, PyAny>,
        target: &Bound<'_, PyAny>,
        up: Option<&Bound<'_, PyAny>>,
        fov_y_deg: f32,
        size: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let camera = Camera {
            eye: vec3("eye", eye)?,
            target: vec3("target", target)?,
            up: up.map_or(Ok(Vec3::Y), |up| vec3("up", up))?,
            fov_y_deg,
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

    /// The image it takes: (width, height).
    #[getter]
    fn size(&self) -> (u32, u32) {
        self.size
    }

    /// For pickle: the constructor and its arguments.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let c = slf.borrow();
        let args = (c.eye(), c.target(), c.up(), c.fov_y_deg(), c.size);
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
            "Camera(eye={:?}, target={:?}, up={:?}, fov_y_deg={}, size={:?})",
            c.eye.to_array(),
            c.target.to_array(),
            c.up.to_array(),
            c.fov_y_deg,
            self.size
        )
    }
}

/// A triangle scene, its camera and light, and its BVH once something casts rays. Read-only
/// once built (`frozen`): any number of threads may render it at once.
#[pyclass(name = "Scene", module = "hmdist._hmdist", frozen)]
struct PyScene {
    scene: hmdist::scene::Scene,
    accel: OnceLock<Accel>,
}

impl PyScene {
    fn new(scene: hmdist::scene::Scene) -> PyResult<Self> {
        scene.validate().map_err(py_error)?;
        Ok(PyScene {
            scene,
            accel: OnceLock::new(),
        })
    }

    /// The scene as `camera` sees it: itself, or (for another camera) a copy with that camera.
    fn seen_by(&self, camera: Option<&PyCamera>) -> std::borrow::Cow<'_, hmdist::scene::Scene> {
        match camera {
            Some(c) if c.camera != self.scene.camera => {
                let mut scene = self.scene.clone();
                scene.camera = c.camera;
                std::borrow::Cow::Owned(scene)
            }
            _ => std::borrow::Cow::Borrowed(&self.scene),
        }
    }

    /// The BVH for `hmd_at` and `cast`, built (without the GIL) at the first call.
    fn accel(&self, py: Python<'_>) -> PyResult<&Accel> {
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

/// A JSON text as a Python object.
fn json_to_py<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

#[pymethods]
impl PyScene {
    /// A built-in scene (cube, hall, sphere, slab, dome) or a file (OBJ, PLY, glTF, GLB, TOML).
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
        })
    }

    /// Triangles, bounds, diagonal, camera, light and display scale.
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
        Ok(info)
    }

    /// An irradiance cache (`hmdist cache`): E per pixel (float32 [height, width], NaN for
    /// background), the report as a dict, and the records as a dict of arrays: `pixel`
    /// (uint32, row-major), `e`, `radius` (float32), `level` (uint32), and per pixel `used`
    /// (records each pixel used) and, with `reference`, `relative_error` (float32 [height,
    /// width]). `params`: the render's own (size, seed, threads, max_distance, bvh),
    /// irradiance's (rays, weighting, sampler, absorption) and the cache's (accuracy, spacing,
    /// clamp_pixels, clamp_scene, neighbour_clamp, gradients); `oracle` and `reference` are float32 [height, width] images
    /// of H and of E.
    #[pyo3(signature = (camera, params, progress, oracle = None, reference = None))]
    fn cache<'py>(
        &self,
        py: Python<'py>,
        camera: Option<PyCamera>,
        params: &Bound<'py, PyDict>,
        progress: bool,
        oracle: Option<PyReadonlyArray2<'py, f32>>,
        reference: Option<PyReadonlyArray2<'py, f32>>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyDict>)> {
        let mut cache_params = CacheParams::default();
        let rest = PyDict::new(py);
        for (key, value) in params.iter() {
            let key: String = key.extract()?;
            let bad = |e: PyErr| value_error(format!("{key}: {e}"));
            match key.as_str() {
                "accuracy" => cache_params.accuracy = value.extract().map_err(bad)?,
                "gradients" => cache_params.gradients = value.extract().map_err(bad)?,
                "neighbour_clamp" => cache_params.neighbour_clamp = value.extract().map_err(bad)?,
                "spacing" => {
                    let text: String = value.extract().map_err(bad)?;
                    cache_params.spacing = Spacing::parse(&text).map_err(py_error)?;
                }
                "clamp_pixels" | "clamp_scene" => {
                    let range: Option<(f32, f32)> = value.extract().map_err(bad)?;
                    let name = if key == "clamp_pixels" {
                        "clamp_pixels"
                    } else {
                        "clamp_scene"
                    };
                    let range = range
                        .map(|(lo, hi)| Range::parse(name, &format!("{lo},{hi}")))
                        .transpose()
                        .map_err(py_error)?;
                    match name {
                        "clamp_pixels" => cache_params.clamp_pixels = range,
                        _ => cache_params.clamp_scene = range,
                    }
                }
                _ => rest.set_item(key, value)?,
            }
        }
        // The records' irradiance parameters, checked by the registry as `render`'s are.
        let (irradiance, mut options) = configure("irradiance", &rest, &[])?;
        let parameters =
            serde_json::to_value(irradiance.parameters()).map_err(|e| value_error(e.to_string()))?;
        cache_params.irradiance =
            serde_json::from_value(parameters).map_err(|e| value_error(e.to_string()))?;
        if let Some(c) = &camera {
            (options.width, options.height) = c.size;
        }
        let image = |a: &PyReadonlyArray2<'py, f32>| -> PyResult<HmdImage> {
            let (h, w) = (a.shape()[0], a.shape()[1]);
            let data = a.as_slice().map_err(|e| value_error(e.to_string()))?.to_vec();
            Ok(HmdImage::new(w as u32, h as u32, data))
        };
        let oracle = oracle.as_ref().map(image).transpose()?;
        let reference = reference.as_ref().map(image).transpose()?;
        let scene = self.seen_by(camera.as_ref());
        let scene = scene.as_ref();
        let reporter: &dyn Progress = if progress { &Stderr } else { &Silent };
        let mut cached = interruptible(py, || {
            cache(scene, &cache_params, &options, oracle.as_ref(), reporter)
        })?
        .map_err(py_error)?;
        let errors = reference
            .as_ref()
            .map(|r| cached.compare(r, "array"))
            .transpose()
            .map_err(py_error)?;
        let (w, h) = (cached.image.width as usize, cached.image.height as usize);
        let records = PyDict::new(py);
        let column =
            |f: fn(&hmdist::cache::Record) -> f32| cached.records.iter().map(f).collect::<Vec<f32>>();
        records.set_item(
            "pixel",
            PyArray1::from_vec(py, cached.records.iter().map(|r| r.pixel).collect()),
        )?;
        records.set_item("e", PyArray1::from_vec(py, column(|r| r.e)))?;
        records.set_item("radius", PyArray1::from_vec(py, column(|r| r.radius)))?;
        records.set_item(
            "level",
            PyArray1::from_vec(py, cached.records.iter().map(|r| r.level).collect()),
        )?;
        records.set_item(
            "used",
            PyArray1::from_vec(py, cached.records_used).reshape([h, w])?,
        )?;
        if let Some(errors) = errors {
            records.set_item("relative_error", PyArray1::from_vec(py, errors).reshape([h, w])?)?;
        }
        let report = json_to_py(py, &cached.report.to_json())?;
        let image = PyArray1::from_vec(py, cached.image.data).reshape([h, w])?;
        Ok((image.into_any(), report, records))
    }

    /// H per pixel (float32 [height, width], NaN for background), the report as a dict
    /// with the JSON sidecar's keys, and each AOV named in `aov` (float32 [height, width]) in a
    /// dict by name. Parameters as `hmdist render`'s flags (`rays`, `photons`, ...), passed by
    /// the Python wrapper as a dict.
    fn render<'py>(
        &self,
        py: Python<'py>,
        camera: Option<PyCamera>,
        method: &str,
        params: &Bound<'py, PyDict>,
        progress: bool,
        aov: Vec<String>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyDict>)> {
        let mut aovs = Vec::new();
        for name in &aov {
            let aov = Aov::parse(name).map_err(py_error)?;
            if !aovs.contains(&aov) {
                aovs.push(aov);
            }
        }
        let (estimator, mut options) = configure(method, params, &aovs)?;
        options.aovs = aovs;
        if let Some(c) = &camera {
            (options.width, options.height) = c.size;
        }
        let scene = self.seen_by(camera.as_ref());
        let scene = scene.as_ref();
        let reporter: &dyn Progress = if progress { &Stderr } else { &Silent };
        let estimator = estimator.as_ref();
        let rendered =
            interruptible(py, || render(scene, estimator, &options, reporter))?.map_err(py_error)?;
        let (w, h) = (rendered.image.width as usize, rendered.image.height as usize);
        let image = PyArray1::from_vec(py, rendered.image.data).reshape([h, w])?;
        let report = json_to_py(py, &rendered.report.to_json())?;
        let channels = PyDict::new(py);
        for channel in rendered.aovs {
            channels.set_item(
                channel.aov.name(),
                PyArray1::from_vec(py, channel.data).reshape([h, w])?,
            )?;
        }
        Ok((image.into_any(), report, channels))
    }

    /// Each pixel's first hit (spec §2) as flat float32 arrays: points [n, 3], normals [n, 3]
    /// (facing the camera), point error bounds [n, 3], triangles (int64 [n], -1 for
    /// background; then the other rows are NaN).
    fn primary_hits<'py>(
        &self,
        py: Python<'py>,
        camera: Option<PyCamera>,
        size: (u32, u32),
    ) -> PyResult<Bound<'py, PyDict>> {
        let size = camera.as_ref().map_or(size, |c| c.size);
        let accel = self.accel(py)?;
        let scene = self.seen_by(camera.as_ref());
        let scene = scene.as_ref();
        let gbuffer = py.detach(|| hmdist::render::primary_hits(accel, scene, size.0, size.1));
        let column = |f: &dyn Fn(&hmdist::accel::Hit) -> Vec3| -> Vec<f32> {
            gbuffer
                .points
                .iter()
                .flat_map(|h| h.map_or([f32::NAN; 3], |h| f(&h).to_array()))
                .collect()
        };
        let hits = PyDict::new(py);
        let n = gbuffer.points.len();
        hits.set_item(
            "points",
            PyArray1::from_vec(py, column(&|h| h.point)).reshape([n, 3])?,
        )?;
        hits.set_item(
            "normals",
            PyArray1::from_vec(py, column(&|h| h.normal)).reshape([n, 3])?,
        )?;
        hits.set_item(
            "point_errors",
            PyArray1::from_vec(py, column(&|h| h.point_error)).reshape([n, 3])?,
        )?;
        let triangles: Vec<i64> = gbuffer
            .points
            .iter()
            .map(|h| h.map_or(-1, |h| h.triangle as i64))
            .collect();
        hits.set_item("triangles", PyArray1::from_vec(py, triangles))?;
        Ok(hits)
    }

    /// H at points [n, 3] with normals [n, 3] (float64), float32 [n]: point i's random
    /// numbers keyed by `keys[i]` (uint64 [n]) or by i; optionally the triangle each lies on
    /// (uint64 [n]) and its error bound (float64 [n, 3]), as `primary_hits` gives them; the
    /// rays cast on `backend` (auto, gpu, gpu-software, cpu) with directions from `sampler`
    /// (sobol, grid), as `render`'s are.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (points, normals, rays, seed, keys, weighting, max_distance, triangles = None, errors = None, backend = "auto", sampler = "sobol"))]
    fn hmd_at<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f64>,
        normals: PyReadonlyArray2<'py, f64>,
        rays: u32,
        seed: u64,
        keys: Option<PyReadonlyArray1<'py, u64>>,
        weighting: &str,
        max_distance: Option<f32>,
        triangles: Option<PyReadonlyArray1<'py, u64>>,
        errors: Option<PyReadonlyArray2<'py, f64>>,
        backend: &str,
        sampler: &str,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let (p, n) = (vectors(&points)?, vectors(&normals)?);
        let triangles = match &triangles {
            Some(t) => Some(t.as_slice().map_err(|e| value_error(e.to_string()))?.to_vec()),
            None => None,
        };
        let errors = errors.as_ref().map(vectors).transpose()?;
        let surface = p
            .iter()
            .zip(&n)
            .enumerate()
            .map(|(i, (p, n))| {
                let mut point =
                    SurfacePoint::new(*p, *n).map_err(|e| value_error(format!("point {i}: {e}")))?;
                if let Some(t) = &triangles {
                    point = point.on_triangle(t[i] as u32);
                }
                if let Some(e) = &errors {
                    point = point.with_error_bound(e[i]);
                }
                Ok(point)
            })
            .collect::<PyResult<Vec<_>>>()?;
        let keys: Option<Vec<u64>> = match &keys {
            Some(k) => Some(k.as_slice().map_err(|e| value_error(e.to_string()))?.to_vec()),
            None => None,
        };
        let gather = Gather::new(rays, named("weighting", weighting)?)
            .map_err(py_error)?
            .with_backend(named("backend", backend)?)
            .with_sampler(named("sampler", sampler)?)
            .map_err(py_error)?;
        let query = PointQuery::new(gather, seed, max_distance).map_err(py_error)?;
        let accel = self.accel(py)?;
        let scene = &self.scene;
        let h = interruptible(py, || hmd_at(scene, accel, &query, &surface, keys.as_deref()))?
            .map_err(py_error)?;
        Ok(PyArray1::from_vec(py, h))
    }

    /// Distance to the first hit along each ray (float32 [n], +inf for a miss); directions
    /// need not be unit length.
    fn cast<'py>(
        &self,
        py: Python<'py>,
        origins: PyReadonlyArray2<'py, f64>,
        directions: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let (o, d) = (vectors(&origins)?, vectors(&directions)?);
        let mut unit = Vec::with_capacity(d.len());
        for (i, d) in d.iter().enumerate() {
            let n = d.normalize_or_zero();
            if n == Vec3::ZERO {
                return Err(value_error(format!("directions[{i}] is zero")));
            }
            unit.push(n);
        }
        let accel = self.accel(py)?;
        let t: Vec<f32> = interruptible(py, || {
            use rayon::prelude::*;
            // In chunks, so that Ctrl-C stops it between them.
            let mut t = Vec::with_capacity(o.len());
            for (o, d) in o.chunks(1 << 16).zip(unit.chunks(1 << 16)) {
                if hmdist::interrupt::requested() {
                    break;
                }
                t.par_extend(
                    o.par_iter()
                        .zip(d)
                        .map(|(o, d)| accel.hit_distance(*o, *d, f32::INFINITY, None)),
                );
            }
            t
        })?;
        Ok(PyArray1::from_vec(py, t))
    }

    /// For pickle: [`PyScene::from_state`] and the scene's name, vertices (float32 bytes),
    /// faces (uint32 bytes), camera, light and display scale.
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
        camera: ([f32; 3], [f32; 3], [f32; 3], f32),
        light: Option<([f32; 3], [f32; 3], f32)>,
        display_scale: f32,
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
        let (eye, target, up, fov_y_deg) = camera;
        let camera = Camera {
            eye: eye.into(),
            target: target.into(),
            up: up.into(),
            fov_y_deg,
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

/// spec §4's f_diff of two images (float64 [h, w] each) of a scene with diagonal `l_diag`.
#[pyfunction]
fn f_diff(
    reference: PyReadonlyArray2<'_, f64>,
    test: PyReadonlyArray2<'_, f64>,
    l_diag: f32,
) -> PyResult<f64> {
    let image = |a: &PyReadonlyArray2<'_, f64>| -> PyResult<HmdImage> {
        let shape = a.shape();
        let data = a.as_slice().map_err(|e| value_error(e.to_string()))?;
        let data = data.iter().map(|&v| v as f32).collect();
        Ok(HmdImage::new(shape[1] as u32, shape[0] as u32, data))
    };
    let d = hmdist::metrics::f_diff(&image(&reference)?, &image(&test)?, l_diag).map_err(py_error)?;
    Ok(d.value)
}

/// One channel of an EXR file (float32 [h, w]): `Y` is H; AOVs have their own names.
#[pyfunction]
#[pyo3(signature = (path, channel = "Y"))]
fn read_exr<'py>(py: Python<'py>, path: &str, channel: &str) -> PyResult<Bound<'py, PyAny>> {
    let image = py
        .detach(|| hmdist::image::exr::read_channel(std::path::Path::new(path), channel))
        .map_err(py_error)?;
    let (w, h) = (image.width as usize, image.height as usize);
    Ok(PyArray1::from_vec(py, image.data).reshape([h, w])?.into_any())
}

/// Progress on stderr, one line per phase (for `progress=True`).
struct Stderr;

impl Progress for Stderr {
    fn start(&self, label: &str, total: u64) {
        eprintln!("hmdist: {label} ({total} steps)");
    }
    fn advance(&self, _: u64) {}
    fn finish(&self) {}
}

/// One of the library's named choices (`cosine`, `light`, `gpu`, `fast`, ...), by the name
/// its serde form gives it; the message lists the names where it is none of them.
fn named<T: serde::de::DeserializeOwned>(key: &str, name: &str) -> PyResult<T> {
    serde_json::from_value(serde_json::Value::String(name.into()))
        .map_err(|e| value_error(format!("{key}: {e}")))
}

/// The estimator and the render options from the keyword parameters: the render options'
/// own (`size`, `seed`, `threads`, `max_distance`, `bvh`), and method `method`'s, which its
/// parameter struct reads by name (`hmdist render`'s flags with underscores). A name the
/// method does not read is a `ValueError`.
fn configure(
    method: &str,
    params: &Bound<'_, PyDict>,
    aovs: &[Aov],
) -> PyResult<(Box<dyn Estimator>, RenderOptions)> {
    let mut o = RenderOptions {
        kernel: Kernel::from_env().map_err(py_error)?,
        ..RenderOptions::default()
    };
    let mut method_params = serde_json::Map::new();
    // `denoise=True` and the filter's own keywords, which need it.
    let (mut denoise, mut filter) = (false, hmdist::denoise::DenoiseParams::default());
    let mut filter_keys = vec![];
    for (key, value) in params.iter() {
        let key: String = key.extract()?;
        let bad = |e: PyErr| value_error(format!("{key}: {e}"));
        match key.as_str() {
            "seed" => o.seed = value.extract().map_err(bad)?,
            "threads" => o.threads = value.extract().map_err(bad)?,
            "max_distance" => o.max_distance = value.extract().map_err(bad)?,
            "size" => (o.width, o.height) = value.extract().map_err(bad)?,
            "bvh" => o.bvh_quality = named(&key, &value.extract::<String>().map_err(bad)?)?,
            "denoise" => denoise = value.extract().map_err(bad)?,
            "denoise_passes" => filter.passes = value.extract().map_err(bad)?,
            "denoise_radius" => filter.radius = value.extract().map_err(bad)?,
            "denoise_edge" => filter.edge = value.extract().map_err(bad)?,
            _ => {
                let value = json_value(&key, &value)?;
                method_params.insert(key, value);
            }
        }
    }
    for key in params.keys() {
        let key: String = key.extract()?;
        if key.starts_with("denoise_") {
            filter_keys.push(key);
        }
    }
    if !denoise && !filter_keys.is_empty() {
        return Err(value_error(format!(
            "{} needs denoise=True",
            filter_keys.join(", ")
        )));
    }
    o.denoise = denoise.then_some(filter);
    let entry = registry::method(method).map_err(py_error)?;
    let estimator = entry.build(&method_params, aovs).map_err(py_error)?;
    Ok((estimator, o))
}

/// A keyword's value as JSON, for a method's parameter struct: None, a bool, an int, a finite
/// float, a str or a path.
fn json_value(key: &str, value: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
    use serde_json::Value;
    if value.is_none() {
        return Ok(Value::Null);
    }
    if value.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(value.extract()?));
    }
    if value.is_instance_of::<PyInt>() {
        return match value.extract::<i64>() {
            Ok(i) => Ok(i.into()),
            Err(_) => Ok(value
                .extract::<u64>()
                .map_err(|e| value_error(format!("{key}: {e}")))?
                .into()),
        };
    }
    if value.is_instance_of::<PyFloat>() {
        let x: f64 = value.extract()?;
        return serde_json::Number::from_f64(x)
            .map(Value::Number)
            .ok_or_else(|| value_error(format!("bad parameter: {key} must be a finite number, not {x}")));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(Value::String(value.extract()?));
    }
    if value.hasattr("__fspath__")? {
        return Ok(Value::String(value.call_method0("__fspath__")?.extract()?));
    }
    let kind = value.get_type().name()?;
    Err(value_error(format!("{key}: a {kind} is not a parameter value")))
}

#[pymodule]
fn _hmdist(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_class::<PyCamera>()?;
    m.add_function(wrap_pyfunction!(f_diff, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add("DeviceError", m.py().get_type::<DeviceError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "BUILTIN_SCENES",
        hmdist::scene::procedural::BUILTIN_NAMES.to_vec(),
    )?;
    // The library's defaults, which the Python signatures take rather than repeat.
    m.add("DEFAULT_RAYS", hmdist::estimators::gather::DEFAULT_RAYS)?;
    m.add("DEFAULT_SEED", hmdist::render::DEFAULT_SEED)?;
    m.add("DEFAULT_SIZE", hmdist::render::DEFAULT_SIZE)?;
    Ok(())
}
