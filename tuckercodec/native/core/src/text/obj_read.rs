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
}

fn error(line: u64, message: String) -> ObjError {
    ObjError {
        line: Some(line),
        message,
    }
}

/// The numbers a `v` line may have: x y z, x y z w, x y z r g b, x y z r g b a.
const VERTEX_NUMBER_COUNTS: [usize; 4] = [3, 4, 6, 7];
/// A face index of more digits than this is out of range for any file (and of i64).
const MAX_INDEX_DIGITS: usize = 18;
const PADDED_PER_CORNER: u128 = 16;
const PADDED_AT_LEAST: u128 = 1 << 24;

/// The class of each byte for the tokenizer: part of a token, a blank between tokens, a line
/// end, or the start of a comment.
const TOKEN: u8 = 0;
const BLANK: u8 = 1;
const LINE_END: u8 = 2;
const COMMENT: u8 = 3;
const CLASSES: [u8; 256] = {
    let mut classes = [TOKEN; 256];
    classes[b' ' as usize] = BLANK;
    classes[b'\t' as usize] = BLANK;
    classes[0x0b] = BLANK;
    classes[0x0c] = BLANK;
    classes[b'\n' as usize] = LINE_END;
    classes[b'\r' as usize] = LINE_END;
    classes[b'#' as usize] = COMMENT;
    classes
};

