//! Prediction (spec section 6.2, `tuckercodec/format/prediction.py`) and the mesh relations it
//! follows (`tuckercodec/model/topology.py`): a caller's error or a restored value out of range
//! is a `ValueError` with the Python's words.

use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use numpy::{PyReadwriteArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use tuckercodec_core::adaptive::{self, CodingOrder};
use tuckercodec_core::encoder;
use tuckercodec_core::prediction::{self, topology, values};

use crate::broken;

/// A one-dimensional numpy array handed to Python.
type Array<'py, T> = Bound<'py, PyArray1<T>>;

fn value_error(message: String) -> PyErr {
    PyValueError::new_err(message)
}

fn int64_array<'py, T: Copy + TryInto<i64>>(
    py: Python<'py>,
    values: &[T],
) -> Bound<'py, PyArray1<i64>> {
    // indices below 2**32 and lengths of memory: always representable
    PyArray1::from_vec(
        py,
        values
            .iter()
            .map(|&v| v.try_into().unwrap_or(i64::MAX))
            .collect(),
    )
}

/// Each column's push (`mean_push`, spec section 6.2): `None` for 2 everywhere (today's
/// predictor 2), else a `bytes` or a one-dimensional uint8 numpy array of one byte per column
/// (their count and values are checked by the core: `ValueError` if they do not fit).
fn pushes(push: Option<&Bound<'_, PyAny>>, cols: usize) -> PyResult<Vec<u8>> {
    let Some(push) = push else {
        return Ok(vec![prediction::PLAIN_PUSH; cols]);
    };
    if let Ok(bytes) = push.cast::<PyBytes>() {
        return Ok(bytes.as_bytes().to_vec());
    }
    let array: PyReadonlyArray1<'_, u8> = push.extract().map_err(|_| {
        value_error("push must be None, bytes or a one-dimensional uint8 array".to_string())
    })?;
    Ok(array.as_array().to_vec())
}

/// `MeshForest.mean_steps`'s result.
type MeanStepsTuple<'py> = (
    Array<'py, i64>,
    Array<'py, i64>,
    Array<'py, i64>,
    Array<'py, i64>,
    Array<'py, i64>,
    usize,
    MeanPlan,
);

/// The breadth-first forest of a face table (`_mesh_forest`), held in the core.
#[pyclass(frozen, module = "tuckercodec._native")]
struct MeshForest {
    forest: topology::Forest,
}

#[pymethods]
impl MeshForest {
    /// The forest of an (M, n) int64 face table padded with -1, over `vertex_count` vertices.
    #[new]
    fn new(
        py: Python<'_>,
        faces: PyReadonlyArray2<'_, i64>,
        vertex_count: usize,
    ) -> PyResult<Self> {
        let width = faces.shape()[1];
        let table = faces.as_slice()?;
        let forest = py
            .detach(|| topology::Forest::new(table, width, vertex_count))
            .map_err(value_error)?;
        Ok(MeshForest { forest })
    }

    /// Each vertex's parent, or -1 (`mesh_parents`).
    fn parents<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_vec(py, self.forest.parents.clone())
    }

    /// The number of depths, 0 included (1 without edges).
    fn levels(&self) -> usize {
        self.forest.levels()
    }

    /// `(rows, step_ends, sources, anchors, source_ends, levels, plan)`: predictor 2's
    /// `MeanSteps` arrays (int64) and their [`MeanPlan`].
    fn mean_steps<'py>(&self, py: Python<'py>) -> MeanStepsTuple<'py> {
        let (steps, plan) = py.detach(|| {
            let steps = self.forest.mean_steps();
            let plan = prediction::MeanPlan::from_arrays(&steps, self.forest.vertex_count);
            (steps, plan)
        });
        (
            int64_array(py, &steps.rows),
            int64_array(py, &steps.step_ends),
            int64_array(py, &steps.sources),
            int64_array(py, &steps.anchors),
            int64_array(py, &steps.source_ends),
            steps.levels,
            MeanPlan { plan },
        )
    }
}

