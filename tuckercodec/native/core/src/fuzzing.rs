//! The fuzz targets' input framing and checks (`tuckercodec/native/fuzz/`, run by cargo-fuzz),
//! here so that `cargo test` replays the committed seeds through the very same code
//! (`core/tests/fuzz_seeds.rs`, seeds in `tests/fuzz/native/<target>/`).
//!
//! Each target takes any bytes, decodes them into the arguments of one entry point of the core
//! with a small framing (below), calls it, and panics only where a property fails: the entry
//! points themselves must never panic, whatever the bytes. Sizes are bounded by the framing
//! (widths up to 8, counts up to 2**16, vertex counts of the encoder up to 2**20), so that the
//! memory a run takes is bounded too.
//!
//! Integers in the framings are LEB128 varints ([`Framing::varint`]: 7 bits a byte, low
//! first, a set high bit means more; at most 10 bytes; a varint cut by the end of the input
//! reads what it has) and signed ones are zigzag varints ([`Framing::signed`]: 0, -1, 1, -2,
//! 2, ...). Bytes read past the end of the input are 0. `tools/fuzz/native_seeds.py` writes
//! the same framings from the conformance vectors.

use crate::adaptive::{self, CodingOrder};
use crate::prediction::topology::Forest;
use crate::prediction::{accumulate_rows, accumulate_tree, linear_accumulate, MeanPlan};
use crate::residual::{correct, pack_chunk, restore_chunk, Domain};
use crate::streams::{pack_planes, unpack_planes, unpack_planes_into};
use crate::text::float_repr::{repr, write_signed, write_unsigned};
use crate::text::obj_read::{parse_obj, parse_obj_frame, KnownFaces, ObjMesh};
use crate::text::obj_write::{face_text, vertex_text};
use crate::text::text_check::TextCheck;
use crate::traversal::{self, Streams};

/// A fuzz target: any bytes in, a panic only where a property fails.
pub type Target = fn(&[u8]);

/// Every fuzz target: its name (the cargo-fuzz target and the seed folder) and its function.
pub const TARGETS: &[(&str, Target)] = &[
    ("traversal_decode", traversal_decode),
    ("traversal_roundtrip", traversal_roundtrip),
    ("obj_parse", obj_parse),
    ("float_repr", float_repr),
    ("text_check", text_check),
    ("residual_restore", residual_restore),
    ("residual_correct", residual_correct),
    ("streams_unpack", streams_unpack),
    ("prediction_restore", prediction_restore),
    ("adaptive_decode", adaptive_decode),
    ("adaptive_roundtrip", adaptive_roundtrip),
];

/// The most faces a decode is asked for, and the most rows an encode is given.
pub const MAX_COUNT: u64 = 1 << 16;
/// The most vertices (and rows) a prediction is given.
pub const MAX_PREDICTION_VERTICES: u64 = 1 << 12;
/// The widest face table.
pub const MAX_WIDTH: usize = 8;
/// The most columns an adaptive stream is decoded into, or encoded from.
pub const MAX_ADAPTIVE_COLUMNS: u64 = 16;
/// The most vertices an encode is given (its tables take one entry a vertex).
pub const MAX_ENCODER_VERTICES: u64 = 1 << 20;

/// A cursor over the fuzzer's bytes.
pub struct Framing<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Framing<'a> {
    /// Reads `data` from its start.
    pub fn new(data: &'a [u8]) -> Self {
        Framing { data, at: 0 }
    }

    /// The input is read to its end.
    pub fn is_empty(&self) -> bool {
        self.at >= self.data.len()
    }

    /// The next byte, 0 past the end.
    pub fn byte(&mut self) -> u8 {
        let value = self.data.get(self.at).copied().unwrap_or(0);
        self.at = self.at.saturating_add(1);
        value
    }

    /// The next LEB128 varint (at most 10 bytes; bits beyond 64 are dropped).
    pub fn varint(&mut self) -> u64 {
        let mut value = 0u64;
        for shift in (0..70).step_by(7) {
            if self.is_empty() {
                break;
            }
            let byte = self.byte();
            if shift < 64 {
                value |= u64::from(byte & 0x7f) << shift;
            }
            if byte & 0x80 == 0 {
                break;
            }
        }
        value
    }

    /// The next zigzag varint.
    pub fn signed(&mut self) -> i64 {
        let value = self.varint();
        ((value >> 1) as i64) ^ -((value & 1) as i64)
    }

    /// Up to `count` zigzag varints, fewer where the input ends first.
    pub fn signed_values(&mut self, count: u64) -> Vec<i64> {
        let mut values = Vec::new();
        let mut left = count;
        while left > 0 && !self.is_empty() {
            values.push(self.signed());
            left -= 1;
        }
        values
    }

    /// The next 8 bytes as a little-endian `f64` (0 bytes past the end).
    pub fn float(&mut self) -> f64 {
        f64::from_le_bytes([0; 8].map(|_: u8| self.byte()))
    }

    /// The bytes not read yet.
    pub fn rest(&self) -> &'a [u8] {
        self.data.get(self.at..).unwrap_or(&[])
    }
}

