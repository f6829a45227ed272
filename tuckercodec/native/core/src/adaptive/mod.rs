//! Spec section 6.14, adaptive coding: a section's integers through a binary range coder with
//! adaptive models and contexts, the same bytes and integers as `tuckercodec/format/adaptive.py`.
//!
//! The matrix is coded column after column (`cols` columns of `rows` integers, column-major as
//! the Python side holds it, shape (cols, rows)), and within a column in a [`CodingOrder`]. Each
//! integer's context is `6 * A + B`: `A` the class of its earlier neighbours in the column
//! (coded before it), `B` the class of the same row in the two columns before.
//!
//! Entry points (each refuses what it cannot use, never panics):
//!
//! - [`CodingOrder::new`]`(order, sources, ends, mesh, rows)`: the order arrays of
//!   `adaptive.CodingOrder`, checked (an [`InvalidOrder`] is the caller's mistake, not a file's);
//! - [`encode_columns`]`(values, cols, rows, order)`: the stream's bytes;
//! - [`decode_columns`] / [`decode_columns_into`]`(payload, order, out)`: the integers, or
//!   R46-adaptive-stream with the reference's message, its first error first;
//! - [`decode_runs`]`(payload, order, cols, block, buffer, done)`: the same, a run of columns at
//!   a time into reused buffers, each handed over as soon as it is decoded;
//! - [`check_size`]`(cols, rows, payload_len)`: the up-front bound (at most 32768 integers a
//!   byte), which a caller checks before it allocates the output.

mod coder;
#[cfg(test)]
mod tests;
pub mod uniform;

use std::fmt;

use crate::error::Broken;

pub use coder::{
    decode_integer, encode_integer, Context, Model, RangeDecoder, RangeEncoder, FRESH_CONTEXT,
    MAX_EXPONENT, MODELS_PER_CONTEXT,
};

/// The rule every check of an adaptive stream reports (spec section 11).
pub const RULE: &str = "R46-adaptive-stream";
/// No payload of L bytes holds more than MAX_EXPANSION * L integers.
pub const MAX_EXPANSION: u64 = 32768;
/// Classes of the earlier neighbours (0 for none, then 1 + min(bit length, 14)).
pub const NEIGHBOUR_CLASSES: usize = 16;
/// Classes of the same row in the two columns before.
pub const LEFT_CLASSES: usize = 6;
/// Contexts: neighbour class times LEFT_CLASSES plus left class.
pub const CONTEXTS: usize = NEIGHBOUR_CLASSES * LEFT_CLASSES;

/// Order arrays that do not describe a coding order of `rows` rows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InvalidOrder(pub String);

impl fmt::Display for InvalidOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid coding order: {}", self.0)
    }
}

impl std::error::Error for InvalidOrder {}

/// The order rows are coded in within a column, and each one's earlier neighbours
/// (`adaptive.CodingOrder`): `sources[ends[j]..ends[j + 1]]` are those of `rows[j]`. With
/// `mesh`, their magnitudes are averaged (`floor(3 * sum / count)`, U1's mesh sources);
/// without, the first counts twice and the second once (`3 |x|` for a single one), the rows
/// before in ascending order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CodingOrder {
    rows: Vec<usize>,
    sources: Vec<usize>,
    ends: Vec<usize>,
    mesh: bool,
    row_count: usize,
    /// The arrays again for the decoder's fast loop ([`decode_proper`]), where the order is
    /// proper: every row once, each source coded before the row it serves, none with more
    /// than [`MAX_FAST_SOURCES`]. The orders of files always are; other arrays take the
    /// general loop.
    proper: Option<Proper>,
}

/// A proper order as the fast loop reads it.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Proper {
    /// [`CodingOrder::sequence`]'s (U3, CORE, CENT): each row's neighbours are the two rows
    /// before it, known without arrays (a CORE has tens of thousands of rows).
    Sequence,
    /// Any other, its arrays narrow, each position's first sources beside its row, so that most
    /// rows' sources are summed without a loop (whose exit, after 2 to 6 sources as the mesh
    /// goes, the processor would mispredict).
    Listed {
        steps: Vec<Step>,
        /// The positions of the sources past the first [`FIRST_SOURCES`] of every position, one
        /// after another.
        more: Vec<u32>,
    },
}

/// Sources kept beside each position's row: most vertices of a mesh have at most four
/// decoded neighbours when predictor 2 restores them.
const FIRST_SOURCES: usize = 4;

