//! `rdo._mean_choice`: U1's columns under predictor 2 rounded down or up against predictor 2's
//! own prediction, in the decoder's order (spec section 6.2), the same integers as the Python.
//!
//! Each entry's floats are those of the reference, with the same operations in the same order;
//! predictor 2's sums are int64 with wrapping, as numpy's are, so regrouping them changes no
//! integer. Columns are independent: one row's columns are formed side by side, so that each
//! source row is read once per row it serves.

use super::{check_shape, fail, EncoderError};
use crate::prediction::exact_floor;

/// What `rdo._mean_choice` needs besides the values and their steps: predictor 2's steps (the
/// arrays of `MeanSteps`), each column's push, the bits of each residual value and the rate
/// weight.
pub struct MeanChoiceModel<'a> {
    /// Every row of depth 1 or more, by step (`MeanSteps.rows`); the others are roots.
    pub rows: &'a [i64],
    /// Step s chooses `rows[step_ends[s]..step_ends[s + 1]]`.
    pub step_ends: &'a [i64],
    /// Row j's sources are `sources[source_ends[j]..source_ends[j + 1]]` (at least one), each
    /// with its anchor in `anchors`.
    pub sources: &'a [i64],
    pub anchors: &'a [i64],
    pub source_ends: &'a [i64],
    /// Each column's push a: predictor 2 sums `(6 + a) q[w] - a q[anchor(w)]`.
    pub push: &'a [i64],
    /// (cols, 2 half + 1) bits of each residual `-half..=half`, row-major
    /// (`rdo._value_table`).
    pub table: &'a [f64],
    pub half: usize,
    pub lam: f64,
}

/// A list of indices, each checked to be one of `bound` rows.
fn row_indices(values: &[i64], bound: usize, what: &str) -> Result<Vec<usize>, EncoderError> {
    values
        .iter()
        .map(|&v| match usize::try_from(v) {
            Ok(i) if i < bound => Ok(i),
            _ => fail(format!("{what} {v} is not one of the {bound} rows")),
        })
        .collect()
}

/// Ends that rise from 0 to `total` (strictly if `strict`), as indices.
fn checked_ends(
    ends: &[i64],
    total: usize,
    strict: bool,
    what: &str,
) -> Result<Vec<usize>, EncoderError> {
    let ends = ends
        .iter()
        .map(|&e| usize::try_from(e).map_err(|_| EncoderError(format!("{what}: {e}"))))
        .collect::<Result<Vec<_>, _>>()?;
    let rising = ends
        .windows(2)
        .all(|w| if strict { w[0] < w[1] } else { w[0] <= w[1] });
    if ends.first() != Some(&0) || ends.last() != Some(&total) || !rising {
        return fail(format!("{what} must rise from 0 to {total}"));
    }
    Ok(ends)
}

/// 2**63, exact in float64.
const INT64_BOUND: f64 = (1u64 << 63) as f64;

/// `numerator.div_euclid(divisor)` (numpy's floor_divide) for a positive `divisor` below
/// 2**53, `divisor_float` the same number: in float64 below 2**52, where the floor of the one
/// correctly rounded quotient is the exact floor (a quotient that is no integer lies at least
/// 1 / divisor from one, more than its rounding error), so without an integer division.
#[inline(always)]
fn floor_divide(numerator: i64, divisor: i64, divisor_float: f64) -> i64 {
    if numerator.unsigned_abs() < 1 << 52 {
        exact_floor(numerator as f64 / divisor_float) as i64
    } else {
        numerator.div_euclid(divisor)
    }
}