/// Predictor 2's steps with their sparse sums (`MeanSteps` and its `matrix`), held in the core.
#[pyclass(frozen, module = "tuckercodec._native")]
struct MeanPlan {
    plan: prediction::MeanPlan,
}

#[pymethods]
impl MeanPlan {
    /// The plan of `MeanSteps` arrays over `vertex_count` vertices, every index checked.
    #[new]
    fn new(
        py: Python<'_>,
        rows: PyReadonlyArray1<'_, i64>,
        step_ends: PyReadonlyArray1<'_, i64>,
        sources: PyReadonlyArray1<'_, i64>,
        anchors: PyReadonlyArray1<'_, i64>,
        source_ends: PyReadonlyArray1<'_, i64>,
        vertex_count: usize,
    ) -> PyResult<Self> {
        let (rows, step_ends) = (rows.as_slice()?, step_ends.as_slice()?);
        let (sources, anchors, source_ends) = (
            sources.as_slice()?,
            anchors.as_slice()?,
            source_ends.as_slice()?,
        );
        let plan = py
            .detach(|| {
                prediction::MeanPlan::from_steps(
                    rows,
                    step_ends,
                    sources,
                    anchors,
                    source_ends,
                    vertex_count,
                )
            })
            .map_err(value_error)?;
        Ok(MeanPlan { plan })
    }

