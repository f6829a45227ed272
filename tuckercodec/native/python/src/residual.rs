//! The binding of `tuckercodec_core::residual` (§6.9 corrections): a chunk's integers restored
//! and packed, the ordered integers of a domain, and the correction of positions.

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use tuckercodec_core::codebooks;
use tuckercodec_core::residual::{self, Domain};

use crate::broken;

/// The domain named as the Python reference names it, with its step or scale.
fn domain_of(name: &str, step: f64, scale: i64) -> PyResult<Domain> {
    Domain::named(name, step, scale).ok_or_else(|| {
        PyValueError::new_err(format!(
            "no domain {name:?} of step {step} and scale {scale}"
        ))
    })
}

/// The restored integers e of one chunk (int64, stream order) from its decompressed zstd
/// frame `raw`: `count` integers in `planes` byte planes, with `predict` each frame of
/// `frame_values` integers summed with the one before.
#[pyfunction]
fn residual_restore_chunk<'py>(
    py: Python<'py>,
    raw: &[u8],
    count: usize,
    planes: usize,
    predict: bool,
    frame_values: usize,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let values = py
        .detach(|| residual::restore_chunk(raw, count, planes, predict, frame_values))
        .map_err(broken)?;
    Ok(PyArray1::from_vec(py, values))
}

/// A chunk's integers as §6.9 stores them before zstd: `(planes, bytes)`.
#[pyfunction]
fn residual_pack_chunk<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, i64>,
    predict: bool,
    frame_values: usize,
) -> PyResult<(usize, Bound<'py, PyBytes>)> {
    let values = values.as_slice()?;
    let (planes, raw) = py
        .detach(|| residual::pack_chunk(values, predict, frame_values))
        .map_err(broken)?;
    Ok((planes, PyBytes::new(py, &raw)))
}

/// The positions `exact` (float64) corrected by `residual` (int64) in the domain `name`
/// (its `step` or `scale`); R41 as `Broken`.
#[pyfunction]
fn residual_correct<'py>(
    py: Python<'py>,
    exact: PyReadonlyArray1<'py, f64>,
    residual: PyReadonlyArray1<'py, i64>,
    name: &str,
    step: f64,
    scale: i64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let domain = domain_of(name, step, scale)?;
    let (exact, residual) = (exact.as_slice()?, residual.as_slice()?);
    let out = py
        .detach(|| {
            let mut out = vec![0.0; exact.len()];
            residual::correct(exact, residual, domain, &mut out).map(|()| out)
        })
        .map_err(broken)?;
    Ok(PyArray1::from_vec(py, out))
}

/// The ordered integers (int64) of `values` (float64) in the lossless domain `name`.
#[pyfunction]
fn residual_ordered<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, f64>,
    name: &str,
    scale: i64,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let domain = domain_of(name, 1.0, scale)?;
    let values = values.as_slice()?;
    let out = py.detach(|| {
        let mut out = vec![0; values.len()];
        residual::ordered_in(values, domain, &mut out);
        out
    });
    Ok(PyArray1::from_vec(py, out))
}

/// j of §6.9 (format 1.8's codebooks) for the ordered integers `base` of one axis: the index
/// of the codebook entry nearest each, from the codebook's `middles`.
#[pyfunction]
fn residual_nearest_entries<'py>(
    py: Python<'py>,
    middles: PyReadonlyArray1<'py, i64>,
    base: PyReadonlyArray1<'py, i64>,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let (middles, base) = (middles.as_slice()?, base.as_slice()?);
    let out = py.detach(|| {
        let mut found = vec![0_usize; base.len()];
        codebooks::nearest_entries(middles, base, &mut found);
        // an index below the codebook's length, itself within a numpy array's
        found.into_iter().map(|j| j as i64).collect::<Vec<i64>>()
    });
    Ok(PyArray1::from_vec(py, out))
}

/// The corrections (int64) of the domain `name` (its `scale`) that `stored` positions in the
/// codebook `book` mean for the positions `exact` of one axis; R41 as `Broken` when one leaves
/// the codebook.
#[pyfunction]
fn residual_codebook_corrections<'py>(
    py: Python<'py>,
    exact: PyReadonlyArray1<'py, f64>,
    stored: PyReadonlyArray1<'py, i64>,
    name: &str,
    scale: i64,
    book: PyReadonlyArray1<'py, i64>,
    middles: PyReadonlyArray1<'py, i64>,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let domain = domain_of(name, 1.0, scale)?;
    let (exact, stored) = (exact.as_slice()?, stored.as_slice()?);
    let (book, middles) = (book.as_slice()?, middles.as_slice()?);
    let out = py
        .detach(|| {
            let mut out = vec![0; exact.len()];
            codebooks::codebook_corrections(exact, stored, domain, book, middles, &mut out)
                .map(|()| out)
        })
        .map_err(broken)?;
    Ok(PyArray1::from_vec(py, out))
}

/// Adds this module's functions to `tuckercodec._native`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(residual_restore_chunk, m)?)?;
    m.add_function(wrap_pyfunction!(residual_pack_chunk, m)?)?;
    m.add_function(wrap_pyfunction!(residual_correct, m)?)?;
    m.add_function(wrap_pyfunction!(residual_ordered, m)?)?;
    m.add_function(wrap_pyfunction!(residual_nearest_entries, m)?)?;
    m.add_function(wrap_pyfunction!(residual_codebook_corrections, m)?)?;
    Ok(())
}
