//! Spec section 6.2, prediction: restoring each entry of a quantized column from its parent's
//! (predictor 1), the mean of its decoded neighbours (predictor 2) or its two previous rows
//! (predictor 3), and forming predictor 2's residuals, with the results of
//! `tuckercodec/format/prediction.py` to the bit.
//!
//! Fuzzing entry points (plain Rust, any input, an `Err` and never a panic for a bad one):
//! [`topology::Forest::new`] then [`MeanPlan::from_steps`] and [`MeanPlan::restore_columns`] for
//! a face table and U1's residuals; [`accumulate_tree`], [`accumulate_rows`] and
//! [`linear_accumulate`] for the other predictors.

mod push_costs;
pub mod topology;
pub mod values;

pub use push_costs::{numpy_pairwise_sum, PUSH_COUNT};

use topology::MeanStepsArrays;

/// Every value of a column with predictor 2 lies within +-this (`MEAN_LIMIT`).
pub const MEAN_LIMIT: i64 = 1 << 32;
/// From this many sources per row on (only a crafted mesh), predictor 2 runs in int64 as
/// `mean_predictions` does; below it float64 is exact (`_FLOAT_SOURCES`).
pub const FLOAT_SOURCES: usize = 1 << 17;
/// From this many sources per row on, a column whose push is not 2 runs in int64 (i128 here):
/// below it float64 sums `V + 3c` exactly (§6.2, *Push*).
pub const PUSHED_FLOAT_SOURCES: usize = 1 << 16;
/// The push of today's predictor 2 (a column without `mean_push`): `V = 2U`.
pub const PLAIN_PUSH: u8 = 2;
/// The largest push a column may carry (`mean_push` bytes lie in `0..=MAX_PUSH`).
pub const MAX_PUSH: u8 = 9;
/// Predictor 3's limits on the restored values and their first differences.
pub const LINEAR_LIMIT: i64 = 1 << 32;
pub const LINEAR_STEP_LIMIT: i64 = 1 << 33;

/// What `mean_accumulate` raises (a `ValueError`, R32 for the caller).
pub const MEAN_RANGE: &str = "a restored value leaves the range of predictor 2";
/// What `linear_accumulate` raises for a first difference out of range.
pub const LINEAR_STEP_RANGE: &str = "a difference restored with predictor 3 leaves the range";
/// What `linear_accumulate` raises for a value out of range.
pub const LINEAR_RANGE: &str = "a value restored with predictor 3 leaves the range";

/// A caller's error or a restored value out of range: the text of the Python `ValueError`.
pub type PredictionError = String;

/// Predictor 2's steps with the sparse matrix of its sums, ready to restore or predict columns.
///
/// Row j of the matrix (`MeanSteps.matrix`) sums `4 q[w] - q[anchor(w)]` over row j's sources:
/// its columns ascending and merged (4 at a source, -1 at an anchor, repeats summed), the
/// order scipy's `sum_duplicates` leaves and `csr_matvecs` adds in.
///
/// Every function that restores or predicts takes a push per column (`mean_push`, §6.2): a
/// column of push a sums `V = sum of (6 + a) q[w] - a q[anchor(w)]` and predicts
/// `floor((2V + 6c) / 12c)`; push 2 is today's prediction and runs today's arithmetic.
#[derive(Debug, Clone)]
pub struct MeanPlan {
    /// The vertex restored by each row, by step.
    pub rows: Vec<u32>,
    /// Step s restores `rows[step_ends[s]..step_ends[s + 1]]`.
    pub step_ends: Vec<usize>,
    /// Each row's number of sources (at least 1), before merging.
    pub counts: Vec<usize>,
    /// The matrix: row j's entries are `columns[pointers[j]..pointers[j + 1]]`.
    pub pointers: Vec<usize>,
    pub columns: Vec<u32>,
    pub weights: Vec<f64>,
    /// Per entry of the matrix: how often its column is a source of the row (`s`), and that
    /// minus how often it is an anchor (`s - t`); a push a weighs it `6 s + a (s - t)`.
    source_weights: Vec<f64>,
    step_weights: Vec<f64>,
    /// Every index lies below this (the mesh's vertex count): the columns restored must have
    /// at least this many values.
    pub vertex_count: usize,
    /// The float path is exact (no row has `FLOAT_SOURCES` sources or more).
    pub exact_in_float: bool,
    /// The float path is exact for any push (no row has `PUSHED_FLOAT_SOURCES` sources or more).
    pub exact_in_float_pushed: bool,
    /// The sources and anchors by row, kept for the int64 path of a crafted mesh.
    sources: Vec<u32>,
    anchors: Vec<u32>,
    source_ends: Vec<usize>,
}

