//! Python values as hmdist's, and hmdist's errors as Python exceptions.

use glam::Vec3;
use numpy::PyReadonlyArray2;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyString};

use hmdist::error::Error;

create_exception!(_hmdist, DeviceError, PyException, "A GPU is missing or failed.");

/// hmdist's error as the Python exception of its kind, with hmdist's message.
pub(crate) fn py_error(error: Error) -> PyErr {
    let message = error.to_string();
    match error {
        Error::File { .. } => PyOSError::new_err(message),
        Error::Device { .. } => DeviceError::new_err(message),
        Error::Parameter { .. } | Error::Scene(_) => PyValueError::new_err(message),
        Error::Interrupted => PyKeyboardInterrupt::new_err(message),
    }
}

pub(crate) fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// Rows of an [n, 3] float64 array as vectors.
pub(crate) fn vectors(array: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<Vec3>> {
    let slice = array.as_slice().map_err(|e| value_error(e.to_string()))?;
    Ok(slice
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
        .collect())
}

/// Any sequence or array of 3 numbers (a list, a tuple, a numpy array) as a vector.
pub(crate) fn vec3(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Vec3> {
    let numbers = numbers(name, value, 3)?;
    Ok(Vec3::new(numbers[0] as f32, numbers[1] as f32, numbers[2] as f32))
}

/// Any sequence or array of `count` numbers, or a `ValueError` naming `name`.
pub(crate) fn numbers(name: &str, value: &Bound<'_, PyAny>, count: usize) -> PyResult<Vec<f64>> {
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
pub(crate) fn shortest(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(v as f64)
}

/// A JSON text as a Python object.
pub(crate) fn json_to_py<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// One of the library's named choices (`cosine`, `light`, `gpu`, `fast`, ...), by the name
/// its serde form gives it; the message lists the names where it is none of them.
pub(crate) fn named<T: serde::de::DeserializeOwned>(key: &str, name: &str) -> PyResult<T> {
    serde_json::from_value(serde_json::Value::String(name.into()))
        .map_err(|e| value_error(format!("{key}: {e}")))
}

/// A keyword's value as JSON, for a method's parameter struct: None, a bool, an int, a finite
/// float, a str or a path.
pub(crate) fn json_value(key: &str, value: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
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
