//! `Scene.cache`: an irradiance cache, its records and report.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use hmdist::cache::{cache, CacheParams, Range, Spacing};
use hmdist::image::HmdImage;
use hmdist::progress::{Progress, Silent};

use crate::camera::PyCamera;
use crate::convert::{json_to_py, py_error, value_error};
use crate::interrupt::{interruptible, Stderr};
use crate::render::configure;
use crate::scene::PyScene;

#[pymethods]
impl PyScene {
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
        if let Some(size) = self.size_for(camera.as_ref(), rest.contains("size")?) {
            (options.width, options.height) = size;
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
}