/// `value` lies outside `-limit..=limit` (compared, not by `abs`, which wraps at -2**63 and
/// would let it through).
#[inline]
fn beyond(value: i64, limit: i64) -> bool {
    value < -limit || value > limit
}

fn index_below(value: i64, bound: usize, what: &str) -> Result<u32, PredictionError> {
    if value < 0 || value as u64 >= bound as u64 || value > i64::from(u32::MAX) {
        return Err(format!("{what} {value} outside 0..{bound}"));
    }
    Ok(value as u32)
}

fn ends_checked(ends: &[i64], total: usize, what: &str) -> Result<Vec<usize>, PredictionError> {
    let mut out = Vec::with_capacity(ends.len());
    let mut last = 0i64;
    for (i, &end) in ends.iter().enumerate() {
        if (i == 0 && end != 0) || end < last || end as u64 > total as u64 {
            return Err(format!("{what} must rise from 0 to {total}"));
        }
        last = end;
        out.push(end as usize);
    }
    if out.last() != Some(&total) {
        return Err(format!("{what} must rise from 0 to {total}"));
    }
    Ok(out)
}

impl MeanPlan {
    /// The plan of `MeanSteps` arrays over `vertex_count` vertices, every index and end
    /// checked (an error, never a panic, for arrays that do not fit together).
    pub fn from_steps(
        rows: &[i64],
        step_ends: &[i64],
        sources: &[i64],
        anchors: &[i64],
        source_ends: &[i64],
        vertex_count: usize,
    ) -> Result<Self, PredictionError> {
        let rows = rows
            .iter()
            .map(|&r| index_below(r, vertex_count, "a row"))
            .collect::<Result<Vec<_>, _>>()?;
        let mut seen = vec![false; vertex_count];
        for &r in &rows {
            if std::mem::replace(&mut seen[r as usize], true) {
                return Err(format!("the row {r} is restored twice"));
            }
        }
        drop(seen);
        let step_ends = ends_checked(step_ends, rows.len(), "step_ends")?;
        if sources.len() != anchors.len() {
            return Err("sources and anchors differ in length".to_string());
        }
        let source_ends = ends_checked(source_ends, sources.len(), "source_ends")?;
        if source_ends.len() != rows.len() + 1 {
            return Err("source_ends must have one entry per row and one more".to_string());
        }
        let check = |values: &[i64], what: &str| {
            values
                .iter()
                .map(|&v| index_below(v, vertex_count, what))
                .collect::<Result<Vec<_>, _>>()
        };
        let sources = check(sources, "a source")?;
        let anchors = check(anchors, "an anchor")?;
        Ok(Self::build(
            rows,
            step_ends,
            sources,
            anchors,
            source_ends,
            vertex_count,
        ))
    }

    /// The plan of a forest's [`MeanStepsArrays`] (their indices are the forest's, in range).
    pub fn from_arrays(steps: &MeanStepsArrays, vertex_count: usize) -> Self {
        Self::build(
            steps.rows.clone(),
            steps.step_ends.clone(),
            steps.sources.clone(),
            steps.anchors.clone(),
            steps.source_ends.clone(),
            vertex_count,
        )
    }