/// One position of a [`Proper`] order.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Step {
    row: u32,
    /// Its number of sources, and [`AFTER_SOURCE`] if the position just before is one.
    count: u32,
    /// The positions of its first sources in the order (not their rows: the magnitudes the
    /// loops read are kept by position, where a mesh's neighbours lie close together), padded
    /// with the row count (a position whose magnitude is always 0).
    first: [u32; FIRST_SOURCES],
    /// For up to [`FIRST_SOURCES`] sources, 3 * 2**MEAN_SHIFT / count (0 for none): the mean's
    /// floor(3 total / count) is (total * mean_scale) >> MEAN_SHIFT, exactly.
    mean_scale: u32,
}

/// See [`Step::mean_scale`]: 3 * 2**30 / count is a whole number for counts 1, 2 and 4 (2**30
/// for 3), and with totals of four magnitudes below 2**29 the product stays below 2**63.
const MEAN_SHIFT: u32 = 30;

/// [`Step::mean_scale`] of `count` sources.
fn mean_scale(count: usize) -> u32 {
    match count {
        1..=FIRST_SOURCES => ((3u64 << MEAN_SHIFT) / count as u64) as u32,
        _ => 0,
    }
}

/// The number of bits of `x` (0 for 0).
#[inline(always)]
fn bit_length(x: u64) -> usize {
    64 - x.leading_zeros() as usize
}

/// The flag of [`Step::count`] that tells a position whose sources include the position just
/// before it (rare in a mesh's order), whose context the decoder's loop cannot make before the
/// integer before it is decoded.
const AFTER_SOURCE: u32 = 1 << 31;

impl Step {
    /// Its number of sources.
    #[inline(always)]
    fn sources(&self) -> usize {
        (self.count & !AFTER_SOURCE) as usize
    }
}

/// The most sources of one row the fast loop takes: its saturated magnitudes give the exact
/// class of their mean only up to 3 * 2**15 of them ([`MAGNITUDE_CAP`]).
const MAX_FAST_SOURCES: usize = 1 << 15;

/// An index of the order arrays as a row or position: `None` outside `0..limit`.
fn index(value: i64, limit: usize) -> Option<usize> {
    usize::try_from(value).ok().filter(|&v| v < limit)
}

impl CodingOrder {
    /// The order of the arrays of `adaptive.CodingOrder` for a matrix of `rows` rows: every
    /// entry of `order` and `sources` a row, `ends` one longer than `order`, non-decreasing,
    /// within `sources`. (Nothing requires each row once, or the sources to be coded before:
    /// the reference's loops run on any such arrays, and so do these.)
    pub fn new(
        order: &[i64],
        sources: &[i64],
        ends: &[i64],
        mesh: bool,
        rows: usize,
    ) -> Result<Self, InvalidOrder> {
        let rows_of = |values: &[i64], what: &str| {
            values
                .iter()
                .map(|&v| index(v, rows))
                .collect::<Option<Vec<usize>>>()
                .ok_or_else(|| InvalidOrder(format!("{what} holds an index outside 0..{rows}")))
        };
        let order_rows = rows_of(order, "order")?;
        let source_rows = rows_of(sources, "sources")?;
        if ends.len() != order.len() + 1 {
            return Err(InvalidOrder(format!(
                "{} ends for {} rows",
                ends.len(),
                order.len()
            )));
        }
        let ends = ends
            .iter()
            .map(|&v| index(v, source_rows.len() + 1))
            .collect::<Option<Vec<usize>>>()
            .ok_or_else(|| InvalidOrder("ends point outside the sources".to_string()))?;
        if ends.windows(2).any(|pair| pair[0] > pair[1]) {
            return Err(InvalidOrder("ends decrease".to_string()));
        }
        let proper = Proper::of(&order_rows, &source_rows, &ends, rows, mesh);
        Ok(CodingOrder {
            rows: order_rows,
            sources: source_rows,
            ends,
            mesh,
            row_count: rows,
            proper,
        })
    }

    /// `adaptive.sequence_order(rows)`: ascending, each row after the (up to) two before it.
    pub fn sequence(rows: usize) -> Self {
        let mut sources = Vec::with_capacity(2 * rows);
        let mut ends = Vec::with_capacity(rows + 1);
        ends.push(0);
        for r in 0..rows {
            sources.extend((r.saturating_sub(2)..r).rev());
            ends.push(sources.len());
        }
        CodingOrder {
            rows: (0..rows).collect(),
            sources,
            ends,
            mesh: false,
            row_count: rows,
            proper: Some(Proper::Sequence),
        }
    }

