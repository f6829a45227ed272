//! The encoder's choice of predictor 2's push (`qmat._pushed_mean`, format 1.6): the price of
//! every push's residuals for every column, in one pass over the mesh's steps.
//!
//! The reference forms each push's residuals (a matrix as large as U1, ten times) and prices
//! each column with `qmat._cost`, the mean of `log2(1 + 2|r|)` over its rows. Here each row's
//! two sums that every push shares are formed once (a push a predicts from `6 S + a D`, S the
//! sum of the sources, D the sum of the sources minus their anchors), laid out by vertex, and
//! each push's residuals are priced and summed as they are made, in one pass down the rows. The floats that decide are numpy's to the bit: each
//! `log2` is read from a table numpy made (`bits`), and each column's sum is taken in the order
//! numpy takes it in `mean(axis=0)`: row after row where the column shares its block of the
//! cost with other columns, numpy's pairwise sum where it is alone in it.

use super::{MeanPlan, PredictionError, COLUMN_BLOCK, MAX_PUSH};

/// The pushes a column may carry, `0..=MAX_PUSH`: the width of [`MeanPlan::push_costs`]'s rows.
pub const PUSH_COUNT: usize = MAX_PUSH as usize + 1;

/// numpy's unrolled block of its pairwise sum (`PW_BLOCKSIZE`).
const PAIRWISE_BLOCK: usize = 128;

/// The sum of `values` as numpy sums a contiguous float64 array along its only axis
/// (`pairwise_sum` in numpy's loops, the reduction starting from 0): below 8 values one after
/// the other; up to 128 in eight interleaved partial sums added in a tree, then the rest;
/// above, the two halves (the first a multiple of 8) summed so and added.
pub fn numpy_pairwise_sum(values: &[f64]) -> f64 {
    0.0 + pairwise(values)
}

fn pairwise(values: &[f64]) -> f64 {
    let n = values.len();
    if n < 8 {
        let mut sum = 0.0;
        for &value in values {
            sum += value;
        }
        sum
    } else if n <= PAIRWISE_BLOCK {
        let mut partial = [0.0f64; 8];
        partial.copy_from_slice(&values[..8]);
        let whole = n - n % 8;
        for chunk in values[8..whole].chunks_exact(8) {
            for (sum, &value) in partial.iter_mut().zip(chunk) {
                *sum += value;
            }
        }
        let mut sum = ((partial[0] + partial[1]) + (partial[2] + partial[3]))
            + ((partial[4] + partial[5]) + (partial[6] + partial[7]));
        for &value in &values[whole..] {
            sum += value;
        }
        sum
    } else {
        let mut half = n / 2;
        half -= half % 8;
        pairwise(&values[..half]) + pairwise(&values[half..])
    }
}

impl MeanPlan {
    /// `qmat._cost` of the predictor-2 residuals of each column of the (height, `width`) int64
    /// matrix `values` (row after row) under each push: (`width`, [`PUSH_COUNT`]) floats, row
    /// c holding column c's price under push 0, 1, ... 9. The price is the mean over the rows
    /// of `bits[|r|]` (`bits[m]` numpy's `log2(1 + 2m)`); the columns are priced in blocks of
    /// `block` as `_cost` prices them, so that a column alone in its block is summed pairwise.
    /// A column with a residual of `bits.len()` or more under some push is priced NaN under
    /// every push: the caller prices it itself. `None` if a value leaves +-`MEAN_LIMIT`
    /// (predictor 2 cannot hold the matrix), as [`MeanPlan::residuals`].
    ///
    /// Errors: a matrix with fewer rows than the steps index, or a `block` of 0.
    pub fn push_costs(
        &self,
        values: &[i64],
        width: usize,
        bits: &[f64],
        block: usize,
    ) -> Result<Option<Vec<f64>>, PredictionError> {
        if block == 0 {
            return Err("columns are priced in blocks of at least one".to_string());
        }
        if width == 0 {
            return Ok(Some(Vec::new()));
        }
        let Some(height) = self.matrix_height(values, width)? else {
            return Ok(None);
        };
        // numpy sums a block of one column pairwise: only the last column can be alone
        let alone = (width % block == 1).then_some(width - 1);
        let bits = Prices::new(bits);
        let mut out = vec![0.0f64; width * PUSH_COUNT];
        let mut work = PushWork::new(self, height);
        for first in (0..width).step_by(COLUMN_BLOCK) {
            let group = COLUMN_BLOCK.min(width - first);
            work.load(values, width, first, group);
            let lone = alone.and_then(|c| c.checked_sub(first));
            if self.exact_in_float_pushed {
                self.shared_sums(&mut work);
            }
            for push in 0..=MAX_PUSH {
                if !self.exact_in_float_pushed {
                    self.integer_predictions(&mut work, push);
                }
                let prices = work.column_prices(push, &bits, lone);
                for (c, &price) in prices.iter().enumerate() {
                    out[(first + c) * PUSH_COUNT + usize::from(push)] = price;
                }
            }
        }
        // a column priced NaN under one push is priced NaN under all
        for row in out.chunks_exact_mut(PUSH_COUNT) {
            if row.iter().any(|p| p.is_nan()) {
                row.fill(f64::NAN);
            }
        }
        Ok(Some(out))
    }