    /// `(indptr, indices, data)` of the matrix, as `MeanSteps.matrix` makes it with scipy.
    fn matrix<'py>(&self, py: Python<'py>) -> (Array<'py, i64>, Array<'py, i64>, Array<'py, f64>) {
        (
            int64_array(py, &self.plan.pointers),
            int64_array(py, &self.plan.columns),
            PyArray1::from_vec(py, self.plan.weights.clone()),
        )
    }

    /// Restores predictor 2's residuals in place, a C-contiguous (cols, K) int64 array whose
    /// rows are columns of U1 (`mean_accumulate_columns`), row c with push `push[c]` (`None`:
    /// 2 for every column); `ValueError` if a value leaves the range or the pushes do not fit.
    #[pyo3(signature = (columns, push=None))]
    fn restore_columns(
        &self,
        py: Python<'_>,
        mut columns: PyReadwriteArray2<'_, i64>,
        push: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let (cols, height) = (columns.shape()[0], columns.shape()[1]);
        let push = pushes(push, cols)?;
        let flat = columns.as_slice_mut()?;
        py.detach(|| self.plan.restore_columns(flat, height, &push))
            .map_err(value_error)
    }

    /// `decode_matrix(...).values()` of a qmat section whose every column has predictor 2:
    /// the (height, cols) float64 matrix from the stream's `raw` bytes (zstd's output, `planes`
    /// byte planes of `cols * height` integers, column after column) and the float32 `steps`,
    /// in one pass and without the integers, on up to `threads` threads (0: as many as the
    /// machine offers, capped), column c with push `push[c]` (`None`: 2 for every column);
    /// `ValueError` if a value leaves the range or the pushes do not fit.
    #[pyo3(signature = (raw, planes, height, steps, threads=0, push=None))]
    #[allow(clippy::too_many_arguments)]
    fn restore_values<'py>(
        &self,
        py: Python<'py>,
        raw: &[u8],
        planes: usize,
        height: usize,
        steps: PyReadonlyArray1<'py, f32>,
        threads: usize,
        push: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let steps = steps.as_slice()?;
        let width = steps.len();
        let push = pushes(push, width)?;
        // numpy's allocation: a large array gets huge pages (a Vec faults 4 KiB at a time)
        let array = PyArray2::<f64>::zeros(py, [height, width], false);
        {
            let mut writable = array.readwrite();
            let out = writable.as_slice_mut()?;
            let threads = if threads == 0 {
                values::thread_count(width.div_ceil(values::VALUE_BLOCK))
            } else {
                threads
            };
            py.detach(|| {
                self.plan
                    .restore_values(raw, planes, height, steps, out, threads, &push)
            })
            .map_err(value_error)?;
        }
        Ok(array)
    }

    /// `restore_values` of a section whose integers are an adaptive stream (§6.14): the
    /// (height, cols) float64 matrix from `payload`, coded in the mesh order given by `order`,
    /// `sources` and `ends` (int64, `adaptive.CodingOrder`'s arrays, over `height` rows), each
    /// integer within `planes` byte planes, restored and times `steps`; a second thread
    /// restores while the stream decodes when `threads` (0: as the machine offers) allows.
    /// `Broken` (R46) for a stream that is not exactly the coding of the integers or an
    /// integer outside the planes; `ValueError` for arrays that are not an order, pushes that
    /// do not fit, or a value out of range.
    #[pyo3(signature = (payload, order, sources, ends, planes, height, steps, threads=0, push=None))]
    #[allow(clippy::too_many_arguments)]
    fn restore_adaptive_values<'py>(
        &self,
        py: Python<'py>,
        payload: &[u8],
        order: PyReadonlyArray1<'py, i64>,
        sources: PyReadonlyArray1<'py, i64>,
        ends: PyReadonlyArray1<'py, i64>,
        planes: usize,
        height: usize,
        steps: PyReadonlyArray1<'py, f32>,
        threads: usize,
        push: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let steps = steps.as_slice()?;
        let width = steps.len();
        let push = pushes(push, width)?;
        // the bound first: nothing is allocated for a size the payload cannot hold
        adaptive::check_size(width, height, payload.len()).map_err(broken)?;
        let (order, sources, ends) = (order.as_slice()?, sources.as_slice()?, ends.as_slice()?);
        // the order is checked and made without the GIL too: a thread waiting for it (U3's,
        // beside U1) starts at once
        let order = py
            .detach(|| CodingOrder::new(order, sources, ends, true, height))
            .map_err(|error| PyValueError::new_err(error.to_string()))?;
        let array = PyArray2::<f64>::zeros(py, [height, width], false);
        {
            let mut writable = array.readwrite();
            let out = writable.as_slice_mut()?;
            // the stream decodes on one thread: a second one restores, more would wait
            let threads = if threads == 0 {
                values::thread_count(2)
            } else {
                threads
            };
            py.detach(|| {
                self.plan
                    .restore_adaptive_values(payload, &order, planes, steps, out, threads, &push)
            })
            .map_err(broken)?
            .map_err(value_error)?;
        }
        Ok(array)
    }

    /// `mean_residuals` of a C-contiguous (K, cols) int64 array, column c with push `push[c]`
    /// (`None`: 2 for every column): a new array, or `None` if a value leaves the range;
    /// `ValueError` if the pushes do not fit. With `columns`, the new array is (cols, K), the
    /// residuals column after column (as a section streams them).
    #[pyo3(signature = (values, push=None, columns=false))]
    fn residuals<'py>(
        &self,
        py: Python<'py>,
        values: PyReadonlyArray2<'py, i64>,
        push: Option<&Bound<'py, PyAny>>,
        columns: bool,
    ) -> PyResult<Option<Bound<'py, PyArray2<i64>>>> {
        let (rows, width) = (values.shape()[0], values.shape()[1]);
        let push = pushes(push, width)?;
        let flat = values.as_slice()?;
        let out = py
            .detach(|| {
                if columns {
                    self.plan.residual_columns(flat, width, &push)
                } else {
                    self.plan.residuals(flat, width, &push)
                }
            })
            .map_err(value_error)?;
        let shape = if columns {
            [width, rows]
        } else {
            [rows, width]
        };
        out.map(|v| PyArray1::from_vec(py, v).reshape(shape))
            .transpose()
    }
    /// `rdo._residual_counts` of `residuals(values, push)`, for the encoder's rounding against
    /// predictor 2 (`rdo.quantize_mesh`), without the residuals: (cols, `table_size` + 1)
    /// int64 counts, or `None` if a value leaves the range.
    fn residual_counts<'py>(
        &self,
        py: Python<'py>,
        values: PyReadonlyArray2<'py, i64>,
        push: &Bound<'py, PyAny>,
        table_size: usize,
    ) -> PyResult<Option<Bound<'py, PyArray2<i64>>>> {
        let (rows, width) = (values.shape()[0], values.shape()[1]);
        let push = pushes(Some(push), width)?;
        let flat = values.as_slice()?;
        let counts = py
            .detach(|| {
                let Some(residual) = self.plan.residuals(flat, width, &push)? else {
                    return Ok(None);
                };
                encoder::zigzag_counts(&residual, rows, width, table_size)
                    .map(Some)
                    .map_err(|error| error.0)
            })
            .map_err(value_error)?;
        counts
            .map(|v| PyArray1::from_vec(py, v).reshape([width, table_size + 1]))
            .transpose()
    }

    /// `qmat._cost` of each column's predictor-2 residuals under each push, for the
    /// encoder's choice of push (`qmat._pushed_mean`): a (cols, 10) float64 array from a
    /// C-contiguous (K, cols) int64 array, `bits[m]` numpy's `log2(1 + 2m)` and the columns
    /// priced in blocks of `block` as `_cost` prices them; a row of NaN for a column with a
    /// residual beyond `bits` (the caller prices it), `None` if a value leaves the range.
    fn push_costs<'py>(
        &self,
        py: Python<'py>,
        values: PyReadonlyArray2<'py, i64>,
        bits: PyReadonlyArray1<'py, f64>,
        block: usize,
    ) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        let width = values.shape()[1];
        let (flat, bits) = (values.as_slice()?, bits.as_slice()?);
        let out = py
            .detach(|| self.plan.push_costs(flat, width, bits, block))
            .map_err(value_error)?;
        out.map(|v| PyArray1::from_vec(py, v).reshape([width, prediction::PUSH_COUNT]))
            .transpose()
    }
}

