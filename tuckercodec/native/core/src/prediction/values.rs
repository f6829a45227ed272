//! Predictor 2's columns of a qmat section straight from their byte planes to the dequantized
//! float64 matrix (`decode_matrix(...).values()` of `tuckercodec/format/qmat.py`) in one pass,
//! without the section's int64 integers: a block of columns at a time, the blocks shared
//! between threads (columns do not depend on each other, so the bits do not depend on them).
//! [`MeanPlan::restore_adaptive_values`] does the same for an adaptive stream (§6.14), whose
//! columns decode one after the other: a second thread restores each block of columns while
//! the next ones decode.

use std::cell::RefCell;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{mpsc, Mutex};

use super::{check_push, MeanPlan, PredictionError, MEAN_LIMIT, MEAN_RANGE, PLAIN_PUSH};
use crate::adaptive::{self, CodingOrder};
use crate::error::Broken;
use crate::streams::unzigzag;

/// Columns restored at once: a block's floats of a 10,000-vertex mesh stay in a core's
/// second-level cache.
pub const VALUE_BLOCK: usize = 8;

/// The most threads [`MeanPlan::restore_values`] starts.
pub const MAX_THREADS: usize = 8;

/// The threads worth starting for `blocks` blocks of work on this machine (at least 1).
pub fn thread_count(blocks: usize) -> usize {
    let available = std::thread::available_parallelism().map_or(1, |n| n.get());
    available.min(MAX_THREADS).min(blocks).max(1)
}

/// Where a block's residuals come from.
#[derive(Clone, Copy)]
enum Residuals<'r> {
    /// The stream's byte planes: `planes` planes of `count` bytes, the block's columns at
    /// their place in it.
    Planes {
        raw: &'r [u8],
        planes: usize,
        count: usize,
    },
    /// The block's columns of integers, one after the other.
    Integers(&'r [i64]),
}

impl MeanPlan {
    /// The (`height`, `steps.len()`) float64 matrix, row after row, into `out`: column c is
    /// predictor 2's restoration of the stream's c-th run of `height` integers (zigzagged in
    /// `planes` byte planes, `raw` holding exactly `steps.len() * height * planes` bytes),
    /// times `steps[c]` as float64, as `np.multiply(q, steps.astype(float64))` computes it.
    /// Column c is predicted with push `push[c]` (one per column, each `0..=MAX_PUSH`; 2 is
    /// today's predictor 2).
    ///
    /// Errors: a caller's error (sizes or pushes that do not fit together) or [`MEAN_RANGE`]
    /// when a restored value leaves +-`MEAN_LIMIT` (`out` is then left partly written).
    #[allow(clippy::too_many_arguments)] // the stream's parts, the output, threads, pushes
    pub fn restore_values(
        &self,
        raw: &[u8],
        planes: usize,
        height: usize,
        steps: &[f32],
        out: &mut [f64],
        threads: usize,
        push: &[u8],
    ) -> Result<(), PredictionError> {
        let width = steps.len();
        let count = width.checked_mul(height);
        if !(1..=8).contains(&planes)
            || count.and_then(|n| n.checked_mul(planes)) != Some(raw.len())
            || count != Some(out.len())
        {
            return Err(format!(
                "{} bytes of {planes} planes and {} values are not {width} columns of {height}",
                raw.len(),
                out.len()
            ));
        }
        check_push(push, width)?;
        if width == 0 {
            return Ok(());
        }
        if height < self.vertex_count || height == 0 {
            return Err(format!(
                "columns of {height} values, fewer than the {} the steps index",
                self.vertex_count
            ));
        }
        let count = width * height;
        let blocks = width.div_ceil(VALUE_BLOCK);
        let next = AtomicUsize::new(0);
        let output = Mutex::new(out);
        let worker = || -> Result<(), PredictionError> {
            let mut work = Vec::new();
            let mut scratch = Vec::new();
            let mut predictions = Vec::new();
            loop {
                let block = next.fetch_add(1, Ordering::Relaxed);
                if block >= blocks {
                    return Ok(());
                }
                let first = block * VALUE_BLOCK;
                let block_width = VALUE_BLOCK.min(width - first);
                let residuals = Residuals::Planes { raw, planes, count };
                self.block_values(
                    residuals,
                    height,
                    first,
                    &push[first..first + block_width],
                    &mut work,
                    &mut scratch,
                    &mut predictions,
                )?;
                let mut out = output.lock().unwrap_or_else(|e| e.into_inner());
                scale_into(
                    &mut out,
                    width,
                    first,
                    &work,
                    &steps[first..first + block_width],
                );
            }
        };
        let threads = threads.clamp(1, blocks);
        if threads == 1 {
            return worker();
        }
        std::thread::scope(|scope| {
            let handles: Vec<_> = (1..threads).map(|_| scope.spawn(worker)).collect();
            let mine = worker();
            // every thread's result, then the first error (all errors say the same)
            let theirs: Vec<_> = handles
                .into_iter()
                .map(|h| {
                    h.join()
                        .unwrap_or_else(|_| Err("a restoring thread failed".into()))
                })
                .collect();
            theirs.into_iter().fold(mine, |all, one| all.and(one))
        })
    }

