//! tuckercodec._native: the binding of tuckercodec-core to Python.
//!
//! Each function takes and returns numpy arrays and Python scalars, runs the core with the GIL
//! released where the work is long, and turns a core [`Broken`] into the Python exception
//! `tuckercodec._native.Broken(rule, detail)`, which the Python side raises again as the
//! `FormatError` of that rule (tuckercodec/system/native.py).
#![forbid(unsafe_code)]

mod prediction;
mod streams;

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tuckercodec_core::error::Broken;

mod adaptive;
mod encoder;
mod residual;
mod text;
mod traversal;

create_exception!(
    _native,
    NativeBroken,
    PyValueError,
    "A rule of spec section 11 broken: args (rule, detail)."
);

/// The Python exception for a broken rule: its args are (rule, detail).
pub fn broken(error: Broken) -> PyErr {
    NativeBroken::new_err((error.rule, error.detail))
}

/// The core's version, which tuckercodec --version prints.
#[pyfunction]
fn core_version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("Broken", m.py().get_type::<NativeBroken>())?;
    m.add_function(wrap_pyfunction!(core_version, m)?)?;
    traversal::register(m)?;
    text::register(m)?;
    residual::register(m)?;
    encoder::register(m)?;
    prediction::register(m)?;
    streams::register(m)?;
    adaptive::register(m)?;
    Ok(())
}