/// Predictor 1 along a tree, in place on a C-contiguous (rows, cols) int64 array.
#[pyfunction]
fn accumulate_tree(
    py: Python<'_>,
    mut values: PyReadwriteArray2<'_, i64>,
    parents: PyReadonlyArray1<'_, i64>,
) -> PyResult<()> {
    let width = values.shape()[1];
    let flat = values.as_slice_mut()?;
    let parents = parents.as_slice()?;
    py.detach(|| prediction::accumulate_tree(flat, width, parents))
        .map_err(value_error)
}

/// Predictor 1 along the rows (time), in place on a C-contiguous (rows, cols) int64 array.
#[pyfunction]
fn accumulate_rows(py: Python<'_>, mut values: PyReadwriteArray2<'_, i64>) -> PyResult<()> {
    let width = values.shape()[1];
    let flat = values.as_slice_mut()?;
    py.detach(|| prediction::accumulate_rows(flat, width));
    Ok(())
}

/// Predictor 3, in place on a C-contiguous (rows, cols) int64 array; `ValueError` with
/// `linear_accumulate`'s words when a difference or a value leaves its range.
#[pyfunction]
fn linear_accumulate(py: Python<'_>, mut values: PyReadwriteArray2<'_, i64>) -> PyResult<()> {
    let width = values.shape()[1];
    let flat = values.as_slice_mut()?;
    py.detach(|| prediction::linear_accumulate(flat, width))
        .map_err(value_error)
}

/// Adds the classes and functions of this module to `_native`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<MeshForest>()?;
    m.add_class::<MeanPlan>()?;
    m.add_function(wrap_pyfunction!(accumulate_tree, m)?)?;
    m.add_function(wrap_pyfunction!(accumulate_rows, m)?)?;
    m.add_function(wrap_pyfunction!(linear_accumulate, m)?)?;
    Ok(())
}