    /// `adaptive.mesh_order`: the rows predictor 2 does not predict (not in `mean_rows`) in
    /// ascending order, without neighbours, then `mean_rows` in order, each with its
    /// `sources[source_ends[j]..source_ends[j + 1]]` (§6.2's mean steps).
    pub fn mesh(
        rows: usize,
        mean_rows: &[u32],
        sources: &[u32],
        source_ends: &[usize],
    ) -> Result<Self, InvalidOrder> {
        let mut predicted = vec![false; rows];
        for &row in mean_rows {
            let slot = predicted
                .get_mut(row as usize)
                .ok_or_else(|| InvalidOrder(format!("mean row {row} of {rows}")))?;
            *slot = true;
        }
        let mut order: Vec<i64> = (0..rows)
            .filter(|&r| !predicted[r])
            .map(|r| r as i64)
            .collect();
        let mut ends = vec![0i64; order.len()];
        order.extend(mean_rows.iter().map(|&r| i64::from(r)));
        ends.extend(source_ends.iter().map(|&e| i64::try_from(e).unwrap_or(-1)));
        let sources: Vec<i64> = sources.iter().map(|&s| i64::from(s)).collect();
        Self::new(&order, &sources, &ends, true, rows)
    }

    /// The number of rows of the matrices this order codes.
    pub fn row_count(&self) -> usize {
        self.row_count
    }

    /// The neighbour class of position `j` in `column` (its values so far): 0 without earlier
    /// neighbours, else 1 + min(bit length of m, 14).
    #[inline(always)]
    fn neighbour_class(&self, column: &[i64], sources: &[usize]) -> usize {
        let magnitude = |w: usize| column.get(w).map_or(0, |v| v.unsigned_abs());
        let m = match *sources {
            [] => return 0,
            [single] if !self.mesh => u128::from(magnitude(single)) * 3,
            [first, second, ..] if !self.mesh => {
                u128::from(magnitude(first)) * 2 + u128::from(magnitude(second))
            }
            _ => mean_magnitude(sources, magnitude),
        };
        1 + (128 - m.leading_zeros() as usize).min(NEIGHBOUR_CLASSES - 2)
    }
}

impl Proper {
    /// The fast loop's form of checked order arrays, if they are proper.
    fn of(
        rows: &[usize],
        sources: &[usize],
        ends: &[usize],
        row_count: usize,
        mesh: bool,
    ) -> Option<Self> {
        if rows.len() != row_count || u32::try_from(row_count).is_err() {
            return None;
        }
        if !mesh && is_sequence(rows, sources, ends) {
            return Some(Proper::Sequence);
        }
        let mut position = vec![usize::MAX; row_count];
        for (j, &row) in rows.iter().enumerate() {
            if position[row] != usize::MAX {
                return None;
            }
            position[row] = j;
        }
        // rows.len() == row_count and no row twice: every row has its position
        let mut steps = Vec::with_capacity(rows.len());
        let mut more = Vec::new();
        for ((j, &row), pair) in rows.iter().enumerate().zip(ends.windows(2)) {
            let mine = &sources[pair[0]..pair[1]];
            if mine.len() > MAX_FAST_SOURCES || mine.iter().any(|&w| position[w] >= j) {
                return None;
            }
            // positions below 2**32 (checked above), and so is the row count, the padding
            let mut first = [row_count as u32; FIRST_SOURCES];
            for (slot, &w) in first.iter_mut().zip(mine) {
                *slot = position[w] as u32;
            }
            more.extend(mine.iter().skip(FIRST_SOURCES).map(|&w| position[w] as u32));
            // at most MAX_FAST_SOURCES: below the flag
            let after = if mine.iter().any(|&w| position[w] + 1 == j) {
                AFTER_SOURCE
            } else {
                0
            };
            steps.push(Step {
                row: row as u32,
                count: mine.len() as u32 | after,
                first,
                mean_scale: mean_scale(mine.len()),
            });
        }
        Some(Proper::Listed { steps, more })
    }
}

