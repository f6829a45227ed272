//! The OBJ reader's careful parser (`tuckercodec/io/obj.py` `_parse_careful`): the `v`
//! positions and the `f` faces of a whole file, or the first error as the reference reports
//! it (same line, same message).
//!
//! Statements are lines (ended by `\n`, `\r\n` or a lone `\r`) without their `#` comment; a
//! line ending in a backslash continues on the next one and the statement keeps its first
//! line's number. Tokens are split at ASCII whitespace (`bytes.split()`).

/// A parsed OBJ mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjMesh {
    /// x y z of each vertex in file order.
    pub vertices: Vec<f64>,
    /// The faces, 0-based, each row `width` long, short rows padded with -1.
    pub faces: Vec<i64>,
    /// The number of faces.
    pub face_count: usize,
    /// The columns of the face table (3 when there are no faces).
    pub width: usize,
}

/// An OBJ text the reference refuses: its message and the 1-based line at fault, if any.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObjError {
    /// The 1-based line at fault, `None` for the whole file.
    pub line: Option<u64>,
    /// The reference's message (the tokens quoted approximately where they are not printable
    /// ASCII, see [`quoted`]).
    pub message: String,
    /// The reference raises a plain `ValueError` here (`float()` of a token such as `+-inf`,
    /// which its check lets through), not an `InputError`.
    pub value_error: bool,
}

fn error(line: u64, message: String) -> ObjError {
    ObjError {
        line: Some(line),
        message,
        value_error: false,
    }
}

/// The numbers a `v` line may have: x y z, x y z w, x y z r g b, x y z r g b a.
const VERTEX_NUMBER_COUNTS: [usize; 4] = [3, 4, 6, 7];
/// A face index of more digits than this is out of range for any file (and of i64).
const MAX_INDEX_DIGITS: usize = 18;
const PADDED_PER_CORNER: u128 = 16;
const PADDED_AT_LEAST: u128 = 1 << 24;

fn is_space(c: u8) -> bool {
    matches!(c, b' ' | b'\t' | b'\n' | b'\r' | 0x0b | 0x0c)
}

