//! The encoder's trial loops (tuckercodec-core `encoder`): rate-distortion rounding and the
//! integers of a trial's entropy, called from `tuckercodec/encoder/rdo.py` and `estimate.py`.

use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArrayDyn,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tuckercodec_core::encoder::{self, ChooseModel, EncoderError, MeanChoiceModel};

fn value_error(error: EncoderError) -> PyErr {
    PyValueError::new_err(error.0)
}

fn shape2<T: numpy::Element>(array: &PyReadonlyArray2<'_, T>) -> (usize, usize) {
    let shape = array.shape();
    (shape[0], shape[1])
}

/// (rows, cols) int64 back to numpy.
fn matrix<'py>(
    py: Python<'py>,
    values: Vec<i64>,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    PyArray1::from_vec(py, values).reshape([rows, cols])
}

/// Which columns rdo._predicted_columns predicts (two columns or more), as a bool array.
#[pyfunction]
fn rdo_predicted_columns<'py>(
    py: Python<'py>,
    q: PyReadonlyArray2<'py, i64>,
    parents: PyReadonlyArray1<'py, i64>,
) -> PyResult<Bound<'py, PyArray1<bool>>> {
    let (rows, cols) = shape2(&q);
    let (q, parents) = (q.as_slice()?, parents.as_slice()?);
    let flags = py
        .detach(|| encoder::rdo_predicted_columns(q, rows, cols, parents))
        .map_err(value_error)?;
    Ok(PyArray1::from_vec(py, flags))
}

/// rdo._bit_table's histograms: (cols, table_size + 1) int64 counts.
#[pyfunction]
fn rdo_residual_counts<'py>(
    py: Python<'py>,
    q: PyReadonlyArray2<'py, i64>,
    parents: PyReadonlyArray1<'py, i64>,
    predicted: PyReadonlyArray1<'py, bool>,
    table_size: usize,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let (rows, cols) = shape2(&q);
    let (q, parents, predicted) = (q.as_slice()?, parents.as_slice()?, predicted.as_slice()?);
    let counts = py
        .detach(|| encoder::rdo_residual_counts(q, rows, cols, parents, predicted, table_size))
        .map_err(value_error)?;
    matrix(py, counts, cols, table_size + 1)
}

/// rdo._choose: the integers chosen, (rows, cols) int64.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn rdo_choose<'py>(
    py: Python<'py>,
    values: PyReadonlyArray2<'py, f64>,
    steps: PyReadonlyArray1<'py, f64>,
    parents: PyReadonlyArray1<'py, i64>,
    order: PyReadonlyArray1<'py, i64>,
    predicted: PyReadonlyArray1<'py, bool>,
    table: PyReadonlyArray2<'py, f64>,
    lam: f64,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let (rows, cols) = shape2(&values);
    let table_size = table.shape()[1].saturating_sub(1);
    let model = ChooseModel {
        parents: parents.as_slice()?,
        order: order.as_slice()?,
        predicted: predicted.as_slice()?,
        table: table.as_slice()?,
        table_size,
        lam,
    };
    let (values, steps) = (values.as_slice()?, steps.as_slice()?);
    let q = py
        .detach(|| encoder::rdo_choose(values, rows, cols, steps, &model))
        .map_err(value_error)?;
    matrix(py, q, rows, cols)
}

/// rdo._mean_choice: U1's columns under predictor 2 chosen against its prediction, in the
/// decoder's order, from MeanSteps' arrays, each column's push (int64) and the value table
/// (cols, 2 half + 1): the integers chosen, (rows, cols) int64.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn rdo_mean_choice<'py>(
    py: Python<'py>,
    values: PyReadonlyArray2<'py, f64>,
    steps: PyReadonlyArray1<'py, f64>,
    rows: PyReadonlyArray1<'py, i64>,
    step_ends: PyReadonlyArray1<'py, i64>,
    sources: PyReadonlyArray1<'py, i64>,
    anchors: PyReadonlyArray1<'py, i64>,
    source_ends: PyReadonlyArray1<'py, i64>,
    push: PyReadonlyArray1<'py, i64>,
    table: PyReadonlyArray2<'py, f64>,
    half: usize,
    lam: f64,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let (height, cols) = shape2(&values);
    let model = MeanChoiceModel {
        rows: rows.as_slice()?,
        step_ends: step_ends.as_slice()?,
        sources: sources.as_slice()?,
        anchors: anchors.as_slice()?,
        source_ends: source_ends.as_slice()?,
        push: push.as_slice()?,
        table: table.as_slice()?,
        half,
        lam,
    };
    let (values, steps) = (values.as_slice()?, steps.as_slice()?);
    let q = py
        .detach(|| encoder::rdo_mean_choice(values, height, cols, steps, &model))
        .map_err(value_error)?;
    matrix(py, q, height, cols)
}

/// np.abs(values).max() of a contiguous float64 array of any shape (0 for none).
#[pyfunction]
fn max_abs(py: Python<'_>, values: PyReadonlyArrayDyn<'_, f64>) -> PyResult<f64> {
    let slice = values.as_slice()?;
    Ok(py.detach(|| encoder::max_abs(slice)))
}

/// Adds the encoder's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(rdo_predicted_columns, m)?)?;
    m.add_function(wrap_pyfunction!(rdo_residual_counts, m)?)?;
    m.add_function(wrap_pyfunction!(rdo_choose, m)?)?;
    m.add_function(wrap_pyfunction!(rdo_mean_choice, m)?)?;
    m.add_function(wrap_pyfunction!(max_abs, m)?)?;
    Ok(())
}