    /// [`MeanPlan::restore_values`] of a section whose integers are an adaptive stream
    /// (§6.14, `payload` in `order`, which must have `height` rows): the (`height`,
    /// `steps.len()`) float64 matrix into `out`, the same floats as decoding the integers
    /// (`adaptive::decode_columns`), checking that each zigzags below 2**(8 `planes`)
    /// (`decode_within_planes`), restoring them (`restore_columns`) and multiplying by the
    /// steps. With `threads` of 2 or more, a second thread restores each block of columns as
    /// soon as it is decoded.
    ///
    /// Errors, in the reference's order: `Err` (R46) for a stream that is not exactly the
    /// coding of the integers, then for an integer outside the planes; `Ok(Err(..))` for a
    /// caller's error (sizes, pushes) or [`MEAN_RANGE`]. `out` is then left partly written.
    #[allow(clippy::too_many_arguments)] // the stream's parts, the output, threads, pushes
    pub fn restore_adaptive_values(
        &self,
        payload: &[u8],
        order: &CodingOrder,
        planes: usize,
        steps: &[f32],
        out: &mut [f64],
        threads: usize,
        push: &[u8],
    ) -> Result<Result<(), PredictionError>, Broken> {
        let (width, height) = (steps.len(), order.row_count());
        if !(1..=8).contains(&planes) || width.checked_mul(height) != Some(out.len()) {
            return Ok(Err(format!(
                "{} values of {planes} planes are not {width} columns of {height}",
                out.len()
            )));
        }
        if let Err(error) = check_push(push, width) {
            return Ok(Err(error));
        }
        if height < self.vertex_count || (height == 0 && width > 0) {
            return Ok(Err(format!(
                "columns of {height} values, fewer than the {} the steps index",
                self.vertex_count
            )));
        }
        let output = Mutex::new(out);
        let restorer = || BlockRestorer::new(self, planes, height, steps, push, &output);
        // the integers go through a few reused runs of columns, never the whole matrix's
        // array: no 8 bytes an integer allocated and first touched while the stream decodes
        let (decoded, outcome) = if threads < 2 {
            let mut mine = restorer();
            let spare = RefCell::new(Vec::new());
            let decoded = adaptive::decode_runs(
                payload,
                order,
                width,
                VALUE_BLOCK,
                || spare.take(),
                |first, run| {
                    mine.restore(first, &run);
                    spare.replace(run);
                },
            );
            (decoded, mine.outcome)
        } else {
            let (send, receive) = mpsc::channel::<(usize, Vec<i64>)>();
            // shared: once the stream is decoded, this thread restores what is left too
            let receive = Mutex::new(receive);
            let next = || receive.lock().ok().and_then(|r| r.recv().ok());
            let (give_back, given_back) = mpsc::channel::<Vec<i64>>();
            let (restorer, next) = (&restorer, &next);
            std::thread::scope(move |scope| {
                let restoring = scope.spawn(move || {
                    let mut theirs = restorer();
                    while let Some((first, run)) = next() {
                        theirs.restore(first, &run);
                        // the decoder may have finished: a run it no longer needs is dropped
                        let _ = give_back.send(run);
                    }
                    theirs.outcome
                });
                // a run the restorer has given back, else a new one: the decoder never waits
                let decoded = adaptive::decode_runs(
                    payload,
                    order,
                    width,
                    VALUE_BLOCK,
                    || given_back.try_recv().unwrap_or_default(),
                    |first, run| {
                        // the receiver ends only with the threads, which fail only on a bug
                        let _ = send.send((first, run));
                    },
                );
                drop(send);
                // the runs not restored yet, shared with the restorer rather than waited for
                // (it lags where it shares a processor with this thread or another program)
                let mut mine = restorer();
                if decoded.is_ok() {
                    while let Some((first, run)) = next() {
                        mine.restore(first, &run);
                    }
                }
                let theirs = restoring.join().unwrap_or_else(|_| Outcome {
                    outside_planes: false,
                    failed: Some("a restoring thread failed".into()),
                });
                (decoded, mine.outcome.and(theirs))
            })
        };
        decoded?;
        if outcome.outside_planes {
            return Err(Broken::new(
                adaptive::RULE,
                format!("an integer of the adaptive stream does not fit its {planes} planes"),
            ));
        }
        Ok(outcome.failed.map_or(Ok(()), Err))
    }

