//! The text formats of tuckercodec-core (`tuckercodec_core::text`) for Python: OBJ frames
//! written (`obj_vertex_text`, `obj_face_text`) and read (`ObjTextCheck`, `obj_parse`), and
//! Python's `repr` of floats (`float_repr_text`).

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use tuckercodec_core::text::{float_repr, obj_read, obj_write, text_check};

create_exception!(
    _native,
    ObjError,
    PyValueError,
    "An OBJ text the reader refuses: args (line or None, message)."
);

/// The `v x y z` lines of a (K, 3) float64 array, every number as Python's `repr` writes it.
#[pyfunction]
fn obj_vertex_text<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyBytes>> {
    if vertices.shape()[1] != 3 {
        return Err(PyValueError::new_err("vertices must have shape (K, 3)"));
    }
    let values = vertices.as_slice()?;
    let text = py.detach(|| obj_write::vertex_text(values));
    Ok(PyBytes::new(py, &text))
}

/// The `f` lines of a (M, n) int64 face table (0-based, negative entries left out), 1-based.
#[pyfunction]
fn obj_face_text<'py>(
    py: Python<'py>,
    faces: PyReadonlyArray2<'py, i64>,
) -> PyResult<Bound<'py, PyBytes>> {
    let width = faces.shape()[1];
    let values = faces.as_slice()?;
    let text = py.detach(|| obj_write::face_text(values, width));
    Ok(PyBytes::new(py, &text))
}

/// Python's `repr` of each float64 of a 1-D array, each ended by a newline (for tests).
#[pyfunction]
fn float_repr_text<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyBytes>> {
    let values = values.as_slice()?;
    let text = py.detach(|| {
        let mut out = Vec::with_capacity(values.len() * 24);
        for &value in values {
            float_repr::write_repr(value, &mut out);
            out.push(b'\n');
        }
        out
    });
    Ok(PyBytes::new(py, &text))
}

/// What `obj_parse` returns: vertices, faces (or None: the known ones), the face key.
type ParsedObj<'py> = (
    Bound<'py, PyAny>,
    Option<Bound<'py, PyAny>>,
    Option<Bound<'py, PyBytes>>,
);

/// Parses a whole OBJ text: `(vertices (K, 3) float64, faces (M, n) int64 or None, face_key
/// bytes or None)`, or raises `ObjError(line, message)` with the reference's first
/// error. Given the `face_key` and vertex count of an earlier frame, faces equal to that
/// frame's are not parsed again: `None` in their place.
#[pyfunction]
#[pyo3(signature = (data, face_key=None, vertex_count=0))]
fn obj_parse<'py>(
    py: Python<'py>,
    data: &[u8],
    face_key: Option<&[u8]>,
    vertex_count: usize,
) -> PyResult<ParsedObj<'py>> {
    let known = face_key.map(|face_key| obj_read::KnownFaces {
        face_key,
        vertex_count,
    });
    let parsed = py.detach(|| obj_read::parse_obj_frame(data, known));
    match parsed {
        Ok(frame) => {
            let mesh = frame.mesh;
            let count = mesh.vertices.len() / 3;
            let vertices = PyArray1::from_vec(py, mesh.vertices).reshape([count, 3])?;
            let faces = if frame.shared {
                None
            } else {
                let table = PyArray1::from_vec(py, mesh.faces);
                Some(table.reshape([mesh.face_count, mesh.width])?.into_any())
            };
            let key = frame.face_key.map(|key| PyBytes::new(py, &key));
            Ok((vertices.into_any(), faces, key))
        }
        Err(error) => Err(ObjError::new_err((error.line, error.message))),
    }
}

/// The checks of a text file read a chunk at a time: `feed(chunk)` and `finish()` return
/// `None`, or `(kind, line)` for the first fault (kind: "nul", "utf8", "long", "truncated").
#[pyclass(module = "tuckercodec._native")]
struct ObjTextCheck {
    inner: text_check::TextCheck,
}

#[pymethods]
impl ObjTextCheck {
    #[new]
    fn new(limit: u64) -> Self {
        ObjTextCheck {
            inner: text_check::TextCheck::new(limit),
        }
    }

    /// Checks the next chunk.
    fn feed(&mut self, chunk: &[u8]) -> Option<(&'static str, u64)> {
        self.inner
            .feed(chunk)
            .err()
            .map(|fault| (fault.kind.name(), fault.line))
    }

    /// Checks the end of the text.
    fn finish(&self) -> Option<(&'static str, u64)> {
        self.inner
            .finish()
            .err()
            .map(|fault| (fault.kind.name(), fault.line))
    }
}

/// Adds the text functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("ObjError", m.py().get_type::<ObjError>())?;
    m.add_class::<ObjTextCheck>()?;
    m.add_function(wrap_pyfunction!(obj_vertex_text, m)?)?;
    m.add_function(wrap_pyfunction!(obj_face_text, m)?)?;
    m.add_function(wrap_pyfunction!(float_repr_text, m)?)?;
    m.add_function(wrap_pyfunction!(obj_parse, m)?)?;
    Ok(())
}