/// One entry's choice: `rdo._mean_choice`'s `choose`, for the value `value`, its column's
/// step and the prediction of its row. `table` is the column's row of the value table and
/// `half` its half width. An entry whose floor is no int64 is an error.
#[inline(always)]
fn choose(
    value: f64,
    step: f64,
    prediction: i64,
    table: &[f64],
    half: i64,
    lam: f64,
) -> Result<i64, EncoderError> {
    let scaled = value / step;
    // floor() to the bit but a zero's sign, which changes nothing below, without libm's call
    let low = exact_floor(scaled);
    // the range of int64 (NaN outside it): numpy's cast would not be the same beyond
    if !(-INT64_BOUND..INT64_BOUND).contains(&low) {
        return fail(format!("{value} / {step} has no int64 floor"));
    }
    let error_low = (scaled - low) * (scaled - low);
    let gap = low + 1.0 - scaled;
    let error_high = gap * gap;
    let below = low as i64;
    // clip(below - prediction, -half, half - 1) + half: in 0..2 half, so index + 1 is in the row
    let index = (below.wrapping_sub(prediction).clamp(-half, half - 1) + half) as usize;
    let cost_low = error_low + lam * table[index];
    let cost_high = error_high + lam * table[index + 1];
    // ties go to the nearer integer, as in the reference
    let high = cost_high < cost_low || (cost_high == cost_low && error_high < error_low);
    Ok(below.wrapping_add(i64::from(high)))
}