    /// Columns `first..first + push.len()` restored into `work` (row after row, the block's
    /// columns side by side) as exact integers in float64, checked against +-`MEAN_LIMIT`,
    /// column `first + c` with push `push[c]`.
    #[allow(clippy::too_many_arguments)]
    fn block_values(
        &self,
        residuals: Residuals<'_>,
        height: usize,
        first: usize,
        push: &[u8],
        work: &mut Vec<f64>,
        scratch: &mut Vec<u64>,
        predictions: &mut Vec<f64>,
    ) -> Result<(), PredictionError> {
        let block_width = push.len();
        work.clear();
        work.resize(height * block_width, 0.0);
        match residuals {
            Residuals::Planes { raw, planes, count } => {
                scratch.clear();
                scratch.resize(height, 0);
                for c in 0..block_width {
                    let start = (first + c) * height;
                    scratch.fill(0);
                    for plane in 0..planes {
                        let bytes = &raw[plane * count + start..plane * count + start + height];
                        for (value, &byte) in scratch.iter_mut().zip(bytes) {
                            *value |= u64::from(byte) << (8 * plane);
                        }
                    }
                    for (v, &value) in scratch.iter().enumerate() {
                        work[v * block_width + c] = unzigzag(value) as f64;
                    }
                }
            }
            Residuals::Integers(columns) => {
                for (c, column) in columns.chunks_exact(height).enumerate() {
                    for (v, &value) in column.iter().enumerate() {
                        work[v * block_width + c] = value as f64;
                    }
                }
            }
        }
        let exact = self.float_is_exact(push);
        if exact && block_width == VALUE_BLOCK {
            let mut factors = [0.0f64; VALUE_BLOCK];
            for (factor, &a) in factors.iter_mut().zip(push) {
                *factor = f64::from(a);
            }
            if push.iter().all(|&a| a == PLAIN_PUSH) {
                self.restore_block_fixed::<VALUE_BLOCK, false>(work, &factors, predictions)
            } else {
                self.restore_block_fixed::<VALUE_BLOCK, true>(work, &factors, predictions)
            }
        } else if exact {
            self.restore_block_float(work, block_width, push, predictions)
        } else {
            // a crafted mesh: the int64 steps of `mean_accumulate`, a column at a time
            let mut column = vec![0i64; height];
            for (c, &a) in push.iter().enumerate() {
                for (v, slot) in column.iter_mut().enumerate() {
                    *slot = work[v * block_width + c] as i64;
                }
                self.restore_column_integer(&mut column, a)?;
                for (v, &value) in column.iter().enumerate() {
                    work[v * block_width + c] = value as f64;
                }
            }
            Ok(())
        }
    }