/// Whether order arrays are [`CodingOrder::sequence`]'s: rows ascending, no sources for row 0,
/// row 0 for row 1, rows r - 1 and r - 2 for each row r after.
fn is_sequence(rows: &[usize], sources: &[usize], ends: &[usize]) -> bool {
    let expected_end = |j: usize| (2 * j).saturating_sub(3);
    rows.iter().enumerate().all(|(j, &row)| row == j)
        && ends
            .iter()
            .enumerate()
            .all(|(j, &end)| end == expected_end(j))
        && sources.len() == expected_end(rows.len())
        && sources.first().is_none_or(|&w| w == 0)
        && sources
            .get(1..)
            .unwrap_or(&[])
            .chunks(2)
            .enumerate()
            .all(|(n, pair)| pair == [n + 1, n])
}

/// floor(3 * sum / count) of the sources' magnitudes, exact where the class depends on it (it
/// only tells bit lengths up to 14 apart: a saturated value is far beyond).
#[inline(always)]
fn mean_magnitude(sources: &[usize], magnitude: impl Fn(usize) -> u64) -> u128 {
    let mut total = 0u64;
    let mut wide = false;
    for &w in sources {
        let (sum, carried) = total.overflowing_add(magnitude(w));
        total = sum;
        wide |= carried;
    }
    let count = sources.len() as u64;
    if !wide && total < 1 << 62 {
        return u128::from(total * 3 / count);
    }
    // magnitudes summing past 2**62: rare, exact in 128 bits (fewer than 2**64 sources)
    let total: u128 = sources.iter().map(|&w| u128::from(magnitude(w))).sum();
    total.saturating_mul(3) / u128::from(count)
}

/// The left classes of one column's rows: min(bit length of 2 |x[r, c-1]| + |x[r, c-2]|, 5),
/// from the columns before, each as long as `out` (`None` before the first).
fn left_classes(before: Option<&[i64]>, two_before: Option<&[i64]>, out: &mut [u8]) {
    match (before, two_before) {
        (None, _) => out.fill(0),
        (Some(b), Some(bb)) => {
            for ((class, &x), &y) in out.iter_mut().zip(b).zip(bb) {
                let m = x
                    .unsigned_abs()
                    .saturating_mul(2)
                    .saturating_add(y.unsigned_abs());
                *class = left_class(m);
            }
        }
        (Some(b), None) => {
            for (class, &x) in out.iter_mut().zip(b) {
                *class = left_class(x.unsigned_abs().saturating_mul(2));
            }
        }
    }
}

/// min(bit length, 5): saturation beyond 2**5 does not change it.
#[inline(always)]
fn left_class(m: u64) -> u8 {
    (64 - m.leading_zeros()).min(LEFT_CLASSES as u32 - 1) as u8
}

/// R46 where `cols * rows` integers cannot come from `payload_len` bytes (the reference's
/// up-front check, before any allocation).
pub fn check_size(cols: usize, rows: usize, payload_len: usize) -> Result<(), Broken> {
    let count = cols as u128 * rows as u128;
    if count > u128::from(MAX_EXPANSION) * payload_len as u128 {
        return Err(Broken::new(
            RULE,
            format!(
                "{count} integers cannot come from {payload_len} bytes (at most {MAX_EXPANSION} \
                 per byte)"
            ),
        ));
    }
    Ok(())
}

/// Every context fresh.
fn fresh_models() -> Vec<Context> {
    vec![FRESH_CONTEXT; CONTEXTS]
}

/// The context of position `j` (row `row`) given the column so far and the left classes.
#[inline(always)]
fn context_of(order: &CodingOrder, column: &[i64], left: &[u8], j: usize, row: usize) -> usize {
    let (start, end) = (order.ends[j], order.ends[j + 1]);
    let sources = order.sources.get(start..end).unwrap_or(&[]);
    let a = order.neighbour_class(column, sources);
    let b = usize::from(left.get(row).copied().unwrap_or(0));
    a * LEFT_CLASSES + b
}

