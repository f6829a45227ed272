//! The text of an OBJ frame: `v x y z` lines (Python's `repr` of each number) and `f` lines,
//! as `tuckercodec/io/common/float_text.py` `vertex_text` and `tuckercodec/io/obj.py`
//! `_face_lines` write them.

use super::float_repr::{write_repr, write_signed};

/// The `v x y z` lines of `values` (x y z of each vertex in turn), each ended by a newline.
/// A last incomplete triple (when `values.len()` is not a multiple of 3) is left out.
pub fn vertex_text(values: &[f64]) -> Vec<u8> {
    // a typical number takes under 20 bytes
    let mut out = Vec::with_capacity(values.len() * 20 + 16);
    for xyz in values.chunks_exact(3) {
        out.push(b'v');
        for &value in xyz {
            out.push(b' ');
            write_repr(value, &mut out);
        }
        out.push(b'\n');
    }
    out
}

/// The `f` lines of a face table of `width` columns (0-based indices, negative for padding,
/// left out), 1-based, each ended by a newline. A last incomplete row is left out; a width
/// of 0 writes nothing.
pub fn face_text(faces: &[i64], width: usize) -> Vec<u8> {
    if width == 0 {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(faces.len() * 8 + 16);
    for row in faces.chunks_exact(width) {
        out.extend_from_slice(b"f ");
        let mut first = true;
        for &index in row.iter().filter(|&&index| index >= 0) {
            if !first {
                out.push(b' ');
            }
            first = false;
            // index >= 0, so index + 1 cannot overflow below i64::MAX; at i64::MAX Python
            // (numpy's int64 + 1) wraps, as wrapping_add does
            write_signed(index.wrapping_add(1), &mut out);
        }
        out.push(b'\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{face_text, vertex_text};

    #[test]
    fn lines() {
        assert_eq!(
            vertex_text(&[0.0, -1.5, 1e-5, 2.0, 3.0, 4.0]),
            b"v 0.0 -1.5 1e-05\nv 2.0 3.0 4.0\n"
        );
        assert_eq!(
            face_text(&[0, 1, 2, -1, 3, 4, 5, 6], 4),
            b"f 1 2 3\nf 4 5 6 7\n"
        );
        assert!(face_text(&[1, 2], 0).is_empty());
    }
}