    /// [`MeanPlan::restore_block_float`] for a block of exactly `W` columns: the same sums in
    /// the same order, with the width known to the compiler (the sums stay in registers and
    /// each source's `W` values are added without a loop over a slice of unknown length).
    /// `PUSHED`: the columns' pushes are `factors` (the sums of `float_predictions_pushed`);
    /// otherwise every push is 2 and `factors` is unread (today's sums, today's speed).
    fn restore_block_fixed<const W: usize, const PUSHED: bool>(
        &self,
        work: &mut [f64],
        factors: &[f64; W],
        predictions: &mut Vec<f64>,
    ) -> Result<(), PredictionError> {
        for span in self.step_ends.windows(2) {
            // a step's predictions all read the values before the step
            predictions.clear();
            predictions.resize((span[1] - span[0]) * W, 0.0f64);
            for (j, out) in (span[0]..span[1]).zip(predictions.chunks_exact_mut(W)) {
                let count = self.counts[j] as f64;
                let (start, stop) = (self.pointers[j], self.pointers[j + 1]);
                let mut sums;
                let divisor;
                if PUSHED {
                    // V + 3c: exact, as in `float_predictions_pushed`
                    sums = [3.0 * count; W];
                    for ((&column, &once), &step) in self.columns[start..stop]
                        .iter()
                        .zip(&self.source_weights[start..stop])
                        .zip(&self.step_weights[start..stop])
                    {
                        let base = column as usize * W;
                        let values: &[f64; W] = work[base..base + W]
                            .try_into()
                            .expect("a slice of W values");
                        let six = 6.0 * once;
                        for ((sum, &value), &a) in sums.iter_mut().zip(values).zip(factors) {
                            *sum += (six + a * step) * value;
                        }
                    }
                    divisor = 6.0 * count;
                } else {
                    sums = [1.5 * count; W];
                    for (&column, &weight) in self.columns[start..stop]
                        .iter()
                        .zip(&self.weights[start..stop])
                    {
                        let base = column as usize * W;
                        let values: &[f64; W] = work[base..base + W]
                            .try_into()
                            .expect("a slice of W values");
                        for (sum, &value) in sums.iter_mut().zip(values) {
                            *sum += weight * value;
                        }
                    }
                    divisor = 3.0 * count;
                }
                for (slot, &sum) in out.iter_mut().zip(&sums) {
                    *slot = super::exact_floor(sum / divisor);
                }
            }
            for (j, sums) in (span[0]..span[1]).zip(predictions.chunks_exact(W)) {
                let base = self.rows[j] as usize * W;
                for (value, &prediction) in work[base..base + W].iter_mut().zip(sums) {
                    *value += prediction;
                }
            }
        }
        let limit = MEAN_LIMIT as f64;
        // the comparison fails for NaN too, as the Python's min and max do
        if !work.iter().all(|&v| v >= -limit && v <= limit) {
            return Err(MEAN_RANGE.to_string());
        }
        Ok(())
    }

    /// The float steps of [`MeanPlan::restore_columns`] on one block (`work` row after row,
    /// `width` columns, column c with push `push[c]`), then the block's range check.
    pub(super) fn restore_block_float(
        &self,
        work: &mut [f64],
        width: usize,
        push: &[u8],
        predictions: &mut Vec<f64>,
    ) -> Result<(), PredictionError> {
        let plain = push.iter().all(|&a| a == PLAIN_PUSH);
        let factors: Vec<f64> = push.iter().map(|&a| f64::from(a)).collect();
        for span in self.step_ends.windows(2) {
            // a step's predictions all read the values before the step
            predictions.clear();
            predictions.resize((span[1] - span[0]) * width, 0.0f64);
            for (j, sums) in (span[0]..span[1]).zip(predictions.chunks_exact_mut(width)) {
                if plain {
                    self.float_predictions(j, work, width, sums);
                } else {
                    self.float_predictions_pushed(j, work, width, &factors, sums);
                }
            }
            for (j, sums) in (span[0]..span[1]).zip(predictions.chunks_exact(width)) {
                let base = self.rows[j] as usize * width;
                for (value, &prediction) in work[base..base + width].iter_mut().zip(sums) {
                    *value += prediction;
                }
            }
        }
        let limit = MEAN_LIMIT as f64;
        // the comparison fails for NaN too, as the Python's min and max do
        if !work.iter().all(|&v| v >= -limit && v <= limit) {
            return Err(MEAN_RANGE.to_string());
        }
        Ok(())
    }
}

