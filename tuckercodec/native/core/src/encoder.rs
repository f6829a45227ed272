//! The encoder's trial loops: rate-distortion rounding (`tuckercodec/encoder/rdo.py`, under
//! predictor 2 in `mean_choice.rs`) and the order-0 entropy of trial streams
//! (`tuckercodec/encoder/estimate.py`).
//!
//! Every result is the same as the Python reference's, integer for integer; where a float
//! feeds a decision it is computed with the same operations in the same order (no fused
//! multiply-add, per-column sums row after row as numpy reduces a C-ordered array along its
//! first axis), so the choices are the same bit for bit. The float sums whose order numpy
//! decides in ways not worth copying (a histogram's total, a dot product) stay in Python: the
//! functions here return the integers they are formed from.
//!
//! The inputs come from the encoder, not from a file, but every index is still checked: a bad
//! one is an [`EncoderError`], never a panic.

use std::fmt;

mod mean_choice;

pub use mean_choice::{rdo_mean_choice, MeanChoiceModel};

/// An argument the encoder's loops cannot use (shapes that disagree, a parent out of range).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EncoderError(pub String);

impl fmt::Display for EncoderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for EncoderError {}

fn fail<T>(detail: impl Into<String>) -> Result<T, EncoderError> {
    Err(EncoderError(detail.into()))
}

/// Signed to unsigned as `streams.zigzag`, kept signed: `(v << 1) ^ (v >> 63)` with int64
/// wrapping, as numpy computes it.
#[inline]
fn zigzag(value: i64) -> i64 {
    value.wrapping_shl(1) ^ (value >> 63)
}

/// A (rows, cols) row-major matrix's shape, checked against the length of its data.
fn check_shape(len: usize, rows: usize, cols: usize, what: &str) -> Result<(), EncoderError> {
    match rows.checked_mul(cols) {
        Some(n) if n == len => Ok(()),
        _ => fail(format!("{what} holds {len} values, not {rows} x {cols}")),
    }
}

/// Each row's parent as an index (`None` for a root), every parent checked to be a row.
fn checked_parents(parents: &[i64], rows: usize) -> Result<Vec<Option<usize>>, EncoderError> {
    if parents.len() != rows {
        return fail(format!("{} parents for {rows} rows", parents.len()));
    }
    parents
        .iter()
        .map(|&p| {
            if p < 0 {
                Ok(None)
            } else {
                match usize::try_from(p) {
                    Ok(i) if i < rows => Ok(Some(i)),
                    _ => fail(format!("parent {p} is not one of the {rows} rows")),
                }
            }
        })
        .collect()
}

/// `q[r, c] - q[parent(r), c] * predicted[c]` (a root, or a column not predicted, keeps `q`):
/// `rdo._residuals`.
fn residual(
    q: &[i64],
    cols: usize,
    row: usize,
    col: usize,
    parent: Option<usize>,
    predicted: bool,
) -> i64 {
    let value = q[row * cols + col];
    match parent {
        Some(p) if predicted => value.wrapping_sub(q[p * cols + col]),
        _ => value,
    }
}

/// `log2(1 + 2|x|)` of integers, small magnitudes from a table made with the same `log2`.
struct ProxyLog {
    small: Vec<f64>,
}

impl ProxyLog {
    const SMALL: usize = 4096;

    fn new() -> Self {
        ProxyLog {
            small: (0..Self::SMALL)
                .map(|m| (1.0 + 2.0 * m as f64).log2())
                .collect(),
        }
    }

    #[inline]
    fn of(&self, value: i64) -> f64 {
        let magnitude = value.unsigned_abs();
        match usize::try_from(magnitude) {
            Ok(m) if m < Self::SMALL => self.small[m],
            // numpy: abs in int64 (the minimum stays negative), then to float64
            _ => (1.0 + 2.0 * (value.wrapping_abs() as f64)).log2(),
        }
    }
}

/// Which columns `rdo._predicted_columns` predicts: those whose mean `log2(1 + 2|x|)` (the
/// proxy of `qmat.encode_matrix`) is smaller over the residuals from every row's parent than
/// over `q` itself. None if no row has a parent. For two columns or more: with one column,
/// numpy sums pairwise, and the caller decides in Python.
pub fn rdo_predicted_columns(
    q: &[i64],
    rows: usize,
    cols: usize,
    parents: &[i64],
) -> Result<Vec<bool>, EncoderError> {
    check_shape(q.len(), rows, cols, "q")?;
    let parents = checked_parents(parents, rows)?;
    if parents.iter().all(Option::is_none) {
        return Ok(vec![false; cols]);
    }
    let log = ProxyLog::new();
    let mut predicted_cost = vec![0.0f64; cols];
    let mut plain_cost = vec![0.0f64; cols];
    for (row, &parent) in parents.iter().enumerate() {
        for col in 0..cols {
            predicted_cost[col] += log.of(residual(q, cols, row, col, parent, true));
            plain_cost[col] += log.of(q[row * cols + col]);
        }
    }
    let count = rows as f64;
    Ok(predicted_cost
        .iter()
        .zip(&plain_cost)
        .map(|(&p, &n)| p / count < n / count)
        .collect())
}