/// The adaptive stream of `values`, `cols` columns of `rows` integers each (column-major,
/// shape (cols, rows)), each column in `order` (whose rows must be `rows`).
pub fn encode_columns(
    values: &[i64],
    cols: usize,
    rows: usize,
    order: &CodingOrder,
) -> Result<Vec<u8>, InvalidOrder> {
    if order.row_count != rows || cols.checked_mul(rows) != Some(values.len()) {
        return Err(InvalidOrder(format!(
            "{} values for {cols} columns of {rows} rows in an order of {} rows",
            values.len(),
            order.row_count
        )));
    }
    let mut coder = RangeEncoder::new();
    let Some(proper) = &order.proper else {
        encode_general(&mut coder, values, cols, order);
        return Ok(coder.finish());
    };
    let mut encoder = ColumnEncoder::new(rows);
    if rows > 0 {
        for column in values.chunks_exact(rows) {
            match proper {
                Proper::Sequence => encoder.sequence_column(&mut coder, column),
                Proper::Listed { steps, more } if order.mesh => {
                    encoder.column::<true>(&mut coder, steps, more, column)
                }
                Proper::Listed { steps, more } => {
                    encoder.column::<false>(&mut coder, steps, more, column)
                }
            }
        }
    }
    Ok(coder.finish())
}

/// The encoder's loop for any order: the reference's, each class from the integers themselves.
fn encode_general(coder: &mut RangeEncoder, values: &[i64], cols: usize, order: &CodingOrder) {
    let rows = order.row_count;
    let mut models = fresh_models();
    let mut left = vec![0u8; rows];
    for c in 0..cols {
        let column = &values[c * rows..(c + 1) * rows];
        let before = c.checked_sub(1).map(|b| &values[b * rows..(b + 1) * rows]);
        let two_before = c.checked_sub(2).map(|b| &values[b * rows..(b + 1) * rows]);
        left_classes(before, two_before, &mut left);
        for (j, &row) in order.rows.iter().enumerate() {
            let t = context_of(order, column, &left, j, row);
            encode_integer(coder, &mut models[t], column[row]);
        }
    }
}

/// The context of a [`Proper::Listed`] order's `step`, at position `j`, from the saturated
/// magnitudes in `recent` (see [`ColumnDecoder`]), the sources past its first ones read from
/// `more`; with its row and the row's magnitude in the column before. `MESH`: the neighbours
/// are averaged (U1's), else the first counts twice and the second once. One function for the
/// encoder's and the decoder's loops, inlined into both.
#[inline(always)]
fn step_context<const MESH: bool>(
    recent: &[[u32; 2]],
    j: usize,
    step: &Step,
    more: &mut std::slice::Iter<'_, u32>,
) -> (usize, usize, u32) {
    // every source is a position below recent.len() (the order was checked, its padding
    // included): clamped to the last one, the index is the same, and known to be in bounds
    let Some(last) = recent.len().checked_sub(1) else {
        return (0, step.row as usize, 0);
    };
    let latest = |w: u32| u64::from(recent[(w as usize).min(last)][0]);
    let count = step.sources();
    let [w, v, ..] = step.first;
    let a = if MESH {
        // the padding adds 0s: no branch on the count
        let mut total: u64 = step.first.iter().map(|&w| latest(w)).sum();
        if count <= FIRST_SOURCES {
            // floor(3 total / count) without a division (total < 2**31, mean_scale < 2**32)
            let mean = (total * u64::from(step.mean_scale)) >> MEAN_SHIFT;
            usize::from(count != 0) + bit_length(mean).min(NEIGHBOUR_CLASSES - 2)
        } else {
            let others = more.by_ref().take(count - FIRST_SOURCES);
            total += others.map(|&w| latest(w)).sum::<u64>();
            mean_class(3 * total, count as u64)
        }
    } else if count == 0 {
        0
    } else if count == 1 {
        magnitude_class(3 * latest(w))
    } else {
        magnitude_class(2 * latest(w) + latest(v))
    };
    let [before, two_before] = recent[j.min(last)];
    let b = usize::from(left_class(u64::from(2 * before + two_before)));
    (a * LEFT_CLASSES + b, step.row as usize, before)
}

/// The context of row `r` in [`Proper::Sequence`]: from `one` and `two`, the saturated
/// magnitudes of the two rows before, and `recent`, the row's in the two columns before (the
/// first of which is returned too). For the encoder's and the decoder's loops, inlined into both.
#[inline(always)]
fn sequence_context(r: usize, one: u64, two: u64, recent: [u32; 2]) -> (usize, u32) {
    let a = match r {
        0 => 0,
        1 => magnitude_class(3 * one),
        _ => magnitude_class(2 * one + two),
    };
    let [before, two_before] = recent;
    let b = usize::from(left_class(u64::from(2 * before + two_before)));
    (a * LEFT_CLASSES + b, before)
}