/// Calls `statement(line number, tokens)` for every statement with tokens, in order.
fn statements<'a, E>(
    data: &'a [u8],
    mut statement: impl FnMut(u64, &[&'a [u8]]) -> Result<(), E>,
) -> Result<(), E> {
    let mut tokens: Vec<&'a [u8]> = Vec::new();
    let mut pending = false;
    let mut pending_line = 0u64;
    let mut number = 0u64;
    let mut start = 0usize;
    while start < data.len() {
        number += 1;
        let end = data[start..]
            .iter()
            .position(|&c| c == b'\n' || c == b'\r')
            .map_or(data.len(), |at| start + at);
        let mut next = end.saturating_add(1);
        if data.get(end) == Some(&b'\r') && data.get(end + 1) == Some(&b'\n') {
            next = end + 2;
        }
        let mut line = &data[start..end];
        start = next;
        if let Some(hash) = line.iter().position(|&c| c == b'#') {
            line = &line[..hash];
        }
        let continued = line.last() == Some(&b'\\');
        if continued {
            line = &line[..line.len() - 1];
            if !pending {
                pending_line = number;
                pending = true;
            }
        }
        // pieces of a continued statement are joined by a space, so their tokens never merge
        tokens.extend(line.split(|&c| is_space(c)).filter(|t| !t.is_empty()));
        if continued {
            continue;
        }
        let at = if pending { pending_line } else { number };
        pending = false;
        if !tokens.is_empty() {
            statement(at, &tokens)?;
            tokens.clear();
        }
    }
    if pending && !tokens.is_empty() {
        statement(pending_line, &tokens)?;
    }
    Ok(())
}

/// Parses a whole OBJ text as the reference's careful parser does.
pub fn parse_obj(data: &[u8]) -> Result<ObjMesh, ObjError> {
    let mut vertices: Vec<f64> = Vec::new();
    let mut corners: Vec<i64> = Vec::new();
    // per face: its first corner in `corners`, its line
    let mut face_starts: Vec<usize> = Vec::new();
    let mut face_lines: Vec<u64> = Vec::new();
    statements(data, |line, tokens| {
        match tokens[0] {
            b"v" => {
                let xyz = vertex(&tokens[1..], line)?;
                vertices.extend_from_slice(&xyz);
            }
            b"f" => {
                face_starts.push(corners.len());
                face_lines.push(line);
                face(&tokens[1..], vertices.len() / 3, line, &mut corners)?;
            }
            _ => {}
        }
        Ok(())
    })?;
    let vertex_count = vertices.len() / 3;
    if vertex_count == 0 {
        return Err(ObjError {
            line: None,
            message: "no vertices: the file has no 'v' lines".to_string(),
            value_error: false,
        });
    }
    let face_count = face_starts.len();
    let mut widest = (0usize, 0usize); // (size, face)
    for face in 0..face_count {
        let span = face_starts[face]..face_starts.get(face + 1).copied().unwrap_or(corners.len());
        for &index in &corners[span.clone()] {
            if index >= vertex_count as i64 {
                return Err(error(
                    face_lines[face],
                    format!(
                        "face refers to vertex {}, but the file has only {vertex_count} vertices",
                        i128::from(index) + 1
                    ),
                ));
            }
        }
        if span.len() > widest.0 {
            widest = (span.len(), face);
        }
    }
    if face_count == 0 {
        return Ok(ObjMesh {
            vertices,
            faces: Vec::new(),
            face_count: 0,
            width: 3,
        });
    }
    let width = widest.0;
    let padded = face_count as u128 * width as u128;
    if padded > PADDED_AT_LEAST.max(PADDED_PER_CORNER * corners.len() as u128) {
        let gib = padded as f64 * 8.0 / (1u64 << 30) as f64;
        return Err(error(
            face_lines[widest.1],
            format!(
                "a face of {width} corners: padding all {face_count} faces to its width would \
                 take {gib:.1} GiB; split the polygon"
            ),
        ));
    }
    let faces = if corners.len() == face_count * width {
        corners
    } else {
        let mut table = vec![-1i64; face_count * width];
        for face in 0..face_count {
            let span =
                face_starts[face]..face_starts.get(face + 1).copied().unwrap_or(corners.len());
            let row = face * width;
            table[row..row + span.len()].copy_from_slice(&corners[span]);
        }
        table
    };
    Ok(ObjMesh {
        vertices,
        faces,
        face_count,
        width,
    })
}

/// The x y z of a `v` line's numbers.
fn vertex(numbers: &[&[u8]], line: u64) -> Result<[f64; 3], ObjError> {
    if !VERTEX_NUMBER_COUNTS.contains(&numbers.len()) {
        return Err(error(
            line,
            format!(
                "a 'v' line needs x y z (optionally w, or an r g b [a] colour), got {} value(s)",
                numbers.len()
            ),
        ));
    }
    let mut xyz = [0.0f64; 3];
    for (position, token) in numbers.iter().enumerate() {
        let value = number(token, line)?;
        if let Some(slot) = xyz.get_mut(position) {
            *slot = value;
        }
    }
    if !xyz.iter().all(|value| value.is_finite()) {
        let shown: Vec<String> = numbers[..3].iter().map(|token| short(token)).collect();
        return Err(error(
            line,
            format!("non-finite vertex coordinate: {}", shown.join(" ")),
        ));
    }
    Ok(xyz)
}

/// Whether `token` is a plain decimal number: `[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?`.
pub fn is_decimal(token: &[u8]) -> bool {
    let digits =
        |text: &[u8], at: usize| text[at..].iter().take_while(|c| c.is_ascii_digit()).count();
    let mut at = usize::from(matches!(token.first(), Some(b'+' | b'-')));
    let whole = digits(token, at);
    at += whole;
    let mut fraction = 0;
    if token.get(at) == Some(&b'.') {
        at += 1;
        fraction = digits(token, at);
        at += fraction;
    }
    if whole == 0 && fraction == 0 {
        return false;
    }
    if matches!(token.get(at), Some(b'e' | b'E')) {
        at += 1;
        at += usize::from(matches!(token.get(at), Some(b'+' | b'-')));
        let exponent = digits(token, at);
        if exponent == 0 {
            return false;
        }
        at += exponent;
    }
    at == token.len()
}

/// A number of a `v` line: a decimal number, or nan/inf (to be refused as x, y or z).
fn number(token: &[u8], line: u64) -> Result<f64, ObjError> {
    if is_decimal(token) {
        // ASCII by the check above; Rust's parse is correctly rounded, as Python's float()
        let parsed = std::str::from_utf8(token)
            .ok()
            .and_then(|t| t.parse::<f64>().ok());
        return parsed.ok_or_else(|| error(line, format!("not a number: {}", quoted(token))));
    }
    let unsigned = {
        let signs = token
            .iter()
            .take_while(|&&c| c == b'+' || c == b'-')
            .count();
        &token[signs..]
    };
    let lower = unsigned.to_ascii_lowercase();
    if matches!(lower.as_slice(), b"nan" | b"inf" | b"infinity") {
        if token.len() - unsigned.len() > 1 {
            // the reference's float() refuses two signs with a ValueError
            return Err(ObjError {
                line: Some(line),
                message: format!(
                    "could not convert string to float: b'{}'",
                    String::from_utf8_lossy(token)
                ),
                value_error: true,
            });
        }
        return Ok(if lower == b"nan" {
            f64::NAN
        } else {
            f64::INFINITY
        });
    }
    Err(error(line, format!("not a number: {}", quoted(token))))
}

/// Appends the 0-based vertex indices of a face's corners to `out`.
fn face(
    corners: &[&[u8]],
    vertices_so_far: usize,
    line: u64,
    out: &mut Vec<i64>,
) -> Result<(), ObjError> {
    if corners.len() < 3 {
        return Err(error(
            line,
            format!("a face needs at least 3 corners, got {}", corners.len()),
        ));
    }
    for corner in corners {
        let text = corner.split(|&c| c == b'/').next().unwrap_or(&[]);
        let negative = text.first() == Some(&b'-');
        let unsigned = &text[usize::from(matches!(text.first(), Some(b'+' | b'-')))..];
        if unsigned.is_empty() || !unsigned.iter().all(u8::is_ascii_digit) {
            return Err(error(
                line,
                format!("face corner {} is not a vertex index", quoted(corner)),
            ));
        }
        let zeros = unsigned.iter().take_while(|&&c| c == b'0').count();
        let digits = &unsigned[zeros..];
        if digits.len() > MAX_INDEX_DIGITS {
            return Err(error(
                line,
                format!(
                    "face corner {} refers to a vertex number of {} digits, more than any file holds",
                    quoted(corner),
                    digits.len()
                ),
            ));
        }
        // at most 18 digits: fits in i64
        let magnitude = digits
            .iter()
            .fold(0i64, |total, &c| total * 10 + i64::from(c - b'0'));
        if magnitude == 0 {
            return Err(error(
                line,
                format!(
                    "face corner {}: OBJ indices start at 1, 0 is invalid",
                    quoted(corner)
                ),
            ));
        }
        if negative {
            if magnitude > vertices_so_far as i64 {
                return Err(error(
                    line,
                    format!(
                        "face corner {} counts back past the first vertex (only {vertices_so_far} defined so far)",
                        quoted(corner)
                    ),
                ));
            }
            out.push(vertices_so_far as i64 - magnitude);
        } else {
            out.push(magnitude - 1);
        }
    }
    Ok(())
}

/// A token as the reference's messages show it (`_short`): its first 40 characters and
/// "..." if it is longer.
pub fn short(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(token);
    if text.chars().count() <= 40 {
        text.into_owned()
    } else {
        let mut cut: String = text.chars().take(40).collect();
        cut.push_str("...");
        cut
    }
}

/// [`short`] in quotes as Python's `repr` of a str writes it, exactly for printable ASCII
/// (other characters are escaped only approximately: the Python side never shows this text).
pub fn quoted(token: &[u8]) -> String {
    let text = short(token);
    let quote = if text.contains('\'') && !text.contains('"') {
        '"'
    } else {
        '\''
    };
    let mut out = String::with_capacity(text.len() + 2);
    out.push(quote);
    for c in text.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '\t' => out.push_str("\\t"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            c if c == quote => {
                out.push('\\');
                out.push(c);
            }
            c if (c as u32) < 0x20 || c as u32 == 0x7f => {
                out.push_str(&format!("\\x{:02x}", c as u32));
            }
            c => out.push(c),
        }
    }
    out.push(quote);
    out
}

