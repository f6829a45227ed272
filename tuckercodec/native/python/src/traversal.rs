//! The binding of §6.8 faces-traverse (tuckercodec_core::traversal): the walk of the decoder
//! and of the encoder, called by tuckercodec/format/traversal.py.

use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tuckercodec_core::traversal::{self, Streams};

use crate::broken;

/// The (count, width) faces the walk decodes from the four streams (ops, degrees, vertices,
/// references: int64 arrays), or Broken(rule, detail) as the Python walk raises it.
#[pyfunction]
fn decode_traversal<'py>(
    py: Python<'py>,
    streams: Vec<PyReadonlyArray1<'py, i64>>,
    count: usize,
    width: usize,
    vertex_count: i64,
    corner_order: i64,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let [ops, degrees, vertices, references] = streams.as_slice() else {
        return Err(PyValueError::new_err("four streams are expected"));
    };
    let streams = Streams {
        ops: ops.as_slice()?,
        degrees: degrees.as_slice()?,
        vertices: vertices.as_slice()?,
        references: references.as_slice()?,
    };
    let table = py
        .detach(|| traversal::decode(&streams, count, width, vertex_count, corner_order))
        .map_err(broken)?;
    PyArray1::from_vec(py, table).reshape([count, width])
}

/// The walk of the (M, n) int64 face table over `vertex_count` vertices: (ops with
/// corner_order 0, ops with corner_order 1, degrees, vertices, references, order) as int64
/// arrays, or None where the Python reference must run (see traversal::encode).
#[pyfunction]
#[allow(clippy::type_complexity)]
fn encode_traversal<'py>(
    py: Python<'py>,
    table: PyReadonlyArray2<'py, i64>,
    vertex_count: u64,
) -> PyResult<Option<[Bound<'py, PyArray1<i64>>; 6]>> {
    let width = table.shape()[1];
    let values = table.as_slice()?;
    let Some(walked) = py.detach(|| traversal::encode(values, width, vertex_count)) else {
        return Ok(None);
    };
    let [ops_from_gate, ops_from_smallest] = walked.ops;
    Ok(Some(
        [
            ops_from_gate,
            ops_from_smallest,
            walked.degrees,
            walked.new_residuals,
            walked.references,
            walked.order,
        ]
        .map(|stream| PyArray1::from_vec(py, stream)),
    ))
}

/// The rank of each NEW vertex (int64, in 0..vertex_count, in the walk's order) among the
/// unseen vertices (format 1.6, unseen.py's `ranks_of`), or None for a vertex outside.
#[pyfunction]
fn unseen_ranks<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray1<'py, i64>,
    vertex_count: u64,
) -> PyResult<Option<Bound<'py, PyArray1<i64>>>> {
    let values = vertices.as_slice()?;
    let ranks = py.detach(|| traversal::ranks(values, vertex_count));
    Ok(ranks.map(|ranks| PyArray1::from_vec(py, ranks)))
}

/// The NEW vertices that the ranks name (unseen.py's `vertices_of`), or Broken(rule, detail)
/// at the first rank that names no unseen vertex.
#[pyfunction]
fn unseen_vertices<'py>(
    py: Python<'py>,
    ranks: PyReadonlyArray1<'py, i64>,
    vertex_count: u64,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let values = ranks.as_slice()?;
    let placed = py
        .detach(|| traversal::vertices(values, vertex_count))
        .map_err(broken)?;
    Ok(PyArray1::from_vec(py, placed))
}

/// Adds the functions of this module to tuckercodec._native.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(decode_traversal, m)?)?;
    m.add_function(wrap_pyfunction!(encode_traversal, m)?)?;
    m.add_function(wrap_pyfunction!(unseen_ranks, m)?)?;
    m.add_function(wrap_pyfunction!(unseen_vertices, m)?)?;
    Ok(())
}
