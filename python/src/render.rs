//! `Scene.render`, and the estimator and render options from its keyword parameters.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use hmdist::accel::Kernel;
use hmdist::estimators::{registry, Aov, Estimator};
use hmdist::progress::{Progress, Silent};
use hmdist::render::{render, RenderOptions};

use crate::camera::PyCamera;
use crate::convert::{json_to_py, json_value, named, py_error, value_error};
use crate::interrupt::{interruptible, Stderr};
use crate::scene::PyScene;

#[pymethods]
impl PyScene {
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
        if let Some(size) = self.size_for(camera.as_ref(), params.contains("size")?) {
            (options.width, options.height) = size;
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
}

/// The estimator and the render options from the keyword parameters: the render options'
/// own (`size`, `seed`, `threads`, `max_distance`, `bvh`), and method `method`'s, which its
/// parameter struct reads by name (`hmdist render`'s flags with underscores). A name the
/// method does not read is a `ValueError`.
pub(crate) fn configure(
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