/// `rdo._mean_choice`: each entry of `values / steps` ((rows, cols), row-major) rounded down
/// or up, whichever costs less in `error + lam * bits(residual)` against predictor 2's
/// prediction from the integers chosen before it (ties to the nearer integer): the roots
/// (rows not in `model.rows`) predicted by 0, then each step's rows predicted by
/// `floor((2V + 6c) / 12c)`, V the sum over the row's c sources w of
/// `(6 + a) q[w] - a q[anchor(w)]`.
///
/// Errors: shapes that disagree, indices out of range, a row chosen twice, a source or anchor
/// not chosen in an earlier step (the decoder could not restore the row), or a value whose
/// floor is no int64.
pub fn rdo_mean_choice(
    values: &[f64],
    rows: usize,
    cols: usize,
    steps: &[f64],
    model: &MeanChoiceModel<'_>,
) -> Result<Vec<i64>, EncoderError> {
    check_shape(values.len(), rows, cols, "values")?;
    if steps.len() != cols || model.push.len() != cols {
        return fail(format!("steps and pushes must be {cols} each"));
    }
    let half = match i64::try_from(model.half) {
        Ok(h) if (1..i64::MAX / 4).contains(&h) => h,
        _ => return fail(format!("a value table of half width {}", model.half)),
    };
    let width = 2 * model.half + 1;
    check_shape(model.table.len(), cols, width, "the value table")?;
    let mean_rows = row_indices(model.rows, rows, "the step row")?;
    let step_ends = checked_ends(model.step_ends, mean_rows.len(), false, "step_ends")?;
    if model.sources.len() != model.anchors.len() {
        return fail("sources and anchors differ in length");
    }
    let sources = row_indices(model.sources, rows, "the source")?;
    let anchors = row_indices(model.anchors, rows, "the anchor")?;
    // every row has a source: the divisor 12c is never 0
    let source_ends = checked_ends(model.source_ends, sources.len(), true, "source_ends")?;
    if source_ends.len() != mean_rows.len() + 1 {
        return fail("source_ends must have one entry per step row and one more");
    }

    let mut q = vec![0i64; values.len()];
    let mut done = vec![false; rows];
    for &row in &mean_rows {
        if std::mem::replace(&mut done[row], true) {
            return fail(format!("the row {row} is chosen twice"));
        }
    }
    // the roots (done is now true exactly for the step rows), predicted by 0
    for (row, flag) in done.iter_mut().enumerate() {
        *flag = !*flag;
        if *flag {
            for (col, &step) in steps.iter().enumerate() {
                let at = row * cols + col;
                let table = &model.table[col * width..(col + 1) * width];
                q[at] = choose(values[at], step, 0, table, half, model.lam)?;
            }
        }
    }

    let source_weight: Vec<i64> = model.push.iter().map(|&a| a.wrapping_add(6)).collect();
    let mut total = vec![0i64; cols];
    for step in step_ends.windows(2) {
        let step_rows = &mean_rows[step[0]..step[1]];
        for (j, &row) in (step[0]..step[1]).zip(step_rows) {
            total.fill(0);
            let span = source_ends[j]..source_ends[j + 1];
            for (&w, &anchor) in sources[span.clone()].iter().zip(&anchors[span.clone()]) {
                // rows of this step are not done yet: each row reads only earlier steps
                if !done[w] || !done[anchor] {
                    return fail(format!("row {row} reads a row not chosen before its step"));
                }
                let source_row = &q[w * cols..(w + 1) * cols];
                let anchor_row = &q[anchor * cols..(anchor + 1) * cols];
                for col in 0..cols {
                    let term = source_weight[col]
                        .wrapping_mul(source_row[col])
                        .wrapping_sub(model.push[col].wrapping_mul(anchor_row[col]));
                    total[col] = total[col].wrapping_add(term);
                }
            }
            let (offset, divisor) = match i64::try_from(span.len()).map(|c| (c, c.checked_mul(12)))
            {
                Ok((count, Some(divisor))) if divisor < 1 << 53 => (6 * count, divisor),
                _ => return fail(format!("row {row} has too many sources")),
            };
            let divisor_float = divisor as f64;
            for col in 0..cols {
                // np.floor_divide by a positive divisor: Euclidean division
                let numerator = total[col].wrapping_mul(2).wrapping_add(offset);
                let prediction = floor_divide(numerator, divisor, divisor_float);
                let at = row * cols + col;
                let table = &model.table[col * width..(col + 1) * width];
                q[at] = choose(values[at], steps[col], prediction, table, half, model.lam)?;
            }
        }
        for &row in step_rows {
            done[row] = true;
        }
    }
    Ok(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan: row 0 a root, rows 1 and 2 in step 0 (sourced by 0), row 3 in step 1 (by 1, 2).
    fn fan<'a>(push: &'a [i64], table: &'a [f64], half: usize, lam: f64) -> MeanChoiceModel<'a> {
        MeanChoiceModel {
            rows: &[1, 2, 3],
            step_ends: &[0, 2, 2, 3],
            sources: &[0, 0, 1, 2],
            anchors: &[0, 0, 0, 0],
            source_ends: &[0, 1, 2, 4],
            push,
            table,
            half,
            lam,
        }
    }

    #[test]
    fn floor_divide_is_euclidean_division() {
        let divisors = [1i64, 6, 12, 36, 12 * 1_000_003];
        let mut numerators = vec![0i64, 1, -1, 5, -5, 6, -6, 7, -7, i64::MAX, i64::MIN];
        for shift in [20, 40, 51, 52, 53, 62] {
            for delta in [-13i64, -1, 0, 1, 13] {
                numerators.push((1i64 << shift) + delta);
                numerators.push(-(1i64 << shift) + delta);
            }
        }
        for &d in &divisors {
            for k in [3i64, 1 << 20, (1 << 52) / d] {
                // multiples of the divisor and their neighbours, where a rounding shows
                numerators.extend([k * d - 1, k * d, k * d + 1, -k * d - 1, -k * d, -k * d + 1]);
            }
        }
        for &d in &divisors {
            for &n in &numerators {
                assert_eq!(floor_divide(n, d, d as f64), n.div_euclid(d), "{n} / {d}");
            }
        }
    }

    #[test]
    fn no_rate_is_nearest_rounding() {
        let values = [0.4, 1.6, -0.4, 2.5, -2.5, 7.49, 3.51, -0.5];
        let table = vec![1.0; 2 * 9];
        let model = fan(&[2, 0], &table, 4, 0.0);
        let q = rdo_mean_choice(&values, 4, 2, &[1.0, 1.0], &model).unwrap();
        // a tie (x.5) with equal errors keeps the floor, as the reference's rule does
        assert_eq!(q, vec![0, 2, 0, 2, -3, 7, 4, -1]);
    }

    #[test]
    fn a_cheap_residual_wins_over_a_nearer_integer() {
        // bits: residual 0 costs nothing, anything else 10 bits; the root's 0.6 stays 1 when
        // the rate is cheap and goes to 0 (residual 0 against prediction 0) when it is dear
        let half = 3;
        let mut table = vec![10.0; 2 * half + 1];
        table[half] = 0.0;
        let model = MeanChoiceModel {
            rows: &[1],
            step_ends: &[0, 1],
            sources: &[0],
            anchors: &[0],
            source_ends: &[0, 1],
            push: &[0],
            table: &table,
            half,
            lam: 0.0,
        };
        let values = [0.6, 0.45];
        assert_eq!(
            rdo_mean_choice(&values, 2, 1, &[1.0], &model).unwrap(),
            vec![1, 0]
        );
        let dear = MeanChoiceModel { lam: 1.0, ..model };
        // row 1 is predicted by floor((2 * 6 * 0 + 6) / 12) = 0 and stays 0
        assert_eq!(
            rdo_mean_choice(&values, 2, 1, &[1.0], &dear).unwrap(),
            vec![0, 0]
        );
        // with the root at 1 (value 1.2), row 1 is predicted by floor((12 + 6) / 12) = 1:
        // 0.45 goes up to its prediction
        assert_eq!(
            rdo_mean_choice(&[1.2, 0.45], 2, 1, &[1.0], &dear).unwrap(),
            vec![1, 1]
        );
    }

    #[test]
    fn predictions_follow_the_push() {
        // residual 0 is free and any other dear: an entry goes to the prediction when it is its
        // floor or its ceiling. Rows 0..3 are integers (nearest, error 0, never the
        // prediction); row 3 has sources 1 and 2 anchored at 0: V = (6 + a)(3 + 5) - 2a = 48 + 6a
        // and c = 2, so its prediction is floor((2V + 12) / 24) = 4 + (a + 1) / 2, and its value
        // 0.7 under that goes up to it (one off either way, it would stay at the floor).
        let half = 64;
        let mut table = vec![10.0; 2 * half + 1];
        table[half] = 0.0;
        for a in 0..10 {
            let prediction = 4 + (a + 1) / 2;
            let values = [1.0, 3.0, 5.0, prediction as f64 - 0.7];
            let push = [a];
            let model = fan(&push, &table, half, 5.0);
            let q = rdo_mean_choice(&values, 4, 1, &[1.0], &model).unwrap();
            assert_eq!(q, vec![1, 3, 5, prediction], "push {a}");
        }
    }

    #[test]
    fn bad_arguments_are_errors() {
        let table = vec![0.0; 9];
        let values = [0.0; 4];
        let ok = fan(&[2], &table, 4, 0.1);
        assert!(rdo_mean_choice(&values, 4, 1, &[1.0], &ok).is_ok());
        let bad_half = fan(&[2], &table, 3, 0.1);
        assert!(rdo_mean_choice(&values, 4, 1, &[1.0], &bad_half).is_err());
        let too_few = MeanChoiceModel {
            source_ends: &[0, 1, 2],
            ..fan(&[2], &table, 4, 0.1)
        };
        assert!(rdo_mean_choice(&values, 4, 1, &[1.0], &too_few).is_err());
        let same_step = MeanChoiceModel {
            step_ends: &[0, 3],
            ..fan(&[2], &table, 4, 0.1)
        };
        let error = rdo_mean_choice(&values, 4, 1, &[1.0], &same_step).unwrap_err();
        assert!(error.0.contains("not chosen before"), "{error}");
        let no_sources = MeanChoiceModel {
            source_ends: &[0, 0, 2, 4],
            ..fan(&[2], &table, 4, 0.1)
        };
        assert!(rdo_mean_choice(&values, 4, 1, &[1.0], &no_sources).is_err());
        let twice = MeanChoiceModel {
            rows: &[1, 1, 3],
            ..fan(&[2], &table, 4, 0.1)
        };
        assert!(rdo_mean_choice(&values, 4, 1, &[1.0], &twice).is_err());
        let outside = MeanChoiceModel {
            sources: &[0, 0, 1, 9],
            ..fan(&[2], &table, 4, 0.1)
        };
        assert!(rdo_mean_choice(&values, 4, 1, &[1.0], &outside).is_err());
        assert!(rdo_mean_choice(&[f64::NAN, 0.0, 0.0, 0.0], 4, 1, &[1.0], &ok).is_err());
        assert!(rdo_mean_choice(&values, 4, 1, &[1.0, 1.0], &ok).is_err());
    }
}