    fn build(
        rows: Vec<u32>,
        step_ends: Vec<usize>,
        sources: Vec<u32>,
        anchors: Vec<u32>,
        source_ends: Vec<usize>,
        vertex_count: usize,
    ) -> Self {
        let counts: Vec<usize> = source_ends.windows(2).map(|w| w[1] - w[0]).collect();
        let mut pointers = Vec::with_capacity(rows.len() + 1);
        let mut columns = Vec::with_capacity(2 * sources.len());
        let mut weights = Vec::with_capacity(2 * sources.len());
        let mut source_weights = Vec::with_capacity(2 * sources.len());
        let mut step_weights = Vec::with_capacity(2 * sources.len());
        // (column, is a source)
        let mut entries: Vec<(u32, bool)> = Vec::new();
        pointers.push(0);
        for span in source_ends.windows(2) {
            entries.clear();
            entries.extend(sources[span[0]..span[1]].iter().map(|&s| (s, true)));
            entries.extend(anchors[span[0]..span[1]].iter().map(|&a| (a, false)));
            entries.sort_by_key(|&(column, _)| column);
            for &(column, source) in &entries {
                let (weight, once, step) = if source {
                    (4.0, 1.0, 1.0)
                } else {
                    (-1.0, 0.0, -1.0)
                };
                match (
                    weights.last_mut(),
                    source_weights.last_mut(),
                    step_weights.last_mut(),
                ) {
                    (Some(w), Some(s), Some(d))
                        if columns.len() > pointers[pointers.len() - 1]
                            && columns.last() == Some(&column) =>
                    {
                        *w += weight;
                        *s += once;
                        *d += step;
                    }
                    _ => {
                        columns.push(column);
                        weights.push(weight);
                        source_weights.push(once);
                        step_weights.push(step);
                    }
                }
            }
            pointers.push(columns.len());
        }
        let exact_in_float = counts.iter().all(|&c| c < FLOAT_SOURCES);
        let exact_in_float_pushed = counts.iter().all(|&c| c < PUSHED_FLOAT_SOURCES);
        MeanPlan {
            rows,
            step_ends,
            counts,
            pointers,
            columns,
            weights,
            source_weights,
            step_weights,
            vertex_count,
            exact_in_float,
            exact_in_float_pushed,
            sources,
            anchors,
            source_ends,
        }
    }

    /// Restores columns of predictor 2's residuals in place (`mean_accumulate_columns`):
    /// `columns` holds them one after the other, `height` values each (at least
    /// `vertex_count`), column c with push `push[c]` (one per column, each `0..=MAX_PUSH`).
    /// The rows are restored a step at a time, each from values restored before it, for
    /// [`COLUMN_BLOCK`] columns at once (their floats side by side, so that each of the
    /// matrix's entries serves them all).
    ///
    /// Errors: a `height` or a `push` that does not fit the steps or the array (a caller's
    /// error), or [`MEAN_RANGE`] when a value leaves +-`MEAN_LIMIT` (in float64 the whole block
    /// is checked at its end, in int64, for a crafted mesh, each step's rows after the step, as
    /// the Python does).
    pub fn restore_columns(
        &self,
        columns: &mut [i64],
        height: usize,
        push: &[u8],
    ) -> Result<(), PredictionError> {
        if height < self.vertex_count || (height == 0 && !columns.is_empty()) {
            return Err(format!(
                "columns of {height} values, fewer than the {} the steps index",
                self.vertex_count
            ));
        }
        if columns.is_empty() {
            return check_push(push, 0);
        }
        if columns.len() % height != 0 {
            return Err(format!(
                "{} values are not columns of {height}",
                columns.len()
            ));
        }
        check_push(push, columns.len() / height)?;
        let mut work = Vec::new();
        let mut predictions = Vec::new();
        for (block, push) in columns
            .chunks_mut(COLUMN_BLOCK * height)
            .zip(push.chunks(COLUMN_BLOCK))
        {
            if !self.float_is_exact(push) {
                for (column, &a) in block.chunks_exact_mut(height).zip(push) {
                    self.restore_column_integer(column, a)?;
                }
                continue;
            }
            let width = block.len() / height;
            // the block's values row after row: a row's columns side by side
            work.clear();
            work.resize(height * width, 0.0f64);
            // row after row, reading the block's columns side by side: each stream is read in
            // order and each row written whole (a column at a time would miss the cache at
            // every value of a large mesh)
            for (v, row) in work.chunks_exact_mut(width).enumerate() {
                for (c, value) in row.iter_mut().enumerate() {
                    *value = block[c * height + v] as f64;
                }
            }
            self.restore_block_float(&mut work, width, push, &mut predictions)?;
            for (v, row) in work.chunks_exact(width).enumerate() {
                for (c, &value) in row.iter().enumerate() {
                    block[c * height + v] = value as i64; // an integer within 2**32: exact
                }
            }
        }
        Ok(())
    }