/// What went wrong in [`MeanPlan::restore_adaptive_values`]'s blocks so far.
#[derive(Default)]
struct Outcome {
    /// An integer outside the planes (R46, before any error of the restoring).
    outside_planes: bool,
    /// The first block's error of restoring.
    failed: Option<PredictionError>,
}

impl Outcome {
    /// What went wrong in either's blocks (every error of restoring says the same).
    fn and(self, other: Outcome) -> Outcome {
        Outcome {
            outside_planes: self.outside_planes || other.outside_planes,
            failed: self.failed.or(other.failed),
        }
    }
}

/// What a block of [`MeanPlan::restore_adaptive_values`] needs, and what went wrong so far: a
/// block outside the planes or failing to restore stops the restoring (not the planes checks,
/// whose error comes first).
struct BlockRestorer<'p, 'm, 'o> {
    plan: &'p MeanPlan,
    planes: usize,
    height: usize,
    steps: &'p [f32],
    push: &'p [u8],
    /// The output, which the threads restoring blocks share.
    out: &'m Mutex<&'o mut [f64]>,
    outcome: Outcome,
    /// `block_values`' work, scratch and predictions.
    buffers: (Vec<f64>, Vec<u64>, Vec<f64>),
}

impl<'p, 'm, 'o> BlockRestorer<'p, 'm, 'o> {
    fn new(
        plan: &'p MeanPlan,
        planes: usize,
        height: usize,
        steps: &'p [f32],
        push: &'p [u8],
        out: &'m Mutex<&'o mut [f64]>,
    ) -> Self {
        BlockRestorer {
            plan,
            planes,
            height,
            steps,
            push,
            out,
            outcome: Outcome::default(),
            buffers: Default::default(),
        }
    }

    /// Columns `first..` (`block`, whole columns) checked against the planes, restored and
    /// written to their place in `out`, times their steps.
    fn restore(&mut self, first: usize, block: &[i64]) {
        if self.planes < 8 {
            // zigzag below 2**(8P): -limit <= x < limit (every int64 does for 8 planes)
            let limit = 1i64 << (8 * self.planes - 1);
            if block.iter().any(|&x| x < -limit || x >= limit) {
                self.outcome.outside_planes = true;
            }
        }
        if self.outcome.outside_planes || self.outcome.failed.is_some() || self.height == 0 {
            return;
        }
        let block_width = block.len() / self.height;
        let (work, scratch, predictions) = &mut self.buffers;
        if let Err(error) = self.plan.block_values(
            Residuals::Integers(block),
            self.height,
            first,
            &self.push[first..first + block_width],
            work,
            scratch,
            predictions,
        ) {
            self.outcome.failed = Some(error);
            return;
        }
        let width = self.steps.len();
        let steps = &self.steps[first..first + block_width];
        let mut out = self.out.lock().unwrap_or_else(|e| e.into_inner());
        scale_into(&mut out, width, first, work, steps);
    }
}

/// A block of restored columns (`work`, row-major, `steps.len()` wide) scaled by their steps
/// into columns `first..` of `out` (row-major, `width` wide).
fn scale_into(out: &mut [f64], width: usize, first: usize, work: &[f64], steps: &[f32]) {
    let block_width = steps.len();
    for (row, values) in out
        .chunks_exact_mut(width)
        .zip(work.chunks_exact(block_width))
    {
        for ((slot, &value), &step) in row[first..first + block_width]
            .iter_mut()
            .zip(values)
            .zip(steps)
        {
            // an exact integer: through int64 as numpy's product of q reads it
            *slot = (value as i64) as f64 * f64::from(step);
        }
    }
}