    /// Each predicted row's sums shared by every push, for the group's columns, at the row's
    /// vertex: `6 S + 3c`, S the sum of the row's sources, and D, the sum of its sources minus
    /// its anchors (integers, exact in float64 below `PUSHED_FLOAT_SOURCES` sources a row). A
    /// root's stay 0: with its divisor 1, it is predicted by 0.
    fn shared_sums(&self, work: &mut PushWork) {
        let group = work.group;
        work.shared.clear();
        work.shared.resize(work.own.len(), 0.0);
        work.steps.clear();
        work.steps.resize(work.own.len(), 0.0);
        for (j, &row) in self.rows.iter().enumerate() {
            let at = row as usize * group;
            let shared = &mut work.shared[at..at + group];
            let steps = &mut work.steps[at..at + group];
            let (start, stop) = (self.pointers[j], self.pointers[j + 1]);
            for ((&column, &once), &step) in self.columns[start..stop]
                .iter()
                .zip(&self.source_weights[start..stop])
                .zip(&self.step_weights[start..stop])
            {
                let base = column as usize * group;
                for ((s, d), &value) in shared
                    .iter_mut()
                    .zip(steps.iter_mut())
                    .zip(&work.floats[base..base + group])
                {
                    *s += once * value;
                    *d += step * value;
                }
            }
            let offset = 3.0 * self.counts[j] as f64;
            for s in shared.iter_mut() {
                *s = 6.0 * *s + offset;
            }
        }
    }

    /// Each predicted row's prediction under `push` in integers, at the row's vertex (a
    /// root's 0), for a crafted mesh whose rows have too many sources for float64.
    fn integer_predictions(&self, work: &mut PushWork, push: u8) {
        let group = work.group;
        work.predictions.clear();
        work.predictions.resize(work.own.len(), 0);
        for c in 0..group {
            work.column.clear();
            work.column
                .extend(work.own.iter().skip(c).step_by(group).copied());
            for (j, &row) in self.rows.iter().enumerate() {
                work.predictions[row as usize * group + c] =
                    self.integer_prediction_pushed(j, &work.column, push);
            }
        }
    }
}

/// The table of prices, `bits[|r|]`, with NaN after its end for every larger |r|.
struct Prices(Vec<f64>);

impl Prices {
    fn new(bits: &[f64]) -> Self {
        Prices(bits.iter().copied().chain([f64::NAN]).collect())
    }

    /// The price of a residual, without a branch on its size.
    #[inline]
    fn price(&self, residual: i64) -> f64 {
        let last = self.0.len() - 1;
        let m = residual.unsigned_abs().min(last as u64) as usize;
        self.0[m]
    }
}