    /// Float64 restores the columns of these pushes exactly: push 2 below `FLOAT_SOURCES`
    /// sources a row, any other below `PUSHED_FLOAT_SOURCES`.
    pub(super) fn float_is_exact(&self, push: &[u8]) -> bool {
        if push.iter().all(|&a| a == PLAIN_PUSH) {
            self.exact_in_float
        } else {
            self.exact_in_float_pushed
        }
    }

    /// `floor((U + 1.5 c) / 3c)` of row j for each of the `width` columns of `work` (row
    /// after row), into `sums`: the sums in the matrix's order, as scipy's `csr_matvecs` adds.
    #[inline]
    fn float_predictions(&self, j: usize, work: &[f64], width: usize, sums: &mut [f64]) {
        let count = self.counts[j] as f64;
        sums.fill(1.5 * count);
        let (start, stop) = (self.pointers[j], self.pointers[j + 1]);
        for (&column, &weight) in self.columns[start..stop]
            .iter()
            .zip(&self.weights[start..stop])
        {
            let base = column as usize * width;
            for (sum, &value) in sums.iter_mut().zip(&work[base..base + width]) {
                *sum += weight * value;
            }
        }
        let divisor = 3.0 * count;
        for sum in sums.iter_mut() {
            *sum = exact_floor(*sum / divisor);
        }
    }

    /// `floor((V + 3c) / 6c)` of row j for each of the `width` columns of `work`, column c
    /// pushed by `factors[c]`, into `sums`. Every term is an integer and every partial sum
    /// lies below `3c + 24c 2**32 < 2**53` (`c < PUSHED_FLOAT_SOURCES`, values within
    /// `MEAN_LIMIT`), so the sum is exact in any order and its one division floors right.
    #[inline]
    fn float_predictions_pushed(
        &self,
        j: usize,
        work: &[f64],
        width: usize,
        factors: &[f64],
        sums: &mut [f64],
    ) {
        let count = self.counts[j] as f64;
        sums.fill(3.0 * count);
        let (start, stop) = (self.pointers[j], self.pointers[j + 1]);
        for ((&column, &once), &step) in self.columns[start..stop]
            .iter()
            .zip(&self.source_weights[start..stop])
            .zip(&self.step_weights[start..stop])
        {
            let base = column as usize * width;
            let six = 6.0 * once;
            for ((sum, &value), &a) in sums.iter_mut().zip(&work[base..base + width]).zip(factors) {
                *sum += (six + a * step) * value;
            }
        }
        let divisor = 6.0 * count;
        for sum in sums.iter_mut() {
            *sum = exact_floor(*sum / divisor);
        }
    }