/// The encoder's loop for a proper order ([`CodingOrder::proper`]): the decoder's
/// ([`ColumnDecoder`]), each class from the saturated magnitudes of a row's latest two values,
/// so the same contexts as the general loop (as the decoder's fast loop reads the general
/// loop's streams), without its divisions and its reads of two other columns a row.
struct ColumnEncoder {
    models: Box<[Context; CONTEXTS]>,
    /// As [`ColumnDecoder`]'s: by position j of the order (row r), |x[r, c]| once row r of
    /// column c is coded, else |x[r, c - 1]|, and the one before it.
    recent: Vec<[u32; 2]>,
}

impl ColumnEncoder {
    fn new(rows: usize) -> Self {
        ColumnEncoder {
            models: Box::new([FRESH_CONTEXT; CONTEXTS]),
            recent: vec![[0u32; 2]; rows + 1],
        }
    }

    /// Codes `column` (the order's rows long) in a [`Proper::Listed`] order, as
    /// [`ColumnDecoder::column`] decodes it.
    #[inline(never)]
    fn column<const MESH: bool>(
        &mut self,
        coder: &mut RangeEncoder,
        steps: &[Step],
        more: &[u32],
        column: &[i64],
    ) {
        let models = &mut self.models;
        let recent = self.recent.as_mut_slice();
        let mut more = more.iter();
        for (j, step) in steps.iter().enumerate() {
            let (context, row, before) = step_context::<MESH>(recent, j, step, &mut more);
            let value = column.get(row).copied().unwrap_or(0);
            encode_integer(coder, &mut models[context], value);
            if let Some(slot) = recent.get_mut(j) {
                *slot = [saturated(value), before];
            }
        }
    }

    /// Codes `column` in [`Proper::Sequence`], as [`ColumnDecoder::sequence_column`] decodes it.
    #[inline(never)]
    fn sequence_column(&mut self, coder: &mut RangeEncoder, column: &[i64]) {
        let models = &mut self.models;
        let (mut one, mut two) = (0u64, 0u64);
        for (r, (&value, recent)) in column.iter().zip(self.recent.iter_mut()).enumerate() {
            let (context, before) = sequence_context(r, one, two, *recent);
            encode_integer(coder, &mut models[context], value);
            let magnitude = saturated(value);
            *recent = [magnitude, before];
            (one, two) = (u64::from(magnitude), one);
        }
    }
}

/// The `cols` columns of `order.row_count()` integers of an adaptive stream (shape (cols,
/// rows), column-major), or R46. Checks [`check_size`] first.
pub fn decode_columns(
    payload: &[u8],
    cols: usize,
    order: &CodingOrder,
) -> Result<Vec<i64>, Broken> {
    let rows = order.row_count;
    check_size(cols, rows, payload.len())?;
    // within the bound: at most 2**15 integers a byte of a payload that exists
    let mut out = vec![0i64; cols * rows];
    decode_columns_into(payload, order, &mut out)?;
    Ok(out)
}

/// [`decode_columns`] into `out`, whose length must be a whole number of columns of the order's
/// rows (an array the caller allocated after [`check_size`]). Every entry is written (0 for a
/// row the order leaves out); on an error, what `out` holds is unspecified.
pub fn decode_columns_into(
    payload: &[u8],
    order: &CodingOrder,
    out: &mut [i64],
) -> Result<(), Broken> {
    let rows = order.row_count;
    let cols = out.len().checked_div(rows).unwrap_or(0);
    check_size(cols, rows, payload.len())?;
    if cols * rows != out.len() {
        return Err(Broken::new(
            RULE,
            format!("{} integers are not columns of {rows} rows", out.len()),
        ));
    }
    let coder = RangeDecoder::new(payload)?;
    let Some(proper) = &order.proper else {
        return decode_general(coder, order, out)?.finish();
    };
    let mut decoder = ColumnDecoder::new(coder, rows);
    if rows > 0 {
        for column in out.chunks_exact_mut(rows) {
            decoder.next_column(proper, order.mesh, column)?;
        }
    }
    decoder.coder.finish()
}