/// `traversal::decode` of any streams. Framing: a byte whose low bit is `corner_order`; a byte
/// `b` for `width = 1 + b % 8`; a varint `count` (at most 2**16); a signed `k`; four varint
/// stream lengths (ops, degrees, vertices, references); then the streams' values, signed, in
/// that order (a stream cut short by the end of the input is shorter).
///
/// Checks: no panic, and a decoded table is `count` rows of `width`, each a face of 3 or more
/// vertices in `0..k` followed by -1 padding.
pub fn traversal_decode(data: &[u8]) {
    let mut input = Framing::new(data);
    let corner_order = i64::from(input.byte() & 1);
    let width = 1 + usize::from(input.byte()) % MAX_WIDTH;
    let count = input.varint().min(MAX_COUNT) as usize;
    let k = input.signed();
    let lengths = [0; 4].map(|_: u8| input.varint());
    let [ops, degrees, vertices, references] = lengths.map(|length| input.signed_values(length));
    let streams = Streams {
        ops: &ops,
        degrees: &degrees,
        vertices: &vertices,
        references: &references,
    };
    if let Ok(table) = traversal::decode(&streams, count, width, k, corner_order) {
        assert_eq!(table.len(), count * width, "the table's size");
        for row in table.chunks_exact(width) {
            check_face(row, k);
        }
    }
}

/// A decoded row: 3 or more vertices in `0..k`, then only padding. (A corner may repeat: the
/// reference's walk lets a tip name a vertex of its own face, and the core gives its faces.)
fn check_face(row: &[i64], k: i64) {
    let corners = row.iter().take_while(|&&v| v >= 0).count();
    assert!(corners >= 3, "a face of {corners} corners: {row:?}");
    assert!(row[corners..].iter().all(|&v| v == -1), "padding: {row:?}");
    assert!(
        row[..corners].iter().all(|&v| v < k),
        "a vertex outside 0..{k}: {row:?}"
    );
}

/// `traversal::encode` of any face table, then `traversal::decode` of its streams for both
/// corner orders. Framing: a byte `b` for `width = 3 + b % 6`; a varint `k` (inputs above
/// 2**20 are skipped); then the table's entries, signed, row-major (negative ones are padding;
/// a last incomplete row is dropped; at most 2**16 rows).
///
/// Checks: no panic; where the encoder takes the table (`Some`), its order is a permutation of
/// the rows and, for a table the writer accepts (each face's corners distinct), the decoder
/// gives back exactly the table's rows in that order, padding moved to the end.
pub fn traversal_roundtrip(data: &[u8]) {
    let mut input = Framing::new(data);
    let width = 3 + usize::from(input.byte()) % 6;
    let k = input.varint();
    if k > MAX_ENCODER_VERTICES {
        return;
    }
    let mut table = input.signed_values(MAX_COUNT * width as u64);
    table.truncate(table.len() / width * width);
    let Some(walked) = traversal::encode(&table, width, k) else {
        return;
    };
    let rows = table.len() / width;
    let mut seen = vec![false; rows];
    for &row in &walked.order {
        let row = usize::try_from(row).expect("an order entry below 0");
        assert!(!seen[row], "row {row} twice in the order");
        seen[row] = true;
    }
    assert!(seen.iter().all(|&s| s), "a row missing from the order");
    if !table.chunks_exact(width).all(distinct_corners) {
        return;
    }
    let mut expected = Vec::with_capacity(table.len());
    for &row in &walked.order {
        let start = row as usize * width;
        let corners = table[start..start + width].iter().filter(|&&v| v >= 0);
        let before = expected.len();
        expected.extend(corners);
        expected.resize(before + width, -1);
    }
    for (corner_order, ops) in walked.ops.iter().enumerate() {
        let streams = Streams {
            ops,
            degrees: &walked.degrees,
            vertices: &walked.new_residuals,
            references: &walked.references,
        };
        let decoded = traversal::decode(&streams, rows, width, k as i64, corner_order as i64);
        assert_eq!(
            decoded.as_ref(),
            Ok(&expected),
            "corner order {corner_order}: decoded faces differ from the encoded"
        );
    }
}