    /// `mean_predictions` of row j in int64, wrapping as numpy does.
    fn integer_prediction(&self, j: usize, values: &[i64]) -> i64 {
        let mut total = 0i64;
        for k in self.source_ends[j]..self.source_ends[j + 1] {
            let term = values[self.sources[k] as usize]
                .wrapping_mul(4)
                .wrapping_sub(values[self.anchors[k] as usize]);
            total = total.wrapping_add(term);
        }
        let count = self.counts[j] as i64;
        let numerator = total.wrapping_mul(2).wrapping_add(count.wrapping_mul(3));
        let divisor = count.wrapping_mul(6);
        if divisor == 0 {
            0 // numpy's floor_divide by zero
        } else {
            numerator.div_euclid(divisor)
        }
    }

    /// Row j's prediction with push `push`, exactly in i128 for any values and any count
    /// (each term is below 2**68 and there are fewer than 2**40 of them); a quotient beyond
    /// int64, only from values far out of range, saturates.
    fn integer_prediction_pushed(&self, j: usize, values: &[i64], push: u8) -> i64 {
        let a = i128::from(push);
        let mut total = 0i128;
        for k in self.source_ends[j]..self.source_ends[j + 1] {
            total += (6 + a) * i128::from(values[self.sources[k] as usize])
                - a * i128::from(values[self.anchors[k] as usize]);
        }
        let count = self.counts[j] as i128;
        if count == 0 {
            return 0; // never: every row has a source
        }
        let quotient = (2 * total + 6 * count).div_euclid(12 * count);
        i64::try_from(quotient).unwrap_or(if quotient < 0 { i64::MIN } else { i64::MAX })
    }

    /// One column restored in integers (a crafted mesh), with push `push`.
    pub(super) fn restore_column_integer(
        &self,
        column: &mut [i64],
        push: u8,
    ) -> Result<(), PredictionError> {
        let mut predictions = Vec::new();
        for span in self.step_ends.windows(2) {
            // a step's predictions all read the values before the step
            predictions.clear();
            if push == PLAIN_PUSH {
                predictions.extend((span[0]..span[1]).map(|j| self.integer_prediction(j, column)));
            } else {
                predictions.extend(
                    (span[0]..span[1]).map(|j| self.integer_prediction_pushed(j, column, push)),
                );
            }
            for (j, &prediction) in (span[0]..span[1]).zip(&predictions) {
                let slot = &mut column[self.rows[j] as usize];
                *slot = slot.wrapping_add(prediction);
            }
            if (span[0]..span[1]).any(|j| beyond(column[self.rows[j] as usize], MEAN_LIMIT)) {
                return Err(MEAN_RANGE.to_string());
            }
        }
        Ok(())
    }

    /// `mean_residuals` of a (`vertex_count`, `width`) int64 matrix given row after row, column
    /// c with push `push[c]`: each predicted row minus predictor 2's prediction from the values
    /// themselves, or `None` if a value leaves +-`MEAN_LIMIT`.
    pub fn residuals(
        &self,
        values: &[i64],
        width: usize,
        push: &[u8],
    ) -> Result<Option<Vec<i64>>, PredictionError> {
        self.residuals_laid_out(values, width, push, false)
    }

    /// [`MeanPlan::residuals`] column after column, (`width`, height), as a section streams
    /// them: the transposition made as the columns are read, not as a pass of its own.
    pub fn residual_columns(
        &self,
        values: &[i64],
        width: usize,
        push: &[u8],
    ) -> Result<Option<Vec<i64>>, PredictionError> {
        self.residuals_laid_out(values, width, push, true)
    }

    /// The rows of `values`, a matrix in rows of `width` (> 0) over this plan's vertices: an
    /// error where it is not one, `None` where a value is beyond predictor 2's range
    /// ([`MEAN_LIMIT`]).
    pub(super) fn matrix_height(
        &self,
        values: &[i64],
        width: usize,
    ) -> Result<Option<usize>, PredictionError> {
        let height = values.len() / width;
        if values.len() % width != 0 || height < self.vertex_count {
            return Err(format!(
                "a matrix of {} values in rows of {width}, fewer rows than the {} the steps index",
                values.len(),
                self.vertex_count
            ));
        }
        Ok((!values.iter().any(|&v| beyond(v, MEAN_LIMIT))).then_some(height))
    }

