use super::topology::Forest;
use super::*;

/// A grid of `side` x `side` vertices cut into quads, a mesh many levels deep.
fn grid(side: usize) -> (Vec<i64>, usize) {
    let mut faces = Vec::new();
    for y in 0..side - 1 {
        for x in 0..side - 1 {
            let v = (y * side + x) as i64;
            let s = side as i64;
            faces.extend([v, v + 1, v + s + 1, v + s]);
        }
    }
    (faces, side * side)
}

fn pseudo_random(count: usize, seed: u64, span: i64) -> Vec<i64> {
    let mut state = seed;
    (0..count)
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as i64 % (2 * span + 1)) - span
        })
        .collect()
}

fn plan_of(faces: &[i64], width: usize, count: usize) -> MeanPlan {
    let forest = Forest::new(faces, width, count).unwrap();
    MeanPlan::from_arrays(&forest.mean_steps(), count)
}

#[test]
fn restore_inverts_residuals_in_float_and_in_int64() {
    let (faces, count) = grid(9);
    let plan = plan_of(&faces, 4, count);
    assert!(plan.exact_in_float);
    let values = pseudo_random(count * 3, 7, 1 << 31);
    let residual = plan.residuals(&values, 3).unwrap().unwrap();
    let mut integer = plan.clone();
    integer.exact_in_float = false;
    assert_eq!(integer.residuals(&values, 3).unwrap().unwrap(), residual);
    let transpose = |m: &[i64]| -> Vec<i64> {
        (0..3)
            .flat_map(|c| (0..count).map(move |v| m[v * 3 + c]))
            .collect()
    };
    let mut columns = transpose(&residual);
    let mut other = columns.clone();
    plan.restore_columns(&mut columns, count).unwrap();
    integer.restore_columns(&mut other, count).unwrap();
    assert_eq!(columns, transpose(&values));
    assert_eq!(other, transpose(&values));
}

#[test]
fn out_of_range_is_refused() {
    let (faces, count) = grid(4);
    let plan = plan_of(&faces, 4, count);
    let mut column = vec![1i64 << 31; count];
    assert_eq!(
        plan.restore_columns(&mut column, count).unwrap_err(),
        MEAN_RANGE
    );
    let mut short = vec![0i64; count - 1];
    assert!(plan.restore_columns(&mut short, count - 1).is_err());
    assert!(plan.restore_columns(&mut short, count).is_err());
    assert!(plan.restore_columns(&mut [], count).is_ok());
    let too_large = vec![MEAN_LIMIT + 1; count];
    assert_eq!(plan.residuals(&too_large, 1).unwrap(), None);
}

#[test]
fn minus_two_to_the_63_is_out_of_range() {
    // its abs() wraps to itself: compared by abs, it would pass every range check
    let (faces, count) = grid(4);
    let plan = plan_of(&faces, 4, count);
    let mut values = vec![0; count];
    values[0] = i64::MIN;
    assert_eq!(plan.residuals(&values, 1).unwrap(), None);
    // the sums wrap back to -2**63 and 0: both checks passed it
    let mut wraps = vec![i64::MIN, 0];
    assert_eq!(
        linear_accumulate(&mut wraps, 1).unwrap_err(),
        LINEAR_STEP_RANGE
    );
}

#[test]
fn plans_from_bad_arrays_are_errors() {
    assert!(MeanPlan::from_steps(&[5], &[0, 1], &[0], &[0], &[0, 1], 3).is_err());
    assert!(MeanPlan::from_steps(&[1], &[0, 2], &[0], &[0], &[0, 1], 3).is_err());
    assert!(MeanPlan::from_steps(&[1], &[0, 1], &[0], &[9], &[0, 1], 3).is_err());
    assert!(MeanPlan::from_steps(&[1, 1], &[0, 2], &[0, 0], &[0, 0], &[0, 1, 2], 3).is_err());
    assert!(MeanPlan::from_steps(&[1], &[0, 1], &[0], &[0], &[0, 1], 3).is_ok());
}