/// Calls `statement(line number, tokens)` for every statement with tokens, in order.
pub fn statements<'a, E>(
    data: &'a [u8],
    mut statement: impl FnMut(u64, &[&'a [u8]]) -> Result<(), E>,
) -> Result<(), E> {
    let mut tokens: Vec<&'a [u8]> = Vec::new();
    let mut pending = false;
    let mut pending_line = 0u64;
    let mut number = 0u64;
    let mut at = 0usize;
    while at < data.len() {
        number += 1;
        // one pass over the line: its tokens up to its end or its comment
        let mut content_end = data.len();
        loop {
            while data
                .get(at)
                .is_some_and(|&c| CLASSES[usize::from(c)] == BLANK)
            {
                at += 1;
            }
            let start = at;
            while data
                .get(at)
                .is_some_and(|&c| CLASSES[usize::from(c)] == TOKEN)
            {
                at += 1;
            }
            if at > start {
                tokens.push(&data[start..at]);
            }
            match data.get(at) {
                Some(&c) if CLASSES[usize::from(c)] == BLANK => {}
                Some(_) => {
                    content_end = at;
                    break;
                }
                None => break,
            }
        }
        // past the comment to the line end, and past that ("\r\n" is one)
        while let Some(&c) = data.get(at) {
            if c == b'\n' || c == b'\r' {
                break;
            }
            at += 1;
        }
        if data.get(at) == Some(&b'\r') && data.get(at + 1) == Some(&b'\n') {
            at += 1;
        }
        at += 1;
        // a backslash last (before the comment) continues the statement on the next line; it
        // ends the last token, which loses it (and is gone if it was only that)
        let continued = content_end > 0 && data.get(content_end - 1) == Some(&b'\\');
        if continued {
            if let Some(last) = tokens.pop() {
                if last.len() > 1 {
                    tokens.push(&last[..last.len() - 1]);
                }
            }
            if !pending {
                pending_line = number;
                pending = true;
            }
            continue;
        }
        let line = if pending { pending_line } else { number };
        pending = false;
        if !tokens.is_empty() {
            statement(line, &tokens)?;
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
    finish(vertices, corners, &face_starts, &face_lines)
}

/// The faces of an earlier frame, which a frame of the same face statements shares.
#[derive(Debug, Clone, Copy)]
pub struct KnownFaces<'a> {
    /// The [`ParsedFrame::face_key`] of the earlier frame.
    pub face_key: &'a [u8],
    /// Its vertex count.
    pub vertex_count: usize,
}

/// A frame parsed by [`parse_obj_frame`].
#[derive(Debug, Clone, PartialEq)]
pub struct ParsedFrame {
    /// The mesh; its `faces` empty when `shared` (the known faces are the frame's).
    pub mesh: ObjMesh,
    /// The faces are the known ones, not parsed again.
    pub shared: bool,
    /// The face statements' tokens (each statement's joined by a space, ended by a newline),
    /// when none holds a `-`: equal keys then mean equal faces, wherever the vertices are.
    pub face_key: Option<Vec<u8>>,
}

/// [`parse_obj`] for a frame of a sequence: when its face statements are those of `known`
/// (without negative, relative indices) and it has as many vertices, its faces are not parsed
/// again (they are the known ones, and valid: nothing else in the file changes that). Any
/// other frame is parsed whole, so results and errors are always [`parse_obj`]'s.
pub fn parse_obj_frame(
    data: &[u8],
    known: Option<KnownFaces<'_>>,
) -> Result<ParsedFrame, ObjError> {
    let Some(known) = known else {
        let mesh = parse_obj(data)?;
        return Ok(ParsedFrame {
            face_key: face_key(data),
            mesh,
            shared: false,
        });
    };
    let mut vertices: Vec<f64> = Vec::new();
    let mut key: Vec<u8> = Vec::with_capacity(known.face_key.len());
    let first_pass: Result<(), ObjError> = statements(data, |line, tokens| {
        match tokens[0] {
            b"v" => {
                let xyz = vertex(&tokens[1..], line)?;
                vertices.extend_from_slice(&xyz);
            }
            b"f" => append_key(&mut key, tokens),
            _ => {}
        }
        Ok(())
    });
    if first_pass.is_err() {
        // a face statement above the vertex at fault may be at fault first: parsed whole
        let mesh = parse_obj(data)?;
        return Ok(ParsedFrame {
            face_key: face_key(data),
            mesh,
            shared: false,
        });
    }
    let reusable = !key.contains(&b'-');
    if reusable
        && key == known.face_key
        && vertices.len() / 3 == known.vertex_count
        && !vertices.is_empty()
    {
        let mesh = ObjMesh {
            vertices,
            faces: Vec::new(),
            face_count: 0,
            width: 0,
        };
        return Ok(ParsedFrame {
            mesh,
            shared: true,
            face_key: Some(key),
        });
    }
    let mesh = parse_obj(data)?;
    Ok(ParsedFrame {
        mesh,
        shared: false,
        face_key: reusable.then_some(key),
    })
}

/// The face key of [`ParsedFrame::face_key`] of a whole text.
fn face_key(data: &[u8]) -> Option<Vec<u8>> {
    let mut key = Vec::new();
    let _ = statements::<()>(data, |_, tokens| {
        if tokens[0] == b"f" {
            append_key(&mut key, tokens);
        }
        Ok(())
    });
    (!key.contains(&b'-')).then_some(key)
}

fn append_key(key: &mut Vec<u8>, tokens: &[&[u8]]) {
    for (at, token) in tokens.iter().enumerate() {
        if at > 0 {
            key.push(b' ');
        }
        key.extend_from_slice(token);
    }
    key.push(b'\n');
}

/// The checks after all statements, and the padded face table.
fn finish(
    vertices: Vec<f64>,
    corners: Vec<i64>,
    face_starts: &[usize],
    face_lines: &[u64],
) -> Result<ObjMesh, ObjError> {
    let vertex_count = vertices.len() / 3;
    if vertex_count == 0 {
        return Err(ObjError {
            line: None,
            message: "no vertices: the file has no 'v' lines".to_string(),
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

/// Exact powers of ten as f64 (10**22 is the last).
const POWERS_OF_TEN: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The value of a plain decimal `[+-]?\d*(\.\d*)?` (no exponent, a digit somewhere) when its
/// digits as an integer are at most 2**53 and at most 22 of them follow the point: then one
/// correctly rounded division of two exact floats gives it (Clinger's fast path), the same
/// float as Python's `float()`. `None` for anything else (left to the full parse).
fn simple_decimal(token: &[u8]) -> Option<f64> {
    let negative = token.first() == Some(&b'-');
    let unsigned = &token[usize::from(matches!(token.first(), Some(b'+' | b'-')))..];
    // at most 19 digits and a point; 20 digits without one would overflow u64, and go to the
    // general parse (checked below, so that no build wraps or panics)
    if unsigned.is_empty() || unsigned.len() > 20 {
        return None;
    }
    let mut mantissa = 0u64;
    let mut point: Option<usize> = None;
    for (at, &c) in unsigned.iter().enumerate() {
        let digit = c.wrapping_sub(b'0');
        if digit < 10 {
            mantissa = mantissa.checked_mul(10)?.checked_add(u64::from(digit))?;
        } else if c == b'.' && point.is_none() {
            point = Some(at);
        } else {
            return None;
        }
    }
    let digits = unsigned.len() - usize::from(point.is_some());
    if digits == 0 || digits > 19 || mantissa > 1 << 53 {
        return None;
    }
    let decimals = point.map_or(0, |at| unsigned.len() - at - 1);
    let divisor = POWERS_OF_TEN.get(decimals)?;
    let magnitude = mantissa as f64 / divisor;
    Some(if negative { -magnitude } else { magnitude })
}

/// A number of a `v` line: a decimal number, or nan/inf (to be refused as x, y or z).
fn number(token: &[u8], line: u64) -> Result<f64, ObjError> {
    if let Some(value) = simple_decimal(token) {
        return Ok(value);
    }
    if is_decimal(token) {
        // ASCII by the check above; Rust's parse is correctly rounded, as Python's float()
        let parsed = std::str::from_utf8(token)
            .ok()
            .and_then(|t| t.parse::<f64>().ok());
        return parsed.ok_or_else(|| error(line, format!("not a number: {}", quoted(token))));
    }
    // one sign at most, as float() takes: "+-inf" is not a number
    let unsigned = match token.first() {
        Some(b'+' | b'-') => &token[1..],
        _ => token,
    };
    let lower = unsigned.to_ascii_lowercase();
    if matches!(lower.as_slice(), b"nan" | b"inf" | b"infinity") {
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
        if let Some(value) = plain_index(corner) {
            if value <= vertices_so_far as u64 || !corner.starts_with(b"-") {
                out.push(if corner.starts_with(b"-") {
                    vertices_so_far as i64 - value as i64
                } else {
                    value as i64 - 1
                });
                continue;
            }
        }
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

/// The vertex number of a tidy corner in one pass: a sign or none, 1 to 18 digits, not zero,
/// then the end or a `/`; `None` for anything else (left to the full checks).
fn plain_index(corner: &[u8]) -> Option<u64> {
    let unsigned = &corner[usize::from(matches!(corner.first(), Some(b'+' | b'-')))..];
    let mut value = 0u64;
    let mut digits = 0usize;
    for &c in unsigned {
        let digit = c.wrapping_sub(b'0');
        if digit >= 10 {
            if c == b'/' {
                break;
            }
            return None;
        }
        value = value.wrapping_mul(10).wrapping_add(u64::from(digit));
        digits += 1;
        if digits > MAX_INDEX_DIGITS {
            return None; // leading zeros too: the full checks count without them
        }
    }
    (digits > 0 && value > 0).then_some(value)
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
    use super::{is_decimal, parse_obj, parse_obj_frame, KnownFaces};

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

    #[test]
    fn frames_share_known_faces() {
        let first = parse_obj_frame(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", None).unwrap();
        let key = first.face_key.clone().unwrap();
        let known = KnownFaces {
            face_key: &key,
            vertex_count: 3,
        };
        let same = parse_obj_frame(b"v 0 0 1\nv 1 0 1\nf  1 2\t3\nv 0 1 1\n", Some(known)).unwrap();
        assert!(same.shared);
        assert_eq!(
            same.mesh.vertices,
            vec![0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 1.0, 1.0]
        );
        // another vertex count: parsed whole, and refused as parse_obj refuses it
        let fewer = parse_obj_frame(b"v 0 0 1\nv 1 0 1\nf 1 2 3\n", Some(known));
        assert_eq!(
            fewer,
            Err(parse_obj(b"v 0 0 1\nv 1 0 1\nf 1 2 3\n").unwrap_err())
        );
        // relative indices: never a key
        let relative = parse_obj_frame(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n", None);
        assert_eq!(relative.unwrap().face_key, None);
    }

    /// Random bytes and mutated texts: no panic, and a frame read against known faces gives
    /// what the whole parse gives.
    #[test]
    fn any_bytes() {
        let seed_text: &[u8] = b"v 0 0 0\nv 1 0 0 # c\nv 0 1 0 \\\n\nf 1 2/1 3//4\nf 3 2 1 1\n";
        let first = parse_obj_frame(seed_text, None).unwrap();
        let key = first.face_key.clone().unwrap();
        let pieces: [&[u8]; 12] = [
            b" ", b"\n", b"\r", b"#", b"\\", b"-", b"/", b"0", b"f ", b"v ", b"1e999", b"\xff",
        ];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move |bound: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % bound as u64) as usize
        };
        for _ in 0..20_000 {
            let mut text = seed_text.to_vec();
            for _ in 0..1 + next(3) {
                let at = next(text.len() + 1);
                if next(2) == 0 && at < text.len() {
                    text.remove(at);
                } else {
                    let piece = pieces[next(pieces.len())];
                    text.splice(at..at, piece.iter().copied());
                }
            }
            let whole = parse_obj(&text);
            let known = KnownFaces {
                face_key: &key,
                vertex_count: 3,
            };
            match parse_obj_frame(&text, Some(known)) {
                Ok(frame) if frame.shared => {
                    let mesh = whole.unwrap();
                    assert_eq!(mesh.vertices, frame.mesh.vertices);
                    assert_eq!(mesh.faces, first.mesh.faces);
                }
                Ok(frame) => assert_eq!(Ok(frame.mesh), whole),
                Err(error) => assert_eq!(Err(error), whole),
            }
        }
    }
}