/// The buffers of [`MeanPlan::push_costs`] for a group of columns, each laid out by vertex
/// (a vertex's columns side by side), reused from group to group.
struct PushWork {
    group: usize,
    /// Each vertex's divisor 6c, c its row's count of sources; a root's 1.
    divisors: Vec<f64>,
    /// The group's values, as integers and as floats.
    own: Vec<i64>,
    floats: Vec<f64>,
    /// The shared sums, `6 S + 3c` and D (float64), or the predictions (int64, a crafted mesh).
    shared: Vec<f64>,
    steps: Vec<f64>,
    predictions: Vec<i64>,
    /// Each column's sum, one column's values for the integer path, one's prices to sum
    /// pairwise.
    sums: Vec<f64>,
    column: Vec<i64>,
    lone: Vec<f64>,
}

impl PushWork {
    fn new(plan: &MeanPlan, height: usize) -> Self {
        let mut divisors = vec![1.0; height];
        for (&row, &count) in plan.rows.iter().zip(&plan.counts) {
            divisors[row as usize] = 6.0 * count as f64;
        }
        PushWork {
            group: 0,
            divisors,
            own: Vec::new(),
            floats: Vec::new(),
            shared: Vec::new(),
            steps: Vec::new(),
            predictions: Vec::new(),
            sums: Vec::new(),
            column: Vec::new(),
            lone: Vec::new(),
        }
    }

    /// Takes columns `first..first + group` of the (height, `width`) matrix `values`.
    fn load(&mut self, values: &[i64], width: usize, first: usize, group: usize) {
        self.group = group;
        self.own.clear();
        self.own.extend(
            values
                .chunks_exact(width)
                .flat_map(|row| row[first..first + group].iter().copied()),
        );
        self.floats.clear();
        self.floats.extend(self.own.iter().map(|&v| v as f64));
    }

    /// The mean of each column's prices under `push`, summed vertex after vertex as numpy
    /// sums a block of columns, or pairwise for the column `lone` in its block (NaN: a
    /// residual beyond the table). The predictions are made here from the shared sums, or
    /// read from `predictions` (a crafted mesh's, when `shared` is empty).
    fn column_prices(&mut self, push: u8, bits: &Prices, lone: Option<usize>) -> &[f64] {
        let group = self.group;
        let height = self.divisors.len();
        let lone = lone.filter(|&c| c < group);
        self.sums.clear();
        self.sums.resize(group, 0.0);
        self.lone.clear();
        let a = f64::from(push);
        let rows = self.own.chunks_exact(group).zip(&self.divisors);
        if self.shared.is_empty() {
            for ((own, _), predictions) in rows.zip(self.predictions.chunks_exact(group)) {
                for (c, (&value, &prediction)) in own.iter().zip(predictions).enumerate() {
                    let price = bits.price(value.wrapping_sub(prediction));
                    self.sums[c] += price;
                    if lone == Some(c) {
                        self.lone.push(price);
                    }
                }
            }
        } else {
            let sums = self
                .shared
                .chunks_exact(group)
                .zip(self.steps.chunks_exact(group));
            for ((own, &divisor), (shared, steps)) in rows.zip(sums) {
                let terms = own.iter().zip(shared).zip(steps);
                for ((sum, ((&value, &s), &d)), c) in self.sums.iter_mut().zip(terms).zip(0..) {
                    // floor((6 S + 3c + a D) / 6c): the numerator an integer below 2**53, so
                    // exact, and its one division floored right (as in the restore); within
                    // 2**36 (the values within MEAN_LIMIT), so truncated and stepped down
                    // where that went up, a negative quotient that is no integer
                    let quotient = (s + a * d) / divisor;
                    let truncated = quotient as i64;
                    let prediction = truncated - i64::from(truncated as f64 > quotient);
                    let price = bits.price(value.wrapping_sub(prediction));
                    *sum += price;
                    if lone == Some(c) {
                        self.lone.push(price);
                    }
                }
            }
        }
        if let Some(c) = lone {
            self.sums[c] = numpy_pairwise_sum(&self.lone);
        }
        for sum in &mut self.sums {
            *sum /= height as f64;
        }
        &self.sums
    }
}
