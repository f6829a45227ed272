//! The integer streams of spec section 6.1 (`tuckercodec/format/streams.py`): the byte planes
//! after zstd has decompressed them, and before it compresses them.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use tuckercodec_core::streams;

/// `count` int64 integers from `planes` byte planes (`from_planes` and the unzigzag of
/// `unpack_integers`); `Broken` if the bytes are not `count * planes`.
#[pyfunction]
fn unpack_planes<'py>(
    py: Python<'py>,
    raw: &[u8],
    count: usize,
    planes: usize,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    // numpy's allocation: a large array gets huge pages (a Vec faults 4 KiB at a time)
    let array = PyArray1::<i64>::zeros(py, count, false);
    {
        let mut writable = array.readwrite();
        let out = writable.as_slice_mut()?;
        py.detach(|| streams::unpack_planes_into(raw, planes, out))
            .map_err(crate::broken)?;
    }
    Ok(array)
}

/// `(planes, bytes)` of int64 integers in stream order (`zigzag`, `planes_needed`, `to_planes`);
/// planes may exceed 4, which the caller refuses.
#[pyfunction]
fn pack_planes<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, i64>,
) -> PyResult<(usize, Bound<'py, PyBytes>)> {
    let slice = values.as_slice()?;
    let (planes, raw) = py.detach(|| streams::pack_planes(slice));
    Ok((planes, PyBytes::new(py, &raw)))
}

/// Adds the functions of this module to `_native`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(unpack_planes, m)?)?;
    m.add_function(wrap_pyfunction!(pack_planes, m)?)?;
    Ok(())
}