    fn residuals_laid_out(
        &self,
        values: &[i64],
        width: usize,
        push: &[u8],
        by_column: bool,
    ) -> Result<Option<Vec<i64>>, PredictionError> {
        check_push(push, width)?;
        if width == 0 {
            return Ok(Some(Vec::new()));
        }
        let Some(height) = self.matrix_height(values, width)? else {
            return Ok(None);
        };
        // where row v of column c goes
        let at = |v: usize, c: usize| {
            if by_column {
                c * height + v
            } else {
                v * width + c
            }
        };
        let mut out = if by_column {
            vec![0i64; values.len()] // each block's columns are copied in as they are read
        } else {
            values.to_vec()
        };
        // COLUMN_BLOCK columns at a time, their floats row after row
        let mut work = Vec::new();
        let mut sums = [0.0f64; COLUMN_BLOCK];
        let mut factors = [0.0f64; COLUMN_BLOCK];
        let mut column = Vec::new();
        for first in (0..width).step_by(COLUMN_BLOCK) {
            let block = COLUMN_BLOCK.min(width - first);
            let push = &push[first..first + block];
            if by_column {
                for (v, row) in values.chunks_exact(width).enumerate() {
                    for (c, &value) in (first..).zip(&row[first..first + block]) {
                        out[c * height + v] = value;
                    }
                }
            }
            if !self.float_is_exact(push) {
                column.resize(height, 0i64);
                for (c, &a) in (first..first + block).zip(push) {
                    for (v, slot) in column.iter_mut().enumerate() {
                        *slot = values[v * width + c];
                    }
                    for j in 0..self.rows.len() {
                        let prediction = if a == PLAIN_PUSH {
                            self.integer_prediction(j, &column)
                        } else {
                            self.integer_prediction_pushed(j, &column, a)
                        };
                        let slot = &mut out[at(self.rows[j] as usize, c)];
                        *slot = slot.wrapping_sub(prediction);
                    }
                }
                continue;
            }
            let plain = push.iter().all(|&a| a == PLAIN_PUSH);
            let factors = &mut factors[..block];
            for (factor, &a) in factors.iter_mut().zip(push) {
                *factor = f64::from(a);
            }
            work.clear();
            work.extend(
                values
                    .chunks_exact(width)
                    .flat_map(|row| row[first..first + block].iter().map(|&v| v as f64)),
            );
            let sums = &mut sums[..block];
            for j in 0..self.rows.len() {
                if plain {
                    self.float_predictions(j, &work, block, sums);
                } else {
                    self.float_predictions_pushed(j, &work, block, factors, sums);
                }
                let row = self.rows[j] as usize;
                for (c, &prediction) in (first..).zip(sums.iter()) {
                    let slot = &mut out[at(row, c)];
                    *slot = slot.wrapping_sub(float_to_int64(prediction));
                }
            }
        }
        Ok(Some(out))
    }
}

/// A caller's `push`: exactly `cols` bytes, each within `0..=MAX_PUSH`.
pub fn check_push(push: &[u8], cols: usize) -> Result<(), PredictionError> {
    if push.len() != cols {
        return Err(format!(
            "{} pushes for {cols} columns: one per column",
            push.len()
        ));
    }
    match push.iter().find(|&&a| a > MAX_PUSH) {
        Some(a) => Err(format!("a push of {a} outside 0..={MAX_PUSH}")),
        None => Ok(()),
    }
}

/// Columns restored or predicted at once: the floats of a block of a 100,000-vertex U1 take
/// 12.8 MB.
pub const COLUMN_BLOCK: usize = 16;