/// The `cols` columns of an adaptive stream decoded into buffers of the caller's instead of one
/// array, so that a caller can use each run of columns while the next ones decode: each
/// run of `block` columns (the last one may be shorter) is decoded into the vector `buffer()`
/// gives (resized to the run, its old values overwritten), then handed to `done(first column,
/// the run)`, which may give it back through `buffer` once it is used. A caller that restores
/// each run on another thread then needs a few runs' memory, not the whole matrix's. Checks
/// [`check_size`] first; the errors are [`decode_columns_into`]'s; a run handed over is final, but
/// the stream is only known to be whole once this returns `Ok`.
pub fn decode_runs(
    payload: &[u8],
    order: &CodingOrder,
    cols: usize,
    block: usize,
    mut buffer: impl FnMut() -> Vec<i64>,
    mut done: impl FnMut(usize, Vec<i64>),
) -> Result<(), Broken> {
    let rows = order.row_count;
    check_size(cols, rows, payload.len())?;
    let coder = RangeDecoder::new(payload)?;
    let block = block.max(1);
    let Some(proper) = &order.proper else {
        // within the bound: at most 2**15 integers a byte of a payload that exists
        let mut out = vec![0i64; cols * rows];
        decode_general(coder, order, &mut out)?.finish()?;
        if rows > 0 {
            for (n, run) in out.chunks(block * rows).enumerate() {
                let mut vector = buffer();
                vector.clear();
                vector.extend_from_slice(run);
                done(n * block, vector);
            }
        }
        return Ok(());
    };
    let mut decoder = ColumnDecoder::new(coder, rows);
    if rows > 0 {
        for first in (0..cols).step_by(block) {
            let mut run = buffer();
            // every entry of a column is written: a reused vector's values need no clearing
            run.resize(block.min(cols - first) * rows, 0);
            for column in run.chunks_exact_mut(rows) {
                decoder.next_column(proper, order.mesh, column)?;
            }
            done(first, run);
        }
    }
    decoder.coder.finish()
}

/// Magnitudes saturate at 2**29 in the fast loop: `2 |x| + |y|` stays within a u32, and any
/// class that a saturated magnitude enters is the top one either way (a left class of 5, a
/// neighbour class of 15 for up to 3 * 2**15 sources: 3 * 2**29 / count >= 2**14).
const MAGNITUDE_CAP: u32 = 1 << 29;

/// |value|, saturated at [`MAGNITUDE_CAP`].
#[inline(always)]
fn saturated(value: i64) -> u32 {
    value.unsigned_abs().min(u64::from(MAGNITUDE_CAP)) as u32
}

/// 1 + min(bit length of m, 14): the neighbour class of a magnitude m.
#[inline(always)]
fn magnitude_class(m: u64) -> usize {
    1 + (64 - m.leading_zeros() as usize).min(NEIGHBOUR_CLASSES - 2)
}

/// `magnitude_class(floor(x / count))` without a division (which would sit in the chain from one
/// integer to the next): with k = bitlen(x) - bitlen(count), floor(x / count) has k + 1 bits if
/// x >= count << k, else k (none if k < 0).
#[inline(always)]
fn mean_class(x: u64, count: u64) -> usize {
    let k = count.leading_zeros() as i32 - x.leading_zeros() as i32;
    let bits = if k < 0 {
        0
    } else {
        // count << k < 2**bitlen(x): no bit is lost
        k + i32::from(x >= count << k)
    };
    1 + (bits as usize).min(NEIGHBOUR_CLASSES - 2)
}

/// The decoder's loop for a proper order ([`CodingOrder::proper`]), a column at a time: each
/// row's earlier neighbours are decoded before it in its column, so one array of saturated
/// magnitudes per row (its latest and the one before) gives both classes, and every entry of
/// a column is written.
struct ColumnDecoder<'a> {
    coder: RangeDecoder<'a>,
    models: Box<[Context; CONTEXTS]>,
    /// recent[j] for position j of the order (row r): |x[r, c]| once row r of column c is
    /// decoded, |x[r, c - 1]| until then, and the one before it. By position, not by row: a
    /// mesh's neighbours, decoded close together, are read from a few cache lines (its
    /// magnitudes by row are spread over more than a core's first-level cache), and each
    /// position's own ones in order. In [`Proper::Sequence`], positions are the rows.
    recent: Vec<[u32; 2]>,
}

impl<'a> ColumnDecoder<'a> {
    fn new(coder: RangeDecoder<'a>, rows: usize) -> Self {
        ColumnDecoder {
            coder,
            models: Box::new([FRESH_CONTEXT; CONTEXTS]),
            // one more than the rows: the padding of the first sources, whose magnitudes stay 0
            recent: vec![[0u32; 2]; rows + 1],
        }
    }

