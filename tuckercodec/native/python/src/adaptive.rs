//! The binding of `tuckercodec_core::adaptive` (§6.14 adaptive coding): a matrix's integers to
//! the adaptive stream and back (`encode_columns` and `decode_columns` of
//! `tuckercodec/format/adaptive.py`), and (format 1.9) uniform streams (`format/uniform.py`).

use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use tuckercodec_core::adaptive::{self, uniform, CodingOrder, InvalidOrder};

use crate::broken;

/// The arrays of an `adaptive.CodingOrder` checked against `rows`: a `ValueError` (the
/// caller's mistake, not a file's) where they are not an order.
fn coding_order(
    order: &PyReadonlyArray1<'_, i64>,
    sources: &PyReadonlyArray1<'_, i64>,
    ends: &PyReadonlyArray1<'_, i64>,
    mesh: bool,
    rows: usize,
) -> PyResult<CodingOrder> {
    CodingOrder::new(
        order.as_slice()?,
        sources.as_slice()?,
        ends.as_slice()?,
        mesh,
        rows,
    )
    .map_err(invalid)
}

fn invalid(error: InvalidOrder) -> PyErr {
    PyValueError::new_err(error.to_string())
}

/// The adaptive stream of `columns` (int64, (cols, rows), C-contiguous), each column in the
/// order given by `order`, `sources`, `ends` (int64) and `mesh`.
#[pyfunction]
fn adaptive_encode<'py>(
    py: Python<'py>,
    columns: PyReadonlyArray2<'py, i64>,
    order: PyReadonlyArray1<'py, i64>,
    sources: PyReadonlyArray1<'py, i64>,
    ends: PyReadonlyArray1<'py, i64>,
    mesh: bool,
) -> PyResult<Bound<'py, PyBytes>> {
    let [cols, rows] = [columns.shape()[0], columns.shape()[1]];
    let order = coding_order(&order, &sources, &ends, mesh, rows)?;
    let values = columns.as_slice()?;
    let payload = py
        .detach(|| adaptive::encode_columns(values, cols, rows, &order))
        .map_err(invalid)?;
    Ok(PyBytes::new(py, &payload))
}

/// The (cols, rows) int64 integers of the adaptive stream `payload`, each column in the given
/// order; `Broken` (R46) for any payload that is not exactly their coding.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn adaptive_decode<'py>(
    py: Python<'py>,
    payload: &[u8],
    cols: usize,
    rows: usize,
    order: PyReadonlyArray1<'py, i64>,
    sources: PyReadonlyArray1<'py, i64>,
    ends: PyReadonlyArray1<'py, i64>,
    mesh: bool,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    // the bound first: nothing is allocated for a size the payload cannot hold
    adaptive::check_size(cols, rows, payload.len()).map_err(broken)?;
    let order = coding_order(&order, &sources, &ends, mesh, rows)?;
    let array = PyArray2::<i64>::zeros(py, [cols, rows], false);
    {
        let mut writable = array.readwrite();
        let out = writable.as_slice_mut()?;
        py.detach(|| adaptive::decode_columns_into(payload, &order, out))
            .map_err(broken)?;
    }
    Ok(array)
}

/// The uniform stream (format 1.9, §6.8) of `values` (int64, value i in `0..total - i - 1`);
/// a `ValueError` naming the first value outside its range.
#[pyfunction]
fn uniform_encode<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, i64>,
    total: u64,
) -> PyResult<Bound<'py, PyBytes>> {
    let values = values.as_slice()?;
    let payload = py
        .detach(|| uniform::encode_uniform(values, total))
        .map_err(PyValueError::new_err)?;
    Ok(PyBytes::new(py, &payload))
}

/// The `count` int64 integers of the uniform stream `payload` over `total`; `Broken` (R46) for
/// any payload that is not exactly their coding.
#[pyfunction]
fn uniform_decode<'py>(
    py: Python<'py>,
    payload: &[u8],
    count: usize,
    total: u64,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let values = py
        .detach(|| uniform::decode_uniform(payload, count, total))
        .map_err(broken)?;
    Ok(PyArray1::from_vec(py, values))
}

/// Adds this module's functions to `tuckercodec._native`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(adaptive_encode, m)?)?;
    m.add_function(wrap_pyfunction!(adaptive_decode, m)?)?;
    m.add_function(wrap_pyfunction!(uniform_encode, m)?)?;
    m.add_function(wrap_pyfunction!(uniform_decode, m)?)?;
    Ok(())
}