/// The row's corners (padding left out) are distinct.
fn distinct_corners(row: &[i64]) -> bool {
    let corners: Vec<i64> = row.iter().copied().filter(|&v| v >= 0).collect();
    corners
        .iter()
        .enumerate()
        .all(|(j, v)| !corners[..j].contains(v))
}

/// `parse_obj` of any bytes (the whole input is the file).
///
/// Checks: no panic; a parsed mesh is consistent (whole `x y z` triples, `face_count` rows of
/// `width`, indices in range); `parse_obj_frame` gives the same mesh, with or without the
/// faces known from the mesh itself; and the mesh written as OBJ text (`vertex_text`,
/// `face_text`) parses back to the same mesh, bit for bit.
pub fn obj_parse(data: &[u8]) {
    let parsed = parse_obj(data);
    let framed = parse_obj_frame(data, None).map(|frame| frame.mesh);
    assert!(same_result(&parsed, &framed), "parse_obj_frame(None)");
    let Ok(mesh) = parsed else {
        return;
    };
    assert_eq!(mesh.vertices.len() % 3, 0, "vertices in triples");
    assert_eq!(
        mesh.faces.len(),
        mesh.face_count * mesh.width,
        "the table's size"
    );
    let vertex_count = (mesh.vertices.len() / 3) as i64;
    assert!(
        mesh.faces
            .iter()
            .all(|&v| v == -1 || (0..vertex_count).contains(&v)),
        "a face index out of range"
    );
    if let Ok(Some(face_key)) = parse_obj_frame(data, None).map(|frame| frame.face_key) {
        let known = KnownFaces {
            face_key: &face_key,
            vertex_count: mesh.vertices.len() / 3,
        };
        let frame = parse_obj_frame(data, Some(known)).expect("the frame parses again");
        assert!(same_vertices(&frame.mesh.vertices, &mesh.vertices));
        if !frame.shared {
            assert!(same_mesh(&frame.mesh, &mesh), "the frame's mesh");
        }
    }
    let mut text = vertex_text(&mesh.vertices);
    text.extend(face_text(&mesh.faces, mesh.width));
    let again = parse_obj(&text).expect("the written mesh parses");
    assert!(
        same_vertices(&again.vertices, &mesh.vertices),
        "vertices written and read"
    );
    if mesh.face_count > 0 {
        assert_eq!(again.faces, mesh.faces, "faces written and read");
        assert_eq!(again.width, mesh.width);
    }
    assert_eq!(again.face_count, mesh.face_count);
}

fn same_result<E: PartialEq>(a: &Result<ObjMesh, E>, b: &Result<ObjMesh, E>) -> bool {
    match (a, b) {
        (Ok(a), Ok(b)) => same_mesh(a, b),
        (Err(a), Err(b)) => a == b,
        _ => false,
    }
}

fn same_mesh(a: &ObjMesh, b: &ObjMesh) -> bool {
    same_vertices(&a.vertices, &b.vertices)
        && a.faces == b.faces
        && a.face_count == b.face_count
        && a.width == b.width
}

