//! `hmdist._hmdist`: the Rust half of the Python package. The Python half (`hmdist/__init__.py`)
//! checks and converts arrays; everything here receives C-contiguous float64 (and uint64) arrays
//! of the right shape, releases the GIL while hmdist works, and turns hmdist's errors into
//! Python exceptions: `ValueError` for bad parameters and scenes, `OSError` for files,
//! `hmdist.DeviceError` for GPU failures.
//!
//! Ctrl-C: long work ([`interrupt::interruptible`]) runs on a helper thread while the calling thread
//! looks at Python's signals every [`interrupt::SIGNAL_POLL`]; a `KeyboardInterrupt` (or any exception a
//! signal handler raises) asks hmdist to stop ([`hmdist::interrupt`]), waits for the work to
//! return, withdraws the request and raises it, so the next call runs normally.

mod cache;
mod camera;
mod convert;
mod functions;
mod interrupt;
mod rays;
mod render;
mod scene;

use pyo3::prelude::*;

use camera::PyCamera;
use convert::DeviceError;
use functions::{f_diff, read_exr};
use scene::PyScene;

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