/// The per-column histograms of `rdo._bit_table`: (cols, table_size + 1) counts of the zigzag
/// residuals (`rdo._residuals` under `predicted`), clipped to `table_size`, row-major.
pub fn rdo_residual_counts(
    q: &[i64],
    rows: usize,
    cols: usize,
    parents: &[i64],
    predicted: &[bool],
    table_size: usize,
) -> Result<Vec<i64>, EncoderError> {
    check_shape(q.len(), rows, cols, "q")?;
    let parents = checked_parents(parents, rows)?;
    if predicted.len() != cols {
        return fail(format!(
            "{} predicted flags for {cols} columns",
            predicted.len()
        ));
    }
    let width = table_size + 1;
    let mut counts = vec![0i64; cols * width];
    let top = i64::try_from(table_size).unwrap_or(i64::MAX);
    for (row, &parent) in parents.iter().enumerate() {
        for (col, &flag) in predicted.iter().enumerate() {
            let zig = zigzag(residual(q, cols, row, col, parent, flag)).min(top);
            match usize::try_from(zig) {
                Ok(index) => counts[col * width + index] += 1,
                Err(_) => return fail("a residual too large for int64's zigzag"),
            }
        }
    }
    Ok(counts)
}

/// `rdo._residual_counts`: each column's histogram of the zigzag of its residuals, clipped to
/// `table_size`, of a (rows, cols) row-major matrix: (cols, `table_size` + 1) counts.
pub fn zigzag_counts(
    residual: &[i64],
    rows: usize,
    cols: usize,
    table_size: usize,
) -> Result<Vec<i64>, EncoderError> {
    check_shape(residual.len(), rows, cols, "the residuals")?;
    let width = table_size + 1;
    let mut counts = vec![0i64; cols * width];
    let top = i64::try_from(table_size).unwrap_or(i64::MAX);
    for row in residual.chunks_exact(cols.max(1)) {
        for (col, &value) in row.iter().enumerate() {
            match usize::try_from(zigzag(value).min(top)) {
                Ok(index) => counts[col * width + index] += 1,
                Err(_) => return fail("a residual too large for int64's zigzag"),
            }
        }
    }
    Ok(counts)
}

/// What `rdo._choose` needs besides the values: the prediction tree and its order, the
/// columns predicted, the bit tables and the rate weight.
pub struct ChooseModel<'a> {
    /// Each row's parent (negative: a root).
    pub parents: &'a [i64],
    /// Every row once, each after its parent (the tree's levels one after the other).
    pub order: &'a [i64],
    /// Per column, whether it is predicted from the parent.
    pub predicted: &'a [bool],
    /// (cols, table_size + 1) bits of each clipped zigzag residual, row-major.
    pub table: &'a [f64],
    pub table_size: usize,
    pub lam: f64,
}

/// `rdo._choose`: each entry of `values / steps` rounded down or up, whichever costs less in
/// `error + lam * bits(residual)` (ties to the nearer integer), rows taken in `order` so that
/// each parent is final before its children.
pub fn rdo_choose(
    values: &[f64],
    rows: usize,
    cols: usize,
    steps: &[f64],
    model: &ChooseModel<'_>,
) -> Result<Vec<i64>, EncoderError> {
    check_shape(values.len(), rows, cols, "values")?;
    let parents = checked_parents(model.parents, rows)?;
    let width = model.table_size + 1;
    if steps.len() != cols || model.predicted.len() != cols {
        return fail(format!("steps and predicted flags must be {cols} each"));
    }
    check_shape(model.table.len(), cols, width, "the bit table")?;
    if model.order.len() != rows {
        return fail(format!("an order of {} rows for {rows}", model.order.len()));
    }
    let top = i64::try_from(model.table_size).unwrap_or(i64::MAX);
    let escape_base = model.table_size as f64;
    let bits = |col: usize, residual: i64| -> f64 {
        let zig = zigzag(residual);
        let index = usize::try_from(zig.min(top)).unwrap_or(0);
        let base = model.table[col * width + index];
        if zig > top {
            base + 2.0 * ((zig.max(1) as f64) / escape_base).log2()
        } else {
            base
        }
    };
    let mut q = vec![0i64; values.len()];
    let mut done = vec![false; rows];
    for &row in model.order {
        let row = match usize::try_from(row) {
            Ok(r) if r < rows && !done[r] => r,
            _ => return fail(format!("the order's row {row} is not a row not yet chosen")),
        };
        let parent = parents[row];
        if let Some(p) = parent {
            if !done[p] {
                return fail(format!("row {row} comes before its parent {p}"));
            }
        }
        for col in 0..cols {
            let scaled = values[row * cols + col] / steps[col];
            let low = scaled.floor();
            let below = (scaled - low) * (scaled - low);
            let above_gap = low + 1.0 - scaled;
            let above = above_gap * above_gap;
            let base = low as i64;
            let prediction = match parent {
                Some(p) if model.predicted[col] => q[p * cols + col],
                _ => 0,
            };
            let residual = base.wrapping_sub(prediction);
            let cost_low = below + model.lam * bits(col, residual);
            let cost_high = above + model.lam * bits(col, residual.wrapping_add(1));
            let high = cost_high < cost_low || (cost_high == cost_low && above < below);
            q[row * cols + col] = base.wrapping_add(i64::from(high));
        }
        done[row] = true;
    }
    Ok(q)
}