#[test]
fn tree_and_rows_accumulate() {
    // 0 <- 2 <- 1, 3 alone
    let parents = [-1, 2, 0, -1];
    let mut values = vec![1, 10, 2, 20, 3, 30, 4, 40];
    accumulate_tree(&mut values, 2, &parents).unwrap();
    assert_eq!(values, vec![1, 10, 6, 60, 4, 40, 4, 40]);
    assert!(accumulate_tree(&mut [0, 0], 1, &[1, 0]).is_err());
    assert!(accumulate_tree(&mut [0, 0], 1, &[-1, 2]).is_err());
    assert!(accumulate_tree(&mut [0, 0, 0], 1, &[-1, 0]).is_err());
    let mut rows = vec![1, 2, 3, 4, 5, 6];
    accumulate_rows(&mut rows, 2);
    assert_eq!(rows, vec![1, 2, 4, 6, 9, 12]);
}

#[test]
fn linear_limits() {
    let mut values = vec![1, 1, 1];
    linear_accumulate(&mut values, 1).unwrap();
    assert_eq!(values, vec![1, 3, 6]);
    let mut steep = vec![LINEAR_STEP_LIMIT, 1];
    assert_eq!(
        linear_accumulate(&mut steep, 1).unwrap_err(),
        LINEAR_STEP_RANGE
    );
    let mut high = vec![LINEAR_LIMIT, LINEAR_LIMIT];
    assert_eq!(linear_accumulate(&mut high, 1).unwrap_err(), LINEAR_RANGE);
}

#[test]
fn exact_floor_is_floor() {
    for x in [
        0.0,
        -0.5,
        0.5,
        -1.0,
        1.0,
        -1.5,
        2.5,
        1e300,
        -1e300,
        4503599627370495.5,
        -4503599627370495.5,
        4503599627370496.0,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ] {
        assert_eq!(exact_floor(x), x.floor(), "{x}");
    }
    assert!(exact_floor(f64::NAN).is_nan());
}

/// `restore_values` of residual columns given as a stream: the same floats as `restore_columns`
/// then the product by each column's step, on any number of threads.
#[test]
fn restore_values_matches_restore_columns_times_steps() {
    let (faces, count) = grid(11);
    let plan = plan_of(&faces, 4, count);
    let width = 19; // two full blocks and a narrower one
    let values = pseudo_random(count * width, 3, 1 << 20);
    let residual = plan.residuals(&values, width).unwrap().unwrap();
    let mut columns: Vec<i64> = (0..width)
        .flat_map(|c| residual.iter().skip(c).step_by(width).copied())
        .collect();
    let (planes, raw) = crate::streams::pack_planes(&columns);
    let steps: Vec<f32> = (0..width).map(|c| 0.001 * (c as f32 + 1.0)).collect();
    plan.restore_columns(&mut columns, count).unwrap();
    let mut integer = plan.clone();
    integer.exact_in_float = false;
    for threads in [1, 2, 3] {
        for plan in [&plan, &integer] {
            let mut out = vec![0.0; count * width];
            plan.restore_values(&raw, planes, count, &steps, &mut out, threads)
                .unwrap();
            for (v, row) in out.chunks_exact(width).enumerate() {
                for (c, &value) in row.iter().enumerate() {
                    let expected = columns[c * count + v] as f64 * f64::from(steps[c]);
                    assert_eq!(value.to_bits(), expected.to_bits());
                }
            }
        }
    }
}

#[test]
fn restore_values_refuses_bad_sizes_and_values_out_of_range() {
    let (faces, count) = grid(5);
    let plan = plan_of(&faces, 4, count);
    let steps = [1.0f32; 9];
    let mut out = vec![0.0; count * 9];
    // a stream that does not fit the columns, and columns shorter than the mesh
    assert!(plan
        .restore_values(&[0; 5], 1, count, &steps, &mut out, 2)
        .is_err());
    let mut short = vec![0.0; (count - 1) * 9];
    let raw = vec![0u8; (count - 1) * 9];
    assert!(plan
        .restore_values(&raw, 1, count - 1, &steps, &mut short, 2)
        .is_err());
    // residuals that push a restored value beyond 2**32, in the last block only
    let mut stream = vec![0i64; count * 9];
    for v in 0..count {
        stream[8 * count + v] = (1 << 31) - 1;
    }
    let (planes, raw) = crate::streams::pack_planes(&stream);
    for threads in [1, 2] {
        let result = plan.restore_values(&raw, planes, count, &steps, &mut out, threads);
        assert_eq!(result, Err(MEAN_RANGE.to_string()));
    }
}