/// `x.floor()` to the bit (the sign of a zero aside, which no integer result keeps), in
/// arithmetic the compiler vectorizes, without the call to libm's `floor` that x86-64 without
/// SSE4.1 makes: below 2**52 in magnitude, adding and taking away 2**52 rounds to the nearest
/// integer, one less if that is above `x`; from 2**52 on `x` is an integer (or not finite).
#[inline]
pub(crate) fn exact_floor(x: f64) -> f64 {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    let big = TWO_52.copysign(x);
    let nearest = (x + big) - big;
    let floor = if nearest > x { nearest - 1.0 } else { nearest };
    if x.abs() < TWO_52 {
        floor
    } else {
        x
    }
}

/// numpy's float64 to int64 cast on x86-64: the value truncated, or `i64::MIN` when it does
/// not fit (NaN included).
#[inline]
fn float_to_int64(value: f64) -> i64 {
    let bound = (1u64 << 63) as f64; // exactly 2**63
    if (-bound..bound).contains(&value) {
        value as i64
    } else {
        i64::MIN
    }
}

/// Predictor 1 along a tree (`accumulate`): each row of the (rows, `width`) matrix `values`
/// plus all its ancestors' residuals, in place, wrapping as numpy's int64 does.
/// `parents[r]` is row r's parent or a negative number; an index out of range or a cycle is an
/// error.
pub fn accumulate_tree(
    values: &mut [i64],
    width: usize,
    parents: &[i64],
) -> Result<(), PredictionError> {
    let rows = parents.len();
    if values.len() != rows.saturating_mul(width) {
        return Err(format!(
            "{} values are not {rows} rows of {width}",
            values.len()
        ));
    }
    // 0: not restored, 1: on the chain being restored, 2: restored
    let mut state = vec![0u8; rows];
    let mut chain = Vec::new();
    for start in 0..rows {
        let mut row = start;
        while state[row] == 0 {
            state[row] = 1;
            chain.push(row);
            let parent = parents[row];
            if parent < 0 {
                break;
            }
            if parent as u64 >= rows as u64 {
                return Err(format!("a parent {parent} outside 0..{rows}"));
            }
            row = parent as usize;
            if state[row] == 1 {
                return Err("the parents form a cycle".to_string());
            }
        }
        while let Some(row) = chain.pop() {
            state[row] = 2;
            let parent = parents[row];
            if parent >= 0 {
                let (parent, row) = (parent as usize, row);
                for c in 0..width {
                    let above = values[parent * width + c];
                    let slot = &mut values[row * width + c];
                    *slot = slot.wrapping_add(above);
                }
            }
        }
    }
    Ok(())
}

/// Predictor 1 along the rows (time): the running sum of each column of the (rows, `width`)
/// matrix, in place, wrapping.
pub fn accumulate_rows(values: &mut [i64], width: usize) {
    if width == 0 {
        return;
    }
    let mut previous = vec![0i64; width];
    for row in values.chunks_exact_mut(width) {
        for (value, sum) in row.iter_mut().zip(previous.iter_mut()) {
            *sum = sum.wrapping_add(*value);
            *value = *sum;
        }
    }
}

/// Predictor 3 (`linear_accumulate`): two running sums down the rows, in place; an error when
/// a first difference leaves +-2**33 (checked over the whole matrix first) or a value +-2**32.
pub fn linear_accumulate(values: &mut [i64], width: usize) -> Result<(), PredictionError> {
    accumulate_rows(values, width);
    if values.iter().any(|&v| beyond(v, LINEAR_STEP_LIMIT)) {
        return Err(LINEAR_STEP_RANGE.to_string());
    }
    accumulate_rows(values, width);
    if values.iter().any(|&v| beyond(v, LINEAR_LIMIT)) {
        return Err(LINEAR_RANGE.to_string());
    }
    Ok(())
}

#[cfg(test)]
mod tests;