#[cfg(test)]
mod tests {
    use super::{is_decimal, parse_obj};

    #[test]
    fn decimals() {
        for good in ["1", "+1", "-1.", ".5", "1e5", "1.5E-3", "007"] {
            assert!(is_decimal(good.as_bytes()), "{good}");
        }
        for bad in [
            "", ".", "+", "1e", "e5", "1_0", "0x1", "1.2.3", "--1", "nan", " 1",
        ] {
            assert!(!is_decimal(bad.as_bytes()), "{bad}");
        }
    }

    #[test]
    fn parses() {
        let mesh =
            parse_obj(b"# c\nv 0 0 0\nv 1 0 0 \\\n  # x\nv 0 1 0 1\nf 1 2/5/6 -1//2\nf 1 2 3 1\n")
                .unwrap();
        assert_eq!(mesh.vertices.len(), 9);
        assert_eq!(mesh.width, 4);
        assert_eq!(mesh.faces, vec![0, 1, 2, -1, 0, 1, 2, 0]);
    }

    #[test]
    fn errors() {
        let cases: &[(&[u8], Option<u64>, &str)] = &[
            (b"f 1 2 3\n", None, "no vertices"),
            (
                b"v 1 2 3\nf -2 1 1\n",
                Some(2),
                "face corner '-2' counts back past",
            ),
            (b"v 1 2\n", Some(1), "a 'v' line needs"),
            (b"v 1 2 x\n", Some(1), "not a number: 'x'"),
            (
                b"v 1 2 inf\n",
                Some(1),
                "non-finite vertex coordinate: 1 2 inf",
            ),
            (
                b"v 1 2 3\nf 1 2\n",
                Some(2),
                "a face needs at least 3 corners, got 2",
            ),
            (
                b"v 1 2 3\nf 1 1 0\n",
                Some(2),
                "face corner '0': OBJ indices start at 1",
            ),
            (
                b"v 1 2 3\nf 1 1 4\n",
                Some(2),
                "face refers to vertex 4, but the file has only 1",
            ),
            (b"vt 1 2\n", None, "no vertices"),
        ];
        for &(text, line, start) in cases {
            let found = parse_obj(text).unwrap_err();
            assert_eq!(found.line, line);
            let prefix = &start[..start.len().min(found.message.len())];
            assert!(found.message.starts_with(prefix), "{}", found.message);
        }
    }
}
