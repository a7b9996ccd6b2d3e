//! The module's functions: f_diff and read_exr.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use hmdist::image::HmdImage;

use crate::convert::{py_error, value_error};

/// spec §4's f_diff of two images (float64 [h, w] each) of a scene with diagonal `l_diag`.
#[pyfunction]
pub(crate) fn f_diff(
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
pub(crate) fn read_exr<'py>(py: Python<'py>, path: &str, channel: &str) -> PyResult<Bound<'py, PyAny>> {
    let image = py
        .detach(|| hmdist::image::exr::read_channel(std::path::Path::new(path), channel))
        .map_err(py_error)?;
    let (w, h) = (image.width as usize, image.height as usize);
    Ok(PyArray1::from_vec(py, image.data).reshape([h, w])?.into_any())
}