    /// The next column into `column` (the order's rows long), in a [`Proper::Listed`] order of
    /// `steps` and `more`. `MESH`: the neighbours are averaged (U1's), else the first counts
    /// twice and the second once.
    // not inlined: compiled on its own, the loop keeps more of its state in registers
    #[inline(never)]
    fn column<const MESH: bool>(
        &mut self,
        steps: &[Step],
        more: &[u32],
        column: &mut [i64],
    ) -> Result<(), Broken> {
        // a copy of its own, in registers (see RangeDecoder)
        let mut coder = self.coder;
        let models = &mut self.models;
        let recent = self.recent.as_mut_slice();
        let mut more = more.iter();
        let Some(first) = steps.first() else {
            return Ok(());
        };
        let mut next = step_context::<MESH>(recent, 0, first, &mut more);
        for j in 0..steps.len() {
            let (context, row, before) = next;
            // the next position's context before this one's decisions, unless this one is
            // among its sources: after a mispredicted branch on the decisions, the next
            // integer's first one does not wait for its context's loads and arithmetic again
            let following = steps.get(j + 1);
            let after = following.filter(|step| step.count & AFTER_SOURCE != 0);
            if let Some(step) = following.filter(|_| after.is_none()) {
                next = step_context::<MESH>(recent, j + 1, step, &mut more);
            }
            let value = decode_integer(&mut coder, &mut models[context])?;
            if let Some(slot) = column.get_mut(row) {
                *slot = value;
            }
            if let Some(slot) = recent.get_mut(j) {
                *slot = [saturated(value), before];
            }
            if let Some(step) = after {
                next = step_context::<MESH>(recent, j + 1, step, &mut more);
            }
        }
        self.coder = coder;
        // a read past the end spoils no check before it: once a column is done is soon enough
        coder.check_overrun()
    }
}

impl ColumnDecoder<'_> {
    /// The next column into `column` (the order's rows long), in the proper order `proper`
    /// (`mesh`: U1's averaged neighbours).
    #[inline]
    fn next_column(
        &mut self,
        proper: &Proper,
        mesh: bool,
        column: &mut [i64],
    ) -> Result<(), Broken> {
        match proper {
            Proper::Sequence => self.sequence_column(column),
            Proper::Listed { steps, more } if mesh => self.column::<true>(steps, more, column),
            Proper::Listed { steps, more } => self.column::<false>(steps, more, column),
        }
    }

    /// The next column into `column` in [`Proper::Sequence`]: [`ColumnDecoder::column`] with
    /// the two rows before in registers.
    #[inline(never)] // as `column`
    fn sequence_column(&mut self, column: &mut [i64]) -> Result<(), Broken> {
        let mut coder = self.coder;
        let models = &mut self.models;
        // |x| of the row before and the one before it, saturated
        let (mut one, mut two) = (0u64, 0u64);
        for (r, (slot, recent)) in column.iter_mut().zip(self.recent.iter_mut()).enumerate() {
            let (context, before) = sequence_context(r, one, two, *recent);
            let value = decode_integer(&mut coder, &mut models[context])?;
            *slot = value;
            let magnitude = saturated(value);
            *recent = [magnitude, before];
            (one, two) = (u64::from(magnitude), one);
        }
        self.coder = coder;
        coder.check_overrun()
    }
}

/// The decoder's loop for any order: the reference's, each class from the integers themselves
/// (rows the order leaves out are 0, sources not decoded yet count as 0).
fn decode_general<'a>(
    coder: RangeDecoder<'a>,
    order: &CodingOrder,
    out: &mut [i64],
) -> Result<RangeDecoder<'a>, Broken> {
    let rows = order.row_count;
    let cols = out.len().checked_div(rows).unwrap_or(0);
    let mut coder = coder;
    out.fill(0);
    let mut models = fresh_models();
    let mut left = vec![0u8; rows];
    for c in 0..cols {
        let (done, rest) = out.split_at_mut(c * rows);
        let column = &mut rest[..rows];
        let before = c.checked_sub(1).map(|b| &done[b * rows..(b + 1) * rows]);
        let two_before = c.checked_sub(2).map(|b| &done[b * rows..(b + 1) * rows]);
        left_classes(before, two_before, &mut left);
        for (j, &row) in order.rows.iter().enumerate() {
            let t = context_of(order, column, &left, j, row);
            let value = decode_integer(&mut coder, &mut models[t])?;
            coder.check_overrun()?;
            column[row] = value;
        }
    }
    Ok(coder)
}