fn same_vertices(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// `repr` of any `f64` (the first 8 bytes, little-endian, short inputs padded with 0), and
/// `write_signed` / `write_unsigned` of the same bits.
///
/// Checks: the text parses back to the same bits (any NaN to a NaN, written `nan`); it is laid
/// out as Python lays out the shortest digits, which are rebuilt here independently from
/// Rust's `{:e}`; and the integers' texts are Rust's.
pub fn float_repr(data: &[u8]) {
    let mut bytes = [0u8; 8];
    for (slot, byte) in bytes.iter_mut().zip(data) {
        *slot = *byte;
    }
    let value = f64::from_le_bytes(bytes);
    let text = repr(value);
    let back: f64 = text.parse().expect("repr parses as a float");
    if value.is_nan() {
        assert!(back.is_nan() && text == "nan", "{text}");
    } else {
        assert_eq!(
            back.to_bits(),
            value.to_bits(),
            "{text} reads back to another float"
        );
        assert_eq!(text, python_layout(value, &text), "laid out unlike Python");
    }
    assert_eq!(repr(back), text, "the same value, another text");
    let mut out = Vec::new();
    write_signed(i64::from_le_bytes(bytes), &mut out);
    assert_eq!(out, i64::from_le_bytes(bytes).to_string().as_bytes());
    out.clear();
    write_unsigned(u64::from_le_bytes(bytes), &mut out);
    assert_eq!(out, u64::from_le_bytes(bytes).to_string().as_bytes());
}

/// Python's `repr` of a non-NaN float, laid out here from the decimal exponent of Rust's
/// shortest digits (`{:e}`: `d.ddde-x`): positional where it is in -4..16, else `d.ddde+XX`.
/// The digits are those of `text` (the core's), checked to be as few as Rust's: where two
/// shortest texts are equally near the value, Rust and Python may choose differently (and
/// both read back to the value, which the caller checks).
fn python_layout(value: f64, text: &str) -> String {
    if value.is_infinite() {
        return if value > 0.0 { "inf" } else { "-inf" }.to_string();
    }
    let sign = if value.is_sign_negative() { "-" } else { "" };
    if value == 0.0 {
        return format!("{sign}0.0");
    }
    let scientific = format!("{:e}", value.abs());
    let (mantissa, exponent) = scientific.split_once('e').expect("{:e} has an exponent");
    let exponent: i32 = exponent.parse().expect("an exponent");
    let shortest = mantissa.chars().filter(|c| *c != '.').count();
    let digits = significant_digits(text);
    assert_eq!(
        digits.len(),
        shortest,
        "{text}: not the shortest digits ({scientific})"
    );
    if (-4..16).contains(&exponent) {
        let point = exponent + 1; // digits before the point
        let text = if point <= 0 {
            format!("0.{}{digits}", "0".repeat((-point) as usize))
        } else if point as usize >= digits.len() {
            format!("{digits}{}.0", "0".repeat(point as usize - digits.len()))
        } else {
            let (whole, fraction) = digits.split_at(point as usize);
            format!("{whole}.{fraction}")
        };
        format!("{sign}{text}")
    } else {
        let (first, others) = digits.split_at(1);
        let fraction = if others.is_empty() {
            String::new()
        } else {
            format!(".{others}")
        };
        let exponent_sign = if exponent < 0 { '-' } else { '+' };
        format!(
            "{sign}{first}{fraction}e{exponent_sign}{:02}",
            exponent.abs()
        )
    }
}

/// The digits of a float's text without sign, point, exponent, leading or trailing zeros.
fn significant_digits(text: &str) -> String {
    let mantissa = text.split('e').next().unwrap_or(text);
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    let digits = digits.trim_start_matches('0').trim_end_matches('0');
    if digits.is_empty() { "0" } else { digits }.to_string()
}

/// `TextCheck` of any text cut into chunks anywhere. Framing: a varint `v` for the line-length
/// limit `1 + v`; a byte `c`, then `c % 8` varints, each a cut position (modulo the text's
/// length + 1); the rest is the text. A piece longer than the limit is cut into pieces of the
/// limit, as the reader's chunks never are longer (`obj.py` reads `min(chunk, limit)` bytes).
///
/// Checks: no panic; the chunked check and, for a text no longer than the limit, the check of
/// the whole text in one chunk accept exactly the texts with no NUL byte, that are UTF-8, and
/// whose lines (ended by `\n`, `\r\n` or a lone `\r`) are at most the limit long; a fault's
/// line is within the text's lines.
pub fn text_check(data: &[u8]) {
    let mut input = Framing::new(data);
    let limit = input.varint().saturating_add(1);
    let cuts = usize::from(input.byte() % 8);
    let mut positions: Vec<u64> = (0..cuts).map(|_| input.varint()).collect();
    let text = input.rest();
    let length = text.len() as u64;
    for position in &mut positions {
        *position %= length + 1;
    }
    positions.sort_unstable();
    positions.push(length);
    let most = usize::try_from(limit).unwrap_or(usize::MAX);
    let mut chunks = Vec::new();
    let mut start = 0;
    for &cut in &positions {
        chunks.extend(text[start..cut as usize].chunks(most));
        start = cut as usize;
    }
    let expected = text_is_fine(text, limit);
    let lines = 1 + crate::text::text_check::line_ends(text, false);
    let mut runs = vec![chunks.as_slice()];
    let whole = [text];
    if length <= limit {
        runs.push(&whole);
    }
    for pieces in runs {
        let mut check = TextCheck::new(limit);
        let result = pieces
            .iter()
            .try_for_each(|chunk| check.feed(chunk))
            .and_then(|()| check.finish());
        assert_eq!(
            result.is_ok(),
            expected,
            "{result:?} for {} chunks",
            pieces.len()
        );
        if let Err(fault) = result {
            assert!(
                (1..=lines).contains(&fault.line),
                "{fault:?} of {lines} lines"
            );
        }
    }
}

/// The text has no NUL byte, is UTF-8, and no line is longer than `limit` bytes.
fn text_is_fine(text: &[u8], limit: u64) -> bool {
    !text.contains(&0)
        && std::str::from_utf8(text).is_ok()
        && text
            .split(|&c| c == b'\n' || c == b'\r')
            .all(|line| line.len() as u64 <= limit)
}

/// `residual::restore_chunk` of any bytes and shape, then `pack_chunk` of what it restores.
/// Framing: a byte of flags (bit 0: `predict`; bit 1: `count` is the bytes' length / `planes`,
/// the bytes cut to whole planes, else a varint `count` follows, at most 2**16 + 1); a byte `b`
/// for `planes = b % 10` (0 and 9 are refused); a varint `frame_values` (at most 2**16 + 1);
/// the rest is the decompressed chunk.
///
/// Checks: no panic; restored integers packed again take at most `planes` planes, restore to
/// the same integers, and in exactly `planes` planes are the same bytes.
pub fn residual_restore(data: &[u8]) {
    let mut input = Framing::new(data);
    let flags = input.byte();
    let predict = flags & 1 != 0;
    let planes = usize::from(input.byte() % 10);
    let whole_planes = flags & 2 != 0;
    let count = if whole_planes {
        0
    } else {
        input.varint().min(MAX_COUNT + 1) as usize
    };
    let frame_values = input.varint().min(MAX_COUNT + 1) as usize;
    let mut raw = input.rest();
    let count = if whole_planes {
        let count = raw.len() / planes.max(1);
        raw = &raw[..count * planes.min(8)];
        count
    } else {
        count
    };
    let Ok(values) = restore_chunk(raw, count, planes, predict, frame_values) else {
        return;
    };
    assert_eq!(values.len(), count);
    let (packed_planes, packed) = pack_chunk(&values, predict, frame_values).expect("packs");
    assert!(
        packed_planes <= planes,
        "{packed_planes} planes for {planes}"
    );
    let again = restore_chunk(&packed, count, packed_planes, predict, frame_values);
    assert_eq!(again.as_ref(), Ok(&values), "packed and restored");
    if packed_planes == planes {
        assert_eq!(
            packed, raw,
            "the same integers in as many planes, other bytes"
        );
    }
}

/// `residual::correct` of any positions and corrections in any domain. Framing: a byte `d` for
/// the domain (`d % 6`: grid, float32, float64, decimal-places, decimal-digits,
/// decimal-digits-float32); a byte `s` for the scale (`s % 23` places, `1 + s % 15` digits); a
/// grid's step as 8 bytes (a little-endian `f64`, any value); then pairs of a position P (8
/// bytes, `f64`) and a correction e (signed varint), at most 2**16 pairs.
///
/// Checks: no panic; in float32, float64 and decimal-digits, corrected values that are all
/// finite are the domain's own: corrected again by zeros, they stay the same bits. (Not in
/// decimal-places: `k / 10**d` times `10**d` rounds to `k + 1` where k has about as many digits
/// as binary64 holds, as §6.9 defines it (0.3600163170749445 with 16 places); nor in
/// decimal-digits-float32: its values are binary32 roundings, and one just below a power of
/// ten, such as the binary32 of 1e-20, has the ordered integer of the decimal below it.)
pub fn residual_correct(data: &[u8]) {
    let mut input = Framing::new(data);
    let kind = input.byte() % 6;
    let scale = u32::from(input.byte());
    let domain = match kind {
        0 => Domain::Grid {
            step: input.float(),
        },
        1 => Domain::Float32,
        2 => Domain::Float64,
        3 => Domain::Places { places: scale % 23 },
        4 => Domain::Digits {
            digits: 1 + scale % 15,
        },
        _ => Domain::Digits32 {
            digits: 1 + scale % 15,
        },
    };
    let mut exact = Vec::new();
    let mut residual = Vec::new();
    while !input.is_empty() && (exact.len() as u64) < MAX_COUNT {
        exact.push(input.float());
        residual.push(input.signed());
    }
    let mut out = vec![0.0; exact.len()];
    let Ok(()) = correct(&exact, &residual, domain, &mut out) else {
        return;
    };
    let fixed_points = matches!(
        domain,
        Domain::Float32 | Domain::Float64 | Domain::Digits { .. }
    );
    if !fixed_points || !out.iter().all(|v| v.is_finite()) {
        return;
    }
    let zeros = vec![0; out.len()];
    let mut again = vec![0.0; out.len()];
    correct(&out, &zeros, domain, &mut again).expect("a domain's values, corrected by zeros");
    assert!(
        same_vertices(&again, &out),
        "{domain:?}: corrected by zeros, moved"
    );
}

/// `streams::unpack_planes` of any bytes and shape, then `pack_planes` of what it unpacks.
/// Framing: a byte of flags (bit 1: `count` is the bytes' length / `planes`, the bytes cut to
/// whole planes, else a varint `count` follows, at most 2**16 + 1); a byte `b` for
/// `planes = b % 10` (0 and 9 are refused); the rest is the decompressed stream.
///
/// Checks: no panic; `unpack_planes_into` gives the same; the integers packed again take at
/// most `planes` planes, unpack to the same integers, and in exactly `planes` planes are the
/// same bytes.
pub fn streams_unpack(data: &[u8]) {
    let mut input = Framing::new(data);
    let whole_planes = input.byte() & 2 != 0;
    let planes = usize::from(input.byte() % 10);
    let count = if whole_planes {
        0
    } else {
        input.varint().min(MAX_COUNT + 1) as usize
    };
    let mut raw = input.rest();
    let count = if whole_planes {
        let count = raw.len() / planes.max(1);
        raw = &raw[..count * planes.min(8)];
        count
    } else {
        count
    };
    let unpacked = unpack_planes(raw, count, planes);
    let mut into = vec![0; count];
    let filled = unpack_planes_into(raw, planes, &mut into).map(|()| into);
    let Ok(values) = unpacked else {
        assert!(
            filled.is_err(),
            "unpack_planes_into takes what unpack_planes refuses"
        );
        return;
    };
    assert_eq!(filled.as_ref(), Ok(&values), "unpack_planes_into");
    let (packed_planes, packed) = pack_planes(&values);
    assert!(
        packed_planes <= planes,
        "{packed_planes} planes for {planes}"
    );
    let again = unpack_planes(&packed, count, packed_planes);
    assert_eq!(again.as_ref(), Ok(&values), "packed and unpacked");
    if packed_planes == planes {
        assert_eq!(
            packed, raw,
            "the same integers in as many planes, other bytes"
        );
    }
}

/// Predictor 1, 2 and 3's restoring loops (§6.2). Framing: a byte `m`, then by `m % 3`:
///
/// - 0, predictor 2 over a mesh: a byte `b` for `width = 3 + b % 6`; a varint vertex count K
///   and a varint face count (each at most 2**12); the faces' entries, signed (any values: the
///   forest checks them); a byte `c` for `1 + c % 4` columns; then K rows of the columns'
///   values, signed (0 past the end); then each column's push, a byte `% 10` (2 past the
///   end). Checks: the forest's mean steps make a plan; where the values are in predictor 2's
///   range, their residuals restore to the values.
/// - 1, predictor 2 from any steps: a varint K (at most 2**12); five arrays (rows, step ends,
///   sources, anchors, source ends), each a varint length (at most 2**12) and signed values;
///   then columns of K values, signed, restored with the plan if it is made, with a push per
///   column as above (after the values: 2 once the input ends). Checks: no panic.
/// - 2, predictors 1 and 3: a varint row count (at most 2**12); a byte `w` for `1 + w % 4`
///   columns; each row's parent, signed; the rows' values, signed (0 past the end). Checks:
///   no panic in `accumulate_tree` and `linear_accumulate`, and `accumulate_rows`' running
///   sums give the values back as differences.
pub fn prediction_restore(data: &[u8]) {
    let mut input = Framing::new(data);
    match input.byte() % 3 {
        0 => mean_over_mesh(&mut input),
        1 => mean_from_steps(&mut input),
        _ => along_rows_and_tree(&mut input),
    }
}

fn bounded(input: &mut Framing<'_>, most: u64) -> usize {
    input.varint().min(most) as usize
}

/// `count` signed values, 0 past the end of the input.
fn padded_values(input: &mut Framing<'_>, count: usize) -> Vec<i64> {
    let mut values = input.signed_values(count as u64);
    values.resize(count, 0);
    values
}

/// `count` pushes, each a byte `% 10`, 2 (today's predictor 2) past the end of the input.
fn pushes(input: &mut Framing<'_>, count: usize) -> Vec<u8> {
    (0..count)
        .map(|_| {
            if input.is_empty() {
                2
            } else {
                input.byte() % 10
            }
        })
        .collect()
}

fn mean_over_mesh(input: &mut Framing<'_>) {
    let width = 3 + usize::from(input.byte()) % 6;
    let vertex_count = bounded(input, MAX_PREDICTION_VERTICES);
    let face_count = bounded(input, MAX_PREDICTION_VERTICES);
    let faces = input.signed_values((face_count * width) as u64);
    let faces = &faces[..faces.len() / width * width];
    let columns = 1 + usize::from(input.byte()) % 4;
    let values = padded_values(input, vertex_count * columns);
    let push = pushes(input, columns);
    let Ok(forest) = Forest::new(faces, width, vertex_count) else {
        return;
    };
    let plan = MeanPlan::from_arrays(&forest.mean_steps(), vertex_count);
    let Ok(Some(residuals)) = plan.residuals(&values, columns, &push) else {
        return;
    };
    // the residuals column after column, as the decoder restores them
    let mut restored: Vec<i64> = (0..columns)
        .flat_map(|c| residuals.iter().skip(c).step_by(columns).copied())
        .collect();
    plan.restore_columns(&mut restored, vertex_count, &push)
        .expect("residuals of values in range restore");
    let expected: Vec<i64> = (0..columns)
        .flat_map(|c| values.iter().skip(c).step_by(columns).copied())
        .collect();
    assert_eq!(
        restored, expected,
        "predictor 2: residuals restored to other values"
    );
}

fn mean_from_steps(input: &mut Framing<'_>) {
    let vertex_count = bounded(input, MAX_PREDICTION_VERTICES);
    let [rows, step_ends, sources, anchors, source_ends] = [0u8; 5].map(|_| {
        let length = bounded(input, MAX_PREDICTION_VERTICES);
        input.signed_values(length as u64)
    });
    let values = input.signed_values(MAX_PREDICTION_VERTICES * 4);
    let push = pushes(input, values.len().checked_div(vertex_count).unwrap_or(0));
    let Ok(plan) = MeanPlan::from_steps(
        &rows,
        &step_ends,
        &sources,
        &anchors,
        &source_ends,
        vertex_count,
    ) else {
        return;
    };
    let mut columns = values;
    if let Some(whole) = columns.len().checked_div(vertex_count) {
        columns.truncate(whole * vertex_count);
    }
    let _ = plan.restore_columns(&mut columns, vertex_count, &push);
    let _ = plan.residuals(&columns, 1, &push[..push.len().min(1)]);
}

fn along_rows_and_tree(input: &mut Framing<'_>) {
    let rows = bounded(input, MAX_PREDICTION_VERTICES);
    let width = 1 + usize::from(input.byte()) % 4;
    let parents = padded_values(input, rows);
    let values = padded_values(input, rows * width);
    let _ = accumulate_tree(&mut values.clone(), width, &parents);
    let _ = linear_accumulate(&mut values.clone(), width);
    let mut sums = values.clone();
    accumulate_rows(&mut sums, width);
    for (j, value) in values.iter().enumerate() {
        let before = if j >= width { sums[j - width] } else { 0 };
        assert_eq!(sums[j].wrapping_sub(before), *value, "running sums");
    }
}

/// A coding order of §6.14 from the framing (`(kind & 3) % 3`) and whether it is one an encoder
/// writes (each row once, every source coded before it):
///
/// - 0, ascending: a varint row count (at most 2**12);
/// - 1, U1's over a mesh: a byte `b` for `width = 3 + b % 6`, a varint vertex count and a
///   varint face count (each at most 2**12), the faces' entries, signed (the forest checks
///   them; a table it refuses gives no order);
/// - 2, any arrays: a varint row count (at most 2**12), then `order`, `sources` and `ends`,
///   each a varint length (at most 2**12) and signed values, `mesh` from bit 2 of `kind`
///   (arrays that are not an order give none).
fn adaptive_order(input: &mut Framing<'_>, kind: u8) -> Option<(CodingOrder, bool)> {
    match (kind & 3) % 3 {
        0 => Some((
            CodingOrder::sequence(bounded(input, MAX_PREDICTION_VERTICES)),
            true,
        )),
        1 => {
            let width = 3 + usize::from(input.byte()) % 6;
            let vertex_count = bounded(input, MAX_PREDICTION_VERTICES);
            let face_count = bounded(input, MAX_PREDICTION_VERTICES);
            let faces = input.signed_values((face_count * width) as u64);
            let faces = &faces[..faces.len() / width * width];
            let steps = Forest::new(faces, width, vertex_count).ok()?.mean_steps();
            let order = CodingOrder::mesh(
                vertex_count,
                &steps.rows,
                &steps.sources,
                &steps.source_ends,
            );
            Some((order.expect("the mean steps are an order"), true))
        }
        _ => {
            let rows = bounded(input, MAX_PREDICTION_VERTICES);
            let [order, sources, ends] = [0u8; 3].map(|_| {
                let length = bounded(input, MAX_PREDICTION_VERTICES);
                input.signed_values(length as u64)
            });
            let order = CodingOrder::new(&order, &sources, &ends, kind & 4 != 0, rows).ok()?;
            Some((order, false))
        }
    }
}

/// `adaptive::decode_columns` of any payload. Framing: a byte `kind` and the order it frames
/// ([`adaptive_order`]), a varint column count (at most 16), the rest is the payload.
///
/// Checks: no panic; `decode_columns_into` an array of other values gives the same; where the
/// order is an encoder's, the integers decoded encode to a stream that decodes to them again.
pub fn adaptive_decode(data: &[u8]) {
    let mut input = Framing::new(data);
    let kind = input.byte();
    let Some((order, encodable)) = adaptive_order(&mut input, kind) else {
        return;
    };
    let cols = input.varint().min(MAX_ADAPTIVE_COLUMNS) as usize;
    let payload = input.rest();
    let decoded = adaptive::decode_columns(payload, cols, &order);
    let mut into = vec![-1; cols * order.row_count()];
    let filled = adaptive::decode_columns_into(payload, &order, &mut into).map(|()| into);
    assert_eq!(decoded, filled, "decode_columns_into");
    let Ok(values) = decoded else {
        return;
    };
    if encodable {
        let again = adaptive::encode_columns(&values, cols, order.row_count(), &order)
            .expect("an order's columns encode");
        assert_eq!(
            adaptive::decode_columns(&again, cols, &order),
            Ok(values),
            "decoded integers encoded and decoded again"
        );
    }
}

/// `adaptive::encode_columns` then `decode_columns`. Framing: a byte `kind` and the order it
/// frames ([`adaptive_order`], `kind % 2`: ascending or a mesh's), a varint column count (at
/// most 16), then the values column after column, signed (0 past the end).
///
/// Checks: no panic; the stream decodes to the values, but for a magnitude of 2**63 (`i64::MIN`,
/// 64 bits), which it codes and no decoder takes (R46).
pub fn adaptive_roundtrip(data: &[u8]) {
    let mut input = Framing::new(data);
    let kind = input.byte() % 2;
    let Some((order, _)) = adaptive_order(&mut input, kind) else {
        return;
    };
    let cols = input.varint().min(MAX_ADAPTIVE_COLUMNS) as usize;
    let rows = order.row_count();
    let values = padded_values(&mut input, cols * rows);
    let payload = adaptive::encode_columns(&values, cols, rows, &order).expect("encodes");
    let decoded = adaptive::decode_columns(&payload, cols, &order);
    if values.contains(&i64::MIN) {
        assert_eq!(decoded.map_err(|e| e.rule), Err(adaptive::RULE), "2**63");
    } else {
        assert_eq!(decoded, Ok(values), "encoded and decoded");
    }
}

#[cfg(test)]
mod tests {
    use super::{python_layout, Framing};

    #[test]
    fn varints() {
        let mut input = Framing::new(&[0x96, 0x01, 0x03, 0x80]);
        assert_eq!(input.varint(), 150);
        assert_eq!(input.signed(), -2);
        // cut by the end: what it has
        assert_eq!(input.varint(), 0);
        assert!(input.is_empty());
        assert_eq!(input.byte(), 0);
    }

    #[test]
    fn layout() {
        for (value, text) in [
            (1e16, "1e+16"),
            (1e15, "1000000000000000.0"),
            (0.0001, "0.0001"),
            (-1.5e-5, "-1.5e-05"),
            (123.25, "123.25"),
            (-0.0, "-0.0"),
            // equally near ...062 and ...063: Python (and the core) write 062, Rust's {:e} 063
            (f64::from_bits(0x41c3_79f9_37e0_8000), "653521519.7539062"),
        ] {
            assert_eq!(python_layout(value, text), text);
        }
    }
}