/// The largest |x| of `values` (NaN if one is NaN, 0 for none), as numpy's
/// `np.abs(values).max()` (the maximum is exact in any order).
pub fn max_abs(values: &[f64]) -> f64 {
    let mut largest = 0.0f64;
    for &value in values {
        let magnitude = value.abs();
        if magnitude.is_nan() {
            return f64::NAN;
        }
        if magnitude > largest {
            largest = magnitude;
        }
    }
    largest
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zigzag_matches_the_stream_rule() {
        assert_eq!(
            [0, -1, 1, -2, 2].map(zigzag),
            [0, 1, 2, 3, 4],
            "0, -1, 1, -2, 2 -> 0, 1, 2, 3, 4"
        );
    }

    #[test]
    fn a_parent_out_of_range_is_an_error() {
        assert!(rdo_residual_counts(&[1, 2], 2, 1, &[-1, 5], &[true], 8).is_err());
        assert!(rdo_predicted_columns(&[1, 2], 2, 1, &[-1, 2]).is_err());
        assert!(checked_parents(&[-1], 2).is_err());
    }

    #[test]
    fn shapes_must_agree() {
        assert!(rdo_residual_counts(&[1, 2], 2, 1, &[-1, 0], &[true, false], 8).is_err());
    }

    #[test]
    fn residual_counts_follow_the_parents() {
        // column 0 predicted: residuals 3, 1, -1 -> zigzag 6, 2, 1; column 1 not: 0, 0, 9 (clipped 8)
        let q = [3, 0, 4, 0, 3, 9];
        let counts = rdo_residual_counts(&q, 3, 2, &[-1, 0, 1], &[true, false], 8).unwrap();
        let mut expected = vec![0i64; 18];
        expected[6] += 1;
        expected[2] += 1;
        expected[1] += 1;
        expected[9] += 2;
        expected[9 + 8] += 1;
        assert_eq!(counts, expected);
    }

    #[test]
    fn zigzag_counts_clip_each_column() {
        // column 0: 3, -1, 0 -> zigzag 6, 1, 0; column 1: -5, 4, 9 -> 9 (clipped 8), 8, 18 (8)
        let residual = [3, -5, -1, 4, 0, 9];
        let counts = zigzag_counts(&residual, 3, 2, 8).unwrap();
        let mut expected = vec![0i64; 18];
        for index in [6, 1, 0, 9 + 8, 9 + 8, 9 + 8] {
            expected[index] += 1;
        }
        assert_eq!(counts, expected);
        assert!(zigzag_counts(&residual, 2, 2, 8).is_err());
        assert!(zigzag_counts(&[i64::MIN / 2 - 1], 1, 1, 8).is_err());
        assert_eq!(zigzag_counts(&[], 0, 3, 2).unwrap(), vec![0; 9]);
    }

    #[test]
    fn choose_with_no_rate_is_nearest_rounding() {
        let values = [0.4, 1.6, -0.4, 2.5, -2.5, 7.49];
        let table = vec![1.0; 2 * 9];
        let model = ChooseModel {
            parents: &[-1, 0, 1],
            order: &[0, 1, 2],
            predicted: &[true, false],
            table: &table,
            table_size: 8,
            lam: 0.0,
        };
        let q = rdo_choose(&values, 3, 2, &[1.0, 1.0], &model).unwrap();
        // a tie (x.5) with equal errors keeps the floor, as the reference's rule does
        assert_eq!(q, vec![0, 2, 0, 2, -3, 7]);
    }

    #[test]
    fn choose_refuses_an_order_that_breaks_the_tree() {
        let table = vec![1.0; 9];
        let model = ChooseModel {
            parents: &[-1, 0],
            order: &[1, 0],
            predicted: &[true],
            table: &table,
            table_size: 8,
            lam: 0.1,
        };
        assert!(rdo_choose(&[0.0, 0.0], 2, 1, &[1.0], &model).is_err());
    }

    #[test]
    fn max_abs_is_the_largest_magnitude() {
        assert_eq!(max_abs(&[]), 0.0);
        assert_eq!(max_abs(&[1.0, -3.5, 2.0]), 3.5);
        assert!(max_abs(&[1.0, f64::NAN]).is_nan());
    }

    #[test]
    fn predicted_columns_compare_the_proxies() {
        // a smooth column pays to predict; a column of zeros does not (equal costs: not less)
        let q = [10, 0, 11, 0, 12, 0];
        assert_eq!(
            rdo_predicted_columns(&q, 3, 2, &[-1, 0, 1]).unwrap(),
            vec![true, false]
        );
        assert_eq!(
            rdo_predicted_columns(&q, 3, 2, &[-1, -1, -1]).unwrap(),
            vec![false, false]
        );
    }
}
