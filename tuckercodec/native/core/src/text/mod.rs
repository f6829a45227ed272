//! Text formats: Python's `repr` of floats, OBJ text written and read, and the checks a text
//! file passes while it is read a chunk at a time (the Python reference:
//! `tuckercodec/io/common/float_text.py` and `tuckercodec/io/obj.py`).
//!
//! Entry points suited to fuzzing (plain bytes in, no Python, no panics on any input):
//! - [`obj_read::parse_obj`]: the careful OBJ parser, `Ok(mesh)` or the first error;
//! - [`text_check::TextCheck`]: feed any chunks, then `finish`;
//! - [`float_repr::write_repr`] of any `f64` (round trip: the text parses back to the same bits);
//! - [`obj_write::vertex_text`] and [`obj_write::face_text`] of any values.

pub mod float_repr;
pub mod obj_read;
pub mod obj_write;
pub mod text_check;
